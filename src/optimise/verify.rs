//! Quantise and verify: the planning controls played through the real frame with yaws on anglemod steps
//! (docs/physics.md section 1), then checked in f64 and in the engine-exact mode.

use super::model::{control_for, rollout, FrameControl, FrameLaw, ModelState};
use super::planner::Planner;
use super::rounding::ROUNDING_HORIZON_S;
use crate::budget::Stage;
use crate::physics::engine_exact::{anglemod_bracket, quantise_yaw_rad};
use crate::physics::{Control, PlayerState};
use crate::sim::{Controller, Simulation, Trace};

/// Plays planning controls through the real frame, recomputing each frame's yaw from the actual velocity.
/// With `quantise`, the yaw is one of the two anglemod steps around the planned one, whichever leaves the
/// real state nearer the planned trajectory (position, and the heading's drift over a short horizon):
/// replaying the relative controls on quantised yaws without this feedback drifts by tenths of a unit.
pub(super) struct PlanPlayer {
    /// Game controls played first, as they are (see [`MIN_PLANNING_SPEED_UPS`]).
    prefix: Vec<Control>,
    controls: Vec<FrameControl>,
    fl: FrameLaw,
    quantise: bool,
    targets: Vec<ModelState>,
}

impl PlanPlayer {
    pub(super) fn new(
        start: &ModelState,
        prefix: &[Control],
        controls: Vec<FrameControl>,
        fl: FrameLaw,
        quantise: bool,
    ) -> Self {
        let targets = rollout(start, &controls, &fl);
        PlanPlayer {
            prefix: prefix.to_vec(),
            controls,
            fl,
            quantise,
            targets,
        }
    }
}

impl Controller for PlanPlayer {
    fn name(&self) -> String {
        "optimised".to_string()
    }

    fn control(&mut self, frame: u64, s: &PlayerState, sim: &Simulation) -> Control {
        let i = usize::try_from(frame.saturating_sub(1)).unwrap_or(usize::MAX);
        if let Some(c) = self.prefix.get(i) {
            return *c;
        }
        let i = i - self.prefix.len();
        let u = self.controls.get(i).copied().unwrap_or(FrameControl {
            sigma: 1.0,
            c: self.fl.c_max(s.speed()),
        });
        let c = control_for(s.vel, u, &self.fl);
        if !self.quantise {
            return c;
        }
        let Some(target) = self.targets.get(i) else {
            return Control {
                yaw_rad: quantise_yaw_rad(c.yaw_rad),
                ..c
            };
        };
        let (lo, hi) = anglemod_bracket(c.yaw_rad);
        let score = |yaw_rad: f64| {
            let mut next = *s;
            sim.frame(&mut next, &Control { yaw_rad, ..c });
            let drift =
                (next.vel.angle() - target.heading).sin() * next.speed() * ROUNDING_HORIZON_S;
            (next.pos - target.pos).length_squared() + drift * drift
        };
        let yaw_rad = if score(lo) <= score(hi) { lo } else { hi };
        Control { yaw_rad, ..c }
    }
}

/// The crossing time of a valid run, seconds; infinite for an invalid or unfinished one.
pub(super) fn time_of(t: &Trace) -> f64 {
    match (t.feasible(), t.crossing) {
        (true, Some(c)) => c.time,
        _ => f64::INFINITY,
    }
}

/// Stage 4: `plan` played through the real frame with quantised yaws; its crossing time and trace when it
/// is valid in f64 and in the engine-exact mode.
pub(super) fn quantised_and_verified(
    planner: &mut Planner,
    plan: Vec<FrameControl>,
) -> Option<(f64, Trace)> {
    let mut player = PlanPlayer::new(&planner.start, &planner.prefix, plan, planner.fl, true);
    let trace = planner.sim.run_within(&mut player, &planner.budget);
    if trace.interrupted {
        planner.timed_out = true;
        planner.note_cut(Stage::Verification);
        return None;
    }
    let t = time_of(&trace);
    if !t.is_finite() {
        return None;
    }
    let run = planner
        .sim
        .run_engine_exact_within(&trace.controls, &planner.budget);
    if run.interrupted {
        planner.timed_out = true;
        planner.note_cut(Stage::Verification);
    }
    run.feasible().then_some((t, trace))
}
