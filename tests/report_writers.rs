//! The report writers on `Vec<u8>`: the HTML report (five SVG figures and the summary table,
//! one or two runs, deterministic), the trajectory CSV / JSON, the `.hltas` script, and rebuilding a
//! saved result.

use hltas::types::AutoMovement;
use hltas::HLTAS;
use serde_json::Value;
use std::path::Path;
use strafeopt::cli::{report_cmd, simulate::summary_json};
use strafeopt::optimise::{lower_bound, LowerBound};
use strafeopt::physics::strafe::{max_accel_control, strafe_keys};
use strafeopt::physics::Side;
use strafeopt::physics::{Control, PlayerState};
use strafeopt::report::{self, figures, html, write_html, ReportInput};
use strafeopt::scene::Scene;
use strafeopt::sim::{Controller, Greedy, SideStrafer, Simulation, Trace};

const SCENE: &str = "scenarios/hl-bend90-100fps.toml";
const LOOKAHEAD: f64 = 300.0;

fn scene() -> Scene {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join(SCENE);
    Scene::load(&path).unwrap_or_else(|e| panic!("{e}"))
}

fn runs(scene: &Scene) -> (LowerBound, Trace, Trace) {
    let sim = Simulation::new(scene).unwrap_or_else(|e| panic!("{e}"));
    let bound = lower_bound(scene, sim.corridor()).unwrap_or_else(|e| panic!("{e}"));
    let greedy = sim.run(&mut Greedy::new(bound.path.clone(), LOOKAHEAD));
    let right = sim.run(&mut SideStrafer { side: Side::Right });
    (bound, greedy, right)
}

fn html_of(input: &ReportInput) -> String {
    let mut out = Vec::new();
    write_html(input, &mut out).unwrap_or_else(|e| panic!("{e}"));
    String::from_utf8(out).unwrap_or_else(|e| panic!("{e}"))
}

/// The text of each `<svg>...</svg>` element.
fn svgs(html: &str) -> Vec<&str> {
    html.match_indices("<svg")
        .filter_map(|(i, _)| html[i..].find("</svg>").map(|j| &html[i..i + j]))
        .collect()
}

#[test]
fn html_has_five_figures_and_the_summary_table() {
    let scene = scene();
    let (bound, greedy, _) = runs(&scene);
    let summary = summary_json(&scene, &greedy, &bound, Some(LOOKAHEAD));
    let input = ReportInput::new(&scene, &bound, &summary).with_run("greedy", &greedy);
    let page = html_of(&input);
    assert!(page.starts_with("<!DOCTYPE html>") && page.trim_end().ends_with("</html>"));
    let figures = svgs(&page);
    assert_eq!(figures.len(), 5, "five inline SVG figures");
    for (svg, id) in figures.iter().zip(html::FIGURE_IDS) {
        assert!(page.contains(&format!("<figure id=\"{id}\">")), "{id}");
        let drawn = svg.matches("<polyline").count() + svg.matches("<path").count();
        assert!(drawn >= 10, "{id}: only {drawn} lines drawn");
    }
    // Plotters draws with the SVG backend; no script, no external resource.
    assert!(!page.contains("<script") && !page.contains("src="));
    // The corridor shows the hull boxes and the rule lines; the radius figure shows the run's radii.
    assert!(figures[0].matches("<rect").count() >= 6);
    assert!(figures[4].matches("<circle").count() >= 100);
    // The turn rate's window is named; the clearance figure marks the run's smallest clearance.
    assert!(figures[2].contains(&format!(
        "averaged over {} frames",
        figures::TURN_RATE_WINDOW_FRAMES
    )));
    assert!(figures[3].contains(&format!("greedy: min {:.4} units", greedy.min_clearance())));
    // The summary table holds the --json keys, nested ones dotted.
    assert!(page.contains(&format!("<table id=\"{}\">", html::SUMMARY_TABLE_ID)));
    for key in [
        "scenario",
        "frames",
        "lower_bound.time",
        "scene_path",
        "lookahead",
    ] {
        assert!(
            page.contains(&format!("<tr><td>{key}</td>")),
            "summary row {key}"
        );
    }
    // The section-9 table compares the relations (about 2x at 500 ups, 100 fps).
    assert!(
        page.contains("<table id=\"radii\">")
            && page.contains("166.9667")
            && page.contains("1.992")
    );
    // Deterministic.
    assert_eq!(page, html_of(&input));
}

#[test]
fn a_second_labelled_run_is_one_call() {
    let scene = scene();
    let (bound, greedy, right) = runs(&scene);
    let summary = summary_json(&scene, &greedy, &bound, Some(LOOKAHEAD));
    let input = ReportInput::new(&scene, &bound, &summary)
        .with_run("greedy", &greedy)
        .with_run("optimised", &right);
    let page = html_of(&input);
    assert_eq!(svgs(&page).len(), 5);
    assert!(page.contains("<td>optimised</td><td>max-accel-right</td>"));
    // Each figure has a legend entry for both runs.
    for svg in svgs(&page) {
        assert!(
            svg.contains("greedy") && svg.contains("optimised"),
            "{}",
            &svg[..200]
        );
    }
    // Circling right breaks the lane rule: the corridor marks it.
    let frame = right.first_rule_violation().unwrap_or(0);
    assert!(frame > 0);
    assert!(page.contains(&format!("optimised: rule broken, frame {frame}")));
}

