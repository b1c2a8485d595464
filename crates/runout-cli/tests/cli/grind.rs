//! `runout grind compensate` end to end on the shipped example (examples/grind).

use crate::common;
use common::*;

fn ex(name: &str) -> String {
    example(&format!("grind/{name}")).display().to_string()
}

fn base() -> Vec<String> {
    [
        "grind",
        "compensate",
        "--probe",
        &ex("probe.csv"),
        "--bar-diameter-mm",
        "6",
        "--probe-tip-radius-mm",
        "1",
    ]
    .iter()
    .map(|s| s.to_string())
    .collect()
}

/// The example bar: offset (8, −4) µm, tilt (0.3, 0.5) µm/mm, noise 0.3 µm (σ√(2/8) = 0.15 µm
/// per layer harmonic): the fitted axis is within 0.5 µm and 0.05 µm/mm, and the NC program
/// changes only in its 27 G1 lines plus the final retract.
#[test]
fn compensates_the_example_program() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out.nc");
    let json = dir.path().join("r.json");
    let path = dir.path().join("path.csv");
    let mut args = base();
    args.extend(
        [
            "--edge",
            &ex("edge.csv"),
            "--nc",
            &ex("flute.nc"),
            "--out",
            out.to_str().unwrap(),
            "--json",
            json.to_str().unwrap(),
            "--path-out",
            path.to_str().unwrap(),
            "--plots",
            dir.path().join("plots").to_str().unwrap(),
        ]
        .map(String::from),
    );
    runout().args(&args).assert().success();
    let r: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    assert_eq!(r["schema"], "runout.grind.compensate/2");
    let off = &r["axis"]["offset_at_u0_um"];
    assert!(
        (off[0].as_f64().unwrap() - 8.0).abs() < 0.5
            && (off[1].as_f64().unwrap() + 4.0).abs() < 0.5
    );
    let tilt = &r["axis"]["tilt_um_per_mm"];
    assert!(
        (tilt[0].as_f64().unwrap() - 0.3).abs() < 0.05
            && (tilt[1].as_f64().unwrap() - 0.5).abs() < 0.05
    );
    assert_eq!(r["compensation"]["points"], 27);
    assert!(
        r["compensation"]["predicted_remaining_max_um"]
            .as_f64()
            .unwrap()
            < 0.6
    );
    assert_eq!(r["nc"]["offset_moves"], 27);
    assert_eq!(r["nc"]["changed_lines"], 28);
    let input = std::fs::read_to_string(ex("flute.nc")).unwrap();
    let output = std::fs::read_to_string(&out).unwrap();
    for (a, b) in input
        .split_inclusive('\n')
        .zip(output.split_inclusive('\n'))
    {
        if a != b {
            assert!(
                a.contains(" G1 ") || a.contains(" G0 Z40."),
                "unexpected change: {a:?} → {b:?}"
            );
            assert!(b.ends_with("\r\n"));
        }
    }
    assert_eq!(std::fs::read_to_string(&path).unwrap().lines().count(), 28);
    for p in ["deviation_heatmap", "eps_along_edge", "radial_error"] {
        let svg =
            std::fs::read_to_string(dir.path().join("plots").join(format!("{p}.svg"))).unwrap();
        assert!(svg.contains("<svg") && svg.len() > 2000);
    }
}

#[test]
fn generated_edge_text_report_and_json_to_stdout() {
    let mut args = base();
    args.extend(["--edge", "flat", "--flutes", "4", "--json", "-"].map(String::from));
    let o = runout()
        .args(&args)
        .assert()
        .success()
        .get_output()
        .stdout
        .clone();
    let r: serde_json::Value = serde_json::from_slice(&o).unwrap();
    assert_eq!(r["compensation"]["points"], 800);
    let mut args = base();
    args.extend(
        [
            "--edge",
            "ball",
            "--flutes",
            "2",
            "--edge-from-mm",
            "0.1",
            "--edge-to-mm",
            "1.9",
            "--outside",
            "extrapolate",
        ]
        .map(String::from),
    );
    let o = runout()
        .args(&args)
        .assert()
        .success()
        .get_output()
        .stdout
        .clone();
    let text = String::from_utf8(o).unwrap();
    assert!(
        text.contains("400 edge points (400 outside the probed range)"),
        "{text}"
    );
    assert!(text.contains("tilt (0.3"), "{text}");
}

#[test]
fn refuses_to_overwrite_inputs_and_names_bad_rows() {
    let mut args = base();
    args.extend(
        [
            "--edge",
            &ex("edge.csv"),
            "--nc",
            &ex("flute.nc"),
            "--out",
            &ex("flute.nc"),
        ]
        .map(String::from),
    );
    runout()
        .args(&args)
        .assert()
        .failure()
        .stderr(predicates::str::contains("refusing to write"));
    let dir = tempfile::tempdir().unwrap();
    let bad = dir.path().join("probe.csv");
    let text = std::fs::read_to_string(ex("probe.csv")).unwrap();
    // line 9 (layer 0, 225°): the probe missed the bar
    let mut lines: Vec<String> = text.lines().map(String::from).collect();
    lines[8] = "0,2,225,-1.0,-1.0,2.0".into();
    std::fs::write(&bad, lines.join("\n")).unwrap();
    let mut args = base();
    args[3] = bad.display().to_string();
    args.extend(["--edge", "flat"].map(String::from));
    runout()
        .args(&args)
        .assert()
        .code(1)
        .stderr(predicates::str::contains("row 9").and(predicates::str::contains("probe miss")));
    // index mapping with a count mismatch is explained
    let mut args = base();
    args.extend(
        [
            "--edge",
            "flat",
            "--nc",
            &ex("flute.nc"),
            "--out",
            dir.path().join("o.nc").to_str().unwrap(),
        ]
        .map(String::from),
    );
    runout()
        .args(&args)
        .assert()
        .failure()
        .stderr(predicates::str::contains("--nc-map xyz"));
}

