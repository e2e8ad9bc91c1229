//! `strafeopt solve` (being written: issue 5).

use super::args::SolveArgs;
use crate::error::{Error, Result};

/// Runs `solve`.
pub fn run(args: &SolveArgs) -> Result<String> {
    Err(Error::Io(format!(
        "{}: solve is not available in this build yet",
        args.scene.display()
    )))
}
