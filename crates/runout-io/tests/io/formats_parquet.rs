//! Parquet read on the `parquet` crate's column API (no Arrow): every numeric physical / logical
//! type pyarrow writes, nulls, the compressions pyarrow, pandas and polars use, and the table
//! writer of the batch summary read back. Values are compared exactly (`==` on f64, NaN for a
//! null): every stored value chosen is exactly representable as f64, so any difference is a
//! decoding error, not rounding.

use runout_io::formats::parquet::{read_table, write_table, TableColumn};
use runout_io::formats::{inspect, open_kind, Kind};
use runout_io::recording::ReadOptions;
use serde_json::Value;
use std::path::Path;

/// Every entry of a Parquet file read whole through the recording `Source` (NaN for nulls).
fn read_columns(path: &Path) -> Vec<(String, bool, Vec<f64>)> {
    let mut o = open_kind(Kind::Parquet, path, "t.parquet").unwrap();
    let n = o.catalog.entries.first().map(|e| e.len).unwrap_or(0) as usize;
    let mut out = Vec::new();
    for (i, e) in o.catalog.entries.iter().enumerate() {
        let mut v = Vec::new();
        if e.readable {
            // two reads: a range crossing row groups, then the rest (increasing `start`)
            o.source.read(i, 0, n / 3, &mut v).unwrap();
            o.source.read(i, (n / 3) as u64, n - n / 3, &mut v).unwrap();
        }
        out.push((e.name.clone(), e.readable, v));
    }
    out
}

/// Same f64, NaN equal to NaN.
fn same(a: &[f64], b: &[f64]) -> bool {
    a.len() == b.len()
        && a.iter()
            .zip(b)
            .all(|(x, y)| x == y || (x.is_nan() && y.is_nan()))
}

/// pyarrow writes every numeric type (int8 … uint64 with values past the signed range, float32,
/// float64), nulls, a timestamp and a string column, under every compression it offers, as
/// PLAIN/dictionary data pages v1 and v2, in several row groups: the reader gives pyarrow's own
/// values (unsigned ones as unsigned), NaN for nulls, the dtypes named as Arrow names them, the
/// timestamp and text not readable; brotli (not built in) is an error naming the codec, the
/// column and the file.
#[test]
#[ignore = "needs python3 with pyarrow (.ci/requirements.txt)"]
fn pyarrow_types_nulls_and_codecs() {
    let dir = tempfile::tempdir().unwrap();
    let script = r#"
import json, sys, os
import numpy as np, pyarrow as pa, pyarrow.parquet as pq
n = 1000
i = np.arange(n)
null = (i % 7 == 3)
cols = {
    "f64": pa.array(np.where(null, np.nan, i * 0.25 - 100.0), mask=null),
    "f32": pa.array((i * 0.5 - 3.0).astype(np.float32)),
    "i8": pa.array(((i % 256) - 128).astype(np.int8)),
    "i16": pa.array((i * 37 - 20000).astype(np.int16)),
    "i32": pa.array((i * 1000003 - 2**30).astype(np.int32), mask=null),
    "i64": pa.array(i.astype(np.int64) * 2**40 - 2**52),
    "u8": pa.array((i % 256).astype(np.uint8)),
    "u16": pa.array((i * 65 % 65536).astype(np.uint16)),
    "u32": pa.array((i.astype(np.uint64) * 4000000 + 2**31).astype(np.uint32)),
    "u64": pa.array(np.uint64(2**63) + i.astype(np.uint64) * np.uint64(2048), type=pa.uint64()),
    "ts": pa.array(i.astype("datetime64[ms]")),
    "label": pa.array([f"s{k % 5}" for k in range(n)]),
}
t = pa.table(cols).replace_schema_metadata({"fs": "500"})
out = sys.argv[1]
for codec in ["none", "snappy", "gzip", "zstd", "lz4", "brotli"]:
    for v in ["1.0", "2.0"]:
        pq.write_table(t, os.path.join(out, f"{codec}-{v}.parquet"), compression=codec,
                       row_group_size=300, data_page_version=v, data_page_size=1024)
want = {}
for name, a in cols.items():
    if name in ("ts", "label"):
        continue
    want[name] = [None if x is None else int(x) if isinstance(x, int) else float(x) for x in a.to_pylist()]
with open(os.path.join(out, "want.json"), "w") as f:
    json.dump(want, f)
"#;
    let st = std::process::Command::new("python3")
        .arg("-c")
        .arg(script)
        .arg(dir.path())
        .status()
        .expect("python3");
    assert!(st.success());
    let want: serde_json::Map<String, Value> =
        serde_json::from_str(&std::fs::read_to_string(dir.path().join("want.json")).unwrap())
            .unwrap();
    let want: Vec<(String, Vec<f64>)> = want
        .into_iter()
        .map(|(k, v)| {
            let v = v
                .as_array()
                .unwrap()
                .iter()
                .map(|x| x.as_f64().unwrap_or(f64::NAN))
                .collect();
            (k, v)
        })
        .collect();
    // the unsigned columns really are past the signed range (a signed read would differ)
    let max = |name: &str| {
        want.iter()
            .find(|(k, _)| k == name)
            .unwrap()
            .1
            .iter()
            .fold(0f64, |a, &b| a.max(b))
    };
    assert!(max("u32") > 2f64.powi(31) && max("u64") >= 2f64.powi(63));
    let dtypes = [
        ("f64", "Float64"),
        ("f32", "Float32"),
        ("i8", "Int8"),
        ("i16", "Int16"),
        ("i32", "Int32"),
        ("i64", "Int64"),
        ("u8", "UInt8"),
        ("u16", "UInt16"),
        ("u32", "UInt32"),
        ("u64", "UInt64"),
        ("label", "Utf8"),
    ];
    let mut checked = 0;
    for codec in ["none", "snappy", "gzip", "zstd", "lz4"] {
        for v in ["1.0", "2.0"] {
            let p = dir.path().join(format!("{codec}-{v}.parquet"));
            let cat = inspect(&p, &ReadOptions::new()).unwrap();
            for (name, dtype) in dtypes {
                let e = cat.entries.iter().find(|e| e.name == name).unwrap();
                assert_eq!(e.dtype, dtype, "{codec} {v} {name}");
                assert_eq!(e.sample_rate_hz, Some(500.0));
            }
            let cols = read_columns(&p);
            for (name, readable, got) in &cols {
                match want.iter().find(|(k, _)| k == name) {
                    Some((_, w)) => {
                        assert!(*readable, "{name}");
                        assert!(
                            same(got, w),
                            "{codec} {v} {name}: {:?} vs {:?}",
                            &got[..5],
                            &w[..5]
                        );
                        checked += 1;
                    }
                    None => assert!(!readable && (name == "ts" || name == "label"), "{name}"),
                }
            }
        }
    }
    assert_eq!(checked, 5 * 2 * 10);
    // brotli: listed, but reading a column names the codec, the column and the file
    let p = dir.path().join("brotli-1.0.parquet");
    let mut o = open_kind(Kind::Parquet, &p, "b.parquet").unwrap();
    let e = &o.catalog.entries[0];
    assert!(e.note.as_deref().unwrap_or("").contains("BROTLI"), "{e:?}");
    let err = o
        .source
        .read(0, 0, 10, &mut Vec::new())
        .unwrap_err()
        .to_string();
    assert!(
        err.contains("b.parquet") && err.contains("BROTLI") && err.contains("`f64`"),
        "{err}"
    );
}

