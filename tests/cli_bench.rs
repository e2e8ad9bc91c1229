//! `strafeopt bench` through the real binary (issue 8): the rows of one scene, cheapest first, none below
//! the lower bound, the solves never slower in game time than greedy, the hill-climbing baseline present.
//! No timing assertions: speed targets live in `benches/`.

use assert_cmd::Command;
use serde_json::Value;

#[test]
fn quick_bench_of_the_bend_has_ordered_consistent_rows() {
    let out = Command::cargo_bin("strafeopt")
        .unwrap_or_else(|e| panic!("{e}"))
        .args([
            "bench",
            "scenarios/hl-bend90-100fps.toml",
            "--quick",
            "--json",
        ])
        .output()
        .unwrap_or_else(|e| panic!("{e}"));
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let rows: Value = serde_json::from_slice(&out.stdout).unwrap_or_else(|e| panic!("{e}"));
    let rows = rows
        .as_array()
        .unwrap_or_else(|| panic!("an array of rows"));
    let method = |r: &Value| r["method"].as_str().unwrap_or("").to_string();
    let methods: Vec<String> = rows.iter().map(method).collect();
    for m in [
        "lower-bound",
        "greedy",
        "solve",
        "hill-climb",
        "engine-exact",
    ] {
        assert!(methods.iter().any(|x| x == m), "no {m} row in {methods:?}");
    }
    // --quick: the fast level only, no scaling rows, each hill climb beside its solve.
    let levels: Vec<&str> = rows
        .iter()
        .filter(|r| r["method"] == "solve")
        .filter_map(|r| r["quality"].as_str())
        .collect();
    assert_eq!(levels, ["fast"]);
    assert_eq!(
        rows.iter().filter(|r| r["method"] == "hill-climb").count(),
        1
    );
    assert!(rows.iter().all(|r| r["section"] == "accuracy"));
    // Cheapest first.
    let ranks: Vec<u64> = rows.iter().filter_map(|r| r["rank"].as_u64()).collect();
    assert_eq!(ranks.len(), rows.len());
    assert!(ranks.windows(2).all(|w| w[0] <= w[1]), "{ranks:?}");
    assert_eq!(methods.first().map(String::as_str), Some("lower-bound"));
    // Nothing below the lower bound; every run here reaches the line validly.
    let bound = rows[0]["time"].as_f64().unwrap_or(f64::NAN);
    assert!(bound > 0.0);
    for r in rows {
        assert_eq!(r["bound_time"].as_f64(), Some(bound));
        let t = r["time"].as_f64().unwrap_or(f64::NAN);
        assert!(
            t >= bound - 1e-12,
            "{} below the bound: {t} < {bound}",
            method(r)
        );
        assert!(r["gap"].as_f64().is_some_and(|g| g >= -1e-12));
        if method(r) != "lower-bound" {
            assert_eq!(r["feasible"], true, "{r}");
        }
    }
    // The solves are never slower in game time than greedy (which is valid here).
    let greedy = rows
        .iter()
        .find(|r| r["method"] == "greedy")
        .and_then(|r| r["time"].as_f64())
        .unwrap_or(f64::NAN);
    for r in rows.iter().filter(|r| r["method"] == "solve") {
        let t = r["time"].as_f64().unwrap_or(f64::INFINITY);
        assert!(
            t <= greedy,
            "solve {} took {t} s, greedy {greedy} s",
            r["quality"]
        );
    }
}

#[test]
fn bench_refuses_bad_input_in_one_line() {
    let out = Command::cargo_bin("strafeopt")
        .unwrap_or_else(|e| panic!("{e}"))
        .args(["bench", "scenarios/no-such-scene.toml", "--json"])
        .output()
        .unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(out.status.code(), Some(2));
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(err.lines().count(), 1, "{err}");
    assert!(err.starts_with("strafeopt: "), "{err}");
}

#[test]
fn staircase_rows_are_valid_and_grow_with_the_corners() {
    let out = Command::cargo_bin("strafeopt")
        .unwrap_or_else(|e| panic!("{e}"))
        .args(["bench", "--staircase", "1,2", "--json"])
        .output()
        .unwrap_or_else(|e| panic!("{e}"));
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let v: Value = serde_json::from_slice(&out.stdout).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(v["quality"], "fast");
    let rows = v["scenes"]
        .as_array()
        .unwrap_or_else(|| panic!("a record per staircase"));
    let frames: Vec<u64> = rows
        .iter()
        .map(|r| {
            assert_eq!(r["valid"], true, "{r}");
            assert_eq!(r["engine_exact_valid"], true, "{r}");
            let (f, b) = (r["frames"].as_u64(), r["bound_frames"].as_u64());
            let (Some(f), Some(b)) = (f, b) else {
                panic!("no frames in {r}")
            };
            assert!(f >= b, "{r}");
            assert!(r["greedy_frames"].as_u64().is_some_and(|g| g >= f), "{r}");
            f
        })
        .collect();
    assert_eq!(
        rows.iter()
            .map(|r| r["corners"].as_u64())
            .collect::<Vec<_>>(),
        [Some(1), Some(2)]
    );
    // A second corner adds a 600-unit leg: at several hundred ups, more than half a second.
    assert!(frames[1] > frames[0] + 50, "{frames:?}");
}

#[test]
fn a_staircase_with_no_corners_is_refused_in_one_line() {
    let out = Command::cargo_bin("strafeopt")
        .unwrap_or_else(|e| panic!("{e}"))
        .args(["bench", "--staircase", "0"])
        .output()
        .unwrap_or_else(|e| panic!("{e}"));
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(err.trim().lines().count(), 1, "{err}");
    assert!(err.contains("1 to 64"), "{err}");
}
