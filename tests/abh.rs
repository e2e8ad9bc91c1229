//! The frame-level accelerated-backhop run (`sim::abh`, docs/physics.md sections 3, 10, 11) on
//! `scenarios/hl2-abh-100m.toml`: hop frames, speeds and the crossing time pinned against an independent
//! one-dimensional re-derivation from docs/physics.md's formulas; the lane kept (also engine-exact); the CLI.

use assert_cmd::Command;
use serde_json::Value;
use strafeopt::physics::abh::boosted_speed;
use strafeopt::physics::{Control, PlayerState};
use strafeopt::scene::Scene;
use strafeopt::sim::abh::{boost_addition, jump_airtime_s, run_abh, Abh, AbhParams, AbhRun};
use strafeopt::sim::{Controller, Simulation};

const SCENE: &str = "scenarios/hl2-abh-100m.toml";
/// 100 m in units (docs/physics.md section 1).
const DISTANCE_UNITS: f64 = 5249.34;

fn scene() -> Scene {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join(SCENE);
    Scene::load(&path).unwrap_or_else(|e| panic!("{e}"))
}

fn run(params: AbhParams) -> AbhRun {
    let scene = scene();
    let sim = Simulation::new(&scene).unwrap_or_else(|e| panic!("{e}"));
    run_abh(&sim, params)
}

/// The run re-derived in one dimension from docs/physics.md alone (no `Stepper`): the unduck frames, ground
/// friction (section 4) and the ground FME along the velocity (section 5) while walking, the boost
/// (section 11) on jump frames, the per-component clamp (section 10), and the discrete airtime of the jump
/// (sections 2 and 3: ducked, the jump sets `v_z = 160`; standing, it adds 160 to the first gravity
/// half-step; the player lands within the 2-unit layer).
struct Expected {
    jump_frames: Vec<u64>,
    speeds: Vec<f64>,
    crossing_time: f64,
}

fn expected(walk_while_unducking: bool) -> Expected {
    let scene = scene();
    let v = scene.vars;
    let tau = v.frame_time_s();
    let (mx, k, e) = (v.maxspeed, v.friction_k(false), v.stopspeed);
    // Unduck: standing once the timer reaches 0.2 s, in the frame it does.
    let unduck_frames = ((v.unduck_time_s / tau) - 1e-9).ceil() as u64;
    // Discrete airtime: with v0 the vertical speed of the jump frame's move, z(n) = tau (n v0 - g tau
    // n (n - 1) / 2); the player lands after frame n when z(n) <= 2 and jumps again in frame n + 1.
    let air_frames_of = |v0: f64| {
        let z = |n: f64| tau * (n * v0 - v.gravity * tau * n * (n - 1.0) / 2.0);
        (2..1000).find(|&n| z(n as f64) <= 2.0).unwrap_or(0) as u64
    };
    let standing_air_frames = air_frames_of(160.0 - v.gravity * tau / 2.0);
    let ducked_air_frames = air_frames_of(160.0);
    let (mut x, mut speed) = (0.0_f64, 0.0_f64);
    let mut jump_frames = Vec::new();
    let mut speeds = Vec::new();
    let mut next_jump: Option<u64> = None;
    for frame in 1..10_000u64 {
        let before = x;
        let standing = frame >= unduck_frames;
        if jump_frames.is_empty() {
            if standing && speed >= mx - 1e-6 {
                speed = boosted_speed(speed, mx, 0.5, mx, false).min(v.maxvelocity);
                jump_frames.push(frame);
                speeds.push(speed);
                next_jump = Some(frame + standing_air_frames);
            } else {
                // Friction, then the ground FME straight ahead with wish speed M (cropped while ducked).
                if speed >= 0.1 {
                    let control = speed.max(e);
                    speed = (speed - control * k * tau).max(0.0);
                }
                let m = if standing {
                    mx
                } else if walk_while_unducking {
                    mx * v.duck_multiplier
                } else {
                    0.0
                };
                let gamma1 = tau * m * v.accelerate;
                if m > speed {
                    speed += gamma1.min(m - speed);
                }
                if speed < 1.0 {
                    speed = 0.0;
                }
            }
        } else if Some(frame) == next_jump {
            speed = boosted_speed(speed, 0.0, 0.1, mx, true).min(v.maxvelocity);
            jump_frames.push(frame);
            speeds.push(speed);
            next_jump = Some(frame + ducked_air_frames);
        }
        x += speed * tau;
        if x >= DISTANCE_UNITS {
            let f = (DISTANCE_UNITS - before) / (x - before);
            return Expected {
                jump_frames,
                speeds,
                crossing_time: (frame as f64 - 1.0 + f) * tau,
            };
        }
    }
    panic!("the one-dimensional run never reached the line");
}

