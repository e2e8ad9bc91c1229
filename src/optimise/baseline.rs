//! Seed and baseline: the greedy strafer's best runs, which the search starts from and which its plan is
//! compared with.
//!
//! The baseline is the strongest greedy strafer we know how to run: the look-ahead strafer (maximum
//! acceleration every frame, docs/physics.md section 6, steering only by its side) along each of several
//! guides: the corridor's shortest path kept 0 to 40 units off the walls and
//! the centre line (the guide kept as far off the walls as the corridor allows), every look-ahead, then on
//! airborne scenes the same turning as sharply as its target needs (section 9: the frame that turns that
//! far for the least speed), and with speed caps and corner speeds from the radius-speed relation, and
//! along racing lines ([`RacingLine`]: the line through the corridor that bends least) at the speeds of
//! their curvature. The fastest valid run whose engine-exact replay is valid too is the baseline (else the
//! fastest valid run), and which guide gave it is reported. The search starts from the strafer's own
//! clean runs, not the racing lines' ([`starts`]). Scenes with ground movement (groundstrafing, jumping) run capped too,
//! with caps that are shares of the groundstrafing top speed as well (section 12), but only when no
//! uncapped run is valid in both arithmetics: maximum acceleration overshoots a sharp corner of a narrow
//! corridor, and scraping along a solid wall it parts ways with the game's f32 replay.

use super::LowerBound;
use crate::budget::Budget;
use crate::geometry::racing_line::RacingLine;
use crate::geometry::{Corridor, HULL_HALF_WIDTH_UNITS};
use crate::physics::closed_form::max_groundstrafe_speed;
use crate::physics::curvature::{
    air_law, bend_arc_radius, circumradius, speed_for_radius, turn_arc_radius, RadiusSpeedTable,
};
use crate::physics::{Effect, Vec2};
use crate::scene::Scene;
use crate::sim::controllers::{CornerSpeed, CornerSpeeds, Greedy, GREEDY_LOOKAHEADS_UNITS};
use crate::sim::{Simulation, Trace};

/// Extra clearances of the guide paths off the walls, units (beyond the hull's half width).
const GUIDE_CLEARANCES_UNITS: [f64; 7] = [0.0, 4.0, 8.0, 16.0, 24.0, 32.0, 40.0];

/// The centre line's clearance is found to within this, units.
const CENTRE_LINE_TOL_UNITS: f64 = 0.5;

/// The centre line is searched for up to this clearance, units (a corridor 2 x 1024 units wide).
const CENTRE_LINE_MAX_UNITS: f64 = 1024.0;

/// Corridor widths, units, whose bend arcs give the greedy strafer's speed caps (see [`corner_caps`]).
const CAP_WIDTHS_UNITS: [f64; 5] = [16.0, 32.0, 64.0, 128.0, 256.0];

/// An invalid greedy run still short of the line after this many times the lower bound's frames is
/// given up (ranked by how far it got).
const BROKEN_RUN_BOUND_FACTOR: u64 = 2;

/// The frame after which a run still short of the line is given up: [`BROKEN_RUN_BOUND_FACTOR`] times
/// the lower bound's crossing frame. The baseline ranks an invalid greedy run by how far it got by then,
/// and a search started from a run that never reaches the line plans no more frames than that at first.
pub(super) fn given_up_frame(bound: &LowerBound) -> u64 {
    BROKEN_RUN_BOUND_FACTOR * bound.crossing.frames.max(1)
}

/// The distinct clean runs kept as starts of the relaxed problem, at most.
pub(super) const MAX_STARTS: usize = 4;

/// A guide of the greedy strafer and its settings.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct GreedyGuide {
    /// How far the guide path keeps off the walls beyond the hull's half width, units.
    pub clearance_units: f64,
    /// Whether this is the centre line: the guide kept as far off the walls as the corridor allows.
    pub centre_line: bool,
    /// The strafer's look-ahead along the guide, units.
    pub lookahead_units: f64,
    /// The speed the strafer holds once reached, ups, if capped.
    pub speed_cap_ups: Option<f64>,
    /// The width of the bends, units for the hull centre, whose arcs' speeds the strafer keeps under
    /// through each corner of its guide (and brakes for before it), if it does.
    pub corner_bend_units: Option<f64>,
    /// Whether the strafer turns as sharply as its target needs (uncapped; see
    /// [`Greedy::with_sharp_turns`]).
    pub sharp_turns: bool,
    /// Whether the guide is a racing line ([`RacingLine`], `clearance_units` off the walls), taken at
    /// the speeds of this share of its curvature's radii (see `baseline.rs::curvature_speeds`).
    pub racing_line: Option<f64>,
}

impl std::fmt::Display for GreedyGuide {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        if let Some(share) = self.racing_line {
            write!(
                f,
                "racing line ({:.1} units off the walls) at the speeds of {:.0} % of its radii",
                self.clearance_units,
                100.0 * share
            )?;
        } else if self.centre_line {
            write!(
                f,
                "centre line ({:.1} units off the walls)",
                self.clearance_units
            )?;
        } else {
            write!(
                f,
                "shortest path {:.1} units off the walls",
                self.clearance_units
            )?;
        }
        write!(f, ", look-ahead {:.1} units", self.lookahead_units)?;
        if let Some(cap) = self.speed_cap_ups {
            write!(f, ", speed cap {cap:.1} ups")?;
        }
        if let Some(w) = self.corner_bend_units {
            write!(f, ", corner speeds of {w:.0}-unit bends")?;
        }
        if self.sharp_turns {
            write!(f, ", turning as sharply as it needs")?;
        }
        Ok(())
    }
}

