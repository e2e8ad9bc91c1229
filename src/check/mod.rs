//! Scenario regression tests: every scene file with an `[expect]` table
//! ([`Expectation`](crate::scene::Expectation)) is run with the command and quality it names, and each
//! figure it gives is compared with the result (every number an upper bound: frames, time plus a
//! tolerance, gap to the lower bound).
//!
//! [`scene_files`] lists the scenes under some paths (sorted, so the order never depends on the file
//! system or on the number of threads); [`run`] checks them on `jobs` threads, telling a callback when
//! each scene starts and ends; [`CheckReport`] holds the verdicts, and [`json`] and [`junit`] write them.
//! With `update`, a scene's [`SceneCheck::update`] holds its text with the `[expect]` values rewritten
//! from the current results ([`update`]); writing it is the caller's job.

pub mod json;
pub mod junit;
pub mod update;

use crate::error::{Error, Result};
use crate::optimise::{lower_bound, solve, Quality, SearchSettings, SearchStatus};
use crate::physics::Side;
use crate::scene::expect::{ExpectController, ExpectQuality};
use crate::scene::{self, Expectation, ExpectedRun, Limits, Scene};
use crate::sim::controllers::{best_greedy, best_sharp_turning_greedy, GREEDY_LOOKAHEADS_UNITS};
use crate::sim::{SideStrafer, Simulation};
use serde_json::{json, Value};
use std::path::{Path, PathBuf};
use std::time::Instant;

/// The figures of one run that an expectation can check.
#[derive(Clone, Debug, PartialEq)]
pub struct Measured {
    /// The frame in which the finish line is crossed (`None`: not reached).
    pub frames: Option<u64>,
    /// The fractional crossing time, seconds.
    pub time_s: Option<f64>,
    /// `100 (time - bound) / bound`, percent (the bound: docs/physics.md section 6).
    pub gap_percent: Option<f64>,
    /// The run reached the line without breaking a rule.
    pub valid: bool,
    /// The plan replayed in the engine-exact mode is valid (`solve` only).
    pub engine_exact_valid: Option<bool>,
    /// The solve status name (`solve` only; one of [`SOLVE_STATUSES`](crate::scene::expect::SOLVE_STATUSES)).
    pub status: Option<String>,
}

/// One figure that did not hold.
#[derive(Clone, Debug, PartialEq)]
pub struct Failure {
    /// The `[expect]` key (`frames`, `time`, `gap-percent`, `valid`, `engine-exact-valid`, `status`,
    /// `error`).
    pub figure: &'static str,
    /// The expectation, as JSON (a number, a boolean, a string or a list).
    pub limit: serde_json::Value,
    /// The result, as JSON (`null` when the line was not reached).
    pub actual: serde_json::Value,
    /// By how much a number went over its limit, in the figure's unit (frames, seconds, percentage points).
    pub excess: Option<f64>,
    /// One line for people: `frames 402 > 401 (+1 frame)`.
    pub message: String,
}

/// What the check of one scene found.
#[derive(Clone, Debug, PartialEq)]
pub enum Verdict {
    /// Every expectation held.
    Pass,
    /// At least one did not.
    Fail(Vec<Failure>),
    /// The scene or its `[expect]` could not be read or run (bad input).
    Error(String),
    /// The file has no `[expect]` table.
    Skipped(String),
}

/// One `[expect]` value rewritten by `--update`.
#[derive(Clone, Debug, PartialEq)]
pub struct Change {
    /// The key in `[expect]`.
    pub key: &'static str,
    /// The old value as written (`None`: the key was added).
    pub old: Option<String>,
    /// The new value as written.
    pub new: String,
}

/// The rewritten scene of `--update`.
#[derive(Clone, Debug, PartialEq)]
pub struct Update {
    /// Each value changed (empty: the file is already up to date).
    pub changes: Vec<Change>,
    /// The file's new text (comments and layout kept).
    pub text: String,
}

