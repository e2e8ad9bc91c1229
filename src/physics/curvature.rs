//! Curvature and the radius-speed relation (docs/physics.md section 9).
//!
//! Two radii are kept apart on purpose. The source text's relation
//! `r = (tau / sin theta)(2|v|^2/mu + 3|v| cos theta + mu)` gives about twice the radius of the path the
//! game actually draws; the first-order radius `tau |v'|^2 / (mu sin theta)` and the circle through three
//! simulated positions agree with each other. Corners are planned with the measured one.

use super::closed_form::strafing_effects;
use super::step::{AccelLaw, PlayerState, Side, Stepper};
use super::strafe::{max_accel, max_accel_wish, mu_at, strafe_keys};
use super::vars::MovementVars;
use super::vec2::Vec2;
use crate::error::{Error, Result};

/// The player hull's width, units (32 x 32 footprint).
pub const HULL_WIDTH_UNITS: f64 = 32.0;

/// Largest arc through a 90-degree bend of equal width `d` before and after, touching both outer walls and
/// the inner corner: `r = (2 + sqrt 2) d` (docs/physics.md section 9). Pass the width left for the hull centre.
pub fn bend_arc_radius(width_for_centre: f64) -> f64 {
    (2.0 + std::f64::consts::SQRT_2) * width_for_centre
}

/// Largest arc through a bend that turns the path by `turn_rad` (0 to pi), of equal width `d` before and
/// after, touching both outer walls and the inner corner: `r = d / (1 - cos(turn / 2))` (docs/physics.md
/// section 9; `(2 + sqrt 2) d` at 90 degrees, `d` for a U-turn). Infinite for no turn.
pub fn turn_arc_radius(width_for_centre: f64, turn_rad: f64) -> f64 {
    let room = 1.0 - (0.5 * turn_rad.clamp(0.0, std::f64::consts::PI)).cos();
    if room > 0.0 {
        width_for_centre / room
    } else {
        f64::INFINITY
    }
}

/// The source text's radius of the path over one frame (docs/physics.md section 9):
/// `r = (tau / sin theta)(2|v|^2/mu + 3|v| cos theta + mu)`. Infinite when `sin theta` or `mu` is zero.
pub fn radius_source_text(speed: f64, cos_theta: f64, mu: f64, tau_s: f64) -> f64 {
    let sin_theta = (1.0 - cos_theta * cos_theta).max(0.0).sqrt();
    if sin_theta <= 0.0 || mu <= 0.0 {
        return f64::INFINITY;
    }
    (tau_s / sin_theta) * (2.0 * speed * speed / mu + 3.0 * speed * cos_theta + mu)
}

/// The first-order radius of the discrete path (docs/physics.md section 9): the velocity turns by about
/// `mu sin theta / |v'|` per frame over a chord of `tau |v'|`, so `r = tau |v'|^2 / (mu sin theta)`.
pub fn radius_first_order(speed_after: f64, cos_theta: f64, mu: f64, tau_s: f64) -> f64 {
    let sin_theta = (1.0 - cos_theta * cos_theta).max(0.0).sqrt();
    if sin_theta <= 0.0 || mu <= 0.0 {
        return f64::INFINITY;
    }
    tau_s * speed_after * speed_after / (mu * sin_theta)
}

/// Radius of the circle through three points (infinite when they are collinear).
pub fn circumradius(a: Vec2, b: Vec2, c: Vec2) -> f64 {
    let (ab, bc, ca) = ((b - a).length(), (c - b).length(), (a - c).length());
    let twice_area = (b - a).cross(c - a).abs();
    if twice_area <= 0.0 {
        return f64::INFINITY;
    }
    ab * bc * ca / (2.0 * twice_area)
}

/// The airstrafing law of `vars` (full strafe key, airborne): `L = min(30, M)`, `gamma1 = k_e tau M A`.
pub fn air_law(vars: &MovementVars) -> AccelLaw {
    AccelLaw::air(vars, vars.maxspeed.min(vars.side_key_speed))
}

/// The groundstrafing law of `vars` (full strafe key, on the ground): `L = M`, `gamma1 = k_e tau M A`.
pub fn ground_law(vars: &MovementVars) -> AccelLaw {
    AccelLaw::ground(vars, vars.maxspeed.min(vars.side_key_speed))
}

/// All the radii of maximum-acceleration airstrafing at `speed` ups.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MaxAccelRadii {
    /// The maximum-acceleration angle, radians.
    pub theta_rad: f64,
    /// `mu` at that angle, ups.
    pub mu: f64,
    /// The source text's relation (type 1 or type 2 of section 9, whichever case applies).
    pub source_text: f64,
    /// The first-order radius `tau |v'|^2 / (mu sin theta)`.
    pub first_order: f64,
    /// The circle through the positions at 0, tau, 2 tau of a simulated run.
    pub measured: f64,
}

