//! The batch framework (`runout::batch`) with a stand-in analysis: every good file in the
//! summary, every bad one listed with its error, a resumed run analyses nothing twice, an
//! interrupted run (rows appended, not yet sorted) resumes.

use runout::batch::{self, BatchRequest, Row};
use std::path::Path;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::Mutex;

/// The stand-in: the file holds `rho,angle`; anything else is an error.
fn analyse(p: &Path) -> anyhow::Result<Row> {
    let text = std::fs::read_to_string(p)?;
    let (a, b) = text
        .trim()
        .split_once(',')
        .ok_or_else(|| anyhow::anyhow!("{}: expected `rho,angle`", p.display()))?;
    Ok(Row {
        offset_um: Some(a.parse()?),
        angle_deg: Some(b.parse()?),
        verdict: "fine".into(),
        ..Row::default()
    })
}

fn make(dir: &Path, n: usize) -> (Vec<std::path::PathBuf>, usize) {
    let mut bad = 0;
    let files = (0..n)
        .map(|i| {
            let p = dir.join(format!("rec{i:04}.txt"));
            let text = if i % 17 == 5 {
                bad += 1;
                "not a recording".to_string()
            } else {
                format!("{},{}", i as f64 * 0.25, -(i as f64))
            };
            std::fs::write(&p, text).unwrap();
            p
        })
        .collect();
    (files, bad)
}

#[test]
fn every_file_once_errors_listed_resumable() {
    let dir = tempfile::tempdir().unwrap();
    let data = dir.path().join("cuts");
    std::fs::create_dir(&data).unwrap();
    let (files, bad) = make(&data, 200);
    assert_eq!(batch::expand(data.to_str().unwrap()).unwrap(), files);
    let pattern = format!("{}/rec00*.txt", data.display());
    assert_eq!(batch::expand(&pattern).unwrap().len(), 100);
    let summary = dir.path().join("out/summary.csv");
    let calls = AtomicUsize::new(0);
    let counted = |p: &Path| {
        calls.fetch_add(1, Ordering::SeqCst);
        analyse(p)
    };
    let req = BatchRequest {
        files: files.clone(),
        summary: summary.clone(),
        threads: Some(2),
        retry_errors: false,
        parquet: None,
    };
    let seen = Mutex::new(0usize);
    let report = batch::run(&req, counted, &|_| *seen.lock().unwrap() += 1).unwrap();
    assert_eq!(calls.load(Ordering::SeqCst), 200);
    assert_eq!(*seen.lock().unwrap(), 200);
    assert_eq!(
        (report.analysed, report.ok, report.failed.len()),
        (200, 200 - bad, bad)
    );
    assert_eq!(report.threads, 2);
    for f in &report.failed {
        assert!(f.error.contains("expected `rho,angle`"), "{f:?}");
    }
    let rows = batch::read_summary(&summary).unwrap();
    assert_eq!(rows.len(), 200);
    // sorted by file, every good value exactly as analysed, bad ones with their message
    for (i, r) in rows.iter().enumerate() {
        assert_eq!(r.file, files[i].display().to_string());
        assert!(!r.time.is_empty());
        if i % 17 == 5 {
            assert_eq!(r.status, "error");
            assert!(r.error.contains(&format!("rec{i:04}.txt")), "{}", r.error);
            assert_eq!(r.offset_um, None);
        } else {
            assert_eq!(r.status, "ok");
            assert_eq!(r.offset_um, Some(i as f64 * 0.25));
            assert_eq!(r.angle_deg, Some(-(i as f64)));
            assert_eq!(r.verdict, "fine");
        }
    }
    // resumed: no work at all
    let before = std::fs::read(&summary).unwrap();
    let report = batch::run(&req, counted, &|_| {}).unwrap();
    assert_eq!(
        calls.load(Ordering::SeqCst),
        200,
        "a file was analysed twice"
    );
    assert_eq!(
        (report.analysed, report.skipped, report.rows),
        (0, 200, 200)
    );
    assert_eq!(std::fs::read(&summary).unwrap(), before);
    // retrying errors analyses exactly the bad files again
    let retry = BatchRequest {
        retry_errors: true,
        ..req.clone()
    };
    let report = batch::run(&retry, counted, &|_| {}).unwrap();
    assert_eq!(calls.load(Ordering::SeqCst), 200 + bad);
    assert_eq!((report.analysed, report.rows), (bad, 200));
    assert_eq!(std::fs::read(&summary).unwrap(), before);
}

