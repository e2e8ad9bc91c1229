//! Fuzzing the scene reader and validator (issue 9): any text gives either a [`Scene`] or an [`Error`],
//! never a panic. Every error displays as one line that starts with the origin (the file name) and carries
//! `origin:line` wherever the document locates it; every accepted scene holds only finite numbers, and
//! simulating it (the corridor, the lower bound and one greedy run, capped at a few thousand frames) never
//! panics or produces a NaN.
//!
//! Inputs: (a) arbitrary strings and soups of TOML tokens; (b) every shipped `scenarios/**/*.toml`
//! mutated by byte flips, deletions, insertions of tokens (`=`, `[`, `"`, `nan`, `1e308`, `-0`, ...),
//! duplicated lines (duplicate keys), truncation and numbers replaced by extreme values; (c) well-formed
//! scenes with random and extreme values in every field, which reach the validator's geometry and the
//! simulation far more often than mutations do. Seeds are fixed; the file runs in a few seconds.

use proptest::prelude::*;
use proptest::test_runner::{Config, RngSeed};
use serde_json::Value;
use std::path::Path;
use strafeopt::geometry::{CONTACT_TOL_UNITS, MIN_SEGMENT_LENGTH_UNITS};
use strafeopt::optimise::lower_bound;
use strafeopt::scene::Scene;
use strafeopt::sim::{Greedy, Simulation};
use strafeopt::Error;

/// The name errors must start with.
const ORIGIN: &str = "fuzz/scene.toml";

/// Frame cap of the simulation check.
const MAX_FRAMES: u64 = 2000;

fn config(cases: u32, seed: u64) -> Config {
    Config {
        cases,
        rng_seed: RngSeed::Fixed(seed),
        failure_persistence: None,
        ..Config::default()
    }
}

/// Every shipped scene file, valid and invalid, sorted by path.
fn shipped() -> Vec<String> {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenarios");
    let mut paths = Vec::new();
    for dir in [root.clone(), root.join("invalid")] {
        for entry in std::fs::read_dir(&dir).unwrap_or_else(|e| panic!("{}: {e}", dir.display())) {
            let p = entry.unwrap_or_else(|e| panic!("{e}")).path();
            if p.extension().is_some_and(|x| x == "toml") {
                paths.push(p);
            }
        }
    }
    paths.sort();
    assert!(paths.len() >= 10, "shipped scenes: {paths:?}");
    paths
        .iter()
        .map(|p| std::fs::read_to_string(p).unwrap_or_else(|e| panic!("{}: {e}", p.display())))
        .collect()
}

/// Tokens inserted into scene text: TOML syntax, extreme numbers, keys and tables of scene files, and
/// text that tests the one-line rule (quoted keys holding line breaks).
const TOKENS: &[&str] = &[
    "=",
    "[",
    "]",
    "[[",
    "]]",
    "\"",
    "'",
    "\"\"\"",
    ",",
    ".",
    "{",
    "}",
    "#",
    "\n",
    "\r\n",
    "\r",
    " ",
    "\t",
    "nan",
    "-nan",
    "+nan",
    "inf",
    "-inf",
    "1e308",
    "-1e308",
    "1e309",
    "-0",
    "-0.0",
    "0",
    "5e-324",
    "1e-9",
    "9223372036854775807",
    "18446744073709551616",
    "-9223372036854775808",
    "0x10",
    "1_000",
    "1979-05-27T07:32:00Z",
    "true",
    "false",
    "\u{0}",
    "\u{feff}",
    "\u{2028}",
    "é",
    "[engine]",
    "[start]",
    "[finish]",
    "[[walls]]",
    "[lane]",
    "[bend90]",
    "[hairpin]",
    "fps = 0",
    "fps = 1e-300",
    "fps = 1e300",
    "max-frames = 0",
    "max-frames = 1",
    "kind = \"solid\"",
    "kind = \"rule\"",
    "points = []",
    "points = [[0, 0]]",
    "points = [[0, 0], [0, 0]]",
    "points = [[0, 0], [1e308, 1e308]]",
    "closed = true",
    "width = 32",
    "width = 1e308",
    "length = 1e308",
    "position = [0, 0]",
    "position = [1e308, -1e308]",
    "velocity = [1e308, 1e308]",
    "velocity = [-0, 5e-324]",
    "on-ground = true",
    "ducked = true",
    "effects = []",
    "accelerate = 1e308",
    "airaccelerate = -1e308",
    "maxvelocity = 5e-324",
    "maxspeed = 1e308",
    "gravity = 1e308",
    "entity-friction = -1e308",
    "\"a\\nb\" = 1",
    "\"a\\rb\" = 1",
    "\"\\u2028\" = 1",
    "'x' = 'y'",
    "a.b.c = 1",
];

