//! Shorthand shapes: a table such as `[bend90]` that expands into walls, a default start and a finish line.
//!
//! Common to all: x runs along the first leg, y to its left; the start wall is the line x = 0; the
//! default start is the hull centre [`START_OFFSET_UNITS`] past the start wall, halfway across the
//! entrance, moving along +x at `sv_maxspeed` (320 ups in GoldSrc); walls are one kind, given by `kind`.
//! Widths are between the wall lines, so the hull centre has `width - 32` units of room.

use crate::geometry::{BoundaryKind, Wall, HULL_HALF_WIDTH_UNITS, MIN_SEGMENT_LENGTH_UNITS};
use crate::physics::Vec2;
use serde::Deserialize;

/// Distance from the start wall to the default start position of the hull centre, units.
pub const START_OFFSET_UNITS: f64 = 40.0;

/// Smallest corridor width, units: the hull's width.
pub const MIN_WIDTH_UNITS: f64 = 2.0 * HULL_HALF_WIDTH_UNITS;

/// `[bend90]`: a corridor of constant `width` that turns 90 degrees to the left.
///
/// Leg 1 runs along +x between the outer wall y = 0 (on the right) and the inner wall y = `width`, from
/// the start wall x = 0 to its far (outer) wall x = `leg1`. Leg 2 runs along +y between the inner wall
/// x = `leg1 - width` and the outer wall x = `leg1`, from the outer wall of leg 1 (y = 0) to the finish line
/// at y = `leg2`. So both legs are measured to the outer corner (`leg1`, 0). The walls are one polyline,
/// open at the finish: (`leg1 - width`, `leg2`) -> (`leg1 - width`, `width`) -> (0, `width`) -> (0, 0) ->
/// (`leg1`, 0) -> (`leg1`, `leg2`). The finish runs from (`leg1 - width`, `leg2`) to (`leg1`, `leg2`).
#[derive(Clone, Copy, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields, rename_all = "kebab-case")]
pub struct Bend90 {
    /// Corridor width, units (at least 32).
    pub width: f64,
    /// Start wall to the outer wall of leg 1, units (more than `width`).
    pub leg1: f64,
    /// Outer wall of leg 1 to the finish line, units (more than `width`).
    pub leg2: f64,
    /// Wall kind.
    pub kind: BoundaryKind,
}

/// `[hairpin]`: a 180-degree left turn around a divider.
///
/// Leg 1 runs along +x between y = 0 and y = `width`, from the start wall x = 0 to the end wall
/// x = `length`. A divider `gap` thick, the block from (0, `width`) to (`length - width`, `width + gap`),
/// separates it from leg 2, which runs back along -x between y = `width + gap` and y = `2 width + gap`; the
/// turn is the `width`-long stretch beyond the divider's end. The finish crosses leg 2 `finish` units back
/// from the end wall, at x = `length - finish` (default: `finish = length`, the start wall's line). Walls:
/// the outer polyline (0, `2w+g`) -> (`length`, `2w+g`) -> (`length`, 0) -> (0, 0) -> (0, `w`), and the
/// divider, a closed rectangle (a single line when `gap = 0`).
#[derive(Clone, Copy, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields, rename_all = "kebab-case")]
pub struct Hairpin {
    /// Width of each leg, units (at least 32).
    pub width: f64,
    /// Start wall to end wall, units (more than `width`).
    pub length: f64,
    /// Thickness of the divider between the legs, units (at least 0).
    pub gap: f64,
    /// End wall to the finish line along leg 2, units (from `width` to `length`; default `length`).
    #[serde(default)]
    pub finish: Option<f64>,
    /// Wall kind.
    pub kind: BoundaryKind,
}

/// `[lane]`: a straight lane along +x between y = 0 and y = `width`, from the start wall x = 0 to the finish
/// line x = `length`. Walls: the polyline (`length`, 0) -> (0, 0) -> (0, `width`) -> (`length`, `width`).
#[derive(Clone, Copy, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields, rename_all = "kebab-case")]
pub struct Lane {
    /// Lane width, units (at least 32).
    pub width: f64,
    /// Start wall to finish line, units (more than 56: the default start's hull must fit).
    pub length: f64,
    /// Wall kind.
    pub kind: BoundaryKind,
}

