//! Issue 20: crashes, hangs, runaway memory and silent wrong answers. One regression test per
//! row of the table (the input as a file under `tests/data/issue20/` where it is a
//! file), each asserting the exit code, the message's key words and that no input changed; and
//! writing to a closed pipe on every command that prints.

use std::path::{Path, PathBuf};
use std::process::Output;
use std::time::{Duration, Instant};

use crate::common;
use common::*;

fn data(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("tests/data/issue20")
        .join(name)
}

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

/// Run `runout args…`, returning its output and how long it took.
fn run(args: &[&str]) -> (Output, Duration) {
    let t = Instant::now();
    let out = runout().args(args).output().unwrap();
    (out, t.elapsed())
}

/// Assert a clean refusal: exit code 1 (no panic, no abort), the message holds every key word,
/// no line of it is longer than `max_line` characters, and the files are unchanged.
fn refused(args: &[&str], words: &[&str], unchanged: &[&Path]) -> String {
    let before: Vec<Vec<u8>> = unchanged
        .iter()
        .map(|p| std::fs::read(p).unwrap())
        .collect();
    let (out, took) = run(args);
    let err = String::from_utf8_lossy(&out.stderr).into_owned();
    assert_eq!(out.status.code(), Some(1), "{args:?}: {err}");
    assert!(!err.contains("panicked"), "{err}");
    for w in words {
        assert!(err.contains(w), "{args:?}: `{w}` not in: {err}");
    }
    assert!(took < Duration::from_secs(20), "{args:?} took {took:?}");
    for (p, b) in unchanged.iter().zip(before) {
        assert_eq!(std::fs::read(p).unwrap(), b, "{} changed", p.display());
    }
    err
}

const SIMULATE: [&str; 17] = [
    "simulate",
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
    "--ktc",
    "1889.2",
    "--krc",
    "806.1",
];

fn simulate_with(extra: &[&str]) -> Vec<String> {
    SIMULATE
        .iter()
        .chain(extra)
        .map(|x| x.to_string())
        .collect()
}

fn strs(v: &[String]) -> Vec<&str> {
    v.iter().map(String::as_str).collect()
}

// ----------------------------------------------------------------------------------------------
// rows 1–3, 9: chip case readers

#[test]
fn row01_apt_coordinate_1e300_is_a_range_error_naming_file_and_line() {
    let case = data("coordinate_out_of_range.toml");
    let apt = data("coordinate_out_of_range.apt");
    let err = refused(
        &["chip", "eval", s(&case)],
        &[
            "coordinate_out_of_range.apt:13",
            "coordinate out of range",
            "100000",
            "1e300",
        ],
        &[&case, &apt],
    );
    assert!(err.len() < 400, "{err}");
}

#[test]
fn row02_apt_feed_1e_minus_300_is_refused_with_the_limit() {
    let case = data("feed_too_small.toml");
    let apt = data("feed_too_small.apt");
    refused(
        &["chip", "eval", s(&case)],
        &[
            "feed_too_small.apt:12",
            "FEDRAT",
            "[0.001, 1000000] mm/min",
            "1e-300",
        ],
        &[&case, &apt],
    );
}

#[test]
fn row03_chip_case_teeth_4e9_is_a_range_error_not_an_allocation_abort() {
    let case = data("teeth_4e9.toml");
    refused(
        &["chip", "eval", s(&case)],
        &["teeth", "[1, 360]", "4000000000"],
        &[&case],
    );
}

#[test]
fn row09_apt_typo_got0_is_an_unknown_record_error_naming_the_line() {
    let case = data("unknown_record.toml");
    let apt = data("unknown_record.apt");
    refused(
        &["chip", "eval", s(&case)],
        &["unknown_record.apt:13", "unknown APT record", "GOT0"],
        &[&case, &apt],
    );
}

// ----------------------------------------------------------------------------------------------
// rows 4, 5, 15: simulate

#[test]
fn row04_simulate_teeth_1e6_is_a_range_error() {
    let a = simulate_with(&["--teeth", "1000000"]);
    refused(&strs(&a), &["teeth", "[1, 360]", "1000000"], &[]);
}