/// The check of one scene file.
#[derive(Clone, Debug, PartialEq)]
pub struct SceneCheck {
    /// The file.
    pub path: PathBuf,
    /// What was run: `solve fast`, `simulate greedy`, `refused` (`None` when nothing was).
    pub run: Option<String>,
    /// The result's figures (for scenes that ran).
    pub measured: Option<Measured>,
    /// The refusal (`key: message`) of a scene expected to be refused, when it was.
    pub refusal: Option<String>,
    /// The verdict against the expectations as they were before any update.
    pub verdict: Verdict,
    /// With `update`: the new text, when the expectations could be rewritten from the result.
    pub update: Option<Update>,
    /// Wall time of this scene, seconds.
    pub seconds: f64,
}

impl SceneCheck {
    /// True when a failed check was resolved by rewriting its expectations.
    pub fn updated(&self) -> bool {
        self.update.as_ref().is_some_and(|u| !u.changes.is_empty())
    }
}

/// How a whole check ended.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Overall {
    /// Every scene with expectations passed (or, with `update`, was rewritten to pass).
    Passed,
    /// A scene got worse than its expectations.
    Regression,
    /// A scene or an expectation could not be read or run.
    BadInput,
}

/// The counts of a check.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize)]
pub struct Summary {
    /// Files looked at.
    pub scenes: usize,
    /// Every expectation held.
    pub passed: usize,
    /// A regression (with `update`: one that could not be rewritten).
    pub failed: usize,
    /// Bad input.
    pub errors: usize,
    /// No `[expect]` table.
    pub skipped: usize,
    /// Files whose `[expect]` values were rewritten (`update`).
    pub updated: usize,
}

/// Every scene's check, in path order.
#[derive(Clone, Debug, PartialEq)]
pub struct CheckReport {
    /// One per file, sorted by path.
    pub scenes: Vec<SceneCheck>,
    /// Wall time of the whole check, seconds.
    pub seconds: f64,
}

impl CheckReport {
    /// The counts. A failed scene whose expectations `update` rewrote counts as passed and updated.
    pub fn summary(&self) -> Summary {
        let mut s = Summary {
            scenes: self.scenes.len(),
            ..Summary::default()
        };
        for c in &self.scenes {
            match &c.verdict {
                Verdict::Pass => s.passed += 1,
                Verdict::Fail(_) if c.update.is_some() => s.passed += 1,
                Verdict::Fail(_) => s.failed += 1,
                Verdict::Error(_) => s.errors += 1,
                Verdict::Skipped(_) => s.skipped += 1,
            }
            if c.updated() {
                s.updated += 1;
            }
        }
        s
    }

    /// Bad input if any scene could not be checked, else a regression if any failed, else passed.
    pub fn overall(&self) -> Overall {
        let s = self.summary();
        if s.errors > 0 {
            Overall::BadInput
        } else if s.failed > 0 {
            Overall::Regression
        } else {
            Overall::Passed
        }
    }
}

/// How to run a check.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct CheckOptions {
    /// Threads, at least 1.
    pub jobs: usize,
    /// Compute each scene's text with its `[expect]` values rewritten from the result.
    pub update: bool,
}

/// What [`run`] tells its callback, from the worker threads.
#[derive(Clone, Copy, Debug)]
pub enum CheckEvent<'a> {
    /// Scene `index` (of the sorted list) starts.
    Started {
        /// Its place in the list.
        index: usize,
        /// The file.
        path: &'a Path,
    },
    /// Scene `index` is done.
    Finished {
        /// Its place in the list.
        index: usize,
        /// Its check.
        check: &'a SceneCheck,
    },
}

/// The scene files under `paths`, sorted and without repeats: a file given by name whatever its name,
/// and every `*.toml` file in a folder and its subfolders (hidden folders and folder links left out). A
/// path that does not exist is bad input.
pub fn scene_files(paths: &[PathBuf]) -> Result<Vec<PathBuf>> {
    let mut files = Vec::new();
    for path in paths {
        let meta = std::fs::metadata(path).map_err(|e| Error::Scene {
            location: crate::scene::one_line(&path.display().to_string()),
            key: "-".to_string(),
            message: format!("cannot read: {e}"),
        })?;
        if meta.is_dir() {
            walk(path, &mut files)?;
        } else {
            files.push(path.clone());
        }
    }
    files.sort();
    files.dedup();
    Ok(files)
}

