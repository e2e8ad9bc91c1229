//! Sequential convex programming over one frame count: the planning problem argmin sees and the solver
//! that steps it. For a frame count N it maximises how far past the finish line the player is after frame
//! N, keeping every frame's straight move clear of the walls by a margin.
//!
//! Each SCP iteration is an argmin [`Solver`] step ([`ScpSolver`]): the frame model ([`super::model`]) is
//! linearised around the current trajectory, Clarabel solves the convexified sub-step ([`super::qp`]), and
//! the step is accepted only after exact re-simulation confirms it (actual against predicted improvement,
//! a trust region in between). argmin's executor owns the loop, the iteration cap and the time limit.
//! From the second iteration on, the sub-step also carries the curvature of the Lagrangian, weighted by
//! the last sub-step's dynamics duals and convexified ([`super::lagrangian`]): a sequential quadratic
//! program. Its model is right to second order, so its steps stay long along a line of hundreds of frames
//! where a linear model's trust region would shrink to nothing. The convexified curvature can be more
//! curved than the merit, so each stage carries a share of it that follows how far its steps outdo their
//! predictions (`OVERCURVED_RATIO`); and a plan left closer to a wall than the merit accepts takes its
//! step back out to the margin before the stage may end (`ScpSolver::restoration`).
//!
//! A step is played open-loop first: each frame's controls moved by the sub-step's change. Along
//! hundreds of frames the second-order error of the heading grows, and the played run can leave the
//! modelled one by more than the corridor is wide. In a relaxed stage a step so rejected is played
//! again closed-loop, each frame's change corrected by the sub-problem's own feedback on how far the run
//! has left the model (`ScpProblem::stepped_with_feedback`), as iterative LQR plays its steps; only if
//! that is rejected too is the step corrected to second order or the trust region cut. (With the sides
//! fixed only `c` can answer, and a polished plan so played ended inside the walls: there the step is
//! played open-loop only.)

use super::lagrangian::{convexify, lagrangian_block, CurvatureBlock};
use super::model::{knot, knot_hessian, rollout_knots, FrameControl, FrameLaw, ModelState};
use super::qp::{self, SubProblem, SubProblemSolver, SubStepStatus, WallRow};
use super::search::SearchStats;
use crate::budget::Budget;
use crate::geometry::{Corridor, Separation};
use crate::physics::Vec2;
use crate::scene::Scene;
use argmin::core::{
    CostFunction, Error as ArgminError, Executor, IterState, Problem, Solver, State,
    TerminationReason, TerminationStatus, KV,
};
use std::time::{Duration, Instant};

/// The problem argmin sees: the plan's parameters `(sigma_0, c_0, sigma_1, c_1, ...)` and, as cost, minus
/// the merit `progress - weight * violation`.
#[derive(Clone)]
pub struct ScpProblem<'a> {
    pub(super) start: ModelState,
    pub(super) fl: FrameLaw,
    pub(super) corridor: &'a Corridor,
    pub(super) finish_a: Vec2,
    pub(super) progress_dir: Vec2,
    pub(super) margin: f64,
    pub(super) slack_weight: f64,
    pub(super) wall_radius: f64,
    pub(super) relaxed: bool,
    /// Frames per planning step: 1, or a coarse stage's knot ([`knot`]).
    pub(super) frames_per_knot: u32,
    /// Whether `c` stays under the anglemod guard of the law's first case ([`FrameLaw::c_plan_max`]);
    /// off for the relaxed certificate, whose feasible set must hold every exact plan.
    pub(super) anglemod_guard: bool,
    /// With exact sides, whether a frame may turn less than the maximum-acceleration turn
    /// ([`FrameLaw::c_exact_max`]); else `c` keeps under the guard as in the relaxed problem. With
    /// `anglemod_guard` too, each frame keeps to its side of the guard's band ([`FrameLaw::guard_band`]).
    pub(super) turn_less: bool,
    /// The solver its sub-problems are given first.
    pub(super) sub_problem_solver: SubProblemSolver,
}

/// One iteration's linearisation with the trust region's ranges: everything its sub-problems need.
struct Linearisation {
    lin: Linearised,
    sigma_range: Vec<(f64, f64)>,
    c_range: Vec<(f64, f64)>,
}

/// The trajectory of a parameter vector with what the sub-problem needs.
struct Linearised {
    states: Vec<ModelState>,
    /// The states' positions, as the sub-problem takes them.
    positions: Vec<Vec2>,
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
    pub(super) fn merit(&self, states: &[ModelState]) -> f64 {
        let last = states.last().map_or(self.start.pos, |s| s.pos);
        self.progress(last) - self.slack_weight * self.violation(states)
    }