#[test]
fn jump_speed_airtime_and_clamp_follow_physics_md() {
    let v = scene().vars;
    // Section 2: Half-Life 2's fixed 160 ups (movement optimisations on), not sqrt(2 * 600 * 21).
    assert_eq!(v.jump_speed_ups(), 160.0);
    assert_eq!(v.jump_vz_ups(-4.5, true), 160.0);
    assert_eq!(v.jump_vz_ups(-4.5, false), 155.5);
    // Section 10's airtime back to the 2-unit layer with Source's numbers: (160 + sqrt(160^2 - 4 g)) / g
    // = 0.5205 s, 34.7 frames; the frame loop lands 36 frames after a ducked jump (0.54 s) and 35 after
    // the standing first jump (0.525 s, 4.5 ups slower up), not the article's 0.51 s.
    let t = jump_airtime_s(&v).unwrap_or(f64::NAN);
    assert!((t - 0.520_53).abs() < 1e-4, "{t}");
    let r = run(AbhParams::default());
    let frames: Vec<Option<u64>> = r.hops[..r.hops.len() - 1]
        .iter()
        .map(|h| h.hop_time.map(|t| (t / 0.015).round() as u64))
        .collect();
    assert_eq!(frames[0], Some(35));
    assert!(frames[1..].iter().all(|&f| f == Some(36)), "{frames:?}");
    assert!((r.hops[1].hop_time.unwrap_or(0.0) - 0.54).abs() < 1e-12);
    // Section 10/11: 2 * 2085 - 165 = 4005 is clamped per component to 3500 (the run is along x).
    let h7 = r.hops[6];
    assert!((boosted_speed(2085.0, 0.0, 0.1, 150.0, true) - 4005.0).abs() < 1e-9);
    assert_eq!(h7.speed, 3500.0);
    let rec = r.trace.frames[h7.frame as usize - 1];
    assert_eq!(rec.vel.x, 3500.0);
}

#[test]
fn frame_level_run_matches_the_independent_derivation() {
    let r = run(AbhParams::default());
    let want = expected(false);
    let frames: Vec<u64> = r.hops.iter().map(|h| h.frame).collect();
    // 14 unduck frames (the 14th already standing), 9 walking frames to 150 ups, the standing jump in
    // frame 23 (35 frames in the air); then a ducked backhop every 36 frames.
    assert_eq!(frames, vec![23, 58, 94, 130, 166, 202, 238, 274]);
    assert_eq!(frames, want.jump_frames);
    for (h, s) in r.hops.iter().zip(&want.speeds) {
        assert!((h.speed - s).abs() < 1e-6, "{} vs {s}", h.speed);
    }
    // The article's speeds, each within 1e-6 ups (the walk reaches 150 up to rounding).
    let article = [225.0, 285.0, 405.0, 645.0, 1125.0, 2085.0, 3500.0, 3500.0];
    for (h, s) in r.hops.iter().zip(article) {
        assert!((h.speed - s).abs() < 1e-6, "{} vs {s}", h.speed);
    }
    // The first hop's speed from the boost formula and the speed before the jump frame.
    let j = r.hops[0].frame as usize;
    let takeoff = r.trace.frames[j - 2].speed;
    assert!((takeoff - 150.0).abs() < 1e-6);
    assert!((r.hops[0].speed - boosted_speed(takeoff, 150.0, 0.5, 150.0, false)).abs() < 1e-9);
    // Times from the pistol: first jump 22 * 0.015 = 0.330 s; the line at 4.316 s (the independent
    // derivation to 1e-6 s; the pinned figure to 1 ms).
    assert!((r.first_jump.unwrap_or(f64::NAN) - 0.33).abs() < 1e-12);
    let t = r.pistol_to_line.unwrap_or(f64::NAN);
    assert!(
        (t - want.crossing_time).abs() < 1e-6,
        "{t} vs {}",
        want.crossing_time
    );
    assert!((t - 4.316).abs() < 1e-3, "{t}");
    // 3.986 s after the first jump, against the article's 3.865 s.
    assert!((t - r.first_jump.unwrap_or(0.0) - 3.986).abs() < 1e-3);
}

