//! Hard cases of the physics (issue 9): each gives a correct finite answer, checked against an independent
//! calculation (the frame step itself, or the vector form of the FME written out here).

use strafeopt::physics::strafe::{
    max_accel, max_accel_control, speed_after, strafe_keys, MaxAccelCase,
};
use strafeopt::physics::{
    AccelLaw, Control, Effect, Effects, MovementVars, PlayerState, Side, Stepper, Vec2,
};

/// The FME in vector form, written independently of the library: v' = v + mu a_hat.
fn fme_vector(v: Vec2, a_hat: Vec2, law: AccelLaw) -> Vec2 {
    let gamma2 = law.l - (v.x * a_hat.x + v.y * a_hat.y);
    let mu = if gamma2 > 0.0 {
        law.gamma1.min(gamma2)
    } else {
        0.0
    };
    Vec2::new(v.x + mu * a_hat.x, v.y + mu * a_hat.y)
}

fn check_against_vector_form(speed: f64, law: AccelLaw) {
    let m = max_accel(speed, law);
    assert!(
        m.speed.is_finite() && m.cos_theta.is_finite(),
        "{speed} {law:?}: {m:?}"
    );
    let theta = m.cos_theta.clamp(-1.0, 1.0).acos();
    let v = Vec2::new(speed, 0.0);
    let a_hat = Vec2::new(theta.cos(), theta.sin());
    let v2 = fme_vector(v, a_hat, law);
    assert!(
        (v2.length() - m.speed).abs() <= 1e-9 * (1.0 + m.speed),
        "{speed} {law:?}: {} vs {}",
        v2.length(),
        m.speed
    );
}

#[test]
fn zero_and_tiny_speeds() {
    let law = AccelLaw {
        l: 30.0,
        gamma1: 3.2,
    };
    for v in [0.0, 1e-9, 1e-300, f64::MIN_POSITIVE] {
        check_against_vector_form(v, law);
        assert!((max_accel(v, law).speed - (v + 3.2)).abs() < 1e-12);
    }
    // Stepping from rest: direction comes from the view, no NaN.
    let vars = MovementVars::goldsrc(100.0);
    let st: Stepper<f64> = Stepper::new(&vars, Effects::AIR_ONLY);
    let mut s = PlayerState::airborne(Vec2::ZERO, Vec2::ZERO);
    let c = max_accel_control(&st, &s, strafe_keys(400.0), Side::Left, 0.7);
    st.step(&mut s, &c.wish());
    assert!(s.is_finite() && (s.speed() - 30.0).abs() < 1e-12);
}

#[test]
fn speeds_exactly_on_case_boundaries() {
    // |v| = L - gamma1
    let law = AccelLaw {
        l: 30.0,
        gamma1: 3.2,
    };
    check_against_vector_form(26.8, law);
    // gamma1 = L
    check_against_vector_form(
        500.0,
        AccelLaw {
            l: 30.0,
            gamma1: 30.0,
        },
    );
    check_against_vector_form(
        0.0,
        AccelLaw {
            l: 30.0,
            gamma1: 30.0,
        },
    );
    // cos zeta_bar = -1: L = -|v| with gamma1 < 0
    let m = max_accel(
        40.0,
        AccelLaw {
            l: -40.0,
            gamma1: -2.0,
        },
    );
    assert_eq!(m.case, MaxAccelCase::Four);
    check_against_vector_form(
        40.0,
        AccelLaw {
            l: -40.0,
            gamma1: -2.0,
        },
    );
}

#[test]
fn cos_zeta_far_above_one() {
    // Low speed, huge L: cos zeta = (L - gamma1)/|v| ~ 1e12.
    let law = AccelLaw {
        l: 1e6,
        gamma1: 1.0,
    };
    check_against_vector_form(1e-6, law);
    assert_eq!(max_accel(1e-6, law).cos_theta, 1.0);
    // And far below -1 (cases 4 and 5 with gamma1 < 0).
    check_against_vector_form(
        1e-6,
        AccelLaw {
            l: -1e6,
            gamma1: -1.0,
        },
    );
    check_against_vector_form(
        1e-6,
        AccelLaw {
            l: 1e6,
            gamma1: -1.0,
        },
    );
}

#[test]
fn gamma1_zero_and_negative_entity_friction() {
    for ke in [0.0, -1.0] {
        let mut vars = MovementVars::goldsrc(100.0);
        vars.entity_friction = ke;
        vars.validate().unwrap_or_else(|e| panic!("{e}"));
        let st: Stepper<f64> = Stepper::new(&vars, Effects::AIR_ONLY);
        let mut s = PlayerState::airborne(Vec2::ZERO, Vec2::new(300.0, 0.0));
        for _ in 0..1000 {
            let c = max_accel_control(&st, &s, strafe_keys(400.0), Side::Left, 0.0);
            st.step(&mut s, &c.wish());
            assert!(s.is_finite());
        }
        if ke == 0.0 {
            // No acceleration at all: the speed stays.
            assert!((s.speed() - 300.0).abs() < 1e-9);
        } else {
            // gamma1 = -32 < 0: case 5 pushes against the velocity, mu = gamma1, the speed grows by 32
            // per frame until the clamp (no clamp here).
            assert!(
                (s.speed() - (300.0 + 32_000.0)).abs() < 1e-6,
                "{}",
                s.speed()
            );
        }
    }
}

#[test]
fn diagonal_velocity_at_the_component_clamp() {
    let vars = MovementVars::goldsrc(1000.0);
    let fx = Effects::AIR_ONLY.with(Effect::MaxVelocity);
    let st: Stepper<f64> = Stepper::new(&vars, fx);
    let mut s = PlayerState::airborne(Vec2::ZERO, Vec2::new(2000.0, 2000.0));
    let before = s.speed();
    for _ in 0..100 {
        let c = max_accel_control(&st, &s, strafe_keys(400.0), Side::Left, 0.0);
        st.step(&mut s, &c.wish());
        assert!(s.is_finite());
        // After the clamp each component is within 2000, then the FME adds at most gamma1 = 3.2.
        assert!(s.vel.x.abs() <= 2000.0 + 3.2 + 1e-9 && s.vel.y.abs() <= 2000.0 + 3.2 + 1e-9);
    }
    assert!(s.speed() <= before + 3.2 + 1e-9);
}

#[test]
fn scalar_fme_agrees_with_the_step_for_random_angles() {
    // The library's scalar FME against its own frame step, at many angles and speeds, 1000 fps.
    let vars = MovementVars::goldsrc(1000.0);
    let st: Stepper<f64> = Stepper::new(&vars, Effects::AIR_ONLY);
    let law = AccelLaw {
        l: 30.0,
        gamma1: 3.2,
    };
    let mut seed = 0x2545_f491_u64;
    for _ in 0..10_000 {
        seed = seed
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        let speed = (seed >> 11) as f64 / (1u64 << 53) as f64 * 3000.0;
        let theta =
            ((seed >> 7) % 10_000) as f64 / 10_000.0 * std::f64::consts::TAU - std::f64::consts::PI;
        let vel = Vec2::new(speed, 0.0);
        let c = Control::strafe(vel, 0.0, theta, 0.0, 400.0);
        let mut s = PlayerState::airborne(Vec2::ZERO, vel);
        st.step(&mut s, &c.wish());
        let expect = speed_after(speed, theta.cos(), law);
        assert!(
            (s.speed() - expect).abs() < 1e-9 * (1.0 + expect),
            "{speed} {theta}"
        );
    }
}
