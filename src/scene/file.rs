//! The scene file as written: raw values, checked only for keys and types ([`SceneFile`]). Every key is
//! kebab-case and unknown keys are refused.

use super::expect::ExpectFile;
use super::shorthand::{Bend90, Hairpin, Lane};
use crate::geometry::{BoundaryKind, FinishPoint};
use crate::physics::{Effect, Preset, VarOverrides, Vec2};
use serde::de::{self, DeserializeSeed, Deserializer, MapAccess, SeqAccess, Visitor};
use serde::Deserialize;
use std::fmt;

/// A scene file before validation. Read one with [`SceneFile::from_toml_str`] or through
/// [`Scene::from_toml_str`](super::Scene::from_toml_str), which also validates it.
#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields, rename_all = "kebab-case")]
pub struct SceneFile {
    /// Scene name; defaults to the file stem.
    #[serde(default)]
    pub name: Option<String>,
    /// Free text.
    #[serde(default)]
    pub description: Option<String>,
    /// Frame cap of a run; defaults to [`DEFAULT_MAX_TIME_S`](super::DEFAULT_MAX_TIME_S) of frames.
    #[serde(default)]
    pub max_frames: Option<u64>,
    /// `[engine]`: preset, effects and movement-variable overrides.
    pub engine: EngineFile,
    /// `[start]`: the player's state at frame 0 (each key optional where a shorthand shape supplies it).
    #[serde(default)]
    pub start: Option<StartFile>,
    /// `[finish]`: the finish line (optional where a shorthand shape supplies it).
    #[serde(default)]
    pub finish: Option<FinishFile>,
    /// `[[walls]]`: explicit walls, added after any shorthand shape's walls.
    #[serde(default)]
    pub walls: Vec<WallFile>,
    /// `[bend90]`: a 90-degree left bend.
    #[serde(default)]
    pub bend90: Option<Bend90>,
    /// `[hairpin]`: a 180-degree left turn.
    #[serde(default)]
    pub hairpin: Option<Hairpin>,
    /// `[lane]`: a straight lane.
    #[serde(default)]
    pub lane: Option<Lane>,
    /// `[expect]`: what `strafeopt check` runs and what must hold (never seen by the simulation).
    #[serde(default)]
    pub expect: Option<ExpectFile>,
}

/// `[engine]`: `preset`, `effects`, and any field of [`VarOverrides`] (`fps = 100`, `airaccelerate = 100`).
#[derive(Clone, Debug, PartialEq)]
pub struct EngineFile {
    /// `preset = "goldsrc"` or `"source-hl2"`.
    pub preset: Preset,
    /// `effects = ["air-accel", ...]`: physics effect names.
    pub effects: Vec<Effect>,
    /// Every other key: changes to the preset (`fps` is required by validation).
    pub overrides: VarOverrides,
}

/// `[start]`; every key is optional when a shorthand shape gives a default start.
#[derive(Clone, Debug, Default, PartialEq, Deserialize)]
#[serde(deny_unknown_fields, rename_all = "kebab-case")]
pub struct StartFile {
    /// `[x, y]` of the hull centre, units.
    pub position: Option<Point>,
    /// `[vx, vy]`, ups.
    pub velocity: Option<Point>,
    /// On the ground (default false).
    pub on_ground: Option<bool>,
    /// Ducked (default false; needs the `duck` effect).
    pub ducked: Option<bool>,
}

/// `[finish]`; `a` and `b` go together.
#[derive(Clone, Debug, Default, PartialEq, Deserialize)]
#[serde(deny_unknown_fields, rename_all = "kebab-case")]
pub struct FinishFile {
    /// One end `[x, y]`, units.
    pub a: Option<Point>,
    /// The other end `[x, y]`, units.
    pub b: Option<Point>,
    /// `"centre"` (default) or `"hull"`.
    pub point: Option<FinishPoint>,
}

/// `[[walls]]`: one polyline or polygon.
#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields, rename_all = "kebab-case")]
pub struct WallFile {
    /// `"rule"` or `"solid"`.
    pub kind: BoundaryKind,
    /// `[[x, y], ...]`, units.
    pub points: Vec<Point>,
    /// Join the last point to the first (default false).
    #[serde(default)]
    pub closed: bool,
}

