//! Shaping the relaxed line with argmin's L-BFGS (issue 5): maximal progress after frame N with a quadratic
//! wall penalty, over smooth transforms of the relaxed controls, with exact gradients computed in reverse
//! through the frames (an adjoint pass over the frame Jacobians of [`super::model`]).
//!
//! The linear sub-steps of the SCP converge slowly on long lines (the progress is linear in the positions,
//! the positions are not in the headings, and a heading change early in the run moves everything after it);
//! a quasi-Newton method sees that curvature. The penalty is raised in steps and the result is handed to
//! the SCP, which enforces the walls exactly.
//!
//! Controls: `sigma = sin(a)`; `c = c_hi - (c_hi - c_lo) sin^2(b)` with `c_lo = L - gamma1` (the kink of the
//! law) and `c_hi` the maximum-acceleration `c`, so the law stays on one smooth piece. Braking below the kink
//! is left to the SCP.

use super::model::{frame, FrameControl, FrameLaw, ModelState};
use crate::geometry::{Corridor, Separation};
use crate::physics::Vec2;
use argmin::core::{CostFunction, Error as ArgminError, Executor, Gradient, State};
use argmin::solver::linesearch::MoreThuenteLineSearch;
use argmin::solver::quasinewton::LBFGS;

/// The penalised progress problem over transformed controls.
#[derive(Clone)]
pub struct ShapingProblem<'a> {
    /// Start of the run.
    pub start: ModelState,
    /// Frame law.
    pub fl: FrameLaw,
    /// Walls.
    pub corridor: &'a Corridor,
    /// A point of the finish line.
    pub finish_a: Vec2,
    /// Unit normal of the finish line (progress direction).
    pub progress_dir: Vec2,
    /// Clearance asked for, units.
    pub margin: f64,
    /// Penalty weight per squared unit of violation.
    pub penalty: f64,
    /// Walls farther than this from a move are ignored, units.
    pub wall_radius: f64,
}

impl ShapingProblem<'_> {
    fn c_range(&self) -> (f64, f64) {
        let hi = self.fl.c_max(f64::INFINITY);
        (self.fl.kink().min(hi), hi)
    }

    /// The controls of a transformed parameter vector.
    pub fn controls(&self, p: &[f64]) -> Vec<FrameControl> {
        let (lo, hi) = self.c_range();
        p.chunks_exact(2)
            .map(|ab| FrameControl {
                sigma: ab[0].sin(),
                c: hi - (hi - lo) * ab[1].sin().powi(2),
            })
            .collect()
    }

    /// The transformed parameters of controls (clamped into range).
    pub fn params(&self, controls: &[FrameControl]) -> Vec<f64> {
        let (lo, hi) = self.c_range();
        controls
            .iter()
            .flat_map(|u| {
                let a = u.sigma.clamp(-1.0, 1.0).asin();
                let frac = if hi > lo {
                    ((hi - u.c) / (hi - lo)).clamp(0.0, 1.0)
                } else {
                    0.0
                };
                [a, frac.sqrt().asin()]
            })
            .collect()
    }

    /// Cost and, when `grad` is given, its gradient.
    fn evaluate(&self, p: &[f64], grad: Option<&mut Vec<f64>>) -> f64 {
        let controls = self.controls(p);
        let n = controls.len();
        let mut states = Vec::with_capacity(n);
        let mut jacs = Vec::with_capacity(n);
        let mut x = self.start;
        for &u in &controls {
            let (next, j) = frame(&x, u, &self.fl, grad.is_some());
            states.push(next);
            jacs.push(j);
            x = next;
        }
        let pos = |k: usize| {
            if k == 0 {
                self.start.pos
            } else {
                states[k - 1].pos
            }
        };
        // Penalty per frame move k (from state k to state k+1, states 0-based with 0 = start).
        let mut cost = -self.progress_dir.dot(pos(n) - self.finish_a);
        let mut dpos = vec![Vec2::ZERO; n + 1]; // d cost / d position of state k
        dpos[n] = -self.progress_dir;
        let mut seps: Vec<Separation> = Vec::new();
        for k in 0..n {
            seps.clear();
            self.corridor
                .separations(pos(k), pos(k + 1), self.wall_radius, None, &mut seps);
            for s in &seps {
                let v = self.margin - s.clearance;
                if v > 0.0 {
                    cost += self.penalty * v * v;
                    let g = s.plane.normal * (-2.0 * self.penalty * v);
                    dpos[k] += g * (1.0 - s.move_param);
                    dpos[k + 1] += g * s.move_param;
                }
            }
        }
        if let Some(grad) = grad {
            grad.clear();
            grad.resize(2 * n, 0.0);
            let (lo, hi) = self.c_range();
            // lambda = d cost / d state after frame k, accumulated backwards.
            let mut lambda = [0.0f64; 4];
            for k in (0..n).rev() {
                lambda[0] += dpos[k + 1].x;
                lambda[1] += dpos[k + 1].y;
                if let Some(j) = &jacs[k] {
                    let mut gu = [0.0; 2];
                    for (r, l) in lambda.iter().enumerate() {
                        gu[0] += j.b[r][0] * l;
                        gu[1] += j.b[r][1] * l;
                    }
                    let (a, b) = (p[2 * k], p[2 * k + 1]);
                    grad[2 * k] = gu[0] * a.cos();
                    grad[2 * k + 1] = gu[1] * (-(hi - lo) * 2.0 * b.sin() * b.cos());
                    let mut prev = [0.0; 4];
                    for (col, pv) in prev.iter_mut().enumerate() {
                        for (r, l) in lambda.iter().enumerate() {
                            *pv += j.a[r][col] * l;
                        }
                    }
                    lambda = prev;
                }
            }
        }
        cost
    }
}

