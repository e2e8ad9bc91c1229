//! Simulation of a scene (docs/physics.md sections 3 and 10): one frame loop, [`Simulation::run`], owns the
//! walls, the rule lines, the finish line and the frame cap; [`Controller`]s only choose each frame's
//! control (as argmin's `Solver` leaves the loop to its `Executor`).
//!
//! Each frame: the controller picks a [`Control`], the stepper runs steps 1-4, the hull is swept through
//! the solid walls (or moved freely), steps 5-6 follow, then rule lines are checked along the frame's
//! straight move and the finish crossing is found with its fraction inside the frame.

pub mod abh;
pub mod controllers;
pub mod trace;

use crate::budget::{Budget, FRAMES_PER_BUDGET_CHECK};
use crate::error::Result;
use crate::geometry::{BoundaryKind, Corridor, DIST_EPSILON_UNITS};
use crate::physics::{Control, Effect, PlayerState, Stepper, Vec2, Wish};
use crate::scene::Scene;
pub use controllers::{Greedy, Playback, SideStrafer};
pub use trace::{Crossing, FrameRecord, Trace};

/// Chooses the control of each frame from the state before it.
pub trait Controller {
    /// A short name for reports (`greedy`, `max-accel-left`).
    fn name(&self) -> String;
    /// The control of frame `frame` (1-based) given the state before it.
    fn control(&mut self, frame: u64, state: &PlayerState, sim: &Simulation) -> Control;
}

/// A scene ready to simulate: its stepper (only the scene's effects) and its corridor, built once.
pub struct Simulation<'s> {
    scene: &'s Scene,
    stepper: Stepper<f64>,
    corridor: Corridor,
    solid_walls: bool,
    rule_walls: bool,
}

impl<'s> Simulation<'s> {
    /// Prepares `scene` for simulation.
    pub fn new(scene: &'s Scene) -> Result<Self> {
        let corridor = scene.corridor()?;
        let solid_walls = scene.effects.has(Effect::Walls) && corridor.has(BoundaryKind::Solid);
        let rule_walls = corridor.has(BoundaryKind::Rule);
        Ok(Simulation {
            scene,
            stepper: Stepper::new(&scene.vars, scene.effects),
            corridor,
            solid_walls,
            rule_walls,
        })
    }

    /// The scene.
    pub fn scene(&self) -> &Scene {
        self.scene
    }

    /// The frame stepper.
    pub fn stepper(&self) -> &Stepper<f64> {
        &self.stepper
    }

    /// The corridor.
    pub fn corridor(&self) -> &Corridor {
        &self.corridor
    }

    /// True when the hull can move straight from `p0` to `p1` without crossing into a rule boundary or
    /// hitting a solid wall (touching is allowed).
    pub fn clear_line(&self, p0: Vec2, p1: Vec2) -> bool {
        if self.rule_walls && self.corridor.rule_violation_swept(p0, p1) {
            return false;
        }
        !(self.solid_walls
            && matches!(
                self.corridor.cast(p0, p1 - p0),
                crate::geometry::Cast::Hit(_) | crate::geometry::Cast::StartedInside { .. }
            ))
    }

    /// One frame from `s` with control `c`: the step, the swept move, the rule check. Returns the number
    /// of wall contacts and whether a rule line was crossed.
    #[inline]
    pub fn frame(&self, s: &mut PlayerState, c: &Control) -> FrameOutcome {
        self.frame_wish(s, &c.wish())
    }

    /// [`Simulation::frame`] with the control already in vector form.
    #[inline]
    pub fn frame_wish(&self, s: &mut PlayerState, wish: &Wish) -> FrameOutcome {
        let before = s.pos;
        self.stepper.pre_move(s, wish);
        let mut contacts = 0;
        if self.solid_walls {
            let r = self
                .corridor
                .sweep(s.pos, s.vel, self.stepper.frame_time_s());
            s.pos = r.pos;
            s.vel = r.vel;
            contacts = r.status.contacts();
        } else {
            s.pos += s.vel * self.stepper.frame_time_s();
        }
        self.stepper.post_move(s);
        let broke_rule = self.rule_walls && self.corridor.rule_violation_swept(before, s.pos);
        FrameOutcome {
            from: before,
            contacts,
            broke_rule,
        }
    }

