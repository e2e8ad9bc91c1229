//! Strafe angles (docs/physics.md sections 5-8). Every function takes `lambda = |lambda(v)|`, the speed after
//! friction (ups), and the frame's [`AccelLaw`] (`L`, `gamma1`), and works with `cos theta`, where `theta`
//! is the angle between `lambda(v)` and the wish direction. Speeds depend only on `cos theta`; the sign of
//! `theta` picks the side. No function divides by a zero speed or takes `acos` of an unclamped value.
//!
//! A chosen angle becomes a frame's input in one of two forms: a [`Wish`] (the view vector, built from
//! `cos theta` by rotations, no trigonometric function; what an `f64` frame loop steps) or a [`Control`]
//! (the same with a yaw, for plans, reports and the engine-exact mode, which sends the yaw through
//! anglemod): [`max_accel_wish`] and [`max_accel_control`], [`strafe_wish`].

use super::real::Real;
use super::step::{AccelLaw, Control, PlayerState, Side, Stepper, Wish};
use super::vec2::Vec2;

/// Speed after one frame at `cos theta` (the scalar FME, docs/physics.md section 5):
/// `|v'|^2 = lambda^2 + mu^2 + 2 mu lambda cos theta` with `mu = min(gamma1, L - lambda cos theta)` when
/// `L - lambda cos theta > 0`, else 0.
#[inline]
pub fn speed_after(lambda: f64, cos_theta: f64, law: AccelLaw) -> f64 {
    let c = lambda * cos_theta;
    let mu = law.mu(c);
    (lambda * lambda + mu * mu + 2.0 * mu * c).max(0.0).sqrt()
}

/// `mu` at `cos theta` (docs/physics.md section 5).
#[inline]
pub fn mu_at(lambda: f64, cos_theta: f64, law: AccelLaw) -> f64 {
    law.mu(lambda * cos_theta)
}

/// `theta` from `cos theta`, clamped into `[-1, 1]` first.
#[inline]
pub fn theta_from_cos(cos_theta: f64) -> f64 {
    cos_theta.clamp(-1.0, 1.0).acos()
}

/// Which case of docs/physics.md section 6 a frame falls in.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum MaxAccelCase {
    /// `gamma1 >= 0`, `L - gamma1 >= 0`, `L >= 0`: `cos Theta = min(1, cos zeta)`.
    One,
    /// `gamma1 >= 0`, `L - gamma1 < 0`, `L >= 0`: `cos Theta = 0`.
    Two,
    /// `gamma1 >= 0`, `L < 0`: no angle accelerates; any `cos Theta >= cos zeta_bar` keeps the speed.
    Three,
    /// `gamma1 < 0`, `cos zeta_bar <= -1`: every angle keeps the speed.
    Four,
    /// `gamma1 < 0`, `cos zeta_bar > -1`: `cos Theta = -1`, pushing against the negative gain.
    Five,
}

/// The maximum-acceleration choice of one frame.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MaxAccel {
    /// The case of docs/physics.md section 6.
    pub case: MaxAccelCase,
    /// The optimal `cos Theta` (for cases 3 and 4, where a range is optimal, 1: keep the heading).
    pub cos_theta: f64,
    /// The new speed, ups, by the closed forms of section 6.
    pub speed: f64,
}

/// Maximum acceleration (docs/physics.md section 6, all five cases). `lambda` may be zero: the direction is then
/// lost and `cos Theta` refers to the view direction. `cos zeta = (L - gamma1)/lambda` and
/// `cos zeta_bar = L/lambda` are compared by multiplying through by `lambda`, never divided by zero.
#[inline]
pub fn max_accel(lambda: f64, law: AccelLaw) -> MaxAccel {
    let AccelLaw { l, gamma1 } = law;
    let (case, cos_theta) = max_accel_cos_theta(lambda, law);
    let speed = match case {
        MaxAccelCase::One if l - gamma1 >= lambda => lambda + gamma1,
        MaxAccelCase::One => (lambda * lambda + gamma1 * (2.0 * l - gamma1)).sqrt(),
        MaxAccelCase::Two => lambda.hypot(l),
        MaxAccelCase::Three | MaxAccelCase::Four => lambda,
        MaxAccelCase::Five => lambda - gamma1,
    };
    MaxAccel {
        case,
        cos_theta,
        speed,
    }
}