    /// Total violation, units: how far the frames' moves come closer to a wall than the accepted
    /// clearance, half the margin. The sub-problems ask for the whole margin, so the second-order error
    /// of a step along a wall (the linearised dynamics are exact only to first order) stays inside the
    /// other half instead of being charged at the slack weight: charging it stalls the trust region.
    pub(super) fn violation(&self, states: &[ModelState]) -> f64 {
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

    /// Whether a sub-problem starts where the stage's last one ended ([`qp::solve_warm`]): with the sides
    /// fixed, not in the relaxed problem. With its sides fixed a plan moves off a wall only through `c`,
    /// and the interior-point method crawls from cold (docs/design.md, "Why a fixed-side sub-problem
    /// takes three times the interior-point iterations of a relaxed one"); started where the last
    /// solution ended, it need not find again which rows are active. An interior-point solve from cold
    /// ends near the centre of the face of optima its tolerances leave open (sides the progress hardly
    /// depends on, inside their box), a warm-started one near where the last solution was.
    /// Warm-started relaxed stages descended to other lines, and on scenes of two CI-sized families the
    /// plans rounded from them were one to seven frames slower (docs/design.md, "A warm start for the
    /// sub-problems").
    fn warm_started(&self) -> bool {
        !self.relaxed
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
                    group: k,
                });
                if k > 0 {
                    walls.push(WallRow {
                        frame: k - 1,
                        plane: sep.plane,
                        group: k,
                    });
                }
            }
            prev = s.pos;
        }
        Linearised {
            positions: states.iter().map(|s| s.pos).collect(),
            states,
            jacobians,
            walls,
            curvature,
        }
    }

    /// The trajectory of `controls` linearised, with each frame's trust-region ranges at radius `trust`:
    /// `sigma` within `trust * SIGMA_TRUST`, `c` within `trust * C_TRUST_UPS` (ups) and its bounds. With `duals` (one per
    /// frame, from the last sub-problem), the curvature of the Lagrangian too.
    fn linearisation(
        &self,
        controls: &[FrameControl],
        duals: Option<&[[f64; 4]]>,
        trust: f64,
        upper_at_kink: bool,
    ) -> Linearisation {
        // Each frame stays on its piece of mu = min(gamma1, L - c) within a step, so the linearisation
        // is exact to first order; a frame on the kink tries the upper piece (mu = L - c) on even
        // iterations and the lower (mu = gamma1) on odd ones.
        let kink = self.fl.kink();
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
        let lin = self.linearise(&lin_controls, duals);
        let mut sigma_range = Vec::with_capacity(controls.len());
        let mut c_range = Vec::with_capacity(controls.len());
        let mut speed = self.start.speed;
        for (k, u) in lin_controls.iter().enumerate() {
            let ds = trust * SIGMA_TRUST;
            sigma_range.push(if self.relaxed {
                (ds.min(1.0 + u.sigma), ds.min(1.0 - u.sigma))
            } else {
                (0.0, 0.0)
            });
            let dc = trust * C_TRUST_UPS;
            // A knot plays its `c` over all its frames: it keeps within the braking limit at the knot's
            // lowest speed (the speed is monotonic over a knot), where a later frame would otherwise be
            // asked for `c < -V` and only brake straight back ([`super::model`]). A frame's `c` is taken
            // at the speed it starts from.
            let lowest_speed = if self.frames_per_knot > 1 {
                speed.min(lin.states[k].speed)
            } else {
                speed
            };
            let (mut lo, mut hi) = (
                dc.min(u.c - self.c_min(lowest_speed)).max(0.0),
                dc.min(self.c_upper(speed) - u.c).max(0.0),
            );
            if u.c > kink {
                lo = lo.min(u.c - kink);
            } else {
                hi = hi.min(kink - u.c);
            }
            // A frame keeps to its side of the guard's band: above the kink no lower than the band's
            // top, else no higher than its bottom (one the speed's change put inside moves out only).
            if let Some((guard, top)) = self.guard_band_kept(speed) {
                if u.c > kink {
                    lo = lo.min((u.c - top).max(0.0));
                } else {
                    hi = hi.min((guard - u.c).max(0.0));
                }
            }
            c_range.push((lo, hi));
            speed = lin.states[k].speed;
        }
        Linearisation {
            lin,
            sigma_range,
            c_range,
        }
    }

    /// The sub-problem around `lz`, its wall rows moved by `wall_shift` (see [`SubProblem::wall_shift`]).
    fn sub_problem<'s>(
        &self,
        lz: &'s Linearisation,
        wall_shift: Option<&'s [Vec2]>,
    ) -> SubProblem<'s> {
        SubProblem {
            jacobians: &lz.lin.jacobians,
            positions: &lz.lin.positions,
            walls: &lz.lin.walls,
            margin: self.margin,
            accepted_clearance: MERIT_MARGIN_SHARE * self.margin,
            slack_weight: self.slack_weight,
            progress_dir: self.progress_dir,
            sigma_range: &lz.sigma_range,
            c_range: &lz.c_range,
            curvature: lz.lin.curvature.as_deref(),
            wall_shift,
            solver: self.sub_problem_solver,
            with_feedback: self.relaxed,
        }
    }

    /// The parameters of `controls` moved by the sub-step `du` and played with its `feedback`: each
    /// frame's change is the step's, plus the feedback on how far the state before it is from where the
    /// model put it (the linearised state plus the step's change `dx`), kept within the frame's trust
    /// region. The feedback is the sub-problem's own (its Newton system's Riccati gains), which answers
    /// a deviation as the sub-problem's optimum would, pressing the frames on the walls it pressed
    /// them on. In a relaxed stage's descent about half the steps rejected open-loop are kept played so.
    fn stepped_with_feedback(
        &self,
        lz: &Linearisation,
        controls: &[FrameControl],
        du: &[(f64, f64)],
        dx: &[[f64; 4]],
        feedback: &[super::stagewise::ControlFeedback],
    ) -> Vec<f64> {
        let mut x = self.start;
        let mut out = Vec::with_capacity(2 * controls.len());
        for k in 0..controls.len() {
            let off = match k.checked_sub(1) {
                Some(before) => {
                    let (lin, d) = (&lz.lin.states[before], dx[before]);
                    [
                        x.pos.x - (lin.pos.x + d[0]),
                        x.pos.y - (lin.pos.y + d[1]),
                        x.speed - (lin.speed + d[2]),
                        x.heading - (lin.heading + d[3]),
                    ]
                }
                None => [0.0; 4],
            };
            let fed = |j: usize| (0..4).map(|i| feedback[k][j][i] * off[i]).sum::<f64>();
            let (s_lo, s_hi) = lz.sigma_range[k];
            let (c_lo, c_hi) = lz.c_range[k];
            let ds = (du[k].0 + fed(0)).clamp(-s_lo, s_hi);
            let dc = (du[k].1 + fed(1)).clamp(-c_lo, c_hi);
            let u = moved(&controls[k], (ds, dc));
            x = knot(&x, u, &self.fl, self.frames_per_knot, false).0;
            out.extend([u.sigma, u.c]);
        }
        out
    }

    /// Highest `c` allowed at speed `v`, ups: [`FrameLaw::c_exact_max`] for exact sides that may turn
    /// less; else [`FrameLaw::c_max`], under the anglemod guard when it is on.
    pub(super) fn c_upper(&self, v: f64) -> f64 {
        if self.turn_less && !self.relaxed {
            self.fl.c_exact_max(v)
        } else if self.anglemod_guard {
            self.fl.c_plan_max(v)
        } else {
            self.fl.c_max(v)
        }
    }

    /// The guard's band at speed `v` where frames that may turn less keep to their side of it.
    fn guard_band_kept(&self, v: f64) -> Option<(f64, f64)> {
        (self.turn_less && self.anglemod_guard && !self.relaxed)
            .then(|| self.fl.guard_band(v))
            .flatten()
    }

    /// Lowest `c` allowed at speed `v` ([`FrameLaw::c_min`]).
    fn c_min(&self, v: f64) -> f64 {
        self.fl.c_min(v)
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
pub struct ScpSolver<'c> {
    budget: Budget<'c>,
    trust: f64,
    min_trust: f64,
    tol: f64,
    converged: bool,
    stats: SearchStats,
    /// Dynamics duals of the last solved sub-problem, per frame: the curvature weights.
    duals: Option<Vec<[f64; 4]>>,
    /// Where the frame-by-frame solver ended on the last solved sub-problem: the next one starts there
    /// ([`qp::solve_warm`]).
    warm_start: Option<qp::WarmStart>,
    /// The share of the Lagrangian's curvature the sub-problems carry, in `[MIN_CURVATURE_SHARE, 1]`
    /// (see [`OVERCURVED_RATIO`]).
    curvature_share: f64,
    /// Whether the last step taken was a restoration ([`ScpSolver::restoration`]): not taken again in a row,
    /// only after an ordinary step is accepted.
    restored_last: bool,
    /// The cost after each iteration so far.
    costs: Vec<f64>,
    /// The stage's iteration cap (the stall test weighs the iterations left).
    max_iters: u64,
    /// How the trust region grows.
    kind: StageKind,
}