/// The table writer's output read back: equal columns (nulls, empty and non-ASCII text, a NaN
/// written as a value stays a value, distinct from a null), and the same file as a recording gives
/// the floats with NaN for nulls and the text not readable; a zero-row table and columns of
/// different lengths (an error naming the column).
#[test]
fn written_tables_read_back_equal() {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("t.parquet");
    let table = vec![
        (
            "file".to_string(),
            TableColumn::Text(vec!["a.csv".into(), "".into(), "µ-ß.mat".into()]),
        ),
        (
            "rho_um".to_string(),
            TableColumn::Float(vec![Some(1.5), None, Some(-0.1)]),
        ),
        (
            "x".to_string(),
            TableColumn::Float(vec![Some(f64::MAX), Some(f64::NAN), None]),
        ),
    ];
    write_table(std::fs::File::create(&p).unwrap(), &table, "t.parquet").unwrap();
    let back = read_table(&p).unwrap();
    assert_eq!(back.len(), 3);
    assert_eq!(back[0], table[0]);
    assert_eq!(back[1], table[1]);
    match &back[2].1 {
        TableColumn::Float(v) => {
            assert_eq!(v[0], Some(f64::MAX));
            assert!(v[1].is_some_and(f64::is_nan));
            assert_eq!(v[2], None);
        }
        c => panic!("{c:?}"),
    }
    let cols = read_columns(&p);
    assert_eq!(cols[0].0, "file");
    assert!(!cols[0].1);
    assert!(same(&cols[1].2, &[1.5, f64::NAN, -0.1]));
    // zero rows
    let empty = vec![
        ("a".to_string(), TableColumn::Text(vec![])),
        ("b".to_string(), TableColumn::Float(vec![])),
    ];
    let q = dir.path().join("e.parquet");
    write_table(std::fs::File::create(&q).unwrap(), &empty, "e.parquet").unwrap();
    assert_eq!(read_table(&q).unwrap(), empty);
    // different lengths
    let bad = vec![
        ("a".to_string(), TableColumn::Text(vec!["x".into()])),
        ("b".to_string(), TableColumn::Float(vec![])),
    ];
    let e = write_table(Vec::new(), &bad, "bad.parquet")
        .unwrap_err()
        .to_string();
    assert!(e.contains("bad.parquet") && e.contains("`b`"), "{e}");
}

/// A file that is not a table of DOUBLE and text columns: `read_table` names the column and its
/// type.
#[test]
fn read_table_names_an_unexpected_column_type() {
    let fixtures = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures");
    // table.parquet: time, Fx, Fy (DOUBLE), Fz (FLOAT), label (text)
    let e = read_table(&fixtures.join("table.parquet"))
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("table.parquet") && e.contains("`Fz`") && e.contains("Float32"),
        "{e}"
    );
}
