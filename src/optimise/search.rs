//! The minimal-time search (issue 5). Min-time is fixed-N maximal progress plus a search over N: for a
//! frame count N, sequential convex programming maximises how far past the finish line the player is after
//! frame N, keeping every frame's straight move clear of the walls by a margin; N is then lowered to the
//! frame before the plan's crossing until the line can no longer be reached. The fractional crossing time
//! of the re-simulated plan is the final measure.
//!
//! Each SCP iteration is an argmin [`Solver`] step ([`ScpSolver`]): the frame model ([`super::model`]) is
//! linearised around the current trajectory, Clarabel solves the convexified sub-step ([`super::qp`]), and
//! the step is accepted only after exact re-simulation confirms it (actual against predicted improvement,
//! a trust region in between). argmin's executor owns the loop, the iteration cap and the time limit.
//! From the second iteration on, the sub-step also carries the curvature of the Lagrangian, weighted by
//! the last sub-step's dynamics duals and convexified ([`super::lagrangian`]): a sequential quadratic
//! program. Its model is right to second order, so its steps are long where the linear model's were
//! not: on the 100 fps bend 32 sub-steps instead of 283, and a better plan (4.00146 s against 4.00196 s).
//!
//! Stages: (0) on long runs (at least twice [`COARSE_KNOTS`] frames), coarse to fine: the relaxed problem
//! over knots of several frames played with one control ([`knot`]: the same interface as a frame, so the
//! same SCP), its plan spread over the frames as the next stage's start; (1) the relaxed problem, sides
//! continuous in `[-1, 1]`, started from the best greedy run (seeded, where the greedy speed cannot take a
//! corner, by speed caps from the radius-speed relation);
//! (2) sides rounded to `+-1` by tracking the relaxed heading, then `c` polished with the sides fixed;
//! (3) yaws quantised to anglemod steps, the plan re-simulated in f64 and in the engine-exact mode.

use super::lagrangian::{convexify, lagrangian_block, CurvatureBlock};
use super::model::{
    control_for, frame, frame_control_of, knot, knot_hessian, rollout, rollout_knots, FrameControl,
    FrameLaw, ModelState,
};
use super::qp::{self, SubProblem, SubStepStatus, WallRow};
use super::{lower_bound, LowerBound};
use crate::error::{Error, Result};
use crate::geometry::{Corridor, Separation, HULL_HALF_WIDTH_UNITS};
use crate::physics::curvature::{air_law, bend_arc_radius, speed_for_radius};
use crate::physics::engine_exact::{anglemod_bracket, quantise_yaw_rad};
use crate::physics::{Control, PlayerState, Vec2};
use crate::scene::Scene;
use crate::sim::controllers::{best_capped_greedy, Greedy, GREEDY_LOOKAHEADS_UNITS};
use crate::sim::{Controller, EngineRun, Simulation, Trace};
use argmin::core::{
    CostFunction, Error as ArgminError, Executor, IterState, Problem, Solver, State,
    TerminationReason, TerminationStatus, KV,
};
use std::time::{Duration, Instant};

/// How hard `solve` works.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum Quality {
    /// The relaxed problem with a coarse tolerance, rounded, briefly polished.
    Fast,
    /// Relaxed, rounded, polished.
    Balanced,
    /// As balanced with tight tolerances and more iterations.
    Exact,
}

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
    /// Stop when the predicted improvement is below this, units of progress.
    pub tol_progress_units: f64,
    /// Weight of a unit of wall violation against a unit of progress.
    pub slack_weight: f64,
    /// Wall pieces farther than this from a frame's move are left out of its sub-problem, units.
    pub wall_radius_units: f64,
    /// Stop with the best valid plan after this long.
    pub time_limit: Option<Duration>,
}

