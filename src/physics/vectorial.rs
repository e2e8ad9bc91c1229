//! Vectorial compensation (docs/physics.md section 1): the wish direction set far finer than the yaw's
//! anglemod steps. The game sends the yaw through anglemod (65536 steps a turn), but the wish direction is
//! `a = F f + S s`, at `yaw - atan2(S, F)`, and forwardmove `F` and sidemove `S` reach the server as
//! integers in `[-2047, 2047]` (the game's `delta.lst` sends them as 12-bit signed integers). A yaw on an
//! anglemod step together with a well-chosen pair `(F, S)` puts the wish direction within a few
//! ten-millionths of a radian of any angle: [`VECTORIAL_RESOLUTION_RAD`] against the step's 9.6e-5.
//!
//! The pair is searched along a direction whose tangent is badly approximable by fractions (the golden
//! ratio's conjugate): over a thousand values of `F` the fractions `S / F` near it are spread evenly, so
//! one of them is within about a thousandth of `1 / F` of any tangent near it.
//!
//! The game's own client scales `(F, S, U)` down to the player's maximum speed before sending it
//! (`CL_CreateMove`), which undoes the search: only a replay tool that writes the user command itself plays
//! such a control, and a scene asks for it (`vectorial-compensation`, off by default).

use super::engine_exact::{yaw_on_step_rad, ANGLEMOD_STEP_RAD};
use super::step::Control;

/// Most `|F|` or `|S|` the game transmits, ups (12-bit signed integers).
pub const MOVE_MAX_UPS: i32 = 2047;

/// The smallest `F` searched, ups: with `S / F` near [`OFFSET_TAN`], every pair searched is at least
/// `MOVE_MIN_UPS * sqrt(1 + OFFSET_TAN^2)`, about 1200 ups, long (see [`VECTORIAL_MAX_WISH_SPEED_UPS`]).
const MOVE_MIN_UPS: i32 = 1024;

/// `tan` of the angle between the yaw and the wish direction the search aims at: the golden ratio's
/// conjugate, `(sqrt 5 - 1) / 2`, the number worst approximated by fractions.
const OFFSET_TAN: f64 = 0.618_033_988_749_894_9;

/// Anglemod steps either side of the nearest one tried as the yaw.
const YAW_STEPS_TRIED: i64 = 1;

/// The largest angle, radians, between a wish direction and the one [`vectorial_strafe`] realises, with
/// room for the game's `f32` view vectors (the yaw in degrees as `float`, up to 4e-7 rad at 360 degrees).
/// Measured by the test `every_angle_is_realised_within_the_resolution` over 20 000 angles: at most
/// 5.2e-7 rad in `f64` and 7.2e-7 rad through the game's `float` view vectors.
pub const VECTORIAL_RESOLUTION_RAD: f64 = 1.5e-6;

/// The largest wish speed `M` (`min(sv_maxspeed, sqrt(F^2 + S^2))`) the search's pairs keep whole, ups:
/// every pair is longer than this, so `M` is the server's maximum speed as with the keys held.
pub const VECTORIAL_MAX_WISH_SPEED_UPS: f64 = 1200.0;

/// The control whose wish direction is nearest to `wish_angle_rad` (radians, anticlockwise from +x): its
/// yaw on an anglemod step (it survives anglemod unchanged), `F` and `S` whole numbers of ups in
/// `[-2047, 2047]`, `sqrt(F^2 + S^2)` above [`VECTORIAL_MAX_WISH_SPEED_UPS`]. No jump, no duck.
pub fn vectorial_strafe(wish_angle_rad: f64) -> Control {
    let nearest = ((wish_angle_rad + OFFSET_TAN.atan()) / ANGLEMOD_STEP_RAD).round();
    let mut best = (f64::INFINITY, yaw_on_step_rad(nearest), 0, 0);
    for j in -YAW_STEPS_TRIED..=YAW_STEPS_TRIED {
        let yaw = yaw_on_step_rad(nearest + j as f64);
        // The wish direction is at `yaw - atan2(S, F)`: the pair must point `xi` off the yaw.
        let xi = yaw - wish_angle_rad;
        let tan = xi.tan();
        for f in MOVE_MIN_UPS..=MOVE_MAX_UPS {
            let s = (f64::from(f) * tan).round();
            if s.abs() > f64::from(MOVE_MAX_UPS) {
                continue;
            }
            let f = f64::from(f);
            // The angle of (f, s) less xi, to first order: d atan(s / f) / ds = f / (f^2 + s^2).
            let err = ((s - f * tan) * f / (f * f + s * s)).abs();
            if err < best.0 {
                best = (err, yaw, f as i32, s as i32);
            }
        }
    }
    let (_, yaw, f, s) = best;
    Control {
        yaw_rad: yaw,
        forwardmove: f64::from(f),
        sidemove: f64::from(s),
        jump: false,
        duck: false,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::physics::engine_exact::{anglemod_deg, engine_wish};
    use crate::physics::{Vec2, Wish};

    /// The angle between two directions, radians, in `[0, pi]`.
    fn between(a: Vec2, b: Vec2) -> f64 {
        a.cross(b).atan2(a.dot(b)).abs()
    }

    /// The wish direction of a control (docs/physics.md section 5), in `f64` from its `f64` wish or from
    /// the game's `f32` one.
    fn direction(w: Wish<f64>) -> Vec2 {
        w.direction().unwrap_or_else(|| panic!("no keys"))
    }

    #[test]
    fn every_angle_is_realised_within_the_resolution() {
        // Angles spread over the whole turn (a fixed low-discrepancy sequence), each realised by a yaw
        // on an anglemod step and whole forwardmove and sidemove in range, long enough for a full wish
        // speed; in f64 within the search's own error, in the game's f32 view vectors within the
        // resolution.
        let mut worst: f64 = 0.0;
        let mut worst_f32: f64 = 0.0;
        for k in 0..20_000 {
            let angle = (f64::from(k) * OFFSET_TAN).fract() * std::f64::consts::TAU - 3.0;
            let c = vectorial_strafe(angle);
            // The yaw is on an anglemod step, the one the game keeps.
            let game_yaw = f64::from(anglemod_deg(c.yaw_rad.to_degrees() as f32)).to_radians();
            assert!(between(Vec2::from_angle(game_yaw), Vec2::from_angle(c.yaw_rad)) < 1e-9);
            for m in [c.forwardmove, c.sidemove] {
                assert_eq!(m, m.round());
                assert!(m.abs() <= f64::from(MOVE_MAX_UPS));
            }
            assert!(c.forwardmove.hypot(c.sidemove) > VECTORIAL_MAX_WISH_SPEED_UPS);
            let want = Vec2::from_angle(angle);
            worst = worst.max(between(direction(c.wish()), want));
            let w = engine_wish(&c);
            let game = Wish {
                forward: w.forward.to_f64(),
                forwardmove: f64::from(w.forwardmove),
                sidemove: f64::from(w.sidemove),
                jump: w.jump,
                duck: w.duck,
            };
            worst_f32 = worst_f32.max(between(direction(game), want));
        }
        assert!(worst < 1.0e-6, "{worst} rad in f64");
        assert!(
            worst_f32 < VECTORIAL_RESOLUTION_RAD,
            "{worst_f32} rad in f32"
        );
        // Far finer than the yaw alone: half an anglemod step is 4.8e-5 rad.
        assert!(worst < 0.05 * ANGLEMOD_STEP_RAD, "{worst} rad");
    }
}
