//! The frame in planning variables (docs/physics.md sections 5 and 6). A frame is described by its side
//! `sigma` (wish direction left, +1, or right, -1, of the velocity) and `c = v . a_hat`, the velocity's
//! projection on the wish direction; `mu` follows from `c` by the law `mu = min(gamma1, L - c)` (0 when
//! `L <= c`). The state is the position, the speed `V` and the heading `psi`:
//!
//! ```text
//! forward = V + mu c / V,   lateral = mu sqrt(V^2 - c^2) / V
//! V'   = sqrt(forward^2 + lateral^2)         (= sqrt(V^2 + 2 mu c + mu^2), the scalar FME)
//! psi' = psi + sigma atan2(lateral, forward)
//! p'   = p + tau V' (cos psi', sin psi')
//! ```
//!
//! For `sigma = +-1` this is the game's airborne frame exactly. Relaxing `sigma` to `[-1, 1]` is the limit
//! of fast left/right alternation: the speed grows as in every frame, the heading turns by the fraction
//! `sigma` of a full turn. Raw yaw is a badly conditioned variable (the speed gain changes with slope
//! about `|v|` per radian near the best angle); `(sigma, c)` are not.

use crate::physics::curvature::air_law;
use crate::physics::engine_exact::ANGLEMOD_STEP_RAD;
use crate::physics::vectorial::{VECTORIAL_MAX_WISH_SPEED_UPS, VECTORIAL_RESOLUTION_RAD};
use crate::physics::{AccelLaw, Control, MovementVars, Vec2};
use std::ops::{Add, Div, Mul, Sub};

/// The change of `c = V cos theta` that one anglemod step of the strafe angle makes near 90 degrees, at
/// speed `v`, ups: `V q` (`q` = [`ANGLEMOD_STEP_RAD`]), the scale of a hair either side of a frame at 90
/// degrees, whichever way the replay sets its angle ([`FrameLaw::angle_step_ups`] is the replay's step).
pub(super) fn anglemod_step_ups(v: f64) -> f64 {
    v * ANGLEMOD_STEP_RAD
}

/// How a replayed plan sets each frame's wish direction in the game, and so how finely.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum AngleControl {
    /// The yaw alone, on anglemod steps, with the side key held: a step `q` of 9.6e-5 rad.
    Yaw,
    /// The yaw on an anglemod step with whole forwardmove and sidemove
    /// ([`crate::physics::vectorial`]): within [`VECTORIAL_RESOLUTION_RAD`] of any angle. Where the
    /// scene turns it on (`vectorial-compensation = true`), the side key's speed reaches the server's
    /// maximum speed (the pairs are longer than both, so the wish speed is the same) and that maximum is
    /// below [`VECTORIAL_MAX_WISH_SPEED_UPS`].
    Vectorial,
}

impl AngleControl {
    /// The angle control of movement variables `vars` ([`AngleControl::Vectorial`] where open).
    pub fn of(vars: &MovementVars) -> Self {
        let open =
            vars.side_key_speed >= vars.maxspeed && vars.maxspeed < VECTORIAL_MAX_WISH_SPEED_UPS;
        if vars.vectorial_compensation && open {
            AngleControl::Vectorial
        } else {
            AngleControl::Yaw
        }
    }

    /// The step in which the game can set the strafe angle, radians: twice the largest error of the
    /// realised angle, so that half a step is that error (one anglemod step; for vectorial
    /// compensation twice its resolution).
    pub fn step_rad(self) -> f64 {
        match self {
            AngleControl::Yaw => ANGLEMOD_STEP_RAD,
            AngleControl::Vectorial => 2.0 * VECTORIAL_RESOLUTION_RAD,
        }
    }
}

/// The strongest braking a plan uses, as `-cos theta` of the strafe angle (see [`FrameLaw::c_min`]).
const BRAKE_COS_LIMIT: f64 = 0.95;

/// Where the zigzag's margin is more than this share of the braking swing's, the two are one (at 100 fps
/// with air acceleration 10, `L = 30` and `gamma1 = 32`: they differ by 6%) and the planning margin is
/// the wider ([`FrameLaw::planning_margin`]).
const ZIGZAG_MARGIN_MAX_SHARE: f64 = 0.9;

/// The constants of one airborne frame: frame time and the acceleration law.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FrameLaw {
    /// Frame time `tau`, seconds.
    pub tau_s: f64,
    /// `L` and `gamma1`.
    pub law: AccelLaw,
    /// Sidemove held, ups (sets `M`; the yaw is turned by `atan2(S, F)`).
    pub side_key_speed: f64,
    /// How the replay sets the wish direction, and so the step of `c` the plan keeps clear of the kink by.
    pub angle_control: AngleControl,
}

impl FrameLaw {
    /// The airborne frame law of movement variables `vars` (docs/physics.md section 5).
    pub fn of(vars: &MovementVars) -> Self {
        FrameLaw {
            tau_s: vars.frame_time_s(),
            law: air_law(vars),
            side_key_speed: vars.side_key_speed,
            angle_control: AngleControl::of(vars),
        }
    }

    /// The change of `c = V cos theta` that one step of the strafe angle ([`AngleControl::step_rad`])
    /// makes near 90 degrees, at speed `v`, ups: `V q`. The replay cannot tell apart two plans of a frame
    /// closer than this.
    pub fn angle_step_ups(&self, v: f64) -> f64 {
        v * self.angle_control.step_rad()
    }

    /// The wall margin a relaxed line is planned at, units: `final_margin` and the sideways room the
    /// rounding of its sides needs. Alternating sides at full acceleration (`mu = min(L, gamma1)`,
    /// docs/physics.md section 6) swing the path `tau mu / 2` either side of the relaxed one, so the
    /// zigzag's margin is `final_margin + tau min(L, gamma1)`. A braking frame can push further,
    /// `tau max(L, gamma1)`; where the two are within [`ZIGZAG_MARGIN_MAX_SHARE`] of each other that
    /// wider one is kept. Where braking's is far wider (high air acceleration, low frame rates: 89 units
    /// at 60 fps with air acceleration 1000, against the zigzag's 0.5, more room than most corridors
    /// have), the plans came from lines far off the walls and were up to half a frame behind what a
    /// line at the zigzag's margin gives, and refining a tighter line from them did not win that back
    /// (docs/design.md, "The planning margin"). A rounding that brakes against a wall is left to the
    /// polish, which widens the line where a rounding leaves the walls.
    pub fn planning_margin(&self, final_margin: f64) -> f64 {
        let AccelLaw { l, gamma1 } = self.law;
        let braking = final_margin + self.tau_s * l.max(gamma1);
        let zigzag = final_margin + self.tau_s * l.min(gamma1);
        if zigzag <= ZIGZAG_MARGIN_MAX_SHARE * braking {
            zigzag
        } else {
            braking
        }
    }