impl SearchSettings {
    /// The settings of a quality level.
    pub fn for_quality(quality: Quality) -> Self {
        let base = SearchSettings {
            quality,
            margin_units: 0.02,
            relaxed_iters: 120,
            polish_iters: 40,
            tol_progress_units: 1e-6,
            slack_weight: 100.0,
            wall_radius_units: 40.0,
            time_limit: None,
        };
        match quality {
            Quality::Fast => SearchSettings {
                relaxed_iters: 25,
                polish_iters: 10,
                tol_progress_units: 1e-3,
                ..base
            },
            Quality::Balanced => base,
            Quality::Exact => SearchSettings {
                margin_units: 0.01,
                relaxed_iters: 150,
                polish_iters: 120,
                tol_progress_units: 1e-9,
                ..base
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
    /// The time limit stopped it; the best valid plan so far is returned.
    TimeLimit,
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

impl std::fmt::Display for SearchStatus {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            SearchStatus::Converged { gap } => {
                write!(f, "converged, {:.3}% above the lower bound", 100.0 * gap)
            }
            SearchStatus::TimeLimit => {
                f.write_str("stopped by the time limit with the best valid plan so far")
            }
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
    /// Steps rejected by exact re-simulation.
    pub rejected_steps: u64,
    /// Frame counts tried.
    pub frame_counts_tried: u64,
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
    /// The plan's source: `greedy` or `optimised`.
    pub source: &'static str,
}

/// The problem argmin sees: the plan's parameters `(sigma_0, c_0, sigma_1, c_1, ...)` and, as cost, minus
/// the merit `progress - weight * violation`.
pub struct ScpProblem<'a> {
    start: ModelState,
    fl: FrameLaw,
    corridor: &'a Corridor,
    finish_a: Vec2,
    progress_dir: Vec2,
    margin: f64,
    slack_weight: f64,
    wall_radius: f64,
    relaxed: bool,
    /// Frames per planning step: 1, or a coarse stage's knot ([`knot`]).
    frames_per_knot: u32,
}

/// The trajectory of a parameter vector with what the sub-problem needs.
struct Linearised {
    states: Vec<ModelState>,
    jacobians: Vec<super::model::FrameJacobian>,
    walls: Vec<WallRow>,
    /// Per frame, the convexified Lagrangian block, when duals were given.
    curvature: Option<Vec<CurvatureBlock>>,
}

fn unpack(p: &[f64]) -> Vec<FrameControl> {
    p.chunks_exact(2)
        .map(|u| FrameControl {
            sigma: u[0],
            c: u[1],
        })
        .collect()
}

fn pack(u: &[FrameControl]) -> Vec<f64> {
    u.iter().flat_map(|f| [f.sigma, f.c]).collect()
}

impl ScpProblem<'_> {
    fn progress(&self, p: Vec2) -> f64 {
        self.progress_dir.dot(p - self.finish_a)
    }

    /// Merit of a trajectory: progress after the last frame less the weighted violations.
    fn merit(&self, states: &[ModelState]) -> f64 {
        let last = states.last().map_or(self.start.pos, |s| s.pos);
        self.progress(last) - self.slack_weight * self.violation(states)
    }

    /// Total violation, units: how far the frames' moves come closer to a wall than the accepted
    /// clearance, half the margin. The sub-problems ask for the whole margin, so the second-order error
    /// of a step along a wall (the linearised dynamics are exact only to first order) stays inside the
    /// other half instead of being charged at the slack weight: charging it stalls the trust region.
    fn violation(&self, states: &[ModelState]) -> f64 {
        let accepted = MERIT_MARGIN_SHARE * self.margin;
        let mut violation = 0.0;
        let mut prev = self.start.pos;
        for s in states {
            violation +=
                (accepted - self.corridor.move_clearance(prev, s.pos, self.wall_radius)).max(0.0);
            prev = s.pos;
        }
        violation
    }

    /// The trajectory of `controls`, its Jacobians and wall rows, and with `duals` (one per frame, from
    /// the last sub-problem) the convexified curvature of the Lagrangian ([`super::lagrangian`]).
    fn linearise(&self, controls: &[FrameControl], duals: Option<&[[f64; 4]]>) -> Linearised {
        let mut states = Vec::with_capacity(controls.len());
        let mut jacobians = Vec::with_capacity(controls.len());
        let duals = duals.filter(|z| z.len() == controls.len());
        let mut curvature = duals.map(|_| Vec::with_capacity(controls.len()));
        let mut x = self.start;
        for (k, &u) in controls.iter().enumerate() {
            let (next, j) = knot(&x, u, &self.fl, self.frames_per_knot, true);
            if let Some(j) = j {
                jacobians.push(j);
            }
            if let (Some(blocks), Some(z)) = (curvature.as_mut(), duals) {
                let hessian = knot_hessian(&x, u, &self.fl, self.frames_per_knot);
                let w = lagrangian_block(&hessian, &z[k]);
                blocks.push(convexify(&w));
            }
            states.push(next);
            x = next;
        }
        let mut walls = Vec::new();
        let mut seps: Vec<Separation> = Vec::new();
        let mut prev = self.start.pos;
        for (k, s) in states.iter().enumerate() {
            seps.clear();
            self.corridor
                .separations(prev, s.pos, self.wall_radius, None, &mut seps);
            for sep in &seps {
                walls.push(WallRow {
                    frame: k,
                    plane: sep.plane,
                });
                if k > 0 {
                    walls.push(WallRow {
                        frame: k - 1,
                        plane: sep.plane,
                    });
                }
            }
            prev = s.pos;
        }
        Linearised {
            states,
            jacobians,
            walls,
            curvature,
        }
    }

    /// Lowest `c` allowed at speed `v`: braking down to `cos theta = -0.95`.
    fn c_min(&self, v: f64) -> f64 {
        -0.95 * v
    }
}

impl CostFunction for ScpProblem<'_> {
    type Param = Vec<f64>;
    type Output = f64;

    fn cost(&self, p: &Self::Param) -> std::result::Result<f64, ArgminError> {
        let states = rollout_knots(&self.start, &unpack(p), &self.fl, self.frames_per_knot);
        let m = self.merit(&states);
        if m.is_finite() {
            Ok(-m)
        } else {
            Err(ArgminError::msg("the plan's trajectory is not finite"))
        }
    }
}

type ScpState = IterState<Vec<f64>, (), (), (), (), f64>;

/// One SCP iteration per argmin iteration: linearise, solve the Clarabel sub-problem, accept the step
/// only if exact re-simulation confirms enough of the predicted gain.
pub struct ScpSolver {
    trust: f64,
    sigma_trust: f64,
    c_trust_ups: f64,
    min_trust: f64,
    tol: f64,
    converged: bool,
    stats: SearchStats,
    /// Dynamics duals of the last solved sub-problem, per frame: the curvature weights.
    duals: Option<Vec<[f64; 4]>>,
}

impl ScpSolver {
    fn new(tol: f64) -> Self {
        ScpSolver {
            trust: 1.0,
            sigma_trust: 0.1,
            c_trust_ups: 5.0,
            min_trust: 1e-7,
            tol,
            converged: false,
            stats: SearchStats::default(),
            duals: None,
        }
    }
}

/// Final wall margins tried, as multiples of the setting, until a plan stays valid.
const FINAL_MARGIN_FACTORS: [f64; 3] = [1.0, 3.0, 10.0];

/// Times the relaxed plan is re-solved with a wider margin when rounding leaves the walls.
const MARGIN_RETRIES: usize = 3;
/// Factor by which that margin grows each time.
const MARGIN_GROWTH: f64 = 2.5;

/// Within this of the kink `L - gamma1`, ups, a frame's `c` counts as on it.
const KINK_TOL_UPS: f64 = 1e-9;

/// Share of the wall margin a plan must keep to count as clear (see [`ScpProblem::violation`]).
const MERIT_MARGIN_SHARE: f64 = 0.5;

/// Least share of the predicted gain a step must deliver to be accepted.
const ACCEPT_RATIO: f64 = 0.1;

impl<'a> Solver<ScpProblem<'a>, ScpState> for ScpSolver {
    fn name(&self) -> &str {
        "scp-clarabel"
    }

