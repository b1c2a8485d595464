//! Progress bars on a terminal: `identify` run under a pseudo-terminal (util-linux `script`)
//! draws one bar per recording on stderr that ends at its total (the file's bytes plus the two
//! passes over the spill), and `--quiet` draws none; off a terminal there are none either
//! (the other tests' captured stderr holds only warnings and errors).

use crate::common::*;
use std::path::Path;
use std::process::Stdio;

/// What `runout ARGS` writes to its terminal (a pty from `script`), escape sequences included.
fn on_a_terminal(args: &[&str], dir: &Path) -> String {
    let bin = assert_cmd::cargo::cargo_bin("runout");
    let quote = |s: &str| format!("'{}'", s.replace('\'', r"'\''"));
    let mut line = quote(bin.to_str().unwrap());
    for a in args {
        line.push(' ');
        line.push_str(&quote(a));
    }
    line.push_str(" > /dev/null"); // the report: only stderr goes to the terminal
    let typescript = dir.join("typescript");
    let status = std::process::Command::new("script")
        .args(["-q", "-e", "-c", &line])
        .arg(&typescript)
        .env("RUST_BACKTRACE", "0")
        .stdin(Stdio::null())
        .stdout(Stdio::null())
        .status()
        .expect("util-linux `script` runs");
    assert!(status.success(), "{line}: {status}");
    String::from_utf8_lossy(&std::fs::read(&typescript).unwrap()).into_owned()
}

/// The `done/total` figures of every bar drawn for `name`, in drawing order.
fn bar_positions<'a>(terminal: &'a str, name: &str) -> Vec<(&'a str, &'a str)> {
    terminal
        .match_indices(&format!("{name} ["))
        .filter_map(|(i, _)| {
            let rest = &terminal[i..];
            let after_bar = &rest[rest.find("] ")? + 2..];
            let figures = after_bar.split(" (").next()?;
            figures.split_once('/')
        })
        .collect()
}

#[test]
#[ignore = "needs util-linux `script` (a pseudo-terminal)"]
fn identify_draws_one_bar_per_recording_that_ends_at_its_total() {
    let dir = tempfile::tempdir().unwrap();
    let (a, b) = (
        example("identify/cut_fz0.05.txt"),
        example("identify/cut_fz0.08.txt"),
    );
    let config = example("identify/cut.toml");
    let json = dir.path().join("id.json");
    let args = [
        "identify",
        a.to_str().unwrap(),
        b.to_str().unwrap(),
        "--config",
        config.to_str().unwrap(),
        "--json",
        json.to_str().unwrap(),
    ];
    let terminal = on_a_terminal(&args, dir.path());
    for rec in [&a, &b] {
        let name = rec.to_str().unwrap();
        let bars = bar_positions(&terminal, name);
        assert!(!bars.is_empty(), "no progress bar for {name}:\n{terminal}");
        let (done, total) = *bars.last().unwrap();
        assert_eq!(
            done, total,
            "{name}: the last bar drawn is not at its total"
        );
        // the total is more than the file (two passes over the spill follow the reading)
        let kib = |s: &str| {
            s.trim_end_matches(" KiB")
                .parse::<f64>()
                .unwrap_or(f64::NAN)
        };
        let file_kib = std::fs::metadata(rec).unwrap().len() as f64 / 1024.0;
        assert!(
            kib(total) > file_kib,
            "{name}: total {total} ≤ the file's {file_kib:.2} KiB"
        );
    }
    assert!(json.exists(), "the report is still written");

    let quiet: Vec<&str> = args.iter().copied().chain(["--quiet"]).collect();
    let terminal = on_a_terminal(&quiet, dir.path());
    assert!(
        bar_positions(&terminal, a.to_str().unwrap()).is_empty() && !terminal.contains("KiB/"),
        "--quiet drew a bar:\n{terminal}"
    );
}
