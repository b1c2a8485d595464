//! Chip-thickness plots: h vs spindle angle per tooth, and a map of h over path time × height
//! (5-axis evaluation, methods.md §2).

use super::{colour, draw_legend, e2s, legend_line, PlotError};
use crate::render_plot;
use plotters::coord::Shift;
use plotters::prelude::*;
use std::path::Path;

/// One tooth's chip thickness over the spindle angle.
#[derive(Debug, Clone)]
pub struct ToothCurve {
    /// Tooth index.
    pub tooth: usize,
    /// (spindle angle (deg), h (µm)) points.
    pub points: Vec<(f64, f64)>,
}

/// h (µm) vs spindle angle (deg), one line per tooth.
pub fn chip_angle_plot(path: &Path, curves: &[ToothCurve], title: &str) -> Result<(), PlotError> {
    render_plot!(path, (1000, 560), |root: &DrawingArea<_, Shift>| {
        draw_angle(root, curves, title)
    })
}

fn draw_angle<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    curves: &[ToothCurve],
    title: &str,
) -> Result<(), String> {
    root.fill(&WHITE).map_err(e2s)?;
    let pts = curves.iter().flat_map(|c| c.points.iter());
    let (x0, x1, hmax) = pts.fold(
        (f64::INFINITY, f64::NEG_INFINITY, 0.0f64),
        |(a, b, h), p| (a.min(p.0), b.max(p.0), h.max(p.1)),
    );
    let (x0, x1) = if x0 < x1 { (x0, x1) } else { (0.0, 360.0) };
    let top = hmax.max(1e-9) * 1.25;
    let mut chart = ChartBuilder::on(root)
        .caption(title, ("sans-serif", 20))
        .margin(12)
        .x_label_area_size(40)
        .y_label_area_size(60)
        .build_cartesian_2d(x0..x1, 0.0..top)
        .map_err(e2s)?;
    chart
        .configure_mesh()
        .light_line_style(BLACK.mix(0.04))
        .x_desc("spindle angle (deg)")
        .y_desc("chip thickness h (µm)")
        .draw()
        .map_err(e2s)?;
    for c in curves {
        let col = colour(c.tooth);
        chart
            .draw_series(LineSeries::new(
                c.points.iter().copied(),
                col.stroke_width(2),
            ))
            .map_err(e2s)?
            .label(format!("tooth {}", c.tooth))
            .legend(legend_line(col.stroke_width(2)));
    }
    draw_legend(&mut chart, SeriesLabelPosition::UpperRight)
}

/// A map of values over (x = path time, y = height): `values[ix][iy]` (µm) on the cell centred at
/// (`x[ix]`, `y[iy]`).
#[derive(Debug, Clone)]
pub struct ChipMap {
    /// Cell centres along the path (s).
    pub time_s: Vec<f64>,
    /// Cell centres along the tool axis (mm).
    pub height_mm: Vec<f64>,
    /// Values (µm), `values[ix][iy]`.
    pub values: Vec<Vec<f64>>,
}

/// Heat map of h (µm) over path time × height, with a colour bar.
pub fn chip_map_plot(path: &Path, map: &ChipMap, title: &str) -> Result<(), PlotError> {
    render_plot!(path, (1100, 560), |root: &DrawingArea<_, Shift>| {
        draw_map(root, map, title)
    })
}

/// Cell edges around sorted centres.
fn edges(c: &[f64]) -> Vec<f64> {
    let n = c.len();
    if n == 1 {
        return vec![c[0] - 0.5, c[0] + 0.5];
    }
    let mut e = Vec::with_capacity(n + 1);
    e.push(c[0] - 0.5 * (c[1] - c[0]));
    e.extend(c.windows(2).map(|w| 0.5 * (w[0] + w[1])));
    e.push(c[n - 1] + 0.5 * (c[n - 1] - c[n - 2]));
    e
}

fn draw_map<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    map: &ChipMap,
    title: &str,
) -> Result<(), String> {
    root.fill(&WHITE).map_err(e2s)?;
    if map.time_s.is_empty() || map.height_mm.is_empty() {
        return Err("empty map".into());
    }
    let (main, bar) = root.split_horizontally(980);
    let xe = edges(&map.time_s);
    let ye = edges(&map.height_mm);
    let vmax = map
        .values
        .iter()
        .flatten()
        .copied()
        .fold(0.0f64, f64::max)
        .max(1e-12);
    let mut chart = ChartBuilder::on(&main)
        .caption(title, ("sans-serif", 20))
        .margin(12)
        .x_label_area_size(40)
        .y_label_area_size(60)
        .build_cartesian_2d(xe[0]..xe[xe.len() - 1], ye[0]..ye[ye.len() - 1])
        .map_err(e2s)?;
    chart
        .configure_mesh()
        .light_line_style(BLACK.mix(0.04))
        .disable_mesh()
        .x_desc("path time (s)")
        .y_desc("height above tool tip z (mm)")
        .draw()
        .map_err(e2s)?;
    let cells = map.values.iter().enumerate().flat_map(|(ix, col)| {
        let (xe, ye) = (&xe, &ye);
        col.iter().enumerate().map(move |(iy, v)| {
            let c = viridis(*v / vmax);
            Rectangle::new([(xe[ix], ye[iy]), (xe[ix + 1], ye[iy + 1])], c.filled())
        })
    });
    chart.draw_series(cells).map_err(e2s)?;
    draw_colour_bar(&bar, vmax)
}

fn draw_colour_bar<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    vmax: f64,
) -> Result<(), String> {
    let mut chart = ChartBuilder::on(area)
        .margin_top(50)
        .margin_bottom(52)
        .margin_right(8)
        .y_label_area_size(50)
        .caption("h (µm)", ("sans-serif", 14))
        .build_cartesian_2d(0.0..1.0, 0.0..vmax)
        .map_err(e2s)?;
    chart
        .configure_mesh()
        .light_line_style(BLACK.mix(0.04))
        .disable_mesh()
        .disable_x_axis()
        .draw()
        .map_err(e2s)?;
    let n = 100;
    chart
        .draw_series((0..n).map(|q| {
            let lo = vmax * q as f64 / n as f64;
            let hi = vmax * (q + 1) as f64 / n as f64;
            let c = viridis(0.5 * (lo + hi) / vmax);
            Rectangle::new([(0.0, lo), (1.0, hi)], c.filled())
        }))
        .map_err(e2s)?;
    Ok(())
}

/// Viridis colour map, linear between 9 anchor colours (the plotters colormaps feature is off).
fn viridis(v: f64) -> RGBColor {
    const A: [(u8, u8, u8); 9] = [
        (68, 1, 84),
        (71, 44, 122),
        (59, 81, 139),
        (44, 113, 142),
        (33, 144, 141),
        (39, 173, 129),
        (92, 200, 99),
        (170, 220, 50),
        (253, 231, 37),
    ];
    let x = v.clamp(0.0, 1.0) * (A.len() - 1) as f64;
    let i = (x.floor() as usize).min(A.len() - 2);
    let f = x - i as f64;
    let mix = |a: u8, b: u8| (a as f64 + f * (b as f64 - a as f64)).round() as u8;
    RGBColor(
        mix(A[i].0, A[i + 1].0),
        mix(A[i].1, A[i + 1].1),
        mix(A[i].2, A[i + 1].2),
    )
}
