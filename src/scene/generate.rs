//! Random valid corridors, seeded: a family of scenes the optimiser was never tuned on.
//!
//! [`generate`] draws one scene from a seed and an item index with the generator's own SplitMix64 stream
//! (`generate/rng.rs`), so item `k` of seed `N` is the same whatever the number of items drawn, on every
//! machine. A scene is an airborne Half-Life (`goldsrc`) run through a corridor: a centre line of straight
//! legs and 1 to 6 turns of 30 to 180 degrees to either side (`generate/centreline.rs`), 64 to 256 units
//! wide, legs of 200 to 1500 units, at 100, 250 or 1000 fps with `sv_airaccelerate` 10 or 100, starting at
//! 0 to 1500 ups along the first leg, between rule or solid walls (docs/physics.md section 10): the default
//! family, [`GeneratorSettings::default`].
//!
//! [`GeneratorSettings::kinds`] adds scenes that start on the ground ([`SceneKind`]): groundstrafing
//! (friction and ground acceleration, no gravity), bunnyhopping (GoldSrc with gravity, jumps, the
//! bunnyhop cap and friction) and Half-Life 2 jumping (Source, gravity, jumps and friction, no jump
//! boost). They run through the same corridors; only the engine, its effects and the start differ.
//!
//! What is drawn, in this order from the item's stream: the number of turns, the width, the frame rate,
//! the air acceleration, the start speed and the wall kind; then the corridor, each turn's angle (whole
//! degrees) and side and each leg's length (whole units), drawn again from the same stream until the
//! corridor does not overlap itself (at most [`GeneratorSettings::max_corridor_draws`] times); then the
//! scene's kind and, for a kind that starts on the ground, its start speed (which replaces the airborne
//! one). Drawn last, the kind changes nothing drawn before it: scene `k` of a seed has the same corridor,
//! frame rate, air acceleration and walls whatever kinds are asked for, and an airborne scene is the same
//! in every family that can draw it (but for the comment line that names the family).
//!
//! Choices of shape:
//! - a leg's length is its straight part: the first from the start wall to the first turn, the last from
//!   the last turn to the finish line (a 180-degree turn has no corner point to measure to);
//! - a turn goes around a pivot `(width + gap) / 2` to its side, so a 180-degree turn leaves a divider
//!   `gap` units thick ([`GeneratorSettings::wall_gap_units`], 16) between the legs; the walls follow the
//!   turn's arcs as polygons, and parts of the corridor that are not neighbours keep their walls at least
//!   `gap / 2` apart;
//! - the start is the hull centre [`START_OFFSET_UNITS`] into the first leg on its centre line (as the
//!   shorthand shapes), airborne or on the ground as the kind says; the start wall closes the corridor
//!   behind it; the finish line spans the last leg's end, wall to wall;
//! - coordinates are written with three decimals and the scene is the one read back from that text, so
//!   a file and the [`GeneratedScene::scene`] it came with are the same scene.
//!
//! The first leg runs along +x from the origin. Nothing here runs the physics: a scene is checked by the
//! scene validator (start clear of the walls, a path for the hull to the finish).

mod centreline;
mod rng;
mod staircase;

pub use centreline::{CentrelinePiece, Side};
pub use rng::SplitMix64;
pub use staircase::{staircase, Staircase, MAX_STAIRCASE_CORNERS};

use super::{Scene, START_OFFSET_UNITS};
use crate::error::{Error, Result};
use crate::geometry::BoundaryKind;
use crate::physics::Vec2;
use centreline::{lay_out, overlaps_itself, Shape};
use serde::Serialize;
use std::fmt::Write as _;

/// Default of [`GeneratorSettings::max_corridor_draws`].
pub const MAX_CORRIDOR_DRAWS: u32 = 10_000;

/// Most turns a corridor may have.
pub const MAX_CORNERS: u32 = 12;

/// Narrowest corridor, units: the hull's 32 units and 8 of room.
pub const MIN_WIDTH_UNITS: u32 = 40;

/// Widest corridor, units.
pub const MAX_WIDTH_UNITS: u32 = 2048;

