//! `strafeopt solve`: the minimal-time plan of a scene, beside the greedy baseline and the lower bound.

use super::args::{QualityArg, SolveArgs};
use super::write_artifacts;
use crate::error::{Error, Result};
use crate::optimise::search::{self, time_limit};
use crate::optimise::{Outcome, Quality, SearchSettings};
use crate::scene::Scene;
use serde_json::{json, Value};

/// Runs `solve` and returns what to print. No valid path: [`Error::NoValidPath`] (exit 3), nothing written.
pub fn run(args: &SolveArgs) -> Result<String> {
    let quality = match args.quality {
        QualityArg::Fast => Quality::Fast,
        QualityArg::Balanced => Quality::Balanced,
        QualityArg::Exact => Quality::Exact,
    };
    let mut settings = SearchSettings::for_quality(quality);
    if let Some(s) = args.time_limit {
        settings.time_limit = Some(time_limit(s)?);
    }
    let scene = Scene::load(&args.scene)?;
    if let Some(path) = &args.artifacts.hltas {
        super::simulate::require_goldsrc_for_hltas(&scene, path)?;
    }
    // Progress on stderr for people watching a terminal; none with --json or when stderr is redirected.
    let show = !args.output.json && std::io::IsTerminal::is_terminal(&std::io::stderr());
    let started = std::time::Instant::now();
    let outcome = search::solve_with_progress(&scene, &settings, &mut |p| {
        if show {
            let line = match p {
                search::Progress::Baseline {
                    greedy_frames,
                    bound_frames,
                } => format!(
                    "greedy {}, lower bound frame {bound_frames}",
                    greedy_frames.map_or("did not finish".to_string(), |f| format!("frame {f}"))
                ),
                search::Progress::FrameCount { frames, reached } => format!(
                    "trying {frames} frames: {}",
                    reached.map_or("not reached".to_string(), |r| format!(
                        "crosses in frame {r}"
                    ))
                ),
                search::Progress::Finishing => {
                    "rounding sides, polishing, checking in engine-exact mode".into()
                }
            };
            eprint!(
                "\r\x1b[2K[{:>6.1} s] {line}",
                started.elapsed().as_secs_f64()
            );
        }
    });
    if show {
        eprintln!();
    }
    let outcome = outcome?;
    if !outcome.trace.feasible() {
        return Err(Error::NoValidPath(format!(
            "{}: neither the optimiser nor the greedy strafer found a run that reaches the finish without \
             breaking a rule",
            scene.origin
        )));
    }
    let summary = summary_json(&scene, quality, &outcome);
    write_artifacts(
        &args.artifacts,
        &scene,
        &outcome.trace,
        &[("greedy", &outcome.greedy), ("optimised", &outcome.trace)],
        &outcome.bound,
        &summary,
    )?;
    if args.output.json {
        Ok(format!("{summary}\n"))
    } else {
        Ok(summary_text(&scene, &outcome))
    }
}

fn quality_name(q: Quality) -> &'static str {
    match q {
        Quality::Fast => "fast",
        Quality::Balanced => "balanced",
        Quality::Exact => "exact",
    }
}

/// The `--json` object of a solve.
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
        "gap_to_lower_bound": crossing.map(|c| (c.time - lb.time) / lb.time.max(f64::MIN_POSITIVE)),
        "status": o.status,
        "stats": o.stats,
        "solve_seconds": o.solve_seconds,
        // What `strafeopt report` replays to rebuild both runs.
        "plans": [
            {"label": "greedy", "controls": o.greedy.controls},
            {"label": "optimised", "controls": o.controls},
        ],
    })
}

/// The plan's crossing time less the relaxed optimum's, in frames: what rounding the sides to `+-1`, the
/// wall margin and the anglemod steps cost.
pub fn rounding_loss_frames(scene: &Scene, o: &Outcome) -> Option<f64> {
    let (c, r) = (o.trace.crossing?, o.relaxed?);
    Some((c.time - r.time) / scene.frame_time_s())
}

fn summary_text(scene: &Scene, o: &Outcome) -> String {
    let fmt_time = |c: Option<crate::sim::Crossing>| {
        c.map_or("not reached".to_string(), |c| {
            format!(
                "{:.6} s (frame {}, {:.4} through it)",
                c.time, c.frames, c.fraction
            )
        })
    };
    let lb = o.bound.crossing;
    let mut s = format!(
        "{} ({} at {} fps)\nplan ({}):      {}\n",
        scene.name,
        scene.preset.name(),
        scene.vars.fps,
        o.source,
        fmt_time(o.trace.crossing)
    );
    s.push_str(&format!(
        "engine-exact:    {}{}\n",
        fmt_time(o.engine_exact.crossing),
        if o.engine_exact.feasible() {
            ", valid"
        } else {
            ", INVALID"
        }
    ));
    s.push_str(&format!(
        "greedy:          {}{}\n",
        fmt_time(o.greedy.crossing),
        if o.greedy.feasible() {
            ", valid"
        } else {
            ", breaks a rule"
        }
    ));
    s.push_str(&format!("greedy guide:    {}\n", o.greedy_guide));
    s.push_str(&format!(
        "lower bound:     {:.6} s (frame {})\n",
        lb.time, lb.frames
    ));
    if let Some(r) = o.relaxed {
        s.push_str(&format!(
            "relaxed optimum: {:.6} s (frame {}; a local optimum: {} of {} starts reached the line, spread {:.6} s)\n",
            r.time, r.frames, r.reached, r.starts, r.spread
        ));
    }
    if let Some(loss) = rounding_loss_frames(scene, o) {
        s.push_str(&format!("rounding loss:   {loss:.3} frames\n"));
    }
    if let Some(c) = o.trace.crossing {
        s.push_str(&format!(
            "gap to bound:    {:.3}%\n",
            100.0 * (c.time - lb.time) / lb.time.max(f64::MIN_POSITIVE)
        ));
        if let Some(g) = o.greedy.crossing.filter(|_| o.greedy.feasible()) {
            s.push_str(&format!(
                "gain on greedy:  {:.6} s ({} frames)\n",
                g.time - c.time,
                g.frames as i64 - c.frames as i64
            ));
        }
    }
    s.push_str(&format!(
        "min clearance:   {:.3e} units\nstatus:          {}\nsolve time:      {:.2} s ({} iterations)\n",
        o.trace.min_clearance(),
        o.status,
        o.solve_seconds,
        o.stats.iterations
    ));
    s
}
