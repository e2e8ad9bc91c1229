//! One simulation frame (docs/physics.md section 3, GoldSrc `PM_PlayerMove` / Source `FullWalkMove` order):
//! duck, first half of gravity, jump, friction, clamp, the FME, the move, categorisation, second half of
//! gravity. The step is written once over the scalar `R` ([`Real`]): `f64` plans, `f32` reproduces the
//! game's own arithmetic (see `engine_exact`).
//!
//! The horizontal move (step 5) is split out: [`Stepper::step`] moves freely, while a simulation with walls
//! calls [`Stepper::pre_move`], sweeps the hull itself, then calls [`Stepper::post_move`].

use super::abh::boost_add_from_keys;
use super::effects::{Effect, Effects};
use super::real::Real;
use super::vars::{
    Game, MovementVars, BHOP_CAP_FACTOR, BHOP_CAP_RESULT_FACTOR, FRICTION_MIN_SPEED_UPS,
    GROUND_LAYER_UNITS, WALK_STOP_SPEED_UPS,
};
use super::vec2::{Vec2, V2};
use serde::{Deserialize, Serialize};

/// The player's state between frames. `Copy`: a frame maps one state to the next.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct PlayerState<R = f64> {
    /// Horizontal position of the hull centre, units.
    pub pos: V2<R>,
    /// Height of the hull's bottom above the floor (z = 0), units.
    pub z: R,
    /// Horizontal velocity, ups.
    pub vel: V2<R>,
    /// Vertical velocity, ups.
    pub vz: R,
    /// Standing on the floor.
    pub on_ground: bool,
    /// Ducked (hull 36 units high instead of 72).
    pub ducked: bool,
    /// Time since duck was released while still ducked, seconds (the unduck timer).
    pub unduck_elapsed_s: R,
}

/// Hull height standing, units (docs/physics.md section 2).
pub const HULL_HEIGHT_STANDING_UNITS: f64 = 72.0;
/// Hull height ducked, units.
pub const HULL_HEIGHT_DUCKED_UNITS: f64 = 36.0;

impl<R: Real> PlayerState<R> {
    /// The hull's height by duck state, units: 72 standing, 36 ducked (docs/physics.md section 2).
    #[inline]
    pub fn hull_height_units(&self) -> f64 {
        if self.ducked {
            HULL_HEIGHT_DUCKED_UNITS
        } else {
            HULL_HEIGHT_STANDING_UNITS
        }
    }

    /// Horizontal speed `|v_xy|`, ups.
    #[inline]
    pub fn speed(&self) -> R {
        self.vel.length()
    }

    /// True when every number in the state is finite.
    pub fn is_finite(&self) -> bool {
        self.pos.is_finite()
            && self.vel.is_finite()
            && self.z.is_finite()
            && self.vz.is_finite()
            && self.unduck_elapsed_s.is_finite()
    }
}

impl PlayerState<f64> {
    /// An airborne player at `pos` moving with `vel`.
    pub fn airborne(pos: Vec2, vel: Vec2) -> Self {
        PlayerState {
            pos,
            vel,
            z: 0.0,
            vz: 0.0,
            on_ground: false,
            ducked: false,
            unduck_elapsed_s: 0.0,
        }
    }

    /// A player standing on the floor at `pos` moving with `vel`.
    pub fn on_ground(pos: Vec2, vel: Vec2) -> Self {
        PlayerState {
            on_ground: true,
            ..Self::airborne(pos, vel)
        }
    }
}

/// What the player does in one frame, after the view angles are turned into vectors: the unit forward view
/// vector flattened to the plane (`f = (cos yaw, sin yaw)`), forwardmove `F` and sidemove `S` in ups, and the
/// buttons. The right vector is `s = (sin yaw, -cos yaw)` (docs/physics.md section 1).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Wish<R = f64> {
    /// Unit forward view vector in the plane.
    pub forward: V2<R>,
    /// Forwardmove `F`, ups (negative: backwards).
    pub forwardmove: R,
    /// Sidemove `S`, ups (positive: to the right).
    pub sidemove: R,
    /// Jump held.
    pub jump: bool,
    /// Duck held.
    pub duck: bool,
}

/// A frame's control in planning form: absolute yaw (radians, anticlockwise from +x), movement keys, buttons.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Control {
    /// View yaw `vartheta`, radians.
    pub yaw_rad: f64,
    /// Forwardmove `F`, ups.
    pub forwardmove: f64,
    /// Sidemove `S`, ups (positive: right).
    pub sidemove: f64,
    /// Jump held.
    pub jump: bool,
    /// Duck held.
    pub duck: bool,
}

