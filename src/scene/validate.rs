//! From a parsed [`SceneFile`] to a validated [`Scene`], with every error located at its key's line.

use super::file::{Point, SceneFile};
use super::locate::KeyIndex;
use super::shorthand::{BadParam, Expanded};
use super::{Scene, DEFAULT_MAX_TIME_S, MAX_COORDINATE_UNITS, MAX_START_SPEED_UPS};
use crate::error::{Error, Result};
use crate::geometry::{
    BoundaryKind, Corridor, FinishLine, Wall, WallDefect, CONTACT_TOL_UNITS,
    MIN_SEGMENT_LENGTH_UNITS,
};
use crate::physics::{Effect, Effects, MovementVars, PlayerState, Vec2};
use serde::Deserialize;
use std::path::Path;
use toml::de::DeTable;

/// Parses, then validates.
pub(crate) fn scene_from_str(text: &str, origin: &str) -> Result<Scene> {
    let doc = DeTable::parse(text).map_err(|e| KeyIndex::empty(origin, text).toml_error(&e))?;
    let index = KeyIndex::new(origin, text, &doc);
    let file = SceneFile::deserialize(toml::de::Deserializer::from(doc))
        .map_err(|e| index.toml_error(&e))?;
    build(file, &index, origin)
}

/// A shorthand shape that was given: its table name and expansion.
struct Shape {
    name: &'static str,
    expanded: Expanded,
}

fn build(file: SceneFile, ix: &KeyIndex<'_>, origin: &str) -> Result<Scene> {
    // The expectations are checked like any table, then left to `strafeopt check`.
    if let Some(expect) = &file.expect {
        super::expect::validate(expect, ix)?;
    }
    let shape = shorthand(&file, ix)?;
    let (vars, effects, max_frames) = engine_of(&file, ix)?;
    let (walls, wall_keys) = walls_of(&file, shape.as_ref());
    for (wall, key) in walls.iter().zip(&wall_keys) {
        check_wall(wall, key, effects, ix)?;
    }
    let start = start_state(&file, shape.as_ref(), &vars, effects, ix)?;
    let (finish, finish_key) = finish_line(&file, shape.as_ref(), ix)?;
    let corridor = Corridor::new(&walls)?;
    let start_key = if file.start.as_ref().and_then(|s| s.position).is_some() {
        "start.position"
    } else {
        shape.as_ref().map_or("start.position", |s| s.name)
    };
    check_start_and_path(
        &corridor,
        &start,
        start_key,
        &wall_keys,
        &finish,
        &finish_key,
        ix,
    )?;
    let name = file.name.clone().unwrap_or_else(|| {
        Path::new(origin)
            .file_stem()
            .map_or_else(|| origin.to_string(), |s| s.to_string_lossy().into_owned())
    });
    Ok(Scene {
        name,
        description: file.description.clone().unwrap_or_default(),
        origin: origin.to_string(),
        preset: file.engine.preset,
        vars,
        effects,
        start,
        finish,
        walls,
        max_frames,
    })
}

/// The engine of a scene file: its preset with the overrides, its effects (each with what it needs),
/// and the most frames a run of it may take (docs/physics.md sections 2, 3).
fn engine_of(file: &SceneFile, ix: &KeyIndex<'_>) -> Result<(MovementVars, Effects, u64)> {
    let engine = &file.engine;
    let fps = engine.overrides.fps.ok_or_else(|| {
        ix.error(
            "engine.fps",
            "missing; give the frame rate, a finite number above 0 (tau = 1/fps s)",
        )
    })?;
    let vars = engine
        .overrides
        .apply(MovementVars::preset(engine.preset, fps))
        .map_err(|e| engine_error(ix, e))?;
    let effects = Effects::from_list(&engine.effects);
    if let Some((effect, needs)) = effects.missing_requirement() {
        return Err(ix.error(
            "engine.effects",
            format!("effect \"{effect}\" needs \"{needs}\"; add \"{needs}\" to the list"),
        ));
    }
    let max_frames = match file.max_frames {
        Some(0) => return Err(ix.error("max-frames", "got 0; must be at least 1")),
        Some(n) => n,
        // Finite and positive: vars.validate() checked the frame time.
        None => (DEFAULT_MAX_TIME_S / vars.frame_time_s()).ceil() as u64,
    };
    Ok((vars, effects, max_frames))
}

/// The walls of a scene: the shorthand shape's, then the file's, each with the key that names it in
/// messages.
fn walls_of(file: &SceneFile, shape: Option<&Shape>) -> (Vec<Wall>, Vec<String>) {
    let mut walls = Vec::new();
    let mut wall_keys = Vec::new();
    if let Some(s) = shape {
        for w in &s.expanded.walls {
            walls.push(w.clone());
            wall_keys.push(s.name.to_string());
        }
    }
    for (i, wf) in file.walls.iter().enumerate() {
        walls.push(Wall {
            points: wf.points.iter().map(|p| p.0).collect(),
            closed: wf.closed,
            kind: wf.kind,
        });
        wall_keys.push(format!("walls[{i}]"));
    }
    (walls, wall_keys)
}