fn walk(dir: &Path, files: &mut Vec<PathBuf>) -> Result<()> {
    let io = |e: std::io::Error| Error::Scene {
        location: crate::scene::one_line(&dir.display().to_string()),
        key: "-".to_string(),
        message: format!("cannot read the folder: {e}"),
    };
    for entry in std::fs::read_dir(dir).map_err(io)? {
        let entry = entry.map_err(io)?;
        let path = entry.path();
        let kind = entry.file_type().map_err(io)?;
        let hidden = entry.file_name().to_string_lossy().starts_with('.');
        if kind.is_dir() && !hidden {
            walk(&path, files)?;
        } else if !kind.is_dir()
            && path.extension().is_some_and(|e| e == "toml")
            && std::fs::metadata(&path).is_ok_and(|m| m.is_file())
        {
            files.push(path);
        }
    }
    Ok(())
}

/// Checks `files` (see [`scene_files`]) on `options.jobs` threads. The report keeps the order of `files`
/// whatever the number of threads; `on_event` hears each start and end as it happens (a progress display
/// can hang on it).
pub fn run(
    files: &[PathBuf],
    options: CheckOptions,
    on_event: &(dyn Fn(CheckEvent<'_>) + Sync),
) -> CheckReport {
    let started = Instant::now();
    let scenes = crate::work::in_job_order(files, options.jobs, |index, path| {
        on_event(CheckEvent::Started { index, path });
        let check = check_scene(path, options.update);
        on_event(CheckEvent::Finished {
            index,
            check: &check,
        });
        check
    });
    CheckReport {
        scenes,
        seconds: started.elapsed().as_secs_f64(),
    }
}

/// Checks one scene file: reads its `[expect]`, runs what it names, compares (and with `update`,
/// rewrites the expectations from the result).
pub fn check_scene(path: &Path, update: bool) -> SceneCheck {
    let started = Instant::now();
    let mut check = SceneCheck {
        path: path.to_path_buf(),
        run: None,
        measured: None,
        refusal: None,
        verdict: Verdict::Pass,
        update: None,
        seconds: 0.0,
    };
    let origin = path.display().to_string();
    let read = scene::read_text(path).and_then(|text| {
        let expectation = scene::expectation_from_str(&text, &origin)?;
        Ok((text, expectation))
    });
    match read {
        Err(e) => check.verdict = Verdict::Error(e.to_string()),
        Ok((_, None)) => check.verdict = Verdict::Skipped("no [expect] table".to_string()),
        Ok((text, Some(Expectation::Refused { message_contains }))) => {
            check.run = Some("refused".to_string());
            let refusal = Scene::from_toml_str(&text, &origin)
                .err()
                .map(|e| refusal_text(&e));
            check.verdict = match &refusal {
                Some(message) if message.contains(&message_contains) => Verdict::Pass,
                _ => Verdict::Fail(vec![refusal_failure(&message_contains, refusal.as_deref())]),
            };
            check.refusal.clone_from(&refusal);
            if update {
                check.update = refusal.and_then(|message| {
                    update::rewrite_refusal(&text, &message_contains, &message)
                        .map_err(|e| check.verdict = Verdict::Error(e.to_string()))
                        .ok()
                });
            }
        }
        Ok((text, Some(Expectation::Runs { run, limits }))) => {
            check.run = Some(run_name(run));
            match Scene::from_toml_str(&text, &origin).and_then(|scene| measure(&scene, run)) {
                Ok(measured) => {
                    let failures = compare(&limits, run, &measured);
                    check.verdict = if failures.is_empty() {
                        Verdict::Pass
                    } else {
                        Verdict::Fail(failures)
                    };
                    if update {
                        match update::rewrite_limits(&text, &limits, run, &measured) {
                            Ok(u) => check.update = u,
                            Err(e) => check.verdict = Verdict::Error(e.to_string()),
                        }
                    }
                    check.measured = Some(measured);
                }
                Err(Error::NoValidPath(why)) => {
                    check.verdict = Verdict::Fail(vec![Failure {
                        figure: "valid",
                        limit: serde_json::Value::Bool(true),
                        actual: serde_json::Value::Bool(false),
                        excess: None,
                        message: format!("no valid path: {why}"),
                    }]);
                }
                Err(e) => check.verdict = Verdict::Error(e.to_string()),
            }
        }
    }
    check.seconds = started.elapsed().as_secs_f64();
    check
}

/// The part of a refusal that `[expect] error` is matched against: `key: message` for a scene error (the
/// file and line depend on how the file was named), the whole message otherwise.
pub fn refusal_text(e: &Error) -> String {
    match e {
        Error::Scene { key, message, .. } => format!("{key}: {message}"),
        other => other.to_string(),
    }
}

fn refusal_failure(expected: &str, refusal: Option<&str>) -> Failure {
    Failure {
        figure: "error",
        limit: serde_json::Value::String(expected.to_string()),
        actual: refusal.map_or(serde_json::Value::Null, |m| {
            serde_json::Value::String(m.to_string())
        }),
        excess: None,
        message: match refusal {
            Some(m) => format!("refused with \"{m}\", expected a message holding \"{expected}\""),
            None => format!("the scene was accepted, expected a refusal holding \"{expected}\""),
        },
    }
}

/// `solve fast`, `simulate greedy`.
pub fn run_name(run: ExpectedRun) -> String {
    match run {
        ExpectedRun::Solve(q) => format!("solve {}", quality_name(q)),
        ExpectedRun::Simulate(c) => format!("simulate {}", controller_name(c)),
    }
}

fn quality_name(q: ExpectQuality) -> &'static str {
    match q {
        ExpectQuality::Fast => "fast",
        ExpectQuality::Balanced => "balanced",
        ExpectQuality::Exact => "exact",
    }
}

fn controller_name(c: ExpectController) -> &'static str {
    match c {
        ExpectController::Greedy => "greedy",
        ExpectController::SharpTurns => "sharp-turns",
        ExpectController::MaxAccelLeft => "max-accel-left",
        ExpectController::MaxAccelRight => "max-accel-right",
        ExpectController::Abh => "abh",
    }
}

