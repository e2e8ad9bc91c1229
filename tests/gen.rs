//! The generated family (`scene::generate`, `strafeopt gen`): 500 scenes of the whole family are valid
//! scenes with a path whose corridor never overlaps itself (checked here from the walls, apart from the
//! generator's own test), the draws stay in their ranges and cover them, a scene depends only on its seed
//! and index, and `gen` writes files the scene loader reads. The kinds that start on the ground
//! (groundstrafing, bunnyhopping) are valid scenes with their effects, run through the same corridors
//! as the airborne scenes of the same index, and cover their start speeds.

mod common;

use common::strafeopt_in;
use std::collections::BTreeSet;
use std::path::{Path, PathBuf};
use strafeopt::geometry::BoundaryKind;
use strafeopt::physics::Vec2;
use strafeopt::physics::{Effect, Preset};
use strafeopt::scene::generate::{
    generate, generate_sample, CentrelinePiece, GeneratedScene, GeneratorSettings, SceneKind, Side,
};
use strafeopt::scene::Scene;

/// The sample the family tests use: scenes 0 to 499 of this seed.
const SAMPLE_SEED: u64 = 20_261_123;
const SAMPLE_COUNT: u64 = 500;

fn sample(settings: &GeneratorSettings, count: u64) -> Vec<GeneratedScene> {
    generate_sample(SAMPLE_SEED, count, settings).unwrap_or_else(|e| panic!("{e}"))
}

/// The whole family's sample, drawn once for the tests that share it.
fn family_sample() -> &'static [GeneratedScene] {
    static SAMPLE: std::sync::OnceLock<Vec<GeneratedScene>> = std::sync::OnceLock::new();
    SAMPLE.get_or_init(|| sample(&GeneratorSettings::default(), SAMPLE_COUNT))
}

/// How far inside a piece of the corridor a wall point may be and still count as on its edge, units:
/// the files' coordinates are rounded to 0.0005.
const INSIDE_TOL_UNITS: f64 = 0.01;

/// True when `p` is inside the part of the corridor that `piece` runs through (a leg's rectangle, a
/// turn's ring sector), more than [`INSIDE_TOL_UNITS`] from its edge.
fn strictly_inside(p: Vec2, piece: &CentrelinePiece, width: f64, gap: f64) -> bool {
    let tol = INSIDE_TOL_UNITS;
    match *piece {
        CentrelinePiece::Leg { from, to } => {
            let along = to - from;
            let length = along.length();
            let u = along * (1.0 / length);
            let t = (p - from).dot(u);
            let lateral = u.cross(p - from).abs();
            t > tol && t < length - tol && lateral < width / 2.0 - tol
        }
        CentrelinePiece::Turn {
            pivot,
            start_angle_rad,
            sweep_rad,
            ..
        } => {
            let r = (p - pivot).length();
            // The angle from the turn's start, in its direction, in [0, 2 pi).
            let raw = (p - pivot).angle() - start_angle_rad;
            let turned = (raw * sweep_rad.signum()).rem_euclid(std::f64::consts::TAU);
            let angle_tol = tol / r.max(1.0);
            r > gap / 2.0 + tol
                && r < width + gap / 2.0 - tol
                && turned > angle_tol
                && turned < sweep_rad.abs() - angle_tol
        }
    }
}

/// Points along every wall of `scene`, at most 4 units apart, each segment's ends included.
fn wall_samples(scene: &Scene) -> Vec<Vec2> {
    let mut out = Vec::new();
    for wall in &scene.walls {
        for s in wall.points.windows(2) {
            let n = ((s[1] - s[0]).length() / 4.0).ceil().max(1.0) as usize;
            out.extend((0..=n).map(|j| s[0] + (s[1] - s[0]) * (j as f64 / n as f64)));
        }
    }
    out
}

