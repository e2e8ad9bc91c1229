//! What the optimiser's pieces cost (issue 8): the greedy strafer over 10,000 frames, the lower bound of a
//! bend, one sub-step (solved frame by frame and by Clarabel, at 100 and 1000 fps), and a whole `solve
//! --quality fast`. `strafeopt bench` measures accuracy
//! against wall time on whole scenes; these are the speed targets.
//!
//! CI runs each once in test mode (`cargo test --release --benches`).

use criterion::{criterion_group, criterion_main, Criterion, Throughput};
use std::hint::black_box;
use std::time::Duration;
use strafeopt::optimise::qp::SubProblemSolver;
use strafeopt::optimise::substep::SubStepSetup;
use strafeopt::optimise::{lower_bound, solve, Quality, SearchSettings};
use strafeopt::physics::Vec2;
use strafeopt::scene::Scene;
use strafeopt::sim::{Greedy, Simulation};

const BEND: &str = include_str!("../scenarios/hl-bend90-100fps.toml");
const BEND_1000: &str = include_str!("../scenarios/hl-bend90-1000fps.toml");

/// A 1000 fps airborne lane too long to finish in the 10,000-frame cap: every run is 10,000 frames.
const LANE: &str = r#"
name = "bench-lane-1000fps"
max-frames = 10000
[engine]
preset = "goldsrc"
fps = 1000
effects = ["air-accel", "max-velocity", "walls"]
[lane]
width = 256
length = 20000
kind = "rule"
"#;

fn scene(text: &str, origin: &str) -> Scene {
    Scene::from_toml_str(text, origin).unwrap_or_else(|e| panic!("{e}"))
}

fn bench_strafer_and_bound(c: &mut Criterion) {
    let lane = scene(LANE, "bench-lane");
    let sim = Simulation::new(&lane).unwrap_or_else(|e| panic!("{e}"));
    // The lane's centre line (its lower bound does not exist: the line is out of reach in the cap).
    let y = lane.start.pos.y;
    let path = vec![
        lane.start.pos,
        Vec2::new(lane.finish.a.x.max(lane.finish.b.x), y),
    ];
    let mut g = c.benchmark_group("strafer");
    g.throughput(Throughput::Elements(lane.max_frames));
    g.bench_function("greedy_10000_frames", |b| {
        b.iter(|| {
            let t = sim.run(&mut Greedy::new(black_box(path.clone()), 1000.0));
            assert_eq!(t.frames.len(), 10_000);
            black_box(t.final_speed())
        })
    });
    g.finish();

    let bend = scene(BEND, "hl-bend90-100fps.toml");
    let corridor = bend.corridor().unwrap_or_else(|e| panic!("{e}"));
    c.bench_function("lower_bound_bend90_100fps", |b| {
        b.iter(|| black_box(lower_bound(black_box(&bend), &corridor).map(|l| l.crossing.time)))
    });
}

fn bench_optimiser(c: &mut Criterion) {
    let bend = scene(BEND, "hl-bend90-100fps.toml");
    let fast = SearchSettings::for_quality(Quality::Fast);
    let mut g = c.benchmark_group("optimiser");
    g.sample_size(10).measurement_time(Duration::from_secs(5));
    // The first sub-step around the greedy run, by each solver: 402 frames at 100 fps, 3479 at 1000.
    let bend_1000 = scene(BEND_1000, "hl-bend90-1000fps.toml");
    for (fps, scene) in [(100, &bend), (1000, &bend_1000)] {
        let mut setup = SubStepSetup::greedy(scene, &fast).unwrap_or_else(|e| panic!("{e}"));
        for (name, solver) in [
            ("riccati", SubProblemSolver::Riccati),
            ("clarabel", SubProblemSolver::Clarabel),
        ] {
            setup.solver = solver;
            g.bench_function(format!("{name}_substep_bend90_{fps}fps"), |b| {
                b.iter(|| black_box(setup.solve().predicted))
            });
        }
    }
    g.warm_up_time(Duration::from_millis(100));
    // A full solve per quality level on the 100 fps bend. The other bends take a minute or more per solve:
    // `strafeopt bench` measures them (CI runs these benches once each in test mode).
    for (name, quality) in [
        ("solve_fast_bend90_100fps", Quality::Fast),
        ("solve_balanced_bend90_100fps", Quality::Balanced),
        ("solve_exact_bend90_100fps", Quality::Exact),
    ] {
        let settings = SearchSettings::for_quality(quality);
        g.bench_function(name, |b| {
            b.iter(|| {
                black_box(
                    solve(black_box(&bend), &settings)
                        .map(|o| o.trace.crossing.map(|c| c.time))
                        .unwrap_or_else(|e| panic!("{e}")),
                )
            })
        });
    }
    g.finish();
}

criterion_group!(benches, bench_strafer_and_bound, bench_optimiser);
criterion_main!(benches);
