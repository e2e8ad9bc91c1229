//! `strafeopt calc` through the real binary: the figures of docs/physics.md section 12 in text and `--json`,
//! and bad input giving one line and exit code 2.

use serde_json::Value;

mod common;
use common::strafeopt;

fn calc(args: &[&str]) -> Value {
    let full: Vec<&str> = ["calc"]
        .into_iter()
        .chain(args.iter().copied())
        .chain(["--json"])
        .collect();
    let out = strafeopt(&full);
    assert!(
        out.status.success(),
        "{args:?}: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(!text.contains("NaN") && !text.contains("inf"));
    serde_json::from_str(&text).unwrap_or_else(|e| panic!("{args:?}: not JSON ({e}): {text}"))
}

fn num(v: &Value, key: &str) -> f64 {
    v[key]
        .as_f64()
        .unwrap_or_else(|| panic!("no number {key} in {v}"))
}

#[test]
fn frames_to_speed_json() {
    let v = calc(&[
        "frames-to-speed",
        "--from",
        "320",
        "--to",
        "1000",
        "--fps",
        "1000",
    ]);
    assert_eq!(v["frames"].as_u64(), Some(4939));
    assert_eq!(format!("{:.0}", num(&v, "frames_closed_form")), "4938");
    assert_eq!(v["inputs"]["fps"].as_f64(), Some(1000.0));
    let v = calc(&[
        "frames-to-speed",
        "--from",
        "0",
        "--to",
        "2000",
        "--airaccelerate",
        "100",
    ]);
    assert_eq!(format!("{:.1}", num(&v, "time")), "4.4");
}

#[test]
fn frames_to_speed_on_the_ground_agrees_with_its_closed_form() {
    let v = calc(&[
        "frames-to-speed",
        "--from",
        "320",
        "--to",
        "500",
        "--ground",
    ]);
    let closed = num(&v, "frames_closed_form");
    let frames = v["frames"].as_u64().unwrap_or(0) as f64;
    assert!(
        (frames - closed.ceil()).abs() <= 1.0,
        "{frames} vs {closed}"
    );
}

#[test]
fn max_ground_speed_json() {
    let v = calc(&["max-ground-speed", "--fps", "1000"]);
    assert_eq!(format!("{:.1}", num(&v, "speed")), "505.2");
    assert!((num(&v, "speed_simulated") - num(&v, "speed")).abs() < 1e-6);
    let v = calc(&["max-ground-speed", "--fps", "100"]);
    assert_eq!(format!("{:.1}", num(&v, "speed")), "498.2");
    // Edge friction doubles k: M sqrt(k_e A (2 - tau k_e A) / (k (2 - tau k))) with k = 8.
    let v = calc(&["max-ground-speed", "--fps", "100", "--edge-friction"]);
    let expect = 320.0 * (10.0 * (2.0 - 0.1) / (8.0 * (2.0 - 0.08f64))).sqrt();
    assert!((num(&v, "speed") - expect).abs() < 1e-9);
}

#[test]
fn radius_json() {
    let v = calc(&["radius", "--speed", "500", "--fps", "100"]);
    assert_eq!(format!("{:.0}", num(&v, "radius")), "167");
    assert_eq!(format!("{:.1}", num(&v, "radius_measured")), "83.8");
}

#[test]
fn speed_for_radius_inverts_radius() {
    let r = num(
        &calc(&["radius", "--speed", "777", "--fps", "250"]),
        "radius_measured",
    );
    let v = calc(&[
        "speed-for-radius",
        "--radius",
        &r.to_string(),
        "--fps",
        "250",
    ]);
    assert!((num(&v, "speed") - 777.0).abs() < 1e-6);
}

#[test]
fn bend_json() {
    let v = calc(&["bend", "--width", "160", "--fps", "100"]);
    let r = (2.0 + 2f64.sqrt()) * 128.0;
    assert!((num(&v, "radius") - r).abs() < 1e-9);
    let back = calc(&[
        "radius",
        "--speed",
        &num(&v, "speed").to_string(),
        "--fps",
        "100",
    ]);
    assert!((num(&back, "radius_measured") - r).abs() < 1e-6);
}

#[test]
fn abh_json() {
    let v = calc(&["abh"]);
    let hops = v["hops"].as_array().cloned().unwrap_or_default();
    let speeds: Vec<f64> = hops.iter().filter_map(|h| h["speed"].as_f64()).collect();
    assert_eq!(
        speeds,
        [225.0, 285.0, 405.0, 645.0, 1125.0, 2085.0, 3500.0, 3500.0]
    );
    assert_eq!(
        format!("{:.2}", hops[7]["distance"].as_f64().unwrap_or(0.0)),
        "4217.70"
    );
    assert_eq!(format!("{:.3}", num(&v, "crossing_time")), "3.865");
    assert_eq!(format!("{:.2}", num(&v, "landing_past_line")), "753.36");
}

#[test]
fn text_output_shows_both_methods() {
    let out = strafeopt(&["calc", "radius", "--speed", "500", "--fps", "100"]);
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(
        text.contains("166.9667") && text.contains("83.8208"),
        "{text}"
    );
}

fn bad(args: &[&str], flag: &str) {
    let out = strafeopt(args);
    assert_eq!(out.status.code(), Some(2), "{args:?}");
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(err.trim_end().lines().count(), 1, "{args:?}: {err}");
    assert!(
        err.starts_with("strafeopt: ") && err.contains(flag),
        "{args:?}: {err}"
    );
    assert!(out.stdout.is_empty());
}

#[test]
fn bad_input_is_one_line_and_exit_2() {
    bad(
        &[
            "calc",
            "frames-to-speed",
            "--from",
            "0",
            "--to",
            "1",
            "--fps",
            "0",
        ],
        "--fps",
    );
    bad(
        &[
            "calc",
            "frames-to-speed",
            "--from",
            "0",
            "--to",
            "1",
            "--fps",
            "-100",
        ],
        "--fps",
    );
    bad(&["calc", "radius", "--speed", "NaN"], "--speed");
    bad(&["calc", "radius", "--speed", "inf"], "--speed");
    bad(&["calc", "radius", "--speed", "-5"], "--speed");
    bad(
        &["calc", "max-ground-speed", "--maxspeed", "0"],
        "--maxspeed",
    );
    bad(
        &["calc", "max-ground-speed", "--friction", "0"],
        "--friction",
    );
    bad(
        &["calc", "frames-to-speed", "--from", "-1", "--to", "5"],
        "--from",
    );
    bad(
        &[
            "calc",
            "frames-to-speed",
            "--from",
            "320",
            "--to",
            "600",
            "--ground",
        ],
        "--to",
    );
    bad(
        &["calc", "frames-to-speed", "--from", "320", "--to", "5000"],
        "--to",
    );
    bad(&["calc", "bend", "--width", "20"], "--width");
    bad(&["calc", "abh", "--hop-time", "0"], "--hop-time");
    bad(&["calc", "radius"], "--speed");
    bad(&["calc", "nope"], "nope");
}