/// Which side a strafe turns to.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Side {
    /// Anticlockwise (yaw grows).
    Left,
    /// Clockwise.
    Right,
}

impl Side {
    /// +1 for left, -1 for right.
    #[inline]
    pub fn sign(self) -> f64 {
        match self {
            Side::Left => 1.0,
            Side::Right => -1.0,
        }
    }
}

impl Wish<f64> {
    /// The unit wish direction `a_hat = (F f + S s)/sqrt(F^2 + S^2)` (docs/physics.md section 5), or `None` with
    /// both keys zero. The duck crop and the max-speed clamp scale both keys alike, so they leave it alone.
    #[inline]
    pub fn direction(&self) -> Option<Vec2> {
        let len = Real::hypot(self.forwardmove, self.sidemove);
        if len > 0.0 {
            let f = self.forward;
            let right = Vec2::new(f.y, -f.x);
            Some((f * self.forwardmove + right * self.sidemove) * (1.0 / len))
        } else {
            None
        }
    }

    /// The angle `theta` (radians, in `[-pi, pi]`) from `vel` to the wish direction (positive: left), for
    /// reports. Zero when the velocity or the keys are zero.
    pub fn theta_rad(&self, vel: Vec2) -> f64 {
        match self.direction() {
            Some(a_hat) if vel.length_squared() > 0.0 => vel.cross(a_hat).atan2(vel.dot(a_hat)),
            _ => 0.0,
        }
    }
}

impl Control {
    /// The wish vectors of this control (`f` from the yaw).
    #[inline]
    pub fn wish(&self) -> Wish<f64> {
        Wish {
            forward: Vec2::from_angle(self.yaw_rad),
            forwardmove: self.forwardmove,
            sidemove: self.sidemove,
            jump: self.jump,
            duck: self.duck,
        }
    }

    /// The control of a wish given in vector form: the yaw is the angle of the forward view vector, in
    /// `(-pi, pi]` (one `atan2`). [`Control::wish`] gives the vector back to within rounding.
    #[inline]
    pub fn from_wish(w: &Wish<f64>) -> Self {
        Control {
            yaw_rad: w.forward.angle(),
            forwardmove: w.forwardmove,
            sidemove: w.sidemove,
            jump: w.jump,
            duck: w.duck,
        }
    }

    /// The convenience form: strafe at angle `theta_rad` between the velocity `vel` and the wish direction
    /// (positive turns left), holding the keys `forwardmove`, `sidemove`. The yaw is chosen so that
    /// `a_hat = R(theta) v_hat` (docs/physics.md section 5): `yaw = angle(v) + theta + atan2(S, F)`. At zero
    /// velocity the direction is lost and `theta` is taken from `heading_rad` instead.
    pub fn strafe(
        vel: Vec2,
        heading_rad: f64,
        theta_rad: f64,
        forwardmove: f64,
        sidemove: f64,
    ) -> Self {
        let base = if vel.length_squared() > 0.0 {
            vel.angle()
        } else {
            heading_rad
        };
        Control {
            yaw_rad: base + theta_rad + sidemove.atan2(forwardmove),
            forwardmove,
            sidemove,
            jump: false,
            duck: false,
        }
    }

    /// The angle `theta` (radians, in `[-pi, pi]`) between `vel` and this control's wish direction, for
    /// reports. Zero when the velocity or the keys are zero.
    pub fn theta_rad(&self, vel: Vec2) -> f64 {
        self.wish().theta_rad(vel)
    }
}

/// Per-frame constants of the FME (docs/physics.md section 5): `L` and `gamma1 = k_e tau M A`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AccelLaw<R = f64> {
    /// `L`: `M` on the ground, `min(30, M)` in the air, ups.
    pub l: R,
    /// `gamma1 = k_e tau M A`, ups.
    pub gamma1: R,
}

impl AccelLaw<f64> {
    /// The air law for wish speed `m` ups (docs/physics.md section 5): `L = min(30, M)`,
    /// `gamma1 = k_e tau M A_air`.
    pub fn air(vars: &MovementVars, m: f64) -> Self {
        AccelLaw {
            l: m.min(vars.air_speed_cap),
            gamma1: vars.entity_friction * vars.frame_time_s() * m * vars.airaccelerate,
        }
    }

