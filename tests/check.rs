//! `strafeopt check` through the real binary: a pass, a regression (exit 1 naming the figure and by how
//! much), bad input (exit 2), the `--json` document, the `--junit` XML read back, `--update` on copies in a
//! temporary folder, and the shipped `scenarios/` with a corrupted scene or a tightened expectation. Most
//! scenes here use `command = "simulate"` (the greedy strafer, milliseconds) so the tests stay fast.

use std::path::{Path, PathBuf};
use std::process::Output;
use strafeopt::check::update::{round_up, GAP_DECIMALS, TIME_DECIMALS};
use strafeopt::scene::{expectation_from_str, Expectation, ExpectedRun, Scene};

mod common;
use common::{strafeopt, strafeopt_in};

/// The 100 fps bend without expectations (greedy: frame 406, 4.050373 s, gap 1.790%, valid).
const BEND: &str = r#"# A bend for the check tests.
name = "bend"
[engine]
preset = "goldsrc"
fps = 100
effects = ["air-accel", "max-velocity", "walls"]

[bend90]
width = 160
leg1 = 1200
leg2 = 1200
kind = "rule"
"#;

/// The greedy figures of [`BEND`], as `[expect]` lines that hold.
const BEND_GREEDY_EXPECT: &str = r#"
[expect]
command = "simulate"     # the greedy baseline
frames = 406
time = 4.050374
gap-percent = 1.791
valid = true
"#;

