//! Movement variables (docs/physics.md section 2): the server settings and client constants one frame of
//! movement depends on, with the Half-Life and Half-Life 2 defaults as presets.

use crate::error::{require_finite, require_non_negative, require_positive, Error, Result};
use serde::{Deserialize, Serialize};

/// Which engine's movement code is reproduced.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Game {
    /// Half-Life (GoldSrc, `PM_PlayerMove`).
    GoldSrc,
    /// Half-Life 2 (Source, `CGameMovement::FullWalkMove`).
    Source,
}

/// A named set of defaults (docs/physics.md section 2).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub enum Preset {
    /// Half-Life defaults: `sv_maxspeed 320`, `sv_accelerate 10`, `sv_airaccelerate 10`, `sv_friction 4`,
    /// `sv_stopspeed 100`, `sv_maxvelocity 2000`, `sv_gravity 800`.
    #[serde(rename = "goldsrc")]
    GoldSrc,
    /// Half-Life 2 defaults: max speed 190 (normal run; 320 sprint, 150 without the suit),
    /// `sv_accelerate 10`, `sv_airaccelerate 10`, `sv_friction 4`, `sv_stopspeed 100`,
    /// `sv_maxvelocity 3500`, `sv_gravity 600`.
    #[serde(rename = "source-hl2")]
    SourceHl2,
}

impl Preset {
    /// The preset's name as written in files and on the command line.
    pub fn name(self) -> &'static str {
        match self {
            Preset::GoldSrc => "goldsrc",
            Preset::SourceHl2 => "source-hl2",
        }
    }

    /// Parses `goldsrc` or `source-hl2`.
    pub fn from_name(name: &str) -> Option<Preset> {
        match name {
            "goldsrc" => Some(Preset::GoldSrc),
            "source-hl2" => Some(Preset::SourceHl2),
            _ => None,
        }
    }
}

/// GoldSrc's jump speed, `sqrt(2 * 800 * 45)` ups: the game hard-codes 800, whatever `sv_gravity` is.
pub const GOLDSRC_JUMP_SPEED_UPS: f64 = 268.328_157_299_974_8;
/// Source's jump speed with movement optimisations on (the game's default), ups: Half-Life 2's
/// `CGameMovement::CheckJumpButton` uses a fixed 160 (about 21 units high at `sv_gravity 600`), not
/// `sqrt(2 g 21)` = 158.75 (docs/physics.md section 2).
pub const SOURCE_JUMP_SPEED_UPS: f64 = 160.0;
/// Bunnyhop cap threshold, a multiple of `sv_maxspeed` (docs/physics.md section 10).
pub const BHOP_CAP_FACTOR: f64 = 1.7;
/// Speed after the bunnyhop cap, a multiple of `sv_maxspeed` (`1.7 * 0.65`).
pub const BHOP_CAP_RESULT_FACTOR: f64 = 1.105;
/// Above this vertical speed (ups) a GoldSrc player is never on the ground (docs/physics.md section 3,
/// step 6: `PM_CatagorizePosition`).
pub const GROUND_MAX_VZ_UPS: f64 = 180.0;
/// Above this vertical speed (ups) a Source player is never on the ground (`NON_JUMP_VELOCITY` in
/// `CGameMovement::CategorizePosition`).
pub const SOURCE_GROUND_MAX_VZ_UPS: f64 = 140.0;
/// The ground layer: within this height (units) above a floor the player stands on it.
pub const GROUND_LAYER_UNITS: f64 = 2.0;
/// Below this speed (ups) ground friction does nothing (`PM_Friction`: `if (speed < 0.1) return`).
pub const FRICTION_MIN_SPEED_UPS: f64 = 0.1;
/// After a ground move, a speed below this (ups) is set to zero (`PM_WalkMove`, `CGameMovement::WalkMove`).
pub const WALK_STOP_SPEED_UPS: f64 = 1.0;