/// Shortest leg, units: the start hull, [`START_OFFSET_UNITS`] into the first leg, must fit.
pub const MIN_LEG_UNITS: u32 = 64;

/// Longest leg, units: 13 legs and their turns stay far inside the scene's coordinate range.
pub const MAX_LEG_UNITS: u32 = 20_000;

/// Largest start speed, ups: GoldSrc's `sv_maxvelocity`, which clamps each velocity component.
pub const MAX_START_SPEED_UPS: u32 = 2000;

/// Default of [`GeneratorSettings::max_ground_start_speed_ups`], ups: GoldSrc's `sv_maxspeed`, running
/// speed.
pub const MAX_GROUND_START_SPEED_UPS: u32 = 320;

/// Frame rates accepted, fps.
pub const FPS_RANGE: std::ops::RangeInclusive<u32> = 10..=10_000;

/// `sv_airaccelerate` values accepted.
pub const AIRACCELERATE_RANGE: std::ops::RangeInclusive<u32> = 1..=1000;

/// What a generated scene's engine and start are; the corridor is drawn the same way for every kind.
/// Every kind runs at the drawn frame rate (a tick rate for Half-Life 2) and `sv_airaccelerate`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum SceneKind {
    /// Airborne at the drawn start speed, air acceleration only: effects `air-accel`, `max-velocity`,
    /// `walls` (the default family).
    Air,
    /// Groundstrafing: on the ground, no gravity, so the whole run is ground frames: effects
    /// `ground-accel`, `friction`, `max-velocity`, `walls` (as `hl-groundstrafe-1000fps`).
    Ground,
    /// Bunnyhopping from the ground: effects `air-accel`, `ground-accel`, `friction`, `gravity`, `jump`,
    /// `bhop-cap`, `max-velocity`, `walls` (as `hl-bhop-bend90-100fps`).
    Bhop,
    /// Half-Life 2 (`preset = "source-hl2"`) jumping from the ground, without the jump boost: effects
    /// `air-accel`, `ground-accel`, `friction`, `gravity`, `jump`, `max-velocity`, `walls` (as
    /// `hl2-bend90-66fps`).
    Hl2,
}

impl SceneKind {
    /// Every kind, in the order of the command line's help.
    pub const ALL: [SceneKind; 4] = [
        SceneKind::Air,
        SceneKind::Ground,
        SceneKind::Bhop,
        SceneKind::Hl2,
    ];

    /// The name used on the command line, in files and tables.
    pub fn name(self) -> &'static str {
        match self {
            SceneKind::Air => "air",
            SceneKind::Ground => "ground",
            SceneKind::Bhop => "bhop",
            SceneKind::Hl2 => "hl2",
        }
    }

    /// The scene file's `preset`.
    fn preset(self) -> &'static str {
        match self {
            SceneKind::Hl2 => "source-hl2",
            _ => "goldsrc",
        }
    }

    /// The engine in words, for the description.
    fn engine(self) -> &'static str {
        match self {
            SceneKind::Hl2 => "Half-Life 2",
            _ => "GoldSrc",
        }
    }

    /// True for the kinds that start on the ground.
    pub fn on_ground(self) -> bool {
        !matches!(self, SceneKind::Air)
    }

    /// The scene file's `effects` list.
    fn effects(self) -> &'static str {
        match self {
            SceneKind::Air => r#"["air-accel", "max-velocity", "walls"]"#,
            SceneKind::Ground => r#"["ground-accel", "friction", "max-velocity", "walls"]"#,
            SceneKind::Bhop => {
                r#"["air-accel", "ground-accel", "friction", "gravity", "jump", "bhop-cap", "max-velocity", "walls"]"#
            }
            SceneKind::Hl2 => {
                r#"["air-accel", "ground-accel", "friction", "gravity", "jump", "max-velocity", "walls"]"#
            }
        }
    }

    /// The kind in words, for the file's comment and description.
    fn describe(self) -> &'static str {
        match self {
            SceneKind::Air => "airborne, air acceleration only",
            SceneKind::Ground => "groundstrafing: on the ground with friction, no gravity",
            SceneKind::Bhop => {
                "bunnyhopping: from the ground with gravity, jumps, the bunnyhop cap and friction"
            }
            SceneKind::Hl2 => {
                "Half-Life 2: from the ground with gravity, jumps and friction, no jump boost"
            }
        }
    }
}