fn temp_dir(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("strafeopt-check-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap_or_else(|e| panic!("{e}"));
    dir
}

fn write(path: &Path, text: &str) {
    if let Some(parent) = path.parent() {
        std::fs::create_dir_all(parent).unwrap_or_else(|e| panic!("{e}"));
    }
    std::fs::write(path, text).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
}

fn read(path: &Path) -> String {
    std::fs::read_to_string(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}

fn stdout(out: &Output) -> String {
    String::from_utf8_lossy(&out.stdout).into_owned()
}

fn stderr(out: &Output) -> String {
    String::from_utf8_lossy(&out.stderr).into_owned()
}

fn check_in(dir: &Path, args: &[&str]) -> Output {
    let mut all = vec!["check"];
    all.extend_from_slice(args);
    strafeopt_in(dir, &all)
}

/// The lines of a text check without the wall times (which differ run to run).
fn without_times(text: &str) -> Vec<String> {
    text.lines()
        .map(|l| match l.rfind(" (") {
            Some(i) if l.ends_with(" s)") => l[..i].to_string(),
            _ => l.to_string(),
        })
        .collect()
}

#[test]
fn a_scene_whose_expectations_hold_passes_with_exit_0() {
    let dir = temp_dir("pass");
    write(
        &dir.join("bend.toml"),
        &format!("{BEND}{BEND_GREEDY_EXPECT}"),
    );
    let out = check_in(&dir, &["bend.toml"]);
    let text = stdout(&out);
    assert_eq!(out.status.code(), Some(0), "{text}{}", stderr(&out));
    let lines: Vec<&str> = text.lines().collect();
    assert_eq!(lines.len(), 2, "{text}");
    assert!(
        lines[0].starts_with(
            "pass   bend.toml  simulate greedy: frame 406, 4.050373 s, gap 1.790%, valid"
        ),
        "{text}"
    );
    assert!(
        lines[1].starts_with("check: 1 scene, 1 passed, 0 failed, 0 errors, 0 skipped"),
        "{text}"
    );
}

#[test]
fn a_regression_is_exit_1_naming_each_figure_and_by_how_much() {
    let dir = temp_dir("regression");
    let tight = BEND_GREEDY_EXPECT
        .replace("frames = 406", "frames = 404")
        .replace("time = 4.050374", "time = 4.04\ntime-tolerance = 0.0001")
        .replace("gap-percent = 1.791", "gap-percent = 1.5");
    write(&dir.join("bend.toml"), &format!("{BEND}{tight}"));
    let out = check_in(&dir, &["."]);
    let text = stdout(&out);
    assert_eq!(out.status.code(), Some(1), "{text}{}", stderr(&out));
    assert!(
        text.starts_with("FAIL   ./bend.toml  simulate greedy: "),
        "{text}"
    );
    for needle in [
        "frames 406 > 404 (+2 frames)",
        "time 4.050373 s > 4.04 s + 0.0001 s (+0.010373 s)",
        "gap 1.790% > 1.5% (+0.290 points)",
        "check: 1 scene, 0 passed, 1 failed, 0 errors, 0 skipped",
    ] {
        assert!(text.contains(needle), "{needle:?} not in {text}");
    }
    // Within the tolerance is a pass.
    let loose =
        BEND_GREEDY_EXPECT.replace("time = 4.050374", "time = 4.05\ntime-tolerance = 0.0004");
    write(&dir.join("bend.toml"), &format!("{BEND}{loose}"));
    let out = check_in(&dir, &["."]);
    assert_eq!(out.status.code(), Some(0), "{}", stdout(&out));
}

#[test]
fn an_invalid_run_against_valid_true_fails() {
    // The narrow bend's greedy run breaks a lane rule (README, `simulate`).
    let dir = temp_dir("invalid-run");
    let narrow = BEND
        .replace("width = 160", "width = 96")
        .replace("1200", "1500");
    write(
        &dir.join("narrow.toml"),
        &format!("{narrow}\n[expect]\ncommand = \"simulate\"\nvalid = true\n"),
    );
    let out = check_in(&dir, &["narrow.toml"]);
    assert_eq!(out.status.code(), Some(1), "{}", stdout(&out));
    assert!(
        stdout(&out).contains("valid false, expected true"),
        "{}",
        stdout(&out)
    );
}

#[test]
fn bad_expectations_are_bad_input_with_their_line() {
    let dir = temp_dir("bad-expect");
    let cases = [
        (
            "quality",
            "[expect]\nquality = \"fastest\"\n",
            "expect.quality: unknown variant `fastest`",
        ),
        (
            "tolerance",
            "[expect]\ntime = 4.1\ntime-tolerance = -0.5\n",
            "expect.time-tolerance: got -0.5; must be a finite number of seconds of at least 0",
        ),
        (
            "unknown",
            "[expect]\nframes = 400\nframe = 3\n",
            "expect.frame: unknown field `frame`",
        ),
        (
            "status",
            "[expect]\nstatus = \"fine\"\n",
            "expect.status: unknown status \"fine\"",
        ),
        (
            "controller",
            "[expect]\ncommand = \"solve\"\ncontroller = \"greedy\"\n",
            "expect.controller: only with command = \"simulate\"",
        ),
        (
            "refusal",
            "[expect]\nerror = \"x\"\nframes = 3\n",
            "expect.frames: an expected refusal (expect.error) takes no other key",
        ),
    ];
    let first_expect_line = BEND.lines().count() + 2;
    for (name, expect, message) in cases {
        let file = format!("{name}.toml");
        write(&dir.join(&file), &format!("{BEND}\n{expect}"));
        let out = check_in(&dir, &[file.as_str()]);
        let text = stdout(&out);
        assert_eq!(out.status.code(), Some(2), "{name}: {text}");
        assert!(
            text.starts_with(&format!("ERROR  {file}  {file}:")),
            "{name}: {text}"
        );
        assert!(text.contains(message), "{name}: {message:?} not in {text}");
        assert!(
            text.contains("0 passed, 0 failed, 1 error,"),
            "{name}: {text}"
        );
        // The scene reader refuses the same table with the same located message (`solve` sees it).
        let err = Scene::from_toml_str(&format!("{BEND}\n{expect}"), &file)
            .err()
            .map(|e| e.to_string())
            .unwrap_or_default();
        assert!(err.contains(message), "{name}: {err}");
        let line: usize = err
            .split(':')
            .nth(1)
            .and_then(|l| l.parse().ok())
            .unwrap_or_else(|| panic!("{err}"));
        assert!(line >= first_expect_line, "{name}: {err}");
    }
    // A path that does not exist, and a folder with no expectations, are bad input before anything runs.
    let out = check_in(&dir, &["no-such-folder"]);
    assert_eq!(out.status.code(), Some(2));
    assert!(
        stderr(&out).starts_with("strafeopt: no-such-folder: -: cannot read"),
        "{}",
        stderr(&out)
    );
    let empty = dir.join("empty");
    write(&empty.join("plain.toml"), BEND);
    let out = check_in(&empty, &["."]);
    assert_eq!(out.status.code(), Some(2), "{}", stdout(&out));
    assert!(
        stdout(&out).contains("skip   ./plain.toml  no [expect] table"),
        "{}",
        stdout(&out)
    );
    assert!(
        stderr(&out).contains("nothing to check"),
        "{}",
        stderr(&out)
    );
    let out = check_in(&dir, &["--jobs", "0", "."]);
    assert_eq!(out.status.code(), Some(2), "{}", stderr(&out));
}

#[test]
fn expectations_read_alone_even_from_a_refused_scene() {
    let text = "[engine]\npreset = \"goldsrc\"\nfps = \"fast\"\n[expect]\nerror = \"engine.fps\"\n";
    assert!(Scene::from_toml_str(text, "x.toml").is_err());
    assert_eq!(
        expectation_from_str(text, "x.toml").ok().flatten(),
        Some(Expectation::Refused {
            message_contains: "engine.fps".to_string()
        })
    );
    match expectation_from_str(&format!("{BEND}{BEND_GREEDY_EXPECT}"), "b.toml") {
        Ok(Some(Expectation::Runs { run, limits })) => {
            assert!(matches!(run, ExpectedRun::Simulate(_)));
            assert_eq!(limits.frames, Some(406));
            assert_eq!(limits.time_tolerance_s, 0.0);
        }
        other => panic!("{other:?}"),
    }
    assert_eq!(expectation_from_str(BEND, "b.toml").ok(), Some(None));
}

#[test]
fn refusals_pass_with_their_message_and_fail_when_the_scene_loads() {
    let dir = temp_dir("refusal");
    let bad = BEND.replace("fps = 100", "fps = -1");
    write(
        &dir.join("a-refused.toml"),
        &format!("{bad}\n[expect]\nerror = \"engine.fps: got -1\"\n"),
    );
    write(
        &dir.join("b-accepted.toml"),
        &format!("{BEND}\n[expect]\nerror = \"engine.fps\"\n"),
    );
    write(
        &dir.join("c-other-message.toml"),
        &format!("{bad}\n[expect]\nerror = \"walls[0]\"\n"),
    );
    let out = check_in(&dir, &["."]);
    let text = stdout(&out);
    assert_eq!(out.status.code(), Some(1), "{text}");
    let lines = without_times(&text);
    assert!(
        lines[0].starts_with("pass   ./a-refused.toml  refused: engine.fps: got -1; must be"),
        "{text}"
    );
    assert!(
        lines[1].starts_with("FAIL   ./b-accepted.toml  refused: the scene was accepted"),
        "{text}"
    );
    assert!(
        lines[2].starts_with(
            "FAIL   ./c-other-message.toml  refused: refused with \"engine.fps: got -1;"
        ),
        "{text}"
    );
    assert!(text.contains("1 passed, 2 failed, 0 errors"), "{text}");
    // --update sets the refusal that changed; the scene that loads stays a failure.
    let out = check_in(&dir, &["--update", "."]);
    assert_eq!(out.status.code(), Some(1), "{}", stdout(&out));
    assert!(
        stdout(&out).contains("2 passed, 1 failed, 0 errors, 0 skipped, 1 updated"),
        "{}",
        stdout(&out)
    );
    let other = read(&dir.join("c-other-message.toml"));
    assert!(
        other.ends_with("error = \"engine.fps: got -1; must be a finite number above 0\"\n"),
        "{other}"
    );
    assert_eq!(
        read(&dir.join("b-accepted.toml")),
        format!("{BEND}\n[expect]\nerror = \"engine.fps\"\n")
    );
}

#[test]
fn json_document_has_every_scene_and_the_summary() {
    let dir = temp_dir("json");
    write(&dir.join("a.toml"), &format!("{BEND}{BEND_GREEDY_EXPECT}"));
    write(
        &dir.join("b.toml"),
        &format!(
            "{BEND}{}",
            BEND_GREEDY_EXPECT.replace("frames = 406", "frames = 400")
        ),
    );
    write(&dir.join("c.toml"), BEND);
    let out = check_in(&dir, &["--json", "."]);
    assert_eq!(out.status.code(), Some(1), "{}", stderr(&out));
    let doc: serde_json::Value =
        serde_json::from_slice(&out.stdout).unwrap_or_else(|e| panic!("{e}: {}", stdout(&out)));
    assert_eq!(doc["result"], "regression");
    assert_eq!(
        doc["summary"],
        serde_json::json!({"scenes": 3, "passed": 1, "failed": 1, "errors": 0, "skipped": 1, "updated": 0})
    );
    let scenes = doc["scenes"].as_array().cloned().unwrap_or_default();
    let verdicts: Vec<&str> = scenes
        .iter()
        .filter_map(|s| s["verdict"].as_str())
        .collect();
    assert_eq!(verdicts, ["pass", "fail", "skipped"]);
    assert_eq!(scenes[0]["path"], "./a.toml");
    assert_eq!(scenes[0]["run"], "simulate greedy");
    assert_eq!(scenes[0]["measured"]["frames"], 406);
    assert_eq!(scenes[0]["measured"]["valid"], true);
    assert!(scenes[0]["measured"]["engine_exact_valid"].is_null());
    let failure = &scenes[1]["failures"][0];
    assert_eq!(failure["figure"], "frames");
    assert_eq!(failure["limit"], 400);
    assert_eq!(failure["actual"], 406);
    assert_eq!(failure["excess"], 6.0);
    assert_eq!(scenes[2]["message"], "no [expect] table");
}

#[test]
fn junit_xml_parses_back_with_the_right_counts() {
    let dir = temp_dir("junit");
    write(
        &dir.join("s/a-pass.toml"),
        &format!("{BEND}{BEND_GREEDY_EXPECT}"),
    );
    write(
        &dir.join("s/b-fail.toml"),
        &format!(
            "{BEND}{}",
            BEND_GREEDY_EXPECT.replace("frames = 406", "frames = 405")
        ),
    );
    write(
        &dir.join("s/c-error <&>.toml"),
        &format!("{BEND}\n[expect]\nquality = \"best\"\n"),
    );
    write(&dir.join("s/d-skip.toml"), BEND);
    let out = check_in(&dir, &["s", "--junit", "out.xml"]);
    assert_eq!(out.status.code(), Some(2), "{}", stdout(&out));
    let xml = read(&dir.join("out.xml"));
    let doc = roxmltree::Document::parse(&xml).unwrap_or_else(|e| panic!("{e}: {xml}"));
    let root = doc.root_element();
    assert_eq!(root.tag_name().name(), "testsuites");
    let suite = root
        .children()
        .find(|n| n.has_tag_name("testsuite"))
        .unwrap_or_else(|| panic!("{xml}"));
    for node in [root, suite] {
        assert_eq!(node.attribute("tests"), Some("4"), "{xml}");
        assert_eq!(node.attribute("failures"), Some("1"), "{xml}");
        assert_eq!(node.attribute("errors"), Some("1"), "{xml}");
        assert_eq!(node.attribute("skipped"), Some("1"), "{xml}");
    }
    let cases: Vec<_> = suite
        .children()
        .filter(|n| n.has_tag_name("testcase"))
        .collect();
    let names: Vec<&str> = cases.iter().filter_map(|c| c.attribute("name")).collect();
    assert_eq!(
        names,
        [
            "a-pass.toml",
            "b-fail.toml",
            "c-error <&>.toml",
            "d-skip.toml"
        ]
    );
    let child = |i: usize, tag: &str| cases[i].children().find(|n| n.has_tag_name(tag));
    assert!(child(0, "failure").is_none() && child(0, "error").is_none());
    assert_eq!(
        child(1, "failure").and_then(|f| f.attribute("message")),
        Some("frames 406 > 405 (+1 frame)")
    );
    assert!(child(2, "error")
        .and_then(|f| f.attribute("message"))
        .is_some_and(|m| m.contains("expect.quality: unknown variant `best`")));
    assert!(child(3, "skipped").is_some());
    assert!(cases.iter().all(|c| c.attribute("classname") == Some("s")));
}

#[test]
fn output_order_is_the_path_order_whatever_the_jobs() {
    let dir = temp_dir("jobs");
    for name in ["d", "a", "c/b", "b", "c/a"] {
        write(
            &dir.join(format!("{name}.toml")),
            &format!("{BEND}{BEND_GREEDY_EXPECT}"),
        );
    }
    let one = check_in(&dir, &["--jobs", "1", "."]);
    let three = check_in(&dir, &["--jobs", "3", ".", "a.toml"]);
    assert_eq!(one.status.code(), Some(0));
    let lines = without_times(&stdout(&one));
    let paths: Vec<&str> = lines
        .iter()
        .filter_map(|l| l.strip_prefix("pass   "))
        .filter_map(|l| l.split("  ").next())
        .collect();
    assert_eq!(
        paths,
        [
            "./a.toml",
            "./b.toml",
            "./c/a.toml",
            "./c/b.toml",
            "./d.toml"
        ]
    );
    // A file named twice (as `./a.toml` in the folder and `a.toml` by name) is two paths, each checked.
    let three_lines = without_times(&stdout(&three));
    assert_eq!(three_lines.len(), lines.len() + 1, "{three_lines:?}");
    assert_eq!(&three_lines[..5], &lines[..5]);
}

#[test]
fn update_rewrites_only_the_values_keeps_comments_and_is_idempotent() {
    let dir = temp_dir("update");
    let stale = r#"
# Expectations of the bend (this comment stays).
[expect]
command = "simulate"     # the greedy baseline
frames = 404             # tightened by hand
time = 4.2
time-tolerance = 1e-6    # kept
valid = true
"#;
    let path = dir.join("bend.toml");
    write(&path, &format!("{BEND}{stale}"));
    write(
        &dir.join("fresh.toml"),
        &format!("{BEND}\n[expect]\ncommand = \"simulate\"\n"),
    );
    let out = check_in(&dir, &["--update", "."]);
    let text = stdout(&out);
    assert_eq!(out.status.code(), Some(0), "{text}{}", stderr(&out));
    assert!(text.contains("[expect] frames: 404 -> 406"), "{text}");
    assert!(text.contains("[expect] time: 4.2 -> 4.050374"), "{text}");
    assert!(
        text.contains("[expect] gap-percent: (none) -> 1.791"),
        "{text}"
    );
    assert!(
        text.contains("2 passed, 0 failed, 0 errors, 0 skipped, 2 updated"),
        "{text}"
    );
    let expected = format!(
        "{BEND}{}",
        stale
            .replace("frames = 404 ", "frames = 406 ")
            .replace("time = 4.2\n", "time = 4.050374\n")
    );
    assert_eq!(read(&path), expected);
    let fresh = read(&dir.join("fresh.toml"));
    assert!(
        fresh.ends_with(
            "[expect]\ncommand = \"simulate\"\nframes = 406\ntime = 4.050374\ngap-percent = 1.791\nvalid = true\n"
        ),
        "{fresh}"
    );
    // The rewritten expectations pass, and a second update changes nothing.
    let again = check_in(&dir, &["--update", "."]);
    assert_eq!(again.status.code(), Some(0));
    assert!(!stdout(&again).contains("->"), "{}", stdout(&again));
    assert!(
        stdout(&again).contains("2 passed, 0 failed"),
        "{}",
        stdout(&again)
    );
    assert_eq!(read(&path), expected);
    assert_eq!(read(&dir.join("fresh.toml")), fresh);
    // No temporary file is left beside them.
    let left: Vec<_> = std::fs::read_dir(&dir)
        .map(|d| d.filter_map(|e| e.ok()).map(|e| e.file_name()).collect())
        .unwrap_or_default();
    assert_eq!(left.len(), 2, "{left:?}");
}

#[test]
fn written_figures_are_rounded_up_and_never_below_the_result() {
    for value in [
        4.0503731,
        4.001483,
        0.1 + 0.2,
        1e-9,
        5.5076,
        123.4567891,
        3.1736359,
        1.5205,
    ] {
        for decimals in [TIME_DECIMALS, GAP_DECIMALS] {
            let r = round_up(value, decimals);
            let step = 10f64.powi(-decimals);
            assert!(
                r >= value && r - value < step * 1.000001,
                "{value} {decimals} {r}"
            );
            // Written as a decimal of at most that many places.
            let written = r.to_string();
            let places = written.split('.').nth(1).map_or(0, str::len);
            assert!(places <= decimals as usize, "{value} {decimals} {written}");
        }
    }
    assert_eq!(round_up(4.0503731, TIME_DECIMALS).to_string(), "4.050374");
    assert_eq!(round_up(3.1736359, TIME_DECIMALS).to_string(), "3.173636");
    assert_eq!(round_up(4.0, TIME_DECIMALS).to_string(), "4");
}

#[test]
fn shipped_scenarios_carry_expectations_and_invalid_ones_are_refused_as_expected() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenarios");
    let files = strafeopt::check::scene_files(&[root]).unwrap_or_else(|e| panic!("{e}"));
    assert!(files.len() >= 16, "{files:?}");
    for file in &files {
        let text = read(file);
        let expect = expectation_from_str(&text, &file.display().to_string())
            .unwrap_or_else(|e| panic!("{e}"));
        let refused = file.components().any(|c| c.as_os_str() == "invalid");
        match expect {
            Some(Expectation::Refused { .. }) => assert!(refused, "{}", file.display()),
            Some(Expectation::Runs { .. }) => assert!(!refused, "{}", file.display()),
            None => panic!("{} has no [expect] table", file.display()),
        }
    }
    let out = strafeopt(&["check", "scenarios/invalid"]);
    assert_eq!(out.status.code(), Some(0), "{}", stdout(&out));
    assert!(
        stdout(&out).contains("8 passed, 0 failed, 0 errors, 0 skipped"),
        "{}",
        stdout(&out)
    );
}

#[test]
fn a_corrupted_shipped_scene_or_a_tightened_expectation_fails() {
    let dir = temp_dir("shipped");
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenarios");
    let bend = read(&root.join("hl-bend90-100fps.toml"));
    let unknown = read(&root.join("invalid/unknown-key.toml"));
    write(&dir.join("bend.toml"), &bend);
    write(&dir.join("unknown-key.toml"), &unknown);
    let out = check_in(&dir, &["."]);
    assert_eq!(out.status.code(), Some(0), "{}", stdout(&out));

    // One frame tighter than the shipped expectation of the bend.
    let frames_line = bend
        .lines()
        .find(|l| l.starts_with("frames = "))
        .unwrap_or_else(|| panic!("{bend}"));
    let frames: u64 = frames_line["frames = ".len()..]
        .split_whitespace()
        .next()
        .and_then(|n| n.parse().ok())
        .unwrap_or_else(|| panic!("{frames_line}"));
    write(
        &dir.join("bend.toml"),
        &bend.replace(frames_line, &format!("frames = {}", frames - 1)),
    );
    let out = check_in(&dir, &["."]);
    assert_eq!(out.status.code(), Some(1), "{}", stdout(&out));
    assert!(
        stdout(&out).contains(&format!("frames {frames} > {} (+1 frame)", frames - 1)),
        "{}",
        stdout(&out)
    );

    // The bend's corridor corrupted (a start inside a wall): bad input. The invalid scene repaired: it
    // loads, which its expectation refuses.
    write(
        &dir.join("bend.toml"),
        &bend.replace("width = 160", "width = 16"),
    );
    write(
        &dir.join("unknown-key.toml"),
        &unknown.replace("speed = 320", ""),
    );
    let out = check_in(&dir, &["."]);
    let text = stdout(&out);
    assert_eq!(out.status.code(), Some(2), "{text}");
    assert!(
        text.starts_with("ERROR  ./bend.toml  ./bend.toml:"),
        "{text}"
    );
    assert!(
        text.contains("FAIL   ./unknown-key.toml  refused: the scene was accepted"),
        "{text}"
    );
}