#[test]
fn row05_simulate_many_teeth_refuses_with_the_work_or_finishes() {
    let a = simulate_with(&["--teeth", "1000"]);
    refused(&strs(&a), &["teeth", "[1, 360]", "1000"], &[]);
    // within the teeth range, but too much work for the exact model: refused with the work
    let a = simulate_with(&[
        "--teeth",
        "200",
        "--helix-deg",
        "30",
        "--chip-model",
        "exact",
    ]);
    refused(
        &strs(&a),
        &["at most 1.000e10", "chip evaluations", "e11"],
        &[],
    );
    // and a large but feasible cutter finishes quickly
    let a = simulate_with(&["--teeth", "60"]);
    let (out, took) = run(&strs(&a));
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(took < Duration::from_secs(20));
}

#[test]
fn row15_simulate_runout_9000_um_on_a_10_mm_cutter_is_refused() {
    let a = simulate_with(&["--teeth", "4", "--runout-um", "9000"]);
    refused(
        &strs(&a),
        &["runout_um", "below the cutter radius", "9000 µm"],
        &[],
    );
    let a = simulate_with(&["--teeth", "4", "--runout-um", "4999"]);
    assert!(run(&strs(&a)).0.status.success());
}

// ----------------------------------------------------------------------------------------------
// rows 6, 7, 12: identify from recordings

fn identify_inputs() -> [PathBuf; 3] {
    [
        example("identify/cut_fz0.05.txt"),
        example("identify/cut_fz0.08.txt"),
        example("identify/cut.toml"),
    ]
}

#[test]
fn row06_identify_ap_1e308_is_a_range_error() {
    let [a, b, c] = identify_inputs();
    refused(
        &[
            "identify",
            s(&a),
            s(&b),
            "--config",
            s(&c),
            "--ap-mm",
            "1e308",
        ],
        &["ap_mm", "out of range", "1e308", "expected |value| <="],
        &[&a, &b, &c],
    );
    // within the range of lengths, beyond the range of depths
    refused(
        &[
            "identify",
            s(&a),
            s(&b),
            "--config",
            s(&c),
            "--ap-mm",
            "5000",
        ],
        &["ap_mm", "[0.001, 1000] mm", "5000"],
        &[&a, &b, &c],
    );
}

#[test]
fn row07_identify_fz_1e308_is_a_range_error_not_a_hang() {
    let [a, b, c] = identify_inputs();
    refused(
        &[
            "identify",
            s(&a),
            s(&b),
            "--config",
            s(&c),
            "--fz-mm",
            "1e308",
        ],
        &["fz_mm", "out of range", "1e308", "expected |value| <="],
        &[&a, &b, &c],
    );
    refused(
        &["identify", s(&a), s(&b), "--config", s(&c), "--fz-mm", "50"],
        &["fz_mm", "(0, 10] mm", "50"],
        &[&a, &b, &c],
    );
}

#[test]
fn row12_identical_recordings_as_two_feeds_are_refused() {
    let [a, _, c] = identify_inputs();
    refused(
        &[
            "identify",
            s(&a),
            s(&a),
            "--config",
            s(&c),
            "--fz-mm",
            "0.05,0.08",
        ],
        &["recordings 1", "and 2", "identical"],
        &[&a, &c],
    );
    // a copy under another name is the same recording too
    let d = tempfile::tempdir().unwrap();
    let copy = d.path().join("copy.txt");
    std::fs::copy(&a, &copy).unwrap();
    refused(
        &[
            "identify",
            s(&a),
            s(&copy),
            "--config",
            s(&c),
            "--fz-mm",
            "0.05,0.08",
        ],
        &["identical"],
        &[&a, &copy],
    );
}

// ----------------------------------------------------------------------------------------------
// rows 13, 14: identify peaks

const PEAKS: [&str; 10] = [
    "identify",
    "peaks",
    "--teeth",
    "4",
    "--fz-mm",
    "0.08",
    "--ae-mm",
    "2",
    "--diameter-mm",
    "10",
];

