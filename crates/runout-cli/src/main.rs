//! `runout`: command-line program for cutter runout in milling. A thin layer over `runout-core`
//! (model and methods) and `runout-io` (formats): parse arguments, read, call, write.
// The flags' doc comments are clap's `--help` text, written for a terminal: `[[case]]`,
// `x,y[,z]` and `h_<model>_mm` are what the user types or reads, not rustdoc links or HTML.
#![allow(rustdoc::broken_intra_doc_links, rustdoc::invalid_html_tags)]

mod cmd;
mod exit;
mod flags;
mod output;
mod progress;
mod provenance;

use clap::{Parser, Subcommand};
use std::process::ExitCode;

/// Cutter runout in milling: simulate, identify, compensate.
///
/// Units: lengths mm (runout µm), forces N, time s, angles deg, speed rpm. Conventions:
/// docs/conventions.md (teeth in cutting order, runout angle from tooth 0 in the
/// direction of rotation, forces acting on the workpiece).
#[derive(Parser, Debug)]
#[command(name = "runout", version, about, long_about = None, after_help = exit::HELP)]
struct Cli {
    /// No progress bars or spinners and no warnings on stderr (errors only); the warnings stay
    /// in the report (text and JSON).
    #[arg(long, short = 'q', global = true)]
    quiet: bool,
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand, Debug)]
#[allow(clippy::large_enum_variant)] // argument structs, parsed once
enum Command {
    /// Simulate milling forces with runout (mechanistic model, helical cutter in axial disks).
    Simulate(cmd::simulate::Args),
    /// Identify runout (and cutting coefficients) from measured forces.
    Identify(cmd::identify::Args),
    /// Runout identified in position from displacement readings: per-tooth readings, runout at
    /// several heights, or a raw signal (methods.md §1).
    Displacement(cmd::displacement::Args),
    /// Chip thickness with runout (exact, arc, equivalent models; 3-axis and 5-axis toolpaths).
    Chip(cmd::chip::Args),
    /// Tool grinding: compensate the bar clamping error (probe grid → wheel path / NC program).
    Grind(cmd::grind::Args),
    /// Cutting force and runout from two-point shank deflection (capacitive sensors).
    Shank(cmd::shank::Args),
    /// Identify many recordings (folder or glob) in parallel into one summary table; resumable.
    Batch(cmd::batch::Args),
    /// What a recording holds (.mat, TDMS, HDF5, Parquet, CSV): channels, units, lengths, rates.
    Inspect(cmd::inspect::Args),
    /// Shell completions (bash, zsh, fish, elvish, powershell) to stdout.
    Completions(cmd::install::CompletionsArgs),
    /// Man pages generated from this program's options.
    Man(cmd::install::ManArgs),
    /// Render saved JSON reports as one self-contained HTML page (verdict, comparison table).
    Report(cmd::report::Args),
}

/// Status of a command whose standard output was closed early (`runout … | head -1`), as a
/// shell reports a program ended by SIGPIPE.
const BROKEN_PIPE_STATUS: u8 = 141;

/// A closed standard output ends the program quietly: the files finished so far are complete and
/// are kept ([`output::commit_all`]), nothing more is written, status 141. `println!` reports a
/// closed pipe by panicking; this hook turns that panic into the quiet end (every other panic
/// keeps the default report).
fn quiet_on_broken_pipe() {
    let default_hook = std::panic::take_hook();
    std::panic::set_hook(Box::new(move |info| {
        let p = info.payload();
        let msg = p
            .downcast_ref::<String>()
            .map(String::as_str)
            .or_else(|| p.downcast_ref::<&str>().copied())
            .unwrap_or("");
        if msg.starts_with("failed printing to stdout") && msg.contains("Broken pipe") {
            let _ = output::commit_all();
            std::process::exit(i32::from(BROKEN_PIPE_STATUS));
        }
        default_hook(info);
    }));
}

/// True if the error is a write to a closed pipe (ends quietly).
fn is_broken_pipe(e: &anyhow::Error) -> bool {
    e.chain().any(|c| {
        c.downcast_ref::<std::io::Error>()
            .is_some_and(|io| io.kind() == std::io::ErrorKind::BrokenPipe)
    })
}

fn main() -> ExitCode {
    quiet_on_broken_pipe();
    // SAFETY: text recordings are mapped instead of read (issue 18: one copy of the file less);
    // a recording shortened while it is read is reported as an error by the reader's SIGBUS
    // guard. One rewritten in place while it is read would be a mixed file either way, as a
    // read of it would be.
    unsafe { runout_io::mapped::allow_mapped_files() };
    let cli = Cli::parse();
    progress::set_quiet(cli.quiet);
    // the program by its name, not the path it was started from (the same on every machine)
    let args: Vec<String> = std::env::args()
        .enumerate()
        .map(|(i, a)| if i == 0 { "runout".to_string() } else { a })
        .collect();
    provenance::start(args);
    let result = match cli.command {
        Command::Simulate(a) => cmd::simulate::run(a),
        Command::Identify(a) => cmd::identify::run(a),
        Command::Displacement(a) => cmd::displacement::run(a),
        Command::Chip(a) => cmd::chip::run(a),
        Command::Grind(a) => cmd::grind::run(a),
        Command::Shank(a) => cmd::shank::run(a),
        Command::Inspect(a) => cmd::inspect::run(a),
        Command::Completions(a) => {
            cmd::install::completions(a, <Cli as clap::CommandFactory>::command())
        }
        Command::Man(a) => cmd::install::man(a, <Cli as clap::CommandFactory>::command()),
        Command::Batch(a) => cmd::batch::run(a),
        Command::Report(a) => cmd::report::run(a),
    };
    // outputs appear only when the whole command succeeded (or only its stdout was cut short)
    let result = match result {
        Ok(()) => output::commit_all(),
        Err(e) if is_broken_pipe(&e) => {
            let _ = output::commit_all();
            return ExitCode::from(BROKEN_PIPE_STATUS);
        }
        Err(e) => {
            output::discard_all();
            Err(e)
        }
    };
    match result {
        Ok(()) if exit::is_not_identified() => ExitCode::from(exit::NOT_IDENTIFIED),
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            progress::to_stderr(&format!("error: {}", error_message(&e)));
            ExitCode::from(exit::INPUT_ERROR)
        }
    }
}

/// The error and its causes, each printed once ([`runout_io::report::chain_of`]); an error that
/// names a flag ends with where the flags are described (`see \`runout identify --help\``).
fn error_message(e: &anyhow::Error) -> String {
    let mut m = runout_io::report::chain_of(e.chain());
    let names_flag = m
        .split("--")
        .skip(1)
        .any(|rest| rest.starts_with(|c: char| c.is_ascii_lowercase()));
    if names_flag && !m.contains("--help") {
        m.push_str(&format!("\n  (see `{} --help`)", command_path()));
    }
    m
}

/// `runout identify peaks`: the program and the subcommands given on the command line.
fn command_path() -> String {
    use clap::CommandFactory;
    let mut cmd = Cli::command();
    let mut path = vec!["runout".to_string()];
    for a in std::env::args().skip(1) {
        let Some(sub) = cmd.find_subcommand(&a).cloned() else {
            break;
        };
        path.push(a);
        cmd = sub;
    }
    path.join(" ")
}

#[cfg(test)]
mod tests {
    use super::Cli;
    use clap::CommandFactory;

    #[test]
    fn command_line_definition_is_consistent() {
        Cli::command().debug_assert();
    }
}
