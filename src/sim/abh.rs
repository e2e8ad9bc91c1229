//! A frame-level accelerated-backhop (ABH) controller (docs/physics.md section 11, the article in
//! `seeds/001_d17d1c79a27eb9a1.txt`), run through the ordinary frame loop ([`Simulation::run`]): duck,
//! gravity, jumps, the Source jump boost, friction and the lane rules of the scene all apply.
//!
//! The run, from the pistol at frame 0 (crouched, at rest):
//! 1. **Stand up**: duck released; standing takes `TIME_TO_UNDUCK` (the scene's `unduck_time_s`, 0.2 s,
//!    which at tau = 0.015 s is 14 frames). The article walks only once standing; [`AbhParams`] can hold
//!    forward while standing up instead (the duck crop, docs/physics.md section 2, then applies).
//! 2. **Walk** forward (forwardmove = the full key, which the game scales down to the max speed) until the
//!    speed before a frame reaches [`AbhParams::walk_speed_ups`].
//! 3. **The forward jump** on that frame, facing forward with the key held: standing, `p = 0.5`, so the
//!    boost takes `|v| = Mx` to `1.5 Mx` (225 ups at `Mx = 150`).
//! 4. **In the air**: keys released, duck held from [`AbhParams::duck_delay_frames`] after the jump, and the
//!    view turned 180 degrees over [`AbhParams::turn_frames`] frames.
//! 5. **Backhops**: on every frame that starts on the ground, jump and duck held, no movement keys, facing
//!    backwards: ducked, `Fm = 0`, `p = 0.1`, so the boost adds `|v| - 1.1 Mx` along the travel direction
//!    (docs/physics.md section 11). Jump is released in the air, so each jump is a fresh press.
//!
//! **Why the turn schedule does not matter.** With no movement keys held in the air the FME adds nothing
//! (`M = 0`), so the view direction only acts on the jump frames, through the boost's `f`. The turn is
//! spread over frames only so the plan could be played by a person; the trajectory is the same for any
//! `turn_frames` (tested). The backhop frames always face backwards: a turn longer than the first hop is
//! cut short on landing.
//!
//! **Direction control.** The boost adds `add * f`, `f` the flattened view (docs/physics.md section 11). On each
//! jump frame the yaw is chosen so that the velocity's component across the lane after the boost is the one
//! that brings the hull centre back to the lane's centre line by the next landing (`-e / T`, `e` the
//! offset from the centre line, `T` the airtime of docs/physics.md section 10). Across-lane speed is set
//! exactly, before the per-component `sv_maxvelocity` clamp (which only touches the along-lane component
//! here), so the clamp cannot spoil it. Facing exactly opposite the velocity, the boost is straight. The
//! yaws are put on anglemod steps (docs/physics.md section 1) so the engine-exact replay sees the same view.

use super::{Controller, EngineRun, Simulation, Trace};
use crate::physics::abh::boost_add_from_keys;
use crate::physics::engine_exact::quantise_yaw_rad;
use crate::physics::{Control, MovementVars, PlayerState, Vec2};
use serde::Serialize;
use std::f64::consts::PI;

/// Largest speed across the lane the steering asks for, ups.
const MAX_LATERAL_UPS: f64 = 50.0;
/// Slack on the walk-speed threshold, ups: the ground FME reaches `M` only up to rounding.
const WALK_SPEED_TOL_UPS: f64 = 1e-6;
/// The ground layer the airtime estimate falls back to, units (docs/physics.md section 3, step 6).
const GROUND_LAYER_UNITS: f64 = 2.0;

/// The knobs of the ABH run (docs/physics.md section 11).
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct AbhParams {
    /// The forward jump is taken on the first standing ground frame whose speed before it is at least this,
    /// ups. `None`: the scene's max speed (the article's "once at speed").
    pub walk_speed_ups: Option<f64>,
    /// Hold forward while standing up (the article waits until standing).
    pub walk_while_unducking: bool,
    /// Frames over which the view turns 180 degrees after the forward jump (at least 1).
    pub turn_frames: u32,
    /// Frames after the forward jump before duck is pressed (0: the first airborne frame). Duck must be held
    /// by the first landing for the backhop to get `p = 0.1`.
    pub duck_delay_frames: u32,
    /// Steer on jump frames to hold the lane's centre line (see the module documentation).
    pub steer: bool,
}

impl Default for AbhParams {
    fn default() -> Self {
        AbhParams {
            walk_speed_ups: None,
            walk_while_unducking: false,
            turn_frames: 10,
            duck_delay_frames: 0,
            steer: true,
        }
    }
}

