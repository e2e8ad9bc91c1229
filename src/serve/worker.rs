//! The solve worker: one solve at a time per server. A new edit replaces a waiting one and cancels the
//! running one; every edit gets exactly one answer (its result, or that a newer edit superseded it), and
//! the last valid result is kept for the downloads.

use crate::error::{Error, Result};
use crate::optimise::search::{self, Progress};
use crate::optimise::{Outcome, Quality, SearchSettings};
use crate::scene::Scene;
use std::collections::HashMap;
use std::panic::{catch_unwind, AssertUnwindSafe};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Condvar, Mutex, MutexGuard};
use std::time::{Duration, Instant};

/// Answers kept for handlers that have not collected them (older ones are dropped).
const KEPT_ANSWERS: u64 = 32;

/// An edit to solve: the validated scene, its TOML, how hard to work.
#[derive(Clone, Debug)]
pub struct SolveJob {
    /// The scene.
    pub scene: Scene,
    /// The scene file it was validated as (what "save" writes).
    pub toml: String,
    /// Search settings, time limit included.
    pub settings: SearchSettings,
}

/// A finished solve with a valid plan.
#[derive(Clone, Debug)]
pub struct Solved {
    /// The edit's number.
    pub id: u64,
    /// What was solved.
    pub job: SolveJob,
    /// The plan, the greedy run and the bound.
    pub outcome: Outcome,
}

/// The one answer an edit gets.
#[derive(Clone, Debug)]
pub enum Answer {
    /// Solved with a valid plan.
    Solved(Arc<Solved>),
    /// A newer edit (`by`) replaced this one before it was answered.
    Superseded {
        /// The newer edit's number.
        by: u64,
    },
    /// The solve ended without a valid plan (no valid path) or failed.
    Failed(Error),
}

/// What the page shows while it waits.
#[derive(Clone, Debug, Default, serde::Serialize)]
pub struct ProgressView {
    /// The edit being solved (0: none yet).
    pub id: u64,
    /// A solve is running.
    pub running: bool,
    /// What the solver is doing, in words.
    pub stage: String,
    /// Seconds since this solve started.
    pub elapsed_s: f64,
}

struct State {
    next_id: u64,
    pending: Option<(u64, SolveJob)>,
    /// The running edit and its cancel flag.
    running: Option<(u64, Arc<AtomicBool>)>,
    started: Option<Instant>,
    answers: HashMap<u64, Answer>,
    stage: String,
    last_solved: Option<Arc<Solved>>,
    shut_down: bool,
}

/// The worker and what handlers share with it.
pub struct Solver {
    state: Mutex<State>,
    changed: Condvar,
}

impl Solver {
    /// Starts the worker thread.
    pub fn start() -> Arc<Solver> {
        let solver = Arc::new(Solver {
            state: Mutex::new(State {
                next_id: 1,
                pending: None,
                running: None,
                started: None,
                answers: HashMap::new(),
                stage: String::new(),
                last_solved: None,
                shut_down: false,
            }),
            changed: Condvar::new(),
        });
        let worker = Arc::clone(&solver);
        std::thread::spawn(move || worker.work());
        solver
    }

