//! strafeopt: minimal-time strafing paths for Half-Life (GoldSrc) and Half-Life 2 (Source) movement.
//!
//! Data flows one way: [`scene`] -> simulation -> [`optimise`] -> reports. [`physics`] is the algebra
//! layer under all of them; [`geometry`] holds the corridor and the swept player hull, and the scene's
//! walls and finish line are geometry's types, so scene validation and simulation agree on contact.
//! [`check`] runs scenes against the expectations their files carry (scenario regression tests).
#![warn(missing_docs)]

pub mod bench;
pub mod budget;
pub mod check;
pub mod cli;
pub mod error;
pub mod geometry;
pub mod optimise;
pub mod physics;
pub mod report;
pub mod scene;
pub mod serve;
pub mod sim;
pub mod work;

#[cfg(test)]
mod test_stream;

pub use error::{Error, Result};
