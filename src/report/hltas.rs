//! A planned run as a Bunnymod XT script (`.hltas`), written with the `hltas` crate.
//!
//! Each frame becomes a frame bulk with the scene's frame time, the frame's yaw as a set yaw (degrees,
//! the game's yaw is our [`Control::yaw_rad`] in degrees, reduced to `[0, 360)`), the movement keys and
//! jump / duck. Consecutive frames with the same yaw (as printed, an `f32`) and keys are merged into one
//! bulk with a frame count.
//!
//! Keys are on or off in a script: `forwardmove > 0` is `+forward`, `< 0` is `+back`; `sidemove > 0` is
//! `+moveright`, `< 0` is `+moveleft` (our controllers hold full keys, `cl_forwardspeed` /
//! `cl_sidespeed`, so nothing is lost). The script cannot set the start state: the player must be placed at
//! the scene's start position and velocity before it runs (the header comments say where). The game
//! quantises each yaw by anglemod (docs/physics.md section 1); a plan meant for the game should be checked in
//! engine-exact mode.
//!
//! [`Control::yaw_rad`]: crate::physics::Control::yaw_rad

use crate::error::{Error, Result};
use crate::physics::{Control, Game, MovementVars};
use crate::sim::Trace;
use hltas::types::{ActionKeys, AutoActions, AutoMovement, FrameBulk, Line, MovementKeys};
use hltas::HLTAS;
use std::io::Write;

/// The game's yaw, degrees in `[0, 360)`, of a yaw in radians (anticlockwise from +x, as the game's).
pub fn yaw_degrees(yaw_rad: f64) -> f64 {
    let d = yaw_rad.to_degrees().rem_euclid(360.0);
    // rem_euclid can round up to exactly 360 for tiny negative inputs.
    if d >= 360.0 {
        0.0
    } else {
        d
    }
}

/// [`yaw_degrees`] as the script stores it, an `f32` in `[0, 360)` (a yaw just below 360 that rounds up
/// to 360 in `f32` is written as 0, the same direction).
pub fn yaw_degrees_f32(yaw_rad: f64) -> f32 {
    let d = yaw_degrees(yaw_rad) as f32;
    if d >= 360.0 {
        0.0
    } else {
        d
    }
}

/// The frame time as the script prints it: the shortest decimal that reads back as `tau` seconds.
pub fn frame_time_text(vars: &MovementVars) -> String {
    format!("{}", vars.frame_time_s())
}

/// Builds the script of `trace`'s controls for a scene with variables `vars`; `title` goes into the header
/// comment (the scene's name).
///
/// Errors: [`Error::InvalidValue`] for a Source (Half-Life 2) scene (Bunnymod XT replays Half-Life only), an
/// empty trace, or a frame whose forwardmove or sidemove is not a key's (a plan with vectorial
/// compensation), [`Error::Numerical`] for a yaw that is not finite.
pub fn hltas_script(trace: &Trace, vars: &MovementVars, title: &str) -> Result<HLTAS> {
    if vars.game != Game::GoldSrc {
        return Err(Error::InvalidValue {
            name: "--hltas".to_string(),
            value: "a Source scene".to_string(),
            allowed: "a GoldSrc scene (Bunnymod XT scripts replay Half-Life only)".to_string(),
        });
    }
    if trace.controls.is_empty() {
        return Err(Error::InvalidValue {
            name: "--hltas".to_string(),
            value: "a run of 0 frames".to_string(),
            allowed: "a run of at least one frame".to_string(),
        });
    }
    if let Some(i) = trace.controls.iter().position(|c| !on_the_keys(c, vars)) {
        let c = &trace.controls[i];
        return Err(Error::InvalidValue {
            name: "--hltas".to_string(),
            value: format!(
                "frame {} with forwardmove {} and sidemove {} (vectorial compensation)",
                i + 1,
                c.forwardmove,
                c.sidemove
            ),
            allowed: format!(
                "movement keys held at their speeds ({} and {} ups): a frame bulk holds keys, not \
                 forwardmove and sidemove values; solve the scene with vectorial-compensation off",
                vars.forward_key_speed, vars.side_key_speed
            ),
        });
    }
    let frame_time = frame_time_text(vars);
    let s = &trace.start;
    let mut lines = vec![
        Line::Comment(format!(
            " strafeopt: {title}, controller {}, {} frames at {frame_time} s",
            trace.controller,
            trace.controls.len()
        )),
        Line::Comment(format!(
            " start: position ({:.6}, {:.6}) units, velocity ({:.6}, {:.6}) ups, {}{}",
            s.pos.x,
            s.pos.y,
            s.vel.x,
            s.vel.y,
            if s.on_ground {
                "on the ground"
            } else {
                "airborne"
            },
            if s.ducked { ", ducked" } else { "" }
        )),
    ];
    let mut current: Option<FrameBulk> = None;
    for (i, c) in trace.controls.iter().enumerate() {
        let bulk = frame_bulk(c, &frame_time).ok_or_else(|| {
            Error::Numerical(format!(
                "--hltas: the yaw of frame {} is not finite ({})",
                i + 1,
                c.yaw_rad
            ))
        })?;
        current = match current {
            Some(mut open) if same_frame(&open, &bulk) => {
                open.frame_count = open.frame_count.saturating_add(1);
                Some(open)
            }
            Some(open) => {
                lines.push(Line::FrameBulk(open));
                Some(bulk)
            }
            None => Some(bulk),
        };
    }
    if let Some(open) = current {
        lines.push(Line::FrameBulk(open));
    }
    Ok(HLTAS {
        properties: Default::default(),
        lines,
    })
}

