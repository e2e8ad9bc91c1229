//! `strafeopt report RESULT.json -o out.html`: the HTML report of a saved result.
//!
//! **A result is rebuilt, not stored.** `simulate --json` stays small (no per-frame data); instead it
//! names what made the run, and the simulation is deterministic, so `report` re-runs it:
//! - `scene_path`: the scene file (absolute when saved; a relative path is tried from the working
//!   directory, then from the result file's directory). The scene is loaded and validated again.
//! - `controller` and `lookahead`: `greedy` and `greedy-sharp-turns` (with its look-ahead, units),
//!   `max-accel-left` or `max-accel-right` are run again on the scene.
//! - `plans` (optional): `[{"label": "optimised", "controls": [Control, ...]}]`, each control as serde
//!   writes [`Control`] (`yaw_rad`, `forwardmove`, `sidemove`, `jump`, `duck`), replayed frame by frame.
//!   This is how a `solve --json` result carries its optimised plan; its `controller` may then name a
//!   controller not listed above, which is skipped.
//!
//! The rebuilt run of `controller` must take the `frames` and `time` the result recorded; otherwise the
//! scene file has changed since and the command refuses with one line saying so (exit code 2), as it does
//! for a result it cannot read.

use super::args::ReportArgs;
use super::write_atomically;
use crate::error::{Error, Result};
use crate::optimise::{lower_bound, LowerBound};
use crate::physics::{Control, Side};
use crate::report::{write_html, ReportInput};
use crate::scene::Scene;
use crate::sim::{Greedy, Playback, SideStrafer, Simulation, Trace};
use serde::Deserialize;
use serde_json::Value;
use std::path::{Path, PathBuf};

/// Relative tolerance when comparing a rebuilt crossing time with the recorded one.
pub const REBUILD_TIME_TOL_REL: f64 = 1e-9;

/// A result rebuilt from its JSON: the scene, its lower bound, and the labelled runs.
#[derive(Clone, Debug)]
pub struct Rebuilt {
    /// The scene named by `scene_path`.
    pub scene: Scene,
    /// Its lower bound.
    pub bound: LowerBound,
    /// `(label, run)`: the result's `controller` first (when it is one `report` can run), then `plans`.
    pub runs: Vec<(String, Trace)>,
}

/// One entry of a result's `plans`.
#[derive(Debug, Deserialize)]
struct PlanEntry {
    label: String,
    controls: Vec<Control>,
}

/// Runs `report`: reads the result, rebuilds it and writes the HTML atomically. Prints one line naming
/// the file written.
pub fn run(args: &ReportArgs) -> Result<String> {
    let origin = args.result.display().to_string();
    let text = std::fs::read_to_string(&args.result).map_err(|e| Error::Scene {
        location: origin.clone(),
        key: "-".to_string(),
        message: format!("cannot read the result: {e}"),
    })?;
    let result: Value = serde_json::from_str(&text).map_err(|e| Error::Scene {
        location: format!("{origin}:{}", e.line()),
        key: "-".to_string(),
        message: format!("not a JSON result ({e}); save one with `simulate --json > RESULT.json`"),
    })?;
    let base_dir = args.result.parent().unwrap_or(Path::new("."));
    let rebuilt = rebuild(&result, &origin, base_dir)?;
    let mut input = ReportInput::new(&rebuilt.scene, &rebuilt.bound, &result);
    for (label, trace) in &rebuilt.runs {
        input = input.with_run(label, trace);
    }
    write_atomically(&args.output, |w| write_html(&input, w))?;
    Ok(format!(
        "report: {} ({} run{})\n",
        args.output.display(),
        rebuilt.runs.len(),
        if rebuilt.runs.len() == 1 { "" } else { "s" }
    ))
}

fn result_error(origin: &str, key: &str, message: impl Into<String>) -> Error {
    Error::Scene {
        location: origin.to_string(),
        key: key.to_string(),
        message: message.into(),
    }
}