/// A run of the greedy strafer and the guide it followed.
#[derive(Clone, Debug)]
pub(super) struct GuideRun {
    pub(super) guide: GreedyGuide,
    pub(super) trace: Trace,
}

/// The baseline and the seeds of a solve.
pub(super) struct Baseline {
    /// The fastest valid greedy run (an invalid one when none is valid): the run the plan is compared
    /// with.
    pub(super) greedy: GuideRun,
    /// Clean runs (valid, finished, no wall contact) from distinct guides, fastest first: the search
    /// starts from the first; the others are further starts of the relaxed problem. Empty when no run is
    /// clean.
    pub(super) clean: Vec<GuideRun>,
}

impl Baseline {
    /// The run the search starts from: the fastest clean run, else the baseline.
    pub(super) fn seed(&self) -> &Trace {
        self.clean.first().map_or(&self.greedy.trace, |r| &r.trace)
    }
}

/// Speed caps from the radius-speed relation (docs/physics.md section 9): the speeds whose measured turn
/// radius fits the largest arc through bends of [`CAP_WIDTHS_UNITS`] for the hull centre, at 90 degrees
/// and, where the guide `path` has a sharper corner, at its sharpest. Capped greedy runs seed corner lines
/// the uncapped strafer overshoots.
pub(super) fn corner_caps(scene: &Scene, path: &[Vec2]) -> Vec<f64> {
    let sharpest = sharpest_corner_rad(path);
    let mut radii: Vec<f64> = CAP_WIDTHS_UNITS
        .iter()
        .map(|&w| bend_arc_radius(w))
        .collect();
    if sharpest > std::f64::consts::FRAC_PI_2 {
        radii.extend(
            CAP_WIDTHS_UNITS
                .iter()
                .map(|&w| turn_arc_radius(w, sharpest)),
        );
    }
    radii.sort_by(f64::total_cmp);
    radii
        .iter()
        .filter_map(|&r| speed_for_radius(&scene.vars, r).ok())
        .collect()
}

/// Path vertices closer than this, units, turn the same corner of the corridor (a corner drawn with
/// several points is wrapped by several vertices).
const CORNER_SPAN_UNITS: f64 = 64.0;

/// A corner of a guide path: the vertices that bend the same way within [`CORNER_SPAN_UNITS`] of each
/// other.
#[derive(Clone, Copy, Debug, PartialEq)]
struct PathCorner {
    /// Arc length of its first vertex along the path, units.
    first_units: f64,
    /// Arc length of its last vertex, units.
    last_units: f64,
    /// Its turn, radians (positive: left).
    turn_rad: f64,
}

/// The corners of the polyline `path`, in order.
fn path_corners(path: &[Vec2]) -> Vec<PathCorner> {
    let mut corners: Vec<PathCorner> = Vec::new();
    let mut s = 0.0;
    for w in path.windows(3) {
        let (a, b) = (w[1] - w[0], w[2] - w[1]);
        s += a.length();
        let turn = a.cross(b).atan2(a.dot(b));
        match corners.last_mut() {
            Some(c) if c.turn_rad * turn > 0.0 && a.length() < CORNER_SPAN_UNITS => {
                c.turn_rad += turn;
                c.last_units = s;
            }
            _ => corners.push(PathCorner {
                first_units: s,
                last_units: s,
                turn_rad: turn,
            }),
        }
    }
    // A vertex on a straight line (no turn) is no corner.
    corners.retain(|c| c.turn_rad.abs() > 1e-12);
    corners
}

/// The largest turn of the polyline `path` at one corner, radians (see [`path_corners`]).
fn sharpest_corner_rad(path: &[Vec2]) -> f64 {
    path_corners(path)
        .iter()
        .map(|c| c.turn_rad.abs())
        .fold(0.0, f64::max)
}

/// The speeds an airborne strafer along `path` keeps under for bends `width_units` wide (for the hull
/// centre): through each corner, the speed whose measured radius (docs/physics.md section 9) is the
/// largest arc through a bend of that width and the corner's turn, over that arc (its tangent length
/// `r tan(turn / 2)`, at most `r`, either side of the corner), and before it what braking at `gamma1` a
/// frame (section 7) can bring down to it. A corner whose arc needs more than `sv_maxvelocity` does not
/// limit.
fn corner_speeds(scene: &Scene, path: &[Vec2], width_units: f64) -> CornerSpeeds {
    let corners = path_corners(path)
        .iter()
        .filter_map(|c| {
            let turn = c.turn_rad.abs();
            let r = turn_arc_radius(width_units, turn);
            let speed_ups = speed_for_radius(&scene.vars, r).ok()?;
            let half = r * (0.5 * turn).tan().min(1.0);
            Some(CornerSpeed {
                start_units: c.first_units - half,
                end_units: c.last_units + half,
                speed_ups,
            })
        })
        .collect();
    CornerSpeeds {
        corners,
        braking_ups_per_s: air_law(&scene.vars).gamma1 / scene.frame_time_s(),
    }
}

