//! The lower bound on the finish time (physics.md section 6): the greedy maximum-acceleration speed is the
//! largest speed any control sequence can have after each frame, so no path can be longer after `n` frames
//! than the distance the greedy speed profile covers. The time that profile needs to cover the corridor's
//! shortest path is a lower bound on the time of every run.
//!
//! The profile is built from speeds alone, so it bounds every direction at once: `s_{k+1} = max_accel(
//! lambda_max(min(s_k, V_max sqrt 2)))`, using that the per-component clamp never raises the speed (and
//! caps it at `V_max sqrt 2`), that friction never raises it, and that the new speed of maximum acceleration
//! grows with the old one.

use crate::error::{Error, Result};
use crate::geometry::{Corridor, FinishPoint, HULL_HALF_WIDTH_UNITS};
use crate::physics::strafe::max_accel;
use crate::physics::{AccelLaw, Effect, Effects, MovementVars, PlayerState, Vec2};
use crate::scene::Scene;
pub use crate::sim::Crossing;
use serde::Serialize;

/// The greedy speed profile's upper bound on the speed after one more frame, ups, for the effects a scene
/// runs. Handles airborne and ground strafing (friction); a scene that can be on the ground uses the larger
/// of the two, so the bound holds whatever the player does.
#[derive(Clone, Copy, Debug)]
pub struct SpeedBound {
    air: Option<AccelLaw>,
    ground: Option<AccelLaw>,
    friction: Option<(f64, f64)>,
    clamp_speed: Option<f64>,
    /// `Mx` when the Source jump boost can fire (physics.md section 11).
    jump_boost_maxspeed: Option<f64>,
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
        let jump_boost_maxspeed = effects.has(Effect::JumpBoost).then_some(vars.maxspeed);
        SpeedBound {
            air,
            ground,
            friction,
            clamp_speed,
            jump_boost_maxspeed,
        }
    }

    /// The largest speed after one frame from any velocity of speed at most `speed`.
    ///
    /// With the Source jump boost a jump may come first: it adds `add` along the view with
    /// `add + |v| <= (1 + p) Mx` when positive, and `|v| - (1 + p) Mx` when the speed is above the cap
    /// (section 11), so the speed after it is at most `max(|v|, 1.5 Mx, 2|v| - 1.1 Mx)`. The bound lets a
    /// jump happen on every frame, which is generous but never wrong.
    pub fn next(&self, speed: f64) -> f64 {
        let speed = match self.jump_boost_maxspeed {
            Some(mx) => speed.max(1.5 * mx).max(2.0 * speed - 1.1 * mx),
            None => speed,
        };
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

/// The lower bound of a scene: the shortest path of the hull centre through the corridor (walls grown by
/// the hull) and the time the greedy speed profile needs to cover it.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct LowerBound {
    /// Length of the path the bound covers, units.
    pub path_length: f64,
    /// The shortest path's corners, from the start to the finish line.
    pub path: Vec<Vec2>,
    /// When the greedy speed profile covers it.
    pub crossing: Crossing,
}

/// The lower bound of `scene` through `corridor` (physics.md section 6). For a `hull` finish the centre
/// need only come within the box of the line, at most `16 sqrt 2` units short of it, so that much is
/// taken off the path. Errors with [`Error::NoValidPath`] when no path reaches the finish.
pub fn lower_bound(scene: &Scene, corridor: &Corridor) -> Result<LowerBound> {
    let (length, path) = corridor
        .shortest_path(scene.start.pos, (scene.finish.a, scene.finish.b))
        .ok_or_else(|| {
            Error::NoValidPath(format!(
                "{}: no path for the 32-unit hull from the start to the finish line",
                scene.origin
            ))
        })?;
    let path_length = match scene.finish.point {
        FinishPoint::Centre => length,
        FinishPoint::Hull => (length - HULL_HALF_WIDTH_UNITS * std::f64::consts::SQRT_2).max(0.0),
    };
    let crossing = time_to_cover(
        &scene.vars,
        scene.effects,
        &scene.start,
        path_length,
        scene.max_frames,
    )
    .ok_or_else(|| {
        Error::NoValidPath(format!(
            "{}: even the greedy speed profile cannot cover {path_length:.3} units in {} frames",
            scene.origin, scene.max_frames
        ))
    })?;
    Ok(LowerBound {
        path_length,
        path,
        crossing,
    })
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
