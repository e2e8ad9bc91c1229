//! Limits that hold: the frame limit (`--max-frames`), the time limit on every stage, cancellation, and
//! what the command line prints around them (progress hidden off a terminal, aligned text).

use std::io::Read;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};
use strafeopt::budget::Stage;
use strafeopt::optimise::{solve_cancellable, Progress, Quality, SearchSettings, SearchStatus};
use strafeopt::scene::Scene;
use strafeopt::Error;

mod common;
use common::strafeopt;

fn shipped(name: &str) -> String {
    std::fs::read_to_string(
        Path::new(env!("CARGO_MANIFEST_DIR")).join(format!("scenarios/{name}.toml")),
    )
    .unwrap_or_else(|e| panic!("{e}"))
}

/// Writes scene `text` into a fresh directory named by `tag`; returns the file.
fn scene_file(tag: &str, text: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("strafeopt-limits-{tag}-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap_or_else(|e| panic!("{e}"));
    let path = dir.join("scene.toml");
    std::fs::write(&path, text).unwrap_or_else(|e| panic!("{e}"));
    path
}

#[test]
fn a_scene_past_the_frame_limit_is_refused_at_once_with_the_figure_and_the_flag() {
    // The 100 fps bend's lower bound is frame 398: no run can take fewer.
    let out = strafeopt(&[
        "solve",
        "scenarios/hl-bend90-100fps.toml",
        "--max-frames",
        "300",
    ]);
    assert_eq!(out.status.code(), Some(2));
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(err.lines().count(), 1, "{err}");
    assert!(
        err.contains("398") && err.contains("300") && err.contains("--max-frames"),
        "{err}"
    );
    assert!(out.stdout.is_empty());
    // At the bound itself it plans.
    let out = strafeopt(&[
        "solve",
        "scenarios/hl-bend90-100fps.toml",
        "--quality",
        "fast",
        "--max-frames",
        "600",
        "--json",
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
}

#[test]
fn a_100000_fps_bend_past_the_default_limit_is_refused_without_work() {
    // The 100 fps bend at 100,000 fps: its lower bound is about 330,000 frames.
    let text = shipped("hl-bend90-100fps").replace("fps = 100", "fps = 100000");
    let scene = scene_file("default-limit", &text);
    let started = Instant::now();
    let out = strafeopt(&["solve", &scene.to_string_lossy()]);
    assert_eq!(out.status.code(), Some(2));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("--max-frames") && err.contains("100000"),
        "{err}"
    );
    // No greedy run of millions of frames was started (each takes seconds): the refusal comes at once.
    assert!(
        started.elapsed() < Duration::from_secs(20),
        "{:?}",
        started.elapsed()
    );
}

#[test]
fn bench_applies_the_frame_limit_before_measuring() {
    let out = strafeopt(&[
        "bench",
        "scenarios/hl-bend90-100fps.toml",
        "--quick",
        "--quiet",
        "--max-frames",
        "300",
    ]);
    assert_eq!(out.status.code(), Some(2));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("398") && err.contains("--max-frames"), "{err}");
    assert!(out.stdout.is_empty());
}

#[test]
fn bad_max_frames_is_bad_input() {
    let out = strafeopt(&[
        "solve",
        "scenarios/hl-bend90-100fps.toml",
        "--max-frames",
        "0",
    ]);
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("--max-frames = 0"));
}

/// Peak resident memory of a running process, kB (`VmHWM`), if it can be read.
fn peak_kb(pid: u32) -> Option<u64> {
    let status = std::fs::read_to_string(format!("/proc/{pid}/status")).ok()?;
    let line = status.lines().find(|l| l.starts_with("VmHWM:"))?;
    line.split_whitespace().nth(1)?.parse().ok()
}

