//! Command-line arguments (stage one of two, as in ripgrep): clap types that mirror the flags and validate
//! only what was typed. [`super::calc`] resolves them into library values; the library never sees clap.

use clap::{Args, Parser, Subcommand, ValueEnum};
use std::path::PathBuf;

/// strafeopt: minimal-time strafing paths for Half-Life and Half-Life 2 movement.
#[derive(Debug, Parser)]
#[command(name = "strafeopt", version, about, propagate_version = true)]
pub struct Cli {
    /// What to do.
    #[command(subcommand)]
    pub command: Command,
}

/// The commands.
#[derive(Debug, Subcommand)]
pub enum Command {
    /// Figures from the physics reference: closed forms beside frame-by-frame simulation.
    Calc(CalcArgs),
    /// Simulate a scene with a controller; print its time beside the lower bound.
    Simulate(SimulateArgs),
    /// Find the minimal-time control sequence through a scene.
    Solve(SolveArgs),
    /// Turn a saved `--json` result into a self-contained HTML report.
    Report(ReportArgs),
    /// Measure what accuracy costs in time: every level from the lower bound to the engine-exact plan.
    Bench(super::bench::BenchArgs),
    /// Run every scene that carries an `[expect]` table and report whether a result got worse.
    Check(CheckArgs),
    /// Serve the planner page on a local port: edit a corridor, see the optimal and greedy lines.
    Serve(ServeArgs),
    /// Write random valid corridors (seeded) as scene files.
    Gen(super::gen::GenArgs),
}

/// `strafeopt check [PATHS...]`
#[derive(Debug, Args)]
pub struct CheckArgs {
    /// Scene files, or folders searched recursively for `*.toml` (default: the current folder).
    pub paths: Vec<PathBuf>,
    /// Scenes checked at once (default: the number of cores).
    #[arg(long, value_parser = clap::value_parser!(u16).range(1..))]
    pub jobs: Option<u16>,
    /// Rewrite each scene's `[expect]` values from the current results (comments and layout kept).
    #[arg(long)]
    pub update: bool,
    /// Also write a JUnit XML report.
    #[arg(long)]
    pub junit: Option<PathBuf>,
    #[command(flatten)]
    #[allow(missing_docs)]
    pub output: OutputFlags,
}

/// `strafeopt serve [SCENE] [--port N]`
#[derive(Debug, Args)]
pub struct ServeArgs {
    /// The scene the page starts from (TOML; default: a 90-degree bend at 100 fps).
    pub scene: Option<PathBuf>,
    /// Port to listen on (0: any free port; the address is printed).
    #[arg(long, default_value_t = 8377)]
    pub port: u16,
    /// Address to listen on instead of 127.0.0.1 (warns: anyone who can reach it can run solves).
    #[arg(long)]
    pub bind: Option<std::net::IpAddr>,
    /// The quality the page starts with.
    #[arg(long, value_enum, default_value_t = QualityArg::Fast)]
    pub quality: QualityArg,
    /// Stop each solve after this many seconds with the best valid plan so far.
    #[arg(long, default_value_t = 20.0, allow_negative_numbers = true)]
    pub time_limit: f64,
}

/// Output files every run can write besides `--trajectory`.
#[derive(Debug, Args, Clone, Default)]
pub struct ArtifactFlags {
    /// Write the trajectory, one row per frame (`.csv`, or `.json` for JSON).
    #[arg(long)]
    pub trajectory: Option<PathBuf>,
    /// Write a self-contained HTML report with figures.
    #[arg(long)]
    pub report: Option<PathBuf>,
    /// Write the plan as a Bunnymod XT TAS script (GoldSrc scenes).
    #[arg(long)]
    pub hltas: Option<PathBuf>,
}

/// Accuracy levels of `solve`, cheapest first. At every level the plan is checked in f64 and in the
/// engine-exact mode; on airborne scenes every level solves the relaxed problem, rounds it to the game's
/// sides and polishes the plan; `balanced` and `exact` polish it on at half the wall margin, and `exact`
/// on again at the certificate's margin (`SearchSettings::for_quality`); on scenes with jumps, the levels
/// differ in the grids searched.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum QualityArg {
    /// The fewest iterations and a coarse tolerance.
    Fast,
    /// The default: `fast`, then its plan polished on at half the wall margin (0.01 units) with a finer
    /// tolerance and more iterations.
    Balanced,
    /// `balanced`, then on airborne scenes its plan polished on again at the certificate's wall margin
    /// (0.002 units), the smallest the search holds; a plan is kept only where it is faster.
    Exact,
}