/// A wall named `key` checked: enough finite points, every one in range, no zero-length segment nor
/// self-intersection, and solid only with the walls effect.
fn check_wall(wall: &Wall, key: &str, effects: Effects, ix: &KeyIndex<'_>) -> Result<()> {
    let points_key = if key.starts_with("walls[") {
        format!("{key}.points")
    } else {
        key.to_string()
    };
    // The point `i` of this wall in messages: its own line for a file's wall, else the shape's.
    let point_key = |i: usize| {
        if key.starts_with("walls[") {
            format!("{points_key}[{i}]")
        } else {
            points_key.clone()
        }
    };
    let defect = wall.defect();
    // Too few or non-finite points first; then the range, before any shape test measures lengths.
    let out_of_range = wall.points.iter().position(|&p| !within_range(p));
    if let (
        None | Some(WallDefect::ZeroLength { .. } | WallDefect::SelfIntersection { .. }),
        Some(i),
    ) = (defect, out_of_range)
    {
        let q = wall.points[i];
        let what = if key.starts_with("walls[") {
            format!("point {i} is at")
        } else {
            format!("[{key}] reaches")
        };
        return Err(ix.error_at(
            &points_key,
            &point_key(i),
            format!(
                "{what} ({}, {}); every coordinate must be between -{MAX_COORDINATE_UNITS} and \
                 {MAX_COORDINATE_UNITS} units",
                short(q.x),
                short(q.y),
            ),
        ));
    }
    if let Some(defect) = defect {
        let locate_at = defect.point().map_or(points_key.clone(), point_key);
        return Err(ix.error_at(&points_key, &locate_at, defect.to_string()));
    }
    if wall.kind == BoundaryKind::Solid && !effects.has(Effect::Walls) {
        return Err(ix.error(
            &format!("{key}.kind"),
            "solid walls need the \"walls\" effect; add \"walls\" to engine.effects, or use \
             kind = \"rule\"",
        ));
    }
    Ok(())
}

/// The geometry's checks: the start hull clear of every wall (`start_key` names the start, `wall_keys`
/// the walls), and the finish line (`finish_key`) reachable from it.
fn check_start_and_path(
    corridor: &Corridor,
    start: &PlayerState,
    start_key: &str,
    wall_keys: &[String],
    finish: &FinishLine,
    finish_key: &str,
    ix: &KeyIndex<'_>,
) -> Result<()> {
    if let Some(n) = corridor.nearest(start.pos, None) {
        if n.clearance_units < -CONTACT_TOL_UNITS {
            return Err(ix.error_at(
                "start.position",
                start_key,
                format!(
                    "the hull at ({}, {}) overlaps {} (segment {}) by {} units; the 32 x 32 hull may touch a \
                     wall but not overlap it",
                    start.pos.x,
                    start.pos.y,
                    wall_keys[n.wall],
                    n.segment,
                    -n.clearance_units
                ),
            ));
        }
    }
    if corridor
        .shortest_path(start.pos, (finish.a, finish.b))
        .is_none()
    {
        return Err(ix.error(
            finish_key,
            format!(
                "no path for the hull from the start ({}, {}) to the finish line ({}, {})-({}, {}); the walls \
                 must leave the 32 x 32 hull a way through",
                start.pos.x, start.pos.y, finish.a.x, finish.a.y, finish.b.x, finish.b.y
            ),
        ));
    }
    Ok(())
}

/// The one shorthand shape given, expanded; an error when more than one is given or a parameter is out
/// of range.
fn shorthand(file: &SceneFile, ix: &KeyIndex<'_>) -> Result<Option<Shape>> {
    let mut given: Vec<(&'static str, std::result::Result<Expanded, BadParam>)> = [
        file.bend90.map(|s| ("bend90", s.expand())),
        file.hairpin.map(|s| ("hairpin", s.expand())),
        file.lane.map(|s| ("lane", s.expand())),
    ]
    .into_iter()
    .flatten()
    .collect();
    if given.len() > 1 {
        // Blame the one written later.
        given.sort_by_key(|(name, _)| ix.line_of(name));
        return Err(ix.error(
            given[1].0,
            format!(
                "a scene takes at most one shorthand shape ([bend90], [hairpin] or [lane]); [{}] is given \
                 already",
                given[0].0
            ),
        ));
    }
    match given.into_iter().next() {
        None => Ok(None),
        Some((name, Ok(expanded))) => Ok(Some(Shape { name, expanded })),
        Some((name, Err(bad))) => Err(ix.error(&format!("{name}.{}", bad.key), bad.message)),
    }
}

/// An error from validating the movement variables, at its `[engine]` key.
fn engine_error(ix: &KeyIndex<'_>, e: Error) -> Error {
    match e {
        Error::InvalidValue {
            name,
            value,
            allowed,
        } => ix.error(
            &format!("engine.{name}"),
            format!("got {value}; must be {allowed}"),
        ),
        other => ix.error("engine", other.to_string()),
    }
}