#[test]
fn the_run_stays_in_the_lane_in_f64_and_engine_exact() {
    let r = run(AbhParams::default());
    assert!(r.in_lane && r.trace.feasible());
    // The hull centre stays on the centre line: 16.02 units from each lane line.
    assert!((r.trace.min_clearance() - 16.02).abs() < 1e-3);
    assert!(r.engine_exact.feasible() && !r.engine_exact.broke_rule);
    let (c64, c32) = (
        r.trace.crossing.map(|c| c.time).unwrap_or(f64::NAN),
        r.engine_exact.crossing.map(|c| c.time).unwrap_or(f64::NAN),
    );
    assert!((c64 - c32).abs() < 1e-3, "{c64} vs {c32}");
    assert!((r.engine_exact.min_clearance - 16.02).abs() < 1e-2);
}

#[test]
fn the_turn_schedule_does_not_change_the_trajectory() {
    // No keys in the air: the view only acts on jump frames (module documentation of sim::abh).
    let a = run(AbhParams {
        turn_frames: 1,
        ..AbhParams::default()
    });
    let b = run(AbhParams {
        turn_frames: 30,
        ..AbhParams::default()
    });
    assert_eq!(a.trace.frames.len(), b.trace.frames.len());
    for (x, y) in a.trace.frames.iter().zip(&b.trace.frames) {
        assert_eq!(x.pos, y.pos);
        assert_eq!(x.vel, y.vel);
    }
}

#[test]
fn walking_while_standing_up_shows_the_duck_crop_order() {
    // Holding forward while standing up. Source clamps the keys to Mx first (CheckParameters) and crops
    // them after (HandleDuckingSpeedCrop): ducked walking has 150 * 0.333 = 49.95 ups of wish speed, so
    // the jump comes in frame 22, as the independent derivation says.
    let r = run(AbhParams {
        walk_while_unducking: true,
        ..AbhParams::default()
    });
    let sdk_order = expected(true);
    assert_eq!(sdk_order.jump_frames[0], 22);
    assert_eq!(r.hops.first().map(|h| h.frame), Some(22));
    // Ducked walking with the full key stays under the cropped wish speed.
    let before_standing = r.trace.frames[12];
    assert!(before_standing.ducked);
    assert!(
        before_standing.speed <= 150.0 * 0.333 + 1e-9,
        "{}",
        before_standing.speed
    );
    assert!(r.in_lane && r.engine_exact.feasible());
}

/// The ABH controller with a fixed yaw error added on every jump frame (a hand that is off by `err`).
struct Shaky {
    inner: Abh,
    err_rad: f64,
}

impl Controller for Shaky {
    fn name(&self) -> String {
        "abh-shaky".to_string()
    }
    fn control(&mut self, frame: u64, s: &PlayerState, sim: &Simulation) -> Control {
        let mut c = self.inner.control(frame, s, sim);
        if c.jump {
            c.yaw_rad += self.err_rad;
        }
        c
    }
}

#[test]
fn steering_holds_the_lane_against_a_yaw_error() {
    let scene = scene();
    let sim = Simulation::new(&scene).unwrap_or_else(|e| panic!("{e}"));
    let err = 0.25_f64.to_radians();
    let steered = sim.run(&mut Shaky {
        inner: Abh::default(),
        err_rad: err,
    });
    let loose = sim.run(&mut Shaky {
        inner: Abh::new(AbhParams {
            steer: false,
            ..AbhParams::default()
        }),
        err_rad: err,
    });
    assert!(steered.feasible(), "{:?}", steered.first_rule_violation());
    assert!(loose.first_rule_violation().is_some());
}

