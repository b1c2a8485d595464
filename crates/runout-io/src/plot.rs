//! Plots (SVG and PNG by file extension) with plotters. PNG text is rasterised from an embedded
//! DejaVu Sans font (Bitstream Vera licence), so no system fonts are needed.

pub mod chip;
pub mod identify;
pub mod metadata;

use plotters::coord::Shift;
use plotters::prelude::*;
use runout_core::{ForceSeries, ToothPeak};
use std::path::Path;
use std::sync::Once;

/// Error while plotting.
#[derive(Debug, thiserror::Error)]
pub enum PlotError {
    /// Neither `.svg` nor `.png`.
    #[error("{path}: plot file must end in .svg or .png")]
    Extension {
        /// The path.
        path: String,
    },
    /// Drawing failed.
    #[error("{path}: plotting failed: {message}")]
    Draw {
        /// The path.
        path: String,
        /// Backend message.
        message: String,
    },
}

static FONT: Once = Once::new();

fn register_font() {
    FONT.call_once(|| {
        let bytes: &'static [u8] = include_bytes!("../assets/DejaVuSans.ttf");
        // registration fails only for a malformed font, which the test suite would catch
        let _ = plotters::style::register_font("sans-serif", FontStyle::Normal, bytes);
    });
}

/// Picture format chosen by extension.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Format {
    /// Scalable vector graphics.
    Svg,
    /// Portable network graphics.
    Png,
}

/// Format of `path` by its extension.
pub fn format_of(path: &Path) -> Result<Format, PlotError> {
    match path
        .extension()
        .and_then(|e| e.to_str())
        .map(|e| e.to_ascii_lowercase())
        .as_deref()
    {
        Some("svg") => Ok(Format::Svg),
        Some("png") => Ok(Format::Png),
        _ => Err(PlotError::Extension {
            path: path.display().to_string(),
        }),
    }
}

/// Make the embedded font available to plotters (idempotent).
pub fn ensure_font() {
    register_font();
}

/// Render to `path` (.svg or .png) by calling the generic drawing function `$draw(&root)`
/// (which returns `Result<(), String>`) with the backend the extension selects.
///
/// Each plot is written once as a function generic over `DB: DrawingBackend`, and this macro
/// dispatches it; plots for other methods use the same macro.
#[macro_export]
macro_rules! render_plot {
    ($path:expr, $size:expr, $draw:expr) => {{
        use plotters::prelude::IntoDrawingArea;
        let final_path: &std::path::Path = $path;
        $crate::plot::ensure_font();
        let p = final_path.display().to_string();
        let format = $crate::plot::format_of(final_path)?;
        $crate::plot::check_destination(final_path)?;
        // drawn into a temporary file next to the destination (same extension: the bitmap
        // backend picks the encoder by it) and renamed when complete: never half-written
        let tmp = $crate::plot::partial_path(final_path);
        let path: &std::path::Path = &tmp;
        let drawn = match format {
            $crate::plot::Format::Svg => {
                let root = plotters::prelude::SVGBackend::new(path, $size).into_drawing_area();
                ($draw)(&root)
                    .map_err(|m: String| $crate::plot::PlotError::Draw {
                        path: p.clone(),
                        message: m,
                    })
                    .and_then(|_| {
                        root.present().map_err(|e| $crate::plot::PlotError::Draw {
                            path: p.clone(),
                            message: e.to_string(),
                        })
                    })
            }
            $crate::plot::Format::Png => {
                let root = plotters::prelude::BitMapBackend::new(path, $size).into_drawing_area();
                ($draw)(&root)
                    .map_err(|m: String| $crate::plot::PlotError::Draw {
                        path: p.clone(),
                        message: m,
                    })
                    .and_then(|_| {
                        root.present().map_err(|e| $crate::plot::PlotError::Draw {
                            path: p.clone(),
                            message: e.to_string(),
                        })
                    })
            }
        };
        // provenance into the file's metadata (plot::metadata), then the rename
        let drawn = drawn.and_then(|()| {
            $crate::plot::metadata::embed(&tmp, format).map_err(|e| $crate::plot::PlotError::Draw {
                path: p.clone(),
                message: format!("cannot write: {}", $crate::report::io_problem(&e)),
            })
        });
        match drawn {
            Ok(()) => std::fs::rename(&tmp, final_path).map_err(|e| {
                let _ = std::fs::remove_file(&tmp);
                $crate::plot::PlotError::Draw {
                    path: p.clone(),
                    message: format!("cannot write: {}", $crate::report::io_problem(&e)),
                }
            }),
            Err(e) => {
                let _ = std::fs::remove_file(&tmp);
                Err(e)
            }
        }
    }};
}

