//! `runout batch`: one analysis (the identify job) over many recordings, in parallel, into one
//! summary table.
//!
//! * **Inputs**: a folder (every regular, non-hidden file in it, sorted) or a glob pattern
//!   (`cuts/**/*.txt`), or explicit files — [`expand`].
//! * **Parallel, bounded memory**: a rayon pool of `threads` workers; each worker holds one
//!   recording's analysis at a time (the identify job streams its recording), and the finished
//!   rows (a few hundred bytes each) are written to the summary as they complete. Memory is
//!   `threads` × one analysis, whatever the number of files.
//! * **Continues past bad files**: a failed analysis is a row with `status = error` and the
//!   message; the run goes on.
//! * **Resumable**: files already in the summary (ok or error) are skipped; rows are appended and
//!   flushed one by one, so an interrupted run loses at most the analyses in flight. At the end the
//!   table is rewritten sorted by file (atomically: temporary file + rename).
//! * **Parquet**: the same table, same columns, typed (numbers as
//!   nullable `DOUBLE`, text as UTF-8), written atomically at the end next to the CSV
//!   ([`BatchRequest::parquet`], [`write_summary_parquet`]). The CSV stays the table a run resumes
//!   from.
//!
//! The analysis is a closure ([`run`]), so the framework is tested without a recording format;
//! `runout batch` plugs in the identify job.

#![allow(non_snake_case)] // field names carry their units, as the JSON and CSV columns do

use crate::job::Report;
use anyhow::{bail, Context, Result};
use rayon::prelude::*;
use schemars::JsonSchema;
use serde::{Deserialize, Serialize};
use std::collections::BTreeSet;
use std::path::{Path, PathBuf};
use std::sync::Mutex;
use std::time::Instant;

/// One row of the summary table (CSV columns in this order; empty cells for values not
/// available). Angles in degrees, offsets in µm, coefficients in N/mm² (cutting) and N/mm (edge).
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize, JsonSchema)]
pub struct Row {
    /// The recording, as given (path).
    pub file: String,
    /// `ok` or `error`.
    pub status: String,
    /// The error message (`status = error`), else empty.
    pub error: String,
    /// Time of the recording: from its header when the analysis finds one, else the file's
    /// modification time (UTC, RFC 3339).
    pub time: String,
    /// Runout offset ρ (µm) and its standard error.
    pub offset_um: Option<f64>,
    pub offset_se_um: Option<f64>,
    /// Runout angle λ (deg, from tooth 0 in the direction of rotation) and its standard error.
    pub angle_deg: Option<f64>,
    pub angle_se_deg: Option<f64>,
    /// Cutting coefficients K_tc, K_rc, K_ac (N/mm²) and their standard errors.
    pub ktc_N_per_mm2: Option<f64>,
    pub ktc_se_N_per_mm2: Option<f64>,
    pub krc_N_per_mm2: Option<f64>,
    pub krc_se_N_per_mm2: Option<f64>,
    pub kac_N_per_mm2: Option<f64>,
    pub kac_se_N_per_mm2: Option<f64>,
    /// Edge coefficients K_te, K_re, K_ae (N/mm) and their standard errors.
    pub kte_N_per_mm: Option<f64>,
    pub kte_se_N_per_mm: Option<f64>,
    pub kre_N_per_mm: Option<f64>,
    pub kre_se_N_per_mm: Option<f64>,
    pub kae_N_per_mm: Option<f64>,
    pub kae_se_N_per_mm: Option<f64>,
    /// Fit quality: coefficient of determination R² of the runout fit, RMS residual (N) and
    /// condition number of the fit.
    pub r_squared: Option<f64>,
    pub residual_rms_N: Option<f64>,
    pub condition: Option<f64>,
    /// The analysis's verdict (e.g. runout within tolerance), when it gives one.
    pub verdict: String,
}

/// A failed file.
#[derive(Debug, Clone, PartialEq, Serialize, JsonSchema)]
pub struct Failure {
    pub file: String,
    pub error: String,
}

