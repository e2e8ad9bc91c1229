//! The lower bound's speed profile (docs/physics.md section 6): no control sequence, whatever its angles, keys,
//! jumps or ducks, covers more path after n frames than the greedy profile, so the time the profile needs
//! for a distance is a lower bound on every run's time over it.

use proptest::prelude::*;
use proptest::test_runner::{Config, RngSeed};
use strafeopt::optimise::bound::{time_to_cover, SpeedBound};
use strafeopt::physics::{Control, Effect, Effects, MovementVars, PlayerState, Stepper, Vec2};

fn config() -> Config {
    Config {
        cases: 200,
        rng_seed: RngSeed::Fixed(0xB0_0D),
        failure_persistence: None,
        ..Config::default()
    }
}

fn effect_sets() -> impl Strategy<Value = (Effects, bool)> {
    prop_oneof![
        Just((Effects::AIR_ONLY, false)),
        Just((Effects::AIR_ONLY.with(Effect::MaxVelocity), false)),
        Just((
            Effects::from_list(&[Effect::GroundAccel, Effect::Friction, Effect::MaxVelocity]),
            true
        )),
        Just((
            Effects::from_list(&[
                Effect::AirAccel,
                Effect::GroundAccel,
                Effect::Friction,
                Effect::Gravity,
                Effect::Jump,
                Effect::BhopCap,
                Effect::MaxVelocity,
            ]),
            true
        )),
    ]
}

proptest! {
    #![proptest_config(config())]

    #[test]
    fn no_random_control_sequence_outruns_the_greedy_profile(
        (fx, ground) in effect_sets(),
        fps in prop_oneof![Just(100.0), Just(1000.0), 20.0..2000.0f64],
        aa in prop_oneof![Just(10.0), Just(100.0)],
        v0 in 0.0..2500.0f64,
        controls in proptest::collection::vec(
            (-7.0..7.0f64, -400.0..400.0f64, -400.0..400.0f64, any::<bool>()), 1..300),
    ) {
        let mut vars = MovementVars::goldsrc(fps);
        vars.airaccelerate = aa;
        let st: Stepper<f64> = Stepper::new(&vars, fx);
        let start = if ground {
            PlayerState::on_ground(Vec2::ZERO, Vec2::new(v0, 0.0))
        } else {
            PlayerState::airborne(Vec2::ZERO, Vec2::new(v0, 0.0))
        };
        let bound = SpeedBound::new(&vars, fx);
        let tau = vars.frame_time_s();
        let (mut s, mut path, mut greedy_speed, mut greedy_path) = (start, 0.0, v0, 0.0);
        for &(yaw_rad, forwardmove, sidemove, jump) in &controls {
            let before = s.pos;
            let c = Control { yaw_rad, forwardmove, sidemove, jump, duck: false };
            st.step(&mut s, &c.wish());
            path += (s.pos - before).length();
            greedy_speed = bound.next(greedy_speed);
            greedy_path += greedy_speed * tau;
            prop_assert!(s.speed() <= greedy_speed * (1.0 + 1e-12) + 1e-9,
                "speed {} above the bound {}", s.speed(), greedy_speed);
            prop_assert!(path <= greedy_path * (1.0 + 1e-12) + 1e-9);
        }
        // The crossing time of the bound over the path actually run is no later than the run's own time.
        let c = time_to_cover(&vars, fx, &start, path, 1_000_000);
        prop_assert!(c.is_some_and(|c| c.time <= controls.len() as f64 * tau + 1e-12));
    }
}
