//! Rounding and polish: the relaxed plan's sides rounded to `+-1` ([`super::rounding`]), then `c` polished
//! by SCP with the sides fixed, at the final wall margin. Where rounding leaves the walls (the relaxed plan
//! ran closer than the rounded zigzag allows), the relaxed plan is re-solved at the same frame count with a
//! wider margin and rounded again. The sides are rounded at several horizons
//! ([`super::rounding::ROUNDING_HORIZONS_S`]), each a choice of the sides' phase through the turns that
//! the beam's tracking cost cannot rank, and every rounding is polished (the distinct ones side by side,
//! on threads of their own) and verified: the search keeps the fastest.

use super::model::{frame, rollout, FrameControl, FrameLaw, ModelState};
use super::planner::Planner;
use super::rounding::{round_sides, ROUNDING_HORIZONS_S};
use super::scp::{model_crossing, ScpProblem, StageKind, CLEAN_VIOLATION_UNITS};
use crate::budget::Stage;

/// Times the planning line is re-solved with a wider margin when rounding leaves the walls.
pub(super) const MARGIN_RETRIES: usize = 3;
/// Factor by which that margin grows each time.
const MARGIN_GROWTH: f64 = 2.5;

/// An exact-side plan and how it was rounded.
pub(super) struct RoundedPlan {
    /// One control per frame, sides `+-1`.
    pub(super) controls: Vec<FrameControl>,
    /// Rounded with the first horizon of [`ROUNDING_HORIZONS_S`]: these plans alone decide whether wider
    /// margins are tried, so the other horizons only add candidates to what would be tried without them.
    pub(super) primary: bool,
}

/// A rounding's polished plans ([`polished`]).
#[derive(Clone, Debug, PartialEq)]
struct Polished {
    /// The plans that decide whether wider margins are tried.
    plans: Vec<Vec<FrameControl>>,
    /// A further candidate only: the plan that may turn less on the other side of the anglemod guard's
    /// band from the deciding one. Where it alone stays valid, the wider margins the deciding plans need
    /// are still tried: their plans there can be the faster.
    added: Option<Vec<FrameControl>>,
}

impl Polished {
    /// `plan` alone, as it is.
    fn only(plan: Vec<FrameControl>) -> Self {
        Polished {
            plans: vec![plan],
            added: None,
        }
    }
}

/// Exact-side plans from `relaxed` (solved at `relaxed_margin`, units), polished at `final_margin`, at
/// every rounding horizon: the plans of the first rounding whose first-horizon plans include one that is
/// clear and reaches the line, after those of each wider-margin retry that had none (at most
/// `margin_retries`).
pub(super) fn rounded_and_polished(
    planner: &mut Planner,
    relaxed: &[FrameControl],
    relaxed_margin: f64,
    final_margin: f64,
    margin_retries: usize,
) -> Vec<RoundedPlan> {
    let fl = planner.fl;
    let mut candidates: Vec<RoundedPlan> = Vec::new();
    let mut relaxed = relaxed.to_vec();
    let mut margin = relaxed_margin;
    for attempt in 0..=margin_retries {
        // The first horizon's plans decide whether a wider margin is needed; the others' are further
        // candidates, the sides' phase through the turns chosen otherwise.
        let roundings = distinct_roundings(planner, &relaxed);
        let polished = polished_side_by_side(planner, roundings, final_margin);
        let clear_and_reaching = polished.iter().any(|(primary, polished)| {
            *primary
                && polished.plans.iter().any(|plan| {
                    let st = rollout(&planner.start, plan, &fl);
                    planner.problem(final_margin, false, 1).violation(&st) <= CLEAN_VIOLATION_UNITS
                        && model_crossing(&planner.start, &st, planner.scene).is_some()
                })
        });
        candidates.extend(polished.into_iter().flat_map(|(primary, polished)| {
            let deciding = polished
                .plans
                .into_iter()
                .map(move |controls| RoundedPlan { controls, primary });
            let added = polished.added.map(|controls| RoundedPlan {
                controls,
                primary: false,
            });
            added.into_iter().chain(deciding)
        }));
        planner.note_cut(Stage::Rounding);
        if clear_and_reaching || attempt == margin_retries || planner.timed_out {
            break;
        }
        margin = (margin * MARGIN_GROWTH).max(final_margin * MARGIN_GROWTH);
        relaxed = resolved_wider(planner, relaxed, margin);
    }
    candidates
}

