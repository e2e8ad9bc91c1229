//! The minimal-time search: a solve reads as its stages in order.
//!
//! 1. Seed and baseline ([`super::baseline`]): the greedy strafer's best valid run, the comparison, and a
//!    clean run the planning model can follow, the search's start.
//! 2. The relaxed problem ([`super::relaxed`]): sides continuous in `[-1, 1]`, coarse to fine, the frame
//!    count lowered until the line can no longer be reached, by sequential quadratic programming
//!    ([`super::scp`]) whose sub-steps Clarabel solves ([`super::qp`]).
//! 3. Rounding and polish ([`super::rounding`], [`super::polish`]): the sides rounded to `+-1`, then `c`
//!    polished with the sides fixed at the final wall margin.
//! 4. Quantise and verify ([`super::verify`]): yaws on anglemod steps, the plan re-simulated in f64 and in
//!    the engine-exact mode; the fastest valid plan is kept, polished on while it gets faster (airborne
//!    scenes), and greedy stays the answer when it is faster.
//! 5. At `balanced` and `exact` ([`FinePolish`]), that plan polished on again at smaller wall margins
//!    ([`super::airborne::plan_polished_finely`]): half the final margin, and at `exact` then the
//!    certificate's.
//!
//! 6. Where the answer of an airborne scene is then a greedy run sliding along a solid wall (ahead of every
//!    plan clear of the walls, which is all the planning model holds), that run kept as played through
//!    a wall contact and the rest solved by stages 1 to 5 from there ([`super::after_contact`]).
//!
//! Jumping scenes go to the jump planner ([`super::jumps`]) after stage 1.

use super::after_contact::planned_on_after_wall_contacts;
use super::airborne::{plan_airborne, plan_polished_finely, AirbornePlan};
use super::baseline::{baseline, corner_caps, given_up_frame, GreedyGuide, GuideRun};
use super::bound::{frame_limited_scene, lower_bound_within};
use super::model::FrameControl;
use super::planner::Planner;
use super::qp::SubProblemSolver;
use super::relaxed::{RelaxedCertificate, CERTIFICATE_MARGIN_UNITS};
use super::verify::time_of;
use super::LowerBound;
use crate::budget::{Budget, Stage, Stop};
use crate::error::{Error, Result};
use crate::physics::Control;
use crate::scene::Scene;
use crate::sim::{EngineRun, Simulation, Trace};
use std::sync::atomic::AtomicBool;
use std::time::{Duration, Instant};

/// How hard `solve` works.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum Quality {
    /// The relaxed problem with a coarse tolerance, rounded, briefly polished.
    Fast,
    /// Fast, its plan then polished on at half the wall margin with a finer tolerance and more
    /// iterations ([`FinePolish`]).
    Balanced,
    /// Balanced, its plan then polished on again at the certificate's wall margin, the smallest the
    /// search holds ([`FinePolish`]).
    Exact,
}

/// The last polishes of the fastest plan, after the final polish, at smaller wall margins than the search
/// before them, one after another, with a finer tolerance and more iterations than `fast`'s (`balanced`'s
/// and `exact`'s): the plan is polished on from its own controls, and a plan is kept only where it is
/// faster, so a level with them is never slower than its search without them.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct FinePolish {
    /// Wall margins of the polished plans, in the order polished, units.
    pub margins_units: &'static [f64],
    /// SCP iterations of each of its stages.
    pub polish_iters: u64,
    /// Stop when the predicted improvement is below this, units of progress.
    pub tol_progress_units: f64,
}

/// The wall margin of `fast`'s plans, units: room for the engine's f32 arithmetic and anglemod (a plan
/// is kept only if its engine-exact replay is valid too, so the finer polishes may go closer).
const FINAL_MARGIN_UNITS: f64 = 0.02;

/// The margin of the first last polish, units: half the final margin.
const HALF_FINAL_MARGIN_UNITS: f64 = 0.5 * FINAL_MARGIN_UNITS;

/// `balanced`'s last polish: at half the final margin.
const BALANCED_MARGINS_UNITS: &[f64] = &[HALF_FINAL_MARGIN_UNITS];

/// `exact`'s last polishes: `balanced`'s, then at the certificate's margin, so that the plan and the
/// certificate are points of one problem.
const EXACT_MARGINS_UNITS: &[f64] = &[HALF_FINAL_MARGIN_UNITS, CERTIFICATE_MARGIN_UNITS];

