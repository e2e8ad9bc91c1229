//! `strafeopt simulate`: loads a scene, runs a controller, and prints its time beside the lower bound.

use super::args::{ControllerArg, SimulateArgs};
use super::write_artifacts;
use crate::error::{Error, Result};
use crate::optimise::lower_bound;
use crate::physics::{Game, Side};
use crate::scene::Scene;
use crate::sim::controllers::{best_greedy, best_sharp_turning_greedy, GREEDY_LOOKAHEADS_UNITS};
use crate::sim::{Greedy, SideStrafer, Simulation, Trace};
use serde_json::{json, Value};

/// Runs `simulate` and returns what to print.
pub fn run(args: &SimulateArgs) -> Result<String> {
    let scene = Scene::load(&args.scene)?;
    if let Some(path) = &args.artifacts.hltas {
        require_goldsrc_for_hltas(&scene, path)?;
    }
    let sim = Simulation::new(&scene)?;
    let bound = lower_bound(&scene, sim.corridor())?;
    let lookahead = match args.lookahead {
        Some(la) if !(la.is_finite() && la > 0.0) => {
            return Err(Error::invalid("--lookahead", la, "a finite number above 0"));
        }
        la => la,
    };
    let (trace, lookahead) = match args.controller {
        ControllerArg::Greedy | ControllerArg::SharpTurns => {
            let sharp = matches!(args.controller, ControllerArg::SharpTurns);
            match lookahead {
                Some(la) => {
                    let mut strafer = Greedy::new(bound.path.clone(), la);
                    if sharp {
                        strafer = strafer.with_sharp_turns();
                    }
                    (sim.run(&mut strafer), Some(la))
                }
                None => {
                    let best = if sharp {
                        best_sharp_turning_greedy
                    } else {
                        best_greedy
                    };
                    let (t, la) = best(&sim, &bound.path, &GREEDY_LOOKAHEADS_UNITS);
                    (t, Some(la))
                }
            }
        }
        ControllerArg::MaxAccelLeft => (sim.run(&mut SideStrafer { side: Side::Left }), None),
        ControllerArg::MaxAccelRight => (sim.run(&mut SideStrafer { side: Side::Right }), None),
        ControllerArg::Abh => (sim.run(&mut crate::sim::abh::Abh::default()), None),
    };
    let summary = summary_json(&scene, &trace, &bound, lookahead);
    write_artifacts(
        &args.artifacts,
        &scene,
        &trace,
        &[(&trace.controller, &trace)],
        &bound,
        &summary,
    )?;
    if args.output.json {
        Ok(format!("{summary}\n"))
    } else {
        Ok(summary_text(&scene, &trace, &bound, lookahead))
    }
}

/// `--hltas` writes Bunnymod XT scripts, which replay Half-Life only: a Source scene is refused before
/// anything runs, with one line naming the flag.
pub fn require_goldsrc_for_hltas(scene: &Scene, path: &std::path::Path) -> Result<()> {
    if scene.vars.game == Game::GoldSrc {
        return Ok(());
    }
    Err(Error::InvalidValue {
        name: "--hltas".to_string(),
        value: path.display().to_string(),
        allowed: format!(
            "used with a GoldSrc scene (Bunnymod XT scripts replay Half-Life; {} is a {} scene)",
            scene.name,
            scene.preset.name()
        ),
    })
}

/// The scene file a result names (`"scene_path"`): the absolute path of the file loaded, so `report`
/// can rebuild the runs from any directory; the origin as given when it cannot be resolved.
pub fn scene_path(scene: &Scene) -> String {
    std::fs::canonicalize(&scene.origin)
        .map(|p| p.display().to_string())
        .unwrap_or_else(|_| scene.origin.clone())
}

fn opt_finite(v: f64) -> Option<f64> {
    v.is_finite().then_some(v)
}

/// The `--json` object of a simulated run. It carries what `strafeopt report` needs to rebuild the run:
/// `scene_path` (see [`scene_path`]), `controller` and `lookahead` (see [`super::report_cmd`]).
pub fn summary_json(
    scene: &Scene,
    trace: &Trace,
    bound: &crate::optimise::LowerBound,
    lookahead: Option<f64>,
) -> Value {
    let frames = trace
        .crossing
        .map_or(trace.frames.len() as u64, |c| c.frames);
    let gap = trace.crossing.map(|c| bound.gap(c.time));
    json!({
        "scenario": scene.name,
        "scene_path": scene_path(scene),
        "controller": trace.controller,
        "lookahead": lookahead,
        "frames": frames,
        "time": trace.crossing.map(|c| c.time),
        "crossing_fraction": trace.crossing.map(|c| c.fraction),
        "feasible": trace.feasible(),
        "min_clearance": opt_finite(trace.min_clearance()),
        "final_speed": trace.final_speed(),
        "collisions": trace.collisions(),
        "first_contact_frame": trace.first_contact(),
        "first_rule_violation_frame": trace.first_rule_violation(),
        "lower_bound": {
            "frames": bound.crossing.frames,
            "time": bound.crossing.time,
            "fraction": bound.crossing.fraction,
            "path_length": bound.path_length,
        },
        "gap_to_lower_bound": gap,
        "frame_time": scene.frame_time_s(),
        "effects": scene.effects.list(),
    })
}

fn summary_text(
    scene: &Scene,
    trace: &Trace,
    bound: &crate::optimise::LowerBound,
    lookahead: Option<f64>,
) -> String {
    let mut out = format!(
        "{} ({} at {} fps, effects: {})\ncontroller:     {}{}\n",
        scene.name,
        scene.preset.name(),
        super::solve::fps_text(scene.vars.fps),
        scene.effects,
        trace.controller,
        lookahead.map_or(String::new(), |l| format!(" (look-ahead {l:.1} units)"))
    );
    match trace.crossing {
        Some(c) => out.push_str(&format!(
            "time:           {:.6} s (line crossed in frame {}, {:.4} of the way through)\n",
            c.time, c.frames, c.fraction
        )),
        None => out.push_str(&format!(
            "time:           the line was not reached in {} frames\n",
            trace.frames.len()
        )),
    }
    let validity = match (trace.feasible(), trace.first_rule_violation()) {
        (true, _) => "valid".to_string(),
        (false, Some(f)) => format!("INVALID: broke a rule line in frame {f}"),
        (false, None) if trace.numerical_failure => "INVALID: numerical failure".to_string(),
        (false, None) => "INVALID: did not finish".to_string(),
    };
    out.push_str(&format!("run:            {validity}\n"));
    out.push_str(&format!("final speed:    {:.4} ups\n", trace.final_speed()));
    let clearance = trace.min_clearance();
    out.push_str(&if clearance.is_finite() {
        format!("min clearance:  {clearance:.6} units\n")
    } else {
        "min clearance:  no walls\n".to_string()
    });
    out.push_str(&format!(
        "collisions:     {}{}\n",
        trace.collisions(),
        trace
            .first_contact()
            .map_or(String::new(), |f| format!(" (first in frame {f})"))
    ));
    out.push_str(&format!(
        "lower bound:    {:.6} s (frame {}), shortest path {:.4} units\n",
        bound.crossing.time, bound.crossing.frames, bound.path_length
    ));
    if let Some(c) = trace.crossing {
        out.push_str(&format!(
            "gap to bound:   {:.3}%\n",
            100.0 * bound.gap(c.time)
        ));
    }
    out
}