/// The case and the optimal `cos Theta` of [`max_accel`] without the new speed: all a controller choosing
/// its angle needs (docs/physics.md section 6).
#[inline]
pub fn max_accel_cos_theta(lambda: f64, law: AccelLaw) -> (MaxAccelCase, f64) {
    let AccelLaw { l, gamma1 } = law;
    if gamma1 >= 0.0 {
        if l >= 0.0 {
            if l - gamma1 >= 0.0 {
                // Case 1: min(1, cos zeta).
                if l - gamma1 >= lambda {
                    (MaxAccelCase::One, 1.0)
                } else {
                    (MaxAccelCase::One, (l - gamma1) / lambda)
                }
            } else {
                (MaxAccelCase::Two, 0.0)
            }
        } else {
            (MaxAccelCase::Three, 1.0)
        }
    } else if l <= -lambda {
        (MaxAccelCase::Four, 1.0)
    } else {
        (MaxAccelCase::Five, -1.0)
    }
}

/// The maximum-acceleration angle `Theta` in `[0, pi]`, radians (docs/physics.md section 6).
#[inline]
pub fn max_accel_theta(lambda: f64, law: AccelLaw) -> f64 {
    theta_from_cos(max_accel_cos_theta(lambda, law).1)
}

/// The candidate `cos theta` values at which the speed, as a function of `cos theta`, can have its extrema:
/// the ends `-1, 1`, the piece boundaries `cos zeta` (`gamma1 = gamma2`) and `cos zeta_bar` (`gamma2 = 0`),
/// each also nudged to both sides (with `gamma1 < 0` the speed jumps at `cos zeta_bar`), and 0. Between
/// them `|v'|^2` is linear (`mu = gamma1`), concave (`mu = gamma2`) or constant (`mu = 0`), so the
/// minimum lies at a candidate and the maximum at a candidate or at 0.
fn extremum_candidates(lambda: f64, law: AccelLaw) -> Vec<f64> {
    let mut c = vec![-1.0, 0.0, 1.0];
    if lambda > 0.0 {
        for b in [(law.l - law.gamma1) / lambda, law.l / lambda] {
            if b.is_finite() && b > -1.0 && b < 1.0 {
                let nudge = 1e-12 * (1.0 + b.abs());
                c.extend([b, (b - nudge).max(-1.0), (b + nudge).min(1.0)]);
            }
        }
    }
    c
}

/// Maximum deceleration (docs/physics.md section 7): the `cos theta` that minimises the new speed, and that
/// speed. In the common case (`gamma1 >= 0`, `L >= 0`, `L - gamma1 >= 0`) it is `cos theta = -1`, giving
/// `| lambda - gamma1 |`; in general the minimum is found exactly among the piece boundaries.
pub fn max_decel(lambda: f64, law: AccelLaw) -> (f64, f64) {
    let mut best = (1.0, speed_after(lambda, 1.0, law));
    for c in extremum_candidates(lambda, law) {
        let sp = speed_after(lambda, c, law);
        if sp < best.1 {
            best = (c, sp);
        }
    }
    best
}