/// `runout batch`: the files, the summary, the pool.
#[derive(Debug, Clone)]
pub struct BatchRequest {
    /// The recordings (see [`expand`]).
    pub files: Vec<PathBuf>,
    /// The summary table (CSV); read first to skip files already analysed.
    pub summary: PathBuf,
    /// Worker threads (default: rayon's, i.e. the number of cores or `RAYON_NUM_THREADS`).
    pub threads: Option<usize>,
    /// Analyse again the files whose row in the summary is an error.
    pub retry_errors: bool,
    /// Also write the final summary as Parquet to this file. [`parquet_next_to`] gives the usual
    /// name.
    pub parquet: Option<PathBuf>,
}

/// The Parquet summary next to the CSV one: `summary.csv` → `summary.parquet`.
pub fn parquet_next_to(summary: &Path) -> PathBuf {
    summary.with_extension("parquet")
}

/// `runout.batch/1`: what a batch run did.
#[derive(Debug, Clone, Serialize, JsonSchema)]
pub struct BatchReport {
    /// `runout.batch/1`
    #[schemars(extend("const" = "runout.batch/1"))]
    pub schema: String,
    pub summary: String,
    /// Files given.
    pub files: usize,
    /// Files skipped because the summary already had them.
    pub skipped: usize,
    /// Files analysed in this run.
    pub analysed: usize,
    /// Of those, analysed successfully.
    pub ok: usize,
    /// Of those, failed (each with its message), sorted by file.
    pub failed: Vec<Failure>,
    /// Rows in the summary after the run.
    pub rows: usize,
    pub threads: usize,
    pub elapsed_s: f64,
    /// `analysed / elapsed_s`.
    pub recordings_per_s: f64,
}

impl Report for BatchReport {
    const SCHEMA: &'static str = "runout.batch/1";
}

/// The files of `spec`: a folder (its regular, non-hidden files, sorted; not recursive), a
/// glob pattern (`*`, `?`, `[…]`, `**`; matches sorted), or one file. A pattern that matches
/// nothing, or an empty folder, is an error naming it.
pub fn expand(spec: &str) -> Result<Vec<PathBuf>> {
    let p = Path::new(spec);
    if p.is_dir() {
        let mut v = Vec::new();
        for e in std::fs::read_dir(p).with_context(|| format!("reading folder {spec}"))? {
            let e = e.with_context(|| format!("reading folder {spec}"))?;
            let hidden = e.file_name().to_string_lossy().starts_with('.');
            if !hidden && e.file_type().map(|t| t.is_file()).unwrap_or(false) {
                v.push(e.path());
            }
        }
        v.sort();
        if v.is_empty() {
            bail!("{spec}: the folder holds no files");
        }
        return Ok(v);
    }
    if p.is_file() {
        return Ok(vec![p.to_path_buf()]);
    }
    let mut v: Vec<PathBuf> = glob::glob(spec)
        .with_context(|| format!("pattern `{spec}`"))?
        .filter_map(|e| e.ok())
        .filter(|p| p.is_file())
        .collect();
    v.sort();
    if v.is_empty() {
        bail!("{spec}: no such file or folder, and no file matches it as a pattern");
    }
    Ok(v)
}

/// Rows of an existing summary (none if the file does not exist).
pub fn read_summary(path: &Path) -> Result<Vec<Row>> {
    if !path.exists() {
        return Ok(Vec::new());
    }
    let mut r = csv::Reader::from_path(path)
        .with_context(|| format!("reading the summary {}", path.display()))?;
    let mut rows = Vec::new();
    for (i, row) in r.deserialize::<Row>().enumerate() {
        rows.push(row.with_context(|| {
            format!(
                "{}:{}: not a row of a batch summary (delete or move the file to start afresh)",
                path.display(),
                i + 2
            )
        })?);
    }
    Ok(rows)
}

/// The summary's columns, in order (the CSV header).
pub fn columns() -> Vec<String> {
    let mut probe = csv::Writer::from_writer(Vec::new());
    probe.serialize(Row::default()).expect("a row serialises");
    let bytes = probe.into_inner().unwrap_or_default();
    let text = String::from_utf8_lossy(&bytes);
    let header = text.lines().next().unwrap_or_default();
    header.split(',').map(String::from).collect()
}

