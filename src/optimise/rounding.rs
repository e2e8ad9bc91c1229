//! Rounding: from the relaxed plan's continuous sides to the game's `+-1` (docs/physics.md section 5: a
//! frame's wish direction is on one side of the velocity or the other).

use super::model::{anglemod_step_ups, frame, rollout, FrameControl, FrameLaw, ModelState};
use crate::budget::{Budget, FRAMES_PER_BUDGET_CHECK};
use crate::physics::Vec2;

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
/// Bisections of `c` for a frame that turns onto the relaxed heading: the turn to `2^-30` of the
/// frame's `c` range.
const ON_TARGET_BISECTIONS: usize = 30;
/// A relaxed side at least this large is at its bound: the relaxed line turns as fast as a frame can, and
/// sides of `+-1` can no longer take back a heading error, only a frame that turns less. The relaxed
/// sub-problems put a side on its bound to their solver's tolerance (about `1e-8`); sides within a
/// thousandth of it drift a path by at most a thousandth of a turn a frame.
const SATURATED_SIDE: f64 = 1.0 - 1e-3;
/// How far the rounding may trim a frame's `c` off the relaxed one, either way, where the relaxed side is
/// inside its bounds: this share of `L` in the law's second case ([`trim_scale_ups`]; 0.9 ups), which
/// turns a frame by about that share of its turn more or less ([`trimmed_frames`]). Its size is not
/// tuned: shares of 0.01, 0.03 and 0.1 won the same frames on the CI-sized family of seed 11
/// (docs/design.md, "Keeping the sides centred on a straight: trimmed frames").
const PHASE_TRIM_SHARE: f64 = 0.03;

/// Rounds relaxed sides to `+-1`: a beam search over side sequences that keeps the exact trajectory on the
/// relaxed one. A sequence's cost adds, each frame, the squared cross-track error and the squared distance
/// its heading error would drift while it cannot be taken back: over `horizon_s` seconds, or to the end of
/// a run of relaxed sides at their bound that the next frame starts or is in (there sides of `+-1` turn as
/// the relaxed line does and keep whatever heading error they carry in). Rounding frame by frame keeps the
/// heading error bounded but not zero-mean where the relaxed sides saturate, and a steady heading error of
/// a few hundredths of a radian drifts the path by tens of units.
///
/// At such a run and the frame before it, each sequence may also play the frame that turns onto the
/// relaxed heading exactly ([`on_target_frame`]), paying once for the speed it gains otherwise, as the
/// distance that puts it off the line by the end of the plan. A relaxed side counts as at its bound
/// from [`SATURATED_SIDE`]. Elsewhere it may play a frame trimmed a little ([`trimmed_frames`]), paying
/// likewise: that keeps the alternating sides centred on the relaxed heading.
/// `None` when `budget` runs out first.
pub(super) fn round_sides(
    start: &ModelState,
    controls: &[FrameControl],
    fl: &FrameLaw,
    horizon_s: f64,
    budget: &Budget,
) -> Option<Vec<FrameControl>> {
    round_sides_trimmed(start, controls, fl, horizon_s, PHASE_TRIM_SHARE, budget)
}