/// The boost's signed addition along the view, ups (docs/physics.md section 11), as the frame computes it
/// ([`boost_add_from_keys`]) with the scene's max speed and duck multiplier.
pub fn boost_addition(
    vars: &MovementVars,
    ducked: bool,
    forwardmove: f64,
    sidemove: f64,
    speed: f64,
) -> f64 {
    boost_add_from_keys(
        forwardmove,
        sidemove,
        vars.maxspeed,
        ducked,
        vars.duck_multiplier,
        speed,
    )
}

/// Time from a jump back to the 2-unit ground layer, seconds (docs/physics.md section 10, with the scene's jump
/// speed `v0` and gravity `g`): `(v0 + sqrt(v0^2 - 4 g)) / g`, the airtime of a jump that sets `v_z = v0`
/// (GoldSrc, or ducked in Source; a standing Source jump starts `g tau / 2` slower, section 2). `None`
/// without gravity.
pub fn jump_airtime_s(vars: &MovementVars) -> Option<f64> {
    let (v0, g) = (vars.jump_speed_ups(), vars.gravity);
    let disc = v0 * v0 - 2.0 * g * GROUND_LAYER_UNITS;
    (g > 0.0 && disc >= 0.0).then(|| (v0 + disc.sqrt()) / g)
}

/// The lane's centre line of a straight-lane scene: a point (the start position) and the unit direction
/// towards the finish line's midpoint.
pub fn lane_centre_line(scene: &crate::scene::Scene) -> (Vec2, Vec2) {
    let start = scene.start.pos;
    let mid = (scene.finish.a + scene.finish.b) * 0.5;
    let dir = (mid - start).normalized().unwrap_or(Vec2::new(1.0, 0.0));
    (start, dir)
}

/// The frame-level ABH controller (docs/physics.md section 11). See the module documentation for the run.
#[derive(Clone, Debug)]
pub struct Abh {
    params: AbhParams,
    /// A point of the lane's centre line and its unit direction, fixed on the first frame.
    line: Option<(Vec2, Vec2)>,
    first_jump_frame: Option<u64>,
    /// The yaw of the last jump frame (held in the air once the turn is done).
    last_jump_yaw: f64,
    /// Backhops pressed so far.
    backhops: u32,
}

impl Abh {
    /// A controller with `params`.
    pub fn new(params: AbhParams) -> Self {
        Abh {
            params,
            line: None,
            first_jump_frame: None,
            last_jump_yaw: 0.0,
            backhops: 0,
        }
    }

    /// The lane's centre line ([`lane_centre_line`]), fixed on the first frame.
    fn centre_line(&mut self, sim: &Simulation) -> (Vec2, Vec2) {
        *self
            .line
            .get_or_insert_with(|| lane_centre_line(sim.scene()))
    }

    /// The yaw of a jump frame: the boost adds `add f`; `f` is chosen so the velocity across the lane after
    /// it is the one that returns to the centre line in one airtime, and along the lane `f` points forward
    /// for a positive addition and backward for a negative one.
    fn jump_yaw(&mut self, s: &PlayerState, sim: &Simulation, add: f64) -> f64 {
        let (origin, axis) = self.centre_line(sim);
        let normal = Vec2::new(-axis.y, axis.x);
        let straight = if add < 0.0 {
            axis.angle() + PI
        } else {
            axis.angle()
        };
        if !self.params.steer || add == 0.0 {
            return straight;
        }
        let offset = (s.pos - origin).dot(normal);
        let airtime = jump_airtime_s(&sim.scene().vars).unwrap_or(1.0);
        let target = (-offset / airtime).clamp(-MAX_LATERAL_UPS, MAX_LATERAL_UPS);
        let f_n = (target - s.vel.dot(normal)) / add;
        if !f_n.is_finite() || f_n.abs() > 1.0 {
            return straight;
        }
        let f_a = add.signum() * (1.0 - f_n * f_n).sqrt();
        (axis * f_a + normal * f_n).angle()
    }
}

impl Default for Abh {
    fn default() -> Self {
        Abh::new(AbhParams::default())
    }
}

impl Controller for Abh {
    fn name(&self) -> String {
        "abh".to_string()
    }