    fn init(
        &mut self,
        problem: &mut Problem<ScpProblem<'a>>,
        state: ScpState,
    ) -> std::result::Result<(ScpState, Option<KV>), ArgminError> {
        let param = state
            .get_param()
            .cloned()
            .ok_or_else(|| ArgminError::msg("no start plan"))?;
        let cost = problem.cost(&param)?;
        Ok((state.cost(cost), None))
    }

    fn next_iter(
        &mut self,
        problem: &mut Problem<ScpProblem<'a>>,
        state: ScpState,
    ) -> std::result::Result<(ScpState, Option<KV>), ArgminError> {
        let param = state
            .get_param()
            .cloned()
            .ok_or_else(|| ArgminError::msg("no plan"))?;
        let cost = state.get_cost();
        let controls = unpack(&param);
        let (trust, sigma_trust, c_trust) = (self.trust, self.sigma_trust, self.c_trust_ups);
        let upper_at_kink = state.get_iter() % 2 == 0;
        let duals = self.duals.take();
        let step = problem.problem("linearise-and-solve", |pr| {
            // Each frame stays on its piece of mu = min(gamma1, L - c) within a step, so the linearisation
            // is exact to first order; a frame on the kink tries the upper piece (mu = L - c) on even
            // iterations and the lower (mu = gamma1) on odd ones.
            let kink = pr.fl.kink();
            let at_kink = |c: f64| (c - kink).abs() <= KINK_TOL_UPS;
            let lin_controls: Vec<FrameControl> = controls
                .iter()
                .map(|u| {
                    if at_kink(u.c) {
                        let c = if upper_at_kink {
                            kink + KINK_TOL_UPS
                        } else {
                            kink - KINK_TOL_UPS
                        };
                        FrameControl { c, ..*u }
                    } else {
                        *u
                    }
                })
                .collect();
            let lin = pr.linearise(&lin_controls, duals.as_deref());
            let mut sigma_range = Vec::with_capacity(controls.len());
            let mut c_range = Vec::with_capacity(controls.len());
            let mut speed = pr.start.speed;
            for (k, u) in lin_controls.iter().enumerate() {
                let ds = trust * sigma_trust;
                sigma_range.push(if pr.relaxed {
                    (ds.min(1.0 + u.sigma), ds.min(1.0 - u.sigma))
                } else {
                    (0.0, 0.0)
                });
                let dc = trust * c_trust;
                let (mut lo, mut hi) = (
                    dc.min(u.c - pr.c_min(speed)).max(0.0),
                    dc.min(pr.fl.c_plan_max(speed) - u.c).max(0.0),
                );
                if u.c > kink {
                    lo = lo.min(u.c - kink);
                } else {
                    hi = hi.min(kink - u.c);
                }
                c_range.push((lo, hi));
                speed = lin.states[k].speed;
            }
            let positions: Vec<Vec2> = lin.states.iter().map(|s| s.pos).collect();
            let sub = SubProblem {
                jacobians: &lin.jacobians,
                positions: &positions,
                walls: &lin.walls,
                margin: pr.margin,
                accepted_clearance: MERIT_MARGIN_SHARE * pr.margin,
                slack_weight: pr.slack_weight,
                progress_dir: pr.progress_dir,
                sigma_range: &sigma_range,
                c_range: &c_range,
                curvature: lin.curvature.as_deref(),
            };
            Ok(qp::solve(&sub))
        })?;
        self.stats.iterations += 1;
        self.stats.subproblems += 1;
        let du = match step.status {
            SubStepStatus::Solved { .. } => {
                self.duals = Some(step.dynamics_duals);
                step.du
            }
            SubStepStatus::Failed(_) => {
                self.stats.subproblem_failures += 1;
                self.trust *= 0.25;
                return Ok((state, None));
            }
        };
        // No gain in the merit by the model: converged. The prediction can be negative: the sub-problem
        // also asks moves inside the wall margin back out to it, which the merit (it counts only what is
        // closer than the accepted clearance) does not pay for.
        if step.predicted <= self.tol {
            self.converged = true;
            return Ok((state, None));
        }
        let candidate: Vec<f64> = controls
            .iter()
            .zip(&du)
            .flat_map(|(u, d)| [(u.sigma + d.0).clamp(-1.0, 1.0), u.c + d.1])
            .collect();
        // A plan whose trajectory is not finite is simply worse than any finite one.
        let new_cost = problem.cost(&candidate).unwrap_or(f64::INFINITY);
        let actual = cost - new_cost;
        let ratio = actual / step.predicted;
        if actual > 0.0 && ratio >= ACCEPT_RATIO {
            if ratio > 0.75 {
                self.trust = (self.trust * 2.0).min(4.0);
            } else if ratio < 0.25 {
                self.trust *= 0.5;
            }
            Ok((state.param(candidate).cost(new_cost), None))
        } else {
            self.stats.rejected_steps += 1;
            self.trust *= 0.3;
            Ok((state, None))
        }
    }