/// Settings of the search, with their units. `Default` is `balanced`.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct SearchSettings {
    /// Accuracy level.
    pub quality: Quality,
    /// Wall margin of the final plan, units: room for the engine's f32 arithmetic and anglemod.
    pub margin_units: f64,
    /// SCP iterations per frame count, relaxed stage.
    pub relaxed_iters: u64,
    /// SCP iterations of the polishing stage.
    pub polish_iters: u64,
    /// Times, at most, a search over frame counts goes back to its best line's count when the count
    /// below it is not reached and the stage that found that line stopped at its iteration cap, still
    /// improving (0: never; the count below is then given up at once).
    pub capped_line_returns: usize,
    /// Times, at most, the fastest airborne plan is polished again from its own controls while it gets
    /// faster (0: never), each time in stages whose trust region regrows after a corrected step.
    pub final_polish_rounds: usize,
    /// Stop when the predicted improvement is below this, units of progress.
    pub tol_progress_units: f64,
    /// Weight of a unit of wall violation against a unit of progress.
    pub slack_weight: f64,
    /// Wall pieces farther than this from a frame's move are left out of its sub-problem, units.
    pub wall_radius_units: f64,
    /// Starts of the relaxed certificate, at most (the relaxed plan, then the other clean greedy runs).
    pub certificate_starts: usize,
    /// Stop with the best valid plan after this long.
    pub time_limit: Option<Duration>,
    /// Most frames a run is planned over: a scene whose lower bound needs more is refused
    /// ([`Error::FrameLimit`]), and no simulated run goes further (the scene's own cap, if lower, holds).
    pub max_frames: u64,
    /// The solver each convexified sub-step is given first.
    pub sub_problem_solver: SubProblemSolver,
    /// The last polishes of the fastest airborne plan at finer settings, if any (`balanced`'s and
    /// `exact`'s).
    pub fine_polish: Option<FinePolish>,
}

impl SearchSettings {
    /// The settings of a quality level.
    pub fn for_quality(quality: Quality) -> Self {
        // Every level searches as `fast` does; the dearer ones then polish its plan closer to the walls.
        let fast = SearchSettings {
            quality,
            margin_units: FINAL_MARGIN_UNITS,
            relaxed_iters: 25,
            polish_iters: 10,
            capped_line_returns: 3,
            final_polish_rounds: 3,
            tol_progress_units: 1e-3,
            slack_weight: 100.0,
            wall_radius_units: 40.0,
            certificate_starts: 2,
            time_limit: None,
            max_frames: crate::budget::DEFAULT_MAX_PLANNED_FRAMES,
            sub_problem_solver: SubProblemSolver::default(),
            fine_polish: None,
        };
        let fine_polish = |margins_units| {
            Some(FinePolish {
                margins_units,
                polish_iters: 40,
                tol_progress_units: 1e-6,
            })
        };
        match quality {
            Quality::Fast => fast,
            Quality::Balanced => SearchSettings {
                fine_polish: fine_polish(BALANCED_MARGINS_UNITS),
                ..fast
            },
            Quality::Exact => SearchSettings {
                fine_polish: fine_polish(EXACT_MARGINS_UNITS),
                ..fast
            },
        }
    }
}

impl Default for SearchSettings {
    fn default() -> Self {
        Self::for_quality(Quality::Balanced)
    }
}

/// Why the search ended, as a status (not an error).
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
#[serde(tag = "status", rename_all = "kebab-case")]
pub enum SearchStatus {
    /// The search converged; `gap` is the relative distance to the lower bound.
    Converged {
        /// `(time - bound) / bound`.
        gap: f64,
    },
    /// The time limit stopped it in `stopped_in`; the best valid plan so far is returned.
    TimeLimit {
        /// The stage that was cut.
        stopped_in: Stage,
    },
    /// The caller's cancel flag stopped it in `stopped_in`; the best valid plan so far is returned.
    Cancelled {
        /// The stage that was cut.
        stopped_in: Stage,
    },
    /// The greedy run is optimal: it crosses in the lower bound's frame, so no plan can cross earlier
    /// (the greedy run is returned).
    GreedyOptimal {
        /// Why, with the frames.
        reason: String,
    },
    /// The optimiser found no valid plan better than the greedy one (which is returned).
    NoImprovement {
        /// What went wrong, if anything.
        reason: String,
    },
}

