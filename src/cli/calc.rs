//! `strafeopt calc`: resolves the flags into movement variables (stage two) and computes each figure with
//! the library, the closed form beside the simulation.

use super::args::{CalcForm, EngineFlags, PresetArg};
use crate::error::{require_non_negative, require_positive, Error, Result};
use crate::physics::closed_form::{
    airstrafe_frames_to_speed, frames_to_speed_by_stepping, groundstrafe_frames_to_speed,
    max_groundstrafe_speed, max_groundstrafe_speed_by_stepping,
};
use crate::physics::curvature::{
    air_law, bend_arc_radius, ground_law, max_accel_radii, speed_for_radius,
    speed_for_radius_source_text, HULL_WIDTH_UNITS,
};
use crate::physics::{abh, MovementVars, Preset, VarOverrides};
use crate::scene::Scene;
use crate::sim::abh::{run_abh, AbhParams};
use crate::sim::Simulation;
use serde_json::{json, Value};

/// Most frames `frames-to-speed` steps before it trusts the closed form alone.
const MAX_STEPPED_FRAMES: f64 = 5e7;
/// Largest change per frame, ups, at which the simulated groundstrafe speed counts as settled.
const SETTLE_TOL_UPS: f64 = 1e-10;
/// Frame cap for settling.
const MAX_SETTLE_FRAMES: u64 = 50_000_000;

/// A computed figure: the JSON object and its text form.
pub struct Figures {
    /// The JSON object (`--json`).
    pub json: Value,
    /// Lines for people.
    pub text: String,
}

/// Default frames per second of a preset: 1000 for Half-Life (the usual TAS rate), 66.67 for Half-Life 2
/// (its 0.015 s tick).
fn default_fps(preset: Preset) -> f64 {
    match preset {
        Preset::GoldSrc => 1000.0,
        Preset::SourceHl2 => 200.0 / 3.0,
    }
}

/// The movement variables from the flags, validated; `default` is the preset when `--preset` is absent.
pub fn resolve_vars(flags: &EngineFlags, default: Preset) -> Result<MovementVars> {
    let preset = match flags.preset {
        Some(PresetArg::Goldsrc) => Preset::GoldSrc,
        Some(PresetArg::SourceHl2) => Preset::SourceHl2,
        None => default,
    };
    let overrides = VarOverrides {
        fps: flags.fps,
        accelerate: flags.accelerate,
        airaccelerate: flags.airaccelerate,
        maxspeed: flags.maxspeed,
        friction: flags.friction,
        stopspeed: flags.stopspeed,
        maxvelocity: flags.maxvelocity,
        gravity: flags.gravity,
        entity_friction: flags.entity_friction,
        ..VarOverrides::default()
    };
    overrides
        .apply(MovementVars::preset(preset, default_fps(preset)))
        .map_err(|e| match e {
            Error::InvalidValue {
                name,
                value,
                allowed,
            } => Error::InvalidValue {
                name: format!("--{name}"),
                value,
                allowed,
            },
            other => other,
        })
}

fn inputs(vars: &MovementVars, preset_name: &str) -> Value {
    json!({
        "preset": preset_name,
        "fps": vars.fps,
        "frame_time": vars.frame_time_s(),
        "maxspeed": vars.maxspeed,
        "accelerate": vars.accelerate,
        "airaccelerate": vars.airaccelerate,
        "friction": vars.friction,
        "edgefriction": vars.edgefriction,
        "entity_friction": vars.entity_friction,
        "stopspeed": vars.stopspeed,
        "maxvelocity": vars.maxvelocity,
        "gravity": vars.gravity,
    })
}

fn preset_name(flags: &EngineFlags, default: Preset) -> &'static str {
    match flags.preset {
        Some(PresetArg::Goldsrc) => Preset::GoldSrc.name(),
        Some(PresetArg::SourceHl2) => Preset::SourceHl2.name(),
        None => default.name(),
    }
}

