//! The scene as an editor holds it ([`SceneEdit`]): every wall explicit (a shorthand shape expanded), the
//! start and the finish written out, the engine as the file gave it (preset, effects, overrides). It reads
//! and writes JSON for the planner page and writes scene-file TOML; it is validated by writing that TOML
//! and reading it back through [`Scene::from_toml_str`], so an edited scene gets the same checks and the
//! same `file:line: key: message` errors as a file, and the TOML saved is the scene that was checked.

use super::file::SceneFile;
use super::Scene;
use crate::error::{Error, Result};
use crate::geometry::{BoundaryKind, FinishPoint};
use crate::physics::{Effect, Preset, VarOverrides, Vec2};
use serde::{Deserialize, Serialize};
use std::fmt::Write as _;

/// Most wall points an edited scene may have: far beyond a hand-drawn corridor, and small enough that
/// validating the walls (pairwise segment tests) stays well under a second.
pub const MAX_EDIT_WALL_POINTS: usize = 2000;

/// Most walls an edited scene may have.
pub const MAX_EDIT_WALLS: usize = 200;

/// A scene being edited. JSON keys are kebab-case like the scene file's; points are `[x, y]` in units.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, rename_all = "kebab-case")]
pub struct SceneEdit {
    /// Scene name.
    pub name: String,
    /// Free text.
    #[serde(default)]
    pub description: String,
    /// Frame cap of a run (`None`: the default of the scene file).
    #[serde(default)]
    pub max_frames: Option<u64>,
    /// Preset, effects and movement-variable overrides.
    pub engine: EngineEdit,
    /// The player at frame 0.
    pub start: StartEdit,
    /// The finish line.
    pub finish: FinishEdit,
    /// The walls, in order.
    pub walls: Vec<WallEdit>,
}

/// `[engine]` of an edited scene.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, rename_all = "kebab-case")]
pub struct EngineEdit {
    /// The preset the variables start from.
    pub preset: Preset,
    /// The effects simulated (docs/physics.md section 3).
    pub effects: Vec<Effect>,
    /// Changes to the preset (`fps` is required by validation; `airaccelerate`, ...).
    pub vars: VarOverrides,
}

/// `[start]` of an edited scene.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, rename_all = "kebab-case")]
pub struct StartEdit {
    /// Hull centre `[x, y]`, units.
    pub position: [f64; 2],
    /// Velocity `[vx, vy]`, ups.
    pub velocity: [f64; 2],
    /// Standing on the floor.
    #[serde(default)]
    pub on_ground: bool,
    /// Ducked.
    #[serde(default)]
    pub ducked: bool,
}

/// `[finish]` of an edited scene.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, rename_all = "kebab-case")]
pub struct FinishEdit {
    /// One end `[x, y]`, units.
    pub a: [f64; 2],
    /// The other end, units.
    pub b: [f64; 2],
    /// Which part of the player must cross.
    #[serde(default)]
    pub point: FinishPoint,
}

/// One `[[walls]]` entry of an edited scene.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, rename_all = "kebab-case")]
pub struct WallEdit {
    /// Rule line or solid wall.
    pub kind: BoundaryKind,
    /// Vertices `[x, y]`, units.
    pub points: Vec<[f64; 2]>,
    /// Join the last point to the first.
    #[serde(default)]
    pub closed: bool,
}

fn pair(v: Vec2) -> [f64; 2] {
    [v.x, v.y]
}

impl SceneEdit {
    /// The editable form of scene text: validated first (so the edit starts from a good scene), then
    /// written out with the validated walls, start and finish in place of any shorthand shape.
    pub fn from_toml_str(text: &str, origin: &str) -> Result<SceneEdit> {
        let scene = Scene::from_toml_str(text, origin)?;
        // The text validated, so it parses; the error is kept in words all the same.
        let file = SceneFile::from_toml_str(text).map_err(|e| Error::Scene {
            location: origin.to_string(),
            key: "-".to_string(),
            message: e.message().to_string(),
        })?;
        Ok(SceneEdit {
            name: scene.name.clone(),
            description: scene.description.clone(),
            max_frames: file.max_frames,
            engine: EngineEdit {
                preset: file.engine.preset,
                effects: file.engine.effects.clone(),
                vars: file.engine.overrides,
            },
            start: StartEdit {
                position: pair(scene.start.pos),
                velocity: pair(scene.start.vel),
                on_ground: scene.start.on_ground,
                ducked: scene.start.ducked,
            },
            finish: FinishEdit {
                a: pair(scene.finish.a),
                b: pair(scene.finish.b),
                point: scene.finish.point,
            },
            walls: scene
                .walls
                .iter()
                .map(|w| WallEdit {
                    kind: w.kind,
                    points: w.points.iter().copied().map(pair).collect(),
                    closed: w.closed,
                })
                .collect(),
        })
    }

