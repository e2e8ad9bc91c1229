//! strafeopt: minimal-time strafing paths for Half-Life (GoldSrc) and Half-Life 2 (Source) movement.
//!
//! Data flows one way: [`scene`] -> [`sim`] -> [`optimise`] -> [`report`]. [`physics`] is the algebra
//! layer under all of them; [`geometry`] holds the corridor and the swept player hull.
#![warn(missing_docs)]

pub mod cli;
pub mod error;
pub mod geometry;
pub mod optimise;
pub mod physics;
pub mod scene;

pub use error::{Error, Result};
