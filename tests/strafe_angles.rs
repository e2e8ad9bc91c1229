//! The analytic strafe angles of docs/physics.md sections 6-9 against brute-force scans of theta over random
//! speeds and settings: the analytic choice must be at least as good as the best of tens of thousands of
//! samples, and finite everywhere.

use proptest::prelude::*;
use proptest::test_runner::{Config, RngSeed};
use strafeopt::physics::strafe::{
    max_accel, max_decel, sharpest_turn, speed_after, speed_preserving_cos_theta, MaxAccelCase,
};
use strafeopt::physics::AccelLaw;

const SAMPLES: usize = 20_000;

fn config() -> Config {
    Config {
        cases: 256,
        rng_seed: RngSeed::Fixed(0x5742_4146),
        failure_persistence: None,
        ..Config::default()
    }
}

/// Speeds from zero to 4000 ups, with the special values mixed in.
fn speed() -> impl Strategy<Value = f64> {
    prop_oneof![Just(0.0), Just(1e-9), 0.0..1.0f64, 0.0..4000.0f64,]
}

/// Laws over realistic and extreme settings: L in the air (30) or on the ground (M), gamma1 for
/// 10..10000 fps and accelerate up to 100, negative entity friction, and L <= 0.
fn law() -> impl Strategy<Value = AccelLaw> {
    prop_oneof![
        (1.0..320.0f64, 0.0..400.0f64).prop_map(|(l, g)| AccelLaw { l, gamma1: g }),
        (0.0..30.0f64, 0.0..40.0f64).prop_map(|(l, g)| AccelLaw { l, gamma1: g }),
        (-50.0..50.0f64, -50.0..50.0f64).prop_map(|(l, g)| AccelLaw { l, gamma1: g }),
        Just(AccelLaw {
            l: 30.0,
            gamma1: 0.0
        }),
        Just(AccelLaw {
            l: 30.0,
            gamma1: 30.0
        }),
    ]
}

fn scan(mut f: impl FnMut(f64) -> f64) -> (f64, f64, f64) {
    // (theta of max, max, min) over theta in [0, pi]
    let (mut arg, mut hi, mut lo) = (0.0, f64::NEG_INFINITY, f64::INFINITY);
    for i in 0..=SAMPLES {
        let th = std::f64::consts::PI * i as f64 / SAMPLES as f64;
        let v = f(th);
        if v > hi {
            hi = v;
            arg = th;
        }
        lo = lo.min(v);
    }
    (arg, hi, lo)
}

