//! The minimal-time plan of a jumping scene: accelerated backhopping (ABH) with air strafing,
//! searched over a family of frame-level policies and checked by exact simulation.
//!
//! # Why a policy family is enough
//!
//! Every frame of a run in a jumping scene is one of three kinds, and the physics fixes most of each:
//! 1. **In the air** (docs/physics.md sections 3 and 5) the view acts only through the wish direction. Maximum
//!    acceleration (section 6) gives the largest speed after every frame whatever the side, so the side is
//!    free: it is spent on steering. With a strafe key held in Half-Life 2 without the suit (`M = 150`,
//!    `gamma1 = tau M A = 22.5`, `L = 30`, case 1) a frame adds `gamma1 (2L - gamma1) = 843.75 ups^2` to
//!    `|v|^2`: about 1.9 ups per frame at 225 ups, some 60 ups over a hop. The article's run holds no keys
//!    in the air and gains nothing.
//! 2. **On a jump frame** (sections 3, 10, 11) the jump comes before the move, so the frame is airborne:
//!    no friction, the boost, then the air FME with the same view. The boost adds `add f` with `add`
//!    independent of the view: ducked (`p = 0.1`) above `1.1 Mx` it is `|v| - 1.1 Mx` against `f`, so the
//!    speed becomes `2|v| - 1.1 Mx` along whatever direction `-f` points. The view of a jump frame
//!    therefore chooses where the boost goes: along the lane, or bent to bring the hull back to the
//!    lane's centre line.
//! 3. **On the ground** (sections 4, 5) friction takes speed; the only ground frames worth having are the
//!    start's: standing up (`TIME_TO_UNDUCK`), walking to speed, the forward jump.
//!
//! Because the boost `v -> 2|v| - 1.1 Mx` is increasing in `|v|` and the airtime is fixed by gravity
//! (section 10: the vertical motion ignores the horizontal controls on the flat floor), speed gained early
//! is doubled at every later backhop, up to the per-component clamp `sv_maxvelocity` (section 10), which
//! caps the speed along an axis-aligned lane.
//!
//! # What is searched
//!
//! What is left are discrete and one-dimensional choices, searched by simulating each candidate with the
//! ordinary frame loop ([`Simulation::run`]) and keeping the earliest valid crossing ([`JumpPolicy`]):
//! the tick of the first jump (a walk-speed threshold in disguise), walking while standing up, maximum
//! acceleration on the ground, ducked or standing jumps (the boost of section 11 for each), how many
//! ticks to wait on the ground before a backhop, the strafe key on jump ticks, whether to strafe in the
//! air at all, and the two steering horizons (air strafing sides and boost direction). The start phase
//! is searched on a full grid, the rest by coordinate descent (repeated at higher quality), each sweep
//! from the best policy so far. Every candidate is a run of the real frame loop, so every plan returned is
//! exactly what it claims; every yaw is put on an anglemod step (section 1) and the best plan is replayed
//! in the engine-exact mode (f32) before it is accepted.

use super::policy_run::{keep_if_better, PolicyRun};
use super::search::{Quality, SearchSettings};
use crate::budget::Budget;
use crate::physics::engine_exact::quantise_yaw_rad;
use crate::physics::strafe::{max_accel_control, strafe_keys};
use crate::physics::{Control, Effect, PlayerState, Side, Vec2};
use crate::sim::abh::{boost_addition, jump_airtime_s, lane_centre_line, run_abh, AbhParams};
use crate::sim::{Controller, Simulation, Trace};
use serde::Serialize;
use std::f64::consts::PI;

/// Largest speed across the lane the steering asks for, as a share of the speed.
const MAX_LATERAL_SHARE: f64 = 0.25;
/// Smallest steering horizon, seconds (guards the division).
const MIN_STEER_TIME_S: f64 = 1e-3;
/// Ticks after the earliest possible first jump that the start grid tries.
const FIRST_JUMP_WINDOW_TICKS: u64 = 40;
/// Most standing jumps after the first that the search tries.
const MAX_STANDING_JUMPS: u32 = 2;
/// Most ground ticks before a backhop that the search tries.
const MAX_JUMP_DELAY_TICKS: u32 = 2;