/// The summary's text columns (the others are numbers, empty when not available).
pub const TEXT_COLUMNS: [&str; 5] = ["file", "status", "error", "time", "verdict"];

/// Write `rows` as the summary CSV (header first).
pub fn write_summary(w: impl std::io::Write, rows: &[Row]) -> Result<()> {
    if rows.is_empty() {
        let mut w = w;
        writeln!(w, "{}", columns().join(","))?;
        w.flush()?;
        return Ok(());
    }
    let mut w = csv::Writer::from_writer(w);
    for r in rows {
        w.serialize(r)?;
    }
    w.flush()?;
    Ok(())
}

/// The summary as Parquet columns: the CSV's columns in the same order ([`columns`]), the
/// [`TEXT_COLUMNS`] as UTF-8 text, every other one as a nullable 64-bit float (null where the
/// CSV cell is empty).
pub fn summary_table(
    rows: &[Row],
) -> Result<Vec<(String, runout_io::formats::parquet::TableColumn)>> {
    use runout_io::formats::parquet::TableColumn;
    let values: Vec<serde_json::Map<String, serde_json::Value>> = rows
        .iter()
        .map(|r| match serde_json::to_value(r)? {
            serde_json::Value::Object(m) => Ok(m),
            _ => unreachable!("a row is a struct"),
        })
        .collect::<Result<_, serde_json::Error>>()?;
    let mut table = Vec::new();
    for name in columns() {
        let cell = |m: &serde_json::Map<String, serde_json::Value>| m.get(&name).cloned();
        let col = if TEXT_COLUMNS.contains(&name.as_str()) {
            TableColumn::Text(
                values
                    .iter()
                    .map(|m| {
                        cell(m)
                            .and_then(|v| v.as_str().map(String::from))
                            .unwrap_or_default()
                    })
                    .collect(),
            )
        } else {
            TableColumn::Float(
                values
                    .iter()
                    .map(|m| cell(m).and_then(|v| v.as_f64()))
                    .collect(),
            )
        };
        table.push((name, col));
    }
    Ok(table)
}

/// Write `rows` as the Parquet summary to `path`, atomically (temporary file + rename).
pub fn write_summary_parquet(path: &Path, rows: &[Row]) -> Result<()> {
    let table = summary_table(rows)?;
    let tmp = tmp_next_to(path);
    let out = std::fs::File::create(&tmp).with_context(|| format!("creating {}", tmp.display()))?;
    runout_io::formats::parquet::write_table(
        std::io::BufWriter::new(out),
        &table,
        &path.display().to_string(),
    )?;
    std::fs::rename(&tmp, path).with_context(|| format!("replacing {}", path.display()))?;
    Ok(())
}

/// The rows of a Parquet summary ([`write_summary_parquet`]).
pub fn read_summary_parquet(path: &Path) -> Result<Vec<Row>> {
    use runout_io::formats::parquet::TableColumn;
    let table = runout_io::formats::parquet::read_table(path)?;
    let want = columns();
    let names: Vec<&str> = table.iter().map(|(n, _)| n.as_str()).collect();
    if names != want {
        bail!(
            "{}: not a batch summary: columns {} (expected {})",
            path.display(),
            names.join(", "),
            want.join(", ")
        );
    }
    let n = match table.first() {
        Some((_, TableColumn::Text(v))) => v.len(),
        Some((_, TableColumn::Float(v))) => v.len(),
        None => 0,
    };
    let mut rows = Vec::with_capacity(n);
    for i in 0..n {
        let mut m = serde_json::Map::new();
        for (name, col) in &table {
            let v = match col {
                TableColumn::Text(v) => serde_json::Value::from(v[i].clone()),
                TableColumn::Float(v) => v[i].map_or(serde_json::Value::Null, Into::into),
            };
            m.insert(name.clone(), v);
        }
        rows.push(
            serde_json::from_value(serde_json::Value::Object(m))
                .with_context(|| format!("{}: row {}", path.display(), i + 1))?,
        );
    }
    Ok(rows)
}

