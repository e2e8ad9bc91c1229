//! The airborne solve, stages 2 to 4 of [`super::search`], in this order:
//!
//! 1. the relaxed line ([`super::relaxed`]) at the planning margin ([`planning_margin`]), which leaves
//!    room for the zigzag of rounded sides; the count search over it is the search's globalisation;
//! 2. the certificate: the relaxed optimum from that line and from the other clean greedy runs, the
//!    greedy starts on a second thread, beside everything else (they need nothing of the relaxed line);
//! 3. the line rounded, polished, quantised and verified ([`super::polish`], [`super::verify`]): the
//!    fastest valid exact plan is kept;
//! 4. that plan polished on from its own controls while it gets faster ([`best_plan_polished_on`]),
//!    after a faster plan whose replay scraped a wall was planned on from that replay
//!    ([`super::anchored`]) or polished wider ([`failed_plan_polished_wider`]);
//! 5. where it still crosses in a later frame than the certificate's fastest line, by more than the
//!    estimates say a replayable plan loses, that line refined at the final margin and rounded again
//!    ([`certificate_line_rounded_at_the_final_margin`]);
//! 6. where the settings ask for it (`balanced` and `exact`), polished on again at smaller wall margins
//!    ([`plan_polished_finely`], run by [`super::search`] after the rest).
//!
//! Where the relaxed stage finds no line from the seed, the certificate's greedy starts' lines are the
//! ones rounded.

use super::anchored::failed_plan_planned_on_from_its_replay;
use super::baseline::{is_clean, Baseline};
use super::model::{rollout, FrameControl};
use super::planner::Planner;
use super::polish::{polished_again, rounded_and_polished, MARGIN_RETRIES};
use super::relaxed::{
    count_search, guard_frames, relaxed_plan, zigzag_frames, Certifier, CountSearch, Descent,
    Relaxation, StartKind, CERTIFICATE_MARGIN_UNITS,
};
use super::scp::StageKind;
use super::search::{seconds_since, FinePolish, Progress, SearchSettings};
use super::verify::quantised_and_verified;
use crate::sim::{Crossing, Trace};
use std::time::Instant;

/// Least gain of a round of the final polish, in frames, for another round to follow
/// ([`best_plan_polished_on`]): a round over a few thousand frames costs seconds (docs/design.md, "The
/// final polish").
const FINAL_POLISH_MIN_GAIN_FRAMES: f64 = 0.01;

/// Steps in which a certificate's line is widened from the certificate's margin to the planning margin
/// where the count search cannot reach the finish line from it at once ([`widened_in_steps`]).
const WIDENING_STEPS: usize = 4;

/// Most rounds of a certificate's line faster than the plan, each from the plan of the one before
/// ([`certificate_lines_rounded_while_ahead`]): a bound on the work, not tuned (the one scene known to
/// take a second round stops after its third, its certificate no faster).
const CERTIFICATE_LINE_ROUNDS: usize = 4;

/// Most rounds of the certificate's fastest line refined at the final margin
/// ([`certificate_line_rounded_at_the_final_margin`]), each while the plan is still behind it in a
/// later frame: a bound on the work, not tuned.
const FINAL_MARGIN_ROUNDS: usize = 3;

/// Final wall margins tried, as multiples of the setting, until a plan stays valid.
const FINAL_MARGIN_FACTORS: [f64; 3] = [1.0, 3.0, 10.0];

/// The wall margin the relaxed line is planned at, units ([`super::model::FrameLaw::planning_margin`]
/// of `planner`'s frame law and final margin).
pub(super) fn planning_margin(planner: &Planner) -> f64 {
    planner.fl.planning_margin(planner.settings.margin_units)
}

/// A relaxed line to round, and the margin it was solved at.
struct Source {
    line: Vec<FrameControl>,
    margin: f64,
    widening: Widening,
}

/// What is widened where none of a line's plans rounded at the first horizon stays valid.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Widening {
    /// The final margin ([`FINAL_MARGIN_FACTORS`]): a certificate's line beside a valid plan. Its plans
    /// only add candidates too, but a plan valid in the model can scrape a wall once its yaws are
    /// quantised, and a wider final margin is a polish more; re-solving the line wider is a relaxed stage
    /// and a polish over every frame for each margin, and on long runs took most of the solve.
    FinalMargin,
    /// The final margin and, where a rounding leaves the walls, the line re-solved wider
    /// ([`MARGIN_RETRIES`]): the line a plan must come from (the relaxed stage's at the planning margin,
    /// or a certificate's while there is no plan).
    FinalMarginAndLine,
}

/// The fastest valid exact plan so far: its crossing time (seconds) and its f64 trace (the plan as
/// played: its controls are the trace's).
pub(super) type BestPlan = Option<(f64, Trace)>;

/// What the airborne stages found.
pub(super) struct AirbornePlan {
    /// The fastest valid exact plan faster than greedy.
    pub(super) best: BestPlan,
    /// The certificate.
    pub(super) certifier: Certifier,
    /// Whether a relaxed line was found at all: the relaxed stage's, or where it found none, one of the
    /// certificate's greedy starts'.
    pub(super) relaxed_found: bool,
}