    /// The `c` of maximum acceleration at speed `v` (docs/physics.md section 6): `min(L - gamma1, V)` in case 1,
    /// 0 in case 2. Larger `c` gains less speed and turns less, so it is the upper bound of `c`.
    pub fn c_max(&self, v: f64) -> f64 {
        let AccelLaw { l, gamma1 } = self.law;
        if gamma1 <= l {
            (l - gamma1).min(v)
        } else {
            0.0
        }
    }

    /// The largest `c` a plan uses at speed `v`, ups: [`FrameLaw::c_max`], less half a step of the strafe
    /// angle (`V q / 2`, `q` = [`AngleControl::step_rad`]: an anglemod step, `2 pi / 65536`, on the yaw
    /// alone, docs/physics.md sections 1 and 6) in case 1. There `c_max` is the law's kink, and the replay's
    /// quantised wish direction puts the real `c` up to half a step either side of the planned one: above
    /// the kink `mu = L - c` drops below `gamma1`, below it `c` is smaller, and either way every frame
    /// gains less than a plan on the kink. Over thousands of frames (1000 fps) that loss is about a frame,
    /// and a plan along a wall at its margin cannot be replayed. Half a step under the kink, the replay
    /// can follow the plan. In case 2 `c_max = 0` is not at the kink and the quantisation error is
    /// symmetric: no guard.
    pub fn c_plan_max(&self, v: f64) -> f64 {
        let AccelLaw { l, gamma1 } = self.law;
        let c = self.c_max(v);
        if gamma1 <= l && c >= self.kink() {
            c - 0.5 * self.angle_step_ups(v)
        } else {
            c
        }
    }

    /// The largest `c` a plan with exact sides uses at speed `v`, ups. With its side fixed, a frame turns
    /// less than the maximum-acceleration turn only with a larger `c` (and gains less speed): one such
    /// frame shifts the phase of the alternating sides where they meet a turn, which the relaxed problem
    /// (sides in between) needs no frame for. The piece `mu = L - c` runs on from `c_max` to `L`, where the
    /// frame coasts; the plan stops at `min(L, 0.95 V)`, as far from `theta = 0` as [`FrameLaw::c_min`] is
    /// from 180 degrees. In case 1 the range passes the kink, which a plan then keeps clear of
    /// ([`FrameLaw::under_the_guard`]).
    pub fn c_exact_max(&self, v: f64) -> f64 {
        self.law.l.min(BRAKE_COS_LIMIT * v).max(self.c_max(v))
    }

    /// The anglemod guard's band around the kink at speed `v`, ups: half a step of the strafe angle either
    /// side of it (`V q / 2`, [`FrameLaw::angle_step_ups`]), where the replay's quantised wish direction can
    /// put a frame on either piece of the law. In case 1 the kink is the maximum-acceleration `c` and the
    /// band's bottom is [`FrameLaw::c_plan_max`]. In case 2 the kink is the frame of the largest turn (`mu` reaches `gamma1` there, at the least braking), a
    /// frame a turning plan plays over and over: on the kink, the replay's yaw puts each such frame either
    /// below it, gaining less speed at the slope `gamma1 / V` (docs/physics.md section 6), or above it,
    /// turning less, and the plan's speed drifts away a few ten-thousandths of an ups a frame, tenths of a
    /// unit over a turning run. `None` where no `c` of the plan reaches the kink.
    pub fn guard_band(&self, v: f64) -> Option<(f64, f64)> {
        let (kink, half) = (self.kink(), 0.5 * self.angle_step_ups(v));
        (kink <= v && kink - half > self.c_min(v)).then_some((kink - half, kink + half))
    }

    /// `c` at speed `v` kept out of the anglemod guard's band ([`FrameLaw::guard_band`]): a `c` inside it
    /// goes down to its lower edge (in case 1 `c_plan_max`, the frame then gains what the guarded plan
    /// counts on; in case 2 the frame turns as on the kink and gains a little less); every other `c` is
    /// kept.
    pub fn under_the_guard(&self, c: f64, v: f64) -> f64 {
        match self.guard_band(v) {
            Some((guard, top)) if c > guard && c < top => guard,
            _ => c,
        }
    }

    /// Whether the law is in its first case (`gamma1 <= L`), where the maximum-acceleration `c` is the
    /// kink and [`FrameLaw::c_plan_max`] keeps plans half a step of the strafe angle under it.
    pub fn has_kink_guard(&self) -> bool {
        self.law.gamma1 <= self.law.l
    }

    /// The lowest `c` a plan uses at speed `v`, ups: braking down to `cos theta = -0.95`. Near
    /// `theta = 180` degrees the lateral push `mu sqrt(V^2 - c^2) / V` has an unbounded derivative in `c`,
    /// so a linearised frame there predicts nothing of what a small change of `c` does.
    pub fn c_min(&self, v: f64) -> f64 {
        -BRAKE_COS_LIMIT * v
    }

    /// `L - gamma1`, where the law's two pieces meet.
    pub fn kink(&self) -> f64 {
        self.law.l - self.law.gamma1
    }
}

/// The planning state after a frame: position (units), speed (ups), heading (radians).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ModelState {
    /// Hull centre.
    pub pos: Vec2,
    /// Speed `V`.
    pub speed: f64,
    /// Heading `psi` of the velocity.
    pub heading: f64,
}

impl ModelState {
    /// The velocity vector.
    pub fn velocity(&self) -> Vec2 {
        Vec2::from_angle(self.heading) * self.speed
    }
}

/// One frame's planning control.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FrameControl {
    /// Side, `+1` left, `-1` right; relaxed values in between.
    pub sigma: f64,
    /// `c = v . a_hat`, ups.
    pub c: f64,
}

/// Derivatives of one frame: `A = d x' / d x` and `B = d x' / d u` with `x = (px, py, V, psi)`,
/// `u = (sigma, c)`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FrameJacobian {
    /// `d x' / d x`, row-major.
    pub a: [[f64; 4]; 4],
    /// `d x' / d u`, row-major.
    pub b: [[f64; 2]; 4],
}

impl FrameJacobian {
    /// The state change after the frame to first order, `dx' = A dx + B du`, from the state change `dx`
    /// before it and the control change `du = (d sigma, d c)`.
    pub fn state_change(&self, dx: &[f64; 4], du: &[f64; 2]) -> [f64; 4] {
        std::array::from_fn(|i| {
            (0..4).map(|j| self.a[i][j] * dx[j]).sum::<f64>()
                + (0..2).map(|j| self.b[i][j] * du[j]).sum::<f64>()
        })
    }
}