/// True when both coordinates are finite and within [`MAX_COORDINATE_UNITS`].
fn within_range(p: Vec2) -> bool {
    p.x.abs() <= MAX_COORDINATE_UNITS && p.y.abs() <= MAX_COORDINATE_UNITS
}

/// A number for a message: plain when moderate, in exponent form when huge or tiny (`1e300`, not 301
/// digits).
fn short(v: f64) -> String {
    if v == 0.0 || !v.is_finite() || (1e-6..1e9).contains(&v.abs()) {
        format!("{v}")
    } else {
        format!("{v:e}")
    }
}

/// A position `[x, y]`: finite and within [`MAX_COORDINATE_UNITS`].
fn position(ix: &KeyIndex<'_>, key: &str, p: Point) -> Result<Vec2> {
    if within_range(p.0) {
        Ok(p.0)
    } else {
        Err(ix.error(
            key,
            format!(
                "got [{}, {}]; must be two finite numbers, each between -{MAX_COORDINATE_UNITS} and \
                 {MAX_COORDINATE_UNITS} units",
                short(p.0.x),
                short(p.0.y),
            ),
        ))
    }
}

/// The player at frame 0: the file's `[start]`, defaults from the shape.
fn start_state(
    file: &SceneFile,
    shape: Option<&Shape>,
    vars: &MovementVars,
    effects: Effects,
    ix: &KeyIndex<'_>,
) -> Result<PlayerState> {
    let sf = file.start.clone().unwrap_or_default();
    let pos = match (sf.position, shape) {
        (Some(p), _) => position(ix, "start.position", p)?,
        (None, Some(s)) => s.expanded.start_position,
        (None, None) => {
            return Err(ix.error(
                "start.position",
                "missing; give the hull centre [x, y] in units (only a shorthand shape supplies a default)",
            ))
        }
    };
    let vel = match (sf.velocity, shape) {
        (Some(v), _) => v.0,
        (None, Some(s)) => s.expanded.start_direction * vars.maxspeed,
        (None, None) => Vec2::ZERO,
    };
    // Finite (a NaN fails the comparison) and at most MAX_START_SPEED_UPS (`hypot` cannot overflow).
    let speed = vel.x.hypot(vel.y);
    let speed_ok = speed <= MAX_START_SPEED_UPS;
    if !speed_ok {
        let (locate_at, what) = match (sf.velocity, shape) {
            (None, Some(s)) => (
                "engine.maxspeed",
                format!(
                    "the default start velocity (sv_maxspeed along [{}]) has speed {} ups",
                    s.name,
                    short(speed)
                ),
            ),
            _ => (
                "start.velocity",
                format!("got [{}, {}]", short(vel.x), short(vel.y)),
            ),
        };
        return Err(ix.error_at(
            "start.velocity",
            locate_at,
            format!(
                "{what}; must be two finite numbers with a speed of at most {MAX_START_SPEED_UPS} ups"
            ),
        ));
    }
    let ducked = sf.ducked.unwrap_or(false);
    if ducked && !effects.has(Effect::Duck) {
        return Err(ix.error(
            "start.ducked",
            "a ducked start needs the \"duck\" effect; add \"duck\" to engine.effects",
        ));
    }
    let on_ground = sf.on_ground.unwrap_or(false);
    Ok(PlayerState {
        ducked,
        ..if on_ground {
            PlayerState::on_ground(pos, vel)
        } else {
            PlayerState::airborne(pos, vel)
        }
    })
}

/// The finish line (the file's `[finish]`, else the shape's) and the key to blame for it.
fn finish_line(
    file: &SceneFile,
    shape: Option<&Shape>,
    ix: &KeyIndex<'_>,
) -> Result<(FinishLine, String)> {
    let ff = file.finish.clone().unwrap_or_default();
    let ((a, b), key) = match (ff.a, ff.b, shape) {
        (Some(a), Some(b), _) => (
            (
                position(ix, "finish.a", a)?,
                position(ix, "finish.b", b)?,
            ),
            "finish".to_string(),
        ),
        (None, None, Some(s)) => (s.expanded.finish, s.name.to_string()),
        (Some(_), None, _) => return Err(ix.error("finish.b", "missing; give both ends, a and b")),
        (None, Some(_), _) => return Err(ix.error("finish.a", "missing; give both ends, a and b")),
        (None, None, None) => {
            return Err(ix.error(
                "finish",
                "missing; give [finish] with ends a and b, or a shorthand shape ([bend90], [hairpin], [lane])",
            ))
        }
    };
    let finish = FinishLine {
        a,
        b,
        point: ff.point.unwrap_or_default(),
    };
    if finish.length_units() <= MIN_SEGMENT_LENGTH_UNITS {
        return Err(ix.error(
            &key,
            format!(
                "the finish line has zero length; a and b must be more than {MIN_SEGMENT_LENGTH_UNITS:e} units \
                 apart"
            ),
        ));
    }
    Ok((finish, key))
}
