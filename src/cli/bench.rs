//! `strafeopt bench`: what accuracy costs in time. Loads the scenes, runs
//! [`crate::bench::measure_scene`] on each and [`crate::bench::measure_scaling`] on the first, and prints
//! an aligned table or (`--json`) one array of rows; `--svg` writes gap against wall time. With
//! `--generated N` it solves N generated scenes instead ([`super::bench_generated`]), with
//! `--staircase C,...` staircases of C corners ([`super::bench_staircase`]).

use super::args::{QualityArg, SubProblemSolverArg};
use super::table::{aligned_line, column_widths};
use super::{progress, write_atomically};
use crate::bench::{
    measure_scaling, measure_scene, quality_name, write_accuracy_svg, BenchRow, BenchSettings,
    Section,
};
use crate::error::{Error, Result};
use crate::optimise::search::time_limit;
use crate::optimise::{Quality, SearchSettings};
use crate::scene::{Scene, SceneFile};
use clap::Args;
use std::path::{Path, PathBuf};

/// The scenes measured when none are given: the four airborne scenes.
pub const DEFAULT_SCENES: [&str; 4] = [
    "scenarios/hl-bend90-100fps.toml",
    "scenarios/hl-bend90-narrow-100fps.toml",
    "scenarios/hl-hairpin-100fps.toml",
    "scenarios/hl-bend90-1000fps-aa100.toml",
];

/// `strafeopt bench [SCENES...] ...`
#[derive(Debug, Args)]
pub struct BenchArgs {
    /// Scene files (default: the four airborne scenes in scenarios/).
    pub scenes: Vec<PathBuf>,
    /// Only the fast level, no frame-rate scaling; by default only the 100 fps scenes.
    #[arg(long)]
    pub quick: bool,
    /// Solve qualities to measure, cheapest first (default: fast, balanced, exact; with --quick: fast).
    #[arg(long, value_enum, value_delimiter = ',')]
    pub levels: Vec<QualityArg>,
    /// Frame rate the first scene is also solved at, for the scaling rows.
    #[arg(long, default_value_t = 1000.0, allow_negative_numbers = true)]
    pub scaling_fps: f64,
    /// Leave out the frame-rate scaling rows.
    #[arg(long)]
    pub no_scaling: bool,
    /// Leave out the hill-climbing baseline.
    #[arg(long)]
    pub no_hill_climb: bool,
    /// Seed: of the generated scenes with --generated (default 1), else of the hill climber.
    #[arg(long)]
    pub seed: Option<u64>,
    /// Stop each solve after this many seconds with its best valid plan.
    #[arg(long, allow_negative_numbers = true)]
    pub time_limit: Option<f64>,
    /// Write gap against wall time as an SVG figure.
    #[arg(long)]
    pub svg: Option<PathBuf>,
    /// Most frames a solve plans (see `solve --max-frames`; default 100000).
    #[arg(long)]
    pub max_frames: Option<u64>,
    /// Print one JSON array of rows instead of a table (with --generated: one object with the
    /// distributions and a record per scene).
    #[arg(long)]
    pub json: bool,
    /// Solve this many generated scenes (`strafeopt gen`, scenes 0 to N-1 of --seed) instead of scene
    /// files, and print the distribution of their results.
    #[arg(long, allow_negative_numbers = true)]
    pub generated: Option<i64>,
    /// Solve staircases of these corner counts instead of scene files (right-angle turns alternating
    /// left and right, 600-unit legs, 128 units wide, 100 fps, airborne at 400 ups), one row each: how
    /// solve time grows with the corners alone.
    #[arg(long, value_delimiter = ',', num_args = 1.., conflicts_with = "generated")]
    pub staircase: Vec<u32>,
    /// Quality of each solve with --generated or --staircase (default fast).
    #[arg(long, value_enum, required = false)]
    pub quality: Option<QualityArg>,
    /// Solver of the convexified sub-steps, with --generated or --staircase.
    #[arg(long, value_enum, default_value_t = SubProblemSolverArg::Riccati)]
    pub sub_problem_solver: SubProblemSolverArg,
    /// With --generated: flags that narrow the family, as for `strafeopt gen`.
    #[command(flatten)]
    pub family: super::gen::FamilyFlags,
    /// Print no progress on stderr.
    #[arg(long, short = 'q')]
    pub quiet: bool,
}