    /// Plays `controls` in the engine-exact mode (f32 state, anglemod yaw; docs/physics.md section 1) through the
    /// same walls, rule lines and finish line. The walls are queried in f64 on the f32 positions, and a
    /// hit stops [`DIST_EPSILON_UNITS`] short of the wall, as the game's trace does.
    pub fn run_engine_exact(&self, controls: &[Control]) -> EngineRun {
        self.run_engine_exact_within(controls, &Budget::unlimited())
    }

    /// [`Self::run_engine_exact`] that stops when `budget` expires; a replay cut short is marked
    /// `interrupted` and is not [`EngineRun::feasible`].
    pub fn run_engine_exact_within(&self, controls: &[Control], budget: &Budget) -> EngineRun {
        use crate::physics::engine_exact::{engine_wish, from_engine_state, to_engine_state};
        let game: Stepper<f32> = Stepper::new(&self.scene.vars, self.scene.effects);
        let tau = f64::from(game.frame_time_s());
        let mut g = to_engine_state(&self.scene.start);
        let mut run = EngineRun {
            crossing: None,
            broke_rule: false,
            min_clearance: self.corridor.clearance(self.scene.start.pos),
            finite: true,
            interrupted: false,
        };
        for (i, c) in controls.iter().enumerate() {
            if i as u64 % FRAMES_PER_BUDGET_CHECK == 0 && budget.expired() {
                run.interrupted = true;
                break;
            }
            let before = from_engine_state(&g).pos;
            game.pre_move(&mut g, &engine_wish(c));
            if self.solid_walls {
                let s = from_engine_state(&g);
                let r = self
                    .corridor
                    .sweep_standing_off(s.pos, s.vel, tau, DIST_EPSILON_UNITS);
                g.pos = crate::physics::V2::from_f64(r.pos);
                g.vel = crate::physics::V2::from_f64(r.vel);
            } else {
                g.pos += g.vel * game.frame_time_s();
            }
            game.post_move(&mut g);
            let after = from_engine_state(&g).pos;
            run.finite &= g.is_finite();
            run.broke_rule |= self.rule_walls && self.corridor.rule_violation_swept(before, after);
            run.min_clearance = run.min_clearance.min(self.corridor.clearance(after));
            if let Some(f) = self.scene.finish.crossing_fraction(before, after) {
                run.crossing = Some(Crossing::new(i as u64 + 1, f, tau));
                break;
            }
            if !run.finite {
                break;
            }
        }
        run
    }

    /// Runs `controller` from the scene's start until the finish line is crossed or the frame cap.
    pub fn run(&self, controller: &mut dyn Controller) -> Trace {
        self.run_within(controller, &Budget::unlimited())
    }

    /// [`Self::run`] that stops when `budget` expires; a run cut short is marked `interrupted` (it has no
    /// crossing, so it is not feasible).
    pub fn run_within(&self, controller: &mut dyn Controller, budget: &Budget) -> Trace {
        let tau = self.stepper.frame_time_s();
        let mut s = self.scene.start;
        let mut trace = Trace::new(controller.name(), &s, self.corridor.clearance(s.pos));
        for frame in 1..=self.scene.max_frames {
            if frame % FRAMES_PER_BUDGET_CHECK == 0 && budget.expired() {
                trace.interrupted = true;
                break;
            }
            let c = controller.control(frame, &s, self);
            let wish = c.wish();
            let theta = wish.theta_rad(s.vel);
            let out = self.frame_wish(&mut s, &wish);
            if !s.is_finite() {
                // The run stops at the last finite state; the failing frame is not recorded.
                trace.numerical_failure = true;
                break;
            }
            let crossing = self
                .scene
                .finish
                .crossing_fraction(out.from, s.pos)
                .map(|f| Crossing::new(frame, f, tau));
            trace.push(
                FrameRecord {
                    frame,
                    time: frame as f64 * tau,
                    pos: s.pos,
                    vel: s.vel,
                    speed: s.speed(),
                    yaw_rad: c.yaw_rad,
                    theta_rad: theta,
                    on_ground: s.on_ground,
                    ducked: s.ducked,
                    clearance: self.corridor.clearance(s.pos),
                    contacts: out.contacts,
                    broke_rule: out.broke_rule,
                },
                c,
            );
            if let Some(c) = crossing {
                trace.crossing = Some(c);
                break;
            }
        }
        trace
    }