/// A point or vector written `[x, y]`: exactly two numbers.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Point(pub Vec2);

impl SceneFile {
    /// Parses a scene file's text (keys and types only; see [`Scene`](super::Scene) for validation). The
    /// error is a `toml::de::Error` whose `span()` points at the offending text.
    pub fn from_toml_str(text: &str) -> Result<SceneFile, toml::de::Error> {
        toml::from_str(text)
    }
}

impl<'de> Deserialize<'de> for Point {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Point, D::Error> {
        struct PointVisitor;
        impl<'de> Visitor<'de> for PointVisitor {
            type Value = Point;
            fn expecting(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
                f.write_str("[x, y], two numbers")
            }
            fn visit_seq<A: SeqAccess<'de>>(self, mut seq: A) -> Result<Point, A::Error> {
                let x: f64 = seq
                    .next_element()?
                    .ok_or_else(|| de::Error::invalid_length(0, &self))?;
                let y: f64 = seq
                    .next_element()?
                    .ok_or_else(|| de::Error::invalid_length(1, &self))?;
                let mut extra = 0;
                while seq.next_element::<de::IgnoredAny>()?.is_some() {
                    extra += 1;
                }
                if extra > 0 {
                    return Err(de::Error::invalid_length(2 + extra, &self));
                }
                Ok(Point(Vec2::new(x, y)))
            }
        }
        d.deserialize_seq(PointVisitor)
    }
}

/// The keys of `[engine]` that are not movement variables.
const ENGINE_KEYS: [&str; 2] = ["preset", "effects"];

impl<'de> Deserialize<'de> for EngineFile {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<EngineFile, D::Error> {
        d.deserialize_map(EngineVisitor)
    }
}

struct EngineVisitor;

impl<'de> Visitor<'de> for EngineVisitor {
    type Value = EngineFile;

    fn expecting(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str("an [engine] table")
    }

    fn visit_map<A: MapAccess<'de>>(self, mut map: A) -> Result<EngineFile, A::Error> {
        let mut preset = None;
        let mut effects = None;
        let mut vars = toml::Table::new();
        while let Some(key) = map.next_key::<String>()? {
            match key.as_str() {
                "preset" => preset = Some(map.next_value::<Preset>()?),
                "effects" => effects = Some(map.next_value::<Vec<Effect>>()?),
                _ => map.next_value_seed(OverrideSeed {
                    key: &key,
                    vars: &mut vars,
                })?,
            }
        }
        // Each key was checked on its own (so an error points at its line); together they cannot fail.
        let overrides = VarOverrides::deserialize(toml::Value::Table(vars))
            .map_err(|e| de::Error::custom(e.message()))?;
        Ok(EngineFile {
            preset: preset.ok_or_else(|| de::Error::missing_field("preset"))?,
            effects: effects.ok_or_else(|| de::Error::missing_field("effects"))?,
            overrides,
        })
    }
}

/// Reads one movement-variable key of `[engine]` and checks it against [`VarOverrides`] at once, so that a
/// wrong key or type is reported with this value's position.
struct OverrideSeed<'a> {
    key: &'a str,
    vars: &'a mut toml::Table,
}

impl<'de> DeserializeSeed<'de> for OverrideSeed<'_> {
    type Value = ();

    fn deserialize<D: Deserializer<'de>>(self, d: D) -> Result<(), D::Error> {
        let value = toml::Value::deserialize(d)?;
        let mut one = toml::Table::new();
        one.insert(self.key.to_string(), value.clone());
        VarOverrides::deserialize(toml::Value::Table(one)).map_err(|e| {
            let message = e.message();
            if message.starts_with("unknown field") {
                de::Error::custom(format!(
                    "{message}, or one of `{}`",
                    ENGINE_KEYS.join("`, `")
                ))
            } else {
                de::Error::custom(message)
            }
        })?;
        self.vars.insert(self.key.to_string(), value);
        Ok(())
    }
}
