//! Speeds and frame counts in closed form (docs/physics.md sections 4 and 6), and the same figures by stepping
//! the frame, so each closed form can be checked against the game's own recurrence.

use super::effects::{Effect, Effects};
use super::step::{AccelLaw, PlayerState, Side, Stepper};
use super::strafe::{max_accel_wish, strafe_keys};
use super::vars::MovementVars;
use super::vec2::Vec2;
use crate::error::{Error, Result};

/// Speed after `n` frames of maximum-acceleration airstrafing from `v0` (docs/physics.md section 6, no
/// friction): linear growth `v0 + n gamma1` while `|v| <= L - gamma1` (case 1, `cos Theta = 1`), then
/// `sqrt(v^2 + n gamma1 (2L - gamma1))` (case 1) or `sqrt(v^2 + n L^2)` (case 2). `n` may be fractional.
pub fn airstrafe_speed_after(v0: f64, n: f64, law: AccelLaw) -> f64 {
    let AccelLaw { l, gamma1 } = law;
    if gamma1 <= 0.0 || l <= 0.0 {
        return v0.max(0.0);
    }
    if gamma1 > l {
        return (v0 * v0 + n * l * l).sqrt();
    }
    let (v_lin, n_rest) = linear_phase(v0, n, law);
    (v_lin * v_lin + n_rest * gamma1 * (2.0 * l - gamma1)).sqrt()
}

/// The linear phase of case 1: the speed after at most `n` frames of `+gamma1`, and the frames left.
fn linear_phase(v0: f64, n: f64, law: AccelLaw) -> (f64, f64) {
    let AccelLaw { l, gamma1 } = law;
    if v0 > l - gamma1 {
        return (v0, n);
    }
    // Frames k with v0 + (k-1) gamma1 <= L - gamma1 add gamma1 each.
    let k = ((l - gamma1 - v0) / gamma1).floor() + 1.0;
    if n <= k {
        (v0 + n * gamma1, 0.0)
    } else {
        (v0 + k * gamma1, n - k)
    }
}

/// Frames of maximum-acceleration airstrafing from `v0` to `v1` ups, by the closed form of docs/physics.md
/// section 6 (fractional: the frame in which `v1` is reached is its ceiling). `None` when the law cannot
/// accelerate.
///
/// # Example
/// 320 to 1000 ups at default Half-Life settings and 1000 fps takes about 4938 frames (section 12):
/// ```
/// use strafeopt::physics::{closed_form::airstrafe_frames_to_speed, curvature::air_law, MovementVars};
/// let law = air_law(&MovementVars::goldsrc(1000.0));
/// let n = airstrafe_frames_to_speed(320.0, 1000.0, law).unwrap();
/// assert_eq!(n.round(), 4938.0);
/// ```
pub fn airstrafe_frames_to_speed(v0: f64, v1: f64, law: AccelLaw) -> Option<f64> {
    let AccelLaw { l, gamma1 } = law;
    if v1 <= v0 {
        return Some(0.0);
    }
    if gamma1 <= 0.0 || l <= 0.0 {
        return None;
    }
    if gamma1 > l {
        return Some((v1 * v1 - v0 * v0) / (l * l));
    }
    let per_frame = gamma1 * (2.0 * l - gamma1);
    if v0 <= l - gamma1 {
        let (v_lin, _) = linear_phase(v0, f64::INFINITY, law);
        let k = ((l - gamma1 - v0) / gamma1).floor() + 1.0;
        if v1 <= v_lin {
            return Some((v1 - v0) / gamma1);
        }
        return Some(k + (v1 * v1 - v_lin * v_lin) / per_frame);
    }
    Some((v1 * v1 - v0 * v0) / per_frame)
}

/// Frames of maximum-acceleration groundstrafing from `v0` to `v1` ups under geometric friction (docs/physics.md
/// sections 4 and 6, case 1 with `cos zeta < 1`): `w = |v|^2` obeys `w' = a w + b` with
/// `a = (1 - tau k)^2`, `b = gamma1 (2L - gamma1)`, so `n = ln((w1 - w*)/(w0 - w*)) / ln a` with
/// `w* = b/(1 - a)`. `None` outside that regime (below `sv_stopspeed`, case 2, or at or above the
/// steady-state speed).
pub fn groundstrafe_frames_to_speed(
    v0: f64,
    v1: f64,
    law: AccelLaw,
    tau_s: f64,
    friction_k: f64,
    stopspeed: f64,
) -> Option<f64> {
    let AccelLaw { l, gamma1 } = law;
    let a = (1.0 - tau_s * friction_k).powi(2);
    if v1 <= v0 {
        return Some(0.0);
    }
    if !(gamma1 > 0.0 && gamma1 <= l && v0 >= stopspeed && a < 1.0 && a > 0.0) {
        return None;
    }
    // cos zeta < 1 needs lambda(v) = (1 - tau k)|v| > L - gamma1 from the start.
    if (1.0 - tau_s * friction_k) * v0 <= l - gamma1 {
        return None;
    }
    let b = gamma1 * (2.0 * l - gamma1);
    let w_star = b / (1.0 - a);
    let (w0, w1) = (v0 * v0, v1 * v1);
    if w1 >= w_star {
        return None;
    }
    Some(((w1 - w_star) / (w0 - w_star)).ln() / a.ln())
}

