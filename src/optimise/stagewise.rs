//! The convexified sub-step solved frame by frame: a primal-dual interior-point method (Mehrotra's
//! predictor-corrector) whose Newton systems are solved by a Riccati recursion over the frames.
//!
//! The sub-problem of [`super::qp`] is an optimal-control problem: the state change `dx_k` of frame `k`
//! follows from the one before and the frame's own variables `v_k` (its free control changes and the
//! slack of the move ending at frame `k`) through `dx_k = A_k dx_{k-1} + B_k v_k`; every inequality row
//! touches one frame's `(dx_{k-1}, v_k)` (a wall row on `dx_k` is written through the dynamics); the
//! curvature couples `dx_{k-1}` and `v_k` only; progress is linear in the last state. A general sparse
//! factorisation of its KKT system (Clarabel's) does not use that chain; the recursion needs per frame a
//! handful of 4x4 products and the Cholesky factor of a matrix at most 3x3, and solves a sub-problem
//! three to eight times faster than Clarabel (docs/design.md, "The sub-problem solved frame by frame").
//!
//! Per interior-point iteration: the inequality rows `G z + t = h` with slacks `t >= 0` and duals
//! `lambda >= 0` are eliminated (weights `lambda / t`), which leaves an equality-constrained QP in the
//! frames' variables; its backward Riccati pass gives the feedback `v_k = K_k dx_{k-1} + k_k`, its
//! forward pass the step. The rows' residuals `G z + t - h` start where the first iterate puts them
//! ([`started`]) and shrink by `1 - alpha` with every step of length `alpha` (the rows are linear), so
//! they are tracked, not recomputed, until the tolerances are checked.
//!
//! A sub-problem of an SCP stage is the last one linearised about a trajectory a step away, or the same
//! one with its wall rows moved: its rows are where they were, and most are as active or as loose as
//! they were. So the last solution's slacks and duals ([`WarmStart`]) can start the next solve, each
//! lifted to at least [`WARM_START_FLOOR`]: the first steps then need not find again which rows are
//! active. The SCP asks for it in its stages with the sides fixed (`ScpProblem::warm_started`).

use super::qp::{
    control_scale, Layout, SubProblem, CONTROL_REGULARISATION, SUBPROBLEM_FEAS_TOL,
    SUBPROBLEM_GAP_TOL,
};

/// Most variables a frame has: its two controls and one slack.
const MAX_FRAME_VARS: usize = 3;

/// The sub-problem with its layout (the variables indexed as for Clarabel, so that a solution of either
/// solver is read by the same code) and its wall rows' right-hand sides.
pub(super) struct StagedProblem<'a> {
    sp: &'a SubProblem<'a>,
    layout: &'a Layout,
    wall_rhs: &'a [f64],
    /// Gradient of the objective in the last state change (minus the progress direction).
    terminal_gradient: [f64; 4],
}

impl<'a> StagedProblem<'a> {
    /// `sp` laid out by `layout`, its wall rows' right-hand sides `wall_rhs` (units).
    pub(super) fn new(sp: &'a SubProblem<'a>, layout: &'a Layout, wall_rhs: &'a [f64]) -> Self {
        let n = sp.progress_dir;
        StagedProblem {
            sp,
            layout,
            wall_rhs,
            terminal_gradient: [-n.x, -n.y, 0.0, 0.0],
        }
    }
}

/// Where a solve ended, to start the next one of the same chain: per frame its number of rows, and per
/// row its slack and dual.
#[derive(Clone, Debug)]
pub struct WarmStart {
    rows_per_frame: Vec<usize>,
    t: Vec<f64>,
    lambda: Vec<f64>,
}

/// A warm start's slacks and duals are lifted to at least this. Left at the last solution's
/// complementarity (`t lambda` near 1e-11), a row active there but loose now blocks the steps until its
/// pair has grown back by orders of magnitude; lifted much less, warm starts fail for their numerics;
/// lifted much more, they start as far from the solution as a cold start (docs/design.md, "A warm
/// start for the sub-problems").
const WARM_START_FLOOR: f64 = 0.1;

impl WarmStart {
    /// This warm start with every dual set to `lambda` (an infinite one is a start the solver cannot
    /// work from), for tests of what a failed warm solve leads to.
    #[cfg(test)]
    pub(super) fn with_duals(&self, lambda: f64) -> WarmStart {
        WarmStart {
            lambda: vec![lambda; self.lambda.len()],
            ..self.clone()
        }
    }

    /// Whether it holds the slacks and duals of every frame of `frames` (each with as many rows).
    fn covers(&self, frames: &[Frame]) -> bool {
        self.rows_per_frame.len() == frames.len()
            && frames
                .iter()
                .zip(&self.rows_per_frame)
                .all(|(f, &rows)| f.rows.len() == rows)
    }
}

/// A solution in Clarabel's layout: the primal `x` and, per frame, the duals of its dynamics rows in
/// Clarabel's convention (`P x + q + A' z = 0`).
pub(super) struct StagedSolution {
    /// All variables, laid out as in [`StagedProblem`].
    pub x: Vec<f64>,
    /// Per frame, the duals of its dynamics rows `(px, py, V, psi)`.
    pub dynamics_duals: Vec<[f64; 4]>,
    /// Met only the looser tolerances.
    pub almost: bool,
    /// The last iterate, to start the next sub-problem from.
    pub warm_start: WarmStart,
    /// Interior-point iterations taken.
    pub iterations: u32,
    /// Per frame, the feedback of its controls `(sigma, c)` (c in ups) on the state change before it
    /// `(px, py, V, psi)`, from the Newton system at the solution; `None` where that system could not be
    /// factorised.
    pub feedback: Option<Vec<ControlFeedback>>,
}

/// A frame's feedback: row `j` is control `j`'s change (`sigma`, then `c` in ups) per unit of each
/// entry of the state change before the frame `(px, py, V, psi)`.
pub type ControlFeedback = [[f64; 4]; 2];

/// Why the frame-by-frame solver gave no solution (the caller then asks Clarabel).
#[derive(Clone, Debug, PartialEq)]
pub(super) enum NotStaged {
    /// A slack is shared by rows more than one frame apart, or two slacks end at one frame: the rows
    /// are not a chain of frames.
    NotAChain,
    /// A frame's reduced Hessian was not positive definite, or a value not finite. Where an active wall
    /// row meets an active bound their weights (`lambda / t`, near 1e12) make the Riccati pass subtract
    /// numbers of that size, and the value matrix can lose its digits.
    Numerics,
    /// The iteration cap came before the tolerances.
    MaxIterations,
    /// The time limit came first.
    TimeLimit,
}

/// What a frame's variable is.
#[derive(Clone, Copy, Debug)]
enum FrameVar {
    /// Control `j` (0: side, 1: `c`) at variable `var` of the layout.
    Control { j: usize, var: usize },
    /// Slack `slack`.
    Slack { slack: usize },
}

/// One inequality row of a frame: `c . dx_{k-1} + d . v_k <= h`.
#[derive(Clone, Copy, Debug)]
struct Row {
    c: [f64; 4],
    d: [f64; MAX_FRAME_VARS],
    h: f64,
    /// A bound on one variable (`c = 0`, one entry of `d`): its index in `v`. Its weight in the Newton
    /// system falls on the diagonal only.
    bound: Option<usize>,
}

impl Row {
    /// `sign v[at] <= h`.
    fn bound(at: usize, sign: f64, h: f64) -> Row {
        let mut d = [0.0; MAX_FRAME_VARS];
        d[at] = sign;
        Row {
            c: [0.0; 4],
            d,
            h,
            bound: Some(at),
        }
    }

    /// `g += weight (c, d)`: the row's pull on a frame's gradient at dual `weight`.
    #[inline]
    fn add_to(&self, g: &mut [f64; 4 + MAX_FRAME_VARS], weight: f64) {
        if let Some(at) = self.bound {
            g[4 + at] += self.d[at] * weight;
            return;
        }
        for (gi, a) in g.iter_mut().zip(self.c.iter().chain(&self.d)) {
            *gi += a * weight;
        }
    }
}

