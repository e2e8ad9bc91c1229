//! Engine-exact replay (docs/physics.md section 1): a planned control sequence run in the game's arithmetic
//! (f32 state, anglemod yaw) drifts from the f64 plan by rounding alone when the plan's yaws are
//! anglemod steps, and by much more when they are not.

use strafeopt::physics::engine_exact::{quantise_yaw_rad, replay, ReplayDrift};
use strafeopt::physics::strafe::{max_accel_control, strafe_keys};
use strafeopt::physics::{Effect, Effects, MovementVars, PlayerState, Side, Stepper, Vec2};

/// Greedy strafing that switches side every 50 frames, planned in f64, replayed in f32.
fn plan_and_replay(fps: f64, frames: usize, v0: f64, quantise: bool) -> ReplayDrift {
    let mut vars = MovementVars::goldsrc(fps);
    vars.maxvelocity = 3500.0;
    let fx = Effects::AIR_ONLY.with(Effect::MaxVelocity);
    let st: Stepper<f64> = Stepper::new(&vars, fx);
    let start = PlayerState::airborne(Vec2::ZERO, Vec2::new(v0, 0.0));
    let mut s = start;
    let keys = strafe_keys(400.0);
    let mut controls = Vec::with_capacity(frames);
    for i in 0..frames {
        let side = if (i / 50) % 2 == 0 {
            Side::Left
        } else {
            Side::Right
        };
        let mut c = max_accel_control(&st, &s, keys, side, 0.0);
        if quantise {
            c.yaw_rad = quantise_yaw_rad(c.yaw_rad);
        }
        st.step(&mut s, &c.wish());
        controls.push(c);
    }
    let d = replay(&vars, fx, &start, &controls);
    assert!(d.finite);
    assert!((d.plan_final_speed - s.speed()).abs() < 1e-9);
    d
}

#[test]
fn quantised_plans_drift_by_rounding_only() {
    // Measured: 0.0022 units and 0.00066 ups after 1000 frames at 100 fps; 0.019 units and 0.0055 ups
    // after 10,000 frames at 1000 fps (positions near 10^4 units, where an f32 step is 0.001).
    let d = plan_and_replay(100.0, 1000, 320.0, true);
    assert!(
        d.final_position_drift < 0.01 && d.max_speed_drift < 0.005,
        "{d:?}"
    );
    let d = plan_and_replay(1000.0, 10_000, 320.0, true);
    assert!(
        d.final_position_drift < 0.1 && d.max_speed_drift < 0.02,
        "{d:?}"
    );
}

#[test]
fn anglemod_truncation_is_what_raw_yaws_lose() {
    // Raw yaws are truncated by up to 360/65536 degrees each frame: 0.28 units at 100 fps, 6 units and
    // 1.2 ups at 1000 fps. If anglemod were skipped, the two runs would agree as closely as quantised ones.
    let raw = plan_and_replay(1000.0, 10_000, 320.0, false);
    let quantised = plan_and_replay(1000.0, 10_000, 320.0, true);
    assert!(
        raw.final_position_drift > 20.0 * quantised.final_position_drift,
        "{raw:?}"
    );
    assert!(raw.max_speed_drift > 0.1, "{raw:?}");
}

#[test]
fn a_million_frames_at_3500_ups_stay_finite_with_bounded_drift() {
    // 1000 fps, 3500 ups for a million frames: 3.5 million units travelled, where an f32 position step is
    // 0.25 units, so the position drifts (measured: 498 units, 1.4e-4 of the distance); the speed does not.
    let d = plan_and_replay(1000.0, 1_000_000, 3500.0, true);
    assert!(d.finite);
    assert!(d.max_speed_drift < 0.01, "{d:?}");
    assert!(d.final_position_drift < 1e-3 * 3.5e6, "{d:?}");
}

/// A straight corridor 64 units wide with solid walls, its centre line at `y` units, from `x = 0` to
/// past a finish line at `x = 3500`; entered at 600 ups along it.
fn solid_corridor_at(y: f64) -> strafeopt::scene::Scene {
    let text = format!(
        r#"
name = "solid-corridor"
[engine]
preset = "goldsrc"
fps = 100
airaccelerate = 10
effects = ["air-accel", "max-velocity", "walls"]
[start]
position = [40.0, {y}]
velocity = [600.0, 0.0]
on-ground = false
[finish]
a = [3500.0, {lo}]
b = [3500.0, {hi}]
[[walls]]
kind = "solid"
points = [[3600.0, {hi}], [0.0, {hi}], [0.0, {lo}], [3600.0, {lo}]]
"#,
        lo = y - 32.0,
        hi = y + 32.0,
    );
    strafeopt::scene::Scene::from_toml_str(&text, "test").unwrap_or_else(|e| panic!("{e}"))
}

#[test]
fn a_run_sliding_along_a_solid_wall_replays_in_the_games_arithmetic() {
    // Turning left at maximum acceleration every frame, the run meets the left wall within a few frames
    // and slides along it to the line, touching it every frame. The game's trace stops 1/32 unit short of
    // the wall; stopped at clearance 0 instead, the f32 position rounds into the wall on some frame and
    // the next trace starts inside it, where the hull is held for good and never reaches the line (at
    // `y = 2500.3`, where the wall's line is no `f32` number).
    use strafeopt::sim::{SideStrafer, Simulation};
    for y in [1000.3, 1777.7, 2500.3] {
        let scene = solid_corridor_at(y);
        let sim = Simulation::new(&scene).unwrap_or_else(|e| panic!("{e}"));
        let plan = sim.run(&mut SideStrafer { side: Side::Left });
        assert!(
            plan.feasible() && plan.collisions() > 100,
            "{y}: the plan slides"
        );
        let game = sim.run_engine_exact(&plan.controls);
        let (planned, played) = (plan.crossing, game.crossing);
        let (Some(planned), Some(played)) = (planned, played) else {
            panic!("{y}: the game's run does not reach the line: {game:?}");
        };
        assert!(game.feasible(), "{y}: {game:?}");
        // Off the wall by the stand-off alone: the two runs slide the same way.
        assert!((game.min_clearance - 0.03125).abs() < 1e-3, "{y}: {game:?}");
        assert!(
            planned.frames.abs_diff(played.frames) <= 1,
            "{y}: {planned:?} {played:?}"
        );
    }
}
