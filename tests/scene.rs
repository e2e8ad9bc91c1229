//! Scene files: every shipped scene loads with the values its comments promise, and every kind of bad
//! input gives one `Error::Scene` naming the file, the line and the key.

use std::path::Path;
use strafeopt::geometry::{BoundaryKind, FinishPoint, HULL_HALF_WIDTH_UNITS};
use strafeopt::physics::{Effect, Effects, Game, Vec2};
use strafeopt::scene::{Scene, DEFAULT_MAX_TIME_S, START_OFFSET_UNITS};
use strafeopt::Error;

fn load(name: &str) -> Scene {
    let path = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("scenarios")
        .join(name);
    match Scene::load(&path) {
        Ok(s) => s,
        Err(e) => panic!("{name}: {e}"),
    }
}

fn v(x: f64, y: f64) -> Vec2 {
    Vec2::new(x, y)
}

const AIR_ONLY: [Effect; 3] = [Effect::AirAccel, Effect::MaxVelocity, Effect::Walls];

#[test]
fn shipped_bend90_scenes() {
    for (file, fps, aa, d, leg) in [
        ("hl-bend90-100fps.toml", 100.0, 10.0, 160.0, 1200.0),
        ("hl-bend90-narrow-100fps.toml", 100.0, 10.0, 96.0, 1500.0),
        ("hl-bend90-1000fps-aa100.toml", 1000.0, 100.0, 128.0, 2000.0),
    ] {
        let s = load(file);
        assert_eq!(s.name, file.trim_end_matches(".toml"));
        assert_eq!(s.vars.game, Game::GoldSrc);
        assert_eq!(
            (s.vars.fps, s.vars.airaccelerate, s.vars.maxspeed),
            (fps, aa, 320.0)
        );
        assert_eq!(s.effects, Effects::from_list(&AIR_ONLY));
        assert_eq!(s.start.pos, v(START_OFFSET_UNITS, d / 2.0));
        assert_eq!(s.start.vel, v(320.0, 0.0));
        assert!(!s.start.on_ground && !s.start.ducked);
        assert_eq!((s.finish.a, s.finish.b), (v(leg - d, leg), v(leg, leg)));
        assert_eq!(s.finish.point, FinishPoint::Centre);
        assert_eq!(s.walls.len(), 1);
        assert_eq!(s.walls[0].kind, BoundaryKind::Rule);
        assert_eq!(
            s.walls[0].points,
            vec![
                v(leg - d, leg),
                v(leg - d, d),
                v(0.0, d),
                v(0.0, 0.0),
                v(leg, 0.0),
                v(leg, leg)
            ]
        );
        assert_eq!(s.max_frames, (DEFAULT_MAX_TIME_S * fps).round() as u64);
        assert!(s.corridor().is_ok());
    }
}

#[test]
fn shipped_hairpin_scene() {
    let s = load("hl-hairpin-100fps.toml");
    assert_eq!(s.effects, Effects::from_list(&AIR_ONLY));
    assert_eq!(s.start.pos, v(40.0, 64.0));
    assert_eq!((s.finish.a, s.finish.b), (v(0.0, 192.0), v(0.0, 320.0)));
    assert_eq!(s.walls.len(), 2);
    assert!(s.walls[1].closed);
    // The way round is longer than out and back along the legs' centres less the corners.
    let corridor = s.corridor().unwrap();
    let (len, _) = corridor
        .shortest_path(s.start.pos, (s.finish.a, s.finish.b))
        .unwrap();
    assert!(len > 2.0 * (1200.0 - 128.0 - 40.0) && len < 2.0 * 1200.0 + 320.0);
}

