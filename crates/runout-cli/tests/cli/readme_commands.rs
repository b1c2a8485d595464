//! Every command line shown to users runs (issue 21 item 8): the ```sh blocks of `README.md`,
//! `examples/README.md` and `examples/*/README.md` are executed with `bash -euo pipefail` in a copy of
//! `examples/` (so nothing in the repository is overwritten), with `runout` on the PATH being the
//! binary under test (`cargo run --release -p runout-cli --` is the same program).
//!
//! A block runs only if each of its commands is a `runout` call (or a shell loop around one); the
//! blocks that are not (`cargo test`, fuzzing, `pip install` …) must be listed in [`NOT_RUN`] with
//! the reason, so no command line is skipped silently.

use std::fs;
use std::path::{Path, PathBuf};
use std::process::Command;

/// Blocks that are shown but not run here, by their first command, with why.
const NOT_RUN: &[(&str, &str)] = &[
    ("cargo test", "the test command itself (CI runs it)"),
    (
        "cargo install cargo-fuzz",
        "fuzzing needs nightly and minutes",
    ),
    ("cargo install --path", "installing is tested by .ci/run"),
    (
        "pip install",
        "the Python package is tested by .ci/run's pytest step",
    ),
    (
        "python3",
        "Python scripts are run by .ci/run's ignored tests",
    ),
    (
        "maturin",
        "the Python package is tested by .ci/run's pytest step",
    ),
];

fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

/// The ```sh blocks of one markdown file, with the line of each block's first command.
fn sh_blocks(path: &Path) -> Vec<(usize, String)> {
    let text = fs::read_to_string(path).unwrap();
    let mut blocks = Vec::new();
    let mut current: Option<(usize, String)> = None;
    for (i, line) in text.lines().enumerate() {
        let fence = line.trim_start().starts_with("```");
        match (&mut current, fence) {
            (None, true) if line.trim() == "```sh" || line.trim() == "```bash" => {
                current = Some((i + 2, String::new()))
            }
            (Some(_), true) => blocks.push(current.take().unwrap()),
            (Some((_, body)), false) => {
                body.push_str(line);
                body.push('\n');
            }
            _ => {}
        }
    }
    blocks
}

/// The commands of a block: continuation lines joined, comments and blank lines dropped.
fn commands(block: &str) -> Vec<String> {
    let mut out = Vec::new();
    let mut acc = String::new();
    for line in block.lines() {
        let line = line.trim();
        if acc.is_empty() && (line.is_empty() || line.starts_with('#')) {
            continue;
        }
        if let Some(head) = line.strip_suffix('\\') {
            acc.push_str(head);
            acc.push(' ');
        } else {
            acc.push_str(line);
            out.push(std::mem::take(&mut acc));
        }
    }
    out
}

fn is_runout_call(cmd: &str) -> bool {
    let cmd = cmd.trim_start_matches("do ").trim();
    cmd.starts_with("runout ")
        || cmd.starts_with("cargo run --release -p runout-cli -- ")
        || cmd.starts_with("for ")
        || cmd == "done"
}

fn copy_dir(from: &Path, to: &Path) {
    fs::create_dir_all(to).unwrap();
    for entry in fs::read_dir(from).unwrap() {
        let entry = entry.unwrap();
        let target = to.join(entry.file_name());
        if entry.file_type().unwrap().is_dir() {
            copy_dir(&entry.path(), &target);
        } else {
            fs::copy(entry.path(), target).unwrap();
        }
    }
}

fn markdown_files() -> Vec<PathBuf> {
    let root = root();
    let mut files = vec![root.join("README.md"), root.join("examples/README.md")];
    let mut dirs: Vec<PathBuf> = fs::read_dir(root.join("examples"))
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.join("README.md").is_file())
        .collect();
    dirs.sort();
    files.extend(dirs.into_iter().map(|d| d.join("README.md")));
    files
}