#[test]
fn an_interrupted_run_resumes_where_it_stopped() {
    let dir = tempfile::tempdir().unwrap();
    let (files, _) = make(dir.path(), 40);
    let summary = dir.path().join("summary.csv");
    // first run over 25 files, then the summary is cut after its 10th row as if killed while
    // appending (unsorted rows, a partial last line would be a parse error, so whole lines)
    let req = BatchRequest {
        files: files[..25].to_vec(),
        summary: summary.clone(),
        threads: Some(1),
        retry_errors: false,
        parquet: None,
    };
    batch::run(&req, analyse, &|_| {}).unwrap();
    let text = std::fs::read_to_string(&summary).unwrap();
    let kept: Vec<&str> = text.lines().take(11).collect();
    std::fs::write(&summary, kept.join("\n") + "\n").unwrap();
    let calls = AtomicUsize::new(0);
    let req = BatchRequest {
        files: files.clone(),
        ..req
    };
    let report = batch::run(
        &req,
        |p: &Path| {
            calls.fetch_add(1, Ordering::SeqCst);
            analyse(p)
        },
        &|_| {},
    )
    .unwrap();
    assert_eq!(calls.load(Ordering::SeqCst), 30);
    assert_eq!((report.skipped, report.rows), (10, 40));
}

#[test]
fn bad_requests_are_errors() {
    let dir = tempfile::tempdir().unwrap();
    let e = batch::expand(&format!("{}/*.none", dir.path().display()))
        .unwrap_err()
        .to_string();
    assert!(e.contains("no file matches"), "{e}");
    let e = batch::expand(dir.path().to_str().unwrap())
        .unwrap_err()
        .to_string();
    assert!(e.contains("holds no files"), "{e}");
    // a summary that is not one
    let summary = dir.path().join("s.csv");
    std::fs::write(&summary, "a,b\n1,2\n").unwrap();
    let req = BatchRequest {
        files: vec![summary.clone()],
        summary: summary.clone(),
        threads: None,
        retry_errors: false,
        parquet: None,
    };
    let e = format!("{:#}", batch::run(&req, analyse, &|_| {}).unwrap_err());
    assert!(e.contains("s.csv:2") && e.contains("batch summary"), "{e}");
}

#[test]
fn identify_row_equals_the_identify_report() {
    // the bundled example: one recording, its feed as a flag
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
    let rec = root.join("examples/identify/cut_fz0.08.txt");
    let config = runout::Source::path(root.join("examples/identify/cut.toml"));
    let flags = || runout::io::config::Layer {
        origin: "command line".into(),
        values: [("fz_mm".to_string(), runout::io::config::Value::Number(0.08))].into(),
    };
    let row = batch::identify_row(runout::Source::path(&rec), Some(&config), flags()).unwrap();
    let req = runout::identify::resolve(Some(&config), flags(), vec![runout::Source::path(&rec)])
        .unwrap();
    let report = runout::identify::recordings(&req, &mut runout::NoProgress).unwrap();
    let v = serde_json::to_value(&report).unwrap();
    // the same job; the full-signal fit's sums run in rayon's order, which on several threads
    // changes the last digits from run to run (snapshots.rs): relative 1e-9
    let close = |a: Option<f64>, b: &serde_json::Value| {
        let (a, b) = (a.unwrap(), b.as_f64().unwrap());
        assert!((a - b).abs() <= 1e-9 * b.abs(), "{a} vs {b}");
    };
    close(row.offset_um, &v["full_signal"]["offset_um"]);
    close(row.angle_se_deg, &v["full_signal"]["angle_deg_se"]);
    close(
        row.kae_se_N_per_mm,
        &v["full_signal"]["coefficients"]["kae_N_per_mm_se"],
    );
    // the known runout of the example: 8 µm at −50° (examples/identify/README.md)
    assert!((row.offset_um.unwrap() - 8.0).abs() < 0.5, "{row:?}");
    assert!((row.angle_deg.unwrap() + 50.0).abs() < 5.0, "{row:?}");
    // a bad recording: an error naming it
    let bad = runout::Source::bytes("bad.txt", &b"Fx,Fy\n1,2\n"[..]);
    let e = batch::identify_row(bad, Some(&config), flags()).unwrap_err();
    let row = batch::finish_row("bad.txt", None, Err(e));
    assert_eq!(row.status, "error");
    assert!(row.error.contains("bad.txt"), "{}", row.error);
    assert_eq!(row.time, "");
}