/// The family to draw from: every range inclusive, in whole units, degrees, fps and ups. `Default` is the
/// full family; [`GeneratorSettings::ci_sized`] a smaller one whose solves take seconds.
#[derive(Clone, Debug, PartialEq, Eq, Serialize)]
pub struct GeneratorSettings {
    /// Fewest turns (at least 1).
    pub min_corners: u32,
    /// Most turns (at most [`MAX_CORNERS`]).
    pub max_corners: u32,
    /// Smallest turn, degrees (at least 1).
    pub min_turn_deg: u32,
    /// Largest turn, degrees (at most 180).
    pub max_turn_deg: u32,
    /// Narrowest corridor, units (at least [`MIN_WIDTH_UNITS`]).
    pub min_width_units: u32,
    /// Widest corridor, units (at most [`MAX_WIDTH_UNITS`]).
    pub max_width_units: u32,
    /// Shortest leg (its straight part), units (at least [`MIN_LEG_UNITS`]).
    pub min_leg_units: u32,
    /// Longest leg, units (at most [`MAX_LEG_UNITS`]).
    pub max_leg_units: u32,
    /// Frame rates to choose from, fps (each in [`FPS_RANGE`]).
    pub fps: Vec<u32>,
    /// `sv_airaccelerate` values to choose from (each in [`AIRACCELERATE_RANGE`]).
    pub airaccelerate: Vec<u32>,
    /// Smallest start speed along the first leg, ups.
    pub min_start_speed_ups: u32,
    /// Largest start speed, ups (at most [`MAX_START_SPEED_UPS`]).
    pub max_start_speed_ups: u32,
    /// Wall kinds to choose from.
    pub wall_kinds: Vec<BoundaryKind>,
    /// Scene kinds to choose from (default: airborne only).
    pub kinds: Vec<SceneKind>,
    /// Smallest start speed of a kind that starts on the ground, ups; a quarter of those scenes start at
    /// exactly this speed (at rest by default), the rest uniformly up to the largest.
    pub min_ground_start_speed_ups: u32,
    /// Largest start speed of a kind that starts on the ground, ups (at most [`MAX_START_SPEED_UPS`]).
    pub max_ground_start_speed_ups: u32,
    /// Margin between two parts of the corridor that are not neighbours: their centre lines stay
    /// `width + gap` apart and their walls at least `gap / 2`; also the divider's thickness at a
    /// 180-degree turn, units (1 to 256).
    pub wall_gap_units: u32,
    /// Most corridors drawn for one scene before giving up (at least 1): the settings then leave (almost)
    /// no corridor that does not overlap itself.
    pub max_corridor_draws: u32,
    /// Whether every scene asks for vectorial compensation (`vectorial-compensation = true`,
    /// docs/physics.md section 1); nothing is drawn for it, so scene k keeps its corridor either way.
    pub vectorial_compensation: bool,
}

impl Default for GeneratorSettings {
    fn default() -> Self {
        GeneratorSettings {
            min_corners: 1,
            max_corners: 6,
            min_turn_deg: 30,
            max_turn_deg: 180,
            min_width_units: 64,
            max_width_units: 256,
            min_leg_units: 200,
            max_leg_units: 1500,
            fps: vec![100, 250, 1000],
            airaccelerate: vec![10, 100],
            min_start_speed_ups: 0,
            max_start_speed_ups: 1500,
            wall_kinds: vec![BoundaryKind::Rule, BoundaryKind::Solid],
            kinds: vec![SceneKind::Air],
            min_ground_start_speed_ups: 0,
            max_ground_start_speed_ups: MAX_GROUND_START_SPEED_UPS,
            wall_gap_units: 16,
            max_corridor_draws: MAX_CORRIDOR_DRAWS,
            vectorial_compensation: false,
        }
    }
}