/// Arithmetic of forward-mode automatic differentiation over the frame's four inputs `(V, psi, c, sigma)`:
/// the frame is written once over this trait and evaluated with [`Dual`] (first derivatives) or
/// [`Dual2`] (first and second).
trait Ad:
    Copy + Add<Output = Self> + Sub<Output = Self> + Mul<Output = Self> + Div<Output = Self>
{
    fn constant(v: f64) -> Self;
    fn var(v: f64, i: usize) -> Self;
    fn value(&self) -> f64;
    fn sqrt(self) -> Self;
    fn sin(self) -> Self;
    fn cos(self) -> Self;
    fn atan2(self, x: Self) -> Self;
}

/// A number with its derivatives with respect to `(V, psi, c, sigma)`.
#[derive(Clone, Copy, Debug)]
struct Dual {
    v: f64,
    d: [f64; 4],
}

impl Dual {
    fn map(self, v: f64, dv: f64) -> Dual {
        Dual {
            v,
            d: self.d.map(|x| x * dv),
        }
    }
}

impl Ad for Dual {
    fn constant(v: f64) -> Dual {
        Dual { v, d: [0.0; 4] }
    }
    fn var(v: f64, i: usize) -> Dual {
        let mut d = [0.0; 4];
        d[i] = 1.0;
        Dual { v, d }
    }
    fn value(&self) -> f64 {
        self.v
    }
    fn sqrt(self) -> Dual {
        let r = self.v.sqrt();
        self.map(r, if r > 0.0 { 0.5 / r } else { 0.0 })
    }
    fn sin(self) -> Dual {
        self.map(self.v.sin(), self.v.cos())
    }
    fn cos(self) -> Dual {
        self.map(self.v.cos(), -self.v.sin())
    }
    fn atan2(self, x: Dual) -> Dual {
        // d atan2(y, x) = (x dy - y dx) / (x^2 + y^2)
        let r2 = self.v * self.v + x.v * x.v;
        let mut d = [0.0; 4];
        if r2 > 0.0 {
            for (i, di) in d.iter_mut().enumerate() {
                *di = (x.v * self.d[i] - self.v * x.d[i]) / r2;
            }
        }
        Dual {
            v: self.v.atan2(x.v),
            d,
        }
    }
}

impl Add for Dual {
    type Output = Dual;
    fn add(self, o: Dual) -> Dual {
        let mut d = self.d;
        for (a, b) in d.iter_mut().zip(o.d) {
            *a += b;
        }
        Dual { v: self.v + o.v, d }
    }
}

impl Sub for Dual {
    type Output = Dual;
    fn sub(self, o: Dual) -> Dual {
        let mut d = self.d;
        for (a, b) in d.iter_mut().zip(o.d) {
            *a -= b;
        }
        Dual { v: self.v - o.v, d }
    }
}

impl Mul for Dual {
    type Output = Dual;
    fn mul(self, o: Dual) -> Dual {
        let mut d = [0.0; 4];
        for (i, di) in d.iter_mut().enumerate() {
            *di = self.d[i] * o.v + self.v * o.d[i];
        }
        Dual { v: self.v * o.v, d }
    }
}

impl Div for Dual {
    type Output = Dual;
    fn div(self, o: Dual) -> Dual {
        let mut d = [0.0; 4];
        for (i, di) in d.iter_mut().enumerate() {
            *di = (self.d[i] * o.v - self.v * o.d[i]) / (o.v * o.v);
        }
        Dual { v: self.v / o.v, d }
    }
}

/// A number with its gradient and Hessian with respect to `(V, psi, c, sigma)`: second-order forward
/// mode, for the curvature of the frame ([`frame_hessian`]).
#[derive(Clone, Copy, Debug)]
struct Dual2 {
    v: f64,
    d: [f64; 4],
    h: [[f64; 4]; 4],
}

impl Dual2 {
    /// `f(self)` given `f`, `f'` and `f''` at `self.v`: `d = f' d`, `h = f' h + f'' d d^T`.
    fn map(self, f: f64, f1: f64, f2: f64) -> Dual2 {
        let mut h = [[0.0; 4]; 4];
        for (i, row) in h.iter_mut().enumerate() {
            for (j, hij) in row.iter_mut().enumerate() {
                *hij = f1 * self.h[i][j] + f2 * self.d[i] * self.d[j];
            }
        }
        Dual2 {
            v: f,
            d: self.d.map(|x| x * f1),
            h,
        }
    }

    fn recip(self) -> Dual2 {
        let r = 1.0 / self.v;
        self.map(r, -r * r, 2.0 * r * r * r)
    }
}

impl Ad for Dual2 {
    fn constant(v: f64) -> Dual2 {
        Dual2 {
            v,
            d: [0.0; 4],
            h: [[0.0; 4]; 4],
        }
    }
    fn var(v: f64, i: usize) -> Dual2 {
        let mut d = [0.0; 4];
        d[i] = 1.0;
        Dual2 {
            v,
            d,
            h: [[0.0; 4]; 4],
        }
    }
    fn value(&self) -> f64 {
        self.v
    }
    fn sqrt(self) -> Dual2 {
        let r = self.v.sqrt();
        if r > 0.0 {
            self.map(r, 0.5 / r, -0.25 / (r * self.v))
        } else {
            Dual2::constant(r)
        }
    }
    fn sin(self) -> Dual2 {
        let (s, c) = self.v.sin_cos();
        self.map(s, c, -s)
    }
    fn cos(self) -> Dual2 {
        let (s, c) = self.v.sin_cos();
        self.map(c, -s, -c)
    }
    fn atan2(self, x: Dual2) -> Dual2 {
        // theta = atan2(y, x): theta_y = x / r^2, theta_x = -y / r^2, theta_yy = -2xy / r^4,
        // theta_xx = 2xy / r^4, theta_xy = (y^2 - x^2) / r^4.
        let y = self;
        let r2 = y.v * y.v + x.v * x.v;
        if r2 <= 0.0 {
            return Dual2::constant(y.v.atan2(x.v));
        }
        let r4 = r2 * r2;
        let (ty, tx) = (x.v / r2, -y.v / r2);
        let (tyy, txx, txy) = (
            -2.0 * x.v * y.v / r4,
            2.0 * x.v * y.v / r4,
            (y.v * y.v - x.v * x.v) / r4,
        );
        let d = std::array::from_fn(|i| ty * y.d[i] + tx * x.d[i]);
        let h = std::array::from_fn(|i| {
            std::array::from_fn(|j| {
                ty * y.h[i][j]
                    + tx * x.h[i][j]
                    + tyy * y.d[i] * y.d[j]
                    + txx * x.d[i] * x.d[j]
                    + txy * (x.d[i] * y.d[j] + y.d[i] * x.d[j])
            })
        });
        Dual2 {
            v: y.v.atan2(x.v),
            d,
            h,
        }
    }
}