/// Stages 2 to 4 (see the module documentation): `warm` is the seed in planning controls, crossing near
/// frame `n`; no plan crosses before frame `lo`; a plan is kept only if it is faster than `greedy_s`.
/// Each stage's seconds go to `planner.seconds`.
pub(super) fn plan_airborne(
    planner: &mut Planner,
    base: &Baseline,
    warm: Vec<FrameControl>,
    n: usize,
    lo: usize,
    greedy_s: f64,
    progress: &mut dyn FnMut(Progress),
) -> AirbornePlan {
    let margin = planning_margin(planner);
    let first_started = Instant::now();
    let greedy_starts = certificate_greedy_starts(planner, base);
    let planning = Relaxation::planning(margin);
    let side = move |fork: &mut Planner| certified_greedy_starts(fork, greedy_starts, planning, lo);
    let seed = Seed {
        warm,
        n,
        greedy: greedy_beside_the_seed(base),
    };
    let (mine, side_certifiers) = beside_certificate_starts(planner, vec![side], |planner| {
        lines_and_plans(planner, seed, lo, planning, greedy_s, progress)
    });
    // The relaxed line and the waits are clocked on their own, inside.
    planner.seconds.first_plans = seconds_since(first_started)
        - planner.seconds.relaxed_line
        - planner.seconds.certificate_wait;
    // Where the relaxed stage found no line from the seed, a line the certificate's greedy starts reached
    // is the one to round (the certificate's fastest, as another optimum crossing before any frame).
    let relaxed_found = mine.is_some();
    let (mut certifier, mut best, relaxed_line_frame) =
        mine.unwrap_or((Certifier::default(), None, u64::MAX));
    for side_certifier in side_certifiers {
        certifier.absorb(side_certifier);
    }
    if !relaxed_found && certifier.best().is_none() {
        return AirbornePlan {
            best,
            certifier,
            relaxed_found,
        };
    }
    let terms = PlanTerms {
        lo,
        planning_margin: margin,
        greedy_s,
    };
    planner.clocked(
        |s| &mut s.certificate_lines,
        |planner| {
            let frame = relaxed_line_frame;
            certificate_lines_rounded(planner, &mut certifier, frame, terms, progress, &mut best);
        },
    );
    planner.clocked(
        |s| &mut s.polish_on,
        |planner| plan_polished_on(planner, &mut certifier, terms, progress, &mut best),
    );
    planner.clocked(
        |s| &mut s.final_margin_round,
        |planner| {
            certificate_line_rounded_at_the_final_margin(
                planner,
                &mut certifier,
                terms,
                progress,
                &mut best,
            );
            if failed_plan_planned_on_from_its_replay(planner, terms.greedy_s, &mut best) {
                polished_plan_as_certificate_start(
                    planner,
                    &mut certifier,
                    terms,
                    progress,
                    &mut best,
                );
            }
        },
    );
    AirbornePlan {
        best,
        certifier,
        relaxed_found: true,
    }
}

/// The lines of the certificate's problem rounded too: another optimum than the relaxed stage's (a
/// greedy start's, faster by more than the stages can tell apart, or any start's crossing a frame or
/// more before the fastest plan, or the relaxed line where there is no plan), and the fastest greedy
/// start's line of the plan's frame (the rounding's outcome within a frame depends on its line:
/// [`Certifier::fastest_greedy_line`]). One is rounded beside the plan as a start: another optimum's
/// where there is one, the greedy start's line first. `relaxed_line_frame` is the frame the relaxed line
/// crosses in, the frame to beat where there is no plan.
fn certificate_lines_rounded(
    planner: &mut Planner,
    certifier: &mut Certifier,
    relaxed_line_frame: u64,
    terms: PlanTerms,
    progress: &mut dyn FnMut(Progress),
    best: &mut BestPlan,
) {
    let same_optimum_s = certifier
        .best()
        .map_or(0.0, |p| same_optimum_s(planner, &p.controls));
    let frame_to_beat = best
        .as_ref()
        .and_then(|(_, trace)| trace.crossing.map(|c| c.frames))
        .unwrap_or(relaxed_line_frame);
    let another = certifier
        .another_optimum(same_optimum_s, frame_to_beat)
        .map(|p| (p.start_index, p.controls.clone()));
    let greedy_line = certifier
        .fastest_greedy_line(frame_to_beat, another.as_ref().map(|a| a.0))
        .map(|p| p.controls.clone());
    let (beside, first) = match another {
        Some((_, line)) => (Some(line), greedy_line),
        None => (greedy_line, None),
    };
    if let Some(line) = first {
        plans_of_certificate_line(planner, line, terms, progress, best);
    }
    // Descending from the plan, the certificate's problem can find a faster line than the relaxed stage
    // did (it stopped short of its optimum, or in a slower basin): that line is rounded too, and the plan
    // that comes of it is a start again, so that the certificate stays no slower than the plan; a faster
    // line from that start is rounded in turn while the plan gains and is a frame or more behind it.
    let faster_line = match beside {
        Some(line) => {
            another_line_beside_the_plan_as_start(planner, certifier, line, terms, progress, best)
        }
        None => plan_as_certificate_start(planner, certifier, best, terms.lo, progress),
    };
    if let Some(line) = faster_line {
        certificate_lines_rounded_while_ahead(planner, certifier, line, terms, progress, best);
    }
}

/// The plan polished on: a plan whose replay failed polished wider ([`failed_plan_polished_wider`]), then
/// the fastest plan from its own controls ([`best_plan_polished_on`]); each that made the plan faster
/// starts the certificate again ([`polished_plan_as_certificate_start`]).
fn plan_polished_on(
    planner: &mut Planner,
    certifier: &mut Certifier,
    terms: PlanTerms,
    progress: &mut dyn FnMut(Progress),
    best: &mut BestPlan,
) {
    let greedy_s = terms.greedy_s;
    if failed_plan_planned_on_from_its_replay(planner, greedy_s, best) {
        polished_plan_as_certificate_start(planner, certifier, terms, progress, best);
    }
    if failed_plan_polished_wider(planner, greedy_s, best) {
        polished_plan_as_certificate_start(planner, certifier, terms, progress, best);
    }
    if best_plan_polished_on(planner, greedy_s, best) {
        polished_plan_as_certificate_start(planner, certifier, terms, progress, best);
    }
}

/// `line`, a line of the certificate's problem faster than the plan, rounded; the plan that comes of it
/// is the certificate's start again, and where the line descended from it is the certificate's fastest,
/// a frame or more ahead of the plan, and the round made the plan faster, that line is rounded in turn,
/// for at most [`CERTIFICATE_LINE_ROUNDS`] rounds. A line rounded into a plan a few frames behind it can
/// lead, from that plan, to a faster line still: the plan starts the certificate nearer the optimum
/// than the line it came from did (docs/design.md, "The certificate's lines rounded while ahead").
fn certificate_lines_rounded_while_ahead(
    planner: &mut Planner,
    certifier: &mut Certifier,
    line: Vec<FrameControl>,
    terms: PlanTerms,
    progress: &mut dyn FnMut(Progress),
    best: &mut BestPlan,
) {
    let frame_s = planner.fl.tau_s;
    let mut next = Some(line);
    for _ in 0..CERTIFICATE_LINE_ROUNDS {
        let Some(line) = next.take() else {
            break;
        };
        let before_s = best.as_ref().map(|b| b.0);
        plans_of_certificate_line(planner, line, terms, progress, best);
        let found = plan_as_certificate_start(planner, certifier, best, terms.lo, progress);
        let plan_s = best.as_ref().map(|b| b.0);
        if worth_another_round(before_s, plan_s, certifier.best_time(), frame_s) {
            next = found;
        }
    }
}

