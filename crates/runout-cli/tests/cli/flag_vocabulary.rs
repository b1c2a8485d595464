//! Issue 13 item 9: one flag vocabulary. Every command names the same concept the same way
//! (read from its `--help`), the old spellings are hidden from the help, and the old spellings
//! still work for one release (the same run under both spellings gives the same output, byte for
//! byte).

use std::collections::BTreeSet;
use std::path::Path;

use crate::common;
use common::*;

/// Every command (subcommand path) of the program.
const COMMANDS: &[&str] = &[
    "simulate",
    "identify",
    "identify peaks",
    "identify tests",
    "displacement teeth",
    "displacement heights",
    "displacement signal",
    "chip compare",
    "chip eval",
    "grind compensate",
    "grind check",
    "shank force",
    "shank calibrate",
    "shank stiffness",
    "inspect",
];

/// The help text of `runout <cmd> --help`.
fn help(cmd: &str) -> String {
    let out = runout()
        .args(cmd.split(' '))
        .arg("--help")
        .output()
        .unwrap();
    assert!(out.status.success(), "{cmd} --help");
    String::from_utf8(out.stdout).unwrap()
}

/// The long flags a help lists (`--plot-dir`, …).
fn flags(help: &str) -> BTreeSet<String> {
    help.lines()
        .filter_map(|l| {
            let t = l.trim_start();
            let t = t.strip_prefix("-h, ").unwrap_or(t);
            let t = if t.len() > 4 && t.as_bytes()[0] == b'-' && &t[2..4] == ", " {
                &t[4..]
            } else {
                t
            };
            t.strip_prefix("--").map(|rest| {
                let name: String = rest
                    .chars()
                    .take_while(|c| c.is_ascii_alphanumeric() || *c == '-')
                    .collect();
                format!("--{name}")
            })
        })
        .collect()
}

/// Canonical name of each concept, and the commands that take that concept.
const CANONICAL: &[(&str, &[&str])] = &[
    (
        "--plot-dir",
        &[
            "simulate",
            "identify",
            "displacement teeth",
            "displacement heights",
            "displacement signal",
            "chip eval",
            "grind compensate",
            "shank force",
        ],
    ),
    (
        "--plot-format",
        &[
            "simulate",
            "identify",
            "displacement teeth",
            "displacement heights",
            "displacement signal",
            "chip eval",
            "grind compensate",
            "shank force",
        ],
    ),
    (
        "--config",
        &[
            "simulate",
            "identify",
            "chip compare",
            "chip eval",
            "shank force",
            "shank calibrate",
        ],
    ),
    ("--tooth0-angle-deg", &["identify", "displacement signal"]),
    ("--chip-model", &["simulate", "chip eval"]),
    (
        "--runout-um",
        &["simulate", "displacement teeth", "grind check"],
    ),
    ("--runout-angle-deg", &["simulate", "grind check"]),
    (
        "--teeth",
        &[
            "simulate",
            "identify",
            "identify peaks",
            "displacement teeth",
            "displacement signal",
            "grind compensate",
            "grind check",
        ],
    ),
    (
        "--helix-deg",
        &[
            "simulate",
            "identify",
            "displacement teeth",
            "displacement signal",
            "grind compensate",
            "grind check",
        ],
    ),
    (
        "--sample-rate-hz",
        &[
            "simulate",
            "identify",
            "shank force",
            "shank calibrate",
            "inspect",
        ],
    ),
    ("--json", COMMANDS),
];

/// Old spellings: hidden from every help, never a second name for a concept.
const OLD: &[&str] = &[
    "--tooth0-deg",
    "--plot",
    "--plots",
    "--model",
    "--offset-um",
    "--offset-se-um",
    "--flutes",
];

#[test]
fn every_command_uses_the_canonical_names_and_hides_the_old_ones() {
    let mut missing = Vec::new();
    let mut shown_old = Vec::new();
    for cmd in COMMANDS {
        let h = help(cmd);
        let f = flags(&h);
        assert!(f.contains("--help"), "{cmd}: flags not parsed from {h}");
        for (name, cmds) in CANONICAL {
            if cmds.contains(cmd) && !f.contains(*name) {
                missing.push(format!("{cmd}: {name}"));
            }
        }
        for old in OLD {
            if f.contains(*old) {
                shown_old.push(format!("{cmd}: {old}"));
            }
        }
    }
    assert!(missing.is_empty(), "canonical flags missing: {missing:?}");
    assert!(shown_old.is_empty(), "old spellings listed: {shown_old:?}");
}

/// The parser itself finds the flags: a wrong name is refused by clap (status 2) and names the
/// flag, so the help-based check above is not fooled by a name that appears only in a text.
#[test]
fn the_flag_parser_refuses_unknown_names() {
    let out = runout()
        .args(["chip", "eval", "x.toml", "--chip-modle", "arc"])
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("--chip-modle"));
}