/// How a jump is taken (docs/physics.md section 11).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum JumpKind {
    /// Standing, forward key held, facing the boost's way: `p = 0.5`, `|v| -> min(|v| + Mx/2, 1.5 Mx)`
    /// below the cap (and `2|v| - 1.5 Mx` facing backwards above it).
    Standing,
    /// Ducked, no forward key, facing against the boost: `p = 0.1`, `|v| -> 2|v| - 1.1 Mx` above the cap.
    Ducked,
}

/// One candidate run: the choices the search makes (see the module documentation). Every yaw follows from
/// these and the state by the rules of docs/physics.md sections 6 and 11.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct JumpPolicy {
    /// The tick of the first jump (1-based; the first tick on the ground at or after it).
    pub first_jump_tick: u64,
    /// How the first jump is taken.
    pub first_jump: JumpKind,
    /// Jumps after the first taken standing (forward key) before the ducked backhops start.
    pub standing_jumps: u32,
    /// Hold forward while the unduck timer runs (the duck crop applies, docs/physics.md section 2).
    pub walk_while_unducking: bool,
    /// On the ground, accelerate at the maximum-acceleration angle (section 6) instead of straight ahead.
    pub ground_strafe: bool,
    /// Strafe at maximum acceleration in the air (section 6); off, no keys are held in the air.
    pub air_strafe: bool,
    /// Hold a strafe key on ducked jump ticks (the air FME follows the boost in the same tick, section 3).
    pub jump_tick_strafe: bool,
    /// Ticks spent on the ground after a landing before the next jump (0: jump on the first ground tick).
    pub jump_delay_ticks: u32,
    /// Air steering: the speed across the lane aimed at is `-offset / steer_time_s`, seconds.
    pub steer_time_s: f64,
    /// Boost steering: `None` boosts straight along the lane; `Some(t)` aims the boost so the speed across
    /// the lane afterwards is `-offset / t`.
    pub boost_return_s: Option<f64>,
}

impl Default for JumpPolicy {
    /// The article's recipe with air strafing: standing forward jump once at walking speed (tick 23 in
    /// `hl2-abh-100m`), ducked backhops on the landing ticks.
    fn default() -> Self {
        JumpPolicy {
            first_jump_tick: 23,
            first_jump: JumpKind::Standing,
            standing_jumps: 0,
            walk_while_unducking: false,
            ground_strafe: false,
            air_strafe: true,
            jump_tick_strafe: true,
            jump_delay_ticks: 0,
            steer_time_s: 0.3,
            boost_return_s: None,
        }
    }
}

impl JumpPolicy {
    /// The kind of the jump with index `i` (0: the first jump).
    pub fn kind(&self, i: u32) -> JumpKind {
        if i == 0 {
            self.first_jump
        } else if i <= self.standing_jumps {
            JumpKind::Standing
        } else {
            JumpKind::Ducked
        }
    }
}

/// The controller that plays a [`JumpPolicy`] (see the module documentation for the physics of each
/// choice). Yaws are put on anglemod steps, so the engine-exact replay sees the planned view.
#[derive(Clone, Debug)]
pub struct JumpRunner {
    policy: JumpPolicy,
    /// A point of the lane's centre line and its unit direction, fixed on the first tick.
    line: Option<(Vec2, Vec2)>,
    /// Jumps taken so far.
    jumps: u32,
    /// The tick the player was first seen on the ground after the last jump.
    landed: Option<u64>,
}

impl JumpRunner {
    /// A controller playing `policy`.
    pub fn new(policy: JumpPolicy) -> Self {
        JumpRunner {
            policy,
            line: None,
            jumps: 0,
            landed: None,
        }
    }

    /// The lane's centre line ([`lane_centre_line`]), fixed on the first frame.
    fn centre_line(&mut self, sim: &Simulation) -> (Vec2, Vec2) {
        *self
            .line
            .get_or_insert_with(|| lane_centre_line(sim.scene()))
    }

    /// The speed across the lane (positive to the left of the lane's direction) that brings the hull
    /// centre from `offset` back to the centre line in `horizon_s`, capped to a share of `speed`.
    fn lateral_target(offset: f64, horizon_s: f64, speed: f64) -> f64 {
        let cap = MAX_LATERAL_SHARE * speed;
        (-offset / horizon_s.max(MIN_STEER_TIME_S)).clamp(-cap, cap)
    }

