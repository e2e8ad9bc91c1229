//! A generated corridor's centre line and walls, and the test that it never overlaps itself.
//!
//! The centre line is straight legs joined by circular turns. A turn of `theta` degrees to one side goes
//! around a pivot on that side, at `radius = (width + gap) / 2` from the centre line, so that a 180-degree
//! turn brings the corridor back alongside itself with a divider `gap` units thick between the two legs
//! (the shipped hairpin's shape). The walls are the centre line's offsets by half the width: on the inner
//! side of a turn an arc of radius `gap / 2` around the pivot (a polygon on the arc, a point per 90
//! degrees or part of it), on the outer side the arc of radius `width + gap / 2` (a polygon around the arc,
//! its corners at most `gap / 4` outside it). Both keep the corridor at least `width` wide everywhere.
//!
//! Two parts of the corridor that are not neighbours along it (a leg and the turn after next, two legs
//! with a leg between them) must keep their centre lines `width + gap` apart: [`overlaps_itself`]. Their
//! walls are then at least `gap / 2` apart (less the outer corners' `gap / 4` on each side) and never
//! cross.

use crate::physics::Vec2;

/// Largest angle of a chord standing for a turn in the overlap test, degrees.
const CHORD_STEP_DEG: f64 = 3.0;

/// Largest angle of a turn's inner wall between two points, degrees.
const INNER_POINT_STEP_DEG: f64 = 90.0;

/// How far a corner of a turn's outer wall may stand outside the arc, as a share of the wall gap.
const OUTER_CORNER_SHARE_OF_GAP: f64 = 0.25;

/// Steps of a polygon around an arc of `radius` turning `sweep_rad` whose corners stand at most
/// `overshoot` outside it: each step's half angle `a` has `radius (1 / cos a - 1) <= overshoot`.
fn outer_steps(sweep_rad: f64, radius: f64, overshoot: f64) -> usize {
    let cos_half = (radius / (radius + overshoot)).clamp(-1.0, 1.0);
    let max_step = 2.0 * cos_half.acos();
    if max_step > 0.0 {
        (sweep_rad.abs() / max_step).ceil().max(1.0) as usize
    } else {
        1
    }
}

/// One piece of a centre line, in the order the corridor is run.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum CentrelinePiece {
    /// A straight leg from `from` to `to`, units.
    Leg {
        /// Where the leg starts.
        from: Vec2,
        /// Where it ends.
        to: Vec2,
    },
    /// A circular turn around `pivot`.
    Turn {
        /// Centre of the turn, units.
        pivot: Vec2,
        /// Radius of the centre line around the pivot, units.
        radius_units: f64,
        /// Direction from the pivot to the turn's first point, radians anticlockwise from +x.
        start_angle_rad: f64,
        /// Angle turned, radians: positive to the left (anticlockwise), negative to the right.
        sweep_rad: f64,
    },
}

impl CentrelinePiece {
    /// The piece as a polyline: a leg's two ends, or a turn's points at most [`CHORD_STEP_DEG`] apart,
    /// with the largest distance from a chord to the arc (its sagitta), units.
    fn polyline(&self) -> (Vec<Vec2>, f64) {
        match *self {
            CentrelinePiece::Leg { from, to } => (vec![from, to], 0.0),
            CentrelinePiece::Turn {
                pivot,
                radius_units,
                start_angle_rad,
                sweep_rad,
            } => {
                let steps = (sweep_rad.abs().to_degrees() / CHORD_STEP_DEG)
                    .ceil()
                    .max(1.0) as usize;
                let step = sweep_rad / steps as f64;
                let points = (0..=steps)
                    .map(|j| {
                        pivot + Vec2::from_angle(start_angle_rad + step * j as f64) * radius_units
                    })
                    .collect();
                (points, radius_units * (1.0 - (step / 2.0).cos()))
            }
        }
    }
}

/// The side a turn goes to.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum Side {
    /// Anticlockwise.
    Left,
    /// Clockwise.
    Right,
}

impl Side {
    /// +1 for left, -1 for right.
    fn sign(self) -> f64 {
        match self {
            Side::Left => 1.0,
            Side::Right => -1.0,
        }
    }

    /// The name used in files and tables.
    pub fn name(self) -> &'static str {
        match self {
            Side::Left => "left",
            Side::Right => "right",
        }
    }
}