/// The summary row of an identify report (`runout.identify.recording/1`, as JSON): ρ, λ and the
/// coefficients with their standard errors and the fit quality from the full-signal fit (the
/// seed-003 sine fit of the first recording when there is no full-signal fit), the recording's
/// date and time from its header when it states them, and as verdict `identified` or
/// `not identified: <parameter> (<reason>), … (<why the fit is not trusted>)` from the report's
/// status.
pub fn row_from_identify(report: &serde_json::Value) -> Row {
    let num = |v: &serde_json::Value, k: &str| v.get(k).and_then(serde_json::Value::as_f64);
    let mut row = Row::default();
    let full = report.get("full_signal").filter(|v| !v.is_null());
    if let Some(f) = full {
        row.offset_um = num(f, "offset_um");
        row.offset_se_um = num(f, "offset_um_se");
        row.angle_deg = num(f, "angle_deg");
        row.angle_se_deg = num(f, "angle_deg_se");
        row.r_squared = num(f, "r_squared");
        row.residual_rms_N = num(f, "residual_rms_N");
        row.condition = num(f, "condition");
        if let Some(c) = f.get("coefficients").filter(|v| !v.is_null()) {
            let k = |name: &str| (num(c, name), num(c, &format!("{name}_se")));
            (row.ktc_N_per_mm2, row.ktc_se_N_per_mm2) = k("ktc_N_per_mm2");
            (row.krc_N_per_mm2, row.krc_se_N_per_mm2) = k("krc_N_per_mm2");
            (row.kac_N_per_mm2, row.kac_se_N_per_mm2) = k("kac_N_per_mm2");
            (row.kte_N_per_mm, row.kte_se_N_per_mm) = k("kte_N_per_mm");
            (row.kre_N_per_mm, row.kre_se_N_per_mm) = k("kre_N_per_mm");
            (row.kae_N_per_mm, row.kae_se_N_per_mm) = k("kae_N_per_mm");
        }
    }
    let first = report
        .get("recordings")
        .and_then(|r| r.as_array())
        .and_then(|r| r.first());
    if full.is_none() {
        if let Some(sf) = first
            .and_then(|r| r.get("sine_fit"))
            .filter(|v| !v.is_null())
        {
            row.offset_um = num(sf, "offset_um");
            row.offset_se_um = num(sf, "offset_um_se").or(num(sf, "offset_se_um"));
            row.angle_deg = num(sf, "angle_deg");
            row.angle_se_deg = num(sf, "angle_deg_se").or(num(sf, "angle_se_deg"));
            row.r_squared = num(sf, "r_squared");
        }
    }
    // date/time stated in the header (DynoWare `Date`, `Time`, …)
    if let Some(meta) = first
        .and_then(|r| r.get("metadata"))
        .and_then(|m| m.as_array())
    {
        let mut parts = Vec::new();
        for kv in meta {
            let (Some(k), Some(v)) = (
                kv.get(0).and_then(|k| k.as_str()),
                kv.get(1).and_then(|v| v.as_str()),
            ) else {
                continue;
            };
            let key = k.to_ascii_lowercase();
            let key = key.trim();
            if [
                "date",
                "time",
                "datetime",
                "timestamp",
                "start time",
                "measuring date",
            ]
            .contains(&key)
            {
                parts.push(v.trim().to_string());
            }
        }
        row.time = parts.join(" ");
    }
    let mut missing = Vec::new();
    if let Some(ps) = report
        .get("status")
        .and_then(|s| s.get("parameters"))
        .and_then(|p| p.as_array())
    {
        for p in ps {
            let status = p.get("status").and_then(|s| s.as_str()).unwrap_or("");
            if status != "identified" {
                let name = p.get("parameter").and_then(|s| s.as_str()).unwrap_or("?");
                match p.get("reason").and_then(|s| s.as_str()) {
                    Some(r) => missing.push(format!("{name} ({r})")),
                    None => missing.push(name.to_string()),
                }
            }
        }
        let why: Vec<&str> = report
            .get("status")
            .and_then(|s| s.get("fit"))
            .and_then(|f| f.as_array())
            .map(|f| f.iter().filter_map(|x| x.as_str()).collect())
            .unwrap_or_default();
        row.verdict = if missing.is_empty() {
            "identified".into()
        } else if why.is_empty() {
            format!("not identified: {}", missing.join(", "))
        } else {
            format!(
                "not identified: {} ({})",
                missing.join(", "),
                why.join("; ")
            )
        };
    }
    row
}