    fn terminate(&mut self, _state: &ScpState) -> TerminationStatus {
        if self.converged || self.trust < self.min_trust {
            TerminationStatus::Terminated(TerminationReason::SolverConverged)
        } else {
            TerminationStatus::NotTerminated
        }
    }
}

/// Runs SCP on `controls`; returns the improved controls, whether the time limit stopped it, whether it
/// stopped at the iteration cap, and the work done.
fn run_scp(
    problem: ScpProblem,
    controls: Vec<FrameControl>,
    max_iters: u64,
    tol: f64,
    deadline: Option<Instant>,
) -> (Vec<FrameControl>, bool, bool, SearchStats) {
    let x0 = pack(&controls);
    let mut exec = Executor::new(problem, ScpSolver::new(tol))
        .configure(|s| s.param(x0.clone()).max_iters(max_iters));
    if let Some(d) = deadline {
        exec = exec.timeout(
            d.saturating_duration_since(Instant::now())
                .max(Duration::from_millis(1)),
        );
    }
    match exec.run() {
        Ok(res) => {
            let reason = res.state().get_termination_reason();
            let timed_out = matches!(reason, Some(TerminationReason::Timeout));
            let capped = matches!(reason, Some(TerminationReason::MaxItersReached));
            let best = res
                .state()
                .get_best_param()
                .or(res.state().get_param())
                .cloned()
                .unwrap_or(x0);
            // The solver's own counts (sub-problems, failures, rejections) with argmin's iterations.
            let stats = SearchStats {
                iterations: res.state().get_iter(),
                ..res.solver.stats
            };
            (unpack(&best), timed_out, capped, stats)
        }
        Err(_) => (controls, false, false, SearchStats::default()),
    }
}

/// One SCP stage: runs it, adds its work to `stats`, notes a timeout; returns the improved controls and
/// whether the stage stopped at its iteration cap (still improving) rather than converged.
fn scp_stage(
    problem: ScpProblem,
    controls: Vec<FrameControl>,
    max_iters: u64,
    settings: &SearchSettings,
    deadline: Option<Instant>,
    stats: &mut SearchStats,
    timed_out: &mut bool,
) -> (Vec<FrameControl>, bool) {
    let (c, t, capped, s) = run_scp(
        problem,
        controls,
        max_iters,
        settings.tol_progress_units,
        deadline,
    );
    add_stats(stats, s);
    *timed_out |= t;
    (c, capped)
}

/// Sums the work counts.
fn add_stats(a: &mut SearchStats, b: SearchStats) {
    a.iterations += b.iterations;
    a.subproblems += b.subproblems;
    a.subproblem_failures += b.subproblem_failures;
    a.rejected_steps += b.rejected_steps;
    a.frame_counts_tried += b.frame_counts_tried;
}

/// The first frame (1-based) whose move crosses the finish line, in the model.
fn model_crossing(start: &ModelState, states: &[ModelState], scene: &Scene) -> Option<usize> {
    let mut prev = start.pos;
    for (k, s) in states.iter().enumerate() {
        if scene.finish.crossing_fraction(prev, s.pos).is_some() {
            return Some(k + 1);
        }
        prev = s.pos;
    }
    None
}

/// How far ahead a heading error is weighed by the side rounding, seconds.
const ROUNDING_HORIZON_S: f64 = 0.05;
/// Side sequences kept by the rounding's beam search.
const ROUNDING_BEAM: usize = 64;

/// Rounds relaxed sides to `+-1`: a beam search over side sequences that keeps the exact trajectory on the
/// relaxed one. A sequence's cost adds, each frame, the squared position error and the squared distance
/// its heading error would drift over a short horizon. Rounding frame by frame keeps the heading error
/// bounded but not zero-mean where the relaxed sides saturate, and a steady heading error of a few
/// hundredths of a radian drifts the path by tens of units.
fn round_sides(start: &ModelState, controls: &[FrameControl], fl: &FrameLaw) -> Vec<FrameControl> {
    let relaxed = rollout(start, controls, fl);
    let horizon_s = ROUNDING_HORIZON_S;
    // Beam entries: (cost, state, index into the history of choices).
    let mut history: Vec<(usize, f64)> = Vec::with_capacity(controls.len() * ROUNDING_BEAM * 2);
    let mut beam: Vec<(f64, ModelState, usize)> = vec![(0.0, *start, usize::MAX)];
    for (k, u) in controls.iter().enumerate() {
        let target = relaxed[k];
        let mut next: Vec<(f64, ModelState, usize)> = Vec::with_capacity(beam.len() * 2);
        for &(cost, x, h) in &beam {
            for sigma in [1.0, -1.0] {
                let y = frame(&x, FrameControl { sigma, c: u.c }, fl, false).0;
                let dpos = (y.pos - target.pos).length_squared();
                let drift = (y.heading - target.heading) * y.speed * horizon_s;
                history.push((h, sigma));
                next.push((cost + dpos + drift * drift, y, history.len() - 1));
            }
        }
        next.sort_by(|a, b| a.0.total_cmp(&b.0));
        next.truncate(ROUNDING_BEAM);
        beam = next;
    }
    let mut sides = Vec::with_capacity(controls.len());
    let mut h = beam.first().map_or(usize::MAX, |b| b.2);
    while h != usize::MAX {
        let (parent, sigma) = history[h];
        sides.push(sigma);
        h = parent;
    }
    sides.reverse();
    controls
        .iter()
        .zip(sides)
        .map(|(u, sigma)| FrameControl { sigma, c: u.c })
        .collect()
}

/// Plays planning controls through the real frame, recomputing each frame's yaw from the actual velocity.
/// With `quantise`, the yaw is one of the two anglemod steps around the planned one, whichever leaves the
/// real state nearer the planned trajectory (position, and the heading's drift over a short horizon):
/// replaying the relative controls on quantised yaws without this feedback drifts by tenths of a unit.
struct PlanPlayer {
    /// Game controls played first, as they are (see [`MIN_PLANNING_SPEED_UPS`]).
    prefix: Vec<Control>,
    controls: Vec<FrameControl>,
    fl: FrameLaw,
    quantise: bool,
    targets: Vec<ModelState>,
}

impl PlanPlayer {
    fn new(
        start: &ModelState,
        prefix: &[Control],
        controls: Vec<FrameControl>,
        fl: FrameLaw,
        quantise: bool,
    ) -> Self {
        let targets = rollout(start, &controls, &fl);
        PlanPlayer {
            prefix: prefix.to_vec(),
            controls,
            fl,
            quantise,
            targets,
        }
    }
}

impl Controller for PlanPlayer {
    fn name(&self) -> String {
        "optimised".to_string()
    }

