//! `strafeopt solve`: the minimal-time plan of a scene, beside the greedy baseline and the lower bound.

use super::args::SolveArgs;
use super::{progress, write_artifacts_within};
use crate::budget::{Budget, Stage};
use crate::error::{Error, Result};
use crate::optimise::search::{self, time_limit, Progress};
use crate::optimise::{
    Outcome, Quality, SearchSettings, SearchStatus, StageSeconds, CERTIFIED_CLEARANCE_UNITS,
};
use crate::scene::Scene;
use serde_json::{json, Value};

/// Runs `solve` and returns what to print. No valid path: [`Error::NoValidPath`] (exit 3), nothing written.
/// A scene that needs more frames than `--max-frames`: [`Error::FrameLimit`] (exit 2), before any work.
pub fn run(args: &SolveArgs) -> Result<String> {
    let quality = args.quality.quality();
    let mut settings = SearchSettings::for_quality(quality);
    if let Some(s) = args.time_limit {
        settings.time_limit = Some(time_limit(s)?);
    }
    if let Some(n) = args.max_frames {
        settings.max_frames = max_frames(n)?;
    }
    settings.sub_problem_solver = args.sub_problem_solver.solver();
    // The whole command's budget: the solve, then writing the files.
    let budget = Budget::from_limit(settings.time_limit, None);
    let scene = Scene::load(&args.scene)?;
    if let Some(path) = &args.artifacts.hltas {
        super::simulate::require_goldsrc_for_hltas(&scene, path)?;
    }
    let bar = progress::spinner(progress::wanted(args.output.json, args.output.quiet));
    bar.set_prefix(Stage::Greedy.name());
    bar.set_message("lower bound, greedy strafer over look-aheads and speed caps");
    let mut counts_tried = 0u64;
    let outcome = search::solve_with_progress(&scene, &settings, &mut |p| match p {
        Progress::Baseline { .. } => {
            bar.set_prefix(Stage::Relaxed.name());
            bar.set_message(p.to_string());
        }
        Progress::FrameCount {
            frames,
            frames_per_step,
            reached,
        } => {
            // The count of counts tried so far, which the report itself does not carry.
            counts_tried += 1;
            bar.set_prefix(Stage::Relaxed.name());
            bar.set_message(format!(
                "frame counts tried {counts_tried}, last {frames}{}: {}",
                Progress::steps_text(frames_per_step),
                Progress::crossing_text(reached)
            ));
        }
        Progress::Finishing | Progress::Polishing { .. } => {
            bar.set_prefix(Stage::Rounding.name());
            bar.set_message(p.to_string());
        }
        Progress::AfterWallContact { .. } => {
            bar.set_prefix(Stage::Relaxed.name());
            bar.set_message(p.to_string());
        }
    });
    bar.finish_and_clear();
    let mut outcome = outcome?;
    if !outcome.trace.feasible() {
        return Err(Error::NoValidPath(format!(
            "{}: neither the optimiser nor the greedy strafer found a run that reaches the finish without \
             breaking a rule",
            scene.origin
        )));
    }
    let summary = summary_json(&scene, quality, &outcome);
    let skipped = write_artifacts_within(
        &args.artifacts,
        &scene,
        &outcome.trace,
        &[("greedy", &outcome.greedy), ("optimised", &outcome.trace)],
        &outcome.bound,
        &summary,
        &budget,
    )?;
    if !skipped.is_empty() {
        for flag in &skipped {
            eprintln!("strafeopt: {flag} not written: the time limit ran out before it");
        }
        if outcome.status.stopped_in().is_none() {
            outcome.status = SearchStatus::stopped(&budget, Stage::Writing);
        }
    }
    if args.output.json {
        let mut summary = summary;
        summary["status"] = json!(outcome.status);
        summary["not_written"] = json!(skipped);
        json_with_plans(&summary, &outcome)
    } else {
        Ok(summary_text(&scene, &outcome))
    }
}