    fn control(&mut self, frame: u64, s: &PlayerState, sim: &Simulation) -> Control {
        let vars = sim.scene().vars;
        let (_, axis) = self.centre_line(sim);
        let forward_key = vars.forward_key_speed;
        let mut c = Control {
            yaw_rad: axis.angle(),
            forwardmove: 0.0,
            sidemove: 0.0,
            jump: false,
            duck: false,
        };
        match self.first_jump_frame {
            None => {
                let threshold = self.params.walk_speed_ups.unwrap_or(vars.maxspeed);
                // The duck step runs first in the frame, so the frame in which the unduck timer
                // completes is already a standing frame.
                let standing = !sim.stepper().ducked_after_duck_step(s, false);
                if !standing {
                    // Standing up (TIME_TO_UNDUCK).
                    if self.params.walk_while_unducking {
                        c.forwardmove = forward_key;
                    }
                } else if s.ducked {
                    c.forwardmove = forward_key;
                } else if s.on_ground && s.speed() >= threshold - WALK_SPEED_TOL_UPS {
                    // The forward jump: standing, key held, p = 0.5.
                    c.forwardmove = forward_key;
                    c.jump = true;
                    let add = boost_addition(&vars, false, forward_key, 0.0, s.speed());
                    c.yaw_rad = self.jump_yaw(s, sim, add);
                    self.first_jump_frame = Some(frame);
                    self.last_jump_yaw = c.yaw_rad;
                } else {
                    c.forwardmove = forward_key;
                }
            }
            Some(j) => {
                let since = frame - j;
                if s.on_ground {
                    // A backhop: ducked, no keys, facing backwards.
                    c.jump = true;
                    c.duck = true;
                    // Duck is held, so the frame's duck step leaves the player ducked: p = 0.1.
                    let add = boost_addition(&vars, true, 0.0, 0.0, s.speed());
                    c.yaw_rad = self.jump_yaw(s, sim, add);
                    self.last_jump_yaw = c.yaw_rad;
                    self.backhops += 1;
                } else {
                    c.duck = since > u64::from(self.params.duck_delay_frames);
                    c.yaw_rad = if self.backhops == 0 {
                        let turn = u64::from(self.params.turn_frames.max(1));
                        self.last_jump_yaw + PI * (since.min(turn) as f64 / turn as f64)
                    } else {
                        self.last_jump_yaw
                    };
                }
            }
        }
        c.yaw_rad = quantise_yaw_rad(wrap_angle(c.yaw_rad));
        c
    }
}

/// `a` wrapped into `[0, 2 pi)`, where [`quantise_yaw_rad`]'s nudge lands on its step.
fn wrap_angle(a: f64) -> f64 {
    a.rem_euclid(2.0 * PI)
}

/// One jump of a frame-level run.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct HopRecord {
    /// The frame of the jump (1-based): the last frame that started on the ground.
    pub frame: u64,
    /// Time of the jump from the pistol, seconds: the jump frame starts at `(frame - 1) tau`.
    pub time: f64,
    /// Horizontal speed after the jump frame (the boost applied), ups; constant in the air with no keys.
    pub speed: f64,
    /// Frames to the next jump times tau, seconds (`None` for the hop in which the line is crossed).
    pub hop_time: Option<f64>,
}

/// The jumps of a run: every frame that started on the ground and ended in the air (on the flat floor
/// only a jump leaves the ground).
pub fn hops_from_trace(trace: &Trace, tau: f64) -> Vec<HopRecord> {
    let mut hops: Vec<HopRecord> = Vec::new();
    let mut before_on_ground = trace.start.on_ground;
    for rec in &trace.frames {
        if before_on_ground && !rec.on_ground {
            if let Some(last) = hops.last_mut() {
                last.hop_time = Some((rec.frame - last.frame) as f64 * tau);
            }
            hops.push(HopRecord {
                frame: rec.frame,
                time: (rec.frame - 1) as f64 * tau,
                speed: rec.speed,
                hop_time: None,
            });
        }
        before_on_ground = rec.on_ground;
    }
    hops
}

/// A frame-level ABH run and its figures (docs/physics.md section 11).
#[derive(Clone, Debug)]
pub struct AbhRun {
    /// The run in `f64`.
    pub trace: Trace,
    /// Its jumps, the forward jump first.
    pub hops: Vec<HopRecord>,
    /// Time from the pistol to the line, seconds (`None` if not reached).
    pub pistol_to_line: Option<f64>,
    /// Time from the pistol to the forward jump, seconds.
    pub first_jump: Option<f64>,
    /// No rule line was crossed and every state stayed finite.
    pub in_lane: bool,
    /// The same controls replayed in the engine-exact mode (f32, anglemod).
    pub engine_exact: EngineRun,
}

/// Runs the ABH controller with `params` through `sim`, then replays its controls engine-exact.
pub fn run_abh(sim: &Simulation, params: AbhParams) -> AbhRun {
    let trace = sim.run(&mut Abh::new(params));
    let tau = sim.scene().frame_time_s();
    let hops = hops_from_trace(&trace, tau);
    let engine_exact = sim.run_engine_exact(&trace.controls);
    AbhRun {
        pistol_to_line: trace.crossing.map(|c| c.time),
        first_jump: hops.first().map(|h| h.time),
        in_lane: trace.first_rule_violation().is_none() && !trace.numerical_failure,
        hops,
        engine_exact,
        trace,
    }
}
