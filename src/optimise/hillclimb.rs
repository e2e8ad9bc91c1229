//! The baseline optimiser TAS tools use today: random-mutation hill climbing over a plan's
//! per-frame strafe angles.
//!
//! A plan is one strafe angle `theta_k` per frame (the angle between the velocity before frame `k` and the
//! wish direction, docs/physics.md section 5) plus that frame's keys. Each iteration picks a random contiguous
//! range of frames and either adds one small random offset to their `theta` or flips their side
//! (`theta -> -theta`), re-simulates the whole run with [`Simulation::run`], and keeps the mutation only if
//! the run is strictly better: a valid run beats an invalid one, then the earlier crossing wins.
//!
//! The angles are relative to the velocity, as a TAS tool's strafe frames are, so a change early in the
//! run does not turn every later frame away from its strafe angle. The best plan is returned as the
//! absolute controls it played (replayable with [`crate::sim::Playback`]).
//!
//! Deterministic: the random numbers come from a seeded xorshift generator ([`XorShift64`], no OS seed).
//! Bounded by an iteration cap and an optional wall-clock budget; only the cap gives a reproducible result
//! (the budget stops after however many iterations the machine managed).

use crate::physics::{Control, PlayerState};
use crate::sim::{Controller, EngineRun, Simulation, Trace};
use std::time::{Duration, Instant};

/// A small deterministic random generator: SplitMix64 to spread the seed, then xorshift64*
/// (Vigna, "An experimental exploration of Marsaglia's xorshift generators", 2016).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct XorShift64 {
    state: u64,
}

impl XorShift64 {
    /// A generator from `seed` (any value, 0 included).
    pub fn new(seed: u64) -> Self {
        // SplitMix64 step: a zero state would stay zero under xorshift.
        let mut z = seed.wrapping_add(0x9E37_79B9_7F4A_7C15);
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^= z >> 31;
        XorShift64 {
            state: if z == 0 { 0x2545_F491_4F6C_DD1D } else { z },
        }
    }

    /// The next 64 random bits.
    pub fn next_u64(&mut self) -> u64 {
        let mut x = self.state;
        x ^= x >> 12;
        x ^= x << 25;
        x ^= x >> 27;
        self.state = x;
        x.wrapping_mul(0x2545_F491_4F6C_DD1D)
    }

    /// Uniform in `[0, 1)` (53 random bits).
    pub fn next_f64(&mut self) -> f64 {
        (self.next_u64() >> 11) as f64 * (1.0 / (1u64 << 53) as f64)
    }

    /// Uniform in `0..n` (0 when `n` is 0); the modulo bias is below `n / 2^64`.
    pub fn below(&mut self, n: u64) -> u64 {
        if n == 0 {
            0
        } else {
            self.next_u64() % n
        }
    }
}

/// Settings of the hill climber, with their units. `Default` is the recommended configuration.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct HillClimbSettings {
    /// Seed of the random generator. Default `0x5EED`.
    pub seed: u64,
    /// Most mutations tried. Default 1,000,000 (the budget usually stops it first).
    pub max_iters: u64,
    /// Stop after this long (checked between evaluations). Default none.
    pub time_budget: Option<Duration>,
    /// Longest range of frames one mutation changes. Default 32.
    pub max_range_frames: usize,
    /// Largest offset added to `theta` by one mutation, radians. Default 0.02 (about 1.1 degrees); each
    /// mutation scales it by `2^-k`, `k` uniform in `0..STEP_OCTAVES`, so small and large steps both occur.
    pub max_step_rad: f64,
    /// Share of mutations that flip the side of the range instead of offsetting it. Default 0.1.
    pub flip_share: f64,
}

impl Default for HillClimbSettings {
    fn default() -> Self {
        HillClimbSettings {
            seed: 0x5EED,
            max_iters: 1_000_000,
            time_budget: None,
            max_range_frames: 32,
            max_step_rad: 0.02,
            flip_share: 0.1,
        }
    }
}

impl HillClimbSettings {
    /// The default settings with at most `max_iters` mutations.
    pub fn with_max_iters(mut self, max_iters: u64) -> Self {
        self.max_iters = max_iters;
        self
    }

    /// The default settings stopping after `budget`.
    pub fn with_time_budget(mut self, budget: Duration) -> Self {
        self.time_budget = Some(budget);
        self
    }

    /// The settings with `seed`.
    pub fn with_seed(mut self, seed: u64) -> Self {
        self.seed = seed;
        self
    }
}

/// Number of binary scales a mutation's step is drawn from (see [`HillClimbSettings::max_step_rad`]).
pub const STEP_OCTAVES: u32 = 8;