/// Checks `--max-frames`.
pub fn max_frames(n: u64) -> Result<u64> {
    if n >= 1 {
        Ok(n)
    } else {
        Err(Error::invalid(
            "--max-frames",
            n as f64,
            "a whole number of frames of at least 1",
        ))
    }
}

fn quality_name(q: Quality) -> &'static str {
    match q {
        Quality::Fast => "fast",
        Quality::Balanced => "balanced",
        Quality::Exact => "exact",
    }
}

/// The `--json` object of a solve without its plans (see [`json_with_plans`]); the HTML report's table.
pub fn summary_json(scene: &Scene, quality: Quality, o: &Outcome) -> Value {
    let crossing = o.trace.crossing;
    let lb = o.bound.crossing;
    json!({
        "scenario": scene.name,
        "scene_path": super::simulate::scene_path(scene),
        "quality": quality_name(quality),
        "frames": crossing.map(|c| c.frames),
        "time": crossing.map(|c| c.time),
        "crossing_fraction": crossing.map(|c| c.fraction),
        "feasible": o.trace.feasible(),
        "min_clearance": o.trace.min_clearance().is_finite().then(|| o.trace.min_clearance()),
        "final_speed": o.trace.final_speed(),
        "source": o.source,
        "engine_exact": {
            "frames": o.engine_exact.crossing.map(|c| c.frames),
            "time": o.engine_exact.crossing.map(|c| c.time),
            "feasible": o.engine_exact.feasible(),
            "min_clearance": o.engine_exact.min_clearance.is_finite().then_some(o.engine_exact.min_clearance),
        },
        "greedy": {
            "frames": o.greedy.crossing.map(|c| c.frames),
            "time": o.greedy.crossing.map(|c| c.time),
            "feasible": o.greedy.feasible(),
            "controller": o.greedy.controller,
            "guide": o.greedy_guide,
        },
        "relaxed": o.relaxed,
        "rounding_loss_frames": rounding_loss_frames(scene, o),
        "gap_to_relaxed": match (crossing, o.relaxed) {
            (Some(c), Some(r)) => Some((c.time - r.time) / r.time.max(f64::MIN_POSITIVE)),
            _ => None,
        },
        "lower_bound": {
            "frames": lb.frames,
            "time": lb.time,
            "path_length": o.bound.path_length,
        },
        "gap_to_lower_bound": crossing.map(|c| o.bound.gap(c.time)),
        "status": o.status,
        "stats": o.stats,
        "stage_seconds": o.stage_seconds,
        "solve_seconds": o.solve_seconds,
    })
}

/// The plan's crossing time less the relaxed optimum's, in frames: what rounding the sides to `+-1`, the
/// wall margin and the anglemod steps cost.
pub fn rounding_loss_frames(scene: &Scene, o: &Outcome) -> Option<f64> {
    let (c, r) = (o.trace.crossing?, o.relaxed?);
    Some(r.loss_frames(c.time, scene.frame_time_s()))
}

/// The rounding loss as the text output prints it, frames: behind the relaxed optimum, about how much of
/// it is the zigzag of alternating sides and the guard under the law's kink (`zigzag_frames` and
/// `guard_frames` of [`crate::optimise::RelaxedCertificate`]; the guard where it costs anything); ahead of
/// it, why: the plan touches a wall (its least clearance `min_clearance_units` is under
/// [`CERTIFIED_CLEARANCE_UNITS`], so it is no run of the relaxed problem), or the relaxed optimum found is
/// a local one.
fn rounding_loss_text(
    loss_frames: f64,
    min_clearance_units: f64,
    zigzag_frames: Option<f64>,
    guard_frames: Option<f64>,
) -> String {
    let why = if loss_frames >= 0.0 {
        let guard = guard_frames
            .filter(|&g| g > 0.0)
            .map_or(String::new(), |g| {
                format!(", {g:.3} the guard half an angle step under the law's kink")
            });
        zigzag_frames.map_or(String::new(), |z| {
            format!(
                " (about {z:.3} of it the estimated zigzag of sides alternating at full acceleration{guard})"
            )
        })
    } else if min_clearance_units < CERTIFIED_CLEARANCE_UNITS {
        " (the plan is ahead: it touches a wall, and the relaxed problem holds only runs clear of the walls)"
            .to_string()
    } else {
        " (the plan is ahead: the relaxed optimum found is a local one)".to_string()
    };
    format!("{loss_frames:>10.3} frames{why}")
}