/// A frame of the chain: its variables, its rows, its cost `0.5 z' H z + g' z` in
/// `z = (dx_{k-1}, v_k)` and its dynamics `dx_k = A dx_{k-1} + B v_k`.
struct Frame {
    vars: Vec<FrameVar>,
    /// Per variable, where the start puts it: a control at the centre of its box.
    centre: [f64; MAX_FRAME_VARS],
    rows: Vec<Row>,
    hessian: [[f64; 4 + MAX_FRAME_VARS]; 4 + MAX_FRAME_VARS],
    gradient: [f64; 4 + MAX_FRAME_VARS],
    a: [[f64; 4]; 4],
    b: [[f64; MAX_FRAME_VARS]; 4],
}

impl Frame {
    fn nv(&self) -> usize {
        self.vars.len()
    }

    /// `A dx + B v`.
    #[inline]
    fn step(&self, dx: &[f64; 4], v: &[f64; MAX_FRAME_VARS]) -> [f64; 4] {
        array_of(|i| {
            (0..4).map(|j| self.a[i][j] * dx[j]).sum::<f64>()
                + (0..self.nv()).map(|j| self.b[i][j] * v[j]).sum::<f64>()
        })
    }

    /// `c . dx + d . v` of a row.
    #[inline]
    fn row_value(&self, row: &Row, dx: &[f64; 4], v: &[f64; MAX_FRAME_VARS]) -> f64 {
        if let Some(at) = row.bound {
            return row.d[at] * v[at];
        }
        (0..4).map(|i| row.c[i] * dx[i]).sum::<f64>()
            + (0..self.nv()).map(|j| row.d[j] * v[j]).sum::<f64>()
    }

    /// `H z + g` at `z = (dx, v)`.
    #[inline]
    fn cost_gradient(&self, dx: &[f64; 4], v: &[f64; MAX_FRAME_VARS]) -> [f64; 4 + MAX_FRAME_VARS] {
        let z = joined(dx, v);
        let n = 4 + self.nv();
        array_of(|i| {
            if i < CURVED_FROM {
                self.gradient[i]
            } else if i < n {
                self.gradient[i]
                    + (CURVED_FROM..n)
                        .map(|j| self.hessian[i][j] * z[j])
                        .sum::<f64>()
            } else {
                0.0
            }
        })
    }
}

/// The first entry of `z = (dx_{k-1}, v_k)` a frame's cost is curved in: the position `(px, py)` enters
/// the frame linearly, so the Hessian's first two rows and columns are zero.
const CURVED_FROM: usize = 2;

/// The array whose entry `i` is `entry(i)`, computed in order. As `std::array::from_fn`, but always
/// inlined with its closure: the frame-by-frame passes build a few such arrays per frame and iteration,
/// and `from_fn`'s closures were left as calls there.
#[inline(always)]
fn array_of<T: Copy + Default, const N: usize>(mut entry: impl FnMut(usize) -> T) -> [T; N] {
    let mut out = [T::default(); N];
    for (i, o) in out.iter_mut().enumerate() {
        *o = entry(i);
    }
    out
}

fn joined(dx: &[f64; 4], v: &[f64; MAX_FRAME_VARS]) -> [f64; 4 + MAX_FRAME_VARS] {
    array_of(|i| if i < 4 { dx[i] } else { v[i - 4] })
}

/// Where a row sits: its frame, and its index among the frame's rows.
type RowAt = (usize, usize);

/// The frames of `p` and, per wall row, its frame and its index among the frame's rows; or
/// [`NotStaged::NotAChain`].
fn frames_of(p: &StagedProblem) -> Result<(Vec<Frame>, Vec<RowAt>), NotStaged> {
    let n = p.sp.jacobians.len();
    // Each slack belongs to the last frame of its rows; its rows must be at that frame or the one before.
    let mut slack_frame = vec![0usize; p.layout.n_slacks];
    for (w, &s) in p.sp.walls.iter().zip(&p.layout.row_slack) {
        slack_frame[s] = slack_frame[s].max(w.frame);
    }
    let mut slack_of_frame: Vec<Option<usize>> = vec![None; n];
    for (s, &k) in slack_frame.iter().enumerate() {
        if k >= n || slack_of_frame[k].replace(s).is_some() {
            return Err(NotStaged::NotAChain);
        }
    }
    let mut frames: Vec<Frame> = (0..n)
        .map(|k| frame_without_walls(p, k, slack_of_frame[k]))
        .collect();
    let mut wall_rows = Vec::with_capacity(p.sp.walls.len());
    for ((w, &rhs), &s) in p.sp.walls.iter().zip(p.wall_rhs).zip(&p.layout.row_slack) {
        let k = slack_frame[s];
        if w.frame + 1 < k {
            return Err(NotStaged::NotAChain);
        }
        let frame = &mut frames[k];
        let slack_at = frame.nv() - 1;
        let (nx, ny) = (w.plane.normal.x, w.plane.normal.y);
        let mut row = Row {
            c: [0.0; 4],
            d: [0.0; MAX_FRAME_VARS],
            h: rhs,
            bound: None,
        };
        if w.frame == k {
            // -n . (A dx + B v): the wall row of the frame's own end, through its dynamics.
            row.c = std::array::from_fn(|j| -(nx * frame.a[0][j] + ny * frame.a[1][j]));
            for j in 0..frame.nv() {
                row.d[j] = -(nx * frame.b[0][j] + ny * frame.b[1][j]);
            }
        } else {
            row.c = [-nx, -ny, 0.0, 0.0];
        }
        row.d[slack_at] -= 1.0;
        wall_rows.push((k, frame.rows.len()));
        frame.rows.push(row);
    }
    Ok((frames, wall_rows))
}

/// Frame `k` with its variables (free controls, then its slack if any), the rows of its controls'
/// boxes and its slack's sign, and its cost.
fn frame_without_walls(p: &StagedProblem, k: usize, slack: Option<usize>) -> Frame {
    let jac = &p.sp.jacobians[k];
    let mut vars: Vec<FrameVar> = (0..2)
        .filter_map(|j| p.layout.iu(k, j).map(|var| FrameVar::Control { j, var }))
        .collect();
    vars.extend(slack.map(|slack| FrameVar::Slack { slack }));
    // The first frame starts from no change: its incoming state carries nothing.
    let a = if k > 0 { jac.a } else { [[0.0; 4]; 4] };
    let mut b = [[0.0; MAX_FRAME_VARS]; 4];
    let mut rows = Vec::new();
    let mut hessian = [[0.0; 4 + MAX_FRAME_VARS]; 4 + MAX_FRAME_VARS];
    let mut gradient = [0.0; 4 + MAX_FRAME_VARS];
    let mut centre = [0.0; MAX_FRAME_VARS];
    for (at, var) in vars.iter().enumerate() {
        match *var {
            FrameVar::Control { j, .. } => {
                for (bi, ji) in b.iter_mut().zip(&jac.b) {
                    bi[at] = ji[j] * control_scale(j);
                }
                let (lo, hi) = p.layout.ranges[k][j];
                centre[at] = 0.5 * (hi - lo);
                rows.push(Row::bound(at, 1.0, hi));
                rows.push(Row::bound(at, -1.0, lo));
                hessian[4 + at][4 + at] += CONTROL_REGULARISATION;
            }
            FrameVar::Slack { .. } => {
                rows.push(Row::bound(at, -1.0, 0.0));
                gradient[4 + at] = p.sp.slack_weight;
            }
        }
    }
    if let Some(block) = p.sp.curvature.and_then(|c| c.get(k)) {
        // The block's inputs (V_{k-1}, psi_{k-1}, sigma_k, c_k) as the layout has them, placed in z: a
        // state change before the frame at its index there, a control at its place among the frame's
        // variables.
        let in_z = |var: usize| {
            vars.iter()
                .position(|v| matches!(v, FrameVar::Control { var: w, .. } if *w == var))
                .map_or_else(|| var - p.layout.ix(k.saturating_sub(1), 0), |at| 4 + at)
        };
        let inputs = p
            .layout
            .curvature_vars(k)
            .map(|v| v.map(|(var, s)| (in_z(var), s)));
        for (i, ai) in inputs.iter().enumerate() {
            for (j, aj) in inputs.iter().enumerate() {
                if let (Some((r, sr)), Some((c, sc))) = (ai, aj) {
                    debug_assert!(*r >= CURVED_FROM && *c >= CURVED_FROM);
                    hessian[*r][*c] += block[i][j] * sr * sc;
                }
            }
        }
    }
    Frame {
        vars,
        centre,
        rows,
        hessian,
        gradient,
        a,
        b,
    }
}