impl SearchStatus {
    /// The status of a search cut by `budget` in `stage` (the time limit unless the cancel flag is set).
    pub fn stopped(budget: &Budget, stage: Stage) -> Self {
        match budget.stop() {
            Some(Stop::Cancelled) => SearchStatus::Cancelled { stopped_in: stage },
            _ => SearchStatus::TimeLimit { stopped_in: stage },
        }
    }

    /// The stage a budget cut, if one was.
    pub fn stopped_in(&self) -> Option<Stage> {
        match self {
            SearchStatus::TimeLimit { stopped_in } | SearchStatus::Cancelled { stopped_in } => {
                Some(*stopped_in)
            }
            _ => None,
        }
    }
}

impl std::fmt::Display for SearchStatus {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            SearchStatus::Converged { gap } => {
                write!(f, "converged, {:.3}% above the lower bound", 100.0 * gap)
            }
            SearchStatus::TimeLimit { stopped_in } => write!(
                f,
                "stopped by the time limit in the {stopped_in} stage, with the best valid plan so far"
            ),
            SearchStatus::Cancelled { stopped_in } => write!(
                f,
                "cancelled in the {stopped_in} stage, with the best valid plan so far"
            ),
            SearchStatus::GreedyOptimal { reason } => write!(f, "greedy is optimal: {reason}"),
            SearchStatus::NoImprovement { reason } => write!(f, "greedy plan returned: {reason}"),
        }
    }
}

/// Counts of the work done.
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize)]
pub struct SearchStats {
    /// SCP iterations (argmin).
    pub iterations: u64,
    /// Clarabel sub-problems solved.
    pub subproblems: u64,
    /// Sub-problems Clarabel could not solve (trust region shrunk).
    pub subproblem_failures: u64,
    /// Interior-point iterations of the solved sub-problems, by either solver.
    pub interior_point_iterations: u64,
    /// Sub-problems the frame-by-frame solver gave no solution for (a frame's reduced Hessian not
    /// positive definite where an active wall row meets an active bound, its iteration cap, or rows not
    /// a chain), each then given to Clarabel. They mark the hard scenes (docs/design.md, "Where
    /// gen-4848-1's time goes").
    pub handed_to_clarabel: u64,
    /// Steps rejected by exact re-simulation, their second-order correction too.
    pub rejected_steps: u64,
    /// Steps rejected by exact re-simulation but kept after a second-order correction (each such
    /// correction is one more sub-problem).
    pub corrected_steps: u64,
    /// Steps rejected as played open-loop but accepted played with the sub-problem's feedback (each
    /// such play one more simulation of the plan, no sub-problem).
    pub fed_steps: u64,
    /// Frame counts tried.
    pub frame_counts_tried: u64,
    /// Exact-side plans played through the real frame with the wish direction set as the game can set
    /// it (stage 4's replays; one the budget cut before its f64 run ended is not counted).
    pub replays: u64,
    /// Of those, the replays valid in f64 and in the engine-exact mode. Where most are not, the plans
    /// went off their planned paths when played, and the search polished its lines again at wider
    /// margins.
    pub valid_replays: u64,
}

impl SearchStats {
    /// Adds the work counted in `other`.
    pub(super) fn add(&mut self, other: &SearchStats) {
        self.iterations += other.iterations;
        self.subproblems += other.subproblems;
        self.subproblem_failures += other.subproblem_failures;
        self.interior_point_iterations += other.interior_point_iterations;
        self.handed_to_clarabel += other.handed_to_clarabel;
        self.rejected_steps += other.rejected_steps;
        self.corrected_steps += other.corrected_steps;
        self.fed_steps += other.fed_steps;
        self.frame_counts_tried += other.frame_counts_tried;
        self.replays += other.replays;
        self.valid_replays += other.valid_replays;
    }
}

