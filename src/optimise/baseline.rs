//! Seed and baseline: the greedy strafer's best runs, which the search starts from and which its plan is
//! compared with.
//!
//! The baseline is the strongest greedy strafer we know how to run: the look-ahead strafer (maximum
//! acceleration every frame, docs/physics.md section 6, steering only by its side) along each of several
//! guides: the corridor's shortest path kept 0 to 40 units off the walls and
//! the centre line (the guide kept as far off the walls as the corridor allows), every look-ahead, then
//! the same with speed caps from the radius-speed relation (section 9) on airborne scenes. The fastest
//! valid run whose engine-exact replay is valid too is the baseline (else the fastest valid run), and
//! which guide gave it is reported. Scenes with ground movement (groundstrafing, jumping) run capped too,
//! with caps that are shares of the groundstrafing top speed as well (section 12), but only when no
//! uncapped run is valid in both arithmetics: maximum acceleration overshoots a sharp corner of a narrow
//! corridor, and scraping along a solid wall it parts ways with the game's f32 replay.

use super::LowerBound;
use crate::budget::Budget;
use crate::geometry::{Corridor, HULL_HALF_WIDTH_UNITS};
use crate::physics::closed_form::max_groundstrafe_speed;
use crate::physics::curvature::{bend_arc_radius, speed_for_radius, turn_arc_radius};
use crate::physics::{Effect, Vec2};
use crate::scene::Scene;
use crate::sim::controllers::{Greedy, GREEDY_LOOKAHEADS_UNITS};
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
}