/// The search settings of each solve of `--generated` or `--staircase`: the level's, with the time
/// limit and the sub-problems' solver given.
pub fn search_settings(args: &BenchArgs, q: Quality) -> Result<SearchSettings> {
    let mut settings = SearchSettings::for_quality(q);
    settings.time_limit = args.time_limit.map(time_limit).transpose()?;
    settings.sub_problem_solver = args.sub_problem_solver.solver();
    Ok(settings)
}

/// The width of a `[bend90]` shorthand, if the file has one.
fn bend_width(path: &Path) -> Option<f64> {
    let text = std::fs::read_to_string(path).ok()?;
    SceneFile::from_toml_str(&text)
        .ok()?
        .bend90
        .map(|b| b.width)
}

/// Runs `bench` and returns what to print.
pub fn run(args: &BenchArgs) -> Result<String> {
    if args.generated.is_some() {
        return super::bench_generated::run(args);
    }
    if !args.staircase.is_empty() {
        return super::bench_staircase::run(args);
    }
    refuse_family_flags(args)?;
    let settings = scene_settings(args)?;
    let scenes = bench_scenes(args)?;
    let rows = measured_rows(args, &scenes, &settings)?;
    if let Some(path) = &args.svg {
        write_atomically(path, |w| write_accuracy_svg(&rows, w))?;
    }
    if args.json {
        let text = serde_json::to_string(&rows)
            .map_err(|e| Error::Io(format!("serialising the rows: {e}")))?;
        Ok(format!("{text}\n"))
    } else {
        Ok(table(&rows))
    }
}

/// The flags of the generated family and its level, refused for scene files.
fn refuse_family_flags(args: &BenchArgs) -> Result<()> {
    if args.quality.is_some() {
        return Err(Error::InvalidValue {
            name: "--quality".to_string(),
            value: "given for scene files".to_string(),
            allowed: "given with --generated or --staircase (for scene files, --levels)"
                .to_string(),
        });
    }
    if let Some(flag) = args.family.first_given() {
        return Err(Error::InvalidValue {
            name: flag.to_string(),
            value: "given without --generated".to_string(),
            allowed: "given with --generated (it narrows the generated family)".to_string(),
        });
    }
    Ok(())
}

/// The settings of a bench over scene files: the levels (in order, each once), the hill climber, its
/// seed, and the limits.
fn scene_settings(args: &BenchArgs) -> Result<BenchSettings> {
    let mut settings = BenchSettings {
        hill_climb: !args.no_hill_climb,
        ..BenchSettings::default()
    };
    if let Some(seed) = args.seed {
        settings.seed = seed;
    }
    if !args.levels.is_empty() {
        let mut levels: Vec<Quality> = args.levels.iter().map(|q| q.quality()).collect();
        levels.sort_by_key(|q| match q {
            Quality::Fast => 0,
            Quality::Balanced => 1,
            Quality::Exact => 2,
        });
        levels.dedup();
        settings.levels = levels;
    } else if args.quick {
        settings.levels = vec![Quality::Fast];
    }
    if let Some(s) = args.time_limit {
        settings.time_limit = Some(time_limit(s)?);
    }
    if let Some(n) = args.max_frames {
        settings.max_frames = super::solve::max_frames(n)?;
    }
    if !(args.scaling_fps.is_finite() && args.scaling_fps > 0.0) {
        return Err(Error::invalid(
            "--scaling-fps",
            args.scaling_fps,
            "a finite number above 0",
        ));
    }
    Ok(settings)
}

/// The scenes to measure (the given files, else the default set), each with its bend's width; every
/// scene is loaded before anything is measured, so a bad file fails at once.
fn bench_scenes(args: &BenchArgs) -> Result<Vec<(Scene, Option<f64>)>> {
    let paths: Vec<PathBuf> = if args.scenes.is_empty() {
        DEFAULT_SCENES
            .iter()
            .filter(|p| !(args.quick && p.contains("1000fps")))
            .map(PathBuf::from)
            .collect()
    } else {
        args.scenes.clone()
    };
    paths
        .iter()
        .map(|p| Scene::load(p).map(|s| (s, bend_width(p))))
        .collect()
}

