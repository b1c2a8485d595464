//! Plots of a force-based runout identification: measured vs predicted waveforms, per-tooth peaks
//! with the fitted sine, and the runout vector with its uncertainty in polar form.

use super::{colour, draw_legend, e2s, legend_line, PlotError};
use crate::plot::tooth_colour;
use crate::{render_plot, render_svg};
use plotters::coord::Shift;
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};
use std::path::Path;

/// One named curve over the spindle angle (deg).
#[derive(Debug, Clone, Copy)]
pub struct Curve<'a> {
    /// Legend label (with unit).
    pub label: &'a str,
    /// Values (N).
    pub values: &'a [f64],
}

/// Measured and predicted force waveforms over one revolution. `measured[i]` is drawn solid in
/// the palette colour [`colour`]`(i)`, `predicted[i]` dashed in [`predicted_colour`]`(i)` (a
/// darker shade of the same hue), and each legend entry shows the colour of its trace.
pub fn waveform_overlay(
    path: &Path,
    angle_deg: &[f64],
    measured: &[Curve],
    predicted: &[Curve],
    title: &str,
) -> Result<(), PlotError> {
    render_plot!(path, (1100, 620), |root: &DrawingArea<_, Shift>| {
        draw_overlay(root, angle_deg, measured, predicted, title)
    })
}

/// [`waveform_overlay`] as an SVG document in memory.
pub fn waveform_overlay_svg(
    angle_deg: &[f64],
    measured: &[Curve],
    predicted: &[Curve],
    title: &str,
) -> Result<String, PlotError> {
    render_svg!((1100, 620), |root: &DrawingArea<_, Shift>| {
        draw_overlay(root, angle_deg, measured, predicted, title)
    })
}

/// [`tooth_peak_bars`] as an SVG document in memory.
pub fn tooth_peak_bars_svg(
    peaks: &[f64],
    peak_se: &[f64],
    mean: f64,
    amplitude: f64,
    phase_rad: f64,
    title: &str,
) -> Result<String, PlotError> {
    render_svg!((800, 520), |root: &DrawingArea<_, Shift>| draw_bars(
        root,
        peaks,
        peak_se,
        (mean, amplitude, phase_rad),
        title
    ))
}

/// [`runout_polar`] as an SVG document in memory.
pub fn runout_polar_svg(
    marks: &[RunoutMark],
    teeth: usize,
    title: &str,
) -> Result<String, PlotError> {
    render_svg!((640, 640), |root: &DrawingArea<_, Shift>| draw_polar(
        root, marks, teeth, title
    ))
}

/// Colour of the predicted trace `i` of [`waveform_overlay`]: [`colour`]`(i)` with each channel
/// scaled by 0.6 (same hue, darker), so that a predicted component is told apart from its
/// measured one yet matched to it.
pub fn predicted_colour(i: usize) -> RGBColor {
    let RGBColor(r, g, b) = colour(i);
    let dark = |v: u8| (f64::from(v) * 0.6).round() as u8;
    RGBColor(dark(r), dark(g), dark(b))
}

fn draw_overlay<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    x: &[f64],
    measured: &[Curve],
    predicted: &[Curve],
    title: &str,
) -> Result<(), String> {
    root.fill(&WHITE).map_err(e2s)?;
    let all = measured
        .iter()
        .chain(predicted)
        .flat_map(|c| c.values.iter().copied());
    let (lo, hi) = all.fold((0.0f64, 0.0f64), |(l, h), v| (l.min(v), h.max(v)));
    let span = (hi - lo).max(1e-9);
    let x0 = x.first().copied().unwrap_or(0.0);
    let x1 = x.last().copied().unwrap_or(360.0).max(x0 + 1e-9);
    let mut chart = ChartBuilder::on(root)
        .caption(title, ("sans-serif", 22))
        .margin(12)
        .x_label_area_size(40)
        .y_label_area_size(60)
        .build_cartesian_2d(x0..x1, (lo - 0.05 * span)..(hi + 0.35 * span))
        .map_err(e2s)?;
    chart
        .configure_mesh()
        .light_line_style(BLACK.mix(0.04))
        .x_desc("spindle angle (deg)")
        .y_desc("force (N)")
        .draw()
        .map_err(e2s)?;
    for (i, c) in measured.iter().enumerate() {
        let col = colour(i);
        chart
            .draw_series(LineSeries::new(
                x.iter().copied().zip(c.values.iter().copied()),
                col.stroke_width(2),
            ))
            .map_err(e2s)?
            .label(format!("{} measured", c.label))
            .legend(legend_line(col.stroke_width(2)));
    }
    for (i, c) in predicted.iter().enumerate() {
        let col = predicted_colour(i);
        chart
            .draw_series(DashedLineSeries::new(
                x.iter().copied().zip(c.values.iter().copied()),
                7,
                4,
                col.stroke_width(2),
            ))
            .map_err(e2s)?
            .label(format!("{} predicted", c.label))
            .legend(legend_line(col.stroke_width(2)));
    }
    draw_legend(&mut chart, SeriesLabelPosition::UpperRight)?;
    Ok(())
}

