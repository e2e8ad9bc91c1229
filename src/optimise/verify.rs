//! Quantise and verify: the planning controls played through the real frame with the wish direction set as
//! the game can set it (docs/physics.md section 1: the yaw on anglemod steps with whole forwardmove and
//! sidemove, or on the keys the yaw alone), then checked in f64 and in the engine-exact mode.

use super::model::{control_for, rollout, AngleControl, FrameControl, FrameLaw, ModelState};
use super::planner::Planner;
use super::rounding::ROUNDING_HORIZON_S;
use crate::budget::Stage;
use crate::physics::engine_exact::{anglemod_bracket, quantise_yaw_rad};
use crate::physics::vectorial::vectorial_strafe;
use crate::physics::{Control, PlayerState};
use crate::sim::{Controller, Simulation, Trace};

/// Plays planning controls through the real frame, recomputing each frame's wish direction from the actual
/// velocity. With `quantise`, it is set as the game can set it: with vectorial compensation
/// ([`AngleControl::Vectorial`]) within its resolution of the planned one; on the yaw alone, the yaw is one
/// of the two anglemod steps around the planned one, whichever leaves the real state nearer the planned
/// trajectory (position, and the heading's drift over a short horizon): replaying the relative controls on
/// quantised yaws without this feedback drifts by tenths of a unit.
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
        if self.fl.angle_control == AngleControl::Vectorial {
            // The wish direction `yaw - atan2(S, F)` set by vectorial compensation, within its
            // resolution of the planned one: no step to choose.
            return vectorial_strafe(c.yaw_rad - c.sidemove.atan2(c.forwardmove));
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
    let trace = quantised_replay(planner, plan);
    verified(planner, &trace).map(|t| (t, trace))
}

/// The crossing time of `replay` (a [`quantised_replay`]) where it is valid in f64 and in the
/// engine-exact mode, replayed there from its controls.
pub(super) fn verified(planner: &mut Planner, replay: &Trace) -> Option<f64> {
    if replay.interrupted {
        planner.timed_out = true;
        planner.note_cut(Stage::Verification);
        return None;
    }
    planner.stats.replays += 1;
    let t = time_of(replay);
    if !t.is_finite() {
        return None;
    }
    let run = planner
        .sim
        .run_engine_exact_within(&replay.controls, &planner.budget);
    if run.interrupted {
        planner.timed_out = true;
        planner.note_cut(Stage::Verification);
    }
    let valid = run.feasible();
    planner.stats.valid_replays += u64::from(valid);
    valid.then_some(t)
}

/// `plan` after the planner's prefix, played through the real frame with quantised yaws
/// ([`PlanPlayer`]), in `f64`: the run [`quantised_and_verified`] checks.
pub(super) fn quantised_replay(planner: &Planner, plan: Vec<FrameControl>) -> Trace {
    let mut player = PlanPlayer::new(&planner.start, &planner.prefix, plan, planner.fl, true);
    planner.sim.run_within(&mut player, &planner.budget)
}

/// The largest distance (units) and speed difference (ups) between `plan` and its replay as verified
/// ([`PlanPlayer`] with the planner's angle control).
#[cfg(test)]
pub(super) fn replay_drift(planner: &Planner, plan: &[FrameControl]) -> (f64, f64) {
    let fl = planner.fl;
    let mut player = PlanPlayer::new(&planner.start, &planner.prefix, plan.to_vec(), fl, true);
    let trace = planner.sim.run_within(&mut player, &planner.budget);
    let states = rollout(&planner.start, plan, &fl);
    let replayed = trace.frames.iter().skip(planner.prefix.len()).zip(&states);
    replayed.fold((0.0, 0.0), |(pos, speed), (f, s)| {
        (
            f64::max(pos, (f.pos - s.pos).length()),
            f64::max(speed, (f.speed - s.speed).abs()),
        )
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::optimise::model::frame;
    use crate::optimise::planner::{staircase_scene, with_fast_planner};
    use crate::scene::Scene;

    #[test]
    fn every_replay_is_counted_and_only_a_valid_one_as_valid() {
        with_fast_planner(&staircase_scene(1), |planner, base, _| {
            // The seed's clean greedy run replays valid; the same number of frames each strafing square
            // to the velocity on one side (`c = 0`) circles into the walls and never crosses.
            let seed = planner.warm_start(base.seed());
            let circling: Vec<FrameControl> = seed
                .iter()
                .map(|_| FrameControl { sigma: 1.0, c: 0.0 })
                .collect();
            let before = planner.stats;
            assert!(quantised_and_verified(planner, seed).is_some());
            assert!(quantised_and_verified(planner, circling).is_none());
            assert_eq!(planner.stats.replays - before.replays, 2);
            assert_eq!(planner.stats.valid_replays - before.valid_replays, 1);
        });
    }

    #[test]
    fn vectorial_compensation_replays_a_plan_on_the_kink_where_yaw_steps_fall_behind() {
        // A lane 2000 units wide at 250 fps with air acceleration 10 (the law's first case, where maximum
        // acceleration sits on the kink) and vectorial compensation on: alternating sides with every
        // frame's `c` on the kink, cut where the line is crossed (674 frames). Replayed on anglemod steps
        // each frame lands up to half a step either side of the kink and gains less (here 0.31 units and
        // 0.21 ups behind by the line); with whole forwardmove and sidemove beside the yaw, a few
        // hundredths of that (0.0013 and 0.0006).
        let toml = "name = \"wide lane\"\n[engine]\npreset = \"goldsrc\"\nfps = 250\n\
                    vectorial-compensation = true\n\
                    effects = [\"air-accel\", \"max-velocity\", \"walls\"]\n\
                    [lane]\nwidth = 2000\nlength = 1500\nkind = \"rule\"\n";
        let scene = Scene::from_toml_str(toml, "wide lane").unwrap_or_else(|e| panic!("{e}"));
        with_fast_planner(&scene, |planner, _, _| {
            assert_eq!(planner.fl.angle_control, AngleControl::Vectorial);
            assert!(planner.fl.has_kink_guard());
            let fl = planner.fl;
            let mut x = planner.start;
            let mut on_the_kink: Vec<FrameControl> = (0..2000)
                .map(|k| {
                    let u = FrameControl {
                        sigma: if k % 2 == 0 { 1.0 } else { -1.0 },
                        c: fl.c_max(x.speed),
                    };
                    x = frame(&x, u, &fl, false).0;
                    u
                })
                .collect();
            let Some(crossing) = planner.crossing_of(&on_the_kink) else {
                panic!("the plan does not cross the line")
            };
            on_the_kink.truncate(crossing.frames as usize);
            let vectorial = replay_drift(planner, &on_the_kink);
            planner.fl.angle_control = AngleControl::Yaw;
            let yaw = replay_drift(planner, &on_the_kink);
            assert!(
                20.0 * vectorial.1 < yaw.1 && 20.0 * vectorial.0 < yaw.0,
                "vectorial {vectorial:?}, yaw steps {yaw:?} (units, ups)"
            );
        });
    }
}
