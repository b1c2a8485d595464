//! Issue 21: the report opens with one answer (status, reasons), the plausibility guards feed it,
//! assumed defaults are stated, and the exit code says whether the result is identified
//! (0 identified, 3 not (fully) identified, 1 input error, 2 usage).

use std::path::{Path, PathBuf};
use std::process::Output;

use crate::common;
use common::*;

fn ex(name: &str) -> PathBuf {
    example(&format!("identify/{name}"))
}

fn identify(files: &[&Path], extra: &[&str]) -> Output {
    runout()
        .env("RAYON_NUM_THREADS", "1")
        .arg("identify")
        .args(files)
        .args(extra)
        .args(["--json", "-"])
        .output()
        .unwrap()
}

fn json(o: &Output) -> serde_json::Value {
    serde_json::from_slice(&o.stdout)
        .unwrap_or_else(|e| panic!("{e}: {}", String::from_utf8_lossy(&o.stderr)))
}

fn reasons(v: &serde_json::Value) -> String {
    v["answer"]["reasons"].to_string()
}

fn config() -> String {
    ex("cut.toml").display().to_string()
}

#[test]
fn bundled_example_is_identified_exit_0_and_the_negative_coefficient_is_not_a_result() {
    let a = ex("cut_fz0.05.txt");
    let b = ex("cut_fz0.08.txt");
    let o = identify(&[&a, &b], &["--config", &config()]);
    assert_eq!(
        o.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
    let v = json(&o);
    let ans = &v["answer"];
    assert_eq!(ans["status"], "identified");
    // known runout 8 µm at −50°: the answer within 0.2 µm / 2° (≈ 4 SE of the fit)
    let rho = ans["runout"]["offset_um"].as_f64().unwrap();
    let lam = ans["runout"]["angle_deg"].as_f64().unwrap();
    assert!((rho - 8.0).abs() < 0.2, "{rho}");
    assert!((lam + 50.0).abs() < 2.0, "{lam}");
    // K_ae was simulated at −3.1 N/mm: negative, so not a value to use
    let kae = &ans["coefficients"][5];
    assert_eq!(kae["name"], "K_ae");
    assert_eq!(kae["status"], "not identified");
    assert!(kae["value"].is_null());
    assert!(reasons(&v).contains("negative"), "{}", reasons(&v));
    // K_tc is positive and in the metal range: identified
    assert_eq!(ans["coefficients"][0]["status"], "identified");
    // the sine fits are cross-checks with the reason they differ
    let cc = ans["cross_checks"].as_array().unwrap();
    assert_eq!(cc.len(), 2);
    assert!(cc[0]["why_it_may_differ"]
        .as_str()
        .unwrap()
        .contains("biased at partial immersion"));
    // the helix is in the config: no helix warning; the profile is not: stated
    let w = ans["warnings"].to_string();
    assert!(!w.contains("--helix-deg"), "{w}");
    assert!(w.contains("--profile"), "{w}");
    // guards not triggered on clean, distinct, unclipped data
    let r = reasons(&v);
    assert!(!r.contains("clipped") && !r.contains("same samples"), "{r}");
}

#[test]
fn text_report_opens_with_the_answer() {
    let o = runout()
        .env("RAYON_NUM_THREADS", "1")
        .arg("identify")
        .args([ex("cut_fz0.05.txt"), ex("cut_fz0.08.txt")])
        .args(["--config", &config()])
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(0));
    let t = String::from_utf8_lossy(&o.stdout);
    let answer = t.find("ANSWER: runout ρ = 7.9").expect("answer line");
    let sine = t.find("sine fit").expect("sine fit line");
    assert!(answer < sine, "{t}");
    assert!(t.contains("status: identified"));
    assert!(t.contains("biased at partial immersion"));
    assert!(t.contains("K_ae not identified"), "{t}");
}

#[test]
fn omitted_helix_is_stated_as_an_assumption_on_stderr_and_in_the_report() {
    let dir = tempfile::tempdir().unwrap();
    let cfg = dir.path().join("cut.toml");
    let text = std::fs::read_to_string(ex("cut.toml")).unwrap();
    let without: String = text
        .lines()
        .filter(|l| !l.starts_with("helix_deg"))
        .map(|l| format!("{l}\n"))
        .collect();
    std::fs::write(&cfg, without).unwrap();
    let o = identify(
        &[&ex("cut_fz0.05.txt"), &ex("cut_fz0.08.txt")],
        &["--config", cfg.to_str().unwrap()],
    );
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        err.contains("assumed helix 0°") && err.contains("--helix-deg"),
        "{err}"
    );
    let v = json(&o);
    assert!(v["answer"]["warnings"]
        .to_string()
        .contains("pass --helix-deg"));
}

#[test]
fn the_same_data_under_another_name_is_refused() {
    // caught before the fit (by content, whatever the name): an input error, exit 1; the
    // report-level guard (`plausibility::duplicates` on the mapped samples) backs it up
    let dir = tempfile::tempdir().unwrap();
    let copy = dir.path().join("copy.txt");
    std::fs::copy(ex("cut_fz0.05.txt"), &copy).unwrap();
    let o = identify(&[&ex("cut_fz0.05.txt"), &copy], &["--config", &config()]);
    assert_eq!(o.status.code(), Some(1));
    assert!(String::from_utf8_lossy(&o.stderr).contains("are identical"));
}