/// Every check of one generated scene that does not depend on the family's ranges.
fn assert_valid(g: &GeneratedScene, gap: f64) {
    let name = &g.name;
    // The file's text validates to the same scene (the scene validator passed inside `generate` too).
    let again = Scene::from_toml_str(&g.toml, &g.file_name()).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(again, g.scene, "{name}");
    // A path for the hull from the start to the finish.
    let corridor = g.scene.corridor().unwrap_or_else(|e| panic!("{name}: {e}"));
    let path = corridor.shortest_path(g.scene.start.pos, (g.scene.finish.a, g.scene.finish.b));
    assert!(path.is_some(), "{name}: no path");
    // No wall point inside any part of the corridor: a leg or turn that crossed another would carry its
    // walls into it.
    let width = f64::from(g.drawn.width_units);
    for p in wall_samples(&g.scene) {
        for (i, piece) in g.centreline.iter().enumerate() {
            assert!(
                !strictly_inside(p, piece, width, gap),
                "{name}: wall point ({:.3}, {:.3}) inside piece {i} {piece:?}",
                p.x,
                p.y
            );
        }
    }
}

/// The drawn figures measured back from the scene and its centre line.
fn assert_matches_drawn(g: &GeneratedScene) {
    let d = &g.drawn;
    let s = &g.scene;
    let name = &g.name;
    assert_eq!(s.vars.fps, f64::from(d.fps), "{name}");
    assert_eq!(s.vars.airaccelerate, f64::from(d.airaccelerate), "{name}");
    assert_eq!(s.start.on_ground, d.kind.on_ground(), "{name}");
    // Each kind's effects, as the shipped scenes of that kind name them (in frame order).
    let want: &[Effect] = match d.kind {
        SceneKind::Air => &[Effect::MaxVelocity, Effect::AirAccel, Effect::Walls],
        SceneKind::Ground => &[
            Effect::Friction,
            Effect::MaxVelocity,
            Effect::GroundAccel,
            Effect::Walls,
        ],
        SceneKind::Bhop => &[
            Effect::Gravity,
            Effect::Jump,
            Effect::BhopCap,
            Effect::Friction,
            Effect::MaxVelocity,
            Effect::AirAccel,
            Effect::GroundAccel,
            Effect::Walls,
        ],
        SceneKind::Hl2 => &[
            Effect::Gravity,
            Effect::Jump,
            Effect::Friction,
            Effect::MaxVelocity,
            Effect::AirAccel,
            Effect::GroundAccel,
            Effect::Walls,
        ],
    };
    assert_eq!(s.effects.list(), want, "{name}");
    let preset = if d.kind == SceneKind::Hl2 {
        Preset::SourceHl2
    } else {
        Preset::GoldSrc
    };
    assert_eq!(s.preset, preset, "{name}");
    assert!(
        (s.start.vel.x - f64::from(d.start_speed_ups)).abs() < 1e-9,
        "{name}"
    );
    assert_eq!(s.start.vel.y, 0.0, "{name}");
    assert!(s.walls.iter().all(|w| w.kind == d.walls), "{name}");
    // The finish spans the last leg's width; legs and turns alternate as drawn.
    let finish = (s.finish.b - s.finish.a).length();
    assert!(
        (finish - f64::from(d.width_units)).abs() < 2e-3,
        "{name}: finish {finish}"
    );
    assert_eq!(g.centreline.len(), 2 * d.turns.len() + 1, "{name}");
    for (k, piece) in g.centreline.iter().enumerate() {
        match (k % 2, *piece) {
            (0, CentrelinePiece::Leg { from, to }) => {
                let leg = f64::from(d.legs_units[k / 2]);
                assert!(((to - from).length() - leg).abs() < 1e-6, "{name}: leg {k}");
            }
            (1, CentrelinePiece::Turn { sweep_rad, .. }) => {
                let t = d.turns[k / 2];
                let sign = if t.side == Side::Left { 1.0 } else { -1.0 };
                let want = sign * f64::from(t.degrees).to_radians();
                assert!((sweep_rad - want).abs() < 1e-12, "{name}: turn {k}");
            }
            _ => panic!("{name}: piece {k} is {piece:?}"),
        }
    }
}

#[test]
fn five_hundred_scenes_of_the_family_are_valid_and_never_overlap_themselves() {
    let settings = GeneratorSettings::default();
    for g in family_sample() {
        assert_valid(g, f64::from(settings.wall_gap_units));
        assert_matches_drawn(g);
        assert_eq!(g.drawn.kind, SceneKind::Air, "{}", g.name);
    }
}