    /// The strafing side (docs/physics.md section 6: both sides gain the same speed) that turns the velocity
    /// towards the across-lane speed target of the air steering.
    fn steering_side(&self, s: &PlayerState, origin: Vec2, axis: Vec2) -> Side {
        let normal = axis.perp();
        let offset = (s.pos - origin).dot(normal);
        let target = Self::lateral_target(offset, self.policy.steer_time_s, s.speed());
        if s.vel.dot(normal) < target {
            Side::Left
        } else {
            Side::Right
        }
    }

    /// A jump tick (docs/physics.md section 11): the boost's signed addition `add` does not depend on the view,
    /// so the view is chosen to point `add f` where the boost should go: along the lane, or bent so that
    /// the speed across the lane afterwards returns the hull to the centre line. A strafe key, if held,
    /// is pressed on the side that turns towards that target in the air FME that follows.
    fn jump_control(&mut self, s: &PlayerState, sim: &Simulation) -> Control {
        let vars = sim.scene().vars;
        let (origin, axis) = self.centre_line(sim);
        let normal = axis.perp();
        let kind = self.policy.kind(self.jumps);
        let (forwardmove, duck) = match kind {
            JumpKind::Standing => (vars.forward_key_speed, false),
            JumpKind::Ducked => (0.0, true),
        };
        // A strafe key only on ducked jumps: with the forward key held it would shorten `Fm` (the keys are
        // scaled down to the max speed together) and so the standing boost.
        let sidemove = if self.policy.jump_tick_strafe && kind == JumpKind::Ducked {
            vars.side_key_speed
        } else {
            0.0
        };
        let ducked = sim.stepper().ducked_after_duck_step(s, duck);
        // The clamp of the first gravity half-step comes before the boost.
        let mut vel = s.vel;
        if sim.scene().effects.has(Effect::MaxVelocity) {
            let m = vars.maxvelocity;
            vel = Vec2::new(vel.x.clamp(-m, m), vel.y.clamp(-m, m));
        }
        let add = boost_addition(&vars, ducked, forwardmove, sidemove, vel.length());
        let offset = (s.pos - origin).dot(normal);
        let lateral = vel.dot(normal);
        // The boost's direction u: along the lane, or with the across-lane part that sets the target.
        let u_n = match self.policy.boost_return_s {
            Some(t) if add != 0.0 => {
                let target = Self::lateral_target(offset, t, vel.length() + add.abs());
                ((target - lateral) / add.abs()).clamp(-1.0, 1.0)
            }
            _ => 0.0,
        };
        let u = axis * (1.0 - u_n * u_n).sqrt() + normal * u_n;
        let f = if add < 0.0 { -u } else { u };
        let yaw = quantise_yaw_rad(f.angle().rem_euclid(2.0 * PI));
        // The air FME of this tick sees the boosted velocity; the strafe key's side steers it.
        let boosted = vel + Vec2::from_angle(yaw) * add;
        let target = Self::lateral_target(offset, self.policy.steer_time_s, boosted.length());
        let right = Vec2::new(f.y, -f.x);
        let turn_left = boosted.dot(normal) < target;
        let sidemove = if (right.dot(normal) > 0.0) == turn_left {
            sidemove
        } else {
            -sidemove
        };
        self.jumps += 1;
        self.landed = None;
        Control {
            yaw_rad: yaw,
            forwardmove,
            sidemove,
            jump: true,
            duck,
        }
    }

    /// An airborne tick: maximum acceleration (docs/physics.md section 6) on the side that steers towards the
    /// across-lane speed target, duck held if the next jump is ducked (released in time for a standing
    /// one: the unduck timer needs `TIME_TO_UNDUCK`, less than a hop).
    fn air_control(&mut self, s: &PlayerState, sim: &Simulation) -> Control {
        let (origin, axis) = self.centre_line(sim);
        let duck = self.policy.kind(self.jumps) == JumpKind::Ducked;
        if !self.policy.air_strafe {
            return Control {
                yaw_rad: quantise_yaw_rad(axis.angle().rem_euclid(2.0 * PI)),
                forwardmove: 0.0,
                sidemove: 0.0,
                jump: false,
                duck,
            };
        }
        let side = self.steering_side(s, origin, axis);
        let mut keys = strafe_keys(sim.scene().vars.side_key_speed);
        keys.duck = duck;
        let mut c = max_accel_control(sim.stepper(), s, keys, side, axis.angle());
        c.yaw_rad = quantise_yaw_rad(c.yaw_rad.rem_euclid(2.0 * PI));
        c
    }

