//! The minimal-time plan of a scene with ground movement, gravity and jumps but no Source jump boost:
//! GoldSrc bunnyhopping under the bunnyhop cap, groundstrafing, jumping corridors, Half-Life 2 air
//! strafing with jumps. Searched over a family of frame-level policies, every candidate a run of the real
//! frame loop, kept only if valid in `f64` and engine-exact.
//!
//! # Why a policy family is enough
//!
//! A frame of such a run is one of three kinds, and the physics fixes most of each:
//! 1. **In the air** (docs/physics.md sections 5-8) the view acts only through the wish direction, and the
//!    speed after the frame is any value between maximum deceleration (section 7) and maximum acceleration
//!    (section 6), each on either side. The side steers (towards the corridor's guide, as the greedy
//!    strafer does); the speed is the choice. Under the bunnyhop cap the speed wanted at the next landing
//!    is what matters: accelerating early and holding the speed (section 8) covers the most distance for
//!    a given landing speed, so one number, the **air speed** held once reached, sets a whole hop.
//! 2. **On a jump frame** (sections 3 and 10) the jump comes first: the cap scales a 3-D speed above
//!    `1.7 M` down to `1.105 M` (544 -> 353.6 ups at `M = 320`), then the air FME runs. Nothing on a jump
//!    frame depends on the view except the air FME, so it is an air frame with the cap before it.
//! 3. **On the ground** (sections 4-6) friction takes `tau k` of the speed, and the ground FME (`L = M`)
//!    adds far more than the air FME below the ground's fixed point (498 ups at 100 fps, section 12). The
//!    choice is whether to jump now or take a ground frame, and on a ground frame the speed to leave it at.
//!
//! So a landing above the cap has three answers: jump and be cut; take ground frames first (friction, and
//! the ground FME against the velocity, brake to just under the cap in as few frames as possible, keeping
//! each frame's speed as high as that allows); or never land above it (an air speed under the cap, which
//! brakes in the air before the landing). Which is fastest depends on how much the hop gains: the search
//! finds it by simulation ([`HopPolicy`]): the air speed (a grid around the cap's speed, the corner speeds
//! of the radius-speed relation, and none), whether to avoid the cut, the speed at which the first jump
//! leaves the ground (groundstrafing to it from a ground start; never, for pure groundstrafing), the
//! steering look-ahead, and ducking in the air where the scene ducks. Coordinate descent from the greedy
//! policy, every candidate a full run of [`Simulation::run`], yaws on anglemod steps (section 1), the best
//! replayed engine-exact before it is kept.

use super::bound::{bhop_cap_horizontal_speed, LowerBound};
use super::policy_run::{keep_if_better, PolicyRun};
use super::search::{Quality, SearchSettings, SearchStatus};
use crate::budget::Budget;
use crate::physics::closed_form::max_groundstrafe_speed;
use crate::physics::engine_exact::quantise_yaw_rad;
use crate::physics::strafe::{
    max_accel, max_decel, speed_preserving_cos_theta, strafe_control, strafe_keys, theta_from_cos,
};
use crate::physics::{friction, AccelLaw, Control, Effect, PlayerState, Side, Vec2, Wish};
use crate::sim::controllers::GREEDY_LOOKAHEADS_UNITS;
use crate::sim::{Controller, Greedy, Simulation, Trace};
use serde::Serialize;
use std::f64::consts::PI;

/// How far under the cap's largest uncut speed a planned jump stays, ups: room for the engine-exact
/// replay's `f32` arithmetic.
pub const CUT_MARGIN_UPS: f64 = 0.01;
/// Most ground frames the braking plan looks ahead.
const MAX_BRAKE_FRAMES: u32 = 1000;
/// Bisection steps for the speed of a braking ground frame.
const BRAKE_BISECTIONS: u32 = 60;

