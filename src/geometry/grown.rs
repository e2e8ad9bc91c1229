//! A wall segment grown by the player's box: the Minkowski sum of a segment and an axis-aligned square,
//! the set of hull centres at which the hull overlaps or touches the segment (docs/physics.md section 10).
//!
//! The sum of two convex polygons has as edge normals the union of theirs, and each edge's offset is the
//! sum of the two support functions. So the grown segment is exactly the intersection of six half-planes
//! `n . x <= c`: normals `+x`, `-x`, `+y`, `-y` (the box) and `+n`, `-n` (the segment's normal), with
//! `c = support_segment(n) + h (|n_x| + |n_y|)`. For an axis-aligned segment two pairs coincide (a
//! rectangle). With `h = 0` the six half-planes describe the segment itself.
//!
//! Every query is a handful of dot products: inside tests, signed distances and the time at which a moving
//! centre enters (Cyrus-Beck clipping), all exact up to `f64` rounding.

use crate::physics::Vec2;
use parry2d::math::Vector;
use parry2d::query::PointQuery;
use parry2d::shape::{Cuboid, Segment};

/// Half-planes of a grown segment: four from the box, two from the segment.
pub(crate) const PLANE_COUNT: usize = 6;

/// A half-plane `normal . x <= offset`, `normal` a unit vector pointing out of the grown segment.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Plane {
    pub normal: Vec2,
    pub offset: f64,
}

/// How far, units, beyond a grown segment's bounding box a move's box still counts as near for the
/// simulation's wall tests ([`GrownSegment::box_near`]): far more than rounding in the planes' sides could
/// reach at corridor coordinates.
pub(crate) const BOX_NEAR_UNITS: f64 = 1.0;

/// The bounding box of the straight move from `p0` to `p1`: its lowest and highest corners.
#[inline]
pub(crate) fn move_box(p0: Vec2, p1: Vec2) -> (Vec2, Vec2) {
    (
        Vec2::new(p0.x.min(p1.x), p0.y.min(p1.y)),
        Vec2::new(p0.x.max(p1.x), p0.y.max(p1.y)),
    )
}

/// A segment grown by an axis-aligned box of half-width `half_width_units`.
#[derive(Clone, Debug)]
pub(crate) struct GrownSegment {
    pub a: Vec2,
    pub b: Vec2,
    pub planes: [Plane; PLANE_COUNT],
    segment: Segment,
    hull: Cuboid,
    /// The corners, anticlockwise ([`GrownSegment::vertices`]): found once, as the wall rows of every
    /// sub-problem read them.
    corners: Vec<Vec2>,
}

/// The open interval of times `t` (over all reals) during which a moving point is strictly inside a grown
/// segment.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Interval {
    pub lo: f64,
    pub hi: f64,
}

impl Interval {
    /// True when the open interval meets the open interval `(0, 1)`: the move from `t = 0` to `t = 1` is
    /// strictly inside for some time of positive length.
    #[inline]
    pub fn meets_unit_open(&self) -> bool {
        self.lo.max(0.0) < self.hi.min(1.0)
    }
}

pub(crate) fn to_parry(v: Vec2) -> Vector {
    Vector::new(v.x, v.y)
}

impl GrownSegment {
    /// The segment from `a` to `b` (distinct points) grown by a box of half-width `half_width_units >= 0`.
    pub fn new(a: Vec2, b: Vec2, half_width_units: f64) -> Self {
        let h = half_width_units;
        let e = b - a;
        // Callers pass segments longer than MIN_SEGMENT_LENGTH_UNITS; the fallback keeps a valid (box) shape.
        let n = e.perp().normalized().unwrap_or(Vec2::new(0.0, 1.0));
        let box_support_n = h * (n.x.abs() + n.y.abs());
        let planes = [
            Plane {
                normal: Vec2::new(1.0, 0.0),
                offset: a.x.max(b.x) + h,
            },
            Plane {
                normal: Vec2::new(-1.0, 0.0),
                offset: -a.x.min(b.x) + h,
            },
            Plane {
                normal: Vec2::new(0.0, 1.0),
                offset: a.y.max(b.y) + h,
            },
            Plane {
                normal: Vec2::new(0.0, -1.0),
                offset: -a.y.min(b.y) + h,
            },
            Plane {
                normal: n,
                offset: n.dot(a) + box_support_n,
            },
            Plane {
                normal: -n,
                offset: -n.dot(a) + box_support_n,
            },
        ];
        GrownSegment {
            a,
            b,
            planes,
            segment: Segment::new(to_parry(a), to_parry(b)),
            hull: Cuboid::new(Vector::new(h, h)),
            corners: box_swept_corners(a, b, h),
        }
    }