#[test]
fn shipped_ground_and_jump_scenes() {
    let g = load("hl-groundstrafe-1000fps.toml");
    assert_eq!(g.vars.fps, 1000.0);
    assert_eq!(
        g.effects,
        Effects::from_list(&[
            Effect::GroundAccel,
            Effect::Friction,
            Effect::MaxVelocity,
            Effect::Walls
        ])
    );
    assert!(g.start.on_ground);
    assert_eq!(g.start.vel, v(320.0, 0.0));
    assert_eq!(
        (g.finish.a, g.finish.b),
        (v(20000.0, 0.0), v(20000.0, 256.0))
    );

    let b = load("hl-bhop-cap-100fps.toml");
    assert!(b.effects.has(Effect::BhopCap) && b.effects.has(Effect::Gravity));
    assert!(b.start.on_ground);
    assert_eq!(b.effects.missing_requirement(), None);
}

#[test]
fn shipped_sbend_scene_from_explicit_walls() {
    let s = load("hl-sbend-100fps.toml");
    assert_eq!(s.walls.len(), 3);
    assert!(s.walls.iter().all(|w| w.kind == BoundaryKind::Rule));
    assert_eq!(s.start.pos, v(40.0, 80.0));
    assert_eq!(s.start.vel, v(320.0, 0.0));
    assert_eq!(
        (s.finish.a, s.finish.b),
        (v(2400.0, 1040.0), v(2400.0, 1200.0))
    );
    assert!(AIR_ONLY.iter().all(|&e| s.effects.has(e)));
    // The start is mid-lane, 80 units from both lane lines and 40 from the start wall, the nearest.
    let clearance = s
        .corridor()
        .unwrap_or_else(|e| panic!("{e}"))
        .clearance(s.start.pos);
    assert!(
        (clearance - (40.0 - HULL_HALF_WIDTH_UNITS)).abs() < 1e-9,
        "{clearance}"
    );
}

#[test]
fn shipped_hl2_abh_scene() {
    let s = load("hl2-abh-100m.toml");
    assert_eq!(s.vars.game, Game::Source);
    assert_eq!(s.vars.maxspeed, 150.0);
    assert!((s.vars.frame_time_s() - 0.015).abs() < 1e-15);
    assert!(s.start.ducked && s.start.on_ground);
    assert_eq!(s.start.vel, Vec2::ZERO);
    assert!(s.effects.has(Effect::JumpBoost) && s.effects.has(Effect::Duck));
    // 100 m from the start position to the line, in a 1.22 m lane.
    assert!((s.finish.a.x - s.start.pos.x - 5249.34).abs() < 1e-9);
    assert!((s.finish.b.y - s.finish.a.y - 64.04).abs() < 1e-12);
    // The hull fits with 16.02 units to spare on each side.
    let clearance = s.corridor().unwrap().clearance(s.start.pos);
    assert!((clearance - (32.02 - HULL_HALF_WIDTH_UNITS)).abs() < 1e-9);
}

/// `(file, line, key, words the message must contain)`.
const INVALID: [(&str, usize, &str, &str); 8] = [
    (
        "unknown-key.toml",
        9,
        "start.speed",
        "unknown field `speed`",
    ),
    ("wrong-type.toml", 4, "engine.fps", "expected a number"),
    (
        "self-intersecting-wall.toml",
        21,
        "walls[1].points",
        "segments 0 and 2 intersect",
    ),
    (
        "zero-length-segment.toml",
        25,
        "walls[2].points",
        "segment 3 has zero length; each segment must be longer than 1e-9 units",
    ),
    (
        "start-inside-wall.toml",
        8,
        "start.position",
        "overlaps lane",
    ),
    (
        "unreachable-finish.toml",
        11,
        "finish",
        "no path for the hull",
    ),
    (
        "bad-engine-value.toml",
        5,
        "engine.fps",
        "got -1; must be a finite number above 0",
    ),
    (
        "missing-effect-requirement.toml",
        5,
        "engine.effects",
        "\"jump\" needs \"gravity\"",
    ),
];

