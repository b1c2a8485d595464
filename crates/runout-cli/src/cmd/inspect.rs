//! `runout inspect FILE`: what a recording holds — channels (variables, TDMS channels, HDF5
//! datasets, Parquet columns), units, lengths, sample rates — for every supported format
//! (issue 16 item 4).

use anyhow::Result;
use runout_io::formats::{inspect, split_selector};
use runout_io::recording::ReadOptions;
use std::path::PathBuf;

/// Arguments of `runout inspect`.
#[derive(clap::Args, Debug)]
pub struct Args {
    /// A recording of any supported format (detected by content): DynoWare/CSV/TSV text, MATLAB
    /// .mat (v5, v7.3), NI TDMS, HDF5, Parquet (with the `parquet` build feature).
    #[arg(value_name = "FILE")]
    pub file: PathBuf,
    /// Sample rate (Hz), for a text recording with neither a time column nor a sampling-rate line.
    #[arg(long)]
    pub sample_rate_hz: Option<f64>,
    /// Print JSON (to stdout) instead of a table.
    #[arg(long)]
    pub json: bool,
}

/// Run `runout inspect`.
pub fn run(a: Args) -> Result<()> {
    let (path, _) = split_selector(&a.file);
    let mut o = ReadOptions::new();
    o.sample_rate_hz = a.sample_rate_hz;
    let c = inspect(&path, &o)?;
    if a.json {
        println!(
            "{}",
            serde_json::to_string_pretty(&serde_json::json!({
                "file": path.display().to_string(),
                "format": c.format,
                "entries": c.entries,
                "metadata": c.metadata,
            }))?
        );
        return Ok(());
    }
    println!("{}: {:?}", path.display(), c.format);
    println!(
        "{:<32} {:>10} {:<22} {:<8} {:>12} {:>10}  note",
        "name", "samples", "type", "unit", "rate_Hz", "start_s"
    );
    for e in &c.entries {
        let opt = |v: Option<f64>| v.map_or("-".to_string(), |x| format!("{x}"));
        println!(
            "{:<32} {:>10} {:<22} {:<8} {:>12} {:>10}  {}",
            e.name,
            e.len,
            e.dtype,
            e.unit.as_deref().unwrap_or("-"),
            opt(e.sample_rate_hz),
            opt(e.start_time_s),
            match (e.scalar, &e.note) {
                (Some(v), _) => format!("value {v}"),
                (None, Some(n)) => n.clone(),
                _ => String::new(),
            }
        );
    }
    for (k, v) in &c.metadata {
        println!("# {k}: {v}");
    }
    Ok(())
}
