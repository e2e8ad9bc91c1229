//! Exit codes through the real binary (issue 9): 0 success; 2 usage, a bad file or a bad value; 1 an I/O
//! failure writing output; 3 no valid path. Every error is exactly one line on stderr, starting with
//! `strafeopt: `, and nothing on stdout.

use std::ffi::OsStr;
use std::path::{Path, PathBuf};

mod common;
use common::strafeopt;

const SCENE: &str = "scenarios/hl-bend90-100fps.toml";

fn temp_dir(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("strafeopt-exit-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap_or_else(|e| panic!("{e}"));
    dir
}

/// Runs `args`, expecting success: exit 0, nothing on stderr. Returns stdout.
fn ok<S: AsRef<OsStr> + std::fmt::Debug>(args: &[S]) -> String {
    let out = strafeopt(args);
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(0), "{args:?}: {err}");
    assert!(err.is_empty(), "{args:?}: {err}");
    String::from_utf8(out.stdout).unwrap_or_else(|e| panic!("{args:?}: {e}"))
}

/// Runs `args`, expecting failure with `code`: exactly one line on stderr, `strafeopt: ` first, holding
/// every one of `needles`; nothing on stdout. Returns the line.
fn fails<S: AsRef<OsStr> + std::fmt::Debug>(args: &[S], code: i32, needles: &[&str]) -> String {
    let out = strafeopt(args);
    let err = String::from_utf8(out.stderr).unwrap_or_else(|e| panic!("{args:?}: {e}"));
    assert_eq!(out.status.code(), Some(code), "{args:?}: {err}");
    assert!(
        err.ends_with('\n') && err.matches('\n').count() == 1,
        "{args:?}: not one line: {err:?}"
    );
    assert!(
        !err.contains(['\r', '\u{0}', '\u{2028}']),
        "{args:?}: {err:?}"
    );
    assert!(err.starts_with("strafeopt: "), "{args:?}: {err}");
    for needle in needles {
        assert!(err.contains(needle), "{args:?}: {needle:?} not in {err}");
    }
    // One hint at most: clap's own "For more information" is dropped in favour of "(see --help)".
    assert!(!err.contains("For more information"), "{args:?}: {err}");
    assert!(
        out.stdout.is_empty(),
        "{args:?}: stdout {:?}",
        String::from_utf8_lossy(&out.stdout)
    );
    err
}

