//! Hard geometry (issue 9): degenerate corridors, walls, starts and finish lines give a correct, finite
//! answer, checked against an independent calculation written here (hand geometry, or brute force over a
//! separating-axis box-segment test), or a clear one-line error. Both the library and `strafeopt simulate`
//! (the real binary) are exercised.
//!
//! **Decision: a corridor exactly one hull wide (32 units) is accepted.** The hull may touch a wall but
//! not overlap it (clearance 0 is contact, docs/physics.md section 10), so the hull centre has exactly one line to
//! travel on: the shortest path exists, runs along that line with clearance 0 to both walls, and the lower
//! bound is finite. With solid walls every move is clipped back onto the line; with rule walls only runs
//! whose velocity stays exactly along the line are valid (the greedy strafer breaks a rule in frame 1,
//! holding forward along the line is valid). Narrower is rejected with a clear message: a shorthand width
//! below 32 names the width; with explicit walls, a gap narrower than 32 by more than the contact tolerance
//! ([`CONTACT_TOL_UNITS`] on each side, the same test the simulation uses) is "no path" when it lies ahead,
//! and an overlap of the start when the start is in it.
//!
//! Found here and fixed (issue 9): the path search shrank the grown walls by 1e-7 units, 100 times the
//! contact tolerance, so the validator's "a path exists" let gaps up to 2e-7 units too narrow through; and
//! a NaN or infinite move was reported as crossing the finish line.

use assert_cmd::Command;
use serde_json::Value;
use std::path::PathBuf;
use std::process::Output;
use strafeopt::geometry::{
    BoundaryKind, Cast, Corridor, FinishLine, FinishPoint, SweepStatus, Wall, CONTACT_TOL_UNITS,
    HULL_HALF_WIDTH_UNITS,
};
use strafeopt::optimise::lower_bound;
use strafeopt::physics::{Control, Vec2};
use strafeopt::scene::Scene;
use strafeopt::sim::{Greedy, Playback, Simulation, Trace};
use strafeopt::Error;

const H: f64 = HULL_HALF_WIDTH_UNITS;
const TOL: f64 = CONTACT_TOL_UNITS;

fn v(x: f64, y: f64) -> Vec2 {
    Vec2::new(x, y)
}

fn wall(kind: BoundaryKind, closed: bool, pts: &[(f64, f64)]) -> Wall {
    Wall {
        points: pts.iter().map(|&(x, y)| v(x, y)).collect(),
        closed,
        kind,
    }
}

// ---------------------------------------------------------------------------------------------------------
// Independent geometry: an axis-aligned box of half-width `h` centred at `c` against the segment `a`-`b`.

/// Distance from the point `p` to the segment `a`-`b`.
fn point_segment(p: Vec2, a: Vec2, b: Vec2) -> f64 {
    let e = b - a;
    let t = ((p - a).dot(e) / e.length_squared()).clamp(0.0, 1.0);
    (a + e * t - p).length()
}

/// Distance from the box to the point `p` (0 inside).
fn box_point(c: Vec2, h: f64, p: Vec2) -> f64 {
    let dx = ((p.x - c.x).abs() - h).max(0.0);
    let dy = ((p.y - c.y).abs() - h).max(0.0);
    dx.hypot(dy)
}

/// Penetration of the segment into the box by the separating axis theorem (axes x, y and the segment's
/// normal): the shortest push along one axis that separates them; negative when some axis separates them.
fn box_segment_overlap(c: Vec2, h: f64, a: Vec2, b: Vec2) -> f64 {
    let e = b - a;
    let n = v(-e.y, e.x) * (1.0 / e.length());
    let axes = [v(1.0, 0.0), v(0.0, 1.0), n];
    axes.iter()
        .map(|&ax| {
            let r = h * (ax.x.abs() + ax.y.abs());
            let (lo, hi) = (c.dot(ax) - r, c.dot(ax) + r);
            let (s0, s1) = (a.dot(ax).min(b.dot(ax)), a.dot(ax).max(b.dot(ax)));
            (hi - s0).min(s1 - lo)
        })
        .fold(f64::INFINITY, f64::min)
}

/// Signed gap between box and segment: the distance when apart, minus the penetration when overlapping.
fn box_segment_gap(c: Vec2, h: f64, a: Vec2, b: Vec2) -> f64 {
    let overlap = box_segment_overlap(c, h, a, b);
    if overlap > 0.0 {
        return -overlap;
    }
    let corners = [v(h, h), v(h, -h), v(-h, h), v(-h, -h)];
    let from_corners = corners
        .iter()
        .map(|&k| point_segment(c + k, a, b))
        .fold(f64::INFINITY, f64::min);
    from_corners.min(box_point(c, h, a)).min(box_point(c, h, b))
}

/// Brute force: the first fraction of the move `p0 -> p1` at which the box comes within `TOL` of the
/// segment (scan, then bisect), or `None`.
fn first_touch(p0: Vec2, p1: Vec2, h: f64, a: Vec2, b: Vec2) -> Option<f64> {
    let touches = |t: f64| box_segment_gap(p0 + (p1 - p0) * t, h, a, b) <= TOL;
    const STEPS: usize = 20_000;
    if touches(0.0) {
        return Some(0.0);
    }
    let hit = (1..=STEPS).find(|&i| touches(i as f64 / STEPS as f64))?;
    let (mut lo, mut hi) = ((hit - 1) as f64 / STEPS as f64, hit as f64 / STEPS as f64);
    for _ in 0..60 {
        let mid = 0.5 * (lo + hi);
        if touches(mid) {
            hi = mid;
        } else {
            lo = mid;
        }
    }
    Some(hi)
}

// ---------------------------------------------------------------------------------------------------------
// Scenes and the binary.