#[test]
fn row13_all_zero_peaks_are_refused_not_nan() {
    let mut a = PEAKS.to_vec();
    a.extend(["--peaks-N", "0,0,0,0"]);
    let err = refused(&a, &["peaks_N", "positive"], &[]);
    assert!(!err.contains("NaN"), "{err}");
}

#[test]
fn row14_negative_peaks_are_refused_never_a_negative_offset() {
    let mut a = PEAKS.to_vec();
    a.extend(["--peaks-N", "-366,-307,-259,-326"]);
    refused(&a, &["peaks_N[0]", ">= 0 N", "-366"], &[]);
}

// ----------------------------------------------------------------------------------------------
// row 8: shank

#[test]
fn row08_shank_reversed_air_cut_window_is_an_error_naming_the_key() {
    let cfg = data("shank_reversed_air_cut.toml");
    let rec = data("shank_recording.csv");
    refused(
        &["shank", "force", s(&rec), "--config", s(&cfg)],
        &["air_cut_s[0]", "start < end", "[0.4, 0]"],
        &[&cfg, &rec],
    );
    // a window past the end of the recording: a clear error, not a slice panic
    let d = tempfile::tempdir().unwrap();
    let text = std::fs::read_to_string(&cfg)
        .unwrap()
        .replace("[[0.4, 0.0]]", "[[0.4, 0.5]]");
    let cfg2 = d.path().join("late.toml");
    std::fs::write(&cfg2, text).unwrap();
    refused(
        &["shank", "force", s(&rec), "--config", s(&cfg2)],
        &["air cut", "revolutions"],
        &[&rec],
    );
}

// ----------------------------------------------------------------------------------------------
// rows 10, 11: grind compensate

fn grind_args<'a>(probe: &'a str, edge: &'a str) -> Vec<&'a str> {
    vec![
        "grind",
        "compensate",
        "--probe",
        probe,
        "--bar-diameter-mm",
        "6",
        "--probe-tip-radius-mm",
        "1",
        "--edge",
        edge,
    ]
}

#[test]
fn row10_nc_word_with_400_digits_is_an_error_naming_line_and_column() {
    let probe = example("grind/probe.csv");
    let edge = example("grind/edge.csv");
    let nc = data("word_400_digits.nc");
    let d = tempfile::tempdir().unwrap();
    let out = d.path().join("out.nc");
    let mut a = grind_args(s(&probe), s(&edge));
    a.extend(["--nc", s(&nc), "--out", s(&out)]);
    let err = refused(
        &a,
        &["word_400_digits.nc", "line 5, column 9", "out of range"],
        &[&probe, &edge, &nc],
    );
    assert!(!err.contains("inf"), "{err}");
    assert!(
        err.len() < 400,
        "the message quotes at most 80 characters: {err}"
    );
    assert!(!out.exists(), "no output on error");
}

#[test]
fn row11_output_hard_linked_to_the_input_program_is_refused() {
    let probe = example("grind/probe.csv");
    let edge = example("grind/edge.csv");
    let d = tempfile::tempdir().unwrap();
    let nc = d.path().join("in.nc");
    std::fs::copy(example("grind/flute.nc"), &nc).unwrap();
    let link = d.path().join("link.nc");
    std::fs::hard_link(&nc, &link).unwrap();
    let mut a = grind_args(s(&probe), s(&edge));
    a.extend(["--nc", s(&nc), "--out", s(&link)]);
    refused(
        &a,
        &["refusing to write", "link.nc", "in.nc"],
        &[&nc, &probe, &edge],
    );
    // the same for a JSON report and a symbolic link to the probe table
    #[cfg(unix)]
    {
        let sym = d.path().join("probe_link.csv");
        std::os::unix::fs::symlink(&probe, &sym).unwrap();
        let mut a = grind_args(s(&probe), s(&edge));
        a.extend(["--json", s(&sym)]);
        refused(&a, &["refusing to write"], &[&probe]);
    }
    // a chip case's toolpath is an input too
    let case = d.path().join("case.toml");
    std::fs::copy(example("chip/flank_path.toml"), &case).unwrap();
    let apt = d.path().join("flank.apt");
    std::fs::copy(example("chip/flank.apt"), &apt).unwrap();
    refused(
        &["chip", "eval", s(&case), "--out", s(&apt)],
        &["refusing to write", "flank.apt"],
        &[&case, &apt],
    );
}