#[test]
fn the_draws_stay_in_their_ranges_and_cover_them() {
    let drawn: Vec<_> = family_sample().iter().map(|g| &g.drawn).collect();
    let corners: BTreeSet<usize> = drawn.iter().map(|d| d.turns.len()).collect();
    assert_eq!(
        corners,
        (1..=6).collect(),
        "every count of turns from 1 to 6"
    );
    let turns: Vec<u32> = drawn
        .iter()
        .flat_map(|d| d.turns.iter().map(|t| t.degrees))
        .collect();
    assert!(turns.iter().all(|t| (30..=180).contains(t)));
    assert!(turns.iter().any(|&t| t <= 35) && turns.iter().any(|&t| t >= 175));
    let sides: BTreeSet<&str> = drawn
        .iter()
        .flat_map(|d| d.turns.iter().map(|t| t.side.name()))
        .collect();
    assert_eq!(sides.len(), 2);
    let widths: Vec<u32> = drawn.iter().map(|d| d.width_units).collect();
    assert!(widths.iter().all(|w| (64..=256).contains(w)));
    assert!(widths.iter().any(|&w| w < 75) && widths.iter().any(|&w| w > 245));
    let legs: Vec<u32> = drawn.iter().flat_map(|d| d.legs_units.clone()).collect();
    assert!(legs.iter().all(|l| (200..=1500).contains(l)));
    assert!(legs.iter().any(|&l| l < 230) && legs.iter().any(|&l| l > 1470));
    let fps: BTreeSet<u32> = drawn.iter().map(|d| d.fps).collect();
    assert_eq!(fps, [100, 250, 1000].into());
    let aa: BTreeSet<u32> = drawn.iter().map(|d| d.airaccelerate).collect();
    assert_eq!(aa, [10, 100].into());
    let speeds: Vec<u32> = drawn.iter().map(|d| d.start_speed_ups).collect();
    assert!(speeds.iter().all(|v| *v <= 1500));
    assert!(speeds.iter().any(|&v| v < 40) && speeds.iter().any(|&v| v > 1460));
    let kinds: Vec<BoundaryKind> = drawn.iter().map(|d| d.walls).collect();
    assert!(kinds.contains(&BoundaryKind::Rule) && kinds.contains(&BoundaryKind::Solid));
    // Some corridors needed more than one draw: the overlap test is not idle.
    assert!(drawn.iter().any(|d| d.corridor_draws > 1));
}

#[test]
fn the_ci_sized_family_is_valid_and_small() {
    let s = GeneratorSettings::ci_sized();
    for g in sample(&s, 100) {
        assert_valid(&g, f64::from(s.wall_gap_units));
        let d = &g.drawn;
        assert!((1..=2).contains(&d.turns.len()), "{}", g.name);
        assert!(d.legs_units.iter().all(|l| (200..=800).contains(l)));
        assert!([100, 250].contains(&d.fps));
    }
}

#[test]
fn a_scene_depends_only_on_its_seed_and_index() {
    let s = GeneratorSettings::default();
    let five = generate_sample(7, 5, &s).unwrap_or_else(|e| panic!("{e}"));
    let twelve = generate_sample(7, 12, &s).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(five[..], twelve[..5]);
    let third = generate(7, 3, &s).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(third, five[3]);
    assert_ne!(five[3].toml, five[4].toml);
    let other_seed = generate(8, 3, &s).unwrap_or_else(|e| panic!("{e}"));
    assert_ne!(other_seed.drawn, third.drawn);
    // The comment records the seed, the index and the draws.
    assert!(third
        .toml
        .starts_with("# Generated by strafeopt: scene 3 of seed 7"));
    assert!(third
        .toml
        .contains(&format!("width {} units", third.drawn.width_units)));
}