/// The status name of a solve (the `status` tag of `solve --json`).
pub fn status_name(status: &SearchStatus) -> &'static str {
    match status {
        SearchStatus::Converged { .. } => "converged",
        SearchStatus::TimeLimit { .. } => "time-limit",
        SearchStatus::Cancelled { .. } => "cancelled",
        SearchStatus::GreedyOptimal { .. } => "greedy-optimal",
        SearchStatus::NoImprovement { .. } => "no-improvement",
    }
}

/// Runs what an expectation names and takes its figures, as `solve --json` and `simulate --json` give
/// them. A solve with no valid plan is [`Error::NoValidPath`], as for `solve`.
pub fn measure(scene: &Scene, run: ExpectedRun) -> Result<Measured> {
    let gap =
        |time_s: f64, bound_s: f64| 100.0 * (time_s - bound_s) / bound_s.max(f64::MIN_POSITIVE);
    match run {
        ExpectedRun::Solve(q) => {
            let quality = match q {
                ExpectQuality::Fast => Quality::Fast,
                ExpectQuality::Balanced => Quality::Balanced,
                ExpectQuality::Exact => Quality::Exact,
            };
            let o = solve(scene, &SearchSettings::for_quality(quality))?;
            if !o.trace.feasible() {
                return Err(Error::NoValidPath(
                    "neither the optimiser nor the greedy strafer reaches the finish without breaking a rule"
                        .to_string(),
                ));
            }
            let crossing = o.trace.crossing;
            Ok(Measured {
                frames: crossing.map(|c| c.frames),
                time_s: crossing.map(|c| c.time),
                gap_percent: crossing.map(|c| gap(c.time, o.bound.crossing.time)),
                valid: true,
                engine_exact_valid: Some(o.engine_exact.feasible()),
                status: Some(status_name(&o.status).to_string()),
            })
        }
        ExpectedRun::Simulate(controller) => {
            let sim = Simulation::new(scene)?;
            let bound = lower_bound(scene, sim.corridor())?;
            let trace = match controller {
                ExpectController::Greedy => {
                    best_greedy(&sim, &bound.path, &GREEDY_LOOKAHEADS_UNITS).0
                }
                ExpectController::SharpTurns => {
                    best_sharp_turning_greedy(&sim, &bound.path, &GREEDY_LOOKAHEADS_UNITS).0
                }
                ExpectController::MaxAccelLeft => sim.run(&mut SideStrafer { side: Side::Left }),
                ExpectController::MaxAccelRight => sim.run(&mut SideStrafer { side: Side::Right }),
                ExpectController::Abh => sim.run(&mut crate::sim::abh::Abh::default()),
            };
            let crossing = trace.crossing;
            Ok(Measured {
                frames: crossing.map(|c| c.frames),
                time_s: crossing.map(|c| c.time),
                gap_percent: crossing.map(|c| gap(c.time, bound.crossing.time)),
                valid: trace.feasible(),
                engine_exact_valid: None,
                status: None,
            })
        }
    }
}