impl Add for Dual2 {
    type Output = Dual2;
    fn add(self, o: Dual2) -> Dual2 {
        let mut r = self;
        r.v += o.v;
        for i in 0..4 {
            r.d[i] += o.d[i];
            for j in 0..4 {
                r.h[i][j] += o.h[i][j];
            }
        }
        r
    }
}

impl Sub for Dual2 {
    type Output = Dual2;
    fn sub(self, o: Dual2) -> Dual2 {
        let mut r = self;
        r.v -= o.v;
        for i in 0..4 {
            r.d[i] -= o.d[i];
            for j in 0..4 {
                r.h[i][j] -= o.h[i][j];
            }
        }
        r
    }
}

impl Mul for Dual2 {
    type Output = Dual2;
    // The product rule to second order: (ab)'' = a'' b + a b'' + a' b'^T + b' a'^T.
    #[allow(clippy::suspicious_arithmetic_impl)]
    fn mul(self, o: Dual2) -> Dual2 {
        let d = std::array::from_fn(|i| self.d[i] * o.v + self.v * o.d[i]);
        let h = std::array::from_fn(|i| {
            std::array::from_fn(|j| {
                self.h[i][j] * o.v + self.v * o.h[i][j] + self.d[i] * o.d[j] + o.d[i] * self.d[j]
            })
        });
        Dual2 {
            v: self.v * o.v,
            d,
            h,
        }
    }
}

impl Div for Dual2 {
    type Output = Dual2;
    // a / b = a (1 / b): the product rule and the reciprocal's second derivative.
    #[allow(clippy::suspicious_arithmetic_impl)]
    fn div(self, o: Dual2) -> Dual2 {
        self * o.recip()
    }
}

/// Smallest `V^2 - c^2` used under the square root (keeps `sin theta` real at `c = V`).
const MIN_SIN_SQ_UPS2: f64 = 1e-18;

/// The outputs `(dx, dy, V', psi')` of `frames` frames played with the same control, over any [`Ad`]
/// number type, inputs `(V, psi, c, sigma)` as variables 0..3 (one frame: `frames = 1`).
fn frame_outputs<T: Ad>(x: &ModelState, u: FrameControl, fl: &FrameLaw, frames: u32) -> [T; 4] {
    let mut v = T::var(x.speed, 0);
    let mut psi = T::var(x.heading, 1);
    let c = T::var(u.c, 2);
    let sigma = T::var(u.sigma, 3);
    let (mut dx, mut dy) = (T::constant(0.0), T::constant(0.0));
    for _ in 0..frames.max(1) {
        let [fx, fy, v_new, psi_new] = one_frame(v, psi, c, sigma, fl);
        dx = dx + fx;
        dy = dy + fy;
        v = v_new;
        psi = psi_new;
    }
    [dx, dy, v, psi]
}

/// One frame over [`Ad`] numbers: `(dx, dy, V', psi')` from `(V, psi)` and the control `(c, sigma)`.
fn one_frame<T: Ad>(v: T, psi: T, c: T, sigma: T, fl: &FrameLaw) -> [T; 4] {
    let AccelLaw { l, gamma1 } = fl.law;
    // `c = V cos theta` is at most the speed either way. A knot plays one `c` over frames whose speed
    // changes, so a braking knot's later frames can be asked for `c < -V`: such a frame brakes straight
    // back (`c = -V`). Taken as it is, `mu c / V` would push harder than `mu` and the frame would gain
    // speed from nothing.
    let c = if c.value() < -v.value() {
        T::constant(0.0) - v
    } else if c.value() > v.value() {
        v
    } else {
        c
    };
    // mu = min(gamma1, L - c) when L - c > 0, else 0 (docs/physics.md section 5); the piece is fixed by value.
    let gamma2 = T::constant(l) - c;
    let mu = if gamma2.value() <= 0.0 {
        T::constant(0.0)
    } else if gamma1 <= gamma2.value() {
        T::constant(gamma1)
    } else {
        gamma2
    };
    let sin_sq = v * v - c * c;
    let sin_sq = if sin_sq.value() > MIN_SIN_SQ_UPS2 {
        sin_sq
    } else {
        T::constant(MIN_SIN_SQ_UPS2)
    };
    let forward = v + mu * c / v;
    let lateral = mu * sin_sq.sqrt() / v;
    let v_new = (forward * forward + lateral * lateral).sqrt();
    let psi_new = psi + sigma * lateral.atan2(forward);
    let tau = T::constant(fl.tau_s);
    let dx = tau * v_new * psi_new.cos();
    let dy = tau * v_new * psi_new.sin();
    [dx, dy, v_new, psi_new]
}

/// One frame in planning variables, with its Jacobian when `jacobian` is set.
pub fn frame(
    x: &ModelState,
    u: FrameControl,
    fl: &FrameLaw,
    jacobian: bool,
) -> (ModelState, Option<FrameJacobian>) {
    knot(x, u, fl, 1, jacobian)
}

/// A knot: `frames` frames played with the same control, as one step with the frame's interface (state
/// in and out, Jacobian in the same four inputs). The coarse stage of the search plans over knots.
pub fn knot(
    x: &ModelState,
    u: FrameControl,
    fl: &FrameLaw,
    frames: u32,
    jacobian: bool,
) -> (ModelState, Option<FrameJacobian>) {
    let rows: [Dual; 4] = frame_outputs(x, u, fl, frames);
    let [dx, dy, v_new, psi_new] = rows;
    let next = ModelState {
        pos: Vec2::new(x.pos.x + dx.v, x.pos.y + dy.v),
        speed: v_new.v,
        heading: psi_new.v,
    };
    let jac = jacobian.then(|| {
        let mut a = [[0.0; 4]; 4];
        let mut b = [[0.0; 2]; 4];
        for (r, out) in rows.iter().enumerate() {
            a[r][2] = out.d[0];
            a[r][3] = out.d[1];
            b[r][0] = out.d[3];
            b[r][1] = out.d[2];
        }
        a[0][0] = 1.0;
        a[1][1] = 1.0;
        FrameJacobian { a, b }
    });
    (next, jac)
}

/// Second derivatives of one frame: for each output `(px', py', V', psi')`, its Hessian with respect to
/// the frame's inputs in the order `(V, psi, sigma, c)` (the position enters linearly, so its rows and
/// columns are zero and left out). Same piece of the law as [`frame`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FrameHessian {
    /// `h[output][i][j]`, symmetric in `i, j`.
    pub h: [[[f64; 4]; 4]; 4],
}

/// Input order of [`FrameHessian`]: `(V, psi, sigma, c)`, from the automatic-differentiation order
/// `(V, psi, c, sigma)`.
const HESSIAN_ORDER: [usize; 4] = [0, 1, 3, 2];

/// The frame's [`FrameHessian`] at `(x, u)`.
pub fn frame_hessian(x: &ModelState, u: FrameControl, fl: &FrameLaw) -> FrameHessian {
    knot_hessian(x, u, fl, 1)
}