/// Pinned: scene 0 of seed 1 as the generator first produced it. The draws change only if the stream or
/// the order of the draws changes, which would change every published sample; the finish line's text
/// also pins the layout and the formatting of coordinates.
#[test]
fn the_stream_is_pinned() {
    let g = generate(1, 0, &GeneratorSettings::default()).unwrap_or_else(|e| panic!("{e}"));
    let d = &g.drawn;
    let turns: Vec<(u32, &str)> = d.turns.iter().map(|t| (t.degrees, t.side.name())).collect();
    assert_eq!(turns, [(114, "left"), (176, "right")], "{}", g.toml);
    assert_eq!(d.legs_units, [1000, 1289, 285]);
    let got = (
        d.width_units,
        d.fps,
        d.airaccelerate,
        d.start_speed_ups,
        d.walls,
    );
    assert_eq!(got, (144, 250, 10, 1115, BoundaryKind::Rule));
    assert!(
        g.toml
            .contains("a = [889.891, 1142.358]\nb = [762.747, 1074.754]"),
        "{}",
        g.toml
    );
}

/// The family with every kind.
fn all_kinds() -> GeneratorSettings {
    GeneratorSettings {
        kinds: SceneKind::ALL.to_vec(),
        ..GeneratorSettings::default()
    }
}

#[test]
fn ground_bhop_and_hl2_scenes_are_valid_and_cover_their_start_speeds() {
    let settings = all_kinds();
    let scenes = sample(&settings, 400);
    for g in &scenes {
        assert_valid(g, f64::from(settings.wall_gap_units));
        assert_matches_drawn(g);
    }
    let count = |k: SceneKind| scenes.iter().filter(|g| g.drawn.kind == k).count();
    // Each kind about a quarter of 400 (a binomial's 5 sigma is 43).
    for k in SceneKind::ALL {
        assert!((57..=143).contains(&count(k)), "{k:?}: {}", count(k));
    }
    let ground: Vec<u32> = scenes
        .iter()
        .filter(|g| g.drawn.kind.on_ground())
        .map(|g| g.drawn.start_speed_ups)
        .collect();
    assert!(ground.iter().all(|&v| v <= 320), "{ground:?}");
    // A quarter at rest (and a few more by the uniform draw), the rest up to 320 ups.
    let at_rest = ground.iter().filter(|&&v| v == 0).count();
    assert!(
        (ground.len() / 8..=ground.len() / 2).contains(&at_rest),
        "{at_rest} of {} at rest",
        ground.len()
    );
    assert!(ground.iter().any(|&v| v > 0 && v < 30));
    assert!(ground.iter().any(|&v| v > 300));
    // The other draws still cover the family: every frame rate and wall kind among the bunnyhops.
    let bhop_fps: BTreeSet<u32> = scenes
        .iter()
        .filter(|g| g.drawn.kind == SceneKind::Bhop)
        .map(|g| g.drawn.fps)
        .collect();
    assert_eq!(bhop_fps, [100, 250, 1000].into());
    // The text says what the scene is.
    for g in &scenes {
        let words = match g.drawn.kind {
            SceneKind::Air => "airborne at",
            SceneKind::Ground => "groundstrafing from",
            SceneKind::Bhop => "bunnyhopping from the ground at",
            SceneKind::Hl2 => "Half-Life 2, ",
        };
        assert!(g.scene.description.contains(words), "{}", g.toml);
        assert_eq!(
            g.toml.contains("# Kind: "),
            g.drawn.kind != SceneKind::Air,
            "{}",
            g.toml
        );
    }
}

#[test]
fn kinds_keep_each_scene_s_corridor_and_the_airborne_scenes() {
    let air = sample(&GeneratorSettings::default(), 60);
    let mixed = sample(&all_kinds(), 60);
    let only_bhop = sample(
        &GeneratorSettings {
            kinds: vec![SceneKind::Bhop],
            ..GeneratorSettings::default()
        },
        60,
    );
    for ((a, m), b) in air.iter().zip(&mixed).zip(&only_bhop) {
        // Same corridor, frame rate, air acceleration and walls whatever the kinds.
        for g in [m, b] {
            assert_eq!(g.centreline, a.centreline, "{}", g.name);
            assert_eq!(g.scene.walls, a.scene.walls, "{}", g.name);
            assert_eq!(g.scene.finish, a.scene.finish, "{}", g.name);
            let (x, y) = (&g.drawn, &a.drawn);
            assert_eq!(
                (
                    x.width_units,
                    &x.legs_units,
                    &x.turns,
                    x.fps,
                    x.airaccelerate,
                    x.walls
                ),
                (
                    y.width_units,
                    &y.legs_units,
                    &y.turns,
                    y.fps,
                    y.airaccelerate,
                    y.walls
                ),
                "{}",
                g.name
            );
        }
        assert_eq!(b.drawn.kind, SceneKind::Bhop);
        // An airborne scene of the mixed family is the airborne family's, but for the family's line.
        if m.drawn.kind == SceneKind::Air {
            assert_eq!(m.drawn, a.drawn);
            assert_eq!(m.scene, a.scene);
        }
    }
    // Scene k is the same drawn alone or in a sample, for every kind.
    let s = all_kinds();
    let five = generate_sample(9, 5, &s).unwrap_or_else(|e| panic!("{e}"));
    let alone = generate(9, 4, &s).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(alone, five[4]);
}

