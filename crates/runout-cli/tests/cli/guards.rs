//! Issue 21 items 2 and 9 at the command line: the forces' magnitude against `--diameter-mm`
//! (a wrong diameter warned, with what to check), the runout larger than the feed per tooth,
//! and `--quiet` (no warnings or progress on stderr; the warnings stay in the report).

use std::path::{Path, PathBuf};
use std::process::Output;

use crate::common::*;

fn ex(name: &str) -> PathBuf {
    example(&format!("identify/{name}"))
}

/// The example's cut.toml with `diameter_mm` replaced (and lines dropped), in `dir`.
fn config(dir: &Path, diameter_mm: &str, drop: &[&str]) -> PathBuf {
    let text = std::fs::read_to_string(ex("cut.toml")).unwrap();
    let mut out = String::new();
    for l in text.lines() {
        if drop.iter().any(|d| l.starts_with(d)) {
            continue;
        }
        if l.starts_with("diameter_mm") {
            out += &format!("diameter_mm = {diameter_mm}\n");
        } else {
            out += l;
            out.push('\n');
        }
    }
    let p = dir.join(format!("cut_{diameter_mm}.toml"));
    std::fs::write(&p, out).unwrap();
    p
}

fn identify(cfg: &Path, extra: &[&str]) -> Output {
    runout()
        .env("RAYON_NUM_THREADS", "1")
        .arg("identify")
        .args([ex("cut_fz0.05.txt"), ex("cut_fz0.08.txt")])
        .arg("--config")
        .arg(cfg)
        .args(extra)
        .output()
        .unwrap()
}

fn json(o: &Output) -> serde_json::Value {
    serde_json::from_slice(&o.stdout)
        .unwrap_or_else(|e| panic!("{e}: {}", String::from_utf8_lossy(&o.stderr)))
}

/// The example was cut with a 10 mm cutter at a_e 2 mm; told 100 mm, the immersion shrinks
/// from 53° to 16°, and the measured mean force would need K_tc ≈ 10× the true 2 200 N/mm²,
/// beyond the 8 000 published for metals: warned, naming --diameter-mm. Told the right
/// diameter: no such warning.
#[test]
fn a_wrong_diameter_is_warned_from_the_forces_magnitude() {
    let dir = tempfile::tempdir().unwrap();
    let good = json(&identify(
        &config(dir.path(), "10.0", &[]),
        &["--json", "-"],
    ));
    let w = good["answer"]["warnings"].to_string() + &good["answer"]["reasons"].to_string();
    assert!(!w.contains("implies a specific cutting force"), "{w}");
    let o = identify(&config(dir.path(), "100.0", &[]), &["--json", "-"]);
    assert!(
        matches!(o.status.code(), Some(0 | 3)),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
    let bad = json(&o);
    let w = bad["answer"]["warnings"].to_string() + &bad["answer"]["reasons"].to_string();
    assert!(w.contains("implies a specific cutting force"), "{w}");
    assert!(w.contains("check --diameter-mm"), "{w}");
}

/// The real PHM 2010 recording (a 6 mm 3-flute **ball-end** cutter at a_p 0.2 mm, a_e 0.125 mm,
/// f_z 0.0498 mm; ../shared/data/phm2010-c1-slice/SOURCE.md): its mean force of 11.4 N was read as
/// K_tc ≈ 51 000 N/mm² by a guard that took the nominal radius and no edge forces — a false
/// alarm naming --diameter-mm on correct input. Described as it is (`--profile ball`: the ball's
/// local radius at these depths is ≤ 1.08 mm, so the immersion is wider; edge forces up to
/// K_te 50, K_re 80 N/mm allowed) it is not warned; described as a flat-end cutter it still is,
/// and the warning names --profile.
#[test]
fn a_ball_end_recording_is_not_a_wrong_diameter() {
    let data = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../../shared/data/phm2010-c1-slice/c1_cut158_rows_slice.csv");
    let data = if data.exists() {
        data
    } else {
        PathBuf::from("/work/shared/data/phm2010-c1-slice/c1_cut158_rows_slice.csv")
    };
    let run = |profile: &str| {
        let o = runout()
            .arg("identify")
            .arg(&data)
            .args(["--teeth", "3", "--diameter-mm", "6", "--helix-deg", "30"])
            .args(["--profile", profile, "--rpm", "10400", "--fz-mm", "0.0498"])
            .args(["--ap-mm", "0.2", "--ae-mm", "0.125", "--mode", "down"])
            .args(["--sample-rate-hz", "50000"])
            .args(["--axes", "x = force_x_N, y = force_y_N, z = force_z_N"])
            .args(["--json", "-"])
            .output()
            .unwrap();
        assert!(
            matches!(o.status.code(), Some(0 | 3)),
            "{}",
            String::from_utf8_lossy(&o.stderr)
        );
        let j = json(&o);
        j["answer"]["warnings"].to_string() + &j["answer"]["reasons"].to_string()
    };
    let ball = run("ball");
    assert!(!ball.contains("implies a specific cutting force"), "{ball}");
    let flat = run("flat");
    assert!(flat.contains("implies a specific cutting force"), "{flat}");
    assert!(flat.contains("--profile"), "{flat}");
}

/// `plausibility::runout_size` at the command line: the displacement example (ρ ≈ 6 µm) with a
/// feed per tooth of 5 µm is warned; with 50 µm it is not.
#[test]
fn runout_larger_than_the_feed_per_tooth_is_warned() {
    let run = |fz: &str| {
        let o = runout()
            .args(["displacement", "teeth"])
            .arg(example("displacement/teeth.csv"))
            .args([
                "--teeth",
                "4",
                "--diameter-mm",
                "10",
                "--helix-deg",
                "30",
                "--fz-mm",
                fz,
            ])
            .args(["--json", "-"])
            .output()
            .unwrap();
        // a warning, not a failure: the runout is still identified
        assert_eq!(
            o.status.code(),
            Some(0),
            "{}",
            String::from_utf8_lossy(&o.stderr)
        );
        json(&o)["answer"]["warnings"].to_string()
    };
    let w = run("0.005");
    assert!(w.contains("exceeds the feed per tooth f_z = 5.0 µm"), "{w}");
    assert!(!run("0.05").contains("exceeds the feed per tooth"));
}

/// Without `helix_deg` in the config the job assumes 0° and says so on stderr; `--quiet` keeps
/// stderr empty and the warning in the report.
#[test]
fn quiet_silences_stderr_but_keeps_the_warnings_in_the_report() {
    let dir = tempfile::tempdir().unwrap();
    let cfg = config(dir.path(), "10.0", &["helix_deg"]);
    let loud = identify(&cfg, &["--json", "-"]);
    let err = String::from_utf8_lossy(&loud.stderr);
    assert!(err.contains("warning: assumed helix 0°"), "{err}");
    for q in ["--quiet", "-q"] {
        let quiet = identify(&cfg, &[q, "--json", "-"]);
        assert_eq!(quiet.status.code(), loud.status.code());
        assert!(
            quiet.stderr.is_empty(),
            "{}",
            String::from_utf8_lossy(&quiet.stderr)
        );
        assert!(json(&quiet)["answer"]["warnings"]
            .to_string()
            .contains("assumed helix 0°"));
    }
    // global: also before the subcommand; errors still reach stderr
    let o = runout()
        .args([
            "--quiet",
            "displacement",
            "teeth",
            "no-such-file.csv",
            "--teeth",
            "4",
        ])
        .args(["--diameter-mm", "10"])
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(1));
    assert!(String::from_utf8_lossy(&o.stderr).contains("error:"));
}