#[test]
fn success_is_exit_0() {
    let text = ok(&["calc", "frames-to-speed", "--from", "320", "--to", "1000"]);
    assert!(text.contains("frames:             4939"), "{text}");
    let json = ok(&[
        "calc",
        "frames-to-speed",
        "--from",
        "320",
        "--to",
        "1000",
        "--json",
    ]);
    let v: serde_json::Value =
        serde_json::from_str(&json).unwrap_or_else(|e| panic!("{e}: {json}"));
    assert_eq!(v["frames"].as_u64(), Some(4939));
    let text = ok(&["simulate", SCENE, "--lookahead", "300"]);
    assert!(text.contains("run:            valid"), "{text}");
    // Help and version are answers, not errors: stdout, exit 0.
    assert!(ok(&["--help"]).contains("Usage: strafeopt <COMMAND>"));
    assert!(ok(&["simulate", "--help"]).contains("Usage: strafeopt simulate"));
    assert!(ok(&["help", "calc"]).contains("Usage: strafeopt calc"));
    assert!(ok(&["--version"]).starts_with("strafeopt "));
    // Writing a trajectory that can be written.
    let dir = temp_dir("ok");
    let csv = dir.join("run.csv");
    ok(&[
        OsStr::new("simulate"),
        OsStr::new(SCENE),
        OsStr::new("--lookahead"),
        OsStr::new("300"),
        OsStr::new("--trajectory"),
        csv.as_os_str(),
    ]);
    assert!(std::fs::metadata(&csv).is_ok_and(|m| m.len() > 0));
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn usage_errors_are_exit_2() {
    let empty: [&str; 0] = [];
    fails(
        &empty,
        2,
        &[
            "`strafeopt` needs a command: calc, simulate, solve, report",
            "--help",
        ],
    );
    fails(
        &["calc"],
        2,
        &["`strafeopt calc` needs a command: frames-to-speed, max-ground-speed"],
    );
    fails(&["nope"], 2, &["unrecognized subcommand 'nope'"]);
    fails(&["simulate"], 2, &["<SCENE>"]);
    fails(
        &["simulate", "a.toml", "b.toml"],
        2,
        &["unexpected argument 'b.toml'"],
    );
    fails(&["simulate", "--bogus", SCENE], 2, &["--bogus"]);
    fails(
        &["simulate", SCENE, "--lookahead"],
        2,
        &["a value is required for '--lookahead"],
    );
    fails(
        &["simulate", SCENE, "--controller", "nope"],
        2,
        &["'nope'", "--controller"],
    );
    fails(&["calc", "frames-to-speed", "--from"], 2, &["--from"]);
    fails(&["calc", "abh", "--preset", "quake"], 2, &["'quake'"]);
}

#[test]
fn bad_values_are_exit_2() {
    for (value, shown) in [
        ("-5", "-5"),
        ("0", "0"),
        ("nan", "NaN"),
        ("inf", "inf"),
        ("-inf", "-inf"),
    ] {
        fails(
            &["simulate", SCENE, &format!("--lookahead={value}")],
            2,
            &[&format!(
                "--lookahead = {shown}: must be a finite number above 0"
            )],
        );
    }
    // Without `=`, `-inf` reads as short flags; still one line, exit 2.
    fails(
        &["simulate", SCENE, "--lookahead", "-inf"],
        2,
        &["unexpected argument '-i'"],
    );
    fails(
        &["simulate", SCENE, "--lookahead", "abc"],
        2,
        &["invalid value 'abc' for '--lookahead"],
    );
    let calc = ["calc", "frames-to-speed", "--from", "320", "--to", "1000"];
    for (flag, value, words) in [
        ("--fps", "-1", "--fps = -1: must be a finite number above 0"),
        ("--fps", "0", "--fps = 0: must be a finite number above 0"),
        ("--fps", "nan", "--fps = NaN"),
        ("--fps", "inf", "--fps = inf"),
        ("--maxspeed", "0", "--maxspeed = 0"),
        ("--fps", "1e-400", "--fps = 0"),
    ] {
        let mut args = calc.to_vec();
        args.extend([flag, value]);
        fails(&args, 2, &[words]);
    }
    fails(
        &[
            "calc",
            "frames-to-speed",
            "--from",
            "320",
            "--to",
            "99999999",
        ],
        2,
        &["--to = 99999999: must be at most"],
    );
    // Bad values inside a scene file name the file, the line and the key.
    let dir = temp_dir("values");
    for (name, text, words) in [
        (
            "fps.toml",
            "[engine]\npreset = \"goldsrc\"\nfps = -1\neffects = []\n",
            ":3: engine.fps: got -1; must be a finite number above 0",
        ),
        (
            "nan.toml",
            "[engine]\npreset = \"goldsrc\"\nfps = nan\neffects = []\n",
            ":3: engine.fps: got NaN",
        ),
        (
            "width.toml",
            "[engine]\npreset = \"goldsrc\"\nfps = 100\neffects = []\n[lane]\nwidth = 31.9\nlength = 500\nkind = \"rule\"\n",
            ":6: lane.width: got 31.9; must be at least 32",
        ),
        (
            "speed.toml",
            "[engine]\npreset = \"goldsrc\"\nfps = 100\neffects = []\n[lane]\nwidth = 64\nlength = 500\nkind = \"rule\"\n[start]\nvelocity = [1e308, 0]\n",
            ":10: start.velocity: got [1e308, 0]",
        ),
        (
            "key.toml",
            "[engine]\npreset = \"goldsrc\"\nfps = 100\neffects = []\n\"a\\nb\" = 1\n",
            ":5: engine.a\\nb: unknown field",
        ),
    ] {
        let path = dir.join(name);
        std::fs::write(&path, text).unwrap_or_else(|e| panic!("{e}"));
        let line = fails(&[OsStr::new("simulate"), path.as_os_str()], 2, &[words]);
        assert!(line.starts_with(&format!("strafeopt: {}:", path.display())), "{line}");
    }
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn bad_files_are_exit_2() {
    fails(
        &["simulate", "scenarios/no-such-scene.toml"],
        2,
        &["strafeopt: scenarios/no-such-scene.toml: -: cannot read the file"],
    );
    // A directory given as the scene.
    fails(
        &["simulate", "scenarios"],
        2,
        &["strafeopt: scenarios: -: cannot read the file"],
    );
    let dir = temp_dir("files");
    let write = |name: &str, bytes: &[u8]| {
        let p = dir.join(name);
        std::fs::write(&p, bytes).unwrap_or_else(|e| panic!("{e}"));
        p
    };
    let mut binary: Vec<u8> = (0u8..=255).collect();
    binary.extend_from_slice(b"\x00\xff[engine]\x00");
    for (path, words) in [
        // Latin-1 text, not UTF-8.
        (
            write("latin1.toml", b"name = \"caf\xe9\"\n[engine]\n"),
            "cannot read the file",
        ),
        // Binary data.
        (write("binary.toml", &binary), "cannot read the file"),
        // Valid UTF-8 but NUL bytes and a line separator: a TOML error, still one line.
        (write("nul.toml", b"\x00\x00\x00\n"), ":1:"),
        (write("sep.toml", "[engine]\u{2028}\n".as_bytes()), ":1:"),
        // Empty, and a TOML document that is not a scene.
        (write("empty.toml", b""), "missing field `engine`"),
        (
            write("other.toml", b"[package]\nname = \"x\"\n"),
            ":1: package: unknown field `package`",
        ),
        // Truncated in the middle of a table header.
        (
            write(
                "cut.toml",
                b"[engine]\npreset = \"goldsrc\"\nfps = 100\neffects = []\n[lan",
            ),
            ":5:",
        ),
    ] {
        let line = fails(&[OsStr::new("simulate"), path.as_os_str()], 2, &[words]);
        assert!(
            line.starts_with(&format!("strafeopt: {}", path.display())),
            "{line}"
        );
    }
    // A file name holding a line break still gives one line (the name is escaped).
    let odd = dir.join("a\nb.toml");
    fails(
        &[OsStr::new("simulate"), odd.as_os_str()],
        2,
        &["a\\nb.toml", "cannot read the file"],
    );
    // The other commands read their input the same way.
    fails(
        &["solve", "scenarios/no-such-scene.toml"],
        2,
        &["no-such-scene.toml"],
    );
    let out = dir.join("out.html");
    fails(
        &[
            OsStr::new("report"),
            OsStr::new("no-such-result.json"),
            OsStr::new("-o"),
            out.as_os_str(),
        ],
        2,
        &["no-such-result.json"],
    );
    assert!(!out.exists());
    let _ = std::fs::remove_dir_all(&dir);
}

/// Files in `dir` (to find temporary files left behind).
fn listing(dir: &Path) -> Vec<String> {
    let mut names: Vec<String> = std::fs::read_dir(dir)
        .map(|d| {
            d.filter_map(|e| e.ok())
                .map(|e| e.file_name().to_string_lossy().into_owned())
                .collect()
        })
        .unwrap_or_default();
    names.sort();
    names
}

#[test]
fn output_that_cannot_be_written_is_exit_1() {
    for path in ["/nonexistent-dir/x.csv", "/nonexistent-dir/x.json"] {
        fails(
            &[
                "simulate",
                SCENE,
                "--lookahead",
                "300",
                "--trajectory",
                path,
            ],
            1,
            &[&format!("strafeopt: {path}: ")],
        );
    }
    // A directory where the file should go: nothing is left behind beside it.
    let dir = temp_dir("io");
    let target = dir.join("taken");
    std::fs::create_dir_all(&target).unwrap_or_else(|e| panic!("{e}"));
    fails(
        &[
            OsStr::new("simulate"),
            OsStr::new(SCENE),
            OsStr::new("--lookahead"),
            OsStr::new("300"),
            OsStr::new("--trajectory"),
            target.as_os_str(),
        ],
        1,
        &[&target.display().to_string()],
    );
    assert_eq!(listing(&dir), vec!["taken".to_string()]);
    let _ = std::fs::remove_dir_all(&dir);
    // Standard output that refuses the result (a full disk).
    let full = Path::new("/dev/full");
    if full.exists() {
        let dev_full = std::fs::OpenOptions::new()
            .write(true)
            .open(full)
            .unwrap_or_else(|e| panic!("{e}"));
        let out = std::process::Command::new(assert_cmd::cargo::cargo_bin("strafeopt"))
            .current_dir(env!("CARGO_MANIFEST_DIR"))
            .args(["calc", "frames-to-speed", "--from", "320", "--to", "1000"])
            .stdout(dev_full)
            .output()
            .unwrap_or_else(|e| panic!("{e}"));
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(1), "{err}");
        assert_eq!(err.matches('\n').count(), 1, "{err:?}");
        assert!(err.starts_with("strafeopt: writing the output: "), "{err}");
    }
}

#[test]
fn no_valid_path_is_exit_3() {
    // A frame cap too short for even the greedy speed profile to reach the line.
    let dir = temp_dir("nopath");
    let path = dir.join("short.toml");
    std::fs::write(
        &path,
        "max-frames = 3\n[engine]\npreset = \"goldsrc\"\nfps = 100\neffects = [\"air-accel\"]\n\
         [lane]\nwidth = 64\nlength = 2000\nkind = \"rule\"\n",
    )
    .unwrap_or_else(|e| panic!("{e}"));
    fails(
        &[OsStr::new("simulate"), path.as_os_str()],
        3,
        &[
            "strafeopt: no valid path: ",
            "cannot cover 1960.000 units in 3 frames",
        ],
    );
    let _ = std::fs::remove_dir_all(&dir);
}