/// The identify job on one recording as its summary row ([`row_from_identify`]). `config` and
/// `flags` as for [`crate::identify::resolve`] (the config's `fz_mm` is one value). `Err` for a
/// recording that cannot be identified; pass it to [`finish_row`] for the row.
///
/// Threads: called from a worker of a rayon pool (the in-process [`run`]), the job runs on a
/// pool of its own with one thread — a batch is parallel across recordings, and this keeps the
/// workers from sharing each other's pool. Called from any other thread (a Dask or Spark task,
/// a Python thread), it runs on rayon's global pool, exactly as `runout identify` does; with
/// `RAYON_NUM_THREADS=1` the full-signal fit then sums in a fixed order and the numbers equal
/// `RAYON_NUM_THREADS=1 runout identify RECORDING` (and `runout batch`) to the last digit.
pub fn identify_row(
    recording: crate::Source,
    config: Option<&crate::Source>,
    flags: runout_io::config::Layer,
) -> Result<Row> {
    let req = crate::identify::resolve(config, flags, vec![recording])?;
    let job = || crate::identify::recordings(&req, &mut crate::NoProgress);
    let report = if rayon::current_thread_index().is_some() {
        rayon::ThreadPoolBuilder::new()
            .num_threads(1)
            .build()
            .context("starting a worker thread")?
            .install(job)?
    } else {
        job()?
    };
    Ok(row_from_identify(&serde_json::to_value(&report)?))
}

fn mtime_utc(path: &Path) -> String {
    let Ok(t) = std::fs::metadata(path).and_then(|m| m.modified()) else {
        return String::new();
    };
    let Ok(d) = t.duration_since(std::time::UNIX_EPOCH) else {
        return String::new();
    };
    rfc3339(d.as_secs() as i64)
}

/// Seconds since 1970 as `YYYY-MM-DDThh:mm:ssZ` (proleptic Gregorian, UTC).
pub fn rfc3339(secs: i64) -> String {
    let days = secs.div_euclid(86_400);
    let s = secs.rem_euclid(86_400);
    // civil from days (H. Hinnant's algorithm)
    let z = days + 719_468;
    let era = z.div_euclid(146_097);
    let doe = z.rem_euclid(146_097);
    let yoe = (doe - doe / 1460 + doe / 36_524 - doe / 146_096) / 365;
    let y = yoe + era * 400;
    let doy = doe - (365 * yoe + yoe / 4 - yoe / 100);
    let mp = (5 * doy + 2) / 153;
    let d = doy - (153 * mp + 2) / 5 + 1;
    let m = if mp < 10 { mp + 3 } else { mp - 9 };
    let y = if m <= 2 { y + 1 } else { y };
    format!(
        "{y:04}-{m:02}-{d:02}T{:02}:{:02}:{:02}Z",
        s / 3600,
        s / 60 % 60,
        s % 60
    )
}