impl std::fmt::Display for GreedyGuide {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        if self.centre_line {
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

/// The largest turn of the polyline `path` at one corner, radians: the turns of consecutive vertices
/// that bend the same way within [`CORNER_SPAN_UNITS`] of each other, summed.
fn sharpest_corner_rad(path: &[Vec2]) -> f64 {
    let mut sharpest: f64 = 0.0;
    let mut current = 0.0;
    for w in path.windows(3) {
        let (a, b) = (w[1] - w[0], w[2] - w[1]);
        let turn = a.cross(b).atan2(a.dot(b));
        let joined = current * turn > 0.0 && a.length() < CORNER_SPAN_UNITS;
        current = if joined { current + turn } else { turn };
        sharpest = sharpest.max(current.abs());
    }
    sharpest
}

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

/// A guide path: the shortest path of a body `clearance_units` wider than the hull on either side.
struct GuidePath {
    clearance_units: f64,
    centre_line: bool,
    path: Vec<Vec2>,
}

/// The guide paths of `scene`: the shortest path (the lower bound's) and the paths kept each of
/// [`GUIDE_CLEARANCES_UNITS`] off the walls where the corridor has room, then the centre line.
fn guide_paths(scene: &Scene, bound: &LowerBound) -> Vec<GuidePath> {
    let mut guides = vec![GuidePath {
        clearance_units: 0.0,
        centre_line: false,
        path: bound.path.clone(),
    }];
    for &extra in &GUIDE_CLEARANCES_UNITS[1..] {
        match clear_path(scene, extra) {
            Some(path) => guides.push(GuidePath {
                clearance_units: extra,
                centre_line: false,
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
                centre_line: true,
                path,
            });
        }
    }
    guides
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
    let guides = guide_paths(scene, bound);
    let fx = scene.effects;
    // Ground movement (groundstrafing, jumping) gets the capped runs only when no uncapped run is valid
    // in both arithmetics: maximum acceleration overshoots a sharp corner of a narrow corridor, and along
    // a solid wall it scrapes where the game's f32 replay parts ways.
    let on_ground = !fx.is_air_only();
    let caps = if fx.is_air_only() {
        corner_caps(scene, &bound.path)
    } else {
        Vec::new()
    };
    let mut runs = GuideRuns::default();
    // An invalid run is ranked by when it crosses; one still going at this frame is given up.
    let broken_frame_limit = BROKEN_RUN_BOUND_FACTOR * bound.crossing.frames.max(1);
    sweep_guides(
        sim,
        &guides,
        &caps,
        true,
        broken_frame_limit,
        budget,
        &mut runs,
    );
    let mut greedy = pick_greedy(sim, &guides, &runs, &[], budget);
    if on_ground && !greedy.engine_valid && !budget.expired() {
        let checked = runs.valid.clone();
        sweep_guides(
            sim,
            &guides,
            &ground_caps(scene, &bound.path),
            false,
            broken_frame_limit,
            budget,
            &mut runs,
        );
        greedy = pick_greedy(sim, &guides, &runs, &checked, budget);
    }
    let clean = runs
        .clean
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

/// The greedy strafer along guide `path` with `guide`'s look-ahead and cap.
fn strafer(path: &[Vec2], guide: &GreedyGuide) -> Greedy {
    let g = Greedy::new(path.to_vec(), guide.lookahead_units);
    match guide.speed_cap_ups {
        Some(cap) => g.with_speed_cap(cap),
        None => g,
    }
}

/// Run `i`'s guide played again whole.
fn replay(sim: &Simulation, guides: &[GuidePath], i: usize, guide: GreedyGuide) -> GuideRun {
    GuideRun {
        guide,
        trace: sim.run(&mut strafer(&guides[i].path, &guide)),
    }
}

/// Plays every guide at every look-ahead, with no cap first when `uncapped`, then each of `caps`, for
/// their verdicts only, into `runs` (kept sorted fastest first).
fn sweep_guides(
    sim: &Simulation,
    guides: &[GuidePath],
    caps: &[f64],
    uncapped: bool,
    broken_frame_limit: u64,
    budget: &Budget,
    runs: &mut GuideRuns,
) {
    let first = uncapped.then_some(None);
    'sweep: for cap in first.into_iter().chain(caps.iter().copied().map(Some)) {
        // Capped runs along the shortest path and the widest guide only: the caps are for corners the
        // uncapped strafer overshoots, and every guide in between would multiply the runs.
        let last = guides.len() - 1;
        for (i, g) in guides.iter().enumerate() {
            if cap.is_some() && i != 0 && i != last {
                continue;
            }
            let mut best_clean: Option<(f64, usize, GreedyGuide)> = None;
            let mut best_valid: Option<(f64, usize, GreedyGuide)> = None;
            // Ranks how far along this guide an unfinished run got.
            let along = Greedy::new(g.path.clone(), 0.0);
            for &la in &GREEDY_LOOKAHEADS_UNITS {
                if budget.expired() {
                    break 'sweep;
                }
                let guide = GreedyGuide {
                    clearance_units: g.clearance_units,
                    centre_line: g.centre_line,
                    lookahead_units: la,
                    speed_cap_ups: cap,
                };
                let run = sim.run_summary_broken_until(
                    &mut strafer(&g.path, &guide),
                    budget,
                    broken_frame_limit,
                );
                let t = match (run.feasible(), run.crossing) {
                    (true, Some(c)) => c.time,
                    _ => f64::INFINITY,
                };
                if t.is_finite() {
                    if run.collisions == 0 && best_clean.as_ref().is_none_or(|b| t < b.0) {
                        best_clean = Some((t, i, guide));
                    }
                    if best_valid.as_ref().is_none_or(|b| t < b.0) {
                        best_valid = Some((t, i, guide));
                    }
                } else if runs.valid.is_empty() && best_valid.is_none() {
                    let r = match run.crossing {
                        Some(c) => (1, c.time),
                        None => (2, -along.project(run.end_pos)),
                    };
                    if runs.fallback.as_ref().is_none_or(|b| r < b.0) {
                        runs.fallback = Some((r, i, guide));
                    }
                }
            }
            runs.clean.extend(best_clean);
            runs.valid.extend(best_valid);
        }
    }
    runs.valid.sort_by(|a, b| a.0.total_cmp(&b.0));
    runs.clean.sort_by(|a, b| a.0.total_cmp(&b.0));
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
            trace: sim.run_within(&mut strafer(&guides[i].path, &guide), budget),
        },
        (None, None) => {
            let guide = GreedyGuide {
                clearance_units: 0.0,
                centre_line: false,
                lookahead_units: GREEDY_LOOKAHEADS_UNITS[0],
                speed_cap_ups: None,
            };
            GuideRun {
                guide,
                trace: sim.run_within(&mut strafer(&guides[0].path, &guide), budget),
            }
        }
    };
    Picked {
        run,
        engine_valid: false,
    }
}

/// A run the planning model can follow: valid, finished, and touching no wall.
fn is_clean(t: &Trace) -> bool {
    t.feasible() && t.crossing.is_some() && t.collisions() == 0
}

#[cfg(test)]
mod tests {
    use super::*;

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
    }
}
