//! The hop planner (`optimise::hops`) on the shipped scenes with ground frames, gravity and jumps but no
//! Source boost: the bunnyhop lane, the bunnyhop bend and hairpin, the Half-Life 2 bend with jumps, the
//! groundstrafe lane. Each plan is pinned (frames, time), valid in f64 and engine-exact in the same frame,
//! never slower than greedy, never below its lower bound; the bunnyhop plans never take the cap's cut and
//! their Bunnymod XT scripts parse back; random hop policies never beat the schedule bound.

use hltas::HLTAS;
use std::path::Path;
use std::time::{Duration, Instant};
use strafeopt::optimise::bound::bhop_cap_horizontal_speed;
use strafeopt::optimise::hillclimb::XorShift64;
use strafeopt::optimise::hops::{HopPolicy, HopRunner};
use strafeopt::optimise::{lower_bound, solve, Outcome, Quality, SearchSettings, SearchStatus};
use strafeopt::report::hltas::write_hltas;
use strafeopt::scene::Scene;
use strafeopt::sim::Simulation;

mod common;
use common::strafeopt;

fn load(name: &str) -> Scene {
    let path = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("scenarios")
        .join(format!("{name}.toml"));
    Scene::load(&path).unwrap_or_else(|e| panic!("{e}"))
}

fn solved(scene: &Scene, quality: Quality) -> Outcome {
    solve(scene, &SearchSettings::for_quality(quality)).unwrap_or_else(|e| panic!("{e}"))
}

/// Times agree to this many seconds: the search is deterministic, the slack is for libm differences.
const TOL_TIME_S: f64 = 1e-6;

/// The checks every hop plan passes: optimised and converged, crossing in `frames` at `time_s`, valid in
/// f64 and engine-exact in the same frame, faster than greedy (its valid run, or any run when greedy
/// breaks a rule), not below the lower bound.
fn check_plan(name: &str, o: &Outcome, frames: u64, time_s: f64) {
    assert_eq!(o.source, "optimised", "{name}");
    assert!(
        matches!(o.status, SearchStatus::Converged { gap } if gap >= 0.0),
        "{name}: {:?}",
        o.status
    );
    let c = o
        .trace
        .crossing
        .unwrap_or_else(|| panic!("{name}: no crossing"));
    assert_eq!(c.frames, frames, "{name}: {c:?}");
    assert!((c.time - time_s).abs() < TOL_TIME_S, "{name}: {c:?}");
    assert!(o.trace.feasible(), "{name}");
    assert!(o.engine_exact.feasible(), "{name}: engine-exact");
    let e = o
        .engine_exact
        .crossing
        .unwrap_or_else(|| panic!("{name}: engine-exact crossing"));
    assert_eq!(e.frames, c.frames, "{name}: engine-exact frame");
    let g = o
        .greedy
        .crossing
        .unwrap_or_else(|| panic!("{name}: greedy crossing"));
    assert!(
        c.time < g.time || !o.greedy.feasible(),
        "{name}: {c:?} vs greedy {g:?}"
    );
    assert!(
        c.time >= o.bound.crossing.time,
        "{name}: below the bound {:?}",
        o.bound
    );
}

/// The frames of a plan that jump (jump held on a frame that starts on the ground) and the speed each
/// leaves at, from its f64 trace.
fn jump_frames(o: &Outcome) -> Vec<(usize, f64)> {
    let mut on_ground = o.trace.start.on_ground;
    let mut out = Vec::new();
    for (i, (c, rec)) in o.trace.controls.iter().zip(&o.trace.frames).enumerate() {
        if c.jump && on_ground {
            out.push((i, rec.speed));
        }
        on_ground = rec.on_ground;
    }
    out
}