impl GeneratorSettings {
    /// The family for tests and CI benches: at most 2 turns, legs of at most 800 units, 100 or 250 fps;
    /// the rest as the default family.
    pub fn ci_sized() -> Self {
        GeneratorSettings {
            max_corners: 2,
            max_leg_units: 800,
            fps: vec![100, 250],
            ..GeneratorSettings::default()
        }
    }

    /// Checks every range; the error names the field (`max_corners`) and what is allowed.
    pub fn validate(&self) -> Result<()> {
        self.check_ranges()?;
        check_list("fps", &self.fps, &FPS_RANGE)?;
        check_list("airaccelerate", &self.airaccelerate, &AIRACCELERATE_RANGE)?;
        self.check_kinds()?;
        if !(1..=256).contains(&self.wall_gap_units) {
            return Err(Error::invalid(
                "wall_gap_units",
                f64::from(self.wall_gap_units),
                "from 1 to 256",
            ));
        }
        if self.max_corridor_draws == 0 {
            return Err(Error::invalid("max_corridor_draws", 0.0, "at least 1"));
        }
        Ok(())
    }

    /// Each `min_`/`max_` pair within its allowed range and in order.
    fn check_ranges(&self) -> Result<()> {
        let pairs = [
            (
                "corners",
                self.min_corners,
                self.max_corners,
                1,
                MAX_CORNERS,
            ),
            ("turn_deg", self.min_turn_deg, self.max_turn_deg, 1, 180),
            (
                "width_units",
                self.min_width_units,
                self.max_width_units,
                MIN_WIDTH_UNITS,
                MAX_WIDTH_UNITS,
            ),
            (
                "leg_units",
                self.min_leg_units,
                self.max_leg_units,
                MIN_LEG_UNITS,
                MAX_LEG_UNITS,
            ),
            (
                "start_speed_ups",
                self.min_start_speed_ups,
                self.max_start_speed_ups,
                0,
                MAX_START_SPEED_UPS,
            ),
            (
                "ground_start_speed_ups",
                self.min_ground_start_speed_ups,
                self.max_ground_start_speed_ups,
                0,
                MAX_START_SPEED_UPS,
            ),
        ];
        pairs
            .into_iter()
            .try_for_each(|(name, lo, hi, floor, ceil)| check_range(name, lo, hi, floor, ceil))
    }

    /// The wall kinds and scene kinds, each at least one.
    fn check_kinds(&self) -> Result<()> {
        if self.wall_kinds.is_empty() {
            return Err(Error::InvalidValue {
                name: "wall_kinds".to_string(),
                value: "an empty list".to_string(),
                allowed: "rule, solid or both".to_string(),
            });
        }
        if self.kinds.is_empty() {
            return Err(Error::InvalidValue {
                name: "kinds".to_string(),
                value: "an empty list".to_string(),
                allowed: "one or more of air, ground, bhop, hl2".to_string(),
            });
        }
        Ok(())
    }

    /// The family in one line (`corners 1-6, turns 30-180 deg, ...`), for files and reports. The scene
    /// kinds and ground start speeds are named only when a kind other than airborne is asked for: the
    /// airborne family's line does not name them.
    pub fn describe(&self) -> String {
        let join = |v: &[u32]| v.iter().map(u32::to_string).collect::<Vec<_>>().join("/");
        let kinds: Vec<&str> = self.wall_kinds.iter().map(|k| k.name()).collect();
        let mut line = format!(
            "corners {}-{}, turns {}-{} deg, widths {}-{} units, legs {}-{} units, fps {}, \
             airaccelerate {}, start speeds {}-{} ups, {} walls, wall gap {} units",
            self.min_corners,
            self.max_corners,
            self.min_turn_deg,
            self.max_turn_deg,
            self.min_width_units,
            self.max_width_units,
            self.min_leg_units,
            self.max_leg_units,
            join(&self.fps),
            join(&self.airaccelerate),
            self.min_start_speed_ups,
            self.max_start_speed_ups,
            kinds.join("/"),
            self.wall_gap_units,
        );
        if self.vectorial_compensation {
            line.push_str(", vectorial compensation");
        }
        if self.kinds != [SceneKind::Air] {
            let names: Vec<&str> = self.kinds.iter().map(|k| k.name()).collect();
            let _ = write!(line, ", kinds {}", names.join("/"));
            if self.kinds.iter().any(|k| k.on_ground()) {
                let _ = write!(
                    line,
                    ", ground start speeds {}-{} ups",
                    self.min_ground_start_speed_ups, self.max_ground_start_speed_ups
                );
            }
        }
        line
    }
}