/// The example program's X Y Z are the edge points themselves, so `--nc-map xyz` (ε evaluated at
/// each move's own position) must give the same program as `--nc-map index` with edge.csv.
#[test]
fn xyz_mapping_equals_index_mapping_on_the_example() {
    let dir = tempfile::tempdir().unwrap();
    let (a, b) = (dir.path().join("a.nc"), dir.path().join("b.nc"));
    let mut args = base();
    args.extend(
        [
            "--edge",
            &ex("edge.csv"),
            "--nc",
            &ex("flute.nc"),
            "--out",
            a.to_str().unwrap(),
        ]
        .map(String::from),
    );
    runout().args(&args).assert().success();
    let mut args = base();
    args.extend(
        [
            "--edge",
            "flat",
            "--nc-map",
            "xyz",
            "--nc",
            &ex("flute.nc"),
            "--out",
            b.to_str().unwrap(),
        ]
        .map(String::from),
    );
    runout().args(&args).assert().success();
    let (ta, tb) = (
        std::fs::read_to_string(&a).unwrap(),
        std::fs::read_to_string(&b).unwrap(),
    );
    assert_eq!(ta, tb);
    assert_ne!(ta, std::fs::read_to_string(ex("flute.nc")).unwrap());
}

/// `runout grind check` reproduces the noise-free rows of methods.md §5.5 with the documented
/// setup (one edge at phase 18°, edge and layers on u = 2..28 mm): seed method 0.47 / 1.04 µm
/// (M5×C8) and 1.93 / 3.94 µm (M3×C4), first harmonic 0 / 0; tolerance 3 % rms, 2 % max as in
/// runout-core's tests/grind_sim.rs.
#[test]
fn check_reproduces_the_methods_table() {
    for (m, c, rms, max) in [("5", "8", 0.47, 1.04), ("3", "4", 1.93, 3.94)] {
        let o = runout()
            .args([
                "grind",
                "check",
                "--layers",
                m,
                "--angles",
                c,
                "--flutes",
                "1",
                "--edge-from-mm",
                "2",
                "--edge-phase-deg",
                "18",
                "--points-per-flute",
                "2001",
                "--json",
                "-",
            ])
            .assert()
            .success()
            .get_output()
            .stdout
            .clone();
        let r: serde_json::Value = serde_json::from_slice(&o).unwrap();
        assert_eq!(r["schema"], "runout.grind.check/2");
        let b = &r["bilinear"];
        let (br, bx) = (
            b["interpolation_rms_um"].as_f64().unwrap(),
            b["interpolation_max_um"].as_f64().unwrap(),
        );
        assert!(
            (br - rms).abs() <= 0.03 * rms && (bx - max).abs() <= 0.02 * max,
            "{b}"
        );
        assert!(
            r["first_harmonic"]["interpolation_max_um"]
                .as_f64()
                .unwrap()
                < 1e-3
        );
        // uncompensated: max |e·n| ≈ |e(28)| = 19.2 µm along the edge's angles
        assert!(r["uncompensated"]["radius_error_um"].as_f64().unwrap() > 10.0);
    }
    runout()
        .args(["grind", "check", "--offset-um", "8"])
        .assert()
        .failure()
        .stderr(predicates::str::contains(
            "--offset-um: expected two comma-separated values",
        ));
}

/// Radius-only probe table, offset 10 µm at 30° in the probe's angle sense: read as ccw the bar
/// offset is at +30°, read as cw at −30° (runout angle λ = −α: −30° and +30°).
#[test]
fn probe_angle_sense() {
    let dir = tempfile::tempdir().unwrap();
    let probe = dir.path().join("p.csv");
    let mut t = String::from("layer,u_mm,angle_deg,radius_mm\n");
    for (i, u) in [5.0, 15.0].iter().enumerate() {
        for j in 0..6 {
            let a = 60.0 * j as f64;
            t += &format!(
                "{i},{u},{a},{:.7}\n",
                3.0 + 0.01 * (a - 30.0f64).to_radians().cos()
            );
        }
    }
    std::fs::write(&probe, t).unwrap();
    for (sense, want) in [("ccw", 30.0), ("cw", -30.0)] {
        let o = runout()
            .args([
                "grind",
                "compensate",
                "--probe",
                probe.to_str().unwrap(),
                "--bar-diameter-mm",
                "6",
                "--probe-angle-sense",
                sense,
                "--json",
                "-",
            ])
            .assert()
            // two layers: the axis has no SE, partly identified (issue 21: exit 3)
            .code(3)
            .get_output()
            .stdout
            .clone();
        let r: serde_json::Value = serde_json::from_slice(&o).unwrap();
        let ax = &r["axis"];
        assert!(
            (ax["offset_angle_bar_deg"].as_f64().unwrap() - want).abs() < 1e-3,
            "{ax}"
        );
        assert!((ax["runout_angle_deg"].as_f64().unwrap() + want).abs() < 1e-3);
        assert!((ax["offset_um"].as_f64().unwrap() - 10.0).abs() < 1e-3);
        // two layers: no standard errors
        assert!(ax["offset_um_se"].is_null());
    }
}

use predicates::prelude::PredicateBooleanExt;
