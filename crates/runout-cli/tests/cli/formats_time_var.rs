//! Issue 16 (session 6): every job that reads recordings reads every format, and `--time-var`.
//!
//! * `displacement signal` reads the example signal from .mat (v5) and TDMS (written here
//!   byte by byte) to the identical JSON of the CSV (everything but provenance and the file
//!   name); with Python (scipy, h5py, nptdms, pyarrow) also from .mat v7.3, HDF5, Parquet and a 2-D
//!   HDF5 dataset selected by `--channels` + `--time-var`.
//! * `shank force` reads its example recording from .mat to the identical JSON.
//! * `--time-var NAME` (identify, displacement signal, shank force): the named channel /
//!   variable is the time base; a missing name lists what the file holds; uneven times (beyond
//!   ½ sample, ¼ for displacement signal) and a disagreeing `--sample-rate-hz` are errors.

use serde_json::Value;
use std::path::{Path, PathBuf};

use crate::common::*;

/// The columns of a CSV file (header names, values parsed as Rust parses them).
fn csv_columns(path: &Path) -> (Vec<String>, Vec<Vec<f64>>) {
    let text = std::fs::read_to_string(path).unwrap();
    let mut lines = text.lines().filter(|l| !l.trim().is_empty());
    let names: Vec<String> = lines
        .next()
        .unwrap()
        .split(',')
        .map(str::to_string)
        .collect();
    let mut cols = vec![Vec::new(); names.len()];
    for l in lines {
        for (c, v) in cols.iter_mut().zip(l.split(',')) {
            c.push(v.trim().parse().unwrap());
        }
    }
    (names, cols)
}

/// Drop what names the input (file names, format, provenance) from a report.
fn strip(v: &mut Value) {
    match v {
        Value::Object(m) => {
            for k in [
                "file",
                "format",
                "metadata",
                "inputs",
                "provenance",
                "recording",
            ] {
                m.remove(k);
            }
            m.values_mut().for_each(strip);
        }
        Value::Array(a) => a.iter_mut().for_each(strip),
        _ => {}
    }
}

fn json_of(args: &[&str], file: &Path, extra: &[&str]) -> Value {
    let out = runout()
        .args(args)
        .arg(file)
        .args(extra)
        .args(["--json", "-"])
        .env("RAYON_NUM_THREADS", "1")
        .output()
        .unwrap();
    assert!(
        out.status.success() || out.status.code() == Some(3),
        "{}: {}",
        file.display(),
        String::from_utf8_lossy(&out.stderr)
    );
    let mut v: Value = serde_json::from_slice(&out.stdout).unwrap();
    strip(&mut v);
    v
}

fn fails(args: &[&str], file: &Path, extra: &[&str]) -> String {
    let out = runout()
        .args(args)
        .arg(file)
        .args(extra)
        .args(["--json", "-"])
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&out.stderr).to_string();
    assert!(
        !out.status.success() && !err.contains("panicked"),
        "{}: expected an error, got {}",
        file.display(),
        err
    );
    err
}

const SIGNAL: [&str; 2] = ["displacement", "signal"];
/// The README's command on the example signal.
const SIGNAL_FLAGS: [&str; 8] = [
    "--sensor-angles-deg",
    "0,90",
    "--teeth",
    "4",
    "--diameter-mm",
    "10",
    "--helix-deg",
    "30",
];

#[test]
fn displacement_signal_reads_mat_and_tdms_to_the_identical_json() {
    let dir = tempfile::tempdir().unwrap();
    let csv = example("displacement/signal.csv");
    let reference = json_of(&SIGNAL, &csv, &SIGNAL_FLAGS);
    assert!(reference["offset_um"].as_f64().unwrap() > 0.0);
    let (names, cols) = csv_columns(&csv);
    let vars: Vec<(&str, &[f64])> = names
        .iter()
        .zip(&cols)
        .map(|(n, c)| (n.as_str(), c.as_slice()))
        .collect();
    let mat = dir.path().join("signal.mat");
    write_mat(&mat, &vars);
    let tdms = dir.path().join("signal.dat"); // detected by content
    write_tdms(&tdms, "Probe", &vars);
    for f in [&mat, &tdms] {
        let v = json_of(&SIGNAL, f, &SIGNAL_FLAGS);
        assert_eq!(v, reference, "{} differs from the CSV", f.display());
    }
    // other names, through the mapping and the time variable (samples in µm, time in s)
    let renamed: Vec<(&str, &[f64])> = ["clock", "probe1", "probe2", "trig"]
        .into_iter()
        .zip(cols.iter().map(|c| c.as_slice()))
        .collect();
    let mat2 = dir.path().join("renamed.mat");
    write_mat(&mat2, &renamed);
    let mut flags = SIGNAL_FLAGS.to_vec();
    flags.extend([
        "--channels",
        "a = probe1 [um], b = probe2 [um], pulse = trig",
        "--time-var",
        "clock",
    ]);
    assert_eq!(json_of(&SIGNAL, &mat2, &flags), reference);
    // without a unit the mapping asks for one; a missing name lists the file
    let e = fails(
        &SIGNAL,
        &mat2,
        &["--channels", "a = probe1", "--time-var", "clock"],
    );
    assert!(e.contains("probe1") && e.contains("[um]"), "{e}");
    let e = fails(
        &SIGNAL,
        &mat2,
        &["--channels", "a = probeX [um]", "--time-var", "clock"],
    );
    assert!(
        e.contains("probeX") && e.contains("probe2") && e.contains("trig"),
        "{e}"
    );
}