#[test]
fn vectorial_compensation_keeps_each_scene_and_asks_for_it() {
    // The family with vectorial compensation: the same drawn scenes, each asking for it in `[engine]`
    // and nothing else changed.
    let plain = sample(&GeneratorSettings::ci_sized(), 20);
    let vectorial = sample(
        &GeneratorSettings {
            vectorial_compensation: true,
            ..GeneratorSettings::ci_sized()
        },
        20,
    );
    for (p, v) in plain.iter().zip(&vectorial) {
        assert_eq!(v.drawn, p.drawn, "{}", v.name);
        assert!(
            v.toml.contains("\nvectorial-compensation = true\n"),
            "{}",
            v.name
        );
        assert!(v.scene.vars.vectorial_compensation && !p.scene.vars.vectorial_compensation);
        let mut as_plain = v.scene.clone();
        as_plain.vars.vectorial_compensation = false;
        assert_eq!(as_plain.vars, p.scene.vars, "{}", v.name);
        assert_eq!(as_plain.walls, p.scene.walls, "{}", v.name);
        assert_eq!(as_plain.finish, p.scene.finish, "{}", v.name);
    }
}

#[test]
fn impossible_settings_are_an_error_not_a_hang() {
    // Twelve 180-degree turns with 64-unit legs: only strictly alternating sides (2 draws in 4096) make a
    // corridor that does not fold onto itself; three draws find none.
    let s = GeneratorSettings {
        min_corners: 12,
        max_corners: 12,
        min_turn_deg: 180,
        min_leg_units: 64,
        max_leg_units: 64,
        max_corridor_draws: 3,
        ..GeneratorSettings::default()
    };
    let e = generate(1, 0, &s)
        .err()
        .map(|e| e.to_string())
        .unwrap_or_default();
    assert!(e.contains("overlap itself"), "{e}");
}