#[test]
fn invalid_scene_files_name_file_line_and_key() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenarios/invalid");
    let mut shipped: Vec<String> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    shipped.sort();
    let mut listed: Vec<String> = INVALID.iter().map(|c| c.0.to_string()).collect();
    listed.sort();
    assert_eq!(shipped, listed, "every invalid file has a case here");

    for (file, line, key, words) in INVALID {
        let path = dir.join(file);
        let err = Scene::load(&path).expect_err(file);
        let Error::Scene {
            location,
            key: got_key,
            message,
        } = &err
        else {
            panic!("{file}: not a scene error: {err:?}");
        };
        assert_eq!(
            location,
            &format!("{}:{line}", path.display()),
            "{file}: {err}"
        );
        assert_eq!(got_key, key, "{file}: {err}");
        assert!(message.contains(words), "{file}: {err}");
        let shown = err.to_string();
        assert!(!shown.contains('\n'), "{file}: not one line: {shown}");
        assert!(shown.starts_with(&format!("{}:{line}: {key}: ", path.display())));
    }
}

/// The error for inline scene text, as `(line, key, message)`.
fn inline_error(text: &str) -> (String, String, String) {
    match Scene::from_toml_str(text, "inline.toml") {
        Ok(s) => panic!("accepted: {s:?}"),
        Err(Error::Scene {
            location,
            key,
            message,
        }) => (location, key, message),
        Err(e) => panic!("not a scene error: {e:?}"),
    }
}