    fn control(&mut self, frame: u64, s: &PlayerState, sim: &Simulation) -> Control {
        let i = usize::try_from(frame.saturating_sub(1)).unwrap_or(usize::MAX);
        if let Some(c) = self.prefix.get(i) {
            return *c;
        }
        let i = i - self.prefix.len();
        let u = self.controls.get(i).copied().unwrap_or(FrameControl {
            sigma: 1.0,
            c: self.fl.c_max(s.speed()),
        });
        let c = control_for(s.vel, u, &self.fl);
        if !self.quantise {
            return c;
        }
        let Some(target) = self.targets.get(i) else {
            return Control {
                yaw_rad: quantise_yaw_rad(c.yaw_rad),
                ..c
            };
        };
        let (lo, hi) = anglemod_bracket(c.yaw_rad);
        let score = |yaw_rad: f64| {
            let mut next = *s;
            sim.frame(&mut next, &Control { yaw_rad, ..c });
            let drift =
                (next.vel.angle() - target.heading).sin() * next.speed() * ROUNDING_HORIZON_S;
            (next.pos - target.pos).length_squared() + drift * drift
        };
        let yaw_rad = if score(lo) <= score(hi) { lo } else { hi };
        Control { yaw_rad, ..c }
    }
}

fn time_of(t: &Trace) -> f64 {
    match (t.feasible(), t.crossing) {
        (true, Some(c)) => c.time,
        _ => f64::INFINITY,
    }
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
        /// The frame in which that plan crosses the line, if it does without touching a wall.
        reached: Option<usize>,
    },
    /// Rounding, polishing and checking the plan.
    Finishing,
}

/// The minimal-time plan of `scene` (see the module documentation). Errors only for bad input or a scene
/// with no valid path ([`Error::NoValidPath`]); everything else is a [`SearchStatus`].
pub fn solve(scene: &Scene, settings: &SearchSettings) -> Result<Outcome> {
    solve_with_progress(scene, settings, &mut |_| {})
}

/// [`solve`], reporting what it does to `progress`.
///
/// On airborne scenes a level also runs the levels below it in the time left (`exact`: `balanced` and
/// `fast`; `balanced`: `fast`) and keeps the fastest valid plan, so a higher level is never worse than a
/// lower one. The levels differ in margin and tolerances and so can end in different local optima (the
/// narrow bend: `balanced` 5.02696 s, `exact` alone 5.02810 s), or, in a corridor little wider than the
/// hull, with no plan that survives rounding at the tighter margin.
pub fn solve_with_progress(
    scene: &Scene,
    settings: &SearchSettings,
    progress: &mut dyn FnMut(Progress),
) -> Result<Outcome> {
    let started = Instant::now();
    let mut best = solve_once(scene, settings, progress)?;
    if !scene.effects.is_air_only() {
        return Ok(best);
    }
    let lower: &[Quality] = match settings.quality {
        Quality::Fast => &[],
        Quality::Balanced => &[Quality::Fast],
        Quality::Exact => &[Quality::Balanced, Quality::Fast],
    };
    let mut stats = best.stats;
    for &quality in lower {
        let time_limit = match settings.time_limit {
            Some(limit) => match limit.checked_sub(started.elapsed()) {
                Some(left) if !left.is_zero() => Some(left),
                _ => break,
            },
            None => None,
        };
        let other = solve_once(
            scene,
            &SearchSettings {
                time_limit,
                ..SearchSettings::for_quality(quality)
            },
            progress,
        )?;
        add_stats(&mut stats, other.stats);
        if other.source == "optimised" && time_of(&other.trace) < time_of(&best.trace) {
            best = other;
        }
    }
    // The work of every run.
    best.stats = stats;
    best.solve_seconds = started.elapsed().as_secs_f64();
    Ok(best)
}