/// Speed-preserving strafing (docs/physics.md section 8): the `cos theta` at which the speed after the frame
/// equals `speed_before` (the speed before friction; equal to `lambda` without friction), turning as hard as
/// possible (the smallest such `cos theta`), or `None` when no angle preserves it (then fall back to
/// [`max_accel`], as section 8 says).
///
/// Section 8's two formulas are the solutions on the `mu = gamma1` piece,
/// `cos theta = ((|v|^2 - lambda^2)/gamma1 - gamma1)/(2 lambda)`, and on the `mu = gamma2` piece,
/// `cos theta = -sqrt(L^2 - (|v|^2 - lambda^2))/lambda`. Each piece of `|v'|^2(cos theta)` is linear,
/// concave quadratic or constant, so every solution is found exactly; where section 8's formulas apply
/// this returns the same value, and it also finds the gentler solutions they miss.
pub fn speed_preserving_cos_theta(speed_before: f64, lambda: f64, law: AccelLaw) -> Option<f64> {
    let AccelLaw { l, gamma1 } = law;
    if !(lambda > 0.0 && speed_before.is_finite()) {
        return None;
    }
    let loss = speed_before * speed_before - lambda * lambda; // what friction took, in speed^2
                                                              // Piece boundaries: gamma2 = gamma1 at cos zeta, gamma2 = 0 at cos zeta_bar.
    let cos_zeta = (l - gamma1) / lambda;
    let cos_zeta_bar = l / lambda;
    let eps = 1e-12;
    let mut solutions: Vec<f64> = Vec::with_capacity(4);
    // mu = gamma1 where gamma2 >= gamma1 and gamma2 > 0: |v'|^2 = lambda^2 + gamma1^2 + 2 gamma1 lambda c.
    if gamma1 != 0.0 {
        let c = (loss / gamma1 - gamma1) / (2.0 * lambda);
        if c <= cos_zeta + eps && c < cos_zeta_bar {
            solutions.push(c);
        }
    }
    // mu = gamma2 where 0 < gamma2 < gamma1: |v'|^2 = lambda^2 (1 - c^2) + L^2.
    let disc = l * l - loss;
    if disc >= 0.0 {
        let r = disc.sqrt() / lambda;
        for c in [-r, r] {
            if c >= cos_zeta - eps && c < cos_zeta_bar {
                solutions.push(c);
            }
        }
    }
    // mu = 0 where gamma2 <= 0: |v'| = lambda, which preserves only without friction.
    if loss.abs() <= eps * speed_before * speed_before {
        solutions.push(cos_zeta_bar);
    }
    solutions
        .into_iter()
        .filter(|c| c.is_finite() && (-1.0..=1.0).contains(c))
        .fold(None, |best: Option<f64>, c| {
            Some(best.map_or(c, |b| b.min(c)))
        })
}

/// Steps of [`sharpest_turn`]'s scan over `theta` from 0 to pi, for the laws its closed form leaves open.
const SHARPEST_TURN_SCAN: usize = 256;

/// Golden-section iterations refining [`sharpest_turn`]'s scan.
const SHARPEST_TURN_GOLDEN_STEPS: usize = 80;