#[test]
fn displacement_signal_time_var_and_sample_rate() {
    let dir = tempfile::tempdir().unwrap();
    let mut text = String::from("clock_ms,disp_a_um\n");
    for i in 0..4000 {
        let t = i as f64 * 0.05; // 20 kHz in ms
        text += &format!("{t},{}\n", 8.0 * (t * 0.1 * std::f64::consts::TAU).cos());
    }
    let p = dir.path().join("s.csv");
    std::fs::write(&p, &text).unwrap();
    // no `time_<unit>` column: named by --time-var (unit from its name)
    let e = fails(&SIGNAL, &p, &[]);
    assert!(e.contains("time_<unit>"), "{e}");
    let v = json_of(&SIGNAL, &p, &["--time-var", "clock_ms"]);
    assert!((v["rpm"].as_f64().unwrap() - 6000.0).abs() < 1.0, "{v}");
    // the same samples by a sample rate: the same result
    let w = json_of(
        &SIGNAL,
        &p,
        &["--time-var", "clock_ms", "--sample-rate-hz", "20000"],
    );
    assert_eq!(v, w);
    // a disagreeing rate: an error naming both
    let e = fails(
        &SIGNAL,
        &p,
        &["--time-var", "clock_ms", "--sample-rate-hz", "20500"],
    );
    assert!(
        e.contains("--sample-rate-hz") && e.contains("clock_ms"),
        "{e}"
    );
    // a missing time column lists the header
    let e = fails(&SIGNAL, &p, &["--time-var", "zeit"]);
    assert!(e.contains("zeit") && e.contains("clock_ms"), "{e}");
}

fn identify_args(file: &Path) -> Vec<String> {
    vec![
        "identify".into(),
        file.display().to_string(),
        "--config".into(),
        example("identify/cut.toml").display().to_string(),
        "--fz-mm".into(),
        "0.05".into(),
    ]
}

