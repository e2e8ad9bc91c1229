//! A greedy run that slides along a solid wall, planned on from after its wall contacts.
//!
//! The planning model has no collisions, so the relaxed problem holds only runs clear of the walls. On
//! solid walls a run that slides along one can be ahead of all of them: a wall takes the speed across it
//! off at once, where braking takes a corner's length; and a fast start before a sharp corner of a narrow
//! corridor may have no line clear of the walls at all. The solve's answer is then the greedy run as it
//! was played. Here that run is kept as played up to where it is clear of the walls again after a
//! contact, and the rest is solved as a scene of its own, from the run's state there, by the whole
//! solve's stages. The two played one after the other are the plan where they are valid in `f64` and
//! engine-exact and cross sooner. The rest is planned on from after the run's last contact (its own rest
//! clear of the walls, a start), then from after its first; where that rest's answer is again its own
//! greedy run sliding along a wall, from after that run's first contact in turn, at most
//! [`MAX_CONTACT_RESTARTS`] times.

use super::model::FrameLaw;
use super::search::{Outcome, SearchStats, SearchStatus};
use super::verify::time_of;
use crate::budget::Budget;
use crate::error::Result;
use crate::physics::{Control, PlayerState};
use crate::scene::Scene;
use crate::sim::{Playback, Simulation, Trace};

/// Most times a solve plans on from a first wall contact: the greedy run's, then each from the first
/// contact of the run the rest before it returned. A bound on the work, where the rests slide again at
/// every corner (docs/design.md, "A greedy answer planned on from its wall contacts").
pub(super) const MAX_CONTACT_RESTARTS: usize = 3;

/// The plan's source when it was planned on from a greedy run's wall contact.
pub(super) const AFTER_CONTACT_SOURCE: &str = "greedy to a wall contact, then optimised";

/// Which of a run's wall contacts the rest is planned on from.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum After {
    /// The first: the rest may slide along a wall again, and is planned on from its own first contact in
    /// turn.
    FirstContact,
    /// The last: the rest is clear of the walls, the run's own rest a start for it.
    LastContact,
}

/// The frames of `run` kept as played before the rest is planned on: up to the first frame after its
/// first or last wall contact (`after`) at which the hull is `margin_units` off the walls. `None` where
/// it touches no wall, or is not that far off them again before the frame it crosses the line in.
pub(super) fn frames_kept_before_planning_on(
    run: &Trace,
    margin_units: f64,
    after: After,
) -> Option<usize> {
    let mut touched = run.frames.iter().map(|f| f.contacts > 0);
    let contact = match after {
        After::FirstContact => touched.position(|t| t)?,
        After::LastContact => touched.rposition(|t| t)?,
    };
    let clear = run.frames[contact + 1..]
        .iter()
        .position(|f| f.clearance >= margin_units)?;
    // Frame records are numbered from 1: the record at index `i` is the state after `i + 1` frames.
    let kept = contact + 1 + clear + 1;
    (kept < run.frames.len()).then_some(kept)
}

/// `scene` started from the state `run` reached after its first `frames` frames (at least one), with
/// the frames left of its cap.
pub(super) fn scene_after(scene: &Scene, run: &Trace, frames: usize) -> Scene {
    let there = &run.frames[frames - 1];
    Scene {
        start: PlayerState {
            pos: there.pos,
            vel: there.vel,
            on_ground: there.on_ground,
            ducked: there.ducked,
            ..scene.start
        },
        max_frames: scene.max_frames.saturating_sub(frames as u64),
        ..scene.clone()
    }
}

/// `outcome`, the solve of the airborne `scene`, planned on from after its greedy run's wall contacts
/// where it is that greedy run (see the module documentation). `solve_rest` solves a rest's scene with
/// the solve's own stages, told how many frames from the whole scene's start are kept before it. A rest
/// starts the planning margin of `scene`'s law at `final_margin_units` off the walls. Stops when `budget`
/// runs out.
pub(super) fn planned_on_after_wall_contacts(
    scene: &Scene,
    final_margin_units: f64,
    outcome: Outcome,
    budget: &Budget,
    solve_rest: &mut dyn FnMut(&Scene, usize) -> Result<Outcome>,
) -> Outcome {
    let sliding = outcome.trace.first_contact().is_some();
    if outcome.source != "greedy" || !outcome.trace.feasible() || !sliding {
        return outcome;
    }
    let Ok(sim) = Simulation::new(scene) else {
        return outcome;
    };
    let greedy = outcome.trace.clone();
    let mut planning_on = PlanningOn {
        sim: &sim,
        margin_units: FrameLaw::of(&scene.vars).planning_margin(final_margin_units),
        budget,
        solve_rest,
        best: outcome,
        stats: SearchStats::default(),
    };
    let last =
        frames_kept_before_planning_on(&greedy, planning_on.margin_units, After::LastContact);
    if let Some(kept) = last {
        planning_on.rest_planned(&scene_after(scene, &greedy, kept), &greedy.controls[..kept]);
    }
    planning_on.planned_on_from_each_first_contact(scene, greedy, last);
    let PlanningOn {
        mut best, stats, ..
    } = planning_on;
    best.stats.add(&stats);
    best
}

/// What planning on from wall contacts shares: the scene's simulation, the rests' margin and solve, the
/// budget, the best outcome so far and the rests' work.
struct PlanningOn<'a, 's> {
    sim: &'a Simulation<'s>,
    margin_units: f64,
    budget: &'a Budget<'a>,
    solve_rest: &'a mut dyn FnMut(&Scene, usize) -> Result<Outcome>,
    best: Outcome,
    stats: SearchStats,
}

