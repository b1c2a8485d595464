//! `runout completions SHELL` and `runout man`: shell completions and a man page generated from
//! the command-line definition itself (clap_complete, clap_mangen), so they never drift from it.

use anyhow::Result;
use std::io::Write;
use std::path::PathBuf;

/// Arguments of `runout completions`.
#[derive(clap::Args, Debug)]
pub struct CompletionsArgs {
    /// Shell to write completions for (to stdout), e.g. `runout completions bash >
    /// ~/.local/share/bash-completion/completions/runout`.
    #[arg(value_enum)]
    pub shell: clap_complete::Shell,
}

/// Arguments of `runout man`.
#[derive(clap::Args, Debug)]
pub struct ManArgs {
    /// Directory to write the man pages into (`runout.1` and one page per subcommand, e.g.
    /// `runout-identify.1`); without it, `runout.1` goes to stdout.
    #[arg(long)]
    pub dir: Option<PathBuf>,
}

/// Writes the completion script of `shell` for `cmd` to stdout.
pub fn completions(args: CompletionsArgs, mut cmd: clap::Command) -> Result<()> {
    // generated into memory first: clap_complete panics on a write error (a closed pipe), while
    // `write_all` reports it (main ends quietly on a closed pipe)
    let mut script = Vec::new();
    clap_complete::generate(args.shell, &mut cmd, "runout", &mut script);
    let mut out = std::io::stdout().lock();
    out.write_all(&script)?;
    out.flush()?;
    Ok(())
}

/// Writes the man page(s) of `cmd`.
pub fn man(args: ManArgs, cmd: clap::Command) -> Result<()> {
    match args.dir {
        Some(dir) => {
            std::fs::create_dir_all(&dir).map_err(|e| {
                anyhow::anyhow!(
                    "cannot create the man page directory {}: {e}",
                    dir.display()
                )
            })?;
            clap_mangen::generate_to(cmd, &dir).map_err(|e| {
                anyhow::anyhow!("cannot write the man pages into {}: {e}", dir.display())
            })?;
        }
        None => {
            let mut out = std::io::stdout().lock();
            clap_mangen::Man::new(cmd).render(&mut out)?;
            out.flush()?;
        }
    }
    Ok(())
}