/// Every limit that `measured` breaks. A solve must be valid unless `valid = false` is given.
pub fn compare(limits: &Limits, run: ExpectedRun, measured: &Measured) -> Vec<Failure> {
    [
        frames_failure(limits, measured),
        time_failure(limits, measured),
        gap_failure(limits, measured),
        validity_failure(limits, run, measured),
        engine_exact_failure(limits, measured),
        status_failure(limits, measured),
    ]
    .into_iter()
    .flatten()
    .collect()
}

/// A limit on `figure` broken by a run that never reached the finish line (`shown`: the limit as text).
fn not_reached(figure: &'static str, limit: Value, shown: String) -> Failure {
    Failure {
        figure,
        limit,
        actual: Value::Null,
        excess: None,
        message: format!("{figure}: the finish line was not reached, expected at most {shown}"),
    }
}

/// More frames than the limit.
fn frames_failure(limits: &Limits, measured: &Measured) -> Option<Failure> {
    let limit = limits.frames?;
    match measured.frames {
        None => Some(not_reached("frames", json!(limit), limit.to_string())),
        Some(f) if f > limit => Some(Failure {
            figure: "frames",
            limit: json!(limit),
            actual: json!(f),
            excess: Some((f - limit) as f64),
            message: format!(
                "frames {f} > {limit} (+{} frame{})",
                f - limit,
                if f - limit == 1 { "" } else { "s" }
            ),
        }),
        Some(_) => None,
    }
}

/// A crossing later than the limit and its tolerance, seconds.
fn time_failure(limits: &Limits, measured: &Measured) -> Option<Failure> {
    let limit = limits.time_s?;
    let tol = limits.time_tolerance_s;
    match measured.time_s {
        None => Some(not_reached("time", json!(limit), format!("{limit} s"))),
        Some(t) if t > limit + tol => Some(Failure {
            figure: "time",
            limit: json!(limit),
            actual: json!(t),
            excess: Some(t - limit),
            message: format!(
                "time {t:.6} s > {limit} s{} (+{:.6} s)",
                if tol > 0.0 {
                    format!(" + {tol} s")
                } else {
                    String::new()
                },
                t - limit
            ),
        }),
        Some(_) => None,
    }
}

/// A gap to the lower bound above the limit, percent.
fn gap_failure(limits: &Limits, measured: &Measured) -> Option<Failure> {
    let limit = limits.gap_percent?;
    match measured.gap_percent {
        None => Some(not_reached(
            "gap-percent",
            json!(limit),
            format!("{limit}%"),
        )),
        Some(g) if g > limit => Some(Failure {
            figure: "gap-percent",
            limit: json!(limit),
            actual: json!(g),
            excess: Some(g - limit),
            message: format!("gap {g:.3}% > {limit}% (+{:.3} points)", g - limit),
        }),
        Some(_) => None,
    }
}

