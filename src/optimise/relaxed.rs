//! The relaxed stage: sides continuous in `[-1, 1]` (the limit of fast left/right alternation, see
//! [`super::model`]), so that every exact plan is one of its points. Min-time is fixed-N maximal progress
//! plus a search over N: SCP at a frame count N, then N lowered to the frame before the plan's crossing
//! until the line can no longer be reached. On long runs (and on the certificate's greedy starts of 200
//! frames or more) the search first runs over knots of several frames played with one control, each the
//! mean of its frames' controls or, where those knots run into the walls, fitted to follow the start's
//! run; when a knot stage stops, over knots half as long from its line, down to knots of 2 or 3 frames
//! (coarse to fine), then frame by frame.

use super::model::{
    frame, knots_averaged, knots_following, rollout_knots, FrameControl, FrameLaw, ModelState,
};
use super::planner::Planner;
use super::scp::{model_crossing, ScpProblem};
use super::search::Progress;
use crate::budget::Stage;
use crate::sim::Crossing;

/// Times, in one count search, a relaxed stage that stopped at its iteration cap without a clean crossing
/// is continued at its count before that count is given up: the budget is the whole search's, not each
/// count's, so a start far from the line whose stages keep ending inside the margin stops at the count it
/// has reached, short of its optimum ([`Descended::short`]: the certificate counts its line for the fastest,
/// not for the spread).
const MAX_CONTINUED_STAGES: usize = 3;

/// About this many knots make the coarse stage of a long run (the planning steps of a 100 fps run of four
/// seconds).
const COARSE_KNOTS: usize = 400;

/// About this many knots make the coarse stage of a certificate's greedy start too short for knots of two
/// frames at [`COARSE_KNOTS`] (200 to 800 frames: knots of 2 to 7 frames). There a sub-problem over knots
/// costs about a fifth of one over frames, and the descent from a greedy run, often a third to twice
/// slower than the plan, is most of the start's work.
const SHORT_RUN_COARSE_KNOTS: usize = 100;

/// Which runs the relaxed stage plans over knots before frames.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum CoarseRuns {
    /// Runs of 800 frames or more ([`COARSE_KNOTS`]).
    Long,
    /// Runs of 200 frames or more ([`SHORT_RUN_COARSE_KNOTS`] below 800).
    AlsoShort,
}

/// Times a frame count that the line cannot be reached in is grown before the search gives up.
const MAX_GROW_TRIES: usize = 3;

/// How the relaxed stage descends from a start: which runs it plans over knots first, how many times it
/// grows a frame count that the line cannot be reached in, and what it descends first where the knots
/// reach no clean line.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) struct Descent {
    /// The runs planned over knots before frames.
    pub(super) coarse: CoarseRuns,
    /// Times an unreachable count is grown (by a twentieth, at least two steps) before the search gives up.
    pub(super) grow_tries: usize,
    /// Where the knots reach no clean line, or were fitted to the run ([`knots_following`]: the averaged
    /// knots ran into the walls), the problem descended frame by frame before the search's own (`None`:
    /// the search's own only). A fitted start's line over knots can be a trap far above the line that
    /// this descent reaches from it.
    pub(super) after_unclear_knots: Option<Relaxation>,
}

impl Descent {
    /// The relaxed plan's: long runs over knots first, an unreachable count grown [`MAX_GROW_TRIES`] times.
    pub(super) const PLAN: Descent = Descent {
        coarse: CoarseRuns::Long,
        grow_tries: MAX_GROW_TRIES,
        after_unclear_knots: None,
    };

    /// A certificate's greedy start ([`StartKind::Greedy`]): over knots from 200 frames, and never over
    /// more frames than the run's own. Where its knots reach no clean line (the knots' chords keep a
    /// sagitta's margin, `m^2 tau gamma1 / 8`, which with air acceleration 100 is wider than a sharply
    /// turning greedy run keeps off the walls), or were fitted to the run, it descends frame by frame in
    /// the relaxed plan's problem (`planning`, at the planning margin) first: at the certificate's
    /// hair-width margin the walls hold each step back and the count search gains a few frames a count
    /// where the wider margin gains tens.
    pub(super) fn greedy_start(planning: Relaxation) -> Descent {
        Descent {
            coarse: CoarseRuns::AlsoShort,
            grow_tries: 0,
            after_unclear_knots: Some(planning),
        }
    }

    /// The count search of this descent over `relaxation`, in steps of `frames_per_knot` frames.
    pub(super) fn count_search(self, relaxation: Relaxation, frames_per_knot: u32) -> CountSearch {
        CountSearch {
            relaxation,
            frames_per_knot,
            grow_tries: self.grow_tries,
        }
    }
}

/// One search over frame counts: the relaxed problem, the planning step and how many times an unreachable
/// count is grown.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) struct CountSearch {
    /// The problem solved at each count.
    pub(super) relaxation: Relaxation,
    /// Frames per planning step (1: frame by frame).
    pub(super) frames_per_knot: u32,
    /// See [`Descent::grow_tries`].
    pub(super) grow_tries: usize,
}

impl CountSearch {
    /// Frame by frame, as the relaxed plan's search ([`Descent::PLAN`]).
    pub(super) fn per_frame(relaxation: Relaxation) -> Self {
        Descent::PLAN.count_search(relaxation, 1)
    }
}

/// Which relaxed problem: the wall margin and whether `c` keeps under the anglemod guard.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) struct Relaxation {
    /// Wall margin, units.
    pub(super) margin_units: f64,
    /// See [`super::scp::ScpProblem::anglemod_guard`].
    pub(super) anglemod_guard: bool,
}

impl Relaxation {
    /// The relaxed problem the plan is rounded from, at `margin_units`, under the anglemod guard.
    pub(super) fn planning(margin_units: f64) -> Self {
        Relaxation {
            margin_units,
            anglemod_guard: true,
        }
    }

    /// The problem of the certificate: no guard, and the smallest margin the SCP can hold (see
    /// [`CERTIFICATE_MARGIN_UNITS`]), so every exact plan that keeps that far off the walls is one of its
    /// points.
    pub(super) fn certificate() -> Self {
        Relaxation {
            margin_units: CERTIFICATE_MARGIN_UNITS,
            anglemod_guard: false,
        }
    }
}

/// The certificate's wall margin, units. A plan counts as clear at half its margin (see
/// [`super::scp::ScpProblem::violation`]), so the certificate holds every plan at least 0.001 units off the
/// walls (a ten-thousandth of a frame at 700 ups and 100 fps). At a margin of zero, the second-order
/// error of each step along a wall lands a hair inside it and the stage never counts a plan as clear.
pub(super) const CERTIFICATE_MARGIN_UNITS: f64 = 0.002;

/// The least clearance of the runs the certificate holds, units: half its margin
/// ([`CERTIFICATE_MARGIN_UNITS`]). A run closer to a wall (one that touches or slides along it) is not a
/// point of the certificate's problem and can be ahead of it.
pub const CERTIFIED_CLEARANCE_UNITS: f64 = 0.5 * CERTIFICATE_MARGIN_UNITS;