/// The sides of `relaxed` rounded at each horizon of [`ROUNDING_HORIZONS_S`] in order, each marked
/// whether it is the first horizon's; a later horizon's rounding equal to the first is left out (the same
/// sides polish to the same plans). Stops at the first horizon the budget cuts.
fn distinct_roundings(
    planner: &mut Planner,
    relaxed: &[FrameControl],
) -> Vec<(bool, Vec<FrameControl>)> {
    let mut roundings: Vec<(bool, Vec<FrameControl>)> = Vec::new();
    for (i, &horizon_s) in ROUNDING_HORIZONS_S.iter().enumerate() {
        let Some(sides) = rounded(planner, relaxed, horizon_s) else {
            break;
        };
        if roundings.first().is_some_and(|(_, first)| *first == sides) {
            continue;
        }
        roundings.push((i == 0, sides));
    }
    roundings
}

/// Each rounding polished at `final_margin` ([`polished_if_set`]), in the order given, with whether it
/// is the first horizon's. The roundings are independent, so all but the first are polished on threads
/// of their own beside the first ([`Planner::beside_forks`]): on a long run the polish is most of the
/// solve.
fn polished_side_by_side(
    planner: &mut Planner,
    roundings: Vec<(bool, Vec<FrameControl>)>,
    final_margin: f64,
) -> Vec<(bool, Polished)> {
    let mut roundings = roundings.into_iter();
    let Some((first_primary, first_sides)) = roundings.next() else {
        return Vec::new();
    };
    let others: Vec<_> = roundings
        .map(|(primary, sides)| {
            move |fork: &mut Planner| {
                let polished = polished_if_set(fork, sides, final_margin, StageKind::Plain);
                (primary, polished)
            }
        })
        .collect();
    let (first, others) = planner.beside_forks(others, |planner| {
        polished_if_set(planner, first_sides, final_margin, StageKind::Plain)
    });
    std::iter::once((first_primary, first))
        .chain(others)
        .collect()
}

/// The sides of `relaxed` rounded weighing heading errors over `horizon_s` seconds
/// ([`round_sides`]); `None` when the budget ran out while rounding.
fn rounded(
    planner: &mut Planner,
    relaxed: &[FrameControl],
    horizon_s: f64,
) -> Option<Vec<FrameControl>> {
    let fl = planner.fl;
    let exact = round_sides(&planner.start, relaxed, &fl, horizon_s, &planner.budget);
    if exact.is_none() {
        planner.timed_out = true;
        planner.note_cut(Stage::Rounding);
    }
    exact
}

/// `exact` polished at `final_margin` in stages of `kind` ([`polished`]), or as it is when the settings
/// polish nothing or the time is up.
fn polished_if_set(
    planner: &mut Planner,
    exact: Vec<FrameControl>,
    final_margin: f64,
    kind: StageKind,
) -> Polished {
    if planner.settings.polish_iters > 0 && !planner.timed_out {
        polished(planner, exact, final_margin, kind)
    } else {
        Polished::only(exact)
    }
}

/// `exact` with its sides fixed and `c` polished at `margin`, as up to three plans: first with every frame
/// at most at the maximum-acceleration turn, as the relaxed plan it was rounded from; then, on from that, with
/// frames that may turn less ([`super::model::FrameLaw::c_exact_max`]), which moves the sides' phase where
/// they meet a turn. The second plan's frames left within the anglemod guard's band around the law's kink
/// go down out of it ([`super::model::FrameLaw::under_the_guard`]): in the first case each such frame
/// then turns more than polished, in the second it gains a little less speed, and either way a few of
/// them put a plan along a wall into it, so the plan is polished once more with every frame kept to its
/// side of the band. The plan as polished before that move stays a candidate too (where its replay
/// follows it, it is the faster), given apart as the one that does not decide the margins
/// ([`Polished::added`]): in the first case the plan as polished, in the second the one out of the band.
/// The plans go on to be quantised and replayed, and the fastest valid one is kept; plans that come out
/// the same are given once.
fn polished(
    planner: &mut Planner,
    exact: Vec<FrameControl>,
    margin: f64,
    kind: StageKind,
) -> Polished {
    let iters = planner.settings.polish_iters;
    let pr = planner.problem(margin, false, 1);
    let rounded = exact.clone();
    let exact = planner.stage_of(pr, exact, iters, kind).0;
    // A rounding inside a wall that the first stage could not move at all (every step rejected) does not
    // move in the second either.
    let stuck = exact == rounded && !planner.keeps_the_walls(&exact, margin);
    if planner.timed_out || stuck {
        return Polished::only(exact);
    }
    let pr = ScpProblem {
        turn_less: true,
        anglemod_guard: false,
        ..planner.problem(margin, false, 1)
    };
    let turned = planner.stage_of(pr, exact.clone(), iters, kind).0;
    let fl = planner.fl;
    let mut guarded = under_the_guard(&planner.start, &turned, &fl);
    let moved = guarded != turned;
    if moved && !planner.timed_out {
        let pr = ScpProblem {
            turn_less: true,
            ..planner.problem(margin, false, 1)
        };
        let repaired = planner.stage_of(pr, guarded, iters, kind).0;
        guarded = under_the_guard(&planner.start, &repaired, &fl);
    }
    // In the first case every plan keeps under the guard and the plan out of the band is the line's own;
    // in the second the band is only the largest turn's, and the plan as polished is.
    let (own, added) = match (moved, fl.has_kink_guard()) {
        (false, _) => (turned, None),
        (true, true) => (guarded, Some(turned)),
        (true, false) => (turned, Some(guarded).filter(|_| !planner.timed_out)),
    };
    let mut plans = vec![own, exact];
    plans.dedup();
    let added = added.filter(|p| !plans.contains(p));
    Polished { plans, added }
}

