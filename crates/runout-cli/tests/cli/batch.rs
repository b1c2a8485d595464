//! `runout batch` over 200 generated recordings, some broken: the summary has every good one
//! (with the values of a single `runout identify` of that file), every bad one listed with its
//! error, a resumed run analyses nothing twice; and the throughput on 1 vs 2 threads.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::time::Instant;

use crate::common;
use common::*;

const CONFIG: &str = "teeth = 4\ndiameter_mm = 10.0\nhelix_deg = 0.0\nrpm = 3240\nfz_mm = 0.05\nap_mm = 2.0\nae_mm = 2.0\nmode = \"down\"\naxes = \"x = Fx, y = Fy, z = Fz\"\npeak_component = \"fxy\"\n";

/// Eight distinct simulated recordings (straight flutes, one disk: a fast fit; 14 revolutions at 5 kHz,
/// 2 % noise; runout 4–11 µm at varied angles).
fn base_recordings(dir: &Path) -> Vec<PathBuf> {
    (0..8)
        .map(|i| {
            let p = dir.join(format!("base{i}.txt"));
            runout()
                .args([
                    "simulate",
                    "--teeth",
                    "4",
                    "--diameter-mm",
                    "10",
                    "--helix-deg",
                    "0",
                ])
                .args([
                    "--rpm", "3240", "--fz-mm", "0.05", "--ap-mm", "2", "--ae-mm", "2",
                ])
                .args([
                    "--mode", "down", "--ktc", "1889.2", "--krc", "806.1", "--kac", "291",
                ])
                .args(["--kte", "63.12", "--kre", "113.7", "--kae", "-3.1"])
                .args([
                    "--revolutions",
                    "14",
                    "--disks",
                    "1",
                    "--sample-rate-hz",
                    "5000",
                ])
                .args(["--noise-percent", "2", "--air-cut-s", "0.05"])
                .arg("--runout-um")
                .arg(format!("{}", 4 + i))
                .arg("--runout-angle-deg")
                .arg(format!("{}", -150 + 40 * i))
                .arg("--seed")
                .arg(format!("{}", i + 1))
                .arg("--recording")
                .arg(&p)
                .success_output();
            p
        })
        .collect()
}

/// A broken recording of kind `k`: what it is, and its bytes.
fn broken(k: usize, good: &[u8]) -> Vec<u8> {
    match k % 5 {
        0 => Vec::new(),                            // empty
        1 => b"this is not a recording\n".to_vec(), // text without data
        2 => good[..good.len() / 40].to_vec(),      // cut in the header / first rows
        3 => {
            // a number spoiled in the middle of the data
            let mut b = good.to_vec();
            let i = b.len() / 2;
            let i = i + b[i..].iter().position(|&c| c == b'\n').unwrap() + 1;
            b[i] = b'x';
            b
        }
        _ => vec![0xff, 0xfe, 0x00, 0x01, 0x02], // binary garbage
    }
}

fn batch(args: &[&str], dir: &Path) -> serde_json::Value {
    let out = runout()
        .current_dir(dir)
        .arg("batch")
        .args(args)
        .args(["--json", "-"])
        .success_output();
    serde_json::from_slice(&out.stdout).unwrap()
}

fn summary(path: &Path) -> Vec<BTreeMap<String, String>> {
    let mut r = csv::Reader::from_path(path).unwrap();
    let header: Vec<String> = r.headers().unwrap().iter().map(String::from).collect();
    r.records()
        .map(|rec| {
            let rec = rec.unwrap();
            header
                .iter()
                .cloned()
                .zip(rec.iter().map(String::from))
                .collect()
        })
        .collect()
}

