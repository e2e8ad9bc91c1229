//! `solve` on generated scenes that start on the ground: a fixed sample of the generated family's
//! groundstrafing, bunnyhopping and Half-Life 2 kinds (`strafeopt gen --kinds ground,bhop,hl2`,
//! [`jump_family`]), at `fast`. For every scene: the plan is valid in f64 and in the engine-exact mode at
//! the same frame, never slower than the strongest greedy run, never before the lower bound; a
//! groundstrafing plan never leaves the ground and a jumping plan is airborne exactly when it jumps. Most
//! bunnyhop plans jump and beat greedy. One scene is solved twice to the same controls.

mod common;

use strafeopt::optimise::{solve, Outcome, Quality, SearchSettings};
use strafeopt::scene::generate::{generate_sample, GeneratedScene, GeneratorSettings, SceneKind};

/// The sample: scenes 0 to [`SAMPLE_COUNT`] - 1 of this seed of [`jump_family`].
const SAMPLE_SEED: u64 = 2027;
/// At least 8 scenes of the kinds that start on the ground, within the CI budget at `fast` (each solves
/// in about a second).
const SAMPLE_COUNT: u64 = 18;

/// The CI-sized family (1 or 2 turns, legs up to 800 units, 100 or 250 fps) with the kinds that start on
/// the ground.
fn jump_family() -> GeneratorSettings {
    GeneratorSettings {
        kinds: vec![SceneKind::Ground, SceneKind::Bhop, SceneKind::Hl2],
        ..GeneratorSettings::ci_sized()
    }
}

fn sample() -> Vec<GeneratedScene> {
    generate_sample(SAMPLE_SEED, SAMPLE_COUNT, &jump_family()).unwrap_or_else(|e| panic!("{e}"))
}

#[test]
fn ground_bhop_and_hl2_scenes_are_solved_validly_never_slower_than_greedy_nor_before_the_bound() {
    let sample = sample();
    // Every kind is in the sample.
    for kind in [SceneKind::Ground, SceneKind::Bhop, SceneKind::Hl2] {
        assert!(
            sample.iter().any(|g| g.drawn.kind == kind),
            "no {kind:?} scene in the sample"
        );
    }
    let settings = SearchSettings::for_quality(Quality::Fast);
    let results = common::on_every_core(&sample, |g| {
        let o = solve(&g.scene, &settings).unwrap_or_else(|e| panic!("{}: {e}", g.name));
        checked(g, &o)
    });
    eprintln!(
        "{}",
        results
            .iter()
            .map(|r| r.0.as_str())
            .collect::<Vec<_>>()
            .join("\n")
    );
    // The hop planner beats greedy on most bunnyhop scenes (a planner that gave up would return greedy),
    // and most of its plans jump (one that never jumped would be groundstrafing only).
    let bhops: Vec<Checked> = results
        .iter()
        .zip(&sample)
        .filter(|(_, g)| g.drawn.kind == SceneKind::Bhop)
        .map(|(r, _)| r.1)
        .collect();
    let won = bhops.iter().filter(|c| c.faster_than_greedy).count();
    let jumped = bhops.iter().filter(|c| c.jumps).count();
    assert!(
        won * 2 > bhops.len() && jumped * 2 > bhops.len(),
        "of {} bunnyhop scenes, {won} faster than greedy, {jumped} jump",
        bhops.len()
    );
}

/// What [`checked`] found beyond its assertions.
#[derive(Clone, Copy, Debug)]
struct Checked {
    /// The plan crosses strictly before greedy.
    faster_than_greedy: bool,
    /// The plan jumps at least once.
    jumps: bool,
}

/// Checks the outcome of `g`; returns a line for the report and what it found.
fn checked(g: &GeneratedScene, o: &Outcome) -> (String, Checked) {
    let name = &g.name;
    let plan = o
        .trace
        .crossing
        .unwrap_or_else(|| panic!("{name}: the plan does not cross"));
    assert!(o.trace.feasible(), "{name}: the plan breaks a rule");
    let ee = o.engine_exact.crossing.map(|c| c.frames);
    assert!(
        o.engine_exact.feasible() && ee == Some(plan.frames),
        "{name}: engine-exact {ee:?} against the plan's frame {}",
        plan.frames
    );
    // The greedy baseline is valid on every scene of the sample, and the plan never slower.
    let greedy = o
        .greedy
        .crossing
        .filter(|_| o.greedy.feasible())
        .unwrap_or_else(|| panic!("{name}: greedy did not finish validly"));
    assert!(
        plan.time <= greedy.time + 1e-12,
        "{name}: plan {plan:?} slower than greedy {greedy:?}"
    );
    let bound = o.bound.crossing;
    assert!(
        plan.time >= bound.time - 1e-12 && plan.frames >= bound.frames,
        "{name}: plan {plan:?} before the bound {bound:?}"
    );
    // The kind shows in the plan: groundstrafing stays on the ground, bunnyhopping leaves it.
    let airborne = o.trace.frames.iter().filter(|f| !f.on_ground).count();
    match g.drawn.kind {
        SceneKind::Ground => assert_eq!(airborne, 0, "{name}: a groundstrafe left the ground"),
        // A bunnyhop plan may groundstrafe all the way (a hairpin in a narrow corridor); whether the
        // plans jump at all is checked over the sample.
        SceneKind::Bhop | SceneKind::Hl2 => assert_eq!(
            o.controls.iter().any(|c| c.jump),
            airborne > 0,
            "{name}: airborne without a jump, or a jump that never left the ground"
        ),
        SceneKind::Air => panic!("{name}: an airborne scene in the ground sample"),
    }
    let jumps = o.controls.iter().filter(|c| c.jump).count();
    let line = format!(
        "{name} ({}, {} fps, {} turns, width {}, start {} ups, {} walls): plan {} ({:.6} s, {jumps} jumps), \
         greedy {}, bound {}, {:.1} s, {} ({})",
        g.drawn.kind.name(),
        g.drawn.fps,
        g.drawn.turns.len(),
        g.drawn.width_units,
        g.drawn.start_speed_ups,
        g.drawn.walls.name(),
        plan.frames,
        plan.time,
        greedy.frames,
        bound.frames,
        o.solve_seconds,
        o.status,
        o.source
    );
    let found = Checked {
        faster_than_greedy: plan.time < greedy.time,
        jumps: jumps > 0,
    };
    (line, found)
}

#[test]
fn a_bhop_scene_is_solved_to_the_same_controls_twice() {
    let sample = sample();
    let g = sample
        .iter()
        .find(|g| g.drawn.kind == SceneKind::Bhop)
        .unwrap_or_else(|| panic!("no bunnyhop scene in the sample"));
    let settings = SearchSettings::for_quality(Quality::Fast);
    let first = solve(&g.scene, &settings).unwrap_or_else(|e| panic!("{e}"));
    let second = solve(&g.scene, &settings).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(first.controls, second.controls, "{}", g.name);
    assert_eq!(first.trace.crossing, second.trace.crossing, "{}", g.name);
    // The plan is the optimiser's, not the greedy fallback.
    assert_eq!(first.source, "optimised", "{}", g.name);
}