/// The sharpest turn of one frame (docs/physics.md section 9): the `theta` in `[0, pi]` that turns the
/// velocity furthest, and that turn, radians. The turn at `theta` is `atan2(mu sin theta, lambda + mu cos
/// theta)`.
///
/// With `gamma1 > 0` and `L >= 0` (every law of a real engine) it is the peak of the `mu = gamma1` piece,
/// `cos theta = max(-gamma1 / lambda, -1)` (`theta = pi` at rest):
/// - On the `mu = gamma1` piece (`lambda cos theta <= L - gamma1`) the new velocity is `lambda` plus
///   `gamma1` along the wish direction; its turn grows with `theta` while `gamma1 + lambda cos theta > 0`
///   and falls after, so it peaks at `cos theta = -gamma1 / lambda`, which lies on this piece as `L >= 0`.
/// - On the `mu = L - lambda cos theta` piece the new velocity is `lambda` projected onto the line
///   `x . a_hat = L`, turned by `theta - atan(lambda sin theta / L)`, whose derivative in `theta` has the
///   sign of `L^2 + lambda^2 sin^2 theta - lambda L cos theta`, never negative where `mu > 0`: the turn
///   grows towards the kink and joins the first piece there.
/// - Where `mu = 0` the velocity does not turn.
///
/// For other laws (negative gains, `L < 0`) the piece boundaries are compared with a scan over `theta`
/// refined by golden-section search.
pub fn sharpest_turn(lambda: f64, law: AccelLaw) -> (f64, f64) {
    let turn = |theta: f64| {
        let (s, c) = theta.sin_cos();
        turn_of(lambda, c, s, law)
    };
    if law.gamma1 > 0.0 && law.l >= 0.0 && lambda >= 0.0 {
        let theta = if lambda > 0.0 {
            theta_from_cos(-law.gamma1 / lambda)
        } else {
            std::f64::consts::PI
        };
        return (theta, turn(theta));
    }
    let mut best = (0.0, turn(0.0));
    let consider = |theta: f64, best: &mut (f64, f64)| {
        let t = turn(theta);
        if t > best.1 {
            *best = (theta, t);
        }
    };
    for c in extremum_candidates(lambda, law) {
        consider(theta_from_cos(c), &mut best);
    }
    if lambda > 0.0 && law.gamma1 > 0.0 {
        consider(theta_from_cos(-law.gamma1 / lambda), &mut best);
    }
    // A scan over theta refined around its best sample (golden section on the bracketing interval).
    let step = std::f64::consts::PI / SHARPEST_TURN_SCAN as f64;
    let mut scan_best = (0.0, f64::NEG_INFINITY);
    for i in 0..=SHARPEST_TURN_SCAN {
        let theta = i as f64 * step;
        let t = turn(theta);
        if t > scan_best.1 {
            scan_best = (theta, t);
        }
    }
    let (mut a, mut b) = (
        (scan_best.0 - step).max(0.0),
        (scan_best.0 + step).min(std::f64::consts::PI),
    );
    let g = 0.5 * (5f64.sqrt() - 1.0);
    for _ in 0..SHARPEST_TURN_GOLDEN_STEPS {
        let x1 = b - g * (b - a);
        let x2 = a + g * (b - a);
        if turn(x1) >= turn(x2) {
            b = x2;
        } else {
            a = x1;
        }
    }
    consider(0.5 * (a + b), &mut best);
    consider(scan_best.0, &mut best);
    best
}

/// The turn of one frame at `cos theta`, radians (docs/physics.md section 9): `atan2(mu sin theta,
/// lambda + mu cos theta)` with `theta` in `[0, pi]`.
#[inline]
pub fn turn_at(lambda: f64, cos_theta: f64, law: AccelLaw) -> f64 {
    let c = cos_theta.clamp(-1.0, 1.0);
    turn_of(lambda, c, (1.0 - c * c).max(0.0).sqrt(), law)
}

/// The turn of one frame at the angle whose cosine and sine are `cos_theta` and `sin_theta` (`>= 0`),
/// radians: `atan2(mu sin theta, lambda + mu cos theta)`.
#[inline]
fn turn_of(lambda: f64, cos_theta: f64, sin_theta: f64, law: AccelLaw) -> f64 {
    let mu = mu_at(lambda, cos_theta, law);
    (mu * sin_theta).atan2(lambda + mu * cos_theta)
}

/// Bisection steps of [`turning_cos_theta`]: the angle to about `pi / 2^40`.
const TURN_BISECTIONS: usize = 40;

/// The strafe angle of a frame that turns the velocity by `wanted_rad` for the least speed (docs/physics.md
/// sections 6 and 9), as `cos theta`: the maximum-acceleration angle where that turns at least as much;
/// else the angle between it and the sharpest turn's that turns by `wanted_rad` (bisection: from the
/// maximum-acceleration angle to the sharpest turn's the speed falls as `theta` grows, so the first angle
/// that turns enough loses the least); else, where no frame turns that far, the sharpest turn's.
pub fn turning_cos_theta(lambda: f64, law: AccelLaw, wanted_rad: f64) -> f64 {
    let accel_cos = max_accel_cos_theta(lambda, law).1;
    if turn_at(lambda, accel_cos, law) >= wanted_rad {
        return accel_cos;
    }
    let (sharp_theta, sharp_turn) = sharpest_turn(lambda, law);
    if sharp_turn <= wanted_rad {
        return sharp_theta.cos();
    }
    let (mut lo, mut hi) = (theta_from_cos(accel_cos), sharp_theta);
    for _ in 0..TURN_BISECTIONS {
        let mid = 0.5 * (lo + hi);
        if turn_at(lambda, mid.cos(), law) >= wanted_rad {
            hi = mid;
        } else {
            lo = mid;
        }
    }
    hi.cos()
}

