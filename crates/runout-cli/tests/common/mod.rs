//! Helpers shared by the CLI integration tests (each test crate uses a subset).
#![allow(dead_code)]

use assert_cmd::Command;
use std::path::PathBuf;

/// The `runout` binary of this build, without backtraces in its error output.
pub fn runout() -> Command {
    let mut c = Command::cargo_bin("runout").unwrap();
    c.env("RUST_BACKTRACE", "0");
    c
}

/// A file under the repository's `examples/` folder, e.g. `example("chip/flank.apt")`.
pub fn example(path: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../../examples")
        .join(path)
}

/// Seed 003's cut as `runout simulate` flags: K 4, D 10 mm, 3240 rpm, f_z 0.08 mm, a_p 1 mm,
/// a_e 2 mm down-milling.
pub const SEED003_CUT: [&str; 15] = [
    "simulate",
    "--teeth",
    "4",
    "--diameter-mm",
    "10",
    "--rpm",
    "3240",
    "--fz-mm",
    "0.08",
    "--ap-mm",
    "1",
    "--ae-mm",
    "2",
    "--mode",
    "down",
];

/// Seed 003's cutting coefficients as flags (N/mm², N/mm).
pub const SEED003_COEFFICIENTS: [&str; 12] = [
    "--ktc", "1889.2", "--krc", "806.1", "--kac", "291", "--kte", "63.12", "--kre", "113.7",
    "--kae", "-3.1",
];
