//! `runout identify peaks` and `runout identify tests` on seed 003's Table 1.

use predicates::prelude::*;
use serde_json::Value;

use crate::common;
use common::*;

fn json_of(args: &[&str]) -> Value {
    let out = runout()
        .args(args)
        .assert()
        .success()
        .get_output()
        .stdout
        .clone();
    serde_json::from_slice(&out).unwrap()
}

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
fn peaks_json_matches_section_7_vectors() {
    let mut args = PEAKS.to_vec();
    args.extend(["--peaks-N", "366.6,307.9,259.9,326.6", "--json", "-"]);
    let j = json_of(&args);
    assert_eq!(j["schema"], "runout.identify.peaks/2");
    // H0 (K peaks): C 315.25, A 54.16, φ 99.94°, R² 0.9973 (methods.md §7)
    let f = |k: &str| j[k].as_f64().unwrap_or_else(|| panic!("{k}: {j}"));
    assert!((f("mean_N") - 315.25).abs() < 0.006);
    assert!((f("amplitude_N") - 54.16).abs() < 0.006);
    assert!((f("phase_deg") - 99.94).abs() < 0.006);
    assert!((f("r_squared") - 0.9973).abs() < 0.0001);
    // ρ = A/C·f_z sin γ/(2 sin(π/4)) = 54.16/315.25·0.064/1.4142 = 7.78 µm; λ = φ − 135°
    assert!((f("offset_um") - 7.775).abs() < 0.01);
    assert!((f("angle_deg") - (99.94 - 135.0)).abs() < 0.01);
    for k in [
        "mean_N_se",
        "amplitude_N_se",
        "phase_deg_se",
        "offset_um_se",
        "angle_deg_se",
    ] {
        assert!(f(k) > 0.0, "{k}");
    }
    // closed period (H1) reproduces Table 2: C 314.96, A 53.60, φ 100.05°, α₀ −34.95°, ρ 7.70 µm
    args.push("--closed-period");
    let j = json_of(&args);
    let f = |k: &str| j[k].as_f64().unwrap();
    assert!((f("mean_N") - 314.96).abs() < 0.006 && (f("amplitude_N") - 53.60).abs() < 0.006);
    assert!((f("phase_deg") - 100.05).abs() < 0.006 && (f("angle_deg") + 34.95).abs() < 0.006);
    assert!((f("offset_um") - 7.70).abs() < 0.006);
}

#[test]
fn peaks_text_summary() {
    let mut args = PEAKS.to_vec();
    args.extend(["--peaks-N", "366.6N,307.9,259.9,326.6"]);
    runout()
        .args(&args)
        .assert()
        .success()
        .stdout(predicate::str::contains("runout offset ρ = 7.78 µm"))
        .stdout(predicate::str::contains("angle λ = -35.06°"));
}

#[test]
fn peaks_degenerate_and_exact_cases() {
    // K = 2: refused with a pointer to the full-signal method
    runout()
        .args([
            "identify",
            "peaks",
            "--fz-mm",
            "0.1",
            "--mode",
            "slot",
            "--peaks-N",
            "110,90",
        ])
        .assert()
        .code(1)
        .stderr(predicate::str::contains("degenerate for K = 2"))
        .stderr(predicate::str::contains("full-signal"));
    // K = 3: exactly determined, no standard errors (null) and a warning
    let j = json_of(&[
        "identify",
        "peaks",
        "--fz-mm",
        "0.1",
        "--mode",
        "slot",
        "--peaks-N",
        "120,95,100",
        "--json",
        "-",
    ]);
    assert!(
        j["offset_um_se"].is_null() && j["mean_N_se"].is_null(),
        "{j}"
    );
    assert_eq!(j["residual_dof"], 0);
    assert!(j["warnings"].to_string().contains("exactly determined"));
    // with per-tooth standard errors they are propagated
    let j = json_of(&[
        "identify",
        "peaks",
        "--fz-mm",
        "0.1",
        "--mode",
        "slot",
        "--peaks-N",
        "120,95,100",
        "--peaks-se-N",
        "1,1,1",
        "--json",
        "-",
    ]);
    assert!((j["mean_N_se"].as_f64().unwrap() - (1.0f64 / 3.0).sqrt()).abs() < 1e-9);
}

#[test]
fn peaks_bad_inputs_give_clear_errors() {
    let mut a = PEAKS.to_vec();
    a.extend(["--peaks-N", "366.6,abc,259.9,326.6"]);
    runout()
        .args(&a)
        .assert()
        .code(1)
        .stderr(predicate::str::contains("--peaks-N: value 2 `abc`"));
    let mut a = PEAKS.to_vec();
    a.extend(["--peaks-N", "366.6,259.9,326.6"]);
    runout()
        .args(&a)
        .assert()
        .code(1)
        .stderr(predicate::str::contains(
            "--teeth 4 but --peaks-N has 3 values",
        ));
    runout()
        .args([
            "identify",
            "peaks",
            "--fz-mm",
            "0.1",
            "--peaks-N",
            "1,2,3,4",
        ])
        .assert()
        .code(1)
        .stderr(predicate::str::contains("--diameter-mm is needed"));
    runout()
        .args([
            "identify",
            "peaks",
            "--fz-mm",
            "0.1um",
            "--mode",
            "slot",
            "--peaks-N",
            "1,2,3,4",
        ])
        .assert()
        .success();
    runout()
        .args([
            "identify",
            "peaks",
            "--fz-mm",
            "0.1N",
            "--mode",
            "slot",
            "--peaks-N",
            "1,2,3,4",
        ])
        .assert()
        .code(1)
        .stderr(predicate::str::contains("--fz-mm"));
    runout()
        .args([
            "identify",
            "peaks",
            "--fz-mm",
            "0.1",
            "--mode",
            "sideways",
            "--peaks-N",
            "1,2,3",
        ])
        .assert()
        .code(1)
        .stderr(predicate::str::contains("mode"));
}