fn finite(name: &str, v: f64) -> Result<f64> {
    if v.is_finite() {
        Ok(v)
    } else {
        Err(Error::Numerical(format!("{name} came out as {v}")))
    }
}

/// Runs one `calc` form.
pub fn run(form: &CalcForm) -> Result<Figures> {
    match form {
        CalcForm::FramesToSpeed {
            from,
            to,
            ground,
            engine,
            ..
        } => frames_to_speed(engine, *from, *to, *ground),
        CalcForm::MaxGroundSpeed {
            edge_friction,
            engine,
            ..
        } => max_ground_speed(engine, *edge_friction),
        CalcForm::Radius { speed, engine, .. } => radius(engine, *speed),
        CalcForm::SpeedForRadius { radius, engine, .. } => speed_for(engine, *radius),
        CalcForm::Bend { width, engine, .. } => bend(engine, *width),
        CalcForm::Abh {
            max_speed,
            hop_time,
            distance,
            engine,
            ..
        } => abh_table(engine, *max_speed, *hop_time, *distance),
    }
}

/// True when the form asked for `--json`.
pub fn wants_json(form: &CalcForm) -> bool {
    match form {
        CalcForm::FramesToSpeed { output, .. }
        | CalcForm::MaxGroundSpeed { output, .. }
        | CalcForm::Radius { output, .. }
        | CalcForm::SpeedForRadius { output, .. }
        | CalcForm::Bend { output, .. }
        | CalcForm::Abh { output, .. } => output.json,
    }
}

fn frames_to_speed(engine: &EngineFlags, from: f64, to: f64, ground: bool) -> Result<Figures> {
    let vars = resolve_vars(engine, Preset::GoldSrc)?;
    require_non_negative("--from", from)?;
    require_non_negative("--to", to)?;
    let reachable = vars.maxvelocity * std::f64::consts::SQRT_2;
    if to > reachable {
        return Err(Error::invalid(
            "--to",
            to,
            format!(
                "at most sv_maxvelocity * sqrt 2 = {reachable:.4} ups (the per-component clamp)"
            ),
        ));
    }
    let closed = if ground {
        groundstrafe_frames_to_speed(
            from,
            to,
            ground_law(&vars),
            vars.frame_time_s(),
            vars.friction_k(false),
            vars.stopspeed,
        )
    } else {
        airstrafe_frames_to_speed(from, to, air_law(&vars))
    };
    if ground {
        let limit = max_groundstrafe_speed(&vars, false);
        if to >= limit {
            return Err(Error::invalid(
                "--to",
                to,
                format!("below the maximum groundstrafe speed {limit:.4} ups (--ground)"),
            ));
        }
    }
    let (frames, method) = match closed {
        Some(n) if n > MAX_STEPPED_FRAMES => (n.ceil() as u64, "closed-form"),
        _ => (
            frames_to_speed_by_stepping(
                &vars,
                from,
                to,
                ground,
                (MAX_STEPPED_FRAMES * 2.0) as u64,
            )?,
            "stepping",
        ),
    };
    let tau = vars.frame_time_s();
    let kind = if ground { "groundstrafe" } else { "airstrafe" };
    let closed_text = match closed {
        Some(n) => format!("{n:.2}"),
        None => "none (outside the closed form's regime)".to_string(),
    };
    Ok(Figures {
        json: json!({
            "form": "frames-to-speed",
            "frames": frames,
            "frames_method": method,
            "frames_closed_form": closed,
            "time": frames as f64 * tau,
            "from": from,
            "to": to,
            "ground": ground,
            "inputs": inputs(&vars, preset_name(engine, Preset::GoldSrc)),
        }),
        text: format!(
            "{kind} {from:.2} -> {to:.2} ups at {} fps\nframes:             {frames} (by {method})\n\
             frames closed form: {closed_text}\ntime:               {:.4} s\n",
            super::solve::fps_text(vars.fps),
            frames as f64 * tau
        ),
    })
}