/// Frames per knot of the coarse stage for a run of about `frames` frames: knots of several frames
/// once the run is long enough that about [`COARSE_KNOTS`] knots cover it; with
/// [`CoarseRuns::AlsoShort`], on shorter runs once about [`SHORT_RUN_COARSE_KNOTS`] do; else 1 (no coarse
/// stage).
pub(super) fn coarse_knot_frames(frames: usize, runs: CoarseRuns) -> u32 {
    let per_knot = match (frames / COARSE_KNOTS, runs) {
        (0 | 1, CoarseRuns::AlsoShort) => frames / SHORT_RUN_COARSE_KNOTS,
        (long, _) => long,
    };
    u32::try_from(per_knot).unwrap_or(u32::MAX).max(1)
}

/// The relaxed plan at wall `margin` (units) from the warm start `controls`, whose line crossing is near
/// frame `n`; no plan crosses before frame `lo` (the lower bound's). Coarse to fine on the `descent`'s
/// coarse runs: over knots, halved each time a knot stage stops on a line ([`finer_knot_frames`]), then
/// frames. Returns the search over frames: its best clean plan, cut at its crossing frame.
pub(super) fn relaxed_plan(
    planner: &mut Planner,
    progress: &mut dyn FnMut(Progress),
    mut controls: Vec<FrameControl>,
    mut n: usize,
    lo: usize,
    relaxation: Relaxation,
    descent: Descent,
) -> Descended {
    let mut knot_frames = coarse_knot_frames(n, descent.coarse);
    // Whether some knots' start was fitted to the run.
    let mut fitted_any = false;
    while knot_frames > 1 {
        let (knots_line, fitted) = knots_descent(
            planner,
            progress,
            &controls[..n.min(controls.len())],
            lo,
            knot_frames,
            relaxation,
            descent,
        );
        fitted_any |= fitted;
        let Some(plan) = knots_line else { break };
        controls = plan
            .iter()
            .flat_map(|u| std::iter::repeat_n(*u, knot_frames as usize))
            .collect();
        n = controls.len();
        knot_frames = finer_knot_frames(knot_frames);
    }
    // The halving ends over knots only where a stage's knots reached no line.
    let unreached = knot_frames > 1;
    if let Some(first) = descent
        .after_unclear_knots
        .filter(|_| fitted_any || unreached)
    {
        let search = descent.count_search(first, 1);
        if let Some(line) = count_search(planner, progress, controls.clone(), n, lo, search).line {
            n = line.len();
            controls = line;
        }
    }
    let per_frame = descent.count_search(relaxation, 1);
    count_search(planner, progress, controls, n, lo, per_frame)
}

/// Frames per knot of the stage that follows a knot stage of `frames_per_knot` once its line stops: half
/// as many, down to knots of 2 or 3 frames; after those, 1 (frame by frame). A knot stage stops where one
/// control per knot, kept a sagitta (`m^2 tau gamma1 / 8`) off the walls, can turn the line no sooner.
/// Knots half as long go on from that line at a quarter of the sagitta, each of their sub-problems a
/// fraction of the price of a frame-by-frame one, where the frames alone gain a few frames a count from
/// far above their line.
fn finer_knot_frames(frames_per_knot: u32) -> u32 {
    if frames_per_knot >= 4 {
        frames_per_knot / 2
    } else {
        1
    }
}

/// The count search over knots of `frames_per_knot` frames from the run of `controls`, at `relaxation`'s
/// margin widened by the knots' sagitta: the line it reaches (cut at its crossing knot), and whether its
/// start had to be fitted to the run ([`coarse_start`]).
fn knots_descent(
    planner: &mut Planner,
    progress: &mut dyn FnMut(Progress),
    controls: &[FrameControl],
    lo: usize,
    frames_per_knot: u32,
    relaxation: Relaxation,
    descent: Descent,
) -> (Option<Vec<FrameControl>>, bool) {
    let m = frames_per_knot as usize;
    // The chord of a knot leaves its frames' arc by at most the sagitta m^2 tau gamma1 / 8 (each frame
    // turns the heading by at most about gamma1 / V).
    let fl = planner.fl;
    let sagitta = (m * m) as f64 * fl.tau_s * fl.law.gamma1 / 8.0;
    let over_knots = Relaxation {
        margin_units: relaxation.margin_units + sagitta,
        ..relaxation
    };
    let (knots, fitted) = coarse_start(planner, controls, m, over_knots);
    let count = knots.len();
    let search = descent.count_search(over_knots, frames_per_knot);
    let line = count_search(planner, progress, knots, count, lo / m, search).line;
    (line, fitted)
}

/// The knots of `frames_per_knot` frames a coarse stage at `relaxation` starts from, for the run of
/// `controls`: each knot the mean of its frames' controls, which keeps the start's own controls, as long
/// as those knots keep clear of the walls at the stage's margin; else knots fitted to follow the run
/// ([`knots_following`]); with whether they were fitted. The mean of alternating sides at different `c`
/// turns on average (a frame's turn is not linear in its `c`): a greedy run that brakes or turns sharply,
/// averaged, drifts off its line into the walls, and a stage started inside them stalls.
fn coarse_start(
    planner: &Planner,
    controls: &[FrameControl],
    frames_per_knot: usize,
    relaxation: Relaxation,
) -> (Vec<FrameControl>, bool) {
    let fl = planner.fl;
    let averaged = knots_averaged(controls, frames_per_knot);
    let per = u32::try_from(frames_per_knot).unwrap_or(u32::MAX);
    let states = rollout_knots(&planner.start, &averaged, &fl, per);
    let problem = relaxed_problem(planner, relaxation, per);
    if problem.violation(&states) <= super::scp::CLEAN_VIOLATION_UNITS {
        return (averaged, false);
    }
    let fitted = knots_following(&planner.start, controls, &fl, frames_per_knot, |v| {
        problem.c_upper(v)
    });
    (fitted, true)
}

/// What a count search ends with.
pub(super) struct Descended {
    /// The best clean line, cut at its crossing step.
    pub(super) line: Option<Vec<FrameControl>>,
    /// Whether the search stopped before it found that one step fewer than its line cannot reach the
    /// finish line (nor stopped at the bound's count): the stages at a count it could not yet reach ran
    /// out of continuations while still improving, or the budget ran out. Its line is then not the local
    /// optimum of its start.
    pub(super) short: bool,
}

/// The search over the number of planning steps (frames or knots, as `search` says): SCP at `n` steps
/// from `controls`, then at one step fewer than the plan's crossing, until the line is no longer reached
/// (or `lo` steps, below which the bound says it cannot be); more steps if the first count does not reach
/// it (at most `search.grow_tries` times). Where the count below the best line is not reached but the
/// stage that found the line was cut by its iteration cap, the search first goes on at the line's own
/// count (each stage starts its trust region afresh, so a line found by a cut stage is not its count's
/// best, and a count below it can be reachable from a better one), at most the settings'
/// `capped_line_returns` times.
pub(super) fn count_search<'a>(
    planner: &mut Planner<'a>,
    progress: &mut dyn FnMut(Progress),
    mut controls: Vec<FrameControl>,
    mut n: usize,
    lo: usize,
    search: CountSearch,
) -> Descended {
    let fl = planner.fl;
    let mut counts = CountsSoFar::new(lo, search.grow_tries, planner.settings.capped_line_returns);
    // A sub-problem has at least one step to plan (an empty one is no problem for the solver).
    n = n.max(1);
    let short = loop {
        if planner.out_of_time() {
            planner.note_cut(Stage::Relaxed);
            break true;
        }
        controls.resize(
            n,
            FrameControl {
                sigma: 0.0,
                c: fl.c_max(f64::INFINITY),
            },
        );
        let tried = stage_at_count(
            planner,
            progress,
            &controls,
            search.relaxation,
            search.frames_per_knot,
        );
        match counts.next(tried, n, planner.timed_out) {
            NextCount::Try {
                steps,
                controls: start,
            } => {
                n = steps;
                controls = start;
            }
            NextCount::Stop { short } => break short,
        }
    };
    Descended {
        line: counts.best,
        short,
    }
}

