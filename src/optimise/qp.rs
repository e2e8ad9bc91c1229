//! The convexified sub-step: the dynamics linearised around the current trajectory, the walls as
//! separating half-planes, a trust region, and slack so that every sub-problem is feasible. A convex QP,
//! solved frame by frame ([`super::stagewise`], by default) or by Clarabel as
//! `min 0.5 z'Pz + q'z  s.t.  Az + s = b, s in K`; Clarabel also takes every sub-problem the
//! frame-by-frame solver gives no solution for. Both read and write the same layout of variables.
//!
//! Variables, in order: the control changes `(d sigma_k, d c_k / C_SCALE)` of the controls with room to
//! move (a control with none, a side fixed at `+-1`, is left out: its change is zero); per frame the
//! state change `dx_k = (d px, d py, d V, d psi)` after frame `k`; one slack per group of wall rows (the
//! rows that keep one move clear). Rows: the linearised dynamics (zero cone, one block per frame:
//! `dx_k - A_k dx_{k-1} - B_k du_k = 0`), then inequalities (nonnegative cone): wall rows
//! `-n . dp_k - s_g <= n . p_k - offset - margin` (`g` the row's group), slack signs, and the
//! trust-region and bound rows on the controls. The objective is minus the progress of the last
//! position, the slack's weight, and with [`SubProblem::curvature`] the convexified curvature of the
//! Lagrangian ([`super::lagrangian`]), which makes the model right to second order.

use super::lagrangian::CurvatureBlock;
use super::model::FrameJacobian;
use super::stagewise;
pub(super) use super::stagewise::WarmStart;
use crate::geometry::HalfPlane;
use clarabel::algebra::CscMatrix;
use clarabel::solver::{
    DefaultSettings, DefaultSettingsBuilder, DefaultSolver, IPSolver, NonnegativeConeT,
    SolverStatus, SupportedConeT, ZeroConeT,
};

/// `c` enters the sub-problem divided by this (ups), so both controls have unit scale.
pub const C_SCALE_UPS: f64 = 10.0;
/// The scale of control `j` (0: the side, 1: `c`) in the sub-problem: its variable is its change divided
/// by this.
pub(super) fn control_scale(j: usize) -> f64 {
    if j == 1 {
        C_SCALE_UPS
    } else {
        1.0
    }
}

/// Weight of the control changes in the objective (keeps the sub-problem strictly convex in them).
pub const CONTROL_REGULARISATION: f64 = 1e-6;

/// A wall row: the position after frame `frame` (0-based) must stay on the free side of `plane` by
/// `margin` units. Rows with the same `group` share one slack: the rows that keep one move clear, so a
/// violation is paid once per move, as the merit counts it (each move's worst clearance).
#[derive(Clone, Copy, Debug)]
pub struct WallRow {
    /// 0-based frame whose end position is constrained.
    pub frame: usize,
    /// The half-plane.
    pub plane: HalfPlane,
    /// The slack this row shares with the other rows of its group (the 0-based move it keeps clear).
    pub group: usize,
}

/// Everything the sub-problem needs about the current trajectory.
pub struct SubProblem<'a> {
    /// Per frame, the Jacobian of the frame at the current trajectory.
    pub jacobians: &'a [FrameJacobian],
    /// Per frame, the current end position.
    pub positions: &'a [crate::physics::Vec2],
    /// Wall rows.
    pub walls: &'a [WallRow],
    /// Wall margin, units: the clearance the sub-problem asks for.
    pub margin: f64,
    /// The clearance the merit accepts, units (at most `margin`): the predicted gain counts violations
    /// below this, as the merit does.
    pub accepted_clearance: f64,
    /// Weight of a unit of slack (wall violation) against a unit of progress.
    pub slack_weight: f64,
    /// Unit normal of the finish line: progress is `n . p_N`.
    pub progress_dir: crate::physics::Vec2,
    /// Per frame, the allowed change of sigma: `[-lo, hi]`.
    pub sigma_range: &'a [(f64, f64)],
    /// Per frame, the allowed change of c, ups: `[-lo, hi]`.
    pub c_range: &'a [(f64, f64)],
    /// Per frame `k`, the convexified Hessian of the Lagrangian in `(V_{k-1}, psi_{k-1}, sigma_k, c_k)`
    /// ([`super::lagrangian`]); `None`: a linear model (the first iteration, before any duals).
    pub curvature: Option<&'a [CurvatureBlock]>,
    /// Per frame, a correction added to the position in its wall rows: a second-order correction's
    /// estimate of what the linearised dynamics leave out ([`super::scp`]); `None`: none.
    pub wall_shift: Option<&'a [crate::physics::Vec2]>,
    /// The solver tried first.
    pub solver: SubProblemSolver,
    /// Whether the frame-by-frame solver hands back its feedback with the step ([`SubStep::feedback`]):
    /// for the stages that play a rejected step again with it (the relaxed ones, [`super::scp`]).
    pub with_feedback: bool,
}

/// Which solver a sub-problem is given first.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum SubProblemSolver {
    /// Frame by frame: a Riccati recursion inside an interior-point method ([`super::stagewise`]),
    /// which uses that the sub-problem is a chain of frames; Clarabel where it gives no solution.
    #[default]
    Riccati,
    /// Clarabel, a general sparse conic solver, on every sub-problem.
    Clarabel,
}

/// How a sub-problem ended: the frame-by-frame solver's solution, or Clarabel's status mapped in one
/// place.
#[derive(Clone, Debug, PartialEq)]
pub enum SubStepStatus {
    /// Solved (possibly to reduced accuracy): the step is usable.
    Solved {
        /// Reduced accuracy (Clarabel's `AlmostSolved`, or the frame-by-frame solver's looser
        /// tolerances at its iteration cap).
        almost: bool,
    },
    /// Clarabel stopped without a usable step (infeasible certificate, iteration or time limit, numerical
    /// error, insufficient progress): shrink the trust region and try again.
    Failed(String),
}

/// The result of one sub-problem.
#[derive(Clone, Debug)]
pub struct SubStep {
    /// What happened.
    pub status: SubStepStatus,
    /// Per frame `(d sigma, d c)` (c in ups), when solved.
    pub du: Vec<(f64, f64)>,
    /// Per frame, the model's change of the end state `(px, py, V, psi)` (position in units), when
    /// solved.
    pub dx: Vec<[f64; 4]>,
    /// Per frame, the feedback of its controls on the state change before it, where the frame-by-frame
    /// solver gave the step ([`stagewise::ControlFeedback`]).
    pub feedback: Option<Vec<stagewise::ControlFeedback>>,
    /// The model's predicted decrease of the merit (progress minus weighted violation), when solved.
    pub predicted: f64,
    /// Per frame, the duals `z` of its dynamics rows `(px, py, V, psi)` (Clarabel's convention
    /// `P x + q + A' z = 0`), when solved: the next iteration's curvature weights.
    pub dynamics_duals: Vec<[f64; 4]>,
    /// Where the frame-by-frame solver ended, when it solved the sub-problem: the start of the next
    /// sub-problem of the same stage ([`solve_warm`]).
    pub(super) warm_start: Option<WarmStart>,
    /// Interior-point iterations of the solve that gave the step (a failed attempt's before it not
    /// counted); 0 when failed.
    pub iterations: u32,
    /// Whether the frame-by-frame solver was asked first and gave no solution, so that Clarabel was
    /// asked.
    pub handed_to_clarabel: bool,
}