/// A corridor's shape: straight legs (units) and the turns between them (one fewer).
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct Shape<'a> {
    pub width_units: f64,
    pub gap_units: f64,
    pub legs_units: &'a [u32],
    pub turns: &'a [(u32, Side)],
}

/// A corridor laid out from its shape: the start of the first leg at the origin, heading along +x.
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct Layout {
    pub pieces: Vec<CentrelinePiece>,
    /// The left wall (seen running the corridor), from the start to the finish.
    pub left: Vec<Vec2>,
    /// The right wall, from the start to the finish.
    pub right: Vec<Vec2>,
}

/// The unit vector to the left of `direction`.
fn left_of(direction: Vec2) -> Vec2 {
    Vec2::new(-direction.y, direction.x)
}

/// Lays out `shape` (see the module documentation).
pub(crate) fn lay_out(shape: &Shape<'_>) -> Layout {
    let half = shape.width_units / 2.0;
    let radius = (shape.width_units + shape.gap_units) / 2.0;
    let inner_radius = shape.gap_units / 2.0;
    let outer_radius = shape.width_units + shape.gap_units / 2.0;
    let mut heading_rad = 0.0_f64;
    let mut at = Vec2::ZERO;
    let mut pieces = Vec::new();
    let mut left = vec![at + left_of(Vec2::from_angle(heading_rad)) * half];
    let mut right = vec![at - left_of(Vec2::from_angle(heading_rad)) * half];
    for (i, &leg) in shape.legs_units.iter().enumerate() {
        let direction = Vec2::from_angle(heading_rad);
        let end = at + direction * f64::from(leg);
        pieces.push(CentrelinePiece::Leg { from: at, to: end });
        at = end;
        let Some(&(degrees, side)) = shape.turns.get(i) else {
            left.push(at + left_of(direction) * half);
            right.push(at - left_of(direction) * half);
            break;
        };
        let sign = side.sign();
        let sweep_rad = sign * f64::from(degrees).to_radians();
        let pivot = at + left_of(direction) * (sign * radius);
        let start_angle_rad = (at - pivot).angle();
        pieces.push(CentrelinePiece::Turn {
            pivot,
            radius_units: radius,
            start_angle_rad,
            sweep_rad,
        });
        // Inner wall: points on the arc of radius gap / 2, the ends included.
        let inner_steps = (f64::from(degrees) / INNER_POINT_STEP_DEG).ceil().max(1.0) as usize;
        let step = sweep_rad / inner_steps as f64;
        let inner: Vec<Vec2> = (0..=inner_steps)
            .map(|j| pivot + Vec2::from_angle(start_angle_rad + step * j as f64) * inner_radius)
            .collect();
        // Outer wall: the corners where the tangents at the step ends meet; the tangent points lie on the
        // straight walls between them.
        let steps = outer_steps(
            sweep_rad,
            outer_radius,
            OUTER_CORNER_SHARE_OF_GAP * shape.gap_units,
        );
        let step = sweep_rad / steps as f64;
        let corner_radius = outer_radius / (step / 2.0).cos();
        let outer: Vec<Vec2> = (0..steps)
            .map(|j| {
                pivot + Vec2::from_angle(start_angle_rad + step * (j as f64 + 0.5)) * corner_radius
            })
            .collect();
        match side {
            Side::Left => {
                left.extend(inner);
                right.extend(outer);
            }
            Side::Right => {
                right.extend(inner);
                left.extend(outer);
            }
        }
        heading_rad += sweep_rad;
        at = pivot + Vec2::from_angle(start_angle_rad + sweep_rad) * radius;
    }
    Layout {
        pieces,
        left,
        right,
    }
}

/// Distance between the segments `a0 a1` and `b0 b1`, units (0 when they cross).
fn segment_distance(a0: Vec2, a1: Vec2, b0: Vec2, b1: Vec2) -> f64 {
    let side = |p: Vec2, q0: Vec2, q1: Vec2| (q1 - q0).cross(p - q0);
    let (d1, d2) = (side(b0, a0, a1), side(b1, a0, a1));
    let (d3, d4) = (side(a0, b0, b1), side(a1, b0, b1));
    if d1 * d2 < 0.0 && d3 * d4 < 0.0 {
        return 0.0;
    }
    point_segment_distance(a0, b0, b1)
        .min(point_segment_distance(a1, b0, b1))
        .min(point_segment_distance(b0, a0, a1))
        .min(point_segment_distance(b1, a0, a1))
}