/// One candidate run: the choices the search makes (see the module documentation).
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct HopPolicy {
    /// The greedy guide's look-ahead along the corridor's shortest path, units.
    pub lookahead_units: f64,
    /// The speed held in the air once reached, ups (above it the air frames brake back to it); infinite:
    /// maximum acceleration every air frame.
    pub air_speed_ups: f64,
    /// On a landing above the bunnyhop cap's uncut speed, brake on the ground to just under it before
    /// jumping; off, jump on every landing and take the cut.
    pub avoid_cut: bool,
    /// The ground speed at which the first jump is taken, ups (groundstrafing at maximum acceleration
    /// until then); 0 jumps at once, infinite never jumps.
    pub takeoff_speed_ups: f64,
    /// Hold duck in the air (scenes with the duck effect).
    pub duck_in_air: bool,
}

impl HopPolicy {
    /// The greedy strafer's policy with autojump: maximum acceleration everywhere, a jump on every frame
    /// that starts on the ground (the cut taken), no duck.
    pub fn greedy(lookahead_units: f64) -> Self {
        HopPolicy {
            lookahead_units,
            air_speed_ups: f64::INFINITY,
            avoid_cut: false,
            takeoff_speed_ups: 0.0,
            duck_in_air: false,
        }
    }
}

/// The controller that plays a [`HopPolicy`] (see the module documentation).
#[derive(Clone, Debug)]
pub struct HopRunner {
    policy: HopPolicy,
    guide: Greedy,
    /// The largest horizontal speed a planned jump leaves at (the cap's uncut speed less
    /// [`CUT_MARGIN_UPS`]); `None` without the cap or when the policy takes the cut.
    jump_speed_limit: Option<f64>,
    jumped: bool,
}

impl HopRunner {
    /// A controller playing `policy` along `guide_path` (the corridor's shortest path) in `sim`.
    pub fn new(policy: HopPolicy, guide_path: &[Vec2], sim: &Simulation) -> Self {
        let scene = sim.scene();
        let jump_speed_limit = (policy.avoid_cut && scene.effects.has(Effect::BhopCap))
            .then(|| bhop_cap_horizontal_speed(&scene.vars, scene.effects) - CUT_MARGIN_UPS);
        HopRunner {
            policy,
            guide: Greedy::new(guide_path.to_vec(), policy.lookahead_units),
            jump_speed_limit,
            jumped: false,
        }
    }

    /// The keys of a frame: full sidemove, with jump and duck as given.
    fn keys(sim: &Simulation, jump: bool, duck: bool) -> Wish {
        let mut keys = strafe_keys(sim.scene().vars.side_key_speed);
        keys.jump = jump;
        keys.duck = duck;
        keys
    }

    /// A frame that leaves at `target_ups` (or as near as one frame gets: maximum acceleration below it,
    /// maximum deceleration above it), turning to `side`, yaw on an anglemod step.
    fn to_speed(
        s: &PlayerState,
        sim: &Simulation,
        keys: Wish,
        side: Side,
        heading: Vec2,
        target_ups: f64,
    ) -> Control {
        let mut c = strafe_control(sim.stepper(), s, keys, heading.angle(), |lambda, law| {
            side.sign() * theta_from_cos(cos_for_speed(lambda, law, target_ups))
        });
        c.yaw_rad = quantise_yaw_rad(c.yaw_rad.rem_euclid(2.0 * PI));
        c
    }

    /// The speed a braking ground frame leaves at: the fewest ground frames of friction and maximum
    /// deceleration that bring the speed under `limit`, and of the speeds this frame can leave at, the
    /// largest that needs no more of them (section 4 and 7 on the ground).
    fn braking_target(s: &PlayerState, sim: &Simulation, keys: &Wish, limit: f64) -> f64 {
        let mut probe = *s;
        let Some((_, law)) = sim.stepper().prepare(&mut probe, keys) else {
            return limit;
        };
        let lambda = probe.vel.length();
        let lo = max_decel(lambda, law).1;
        let hi = max_accel(lambda, law).speed;
        if lo <= limit {
            return limit.min(hi);
        }
        let vars = &sim.scene().vars;
        let k = vars.friction_k(sim.scene().effects.has(Effect::EdgeFriction));
        let tau = vars.frame_time_s();
        let brake = |u: f64| {
            let after = friction(Vec2::new(u, 0.0), tau, k, vars.stopspeed).length();
            max_decel(after, law).1
        };
        let frames_to_limit = |mut u: f64| {
            let mut n = 0;
            while u > limit && n < MAX_BRAKE_FRAMES {
                let next = brake(u);
                if next >= u {
                    return MAX_BRAKE_FRAMES;
                }
                u = next;
                n += 1;
            }
            n
        };
        let needed = frames_to_limit(lo);
        let (mut a, mut b) = (lo, hi);
        for _ in 0..BRAKE_BISECTIONS {
            let mid = 0.5 * (a + b);
            if frames_to_limit(mid) <= needed {
                a = mid;
            } else {
                b = mid;
            }
        }
        a
    }
}