/// Whether a round of [`certificate_lines_rounded_while_ahead`] that took the plan from `before_s` to
/// `plan_s` (seconds; `None`: no plan) is followed by another: the plan got faster, and the
/// certificate's fastest line (`certificate_s`) crosses at least a frame (`frame_s`) before it.
fn worth_another_round(
    before_s: Option<f64>,
    plan_s: Option<f64>,
    certificate_s: Option<f64>,
    frame_s: f64,
) -> bool {
    let Some(plan_s) = plan_s else {
        return false;
    };
    let faster = before_s.is_none_or(|b| plan_s < b);
    faster && a_frame_ahead(certificate_s, plan_s, frame_s)
}

/// Whether the certificate's fastest line (`certificate_s`, seconds; `None`: no line) crosses at least a
/// frame (`frame_s`) before the plan (`plan_s`).
fn a_frame_ahead(certificate_s: Option<f64>, plan_s: f64, frame_s: f64) -> bool {
    certificate_s.is_some_and(|c| c + frame_s <= plan_s)
}

/// A plan a polish made faster, the certificate's start again ([`plan_as_certificate_start`]); where the
/// line the certificate descends to from it crosses a frame or more before the plan, that line is
/// rounded in turn, and so on while ahead ([`certificate_lines_rounded_while_ahead`]). A faster line
/// within the plan's frame is left: closing less than a frame is the polishes' part.
fn polished_plan_as_certificate_start(
    planner: &mut Planner,
    certifier: &mut Certifier,
    terms: PlanTerms,
    progress: &mut dyn FnMut(Progress),
    best: &mut BestPlan,
) {
    let Some(line) = plan_as_certificate_start(planner, certifier, best, terms.lo, progress) else {
        return;
    };
    // A line came back, so there is a plan: the certificate started from it.
    let frame_s = planner.fl.tau_s;
    if best
        .as_ref()
        .is_some_and(|b| a_frame_ahead(certifier.best_time(), b.0, frame_s))
    {
        certificate_lines_rounded_while_ahead(planner, certifier, line, terms, progress, best);
    }
}

/// Where the plan, polished, still crosses in a later frame than the certificate's fastest line, and is
/// behind it by more than a replayable plan is estimated to lose against it ([`behind_beyond_estimates`]),
/// that line refined at the final margin, the margin the plan itself keeps, then rounded, polished and
/// verified; where that makes the plan faster, the plan is polished on and is the certificate's start
/// again (with the rounds while a frame ahead), and the round is taken again, at most
/// [`FINAL_MARGIN_ROUNDS`] times. Every other line is refined at the planning margin, `tau max(L,
/// gamma1)` off the walls so that any rounding of its sides stays clear; where a line presses on the walls
/// through braking turns, that width costs it a frame or two, which the polishes at the final margin do
/// not win back (docs/design.md, "The certificate's line rounded at the final margin"). A plan rounded
/// from the line at the final margin that scrapes a wall fails its replay, and the final margin widens
/// as for every certificate's line.
fn certificate_line_rounded_at_the_final_margin(
    planner: &mut Planner,
    certifier: &mut Certifier,
    terms: PlanTerms,
    progress: &mut dyn FnMut(Progress),
    best: &mut BestPlan,
) {
    let final_margin = planner.settings.margin_units;
    for _ in 0..FINAL_MARGIN_ROUNDS {
        if planner.timed_out {
            break;
        }
        let Some(line) = line_the_plan_is_behind(planner, certifier, best) else {
            break;
        };
        let before_s = best.as_ref().map(|b| b.0);
        let Some(source) = refined(
            planner,
            progress,
            line,
            terms.lo,
            final_margin,
            Widening::FinalMargin,
        ) else {
            break;
        };
        exact_plans(planner, &source, terms.greedy_s, best);
        if !faster_than_before(best, before_s) {
            break;
        }
        best_plan_polished_on(planner, terms.greedy_s, best);
        polished_plan_as_certificate_start(planner, certifier, terms, progress, best);
    }
}

/// Whether `best` holds a plan faster than `before_s` (seconds; `None`: there was no plan).
fn faster_than_before(best: &BestPlan, before_s: Option<f64>) -> bool {
    best.as_ref()
        .is_some_and(|b| before_s.is_none_or(|t| b.0 < t))
}

/// The certificate's fastest line, where the plan crosses in a later frame and behind it by more than
/// the zigzag and guard estimates along it ([`behind_beyond_estimates`]).
fn line_the_plan_is_behind(
    planner: &Planner,
    certifier: &Certifier,
    best: &BestPlan,
) -> Option<Vec<FrameControl>> {
    let plan = best.as_ref().and_then(|(_, trace)| trace.crossing)?;
    let line = certifier.best()?;
    let (start, fl) = (&planner.start, &planner.fl);
    let estimate_frames =
        || zigzag_frames(start, &line.controls, fl) + guard_frames(start, &line.controls, fl);
    behind_beyond_estimates(line.crossing, plan, fl.tau_s, estimate_frames)
        .then(|| line.controls.clone())
}

/// Whether a plan crossing at `plan` is behind a certificate's line crossing at `certificate` by what a
/// rounding could still win: it crosses in a later frame, and more than `estimate_frames()` (what a
/// replayable plan is estimated to lose against the line, two rollouts: asked for only once the frames
/// differ) of frame time `frame_s` after it.
fn behind_beyond_estimates(
    certificate: Crossing,
    plan: Crossing,
    frame_s: f64,
    estimate_frames: impl FnOnce() -> f64,
) -> bool {
    certificate.frames < plan.frames && plan.time - certificate.time > estimate_frames() * frame_s
}

