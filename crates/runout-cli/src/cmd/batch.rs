//! `runout batch DIR|GLOB… --config cut.toml`: identify every recording on its own, in parallel,
//! into one summary table ([`runout::batch`]; docs/batch.md).

use anyhow::{bail, Context, Result};
use runout::batch::{self, BatchRequest, Row};
use std::io::Write;
use std::path::{Path, PathBuf};
use std::process::Command;

/// Arguments of `runout batch`.
#[derive(clap::Args, Debug)]
pub struct Args {
    /// Recordings: folders (their files, not recursive), glob patterns (quote them: `'cuts/*.txt'`,
    /// `'cuts/**/*.mat'`) or files.
    #[arg(required = true)]
    pub inputs: Vec<String>,
    /// Cut description (TOML, as for `runout identify`); `fz_mm` is one value for every recording.
    #[arg(long)]
    pub config: PathBuf,
    /// Summary table (CSV): read first (files already in it are skipped), rows appended as they
    /// finish, rewritten sorted by file at the end.
    #[arg(long, default_value = "runout-summary.csv")]
    pub summary: PathBuf,
    /// The summary also as Parquet (same columns; numbers as DOUBLE, text as UTF-8), written
    /// atomically at the end. Default: the summary's name with `.parquet`.
    #[arg(long, value_name = "FILE")]
    pub parquet: Option<PathBuf>,
    /// Worker threads (recordings analysed at once); default the number of cores.
    #[arg(long)]
    pub threads: Option<usize>,
    /// Analyse again the files whose row in the summary is an error.
    #[arg(long)]
    pub retry_errors: bool,
    /// The batch report (`runout.batch/1`: counts, failures, recordings/s) as JSON; `-` = stdout.
    #[arg(long)]
    pub json: Option<PathBuf>,
    /// Further `runout identify` flags for every recording, after `--` (e.g. `-- --axes "x = -Fy, y = -Fx, z = -Fz"`).
    #[arg(last = true, allow_hyphen_values = true)]
    pub identify_flags: Vec<String>,
}

/// The identify job on one recording, reduced to its summary row. Each recording runs in its
/// own `runout identify` process with one rayon thread: parallelism is across recordings (so a
/// recording's results do not depend on the thread count and equal a single `runout identify`
/// with `RAYON_NUM_THREADS=1` to the last digit), and a recording that exhausts memory or
/// crashes fails alone.
fn identify_row(exe: &Path, file: &Path, config: &Path, flags: &[String]) -> Result<Row> {
    let out = Command::new(exe)
        .arg("identify")
        .arg(file)
        .arg("--config")
        .arg(config)
        .args(flags)
        .args(["--json", "-"])
        .env("RAYON_NUM_THREADS", "1")
        .env("RUST_BACKTRACE", "0")
        .output()
        .with_context(|| format!("starting {}", exe.display()))?;
    // exit 3 = the report was written but the runout is not (fully) identified: a row with
    // its status, not a failure (crate::exit)
    let wrote_report =
        out.status.success() || out.status.code() == Some(i32::from(crate::exit::NOT_IDENTIFIED));
    if !wrote_report {
        let err = String::from_utf8_lossy(&out.stderr);
        let msg = err.trim().strip_prefix("error: ").unwrap_or(err.trim());
        bail!(
            "{}",
            if msg.is_empty() {
                "identify failed"
            } else {
                msg
            }
        );
    }
    let report: serde_json::Value = serde_json::from_slice(&out.stdout)
        .with_context(|| format!("{}: the identify report is not JSON", file.display()))?;
    Ok(batch::row_from_identify(&report))
}

pub fn run(a: Args) -> Result<()> {
    if !a.config.is_file() {
        bail!("--config {}: no such file", a.config.display());
    }
    let mut files = Vec::new();
    for spec in &a.inputs {
        files.extend(batch::expand(spec)?);
    }
    let parquet = Some(
        a.parquet
            .clone()
            .unwrap_or_else(|| batch::parquet_next_to(&a.summary)),
    );
    for out in [Some(&a.summary), a.json.as_ref(), parquet.as_ref()]
        .into_iter()
        .flatten()
    {
        if files.iter().any(|f| crate::output::same_file(out, f))
            || crate::output::same_file(out, &a.config)
        {
            bail!("refusing to write {}: it is an input", out.display());
        }
    }
    let exe = std::env::current_exe().context("finding the runout program")?;
    let req = BatchRequest {
        files,
        summary: a.summary.clone(),
        threads: a.threads,
        retry_errors: a.retry_errors,
        parquet,
    };
    // one step per recording (hidden when stderr is not a terminal, and with --quiet)
    let bar = if crate::progress::quiet() {
        indicatif::ProgressBar::hidden()
    } else {
        indicatif::ProgressBar::new(req.files.len() as u64)
    };
    let report = batch::run(
        &req,
        |p: &Path| identify_row(&exe, p, &a.config, &a.identify_flags),
        &|_| bar.inc(1),
    )?;
    bar.finish_and_clear();
    let json_on_stdout = a.json.as_deref() == Some(Path::new("-"));
    if let Some(j) = &a.json {
        crate::output::write_text(j, &runout::to_json(&report)?)?;
    }
    if !json_on_stdout {
        let mut o = std::io::stdout().lock();
        writeln!(
            o,
            "{} files: {} analysed ({} ok, {} failed), {} already in the summary; {} rows in {}",
            report.files,
            report.analysed,
            report.ok,
            report.failed.len(),
            report.skipped,
            report.rows,
            report.summary
        )?;
        writeln!(
            o,
            "{:.2} recordings/s on {} threads ({:.1} s)",
            report.recordings_per_s, report.threads, report.elapsed_s
        )?;
        for f in &report.failed {
            writeln!(o, "failed: {}: {}", f.file, f.error)?;
        }
    }
    Ok(())
}