// ----------------------------------------------------------------------------------------------
// row 16: huge one-line tables

#[test]
fn row16_100_mb_one_line_table_is_refused_with_a_short_message() {
    let d = tempfile::tempdir().unwrap();
    let big = d.path().join("big.csv");
    std::fs::write(&big, vec![b'a'; 100 * 1024 * 1024]).unwrap();
    let long = d.path().join("long.csv");
    std::fs::write(&long, vec![b'7'; 2 * 1024 * 1024]).unwrap();
    for table in [&big, &long] {
        let err = refused(&["identify", "tests", s(table)], &["bytes"], &[]);
        assert!(err.len() < 400, "{}", &err[..err.len().min(400)]);
        let edge = example("grind/edge.csv");
        let err = refused(&grind_args(s(table), s(&edge)), &["bytes"], &[]);
        assert!(err.len() < 400, "{}", &err[..err.len().min(400)]);
    }
    let err = refused(
        &["identify", "tests", s(&long)],
        &["long.csv:1", "longer than"],
        &[],
    );
    // the quote is at most 80 characters of the line
    assert!(err.contains(&format!("`{}…`", "7".repeat(80))), "{err}");
    assert!(!err.contains(&"7".repeat(81)), "{err}");
}

// ----------------------------------------------------------------------------------------------
// broken pipes: every command that prints ends quietly (status 0 or 141), never a panic

#[test]
fn broken_pipe_ends_quietly_on_every_command_that_prints() {
    let d = tempfile::tempdir().unwrap();
    let teeth = d.path().join("t.csv");
    std::fs::write(
        &teeth,
        "seed_edge,reading_um\n1,253.850568\n2,250.916561\n3,245.307498\n",
    )
    .unwrap();
    let heights = d.path().join("h.csv");
    std::fs::write(&heights, "z_mm,tir_um\n1,6.8\n2,7.6\n3,8.4\n4,9.2\n").unwrap();
    let e = |p: &str| example(p).to_str().unwrap().to_string();
    let owned = |v: &[&str]| v.iter().map(|x| x.to_string()).collect::<Vec<_>>();
    let mut cases: Vec<Vec<String>> = vec![
        simulate_with(&["--teeth", "4"]),
        simulate_with(&["--teeth", "4", "--out", "-"]),
        simulate_with(&["--teeth", "4", "--json", "-"]),
        owned(&[
            "identify",
            &e("identify/cut_fz0.05.txt"),
            &e("identify/cut_fz0.08.txt"),
            "--config",
            &e("identify/cut.toml"),
        ]),
        owned(&[
            "identify",
            "peaks",
            "--teeth",
            "4",
            "--fz-mm",
            "0.08",
            "--ae-mm",
            "2",
            "--diameter-mm",
            "10",
            "--peaks-N",
            "366.6,307.9,259.9,326.6",
        ]),
        owned(&["identify", "tests", &e("seed003_table1.csv")]),
        owned(&["chip", "eval", &e("chip/flank_path.toml")]),
        owned(&["chip", "eval", &e("chip/flank_path.toml"), "--out", "-"]),
        owned(&[
            "displacement",
            "teeth",
            teeth.to_str().unwrap(),
            "--teeth",
            "3",
            "--diameter-mm",
            "0.5",
            "--sensor",
            "radial",
            "--fz-mm",
            "0.002",
        ]),
        owned(&["displacement", "heights", heights.to_str().unwrap()]),
        owned(&[
            "shank",
            "stiffness",
            "--modulus-gpa",
            "210",
            "--diameter-mm",
            "8",
            "--tool-length-mm",
            "65",
            "--l1-mm",
            "10",
            "--l2-mm",
            "30",
        ]),
        owned(&["grind", "check"]),
        owned(&[
            "grind",
            "compensate",
            "--probe",
            &e("grind/probe.csv"),
            "--bar-diameter-mm",
            "6",
            "--probe-tip-radius-mm",
            "1",
            "--edge",
            &e("grind/edge.csv"),
        ]),
        owned(&[
            "grind",
            "compensate",
            "--probe",
            &e("grind/probe.csv"),
            "--bar-diameter-mm",
            "6",
            "--probe-tip-radius-mm",
            "1",
            "--edge",
            &e("grind/edge.csv"),
            "--path-out",
            "-",
        ]),
        owned(&["--help"]),
    ];
    cases.push(owned(&["chip", "compare", &e("chip/flank_path.toml")]));
    for c in &cases {
        closed_pipe(c);
    }
}