/// What the exact plans of a certificate's line are held to: no plan crosses before frame `lo`, each
/// is rounded from lines at `planning_margin` (units), and one is kept only if faster than `greedy_s`
/// seconds.
#[derive(Clone, Copy)]
struct PlanTerms {
    lo: usize,
    planning_margin: f64,
    greedy_s: f64,
}

/// The exact plans of `line`, a line of the certificate's problem other than the relaxed stage's (another
/// optimum, or a greedy start's line of the plan's frame), with the plan so far as the certificate's start
/// solved beside them on a fork: the two need nothing of each other, and after the relaxed stage nothing
/// else keeps the second core busy. Where the rounding gives a faster plan, that plan is a start too (as
/// the plan so far would have been had the two run one after the other). Returns the line solved from a
/// plan as a start when it is the certificate's fastest.
fn another_line_beside_the_plan_as_start(
    planner: &mut Planner,
    certifier: &mut Certifier,
    line: Vec<FrameControl>,
    terms: PlanTerms,
    progress: &mut dyn FnMut(Progress),
    best: &mut BestPlan,
) -> Option<Vec<FrameControl>> {
    let lo = terms.lo;
    let plan_so_far_s = best.as_ref().map(|b| b.0);
    let start = plan_as_start(planner, certifier, best);
    let solve_start = start.map(|start| {
        move |fork: &mut Planner| {
            let mut side = Certifier::default();
            let won = side.add_start(fork, &mut |_| {}, start, StartKind::Planned, lo);
            (won, side)
        }
    });
    let ((), side) = planner.beside_forks(solve_start.into_iter().collect(), |planner| {
        plans_of_certificate_line(planner, line, terms, progress, best);
    });
    let mut faster_line = None;
    for (won, side_certifier) in side {
        if certifier.absorb(side_certifier) && won {
            faster_line = certifier.best().map(|p| p.controls.clone());
        }
    }
    if faster_than_before(best, plan_so_far_s) {
        if let Some(l) = plan_as_certificate_start(planner, certifier, best, lo, progress) {
            faster_line = Some(l);
        }
    }
    faster_line
}

/// How far apart in time two lines of the certificate's problem may cross and still be one optimum to the
/// SCP stages, seconds: their tolerance in progress (`tol_progress_units`) at `line`'s speed at its end.
fn same_optimum_s(planner: &Planner, line: &[FrameControl]) -> f64 {
    let speed = rollout(&planner.start, line, &planner.fl)
        .last()
        .map_or(0.0, |s| s.speed);
    if speed > 0.0 {
        planner.settings.tol_progress_units / speed
    } else {
        0.0
    }
}

/// The exact plans of a line of the certificate's problem faster than the relaxed plan's: the line is
/// refined at the planning margin, then rounded, polished and verified as `terms` say; a faster plan
/// replaces `best`.
fn plans_of_certificate_line(
    planner: &mut Planner,
    line: Vec<FrameControl>,
    terms: PlanTerms,
    progress: &mut dyn FnMut(Progress),
    best: &mut BestPlan,
) {
    let widening = match best {
        Some(_) => Widening::FinalMargin,
        None => Widening::FinalMarginAndLine,
    };
    let planning = terms.planning_margin;
    let source = refined(
        planner,
        progress,
        line.clone(),
        terms.lo,
        planning,
        widening,
    )
    .or_else(|| widened_in_steps(planner, progress, line, terms.lo, planning, widening));
    if let Some(source) = source {
        exact_plans(planner, &source, terms.greedy_s, best);
    }
}

/// `line`, a line of the certificate's problem (at [`CERTIFICATE_MARGIN_UNITS`]) that the count search
/// could not refine at `margin` (units) at once, refined towards it in [`WIDENING_STEPS`] even steps of
/// the margin, each count search frame by frame from the line of the one before, as a line to round with
/// `widening` at the widest margin reached; `None` if not even the first step reaches the finish line.
/// Along a wall the certificate's line starts a whole planning margin inside it, and moved out at once
/// its stage can stall short of the finish line, its later steps rejected (docs/design.md, "A
/// certificate's line widened in steps"). A line rounded at a margin under the planning margin can round
/// into plans that scrape a wall; the replays decide, and the final margin widens as for any
/// certificate's line.
fn widened_in_steps(
    planner: &mut Planner,
    progress: &mut dyn FnMut(Progress),
    line: Vec<FrameControl>,
    lo: usize,
    margin: f64,
    widening: Widening,
) -> Option<Source> {
    let mut widest: Option<Source> = None;
    for step in 1..=WIDENING_STEPS {
        let share = step as f64 / WIDENING_STEPS as f64;
        let step_margin = CERTIFICATE_MARGIN_UNITS + share * (margin - CERTIFICATE_MARGIN_UNITS);
        let from = widest.as_ref().map_or(&line, |w| &w.line).clone();
        match refined(planner, progress, from, lo, step_margin, widening) {
            Some(wider) => widest = Some(wider),
            None => break,
        }
    }
    widest
}

/// `line` refined by the count search at `margin` (units), frame by frame, as a line to round with
/// `widening`; `None` if it no longer reaches the line.
fn refined(
    planner: &mut Planner,
    progress: &mut dyn FnMut(Progress),
    line: Vec<FrameControl>,
    lo: usize,
    margin: f64,
    widening: Widening,
) -> Option<Source> {
    let n = line.len();
    let search = CountSearch::per_frame(Relaxation::planning(margin));
    let line = count_search(planner, progress, line, n, lo, search).line?;
    Some(Source {
        line,
        margin,
        widening,
    })
}

/// The final plan is a point of the certificate's problem too: where it is faster than the certificate,
/// it becomes the certificate's last start. The start is the plan as played, not its planned controls: a
/// plan whose controls end before the line is played on at maximum acceleration until it crosses. Returns
/// the line solved from that start when it is the certificate's fastest (and so faster than the plan).
fn plan_as_certificate_start(
    planner: &mut Planner,
    certifier: &mut Certifier,
    best: &BestPlan,
    lo: usize,
    progress: &mut dyn FnMut(Progress),
) -> Option<Vec<FrameControl>> {
    let start = plan_as_start(planner, certifier, best)?;
    if !certifier.add_start(planner, progress, start, StartKind::Planned, lo) {
        return None;
    }
    certifier.best().map(|p| p.controls.clone())
}