#[test]
fn bunnyhop_lane_brakes_one_ground_frame_under_the_cap_and_nears_the_bound() {
    let scene = load("hl-bhop-cap-100fps");
    let o = solved(&scene, Quality::Fast);
    // Measured with `strafeopt solve scenarios/hl-bhop-cap-100fps.toml --quality fast --json`: greedy
    // takes 21.61 s (every landing over the cap, every jump cut); the schedule bound is 17.5447 s.
    check_plan("hl-bhop-cap-100fps", &o, 1759, 17.581_768_511_802_16);
    assert_eq!(o.bound.crossing.frames, 1755);
    let g = o.greedy.crossing.map_or(0.0, |g| g.time);
    assert!(g > 21.6, "{g}");
    let gap = match o.status {
        SearchStatus::Converged { gap } => gap,
        _ => f64::NAN,
    };
    assert!(gap < 0.003, "{gap}");
    // No jump is cut: each leaves at most at the cap's uncut speed (544 ups in 3-D, 353.6 if cut), and
    // every jump after the first comes after a single ground frame that braked from the hop's 588 ups.
    let limit = bhop_cap_horizontal_speed(&scene.vars, scene.effects);
    let jumps = jump_frames(&o);
    assert!(jumps.len() >= 20, "{jumps:?}");
    for &(i, _) in &jumps[1..] {
        let before = o.trace.frames[i - 1];
        assert!(before.speed <= limit, "frame {i}: {}", before.speed);
        assert!(before.speed > limit - 0.05, "frame {i}: {}", before.speed);
        assert!(o.trace.frames[i - 2].on_ground && !o.trace.frames[i - 3].on_ground);
    }
    let peak = o.trace.frames.iter().map(|f| f.speed).fold(0.0, f64::max);
    assert!(peak > 580.0 && peak < 600.0, "{peak}");
    // Jump is released in the air: never held on two frames in a row (the game needs it released to
    // jump again), so the script plays in the game.
    for w in o.trace.controls.windows(2) {
        assert!(!(w[0].jump && w[1].jump));
    }
}

#[test]
fn bunnyhop_corners_and_the_half_life_2_bend_are_pinned() {
    // Measured with `strafeopt solve SCENE --quality fast --json`.
    for (name, frames, time_s) in [
        ("hl-bhop-bend90-100fps", 387, 3.866_731_981_004_375_7),
        ("hl-bhop-hairpin-100fps", 455, 4.543_280_784_029_232),
        ("hl2-bend90-66fps", 320, 4.793_256_602_595_346_5),
    ] {
        let o = solved(&load(name), Quality::Fast);
        check_plan(name, &o, frames, time_s);
    }
}

#[test]
fn the_plan_is_deterministic_and_higher_quality_is_no_worse() {
    let scene = load("hl-bhop-bend90-100fps");
    let a = solved(&scene, Quality::Fast);
    let b = solved(&scene, Quality::Fast);
    assert_eq!(a.controls, b.controls);
    assert_eq!(a.stats.iterations, b.stats.iterations);
    let c = solved(&scene, Quality::Balanced);
    let t = |o: &Outcome| o.trace.crossing.map_or(f64::INFINITY, |c| c.time);
    assert!(t(&c) <= t(&a), "{} vs {}", t(&c), t(&a));
    assert!(c.engine_exact.feasible());
}

#[test]
fn groundstrafing_lane_says_greedy_is_optimal() {
    let scene = load("hl-groundstrafe-1000fps");
    let o = solved(&scene, Quality::Fast);
    assert_eq!(o.source, "greedy");
    let reason = match &o.status {
        SearchStatus::GreedyOptimal { reason } => reason.clone(),
        s => panic!("{s:?}"),
    };
    assert!(reason.contains("39550"), "{reason}");
    assert_eq!(o.trace.crossing, o.greedy.crossing);
    assert_eq!(o.bound.crossing.frames, 39550);
    assert!(o.engine_exact.feasible());
}

