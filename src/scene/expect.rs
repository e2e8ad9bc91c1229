//! `[expect]`: what `strafeopt check` runs on a scene and what its result must satisfy (a scenario
//! regression test). The simulation and the optimiser never see it: a [`Scene`](super::Scene) does not
//! carry it, and [`expectation_from_str`] reads it on its own, even from a scene that is meant to be
//! refused.
//!
//! ```toml
//! [expect]
//! command = "solve"            # or "simulate" (default "solve")
//! quality = "fast"             # solve only: "fast", "balanced" (default) or "exact"
//! frames = 401                 # the finish line crossed in frame 401 or earlier
//! time = 4.001484              # crossing time at most this, seconds ...
//! time-tolerance = 1e-6        # ... plus this, seconds (default 0)
//! gap-percent = 0.563          # (time - lower bound) / lower bound at most this, percent
//! valid = true                 # the run reaches the line without breaking a rule
//! engine-exact-valid = true    # solve only: the plan is also valid replayed in the engine-exact mode
//! status = "converged"         # solve only: one status or a list of allowed ones
//! ```
//!
//! or, for a scene that must be refused, `error = "start.position: the hull"`: a part of the one-line
//! message (`key: message`, without the file and line) that the refusal must contain.

use super::locate::KeyIndex;
use crate::error::Result;
use serde::de::{self, Deserializer, SeqAccess, Visitor};
use serde::Deserialize;
use std::fmt;
use toml::de::DeTable;

/// The statuses `solve` reports (the `status` of its `--json`), in the words `[expect] status` takes.
pub const SOLVE_STATUSES: [&str; 5] = [
    "converged",
    "time-limit",
    "cancelled",
    "greedy-optimal",
    "no-improvement",
];

/// `[expect]` as written: keys and types only. See the module documentation for each key.
#[derive(Clone, Debug, Default, PartialEq, Deserialize)]
#[serde(deny_unknown_fields, rename_all = "kebab-case")]
pub struct ExpectFile {
    /// `"solve"` (default) or `"simulate"`.
    pub command: Option<ExpectCommand>,
    /// The `solve` quality (default `balanced`).
    pub quality: Option<ExpectQuality>,
    /// The `simulate` controller (default `greedy`, the best of its look-aheads).
    pub controller: Option<ExpectController>,
    /// Frames to the finish line, at most.
    pub frames: Option<u64>,
    /// Crossing time, seconds, at most (plus `time-tolerance`).
    pub time: Option<f64>,
    /// Added to `time`, seconds (default 0).
    pub time_tolerance: Option<f64>,
    /// Gap to the lower bound, percent, at most.
    pub gap_percent: Option<f64>,
    /// Whether the run must be valid (reach the line without breaking a rule).
    pub valid: Option<bool>,
    /// Whether the plan must be valid in the engine-exact mode (`solve` only).
    pub engine_exact_valid: Option<bool>,
    /// The allowed `solve` statuses.
    pub status: Option<StatusList>,
    /// The scene must be refused with a message holding this text.
    pub error: Option<String>,
}

/// The command an expectation runs.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum ExpectCommand {
    /// `strafeopt solve`.
    Solve,
    /// `strafeopt simulate`.
    Simulate,
}

/// The `solve` quality of an expectation (the names of `solve --quality`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum ExpectQuality {
    /// `--quality fast`.
    Fast,
    /// `--quality balanced`.
    Balanced,
    /// `--quality exact`.
    Exact,
}

/// The `simulate` controller of an expectation (the names of `simulate --controller`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum ExpectController {
    /// The greedy strafer, best of its look-aheads.
    Greedy,
    /// The greedy strafer turning as sharply as its target needs, best of its look-aheads.
    SharpTurns,
    /// Maximum acceleration turning left.
    MaxAccelLeft,
    /// Maximum acceleration turning right.
    MaxAccelRight,
    /// Accelerated backhopping.
    Abh,
}

/// `status = "converged"` or `status = ["converged", "greedy-optimal"]`.
#[derive(Clone, Debug, PartialEq)]
pub struct StatusList(pub Vec<String>);

