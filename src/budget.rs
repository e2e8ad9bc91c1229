//! The budget of a long computation: a deadline (the `--time-limit`) and a cancel flag (set by a caller
//! that no longer wants the answer, such as an editor re-solving after every edit). Every stage that can
//! run long (the frame loop, the greedy sweeps, the lower bound's schedule search, the optimiser's
//! stages, the engine-exact replay, the jump planner, writing outputs) asks [`Budget::expired`] between
//! units of work and, when it has expired, stops with the best valid result it has.
//!
//! An expired budget is not an error: the result says where it stopped ([`Stop`], [`Stage`]).

use serde::Serialize;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};

/// A deadline and a cancel flag, either optional. `Copy`: each stage takes its own.
#[derive(Clone, Copy, Debug, Default)]
pub struct Budget<'c> {
    deadline: Option<Instant>,
    cancel: Option<&'c AtomicBool>,
}

/// Why a budget ran out.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum Stop {
    /// The deadline passed.
    TimeLimit,
    /// The cancel flag was set.
    Cancelled,
}

impl std::fmt::Display for Stop {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            Stop::TimeLimit => "the time limit",
            Stop::Cancelled => "cancellation",
        })
    }
}

/// The stages of a solve, in the order they run, as the status names them (`stopped_in: "greedy"`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum Stage {
    /// The lower bound: the shortest path and the speed profile (or the jump-schedule search).
    LowerBound,
    /// The greedy strafer over its look-aheads and speed caps.
    Greedy,
    /// The relaxed search over frame counts (the coarse stage included).
    Relaxed,
    /// Rounding the sides to `+-1` and polishing `c`.
    Rounding,
    /// Replaying the plan with quantised yaws and checking it in the engine-exact mode.
    Verification,
    /// The policy search of a jumping scene.
    Jumps,
    /// Writing the requested files.
    Writing,
}

impl Stage {
    /// The name used in statuses and progress lines.
    pub fn name(self) -> &'static str {
        match self {
            Stage::LowerBound => "lower-bound",
            Stage::Greedy => "greedy",
            Stage::Relaxed => "relaxed",
            Stage::Rounding => "rounding",
            Stage::Verification => "verification",
            Stage::Jumps => "jumps",
            Stage::Writing => "writing",
        }
    }
}

impl std::fmt::Display for Stage {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

/// Default of the most frames a solve plans (`--max-frames`): a scene whose lower bound needs more is
/// refused at once, and no run is simulated further. See `docs/limits.md` for the measured memory per
/// planned frame this is chosen from.
pub const DEFAULT_MAX_PLANNED_FRAMES: u64 = 100_000;

/// Frames a frame loop runs between two looks at its budget: an `Instant::now()` costs about as much as
/// a tenth of a frame, so looking every few hundred frames costs nothing measurable and still stops a
/// run within a millisecond.
pub const FRAMES_PER_BUDGET_CHECK: u64 = 256;

impl<'c> Budget<'c> {
    /// No deadline and no cancel flag: never expires.
    pub fn unlimited() -> Self {
        Budget::default()
    }

    /// A budget ending at `deadline` (if any), or earlier when `cancel` (if any) is set.
    pub fn new(deadline: Option<Instant>, cancel: Option<&'c AtomicBool>) -> Self {
        Budget { deadline, cancel }
    }

    /// A budget of `limit` from now (none: no deadline), with `cancel`.
    pub fn from_limit(limit: Option<Duration>, cancel: Option<&'c AtomicBool>) -> Self {
        Budget::new(limit.map(|d| Instant::now() + d), cancel)
    }

    /// The same cancel flag with the earlier of the two deadlines.
    pub fn with_deadline(self, deadline: Option<Instant>) -> Self {
        let deadline = match (self.deadline, deadline) {
            (Some(a), Some(b)) => Some(a.min(b)),
            (a, b) => a.or(b),
        };
        Budget { deadline, ..self }
    }

    /// The deadline, if any.
    pub fn deadline(&self) -> Option<Instant> {
        self.deadline
    }

    /// Why the budget has run out, if it has: the cancel flag first, then the deadline.
    pub fn stop(&self) -> Option<Stop> {
        if self.cancel.is_some_and(|c| c.load(Ordering::Relaxed)) {
            Some(Stop::Cancelled)
        } else if self.deadline.is_some_and(|d| Instant::now() >= d) {
            Some(Stop::TimeLimit)
        } else {
            None
        }
    }

    /// True once the deadline has passed or the cancel flag is set.
    pub fn expired(&self) -> bool {
        self.stop().is_some()
    }

    /// Time left before the deadline (`None`: no deadline); zero once it has passed.
    pub fn remaining(&self) -> Option<Duration> {
        self.deadline
            .map(|d| d.saturating_duration_since(Instant::now()))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_set_flag_expires_at_once_and_says_cancelled() {
        let flag = AtomicBool::new(false);
        let b = Budget::from_limit(Some(Duration::from_secs(3600)), Some(&flag));
        assert_eq!(b.stop(), None);
        flag.store(true, Ordering::Relaxed);
        assert_eq!(b.stop(), Some(Stop::Cancelled));
    }

    #[test]
    fn a_past_deadline_says_time_limit_and_the_earlier_deadline_wins() {
        let now = Instant::now();
        let b = Budget::new(Some(now + Duration::from_secs(3600)), None);
        assert!(!b.expired());
        let b = b.with_deadline(Some(now));
        assert_eq!(b.stop(), Some(Stop::TimeLimit));
        assert_eq!(b.remaining(), Some(Duration::ZERO));
        assert!(!Budget::unlimited().expired());
        assert_eq!(Budget::unlimited().remaining(), None);
    }
}