/// Largest magnitude of any movement variable: far beyond any game's settings, small enough that no run
/// overflows.
pub const MAX_SETTING_MAGNITUDE: f64 = 1e6;
/// Fewest frames per second accepted.
pub const MIN_FPS: f64 = 1.0;
/// Most frames per second accepted (a frame time of 10 microseconds; the default frame cap of 60 s is then
/// six million frames).
pub const MAX_FPS: f64 = 1e5;

/// The movement variables of docs/physics.md section 2, in ups, ups^2, seconds.
///
/// Build one from a [`Preset`] and change any field through [`VarOverrides`], which validates.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct MovementVars {
    /// Whose movement code runs.
    pub game: Game,
    /// Frames per second; the frame time `tau = 1/fps` (truncated to whole milliseconds when
    /// `truncate_frame_time_ms` is set, as older GoldSrc engines do).
    pub fps: f64,
    /// Truncate the frame time to a multiple of 0.001 s (older GoldSrc engines).
    pub truncate_frame_time_ms: bool,
    /// `sv_maxspeed` `M_m`, ups.
    pub maxspeed: f64,
    /// `sv_accelerate` `A` on the ground.
    pub accelerate: f64,
    /// `sv_airaccelerate` `A` in the air.
    pub airaccelerate: f64,
    /// `sv_friction`.
    pub friction: f64,
    /// Edge friction `e_f`, applied only when a scene asks for edge friction.
    pub edgefriction: f64,
    /// Entity (surface) friction `k_e`: scales friction and the acceleration gamma1.
    pub entity_friction: f64,
    /// `sv_stopspeed` `E`, ups.
    pub stopspeed: f64,
    /// `sv_maxvelocity` `V_max`, ups, applied to each velocity component.
    pub maxvelocity: f64,
    /// `sv_gravity` `g`, ups per second.
    pub gravity: f64,
    /// The air wish-speed cap (30 ups): `L = min(30, M)` in the air.
    pub air_speed_cap: f64,
    /// Forwardmove with the forward key held (`cl_forwardspeed`), ups.
    pub forward_key_speed: f64,
    /// Sidemove with a strafe key held (`cl_sidespeed`), ups.
    pub side_key_speed: f64,
    /// Multiplier on forwardmove and sidemove while ducked (0.333).
    pub duck_multiplier: f64,
    /// Time to stand up after releasing duck, seconds (Source `TIME_TO_UNDUCK` 0.2; GoldSrc in the air 0).
    pub unduck_time_s: f64,
    /// Whether a replayed plan may set the wish direction with whole forwardmove and sidemove besides the
    /// yaw (vectorial compensation, docs/physics.md section 1). Off by default: the game's own client
    /// scales `(F, S, U)` down to the player's maximum speed before sending it (`CL_CreateMove`), which
    /// undoes it, so only a replay tool that writes the user command itself can play such a plan. Off,
    /// the keys stay at their speeds and the yaw alone, on anglemod steps, turns the wish direction.
    #[serde(default)]
    pub vectorial_compensation: bool,
}

impl MovementVars {
    /// The defaults of a preset at `fps` frames per second.
    pub fn preset(preset: Preset, fps: f64) -> Self {
        match preset {
            Preset::GoldSrc => MovementVars {
                game: Game::GoldSrc,
                fps,
                truncate_frame_time_ms: false,
                maxspeed: 320.0,
                accelerate: 10.0,
                airaccelerate: 10.0,
                friction: 4.0,
                edgefriction: 2.0,
                entity_friction: 1.0,
                stopspeed: 100.0,
                maxvelocity: 2000.0,
                gravity: 800.0,
                air_speed_cap: 30.0,
                forward_key_speed: 400.0,
                side_key_speed: 400.0,
                duck_multiplier: 0.333,
                unduck_time_s: 0.0,
                vectorial_compensation: false,
            },
            Preset::SourceHl2 => MovementVars {
                game: Game::Source,
                fps,
                truncate_frame_time_ms: false,
                maxspeed: 190.0,
                accelerate: 10.0,
                airaccelerate: 10.0,
                friction: 4.0,
                edgefriction: 2.0,
                entity_friction: 1.0,
                stopspeed: 100.0,
                maxvelocity: 3500.0,
                gravity: 600.0,
                air_speed_cap: 30.0,
                forward_key_speed: 450.0,
                side_key_speed: 450.0,
                duck_multiplier: 0.333,
                unduck_time_s: 0.2,
                vectorial_compensation: false,
            },
        }
    }

