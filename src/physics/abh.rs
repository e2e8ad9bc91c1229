//! The accelerated-backhop article's model (docs/physics.md section 11): each hop lasts a fixed time at constant
//! speed, and each backhop's jump boost maps `|v|` to `2|v| - 1.1 Mx`, clamped to `sv_maxvelocity`.

use super::real::Real;
use serde::Serialize;

/// One hop of the article's model.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct Hop {
    /// Time of the hop's jump after the first jump, seconds.
    pub time: f64,
    /// Distance covered when the hop starts, units.
    pub distance: f64,
    /// Speed during the hop, ups.
    pub speed: f64,
}

/// The article's table and its answer.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct AbhArticle {
    /// The hops up to and including the one in which the line is crossed.
    pub hops: Vec<Hop>,
    /// Time from the first jump to the line, seconds.
    pub crossing_time: f64,
    /// How far past the line the crossing hop lands, units.
    pub landing_past_line: f64,
}

/// The boost's signed addition along the view, ups (docs/physics.md section 11), for the effective forwardmove
/// `fm`, `p` (0.1 ducked or sprinting, else 0.5), max speed `mx` and horizontal speed `speed`:
/// `add = |Fm p|`, cut so the new speed does not pass `Mx (1 + p)`, negated for a backwards key. Written
/// once over [`Real`] for the frame step (`f64` and `f32`), the frame-level planners and the article's
/// model.
pub fn boost_add<R: Real>(fm: R, p: R, mx: R, speed: R) -> R {
    let mut add = (fm * p).abs();
    let cap = mx + mx * p;
    let new = add + speed;
    if new > cap {
        add -= new - cap;
    }
    if fm < R::ZERO {
        -add
    } else {
        add
    }
}

/// [`boost_add`] as the frame computes it from the keys: forwardmove scaled down to the max speed together
/// with sidemove (`CheckParameters`), cropped by `duck_crop` when ducked (`HandleDuckingSpeedCrop`),
/// `p = 0.1` ducked else `0.5`.
pub fn boost_add_from_keys<R: Real>(
    forwardmove: R,
    sidemove: R,
    mx: R,
    ducked: bool,
    duck_crop: R,
    speed: R,
) -> R {
    let len = forwardmove.hypot(sidemove);
    let mut fm = forwardmove;
    if len > mx {
        fm = fm * (mx / len);
    }
    if ducked {
        fm = fm * duck_crop;
    }
    let p = R::from_f64(if ducked { 0.1 } else { 0.5 });
    boost_add(fm, p, mx, speed)
}

/// Speed after a jump with the Source boost (docs/physics.md section 11) for forwardmove `fm` along the view,
/// speed `speed` along the view's axis, `p = 0.1` ducked or sprinting else `0.5`, max speed `mx`.
/// Facing backwards, `fm = 0`, ducked: `2|v| - 1.1 Mx` when `|v| > 1.1 Mx`.
pub fn boosted_speed(speed: f64, fm: f64, p: f64, mx: f64, facing_backwards: bool) -> f64 {
    let add = boost_add(fm, p, mx, speed);
    if facing_backwards {
        speed - add
    } else {
        speed + add
    }
}

/// The article's run (docs/physics.md section 11): walking at `max_speed`, a forward jump (`p = 0.5`,
/// `Fm = Mx`) gives `1.5 Mx`; then each ducked backhop (`Fm = 0`, `p = 0.1`) doubles the excess over
/// `1.1 Mx`, clamped to `max_velocity`; each hop lasts `hop_time_s` at constant speed. The table runs until
/// the hop in which `distance_units` is crossed.
///
/// # Example
/// The article's 100 m: the line is crossed 3.865 s after the first jump (section 12):
/// ```
/// let a = strafeopt::physics::abh::article_model(150.0, 0.51, 5249.34, 3500.0);
/// assert_eq!(format!("{:.3}", a.crossing_time), "3.865");
/// ```
pub fn article_model(
    max_speed: f64,
    hop_time_s: f64,
    distance_units: f64,
    max_velocity: f64,
) -> AbhArticle {
    let mut hops = Vec::new();
    let mut speed = boosted_speed(max_speed, max_speed, 0.5, max_speed, false).min(max_velocity);
    let (mut t, mut d) = (0.0, 0.0);
    // Speeds grow while above 1.1 Mx; otherwise the line is still reached at a constant speed.
    const MAX_HOPS: usize = 10_000;
    for _ in 0..MAX_HOPS {
        hops.push(Hop {
            time: t,
            distance: d,
            speed,
        });
        let end = d + speed * hop_time_s;
        if end >= distance_units || speed <= 0.0 {
            let crossing_time = if speed > 0.0 {
                t + (distance_units - d) / speed
            } else {
                f64::INFINITY
            };
            return AbhArticle {
                hops,
                crossing_time,
                landing_past_line: end - distance_units,
            };
        }
        t += hop_time_s;
        d = end;
        speed = boosted_speed(speed, 0.0, 0.1, max_speed, true).min(max_velocity);
    }
    AbhArticle {
        hops,
        crossing_time: f64::INFINITY,
        landing_past_line: f64::NAN,
    }
}
