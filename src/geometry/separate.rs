//! Separating half-planes between a straight move of the hull centre and the grown walls (docs/physics.md
//! section 10): the linearised wall constraints of the optimiser. For a convex grown segment and a move
//! from `p0` to `p1` apart from it, the line through the closest point of the grown segment, normal to
//! the closest pair, has the whole grown segment on one side; keeping both ends of the move on the other
//! side keeps the whole straight move clear (a half-plane is convex).

use super::corridor::Corridor;
use super::grown::{move_box, GrownSegment, PLANE_COUNT};
use super::wall::BoundaryKind;
use crate::physics::Vec2;

/// The free side of a wall near a move: `normal . x >= offset`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct HalfPlane {
    /// Unit normal pointing away from the wall.
    pub normal: Vec2,
    /// Offset: the plane is `normal . x = offset`.
    pub offset: f64,
}

impl HalfPlane {
    /// Signed distance of `p` on the free side, units.
    #[inline]
    pub fn side(&self, p: Vec2) -> f64 {
        self.normal.dot(p) - self.offset
    }
}

/// One grown wall segment near a move.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Separation {
    /// The half-plane that separates the move from the wall (or, when they overlap, the wall face the move
    /// is least deep behind).
    pub plane: HalfPlane,
    /// Signed clearance of the move to the wall, units: the distance when apart, minus the depth (as the
    /// least-deep face sees it) when they overlap.
    pub clearance: f64,
    /// Index of the wall.
    pub wall: usize,
    /// Where along the move (0 at `p0`, 1 at `p1`) the clearance is measured: the clearance changes with
    /// the ends as `(1 - t) n` and `t n`.
    pub move_param: f64,
}

/// Closest points between segments `p0 p1` and `q0 q1` (Ericson, Real-Time Collision Detection 5.1.9).
fn closest_segment_segment(p0: Vec2, p1: Vec2, q0: Vec2, q1: Vec2) -> (Vec2, Vec2) {
    let d1 = p1 - p0;
    let d2 = q1 - q0;
    let r = p0 - q0;
    let a = d1.dot(d1);
    let e = d2.dot(d2);
    let f = d2.dot(r);
    let (s, t);
    if a <= f64::EPSILON && e <= f64::EPSILON {
        return (p0, q0);
    }
    if a <= f64::EPSILON {
        s = 0.0;
        t = (f / e).clamp(0.0, 1.0);
    } else {
        let c = d1.dot(r);
        if e <= f64::EPSILON {
            t = 0.0;
            s = (-c / a).clamp(0.0, 1.0);
        } else {
            let b = d1.dot(d2);
            let denom = a * e - b * b;
            let s0 = if denom > 0.0 {
                ((b * f - c * e) / denom).clamp(0.0, 1.0)
            } else {
                0.0
            };
            let t0 = (b * s0 + f) / e;
            if t0 < 0.0 {
                t = 0.0;
                s = (-c / a).clamp(0.0, 1.0);
            } else if t0 > 1.0 {
                t = 1.0;
                s = ((b - c) / a).clamp(0.0, 1.0);
            } else {
                t = t0;
                s = s0;
            }
        }
    }
    (p0 + d1 * s, q0 + d2 * t)
}

/// Below this distance, units, the closest pair gives no reliable direction and the face normal is used.
const DIRECTION_MIN_UNITS: f64 = 1e-7;

impl Corridor {
    /// The separations of the straight move `p0 -> p1` from every grown wall segment whose clearance to
    /// it is below `radius_units`, walls of `kind` only (all walls for `None`), appended to `out`.
    pub fn separations(
        &self,
        p0: Vec2,
        p1: Vec2,
        radius_units: f64,
        kind: Option<BoundaryKind>,
        out: &mut Vec<Separation>,
    ) {
        let (lo, hi) = move_box(p0, p1);
        let reach = Vec2::new(radius_units, radius_units);
        let (lo, hi) = (lo - reach, hi + reach);
        for piece in &self.pieces {
            if kind.is_some_and(|k| k != piece.kind) {
                continue;
            }
            let g = &piece.grown;
            // Cheap rejection: the grown segment's bounding box against the move's, grown by the radius.
            if !g.box_near(lo, hi, 0.0) {
                continue;
            }
            let (face, face_sep) = least_deep_face(g, p0, p1);
            let face_plane = HalfPlane {
                normal: g.planes[face].normal,
                offset: g.planes[face].offset,
            };
            let intersects = g
                .open_interval(p0, p1 - p0, 0.0)
                .is_some_and(|iv| iv.meets_unit_open())
                || g.max_side(p0) < 0.0;
            let sep = if intersects {
                let end_param = if g.side(face, p0) <= g.side(face, p1) {
                    0.0
                } else {
                    1.0
                };
                Separation {
                    plane: face_plane,
                    clearance: face_sep.min(0.0),
                    wall: piece.wall,
                    move_param: end_param,
                }
            } else {
                let near = nearest_separation(g, p0, p1, radius_units, face_plane, piece.wall);
                match near {
                    Some(sep) => sep,
                    None => continue,
                }
            };
            out.push(sep);
        }
    }