/// A control's allowed change at most this wide (scaled units) counts as none: the control is fixed.
const FIXED_RANGE: f64 = 1e-12;

impl SubStep {
    /// The model's change of frame `k`'s end position, units.
    pub fn dp(&self, k: usize) -> crate::physics::Vec2 {
        crate::physics::Vec2::new(self.dx[k][0], self.dx[k][1])
    }

    /// A sub-step with no step: `status` says why.
    fn failed(status: SubStepStatus) -> SubStep {
        SubStep {
            status,
            du: vec![],
            dx: vec![],
            feedback: None,
            predicted: 0.0,
            dynamics_duals: vec![],
            warm_start: None,
            iterations: 0,
            handed_to_clarabel: false,
        }
    }
}

/// The duality gap tolerance (absolute and relative) on a sub-problem.
pub(super) const SUBPROBLEM_GAP_TOL: f64 = 1e-6;
/// The feasibility tolerance on a sub-problem.
pub(super) const SUBPROBLEM_FEAS_TOL: f64 = 1e-7;

/// Interior-point iterations Clarabel may take on one sub-problem.
pub const MAX_SUBPROBLEM_ITERATIONS: u32 = 200;

/// Solves the sub-problem. Dimension errors from Clarabel (which would be a bug here) come back as a
/// failed status, never a panic.
pub fn solve(sp: &SubProblem) -> SubStep {
    solve_capped(sp, MAX_SUBPROBLEM_ITERATIONS)
}

/// [`solve`] stopped after `time_limit_s` seconds (the solvers' own clocks, the frame-by-frame solver's
/// and then Clarabel's in the time left; infinite: no limit): a sub-problem cut short is a failed step,
/// so the search's deadline holds inside one too.
pub fn solve_within_time(sp: &SubProblem, time_limit_s: f64) -> SubStep {
    solve_limited(sp, MAX_SUBPROBLEM_ITERATIONS, time_limit_s, None)
}

/// [`solve_within_time`] with the frame-by-frame solver started where the last sub-problem of the stage
/// ended (`warm`, its [`SubStep::warm_start`]). A warm solve that ends for its numerics or at the
/// iteration cap is solved again from cold before Clarabel is asked.
pub(super) fn solve_warm(sp: &SubProblem, time_limit_s: f64, warm: Option<&WarmStart>) -> SubStep {
    solve_limited(sp, MAX_SUBPROBLEM_ITERATIONS, time_limit_s, warm)
}

/// [`solve`] with the solvers' interior-point iteration cap given (tests force Clarabel's
/// `MaxIterations` status with it).
pub fn solve_capped(sp: &SubProblem, max_iterations: u32) -> SubStep {
    solve_limited(sp, max_iterations, f64::INFINITY, None)
}

/// [`solve`] with the iteration cap and time limit, seconds, and the frame-by-frame solver's warm start:
/// by [`SubProblem::solver`], then by Clarabel where the frame-by-frame solver gives no solution.
fn solve_limited(
    sp: &SubProblem,
    max_iterations: u32,
    time_limit_s: f64,
    warm: Option<&WarmStart>,
) -> SubStep {
    let layout = Layout::of(sp);
    let rhs = wall_rhs(sp);
    let started = std::time::Instant::now();
    let staged = match sp.solver {
        SubProblemSolver::Riccati => {
            let problem = stagewise::StagedProblem::new(sp, &layout, &rhs);
            let solved = stagewise::solve(&problem, max_iterations, time_limit_s, warm);
            let solved = match solved {
                Err(stagewise::NotStaged::Numerics | stagewise::NotStaged::MaxIterations)
                    if warm.is_some() =>
                {
                    let left_s = time_limit_s - started.elapsed().as_secs_f64();
                    stagewise::solve(&problem, max_iterations, left_s, None)
                }
                solved => solved,
            };
            match solved {
                Ok(solution) => Some(solution),
                // Clarabel would have no time left either: setting it up would be work after the
                // deadline (on a run of thousands of frames, tenths of a second).
                Err(stagewise::NotStaged::TimeLimit) => {
                    return SubStep::failed(SubStepStatus::Failed("time limit reached".into()))
                }
                Err(_) => None,
            }
        }
        SubProblemSolver::Clarabel => None,
    };
    if let Some(s) = staged {
        let status = SubStepStatus::Solved { almost: s.almost };
        let step = sub_step_of(sp, &layout, status, s.x, s.dynamics_duals, s.iterations);
        return SubStep {
            warm_start: Some(s.warm_start),
            feedback: s.feedback,
            ..step
        };
    }
    let handed_to_clarabel = sp.solver == SubProblemSolver::Riccati;
    let left_s = time_limit_s - started.elapsed().as_secs_f64();
    let step = match clarabel_solved(sp, &layout, &rhs, max_iterations, left_s) {
        Ok(solution) if solution.x.len() == layout.n_vars() => {
            // Clarabel's duals begin with those of the dynamics rows, four a frame.
            let z = &solution.z;
            let duals = (0..layout.n_frames)
                .map(|k| std::array::from_fn(|i| z.get(4 * k + i).copied().unwrap_or(0.0)))
                .collect();
            sub_step_of(
                sp,
                &layout,
                solution.status,
                solution.x,
                duals,
                solution.iterations,
            )
        }
        Ok(_) => SubStep::failed(SubStepStatus::Failed("solution of the wrong size".into())),
        Err(no) => SubStep::failed(SubStepStatus::Failed(no.to_string())),
    };
    SubStep {
        handed_to_clarabel,
        ..step
    }
}

/// Where each variable of a sub-problem sits: the free controls first, then `4 n` state changes, then
/// one slack per group of wall rows. Both solvers read and write it.
pub(super) struct Layout {
    /// Per frame `k` and control `j`, at `2 k + j`, its variable; `None`: fixed.
    control_var: Vec<Option<usize>>,
    /// Free controls.
    n_controls: usize,
    /// Frames.
    pub(super) n_frames: usize,
    /// Per wall row, its slack.
    pub(super) row_slack: Vec<usize>,
    /// Slacks (groups of wall rows).
    pub(super) n_slacks: usize,
    /// Per frame, each control's allowed change `[-lo, hi]`, scaled.
    pub(super) ranges: Vec<[(f64, f64); 2]>,
}