/// Why the climb stopped.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum HillClimbStop {
    /// `max_iters` mutations were tried.
    MaxIterations,
    /// The time budget ran out.
    TimeBudget,
    /// The start plan is empty: nothing to mutate.
    EmptyPlan,
}

/// The result of [`hill_climb`].
#[derive(Clone, Debug)]
pub struct HillClimbOutcome {
    /// The best plan's controls (absolute yaws), one per frame up to its crossing.
    pub controls: Vec<Control>,
    /// The best plan simulated.
    pub trace: Trace,
    /// The best plan in the engine-exact mode.
    pub engine_exact: EngineRun,
    /// Mutations tried.
    pub iterations: u64,
    /// Simulations run (the start plan's included).
    pub evaluations: u64,
    /// Mutations kept.
    pub accepted: u64,
    /// Why it stopped.
    pub stop: HillClimbStop,
    /// Wall-clock time of the climb, seconds.
    pub seconds: f64,
}

/// Plays strafe angles relative to the velocity: frame `k`'s yaw is the velocity's heading plus
/// `theta_k` plus the keys' angle, as [`Control::strafe`] builds it. Past the plan's end it repeats the
/// last frame.
struct RelativePlayer<'a> {
    thetas: &'a [f64],
    keys: &'a [Control],
}

impl Controller for RelativePlayer<'_> {
    fn name(&self) -> String {
        "hill-climb".to_string()
    }

    fn control(&mut self, frame: u64, s: &PlayerState, _sim: &Simulation) -> Control {
        let i = usize::try_from(frame.saturating_sub(1))
            .unwrap_or(usize::MAX)
            .min(self.thetas.len().saturating_sub(1));
        let (Some(&theta), Some(k)) = (self.thetas.get(i), self.keys.get(i)) else {
            return Control::strafe(s.vel, 0.0, 0.0, 0.0, 0.0);
        };
        Control {
            jump: k.jump,
            duck: k.duck,
            ..Control::strafe(s.vel, k.yaw_rad, theta, k.forwardmove, k.sidemove)
        }
    }
}

/// Sort key of a run, smaller is better: valid crossings by time, then invalid crossings by how many
/// frames break a rule and then time, then runs that never cross.
fn score(t: &Trace) -> (u8, f64, f64) {
    match t.crossing {
        Some(c) if t.feasible() => (0, 0.0, c.time),
        Some(c) => {
            let broken = t.frames.iter().filter(|f| f.broke_rule).count();
            (1, broken as f64, c.time)
        }
        None => (2, 0.0, 0.0),
    }
}

/// Strictly better (lexicographic on the score; NaN compares as not better).
fn better(a: (u8, f64, f64), b: (u8, f64, f64)) -> bool {
    a < b
}

/// The strafe angle of each frame of `trace` and the keys it held.
fn relative_plan(trace: &Trace) -> (Vec<f64>, Vec<Control>) {
    let mut vel = trace.start.vel;
    let mut thetas = Vec::with_capacity(trace.controls.len());
    for (c, rec) in trace.controls.iter().zip(&trace.frames) {
        thetas.push(c.theta_rad(vel));
        vel = rec.vel;
    }
    (thetas, trace.controls.clone())
}

