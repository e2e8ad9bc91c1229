//! `solve` on corridors it was never tuned on: a fixed sample of the generated family
//! (`strafeopt gen`, the CI-sized family: 1 or 2 turns of 30 to 180 degrees either way, widths 64 to 256,
//! legs up to 800 units, 100 or 250 fps, air acceleration 10 or 100, start speeds 0 to 1500, rule or
//! solid walls), at `fast`. For every scene: the plan is valid in f64 and in the engine-exact mode at the
//! same frame, never slower than the strongest greedy run, never below the lower bound, and the relaxed
//! certificate lies between the bound and the plan.

mod common;

use strafeopt::optimise::{solve, Quality, SearchSettings};
use strafeopt::scene::generate::{generate_sample, GeneratedScene, GeneratorSettings};

/// The sample: scenes 0 to [`SAMPLE_COUNT`] - 1 of this seed of the CI-sized family.
const SAMPLE_SEED: u64 = 2026;
/// At least 30 scenes, within the CI budget at `fast`.
const SAMPLE_COUNT: u64 = 30;

#[test]
fn the_generated_family_is_solved_validly_never_slower_than_greedy_nor_below_the_bound() {
    let sample = generate_sample(SAMPLE_SEED, SAMPLE_COUNT, &GeneratorSettings::ci_sized())
        .unwrap_or_else(|e| panic!("{e}"));
    let settings = SearchSettings::for_quality(Quality::Fast);
    // Solved on as many threads as the machine has cores; each scene's checks are its own.
    let results = common::on_every_core(&sample, |g| checked(g, &settings));
    let report: Vec<String> = results.iter().map(|r| r.0.clone()).collect();
    let losses: Vec<f64> = results.iter().filter_map(|r| r.1).collect();
    eprintln!("{}", report.join("\n"));
    // Most scenes are planned: the certificate exists wherever the optimiser's plan won.
    assert!(
        losses.len() * 2 >= sample.len(),
        "{} of {} optimised",
        losses.len(),
        sample.len()
    );
}

/// Solves `g` and checks it; returns a line for the report and the rounding loss in frames, if the
/// certificate exists.
fn checked(g: &GeneratedScene, settings: &SearchSettings) -> (String, Option<f64>) {
    let name = &g.name;
    let o = solve(&g.scene, settings).unwrap_or_else(|e| panic!("{name}: {e}"));
    let plan = o
        .trace
        .crossing
        .unwrap_or_else(|| panic!("{name}: the plan does not cross"));
    assert!(o.trace.feasible(), "{name}: the plan breaks a rule");
    let ee = o.engine_exact.crossing.map(|c| c.frames);
    assert!(
        o.engine_exact.feasible() && ee == Some(plan.frames),
        "{name}: engine-exact {ee:?} against the plan's frame {}",
        plan.frames
    );
    if let Some(greedy) = o.greedy.crossing.filter(|_| o.greedy.feasible()) {
        assert!(
            plan.time <= greedy.time + 1e-12,
            "{name}: plan {plan:?} slower than greedy {greedy:?}"
        );
    }
    let bound = o.bound.crossing.time;
    assert!(
        plan.time >= bound - 1e-12,
        "{name}: plan {plan:?} below the bound {bound}"
    );
    let mut loss = None;
    if let Some(r) = o.relaxed {
        assert!(
            r.time >= bound - 1e-9,
            "{name}: relaxed {r:?} below the bound {bound}"
        );
        // A plan clear of the walls is the certificate's last start: the certificate is never behind
        // it (to the quantisation of the plan's yaws, a few thousandths of a frame). A greedy run
        // sliding along a solid wall is no point of the relaxed problem, and may be ahead of it.
        let tau = g.scene.frame_time_s();
        assert!(
            r.time <= plan.time + 0.01 * tau || o.trace.collisions() > 0,
            "{name}: relaxed {r:?} after the plan {plan:?}, which touches no wall"
        );
        loss = Some((plan.time - r.time) / tau);
    }
    let line = format!(
        "{name}: plan {} ({:.6} s), greedy {:?}, bound {}, relaxed {:?}, {}",
        plan.frames,
        plan.time,
        o.greedy
            .crossing
            .filter(|_| o.greedy.feasible())
            .map(|c| c.frames),
        o.bound.crossing.frames,
        o.relaxed.map(|r| r.frames),
        o.greedy_guide
    );
    (line, loss)
}
