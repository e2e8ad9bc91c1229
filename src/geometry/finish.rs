//! The finish line and the moment a move crosses it.

use super::grown::GrownSegment;
use super::{CONTACT_TOL_UNITS, HULL_HALF_WIDTH_UNITS};
use crate::physics::Vec2;
use serde::{Deserialize, Serialize};

/// Which part of the player must cross the finish line.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum FinishPoint {
    /// The hull centre must reach the line.
    #[default]
    Centre,
    /// Any part of the 32 x 32 box touching the line counts (a trigger brush's behaviour).
    Hull,
}

/// The finish: the segment from `a` to `b` (units), and what must cross it.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct FinishLine {
    /// One end, units.
    pub a: Vec2,
    /// The other end, units.
    pub b: Vec2,
    /// What must cross.
    pub point: FinishPoint,
}

impl FinishLine {
    /// Length of the line, units.
    pub fn length_units(&self) -> f64 {
        (self.b - self.a).length()
    }

    /// The fraction in `[0, 1]` of the straight move from `p0` to `p1` (hull centre, units) at which the
    /// player first crosses the line, by this line's [`FinishPoint`] and the hull half-width
    /// [`HULL_HALF_WIDTH_UNITS`]; `None` if it does not.
    pub fn crossing_fraction(&self, p0: Vec2, p1: Vec2) -> Option<f64> {
        self.crossing_fraction_with(p0, p1, self.point, HULL_HALF_WIDTH_UNITS)
    }

    /// The fraction in `[0, 1]` of the straight move from `p0` to `p1` at which the point (for
    /// [`FinishPoint::Centre`]) or the axis-aligned box of half-width `half_width_units` around it (for
    /// [`FinishPoint::Hull`]) first touches the segment `a`-`b`; `None` if it never does.
    ///
    /// Touching counts (a move ending exactly on the line crosses it at fraction 1) and so does a start on
    /// the line (fraction 0). The test is made with [`CONTACT_TOL_UNITS`] of slack; the fraction returned is
    /// the exact one, clamped to `[0, 1]`. A move with a NaN or infinite end crosses nothing (it is a
    /// numerical failure, not a finish).
    pub fn crossing_fraction_with(
        &self,
        p0: Vec2,
        p1: Vec2,
        point: FinishPoint,
        half_width_units: f64,
    ) -> Option<f64> {
        if !(p0.is_finite() && p1.is_finite()) {
            return None;
        }
        let h = match point {
            FinishPoint::Centre => 0.0,
            FinishPoint::Hull => half_width_units.max(0.0),
        };
        let grown = GrownSegment::new(self.a, self.b, h);
        let d = p1 - p0;
        let iv = grown.open_interval(p0, d, -CONTACT_TOL_UNITS)?;
        if iv.lo.max(0.0) > iv.hi.min(1.0) {
            return None;
        }
        if grown.max_side(p0) <= 0.0 {
            return Some(0.0);
        }
        let t = grown.entry(p0, d).map_or(0.0, |(t, _)| t);
        Some(t.clamp(0.0, 1.0))
    }
}