/// One turn of a generated corridor.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
pub struct Turn {
    /// Angle turned, degrees.
    pub degrees: u32,
    /// Which way.
    pub side: Side,
}

/// What was drawn for one scene.
#[derive(Clone, Debug, PartialEq, Eq, Serialize)]
pub struct Drawn {
    /// Corridor width, units.
    pub width_units: u32,
    /// Straight part of each leg, units, from the start (one more than the turns).
    pub legs_units: Vec<u32>,
    /// The turns, from the start.
    pub turns: Vec<Turn>,
    /// Frame rate, fps.
    pub fps: u32,
    /// `sv_airaccelerate`.
    pub airaccelerate: u32,
    /// Start speed along the first leg, ups: the airborne draw, or the ground draw for a kind that starts
    /// on the ground.
    pub start_speed_ups: u32,
    /// Kind of every wall.
    pub walls: BoundaryKind,
    /// The scene's kind: its effects and whether it starts on the ground.
    pub kind: SceneKind,
    /// Corridors drawn until one did not overlap itself (1 when the first did).
    pub corridor_draws: u32,
}

/// A generated scene: what was drawn, the centre line, the file's text and the scene read from it.
#[derive(Clone, Debug, PartialEq)]
pub struct GeneratedScene {
    /// The family's seed.
    pub seed: u64,
    /// The item's index in the family.
    pub index: u64,
    /// `gen-SEED-INDEX`, the scene's name and file stem.
    pub name: String,
    /// What was drawn.
    pub drawn: Drawn,
    /// The corridor's centre line, piece by piece (legs and turns alternate).
    pub centreline: Vec<CentrelinePiece>,
    /// The scene file's text (TOML, explicit walls), with the seed and the draws in a leading comment.
    pub toml: String,
    /// The scene read back from [`GeneratedScene::toml`] and validated.
    pub scene: Scene,
}

impl GeneratedScene {
    /// The file name the scene is written under: `gen-SEED-INDEX.toml`.
    pub fn file_name(&self) -> String {
        format!("{}.toml", self.name)
    }
}

/// Scene `index` of the family `seed` (see the module documentation). Errors when the settings are out of
/// range ([`Error::InvalidValue`]) or leave no corridor that does not overlap itself within
/// [`GeneratorSettings::max_corridor_draws`] ([`Error::Unreachable`]).
pub fn generate(seed: u64, index: u64, settings: &GeneratorSettings) -> Result<GeneratedScene> {
    settings.validate()?;
    let mut rng = SplitMix64::for_item(seed, index);
    let corners = rng.in_range(settings.min_corners, settings.max_corners);
    let width_units = rng.in_range(settings.min_width_units, settings.max_width_units);
    let fps = pick(&mut rng, &settings.fps)?;
    let airaccelerate = pick(&mut rng, &settings.airaccelerate)?;
    let start_speed_ups = rng.in_range(settings.min_start_speed_ups, settings.max_start_speed_ups);
    let walls = pick(&mut rng, &settings.wall_kinds)?;
    let width = f64::from(width_units);
    let gap = f64::from(settings.wall_gap_units);

    for draw in 1..=settings.max_corridor_draws {
        let (turns, legs_units) = draw_corridor(&mut rng, corners, settings);
        let Some(layout) = clear_layout(width, gap, &legs_units, &turns) else {
            continue;
        };
        let kind = pick(&mut rng, &settings.kinds)?;
        let start_speed_ups = if kind.on_ground() {
            ground_start_speed(&mut rng, settings)
        } else {
            start_speed_ups
        };
        let drawn = Drawn {
            width_units,
            legs_units,
            turns: turns
                .into_iter()
                .map(|(degrees, side)| Turn { degrees, side })
                .collect(),
            fps,
            airaccelerate,
            start_speed_ups,
            walls,
            kind,
            corridor_draws: draw,
        };
        let name = format!("gen-{seed}-{index}");
        let header = header_comment(seed, index, settings, &drawn);
        let origin = format!("Generated (seed {seed}, scene {index})");
        let vectorial = settings.vectorial_compensation;
        let toml = scene_text(&name, &header, &origin, &drawn, &layout, vectorial);
        let scene = Scene::from_toml_str(&toml, &format!("{name}.toml"))?;
        return Ok(GeneratedScene {
            seed,
            index,
            name,
            drawn,
            centreline: layout.pieces,
            toml,
            scene,
        });
    }
    Err(Error::Unreachable {
        what: format!(
            "scene {index} of seed {seed}: no corridor of {corners} turns {width_units} units wide that does \
             not overlap itself in {} draws; allow longer legs, smaller turns or fewer corners",
            settings.max_corridor_draws
        ),
    })
}