/// Values that replace a number of a scene file.
const EXTREMES: &[&str] = &[
    "nan",
    "inf",
    "-inf",
    "1e308",
    "-1e308",
    "1.7976931348623157e308",
    "5e-324",
    "-0",
    "-0.0",
    "0",
    "1e-9",
    "1e-300",
    "-1",
    "31.999999999",
    "32",
    "4294967296",
    "18446744073709551615",
    "1e20",
    "2000",
    "0.000000001",
];

/// One edit of a scene file. Positions are fractions of the current length, so every edit applies.
#[derive(Clone, Debug)]
enum Mutation {
    FlipBit { at: f64, bit: u8 },
    Delete { at: f64, len: usize },
    Insert { at: f64, token: usize },
    DuplicateLine { at: f64 },
    SwapLines { a: f64, b: f64 },
    Truncate { at: f64 },
    ReplaceNumber { which: usize, value: usize },
}

fn mutation() -> impl Strategy<Value = Mutation> {
    let at = 0.0..1.0f64;
    prop_oneof![
        1 => (at.clone(), 0u8..8).prop_map(|(at, bit)| Mutation::FlipBit { at, bit }),
        1 => (at.clone(), 1usize..24).prop_map(|(at, len)| Mutation::Delete { at, len }),
        3 => (at.clone(), 0..TOKENS.len()).prop_map(|(at, token)| Mutation::Insert { at, token }),
        1 => at.clone().prop_map(|at| Mutation::DuplicateLine { at }),
        1 => (at.clone(), at.clone()).prop_map(|(a, b)| Mutation::SwapLines { a, b }),
        1 => at.prop_map(|at| Mutation::Truncate { at }),
        4 => (0usize..64, 0..EXTREMES.len())
            .prop_map(|(which, value)| Mutation::ReplaceNumber { which, value }),
    ]
}

fn index(at: f64, len: usize) -> usize {
    ((at * len as f64) as usize).min(len)
}

/// Byte ranges of the numbers in `text` (a digit run with its sign, point and exponent).
fn numbers(text: &[u8]) -> Vec<(usize, usize)> {
    let mut out = Vec::new();
    let mut i = 0;
    while i < text.len() {
        let starts = text[i].is_ascii_digit()
            || (text[i] == b'-' && text.get(i + 1).is_some_and(u8::is_ascii_digit));
        let after_word = i > 0 && (text[i - 1].is_ascii_alphanumeric() || text[i - 1] == b'-');
        if starts && !after_word {
            let mut j = i + 1;
            while j < text.len()
                && (text[j].is_ascii_digit()
                    || matches!(text[j], b'.' | b'e' | b'E' | b'_')
                    || (matches!(text[j], b'+' | b'-') && matches!(text[j - 1], b'e' | b'E')))
            {
                j += 1;
            }
            out.push((i, j));
            i = j;
        } else {
            i += 1;
        }
    }
    out
}

fn line_spans(text: &[u8]) -> Vec<(usize, usize)> {
    let mut spans = Vec::new();
    let mut start = 0;
    for (i, &b) in text.iter().enumerate() {
        if b == b'\n' {
            spans.push((start, i + 1));
            start = i + 1;
        }
    }
    if start < text.len() {
        spans.push((start, text.len()));
    }
    spans
}

fn apply(text: &mut Vec<u8>, m: &Mutation) {
    match *m {
        Mutation::FlipBit { at, bit } => {
            if !text.is_empty() {
                let i = index(at, text.len() - 1);
                text[i] ^= 1 << bit;
            }
        }
        Mutation::Delete { at, len } => {
            let i = index(at, text.len());
            let j = (i + len).min(text.len());
            text.drain(i..j);
        }
        Mutation::Insert { at, token } => {
            let i = index(at, text.len());
            text.splice(i..i, TOKENS[token].bytes());
        }
        Mutation::DuplicateLine { at } => {
            let lines = line_spans(text);
            if !lines.is_empty() {
                let (s, e) = lines[index(at, lines.len() - 1)];
                let mut line = text[s..e].to_vec();
                if line.last() != Some(&b'\n') {
                    line.insert(0, b'\n');
                }
                text.splice(e..e, line);
            }
        }
        Mutation::SwapLines { a, b } => {
            let lines = line_spans(text);
            if lines.len() >= 2 {
                let (i, j) = (index(a, lines.len() - 1), index(b, lines.len() - 1));
                let (i, j) = (i.min(j), i.max(j));
                if i != j {
                    let (li, lj) = (lines[i], lines[j]);
                    let mut out = text[..li.0].to_vec();
                    out.extend_from_slice(&text[lj.0..lj.1]);
                    out.extend_from_slice(&text[li.1..lj.0]);
                    out.extend_from_slice(&text[li.0..li.1]);
                    out.extend_from_slice(&text[lj.1..]);
                    *text = out;
                }
            }
        }
        Mutation::Truncate { at } => {
            let i = index(at, text.len());
            text.truncate(i);
        }
        Mutation::ReplaceNumber { which, value } => {
            let nums = numbers(text);
            if !nums.is_empty() {
                let (s, e) = nums[which % nums.len()];
                text.splice(s..e, EXTREMES[value].bytes());
            }
        }
    }
}

