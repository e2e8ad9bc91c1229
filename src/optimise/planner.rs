//! What the stages of an airborne solve share: where planning starts, the frame law, the corridor, the
//! direction of progress, the settings, the deadline and the work done so far.

use super::model::{frame_control_of, rollout, FrameControl, FrameLaw, ModelState};
use super::scp::{run_scp, ScpProblem, StageKind, CLEAN_VIOLATION_UNITS};
use super::search::{seconds_since, SearchSettings, SearchStats, StageSeconds};
use super::LowerBound;
use crate::budget::{Budget, Stage};
use crate::physics::{Control, Vec2};
use crate::scene::Scene;
use crate::sim::{Crossing, Simulation, Trace};

/// Below this start speed, ups, the planning model has no heading to work from: the seed's first frame is
/// played as it is and the plan starts after it.
const MIN_PLANNING_SPEED_UPS: f64 = 1.0;

/// The shared state of the stages of one airborne solve.
pub(super) struct Planner<'a> {
    pub(super) scene: &'a Scene,
    pub(super) sim: &'a Simulation<'a>,
    pub(super) settings: &'a SearchSettings,
    /// The planning state after the fixed prefix.
    pub(super) start: ModelState,
    /// Game controls played before the plan, as they are: the seed's first frame when the start is at
    /// rest (from rest every wish direction gains the same, and the planning model has no heading).
    pub(super) prefix: Vec<Control>,
    pub(super) fl: FrameLaw,
    /// The finish line's normal, pointing the way the shortest path crosses it.
    pub(super) progress_dir: Vec2,
    pub(super) budget: Budget<'a>,
    pub(super) stats: SearchStats,
    /// Whether the budget stopped a stage.
    pub(super) timed_out: bool,
    /// The first stage the budget cut.
    pub(super) cut_in: Option<Stage>,
    /// Of the exact plans whose replay failed on this planner, the one planned to cross first: where it
    /// crosses in the model, and its controls (a fork's own is not joined back: exact plans are verified on
    /// the solve's planner).
    pub(super) earliest_failed_plan: Option<(Crossing, Vec<FrameControl>)>,
    /// The seconds of the airborne stages run on this planner's thread (a fork's are not joined back:
    /// its work is inside the stage it runs beside).
    pub(super) seconds: StageSeconds,
}

/// The airborne frame law of a scene.
pub(super) fn frame_law(scene: &Scene) -> FrameLaw {
    FrameLaw::of(&scene.vars)
}

impl<'a> Planner<'a> {
    /// The planner of `scene` starting from the `seed` run (its first frame becomes the prefix when the
    /// start is at rest).
    pub(super) fn new(
        scene: &'a Scene,
        sim: &'a Simulation<'a>,
        settings: &'a SearchSettings,
        bound: &LowerBound,
        seed: &Trace,
        budget: Budget<'a>,
    ) -> Self {
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
        Planner {
            scene,
            sim,
            settings,
            start,
            prefix,
            fl: frame_law(scene),
            progress_dir: finish_direction(scene, bound),
            budget,
            stats: SearchStats::default(),
            timed_out: false,
            cut_in: None,
            earliest_failed_plan: None,
            seconds: StageSeconds::default(),
        }
    }

