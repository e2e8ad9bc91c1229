//! The command line: a thin layer over the library. Parses arguments, resolves them into library values,
//! prints the result, and maps errors to exit codes: 0 done, 2 bad input (usage, file, value), 3 no valid
//! path through the scene, 1 anything else (for `check`: a regression). Every error is one line on stderr
//! behind `strafeopt: `.

pub mod args;
pub mod bench;
pub mod bench_generated;
pub mod bench_staircase;
pub mod calc;
pub mod check;
pub mod gen;
pub mod progress;
pub mod report_cmd;
pub mod serve;
pub mod simulate;
pub mod solve;
pub mod table;

use crate::error::Error;
use args::{Cli, Command};
use clap::{CommandFactory, Parser};
use std::io::Write;

/// Exit code for success.
pub const EXIT_OK: u8 = 0;
/// Exit code for anything unexpected.
pub const EXIT_FAILURE: u8 = 1;
/// Exit code for bad input: usage, a file, a value.
pub const EXIT_BAD_INPUT: u8 = 2;
/// Exit code when no valid path goes through the scene.
pub const EXIT_NO_PATH: u8 = 3;

/// The exit code for a library error.
pub fn exit_code(e: &Error) -> u8 {
    match e {
        Error::InvalidValue { .. }
        | Error::Scene { .. }
        | Error::Unreachable { .. }
        | Error::FrameLimit { .. } => EXIT_BAD_INPUT,
        Error::NoValidPath(_) => EXIT_NO_PATH,
        _ => EXIT_FAILURE,
    }
}

/// Runs the program on `argv` and returns the exit code.
pub fn main_with_args(argv: impl IntoIterator<Item = std::ffi::OsString>) -> u8 {
    let argv: Vec<std::ffi::OsString> = argv.into_iter().collect();
    let cli = match Cli::try_parse_from(&argv) {
        Ok(cli) => cli,
        Err(e) => {
            use clap::error::ErrorKind;
            if matches!(e.kind(), ErrorKind::DisplayHelp | ErrorKind::DisplayVersion) {
                let _ = e.print();
                return EXIT_OK;
            }
            if e.kind() == ErrorKind::DisplayHelpOnMissingArgumentOrSubcommand {
                // An error like any other: one line, not the whole help.
                eprintln!("strafeopt: {}", missing_command(&argv));
                return EXIT_BAD_INPUT;
            }
            // One line: clap's message up to its usage block or hint, without the "error: " prefix.
            let rendered = e.render().to_string();
            let message: Vec<&str> = rendered
                .lines()
                .map(str::trim)
                .take_while(|l| {
                    !l.starts_with("Usage:")
                        && !l.starts_with("tip:")
                        && !l.starts_with("For more information")
                })
                .filter(|l| !l.is_empty())
                .collect();
            let line = message.join(" ");
            let line = line.trim_start_matches("error: ");
            eprintln!("strafeopt: {line} (see --help)");
            return EXIT_BAD_INPUT;
        }
    };
    let result = match &cli.command {
        Command::Check(a) => check::run(a),
        _ => run(&cli).map(|out| (out, EXIT_OK)),
    };
    match result {
        Ok((out, code)) => {
            let mut stdout = std::io::stdout().lock();
            match stdout
                .write_all(out.as_bytes())
                .and_then(|_| stdout.flush())
            {
                Ok(()) => code,
                // A closed pipe (`| head`) is not a failure.
                Err(e) if e.kind() == std::io::ErrorKind::BrokenPipe => code,
                Err(e) => {
                    eprintln!("strafeopt: writing the output: {e}");
                    EXIT_FAILURE
                }
            }
        }
        Err(e) => {
            eprintln!("strafeopt: {e}");
            exit_code(&e)
        }
    }
}

/// The message for a command line that stops before naming its (sub)command: `strafeopt` alone, or
/// `strafeopt calc` without a figure.
fn missing_command(argv: &[std::ffi::OsString]) -> String {
    let mut cmd = Cli::command();
    let mut path = vec![cmd.get_name().to_string()];
    for arg in argv.iter().skip(1).filter_map(|a| a.to_str()) {
        if let Some(sub) = cmd.find_subcommand(arg).cloned() {
            path.push(sub.get_name().to_string());
            cmd = sub;
        }
    }
    let names: Vec<&str> = cmd
        .get_subcommands()
        .map(|c| c.get_name())
        .filter(|&n| n != "help")
        .collect();
    format!(
        "`{}` needs a command: {} (see --help)",
        path.join(" "),
        names.join(", ")
    )
}