/// The corridor of `legs_units` and `turns`, `width` wide with dividers `gap` thick (units), laid out;
/// `None` when it overlaps itself.
fn clear_layout(
    width: f64,
    gap: f64,
    legs_units: &[u32],
    turns: &[(u32, Side)],
) -> Option<centreline::Layout> {
    let layout = lay_out(&Shape {
        width_units: width,
        gap_units: gap,
        legs_units,
        turns,
    });
    (!overlaps_itself(&layout.pieces, width, gap)).then_some(layout)
}

/// One draw of a corridor: each turn's angle and side, then each leg's length (one more than the turns).
fn draw_corridor(
    rng: &mut SplitMix64,
    corners: u32,
    settings: &GeneratorSettings,
) -> (Vec<(u32, Side)>, Vec<u32>) {
    let turns = (0..corners)
        .map(|_| {
            let degrees = rng.in_range(settings.min_turn_deg, settings.max_turn_deg);
            let side = if rng.coin() { Side::Left } else { Side::Right };
            (degrees, side)
        })
        .collect();
    let legs = (0..=corners)
        .map(|_| rng.in_range(settings.min_leg_units, settings.max_leg_units))
        .collect();
    (turns, legs)
}

/// A ground start's speed: a quarter of the time the range's lowest (at rest by default), else uniform
/// over the range, ups.
fn ground_start_speed(rng: &mut SplitMix64, settings: &GeneratorSettings) -> u32 {
    let lo = settings.min_ground_start_speed_ups;
    if rng.below(4) == 0 {
        lo
    } else {
        rng.in_range(lo, settings.max_ground_start_speed_ups)
    }
}

/// Scenes `0..count` of the family `seed`: the fixed sample tests and benches use.
pub fn generate_sample(
    seed: u64,
    count: u64,
    settings: &GeneratorSettings,
) -> Result<Vec<GeneratedScene>> {
    (0..count).map(|k| generate(seed, k, settings)).collect()
}

fn pick<T: Copy>(rng: &mut SplitMix64, items: &[T]) -> Result<T> {
    rng.pick(items).ok_or_else(|| Error::Unreachable {
        what: "the generator was given an empty list to choose from".to_string(),
    })
}

/// A coordinate as written: three decimals, no negative zero.
fn coordinate(v: f64) -> String {
    let text = format!("{v:.3}");
    if text
        .trim_start_matches('-')
        .chars()
        .all(|c| c == '0' || c == '.')
    {
        "0.000".to_string()
    } else {
        text
    }
}

fn point(p: Vec2) -> String {
    format!("[{}, {}]", coordinate(p.x), coordinate(p.y))
}

/// The turns as words: `left 95, right 140`.
fn turns_text(turns: &[Turn]) -> String {
    turns
        .iter()
        .map(|t| format!("{} {}", t.side.name(), t.degrees))
        .collect::<Vec<_>>()
        .join(", ")
}