/// The speeds a strafer along the racing line `line` keeps under: at each of its points the speed whose
/// maximum-acceleration radius (docs/physics.md section 9) is the radius of the circle through it and its
/// neighbours, and before it what braking at `gamma1` a frame (section 7) can bring down to it.
fn curvature_speeds(scene: &Scene, line: &[Vec2], radius_share: f64) -> CornerSpeeds {
    binding(point_speeds(scene, line, radius_share))
}

/// [`curvature_speeds`] at every point of `line`, each a stretch of no length.
fn point_speeds(scene: &Scene, line: &[Vec2], radius_share: f64) -> CornerSpeeds {
    let table = RadiusSpeedTable::new(&scene.vars);
    let mut corners = Vec::new();
    let mut s = 0.0;
    for w in line.windows(3) {
        s += (w[1] - w[0]).length();
        if let Some(speed_ups) = table.speed_for(radius_share * circumradius(w[0], w[1], w[2])) {
            corners.push(CornerSpeed {
                start_units: s,
                end_units: s,
                speed_ups,
            });
        }
    }
    CornerSpeeds {
        corners,
        braking_ups_per_s: air_law(&scene.vars).gamma1 / scene.frame_time_s(),
    }
}

/// The points of `speeds` (stretches of no length, in order along the line) that bind: a point whose
/// speed braking for a later point already keeps under limits nothing, and is dropped, so that the
/// strafer weighs a few points a frame instead of every point of the line.
fn binding(speeds: CornerSpeeds) -> CornerSpeeds {
    let braking = speeds.braking_ups_per_s;
    let mut kept: Vec<CornerSpeed> = Vec::with_capacity(speeds.corners.len());
    for c in speeds.corners.into_iter().rev() {
        let braked_ups = kept.last().map_or(f64::INFINITY, |next| {
            (next.speed_ups * next.speed_ups + 2.0 * braking * (next.start_units - c.start_units))
                .sqrt()
        });
        if c.speed_ups < braked_ups {
            kept.push(c);
        }
    }
    kept.reverse();
    CornerSpeeds {
        corners: kept,
        braking_ups_per_s: braking,
    }
}

/// Shares of a racing line's radii whose speeds the strafer keeps under: the line's own, and slower for
/// where the strafer falls behind the line's turn and strays outwards (the turn of a frame at a speed,
/// about `min(L, gamma1) / |v|`, leaves it little room to catch up). Measured on three generated
/// families, the line's own speeds gave the baseline 18 times of 20 and 80 % the other two; 60 and 40 %
/// never did (docs/design.md, "The racing line").
const RACING_RADIUS_SHARES: [f64; 2] = [1.0, 0.8];

/// Margins of the racing lines off the walls, units (beyond the hull's half width): the strafer
/// tracking a line strays from it by a few units.
const RACING_LINE_MARGINS_UNITS: [f64; 3] = [4.0, 12.0, 24.0];

/// Shares of the groundstrafing top speed (docs/physics.md section 12) the ground's capped greedy runs
/// hold.
const GROUND_CAP_SHARES: [f64; 6] = [0.3, 0.4, 0.5, 0.6, 0.7, 0.8];

/// Speed caps of scenes with ground movement, ups: the air's [`corner_caps`] (the ground turns tighter at
/// a speed, so they are on the safe side) and shares of the groundstrafing top speed
/// ([`GROUND_CAP_SHARES`]).
fn ground_caps(scene: &Scene, path: &[Vec2]) -> Vec<f64> {
    let top = max_groundstrafe_speed(&scene.vars, scene.effects.has(Effect::EdgeFriction));
    let mut caps = corner_caps(scene, path);
    if top.is_finite() {
        caps.extend(GROUND_CAP_SHARES.iter().map(|f| f * top));
    }
    caps
}

/// A guide path, `clearance_units` off the walls beyond the hull's half width.
struct GuidePath {
    clearance_units: f64,
    kind: GuideKind,
    path: Vec<Vec2>,
}

/// What a guide path is.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum GuideKind {
    /// The shortest path of a body `clearance_units` wider than the hull on either side.
    Shortest,
    /// The centre line ([`centre_line`]).
    CentreLine,
    /// A racing line ([`RacingLine`]).
    RacingLine,
}

/// How a greedy run takes corners its maximum-acceleration turn cannot: keeping its speed down (a speed
/// cap held once reached, or the corner speeds of bends of a width, units for the hull centre), or
/// turning harder than maximum acceleration as its target needs.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Cornering {
    Cap(f64),
    CornerSpeeds(f64),
    SharpTurns,
    /// Along a racing line, under the speeds of its curvature, turning as sharply as needed.
    Curvature(f64),
}