/// The tolerances loosened by this much: a solution that meets only these at the iteration cap is
/// "almost" solved (as Clarabel's `AlmostSolved`).
const ALMOST_FACTOR: f64 = 1e3;
/// Share of the way to the boundary that a step goes.
const STEP_TO_BOUNDARY: f64 = 0.99;

/// The iterate: per frame its variables and the state change after it, per row its slack and dual.
struct Iterate {
    v: Vec<[f64; MAX_FRAME_VARS]>,
    dx: Vec<[f64; 4]>,
    t: Vec<f64>,
    lambda: Vec<f64>,
    /// Per row, `G z + t - h`; a step of length `alpha` scales it by `1 - alpha` (the rows are linear).
    rp: Vec<f64>,
    /// Per frame, its cost's gradient `H z + g` at the iterate ([`Frame::cost_gradient`]): kept with the
    /// variables, as every pass of an iteration reads it.
    grad: Vec<[f64; 4 + MAX_FRAME_VARS]>,
}

/// A frame's part of the Newton system's factorisation.
#[derive(Clone, Copy, Default)]
struct FrameFactor {
    /// Lower Cholesky factor of the reduced Hessian in the frame's variables.
    chol: [[f64; MAX_FRAME_VARS]; MAX_FRAME_VARS],
    /// Cross term `Q_vx`.
    q_vx: [[f64; 4]; MAX_FRAME_VARS],
    /// Feedback `K = -Q_vv^-1 Q_vx`.
    gain: [[f64; 4]; MAX_FRAME_VARS],
}

/// A Newton direction.
#[derive(Default)]
struct Direction {
    dv: Vec<[f64; MAX_FRAME_VARS]>,
    dt: Vec<f64>,
    dlambda: Vec<f64>,
    /// Per frame, the feed-forward term of the backward pass that gave it.
    feed: Vec<[f64; MAX_FRAME_VARS]>,
}

impl Direction {
    /// Room for `frames` frames' and `rows` rows' changes (their values are written before they are read).
    fn sized(&mut self, frames: usize, rows: usize) {
        self.dv.resize(frames, [0.0; MAX_FRAME_VARS]);
        self.feed.resize(frames, [0.0; MAX_FRAME_VARS]);
        self.dt.resize(rows, 0.0);
        self.dlambda.resize(rows, 0.0);
    }
}

/// The buffers of an iteration, kept from one to the next: a solve's sub-problem has thousands of frames,
/// and every iteration would otherwise allocate and clear them all again.
#[derive(Default)]
struct Workspace {
    factors: Vec<FrameFactor>,
    /// The affine (predictor) direction and the corrector.
    affine: Direction,
    corrector: Direction,
    /// Per row, the complementarity residuals of the two directions.
    rc_affine: Vec<f64>,
    rc: Vec<f64>,
}

/// Solves `p` within `max_iterations` interior-point iterations and `time_limit_s` seconds.
///
/// Solved means: complementarity summed over the rows within the gap tolerance, stationarity within the
/// feasibility tolerance relative to the objective's largest gradient entry, and every row met within it
/// relative to the largest right-hand side (the tolerances of [`super::qp`]). The gap is absolute: the
/// objective carries the weighted violation the trust region cannot remove (thousands of units where a
/// start is far inside a wall), and a gap relative to it left a control 5e-4 short of its bound.
///
/// With `warm`, the slacks and duals of each frame with as many rows as there start from there (see
/// [`WarmStart`]); the other frames', and every primal variable, start as from cold.
pub(super) fn solve(
    p: &StagedProblem,
    max_iterations: u32,
    time_limit_s: f64,
    warm: Option<&WarmStart>,
) -> Result<StagedSolution, NotStaged> {
    let clock = std::time::Instant::now();
    let (frames, wall_rows) = frames_of(p)?;
    let offsets = row_offsets(&frames);
    let mut work = Workspace::default();
    let mut it = match warm {
        // Every frame's slacks and duals come from the warm start: the cold start's affine step would
        // be overwritten.
        Some(warm) if warm.covers(&frames) => centred(&frames),
        _ => started(p, &frames, &offsets, &mut work)?,
    };
    if let Some(warm) = warm {
        warm_started(&frames, &offsets, &mut it, warm);
    }
    let tolerances = Tolerances::of(p, &frames);
    let mut almost = false;
    for iteration in 0..max_iterations {
        if clock.elapsed().as_secs_f64() > time_limit_s {
            return Err(NotStaged::TimeLimit);
        }
        match tolerances.met(p, &frames, &offsets, &it) {
            Met::Solved => {
                return Ok(solution(
                    p, &frames, &wall_rows, &offsets, it, false, iteration,
                ));
            }
            Met::Almost => almost = true,
            Met::Not => almost = false,
        }
        mehrotra_step(p, &frames, &offsets, &mut it, &mut work)?;
    }
    if almost {
        return Ok(solution(
            p,
            &frames,
            &wall_rows,
            &offsets,
            it,
            true,
            max_iterations,
        ));
    }
    Err(NotStaged::MaxIterations)
}

/// Most weight a row has in the Newton system the feedback is taken from ([`feedback_at`]). At the
/// solution an active row weighs `lambda / t`, near 1e12 where `t` is a hair from zero: the gains then
/// hold every active row (a wall a frame is pressed on, a control at its trust bound) exactly, and a
/// frame whose controls are all held by bounds has no feedback left to give. Capped, an active row
/// still outweighs a frame's own curvature (the control regularisation is 1e-6) by orders of
/// magnitude. On a narrow 100 fps corridor the steps played with the capped gains were kept in half the
/// cases they were tried on, against 28 to 38 % uncapped or capped at 1e2 or 1e6 (docs/design.md, "A
/// rejected step played again with the sub-problem's feedback").
const FEEDBACK_ROW_WEIGHT_CAP: f64 = 1e4;

/// Per frame, the feedback of its controls on the state change before it (see [`ControlFeedback`]):
/// the Riccati gains `K_k = -Q_vv^-1 Q_vx` of the Newton system factorised at `it`, each row weighing
/// `lambda / t` up to [`FEEDBACK_ROW_WEIGHT_CAP`], so that an active row's weight holds the feedback to
/// it. A fixed control's row is zero; `None` where `p` does not ask for it
/// ([`SubProblem::with_feedback`]), the system is not positive definite or a gain not finite.
fn feedback_at(
    p: &StagedProblem,
    frames: &[Frame],
    offsets: &[usize],
    it: &Iterate,
) -> Option<Vec<ControlFeedback>> {
    if !p.sp.with_feedback {
        return None;
    }
    let mut factors = Vec::new();
    factorised_capped(frames, offsets, it, &mut factors, FEEDBACK_ROW_WEIGHT_CAP).ok()?;
    let feedback = frames
        .iter()
        .zip(factors.iter())
        .map(|(f, factor)| {
            let mut rows = [[0.0; 4]; 2];
            for (at, var) in f.vars.iter().enumerate() {
                if let FrameVar::Control { j, .. } = *var {
                    rows[j] = factor.gain[at].map(|g| g * control_scale(j));
                }
            }
            rows
        })
        .collect::<Vec<_>>();
    feedback
        .iter()
        .flatten()
        .flatten()
        .all(|g| g.is_finite())
        .then_some(feedback)
}