/// Where a solve's time went: the wall-clock seconds of each of its stages on the solving thread, in the
/// order they run. Work on other threads is inside the stage it runs beside (the certificate's greedy
/// starts beside the relaxed line and the first plans, its start from the relaxed line beside the first
/// plans), so the stages add up to the solve, less the moments between them. A stage that does not run
/// takes 0.
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize)]
pub struct StageSeconds {
    /// The lower bound (the shortest path and its speed profile, or the jump schedules).
    pub bound: f64,
    /// The greedy baseline over its guides, and the seed.
    pub baseline: f64,
    /// The relaxed line from the seed: its count search, coarse to fine.
    pub relaxed_line: f64,
    /// The relaxed line rounded, polished and verified.
    pub first_plans: f64,
    /// The first plans done, the wait for the certificate's starts still running on other threads (its
    /// greedy starts, and its start from the relaxed line).
    pub certificate_wait: f64,
    /// The certificate's lines rounded: a greedy start's line of the plan's frame, another optimum, and the
    /// faster lines the certificate finds from the plan.
    pub certificate_lines: f64,
    /// The plan polished on from its own controls, a failed plan polished wider, and the certificate
    /// started from the polished plan.
    pub polish_on: f64,
    /// The certificate's fastest line refined and rounded at the final margin where the plan is still a
    /// frame behind it.
    pub final_margin_round: f64,
    /// The polishes at smaller wall margins of `balanced` and `exact`.
    pub fine_polish: f64,
    /// The policy search of a scene with jumps or ground frames, its plan's verification included.
    pub jumps: f64,
    /// The plan replayed in the engine-exact mode, and the certificate's estimates.
    pub verification: f64,
    /// A greedy answer sliding along a wall, planned on from after its wall contacts: the rests' solves
    /// and the plans played whole.
    pub after_contact: f64,
}

impl StageSeconds {
    /// Each stage's name, as the text output prints it, and its seconds, in the order the stages run.
    pub fn named(&self) -> [(&'static str, f64); 12] {
        [
            ("bound", self.bound),
            ("baseline", self.baseline),
            ("relaxed line", self.relaxed_line),
            ("first plans", self.first_plans),
            ("certificate wait", self.certificate_wait),
            ("certificate lines", self.certificate_lines),
            ("polish on", self.polish_on),
            ("final-margin round", self.final_margin_round),
            ("fine polish", self.fine_polish),
            ("jumps", self.jumps),
            ("verification", self.verification),
            ("after a wall contact", self.after_contact),
        ]
    }

    /// The stages' sum, seconds.
    pub fn total(&self) -> f64 {
        self.named().iter().map(|(_, s)| s).sum()
    }
}

/// The seconds since `started`.
pub(super) fn seconds_since(started: Instant) -> f64 {
    started.elapsed().as_secs_f64()
}

/// The result of `solve`.
#[derive(Clone, Debug)]
pub struct Outcome {
    /// The plan, one control per frame, yaws on anglemod steps.
    pub controls: Vec<Control>,
    /// The plan re-simulated in f64.
    pub trace: Trace,
    /// The plan in the engine-exact mode.
    pub engine_exact: EngineRun,
    /// The greedy baseline.
    pub greedy: Trace,
    /// The lower bound.
    pub bound: LowerBound,
    /// Why it stopped.
    pub status: SearchStatus,
    /// Work counts.
    pub stats: SearchStats,
    /// Wall-clock time of the solve, seconds.
    pub solve_seconds: f64,
    /// The plan's source: `greedy`, `optimised`, or the greedy run to a wall contact and then optimised
    /// ([`super::after_contact`]).
    pub source: &'static str,
    /// The guide and settings of the greedy strafer that gave the baseline.
    pub greedy_guide: GreedyGuide,
    /// The relaxed optimum the plan is measured against, on airborne scenes.
    pub relaxed: Option<RelaxedCertificate>,
    /// Where the solve's time went.
    pub stage_seconds: StageSeconds,
}

/// What the search is doing, for a progress display (the library prints nothing itself).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Progress {
    /// The greedy baseline and the lower bound are ready.
    Baseline {
        /// Greedy crossing frame, if it finished.
        greedy_frames: Option<u64>,
        /// The bound's crossing frame.
        bound_frames: u64,
    },
    /// A frame count was tried in the relaxed stage.
    FrameCount {
        /// The frame count.
        frames: usize,
        /// Frames per planning step: 1 frame by frame, more over knots (one control held for that many
        /// frames), the coarse stages of a long run.
        frames_per_step: u32,
        /// The frame in which that plan crosses the line, if it does without touching a wall.
        reached: Option<usize>,
    },
    /// Rounding, polishing and checking the plan.
    Finishing,
    /// Polishing the plan on at a smaller wall margin ([`FinePolish`]).
    Polishing {
        /// The wall margin, units.
        margin_units: f64,
    },
    /// Solving the rest of a greedy run that slides along a wall, after its first `kept_frames` frames
    /// as played ([`super::after_contact`]).
    AfterWallContact {
        /// The frames of the greedy run kept, from the scene's start.
        kept_frames: usize,
    },
}