/// The radii of maximum-acceleration airstrafing at `speed` (docs/physics.md section 9).
///
/// # Example
/// At 500 ups and 100 fps (theta = 90 degrees) the relation gives 167 units, the game draws 83.8:
/// ```
/// use strafeopt::physics::{curvature::max_accel_radii, MovementVars};
/// let r = max_accel_radii(&MovementVars::goldsrc(100.0), 500.0);
/// assert_eq!(format!("{:.0} {:.1}", r.source_text, r.measured), "167 83.8");
/// ```
pub fn max_accel_radii(vars: &MovementVars, speed: f64) -> MaxAccelRadii {
    let law = air_law(vars);
    let tau = vars.frame_time_s();
    let m = max_accel(speed, law);
    let mu = mu_at(speed, m.cos_theta, law);
    MaxAccelRadii {
        theta_rad: m.cos_theta.clamp(-1.0, 1.0).acos(),
        mu,
        source_text: radius_source_text(speed, m.cos_theta, mu, tau),
        first_order: radius_first_order(m.speed, m.cos_theta, mu, tau),
        measured: measured_radius(vars, speed),
    }
}

/// The radius of the circle through the positions at 0, tau and 2 tau of maximum-acceleration airstrafing
/// from `speed` ups, simulated frame by frame (no velocity clamp).
pub fn measured_radius(vars: &MovementVars, speed: f64) -> f64 {
    let fx = strafing_effects(false, false);
    let stepper: Stepper<f64> = Stepper::new(vars, fx);
    let keys = strafe_keys(vars.side_key_speed);
    let mut s = PlayerState::airborne(Vec2::ZERO, Vec2::new(speed, 0.0));
    let mut pts = [Vec2::ZERO; 3];
    for p in pts.iter_mut() {
        *p = s.pos;
        let w = max_accel_wish(&stepper, &s, keys, Side::Left, 0.0);
        stepper.step(&mut s, &w);
    }
    circumradius(pts[0], pts[1], pts[2])
}

/// The speed whose measured maximum-acceleration radius is `radius` units, by bisection (the radius grows
/// monotonically with speed). Errors when `radius` is beyond what speeds up to `sv_maxvelocity` draw.
pub fn speed_for_radius(vars: &MovementVars, radius: f64) -> Result<f64> {
    invert_rising_branch(|v| measured_radius(vars, v), radius, vars.maxvelocity)
}

/// The speed whose radius by the source text's relation is `radius` (type 2 in closed form
/// `|v| = sqrt((L/2)(r/tau - L))`, type 1 by bisection).
pub fn speed_for_radius_source_text(vars: &MovementVars, radius: f64) -> Result<f64> {
    let law = air_law(vars);
    let tau = vars.frame_time_s();
    if law.gamma1 >= law.l && law.l > 0.0 {
        let v2 = 0.5 * law.l * (radius / tau - law.l);
        if v2 < 0.0 {
            return Err(Error::Unreachable {
                what: format!(
                    "radius {radius} is below the smallest the relation gives, tau L = {}",
                    tau * law.l
                ),
            });
        }
        return Ok(v2.sqrt());
    }
    invert_rising_branch(
        |v| {
            let m = max_accel(v, law);
            radius_source_text(v, m.cos_theta, mu_at(v, m.cos_theta, law), tau)
        },
        radius,
        vars.maxvelocity,
    )
}

/// [`speed_for_radius`] tabulated once for many radii: the measured radius (docs/physics.md section 9) at
/// [`RadiusSpeedTable::SPEEDS`] even steps of speed up to `sv_maxvelocity`, read back by linear
/// interpolation on its rising branch. A line of hundreds of points asks for the speed of each.
#[derive(Clone, Debug)]
pub struct RadiusSpeedTable {
    /// `(speed ups, measured radius units)` on the rising branch, slowest first.
    rising: Vec<(f64, f64)>,
}

impl RadiusSpeedTable {
    /// Speeds tabulated, evenly up to `sv_maxvelocity`.
    pub const SPEEDS: usize = 512;

    /// The table of `vars`.
    pub fn new(vars: &MovementVars) -> Self {
        let table: Vec<(f64, f64)> = (1..=Self::SPEEDS)
            .map(|j| {
                let v = vars.maxvelocity * j as f64 / Self::SPEEDS as f64;
                (v, measured_radius(vars, v))
            })
            .filter(|(_, r)| r.is_finite())
            .collect();
        // The rising branch: from the tightest radius on.
        let tightest = table
            .iter()
            .enumerate()
            .min_by(|a, b| a.1 .1.total_cmp(&b.1 .1))
            .map_or(0, |(i, _)| i);
        let mut rising: Vec<(f64, f64)> = Vec::with_capacity(table.len() - tightest);
        for &(v, r) in &table[tightest..] {
            if rising.last().is_none_or(|&(_, last)| r > last) {
                rising.push((v, r));
            }
        }
        RadiusSpeedTable { rising }
    }

