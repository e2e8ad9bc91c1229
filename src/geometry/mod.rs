//! The corridor and the player's swept hull (docs/physics.md section 10), over parry2d's f64 shapes.
//!
//! The player is an axis-aligned box, [`HULL_HALF_WIDTH_UNITS`] on each side of its centre, that never
//! rotates; only its 32 x 32 footprint meets walls. Every query here reduces to the hull *centre* against a
//! wall segment grown by that box (their Minkowski sum, a convex hexagon; a rectangle for axis-aligned
//! segments), so each one is exact in `f64` up to rounding (about 1e-12 units at corridor scale), well inside
//! [`CONTACT_TOL_UNITS`]. Parry types never leave this module: the API speaks [`Vec2`] in units.
//!
//! - [`wall`]: [`Wall`] and [`BoundaryKind`] (scene data) and their shape checks ([`WallDefect`]).
//! - [`corridor`]: [`Corridor`]: clearance, rule boundaries, and the constructor.
//! - [`sweep`]: the swept hull against solid walls: [`Corridor::cast`] (one time of impact) and
//!   [`Corridor::sweep`] (GoldSrc `PM_FlyMove`: clip and retry up to [`MAX_BUMPS_PER_FRAME`] times).
//! - [`finish`]: [`FinishLine`] and the fraction of a move at which it is crossed.
//! - [`path`]: [`Corridor::shortest_path`], the exact shortest path of the hull centre (a lower bound).
//! - [`racing_line`]: [`racing_line::RacingLine`], the line through the corridor that bends least (a guide
//!   of the greedy baseline).
//!
//! [`Vec2`]: crate::physics::Vec2

pub mod corridor;
pub mod finish;
mod grown;
pub mod path;
pub mod racing_line;
pub mod separate;
pub mod sweep;
pub mod wall;

pub use corridor::{Corridor, Nearest};
pub use finish::{FinishLine, FinishPoint};
pub use separate::{HalfPlane, Separation};
pub use sweep::{Cast, Contact, SweepResult, SweepStatus};
pub use wall::{BoundaryKind, Wall, WallDefect};

/// Half the width of the player's box, units: the hull is 32 x 32 units in the plane (docs/physics.md
/// section 2), for standing and ducked players alike.
pub const HULL_HALF_WIDTH_UNITS: f64 = 16.0;

/// Distance within which the hull counts as touching a wall, units. A hull this close to (or this deep in)
/// a wall is in contact, not overlapping: running exactly along a rule line is allowed, and a solid wall
/// stops a move only when the hull would go deeper than this.
pub const CONTACT_TOL_UNITS: f64 = 1e-9;

/// How far short of a wall the game's hull trace stops, units: `DIST_EPSILON`, 1/32 (GoldSrc's and
/// Source's hull checks, "to keep floating point happy"). The engine-exact mode stands off this far
/// ([`Corridor::sweep_standing_off`]); planning in `f64` stops where the hull touches.
pub const DIST_EPSILON_UNITS: f64 = 0.03125;

/// Shortest wall segment accepted, units; shorter segments have no direction.
pub const MIN_SEGMENT_LENGTH_UNITS: f64 = 1e-9;

/// Moves tried per frame against solid walls: the first plus three retries after clipping (GoldSrc
/// `PM_FlyMove`'s `numbumps`, docs/physics.md section 10).
pub const MAX_BUMPS_PER_FRAME: usize = 4;

/// How much the grown walls are shrunk for [`Corridor::shortest_path`], units, so that a path that touches
/// a grown wall (as every shortest path does at its corners) is never blocked by rounding (about 1e-12
/// units at corridor scale). Shrinking keeps the result a lower bound: it can only shorten the path, by at
/// most a few times this value. It is exactly the contact tolerance, so the path search admits the same
/// hull positions as the simulation and the scene validator (touching, or at most [`CONTACT_TOL_UNITS`]
/// deep): a larger value would let "a path exists" squeeze through gaps too narrow for the hull.
pub const PATH_SHRINK_UNITS: f64 = CONTACT_TOL_UNITS;