/// The guide paths of `scene`: the shortest path (the lower bound's) and the paths kept each of
/// [`GUIDE_CLEARANCES_UNITS`] off the walls where the corridor has room, then the centre line.
fn guide_paths(sim: &Simulation, bound: &LowerBound) -> Vec<GuidePath> {
    let scene = sim.scene();
    let mut guides = vec![GuidePath {
        clearance_units: 0.0,
        kind: GuideKind::Shortest,
        path: bound.path.clone(),
    }];
    for &extra in &GUIDE_CLEARANCES_UNITS[1..] {
        match clear_path(scene, extra) {
            Some(path) => guides.push(GuidePath {
                clearance_units: extra,
                kind: GuideKind::Shortest,
                path,
            }),
            None => break,
        }
    }
    if let Some((extra, path)) = centre_line(scene) {
        let known = guides
            .iter()
            .any(|g| (g.clearance_units - extra).abs() < 2.0 * CENTRE_LINE_TOL_UNITS);
        if !known {
            guides.push(GuidePath {
                clearance_units: extra,
                kind: GuideKind::CentreLine,
                path,
            });
        }
    }
    if scene.effects.is_air_only() {
        let lines = racing_lines(sim.corridor(), &guides[guides.len() - 1]);
        guides.extend(lines);
    }
    guides
}

/// The racing lines ([`RacingLine`]) along the widest guide `widest`, one at each of
/// [`RACING_LINE_MARGINS_UNITS`] it has room for.
fn racing_lines(corridor: &Corridor, widest: &GuidePath) -> Vec<GuidePath> {
    RACING_LINE_MARGINS_UNITS
        .iter()
        .filter(|&&m| m <= widest.clearance_units)
        .filter_map(|&m| {
            let line = RacingLine::through(corridor, &widest.path, m)?;
            Some(GuidePath {
                clearance_units: m,
                kind: GuideKind::RacingLine,
                path: line.points,
            })
        })
        .collect()
}

/// The shortest path kept `extra_units` further off every wall than the hull needs, if there is one.
fn clear_path(scene: &Scene, extra_units: f64) -> Option<Vec<Vec2>> {
    let corridor =
        Corridor::with_half_width(&scene.walls, HULL_HALF_WIDTH_UNITS + extra_units).ok()?;
    corridor
        .shortest_path(scene.start.pos, (scene.finish.a, scene.finish.b))
        .map(|(_, path)| path)
}

/// The centre line: the path kept as far off the walls as the corridor allows (bisection on the
/// clearance).
fn centre_line(scene: &Scene) -> Option<(f64, Vec<Vec2>)> {
    let (mut lo, mut hi) = (0.0, CENTRE_LINE_MAX_UNITS);
    let mut best: Option<(f64, Vec<Vec2>)> = None;
    while hi - lo > CENTRE_LINE_TOL_UNITS {
        let mid = 0.5 * (lo + hi);
        match clear_path(scene, mid) {
            Some(path) => {
                best = Some((mid, path));
                lo = mid;
            }
            None => hi = mid,
        }
    }
    best
}

/// The baseline and seeds of `scene` (see the module documentation). The planning model has no
/// collisions (after a contact the model and the game part ways), so the seeds are clean runs. Each run
/// is first played for its verdicts only; the few kept are played again whole, so the memory held is a
/// few runs' whatever the number of guides and look-aheads. Stops sweeping when `budget` runs out.
pub(super) fn baseline(
    sim: &Simulation,
    scene: &Scene,
    bound: &LowerBound,
    budget: &Budget,
) -> Baseline {
    let guides = guide_paths(sim, bound);
    let fx = scene.effects;
    // Ground movement (groundstrafing, jumping) gets the capped runs only when no uncapped run is valid
    // in both arithmetics: maximum acceleration overshoots a sharp corner of a narrow corridor, and along
    // a solid wall it scrapes where the game's f32 replay parts ways.
    let on_ground = !fx.is_air_only();
    let cornering: Vec<Cornering> = if fx.is_air_only() {
        std::iter::once(Cornering::SharpTurns)
            .chain(speed_limits(scene, &bound.path))
            .collect()
    } else {
        Vec::new()
    };
    let mut runs = GuideRuns::default();
    // An invalid run is ranked by when it crosses; one still going at this frame is given up.
    let broken_frame_limit = given_up_frame(bound);
    sweep_guides(
        sim,
        &guides,
        &cornering,
        true,
        broken_frame_limit,
        budget,
        &mut runs,
    );
    let mut greedy = pick_greedy(sim, &guides, &runs, &[], budget);
    if on_ground && !greedy.engine_valid && !budget.expired() {
        let checked = runs.valid.clone();
        let caps: Vec<Cornering> = ground_caps(scene, &bound.path)
            .into_iter()
            .map(Cornering::Cap)
            .collect();
        sweep_guides(
            sim,
            &guides,
            &caps,
            false,
            broken_frame_limit,
            budget,
            &mut runs,
        );
        greedy = pick_greedy(sim, &guides, &runs, &checked, budget);
    }
    let clean = starts(runs.clean)
        .into_iter()
        .take(MAX_STARTS)
        .map(|(_, i, guide)| replay(sim, &guides, i, guide))
        .filter(|r| is_clean(&r.trace))
        .collect();
    Baseline {
        greedy: greedy.run,
        clean,
    }
}

/// The starts of the relaxed problem among the clean runs `clean` (fastest first): the strafer's own
/// along its guides, not the racing lines' ([`Cornering::Curvature`]). A racing-line run is often nearer
/// the plan, but as a start it was measured to save no time (docs/design.md, "The racing line").
fn starts(clean: Vec<(f64, usize, GreedyGuide)>) -> Vec<(f64, usize, GreedyGuide)> {
    clean
        .into_iter()
        .filter(|r| r.2.racing_line.is_none())
        .collect()
}

