//! The library's progress reports ([`runout::Progress`]) as indicatif bars on stderr (hidden
//! when stderr is not a terminal, and with `--quiet`), and the warnings on stderr (none with
//! `--quiet`: they stay in the report).

use indicatif::{ProgressBar, ProgressStyle};
use std::sync::atomic::{AtomicBool, Ordering};

static QUIET: AtomicBool = AtomicBool::new(false);

/// `--quiet`: no progress bars or spinners, no warnings on stderr (errors only).
pub fn set_quiet(quiet: bool) {
    QUIET.store(quiet, Ordering::Relaxed);
}

/// Whether `--quiet` was given.
pub fn quiet() -> bool {
    QUIET.load(Ordering::Relaxed)
}

/// A warning on stderr, unless `--quiet` (the report keeps it either way).
pub fn warn(message: &str) {
    if !quiet() {
        to_stderr(&format!("warning: {message}"));
    }
}

/// One line on stderr. A stderr that cannot be written (a reader that closed it, as with
/// `2>&1 | head -1`) is ignored: there is nobody left to tell, and `eprintln!` would panic
/// (exit 101) instead of ending with the command's own status.
pub fn to_stderr(line: &str) {
    use std::io::Write;
    let _ = writeln!(std::io::stderr().lock(), "{line}");
}

/// A spinner on stderr for a job without a byte count (hidden when stderr is not a terminal or
/// with `--quiet`); cleared when dropped.
pub struct Spinner(ProgressBar);

impl Spinner {
    /// Start a spinner with `message`.
    pub fn new(message: &str) -> Self {
        let bar = if quiet() {
            ProgressBar::hidden()
        } else {
            ProgressBar::new_spinner()
        };
        bar.set_message(message.to_string());
        bar.enable_steady_tick(std::time::Duration::from_millis(120));
        Spinner(bar)
    }
}

impl Drop for Spinner {
    fn drop(&mut self) {
        self.0.finish_and_clear();
    }
}

/// One bar per stage, in bytes of input.
#[derive(Default)]
pub struct Bars {
    bar: Option<ProgressBar>,
}

impl runout::Progress for Bars {
    fn begin(&mut self, stage: &str, total_bytes: Option<u64>) {
        let bar = if quiet() {
            ProgressBar::hidden()
        } else {
            ProgressBar::new(total_bytes.unwrap_or(0))
        };
        bar.set_style(
            ProgressStyle::with_template(
                "{msg} [{bar:40}] {bytes}/{total_bytes} ({bytes_per_sec}, {eta})",
            )
            .unwrap_or_else(|_| ProgressStyle::default_bar()),
        );
        bar.set_message(stage.to_string());
        self.bar = Some(bar);
    }

    fn set_position(&mut self, bytes: u64) {
        if let Some(b) = &self.bar {
            b.set_position(bytes);
        }
    }

    fn advance(&mut self, bytes: u64) {
        if let Some(b) = &self.bar {
            b.inc(bytes);
        }
    }

    fn end(&mut self) {
        if let Some(b) = self.bar.take() {
            b.finish_and_clear();
        }
    }
}