// ---------------------------------------------------------------------------------------------------------
// The invariants.

/// The first component of an error key: `walls[2].points` -> `walls`, `engine.fps` -> `engine`.
fn top_key(key: &str) -> &str {
    key.split(['.', '[']).next().unwrap_or(key)
}

/// Checks an error for `text`: a scene error, one line, starting with the origin, with a line number
/// within the text wherever the document locates the fault (a syntax error, or a key whose table or
/// top-level key is in the file).
fn check_error(text: &str, e: &Error) -> Result<(), TestCaseError> {
    let shown = e.to_string();
    prop_assert!(
        !shown.contains(['\n', '\r', '\u{2028}', '\u{2029}', '\u{85}', '\u{b}', '\u{c}']),
        "not one line: {shown:?}"
    );
    prop_assert!(shown.starts_with(ORIGIN), "{shown:?}");
    let Error::Scene {
        location,
        key,
        message,
    } = e
    else {
        return Err(TestCaseError::fail(format!("not a scene error: {e:?}")));
    };
    prop_assert!(!key.is_empty() && !message.trim().is_empty(), "{shown:?}");
    let line = match location.strip_prefix(ORIGIN) {
        Some("") => None,
        Some(rest) => {
            let n = rest
                .strip_prefix(':')
                .and_then(|n| n.parse::<usize>().ok())
                .ok_or_else(|| TestCaseError::fail(format!("bad location: {shown:?}")))?;
            Some(n)
        }
        None => return Err(TestCaseError::fail(format!("bad location: {shown:?}"))),
    };
    if let Some(n) = line {
        let lines = text.split('\n').count();
        prop_assert!((1..=lines).contains(&n), "line {n} of {lines}: {shown:?}");
    }
    // Does the document parse (as TOML, whatever its keys), and is the key's top-level key in it?
    let expects_line = match toml::de::DeTable::parse(text) {
        Err(_) => true,
        Ok(doc) => {
            key != "-"
                && doc
                    .get_ref()
                    .iter()
                    .any(|(k, _)| **k.get_ref() == *top_key(key))
        }
    };
    if expects_line {
        prop_assert!(line.is_some(), "no line number: {shown:?}\n---\n{text}");
    }
    Ok(())
}

/// Every number of the value is finite (a NaN or infinity serialises as `null`; a scene has no optional
/// fields, so any `null` is one).
fn finite_json(v: &Value, at: &str) -> Result<(), String> {
    match v {
        Value::Null => Err(format!("{at} is not finite")),
        Value::Number(n) => match n.as_f64() {
            Some(x) if x.is_finite() => Ok(()),
            _ => Err(format!("{at} = {n}")),
        },
        Value::Array(items) => items
            .iter()
            .enumerate()
            .try_for_each(|(i, x)| finite_json(x, &format!("{at}[{i}]"))),
        Value::Object(map) => map
            .iter()
            .try_for_each(|(k, x)| finite_json(x, &format!("{at}.{k}"))),
        Value::Bool(_) | Value::String(_) => Ok(()),
    }
}