/// [`round_sides`] with frames trimmed by `trim_share` of [`trim_scale_ups`] (0: none).
pub(super) fn round_sides_trimmed(
    start: &ModelState,
    controls: &[FrameControl],
    fl: &FrameLaw,
    horizon_s: f64,
    trim_share: f64,
    budget: &Budget,
) -> Option<Vec<FrameControl>> {
    let trim_ups = trim_share * trim_scale_ups(fl);
    let relaxed = rollout(start, controls, fl);
    let frames = controls.len();
    // The kept sequences' choices, each with the index of the choice before it.
    let mut history: Vec<(usize, FrameControl)> = Vec::with_capacity(frames * ROUNDING_BEAM);
    let mut beam = vec![Sequence {
        cost: 0.0,
        state: *start,
        last: usize::MAX,
        behind_units: 0.0,
    }];
    let held_s = saturated_runs_s(controls, fl.tau_s);
    for (k, u) in controls.iter().enumerate() {
        if k as u64 % FRAMES_PER_BUDGET_CHECK == 0 && budget.expired() {
            return None;
        }
        // The run of saturated sides the next frame starts or is in, seconds (0 if none); a frame
        // that turns less is offered in such a run and the frame before it, a trimmed frame elsewhere.
        let next_run_s = held_s.get(k + 1).copied().unwrap_or(0.0);
        let saturated = held_s[k] > 0.0 || next_run_s > 0.0;
        let target = Target {
            relaxed: relaxed[k],
            normal: Vec2::from_angle(relaxed[k].heading).perp(),
            held_s: horizon_s.max(next_run_s),
            remaining_s: (frames - k - 1) as f64 * fl.tau_s,
        };
        let trim = if saturated { 0.0 } else { trim_ups };
        // Each sequence one frame on, with its last choice (its `last` still its parent's).
        let mut next: Vec<(Sequence, FrameControl)> = Vec::with_capacity(beam.len() * 6);
        for seq in &beam {
            let x = seq.state;
            let sides = [1.0, -1.0].map(|sigma| {
                let choice = FrameControl { sigma, c: u.c };
                (choice, frame(&x, choice, fl, false).0, false)
            });
            // Sides of `+-1` at the relaxed `c` reach the relaxed frame's speed (`V'` does not depend
            // on the side).
            let relaxed_speed = sides[0].1.speed;
            let on_target = saturated
                .then(|| on_target_frame(&x, target.relaxed.heading, u.c, fl))
                .flatten();
            let paying = on_target
                .into_iter()
                .chain(trimmed_frames(&x, *u, trim, fl))
                .map(|choice| (choice, frame(&x, choice, fl, false).0, true));
            for (choice, y, pays_speed) in sides.into_iter().chain(paying) {
                let extended = seq.extended(y, pays_speed.then_some(relaxed_speed), &target);
                next.push((extended, choice));
            }
        }
        beam = kept(next, &mut history);
    }
    Some(traced_back(beam.first(), &history))
}

/// What a frame's choices are judged against: the relaxed line's state after the frame, the normal of
/// its heading, how long a heading error is held ([`round_sides`]) and the plan's time left after it.
struct Target {
    relaxed: ModelState,
    normal: Vec2,
    held_s: f64,
    remaining_s: f64,
}

impl Sequence {
    /// This sequence one frame on to `y`, its cost grown by the frame's errors against `target`; a frame
    /// that gives up speed against the relaxed frame's `relaxed_speed` (ups) pays for it too.
    fn extended(&self, y: ModelState, relaxed_speed: Option<f64>, target: &Target) -> Sequence {
        // Across the track and the heading only: the zigzag of alternating sides shortens each move
        // along the track by about `1 - cos(e)` of a heading error `e`, which the heading's term weighs
        // too.
        let cross = (y.pos - target.relaxed.pos).dot(target.normal);
        let drift = (y.heading - target.relaxed.heading) * y.speed * target.held_s;
        // A frame that turns less, or is trimmed, gives up speed against the relaxed frame, which by the
        // end of the plan puts the sequence that distance behind the line; the cost carries the square
        // of that distance, summed over the sequence's frames (many small trims add up as one large one).
        let behind_units = match relaxed_speed {
            Some(v) => self.behind_units + (v - y.speed) * target.remaining_s,
            None => self.behind_units,
        };
        let cost = self.cost + cross * cross + drift * drift + behind_units * behind_units
            - self.behind_units * self.behind_units;
        Sequence {
            cost,
            state: y,
            last: self.last,
            behind_units,
        }
    }
}