/// Solvers of the convexified sub-steps (`SubProblemSolver`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum SubProblemSolverArg {
    /// Frame by frame (a Riccati recursion inside an interior-point method), Clarabel where it gives
    /// no solution.
    Riccati,
    /// Clarabel on every sub-problem (slower; the same problems, for comparison).
    Clarabel,
}

impl QualityArg {
    /// The library's level.
    pub fn quality(self) -> crate::optimise::Quality {
        match self {
            QualityArg::Fast => crate::optimise::Quality::Fast,
            QualityArg::Balanced => crate::optimise::Quality::Balanced,
            QualityArg::Exact => crate::optimise::Quality::Exact,
        }
    }
}

impl SubProblemSolverArg {
    /// The library's solver.
    pub fn solver(self) -> crate::optimise::qp::SubProblemSolver {
        match self {
            SubProblemSolverArg::Riccati => crate::optimise::qp::SubProblemSolver::Riccati,
            SubProblemSolverArg::Clarabel => crate::optimise::qp::SubProblemSolver::Clarabel,
        }
    }
}

/// `strafeopt solve SCENE ...`
#[derive(Debug, Args)]
pub struct SolveArgs {
    /// The scene file (TOML).
    pub scene: PathBuf,
    /// How hard to work. At every level the plan is checked in f64 and in the engine-exact mode (an
    /// airborne plan after its sides are rounded to the game's and it is polished).
    #[arg(long, value_enum, default_value_t = QualityArg::Balanced)]
    pub quality: QualityArg,
    /// Stop after this many seconds (every stage, writing included) with the best valid plan so far.
    #[arg(long, allow_negative_numbers = true)]
    pub time_limit: Option<f64>,
    /// Most frames to plan: a scene whose fastest possible run needs more is refused at once, and no run
    /// is simulated further (default 100000, about 1.2 GB at the peak; see docs/limits.md).
    #[arg(long)]
    pub max_frames: Option<u64>,
    /// Solver of the convexified sub-steps.
    #[arg(long, value_enum, default_value_t = SubProblemSolverArg::Riccati)]
    pub sub_problem_solver: SubProblemSolverArg,
    #[command(flatten)]
    #[allow(missing_docs)]
    pub artifacts: ArtifactFlags,
    #[command(flatten)]
    #[allow(missing_docs)]
    pub output: OutputFlags,
}

/// `strafeopt report RESULT.json -o out.html`
#[derive(Debug, Args)]
pub struct ReportArgs {
    /// A result saved from `simulate --json` or `solve --json`.
    pub result: PathBuf,
    /// Where to write the HTML.
    #[arg(short = 'o', long = "output")]
    pub output: PathBuf,
}

/// Controllers `simulate` can run.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum ControllerArg {
    /// Maximum acceleration, steering left or right towards a look-ahead point on the shortest path.
    Greedy,
    /// The greedy strafer, turning harder than maximum acceleration where its look-ahead target needs it:
    /// the frame that turns far enough for the least speed (docs/physics.md section 9).
    SharpTurns,
    /// Maximum acceleration turning left every frame.
    MaxAccelLeft,
    /// Maximum acceleration turning right every frame.
    MaxAccelRight,
    /// Accelerated backhopping (Source scenes; docs/physics.md section 11): stand up, walk, a forward jump, then
    /// ducked backhops facing backwards, steering on the jump frames to hold the lane.
    Abh,
}

/// `strafeopt simulate SCENE ...`
#[derive(Debug, Args)]
pub struct SimulateArgs {
    /// The scene file (TOML).
    pub scene: PathBuf,
    /// Who steers.
    #[arg(long, value_enum, default_value_t = ControllerArg::Greedy)]
    pub controller: ControllerArg,
    /// Greedy look-ahead distance, units (default: the best of a sweep from 25 to 1200).
    #[arg(long, allow_negative_numbers = true)]
    pub lookahead: Option<f64>,
    #[command(flatten)]
    #[allow(missing_docs)]
    pub artifacts: ArtifactFlags,
    #[command(flatten)]
    #[allow(missing_docs)]
    pub output: OutputFlags,
}

/// `strafeopt calc FORM ...`
#[derive(Debug, Args)]
pub struct CalcArgs {
    /// Which figure.
    #[command(subcommand)]
    pub form: CalcForm,
}