    /// Signed distance of `p` past plane `i` (positive outside), units.
    #[inline]
    pub fn side(&self, i: usize, p: Vec2) -> f64 {
        let pl = &self.planes[i];
        pl.normal.dot(p) - pl.offset
    }

    /// The largest plane distance: negative exactly when `p` is strictly inside, and then minus the depth.
    #[inline]
    pub fn max_side(&self, p: Vec2) -> f64 {
        (0..PLANE_COUNT)
            .map(|i| self.side(i, p))
            .fold(f64::NEG_INFINITY, f64::max)
    }

    /// Signed distance from the hull centred at `p` to the segment, units: the gap when apart, 0 when
    /// touching, minus the penetration depth (the shortest move that separates them) when overlapping.
    pub fn signed_distance(&self, p: Vec2) -> f64 {
        let m = self.max_side(p);
        if m < 0.0 {
            // Inside a convex polygon the nearest boundary point lies on the nearest supporting line.
            return m;
        }
        // Apart (or touching): the closest pair has a vertex of one shape, so check the hull's corners
        // against the segment and the segment's ends against the hull.
        let h = self.hull.half_extents.x;
        let corners = [
            Vec2::new(h, h),
            Vec2::new(h, -h),
            Vec2::new(-h, h),
            Vec2::new(-h, -h),
        ];
        let from_corners = corners
            .iter()
            .map(|&c| self.segment.distance_to_local_point(to_parry(p + c), true))
            .fold(f64::INFINITY, f64::min);
        let from_ends = [self.a, self.b]
            .iter()
            .map(|&e| self.hull.distance_to_local_point(to_parry(e - p), true))
            .fold(f64::INFINITY, f64::min);
        from_corners.min(from_ends)
    }

    /// Whether the box from `lo` to `hi` comes within `margin_units` of this grown segment's bounding
    /// box. A move whose box does not cannot enter the segment, so a test may skip its planes. A box
    /// with a coordinate that is not a number counts as near: its planes decide.
    #[inline]
    pub fn box_near(&self, lo: Vec2, hi: Vec2, margin_units: f64) -> bool {
        let half = self.hull.half_extents;
        let (reach_x, reach_y) = (half.x + margin_units, half.y + margin_units);
        !(self.a.x.max(self.b.x) + reach_x < lo.x
            || self.a.x.min(self.b.x) - reach_x > hi.x
            || self.a.y.max(self.b.y) + reach_y < lo.y
            || self.a.y.min(self.b.y) - reach_y > hi.y)
    }

    /// Times at which `p + t d` is strictly inside this grown segment shrunk by `shrink_units` (a negative
    /// value grows it), or `None` when it never is.
    pub fn open_interval(&self, p: Vec2, d: Vec2, shrink_units: f64) -> Option<Interval> {
        let mut lo = f64::NEG_INFINITY;
        let mut hi = f64::INFINITY;
        for i in 0..PLANE_COUNT {
            let s = self.side(i, p) + shrink_units;
            let r = self.planes[i].normal.dot(d);
            if r == 0.0 {
                // Parallel (exactly: also a zero move): inside this half-plane for all t, or never.
                if s >= 0.0 {
                    return None;
                }
                continue;
            }
            let t = -s / r;
            if r < 0.0 {
                lo = lo.max(t);
            } else if t < hi {
                hi = t;
            }
        }
        (lo < hi).then_some(Interval { lo, hi })
    }

    /// The time at which `p + t d` reaches the (unshrunk) boundary on its way in, and the plane crossed:
    /// the largest entry time over the planes the move heads into. `None` when the move heads into none.
    pub fn entry(&self, p: Vec2, d: Vec2) -> Option<(f64, usize)> {
        let mut best: Option<(f64, usize)> = None;
        for i in 0..PLANE_COUNT {
            let r = self.planes[i].normal.dot(d);
            if r < 0.0 {
                let t = -self.side(i, p) / r;
                if best.is_none_or(|(bt, _)| t > bt) {
                    best = Some((t, i));
                }
            }
        }
        best
    }

    /// The grown segment's corners, anticlockwise (4 for an axis-aligned segment, else 6).
    pub fn vertices(&self) -> &[Vec2] {
        &self.corners
    }
}

/// The corners of the box of half-width `h` swept from `a` to `b`: the convex hull of the box's corners
/// at both ends.
fn box_swept_corners(a: Vec2, b: Vec2, h: f64) -> Vec<Vec2> {
    let mut pts = Vec::with_capacity(8);
    for e in [a, b] {
        for (sx, sy) in [(1.0, 1.0), (1.0, -1.0), (-1.0, 1.0), (-1.0, -1.0)] {
            pts.push(e + Vec2::new(sx * h, sy * h));
        }
    }
    convex_hull(pts)
}

