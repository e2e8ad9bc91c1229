//! A plan whose replay scrapes a wall, planned on from its own replay. A plan that keeps its margin in the
//! model can still touch a wall once played on the game's quantised yaws: where the law's kink is in the
//! plan's way (air acceleration 10, docs/physics.md section 6), neither anglemod step around a frame's
//! wish direction gives its speed and turn together, and the replay drifts off the plan by hundredths to
//! tenths of a unit over a few hundred frames, more than the final margin. Widening the margin costs the
//! whole plan that much room. Here the replay is kept as it was played up to a while before its first
//! contact, and the rest of the plan is polished again from the replay's own state there: the drift so far
//! is then part of the start, and the rest has less of it to come.

use super::airborne::{kept_if_faster, time_to_beat, BestPlan};
use super::model::FrameControl;
use super::planner::Planner;
use super::polish::polished_again;
use super::scp::StageKind;
use super::verify::{quantised_replay, verified};
use crate::sim::Trace;

/// How long before a replay's first wall contact it is kept as played, seconds: the rest of the plan is
/// polished again from there, so the polish has that much run-up to move the path off the wall by the
/// drift (hundredths to tenths of a unit) without turning sharply.
const ANCHOR_BEFORE_CONTACT_S: f64 = 0.5;

/// Most times a plan is planned on from its replay: each time from a later contact, while the polished
/// rest still fails its replay and is planned to cross before the best plan. A bound on the work.
const MAX_ANCHORED_ROUNDS: usize = 3;

/// The earliest failed plan of `planner` ([`Planner::earliest_failed_plan`]), where it is planned to cross
/// before the best plan and keeps the walls in the model (a plan its polish left in a wall fails for that,
/// not for its replay's drift), planned on from its replay: the replay kept up to
/// [`ANCHOR_BEFORE_CONTACT_S`] before its first wall contact and the rest polished again at the final
/// margin from there, each polished plan quantised and verified, and kept if faster than `best` (and than
/// `greedy_s`). A rest that still fails is planned on from its own replay in turn, at most
/// [`MAX_ANCHORED_ROUNDS`] times. Whether the plan got faster.
pub(super) fn failed_plan_planned_on_from_its_replay(
    planner: &mut Planner,
    greedy_s: f64,
    best: &mut BestPlan,
) -> bool {
    let Some((planned, controls)) = planner.earliest_failed_plan.clone() else {
        return false;
    };
    if planned.time >= time_to_beat(best, greedy_s) || !planner.keeps_the_walls(&controls, 0.0) {
        return false;
    }
    // A failed plan is kept without its replay; played again, the replay is the same to the bit.
    let mut replay = quantised_replay(planner, controls.clone());
    let mut rest = controls;
    let mut on = planner.fork();
    let mut improved = false;
    for _ in 0..MAX_ANCHORED_ROUNDS {
        let Some((anchored, tail)) = anchored_before_contact(&on, &replay, rest) else {
            break;
        };
        planner.join(&on);
        on = anchored;
        let margin = on.settings.margin_units;
        let mut failed: Option<(Vec<FrameControl>, Trace)> = None;
        for plan in polished_again(&mut on, tail, margin, StageKind::Plain) {
            let planned_s = on.crossing_of(&plan).map(|c| c.time);
            let replayed = quantised_replay(&on, plan.clone());
            if let Some(t) = verified(&mut on, &replayed) {
                improved |= kept_if_faster(best, greedy_s, t, replayed);
            } else if failed.is_none()
                && planned_s.is_some_and(|p| p < time_to_beat(best, greedy_s))
                && on.keeps_the_walls(&plan, 0.0)
            {
                failed = Some((plan, replayed));
            }
        }
        match failed {
            Some(next) if !on.timed_out => (rest, replay) = next,
            _ => break,
        }
    }
    planner.join(&on);
    improved
}

