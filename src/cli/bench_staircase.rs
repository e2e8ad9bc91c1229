//! `strafeopt bench --staircase C1,C2,... [--quality Q] [--time-limit S]`: solves a staircase of each
//! corner count ([`crate::scene::generate::staircase`]) and prints one row per staircase, or (`--json`)
//! one object with a record per staircase ([`crate::bench::generated::SceneRecord`]).

use super::args::QualityArg;
use super::bench::BenchArgs;
use super::bench_generated::progress_lines;
use super::table::aligned_table;
use crate::bench::generated::{measure_generated, SceneRecord};
use crate::bench::quality_name;
use crate::error::{Error, Result};
use crate::optimise::Quality;
use crate::scene::generate::{staircase, GeneratedScene, Staircase};
use std::io::IsTerminal;

/// Runs `bench --staircase`.
pub fn run(args: &BenchArgs) -> Result<String> {
    let scene_flags = [
        (!args.scenes.is_empty(), "scene files"),
        (args.quick, "--quick"),
        (!args.levels.is_empty(), "--levels"),
        (args.svg.is_some(), "--svg"),
        (args.no_hill_climb, "--no-hill-climb"),
        (args.no_scaling, "--no-scaling"),
        (args.seed.is_some(), "--seed"),
        (args.family.first_given().is_some(), "family flags"),
    ];
    if let Some((_, flag)) = scene_flags.iter().find(|(given, _)| *given) {
        return Err(Error::InvalidValue {
            name: "--staircase".to_string(),
            value: format!("given with {flag}"),
            allowed: "given alone, with --quality, --time-limit, --json or -q".to_string(),
        });
    }
    let spec = Staircase::default();
    let scenes: Vec<GeneratedScene> = args
        .staircase
        .iter()
        .map(|&corners| staircase(&Staircase { corners, ..spec }))
        .collect::<Result<_>>()?;
    let q = args.quality.map_or(Quality::Fast, QualityArg::quality);
    let search = super::bench::search_settings(args, q)?;
    let show = std::io::stderr().is_terminal() && !args.json && !args.quiet;
    let count = scenes.len() as u64;
    let records = measure_generated(&scenes, &search, &mut progress_lines(show, count));
    if args.json {
        let value = serde_json::json!({
            "quality": quality_name(q),
            "sub_problem_solver": search.sub_problem_solver,
            "leg_units": spec.leg_units,
            "width_units": spec.width_units,
            "fps": spec.fps,
            "start_speed_ups": spec.start_speed_ups,
            "scenes": records,
        });
        return serde_json::to_string(&value)
            .map(|t| format!("{t}\n"))
            .map_err(|e| Error::Io(format!("serialising the records: {e}")));
    }
    let mut out = format!(
        "solve --quality {} on staircases ({}-unit legs, {} units wide, {} fps, {} ups start, {} walls)\n",
        quality_name(q),
        spec.leg_units,
        spec.width_units,
        spec.fps,
        spec.start_speed_ups,
        spec.walls.name()
    );
    out.push_str(&table(&records));
    Ok(out)
}

/// One aligned row per staircase.
fn table(records: &[SceneRecord]) -> String {
    let header = [
        "corners",
        "frames",
        "bound",
        "greedy",
        "relaxed",
        "valid",
        "solve (s)",
        "ms/frame",
        "status",
    ];
    let opt = |v: Option<u64>| v.map_or("-".to_string(), |x| x.to_string());
    let rows: Vec<[String; 9]> = records
        .iter()
        .map(|r| {
            [
                r.corners.to_string(),
                opt(r.frames),
                opt(r.bound_frames),
                opt(r.greedy_frames),
                opt(r.relaxed_frames),
                match (r.valid, r.engine_exact_valid) {
                    (true, true) => "both",
                    (true, false) => "f64 only",
                    _ => "no",
                }
                .to_string(),
                format!("{:.1}", r.solve_seconds),
                r.solve_ms_per_frame
                    .map_or("-".to_string(), |m| format!("{m:.1}")),
                r.status.clone(),
            ]
        })
        .collect();
    let mut right_aligned = [true; 9];
    right_aligned[8] = false;
    aligned_table(&header, &rows, &right_aligned)
}