/// The plan as played, as a start of the certificate, where it is faster than the certificate.
fn plan_as_start(
    planner: &Planner,
    certifier: &Certifier,
    best: &BestPlan,
) -> Option<Vec<FrameControl>> {
    let behind = |t: f64| certifier.best_time().is_none_or(|c| t < c);
    let (_, trace) = best.as_ref().filter(|b| behind(b.0))?;
    Some(planner.warm_start(trace))
}

/// The warm starts of the certificate's greedy starts: the other clean greedy runs (not from a start at
/// rest, whose first frame is the seed's own), as many as the settings give the certificate besides the
/// relaxed plan.
fn certificate_greedy_starts(planner: &Planner, base: &Baseline) -> Vec<Vec<FrameControl>> {
    if !planner.prefix.is_empty() {
        return Vec::new();
    }
    let more = planner.settings.certificate_starts.saturating_sub(1);
    base.clean
        .iter()
        .skip(1)
        .take(more)
        .map(|run| planner.warm_start(&run.trace))
        .collect()
}

/// The certificate's greedy starts, solved by `planner` (a fork, on its own thread); `planning` is the
/// relaxed plan's problem (see [`StartKind::Greedy`]).
fn certified_greedy_starts(
    planner: &mut Planner,
    starts: Vec<Vec<FrameControl>>,
    planning: Relaxation,
    lo: usize,
) -> Certifier {
    let mut certifier = Certifier::default();
    for warm in starts {
        let kind = StartKind::Greedy { planning };
        certifier.add_start(planner, &mut |_| {}, warm, kind, lo);
    }
    certifier
}

/// The relaxed line of `planning`, the certificate's start from it, and the line's exact plans,
/// with the frame the relaxed line crosses in; `None` when the relaxed stage found no line. The
/// certificate's start from the relaxed line is solved on a fork beside the exact plans: both begin at
/// the relaxed line and neither needs the other.
fn lines_and_plans(
    planner: &mut Planner,
    seed: Seed,
    lo: usize,
    planning: Relaxation,
    greedy_s: f64,
    progress: &mut dyn FnMut(Progress),
) -> Option<(Certifier, BestPlan, u64)> {
    let relaxed = planner.clocked(
        |s| &mut s.relaxed_line,
        |planner| relaxed_line(planner, progress, seed, lo, planning),
    )?;
    let relaxed_line_frame = planner.crossing_of(&relaxed).map_or(u64::MAX, |c| c.frames);
    let start = relaxed.clone();
    let certify = move |fork: &mut Planner| {
        let mut certifier = Certifier::default();
        certifier.add_start(fork, &mut |_| {}, start, StartKind::Planned, lo);
        certifier
    };
    let (best, certifiers) = beside_certificate_starts(planner, vec![certify], |planner| {
        exact_plans_of_the_line(planner, relaxed, planning.margin_units, greedy_s, progress)
    });
    let certifier = certifiers.into_iter().next().unwrap_or_default();
    Some((certifier, best, relaxed_line_frame))
}

/// Where the relaxed stage starts: the seed's controls over `n` frames, and the valid greedy run where
/// it is another run ([`greedy_beside_the_seed`]).
struct Seed<'t> {
    warm: Vec<FrameControl>,
    n: usize,
    greedy: Option<&'t Trace>,
}

/// The greedy run, where it is clean (a run the planning model can follow: valid, across the line, no
/// wall touched) and not the seed. The seed is the fastest clean run of the strafer's own guides; a
/// racing line's run can be faster. (A run that touches a wall is no start: the model, which has no
/// collisions, leaves the corridor at the contact and the stage stalls there.)
fn greedy_beside_the_seed(base: &Baseline) -> Option<&Trace> {
    // Without clean runs the seed is the greedy run itself.
    let seed_guide = base.clean.first().map(|run| run.guide);
    let greedy = &base.greedy;
    (is_clean(&greedy.trace) && seed_guide.is_some_and(|guide| guide != greedy.guide))
        .then_some(&greedy.trace)
}

/// The relaxed line from the seed; where it finds none, or one that crosses after the greedy run, also
/// the line from that run, and whichever crosses sooner. A descent is local: it ends where its stage
/// cannot reach the count below, and from a seed far slower than the greedy run it can end behind that
/// run, whose own descent starts nearer the line.
fn relaxed_line(
    planner: &mut Planner,
    progress: &mut dyn FnMut(Progress),
    seed: Seed,
    lo: usize,
    planning: Relaxation,
) -> Option<Vec<FrameControl>> {
    let Seed { warm, n, greedy } = seed;
    let line = relaxed_plan(planner, progress, warm, n, lo, planning, Descent::PLAN).line;
    let Some((greedy, crossing)) = greedy.and_then(|g| g.crossing.map(|c| (g, c))) else {
        return line;
    };
    let line_s = crossing_s(planner, line.as_deref());
    if line_s <= crossing.time || planner.out_of_time() {
        return line;
    }
    let start = planner.warm_start(greedy);
    let m = (crossing.frames as usize).saturating_sub(planner.prefix.len());
    let from_greedy = relaxed_plan(planner, progress, start, m, lo, planning, Descent::PLAN).line;
    if crossing_s(planner, from_greedy.as_deref()) < line_s {
        from_greedy
    } else {
        line
    }
}

/// When `line` crosses the finish line in the model, seconds (infinite where it does not or there is
/// no line).
fn crossing_s(planner: &Planner, line: Option<&[FrameControl]>) -> f64 {
    line.and_then(|l| planner.crossing_of(l))
        .map_or(f64::INFINITY, |c| c.time)
}