impl Progress {
    /// The planning step of a tried frame count, in words (`frames_per_step` of
    /// [`Progress::FrameCount`]): nothing frame by frame.
    pub fn steps_text(frames_per_step: u32) -> String {
        if frames_per_step > 1 {
            format!(" over knots of {frames_per_step}")
        } else {
            String::new()
        }
    }

    /// Where a tried frame count's plan crosses the line, in words (`reached` of
    /// [`Progress::FrameCount`]).
    pub fn crossing_text(reached: Option<usize>) -> String {
        reached.map_or("not reached".to_string(), |r| {
            format!("crosses in frame {r}")
        })
    }
}

/// The report in words, as a progress display shows it.
impl std::fmt::Display for Progress {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Progress::Baseline {
                greedy_frames,
                bound_frames,
            } => {
                let greedy =
                    greedy_frames.map_or("did not finish".to_string(), |g| format!("frame {g}"));
                write!(f, "greedy {greedy}, lower bound frame {bound_frames}")
            }
            Progress::FrameCount {
                frames,
                frames_per_step,
                reached,
            } => {
                write!(
                    f,
                    "trying {frames} frames{}: {}",
                    Progress::steps_text(*frames_per_step),
                    Progress::crossing_text(*reached)
                )
            }
            Progress::Finishing => {
                write!(
                    f,
                    "rounding sides, polishing, checking in engine-exact mode"
                )
            }
            Progress::Polishing { margin_units } => {
                write!(
                    f,
                    "polishing the plan on at a wall margin of {margin_units} units"
                )
            }
            Progress::AfterWallContact { kept_frames } => {
                write!(
                    f,
                    "the greedy run slides along a wall: planning on after its frame {kept_frames}"
                )
            }
        }
    }
}

/// The minimal-time plan of `scene` (see the module documentation). Errors only for bad input or a scene
/// with no valid path ([`Error::NoValidPath`]); everything else is a [`SearchStatus`].
pub fn solve(scene: &Scene, settings: &SearchSettings) -> Result<Outcome> {
    solve_with_progress(scene, settings, &mut |_| {})
}

/// [`solve`], reporting what it does to `progress`.
///
/// `balanced` is `fast`'s search with its plan polished on at half the wall margin ([`FinePolish`]), and
/// `exact` is `balanced` with that plan polished on again at the certificate's margin. A polish keeps a
/// plan only where it is faster: `balanced` is never slower than `fast`, nor `exact` than `balanced`, and
/// a time limit that cuts a polish leaves the plan before it.
pub fn solve_with_progress(
    scene: &Scene,
    settings: &SearchSettings,
    progress: &mut dyn FnMut(Progress),
) -> Result<Outcome> {
    solve_within(
        scene,
        settings,
        Budget::from_limit(settings.time_limit, None),
        progress,
    )
}

/// [`solve_with_progress`] that also stops when `cancel` is set: a set flag acts like the time limit
/// expiring at once, in whatever stage is running. The best valid plan so far is returned with status
/// [`SearchStatus::Cancelled`] naming that stage; [`Error::Stopped`] when nothing valid was found yet.
/// For callers that replace a solve by a newer one (an editor re-solving after every edit).
pub fn solve_cancellable(
    scene: &Scene,
    settings: &SearchSettings,
    progress: &mut dyn FnMut(Progress),
    cancel: &AtomicBool,
) -> Result<Outcome> {
    solve_within(
        scene,
        settings,
        Budget::from_limit(settings.time_limit, Some(cancel)),
        progress,
    )
}

/// What every outcome of one solve shares: the simulation, the baseline, the bound, the start time.
struct Finisher<'a> {
    sim: &'a Simulation<'a>,
    greedy: &'a GuideRun,
    bound: &'a LowerBound,
    started: Instant,
}