/// What a shorthand shape expands to.
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct Expanded {
    pub walls: Vec<Wall>,
    pub start_position: Vec2,
    /// Unit direction of leg 1.
    pub start_direction: Vec2,
    pub finish: (Vec2, Vec2),
}

/// A shorthand parameter out of range: the key (`width`) and what is allowed.
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct BadParam {
    pub key: &'static str,
    pub message: String,
}

fn check(key: &'static str, value: f64, ok: bool, allowed: String) -> Result<(), BadParam> {
    if value.is_finite() && ok {
        Ok(())
    } else {
        Err(BadParam {
            key,
            message: format!("got {value}; must be {allowed}"),
        })
    }
}

fn check_width(width: f64) -> Result<(), BadParam> {
    check(
        "width",
        width,
        width >= MIN_WIDTH_UNITS,
        format!("at least {MIN_WIDTH_UNITS} units (the hull width)"),
    )
}

fn p(x: f64, y: f64) -> Vec2 {
    Vec2::new(x, y)
}

impl Bend90 {
    pub(crate) fn expand(&self) -> Result<Expanded, BadParam> {
        let Bend90 {
            width: w,
            leg1,
            leg2,
            kind,
        } = *self;
        check_width(w)?;
        check(
            "leg1",
            leg1,
            leg1 > w,
            format!("more than the width ({w} units)"),
        )?;
        check(
            "leg2",
            leg2,
            leg2 > w,
            format!("more than the width ({w} units)"),
        )?;
        let inner = leg1 - w;
        Ok(Expanded {
            walls: vec![Wall {
                points: vec![
                    p(inner, leg2),
                    p(inner, w),
                    p(0.0, w),
                    p(0.0, 0.0),
                    p(leg1, 0.0),
                    p(leg1, leg2),
                ],
                closed: false,
                kind,
            }],
            start_position: p(START_OFFSET_UNITS, w / 2.0),
            start_direction: p(1.0, 0.0),
            finish: (p(inner, leg2), p(leg1, leg2)),
        })
    }
}

impl Hairpin {
    pub(crate) fn expand(&self) -> Result<Expanded, BadParam> {
        let Hairpin {
            width: w,
            length,
            gap: g,
            finish,
            kind,
        } = *self;
        check_width(w)?;
        check(
            "length",
            length,
            length > w,
            format!("more than the width ({w} units)"),
        )?;
        check("gap", g, g >= 0.0, "at least 0 units".to_string())?;
        let finish = finish.unwrap_or(length);
        check(
            "finish",
            finish,
            (w..=length).contains(&finish),
            format!("from the width ({w}) to the length ({length}) units"),
        )?;
        let top = 2.0 * w + g;
        let divider_end = length - w;
        let divider = if g > MIN_SEGMENT_LENGTH_UNITS {
            Wall {
                points: vec![
                    p(0.0, w),
                    p(divider_end, w),
                    p(divider_end, w + g),
                    p(0.0, w + g),
                ],
                closed: true,
                kind,
            }
        } else {
            Wall {
                points: vec![p(0.0, w), p(divider_end, w)],
                closed: false,
                kind,
            }
        };
        let xf = length - finish;
        Ok(Expanded {
            walls: vec![
                Wall {
                    points: vec![
                        p(0.0, top),
                        p(length, top),
                        p(length, 0.0),
                        p(0.0, 0.0),
                        p(0.0, w),
                    ],
                    closed: false,
                    kind,
                },
                divider,
            ],
            start_position: p(START_OFFSET_UNITS, w / 2.0),
            start_direction: p(1.0, 0.0),
            finish: (p(xf, w + g), p(xf, top)),
        })
    }
}

impl Lane {
    pub(crate) fn expand(&self) -> Result<Expanded, BadParam> {
        let Lane {
            width: w,
            length,
            kind,
        } = *self;
        check_width(w)?;
        let min_length = START_OFFSET_UNITS + HULL_HALF_WIDTH_UNITS;
        check(
            "length",
            length,
            length > min_length,
            format!("more than {min_length} units (the default start's hull must fit)"),
        )?;
        Ok(Expanded {
            walls: vec![Wall {
                points: vec![p(length, 0.0), p(0.0, 0.0), p(0.0, w), p(length, w)],
                closed: false,
                kind,
            }],
            start_position: p(START_OFFSET_UNITS, w / 2.0),
            start_direction: p(1.0, 0.0),
            finish: (p(length, 0.0), p(length, w)),
        })
    }
}