/// Hill-climbs from the plan `start` (usually the greedy run's trace) on `sim`'s scene. Never fails: an
/// empty start comes back as it is with [`HillClimbStop::EmptyPlan`].
pub fn hill_climb(
    sim: &Simulation,
    start: &Trace,
    settings: &HillClimbSettings,
) -> HillClimbOutcome {
    let started = Instant::now();
    let deadline = settings.time_budget.map(|d| started + d);
    let (mut thetas, keys) = relative_plan(start);
    let play = |thetas: &[f64]| {
        sim.run(&mut RelativePlayer {
            thetas,
            keys: &keys,
        })
    };
    let mut best = play(&thetas);
    let mut best_score = score(&best);
    let mut evaluations = 1;
    let mut iterations = 0;
    let mut accepted = 0;
    let mut rng = XorShift64::new(settings.seed);
    let n = thetas.len();
    let mut stop = if n == 0 {
        HillClimbStop::EmptyPlan
    } else {
        HillClimbStop::MaxIterations
    };
    let mut trial = thetas.clone();
    while n > 0 && iterations < settings.max_iters {
        if deadline.is_some_and(|d| Instant::now() >= d) {
            stop = HillClimbStop::TimeBudget;
            break;
        }
        iterations += 1;
        // Only the frames up to the best plan's crossing matter.
        let live = best.frames.len().clamp(1, n);
        let len = 1 + rng.below(settings.max_range_frames.max(1) as u64) as usize;
        let first = rng.below(live as u64) as usize;
        let last = (first + len).min(live);
        trial.clone_from(&thetas);
        if rng.next_f64() < settings.flip_share {
            for t in &mut trial[first..last] {
                *t = -*t;
            }
        } else {
            let octave = rng.below(u64::from(STEP_OCTAVES)) as i32;
            let step = settings.max_step_rad * (2.0 * rng.next_f64() - 1.0) * 0.5f64.powi(octave);
            for t in &mut trial[first..last] {
                *t += step;
            }
        }
        let t = play(&trial);
        evaluations += 1;
        let s = score(&t);
        if better(s, best_score) {
            std::mem::swap(&mut thetas, &mut trial);
            best = t;
            best_score = s;
            accepted += 1;
        }
    }
    let controls = best.controls.clone();
    let engine_exact = sim.run_engine_exact(&controls);
    HillClimbOutcome {
        controls,
        trace: best,
        engine_exact,
        iterations,
        evaluations,
        accepted,
        stop,
        seconds: started.elapsed().as_secs_f64(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::optimise::lower_bound;
    use crate::scene::Scene;
    use crate::sim::controllers::{best_greedy, GREEDY_LOOKAHEADS_UNITS};
    use crate::sim::Playback;

    fn bend90() -> Scene {
        let text = include_str!("../../scenarios/hl-bend90-100fps.toml");
        match Scene::from_toml_str(text, "hl-bend90-100fps.toml") {
            Ok(s) => s,
            Err(e) => panic!("the shipped scene loads: {e}"),
        }
    }

    fn greedy(sim: &Simulation) -> Trace {
        let bound = match lower_bound(sim.scene(), sim.corridor()) {
            Ok(b) => b,
            Err(e) => panic!("the shipped scene has a bound: {e}"),
        };
        best_greedy(sim, &bound.path, &GREEDY_LOOKAHEADS_UNITS).0
    }

    #[test]
    fn rng_is_deterministic_and_uniform_enough() {
        let mut a = XorShift64::new(7);
        let mut b = XorShift64::new(7);
        let xs: Vec<f64> = (0..10_000).map(|_| a.next_f64()).collect();
        assert!(xs.iter().all(|&x| (0.0..1.0).contains(&x)));
        assert!(xs
            .iter()
            .zip((0..).map(|_| b.next_f64()))
            .all(|(x, y)| *x == y));
        let mean = xs.iter().sum::<f64>() / xs.len() as f64;
        assert!((mean - 0.5).abs() < 0.02, "{mean}");
        assert_ne!(XorShift64::new(0).next_u64(), 0);
    }

    #[test]
    fn replaying_the_start_reproduces_greedy() {
        let scene = bend90();
        let sim = Simulation::new(&scene).unwrap_or_else(|e| panic!("{e}"));
        let g = greedy(&sim);
        let out = hill_climb(&sim, &g, &HillClimbSettings::default().with_max_iters(0));
        assert_eq!(out.evaluations, 1);
        let (a, b) = (out.trace.crossing, g.crossing);
        assert_eq!(a.map(|c| c.frames), b.map(|c| c.frames));
        let dt = a
            .zip(b)
            .map_or(f64::INFINITY, |(a, b)| (a.time - b.time).abs());
        assert!(dt < 1e-9, "{dt}");
    }

    #[test]
    fn climbing_keeps_or_improves_greedy_on_the_bend_and_is_deterministic() {
        let scene = bend90();
        let sim = Simulation::new(&scene).unwrap_or_else(|e| panic!("{e}"));
        let g = greedy(&sim);
        let settings = HillClimbSettings::default()
            .with_max_iters(150)
            .with_seed(3);
        let a = hill_climb(&sim, &g, &settings);
        let b = hill_climb(&sim, &g, &settings);
        assert_eq!(a.iterations, 150);
        assert_eq!(a.evaluations, 151);
        assert_eq!(a.stop, HillClimbStop::MaxIterations);
        assert!(a.trace.feasible());
        let (ta, tg) = match (a.trace.crossing, g.crossing) {
            (Some(x), Some(y)) => (x.time, y.time),
            _ => panic!("both runs cross"),
        };
        assert!(ta <= tg, "hill climbing {ta} s, greedy {tg} s");
        // Same seed, same iteration cap: the same plan.
        assert_eq!(a.controls, b.controls);
        assert_eq!(a.accepted, b.accepted);
        // The returned controls replay to the same run.
        let replay = sim.run(&mut Playback {
            controls: a.controls.clone(),
            label: "replay".into(),
        });
        assert_eq!(replay.crossing, a.trace.crossing);
    }
}
