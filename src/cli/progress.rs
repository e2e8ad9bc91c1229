//! Progress on stderr for long work (`solve`, `bench`, `check`): a spinner with the stage, what has been
//! tried and the elapsed time, redrawn in place. Shown only to a person watching: hidden with `--json`,
//! `--quiet`, or when stderr is not a terminal, so scripts and logs never see it.

use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use std::io::IsTerminal;
use std::time::Duration;

/// How often the spinner redraws (and the elapsed time moves) while a stage runs.
const TICK: Duration = Duration::from_millis(120);

/// True when progress should be drawn: not `--json`, not `--quiet`, and stderr is a terminal.
pub fn wanted(json: bool, quiet: bool) -> bool {
    !json && !quiet && std::io::stderr().is_terminal()
}

/// A spinner on stderr (`[   12.3 s] greedy       look-aheads and speed caps`), or a hidden one when
/// `visible` is false (see [`wanted`]). Set the stage with [`ProgressBar::set_prefix`] and the detail
/// with [`ProgressBar::set_message`]; [`ProgressBar::finish_and_clear`] removes it before the result
/// is printed.
pub fn spinner(visible: bool) -> ProgressBar {
    if !visible {
        return ProgressBar::hidden();
    }
    let bar = ProgressBar::with_draw_target(None, ProgressDrawTarget::stderr());
    let style = ProgressStyle::with_template("{spinner} [{elapsed:>5}] {prefix:<13} {wide_msg}")
        .unwrap_or_else(|_| ProgressStyle::default_spinner());
    bar.set_style(style);
    bar.enable_steady_tick(TICK);
    bar
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn json_or_quiet_hide_it() {
        assert!(!wanted(true, false));
        assert!(!wanted(false, true));
        assert!(spinner(false).is_hidden());
    }
}