/// One run of the search at `settings` (see [`solve_with_progress`]).
fn solve_once(
    scene: &Scene,
    settings: &SearchSettings,
    progress: &mut dyn FnMut(Progress),
) -> Result<Outcome> {
    let started = Instant::now();
    let deadline = settings.time_limit.map(|d| started + d);
    let sim = Simulation::new(scene)?;
    let bound = lower_bound(scene, sim.corridor())?;
    let fl = FrameLaw {
        tau_s: scene.frame_time_s(),
        law: air_law(&scene.vars),
        side_key_speed: scene.vars.side_key_speed,
    };
    // Speed caps from the radius-speed relation: the speeds whose measured turn radius fits the largest
    // arc through bends of these widths for the hull centre.
    let caps: Vec<f64> = [16.0, 32.0, 64.0, 128.0, 256.0]
        .iter()
        .filter_map(|&w| speed_for_radius(&scene.vars, bend_arc_radius(w)).ok())
        .collect();
    let (greedy, _, _) = best_greedy_or_capped(&sim, &bound, &caps, scene.effects.is_air_only());
    // The search's start: the greedy run if it is valid and touches no wall (the planning model has no
    // collisions: after a contact the model and the game part ways), else a run along a centred guide.
    let clean = |t: &Trace| t.feasible() && t.crossing.is_some() && t.collisions() == 0;
    let seed = if scene.effects.is_air_only() && !clean(&greedy) {
        centred_greedy(&sim, scene, &caps, &clean)
    } else {
        None
    };
    // The baseline is the faster valid run of the two (`time_of` is infinite for an invalid one).
    let greedy = match &seed {
        Some(s) if time_of(s) <= time_of(&greedy) => s.clone(),
        _ => greedy,
    };
    let seed = seed.unwrap_or_else(|| greedy.clone());
    let mut stats = SearchStats::default();
    progress(Progress::Baseline {
        greedy_frames: greedy.crossing.map(|c| c.frames),
        bound_frames: bound.crossing.frames,
    });
    let finish = |controls: Vec<Control>,
                  trace: Trace,
                  status: SearchStatus,
                  stats: SearchStats,
                  source: &'static str| {
        let engine_exact = sim.run_engine_exact(&controls);
        Outcome {
            controls,
            trace,
            engine_exact,
            greedy: greedy.clone(),
            bound: bound.clone(),
            status,
            stats,
            solve_seconds: started.elapsed().as_secs_f64(),
            source,
        }
    };
    // The baseline plan is the greedy run itself (its yaws as planned: the engine-exact replay applies
    // anglemod, and quantising them here could cost the frame that makes the plan no worse than greedy).
    let greedy_plan = (greedy.controls.clone(), greedy.clone());
    if !scene.effects.is_air_only() {
        // Greedy already crossing in the bound's frame is optimal (the groundstrafe lane): say so.
        let greedy_status = super::hops::greedy_status(&greedy_plan.1, &bound);
        if matches!(greedy_status, SearchStatus::GreedyOptimal { .. }) {
            return Ok(finish(
                greedy_plan.0,
                greedy_plan.1,
                greedy_status,
                stats,
                "greedy",
            ));
        }
        // Jumping scenes with the Source boost: the policy search of `jumps` (issue 7). It keeps a plan
        // only if it is valid in f64 and engine-exact; greedy stays the answer when it is faster.
        if let Some(plan) = super::jumps::plan_jumps(&sim, settings, deadline) {
            stats.iterations = plan.evaluations;
            let t = plan.best.time();
            if t < time_of(&greedy_plan.1) {
                let status = if plan.timed_out {
                    SearchStatus::TimeLimit
                } else {
                    SearchStatus::Converged {
                        gap: (t - bound.crossing.time) / bound.crossing.time.max(f64::MIN_POSITIVE),
                    }
                };
                let best = plan.best;
                return Ok(finish(
                    best.trace.controls.clone(),
                    best.trace,
                    status,
                    stats,
                    "optimised",
                ));
            }
        }
        // Ground, gravity and jumps without the boost (GoldSrc bunnyhops under the cap, groundstrafing,
        // Half-Life 2 air strafing with jumps): the hop planner of `hops`, same rules.
        if let Some(plan) = super::hops::plan_hops(&sim, &bound.path, &caps, settings, deadline) {
            stats.iterations = plan.evaluations;
            let t = plan.best.time();
            if t < time_of(&greedy_plan.1) {
                let status = if plan.timed_out {
                    SearchStatus::TimeLimit
                } else {
                    SearchStatus::Converged {
                        gap: (t - bound.crossing.time) / bound.crossing.time.max(f64::MIN_POSITIVE),
                    }
                };
                let best = plan.best;
                return Ok(finish(
                    best.trace.controls.clone(),
                    best.trace,
                    status,
                    stats,
                    "optimised",
                ));
            }
        }
        return Ok(finish(
            greedy_plan.0,
            greedy_plan.1,
            greedy_status,
            stats,
            "greedy",
        ));
    }
    // A start at rest has no heading, and the planning model none to turn: the seed's first frame
    // (from rest every wish direction gains the same) is kept as a fixed prefix and planning starts
    // after it.
    let prefix: Vec<Control> = if scene.start.speed() < MIN_PLANNING_SPEED_UPS {
        seed.controls.iter().take(1).copied().collect()
    } else {
        Vec::new()
    };
    let (start_pos, start_vel) = match (prefix.len(), seed.frames.first()) {
        (1, Some(first)) => (first.pos, first.vel),
        _ => (scene.start.pos, scene.start.vel),
    };
    let start = ModelState {
        pos: start_pos,
        speed: start_vel.length(),
        heading: if start_vel.length() > 0.0 {
            start_vel.angle()
        } else {
            0.0
        },
    };
    let progress_dir = finish_direction(scene, &bound);
    let problem = |margin: f64, relaxed: bool| ScpProblem {
        start,
        fl,
        corridor: sim.corridor(),
        finish_a: scene.finish.a,
        progress_dir,
        margin,
        slack_weight: settings.slack_weight,
        wall_radius: settings.wall_radius_units,
        relaxed,
        frames_per_knot: 1,
    };
    // The warm start: the greedy (or capped greedy) run in planning variables.
    let mut vel = start_vel;
    let mut warm: Vec<FrameControl> = Vec::with_capacity(seed.controls.len());
    for (c, rec) in seed.controls.iter().zip(&seed.frames).skip(prefix.len()) {
        let mut u = frame_control_of(vel, c);
        // Below the anglemod guard of case 1, where there is one.
        let v = vel.length();
        if fl.c_plan_max(v) < fl.c_max(v) {
            u.c = u.c.min(fl.c_plan_max(v));
        }
        warm.push(u);
        vel = rec.vel;
    }
    // Stage 1: the relaxed problem; its margin leaves room for the zigzag of rounded sides.
    let zigzag = fl.tau_s * fl.law.l.max(fl.law.gamma1);
    let relaxed_margin = settings.margin_units + zigzag;
    let mut n = seed.crossing.map_or(warm.len(), |c| {
        (c.frames as usize).saturating_sub(prefix.len())
    });
    let mut timed_out = false;
    let mut controls = warm;
    // No plan crosses before the bound's frame.
    let lo = (bound.crossing.frames as usize).saturating_sub(1 + prefix.len());
    let mut search = CountSearch {
        scene,
        start,
        fl,
        settings,
        deadline,
        stats: &mut stats,
        timed_out: &mut timed_out,
        progress,
    };
    // Coarse to fine: on long runs, first the relaxed problem over knots of several frames each, its plan
    // then spread over the frames as the fine stage's start.
    let knot_frames = coarse_knot_frames(n);
    if knot_frames > 1 {
        let m = knot_frames as usize;
        let knots: Vec<FrameControl> = controls[..n.min(controls.len())]
            .chunks(m)
            .map(|chunk| {
                let k = chunk.len() as f64;
                FrameControl {
                    sigma: chunk.iter().map(|u| u.sigma).sum::<f64>() / k,
                    c: chunk.iter().map(|u| u.c).sum::<f64>() / k,
                }
            })
            .collect();
        // The chord of a knot leaves its frames' arc by at most the sagitta m^2 tau gamma1 / 8 (each frame
        // turns the heading by at most about gamma1 / V).
        let sagitta = (m * m) as f64 * fl.tau_s * fl.law.gamma1 / 8.0;
        let coarse = search.run(
            &|margin, relaxed| ScpProblem {
                frames_per_knot: knot_frames,
                ..problem(margin, relaxed)
            },
            knots.clone(),
            knots.len(),
            lo / m,
            relaxed_margin + sagitta,
            knot_frames,
        );
        if let Some(plan) = coarse {
            controls = plan
                .iter()
                .flat_map(|u| std::iter::repeat_n(*u, m))
                .collect();
            n = controls.len();
        }
    }
    let best_relaxed = search.run(&problem, controls, n, lo, relaxed_margin, 1);
    let Some(relaxed) = best_relaxed else {
        return Ok(finish(
            greedy_plan.0,
            greedy_plan.1,
            if timed_out {
                SearchStatus::TimeLimit
            } else {
                SearchStatus::NoImprovement {
                    reason: "the relaxed search found no valid plan".into(),
                }
            },
            stats,
            "greedy",
        ));
    };
    progress(Progress::Finishing);
    // Stages 2 and 3, first with the settings' final margin; if no plan stays valid through rounding and
    // quantisation (a tight margin along a long wall), again with wider ones.
    let relaxed_plan = relaxed;
    let mut best = (
        time_of(&greedy_plan.1),
        greedy_plan.0,
        greedy_plan.1,
        "greedy",
    );
    for final_margin in FINAL_MARGIN_FACTORS.map(|f| f * settings.margin_units) {
        // Stage 2: exact sides, then c polished with the sides fixed. Where rounding leaves the walls (the
        // relaxed plan ran closer than the rounded zigzag allows), the relaxed plan is re-solved at the same
        // frame count with a wider margin, up to MARGIN_RETRIES times.
        let mut candidates: Vec<Vec<FrameControl>> = Vec::new();
        let mut relaxed = relaxed_plan.clone();
        let mut margin = relaxed_margin;
        for attempt in 0..=MARGIN_RETRIES {
            let mut exact = round_sides(&start, &relaxed, &fl);
            if settings.polish_iters > 0 && !timed_out {
                let pr = problem(final_margin, false);
                let (c, _) = scp_stage(
                    pr,
                    exact.clone(),
                    settings.polish_iters,
                    settings,
                    deadline,
                    &mut stats,
                    &mut timed_out,
                );
                exact = c;
            }
            let st = rollout(&start, &exact, &fl);
            let clean = problem(final_margin, false).violation(&st) <= 1e-9;
            let reaches = model_crossing(&start, &st, scene).is_some();
            candidates.push(exact);
            if (clean && reaches) || attempt == MARGIN_RETRIES || timed_out {
                break;
            }
            margin *= MARGIN_GROWTH;
            let pr = problem(margin, true);
            let (c, _) = scp_stage(
                pr,
                relaxed.clone(),
                settings.relaxed_iters,
                settings,
                deadline,
                &mut stats,
                &mut timed_out,
            );
            let st = rollout(&start, &c, &fl);
            match model_crossing(&start, &st, scene) {
                Some(k) if problem(margin, true).violation(&st) <= 1e-9 => {
                    relaxed = c[..k].to_vec()
                }
                _ => {
                    // One frame more for the wider margin.
                    let mut longer = c;
                    let last = *longer.last().unwrap_or(&FrameControl {
                        sigma: 0.0,
                        c: fl.c_max(f64::INFINITY),
                    });
                    longer.push(last);
                    relaxed = longer;
                }
            }
        }
        // Stage 3: the real frame, quantised yaws, engine-exact check; keep the best valid plan.
        for cand in candidates {
            let trace = sim.run(&mut PlanPlayer::new(&start, &prefix, cand, fl, true));
            let t = time_of(&trace);
            let controls = trace.controls.clone();
            if t < best.0 && sim.run_engine_exact(&controls).feasible() {
                best = (t, controls, trace, "optimised");
            }
        }
        if best.3 == "optimised" || timed_out {
            break;
        }
    }
    let status = if timed_out {
        SearchStatus::TimeLimit
    } else if best.3 == "greedy" {
        SearchStatus::NoImprovement {
            reason: "no optimised plan stayed valid after rounding and quantisation".into(),
        }
    } else {
        SearchStatus::Converged {
            gap: (best.0 - bound.crossing.time) / bound.crossing.time.max(f64::MIN_POSITIVE),
        }
    };
    Ok(finish(best.1, best.2, status, stats, best.3))
}

