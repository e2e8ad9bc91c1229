//! One convexified sub-step set up from a scene, for benchmarks and tests: the greedy run in
//! planning variables, linearised frame by frame, its walls as separating half-planes, and a trust region
//! around it, in the shape [`qp::solve`] takes. It mirrors the first relaxed iteration of
//! [`super::search`] without running the search.

use super::model::{frame, frame_control_of, FrameControl, FrameJacobian, FrameLaw, ModelState};
use super::qp::{self, SubProblem, SubProblemSolver, SubStep, WallRow};
use super::{lower_bound, SearchSettings};
use crate::error::{Error, Result};
use crate::geometry::Separation;
use crate::physics::Vec2;
use crate::scene::Scene;
use crate::sim::controllers::{best_greedy, GREEDY_LOOKAHEADS_UNITS};
use crate::sim::Simulation;

/// Trust region on `sigma` of the set-up sub-step (the search's first iteration uses the same).
pub const SUBSTEP_SIGMA_TRUST: f64 = 0.1;
/// Trust region on `c` of the set-up sub-step, ups.
pub const SUBSTEP_C_TRUST_UPS: f64 = 5.0;

/// The data of one sub-problem, owned, so that [`SubStepSetup::sub_problem`] can lend it to [`qp::solve`].
#[derive(Clone, Debug)]
pub struct SubStepSetup {
    /// Per frame, the Jacobian at the greedy trajectory.
    pub jacobians: Vec<FrameJacobian>,
    /// Per frame, the end position.
    pub positions: Vec<Vec2>,
    /// Wall rows.
    pub walls: Vec<WallRow>,
    /// Per frame, the allowed change of sigma.
    pub sigma_range: Vec<(f64, f64)>,
    /// Per frame, the allowed change of c, ups.
    pub c_range: Vec<(f64, f64)>,
    /// Unit normal of the finish line, the way the run crosses it.
    pub progress_dir: Vec2,
    /// Wall margin, units.
    pub margin: f64,
    /// Slack weight.
    pub slack_weight: f64,
    /// The solver the sub-problem is given first.
    pub solver: SubProblemSolver,
}

impl SubStepSetup {
    /// The first relaxed sub-step of `scene` around its best greedy run (airborne scenes only; others are
    /// an [`Error::Unreachable`]).
    pub fn greedy(scene: &Scene, settings: &SearchSettings) -> Result<Self> {
        if !scene.effects.is_air_only() {
            return Err(Error::Unreachable {
                what: format!(
                    "{}: a sub-step is set up for airborne scenes only; this scene runs {}",
                    scene.origin, scene.effects
                ),
            });
        }
        let sim = Simulation::new(scene)?;
        let bound = lower_bound(scene, sim.corridor())?;
        let (greedy, _) = best_greedy(&sim, &bound.path, &GREEDY_LOOKAHEADS_UNITS);
        let fl = FrameLaw::of(&scene.vars);
        let mut x = ModelState {
            pos: scene.start.pos,
            speed: scene.start.speed(),
            heading: scene.start.vel.angle(),
        };
        let mut vel = scene.start.vel;
        let mut controls: Vec<FrameControl> = Vec::with_capacity(greedy.controls.len());
        for (c, rec) in greedy.controls.iter().zip(&greedy.frames) {
            controls.push(frame_control_of(vel, c));
            vel = rec.vel;
        }
        let margin = fl.planning_margin(settings.margin_units);
        let mut jacobians = Vec::with_capacity(controls.len());
        let mut positions = Vec::with_capacity(controls.len());
        let mut sigma_range = Vec::with_capacity(controls.len());
        let mut c_range = Vec::with_capacity(controls.len());
        let mut walls = Vec::new();
        let mut seps: Vec<Separation> = Vec::new();
        for (k, &u) in controls.iter().enumerate() {
            let (next, j) = frame(&x, u, &fl, true);
            if let Some(j) = j {
                jacobians.push(j);
            }
            sigma_range.push((
                SUBSTEP_SIGMA_TRUST.min(1.0 + u.sigma),
                SUBSTEP_SIGMA_TRUST.min(1.0 - u.sigma),
            ));
            let c_min = fl.c_min(x.speed);
            c_range.push((
                SUBSTEP_C_TRUST_UPS.min(u.c - c_min).max(0.0),
                SUBSTEP_C_TRUST_UPS.min(fl.c_max(x.speed) - u.c).max(0.0),
            ));
            seps.clear();
            sim.corridor().separations(
                x.pos,
                next.pos,
                settings.wall_radius_units,
                None,
                &mut seps,
            );
            for sep in &seps {
                walls.push(WallRow {
                    frame: k,
                    plane: sep.plane,
                    group: k,
                });
            }
            positions.push(next.pos);
            x = next;
        }
        let d = scene.finish.b - scene.finish.a;
        let n = d.perp().normalized().unwrap_or(Vec2::new(1.0, 0.0));
        let approach = match bound.path.len() {
            0 | 1 => scene.finish.a - scene.start.pos,
            k => bound.path[k - 1] - bound.path[k - 2],
        };
        Ok(SubStepSetup {
            jacobians,
            positions,
            walls,
            sigma_range,
            c_range,
            progress_dir: if n.dot(approach) >= 0.0 { n } else { -n },
            margin,
            slack_weight: settings.slack_weight,
            solver: settings.sub_problem_solver,
        })
    }

    /// The sub-problem borrowing this data.
    pub fn sub_problem(&self) -> SubProblem<'_> {
        SubProblem {
            jacobians: &self.jacobians,
            positions: &self.positions,
            walls: &self.walls,
            margin: self.margin,
            accepted_clearance: 0.5 * self.margin,
            slack_weight: self.slack_weight,
            progress_dir: self.progress_dir,
            sigma_range: &self.sigma_range,
            c_range: &self.c_range,
            curvature: None,
            wall_shift: None,
            solver: self.solver,
            with_feedback: false,
        }
    }

    /// Solves the sub-problem.
    pub fn solve(&self) -> SubStep {
        qp::solve(&self.sub_problem())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::optimise::qp::SubStepStatus;
    use crate::optimise::Quality;

    #[test]
    fn the_bend_substep_solves_and_predicts_progress() {
        let text = include_str!("../../scenarios/hl-bend90-100fps.toml");
        let scene =
            Scene::from_toml_str(text, "hl-bend90-100fps.toml").unwrap_or_else(|e| panic!("{e}"));
        let setup = SubStepSetup::greedy(&scene, &SearchSettings::for_quality(Quality::Fast))
            .unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(setup.jacobians.len(), setup.positions.len());
        let step = setup.solve();
        assert!(
            matches!(step.status, SubStepStatus::Solved { .. }),
            "{:?}",
            step.status
        );
        assert_eq!(step.du.len(), setup.positions.len());
        assert!(step.predicted.is_finite());
    }
}