impl<'de> Deserialize<'de> for StatusList {
    fn deserialize<D: Deserializer<'de>>(d: D) -> std::result::Result<StatusList, D::Error> {
        struct StatusVisitor;
        impl<'de> Visitor<'de> for StatusVisitor {
            type Value = StatusList;
            fn expecting(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
                f.write_str("a status name or a list of status names")
            }
            fn visit_str<E: de::Error>(self, v: &str) -> std::result::Result<StatusList, E> {
                Ok(StatusList(vec![v.to_string()]))
            }
            fn visit_seq<A: SeqAccess<'de>>(
                self,
                mut seq: A,
            ) -> std::result::Result<StatusList, A::Error> {
                let mut names = Vec::new();
                while let Some(name) = seq.next_element::<String>()? {
                    names.push(name);
                }
                Ok(StatusList(names))
            }
        }
        d.deserialize_any(StatusVisitor)
    }
}

/// What `[expect]` asks, validated.
#[derive(Clone, Debug, PartialEq)]
pub enum Expectation {
    /// The scene must be refused with a message (`key: message`) holding `message_contains`.
    Refused {
        /// The text the refusal must hold.
        message_contains: String,
    },
    /// The scene must load, `run` must finish, and every limit given must hold.
    Runs {
        /// What to run.
        run: ExpectedRun,
        /// The figures that must hold.
        limits: Limits,
    },
}

/// The command an expectation runs, with its setting.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ExpectedRun {
    /// `solve --quality Q`.
    Solve(ExpectQuality),
    /// `simulate --controller C`.
    Simulate(ExpectController),
}

/// The figures of a run that must hold; `None` is not checked. Every number is an upper bound.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Limits {
    /// Frames to the finish line, at most.
    pub frames: Option<u64>,
    /// Crossing time, seconds, at most (plus `time_tolerance_s`).
    pub time_s: Option<f64>,
    /// Added to `time_s`, seconds.
    pub time_tolerance_s: f64,
    /// Gap to the lower bound, percent, at most.
    pub gap_percent: Option<f64>,
    /// The run's validity (f64 replay).
    pub valid: Option<bool>,
    /// The plan's validity in the engine-exact mode (`solve` only).
    pub engine_exact_valid: Option<bool>,
    /// Allowed `solve` statuses (names of [`SOLVE_STATUSES`]).
    pub status: Option<Vec<String>>,
}

impl Limits {
    /// True when no figure is checked.
    pub fn is_empty(&self) -> bool {
        self.frames.is_none()
            && self.time_s.is_none()
            && self.gap_percent.is_none()
            && self.valid.is_none()
            && self.engine_exact_valid.is_none()
            && self.status.is_none()
    }
}

/// Only the `[expect]` table of a document; every other key is left to the scene's own reader.
#[derive(Deserialize)]
struct ExpectOnly {
    #[serde(default)]
    expect: Option<ExpectFile>,
}

/// Reads the `[expect]` table of scene text alone (`None` when there is none), validated, with errors
/// located like the scene's (`path:line: expect.key: message`). The rest of the file is not checked, so
/// the expectation of a scene meant to be refused can be read.
pub fn expectation_from_str(text: &str, origin: &str) -> Result<Option<Expectation>> {
    let doc = DeTable::parse(text).map_err(|e| KeyIndex::empty(origin, text).toml_error(&e))?;
    let index = KeyIndex::new(origin, text, &doc);
    let only = ExpectOnly::deserialize(toml::de::Deserializer::from(doc))
        .map_err(|e| index.toml_error(&e))?;
    only.expect.map(|e| validate(&e, &index)).transpose()
}

/// Checks the values of an `[expect]` table and the keys that go together.
pub(crate) fn validate(file: &ExpectFile, ix: &KeyIndex<'_>) -> Result<Expectation> {
    if let Some(message) = &file.error {
        return refusal(file, message, ix);
    }
    let run = expected_run(file, ix)?;
    let time_tolerance_s = checked_limits(file, ix)?;
    if let Some(StatusList(names)) = &file.status {
        check_statuses(names, ix)?;
    }
    Ok(Expectation::Runs {
        run,
        limits: Limits {
            frames: file.frames,
            time_s: file.time,
            time_tolerance_s,
            gap_percent: file.gap_percent,
            valid: file.valid,
            engine_exact_valid: file.engine_exact_valid,
            status: file.status.as_ref().map(|s| s.0.clone()),
        },
    })
}