    /// Checks the size limits ([`MAX_EDIT_WALLS`], [`MAX_EDIT_WALL_POINTS`]) before anything costly runs.
    pub fn check_size(&self) -> Result<()> {
        if self.walls.len() > MAX_EDIT_WALLS {
            return Err(Error::InvalidValue {
                name: "walls".to_string(),
                value: format!("{} walls", self.walls.len()),
                allowed: format!("at most {MAX_EDIT_WALLS} walls"),
            });
        }
        let points: usize = self.walls.iter().map(|w| w.points.len()).sum();
        if points > MAX_EDIT_WALL_POINTS {
            return Err(Error::InvalidValue {
                name: "walls".to_string(),
                value: format!("{points} points"),
                allowed: format!("at most {MAX_EDIT_WALL_POINTS} wall points in all"),
            });
        }
        Ok(())
    }

    /// Validates the edit as the scene file [`SceneEdit::to_toml`] writes, named `origin` in errors.
    pub fn validate(&self, origin: &str) -> Result<Scene> {
        self.check_size()?;
        Scene::from_toml_str(&self.to_toml(), origin)
    }

    /// The scene file of this edit. Numbers are written so they read back exactly (`f64` shortest
    /// round-trip form; `nan` and `inf` as TOML spells them, for the validator to refuse).
    pub fn to_toml(&self) -> String {
        let mut s = String::new();
        let _ = writeln!(s, "name = {}", toml_string(&self.name));
        if !self.description.is_empty() {
            let _ = writeln!(s, "description = {}", toml_string(&self.description));
        }
        if let Some(n) = self.max_frames {
            let _ = writeln!(s, "max-frames = {n}");
        }
        s.push_str("\n[engine]\n");
        let _ = writeln!(s, "preset = {}", toml_string(self.engine.preset.name()));
        let effects: Vec<String> = self
            .engine
            .effects
            .iter()
            .map(|e| toml_string(e.name()))
            .collect();
        let _ = writeln!(s, "effects = [{}]", effects.join(", "));
        // The overrides' own serde names, in field order; unset ones are left out.
        if let Ok(serde_json::Value::Object(vars)) = serde_json::to_value(self.engine.vars) {
            for (key, value) in vars {
                match value {
                    serde_json::Value::Bool(b) => {
                        let _ = writeln!(s, "{key} = {b}");
                    }
                    serde_json::Value::Number(n) => {
                        let _ =
                            writeln!(s, "{key} = {}", toml_float(n.as_f64().unwrap_or(f64::NAN)));
                    }
                    _ => {}
                }
            }
        }
        s.push_str("\n[start]\n");
        let _ = writeln!(s, "position = {}", toml_point(self.start.position));
        let _ = writeln!(s, "velocity = {}", toml_point(self.start.velocity));
        let _ = writeln!(s, "on-ground = {}", self.start.on_ground);
        if self.start.ducked {
            s.push_str("ducked = true\n");
        }
        s.push_str("\n[finish]\n");
        let _ = writeln!(s, "a = {}", toml_point(self.finish.a));
        let _ = writeln!(s, "b = {}", toml_point(self.finish.b));
        if self.finish.point != FinishPoint::Centre {
            s.push_str("point = \"hull\"\n");
        }
        for w in &self.walls {
            s.push_str("\n[[walls]]\n");
            let _ = writeln!(s, "kind = {}", toml_string(w.kind.name()));
            // One point a line, so an error about a point names its own line.
            s.push_str("points = [\n");
            for &p in &w.points {
                let _ = writeln!(s, "  {},", toml_point(p));
            }
            s.push_str("]\n");
            if w.closed {
                s.push_str("closed = true\n");
            }
        }
        s
    }
}

/// A TOML float that reads back as exactly `v`.
fn toml_float(v: f64) -> String {
    if v.is_nan() {
        "nan".to_string()
    } else if v.is_infinite() {
        if v > 0.0 { "inf" } else { "-inf" }.to_string()
    } else {
        // Debug is the shortest round-trip form and always has a `.` or an exponent (`40.0`, `1e300`).
        format!("{v:?}")
    }
}