    /// Half-Life defaults at `fps`.
    pub fn goldsrc(fps: f64) -> Self {
        Self::preset(Preset::GoldSrc, fps)
    }

    /// Half-Life 2 defaults at `fps`.
    pub fn source_hl2(fps: f64) -> Self {
        Self::preset(Preset::SourceHl2, fps)
    }

    /// The frame time `tau`, seconds (docs/physics.md section 1).
    #[inline]
    pub fn frame_time_s(&self) -> f64 {
        let tau = 1.0 / self.fps;
        if self.truncate_frame_time_ms {
            (tau * 1000.0).floor() / 1000.0
        } else {
            tau
        }
    }

    /// The jump speed, ups (docs/physics.md section 2): `sqrt(2*800*45)` in GoldSrc (the game hard-codes 800),
    /// 160 in Source. GoldSrc's jump always sets `v_z` to it; so does Source's when ducked, while a standing
    /// Source jump adds it to `v_z` ([`MovementVars::jump_vz_ups`]).
    pub fn jump_speed_ups(&self) -> f64 {
        match self.game {
            Game::GoldSrc => GOLDSRC_JUMP_SPEED_UPS,
            Game::Source => SOURCE_JUMP_SPEED_UPS,
        }
    }

    /// The largest vertical speed at which the player can be on the ground, ups: 180 in GoldSrc, 140 in
    /// Source (docs/physics.md section 3, step 6).
    pub fn ground_max_vz_ups(&self) -> f64 {
        match self.game {
            Game::GoldSrc => GROUND_MAX_VZ_UPS,
            Game::Source => SOURCE_GROUND_MAX_VZ_UPS,
        }
    }

    /// The vertical speed right after a jump, ups, from `vz_ups` (the frame's `v_z` so far, which holds
    /// the first half-step of gravity, `-g tau / 2`, on the flat floor) and whether the player is ducked
    /// (docs/physics.md section 2): GoldSrc sets the jump speed; Source sets it ducked and adds it standing.
    pub fn jump_vz_ups(&self, vz_ups: f64, ducked: bool) -> f64 {
        match self.game {
            Game::Source if !ducked => vz_ups + SOURCE_JUMP_SPEED_UPS,
            _ => self.jump_speed_ups(),
        }
    }

    /// Ground friction constant `k = sv_friction * k_e * e_f` (docs/physics.md section 2); `edge` applies `e_f`.
    #[inline]
    pub fn friction_k(&self, edge: bool) -> f64 {
        let ef = if edge { self.edgefriction } else { 1.0 };
        self.friction * self.entity_friction * ef
    }