/// Per frame, the index of its first row among all rows.
fn row_offsets(frames: &[Frame]) -> Vec<usize> {
    frames
        .iter()
        .scan(0, |at, f| {
            let o = *at;
            *at += f.rows.len();
            Some(o)
        })
        .collect()
}

/// The tolerances of a solution, scaled to the problem's data.
struct Tolerances {
    gap: f64,
    stationarity: f64,
    feasibility: f64,
}

/// Which tolerances an iterate meets.
enum Met {
    Solved,
    Almost,
    Not,
}

impl Tolerances {
    fn of(p: &StagedProblem, frames: &[Frame]) -> Tolerances {
        let rhs_scale = frames
            .iter()
            .flat_map(|f| f.rows.iter())
            .fold(1.0_f64, |m, r| m.max(r.h.abs()));
        Tolerances {
            gap: SUBPROBLEM_GAP_TOL,
            stationarity: SUBPROBLEM_FEAS_TOL * gradient_scale(p, frames),
            feasibility: SUBPROBLEM_FEAS_TOL * rhs_scale,
        }
    }

    /// Whether `it` meets the tolerances, or the looser ones of "almost". Stationarity and the rows'
    /// residuals (a pass over the frames each) are measured only once the gap is within reach.
    fn met(&self, p: &StagedProblem, frames: &[Frame], offsets: &[usize], it: &Iterate) -> Met {
        let gap: f64 = it.t.iter().zip(&it.lambda).map(|(t, l)| t * l).sum();
        if gap > ALMOST_FACTOR * self.gap {
            return Met::Not;
        }
        let stationarity = stationarity(p, frames, offsets, it);
        let infeasibility = primal_residual(frames, offsets, it)
            .iter()
            .fold(0.0_f64, |m, r| m.max(r.abs()));
        let within = |factor: f64| {
            gap <= factor * self.gap
                && stationarity <= factor * self.stationarity
                && infeasibility <= factor * self.feasibility
        };
        if within(1.0) {
            Met::Solved
        } else if within(ALMOST_FACTOR) {
            Met::Almost
        } else {
            Met::Not
        }
    }
}

/// One predictor-corrector step (Mehrotra's): the affine direction drives complementarity to zero; how
/// far it gets sets the centring `sigma = (mu_aff / mu)^3`; the corrector adds the affine step's
/// second-order term and the centring. Both directions share one factorisation.
fn mehrotra_step(
    p: &StagedProblem,
    frames: &[Frame],
    offsets: &[usize],
    it: &mut Iterate,
    work: &mut Workspace,
) -> Result<(), NotStaged> {
    let m = it.t.len().max(1) as f64;
    affine_direction(p, frames, offsets, it, work)?;
    let (rc_aff, aff) = (&work.rc_affine, &work.affine);
    let alpha_aff = step_to_boundary(it, aff, 1.0);
    let mu = rc_aff.iter().sum::<f64>() / m;
    let mu_aff = (0..it.t.len())
        .map(|i| (it.t[i] + alpha_aff * aff.dt[i]) * (it.lambda[i] + alpha_aff * aff.dlambda[i]))
        .sum::<f64>()
        / m;
    let sigma = (mu_aff / mu).clamp(0.0, 1.0).powi(3);
    let rc = &mut work.rc;
    rc.clear();
    rc.extend((0..it.t.len()).map(|i| rc_aff[i] + aff.dt[i] * aff.dlambda[i] - sigma * mu));
    let dir = &mut work.corrector;
    direction(p, frames, offsets, &work.factors, it, rc, dir)?;
    let alpha = step_to_boundary(it, dir, STEP_TO_BOUNDARY);
    take_step(frames, it, dir, alpha);
    if it.v.iter().flatten().all(|v| v.is_finite()) {
        Ok(())
    } else {
        Err(NotStaged::Numerics)
    }
}

/// The Newton system factorised at `it`, and its affine direction, which drives every row's `t lambda`
/// to zero, into `work` (`factors`, `rc_affine`, `affine`).
fn affine_direction(
    p: &StagedProblem,
    frames: &[Frame],
    offsets: &[usize],
    it: &Iterate,
    work: &mut Workspace,
) -> Result<(), NotStaged> {
    factorised(frames, offsets, it, &mut work.factors)?;
    let rc = &mut work.rc_affine;
    rc.clear();
    rc.extend(it.t.iter().zip(&it.lambda).map(|(t, l)| t * l));
    direction(p, frames, offsets, &work.factors, it, rc, &mut work.affine)
}

/// The first iterate (Mehrotra's, as in Nocedal and Wright, section 16.6): from controls at the centre
/// of their boxes, slacks one unit above their rows' worst violation and every row's slack and dual at
/// one, one affine step; then each row's slack and dual is the size that step gives it, at least one.
fn started(
    p: &StagedProblem,
    frames: &[Frame],
    offsets: &[usize],
    work: &mut Workspace,
) -> Result<Iterate, NotStaged> {
    let mut it = centred(frames);
    it.rp = primal_residual(frames, offsets, &it);
    affine_direction(p, frames, offsets, &it, work)?;
    let aff = &work.affine;
    for (t, dt) in it.t.iter_mut().zip(&aff.dt) {
        *t = (*t + dt).abs().max(1.0);
    }
    for (l, dl) in it.lambda.iter_mut().zip(&aff.dlambda) {
        *l = (*l + dl).abs().max(1.0);
    }
    it.rp = primal_residual(frames, offsets, &it);
    Ok(it)
}

/// `it` with the slacks and duals of `warm` (lifted to [`WARM_START_FLOOR`]) on every frame that has as
/// many rows as it had there, its rows' residuals measured again; unchanged if the frames differ in
/// number.
fn warm_started(frames: &[Frame], offsets: &[usize], it: &mut Iterate, warm: &WarmStart) {
    if warm.rows_per_frame.len() != frames.len() {
        return;
    }
    let mut at = 0;
    for ((f, &o), &rows) in frames.iter().zip(offsets).zip(&warm.rows_per_frame) {
        if f.rows.len() == rows {
            for i in 0..rows {
                it.t[o + i] = warm.t[at + i].max(WARM_START_FLOOR);
                it.lambda[o + i] = warm.lambda[at + i].max(WARM_START_FLOOR);
            }
        }
        at += rows;
    }
    it.rp = primal_residual(frames, offsets, it);
}

/// Per row, `G z + t - h`.
fn primal_residual(frames: &[Frame], offsets: &[usize], it: &Iterate) -> Vec<f64> {
    let mut rp = vec![0.0; it.t.len()];
    for (k, f) in frames.iter().enumerate() {
        let xb = before(it, k);
        for (r, row) in f.rows.iter().enumerate() {
            let i = offsets[k] + r;
            rp[i] = f.row_value(row, &xb, &it.v[k]) + it.t[i] - row.h;
        }
    }
    rp
}

/// Controls at the centre of their boxes, each slack one unit above its rows' worst violation, every
/// row's slack and dual at one.
fn centred(frames: &[Frame]) -> Iterate {
    let mut v = Vec::with_capacity(frames.len());
    let mut dx = Vec::with_capacity(frames.len());
    let mut grad = Vec::with_capacity(frames.len());
    let mut t = Vec::new();
    let mut before = [0.0; 4];
    for f in frames {
        let mut vk = f.centre;
        let worst = f
            .rows
            .iter()
            .map(|r| f.row_value(r, &before, &vk) - r.h)
            .fold(0.0_f64, f64::max);
        if let Some(at) = f
            .vars
            .iter()
            .position(|v| matches!(v, FrameVar::Slack { .. }))
        {
            vk[at] = worst + 1.0;
        }
        t.extend(f.rows.iter().map(|_| 1.0));
        grad.push(f.cost_gradient(&before, &vk));
        let after = f.step(&before, &vk);
        v.push(vk);
        dx.push(after);
        before = after;
    }
    let lambda = vec![1.0; t.len()];
    let rp = vec![0.0; t.len()];
    Iterate {
        v,
        dx,
        t,
        lambda,
        rp,
        grad,
    }
}