/// The maximum-acceleration control of this frame for a player holding the keys `forwardmove`, `sidemove`,
/// turning to `side`: the stepper's own friction and law are applied to a copy of the state, then the yaw is
/// set so that the wish direction makes the angle [`max_accel_theta`] with `lambda(v)` (docs/physics.md
/// section 6). `heading_rad` is used at zero speed. The returned control carries the given buttons.
///
/// This is [`max_accel_wish`] with its view vector turned into a yaw (one `atan2`); a loop that only
/// steps the `f64` planning physics can step that wish directly and skip the yaw.
#[inline]
pub fn max_accel_control(
    stepper: &Stepper<f64>,
    state: &PlayerState,
    keys: Wish,
    side: Side,
    heading_rad: f64,
) -> Control {
    Control::from_wish(&max_accel_wish(stepper, state, keys, side, heading_rad))
}

/// The maximum-acceleration wish of this frame (see [`max_accel_control`]) in vector form, ready for
/// [`Stepper::step`]: the wish direction is `lambda_hat` turned to `side` by the angle whose cosine is
/// [`max_accel_cos_theta`] (docs/physics.md section 6), with no trigonometric function.
#[inline]
pub fn max_accel_wish(
    stepper: &Stepper<f64>,
    state: &PlayerState,
    keys: Wish,
    side: Side,
    heading_rad: f64,
) -> Wish {
    strafe_wish(stepper, state, keys, side, heading_rad, |lambda, law| {
        max_accel_cos_theta(lambda, law).1
    })
}

/// The wish of this frame whose direction makes the angle `theta` with `lambda(v)` (docs/physics.md section 5:
/// `a_hat = R(theta) lambda_hat`), turning to `side`, where `cos theta = pick_cos_theta(lambda, law)` from
/// the frame's speed after friction and acceleration law (clamped into `[-1, 1]`; `cos theta = 1` when no
/// acceleration applies). `heading_rad` stands in for `lambda_hat` at zero speed.
///
/// No trigonometric function: `sin theta = sqrt(1 - cos^2 theta)`, and the view vector is `a_hat` turned
/// back by the keys' angle `kappa`, `f = R(kappa) a_hat = R(theta) R(kappa) lambda_hat` with
/// `(cos kappa, sin kappa) = (F, S)/|(F, S)|` (the right vector is `f` turned clockwise, so
/// `a_hat = cos kappa f + sin kappa s = R(-kappa) f`).
#[inline(always)]
pub fn strafe_wish(
    stepper: &Stepper<f64>,
    state: &PlayerState,
    keys: Wish,
    side: Side,
    heading_rad: f64,
    pick_cos_theta: impl FnOnce(f64, AccelLaw) -> f64,
) -> Wish {
    let mut probe = *state;
    let law = stepper.prepare(&mut probe, &keys).map(|(_, law)| law);
    let lambda = probe.vel.length();
    let cos_theta = law.map_or(1.0, |law| pick_cos_theta(lambda, law).clamp(-1.0, 1.0));
    let sin_theta = side.sign() * (1.0 - cos_theta * cos_theta).max(0.0).sqrt();
    let lambda_hat = probe
        .vel
        .normalized()
        .unwrap_or_else(|| Vec2::from_angle(heading_rad));
    // f = R(kappa) R(theta) lambda_hat, with the keys' turn first: it needs only lambda_hat, so it is done
    // while sin theta (a division and a square root later) is still being computed.
    let keys_len = Real::hypot(keys.forwardmove, keys.sidemove);
    let lambda_hat_by_keys = if keys_len > 0.0 {
        lambda_hat.rotated_cos_sin(keys.forwardmove / keys_len, keys.sidemove / keys_len)
    } else {
        lambda_hat
    };
    let forward = lambda_hat_by_keys.rotated_cos_sin(cos_theta, sin_theta);
    Wish { forward, ..keys }
}