    fn lock(&self) -> MutexGuard<'_, State> {
        // A handler that panicked while holding the lock left consistent data (every update is one
        // assignment); keep serving.
        self.state.lock().unwrap_or_else(|e| e.into_inner())
    }

    /// Queues `job` as the newest edit and returns its number. A waiting edit is answered superseded at
    /// once; a running one is cancelled (answered superseded when its solve returns).
    pub fn submit(&self, job: SolveJob) -> u64 {
        let mut s = self.lock();
        let id = s.next_id;
        s.next_id += 1;
        if let Some((old, _)) = s.pending.take() {
            s.answers.insert(old, Answer::Superseded { by: id });
        }
        if let Some((_, cancel)) = &s.running {
            cancel.store(true, Ordering::SeqCst);
        }
        s.pending = Some((id, job));
        s.answers.retain(|&k, _| k + KEPT_ANSWERS > id);
        drop(s);
        self.changed.notify_all();
        id
    }

    /// Waits up to `timeout` for the answer to edit `id` and takes it.
    pub fn wait(&self, id: u64, timeout: Duration) -> Option<Answer> {
        let until = Instant::now() + timeout;
        let mut s = self.lock();
        loop {
            if let Some(answer) = s.answers.remove(&id) {
                return Some(answer);
            }
            let left = until.checked_duration_since(Instant::now())?;
            s = self
                .changed
                .wait_timeout(s, left)
                .map(|(g, _)| g)
                .unwrap_or_else(|e| e.into_inner().0);
        }
    }

    /// The progress of the running solve.
    pub fn progress(&self) -> ProgressView {
        let s = self.lock();
        ProgressView {
            id: s.running.as_ref().map_or(0, |(id, _)| *id),
            running: s.running.is_some(),
            stage: s.stage.clone(),
            elapsed_s: s.started.map_or(0.0, |t| t.elapsed().as_secs_f64()),
        }
    }

    /// The last edit solved with a valid plan.
    pub fn last_solved(&self) -> Option<Arc<Solved>> {
        self.lock().last_solved.clone()
    }

    /// Stops the worker once the running solve returns (waiting edits are answered superseded).
    pub fn shut_down(&self) {
        let mut s = self.lock();
        s.shut_down = true;
        if let Some((_, cancel)) = &s.running {
            cancel.store(true, Ordering::SeqCst);
        }
        drop(s);
        self.changed.notify_all();
    }

    fn work(&self) {
        loop {
            let (id, job, cancel) = {
                let mut s = self.lock();
                loop {
                    if s.shut_down {
                        return;
                    }
                    if let Some((id, job)) = s.pending.take() {
                        let cancel = Arc::new(AtomicBool::new(false));
                        s.running = Some((id, Arc::clone(&cancel)));
                        s.started = Some(Instant::now());
                        s.stage = "greedy baseline and lower bound".to_string();
                        break (id, job, cancel);
                    }
                    s = self.changed.wait(s).unwrap_or_else(|e| e.into_inner());
                }
            };
            let result = catch_unwind(AssertUnwindSafe(|| {
                run_solve(
                    &job.scene,
                    &job.settings,
                    &mut |p| self.lock().stage = p.to_string(),
                    &cancel,
                )
            }));
            let mut s = self.lock();
            s.running = None;
            s.started = None;
            s.stage.clear();
            let answer = if cancel.load(Ordering::SeqCst) {
                Answer::Superseded {
                    by: s.pending.as_ref().map_or(id + 1, |(next, _)| *next),
                }
            } else {
                match result {
                    Ok(Ok(outcome)) if outcome.trace.feasible() => {
                        let solved = Arc::new(Solved { id, job, outcome });
                        s.last_solved = Some(Arc::clone(&solved));
                        Answer::Solved(solved)
                    }
                    Ok(Ok(_)) => Answer::Failed(Error::NoValidPath(
                        "neither the optimiser nor the greedy strafer found a run that reaches the finish \
                         without breaking a rule"
                            .to_string(),
                    )),
                    Ok(Err(e)) => Answer::Failed(e),
                    Err(_) => Answer::Failed(Error::Numerical(
                        "the solver stopped on an internal error; the scene is kept".to_string(),
                    )),
                }
            };
            s.answers.insert(id, answer);
            drop(s);
            self.changed.notify_all();
        }
    }
}

/// Solves `scene`, stopping in whatever stage is running when `cancel` is set (the answer is then
/// dropped by the caller): the library's cancellable solve, its progress silenced once cancelled.
pub fn run_solve(
    scene: &Scene,
    settings: &SearchSettings,
    progress: &mut dyn FnMut(Progress),
    cancel: &AtomicBool,
) -> Result<Outcome> {
    search::solve_cancellable(
        scene,
        settings,
        &mut |p| {
            if !cancel.load(Ordering::SeqCst) {
                progress(p);
            }
        },
        cancel,
    )
}

/// The name of a quality level as the page and the command line write it.
pub fn quality_name(q: Quality) -> &'static str {
    match q {
        Quality::Fast => "fast",
        Quality::Balanced => "balanced",
        Quality::Exact => "exact",
    }
}
