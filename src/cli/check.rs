//! `strafeopt check [PATHS...]`: scenario regression tests over the library's [`check`](crate::check).
//! One line per scene as soon as it and every scene before it are done (path order, whatever `--jobs`),
//! then a summary line; `--json` prints one document instead, `--junit` also writes JUnit XML, and
//! `--update` writes each rewritten scene atomically. Exit code: 0 every scene passed, 1 a regression,
//! 2 bad input (a scene or an `[expect]` table that cannot be read or run, or nothing to check).

use super::args::CheckArgs;
use super::{write_atomically, EXIT_BAD_INPUT, EXIT_FAILURE, EXIT_OK};
use crate::check::{self, CheckEvent, CheckOptions, Overall, SceneCheck};
use crate::error::{Error, Result};
use std::collections::BTreeMap;
use std::io::Write;
use std::path::PathBuf;
use std::sync::Mutex;

/// Lines waiting for the scenes before them, and the first scene not yet printed.
#[derive(Default)]
struct InOrder {
    next: usize,
    waiting: BTreeMap<usize, String>,
}

/// Runs `check`: prints the scene lines as they come and returns the closing text with the exit code.
pub fn run(args: &CheckArgs) -> Result<(String, u8)> {
    let paths = if args.paths.is_empty() {
        vec![PathBuf::from(".")]
    } else {
        args.paths.clone()
    };
    let files = check::scene_files(&paths)?;
    if files.is_empty() {
        return Err(nothing_to_check(&paths));
    }
    let jobs = args.jobs.map_or_else(crate::work::cores, usize::from);
    let options = CheckOptions {
        jobs,
        update: args.update,
    };
    let stream = !args.output.json;
    let printer = Mutex::new(InOrder::default());
    let write_error: Mutex<Option<Error>> = Mutex::new(None);
    let on_event = |event: CheckEvent<'_>| {
        let CheckEvent::Finished { index, check } = event else {
            return;
        };
        if args.update {
            if let Err(e) = write_update(check) {
                let mut slot = write_error.lock().unwrap_or_else(|p| p.into_inner());
                slot.get_or_insert(e);
            }
        }
        if stream {
            let mut guard = printer.lock().unwrap_or_else(|p| p.into_inner());
            let p = &mut *guard;
            p.waiting.insert(index, scene_text(check));
            let mut out = std::io::stdout().lock();
            while let Some(text) = p.waiting.remove(&p.next) {
                // A closed pipe is not the check's failure; the exit code still tells.
                let _ = out.write_all(text.as_bytes()).and_then(|_| out.flush());
                p.next += 1;
            }
        }
    };
    let report = check::run(&files, options, &on_event);
    if let Some(path) = &args.junit {
        write_atomically(path, |w| check::junit::write_junit(&report, w))?;
    }
    if let Some(e) = write_error.into_inner().unwrap_or_else(|p| p.into_inner()) {
        return Err(e);
    }
    let summary = report.summary();
    if summary.passed + summary.failed + summary.errors == 0 {
        return Err(nothing_to_check(&paths));
    }
    let code = match report.overall() {
        Overall::Passed => EXIT_OK,
        Overall::Regression => EXIT_FAILURE,
        Overall::BadInput => EXIT_BAD_INPUT,
    };
    let text = if args.output.json {
        let mut buf = Vec::new();
        check::json::write_json(&report, &mut buf).map_err(|e| Error::Io(e.to_string()))?;
        String::from_utf8_lossy(&buf).into_owned()
    } else {
        format!("{}\n", check::summary_line(&report))
    };
    Ok((text, code))
}

fn nothing_to_check(paths: &[PathBuf]) -> Error {
    let shown: Vec<String> = paths.iter().map(|p| p.display().to_string()).collect();
    Error::Scene {
        location: crate::scene::one_line(&shown.join(" ")),
        key: "-".to_string(),
        message: "nothing to check: no scene file with an [expect] table".to_string(),
    }
}

/// A scene's line, and under it one line per rewritten value.
fn scene_text(c: &SceneCheck) -> String {
    let mut text = format!("{}\n", check::scene_line(c));
    if let Some(update) = &c.update {
        for ch in &update.changes {
            text.push_str(&format!(
                "       [expect] {}: {} -> {}\n",
                ch.key,
                ch.old.as_deref().unwrap_or("(none)"),
                ch.new
            ));
        }
    }
    text
}

/// Writes a scene's rewritten text over it, atomically, when anything changed.
fn write_update(c: &SceneCheck) -> Result<()> {
    match &c.update {
        Some(update) if !update.changes.is_empty() => {
            write_atomically(&c.path, |w| w.write_all(update.text.as_bytes()))
        }
        _ => Ok(()),
    }
}
