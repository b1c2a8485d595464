//! Issue 16: the same recording as DynoWare text, CSV, MATLAB .mat, TDMS, HDF5 and Parquet
//! gives identical `runout identify` results, field by field of the JSON (only the file name, format and format metadata differ), every number to the last digit. The
//! runs use one thread (`RAYON_NUM_THREADS=1`, as the snapshot tests; the results are the same at
//! any thread count since session 8, `snapshots::identify_is_identical_at_any_thread_count`).
//! `runout inspect` on each format.

use serde_json::Value;
use std::path::{Path, PathBuf};

use crate::common;
use common::*;

const FEEDS: [&str; 2] = ["cut_fz0.05.txt", "cut_fz0.08.txt"];

/// Drop what names the input (file, format, format metadata, input paths) from identify's JSON.
fn strip(v: &mut Value) {
    match v {
        Value::Object(m) => {
            for k in ["file", "format", "metadata", "inputs", "provenance"] {
                m.remove(k);
            }
            m.values_mut().for_each(strip);
        }
        Value::Array(a) => a.iter_mut().for_each(strip),
        _ => {}
    }
}

fn identify(files: &[PathBuf], dir: &Path, tag: &str) -> Value {
    let json = dir.join(format!("{tag}.json"));
    let out = runout()
        .arg("identify")
        .args(files)
        .arg("--config")
        .arg(example("identify/cut.toml"))
        .args(["--sample-rate-hz", "10000", "--json"])
        .arg(&json)
        .env("RAYON_NUM_THREADS", "1")
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{tag}: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    let mut v: Value = serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    strip(&mut v);
    v
}

/// Field-by-field comparison with the path of the first difference.
fn same(a: &Value, b: &Value, path: &str) -> Result<(), String> {
    match (a, b) {
        (Value::Object(x), Value::Object(y)) => {
            let kx: Vec<_> = x.keys().collect();
            let ky: Vec<_> = y.keys().collect();
            if kx != ky {
                return Err(format!("{path}: keys {kx:?} vs {ky:?}"));
            }
            for (k, v) in x {
                same(v, &y[k], &format!("{path}.{k}"))?;
            }
            Ok(())
        }
        (Value::Array(x), Value::Array(y)) => {
            if x.len() != y.len() {
                return Err(format!("{path}: {} vs {} elements", x.len(), y.len()));
            }
            for (i, (p, q)) in x.iter().zip(y).enumerate() {
                same(p, q, &format!("{path}[{i}]"))?;
            }
            Ok(())
        }
        // every number to the last digit (one thread: see the module documentation)
        _ if a == b => Ok(()),
        _ => Err(format!("{path}: {a} vs {b}")),
    }
}

#[test]
fn same_recording_in_csv_mat_tdms_gives_identical_identification() {
    let dir = tempfile::tempdir().unwrap();
    let reference = identify(
        &FEEDS.map(|f| example(&format!("identify/{f}"))),
        dir.path(),
        "dynoware",
    );
    let mut sets: Vec<(&str, Vec<PathBuf>)> =
        vec![("csv", vec![]), ("mat", vec![]), ("tdms", vec![])];
    for f in FEEDS {
        let [t, x, y, z] = example_columns(f);
        let stem = f.trim_end_matches(".txt");
        let csv = dir.path().join(format!("{stem}.csv"));
        let mut text = String::from("time_s,Fx_N,Fy_N,Fz_N\n");
        for k in 0..t.len() {
            text += &format!("{:?},{:?},{:?},{:?}\n", t[k], x[k], y[k], z[k]);
        }
        std::fs::write(&csv, text).unwrap();
        let mat = dir.path().join(format!("{stem}.mat"));
        write_mat(
            &mat,
            &[
                ("t", &t),
                ("Fx", &x),
                ("Fy", &y),
                ("Fz", &z),
                ("fs", &[10000.0]),
            ],
        );
        let tdms = dir.path().join(format!("{stem}.bin")); // detected by content
        write_tdms(
            &tdms,
            "Force",
            &[("time", &t), ("Fx", &x), ("Fy", &y), ("Fz", &z)],
        );
        sets[0].1.push(csv);
        sets[1].1.push(mat);
        sets[2].1.push(tdms);
    }
    for (tag, files) in &sets {
        let v = identify(files, dir.path(), tag);
        same(&reference, &v, tag).unwrap_or_else(|e| panic!("{tag} differs from DynoWare: {e}"));
    }
    // the result is not trivially empty
    assert!(reference["recordings"].as_array().unwrap().len() == 2);
    assert!(reference["full_signal"].is_object());
}

#[test]
#[ignore = "needs python3 with scipy, h5py, nptdms, pyarrow: .ci/run installs them"]
fn same_recording_written_by_scipy_nptdms_h5py_pyarrow_gives_identical_identification() {
    let dir = tempfile::tempdir().unwrap();
    let script = PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../runout-io/tests/fixtures/make_fixtures.py");
    let reference = identify(
        &FEEDS.map(|f| example(&format!("identify/{f}"))),
        dir.path(),
        "dynoware",
    );
    let exts = ["csv", "mat", "tdms", "h5", "parquet"];
    for f in FEEDS {
        let sub = dir.path().join(f.trim_end_matches(".txt"));
        let st = std::process::Command::new("python3")
            .arg(&script)
            .arg(&sub)
            .arg("--from-dynoware")
            .arg(example(&format!("identify/{f}")))
            .status()
            .expect("python3");
        assert!(st.success());
    }
    for ext in exts {
        let files: Vec<PathBuf> = FEEDS
            .iter()
            .map(|f| {
                dir.path()
                    .join(f.trim_end_matches(".txt"))
                    .join(format!("same.{ext}"))
            })
            .collect();
        let v = identify(&files, dir.path(), ext);
        same(&reference, &v, ext).unwrap_or_else(|e| panic!("{ext} differs from DynoWare: {e}"));
    }
}

#[test]
fn inspect_prints_every_format() {
    let fx = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../runout-io/tests/fixtures");
    for (f, want) in [
        ("mat5_compressed.mat", "Fx_600"),
        ("mat73.mat", "rec800.Fy"),
        ("plain.h5", "/force/Fz"),
        ("tdms_big_endian.tdms", "Force/Fy"),
    ] {
        let out = runout().arg("inspect").arg(fx.join(f)).output().unwrap();
        let text = String::from_utf8_lossy(&out.stdout);
        assert!(
            out.status.success(),
            "{f}: {}",
            String::from_utf8_lossy(&out.stderr)
        );
        assert!(text.contains(want) && text.contains("200"), "{f}: {text}");
    }
    let out = runout()
        .args(["inspect", "--json"])
        .arg(fx.join("tdms_writer.tdms"))
        .output()
        .unwrap();
    let v: Value = serde_json::from_slice(&out.stdout).unwrap();
    let e = &v["entries"][0];
    assert_eq!(e["name"], "Force/Fx");
    assert_eq!(e["len"], 200);
    assert_eq!(e["unit"], "N");
    assert_eq!(e["sample_rate_hz"], 1000.0);
    // a corrupt file: a clear error naming the file, no panic
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("cut.tdms");
    let b = std::fs::read(fx.join("tdms_writer.tdms")).unwrap();
    std::fs::write(&p, &b[..40]).unwrap();
    let out = runout().arg("inspect").arg(&p).output().unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        !out.status.success() && err.contains("cut.tdms") && !err.contains("panicked"),
        "{err}"
    );
}
