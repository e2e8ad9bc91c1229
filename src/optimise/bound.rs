//! The lower bound on the finish time (docs/physics.md section 6): the greedy maximum-acceleration speed is the
//! largest speed any control sequence can have after each frame, so no path can be longer after `n` frames
//! than the distance the greedy speed profile covers. The time that profile needs to cover the corridor's
//! shortest path is a lower bound on the time of every run.
//!
//! The profile is built from speeds alone, so it bounds every direction at once: `s_{k+1} = max_accel(
//! lambda_max(min(s_k, V_max sqrt 2)))`, using that the per-component clamp never raises the speed (and
//! caps it at `V_max sqrt 2`), that friction never raises it, and that the new speed of maximum acceleration
//! grows with the old one.

use crate::budget::{Budget, Stage};
use crate::error::{Error, Result};
use crate::geometry::{Corridor, FinishPoint, HULL_HALF_WIDTH_UNITS};
use crate::physics::strafe::max_accel;
use crate::physics::vars::BHOP_CAP_FACTOR;
use crate::physics::{AccelLaw, Effect, Effects, MovementVars, PlayerState, Stepper, Vec2, Wish};
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
    /// `Mx` when the Source jump boost can fire (docs/physics.md section 11).
    jump_boost_maxspeed: Option<f64>,
    /// With the bunnyhop cap (docs/physics.md section 10), the largest horizontal speed a jump keeps uncut, ups.
    bhop_cap_speed: Option<f64>,
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
        let bhop_cap_speed = effects
            .has(Effect::BhopCap)
            .then(|| bhop_cap_horizontal_speed(vars, effects));
        SpeedBound {
            air,
            ground,
            friction,
            clamp_speed,
            jump_boost_maxspeed,
            bhop_cap_speed,
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

    /// The largest speed after one airborne frame from any speed up to `speed` (no jump): the clamp, then
    /// the air FME at maximum acceleration (docs/physics.md sections 6 and 10).
    fn air_next(&self, speed: f64) -> f64 {
        let s = self.clamp_speed.map_or(speed, |c| speed.min(c));
        self.air.map_or(s, |law| s.max(max_accel(s, law).speed))
    }

    /// The largest speed after one ground frame without a jump from any speed up to `speed`: friction,
    /// the clamp, the ground FME at maximum acceleration with wish speed `m_ups` (sections 4-6).
    fn ground_next(&self, speed: f64, law: Option<AccelLaw>) -> f64 {
        let s = self.clamp_speed.map_or(speed, |c| speed.min(c));
        let l = self.lambda_max(s);
        law.map_or(l, |law| l.max(max_accel(l, law).speed))
    }

    /// The largest speed after a jump frame from any speed up to `speed`: the bunnyhop cap (section 10),
    /// then the Source boost (section 11), which adds at most `p |Fm| <= p Mx` below the cap `(1 + p) Mx`
    /// and `|v| - (1 + p) Mx` above it, with `p = 0.1` and the keys cropped by `duck_multiplier` when
    /// ducked (`ducked = Some(crop)`), `p = 0.5` standing (the frame step has no sprint); then the clamp
    /// and the air FME (the jump leaves the ground before friction, section 3).
    fn jump_next(&self, speed: f64, ducked: Option<f64>) -> f64 {
        // The cap keeps speeds up to T and cuts faster ones below 1.105 M <= T: at most min(s, T).
        let speed = self.bhop_cap_speed.map_or(speed, |t| speed.min(t));
        let boosted = match self.jump_boost_maxspeed {
            Some(mx) => {
                let (p, fm) = match ducked {
                    Some(crop) => (0.1, crop * mx),
                    None => (0.5, mx),
                };
                let cap = (1.0 + p) * mx;
                let below = (speed + p * fm).min(cap.max(speed));
                // Above the cap the addition is `cap - |v|`: the speed becomes at most `2|v| - cap`.
                below.max(2.0 * speed - cap)
            }
            None => speed,
        };
        self.air_next(boosted)
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

/// The largest horizontal speed a jump from the flat floor keeps under the bunnyhop cap (docs/physics.md
/// section 10), ups: the cap measures the 3-D speed after the first gravity half-step, `v_z = -g tau / 2`,
/// so it is `sqrt((1.7 M)^2 - v_z^2)`. Faster jumps are cut to `1.105 M` in 3-D.
pub fn bhop_cap_horizontal_speed(vars: &MovementVars, effects: Effects) -> f64 {
    let cap = BHOP_CAP_FACTOR * vars.maxspeed;
    let vz = if effects.has(Effect::Gravity) {
        0.5 * vars.gravity * vars.frame_time_s()
    } else {
        0.0
    };
    (cap * cap - vz * vz).max(0.0).sqrt()
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
    time_to_cover_within(
        vars,
        effects,
        start,
        distance,
        max_frames,
        &Budget::unlimited(),
    )
    .ok()
    .flatten()
}

/// Frames of the speed profile between two looks at the budget.
const PROFILE_FRAMES_PER_BUDGET_CHECK: u64 = 1 << 16;

/// [`time_to_cover`] within `budget`: [`Error::Stopped`] when it runs out first.
fn time_to_cover_within(
    vars: &MovementVars,
    effects: Effects,
    start: &PlayerState,
    distance: f64,
    max_frames: u64,
    budget: &Budget,
) -> Result<Option<Crossing>> {
    let bound = SpeedBound::new(vars, effects);
    let tau = vars.frame_time_s();
    let mut speed = start.speed();
    let mut covered = 0.0;
    if distance <= 0.0 {
        return Ok(Some(Crossing::new(1, 0.0, tau)));
    }
    for frame in 1..=max_frames {
        if frame % PROFILE_FRAMES_PER_BUDGET_CHECK == 0 && budget.expired() {
            return Err(Error::stopped(budget.stop(), Stage::LowerBound));
        }
        speed = bound.next(speed);
        let step = speed * tau;
        if covered + step >= distance && step > 0.0 {
            let fraction = ((distance - covered) / step).clamp(0.0, 1.0);
            return Ok(Some(Crossing::new(frame, fraction, tau)));
        }
        covered += step;
    }
    Ok(None)
}

/// The schedule-aware bound of a scene with gravity and jumps (docs/physics.md sections 3, 4, 10, 11), far
/// tighter than [`time_to_cover`]'s profile, which lets a jump (and its boost) fire on any frame and
/// ignores the bunnyhop cap. It uses what the flat floor fixes whatever the controls:
/// - the vertical motion depends on the jump frames only (gravity, the jump speed, the 2-unit ground
///   layer), so after a jump in frame `j` the player is airborne until frame `j + K` starts, `K` measured
///   with the scene's own stepper; in Source a ducked jump sets `v_z = 160` and a standing one adds 160 to
///   the first gravity half-step (section 2), so both airtimes are allowed; a jump needs a frame that
///   starts on the ground;
/// - an airborne frame runs only the air FME, a ground frame without a jump friction and the ground FME,
///   a jump frame the bunnyhop cap, the Source boost and the air FME (the jump comes before friction);
/// - the bunnyhop cap (section 10) scales a jump's 3-D speed above `1.7 M` to `1.105 M`: whatever the
///   speed `s` on the ground, the jump leaves at most `min(s, T)` horizontally, `T` the largest uncut
///   horizontal speed with the frame's `v_z = -g tau / 2`;
/// - from a ducked start the duck step keeps the player ducked until the unduck timer runs out (frame
///   `U`, also measured): before it the ground wish speed is cropped and the boost has `p = 0.1`;
/// - `sv_maxvelocity` clamps each component before the FME (section 10), so the progress along the unit
///   normal `n` of the finish line in a frame is at most `tau (V_max (|n_x| + |n_y|) + gamma1)`.
///
/// A jump schedule fixes which frames are ground, air and jump frames, so with the largest speed of each
/// kind of frame (every step increasing in the speed) it gives the largest speed in every frame, hence the
/// earliest frame that schedule could cover `path_length` along the path and `progress.1` units along
/// `n = progress.0` (the later of the two). The bound is the earliest over all schedules, found by dynamic
/// programming over frames: the state of a schedule in a frame is its phase (on the ground, or airborne
/// with `k` frames to the next landing) and its speed and both distances so far; of two states in the same
/// frame and phase, one at least as fast and as far along in both distances does at least as well in every
/// later frame (the steps are monotone and depend on the frame only through `U`), so only the Pareto front
/// of each phase is kept. One more dominance prunes: **jump on the landing frame once the speed is at least
/// the ground's fixed point `s*` (and at most `T` under the cap)**: above `s*` a ground frame cannot raise
/// the speed (`G(s) <= s`), and below `T` a jump keeps it, so a delayed jump is a prompt one shifted later
/// with no higher speeds. After frame `U` the steps do not depend on the frame, which the shift needs, so
/// before `U` every choice is kept.
///
/// `None` when the scene does not jump, or no schedule gets there within `max_frames`; [`lower_bound`]
/// then falls back to [`time_to_cover`].
pub fn jump_schedule_time_to_cover(
    scene: &Scene,
    path_length: f64,
    progress: (Vec2, f64),
) -> Option<Crossing> {
    jump_schedule_time_to_cover_within(scene, path_length, progress, &Budget::unlimited())
}

/// [`jump_schedule_time_to_cover`] within `budget`: a programme cut short proves nothing about the
/// schedules it did not reach, so it gives `None` (and [`lower_bound_within`] the looser profile).
pub fn jump_schedule_time_to_cover_within(
    scene: &Scene,
    path_length: f64,
    progress: (Vec2, f64),
    budget: &Budget,
) -> Option<Crossing> {
    let (search, first_ground) = schedule_search(scene, path_length, progress)?;
    search.run(scene.start.speed(), first_ground, scene.max_frames, budget)
}

/// The dynamic programme of [`jump_schedule_time_to_cover`] for `scene`, with the first frame that starts
/// on the ground; `None` when the scene does not jump or never lands.
fn schedule_search(
    scene: &Scene,
    path_length: f64,
    progress: (Vec2, f64),
) -> Option<(ScheduleSearch, u64)> {
    let (vars, fx) = (&scene.vars, scene.effects);
    if !(fx.has(Effect::Gravity) && fx.has(Effect::Jump)) {
        return None;
    }
    let tau = vars.frame_time_s();
    let stepper: Stepper<f64> = Stepper::new(vars, fx);
    let probe_frames = scene.max_frames.min(MAX_SCHEDULE_PROBE_FRAMES);
    let (first_ground, standing_from) = first_ground_and_standing(scene, &stepper, probe_frames)?;
    let (standing_airtime, ducked_airtime) = airtimes(&stepper, fx, probe_frames)?;
    let (m, m_ducked) = wish_speeds_ups(vars, &stepper);
    let crop = vars.duck_multiplier;
    let law = |wish: f64| {
        fx.has(Effect::GroundAccel)
            .then(|| AccelLaw::ground(vars, wish))
    };
    let (dir, progress_units) = progress;
    let gamma1_max = vars.entity_friction * tau * m * vars.accelerate.max(vars.airaccelerate);
    let along_cap = if fx.has(Effect::MaxVelocity) {
        vars.maxvelocity * (dir.x.abs() + dir.y.abs()) + gamma1_max
    } else {
        f64::INFINITY
    };
    let bound = SpeedBound::new(vars, fx);
    let standing_law = law(m);
    let search = ScheduleSearch {
        bound,
        tau,
        standing_airtime,
        ducked_airtime,
        standing_from,
        standing_law,
        ducked_law: law(m_ducked),
        crop,
        ground_fixed_point: ground_fixed_point(&bound, standing_law),
        path_length,
        progress_units,
        along_cap,
    };
    Some((search, first_ground))
}

/// The first frame that starts on the ground and the first that can be standing (duck released from
/// the start; `u64::MAX` if none within `probe_frames`), the start played idle; `None` when it never lands
/// within `probe_frames`.
fn first_ground_and_standing(
    scene: &Scene,
    stepper: &Stepper<f64>,
    probe_frames: u64,
) -> Option<(u64, u64)> {
    let mut s = scene.start;
    let mut first_ground = None;
    let mut standing_from = if s.ducked { None } else { Some(1) };
    let idle = idle_forward();
    for frame in 1..=probe_frames {
        if s.on_ground && first_ground.is_none() {
            first_ground = Some(frame);
        }
        stepper.step(&mut s, &idle);
        if !s.ducked && standing_from.is_none() {
            standing_from = Some(frame);
        }
        if first_ground.is_some() && standing_from.is_some() {
            break;
        }
    }
    Some((first_ground?, standing_from.unwrap_or(u64::MAX)))
}

/// No keys, facing along x.
fn idle_forward() -> Wish {
    Wish {
        forward: Vec2::new(1.0, 0.0),
        ..Wish::default()
    }
}

/// The airtimes, standing and (with the duck effect, else the standing one again) ducked: frames from a
/// jump frame to the next frame that starts on the ground; `None` when a jump does not land within
/// `probe_frames`.
fn airtimes(stepper: &Stepper<f64>, fx: Effects, probe_frames: u64) -> Option<(u64, u64)> {
    let airtime_of = |ducked: bool| -> Option<u64> {
        let mut s = PlayerState::on_ground(Vec2::ZERO, Vec2::ZERO);
        s.ducked = ducked;
        let jump = Wish {
            jump: true,
            duck: ducked,
            ..idle_forward()
        };
        let hold = Wish {
            duck: ducked,
            ..idle_forward()
        };
        stepper.step(&mut s, &jump);
        let mut airtime = 1u64;
        while !s.on_ground {
            if airtime >= probe_frames {
                return None;
            }
            stepper.step(&mut s, &hold);
            airtime += 1;
        }
        Some(airtime)
    };
    let standing_airtime = airtime_of(false)?;
    let ducked_airtime = if fx.has(Effect::Duck) {
        airtime_of(true)?
    } else {
        standing_airtime
    };
    Some((standing_airtime, ducked_airtime))
}

/// The wish speed of a ground frame with the movement keys, standing and ducked, ups: the frame step's
/// own [`Stepper::wish_direction`], so each game's duck crop comes in its own order.
fn wish_speeds_ups(vars: &MovementVars, stepper: &Stepper<f64>) -> (f64, f64) {
    let keys = Wish {
        forward: Vec2::new(1.0, 0.0),
        forwardmove: vars.forward_key_speed,
        sidemove: vars.side_key_speed,
        ..Wish::default()
    };
    let on_ground = true;
    let (_, m) = stepper.wish_direction(&keys, false, on_ground);
    let (_, m_ducked) = stepper.wish_direction(&keys, true, on_ground);
    (m, m_ducked)
}

/// Frames [`jump_schedule_time_to_cover`] steps to find the first landing, the unduck frame and the
/// airtime (far beyond any jump: 10 minutes at 100 fps).
const MAX_SCHEDULE_PROBE_FRAMES: u64 = 60_000;
/// Most states kept per phase and frame: beyond it the two nearest in speed are merged into one with the
/// larger of each coordinate, which no schedule can beat (the bound stays valid, a little looser).
const MAX_FRONT_STATES: usize = 64;

/// Frames of the schedule programme between two looks at the budget.
const SCHEDULE_FRAMES_PER_BUDGET_CHECK: u64 = 256;

/// The fixed point `s*` of the standing ground step `G` (friction, then maximum ground acceleration): the
/// limit of `G` iterated from rest. `G` is increasing, so it climbs to `s*`, and above `s*` the friction
/// `tau k s` outgrows the acceleration: `G(s) <= s` (tested).
fn ground_fixed_point(bound: &SpeedBound, law: Option<AccelLaw>) -> f64 {
    let mut s = 0.0;
    for _ in 0..MAX_FIXED_POINT_ITERS {
        let next = bound.ground_next(s, law);
        if next <= s {
            return s;
        }
        s = next;
    }
    s
}

/// Iterations of [`ground_fixed_point`] (the ground speed converges geometrically, by `1 - tau k` a frame).
const MAX_FIXED_POINT_ITERS: usize = 1_000_000;

/// One schedule's state after a frame: its speed bound and both distances, each held at its target once
/// reached (past the target only the crossing frame matters, found when it is reached).
#[derive(Clone, Copy, Debug, PartialEq)]
struct ScheduleState {
    speed: f64,
    covered: f64,
    covered_along: f64,
}

impl ScheduleState {
    /// At least as fast and as far along in both distances as `other`.
    fn dominates(&self, other: &ScheduleState) -> bool {
        self.speed >= other.speed
            && self.covered >= other.covered
            && self.covered_along >= other.covered_along
    }
}

/// The Pareto front of one phase in one frame.
#[derive(Clone, Debug, Default)]
struct Front(Vec<ScheduleState>);

impl Front {
    /// Adds `state` unless a kept state dominates it, dropping the states it dominates.
    fn insert(&mut self, state: ScheduleState) {
        if self.0.iter().any(|k| k.dominates(&state)) {
            return;
        }
        self.0.retain(|k| !state.dominates(k));
        self.0.push(state);
        if self.0.len() > MAX_FRONT_STATES {
            self.merge_closest();
        }
    }

    /// Replaces the two states nearest in speed by their coordinate-wise maximum.
    fn merge_closest(&mut self) {
        self.0.sort_by(|a, b| a.speed.total_cmp(&b.speed));
        let Some(i) = (1..self.0.len()).min_by(|&i, &j| {
            let di = self.0[i].speed - self.0[i - 1].speed;
            let dj = self.0[j].speed - self.0[j - 1].speed;
            di.total_cmp(&dj)
        }) else {
            return;
        };
        let (a, b) = (self.0[i - 1], self.0[i]);
        self.0[i - 1] = ScheduleState {
            speed: a.speed.max(b.speed),
            covered: a.covered.max(b.covered),
            covered_along: a.covered_along.max(b.covered_along),
        };
        self.0.remove(i);
    }
}

/// The dynamic programme of [`jump_schedule_time_to_cover`].
struct ScheduleSearch {
    bound: SpeedBound,
    tau: f64,
    standing_airtime: u64,
    ducked_airtime: u64,
    standing_from: u64,
    standing_law: Option<AccelLaw>,
    ducked_law: Option<AccelLaw>,
    crop: f64,
    ground_fixed_point: f64,
    path_length: f64,
    progress_units: f64,
    along_cap: f64,
}

impl ScheduleSearch {
    /// Plays one frame of `state` at `speed` (the speed after the frame's FME, which the move uses) as
    /// frame `frame`: the new state, or the crossing when both distances are covered in it.
    fn play(
        &self,
        state: &ScheduleState,
        speed: f64,
        frame: u64,
    ) -> Result<ScheduleState, Crossing> {
        let tau = self.tau;
        let (step, along) = (speed * tau, speed.min(self.along_cap) * tau);
        let fraction = |covered: f64, step: f64, target: f64| -> f64 {
            if covered >= target {
                0.0
            } else if step > 0.0 {
                ((target - covered) / step).clamp(0.0, 1.0)
            } else {
                1.0
            }
        };
        let covered = (state.covered + step).min(self.path_length);
        let covered_along = (state.covered_along + along).min(self.progress_units);
        if covered >= self.path_length && covered_along >= self.progress_units {
            let f = fraction(state.covered, step, self.path_length).max(fraction(
                state.covered_along,
                along,
                self.progress_units,
            ));
            return Err(Crossing::new(frame, f, tau));
        }
        Ok(ScheduleState {
            speed,
            covered,
            covered_along,
        })
    }

    /// The earliest crossing over all schedules from `speed` at the start, first on the ground in frame
    /// `first_ground`, within `max_frames`.
    fn run(
        &self,
        start_speed: f64,
        first_ground: u64,
        max_frames: u64,
        budget: &Budget,
    ) -> Option<Crossing> {
        let longest = self.standing_airtime.max(self.ducked_airtime);
        let phases = usize::try_from(longest).ok()?;
        // fronts[0]: starts the frame on the ground; fronts[k]: airborne, k frames to the landing.
        let mut fronts: Vec<Front> = vec![Front::default(); phases.max(1)];
        let mut state = ScheduleState {
            speed: start_speed,
            covered: 0.0,
            covered_along: 0.0,
        };
        // Falling towards the first landing: air frames.
        for frame in 1..first_ground {
            let speed = self.bound.air_next(state.speed);
            match self.play(&state, speed, frame) {
                Ok(next) => state = next,
                Err(c) => return Some(c),
            }
        }
        fronts[0].insert(state);
        for frame in first_ground..=max_frames {
            if frame % SCHEDULE_FRAMES_PER_BUDGET_CHECK == 0 && budget.expired() {
                return None;
            }
            let mut next: Vec<Front> = vec![Front::default(); fronts.len()];
            let mut best: Option<Crossing> = None;
            let mut keep = |phase: usize, r: Result<ScheduleState, Crossing>| match r {
                Ok(st) => next[phase].insert(st),
                Err(c) => {
                    if best.is_none_or(|b| c.time < b.time) {
                        best = Some(c);
                    }
                }
            };
            let ducked = frame < self.standing_from;
            for st in &fronts[0].0 {
                // Jump: standing (not before the unduck frame) or ducked.
                let mut kinds: Vec<(Option<f64>, u64)> =
                    vec![(Some(self.crop), self.ducked_airtime)];
                if !ducked {
                    kinds.push((None, self.standing_airtime));
                }
                for (crop, airtime) in kinds {
                    let speed = self.bound.jump_next(st.speed, crop);
                    let phase = usize::try_from(airtime - 1).unwrap_or(0);
                    keep(phase, self.play(st, speed, frame));
                }
                let jump_at_once = !ducked
                    && st.speed >= self.ground_fixed_point
                    && self.bound.bhop_cap_speed.is_none_or(|t| st.speed <= t);
                if !jump_at_once {
                    let law = if ducked {
                        self.ducked_law
                    } else {
                        self.standing_law
                    };
                    let speed = self.bound.ground_next(st.speed, law);
                    keep(0, self.play(st, speed, frame));
                }
            }
            for (phase, front) in fronts.iter().enumerate().skip(1) {
                for st in &front.0 {
                    let speed = self.bound.air_next(st.speed);
                    keep(phase - 1, self.play(st, speed, frame));
                }
            }
            if best.is_some() {
                return best;
            }
            fronts = next;
        }
        None
    }
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

impl LowerBound {
    /// The relative gap of a run crossing at `time_s` seconds to the bound: `(time - bound) / bound`.
    pub fn gap(&self, time_s: f64) -> f64 {
        (time_s - self.crossing.time) / self.crossing.time.max(f64::MIN_POSITIVE)
    }
}

/// `scene` with its frame cap lowered to `max_frames`, after checking that the bound's crossing fits under
/// it: [`Error::FrameLimit`] names the frames needed and the limit. No run then goes past the limit: the
/// memory of a run (and of every stage after it) grows with its frames.
pub fn frame_limited_scene(scene: &Scene, bound: &LowerBound, max_frames: u64) -> Result<Scene> {
    if bound.crossing.frames > max_frames {
        return Err(Error::FrameLimit {
            scene: scene.origin.clone(),
            frames: bound.crossing.frames,
            limit: max_frames,
        });
    }
    Ok(Scene {
        max_frames: scene.max_frames.min(max_frames),
        ..scene.clone()
    })
}

/// The lower bound of `scene` through `corridor` (docs/physics.md section 6). For a `hull` finish the centre
/// need only come within the box of the line, at most `16 sqrt 2` units short of it, so that much is
/// taken off the path. Errors with [`Error::NoValidPath`] when no path reaches the finish.
pub fn lower_bound(scene: &Scene, corridor: &Corridor) -> Result<LowerBound> {
    lower_bound_within(scene, corridor, &Budget::unlimited())
}

/// [`lower_bound`] within `budget`: when it runs out during the jump-schedule search, the bound is the
/// speed profile's (valid, looser); when it runs out during the profile, [`Error::Stopped`].
pub fn lower_bound_within(
    scene: &Scene,
    corridor: &Corridor,
    budget: &Budget,
) -> Result<LowerBound> {
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
    // A scene with the Source boost gets the schedule-aware profile; the progress along the finish
    // line's normal is measured from the start to the line, less the hull's reach for a `hull` finish.
    let normal = (scene.finish.b - scene.finish.a)
        .perp()
        .normalized()
        .unwrap_or(Vec2::new(1.0, 0.0));
    let normal = if normal.dot(scene.finish.a - scene.start.pos) >= 0.0 {
        normal
    } else {
        -normal
    };
    let reach = match scene.finish.point {
        FinishPoint::Centre => 0.0,
        FinishPoint::Hull => HULL_HALF_WIDTH_UNITS * (normal.x.abs() + normal.y.abs()),
    };
    let along = ((scene.finish.a - scene.start.pos).dot(normal) - reach).max(0.0);
    let crossing =
        match jump_schedule_time_to_cover_within(scene, path_length, (normal, along), budget) {
            Some(c) => Some(c),
            None => time_to_cover_within(
                &scene.vars,
                scene.effects,
                &scene.start,
                path_length,
                scene.max_frames,
                budget,
            )?,
        };
    let crossing = crossing.ok_or_else(|| {
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

#[cfg(test)]
mod jump_schedule_tests {
    use super::*;
    use crate::optimise::hillclimb::XorShift64;
    use crate::physics::Control;

    fn hl2() -> (MovementVars, Effects) {
        let mut vars = MovementVars::source_hl2(200.0 / 3.0);
        vars.maxspeed = 150.0;
        let fx = Effects::from_list(&[
            Effect::AirAccel,
            Effect::GroundAccel,
            Effect::Friction,
            Effect::Gravity,
            Effect::Jump,
            Effect::JumpBoost,
            Effect::Duck,
            Effect::MaxVelocity,
        ]);
        (vars, fx)
    }

    /// Each step bound holds for random states and controls of the stepper: an airborne frame, a ground
    /// frame without a jump, a jump frame (standing or ducked), at speeds from rest to past the clamp.
    #[test]
    fn step_bounds_hold_for_random_frames() {
        let (vars, fx) = hl2();
        let st: Stepper<f64> = Stepper::new(&vars, fx);
        let b = SpeedBound::new(&vars, fx);
        let m = vars.maxspeed;
        let crop = vars.duck_multiplier;
        let ground = Some(AccelLaw::ground(&vars, m));
        let mut rng = XorShift64::new(11);
        for i in 0..20_000 {
            let speed = 5000.0 * rng.next_f64().powi(2);
            let dir = 2.0 * PI_F * rng.next_f64();
            let vel = Vec2::from_angle(dir) * speed;
            let on_ground = i % 2 == 0;
            let mut s = if on_ground {
                PlayerState::on_ground(Vec2::ZERO, vel)
            } else {
                let mut a = PlayerState::airborne(Vec2::ZERO, vel);
                a.z = 20.0;
                a.vz = 50.0;
                a
            };
            s.ducked = rng.next_f64() < 0.5;
            let key = |r: f64| [-450.0, 0.0, 450.0][(3.0 * r) as usize % 3];
            let c = Control {
                yaw_rad: 2.0 * PI_F * rng.next_f64(),
                forwardmove: key(rng.next_f64()),
                sidemove: key(rng.next_f64()),
                jump: rng.next_f64() < 0.5,
                duck: rng.next_f64() < 0.5,
            };
            let before = s.speed();
            let was_ducked = s.ducked;
            st.step(&mut s, &c.wish());
            let ducked_in_frame = c.duck || was_ducked;
            let limit = match (on_ground, c.jump) {
                (false, _) => b.air_next(before),
                (true, false) => b.ground_next(before, ground),
                (true, true) => {
                    let any = b.jump_next(before, None);
                    if ducked_in_frame {
                        any.max(b.jump_next(before, Some(crop)))
                    } else {
                        any
                    }
                }
            };
            assert!(
                s.speed() <= limit * (1.0 + 1e-12) + 1e-9,
                "frame {i}: {before} -> {} > {limit} ({c:?}, ground {on_ground})",
                s.speed()
            );
            // Ducked for the whole frame: the tighter ducked jump bound holds too.
            if on_ground && c.jump && c.duck {
                assert!(s.speed() <= b.jump_next(before, Some(crop)) * (1.0 + 1e-12) + 1e-9);
            }
        }
    }

    const PI_F: f64 = std::f64::consts::PI;

    /// Above the ground's fixed point a ground frame cannot raise the speed (the dominance the schedule
    /// search relies on), and below it, it does.
    #[test]
    fn ground_step_falls_above_its_fixed_point() {
        let (vars, fx) = hl2();
        let b = SpeedBound::new(&vars, fx);
        let law = Some(AccelLaw::ground(&vars, vars.maxspeed));
        let s_star = ground_fixed_point(&b, law);
        // Section 12's maximum groundstrafe speed: M sqrt(A (2 - tau A) / (k (2 - tau k))).
        let tau = vars.frame_time_s();
        let closed = vars.maxspeed
            * (vars.accelerate * (2.0 - tau * vars.accelerate) / (4.0 * (2.0 - tau * 4.0))).sqrt();
        assert!((s_star - closed).abs() < 1e-3, "{s_star} vs {closed}");
        for i in 0..10_000 {
            let s = s_star + 0.5 * i as f64;
            assert!(b.ground_next(s, law) <= s + 1e-9, "{s}");
        }
        assert!(b.ground_next(0.5 * s_star, law) > 0.5 * s_star);
    }

    /// Every jump schedule, enumerated without pruning or merging: the earliest crossing from a state
    /// that starts frame `frame` in `phase` (0: on the ground, `k`: `k` air frames to the landing).
    fn exhaustive(
        search: &ScheduleSearch,
        state: ScheduleState,
        frame: u64,
        phase: u64,
        max_frames: u64,
    ) -> Option<Crossing> {
        if frame > max_frames {
            return None;
        }
        let mut best: Option<Crossing> = None;
        let mut follow = |speed: f64, next_phase: u64| {
            let c = match search.play(&state, speed, frame) {
                Err(c) => Some(c),
                Ok(next) => exhaustive(search, next, frame + 1, next_phase, max_frames),
            };
            if let Some(c) = c {
                if best.is_none_or(|b| c.time < b.time) {
                    best = Some(c);
                }
            }
        };
        if phase > 0 {
            follow(search.bound.air_next(state.speed), phase - 1);
            return best;
        }
        let ducked = frame < search.standing_from;
        follow(
            search.bound.jump_next(state.speed, Some(search.crop)),
            search.ducked_airtime - 1,
        );
        if !ducked {
            follow(
                search.bound.jump_next(state.speed, None),
                search.standing_airtime - 1,
            );
        }
        let law = if ducked {
            search.ducked_law
        } else {
            search.standing_law
        };
        follow(search.bound.ground_next(state.speed, law), 0);
        best
    }

    /// The dynamic programme (Pareto fronts, the jump-at-once prune, the cap's envelope) finds the same
    /// earliest crossing as enumerating every schedule, on short GoldSrc bunnyhop lanes starting on the
    /// ground below, near and above the cap's speed (so the cut, the prune and ground braking all occur).
    #[test]
    fn the_schedule_programme_equals_exhaustive_enumeration() {
        for (speed, length) in [
            (320.0, 700.0),
            (540.0, 900.0),
            (600.0, 1000.0),
            (700.0, 1100.0),
        ] {
            let text = format!(
                "name = \"t\"\n[engine]\npreset = \"goldsrc\"\nfps = 100\neffects = [\"air-accel\", \
                 \"ground-accel\", \"friction\", \"gravity\", \"jump\", \"bhop-cap\", \"max-velocity\"]\n\
                 [start]\non-ground = true\nvelocity = [{speed}, 0]\n[lane]\nwidth = 256\nlength = {length}\n\
                 kind = \"rule\"\n"
            );
            let scene = Scene::from_toml_str(&text, "t.toml").unwrap_or_else(|e| panic!("{e}"));
            let distance = length - 40.0;
            let progress = (Vec2::new(1.0, 0.0), distance);
            let (search, first_ground) =
                schedule_search(&scene, distance, progress).unwrap_or_else(|| panic!("a search"));
            assert_eq!(first_ground, 1);
            let dp = search.run(speed, first_ground, scene.max_frames, &Budget::unlimited());
            let start = ScheduleState {
                speed,
                covered: 0.0,
                covered_along: 0.0,
            };
            let all = exhaustive(&search, start, 1, 0, 400);
            assert!(dp.is_some(), "{speed}");
            assert_eq!(dp, all, "start {speed} ups, {distance} units");
        }
        // Half-Life 2 with the boost, a ducked start at rest: both jump kinds and their airtimes (35
        // ticks standing, 36 ducked), the unduck frames.
        for length in [300.0, 450.0] {
            let text = format!(
                "name = \"t\"\n[engine]\npreset = \"source-hl2\"\nfps = 66.666666666666667\nmaxspeed = 150\n\
                 effects = [\"air-accel\", \"ground-accel\", \"friction\", \"gravity\", \"jump\", \
                 \"jump-boost\", \"duck\", \"max-velocity\"]\n[start]\nvelocity = [0, 0]\non-ground = true\n\
                 ducked = true\n[lane]\nwidth = 64\nlength = {length}\nkind = \"rule\"\n"
            );
            let scene = Scene::from_toml_str(&text, "t.toml").unwrap_or_else(|e| panic!("{e}"));
            let distance = length - 40.0;
            let (search, first_ground) =
                schedule_search(&scene, distance, (Vec2::new(1.0, 0.0), distance))
                    .unwrap_or_else(|| panic!("a search"));
            assert_eq!((search.standing_airtime, search.ducked_airtime), (35, 36));
            let dp = search.run(0.0, first_ground, scene.max_frames, &Budget::unlimited());
            let start = ScheduleState {
                speed: 0.0,
                covered: 0.0,
                covered_along: 0.0,
            };
            let all = exhaustive(&search, start, first_ground, 0, 200);
            assert!(dp.is_some(), "{length}");
            assert_eq!(dp, all, "{length} units");
        }
    }
}
