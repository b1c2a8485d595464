//! Generic stacked line plots (one or more panels sharing the x axis), used for time histories
//! such as the shank method's raw signals, deflections and forces.

use crate::plot::{colour, draw_legend, e2s, PlotError};
use crate::{render_plot, render_svg};
use plotters::coord::Shift;
use plotters::prelude::*;
use std::path::Path;

/// One curve: legend name and (x, y) points.
#[derive(Debug, Clone)]
pub struct Curve {
    /// Legend text.
    pub name: String,
    /// Points.
    pub points: Vec<(f64, f64)>,
}

/// One panel: y-axis label and its curves.
#[derive(Debug, Clone)]
pub struct Panel {
    /// y-axis label with unit.
    pub y_label: String,
    /// Curves.
    pub curves: Vec<Curve>,
}

/// Draw `panels` stacked vertically to `path` (.svg or .png) with a common x label.
pub fn stacked_plot(
    path: &Path,
    title: &str,
    x_label: &str,
    panels: &[Panel],
) -> Result<(), PlotError> {
    let h = 260 * panels.len().max(1) as u32 + 60;
    render_plot!(path, (1100, h), |root: &DrawingArea<_, Shift>| {
        draw(root, title, x_label, panels)
    })
}

/// [`stacked_plot`] as an SVG document in memory.
pub fn stacked_svg(title: &str, x_label: &str, panels: &[Panel]) -> Result<String, PlotError> {
    let h = 260 * panels.len().max(1) as u32 + 60;
    render_svg!((1100, h), |root: &DrawingArea<_, Shift>| {
        draw(root, title, x_label, panels)
    })
}

fn draw<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    title: &str,
    x_label: &str,
    panels: &[Panel],
) -> Result<(), String> {
    root.fill(&WHITE).map_err(e2s)?;
    let root = root.titled(title, ("sans-serif", 22)).map_err(e2s)?;
    let areas = root.split_evenly((panels.len().max(1), 1));
    for (area, panel) in areas.iter().zip(panels) {
        let pts = panel
            .curves
            .iter()
            .flat_map(|c| c.points.iter())
            .filter(|p| p.0.is_finite() && p.1.is_finite());
        let (x0, x1, y0, y1) = pts.fold(
            (
                f64::INFINITY,
                f64::NEG_INFINITY,
                f64::INFINITY,
                f64::NEG_INFINITY,
            ),
            |a, p| (a.0.min(p.0), a.1.max(p.0), a.2.min(p.1), a.3.max(p.1)),
        );
        if !(x0.is_finite() && y0.is_finite()) {
            continue;
        }
        let (x1, y1) = (x1.max(x0 + 1e-12), y1.max(y0 + 1e-12));
        let pad = 0.05 * (y1 - y0);
        let mut chart = ChartBuilder::on(area)
            .margin(10)
            .x_label_area_size(35)
            .y_label_area_size(70)
            .build_cartesian_2d(x0..x1, (y0 - pad)..(y1 + 4.0 * pad))
            .map_err(e2s)?;
        chart
            .configure_mesh()
            .light_line_style(BLACK.mix(0.04))
            .x_desc(x_label)
            .y_desc(panel.y_label.as_str())
            .draw()
            .map_err(e2s)?;
        for (i, c) in panel.curves.iter().enumerate() {
            let col = colour(i);
            // NaN (e.g. saturated samples) breaks the line
            let mut segs: Vec<Vec<(f64, f64)>> = vec![Vec::new()];
            for p in &c.points {
                if p.1.is_finite() {
                    segs.last_mut().expect("non-empty").push(*p);
                } else if !segs.last().expect("non-empty").is_empty() {
                    segs.push(Vec::new());
                }
            }
            let mut first = true;
            for s in segs.into_iter().filter(|s| !s.is_empty()) {
                let series = chart
                    .draw_series(LineSeries::new(s, col.stroke_width(1)))
                    .map_err(e2s)?;
                if first {
                    series.label(c.name.as_str()).legend(move |(x, y)| {
                        PathElement::new(vec![(x, y), (x + 18, y)], col.stroke_width(2))
                    });
                    first = false;
                }
            }
        }
        draw_legend(&mut chart, SeriesLabelPosition::UpperRight)?;
    }
    Ok(())
}