fn max_ground_speed(engine: &EngineFlags, edge: bool) -> Result<Figures> {
    let vars = resolve_vars(engine, Preset::GoldSrc)?;
    let speed = max_groundstrafe_speed(&vars, edge);
    if !speed.is_finite() || vars.friction_k(edge) <= 0.0 {
        return Err(Error::invalid(
            "--friction",
            vars.friction_k(edge),
            "such that k = sv_friction * k_e * e_f is above 0 (no steady state otherwise)",
        ));
    }
    let (simulated, frames) =
        max_groundstrafe_speed_by_stepping(&vars, edge, SETTLE_TOL_UPS, MAX_SETTLE_FRAMES);
    let simulated = finite("simulated speed", simulated)?;
    Ok(Figures {
        json: json!({
            "form": "max-ground-speed",
            "speed": speed,
            "speed_simulated": simulated,
            "frames_to_settle": frames,
            "edge_friction": edge,
            "friction_k": vars.friction_k(edge),
            "inputs": inputs(&vars, preset_name(engine, Preset::GoldSrc)),
        }),
        text: format!(
            "maximum groundstrafe speed at {} fps{}\nspeed (closed form): {speed:.4} ups\n\
             speed (simulated):   {simulated:.4} ups after {frames} frames\n",
            super::solve::fps_text(vars.fps),
            if edge { ", edge friction" } else { "" }
        ),
    })
}

fn radius(engine: &EngineFlags, speed: f64) -> Result<Figures> {
    let vars = resolve_vars(engine, Preset::GoldSrc)?;
    require_positive("--speed", speed)?;
    let r = max_accel_radii(&vars, speed);
    let source = finite("radius", r.source_text)?;
    let measured = finite("radius_measured", r.measured)?;
    Ok(Figures {
        json: json!({
            "form": "radius",
            "radius": source,
            "radius_measured": measured,
            "radius_first_order": r.first_order,
            "ratio": source / measured,
            "speed": speed,
            "theta_deg": r.theta_rad.to_degrees(),
            "mu": r.mu,
            "inputs": inputs(&vars, preset_name(engine, Preset::GoldSrc)),
        }),
        text: format!(
            "maximum-acceleration airstrafe at {speed:.2} ups, {} fps (theta {:.4} deg, mu {:.4})\n\
             radius (source text's relation): {source:.4} units\n\
             radius (circle through 3 simulated positions): {measured:.4} units\n\
             radius (first order tau v'^2/(mu sin theta)): {:.4} units\n\
             the relation gives {:.3} times the measured radius (docs/physics.md section 9)\n",
            super::solve::fps_text(vars.fps),
            r.theta_rad.to_degrees(),
            r.mu,
            r.first_order,
            source / measured
        ),
    })
}

fn speed_for(engine: &EngineFlags, radius: f64) -> Result<Figures> {
    let vars = resolve_vars(engine, Preset::GoldSrc)?;
    require_positive("--radius", radius)?;
    let measured =
        speed_for_radius(&vars, radius).map_err(|e| flag_unreachable("--radius", radius, e))?;
    let source = speed_for_radius_source_text(&vars, radius).ok();
    Ok(Figures {
        json: json!({
            "form": "speed-for-radius",
            "speed": measured,
            "speed_source_text": source,
            "radius": radius,
            "inputs": inputs(&vars, preset_name(engine, Preset::GoldSrc)),
        }),
        text: format!(
            "speed whose maximum-acceleration turn has radius {radius:.2} units at {} fps\n\
             speed (measured relation): {measured:.4} ups\nspeed (source text's relation): {}\n",
            super::solve::fps_text(vars.fps),
            source.map_or("none".to_string(), |s| format!("{s:.4} ups"))
        ),
    })
}

fn flag_unreachable(flag: &str, value: f64, e: Error) -> Error {
    match e {
        Error::Unreachable { what } => Error::invalid(flag, value, format!("reachable: {what}")),
        other => other,
    }
}

