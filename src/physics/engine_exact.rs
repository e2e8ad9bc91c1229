//! The engine-exact mode (docs/physics.md section 1): the state in `f32` as the game keeps it, and the yaw sent
//! through *anglemod*, `A_d(x) = (360/65536) (int(x 65536/360) AND 65535)` degrees, before the view vectors
//! are computed. The frame logic is the very same [`Stepper`], run over `f32`.
//!
//! [`replay`] runs a planned control sequence in both arithmetics side by side and reports how far the
//! game's run drifts from the `f64` plan.

use super::effects::Effects;
use super::step::{Control, PlayerState, Stepper, Wish};
use super::vars::MovementVars;
use super::vec2::V2;
use serde::Serialize;

/// Number of anglemod steps in a full turn.
pub const ANGLEMOD_STEPS: u32 = 65536;

/// One anglemod step, degrees: `360 / 65536`.
const ANGLEMOD_STEP_DEG: f64 = 360.0 / ANGLEMOD_STEPS as f64;

/// One anglemod step, radians: `2 pi / 65536`.
pub const ANGLEMOD_STEP_RAD: f64 = std::f64::consts::TAU / ANGLEMOD_STEPS as f64;

/// The game's anglemod of a yaw in degrees (docs/physics.md section 1): the angle truncated towards zero to a
/// multiple of `360/65536` degrees and wrapped into `[0, 360)`. Computed as the game does: the `float`
/// argument promoted to `double`, the result stored as `float`.
pub fn anglemod_deg(yaw_deg: f32) -> f32 {
    let step = ANGLEMOD_STEP_DEG;
    let scaled = f64::from(yaw_deg) * (f64::from(ANGLEMOD_STEPS) / 360.0);
    // `as i64` truncates towards zero and saturates, like a C cast for in-range values.
    let index = (scaled as i64) & i64::from(ANGLEMOD_STEPS - 1);
    (step * index as f64) as f32
}

/// The wish of a planned control as the game computes it: the yaw in degrees as `float`, anglemod, then
/// `AngleVectors` (`angle * (2 pi/360)` in `float`, `sin`/`cos` in `double`, stored as `float`).
pub fn engine_wish(control: &Control) -> Wish<f32> {
    let yaw_deg = anglemod_deg(control.yaw_rad.to_degrees() as f32);
    let angle = (f64::from(yaw_deg) * (std::f64::consts::PI * 2.0 / 360.0)) as f32;
    let (s, c) = f64::from(angle).sin_cos();
    Wish {
        forward: V2::new(c as f32, s as f32),
        forwardmove: control.forwardmove as f32,
        sidemove: control.sidemove as f32,
        jump: control.jump,
        duck: control.duck,
    }
}

/// The planning yaw (radians) that anglemod leaves unchanged and that is nearest to `yaw_rad`: planning on
/// these yaws makes the plan and the game see the same view direction (up to `f32` rounding).
pub fn quantise_yaw_rad(yaw_rad: f64) -> f64 {
    yaw_on_step_rad((yaw_rad.to_degrees() / ANGLEMOD_STEP_DEG).round())
}

/// The two yaws on anglemod steps either side of `yaw_rad` (equal when it is on a step), each surviving
/// anglemod unchanged: a planner picks between them to steer the game's quantised view.
pub fn anglemod_bracket(yaw_rad: f64) -> (f64, f64) {
    let k = yaw_rad.to_degrees() / ANGLEMOD_STEP_DEG;
    (yaw_on_step_rad(k.floor()), yaw_on_step_rad(k.ceil()))
}

/// The yaw of anglemod step `k` (a whole number), radians, nudged a millionth of a step away from zero so
/// that the game's `f32` truncation (towards zero) lands on the step and not the one nearer zero.
pub fn yaw_on_step_rad(k: f64) -> f64 {
    ((k + 1e-6_f64.copysign(k)) * ANGLEMOD_STEP_DEG).to_radians()
}

/// An `f64` state rounded to the game's `f32`.
pub fn to_engine_state(s: &PlayerState) -> PlayerState<f32> {
    PlayerState {
        pos: V2::from_f64(s.pos),
        z: s.z as f32,
        vel: V2::from_f64(s.vel),
        vz: s.vz as f32,
        on_ground: s.on_ground,
        ducked: s.ducked,
        unduck_elapsed_s: s.unduck_elapsed_s as f32,
    }
}