/// Frames per knot of the coarse stage for a run of about `frames` frames: knots of several frames
/// once the run is long enough that about [`COARSE_KNOTS`] knots cover it, else 1 (no coarse stage).
fn coarse_knot_frames(frames: usize) -> u32 {
    u32::try_from(frames / COARSE_KNOTS)
        .unwrap_or(u32::MAX)
        .max(1)
}

/// Below this start speed, ups, the planning model has no heading to work from: the seed's first frame is
/// played as it is and the plan starts after it.
const MIN_PLANNING_SPEED_UPS: f64 = 1.0;

/// Times a relaxed stage that stopped at its iteration cap without a clean crossing is continued at the
/// same count before the count is given up.
const MAX_CONTINUED_STAGES: usize = 3;

/// About this many knots make the coarse stage (the planning steps of a 100 fps run of four seconds).
const COARSE_KNOTS: usize = 400;

/// The relaxed stage's search over the number of planning steps (frames or knots), with what it shares
/// across the stages of a solve.
struct CountSearch<'s, 'p> {
    scene: &'s Scene,
    start: ModelState,
    fl: FrameLaw,
    settings: &'s SearchSettings,
    deadline: Option<Instant>,
    stats: &'s mut SearchStats,
    timed_out: &'s mut bool,
    progress: &'p mut dyn FnMut(Progress),
}

