//! The batch report (`runout batch --json -`, `runout.batch/1`) on the bundled example recording
//! plus one broken file, byte for byte (insta snapshot), and its summary's values equal a single
//! `runout identify` of the example. Redacted: the temporary directory (`[TMP]`) and the
//! wall-clock fields `elapsed_s` and `recordings_per_s` (`"[wall-clock]"`; they are checked here
//! to be positive numbers, and `crates/runout/tests/schemas.rs` puts numbers back before
//! validating the snapshot against docs/schema/batch.json).

use std::path::Path;

use crate::common::*;

/// The report's text with `tmp` as `[TMP]` and the wall-clock values as `"[wall-clock]"`.
fn redact(text: &str, tmp: &Path) -> String {
    let mut out = String::new();
    for line in text.lines() {
        let key = line.trim_start().split(':').next().unwrap_or_default();
        if key == "\"elapsed_s\"" || key == "\"recordings_per_s\"" {
            let (name, value) = line.split_once(": ").unwrap();
            let value = value.trim_end_matches(',');
            let x: f64 = value.parse().unwrap_or_else(|_| panic!("{line}"));
            assert!(x.is_finite() && x > 0.0, "{line}");
            let comma = if line.ends_with(',') { "," } else { "" };
            out.push_str(&format!("{name}: \"[wall-clock]\"{comma}\n"));
        } else {
            out.push_str(line);
            out.push('\n');
        }
    }
    out.replace(tmp.to_str().unwrap(), "[TMP]")
}

#[test]
fn batch() {
    let d = tempfile::tempdir().unwrap();
    let broken = d.path().join("broken.txt");
    std::fs::write(&broken, "time,Fx,Fy,Fz\n0,1,2\n").unwrap();
    let root = example("..");
    let summary = d.path().join("summary.csv");
    let out = runout()
        .current_dir(&root)
        .env("RAYON_NUM_THREADS", "1")
        .args([
            "batch",
            "examples/identify/cut_fz0.08.txt",
            broken.to_str().unwrap(),
            "--config",
            "examples/identify/cut.toml",
            "--summary",
            summary.to_str().unwrap(),
            "--threads",
            "1",
            "--json",
            "-",
            "--",
            "--fz-mm",
            "0.08",
        ])
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let text = String::from_utf8(out.stdout).unwrap();
    let v: serde_json::Value = serde_json::from_str(&text).unwrap();
    assert_eq!(v["schema"], "runout.batch/1");
    assert_eq!(
        (v["analysed"].as_u64(), v["ok"].as_u64()),
        (Some(2), Some(1))
    );
    insta::assert_snapshot!(redact(&text, d.path()));
    // the summary's row equals a single identify of the example (one thread, as batch runs it)
    let single = runout()
        .current_dir(&root)
        .env("RAYON_NUM_THREADS", "1")
        .args([
            "identify",
            "examples/identify/cut_fz0.08.txt",
            "--config",
            "examples/identify/cut.toml",
            "--fz-mm",
            "0.08",
            "--json",
            "-",
        ])
        .output()
        .unwrap();
    let single: serde_json::Value = serde_json::from_slice(&single.stdout).unwrap();
    let rows = runout::batch::read_summary(&summary).unwrap();
    let ok = rows.iter().find(|r| r.status == "ok").unwrap();
    let full = &single["full_signal"];
    assert_eq!(ok.offset_um, full["offset_um"].as_f64());
    assert_eq!(ok.angle_deg, full["angle_deg"].as_f64());
    assert_eq!(
        ok.ktc_N_per_mm2,
        full["coefficients"]["ktc_N_per_mm2"].as_f64()
    );
}