/// The file's leading comment: where the scene comes from and everything drawn.
fn header_comment(seed: u64, index: u64, settings: &GeneratorSettings, d: &Drawn) -> String {
    let legs: Vec<String> = d.legs_units.iter().map(u32::to_string).collect();
    let flags = if *settings == GeneratorSettings::default() {
        ""
    } else {
        " and the flags of the family below"
    };
    let mut s = String::new();
    // `write!` to a String cannot fail.
    let _ = writeln!(
        s,
        "# Generated by strafeopt: scene {index} of seed {seed} (`strafeopt gen --seed {seed} --count {}`{flags}),",
        index + 1
    );
    let _ = writeln!(s, "# family: {}.", settings.describe());
    let _ = writeln!(
        s,
        "# Drawn: {} turns (degrees: {}); width {} units; legs {} units (straight parts); {} fps,",
        d.turns.len(),
        turns_text(&d.turns),
        d.width_units,
        legs.join(", "),
        d.fps
    );
    let _ = writeln!(
        s,
        "# sv_airaccelerate {}; start speed {} ups along the first leg; {} walls; corridor draw {}.",
        d.airaccelerate,
        d.start_speed_ups,
        d.walls.name(),
        d.corridor_draws
    );
    if d.kind != SceneKind::Air {
        let _ = writeln!(s, "# Kind: {} ({}).", d.kind.name(), d.kind.describe());
    }
    s
}

/// The scene file: the leading comment `header`, then the scene with explicit walls; its description
/// starts with `origin`; with `vectorial_compensation`, its `[engine]` asks for it.
fn scene_text(
    name: &str,
    header: &str,
    origin: &str,
    d: &Drawn,
    layout: &centreline::Layout,
    vectorial_compensation: bool,
) -> String {
    let corners = d.turns.len();
    let mut s = header.to_string();
    let _ = writeln!(s, "name = \"{name}\"");
    let start_words = match d.kind {
        SceneKind::Air => "airborne at",
        SceneKind::Ground => "groundstrafing from",
        SceneKind::Bhop => "bunnyhopping from the ground at",
        SceneKind::Hl2 => "jumping from the ground at",
    };
    let _ = writeln!(
        s,
        "description = \"{origin}: {}, {} fps, sv_airaccelerate {}, {start_words} \
         {} ups; {corners} turns ({}), {} units wide, {} walls\"",
        d.kind.engine(),
        d.fps,
        d.airaccelerate,
        d.start_speed_ups,
        turns_text(&d.turns),
        d.width_units,
        d.walls.name()
    );
    let _ = writeln!(
        s,
        "\n[engine]\npreset = \"{}\"\nfps = {}",
        d.kind.preset(),
        d.fps
    );
    let _ = writeln!(s, "airaccelerate = {}", d.airaccelerate);
    if vectorial_compensation {
        let _ = writeln!(s, "vectorial-compensation = true");
    }
    let _ = writeln!(s, "effects = {}", d.kind.effects());
    let start = Vec2::new(START_OFFSET_UNITS, 0.0);
    let velocity = Vec2::new(f64::from(d.start_speed_ups), 0.0);
    let _ = writeln!(
        s,
        "\n[start]\nposition = {}\nvelocity = {}\non-ground = {}",
        point(start),
        point(velocity),
        d.kind.on_ground()
    );
    let (finish_a, finish_b) = match (layout.left.last(), layout.right.last()) {
        (Some(&a), Some(&b)) => (a, b),
        _ => (Vec2::ZERO, Vec2::ZERO),
    };
    let _ = writeln!(
        s,
        "\n[finish]\na = {}\nb = {}",
        point(finish_a),
        point(finish_b)
    );
    // One polyline: the left wall from the finish back to the start, the start wall, the right wall.
    let points: Vec<String> = layout
        .left
        .iter()
        .rev()
        .chain(&layout.right)
        .map(|&p| point(p))
        .collect();
    let _ = writeln!(
        s,
        "\n# Left wall from the finish to the start, the start wall, the right wall to the finish.\n[[walls]]\n\
         kind = \"{}\"\npoints = [\n    {},\n]",
        d.walls.name(),
        points.join(",\n    ")
    );
    s
}