/// Checks an accepted scene: finite numbers, usable walls and finish, a start clear of the walls; then
/// the corridor, the lower bound and one greedy run of at most [`MAX_FRAMES`] frames, without NaN.
fn check_scene(scene: &Scene) -> Result<(), TestCaseError> {
    let json = serde_json::to_value(scene).map_err(|e| TestCaseError::fail(e.to_string()))?;
    finite_json(&json, "scene").map_err(|e| TestCaseError::fail(format!("{e}: {scene:?}")))?;
    let tau = scene.frame_time_s();
    prop_assert!(tau.is_finite() && tau > 0.0, "tau {tau}");
    prop_assert!(scene.max_frames >= 1);
    prop_assert!(scene.finish.length_units() > MIN_SEGMENT_LENGTH_UNITS);
    for w in &scene.walls {
        prop_assert!(w.defect().is_none(), "{w:?}");
    }
    let corridor = scene
        .corridor()
        .map_err(|e| TestCaseError::fail(format!("accepted scene, bad corridor: {e}")))?;
    prop_assert!(corridor.clearance(scene.start.pos) >= -CONTACT_TOL_UNITS);
    let (path_length, path) = corridor
        .shortest_path(scene.start.pos, (scene.finish.a, scene.finish.b))
        .ok_or_else(|| TestCaseError::fail("accepted scene without a path"))?;
    prop_assert!(
        path_length.is_finite() && path_length >= 0.0,
        "{path_length}"
    );
    prop_assert!(path.iter().all(|p| p.is_finite()), "{path:?}");

    let mut capped = scene.clone();
    capped.max_frames = capped.max_frames.min(MAX_FRAMES);
    let sim = Simulation::new(&capped).map_err(|e| TestCaseError::fail(e.to_string()))?;
    match lower_bound(&capped, sim.corridor()) {
        Ok(b) => {
            prop_assert!(b.path_length.is_finite() && b.path_length >= 0.0);
            prop_assert!(
                b.crossing.time.is_finite() && b.crossing.time >= 0.0,
                "{b:?}"
            );
            prop_assert!((0.0..=1.0).contains(&b.crossing.fraction), "{b:?}");
        }
        Err(e @ Error::NoValidPath(_)) => {
            prop_assert!(!e.to_string().contains('\n'), "{e}");
        }
        Err(e) => return Err(TestCaseError::fail(format!("lower bound: {e:?}"))),
    }
    let trace = sim.run(&mut Greedy::new(path, 300.0));
    prop_assert!(trace.frames.len() as u64 <= MAX_FRAMES);
    for f in std::iter::once(&trace.start).chain(&trace.frames) {
        let numbers = [
            f.time,
            f.pos.x,
            f.pos.y,
            f.vel.x,
            f.vel.y,
            f.speed,
            f.yaw_rad,
            f.theta_rad,
            f.clearance,
        ];
        prop_assert!(
            numbers.iter().all(|x| !x.is_nan()),
            "NaN in frame {}: {f:?}\n{scene:?}",
            f.frame
        );
    }
    prop_assert!(
        !trace.numerical_failure,
        "numerical failure: {:?}\n{scene:?}",
        trace.frames.last()
    );
    if let Some(c) = trace.crossing {
        prop_assert!(
            c.time.is_finite() && (0.0..=1.0).contains(&c.fraction),
            "{c:?}"
        );
    }
    Ok(())
}

/// Reads `text` and checks whichever comes out. Returns whether it was accepted.
fn check_text(text: &str) -> Result<bool, TestCaseError> {
    match Scene::from_toml_str(text, ORIGIN) {
        Ok(scene) => check_scene(&scene).map(|()| true),
        Err(e) => check_error(text, &e).map(|()| false),
    }
}

/// Reads bytes as a file reader would: text when it is UTF-8; otherwise the lossy text (the CLI refuses
/// such a file before reading it, see `tests/cli_exit_codes.rs`).
fn check_bytes(bytes: &[u8]) -> Result<bool, TestCaseError> {
    check_text(&String::from_utf8_lossy(bytes))
}

// ---------------------------------------------------------------------------------------------------------
// (c) Well-formed scenes with random and extreme values.

/// Extreme values for the well-formed scenes.
const EXTREME_F64: &[f64] = &[
    f64::NAN,
    f64::INFINITY,
    f64::NEG_INFINITY,
    f64::MAX,
    -f64::MAX,
    1e308,
    1e20,
    5e-324,
    1e-300,
    -0.0,
    0.0,
    1e-9,
    -1.0,
];

/// Extreme values for movement variables: all but the huge finite ones, which overflow a run whatever the
/// scene (see `known_overflowing_scenes`).
const EXTREME_VARS: &[f64] = &[
    f64::NAN,
    f64::INFINITY,
    f64::NEG_INFINITY,
    1e20,
    5e-324,
    1e-300,
    -0.0,
    0.0,
    1e-9,
    -1.0,
];

/// A movement variable: usually in `lo..hi`, sometimes extreme.
fn var(lo: f64, hi: f64) -> impl Strategy<Value = f64> {
    prop_oneof![
        12 => lo..hi,
        1 => (0..EXTREME_VARS.len()).prop_map(|i| EXTREME_VARS[i]),
    ]
}

/// A number: usually in `lo..hi`, sometimes extreme.
fn num(lo: f64, hi: f64) -> impl Strategy<Value = f64> {
    prop_oneof![
        12 => lo..hi,
        1 => (0..EXTREME_F64.len()).prop_map(|i| EXTREME_F64[i]),
    ]
}