/// What a count search does after a count: try `steps` planning steps from `controls`, or stop
/// (`short`: see [`Descended::short`]).
enum NextCount {
    Try {
        steps: usize,
        controls: Vec<FrameControl>,
    },
    Stop {
        short: bool,
    },
}

/// A count search between counts ([`count_search`]): its best clean line so far and the times it went on
/// without descending, each against its limit.
struct CountsSoFar {
    /// The best clean line, cut at its crossing step.
    best: Option<Vec<FrameControl>>,
    /// Whether the stage that found `best` stopped at its iteration cap.
    best_capped: bool,
    /// No line crosses before this step (the bound's).
    lo: usize,
    /// Times an unreachable count was grown, and the most allowed.
    grow_tries: usize,
    max_grow_tries: usize,
    /// Times a capped stage was continued at its own count (at most [`MAX_CONTINUED_STAGES`]).
    continue_tries: usize,
    /// Times the search went back to a line its capped stage left improving, and the most allowed.
    returns: usize,
    max_returns: usize,
}

impl CountsSoFar {
    fn new(lo: usize, max_grow_tries: usize, max_returns: usize) -> Self {
        CountsSoFar {
            best: None,
            best_capped: false,
            lo,
            grow_tries: 0,
            max_grow_tries,
            continue_tries: 0,
            returns: 0,
            max_returns,
        }
    }

    /// The next count after `tried` at `n` steps (`timed_out`: the solve's budget is spent).
    fn next(&mut self, tried: CountTried, n: usize, timed_out: bool) -> NextCount {
        let CountTried {
            controls: c,
            capped,
            crossing,
        } = tried;
        match crossing {
            Some(k) => {
                self.best = Some(c[..k].to_vec());
                self.best_capped = capped;
                // One step short of this plan's crossing, warm-started from it: each solve keeps
                // improving the same line (stepping further on a failed probe proves nothing, the
                // search being local).
                if k <= self.lo + 1 || timed_out {
                    return NextCount::Stop { short: timed_out };
                }
                NextCount::Try {
                    steps: k - 1,
                    controls: c[..k - 1].to_vec(),
                }
            }
            _ if capped && self.continue_tries < MAX_CONTINUED_STAGES && !timed_out => {
                // The stage ran out of iterations still improving (a start far from the line: the
                // capped greedy run of a narrow bend at 1000 fps): go on at the same count.
                self.continue_tries += 1;
                NextCount::Try {
                    steps: n,
                    controls: c,
                }
            }
            _ if self.best_capped && self.returns < self.max_returns && !timed_out => {
                // The count below the best line was not reached from it, but the stage that found that
                // line stopped at its cap still improving: the line is not yet its count's best. Go on
                // at its count from it, then try the count below again.
                self.returns += 1;
                self.best_capped = false;
                // (A capped best is always a line: the two are set together.)
                let line = self.best.clone().unwrap_or(c);
                NextCount::Try {
                    steps: line.len(),
                    controls: line,
                }
            }
            _ => {
                // With a line in hand the count below it is unreachable from it, unless the stage was
                // still improving when its continuations ran out.
                if self.best.is_some() || self.grow_tries >= self.max_grow_tries || timed_out {
                    return NextCount::Stop {
                        short: capped || timed_out,
                    };
                }
                // Not reachable at this count from this start: give it more steps.
                self.grow_tries += 1;
                NextCount::Try {
                    steps: n + (n / 20).max(2),
                    controls: c,
                }
            }
        }
    }
}

/// One count of a count search: the plan its stage ended with, whether the stage stopped at its
/// iteration cap, and the step its plan crosses the finish line in when it does so clear of the walls.
struct CountTried {
    controls: Vec<FrameControl>,
    capped: bool,
    crossing: Option<usize>,
}

/// The relaxed problem's SCP stage over the planning steps of `controls` (steps of `frames_per_knot`
/// frames), reported to `progress`.
fn stage_at_count(
    planner: &mut Planner,
    progress: &mut dyn FnMut(Progress),
    controls: &[FrameControl],
    relaxation: Relaxation,
    frames_per_knot: u32,
) -> CountTried {
    planner.stats.frame_counts_tried += 1;
    let relaxed_iters = planner.settings.relaxed_iters;
    let problem = relaxed_problem(planner, relaxation, frames_per_knot);
    let (c, capped) = planner.stage(problem.clone(), controls.to_vec(), relaxed_iters);
    planner.note_cut(Stage::Relaxed);
    let states = rollout_knots(&planner.start, &c, &planner.fl, frames_per_knot);
    let reached = model_crossing(&planner.start, &states, planner.scene);
    let clean = problem.violation(&states) <= super::scp::CLEAN_VIOLATION_UNITS;
    let crossing = reached.filter(|_| clean);
    let per = frames_per_knot as usize;
    progress(Progress::FrameCount {
        frames: controls.len() * per,
        frames_per_step: frames_per_knot,
        reached: crossing.map(|k| k * per),
    });
    CountTried {
        controls: c,
        capped,
        crossing,
    }
}

/// The SCP problem of `relaxation` over planning steps of `frames_per_knot` frames.
fn relaxed_problem<'a>(
    planner: &Planner<'a>,
    relaxation: Relaxation,
    frames_per_knot: u32,
) -> ScpProblem<'a> {
    ScpProblem {
        anglemod_guard: relaxation.anglemod_guard,
        ..planner.problem(relaxation.margin_units, true, frames_per_knot)
    }
}

/// The relaxed optimum as a certificate: the relaxed problem at zero wall margin and without the anglemod
/// guard, whose feasible set holds every exact plan, solved from several starts. Each start ends in a
/// local optimum (the problem is not convex), so this is not a proof of a bound: the spread of the
/// optimum over the starts is the evidence of how far from global it may be.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct RelaxedCertificate {
    /// The frame in which the fastest relaxed plan crosses the line.
    pub frames: u64,
    /// Its fractional crossing time, seconds.
    pub time: f64,
    /// Starts tried.
    pub starts: usize,
    /// Starts whose relaxed plan reached the line.
    pub reached: usize,
    /// Of those, starts whose search stopped short of its local optimum, still improving when its
    /// stages ran out (or when the time limit came): their lines count towards the fastest, not the spread.
    pub short: usize,
    /// The slowest less the fastest crossing time over the starts that reached the line at their local
    /// optimum (and the fastest, wherever it came from), seconds.
    pub spread: f64,
    /// About how far, in frames, the game's sides of `+-1` must fall behind the fastest relaxed plan:
    /// where a frame's side is between them, the exact plan alternates, and each move points half a turn
    /// off the mean heading ([`zigzag_frames`]). `None` where not estimated.
    pub zigzag_frames: Option<f64>,
    /// About how far, in frames, a replayable plan falls behind the fastest relaxed plan by keeping half
    /// a step of the replay's strafe angle under the law's kink where that plan sits on it
    /// ([`guard_frames`]; zero in the law's second case). `None` where not estimated.
    pub guard_frames: Option<f64>,
}