/// The [`ROUNDING_BEAM`] cheapest of `next` (each a sequence one frame on and its last choice), cheapest
/// first, their choices added to `history`.
fn kept(
    mut next: Vec<(Sequence, FrameControl)>,
    history: &mut Vec<(usize, FrameControl)>,
) -> Vec<Sequence> {
    let by_cost =
        |a: &(Sequence, FrameControl), b: &(Sequence, FrameControl)| a.0.cost.total_cmp(&b.0.cost);
    if next.len() > ROUNDING_BEAM {
        next.select_nth_unstable_by(ROUNDING_BEAM, by_cost);
        next.truncate(ROUNDING_BEAM);
    }
    next.sort_by(by_cost);
    next.into_iter()
        .map(|(seq, choice)| {
            history.push((seq.last, choice));
            Sequence {
                last: history.len() - 1,
                ..seq
            }
        })
        .collect()
}

/// The choices of `best` from the first frame on, traced back through `history`.
fn traced_back(best: Option<&Sequence>, history: &[(usize, FrameControl)]) -> Vec<FrameControl> {
    let mut rounded = Vec::new();
    let mut h = best.map_or(usize::MAX, |b| b.last);
    while h != usize::MAX {
        let (parent, u) = history[h];
        rounded.push(u);
        h = parent;
    }
    rounded.reverse();
    rounded
}

/// The `c` a trim is a share of, ups: `L` in the law's second case (`gamma1 > L`), where the maximum
/// acceleration is at `c = 0` and the speed gained, `V'^2 = V^2 + L^2 - c^2`, is stationary there, so a
/// trim gives up only the square of its size; zero in the first, where the maximum acceleration is at the
/// law's kink and a trim either way gives up speed in proportion to its size (`2 gamma1` of `V'^2` an ups
/// below the kink), which the heading it sets back does not repay (a straight at 250 fps from 200 ups,
/// trimmed, ended five times further behind its relaxed line than with the relaxed `c`).
fn trim_scale_ups(fl: &FrameLaw) -> f64 {
    if fl.has_kink_guard() {
        0.0
    } else {
        fl.law.l
    }
}

/// A side sequence of the rounding's beam.
#[derive(Clone, Copy)]
struct Sequence {
    /// Its cost so far (see [`round_sides`]).
    cost: f64,
    /// The state after its last frame.
    state: ModelState,
    /// Its last choice's index in the beam's history (`usize::MAX`: none yet).
    last: usize,
    /// How far behind the relaxed line the speed its frames gave up puts it by the end of the plan,
    /// units.
    behind_units: f64,
}

/// Per frame, how long from it the relaxed sides stay at their bound, seconds (0 where they are not):
/// a heading error the rounded plan carries into such a run stays through it.
fn saturated_runs_s(controls: &[FrameControl], tau_s: f64) -> Vec<f64> {
    let mut held = vec![0.0; controls.len()];
    let mut run = 0.0;
    for (k, u) in controls.iter().enumerate().rev() {
        run = if u.sigma.abs() >= SATURATED_SIDE {
            run + tau_s
        } else {
            0.0
        };
        held[k] = run;
    }
    held
}

/// The frames from `x` with the relaxed control `u`'s `c` trimmed by `trim_ups` either way, on either
/// side, within the `c` a plan with exact sides may use (from [`FrameLaw::c_min`] to
/// [`FrameLaw::c_exact_max`]). Sides of `+-1` at one `c` swing the heading a turn `delta` a frame, at best
/// centred on the relaxed heading (`+-delta / 2`, each move `(delta / 2)^2 / 2` of its length short), at
/// worst with one move on it (`0` and `delta`: twice the loss). `delta` falls as the speed rises (about
/// `min(L, gamma1) / V`), so a phase set once drifts off centre, and at the relaxed `c` the sides can take
/// it back only by playing one side twice, which swings the heading `3 delta / 2` off for a frame. A
/// trimmed frame turns by about `trim_ups / V` more or less, and in the law's second case, off the
/// maximum-acceleration `c = 0`, gains `V'^2 = V^2 + L^2 - c^2`: the speed it gives up grows as the square
/// of the trim, so a phase taken back over many small trims costs less than over few large ones.
/// Empty for a trim of zero.
fn trimmed_frames(
    x: &ModelState,
    u: FrameControl,
    trim_ups: f64,
    fl: &FrameLaw,
) -> impl Iterator<Item = FrameControl> {
    let (lo, hi) = (fl.c_min(x.speed), fl.c_exact_max(x.speed));
    [u.c + trim_ups, u.c - trim_ups]
        .into_iter()
        .filter(move |c| trim_ups > 0.0 && (lo..=hi).contains(c))
        .flat_map(|c| [1.0, -1.0].map(|sigma| FrameControl { sigma, c }))
}