/// The [`FrameHessian`] of a [`knot`] of `frames` frames.
pub fn knot_hessian(x: &ModelState, u: FrameControl, fl: &FrameLaw, frames: u32) -> FrameHessian {
    let rows: [Dual2; 4] = frame_outputs(x, u, fl, frames);
    let mut h = [[[0.0; 4]; 4]; 4];
    for (r, out) in rows.iter().enumerate() {
        for (i, &ai) in HESSIAN_ORDER.iter().enumerate() {
            for (j, &aj) in HESSIAN_ORDER.iter().enumerate() {
                h[r][i][j] = out.h[ai][aj];
            }
        }
    }
    FrameHessian { h }
}

/// The states after each frame of `controls` from `start` (the start itself not included).
pub fn rollout(start: &ModelState, controls: &[FrameControl], fl: &FrameLaw) -> Vec<ModelState> {
    rollout_knots(start, controls, fl, 1)
}

/// The states after each [`knot`] of `frames` frames of `controls` from `start`.
pub fn rollout_knots(
    start: &ModelState,
    controls: &[FrameControl],
    fl: &FrameLaw,
    frames: u32,
) -> Vec<ModelState> {
    let mut out = Vec::with_capacity(controls.len());
    let mut x = *start;
    for &u in controls {
        x = knot(&x, u, fl, frames, false).0;
        out.push(x);
    }
    out
}

/// Knots of `frames_per_knot` frames, each the mean of its frames' `controls` (the last knot's of the
/// frames left).
pub fn knots_averaged(controls: &[FrameControl], frames_per_knot: usize) -> Vec<FrameControl> {
    controls
        .chunks(frames_per_knot.max(1))
        .map(|chunk| {
            let k = chunk.len() as f64;
            FrameControl {
                sigma: chunk.iter().map(|u| u.sigma).sum::<f64>() / k,
                c: chunk.iter().map(|u| u.c).sum::<f64>() / k,
            }
        })
        .collect()
}

/// Bisection steps of a knot's `c` ([`knots_following`]): the range, under twice the speed wide, down
/// to under a millionth of an ups.
const KNOT_FIT_BISECTIONS: usize = 40;

/// How far ahead a knot following a run takes back its lateral offset from the run, in knots' travel
/// ([`knots_following`]).
const KNOT_FIT_REACH_KNOTS: f64 = 2.0;

/// Knots of `frames_per_knot` frames that follow the run of `controls` from `start` (the coarse stage's
/// start from a frame-by-frame run), `c` kept within `c_min` and `c_top(V)`. Each knot's `c` brings the
/// speed to the run's at the knot's end: the speed does not depend on the side, and grows with `c` up
/// to the maximum-acceleration `c` (`V'^2 = V^2 + 2 mu c + mu^2`; in the law's second case
/// `V^2 + L^2 - c^2` above `L - gamma1`), so a bisection finds it. Its side turns the heading to the run's
/// there: a knot's turn is its side times the turn at `sigma = 1` (`psi' = psi + sigma atan2(lateral,
/// forward)`, neither depending on the side), plus the turn that takes the knot's lateral offset from
/// the run back over [`KNOT_FIT_REACH_KNOTS`] knots' travel. Averaging each knot's frames' controls instead
/// does not follow the run: a frame's turn is not linear in its `c`, so sides alternating at different
/// `c` turn on average, and the averaged run drifts off its line into the walls.
pub fn knots_following(
    start: &ModelState,
    controls: &[FrameControl],
    fl: &FrameLaw,
    frames_per_knot: usize,
    c_top: impl Fn(f64) -> f64,
) -> Vec<FrameControl> {
    let per = frames_per_knot.max(1);
    let run = rollout(start, controls, fl);
    let mut here = *start;
    let mut knots = Vec::with_capacity(controls.len().div_ceil(per));
    // Every knot plays `per` frames (as the coarse stage plays them); the last aims at the run's end.
    let frames = u32::try_from(per).unwrap_or(u32::MAX);
    for (j, chunk) in controls.chunks(per).enumerate() {
        let first = j * per;
        let target = run[first + chunk.len() - 1];
        let c = knot_c_for_speed(&here, fl, frames, target.speed, c_top(here.speed));
        // The run where this knot starts, and this knot's offset from it, positive to the left.
        let on_run = if first == 0 { *start } else { run[first - 1] };
        let offset = Vec2::from_angle(on_run.heading).cross(on_run.pos - here.pos);
        let reach_units = KNOT_FIT_REACH_KNOTS * per as f64 * fl.tau_s * here.speed.max(1.0);
        let wanted = target.heading + (offset / reach_units).atan();
        let sigma = knot_side_for_turn(&here, c, fl, frames, wrapped_rad(wanted - here.heading));
        let u = FrameControl { sigma, c };
        here = knot(&here, u, fl, frames, false).0;
        knots.push(u);
    }
    knots
}

/// The `c` in `[c_min(V), c_top]` of a knot of `frames` frames from `x` that ends nearest to
/// `target_speed` (ups): the speed at the knot's end grows with `c` (see [`knots_following`]).
fn knot_c_for_speed(
    x: &ModelState,
    fl: &FrameLaw,
    frames: u32,
    target_speed: f64,
    c_top: f64,
) -> f64 {
    let speed_at = |c: f64| {
        knot(x, FrameControl { sigma: 0.0, c }, fl, frames, false)
            .0
            .speed
    };
    // The braking limit holds at every frame of the knot, so at its end speed, the lowest: the least `c`
    // at or above `c_min` of the speed it ends at (that speed grows with `c`, so `c - c_min(V_end)` does).
    let within_limit = |c: f64| c >= fl.c_min(speed_at(c));
    let mut lo = fl.c_min(x.speed).min(c_top);
    if !within_limit(lo) {
        lo = bracket(lo, c_top, within_limit).1;
    }
    if speed_at(c_top) <= target_speed {
        return c_top;
    }
    if speed_at(lo) >= target_speed {
        return lo;
    }
    let (lo, hi) = bracket(lo, c_top, |c| speed_at(c) >= target_speed);
    0.5 * (lo + hi)
}

/// Where `holds` (false at `lo`, true at `hi`, and once true for a value, true for every larger one)
/// turns true, bracketed by bisection ([`KNOT_FIT_BISECTIONS`] halvings): the last value found false and
/// the first found true.
fn bracket(mut lo: f64, mut hi: f64, holds: impl Fn(f64) -> bool) -> (f64, f64) {
    for _ in 0..KNOT_FIT_BISECTIONS {
        let mid = 0.5 * (lo + hi);
        if holds(mid) {
            hi = mid;
        } else {
            lo = mid;
        }
    }
    (lo, hi)
}

