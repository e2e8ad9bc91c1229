//! Walls as scenes give them: polylines or polygons in the plane, each a solid wall or a rule boundary
//! (docs/physics.md section 10), and the shape checks a wall must pass before a [`Corridor`] is built from it.
//!
//! [`Corridor`]: super::Corridor

use super::MIN_SEGMENT_LENGTH_UNITS;
use crate::physics::Vec2;
use parry2d::query::PointQuery;
use parry2d::shape::Segment;
use serde::{Deserialize, Serialize};
use std::fmt;

/// How a wall constrains the player (docs/physics.md section 10).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum BoundaryKind {
    /// A rule line (a lane marking): the hull must never overlap it. Touching it, or running exactly along
    /// it, is allowed. Nothing stops the player physically: a plan that crosses it is invalid.
    Rule,
    /// A solid wall: the game stops the hull at contact and clips the velocity (`PM_FlyMove`).
    Solid,
}

impl BoundaryKind {
    /// The name used in scene files.
    pub fn name(self) -> &'static str {
        match self {
            BoundaryKind::Rule => "rule",
            BoundaryKind::Solid => "solid",
        }
    }
}

/// A wall: a polyline through `points` (units), closed into a polygon when `closed` is set.
///
/// A closed wall is only its boundary: its inside is not filled, but since the hull can never cross the
/// boundary, a player who starts outside never gets in.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Wall {
    /// Vertices, units, in order.
    pub points: Vec<Vec2>,
    /// Join the last point back to the first.
    pub closed: bool,
    /// Solid wall or rule boundary.
    pub kind: BoundaryKind,
}

/// What is wrong with a wall's shape. Displays as the message of a scene error; [`WallDefect::point`]
/// gives the point to blame.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum WallDefect {
    /// Fewer points than a polyline (2) or polygon (3) needs.
    TooFewPoints {
        /// Points given.
        count: usize,
        /// Points needed.
        needed: usize,
    },
    /// A coordinate that is infinite or NaN.
    NonFinite {
        /// Index of the point.
        point: usize,
    },
    /// A segment no longer than [`MIN_SEGMENT_LENGTH_UNITS`] (segment `i` runs from point `i` to `i + 1`).
    ZeroLength {
        /// Index of the segment.
        segment: usize,
    },
    /// Two segments that cross or touch, other than neighbours meeting at their shared point, or
    /// neighbours that fold back onto each other.
    SelfIntersection {
        /// The earlier segment.
        first: usize,
        /// The later segment.
        second: usize,
    },
}

impl WallDefect {
    /// The index of the point where the defect starts (for finding its line in a file).
    pub fn point(&self) -> Option<usize> {
        match *self {
            WallDefect::TooFewPoints { .. } => None,
            WallDefect::NonFinite { point } => Some(point),
            WallDefect::ZeroLength { segment } => Some(segment),
            WallDefect::SelfIntersection { second, .. } => Some(second),
        }
    }
}

impl fmt::Display for WallDefect {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match *self {
            WallDefect::TooFewPoints { count, needed } => write!(
                f,
                "{count} point(s); a wall needs at least {needed} ({})",
                if needed == 2 {
                    "a polyline"
                } else {
                    "a closed polygon"
                }
            ),
            WallDefect::NonFinite { point } => {
                write!(f, "point {point} is not finite; coordinates must be finite numbers (units)")
            }
            WallDefect::ZeroLength { segment } => write!(
                f,
                "segment {segment} has zero length; each segment must be longer than {MIN_SEGMENT_LENGTH_UNITS:e} units"
            ),
            WallDefect::SelfIntersection { first, second } => write!(
                f,
                "segments {first} and {second} intersect; a wall must not cross or touch itself (split it into \
                 separate walls)"
            ),
        }
    }
}

impl Wall {
    /// Number of segments: `n - 1` for a polyline of `n` points, `n` when closed.
    pub fn segment_count(&self) -> usize {
        let n = self.points.len();
        match (n, self.closed) {
            (0 | 1, _) => 0,
            (_, false) => n - 1,
            (_, true) => n,
        }
    }

    /// Segment `i`: from point `i` to point `i + 1` (to point 0 for the closing segment).
    pub fn segment(&self, i: usize) -> (Vec2, Vec2) {
        let n = self.points.len();
        (self.points[i], self.points[(i + 1) % n])
    }

    /// Every segment in order.
    pub fn segments(&self) -> impl Iterator<Item = (Vec2, Vec2)> + '_ {
        (0..self.segment_count()).map(|i| self.segment(i))
    }

    /// The first shape defect, or `None` for a usable wall: at least 2 points (3 when closed), finite,
    /// every segment longer than [`MIN_SEGMENT_LENGTH_UNITS`], and no segment touching another except
    /// neighbours at their shared point. `O(n^2)` in the number of segments.
    pub fn defect(&self) -> Option<WallDefect> {
        let needed = if self.closed { 3 } else { 2 };
        if self.points.len() < needed {
            return Some(WallDefect::TooFewPoints {
                count: self.points.len(),
                needed,
            });
        }
        if let Some(point) = self.points.iter().position(|p| !p.is_finite()) {
            return Some(WallDefect::NonFinite { point });
        }
        let count = self.segment_count();
        if let Some(segment) = (0..count).find(|&i| {
            let (a, b) = self.segment(i);
            (b - a).length() <= MIN_SEGMENT_LENGTH_UNITS
        }) {
            return Some(WallDefect::ZeroLength { segment });
        }
        for j in 1..count {
            for i in 0..j {
                let (a, b) = self.segment(i);
                let (c, d) = self.segment(j);
                let bad = if j == i + 1 {
                    // Neighbours share b == c: they may not fold back onto each other.
                    point_segment_distance(a, c, d) <= MIN_SEGMENT_LENGTH_UNITS
                        || point_segment_distance(d, a, b) <= MIN_SEGMENT_LENGTH_UNITS
                } else if self.closed && i == 0 && j == count - 1 {
                    // The closing segment's end is segment 0's start.
                    point_segment_distance(b, c, d) <= MIN_SEGMENT_LENGTH_UNITS
                        || point_segment_distance(c, a, b) <= MIN_SEGMENT_LENGTH_UNITS
                } else {
                    segment_distance(a, b, c, d) <= MIN_SEGMENT_LENGTH_UNITS
                };
                if bad {
                    return Some(WallDefect::SelfIntersection {
                        first: i,
                        second: j,
                    });
                }
            }
        }
        None
    }
}

/// Distance from `p` to the segment `a`-`b`, units.
pub(crate) fn point_segment_distance(p: Vec2, a: Vec2, b: Vec2) -> f64 {
    use super::grown::to_parry;
    Segment::new(to_parry(a), to_parry(b)).distance_to_local_point(to_parry(p), true)
}

/// Distance between the segments `a`-`b` and `c`-`d`, units (0 when they cross).
pub(crate) fn segment_distance(a: Vec2, b: Vec2, c: Vec2, d: Vec2) -> f64 {
    let o1 = (b - a).cross(c - a);
    let o2 = (b - a).cross(d - a);
    let o3 = (d - c).cross(a - c);
    let o4 = (d - c).cross(b - c);
    if o1 * o2 < 0.0 && o3 * o4 < 0.0 {
        return 0.0;
    }
    point_segment_distance(a, c, d)
        .min(point_segment_distance(b, c, d))
        .min(point_segment_distance(c, a, b))
        .min(point_segment_distance(d, a, b))
}
