//! Progress bars on stderr (indicatif); hidden automatically when stderr is not a terminal, so piped `--json`
//! output stays clean.

use indicatif::{ProgressBar, ProgressStyle};

/// A bar of `len` steps labelled `label`, with rate and ETA.
pub fn bar(len: u64, label: &str) -> ProgressBar {
    let bar = ProgressBar::new(len);
    if let Ok(style) = ProgressStyle::with_template("{msg:>12} [{bar:40}] {pos}/{len} {per_sec} ETA {eta}") {
        bar.set_style(style.progress_chars("=> "));
    }
    bar.set_message(label.to_string());
    bar
}

/// A spinner for work whose length is unknown.
pub fn spinner(message: String) -> ProgressBar {
    let spinner = ProgressBar::new_spinner();
    spinner.set_message(message);
    spinner.enable_steady_tick(std::time::Duration::from_millis(200));
    spinner
}

/// A bar for a measurement run of `len` units, `done` of them already committed (resume): `label` before the bar,
/// the wall time elapsed after it, and a message (what the run does, retries, remaining time, SNR) that the caller
/// keeps current.
pub fn run_bar(len: u64, done: u64, label: &str) -> ProgressBar {
    let bar = ProgressBar::new(len);
    if let Ok(style) = ProgressStyle::with_template("{prefix:>10} [{bar:30}] {pos}/{len} {elapsed_precise} {msg}") {
        bar.set_style(style.progress_chars("=> "));
    }
    bar.set_prefix(label.to_string());
    bar.set_position(done);
    bar
}