impl Finisher<'_> {
    /// The outcome of a plan: `controls` and their f64 `trace`, checked in the engine-exact mode.
    fn outcome(
        &self,
        controls: Vec<Control>,
        trace: Trace,
        status: SearchStatus,
        stats: SearchStats,
        source: &'static str,
    ) -> Outcome {
        let engine_exact = self.sim.run_engine_exact(&controls);
        Outcome {
            controls,
            trace,
            engine_exact,
            greedy: self.greedy.trace.clone(),
            bound: self.bound.clone(),
            status,
            stats,
            solve_seconds: self.started.elapsed().as_secs_f64(),
            source,
            greedy_guide: self.greedy.guide,
            relaxed: None,
            stage_seconds: StageSeconds::default(),
        }
    }

    /// The baseline itself as the outcome (its yaws as planned: the engine-exact replay applies anglemod,
    /// and quantising them here could cost the frame that makes the plan no worse than greedy).
    fn greedy_outcome(&self, status: SearchStatus, stats: SearchStats) -> Outcome {
        self.outcome(
            self.greedy.trace.controls.clone(),
            self.greedy.trace.clone(),
            status,
            stats,
            "greedy",
        )
    }
}

/// The solve of every entry point, at `settings` within `budget` (see [`solve_with_progress`]): the
/// stages of the module documentation in order, then on airborne scenes, where the answer is a greedy
/// run sliding along a solid wall, that run planned on from after its wall contacts
/// ([`super::after_contact`]).
fn solve_within(
    scene: &Scene,
    settings: &SearchSettings,
    budget: Budget,
    progress: &mut dyn FnMut(Progress),
) -> Result<Outcome> {
    let started = Instant::now();
    let outcome = solve_stages(scene, settings, budget, progress)?;
    if !scene.effects.is_air_only() {
        return Ok(outcome);
    }
    let after_contact_started = Instant::now();
    let mut solve_rest = |rest: &Scene, kept_frames: usize| {
        progress(Progress::AfterWallContact { kept_frames });
        solve_stages(rest, settings, budget, &mut |_| {})
    };
    let outcome = planned_on_after_wall_contacts(
        scene,
        settings.margin_units,
        outcome,
        &budget,
        &mut solve_rest,
    );
    Ok(Outcome {
        solve_seconds: seconds_since(started),
        stage_seconds: StageSeconds {
            after_contact: seconds_since(after_contact_started),
            ..outcome.stage_seconds
        },
        ..outcome
    })
}

/// The stages of the module documentation in order, on `scene` at `settings` within `budget`.
fn solve_stages(
    scene: &Scene,
    settings: &SearchSettings,
    budget: Budget,
    progress: &mut dyn FnMut(Progress),
) -> Result<Outcome> {
    let started = Instant::now();
    let mut seconds = StageSeconds::default();
    let bound = lower_bound_within(scene, &scene.corridor()?, &budget)?;
    seconds.bound = seconds_since(started);
    let baseline_started = Instant::now();
    let scene = &frame_limited_scene(scene, &bound, settings.max_frames)?;
    let sim = Simulation::new(scene)?;
    if budget.expired() {
        return Err(Error::stopped(budget.stop(), Stage::LowerBound));
    }
    // Stage 1: seed and baseline.
    let base = baseline(&sim, scene, &bound, &budget);
    seconds.baseline = seconds_since(baseline_started);
    let greedy = &base.greedy.trace;
    let seed = base.seed();
    if budget.expired() && !greedy.feasible() {
        return Err(Error::stopped(budget.stop(), Stage::Greedy));
    }
    progress(Progress::Baseline {
        greedy_frames: greedy.crossing.map(|c| c.frames),
        bound_frames: bound.crossing.frames,
    });
    let finisher = Finisher {
        sim: &sim,
        greedy: &base.greedy,
        bound: &bound,
        started,
    };
    if !scene.effects.is_air_only() {
        let jumps_from_s = seconds_since(started);
        let outcome = plan_jumping_scene(&finisher, settings, budget);
        seconds.jumps = outcome.solve_seconds - jumps_from_s;
        return Ok(Outcome {
            stage_seconds: seconds,
            ..outcome
        });
    }
    let mut planner = Planner::new(scene, &sim, settings, &bound, seed, budget);
    let (warm, n, lo) = planning_start(&planner, seed, &bound);
    // Stages 2 to 4, then 5 where the settings ask for it.
    let greedy_s = time_of(greedy);
    let mut found = plan_airborne(&mut planner, &base, warm, n, lo, greedy_s, progress);
    if let Some(fine) = settings.fine_polish {
        planner.clocked(
            |s| &mut s.fine_polish,
            |planner| plan_polished_finely(planner, &mut found, fine, greedy_s, lo, progress),
        );
    }
    Ok(airborne_outcome(
        &finisher, &planner, found, &budget, seconds,
    ))
}

