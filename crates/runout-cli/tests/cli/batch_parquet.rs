//! `runout batch` writes the summary also as Parquet next to the CSV (same columns, numbers as
//! DOUBLE, text as UTF-8), equal to the CSV row for row; read back by pyarrow (an independent
//! reader) in the ignored test that `.ci/run` runs.

use std::path::Path;

use crate::common::*;

/// `runout batch` on the bundled example and a broken file, into `dir/summary.csv`; extra args.
fn batch(dir: &Path, extra: &[&str]) -> std::process::Output {
    let broken = dir.join("broken.txt");
    std::fs::write(&broken, "time,Fx,Fy,Fz\n0,1,2\n").unwrap();
    runout()
        .current_dir(example(".."))
        .env("RAYON_NUM_THREADS", "1")
        .args(["batch", "examples/identify/cut_fz0.08.txt"])
        .arg(&broken)
        .args(["--config", "examples/identify/cut.toml", "--summary"])
        .arg(dir.join("summary.csv"))
        .args(["--threads", "2"])
        .args(extra)
        .args(["--", "--fz-mm", "0.08"])
        .output()
        .unwrap()
}

fn summaries() -> (tempfile::TempDir, std::path::PathBuf, std::path::PathBuf) {
    let d = tempfile::tempdir().unwrap();
    let out = batch(d.path(), &[]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let (csv, pq) = (
        d.path().join("summary.csv"),
        d.path().join("summary.parquet"),
    );
    (d, csv, pq)
}

#[test]
fn the_parquet_summary_equals_the_csv() {
    let (d, csv, pq) = summaries();
    let rows = runout::batch::read_summary(&csv).unwrap();
    assert_eq!(rows.len(), 2);
    assert_eq!(rows.iter().filter(|r| r.status == "ok").count(), 1);
    assert_eq!(runout::batch::read_summary_parquet(&pq).unwrap(), rows);
    // a resumed run analyses nothing, and both tables stay equal
    let out = batch(d.path(), &["--json", "-"]);
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(
        (v["analysed"].as_u64(), v["skipped"].as_u64()),
        (Some(0), Some(2))
    );
    assert_eq!(runout::batch::read_summary(&csv).unwrap(), rows);
    assert_eq!(runout::batch::read_summary_parquet(&pq).unwrap(), rows);
    // --parquet FILE elsewhere
    let other = d.path().join("elsewhere.parquet");
    let out = batch(d.path(), &["--parquet", other.to_str().unwrap()]);
    assert!(out.status.success());
    assert_eq!(runout::batch::read_summary_parquet(&other).unwrap(), rows);
}

/// pyarrow reads the Parquet summary with the documented types (float64 for numbers, string for
/// text) and the CSV's values: text equal, numbers equal as doubles (the CSV writes the shortest
/// round-trip decimal), empty CSV cells null.
#[test]
#[ignore = "needs python3 with pyarrow (.ci/requirements.txt)"]
fn pyarrow_reads_the_parquet_summary_as_the_csv() {
    let (_d, csv, pq) = summaries();
    let script = r#"
import csv, sys
import pyarrow as pa, pyarrow.parquet as pq
text = {"file", "status", "error", "time", "verdict"}
t = pq.read_table(sys.argv[2])
with open(sys.argv[1], newline="") as f:
    rows = list(csv.reader(f))
header, rows = rows[0], rows[1:]
assert t.column_names == header, (t.column_names, header)
assert t.num_rows == len(rows) == 2
for name in header:
    want = pa.string() if name in text else pa.float64()
    assert t.schema.field(name).type == want, (name, t.schema.field(name).type)
cols = t.to_pydict()
checked = 0
for i, row in enumerate(rows):
    for name, cell in zip(header, row):
        got = cols[name][i]
        if name in text:
            assert got == cell, (name, got, cell)
        elif cell == "":
            assert got is None, (name, got)
        else:
            assert got == float(cell), (name, got, cell)
            checked += 1
# the ok row's rho, lambda, the coefficients with their SEs and the fit quality
assert checked >= 15, checked
print("ok", checked)
"#;
    let out = std::process::Command::new("python3")
        .arg("-c")
        .arg(script)
        .arg(&csv)
        .arg(&pq)
        .output()
        .expect("python3");
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(String::from_utf8_lossy(&out.stdout).starts_with("ok "));
}