fn temp_dir(tag: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("strafeopt-gen-{tag}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    dir
}

fn run(args: &[&str]) -> std::process::Output {
    strafeopt_in(Path::new(env!("CARGO_MANIFEST_DIR")), args)
}

#[test]
fn gen_writes_the_files_the_scene_loader_reads() {
    let dir = temp_dir("ok");
    let out_dir = dir.join("new").display().to_string();
    let out = run(&["gen", "--seed", "42", "--count", "3", "-o", &out_dir]);
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert_eq!(stdout.lines().count(), 3, "{stdout}");
    for k in 0..3u64 {
        let path = dir.join("new").join(format!("gen-42-{k}.toml"));
        let scene = Scene::load(&path).unwrap_or_else(|e| panic!("{e}"));
        let g = generate(42, k, &GeneratorSettings::default()).unwrap_or_else(|e| panic!("{e}"));
        let text = std::fs::read_to_string(&path).unwrap_or_default();
        assert_eq!(text, g.toml);
        assert_eq!(scene.walls, g.scene.walls);
        let line = stdout.lines().nth(k as usize).unwrap_or("");
        assert!(line.starts_with(&path.display().to_string()), "{line}");
        let want = format!(
            "corners {}  width {:>4}  fps {:>4}",
            g.drawn.turns.len(),
            g.drawn.width_units,
            g.drawn.fps
        );
        assert!(line.contains(&want), "{line} lacks {want}");
        assert!(
            line.contains(&format!("{} walls", g.drawn.walls.name())),
            "{line}"
        );
    }
    // A narrowed family: CI-sized, 1000 fps only, solid walls.
    let out = run(&[
        "gen",
        "--seed",
        "5",
        "--count",
        "4",
        "-o",
        &out_dir,
        "--ci-sized",
        "--fps",
        "1000",
        "--walls",
        "solid",
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    for k in 0..4 {
        let scene = Scene::load(&dir.join("new").join(format!("gen-5-{k}.toml")))
            .unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(scene.vars.fps, 1000.0);
        assert!(scene.walls.iter().all(|w| w.kind == BoundaryKind::Solid));
    }
    // Ground and bunnyhop scenes: the files load, start on the ground, and the line names the kind.
    let out = run(&[
        "gen",
        "--seed",
        "6",
        "--count",
        "6",
        "-o",
        &out_dir,
        "--ci-sized",
        "--kinds",
        "ground,bhop",
    ]);
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let settings = GeneratorSettings {
        kinds: vec![SceneKind::Ground, SceneKind::Bhop],
        ..GeneratorSettings::ci_sized()
    };
    for k in 0..6u64 {
        let path = dir.join("new").join(format!("gen-6-{k}.toml"));
        let scene = Scene::load(&path).unwrap_or_else(|e| panic!("{e}"));
        let g = generate(6, k, &settings).unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(std::fs::read_to_string(&path).unwrap_or_default(), g.toml);
        assert!(scene.start.on_ground);
        assert_eq!(
            scene.effects.has(Effect::Jump),
            g.drawn.kind == SceneKind::Bhop
        );
        let line = stdout.lines().nth(k as usize).unwrap_or("");
        assert!(
            line.ends_with(&format!("walls  {}", g.drawn.kind.name())),
            "{line}"
        );
    }
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn gen_refuses_bad_input_with_exit_2_in_one_line() {
    let dir = temp_dir("bad");
    let _ = std::fs::create_dir_all(&dir);
    let file = dir.join("a-file");
    let _ = std::fs::write(&file, "x");
    let under_file = file.join("sub").display().to_string();
    let ok_dir = dir.join("out").display().to_string();
    let cases: [(&[&str], &str); 8] = [
        (
            &["gen", "--seed", "1", "--count", "0", "-o", &ok_dir],
            "--count",
        ),
        (
            &["gen", "--seed", "1", "--count", "10001", "-o", &ok_dir],
            "--count",
        ),
        (
            &["gen", "--seed", "1", "--count", "-3", "-o", &ok_dir],
            "--count",
        ),
        (&["gen", "--seed", "1", "-o", &under_file], "--output"),
        (
            &["gen", "--seed", "1", "-o", &ok_dir, "--max-corners", "0"],
            "--max-corners",
        ),
        (
            &["gen", "--seed", "1", "-o", &ok_dir, "--fps", "100,0"],
            "--fps",
        ),
        (&["gen", "--count", "2", "-o", &ok_dir], "--seed"),
        (
            &["gen", "--seed", "1", "-o", &ok_dir, "--kinds", "air,walk"],
            "--kinds",
        ),
    ];
    for (args, names) in cases {
        let out = run(args);
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{args:?}: {err}");
        assert_eq!(err.lines().count(), 1, "{args:?}: {err}");
        assert!(
            err.starts_with("strafeopt: ") && err.contains(names),
            "{args:?}: {err}"
        );
    }
    // Nothing was written for the refused runs.
    let written = std::fs::read_dir(&ok_dir).map(|d| d.count()).unwrap_or(0);
    assert_eq!(written, 0);
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn bench_generated_gives_a_record_per_scene_and_the_distributions() {
    let out = run(&[
        "bench",
        "--generated",
        "2",
        "--seed",
        "3",
        "--ci-sized",
        "--max-corners",
        "1",
        "--max-leg",
        "400",
        "--fps",
        "100",
        "--json",
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let v: serde_json::Value =
        serde_json::from_slice(&out.stdout).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(v["seed"], 3);
    assert_eq!(v["quality"], "fast");
    let scenes = v["scenes"].as_array().cloned().unwrap_or_default();
    let names: Vec<&str> = scenes.iter().filter_map(|r| r["scene"].as_str()).collect();
    assert_eq!(names, ["gen-3-0", "gen-3-1"]);
    for r in &scenes {
        assert_eq!(r["valid"], true, "{r}");
        let frames = r["frames"].as_i64().unwrap_or(-1);
        let bound = r["bound_frames"].as_i64().unwrap_or(i64::MAX);
        assert!(frames >= bound, "{r}");
        assert!(r["gap_pct"].as_f64().is_some_and(|g| g >= 0.0), "{r}");
        if r["greedy_valid"] == true {
            let greedy = r["greedy_frames"].as_i64().unwrap_or(-1);
            assert_eq!(r["frames_gained"].as_i64(), Some(greedy - frames), "{r}");
        }
    }
    let columns: Vec<&str> = v["distributions"]
        .as_array()
        .map(|d| d.iter().filter_map(|c| c["column"].as_str()).collect())
        .unwrap_or_default();
    for c in [
        "frames gained on greedy",
        "gap to bound (%)",
        "solve time per frame (ms)",
        "share in the relaxed line (%)",
    ] {
        assert!(columns.contains(&c), "{columns:?}");
    }
    // Where each solve's time went: the relaxed line ran on both, within the solve.
    for r in &scenes {
        let relaxed_line = r["stage_seconds"]["relaxed_line"].as_f64().unwrap_or(0.0);
        let solve_s = r["solve_seconds"].as_f64().unwrap_or(0.0);
        assert!(relaxed_line > 0.0 && relaxed_line < solve_s, "{r}");
    }
    // Where each plan crosses against its relaxed optimum's frame, counted, and how much of that frame
    // the relaxed optimum leaves, per record (a fraction of a frame).
    for r in &scenes {
        let left = r["relaxed_frame_left"].as_f64().unwrap_or(f64::NAN);
        assert!((0.0..1.0).contains(&left), "{r}");
        // Its replays: an optimised plan (both scenes' are) is one of the valid ones.
        let (replays, valid) = (r["replays"].as_u64(), r["valid_replays"].as_u64());
        assert!(
            r["status"]
                .as_str()
                .is_some_and(|s| s.ends_with("(optimised)")),
            "{r}"
        );
        assert!(
            matches!((replays, valid), (Some(n), Some(ok)) if ok >= 1 && ok <= n),
            "{r}"
        );
    }
    let (in_frame, behind, ahead, past) = (
        v["in_relaxed_frame"].as_u64().unwrap_or(99),
        v["behind_relaxed_frame"].as_u64().unwrap_or(99),
        v["ahead_of_relaxed_frame"].as_u64().unwrap_or(99),
        v["behind_where_estimates_pass_the_frame"]
            .as_u64()
            .unwrap_or(99),
    );
    // Both plans have a certificate: each is in its frame, behind it or ahead of it.
    assert!(in_frame + behind + ahead == 2 && past <= behind, "{v}");
    let gap = &v["distributions"][1];
    assert_eq!(gap["count"], 2);
    assert!(gap["min"].as_f64() <= gap["median"].as_f64());
    assert!(gap["median"].as_f64() <= gap["max"].as_f64());
    // Each record names its kind; --kinds passes through to the family.
    assert!(scenes.iter().all(|r| r["kind"] == "air"), "{scenes:?}");
    let out = run(&[
        "bench",
        "--generated",
        "2",
        "--seed",
        "3",
        "--ci-sized",
        "--max-corners",
        "1",
        "--max-leg",
        "400",
        "--fps",
        "100",
        "--kinds",
        "bhop",
        "--json",
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let v: serde_json::Value =
        serde_json::from_slice(&out.stdout).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(v["family"]["kinds"], serde_json::json!(["bhop"]));
    for r in v["scenes"].as_array().cloned().unwrap_or_default() {
        assert_eq!(r["kind"], "bhop", "{r}");
        assert_eq!(r["valid"], true, "{r}");
        assert_eq!(r["engine_exact_valid"], true, "{r}");
    }
    // Family flags belong to --generated.
    let out = run(&["bench", "scenarios/hl-bend90-100fps.toml", "--fps", "100"]);
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("--fps"));
    let out = run(&["bench", "--generated", "0"]);
    assert_eq!(out.status.code(), Some(2));
    // The scene-file levels are not the generated bench's.
    let out = run(&["bench", "--generated", "1", "--levels", "exact"]);
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("--levels"));
}
