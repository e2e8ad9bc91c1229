//! `check --update`: a scene's `[expect]` values rewritten from the current result, everything else in
//! the file (comments, blank lines, key order, the other tables) left as it was, through `toml_edit`.
//!
//! The figures written are the ones the table already gives; a table that gives none (only `command`
//! and `quality`) gets every figure of its command. Times are rounded up to the microsecond and gaps to
//! the thousandth of a percent, so the result satisfies the limits it writes and a second update changes
//! nothing. `time-tolerance` is the user's choice and is kept.

use super::{Change, Measured, Update};
use crate::error::{Error, Result};
use crate::scene::{ExpectedRun, Limits};
use toml_edit::{DocumentMut, Item, TableLike, Value};

/// Decimals of a written time (a microsecond).
pub const TIME_DECIMALS: i32 = 6;
/// Decimals of a written gap, percent (a thousandth of a percent).
pub const GAP_DECIMALS: i32 = 3;

/// `value` rounded up to `decimals` decimal places: at least `value`, and the nearest `f64` to a decimal
/// of that many places, so it is written as one (`4.001484`, not `4.0014839999999995`).
pub fn round_up(value: f64, decimals: i32) -> f64 {
    let scale = 10f64.powi(decimals);
    let units = (value * scale).ceil();
    // Dividing a whole number by a power of ten rounds to the nearest f64 of the decimal.
    let rounded = units / scale;
    if rounded < value {
        (units + 1.0) / scale
    } else {
        rounded
    }
}

/// The scene text with its `[expect]` figures set from `measured`; `None` when the figures cannot be
/// written (the line was not reached).
pub fn rewrite_limits(
    text: &str,
    limits: &Limits,
    run: ExpectedRun,
    measured: &Measured,
) -> Result<Option<Update>> {
    let (Some(frames), Some(time_s), Some(gap)) =
        (measured.frames, measured.time_s, measured.gap_percent)
    else {
        return Ok(None);
    };
    let all = limits.is_empty();
    let solve = matches!(run, ExpectedRun::Solve(_));
    let mut wanted: Vec<(&'static str, Value)> = Vec::new();
    if all || limits.frames.is_some_and(|f| f != frames) {
        wanted.push((
            "frames",
            Value::from(i64::try_from(frames).unwrap_or(i64::MAX)),
        ));
    }
    let time = round_up(time_s, TIME_DECIMALS);
    // Equality of the written decimal: an unchanged figure is not rewritten.
    if all || limits.time_s.is_some_and(|t| t != time) {
        wanted.push(("time", Value::from(time)));
    }
    let gap = round_up(gap, GAP_DECIMALS);
    if all || limits.gap_percent.is_some_and(|g| g != gap) {
        wanted.push(("gap-percent", Value::from(gap)));
    }
    if all || limits.valid.is_some_and(|v| v != measured.valid) {
        wanted.push(("valid", Value::from(measured.valid)));
    }
    if let Some(e) = measured.engine_exact_valid {
        if (all && solve) || limits.engine_exact_valid.is_some_and(|v| v != e) {
            wanted.push(("engine-exact-valid", Value::from(e)));
        }
    }
    if let Some(status) = &measured.status {
        let allowed = limits.status.as_ref().is_some_and(|a| a.contains(status));
        if (all && solve) || (limits.status.is_some() && !allowed) {
            wanted.push(("status", Value::from(status.as_str())));
        }
    }
    set_values(text, &wanted).map(Some)
}

/// The scene text with `[expect] error` set to the current refusal (no change when the refusal already
/// holds the expected text).
pub fn rewrite_refusal(text: &str, expected: &str, refusal: &str) -> Result<Update> {
    if refusal.contains(expected) {
        return set_values(text, &[]);
    }
    set_values(text, &[("error", Value::from(refusal))])
}

/// Sets each `(key, value)` of `[expect]`, keeping each old value's surrounding whitespace and comment.
fn set_values(text: &str, values: &[(&'static str, Value)]) -> Result<Update> {
    let parse_error = |e: toml_edit::TomlError| {
        Error::Io(format!(
            "the scene no longer parses for --update: {}",
            e.to_string().replace('\n', " ")
        ))
    };
    let mut doc: DocumentMut = text.parse().map_err(parse_error)?;
    let table: &mut dyn TableLike = doc
        .get_mut("expect")
        .and_then(Item::as_table_like_mut)
        .ok_or_else(|| Error::Io("the scene has no [expect] table for --update".to_string()))?;
    let mut changes = Vec::new();
    for (key, new) in values {
        let mut new = new.clone();
        let old = match table.get_mut(key).and_then(Item::as_value_mut) {
            Some(old) => {
                let shown = old.clone().decorated("", "").to_string();
                *new.decor_mut() = old.decor().clone();
                *old = new.clone();
                Some(shown)
            }
            None => {
                table.insert(key, Item::Value(new.clone()));
                None
            }
        };
        changes.push(Change {
            key,
            old,
            new: new.decorated("", "").to_string(),
        });
    }
    Ok(Update {
        changes,
        text: doc.to_string(),
    })
}