impl CountSearch<'_, '_> {
    /// From `controls` over `n` steps of `frames_per_knot` frames: SCP at `n` steps, then at one step
    /// fewer than the plan's crossing, until the line is no longer reached (or `lo` steps, below which
    /// the bound says it cannot be); more steps if the first count does not reach it. Returns the best
    /// clean plan, cut at its crossing step.
    fn run<'a>(
        &mut self,
        problem: &dyn Fn(f64, bool) -> ScpProblem<'a>,
        mut controls: Vec<FrameControl>,
        mut n: usize,
        lo: usize,
        margin: f64,
        frames_per_knot: u32,
    ) -> Option<Vec<FrameControl>> {
        let fl = self.fl;
        let mut best: Option<Vec<FrameControl>> = None;
        let mut grow_tries = 0;
        let mut continue_tries = 0;
        loop {
            if self.deadline.is_some_and(|d| Instant::now() >= d) {
                *self.timed_out = true;
                break;
            }
            controls.resize(
                n,
                FrameControl {
                    sigma: 0.0,
                    c: fl.c_max(f64::INFINITY),
                },
            );
            self.stats.frame_counts_tried += 1;
            let (c, capped) = scp_stage(
                problem(margin, true),
                controls.clone(),
                self.settings.relaxed_iters,
                self.settings,
                self.deadline,
                self.stats,
                self.timed_out,
            );
            let check = problem(margin, true);
            let states = rollout_knots(&self.start, &c, &fl, frames_per_knot);
            let reached = model_crossing(&self.start, &states, self.scene);
            let clean = check.violation(&states) <= 1e-9;
            let per = frames_per_knot as usize;
            (self.progress)(Progress::FrameCount {
                frames: n * per,
                reached: reached.filter(|_| clean).map(|k| k * per),
            });
            match reached {
                Some(k) if clean => {
                    best = Some(c[..k].to_vec());
                    // One step short of this plan's crossing, warm-started from it: each solve keeps
                    // improving the same line (stepping further on a failed probe proves nothing, the
                    // search being local).
                    if k <= lo + 1 || *self.timed_out {
                        break;
                    }
                    n = k - 1;
                    controls = c[..n].to_vec();
                }
                _ if capped && continue_tries < MAX_CONTINUED_STAGES && !*self.timed_out => {
                    // The stage ran out of iterations still improving (a start far from the line: the
                    // capped greedy run of a narrow bend at 1000 fps): go on at the same count.
                    continue_tries += 1;
                    controls = c;
                }
                _ => {
                    if best.is_some() || grow_tries >= 3 || *self.timed_out {
                        break;
                    }
                    // Not reachable at this count from this start: give it more steps.
                    grow_tries += 1;
                    n += (n / 20).max(2);
                    controls = c;
                }
            }
        }
        best
    }
}

/// The best greedy run, also trying speed caps when the scene is airborne.
fn best_greedy_or_capped(
    sim: &Simulation,
    bound: &LowerBound,
    caps: &[f64],
    air_only: bool,
) -> (Trace, f64, Option<f64>) {
    let caps: &[f64] = if air_only { caps } else { &[] };
    best_capped_greedy(sim, &bound.path, &GREEDY_LOOKAHEADS_UNITS, caps)
}

/// Extra clearances of the guide paths, units, tried in turn when the best greedy run is not clean.
const GUIDE_CLEARANCES_UNITS: [f64; 5] = [0.0, 2.0, 4.0, 8.0, 12.0];

/// The fastest `clean` run of the greedy strafer (every look-ahead, uncapped and with each speed cap)
/// along a guide: the shortest path of a body wider than the hull by each of [`GUIDE_CLEARANCES_UNITS`]
/// on either side in turn, so the guide keeps that far from every wall; the first guide with a clean run
/// gives it. Needed where the best greedy run is not clean: in a corridor only a little wider than the
/// hull the plain guide runs along the grown inner corner and the greedy strafer, steering by its side
/// only, weaves across it; between solid walls the fastest greedy runs slide along them, which the
/// planning model (no collisions) cannot follow. `None` if no run is clean.
fn centred_greedy(
    sim: &Simulation,
    scene: &Scene,
    caps: &[f64],
    clean: &dyn Fn(&Trace) -> bool,
) -> Option<Trace> {
    for extra in GUIDE_CLEARANCES_UNITS {
        let Ok(corridor) = Corridor::with_half_width(&scene.walls, HULL_HALF_WIDTH_UNITS + extra)
        else {
            continue;
        };
        let Some((_, path)) =
            corridor.shortest_path(scene.start.pos, (scene.finish.a, scene.finish.b))
        else {
            continue;
        };
        let mut best: Option<Trace> = None;
        for cap in std::iter::once(None).chain(caps.iter().copied().map(Some)) {
            for &la in &GREEDY_LOOKAHEADS_UNITS {
                let greedy = Greedy::new(path.clone(), la);
                let t = sim.run(&mut match cap {
                    Some(cap) => greedy.with_speed_cap(cap),
                    None => greedy,
                });
                if clean(&t) && best.as_ref().is_none_or(|b| time_of(&t) < time_of(b)) {
                    best = Some(t);
                }
            }
        }
        if best.is_some() {
            return best;
        }
    }
    None
}

/// The finish line's unit normal pointing the way the shortest path crosses it.
fn finish_direction(scene: &Scene, bound: &LowerBound) -> Vec2 {
    let d = scene.finish.b - scene.finish.a;
    let n = d.perp().normalized().unwrap_or(Vec2::new(1.0, 0.0));
    let approach = match bound.path.len() {
        0 | 1 => scene.finish.a - scene.start.pos,
        k => bound.path[k - 1] - bound.path[k - 2],
    };
    if n.dot(approach) >= 0.0 {
        n
    } else {
        -n
    }
}

/// Checks a time limit given in seconds.
pub fn time_limit(seconds: f64) -> Result<Duration> {
    if seconds.is_finite() && seconds > 0.0 {
        Ok(Duration::from_secs_f64(seconds))
    } else {
        Err(Error::invalid(
            "--time-limit",
            seconds,
            "a finite number of seconds above 0",
        ))
    }
}