impl CostFunction for ShapingProblem<'_> {
    type Param = Vec<f64>;
    type Output = f64;
    fn cost(&self, p: &Vec<f64>) -> Result<f64, ArgminError> {
        let c = self.evaluate(p, None);
        if c.is_finite() {
            Ok(c)
        } else {
            Err(ArgminError::msg("non-finite cost"))
        }
    }
}

impl Gradient for ShapingProblem<'_> {
    type Param = Vec<f64>;
    type Gradient = Vec<f64>;
    fn gradient(&self, p: &Vec<f64>) -> Result<Vec<f64>, ArgminError> {
        let mut g = Vec::new();
        self.evaluate(p, Some(&mut g));
        if g.iter().all(|v| v.is_finite()) {
            Ok(g)
        } else {
            Err(ArgminError::msg("non-finite gradient"))
        }
    }
}

/// L-BFGS memory.
const LBFGS_MEMORY: usize = 12;
/// Penalty weights of the continuation, per squared unit.
pub const PENALTY_STEPS: [f64; 3] = [10.0, 100.0, 1000.0];

/// Shapes `controls` with L-BFGS under the penalty continuation; returns the best controls found and the
/// L-BFGS iterations used. A failed line search (the penalty's kinks) ends that step with the best point.
pub fn shape(
    problem: &ShapingProblem,
    controls: &[FrameControl],
    iters_per_step: u64,
) -> (Vec<FrameControl>, u64) {
    let mut p = problem.params(controls);
    let mut iterations = 0;
    for &penalty in &PENALTY_STEPS {
        let step = ShapingProblem {
            penalty,
            ..problem.clone()
        };
        let solver = LBFGS::new(MoreThuenteLineSearch::new(), LBFGS_MEMORY);
        let start = p.clone();
        // A failed line search at a kink of the penalty ends this step; the best point so far is kept.
        if let Ok(res) = Executor::new(step, solver)
            .configure(|s| s.param(start).max_iters(iters_per_step))
            .run()
        {
            iterations += res.state().get_iter();
            if let Some(best) = res.state().get_best_param() {
                p = best.clone();
            }
        }
    }
    (problem.controls(&p), iterations)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::{BoundaryKind, Wall};
    use crate::physics::{curvature::air_law, MovementVars};

    #[test]
    fn a_failing_line_search_keeps_the_start() {
        // An infinite penalty makes every cost non-finite: argmin's run fails, and shaping hands back the
        // controls it was given instead of panicking or returning garbage.
        let vars = MovementVars::goldsrc(100.0);
        let fl = FrameLaw {
            tau_s: 0.01,
            law: air_law(&vars),
            side_key_speed: 400.0,
        };
        let walls = [Wall {
            points: vec![Vec2::new(0.0, 1.0), Vec2::new(400.0, 1.0)],
            closed: false,
            kind: BoundaryKind::Rule,
        }];
        let corridor = Corridor::new(&walls).unwrap_or_else(|e| panic!("{e}"));
        let pr = ShapingProblem {
            start: ModelState {
                pos: Vec2::ZERO,
                speed: 400.0,
                heading: 0.0,
            },
            fl,
            corridor: &corridor,
            finish_a: Vec2::new(300.0, 0.0),
            progress_dir: Vec2::new(1.0, 0.0),
            margin: f64::INFINITY,
            penalty: 0.0,
            wall_radius: 40.0,
        };
        let controls = vec![FrameControl { sigma: 0.5, c: 0.0 }; 20];
        let (out, _) = shape(&pr, &controls, 50);
        for (a, b) in out.iter().zip(&controls) {
            assert!(
                (a.sigma - b.sigma).abs() < 1e-12 && (a.c - b.c).abs() < 1e-9,
                "{a:?} vs {b:?}"
            );
        }
    }

    #[test]
    fn gradient_matches_finite_differences() {
        let vars = MovementVars::goldsrc(100.0);
        let fl = FrameLaw {
            tau_s: 0.01,
            law: air_law(&vars),
            side_key_speed: 400.0,
        };
        let walls = [Wall {
            points: vec![Vec2::new(0.0, 40.0), Vec2::new(400.0, 40.0)],
            closed: false,
            kind: BoundaryKind::Rule,
        }];
        let corridor = Corridor::new(&walls).unwrap_or_else(|e| panic!("{e}"));
        let pr = ShapingProblem {
            start: ModelState {
                pos: Vec2::ZERO,
                speed: 400.0,
                heading: 0.3,
            },
            fl,
            corridor: &corridor,
            finish_a: Vec2::new(300.0, 0.0),
            progress_dir: Vec2::new(1.0, 0.0),
            margin: 2.0,
            penalty: 10.0,
            wall_radius: 40.0,
        };
        let p: Vec<f64> = (0..60).map(|i| 0.3 * ((i as f64) * 0.7).sin()).collect();
        let mut g = Vec::new();
        pr.evaluate(&p, Some(&mut g));
        // The run heads into the wall, so the penalty is active on some frames.
        let unpenalised = ShapingProblem {
            penalty: 0.0,
            ..pr.clone()
        };
        assert!(pr.evaluate(&p, None) > unpenalised.evaluate(&p, None) + 1.0);
        let h = 1e-6;
        for i in 0..p.len() {
            let mut a = p.clone();
            let mut b = p.clone();
            a[i] += h;
            b[i] -= h;
            let fd = (pr.evaluate(&a, None) - pr.evaluate(&b, None)) / (2.0 * h);
            assert!(
                (fd - g[i]).abs() < 1e-4 * (1.0 + fd.abs()),
                "param {i}: {fd} vs {}",
                g[i]
            );
        }
    }
}
