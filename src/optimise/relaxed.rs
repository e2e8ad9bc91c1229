//! The relaxed stage: sides continuous in `[-1, 1]` (the limit of fast left/right alternation, see
//! [`super::model`]), so that every exact plan is one of its points. Min-time is fixed-N maximal progress
//! plus a search over N: SCP at a frame count N, then N lowered to the frame before the plan's crossing
//! until the line can no longer be reached. On long runs the search first runs over knots of several
//! frames played with one control (coarse to fine).

use super::model::{rollout_knots, FrameControl};
use super::planner::Planner;
use super::scp::model_crossing;
use super::search::Progress;

/// Times a relaxed stage that stopped at its iteration cap without a clean crossing is continued at the
/// same count before the count is given up.
const MAX_CONTINUED_STAGES: usize = 3;

/// About this many knots make the coarse stage (the planning steps of a 100 fps run of four seconds).
const COARSE_KNOTS: usize = 400;

/// Times a frame count that the line cannot be reached in is grown before the search gives up.
const MAX_GROW_TRIES: usize = 3;

/// Frames per knot of the coarse stage for a run of about `frames` frames: knots of several frames
/// once the run is long enough that about [`COARSE_KNOTS`] knots cover it, else 1 (no coarse stage).
pub(super) fn coarse_knot_frames(frames: usize) -> u32 {
    u32::try_from(frames / COARSE_KNOTS)
        .unwrap_or(u32::MAX)
        .max(1)
}

/// The relaxed plan at wall `margin` (units) from the warm start `controls`, whose line crossing is near
/// frame `n`; no plan crosses before frame `lo` (the lower bound's). Coarse to fine on long runs. Returns
/// the best clean plan, cut at its crossing frame.
pub(super) fn relaxed_plan(
    planner: &mut Planner,
    progress: &mut dyn FnMut(Progress),
    mut controls: Vec<FrameControl>,
    mut n: usize,
    lo: usize,
    margin: f64,
) -> Option<Vec<FrameControl>> {
    let knot_frames = coarse_knot_frames(n);
    if knot_frames > 1 {
        let m = knot_frames as usize;
        let knots: Vec<FrameControl> = controls[..n.min(controls.len())]
            .chunks(m)
            .map(|chunk| {
                let k = chunk.len() as f64;
                FrameControl {
                    sigma: chunk.iter().map(|u| u.sigma).sum::<f64>() / k,
                    c: chunk.iter().map(|u| u.c).sum::<f64>() / k,
                }
            })
            .collect();
        // The chord of a knot leaves its frames' arc by at most the sagitta m^2 tau gamma1 / 8 (each frame
        // turns the heading by at most about gamma1 / V).
        let fl = planner.fl;
        let sagitta = (m * m) as f64 * fl.tau_s * fl.law.gamma1 / 8.0;
        let count = knots.len();
        if let Some(plan) = count_search(
            planner,
            progress,
            knots,
            count,
            lo / m,
            margin + sagitta,
            knot_frames,
        ) {
            controls = plan
                .iter()
                .flat_map(|u| std::iter::repeat_n(*u, m))
                .collect();
            n = controls.len();
        }
    }
    count_search(planner, progress, controls, n, lo, margin, 1)
}

/// The search over the number of planning steps (frames or knots of `frames_per_knot` frames): SCP at `n`
/// steps from `controls`, then at one step fewer than the plan's crossing, until the line is no longer
/// reached (or `lo` steps, below which the bound says it cannot be); more steps if the first count does
/// not reach it. Returns the best clean plan, cut at its crossing step.
pub(super) fn count_search(
    planner: &mut Planner,
    progress: &mut dyn FnMut(Progress),
    mut controls: Vec<FrameControl>,
    mut n: usize,
    lo: usize,
    margin: f64,
    frames_per_knot: u32,
) -> Option<Vec<FrameControl>> {
    let fl = planner.fl;
    let relaxed_iters = planner.settings.relaxed_iters;
    let mut best: Option<Vec<FrameControl>> = None;
    let mut grow_tries = 0;
    let mut continue_tries = 0;
    loop {
        if planner.out_of_time() {
            break;
        }
        controls.resize(
            n,
            FrameControl {
                sigma: 0.0,
                c: fl.c_max(f64::INFINITY),
            },
        );
        planner.stats.frame_counts_tried += 1;
        let pr = planner.problem(margin, true, frames_per_knot);
        let (c, capped) = planner.stage(pr, controls.clone(), relaxed_iters);
        let states = rollout_knots(&planner.start, &c, &fl, frames_per_knot);
        let reached = model_crossing(&planner.start, &states, planner.scene);
        let clean = planner
            .problem(margin, true, frames_per_knot)
            .violation(&states)
            <= super::scp::CLEAN_VIOLATION_UNITS;
        let per = frames_per_knot as usize;
        progress(Progress::FrameCount {
            frames: n * per,
            reached: reached.filter(|_| clean).map(|k| k * per),
        });
        match reached {
            Some(k) if clean => {
                best = Some(c[..k].to_vec());
                // One step short of this plan's crossing, warm-started from it: each solve keeps
                // improving the same line (stepping further on a failed probe proves nothing, the
                // search being local).
                if k <= lo + 1 || planner.timed_out {
                    break;
                }
                n = k - 1;
                controls = c[..n].to_vec();
            }
            _ if capped && continue_tries < MAX_CONTINUED_STAGES && !planner.timed_out => {
                // The stage ran out of iterations still improving (a start far from the line: the
                // capped greedy run of a narrow bend at 1000 fps): go on at the same count.
                continue_tries += 1;
                controls = c;
            }
            _ => {
                if best.is_some() || grow_tries >= MAX_GROW_TRIES || planner.timed_out {
                    break;
                }
                // Not reachable at this count from this start: give it more steps.
                grow_tries += 1;
                n += (n / 20).max(2);
                controls = c;
            }
        }
    }
    best
}