fn identify_json(file: &Path, extra: &[&str]) -> Value {
    let a = identify_args(file);
    let args: Vec<&str> = a.iter().map(String::as_str).collect();
    let out = runout()
        .args(&args[..1])
        .args(&args[1..])
        .args(extra)
        .args(["--json", "-"])
        .env("RAYON_NUM_THREADS", "1")
        .output()
        .unwrap();
    assert!(
        out.status.success() || out.status.code() == Some(3),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let mut v: Value = serde_json::from_slice(&out.stdout).unwrap();
    strip(&mut v);
    v
}

fn identify_fails(file: &Path, extra: &[&str]) -> String {
    let a = identify_args(file);
    let out = runout().args(&a).args(extra).output().unwrap();
    let err = String::from_utf8_lossy(&out.stderr).to_string();
    assert!(
        !out.status.success() && !err.contains("panicked"),
        "expected an error: {err}"
    );
    err
}

#[test]
fn identify_time_var_in_a_mat_file() {
    let dir = tempfile::tempdir().unwrap();
    let [t, x, y, z] = example_columns("cut_fz0.05.txt");
    let p = dir.path().join("r.mat");
    write_mat(
        &p,
        &[
            ("clock", &t),
            ("Fx", &x),
            ("Fy", &y),
            ("Fz", &z),
            ("rate", &[10000.0]),
        ],
    );
    // the time vector, the rate scalar, or the caller's rate: the same answer
    let by_vector = identify_json(&p, &["--time-var", "clock"]);
    let by_scalar = identify_json(&p, &["--time-var", "rate"]);
    let by_flag = identify_json(&p, &["--sample-rate-hz", "10000"]);
    let rate = |v: &Value| v["recordings"][0]["sample_rate_hz"].as_f64().unwrap();
    assert_eq!(rate(&by_vector), 10000.0);
    assert_eq!(by_scalar["recordings"], by_flag["recordings"]);
    assert_eq!(by_vector["answer"], by_flag["answer"]);
    // missing: the error lists what the file holds
    let e = identify_fails(&p, &["--time-var", "zeit"]);
    assert!(
        e.contains("zeit") && e.contains("Fx") && e.contains("clock"),
        "{e}"
    );
    // a rate variable and a disagreeing --sample-rate-hz
    let e = identify_fails(&p, &["--time-var", "rate", "--sample-rate-hz", "9000"]);
    assert!(
        e.contains("rate") && e.contains("9000") && e.contains("agree"),
        "{e}"
    );
    // a time vector and a disagreeing --sample-rate-hz (checked sample by sample, ½ period)
    let e = identify_fails(&p, &["--time-var", "clock", "--sample-rate-hz", "10100"]);
    assert!(e.contains("clock") && e.contains("--sample-rate-hz"), "{e}");
    // uneven times: a gap of 3 samples after sample 5000
    let gap: Vec<f64> = t
        .iter()
        .enumerate()
        .map(|(k, v)| if k > 5000 { v + 3e-4 } else { *v })
        .collect();
    let p2 = dir.path().join("gap.mat");
    write_mat(&p2, &[("clock", &gap), ("Fx", &x), ("Fy", &y), ("Fz", &z)]);
    let e = identify_fails(&p2, &["--time-var", "clock"]);
    assert!(
        e.contains("clock") && e.contains("sample 5001") && e.contains("evenly spaced"),
        "{e}"
    );
}

#[test]
fn shank_force_reads_a_mat_file_and_a_named_time_column() {
    let dir = tempfile::tempdir().unwrap();
    let rec = example("shank/recording.csv");
    let cfg = example("shank/shank.toml");
    let args = ["shank", "force"];
    let cfg_s = cfg.display().to_string();
    let reference = json_of(&args, &rec, &["--config", &cfg_s]);
    let (names, cols) = csv_columns(&rec);
    let vars: Vec<(&str, &[f64])> = names
        .iter()
        .zip(&cols)
        .map(|(n, c)| (n.as_str(), c.as_slice()))
        .collect();
    // .mat variables have no unit row: the units are in the names (xI_um, Fx_N) as in the CSV
    let mat = dir.path().join("recording.mat");
    write_mat(&mat, &vars);
    assert_eq!(json_of(&args, &mat, &["--config", &cfg_s]), reference);
    // the time column under another name, named by --time-var
    let text = std::fs::read_to_string(&rec)
        .unwrap()
        .replacen("time_s", "clock_s", 1);
    let renamed = dir.path().join("renamed.csv");
    std::fs::write(&renamed, text).unwrap();
    assert_eq!(
        json_of(
            &args,
            &renamed,
            &["--config", &cfg_s, "--time-var", "clock_s"]
        ),
        reference
    );
    let e = fails(&args, &renamed, &["--config", &cfg_s, "--time-var", "zeit"]);
    assert!(e.contains("zeit") && e.contains("clock_s"), "{e}");
}

/// The example signal exported by scipy (.mat v5), h5py (.mat v7.3, HDF5, a 2-D dataset),
/// nptdms and pyarrow (`runout-io/tests/fixtures/make_fixtures.py --signal`).
#[test]
#[ignore = "needs python3 with scipy, h5py, nptdms, pyarrow: .ci/run installs them"]
fn displacement_signal_from_independent_writers_is_identical() {
    let dir = tempfile::tempdir().unwrap();
    let script = PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../runout-io/tests/fixtures/make_fixtures.py");
    let csv = example("displacement/signal.csv");
    let st = std::process::Command::new("python3")
        .arg(&script)
        .arg(dir.path())
        .arg("--signal")
        .arg(&csv)
        .status()
        .expect("python3");
    assert!(st.success());
    let reference = json_of(&SIGNAL, &csv, &SIGNAL_FLAGS);
    let files = [
        "signal.mat",
        "signal73.mat",
        "signal.h5",
        "signal.tdms",
        "signal.parquet",
    ];
    for f in files {
        let v = json_of(&SIGNAL, &dir.path().join(f), &SIGNAL_FLAGS);
        assert_eq!(v, reference, "{f} differs from the CSV");
    }
    // a 2-D dataset with column names, the times in `t`, the pulse in `trig`
    let mut flags = SIGNAL_FLAGS.to_vec();
    flags.extend([
        "--channels",
        "a = D/a, b = D[:,1], pulse = trig",
        "--time-var",
        "t",
    ]);
    let v = json_of(&SIGNAL, &dir.path().join("signal_matrix.h5"), &flags);
    assert_eq!(v, reference, "signal_matrix.h5 differs from the CSV");
}

/// `runout inspect` shows struct-array fields, cells and the columns of 2-D datasets.
#[test]
fn inspect_shows_struct_fields_cells_and_matrix_columns() {
    let fx = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../runout-io/tests/fixtures");
    for (f, wants) in [
        (
            "mat5_cells.mat",
            &["s(2).Fy", "c{2}", "c{3}", "char array, not a channel"][..],
        ),
        (
            "matrix.h5",
            &[
                "/data[:,0]",
                "/data/Fz",
                "column 2 of the 200×3 dataset",
                "/dataT[:,2]",
            ][..],
        ),
        (
            "mat73_matrix.mat",
            &["s.Fx", "M(:,2)", "column 2 of the 2×200 dataset"][..],
        ),
    ] {
        let out = runout().arg("inspect").arg(fx.join(f)).output().unwrap();
        let text = String::from_utf8_lossy(&out.stdout);
        assert!(
            out.status.success(),
            "{f}: {}",
            String::from_utf8_lossy(&out.stderr)
        );
        for w in wants {
            assert!(text.contains(w), "{f}: `{w}` not in\n{text}");
        }
    }
}