/// `x` as a TOML float.
fn toml_f64(x: f64) -> String {
    if x.is_nan() {
        "nan".to_string()
    } else if x.is_infinite() {
        if x > 0.0 { "inf" } else { "-inf" }.to_string()
    } else {
        format!("{x:?}")
    }
}

fn point(lo: f64, hi: f64) -> impl Strategy<Value = String> {
    (num(lo, hi), num(lo, hi)).prop_map(|(x, y)| format!("[{}, {}]", toml_f64(x), toml_f64(y)))
}

const EFFECTS: &[&str] = &[
    "air-accel",
    "ground-accel",
    "friction",
    "edge-friction",
    "gravity",
    "jump",
    "bhop-cap",
    "jump-boost",
    "duck",
    "max-velocity",
    "walls",
];

/// Effect lists the shipped scenes use, and any subset.
fn effects() -> impl Strategy<Value = Vec<&'static str>> {
    let sets: [&[&'static str]; 5] = [
        &["air-accel", "max-velocity", "walls"],
        &["air-accel"],
        &["ground-accel", "friction", "max-velocity", "walls"],
        &[
            "air-accel",
            "ground-accel",
            "friction",
            "edge-friction",
            "gravity",
            "jump",
            "bhop-cap",
            "max-velocity",
            "walls",
        ],
        &[
            "air-accel",
            "ground-accel",
            "friction",
            "gravity",
            "jump",
            "jump-boost",
            "duck",
            "max-velocity",
            "walls",
        ],
    ];
    prop_oneof![
        4 => (0..sets.len()).prop_map(move |i| sets[i].to_vec()),
        1 => proptest::collection::vec(0..EFFECTS.len(), 0..8).prop_map(|fx| {
            let mut fx: Vec<&str> = fx.into_iter().map(|i| EFFECTS[i]).collect();
            // The jump boost without the velocity clamp doubles the speed every hop until it overflows
            // (see `known_overflowing_scenes`).
            if fx.contains(&"jump-boost") {
                fx.push("max-velocity");
            }
            fx.sort_unstable();
            fx.dedup();
            fx
        }),
    ]
}

const ENGINE_KEYS: &[&str] = &[
    "maxspeed",
    "accelerate",
    "airaccelerate",
    "friction",
    "edgefriction",
    "entity-friction",
    "stopspeed",
    "maxvelocity",
    "gravity",
    "air-speed-cap",
    "forward-key-speed",
    "side-key-speed",
    "duck-multiplier",
];