#[test]
fn millions_of_frames_under_a_small_time_limit_return_soon_in_bounded_memory() {
    // The groundstrafe lane at 100,000 fps and five times as long: about 20 million frames to the line.
    // Any greedy run alone takes far longer than the limit (even at 0.1 us a frame, several times as fast
    // as the development machine, 2 s), so what ends the solve is the limit.
    let text = shipped("hl-groundstrafe-1000fps")
        .replace("fps = 1000", "fps = 100000")
        .replace("length = 20000", "length = 100000");
    let scene = scene_file("millions", &format!("max-frames = 30000000\n{text}"));
    let limit_s = 2.0;
    let started = Instant::now();
    let mut child = Command::new(assert_cmd::cargo::cargo_bin("strafeopt"))
        .args([
            "solve",
            &scene.to_string_lossy(),
            "--max-frames",
            "30000000",
            "--time-limit",
            &limit_s.to_string(),
            "--json",
        ])
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap_or_else(|e| panic!("{e}"));
    let mut peak = 0;
    let status = loop {
        if let Some(kb) = peak_kb(child.id()) {
            peak = peak.max(kb);
        }
        if let Some(status) = child.try_wait().unwrap_or_else(|e| panic!("{e}")) {
            break status;
        }
        if started.elapsed() > Duration::from_secs(120) {
            let _ = child.kill();
            panic!("still running after 120 s");
        }
        std::thread::sleep(Duration::from_millis(20));
    };
    let elapsed = started.elapsed().as_secs_f64();
    let mut err = String::new();
    if let Some(mut e) = child.stderr.take() {
        let _ = e.read_to_string(&mut err);
    }
    // Loose: within ten times the limit plus start-up, never the minutes a full sweep takes.
    assert!(elapsed < 10.0 * limit_s + 10.0, "{elapsed} s");
    // No run reached the line in 2 s: exit 1 with one line that says what stopped it and where.
    assert_eq!(status.code(), Some(1), "{err}");
    // In the greedy sweep, or (on a loaded machine) still in the lower bound's 20-million-frame profile.
    assert!(
        err.contains("stopped by the time limit in the ")
            && (err.contains("greedy stage") || err.contains("lower-bound stage"))
            && err.contains("--time-limit"),
        "{err}"
    );
    // Runs in a sweep keep no frames: a trace of 20 million frames alone would be some 2.5 GB.
    assert!(peak < 150_000, "peak {peak} kB");
}

#[test]
fn a_set_cancel_flag_returns_the_best_valid_plan_and_names_the_stage() {
    let scene = Scene::from_toml_str(&shipped("hl-bend90-100fps"), "bend")
        .unwrap_or_else(|e| panic!("{e}"));
    let settings = SearchSettings::for_quality(Quality::Balanced);
    // Cancelled as soon as the greedy baseline is ready: the relaxed stage stops at once.
    let cancel = AtomicBool::new(false);
    let o = solve_cancellable(
        &scene,
        &settings,
        &mut |p| {
            if matches!(p, Progress::Baseline { .. }) {
                cancel.store(true, Ordering::Relaxed);
            }
        },
        &cancel,
    )
    .unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(
        o.status,
        SearchStatus::Cancelled {
            stopped_in: Stage::Relaxed
        }
    );
    assert!(o.trace.feasible() && o.engine_exact.feasible());
    assert_eq!(
        o.trace.crossing, o.greedy.crossing,
        "the greedy plan, nothing newer"
    );
    // Set before the start: nothing valid yet, an error that says so.
    let cancel = AtomicBool::new(true);
    match solve_cancellable(&scene, &settings, &mut |_| {}, &cancel) {
        Err(e @ Error::Stopped { .. }) => assert!(e.to_string().contains("cancellation"), "{e}"),
        other => panic!("{other:?}"),
    }
}