/// `cos theta` of a frame that leaves at `target_ups` from `lambda` (the speed after friction) with `law`:
/// maximum acceleration (docs/physics.md section 6) when even that stays under the target, else the sharpest
/// angle that gives the target (section 8's solutions), else maximum deceleration (section 7).
pub fn cos_for_speed(lambda: f64, law: AccelLaw, target_ups: f64) -> f64 {
    let accel = max_accel(lambda, law);
    if accel.speed <= target_ups {
        return accel.cos_theta;
    }
    speed_preserving_cos_theta(target_ups, lambda, law).unwrap_or_else(|| max_decel(lambda, law).0)
}

impl Controller for HopRunner {
    fn name(&self) -> String {
        "hops".to_string()
    }

    fn control(&mut self, _frame: u64, s: &PlayerState, sim: &Simulation) -> Control {
        let fx = sim.scene().effects;
        let (side, to_target) = self.guide.steer(s, sim);
        let duck_in_air = self.policy.duck_in_air && fx.has(Effect::Duck);
        if !s.on_ground {
            let keys = Self::keys(sim, false, duck_in_air);
            return Self::to_speed(s, sim, keys, side, to_target, self.policy.air_speed_ups);
        }
        let speed = s.speed();
        let takes_off = fx.has(Effect::Jump)
            && (self.jumped || speed >= self.policy.takeoff_speed_ups)
            && self.policy.takeoff_speed_ups.is_finite();
        if !takes_off {
            // Groundstrafing at maximum acceleration (section 6 with the ground law).
            let keys = Self::keys(sim, false, false);
            return Self::to_speed(s, sim, keys, side, to_target, f64::INFINITY);
        }
        if let Some(limit) = self.jump_speed_limit.filter(|&l| speed > l) {
            let keys = Self::keys(sim, false, false);
            // Aimed a margin further under, so that rounding cannot leave it a hair over the limit.
            let target = Self::braking_target(s, sim, &keys, limit - CUT_MARGIN_UPS);
            return Self::to_speed(s, sim, keys, side, to_target, target);
        }
        self.jumped = true;
        let keys = Self::keys(sim, true, duck_in_air);
        Self::to_speed(s, sim, keys, side, to_target, self.policy.air_speed_ups)
    }
}

/// One evaluated hop policy.
pub type HopCandidate = PolicyRun<HopPolicy>;

/// The result of [`plan_hops`].
#[derive(Clone, Debug)]
pub struct HopPlan {
    /// The best valid run found.
    pub best: HopCandidate,
    /// Candidates simulated.
    pub evaluations: u64,
    /// Coordinate-descent sweeps run.
    pub sweeps: u64,
    /// The deadline stopped the search.
    pub timed_out: bool,
}

/// The search's state: the best candidate, the work done, the deadline.
struct HopSearch<'a, 's> {
    sim: &'a Simulation<'s>,
    guide: &'a [Vec2],
    best: Option<HopCandidate>,
    evaluations: u64,
    budget: Budget<'a>,
    timed_out: bool,
}

impl HopSearch<'_, '_> {
    /// Simulates `policy` and keeps it if it is valid in both arithmetics and crosses strictly earlier.
    fn try_policy(&mut self, policy: HopPolicy) -> bool {
        if self.timed_out || self.budget.expired() {
            self.timed_out = true;
            return false;
        }
        self.evaluations += 1;
        let trace = self.sim.run_within(
            &mut HopRunner::new(policy, self.guide, self.sim),
            &self.budget,
        );
        if trace.interrupted {
            self.timed_out = true;
            return false;
        }
        let (kept, interrupted) =
            keep_if_better(&mut self.best, self.sim, policy, trace, &self.budget);
        self.timed_out |= interrupted;
        kept
    }