impl<'c> ScpSolver<'c> {
    fn new(tol: f64, budget: Budget<'c>) -> Self {
        ScpSolver {
            budget,
            trust: 1.0,
            min_trust: 1e-7,
            tol,
            converged: false,
            stats: SearchStats::default(),
            duals: None,
            warm_start: None,
            curvature_share: 1.0,
            restored_last: false,
            costs: Vec::new(),
            max_iters: u64::MAX,
            kind: StageKind::Plain,
        }
    }
}

/// The curvature's share after a step that gained `ratio` times its prediction (`None`: rejected): halved
/// above [`OVERCURVED_RATIO`], doubled below [`UNDERCURVED_RATIO`] or after a rejection, within
/// `[MIN_CURVATURE_SHARE, 1]`.
fn next_curvature_share(share: f64, ratio: Option<f64>) -> f64 {
    match ratio {
        Some(r) if r > OVERCURVED_RATIO => (0.5 * share).max(MIN_CURVATURE_SHARE),
        Some(r) if r >= UNDERCURVED_RATIO => share,
        _ => (2.0 * share).min(1.0),
    }
}

/// The parameters of `controls` moved by `du` (`(d sigma, d c)` per frame), each side kept in `[-1, 1]`.
fn stepped(controls: &[FrameControl], du: &[(f64, f64)]) -> Vec<f64> {
    controls
        .iter()
        .zip(du)
        .flat_map(|(u, d)| {
            let m = moved(u, *d);
            [m.sigma, m.c]
        })
        .collect()
}

/// The control `u` moved by `(d sigma, d c)`, its side kept in `[-1, 1]`.
fn moved(u: &FrameControl, (d_sigma, d_c): (f64, f64)) -> FrameControl {
    FrameControl {
        sigma: (u.sigma + d_sigma).clamp(-1.0, 1.0),
        c: u.c + d_c,
    }
}

/// The largest trust radius.
const MAX_TRUST: f64 = 4.0;

/// A step that delivers more than this share of its predicted gain doubles the trust radius.
const GOOD_STEP_RATIO: f64 = 0.75;