/// The largest entry of the objective's and the rows' data: the scale of stationarity.
fn gradient_scale(p: &StagedProblem, frames: &[Frame]) -> f64 {
    let terminal = p
        .terminal_gradient
        .iter()
        .fold(0.0_f64, |m, g| m.max(g.abs()));
    frames
        .iter()
        .flat_map(|f| f.gradient.iter())
        .fold(terminal.max(1.0), |m, g| m.max(g.abs()))
}

/// The state change before frame `k` (none before the first).
fn before(it: &Iterate, k: usize) -> [f64; 4] {
    if k == 0 {
        [0.0; 4]
    } else {
        it.dx[k - 1]
    }
}

/// The largest entry of the reduced gradient of the Lagrangian: stationarity in the frames' variables,
/// the states eliminated through the dynamics.
fn stationarity(p: &StagedProblem, frames: &[Frame], offsets: &[usize], it: &Iterate) -> f64 {
    let mut adjoint = p.terminal_gradient;
    let mut largest = 0.0_f64;
    for (k, f) in frames.iter().enumerate().rev() {
        let mut grad = it.grad[k];
        for (r, row) in f.rows.iter().enumerate() {
            row.add_to(&mut grad, it.lambda[offsets[k] + r]);
        }
        for j in 0..f.nv() {
            let r = grad[4 + j] + (0..4).map(|i| f.b[i][j] * adjoint[i]).sum::<f64>();
            largest = largest.max(r.abs());
        }
        adjoint = array_of(|j| grad[j] + (0..4).map(|i| f.a[i][j] * adjoint[i]).sum::<f64>());
    }
    largest
}

/// The backward Riccati pass over the frames with the rows eliminated at weights `lambda / t`: per
/// frame the factor of its reduced Hessian, its cross term and its feedback gain.
fn factorised(
    frames: &[Frame],
    offsets: &[usize],
    it: &Iterate,
    factors: &mut Vec<FrameFactor>,
) -> Result<(), NotStaged> {
    factorised_capped(frames, offsets, it, factors, f64::INFINITY)
}

/// [`factorised`] with every row's weight `lambda / t` capped at `weight_cap`.
fn factorised_capped(
    frames: &[Frame],
    offsets: &[usize],
    it: &Iterate,
    factors: &mut Vec<FrameFactor>,
    weight_cap: f64,
) -> Result<(), NotStaged> {
    // Every frame's entry is written below before any is read.
    factors.resize(frames.len(), FrameFactor::default());
    let mut value = [[0.0; 4]; 4];
    for (k, f) in frames.iter().enumerate().rev() {
        let nv = f.nv();
        let mut h = f.hessian;
        for (r, row) in f.rows.iter().enumerate() {
            let w = it.lambda[offsets[k] + r] / it.t[offsets[k] + r];
            // Not `min`: a weight that is not a number stays one, and the factorisation fails on it.
            let w = if w > weight_cap { weight_cap } else { w };
            if let Some(at) = row.bound {
                h[4 + at][4 + at] += w;
                continue;
            }
            // Over every entry the passes below read, not the frame's `n` alone: fixed bounds let the
            // loops unroll, and the entries past `n` (where `z` is zero) are not read. The state rows'
            // control columns are not read either (`Q_vx` takes the control rows' state columns).
            let z = joined(&row.c, &row.d);
            let (state_rows, control_rows) = h.split_at_mut(4);
            for (hi, zi) in state_rows.iter_mut().zip(z) {
                let wz = w * zi;
                for (hij, zj) in hi[..4].iter_mut().zip(z) {
                    *hij += wz * zj;
                }
            }
            for (hi, zi) in control_rows.iter_mut().zip(&z[4..]) {
                let wz = w * zi;
                for (hij, zj) in hi.iter_mut().zip(z) {
                    *hij += wz * zj;
                }
            }
        }
        // P A and P B.
        let pa: [[f64; 4]; 4] =
            array_of(|i| array_of(|j| (0..4).map(|l| value[i][l] * f.a[l][j]).sum()));
        let pb: [[f64; MAX_FRAME_VARS]; 4] =
            array_of(|i| array_of(|j| (0..4).map(|l| value[i][l] * f.b[l][j]).sum()));
        let q_xx: [[f64; 4]; 4] =
            array_of(|i| array_of(|j| h[i][j] + (0..4).map(|l| f.a[l][i] * pa[l][j]).sum::<f64>()));
        let mut q_vv = [[0.0; MAX_FRAME_VARS]; MAX_FRAME_VARS];
        let mut q_vx = [[0.0; 4]; MAX_FRAME_VARS];
        for i in 0..nv {
            for j in 0..nv {
                q_vv[i][j] = h[4 + i][4 + j] + (0..4).map(|l| f.b[l][i] * pb[l][j]).sum::<f64>();
            }
            for j in 0..4 {
                q_vx[i][j] = h[4 + i][j] + (0..4).map(|l| f.b[l][i] * pa[l][j]).sum::<f64>();
            }
        }
        let chol = cholesky(&q_vv, nv).ok_or(NotStaged::Numerics)?;
        let mut gain = [[0.0; 4]; MAX_FRAME_VARS];
        for j in 0..4 {
            let col: [f64; MAX_FRAME_VARS] = array_of(|i| q_vx[i][j]);
            let s = cholesky_solve(&chol, nv, &col);
            for i in 0..nv {
                gain[i][j] = -s[i];
            }
        }
        // P = Q_xx + Q_vx' K, kept symmetric.
        let p: [[f64; 4]; 4] = array_of(|i| {
            array_of(|j| q_xx[i][j] + (0..nv).map(|l| q_vx[l][i] * gain[l][j]).sum::<f64>())
        });
        value = array_of(|i| array_of(|j| 0.5 * (p[i][j] + p[j][i])));
        factors[k] = FrameFactor { chol, q_vx, gain };
    }
    Ok(())
}

/// The Newton direction for complementarity residuals `rc` (`t lambda` minus the target), from the
/// factorisation: the rows' weighted residuals enter the frames' gradients, the backward pass gives the
/// feed-forward terms, the forward pass the step, and the rows give the slacks' and duals' changes.
fn direction(
    p: &StagedProblem,
    frames: &[Frame],
    offsets: &[usize],
    factors: &[FrameFactor],
    it: &Iterate,
    rc: &[f64],
    out: &mut Direction,
) -> Result<(), NotStaged> {
    let rp = &it.rp;
    // Row i's weight in the gradient: lambda_i + (lambda_i rp_i - rc_i) / t_i. Every frame's feed and
    // every row's change is written below before it is read.
    out.sized(frames.len(), it.t.len());
    let Direction {
        dv,
        dt,
        dlambda,
        feed,
    } = out;
    let mut cost_to_go = p.terminal_gradient;
    for (k, f) in frames.iter().enumerate().rev() {
        let nv = f.nv();
        let mut g = it.grad[k];
        for (r, row) in f.rows.iter().enumerate() {
            let i = offsets[k] + r;
            row.add_to(
                &mut g,
                it.lambda[i] + (it.lambda[i] * rp[i] - rc[i]) / it.t[i],
            );
        }
        let q_v: [f64; MAX_FRAME_VARS] =
            array_of(|j| g[4 + j] + (0..4).map(|l| f.b[l][j] * cost_to_go[l]).sum::<f64>());
        let s = cholesky_solve(&factors[k].chol, nv, &q_v);
        let kk: [f64; MAX_FRAME_VARS] = array_of(|j| -s[j]);
        cost_to_go = array_of(|j| {
            g[j] + (0..4).map(|l| f.a[l][j] * cost_to_go[l]).sum::<f64>()
                + (0..nv).map(|l| factors[k].q_vx[l][j] * kk[l]).sum::<f64>()
        });
        feed[k] = kk;
    }
    let mut dx_before = [0.0; 4];
    for (k, f) in frames.iter().enumerate() {
        let fk = &factors[k];
        let step: [f64; MAX_FRAME_VARS] =
            array_of(|j| feed[k][j] + (0..4).map(|l| fk.gain[j][l] * dx_before[l]).sum::<f64>());
        for (r, row) in f.rows.iter().enumerate() {
            let i = offsets[k] + r;
            dt[i] = -rp[i] - f.row_value(row, &dx_before, &step);
            dlambda[i] = (-rc[i] - it.lambda[i] * dt[i]) / it.t[i];
        }
        dx_before = f.step(&dx_before, &step);
        dv[k] = step;
    }
    if !dx_before.iter().all(|d| d.is_finite()) {
        return Err(NotStaged::Numerics);
    }
    Ok(())
}