/// The `calc` forms (the flattened `engine`/`output` fields are the common flags).
#[allow(missing_docs)]
#[derive(Debug, Subcommand)]
pub enum CalcForm {
    /// Frames of maximum-acceleration strafing from one speed to another (closed form and stepping).
    FramesToSpeed {
        /// Start speed, ups.
        #[arg(long, allow_negative_numbers = true)]
        from: f64,
        /// Target speed, ups.
        #[arg(long, allow_negative_numbers = true)]
        to: f64,
        /// Groundstrafe (friction, ground acceleration) instead of airstrafe.
        #[arg(long)]
        ground: bool,
        #[command(flatten)]
        engine: EngineFlags,
        #[command(flatten)]
        output: OutputFlags,
    },
    /// The steady groundstrafe speed (closed form and simulated until it settles).
    MaxGroundSpeed {
        /// Apply edge friction (`e_f`, 2 by default).
        #[arg(long)]
        edge_friction: bool,
        #[command(flatten)]
        engine: EngineFlags,
        #[command(flatten)]
        output: OutputFlags,
    },
    /// Turn radius of maximum-acceleration airstrafing at a speed: the source text's relation and the
    /// circle through three simulated positions.
    Radius {
        /// Speed, ups.
        #[arg(long, allow_negative_numbers = true)]
        speed: f64,
        #[command(flatten)]
        engine: EngineFlags,
        #[command(flatten)]
        output: OutputFlags,
    },
    /// The speed whose maximum-acceleration turn has a given radius (root finder on the measured relation).
    SpeedForRadius {
        /// Radius, units.
        #[arg(long, allow_negative_numbers = true)]
        radius: f64,
        #[command(flatten)]
        engine: EngineFlags,
        #[command(flatten)]
        output: OutputFlags,
    },
    /// Largest arc through a 90-degree bend of a given width, (2 + sqrt 2)(D - hull width), and its speed.
    Bend {
        /// Corridor width D, units.
        #[arg(long, allow_negative_numbers = true)]
        width: f64,
        #[command(flatten)]
        engine: EngineFlags,
        #[command(flatten)]
        output: OutputFlags,
    },
    /// The accelerated-backhop article's per-hop table and the time the line is crossed.
    Abh {
        /// Max speed Mx, ups (150 without the suit).
        #[arg(long, default_value_t = 150.0, allow_negative_numbers = true)]
        max_speed: f64,
        /// Time of one hop, seconds (GAMEMOVEMENT_JUMP_TIME).
        #[arg(long, default_value_t = 0.51, allow_negative_numbers = true)]
        hop_time: f64,
        /// Distance to the line, units (100 m = 5249.34).
        #[arg(long, default_value_t = 5249.34, allow_negative_numbers = true)]
        distance: f64,
        #[command(flatten)]
        engine: EngineFlags,
        #[command(flatten)]
        output: OutputFlags,
    },
}

/// Engine presets on the command line.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum PresetArg {
    /// Half-Life defaults (1000 fps unless --fps).
    Goldsrc,
    /// Half-Life 2 defaults (66.67 ticks/s unless --fps).
    #[value(name = "source-hl2")]
    SourceHl2,
}

/// The movement variables common to every form.
#[derive(Debug, Args, Clone, Default)]
pub struct EngineFlags {
    /// Engine defaults to start from.
    #[arg(long, value_enum)]
    pub preset: Option<PresetArg>,
    /// Frames per second (frame time 1/fps).
    #[arg(long, allow_negative_numbers = true)]
    pub fps: Option<f64>,
    /// sv_accelerate.
    #[arg(long, allow_negative_numbers = true)]
    pub accelerate: Option<f64>,
    /// sv_airaccelerate.
    #[arg(long, allow_negative_numbers = true)]
    pub airaccelerate: Option<f64>,
    /// sv_maxspeed, ups.
    #[arg(long, allow_negative_numbers = true)]
    pub maxspeed: Option<f64>,
    /// sv_friction.
    #[arg(long, allow_negative_numbers = true)]
    pub friction: Option<f64>,
    /// sv_stopspeed, ups.
    #[arg(long, allow_negative_numbers = true)]
    pub stopspeed: Option<f64>,
    /// sv_maxvelocity, ups (each component).
    #[arg(long, allow_negative_numbers = true)]
    pub maxvelocity: Option<f64>,
    /// sv_gravity, ups per second.
    #[arg(long, allow_negative_numbers = true)]
    pub gravity: Option<f64>,
    /// Entity (surface) friction k_e.
    #[arg(long, allow_negative_numbers = true)]
    pub entity_friction: Option<f64>,
}

/// Output format.
#[derive(Debug, Args, Clone, Copy, Default)]
pub struct OutputFlags {
    /// Print one JSON object instead of text.
    #[arg(long)]
    pub json: bool,
    /// Print no progress on stderr.
    #[arg(long, short = 'q')]
    pub quiet: bool,
}