/// The side in `[-1, 1]` of a knot of `frames` frames from `x` at `c` that turns the heading by
/// `turn_rad` (as near as the full turn allows): the turn is the side times the turn at `sigma = 1`.
fn knot_side_for_turn(x: &ModelState, c: f64, fl: &FrameLaw, frames: u32, turn_rad: f64) -> f64 {
    let full = knot(x, FrameControl { sigma: 1.0, c }, fl, frames, false)
        .0
        .heading
        - x.heading;
    if full.abs() > f64::EPSILON {
        (turn_rad / full).clamp(-1.0, 1.0)
    } else {
        0.0
    }
}

/// `angle_rad` wrapped to `[-pi, pi)`.
fn wrapped_rad(angle_rad: f64) -> f64 {
    use std::f64::consts::{PI, TAU};
    (angle_rad + PI).rem_euclid(TAU) - PI
}

/// The game control that realises `(sigma = +-1, c)` from a velocity `vel`: the strafe angle
/// `theta = sigma acos(c / |v|)` with full sidemove (docs/physics.md section 5).
pub fn control_for(vel: Vec2, u: FrameControl, fl: &FrameLaw) -> Control {
    let speed = vel.length();
    let cos_theta = if speed > 0.0 {
        (u.c / speed).clamp(-1.0, 1.0)
    } else {
        1.0
    };
    let theta = u.sigma.signum() * cos_theta.acos();
    Control::strafe(vel, vel.angle(), theta, 0.0, fl.side_key_speed)
}