impl Layout {
    pub(super) fn of(sp: &SubProblem) -> Layout {
        let n = sp.jacobians.len();
        // One slack per group of wall rows, numbered in order of first appearance.
        let mut slack_of_group: Vec<Option<usize>> = Vec::new();
        let mut row_slack: Vec<usize> = Vec::with_capacity(sp.walls.len());
        let mut n_slacks = 0;
        for w in sp.walls {
            if slack_of_group.len() <= w.group {
                slack_of_group.resize(w.group + 1, None);
            }
            let slack = *slack_of_group[w.group].get_or_insert_with(|| {
                n_slacks += 1;
                n_slacks - 1
            });
            row_slack.push(slack);
        }
        let ranges: Vec<[(f64, f64); 2]> = (0..n)
            .map(|k| {
                let (slo, shi) = sp.sigma_range[k];
                let (clo, chi) = sp.c_range[k];
                [
                    (slo.max(0.0), shi.max(0.0)),
                    (clo.max(0.0) / C_SCALE_UPS, chi.max(0.0) / C_SCALE_UPS),
                ]
            })
            .collect();
        // A control whose allowed change is empty (a side fixed at +-1, a frame held on the kink) is no
        // variable at all: its change is zero. (A box of zero width has no interior, which costs an
        // interior-point method many iterations; an equality row for it would only make the system
        // larger.)
        let mut control_var: Vec<Option<usize>> = Vec::with_capacity(2 * n);
        let mut n_controls = 0;
        for range in &ranges {
            for (lo, hi) in range {
                control_var.push((lo + hi > FIXED_RANGE).then(|| {
                    n_controls += 1;
                    n_controls - 1
                }));
            }
        }
        Layout {
            control_var,
            n_controls,
            n_frames: n,
            row_slack,
            n_slacks,
            ranges,
        }
    }

    /// The variable of control `j` of frame `k`; `None`: fixed.
    pub(super) fn iu(&self, k: usize, j: usize) -> Option<usize> {
        self.control_var[2 * k + j]
    }

    /// The variable of state change `i` after frame `k`.
    pub(super) fn ix(&self, k: usize, i: usize) -> usize {
        self.n_controls + 4 * k + i
    }

    /// The variable of slack `j`.
    pub(super) fn is(&self, j: usize) -> usize {
        self.n_controls + 4 * self.n_frames + j
    }

    pub(super) fn n_vars(&self) -> usize {
        self.n_controls + 4 * self.n_frames + self.n_slacks
    }

    /// Per frame `k`, the variables of the curvature block's inputs `(V_{k-1}, psi_{k-1}, sigma_k,
    /// c_k)` with their scales.
    pub(super) fn curvature_vars(&self, k: usize) -> [Option<(usize, f64)>; 4] {
        [
            (k > 0).then(|| (self.ix(k.saturating_sub(1), 2), 1.0)),
            (k > 0).then(|| (self.ix(k.saturating_sub(1), 3), 1.0)),
            self.iu(k, 0).map(|v| (v, control_scale(0))),
            self.iu(k, 1).map(|v| (v, control_scale(1))),
        ]
    }
}

/// Per wall row, its right-hand side: the clearance of the current position (moved by the wall shift)
/// less the margin, units.
fn wall_rhs(sp: &SubProblem) -> Vec<f64> {
    sp.walls
        .iter()
        .map(|w| {
            let shift = sp
                .wall_shift
                .and_then(|e| e.get(w.frame).copied())
                .unwrap_or_default();
            w.plane.side(sp.positions[w.frame] + shift) - sp.margin
        })
        .collect()
}

/// The sub-problem solved by Clarabel: built in its form and run ([`clarabel_solution`]).
fn clarabel_solved(
    sp: &SubProblem,
    layout: &Layout,
    rhs: &[f64],
    max_iterations: u32,
    time_limit_s: f64,
) -> std::result::Result<Solution, NoSolution> {
    let (a, b, cones) = clarabel_rows(sp, layout, rhs);
    let (p, q) = clarabel_objective(sp, layout);
    let problem = ClarabelProblem {
        p: &p,
        q: &q,
        a: &a,
        b: &b,
        cones: &cones,
    };
    clarabel_solution(&problem, max_iterations, time_limit_s)
}

/// The rows `A z + s = b, s in K`: the linearised dynamics (zero cone, one block per frame), then the
/// wall rows, the slacks' signs and the controls' boxes (nonnegative cone).
fn clarabel_rows(
    sp: &SubProblem,
    layout: &Layout,
    rhs: &[f64],
) -> (CscMatrix<f64>, Vec<f64>, Vec<SupportedConeT<f64>>) {
    let (iu, ix, is) = (
        |k, j| layout.iu(k, j),
        |k, i| layout.ix(k, i),
        |j| layout.is(j),
    );
    let (mut ri, mut ci, mut vals): (Vec<usize>, Vec<usize>, Vec<f64>) = (vec![], vec![], vec![]);
    let mut b: Vec<f64> = Vec::new();
    let mut row = 0usize;
    // Dynamics: dx_k - A_k dx_{k-1} - B_k du_k = 0.
    for (k, jac) in sp.jacobians.iter().enumerate() {
        for i in 0..4 {
            ri.push(row);
            ci.push(ix(k, i));
            vals.push(1.0);
            if k > 0 {
                for (j, &a) in jac.a[i].iter().enumerate() {
                    if a != 0.0 {
                        ri.push(row);
                        ci.push(ix(k - 1, j));
                        vals.push(-a);
                    }
                }
            }
            for (j, &bb) in jac.b[i].iter().enumerate() {
                if bb == 0.0 {
                    continue;
                }
                if let Some(var) = iu(k, j) {
                    ri.push(row);
                    ci.push(var);
                    vals.push(-bb * control_scale(j));
                }
            }
            b.push(0.0);
            row += 1;
        }
    }
    let n_eq = row;
    // Walls: -n . dp_k - s_j <= n . p_k - offset - margin.
    for ((w, &slack), &rhs) in sp.walls.iter().zip(&layout.row_slack).zip(rhs) {
        ri.extend([row, row, row]);
        ci.extend([ix(w.frame, 0), ix(w.frame, 1), is(slack)]);
        vals.extend([-w.plane.normal.x, -w.plane.normal.y, -1.0]);
        b.push(rhs);
        row += 1;
    }
    // Slacks are nonnegative.
    for j in 0..layout.n_slacks {
        ri.push(row);
        ci.push(is(j));
        vals.push(-1.0);
        b.push(0.0);
        row += 1;
    }
    // Trust region and bounds on the controls that may move.
    for (k, range) in layout.ranges.iter().enumerate() {
        for (j, &(lo, hi)) in range.iter().enumerate() {
            let Some(var) = iu(k, j) else {
                continue;
            };
            ri.extend([row, row + 1]);
            ci.extend([var, var]);
            vals.extend([1.0, -1.0]);
            b.extend([hi, lo]);
            row += 2;
        }
    }
    let a = CscMatrix::new_from_triplets(row, layout.n_vars(), ri, ci, vals);
    let cones = vec![ZeroConeT(n_eq), NonnegativeConeT(row - n_eq)];
    (a, b, cones)
}