    /// A ground tick before the first jump or while waiting to backhop: stand up (or stay ducked for a
    /// ducked first jump), walk forward or accelerate at the maximum-acceleration angle (section 6).
    fn ground_control(&mut self, s: &PlayerState, sim: &Simulation) -> Control {
        let vars = sim.scene().vars;
        let (origin, axis) = self.centre_line(sim);
        let duck = if self.jumps == 0 {
            self.policy.first_jump == JumpKind::Ducked
        } else {
            self.policy.kind(self.jumps) == JumpKind::Ducked
        };
        let ducked = sim.stepper().ducked_after_duck_step(s, duck);
        let walk = self.jumps == 0 && (!ducked || duck || self.policy.walk_while_unducking);
        let mut c = Control {
            yaw_rad: axis.angle(),
            forwardmove: if walk { vars.forward_key_speed } else { 0.0 },
            sidemove: 0.0,
            jump: false,
            duck,
        };
        if walk && self.policy.ground_strafe {
            let side = self.steering_side(s, origin, axis);
            let mut keys = strafe_keys(0.0);
            keys.forwardmove = vars.forward_key_speed;
            keys.duck = duck;
            c = max_accel_control(sim.stepper(), s, keys, side, axis.angle());
        }
        c.yaw_rad = quantise_yaw_rad(c.yaw_rad.rem_euclid(2.0 * PI));
        c
    }
}

impl Controller for JumpRunner {
    fn name(&self) -> String {
        "jumps".to_string()
    }

    fn control(&mut self, frame: u64, s: &PlayerState, sim: &Simulation) -> Control {
        if !s.on_ground {
            return if self.jumps == 0 {
                self.ground_control(s, sim)
            } else {
                self.air_control(s, sim)
            };
        }
        let due = if self.jumps == 0 {
            frame >= self.policy.first_jump_tick
        } else {
            let landed = *self.landed.get_or_insert(frame);
            frame >= landed + u64::from(self.policy.jump_delay_ticks)
        };
        if due {
            self.jump_control(s, sim)
        } else {
            self.ground_control(s, sim)
        }
    }
}

/// One evaluated jump policy.
pub type Candidate = PolicyRun<JumpPolicy>;

/// The result of [`plan_jumps`].
#[derive(Clone, Debug)]
pub struct JumpPlan {
    /// The best valid run found (the hand-tuned ABH run if nothing beat it).
    pub best: Candidate,
    /// Candidates simulated.
    pub evaluations: u64,
    /// Coordinate-descent sweeps run.
    pub sweeps: u64,
    /// The budget (time limit or cancel flag) stopped the search.
    pub timed_out: bool,
}

/// The search's state: the best candidate, the work done, the budget.
struct Search<'a, 's, 'c> {
    sim: &'a Simulation<'s>,
    best: Option<Candidate>,
    evaluations: u64,
    budget: Budget<'c>,
    timed_out: bool,
}