/// Validity other than expected: a solve must be valid unless `valid = false` is given; a simulation
/// only where `valid` is given.
fn validity_failure(limits: &Limits, run: ExpectedRun, measured: &Measured) -> Option<Failure> {
    let want = match run {
        ExpectedRun::Solve(_) => Some(limits.valid.unwrap_or(true)),
        ExpectedRun::Simulate(_) => limits.valid,
    }?;
    (measured.valid != want).then(|| Failure {
        figure: "valid",
        limit: json!(want),
        actual: json!(measured.valid),
        excess: None,
        message: format!("valid {}, expected {want}", measured.valid),
    })
}

/// Engine-exact validity other than expected.
fn engine_exact_failure(limits: &Limits, measured: &Measured) -> Option<Failure> {
    let (want, got) = (limits.engine_exact_valid?, measured.engine_exact_valid?);
    (want != got).then(|| Failure {
        figure: "engine-exact-valid",
        limit: json!(want),
        actual: json!(got),
        excess: None,
        message: format!("engine-exact valid {got}, expected {want}"),
    })
}

/// A status not among the allowed ones.
fn status_failure(limits: &Limits, measured: &Measured) -> Option<Failure> {
    let (allowed, got) = (limits.status.as_ref()?, measured.status.as_ref()?);
    (!allowed.contains(got)).then(|| Failure {
        figure: "status",
        limit: json!(allowed),
        actual: json!(got),
        excess: None,
        message: format!("status {got}, expected {}", allowed.join(" or ")),
    })
}

/// The figures of a run in one short phrase: `frame 401, 4.001483 s, gap 0.562%, valid, engine-exact
/// valid, converged`.
pub fn measured_text(m: &Measured) -> String {
    let mut parts = Vec::new();
    match (m.frames, m.time_s) {
        (Some(f), Some(t)) => parts.push(format!("frame {f}, {t:.6} s")),
        _ => parts.push("finish not reached".to_string()),
    }
    if let Some(g) = m.gap_percent {
        parts.push(format!("gap {g:.3}%"));
    }
    parts.push(if m.valid { "valid" } else { "INVALID" }.to_string());
    if let Some(e) = m.engine_exact_valid {
        parts.push(
            if e {
                "engine-exact valid"
            } else {
                "engine-exact INVALID"
            }
            .to_string(),
        );
    }
    if let Some(s) = &m.status {
        parts.push(s.clone());
    }
    parts.join(", ")
}

/// The one line of a scene's check: `pass   PATH  solve fast: frame 401, ... (0.8 s)`.
pub fn scene_line(c: &SceneCheck) -> String {
    let path = c.path.display();
    let run = c.run.as_deref().unwrap_or("-");
    let secs = format!("({:.1} s)", c.seconds);
    match &c.verdict {
        Verdict::Pass => match (&c.measured, &c.refusal) {
            (Some(m), _) => format!("pass   {path}  {run}: {} {secs}", measured_text(m)),
            (None, Some(why)) => format!("pass   {path}  {run}: {why} {secs}"),
            (None, None) => format!("pass   {path}  {run} {secs}"),
        },
        Verdict::Fail(failures) => {
            let what: Vec<&str> = failures.iter().map(|f| f.message.as_str()).collect();
            let tag = if c.update.is_some() {
                "was FAIL"
            } else {
                "FAIL"
            };
            format!("{tag:<6} {path}  {run}: {} {secs}", what.join("; "))
        }
        Verdict::Error(message) => format!("ERROR  {path}  {message}"),
        Verdict::Skipped(why) => format!("skip   {path}  {why}"),
    }
}

/// The closing line: `check: 16 scenes, 15 passed, 1 failed, 0 errors, 0 skipped (12.3 s)`.
pub fn summary_line(report: &CheckReport) -> String {
    let s = report.summary();
    let updated = if s.updated > 0 {
        format!(", {} updated", s.updated)
    } else {
        String::new()
    };
    format!(
        "check: {} scene{}, {} passed, {} failed, {} error{}, {} skipped{updated} ({:.1} s)",
        s.scenes,
        if s.scenes == 1 { "" } else { "s" },
        s.passed,
        s.failed,
        s.errors,
        if s.errors == 1 { "" } else { "s" },
        s.skipped,
        report.seconds
    )
}