proptest! {
    #![proptest_config(config())]

    #[test]
    fn max_accel_beats_every_sampled_angle(lambda in speed(), law in law()) {
        let m = max_accel(lambda, law);
        prop_assert!(m.speed.is_finite() && m.cos_theta.is_finite());
        prop_assert!((-1.0..=1.0).contains(&m.cos_theta));
        let achieved = speed_after(lambda, m.cos_theta, law);
        prop_assert!((achieved - m.speed).abs() <= 1e-9 * (1.0 + m.speed), "{achieved} vs {}", m.speed);
        let (_, best, _) = scan(|th| speed_after(lambda, th.cos(), law));
        prop_assert!(achieved >= best - 1e-9 * (1.0 + best), "{m:?}: {achieved} < sampled {best}");
    }

    #[test]
    fn max_decel_is_below_every_sampled_angle(lambda in speed(), law in law()) {
        let (c, sp) = max_decel(lambda, law);
        prop_assert!(sp.is_finite() && (-1.0..=1.0).contains(&c));
        let (_, _, lowest) = scan(|th| speed_after(lambda, th.cos(), law));
        prop_assert!(sp <= lowest + 1e-9 * (1.0 + lowest), "{sp} > sampled {lowest}");
    }

    #[test]
    fn common_case_decel_is_cos_minus_one(lambda in 0.0..3000.0f64, l in 1.0..320.0f64, frac in 0.0..1.0f64) {
        // docs/physics.md section 7: gamma1 >= 0, L >= 0, L - gamma1 >= 0 gives | lambda - gamma1 |.
        let law = AccelLaw { l, gamma1: frac * l };
        let (_, sp) = max_decel(lambda, law);
        prop_assert!((sp - (lambda - law.gamma1).abs()).abs() < 1e-9 * (1.0 + lambda));
    }

    #[test]
    fn sharpest_turn_beats_every_sampled_angle(lambda in speed(), law in law()) {
        let (theta, turn) = sharpest_turn(lambda, law);
        prop_assert!(theta.is_finite() && turn.is_finite());
        let turn_at = |th: f64| {
            let (s, c) = th.sin_cos();
            let mu = law.mu(lambda * c);
            (mu * s).atan2(lambda + mu * c)
        };
        prop_assert!((turn_at(theta) - turn).abs() < 1e-12);
        let (_, best, _) = scan(turn_at);
        prop_assert!(turn >= best - 1e-9, "{turn} < sampled {best}");
    }

    #[test]
    fn speed_preserving_preserves_or_proves_it_cannot(
        speed_before in 1.0..3000.0f64,
        friction_frac in prop_oneof![Just(1.0), 0.9..1.0f64],
        law in law(),
    ) {
        let lambda = speed_before * friction_frac;
        match speed_preserving_cos_theta(speed_before, lambda, law) {
            Some(c) => {
                prop_assert!((-1.0..=1.0).contains(&c));
                let sp = speed_after(lambda, c, law);
                prop_assert!((sp - speed_before).abs() < 1e-7 * speed_before, "{sp} vs {speed_before}");
            }
            None => {
                // No angle preserves the speed: the sampled speeds stay on one side of it.
                let (_, best, lowest) = scan(|th| speed_after(lambda, th.cos(), law));
                let tol = 1e-9 * speed_before;
                prop_assert!(
                    best < speed_before + tol || lowest > speed_before - tol,
                    "samples span {lowest}..{best} around {speed_before}"
                );
            }
        }
    }

    #[test]
    fn speed_preserving_matches_section_8_where_its_formula_applies(
        speed_before in 1.0..3000.0f64,
        friction_frac in 0.9..1.0f64,
        l in 1.0..320.0f64,
        gamma1 in 0.1..100.0f64,
    ) {
        let lambda = speed_before * friction_frac;
        let law = AccelLaw { l, gamma1 };
        let loss = speed_before * speed_before - lambda * lambda;
        if loss / gamma1 + gamma1 <= 2.0 * l {
            let c = (loss / gamma1 - gamma1) / (2.0 * lambda);
            if c.abs() <= 1.0 {
                let got = speed_preserving_cos_theta(speed_before, lambda, law);
                prop_assert!(got.is_some_and(|g| (g - c).abs() < 1e-9), "{got:?} vs {c}");
            }
        }
    }
}

#[test]
fn case_boundaries_are_continuous() {
    // |v| = L - gamma1 (cos zeta = 1), gamma1 = L (cases 1/2), cos zeta_bar = -1 (cases 4/5).
    let law = AccelLaw {
        l: 30.0,
        gamma1: 3.2,
    };
    let at = max_accel(26.8, law);
    assert_eq!(at.case, MaxAccelCase::One);
    assert!((at.speed - 30.0).abs() < 1e-12);
    let law = AccelLaw {
        l: 30.0,
        gamma1: 30.0,
    };
    let one = max_accel(500.0, law);
    let two = max_accel(
        500.0,
        AccelLaw {
            l: 30.0,
            gamma1: 30.0 + 1e-12,
        },
    );
    assert_eq!(one.case, MaxAccelCase::One);
    assert_eq!(two.case, MaxAccelCase::Two);
    assert!((one.speed - two.speed).abs() < 1e-9);
    let four = max_accel(
        500.0,
        AccelLaw {
            l: -500.0,
            gamma1: -1.0,
        },
    );
    let five = max_accel(
        500.0,
        AccelLaw {
            l: -500.0 + 1e-9,
            gamma1: -1.0,
        },
    );
    assert_eq!(four.case, MaxAccelCase::Four);
    assert_eq!(five.case, MaxAccelCase::Five);
}