/// Air acceleration, 100 fps, solid walls allowed.
const AIR: &str = "[engine]
preset = \"goldsrc\"
fps = 100
effects = [\"air-accel\", \"max-velocity\", \"walls\"]
";

/// No acceleration at all: the start velocity is kept (until a solid wall clips it).
const COAST: &str = "[engine]
preset = \"goldsrc\"
fps = 100
effects = [\"max-velocity\", \"walls\"]
";

fn lane(width: f64, length: f64, kind: &str) -> String {
    format!("[lane]\nwidth = {width}\nlength = {length}\nkind = \"{kind}\"\n")
}

fn scene(text: &str) -> Scene {
    Scene::from_toml_str(text, "hard.toml").unwrap_or_else(|e| panic!("{e}\n---\n{text}"))
}

/// The scene error for `text`: `(location, key, message)`, checked to display as one line.
fn scene_error(text: &str) -> (String, String, String) {
    match Scene::from_toml_str(text, "hard.toml") {
        Ok(s) => panic!("accepted: {s:?}\n---\n{text}"),
        Err(e @ Error::Scene { .. }) => {
            let shown = e.to_string();
            assert!(!shown.contains('\n'), "not one line: {shown}");
            assert!(shown.starts_with("hard.toml"), "{shown}");
            let Error::Scene {
                location,
                key,
                message,
            } = e
            else {
                unreachable!()
            };
            (location, key, message)
        }
        Err(e) => panic!("not a scene error: {e:?}"),
    }
}

fn run(scene: &Scene, controller: &mut dyn strafeopt::sim::Controller) -> Trace {
    let sim = Simulation::new(scene).unwrap_or_else(|e| panic!("{e}"));
    sim.run(controller)
}

fn greedy(scene: &Scene, lookahead: f64) -> Trace {
    let corridor = scene.corridor().unwrap_or_else(|e| panic!("{e}"));
    let bound = lower_bound(scene, &corridor).unwrap_or_else(|e| panic!("{e}"));
    run(scene, &mut Greedy::new(bound.path, lookahead))
}

/// Holds `forwardmove` towards +x every frame.
fn forward_along_x() -> Playback {
    Playback {
        controls: vec![Control {
            yaw_rad: 0.0,
            forwardmove: 400.0,
            sidemove: 0.0,
            jump: false,
            duck: false,
        }],
        label: "forward".to_string(),
    }
}

fn assert_trace_finite(t: &Trace) {
    assert!(!t.numerical_failure);
    for f in std::iter::once(&t.start).chain(&t.frames) {
        assert!(
            f.pos.is_finite() && f.vel.is_finite() && f.speed.is_finite() && !f.clearance.is_nan(),
            "frame {}: {f:?}",
            f.frame
        );
    }
}

fn strafeopt(args: &[&str]) -> Output {
    Command::cargo_bin("strafeopt")
        .map(|mut c| {
            c.current_dir(env!("CARGO_MANIFEST_DIR"))
                .args(args)
                .output()
        })
        .unwrap_or_else(|e| panic!("binary: {e}"))
        .unwrap_or_else(|e| panic!("run {args:?}: {e}"))
}

fn temp_dir(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("strafeopt-hard-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap_or_else(|e| panic!("{e}"));
    dir
}

/// Writes `text` to `dir/name` and runs `simulate` on it with `extra` flags.
fn simulate_file(dir: &std::path::Path, name: &str, text: &str, extra: &[&str]) -> Output {
    let path = dir.join(name);
    std::fs::write(&path, text).unwrap_or_else(|e| panic!("{e}"));
    let p = path.to_string_lossy().into_owned();
    let mut args = vec!["simulate", p.as_str()];
    args.extend_from_slice(extra);
    strafeopt(&args)
}

/// `simulate --json` on scene text: the JSON, after checking exit 0 and an empty stderr.
fn simulate_json(dir: &std::path::Path, name: &str, text: &str, extra: &[&str]) -> Value {
    let mut flags = vec!["--json"];
    flags.extend_from_slice(extra);
    let out = simulate_file(dir, name, text, &flags);
    assert_eq!(
        out.status.code(),
        Some(0),
        "{name}: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(
        out.stderr.is_empty(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(!text.contains("NaN") && !text.contains("inf"), "{text}");
    serde_json::from_slice(&out.stdout).unwrap_or_else(|e| panic!("{name}: {e}"))
}

/// `simulate` on scene text that must fail: exit 2, one line on stderr starting with the program and the
/// file, holding `needle`, nothing on stdout.
fn simulate_rejected(dir: &std::path::Path, name: &str, text: &str, needle: &str) {
    let out = simulate_file(dir, name, text, &[]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{name}: {err}");
    assert_eq!(err.lines().count(), 1, "{err}");
    assert!(err.ends_with('\n'), "{err:?}");
    let path = dir.join(name);
    assert!(
        err.starts_with(&format!("strafeopt: {}:", path.display())),
        "{err}"
    );
    assert!(err.contains(needle), "{name}: {err}");
    assert!(out.stdout.is_empty());
}

/// The overlap a start-inside-a-wall message reports: the number between `by ` and ` units`.
fn overlap_in(message: &str) -> f64 {
    message
        .split("by ")
        .nth(1)
        .and_then(|rest| rest.split(" units").next())
        .and_then(|n| n.parse().ok())
        .unwrap_or_else(|| panic!("no overlap in: {message}"))
}

fn num(v: &Value, key: &str) -> f64 {
    v[key]
        .as_f64()
        .unwrap_or_else(|| panic!("{key} is not a number: {v}"))
}

// ---------------------------------------------------------------------------------------------------------
// A corridor exactly one hull wide, and one 1e-6 wider.

#[test]
fn one_hull_wide_lane_is_a_single_line_with_clearance_zero() {
    for kind in ["rule", "solid"] {
        let s = scene(&format!("{AIR}{}", lane(32.0, 2000.0, kind)));
        // The default start is halfway across: touching both walls.
        assert_eq!(s.start.pos, v(40.0, 16.0));
        let corridor = s.corridor().unwrap();
        assert_eq!(corridor.clearance(s.start.pos), 0.0);
        // Hand geometry: the only path is the centre line, 2000 - 40 units.
        let (len, path) = corridor
            .shortest_path(s.start.pos, (s.finish.a, s.finish.b))
            .unwrap_or_else(|| panic!("{kind}: no path"));
        assert!((len - 1960.0).abs() < 1e-6, "{kind}: {len}");
        assert!(len <= 1960.0 + 1e-9, "a lower bound: {len}");
        for p in &path {
            assert!((p.y - 16.0).abs() < 1e-6, "{kind}: {path:?}");
        }
        // Every point of the line is contact, not overlap; a hair off it is overlap.
        for x in [40.0, 500.0, 1000.0, 1983.9] {
            assert!(corridor.clearance(v(x, 16.0)).abs() <= TOL, "{kind} at {x}");
            assert!(!corridor.rule_violation(v(x, 16.0)));
            let off = corridor.clearance(v(x, 16.0 + 1e-6));
            assert!((off + 1e-6).abs() < 1e-12, "{kind} at {x}: {off}");
        }
        let bound = lower_bound(&s, &corridor).unwrap();
        assert!((bound.path_length - 1960.0).abs() < 1e-6);
        assert!(bound.crossing.time.is_finite() && bound.crossing.time > 0.0);
    }
}

#[test]
fn one_hull_wide_rule_lane_admits_only_runs_along_the_line() {
    let s = scene(&format!("{AIR}{}", lane(32.0, 2000.0, "rule")));
    // Holding forward along the line: at 320 ups in the air, gamma2 = 30 - 320 < 0, so mu = 0 and the
    // velocity never changes (docs/physics.md section 5): the line x = 2000 is reached after 1960 / 320 s.
    let t = run(&s, &mut forward_along_x());
    assert_trace_finite(&t);
    assert!(t.feasible(), "{:?}", t.first_rule_violation());
    let c = t.crossing.unwrap();
    assert_eq!(c.frames, 613);
    assert!((c.fraction - 0.5).abs() < 1e-9, "{c:?}");
    assert!((c.time - 6.125).abs() < 1e-9, "{c:?}");
    assert!(t
        .frames
        .iter()
        .all(|f| f.pos.y == 16.0 && f.clearance.abs() <= TOL));
    // The lower bound can only be faster.
    let bound = lower_bound(&s, &s.corridor().unwrap()).unwrap();
    assert!(bound.crossing.time <= c.time);
    // Any strafe turns the velocity off the line: the greedy strafer breaks a rule in frame 1.
    let g = greedy(&s, 300.0);
    assert_trace_finite(&g);
    assert_eq!(g.first_rule_violation(), Some(1));
    assert!(!g.feasible());
}

#[test]
fn one_hull_wide_solid_lane_clips_every_move_back_onto_the_line() {
    let s = scene(&format!("{AIR}{}", lane(32.0, 2000.0, "solid")));
    let t = greedy(&s, 300.0);
    assert_trace_finite(&t);
    assert!(t.feasible());
    let bound = lower_bound(&s, &s.corridor().unwrap()).unwrap();
    let c = t.crossing.unwrap();
    assert!(
        c.time >= bound.crossing.time,
        "{c:?} vs {:?}",
        bound.crossing
    );
    let tau = s.frame_time_s();
    let mut prev = t.start;
    for f in &t.frames {
        // The walls allow no sideways motion at all.
        assert!(
            (f.pos.y - 16.0).abs() <= TOL,
            "frame {}: {:?}",
            f.frame,
            f.pos
        );
        assert_eq!(f.vel.y, 0.0, "frame {}", f.frame);
        assert!(
            f.clearance.abs() <= TOL,
            "frame {}: {}",
            f.frame,
            f.clearance
        );
        // Each frame the strafe pushes sideways into a wall, which clips it: the hull slides the whole
        // frame at the clipped velocity.
        assert!(f.contacts >= 1, "frame {}", f.frame);
        assert!(
            ((f.pos.x - prev.pos.x) - f.vel.x * tau).abs() < 1e-9,
            "frame {}",
            f.frame
        );
        assert!(
            f.vel.x >= prev.vel.x - 1e-9,
            "clipping never slows a slide here"
        );
        prev = *f;
    }
}

#[test]
fn one_micro_unit_wider_lane_leaves_half_a_micro_unit_each_side() {
    let s = scene(&format!("{AIR}{}", lane(32.000001, 2000.0, "rule")));
    assert_eq!(s.start.pos, v(40.0, 16.0000005));
    let corridor = s.corridor().unwrap();
    let c = corridor.clearance(s.start.pos);
    assert!((c - 5e-7).abs() < 1e-12, "{c}");
    let (len, _) = corridor
        .shortest_path(s.start.pos, (s.finish.a, s.finish.b))
        .unwrap();
    assert!((len - 1960.0).abs() < 1e-6, "{len}");
    // Moving 1e-6 sideways is overlap on one side.
    assert!(corridor.rule_violation(v(500.0, 16.0000005 + 1e-6)));
    assert!(!corridor.rule_violation(v(500.0, 16.0000005 + 4e-7)));
}

#[test]
fn a_one_hull_wide_bend_turns_on_a_single_point() {
    // Width 32, legs 500: the centre runs along y = 16 to the corner (484, 16), then along x = 484.
    let s = scene(&format!(
        "{AIR}[bend90]\nwidth = 32\nleg1 = 500\nleg2 = 500\nkind = \"solid\"\n"
    ));
    let corridor = s.corridor().unwrap();
    let (len, path) = corridor
        .shortest_path(s.start.pos, (s.finish.a, s.finish.b))
        .unwrap();
    let hand = (484.0 - 40.0) + (500.0 - 16.0);
    assert!(
        (len - hand).abs() < 1e-6 && len <= hand + 1e-9,
        "{len} {path:?}"
    );
    // The corner touches the outer walls and the inner corner at once.
    assert!(corridor.clearance(v(484.0, 16.0)).abs() <= TOL);
    // Hold forward along +x until the end wall stops the hull in the corner, then forward along +y. Hand:
    // 320 ups covers 484 - 40 = 444 units in 138.75 frames; in frame 139 the end wall stops the hull dead
    // at (484, 16) (velocity clipped to 0: gamma1 = 32 > L = 30 at 100 fps, so holding forward adds
    // nothing). From rest, forward gives mu = gamma2 = L - |v| (docs/physics.md section 5), so the speed is 30
    // ups from frame 140 on: the line y = 500 is 484 units away, 1613.33 frames, so it is crossed in frame
    // 139 + 1614 = 1753, a third of the way through.
    let mut controls = vec![
        Control {
            yaw_rad: 0.0,
            forwardmove: 400.0,
            sidemove: 0.0,
            jump: false,
            duck: false,
        };
        139
    ];
    controls.push(Control {
        yaw_rad: std::f64::consts::FRAC_PI_2,
        ..controls[0]
    });
    let t = run(
        &s,
        &mut Playback {
            controls,
            label: "corner".to_string(),
        },
    );
    assert_trace_finite(&t);
    assert_eq!(t.frames[138].pos, v(484.0, 16.0));
    assert_eq!(t.frames[138].vel, Vec2::ZERO);
    for f in &t.frames {
        let on_leg1 = (f.pos.y - 16.0).abs() <= TOL && f.pos.x <= 484.0 + TOL;
        let on_leg2 = (f.pos.x - 484.0).abs() <= TOL && f.pos.y >= 16.0 - TOL;
        assert!(
            on_leg1 || on_leg2,
            "frame {}: off the line at {:?}",
            f.frame,
            f.pos
        );
        assert!(f.clearance >= -TOL, "frame {}: {}", f.frame, f.clearance);
    }
    assert!(t.feasible());
    let c = t.crossing.unwrap();
    assert_eq!(c.frames, 1753);
    assert!((c.fraction - 1.0 / 3.0).abs() < 1e-6, "{c:?}");
    let bound = lower_bound(&s, &corridor).unwrap();
    assert!(bound.crossing.time <= c.time);
}

#[test]
fn narrower_than_one_hull_is_a_clear_error() {
    // The shorthand names the width.
    let (loc, key, msg) = scene_error(&format!("{AIR}{}", lane(31.999999, 2000.0, "rule")));
    assert_eq!((loc.as_str(), key.as_str()), ("hard.toml:6", "lane.width"));
    assert!(msg.contains("got 31.999999; must be at least 32"), "{msg}");
    // Explicit walls 32 - 1e-6 apart with the start between them: the start overlaps by 5e-7.
    let walls = |gap: f64, x0: f64| {
        format!(
            "[[walls]]\nkind = \"rule\"\npoints = [[{x0}, 0], [2000, 0]]\n\
             [[walls]]\nkind = \"rule\"\npoints = [[{x0}, {gap}], [2000, {gap}]]\n"
        )
    };
    let text = format!(
        "{AIR}[start]\nposition = [40, 15.9999995]\n[finish]\na = [1900, -100]\nb = [1900, 100]\n{}",
        walls(31.999999, 0.0)
    );
    let (loc, key, msg) = scene_error(&text);
    assert_eq!(
        (loc.as_str(), key.as_str()),
        ("hard.toml:6", "start.position")
    );
    assert!(msg.contains("overlaps walls["), "{msg}");
    assert!((overlap_in(&msg) - 5e-7).abs() < 1e-12, "{msg}");
}

#[test]
fn a_gap_just_under_one_hull_wide_is_no_path_and_the_validator_agrees_with_clearance() {
    // A closed room (y from -200 to 200) pinched to a gap of `gap` units around y = 0 for 1000 <= x <= 1200:
    // the start is before the gap, the finish after it. The scene must be accepted exactly when a hull
    // centre can stand in the gap without overlapping a wall by more than the contact tolerance.
    for gap in [
        32.0 + 1e-6,
        32.0,
        32.0 - 1e-9,
        32.0 - 2.2e-9,
        32.0 - 1e-8,
        32.0 - 1e-7,
        32.0 - 1e-6,
    ] {
        let half = gap / 2.0;
        let text = format!(
            "{AIR}[start]\nposition = [100, 0]\n[finish]\na = [1900, -100]\nb = [1900, 100]\n\
             [[walls]]\nkind = \"rule\"\nclosed = true\npoints = [[0, -200], [1000, -200], [1000, -{half}], \
             [1200, -{half}], [1200, -200], [2000, -200], [2000, 200], [1200, 200], [1200, {half}], \
             [1000, {half}], [1000, 200], [0, 200]]\n"
        );
        let fits = {
            let walls = [
                wall(
                    BoundaryKind::Rule,
                    false,
                    &[(1000.0, -half), (1200.0, -half)],
                ),
                wall(BoundaryKind::Rule, false, &[(1000.0, half), (1200.0, half)]),
            ];
            // Independent: the best the hull can do in the gap is the middle, y = 0.
            walls
                .iter()
                .flat_map(|w| w.segments())
                .map(|(a, b)| box_segment_gap(v(1100.0, 0.0), H, a, b))
                .fold(f64::INFINITY, f64::min)
                >= -TOL
        };
        match Scene::from_toml_str(&text, "hard.toml") {
            Ok(s) => {
                assert!(
                    fits,
                    "gap {gap}: accepted, but the hull cannot stand in the gap"
                );
                let bound = lower_bound(&s, &s.corridor().unwrap()).unwrap();
                assert!(bound.path_length >= 1800.0 - 1e-6 && bound.path_length.is_finite());
            }
            Err(e) => {
                assert!(!fits, "gap {gap}: rejected, but the hull fits: {e}");
                let shown = e.to_string();
                assert!(shown.starts_with("hard.toml:7: finish: no path"), "{shown}");
            }
        }
    }
}

// ---------------------------------------------------------------------------------------------------------
// Collinear and zero-length segments.

#[test]
fn collinear_segments_act_as_one_straight_wall() {
    let kinds = [BoundaryKind::Solid, BoundaryKind::Rule];
    for kind in kinds {
        let walls = vec![
            // One wall with collinear neighbours, and a second wall overlapping it along the same line.
            wall(
                kind,
                false,
                &[(0.0, 0.0), (100.0, 0.0), (200.0, 0.0), (300.0, 0.0)],
            ),
            wall(kind, false, &[(150.0, 0.0), (250.0, 0.0)]),
            // A closed polygon with a collinear vertex on its top edge, far away.
            wall(
                kind,
                true,
                &[
                    (0.0, 500.0),
                    (100.0, 500.0),
                    (200.0, 500.0),
                    (200.0, 600.0),
                    (0.0, 600.0),
                ],
            ),
        ];
        for w in &walls {
            assert_eq!(w.defect(), None, "{w:?}");
        }
        let corridor = Corridor::new(&walls).unwrap();
        // Clearance over and around the joints against the independent box-segment gap.
        for &x in &[
            -20.0, 0.0, 50.0, 99.999, 100.0, 100.001, 150.0, 200.0, 250.0, 300.0, 316.0, 330.0,
        ] {
            for &y in &[
                -30.0,
                -16.0,
                -3.0,
                0.0,
                8.0,
                16.0 - 1e-6,
                16.0,
                16.0 + 1e-6,
                40.0,
            ] {
                let c = v(x, y);
                let brute = walls
                    .iter()
                    .flat_map(|w| w.segments().collect::<Vec<_>>())
                    .map(|(a, b)| box_segment_gap(c, H, a, b))
                    .fold(f64::INFINITY, f64::min);
                let got = corridor.clearance(c);
                assert!(
                    (got - brute).abs() < 1e-9,
                    "{kind:?} at {c:?}: {got} vs {brute}"
                );
            }
        }
        // Sliding exactly along the line across the joints: free; a hair below it: overlap.
        let (p0, p1) = (v(20.0, 16.0), v(280.0, 16.0));
        assert!(!corridor.rule_violation_swept(p0, p1));
        assert_eq!(corridor.cast(p0, p1 - p0), Cast::Free);
        if kind == BoundaryKind::Rule {
            assert!(corridor.rule_violation_swept(p0, v(280.0, 16.0 - 1e-6)));
        }
    }
    // A solid collinear wall: a move angled into it slides along it across every joint and ends on it.
    let corridor = Corridor::new(&[
        wall(
            BoundaryKind::Solid,
            false,
            &[(0.0, 0.0), (100.0, 0.0), (200.0, 0.0), (300.0, 0.0)],
        ),
        wall(BoundaryKind::Solid, false, &[(150.0, 0.0), (250.0, 0.0)]),
    ])
    .unwrap();
    let r = corridor.sweep(v(20.0, 20.0), v(10_000.0, -1_000.0), 0.02);
    // Hand: 4 of the 20 units down to contact (a fifth of the move, x = 60), then the other 0.016 s along x
    // at 10000 ups.
    assert_eq!(r.vel, v(10_000.0, 0.0));
    assert!(
        (r.pos.y - 16.0).abs() <= 1e-12 && (r.pos.x - 220.0).abs() < 1e-9,
        "{r:?}"
    );
    assert_eq!(r.status, SweepStatus::Clipped { contacts: 1 });
}

/// A scene with the lane and one extra wall whose `points` are written one per line.
fn with_wall(points: &[&str], closed: bool) -> String {
    format!(
        "{AIR}{}[[walls]]\nkind = \"rule\"\nclosed = {closed}\npoints = [\n{}\n]\n",
        lane(256.0, 2000.0, "rule"),
        points
            .iter()
            .map(|p| format!("  {p},"))
            .collect::<Vec<_>>()
            .join("\n")
    )
}

#[test]
fn zero_length_and_folded_segments_from_the_scene_file_are_located() {
    // Lines: 1-4 engine, 5-8 lane, 9 [[walls]], 10 kind, 11 closed, 12 `points = [`, 13.. the points.
    let cases: [(&[&str], bool, usize, &str); 6] = [
        // A repeated point: segment 1 has zero length, blamed on its first point.
        (
            &["[500, 100]", "[600, 100]", "[600, 100]", "[700, 100]"],
            false,
            14,
            "segment 1 has zero length",
        ),
        // A closed polygon whose last point repeats the first: the closing segment has zero length.
        (
            &["[500, 100]", "[600, 100]", "[600, 150]", "[500, 100]"],
            true,
            16,
            "segment 3 has zero length",
        ),
        // Shorter than the minimum (1e-9 units), and exactly the minimum: both zero length.
        (
            &["[500, 100]", "[500.0000000001, 100]"],
            false,
            13,
            "segment 0 has zero length",
        ),
        (
            &["[0, 100]", "[0.000000001, 100]", "[10, 100]"],
            false,
            13,
            "segment 0 has zero length",
        ),
        // Collinear, but folding back onto itself.
        (
            &["[500, 100]", "[600, 100]", "[550, 100]"],
            false,
            14,
            "segments 0 and 1 intersect",
        ),
        // A later segment collinear with the first, overlapping it.
        (
            &[
                "[500, 100]",
                "[600, 100]",
                "[600, 120]",
                "[400, 120]",
                "[400, 100]",
                "[550, 100]",
            ],
            false,
            17,
            "segments 0 and 4 intersect",
        ),
    ];
    for (points, closed, line, words) in cases {
        let text = with_wall(points, closed);
        let (loc, key, msg) = scene_error(&text);
        assert_eq!(
            (loc.as_str(), key.as_str()),
            (format!("hard.toml:{line}").as_str(), "walls[0].points"),
            "{msg}\n---\n{text}"
        );
        assert!(msg.contains(words), "{msg}");
    }
    // Short but longer than the minimum: accepted, and the corridor gives finite answers near it.
    let s = scene(&with_wall(
        &["[500, 100]", "[500.00000001, 100]", "[600, 100]"],
        false,
    ));
    let corridor = s.corridor().unwrap();
    let c = corridor.clearance(v(500.0, 116.0));
    assert!(c.abs() <= TOL, "{c}");
    let r = corridor.sweep(v(450.0, 130.0), v(1000.0, -1000.0), 0.1);
    assert!(r.pos.is_finite() && r.vel.is_finite());
    // A collinear polyline and a hairpin with no divider gap (a single line) are fine.
    scene(&with_wall(
        &["[500, 100]", "[600, 100]", "[700, 100]"],
        false,
    ));
    let s = scene(&format!(
        "{AIR}[hairpin]\nwidth = 64\nlength = 800\ngap = 0\nkind = \"rule\"\n"
    ));
    assert_eq!(s.walls[1].points.len(), 2);
    // A zero-length finish line.
    let (loc, key, msg) = scene_error(&format!(
        "{AIR}[start]\nposition = [0, 0]\n[finish]\na = [100, 5]\nb = [100, 5]\n"
    ));
    assert_eq!((loc.as_str(), key.as_str()), ("hard.toml:7", "finish"));
    assert!(msg.contains("zero length"), "{msg}");
}

// ---------------------------------------------------------------------------------------------------------
// Starts touching a wall, and a hair inside one.

#[test]
fn a_start_touching_a_wall_is_allowed_and_a_start_inside_is_not() {
    for kind in ["rule", "solid"] {
        // Touching the bottom wall, and the bottom-left corner (both walls at once).
        for (x, y) in [(40.0, 16.0), (16.0, 16.0), (16.0, 100.0)] {
            let s = scene(&format!(
                "{AIR}[start]\nposition = [{x}, {y}]\n{}",
                lane(256.0, 2000.0, kind)
            ));
            let corridor = s.corridor().unwrap();
            assert_eq!(corridor.clearance(s.start.pos), 0.0, "{kind} ({x}, {y})");
            assert!(!corridor.rule_violation(s.start.pos));
            assert_eq!(corridor.cast(s.start.pos, v(100.0, 0.0)), Cast::Free);
            lower_bound(&s, &corridor).unwrap();
        }
        // 1e-6 inside: a clear error at the start's line with the overlap.
        let (loc, key, msg) = scene_error(&format!(
            "{AIR}[start]\nposition = [40, 15.999999]\n{}",
            lane(256.0, 2000.0, kind)
        ));
        assert_eq!(
            (loc.as_str(), key.as_str()),
            ("hard.toml:6", "start.position")
        );
        assert!(msg.contains("overlaps lane (segment 0) by "), "{msg}");
        assert!((overlap_in(&msg) - 1e-6).abs() < 1e-12, "{msg}");
        let corridor = Corridor::new(&[wall(
            BoundaryKind::Solid,
            false,
            &[(0.0, 0.0), (100.0, 0.0)],
        )])
        .unwrap();
        match corridor.cast(v(50.0, 16.0 - 1e-6), v(10.0, 0.0)) {
            Cast::StartedInside { depth_units, .. } => {
                assert!((depth_units - 1e-6).abs() < 1e-12)
            }
            other => panic!("{other:?}"),
        }
    }
}

#[test]
fn a_start_at_the_contact_tolerance_is_judged_alike_everywhere() {
    // Around 1e-9 inside, rounding decides which side of the tolerance a start falls: whatever it
    // decides, the scene validator, the rule check and the solid cast must decide the same.
    for depth in [0.0, 0.5e-9, 0.9e-9, 1e-9, 1.1e-9, 1.5e-9, 2e-9, 1e-8] {
        let y = 16.0 - depth;
        for kind in ["rule", "solid"] {
            let text = format!(
                "{AIR}[start]\nposition = [40, {y:?}]\n{}",
                lane(256.0, 2000.0, kind)
            );
            let accepted = Scene::from_toml_str(&text, "hard.toml").is_ok();
            let corridor = Corridor::new(&[wall(
                if kind == "rule" {
                    BoundaryKind::Rule
                } else {
                    BoundaryKind::Solid
                },
                false,
                &[(2000.0, 0.0), (0.0, 0.0), (0.0, 256.0), (2000.0, 256.0)],
            )])
            .unwrap();
            let p = v(40.0, y);
            let inside = if kind == "rule" {
                corridor.rule_violation(p)
            } else {
                matches!(corridor.cast(p, v(10.0, 0.0)), Cast::StartedInside { .. })
            };
            assert_eq!(accepted, !inside, "{kind} at depth {depth}");
            // And both agree with the independent overlap, away from the rounding band.
            let overlap = box_segment_overlap(p, H, v(2000.0, 0.0), v(0.0, 0.0));
            if (overlap - TOL).abs() > 1e-14 {
                assert_eq!(
                    accepted,
                    overlap <= TOL,
                    "{kind} at depth {depth}: {overlap}"
                );
            }
        }
    }
}

// ---------------------------------------------------------------------------------------------------------
// Finish lines parallel to the motion.

#[test]
fn finish_line_parallel_to_the_motion() {
    let centre = |a: Vec2, b: Vec2| FinishLine {
        a,
        b,
        point: FinishPoint::Centre,
    };
    let hull = |a: Vec2, b: Vec2| FinishLine {
        a,
        b,
        point: FinishPoint::Hull,
    };
    // Centre, horizontal line from x = 100 to 200 on y = 0: along it from before its start (hand: the
    // fraction at which x reaches 100), from on it, ending exactly on its start, and off it by 1e-6.
    let l = centre(v(100.0, 0.0), v(200.0, 0.0));
    assert_eq!(l.crossing_fraction(v(0.0, 0.0), v(400.0, 0.0)), Some(0.25));
    assert_eq!(l.crossing_fraction(v(400.0, 0.0), v(0.0, 0.0)), Some(0.5));
    assert_eq!(l.crossing_fraction(v(150.0, 0.0), v(170.0, 0.0)), Some(0.0));
    assert_eq!(l.crossing_fraction(v(20.0, 0.0), v(100.0, 0.0)), Some(1.0));
    assert_eq!(l.crossing_fraction(v(20.0, 0.0), v(99.999, 0.0)), None);
    assert_eq!(l.crossing_fraction(v(0.0, 1e-6), v(400.0, 1e-6)), None);
    assert_eq!(l.crossing_fraction(v(0.0, -1e-6), v(400.0, -1e-6)), None);
    // Within the contact tolerance of the line counts as on it.
    assert_eq!(
        l.crossing_fraction(v(0.0, 0.5e-9), v(400.0, 0.5e-9)),
        Some(0.25)
    );
    // A zero-length move on the line and off it.
    assert_eq!(l.crossing_fraction(v(150.0, 0.0), v(150.0, 0.0)), Some(0.0));
    assert_eq!(l.crossing_fraction(v(50.0, 0.0), v(50.0, 0.0)), None);
    // A diagonal line, moving along it: reaches its end (0, 0) a third of the way.
    let d = centre(v(0.0, 0.0), v(100.0, 100.0));
    let t = d
        .crossing_fraction(v(-100.0, -100.0), v(200.0, 200.0))
        .unwrap();
    assert!((t - 1.0 / 3.0).abs() < 1e-12, "{t}");
    assert_eq!(
        d.crossing_fraction(v(-100.0, -99.99), v(200.0, 200.01)),
        None
    );

    // Hull: the box touches the line once its edge reaches it, checked against brute force.
    let lh = hull(v(100.0, 16.0), v(200.0, 16.0));
    let cases = [
        (v(0.0, 0.0), v(400.0, 0.0)),       // the top edge slides along the line
        (v(0.0, 0.5e-9), v(400.0, 0.5e-9)), // inside the tolerance: touching
        (v(0.0, -1e-6), v(400.0, -1e-6)),   // 1e-6 below: never touches
        (v(0.0, 32.0), v(400.0, 32.0)),     // the bottom edge slides along it
        (v(0.0, 16.0), v(400.0, 16.0)),     // the centre runs along it
        (v(500.0, 1.0), v(0.0, 1.0)),       // backwards, overlapping by 1
        (v(150.0, 0.0), v(500.0, 0.0)),     // starts touching
    ];
    for (p0, p1) in cases {
        let got = lh.crossing_fraction(p0, p1);
        let brute = first_touch(p0, p1, H, lh.a, lh.b);
        match (got, brute) {
            (Some(g), Some(b)) => assert!((g - b).abs() < 1e-8, "{p0:?}->{p1:?}: {g} vs {b}"),
            (None, None) => {}
            _ => panic!("{p0:?}->{p1:?}: {got:?} vs brute {brute:?}"),
        }
    }
    // The hand values of two of them.
    assert_eq!(lh.crossing_fraction(v(0.0, 0.0), v(400.0, 0.0)), Some(0.21));
    assert_eq!(lh.crossing_fraction(v(0.0, -1e-6), v(400.0, -1e-6)), None);
    // Diagonal hull finish, moving parallel to it with a corner exactly on it, a hair off, a hair over.
    let dh = hull(v(0.0, 0.0), v(100.0, 100.0));
    for c in [16.0, 16.0 + 1e-6, 16.0 - 1e-6, 10.0, 30.0] {
        let (p0, p1) = (v(-100.0 + c, -100.0 - c), v(200.0 + c, 200.0 - c));
        let got = dh.crossing_fraction(p0, p1);
        let brute = first_touch(p0, p1, H, dh.a, dh.b);
        // Hand: touching starts at s = -(16 - c) along the diagonal, i.e. t = (100 - (16 - c)) / 300.
        let hand = (c <= 16.0).then(|| (100.0 - (16.0 - c)) / 300.0);
        match (got, brute, hand) {
            (Some(g), Some(b), Some(h)) => {
                assert!(
                    (g - b).abs() < 1e-8 && (g - h).abs() < 1e-9,
                    "c {c}: {g} {b} {h}"
                )
            }
            (None, None, None) => {}
            _ => panic!("c {c}: {got:?} vs brute {brute:?} vs hand {hand:?}"),
        }
    }
}

#[test]
fn simulate_a_finish_line_along_the_motion() {
    let dir = temp_dir("parallel-finish");
    // No acceleration: the start velocity, 320 ups along +x from (0, 0), is kept. The finish lies on the
    // x axis from x = 100 to 200: the centre reaches it after 100 / 320 = 0.3125 s, in frame 32, a quarter
    // of the way through. The bound's speed profile is the same constant speed: the same time.
    let text = format!(
        "{COAST}[start]\nposition = [0, 0]\nvelocity = [320, 0]\n[finish]\na = [100, 0]\nb = [200, 0]\n"
    );
    let s = scene(&text);
    let t = run(&s, &mut forward_along_x());
    let c = t.crossing.unwrap();
    assert_eq!(c.frames, 32);
    assert!(
        (c.fraction - 0.25).abs() < 1e-9 && (c.time - 0.3125).abs() < 1e-9,
        "{c:?}"
    );
    let j = simulate_json(&dir, "along.toml", &text, &[]);
    assert_eq!(j["frames"].as_u64(), Some(32));
    assert!((num(&j, "time") - 0.3125).abs() < 1e-9, "{j}");
    assert!((num(&j, "crossing_fraction") - 0.25).abs() < 1e-9, "{j}");
    assert!(
        (num(&j["lower_bound"], "time") - 0.3125).abs() < 1e-9,
        "{j}"
    );
    assert!(
        (num(&j["lower_bound"], "path_length") - 100.0).abs() < 1e-9,
        "{j}"
    );
    assert_eq!(j["feasible"], true);
    assert!(j["min_clearance"].is_null(), "no walls: {j}");

    // A hull finish 16 units to the side of the motion: the box's top edge runs along it and touches it
    // once the box's right edge reaches x = 100, centre x = 84: frame 27, a quarter through, 0.2625 s.
    let text = format!(
        "{COAST}[start]\nposition = [0, 0]\nvelocity = [320, 0]\n\
         [finish]\na = [100, 16]\nb = [200, 16]\npoint = \"hull\"\n"
    );
    let j = simulate_json(&dir, "along-hull.toml", &text, &[]);
    assert_eq!(j["frames"].as_u64(), Some(27));
    assert!((num(&j, "time") - 0.2625).abs() < 1e-9, "{j}");
    assert!(num(&j["lower_bound"], "time") <= num(&j, "time"));

    // 1e-6 further to the side: never touched; the run ends at the frame cap without a time.
    let text = format!(
        "max-frames = 200\n{COAST}[start]\nposition = [0, 0]\nvelocity = [320, 0]\n\
         [finish]\na = [100, 16.000001]\nb = [200, 16.000001]\npoint = \"hull\"\n"
    );
    let j = simulate_json(&dir, "beside-hull.toml", &text, &[]);
    assert!(j["time"].is_null(), "{j}");
    assert_eq!(j["feasible"], false);
    assert_eq!(j["frames"].as_u64(), Some(200));
    let _ = std::fs::remove_dir_all(&dir);
}

// ---------------------------------------------------------------------------------------------------------
// Moves exactly along a rule line.

#[test]
fn moves_exactly_along_rule_lines() {
    let corridor = Corridor::new(&[
        wall(BoundaryKind::Rule, false, &[(0.0, 0.0), (1000.0, 0.0)]),
        wall(BoundaryKind::Rule, false, &[(0.0, 100.0), (1000.0, 1100.0)]),
    ])
    .unwrap();
    // Horizontal: the hull's bottom edge on the line; the joint-free line end; 1e-6 into it.
    let segs = [
        (v(0.0, 0.0), v(1000.0, 0.0)),
        (v(0.0, 100.0), v(1000.0, 1100.0)),
    ];
    let brute_violation = |p0: Vec2, p1: Vec2| {
        (0..=1000).any(|i| {
            let c = p0 + (p1 - p0) * (i as f64 / 1000.0);
            segs.iter()
                .any(|&(a, b)| box_segment_overlap(c, H, a, b) > TOL)
        })
    };
    let moves = [
        (v(-50.0, 16.0), v(1050.0, 16.0)),
        (v(-50.0, -16.0), v(1050.0, -16.0)),
        (v(-50.0, 16.0 - 1e-6), v(1050.0, 16.0 - 1e-6)),
        (v(-50.0, 16.0 + 1e-6), v(1050.0, 16.0 + 1e-6)),
        // Past the end: the box's left edge along the line's end x = 1000 + 16.
        (v(1016.0, -40.0), v(1016.0, 40.0)),
        (v(1016.0 - 1e-6, -40.0), v(1016.0 - 1e-6, 40.0)),
        // Diagonal line y = x + 100: a corner of the box runs exactly along it at centre offset (16, -16).
        (v(216.0, 284.0), v(816.0, 884.0)),
        (v(216.0 - 1e-6, 284.0), v(816.0 - 1e-6, 884.0)),
        (v(216.0 + 1e-6, 284.0), v(816.0 + 1e-6, 884.0)),
        (v(-16.0, 116.0), v(984.0, 1116.0)),
    ];
    for (p0, p1) in moves {
        assert_eq!(
            corridor.rule_violation_swept(p0, p1),
            brute_violation(p0, p1),
            "{p0:?} -> {p1:?}"
        );
    }
    // The exact ones are along the line and allowed; the 1e-6 ones into it are not.
    assert!(!corridor.rule_violation_swept(moves[0].0, moves[0].1));
    assert!(corridor.rule_violation_swept(moves[2].0, moves[2].1));
    assert!(!corridor.rule_violation_swept(moves[6].0, moves[6].1));
    assert!(corridor.rule_violation_swept(moves[7].0, moves[7].1));
    assert!(!corridor.rule_violation_swept(moves[8].0, moves[8].1));
}

#[test]
fn runs_along_rule_lines_are_valid() {
    // Coasting at 320 ups with the hull's edge on a rule line (a lane 64 wide, start at y = 16), and with a
    // corner on a diagonal rule line: valid runs with clearance 0 in every frame.
    let straight = format!(
        "{COAST}[start]\nposition = [40, 16]\nvelocity = [320, 0]\n{}",
        lane(64.0, 1000.0, "rule")
    );
    let s = scene(&straight);
    let t = run(&s, &mut forward_along_x());
    assert!(t.feasible());
    assert!(t.frames.iter().all(|f| f.clearance.abs() <= TOL));
    // Hand: (1000 - 40) / 320 = 3 s.
    assert!((t.crossing.unwrap().time - 3.0).abs() < 1e-9);

    let diag = format!(
        "{COAST}[start]\nposition = [216, 284]\nvelocity = [226.27416997969522, 226.27416997969522]\n\
         [finish]\na = [800, 1200]\nb = [1200, 800]\n\
         [[walls]]\nkind = \"rule\"\npoints = [[0, 100], [1000, 1100]]\n"
    );
    let s = scene(&diag);
    let t = run(&s, &mut forward_along_x());
    assert!(t.feasible(), "{:?}", t.first_rule_violation());
    assert!(
        t.frames.iter().all(|f| f.clearance.abs() <= TOL),
        "clearance"
    );
    // Hand: the centre moves along (1, 1) from (216, 284) to the line x + y = 2000: 1500 / (2 * 226.27...)
    // seconds at 226.27 ups per axis.
    let hand = 1500.0 / (2.0 * 226.274_169_979_695_22);
    assert!((t.crossing.unwrap().time - hand).abs() < 1e-9);

    let dir = temp_dir("along-rule");
    for (name, text, time) in [
        ("straight.toml", &straight, 3.0),
        ("diag.toml", &diag, hand),
    ] {
        let j = simulate_json(&dir, name, text, &[]);
        assert_eq!(j["feasible"], true, "{name}: {j}");
        assert!(num(&j, "min_clearance").abs() <= TOL, "{name}: {j}");
        assert!((num(&j, "time") - time).abs() < 1e-9, "{name}: {j}");
        assert!(j["first_rule_violation_frame"].is_null());
    }
    let _ = std::fs::remove_dir_all(&dir);
}

// ---------------------------------------------------------------------------------------------------------
// The same corridors through the real binary.

#[test]
fn simulate_one_hull_wide_corridors_through_the_binary() {
    let dir = temp_dir("one-hull");
    // Solid: valid, clearance 0, the centre-line path.
    let j = simulate_json(
        &dir,
        "solid32.toml",
        &format!("{AIR}{}", lane(32.0, 2000.0, "solid")),
        &["--lookahead", "300"],
    );
    assert_eq!(j["feasible"], true, "{j}");
    assert!(num(&j, "min_clearance").abs() <= TOL, "{j}");
    assert!(
        (num(&j["lower_bound"], "path_length") - 1960.0).abs() < 1e-6,
        "{j}"
    );
    assert!(num(&j, "time") >= num(&j["lower_bound"], "time"));
    assert!(j["collisions"].as_u64().unwrap_or(0) > 0);
    // Rule: accepted, but the greedy strafer breaks a rule in frame 1 (exit 0: an outcome, not an error).
    let j = simulate_json(
        &dir,
        "rule32.toml",
        &format!("{AIR}{}", lane(32.0, 2000.0, "rule")),
        &["--lookahead", "300"],
    );
    assert_eq!(j["feasible"], false, "{j}");
    assert_eq!(j["first_rule_violation_frame"].as_u64(), Some(1), "{j}");
    assert!(num(&j["lower_bound"], "time").is_finite());
    // The text form says so in one word.
    let out = simulate_file(
        &dir,
        "rule32.toml",
        &format!("{AIR}{}", lane(32.0, 2000.0, "rule")),
        &["--lookahead", "300"],
    );
    assert_eq!(out.status.code(), Some(0));
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(
        text.contains("INVALID: broke a rule line in frame 1"),
        "{text}"
    );
    // 1e-6 wider: half a micro-unit each side at the start.
    let j = simulate_json(
        &dir,
        "wider.toml",
        &format!("{AIR}{}", lane(32.000001, 2000.0, "solid")),
        &["--lookahead", "300"],
    );
    let c = num(&j, "min_clearance");
    assert!((-TOL..=5e-7 + 1e-12).contains(&c), "{j}");
    assert_eq!(j["feasible"], true);
    // Narrower: exit 2 with the key and the allowed range.
    simulate_rejected(
        &dir,
        "narrow.toml",
        &format!("{AIR}{}", lane(31.999999, 2000.0, "solid")),
        "lane.width: got 31.999999; must be at least 32",
    );
    // A start 1e-6 inside a wall, a zero-length wall segment, a zero-length finish.
    simulate_rejected(
        &dir,
        "inside.toml",
        &format!(
            "{AIR}[start]\nposition = [40, 15.999999]\n{}",
            lane(256.0, 2000.0, "solid")
        ),
        "start.position: the hull at (40, 15.999999) overlaps lane",
    );
    simulate_rejected(
        &dir,
        "zero-seg.toml",
        &with_wall(&["[500, 100]", "[600, 100]", "[600, 100]"], false),
        "walls[0].points: segment 1 has zero length",
    );
    simulate_rejected(
        &dir,
        "zero-finish.toml",
        &format!("{COAST}[start]\nposition = [0, 0]\n[finish]\na = [100, 5]\nb = [100, 5]\n"),
        "finish: the finish line has zero length",
    );
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn a_non_finite_move_crosses_no_finish_line() {
    // Regression (issue 9): a NaN or infinite end of the move made the crossing test answer 0.0, so a run
    // whose state had overflowed was reported as crossing the line.
    for point in [FinishPoint::Centre, FinishPoint::Hull] {
        let l = FinishLine {
            a: v(100.0, -50.0),
            b: v(100.0, 50.0),
            point,
        };
        for bad in [
            v(f64::NAN, 0.0),
            v(0.0, f64::NAN),
            v(f64::INFINITY, 0.0),
            v(f64::NEG_INFINITY, 0.0),
        ] {
            assert_eq!(
                l.crossing_fraction(v(0.0, 0.0), bad),
                None,
                "{point:?} to {bad:?}"
            );
            assert_eq!(
                l.crossing_fraction(bad, v(200.0, 0.0)),
                None,
                "{point:?} from {bad:?}"
            );
        }
        let expected = if point == FinishPoint::Centre {
            0.5
        } else {
            0.42
        };
        assert_eq!(
            l.crossing_fraction(v(0.0, 0.0), v(200.0, 0.0)),
            Some(expected)
        );
    }
}