    /// The speed whose maximum-acceleration radius is `radius_units`, ups: the tightest radius's speed
    /// below it, `None` where even `sv_maxvelocity` turns tighter (no limit).
    pub fn speed_for(&self, radius_units: f64) -> Option<f64> {
        let last = self.rising.last()?;
        if radius_units >= last.1 {
            return None;
        }
        let k = self.rising.partition_point(|&(_, r)| r <= radius_units);
        if k == 0 {
            return Some(self.rising[0].0);
        }
        let ((v0, r0), (v1, r1)) = (self.rising[k - 1], self.rising[k]);
        Some(v0 + (v1 - v0) * (radius_units - r0) / (r1 - r0))
    }
}

/// Solves `f(v) = target` for `v` in `(0, v_max]` on the branch where `f` increases. Below `L - gamma1`
/// maximum acceleration goes straight ahead (infinite radius), so the radius first falls with speed and then
/// rises: the smallest radius is located by a log-spaced scan refined by golden section, and the target is
/// bracketed above it.
fn invert_rising_branch(f: impl Fn(f64) -> f64, target: f64, v_max: f64) -> Result<f64> {
    const SCAN: usize = 400;
    let v_min_scan = 1e-3_f64;
    let ratio = (v_max / v_min_scan).powf(1.0 / SCAN as f64);
    let mut best = (v_max, f(v_max));
    let mut v = v_min_scan;
    for _ in 0..=SCAN {
        let r = f(v);
        if r < best.1 {
            best = (v, r);
        }
        v *= ratio;
    }
    let (mut a, mut b) = (
        (best.0 / ratio).max(v_min_scan),
        (best.0 * ratio).min(v_max),
    );
    let g = 0.5 * (5f64.sqrt() - 1.0);
    for _ in 0..100 {
        let (x1, x2) = (b - g * (b - a), a + g * (b - a));
        if f(x1) <= f(x2) {
            b = x2;
        } else {
            a = x1;
        }
    }
    let (mut lo, mut hi) = (0.5 * (a + b), v_max);
    let smallest = f(lo);
    let at_max = f(hi);
    if at_max.is_nan() || at_max < target {
        return Err(Error::Unreachable {
            what: format!(
                "radius {target} needs more than sv_maxvelocity = {v_max} ups (radius there {at_max:.3})"
            ),
        });
    }
    if smallest > target {
        return Err(Error::Unreachable {
            what: format!(
                "radius {target} is tighter than maximum acceleration ever turns (smallest {smallest:.4} at {lo:.4} ups)"
            ),
        });
    }
    for _ in 0..200 {
        let mid = 0.5 * (lo + hi);
        if f(mid) < target {
            lo = mid;
        } else {
            hi = mid;
        }
        if hi - lo <= 1e-12 * hi {
            break;
        }
    }
    Ok(0.5 * (lo + hi))
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f64::consts::{FRAC_PI_2, PI};

    #[test]
    fn the_tabulated_speed_of_a_radius_is_the_root_finders() {
        for (fps, airaccelerate) in [(100.0, 10.0), (100.0, 100.0), (1000.0, 10.0)] {
            let vars = MovementVars {
                airaccelerate,
                ..MovementVars::goldsrc(fps)
            };
            let table = RadiusSpeedTable::new(&vars);
            for radius in [60.0, 150.0, 400.0, 1000.0, 3000.0] {
                match (table.speed_for(radius), speed_for_radius(&vars, radius)) {
                    (Some(ours), Ok(theirs)) => assert!(
                        (ours - theirs).abs() < 0.002 * theirs,
                        "{fps} fps, aa {airaccelerate}, r {radius}: {ours} against {theirs}"
                    ),
                    // Both agree that no speed up to sv_maxvelocity turns that wide.
                    (None, Err(_)) => {}
                    (ours, theirs) => {
                        panic!("{fps} fps, aa {airaccelerate}, r {radius}: {ours:?} {theirs:?}")
                    }
                }
            }
            // Beyond the radius of sv_maxvelocity nothing limits the speed.
            let widest = measured_radius(&vars, vars.maxvelocity);
            assert_eq!(table.speed_for(1.01 * widest), None);
        }
    }

    #[test]
    fn the_turn_arc_is_the_bend_arc_at_90_degrees_and_the_width_for_a_u_turn() {
        assert!((turn_arc_radius(48.0, FRAC_PI_2) - bend_arc_radius(48.0)).abs() < 1e-9);
        assert!((turn_arc_radius(48.0, PI) - 48.0).abs() < 1e-9);
        // Sharper turns leave smaller arcs; no turn leaves any.
        assert!(turn_arc_radius(48.0, 2.5) < turn_arc_radius(48.0, 2.0));
        assert!(turn_arc_radius(48.0, 0.0).is_infinite());
    }
}
