//! Exit codes (issue 21 item 5), so scripts can tell a failed identification from a good one:
//!
//! | code | meaning |
//! |---|---|
//! | 0 | done; every result it reports is identified (or the command identifies nothing) |
//! | 3 | ran, but the result is not (fully) identified: the report says which part and why |
//! | 1 | error in the input or the data (a message names the file, line or flag) |
//! | 2 | usage: unknown flag, missing argument (clap) |
//! | 141 | standard output closed early (`runout … | head`), as a shell reports SIGPIPE |
//!
//! A command reports a result that is not identified with [`not_identified`]; `main` turns it into
//! code 3 once every output is written (outputs are still written: the report explains).

use std::sync::atomic::{AtomicBool, Ordering};

/// Exit code: ran, but the result is not (fully) identified.
pub const NOT_IDENTIFIED: u8 = 3;
/// Exit code: error in the input or the data.
pub const INPUT_ERROR: u8 = 1;

static NOT_IDENTIFIED_FLAG: AtomicBool = AtomicBool::new(false);

/// The command's result is not (fully) identified: exit with [`NOT_IDENTIFIED`].
pub fn not_identified() {
    NOT_IDENTIFIED_FLAG.store(true, Ordering::Relaxed);
}

/// Whether [`not_identified`] was called.
pub fn is_not_identified() -> bool {
    NOT_IDENTIFIED_FLAG.load(Ordering::Relaxed)
}

/// The exit-code table for `--help`.
pub const HELP: &str =
    "Exit status: 0 identified (or nothing to identify); 3 ran, but the result is \
not (fully) identified (the report says which part and why); 1 error in the input or data; 2 usage \
error; 141 output pipe closed early.";

/// Exit with [`NOT_IDENTIFIED`] unless the report's answer is `identified`.
pub fn from_answer<R: runout::answer::Answered>(report: &R) {
    if !report.answer().is_identified() {
        not_identified();
    }
}