/// An error or a warning for a stderr whose reader is gone (as with `2>&1 | head -1` after the
/// first line): the command ends with its own status — 1 for the error — not a panic (status
/// 101: `eprintln!` panics when it cannot write).
#[test]
fn a_closed_stderr_keeps_the_commands_status() {
    use std::process::{Command as StdCommand, Stdio};
    let e = |p: &str| example(p).display().to_string();
    let run = |args: &[String]| {
        let mut child = StdCommand::new(assert_cmd::cargo::cargo_bin("runout"))
            .args(args)
            .env("RUST_BACKTRACE", "0")
            .stdout(Stdio::null())
            .stderr(Stdio::piped())
            .spawn()
            .unwrap();
        drop(child.stderr.take());
        child.wait().unwrap().code()
    };
    let rate = |v: &str| {
        vec![
            "identify".to_string(),
            e("identify/cut_fz0.05.txt"),
            e("identify/cut_fz0.08.txt"),
            "--config".into(),
            e("identify/cut.toml"),
            format!("--sample-rate-hz={v}"),
        ]
    };
    // an error (its message and the help pointer after it)
    assert_eq!(run(&rate("nan")), Some(1));
    assert_eq!(run(&rate("-5")), Some(1));
    // warnings, then the answer (the example's fit is identified)
    assert_eq!(run(&rate("10000")), Some(0));
}

// ----------------------------------------------------------------------------------------------
// item 5: non-finite numbers anywhere in a parsed file are errors naming where

#[test]
fn non_finite_numbers_anywhere_in_a_parsed_file_are_errors() {
    let d = tempfile::tempdir().unwrap();
    let put = |name: &str, text: String| {
        let p = d.path().join(name);
        std::fs::write(&p, text).unwrap();
        p
    };
    // a chip case: a key the resolver would not check itself
    let case = put(
        "case.toml",
        "[[case]]\nname = \"a\"\nteeth = 4\ndiameter_mm = 10\nrpm = 6000\nfz_mm = 0.1\n\
         heights_mm = [0.0]\nstart_s = nan\n"
            .into(),
    );
    refused(
        &["chip", "eval", s(&case)],
        &["case.toml", "start_s", "finite"],
        &[&case],
    );
    // a nested array element
    let case2 = put(
        "case2.toml",
        "[[case]]\nname = \"a\"\nteeth = 4\ndiameter_mm = 10\nrpm = 6000\nfz_mm = 0.1\n\
         heights_mm = [0.0, inf]\n"
            .into(),
    );
    refused(
        &["chip", "eval", s(&case2)],
        &["heights_mm[1]", "finite"],
        &[&case2],
    );
    // a simulate case file
    let sim = put(
        "sim.toml",
        "teeth = 4\ndiameter_mm = 10\nrpm = 3000\nfz_mm = 0.1\nap_mm = 1\nae_mm = 2\n\
         mode = \"up\"\nktc = nan\nkrc = 800\n"
            .into(),
    );
    refused(
        &["simulate", s(&sim)],
        &["sim.toml", "ktc", "finite"],
        &[&sim],
    );
    // a probe table cell
    let probe_text = std::fs::read_to_string(example("grind/probe.csv"))
        .unwrap()
        .replacen("4.008611", "nan", 1);
    let probe = put("probe.csv", probe_text);
    let edge = example("grind/edge.csv");
    refused(
        &grind_args(s(&probe), s(&edge)),
        &["probe.csv", "x_mm", "nan", "finite"],
        &[&probe],
    );
    // a peak table cell
    let table_text = std::fs::read_to_string(example("seed003_table1.csv")).unwrap();
    let first_data = table_text
        .lines()
        .find(|l| !l.starts_with('#') && l.starts_with(|c: char| c.is_ascii_digit()))
        .unwrap()
        .to_string();
    let mut cells: Vec<&str> = first_data.split(',').collect();
    cells[3] = "inf"; // peak0_N
    let table = put(
        "peaks.csv",
        table_text.replacen(&first_data, &cells.join(","), 1),
    );
    refused(
        &["identify", "tests", s(&table)],
        &["peaks.csv", "not finite"],
        &[&table],
    );
    // a shank config
    let shank = put(
        "shank.toml",
        std::fs::read_to_string(data("shank_reversed_air_cut.toml"))
            .unwrap()
            .replace("modulus_gpa = 210", "modulus_gpa = nan"),
    );
    refused(
        &[
            "shank",
            "force",
            s(&data("shank_recording.csv")),
            "--config",
            s(&shank),
        ],
        &["shank.modulus_gpa", "finite"],
        &[&shank],
    );
}

