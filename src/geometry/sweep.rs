//! The player's hull swept through solid walls (docs/physics.md section 10, GoldSrc `PM_FlyMove`).
//!
//! [`Corridor::cast`] is one trace: the hull centre is cast as a ray against each solid segment grown by
//! the box (Cyrus-Beck clipping against its six half-planes), which is the exact time of impact of the
//! moving box, to `f64` rounding. [`Corridor::sweep`] is the frame's move: trace, stop at the contact, clip
//! the velocity `v <- v - (v . n) n`, retry with the time left, at most [`MAX_BUMPS_PER_FRAME`] traces.
//!
//! Contact is decided with [`CONTACT_TOL_UNITS`]: a move is stopped only if it would take the hull deeper
//! than that into a wall, and then it stops where the hull first touches (clearance 0). So a hull resting
//! against a wall may slide along it, and moves that graze a corner or run exactly along a wall are free.

use super::corridor::Corridor;
use super::grown::{move_box, BOX_NEAR_UNITS};
use super::wall::BoundaryKind;
use super::{CONTACT_TOL_UNITS, MAX_BUMPS_PER_FRAME};
use crate::physics::Vec2;

/// The first contact of a cast.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Contact {
    /// Fraction of the move, in `[0, 1]`, at which the hull first touches the wall.
    pub fraction: f64,
    /// Unit normal of the contact plane, pointing out of the wall towards the player.
    pub normal: Vec2,
    /// Index of the wall hit.
    pub wall: usize,
    /// Index of the segment hit in that wall.
    pub segment: usize,
}

/// The result of one trace of the hull ([`Corridor::cast`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Cast {
    /// The whole move is clear (it may touch walls, never go deeper than [`CONTACT_TOL_UNITS`]).
    Free,
    /// The move hits a wall.
    Hit(Contact),
    /// The hull already overlaps a solid wall by more than [`CONTACT_TOL_UNITS`] at the start; no time of
    /// impact is meaningful.
    StartedInside {
        /// Index of the deepest wall.
        wall: usize,
        /// Penetration depth, units.
        depth_units: f64,
    },
}

/// How a frame's swept move ended.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum SweepStatus {
    /// No wall touched: the hull moved the full `vel * frame_time`.
    Free,
    /// The hull hit walls `contacts` times; the velocity was clipped each time and the whole frame's time
    /// was used (sliding along walls, or stopped dead by a head-on hit).
    Clipped {
        /// Traces that hit a wall (1 to [`MAX_BUMPS_PER_FRAME`]).
        contacts: u32,
    },
    /// The move was cut short: all [`MAX_BUMPS_PER_FRAME`] traces hit a wall with time left over, or no
    /// trace moved the hull at all (wedged in a corner; the velocity is then zeroed, as `PM_FlyMove` does).
    Stuck {
        /// Traces that hit a wall.
        contacts: u32,
    },
    /// The hull started inside a solid wall (deeper than [`CONTACT_TOL_UNITS`]): it is not moved and its
    /// velocity is zeroed (`PM_FlyMove`'s `allsolid` case).
    StartedInside {
        /// Index of the deepest wall.
        wall: usize,
        /// Penetration depth, units.
        depth_units: f64,
    },
}

impl SweepStatus {
    /// Number of wall contacts in the frame.
    pub fn contacts(&self) -> u32 {
        match *self {
            SweepStatus::Free | SweepStatus::StartedInside { .. } => 0,
            SweepStatus::Clipped { contacts } | SweepStatus::Stuck { contacts } => contacts,
        }
    }
}

/// The end of one frame's swept move ([`Corridor::sweep`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SweepResult {
    /// Final hull centre, units.
    pub pos: Vec2,
    /// Final velocity after clipping, ups.
    pub vel: Vec2,
    /// How the move ended.
    pub status: SweepStatus,
}