/// The airborne ways of keeping the speed down for corners along `path`: the speed caps
/// ([`corner_caps`]), then the corner speeds of bends of each of [`CAP_WIDTHS_UNITS`].
fn speed_limits(scene: &Scene, path: &[Vec2]) -> impl Iterator<Item = Cornering> {
    let caps = corner_caps(scene, path).into_iter().map(Cornering::Cap);
    caps.chain(CAP_WIDTHS_UNITS.iter().map(|&w| Cornering::CornerSpeeds(w)))
        .chain(
            RACING_RADIUS_SHARES
                .iter()
                .map(|&k| Cornering::Curvature(k)),
        )
}

/// The verdicts of the greedy runs swept so far, each as its crossing time (or rank), guide index and
/// guide.
#[derive(Default)]
struct GuideRuns {
    /// Per guide and cap, the fastest valid run, fastest first.
    valid: Vec<(f64, usize, GreedyGuide)>,
    /// The best-ranked invalid run while no run is valid: by crossing time, else by how far it got.
    fallback: Option<((u8, f64), usize, GreedyGuide)>,
    /// Per guide and cap, the fastest clean run, fastest first.
    clean: Vec<(f64, usize, GreedyGuide)>,
}

/// The greedy strafer along guide `path` with `guide`'s look-ahead and cap, and `corners`, the corner
/// speeds of `guide.corner_bend_units` along `path` ([`corner_speeds`]).
fn strafer(path: &[Vec2], guide: &GreedyGuide, corners: Option<&CornerSpeeds>) -> Greedy {
    let mut g = Greedy::new(path.to_vec(), guide.lookahead_units);
    if let Some(cap) = guide.speed_cap_ups {
        g = g.with_speed_cap(cap);
    }
    if let Some(speeds) = corners {
        g = g.with_corner_speeds(speeds.clone());
    }
    if guide.sharp_turns {
        g = g.with_sharp_turns();
    }
    g
}

/// The strafer of `guide` along `path`, its corner speeds worked out for it.
fn strafer_of(sim: &Simulation, path: &[Vec2], guide: &GreedyGuide) -> Greedy {
    let corners = speeds_along(
        sim.scene(),
        path,
        guide.corner_bend_units,
        guide.racing_line,
    );
    strafer(path, guide, corners.as_ref())
}

/// The speeds a strafer keeps under along `path`: a racing line's at the share `racing_line` of its
/// radii ([`curvature_speeds`]), else the corner speeds of bends `corner_bend_units` wide
/// ([`corner_speeds`]), else none. The same at every look-ahead.
fn speeds_along(
    scene: &Scene,
    path: &[Vec2],
    corner_bend_units: Option<f64>,
    racing_line: Option<f64>,
) -> Option<CornerSpeeds> {
    match (racing_line, corner_bend_units) {
        (Some(share), _) => Some(curvature_speeds(scene, path, share)),
        (None, Some(w)) => Some(corner_speeds(scene, path, w)),
        (None, None) => None,
    }
}

/// Run `i`'s guide played again whole.
fn replay(sim: &Simulation, guides: &[GuidePath], i: usize, guide: GreedyGuide) -> GuideRun {
    GuideRun {
        guide,
        trace: sim.run(&mut strafer_of(sim, &guides[i].path, &guide)),
    }
}

/// Plays every guide at every look-ahead, plain first when `uncapped`, then each way of `cornering`, for
/// their verdicts only, into `runs` (kept sorted fastest first). The guides are played side by side on
/// the machine's cores ([`crate::work::in_job_order`]) and their verdicts gathered in the order of the sweep, so the runs kept are those
/// of playing them one after the other.
fn sweep_guides(
    sim: &Simulation,
    guides: &[GuidePath],
    cornering: &[Cornering],
    uncapped: bool,
    broken_frame_limit: u64,
    budget: &Budget,
    runs: &mut GuideRuns,
) {
    let first = uncapped.then_some(None);
    // Speed-limited runs along the shortest path and the widest guide only: the limits are for corners
    // the uncapped strafer overshoots, and every guide in between would multiply the runs. Sharp turns
    // keep the speed, so the guide they follow matters as much as the plain strafer's.
    let last = guides
        .iter()
        .rposition(|g| g.kind != GuideKind::RacingLine)
        .unwrap_or(0);
    let jobs: Vec<(Option<Cornering>, usize)> = first
        .into_iter()
        .chain(cornering.iter().copied().map(Some))
        .flat_map(|way| {
            let limited = matches!(way, Some(Cornering::Cap(_) | Cornering::CornerSpeeds(_)));
            let racing = matches!(way, Some(Cornering::Curvature(_)));
            (0..guides.len())
                .filter(move |&i| {
                    if guides[i].kind == GuideKind::RacingLine {
                        racing
                    } else {
                        !racing && (!limited || i == 0 || i == last)
                    }
                })
                .map(move |i| (way, i))
        })
        .collect();
    let swept = crate::work::in_job_order(&jobs, crate::work::cores(), |_, &(way, i)| {
        sweep_guide(sim, guides, way, i, broken_frame_limit, budget)
    });
    for guide in swept {
        if guide.cut {
            break;
        }
        if runs.valid.is_empty() {
            if let Some(f) = guide.fallback {
                if runs.fallback.as_ref().is_none_or(|b| f.0 < b.0) {
                    runs.fallback = Some(f);
                }
            }
        }
        runs.clean.extend(guide.clean);
        runs.valid.extend(guide.valid);
    }
    runs.valid.sort_by(|a, b| a.0.total_cmp(&b.0));
    runs.clean.sort_by(|a, b| a.0.total_cmp(&b.0));
}

