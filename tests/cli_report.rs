//! `simulate --report`, `simulate --hltas`, `solve --hltas` of a plan with vectorial compensation and
//! `report RESULT.json -o` through the real binary.

use hltas::types::AutoMovement;
use hltas::HLTAS;
use serde_json::Value;
use std::path::{Path, PathBuf};
use std::process::Output;

mod common;
use common::{strafeopt, strafeopt_in};

fn ok(out: &Output, args: &[&str]) {
    assert!(
        out.status.success(),
        "{args:?}: {}",
        String::from_utf8_lossy(&out.stderr)
    );
}

fn json(args: &[&str]) -> Value {
    let out = strafeopt(args);
    ok(&out, args);
    serde_json::from_slice(&out.stdout).unwrap_or_else(|e| panic!("{args:?}: {e}"))
}

fn temp_dir(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!(
        "strafeopt-test-report-{name}-{}",
        std::process::id()
    ));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap_or_else(|e| panic!("{e}"));
    dir
}

fn read(path: &Path) -> String {
    std::fs::read_to_string(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}

fn s(p: &Path) -> String {
    p.to_string_lossy().into_owned()
}

#[test]
fn simulate_report_and_report_command_write_the_same_page() {
    let dir = temp_dir("page");
    let (html, again, result) = (dir.join("a.html"), dir.join("b.html"), dir.join("r.json"));
    let out = strafeopt(&[
        "simulate",
        "scenarios/hl-hairpin-100fps.toml",
        "--json",
        "--report",
        &s(&html),
    ]);
    ok(&out, &[]);
    let v: Value = serde_json::from_slice(&out.stdout).unwrap_or_default();
    let scene_path = v["scene_path"].as_str().unwrap_or_default();
    assert!(
        Path::new(scene_path).is_absolute() && scene_path.ends_with("hl-hairpin-100fps.toml"),
        "{scene_path}"
    );
    std::fs::write(&result, &out.stdout).unwrap_or_else(|e| panic!("{e}"));
    let page = read(&html);
    assert_eq!(
        page.matches("<svg").count(),
        strafeopt::report::html::FIGURE_IDS.len()
    );
    assert!(page.contains("<table id=\"summary\">"));
    // The greedy run breaks the hairpin's rule: marked in the corridor.
    let frame = v["first_rule_violation_frame"].as_u64().unwrap_or(0);
    assert!(page.contains(&format!("greedy: rule broken, frame {frame}")));

    // `report` rebuilds the run from the saved result, from any directory, to the same bytes.
    let out = strafeopt_in(&dir, &["report", "r.json", "-o", "b.html"]);
    ok(&out, &["report"]);
    assert_eq!(
        String::from_utf8_lossy(&out.stdout),
        "report: b.html (1 run)\n"
    );
    assert!(read(&again) == page, "report and simulate --report differ");
    let leftovers = std::fs::read_dir(&dir).map(|d| d.count()).unwrap_or(0);
    assert_eq!(leftovers, 3, "no temporary files left");
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn report_finds_a_relative_scene_beside_the_result() {
    let dir = temp_dir("relative");
    let mut v = json(&[
        "simulate",
        "scenarios/hl-bend90-100fps.toml",
        "--controller",
        "max-accel-left",
        "--json",
    ]);
    let scene = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenarios/hl-bend90-100fps.toml");
    std::fs::copy(&scene, dir.join("bend.toml")).unwrap_or_else(|e| panic!("{e}"));
    v["scene_path"] = Value::from("bend.toml");
    let result = dir.join("r.json");
    std::fs::write(&result, v.to_string()).unwrap_or_else(|e| panic!("{e}"));
    let html = dir.join("out.html");
    let args = ["report", &s(&result), "-o", &s(&html)];
    ok(&strafeopt(&args), &args);
    assert!(read(&html).contains("<td>max-accel-left</td>"));
    let _ = std::fs::remove_dir_all(&dir);
}

fn bad(dir: &Path, args: &[&str], needle: &str) {
    let out = strafeopt_in(dir, args);
    assert_eq!(
        out.status.code(),
        Some(2),
        "{args:?}: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(err.lines().count(), 1, "one line: {err}");
    assert!(
        err.starts_with("strafeopt: ") && err.contains(needle),
        "{args:?}: {err}"
    );
}

#[test]
fn report_refuses_bad_results_in_one_line() {
    let dir = temp_dir("bad");
    let v = json(&["simulate", "scenarios/hl-bend90-100fps.toml", "--json"]);
    let write = |name: &str, text: String| {
        std::fs::write(dir.join(name), text).unwrap_or_else(|e| panic!("{e}"));
    };
    write("garbage.json", "not json".to_string());
    let mut no_scene = v.clone();
    no_scene.as_object_mut().map(|m| m.remove("scene_path"));
    write("no-scene.json", no_scene.to_string());
    let mut stale = v.clone();
    stale["frames"] = Value::from(3);
    write("stale.json", stale.to_string());
    let mut unknown = v;
    unknown["controller"] = Value::from("magic");
    write("unknown.json", unknown.to_string());
    bad(
        &dir,
        &["report", "missing.json", "-o", "x.html"],
        "missing.json: -: cannot read",
    );
    bad(
        &dir,
        &["report", "garbage.json", "-o", "x.html"],
        "not a JSON result",
    );
    bad(
        &dir,
        &["report", "no-scene.json", "-o", "x.html"],
        "scene_path: missing",
    );
    bad(
        &dir,
        &["report", "stale.json", "-o", "x.html"],
        "frames: 3, but the scene now gives 406",
    );
    bad(
        &dir,
        &["report", "unknown.json", "-o", "x.html"],
        "controller: \"magic\"",
    );
    assert!(!dir.join("x.html").exists());
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn hltas_replays_the_trajectory_yaws() {
    let dir = temp_dir("hltas");
    let (script, traj) = (dir.join("run.hltas"), dir.join("run.json"));
    let v = json(&[
        "simulate",
        "scenarios/hl-bend90-100fps.toml",
        "--json",
        "--hltas",
        &s(&script),
        "--trajectory",
        &s(&traj),
    ]);
    let frames = v["frames"].as_u64().unwrap_or(0) as usize;
    let parsed = HLTAS::from_str(&read(&script)).unwrap_or_else(|e| panic!("{e}"));
    let mut yaws = Vec::new();
    for b in parsed.frame_bulks() {
        assert_eq!(b.frame_time, "0.01", "frame time of 100 fps");
        let Some(AutoMovement::SetYaw(y)) = b.auto_actions.movement else {
            panic!("a frame bulk without a yaw")
        };
        yaws.extend(std::iter::repeat_n(y, b.frame_count.get() as usize));
    }
    assert_eq!(yaws.len(), frames, "one frame per simulated frame");
    let rows: Vec<Value> = serde_json::from_str(&read(&traj)).unwrap_or_default();
    assert_eq!(rows.len(), frames + 1);
    for (row, y) in rows[1..].iter().zip(&yaws) {
        let want = row["yaw"].as_f64().unwrap_or(f64::NAN);
        // The script prints each yaw as an f32 (about 1e-5 degrees here) in [0, 360).
        let diff = (f64::from(*y) - want).rem_euclid(360.0);
        assert!(
            diff.min(360.0 - diff) < 1e-4 && (0.0..360.0).contains(y),
            "frame {}: {y} vs {want}",
            row["frame"]
        );
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// Runs `command` with `--hltas` into a fresh directory (`tag`) and checks it is refused in one line
/// containing `needle`, with no script written.
fn hltas_refused(tag: &str, command: &[&str], needle: &str) {
    let dir = temp_dir(tag);
    let script = s(&dir.join("plan.hltas"));
    let args: Vec<&str> = command
        .iter()
        .copied()
        .chain(["--hltas", &script])
        .collect();
    bad(Path::new(env!("CARGO_MANIFEST_DIR")), &args, needle);
    assert!(!Path::new(&script).exists());
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn hltas_is_refused_for_a_source_scene() {
    hltas_refused(
        "hltas-source",
        &["simulate", "scenarios/hl2-abh-100m.toml"],
        "--hltas",
    );
}

#[test]
fn hltas_is_refused_for_a_plan_with_vectorial_compensation() {
    // The 1000 fps bend asks for vectorial compensation: its plan sets forwardmove and sidemove frame by
    // frame, which a script's frame bulks (keys held at their speeds) cannot carry.
    hltas_refused(
        "hltas-vectorial",
        &[
            "solve",
            "scenarios/hl-bend90-1000fps.toml",
            "--quality",
            "fast",
        ],
        "vectorial compensation",
    );
}