fn toml_point(p: [f64; 2]) -> String {
    format!("[{}, {}]", toml_float(p[0]), toml_float(p[1]))
}

/// A TOML basic string: quotes, backslashes and control characters escaped.
fn toml_string(text: &str) -> String {
    let mut s = String::with_capacity(text.len() + 2);
    s.push('"');
    for c in text.chars() {
        match c {
            '"' => s.push_str("\\\""),
            '\\' => s.push_str("\\\\"),
            '\n' => s.push_str("\\n"),
            '\t' => s.push_str("\\t"),
            '\r' => s.push_str("\\r"),
            c if c.is_control() => {
                let _ = write!(s, "\\u{:04X}", c as u32);
            }
            c => s.push(c),
        }
    }
    s.push('"');
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    const BEND: &str = include_str!("../../scenarios/hl-bend90-100fps.toml");

    #[test]
    fn an_expanded_shorthand_scene_validates_to_the_same_scene() {
        let original = Scene::from_toml_str(BEND, "bend.toml").unwrap_or_else(|e| panic!("{e}"));
        let edit = SceneEdit::from_toml_str(BEND, "bend.toml").unwrap_or_else(|e| panic!("{e}"));
        assert!(!edit.to_toml().contains("[bend90]"));
        let again = edit.validate("bend.toml").unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(again, original);
    }

    #[test]
    fn json_round_trips_and_numbers_read_back_exactly() {
        let mut edit =
            SceneEdit::from_toml_str(BEND, "bend.toml").unwrap_or_else(|e| panic!("{e}"));
        edit.start.position = [40.1 + 1e-13, 80.0 / 3.0];
        edit.engine.vars.airaccelerate = Some(0.1 + 0.2);
        edit.name = "a \"quoted\"\nname".to_string();
        let json = serde_json::to_string(&edit).unwrap_or_else(|e| panic!("{e}"));
        let back: SceneEdit = serde_json::from_str(&json).unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(back, edit);
        let scene = edit.validate("edit.toml").unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(scene.start.pos, Vec2::new(40.1 + 1e-13, 80.0 / 3.0));
        assert_eq!(scene.vars.airaccelerate, 0.1 + 0.2);
        assert_eq!(scene.name, "a \"quoted\"\nname");
    }

    #[test]
    fn a_bad_point_is_an_error_at_its_own_line_and_key() {
        let mut edit =
            SceneEdit::from_toml_str(BEND, "bend.toml").unwrap_or_else(|e| panic!("{e}"));
        edit.walls[0].points[2] = edit.walls[0].points[1];
        let toml = edit.to_toml();
        let err = edit
            .validate("edit.toml")
            .err()
            .map(|e| e.to_string())
            .unwrap_or_default();
        // The point's own line (points 1 and 2 are now the same text; either may be blamed).
        let point_line = format!("{},", toml_point(edit.walls[0].points[2]));
        let lines: Vec<String> = toml
            .lines()
            .enumerate()
            .filter(|(_, l)| l.trim() == point_line)
            .map(|(i, _)| format!("edit.toml:{}: walls[0].points: ", i + 1))
            .collect();
        assert_eq!(lines.len(), 2, "{toml}");
        assert!(
            lines.iter().any(|l| err.starts_with(l)),
            "{err} at none of {lines:?}"
        );
        edit.walls[0].points[2] = [f64::INFINITY, 0.0];
        let err = edit.validate("edit.toml").err().map(|e| e.to_string());
        assert!(
            err.as_deref()
                .is_some_and(|e| e.contains("walls[0].points")),
            "{err:?}"
        );
    }

    #[test]
    fn too_many_points_are_refused_before_validation() {
        let mut edit =
            SceneEdit::from_toml_str(BEND, "bend.toml").unwrap_or_else(|e| panic!("{e}"));
        edit.walls.push(WallEdit {
            kind: BoundaryKind::Rule,
            points: (0..MAX_EDIT_WALL_POINTS)
                .map(|i| [i as f64, -500.0])
                .collect(),
            closed: false,
        });
        let err = edit.validate("edit.toml").err().map(|e| e.to_string());
        assert!(
            err.as_deref().is_some_and(|e| e.contains("at most 2000")),
            "{err:?}"
        );
    }
}