/// The objective `0.5 z' P z + q' z`: the regularisation of the control changes (diagonal) and the
/// curvature blocks (upper triangle; Clarabel sums repeated entries), minus the progress of the last
/// position, and the slacks' weight.
fn clarabel_objective(sp: &SubProblem, layout: &Layout) -> (CscMatrix<f64>, Vec<f64>) {
    let (n, nu, nvar) = (layout.n_frames, layout.n_controls, layout.n_vars());
    let (mut pr, mut pc, mut pv): (Vec<usize>, Vec<usize>, Vec<f64>) = (
        (0..nu).collect(),
        (0..nu).collect(),
        vec![CONTROL_REGULARISATION; nu],
    );
    if let Some(blocks) = sp.curvature {
        for (k, w) in blocks.iter().enumerate().take(n) {
            let vars = layout.curvature_vars(k);
            for (i, vi) in vars.iter().enumerate() {
                for (j, vj) in vars.iter().enumerate() {
                    if let (Some((a, sa)), Some((b, sb))) = (vi, vj) {
                        if a <= b && w[i][j] != 0.0 {
                            pr.push(*a);
                            pc.push(*b);
                            pv.push(w[i][j] * sa * sb);
                        }
                    }
                }
            }
        }
    }
    let p = CscMatrix::new_from_triplets(nvar, nvar, pr, pc, pv);
    let mut q = vec![0.0; nvar];
    if n > 0 {
        q[layout.ix(n - 1, 0)] = -sp.progress_dir.x;
        q[layout.ix(n - 1, 1)] = -sp.progress_dir.y;
    }
    for j in 0..layout.n_slacks {
        q[layout.is(j)] = sp.slack_weight;
    }
    (p, q)
}

/// The sub-step of a solution `x` (laid out by `layout`) with the duals of its dynamics rows, reached
/// after `iterations` of its solver: its control changes, the state changes they give, and what the
/// model predicts the step gains.
fn sub_step_of(
    sp: &SubProblem,
    layout: &Layout,
    status: SubStepStatus,
    x: Vec<f64>,
    dynamics_duals: Vec<[f64; 4]>,
    iterations: u32,
) -> SubStep {
    let n = layout.n_frames;
    // The step is judged on what its control changes do: a solver meets the dynamics rows only to its
    // feasibility tolerance, and along a chain of thousands of frames their residuals add up.
    let x = with_the_states_of_its_controls(sp.jacobians, x, layout);
    let du: Vec<(f64, f64)> = (0..n)
        .map(|k| {
            let change = |j: usize| layout.iu(k, j).map_or(0.0, |v| x[v] * control_scale(j));
            (change(0), change(1))
        })
        .collect();
    let dx: Vec<[f64; 4]> = (0..n)
        .map(|k| std::array::from_fn(|i| x[layout.ix(k, i)]))
        .collect();
    let predicted = predicted_gain(sp, layout, &x);
    SubStep {
        status,
        du,
        dx,
        feedback: None,
        predicted,
        dynamics_duals,
        warm_start: None,
        iterations,
        handed_to_clarabel: false,
    }
}

/// The model's predicted decrease of the merit at the solution `x`: progress, less the weighted
/// violation (per group of wall rows, one move, how far its worst row is below the accepted clearance,
/// before and after the step), less the curvature term `0.5 d' W d`.
fn predicted_gain(sp: &SubProblem, layout: &Layout, x: &[f64]) -> f64 {
    let n = layout.n_frames;
    let progress_gain = if n > 0 {
        sp.progress_dir.x * x[layout.ix(n - 1, 0)] + sp.progress_dir.y * x[layout.ix(n - 1, 1)]
    } else {
        0.0
    };
    let mut worst_before = vec![0.0_f64; layout.n_slacks];
    let mut worst_after = vec![0.0_f64; layout.n_slacks];
    for (w, &slack) in sp.walls.iter().zip(&layout.row_slack) {
        let side = w.plane.side(sp.positions[w.frame]);
        let dp = w.plane.normal.x * x[layout.ix(w.frame, 0)]
            + w.plane.normal.y * x[layout.ix(w.frame, 1)];
        worst_before[slack] = worst_before[slack].max(sp.accepted_clearance - side);
        worst_after[slack] = worst_after[slack].max(sp.accepted_clearance - side - dp);
    }
    let viol_before: f64 = worst_before.iter().sum();
    let viol_after: f64 = worst_after.iter().sum();
    let mut curvature_term = 0.0;
    if let Some(blocks) = sp.curvature {
        for (k, w) in blocks.iter().enumerate().take(n) {
            let d: [f64; 4] = layout
                .curvature_vars(k)
                .map(|v| v.map_or(0.0, |(i, s)| x[i] * s));
            for i in 0..4 {
                for j in 0..4 {
                    curvature_term += 0.5 * d[i] * w[i][j] * d[j];
                }
            }
        }
    }
    progress_gain + sp.slack_weight * (viol_before - viol_after) - curvature_term
}

/// What Clarabel returned for a solved sub-problem: the primal `x` and the duals `z`, those of the
/// dynamics rows first (Clarabel's convention `P x + q + A' z = 0`).
struct Solution {
    status: SubStepStatus,
    x: Vec<f64>,
    z: Vec<f64>,
    iterations: u32,
}

/// Why Clarabel gave no usable solution.
#[derive(Clone, Debug, PartialEq)]
enum NoSolution {
    /// It stopped for its numerics: at its iteration cap, with insufficient progress, or a numerical
    /// error.
    Numerics(SolverStatus),
    /// Anything else: a certificate of infeasibility, the time limit, the set-up, a non-finite solution.
    Other(String),
}

impl std::fmt::Display for NoSolution {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            NoSolution::Numerics(status) => write!(f, "{status:?}"),
            NoSolution::Other(why) => f.write_str(why),
        }
    }
}

/// A sub-problem in Clarabel's form: `min 0.5 x'Px + q'x  s.t.  Ax + s = b, s in cones`.
struct ClarabelProblem<'a> {
    p: &'a CscMatrix<f64>,
    q: &'a [f64],
    a: &'a CscMatrix<f64>,
    b: &'a [f64],
    cones: &'a [SupportedConeT<f64>],
}