/// Runs a parsed command and returns what to print.
pub fn run(cli: &Cli) -> Result<String, Error> {
    match &cli.command {
        Command::Simulate(a) => simulate::run(a),
        Command::Solve(a) => solve::run(a),
        Command::Report(a) => report_cmd::run(a),
        Command::Bench(a) => bench::run(a),
        Command::Check(a) => check::run(a).map(|(out, _)| out),
        Command::Serve(a) => serve::run(a),
        Command::Gen(a) => gen::run(a),
        Command::Calc(c) => {
            let figures = calc::run(&c.form)?;
            if calc::wants_json(&c.form) {
                Ok(format!("{}\n", figures.json))
            } else {
                Ok(figures.text)
            }
        }
    }
}

/// Writes a file through a temporary name in the same directory and renames it into place, so an
/// interrupted run never leaves a half-written file.
pub fn write_atomically(
    path: &std::path::Path,
    write: impl FnOnce(&mut std::io::BufWriter<std::fs::File>) -> std::io::Result<()>,
) -> Result<(), Error> {
    let io_err = |e: std::io::Error| Error::Io(format!("{}: {e}", path.display()));
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_else(|| "output".to_string());
    let tmp = path.with_file_name(format!(".{name}.tmp-{}", std::process::id()));
    let result = (|| {
        let file = std::fs::File::create(&tmp)?;
        let mut w = std::io::BufWriter::new(file);
        write(&mut w)?;
        let file = w.into_inner().map_err(|e| e.into_error())?;
        file.sync_all()?;
        std::fs::rename(&tmp, path)
    })();
    if result.is_err() {
        let _ = std::fs::remove_file(&tmp);
    }
    result.map_err(io_err)
}

/// Writes the files a run asked for (`--trajectory`, `--report`, `--hltas`), each atomically: the trajectory
/// and the TAS script of `plan`, and a report showing every run in `runs` (label, trace).
pub fn write_artifacts(
    artifacts: &args::ArtifactFlags,
    scene: &crate::scene::Scene,
    plan: &crate::sim::Trace,
    runs: &[(&str, &crate::sim::Trace)],
    bound: &crate::optimise::LowerBound,
    summary: &serde_json::Value,
) -> Result<(), Error> {
    write_artifacts_within(
        artifacts,
        scene,
        plan,
        runs,
        bound,
        summary,
        &crate::budget::Budget::unlimited(),
    )
    .map(|_| ())
}

/// [`write_artifacts`] within `budget`: a file whose turn comes after the budget has run out is not
/// written (a file is written whole or not at all). Returns the flags of the files not written.
pub fn write_artifacts_within(
    artifacts: &args::ArtifactFlags,
    scene: &crate::scene::Scene,
    plan: &crate::sim::Trace,
    runs: &[(&str, &crate::sim::Trace)],
    bound: &crate::optimise::LowerBound,
    summary: &serde_json::Value,
    budget: &crate::budget::Budget,
) -> Result<Vec<&'static str>, Error> {
    use crate::report;
    let mut skipped = Vec::new();
    let mut turn = |flag: &'static str, asked: bool| {
        let go = asked && !budget.expired();
        if asked && !go {
            skipped.push(flag);
        }
        go
    };
    let trajectory = artifacts
        .trajectory
        .as_ref()
        .filter(|_| turn("--trajectory", true));
    if let Some(path) = trajectory {
        let json = path
            .extension()
            .is_some_and(|e| e.eq_ignore_ascii_case("json"));
        write_atomically(path, |w| {
            if json {
                report::write_trajectory_json(plan, w)
            } else {
                report::write_trajectory_csv(plan, w)
            }
        })?;
    }
    let html = artifacts.report.as_ref().filter(|_| turn("--report", true));
    if let Some(path) = html {
        let input = runs.iter().fold(
            report::ReportInput::new(scene, bound, summary),
            |input, (label, trace)| input.with_run(label, trace),
        );
        write_atomically(path, |w| report::write_html(&input, w))?;
    }
    let hltas = artifacts.hltas.as_ref().filter(|_| turn("--hltas", true));
    if let Some(path) = hltas {
        let script = report::hltas_script(plan, &scene.vars, &scene.name)?;
        write_atomically(path, |w| {
            script
                .to_writer(w)
                .map_err(|e| std::io::Error::other(format!("{e:?}")))
        })?;
    }
    Ok(skipped)
}
