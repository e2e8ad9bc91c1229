//! The lower bound on the finish time (physics.md section 6): the greedy maximum-acceleration speed is the
//! largest speed any control sequence can have after each frame, so no path can be longer after `n` frames
//! than the distance the greedy speed profile covers. The time that profile needs to cover the corridor's
//! shortest path is a lower bound on the time of every run.
//!
//! The profile is built from speeds alone, so it bounds every direction at once: `s_{k+1} = max_accel(
//! lambda_max(min(s_k, V_max sqrt 2)))`, using that the per-component clamp never raises the speed (and
//! caps it at `V_max sqrt 2`), that friction never raises it, and that the new speed of maximum acceleration
//! grows with the old one.

use crate::physics::strafe::max_accel;
use crate::physics::{AccelLaw, Effect, Effects, MovementVars, PlayerState};
use serde::Serialize;

/// When a bound (or a run) crosses the line: in frame `frames` (1-based), `fraction` of the way through
/// it, at `time = (frames - 1 + fraction) tau` seconds.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct Crossing {
    /// The frame in which the line is crossed (1-based).
    pub frames: u64,
    /// How far through that frame, in `[0, 1]`.
    pub fraction: f64,
    /// Fractional crossing time, seconds.
    pub time: f64,
}

impl Crossing {
    /// The crossing in frame `frames` at `fraction` for frame time `tau_s`.
    pub fn new(frames: u64, fraction: f64, tau_s: f64) -> Self {
        Crossing {
            frames,
            fraction,
            time: ((frames as f64) - 1.0 + fraction) * tau_s,
        }
    }
}

/// The greedy speed profile's upper bound on the speed after one more frame, ups, for the effects a scene
/// runs. Handles airborne and ground strafing (friction); a scene that can be on the ground uses the larger
/// of the two, so the bound holds whatever the player does.
#[derive(Clone, Copy, Debug)]
pub struct SpeedBound {
    air: Option<AccelLaw>,
    ground: Option<AccelLaw>,
    friction: Option<(f64, f64)>,
    clamp_speed: Option<f64>,
}

impl SpeedBound {
    /// The bound for `vars` and `effects` with full keys.
    pub fn new(vars: &MovementVars, effects: Effects) -> Self {
        let tau = vars.frame_time_s();
        // The largest wish speed any keys give: both keys held.
        let m = vars
            .maxspeed
            .min(vars.forward_key_speed.hypot(vars.side_key_speed));
        let air = effects
            .has(Effect::AirAccel)
            .then(|| AccelLaw::air(vars, m));
        let ground = effects
            .has(Effect::GroundAccel)
            .then(|| AccelLaw::ground(vars, m));
        let friction = effects.has(Effect::Friction).then(|| {
            (
                tau * vars.friction_k(effects.has(Effect::EdgeFriction)),
                vars.stopspeed,
            )
        });
        let clamp_speed = effects
            .has(Effect::MaxVelocity)
            .then_some(vars.maxvelocity * std::f64::consts::SQRT_2);
        SpeedBound {
            air,
            ground,
            friction,
            clamp_speed,
        }
    }

    /// The largest speed after one frame from any velocity of speed at most `speed`.
    pub fn next(&self, speed: f64) -> f64 {
        let s = self.clamp_speed.map_or(speed, |c| speed.min(c));
        let mut best = s; // no acceleration at all keeps at most the speed
        if let Some(law) = self.air {
            best = best.max(max_accel(s, law).speed);
        }
        if let Some(law) = self.ground {
            best = best.max(max_accel(self.lambda_max(s), law).speed);
        }
        best
    }

    /// The largest speed after friction from any speed up to `s` (friction is monotone except just above
    /// 0.1 ups, where the game's early return keeps slower crawls untouched).
    fn lambda_max(&self, s: f64) -> f64 {
        match self.friction {
            None => s,
            Some((tau_k, stopspeed)) => {
                let control = s.max(stopspeed);
                let after = (s - control * tau_k).max(0.0);
                after.max(s.min(0.1))
            }
        }
    }
}

/// The time the greedy speed profile from `start` needs to cover `distance` units: the frame in which the
/// covered distance first reaches it and the fraction of that frame. `None` when `max_frames` pass first.
pub fn time_to_cover(
    vars: &MovementVars,
    effects: Effects,
    start: &PlayerState,
    distance: f64,
    max_frames: u64,
) -> Option<Crossing> {
    let bound = SpeedBound::new(vars, effects);
    let tau = vars.frame_time_s();
    let mut speed = start.speed();
    let mut covered = 0.0;
    if distance <= 0.0 {
        return Some(Crossing::new(1, 0.0, tau));
    }
    for frame in 1..=max_frames {
        speed = bound.next(speed);
        let step = speed * tau;
        if covered + step >= distance && step > 0.0 {
            let fraction = ((distance - covered) / step).clamp(0.0, 1.0);
            return Some(Crossing::new(frame, fraction, tau));
        }
        covered += step;
    }
    None
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::physics::Vec2;

    #[test]
    fn straight_line_bound_matches_the_airstrafe_closed_form() {
        // From 320 ups at 1000 fps the greedy speed after n frames is sqrt(320^2 + n gamma1 (2L - gamma1)).
        let vars = MovementVars::goldsrc(1000.0);
        let start = PlayerState::airborne(Vec2::ZERO, Vec2::new(320.0, 0.0));
        let c = time_to_cover(&vars, Effects::AIR_ONLY, &start, 1000.0, 1_000_000)
            .unwrap_or(Crossing::new(0, 0.0, 0.0));
        let per = 3.2 * (60.0 - 3.2);
        let dist = |n: u64| -> f64 {
            (1..=n)
                .map(|k| (320.0f64.powi(2) + k as f64 * per).sqrt() * 0.001)
                .sum()
        };
        assert!(dist(c.frames - 1) < 1000.0 && dist(c.frames) >= 1000.0);
        assert!(c.time > 0.0 && c.fraction > 0.0 && c.fraction <= 1.0);
    }
}
