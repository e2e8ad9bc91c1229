//! Rounding: from the relaxed plan's continuous sides to the game's `+-1` (docs/physics.md section 5: a
//! frame's wish direction is on one side of the velocity or the other).

use super::model::{frame, rollout, FrameControl, FrameLaw, ModelState};
use crate::budget::{Budget, FRAMES_PER_BUDGET_CHECK};

/// How far ahead a heading error is weighed by the side rounding, seconds.
pub(super) const ROUNDING_HORIZON_S: f64 = 0.05;
/// The horizons the sides are rounded with, seconds, each rounding polished and verified as a candidate:
/// a longer horizon keeps the heading closer to the relaxed line's for more cross-track error now, so
/// through a turn it carries the sides' phase otherwise, and which phase polishes to the faster plan shows
/// only after polishing. A third, shorter horizon (0.02 s) was tried beside these and added almost
/// nothing for its cost (docs/design.md, "What rounding costs").
pub(super) const ROUNDING_HORIZONS_S: [f64; 2] = [ROUNDING_HORIZON_S, 0.15];
/// Side sequences kept by the rounding's beam search.
const ROUNDING_BEAM: usize = 64;

/// Rounds relaxed sides to `+-1`: a beam search over side sequences that keeps the exact trajectory on the
/// relaxed one. A sequence's cost adds, each frame, the squared position error and the squared distance
/// its heading error would drift over `horizon_s` seconds. Rounding frame by frame keeps the heading error
/// bounded but not zero-mean where the relaxed sides saturate, and a steady heading error of a few
/// hundredths of a radian drifts the path by tens of units.
/// `None` when `budget` runs out first.
pub(super) fn round_sides(
    start: &ModelState,
    controls: &[FrameControl],
    fl: &FrameLaw,
    horizon_s: f64,
    budget: &Budget,
) -> Option<Vec<FrameControl>> {
    let relaxed = rollout(start, controls, fl);
    // Beam entries: (cost, state, index into the history of choices).
    let mut history: Vec<(usize, f64)> = Vec::with_capacity(controls.len() * ROUNDING_BEAM * 2);
    let mut beam: Vec<(f64, ModelState, usize)> = vec![(0.0, *start, usize::MAX)];
    for (k, u) in controls.iter().enumerate() {
        if k as u64 % FRAMES_PER_BUDGET_CHECK == 0 && budget.expired() {
            return None;
        }
        let target = relaxed[k];
        let mut next: Vec<(f64, ModelState, usize)> = Vec::with_capacity(beam.len() * 2);
        for &(cost, x, h) in &beam {
            for sigma in [1.0, -1.0] {
                let y = frame(&x, FrameControl { sigma, c: u.c }, fl, false).0;
                // Cross-track error only: every side sequence falls behind the relaxed line along the
                // track alike (the zigzag of alternating sides shortens each move by about
                // 1 - cos(delta / 2)), which the polish of `c` then trades off.
                let normal = crate::physics::Vec2::from_angle(target.heading).perp();
                let cross = (y.pos - target.pos).dot(normal);
                let dpos = cross * cross;
                let drift = (y.heading - target.heading) * y.speed * horizon_s;
                history.push((h, sigma));
                next.push((cost + dpos + drift * drift, y, history.len() - 1));
            }
        }
        next.sort_by(|a, b| a.0.total_cmp(&b.0));
        next.truncate(ROUNDING_BEAM);
        beam = next;
    }
    let mut sides = Vec::with_capacity(controls.len());
    let mut h = beam.first().map_or(usize::MAX, |b| b.2);
    while h != usize::MAX {
        let (parent, sigma) = history[h];
        sides.push(sigma);
        h = parent;
    }
    sides.reverse();
    Some(
        controls
            .iter()
            .zip(sides)
            .map(|(u, sigma)| FrameControl { sigma, c: u.c })
            .collect(),
    )
}