/// Every scene measured at every level, then (unless `--quick` or `--no-scaling`) the first scene's
/// frame-rate scaling.
fn measured_rows(
    args: &BenchArgs,
    scenes: &[(Scene, Option<f64>)],
    settings: &BenchSettings,
) -> Result<Vec<BenchRow>> {
    let mut rows = Vec::new();
    let bar = progress::spinner(progress::wanted(args.json, args.quiet));
    bar.set_prefix("bench");
    for (i, (scene, width)) in scenes.iter().enumerate() {
        bar.set_message(format!(
            "scene {} of {}: {} (every level)",
            i + 1,
            scenes.len(),
            scene.name
        ));
        rows.extend(measure_scene(scene, *width, settings)?);
    }
    if !(args.quick || args.no_scaling) {
        if let Some((scene, _)) = scenes.first() {
            if scene.vars.fps != args.scaling_fps {
                bar.set_message(format!(
                    "frame-rate scaling: {} at {} fps",
                    scene.name,
                    super::solve::fps_text(args.scaling_fps)
                ));
                let q = settings.levels.first().copied().unwrap_or(Quality::Fast);
                rows.extend(measure_scaling(scene, args.scaling_fps, q, settings)?);
            }
        }
    }
    bar.finish_and_clear();
    Ok(rows)
}

fn opt<T>(v: Option<T>, f: impl Fn(T) -> String) -> String {
    v.map_or_else(|| "-".to_string(), f)
}

/// The rows as an aligned text table (accuracy, then scaling).
pub fn table(rows: &[BenchRow]) -> String {
    let header = [
        "scene", "fps", "method", "level", "wall (s)", "frames", "time (s)", "valid", "gap",
        "iters", "evals", "notes",
    ];
    let mut cells: Vec<[String; 12]> = Vec::with_capacity(rows.len());
    for r in rows {
        let mut notes = r.status.clone().unwrap_or_default();
        if let Some(v) = r.corner_speed_ups {
            notes = format!("{notes}; corner speed {v:.1} ups");
        }
        if let (Some(w), Some(f)) = (r.wall_ratio, r.frames_ratio) {
            notes = format!("{notes}; {w:.2}x wall time, {f:.2}x frames");
        }
        cells.push([
            r.scene.clone(),
            super::solve::fps_text(r.fps),
            r.method.name().to_string(),
            opt(r.quality, |q| quality_name(q).to_string()),
            format!("{:.3}", r.wall_seconds),
            opt(r.frames, |f| f.to_string()),
            opt(r.time, |t| format!("{t:.6}")),
            opt(r.feasible, |v| if v { "yes" } else { "no" }.to_string()),
            opt(r.gap, |g| format!("{:+.3}%", 100.0 * g)),
            opt(r.iterations, |i| i.to_string()),
            opt(r.evaluations, |e| e.to_string()),
            notes,
        ]);
    }
    // Text columns left-aligned, numbers right-aligned; the notes column is not padded.
    let right_aligned = [
        false, true, false, false, true, true, true, false, true, true, true, false,
    ];
    let widths = column_widths(&header, &cells);
    let line = |c: &[String]| aligned_line(c, &widths, &right_aligned);
    let mut out = String::new();
    for (title, section) in [
        ("accuracy against time", Section::Accuracy),
        ("frame-rate scaling", Section::Scaling),
    ] {
        let part: Vec<&[String; 12]> = rows
            .iter()
            .zip(&cells)
            .filter(|(r, _)| r.section == section)
            .map(|(_, c)| c)
            .collect();
        if part.is_empty() {
            continue;
        }
        if !out.is_empty() {
            out.push('\n');
        }
        out.push_str(title);
        out.push('\n');
        out.push_str(&line(&header.map(String::from)));
        for c in part {
            out.push_str(&line(c));
        }
    }
    out
}