impl PlanningOn<'_, '_> {
    /// `greedy`, the answer of `scene`, planned on from after its first contact, then each rest's
    /// greedy answer from after its own first contact in turn, at most [`MAX_CONTACT_RESTARTS`] times.
    /// `planned_from_the_last` is the frames kept where the rest after its last contact was solved.
    fn planned_on_from_each_first_contact(
        &mut self,
        scene: &Scene,
        greedy: Trace,
        planned_from_the_last: Option<usize>,
    ) {
        let mut played: Vec<Control> = Vec::new();
        let mut rest_scene = scene.clone();
        let mut run = greedy;
        for _ in 0..MAX_CONTACT_RESTARTS {
            let Some(kept) =
                frames_kept_before_planning_on(&run, self.margin_units, After::FirstContact)
            else {
                break;
            };
            // After a single contact the first is the last, planned on from already.
            if played.is_empty() && planned_from_the_last == Some(kept) {
                break;
            }
            played.extend_from_slice(&run.controls[..kept]);
            rest_scene = scene_after(&rest_scene, &run, kept);
            let Some(rest) = self.rest_planned(&rest_scene, &played) else {
                break;
            };
            if rest.source != "greedy" {
                break;
            }
            run = rest.trace;
        }
    }

    /// The rest `rest_scene`, which starts where the controls `played` (from the whole scene's start)
    /// leave the player, solved; the two together kept as the best where they are faster. The rest's
    /// outcome; `None` where its solve failed or the budget ran out.
    fn rest_planned(&mut self, rest_scene: &Scene, played: &[Control]) -> Option<Outcome> {
        if self.budget.expired() {
            return None;
        }
        let rest = (self.solve_rest)(rest_scene, played.len()).ok()?;
        self.stats.add(&rest.stats);
        let controls: Vec<Control> = played.iter().chain(&rest.controls).copied().collect();
        if let Some(spliced) =
            spliced_if_faster(self.sim, &self.best, controls, &rest.status, self.budget)
        {
            self.best = spliced;
        }
        Some(rest)
    }
}

/// The outcome of playing `controls` through `sim`'s scene from its start, where that is valid in `f64`
/// and engine-exact and crosses before `best`; its status the rest's where a budget cut it, else its gap
/// to the bound.
fn spliced_if_faster(
    sim: &Simulation,
    best: &Outcome,
    controls: Vec<Control>,
    rest_status: &SearchStatus,
    budget: &Budget,
) -> Option<Outcome> {
    let trace = sim.run_within(
        &mut Playback {
            controls,
            label: AFTER_CONTACT_SOURCE.to_string(),
        },
        budget,
    );
    let t = time_of(&trace);
    if t >= time_of(&best.trace) {
        return None;
    }
    let engine_exact = sim.run_engine_exact_within(&trace.controls, budget);
    if !engine_exact.feasible() {
        return None;
    }
    let status = match rest_status.stopped_in() {
        Some(_) => rest_status.clone(),
        None => SearchStatus::Converged {
            gap: best.bound.gap(t),
        },
    };
    // The controls as played: a playback repeats its last control past its end.
    Some(Outcome {
        controls: trace.controls.clone(),
        trace,
        engine_exact,
        status,
        source: AFTER_CONTACT_SOURCE,
        ..best.clone()
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::physics::Vec2;
    use crate::sim::FrameRecord;

    /// A run of `clearances.len()` frames with a wall contact on the frames of `contacts` (1-based) and
    /// the given clearance after each frame.
    fn run_with(clearances: &[f64], contacts: &[u64]) -> Trace {
        let mut t = Trace::new("test".into(), &PlayerState::default(), 10.0);
        for (i, &clearance) in clearances.iter().enumerate() {
            let frame = i as u64 + 1;
            let record = FrameRecord {
                frame,
                clearance,
                contacts: u32::from(contacts.contains(&frame)),
                ..t.frames.last().copied().unwrap_or(t.start)
            };
            t.push(
                record,
                Control::strafe(Vec2::new(1.0, 0.0), 0.0, 0.0, 0.0, 0.0),
            );
        }
        t
    }

    #[test]
    fn the_run_is_kept_to_where_it_is_clear_of_the_walls_after_its_first_or_last_contact() {
        let (first, last) = (After::FirstContact, After::LastContact);
        let clearances = [5.0, 0.0, 0.0, 0.1, 0.2, 0.5, 0.0, 0.3, 1.0, 2.0, 3.0];
        // The last contact is frame 7; the first frame after it 0.4 units off the walls is frame 9.
        assert_eq!(
            frames_kept_before_planning_on(&run_with(&clearances, &[2, 3, 7]), 0.4, last),
            Some(9)
        );
        // A frame after the contact already that far off: kept to it.
        assert_eq!(
            frames_kept_before_planning_on(&run_with(&clearances, &[2, 3, 7]), 0.3, last),
            Some(8)
        );
        // No contact: nothing to plan on from. Never that far off again before the crossing frame (the
        // last): nothing either.
        assert_eq!(
            frames_kept_before_planning_on(&run_with(&clearances, &[]), 0.4, last),
            None
        );
        assert_eq!(
            frames_kept_before_planning_on(&run_with(&clearances, &[2, 3, 7]), 3.0, last),
            None
        );
        // After the first contact (frames 2 and 3 touch): kept to frame 5, the first 0.2 units off.
        assert_eq!(
            frames_kept_before_planning_on(&run_with(&clearances, &[2, 3, 7]), 0.2, first),
            Some(5)
        );
    }
}