    /// The ground law for wish speed `m` ups: `L = M`, `gamma1 = k_e tau M A`.
    pub fn ground(vars: &MovementVars, m: f64) -> Self {
        AccelLaw {
            l: m,
            gamma1: vars.entity_friction * vars.frame_time_s() * m * vars.accelerate,
        }
    }
}

impl<R: Real> AccelLaw<R> {
    /// `mu = min(gamma1, gamma2)` if `gamma2 = L - lambda(v).a_hat > 0`, else 0 (docs/physics.md section 5), given
    /// `c = lambda(v).a_hat`.
    #[inline]
    pub fn mu(&self, c: R) -> R {
        let gamma2 = self.l - c;
        if gamma2 > R::ZERO {
            self.gamma1.min(gamma2)
        } else {
            R::ZERO
        }
    }
}

/// The frame step for one set of movement variables and effects, with its constants precomputed in `R`.
/// Build it once per scene; [`Stepper::step`] is the hot loop.
#[derive(Clone, Copy, Debug)]
pub struct Stepper<R = f64> {
    effects: Effects,
    game: Game,
    tau: R,
    half_gravity_dv: R,
    jump_speed: R,
    /// [`MovementVars::ground_max_vz_ups`].
    ground_max_vz: R,
    maxspeed: R,
    accelerate: R,
    airaccelerate: R,
    entity_friction: R,
    friction_k: R,
    stopspeed: R,
    maxvelocity: R,
    air_speed_cap: R,
    duck_multiplier: R,
    unduck_time_s: R,
}

impl<R: Real> Stepper<R> {
    /// A stepper for `vars` running only `effects`.
    pub fn new(vars: &MovementVars, effects: Effects) -> Self {
        let tau = vars.frame_time_s();
        let f = R::from_f64;
        Stepper {
            effects,
            game: vars.game,
            tau: f(tau),
            half_gravity_dv: f(vars.gravity * tau * 0.5),
            jump_speed: f(vars.jump_speed_ups()),
            ground_max_vz: f(vars.ground_max_vz_ups()),
            maxspeed: f(vars.maxspeed),
            accelerate: f(vars.accelerate),
            airaccelerate: f(vars.airaccelerate),
            entity_friction: f(vars.entity_friction),
            friction_k: f(vars.friction_k(effects.has(Effect::EdgeFriction))),
            stopspeed: f(vars.stopspeed),
            maxvelocity: f(vars.maxvelocity),
            air_speed_cap: f(vars.air_speed_cap),
            duck_multiplier: f(vars.duck_multiplier),
            unduck_time_s: f(vars.unduck_time_s),
        }
    }

    /// The effects this stepper runs.
    #[inline]
    pub fn effects(&self) -> Effects {
        self.effects
    }

    /// The frame time `tau`, seconds.
    #[inline]
    pub fn frame_time_s(&self) -> R {
        self.tau
    }

    /// One whole frame with a free horizontal move (no walls).
    ///
    /// Always inlined, with [`Stepper::prepare`]: it is the body of every frame loop, and only inlined does
    /// the airborne frame run within a fifth of the same frame written by hand (docs/step-performance.md).
    #[inline(always)]
    pub fn step(&self, s: &mut PlayerState<R>, w: &Wish<R>) {
        if self.effects.is_air_only() {
            self.air_step(s, w);
        } else {
            *s = self.full_step(*s, w);
        }
    }

    /// Every step of the frame, for effect sets beyond the airborne-only one. Kept out of line so that
    /// [`Stepper::step`] stays small enough to inline into a caller's frame loop, and by value so that the
    /// caller's state never escapes into a call: the loop can then hold it in registers.
    fn full_step(&self, mut s: PlayerState<R>, w: &Wish<R>) -> PlayerState<R> {
        self.pre_move(&mut s, w);
        s.pos += s.vel * self.tau;
        self.post_move(&mut s);
        s
    }

    /// The airborne-only frame: steps 4 and 5 of docs/physics.md section 3 and nothing else.
    #[inline(always)]
    fn air_step(&self, s: &mut PlayerState<R>, w: &Wish<R>) {
        if self.effects.has(Effect::MaxVelocity) {
            self.clamp_horizontal(s);
        }
        let (a_hat, m) = self.wish_direction(w, false, false);
        let law = self.air_law(m);
        s.vel = accelerate(s.vel, a_hat, law);
        s.pos += s.vel * self.tau;
    }