    fn best_policy(&self, fallback: HopPolicy) -> HopPolicy {
        self.best.as_ref().map_or(fallback, |b| b.policy)
    }

    /// Tries every value of one coordinate from the best policy so far.
    fn sweep<T: Copy>(
        &mut self,
        fallback: HopPolicy,
        values: &[T],
        set: impl Fn(HopPolicy, T) -> HopPolicy,
    ) {
        let base = self.best_policy(fallback);
        for &v in values {
            self.try_policy(set(base, v));
        }
    }
}

/// The grids of one quality level.
struct Grids {
    sweeps: u64,
    air_steps_ups: Vec<f64>,
    /// Take-off speeds as shares of the groundstrafing top speed.
    takeoff_shares: Vec<f64>,
    lookaheads_units: Vec<f64>,
}

impl Grids {
    fn for_quality(quality: Quality) -> Self {
        let (sweeps, air_step, air_span, lookahead_stride) = match quality {
            Quality::Fast => (3, 4.0, 80.0, 3),
            Quality::Balanced => (4, 2.0, 100.0, 2),
            Quality::Exact => (6, 1.0, 120.0, 1),
        };
        let n = (air_span / air_step) as usize;
        Grids {
            sweeps,
            air_steps_ups: (0..=n).map(|i| i as f64 * air_step).collect(),
            takeoff_shares: vec![
                0.6, 0.7, 0.8, 0.85, 0.9, 0.93, 0.95, 0.97, 0.98, 0.99, 0.995,
            ],
            lookaheads_units: GREEDY_LOOKAHEADS_UNITS
                .iter()
                .copied()
                .step_by(lookahead_stride)
                .collect(),
        }
    }
}

/// The fastest valid run of a scene with ground movement, gravity or jumps and no Source jump boost (see
/// the module documentation) along `guide` (the corridor's shortest path), found by coordinate descent
/// over [`HopPolicy`] from the best greedy policy (every look-ahead); `None` for scenes this planner does
/// not cover (purely airborne, or with the Source boost: [`super::jumps`]) or when no candidate reaches
/// the line validly. `corner_speeds_ups` are extra air speeds to try (the radius-speed relation's corner
/// speeds). `balanced` and `exact` also run the levels below them, each its own descent from greedy
/// (they end in different local optima), and keep the fastest plan: a higher level is never worse.
pub fn plan_hops(
    sim: &Simulation,
    guide: &[Vec2],
    corner_speeds_ups: &[f64],
    settings: &SearchSettings,
    budget: Budget,
) -> Option<HopPlan> {
    let fx = sim.scene().effects;
    if fx.is_air_only() || fx.has(Effect::JumpBoost) {
        return None;
    }
    let levels: &[Quality] = match settings.quality {
        Quality::Fast => &[Quality::Fast],
        Quality::Balanced => &[Quality::Fast, Quality::Balanced],
        Quality::Exact => &[Quality::Fast, Quality::Balanced, Quality::Exact],
    };
    let mut plan: Option<HopPlan> = None;
    for &level in levels {
        let mut search = HopSearch {
            sim,
            guide,
            best: None,
            evaluations: 0,
            budget,
            timed_out: false,
        };
        for &la in &GREEDY_LOOKAHEADS_UNITS {
            search.try_policy(HopPolicy::greedy(la));
        }
        let sweeps = descend(&mut search, &Grids::for_quality(level), corner_speeds_ups);
        let (evaluations, timed_out) = (search.evaluations, search.timed_out);
        let before = plan.take();
        let (mut total_evaluations, mut total_sweeps) = (evaluations, sweeps);
        if let Some(p) = &before {
            total_evaluations += p.evaluations;
            total_sweeps += p.sweeps;
        }
        let timed_out = timed_out || before.as_ref().is_some_and(|p| p.timed_out);
        let best = match (before.map(|p| p.best), search.best) {
            (Some(a), Some(b)) => Some(if b.time() < a.time() { b } else { a }),
            (a, b) => a.or(b),
        };
        plan = best.map(|best| HopPlan {
            best,
            evaluations: total_evaluations,
            sweeps: total_sweeps,
            timed_out,
        });
        if timed_out {
            break;
        }
    }
    plan
}