#[test]
fn csv_and_json_trajectories_have_the_columns() {
    let scene = scene();
    let (_, greedy, _) = runs(&scene);
    let mut csv = Vec::new();
    report::write_trajectory_csv(&greedy, &mut csv).unwrap_or_else(|e| panic!("{e}"));
    let text = String::from_utf8(csv).unwrap_or_default();
    let mut lines = text.lines();
    assert_eq!(
        lines.next(),
        Some(report::TRAJECTORY_COLUMNS.join(",").as_str())
    );
    let rows: Vec<&str> = lines.collect();
    assert_eq!(rows.len(), greedy.frames.len() + 1);
    assert!(rows.iter().all(|r| r.split(',').count() == 12));
    let mut js = Vec::new();
    report::write_trajectory_json(&greedy, &mut js).unwrap_or_else(|e| panic!("{e}"));
    let rows: Vec<Value> = serde_json::from_slice(&js).unwrap_or_default();
    assert_eq!(rows.len(), greedy.frames.len() + 1);
    for key in report::TRAJECTORY_COLUMNS {
        assert!(rows[1].get(key).is_some(), "{key}");
    }
}

#[test]
fn hltas_script_parses_back_with_the_frames_and_yaws() {
    let scene = scene();
    let (_, greedy, _) = runs(&scene);
    let mut out = Vec::new();
    report::write_hltas(&greedy, &scene.vars, &scene.name, &mut out)
        .unwrap_or_else(|e| panic!("{e}"));
    let text = String::from_utf8(out).unwrap_or_default();
    let script = HLTAS::from_str(&text).unwrap_or_else(|e| panic!("{e}"));
    let mut yaws = Vec::new();
    for b in script.frame_bulks() {
        assert_eq!(b.frame_time, "0.01");
        let Some(AutoMovement::SetYaw(y)) = b.auto_actions.movement else {
            panic!("frame bulk without a yaw")
        };
        assert!(
            b.movement_keys.left != b.movement_keys.right,
            "one strafe key"
        );
        yaws.extend(std::iter::repeat_n(y, b.frame_count.get() as usize));
    }
    assert_eq!(yaws.len(), greedy.controls.len());
    for (y, c) in yaws.iter().zip(&greedy.controls) {
        assert_eq!(*y, report::hltas::yaw_degrees_f32(c.yaw_rad));
    }
}

#[test]
fn a_result_with_plans_is_rebuilt() {
    let scene = scene();
    let (_, greedy, right) = runs(&scene);
    let dir = Path::new(env!("CARGO_MANIFEST_DIR"));
    let result = serde_json::json!({
        "scene_path": SCENE,
        "controller": "greedy",
        "lookahead": LOOKAHEAD,
        "frames": greedy.crossing.map(|c| c.frames),
        "time": greedy.crossing.map(|c| c.time),
        "plans": [{"label": "optimised", "controls": right.controls}],
    });
    let rebuilt =
        report_cmd::rebuild(&result, "result.json", dir).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(rebuilt.runs.len(), 2);
    assert_eq!(rebuilt.runs[0].1, greedy);
    assert_eq!(rebuilt.runs[1].0, "optimised");
    assert_eq!(rebuilt.runs[1].1.frames, right.frames);
    // A solve result names its own controller: only the plans are rebuilt.
    let mut only_plans = result.clone();
    only_plans["controller"] = Value::from("solve");
    let rebuilt = report_cmd::rebuild(&only_plans, "r.json", dir).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(rebuilt.runs.len(), 1);
    // A recorded frame count the scene no longer gives is refused.
    let mut stale = result;
    stale["frames"] = Value::from(1);
    let e = report_cmd::rebuild(&stale, "r.json", dir)
        .err()
        .map(|e| e.to_string())
        .unwrap_or_default();
    assert!(
        e.contains("r.json: frames: 1") && e.contains("changed"),
        "{e}"
    );
}