#[test]
fn the_boost_addition_matches_the_article_model() {
    let v = scene().vars;
    for speed in [0.0, 100.0, 150.0, 225.0, 2085.0, 3500.0] {
        // Ducked, no keys, facing backwards: v -> v - add.
        let add = boost_addition(&v, true, 0.0, 0.0, speed);
        assert!((speed - add - boosted_speed(speed, 0.0, 0.1, 150.0, true)).abs() < 1e-9);
        // Standing, full forward key (scaled down to 150): v -> v + add.
        let add = boost_addition(&v, false, v.forward_key_speed, 0.0, speed);
        assert!((speed + add - boosted_speed(speed, 150.0, 0.5, 150.0, false)).abs() < 1e-9);
    }
}

fn strafeopt(args: &[&str]) -> Value {
    let out = Command::cargo_bin("strafeopt")
        .map(|mut c| {
            c.current_dir(env!("CARGO_MANIFEST_DIR"))
                .args(args)
                .output()
        })
        .unwrap_or_else(|e| panic!("binary: {e}"))
        .unwrap_or_else(|e| panic!("run {args:?}: {e}"));
    assert!(
        out.status.success(),
        "{args:?}: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    serde_json::from_slice(&out.stdout).unwrap_or_else(|e| panic!("{args:?}: {e}"))
}

#[test]
fn cli_simulate_controller_abh() {
    let v = strafeopt(&["simulate", SCENE, "--controller", "abh", "--json"]);
    assert_eq!(v["controller"], "abh");
    assert_eq!(v["feasible"], true);
    assert_eq!(v["frames"], 288);
    let t = v["time"].as_f64().unwrap_or(f64::NAN);
    assert!((t - 4.316).abs() < 1e-3, "{t}");
    assert_eq!(v["first_rule_violation_frame"], Value::Null);
}

#[test]
fn cli_calc_abh_json_has_frame_level() {
    let v = strafeopt(&["calc", "abh", "--json"]);
    // The article's keys, unchanged.
    for key in [
        "form",
        "hops",
        "crossing_time",
        "landing_past_line",
        "max_speed",
        "hop_time",
        "distance",
        "inputs",
    ] {
        assert!(v.get(key).is_some(), "no {key}");
    }
    let article = v["crossing_time"].as_f64().unwrap_or(0.0);
    assert_eq!(format!("{article:.3}"), "3.865");
    let fl = &v["frame_level"];
    let hops = fl["hops"].as_array().cloned().unwrap_or_default();
    assert_eq!(hops.len(), 8);
    for h in &hops {
        assert!(h["time"].is_f64() && h["speed"].is_f64(), "{h}");
    }
    assert!((hops[1]["speed"].as_f64().unwrap_or(0.0) - 285.0).abs() < 1e-6);
    assert!((fl["pistol_to_line"].as_f64().unwrap_or(0.0) - 4.316).abs() < 1e-3);
    assert!((fl["first_jump"].as_f64().unwrap_or(0.0) - 0.330).abs() < 1e-9);
    assert_eq!(fl["in_lane"], true);
    assert_eq!(fl["engine_exact"]["feasible"], true);
}

#[test]
fn report_rebuilds_a_saved_abh_run() {
    let dir = std::env::temp_dir().join(format!("strafeopt-abh-report-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap_or_else(|e| panic!("{e}"));
    let bin = || {
        assert_cmd::Command::cargo_bin("strafeopt")
            .map(|mut c| {
                c.current_dir(env!("CARGO_MANIFEST_DIR"));
                c
            })
            .unwrap_or_else(|e| panic!("{e}"))
    };
    let out = bin()
        .args([
            "simulate",
            "scenarios/hl2-abh-100m.toml",
            "--controller",
            "abh",
            "--json",
        ])
        .output()
        .unwrap_or_else(|e| panic!("{e}"));
    assert!(out.status.success());
    let saved = dir.join("abh.json");
    std::fs::write(&saved, &out.stdout).unwrap_or_else(|e| panic!("{e}"));
    let html = dir.join("abh.html");
    let out = bin()
        .args([
            "report",
            &saved.to_string_lossy(),
            "-o",
            &html.to_string_lossy(),
        ])
        .output()
        .unwrap_or_else(|e| panic!("{e}"));
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let page = std::fs::read_to_string(&html).unwrap_or_default();
    assert!(
        page.matches("<svg").count() >= 4,
        "the report has its figures"
    );
    let _ = std::fs::remove_dir_all(&dir);
}
