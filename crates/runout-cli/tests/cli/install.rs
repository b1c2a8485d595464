//! Install and try (issue 21 item 8): `runout --version`, shell completions and man pages generated
//! from the command-line definition. (`cargo install --path crates/runout-cli` itself is run by
//! `.ci/run`.)

use std::process::Command;

fn runout(args: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_runout"))
        .args(args)
        .output()
        .unwrap()
}

#[test]
fn version_names_the_package_version() {
    let out = runout(&["--version"]);
    assert!(out.status.success());
    assert_eq!(
        String::from_utf8_lossy(&out.stdout).trim(),
        format!("runout {}", env!("CARGO_PKG_VERSION"))
    );
}

#[test]
fn completions_cover_every_subcommand_and_flag() {
    for shell in ["bash", "zsh", "fish", "elvish", "powershell"] {
        let out = runout(&["completions", shell]);
        assert!(out.status.success(), "{shell}");
        let script = String::from_utf8_lossy(&out.stdout);
        for word in [
            "identify",
            "displacement",
            "shank",
            "grind",
            "chip",
            "simulate",
            "tooth0-angle-deg",
        ] {
            assert!(script.contains(word), "{shell} completions lack `{word}`");
        }
    }
    let out = runout(&["completions", "tcsh"]);
    assert!(!out.status.success());
    assert!(String::from_utf8_lossy(&out.stderr).contains("possible values"));
}

#[test]
fn man_pages_one_per_command_with_the_flags_and_units() {
    let dir = tempfile::tempdir().unwrap();
    let out = runout(&["man", "--dir", dir.path().to_str().unwrap()]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    for page in [
        "runout.1",
        "runout-identify.1",
        "runout-shank-force.1",
        "runout-displacement-signal.1",
    ] {
        assert!(dir.path().join(page).is_file(), "{page} missing");
    }
    let identify = std::fs::read_to_string(dir.path().join("runout-identify.1")).unwrap();
    assert!(identify.contains(r"\-\-diameter\-mm"), "{identify}");
    assert!(identify.contains("(mm)"), "units in the man page");
    let out = runout(&["man"]);
    assert!(String::from_utf8_lossy(&out.stdout).contains(".TH runout 1"));
}