    /// Steps 1-4 of docs/physics.md section 3: everything before the position update.
    #[inline]
    pub fn pre_move(&self, s: &mut PlayerState<R>, w: &Wish<R>) {
        if let Some((a_hat, law)) = self.prepare(s, w) {
            s.vel = accelerate(s.vel, a_hat, law);
            if s.on_ground && s.vel.length() < R::from_f64(WALK_STOP_SPEED_UPS) {
                // PM_WalkMove / WalkMove: a crawl below 1 ups stops dead.
                s.vel = V2::ZERO;
            }
        }
    }

    /// Steps 1-3 and the clamp of step 4: duck, gravity, jump, friction. Afterwards `s.vel` is `lambda(v)`.
    /// Returns the wish direction and the acceleration law (docs/physics.md section 5) when an acceleration
    /// effect applies this frame. The law does not depend on the view direction, so a controller can call
    /// this on a copy of the state to choose its angle from `lambda(v)`.
    #[inline(always)]
    pub fn prepare(&self, s: &mut PlayerState<R>, w: &Wish<R>) -> Option<(V2<R>, AccelLaw<R>)> {
        if self.effects.is_air_only() && !s.on_ground {
            // What the steps below come to in the air with none of duck, gravity, jump or friction.
            self.clamp_all(s);
            let (a_hat, m) = self.wish_direction(w, s.ducked, false);
            return self
                .effects
                .has(Effect::AirAccel)
                .then(|| (a_hat, self.air_law(m)));
        }
        let (prepared, out) = self.prepare_all(*s, *w);
        *s = prepared;
        out
    }

    /// [`Stepper::prepare`] for any effect set and state, out of line and by value (see
    /// [`Stepper::full_step`]).
    #[allow(clippy::type_complexity)]
    fn prepare_all(
        &self,
        mut state: PlayerState<R>,
        w: Wish<R>,
    ) -> (PlayerState<R>, Option<(V2<R>, AccelLaw<R>)>) {
        let out = self.prepare_every_effect(&mut state, &w);
        (state, out)
    }

    /// Steps 1-3 and the clamp of step 4 for any effect set and state.
    #[inline]
    fn prepare_every_effect(
        &self,
        s: &mut PlayerState<R>,
        w: &Wish<R>,
    ) -> Option<(V2<R>, AccelLaw<R>)> {
        let fx = self.effects;
        if fx.has(Effect::Duck) {
            self.duck(s, w.duck);
        }
        if fx.has(Effect::Gravity) {
            s.vz -= self.half_gravity_dv;
            self.clamp_all(s);
        }
        if fx.has(Effect::Jump) && w.jump && s.on_ground {
            self.jump(s, w);
        }
        if s.on_ground {
            s.vz = R::ZERO;
            if fx.has(Effect::Friction) {
                s.vel = friction(s.vel, self.tau, self.friction_k, self.stopspeed);
            }
        }
        self.clamp_all(s);
        let (a_hat, m) = self.wish_direction(w, s.ducked, s.on_ground);
        if s.on_ground {
            fx.has(Effect::GroundAccel)
                .then(|| (a_hat, self.ground_law(m)))
        } else {
            fx.has(Effect::AirAccel).then(|| (a_hat, self.air_law(m)))
        }
    }

    /// Steps 5 (vertical part) and 6 of docs/physics.md section 3: the vertical move onto the flat floor, ground
    /// categorisation and the second half of gravity. Call after the horizontal move.
    pub fn post_move(&self, s: &mut PlayerState<R>) {
        if !self.effects.has(Effect::Gravity) {
            return;
        }
        s.z += s.vz * self.tau;
        if s.z < R::ZERO {
            s.z = R::ZERO;
            if s.vz < R::ZERO {
                s.vz = R::ZERO;
            }
        }
        s.on_ground = s.vz <= self.ground_max_vz && s.z <= R::from_f64(GROUND_LAYER_UNITS);
        if s.on_ground {
            s.z = R::ZERO;
            s.vz = R::ZERO;
        } else {
            s.vz -= self.half_gravity_dv;
            self.clamp_all(s);
        }
    }

    /// `L` and `gamma1` in the air for wish speed `m` (docs/physics.md section 5).
    #[inline]
    pub fn air_law(&self, m: R) -> AccelLaw<R> {
        AccelLaw {
            l: m.min(self.air_speed_cap),
            gamma1: self.entity_friction * self.tau * m * self.airaccelerate,
        }
    }

