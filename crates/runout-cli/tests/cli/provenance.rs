//! The provenance of a report (`crates/runout-cli/src/provenance.rs`): an output's old file is not
//! an input, and a failed hashing of an input leaves the report without provenance, with a
//! warning — it once spun for ever at 100 % CPU instead of writing the report.

use crate::common::*;
use std::path::Path;
use std::process::{Command as StdCommand, Output, Stdio};
use std::time::{Duration, Instant};

/// Run `runout ARGS` in `dir` on one rayon thread; killed after `limit` (a hang fails the test
/// instead of the CI job).
fn run_bounded(dir: &Path, args: &[&str], limit: Duration) -> Output {
    let mut child = StdCommand::new(assert_cmd::cargo::cargo_bin("runout"))
        .current_dir(dir)
        .args(args)
        .env("RUST_BACKTRACE", "0")
        .env("RAYON_NUM_THREADS", "1")
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let start = Instant::now();
    while child.try_wait().unwrap().is_none() {
        if start.elapsed() > limit {
            child.kill().unwrap();
            let out = child.wait_with_output().unwrap();
            panic!(
                "runout {args:?} still running after {limit:?} (killed); stderr: {}",
                String::from_utf8_lossy(&out.stderr)
            );
        }
        std::thread::sleep(Duration::from_millis(50));
    }
    child.wait_with_output().unwrap()
}

/// The identify example's recordings copied into `dir` with their time column renamed `time`.
fn copy_recordings(dir: &Path, time: &str) {
    for name in ["cut_fz0.05.txt", "cut_fz0.08.txt"] {
        let text = std::fs::read_to_string(example(&format!("identify/{name}"))).unwrap();
        let text = text.replacen("\nTime,Fx,Fy,Fz\n", &format!("\n{time},Fx,Fy,Fz\n"), 1);
        assert!(text.contains(time));
        std::fs::write(dir.join(name), text).unwrap();
    }
    std::fs::copy(example("identify/cut.toml"), dir.join("cut.toml")).unwrap();
}

/// Generous for a job of ~1 s on an idle machine: the bound only has to tell a hang from a
/// slow run on a loaded 2-core machine.
const LIMIT: Duration = Duration::from_secs(60);

/// An input the program cannot read to hash it: `/proc/self/mem` is a regular file that every
/// read at offset 0 fails with EIO (address 0 is never mapped), for root too — the tests run as
/// root, where file permissions would not stop a read. It reaches the hashing as the value of
/// `--time-var` naming the time column, which is an existing file's name by construction. The
/// pre-existing `--json` target is write-only, as in the report of the hang (it is an output:
/// not hashed).
#[cfg(target_os = "linux")]
#[test]
fn a_failed_hashing_writes_the_report_without_provenance_and_says_why() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    copy_recordings(d, "/proc/self/mem");
    let out_json = d.join("out.json");
    std::fs::write(&out_json, "old").unwrap();
    {
        use std::os::unix::fs::PermissionsExt;
        std::fs::set_permissions(&out_json, std::fs::Permissions::from_mode(0o222)).unwrap();
    }
    let args = [
        "identify",
        "cut_fz0.05.txt",
        "cut_fz0.08.txt",
        "--config",
        "cut.toml",
        "--time-var",
        "/proc/self/mem",
        "--json",
        "out.json",
    ];
    let out = run_bounded(d, &args, LIMIT);
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(0), "{err}");
    assert!(
        err.contains(
            "warning: the outputs carry no provenance (command line, inputs' SHA-256): \
             /proc/self/mem: cannot read to hash it:"
        ),
        "{err}"
    );
    let written = std::fs::read_to_string(&out_json).unwrap();
    let v: serde_json::Value = serde_json::from_str(&written).expect("valid JSON");
    assert!(v.get("provenance").is_none(), "{written}");
    assert_eq!(v["schema"], "runout.identify.recording/3", "{written}");

    // the same report as with provenance, but for it: the same job on the same samples, with
    // the time column under its usual name
    let plain = tempfile::tempdir().unwrap();
    copy_recordings(plain.path(), "Time");
    let mut args = args;
    args[6] = "Time";
    let out = run_bounded(plain.path(), &args, LIMIT);
    assert_eq!(out.status.code(), Some(0));
    let stamped = std::fs::read_to_string(plain.path().join("out.json")).unwrap();
    assert_eq!(without_provenance(&stamped), written);
}

