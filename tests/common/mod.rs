//! What the command-line tests share: running the real binary.

use assert_cmd::Command;
use std::ffi::OsStr;
use std::path::Path;
use std::process::Output;

/// Runs `strafeopt` with `args` in `dir` and returns its output (no timeout: every command here ends).
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