#[test]
fn two_hundred_recordings_some_broken_resumable_and_throughput() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path();
    std::fs::write(dir.join("cut.toml"), CONFIG).unwrap();
    let bases = base_recordings(dir);
    let cuts = dir.join("cuts");
    std::fs::create_dir(&cuts).unwrap();
    let mut bad = Vec::new();
    let mut origin = BTreeMap::new();
    for i in 0..200 {
        let name = format!("cut{i:03}.txt");
        let base = std::fs::read(&bases[i % 8]).unwrap();
        if i % 13 == 7 {
            std::fs::write(cuts.join(&name), broken(i, &base)).unwrap();
            bad.push(format!("cuts/{name}"));
        } else {
            std::fs::write(cuts.join(&name), &base).unwrap();
            origin.insert(format!("cuts/{name}"), i % 8);
        }
    }
    assert!(bad.len() >= 15);
    // the reference: one `runout identify` per distinct recording
    let mut reference = Vec::new();
    for b in &bases {
        let out = runout()
            .current_dir(dir)
            .env("RAYON_NUM_THREADS", "1")
            .args([
                "identify",
                b.to_str().unwrap(),
                "--config",
                "cut.toml",
                "--json",
                "-",
            ])
            .success_output();
        let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
        reference.push(v["full_signal"].clone());
    }

    let t0 = Instant::now();
    let report = batch(
        &[
            "cuts",
            "--config",
            "cut.toml",
            "--summary",
            "summary.csv",
            "--threads",
            "2",
        ],
        dir,
    );
    let two_threads_all = t0.elapsed().as_secs_f64();
    assert_eq!(report["analysed"], 200);
    assert_eq!(report["ok"], 200 - bad.len());
    let failed: Vec<&str> = report["failed"]
        .as_array()
        .unwrap()
        .iter()
        .map(|f| f["file"].as_str().unwrap())
        .collect();
    assert_eq!(failed, bad.iter().map(String::as_str).collect::<Vec<_>>());
    let rows = summary(&dir.join("summary.csv"));
    assert_eq!(rows.len(), 200);
    for r in &rows {
        let file = &r["file"];
        match origin.get(file) {
            Some(&k) => {
                assert_eq!(r["status"], "ok", "{r:?}");
                // the values of a single `runout identify`, to the last digit (CSV keeps the
                // shortest round-trip representation)
                let f = &reference[k];
                for (col, key) in [
                    ("offset_um", "offset_um"),
                    ("offset_se_um", "offset_um_se"),
                    ("angle_deg", "angle_deg"),
                    ("angle_se_deg", "angle_deg_se"),
                    ("r_squared", "r_squared"),
                    ("residual_rms_N", "residual_rms_N"),
                    ("condition", "condition"),
                ] {
                    assert_eq!(
                        r[col].parse::<f64>().unwrap(),
                        f[key].as_f64().unwrap(),
                        "{file} {col}"
                    );
                }
                assert_eq!(
                    r["ktc_N_per_mm2"].parse::<f64>().unwrap(),
                    f["coefficients"]["ktc_N_per_mm2"].as_f64().unwrap()
                );
                // ρ and λ identified (a small edge coefficient may not be, with its reason)
                let v = &r["verdict"];
                assert!(
                    v == "identified" || v.starts_with("not identified: k"),
                    "{v}"
                );
                assert!(r["time"].ends_with('Z'), "{r:?}");
                let rho = r["offset_um"].parse::<f64>().unwrap();
                assert!(
                    (rho - (4 + k) as f64).abs() < 1.0,
                    "{file}: ρ {rho} µm, simulated {}",
                    4 + k
                );
            }
            None => {
                assert!(bad.contains(file));
                assert_eq!(r["status"], "error");
                assert!(r["error"].contains(file.as_str()), "{r:?}");
                assert_eq!(r["offset_um"], "");
            }
        }
    }

    // resumed: nothing analysed again, the summary unchanged
    let before = std::fs::read(dir.join("summary.csv")).unwrap();
    let report = batch(
        &[
            "cuts/*.txt",
            "--config",
            "cut.toml",
            "--summary",
            "summary.csv",
        ],
        dir,
    );
    assert_eq!(
        (report["analysed"].as_u64(), report["skipped"].as_u64()),
        (Some(0), Some(200))
    );
    assert_eq!(std::fs::read(dir.join("summary.csv")).unwrap(), before);

    // throughput: the same 24 good recordings on 1 and on 2 threads (same run)
    let subset = dir.join("subset");
    std::fs::create_dir(&subset).unwrap();
    for i in 0..24 {
        std::fs::copy(&bases[i % 8], subset.join(format!("s{i:02}.txt"))).unwrap();
    }
    let mut rate = Vec::new();
    for threads in ["1", "2"] {
        let s = format!("summary{threads}.csv");
        let r = batch(
            &[
                "subset",
                "--config",
                "cut.toml",
                "--summary",
                &s,
                "--threads",
                threads,
            ],
            dir,
        );
        assert_eq!(r["ok"], 24);
        rate.push(r["recordings_per_s"].as_f64().unwrap());
    }
    // equal summaries whatever the thread count (times aside: copies made at different moments)
    let strip = |p: &str| {
        summary(&dir.join(p))
            .into_iter()
            .map(|mut r| {
                r.remove("time");
                r
            })
            .collect::<Vec<_>>()
    };
    assert_eq!(strip("summary1.csv"), strip("summary2.csv"));
    eprintln!(
        "batch: 200 recordings ({} broken) on 2 threads in {two_threads_all:.1} s; 24 recordings: {:.2} recordings/s on 1 thread, {:.2} on 2 threads (×{:.2})",
        bad.len(),
        rate[0],
        rate[1],
        rate[1] / rate[0]
    );
    // two workers must not be slower than one (the machine may be shared, so no speed-up is asserted)
    assert!(rate[1] > 0.8 * rate[0], "{rate:?}");
}
