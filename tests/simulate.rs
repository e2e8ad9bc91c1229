//! Simulation of every shipped scene (issue 4): the greedy baseline and the lower bound are pinned, no
//! valid run beats its bound, and solid walls keep the hull out.

use std::path::Path;
use strafeopt::optimise::lower_bound;
use strafeopt::scene::Scene;
use strafeopt::sim::controllers::{best_greedy, GREEDY_LOOKAHEADS_UNITS};
use strafeopt::sim::{Greedy, Playback, SideStrafer, Simulation};

fn load(name: &str) -> Scene {
    let path = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("scenarios")
        .join(format!("{name}.toml"));
    Scene::load(&path).unwrap_or_else(|e| panic!("{e}"))
}

/// (scene, greedy frames, greedy time s, greedy valid, bound frames, bound time s), measured with
/// `strafeopt simulate SCENE --json`.
const PINNED: [(&str, u64, f64, bool, u64, f64); 11] = [
    (
        "hl-bend90-1000fps-aa100",
        3188,
        3.1877272478539265,
        true,
        3169,
        3.1680846651802557,
    ),
    (
        "hl-bend90-100fps",
        406,
        4.050373391977208,
        true,
        398,
        3.979127346746283,
    ),
    (
        "hl-bend90-narrow-100fps",
        514,
        5.139674703868488,
        false,
        500,
        4.999689318900755,
    ),
    (
        "hl-bhop-bend90-100fps",
        459,
        4.586892838761801,
        true,
        377,
        3.7611453857915844,
    ),
    (
        "hl-bhop-cap-100fps",
        2161,
        21.60976962007521,
        true,
        1755,
        17.544652677942764,
    ),
    (
        "hl-bhop-hairpin-100fps",
        536,
        5.351822053302249,
        false,
        405,
        4.043329738964877,
    ),
    (
        "hl-groundstrafe-1000fps",
        39550,
        39.549726815201716,
        true,
        39550,
        39.54960377339651,
    ),
    (
        "hl-hairpin-100fps",
        456,
        4.55834963076213,
        false,
        422,
        4.21083683381524,
    ),
    (
        "hl-sbend-100fps",
        561,
        5.602848635083389,
        false,
        547,
        5.467776836309179,
    ),
    (
        "hl2-abh-100m",
        737,
        11.05453621493537,
        true,
        247,
        3.6967325643592135,
    ),
    (
        "hl2-bend90-66fps",
        338,
        5.065711647099607,
        false,
        313,
        4.6840258444292076,
    ),
];

/// Times agree to this many seconds: the runs are deterministic, the slack is for libm differences.
const TOL_TIME_S: f64 = 1e-6;

#[test]
fn shipped_scenes_greedy_and_bound_are_pinned() {
    for (name, frames, time, valid, lb_frames, lb_time) in PINNED {
        let scene = load(name);
        let sim = Simulation::new(&scene).unwrap_or_else(|e| panic!("{name}: {e}"));
        let bound = lower_bound(&scene, sim.corridor()).unwrap_or_else(|e| panic!("{name}: {e}"));
        assert_eq!(bound.crossing.frames, lb_frames, "{name}: bound frames");
        assert!(
            (bound.crossing.time - lb_time).abs() < TOL_TIME_S,
            "{name}: bound {bound:?}"
        );
        let (trace, _) = best_greedy(&sim, &bound.path, &GREEDY_LOOKAHEADS_UNITS);
        let c = trace
            .crossing
            .unwrap_or_else(|| panic!("{name}: greedy never finished"));
        assert_eq!(c.frames, frames, "{name}: greedy frames");
        assert!((c.time - time).abs() < TOL_TIME_S, "{name}: greedy {c:?}");
        assert_eq!(trace.feasible(), valid, "{name}: greedy validity");
        if trace.feasible() {
            // No valid run beats the bound (docs/physics.md section 6).
            assert!(
                c.time >= bound.crossing.time,
                "{name}: {} < bound {}",
                c.time,
                bound.crossing.time
            );
        } else {
            assert!(trace.first_rule_violation().is_some());
        }
    }
}

#[test]
fn groundstrafing_settles_at_the_maximum_groundstrafe_speed() {
    let scene = load("hl-groundstrafe-1000fps");
    let sim = Simulation::new(&scene).unwrap_or_else(|e| panic!("{e}"));
    let bound = lower_bound(&scene, sim.corridor()).unwrap_or_else(|e| panic!("{e}"));
    let trace = sim.run(&mut Greedy::new(bound.path.clone(), 1000.0));
    assert_eq!(format!("{:.1}", trace.final_speed()), "505.2");
}

#[test]
fn the_bunnyhop_cap_holds_the_speed_under_1_7_maxspeed_at_each_jump() {
    let scene = load("hl-bhop-cap-100fps");
    let sim = Simulation::new(&scene).unwrap_or_else(|e| panic!("{e}"));
    let bound = lower_bound(&scene, sim.corridor()).unwrap_or_else(|e| panic!("{e}"));
    let trace = sim.run(&mut Greedy::new(bound.path.clone(), 150.0));
    // Each takeoff (ground -> air) leaves at most 1.7 * 320 = 544 ups, and some are cut to 353.6.
    let mut capped = 0;
    for w in trace.frames.windows(2) {
        if w[0].on_ground && !w[1].on_ground {
            assert!(w[1].speed <= 544.0 + 1.0, "takeoff at {}", w[1].speed);
        }
        if w[1].speed < w[0].speed - 100.0 {
            capped += 1;
            assert!((w[1].speed - 353.6).abs() < 2.0, "cut to {}", w[1].speed);
        }
    }
    assert!(capped > 0, "the cap never fired");
}

#[test]
fn playback_reproduces_a_run_exactly() {
    let scene = load("hl-bend90-100fps");
    let sim = Simulation::new(&scene).unwrap_or_else(|e| panic!("{e}"));
    let bound = lower_bound(&scene, sim.corridor()).unwrap_or_else(|e| panic!("{e}"));
    let greedy = sim.run(&mut Greedy::new(bound.path.clone(), 300.0));
    let replay = sim.run(&mut Playback {
        controls: greedy.controls.clone(),
        label: "playback".into(),
    });
    assert_eq!(replay.crossing, greedy.crossing);
    assert_eq!(replay.frames, greedy.frames);
}

#[test]
fn solid_walls_stop_the_hull_and_it_never_ends_inside() {
    // The 100 fps bend with solid walls: turning left from the start runs into the inner wall and slides.
    let text = std::fs::read_to_string(
        Path::new(env!("CARGO_MANIFEST_DIR")).join("scenarios/hl-bend90-100fps.toml"),
    )
    .unwrap_or_default()
    .replace("kind = \"rule\"", "kind = \"solid\"");
    let scene = Scene::from_toml_str(&text, "solid-bend").unwrap_or_else(|e| panic!("{e}"));
    let sim = Simulation::new(&scene).unwrap_or_else(|e| panic!("{e}"));
    let trace = sim.run(&mut SideStrafer {
        side: strafeopt::physics::Side::Left,
    });
    assert!(trace.collisions() > 0, "never touched a wall");
    assert!(trace.first_rule_violation().is_none());
    for f in &trace.frames {
        assert!(
            f.clearance >= -1e-9,
            "frame {} inside a wall by {}",
            f.frame,
            -f.clearance
        );
        assert!(f.speed.is_finite());
    }
}
