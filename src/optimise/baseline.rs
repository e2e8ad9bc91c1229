//! Seed and baseline: the greedy strafer's best runs, which the search starts from and which its plan is
//! compared with.

use super::verify::time_of;
use super::LowerBound;
use crate::geometry::{Corridor, HULL_HALF_WIDTH_UNITS};
use crate::physics::curvature::{bend_arc_radius, speed_for_radius};
use crate::scene::Scene;
use crate::sim::controllers::{best_capped_greedy, Greedy, GREEDY_LOOKAHEADS_UNITS};
use crate::sim::{Simulation, Trace};

/// Extra clearances of the guide paths, units, tried in turn when the best greedy run is not clean.
const GUIDE_CLEARANCES_UNITS: [f64; 5] = [0.0, 2.0, 4.0, 8.0, 12.0];

/// Corridor widths, units, whose bend arcs give the greedy strafer's speed caps (see [`corner_caps`]).
const CAP_WIDTHS_UNITS: [f64; 5] = [16.0, 32.0, 64.0, 128.0, 256.0];

/// The baseline and the seed of a solve.
pub(super) struct Baseline {
    /// The fastest valid greedy run (infinite time when none is valid): the run the plan is compared with.
    pub(super) greedy: Trace,
    /// The run the search starts from: a valid run that touches no wall, where there is one.
    pub(super) seed: Trace,
}

/// Speed caps from the radius-speed relation (docs/physics.md section 9): the speeds whose measured turn
/// radius fits the largest arc through bends of [`CAP_WIDTHS_UNITS`] for the hull centre. Capped greedy
/// runs seed corner lines the uncapped strafer overshoots.
fn corner_caps(scene: &Scene) -> Vec<f64> {
    CAP_WIDTHS_UNITS
        .iter()
        .filter_map(|&w| speed_for_radius(&scene.vars, bend_arc_radius(w)).ok())
        .collect()
}

/// The baseline and seed of `scene`. The search's start is the greedy run if it is valid and touches no
/// wall (the planning model has no collisions: after a contact the model and the game part ways), else a
/// run along a centred guide; the baseline is the faster valid run of the two.
pub(super) fn baseline(sim: &Simulation, scene: &Scene, bound: &LowerBound) -> Baseline {
    let air_only = scene.effects.is_air_only();
    let caps = if air_only {
        corner_caps(scene)
    } else {
        Vec::new()
    };
    let (greedy, _, _) = best_capped_greedy(sim, &bound.path, &GREEDY_LOOKAHEADS_UNITS, &caps);
    let seed = if air_only && !clean(&greedy) {
        centred_greedy(sim, scene, &caps)
    } else {
        None
    };
    let greedy = match &seed {
        Some(s) if time_of(s) <= time_of(&greedy) => s.clone(),
        _ => greedy,
    };
    let seed = seed.unwrap_or_else(|| greedy.clone());
    Baseline { greedy, seed }
}

/// A run the planning model can follow: valid, finished, and touching no wall.
fn clean(t: &Trace) -> bool {
    t.feasible() && t.crossing.is_some() && t.collisions() == 0
}

/// The fastest clean run of the greedy strafer (every look-ahead, uncapped and with each speed cap)
/// along a guide: the shortest path of a body wider than the hull by each of [`GUIDE_CLEARANCES_UNITS`]
/// on either side in turn, so the guide keeps that far from every wall; the first guide with a clean run
/// gives it. Needed where the best greedy run is not clean: in a corridor only a little wider than the
/// hull the plain guide runs along the grown inner corner and the greedy strafer, steering by its side
/// only, weaves across it; between solid walls the fastest greedy runs slide along them, which the
/// planning model (no collisions) cannot follow. `None` if no run is clean.
fn centred_greedy(sim: &Simulation, scene: &Scene, caps: &[f64]) -> Option<Trace> {
    for extra in GUIDE_CLEARANCES_UNITS {
        let Ok(corridor) = Corridor::with_half_width(&scene.walls, HULL_HALF_WIDTH_UNITS + extra)
        else {
            continue;
        };
        let Some((_, path)) =
            corridor.shortest_path(scene.start.pos, (scene.finish.a, scene.finish.b))
        else {
            continue;
        };
        let mut best: Option<Trace> = None;
        for cap in std::iter::once(None).chain(caps.iter().copied().map(Some)) {
            for &la in &GREEDY_LOOKAHEADS_UNITS {
                let greedy = Greedy::new(path.clone(), la);
                let t = sim.run(&mut match cap {
                    Some(cap) => greedy.with_speed_cap(cap),
                    None => greedy,
                });
                if clean(&t) && best.as_ref().is_none_or(|b| time_of(&t) < time_of(b)) {
                    best = Some(t);
                }
            }
        }
        if best.is_some() {
            return best;
        }
    }
    None
}