/// Clarabel run on `problem` within `max_iterations` interior-point iterations and `time_limit_s`
/// seconds. Where it stops for its numerics ([`NoSolution::Numerics`]) the same problem is solved once
/// more with Ruiz equilibration, in the time left. Equilibration is not the first try: on these
/// sub-problems it doubled Clarabel's iterations (about 40 against 20 on the 100 fps bend) for no better
/// steps. But on the polish of thousands of frames in the law's first case Clarabel ended a third of the
/// sub-problems at its iteration cap, where the same sub-problems equilibrated take about 80
/// (docs/design.md, "What a sub-problem costs"); a step found so is one the trust region need not shrink
/// for.
fn clarabel_solution(
    problem: &ClarabelProblem,
    max_iterations: u32,
    time_limit_s: f64,
) -> std::result::Result<Solution, NoSolution> {
    let started = std::time::Instant::now();
    let first = clarabel_run(problem, max_iterations, time_limit_s, false);
    let Err(NoSolution::Numerics(_)) = first else {
        return first;
    };
    let left_s = time_limit_s - started.elapsed().as_secs_f64();
    if left_s > 0.0 {
        clarabel_run(problem, max_iterations, left_s, true)
    } else {
        first
    }
}

/// One Clarabel run of [`clarabel_solution`]'s problem, with Ruiz equilibration or without.
fn clarabel_run(
    problem: &ClarabelProblem,
    max_iterations: u32,
    time_limit_s: f64,
    equilibrate: bool,
) -> std::result::Result<Solution, NoSolution> {
    let settings: DefaultSettings<f64> = DefaultSettingsBuilder::default()
        .verbose(false)
        .presolve_enable(false)
        .max_iter(max_iterations)
        .time_limit(time_limit_s)
        .equilibrate_enable(equilibrate)
        // A sub-problem is one step of the SCP, linearised again at the next iteration: the step needs
        // the accuracy of the trust region, not of the last digit. Iterative refinement (up to 10 extra
        // KKT solves per interior-point iteration) and gap tolerances of 1e-8 more than doubled the time
        // of a sub-problem for steps no better (docs/design.md, "What a sub-problem costs").
        .iterative_refinement_enable(false)
        .tol_gap_abs(SUBPROBLEM_GAP_TOL)
        .tol_gap_rel(SUBPROBLEM_GAP_TOL)
        .tol_feas(SUBPROBLEM_FEAS_TOL)
        .build()
        .map_err(|e| NoSolution::Other(format!("settings: {e}")))?;
    let ClarabelProblem { p, q, a, b, cones } = *problem;
    let mut solver = DefaultSolver::new(p, q, a, b, cones, settings)
        .map_err(|e| NoSolution::Other(format!("setup: {e:?}")))?;
    solver.solve();
    let status = match solver.solution.status {
        SolverStatus::Solved => SubStepStatus::Solved { almost: false },
        SolverStatus::AlmostSolved => SubStepStatus::Solved { almost: true },
        numerics @ (SolverStatus::MaxIterations
        | SolverStatus::NumericalError
        | SolverStatus::InsufficientProgress) => return Err(NoSolution::Numerics(numerics)),
        other @ (SolverStatus::PrimalInfeasible
        | SolverStatus::DualInfeasible
        | SolverStatus::AlmostPrimalInfeasible
        | SolverStatus::AlmostDualInfeasible
        | SolverStatus::MaxTime
        | SolverStatus::CallbackTerminated
        | SolverStatus::Unsolved) => return Err(NoSolution::Other(format!("{other:?}"))),
    };
    let x = std::mem::take(&mut solver.solution.x);
    if x.iter().any(|v| !v.is_finite()) {
        return Err(NoSolution::Other("non-finite solution".into()));
    }
    Ok(Solution {
        status,
        x,
        z: std::mem::take(&mut solver.solution.z),
        iterations: solver.info.iterations,
    })
}

