//! The corridor: every wall segment of a scene grown by the player's box, with the clearance and
//! rule-boundary queries (docs/physics.md section 10).
//!
//! Performance: each query scans all segments (six dot products per segment for inside tests and casts), which
//! is the right trade for corridors of tens of segments; a BVH would pay off only past about a hundred.

use super::grown::{move_box, GrownSegment, BOX_NEAR_UNITS};
use super::wall::{BoundaryKind, Wall};
use super::{CONTACT_TOL_UNITS, HULL_HALF_WIDTH_UNITS};
use crate::error::{Error, Result};
use crate::physics::Vec2;

/// One grown segment and where it came from.
#[derive(Clone, Debug)]
pub(crate) struct Piece {
    pub grown: GrownSegment,
    pub wall: usize,
    pub segment: usize,
    pub kind: BoundaryKind,
}

/// The walls of a scene, ready for hull queries. Build it once per scene with [`Corridor::new`].
#[derive(Clone, Debug)]
pub struct Corridor {
    walls: Vec<Wall>,
    pub(crate) pieces: Vec<Piece>,
}

/// The wall segment nearest to a hull, from [`Corridor::nearest`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Nearest {
    /// Index of the wall in the slice given to [`Corridor::new`].
    pub wall: usize,
    /// Index of the segment in that wall (segment `i` starts at point `i`).
    pub segment: usize,
    /// The wall's kind.
    pub kind: BoundaryKind,
    /// Signed clearance, units: as [`Corridor::clearance`].
    pub clearance_units: f64,
}

impl Corridor {
    /// A corridor from walls. Each wall must pass [`Wall::defect`]; the error names the first that does not
    /// (`walls[2].points`), with `corridor` as its location since no file is known here (scene files are
    /// checked, with lines, before they get here).
    pub fn new(walls: &[Wall]) -> Result<Corridor> {
        Self::with_half_width(walls, HULL_HALF_WIDTH_UNITS)
    }

    /// As [`Corridor::new`], with the walls grown by `half_width_units` instead of the hull's half width:
    /// a wider body keeps its centre that much further from every wall (the optimiser's centred guide
    /// paths use it).
    pub fn with_half_width(walls: &[Wall], half_width_units: f64) -> Result<Corridor> {
        let mut pieces = Vec::new();
        for (w, wall) in walls.iter().enumerate() {
            if let Some(defect) = wall.defect() {
                return Err(Error::Scene {
                    location: "corridor".to_string(),
                    key: format!("walls[{w}].points"),
                    message: defect.to_string(),
                });
            }
            for (s, (a, b)) in wall.segments().enumerate() {
                pieces.push(Piece {
                    grown: GrownSegment::new(a, b, half_width_units),
                    wall: w,
                    segment: s,
                    kind: wall.kind,
                });
            }
        }
        Ok(Corridor {
            walls: walls.to_vec(),
            pieces,
        })
    }

    /// The walls this corridor was built from.
    pub fn walls(&self) -> &[Wall] {
        &self.walls
    }

    /// True when some wall is of kind `kind`.
    pub fn has(&self, kind: BoundaryKind) -> bool {
        self.walls.iter().any(|w| w.kind == kind)
    }

    /// The segment nearest to the hull centred at `pos` among walls of kind `kind` (all walls for `None`),
    /// or `None` when there is no such wall.
    pub fn nearest(&self, pos: Vec2, kind: Option<BoundaryKind>) -> Option<Nearest> {
        self.pieces
            .iter()
            .filter(|p| kind.is_none_or(|k| p.kind == k))
            .map(|p| Nearest {
                wall: p.wall,
                segment: p.segment,
                kind: p.kind,
                clearance_units: p.grown.signed_distance(pos),
            })
            .min_by(|x, y| x.clearance_units.total_cmp(&y.clearance_units))
    }

    /// Smallest distance from the hull (the 32 x 32 box centred at `pos`) to any wall, units.
    ///
    /// Positive: the gap. Zero: touching. Negative: overlapping, and then minus the penetration depth (the
    /// shortest move that would separate the hull from the deepest wall). Within [`CONTACT_TOL_UNITS`] of
    /// zero counts as touching. `f64::INFINITY` when there are no walls.
    pub fn clearance(&self, pos: Vec2) -> f64 {
        self.clearance_of(pos, None)
    }

    /// [`Corridor::clearance`] over walls of kind `kind` only (all walls for `None`).
    pub fn clearance_of(&self, pos: Vec2, kind: Option<BoundaryKind>) -> f64 {
        self.nearest(pos, kind)
            .map_or(f64::INFINITY, |n| n.clearance_units)
    }

    /// True when the hull centred at `pos` overlaps a rule boundary by more than [`CONTACT_TOL_UNITS`].
    /// Touching a rule line, or running exactly along it, is allowed.
    pub fn rule_violation(&self, pos: Vec2) -> bool {
        self.pieces
            .iter()
            .filter(|p| p.kind == BoundaryKind::Rule)
            .any(|p| p.grown.max_side(pos) < -CONTACT_TOL_UNITS)
    }

    /// True when the hull, moving in a straight line from `p0` to `p1` (one frame's move), overlaps a rule
    /// boundary by more than [`CONTACT_TOL_UNITS`] at any moment, ends included. This catches a thin rule
    /// line crossed between two frame positions that are both clear of it. Exact: the grown segment is
    /// convex and the move linear.
    pub fn rule_violation_swept(&self, p0: Vec2, p1: Vec2) -> bool {
        let d = p1 - p0;
        let (lo, hi) = move_box(p0, p1);
        self.pieces
            .iter()
            .filter(|p| p.kind == BoundaryKind::Rule && p.grown.box_near(lo, hi, BOX_NEAR_UNITS))
            .any(|p| {
                p.grown
                    .open_interval(p0, d, CONTACT_TOL_UNITS)
                    .is_some_and(|iv| iv.meets_unit_open())
            })
    }
}