/// Run `analyse` on every file of `req` not yet in the summary, in parallel; append each row to
/// the summary as it completes; rewrite the summary sorted by file at the end. `analyse` returns
/// the measurements of a row (its `file`, `status` and `error` are set here, and `time` when it
/// leaves it empty); an `Err` becomes an error row with the message (the error and its causes).
/// `on_row` is called for every finished row (from the worker threads), e.g. for progress.
pub fn run<F>(req: &BatchRequest, analyse: F, on_row: &(dyn Fn(&Row) + Sync)) -> Result<BatchReport>
where
    F: Fn(&Path) -> Result<Row> + Sync,
{
    let start = Instant::now();
    if let Some(p) = &req.parquet {
        if p == &req.summary {
            bail!(
                "{}: the Parquet summary cannot be the CSV summary",
                p.display()
            );
        }
    }
    let mut existing = read_summary(&req.summary)?;
    if req.retry_errors {
        existing.retain(|r| r.status != "error");
    }
    let done: BTreeSet<&str> = existing.iter().map(|r| r.file.as_str()).collect();
    let mut todo: Vec<&PathBuf> = Vec::new();
    let mut seen = BTreeSet::new();
    for f in &req.files {
        let name = f.display().to_string();
        if !done.contains(name.as_str()) && seen.insert(name) {
            todo.push(f);
        }
    }
    let skipped = req.files.len() - todo.len();
    // the summary so far (rewritten when errors are retried), then rows appended as they finish
    let mut file = write_then_append(&req.summary, &existing)?;
    let pool = {
        let mut b = rayon::ThreadPoolBuilder::new();
        if let Some(n) = req.threads {
            if n == 0 {
                bail!("threads: expected at least 1, got 0");
            }
            b = b.num_threads(n);
        }
        b.build().context("starting the worker threads")?
    };
    let threads = pool.current_num_threads();
    let sink = Mutex::new((
        csv::WriterBuilder::new()
            .has_headers(false)
            .from_writer(&mut file),
        Vec::<Row>::with_capacity(todo.len()),
        None::<anyhow::Error>,
    ));
    pool.install(|| {
        todo.par_iter().with_max_len(1).for_each(|path| {
            let row = finish_row(&path.display().to_string(), Some(path), analyse(path));
            on_row(&row);
            let mut s = sink.lock().expect("not poisoned");
            let written = s.0.serialize(&row).and_then(|_| Ok(s.0.flush()?));
            if let Err(e) = written {
                s.2.get_or_insert(anyhow::Error::new(e).context(format!(
                    "appending to the summary {}",
                    req.summary.display()
                )));
            }
            s.1.push(row);
        })
    });
    let (w, new_rows, err) = sink.into_inner().expect("not poisoned");
    drop(w);
    if let Some(e) = err {
        return Err(e);
    }
    let elapsed_s = start.elapsed().as_secs_f64();
    let analysed = new_rows.len();
    let mut failed: Vec<Failure> = new_rows
        .iter()
        .filter(|r| r.status == "error")
        .map(|r| Failure {
            file: r.file.clone(),
            error: r.error.clone(),
        })
        .collect();
    failed.sort_by(|a, b| a.file.cmp(&b.file));
    let ok = analysed - failed.len();
    let mut all = existing;
    all.extend(new_rows);
    all.sort_by(|a, b| a.file.cmp(&b.file));
    // sorted, atomically: a crash here leaves the appended file, which resumes as well
    let tmp = tmp_next_to(&req.summary);
    let out = std::fs::File::create(&tmp).with_context(|| format!("creating {}", tmp.display()))?;
    write_summary(std::io::BufWriter::new(out), &all)
        .with_context(|| format!("writing {}", tmp.display()))?;
    std::fs::rename(&tmp, &req.summary)
        .with_context(|| format!("replacing {}", req.summary.display()))?;
    if let Some(p) = &req.parquet {
        write_summary_parquet(p, &all)?;
    }
    Ok(BatchReport {
        schema: BatchReport::SCHEMA.into(),
        summary: req.summary.display().to_string(),
        files: req.files.len(),
        skipped,
        analysed,
        ok,
        failed,
        rows: all.len(),
        threads,
        elapsed_s,
        recordings_per_s: if elapsed_s > 0.0 {
            analysed as f64 / elapsed_s
        } else {
            0.0
        },
    })
}

/// The summary row of one analysis: `file` = `name`, `status` ok or error, the error's message
/// (the error and its causes, as the CLI prints them), and `time` from the file's modification
/// time (UTC) when the analysis found none (empty for a recording in memory, `path` = `None`).
pub fn finish_row(name: &str, path: Option<&Path>, result: Result<Row>) -> Row {
    let mtime = || path.map(mtime_utc).unwrap_or_default();
    match result {
        Ok(mut r) => {
            r.file = name.into();
            r.status = "ok".into();
            r.error.clear();
            if r.time.is_empty() {
                r.time = mtime();
            }
            r
        }
        Err(e) => Row {
            file: name.into(),
            status: "error".into(),
            error: runout_io::report::chain_of(e.chain()),
            time: mtime(),
            ..Row::default()
        },
    }
}