/// One level's coordinate descent from the best policy so far: the air speed with and without the cut
/// together, the take-off speed, the look-ahead and the duck, repeated until a sweep gains nothing or
/// the level's sweeps are spent. Returns the sweeps run.
fn descend(search: &mut HopSearch, grids: &Grids, corner_speeds_ups: &[f64]) -> u64 {
    let scene = search.sim.scene();
    let fx = scene.effects;
    let start = HopPolicy::greedy(GREEDY_LOOKAHEADS_UNITS[GREEDY_LOOKAHEADS_UNITS.len() / 2]);
    // Air speeds: none, around the cap's uncut speed (from just under it up), and the corner speeds.
    let mut air_speeds: Vec<f64> = vec![f64::INFINITY];
    if fx.has(Effect::BhopCap) {
        let uncut = bhop_cap_horizontal_speed(&scene.vars, fx) - CUT_MARGIN_UPS;
        air_speeds.extend(grids.air_steps_ups.iter().map(|d| uncut + d));
    }
    air_speeds.extend(corner_speeds_ups.iter().copied());
    // Take-off speeds: at once, shares of the groundstrafing top speed (docs/physics.md section 12; the
    // ground FME gains fastest far below it), never.
    let top = max_groundstrafe_speed(&scene.vars, fx.has(Effect::EdgeFriction));
    let mut takeoffs = vec![0.0];
    if top.is_finite() {
        takeoffs.extend(grids.takeoff_shares.iter().map(|f| f * top));
    }
    takeoffs.push(f64::INFINITY);
    let mut sweeps = 0;
    loop {
        sweeps += 1;
        let before = search.best.as_ref().map_or(f64::INFINITY, |b| b.time());
        if fx.has(Effect::Jump) {
            // The cap's choices together: the air speed with and without the cut.
            let base = search.best_policy(start);
            for avoid_cut in [true, false] {
                for &air_speed_ups in &air_speeds {
                    search.try_policy(HopPolicy {
                        avoid_cut,
                        air_speed_ups,
                        ..base
                    });
                }
            }
            search.sweep(start, &takeoffs, |p, v| HopPolicy {
                takeoff_speed_ups: v,
                ..p
            });
        } else {
            search.sweep(start, &air_speeds, |p, v| HopPolicy {
                air_speed_ups: v,
                ..p
            });
        }
        search.sweep(start, &grids.lookaheads_units, |p, v| HopPolicy {
            lookahead_units: v,
            ..p
        });
        if fx.has(Effect::Duck) {
            search.sweep(start, &[false, true], |p, v| HopPolicy {
                duck_in_air: v,
                ..p
            });
        }
        let after = search.best.as_ref().map_or(f64::INFINITY, |b| b.time());
        if after >= before || sweeps >= grids.sweeps || search.timed_out {
            return sweeps;
        }
    }
}

/// The status of a solve that returns the greedy run: [`SearchStatus::GreedyOptimal`] when greedy is
/// valid and crosses in the lower bound's frame (no run crosses in an earlier frame, so at most the
/// fraction of that frame is left), else [`SearchStatus::NoImprovement`].
pub fn greedy_status(greedy: &Trace, bound: &LowerBound) -> SearchStatus {
    match greedy.crossing {
        Some(c) if greedy.feasible() && c.frames <= bound.crossing.frames => {
            SearchStatus::GreedyOptimal {
                reason: format!(
                    "it crosses in frame {}, the lower bound's frame ({:.6} s against {:.6} s): no run \
                     crosses in an earlier frame",
                    c.frames, c.time, bound.crossing.time
                ),
            }
        }
        _ => SearchStatus::NoImprovement {
            reason: "no valid plan of the search crosses earlier than the greedy run".to_string(),
        },
    }
}
