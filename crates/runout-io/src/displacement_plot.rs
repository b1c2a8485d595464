//! Plots of the displacement methods (methods.md §1): polar plot of the per-tooth radii with the
//! runout vector, and runout vs height with the regression line.

use crate::plot::{
    colour, draw_legend, e2s, legend_dot, legend_line, polar_page_xy, tooth_colour, PlotError,
    POLAR_CONVENTION,
};
use crate::{render_plot, render_svg};
use plotters::coord::Shift;
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};
use std::f64::consts::TAU;
use std::path::Path;

/// Data of the polar per-tooth plot. Angles in the spindle frame (rad, direction of rotation,
/// drawn counter-clockwise); deviations in µm relative to their mean.
#[derive(Debug, Clone)]
pub struct TeethPlot {
    /// Angle ψ_i of each tooth (rad).
    pub tooth_angles_rad: Vec<f64>,
    /// Measured radial deviation of each tooth (µm).
    pub measured_um: Vec<f64>,
    /// Deviation predicted by the identified runout (µm), if determined.
    pub model_um: Option<Vec<f64>>,
    /// Identified offset ρ (µm).
    pub offset_um: f64,
    /// Identified angle λ (rad), if determined.
    pub angle_rad: Option<f64>,
    /// Title.
    pub title: String,
}

/// Polar plot: reference circle, measured tooth deviations (points), model deviations (crosses),
/// the first-order radius curve ρ·cos(ψ − λ) and the runout vector (arrow), all in µm. The radius
/// drawn is `base + deviation` with base = 3·max(|dev|, ρ) so that deviations stay visible.
pub fn teeth_polar_plot(path: &Path, d: &TeethPlot) -> Result<(), PlotError> {
    render_plot!(path, (760, 760), |root: &DrawingArea<_, Shift>| draw_teeth(
        root, d
    ))
}

/// [`teeth_polar_plot`] as an SVG document in memory.
pub fn teeth_polar_svg(d: &TeethPlot) -> Result<String, PlotError> {
    render_svg!((760, 760), |root: &DrawingArea<_, Shift>| draw_teeth(
        root, d
    ))
}

fn draw_teeth<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    d: &TeethPlot,
) -> Result<(), String> {
    root.fill(&WHITE).map_err(e2s)?;
    let dev_max = d
        .measured_um
        .iter()
        .chain(d.model_um.iter().flatten())
        .fold(d.offset_um, |m, v| m.max(v.abs()))
        .max(1e-3);
    let base = 3.0 * dev_max;
    let lim = (base + 1.3 * dev_max) * 1.35;
    let mut chart = ChartBuilder::on(root)
        .caption(&d.title, ("sans-serif", 20))
        .margin(12)
        .x_label_area_size(36)
        .y_label_area_size(50)
        .build_cartesian_2d(-lim..lim, -lim..lim)
        .map_err(e2s)?;
    chart
        .configure_mesh()
        .light_line_style(BLACK.mix(0.04))
        .x_desc(format!(
            "µm ({POLAR_CONVENTION}; radius = {base:.2} µm + deviation)"
        ))
        .y_desc("µm")
        .draw()
        .map_err(e2s)?;
    let circle = |r: &dyn Fn(f64) -> f64| -> Vec<(f64, f64)> {
        (0..=360)
            .map(|i| {
                let a = TAU * i as f64 / 360.0;
                polar_page_xy(r(a), a)
            })
            .collect()
    };
    chart
        .draw_series(LineSeries::new(
            circle(&|_| base),
            BLACK.mix(0.4).stroke_width(1),
        ))
        .map_err(e2s)?
        .label("nominal radius")
        .legend(legend_line(BLACK.mix(0.4)));
    if let Some(l) = d.angle_rad {
        let rho = d.offset_um;
        chart
            .draw_series(LineSeries::new(
                circle(&|a| base + rho * (a - l).cos()),
                BLACK.mix(0.6).stroke_width(2),
            ))
            .map_err(e2s)?
            .label(format!(
                "first order ρ·cos(ψ − λ), ρ = {rho:.3} µm, λ = {:.2}°",
                l.to_degrees()
            ))
            .legend(|(x, y)| {
                PathElement::new(vec![(x, y), (x + 18, y)], BLACK.mix(0.6).stroke_width(2))
            });
        let tip = polar_page_xy(rho, l);
        chart
            .draw_series(LineSeries::new(
                vec![(0.0, 0.0), tip],
                colour(3).stroke_width(3),
            ))
            .map_err(e2s)?
            .label("runout vector e (µm, true scale)")
            .legend(|(x, y)| {
                PathElement::new(vec![(x, y), (x + 18, y)], colour(3).stroke_width(3))
            });
        chart
            .draw_series(std::iter::once(Circle::new(tip, 5, colour(3).filled())))
            .map_err(e2s)?;
    }
    let pt = |a: f64, v: f64| polar_page_xy(base + v, a);
    chart
        .draw_series(
            d.tooth_angles_rad
                .iter()
                .zip(&d.measured_um)
                .enumerate()
                .map(|(i, (a, v))| {
                    // each tooth in its colour; the label on the side towards the centre, so
                    // that no label runs off the plot
                    let right = a.sin() > 0.2;
                    let mut style = TextStyle::from(("sans-serif", 14).into_font()).pos(Pos::new(
                        if right { HPos::Right } else { HPos::Left },
                        VPos::Bottom,
                    ));
                    style.color = tooth_colour(i).to_backend_color();
                    EmptyElement::at(pt(*a, *v))
                        + Circle::new((0, 0), 6, tooth_colour(i).filled())
                        + Text::new(
                            format!("tooth {i}: {v:+.3} µm"),
                            (if right { -8 } else { 8 }, -6),
                            style,
                        )
                }),
        )
        .map_err(e2s)?
        .label("measured (tooth tip; tooth colours as in every plot)")
        .legend(legend_dot(tooth_colour(0)));
    if let Some(m) = &d.model_um {
        chart
            .draw_series(
                d.tooth_angles_rad
                    .iter()
                    .zip(m)
                    .map(|(a, v)| Cross::new(pt(*a, *v), 7, BLACK.stroke_width(2))),
            )
            .map_err(e2s)?
            .label("model (exact)")
            .legend(|(x, y)| Cross::new((x + 9, y), 5, BLACK.stroke_width(2)));
    }
    draw_legend(&mut chart, SeriesLabelPosition::LowerRight)?;
    Ok(())
}

