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
fn settings() -> (Stepper<f64>, by_hand::AirFrameConstants, PlayerState) {
    let vars = MovementVars::goldsrc(1000.0);
    let st: Stepper<f64> = Stepper::new(&vars, Effects::AIR_ONLY);
    let k = by_hand::AirFrameConstants::of(&vars);
    (
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
    let (_, k, start) = settings();
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
    // Measured: the wish loop is bit-identical to the by-hand loop for 10 frames and within 9e-12 units and
    // 2.3e-11 ups after 10,000 (10 s of game time, 320 to 1386 ups); the control loop, through a yaw and
    // libm's atan2 and sin_cos, within 4.3e-11 units and 1.7e-10 ups. The tolerance leaves room for
    // another libm, not for another physics: a wish direction off by 1e-9 radians every frame moves the
    // run by about 1e-6 units within 1000 frames (mu = 3.2 ups a frame, tau = 1 ms).
    let (st, k, start) = settings();
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
            dp < 1e-8 && dv < 1e-8,
            "{frames} frames: wish loop {dp} units, {dv} ups"
        );
        let (dp, dv) = difference(&ctl, &hand);
        assert!(
            dp < 1e-8 && dv < 1e-8,
            "{frames} frames: control loop {dp} units, {dv} ups"
        );
        // Not a run that stands still: the speed grows (533 ups after 1000 frames, 1386 after 10,000).
        assert!(
            hand.speed() > 320.0 + 0.05 * frames as f64,
            "{}",
            hand.speed()
        );
    }
}

#[test]
fn the_right_side_mirrors_the_left() {
    let (st, _, start) = settings();
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
