//! Scenes: a TOML file read ([`SceneFile`], keys and types) and validated ([`Scene`], ready to simulate).
//!
//! ```toml
//! name = "hl-bend90-100fps"          # optional; defaults to the file stem
//! description = "..."                # optional
//! max-frames = 2000                  # optional; default DEFAULT_MAX_TIME_S of frames
//! [engine]
//! preset = "goldsrc"                 # or "source-hl2" (docs/physics.md section 2)
//! fps = 100                          # required; plus any movement variable: airaccelerate = 100, ...
//! effects = ["air-accel", "max-velocity", "walls"]
//! [start]                            # each key optional when a shorthand shape gives a default
//! position = [40, 80]                # hull centre, units
//! velocity = [320, 0]                # ups
//! on-ground = false
//! ducked = false                     # needs the "duck" effect
//! [finish]                           # optional with a shorthand shape
//! a = [1040, 1200]
//! b = [1200, 1200]
//! point = "centre"                   # or "hull": any part of the 32 x 32 box
//! [[walls]]                          # any number, after the shorthand's walls
//! kind = "rule"                      # or "solid" (needs the "walls" effect)
//! points = [[0, 0], [100, 0]]
//! closed = false
//! [bend90]                           # at most one shorthand: [bend90], [hairpin] or [lane]
//! width = 160
//! leg1 = 1200
//! leg2 = 1200
//! kind = "rule"
//! [expect]                           # optional: what `strafeopt check` runs and what must hold
//! command = "solve"                  # see the `expect` module
//! quality = "fast"
//! frames = 401
//! ```
//!
//! Every error is one line, `file:line: key: what is wrong; what is allowed`
//! ([`Error::Scene`]). Validation checks the movement variables and effects, the wall
//! shapes (no zero-length segment, no self-intersection), that the start hull does not overlap a wall, and
//! that a path for the hull exists from the start to the finish line; the last two use the [`geometry`]
//! corridor, so the scene and the simulation agree on what touching means.
//!
//! This is the one module that reads files.
//!
//! [`geometry`]: crate::geometry

pub mod edit;
pub mod expect;
mod file;
pub mod generate;
mod locate;
pub mod shorthand;
mod validate;

pub use crate::geometry::{BoundaryKind, FinishLine, FinishPoint, Wall};
pub use edit::SceneEdit;
pub use expect::{expectation_from_str, Expectation, ExpectedRun, Limits};
pub use file::{EngineFile, FinishFile, Point, SceneFile, StartFile, WallFile};
pub(crate) use locate::one_line;
pub use shorthand::{Bend90, Hairpin, Lane, START_OFFSET_UNITS};

use crate::error::{Error, Result};
use crate::geometry::Corridor;
use crate::physics::{Effects, MovementVars, PlayerState, Preset};
use serde::Serialize;
use std::path::Path;

/// Default frame cap of a run, as a time: `max-frames = ceil(DEFAULT_MAX_TIME_S * fps)`.
pub const DEFAULT_MAX_TIME_S: f64 = 60.0;

/// Largest magnitude of any coordinate of a scene (walls, shorthand shapes, start, finish), units. The
/// contact tolerance of 1e-9 units must stay representable (`f64` spacing is 1.2e-10 at 1e6), and segment
/// lengths and clearances must not overflow; no map comes near it (GoldSrc maps span +-4096 units, Source
/// maps +-16384).
pub const MAX_COORDINATE_UNITS: f64 = 1e6;

/// Largest start speed, ups: far beyond any reachable speed (`sv_maxvelocity` clamps each component at 2000
/// ups in Half-Life, 3500 in Half-Life 2), and small enough that no position of a run overflows.
pub const MAX_START_SPEED_UPS: f64 = 1e6;

/// The text of a scene file. A file that cannot be read is an [`Error::Scene`] naming the path.
pub fn read_text(path: &Path) -> Result<String> {
    std::fs::read_to_string(path).map_err(|e| Error::Scene {
        location: locate::one_line(&path.display().to_string()),
        key: "-".to_string(),
        message: format!("cannot read the file: {e}"),
    })
}

/// A validated scene: everything a simulation needs.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Scene {
    /// Name (the file's `name`, else the file stem).
    pub name: String,
    /// Free text.
    pub description: String,
    /// Where the scene came from (the path given to [`Scene::load`] or the origin given to
    /// [`Scene::from_toml_str`]).
    pub origin: String,
    /// The preset the variables start from.
    pub preset: Preset,
    /// Movement variables: the preset with the file's overrides, validated (docs/physics.md section 2).
    pub vars: MovementVars,
    /// The effects simulated (docs/physics.md section 3), every requirement present.
    pub effects: Effects,
    /// The player at frame 0.
    pub start: PlayerState,
    /// The finish line.
    pub finish: FinishLine,
    /// Walls: the shorthand shape's first, then the file's `[[walls]]` in order.
    pub walls: Vec<Wall>,
    /// Frame cap of a run.
    pub max_frames: u64,
}

impl Scene {
    /// Reads and validates scene text. `origin` names it in errors (usually its path).
    pub fn from_toml_str(text: &str, origin: &str) -> Result<Scene> {
        validate::scene_from_str(text, origin)
    }

    /// Reads and validates a scene file. A file that cannot be read is an [`Error::Scene`] naming the path.
    pub fn load(path: &Path) -> Result<Scene> {
        let text = read_text(path)?;
        Scene::from_toml_str(&text, &path.display().to_string())
    }

    /// The corridor of this scene's walls (valid by construction of a loaded scene).
    pub fn corridor(&self) -> Result<Corridor> {
        Corridor::new(&self.walls)
    }

    /// Frame time `tau`, seconds (docs/physics.md section 1).
    pub fn frame_time_s(&self) -> f64 {
        self.vars.frame_time_s()
    }
}