    /// Runs `controller` like [`Self::run_within`] but keeps only the summary of the run, not its frames:
    /// memory that does not grow with the run's length, for sweeps that keep only their best run (and
    /// replay it with [`Self::run`]).
    pub fn run_summary(&self, controller: &mut dyn Controller, budget: &Budget) -> RunSummary {
        self.summarise(controller, budget, None)
    }

    /// [`Self::run_summary`] that gives a run up once it has broken a rule and run `broken_frame_limit`
    /// frames: an invalid run is then only ranked by when it crosses, and one that has not crossed by then
    /// need not be played on (an invalid run may wander until the frame cap).
    pub fn run_summary_broken_until(
        &self,
        controller: &mut dyn Controller,
        budget: &Budget,
        broken_frame_limit: u64,
    ) -> RunSummary {
        self.summarise(controller, budget, Some(broken_frame_limit))
    }

    fn summarise(
        &self,
        controller: &mut dyn Controller,
        budget: &Budget,
        broken_frame_limit: Option<u64>,
    ) -> RunSummary {
        let tau = self.stepper.frame_time_s();
        let mut s = self.scene.start;
        let mut summary = RunSummary {
            crossing: None,
            end_pos: s.pos,
            frames_run: 0,
            collisions: 0,
            broke_rule: false,
            numerical_failure: false,
            interrupted: false,
        };
        for frame in 1..=self.scene.max_frames {
            if frame % FRAMES_PER_BUDGET_CHECK == 0 && budget.expired() {
                summary.interrupted = true;
                break;
            }
            let c = controller.control(frame, &s, self);
            let out = self.frame(&mut s, &c);
            if !s.is_finite() {
                summary.numerical_failure = true;
                break;
            }
            summary.frames_run = frame;
            summary.end_pos = s.pos;
            summary.collisions += out.contacts;
            summary.broke_rule |= out.broke_rule;
            if summary.broke_rule && broken_frame_limit.is_some_and(|limit| frame >= limit) {
                break;
            }
            if let Some(f) = self.scene.finish.crossing_fraction(out.from, s.pos) {
                summary.crossing = Some(Crossing::new(frame, f, tau));
                break;
            }
        }
        summary
    }
}

/// What a run did, without its frames ([`Simulation::run_summary`]): the same verdicts as its [`Trace`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RunSummary {
    /// The finish crossing, if reached.
    pub crossing: Option<Crossing>,
    /// Hull centre after the last frame run.
    pub end_pos: Vec2,
    /// Frames run.
    pub frames_run: u64,
    /// Total wall contacts.
    pub collisions: u32,
    /// A frame's move crossed into a rule boundary.
    pub broke_rule: bool,
    /// A state became NaN or infinite.
    pub numerical_failure: bool,
    /// The budget ran out before the run ended.
    pub interrupted: bool,
}

impl RunSummary {
    /// As [`Trace::feasible`]: crossed the line, no rule broken, every state finite.
    pub fn feasible(&self) -> bool {
        self.crossing.is_some() && !self.broke_rule && !self.numerical_failure
    }
}

/// A plan played in the engine-exact mode.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct EngineRun {
    /// The finish crossing, if reached.
    pub crossing: Option<Crossing>,
    /// A frame's move crossed into a rule boundary.
    pub broke_rule: bool,
    /// Smallest clearance over the frame ends, units.
    pub min_clearance: f64,
    /// Every state stayed finite.
    pub finite: bool,
    /// The budget ran out before the replay ended (the plan is unverified).
    pub interrupted: bool,
}

impl EngineRun {
    /// Reached the line without breaking a rule.
    pub fn feasible(&self) -> bool {
        self.crossing.is_some() && !self.broke_rule && self.finite && !self.interrupted
    }
}

/// What one frame did besides moving the state.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FrameOutcome {
    /// Hull centre before the frame.
    pub from: Vec2,
    /// Wall contacts of the swept move.
    pub contacts: u32,
    /// The straight move crossed into a rule boundary.
    pub broke_rule: bool,
}