/// Where the relaxed stage starts from the seed run: the seed in planning controls, the frame count to
/// plan over, and the count below which no plan can cross (the bound's).
fn planning_start(
    planner: &Planner,
    seed: &Trace,
    bound: &LowerBound,
) -> (Vec<FrameControl>, usize, usize) {
    let warm = planner.warm_start(seed);
    let prefix_len = planner.prefix.len();
    // A seed that never reaches the line (no greedy run is valid) ran to the frame cap: planned over
    // that many frames, each count of the search takes tens of seconds. It is planned over as many
    // frames as the baseline gives an invalid run, and the search grows the count from there if need be.
    let n = match seed.crossing {
        Some(c) => (c.frames as usize).saturating_sub(prefix_len),
        None => {
            let given_up = usize::try_from(given_up_frame(bound)).unwrap_or(usize::MAX);
            warm.len().min(given_up.saturating_sub(prefix_len))
        }
    };
    // No plan crosses before the bound's frame.
    let lo = (bound.crossing.frames as usize).saturating_sub(1 + prefix_len);
    (warm, n, lo)
}

/// The outcome of an airborne solve from what its stages `found` (the greedy run's where they found no
/// plan faster), with its certificate, work and stage seconds (`seconds` holds the bound's and the
/// baseline's); the verification's seconds end here, so the stages add up to the solve's time.
fn airborne_outcome(
    finisher: &Finisher,
    planner: &Planner,
    found: AirbornePlan,
    budget: &Budget,
    seconds: StageSeconds,
) -> Outcome {
    let verification_from_s = seconds_since(finisher.started);
    let relaxed = found
        .certifier
        .certificate_with_estimates(&planner.start, &planner.fl);
    let stats = planner.stats;
    let stopped = planner
        .cut_in
        .filter(|_| planner.timed_out)
        .map(|stage| SearchStatus::stopped(budget, stage));
    let outcome = match found.best {
        Some((t, trace)) => {
            let status = stopped.unwrap_or(SearchStatus::Converged {
                gap: finisher.bound.gap(t),
            });
            finisher.outcome(trace.controls.clone(), trace, status, stats, "optimised")
        }
        None => {
            let reason = no_improvement_reason(found.relaxed_found, &stats);
            finisher.greedy_outcome(
                stopped.unwrap_or_else(|| SearchStatus::NoImprovement {
                    reason: reason.into(),
                }),
                stats,
            )
        }
    };
    let stage_seconds = StageSeconds {
        bound: seconds.bound,
        baseline: seconds.baseline,
        verification: outcome.solve_seconds - verification_from_s,
        ..planner.seconds
    };
    Outcome {
        relaxed,
        stage_seconds,
        ..outcome
    }
}

/// Why no optimised plan was returned, from whether the relaxed stage found a line and the replays
/// `stats` counted: none found, none of its plans replayed valid, or every plan that did was slower than
/// the greedy run (a greedy run that slides along a wall can be ahead of every plan clear of the walls).
fn no_improvement_reason(relaxed_found: bool, stats: &SearchStats) -> &'static str {
    if !relaxed_found {
        "the relaxed search found no valid plan"
    } else if stats.valid_replays == 0 {
        "no optimised plan stayed valid after rounding and quantisation"
    } else {
        "every optimised plan that stayed valid was slower than the greedy run"
    }
}