const LANE_HEAD: &str = "[engine]
preset = \"goldsrc\"
fps = 100
effects = [\"air-accel\", \"max-velocity\", \"walls\"]
";

const LANE: &str = "[lane]
width = 256
length = 2000
kind = \"rule\"
";

#[test]
fn more_bad_inputs_are_located() {
    let cases: Vec<(String, &str, &str, &str)> = vec![
        // TOML syntax error.
        (
            format!("{LANE_HEAD}name = \"x\n{LANE}"),
            "inline.toml:5",
            "-",
            "string",
        ),
        // A point with three numbers.
        (
            format!("{LANE_HEAD}[start]\nposition = [1, 2, 3]\n{LANE}"),
            "inline.toml:6",
            "start.position",
            "invalid length 3",
        ),
        // An unknown key in [engine].
        (
            format!("{LANE_HEAD}turbo = 2\n{LANE}"),
            "inline.toml:5",
            "engine.turbo",
            "unknown field `turbo`",
        ),
        // An unknown effect name.
        (
            format!("[engine]\npreset = \"goldsrc\"\nfps = 100\neffects = [\"air-accel\", \"fly\"]\n{LANE}"),
            "inline.toml:4",
            "engine.effects[1]",
            "unknown variant `fly`",
        ),
        // An unknown preset.
        (
            format!("[engine]\npreset = \"quake\"\nfps = 100\neffects = []\n{LANE}"),
            "inline.toml:2",
            "engine.preset",
            "unknown variant `quake`",
        ),
        // fps missing.
        (
            format!("[engine]\npreset = \"goldsrc\"\neffects = []\n{LANE}"),
            "inline.toml:1",
            "engine.fps",
            "missing",
        ),
        // Two shorthand shapes.
        (
            format!("{LANE_HEAD}{LANE}[bend90]\nwidth = 100\nleg1 = 500\nleg2 = 500\nkind = \"rule\"\n"),
            "inline.toml:9",
            "bend90",
            "at most one shorthand",
        ),
        // A corridor narrower than the hull.
        (
            format!("{LANE_HEAD}[bend90]\nwidth = 20\nleg1 = 500\nleg2 = 500\nkind = \"rule\"\n"),
            "inline.toml:6",
            "bend90.width",
            "got 20; must be at least 32 units",
        ),
        // Solid walls without the walls effect.
        (
            format!("[engine]\npreset = \"goldsrc\"\nfps = 100\neffects = [\"air-accel\"]\n{}", LANE.replace("rule", "solid")),
            "inline.toml:8",
            "lane.kind",
            "\"walls\" effect",
        ),
        // Ducked without the duck effect.
        (
            format!("{LANE_HEAD}[start]\nducked = true\n{LANE}"),
            "inline.toml:6",
            "start.ducked",
            "\"duck\" effect",
        ),
        // Half a finish line.
        (
            format!("{LANE_HEAD}[finish]\na = [0, 0]\n{LANE}"),
            "inline.toml:5",
            "finish.b",
            "give both ends",
        ),
        // No finish at all.
        (
            format!("{LANE_HEAD}[start]\nposition = [40, 40]\n"),
            "inline.toml",
            "finish",
            "missing",
        ),
        // A start position that is not finite.
        (
            format!("{LANE_HEAD}[start]\nposition = [nan, 40]\n{LANE}"),
            "inline.toml:6",
            "start.position",
            "finite",
        ),
        // max-frames 0.
        (
            format!("max-frames = 0\n{LANE_HEAD}{LANE}"),
            "inline.toml:1",
            "max-frames",
            "at least 1",
        ),
        // A negative frame cap is a type error.
        (
            format!("max-frames = -5\n{LANE_HEAD}{LANE}"),
            "inline.toml:1",
            "max-frames",
            "whole number",
        ),
        // A wall with one point, its points on several lines.
        (
            format!("{LANE_HEAD}{LANE}[[walls]]\nkind = \"rule\"\npoints = [\n  [5, 5],\n]\n"),
            "inline.toml:11",
            "walls[0].points",
            "at least 2",
        ),
        // A finish line wholly inside a wall.
        (
            format!("{LANE_HEAD}[start]\nposition = [40, 40]\n[finish]\na = [100, -10]\nb = [100, 10]\n[[walls]]\nkind = \"rule\"\npoints = [[0, 0], [200, 0]]\n"),
            "inline.toml:7",
            "finish",
            "no path",
        ),
    ];
    for (text, location, key, words) in cases {
        let (got_location, got_key, message) = inline_error(&text);
        assert_eq!(
            (got_location.as_str(), got_key.as_str()),
            (location, key),
            "{message}\n---\n{text}"
        );
        assert!(message.contains(words), "{message}\n---\n{text}");
    }
}

#[test]
fn defaults_and_explicit_values() {
    // No name: the file stem. No shorthand: explicit start, finish and walls.
    let text = "[engine]
preset = \"source-hl2\"
fps = 66.666666666666667
maxspeed = 150
effects = [\"air-accel\"]
[start]
position = [0, 0]
[finish]
a = [500, -100]
b = [500, 100]
point = \"hull\"
";
    let s = Scene::from_toml_str(text, "dir/open-field.toml").unwrap();
    assert_eq!(s.name, "open-field");
    assert_eq!(s.origin, "dir/open-field.toml");
    assert_eq!(s.description, "");
    assert!(s.walls.is_empty());
    assert_eq!(s.start.vel, Vec2::ZERO);
    assert_eq!(s.finish.point, FinishPoint::Hull);
    assert_eq!(s.max_frames, 4000);
    assert_eq!(s.vars.maxspeed, 150.0);
    // A missing file names its path.
    let err = Scene::load(Path::new("scenarios/no-such-scene.toml")).unwrap_err();
    assert!(err
        .to_string()
        .starts_with("scenarios/no-such-scene.toml: -: cannot read the file"));
}

#[test]
fn explicit_walls_follow_the_shorthand_and_may_touch_the_start() {
    let text = format!(
        "{LANE_HEAD}[start]\nposition = [40, 16]\n{LANE}[[walls]]\nkind = \"solid\"\npoints = [[500, 100], [600, 150], [700, 100]]\n"
    );
    let s = Scene::from_toml_str(&text, "x.toml").unwrap();
    assert_eq!(s.walls.len(), 2);
    assert_eq!(s.walls[1].kind, BoundaryKind::Solid);
    // Touching the lane wall (clearance 0) is allowed.
    assert_eq!(s.corridor().unwrap().clearance(s.start.pos), 0.0);
}