#[test]
fn every_command_line_in_the_readmes_runs() {
    let work = tempfile::tempdir().unwrap();
    copy_dir(&root().join("examples"), &work.path().join("examples"));
    let bin = work.path().join("bin");
    fs::create_dir_all(&bin).unwrap();
    std::os::unix::fs::symlink(env!("CARGO_BIN_EXE_runout"), bin.join("runout")).unwrap();
    let path = format!("{}:{}", bin.display(), std::env::var("PATH").unwrap());

    let (mut ran, mut failures) = (Vec::new(), Vec::new());
    for file in markdown_files() {
        let name = file.strip_prefix(root()).unwrap().display().to_string();
        let name = name.trim_start_matches("/").to_string();
        for (line, block) in sh_blocks(&file) {
            let cmds = commands(&block);
            if cmds.iter().all(|c| is_runout_call(c)) {
                let script = block.replace("cargo run --release -p runout-cli --", "runout");
                let out = Command::new("bash")
                    .args(["-euo", "pipefail", "-c", &script])
                    .current_dir(work.path())
                    .env("PATH", &path)
                    .output()
                    .unwrap();
                // issue 21 item 4: what users read has no words from the code
                let said = format!(
                    "{}{}",
                    String::from_utf8_lossy(&out.stdout),
                    String::from_utf8_lossy(&out.stderr)
                );
                for token in ["::", "Some(", "Ok(", "Err("] {
                    if said.contains(token) {
                        failures.push(format!("{name}:{line}: output contains `{token}`"));
                    }
                }
                if !out.status.success() {
                    failures.push(format!(
                        "{name}:{line}: exit {:?}\n{script}\n{}",
                        out.status.code(),
                        String::from_utf8_lossy(&out.stderr)
                    ));
                }
                ran.push(format!("{name}:{line}"));
            } else {
                let first = cmds.first().map(String::as_str).unwrap_or("");
                assert!(
                    NOT_RUN.iter().any(|(p, _)| first.starts_with(p)),
                    "{name}:{line}: a ```sh block that is neither a runout call nor listed in NOT_RUN:\n{block}\n\
                     (make it runnable, mark it ```text if it is only illustrative, or list it with a reason)"
                );
            }
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n\n"));
    // the main job, and at least one block per examples README
    assert!(ran.iter().any(|b| b.starts_with("README.md")), "{ran:?}");
    for file in markdown_files().iter().skip(1) {
        let name = file.strip_prefix(root()).unwrap().display().to_string();
        let name = name.trim_start_matches('/');
        assert!(
            ran.iter().any(|b| b.starts_with(name)),
            "no command of {name} ran: {ran:?}"
        );
    }
    // the README's main job wrote what it promises
    assert!(work.path().join("identify.json").is_file());
    assert!(work.path().join("plots").is_dir());
}

/// The bundled identify example recordings are what the command in its README makes (values; the
/// regenerated files are compared line by line, header included).
#[test]
fn identify_example_recordings_are_reproducible() {
    let readme = root().join("examples/identify/README.md");
    let (_, block) = sh_blocks(&readme)
        .into_iter()
        .find(|(_, b)| b.contains("runout simulate"))
        .expect("examples/identify/README.md shows how the recordings were made");
    let work = tempfile::tempdir().unwrap();
    fs::create_dir_all(work.path().join("examples/identify")).unwrap();
    let bin = work.path().join("bin");
    fs::create_dir_all(&bin).unwrap();
    std::os::unix::fs::symlink(env!("CARGO_BIN_EXE_runout"), bin.join("runout")).unwrap();
    let path = format!("{}:{}", bin.display(), std::env::var("PATH").unwrap());
    let out = Command::new("bash")
        .args(["-euo", "pipefail", "-c", &block])
        .current_dir(work.path())
        .env("PATH", &path)
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    for name in ["cut_fz0.05.txt", "cut_fz0.08.txt"] {
        let made = fs::read_to_string(work.path().join("examples/identify").join(name)).unwrap();
        let shipped = fs::read_to_string(root().join("examples/identify").join(name)).unwrap();
        let diff: Vec<(usize, &str, &str)> = made
            .lines()
            .zip(shipped.lines())
            .enumerate()
            .filter(|(_, (a, b))| a != b)
            .map(|(i, (a, b))| (i + 1, a, b))
            .take(3)
            .collect();
        assert!(
            diff.is_empty() && made.lines().count() == shipped.lines().count(),
            "{name}: regenerated file differs from the shipped one (line, made, shipped): {diff:?}"
        );
    }
}