/// The scene file of a result: `scene_path` as saved, else relative to `base_dir`.
fn resolve_scene_path(result: &Value, origin: &str, base_dir: &Path) -> Result<PathBuf> {
    let named = result
        .get("scene_path")
        .and_then(Value::as_str)
        .ok_or_else(|| {
            result_error(
                origin,
                "scene_path",
                "missing; the result must be saved by `strafeopt simulate --json` (which names the scene \
                 file)",
            )
        })?;
    let path = PathBuf::from(named);
    if path.is_relative() && !path.exists() {
        let beside = base_dir.join(&path);
        if beside.exists() {
            return Ok(beside);
        }
    }
    if !path.exists() {
        return Err(result_error(
            origin,
            "scene_path",
            format!("{named}: no such scene file; the result names the scene it was made from"),
        ));
    }
    Ok(path)
}

/// Rebuilds the runs of `result` (see the module documentation). `origin` names the result in errors;
/// `base_dir` is where a relative `scene_path` is also looked for.
pub fn rebuild(result: &Value, origin: &str, base_dir: &Path) -> Result<Rebuilt> {
    let scene = Scene::load(&resolve_scene_path(result, origin, base_dir)?)?;
    let sim = Simulation::new(&scene)?;
    let bound = lower_bound(&scene, sim.corridor())?;
    let mut runs = Vec::new();
    let controller = result
        .get("controller")
        .and_then(Value::as_str)
        .unwrap_or("");
    let recorded = match controller {
        "greedy" | "greedy-sharp-turns" => {
            let la = result
                .get("lookahead")
                .and_then(Value::as_f64)
                .filter(|l| l.is_finite() && *l > 0.0)
                .ok_or_else(|| {
                    result_error(
                        origin,
                        "lookahead",
                        "missing or not a finite number above 0; a greedy result records its look-ahead",
                    )
                })?;
            let strafer = Greedy::new(bound.path.clone(), la);
            let mut strafer = if controller == "greedy" {
                strafer
            } else {
                strafer.with_sharp_turns()
            };
            Some(sim.run(&mut strafer))
        }
        "abh" => Some(sim.run(&mut crate::sim::abh::Abh::default())),
        "max-accel-left" => Some(sim.run(&mut SideStrafer { side: Side::Left })),
        "max-accel-right" => Some(sim.run(&mut SideStrafer { side: Side::Right })),
        _ => None,
    };
    if let Some(trace) = recorded {
        check_matches(result, origin, &trace)?;
        runs.push((controller.to_string(), trace));
    }
    if let Some(plans) = result.get("plans") {
        let plans: Vec<PlanEntry> = serde_json::from_value(plans.clone()).map_err(|e| {
            result_error(
                origin,
                "plans",
                format!("{e}; expected [{{\"label\": ..., \"controls\": [...]}}]"),
            )
        })?;
        for plan in plans {
            let trace = sim.run(&mut Playback {
                controls: plan.controls,
                label: plan.label.clone(),
            });
            runs.push((plan.label, trace));
        }
    }
    if runs.is_empty() {
        return Err(result_error(
            origin,
            "controller",
            format!(
                "{controller:?}: must be greedy, greedy-sharp-turns, abh, max-accel-left or \
                 max-accel-right, or the result must carry `plans`"
            ),
        ));
    }
    Ok(Rebuilt { scene, bound, runs })
}

/// The rebuilt run must cross in the recorded frame at the recorded time.
fn check_matches(result: &Value, origin: &str, trace: &Trace) -> Result<()> {
    let frames = trace
        .crossing
        .map_or(trace.frames.len() as u64, |c| c.frames);
    if let Some(saved) = result.get("frames").and_then(Value::as_u64) {
        if saved != frames {
            return Err(result_error(
                origin,
                "frames",
                format!(
                    "{saved}, but the scene now gives {frames}: the scene file has changed since the result \
                     was saved; run simulate again"
                ),
            ));
        }
    }
    let saved_time = result.get("time").and_then(Value::as_f64);
    let time = trace.crossing.map(|c| c.time);
    let agree = match (saved_time, time) {
        (Some(a), Some(b)) => (a - b).abs() <= REBUILD_TIME_TOL_REL * a.abs().max(1.0),
        (None, None) => true,
        _ => false,
    };
    if !agree {
        return Err(result_error(
            origin,
            "time",
            format!(
                "{saved_time:?}, but the scene now gives {time:?}: the scene file has changed since the result \
                 was saved; run simulate again"
            ),
        ));
    }
    Ok(())
}