#[test]
fn exact_cut_as_its_last_polish_starts_keeps_balanceds_plan() {
    let scene = Scene::from_toml_str(&shipped("hl-bend90-100fps"), "bend")
        .unwrap_or_else(|e| panic!("{e}"));
    let balanced = solve_cancellable(
        &scene,
        &SearchSettings::for_quality(Quality::Balanced),
        &mut |_| {},
        &AtomicBool::new(false),
    )
    .unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(balanced.source, "optimised");
    // `exact` polishes `balanced`'s plan on at a smaller margin still: cancelled as that polish starts,
    // it keeps the plan it had and says it was cut.
    let exact = SearchSettings::for_quality(Quality::Exact);
    let last_margin = exact
        .fine_polish
        .and_then(|f| f.margins_units.last().copied())
        .unwrap_or_else(|| panic!("exact has no last polish"));
    let cancel = AtomicBool::new(false);
    let mut polishes = 0;
    let o = solve_cancellable(
        &scene,
        &exact,
        &mut |p| {
            if let Progress::Polishing { margin_units } = p {
                polishes += 1;
                // The very constant the settings hold, passed on unchanged.
                if margin_units == last_margin {
                    cancel.store(true, Ordering::Relaxed);
                }
            }
        },
        &cancel,
    )
    .unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(polishes, 2);
    assert_eq!(o.source, "optimised");
    assert_eq!(o.controls, balanced.controls, "balanced's plan");
    // Cut in the polish's own stages, not in the replay of what they gave.
    assert_eq!(
        o.status,
        SearchStatus::Cancelled {
            stopped_in: Stage::Rounding
        }
    );
    assert!(o.trace.feasible() && o.engine_exact.feasible());
}