    /// A planner for work on another thread: the same scene, start, law, settings and budget, with work
    /// counts of its own ([`Planner::join`] adds them back).
    pub(super) fn fork(&self) -> Planner<'a> {
        Planner {
            scene: self.scene,
            sim: self.sim,
            settings: self.settings,
            start: self.start,
            prefix: self.prefix.clone(),
            fl: self.fl,
            progress_dir: self.progress_dir,
            budget: self.budget,
            stats: SearchStats::default(),
            timed_out: false,
            cut_in: None,
            earliest_failed_plan: None,
            seconds: StageSeconds::default(),
        }
    }

    /// Whether `plan` from this planner's start keeps `margin` units off the walls in the planning model
    /// (a move counts as clear at half its margin: [`ScpProblem::violation`]).
    pub(super) fn keeps_the_walls(&self, plan: &[FrameControl], margin: f64) -> bool {
        let states = rollout(&self.start, plan, &self.fl);
        self.problem(margin, false, 1).violation(&states) <= CLEAN_VIOLATION_UNITS
    }

    /// A plan whose replay failed, planned to cross at `planned` in the model (`None`: it does not reach
    /// the line), kept as [`Planner::earliest_failed_plan`] where it crosses before the one kept so far.
    pub(super) fn note_failed_plan(
        &mut self,
        planned: Option<Crossing>,
        controls: Vec<FrameControl>,
    ) {
        let earliest = &mut self.earliest_failed_plan;
        if let Some(p) = planned.filter(|p| earliest.as_ref().is_none_or(|f| p.time < f.0.time)) {
            *earliest = Some((p, controls));
        }
    }

    /// A [`Planner::fork`] that plans on from `replay` (a run of this planner's prefix and then a plan)
    /// after the plan's first `frames` frames: its prefix is this one's and the replay's controls of those
    /// frames, as they were played, and its start the replay's state after them.
    pub(super) fn fork_after(&self, replay: &Trace, frames: usize) -> Planner<'a> {
        let played = (self.prefix.len() + frames).min(replay.controls.len());
        let start = played
            .checked_sub(1)
            .and_then(|i| replay.frames.get(i))
            .map_or(self.start, |f| ModelState {
                pos: f.pos,
                speed: f.vel.length(),
                heading: f.vel.angle(),
            });
        Planner {
            start,
            prefix: replay.controls[..played].to_vec(),
            ..self.fork()
        }
    }

    /// A [`Planner::fork`] at other `settings`, for a stage run at settings of its own on this thread.
    pub(super) fn fork_with<'b>(&self, settings: &'b SearchSettings) -> Planner<'b>
    where
        'a: 'b,
    {
        Planner {
            settings,
            ..self.fork()
        }
    }

    /// `work` on this planner, its wall-clock seconds added to the stage `stage` picks of
    /// [`Planner::seconds`].
    pub(super) fn clocked<R>(
        &mut self,
        stage: fn(&mut StageSeconds) -> &mut f64,
        work: impl FnOnce(&mut Self) -> R,
    ) -> R {
        let started = std::time::Instant::now();
        let result = work(self);
        *stage(&mut self.seconds) += seconds_since(started);
        result
    }

    /// Adds the work of a [`Planner::fork`] done, and whether the budget cut it.
    pub(super) fn join(&mut self, forked: &Planner) {
        self.stats.add(&forked.stats);
        self.timed_out |= forked.timed_out;
        self.cut_in = self.cut_in.or(forked.cut_in);
    }

    /// `here` on this planner while each of `jobs` runs on a [`Planner::fork`] of it, on a thread of its
    /// own; returns `here`'s result and the jobs' in their order, with the forks' work added back
    /// ([`Planner::join`]). A job's panic is resumed on this thread.
    pub(super) fn beside_forks<T, U, J>(
        &mut self,
        jobs: Vec<J>,
        here: impl FnOnce(&mut Self) -> U,
    ) -> (U, Vec<T>)
    where
        J: FnOnce(&mut Planner<'a>) -> T + Send,
        T: Send,
    {
        let forks: Vec<(J, Planner<'a>)> = jobs.into_iter().map(|job| (job, self.fork())).collect();
        let (mine, theirs) = std::thread::scope(|scope| {
            let handles: Vec<_> = forks
                .into_iter()
                .map(|(job, mut fork)| scope.spawn(move || (job(&mut fork), fork)))
                .collect();
            let mine = here(self);
            let theirs: Vec<(T, Planner<'a>)> = handles
                .into_iter()
                .map(|h| {
                    h.join()
                        .unwrap_or_else(|panic| std::panic::resume_unwind(panic))
                })
                .collect();
            (mine, theirs)
        });
        let results = theirs
            .into_iter()
            .map(|(result, fork)| {
                self.join(&fork);
                result
            })
            .collect();
        (mine, results)
    }

    /// The SCP problem at wall `margin` (units), with relaxed or fixed sides, over planning steps of
    /// `frames_per_knot` frames.
    pub(super) fn problem(
        &self,
        margin: f64,
        relaxed: bool,
        frames_per_knot: u32,
    ) -> ScpProblem<'a> {
        ScpProblem {
            start: self.start,
            fl: self.fl,
            corridor: self.sim.corridor(),
            finish_a: self.scene.finish.a,
            progress_dir: self.progress_dir,
            margin,
            slack_weight: self.settings.slack_weight,
            wall_radius: self.settings.wall_radius_units,
            relaxed,
            frames_per_knot,
            anglemod_guard: true,
            turn_less: false,
            sub_problem_solver: self.settings.sub_problem_solver,
        }
    }

    /// Runs one SCP stage of at most `max_iters` iterations from `controls`, counting its work; returns
    /// the improved controls and whether it stopped at its iteration cap (still improving) rather than
    /// converged.
    pub(super) fn stage(
        &mut self,
        problem: ScpProblem,
        controls: Vec<FrameControl>,
        max_iters: u64,
    ) -> (Vec<FrameControl>, bool) {
        self.stage_of(problem, controls, max_iters, StageKind::Plain)
    }

    /// [`Self::stage`], its trust region growing as `kind` says.
    pub(super) fn stage_of(
        &mut self,
        problem: ScpProblem,
        controls: Vec<FrameControl>,
        max_iters: u64,
        kind: StageKind,
    ) -> (Vec<FrameControl>, bool) {
        let tol = self.settings.tol_progress_units;
        let (c, timed_out, capped, stats) =
            run_scp(problem, controls, max_iters, tol, self.budget, kind);
        self.stats.add(&stats);
        self.timed_out |= timed_out;
        (c, capped)
    }

    /// The time of a planned run of `controls` after the prefix: the fractional crossing time of the
    /// model's trajectory, seconds, and the crossing frame (counting the prefix); `None` if it does not
    /// cross the line.
    pub(super) fn crossing_of(&self, controls: &[FrameControl]) -> Option<Crossing> {
        let states = rollout(&self.start, controls, &self.fl);
        let mut prev = self.start.pos;
        for (k, s) in states.iter().enumerate() {
            if let Some(f) = self.scene.finish.crossing_fraction(prev, s.pos) {
                let frame = (self.prefix.len() + k + 1) as u64;
                return Some(Crossing::new(frame, f, self.fl.tau_s));
            }
            prev = s.pos;
        }
        None
    }

    /// Whether the budget has run out (and notes it).
    pub(super) fn out_of_time(&mut self) -> bool {
        if self.budget.expired() {
            self.timed_out = true;
        }
        self.timed_out
    }

    /// Notes that `stage` was cut when the budget stopped it (the first such stage is the one reported).
    pub(super) fn note_cut(&mut self, stage: Stage) {
        if self.timed_out || self.budget.expired() {
            self.timed_out = true;
            self.cut_in = self.cut_in.or(Some(stage));
        }
    }

    /// The `seed` run in planning variables, after the prefix: the warm start of the relaxed stage. Each
    /// frame's `c` is kept below the anglemod guard of the law's first case, where there is one.
    pub(super) fn warm_start(&self, seed: &Trace) -> Vec<FrameControl> {
        let fl = self.fl;
        let mut vel = match self.prefix.len() {
            0 => self.scene.start.vel,
            _ => seed.frames.first().map_or(self.scene.start.vel, |f| f.vel),
        };
        let mut warm: Vec<FrameControl> = Vec::with_capacity(seed.controls.len());
        for (c, rec) in seed
            .controls
            .iter()
            .zip(&seed.frames)
            .skip(self.prefix.len())
        {
            let mut u = frame_control_of(vel, c);
            let v = vel.length();
            if fl.c_plan_max(v) < fl.c_max(v) {
                u.c = u.c.min(fl.c_plan_max(v));
            }
            // A greedy run brakes straight back (`c = -V`), beyond the plan's range, where the frame's
            // heading is singular in `c` (`sqrt(V^2 - c^2)`): the relaxed frame there keeps its sides
            // cancelled (`sigma = 0`, the same move) so that raising `c` into the range does not swing
            // the heading by more than its linearisation sees. A frame below the range that turns (a
            // greedy run braking into a corner, a plan's frame after the game's quantised angles) keeps
            // its side: cancelled, its push sideways is lost and the run replays off its path.
            if braking_straight_back(u.c, v, &fl) {
                u.sigma = 0.0;
            }
            warm.push(u);
            vel = rec.vel;
        }
        warm
    }
}

/// Whether a frame of strafe cosine `c / v` (speed `v`, ups) pushes straight back to within one step of
/// the replay's strafe angle: `c < 0` and `sin theta < q`, `q` = [`super::model::AngleControl::step_rad`]
/// (docs/physics.md section 1), so that its side moves the player by less than the game can resolve.
/// Such a frame is below [`FrameLaw::c_min`].
fn braking_straight_back(c: f64, v: f64, fl: &FrameLaw) -> bool {
    let step = v * fl.angle_control.step_rad();
    c < 0.0 && v * v - c * c < step * step
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

/// What a planner of `scene` starts from, as a solve computes it: the simulation, the lower bound and the
/// baseline (for the tests of the stages).
#[cfg(test)]
pub(super) fn planning_inputs(
    scene: &Scene,
) -> (Simulation<'_>, LowerBound, super::baseline::Baseline) {
    let sim = Simulation::new(scene).unwrap_or_else(|e| panic!("{e}"));
    let corridor = scene.corridor().unwrap_or_else(|e| panic!("{e}"));
    let bound = super::bound::lower_bound(scene, &corridor).unwrap_or_else(|e| panic!("{e}"));
    let base = super::baseline::baseline(&sim, scene, &bound, &Budget::unlimited());
    (sim, bound, base)
}

/// Runs `test` with a `fast` planner of `scene` seeded as a solve seeds it (its first clean greedy run),
/// with the baseline and the lower bound it was made from (for the tests of the stages).
#[cfg(test)]
pub(super) fn with_fast_planner<R>(
    scene: &Scene,
    test: impl FnOnce(&mut Planner, &super::baseline::Baseline, &LowerBound) -> R,
) -> R {
    let settings = super::search::SearchSettings::for_quality(super::Quality::Fast);
    with_planner(scene, &settings, test)
}

/// [`with_fast_planner`] with the given settings.
#[cfg(test)]
pub(super) fn with_planner<R>(
    scene: &Scene,
    settings: &super::search::SearchSettings,
    test: impl FnOnce(&mut Planner, &super::baseline::Baseline, &LowerBound) -> R,
) -> R {
    let (sim, bound, base) = planning_inputs(scene);
    let mut planner = Planner::new(
        scene,
        &sim,
        settings,
        &bound,
        base.seed(),
        Budget::unlimited(),
    );
    test(&mut planner, &base, &bound)
}

/// The default staircase (`scene::generate::Staircase`) of `corners` corners, for the tests of the stages.
#[cfg(test)]
pub(super) fn staircase_scene(corners: u32) -> Scene {
    use crate::scene::generate::{staircase, Staircase};
    let spec = Staircase {
        corners,
        ..Staircase::default()
    };
    staircase(&spec).unwrap_or_else(|e| panic!("{e}")).scene
}

/// `scenarios/hl-hairpin-aa100-100fps.toml`: the shipped hairpin (128-unit legs around a 64-unit
/// divider) at air acceleration 100, entered at 1200 ups.
#[cfg(test)]
pub(super) fn fast_hairpin_at_air_acceleration_100() -> Scene {
    let text = include_str!("../../scenarios/hl-hairpin-aa100-100fps.toml");
    Scene::from_toml_str(text, "test").unwrap_or_else(|e| panic!("{e}"))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::optimise::model::rollout;
    use crate::scene::generate::{generate, GeneratorSettings};

    #[test]
    fn a_warm_start_cancels_the_sides_of_frames_braking_straight_back_only() {
        // Generated scene 12 of seed 11: 1472 ups into a turn, so the capped greedy runs brake first.
        let g = generate(11, 12, &GeneratorSettings::ci_sized()).unwrap_or_else(|e| panic!("{e}"));
        let scene = g.scene;
        let (sim, bound, base) = planning_inputs(&scene);
        let budget = Budget::unlimited();
        let settings = SearchSettings::for_quality(crate::optimise::Quality::Fast);
        let (mut braked, mut braked_turning, mut held) = (0, 0, 0);
        for run in &base.clean {
            let planner = Planner::new(&scene, &sim, &settings, &bound, &run.trace, budget);
            let warm = planner.warm_start(&run.trace);
            let states = rollout(&planner.start, &warm, &planner.fl);
            let mut vel = scene.start.vel;
            for (k, (u, rec)) in warm.iter().zip(&run.trace.frames).enumerate() {
                let game = crate::optimise::model::frame_control_of(vel, &run.trace.controls[k]);
                if game.c < planner.fl.c_min(vel.length()) {
                    // Straight back, the side cancelled; braking into a corner while turning, the
                    // side kept.
                    if braking_straight_back(game.c, vel.length(), &planner.fl) {
                        braked += 1;
                        assert_eq!(u.sigma, 0.0, "frame {k}");
                    } else {
                        braked_turning += 1;
                        assert_eq!(u.sigma, game.sigma, "frame {k}");
                    }
                }
                // Each frame's `c` is the run's, no more than the plan's largest.
                let c_max = planner.fl.c_plan_max(vel.length());
                assert!((u.c - game.c.min(c_max)).abs() < 1e-9, "frame {k}");
                // A run that holds a speed cap is the warm start itself: the same path to within the
                // model's rounding. (One that accelerates at the kink for long, as between corners,
                // drifts by the half anglemod step the plan keeps under the kink.)
                if run.guide.speed_cap_ups.is_some() {
                    assert!((states[k].pos - rec.pos).length() < 0.5, "frame {k}");
                }
                vel = rec.vel;
            }
            held += usize::from(run.guide.speed_cap_ups.is_some());
        }
        assert!(braked > 0, "no clean run braked straight back");
        assert!(braked_turning > 0, "no clean run braked while turning");
        assert!(held > 0, "no clean run held a speed cap");
    }

    #[test]
    fn a_warm_start_braking_below_the_plans_range_while_turning_keeps_its_side_and_its_path() {
        // The same 1472-ups start, played turning left 12 frames at `cos theta = -0.97` (below
        // `c_min`, as a plan's frame can land after the game's quantised angles), then 8 at maximum
        // acceleration. With its sides cancelled there, the warm start ran units off the run.
        let g = generate(11, 12, &GeneratorSettings::ci_sized()).unwrap_or_else(|e| panic!("{e}"));
        let scene = g.scene;
        let (sim, bound, base) = planning_inputs(&scene);
        let settings = SearchSettings::for_quality(crate::optimise::Quality::Fast);
        let planner = Planner::new(
            &scene,
            &sim,
            &settings,
            &bound,
            base.seed(),
            Budget::unlimited(),
        );
        let fl = planner.fl;
        let braking_cos = -0.97;
        let mut speed = scene.start.vel.length();
        let mut planned = Vec::new();
        for k in 0..20 {
            let u = if k < 12 {
                FrameControl {
                    sigma: 1.0,
                    c: braking_cos * speed,
                }
            } else {
                FrameControl {
                    sigma: if k % 2 == 0 { 1.0 } else { -1.0 },
                    c: fl.c_plan_max(speed),
                }
            };
            assert!(k >= 12 || u.c < fl.c_min(speed));
            planned.push(u);
            speed = crate::optimise::model::frame(
                &ModelState {
                    pos: Vec2::ZERO,
                    speed,
                    heading: 0.0,
                },
                u,
                &fl,
                false,
            )
            .0
            .speed;
        }
        let mut player =
            crate::optimise::verify::PlanPlayer::new(&planner.start, &[], planned, fl, false);
        let run = sim.run(&mut player);
        assert!(
            run.frames.len() >= 20,
            "the run stopped at {}",
            run.frames.len()
        );
        let warm = planner.warm_start(&run);
        let states = rollout(&planner.start, &warm[..20], &fl);
        for (k, (x, rec)) in states.iter().zip(&run.frames).enumerate() {
            assert_eq!(rec.contacts, 0, "frame {k} touched a wall");
            assert!(
                (x.pos - rec.pos).length() < 1e-6,
                "frame {k}: {x:?} against {rec:?}"
            );
        }
        // The turn is real: a warm start with the braking frames' sides cancelled ends units away.
        let mut cancelled = warm.clone();
        cancelled[..12].iter_mut().for_each(|u| u.sigma = 0.0);
        let off = rollout(&planner.start, &cancelled[..20], &fl);
        assert!((off[19].pos - run.frames[19].pos).length() > 1.0);
    }
}
