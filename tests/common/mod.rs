//! What the tests share: running the real binary, and solving a sample on every core.

use assert_cmd::Command;
use std::ffi::OsStr;
use std::path::Path;
use std::process::Output;

/// Runs `strafeopt` with `args` in `dir` and returns its output (no timeout: every command here ends).
#[allow(dead_code)]
pub fn strafeopt_in<S: AsRef<OsStr>>(dir: &Path, args: &[S]) -> Output {
    Command::cargo_bin("strafeopt")
        .map(|mut c| c.current_dir(dir).args(args).output())
        .unwrap_or_else(|e| panic!("binary: {e}"))
        .unwrap_or_else(|e| panic!("run: {e}"))
}

/// Runs `strafeopt` with `args` from the package root (so `scenarios/...` paths work).
#[allow(dead_code)]
pub fn strafeopt<S: AsRef<OsStr>>(args: &[S]) -> Output {
    strafeopt_in(Path::new(env!("CARGO_MANIFEST_DIR")), args)
}

/// `check` applied to every item of `items` on as many threads as the machine has cores, the results in
/// the items' order (each item's checks are its own; a failed one fails the test).
#[allow(dead_code)]
pub fn on_every_core<T: Sync, R: Send>(items: &[T], check: impl Fn(&T) -> R + Sync) -> Vec<R> {
    let workers = std::thread::available_parallelism().map_or(1, |n| n.get());
    let next = std::sync::atomic::AtomicUsize::new(0);
    let mut results: Vec<(usize, R)> = std::thread::scope(|scope| {
        let handles: Vec<_> = (0..workers)
            .map(|_| {
                scope.spawn(|| {
                    let mut done = Vec::new();
                    loop {
                        let k = next.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
                        let Some(item) = items.get(k) else { break };
                        done.push((k, check(item)));
                    }
                    done
                })
            })
            .collect();
        handles
            .into_iter()
            .flat_map(|h| {
                h.join()
                    .unwrap_or_else(|_| panic!("an item's checks failed"))
            })
            .collect()
    });
    results.sort_by_key(|r| r.0);
    results.into_iter().map(|r| r.1).collect()
}