fn template_scene() -> impl Strategy<Value = String> {
    let engine = (
        prop_oneof![Just("goldsrc"), Just("source-hl2")],
        prop_oneof![
            4 => Just(100.0),
            2 => Just(1000.0),
            2 => var(1.0, 3000.0),
        ],
        effects(),
        proptest::collection::vec((0..ENGINE_KEYS.len(), var(0.0, 3000.0)), 0..4),
        proptest::bool::weighted(0.1),
    )
        .prop_map(|(preset, fps, fx, overrides, truncate)| {
            let mut s = format!(
                "[engine]\npreset = \"{preset}\"\nfps = {}\neffects = [{}]\n",
                toml_f64(fps),
                fx.iter()
                    .map(|e| format!("\"{e}\""))
                    .collect::<Vec<_>>()
                    .join(", ")
            );
            if truncate {
                s.push_str("truncate-frame-time-ms = true\n");
            }
            let mut seen = Vec::new();
            for (k, v) in overrides {
                if !seen.contains(&k) {
                    seen.push(k);
                    s.push_str(&format!("{} = {}\n", ENGINE_KEYS[k], toml_f64(v)));
                }
            }
            s
        });
    let kind = prop_oneof![3 => Just("rule"), 1 => Just("solid")];
    let shape = prop_oneof![
        (num(32.0, 400.0), num(20.0, 4000.0), kind.clone()).prop_map(|(w, l, k)| format!(
            "[lane]\nwidth = {}\nlength = {}\nkind = \"{k}\"\n",
            toml_f64(w),
            toml_f64(l + 60.0)
        )),
        (
            num(32.0, 400.0),
            num(1.0, 3000.0),
            num(1.0, 3000.0),
            kind.clone()
        )
            .prop_map(|(w, a, b, k)| format!(
                "[bend90]\nwidth = {}\nleg1 = {}\nleg2 = {}\nkind = \"{k}\"\n",
                toml_f64(w),
                toml_f64(w + a),
                toml_f64(w + b)
            )),
        (
            num(32.0, 300.0),
            num(1.0, 3000.0),
            num(0.0, 200.0),
            proptest::option::weighted(0.2, num(0.0, 1.0)),
            kind.clone()
        )
            .prop_map(|(w, l, g, f, k)| format!(
                "[hairpin]\nwidth = {}\nlength = {}\ngap = {}\n{}kind = \"{k}\"\n",
                toml_f64(w),
                toml_f64(w + l),
                toml_f64(g),
                f.map_or(String::new(), |f| format!(
                    "finish = {}\n",
                    toml_f64(w + f * l)
                ))
            )),
        Just(String::new()),
    ];
    let start = (
        proptest::option::weighted(0.3, point(-100.0, 2000.0)),
        proptest::option::weighted(0.5, point(-2000.0, 2000.0)),
        proptest::option::of(any::<bool>()),
        proptest::option::weighted(0.2, any::<bool>()),
    )
        .prop_map(|(p, v, g, d)| {
            let mut s = "[start]\n".to_string();
            if let Some(p) = p {
                s.push_str(&format!("position = {p}\n"));
            }
            if let Some(v) = v {
                s.push_str(&format!("velocity = {v}\n"));
            }
            if let Some(g) = g {
                s.push_str(&format!("on-ground = {g}\n"));
            }
            if let Some(d) = d {
                s.push_str(&format!("ducked = {d}\n"));
            }
            s
        });
    let finish = proptest::option::weighted(
        0.3,
        (
            point(-500.0, 3000.0),
            point(-500.0, 3000.0),
            prop_oneof![
                Just(""),
                Just("point = \"hull\"\n"),
                Just("point = \"centre\"\n")
            ],
        ),
    )
    .prop_map(|f| {
        f.map_or(String::new(), |(a, b, p)| {
            format!("[finish]\na = {a}\nb = {b}\n{p}")
        })
    });
    let walls = proptest::collection::vec(
        (
            kind,
            proptest::collection::vec(point(-200.0, 3000.0), 2..5),
            proptest::bool::weighted(0.2),
        ),
        0..2,
    )
    .prop_map(|ws| {
        ws.into_iter()
            .map(|(k, pts, closed)| {
                format!(
                    "[[walls]]\nkind = \"{k}\"\nclosed = {closed}\npoints = [{}]\n",
                    pts.join(", ")
                )
            })
            .collect::<String>()
    });
    let max_frames = proptest::option::weighted(
        0.2,
        prop_oneof![
            Just("0".to_string()),
            Just("1".to_string()),
            (1u64..100_000).prop_map(|n| n.to_string()),
            Just("18446744073709551615".to_string()),
        ],
    );
    (engine, shape, start, finish, walls, max_frames).prop_map(|(e, sh, st, f, w, m)| {
        let head = m.map_or(String::new(), |m| format!("max-frames = {m}\n"));
        format!("{head}{e}{sh}{st}{f}{w}")
    })
}

// ---------------------------------------------------------------------------------------------------------
// The properties.

proptest! {
    #![proptest_config(config(1000, 0x5CE7_E0A1))]

    /// (a) Arbitrary strings.
    #[test]
    fn arbitrary_strings_give_a_scene_or_a_located_error(text in any::<String>()) {
        check_text(&text)?;
    }
}

proptest! {
    #![proptest_config(config(2000, 0x5CE7_E0A2))]

    /// (a) Soups of TOML tokens, which get past the first character far more often than random text.
    #[test]
    fn token_soups_give_a_scene_or_a_located_error(
        tokens in proptest::collection::vec(
            prop_oneof![
                3 => (0..TOKENS.len()).prop_map(|i| TOKENS[i].to_string()),
                1 => "[a-z-]{1,12}",
                1 => (0..EXTREMES.len()).prop_map(|i| EXTREMES[i].to_string()),
            ],
            0..40,
        ),
    ) {
        check_text(&tokens.join(""))?;
    }
}

proptest! {
    #![proptest_config(config(4000, 0x5CE7_E0A3))]

    /// (b) Mutations of the shipped scenes.
    #[test]
    fn mutated_shipped_scenes_give_a_scene_or_a_located_error(
        pick in any::<prop::sample::Index>(),
        edits in proptest::collection::vec(mutation(), 1..5),
    ) {
        let scenes = shipped_scenes();
        let mut bytes = scenes[pick.index(scenes.len())].clone().into_bytes();
        for m in &edits {
            apply(&mut bytes, m);
        }
        check_bytes(&bytes)?;
    }
}

proptest! {
    #![proptest_config(config(3000, 0x5CE7_E0A4))]

    /// (c) Well-formed scenes with random and extreme values.
    #[test]
    fn random_well_formed_scenes_give_a_scene_or_a_located_error(text in template_scene()) {
        check_text(&text)?;
    }
}