    /// `L` and `gamma1` on the ground for wish speed `m`.
    #[inline]
    pub fn ground_law(&self, m: R) -> AccelLaw<R> {
        AccelLaw {
            l: m,
            gamma1: self.entity_friction * self.tau * m * self.accelerate,
        }
    }

    /// The unit wish direction `a_hat = (F f + S s)/sqrt(F^2+S^2)` and wish speed `M = min(M_m, |(F, S)|)`
    /// (docs/physics.md section 2), with the duck multiplier where it applies. Zero keys give `M = 0`.
    #[inline]
    pub fn wish_direction(&self, w: &Wish<R>, ducked: bool, on_ground: bool) -> (V2<R>, R) {
        let (mut fm, mut sm) = (w.forwardmove, w.sidemove);
        // The duck crop (0.333) and the clamp to the max speed come in each engine's own order: GoldSrc's
        // PM_Duck scales the keys whenever ducked and PM_WalkMove/PM_AirMove clamp the wish speed after;
        // Source's CheckParameters clamps the keys first and HandleDuckingSpeedCrop scales them after, on
        // the ground only. Ducked walking is 450 * 0.333 = 149.85 ups of wish speed in Half-Life, but
        // 150 * 0.333 = 49.95 in Half-Life 2 without the suit.
        let crop = ducked
            && self.effects.has(Effect::Duck)
            && match self.game {
                Game::GoldSrc => true,
                Game::Source => on_ground,
            };
        if self.game == Game::Source {
            let len = fm.hypot(sm);
            if len > self.maxspeed {
                let k = self.maxspeed / len;
                fm = fm * k;
                sm = sm * k;
            }
        }
        if crop {
            fm = fm * self.duck_multiplier;
            sm = sm * self.duck_multiplier;
        }
        let len = fm.hypot(sm);
        if len > R::ZERO {
            let f = w.forward;
            let right = V2::new(f.y, -f.x);
            let a_hat = (f * fm + right * sm) * (R::ONE / len);
            (a_hat, len.min(self.maxspeed))
        } else {
            (w.forward, R::ZERO)
        }
    }

    /// Whether the duck step of the next frame (step 1) leaves the player ducked, with duck `held` or
    /// not: the controllers that must know it before the frame (the Source boost's `p`) ask here rather
    /// than repeat the unduck timer.
    pub fn ducked_after_duck_step(&self, s: &PlayerState<R>, held: bool) -> bool {
        if !self.effects.has(Effect::Duck) {
            return s.ducked;
        }
        let mut next = *s;
        self.duck(&mut next, held);
        next.ducked
    }

    fn duck(&self, s: &mut PlayerState<R>, held: bool) {
        if held {
            s.ducked = true;
            s.unduck_elapsed_s = R::ZERO;
        } else if s.ducked {
            s.unduck_elapsed_s += self.tau;
            if s.unduck_elapsed_s >= self.unduck_time_s - R::from_f64(1e-9) {
                s.ducked = false;
                s.unduck_elapsed_s = R::ZERO;
            }
        }
    }

    /// Step 2: the jump, with the bunnyhop cap (section 10) and the Source jump boost (section 11).
    fn jump(&self, s: &mut PlayerState<R>, w: &Wish<R>) {
        if self.effects.has(Effect::BhopCap) {
            let cap = R::from_f64(BHOP_CAP_FACTOR) * self.maxspeed;
            let speed3 = (s.vel.length_squared() + s.vz * s.vz).sqrt();
            if cap > R::ZERO && speed3 > cap {
                let scale = R::from_f64(BHOP_CAP_RESULT_FACTOR) * self.maxspeed / speed3;
                s.vel = s.vel * scale;
            }
        }
        // GoldSrc sets the jump speed; Source sets it ducked and adds it to the first gravity half-step
        // standing (docs/physics.md section 2).
        s.vz = if self.game == Game::Source && !s.ducked {
            s.vz + self.jump_speed
        } else {
            self.jump_speed
        };
        s.on_ground = false;
        if self.effects.has(Effect::JumpBoost) {
            self.jump_boost(s, w);
        }
    }

    /// The Source jump boost (docs/physics.md section 11); the duck crop applies when the duck effect runs.
    fn jump_boost(&self, s: &mut PlayerState<R>, w: &Wish<R>) {
        let crop = if self.effects.has(Effect::Duck) {
            self.duck_multiplier
        } else {
            R::ONE
        };
        let add = boost_add_from_keys(
            w.forwardmove,
            w.sidemove,
            self.maxspeed,
            s.ducked,
            crop,
            s.vel.length(),
        );
        s.vel += w.forward * add;
    }