#[test]
fn text_output_has_fixed_decimals_in_one_column_and_no_progress_off_a_terminal() {
    let out = strafeopt(&[
        "solve",
        "scenarios/hl-bend90-100fps.toml",
        "--quality",
        "fast",
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(
        out.stderr.is_empty(),
        "stderr is not a terminal: no progress"
    );
    let text = String::from_utf8_lossy(&out.stdout);
    let mut lines = text.lines();
    assert_eq!(
        lines.next(),
        Some("hl-bend90-100fps (goldsrc at 100 fps)"),
        "{text}"
    );
    for line in lines {
        let (label, value) = line.split_at(17.min(line.len()));
        assert!(label.trim_end().ends_with(':'), "label column: {line:?}");
        // No exponent notation (`3.238e-1`) anywhere.
        assert!(
            !value
                .split_whitespace()
                .any(|w| w.parse::<f64>().is_ok() && w.contains('e')),
            "{line:?}"
        );
    }
    assert!(text.contains("min clearance:   "), "{text}");
    assert!(text.contains(" units\n"), "{text}");
}

#[test]
fn a_broken_run_is_given_up_at_its_frame_limit_and_a_valid_one_is_not() {
    use strafeopt::budget::Budget;
    use strafeopt::sim::{Greedy, Simulation};
    // On the narrow bend every look-ahead breaks a rule (at frame 289 for the look-ahead of 100): played
    // with a limit of 300 frames it stops there, uncrossed; the wide bend's valid run crosses past the
    // limit all the same.
    for (name, broken) in [
        ("hl-bend90-narrow-100fps", true),
        ("hl-bend90-100fps", false),
    ] {
        let scene = Scene::from_toml_str(&shipped(name), name).unwrap_or_else(|e| panic!("{e}"));
        let sim = Simulation::new(&scene).unwrap_or_else(|e| panic!("{e}"));
        let bound = strafeopt::optimise::lower_bound(&scene, sim.corridor())
            .unwrap_or_else(|e| panic!("{e}"));
        let full = sim.run(&mut Greedy::new(bound.path.clone(), 100.0));
        let limited = sim.run_summary_broken_until(
            &mut Greedy::new(bound.path.clone(), 100.0),
            &Budget::unlimited(),
            300,
        );
        assert_eq!(limited.broke_rule, broken, "{name}");
        if broken {
            let first = full.first_rule_violation();
            assert!(first.is_some_and(|f| f <= 300), "{name}: {first:?}");
            assert_eq!(limited.frames_run, 300, "{name}");
            assert!(
                limited.crossing.is_none() && full.crossing.is_some(),
                "{name}"
            );
        } else {
            assert_eq!(limited.crossing, full.crossing, "{name}");
            assert!(limited.feasible(), "{name}");
        }
    }
}

#[test]
fn a_run_summary_gives_the_verdicts_of_the_full_run() {
    use strafeopt::budget::Budget;
    use strafeopt::sim::{Greedy, Simulation};
    // The wide bend (runs cross validly), the narrow one (every look-ahead breaks a rule) and the narrow
    // one between solid walls (runs slide along them: contacts).
    let solid = shipped("hl-bend90-narrow-100fps").replace("kind = \"rule\"", "kind = \"solid\"");
    let mut contacts = 0;
    for (name, text) in [
        ("hl-bend90-100fps", shipped("hl-bend90-100fps")),
        (
            "hl-bend90-narrow-100fps",
            shipped("hl-bend90-narrow-100fps"),
        ),
        ("solid narrow bend", solid),
    ] {
        let scene = Scene::from_toml_str(&text, name).unwrap_or_else(|e| panic!("{e}"));
        let sim = Simulation::new(&scene).unwrap_or_else(|e| panic!("{e}"));
        let bound = strafeopt::optimise::lower_bound(&scene, sim.corridor())
            .unwrap_or_else(|e| panic!("{e}"));
        for la in [25.0, 100.0, 400.0, 1600.0] {
            let trace = sim.run(&mut Greedy::new(bound.path.clone(), la));
            let run = sim.run_summary(
                &mut Greedy::new(bound.path.clone(), la),
                &Budget::unlimited(),
            );
            assert_eq!(run.crossing, trace.crossing, "{name} {la}");
            assert_eq!(run.feasible(), trace.feasible(), "{name} {la}");
            assert_eq!(run.collisions, trace.collisions(), "{name} {la}");
            assert_eq!(run.frames_run, trace.frames.len() as u64, "{name} {la}");
            assert_eq!(
                run.broke_rule,
                trace.first_rule_violation().is_some(),
                "{name} {la}"
            );
            assert!(!run.interrupted && !trace.interrupted);
            contacts += run.collisions;
        }
    }
    assert!(contacts > 0, "some run touched a solid wall");
}

#[test]
fn an_expired_budget_stops_the_greedy_sweep_within_its_first_frames() {
    use strafeopt::budget::{Budget, FRAMES_PER_BUDGET_CHECK};
    use strafeopt::sim::controllers::{best_capped_greedy_within, GREEDY_LOOKAHEADS_UNITS};
    use strafeopt::sim::Simulation;
    let scene = Scene::from_toml_str(&shipped("hl-bend90-100fps"), "bend")
        .unwrap_or_else(|e| panic!("{e}"));
    let sim = Simulation::new(&scene).unwrap_or_else(|e| panic!("{e}"));
    let bound =
        strafeopt::optimise::lower_bound(&scene, sim.corridor()).unwrap_or_else(|e| panic!("{e}"));
    let expired = Budget::new(Some(Instant::now()), None);
    let (trace, _, _) = best_capped_greedy_within(
        &sim,
        &bound.path,
        &GREEDY_LOOKAHEADS_UNITS,
        &[500.0, 600.0],
        &expired,
    );
    // One run was started and cut at its first look at the budget; none after it.
    assert!(trace.interrupted && !trace.feasible());
    assert!(
        trace.frames.len() as u64 <= FRAMES_PER_BUDGET_CHECK,
        "{}",
        trace.frames.len()
    );
    // Unlimited, the same sweep finishes (the 100 fps bend: greedy crosses validly).
    let (full, _, _) = best_capped_greedy_within(
        &sim,
        &bound.path,
        &GREEDY_LOOKAHEADS_UNITS,
        &[500.0, 600.0],
        &Budget::unlimited(),
    );
    assert!(full.feasible() && !full.interrupted);
}