/// The shipped scenes, read once.
fn shipped_scenes() -> &'static [String] {
    static SCENES: std::sync::OnceLock<Vec<String>> = std::sync::OnceLock::new();
    SCENES.get_or_init(shipped)
}

/// The shipped scenes themselves pass the same checks (so the mutations start from accepted scenes and
/// from each kind of error), and the mutation machinery does what it says.
#[test]
fn shipped_scenes_pass_and_mutations_apply() {
    let mut accepted = 0;
    for text in shipped_scenes() {
        if check_text(text).unwrap_or_else(|e| panic!("{e}\n---\n{text}")) {
            accepted += 1;
        }
    }
    assert_eq!(accepted, 13, "the thirteen valid shipped scenes");
    let text = b"fps = 100\nx = -1.5e3\nname = \"a1\"\n".to_vec();
    assert_eq!(numbers(&text), vec![(6, 9), (14, 20)]);
    let mut t = text.clone();
    apply(&mut t, &Mutation::ReplaceNumber { which: 1, value: 0 });
    assert_eq!(t, b"fps = 100\nx = nan\nname = \"a1\"\n");
    let mut t = text.clone();
    apply(&mut t, &Mutation::DuplicateLine { at: 0.0 });
    assert_eq!(t, b"fps = 100\nfps = 100\nx = -1.5e3\nname = \"a1\"\n");
    let mut t = text.clone();
    apply(&mut t, &Mutation::SwapLines { a: 0.0, b: 1.0 });
    assert_eq!(t, b"name = \"a1\"\nx = -1.5e3\nfps = 100\n");
    let mut t = text;
    apply(&mut t, &Mutation::Truncate { at: 0.5 });
    assert_eq!(t.len(), 16);
    // A duplicate key is a located error.
    let dup = "[engine]\npreset = \"goldsrc\"\nfps = 100\nfps = 100\neffects = []\n";
    let e = Scene::from_toml_str(dup, ORIGIN).unwrap_err();
    assert!(e.to_string().starts_with(&format!("{ORIGIN}:4: ")), "{e}");
}

// ---------------------------------------------------------------------------------------------------------
// Regressions the fuzzing found (issue 9).

/// The error for `text` (from `origin`), checked by [`check_error`]-like rules: `(location, key, message)`.
fn error_of(text: &str, origin: &str) -> (String, String, String) {
    match Scene::from_toml_str(text, origin) {
        Ok(s) => panic!("accepted: {s:?}\n---\n{text}"),
        Err(e) => {
            let shown = e.to_string();
            assert_eq!(shown.lines().count(), 1, "{shown:?}");
            assert!(!shown.contains(['\r', '\u{2028}', '\u{0}']), "{shown:?}");
            match e {
                Error::Scene {
                    location,
                    key,
                    message,
                } => (location, key, message),
                other => panic!("not a scene error: {other:?}"),
            }
        }
    }
}

const HEAD: &str = "[engine]\npreset = \"goldsrc\"\nfps = 100\neffects = [\"air-accel\"]\n";

#[test]
fn line_breaks_in_keys_values_and_file_names_are_escaped() {
    // A quoted key holding a line break: the key and the message show it as an escape.
    let (loc, key, msg) = error_of(&format!("{HEAD}\"a\\nb\" = 1\n"), ORIGIN);
    assert_eq!(
        (loc.as_str(), key.as_str()),
        ("fuzz/scene.toml:5", "engine.a\\nb")
    );
    assert!(msg.contains("unknown field"), "{msg}");
    // A carriage return, a NUL and a line separator in a string value.
    for bad in ["gold\\rsrc", "gold\\u0000src", "gold\\u2028src"] {
        let (loc, key, msg) = error_of(
            &format!("[engine]\npreset = \"{bad}\"\nfps = 100\neffects = []\n"),
            ORIGIN,
        );
        assert_eq!(
            (loc.as_str(), key.as_str()),
            ("fuzz/scene.toml:2", "engine.preset")
        );
        assert!(msg.contains("unknown variant `gold\\"), "{msg}");
    }
    // A file name with a line break (legal on Unix) is escaped in the location.
    let (loc, _, _) = error_of("[engine]\n", "dir/a\nb.toml");
    assert!(loc.starts_with("dir/a\\nb.toml"), "{loc}");
}