/// Writes the script of [`hltas_script`] to `w`.
pub fn write_hltas(trace: &Trace, vars: &MovementVars, title: &str, w: impl Write) -> Result<()> {
    let script = hltas_script(trace, vars, title)?;
    script
        .to_writer(w)
        .map_err(|e| Error::Io(format!("writing the .hltas script: {e:?}")))
}

/// Whether `c`'s forwardmove and sidemove are the keys a frame bulk can hold: each zero or its key's speed
/// either way (compared exactly: the controllers copy the key speeds as they are).
fn on_the_keys(c: &Control, vars: &MovementVars) -> bool {
    let key = |m: f64, speed: f64| m == 0.0 || m.abs() == speed;
    key(c.forwardmove, vars.forward_key_speed) && key(c.sidemove, vars.side_key_speed)
}

/// One frame's bulk, or `None` when the yaw is not finite.
fn frame_bulk(c: &Control, frame_time: &str) -> Option<FrameBulk> {
    if !c.yaw_rad.is_finite() {
        return None;
    }
    let mut b = FrameBulk::with_frame_time(frame_time.to_string());
    b.auto_actions = AutoActions {
        movement: Some(AutoMovement::SetYaw(yaw_degrees_f32(c.yaw_rad))),
        ..Default::default()
    };
    b.movement_keys = MovementKeys {
        forward: c.forwardmove > 0.0,
        back: c.forwardmove < 0.0,
        right: c.sidemove > 0.0,
        left: c.sidemove < 0.0,
        ..Default::default()
    };
    b.action_keys = ActionKeys {
        jump: c.jump,
        duck: c.duck,
        ..Default::default()
    };
    Some(b)
}