    /// The smallest clearance of the straight move `p0 -> p1` to any wall, up to `radius_units` (larger
    /// clearances are reported as `radius_units`).
    pub fn move_clearance(&self, p0: Vec2, p1: Vec2, radius_units: f64) -> f64 {
        let mut seps = Vec::new();
        self.separations(p0, p1, radius_units, None, &mut seps);
        seps.iter()
            .map(|s| s.clearance)
            .fold(radius_units, f64::min)
    }
}

/// The least-deep face of `g` for the move `p0 -> p1`: the plane both ends are furthest outside, and
/// how far (the smaller of the two ends' distances).
#[inline]
fn least_deep_face(g: &GrownSegment, p0: Vec2, p1: Vec2) -> (usize, f64) {
    let (mut face, mut face_sep) = (0, f64::NEG_INFINITY);
    for i in 0..PLANE_COUNT {
        let sep = g.side(i, p0).min(g.side(i, p1));
        if sep > face_sep {
            face_sep = sep;
            face = i;
        }
    }
    (face, face_sep)
}

/// The separation of a move `p0 -> p1` clear of `g` (wall `wall`): the plane through the nearest point
/// of `g`'s boundary normal to the gap (`face_plane` where the gap is too short to give a direction),
/// the gap as its clearance, and where along the move its nearest point lies; `None` when the gap is
/// over `radius_units`.
#[inline]
fn nearest_separation(
    g: &GrownSegment,
    p0: Vec2,
    p1: Vec2,
    radius_units: f64,
    face_plane: HalfPlane,
    wall: usize,
) -> Option<Separation> {
    let verts = g.vertices();
    let n = verts.len();
    let mut best = (f64::INFINITY, Vec2::ZERO, Vec2::ZERO);
    for i in 0..n {
        let (x, y) = closest_segment_segment(p0, p1, verts[i], verts[(i + 1) % n]);
        let d = (x - y).length();
        if d < best.0 {
            best = (d, x, y);
        }
    }
    let (d, x, y) = best;
    if d > radius_units {
        return None;
    }
    let mv = p1 - p0;
    let t = if mv.length_squared() > 0.0 {
        ((x - p0).dot(mv) / mv.length_squared()).clamp(0.0, 1.0)
    } else {
        0.0
    };
    let plane = if d < DIRECTION_MIN_UNITS {
        face_plane
    } else {
        let normal = (x - y) * (1.0 / d);
        HalfPlane {
            normal,
            offset: normal.dot(y),
        }
    };
    Some(Separation {
        plane,
        clearance: d,
        wall,
        move_param: t,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::Wall;
    use crate::test_stream::Stream;

    fn corridor() -> Corridor {
        // One horizontal rule line along y = 0 from x = 0 to 100, and a square post at (200, 50).
        let walls = [
            Wall {
                points: vec![Vec2::new(0.0, 0.0), Vec2::new(100.0, 0.0)],
                closed: false,
                kind: BoundaryKind::Rule,
            },
            Wall {
                points: vec![
                    Vec2::new(190.0, 40.0),
                    Vec2::new(210.0, 40.0),
                    Vec2::new(210.0, 60.0),
                    Vec2::new(190.0, 60.0),
                ],
                closed: true,
                kind: BoundaryKind::Rule,
            },
        ];
        Corridor::new(&walls).unwrap_or_else(|e| panic!("{e}"))
    }

    #[test]
    fn clearance_matches_sampled_points_and_planes_separate() {
        let c = corridor();
        let mut stream = Stream(7);
        let mut rnd = || stream.next();
        for _ in 0..2000 {
            let p0 = Vec2::new(rnd() * 300.0 - 20.0, rnd() * 120.0 - 30.0);
            let p1 = p0 + Vec2::new(rnd() * 40.0 - 20.0, rnd() * 40.0 - 20.0);
            let clearance = c.move_clearance(p0, p1, 1e3);
            // Sampled: the smallest point clearance along the move (point clearances are exact).
            let sampled = (0..=400)
                .map(|i| c.clearance(p0 + (p1 - p0) * (i as f64 / 400.0)))
                .fold(f64::INFINITY, f64::min);
            if sampled > 1e-6 {
                // Apart: the exact distance is at most every sample and within a sample step of the least.
                assert!(clearance <= sampled + 1e-9, "{clearance} > {sampled}");
                assert!(clearance >= sampled - 0.06 * (p1 - p0).length() - 1e-9);
                let mut seps = Vec::new();
                c.separations(p0, p1, 1e3, None, &mut seps);
                for s in seps {
                    // Both ends on the free side: the straight move is clear of that wall.
                    assert!(s.plane.side(p0) >= -1e-9 && s.plane.side(p1) >= -1e-9);
                }
            } else if sampled < -1e-6 {
                assert!(
                    clearance <= 0.0,
                    "overlap not seen: {clearance} vs {sampled}"
                );
            }
        }
    }
}