#[test]
fn huge_coordinates_and_speeds_are_refused_with_their_key() {
    use strafeopt::scene::{MAX_COORDINATE_UNITS, MAX_START_SPEED_UPS};
    let lane = "[lane]\nwidth = 64\nlength = 1000\nkind = \"rule\"\n";
    // (text, location, key, words); HEAD is lines 1-4.
    let cases: Vec<(String, &str, &str, &str)> = vec![
        // A finite start velocity so large that the first frames overflow the position.
        (
            format!("{HEAD}{lane}[start]\nvelocity = [1.7976931348623157e308, 0]\n"),
            "fuzz/scene.toml:10",
            "start.velocity",
            "got [1.7976931348623157e308, 0]; must be two finite numbers with a speed of at most 1000000 ups",
        ),
        (
            format!("{HEAD}{lane}[start]\nvelocity = [800000, -800000]\n"),
            "fuzz/scene.toml:10",
            "start.velocity",
            "at most 1000000 ups",
        ),
        (
            format!("{HEAD}{lane}[start]\nvelocity = [nan, 0]\n"),
            "fuzz/scene.toml:10",
            "start.velocity",
            "got [NaN, 0]",
        ),
        // The shape's default start velocity is sv_maxspeed: blamed on the setting.
        (
            format!("{HEAD}maxspeed = 2e6\n{lane}"),
            "fuzz/scene.toml:5",
            "engine.maxspeed",
            "must be at most 1e6 in magnitude",
        ),
        // Coordinates: a shape, a wall point, a start, a finish end.
        (
            format!("{HEAD}[lane]\nwidth = 64\nlength = 1e300\nkind = \"rule\"\n"),
            "fuzz/scene.toml:5",
            "lane",
            "[lane] reaches (1e300, 0); every coordinate must be between -1000000 and 1000000 units",
        ),
        (
            format!("{HEAD}{lane}[[walls]]\nkind = \"rule\"\npoints = [\n  [0, 500],\n  [-1e308, 500],\n]\n"),
            "fuzz/scene.toml:13",
            "walls[0].points",
            "point 1 is at (-1e308, 500)",
        ),
        (
            format!("{HEAD}{lane}[start]\nposition = [1000000.5, 32]\n"),
            "fuzz/scene.toml:10",
            "start.position",
            "got [1000000.5, 32]; must be two finite numbers, each between",
        ),
        (
            format!("{HEAD}[start]\nposition = [0, 0]\n[finish]\na = [1e7, -1]\nb = [1e7, 1]\n"),
            "fuzz/scene.toml:8",
            "finish.a",
            "got [10000000, -1]",
        ),
    ];
    for (text, location, key, words) in cases {
        let (loc, k, msg) = error_of(&text, ORIGIN);
        assert_eq!(
            (loc.as_str(), k.as_str()),
            (location, key),
            "{msg}\n---\n{text}"
        );
        assert!(msg.contains(words), "{msg}\n---\n{text}");
    }
    // The limits themselves are allowed.
    let s = Scene::from_toml_str(
        &format!(
            "{HEAD}[start]\nposition = [-{MAX_COORDINATE_UNITS}, 0]\nvelocity = [{MAX_START_SPEED_UPS}, 0]\n\
             [finish]\na = [{MAX_COORDINATE_UNITS}, -{MAX_COORDINATE_UNITS}]\nb = [{MAX_COORDINATE_UNITS}, {MAX_COORDINATE_UNITS}]\n"
        ),
        ORIGIN,
    )
    .unwrap_or_else(|e| panic!("{e}"));
    check_scene(&s).unwrap_or_else(|e| panic!("{e}"));
}

/// Scenes whose runs used to overflow: huge but finite movement variables, and the Source jump boost
/// without `max-velocity` (accelerated backhopping doubles the speed every hop, docs/physics.md section 11).
/// Physics now refuses both (`MovementVars::validate` bounds every magnitude; `jump-boost` requires
/// `max-velocity`), so each gives a clean error.
#[test]
fn known_overflowing_scenes() {
    let lane = "[lane]\nwidth = 64\nlength = 3000\nkind = \"rule\"\n";
    for text in [
        format!("[engine]\npreset = \"goldsrc\"\nfps = 100\neffects = [\"air-accel\"]\nairaccelerate = -1.7976931348623157e308\n{lane}"),
        format!("[engine]\npreset = \"goldsrc\"\nfps = 1000\neffects = [\"friction\", \"gravity\", \"ground-accel\", \"jump\"]\ngravity = 1e308\n{lane}[start]\non-ground = true\n"),
        format!("[engine]\npreset = \"source-hl2\"\nfps = 100\neffects = [\"air-accel\", \"gravity\", \"jump\", \"jump-boost\"]\n{lane}[start]\nvelocity = [0, -1846]\n"),
    ] {
        check_text(&text).unwrap_or_else(|e| panic!("{e}\n---\n{text}"));
    }
}
