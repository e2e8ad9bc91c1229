//! The effects a scene can ask for (docs/physics.md section 3). The frame step runs only those a scene names:
//! a purely airborne scene pays nothing for friction, gravity or jumps.

use serde::{Deserialize, Serialize};
use std::fmt;

/// One effect of the frame (docs/physics.md section 3), as named in scene files.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Effect {
    /// Air acceleration: the FME with `L = min(30, M)` (step 4, airborne).
    AirAccel,
    /// Ground acceleration: the FME with `L = M` (step 4, on the ground).
    GroundAccel,
    /// Ground friction `lambda(v)` (step 3, section 4).
    Friction,
    /// Edge friction: friction multiplied by `e_f` (needs `friction`).
    EdgeFriction,
    /// Gravity half-steps, the flat floor and ground categorisation (steps 1 and 6).
    Gravity,
    /// Jumping off the ground (step 2; needs `gravity`).
    Jump,
    /// The bunnyhop cap on a jump (section 10; needs `jump`).
    BhopCap,
    /// The Source jump boost and accelerated backhopping (section 11; needs `jump`).
    JumpBoost,
    /// The per-component `sv_maxvelocity` clamp (steps 1 and 4).
    MaxVelocity,
    /// Ducking: the duck button, hull height, move multiplier and unduck time.
    Duck,
    /// Solid walls: the hull is swept and clipped (section 10). Applied by the simulation, not the step.
    Walls,
}

impl Effect {
    /// Every effect, in frame order.
    pub const ALL: [Effect; 11] = [
        Effect::Duck,
        Effect::Gravity,
        Effect::Jump,
        Effect::BhopCap,
        Effect::JumpBoost,
        Effect::Friction,
        Effect::EdgeFriction,
        Effect::MaxVelocity,
        Effect::AirAccel,
        Effect::GroundAccel,
        Effect::Walls,
    ];

    /// The name used in scene files.
    pub fn name(self) -> &'static str {
        match self {
            Effect::AirAccel => "air-accel",
            Effect::GroundAccel => "ground-accel",
            Effect::Friction => "friction",
            Effect::EdgeFriction => "edge-friction",
            Effect::Gravity => "gravity",
            Effect::Jump => "jump",
            Effect::BhopCap => "bhop-cap",
            Effect::JumpBoost => "jump-boost",
            Effect::MaxVelocity => "max-velocity",
            Effect::Duck => "duck",
            Effect::Walls => "walls",
        }
    }

    /// The effects this one needs (`jump` needs `gravity`). The Source jump boost also needs the
    /// velocity clamp: backhops double the excess speed every hop (docs/physics.md section 11), and only
    /// `sv_maxvelocity` stops that reaching infinity.
    pub fn requires(self) -> &'static [Effect] {
        match self {
            Effect::EdgeFriction => &[Effect::Friction],
            Effect::Jump => &[Effect::Gravity],
            Effect::BhopCap => &[Effect::Jump],
            Effect::JumpBoost => &[Effect::Jump, Effect::MaxVelocity],
            _ => &[],
        }
    }

    #[inline]
    const fn bit(self) -> u16 {
        1 << (self as u16)
    }
}

impl fmt::Display for Effect {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

/// A set of effects (a bit set: testing one is a single AND in the hot loop).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub struct Effects(u16);

impl Effects {
    /// No effect at all.
    pub const NONE: Effects = Effects(0);

    /// Airborne strafing only: air acceleration (add `max-velocity` and `walls` as needed).
    pub const AIR_ONLY: Effects = Effects(Effect::AirAccel.bit());

    /// Every effect.
    pub fn all() -> Effects {
        Effect::ALL.iter().fold(Effects::NONE, |s, &e| s.with(e))
    }

    /// The set from a list.
    pub fn from_list(list: &[Effect]) -> Effects {
        list.iter().fold(Effects::NONE, |s, &e| s.with(e))
    }

    /// This set plus `e`.
    #[inline]
    pub const fn with(self, e: Effect) -> Effects {
        Effects(self.0 | e.bit())
    }

    /// This set less `e`.
    #[inline]
    pub const fn without(self, e: Effect) -> Effects {
        Effects(self.0 & !e.bit())
    }

    /// True when `e` is in the set.
    #[inline]
    pub const fn has(self, e: Effect) -> bool {
        self.0 & e.bit() != 0
    }

    /// The effects in the set, in frame order.
    pub fn list(self) -> Vec<Effect> {
        Effect::ALL.into_iter().filter(|&e| self.has(e)).collect()
    }

    /// The first effect present whose requirement is missing, with that requirement.
    pub fn missing_requirement(self) -> Option<(Effect, Effect)> {
        self.list().into_iter().find_map(|e| {
            e.requires()
                .iter()
                .find(|&&r| !self.has(r))
                .map(|&r| (e, r))
        })
    }

    /// True when only air acceleration, the velocity clamp and walls are asked for: the frame is then just
    /// steps 4 and 5 of docs/physics.md section 3.
    #[inline]
    pub const fn is_air_only(self) -> bool {
        let air = Effect::AirAccel.bit() | Effect::MaxVelocity.bit() | Effect::Walls.bit();
        self.0 & !air == 0
    }
}

impl Serialize for Effects {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        self.list().serialize(s)
    }
}

impl<'de> Deserialize<'de> for Effects {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        let list = Vec::<Effect>::deserialize(d)?;
        Ok(Effects::from_list(&list))
    }
}

impl fmt::Display for Effects {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let names: Vec<&str> = self.list().into_iter().map(Effect::name).collect();
        f.write_str(&names.join(", "))
    }
}