/// One guide's runs at every look-ahead in one way of cornering.
struct GuideSweep {
    /// The fastest clean run.
    clean: Option<(f64, usize, GreedyGuide)>,
    /// The fastest valid run.
    valid: Option<(f64, usize, GreedyGuide)>,
    /// The best-ranked invalid run before the first valid one: by crossing time, else by how far it got.
    fallback: Option<((u8, f64), usize, GreedyGuide)>,
    /// Whether the budget ran out before every look-ahead was played.
    cut: bool,
}

/// Guide `i` played at every look-ahead in `way` of cornering (plain when `None`), for its verdicts.
fn sweep_guide(
    sim: &Simulation,
    guides: &[GuidePath],
    way: Option<Cornering>,
    i: usize,
    broken_frame_limit: u64,
    budget: &Budget,
) -> GuideSweep {
    let (cap, corner_bend_units, sharp_turns, racing_line) = match way {
        None => (None, None, false, None),
        Some(Cornering::Cap(cap)) => (Some(cap), None, false, None),
        Some(Cornering::CornerSpeeds(w)) => (None, Some(w), false, None),
        Some(Cornering::SharpTurns) => (None, None, true, None),
        Some(Cornering::Curvature(share)) => (None, None, true, Some(share)),
    };
    let g = &guides[i];
    let corners = speeds_along(sim.scene(), &g.path, corner_bend_units, racing_line);
    let mut swept = GuideSweep {
        clean: None,
        valid: None,
        fallback: None,
        cut: false,
    };
    // Ranks how far along this guide an unfinished run got.
    let along = Greedy::new(g.path.clone(), 0.0);
    for &la in &GREEDY_LOOKAHEADS_UNITS {
        if budget.expired() {
            swept.cut = true;
            break;
        }
        let guide = GreedyGuide {
            clearance_units: g.clearance_units,
            centre_line: g.kind == GuideKind::CentreLine,
            lookahead_units: la,
            speed_cap_ups: cap,
            corner_bend_units,
            sharp_turns,
            racing_line,
        };
        let run = sim.run_summary_broken_until(
            &mut strafer(&g.path, &guide, corners.as_ref()),
            budget,
            broken_frame_limit,
        );
        let t = match (run.feasible(), run.crossing) {
            (true, Some(c)) => c.time,
            _ => f64::INFINITY,
        };
        if t.is_finite() {
            if run.collisions == 0 && swept.clean.as_ref().is_none_or(|b| t < b.0) {
                swept.clean = Some((t, i, guide));
            }
            if swept.valid.as_ref().is_none_or(|b| t < b.0) {
                swept.valid = Some((t, i, guide));
            }
        } else if swept.valid.is_none() {
            let r = match run.crossing {
                Some(c) => (1, c.time),
                None => (2, -along.project(run.end_pos)),
            };
            if swept.fallback.as_ref().is_none_or(|b| r < b.0) {
                swept.fallback = Some((r, i, guide));
            }
        }
    }
    swept
}

/// The baseline run picked from `runs`, and whether its engine-exact replay is valid.
struct Picked {
    run: GuideRun,
    engine_valid: bool,
}

/// The fastest valid run whose engine-exact replay is valid too (the f64 run may graze a wall the game's
/// f32 arithmetic touches), else the fastest valid one, else the best-ranked invalid one. The valid
/// runs in `checked` were replayed engine-exact before and failed: they are not replayed again. An
/// invalid run kept is played within the budget: it may never end before the frame cap.
fn pick_greedy(
    sim: &Simulation,
    guides: &[GuidePath],
    runs: &GuideRuns,
    checked: &[(f64, usize, GreedyGuide)],
    budget: &Budget,
) -> Picked {
    let engine_valid =
        runs.valid
            .iter()
            .filter(|v| !checked.contains(v))
            .find_map(|&(_, i, guide)| {
                let run = replay(sim, guides, i, guide);
                sim.run_engine_exact_within(&run.trace.controls, budget)
                    .feasible()
                    .then_some(run)
            });
    if let Some(run) = engine_valid {
        return Picked {
            run,
            engine_valid: true,
        };
    }
    let run = match (runs.valid.first(), runs.fallback) {
        (Some(&(_, i, guide)), _) => replay(sim, guides, i, guide),
        (None, Some((_, i, guide))) => GuideRun {
            guide,
            trace: sim.run_within(&mut strafer_of(sim, &guides[i].path, &guide), budget),
        },
        (None, None) => {
            let guide = GreedyGuide {
                clearance_units: 0.0,
                centre_line: false,
                lookahead_units: GREEDY_LOOKAHEADS_UNITS[0],
                speed_cap_ups: None,
                corner_bend_units: None,
                sharp_turns: false,
                racing_line: None,
            };
            GuideRun {
                guide,
                trace: sim.run_within(&mut strafer_of(sim, &guides[0].path, &guide), budget),
            }
        }
    };
    Picked {
        run,
        engine_valid: false,
    }
}