impl Corridor {
    /// One trace against the solid walls: the hull centred at `pos` moved by `delta` (units).
    ///
    /// Returns the earliest contact over all solid segments, [`Cast::Free`] when the move never takes the
    /// hull deeper than [`CONTACT_TOL_UNITS`] into one, or [`Cast::StartedInside`]. Rule boundaries are
    /// ignored (see [`Corridor::rule_violation_swept`]).
    pub fn cast(&self, pos: Vec2, delta: Vec2) -> Cast {
        // Only the pieces near the move can hold its start or take it in (`GrownSegment::box_near`).
        let (lo, hi) = move_box(pos, pos + delta);
        let solid = || {
            self.pieces.iter().filter(move |p| {
                p.kind == BoundaryKind::Solid && p.grown.box_near(lo, hi, BOX_NEAR_UNITS)
            })
        };
        let deepest = solid()
            .map(|p| (p.wall, p.grown.max_side(pos)))
            .min_by(|x, y| x.1.total_cmp(&y.1));
        if let Some((wall, side)) = deepest {
            if side < -CONTACT_TOL_UNITS {
                return Cast::StartedInside {
                    wall,
                    depth_units: -side,
                };
            }
        }
        let mut best: Option<Contact> = None;
        for p in solid() {
            let goes_in = p
                .grown
                .open_interval(pos, delta, CONTACT_TOL_UNITS)
                .is_some_and(|iv| iv.meets_unit_open());
            if !goes_in {
                continue;
            }
            // The move goes deeper than the tolerance, so it heads into at least one plane: stop where it
            // crosses the unshrunk boundary (at once if it starts within the tolerance band).
            let Some((t, plane)) = p.grown.entry(pos, delta) else {
                continue;
            };
            let fraction = t.clamp(0.0, 1.0);
            if best.is_none_or(|b| fraction < b.fraction) {
                best = Some(Contact {
                    fraction,
                    normal: p.grown.planes[plane].normal,
                    wall: p.wall,
                    segment: p.segment,
                });
            }
        }
        best.map_or(Cast::Free, Cast::Hit)
    }

    /// One frame's move of the hull centred at `pos` with velocity `vel_ups` for `frame_time_s` seconds,
    /// against the solid walls (docs/physics.md section 10, GoldSrc `PM_FlyMove` in the air):
    ///
    /// 1. trace `vel * time_left`; if clear, move and stop;
    /// 2. on a hit at fraction `f`, move to the contact, `time_left -= f * time_left`, clip
    ///    `v <- v - (v . n) n` (overbounce 1), and retry, at most [`MAX_BUMPS_PER_FRAME`] traces;
    /// 3. if no trace moved the hull at all, zero the velocity.
    ///
    /// Deliberate simplifications of the game: no `DIST_EPSILON` back-off from the wall (we stop at
    /// clearance 0 exactly; the engine-exact mode backs off, [`Corridor::sweep_standing_off`]) and no
    /// `STOP_EPSILON` zeroing of velocity components under 0.1 ups.
    pub fn sweep(&self, pos: Vec2, vel_ups: Vec2, frame_time_s: f64) -> SweepResult {
        self.sweep_standing_off(pos, vel_ups, frame_time_s, 0.0)
    }

    /// [`Corridor::sweep`] with each hit stopped `stand_off_units` short of the wall's plane, measured
    /// along its normal, as the game's trace stops [`super::DIST_EPSILON_UNITS`] short: the fraction of
    /// a move that starts `d1` off the plane and would end `d2` off it is `(d1 - stand_off) / (d1 - d2)`,
    /// at least 0. Positions kept in `f32` need it: a hull stopped at clearance 0 and rounded to `f32`
    /// lands inside the wall about half the time, where the next trace starts solid and the hull is held
    /// there for good.
    pub fn sweep_standing_off(
        &self,
        pos: Vec2,
        vel_ups: Vec2,
        frame_time_s: f64,
        stand_off_units: f64,
    ) -> SweepResult {
        let mut pos = pos;
        let mut vel = vel_ups;
        let mut time_left = frame_time_s;
        let mut contacts: u32 = 0;
        let mut moved = false;
        let mut cut_short = false;
        for bump in 0..MAX_BUMPS_PER_FRAME {
            // Exact zero on purpose: PM_FlyMove stops only on an exactly zero velocity.
            if vel == Vec2::ZERO {
                break;
            }
            let delta = vel * time_left;
            match self.cast(pos, delta) {
                Cast::StartedInside { wall, depth_units } => {
                    return SweepResult {
                        pos,
                        vel: Vec2::ZERO,
                        status: SweepStatus::StartedInside { wall, depth_units },
                    };
                }
                Cast::Free => {
                    pos += delta;
                    moved = true;
                    break;
                }
                Cast::Hit(c) => {
                    // `d1 - d2`: how far the whole move goes into the wall's plane.
                    let into_plane = -delta.dot(c.normal);
                    let fraction = if into_plane > 0.0 {
                        (c.fraction - stand_off_units / into_plane).max(0.0)
                    } else {
                        c.fraction
                    };
                    if fraction > 0.0 {
                        pos += delta * fraction;
                        moved = true;
                    }
                    time_left -= time_left * fraction;
                    contacts += 1;
                    vel = vel - c.normal * vel.dot(c.normal);
                    if bump + 1 == MAX_BUMPS_PER_FRAME && vel != Vec2::ZERO && time_left > 0.0 {
                        cut_short = true;
                    }
                }
            }
        }
        let status = if contacts == 0 {
            SweepStatus::Free
        } else if !moved && vel != Vec2::ZERO {
            vel = Vec2::ZERO;
            SweepStatus::Stuck { contacts }
        } else if cut_short {
            SweepStatus::Stuck { contacts }
        } else {
            SweepStatus::Clipped { contacts }
        };
        SweepResult { pos, vel, status }
    }
}