/// `min_NAME = lo` and `max_NAME = hi` each within `floor..=ceil`, and `lo <= hi`.
fn check_range(name: &str, lo: u32, hi: u32, floor: u32, ceil: u32) -> Result<()> {
    for (which, v) in [("min", lo), ("max", hi)] {
        if !(floor..=ceil).contains(&v) {
            return Err(Error::invalid(
                format!("{which}_{name}"),
                f64::from(v),
                format!("from {floor} to {ceil}"),
            ));
        }
    }
    if lo > hi {
        return Err(Error::invalid(
            format!("min_{name}"),
            f64::from(lo),
            format!("at most max_{name} ({hi})"),
        ));
    }
    Ok(())
}

/// A list of values `name`, not empty and each in `allowed`.
fn check_list(name: &str, values: &[u32], allowed: &std::ops::RangeInclusive<u32>) -> Result<()> {
    if values.is_empty() {
        return Err(Error::InvalidValue {
            name: name.to_string(),
            value: "an empty list".to_string(),
            allowed: "at least one value".to_string(),
        });
    }
    match values.iter().find(|v| !allowed.contains(v)) {
        Some(&v) => Err(Error::invalid(
            name,
            f64::from(v),
            format!("from {} to {}", allowed.start(), allowed.end()),
        )),
        None => Ok(()),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn default_settings_are_the_full_family_and_valid() {
        let s = GeneratorSettings::default();
        assert!(s.validate().is_ok());
        assert_eq!((s.min_corners, s.max_corners), (1, 6));
        assert_eq!((s.min_turn_deg, s.max_turn_deg), (30, 180));
        assert_eq!((s.min_width_units, s.max_width_units), (64, 256));
        assert_eq!((s.min_leg_units, s.max_leg_units), (200, 1500));
        assert_eq!(s.fps, [100, 250, 1000]);
        assert_eq!(s.airaccelerate, [10, 100]);
        assert_eq!((s.min_start_speed_ups, s.max_start_speed_ups), (0, 1500));
        assert_eq!(s.kinds, [SceneKind::Air]);
        assert!(GeneratorSettings::ci_sized().validate().is_ok());
    }

    #[test]
    fn out_of_range_settings_name_the_field() {
        let bad = |f: fn(&mut GeneratorSettings)| {
            let mut s = GeneratorSettings::default();
            f(&mut s);
            match s.validate() {
                Err(Error::InvalidValue { name, .. }) => name,
                other => panic!("{other:?}"),
            }
        };
        assert_eq!(bad(|s| s.max_corners = 0), "max_corners");
        assert_eq!(bad(|s| s.min_corners = 7), "min_corners");
        assert_eq!(bad(|s| s.max_turn_deg = 181), "max_turn_deg");
        assert_eq!(bad(|s| s.min_width_units = 32), "min_width_units");
        assert_eq!(bad(|s| s.fps = vec![100, 0]), "fps");
        assert_eq!(bad(|s| s.airaccelerate.clear()), "airaccelerate");
        assert_eq!(bad(|s| s.max_start_speed_ups = 2001), "max_start_speed_ups");
        assert_eq!(bad(|s| s.wall_kinds.clear()), "wall_kinds");
        assert_eq!(bad(|s| s.wall_gap_units = 0), "wall_gap_units");
        assert_eq!(bad(|s| s.kinds.clear()), "kinds");
        assert_eq!(
            bad(|s| s.max_ground_start_speed_ups = 2001),
            "max_ground_start_speed_ups"
        );
        assert_eq!(
            bad(|s| s.min_ground_start_speed_ups = 400),
            "min_ground_start_speed_ups"
        );
    }

    #[test]
    fn coordinates_have_three_decimals_and_no_negative_zero() {
        assert_eq!(coordinate(-0.0001), "0.000");
        assert_eq!(coordinate(-0.0), "0.000");
        assert_eq!(coordinate(12.34567), "12.346");
        assert_eq!(coordinate(-5.0), "-5.000");
    }
}
