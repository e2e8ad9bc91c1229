//! One frame per effect set (issue 8) and the air-only step against a hand-written minimal air step
//! (issue 3: simulate only the effects a scene calls for; target within 10%).
//!
//! Each iteration runs 1000 frames of a strafing sequence so the per-frame cost dominates.
//!
//! `max_accel_frame` times the whole greedy frame, choosing the maximum-acceleration angle and stepping,
//! through the library beside the same loop written out by hand (`by_hand`); docs/step-performance.md
//! holds the figures.

mod by_hand;

use criterion::{criterion_group, criterion_main, Criterion, Throughput};
use std::hint::black_box;
use strafeopt::physics::strafe::{max_accel_control, max_accel_wish, strafe_keys};
use strafeopt::physics::{Effect, Effects, MovementVars, PlayerState, Side, Stepper, Vec2, Wish};

const FRAMES: usize = 1000;

fn wishes() -> Vec<Wish> {
    (0..FRAMES)
        .map(|i| {
            let yaw = 0.3 * (i as f64 * 0.01).sin() + if i % 2 == 0 { 1.4 } else { -1.4 };
            Wish {
                forward: Vec2::from_angle(yaw),
                forwardmove: 0.0,
                sidemove: 400.0,
                jump: i % 70 == 0,
                duck: false,
            }
        })
        .collect()
}

/// The airborne frame written out by hand: wish direction, the FME (docs/physics.md section 5), the move.
#[inline(never)]
fn minimal_air_frames(s: &mut PlayerState, wishes: &[Wish], vars: &MovementVars) {
    let tau = vars.frame_time_s();
    for w in wishes {
        let f = w.forward;
        let right = Vec2::new(f.y, -f.x);
        let len = w.forwardmove.hypot(w.sidemove);
        let a_hat = (f * w.forwardmove + right * w.sidemove) * (1.0 / len);
        let m = len.min(vars.maxspeed);
        let gamma1 = vars.entity_friction * tau * m * vars.airaccelerate;
        let gamma2 = m.min(vars.air_speed_cap) - s.vel.dot(a_hat);
        if gamma2 > 0.0 {
            s.vel += a_hat * gamma1.min(gamma2);
        }
        s.pos += s.vel * tau;
    }
}

#[inline(never)]
fn stepper_frames(st: &Stepper<f64>, s: &mut PlayerState, wishes: &[Wish]) {
    for w in wishes {
        st.step(s, w);
    }
}

fn bench_steps(c: &mut Criterion) {
    let vars = MovementVars::goldsrc(100.0);
    let ws = wishes();
    let start = PlayerState::airborne(Vec2::ZERO, Vec2::new(320.0, 0.0));
    let mut g = c.benchmark_group("frame_step");
    g.throughput(Throughput::Elements(FRAMES as u64));
    g.bench_function("minimal_air_by_hand", |b| {
        b.iter(|| {
            let mut s = start;
            minimal_air_frames(&mut s, black_box(&ws), &vars);
            black_box(s)
        })
    });
    let sets: [(&str, Effects, bool); 4] = [
        ("air_only", Effects::AIR_ONLY, false),
        (
            "ground_friction",
            Effects::from_list(&[Effect::GroundAccel, Effect::Friction, Effect::MaxVelocity]),
            true,
        ),
        (
            "gravity_jump_cap",
            Effects::from_list(&[
                Effect::AirAccel,
                Effect::GroundAccel,
                Effect::Friction,
                Effect::Gravity,
                Effect::Jump,
                Effect::BhopCap,
                Effect::MaxVelocity,
            ]),
            true,
        ),
        ("all_effects", Effects::all(), true),
    ];
    for (name, fx, ground) in sets {
        let st: Stepper<f64> = Stepper::new(&vars, fx);
        let start = PlayerState {
            on_ground: ground,
            ..start
        };
        g.bench_function(name, |b| {
            b.iter(|| {
                let mut s = start;
                stepper_frames(&st, &mut s, black_box(&ws));
                black_box(s)
            })
        });
    }
    let st32: Stepper<f32> = Stepper::new(&vars, Effects::AIR_ONLY);
    let ws32: Vec<Wish<f32>> = ws
        .iter()
        .map(|w| Wish {
            forward: strafeopt::physics::V2::from_f64(w.forward),
            forwardmove: w.forwardmove as f32,
            sidemove: w.sidemove as f32,
            jump: w.jump,
            duck: w.duck,
        })
        .collect();
    g.bench_function("air_only_engine_exact_f32", |b| {
        b.iter(|| {
            let mut s = strafeopt::physics::engine_exact::to_engine_state(&start);
            for w in black_box(&ws32) {
                st32.step(&mut s, w);
            }
            black_box(s)
        })
    });
    g.finish();
}

/// The library's greedy frame in planning form: the maximum-acceleration wish (view vector, no yaw), then
/// the step.
#[inline(never)]
fn max_accel_wish_frames(st: &Stepper<f64>, state: &mut PlayerState, frames: usize) {
    let keys = strafe_keys(400.0);
    let mut s = *state;
    for _ in 0..frames {
        let w = max_accel_wish(st, &s, keys, Side::Left, 0.0);
        st.step(&mut s, &w);
    }
    *state = s;
}

/// The library's greedy frame with a yaw: the maximum-acceleration control, its wish, then the step.
#[inline(never)]
fn max_accel_control_frames(st: &Stepper<f64>, state: &mut PlayerState, frames: usize) {
    let keys = strafe_keys(400.0);
    let mut s = *state;
    for _ in 0..frames {
        let c = max_accel_control(st, &s, keys, Side::Left, 0.0);
        st.step(&mut s, &c.wish());
    }
    *state = s;
}

/// Airborne maximum acceleration turning left at 1000 fps (case 1 of section 6: `gamma1 = 3.2 < L = 30`).
fn bench_max_accel_frames(c: &mut Criterion) {
    let vars = MovementVars::goldsrc(1000.0);
    let st: Stepper<f64> = Stepper::new(&vars, Effects::AIR_ONLY);
    let k = by_hand::AirFrameConstants::of(&vars);
    let start = PlayerState::airborne(Vec2::ZERO, Vec2::new(320.0, 0.0));
    let mut g = c.benchmark_group("max_accel_frame");
    g.throughput(Throughput::Elements(FRAMES as u64));
    g.bench_function("by_hand", |b| {
        b.iter(|| {
            let (mut pos, mut vel) = ([start.pos.x, start.pos.y], [start.vel.x, start.vel.y]);
            by_hand::max_accel_left_frames(&mut pos, &mut vel, black_box(FRAMES), k);
            black_box((pos, vel))
        })
    });
    g.bench_function("max_accel_wish_step", |b| {
        b.iter(|| {
            let mut s = start;
            max_accel_wish_frames(&st, &mut s, black_box(FRAMES));
            black_box(s)
        })
    });
    g.bench_function("max_accel_control_step", |b| {
        b.iter(|| {
            let mut s = start;
            max_accel_control_frames(&st, &mut s, black_box(FRAMES));
            black_box(s)
        })
    });
    g.finish();
}

criterion_group!(benches, bench_max_accel_frames, bench_steps);
criterion_main!(benches);