fn tmp_next_to(path: &Path) -> PathBuf {
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().to_string())
        .unwrap_or_else(|| "summary.csv".into());
    path.with_file_name(format!(".{name}.{}.tmp", std::process::id()))
}

/// Write `rows` (with the header) to `path` and return it open for appending.
fn write_then_append(path: &Path, rows: &[Row]) -> Result<std::fs::File> {
    if let Some(dir) = path.parent().filter(|d| !d.as_os_str().is_empty()) {
        std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
    }
    let tmp = tmp_next_to(path);
    {
        let f =
            std::fs::File::create(&tmp).with_context(|| format!("creating {}", tmp.display()))?;
        write_summary(std::io::BufWriter::new(f), rows)
            .with_context(|| format!("writing {}", tmp.display()))?;
    }
    std::fs::rename(&tmp, path).with_context(|| format!("writing {}", path.display()))?;
    std::fs::OpenOptions::new()
        .append(true)
        .open(path)
        .with_context(|| format!("opening {}", path.display()))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_row_from_an_identify_report() {
        let report = serde_json::json!({
            "schema": "runout.identify.recording/1",
            "recordings": [{"metadata": [["Date", "2026-11-25"], ["Time", "07:10:00"], ["Noise", "2%"]],
                            "sine_fit": {"offset_um": 6.0, "angle_deg": 1.0}}],
            "full_signal": {"offset_um": 7.9, "offset_um_se": 0.1, "angle_deg": -49.8, "angle_deg_se": 1.2,
                            "coefficients": {"ktc_N_per_mm2": 1895.0, "ktc_N_per_mm2_se": 38.0,
                                             "kae_N_per_mm": -2.6, "kae_N_per_mm_se": 0.4},
                            "residual_rms_N": 1.8, "r_squared": 0.9996, "condition": 5.5},
            "status": {"parameters": [{"parameter": "offset", "status": "identified"},
                                      {"parameter": "angle", "status": "not identified", "reason": "K = 2"}]}
        });
        let r = row_from_identify(&report);
        assert_eq!((r.offset_um, r.offset_se_um), (Some(7.9), Some(0.1)));
        assert_eq!((r.angle_deg, r.angle_se_deg), (Some(-49.8), Some(1.2)));
        assert_eq!(
            (r.ktc_N_per_mm2, r.ktc_se_N_per_mm2),
            (Some(1895.0), Some(38.0))
        );
        assert_eq!((r.kae_N_per_mm, r.kae_se_N_per_mm), (Some(-2.6), Some(0.4)));
        assert_eq!(r.krc_N_per_mm2, None);
        assert_eq!(
            (r.r_squared, r.residual_rms_N, r.condition),
            (Some(0.9996), Some(1.8), Some(5.5))
        );
        assert_eq!(r.time, "2026-11-25 07:10:00");
        assert_eq!(r.verdict, "not identified: angle (K = 2)");
        // no full-signal fit: the sine fit
        let mut report = report;
        report["full_signal"] = serde_json::Value::Null;
        let r = row_from_identify(&report);
        assert_eq!(
            (r.offset_um, r.angle_deg, r.ktc_N_per_mm2),
            (Some(6.0), Some(1.0), None)
        );
    }

    #[test]
    fn columns_are_the_header() {
        let c = columns();
        assert_eq!(c.len(), 24);
        assert_eq!(&c[..4], ["file", "status", "error", "time"]);
        assert!(TEXT_COLUMNS.iter().all(|t| c.iter().any(|x| x == t)));
        let mut out = Vec::new();
        write_summary(&mut out, &[]).unwrap();
        assert_eq!(String::from_utf8(out).unwrap(), c.join(",") + "\n");
    }

    #[test]
    fn dates() {
        assert_eq!(rfc3339(0), "1970-01-01T00:00:00Z");
        assert_eq!(rfc3339(951_782_400), "2000-02-29T00:00:00Z");
        assert_eq!(rfc3339(1_795_568_461), "2026-11-25T01:01:01Z");
    }
}