#[test]
fn endless_recording_header_is_refused_at_the_header_limit() {
    let d = tempfile::tempdir().unwrap();
    let rec = d.path().join("endless.txt");
    let mut text = String::from("DynoWare,Version 2.5.1.2\n");
    while text.len() < 2 * 1024 * 1024 {
        text += "Comment:,a long comment line that never ends the header\n";
    }
    std::fs::write(&rec, text).unwrap();
    let cfg = example("identify/cut.toml");
    refused(
        &["identify", s(&rec), "--config", s(&cfg), "--fz-mm", "0.05"],
        &["endless.txt", "DynoWare header longer than"],
        &[&rec],
    );
}

// ----------------------------------------------------------------------------------------------
// item 3: outputs are renamed into place only when the whole command succeeded

#[test]
fn a_command_failing_after_writing_leaves_no_output_and_no_temporary_file() {
    let d = tempfile::tempdir().unwrap();
    let out = d.path().join("forces.csv");
    let old = d.path().join("old.csv");
    std::fs::write(&old, "previous contents\n").unwrap();
    // the CSV is written before `--recording` is found to lack `--sample-rate-hz`
    let a = simulate_with(&[
        "--teeth",
        "4",
        "--out",
        s(&out),
        "--json",
        s(&old),
        "--recording",
        s(&d.path().join("rec.txt")),
    ]);
    refused(&strs(&a), &["--sample-rate-hz"], &[&old]);
    assert!(!out.exists());
    let names: Vec<String> = std::fs::read_dir(d.path())
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    assert_eq!(names, ["old.csv"], "{names:?}");
    // and a successful run writes both
    let a = simulate_with(&["--teeth", "4", "--out", s(&out), "--json", s(&old)]);
    assert!(run(&strs(&a)).0.status.success());
    assert!(std::fs::read_to_string(&out)
        .unwrap()
        .starts_with("time_s,"));
    assert!(std::fs::read_to_string(&old).unwrap().starts_with('{'));
}

#[test]
fn toml_errors_on_long_lines_do_not_echo_the_line() {
    let d = tempfile::tempdir().unwrap();
    let cfg = d.path().join("long.toml");
    std::fs::write(&cfg, format!("teeth = 4\n{}\n", "x".repeat(500_000))).unwrap();
    for cmd in [&["simulate"][..], &["chip", "eval"][..]] {
        let mut a = cmd.to_vec();
        a.push(s(&cfg));
        let err = refused(&a, &["long.toml", "line 2"], &[&cfg]);
        assert!(err.len() < 300, "{}", &err[..err.len().min(300)]);
    }
    let long_value = d.path().join("value.toml");
    std::fs::write(
        &long_value,
        format!("[[case]]\nname = \"a\"\nteeth = \"{}\"\n", "y".repeat(5000)),
    )
    .unwrap();
    let err = refused(
        &["chip", "eval", s(&long_value)],
        &["case 1"],
        &[&long_value],
    );
    assert!(err.len() < 600, "{}", &err[..err.len().min(600)]);
}