impl Search<'_, '_, '_> {
    /// Simulates `policy` (in `f64`, and engine-exact when it would become the best) and keeps it if it
    /// is valid and crosses strictly earlier. Returns whether it was kept.
    fn try_policy(&mut self, policy: JumpPolicy) -> bool {
        if self.budget.expired() {
            self.timed_out = true;
            return false;
        }
        self.evaluations += 1;
        let trace = self
            .sim
            .run_within(&mut JumpRunner::new(policy), &self.budget);
        self.consider(policy, trace)
    }

    /// Keeps `trace` (played by `policy`) if it is valid in both arithmetics and better than the best.
    fn consider(&mut self, policy: JumpPolicy, trace: Trace) -> bool {
        // The first valid run is verified whatever the budget, so there is always a result to return.
        let budget = if self.best.is_some() {
            self.budget
        } else {
            Budget::unlimited()
        };
        let (kept, interrupted) = keep_if_better(&mut self.best, self.sim, policy, trace, &budget);
        self.timed_out |= interrupted;
        kept
    }

    fn best_policy(&self) -> JumpPolicy {
        self.best
            .as_ref()
            .map_or(JumpPolicy::default(), |b| b.policy)
    }

    /// The start phase tried on a full grid from the best policy: the first jump's tick (from `first`,
    /// the first tick on the ground) and kind, walking while standing up, ground strafing.
    fn start_phase_swept(&mut self, first: u64) {
        let base = self.best_policy();
        for kind in [JumpKind::Standing, JumpKind::Ducked] {
            for walk_while_unducking in [false, true] {
                for ground_strafe in [false, true] {
                    for tick in first..first + FIRST_JUMP_WINDOW_TICKS {
                        self.try_policy(JumpPolicy {
                            first_jump_tick: tick,
                            first_jump: kind,
                            walk_while_unducking,
                            ground_strafe,
                            ..base
                        });
                    }
                }
            }
        }
    }

    /// The flight tried on `grid` from the best policy: air strafing, the strafe key on jump ticks, and
    /// both steering horizons (the boost's return as shares of the jump's `airtime_s`).
    fn flight_swept(&mut self, grid: &SweepGrid, airtime_s: f64) {
        let base = self.best_policy();
        let mut returns: Vec<Option<f64>> = vec![None];
        returns.extend(grid.return_factors.iter().map(|f| Some(f * airtime_s)));
        for air_strafe in [true, false] {
            for jump_tick_strafe in [true, false] {
                for &steer_time_s in grid.steer_times {
                    for &boost_return_s in &returns {
                        self.try_policy(JumpPolicy {
                            air_strafe,
                            jump_tick_strafe,
                            steer_time_s,
                            boost_return_s,
                            ..base
                        });
                    }
                }
            }
        }
    }

    /// The jump kinds and the wait on the ground tried one at a time, each from the best policy so far.
    fn ground_swept(&mut self) {
        for standing_jumps in 0..=MAX_STANDING_JUMPS {
            self.try_policy(JumpPolicy {
                standing_jumps,
                ..self.best_policy()
            });
        }
        for jump_delay_ticks in 0..=MAX_JUMP_DELAY_TICKS {
            self.try_policy(JumpPolicy {
                jump_delay_ticks,
                ..self.best_policy()
            });
        }
    }
}

/// The policy search's grid at a quality level: most coordinate-descent sweeps, the steering horizons
/// (seconds) and the boost's return times (shares of the jump's airtime) tried.
struct SweepGrid {
    sweeps_max: u64,
    steer_times: &'static [f64],
    return_factors: &'static [f64],
}

impl SweepGrid {
    fn of(quality: Quality) -> SweepGrid {
        let (sweeps_max, steer_times, return_factors): (u64, &[f64], &[f64]) = match quality {
            Quality::Fast => (2, &[0.1, 0.2, 0.4, 0.8], &[0.5, 1.0, 2.0]),
            Quality::Balanced => (
                4,
                &[0.05, 0.1, 0.15, 0.2, 0.3, 0.4, 0.6, 0.8, 1.2],
                &[0.5, 0.75, 1.0, 1.5, 2.0, 3.0],
            ),
            Quality::Exact => (
                8,
                &[
                    0.05, 0.075, 0.1, 0.15, 0.2, 0.25, 0.3, 0.4, 0.5, 0.6, 0.8, 1.0, 1.2, 1.6,
                ],
                &[0.4, 0.5, 0.6, 0.75, 0.9, 1.0, 1.25, 1.5, 2.0, 2.5, 3.0, 4.0],
            ),
        };
        SweepGrid {
            sweeps_max,
            steer_times,
            return_factors,
        }
    }
}

