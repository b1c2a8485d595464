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
            offset_um_se: 0.4,
            angle_deg_se: 4.0,
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

/// Issue 11 acceptance: each predicted component is drawn in its legend colour (measured solid
/// in the palette colour, predicted dashed in a darker shade of the same hue), not in black.
/// (Fails on the former code: its predicted traces were three more black 360-point polylines
/// and their legend samples were the measured colours.)
#[test]
fn waveform_predicted_traces_use_their_legend_colours() {
    use runout_io::plot::colour;
    use runout_io::plot::identify::predicted_colour;
    let d = out_dir();
    let x: Vec<f64> = (0..360).map(|i| i as f64).collect();
    let wave = |k: f64, s: f64| -> Vec<f64> {
        x.iter()
            .map(|a| s * 100.0 * (a.to_radians() * k).sin())
            .collect()
    };
    let (mx, my, mz) = (wave(2.0, 1.0), wave(2.0, -0.6), wave(4.0, 0.3));
    let (px, py, pz) = (wave(2.0, 0.97), wave(2.0, -0.58), wave(4.0, 0.31));
    let labels = ["F_x (N)", "F_y (N)", "F_z (N)"];
    let measured: Vec<Curve> = labels
        .iter()
        .zip([&mx, &my, &mz])
        .map(|(l, v)| Curve {
            label: l,
            values: v,
        })
        .collect();
    let predicted: Vec<Curve> = labels
        .iter()
        .zip([&px, &py, &pz])
        .map(|(l, v)| Curve {
            label: l,
            values: v,
        })
        .collect();
    let f = d.join("overlay_colours.svg");
    waveform_overlay(&f, &x, &measured, &predicted, "colours").unwrap();
    let svg = std::fs::read_to_string(&f).unwrap();
    let hex = |c: plotters::style::RGBColor| format!("#{:02X}{:02X}{:02X}", c.0, c.1, c.2);
    // every polyline's stroke colour and point count, in drawing order
    let lines: Vec<(String, usize)> = svg
        .split("<polyline")
        .skip(1)
        .map(|el| {
            let el = &el[..el.find("/>").unwrap()];
            let stroke = el.split("stroke=\"").nth(1).unwrap();
            let points = el.split("points=\"").nth(1).unwrap();
            let points = &points[..points.find('"').unwrap()];
            (
                stroke[..7].to_uppercase(),
                points.split_whitespace().count(),
            )
        })
        .collect();
    // the legend is drawn last: one 2-point sample per series, measured then predicted
    let n = labels.len();
    let legend: Vec<&str> = lines[lines.len() - 2 * n..]
        .iter()
        .map(|(c, _)| c.as_str())
        .collect();
    for i in 0..n {
        assert_eq!(legend[i], hex(colour(i)), "legend of measured {i}");
        assert_eq!(
            legend[n + i],
            hex(predicted_colour(i)),
            "legend of predicted {i}"
        );
        assert_ne!(
            legend[n + i],
            legend[i],
            "predicted {i} told apart from measured"
        );
        // same hue: each channel scaled by the same factor (0.6, rounded to a unit)
        let (c, p) = (colour(i), predicted_colour(i));
        for (a, b) in [(c.0, p.0), (c.1, p.1), (c.2, p.2)] {
            assert!(
                (f64::from(a) * 0.6 - f64::from(b)).abs() <= 0.5,
                "{c:?} {p:?}"
            );
        }
    }
    // the traces: the measured ones are one polyline each (360 points), in their legend colour;
    // then the predicted dashes, each in one predicted legend colour, all three present
    let traces = &lines[..lines.len() - 2 * n];
    let long: Vec<&(String, usize)> = traces.iter().filter(|(_, k)| *k >= 300).collect();
    assert_eq!(long.len(), n, "{long:?}");
    for (i, (c, _)) in long.iter().enumerate() {
        assert_eq!(c, &hex(colour(i)));
    }
    let last_measured = traces.iter().rposition(|(_, k)| *k >= 300).unwrap();
    let dashes = &traces[last_measured + 1..];
    assert!(dashes.len() > 3 * n, "{} dashes", dashes.len());
    for (i, want) in (0..n).map(|i| (i, hex(predicted_colour(i)))) {
        let count = dashes.iter().filter(|(c, _)| *c == want).count();
        assert!(count > 3, "predicted {i}: {count} dashes in {want}");
    }
    assert!(
        dashes
            .iter()
            .all(|(c, _)| (0..n).any(|i| *c == hex(predicted_colour(i)))),
        "a predicted dash in another colour: {dashes:?}"
    );
}

/// Issue 20 item 3: a plot is drawn into a temporary file in the same folder and renamed when
/// complete — the destination appears whole, and no temporary file is left behind.
#[test]
fn plots_are_written_whole_without_leftovers() {
    let dir = tempfile::tempdir().unwrap();
    for ext in ["svg", "png"] {
        let dest = dir.path().join(format!("w.{ext}"));
        let deg: Vec<f64> = (0..36).map(|i| i as f64 * 10.0).collect();
        let v: Vec<f64> = deg.iter().map(|d| d.to_radians().sin()).collect();
        let c = [runout_io::plot::identify::Curve {
            label: "F_x (N)",
            values: &v,
        }];
        runout_io::plot::identify::waveform_overlay(&dest, &deg, &c, &c, "t").unwrap();
        assert!(std::fs::metadata(&dest).unwrap().len() > 0);
    }
    let names: Vec<String> = std::fs::read_dir(dir.path())
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    assert_eq!(names.len(), 2, "{names:?}");
    assert!(names.iter().all(|n| !n.contains("partial")), "{names:?}");
}
