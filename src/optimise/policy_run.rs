//! What the policy searches of scenes with jumps share ([`super::hops`], [`super::jumps`]): a policy's
//! run checked in both arithmetics, and the rule by which the best one is kept.

use crate::budget::Budget;
use crate::sim::{EngineRun, Simulation, Trace};

/// One evaluated policy: its run and the run's engine-exact replay.
#[derive(Clone, Debug)]
pub struct PolicyRun<P> {
    /// The policy played.
    pub policy: P,
    /// Its run in `f64`.
    pub trace: Trace,
    /// Its controls replayed engine-exact.
    pub engine_exact: EngineRun,
}

impl<P> PolicyRun<P> {
    /// Valid in `f64` and in the engine-exact replay (both cross the line).
    pub fn valid(&self) -> bool {
        self.trace.feasible() && self.engine_exact.feasible()
    }

    /// The `f64` crossing time, seconds; infinite when not valid.
    pub fn time(&self) -> f64 {
        match self.trace.crossing {
            Some(c) if self.valid() => c.time,
            _ => f64::INFINITY,
        }
    }
}

/// Keeps `trace` (played by `policy`) as `best` if it crosses validly in `f64` strictly earlier than
/// `best` and its engine-exact replay, within `replay_budget`, is valid too (only a run that would become
/// the best is replayed). Returns whether it was kept, and whether the budget cut the replay.
pub(super) fn keep_if_better<P>(
    best: &mut Option<PolicyRun<P>>,
    sim: &Simulation,
    policy: P,
    trace: Trace,
    replay_budget: &Budget,
) -> (bool, bool) {
    let t = match trace.crossing {
        Some(c) if trace.feasible() => c.time,
        _ => return (false, false),
    };
    if best.as_ref().is_some_and(|b| t >= b.time()) {
        return (false, false);
    }
    let engine_exact = sim.run_engine_exact_within(&trace.controls, replay_budget);
    let run = PolicyRun {
        policy,
        trace,
        engine_exact,
    };
    let kept = run.valid();
    if kept {
        *best = Some(run);
    }
    (kept, engine_exact.interrupted)
}