#[test]
fn a_clipped_channel_is_not_identified_exit_3() {
    // clamp F_y of the second recording (its large component, negative: about −526 N) at 80 % of
    // its most negative value: 60 flat runs of ≥ 3 samples at the limit
    let dir = tempfile::tempdir().unwrap();
    let text = std::fs::read_to_string(ex("cut_fz0.08.txt")).unwrap();
    let rows: Vec<&str> = text.lines().collect();
    let start = rows.iter().position(|l| l.starts_with("s,N")).unwrap() + 1;
    let max = rows[start..]
        .iter()
        .filter_map(|l| l.split(',').nth(2)?.parse::<f64>().ok())
        .fold(f64::MAX, f64::min);
    let limit = 0.8 * max; // max is the most negative F_y
    let mut out = String::new();
    for (i, l) in rows.iter().enumerate() {
        if i < start {
            out += l;
        } else {
            let mut c: Vec<String> = l.split(',').map(String::from).collect();
            let y: f64 = c[2].parse().unwrap();
            c[2] = format!("{}", y.max(limit));
            out += &c.join(",");
        }
        out.push('\n');
    }
    let clipped = dir.path().join("clipped.txt");
    std::fs::write(&clipped, out).unwrap();
    let o = identify(&[&ex("cut_fz0.05.txt"), &clipped], &["--config", &config()]);
    assert_eq!(
        o.status.code(),
        Some(3),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
    let v = json(&o);
    assert_eq!(v["answer"]["status"], "not identified");
    assert!(reasons(&v).contains("is clipped"), "{}", reasons(&v));
}

/// A bull-nose cutter (corner radius 2 mm) at a_p = 1 mm < r_c, simulated with the general
/// geometry, identified as a flat end mill: not identified, with the reason, exit 3.
#[test]
fn bull_nose_cut_identified_as_flat_is_not_identified_exit_3() {
    let dir = tempfile::tempdir().unwrap();
    let mut files = Vec::new();
    for fz in ["0.05", "0.08"] {
        let f = dir.path().join(format!("bn_{fz}.txt"));
        runout()
            .args([
                "simulate",
                "--teeth",
                "4",
                "--diameter-mm",
                "10",
                "--helix-deg",
                "30",
            ])
            .args([
                "--rpm", "3240", "--fz-mm", fz, "--ap-mm", "1", "--ae-mm", "2",
            ])
            .args([
                "--mode",
                "down",
                "--runout-um",
                "8",
                "--runout-angle-deg",
                "-50",
            ])
            .args([
                "--ktc", "1889.2", "--krc", "806.1", "--kac", "291", "--kte", "63.12",
            ])
            .args([
                "--kre",
                "113.7",
                "--kae",
                "3.1",
                "--revolutions",
                "20",
                "--disks",
                "100",
            ])
            .args([
                "--sample-rate-hz",
                "10000",
                "--noise-percent",
                "2",
                "--air-cut-s",
                "0.2",
            ])
            .args([
                "--profile",
                "bull_nose",
                "--corner-radius-mm",
                "2",
                "--recording",
            ])
            .arg(&f)
            .success_output();
        files.push(f);
    }
    let refs: Vec<&Path> = files.iter().map(|p| p.as_path()).collect();
    let o = identify(
        &refs,
        &[
            "--teeth",
            "4",
            "--diameter-mm",
            "10",
            "--helix-deg",
            "30",
            "--rpm",
            "3240",
            "--fz-mm",
            "0.05,0.08",
            "--ap-mm",
            "1",
            "--ae-mm",
            "2",
            "--mode",
            "down",
            "--profile",
            "flat",
        ],
    );
    assert_eq!(
        o.status.code(),
        Some(3),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
    let v = json(&o);
    assert_eq!(v["answer"]["status"], "not identified");
    assert!(v["answer"]["runout"]["offset_um"].is_null());
    let r = reasons(&v);
    assert!(r.contains("end profile") || r.contains("profile"), "{r}");
    // the profile was given: no assumed-profile warning
    assert!(!v["answer"]["warnings"]
        .to_string()
        .contains("pass --profile"));
}

#[test]
fn exit_code_1_on_bad_input_and_2_on_usage() {
    let o = identify(
        &[Path::new("no/such/recording.txt")],
        &["--config", &config()],
    );
    assert_eq!(o.status.code(), Some(1));
    let o = runout()
        .args(["identify", "--no-such-flag"])
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(2));
    // and the table is in --help
    let h = runout().arg("--help").output().unwrap();
    assert!(String::from_utf8_lossy(&h.stdout).contains("3 ran, but the result is"));
}

/// Shank sensors: sensor II of the x pair with its sense reversed (968.6 µm − reading: same
/// range, variations mirrored) → a warning naming the axis; the bundled recording → none.
#[test]
fn shank_sensors_of_opposite_sense_are_warned() {
    let dir = tempfile::tempdir().unwrap();
    let text = std::fs::read_to_string(example("shank/recording.csv")).unwrap();
    let mut out = String::new();
    for (i, l) in text.lines().enumerate() {
        if i == 0 {
            out += l;
        } else {
            let mut c: Vec<String> = l.split(',').map(String::from).collect();
            let x: f64 = c[2].parse().unwrap();
            c[2] = format!("{:.4}", 968.6 - x);
            out += &c.join(",");
        }
        out.push('\n');
    }
    let flipped = dir.path().join("flipped.csv");
    std::fs::write(&flipped, out).unwrap();
    let run = |rec: &Path| {
        let o = runout()
            .args(["shank", "force"])
            .arg(rec)
            .arg("--config")
            .arg(example("shank/shank.toml"))
            .args(["--json", "-"])
            .output()
            .unwrap();
        assert!(
            o.status.code().is_some(),
            "{}",
            String::from_utf8_lossy(&o.stderr)
        );
        json(&o)["warnings"].to_string()
    };
    let w = run(&flipped);
    assert!(w.contains("x signals move in opposite senses"), "{w}");
    let w = run(&example("shank/recording.csv"));
    assert!(!w.contains("opposite senses"), "{w}");
}
