//! `runout simulate` end to end: outputs, units in names, and clear errors for bad configs.

use std::fs;

use crate::common;
use common::*;

#[test]
fn flags_alone_give_reference_peak_in_json() {
    let out = runout()
        .args(SEED003_CUT)
        .args(SEED003_COEFFICIENTS)
        .args(["--step-deg", "0.01", "--revolutions", "1", "--json", "-"])
        .success_output();
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(v["schema"], "runout.simulate/1");
    let peaks = v["tooth_peaks"].as_array().unwrap();
    assert_eq!(peaks.len(), 4);
    for p in peaks {
        let f = p["peak_fxy_N"].as_f64().unwrap();
        assert!((f - 247.361).abs() < 0.02, "{f}");
    }
    assert_eq!(v["inputs"]["diameter_mm"], 10.0);
}

#[test]
fn example_config_writes_csv_json_and_plots() {
    let dir = tempfile::tempdir().unwrap();
    let csv = dir.path().join("f.csv");
    let json = dir.path().join("s.json");
    let svg = dir.path().join("f.svg");
    let png = dir.path().join("f.png");
    let cfg = concat!(env!("CARGO_MANIFEST_DIR"), "/../../examples/simulate.toml");
    for plot in [&svg, &png] {
        runout()
            .args(["simulate", cfg, "--out"])
            .arg(&csv)
            .arg("--json")
            .arg(&json)
            .arg("--plot")
            .arg(plot)
            .assert()
            .success();
    }
    let text = fs::read_to_string(&csv).unwrap();
    let header = text.lines().next().unwrap();
    assert_eq!(
        header,
        "time_s,angle_deg,fx_N,fy_N,fz_N,torque_Nm,h0_mm,h1_mm,h2_mm,h3_mm"
    );
    assert_eq!(text.lines().count(), 1 + 2 * 1440);
    let v: serde_json::Value = serde_json::from_str(&fs::read_to_string(&json).unwrap()).unwrap();
    assert_eq!(v["inputs"]["runout_um"], 8.0);
    assert!(fs::read_to_string(&svg).unwrap().contains("<svg"));
    assert_eq!(&fs::read(&png).unwrap()[1..4], b"PNG");
}

#[test]
fn flags_override_the_file_and_accept_unit_suffixes() {
    let cfg = concat!(env!("CARGO_MANIFEST_DIR"), "/../../examples/simulate.toml");
    let out = runout()
        .args([
            "simulate",
            cfg,
            "--runout-um",
            "0.012mm",
            "--revolutions",
            "1",
            "--json",
            "-",
        ])
        .success_output();
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert!((v["inputs"]["runout_um"].as_f64().unwrap() - 12.0).abs() < 1e-9);
}

/// Run with a config text; return (success, stderr).
fn with_config(text: &str) -> (bool, String) {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("case.toml");
    fs::write(&p, text).unwrap();
    let out = runout().arg("simulate").arg(&p).output().unwrap();
    (
        out.status.success(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

const GOOD: &str = "teeth = 4\ndiameter_mm = 10\nrpm = 3000\nfz_mm = 0.1\nap_mm = 1\nae_mm = 2\nmode = \"up\"\nktc = 2000\nkrc = 800\nrevolutions = 1\nstep_deg = 1\n";

#[test]
fn bad_configs_name_the_key_and_what_was_expected() {
    assert!(with_config(GOOD).0);
    let cases: [(&str, &str, &str); 12] = [
        (
            "ap_mm = 1",
            "ap_mm = 1\nflute_length_mm = 0.5",
            "flute length",
        ),
        ("revolutions = 1", "revolutions = 1e9", "(0, 100000]"),
        (
            "step_deg = 1",
            "step_deg = 0.00001",
            "at most 20000000 samples",
        ),
        ("diameter_mm = 10", "diameter_mm = -10", "diameter_mm"),
        ("diameter_mm = 10", "diameter_mm = 0", "diameter_mm"),
        ("ae_mm = 2", "ae_mm = 12", "ae_mm"),
        ("teeth = 4", "teeth = 0", "teeth"),
        ("fz_mm = 0.1", "fz_mm = nan", "fz_mm"),
        ("fz_mm = 0.1", "fz_mm = 0", "fz_mm"),
        (
            "rpm = 3000",
            "rpm = 3000\nhelix = 30",
            "unknown key `helix`",
        ),
        (
            "diameter_mm = 10",
            "diameter_mm = \"10 furlongs\"",
            "not a recognised unit",
        ),
        ("diameter_mm = 10", "diameter_mm = \"10rpm\"", "diameter_mm"),
    ];
    for (from, to, needle) in cases {
        let (ok, err) = with_config(&GOOD.replace(from, to));
        assert!(!ok, "{to} should fail");
        assert!(err.contains(needle), "{to}: stderr lacks `{needle}`: {err}");
        assert!(!err.contains("panicked"), "{to}: {err}");
    }
}

#[test]
fn malformed_toml_reports_line_and_missing_keys_name_the_flag() {
    let (ok, err) = with_config("teeth = 4\ndiameter_mm = = 3\n");
    assert!(!ok && err.contains("line 2"), "{err}");
    let (ok, err) = with_config(&GOOD.replace("rpm = 3000\n", ""));
    assert!(!ok && err.contains("--rpm"), "{err}");
}

#[test]
fn refuses_to_overwrite_the_config() {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("case.toml");
    fs::write(&p, GOOD).unwrap();
    runout()
        .arg("simulate")
        .arg(&p)
        .arg("--out")
        .arg(&p)
        .failure_output();
    assert_eq!(fs::read_to_string(&p).unwrap(), GOOD);
}
