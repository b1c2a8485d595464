//! Plots render to both formats; a wrong extension is an error, not a silent default.

use runout_io::plot::identify::{
    runout_polar, tooth_peak_bars, waveform_overlay, Curve, RunoutMark,
};
use runout_io::plot::PlotError;

fn out_dir() -> std::path::PathBuf {
    let d = std::env::var_os("RUNOUT_PLOT_DIR")
        .map(std::path::PathBuf::from)
        .unwrap_or_else(|| {
            std::env::temp_dir().join(format!("runout-plots-{}", std::process::id()))
        });
    std::fs::create_dir_all(&d).unwrap();
    d
}

#[test]
fn identify_plots_render_svg_and_png() {
    let d = out_dir();
    let x: Vec<f64> = (0..360).map(|i| i as f64).collect();
    let m: Vec<f64> = x
        .iter()
        .map(|a| 100.0 * (a.to_radians() * 4.0).sin().max(0.0))
        .collect();
    let p: Vec<f64> = m.iter().map(|v| v * 0.98).collect();
    for ext in ["svg", "png"] {
        let f = d.join(format!("overlay.{ext}"));
        waveform_overlay(
            &f,
            &x,
            &[Curve {
                label: "F_x (N)",
                values: &m,
            }],
            &[Curve {
                label: "F_x (N)",
                values: &p,
            }],
            "overlay",
        )
        .unwrap();
        let b = d.join(format!("bars.{ext}"));
        tooth_peak_bars(
            &b,
            &[366.6, 307.9, 259.9, 326.6],
            &[3.0, 2.0, 2.5, 3.1],
            315.0,
            53.6,
            100.05f64.to_radians(),
            "peaks",
        )
        .unwrap();
        let pp = d.join(format!("polar.{ext}"));
        let mark = RunoutMark {
            label: "sine fit",
            offset_um: 7.7,
            angle_deg: -35.0,
            offset_se_um: 0.4,
            angle_se_deg: 4.0,
        };
        runout_polar(&pp, &[mark], 4, "runout").unwrap();
        for file in [f, b, pp] {
            let bytes = std::fs::read(&file).unwrap();
            assert!(bytes.len() > 1000, "{} too small", file.display());
            if ext == "png" {
                assert_eq!(&bytes[1..4], b"PNG");
            } else {
                assert!(String::from_utf8_lossy(&bytes).contains("<svg"));
            }
        }
    }
}

#[test]
fn unknown_extension_is_an_error() {
    let e = tooth_peak_bars(
        std::path::Path::new("/tmp/x.jpg"),
        &[1.0],
        &[0.1],
        1.0,
        0.0,
        0.0,
        "t",
    )
    .unwrap_err();
    assert!(matches!(e, PlotError::Extension { .. }), "{e}");
}