/// An accepted step that delivers less than this share of its predicted gain halves the trust radius.
const POOR_STEP_RATIO: f64 = 0.25;

/// The trust radius after a good step: doubled, up to [`MAX_TRUST`].
fn doubled(trust: f64) -> f64 {
    (2.0 * trust).min(MAX_TRUST)
}

/// A step's change of each frame's side at trust radius 1.
const SIGMA_TRUST: f64 = 0.1;

/// A step's change of each frame's `c` at trust radius 1, ups.
const C_TRUST_UPS: f64 = 5.0;

/// Total wall violation, units, up to which a plan counts as clear (rounding of the clearance sums).
pub(super) const CLEAN_VIOLATION_UNITS: f64 = 1e-9;

/// Within this of the kink `L - gamma1`, ups, a frame's `c` counts as on it.
const KINK_TOL_UPS: f64 = 1e-9;

/// Share of the wall margin a plan must keep to count as clear (see [`ScpProblem::violation`]).
const MERIT_MARGIN_SHARE: f64 = 0.5;

/// Iterations over which the pace of a stage short of the line is measured.
const STALL_WINDOW: usize = 10;

/// Least share of the predicted gain a step must deliver to be accepted.
const ACCEPT_RATIO: f64 = 0.1;

/// Whether a step that gained `actual` against its prediction `predicted` is accepted: a gain, and at
/// least [`ACCEPT_RATIO`] of the prediction.
fn kept(actual: f64, predicted: f64) -> bool {
    actual > 0.0 && actual / predicted >= ACCEPT_RATIO
}

/// A step that gains more than this many times its prediction halves the share of the curvature the
/// next sub-problems carry. Each frame's block of the Lagrangian's Hessian has its negative part cut off
/// ([`super::lagrangian::convexify`]), so wherever neighbouring blocks' curvatures cancel the model is
/// more curved than the merit, and its step stops short of a gain that is there: a step interior to the
/// trust region that gains twice its prediction is the sign (the merit was about linear along it).
const OVERCURVED_RATIO: f64 = 1.5;

/// A step that gains less than this share of its prediction (or is rejected) doubles the curvature's
/// share back, up to the whole curvature.
const UNDERCURVED_RATIO: f64 = 0.75;

/// A restoration step ([`ScpSolver::restoration`]) may lose at most this many times its predicted loss.
const RESTORATION_LOSS_FACTOR: f64 = 2.0;

/// The least share of the curvature the sub-problems carry.
const MIN_CURVATURE_SHARE: f64 = 1.0 / 64.0;

impl<'a> Solver<ScpProblem<'a>, ScpState> for ScpSolver<'_> {
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
        let trust = self.trust;
        let upper_at_kink = state.get_iter() % 2 == 0;
        let duals = self.duals_at_curvature_share();
        let seconds_left = self
            .budget
            .remaining()
            .map_or(f64::INFINITY, |d| d.as_secs_f64());
        let lz = problem.problem("linearise", |pr| {
            Ok(pr.linearisation(&controls, duals.as_deref(), trust, upper_at_kink))
        })?;
        let mut step = problem.problem("solve", |pr| {
            Ok(qp::solve_warm(
                &pr.sub_problem(&lz, None),
                seconds_left,
                self.warm_start_for(pr),
            ))
        })?;
        self.stats.iterations += 1;
        self.sub_problem_solved(&mut step);
        let du = match step.status {
            SubStepStatus::Solved { .. } => {
                self.duals = Some(std::mem::take(&mut step.dynamics_duals));
                std::mem::take(&mut step.du)
            }
            SubStepStatus::Failed(_) => {
                self.trust *= 0.25;
                return Ok((state, None));
            }
        };
        // No gain in the merit by the model: converged. The prediction can be negative: the sub-problem
        // also asks moves inside the wall margin back out to it, which the merit (it counts only what is
        // closer than the accepted clearance) does not pay for. A plan closer to a wall than that would
        // end unclean, of no use to a count search, so its step out is taken first.
        if step.predicted <= self.tol {
            if step.predicted < -self.tol && !self.restored_last {
                if let Some((restored, restored_cost)) =
                    self.restoration(problem, &controls, &du, cost, step.predicted)?
                {
                    self.restored_last = true;
                    return Ok((state.param(restored).cost(restored_cost), None));
                }
            }
            self.converged = true;
            return Ok((state, None));
        }
        let (candidate, new_cost) = self.played(problem, &lz, &controls, &du, &step, cost)?;
        let actual = cost - new_cost;
        let ratio = actual / step.predicted;
        let accepted = kept(actual, step.predicted);
        if accepted {
            self.after_accepted_step(ratio);
            Ok((state.param(candidate).cost(new_cost), None))
        } else {
            if let Some((corrected, corrected_cost)) = self.second_order_correction(
                problem,
                &lz,
                &controls,
                &candidate,
                &step,
                seconds_left,
            )? {
                // Delivered enough of the first step's prediction: kept, the trust region as the
                // stage's kind says.
                let delivered = (cost - corrected_cost) / step.predicted;
                if delivered >= ACCEPT_RATIO {
                    self.stats.corrected_steps += 1;
                    self.trust = trust_after_correction(self.trust, delivered, self.kind);
                    return Ok((state.param(corrected).cost(corrected_cost), None));
                }
            }
            self.after_rejected_step();
            Ok((state, None))
        }
    }

    fn terminate(&mut self, state: &ScpState) -> TerminationStatus {
        let cost = state.get_cost();
        self.costs.push(cost);
        if self.stalled_short_of_the_line(cost, state.get_iter()) {
            return TerminationStatus::Terminated(TerminationReason::SolverExit(
                "stalled short of the line".into(),
            ));
        }
        if self.converged || self.trust < self.min_trust {
            TerminationStatus::Terminated(TerminationReason::SolverConverged)
        } else if self.budget.expired() {
            TerminationStatus::Terminated(TerminationReason::Interrupt)
        } else {
            TerminationStatus::NotTerminated
        }
    }
}