/// Data of the runout-vs-height plot (µm, mm).
#[derive(Debug, Clone)]
pub struct HeightPlot {
    /// Measured (z mm, runout µm).
    pub points: Vec<(f64, f64)>,
    /// Fitted line evaluated at (z mm, runout µm), already sampled over the plotted range.
    pub line: Vec<(f64, f64)>,
    /// Name of the line (method).
    pub line_label: String,
    /// Result at the cutting height: (z mm, runout µm, standard error µm).
    pub at: (f64, f64, Option<f64>),
    /// Title.
    pub title: String,
}

/// Runout vs height: measured points, the regression line (extrapolated to the cutting height)
/// and the result with its ±2σ bar.
pub fn height_plot(path: &Path, d: &HeightPlot) -> Result<(), PlotError> {
    render_plot!(path, (900, 560), |root: &DrawingArea<_, Shift>| {
        draw_heights(root, d)
    })
}

/// [`height_plot`] as an SVG document in memory.
pub fn height_svg(d: &HeightPlot) -> Result<String, PlotError> {
    render_svg!((900, 560), |root: &DrawingArea<_, Shift>| draw_heights(
        root, d
    ))
}

fn draw_heights<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    d: &HeightPlot,
) -> Result<(), String> {
    root.fill(&WHITE).map_err(e2s)?;
    let se = d.at.2.unwrap_or(0.0);
    let xs = d
        .points
        .iter()
        .map(|p| p.0)
        .chain(d.line.iter().map(|p| p.0))
        .chain([d.at.0]);
    let ys = d
        .points
        .iter()
        .map(|p| p.1)
        .chain(d.line.iter().map(|p| p.1))
        .chain([d.at.1 - 2.0 * se, d.at.1 + 2.0 * se, 0.0]);
    let (x0, x1) = xs.fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), v| {
        (a.min(v), b.max(v))
    });
    let (y0, y1) = ys.fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), v| {
        (a.min(v), b.max(v))
    });
    let (px, py) = (0.05 * (x1 - x0).max(1e-6), 0.08 * (y1 - y0).max(1e-6));
    let mut chart = ChartBuilder::on(root)
        .caption(&d.title, ("sans-serif", 20))
        .margin(12)
        .x_label_area_size(40)
        .y_label_area_size(60)
        .build_cartesian_2d((x0 - px)..(x1 + px), (y0 - py)..(y1 + py))
        .map_err(e2s)?;
    chart
        .configure_mesh()
        .light_line_style(BLACK.mix(0.04))
        .x_desc("height z (mm)")
        .y_desc("runout r = TIR/2 (µm)")
        .draw()
        .map_err(e2s)?;
    chart
        .draw_series(LineSeries::new(
            d.line.iter().copied(),
            colour(0).stroke_width(2),
        ))
        .map_err(e2s)?
        .label(d.line_label.clone())
        .legend(legend_line(colour(0).stroke_width(2)));
    chart
        .draw_series(
            d.points
                .iter()
                .map(|p| Circle::new(*p, 5, colour(1).filled())),
        )
        .map_err(e2s)?
        .label("measured")
        .legend(legend_dot(colour(1)));
    let (z, r, _) = d.at;
    chart
        .draw_series(LineSeries::new(
            vec![(z, r - 2.0 * se), (z, r + 2.0 * se)],
            colour(3).stroke_width(2),
        ))
        .map_err(e2s)?;
    chart
        .draw_series(std::iter::once(TriangleMarker::new(
            (z, r),
            8,
            colour(3).filled(),
        )))
        .map_err(e2s)?
        .label(format!("z = {z} mm: {r:.3} µm ± 2σ"))
        .legend(|(x, y)| TriangleMarker::new((x + 9, y), 6, colour(3).filled()));
    draw_legend(&mut chart, SeriesLabelPosition::UpperLeft)?;
    Ok(())
}
