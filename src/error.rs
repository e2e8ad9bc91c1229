//! The library's typed errors. Each displays as one line that says what is wrong, where, and what is
//! allowed (`--fps = -1: must be a finite number above 0`). The command line maps them to exit codes.

use thiserror::Error;

/// Everything the library can refuse. Outcomes (a slow plan, no way through a corridor) are not errors;
/// see the optimiser's status for those.
#[derive(Debug, Error, Clone, PartialEq)]
#[non_exhaustive]
pub enum Error {
    /// A number outside its allowed range: `name` is the setting (a flag or a scene key), `allowed` the range.
    #[error("{name} = {value}: must be {allowed}")]
    InvalidValue {
        /// The setting, as the user wrote it (`--fps`, `engine.maxspeed`).
        name: String,
        /// The value given, formatted.
        value: String,
        /// The allowed range, in words (`a finite number above 0`).
        allowed: String,
    },
    /// A request that cannot be met with these settings (a target speed above the reachable limit).
    #[error("{what}")]
    Unreachable {
        /// What cannot be reached, and the limit.
        what: String,
    },
    /// A scene file that does not parse or does not validate: `location` is `file:line` (or the file) and
    /// `key` the dotted key at fault.
    #[error("{location}: {key}: {message}")]
    Scene {
        /// `path:line` (the line where known).
        location: String,
        /// The key at fault (`walls[2].points`), or `-` where none applies.
        key: String,
        /// What is wrong and what is allowed.
        message: String,
    },
    /// No control sequence can reach the finish without breaking a rule.
    #[error("no valid path: {0}")]
    NoValidPath(String),
    /// A file could not be written (the path and the system's reason).
    #[error("{0}")]
    Io(String),
    /// A numerical failure the library could not recover from (a NaN at a stage boundary).
    #[error("numerical error: {0}")]
    Numerical(String),
    /// A scene whose fastest possible run (its lower bound) needs more frames than may be planned.
    #[error(
        "{scene}: the fastest possible run takes at least {frames} frames (the lower bound), more than the \
         {limit} frames that may be planned; raise --max-frames to at least {frames} (memory grows with the \
         frames)"
    )]
    FrameLimit {
        /// The scene's origin.
        scene: String,
        /// The lower bound's frame count.
        frames: u64,
        /// The frame limit in force.
        limit: u64,
    },
    /// The time limit or the cancel flag stopped the work before any valid result was found.
    #[error(
        "stopped by {reason} in the {stage} stage before any run reached the finish validly{hint}"
    )]
    Stopped {
        /// What stopped it.
        reason: crate::budget::Stop,
        /// The stage that was cut.
        stage: crate::budget::Stage,
        /// What to do about it, with its leading separator (empty when cancelled).
        hint: String,
    },
}

impl Error {
    /// The error of a budget that ran out (`reason`, the time limit if `None`) in `stage` with nothing
    /// valid found.
    pub fn stopped(reason: Option<crate::budget::Stop>, stage: crate::budget::Stage) -> Self {
        let reason = reason.unwrap_or(crate::budget::Stop::TimeLimit);
        let hint = match reason {
            crate::budget::Stop::TimeLimit => "; raise --time-limit".to_string(),
            crate::budget::Stop::Cancelled => String::new(),
        };
        Error::Stopped {
            reason,
            stage,
            hint,
        }
    }
}

/// Result with the library's error.
pub type Result<T, E = Error> = std::result::Result<T, E>;

impl Error {
    /// An out-of-range value.
    pub fn invalid(name: impl Into<String>, value: f64, allowed: impl Into<String>) -> Self {
        Error::InvalidValue {
            name: name.into(),
            value: format_value(value),
            allowed: allowed.into(),
        }
    }
}

fn format_value(v: f64) -> String {
    if v.is_nan() {
        "NaN".to_string()
    } else {
        format!("{v}")
    }
}

/// Checks that `value` is finite and above zero.
pub fn require_positive(name: &str, value: f64) -> Result<f64> {
    if value.is_finite() && value > 0.0 {
        Ok(value)
    } else {
        Err(Error::invalid(name, value, "a finite number above 0"))
    }
}

/// Checks that `value` is finite and at least zero.
pub fn require_non_negative(name: &str, value: f64) -> Result<f64> {
    if value.is_finite() && value >= 0.0 {
        Ok(value)
    } else {
        Err(Error::invalid(name, value, "a finite number of at least 0"))
    }
}

/// Checks that `value` is finite.
pub fn require_finite(name: &str, value: f64) -> Result<f64> {
    if value.is_finite() {
        Ok(value)
    } else {
        Err(Error::invalid(name, value, "a finite number"))
    }
}