/// Per-tooth peaks as bars with ±1 standard-error whiskers and the fitted sine
/// F(i) = C + A·sin(φ + 2πi/K) drawn continuously over i.
pub fn tooth_peak_bars(
    path: &Path,
    peaks: &[f64],
    peak_se: &[f64],
    mean: f64,
    amplitude: f64,
    phase_rad: f64,
    title: &str,
) -> Result<(), PlotError> {
    render_plot!(path, (800, 520), |root: &DrawingArea<_, Shift>| draw_bars(
        root,
        peaks,
        peak_se,
        (mean, amplitude, phase_rad),
        title
    ))
}

fn draw_bars<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    peaks: &[f64],
    se: &[f64],
    fit: (f64, f64, f64),
    title: &str,
) -> Result<(), String> {
    root.fill(&WHITE).map_err(e2s)?;
    let k = peaks.len().max(1);
    let (c, a, phi) = fit;
    let sine = |x: f64| c + a * (phi + std::f64::consts::TAU * x / k as f64).sin();
    let hi = peaks
        .iter()
        .zip(se.iter().chain(std::iter::repeat(&0.0)))
        .map(|(p, s)| p + s)
        .fold(c + a.abs(), f64::max);
    let mut chart = ChartBuilder::on(root)
        .caption(title, ("sans-serif", 20))
        .margin(12)
        .x_label_area_size(40)
        .y_label_area_size(60)
        .build_cartesian_2d(-0.6..(k as f64 - 0.4), 0.0..hi * 1.15)
        .map_err(e2s)?;
    chart
        .configure_mesh()
        .light_line_style(BLACK.mix(0.04))
        .x_desc("tooth (cutting order)")
        .y_desc("peak force (N)")
        .x_labels(k)
        .x_label_formatter(&|v| format!("{:.0}", v))
        .draw()
        .map_err(e2s)?;
    chart
        .draw_series(peaks.iter().enumerate().map(|(i, p)| {
            Rectangle::new(
                [(i as f64 - 0.3, 0.0), (i as f64 + 0.3, *p)],
                colour(0).mix(0.6).filled(),
            )
        }))
        .map_err(e2s)?
        .label("measured peak (mean over revolutions)")
        .legend(|(x, y)| {
            Rectangle::new([(x, y - 5), (x + 14, y + 5)], colour(0).mix(0.6).filled())
        });
    for (i, (p, s)) in peaks.iter().zip(se).enumerate() {
        let x = i as f64;
        chart
            .draw_series(std::iter::once(PathElement::new(
                vec![(x, p - s), (x, p + s)],
                BLACK.stroke_width(2),
            )))
            .map_err(e2s)?;
    }
    let n = 200;
    let xs = (0..=n).map(|j| -0.5 + (k as f64) * j as f64 / n as f64);
    chart
        .draw_series(LineSeries::new(
            xs.map(|x| (x, sine(x))),
            colour(3).stroke_width(2),
        ))
        .map_err(e2s)?
        .label(format!(
            "fit C + A·sin(φ + 2πi/K): C {c:.1} N, A {a:.1} N, φ {:.1}°",
            phi.to_degrees()
        ))
        .legend(legend_line(colour(3).stroke_width(2)));
    draw_legend(&mut chart, SeriesLabelPosition::LowerRight)?;
    Ok(())
}

/// A runout estimate to draw in polar form: the vector (µm, deg from tooth 0 in the rotation
/// direction) with its 1-σ uncertainty region (offset ± σ_ρ, angle ± σ_λ).
#[derive(Debug, Clone, Copy)]
pub struct RunoutMark<'a> {
    /// Label (method name).
    pub label: &'a str,
    /// Offset ρ (µm).
    pub offset_um: f64,
    /// Angle λ (deg).
    pub angle_deg: f64,
    /// Standard error of ρ (µm); NaN if unknown.
    pub offset_um_se: f64,
    /// Standard error of λ (deg); NaN if unknown.
    pub angle_deg_se: f64,
}

/// Polar plot of runout vectors with their uncertainty sectors; tooth directions marked.
pub fn runout_polar(
    path: &Path,
    marks: &[RunoutMark],
    teeth: usize,
    title: &str,
) -> Result<(), PlotError> {
    render_plot!(path, (640, 640), |root: &DrawingArea<_, Shift>| draw_polar(
        root, marks, teeth, title
    ))
}