/// An engine state in planning precision.
pub fn from_engine_state(s: &PlayerState<f32>) -> PlayerState {
    PlayerState {
        pos: s.pos.to_f64(),
        z: f64::from(s.z),
        vel: s.vel.to_f64(),
        vz: f64::from(s.vz),
        on_ground: s.on_ground,
        ducked: s.ducked,
        unduck_elapsed_s: f64::from(s.unduck_elapsed_s),
    }
}

/// How far an engine-exact run drifts from the `f64` plan of the same controls.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct ReplayDrift {
    /// Frames replayed.
    pub frames: usize,
    /// Largest horizontal position difference over the run, units.
    pub max_position_drift: f64,
    /// Horizontal position difference at the end, units.
    pub final_position_drift: f64,
    /// Largest speed difference over the run, ups.
    pub max_speed_drift: f64,
    /// The plan's final state.
    pub plan_final_speed: f64,
    /// The game's final speed.
    pub engine_final_speed: f64,
    /// True when every engine state stayed finite.
    pub finite: bool,
}

/// Runs `controls` from `start` (no walls) in `f64` with the raw yaws and in engine-exact `f32` with
/// anglemod, and reports the drift between the two runs.
pub fn replay(
    vars: &MovementVars,
    effects: Effects,
    start: &PlayerState,
    controls: &[Control],
) -> ReplayDrift {
    let plan: Stepper<f64> = Stepper::new(vars, effects);
    let game: Stepper<f32> = Stepper::new(vars, effects);
    let mut p = *start;
    let mut g = to_engine_state(start);
    let mut drift = ReplayDrift {
        frames: controls.len(),
        max_position_drift: 0.0,
        final_position_drift: 0.0,
        max_speed_drift: 0.0,
        plan_final_speed: p.speed(),
        engine_final_speed: f64::from(g.speed()),
        finite: true,
    };
    for c in controls {
        plan.step(&mut p, &c.wish());
        game.step(&mut g, &engine_wish(c));
        let gp = from_engine_state(&g);
        drift.finite &= g.is_finite();
        drift.max_position_drift = drift.max_position_drift.max((gp.pos - p.pos).length());
        drift.max_speed_drift = drift.max_speed_drift.max((gp.speed() - p.speed()).abs());
    }
    let gp = from_engine_state(&g);
    drift.final_position_drift = (gp.pos - p.pos).length();
    drift.plan_final_speed = p.speed();
    drift.engine_final_speed = gp.speed();
    drift
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn anglemod_truncates_to_65536_steps_and_wraps() {
        let step = 360.0f64 / 65536.0;
        assert_eq!(anglemod_deg(0.0), 0.0);
        assert_eq!(f64::from(anglemod_deg(1.5 * step as f32)), step);
        assert!((f64::from(anglemod_deg(370.0)) - 10.0).abs() < step);
        // Negative angles: truncation towards zero, then the AND wraps into [0, 360).
        let neg = f64::from(anglemod_deg(-0.5 * step as f32));
        assert_eq!(neg, 0.0);
        let neg = f64::from(anglemod_deg(-10.0));
        assert!((neg - 350.0).abs() < step, "{neg}");
    }

    #[test]
    fn bracket_yaws_are_adjacent_steps_around_the_yaw() {
        let step = (360.0f64 / 65536.0).to_radians();
        for i in 0..500 {
            let yaw = -3.0 + 0.0123 * i as f64;
            let (lo, hi) = anglemod_bracket(yaw);
            assert!(
                lo <= yaw + 1e-9 * step && hi >= yaw - 1e-9 * step,
                "{yaw}: {lo} {hi}"
            );
            assert!(hi - lo <= step * (1.0 + 1e-9));
            for y in [lo, hi] {
                let back = f64::from(anglemod_deg(y.to_degrees() as f32));
                assert!((back - y.to_degrees().rem_euclid(360.0)).abs() < 1e-3 * step.to_degrees());
            }
        }
    }

    #[test]
    fn quantised_yaws_survive_anglemod() {
        // Every step within a few hundredths of a degree of zero, where the `f32` yaw keeps the nudge
        // off the step (a nudge up put the steps just below zero one step nearer it), then a spread.
        let near_zero = (-40..=40).map(|k| f64::from(k) * (360.0f64 / 65536.0).to_radians());
        for yaw in near_zero.chain((0..1000).map(|i| -7.0 + 0.0137 * f64::from(i))) {
            let q = quantise_yaw_rad(yaw);
            let back = f64::from(anglemod_deg(q.to_degrees() as f32));
            let want = q.to_degrees().rem_euclid(360.0);
            assert!(
                (back - want).abs() < 1e-3 * (360.0 / 65536.0),
                "{yaw}: {back} vs {want}"
            );
        }
    }
}