/// `here` on `planner` while the certificate's starts `jobs` run on forks of it
/// ([`Planner::beside_forks`]); the time this thread then waits for them goes to the certificate wait of
/// [`Planner::seconds`].
fn beside_certificate_starts<'a, T, U, J>(
    planner: &mut Planner<'a>,
    jobs: Vec<J>,
    here: impl FnOnce(&mut Planner<'a>) -> U,
) -> (U, Vec<T>)
where
    J: FnOnce(&mut Planner<'a>) -> T + Send,
    T: Send,
{
    let mut done = None;
    let results = planner.beside_forks(jobs, |planner| {
        let mine = here(planner);
        done = Some(Instant::now());
        mine
    });
    planner.seconds.certificate_wait += done.map_or(0.0, seconds_since);
    results
}

/// The exact plans of the relaxed line, solved at `margin` (units).
fn exact_plans_of_the_line(
    planner: &mut Planner,
    relaxed: Vec<FrameControl>,
    margin: f64,
    greedy_s: f64,
    progress: &mut dyn FnMut(Progress),
) -> BestPlan {
    let source = Source {
        line: relaxed,
        margin,
        widening: Widening::FinalMarginAndLine,
    };
    progress(Progress::Finishing);
    let mut best = None;
    exact_plans(planner, &source, greedy_s, &mut best);
    best
}

/// Stage 3 for one relaxed line: rounded, polished, quantised and verified, first at the settings'
/// final margin; if no plan rounded at the first horizon stays valid (a tight margin along a long wall),
/// again as the line's [`Widening`] allows. A plan replaces `best` when it is faster (and faster than
/// `greedy_s`); a plan whose replay fails is kept aside if it was planned to cross before every other
/// such plan ([`Planner::earliest_failed_plan`], for [`failed_plan_polished_wider`]).
fn exact_plans(planner: &mut Planner, source: &Source, greedy_s: f64, best: &mut BestPlan) {
    let final_margin_units = planner.settings.margin_units;
    let (factors, margin_retries) = match source.widening {
        Widening::FinalMargin => (&FINAL_MARGIN_FACTORS[..], 0),
        Widening::FinalMarginAndLine => (&FINAL_MARGIN_FACTORS[..], MARGIN_RETRIES),
    };
    for final_margin in factors.iter().map(|f| f * final_margin_units) {
        let mut valid = false;
        let plans = rounded_and_polished(
            planner,
            &source.line,
            source.margin,
            final_margin,
            margin_retries,
        );
        for plan in plans {
            let planned = planner.crossing_of(&plan.controls);
            let planned_s = planned.map(|c| c.time);
            let primary = plan.primary;
            let kept = plan.controls.clone();
            let Some((t, trace)) = quantised_and_verified(planner, plan.controls) else {
                planner.note_failed_plan(planned, kept);
                continue;
            };
            // A replay that fell half a frame behind its plan scraped a wall the margin did not keep it
            // off: the next margin is tried as well.
            let as_planned = planned_s.is_none_or(|p| t <= p + 0.5 * planner.fl.tau_s);
            valid |= primary && as_planned;
            kept_if_faster(best, greedy_s, t, trace);
        }
        if valid || planner.timed_out {
            break;
        }
    }
}

/// The exact plan planned to cross first of those whose replay failed ([`Planner::earliest_failed_plan`]),
/// where it was planned a frame or more before the best plan: polished again from its own controls at the
/// wider final margins until a plan of it stays valid, once a solve. A plan whose every move keeps the
/// margin in the model fails its replay where the replay, on the game's quantised angles, falls behind it
/// by more than that: its move cuts a grown wall's corner, or it touches a wall and the engine-exact run
/// falls behind the frames its controls give; a wider margin leaves room for that lag. A plan planned in the best plan's own
/// frame is left: on long runs the polishes cost more than the rounding for a fraction of a frame at most.
fn failed_plan_polished_wider(planner: &mut Planner, greedy_s: f64, best: &mut BestPlan) -> bool {
    let Some((planned, controls)) = planner.earliest_failed_plan.take() else {
        return false;
    };
    let ahead = best.as_ref().map_or(planned.time < greedy_s, |(_, trace)| {
        trace.crossing.is_some_and(|c| planned.frames < c.frames)
    });
    if !ahead {
        return false;
    }
    let final_margin_units = planner.settings.margin_units;
    let mut improved = false;
    for factor in &FINAL_MARGIN_FACTORS[1..] {
        if planner.timed_out {
            break;
        }
        let margin = factor * final_margin_units;
        let kind = StageKind::Plain;
        let (valid, faster) =
            plans_polished_again(planner, controls.clone(), margin, kind, greedy_s, best);
        improved |= faster;
        if valid {
            break;
        }
    }
    improved
}

/// The fastest valid plan polished again from its own controls as played, at the final margin, in
/// stages whose trust region regrows after a kept second-order correction ([`StageKind::Regrowing`]),
/// while a round makes it faster by [`FINAL_POLISH_MIN_GAIN_FRAMES`] or more (at most the settings'
/// `final_polish_rounds` rounds): each plan quantised and verified, and kept only if faster, so the plan
/// can only gain. The polishes before it grow their trust region after good steps only: along a plan
/// pressed against the walls nearly every step is a correction, the region stays where the rejections
/// cut it, and the polish stops at its iterations while the plan is still improving, on some corridors
/// by more than a frame (docs/design.md, "The final polish"). Whether the plan got faster.
fn best_plan_polished_on(planner: &mut Planner, greedy_s: f64, best: &mut BestPlan) -> bool {
    let margin = planner.settings.margin_units;
    let worth_a_round_s = FINAL_POLISH_MIN_GAIN_FRAMES * planner.fl.tau_s;
    let mut improved = false;
    for _ in 0..planner.settings.final_polish_rounds {
        let Some((before_s, trace)) = best.as_ref().filter(|_| !planner.timed_out) else {
            break;
        };
        let before_s = *before_s;
        let controls = planner.warm_start(trace);
        let kind = StageKind::Regrowing;
        improved |= plans_polished_again(planner, controls, margin, kind, greedy_s, best).1;
        let gained_s = best.as_ref().map_or(0.0, |b| before_s - b.0);
        if gained_s < worth_a_round_s {
            break;
        }
    }
    improved
}

/// Stage 7 ([`FinePolish`], where the settings ask for it): the fastest valid plan polished on again at
/// each of `fine`'s wall margins in turn, with its iterations and tolerance, in rounds as
/// [`best_plan_polished_on`]: each plan quantised and verified, and kept only if faster. Where one is,
/// the plan is a start of the certificate too once the last margin is done, as after stage 5 (no plan
/// crosses before frame `lo`); none is kept that is not faster than `greedy_s`.
pub(super) fn plan_polished_finely(
    planner: &mut Planner,
    found: &mut AirbornePlan,
    fine: FinePolish,
    greedy_s: f64,
    lo: usize,
    progress: &mut dyn FnMut(Progress),
) {
    let mut faster = false;
    for &margin_units in fine.margins_units {
        if planner.timed_out {
            break;
        }
        progress(Progress::Polishing { margin_units });
        let settings = SearchSettings {
            margin_units,
            polish_iters: fine.polish_iters,
            tol_progress_units: fine.tol_progress_units,
            ..*planner.settings
        };
        let mut finer = planner.fork_with(&settings);
        faster |= best_plan_polished_on(&mut finer, greedy_s, &mut found.best);
        planner.join(&finer);
    }
    if faster {
        let terms = PlanTerms {
            lo,
            planning_margin: planning_margin(planner),
            greedy_s,
        };
        let (certifier, best) = (&mut found.certifier, &mut found.best);
        polished_plan_as_certificate_start(planner, certifier, terms, progress, best);
    }
}

/// The plans of `controls` polished again at `margin` in stages of `kind` ([`polished_again`]), each
/// quantised and verified and made the best where it is faster ([`kept_if_faster`]): whether any stayed
/// valid, and whether one was faster.
fn plans_polished_again(
    planner: &mut Planner,
    controls: Vec<FrameControl>,
    margin: f64,
    kind: StageKind,
    greedy_s: f64,
    best: &mut BestPlan,
) -> (bool, bool) {
    let (mut valid, mut faster) = (false, false);
    for plan in polished_again(planner, controls, margin, kind) {
        let planned = planner.crossing_of(&plan);
        if let Some((t, trace)) = quantised_and_verified(planner, plan.clone()) {
            valid = true;
            faster |= kept_if_faster(best, greedy_s, t, trace);
        } else {
            planner.note_failed_plan(planned, plan);
        }
    }
    (valid, faster)
}

/// The time a plan must beat, seconds: the best plan's, or `greedy_s` where there is none.
pub(super) fn time_to_beat(best: &BestPlan, greedy_s: f64) -> f64 {
    best.as_ref().map_or(greedy_s, |b| b.0)
}

/// The plan `(t, trace)` made the best if it is faster than the best so far and than `greedy_s`
/// (seconds); whether it was.
pub(super) fn kept_if_faster(best: &mut BestPlan, greedy_s: f64, t: f64, trace: Trace) -> bool {
    let faster = t < time_to_beat(best, greedy_s);
    if faster {
        *best = Some((t, trace));
    }
    faster
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::budget::Budget;
    use crate::optimise::baseline::GuideRun;
    use crate::optimise::planner::{planning_inputs, staircase_scene, with_fast_planner};
    use crate::optimise::search::SearchSettings;
    use crate::optimise::verify::time_of;
    use crate::optimise::Quality;

    #[test]
    fn a_plan_is_behind_a_certificate_line_only_in_a_later_frame_and_beyond_the_estimates() {
        let frame = 0.01;
        let at = |frames: u64, fraction: f64| Crossing::new(frames, fraction, frame);
        // Half a frame behind, in the next frame, with estimates of a tenth: a rounding can win it.
        assert!(behind_beyond_estimates(
            at(408, 0.97),
            at(409, 0.47),
            frame,
            || 0.1
        ));
        // The same gap explained by the estimates (the guard under the kink at 1000 fps): nothing to win.
        assert!(!behind_beyond_estimates(
            at(408, 0.97),
            at(409, 0.47),
            frame,
            || 0.6
        ));
        // In the same frame, however far behind: the rounding target is met.
        assert!(!behind_beyond_estimates(
            at(408, 0.05),
            at(408, 0.95),
            frame,
            || 0.0
        ));
        // Ahead of the line (a plan that slides along a wall the certificate keeps off).
        assert!(!behind_beyond_estimates(
            at(409, 0.2),
            at(408, 0.9),
            frame,
            || 0.0
        ));
        // Across the frame's boundary by a hair beyond estimates of zero.
        assert!(behind_beyond_estimates(
            at(135, 0.99),
            at(136, 0.01),
            frame,
            || 0.0
        ));
    }

    #[test]
    fn a_certificate_line_is_rounded_again_only_after_a_round_that_gained_and_a_frame_behind_it() {
        let frame = 0.01;
        // The round made the plan faster, and the certificate is 1.5 frames ahead of it: again.
        assert!(worth_another_round(
            Some(5.60),
            Some(5.55),
            Some(5.535),
            frame
        ));
        // The first plan of all (none before) a frame behind the certificate: again.
        assert!(worth_another_round(None, Some(5.55), Some(5.535), frame));
        // No faster: the same line would be rounded into the same plan.
        assert!(!worth_another_round(
            Some(5.55),
            Some(5.55),
            Some(5.50),
            frame
        ));
        assert!(!worth_another_round(
            Some(5.54),
            Some(5.55),
            Some(5.50),
            frame
        ));
        // Less than a frame behind the certificate: the final polish's part, not another rounding.
        assert!(!worth_another_round(
            Some(5.60),
            Some(5.55),
            Some(5.545),
            frame
        ));
        // No certificate, or no plan.
        assert!(!worth_another_round(Some(5.60), Some(5.55), None, frame));
        assert!(!worth_another_round(Some(5.60), None, Some(5.50), frame));
    }

    #[test]
    fn a_plan_whose_controls_end_short_of_the_line_starts_the_certificate_as_played() {
        let scene = staircase_scene(1);
        let (sim, bound, base) = planning_inputs(&scene);
        let seed = base.seed();
        let settings = SearchSettings::for_quality(Quality::Fast);
        let mut planner = Planner::new(&scene, &sim, &settings, &bound, seed, Budget::unlimited());
        // The seed's controls cut five frames before its crossing: played, the plan goes on at maximum
        // acceleration and crosses all the same.
        let mut controls = planner.warm_start(seed);
        let frames = controls.len();
        controls.truncate(frames - 5);
        assert!(planner.crossing_of(&controls).is_none());
        let (t, trace) = quantised_and_verified(&mut planner, controls)
            .unwrap_or_else(|| panic!("the cut plan is not valid"));
        let played = trace.crossing.map_or(0, |c| c.frames);
        // As played, the start crosses where the plan does (to the model's rounding).
        let start = planner.warm_start(&trace);
        let own = planner
            .crossing_of(&start)
            .unwrap_or_else(|| panic!("the start does not cross"));
        assert!(own.frames.abs_diff(played) <= 1, "{own:?} against {played}");
        assert!(
            (own.time - t).abs() < 0.5 * scene.frame_time_s(),
            "{own:?} against {t}"
        );
    }

    #[test]
    fn a_seed_that_reaches_no_line_ahead_of_the_greedy_run_is_descended_from_that_run_too() {
        with_fast_planner(&staircase_scene(1), |planner, base, bound| {
            let lo = (bound.crossing.frames as usize).saturating_sub(1);
            let planning = Relaxation::planning(planning_margin(planner));
            let greedy = &base.greedy.trace;
            let greedy_s = time_of(greedy);
            let line_of = |planner: &mut Planner, warm: &[FrameControl], greedy| {
                let seed = Seed {
                    warm: warm.to_vec(),
                    n: warm.len(),
                    greedy,
                };
                relaxed_line(planner, &mut |_| {}, seed, lo, planning)
            };
            // An empty seed reaches nothing (its count grows a few frames at a time); beside the greedy
            // run, the line is that run's, ahead of it.
            assert!(line_of(planner, &[], None).is_none());
            let from_greedy = line_of(planner, &[], Some(greedy));
            let from_greedy_s = crossing_s(planner, from_greedy.as_deref());
            assert!(
                from_greedy_s < greedy_s,
                "{from_greedy_s} s against {greedy_s} s"
            );
            // A seed whose line is ahead of the greedy run keeps it: no second descent.
            let seed = planner.warm_start(base.seed());
            let own = line_of(planner, &seed, None);
            assert!(crossing_s(planner, own.as_deref()) < greedy_s);
            assert!(own == line_of(planner, &seed, Some(greedy)));
        });
    }

    #[test]
    fn the_greedy_run_is_descended_from_beside_the_seed_only_where_it_is_another_run() {
        let (_, _, base) = planning_inputs(&staircase_scene(1));
        assert!(base.clean.len() > 1, "no second clean greedy run");
        let with_greedy = |greedy: &GuideRun, clean: &[GuideRun]| Baseline {
            greedy: greedy.clone(),
            clean: clean.to_vec(),
        };
        let other = with_greedy(&base.clean[1], &base.clean);
        assert!(
            greedy_beside_the_seed(&other).is_some_and(|t| std::ptr::eq(t, &other.greedy.trace))
        );
        let seed = with_greedy(&base.clean[0], &base.clean);
        assert!(greedy_beside_the_seed(&seed).is_none());
        // With no clean run the greedy run is the seed.
        let alone = with_greedy(&base.clean[1], &[]);
        assert!(greedy_beside_the_seed(&alone).is_none());
    }

    #[test]
    fn a_plan_ahead_of_the_certificate_is_its_start_beside_another_lines_rounding() {
        // The plan so far is the greedy run, and the certificate has no line yet: the plan is ahead of
        // it, so while another line is rounded, the plan is solved as the certificate's start on a fork
        // beside it. The other line here is empty and rounds into no plan, so the plan is not a start
        // again after it: the certificate's one start is the fork's. The certificate is then no slower
        // than the plan, and its line is returned to be rounded in turn.
        with_fast_planner(&staircase_scene(1), |planner, base, bound| {
            let greedy = base.greedy.trace.clone();
            let greedy_s = time_of(&greedy);
            let terms = PlanTerms {
                lo: (bound.crossing.frames as usize).saturating_sub(1),
                planning_margin: planning_margin(planner),
                greedy_s,
            };
            let mut best: BestPlan = Some((greedy_s, greedy));
            let mut certifier = Certifier::default();
            let line = Vec::new();
            let faster_line = another_line_beside_the_plan_as_start(
                planner,
                &mut certifier,
                line,
                terms,
                &mut |_| {},
                &mut best,
            );
            let certificate = certifier
                .certificate()
                .unwrap_or_else(|| panic!("the plan was not solved as a start"));
            assert_eq!(certificate.starts, 1);
            let Some((plan_s, _)) = best else {
                panic!("no plan")
            };
            assert_eq!(plan_s, greedy_s, "a plan of the rounding was kept");
            assert!(
                certificate.time <= plan_s,
                "certificate {certificate:?} behind the plan's {plan_s} s"
            );
            let faster_line = faster_line.unwrap_or_else(|| panic!("no line returned"));
            assert!(certifier.best().is_some_and(|p| p.controls == faster_line));
        });
    }

    #[test]
    fn where_the_seed_gives_no_relaxed_line_a_greedy_starts_line_is_rounded() {
        // An empty seed: the relaxed stage grows it a few frames at a time and never reaches the line.
        // The certificate's greedy start (the second clean greedy run) does, and its line is the plan's.
        with_fast_planner(&staircase_scene(1), |planner, base, bound| {
            assert!(base.clean.len() > 1, "no second clean greedy run");
            let lo = (bound.crossing.frames as usize).saturating_sub(1);
            let greedy_s = time_of(&base.greedy.trace);
            let found = plan_airborne(planner, base, Vec::new(), 0, lo, greedy_s, &mut |_| {});
            assert!(found.relaxed_found);
            let certificate = found
                .certifier
                .certificate()
                .unwrap_or_else(|| panic!("no certificate"));
            let Some((t, trace)) = found.best else {
                panic!("no plan from the greedy start's line")
            };
            assert!(
                trace.feasible() && t < greedy_s,
                "{t} s against greedy's {greedy_s} s"
            );
            assert!(
                certificate.time <= t,
                "certificate {certificate:?} behind the plan's {t} s"
            );
        });
    }
}