/// An exact plan's controls polished again at `margin` from where they are, in stages of `kind`
/// ([`polished`]): every plan that comes of it, the deciding ones and the added one alike.
pub(super) fn polished_again(
    planner: &mut Planner,
    exact: Vec<FrameControl>,
    margin: f64,
    kind: StageKind,
) -> Vec<Vec<FrameControl>> {
    let Polished { plans, added } = polished_if_set(planner, exact, margin, kind);
    // A cut in these stages is the polish's, as in the rounding's own polish.
    planner.note_cut(Stage::Rounding);
    plans.into_iter().chain(added).collect()
}

/// `controls` with every frame's `c` out of the anglemod guard's band ([`FrameLaw::under_the_guard`]),
/// at the speeds of its own trajectory.
fn under_the_guard(
    start: &ModelState,
    controls: &[FrameControl],
    fl: &FrameLaw,
) -> Vec<FrameControl> {
    let mut x = *start;
    controls
        .iter()
        .map(|u| {
            let u = FrameControl {
                c: fl.under_the_guard(u.c, x.speed),
                ..*u
            };
            x = frame(&x, u, fl, false).0;
            u
        })
        .collect()
}

/// The relaxed plan re-solved at the wider `margin`, cut at its crossing, or one frame longer when it no
/// longer reaches the line cleanly.
fn resolved_wider(
    planner: &mut Planner,
    relaxed: Vec<FrameControl>,
    margin: f64,
) -> Vec<FrameControl> {
    let fl = planner.fl;
    let pr = planner.problem(margin, true, 1);
    let (c, _) = planner.stage(pr, relaxed, planner.settings.relaxed_iters);
    let st = rollout(&planner.start, &c, &fl);
    let clean = planner.problem(margin, true, 1).violation(&st) <= CLEAN_VIOLATION_UNITS;
    match model_crossing(&planner.start, &st, planner.scene) {
        Some(k) if clean => c[..k].to_vec(),
        _ => {
            let mut longer = c;
            let last = *longer.last().unwrap_or(&FrameControl {
                sigma: 0.0,
                c: fl.c_max(f64::INFINITY),
            });
            longer.push(last);
            longer
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::optimise::planner::{staircase_scene, with_fast_planner};
    use crate::optimise::rounding::round_sides_trimmed;
    use crate::optimise::verify::replay_drift;
    use crate::scene::generate::{generate, GeneratorSettings};
    use crate::scene::Scene;

    /// How far inside the guard's band a frame may end, as a share of the band's width: the band is
    /// worked out at the speed the stage's linearisation saw, and a step changes the speeds, so a frame
    /// kept at an edge ends a little past it (up to 1.04e-3 ups of a 0.052-ups band here). A frame the
    /// side rule did not hold sits anywhere in the band.
    const BAND_TOL_SHARE: f64 = 0.1;

    /// Each frame's guard band `(bottom, top)` at the speed it starts from along `controls`.
    fn bands(start: &ModelState, controls: &[FrameControl], fl: &FrameLaw) -> Vec<(f64, f64)> {
        let states = rollout(start, controls, fl);
        std::iter::once(start)
            .chain(&states)
            .take(controls.len())
            .map(|x| {
                fl.guard_band(x.speed)
                    .unwrap_or_else(|| panic!("no guard band at {} ups", x.speed))
            })
            .collect()
    }

    /// Frames of `controls` whose `c` lies inside the guard's band at their own speed, by more than
    /// `tol_share` of its width.
    fn in_the_band(
        start: &ModelState,
        controls: &[FrameControl],
        fl: &FrameLaw,
        tol_share: f64,
    ) -> Vec<usize> {
        let inside = |(u, (guard, top)): (&FrameControl, (f64, f64))| {
            let tol = tol_share * (top - guard);
            u.c > guard + tol && u.c < top - tol
        };
        controls
            .iter()
            .zip(bands(start, controls, fl))
            .enumerate()
            .filter(|&(_, frame_and_band)| inside(frame_and_band))
            .map(|(k, _)| k)
            .collect()
    }

    /// Runs `test` with a `fast` planner of generated scene 28 of seed 11 (250 fps, air acceleration 10:
    /// the law's first case, where the maximum-acceleration frame sits on the kink and plans keep half an
    /// anglemod step under it) and the warm start of its first clean greedy run, which runs along the
    /// walls.
    fn on_the_kink_guard_scene(test: impl FnOnce(&mut Planner, Vec<FrameControl>)) {
        let g = generate(11, 28, &GeneratorSettings::ci_sized()).unwrap_or_else(|e| panic!("{e}"));
        on_a_fast_planner(&g.scene, |planner, warm| {
            assert!(planner.fl.has_kink_guard());
            test(planner, warm);
        });
    }

    /// Runs `test` with a `fast` planner of `scene` and the warm start of its seed, its first clean greedy
    /// run ([`with_fast_planner`]).
    fn on_a_fast_planner(scene: &Scene, test: impl FnOnce(&mut Planner, Vec<FrameControl>)) {
        with_fast_planner(scene, |planner, base, _| {
            let warm = planner.warm_start(base.seed());
            test(planner, warm);
        });
    }

    #[test]
    fn frames_that_turn_less_keep_to_their_side_of_the_guard_band() {
        on_the_kink_guard_scene(|planner, warm| {
            let fl = planner.fl;
            let margin = planner.settings.margin_units;
            // The greedy run's sides out of the band, every fifth frame turning less, just above it.
            let mut x = planner.start;
            let mut plan = warm;
            for (k, u) in plan.iter_mut().enumerate() {
                if let Some((_, top)) = fl.guard_band(x.speed) {
                    u.c = if k % 5 == 0 {
                        top + 0.01
                    } else {
                        fl.under_the_guard(u.c, x.speed)
                    };
                }
                x = frame(&x, *u, &fl, false).0;
            }
            assert_eq!(
                in_the_band(&planner.start, &plan, &fl, BAND_TOL_SHARE),
                Vec::<usize>::new()
            );
            // A stage that may turn less and keeps to the band's sides: frames above it (every fifth) stay
            // above, the others under it.
            let pr = ScpProblem {
                turn_less: true,
                ..planner.problem(margin, false, 1)
            };
            let kept = planner.stage(pr, plan.clone(), 5).0;
            assert_ne!(kept, plan, "the stage did not move");
            assert_eq!(
                in_the_band(&planner.start, &kept, &fl, BAND_TOL_SHARE),
                Vec::<usize>::new()
            );
            for (k, (u, (guard, top))) in kept
                .iter()
                .zip(bands(&planner.start, &kept, &fl))
                .enumerate()
            {
                let tol = BAND_TOL_SHARE * (top - guard);
                let side_ok = if k % 5 == 0 {
                    u.c >= top - tol
                } else {
                    u.c <= guard + tol
                };
                assert!(
                    side_ok,
                    "frame {k}: c {} against the band ({guard}, {top})",
                    u.c
                );
            }
            // Free of the band, the same stage moves frames into it.
            let pr = ScpProblem {
                turn_less: true,
                anglemod_guard: false,
                ..planner.problem(margin, false, 1)
            };
            let free = planner.stage(pr, plan, 5).0;
            assert!(!in_the_band(&planner.start, &free, &fl, BAND_TOL_SHARE).is_empty());
        });
    }

    #[test]
    fn a_polished_plan_ends_clear_of_the_walls_and_out_of_the_guard_band() {
        // Polished, frames that turn less end in the band unless put back under it, and put back they
        // turn more, into the walls unless polished again (without that polish the plan that turns less
        // ends 0.45 units into them).
        on_the_kink_guard_scene(|planner, warm| {
            let (fl, margin) = (planner.fl, planner.settings.margin_units);
            let polished = polished(planner, warm, margin, StageKind::Plain);
            // The plan put out of the band and polished again and the first stage's, and apart from them
            // the one as first polished.
            assert_eq!(polished.plans.len(), 2, "no frame turned less");
            assert!(polished.added.is_some(), "no frame ended in the band");
            let turned = &polished.plans[0];
            let states = rollout(&planner.start, turned, &fl);
            let violation = planner.problem(margin, false, 1).violation(&states);
            assert!(
                violation <= CLEAN_VIOLATION_UNITS,
                "{violation} units into the walls"
            );
            assert_eq!(
                in_the_band(&planner.start, turned, &fl, 0.0),
                Vec::<usize>::new()
            );
        });
    }

    #[test]
    fn in_the_second_case_frames_of_the_largest_turn_end_out_of_the_kinks_band() {
        // The staircase at 100 fps with air acceleration 10: gamma1 = 32 > L = 30, the law's second
        // case, whose kink (c = -2 ups) is the frame of the largest turn. The relaxed line turns its
        // corner on such frames; rounded and polished, the plan that may turn less ends with none of them
        // inside the band the game's yaw cannot resolve, and with some at its bottom edge. The sides
        // are rounded at the relaxed `c`, untrimmed (`round_sides` trims them on the straights), so
        // that the frames on the kink are the relaxed line's own.
        on_a_fast_planner(&staircase_scene(1), |planner, warm| {
            let (fl, margin) = (planner.fl, planner.settings.margin_units);
            assert!(!fl.has_kink_guard());
            let relaxed = planner.stage(planner.problem(margin, true, 1), warm, 25).0;
            let horizon = ROUNDING_HORIZONS_S[0];
            let untrimmed =
                round_sides_trimmed(&planner.start, &relaxed, &fl, horizon, 0.0, &planner.budget);
            let Some(sides) = untrimmed else {
                panic!("no rounding")
            };
            let polished = polished(planner, sides, margin, StageKind::Plain);
            assert_eq!(polished.plans.len(), 2, "no frame turned less");
            let Some(turned) = &polished.added else {
                panic!("no frame ended in the band")
            };
            assert_eq!(
                in_the_band(&planner.start, turned, &fl, 0.0),
                Vec::<usize>::new()
            );
            let at_the_bottom = turned
                .iter()
                .zip(bands(&planner.start, turned, &fl))
                .filter(|(u, (bottom, _))| (u.c - bottom).abs() < 1e-9)
                .count();
            assert!(at_the_bottom > 0, "no frame of the largest turn");
            let states = rollout(&planner.start, turned, &fl);
            let violation = planner.problem(margin, false, 1).violation(&states);
            assert!(
                violation <= CLEAN_VIOLATION_UNITS,
                "{violation} units into the walls"
            );
            // Replayed on the game's yaws, the plan out of the band keeps to its speed and path; the one as
            // first polished, whose frames of the largest turn sit on the kink, falls behind (here 0.025 ups
            // and 0.028 units against 0.006 and 0.009).
            let (guarded, free) = (
                replay_drift(planner, turned),
                replay_drift(planner, &polished.plans[0]),
            );
            assert!(
                2.0 * guarded.0 < free.0 && 2.0 * guarded.1 < free.1,
                "drift out of the band {guarded:?}, on the kink {free:?} (units, ups)"
            );
        });
    }

    #[test]
    fn roundings_polished_side_by_side_are_those_polished_one_after_the_other() {
        on_a_fast_planner(&staircase_scene(2), |planner, warm| {
            let margin = planner.settings.margin_units;
            let relaxed = planner.stage(planner.problem(margin, true, 1), warm, 25).0;
            let roundings = distinct_roundings(planner, &relaxed);
            assert_eq!(roundings.len(), 2, "the horizons round the line alike");
            let mut one_by_one = planner.fork();
            let expected: Vec<(bool, Polished)> = roundings
                .iter()
                .map(|(primary, sides)| {
                    let plans =
                        polished_if_set(&mut one_by_one, sides.clone(), margin, StageKind::Plain);
                    (*primary, plans)
                })
                .collect();
            let before = planner.stats.subproblems;
            let side_by_side = polished_side_by_side(planner, roundings, margin);
            // The same plans in the same order (the first horizon's first), and every thread's work counted.
            assert!(side_by_side == expected);
            assert_eq!(
                planner.stats.subproblems - before,
                one_by_one.stats.subproblems
            );
        });
    }
}
