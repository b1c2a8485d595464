//! `runout inspect FILE`: what a recording holds — channels (variables, TDMS channels, HDF5
//! datasets, Parquet columns), units, lengths, sample rates — for every supported format
//! (issue 16 item 4). Flags → [`runout::inspect`] → JSON or a table.

use anyhow::Result;
use runout::inspect::{inspect, render, InspectRequest};
use runout::Source;
use std::path::PathBuf;

/// Arguments of `runout inspect`.
#[derive(clap::Args, Debug)]
pub struct Args {
    /// A recording of any supported format (detected by content): DynoWare/CSV/TSV text, MATLAB
    /// .mat (v5, v7.3), NI TDMS, HDF5, Parquet.
    #[arg(value_name = "FILE")]
    pub file: PathBuf,
    /// Sample rate (Hz), for a text recording with neither a time column nor a sampling-rate line.
    #[arg(long)]
    pub sample_rate_hz: Option<f64>,
    /// Print JSON (schema runout.inspect/2, to stdout) instead of a table.
    #[arg(long)]
    pub json: bool,
}

/// Run `runout inspect`.
pub fn run(a: Args) -> Result<()> {
    let report = inspect(&InspectRequest {
        recording: Source::path(&a.file),
        sample_rate_hz: a.sample_rate_hz,
    })?;
    if a.json {
        print!("{}", crate::provenance::stamped_json(&report)?);
    } else {
        print!("{}", render::text(&report));
    }
    Ok(())
}