impl ScpSolver<'_> {
    /// The last sub-problem's dynamics duals (taken: each is used once) scaled by the curvature's share.
    /// The curvature is linear in the duals, and so is its convexification: scaling the duals scales
    /// the model's curvature.
    fn duals_at_curvature_share(&mut self) -> Option<Vec<[f64; 4]>> {
        let share = self.curvature_share;
        self.duals.take().map(|z| {
            z.into_iter()
                .map(|zk| zk.map(|v| v * share))
                .collect::<Vec<_>>()
        })
    }

    /// The trust region and the curvature's share after a step kept with `ratio` of its predicted gain:
    /// the radius doubled after a good step, halved after a poor one.
    fn after_accepted_step(&mut self, ratio: f64) {
        self.curvature_share = next_curvature_share(self.curvature_share, Some(ratio));
        self.restored_last = false;
        if ratio > GOOD_STEP_RATIO {
            self.trust = doubled(self.trust);
        } else if ratio < POOR_STEP_RATIO {
            self.trust *= 0.5;
        }
    }

    /// The trust region and the curvature's share after a step rejected (its correction too).
    fn after_rejected_step(&mut self) {
        self.stats.rejected_steps += 1;
        self.curvature_share = next_curvature_share(self.curvature_share, None);
        self.trust *= 0.3;
    }

    /// The warm start of `pr`'s next sub-problem: where the last one's solver ended, in the stages that
    /// take one ([`ScpProblem::warm_started`]).
    fn warm_start_for(&self, pr: &ScpProblem<'_>) -> Option<&qp::WarmStart> {
        self.warm_start.as_ref().filter(|_| pr.warm_started())
    }

    /// The plan a solved sub-step `step` (control changes `du`) leads to from `controls` (cost `cost`),
    /// with its cost: played open-loop, or where that is rejected and the sub-problem gave its feedback
    /// (a relaxed stage's, [`SubProblem::with_feedback`]), played with it
    /// ([`ScpProblem::stepped_with_feedback`]) if that comes out better.
    fn played(
        &mut self,
        problem: &mut Problem<ScpProblem<'_>>,
        lz: &Linearisation,
        controls: &[FrameControl],
        du: &[(f64, f64)],
        step: &qp::SubStep,
        cost: f64,
    ) -> std::result::Result<(Vec<f64>, f64), ArgminError> {
        let open_loop = stepped(controls, du);
        // A plan whose trajectory is not finite is simply worse than any finite one.
        let open_loop_cost = problem.cost(&open_loop).unwrap_or(f64::INFINITY);
        if kept(cost - open_loop_cost, step.predicted) {
            return Ok((open_loop, open_loop_cost));
        }
        let Some(feedback) = step.feedback.as_deref() else {
            return Ok((open_loop, open_loop_cost));
        };
        let fed = problem.problem("feedback", |pr| {
            Ok(pr.stepped_with_feedback(lz, controls, du, &step.dx, feedback))
        })?;
        let fed_cost = problem.cost(&fed).unwrap_or(f64::INFINITY);
        if fed_cost >= open_loop_cost {
            return Ok((open_loop, open_loop_cost));
        }
        if kept(cost - fed_cost, step.predicted) {
            self.stats.fed_steps += 1;
        }
        Ok((fed, fed_cost))
    }

    /// A sub-problem solved (or failed): its work counted, and where its solver ended, if it says, kept
    /// as the start of the next one.
    fn sub_problem_solved(&mut self, step: &mut qp::SubStep) {
        if let Some(warm) = step.warm_start.take() {
            self.warm_start = Some(warm);
        }
        self.stats.subproblems += 1;
        self.stats.interior_point_iterations += u64::from(step.iterations);
        self.stats.handed_to_clarabel += u64::from(step.handed_to_clarabel);
        if !matches!(step.status, SubStepStatus::Solved { .. }) {
            self.stats.subproblem_failures += 1;
        }
    }

    /// The second-order correction of a rejected step (Nocedal and Wright, section 18.3): the linearised
    /// dynamics leave out the second-order change of the positions, which along hundreds of frames adds up
    /// to units, so a step that the sub-problem kept clear can land in a wall, and the merit charges that
    /// at the slack weight. The sub-problem is solved again about the same linearisation with each frame's
    /// wall rows moved by what the model left out of the trial's position (`candidate` played, less the
    /// model's position after the step, [`qp::SubStep::dp`] its change), and the corrected plan and its
    /// cost come back.
    fn second_order_correction(
        &mut self,
        problem: &mut Problem<ScpProblem<'_>>,
        lz: &Linearisation,
        controls: &[FrameControl],
        candidate: &[f64],
        step: &qp::SubStep,
        seconds_left: f64,
    ) -> std::result::Result<Option<(Vec<f64>, f64)>, ArgminError> {
        let corrected = problem.problem("correct", |pr| {
            let trial = rollout_knots(&pr.start, &unpack(candidate), &pr.fl, pr.frames_per_knot);
            // A step that came no closer to the walls failed on the model's progress, which moving the
            // wall rows does not mend.
            if pr.violation(&trial) <= pr.violation(&lz.lin.states) {
                return Ok(None);
            }
            let left_out: Vec<Vec2> = trial
                .iter()
                .zip(&lz.lin.positions)
                .enumerate()
                .map(|(k, (t, p))| t.pos - (*p + step.dp(k)))
                .collect();
            Ok(Some(qp::solve_warm(
                &pr.sub_problem(lz, Some(&left_out)),
                seconds_left,
                self.warm_start_for(pr),
            )))
        })?;
        let Some(mut corrected) = corrected else {
            return Ok(None);
        };
        self.sub_problem_solved(&mut corrected);
        if !matches!(corrected.status, SubStepStatus::Solved { .. }) {
            return Ok(None);
        }
        let corrected = stepped(controls, &corrected.du);
        // A plan whose trajectory is not finite is simply worse than any finite one.
        let corrected_cost = problem.cost(&corrected).unwrap_or(f64::INFINITY);
        Ok(Some((corrected, corrected_cost)))
    }

    /// The restoration of a plan that is not clear: where the sub-problem predicts a loss (`predicted`,
    /// negative), it moved frames inside the wall margin back out to it. If the plan (cost `cost`) comes
    /// closer to a wall than the merit accepts, that step `du` is taken, as long as it loses at most
    /// [`RESTORATION_LOSS_FACTOR`] times the predicted loss; else `None` (the stage converged). Without
    /// it a line solved at a smaller margin and refined at a wider one (the certificate's line, rounded)
    /// could stop inside the wider margin after a few iterations, and its count search give it up.
    fn restoration(
        &self,
        problem: &mut Problem<ScpProblem<'_>>,
        controls: &[FrameControl],
        du: &[(f64, f64)],
        cost: f64,
        predicted: f64,
    ) -> std::result::Result<Option<(Vec<f64>, f64)>, ArgminError> {
        let unclear = problem.problem("restore", |pr| {
            let states = rollout_knots(&pr.start, controls, &pr.fl, pr.frames_per_knot);
            Ok(pr.violation(&states) > CLEAN_VIOLATION_UNITS)
        })?;
        if !unclear {
            return Ok(None);
        }
        let restored = stepped(controls, du);
        // A plan whose trajectory is not finite is simply worse than any finite one.
        let restored_cost = problem.cost(&restored).unwrap_or(f64::INFINITY);
        Ok(
            (cost - restored_cost >= RESTORATION_LOSS_FACTOR * predicted)
                .then_some((restored, restored_cost)),
        )
    }

    /// Whether a plan short of the line (`cost > 0`: the merit is the progress past it) cannot reach it
    /// in the iterations the stage has left, at the pace of the last [`STALL_WINDOW`] iterations. The
    /// count search then gives the count up at once instead of spending the stage's cap proving it.
    fn stalled_short_of_the_line(&self, cost: f64, iter: u64) -> bool {
        let n = self.costs.len();
        if cost <= 0.0 || n <= STALL_WINDOW {
            return false;
        }
        let gained = self.costs[n - 1 - STALL_WINDOW] - cost;
        let left = self.max_iters.saturating_sub(iter) as f64;
        gained * left / (STALL_WINDOW as f64) < cost
    }
}