/// Run `runout ARGS` (must succeed: exit 0, or 3 = ran but not fully identified, which is a
/// report too); its stdout.
fn stdout(args: &[&str]) -> String {
    let out = runout().args(args).output().unwrap();
    assert!(
        matches!(out.status.code(), Some(0 | 3)),
        "{args:?}: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    // the JSON's provenance names the command line, which differs by design
    without_provenance(&String::from_utf8(out.stdout).unwrap())
}

/// `old` and `new` (argument lists) give the same stdout, and it is not empty.
fn same(old: &[&str], new: &[&str]) {
    let (a, b) = (stdout(old), stdout(new));
    assert!(!a.is_empty(), "{old:?}");
    assert_eq!(a, b, "{old:?} vs {new:?}");
}

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

#[test]
fn old_spellings_still_work() {
    let d = tempfile::tempdir().unwrap();
    let sim = example("simulate.toml");
    let chip = example("chip/section2_5.toml");
    // --config FILE = the positional case file
    same(
        &["simulate", s(&sim), "--revolutions", "1", "--json", "-"],
        &[
            "simulate",
            "--config",
            s(&sim),
            "--revolutions",
            "1",
            "--json",
            "-",
        ],
    );
    same(
        &["chip", "eval", s(&chip), "--json", "-"],
        &["chip", "eval", "--config", s(&chip), "--json", "-"],
    );
    // --model = --chip-model
    same(
        &["chip", "eval", s(&chip), "--model", "arc", "--json", "-"],
        &[
            "chip",
            "eval",
            s(&chip),
            "--chip-model",
            "arc",
            "--json",
            "-",
        ],
    );
    // and the message names the spelling used
    for flag in ["--model", "--chip-model"] {
        let out = runout()
            .args(["chip", "eval", s(&chip), flag, "magic"])
            .output()
            .unwrap();
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(err.contains(&format!("{flag}: expected exact")), "{err}");
    }
    // --plot FILE = --plot-dir DIR (same plot, same bytes)
    let old_svg = d.path().join("f.svg");
    let dir = d.path().join("plots");
    stdout(&[
        "simulate",
        s(&sim),
        "--revolutions",
        "1",
        "--plot",
        s(&old_svg),
    ]);
    stdout(&[
        "simulate",
        s(&sim),
        "--revolutions",
        "1",
        "--plot-dir",
        s(&dir),
    ]);
    let a = plot_without_provenance(&old_svg);
    assert!(a.starts_with(b"<svg"));
    assert_eq!(a, plot_without_provenance(&dir.join("forces.svg")));
    stdout(&[
        "simulate",
        s(&sim),
        "--revolutions",
        "1",
        "--plot-dir",
        s(&dir),
        "--plot-format",
        "png",
    ]);
    assert_eq!(
        &std::fs::read(dir.join("forces.png")).unwrap()[1..4],
        b"PNG"
    );

    // displacement: --offset-um = --runout-um, --offset-se-um = --runout-se-um
    let t = d.path().join("t.csv");
    std::fs::write(
        &t,
        "seed_edge,reading_um\n1,253.850568\n2,250.916561\n3,245.307498\n",
    )
    .unwrap();
    let teeth = |rho: &str, se: &str| {
        stdout(&[
            "displacement",
            "teeth",
            s(&t),
            "--teeth",
            "3",
            "--diameter-mm",
            "0.5",
            "--sensor",
            "radial",
            rho,
            "3",
            se,
            "0.2",
            "--json",
            "-",
        ])
    };
    let (a, b) = (
        teeth("--offset-um", "--offset-se-um"),
        teeth("--runout-um", "--runout-se-um"),
    );
    assert_eq!(a, b);
    assert!(a.contains("\"known_offset_um\": 3.0"), "{a}");
    // displacement --plot FILE = --plot-dir DIR/teeth.svg
    let tp = d.path().join("teeth_old.svg");
    let args = [
        "displacement",
        "teeth",
        s(&t),
        "--teeth",
        "3",
        "--diameter-mm",
        "0.5",
        "--json",
        "-",
    ];
    stdout(&[&args[..], &["--plot", s(&tp)]].concat());
    stdout(&[&args[..], &["--plot-dir", s(&dir)]].concat());
    assert_eq!(
        plot_without_provenance(&tp),
        plot_without_provenance(&dir.join("teeth.svg"))
    );

    // grind check: --offset-um x,y = --runout-um ρ --runout-angle-deg λ (8, 0 = 8 µm at 0°, exactly)
    same(
        &["grind", "check", "--offset-um", "8,0", "--json", "-"],
        &["grind", "check", "--runout-um", "8", "--json", "-"],
    );
    // 5 µm at 90° = (0, 5) within the last digit of cos 90°: compare the fitted offsets
    let v: serde_json::Value = serde_json::from_str(&stdout(&[
        "grind",
        "check",
        "--runout-um",
        "5",
        "--runout-angle-deg",
        "90",
        "--json",
        "-",
    ]))
    .unwrap();
    let off = &v["inputs"]["offset_um"];
    assert!(off[0].as_f64().unwrap().abs() < 1e-12, "{v}");
    assert_eq!(off[1].as_f64().unwrap(), 5.0, "{v}");
    // the old message names the old spelling
    let out = runout()
        .args(["grind", "check", "--offset-um", "8"])
        .output()
        .unwrap();
    assert!(String::from_utf8_lossy(&out.stderr).contains("--offset-um: expected two"));
    // both spellings at once are refused
    let out = runout()
        .args(["grind", "check", "--offset-um", "8,0", "--runout-um", "8"])
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(2));
    // grind: --flutes = --teeth
    same(
        &["grind", "check", "--flutes", "3", "--json", "-"],
        &["grind", "check", "--teeth", "3", "--json", "-"],
    );
}