/// Convex hull of a few points (Andrew's monotone chain), anticlockwise, collinear points dropped.
fn convex_hull(mut pts: Vec<Vec2>) -> Vec<Vec2> {
    pts.sort_by(|p, q| p.x.total_cmp(&q.x).then(p.y.total_cmp(&q.y)));
    pts.dedup();
    if pts.len() < 3 {
        return pts;
    }
    let turn = |o: Vec2, a: Vec2, b: Vec2| (a - o).cross(b - o);
    let mut hull: Vec<Vec2> = Vec::with_capacity(pts.len() + 1);
    for pass in 0..2 {
        let start = hull.len();
        let iter: Box<dyn Iterator<Item = &Vec2>> = if pass == 0 {
            Box::new(pts.iter())
        } else {
            Box::new(pts.iter().rev())
        };
        for &p in iter {
            while hull.len() >= start + 2
                && turn(hull[hull.len() - 2], hull[hull.len() - 1], p) <= 0.0
            {
                hull.pop();
            }
            hull.push(p);
        }
        hull.pop();
    }
    hull
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::test_stream::Stream;

    #[test]
    fn diagonal_segment_grows_to_a_hexagon() {
        let g = GrownSegment::new(Vec2::new(0.0, 0.0), Vec2::new(100.0, 100.0), 16.0);
        assert_eq!(g.vertices().len(), 6);
        let r = GrownSegment::new(Vec2::new(0.0, 0.0), Vec2::new(100.0, 0.0), 16.0);
        assert_eq!(r.vertices().len(), 4);
    }

    #[test]
    fn a_move_whose_box_is_not_near_never_enters_the_segment() {
        // Segments of every direction and moves of every length about them, from a fixed seed: wherever
        // the boxes are far apart, the planes say the move never enters either, so skipping them changes
        // no verdict; some moves are culled and some enter, so both branches are met.
        let mut stream = Stream(2026);
        let (mut culled, mut entered) = (0, 0);
        for _ in 0..20_000 {
            let mut point = |spread: f64| {
                let half = 0.5 * spread;
                Vec2::new(stream.within(-half, half), stream.within(-half, half))
            };
            let (a, b) = (point(400.0), point(400.0));
            let g = GrownSegment::new(a, b, 16.0);
            let p0 = point(600.0);
            let p1 = p0 + point(300.0);
            let enters = g
                .open_interval(p0, p1 - p0, 0.0)
                .is_some_and(|iv| iv.meets_unit_open());
            let (lo, hi) = move_box(p0, p1);
            if !g.box_near(lo, hi, BOX_NEAR_UNITS) {
                culled += 1;
                assert!(!enters, "{a:?}-{b:?}: {p0:?} -> {p1:?}");
            }
            entered += usize::from(enters);
        }
        assert!(
            culled > 1000 && entered > 1000,
            "{culled} culled, {entered} entered"
        );
    }

    #[test]
    fn a_box_touching_the_grown_segments_box_is_near() {
        // The segment (0, 0)-(100, 0) grown by 16: its box is x in [-16, 116], y in [-16, 16].
        let g = GrownSegment::new(Vec2::new(0.0, 0.0), Vec2::new(100.0, 0.0), 16.0);
        let near = |lo: (f64, f64), hi: (f64, f64)| {
            g.box_near(Vec2::new(lo.0, lo.1), Vec2::new(hi.0, hi.1), BOX_NEAR_UNITS)
        };
        assert!(near((116.5, 0.0), (200.0, 1.0)));
        assert!(!near((117.5, 0.0), (200.0, 1.0)));
        assert!(near((0.0, -40.0), (1.0, -16.5)));
        assert!(!near((0.0, -40.0), (1.0, -17.5)));
        assert!(near((-30.0, -30.0), (130.0, 30.0)));
        // Without the margin the box itself is the edge; a box not a number is left to the planes.
        assert!(g.box_near(Vec2::new(116.0, 0.0), Vec2::new(200.0, 1.0), 0.0));
        assert!(!g.box_near(Vec2::new(116.5, 0.0), Vec2::new(200.0, 1.0), 0.0));
        assert!(near((f64::NAN, 0.0), (f64::NAN, 1.0)));
    }

    #[test]
    fn signed_distance_is_continuous_across_the_boundary() {
        let g = GrownSegment::new(Vec2::new(0.0, 0.0), Vec2::new(100.0, 0.0), 16.0);
        assert!((g.signed_distance(Vec2::new(50.0, 20.0)) - 4.0).abs() < 1e-12);
        assert!(g.signed_distance(Vec2::new(50.0, 16.0)).abs() < 1e-12);
        assert!((g.signed_distance(Vec2::new(50.0, 15.0)) + 1.0).abs() < 1e-12);
        // Beyond the end, diagonally off the corner of the rectangle.
        assert!((g.signed_distance(Vec2::new(119.0, 20.0)) - 5.0).abs() < 1e-12);
    }
}
