//! The optimised legal ABH run (issue 7, point 3): `solve` on `scenarios/hl2-abh-100m.toml` plans the jumps
//! (`optimise::jumps`), stays in the lane in f64 and engine-exact, beats the hand-tuned controller of
//! `sim::abh` (4.316 s) and the greedy strafer, and stays above the schedule-aware lower bound.

use serde_json::Value;
use strafeopt::optimise::{solve, Quality, SearchSettings, SearchStatus};
use strafeopt::scene::Scene;
use strafeopt::sim::abh::{hops_from_trace, run_abh, AbhParams};
use strafeopt::sim::Simulation;

mod common;
use common::strafeopt;

const SCENE: &str = "scenarios/hl2-abh-100m.toml";
/// The optimised time from the pistol at `--quality fast`, seconds, and its crossing tick.
const FAST_TIME_S: f64 = 3.708_771_145_400_956;
const FAST_FRAME: u64 = 248;
/// Times agree to this many seconds: the search is deterministic, the slack is for libm differences.
const TOL_TIME_S: f64 = 1e-6;
/// The hand-tuned ABH controller's time from the pistol, seconds (`tests/abh.rs`).
const HAND_TUNED_S: f64 = 4.316;

fn scene() -> Scene {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join(SCENE);
    Scene::load(&path).unwrap_or_else(|e| panic!("{e}"))
}

#[test]
fn optimised_run_is_pinned_legal_and_beats_the_hand_tuned_one() {
    let scene = scene();
    let o = solve(&scene, &SearchSettings::for_quality(Quality::Fast))
        .unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(o.source, "optimised");
    assert!(
        matches!(o.status, SearchStatus::Converged { .. }),
        "{:?}",
        o.status
    );
    let c = o
        .trace
        .crossing
        .unwrap_or_else(|| panic!("the plan crosses"));
    assert_eq!(c.frames, FAST_FRAME);
    assert!((c.time - FAST_TIME_S).abs() < TOL_TIME_S, "{c:?}");
    // In the lane in f64 (the hull never touches a lane line) and engine-exact, crossing in the same tick.
    assert!(o.trace.feasible() && o.trace.first_rule_violation().is_none());
    assert!(
        o.trace.min_clearance() > 10.0,
        "{}",
        o.trace.min_clearance()
    );
    assert!(o.engine_exact.feasible());
    let e = o
        .engine_exact
        .crossing
        .unwrap_or_else(|| panic!("engine-exact crosses"));
    assert_eq!(e.frames, c.frames);
    assert!((e.time - c.time).abs() < 1e-5, "{e:?} vs {c:?}");
    // Better than the hand-tuned controller and the greedy strafer; above the lower bound, within 1%.
    let sim = Simulation::new(&scene).unwrap_or_else(|e| panic!("{e}"));
    let hand = run_abh(&sim, AbhParams::default());
    let hand_time = hand.pistol_to_line.unwrap_or(0.0);
    assert!((hand_time - HAND_TUNED_S).abs() < 1e-3, "{hand_time}");
    assert!(c.time < hand_time - 0.6, "{} vs {hand_time}", c.time);
    let g = o.greedy.crossing.map_or(0.0, |g| g.time);
    assert!(c.time < g);
    let lb = o.bound.crossing.time;
    assert!(
        lb <= c.time && (c.time - lb) / lb < 0.01,
        "{lb} vs {}",
        c.time
    );
    // The hops: jumps on the landing ticks, the standing first jump 35 ticks (0.525 s) in the air, the
    // ducked backhops 36 (0.540 s); the clamp reached on the sixth.
    let tau = scene.frame_time_s();
    let hops = hops_from_trace(&o.trace, tau);
    let frames: Vec<u64> = hops.iter().map(|h| h.frame).collect();
    assert_eq!(frames, [22, 57, 93, 129, 165, 201, 237]);
    assert!((hops[0].hop_time.unwrap_or(0.0) - 0.525).abs() < 1e-9);
    for h in &hops[1..hops.len() - 1] {
        assert!((h.hop_time.unwrap_or(0.0) - 0.54).abs() < 1e-9, "{h:?}");
    }
    let speeds: Vec<f64> = hops.iter().map(|h| h.speed).collect();
    for (s, want) in speeds.iter().zip([
        224.975, 399.048, 704.144, 1284.868, 2427.657, 3500.105, 3500.046,
    ]) {
        assert!((s - want).abs() < 0.01, "{speeds:?}");
    }
}

#[test]
fn higher_quality_is_no_worse() {
    let scene = scene();
    let fast = solve(&scene, &SearchSettings::for_quality(Quality::Fast))
        .unwrap_or_else(|e| panic!("{e}"));
    let balanced = solve(&scene, &SearchSettings::for_quality(Quality::Balanced))
        .unwrap_or_else(|e| panic!("{e}"));
    let t = |o: &strafeopt::optimise::Outcome| o.trace.crossing.map_or(f64::INFINITY, |c| c.time);
    assert!(t(&balanced) <= t(&fast), "{} vs {}", t(&balanced), t(&fast));
    assert!(balanced.engine_exact.feasible());
}

#[test]
fn cli_solve_json_plans_the_abh_run_and_report_rebuilds_it() {
    let out = strafeopt(&["solve", SCENE, "--quality", "fast", "--json"]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let v: Value = serde_json::from_slice(&out.stdout).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(v["source"], "optimised");
    assert_eq!(v["status"]["status"], "converged");
    assert_eq!(v["feasible"], true);
    assert_eq!(v["engine_exact"]["feasible"], true);
    assert_eq!(v["frames"].as_u64(), Some(FAST_FRAME));
    assert_eq!(v["engine_exact"]["frames"].as_u64(), Some(FAST_FRAME));
    let t = v["time"].as_f64().unwrap_or(f64::NAN);
    assert!((t - FAST_TIME_S).abs() < TOL_TIME_S, "{t}");
    let lb = v["lower_bound"]["time"].as_f64().unwrap_or(f64::NAN);
    assert!(lb <= t);
    // `report` replays the saved plans.
    let dir = std::env::temp_dir().join(format!("strafeopt-abh-solve-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap_or_else(|e| panic!("{e}"));
    let result = dir.join("abh.json");
    std::fs::write(&result, &out.stdout).unwrap_or_else(|e| panic!("{e}"));
    let html = dir.join("abh.html");
    let out = strafeopt(&[
        "report",
        result.to_str().unwrap_or_default(),
        "-o",
        html.to_str().unwrap_or_default(),
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(html.exists());
    let _ = std::fs::remove_dir_all(&dir);
}
