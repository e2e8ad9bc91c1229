//! The library's greedy frame against the same frame written out by hand (`benches/by_hand`): airborne
//! maximum acceleration turning left, case 1 of docs/physics.md section 6. `cargo bench --bench step`
//! times the two loops side by side; these tests check that they compute the same run, so the bench
//! compares like with like.

#[path = "../benches/by_hand/mod.rs"]
mod by_hand;

use strafeopt::physics::strafe::{
    max_accel, max_accel_control, max_accel_wish, strafe_keys, MaxAccelCase,
};
use strafeopt::physics::{AccelLaw, Effects, MovementVars, PlayerState, Side, Stepper, Vec2};

/// The bench's settings: Half-Life at 1000 fps, airborne, full sidemove, from 320 ups along +x.
fn settings() -> (
    MovementVars,
    Stepper<f64>,
    by_hand::AirFrameConstants,
    PlayerState,
) {
    let vars = MovementVars::goldsrc(1000.0);
    let st: Stepper<f64> = Stepper::new(&vars, Effects::AIR_ONLY);
    let k = by_hand::AirFrameConstants {
        l: vars.air_speed_cap,
        gamma1: vars.entity_friction * vars.frame_time_s() * vars.maxspeed * vars.airaccelerate,
        tau: vars.frame_time_s(),
    };
    (
        vars,
        st,
        k,
        PlayerState::airborne(Vec2::ZERO, Vec2::new(320.0, 0.0)),
    )
}

fn by_hand_run(k: by_hand::AirFrameConstants, start: &PlayerState, frames: usize) -> PlayerState {
    let (mut pos, mut vel) = ([start.pos.x, start.pos.y], [start.vel.x, start.vel.y]);
    by_hand::max_accel_left_frames(&mut pos, &mut vel, frames, k);
    PlayerState::airborne(Vec2::new(pos[0], pos[1]), Vec2::new(vel[0], vel[1]))
}

/// Largest position (units) and velocity (ups) difference between two states.
fn difference(a: &PlayerState, b: &PlayerState) -> (f64, f64) {
    ((a.pos - b.pos).length(), (a.vel - b.vel).length())
}

#[test]
fn the_settings_are_case_one_with_a_turning_angle() {
    let (_, _, k, start) = settings();
    let law = AccelLaw {
        l: k.l,
        gamma1: k.gamma1,
    };
    // gamma1 = 3.2 <= L = 30, and at 320 ups cos Theta = 26.8/320 < 1: the by-hand formula's case.
    assert!((k.gamma1 - 3.2).abs() < 1e-12);
    let m = max_accel(start.speed(), law);
    assert_eq!(m.case, MaxAccelCase::One);
    assert!((m.cos_theta - 26.8 / 320.0).abs() < 1e-12);
}

#[test]
fn the_library_loop_and_the_by_hand_loop_give_the_same_states() {
    // Measured: after 10,000 frames (10 s of game time, 5000 ups, positions near 5000 units) the two runs
    // agree to 2e-9 units and 1e-10 ups; the tolerance leaves room for another libm, not for another
    // physics (one frame of a different angle moves the position by more than 1e-3 units).
    let (_, st, k, start) = settings();
    let keys = strafe_keys(400.0);
    for frames in [1, 10, 1000, 10_000] {
        let hand = by_hand_run(k, &start, frames);
        let (mut lib, mut ctl) = (start, start);
        for _ in 0..frames {
            let w = max_accel_wish(&st, &lib, keys, Side::Left, 0.0);
            st.step(&mut lib, &w);
            let c = max_accel_control(&st, &ctl, keys, Side::Left, 0.0);
            st.step(&mut ctl, &c.wish());
        }
        let (dp, dv) = difference(&lib, &hand);
        assert!(
            dp < 1e-6 && dv < 1e-7,
            "{frames} frames: wish loop {dp} units, {dv} ups"
        );
        let (dp, dv) = difference(&ctl, &hand);
        assert!(
            dp < 1e-6 && dv < 1e-7,
            "{frames} frames: control loop {dp} units, {dv} ups"
        );
        // Not a run that stands still: the speed grows every frame.
        assert!(
            hand.speed() > 320.0 + 0.5 * frames as f64 * 0.1,
            "{}",
            hand.speed()
        );
    }
}

#[test]
fn the_right_side_mirrors_the_left() {
    let (_, st, _, start) = settings();
    let keys = strafe_keys(400.0);
    let (mut left, mut right) = (start, start);
    for _ in 0..1000 {
        let w = max_accel_wish(&st, &left, keys, Side::Left, 0.0);
        st.step(&mut left, &w);
        let w = max_accel_wish(&st, &right, keys, Side::Right, 0.0);
        st.step(&mut right, &w);
    }
    assert!(left.pos.y > 1.0, "{:?}", left.pos);
    let mirrored = PlayerState::airborne(
        Vec2::new(right.pos.x, -right.pos.y),
        Vec2::new(right.vel.x, -right.vel.y),
    );
    let (dp, dv) = difference(&left, &mirrored);
    assert!(dp < 1e-9 && dv < 1e-9, "{dp} {dv}");
}
