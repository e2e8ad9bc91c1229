//! A staircase: a corridor of right-angle turns alternating left and right, every leg the same length.
//! Nothing is drawn: the scene is the same for the same [`Staircase`], so a run of staircases of 1 to 20
//! corners measures how `solve`'s time grows with the corners alone (the bench's `--staircase` rows).
//!
//! The corridor is laid out as the generated family's ([`super::centreline`]): the first leg along +x
//! from the origin, each turn around a pivot `(width + gap) / 2` to its side with the family's wall gap;
//! the start is airborne [`crate::scene::START_OFFSET_UNITS`] into the first leg on its centre line, moving along it;
//! the finish line spans the last leg's end. The first turn is to the left.

use super::centreline::Side;
use super::{clear_layout, scene_text, Drawn, GeneratedScene, GeneratorSettings, SceneKind, Turn};
use crate::error::{Error, Result};
use crate::geometry::BoundaryKind;
use crate::scene::Scene;

/// Most corners a staircase may have (a 64-corner staircase of 600-unit legs is about 40,000 units long).
pub const MAX_STAIRCASE_CORNERS: u32 = 64;

/// The shape and settings of a staircase. `Default`: 4 corners, 128 units wide, 600-unit legs, Half-Life
/// at 100 fps with `sv_airaccelerate` 10, airborne at 400 ups, rule walls.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Staircase {
    /// Turns, 1 to [`MAX_STAIRCASE_CORNERS`].
    pub corners: u32,
    /// Corridor width, units (at least the 32-unit hull and at most the leg, so that the legs do not
    /// overlap).
    pub width_units: u32,
    /// Straight part of every leg, units.
    pub leg_units: u32,
    /// Frame rate, fps.
    pub fps: u32,
    /// `sv_airaccelerate`.
    pub airaccelerate: u32,
    /// Start speed along the first leg, ups.
    pub start_speed_ups: u32,
    /// Kind of every wall.
    pub walls: BoundaryKind,
}

impl Default for Staircase {
    fn default() -> Self {
        Staircase {
            corners: 4,
            width_units: 128,
            leg_units: 600,
            fps: 100,
            airaccelerate: 10,
            start_speed_ups: 400,
            walls: BoundaryKind::Rule,
        }
    }
}

/// The staircase `spec` as a scene named `staircase-CORNERS` (its `seed` is 0 and its `index` the
/// corners: nothing is drawn). Errors when a figure is out of range ([`Error::InvalidValue`]).
pub fn staircase(spec: &Staircase) -> Result<GeneratedScene> {
    let range = |name: &str, value: u32, lo: u32, hi: u32| {
        if (lo..=hi).contains(&value) {
            Ok(())
        } else {
            Err(Error::InvalidValue {
                name: name.to_string(),
                value: value.to_string(),
                allowed: format!("{lo} to {hi}"),
            })
        }
    };
    range("staircase corners", spec.corners, 1, MAX_STAIRCASE_CORNERS)?;
    range(
        "staircase width",
        spec.width_units,
        33,
        spec.leg_units.max(33),
    )?;
    range("staircase leg", spec.leg_units, 33, 100_000)?;
    range("staircase fps", spec.fps, 10, 10_000)?;
    range("staircase airaccelerate", spec.airaccelerate, 1, 1000)?;
    range("staircase start speed", spec.start_speed_ups, 0, 10_000)?;
    let turns: Vec<(u32, Side)> = (0..spec.corners)
        .map(|k| (90, if k % 2 == 0 { Side::Left } else { Side::Right }))
        .collect();
    let legs_units = vec![spec.leg_units; spec.corners as usize + 1];
    let (width, gap) = (
        f64::from(spec.width_units),
        f64::from(GeneratorSettings::default().wall_gap_units),
    );
    let Some(layout) = clear_layout(width, gap, &legs_units, &turns) else {
        return Err(Error::InvalidValue {
            name: "staircase width".to_string(),
            value: spec.width_units.to_string(),
            allowed: format!(
                "a width whose turns leave the {}-unit legs apart",
                spec.leg_units
            ),
        });
    };
    let drawn = Drawn {
        width_units: spec.width_units,
        legs_units,
        turns: turns
            .into_iter()
            .map(|(degrees, side)| Turn { degrees, side })
            .collect(),
        fps: spec.fps,
        airaccelerate: spec.airaccelerate,
        start_speed_ups: spec.start_speed_ups,
        walls: spec.walls,
        kind: SceneKind::Air,
        corridor_draws: 1,
    };
    let name = format!("staircase-{}", spec.corners);
    let header = format!(
        "# A staircase of strafeopt: {} right-angle turns alternating left and right, legs of {} units, \
         {} units wide,\n# {} fps, sv_airaccelerate {}, airborne at {} ups along the first leg, {} walls.\n",
        spec.corners,
        spec.leg_units,
        spec.width_units,
        spec.fps,
        spec.airaccelerate,
        spec.start_speed_ups,
        spec.walls.name()
    );
    let toml = scene_text(&name, &header, "Staircase", &drawn, &layout, false);
    let scene = Scene::from_toml_str(&toml, &format!("{name}.toml"))?;
    Ok(GeneratedScene {
        seed: 0,
        index: u64::from(spec.corners),
        name,
        drawn,
        centreline: layout.pieces,
        toml,
        scene,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::optimise::bound::lower_bound;

    fn shortest_path_units(corners: u32) -> f64 {
        let g = staircase(&Staircase {
            corners,
            ..Staircase::default()
        })
        .unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(g.drawn.turns.len(), corners as usize);
        let sides: Vec<Side> = g.drawn.turns.iter().map(|t| t.side).collect();
        assert!(sides.windows(2).all(|w| w[0] != w[1]), "{sides:?}");
        let corridor = g.scene.corridor().unwrap_or_else(|e| panic!("{e}"));
        let bound = lower_bound(&g.scene, &corridor).unwrap_or_else(|e| panic!("{e}"));
        bound.path.windows(2).map(|w| (w[1] - w[0]).length()).sum()
    }

    #[test]
    fn each_corner_adds_a_leg_and_a_turn_to_the_shortest_path() {
        // The hull cuts each right angle: a corner adds a 600-unit leg plus the turn's straight-line
        // share, the same for every corner after the first.
        let lengths: Vec<f64> = [1, 2, 3, 6].map(shortest_path_units).to_vec();
        let per_corner = lengths[2] - lengths[1];
        assert!(
            per_corner > 600.0 && per_corner < 600.0 + 2.0 * 128.0,
            "{lengths:?}"
        );
        assert!(
            (lengths[1] - lengths[0] - per_corner).abs() < 1.0,
            "{lengths:?}"
        );
        assert!(
            (lengths[3] - lengths[2] - 3.0 * per_corner).abs() < 1.0,
            "{lengths:?}"
        );
    }

    #[test]
    fn out_of_range_figures_are_errors_not_panics() {
        for bad in [
            Staircase {
                corners: 0,
                ..Staircase::default()
            },
            Staircase {
                corners: MAX_STAIRCASE_CORNERS + 1,
                ..Staircase::default()
            },
            Staircase {
                width_units: 20,
                ..Staircase::default()
            },
            Staircase {
                width_units: 700,
                ..Staircase::default()
            },
        ] {
            assert!(staircase(&bad).is_err(), "{bad:?}");
        }
        let g = staircase(&Staircase {
            corners: 20,
            ..Staircase::default()
        })
        .unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(g.name, "staircase-20");
    }
}
