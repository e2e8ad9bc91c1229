//! Every figure of docs/physics.md section 12 (and the worked numbers of sections 9-11), reproduced through
//! the library to the printed precision.

use strafeopt::physics::closed_form::{
    airstrafe_frames_to_speed, frames_to_speed_by_stepping, max_groundstrafe_speed,
    max_groundstrafe_speed_by_stepping,
};
use strafeopt::physics::curvature::{air_law, max_accel_radii, speed_for_radius};
use strafeopt::physics::{abh, Effect, Effects, MovementVars, PlayerState, Stepper, Vec2, Wish};

#[test]
fn airstrafe_320_to_1000_at_1000_fps_takes_about_4938_frames() {
    let vars = MovementVars::goldsrc(1000.0);
    let n = airstrafe_frames_to_speed(320.0, 1000.0, air_law(&vars)).unwrap_or(f64::NAN);
    assert_eq!(format!("{n:.0}"), "4938");
    // Stepping the real frame: the speed first reaches 1000 in frame ceil(n).
    let stepped = frames_to_speed_by_stepping(&vars, 320.0, 1000.0, false, 100_000);
    assert_eq!(stepped, Ok(n.ceil() as u64));
}

#[test]
fn max_groundstrafe_speed_is_505_2_at_1000_fps_and_498_2_at_100_fps() {
    for (fps, printed) in [(1000.0, "505.2"), (100.0, "498.2")] {
        let vars = MovementVars::goldsrc(fps);
        let closed = max_groundstrafe_speed(&vars, false);
        assert_eq!(format!("{closed:.1}"), printed);
        let (simulated, _) = max_groundstrafe_speed_by_stepping(&vars, false, 1e-10, 10_000_000);
        assert!((simulated - closed).abs() < 1e-6, "{simulated} vs {closed}");
    }
}

#[test]
fn airstrafe_0_to_2000_at_aa100_1000_fps_takes_about_4_4_s() {
    let mut vars = MovementVars::goldsrc(1000.0);
    vars.airaccelerate = 100.0;
    let n = airstrafe_frames_to_speed(0.0, 2000.0, air_law(&vars)).unwrap_or(f64::NAN);
    assert_eq!(format!("{:.1}", n * 0.001), "4.4");
    let stepped = frames_to_speed_by_stepping(&vars, 0.0, 2000.0, false, 100_000).unwrap_or(0);
    assert_eq!(format!("{:.1}", stepped as f64 * 0.001), "4.4");
}

#[test]
fn radius_relation_is_about_twice_the_measured_circle() {
    // docs/physics.md section 9: v = 500, 100 fps, theta = 90 deg: 167 by the relation, 83.8 measured.
    let vars = MovementVars::goldsrc(100.0);
    let r = max_accel_radii(&vars, 500.0);
    assert_eq!(format!("{:.0}", r.theta_rad.to_degrees()), "90");
    assert_eq!(format!("{:.0}", r.source_text), "167");
    assert_eq!(format!("{:.1}", r.measured), "83.8");
    assert!((r.first_order - r.measured).abs() / r.measured < 0.01);
    // The inverse finds the speed back.
    let v = speed_for_radius(&vars, r.measured).unwrap_or(f64::NAN);
    assert!((v - 500.0).abs() < 1e-6, "{v}");
}

#[test]
fn abh_article_table_and_crossing() {
    let a = abh::article_model(150.0, 0.51, 5249.34, 3500.0);
    let speeds: Vec<String> = a
        .hops
        .iter()
        .take(7)
        .map(|h| format!("{:.0}", h.speed))
        .collect();
    assert_eq!(speeds, ["225", "285", "405", "645", "1125", "2085", "3500"]);
    let d: Vec<String> = a
        .hops
        .iter()
        .map(|h| format!("{:.2}", h.distance))
        .collect();
    assert_eq!(
        d,
        ["0.00", "114.75", "260.10", "466.65", "795.60", "1369.35", "2432.70", "4217.70"]
    );
    assert_eq!(format!("{:.3}", a.crossing_time), "3.865");
    assert_eq!(format!("{:.2}", a.landing_past_line), "753.36");
}

#[test]
fn bunnyhop_cap_drops_544_plus_to_353_6() {
    // Jumping above 1.7 x 320 = 544 ups drops the speed to 1.105 x 320 = 353.6 (section 10), through the
    // library's own frame.
    let vars = MovementVars::goldsrc(100.0);
    let fx = Effects::from_list(&[Effect::Gravity, Effect::Jump, Effect::BhopCap]);
    let st: Stepper<f64> = Stepper::new(&vars, fx);
    let jump = Wish {
        forward: Vec2::new(1.0, 0.0),
        jump: true,
        ..Wish::default()
    };
    for (speed, expect) in [(600.0, "353.6"), (1500.0, "353.6"), (500.0, "500.0")] {
        let mut s = PlayerState::on_ground(Vec2::ZERO, Vec2::new(speed, 0.0));
        st.pre_move(&mut s, &jump);
        assert_eq!(format!("{:.1}", s.speed()), expect, "from {speed}");
        assert!(!s.on_ground);
    }
}