/// Distance from `p` to the segment `q0 q1`, units.
pub(crate) fn point_segment_distance(p: Vec2, q0: Vec2, q1: Vec2) -> f64 {
    let d = q1 - q0;
    let len2 = d.length_squared();
    let t = if len2 > 0.0 {
        ((p - q0).dot(d) / len2).clamp(0.0, 1.0)
    } else {
        0.0
    };
    (q0 + d * t - p).length()
}

/// The smallest box around `points`: its low and high corners.
fn bounding_box(points: &[Vec2]) -> (Vec2, Vec2) {
    points.iter().fold(
        (
            Vec2::new(f64::INFINITY, f64::INFINITY),
            Vec2::new(f64::NEG_INFINITY, f64::NEG_INFINITY),
        ),
        |(lo, hi), p| {
            (
                Vec2::new(lo.x.min(p.x), lo.y.min(p.y)),
                Vec2::new(hi.x.max(p.x), hi.y.max(p.y)),
            )
        },
    )
}

/// Distance between two boxes (0 when they overlap), a lower bound of the distance between what they hold.
fn box_distance(a: (Vec2, Vec2), b: (Vec2, Vec2)) -> f64 {
    let dx = (b.0.x - a.1.x).max(a.0.x - b.1.x).max(0.0);
    let dy = (b.0.y - a.1.y).max(a.0.y - b.1.y).max(0.0);
    dx.hypot(dy)
}

/// Distance between two polylines, units.
fn polyline_distance(a: &[Vec2], b: &[Vec2]) -> f64 {
    let mut best = f64::INFINITY;
    for sa in a.windows(2) {
        for sb in b.windows(2) {
            best = best.min(segment_distance(sa[0], sa[1], sb[0], sb[1]));
        }
    }
    best
}

/// Pieces this far apart along the centre line or more must keep `width + gap` apart: a leg, the turn
/// after it and the next leg touch by construction.
const FIRST_SEPARATED_PIECE: usize = 3;