fn bend(engine: &EngineFlags, width: f64) -> Result<Figures> {
    let vars = resolve_vars(engine, Preset::GoldSrc)?;
    if !(width.is_finite() && width > HULL_WIDTH_UNITS) {
        return Err(Error::invalid(
            "--width",
            width,
            format!("a finite number above {HULL_WIDTH_UNITS} (the hull width)"),
        ));
    }
    let d = width - HULL_WIDTH_UNITS;
    let r = bend_arc_radius(d);
    let speed = speed_for_radius(&vars, r).map_err(|e| flag_unreachable("--width", width, e))?;
    let source = speed_for_radius_source_text(&vars, r).ok();
    Ok(Figures {
        json: json!({
            "form": "bend",
            "radius": r,
            "speed": speed,
            "speed_source_text": source,
            "width": width,
            "width_for_centre": d,
            "inputs": inputs(&vars, preset_name(engine, Preset::GoldSrc)),
        }),
        text: format!(
            "90-degree bend of width {width:.2} units ({d:.2} for the hull centre) at {} fps\n\
             largest arc radius (2 + sqrt 2) d: {r:.4} units\n\
             speed on it (measured relation): {speed:.4} ups\nspeed (source text's relation): {}\n",
            super::solve::fps_text(vars.fps),
            source.map_or("none".to_string(), |s| format!("{s:.4} ups"))
        ),
    })
}

fn abh_table(
    engine: &EngineFlags,
    max_speed: f64,
    hop_time: f64,
    distance: f64,
) -> Result<Figures> {
    let vars = resolve_vars(engine, Preset::SourceHl2)?;
    require_positive("--max-speed", max_speed)?;
    require_positive("--hop-time", hop_time)?;
    require_positive("--distance", distance)?;
    let a = abh::article_model(max_speed, hop_time, distance, vars.maxvelocity);
    let crossing = finite("crossing_time", a.crossing_time)?;
    let mut text = format!(
        "accelerated backhopping, the article's model: Mx = {max_speed:.2} ups, hop time {hop_time:.3} s, \
         sv_maxvelocity {:.2} ups\n  hop     time (s)   distance (units)   speed (ups)\n",
        vars.maxvelocity
    );
    for (i, h) in a.hops.iter().enumerate() {
        text.push_str(&format!(
            "  {:>3}   {:>8.2}   {:>16.2}   {:>11.2}\n",
            i + 1,
            h.time,
            h.distance,
            h.speed
        ));
    }
    text.push_str(&format!(
        "line at {distance:.2} units crossed {crossing:.3} s after the first jump; the hop lands {:.2} units past it\n",
        a.landing_past_line
    ));
    let frame_level = abh_frame_level(&vars, max_speed, distance)?;
    text.push_str(&frame_level.text);
    Ok(Figures {
        json: json!({
            "form": "abh",
            "hops": a.hops,
            "crossing_time": crossing,
            "landing_past_line": a.landing_past_line,
            "max_speed": max_speed,
            "hop_time": hop_time,
            "distance": distance,
            "inputs": inputs(&vars, preset_name(engine, Preset::SourceHl2)),
            "frame_level": frame_level.json,
        }),
        text,
    })
}

/// The scene of the frame-level ABH run for `calc abh` (docs/physics.md section 11): the resolved variables with
/// max speed `max_speed`, every effect the run needs, a 64.04-unit rule lane (1.22 m) whose line is
/// `distance` units from the start, a crouched start at rest. Written as a scene file and loaded, so it is
/// validated like any other scene.
fn abh_scene_toml(vars: &MovementVars, max_speed: f64, distance: f64) -> String {
    format!(
        "name = \"calc-abh\"\n\
         [engine]\npreset = \"source-hl2\"\nfps = {:?}\nmaxspeed = {max_speed:?}\naccelerate = {:?}\n\
         airaccelerate = {:?}\nfriction = {:?}\nentity-friction = {:?}\nstopspeed = {:?}\n\
         maxvelocity = {:?}\ngravity = {:?}\n\
         effects = [\"air-accel\", \"ground-accel\", \"friction\", \"gravity\", \"jump\", \"jump-boost\", \
         \"duck\", \"max-velocity\", \"walls\"]\n\
         [start]\nposition = [40.0, {:?}]\nvelocity = [0.0, 0.0]\non-ground = true\nducked = true\n\
         [lane]\nwidth = {ABH_LANE_WIDTH_UNITS:?}\nlength = {:?}\nkind = \"rule\"\n",
        vars.fps,
        vars.accelerate,
        vars.airaccelerate,
        vars.friction,
        vars.entity_friction,
        vars.stopspeed,
        vars.maxvelocity,
        vars.gravity,
        ABH_LANE_WIDTH_UNITS / 2.0,
        40.0 + distance,
    )
}