    #[inline]
    fn clamp_horizontal(&self, s: &mut PlayerState<R>) {
        let m = self.maxvelocity;
        s.vel.x = s.vel.x.max(-m).min(m);
        s.vel.y = s.vel.y.max(-m).min(m);
    }

    #[inline]
    fn clamp_all(&self, s: &mut PlayerState<R>) {
        if self.effects.has(Effect::MaxVelocity) {
            self.clamp_horizontal(s);
            let m = self.maxvelocity;
            s.vz = s.vz.max(-m).min(m);
        }
    }
}

/// Ground friction `lambda(v)` (docs/physics.md section 4) with `k = sv_friction k_e e_f`, `E = sv_stopspeed`:
/// geometric above `E`, arithmetic below, zero once the drop exceeds the speed. Below 0.1 ups the game
/// leaves the velocity alone (`PM_Friction`: `if (speed < 0.1) return`), and so do we.
#[inline]
pub fn friction<R: Real>(vel: V2<R>, tau: R, k: R, stopspeed: R) -> V2<R> {
    let speed = vel.length();
    if speed < R::from_f64(FRICTION_MIN_SPEED_UPS) {
        return vel;
    }
    let control = if speed < stopspeed { stopspeed } else { speed };
    let drop = control * k * tau;
    let new_speed = (speed - drop).max(R::ZERO);
    vel * (new_speed / speed)
}