/// Two bulks that differ only in their frame counts.
fn same_frame(a: &FrameBulk, b: &FrameBulk) -> bool {
    a.auto_actions == b.auto_actions
        && a.movement_keys == b.movement_keys
        && a.action_keys == b.action_keys
        && a.frame_time == b.frame_time
        && a.pitch == b.pitch
        && a.console_command == b.console_command
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::physics::Vec2;
    use crate::sim::{FrameRecord, Trace};

    fn trace(yaws: &[f64]) -> Trace {
        let rec = FrameRecord {
            frame: 0,
            time: 0.0,
            pos: Vec2::ZERO,
            vel: Vec2::new(320.0, 0.0),
            speed: 320.0,
            yaw_rad: 0.0,
            theta_rad: 0.0,
            on_ground: false,
            ducked: false,
            clearance: 10.0,
            contacts: 0,
            broke_rule: false,
        };
        let mut t = Trace {
            controller: "test".to_string(),
            start: rec,
            frames: Vec::new(),
            controls: Vec::new(),
            crossing: None,
            numerical_failure: false,
            interrupted: false,
        };
        for (i, &y) in yaws.iter().enumerate() {
            t.frames.push(FrameRecord {
                frame: i as u64 + 1,
                ..rec
            });
            t.controls.push(Control {
                yaw_rad: y,
                forwardmove: 0.0,
                sidemove: if i % 2 == 0 { 400.0 } else { -400.0 },
                jump: i == 2,
                duck: false,
            });
        }
        t
    }

    #[test]
    fn yaw_degrees_wraps_into_0_360() {
        assert_eq!(yaw_degrees(0.0), 0.0);
        assert!((yaw_degrees(-std::f64::consts::FRAC_PI_2) - 270.0).abs() < 1e-12);
        assert!((yaw_degrees(5.0 * std::f64::consts::PI) - 180.0).abs() < 1e-9);
        assert_eq!(yaw_degrees(-1e-300), 0.0);
        assert_eq!(yaw_degrees_f32((360.0f64 - 1e-9).to_radians()), 0.0);
    }

    #[test]
    fn script_round_trips_through_the_crate() {
        let yaws = [0.1, -0.2, 0.3, 0.3, 2.0];
        let t = trace(&yaws);
        let vars = MovementVars::goldsrc(100.0);
        let mut out = Vec::new();
        write_hltas(&t, &vars, "unit", &mut out).unwrap_or_else(|e| panic!("{e}"));
        let text = String::from_utf8(out).unwrap_or_else(|e| panic!("{e}"));
        let back = HLTAS::from_str(&text).unwrap_or_else(|e| panic!("{e}\n{text}"));
        let bulks: Vec<_> = back.frame_bulks().collect();
        // Frames 3 and 4 have the same yaw but different keys (sidemove sign, jump): no merge.
        assert_eq!(bulks.len(), 5);
        for (b, y) in bulks.iter().zip(yaws) {
            assert_eq!(b.frame_time, "0.01");
            assert_eq!(
                b.auto_actions.movement,
                Some(AutoMovement::SetYaw(yaw_degrees_f32(y)))
            );
        }
        assert!(bulks[0].movement_keys.right && !bulks[0].movement_keys.left);
        assert!(bulks[1].movement_keys.left && !bulks[1].movement_keys.right);
        assert!(bulks[2].action_keys.jump && !bulks[1].action_keys.jump);
    }

    #[test]
    fn identical_frames_merge() {
        let mut t = trace(&[0.5, 0.5, 0.5]);
        for c in &mut t.controls {
            c.sidemove = 400.0;
            c.jump = false;
        }
        let script = hltas_script(&t, &MovementVars::goldsrc(1000.0), "merge")
            .unwrap_or_else(|e| panic!("{e}"));
        let bulks: Vec<_> = script.frame_bulks().collect();
        assert_eq!(bulks.len(), 1);
        assert_eq!(bulks[0].frame_count.get(), 3);
        assert_eq!(bulks[0].frame_time, "0.001");
    }

    #[test]
    fn source_scenes_and_bad_yaws_are_refused() {
        let t = trace(&[0.0]);
        let e = hltas_script(&t, &MovementVars::source_hl2(66.67), "x")
            .err()
            .map(|e| e.to_string())
            .unwrap_or_default();
        assert!(e.starts_with("--hltas") && !e.contains('\n'), "{e}");
        let t = trace(&[f64::NAN]);
        assert!(matches!(
            hltas_script(&t, &MovementVars::goldsrc(100.0), "x"),
            Err(Error::Numerical(_))
        ));
    }

    #[test]
    fn a_plan_with_vectorial_compensation_is_refused() {
        // Frame 2 sets forwardmove and sidemove to whole numbers other than the keys': a frame bulk holds
        // keys only, and the script would replay full keys.
        let mut t = trace(&[0.1, 0.2, 0.3]);
        t.controls[1].forwardmove = 1303.0;
        t.controls[1].sidemove = -805.0;
        let e = hltas_script(&t, &MovementVars::goldsrc(1000.0), "x")
            .err()
            .map(|e| e.to_string())
            .unwrap_or_default();
        assert!(
            e.starts_with("--hltas") && e.contains("frame 2") && !e.contains('\n'),
            "{e}"
        );
    }
}