/// Scenes with ground frames, gravity or jumps: greedy when it already crosses in the bound's frame
/// (nothing can cross earlier); else the policy search of [`super::jumps`] (the Source jump boost) or of
/// [`super::hops`] (everything else). Each keeps a plan only if it is valid in f64 and engine-exact;
/// greedy stays the answer when it is faster.
fn plan_jumping_scene(finisher: &Finisher, settings: &SearchSettings, budget: Budget) -> Outcome {
    let mut stats = SearchStats::default();
    let greedy_status = super::hops::greedy_status(&finisher.greedy.trace, finisher.bound);
    if matches!(greedy_status, SearchStatus::GreedyOptimal { .. }) {
        return finisher.greedy_outcome(greedy_status, stats);
    }
    let scene = finisher.sim.scene();
    let path = &finisher.bound.path;
    let planned = super::jumps::plan_jumps(finisher.sim, settings, budget)
        .map(|p| (p.best.trace, p.evaluations, p.timed_out))
        .or_else(|| {
            let caps = corner_caps(scene, path);
            super::hops::plan_hops(finisher.sim, path, &caps, settings, budget)
                .map(|p| (p.best.trace, p.evaluations, p.timed_out))
        });
    if let Some((trace, evaluations, timed_out)) = planned {
        stats.iterations = evaluations;
        let t = time_of(&trace);
        if t < time_of(&finisher.greedy.trace) {
            let status = if timed_out {
                SearchStatus::stopped(&budget, Stage::Jumps)
            } else {
                SearchStatus::Converged {
                    gap: finisher.bound.gap(t),
                }
            };
            return finisher.outcome(trace.controls.clone(), trace, status, stats, "optimised");
        }
    }
    if budget.expired() {
        return finisher.greedy_outcome(SearchStatus::stopped(&budget, Stage::Jumps), stats);
    }
    finisher.greedy_outcome(greedy_status, stats)
}

/// Checks a time limit given in seconds.
pub fn time_limit(seconds: f64) -> Result<Duration> {
    match Duration::try_from_secs_f64(seconds) {
        Ok(d) if seconds > 0.0 => Ok(d),
        _ => Err(Error::invalid(
            "--time-limit",
            seconds,
            "a finite number of seconds above 0 and below about 1.8e19",
        )),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn each_progress_report_reads_with_its_own_figures() {
        let said = [
            Progress::Baseline {
                greedy_frames: Some(412),
                bound_frames: 398,
            },
            Progress::Baseline {
                greedy_frames: None,
                bound_frames: 398,
            },
            Progress::FrameCount {
                frames: 405,
                frames_per_step: 1,
                reached: Some(403),
            },
            Progress::FrameCount {
                frames: 402,
                frames_per_step: 1,
                reached: None,
            },
            Progress::FrameCount {
                frames: 2358,
                frames_per_step: 3,
                reached: Some(2358),
            },
            Progress::Finishing,
            Progress::Polishing {
                margin_units: 0.002,
            },
            Progress::AfterWallContact { kept_frames: 57 },
        ]
        .map(|p| p.to_string());
        assert_eq!(
            said,
            [
                "greedy frame 412, lower bound frame 398",
                "greedy did not finish, lower bound frame 398",
                "trying 405 frames: crosses in frame 403",
                "trying 402 frames: not reached",
                "trying 2358 frames over knots of 3: crosses in frame 2358",
                "rounding sides, polishing, checking in engine-exact mode",
                "polishing the plan on at a wall margin of 0.002 units",
                "the greedy run slides along a wall: planning on after its frame 57",
            ]
        );
    }

    #[test]
    fn every_level_searches_as_fast_and_each_dearer_one_polishes_on_closer_to_the_walls() {
        let [fast, balanced, exact] =
            [Quality::Fast, Quality::Balanced, Quality::Exact].map(SearchSettings::for_quality);
        for level in [balanced, exact] {
            let search = SearchSettings {
                quality: Quality::Fast,
                fine_polish: None,
                ..level
            };
            assert_eq!(search, fast, "{:?} searches as fast does", level.quality);
        }
        assert_eq!(fast.fine_polish, None);
        let margins = |s: SearchSettings| s.fine_polish.map_or(&[][..], |f| f.margins_units);
        // A dearer level polishes on from where the cheaper one ends, so it is never slower.
        assert!(margins(exact).starts_with(margins(balanced)));
        assert!(margins(exact).len() > margins(balanced).len());
        let mut wall_margin = fast.margin_units;
        for &m in margins(exact) {
            assert!(m < wall_margin, "{:?}", margins(exact));
            wall_margin = m;
        }
        // The last is the certificate's, the smallest the search holds.
        assert_eq!(margins(exact).last(), Some(&CERTIFICATE_MARGIN_UNITS));
    }

    #[test]
    fn time_limits_out_of_range_are_errors_not_panics() {
        for bad in [0.0, -1.0, f64::NAN, f64::INFINITY, 1e300] {
            assert!(time_limit(bad).is_err(), "{bad}");
        }
        assert_eq!(time_limit(2.5).ok(), Some(Duration::from_millis(2500)));
    }
}