/// A control whose strafe angle is chosen by `pick_theta(lambda, law)` from the frame's speed after friction
/// and acceleration law (see [`max_accel_control`]).
pub fn strafe_control(
    stepper: &Stepper<f64>,
    state: &PlayerState,
    keys: Wish,
    heading_rad: f64,
    pick_theta: impl FnOnce(f64, AccelLaw) -> f64,
) -> Control {
    let mut probe = *state;
    let theta = match stepper.prepare(&mut probe, &keys) {
        Some((_, law)) => pick_theta(probe.vel.length(), law),
        None => 0.0,
    };
    let heading = if probe.vel.length_squared() > 0.0 {
        probe.vel.angle()
    } else {
        heading_rad
    };
    let mut c = Control::strafe(probe.vel, heading, theta, keys.forwardmove, keys.sidemove);
    c.jump = keys.jump;
    c.duck = keys.duck;
    c
}

/// The keys a strafer holds by default: full sidemove only (`S = 400` in GoldSrc), so `M = min(M_m, 400)`.
pub fn strafe_keys(side_key_speed: f64) -> Wish {
    Wish {
        forward: Vec2::new(1.0, 0.0),
        forwardmove: 0.0,
        sidemove: side_key_speed,
        jump: false,
        duck: false,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn law(l: f64, gamma1: f64) -> AccelLaw {
        AccelLaw { l, gamma1 }
    }

    #[test]
    fn the_sharpest_turn_of_a_law_its_closed_form_leaves_open_is_refined_to_its_peak() {
        // L < 0 or negative gains: the scan and its golden section decide. No angle within a
        // thousandth of a radian of theirs may turn further (a refinement cut short leaves its answer
        // up to a scan step off the peak).
        let turn = |lam: f64, theta: f64, law: AccelLaw| {
            let (s, c) = theta.sin_cos();
            turn_of(lam, c, s, law)
        };
        for &(l, g) in &[
            (-5.0, 3.2),
            (-20.0, 32.0),
            (-50.0, 320.0),
            (30.0, -3.2),
            (-5.0, -32.0),
        ] {
            for &lam in &[10.0, 100.0, 700.0, 2000.0] {
                let law = law(l, g);
                let (theta, best) = sharpest_turn(lam, law);
                assert!((turn(lam, theta, law) - best).abs() < 1e-15);
                for i in -1000..=1000 {
                    let other = (theta + f64::from(i) * 1e-6).clamp(0.0, std::f64::consts::PI);
                    let t = turn(lam, other, law);
                    assert!(
                        t <= best + 1e-13,
                        "L {l}, gamma1 {g}, lambda {lam}: {other} turns {t} > {best}"
                    );
                }
            }
        }
    }

    #[test]
    fn the_sharpest_turn_of_an_engine_law_is_its_closed_form() {
        // gamma1 < lambda: the peak of the mu = gamma1 piece, asin(gamma1 / lambda); else half a turn.
        for &(lam, l, g) in &[
            (700.0, 30.0, 3.2),
            (700.0, 30.0, 32.0),
            (1200.0, 30.0, 320.0),
            (320.0, 320.0, 32.0),
        ] {
            let (theta, turn) = sharpest_turn(lam, law(l, g));
            assert!((theta.cos() + g / lam).abs() < 1e-12, "{lam} {l} {g}");
            assert!((turn - (g / lam).asin()).abs() < 1e-12, "{lam} {l} {g}");
        }
        let (theta, turn) = sharpest_turn(100.0, law(30.0, 320.0));
        assert_eq!(theta, std::f64::consts::PI);
        assert!((turn - std::f64::consts::PI).abs() < 1e-12);
    }

    #[test]
    fn case_formulas_match_the_scalar_fme_at_the_chosen_angle() {
        for &(lam, l, g) in &[
            (500.0, 30.0, 3.2),    // case 1, cos zeta < 1
            (10.0, 30.0, 3.2),     // case 1, cos = 1
            (500.0, 30.0, 32.0),   // case 2
            (500.0, -5.0, 3.0),    // case 3
            (500.0, -600.0, -1.0), // case 4
            (500.0, 30.0, -2.0),   // case 5
            (0.0, 30.0, 3.2),      // zero speed
            (0.0, 30.0, 32.0),
            (0.0, 0.0, 0.0),
        ] {
            let m = max_accel(lam, law(l, g));
            let direct = speed_after(lam, m.cos_theta, law(l, g));
            assert!(
                (m.speed - direct).abs() < 1e-9,
                "{lam} {l} {g}: {m:?} vs {direct}"
            );
            assert!(m.speed.is_finite() && m.cos_theta.abs() <= 1.0);
        }
    }

    #[test]
    fn a_wanted_turn_is_made_for_the_least_speed_of_any_angle_that_turns_as_far() {
        // Both cases of the air (1000 fps with air acceleration 10; 100 fps with 100) and a slow start.
        for &(lam, l, g) in &[
            (700.0, 30.0, 3.2),
            (1200.0, 30.0, 320.0),
            (90.0, 30.0, 32.0),
        ] {
            let law = law(l, g);
            let accel_cos = max_accel_cos_theta(lam, law).1;
            let accel_turn = turn_at(lam, accel_cos, law);
            let (sharp_theta, sharp_turn) = sharpest_turn(lam, law);
            // Up to the maximum-acceleration turn: maximum acceleration (it turns at least as far).
            assert_eq!(turning_cos_theta(lam, law, 0.5 * accel_turn), accel_cos);
            // Beyond the sharpest turn: the sharpest.
            let beyond = turning_cos_theta(lam, law, 2.0 * sharp_turn);
            assert!((beyond - sharp_theta.cos()).abs() < 1e-12, "{lam} {l} {g}");
            for share in [0.1, 0.5, 0.9] {
                let wanted = accel_turn + share * (sharp_turn - accel_turn);
                let c = turning_cos_theta(lam, law, wanted);
                let turn = turn_at(lam, c, law);
                assert!(
                    (turn - wanted).abs() < 1e-9,
                    "{lam} {l} {g} {share}: {turn} for {wanted}"
                );
                // No angle on a fine grid turns as far and keeps more speed.
                let speed = speed_after(lam, c, law);
                for i in 0..=2000 {
                    let other = -1.0 + 2.0 * f64::from(i) / 2000.0;
                    if turn_at(lam, other, law) >= wanted {
                        assert!(
                            speed_after(lam, other, law) <= speed + 1e-9,
                            "{lam} {l} {g} {share}: cos {other} keeps more than {c}"
                        );
                    }
                }
            }
        }
    }

    /// The wish direction of a control, as the step computes it.
    fn a_hat(st: &Stepper<f64>, w: &Wish) -> Vec2 {
        st.wish_direction(w, false, false).0
    }

    #[test]
    fn the_wish_turns_lambda_hat_by_the_chosen_angle_without_trigonometry() {
        use super::super::effects::{Effect, Effects};
        use super::super::vars::MovementVars;
        let vars = MovementVars::goldsrc(100.0);
        let ground_fx = Effects::from_list(&[Effect::GroundAccel, Effect::Friction]);
        let air: Stepper<f64> = Stepper::new(&vars, Effects::AIR_ONLY);
        let ground: Stepper<f64> = Stepper::new(&vars, ground_fx);
        let key_sets = [
            (0.0, 400.0),
            (400.0, 0.0),
            (400.0, -400.0),
            (-250.0, 100.0),
            (0.0, 0.0),
        ];
        let vels = [
            Vec2::new(320.0, 0.0),
            Vec2::new(-700.0, 150.0),
            Vec2::new(0.0, -20.0),
        ];
        for (st, on_ground) in [(&air, false), (&ground, true)] {
            for &(f, sm) in &key_sets {
                for &vel in &vels {
                    for side in [Side::Left, Side::Right] {
                        let s = PlayerState {
                            on_ground,
                            ..PlayerState::airborne(Vec2::ZERO, vel)
                        };
                        let keys = Wish {
                            forwardmove: f,
                            sidemove: sm,
                            ..strafe_keys(0.0)
                        };
                        let w = max_accel_wish(st, &s, keys, side, 1.0);
                        assert!((w.forward.length() - 1.0).abs() < 1e-15);
                        // The same frame planned through angles: Control::strafe at +-Theta.
                        let mut probe = s;
                        let law = st.prepare(&mut probe, &keys).map(|(_, l)| l);
                        let theta = law.map_or(0.0, |l| max_accel_theta(probe.vel.length(), l));
                        let by_angles =
                            Control::strafe(probe.vel, 1.0, side.sign() * theta, f, sm).wish();
                        assert!(
                            (w.forward - by_angles.forward).length() < 1e-12,
                            "{f} {sm} {vel:?} {side:?}: {:?} vs {:?}",
                            w.forward,
                            by_angles.forward
                        );
                        if f != 0.0 || sm != 0.0 {
                            let lambda_hat = probe.vel.normalized().unwrap_or(Vec2::new(1.0, 0.0));
                            let a = a_hat(st, &w);
                            assert!((a.dot(lambda_hat) - theta.cos()).abs() < 1e-12);
                            assert!(side.sign() * lambda_hat.cross(a) >= -1e-12);
                        }
                        // The control is the same wish with a yaw: one atan2 there, sin_cos back.
                        let c = max_accel_control(st, &s, keys, side, 1.0);
                        assert!((c.wish().forward - w.forward).length() < 1e-15);
                        assert_eq!((c.forwardmove, c.sidemove), (f, sm));
                    }
                }
            }
        }
    }

    #[test]
    fn at_zero_speed_the_heading_stands_in_for_the_velocity() {
        use super::super::effects::Effects;
        use super::super::vars::MovementVars;
        let st: Stepper<f64> = Stepper::new(&MovementVars::goldsrc(100.0), Effects::AIR_ONLY);
        let s = PlayerState::airborne(Vec2::ZERO, Vec2::ZERO);
        // At rest L - gamma1 = 30 - 32 < 0 is case 2: cos Theta = 0, the wish a quarter turn off the heading.
        let w = max_accel_wish(&st, &s, strafe_keys(400.0), Side::Left, 0.5);
        let a = a_hat(&st, &w);
        assert!((a - Vec2::from_angle(0.5 + std::f64::consts::FRAC_PI_2)).length() < 1e-12);
    }

    #[test]
    fn speed_preserving_keeps_the_speed_without_friction() {
        let l = law(30.0, 3.2);
        let c = speed_preserving_cos_theta(500.0, 500.0, l).unwrap_or(2.0);
        assert!((c + 3.2 / 1000.0).abs() < 1e-15);
        assert!((speed_after(500.0, c, l) - 500.0).abs() < 1e-9);
        // gamma1 > 2L: cos theta = -L/|v|.
        let l = law(30.0, 64.0);
        let c = speed_preserving_cos_theta(500.0, 500.0, l).unwrap_or(2.0);
        assert!((c + 30.0 / 500.0).abs() < 1e-15);
        assert!((speed_after(500.0, c, l) - 500.0).abs() < 1e-9);
    }
}