/// The longest step up to `share` of the way to the boundary of `t, lambda >= 0`, at most 1.
fn step_to_boundary(it: &Iterate, dir: &Direction, share: f64) -> f64 {
    // `share` is positive and rounding is monotonic, so scaling the least ratio is scaling each.
    let nearest = nearest_boundary(&it.t, &dir.dt).min(nearest_boundary(&it.lambda, &dir.dlambda));
    (share * nearest).min(1.0)
}

/// The least `-x_i / d_i` over the entries with `d_i < 0` (infinite where none falls): how far along
/// `d` the first entry of `x` reaches zero. Kept in four running minima, so that the divisions, each
/// independent of the others, overlap instead of waiting on one chain of minima.
fn nearest_boundary(x: &[f64], d: &[f64]) -> f64 {
    let ratio = |x: f64, d: f64| if d < 0.0 { -x / d } else { f64::INFINITY };
    let mut least = [f64::INFINITY; 4];
    let (xs, ds) = (x.chunks_exact(4), d.chunks_exact(4));
    let (x_rest, d_rest) = (xs.remainder(), ds.remainder());
    for (xc, dc) in xs.zip(ds) {
        for l in 0..4 {
            least[l] = least[l].min(ratio(xc[l], dc[l]));
        }
    }
    for (&xi, &di) in x_rest.iter().zip(d_rest) {
        least[0] = least[0].min(ratio(xi, di));
    }
    least.into_iter().fold(f64::INFINITY, f64::min)
}

/// The iterate moved by `alpha` along `dir`, its states played again through the dynamics.
fn take_step(frames: &[Frame], it: &mut Iterate, dir: &Direction, alpha: f64) {
    for (v, dv) in it.v.iter_mut().zip(&dir.dv) {
        for (a, b) in v.iter_mut().zip(dv) {
            *a += alpha * b;
        }
    }
    for (t, d) in it.t.iter_mut().zip(&dir.dt) {
        *t += alpha * d;
    }
    for (l, d) in it.lambda.iter_mut().zip(&dir.dlambda) {
        *l += alpha * d;
    }
    for r in &mut it.rp {
        *r *= 1.0 - alpha;
    }
    let mut x = [0.0; 4];
    for (k, f) in frames.iter().enumerate() {
        it.grad[k] = f.cost_gradient(&x, &it.v[k]);
        x = f.step(&x, &it.v[k]);
        it.dx[k] = x;
    }
}

/// Lower Cholesky factor of the leading `n x n` block of `a`; `None`: not positive definite.
fn cholesky(
    a: &[[f64; MAX_FRAME_VARS]; MAX_FRAME_VARS],
    n: usize,
) -> Option<[[f64; MAX_FRAME_VARS]; MAX_FRAME_VARS]> {
    let mut l = [[0.0; MAX_FRAME_VARS]; MAX_FRAME_VARS];
    for i in 0..n {
        for j in 0..=i {
            let mut sum = 0.0;
            for (lik, ljk) in l[i][..j].iter().zip(&l[j][..j]) {
                sum += lik * ljk;
            }
            let s = a[i][j] - sum;
            if i == j {
                if !(s > 0.0 && s.is_finite()) {
                    return None;
                }
                l[i][i] = s.sqrt();
            } else {
                l[i][j] = s / l[j][j];
            }
        }
    }
    Some(l)
}

/// `x` with `L L' x = b` over the leading `n` entries.
#[inline(always)]
fn cholesky_solve(
    l: &[[f64; MAX_FRAME_VARS]; MAX_FRAME_VARS],
    n: usize,
    b: &[f64; MAX_FRAME_VARS],
) -> [f64; MAX_FRAME_VARS] {
    // One copy per size: with the size fixed the loops unroll, and the solves of a frame's columns,
    // each a chain of divisions, can overlap.
    match n {
        0 => [0.0; MAX_FRAME_VARS],
        1 => cholesky_solve_sized::<1>(l, b),
        2 => cholesky_solve_sized::<2>(l, b),
        _ => cholesky_solve_sized::<MAX_FRAME_VARS>(l, b),
    }
}

/// [`cholesky_solve`] over the leading `N` entries.
#[inline(always)]
fn cholesky_solve_sized<const N: usize>(
    l: &[[f64; MAX_FRAME_VARS]; MAX_FRAME_VARS],
    b: &[f64; MAX_FRAME_VARS],
) -> [f64; MAX_FRAME_VARS] {
    let mut y = [0.0; MAX_FRAME_VARS];
    for i in 0..N {
        let mut sum = 0.0;
        for k in 0..i {
            sum += l[i][k] * y[k];
        }
        y[i] = (b[i] - sum) / l[i][i];
    }
    let mut x = [0.0; MAX_FRAME_VARS];
    for i in (0..N).rev() {
        let mut sum = 0.0;
        for k in i + 1..N {
            sum += l[k][i] * x[k];
        }
        x[i] = (y[i] - sum) / l[i][i];
    }
    x
}