/// The frame from `x` that turns the heading onto `heading` exactly, when a frame that turns less than the
/// one of `c` can (a larger `c`, up to [`FrameLaw::c_exact_max`]): with its sides at `+-1`, the rounded
/// heading alternates half a turn either side of a straight relaxed one, and where the relaxed sides then
/// saturate through a turn that half turn stays, drifting the path sideways by half a turn times the
/// turn's length. One such frame sets the phase; it gains speed otherwise, which the beam weighs. Only
/// from a frame that does not brake: from there up to a coasting frame the turn falls as `c` rises
/// (docs/physics.md section 6), so one bisection finds it; a braking frame slows for a reason the
/// rounding cannot see. A frame brakes when its strafe angle is more than an anglemod step past 90
/// degrees (`c < -V q`): in the law's second case the maximum-acceleration frame is at 90 degrees
/// (`c_max = 0`), where the relaxed stage leaves it only to its tolerance, a hair either side, which the
/// game's yaw cannot tell apart (the threshold stays an anglemod step with vectorial compensation too: it
/// is the relaxed stage's hair, not the replay's step).
fn on_target_frame(x: &ModelState, heading: f64, c: f64, fl: &FrameLaw) -> Option<FrameControl> {
    let wanted = heading - x.heading;
    let turn = |c: f64| {
        frame(x, FrameControl { sigma: 1.0, c }, fl, false)
            .0
            .heading
            - x.heading
    };
    let c_top = fl.c_exact_max(x.speed);
    let braking = c < -anglemod_step_ups(x.speed);
    if braking || c_top <= c || wanted.abs() >= turn(c) || wanted.abs() <= turn(c_top) {
        return None;
    }
    // The turn falls as `c` rises from the maximum-acceleration turn to a coasting frame.
    let (mut lo, mut hi) = (c, c_top);
    for _ in 0..ON_TARGET_BISECTIONS {
        let mid = 0.5 * (lo + hi);
        if turn(mid) > wanted.abs() {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    Some(FrameControl {
        sigma: wanted.signum(),
        c: 0.5 * (lo + hi),
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::optimise::model::AngleControl;
    use crate::physics::{MovementVars, Vec2};

    fn law(fps: f64) -> FrameLaw {
        let vars = MovementVars::goldsrc(fps);
        FrameLaw::of(&vars)
    }

    fn start(speed: f64) -> ModelState {
        ModelState {
            pos: Vec2::ZERO,
            speed,
            heading: 0.0,
        }
    }

    /// A straight of relaxed sides `0`, a frame of half a turn, then a turn at the bound: sides of `+-1`
    /// meet the turn half a turn out of phase, whichever they choose.
    fn straight_then_turn(
        fl: &FrameLaw,
        v: f64,
        straight: usize,
        turn: usize,
    ) -> Vec<FrameControl> {
        let mut controls = Vec::new();
        let mut x = start(v);
        for k in 0..straight + 1 + turn {
            let sigma = match k.cmp(&straight) {
                std::cmp::Ordering::Less => 0.0,
                std::cmp::Ordering::Equal => -0.5,
                std::cmp::Ordering::Greater => -1.0,
            };
            let u = FrameControl {
                sigma,
                c: fl.c_plan_max(x.speed),
            };
            controls.push(u);
            x = frame(&x, u, fl, false).0;
        }
        controls
    }

    #[test]
    fn an_on_target_frame_turns_onto_the_heading_and_gains_less() {
        for (fps, aa) in [(250.0, false), (100.0, true)] {
            let mut fl = law(fps);
            if aa {
                // Air acceleration 100: the law's second case (gamma1 > L).
                fl.law.gamma1 *= 10.0;
            }
            let x = start(450.0);
            let c = fl.c_plan_max(x.speed);
            let full = frame(&x, FrameControl { sigma: -1.0, c }, &fl, false).0;
            let full_turn = x.heading - full.heading;
            for share in [0.1, 0.5, 0.9] {
                let wanted = -share * full_turn;
                let u = on_target_frame(&x, wanted, c, &fl)
                    .unwrap_or_else(|| panic!("{fps} fps: no frame turns {share} of a full turn"));
                let y = frame(&x, u, &fl, false).0;
                assert!(
                    (y.heading - wanted).abs() < 1e-9 * full_turn,
                    "{fps} {share}"
                );
                assert_eq!(u.sigma, -1.0);
                assert!(u.c > c && y.speed < full.speed, "{fps} {share}: {u:?}");
            }
            // More than a full turn, and from a braking frame, there is none.
            assert!(on_target_frame(&x, -1.5 * full_turn, c, &fl).is_none());
            assert!(on_target_frame(&x, -0.5 * full_turn, -100.0, &fl).is_none());
            // A frame a hair past the maximum-acceleration one, as the relaxed stage leaves it (in the
            // second case at 90 degrees, `c = 0`), does not brake, however finely the replay sets the
            // angle (with vectorial compensation its step is 32 times finer than the hair).
            let hair = c - 0.1 * anglemod_step_ups(x.speed);
            for angle_control in [AngleControl::Yaw, AngleControl::Vectorial] {
                let fl = FrameLaw {
                    angle_control,
                    ..fl
                };
                assert!(
                    on_target_frame(&x, -0.5 * full_turn, hair, &fl).is_some(),
                    "{fps} fps, {angle_control:?}"
                );
            }
        }
    }

    /// The rounding of a straight of relaxed sides `0` from `v` ups, `frames` long, under the frame law
    /// `fl` with the frames trimmed by `trim_share`: how far the rounded path ends behind the relaxed one along the
    /// track, and its largest distance across it, units.
    fn straight_rounded(fl: &FrameLaw, v: f64, frames: usize, trim_share: f64) -> (f64, f64) {
        let fl = *fl;
        let x0 = start(v);
        let controls = straight(&fl, v, frames);
        let relaxed = rollout(&x0, &controls, &fl);
        let rounded = round_sides_trimmed(
            &x0,
            &controls,
            &fl,
            ROUNDING_HORIZON_S,
            trim_share,
            &Budget::unlimited(),
        )
        .unwrap_or_else(|| panic!("the unlimited budget ran out"));
        assert!(rounded.iter().all(|u| u.sigma.abs() == 1.0));
        let played = rollout(&x0, &rounded, &fl);
        let across = most_across(&relaxed, &played);
        let (r, p) = (relaxed[frames - 1], played[frames - 1]);
        ((r.pos - p.pos).dot(Vec2::from_angle(r.heading)), across)
    }

    /// The farthest the `played` path is across the track from the `relaxed` one, frame by frame, units.
    fn most_across(relaxed: &[ModelState], played: &[ModelState]) -> f64 {
        relaxed
            .iter()
            .zip(played)
            .map(|(r, p)| {
                (p.pos - r.pos)
                    .dot(Vec2::from_angle(r.heading).perp())
                    .abs()
            })
            .fold(0.0, f64::max)
    }

    /// `frames` frames of relaxed side `0` at the maximum-acceleration `c`, from `v` ups.
    fn straight(fl: &FrameLaw, v: f64, frames: usize) -> Vec<FrameControl> {
        let mut x = start(v);
        (0..frames)
            .map(|_| {
                let u = FrameControl {
                    sigma: 0.0,
                    c: fl.c_plan_max(x.speed),
                };
                x = frame(&x, u, fl, false).0;
                u
            })
            .collect()
    }

    #[test]
    fn trimmed_frames_keep_the_sides_centred_on_a_straight_as_the_turn_shrinks() {
        // From 80 ups at 100 fps a frame turns 0.36 rad, and by 300 frames (about 520 ups) 0.06: the
        // phase of alternating sides drifts off centre all the way. 100 fps with air acceleration 10,
        // and 250 fps with 100, are the law's second case.
        for (fps, aa100, v, frames) in [(100.0, false, 80.0, 300), (250.0, true, 200.0, 500)] {
            let mut fl = law(fps);
            if aa100 {
                fl.law.gamma1 *= 10.0;
            }
            assert!(fl.law.gamma1 > fl.law.l);
            let controls = straight(&fl, v, frames);
            let x0 = start(v);
            let end = rollout(&x0, &controls, &fl)[frames - 1];
            let zigzag_units =
                super::super::relaxed::zigzag_frames(&x0, &controls, &fl) * end.speed * fl.tau_s;
            let (trimmed, across) = straight_rounded(&fl, v, frames, PHASE_TRIM_SHARE);
            let (fixed, _) = straight_rounded(&fl, v, frames, 0.0);
            // Untrimmed, the sides end twice the zigzag's estimate behind (one move of each pair on
            // the relaxed heading); trimmed, a tenth closer at least, never ahead of the estimate (the
            // least any sides can lose), and still on the line across the track.
            assert!(
                trimmed < 0.9 * fixed && trimmed > 0.9 * zigzag_units,
                "{fps} fps: {trimmed} units behind trimmed, {fixed} untrimmed, estimate {zigzag_units}"
            );
            assert!(across < 1.0, "{fps} fps: {across} units across");
        }
        // In the law's first case (250 fps, air acceleration 10) no frame is trimmed: the same sides.
        let fl = law(250.0);
        assert!(fl.law.gamma1 < fl.law.l);
        let untrimmed = straight_rounded(&fl, 200.0, 500, 0.0);
        assert_eq!(
            straight_rounded(&fl, 200.0, 500, PHASE_TRIM_SHARE),
            untrimmed
        );
    }

    #[test]
    fn the_rounded_sides_meet_a_turn_at_the_bound_in_phase() {
        // 250 fps, 450 ups: a 60-frame turn after a 200-frame straight and a half-turn frame. Sides of
        // +-1 alone meet the turn with the heading half a turn (0.014 rad) off either way, and that error
        // stays through the turn: 1.26 units off by its end.
        let fl = law(250.0);
        let x0 = start(450.0);
        let controls = straight_then_turn(&fl, x0.speed, 200, 60);
        let relaxed = rollout(&x0, &controls, &fl);
        let rounded = round_sides(
            &x0,
            &controls,
            &fl,
            ROUNDING_HORIZON_S,
            &Budget::unlimited(),
        )
        .unwrap_or_else(|| panic!("the unlimited budget ran out"));
        let played = rollout(&x0, &rounded, &fl);
        let worst = most_across(&relaxed, &played);
        assert!(
            worst < 0.15,
            "the rounded path is {worst} units off the relaxed one"
        );
        // The phase is set by frames that turn less (then slightly less again as the path, a little
        // slower, turns a little faster), and all of them cost less speed than one frame gains.
        assert!(rounded.iter().zip(&controls).any(|(r, u)| r.c > u.c));
        let gain = frame(&x0, controls[0], &fl, false).0.speed - x0.speed;
        let lost = relaxed[260].speed - played[260].speed;
        assert!(
            lost > 0.0 && lost < gain,
            "{lost} ups lost, a frame gains {gain}"
        );
        assert!(rounded.iter().all(|u| u.sigma.abs() == 1.0));
    }
}