impl RelaxedCertificate {
    /// A plan crossing at `time_s` less the relaxed optimum, in frames of `tau_s` seconds: its rounding
    /// loss (negative for a plan ahead of it).
    pub fn loss_frames(&self, time_s: f64, tau_s: f64) -> f64 {
        (time_s - self.time) / tau_s
    }

    /// How much of its crossing frame the relaxed optimum leaves, in frames of `tau_s` seconds: a plan
    /// that loses more to it crosses a frame later.
    pub fn frame_left(&self, tau_s: f64) -> f64 {
        self.frames as f64 - self.time / tau_s
    }
}

/// `behind_units` of a plan's path in frames at the speed of its last state `end` (zero at rest).
fn frames_at_end_speed(behind_units: f64, end: &ModelState, tau_s: f64) -> f64 {
    if end.speed > 0.0 {
        behind_units / (end.speed * tau_s)
    } else {
        0.0
    }
}

/// The zigzag of alternating sides along the relaxed plan `controls` from `start`, in frames at the
/// speed it crosses with: a frame of side `sigma` and full turn `delta` moves `(1 - sigma^2) delta^2 / 8`
/// of its length less along the track (`1 - cos(delta / 2)` for sides alternating every frame,
/// docs/physics.md section 6; the weight `1 - sigma^2` is the least mean square of the heading's offset
/// over any sequence of sides with mean `sigma`, so the estimate errs low).
pub fn zigzag_frames(start: &ModelState, controls: &[FrameControl], fl: &FrameLaw) -> f64 {
    let mut x = *start;
    let mut behind_units = 0.0;
    for u in controls {
        let full = frame(&x, FrameControl { sigma: 1.0, c: u.c }, fl, false).0;
        let delta = (full.heading - x.heading).abs();
        let next = frame(&x, *u, fl, false).0;
        let sigma = u.sigma.clamp(-1.0, 1.0);
        behind_units += next.speed * fl.tau_s * (1.0 - sigma * sigma) * delta * delta / 8.0;
        x = next;
    }
    frames_at_end_speed(behind_units, &x, fl.tau_s)
}

/// The cost of the guard under the kink along the relaxed plan `controls` from `start`, in frames at the
/// speed it crosses with. In the law's first case a frame whose `c` is above [`FrameLaw::c_plan_max`]
/// (half a step of the replay's strafe angle under the kink, docs/physics.md section 6) is played at that
/// `c` by every plan the replay can follow, and gains less speed. The speed not gained is carried on
/// frame by frame through the plan's own controls (a slower frame gains a little more in the first case,
/// so the deficit shrinks), and each frame's deficit moves the plan back by it times the frame time:
/// about `N^2 tau gamma1 q / 4` units over `N` frames on the kink. An estimate like [`zigzag_frames`]: a
/// plan can trade some of it for a shorter path.
pub fn guard_frames(start: &ModelState, controls: &[FrameControl], fl: &FrameLaw) -> f64 {
    let mut x = *start;
    let mut deficit_ups = 0.0;
    let mut behind_units = 0.0;
    for u in controls {
        let next = frame(&x, *u, fl, false).0;
        let slower = ModelState {
            speed: x.speed - deficit_ups,
            ..x
        };
        let carried = next.speed - frame(&slower, *u, fl, false).0.speed;
        let guarded_c = fl.c_plan_max(x.speed);
        let lost = if u.c > guarded_c {
            next.speed
                - frame(&x, FrameControl { c: guarded_c, ..*u }, fl, false)
                    .0
                    .speed
        } else {
            0.0
        };
        deficit_ups = (carried + lost).max(0.0);
        behind_units += deficit_ups * fl.tau_s;
        x = next;
    }
    frames_at_end_speed(behind_units, &x, fl.tau_s)
}

/// The certificate's fastest relaxed plan and the start it came from.
pub(super) struct CertifiedPlan {
    pub(super) controls: Vec<FrameControl>,
    pub(super) start_index: usize,
    pub(super) crossing: Crossing,
}

/// The certificate as its starts are solved: what each start reached and the fastest plan.
#[derive(Default)]
pub(super) struct Certifier {
    tried: usize,
    /// Per start that reached the line, in order.
    ends: Vec<StartEnd>,
    best: Option<CertifiedPlan>,
    /// The line each greedy start reached ([`StartKind::Greedy`]).
    greedy_lines: Vec<CertifiedPlan>,
}

/// Where a start of the certificate ended.
#[derive(Clone, Copy, Debug)]
struct StartEnd {
    /// Which start, in the order tried (absorbed starts after this certifier's own).
    index: usize,
    /// Its line's crossing time, seconds.
    time: f64,
    /// Whether its search stopped short of its local optimum ([`Descended::short`]).
    short: bool,
}

/// How a start of the certificate is solved.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) enum StartKind {
    /// A line already planned frame by frame (the relaxed stage's, or the final plan): refined at its
    /// frame count and below; it is itself a point of the certificate's problem.
    Planned,
    /// A greedy run: coarse to fine, as the relaxed stage, but as [`Descent::greedy_start`] says: over
    /// knots from 200 frames, and never over more frames than the run's own (a start whose line cannot be
    /// reached in the frames its run took is far from the optimum, and growing its count, three stages
    /// over more frames each, only spends the solve's time); where the knots reach no clean line, frame
    /// by frame in `planning`, the relaxed plan's problem, first.
    Greedy {
        /// The relaxed plan's problem.
        planning: Relaxation,
    },
}

impl Certifier {
    /// Solves the certificate's problem from `start` (planning controls cut near their crossing); no plan
    /// crosses before frame `lo`. Does nothing once time is up. Returns whether the line solved from the
    /// start (not a planned start's own) is now the fastest.
    pub(super) fn add_start(
        &mut self,
        planner: &mut Planner,
        progress: &mut dyn FnMut(Progress),
        start: Vec<FrameControl>,
        kind: StartKind,
        lo: usize,
    ) -> bool {
        if planner.out_of_time() {
            return false;
        }
        let index = self.tried;
        self.tried += 1;
        let n = start.len();
        let own = match kind {
            StartKind::Planned => planner.crossing_of(&start).map(|c| (c, start.clone())),
            StartKind::Greedy { .. } => None,
        };
        let relaxation = Relaxation::certificate();
        let descended = match kind {
            StartKind::Planned => {
                let search = CountSearch::per_frame(relaxation);
                count_search(planner, progress, start, n, lo, search)
            }
            StartKind::Greedy { planning } => {
                let descent = Descent::greedy_start(planning);
                relaxed_plan(planner, progress, start, n, lo, relaxation, descent)
            }
        };
        let short = descended.short;
        let solved = descended
            .line
            .and_then(|p| planner.crossing_of(&p).map(|c| (c, p)));
        let (reached, solved_won) = match (solved, own) {
            (Some(s), Some(o)) if o.0.time < s.0.time => (Some(o), false),
            (Some(s), _) => (Some(s), true),
            (None, o) => (o, false),
        };
        let Some((crossing, controls)) = reached else {
            return false;
        };
        self.ends.push(StartEnd {
            index,
            time: crossing.time,
            short,
        });
        let fastest = self
            .best
            .as_ref()
            .is_none_or(|b| crossing.time < b.crossing.time);
        if matches!(kind, StartKind::Greedy { .. }) {
            self.greedy_lines.push(CertifiedPlan {
                controls: controls.clone(),
                start_index: index,
                crossing,
            });
        }
        if fastest {
            self.best = Some(CertifiedPlan {
                controls,
                start_index: index,
                crossing,
            });
        }
        fastest && solved_won
    }

