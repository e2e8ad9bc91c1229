//! `strafeopt bench --generated N [--seed S] [--quality Q] [--ci-sized ...]`: solves scenes 0 to N-1 of
//! the generated family ([`crate::bench::generated`]) and prints the distribution of each column, the
//! share of scenes where greedy and the plan finished validly, and (`--json`) a record per scene.

use super::args::QualityArg;
use super::bench::{search_settings, BenchArgs};
use super::gen::checked_count;
use super::table::aligned_table;
use crate::bench::generated::{
    columns, distributions, measure_generated, share, Distribution, SceneRecord,
};
use crate::bench::quality_name;
use crate::error::{Error, Result};
use crate::optimise::Quality;
use crate::scene::generate::generate_sample;
use std::io::IsTerminal;

/// The family seed when `--seed` is not given.
pub const DEFAULT_SEED: u64 = 1;

/// Runs `bench --generated`.
pub fn run(args: &BenchArgs) -> Result<String> {
    let count = checked_count("--generated", args.generated.unwrap_or(0))?;
    if !args.scenes.is_empty() {
        return Err(Error::InvalidValue {
            name: "--generated".to_string(),
            value: format!("given with {} scene files", args.scenes.len()),
            allowed: "given without scene files (the scenes are generated)".to_string(),
        });
    }
    let scene_flags = [
        (args.quick, "--quick"),
        (!args.levels.is_empty(), "--levels"),
        (args.svg.is_some(), "--svg"),
        (args.no_hill_climb, "--no-hill-climb"),
        (args.no_scaling, "--no-scaling"),
    ];
    if let Some((_, flag)) = scene_flags.iter().find(|(given, _)| *given) {
        return Err(Error::InvalidValue {
            name: flag.to_string(),
            value: "given with --generated".to_string(),
            allowed: "given for scene files only (with --generated, --quality sets the level)"
                .to_string(),
        });
    }
    let settings = args.family.settings()?;
    let seed = args.seed.unwrap_or(DEFAULT_SEED);
    let q = args.quality.map_or(Quality::Fast, QualityArg::quality);
    let search = search_settings(args, q)?;
    let scenes = generate_sample(seed, count, &settings)?;
    let show = std::io::stderr().is_terminal() && !args.json;
    let records = measure_generated(&scenes, &search, &mut progress_lines(show, count));
    let dist = distributions(&records, &columns());
    let greedy = share(&records, |r| r.greedy_valid);
    let plan = share(&records, |r| r.valid);
    let exact = share(&records, |r| r.engine_exact_valid);
    let in_frame = share(&records, |r| r.frames_behind_relaxed() == Some(0));
    let is_behind = |r: &SceneRecord| r.frames_behind_relaxed().is_some_and(|k| k > 0);
    let behind = share(&records, is_behind);
    let ahead = share(&records, |r| {
        r.frames_behind_relaxed().is_some_and(|k| k < 0)
    });
    let behind_past_estimates = share(&records, |r| {
        is_behind(r) && r.estimates_pass_the_relaxed_frame() == Some(true)
    });
    if args.json {
        let value = serde_json::json!({
            "seed": seed,
            "count": count,
            "quality": quality_name(q),
            "sub_problem_solver": search.sub_problem_solver,
            "family": settings,
            "distributions": dist,
            "greedy_valid": greedy.0,
            "plan_valid": plan.0,
            "engine_exact_valid": exact.0,
            "in_relaxed_frame": in_frame.0,
            "behind_relaxed_frame": behind.0,
            "behind_where_estimates_pass_the_frame": behind_past_estimates.0,
            "ahead_of_relaxed_frame": ahead.0,
            "scenes": records,
        });
        return serde_json::to_string(&value)
            .map(|t| format!("{t}\n"))
            .map_err(|e| Error::Io(format!("serialising the records: {e}")));
    }
    let mut out = format!(
        "solve --quality {} on {count} generated scenes (seed {seed}; {})\n",
        quality_name(q),
        settings.describe()
    );
    out.push_str(&table(&dist));
    let pct = |(n, of): (usize, usize)| {
        format!("{n} of {of} ({:.0}%)", 100.0 * n as f64 / of.max(1) as f64)
    };
    out.push_str(&format!(
        "greedy valid: {}; plan valid: {}; engine-exact valid: {}\n",
        pct(greedy),
        pct(plan),
        pct(exact)
    ));
    out.push_str(&format!(
        "plan in its relaxed optimum's frame: {}; a frame or more behind it: {}, on {} of them the \
         estimated zigzag and guard alone take more than that frame leaves; ahead of it: {} (a plan \
         sliding along a wall, or another local optimum)\n",
        pct(in_frame),
        behind.0,
        behind_past_estimates.0,
        ahead.0
    ));
    Ok(out)
}

/// What `bench` prints on stderr as each of `count` scenes is solved (nothing unless `show`): its place,
/// name, frames, solve time and status.
pub fn progress_lines(show: bool, count: u64) -> impl FnMut(usize, &SceneRecord) {
    move |i, r| {
        if show {
            eprintln!(
                "[{}/{count}] {}: {} frames, {:.1} s, {}",
                i + 1,
                r.scene,
                r.frames.map_or("-".to_string(), |f| f.to_string()),
                r.solve_seconds,
                r.status
            );
        }
    }
}

/// The distributions as an aligned table, one row per column.
pub fn table(dist: &[Distribution]) -> String {
    let header = ["", "scenes", "min", "median", "p90", "max"];
    let num = |v: Option<f64>| v.map_or("-".to_string(), |x| format!("{x:.3}"));
    let rows: Vec<[String; 6]> = dist
        .iter()
        .map(|d| {
            [
                d.column.to_string(),
                d.count.to_string(),
                num(d.min),
                num(d.median),
                num(d.p90),
                num(d.max),
            ]
        })
        .collect();
    aligned_table(&header, &rows, &[false, true, true, true, true, true])
}
