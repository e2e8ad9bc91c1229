//! The airborne maximum-acceleration frame written out by hand, as a C programmer would: case 1 of
//! docs/physics.md section 6 on one side, with the wish direction a rotation of the velocity's unit vector
//! by the angle whose cosine is `(L - gamma1)/|v|`, then the FME (section 5) and the move. No yaw, no
//! trigonometric function, no effect dispatch: the floor the library's frame loop is measured against.
//!
//! Shared by `benches/step.rs` (the timing) and `tests/step_by_hand.rs` (the two loops give the same
//! states), so the bench compares like with like.

/// The constants of the airborne frame: `L = min(30, M)`, `gamma1 = k_e tau M A_air`, `tau`.
#[derive(Clone, Copy, Debug)]
pub struct AirFrameConstants {
    /// `L`, ups.
    pub l: f64,
    /// `gamma1`, ups.
    pub gamma1: f64,
    /// Frame time `tau`, seconds.
    pub tau: f64,
}

impl AirFrameConstants {
    /// The constants of `vars` with the full strafe key held (`M` the max speed).
    pub fn of(vars: &strafeopt::physics::MovementVars) -> Self {
        AirFrameConstants {
            l: vars.air_speed_cap,
            gamma1: vars.entity_friction * vars.frame_time_s() * vars.maxspeed * vars.airaccelerate,
            tau: vars.frame_time_s(),
        }
    }
}

/// Runs `frames` airborne maximum-acceleration frames turning left (anticlockwise) from `pos`, `vel`.
/// Valid while `0 <= gamma1 <= L` (case 1) and the speed stays positive, which the bench settings keep.
#[inline(never)]
pub fn max_accel_left_frames(
    pos: &mut [f64; 2],
    vel: &mut [f64; 2],
    frames: usize,
    k: AirFrameConstants,
) {
    let (mut px, mut py) = (pos[0], pos[1]);
    let (mut vx, mut vy) = (vel[0], vel[1]);
    for _ in 0..frames {
        let speed = (vx * vx + vy * vy).sqrt();
        let cos = ((k.l - k.gamma1) / speed).min(1.0);
        let sin = (1.0 - cos * cos).max(0.0).sqrt();
        let (ux, uy) = (vx / speed, vy / speed);
        // The wish direction: the velocity's unit vector turned anticlockwise by theta.
        let ax = cos * ux - sin * uy;
        let ay = sin * ux + cos * uy;
        let gamma2 = k.l - (vx * ax + vy * ay);
        if gamma2 > 0.0 {
            let mu = k.gamma1.min(gamma2);
            vx += mu * ax;
            vy += mu * ay;
        }
        px += vx * k.tau;
        py += vy * k.tau;
    }
    *pos = [px, py];
    *vel = [vx, vy];
}