/// The solution `x` with its state changes replaced by those its control changes give through the
/// linearised dynamics, frame by frame: `dx_k = A_k dx_{k-1} + B_k du_k` (`iu`, `ix`: the variables of a
/// frame's controls and state changes, as laid out by [`solve`]).
///
/// Clarabel meets the dynamics rows only to its feasibility tolerance, and along a chain of thousands of
/// frames their residuals add up: on a 2,217-frame run at 1000 fps a tenth of the solutions ended more
/// than 0.16 units from where their control changes take the trajectory, and a step that changed next to
/// nothing could predict that it took a frame out of a wall (docs/design.md, "What a step is judged
/// on").
fn with_the_states_of_its_controls(
    jacobians: &[FrameJacobian],
    mut x: Vec<f64>,
    layout: &Layout,
) -> Vec<f64> {
    let mut before = [0.0; 4];
    for (k, jac) in jacobians.iter().enumerate() {
        let du: [f64; 2] =
            std::array::from_fn(|j| layout.iu(k, j).map_or(0.0, |v| x[v] * control_scale(j)));
        let after = jac.state_change(&before, &du);
        for (i, &d) in after.iter().enumerate() {
            x[layout.ix(k, i)] = d;
        }
        before = after;
    }
    x
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::HalfPlane;
    use crate::physics::Vec2;
    use crate::test_stream::Stream;

    /// One frame moving along +x; progress along +x; a wall row keeping the end position at y <= 0.
    fn one_frame(
        jac: FrameJacobian,
        rhs_side: f64,
    ) -> (Vec<FrameJacobian>, Vec<Vec2>, Vec<WallRow>) {
        let walls = vec![WallRow {
            frame: 0,
            group: 0,
            plane: HalfPlane {
                normal: Vec2::new(0.0, -1.0),
                offset: -rhs_side,
            },
        }];
        (vec![jac], vec![Vec2::new(5.0, 0.0)], walls)
    }

    /// A frame that carries the state over unchanged and adds `b` times the control change.
    fn carrying_over(b: [[f64; 2]; 4]) -> FrameJacobian {
        let mut a = [[0.0; 4]; 4];
        for (i, row) in a.iter_mut().enumerate() {
            row[i] = 1.0;
        }
        FrameJacobian { a, b }
    }

    fn jacobian(v: f64) -> FrameJacobian {
        // d px / d c = v, d py / d sigma = v
        carrying_over([[0.0, v], [v, 0.0], [0.0, 0.0], [0.0, 0.0]])
    }

    /// The side moves the end position up and along, one unit each.
    fn side_moves_up_and_along() -> FrameJacobian {
        carrying_over([[1.0, 0.0], [1.0, 0.0], [0.0, 0.0], [0.0, 0.0]])
    }

    fn sub<'a>(
        j: &'a [FrameJacobian],
        p: &'a [Vec2],
        w: &'a [WallRow],
        ranges: &'a [(f64, f64)],
    ) -> SubProblem<'a> {
        SubProblem {
            jacobians: j,
            positions: p,
            walls: w,
            margin: 0.0,
            accepted_clearance: 0.0,
            slack_weight: 100.0,
            progress_dir: Vec2::new(1.0, 0.0),
            sigma_range: ranges,
            c_range: ranges,
            curvature: None,
            wall_shift: None,
            solver: SubProblemSolver::Riccati,
            with_feedback: false,
        }
    }

    /// `sp` solved by each solver, the frame-by-frame one first.
    fn by_each_solver(sp: &SubProblem) -> [SubStep; 2] {
        [SubProblemSolver::Riccati, SubProblemSolver::Clarabel]
            .map(|solver| solve(&SubProblem { solver, ..*sp }))
    }

    #[test]
    fn a_sub_problem_out_of_time_frame_by_frame_is_not_handed_to_clarabel() {
        let (j, p, w) = one_frame(jacobian(0.01), 10.0);
        let ranges = [(1.0, 1.0)];
        let sp = sub(&j, &p, &w, &ranges);
        assert_eq!(sp.solver, SubProblemSolver::Riccati);
        let r = solve_within_time(&sp, 0.0);
        // Clarabel, given no time, reports its own status; this one is the frame-by-frame solver's.
        assert_eq!(
            r.status,
            SubStepStatus::Failed("time limit reached".into()),
            "{:?}",
            r.status
        );
        assert!(r.du.is_empty(), "{:?}", r.du);
    }

    #[test]
    fn a_plain_sub_step_moves_to_the_trust_region_edge_of_progress() {
        let (j, p, w) = one_frame(jacobian(0.01), 10.0);
        let ranges = [(1.0, 1.0)];
        for r in by_each_solver(&sub(&j, &p, &w, &ranges)) {
            assert_eq!(r.status, SubStepStatus::Solved { almost: false });
            // Progress is 0.01 per ups of c: c rises to its bound, +1 ups (to the duality gap's
            // precision: the frame-by-frame solver stops 1.6e-6 ups short of it).
            assert!((r.du[0].1 - 1.0).abs() < 1e-5, "{:?}", r.du);
            assert!((r.predicted - 0.01).abs() < 1e-6, "{}", r.predicted);
        }
    }

    #[test]
    fn a_control_with_no_room_stays_and_the_others_step() {
        // Two frames; every control moves the end position along +x by its own amount per unit (c per
        // ups). Frame 0's side and frame 1's c have no room: they stay, and the others rise to their
        // bounds. A control mapped to the wrong variable would move, or gain another's progress.
        let jac = |b_sigma: f64, b_c: f64| {
            carrying_over([[b_sigma, b_c], [0.0, 0.0], [0.0, 0.0], [0.0, 0.0]])
        };
        let j = [jac(1.0, 2.0), jac(3.0, 4.0)];
        let p = [Vec2::new(5.0, 0.0), Vec2::new(10.0, 0.0)];
        let sigma_range = [(0.0, 0.0), (0.5, 0.5)];
        let c_range = [(1.0, 1.0), (0.0, 0.0)];
        let sp = SubProblem {
            sigma_range: &sigma_range,
            c_range: &c_range,
            ..sub(&j, &p, &[], &sigma_range)
        };
        for r in by_each_solver(&sp) {
            assert_eq!(r.status, SubStepStatus::Solved { almost: false });
            assert_eq!((r.du[0].0, r.du[1].1), (0.0, 0.0), "{:?}", r.du);
            assert!((r.du[0].1 - 1.0).abs() < 1e-6, "{:?}", r.du);
            assert!((r.du[1].0 - 0.5).abs() < 1e-6, "{:?}", r.du);
            // 2 per ups of frame 0's c, 3 per unit of frame 1's side.
            assert!((r.predicted - (2.0 + 1.5)).abs() < 1e-5, "{}", r.predicted);
            assert_eq!(r.dynamics_duals.len(), 2);
        }
    }

    #[test]
    fn a_wall_shift_moves_the_wall_rows_by_what_the_model_leaves_out() {
        // The side moves the end position up and along, one unit each; the wall keeps it at y <= 0.5.
        // Unshifted, the side rises until the wall binds (0.5); with 0.2 units of y the model leaves out,
        // only to 0.3. The step's position change is reported either way.
        let jac = side_moves_up_and_along();
        let (j, p, w) = one_frame(jac, 0.5);
        let ranges = [(1.0, 1.0)];
        let plain = by_each_solver(&sub(&j, &p, &w, &ranges));
        let left_out = [Vec2::new(0.0, 0.2)];
        let shifted = by_each_solver(&SubProblem {
            wall_shift: Some(&left_out),
            ..sub(&j, &p, &w, &ranges)
        });
        let cases = plain.iter().map(|r| (r, 0.5));
        for (r, side) in cases.chain(shifted.iter().map(|r| (r, 0.3))) {
            assert_eq!(r.status, SubStepStatus::Solved { almost: false });
            assert!((r.du[0].0 - side).abs() < 1e-6, "{:?}", r.du);
            assert!((r.dp(0).y - side).abs() < 1e-6, "{:?}", r.dx);
        }
    }

    #[test]
    fn clarabel_out_of_iterations_is_a_failed_step_not_a_panic() {
        let (j, p, w) = one_frame(jacobian(0.01), 10.0);
        let ranges = [(1.0, 1.0)];
        let sp = SubProblem {
            solver: SubProblemSolver::Clarabel,
            with_feedback: false,
            ..sub(&j, &p, &w, &ranges)
        };
        let r = solve_capped(&sp, 1);
        assert!(
            matches!(r.status, SubStepStatus::Failed(ref s) if s.contains("MaxIterations")),
            "{:?}",
            r.status
        );
        assert!(r.du.is_empty());
    }

    #[test]
    fn a_sub_problem_clarabel_stops_on_for_its_numerics_is_solved_again_equilibrated() {
        // Three boxes |x_i| <= 1 written with row scales 1e-7, 1 and 1e7, the objective pushing each x_i
        // up: as it is, Clarabel stops without a solution (insufficient progress, its numerics);
        // equilibrated it solves it, every x_i at 1.
        let scales = [1e-7, 1.0, 1e7];
        let (mut rows, mut cols, mut vals, mut b) = (vec![], vec![], vec![], vec![]);
        for (i, s) in scales.iter().enumerate() {
            rows.extend([2 * i, 2 * i + 1]);
            cols.extend([i, i]);
            vals.extend([*s, -*s]);
            b.extend([*s, *s]);
        }
        let a = CscMatrix::new_from_triplets(6, 3, rows, cols, vals);
        let p = CscMatrix::new_from_triplets(3, 3, vec![0, 1, 2], vec![0, 1, 2], vec![1e-6; 3]);
        let cones = [NonnegativeConeT(6)];
        let problem = ClarabelProblem {
            p: &p,
            q: &[-1.0; 3],
            a: &a,
            b: &b,
            cones: &cones,
        };
        let as_it_is = clarabel_run(&problem, MAX_SUBPROBLEM_ITERATIONS, f64::INFINITY, false);
        assert!(
            matches!(as_it_is, Err(NoSolution::Numerics(_))),
            "{:?}",
            as_it_is.err()
        );
        let solved = clarabel_solution(&problem, MAX_SUBPROBLEM_ITERATIONS, f64::INFINITY)
            .unwrap_or_else(|e| panic!("not solved again equilibrated: {e}"));
        assert!(
            solved.x.iter().all(|x| (x - 1.0).abs() < 1e-4),
            "{:?}",
            solved.x
        );
    }

    #[test]
    fn non_finite_data_is_a_failed_step_not_a_panic() {
        let (j, p, w) = one_frame(jacobian(f64::NAN), 10.0);
        let ranges = [(1.0, 1.0)];
        for r in by_each_solver(&sub(&j, &p, &w, &ranges)) {
            assert!(
                matches!(r.status, SubStepStatus::Failed(_)),
                "{:?}",
                r.status
            );
        }
    }

    #[test]
    fn the_rows_of_one_move_share_one_slack() {
        // Sigma moves the end position up and along: one unit of progress per unit of violation of two
        // walls of the same move, both out of reach. At a slack weight of 0.75 the step pays for the
        // violation once (0.75 < 1: sigma rises); paid per row (1.5 > 1) sigma would fall.
        let jac = side_moves_up_and_along();
        let wall = |offset: f64, group: usize| WallRow {
            frame: 0,
            group,
            plane: HalfPlane {
                normal: Vec2::new(0.0, -1.0),
                offset,
            },
        };
        let ranges = [(1.0, 1.0)];
        let (j, p) = (vec![jac], vec![Vec2::new(5.0, 0.0)]);
        for (groups, sigma_rises) in [([0, 0], true), ([0, 1], false)] {
            let w = [wall(50.0, groups[0]), wall(40.0, groups[1])];
            let sp = SubProblem {
                slack_weight: 0.75,
                ..sub(&j, &p, &w, &ranges)
            };
            for r in by_each_solver(&sp) {
                assert!(matches!(r.status, SubStepStatus::Solved { .. }));
                assert_eq!(
                    r.du[0].0 > 0.5,
                    sigma_rises,
                    "groups {groups:?}: {:?}",
                    r.du
                );
                // The prediction counts the move's worst row once: progress 1 less 0.75 per unit of
                // the worst violation, or nothing gained the other way.
                let expected = if sigma_rises {
                    1.0 - 0.75
                } else {
                    -1.0 + 2.0 * 0.75
                };
                assert!((r.predicted - expected).abs() < 1e-5, "{}", r.predicted);
            }
        }
    }

    #[test]
    fn an_unreachable_wall_is_paid_for_with_slack_not_infeasibility() {
        // The end position must move 50 units but the trust region allows 1 ups of change: the sub-problem
        // stays feasible through its slack and reports the violation it could not remove.
        let (j, p, w) = one_frame(jacobian(0.01), -50.0);
        let ranges = [(1.0, 1.0)];
        for r in by_each_solver(&sub(&j, &p, &w, &ranges)) {
            assert!(
                matches!(r.status, SubStepStatus::Solved { .. }),
                "{:?}",
                r.status
            );
            // It uses the whole sideways range to reduce the violation: sigma moves y by -0.01.
            assert!((r.du[0].0 + 1.0).abs() < 1e-6, "{:?}", r.du);
        }
    }

    /// Owned data of a random chain sub-problem shaped as the SCP makes them: frames that carry the
    /// state over with small couplings, wall rows on a move's two ends sharing the move's slack, some
    /// controls fixed, and curvature blocks `M M'`.
    struct RandomChain {
        jacobians: Vec<FrameJacobian>,
        positions: Vec<Vec2>,
        walls: Vec<WallRow>,
        sigma_range: Vec<(f64, f64)>,
        c_range: Vec<(f64, f64)>,
        curvature: Option<Vec<CurvatureBlock>>,
    }

    impl RandomChain {
        /// The chain as a sub-problem for the frame-by-frame solver, progress along `(0.8, 0.6)`.
        fn sub_problem(&self) -> SubProblem<'_> {
            SubProblem {
                jacobians: &self.jacobians,
                positions: &self.positions,
                walls: &self.walls,
                margin: 0.0,
                accepted_clearance: 0.0,
                slack_weight: 100.0,
                progress_dir: Vec2::new(0.8, 0.6),
                sigma_range: &self.sigma_range,
                c_range: &self.c_range,
                curvature: self.curvature.as_deref(),
                wall_shift: None,
                solver: SubProblemSolver::Riccati,
                with_feedback: false,
            }
        }
    }

    fn random_chain(s: &mut Stream) -> RandomChain {
        let n = 1 + (s.next() * 60.0) as usize;
        let mut chain = RandomChain {
            jacobians: vec![],
            positions: vec![],
            walls: vec![],
            sigma_range: vec![],
            c_range: vec![],
            curvature: None,
        };
        let mut y = 0.0;
        for k in 0..n {
            let mut a = [[0.0; 4]; 4];
            for (i, row) in a.iter_mut().enumerate() {
                for (j, x) in row.iter_mut().enumerate() {
                    *x = if i == j { 1.0 } else { s.within(-0.1, 0.1) };
                }
            }
            let b = std::array::from_fn(|_| [s.within(-1.0, 1.0), s.within(-0.1, 0.1)]);
            chain.jacobians.push(FrameJacobian { a, b });
            y += s.within(-1.0, 1.0);
            chain.positions.push(Vec2::new(k as f64, y));
            let range = |s: &mut Stream| {
                if s.next() < 0.2 {
                    (0.0, 0.0)
                } else {
                    (s.within(0.0, 0.5), s.within(0.0, 0.5))
                }
            };
            chain.sigma_range.push(range(s));
            let (lo, hi) = range(s);
            chain.c_range.push((10.0 * lo, 10.0 * hi));
            // Walls above and below the line, leaning either way: some rows violated (paid with
            // slack), some binding.
            for normal_y in [-1.0, 1.0] {
                if s.next() < 0.5 {
                    let normal = Vec2::new(s.within(-0.5, 0.5), normal_y);
                    let normal = normal * (1.0 / normal.length());
                    let plane = HalfPlane {
                        normal,
                        offset: normal.dot(Vec2::new(k as f64, y)) - s.within(-0.5, 3.0),
                    };
                    chain.walls.push(WallRow {
                        frame: k,
                        plane,
                        group: k,
                    });
                    if k > 0 {
                        chain.walls.push(WallRow {
                            frame: k - 1,
                            plane,
                            group: k,
                        });
                    }
                }
            }
        }
        if s.next() < 0.7 {
            let blocks = (0..n)
                .map(|_| {
                    let m: [[f64; 4]; 4] =
                        std::array::from_fn(|_| std::array::from_fn(|_| s.within(-1.0, 1.0)));
                    std::array::from_fn(|i| {
                        std::array::from_fn(|j| (0..4).map(|l| m[i][l] * m[j][l]).sum::<f64>())
                    })
                })
                .collect();
            chain.curvature = Some(blocks);
        }
        chain
    }

    /// `sp` laid out and solved frame by frame, from `warm` if given.
    fn frame_by_frame(
        sp: &SubProblem,
        warm: Option<&WarmStart>,
    ) -> Result<stagewise::StagedSolution, stagewise::NotStaged> {
        let layout = Layout::of(sp);
        let rhs = wall_rhs(sp);
        let problem = stagewise::StagedProblem::new(sp, &layout, &rhs);
        stagewise::solve(&problem, MAX_SUBPROBLEM_ITERATIONS, 10.0, warm)
    }

    /// [`frame_by_frame`], which must give a solution.
    fn solved_frame_by_frame(
        sp: &SubProblem,
        warm: Option<&WarmStart>,
    ) -> stagewise::StagedSolution {
        frame_by_frame(sp, warm).unwrap_or_else(|e| panic!("{e:?}"))
    }

    #[test]
    fn a_sub_problem_started_where_its_neighbour_ended_reaches_the_same_step_in_fewer_iterations() {
        // The SCP's next sub-problem after a rejected step: the same linearisation, the trust region
        // cut to a third. Started from where the first one ended, the solver must reach the step it
        // reaches from cold (the optimum's value is unique) and take fewer iterations over the cases:
        // a warm start that is not applied, or applied to the wrong rows, takes as many or more.
        let mut s = Stream(20261129);
        let (mut cold_iterations, mut warm_iterations) = (0, 0);
        for case in 0..40 {
            let c = random_chain(&mut s);
            let mut sp = c.sub_problem();
            let first = solved_frame_by_frame(&sp, None);
            let third = |r: &[(f64, f64)]| r.iter().map(|(lo, hi)| (lo / 3.0, hi / 3.0)).collect();
            let (sigma_range, c_range): (Vec<_>, Vec<_>) =
                (third(&c.sigma_range), third(&c.c_range));
            sp.sigma_range = &sigma_range;
            sp.c_range = &c_range;
            let cold = solved_frame_by_frame(&sp, None);
            let warm = solved_frame_by_frame(&sp, Some(&first.warm_start));
            let layout = Layout::of(&sp);
            let [cold_gain, warm_gain] = [&cold, &warm].map(|s| predicted_gain(&sp, &layout, &s.x));
            assert!(
                (cold_gain - warm_gain).abs() < 1e-5 * (1.0 + cold_gain.abs()),
                "case {case}: predicted {warm_gain} warm against {cold_gain} cold"
            );
            cold_iterations += cold.iterations;
            warm_iterations += warm.iterations;
        }
        assert!(
            warm_iterations < cold_iterations,
            "{warm_iterations} iterations warm against {cold_iterations} cold"
        );
    }

    #[test]
    fn a_warm_start_that_fails_is_solved_again_from_cold_before_clarabel() {
        // Infinite duals weigh every row infinitely: the warm solve fails for its numerics (duals of
        // 1e300 do not: the solver works back from them). The same sub-problem is then solved again
        // frame by frame from cold, which gives the cold solve's step to the last digit in as many
        // iterations. Handed to Clarabel instead (checked), the iterations are Clarabel's and the
        // assertion on them fails.
        let mut s = Stream(20261130);
        for case in 0..10 {
            let c = random_chain(&mut s);
            let sp = c.sub_problem();
            let poisoned = solved_frame_by_frame(&sp, None)
                .warm_start
                .with_duals(f64::INFINITY);
            assert!(
                frame_by_frame(&sp, Some(&poisoned)).is_err(),
                "case {case}: the poisoned warm start solved"
            );
            let cold = solve_warm(&sp, 10.0, None);
            let retried = solve_warm(&sp, 10.0, Some(&poisoned));
            assert_eq!(retried.status, cold.status, "case {case}");
            assert!(
                matches!(cold.status, SubStepStatus::Solved { .. }),
                "case {case}"
            );
            assert_eq!(retried.iterations, cold.iterations, "case {case}");
            assert_eq!(retried.du, cold.du, "case {case}");
        }
    }

    #[test]
    fn only_a_sub_problem_the_frame_by_frame_solver_cannot_take_is_counted_as_handed_to_clarabel() {
        let mut s = Stream(20261202);
        let mut chain = random_chain(&mut s);
        let [riccati, clarabel] = by_each_solver(&chain.sub_problem());
        assert_eq!(riccati.status, SubStepStatus::Solved { almost: false });
        assert!(!riccati.handed_to_clarabel);
        // Asked for Clarabel, it is not handed on: it is where it was sent.
        assert!(!clarabel.handed_to_clarabel);
        // Two slacks ending at the last frame: not a chain of frames, so Clarabel solves it.
        let last = chain.jacobians.len() - 1;
        let plane = HalfPlane {
            normal: Vec2::new(0.0, 1.0),
            offset: -100.0,
        };
        for group in [1000, 1001] {
            chain.walls.push(WallRow {
                frame: last,
                plane,
                group,
            });
        }
        let [handed, asked] = by_each_solver(&chain.sub_problem());
        assert_eq!(handed.status, SubStepStatus::Solved { almost: false });
        assert!(handed.handed_to_clarabel);
        assert!(!asked.handed_to_clarabel);
        assert_eq!(handed.du, asked.du);
    }

    #[test]
    fn both_solvers_find_the_same_step_on_random_chains_of_frames() {
        // The same convex QP: the optimum's value is unique, and with strictly convex curvature so are
        // its steps and duals. Either solver wrong (a row mis-signed, a frame's dynamics or curvature
        // misplaced, the duals' convention) moves the predicted gain or the duals apart.
        let mut s = Stream(20261128);
        let mut compared = 0;
        for case in 0..60 {
            let c = random_chain(&mut s);
            let sp = c.sub_problem();
            let layout = Layout::of(&sp);
            let rhs = wall_rhs(&sp);
            let staged = stagewise::solve(
                &stagewise::StagedProblem::new(&sp, &layout, &rhs),
                MAX_SUBPROBLEM_ITERATIONS,
                10.0,
                None,
            );
            assert!(staged.is_ok(), "case {case}: {:?}", staged.err());
            let [riccati, clarabel] = by_each_solver(&sp);
            assert_eq!(
                clarabel.status,
                SubStepStatus::Solved { almost: false },
                "case {case}"
            );
            assert_eq!(
                riccati.status,
                SubStepStatus::Solved { almost: false },
                "case {case}"
            );
            let scale = 1.0 + clarabel.predicted.abs();
            assert!(
                (riccati.predicted - clarabel.predicted).abs() < 1e-4 * scale,
                "case {case}: predicted {} against {}",
                riccati.predicted,
                clarabel.predicted
            );
            if c.curvature.is_some() {
                let largest = clarabel
                    .dynamics_duals
                    .iter()
                    .flatten()
                    .fold(1.0_f64, |m, z| m.max(z.abs()));
                for (k, (zr, zc)) in riccati
                    .dynamics_duals
                    .iter()
                    .zip(&clarabel.dynamics_duals)
                    .enumerate()
                {
                    for i in 0..4 {
                        assert!(
                            (zr[i] - zc[i]).abs() < 1e-3 * largest,
                            "case {case}, frame {k}, dual {i}: {} against {}",
                            zr[i],
                            zc[i]
                        );
                    }
                }
                compared += 1;
            }
        }
        assert!(compared >= 30, "only {compared} cases had curvature");
    }
}