/// The iterate in Clarabel's layout, with the duals of the dynamics rows: `z_k = -a_k`, `a_k` the
/// gradient of the Lagrangian in the state change after frame `k` through all later frames (its
/// direct terms: the next frame's curvature, the last frame's progress and the wall rows of frame `k`'s
/// end, which the frames hold through their dynamics and so are added back here), reached after
/// `iterations`; with the feedback at it where `p` asks for it ([`feedback_at`]).
fn solution(
    p: &StagedProblem,
    frames: &[Frame],
    wall_rows: &[RowAt],
    offsets: &[usize],
    it: Iterate,
    almost: bool,
    iterations: u32,
) -> StagedSolution {
    let n = frames.len();
    let layout = p.layout;
    let mut x = vec![0.0; layout.n_vars()];
    for (k, f) in frames.iter().enumerate() {
        for (at, var) in f.vars.iter().enumerate() {
            match *var {
                FrameVar::Control { var, .. } => x[var] = it.v[k][at],
                FrameVar::Slack { slack } => x[layout.is(slack)] = it.v[k][at],
            }
        }
        for i in 0..4 {
            x[layout.ix(k, i)] = it.dx[k][i];
        }
    }
    // Per frame end, the wall rows' pull on its position: sum of lambda (-n).
    let mut wall_pull = vec![[0.0; 4]; n];
    for (w, &(k, r)) in p.sp.walls.iter().zip(wall_rows) {
        let l = it.lambda[offsets[k] + r];
        wall_pull[w.frame][0] -= l * w.plane.normal.x;
        wall_pull[w.frame][1] -= l * w.plane.normal.y;
    }
    let mut adjoint = [0.0; 4];
    let mut duals = vec![[0.0; 4]; n];
    for k in (0..n).rev() {
        let mut direct = wall_pull[k];
        if k + 1 == n {
            for (d, g) in direct.iter_mut().zip(&p.terminal_gradient) {
                *d += g;
            }
        } else {
            // The next frame's cost in its incoming state (its constant gradient has no state part).
            for (d, gi) in direct.iter_mut().zip(&it.grad[k + 1]) {
                *d += gi;
            }
        }
        let next_a = if k + 1 < n {
            frames[k + 1].a
        } else {
            [[0.0; 4]; 4]
        };
        adjoint = array_of(|j| direct[j] + (0..4).map(|i| next_a[i][j] * adjoint[i]).sum::<f64>());
        duals[k] = adjoint.map(|a| -a);
    }
    StagedSolution {
        feedback: feedback_at(p, frames, offsets, &it),
        x,
        dynamics_duals: duals,
        almost,
        warm_start: WarmStart {
            rows_per_frame: frames.iter().map(|f| f.rows.len()).collect(),
            t: it.t,
            lambda: it.lambda,
        },
        iterations,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::HalfPlane;
    use crate::optimise::lagrangian::CurvatureBlock;
    use crate::optimise::model::FrameJacobian;
    use crate::optimise::qp::{SubProblemSolver, WallRow, C_SCALE_UPS};
    use crate::physics::Vec2;
    use crate::test_stream::Stream;

    /// One frame that carries the state over, its side moving the end position along `y` and its `c`
    /// along `x` (progress), both within a unit box (scaled); the wall rows `walls` on frame 0, each
    /// with the right-hand side 0.5.
    fn one_frame(walls: &[WallRow], time_limit_s: f64) -> Result<StagedSolution, NotStaged> {
        let (sp, layout) = unit_chain(1, walls);
        let rhs = vec![0.5; walls.len()];
        solve(
            &StagedProblem::new(&sp, &layout, &rhs),
            100,
            time_limit_s,
            None,
        )
    }

    /// `frames` frames as [`one_frame`]'s, at `x` = 5, 6, ..., with the wall rows `walls`.
    fn unit_chain(frames: usize, walls: &[WallRow]) -> (SubProblem<'static>, Layout) {
        let mut a = [[0.0; 4]; 4];
        for (i, row) in a.iter_mut().enumerate() {
            row[i] = 1.0;
        }
        let jacobian = FrameJacobian {
            a,
            b: [[0.0, 1.0 / C_SCALE_UPS], [1.0, 0.0], [0.0, 0.0], [0.0, 0.0]],
        };
        let positions = (0..frames).map(|k| Vec2::new(5.0 + k as f64, 0.0));
        let sp = SubProblem {
            jacobians: Box::leak(vec![jacobian; frames].into_boxed_slice()),
            positions: Box::leak(positions.collect::<Vec<_>>().into_boxed_slice()),
            walls: Box::leak(walls.to_vec().into_boxed_slice()),
            margin: 0.0,
            accepted_clearance: 0.0,
            slack_weight: 100.0,
            progress_dir: Vec2::new(1.0, 0.0),
            sigma_range: Box::leak(vec![(1.0, 1.0); frames].into_boxed_slice()),
            c_range: Box::leak(vec![(C_SCALE_UPS, C_SCALE_UPS); frames].into_boxed_slice()),
            curvature: None,
            wall_shift: None,
            solver: SubProblemSolver::Riccati,
            with_feedback: false,
        };
        let layout = Layout::of(&sp);
        (sp, layout)
    }

    /// Three frames as [`one_frame`]'s, each with a wall of its own (rows on the frame's end position).
    fn walled_chain() -> (SubProblem<'static>, Layout) {
        let walls: [WallRow; 3] = std::array::from_fn(|k| WallRow {
            frame: k,
            ..wall(k)
        });
        unit_chain(3, &walls)
    }

    /// A wall keeping the end position at `y <= 0.5` (the row `-n . dp - s <= 0.5`, `n = (0, -1)`).
    fn wall(group: usize) -> WallRow {
        WallRow {
            frame: 0,
            group,
            plane: HalfPlane {
                normal: Vec2::new(0.0, -1.0),
                offset: 0.0,
            },
        }
    }

    #[test]
    fn the_feedback_holds_an_active_wall_sharing_a_deviation_among_the_frames_before_it() {
        // Three frames whose sides move the position along y, progress along y, and a wall at the last
        // frame's end (y <= 0.5): the wall binds. A deviation of y before frame 1 is taken back by the
        // sides of frames 1 and 2 in equal shares (their changes weigh alike), one before frame 2 by
        // frame 2's side alone; `c` moves x, which nothing asks for, and feeds back nothing.
        let (mut sp, layout) = unit_chain(
            3,
            &[WallRow {
                frame: 2,
                ..wall(0)
            }],
        );
        sp.progress_dir = Vec2::new(0.0, 1.0);
        sp.with_feedback = true;
        let solved = solve(&StagedProblem::new(&sp, &layout, &[0.5]), 100, 10.0, None);
        let feedback = solved.ok().and_then(|s| s.feedback).unwrap_or_default();
        assert_eq!(feedback.len(), 3);
        let side_on_y = |k: usize| feedback[k][0][1];
        assert!((side_on_y(1) + 0.5).abs() < 1e-3, "{feedback:?}");
        assert!((side_on_y(2) + 1.0).abs() < 1e-3, "{feedback:?}");
        let c_fed = feedback
            .iter()
            .flat_map(|f| f[1])
            .fold(0.0_f64, |m, g| m.max(g.abs()));
        assert!(c_fed < 1e-6, "{feedback:?}");
    }

    #[test]
    fn two_slacks_ending_at_one_frame_are_not_a_chain() {
        let walls = [wall(0), wall(1)];
        let shared = one_frame(&[wall(0), wall(0)], 10.0);
        let solved = shared.as_ref().map_err(|e| format!("{e:?}"));
        // c rises to its bound (progress); the wall's rows bind nothing at y = 0, so its slack is zero.
        let x = solved.map(|s| s.x.clone()).unwrap_or_default();
        assert!((x[1] - 1.0).abs() < 1e-5, "{x:?}");
        assert!(x[2 + 4].abs() < 1e-5, "{x:?}");
        assert_eq!(one_frame(&walls, 10.0).err(), Some(NotStaged::NotAChain));
    }

    /// Numbers in `[-1, 1)` from a fixed seed.
    fn numbers(seed: u64) -> impl FnMut() -> f64 {
        let mut stream = Stream(seed);
        move || stream.within(-1.0, 1.0)
    }

    #[test]
    fn the_step_to_the_boundary_is_the_least_scaled_ratio_of_the_falling_entries_at_every_length() {
        // Four running minima and a remainder: every length from none to three chunks and a rest,
        // entries falling, rising and still, and the one nearest anywhere in the list; the share
        // applied to the least ratio must give what it gives applied to each, capped at a full step.
        let mut next = numbers(19);
        let mut entries = |len: usize| -> (Vec<f64>, Vec<f64>) {
            let x: Vec<f64> = (0..len).map(|_| 0.1 + 2.0 * (1.0 + next())).collect();
            let d: Vec<f64> = (0..len)
                .map(|_| match next() {
                    r if r < -0.8 => 0.0,
                    r => 4.0 * r,
                })
                .collect();
            (x, d)
        };
        for len in 0..=15 {
            for _ in 0..20 {
                let (t, dt) = entries(len);
                let (lambda, dlambda) = entries(len);
                let naive = t
                    .iter()
                    .zip(&dt)
                    .filter(|(_, &d)| d < 0.0)
                    .map(|(&x, &d)| -x / d)
                    .fold(f64::INFINITY, f64::min);
                assert_eq!(nearest_boundary(&t, &dt), naive, "{t:?} {dt:?}");
                let it = Iterate {
                    v: Vec::new(),
                    dx: Vec::new(),
                    t: t.clone(),
                    lambda: lambda.clone(),
                    rp: Vec::new(),
                    grad: Vec::new(),
                };
                let dir = Direction {
                    dt: dt.clone(),
                    dlambda: dlambda.clone(),
                    ..Direction::default()
                };
                for share in [1.0, STEP_TO_BOUNDARY] {
                    let mut each = 1.0_f64;
                    for (x, d) in t.iter().zip(&dt).chain(lambda.iter().zip(&dlambda)) {
                        if *d < 0.0 {
                            each = each.min(share * (-x / d));
                        }
                    }
                    assert_eq!(step_to_boundary(&it, &dir, share), each, "{t:?} {dt:?}");
                }
            }
        }
    }

    #[test]
    fn a_bound_row_adds_and_reads_as_the_full_row_it_stands_for() {
        // The bound rows take a short way in `add_to` and `row_value`; the row written out in full
        // (its one entry in `d`, no `bound`) must give the same numbers.
        let mut next = numbers(7);
        let (sp, layout) = curved_chain();
        let frame = frame_without_walls(&StagedProblem::new(&sp, &layout, &[]), 1, None);
        for at in 0..MAX_FRAME_VARS {
            for sign in [1.0, -1.0] {
                let bound = Row::bound(at, sign, next());
                let full = Row {
                    bound: None,
                    ..bound
                };
                let dx: [f64; 4] = std::array::from_fn(|_| next());
                let v: [f64; MAX_FRAME_VARS] = std::array::from_fn(|_| next());
                let weight = next();
                let mut g_bound: [f64; 4 + MAX_FRAME_VARS] = std::array::from_fn(|_| next());
                let mut g_full = g_bound;
                bound.add_to(&mut g_bound, weight);
                full.add_to(&mut g_full, weight);
                assert_eq!(g_bound, g_full, "row {at}, sign {sign}");
                if at < frame.nv() {
                    assert_eq!(
                        frame.row_value(&bound, &dx, &v),
                        frame.row_value(&full, &dx, &v)
                    );
                }
            }
        }
    }

    /// A chain of two frames with random Jacobians, both controls free, and a curvature block on each:
    /// the sub-problem and its layout.
    fn curved_chain() -> (SubProblem<'static>, Layout) {
        let mut next = numbers(11);
        let jacobians: &'static [FrameJacobian] =
            Box::leak(Box::new(std::array::from_fn::<_, 2, _>(|_| {
                FrameJacobian {
                    a: std::array::from_fn(|_| std::array::from_fn(|_| next())),
                    b: std::array::from_fn(|_| std::array::from_fn(|_| next())),
                }
            })));
        let curvature: &'static [CurvatureBlock] =
            Box::leak(Box::new(std::array::from_fn::<CurvatureBlock, 2, _>(
                |_| std::array::from_fn(|_| std::array::from_fn(|_| next())),
            )));
        let sp = SubProblem {
            jacobians,
            positions: Box::leak(Box::new([Vec2::new(5.0, 0.0), Vec2::new(6.0, 0.0)])),
            walls: &[],
            margin: 0.0,
            accepted_clearance: 0.0,
            slack_weight: 100.0,
            progress_dir: Vec2::new(1.0, 0.0),
            sigma_range: &[(1.0, 1.0), (1.0, 1.0)],
            c_range: &[(C_SCALE_UPS, C_SCALE_UPS), (C_SCALE_UPS, C_SCALE_UPS)],
            curvature: Some(curvature),
            wall_shift: None,
            solver: SubProblemSolver::Riccati,
            with_feedback: false,
        };
        let layout = Layout::of(&sp);
        (sp, layout)
    }

    #[test]
    fn a_frames_cost_is_curved_in_its_speed_heading_and_controls_only() {
        // The cost gradient skips the Hessian's first `CURVED_FROM` rows and columns (the position
        // enters a frame linearly): they must be zero, and the gradient the full product `H z + g`.
        let (sp, layout) = curved_chain();
        let problem = StagedProblem::new(&sp, &layout, &[]);
        let mut next = numbers(13);
        for k in 0..2 {
            let frame = frame_without_walls(&problem, k, None);
            let n = 4 + frame.nv();
            for i in 0..n {
                for j in 0..CURVED_FROM {
                    assert_eq!(frame.hessian[i][j], 0.0, "frame {k}, entry ({i}, {j})");
                    assert_eq!(frame.hessian[j][i], 0.0, "frame {k}, entry ({j}, {i})");
                }
            }
            // The curvature block lands on the speed, heading and controls of frames after the first.
            if k > 0 {
                assert!(frame.hessian[2][2] != 0.0 && frame.hessian[3][4] != 0.0);
            }
            let dx: [f64; 4] = std::array::from_fn(|_| next());
            let v: [f64; MAX_FRAME_VARS] = std::array::from_fn(|_| next());
            let z = joined(&dx, &v);
            let full: Vec<f64> = (0..n)
                .map(|i| {
                    frame.gradient[i] + (0..n).map(|j| frame.hessian[i][j] * z[j]).sum::<f64>()
                })
                .collect();
            assert_eq!(frame.cost_gradient(&dx, &v)[..n], full[..]);
        }
    }

    #[test]
    fn an_iterate_keeps_the_cost_gradients_of_its_variables_through_its_steps() {
        // Every pass of an iteration reads the frames' cost gradients from the iterate: from the start
        // and after each step they must be those of its variables and of the states the step played.
        let (sp, layout) = curved_chain();
        let problem = StagedProblem::new(&sp, &layout, &[]);
        let (frames, _) = frames_of(&problem).unwrap_or_else(|e| panic!("{e:?}"));
        let mut it = centred(&frames);
        let mut next = numbers(17);
        for step in 0..3 {
            if step > 0 {
                let dir = Direction {
                    dv: frames
                        .iter()
                        .map(|_| std::array::from_fn(|_| next()))
                        .collect(),
                    dt: vec![0.0; it.t.len()],
                    dlambda: vec![0.0; it.t.len()],
                    feed: Vec::new(),
                };
                take_step(&frames, &mut it, &dir, 0.5);
            }
            for (k, f) in frames.iter().enumerate() {
                let fresh = f.cost_gradient(&before(&it, k), &it.v[k]);
                assert_eq!(it.grad[k], fresh, "step {step}, frame {k}");
            }
        }
    }

    #[test]
    fn a_factorisation_and_a_direction_into_used_buffers_are_those_into_fresh_ones() {
        // The buffers are kept from one iteration to the next and every entry must be written again:
        // used buffers hold NaN (which equals nothing) and are longer than the problem needs.
        let (sp, layout) = walled_chain();
        let rhs = vec![0.5; sp.walls.len()];
        let problem = StagedProblem::new(&sp, &layout, &rhs);
        let (frames, _) = frames_of(&problem).unwrap_or_else(|e| panic!("{e:?}"));
        let offsets = row_offsets(&frames);
        let mut it = centred(&frames);
        it.rp = primal_residual(&frames, &offsets, &it);
        let (n, rows) = (frames.len(), it.t.len());
        let nan_vars = [f64::NAN; MAX_FRAME_VARS];
        let stale = FrameFactor {
            chol: [nan_vars; MAX_FRAME_VARS],
            q_vx: [[f64::NAN; 4]; MAX_FRAME_VARS],
            gain: [[f64::NAN; 4]; MAX_FRAME_VARS],
        };
        let mut fresh_factors = Vec::new();
        let mut used_factors = vec![stale; n + 2];
        for factors in [&mut fresh_factors, &mut used_factors] {
            factorised(&frames, &offsets, &it, factors).unwrap_or_else(|e| panic!("{e:?}"));
        }
        assert_eq!(used_factors.len(), n);
        for (a, b) in fresh_factors.iter().zip(&used_factors) {
            assert_eq!((a.chol, a.q_vx, a.gain), (b.chol, b.q_vx, b.gain));
        }
        let rc: Vec<f64> =
            it.t.iter()
                .zip(&it.lambda)
                .map(|(t, l)| 0.5 * t * l)
                .collect();
        let mut fresh = Direction::default();
        let mut used = Direction {
            dv: vec![nan_vars; n + 3],
            dt: vec![f64::NAN; rows + 3],
            dlambda: vec![f64::NAN; rows + 3],
            feed: vec![nan_vars; n + 3],
        };
        for dir in [&mut fresh, &mut used] {
            direction(&problem, &frames, &offsets, &fresh_factors, &it, &rc, dir)
                .unwrap_or_else(|e| panic!("{e:?}"));
        }
        assert_eq!(fresh.dv, used.dv);
        assert_eq!(fresh.dt, used.dt);
        assert_eq!(fresh.dlambda, used.dlambda);
        assert_eq!(fresh.feed, used.feed);
        assert!(
            fresh.dv.iter().flatten().any(|d| *d != 0.0),
            "a direction that moves"
        );
    }

    #[test]
    fn a_solve_out_of_time_stops_and_says_so() {
        let walls = [wall(0)];
        assert_eq!(one_frame(&walls, 0.0).err(), Some(NotStaged::TimeLimit));
        assert!(one_frame(&walls, 10.0).is_ok());
    }
}