/// True when two pieces of the centre line that are not neighbours come closer than `width + gap`
/// (less the chords' sagittas and 1e-6 units of rounding): their walls would be less than `gap` apart or
/// cross.
pub(crate) fn overlaps_itself(
    pieces: &[CentrelinePiece],
    width_units: f64,
    gap_units: f64,
) -> bool {
    let lines: Vec<(Vec<Vec2>, f64, (Vec2, Vec2))> = pieces
        .iter()
        .map(|p| {
            let (points, sagitta) = p.polyline();
            let bounds = bounding_box(&points);
            (points, sagitta, bounds)
        })
        .collect();
    let required = width_units + gap_units - 1e-6;
    lines.iter().enumerate().any(|(i, (a, sa, ba))| {
        lines
            .iter()
            .skip(i + FIRST_SEPARATED_PIECE)
            .any(|(b, sb, bb)| {
                let need = required - sa - sb;
                box_distance(*ba, *bb) < need && polyline_distance(a, b) < need
            })
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn close(a: Vec2, b: Vec2) -> bool {
        (a - b).length() < 1e-9
    }

    #[test]
    fn a_left_90_turn_goes_around_its_pivot() {
        // Width 128, gap 16: radius 72, pivot 72 to the left of the first leg's end.
        let legs = [500, 400];
        let turns = [(90, Side::Left)];
        let l = lay_out(&Shape {
            width_units: 128.0,
            gap_units: 16.0,
            legs_units: &legs,
            turns: &turns,
        });
        assert_eq!(l.pieces.len(), 3);
        // Inner (left) wall: start, the arc of radius 8 around (500, 72), finish.
        assert_eq!(l.left.len(), 4);
        assert!(close(l.left[1], Vec2::new(500.0, 64.0)), "{:?}", l.left);
        assert!(close(l.left[2], Vec2::new(508.0, 72.0)), "{:?}", l.left);
        // The second leg runs up x = 572 for 400 units; the finish spans it.
        assert!(close(l.left[3], Vec2::new(508.0, 472.0)), "{:?}", l.left);
        let (first, last) = (l.right[0], l.right[l.right.len() - 1]);
        assert!(close(first, Vec2::new(0.0, -64.0)), "{first:?}");
        assert!(close(last, Vec2::new(636.0, 472.0)), "{last:?}");
        // Outer (right) wall: corners at most gap / 4 = 4 units outside the arc of radius 136, and
        // never inside it.
        let pivot = Vec2::new(500.0, 72.0);
        let corners = &l.right[1..l.right.len() - 1];
        assert!(corners.len() >= 2, "{corners:?}");
        for c in corners {
            let r = (*c - pivot).length();
            assert!((136.0..=140.0 + 1e-9).contains(&r), "{c:?} at {r}");
        }
    }

    #[test]
    fn a_hairpin_comes_back_a_divider_gap_from_itself() {
        let legs = [600, 600];
        let turns = [(180, Side::Right)];
        let l = lay_out(&Shape {
            width_units: 100.0,
            gap_units: 16.0,
            legs_units: &legs,
            turns: &turns,
        });
        let CentrelinePiece::Leg { from, to } = l.pieces[2] else {
            panic!("{:?}", l.pieces)
        };
        // Back along -x, 116 units to the right of the first leg.
        assert!(close(from, Vec2::new(600.0, -116.0)), "{from:?}");
        assert!(close(to, Vec2::new(0.0, -116.0)), "{to:?}");
        // Inner (right) wall: the divider's end, a half circle of radius 8 around (600, -58).
        assert!(close(l.right[1], Vec2::new(600.0, -50.0)), "{:?}", l.right);
        assert!(close(l.right[2], Vec2::new(608.0, -58.0)), "{:?}", l.right);
        assert!(close(l.right[3], Vec2::new(600.0, -66.0)), "{:?}", l.right);
        assert!(!overlaps_itself(&l.pieces, 100.0, 16.0));
    }

    #[test]
    fn outer_steps_keep_corners_within_the_overshoot() {
        for (sweep_deg, radius, overshoot) in
            [(180.0, 264.0, 4.0), (30.0, 72.0, 4.0), (90.0, 40.5, 0.25)]
        {
            let sweep = f64::to_radians(sweep_deg);
            let n = outer_steps(sweep, radius, overshoot);
            let out = radius / (sweep / n as f64 / 2.0).cos() - radius;
            assert!(
                out <= overshoot + 1e-9,
                "{sweep_deg} {radius}: {n} steps, {out}"
            );
            // One step fewer would stand out too far.
            if n > 1 {
                let out = radius / (sweep / (n - 1) as f64 / 2.0).cos() - radius;
                assert!(
                    out > overshoot,
                    "{sweep_deg} {radius}: {n} steps not the fewest"
                );
            }
        }
    }

    #[test]
    fn two_hairpins_the_same_way_fold_onto_the_first_leg() {
        let legs = [600, 300, 600];
        let turns = [(180, Side::Left), (180, Side::Left)];
        let shape = Shape {
            width_units: 100.0,
            gap_units: 16.0,
            legs_units: &legs,
            turns: &turns,
        };
        assert!(overlaps_itself(&lay_out(&shape).pieces, 100.0, 16.0));
        // The other way round is a zigzag: fine.
        let turns = [(180, Side::Left), (180, Side::Right)];
        let shape = Shape {
            turns: &turns,
            ..shape
        };
        assert!(!overlaps_itself(&lay_out(&shape).pieces, 100.0, 16.0));
    }

    #[test]
    fn segment_distances() {
        let p = Vec2::new;
        assert_eq!(
            segment_distance(p(0.0, 0.0), p(2.0, 2.0), p(0.0, 2.0), p(2.0, 0.0)),
            0.0
        );
        let d = segment_distance(p(0.0, 0.0), p(1.0, 0.0), p(3.0, 4.0), p(3.0, 9.0));
        assert!((d - 20.0_f64.sqrt()).abs() < 1e-12, "{d}");
        let d = segment_distance(p(0.0, 0.0), p(10.0, 0.0), p(5.0, 3.0), p(6.0, 7.0));
        assert!((d - 3.0).abs() < 1e-12, "{d}");
    }
}