    /// Takes in the starts of `other`, solved apart (on another thread), as the starts after this one's:
    /// their indices follow this one's, and a plan of theirs is the best only if strictly faster. Returns
    /// whether one is.
    pub(super) fn absorb(&mut self, other: Certifier) -> bool {
        let offset = self.tried;
        self.tried += other.tried;
        self.ends.extend(other.ends.into_iter().map(|e| StartEnd {
            index: e.index + offset,
            ..e
        }));
        let greedy_lines = other.greedy_lines.into_iter();
        self.greedy_lines
            .extend(greedy_lines.map(|p| CertifiedPlan {
                start_index: p.start_index + offset,
                ..p
            }));
        if let Some(plan) = other.best {
            if self
                .best
                .as_ref()
                .is_none_or(|b| plan.crossing.time < b.crossing.time)
            {
                self.best = Some(CertifiedPlan {
                    start_index: plan.start_index + offset,
                    ..plan
                });
                return true;
            }
        }
        false
    }

    /// The fastest line a greedy start other than start `except` reached that crosses in frame `frame`
    /// or before. Where no start found another optimum, such a line is no faster than the relaxed plan's
    /// own (to within the stages' tolerance), but within a frame the rounding's outcome depends on the
    /// line it starts from by more than the lines' own times differ: rounded from the relaxed plan's line
    /// and from a greedy start's, plans come out up to 0.9 ms apart (near a tenth of a frame at 100 fps),
    /// either way round. So that line is rounded too, and the plan is the fastest.
    pub(super) fn fastest_greedy_line(
        &self,
        frame: u64,
        except: Option<usize>,
    ) -> Option<&CertifiedPlan> {
        self.greedy_lines
            .iter()
            .filter(|p| p.crossing.frames <= frame && Some(p.start_index) != except)
            .min_by(|a, b| a.crossing.time.total_cmp(&b.crossing.time))
    }

    /// The fastest relaxed plan so far.
    pub(super) fn best(&self) -> Option<&CertifiedPlan> {
        self.best.as_ref()
    }

    /// The fastest relaxed plan, if it is another local optimum than the line the relaxed stage rounded:
    /// a start after the first found it more than `same_optimum_s` seconds before the first start's line
    /// (or the first reached nothing), not the same optimum found again to within the stages' tolerance;
    /// or it crosses before frame `frame_to_beat` (the fastest exact plan's, or the relaxed stage's line's
    /// where there is none), whichever start found it: the relaxed stage, at the planning margin, can stop
    /// short of an optimum that the certificate's problem, descending from its line, goes on to.
    pub(super) fn another_optimum(
        &self,
        same_optimum_s: f64,
        frame_to_beat: u64,
    ) -> Option<&CertifiedPlan> {
        let best = self.best.as_ref()?;
        if best.crossing.frames < frame_to_beat {
            return Some(best);
        }
        let first = self.ends.iter().find(|e| e.index == 0).map(|e| e.time);
        (best.start_index > 0 && first.is_none_or(|t| best.crossing.time < t - same_optimum_s))
            .then_some(best)
    }

    /// The crossing time of the fastest relaxed plan so far, seconds.
    pub(super) fn best_time(&self) -> Option<f64> {
        self.best.as_ref().map(|b| b.crossing.time)
    }

    /// The certificate, if any start reached the line.
    pub(super) fn certificate(&self) -> Option<RelaxedCertificate> {
        let best = self.best.as_ref()?;
        let at_optimum = self.ends.iter().filter(|e| !e.short);
        let slowest = at_optimum
            .map(|e| e.time)
            .fold(best.crossing.time, f64::max);
        Some(RelaxedCertificate {
            frames: best.crossing.frames,
            time: best.crossing.time,
            starts: self.tried,
            reached: self.ends.len(),
            short: self.ends.iter().filter(|e| e.short).count(),
            spread: slowest - best.crossing.time,
            zigzag_frames: None,
            guard_frames: None,
        })
    }