/// Render to an SVG document in memory (for reports that inline their plots, e.g. the HTML
/// report) by calling the same generic drawing function as [`render_plot!`]; evaluates to
/// `Result<String, PlotError>`.
#[macro_export]
macro_rules! render_svg {
    ($size:expr, $draw:expr) => {{
        use plotters::prelude::IntoDrawingArea;
        $crate::plot::ensure_font();
        let err = |m: String| $crate::plot::PlotError::Draw {
            path: "(inline svg)".into(),
            message: m,
        };
        let mut buf = String::new();
        let drawn: Result<(), $crate::plot::PlotError> = {
            let root =
                plotters::prelude::SVGBackend::with_string(&mut buf, $size).into_drawing_area();
            ($draw)(&root)
                .map_err(err)
                .and_then(|_| root.present().map_err(|e| err(e.to_string())))
        };
        drawn.map(|_| buf)
    }};
}

/// A plot can be written to `path`: its folder exists and it is not a folder itself (checked
/// before drawing, so the message says so rather than the drawing backend's error).
pub fn check_destination(path: &std::path::Path) -> Result<(), PlotError> {
    let err = |message: String| PlotError::Draw {
        path: path.display().to_string(),
        message,
    };
    if path.is_dir() {
        return Err(err(
            "is a folder: expected a file name such as plot.svg".into()
        ));
    }
    match path.parent() {
        Some(dir) if !dir.as_os_str().is_empty() && !dir.is_dir() => Err(err(format!(
            "cannot write: folder `{}` does not exist; create it or choose another path",
            dir.display()
        ))),
        _ => Ok(()),
    }
}

/// Temporary file for drawing `path`: `.NAME.partial-PID.EXT` in the same folder.
pub fn partial_path(path: &std::path::Path) -> std::path::PathBuf {
    let stem = path
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_default();
    let ext = path
        .extension()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_default();
    path.with_file_name(format!(".{stem}.partial-{}.{ext}", std::process::id()))
}

/// Draw the series legend of `chart` at `position` in the one legend style of every plot:
/// translucent white box, black border.
pub fn draw_legend<'a, DB: DrawingBackend + 'a, CT: CoordTranslate>(
    chart: &mut ChartContext<'a, DB, CT>,
    position: SeriesLabelPosition,
) -> Result<(), String> {
    chart
        .configure_series_labels()
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK)
        .position(position)
        .draw()
        .map_err(e2s)
}

/// Legend glyph of a line series: an 18 px stroke in `style`.
pub fn legend_line<S: Into<ShapeStyle>>(
    style: S,
) -> impl Fn((i32, i32)) -> PathElement<(i32, i32)> {
    let style: ShapeStyle = style.into();
    move |(x, y)| PathElement::new(vec![(x, y), (x + 18, y)], style)
}

/// Legend glyph of a marker series: a filled dot of radius 5 px in `colour`.
pub fn legend_dot(colour: RGBColor) -> impl Fn((i32, i32)) -> Circle<(i32, i32), i32> {
    move |(x, y)| Circle::new((x + 9, y), 5, colour.filled())
}

/// The one polar convention of every plot (issue 21 item 7; docs/conventions.md): the spindle
/// frame seen from above the tool (looking down −z), tooth 0 (angle 0) up and angles positive
/// clockwise on the page — the direction the spindle turns. Returns page (x, y) for radius `r` at
/// spindle-frame angle `angle_rad`.
///
/// ```
/// let (x, y) = runout_io::plot::polar_page_xy(1.0, 90f64.to_radians());
/// assert!((x - 1.0).abs() < 1e-12 && y.abs() < 1e-12); // 90° in the rotation direction: right
/// ```
pub fn polar_page_xy(r: f64, angle_rad: f64) -> (f64, f64) {
    (r * angle_rad.sin(), r * angle_rad.cos())
}

/// How [`polar_page_xy`] draws the spindle frame, for the plots' captions.
pub const POLAR_CONVENTION: &str = "seen from above the tool: tooth 0 up, rotation clockwise";

/// Ring spacing of a polar plot of radius `rmax`: the smallest round number (1, 2, 2.5, 5 or 10
/// × 10ⁿ) at least rmax/4, which gives 3–6 rings.
///
/// ```
/// assert_eq!(runout_io::plot::polar_ring_step(10.0), 2.5);
/// assert_eq!(runout_io::plot::polar_ring_step(33.0), 10.0);
/// ```
pub fn polar_ring_step(rmax: f64) -> f64 {
    let raw = rmax / 4.0;
    let mag = 10f64.powf(raw.log10().floor());
    [1.0, 2.0, 2.5, 5.0, 10.0]
        .iter()
        .map(|f| f * mag)
        .find(|s| *s >= raw)
        .unwrap_or(10.0 * mag)
}

/// Stringify a plotters error.
pub fn e2s<E: std::fmt::Debug>(e: E) -> String {
    format!("{e:?}")
}

/// Palette for teeth / channels.
pub fn colour(i: usize) -> RGBColor {
    const C: [RGBColor; 8] = [
        RGBColor(31, 119, 180),
        RGBColor(255, 127, 14),
        RGBColor(44, 160, 44),
        RGBColor(214, 39, 40),
        RGBColor(148, 103, 189),
        RGBColor(140, 86, 75),
        RGBColor(227, 119, 194),
        RGBColor(127, 127, 127),
    ];
    C[i % C.len()]
}