/// The lane width of the 100 m, units (1.22 m, docs/physics.md section 1).
const ABH_LANE_WIDTH_UNITS: f64 = 64.04;

/// The frame-level ABH run (`sim::abh`) beside the article's model: hops, the time from the pistol to the
/// first jump and to the line, and whether the run stayed in the lane (also engine-exact).
fn abh_frame_level(vars: &MovementVars, max_speed: f64, distance: f64) -> Result<Figures> {
    // A line closer than the default start's hull allows has no lane scene: the frame-level run is
    // skipped (`null`) rather than the article's figures refused.
    let scene = match Scene::from_toml_str(&abh_scene_toml(vars, max_speed, distance), "calc abh") {
        Ok(scene) => scene,
        Err(e) => {
            return Ok(Figures {
                json: Value::Null,
                text: format!("frame-level run: skipped (no lane scene for these inputs: {e})\n"),
            })
        }
    };
    let sim = Simulation::new(&scene)?;
    let run = run_abh(&sim, AbhParams::default());
    let hops: Vec<Value> = run
        .hops
        .iter()
        .map(
            |h| json!({"time": h.time, "speed": h.speed, "frame": h.frame, "hop_time": h.hop_time}),
        )
        .collect();
    let mut text = format!(
        "frame-level run (tau = {:.4} s, gravity {:.2} ups/s, 64.04-unit rule lane, crouched start at rest):\n\
         \x20 hop   jump frame   time from pistol (s)   hop time (s)   speed (ups)\n",
        vars.frame_time_s(),
        vars.gravity
    );
    for (i, h) in run.hops.iter().enumerate() {
        text.push_str(&format!(
            "  {:>3}   {:>10}   {:>20.3}   {:>12}   {:>11.2}\n",
            i + 1,
            h.frame,
            h.time,
            h.hop_time.map_or("-".to_string(), |t| format!("{t:.3}")),
            h.speed
        ));
    }
    let fmt = |t: Option<f64>| t.map_or("none".to_string(), |t| format!("{t:.3} s"));
    text.push_str(&format!(
        "first jump: {}; line crossed from the pistol: {} ({} after the first jump); {}; engine-exact: {}\n",
        fmt(run.first_jump),
        fmt(run.pistol_to_line),
        fmt(run.pistol_to_line.zip(run.first_jump).map(|(l, j)| l - j)),
        if run.in_lane { "stayed in the lane" } else { "LEFT the lane" },
        match (run.engine_exact.feasible(), run.engine_exact.crossing) {
            (true, Some(c)) => format!("valid, line at {:.3} s", c.time),
            (false, _) if run.engine_exact.broke_rule => "INVALID: left the lane".to_string(),
            _ => "INVALID: did not reach the line".to_string(),
        }
    ));
    Ok(Figures {
        json: json!({
            "hops": hops,
            "pistol_to_line": run.pistol_to_line,
            "first_jump": run.first_jump,
            "in_lane": run.in_lane,
            "engine_exact": {
                "pistol_to_line": run.engine_exact.crossing.map(|c| c.time),
                "in_lane": !run.engine_exact.broke_rule && run.engine_exact.finite,
                "feasible": run.engine_exact.feasible(),
            },
        }),
        text,
    })
}
