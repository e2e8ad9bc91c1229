//! `strafeopt report RESULT.json -o out.html` (being written: issue 6).

use super::args::ReportArgs;
use crate::error::{Error, Result};

/// Runs `report`.
pub fn run(args: &ReportArgs) -> Result<String> {
    Err(Error::Io(format!(
        "{}: HTML reports are not available in this build yet",
        args.output.display()
    )))
}