    /// The certificate with the estimates of what a replayable exact plan loses against it along its
    /// fastest plan from `start`: the zigzag of alternating sides ([`zigzag_frames`]) and the guard under
    /// the kink ([`guard_frames`]).
    pub(super) fn certificate_with_estimates(
        &self,
        start: &ModelState,
        fl: &FrameLaw,
    ) -> Option<RelaxedCertificate> {
        let best = self.best.as_ref()?;
        self.certificate().map(|c| RelaxedCertificate {
            zigzag_frames: Some(zigzag_frames(start, &best.controls, fl)),
            guard_frames: Some(guard_frames(start, &best.controls, fl)),
            ..c
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::budget::Budget;
    use crate::optimise::airborne::planning_margin;
    use crate::optimise::model::rollout;
    use crate::optimise::planner::{planning_inputs, staircase_scene, with_planner};
    use crate::optimise::qp::SubProblemSolver;
    use crate::optimise::search::SearchSettings;
    use crate::optimise::Quality;
    use crate::physics::{MovementVars, Vec2};

    #[test]
    fn the_zigzag_estimate_is_what_alternating_sides_lose_on_a_straight() {
        // 100 fps, air acceleration 10, 400 frames from 320 ups: the relaxed straight (side 0) against
        // the exact one, sides alternating every frame. The exact run's displacement falls short of the
        // relaxed one's by what the estimate says, to a tenth (here 0.1324 frame estimated, 0.1321 lost).
        let vars = MovementVars::goldsrc(100.0);
        let fl = FrameLaw::of(&vars);
        let start = ModelState {
            pos: Vec2::ZERO,
            speed: 320.0,
            heading: 0.0,
        };
        let mut x = start;
        let relaxed: Vec<FrameControl> = (0..400)
            .map(|_| {
                let u = FrameControl {
                    sigma: 0.0,
                    c: fl.c_plan_max(x.speed),
                };
                x = frame(&x, u, &fl, false).0;
                u
            })
            .collect();
        let exact: Vec<FrameControl> = relaxed
            .iter()
            .enumerate()
            .map(|(k, u)| FrameControl {
                sigma: if k % 2 == 0 { 1.0 } else { -1.0 },
                ..*u
            })
            .collect();
        let end = |controls: &[FrameControl]| rollout(&start, controls, &fl).last().copied();
        let (Some(r), Some(e)) = (end(&relaxed), end(&exact)) else {
            panic!("no frames played");
        };
        let behind_frames = (r.pos.length() - e.pos.length()) / (r.speed * fl.tau_s);
        let estimate = zigzag_frames(&start, &relaxed, &fl);
        assert!(
            estimate > 0.05 && (estimate - behind_frames).abs() < 0.1 * behind_frames,
            "estimate {estimate} frames, behind {behind_frames} frames"
        );
        // Sides at their bound turn without a zigzag.
        let turning: Vec<FrameControl> = exact
            .iter()
            .map(|u| FrameControl { sigma: 1.0, ..*u })
            .collect();
        assert!(zigzag_frames(&start, &turning, &fl) < 1e-12);
    }

    #[test]
    fn the_guard_estimate_is_what_keeping_under_the_kink_loses_on_a_straight() {
        // 1000 fps, air acceleration 10 (the law's first case), 3000 frames from 400 ups: the relaxed
        // straight on the kink against the same straight half an anglemod step under it, each frame's `c`
        // at its own speed. The guarded run falls behind by what the estimate says, to a hundredth (here
        // 0.66213 frame either way; charging each frame's loss to the end unchanged would say 0.82).
        let vars = MovementVars::goldsrc(1000.0);
        let fl = FrameLaw::of(&vars);
        assert!(fl.has_kink_guard());
        let start = ModelState {
            pos: Vec2::ZERO,
            speed: 400.0,
            heading: 0.0,
        };
        let run = |c_of: &dyn Fn(f64) -> f64| {
            let mut x = start;
            let controls: Vec<FrameControl> = (0..3000)
                .map(|_| {
                    let u = FrameControl {
                        sigma: 0.0,
                        c: c_of(x.speed),
                    };
                    x = frame(&x, u, &fl, false).0;
                    u
                })
                .collect();
            (controls, x)
        };
        let (on_kink, r) = run(&|v| fl.c_max(v));
        let (guarded, g) = run(&|v| fl.c_plan_max(v));
        let behind_frames = (r.pos.length() - g.pos.length()) / (r.speed * fl.tau_s);
        let estimate = guard_frames(&start, &on_kink, &fl);
        assert!(
            estimate > 0.1 && (estimate - behind_frames).abs() < 0.01 * behind_frames,
            "estimate {estimate} frames, behind {behind_frames} frames"
        );
        // A plan under the guard already, or in the law's second case (100 fps), loses nothing to it.
        assert!(guard_frames(&start, &guarded, &fl) < 1e-12);
        let fl100 = FrameLaw::of(&MovementVars::goldsrc(100.0));
        let at_100 = [FrameControl {
            sigma: 0.0,
            c: fl100.c_max(400.0),
        }; 100];
        assert!(!fl100.has_kink_guard() && guard_frames(&start, &at_100, &fl100) < 1e-12);
    }

    /// A certifier that tried `tried` starts, reached the line at `fractions` (frame 100 at 100 fps, as a
    /// fraction through it), the fastest from start `best_index`.
    fn certifier_of(tried: usize, fractions: &[f64], best_index: usize) -> Certifier {
        let ends: Vec<(f64, bool)> = fractions.iter().map(|&f| (f, false)).collect();
        certifier_ending(tried, &ends, best_index)
    }

    /// As [`certifier_of`], each start's fraction with whether its search stopped short.
    fn certifier_ending(tried: usize, ends: &[(f64, bool)], best_index: usize) -> Certifier {
        let crossing = |f: f64| Crossing::new(100, f, 0.01);
        let fastest = ends.iter().map(|e| e.0).fold(f64::INFINITY, f64::min);
        Certifier {
            tried,
            ends: ends
                .iter()
                .enumerate()
                .map(|(index, &(f, short))| StartEnd {
                    index,
                    time: crossing(f).time,
                    short,
                })
                .collect(),
            best: Some(CertifiedPlan {
                controls: Vec::new(),
                start_index: best_index,
                crossing: crossing(fastest),
            }),
            greedy_lines: Vec::new(),
        }
    }

    #[test]
    fn the_greedy_line_of_a_frame_is_the_fastest_greedy_starts_line_crossing_in_it_or_before() {
        let line = |index: usize, frame: u64, fraction: f64| CertifiedPlan {
            controls: vec![FrameControl { sigma: 1.0, c: 0.0 }],
            start_index: index,
            crossing: Crossing::new(frame, fraction, 0.01),
        };
        // The relaxed plan's start (no greedy line), then two greedy starts solved apart.
        let mut certifier = certifier_of(1, &[0.5], 0);
        let mut side = certifier_of(2, &[0.6, 0.2], 0);
        side.greedy_lines = vec![line(0, 100, 0.6), line(1, 101, 0.2)];
        certifier.absorb(side);
        let by =
            |c: &Certifier, frame: u64| c.fastest_greedy_line(frame, None).map(|p| p.start_index);
        // Their indices follow the relaxed plan's start; none crosses before frame 100.
        assert_eq!(by(&certifier, 99), None);
        assert_eq!(by(&certifier, 100), Some(1));
        // Frame 101's line is later than frame 100's.
        assert_eq!(by(&certifier, 101), Some(1));
        // A faster line of the same frame is the one.
        certifier.greedy_lines.push(line(3, 100, 0.1));
        assert_eq!(by(&certifier, 100), Some(3));
        // Unless it is the line rounded anyway (another optimum's).
        let except = certifier.fastest_greedy_line(100, Some(3));
        assert_eq!(except.map(|p| p.start_index), Some(1));
    }

    #[test]
    fn starts_solved_apart_follow_in_order_and_win_only_when_strictly_faster() {
        let mut mine = certifier_of(1, &[0.5], 0);
        // A tie does not replace the plan already held, and says so.
        assert!(!mine.absorb(certifier_of(2, &[0.7, 0.5], 1)));
        assert_eq!(mine.best().map(|b| b.start_index), Some(0));
        // A faster plan does, numbered after every start before it.
        assert!(mine.absorb(certifier_of(1, &[0.25], 0)));
        assert_eq!(mine.best().map(|b| b.start_index), Some(3));
        let c = mine
            .certificate()
            .unwrap_or_else(|| panic!("no certificate"));
        assert_eq!((c.starts, c.reached), (4, 4));
        assert!((c.spread - 0.0045).abs() < 1e-12, "{c:?}");
        // A certifier whose starts reached nothing adds its starts only.
        assert!(!mine.absorb(Certifier {
            tried: 2,
            ..Certifier::default()
        }));
        let c = mine
            .certificate()
            .unwrap_or_else(|| panic!("no certificate"));
        assert_eq!((c.starts, c.reached), (6, 4));
    }

    #[test]
    fn a_later_start_is_another_line_only_when_ahead_of_the_first_by_more_than_the_tolerance() {
        // Through frame 100 at 100 fps: the first start at 0.5 of the frame, the second 1e-5 of a frame
        // (1e-7 s) before it; the frame to beat is the same.
        let c = certifier_of(2, &[0.5, 0.5 - 1e-5], 1);
        assert!(c.another_optimum(1e-6, 100).is_none());
        assert_eq!(c.another_optimum(1e-8, 100).map(|b| b.start_index), Some(1));
        // The first start's own line is not another while it crosses in the frame to beat.
        let first_fastest = certifier_of(2, &[0.4, 0.5], 0);
        assert!(first_fastest.another_optimum(0.0, 100).is_none());
        // Where the first start reached nothing, a later start's line is the only one.
        let mut first_short = Certifier {
            tried: 1,
            ..Certifier::default()
        };
        first_short.absorb(certifier_of(1, &[0.5], 0));
        assert_eq!(
            first_short.another_optimum(1.0, 100).map(|b| b.start_index),
            Some(1)
        );
    }

    #[test]
    fn a_line_a_frame_ahead_of_the_frame_to_beat_is_another_whichever_start_found_it() {
        // The frame to beat is 101; the certificate's starts cross in frame 100.
        let first_fastest = certifier_of(2, &[0.4, 0.5], 0);
        assert_eq!(
            first_fastest
                .another_optimum(1.0, 101)
                .map(|b| b.start_index),
            Some(0)
        );
        let second_fastest = certifier_of(2, &[0.5, 0.5 - 1e-5], 1);
        assert_eq!(
            second_fastest
                .another_optimum(1.0, 101)
                .map(|b| b.start_index),
            Some(1)
        );
    }

    #[test]
    fn a_start_stopped_short_of_its_optimum_counts_for_the_fastest_but_not_the_spread() {
        // Starts at 0.5, 0.2 (short, the fastest) and 0.9 through frame 100 at 100 fps; one more tried.
        let c = certifier_ending(4, &[(0.5, false), (0.2, true), (0.9, false)], 1)
            .certificate()
            .unwrap_or_else(|| panic!("no certificate"));
        assert_eq!((c.starts, c.reached, c.short), (4, 3, 1));
        assert!(
            (c.time - Crossing::new(100, 0.2, 0.01).time).abs() < 1e-12,
            "{c:?}"
        );
        // The slowest start at its optimum less the fastest: 0.9 - 0.2 of a frame.
        assert!((c.spread - 0.007).abs() < 1e-12, "{c:?}");
        // A slow start stopped short widens nothing: only the fastest at its optimum then counts.
        let c = certifier_ending(2, &[(0.5, false), (0.9, true)], 0)
            .certificate()
            .unwrap_or_else(|| panic!("no certificate"));
        assert_eq!((c.reached, c.short), (2, 1));
        assert!(c.spread.abs() < 1e-12, "{c:?}");
    }

    #[test]
    fn a_count_search_whose_stages_run_out_still_improving_says_it_stopped_short() {
        // The one-corner staircase from its greedy seed, to the certificate's problem: with two SCP
        // iterations a count every stage ends at its cap, and the search stops while still improving;
        // with the settings' own cap it ends where one frame fewer cannot reach the line.
        let scene = staircase_scene(1);
        let (sim, bound, base) = planning_inputs(&scene);
        let search = CountSearch::per_frame(Relaxation::certificate());
        let mut ends = Vec::new();
        for relaxed_iters in [2, SearchSettings::for_quality(Quality::Fast).relaxed_iters] {
            let settings = SearchSettings {
                relaxed_iters,
                ..SearchSettings::for_quality(Quality::Fast)
            };
            let budget = Budget::unlimited();
            let mut planner = Planner::new(&scene, &sim, &settings, &bound, base.seed(), budget);
            let warm = planner.warm_start(base.seed());
            let n = warm.len();
            let d = count_search(&mut planner, &mut |_| {}, warm, n, 0, search);
            let frames = d.line.as_ref().map(Vec::len);
            ends.push((frames, d.short));
        }
        let [(capped_frames, capped_short), (full_frames, full_short)] = ends[..] else {
            panic!("{ends:?}");
        };
        assert!(capped_short && !full_short, "{ends:?}");
        assert!(capped_frames.is_some() && full_frames.is_some(), "{ends:?}");
        assert!(full_frames <= capped_frames, "{ends:?}");
    }

    #[test]
    fn a_count_search_goes_back_to_a_line_its_capped_stage_left_still_improving() {
        // The one-corner staircase from its greedy seed, five SCP iterations a count: stages stop at
        // their cap still improving, and a count below the best line is not reached from it. The search
        // then solves the best line's count again, from that line, before it gives the count below up;
        // with no returns allowed it gives it up at once.
        let scene = staircase_scene(1);
        let search = CountSearch::per_frame(Relaxation::certificate());
        let searched = |capped_line_returns: usize| {
            let settings = SearchSettings {
                relaxed_iters: 5,
                capped_line_returns,
                ..SearchSettings::for_quality(Quality::Fast)
            };
            with_planner(&scene, &settings, |planner, base, _| {
                let warm = planner.warm_start(base.seed());
                let n = warm.len();
                let mut line = None;
                let tried = counts_and_crossings(|record| {
                    line = count_search(planner, record, warm, n, 0, search).line;
                });
                let line = line.unwrap_or_else(|| panic!("no line: {tried:?}"));
                // The line returned is the fastest any count reached.
                let fastest = tried.iter().filter_map(|t| t.1).min();
                assert_eq!(Some(line.len()), fastest, "{tried:?}");
                tried
            })
        };
        // A count not reached, below a line already found, followed by that line's own count.
        let went_back = |tried: &[(usize, Option<usize>)]| {
            tried.windows(2).enumerate().any(|(i, w)| {
                let best_before = tried[..i].iter().filter_map(|t| t.1).min();
                w[0].1.is_none() && best_before.is_some_and(|b| w[0].0 < b && w[1].0 == b)
            })
        };
        let with_returns = searched(SearchSettings::for_quality(Quality::Fast).capped_line_returns);
        assert!(went_back(&with_returns), "{with_returns:?}");
        let without = searched(0);
        assert!(!went_back(&without), "{without:?}");
        // Without returns the search ends at the count below its line (continued at that count while
        // its own stages stop at their cap).
        let line = without.iter().filter_map(|t| t.1).min();
        assert!(
            without
                .iter()
                .all(|t| t.1.is_some() || Some(t.0 + 1) == line),
            "{without:?}"
        );
    }

    /// The frame counts a search reports (through `search`'s progress callback) as it tries them, each
    /// with the frame its line crosses in where it reaches the line cleanly.
    fn counts_and_crossings(
        search: impl FnOnce(&mut dyn FnMut(Progress)),
    ) -> Vec<(usize, Option<usize>)> {
        stages_tried(search)
            .into_iter()
            .flat_map(|(_, counts)| counts)
            .collect()
    }

    /// A stage of a descent as it reports it: its planning step (frames per knot) with the counts tried
    /// over it, in frames, each with the frame its line crosses in where it reaches the line cleanly.
    type StageTried = (u32, Vec<(usize, Option<usize>)>);

    /// The stages of a descent as it reports them ([`StageTried`]); consecutive counts over the same step
    /// are one stage.
    fn stages_tried(search: impl FnOnce(&mut dyn FnMut(Progress))) -> Vec<StageTried> {
        let mut stages: Vec<StageTried> = Vec::new();
        search(&mut |p| {
            if let Progress::FrameCount {
                frames,
                frames_per_step,
                reached,
            } = p
            {
                match stages.last_mut() {
                    Some((step, counts)) if *step == frames_per_step => {
                        counts.push((frames, reached));
                    }
                    _ => stages.push((frames_per_step, vec![(frames, reached)])),
                }
            }
        });
        stages
    }

    /// The frame counts a search reports as it tries them ([`counts_and_crossings`]).
    fn counts_tried(search: impl FnOnce(&mut dyn FnMut(Progress))) -> Vec<usize> {
        counts_and_crossings(search)
            .into_iter()
            .map(|(frames, _)| frames)
            .collect()
    }

    #[test]
    fn a_greedy_start_of_the_certificate_is_never_solved_over_more_frames_than_its_run() {
        // The first half of a one-corner staircase's greedy seed: the line is out of its reach.
        let scene = staircase_scene(1);
        let (sim, bound, base) = planning_inputs(&scene);
        let budget = Budget::unlimited();
        let settings = SearchSettings::for_quality(Quality::Fast);
        let mut planner = Planner::new(&scene, &sim, &settings, &bound, base.seed(), budget);
        let warm = planner.warm_start(base.seed());
        let half = warm[..warm.len() / 2].to_vec();
        let n = half.len();
        let mut certifier = Certifier::default();
        let planning = Relaxation::planning(planning_margin(&planner));
        let counts = counts_tried(|record| {
            let kind = StartKind::Greedy { planning };
            certifier.add_start(&mut planner, record, half.clone(), kind, 0);
        });
        assert!(!counts.is_empty());
        assert!(counts.iter().all(|&c| c <= n), "{counts:?} against {n}");
        assert!(certifier.certificate().is_none(), "{counts:?}");
        // The relaxed plan's search from the same start grows the count it cannot reach the line in.
        let search = CountSearch::per_frame(Relaxation::certificate());
        let grown = counts_tried(|record| {
            count_search(&mut planner, record, half, n, 0, search);
        });
        assert!(grown.iter().any(|&c| c > n), "{grown:?} against {n}");
    }

    #[test]
    fn a_knot_stage_that_stops_hands_its_line_to_knots_half_as_long() {
        // A four-corner staircase's greedy seed (about 500 frames at 100 fps) as a certificate's greedy
        // start: knots of about five frames, then two, then frames, each stage from the line the one
        // before stopped at.
        let scene = staircase_scene(4);
        let settings = SearchSettings::for_quality(Quality::Fast);
        let (steps, stages) = with_planner(&scene, &settings, |planner, base, _| {
            let warm = planner.warm_start(base.seed());
            let n = warm.len();
            let planning = Relaxation::planning(planning_margin(planner));
            let first = coarse_knot_frames(n, CoarseRuns::AlsoShort);
            let stages = stages_tried(|record| {
                let descent = Descent::greedy_start(planning);
                relaxed_plan(
                    planner,
                    record,
                    warm,
                    n,
                    0,
                    Relaxation::certificate(),
                    descent,
                );
            });
            let mut steps = vec![first];
            while let Some(&last) = steps.last().filter(|&&s| s > 1) {
                steps.push(finer_knot_frames(last));
            }
            (steps, stages)
        });
        assert!(steps.len() >= 3, "{steps:?}");
        let tried: Vec<u32> = stages.iter().map(|s| s.0).collect();
        assert_eq!(tried, steps, "{stages:?}");
        let best = |counts: &[(usize, Option<usize>)]| counts.iter().filter_map(|c| c.1).min();
        for pair in stages.windows(2) {
            let [(coarse, coarser), (fine, finer)] = pair else {
                unreachable!()
            };
            let Some(line) = best(coarser) else {
                panic!("knots of {coarse} reached no line: {coarser:?}")
            };
            // The finer stage starts from the coarser line (its last knot may run on a few frames past
            // it), and ends no later.
            let start = finer.first().map_or(0, |c| c.0);
            let fine = *fine as usize;
            assert!(
                start >= line && start < line + fine,
                "{coarse} -> {fine}: {start} from {line}"
            );
            assert!(
                best(finer).is_some_and(|b| b <= line),
                "{coarse} -> {fine}: {finer:?}"
            );
        }
    }

    #[test]
    fn a_greedy_start_whose_knots_reach_no_clean_line_descends_at_the_planning_margin_first() {
        // Generated scene 23 of seed 97 (CI-sized: 100 fps, air acceleration 10, 66 units wide, a plan
        // of 354 frames), its second clean greedy run: averaged over knots it runs into the walls, so its
        // knots are fitted to the run, and their line stops at 484 frames. Measured with Clarabel on
        // every sub-problem: descending at the planning margin first it ends at the plan's 354 frames; at
        // the certificate's margin alone it stays at 484. Where this start's descent ends depends on the
        // sub-problems' numerics: with the frame-by-frame solver it ends at 443 frames first and finds no
        // line at the certificate's margin alone (the solve as a whole reaches 354 through its other
        // starts). Under either solver the planning margin first ends at least ten frames sooner.
        use crate::scene::generate::{generate, GeneratorSettings};
        let g = generate(97, 23, &GeneratorSettings::ci_sized()).unwrap_or_else(|e| panic!("{e}"));
        for solver in [SubProblemSolver::Clarabel, SubProblemSolver::Riccati] {
            let settings = SearchSettings {
                sub_problem_solver: solver,
                ..SearchSettings::for_quality(Quality::Fast)
            };
            let ends = with_planner(&g.scene, &settings, descent_ends_from_second_greedy_run);
            if solver == SubProblemSolver::Clarabel {
                assert!(ends[0] <= 355, "{ends:?}");
            }
            assert!(ends[0] + 10 <= ends[1], "{solver:?}: {ends:?}");
        }
    }

    /// Where the relaxed plan from the second clean greedy run ends (its crossing frame, `u64::MAX` for
    /// none), descending at the planning margin first and at the certificate's margin alone.
    fn descent_ends_from_second_greedy_run(
        planner: &mut Planner,
        base: &crate::optimise::baseline::Baseline,
        _: &crate::optimise::LowerBound,
    ) -> Vec<u64> {
        let warm = planner.warm_start(&base.clean[1].trace);
        let n = warm.len();
        let planning = Relaxation::planning(planning_margin(planner));
        let certificate = Relaxation::certificate();
        let mut ends = Vec::new();
        for first in [Some(planning), None] {
            let descent = Descent {
                after_unclear_knots: first,
                ..Descent::greedy_start(planning)
            };
            let mut line = None;
            let counts = counts_tried(|record| {
                let start = warm.clone();
                line = relaxed_plan(planner, record, start, n, 0, certificate, descent).line;
            });
            // Knots first: the count search's first count is theirs.
            let knot = coarse_knot_frames(n, CoarseRuns::AlsoShort) as usize;
            assert!(knot > 1, "{knot}");
            assert!(counts.first().is_some_and(|&c| c % knot == 0), "{counts:?}");
            let frames = line
                .as_deref()
                .and_then(|l| planner.crossing_of(l))
                .map_or(u64::MAX, |c| c.frames);
            ends.push(frames);
        }
        ends
    }

    #[test]
    fn long_runs_and_greedy_starts_of_200_frames_or_more_are_planned_over_knots_first() {
        // About 400 knots from 800 frames on; below, about 100 knots from 200 frames for the certificate's
        // greedy starts only.
        let cases = [
            (150, 1, 1),
            (199, 1, 1),
            (200, 1, 2),
            (450, 1, 4),
            (799, 1, 7),
            (800, 2, 2),
            (3174, 7, 7),
            (3368, 8, 8),
        ];
        for (frames, long, also_short) in cases {
            assert_eq!(
                coarse_knot_frames(frames, CoarseRuns::Long),
                long,
                "{frames}"
            );
            assert_eq!(
                coarse_knot_frames(frames, CoarseRuns::AlsoShort),
                also_short,
                "{frames}"
            );
        }
    }
}