/// The FME (docs/physics.md section 5): `v' = lambda(v) + mu a_hat`, `mu = min(gamma1, L - v.a_hat)` when
/// positive, else no change. `vel` is already `lambda(v)`.
#[inline]
pub fn accelerate<R: Real>(vel: V2<R>, a_hat: V2<R>, law: AccelLaw<R>) -> V2<R> {
    let gamma2 = law.l - vel.dot(a_hat);
    if gamma2 <= R::ZERO {
        return vel;
    }
    vel + a_hat * law.gamma1.min(gamma2)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn air() -> (MovementVars, Stepper<f64>) {
        let v = MovementVars::goldsrc(100.0);
        (v, Stepper::new(&v, Effects::AIR_ONLY))
    }

    #[test]
    fn air_fme_adds_gamma1_along_the_wish_direction_below_l() {
        let (_, st) = air();
        // v = 0, yaw 0, forward only: a_hat = +x, gamma1 = 0.01*320*10 = 32 > L = 30, so mu = 30.
        let mut s = PlayerState::airborne(Vec2::ZERO, Vec2::ZERO);
        let w = Control {
            yaw_rad: 0.0,
            forwardmove: 400.0,
            sidemove: 0.0,
            jump: false,
            duck: false,
        }
        .wish();
        st.step(&mut s, &w);
        assert!((s.vel.x - 30.0).abs() < 1e-12 && s.vel.y.abs() < 1e-12);
        assert!((s.pos.x - 0.3).abs() < 1e-12);
        // Now v.a_hat = 30 = L: no more gain straight ahead.
        st.step(&mut s, &w);
        assert!((s.vel.x - 30.0).abs() < 1e-12);
    }

    #[test]
    fn sidemove_right_points_the_wish_direction_clockwise_of_the_view() {
        let (_, st) = air();
        let w = Wish {
            forward: Vec2::new(1.0, 0.0),
            forwardmove: 0.0,
            sidemove: 400.0,
            jump: false,
            duck: false,
        };
        let (a_hat, m) = st.wish_direction(&w, false, false);
        assert!((a_hat.x).abs() < 1e-12 && (a_hat.y + 1.0).abs() < 1e-12);
        assert_eq!(m, 320.0); // min(320, 400)
    }

    #[test]
    fn strafe_control_realises_the_requested_theta() {
        let vel = Vec2::new(300.0, 100.0);
        for &(f, s) in &[(400.0, 0.0), (0.0, 400.0), (400.0, -400.0), (-400.0, 400.0)] {
            for &theta in &[0.3, -1.2, 2.5] {
                let c = Control::strafe(vel, 0.0, theta, f, s);
                assert!((c.theta_rad(vel) - theta).abs() < 1e-12, "{f} {s} {theta}");
                let st: Stepper<f64> =
                    Stepper::new(&MovementVars::goldsrc(100.0), Effects::AIR_ONLY);
                let (a_hat, _) = st.wish_direction(&c.wish(), false, false);
                let expect = vel.normalized().unwrap().rotated(theta);
                assert!((a_hat - expect).length() < 1e-12);
            }
        }
    }

    #[test]
    fn friction_has_three_branches_and_leaves_crawls_alone() {
        let (tau, k, e) = (0.01, 4.0, 100.0);
        // geometric: |v| >= E
        let v = friction(Vec2::new(200.0, 0.0), tau, k, e);
        assert!((v.x - 200.0 * (1.0 - tau * k)).abs() < 1e-12);
        // arithmetic: 0.1 <= |v| < E, drop tau E k = 4
        let v = friction(Vec2::new(50.0, 0.0), tau, k, e);
        assert!((v.x - 46.0).abs() < 1e-12);
        // zero: |v| < tau E k
        let v = friction(Vec2::new(3.0, 0.0), tau, k, e);
        assert_eq!(v, Vec2::ZERO);
        // below 0.1 ups the game returns early
        let v = friction(Vec2::new(0.05, 0.0), tau, k, e);
        assert_eq!(v.x, 0.05);
    }

    #[test]
    fn jump_airtime_matches_the_two_unit_layer_formula() {
        // docs/physics.md section 10: t = (2/g)(60 sqrt 5 + sqrt(18000 - g)) = 0.663 s at g = 800.
        let vars = MovementVars::goldsrc(1000.0);
        let fx = Effects::from_list(&[Effect::Gravity, Effect::Jump]);
        let st: Stepper<f64> = Stepper::new(&vars, fx);
        let mut s = PlayerState::on_ground(Vec2::ZERO, Vec2::ZERO);
        let w = Wish {
            forward: Vec2::new(1.0, 0.0),
            jump: true,
            ..Wish::default()
        };
        st.step(&mut s, &w);
        assert!(!s.on_ground);
        let w = Wish { jump: false, ..w };
        let mut frames = 1;
        while !s.on_ground {
            st.step(&mut s, &w);
            frames += 1;
            assert!(frames < 10_000);
        }
        // The continuous formula gives 0.6633 s. The game's frame lags it: on the jump frame the jump
        // speed replaces the first gravity half-step, so z(n tau) = tau (n v0 - g tau n(n-1)/2), which
        // reaches 2 units 0.66 frames later than the parabola: landing is detected after frame 665.
        let g: f64 = 800.0;
        let t = (2.0 / g) * (60.0 * 5f64.sqrt() + (18000.0 - g).sqrt());
        assert!((t - 0.6633).abs() < 1e-4);
        let v0 = vars.jump_speed_ups();
        let z = |n: f64| 0.001 * (n * v0 - g * 0.001 * n * (n - 1.0) / 2.0);
        let expected = (1..2000)
            .find(|&n| z(n as f64) <= 2.0 && n > 10)
            .unwrap_or(0);
        assert_eq!(frames, expected);
        assert_eq!(frames, 665);
    }

    #[test]
    fn a_source_jump_leaves_the_ground_at_any_tick_rate() {
        // Source's standing jump gives v_z = 160 - g tau / 2 (157 ups at 100 ticks/s), which rises only
        // 1.57 units in the jump frame at 100 ticks/s: inside the 2-unit ground layer. It is off the
        // ground because v_z is above Source's 140 ups; GoldSrc's 180 would have kept it there.
        for fps in [66.666_666_666_666_67, 100.0, 250.0, 1000.0] {
            let vars = MovementVars::source_hl2(fps);
            let fx = Effects::from_list(&[Effect::Gravity, Effect::Jump]);
            let st: Stepper<f64> = Stepper::new(&vars, fx);
            let mut s = PlayerState::on_ground(Vec2::ZERO, Vec2::ZERO);
            let w = Wish {
                forward: Vec2::new(1.0, 0.0),
                jump: true,
                ..Wish::default()
            };
            st.step(&mut s, &w);
            assert!(!s.on_ground, "{fps} ticks/s: z {} vz {}", s.z, s.vz);
        }
    }

    #[test]
    fn bhop_cap_scales_544_to_353_6() {
        let vars = MovementVars::goldsrc(100.0);
        let fx = Effects::from_list(&[Effect::Gravity, Effect::Jump, Effect::BhopCap]);
        let st: Stepper<f64> = Stepper::new(&vars, fx);
        let mut s = PlayerState::on_ground(Vec2::ZERO, Vec2::new(600.0, 0.0));
        let w = Wish {
            forward: Vec2::new(1.0, 0.0),
            jump: true,
            ..Wish::default()
        };
        st.pre_move(&mut s, &w);
        // The cap scales the 3-D velocity, which includes the first gravity half-step (vz = -4 at 100 fps):
        // 1.105 * 320 = 353.6 in 3-D, a hair less horizontally.
        let vz_before: f64 = -800.0 * 0.01 * 0.5;
        let speed3_before = (600.0f64.powi(2) + vz_before * vz_before).sqrt();
        let expected = 600.0 * 353.6 / speed3_before;
        assert!((s.speed() - expected).abs() < 1e-9, "{}", s.speed());
        assert!((s.speed() - 353.6).abs() < 1e-2);
        // Just under 1.7 M = 544 in 3-D nothing happens; 544 horizontally plus vz = -4 is already over.
        let mut s = PlayerState::on_ground(Vec2::ZERO, Vec2::new(543.9, 0.0));
        st.pre_move(&mut s, &w);
        assert_eq!(s.speed(), 543.9);
        let mut s = PlayerState::on_ground(Vec2::ZERO, Vec2::new(544.0, 0.0));
        st.pre_move(&mut s, &w);
        assert!(s.speed() < 354.0);
    }

    #[test]
    fn source_backhop_boost_gives_two_v_minus_cap() {
        // docs/physics.md section 11: ducked, facing backwards, no keys: v -> 2|v| - 1.1 Mx.
        let mut vars = MovementVars::source_hl2(66.666_666_666_666_67);
        vars.maxspeed = 150.0;
        let fx = Effects::from_list(&[
            Effect::Gravity,
            Effect::Jump,
            Effect::JumpBoost,
            Effect::Duck,
        ]);
        let st: Stepper<f64> = Stepper::new(&vars, fx);
        let mut s = PlayerState::on_ground(Vec2::ZERO, Vec2::new(225.0, 0.0));
        s.ducked = true;
        let w = Wish {
            forward: Vec2::new(-1.0, 0.0),
            jump: true,
            duck: true,
            ..Wish::default()
        };
        st.pre_move(&mut s, &w);
        assert!((s.vel.x - 285.0).abs() < 1e-9, "{:?}", s.vel);
    }

    #[test]
    fn duck_crop_and_max_speed_clamp_come_in_each_engines_order() {
        let w = Wish {
            forward: Vec2::new(1.0, 0.0),
            forwardmove: 450.0,
            ..Wish::default()
        };
        let fx = Effects::from_list(&[Effect::Duck, Effect::GroundAccel]);
        // Source: clamp 450 to 150 first, then crop: 49.95.
        let mut hl2 = MovementVars::source_hl2(200.0 / 3.0);
        hl2.maxspeed = 150.0;
        let st: Stepper<f64> = Stepper::new(&hl2, fx);
        assert!((st.wish_direction(&w, true, true).1 - 150.0 * 0.333).abs() < 1e-9);
        // Source in the air: no crop.
        assert!((st.wish_direction(&w, true, false).1 - 150.0).abs() < 1e-9);
        // GoldSrc: crop 400 first (133.2), then clamp to 320: 133.2.
        let hl = MovementVars::goldsrc(100.0);
        let st: Stepper<f64> = Stepper::new(&hl, fx);
        let w1 = Wish {
            forwardmove: 400.0,
            ..w
        };
        assert!((st.wish_direction(&w1, true, true).1 - 400.0 * 0.333).abs() < 1e-9);
        assert!((st.wish_direction(&w1, false, true).1 - 320.0).abs() < 1e-9);
    }

    #[test]
    fn max_velocity_clamps_each_component() {
        let vars = MovementVars::goldsrc(100.0);
        let st: Stepper<f64> = Stepper::new(&vars, Effects::AIR_ONLY.with(Effect::MaxVelocity));
        let mut s = PlayerState::airborne(Vec2::ZERO, Vec2::new(2500.0, -2500.0));
        let w = Wish {
            forward: Vec2::new(1.0, 0.0),
            ..Wish::default()
        };
        st.step(&mut s, &w);
        assert_eq!(s.vel, Vec2::new(2000.0, -2000.0));
        assert!((s.speed() - 2000.0 * 2f64.sqrt()).abs() < 1e-9);
    }
}