/// A plan in the `--json` object.
#[derive(serde::Serialize)]
struct PlanJson<'a> {
    label: &'a str,
    controls: &'a [crate::physics::Control],
}

/// The `--json` object of a solve as text: `summary` ([`summary_json`]) and `plans`, what `strafeopt
/// report` replays to rebuild both runs. The plans are written straight from the controls: as a JSON
/// tree they would take some two kilobytes a frame (gigabytes for a run of millions of frames).
fn json_with_plans(summary: &Value, o: &Outcome) -> Result<String> {
    #[derive(serde::Serialize)]
    struct SolveJson<'a> {
        #[serde(flatten)]
        summary: &'a Value,
        plans: [PlanJson<'a>; 2],
    }
    let out = SolveJson {
        summary,
        plans: [
            PlanJson {
                label: "greedy",
                controls: &o.greedy.controls,
            },
            PlanJson {
                label: "optimised",
                controls: &o.controls,
            },
        ],
    };
    let mut text = serde_json::to_string(&out)
        .map_err(|e| Error::Io(format!("serialising the result: {e}")))?;
    text.push('\n');
    Ok(text)
}

/// A frame rate as typed: whole rates without decimals (`100`), others with two (`66.67`).
pub fn fps_text(fps: f64) -> String {
    if fps.fract() == 0.0 && fps.abs() < 1e15 {
        format!("{fps:.0}")
    } else {
        format!("{fps:.2}")
    }
}

/// One `label: value` line with the labels in one column.
pub fn field(label: &str, value: impl std::fmt::Display) -> String {
    format!("{:<16} {value}\n", format!("{label}:"))
}

fn summary_text(scene: &Scene, o: &Outcome) -> String {
    let mut s = format!(
        "{} ({} at {} fps)\n",
        scene.name,
        scene.preset.name(),
        fps_text(scene.vars.fps)
    );
    s.push_str(&runs_text(o));
    s.push_str(&certificate_text(scene, o));
    s.push_str(&gains_text(o));
    s.push_str(&work_text(o));
    s
}

/// A crossing's time, frame and how far through it, or that the line was not reached.
fn crossing_text(c: Option<crate::sim::Crossing>) -> String {
    c.map_or("not reached".to_string(), |c| {
        format!(
            "{:>10.6} s (frame {}, {:.4} through it)",
            c.time, c.frames, c.fraction
        )
    })
}

/// The summary's runs: the plan, its engine-exact replay, the greedy run and its guide, and the lower
/// bound.
fn runs_text(o: &Outcome) -> String {
    let lb = o.bound.crossing;
    let mut s = field(
        "plan",
        format!("{} ({})", crossing_text(o.trace.crossing), o.source),
    );
    s.push_str(&field(
        "engine-exact",
        format!(
            "{}, {}",
            crossing_text(o.engine_exact.crossing),
            match (o.engine_exact.feasible(), o.engine_exact.interrupted) {
                (true, _) => "valid",
                (false, true) => "not checked (stopped)",
                (false, false) => "INVALID",
            }
        ),
    ));
    s.push_str(&field(
        "greedy",
        format!(
            "{}, {}",
            crossing_text(o.greedy.crossing),
            if o.greedy.feasible() {
                "valid"
            } else {
                "breaks a rule"
            }
        ),
    ));
    s.push_str(&field("greedy guide", o.greedy_guide));
    s.push_str(&field(
        "lower bound",
        format!("{:>10.6} s (frame {})", lb.time, lb.frames),
    ));
    s
}