/// The Parquet summary holds the CSV's rows (read back equal, field
/// for field: the floats are the same f64, written as DOUBLE), same columns in the same order,
/// numbers typed as DOUBLE with nulls where the CSV is empty, text as UTF-8; it is rewritten on a
/// resumed run, and the CSV alone is what a run resumes from.
#[test]
fn parquet_summary_equals_the_csv() {
    use runout::io::formats::parquet::{read_table, TableColumn};
    let dir = tempfile::tempdir().unwrap();
    let (files, bad) = make(dir.path(), 40);
    let summary = dir.path().join("s.csv");
    let parquet = batch::parquet_next_to(&summary);
    assert_eq!(parquet, dir.path().join("s.parquet"));
    let req = BatchRequest {
        files: files[..30].to_vec(),
        summary: summary.clone(),
        threads: Some(2),
        retry_errors: false,
        parquet: Some(parquet.clone()),
    };
    batch::run(&req, analyse, &|_| {}).unwrap();
    let rows = batch::read_summary(&summary).unwrap();
    assert_eq!(rows.len(), 30);
    assert_eq!(batch::read_summary_parquet(&parquet).unwrap(), rows);
    // typed columns, the CSV's order
    let table = read_table(&parquet).unwrap();
    let names: Vec<String> = table.iter().map(|(n, _)| n.clone()).collect();
    assert_eq!(names, batch::columns());
    for (name, col) in &table {
        let text = batch::TEXT_COLUMNS.contains(&name.as_str());
        assert_eq!(matches!(col, TableColumn::Text(_)), text, "{name}");
    }
    let (_, TableColumn::Float(ktc)) = &table[8] else {
        panic!("ktc is a float column")
    };
    assert_eq!(table[8].0, "ktc_N_per_mm2");
    assert!(
        ktc.iter().all(Option::is_none),
        "not given by the stand-in: null"
    );
    let (_, TableColumn::Float(offset)) = &table[4] else {
        panic!("offset is a float column")
    };
    let errors = rows.iter().filter(|r| r.status == "error").count();
    assert!(errors > 0);
    assert_eq!(offset.iter().filter(|x| x.is_none()).count(), errors);
    // resumed over all 40: the Parquet file is rewritten with every row; the CSV drives the skip
    let calls = AtomicUsize::new(0);
    let counted = |p: &Path| {
        calls.fetch_add(1, Ordering::SeqCst);
        analyse(p)
    };
    let all = BatchRequest {
        files: files.clone(),
        ..req.clone()
    };
    let report = batch::run(&all, counted, &|_| {}).unwrap();
    assert_eq!((report.skipped, report.analysed), (30, 10));
    assert_eq!(calls.load(Ordering::SeqCst), 10);
    let rows = batch::read_summary(&summary).unwrap();
    assert_eq!(rows.len(), 40);
    assert_eq!(
        rows.iter().filter(|r| r.status == "error").count(),
        bad,
        "every bad file a row"
    );
    assert_eq!(batch::read_summary_parquet(&parquet).unwrap(), rows);
    // no temporary file left next to them
    let left: Vec<_> = std::fs::read_dir(dir.path())
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().to_string())
        .filter(|n| n.ends_with(".tmp"))
        .collect();
    assert!(left.is_empty(), "{left:?}");
    // the same path for both is refused
    let same = BatchRequest {
        parquet: Some(summary.clone()),
        ..req
    };
    let e = format!("{:#}", batch::run(&same, analyse, &|_| {}).unwrap_err());
    assert!(e.contains("cannot be the CSV summary"), "{e}");
}