/// An expected refusal: `expect.error` alone, a part of the message the scene must be refused with.
fn refusal(file: &ExpectFile, message: &str, ix: &KeyIndex<'_>) -> Result<Expectation> {
    let others = [
        ("command", file.command.is_some()),
        ("quality", file.quality.is_some()),
        ("controller", file.controller.is_some()),
        ("frames", file.frames.is_some()),
        ("time", file.time.is_some()),
        ("time-tolerance", file.time_tolerance.is_some()),
        ("gap-percent", file.gap_percent.is_some()),
        ("valid", file.valid.is_some()),
        ("engine-exact-valid", file.engine_exact_valid.is_some()),
        ("status", file.status.is_some()),
    ];
    if let Some((key, _)) = others.iter().find(|(_, given)| *given) {
        return Err(ix.error(
            &format!("expect.{key}"),
            "an expected refusal (expect.error) takes no other key: a refused scene runs nothing",
        ));
    }
    if message.trim().is_empty() {
        return Err(ix.error(
            "expect.error",
            "empty; give a part of the message the scene must be refused with",
        ));
    }
    Ok(Expectation::Refused {
        message_contains: message.to_string(),
    })
}

/// The run an expectation is about: `solve` at its quality or `simulate` with its controller, each
/// refusing the other's keys.
fn expected_run(file: &ExpectFile, ix: &KeyIndex<'_>) -> Result<ExpectedRun> {
    let command = file.command.unwrap_or(ExpectCommand::Solve);
    let solve_only = [
        ("quality", file.quality.is_some()),
        ("engine-exact-valid", file.engine_exact_valid.is_some()),
        ("status", file.status.is_some()),
    ];
    let simulate_only = [("controller", file.controller.is_some())];
    let (misplaced, other) = match command {
        ExpectCommand::Solve => (&simulate_only[..], "simulate"),
        ExpectCommand::Simulate => (&solve_only[..], "solve"),
    };
    if let Some((key, _)) = misplaced.iter().find(|(_, given)| *given) {
        return Err(ix.error(
            &format!("expect.{key}"),
            format!("only with command = \"{other}\""),
        ));
    }
    Ok(match command {
        ExpectCommand::Solve => ExpectedRun::Solve(file.quality.unwrap_or(ExpectQuality::Balanced)),
        ExpectCommand::Simulate => {
            ExpectedRun::Simulate(file.controller.unwrap_or(ExpectController::Greedy))
        }
    })
}

/// The frames, time and gap limits checked in range; the time's tolerance, seconds (0 when not given).
fn checked_limits(file: &ExpectFile, ix: &KeyIndex<'_>) -> Result<f64> {
    if file.frames == Some(0) {
        return Err(ix.error(
            "expect.frames",
            "got 0; must be at least 1 (the finish is crossed in frame 1 at the earliest)",
        ));
    }
    if let Some(t) = file.time {
        if !(t.is_finite() && t > 0.0) {
            return Err(ix.error(
                "expect.time",
                format!("got {t}; must be a finite number of seconds above 0"),
            ));
        }
    }
    // A tolerance without a time is kept for the time `check --update` writes.
    let time_tolerance_s = match file.time_tolerance {
        None => 0.0,
        Some(tol) if tol.is_finite() && tol >= 0.0 => tol,
        Some(tol) => {
            return Err(ix.error(
                "expect.time-tolerance",
                format!("got {tol}; must be a finite number of seconds of at least 0"),
            ))
        }
    };
    if let Some(g) = file.gap_percent {
        if !(g.is_finite() && g >= 0.0) {
            return Err(ix.error(
                "expect.gap-percent",
                format!("got {g}; must be a finite percentage of at least 0 (no run beats the lower bound)"),
            ));
        }
    }
    Ok(time_tolerance_s)
}

/// The statuses a solve may end with: one or more, each a known one.
fn check_statuses(names: &[String], ix: &KeyIndex<'_>) -> Result<()> {
    if names.is_empty() {
        return Err(ix.error(
            "expect.status",
            format!(
                "an empty list; give one or more of {}",
                SOLVE_STATUSES.join(", ")
            ),
        ));
    }
    if let Some(bad) = names.iter().find(|n| !SOLVE_STATUSES.contains(&n.as_str())) {
        return Err(ix.error(
            "expect.status",
            format!(
                "unknown status \"{}\"; must be one of {}",
                super::locate::one_line(bad),
                SOLVE_STATUSES.join(", ")
            ),
        ));
    }
    Ok(())
}
