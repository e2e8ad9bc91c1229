//! `strafeopt gen --seed N [--count K] -o DIR`: writes generated scenes ([`crate::scene::generate`]) as
//! `DIR/gen-N-k.toml`, one line per scene on stdout. [`FamilyFlags`] narrows the family; `bench
//! --generated` takes the same flags.

use super::write_atomically;
use crate::error::{Error, Result};
use crate::geometry::BoundaryKind;
use crate::scene::generate::{generate_sample, GeneratedScene, GeneratorSettings, SceneKind};
use clap::{Args, ValueEnum};
use std::io::Write;
use std::path::{Path, PathBuf};

/// Most scenes one `gen` writes.
pub const MAX_COUNT: u64 = 10_000;

/// `strafeopt gen ...`
#[derive(Debug, Args)]
pub struct GenArgs {
    /// Seed of the family (any 64-bit number).
    #[arg(long)]
    pub seed: u64,
    /// How many scenes (1 to 10000). Scene k of a seed is the same whatever the count.
    #[arg(long, default_value_t = 1, allow_negative_numbers = true)]
    pub count: i64,
    /// Directory to write the scenes into (created when missing).
    #[arg(short = 'o', long = "output")]
    pub output: PathBuf,
    #[command(flatten)]
    #[allow(missing_docs)]
    pub family: FamilyFlags,
}

/// Wall kinds on the command line.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum WallsArg {
    /// Rule lines only.
    Rule,
    /// Solid walls only.
    Solid,
}

/// Scene kinds on the command line.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum KindArg {
    /// Airborne, air acceleration only (the default family).
    Air,
    /// Groundstrafing: on the ground with friction and ground acceleration, no gravity.
    Ground,
    /// Bunnyhopping: from the ground with gravity, jumps, the bunnyhop cap and friction.
    Bhop,
    /// Half-Life 2 (Source) from the ground with gravity, jumps and friction, no jump boost.
    Hl2,
}

impl KindArg {
    fn kind(self) -> SceneKind {
        match self {
            KindArg::Air => SceneKind::Air,
            KindArg::Ground => SceneKind::Ground,
            KindArg::Bhop => SceneKind::Bhop,
            KindArg::Hl2 => SceneKind::Hl2,
        }
    }
}

/// Flags that narrow the generated family (each replaces one range or list of the settings).
#[derive(Debug, Args, Clone, Default, PartialEq, Eq)]
pub struct FamilyFlags {
    /// Start from the CI-sized family: at most 2 turns, legs up to 800 units, 100 or 250 fps.
    #[arg(long)]
    pub ci_sized: bool,
    /// Frame rates to choose from, comma-separated (default 100,250,1000).
    #[arg(long, value_delimiter = ',')]
    pub fps: Vec<u32>,
    /// sv_airaccelerate values to choose from, comma-separated (default 10,100).
    #[arg(long, value_delimiter = ',')]
    pub airaccelerate: Vec<u32>,
    /// Fewest turns (default 1).
    #[arg(long)]
    pub min_corners: Option<u32>,
    /// Most turns (default 6).
    #[arg(long)]
    pub max_corners: Option<u32>,
    /// Narrowest corridor, units (default 64).
    #[arg(long)]
    pub min_width: Option<u32>,
    /// Widest corridor, units (default 256).
    #[arg(long)]
    pub max_width: Option<u32>,
    /// Shortest leg, units (default 200).
    #[arg(long)]
    pub min_leg: Option<u32>,
    /// Longest leg, units (default 1500).
    #[arg(long)]
    pub max_leg: Option<u32>,
    /// Only this wall kind (default: either).
    #[arg(long, value_enum)]
    pub walls: Option<WallsArg>,
    /// Scene kinds to choose from, comma-separated (default air): air (GoldSrc, airborne at 0-1500
    /// ups), ground (GoldSrc groundstrafing, no gravity), bhop (GoldSrc bunnyhopping: gravity, jumps, the
    /// bunnyhop cap, friction), hl2 (Half-Life 2 with gravity, jumps and friction, no jump boost, the
    /// frame rate as its tick rate). All but air start on the ground at rest or at up to 320 ups along
    /// the first leg. Scene k keeps its corridor whatever the kinds.
    #[arg(long, value_enum, value_delimiter = ',')]
    pub kinds: Vec<KindArg>,
    /// Every scene asks for vectorial compensation (`vectorial-compensation = true` in `[engine]`): plans
    /// for a replay tool that writes forwardmove and sidemove itself. The corridors are the same.
    #[arg(long)]
    pub vectorial_compensation: bool,
}

