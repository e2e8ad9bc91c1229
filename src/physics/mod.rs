//! Movement physics: the per-frame dynamics of docs/physics.md, with no I/O and no geometry.
//!
//! - [`vars`]: movement variables and presets (section 2).
//! - [`effects`]: which parts of the frame a scene runs (section 3).
//! - [`step`]: one frame, friction and the FME (sections 3-5), over `f64` or `f32`.
//! - [`strafe`]: strafe angles: maximum acceleration and deceleration, speed preserving, sharpest turn
//!   (sections 6-8).
//! - [`closed_form`]: speeds and frame counts in closed form (sections 4, 6).
//! - [`curvature`]: turn radius and the radius-speed relation (section 9).
//! - [`abh`]: the Source jump boost model of the accelerated-backhop article (section 11).
//! - [`engine_exact`]: the game's own arithmetic (f32, anglemod) and replay drift (section 1).
//! - [`vectorial`]: the wish direction set finer than anglemod by whole forwardmove and sidemove (section 1).

pub mod abh;
pub mod closed_form;
pub mod curvature;
pub mod effects;
pub mod engine_exact;
pub mod real;
pub mod step;
pub mod strafe;
pub mod vars;
pub mod vec2;
pub mod vectorial;

pub use effects::{Effect, Effects};
pub use real::Real;
pub use step::{accelerate, friction, AccelLaw, Control, PlayerState, Side, Stepper, Wish};
pub use vars::{Game, MovementVars, Preset, VarOverrides};
pub use vec2::{Vec2, V2};