/// How an SCP stage grows its trust region.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum StageKind {
    /// After a good step only; a kept second-order correction leaves the region as it was.
    Plain,
    /// After a kept second-order correction that delivers most of the step's prediction too. Along a
    /// line pressed against the walls nearly every step is corrected, and with the region left as it was
    /// it stays where the rejections cut it, and the stage creeps (docs/design.md, "The final polish").
    Regrowing,
}

/// The trust radius after a kept second-order correction that delivered `delivered` times the first
/// step's predicted gain: in a [`StageKind::Regrowing`] stage doubled (up to [`MAX_TRUST`]) where that
/// is more than [`GOOD_STEP_RATIO`], as after a good step; else `trust` as it was.
fn trust_after_correction(trust: f64, delivered: f64, kind: StageKind) -> f64 {
    match kind {
        StageKind::Regrowing if delivered > GOOD_STEP_RATIO => doubled(trust),
        _ => trust,
    }
}

/// Runs SCP on `controls`; returns the improved controls, whether the time limit stopped it, whether it
/// stopped at the iteration cap, and the work done.
pub(super) fn run_scp(
    problem: ScpProblem,
    controls: Vec<FrameControl>,
    max_iters: u64,
    tol: f64,
    budget: Budget,
    kind: StageKind,
) -> (Vec<FrameControl>, bool, bool, SearchStats) {
    let x0 = pack(&controls);
    let mut solver = ScpSolver::new(tol, budget);
    solver.max_iters = max_iters;
    solver.kind = kind;
    let mut exec =
        Executor::new(problem, solver).configure(|s| s.param(x0.clone()).max_iters(max_iters));
    if let Some(d) = budget.deadline() {
        exec = exec.timeout(
            d.saturating_duration_since(Instant::now())
                .max(Duration::from_millis(1)),
        );
    }
    match exec.run() {
        Ok(res) => {
            let reason = res.state().get_termination_reason();
            let timed_out = matches!(
                reason,
                Some(TerminationReason::Timeout | TerminationReason::Interrupt)
            );
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

/// The first frame (1-based) whose move crosses the finish line, in the model.
pub(super) fn model_crossing(
    start: &ModelState,
    states: &[ModelState],
    scene: &Scene,
) -> Option<usize> {
    let mut prev = start.pos;
    for (k, s) in states.iter().enumerate() {
        if scene.finish.crossing_fraction(prev, s.pos).is_some() {
            return Some(k + 1);
        }
        prev = s.pos;
    }
    None
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::optimise::planner::{planning_inputs, staircase_scene, Planner};
    use crate::optimise::search::SearchSettings;
    use crate::optimise::stagewise::ControlFeedback;
    use crate::optimise::Quality;
    use crate::scene::generate::{generate, GeneratorSettings};

    #[test]
    fn a_long_sub_step_ends_where_its_control_changes_take_the_trajectory() {
        // A 1000 fps corridor of 2,217 frames: Clarabel meets each dynamics row to its tolerance only,
        // and along the chain those residuals add up to more than a margin's width.
        let family = GeneratorSettings {
            fps: vec![1000],
            max_corners: 2,
            max_leg_units: 800,
            ..GeneratorSettings::default()
        };
        let scene = generate(61, 5, &family)
            .unwrap_or_else(|e| panic!("{e}"))
            .scene;
        let (sim, bound, base) = planning_inputs(&scene);
        let settings = SearchSettings::for_quality(Quality::Fast);
        let run = &base.clean[0].trace;
        let planner = Planner::new(&scene, &sim, &settings, &bound, run, Budget::unlimited());
        let warm = planner.warm_start(run);
        assert!(warm.len() > 2000, "{} frames", warm.len());
        let pr = planner.problem(settings.margin_units, true, 1);
        let lz = pr.linearisation(&warm, None, 1.0, true);
        let step = qp::solve(&pr.sub_problem(&lz, None));
        assert!(matches!(step.status, SubStepStatus::Solved { .. }));
        // The end positions the linearised dynamics give the step's control changes, frame by frame.
        let mut dx = [0.0; 4];
        let mut furthest = 0.0_f64;
        for (k, jac) in lz.lin.jacobians.iter().enumerate() {
            dx = jac.state_change(&dx, &[step.du[k].0, step.du[k].1]);
            furthest = furthest.max((Vec2::new(dx[0], dx[1]) - step.dp(k)).length());
        }
        assert!(furthest < 1e-9, "{furthest} units apart");
    }

    #[test]
    fn a_relaxed_stage_keeps_many_of_its_rejected_steps_played_with_their_feedback() {
        // Narrow 100 fps corridors at air acceleration 10, over a thousand frames: the relaxed plan's
        // stage from the greedy run. Where a step played open-loop is rejected, the same step played with
        // the sub-problem's feedback is kept in about half the cases (38 of 69 on these two); with the
        // feedback's sign turned, in none. Every frame's change, however large the feedback, stays within
        // its trust region.
        let family = GeneratorSettings {
            fps: vec![100],
            airaccelerate: vec![10],
            max_width_units: 96,
            ..GeneratorSettings::default()
        };
        let (mut fed, mut rejected_open_loop) = (0, 0);
        for index in 0..2 {
            let scene = generate(6161, index, &family)
                .unwrap_or_else(|e| panic!("{e}"))
                .scene;
            let (sim, bound, base) = planning_inputs(&scene);
            let settings = SearchSettings::for_quality(Quality::Fast);
            let run = &base.clean[0].trace;
            let mut planner =
                Planner::new(&scene, &sim, &settings, &bound, run, Budget::unlimited());
            let warm = planner.warm_start(run);
            let pr = planner.problem(settings.margin_units, true, 1);
            let lz = pr.linearisation(&warm, None, 1.0, true);
            let step = qp::solve(&pr.sub_problem(&lz, None));
            let Some(feedback) = step.feedback.as_deref() else {
                panic!("scene {index}: no feedback ({:?})", step.status);
            };
            let strong: Vec<ControlFeedback> = feedback
                .iter()
                .map(|f| f.map(|row| row.map(|g| 1e6 * g)))
                .collect();
            let played = unpack(&pr.stepped_with_feedback(&lz, &warm, &step.du, &step.dx, &strong));
            for (k, (u, w)) in played.iter().zip(&warm).enumerate() {
                let ((s_lo, s_hi), (c_lo, c_hi)) = (lz.sigma_range[k], lz.c_range[k]);
                let (ds, dc) = (u.sigma - w.sigma, u.c - w.c);
                assert!(
                    ds >= -s_lo - 1e-12 && ds <= s_hi + 1e-12,
                    "frame {k}: side {ds}"
                );
                assert!(dc >= -c_lo - 1e-9 && dc <= c_hi + 1e-9, "frame {k}: c {dc}");
            }
            planner.stage(pr, warm, 40);
            let s = &planner.stats;
            fed += s.fed_steps;
            rejected_open_loop += s.fed_steps + s.corrected_steps + s.rejected_steps;
        }
        assert!(
            4 * fed >= rejected_open_loop,
            "{fed} of {rejected_open_loop} rejected steps kept with the feedback"
        );
    }

    #[test]
    fn a_move_cutting_a_grown_corner_between_two_clear_frame_ends_is_a_violation() {
        // The merit holds each frame's whole move, not only its end: next to every corner of a grown
        // wall that stands out into the corridor, a move from just outside one face to just outside the
        // other has both ends clear and its middle inside.
        let scene = staircase_scene(2);
        let (sim, bound, base) = planning_inputs(&scene);
        let settings = SearchSettings::for_quality(Quality::Fast);
        let planner = Planner::new(
            &scene,
            &sim,
            &settings,
            &bound,
            &base.clean[0].trace,
            Budget::unlimited(),
        );
        let corridor = sim.corridor();
        let accepted = MERIT_MARGIN_SHARE * settings.margin_units;
        let (outside, across) = (4.0 * accepted, 1.0);
        let h = crate::geometry::HULL_HALF_WIDTH_UNITS;
        let mut cut_corners = 0;
        for vertex in corridor.walls().iter().flat_map(|w| &w.points) {
            for (sx, sy) in [(1.0, 1.0), (1.0, -1.0), (-1.0, 1.0), (-1.0, -1.0)] {
                let corner = *vertex + Vec2::new(sx * h, sy * h);
                let p0 = corner + Vec2::new(sx * outside, -sy * across);
                let p1 = corner + Vec2::new(-sx * across, sy * outside);
                let ends_clear =
                    corridor.clearance(p0).min(corridor.clearance(p1)) > 2.0 * accepted;
                if !ends_clear || corridor.move_clearance(p0, p1, across) >= 0.0 {
                    continue;
                }
                cut_corners += 1;
                let problem = ScpProblem {
                    start: ModelState {
                        pos: p0,
                        speed: 300.0,
                        heading: 0.0,
                    },
                    ..planner.problem(settings.margin_units, true, 1)
                };
                let moved = [ModelState {
                    pos: p1,
                    ..problem.start
                }];
                let violation = problem.violation(&moved);
                assert!(
                    violation > accepted,
                    "{violation} units across the corner at {corner:?}"
                );
            }
        }
        assert!(cut_corners >= 2, "{cut_corners} corners cut");
    }

    #[test]
    fn the_curvature_share_halves_after_steps_gaining_twice_their_prediction_and_comes_back_after_poor_ones(
    ) {
        // A step gaining twice its prediction: the merit was about linear along it. The shares are powers
        // of two, so they compare exactly.
        let mut share = 1.0;
        let halved: Vec<f64> = (0..8)
            .map(|_| {
                share = next_curvature_share(share, Some(2.0));
                share
            })
            .collect();
        let floor = MIN_CURVATURE_SHARE;
        assert_eq!(
            halved,
            [0.5, 0.25, 0.125, 0.0625, 0.03125, floor, floor, floor]
        );
        // A step the model predicted well keeps the share; a poor or rejected one doubles it back.
        assert_eq!(next_curvature_share(0.25, Some(1.0)), 0.25);
        assert_eq!(next_curvature_share(0.25, Some(0.5)), 0.5);
        assert_eq!(next_curvature_share(0.25, None), 0.5);
        assert_eq!(next_curvature_share(1.0, None), 1.0);
    }

    #[test]
    fn only_a_regrowing_stage_grows_its_trust_region_after_a_good_correction() {
        // A correction that delivered most of its prediction: doubled, up to the cap.
        assert_eq!(trust_after_correction(0.3, 0.9, StageKind::Regrowing), 0.6);
        assert_eq!(
            trust_after_correction(3.0, 0.9, StageKind::Regrowing),
            MAX_TRUST
        );
        // One that delivered less, or any in a plain stage: the region as it was.
        assert_eq!(trust_after_correction(0.3, 0.5, StageKind::Regrowing), 0.3);
        assert_eq!(trust_after_correction(0.3, 0.9, StageKind::Plain), 0.3);
    }

    fn solver_with(costs: &[f64], max_iters: u64) -> ScpSolver<'static> {
        let mut s = ScpSolver::new(1e-6, Budget::unlimited());
        s.costs = costs.to_vec();
        s.max_iters = max_iters;
        s
    }

    #[test]
    fn a_stage_short_of_the_line_stops_only_when_its_pace_cannot_reach_it() {
        // 2 units short, gaining 0.01 a step: 100 iterations left would close only 1 unit.
        let creeping: Vec<f64> = (0..=10).map(|k| 2.1 - 0.01 * f64::from(k)).collect();
        assert!(solver_with(&creeping, 110).stalled_short_of_the_line(2.0, 10));
        // The same pace with 300 iterations left could close 3 units: go on.
        assert!(!solver_with(&creeping, 310).stalled_short_of_the_line(2.0, 10));
        // Past the line (cost <= 0) never stalls, nor does a stage without a window of history.
        let past: Vec<f64> = (0..=10).map(|k| -0.1 - 1e-6 * f64::from(k)).collect();
        assert!(!solver_with(&past, 110).stalled_short_of_the_line(-0.10001, 10));
        assert!(!solver_with(&creeping[..5], 110).stalled_short_of_the_line(2.06, 4));
    }
}