/// The summary's certificate: the relaxed optimum with its starts and spread, and the rounding loss.
fn certificate_text(scene: &Scene, o: &Outcome) -> String {
    let mut s = String::new();
    if let Some(r) = o.relaxed {
        let spread = match r.short {
            0 => format!("spread {:.6} s", r.spread),
            k => format!(
                "{k} still improving when stopped; spread of the others {:.6} s",
                r.spread
            ),
        };
        let left = r.frame_left(scene.frame_time_s());
        s.push_str(&field(
            "relaxed optimum",
            format!(
                "{:>10.6} s (frame {}, {left:.3} of it left; a local optimum: {} of {} starts reached the \
                 line, {spread})",
                r.time, r.frames, r.reached, r.starts
            ),
        ));
    }
    if let Some(loss) = rounding_loss_frames(scene, o) {
        let zigzag = o.relaxed.and_then(|r| r.zigzag_frames);
        let guard = o.relaxed.and_then(|r| r.guard_frames);
        let text = rounding_loss_text(loss, o.trace.min_clearance(), zigzag, guard);
        s.push_str(&field("rounding loss", text));
    }
    s
}

/// The summary's comparisons of a plan that crosses: its gap to the lower bound and its gain on a valid
/// greedy run.
fn gains_text(o: &Outcome) -> String {
    let mut s = String::new();
    if let Some(c) = o.trace.crossing {
        s.push_str(&field(
            "gap to bound",
            format!("{:>10.3} %", 100.0 * o.bound.gap(c.time)),
        ));
        if let Some(g) = o.greedy.crossing.filter(|_| o.greedy.feasible()) {
            s.push_str(&field(
                "gain on greedy",
                format!(
                    "{:>10.6} s ({} frames)",
                    g.time - c.time,
                    g.frames as i64 - c.frames as i64
                ),
            ));
        }
    }
    s
}

/// The summary's plan clearance, status and work: the solve's time, iterations and seconds by stage.
fn work_text(o: &Outcome) -> String {
    let clearance = o.trace.min_clearance();
    let mut s = field(
        "min clearance",
        if clearance.is_finite() {
            format!("{clearance:>10.6} units")
        } else {
            "no walls".to_string()
        },
    );
    s.push_str(&field("status", &o.status));
    s.push_str(&field(
        "solve time",
        format!(
            "{:>10.2} s ({} iterations)",
            o.solve_seconds, o.stats.iterations
        ),
    ));
    s.push_str(&field("by stage", stage_seconds_text(&o.stage_seconds)));
    s
}

/// The stages that took any time, each with its seconds, in the order they ran.
fn stage_seconds_text(seconds: &StageSeconds) -> String {
    let stages: Vec<String> = seconds
        .named()
        .iter()
        .filter(|(_, s)| *s >= 0.005)
        .map(|(name, s)| format!("{name} {s:.2} s"))
        .collect();
    stages.join(", ")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_plan_ahead_of_the_relaxed_optimum_says_why() {
        // Behind it: the loss alone. Ahead of it, touching a wall (a greedy run sliding along one): not a
        // run of the relaxed problem. Ahead of it, clear of the walls: the relaxed optimum is local.
        assert_eq!(
            rounding_loss_text(0.25, 1.0, None, None),
            "     0.250 frames"
        );
        let zigzag = rounding_loss_text(0.169, 1.0, Some(0.15), Some(0.0));
        assert!(
            zigzag.starts_with("     0.169 frames (about 0.150 of it the estimated zigzag")
                && !zigzag.contains("guard"),
            "{zigzag}"
        );
        let guard = rounding_loss_text(0.83, 1.0, Some(0.011), Some(0.79));
        assert!(
            guard.ends_with(
                "acceleration, 0.790 the guard half an angle step under the law's kink)"
            ),
            "{guard}"
        );
        let touching = rounding_loss_text(-63.4, 0.0, Some(0.1), Some(0.5));
        assert!(touching.starts_with("   -63.400 frames (") && touching.contains("touches a wall"));
        let clear = rounding_loss_text(-0.2, 2.0 * CERTIFIED_CLEARANCE_UNITS, None, None);
        assert!(
            clear.contains("a local one") && !clear.contains("wall"),
            "{clear}"
        );
    }
}
