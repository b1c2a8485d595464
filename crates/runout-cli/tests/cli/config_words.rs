//! Issue 13 item 7: config words are closed vocabularies (serde enums), so an unknown word is an
//! error that names where it was set (the file and key, or the flag) and lists the accepted
//! words — for every command's words: `profile`, identify's `chain` and `peak_component`, chip's
//! `motion` and `spindle`, shank's `load_point` and `[[pair]] axis`. And `identify` takes the
//! cutter flags of every other command (`flags::CutterFlags`).

use std::path::Path;

use crate::common::*;

/// `runout ARGS` fails with status 1; its stderr.
fn error(args: &[&str]) -> String {
    let out = runout().args(args).output().unwrap();
    let err = String::from_utf8_lossy(&out.stderr).to_string();
    assert_eq!(out.status.code(), Some(1), "{args:?}: {err}");
    assert!(err.starts_with("error: "), "{err}");
    err
}

fn assert_all(err: &str, parts: &[&str]) {
    for p in parts {
        assert!(err.contains(p), "`{p}` missing in: {err}");
    }
}

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

const ID_REC: &str = "identify/cut_fz0.08.txt";
const ID_CFG: &str = "identify/cut.toml";

#[test]
fn identify_words_from_flags_and_files() {
    let (rec, cfg) = (example(ID_REC), example(ID_CFG));
    let base = ["identify", s(&rec), "--config", s(&cfg), "--fz-mm", "0.08"];
    // a flag: named as the flag (and its key), the accepted words listed
    let err = error(&[&base[..], &["--chain", "magic"]].concat());
    assert_all(
        &err,
        &[
            "--chain (key `chain`)",
            "`magic`",
            "`auto`, `rigid`, `modes`, `frf`, `band`",
        ],
    );
    let err = error(&[&base[..], &["--peak-component", "fq"]].concat());
    assert_all(
        &err,
        &["--peak-component", "`fq`", "`fxy`, `fx`, `fy`, `fz`"],
    );
    let err = error(&[&base[..], &["--profile", "round"]].concat());
    assert_all(
        &err,
        &[
            "--profile (key `profile`)",
            "`round`",
            "flat, ball, bull_nose, tapered",
        ],
    );
    // words are case-insensitive, as before
    let d = tempfile::tempdir().unwrap();
    let json = |extra: &[&str]| {
        let out = runout()
            .env("RAYON_NUM_THREADS", "1")
            .args([&base[..], extra, &["--chain", "rigid", "--json", "-"]].concat())
            .output()
            .unwrap();
        assert!(
            out.status.code() == Some(0) || out.status.code() == Some(3),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
        without_provenance(&String::from_utf8(out.stdout).unwrap())
    };
    assert_eq!(
        json(&["--peak-component", "FXY"]),
        json(&["--peak-component", "fxy"])
    );
    // a file: named with the key
    let bad = d.path().join("cut.toml");
    let text: String = std::fs::read_to_string(&cfg)
        .unwrap()
        .lines()
        .filter(|l| !l.starts_with("peak_component"))
        .map(|l| format!("{l}\n"))
        .collect::<String>()
        + "peak_component = \"fq\"\n";
    std::fs::write(&bad, text).unwrap();
    let err = error(&["identify", s(&rec), "--config", s(&bad), "--fz-mm", "0.08"]);
    assert_all(&err, &[s(&bad), "`peak_component`", "`fq`", "`fxy`, `fx`"]);
    // the plot format is a clap choice: refused by the parser (status 2) with the values
    let out = runout()
        .args([&base[..], &["--plot-format", "pdf"]].concat())
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(2));
    let err = String::from_utf8_lossy(&out.stderr);
    assert_all(&err, &["pdf", "svg", "png"]);
}

/// `identify` has the cutter flags of `simulate` (one set, `flags::CutterFlags`), and they reach
/// the one cutter resolver (a bad pitch is refused naming the flag).
#[test]
fn identify_takes_the_shared_cutter_flags() {
    let help = |cmd: &str| {
        let out = runout().args([cmd, "--help"]).output().unwrap();
        String::from_utf8(out.stdout).unwrap()
    };
    let (id, sim) = (help("identify"), help("simulate"));
    for flag in [
        "--teeth",
        "--diameter-mm",
        "--helix-deg",
        "--pitch-deg",
        "--flute-length-mm",
        "--profile",
        "--corner-radius-mm",
        "--taper-deg",
        "--flute-lead",
    ] {
        assert!(id.contains(flag), "identify --help lacks {flag}");
        assert!(sim.contains(flag), "simulate --help lacks {flag}");
    }
    let (rec, cfg) = (example(ID_REC), example(ID_CFG));
    let err = error(&[
        "identify",
        s(&rec),
        "--config",
        s(&cfg),
        "--fz-mm",
        "0.08",
        "--pitch-deg",
        "100,100,100,100",
    ]);
    assert_all(&err, &["--pitch-deg", "360"]);
}

#[test]
fn chip_words_name_the_file_and_key() {
    let d = tempfile::tempdir().unwrap();
    let text = std::fs::read_to_string(example("chip/section2_5.toml")).unwrap();
    for (key, from, to, accepted) in [
        (
            "motion",
            "motion = \"swing\"",
            "motion = \"orbit\"",
            "`straight`, `circular`, `swing`, `path`, `joints`",
        ),
        (
            "spindle",
            "rpm = 6000.0",
            "rpm = 6000.0\nspindle = \"left\"",
            "`cw` or `ccw`",
        ),
    ] {
        assert!(text.contains(from), "{from}");
        let bad = d.path().join(format!("{key}.toml"));
        std::fs::write(&bad, text.replacen(from, to, 1)).unwrap();
        let err = error(&["chip", "compare", s(&bad)]);
        assert_all(&err, &[s(&bad), &format!("`{key}`"), accepted]);
    }
}

#[test]
fn shank_words_name_the_file_line_and_key() {
    let d = tempfile::tempdir().unwrap();
    let text = std::fs::read_to_string(example("shank/shank.toml")).unwrap();
    for (key, from, to, accepted) in [
        (
            "load_point",
            "axial_depth_mm = 2",
            "axial_depth_mm = 2\nload_point = \"middle\"",
            "`tip` or `mid-depth`",
        ),
        ("axis", "axis = \"y\"", "axis = \"z\"", "`y`"),
    ] {
        let bad = d.path().join(format!("{key}.toml"));
        std::fs::write(&bad, text.replacen(from, to, 1)).unwrap();
        let err = error(&[
            "shank",
            "force",
            s(&example("shank/recording.csv")),
            "--config",
            s(&bad),
        ]);
        assert_all(&err, &[s(&bad), "line ", &format!("key `{key}`"), accepted]);
    }
    // upper-case axes are accepted, as before: the same output as lower case
    let upper = d.path().join("upper.toml");
    std::fs::write(&upper, text.replace("axis = \"x\"", "axis = \"X\"")).unwrap();
    let run = |cfg: &Path| {
        let out = runout()
            .args([
                "shank",
                "force",
                s(&example("shank/recording.csv")),
                "--config",
            ])
            .arg(cfg)
            .args(["--json", "-"])
            .output()
            .unwrap();
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
        without_provenance(&String::from_utf8(out.stdout).unwrap()).replace(s(cfg), "CONFIG")
    };
    assert_eq!(run(&upper), run(&example("shank/shank.toml")));
}