/// Colour of tooth `i` in every plot and in the HTML report (Okabe–Ito palette, readable for
/// colour-blind readers and in greyscale print; 7 colours, then repeated).
pub fn tooth_colour(i: usize) -> RGBColor {
    const C: [RGBColor; 7] = [
        RGBColor(0, 114, 178),
        RGBColor(213, 94, 0),
        RGBColor(0, 158, 115),
        RGBColor(204, 121, 167),
        RGBColor(230, 159, 0),
        RGBColor(86, 180, 233),
        RGBColor(120, 94, 60),
    ];
    C[i % C.len()]
}

/// [`tooth_colour`] as CSS `#rrggbb`.
pub fn tooth_hex(i: usize) -> String {
    let RGBColor(r, g, b) = tooth_colour(i);
    format!("#{r:02x}{g:02x}{b:02x}")
}

/// Forces vs spindle angle (deg) with each tooth's |F_xy| peak marked.
pub fn force_plot(
    path: &Path,
    series: &ForceSeries,
    peaks: &[ToothPeak],
    title: &str,
) -> Result<(), PlotError> {
    render_plot!(path, (1100, 620), |root: &DrawingArea<_, Shift>| {
        draw_forces(root, series, peaks, title)
    })
}

fn draw_forces<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    s: &ForceSeries,
    peaks: &[ToothPeak],
    title: &str,
) -> Result<(), String> {
    root.fill(&WHITE).map_err(e2s)?;
    let ang: Vec<f64> = s.angle.iter().map(|a| a.to_degrees()).collect();
    let fxy = s.fxy();
    let all = s.fx.iter().chain(&s.fy).chain(&s.fz).chain(&fxy);
    let (lo, hi) = all.fold((0.0f64, 0.0f64), |(l, h), v| (l.min(*v), h.max(*v)));
    let pad = 0.05 * (hi - lo).max(1e-9);
    // headroom above the data for the legend, so it never hides a peak marker
    let top = hi + 0.45 * (hi - lo).max(1e-9);
    let x1 = ang.last().copied().unwrap_or(360.0).max(1e-9);
    let mut chart = ChartBuilder::on(root)
        .caption(title, ("sans-serif", 22))
        .margin(12)
        .x_label_area_size(40)
        .y_label_area_size(60)
        .build_cartesian_2d(0.0..x1, (lo - pad)..top)
        .map_err(e2s)?;
    chart
        .configure_mesh()
        .light_line_style(BLACK.mix(0.04))
        .x_desc("spindle angle (deg)")
        .y_desc("force on workpiece (N)")
        .draw()
        .map_err(e2s)?;
    let series_list: [(&str, &[f64], RGBColor); 4] = [
        ("F_x", &s.fx, colour(0)),
        ("F_y", &s.fy, colour(1)),
        ("F_z", &s.fz, colour(2)),
        ("|F_xy|", &fxy, BLACK),
    ];
    for (name, v, c) in series_list {
        chart
            .draw_series(LineSeries::new(
                ang.iter().copied().zip(v.iter().copied()),
                c.stroke_width(1),
            ))
            .map_err(e2s)?
            .label(name)
            .legend(legend_line(c.stroke_width(2)));
    }
    // mark each tooth's peak in every revolution
    let turns = (x1 / 360.0).ceil() as usize;
    for p in peaks.iter().filter(|p| p.angle.is_finite()) {
        let c = tooth_colour(p.tooth);
        let pts: Vec<(f64, f64)> = (0..turns)
            .map(|t| (p.angle.to_degrees() + 360.0 * t as f64, p.peak_fxy))
            .filter(|(x, _)| *x <= x1)
            .collect();
        chart
            .draw_series(pts.into_iter().map(|pt| Circle::new(pt, 5, c.filled())))
            .map_err(e2s)?
            .label(format!("tooth {} peak {:.1} N", p.tooth, p.peak_fxy))
            .legend(legend_dot(c));
    }
    draw_legend(&mut chart, SeriesLabelPosition::UpperRight)?;
    Ok(())
}

#[cfg(test)]
mod polar_convention_tests {
    use super::polar_page_xy;

    /// Tooth 0 up; a quarter turn in the rotation direction is on the right (clockwise seen from
    /// above, conventions.md); a quarter turn against it on the left.
    #[test]
    fn rotation_is_clockwise_on_the_page_with_tooth_0_up() {
        let close =
            |(x, y): (f64, f64), (u, v): (f64, f64)| (x - u).abs() < 1e-12 && (y - v).abs() < 1e-12;
        assert!(close(polar_page_xy(2.0, 0.0), (0.0, 2.0)));
        assert!(close(polar_page_xy(2.0, 90f64.to_radians()), (2.0, 0.0)));
        assert!(close(polar_page_xy(2.0, -90f64.to_radians()), (-2.0, 0.0)));
    }
}