/// The planning control of a game control played from velocity `vel`.
pub fn frame_control_of(vel: Vec2, c: &Control) -> FrameControl {
    let theta = c.theta_rad(vel);
    FrameControl {
        sigma: if theta >= 0.0 { 1.0 } else { -1.0 },
        c: vel.length() * theta.cos(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::physics::{Effects, MovementVars, PlayerState, Stepper};

    #[test]
    fn the_line_keeps_the_zigzags_margin_unless_a_braking_frames_is_within_a_tenth_of_it() {
        // Half-Life's air law at a frame rate and air acceleration, and the final margin 0.02 units.
        let at = |fps: f64, airaccelerate: f64| {
            let vars = MovementVars {
                airaccelerate,
                ..MovementVars::goldsrc(fps)
            };
            FrameLaw::of(&vars).planning_margin(0.02)
        };
        let close = |a: f64, b: f64| (a - b).abs() < 1e-12;
        // 100 fps, air acceleration 10: `L = 30` and `gamma1 = 32`, the zigzag's and the braking swings
        // 0.30 and 0.32 units are one; the wider is kept.
        assert!(close(at(100.0, 10.0), 0.34), "{}", at(100.0, 10.0));
        // Air acceleration 100: `gamma1 = 320`, a braking frame's 3.2 units against the zigzag's 0.3.
        assert!(close(at(100.0, 100.0), 0.32), "{}", at(100.0, 100.0));
        // 60 fps, air acceleration 1000: the zigzag's 0.5 units.
        assert!(close(at(60.0, 1000.0), 0.52), "{}", at(60.0, 1000.0));
        // 250 fps, air acceleration 10: `gamma1 = 12.8` is the smaller, 0.0512 units against 0.12.
        assert!(close(at(250.0, 10.0), 0.0712), "{}", at(250.0, 10.0));
    }

    /// A state for the derivative tests.
    const SAMPLE_STATE: ModelState = ModelState {
        pos: Vec2::new(3.0, 4.0),
        speed: 612.0,
        heading: 0.7,
    };

    /// One control on each piece of `mu = min(gamma1, L - c)` at 100 fps.
    const ONE_CONTROL_PER_PIECE: [FrameControl; 2] = [
        FrameControl {
            sigma: 0.3,
            c: -1.0,
        }, // mu = L - c piece
        FrameControl {
            sigma: -1.0,
            c: -40.0,
        }, // mu = gamma1 piece
    ];

    fn law(fps: f64) -> (MovementVars, FrameLaw) {
        let vars = MovementVars::goldsrc(fps);
        (vars, FrameLaw::of(&vars))
    }

    #[test]
    fn exact_sides_reproduce_the_game_frame() {
        for fps in [100.0, 1000.0] {
            let (vars, fl) = law(fps);
            let st: Stepper<f64> = Stepper::new(&vars, Effects::AIR_ONLY);
            let mut s = PlayerState::airborne(Vec2::ZERO, Vec2::new(300.0, 200.0));
            let mut x = ModelState {
                pos: s.pos,
                speed: s.speed(),
                heading: s.vel.angle(),
            };
            for k in 0..500 {
                let u = FrameControl {
                    sigma: if k % 3 == 0 { -1.0 } else { 1.0 },
                    c: fl.c_max(x.speed) - (k % 7) as f64,
                };
                let c = control_for(s.vel, u, &fl);
                st.step(&mut s, &c.wish());
                x = frame(&x, u, &fl, false).0;
                assert!((x.pos - s.pos).length() < 1e-6, "{fps} frame {k}");
                assert!((x.speed - s.speed()).abs() < 1e-9);
            }
        }
    }

    #[test]
    fn jacobian_matches_finite_differences() {
        let (_, fl) = law(100.0);
        let x = SAMPLE_STATE;
        for u in ONE_CONTROL_PER_PIECE {
            let (_, j) = frame(&x, u, &fl, true);
            let j = j.unwrap_or(FrameJacobian {
                a: [[f64::NAN; 4]; 4],
                b: [[f64::NAN; 2]; 4],
            });
            let f = |x: &ModelState, u: FrameControl| {
                let n = frame(x, u, &fl, false).0;
                [n.pos.x, n.pos.y, n.speed, n.heading]
            };
            let h = 1e-6;
            let fd = |plus: [f64; 4], minus: [f64; 4]| -> [f64; 4] {
                std::array::from_fn(|i| (plus[i] - minus[i]) / (2.0 * h))
            };
            let dv = fd(
                f(
                    &ModelState {
                        speed: x.speed + h,
                        ..x
                    },
                    u,
                ),
                f(
                    &ModelState {
                        speed: x.speed - h,
                        ..x
                    },
                    u,
                ),
            );
            let dpsi = fd(
                f(
                    &ModelState {
                        heading: x.heading + h,
                        ..x
                    },
                    u,
                ),
                f(
                    &ModelState {
                        heading: x.heading - h,
                        ..x
                    },
                    u,
                ),
            );
            let dsig = fd(
                f(
                    &x,
                    FrameControl {
                        sigma: u.sigma + h,
                        ..u
                    },
                ),
                f(
                    &x,
                    FrameControl {
                        sigma: u.sigma - h,
                        ..u
                    },
                ),
            );
            let dc = fd(
                f(&x, FrameControl { c: u.c + h, ..u }),
                f(&x, FrameControl { c: u.c - h, ..u }),
            );
            for r in 0..4 {
                assert!((j.a[r][2] - dv[r]).abs() < 1e-6, "dV row {r}");
                assert!((j.a[r][3] - dpsi[r]).abs() < 1e-6, "dpsi row {r}");
                assert!((j.b[r][0] - dsig[r]).abs() < 1e-6, "dsigma row {r}");
                assert!((j.b[r][1] - dc[r]).abs() < 1e-6, "dc row {r}");
            }
        }
    }
    #[test]
    fn hessian_matches_finite_differences_of_the_jacobian() {
        let (_, fl) = law(100.0);
        let x = SAMPLE_STATE;
        // Inputs in the Hessian's order (V, psi, sigma, c), and the gradient row in that order.
        let perturb = |i: usize, h: f64, u: FrameControl| -> (ModelState, FrameControl) {
            let (mut x, mut u) = (x, u);
            match i {
                0 => x.speed += h,
                1 => x.heading += h,
                2 => u.sigma += h,
                _ => u.c += h,
            }
            (x, u)
        };
        let grad = |x: &ModelState, u: FrameControl| -> [[f64; 4]; 4] {
            frame(x, u, &fl, true).1.map_or([[f64::NAN; 4]; 4], |j| {
                std::array::from_fn(|r| [j.a[r][2], j.a[r][3], j.b[r][0], j.b[r][1]])
            })
        };
        for u in ONE_CONTROL_PER_PIECE {
            let hess = frame_hessian(&x, u, &fl);
            let step = 1e-5;
            for i in 0..4 {
                let (xp, up) = perturb(i, step, u);
                let (xm, um) = perturb(i, -step, u);
                let (gp, gm) = (grad(&xp, up), grad(&xm, um));
                for r in 0..4 {
                    for j in 0..4 {
                        let fd = (gp[r][j] - gm[r][j]) / (2.0 * step);
                        let h = hess.h[r][i][j];
                        assert!(
                            (h - fd).abs() <= 1e-6 * (1.0 + fd.abs()),
                            "output {r}, d2/d{i}d{j}: {h} vs {fd}"
                        );
                        assert!((h - hess.h[r][j][i]).abs() <= 1e-9 * (1.0 + h.abs()));
                    }
                }
            }
        }
    }

    #[test]
    fn a_knot_is_its_frames_played_in_turn() {
        let (_, fl) = law(1000.0);
        let x = SAMPLE_STATE;
        let u = FrameControl {
            sigma: 0.4,
            c: -1.0,
        };
        let mut y = x;
        for _ in 0..7 {
            y = frame(&y, u, &fl, false).0;
        }
        let (k, j) = knot(&x, u, &fl, 7, true);
        assert!((k.pos - y.pos).length() < 1e-9);
        assert!((k.speed - y.speed).abs() < 1e-9 && (k.heading - y.heading).abs() < 1e-12);
        // Its Jacobian by finite differences in sigma.
        let h = 1e-6;
        let plus = knot(
            &x,
            FrameControl {
                sigma: u.sigma + h,
                ..u
            },
            &fl,
            7,
            false,
        )
        .0;
        let minus = knot(
            &x,
            FrameControl {
                sigma: u.sigma - h,
                ..u
            },
            &fl,
            7,
            false,
        )
        .0;
        let j = j.unwrap_or(FrameJacobian {
            a: [[f64::NAN; 4]; 4],
            b: [[f64::NAN; 2]; 4],
        });
        assert!((j.b[1][0] - (plus.pos.y - minus.pos.y) / (2.0 * h)).abs() < 1e-5);
        assert!((j.b[3][0] - (plus.heading - minus.heading) / (2.0 * h)).abs() < 1e-7);
    }

    #[test]
    fn the_plan_stays_half_an_anglemod_step_under_the_kink_only_in_case_1() {
        // 100 fps: gamma1 = 32 > L = 30, case 2: c_max = 0, no guard.
        let (_, fl) = law(100.0);
        assert_eq!(fl.c_plan_max(600.0), fl.c_max(600.0));
        // 1000 fps: gamma1 = 3.2 < L, case 1: c_max = L - gamma1 = 26.8, the kink.
        let (_, fl) = law(1000.0);
        let step = (360.0f64 / 65536.0).to_radians();
        assert!((fl.c_max(600.0) - 26.8).abs() < 1e-12);
        assert!((fl.c_max(600.0) - fl.c_plan_max(600.0) - 300.0 * step).abs() < 1e-12);
    }

    #[test]
    fn braking_straight_back_is_linear_in_c_only_with_the_sides_cancelled() {
        // At c = -V the heading's push mu sqrt(V^2 - c^2) / V has an unbounded derivative: one ups more
        // of c swings a sided frame's heading by about 1e-3 rad, which its Jacobian does not see; with
        // the sides cancelled (sigma = 0) the heading does not move and the Jacobian is right.
        let (_, fl) = law(100.0);
        let x = SAMPLE_STATE;
        for (sigma, linear_holds) in [(0.0, true), (1.0, false)] {
            let u = FrameControl { sigma, c: -x.speed };
            let (y0, j) = frame(&x, u, &fl, true);
            let Some(j) = j else { panic!("no Jacobian") };
            let y1 = frame(&x, FrameControl { c: u.c + 1.0, ..u }, &fl, false).0;
            let error = (y1.heading - y0.heading - j.b[3][1]).abs();
            assert_eq!(error < 1e-6, linear_holds, "sigma {sigma}: error {error}");
        }
        assert!(fl.c_min(x.speed) > -x.speed);
    }

    #[test]
    fn exact_sides_may_turn_less_than_maximum_acceleration_clear_of_the_guard() {
        // Case 2 (100 fps): c runs on past c_max = 0 to L = 30, where the frame coasts; below L / 0.95
        // ups it stops at 0.95 V, clear of theta = 0.
        let (_, fl) = law(100.0);
        assert_eq!(fl.c_exact_max(600.0), 30.0);
        assert!((fl.c_exact_max(20.0) - 19.0).abs() < 1e-12);
        // Each step of c above c_max turns less and gains less: it is the turn-less piece, not a better
        // maximum.
        let x = SAMPLE_STATE;
        let at = |c: f64| frame(&x, FrameControl { sigma: 1.0, c }, &fl, false).0;
        let (max, less, coast) = (at(fl.c_max(x.speed)), at(15.0), at(fl.c_exact_max(x.speed)));
        assert!(less.heading - x.heading < max.heading - x.heading);
        assert!(less.speed < max.speed && less.heading > x.heading);
        assert!((coast.heading - x.heading).abs() < 1e-12 && (coast.speed - x.speed).abs() < 1e-9);
        // Case 1 (1000 fps): c_max is the kink. Exact sides may turn less past it, but not stay within
        // the guard's band around it.
        let (_, fl) = law(1000.0);
        assert_eq!(fl.c_exact_max(600.0), 30.0);
        let (guard, kink) = (fl.c_plan_max(600.0), fl.kink());
        assert_eq!(fl.under_the_guard(kink, 600.0), guard);
        assert_eq!(fl.under_the_guard(guard + 1e-9, 600.0), guard);
        assert_eq!(fl.under_the_guard(guard - 1.0, 600.0), guard - 1.0);
        assert_eq!(fl.under_the_guard(kink + 1.0, 600.0), kink + 1.0);
        // Case 2 (100 fps): the maximum-acceleration c = 0 is kept; the kink L - gamma1 = -2, the frame
        // of the largest turn, has its band, and a frame in it goes down to its bottom.
        let (_, fl) = law(100.0);
        assert_eq!(fl.under_the_guard(0.0, 600.0), 0.0);
        let half = 0.5 * fl.angle_step_ups(600.0);
        let Some((bottom, top)) = fl.guard_band(600.0) else {
            panic!("no band around the kink in case 2")
        };
        assert!((bottom - (-2.0 - half)).abs() < 1e-12 && (top - (-2.0 + half)).abs() < 1e-12);
        assert_eq!(fl.under_the_guard(-2.0, 600.0), bottom);
        assert_eq!(
            fl.under_the_guard(-2.0 - 2.0 * half, 600.0),
            -2.0 - 2.0 * half
        );
        // Below the speed at which braking reaches the kink (0.95 V = 2 ups) there is no band.
        assert!(fl.guard_band(2.0).is_none());
    }

    /// A strafer's run of `frames` frames from `start`, in four stretches: sides alternating at maximum
    /// acceleration (a straight), a left turn, sides alternating with every right frame braking
    /// (`c = -V / 2`), and a right turn.
    fn strafer_run(fl: &FrameLaw, start: &ModelState, frames: usize) -> Vec<FrameControl> {
        let mut x = *start;
        let mut controls = Vec::with_capacity(frames);
        for k in 0..frames {
            let left = k % 2 == 0;
            let (sigma, c) = match 4 * k / frames {
                0 => (if left { 1.0 } else { -1.0 }, fl.c_max(x.speed)),
                1 => (1.0, fl.c_max(x.speed)),
                2 if left => (1.0, fl.c_max(x.speed)),
                2 => (-1.0, -0.5 * x.speed),
                _ => (-1.0, fl.c_max(x.speed)),
            };
            let u = FrameControl { sigma, c };
            x = frame(&x, u, fl, false).0;
            controls.push(u);
        }
        controls
    }

    /// The largest distance, units, between the knots' states and the run's at the knots' ends.
    fn worst_knot_offset(run: &[ModelState], knots: &[ModelState], per: usize) -> f64 {
        knots
            .iter()
            .enumerate()
            .map(|(j, k)| (k.pos - run[(j * per + per - 1).min(run.len() - 1)].pos).length())
            .fold(0.0, f64::max)
    }

    #[test]
    fn knots_following_a_run_keep_to_its_line_and_reach_its_speed() {
        // Both cases of the law (100 fps: the second, 1000 fps: the first), four seconds each, knots of
        // six and of 25 frames (the last knot shorter).
        for (fps, per) in [(100.0, 6), (1000.0, 25)] {
            let (_, fl) = law(fps);
            let start = ModelState {
                pos: Vec2::new(10.0, -20.0),
                speed: 500.0,
                heading: 0.3,
            };
            let controls = strafer_run(&fl, &start, (4.0 * fps) as usize);
            let run = rollout(&start, &controls, &fl);
            let knots = knots_following(&start, &controls, &fl, per, |v| fl.c_max(v));
            assert_eq!(knots.len(), controls.len().div_ceil(per));
            assert!(knots
                .iter()
                .all(|u| u.sigma.abs() <= 1.0 && u.c <= fl.c_max(start.speed) + 1e-9));
            // Each knot brakes within the limit at every frame it plays: at its end speed too.
            let mut at = start;
            for &u in &knots {
                let next = knot(&at, u, &fl, per as u32, false).0;
                assert!(
                    u.c >= fl.c_min(at.speed.min(next.speed)) - 1e-6,
                    "{fps} fps: {u:?}"
                );
                at = next;
            }
            let followed = rollout_knots(&start, &knots, &fl, per as u32);
            let (end, run_end) = (followed[followed.len() - 1], run[run.len() - 1]);
            // Within 15 units (the narrowest generated corridor leaves its hull 16 either side); measured
            // 11.4 at 100 fps, where the run brakes to 75 ups, and 0.24 at 1000 fps.
            let worst = worst_knot_offset(&run, &followed, per);
            assert!(worst < 15.0, "{fps} fps: {worst} units off the run");
            assert!((end.speed - run_end.speed).abs() < 1e-6 * run_end.speed);
            // The same knots with their frames' controls averaged leave the line (77 and 85 units): the
            // test's run is one that averaging cannot follow.
            let averaged = knots_averaged(&controls, per);
            let drifted = worst_knot_offset(
                &run,
                &rollout_knots(&start, &averaged, &fl, per as u32),
                per,
            );
            assert!(
                drifted > 50.0,
                "{fps} fps: averaged knots only {drifted} units off"
            );
        }
    }

    #[test]
    fn a_frame_asked_to_brake_harder_than_its_speed_brakes_straight_back() {
        // `c = V cos theta` cannot pass the speed: a knot's later frames asked for `c < -V` brake as at
        // `c = -V`, and never gain more than `mu` (taken as it is, `c = -600` at 20 ups would leave at
        // about 940 ups at 100 fps, 76 at 1000 fps).
        for fps in [100.0, 1000.0] {
            let (_, fl) = law(fps);
            let x = ModelState {
                pos: Vec2::ZERO,
                speed: 20.0,
                heading: 0.4,
            };
            let mu = fl.law.gamma1.min(fl.law.l + x.speed);
            for sigma in [-1.0, 0.3, 1.0] {
                let asked = frame(&x, FrameControl { sigma, c: -600.0 }, &fl, false).0;
                let back = frame(&x, FrameControl { sigma, c: -x.speed }, &fl, false).0;
                assert_eq!(asked, back, "{fps} fps, side {sigma}");
                assert!(
                    asked.speed <= x.speed + mu + 1e-9,
                    "{fps} fps: {}",
                    asked.speed
                );
            }
            // Its derivative is the speed's: `c` no longer counts.
            let (_, jac) = frame(
                &x,
                FrameControl {
                    sigma: 1.0,
                    c: -600.0,
                },
                &fl,
                true,
            );
            let jac = jac.unwrap_or_else(|| panic!("no Jacobian"));
            assert!(jac.b.iter().all(|row| row[1] == 0.0), "{:?}", jac.b);
        }
    }
}
