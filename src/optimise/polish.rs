//! Rounding and polish: the relaxed plan's sides rounded to `+-1` ([`super::rounding`]), then `c` polished
//! by SCP with the sides fixed, at the final wall margin. Where rounding leaves the walls (the relaxed plan
//! ran closer than the rounded zigzag allows), the relaxed plan is re-solved at the same frame count with a
//! wider margin and rounded again.

use super::model::{rollout, FrameControl};
use super::planner::Planner;
use super::rounding::round_sides;
use super::scp::{model_crossing, ScpProblem, CLEAN_VIOLATION_UNITS};
use crate::budget::Stage;

/// Times the relaxed plan is re-solved with a wider margin when rounding leaves the walls.
const MARGIN_RETRIES: usize = 3;
/// Factor by which that margin grows each time.
const MARGIN_GROWTH: f64 = 2.5;

/// Exact-side plans from `relaxed` (solved at `relaxed_margin`, units), polished at `final_margin`: the
/// first that is clear and reaches the line, after the plans of each wider-margin retry that were not.
pub(super) fn rounded_and_polished(
    planner: &mut Planner,
    relaxed: &[FrameControl],
    relaxed_margin: f64,
    final_margin: f64,
) -> Vec<Vec<FrameControl>> {
    let fl = planner.fl;
    let mut candidates: Vec<Vec<FrameControl>> = Vec::new();
    let mut relaxed = relaxed.to_vec();
    let mut margin = relaxed_margin;
    for attempt in 0..=MARGIN_RETRIES {
        let Some(mut exact) = round_sides(&planner.start, &relaxed, &fl, &planner.budget) else {
            planner.timed_out = true;
            planner.note_cut(Stage::Rounding);
            break;
        };
        if planner.settings.polish_iters > 0 && !planner.timed_out {
            exact = polished(planner, exact, final_margin);
        }
        let st = rollout(&planner.start, &exact, &fl);
        let clean = planner.problem(final_margin, false, 1).violation(&st) <= CLEAN_VIOLATION_UNITS;
        let reaches = model_crossing(&planner.start, &st, planner.scene).is_some();
        candidates.push(exact);
        planner.note_cut(Stage::Rounding);
        if (clean && reaches) || attempt == MARGIN_RETRIES || planner.timed_out {
            break;
        }
        margin = (margin * MARGIN_GROWTH).max(final_margin * MARGIN_GROWTH);
        relaxed = resolved_wider(planner, relaxed, margin);
    }
    candidates
}

/// `exact` with its sides fixed and `c` polished at `margin`: first with every frame at most at the
/// maximum-acceleration turn, as the relaxed plan it was rounded from, then on from there with frames that
/// may turn less ([`super::model::FrameLaw::c_exact_max`]), which moves the sides' phase where they meet a
/// turn. The second stage starts from the first's plan, so it only keeps what improves on it; in the law's
/// first case there is no such frame and no second stage.
fn polished(planner: &mut Planner, exact: Vec<FrameControl>, margin: f64) -> Vec<FrameControl> {
    let iters = planner.settings.polish_iters;
    let pr = planner.problem(margin, false, 1);
    let exact = planner.stage(pr, exact, iters).0;
    if planner.timed_out || !planner.fl.exact_sides_turn_less() {
        return exact;
    }
    let pr = ScpProblem {
        turn_less: true,
        ..planner.problem(margin, false, 1)
    };
    planner.stage(pr, exact, iters).0
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