#[test]
fn a_time_limit_keeps_a_valid_plan_never_slower_than_greedy() {
    let scene = load("hl-bhop-cap-100fps");
    let settings = SearchSettings {
        time_limit: Some(Duration::from_millis(1)),
        ..SearchSettings::for_quality(Quality::Exact)
    };
    let started = Instant::now();
    // The limit reaches every stage: cut before any valid run, the solve says so and where; else the
    // best valid plan so far is returned.
    let o = match solve(&scene, &settings) {
        Ok(o) => o,
        Err(e @ strafeopt::Error::Stopped { .. }) => {
            assert!(e.to_string().contains("time limit"), "{e}");
            return;
        }
        Err(e) => panic!("{e}"),
    };
    assert!(started.elapsed() < Duration::from_secs(5));
    assert!(o.trace.feasible() && o.engine_exact.feasible());
    let (t, g) = (
        o.trace.crossing.map_or(f64::INFINITY, |c| c.time),
        o.greedy.crossing.map_or(0.0, |c| c.time),
    );
    assert!(t <= g, "{t} vs {g}");
}

#[test]
fn random_hop_policies_never_beat_the_schedule_bound() {
    for name in [
        "hl-bhop-cap-100fps",
        "hl-bhop-bend90-100fps",
        "hl2-bend90-66fps",
    ] {
        let scene = load(name);
        let sim = Simulation::new(&scene).unwrap_or_else(|e| panic!("{e}"));
        let bound = lower_bound(&scene, sim.corridor()).unwrap_or_else(|e| panic!("{e}"));
        let mut rng = XorShift64::new(7);
        for _ in 0..12 {
            let policy = HopPolicy {
                lookahead_units: 50.0 + 3000.0 * rng.next_f64(),
                air_speed_ups: if rng.next_f64() < 0.2 {
                    f64::INFINITY
                } else {
                    300.0 + 400.0 * rng.next_f64()
                },
                avoid_cut: rng.next_f64() < 0.7,
                takeoff_speed_ups: 500.0 * rng.next_f64(),
                duck_in_air: false,
            };
            let t = sim.run(&mut HopRunner::new(policy, &bound.path, &sim));
            if let Some(c) = t.crossing {
                assert!(
                    c.time >= bound.crossing.time,
                    "{name}: {policy:?} crosses at {c:?}, the bound {:?}",
                    bound.crossing
                );
            }
        }
    }
}

#[test]
fn cli_solve_writes_a_script_with_the_jumps_that_parses_back() {
    let dir = std::env::temp_dir().join(format!("strafeopt-hops-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap_or_else(|e| panic!("{e}"));
    let script = dir.join("bend.hltas");
    let out = strafeopt(&[
        "solve",
        "scenarios/hl-bhop-bend90-100fps.toml",
        "--quality",
        "fast",
        "--json",
        "--hltas",
        script.to_str().unwrap_or_default(),
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let v: serde_json::Value =
        serde_json::from_slice(&out.stdout).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(v["source"], "optimised");
    assert_eq!(v["engine_exact"]["feasible"], true);
    assert_eq!(v["engine_exact"]["frames"], v["frames"]);
    let text = std::fs::read_to_string(&script).unwrap_or_else(|e| panic!("{e}"));
    let parsed = HLTAS::from_str(&text).unwrap_or_else(|e| panic!("{e}"));
    // The script holds the plan frame for frame: its jump frames are the plan's, and so are its frames.
    let scene = load("hl-bhop-bend90-100fps");
    let o = solved(&scene, Quality::Fast);
    let mut frames = 0usize;
    let mut jumps = Vec::new();
    for b in parsed.frame_bulks() {
        let n = b.frame_count.get() as usize;
        if b.action_keys.jump {
            assert_eq!(n, 1, "a jump is held for one frame");
            jumps.push(frames);
        }
        frames += n;
    }
    assert_eq!(frames, o.controls.len());
    let planned: Vec<usize> = o
        .controls
        .iter()
        .enumerate()
        .filter(|(_, c)| c.jump)
        .map(|(i, _)| i)
        .collect();
    assert_eq!(jumps, planned);
    assert!(jumps.len() >= 4, "{jumps:?}");
    // The same plan written by the library gives the same text.
    let mut again = Vec::new();
    write_hltas(&o.trace, &scene.vars, &scene.name, &mut again).unwrap_or_else(|e| panic!("{e}"));
    let again = HLTAS::from_str(&String::from_utf8_lossy(&again)).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(again.frame_bulks().count(), parsed.frame_bulks().count());
    let _ = std::fs::remove_dir_all(&dir);
}
