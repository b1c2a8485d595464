//! `runout identify RECORDING… --config cut.toml`: runout and coefficients from force
//! recordings (see [`recording`]). Subcommands:
//! `peaks` (seed 003 sine fit of one per-tooth peak table) and `tests` (several tests from a
//! CSV/TOML table: per-test fits, regressions, K_T/K_R, pooled edge-aware fit).

pub mod peaks;
mod plots;
pub mod recording;
pub mod tests;

use anyhow::Result;

/// Arguments of `runout identify`: recordings (the main job), or a subcommand working on
/// peak tables.
#[derive(clap::Args, Debug)]
#[command(args_conflicts_with_subcommands = true, subcommand_negates_reqs = true)]
pub struct Args {
    #[command(subcommand)]
    pub command: Option<Command>,
    #[command(flatten)]
    pub recording: recording::RecordingArgs,
}

/// `runout identify` subcommands.
#[derive(clap::Subcommand, Debug)]
pub enum Command {
    /// Runout from one set of per-tooth peak forces (seed 003 sine fit, methods.md §4.2).
    Peaks(peaks::Args),
    /// Several peak tests from a CSV or TOML table: per-test fits, regressions of A on a_p and C
    /// on f_z·a_p, K_T/K_R (seed eq. 17), pooled edge-force-aware fit (methods.md §4.6).
    Tests(tests::Args),
}

pub fn run(a: Args) -> Result<()> {
    match a.command {
        Some(Command::Peaks(p)) => peaks::run(p),
        Some(Command::Tests(t)) => tests::run(t),
        None => {
            crate::output::check_distinct(&a.recording.recordings, "recordings")?;
            recording::run(a.recording)
        }
    }
}

/// Write the JSON (`-` = stdout) and print the text unless the JSON went to stdout.
fn emit<R: runout::Report>(
    json: Option<&std::path::Path>,
    report: &R,
    text: impl FnOnce() -> String,
) -> Result<()> {
    if let Some(p) = json {
        crate::output::write_text(p, &runout::to_json(report)?)?;
    }
    if json != Some(std::path::Path::new("-")) {
        print!("{}", text());
    }
    Ok(())
}