#[test]
fn tooth0_and_plots_old_spellings() {
    let d = tempfile::tempdir().unwrap();
    // displacement signal: --tooth0-deg = --tooth0-angle-deg
    let (fs, w) = (20_000.0, 3000.0 / 60.0 * std::f64::consts::TAU);
    let mut csv = String::from("time_s,disp_a_um,disp_b_um,pulse\n");
    for i in 0..4000 {
        let t = i as f64 / fs;
        let phi = w * t;
        let a = 100.0 - 8.0 * (phi - 0.5).cos();
        let b = 100.0 - 8.0 * (phi - 0.5 - std::f64::consts::FRAC_PI_2).cos();
        let pulse = i32::from((phi % std::f64::consts::TAU) < w / fs);
        csv.push_str(&format!("{t:.6},{a:.5},{b:.5},{pulse}\n"));
    }
    let p = d.path().join("s.csv");
    std::fs::write(&p, csv).unwrap();
    let run = |flag: &str| {
        stdout(&[
            "displacement",
            "signal",
            s(&p),
            "--sensor-angles-deg",
            "0,90",
            flag,
            "20",
            "--json",
            "-",
        ])
    };
    let (a, b) = (run("--tooth0-deg"), run("--tooth0-angle-deg"));
    assert_eq!(a, b);
    assert!(a.contains("\"schema\""), "{a}");
    // grind compensate: --plots DIR = --plot-dir DIR, --flutes = --teeth
    let g = |name: &str| example(&format!("grind/{name}")).display().to_string();
    let (probe, edge) = (g("probe.csv"), g("edge.csv"));
    let base = [
        "grind",
        "compensate",
        "--probe",
        &probe,
        "--bar-diameter-mm",
        "6",
        "--probe-tip-radius-mm",
        "1",
        "--json",
        "-",
    ];
    let (old, new) = (d.path().join("old"), d.path().join("new"));
    same(
        &[
            &base[..],
            &["--edge", "flat", "--flutes", "3", "--plots", s(&old)],
        ]
        .concat(),
        &[
            &base[..],
            &["--edge", "flat", "--teeth", "3", "--plot-dir", s(&new)],
        ]
        .concat(),
    );
    let mut names: Vec<String> = std::fs::read_dir(&new)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    names.sort();
    assert!(!names.is_empty());
    for n in &names {
        assert_eq!(
            plot_without_provenance(&old.join(n)),
            plot_without_provenance(&new.join(n)),
            "{n}"
        );
    }
    stdout(&[&base[..], &["--edge", &edge]].concat());
}

/// `identify` adopts the shared cutter flags (whose help names the unit) after the merge of
/// issue 13 (its files are being moved into the library at the same time).
const PENDING: &[&str] = &["identify: --teeth"];

/// Every option's help names its unit, its values, or what it is (a file, a count, a switch):
/// the help of each option has a `(…)` or a `[…]` or one of the words for a file or a switch.
#[test]
fn every_flag_help_names_its_unit() {
    let mut bare = Vec::new();
    for cmd in COMMANDS {
        let h = help(cmd);
        let lines: Vec<&str> = h.lines().collect();
        for (i, l) in lines.iter().enumerate() {
            let t = l.trim_start();
            if !t.starts_with("--") || t.starts_with("--help") {
                continue;
            }
            // the option's description: the lines up to the next option
            let desc: String = lines[i + 1..]
                .iter()
                .take_while(|x| !x.trim_start().starts_with('-'))
                .copied()
                .collect::<Vec<_>>()
                .join(" ");
            let text = format!("{t} {desc}");
            let named = text.contains('(')
                || text.contains("[possible values")
                || text.contains('|')
                || [
                    "file",
                    "File",
                    "folder",
                    "directory",
                    "Directory",
                    "FILE",
                    "DIR",
                    "stdout",
                    "CSV",
                    "JSON",
                    "table",
                    "count",
                ]
                .iter()
                .any(|w| text.contains(w));
            if !named && !PENDING.iter().any(|p| format!("{cmd}: {t}").starts_with(p)) {
                bare.push(format!("{cmd}: {t}"));
            }
        }
    }
    assert!(bare.is_empty(), "flags whose help names no unit: {bare:#?}");
}