#[test]
fn degenerate_inputs_still_draw_five_figures() {
    // No walls at all, a short frame cap the run never finishes in, and a run of no frames.
    let text = r#"
name = "open"
max-frames = 50
[engine]
preset = "goldsrc"
fps = 100
effects = ["air-accel"]
[start]
position = [0, 0]
velocity = [320, 0]
[finish]
a = [5000, -100]
b = [5000, 100]
"#;
    let scene = Scene::from_toml_str(text, "open.toml").unwrap_or_else(|e| panic!("{e}"));
    let sim = Simulation::new(&scene).unwrap_or_else(|e| panic!("{e}"));
    let bound = LowerBound {
        path_length: 5000.0,
        path: vec![scene.start.pos, strafeopt::physics::Vec2::new(5000.0, 0.0)],
        crossing: strafeopt::sim::Crossing::new(40, 0.5, 0.01),
    };
    let left = sim.run(&mut SideStrafer { side: Side::Left });
    assert!(left.crossing.is_none() && left.min_clearance().is_infinite());
    let empty = Trace {
        frames: Vec::new(),
        controls: Vec::new(),
        ..left.clone()
    };
    let summary = serde_json::json!({"note": "no walls"});
    let input = ReportInput::new(&scene, &bound, &summary)
        .with_run("left", &left)
        .with_run("empty", &empty);
    let page = html_of(&input);
    assert_eq!(svgs(&page).len(), 5);
    assert!(page.contains("not reached") && page.contains("no walls"));
    // No runs at all: the figures are drawn with the corridor and the bound alone.
    let page = html_of(&ReportInput::new(&scene, &bound, &summary));
    assert_eq!(svgs(&page).len(), 5);
    // The script of an empty run is refused, not written.
    assert!(report::hltas_script(&empty, &scene.vars, "open").is_err());
}

/// Maximum acceleration on alternating sides, left on odd frames: the velocity zigzags about a straight
/// line (a few degrees left of the start's heading, as the first frame turns left).
struct Alternating;

impl Controller for Alternating {
    fn name(&self) -> String {
        "alternating".to_string()
    }

    fn control(&mut self, frame: u64, s: &PlayerState, sim: &Simulation) -> Control {
        let side = if frame % 2 == 1 {
            Side::Left
        } else {
            Side::Right
        };
        let keys = strafe_keys(sim.scene().vars.side_key_speed);
        max_accel_control(sim.stepper(), s, keys, side, s.vel.angle())
    }
}

#[test]
fn heading_and_turn_rate_of_a_straight_alternating_run_stay_level() {
    let text = r#"
name = "straight"
[engine]
preset = "goldsrc"
fps = 100
effects = ["air-accel", "max-velocity", "walls"]
[lane]
width = 1024
length = 3000
kind = "rule"
"#;
    let scene = Scene::from_toml_str(text, "straight.toml").unwrap_or_else(|e| panic!("{e}"));
    let sim = Simulation::new(&scene).unwrap_or_else(|e| panic!("{e}"));
    let run = sim.run(&mut Alternating);
    assert!(run.feasible(), "the alternating run stays in the lane");
    // The heading zigzags by a few degrees about the lane and does not drift.
    let heading = figures::heading_degrees(&run);
    assert_eq!(heading.len(), run.frames.len() + 1);
    assert!(heading.iter().all(|h| h.1.abs() < 10.0), "{heading:?}");
    // Averaged over the window, the turn rate is near zero; one side alone turns hundreds of degrees a
    // second.
    let rates = figures::turn_rate_deg_per_s(&run);
    assert_eq!(
        rates.len(),
        heading.len() - figures::TURN_RATE_WINDOW_FRAMES
    );
    let worst = rates.iter().map(|r| r.1.abs()).fold(0.0, f64::max);
    assert!(worst < 5.0, "largest turn rate {worst} deg/s");
    let left = sim.run(&mut SideStrafer { side: Side::Left });
    let turning = figures::turn_rate_deg_per_s(&left);
    // 30 ups of turn a frame at 320 ups, 100 fps: about 530 degrees per second, slowing as it speeds up.
    assert!((turning[0].1 - 530.0).abs() < 10.0, "{:?}", &turning[..5]);
    assert!(turning.iter().all(|r| r.1 > 0.0));
}

#[test]
fn heading_and_clearance_of_the_greedy_bend() {
    let scene = scene();
    let (_, greedy, _) = runs(&scene);
    // Into the bend along +x, out of it along +y: a quarter turn to the left.
    let heading = figures::heading_degrees(&greedy);
    let (first, last) = (heading[0].1, heading[heading.len() - 1].1);
    assert!(
        first.abs() < 20.0 && (last - 90.0).abs() < 20.0,
        "{first} -> {last}"
    );
    let rates = figures::turn_rate_deg_per_s(&greedy);
    let mean_rate = rates.iter().map(|r| r.1).sum::<f64>() / rates.len() as f64;
    assert!(mean_rate > 0.0, "turns left on average: {mean_rate}");
    // The clearance series is the start and every frame; its minimum is the run's min clearance (the same
    // values, so exactly equal).
    let clearance = figures::clearance_series(&greedy);
    assert_eq!(clearance.len(), greedy.frames.len() + 1);
    let min = clearance.iter().map(|c| c.1).fold(f64::INFINITY, f64::min);
    assert_eq!(min, greedy.min_clearance());
    assert!(
        (0.0..16.0).contains(&min),
        "greedy hugs the inner corner: {min}"
    );
}