fn check_tests_json(j: &Value) {
    assert_eq!(j["schema"], "runout.identify.tests/1");
    let t = j["tests"].as_array().unwrap();
    assert_eq!(t.len(), 8);
    // seed eq. 17 from test 1: K_T ≈ 4081.6, K_R ≈ 3116.6 N/mm² within 0.5 %
    let kt = t[0]["kt_N_per_mm2"].as_f64().unwrap();
    let kr = t[0]["kr_N_per_mm2"].as_f64().unwrap();
    assert!(
        (kt / 4081.6 - 1.0).abs() < 0.005 && (kr / 3116.6 - 1.0).abs() < 0.005,
        "{kt} {kr}"
    );
    assert!(t[1]["kt_N_per_mm2"].is_null());
    // pooled edge-aware fit (methods.md §4.6): ρ 12.3 ± 1.3 µm, λ −50.7 ± 4.3°
    let p = &j["pooled_edge_aware"];
    assert!(
        (p["offset_um"].as_f64().unwrap() - 12.3).abs() < 0.05,
        "{p}"
    );
    assert!((p["angle_deg"].as_f64().unwrap() + 50.7).abs() < 0.1, "{p}");
    assert!((j["vector_mean"]["offset_um"].as_f64().unwrap() - 7.9).abs() < 0.05);
}

#[test]
fn tests_table_csv_and_toml() {
    for name in ["seed003_table1.csv", "seed003_table1.toml"] {
        let path = example(name);
        let j = json_of(&["identify", "tests", path.to_str().unwrap(), "--json", "-"]);
        check_tests_json(&j);
        // Table 2 under the closed-period hypothesis: test 5 C 203.58, φ 84.94°, ρ 8.34 µm
        let j = json_of(&[
            "identify",
            "tests",
            path.to_str().unwrap(),
            "--closed-period",
            "--json",
            "-",
        ]);
        let t5 = &j["tests"][4];
        assert!(
            (t5["mean_N"].as_f64().unwrap() - 203.58).abs() < 0.01,
            "{t5}"
        );
        assert!(
            (t5["phase_deg"].as_f64().unwrap() - 84.94).abs() < 0.01,
            "{t5}"
        );
        assert!(
            (t5["offset_um"].as_f64().unwrap() - 8.34).abs() < 0.01,
            "{t5}"
        );
    }
    runout()
        .args([
            "identify",
            "tests",
            example("seed003_table1.csv").to_str().unwrap(),
        ])
        .assert()
        .success()
        .stdout(predicate::str::contains(
            "pooled fit, edge force C0 + E·a_p: ρ = 12.32 µm",
        ));
}

#[test]
fn tests_table_errors_name_file_line_and_column() {
    let dir = tempfile::tempdir().unwrap();
    let bad = dir.path().join("bad.csv");
    std::fs::write(
        &bad,
        "test,fz_mm,ap_mm,peak0_N,peak1_N,peak2_N\n1,0.1,1,10,20,30\n2,0.1,1,10,x,30\n",
    )
    .unwrap();
    runout()
        .args(["identify", "tests", bad.to_str().unwrap(), "--mode", "slot"])
        .assert()
        .code(1)
        .stderr(predicate::str::contains(
            "bad.csv:3:5: `x` in column `peak1_N`",
        ));
    let missing = dir.path().join("m.csv");
    std::fs::write(
        &missing,
        "test,fz_mm,peak0_N,peak1_N,peak2_N\n1,0.1,10,20,30\n",
    )
    .unwrap();
    runout()
        .args(["identify", "tests", missing.to_str().unwrap()])
        .assert()
        .code(1)
        .stderr(predicate::str::contains("no column `ap_mm`"));
    // geometry missing for up-milling: names the file, line and test
    let nogeo = dir.path().join("g.csv");
    std::fs::write(
        &nogeo,
        "test,fz_mm,ap_mm,peak0_N,peak1_N,peak2_N\nA,0.1,1,10,20,30\n",
    )
    .unwrap();
    runout()
        .args(["identify", "tests", nogeo.to_str().unwrap()])
        .assert()
        .code(1)
        .stderr(predicate::str::contains("g.csv:2 (test A)"))
        .stderr(predicate::str::contains("--diameter-mm"));
    let toml = dir.path().join("t.toml");
    std::fs::write(
        &toml,
        "[[test]]\nfz_mm = 0.1\nap_mm = \"x\"\npeaks_N = [1, 2, 3]\n",
    )
    .unwrap();
    runout()
        .args([
            "identify",
            "tests",
            toml.to_str().unwrap(),
            "--mode",
            "slot",
        ])
        .assert()
        .code(1)
        .stderr(predicate::str::contains("t.toml:3"));
    // refuses to overwrite the input with --json
    runout()
        .args([
            "identify",
            "tests",
            bad.to_str().unwrap(),
            "--json",
            bad.to_str().unwrap(),
        ])
        .assert()
        .code(1)
        .stderr(predicate::str::contains("input file"));
}