fn draw_polar<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    marks: &[RunoutMark],
    teeth: usize,
    title: &str,
) -> Result<(), String> {
    root.fill(&WHITE).map_err(e2s)?;
    let rmax = marks
        .iter()
        .map(|m| {
            m.offset_um
                + if m.offset_um_se.is_finite() {
                    m.offset_um_se
                } else {
                    0.0
                }
        })
        .fold(1.0, f64::max)
        * 1.25;
    let mut chart = ChartBuilder::on(root)
        .caption(title, ("sans-serif", 20))
        .margin(20)
        .build_cartesian_2d(-rmax..rmax, -rmax..rmax)
        .map_err(e2s)?;
    // Spindle frame drawn with tooth 0 up and the rotation direction clockwise on the page.
    let to_xy = |r: f64, deg: f64| super::polar_page_xy(r, deg.to_radians());
    chart
        .draw_series(std::iter::once(Text::new(
            super::POLAR_CONVENTION,
            (-rmax * 0.97, rmax * 0.97),
            ("sans-serif", 12),
        )))
        .map_err(e2s)?;
    // ring spacing: a round number giving 3–6 rings
    let step = crate::plot::polar_ring_step(rmax);
    let rings = (rmax / step).floor() as usize;
    for ring in 1..=rings {
        let r = step * ring as f64;
        let pts: Vec<(f64, f64)> = (0..=120).map(|j| to_xy(r, 3.0 * j as f64)).collect();
        chart
            .draw_series(std::iter::once(PathElement::new(pts, BLACK.mix(0.2))))
            .map_err(e2s)?;
        let (x, y) = to_xy(r, 0.0);
        chart
            .draw_series(std::iter::once(Text::new(
                format!("{r:.1} µm"),
                (x + rmax * 0.01, y),
                ("sans-serif", 12),
            )))
            .map_err(e2s)?;
    }
    for i in 0..teeth.max(1) {
        let deg = -360.0 * i as f64 / teeth.max(1) as f64;
        let end = to_xy(rmax * 0.95, deg);
        chart
            .draw_series(std::iter::once(PathElement::new(
                vec![(0.0, 0.0), end],
                BLACK.mix(0.35),
            )))
            .map_err(e2s)?;
        // anchored towards the centre so that no label runs off the plot
        let h = if end.0 > 0.3 * rmax {
            HPos::Right
        } else if end.0 < -0.3 * rmax {
            HPos::Left
        } else {
            HPos::Center
        };
        let v = if end.1 > 0.3 * rmax {
            VPos::Top
        } else if end.1 < -0.3 * rmax {
            VPos::Bottom
        } else {
            VPos::Center
        };
        let mut style = TextStyle::from(("sans-serif", 13).into_font()).pos(Pos::new(h, v));
        style.color = tooth_colour(i).to_backend_color();
        chart
            .draw_series(std::iter::once(Text::new(format!("tooth {i}"), end, style)))
            .map_err(e2s)?;
    }
    for (q, m) in marks.iter().enumerate() {
        let col = colour(q + 3);
        if m.offset_um_se.is_finite() && m.angle_deg_se.is_finite() {
            let (r0, r1) = (
                (m.offset_um - m.offset_um_se).max(0.0),
                m.offset_um + m.offset_um_se,
            );
            let (a0, a1) = (m.angle_deg - m.angle_deg_se, m.angle_deg + m.angle_deg_se);
            let mut pts: Vec<(f64, f64)> = (0..=40)
                .map(|j| to_xy(r1, a0 + (a1 - a0) * j as f64 / 40.0))
                .collect();
            pts.extend(
                (0..=40)
                    .rev()
                    .map(|j| to_xy(r0, a0 + (a1 - a0) * j as f64 / 40.0)),
            );
            chart
                .draw_series(std::iter::once(Polygon::new(pts, col.mix(0.25).filled())))
                .map_err(e2s)?;
        }
        let tip = to_xy(m.offset_um, m.angle_deg);
        chart
            .draw_series(std::iter::once(PathElement::new(
                vec![(0.0, 0.0), tip],
                col.stroke_width(3),
            )))
            .map_err(e2s)?
            .label(format!(
                "{}: ρ {:.2} µm at λ {:.1}°",
                m.label, m.offset_um, m.angle_deg
            ))
            .legend(legend_line(col.stroke_width(3)));
        chart
            .draw_series(std::iter::once(Circle::new(tip, 4, col.filled())))
            .map_err(e2s)?;
    }
    draw_legend(&mut chart, SeriesLabelPosition::LowerLeft)?;
    Ok(())
}