/// A run the planning model can follow: valid, finished, and touching no wall.
pub(super) fn is_clean(t: &Trace) -> bool {
    t.feasible() && t.crossing.is_some() && t.collisions() == 0
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::optimise::planner::{
        fast_hairpin_at_air_acceleration_100, planning_inputs, staircase_scene,
    };

    /// Scene `index` of the narrow family at air acceleration 10 (`strafeopt gen --seed 5151 --fps 100
    /// --airaccelerate 10 --max-width 128 --max-corners 4 --max-leg 1000`).
    fn narrow_scene(index: u64) -> Scene {
        use crate::scene::generate::{generate, GeneratorSettings};
        let settings = GeneratorSettings {
            fps: vec![100],
            airaccelerate: vec![10],
            max_width_units: 128,
            max_corners: 4,
            max_leg_units: 1000,
            ..GeneratorSettings::default()
        };
        generate(5151, index, &settings)
            .unwrap_or_else(|e| panic!("{e}"))
            .scene
    }

    #[test]
    fn a_racing_line_keeps_only_its_binding_points_and_limits_the_same() {
        let scene = narrow_scene(3);
        let (sim, bound, _) = planning_inputs(&scene);
        let guides = guide_paths(&sim, &bound);
        let line = guides
            .iter()
            .find(|g| g.kind == GuideKind::RacingLine)
            .unwrap_or_else(|| panic!("no racing line"));
        let every = point_speeds(&scene, &line.path, 1.0);
        let kept = binding(every.clone());
        assert!(
            kept.corners.len() < every.corners.len(),
            "{} of {}",
            kept.corners.len(),
            every.corners.len()
        );
        let end = every.corners.last().map_or(0.0, |c| c.end_units);
        for k in 0..=2000 {
            let s = end * k as f64 / 2000.0;
            match (every.cap_at(s), kept.cap_at(s)) {
                (Some(a), Some(b)) => assert!((a - b).abs() <= 1e-9 * a, "at {s}: {a} {b}"),
                (a, b) => assert_eq!(a, b, "at {s}"),
            }
        }
    }

    #[test]
    fn on_a_narrow_corridor_the_racing_line_is_the_baseline_but_not_a_start() {
        // 100 fps, air acceleration 10, four turns 64 to 128 units wide: the strafer's own runs slow
        // for every corner along their guides; the racing line's speeds let it carry more.
        let scene = narrow_scene(3);
        let (_, _, base) = planning_inputs(&scene);
        let greedy = base
            .greedy
            .trace
            .crossing
            .unwrap_or_else(|| panic!("no greedy crossing"));
        assert!(base.greedy.trace.feasible());
        assert!(
            base.greedy.guide.racing_line.is_some(),
            "{}",
            base.greedy.guide
        );
        let seed = base
            .seed()
            .crossing
            .unwrap_or_else(|| panic!("no seed crossing"));
        assert!(greedy.frames < seed.frames, "{greedy:?} {seed:?}");
        assert!(base.clean.iter().all(|r| r.guide.racing_line.is_none()));
    }

    #[test]
    fn a_corner_wrapped_by_several_vertices_counts_as_one_turn() {
        // A 150-degree left turn drawn as three 50-degree bends 10 units apart, then, 500 units on, a
        // 60-degree right turn.
        let mut path = vec![Vec2::new(-500.0, 0.0), Vec2::new(0.0, 0.0)];
        let mut heading: f64 = 0.0;
        for _ in 0..3 {
            heading += 50f64.to_radians();
            let last = path[path.len() - 1];
            path.push(last + Vec2::from_angle(heading) * 10.0);
        }
        let last = path[path.len() - 1];
        path.push(last + Vec2::from_angle(heading) * 500.0);
        heading -= 60f64.to_radians();
        let last = path[path.len() - 1];
        path.push(last + Vec2::from_angle(heading) * 500.0);
        let sharpest = sharpest_corner_rad(&path);
        assert!((sharpest - 150f64.to_radians()).abs() < 1e-9, "{sharpest}");
        // The corners in order, where they start and end along the path, and their turns.
        let corners = path_corners(&path);
        assert_eq!(corners.len(), 2, "{corners:?}");
        let want = [(500.0, 520.0, 150.0), (1030.0, 1030.0, -60.0)];
        for (c, (first, last, turn)) in corners.iter().zip(want) {
            assert!((c.first_units - first).abs() < 1e-9, "{c:?}");
            assert!((c.last_units - last).abs() < 1e-9, "{c:?}");
            assert!((c.turn_rad - f64::to_radians(turn)).abs() < 1e-9, "{c:?}");
        }
    }

    #[test]
    fn each_corner_has_the_speed_of_its_own_arc_over_its_tangent_lengths() {
        // A staircase of right-angle turns; its shortest path cuts each corner's diagonal a little
        // differently, so each corner has its own turn and speed.
        let scene = staircase_scene(3);
        let (_, bound, _) = planning_inputs(&scene);
        let width = 64.0;
        let corners = path_corners(&bound.path);
        let speeds = corner_speeds(&scene, &bound.path, width);
        assert_eq!((corners.len(), speeds.corners.len()), (3, 3), "{speeds:?}");
        for (c, corner) in speeds.corners.iter().zip(&corners) {
            let turn = corner.turn_rad.abs();
            assert!(
                turn > 1.0 && turn < std::f64::consts::FRAC_PI_2,
                "{corner:?}"
            );
            let r = turn_arc_radius(width, turn);
            let v = speed_for_radius(&scene.vars, r).unwrap_or_else(|e| panic!("{e}"));
            assert!((c.speed_ups - v).abs() < 1e-9, "{c:?} against {v}");
            // Under a right angle the tangent length is r tan(turn / 2), both sides.
            let half = r * (0.5 * turn).tan();
            assert!(
                (corner.first_units - c.start_units - half).abs() < 1e-9,
                "{c:?}"
            );
            assert!(
                (c.end_units - corner.last_units - half).abs() < 1e-9,
                "{c:?}"
            );
        }
        // A sharper turn, a slower corner.
        let mut by_turn: Vec<(f64, f64)> = corners
            .iter()
            .zip(&speeds.corners)
            .map(|(c, s)| (c.turn_rad.abs(), s.speed_ups))
            .collect();
        by_turn.sort_by(|a, b| a.0.total_cmp(&b.0));
        assert!(by_turn.windows(2).all(|w| w[1].1 < w[0].1), "{by_turn:?}");
        let gamma1 = air_law(&scene.vars).gamma1;
        assert!((speeds.braking_ups_per_s - gamma1 * 100.0).abs() < 1e-9);
    }

    /// The fastest valid run of the strafer along every guide of `sim`'s scene taking corners each of the
    /// ways of `cornering` (and plain first if `plain`): its crossing time, seconds, and its guide.
    fn fastest_valid(
        sim: &Simulation,
        bound: &LowerBound,
        cornering: &[Cornering],
        plain: bool,
    ) -> (f64, GreedyGuide) {
        let mut runs = GuideRuns::default();
        let limit = given_up_frame(bound);
        let guides = guide_paths(sim, bound);
        let budget = Budget::unlimited();
        sweep_guides(sim, &guides, cornering, plain, limit, &budget, &mut runs);
        let (t, _, guide) = runs.valid[0];
        (t, guide)
    }

    #[test]
    fn at_air_acceleration_100_the_strafer_turning_sharply_takes_a_hairpin_at_speed() {
        // Maximum acceleration turns about L / V = 30 / 1200 rad a frame, an arc of 480 units: the plain
        // strafer must slow to about 540 ups for the hairpin's 96-unit arc. A frame pushing sideways
        // harder (gamma1 = 320 ups) turns ten times as fast for a few ups.
        let scene = fast_hairpin_at_air_acceleration_100();
        let (sim, bound, base) = planning_inputs(&scene);
        let guide = base.greedy.guide;
        assert!(guide.sharp_turns, "{guide}");
        assert!(base.greedy.trace.feasible(), "{guide}");
        let frames = base.greedy.trace.crossing.map_or(u64::MAX, |c| c.frames);
        let slowest = base
            .greedy
            .trace
            .frames
            .iter()
            .map(|r| r.speed)
            .fold(f64::INFINITY, f64::min);
        // The best valid run of every other strafer.
        let others: Vec<Cornering> = speed_limits(&scene, &bound.path).collect();
        let (other_s, other) = fastest_valid(&sim, &bound, &others, true);
        // Measured: 200 frames, never under 1073 ups; the best other run 2.65 s (corner speeds).
        assert!(slowest > 800.0, "{slowest} ups through the hairpin");
        assert!(
            (frames as f64) * scene.frame_time_s() < 0.85 * other_s,
            "{frames} frames against {other_s} s ({other})"
        );
    }

    #[test]
    fn on_a_staircase_the_strafer_with_corner_speeds_beats_every_single_cap() {
        // One cap is the sharpest corner's speed held on every leg; corner speeds free the legs between.
        let scene = staircase_scene(5);
        let (sim, bound, _) = planning_inputs(&scene);
        let corner_speeds: Vec<Cornering> = CAP_WIDTHS_UNITS
            .iter()
            .map(|&w| Cornering::CornerSpeeds(w))
            .collect();
        let (best_s, guide) = fastest_valid(&sim, &bound, &corner_speeds, false);
        assert!(guide.corner_bend_units.is_some(), "{guide}");
        let frames = (best_s / scene.frame_time_s()).ceil() as u64;
        let shortest = &guide_paths(&sim, &bound)[0].path;
        let mut capped = u64::MAX;
        for cap in corner_caps(&scene, &bound.path) {
            for &la in &GREEDY_LOOKAHEADS_UNITS {
                let mut g = Greedy::new(shortest.clone(), la).with_speed_cap(cap);
                let t = sim.run(&mut g);
                if let (true, Some(c)) = (t.feasible(), t.crossing) {
                    capped = capped.min(c.frames);
                }
            }
        }
        assert!(frames < capped, "{frames} against capped {capped}");
    }
}