/// The old file at an output's path is not an input of the report: only the recordings and the
/// case file are hashed, whichever way the flag is written.
#[test]
fn an_existing_output_is_not_an_input() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    copy_recordings(d, "Time");
    std::fs::write(d.join("out.json"), "old").unwrap();
    std::fs::write(d.join("out.html"), "old").unwrap();
    let out = run_bounded(
        d,
        &[
            "identify",
            "cut_fz0.05.txt",
            "--json=out.json",
            "cut_fz0.08.txt",
            "--config",
            "cut.toml",
            "--html",
            "out.html",
        ],
        LIMIT,
    );
    assert_eq!(
        out.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let v: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(d.join("out.json")).unwrap()).unwrap();
    let names: Vec<&str> = v["provenance"]["inputs"]
        .as_array()
        .unwrap()
        .iter()
        .map(|i| i["name"].as_str().unwrap())
        .collect();
    assert_eq!(names, ["cut_fz0.05.txt", "cut_fz0.08.txt", "cut.toml"]);
}

/// A recording from standard input (`-`) gives the answer the file gives; the provenance names
/// `-` without a hash (the job read it: it cannot be read again) and says so. A second `-` is
/// an error. (`-` was read as a file named "-"; a pipe path such as `<(cat rec.txt)` was opened
/// twice and its header lost: "no sample rate".)
#[cfg(unix)]
#[test]
fn a_recording_from_standard_input_gives_the_files_answer() {
    let dir = tempfile::tempdir().unwrap();
    let root = example("..");
    let answer = |json: &Path| {
        let v: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(json).unwrap()).unwrap();
        let mut answer = v["answer"].clone();
        // the recordings by name: `/dev/stdin` for `-`
        for c in answer["cross_checks"].as_array_mut().unwrap() {
            c["file"] = serde_json::Value::Null;
        }
        (answer, v["full_signal"].clone(), v["provenance"].clone())
    };
    let files = dir.path().join("files.json");
    runout()
        .current_dir(&root)
        .args(IDENTIFY_EXAMPLE_INPUTS)
        .arg("--json")
        .arg(&files)
        .assert()
        .success();
    let piped = dir.path().join("stdin.json");
    let out = runout()
        .current_dir(&root)
        .args([
            "identify",
            "-",
            "examples/identify/cut_fz0.08.txt",
            "--config",
            "examples/identify/cut.toml",
            "--json",
        ])
        .arg(&piped)
        .pipe_stdin(root.join("examples/identify/cut_fz0.05.txt"))
        .unwrap()
        .assert()
        .success();
    let stderr = String::from_utf8_lossy(&out.get_output().stderr).to_string();
    let (want, want_fit, _) = answer(&files);
    let (got, got_fit, provenance) = answer(&piped);
    assert_eq!(got, want);
    assert_eq!(got_fit, want_fit);
    assert_eq!(provenance["not_hashed"], serde_json::json!(["-"]));
    let hashed: Vec<&str> = provenance["inputs"]
        .as_array()
        .unwrap()
        .iter()
        .map(|i| i["name"].as_str().unwrap())
        .collect();
    assert_eq!(
        hashed,
        [
            "examples/identify/cut_fz0.08.txt",
            "examples/identify/cut.toml"
        ]
    );
    assert!(stderr.contains("names - without a SHA-256"), "{stderr}");
    // standard input can be read once
    runout()
        .current_dir(&root)
        .args([
            "identify",
            "-",
            "-",
            "--config",
            "examples/identify/cut.toml",
        ])
        .write_stdin("")
        .assert()
        .code(1)
        .stderr(predicates::str::contains("given 2 times"));
}