    /// Checks every field; the error names the field and its allowed range. Besides each field's sign,
    /// every magnitude is bounded ([`MAX_SETTING_MAGNITUDE`], fps in [`MIN_FPS`, `MAX_FPS`]), so no run of
    /// the default frame cap can overflow `f64`: a finite `1e308` acceleration would reach infinity in a frame.
    pub fn validate(&self) -> Result<()> {
        let tau = self.frame_time_s();
        require_positive("fps", self.fps)?;
        if !(MIN_FPS..=MAX_FPS).contains(&self.fps) {
            return Err(Error::invalid(
                "fps",
                self.fps,
                format!("between {MIN_FPS} and {MAX_FPS} frames per second"),
            ));
        }
        if !(tau.is_finite() && tau > 0.0) {
            return Err(Error::invalid(
                "fps",
                self.fps,
                "at most 1000 when the frame time is truncated to milliseconds",
            ));
        }
        require_positive("maxspeed", self.maxspeed)?;
        require_finite("accelerate", self.accelerate)?;
        require_finite("airaccelerate", self.airaccelerate)?;
        require_non_negative("friction", self.friction)?;
        require_non_negative("edgefriction", self.edgefriction)?;
        require_finite("entity-friction", self.entity_friction)?;
        require_non_negative("stopspeed", self.stopspeed)?;
        require_positive("maxvelocity", self.maxvelocity)?;
        require_non_negative("gravity", self.gravity)?;
        require_non_negative("air-speed-cap", self.air_speed_cap)?;
        require_non_negative("forward-key-speed", self.forward_key_speed)?;
        require_non_negative("side-key-speed", self.side_key_speed)?;
        require_non_negative("duck-multiplier", self.duck_multiplier)?;
        require_non_negative("unduck-time-s", self.unduck_time_s)?;
        let magnitudes = [
            ("maxspeed", self.maxspeed),
            ("accelerate", self.accelerate),
            ("airaccelerate", self.airaccelerate),
            ("friction", self.friction),
            ("edgefriction", self.edgefriction),
            ("entity-friction", self.entity_friction),
            ("stopspeed", self.stopspeed),
            ("maxvelocity", self.maxvelocity),
            ("gravity", self.gravity),
            ("air-speed-cap", self.air_speed_cap),
            ("forward-key-speed", self.forward_key_speed),
            ("side-key-speed", self.side_key_speed),
            ("duck-multiplier", self.duck_multiplier),
            ("unduck-time-s", self.unduck_time_s),
        ];
        for (name, v) in magnitudes {
            if v.abs() > MAX_SETTING_MAGNITUDE {
                return Err(Error::invalid(
                    name,
                    v,
                    format!("at most {MAX_SETTING_MAGNITUDE:e} in magnitude"),
                ));
            }
        }
        Ok(())
    }
}

/// Optional changes to a preset, each field named as the game's cvar (without `sv_`). Used by scene files
/// (`[engine]`) and the command line; `apply` validates the result.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields, rename_all = "kebab-case")]
pub struct VarOverrides {
    /// Frames per second.
    pub fps: Option<f64>,
    /// Truncate the frame time to whole milliseconds.
    pub truncate_frame_time_ms: Option<bool>,
    /// `sv_maxspeed`, ups.
    pub maxspeed: Option<f64>,
    /// `sv_accelerate`.
    pub accelerate: Option<f64>,
    /// `sv_airaccelerate`.
    pub airaccelerate: Option<f64>,
    /// `sv_friction`.
    pub friction: Option<f64>,
    /// Edge friction multiplier.
    pub edgefriction: Option<f64>,
    /// Entity friction `k_e`.
    pub entity_friction: Option<f64>,
    /// `sv_stopspeed`, ups.
    pub stopspeed: Option<f64>,
    /// `sv_maxvelocity`, ups.
    pub maxvelocity: Option<f64>,
    /// `sv_gravity`, ups per second.
    pub gravity: Option<f64>,
    /// Air wish-speed cap, ups.
    pub air_speed_cap: Option<f64>,
    /// Forwardmove with the key held, ups.
    pub forward_key_speed: Option<f64>,
    /// Sidemove with the key held, ups.
    pub side_key_speed: Option<f64>,
    /// Duck move multiplier.
    pub duck_multiplier: Option<f64>,
    /// Unduck time, seconds.
    pub unduck_time_s: Option<f64>,
    /// Vectorial compensation (whole forwardmove and sidemove set with the yaw; off by default).
    pub vectorial_compensation: Option<bool>,
}

impl VarOverrides {
    /// The preset's variables with these overrides applied, validated.
    pub fn apply(&self, mut vars: MovementVars) -> Result<MovementVars> {
        macro_rules! set {
            ($($f:ident),*) => {$(
                if let Some(v) = self.$f {
                    vars.$f = v;
                }
            )*};
        }
        set!(
            fps,
            truncate_frame_time_ms,
            maxspeed,
            accelerate,
            airaccelerate,
            friction,
            edgefriction,
            entity_friction,
            stopspeed,
            maxvelocity,
            gravity,
            air_speed_cap,
            forward_key_speed,
            side_key_speed,
            duck_multiplier,
            unduck_time_s,
            vectorial_compensation
        );
        vars.validate()?;
        Ok(vars)
    }
}