/// The earliest tick on which the player can be on the ground, from the scene's start.
fn first_ground_tick(sim: &Simulation) -> u64 {
    let mut s = sim.scene().start;
    let idle = Control {
        yaw_rad: 0.0,
        forwardmove: 0.0,
        sidemove: 0.0,
        jump: false,
        duck: false,
    };
    for tick in 1..=sim.scene().max_frames.min(10_000) {
        if s.on_ground {
            return tick;
        }
        sim.frame(&mut s, &idle);
    }
    1
}

/// The fastest valid run of a jumping scene found by the policy search (see the module documentation),
/// or `None` when the scene cannot jump with the Source boost (no gravity, jump or boost: nothing here
/// applies) or no candidate reached the line validly. The hand-tuned ABH controller
/// ([`crate::sim::abh::Abh`]) is one of the candidates, so the plan is never worse than it.
pub fn plan_jumps(sim: &Simulation, settings: &SearchSettings, budget: Budget) -> Option<JumpPlan> {
    let fx = sim.scene().effects;
    if !(fx.has(Effect::Gravity) && fx.has(Effect::Jump) && fx.has(Effect::JumpBoost)) {
        return None;
    }
    let mut search = Search {
        sim,
        best: None,
        evaluations: 0,
        budget,
        timed_out: false,
    };
    // The hand-tuned run is the baseline to beat.
    let abh = run_abh(sim, AbhParams::default());
    search.evaluations += 1;
    search.consider(JumpPolicy::default(), abh.trace);
    search.try_policy(JumpPolicy::default());

    let first = first_ground_tick(sim);
    let airtime = jump_airtime_s(&sim.scene().vars).unwrap_or(0.5);
    let grid = SweepGrid::of(settings.quality);
    let mut sweeps = 0;
    loop {
        sweeps += 1;
        let before = search.best.as_ref().map_or(f64::INFINITY, |b| b.time());
        search.start_phase_swept(first);
        search.flight_swept(&grid, airtime);
        search.ground_swept();
        let after = search.best.as_ref().map_or(f64::INFINITY, |b| b.time());
        if after >= before || sweeps >= grid.sweeps_max || search.timed_out {
            break;
        }
    }
    let Search {
        best,
        evaluations,
        timed_out,
        ..
    } = search;
    best.map(|best| JumpPlan {
        best,
        evaluations,
        sweeps,
        timed_out,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::Scene;
    use crate::sim::abh::hops_from_trace;

    fn abh_scene() -> Scene {
        let text = include_str!("../../scenarios/hl2-abh-100m.toml");
        Scene::from_toml_str(text, "hl2-abh-100m.toml")
            .unwrap_or_else(|e| panic!("the shipped scene loads: {e}"))
    }

    fn time(t: &Trace) -> f64 {
        match t.crossing {
            Some(c) if t.feasible() => c.time,
            _ => f64::INFINITY,
        }
    }

    #[test]
    fn jump_kinds_follow_the_policy() {
        let p = JumpPolicy {
            first_jump: JumpKind::Standing,
            standing_jumps: 2,
            ..JumpPolicy::default()
        };
        let kinds: Vec<JumpKind> = (0..5).map(|i| p.kind(i)).collect();
        use JumpKind::{Ducked, Standing};
        assert_eq!(kinds, [Standing, Standing, Standing, Ducked, Ducked]);
    }

    #[test]
    fn the_runner_backhops_on_every_landing_and_strafing_beats_holding_no_keys() {
        let scene = abh_scene();
        let sim = Simulation::new(&scene).unwrap_or_else(|e| panic!("{e}"));
        let tau = scene.frame_time_s();
        let strafing = sim.run(&mut JumpRunner::new(JumpPolicy::default()));
        let still = sim.run(&mut JumpRunner::new(JumpPolicy {
            air_strafe: false,
            jump_tick_strafe: false,
            ..JumpPolicy::default()
        }));
        assert!(strafing.feasible() && still.feasible());
        for t in [&strafing, &still] {
            let hops = hops_from_trace(t, tau);
            assert_eq!(hops.first().map(|h| h.frame), Some(23));
            // Every hop lasts the airtime fixed by gravity, no ground tick in between: 35 ticks after the
            // standing first jump (160 ups added to the first gravity half-step), 36 after each ducked
            // backhop (160 ups set; docs/physics.md section 2).
            for (i, h) in hops[..hops.len() - 1].iter().enumerate() {
                let ticks = if i == 0 { 35.0 } else { 36.0 };
                assert!(
                    (h.hop_time.unwrap_or(0.0) - ticks * tau).abs() < 1e-12,
                    "{h:?}"
                );
            }
        }
        // Without keys in the air this is the article's recipe: 225, 285, 405, ... (section 11).
        let speeds: Vec<f64> = hops_from_trace(&still, tau)
            .iter()
            .map(|h| h.speed)
            .collect();
        for (s, want) in speeds.iter().zip([225.0, 285.0, 405.0, 645.0, 1125.0]) {
            assert!((s - want).abs() < 1e-6, "{speeds:?}");
        }
        // Air strafing adds about 1.9 ups a tick at 225 ups, doubled by every later boost.
        let strafed: Vec<f64> = hops_from_trace(&strafing, tau)
            .iter()
            .map(|h| h.speed)
            .collect();
        assert!(strafed[1] > 360.0 && strafed[2] > 640.0, "{strafed:?}");
        assert!(
            time(&strafing) + 0.4 < time(&still),
            "{} vs {}",
            time(&strafing),
            time(&still)
        );
    }

    #[test]
    fn jumping_on_the_landing_tick_beats_waiting() {
        let scene = abh_scene();
        let sim = Simulation::new(&scene).unwrap_or_else(|e| panic!("{e}"));
        let times: Vec<f64> = (0..3)
            .map(|d| {
                time(&sim.run(&mut JumpRunner::new(JumpPolicy {
                    jump_delay_ticks: d,
                    ..JumpPolicy::default()
                })))
            })
            .collect();
        assert!(times[0] < times[1] && times[1] < times[2], "{times:?}");
    }

    #[test]
    fn the_search_is_deterministic_and_beats_the_hand_tuned_run() {
        let scene = abh_scene();
        let sim = Simulation::new(&scene).unwrap_or_else(|e| panic!("{e}"));
        let settings = SearchSettings::for_quality(Quality::Fast);
        let a =
            plan_jumps(&sim, &settings, Budget::unlimited()).unwrap_or_else(|| panic!("a plan"));
        let b =
            plan_jumps(&sim, &settings, Budget::unlimited()).unwrap_or_else(|| panic!("a plan"));
        assert_eq!(a.best.trace.controls, b.best.trace.controls);
        assert_eq!(a.evaluations, b.evaluations);
        assert!(a.best.valid() && !a.timed_out);
        let hand = run_abh(&sim, AbhParams::default());
        let hand_time = hand.pistol_to_line.unwrap_or(0.0);
        assert!(
            a.best.time() + 0.5 < hand_time,
            "{} vs {hand_time}",
            a.best.time()
        );
        // Every yaw is on an anglemod step, so the engine-exact run crosses in the same tick.
        assert_eq!(
            a.best.engine_exact.crossing.map(|c| c.frames),
            a.best.trace.crossing.map(|c| c.frames)
        );
    }

    #[test]
    fn a_deadline_in_the_past_keeps_the_hand_tuned_run() {
        let scene = abh_scene();
        let sim = Simulation::new(&scene).unwrap_or_else(|e| panic!("{e}"));
        let settings = SearchSettings::for_quality(Quality::Fast);
        let p = plan_jumps(
            &sim,
            &settings,
            Budget::new(Some(std::time::Instant::now()), None),
        )
        .unwrap_or_else(|| panic!("a plan"));
        assert!(p.timed_out && p.best.valid());
        let hand = run_abh(&sim, AbhParams::default());
        assert_eq!(p.best.trace.crossing, hand.trace.crossing);
    }

    #[test]
    fn scenes_without_the_jump_boost_are_not_planned() {
        let text = include_str!("../../scenarios/hl-bhop-cap-100fps.toml");
        let scene =
            Scene::from_toml_str(text, "hl-bhop-cap-100fps.toml").unwrap_or_else(|e| panic!("{e}"));
        let sim = Simulation::new(&scene).unwrap_or_else(|e| panic!("{e}"));
        let settings = SearchSettings::for_quality(Quality::Fast);
        assert!(plan_jumps(&sim, &settings, Budget::unlimited()).is_none());
    }
}