impl FamilyFlags {
    /// The first flag given, if any.
    pub fn first_given(&self) -> Option<&'static str> {
        [
            (self.ci_sized, "--ci-sized"),
            (!self.fps.is_empty(), "--fps"),
            (!self.airaccelerate.is_empty(), "--airaccelerate"),
            (self.min_corners.is_some(), "--min-corners"),
            (self.max_corners.is_some(), "--max-corners"),
            (self.min_width.is_some(), "--min-width"),
            (self.max_width.is_some(), "--max-width"),
            (self.min_leg.is_some(), "--min-leg"),
            (self.max_leg.is_some(), "--max-leg"),
            (self.walls.is_some(), "--walls"),
            (!self.kinds.is_empty(), "--kinds"),
            (self.vectorial_compensation, "--vectorial-compensation"),
        ]
        .into_iter()
        .find_map(|(given, flag)| given.then_some(flag))
    }

    /// The settings these flags ask for, validated; an error names the flag.
    pub fn settings(&self) -> Result<GeneratorSettings> {
        let mut s = if self.ci_sized {
            GeneratorSettings::ci_sized()
        } else {
            GeneratorSettings::default()
        };
        if !self.fps.is_empty() {
            s.fps.clone_from(&self.fps);
        }
        if !self.airaccelerate.is_empty() {
            s.airaccelerate.clone_from(&self.airaccelerate);
        }
        let set = |field: &mut u32, flag: Option<u32>| {
            if let Some(v) = flag {
                *field = v;
            }
        };
        set(&mut s.min_corners, self.min_corners);
        set(&mut s.max_corners, self.max_corners);
        set(&mut s.min_width_units, self.min_width);
        set(&mut s.max_width_units, self.max_width);
        set(&mut s.min_leg_units, self.min_leg);
        set(&mut s.max_leg_units, self.max_leg);
        if let Some(w) = self.walls {
            s.wall_kinds = vec![match w {
                WallsArg::Rule => BoundaryKind::Rule,
                WallsArg::Solid => BoundaryKind::Solid,
            }];
        }
        if !self.kinds.is_empty() {
            let mut kinds: Vec<SceneKind> = Vec::new();
            for k in self.kinds.iter().map(|k| k.kind()) {
                if !kinds.contains(&k) {
                    kinds.push(k);
                }
            }
            s.kinds = kinds;
        }
        s.vectorial_compensation = self.vectorial_compensation;
        s.validate().map_err(flag_error)?;
        Ok(s)
    }
}

/// A settings error renamed from the field to the flag that sets it.
fn flag_error(e: Error) -> Error {
    const FLAGS: [(&str, &str); 10] = [
        ("min_corners", "--min-corners"),
        ("max_corners", "--max-corners"),
        ("min_width_units", "--min-width"),
        ("max_width_units", "--max-width"),
        ("min_leg_units", "--min-leg"),
        ("max_leg_units", "--max-leg"),
        ("fps", "--fps"),
        ("airaccelerate", "--airaccelerate"),
        ("wall_kinds", "--walls"),
        ("kinds", "--kinds"),
    ];
    match e {
        Error::InvalidValue {
            name,
            value,
            allowed,
        } => {
            let rename = |text: &str| {
                FLAGS
                    .iter()
                    .fold(text.to_string(), |t, (field, flag)| t.replace(field, flag))
            };
            Error::InvalidValue {
                name: rename(&name),
                value,
                allowed: rename(&allowed),
            }
        }
        other => other,
    }
}

/// The count, checked: 1 to [`MAX_COUNT`].
pub fn checked_count(flag: &str, count: i64) -> Result<u64> {
    match u64::try_from(count) {
        Ok(n) if (1..=MAX_COUNT).contains(&n) => Ok(n),
        _ => Err(Error::InvalidValue {
            name: flag.to_string(),
            value: count.to_string(),
            allowed: format!("a whole number from 1 to {MAX_COUNT}"),
        }),
    }
}

/// Creates `dir` when missing and checks that a file can be written in it.
fn writable_dir(dir: &Path) -> Result<()> {
    let refuse = |why: std::io::Error| Error::InvalidValue {
        name: "--output".to_string(),
        value: dir.display().to_string(),
        allowed: format!("a directory that can be created and written to ({why})"),
    };
    std::fs::create_dir_all(dir).map_err(refuse)?;
    let probe = dir.join(format!(".strafeopt-gen-probe-{}", std::process::id()));
    std::fs::File::create(&probe)
        .and_then(|mut f| f.write_all(b"probe"))
        .map_err(refuse)?;
    std::fs::remove_file(&probe).map_err(refuse)
}

/// One line about a scene: file, turns, width, fps, air acceleration, start speed, walls, kind.
pub fn scene_line(path: &Path, g: &GeneratedScene) -> String {
    let d = &g.drawn;
    format!(
        "{}  corners {}  width {:>4}  fps {:>4}  aa {:>3}  start {:>4} ups  {} walls  {}\n",
        path.display(),
        d.turns.len(),
        d.width_units,
        d.fps,
        d.airaccelerate,
        d.start_speed_ups,
        d.walls.name(),
        d.kind.name()
    )
}

/// Runs `gen`: every scene is drawn before any file is written.
pub fn run(args: &GenArgs) -> Result<String> {
    let count = checked_count("--count", args.count)?;
    let settings = args.family.settings()?;
    let scenes = generate_sample(args.seed, count, &settings)?;
    writable_dir(&args.output)?;
    let mut out = String::new();
    for g in &scenes {
        let path = args.output.join(g.file_name());
        write_atomically(&path, |w| w.write_all(g.toml.as_bytes()))?;
        out.push_str(&scene_line(&path, g));
    }
    Ok(out)
}