/// Where `replay` (of `plan` from `planner`) touches a wall or a rule line, a fork of `planner` that plans
/// on from the replay [`ANCHOR_BEFORE_CONTACT_S`] before that frame, and the plan's frames from there.
/// `None` where the replay touches nothing (it failed elsewhere, or not at all) or was cut.
fn anchored_before_contact<'a>(
    planner: &Planner<'a>,
    replay: &Trace,
    plan: Vec<FrameControl>,
) -> Option<(Planner<'a>, Vec<FrameControl>)> {
    if replay.interrupted {
        return None;
    }
    let contact = first_touch(replay)?;
    // Frames are numbered from 1; the plan starts after the prefix.
    let contact_in_plan = usize::try_from(contact)
        .ok()?
        .checked_sub(1 + planner.prefix.len())?;
    let back = (ANCHOR_BEFORE_CONTACT_S / planner.fl.tau_s).round() as usize;
    let kept = contact_in_plan.saturating_sub(back);
    let rest = plan.get(kept..)?.to_vec();
    Some((planner.fork_after(replay, kept), rest))
}

/// The first frame of `replay` that touched a solid wall or crossed a rule line.
fn first_touch(replay: &Trace) -> Option<u64> {
    [replay.first_contact(), replay.first_rule_violation()]
        .into_iter()
        .flatten()
        .min()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::optimise::model::FrameControl;
    use crate::optimise::planner::{staircase_scene, with_fast_planner};

    #[test]
    fn a_plan_planned_on_from_its_replay_plays_the_replay_up_to_its_anchor() {
        with_fast_planner(&staircase_scene(1), |planner, base, _| {
            let seed = planner.warm_start(base.seed());
            let replay = quantised_replay(planner, seed.clone());
            let kept = 40;
            let on = planner.fork_after(&replay, kept);
            // The fork starts where the replay was after `kept` frames of the plan, those frames played as
            // they were.
            let played = planner.prefix.len() + kept;
            let there = &replay.frames[played - 1];
            assert_eq!(on.prefix.len(), played);
            assert!((on.start.pos - there.pos).length() < 1e-12);
            assert!((on.start.speed - there.vel.length()).abs() < 1e-12);
            assert!((on.start.heading - there.vel.angle()).abs() < 1e-12);
            // The same controls replay the same frames; the rest of the plan from the fork's start crosses
            // where the whole replay did, within the replay's own drift.
            let again = quantised_replay(&on, seed[kept..].to_vec());
            for (a, b) in again.frames.iter().zip(&replay.frames).take(played) {
                assert!((a.pos - b.pos).length() < 1e-12, "frame {}", a.frame);
            }
            let (Some(a), Some(b)) = (again.crossing, replay.crossing) else {
                panic!("a replay does not cross the line");
            };
            assert!((a.time - b.time).abs() < 1e-4, "{a:?} {b:?}");
        });
    }

    #[test]
    fn a_replay_that_touches_a_wall_is_kept_until_the_anchor_before_its_first_touch() {
        with_fast_planner(&staircase_scene(1), |planner, base, _| {
            // The seed's clean run, then strafing square to the velocity on one side, which circles into
            // the walls.
            let seed = planner.warm_start(base.seed());
            let circling: Vec<FrameControl> = seed
                .iter()
                .enumerate()
                .map(|(k, u)| {
                    if k < 150 {
                        *u
                    } else {
                        FrameControl { sigma: 1.0, c: 0.0 }
                    }
                })
                .collect();
            let replay = quantised_replay(planner, circling.clone());
            let Some(touch) = first_touch(&replay) else {
                panic!("the circling replay touches nothing");
            };
            let Some((on, rest)) = anchored_before_contact(planner, &replay, circling.clone())
            else {
                panic!("no anchor before the touch at frame {touch}");
            };
            let back = (ANCHOR_BEFORE_CONTACT_S / planner.fl.tau_s).round() as usize;
            let touch_in_plan = touch as usize - 1 - planner.prefix.len();
            assert!(
                touch_in_plan > back,
                "touch at {touch_in_plan}, back {back}"
            );
            let kept = touch_in_plan - back;
            assert_eq!(on.prefix.len(), planner.prefix.len() + kept);
            assert_eq!(rest, circling[kept..].to_vec());
            // The seed's clean run touches nothing: there is no anchor.
            let clean = quantised_replay(planner, seed.clone());
            assert!(first_touch(&clean).is_none());
            assert!(anchored_before_contact(planner, &clean, seed).is_none());
        });
    }
}