/// The steady groundstrafe speed, ups, where maximum acceleration exactly cancels friction (docs/physics.md
/// sections 6 and 12): `M sqrt(k_e A (2 - tau k_e A) / (k (2 - tau k)))` in case 1 with geometric
/// friction, `L / sqrt(1 - (1 - tau k)^2)` in case 2, and `(d^2 + b)/(2 d)` (`d = tau E k`) when the
/// steady state lies in the arithmetic branch below `sv_stopspeed`. Infinite without friction.
///
/// # Example
/// About 505.2 ups at 1000 fps and 498.2 ups at 100 fps with Half-Life defaults (section 12):
/// ```
/// use strafeopt::physics::{closed_form::max_groundstrafe_speed, MovementVars};
/// let at = |fps| max_groundstrafe_speed(&MovementVars::goldsrc(fps), false);
/// assert_eq!(format!("{:.1} {:.1}", at(1000.0), at(100.0)), "505.2 498.2");
/// ```
pub fn max_groundstrafe_speed(vars: &MovementVars, edge_friction: bool) -> f64 {
    let tau = vars.frame_time_s();
    let k = vars.friction_k(edge_friction);
    let AccelLaw { l, gamma1 } = AccelLaw::ground(vars, vars.maxspeed.min(vars.side_key_speed));
    if gamma1 <= 0.0 {
        return 0.0;
    }
    let b = if gamma1 > l {
        l * l
    } else {
        gamma1 * (2.0 * l - gamma1)
    };
    let shrink = 1.0 - tau * k;
    let one_minus_a = 1.0 - shrink * shrink;
    if one_minus_a <= 0.0 {
        return f64::INFINITY;
    }
    let geometric = (b / one_minus_a).sqrt();
    if geometric >= vars.stopspeed {
        return geometric;
    }
    let d = tau * vars.stopspeed * k;
    if d <= 0.0 {
        return f64::INFINITY;
    }
    (d * d + b) / (2.0 * d)
}

/// The effects of plain strafing: air or ground acceleration (with friction on the ground, edge friction
/// when asked), and the velocity clamp.
pub fn strafing_effects(ground: bool, edge_friction: bool) -> Effects {
    let mut fx = Effects::NONE.with(Effect::MaxVelocity);
    if ground {
        fx = fx.with(Effect::GroundAccel).with(Effect::Friction);
        if edge_friction {
            fx = fx.with(Effect::EdgeFriction);
        }
    } else {
        fx = fx.with(Effect::AirAccel);
    }
    fx
}

/// Frames to strafe from `v0` to `v1` by stepping the frame with the maximum-acceleration angle every
/// frame (the whole frame of docs/physics.md section 3, with the velocity clamp). Errors when the speed stops
/// growing before `v1` or `max_frames` pass.
pub fn frames_to_speed_by_stepping(
    vars: &MovementVars,
    v0: f64,
    v1: f64,
    ground: bool,
    max_frames: u64,
) -> Result<u64> {
    let stepper: Stepper<f64> = Stepper::new(vars, strafing_effects(ground, false));
    let mut s = if ground {
        PlayerState::on_ground(Vec2::ZERO, Vec2::new(v0, 0.0))
    } else {
        PlayerState::airborne(Vec2::ZERO, Vec2::new(v0, 0.0))
    };
    let keys = strafe_keys(vars.side_key_speed);
    let mut frames = 0u64;
    while s.speed() < v1 {
        let before = s.speed();
        let w = max_accel_wish(&stepper, &s, keys, Side::Left, 0.0);
        stepper.step(&mut s, &w);
        frames += 1;
        if frames >= max_frames || (frames > 16 && s.speed() <= before) {
            return Err(Error::Unreachable {
                what: format!(
                    "the speed stops at {:.4} ups after {frames} frames, short of --to {v1}",
                    s.speed()
                ),
            });
        }
    }
    Ok(frames)
}

/// The steady groundstrafe speed by simulation: maximum-acceleration groundstrafing from rest until the
/// speed changes by less than `tol_ups` per frame. Returns the speed and the frames it took.
pub fn max_groundstrafe_speed_by_stepping(
    vars: &MovementVars,
    edge_friction: bool,
    tol_ups: f64,
    max_frames: u64,
) -> (f64, u64) {
    let stepper: Stepper<f64> = Stepper::new(vars, strafing_effects(true, edge_friction));
    let mut s = PlayerState::on_ground(Vec2::ZERO, Vec2::ZERO);
    let keys = strafe_keys(vars.side_key_speed);
    let mut frames = 0u64;
    loop {
        let before = s.speed();
        let w = max_accel_wish(&stepper, &s, keys, Side::Left, 0.0);
        stepper.step(&mut s, &w);
        frames += 1;
        if ((s.speed() - before).abs() < tol_ups && frames > 2) || frames >= max_frames {
            return (s.speed(), frames);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn closed_form_speed_inverts_frames() {
        let law = AccelLaw {
            l: 30.0,
            gamma1: 3.2,
        };
        for &(v0, v1) in &[(0.0, 100.0), (10.0, 27.0), (320.0, 1000.0)] {
            let n = airstrafe_frames_to_speed(v0, v1, law).unwrap_or(f64::NAN);
            assert!(
                (airstrafe_speed_after(v0, n, law) - v1).abs() < 1e-9,
                "{v0} {v1}"
            );
        }
    }
}
