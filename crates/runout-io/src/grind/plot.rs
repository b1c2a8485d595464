//! Plots of the grinding compensation: deviation heat map over (u, α), ε along the edge, and
//! the predicted radial error before / after compensation (SVG or PNG by extension).

use crate::plot::{colour, draw_legend, e2s, PlotError};
use crate::{render_plot, render_svg};
use plotters::coord::Shift;
use plotters::prelude::*;
use runout_core::grind::{Compensation, DeviationMap, EdgeLine};
use std::f64::consts::TAU;
use std::path::Path;

/// Diverging colour for v in [−1, 1]: blue – white – red.
fn diverging(v: f64) -> RGBColor {
    let v = v.clamp(-1.0, 1.0);
    let mix = |a: f64| (255.0 * (1.0 - a)).round() as u8;
    if v >= 0.0 {
        RGBColor(255, mix(v), mix(v))
    } else {
        RGBColor(mix(-v), mix(-v), 255)
    }
}

/// Heat map of the seed deviation δ_ij (µm) over u (mm) and α (deg), methods.md §5.2; each
/// probe point colours the cell reaching halfway to its neighbours (angles wrap).
pub fn deviation_heatmap(path: &Path, map: &DeviationMap) -> Result<(), PlotError> {
    render_plot!(path, (900, 560), |root: &DrawingArea<_, Shift>| draw_heat(
        root, map
    ))
}

/// [`deviation_heatmap`] as an SVG document in memory.
pub fn deviation_heatmap_svg(map: &DeviationMap) -> Result<String, PlotError> {
    render_svg!((900, 560), |root: &DrawingArea<_, Shift>| draw_heat(
        root, map
    ))
}

fn draw_heat<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    map: &DeviationMap,
) -> Result<(), String> {
    root.fill(&WHITE).map_err(e2s)?;
    let u: Vec<f64> = map.u();
    let m = u.len();
    let edges_u: Vec<f64> = (0..=m)
        .map(|i| match i {
            0 => u[0] - 0.5 * (u[1] - u[0]),
            i if i == m => u[m - 1] + 0.5 * (u[m - 1] - u[m - 2]),
            i => 0.5 * (u[i - 1] + u[i]),
        })
        .collect();
    let scale = map.max_abs_delta().max(1e-12);
    let title = format!(
        "bar deviation δ (seed, max |δ| = {:.2} µm; red outward, blue inward)",
        scale * 1e3
    );
    // the map and its colour bar (δ in µm, −max … +max)
    let (width, _) = root.dim_in_pixel();
    let (root, bar) = root.split_horizontally(width.saturating_sub(110));
    draw_deviation_bar(&bar, scale * 1e3)?;
    let root = &root;
    let mut chart = ChartBuilder::on(root)
        .caption(title, ("sans-serif", 18))
        .margin(12)
        .x_label_area_size(40)
        .y_label_area_size(60)
        .build_cartesian_2d(edges_u[0]..edges_u[m], 0.0..360.0)
        .map_err(e2s)?;
    chart
        .configure_mesh()
        .x_desc("u, axial position (mm)")
        .y_desc("probe angle α (deg)")
        .disable_mesh()
        .draw()
        .map_err(e2s)?;
    for (i, l) in map.layers.iter().enumerate() {
        let c = l.alpha.len();
        for j in 0..c {
            let prev = if j == 0 {
                l.alpha[c - 1] - TAU
            } else {
                l.alpha[j - 1]
            };
            let next = if j + 1 == c {
                l.alpha[0] + TAU
            } else {
                l.alpha[j + 1]
            };
            let (lo, hi) = (0.5 * (prev + l.alpha[j]), 0.5 * (l.alpha[j] + next));
            let col = diverging(l.delta[j] / scale);
            // split cells that cross 0°/360°
            for (a0, a1) in [(lo, hi), (lo + TAU, hi + TAU), (lo - TAU, hi - TAU)] {
                let (a0, a1) = (a0.max(0.0).to_degrees(), a1.min(TAU).to_degrees());
                if a1 > a0 {
                    chart
                        .draw_series(std::iter::once(Rectangle::new(
                            [(edges_u[i], a0), (edges_u[i + 1], a1)],
                            col.filled(),
                        )))
                        .map_err(e2s)?;
                }
            }
        }
        chart
            .draw_series(
                l.alpha
                    .iter()
                    .map(|a| Circle::new((l.u, a.to_degrees()), 2, BLACK.filled())),
            )
            .map_err(e2s)?;
    }
    Ok(())
}

/// The colour bar of the deviation heat map: δ from −`max_um` (blue, inward) to +`max_um` (red,
/// outward), labelled `δ (µm)`.
fn draw_deviation_bar<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    max_um: f64,
) -> Result<(), String> {
    let mut chart = ChartBuilder::on(area)
        .margin_top(50)
        .margin_bottom(52)
        .margin_right(8)
        .y_label_area_size(55)
        .caption("δ (µm)", ("sans-serif", 14))
        .build_cartesian_2d(0.0..1.0, -max_um..max_um)
        .map_err(e2s)?;
    chart
        .configure_mesh()
        .disable_mesh()
        .disable_x_axis()
        .draw()
        .map_err(e2s)?;
    let n = 100;
    chart
        .draw_series((0..n).map(|q| {
            let lo = -max_um + 2.0 * max_um * q as f64 / n as f64;
            let hi = -max_um + 2.0 * max_um * (q + 1) as f64 / n as f64;
            let c = diverging(0.5 * (lo + hi) / max_um);
            Rectangle::new([(0.0, lo), (1.0, hi)], c.filled())
        }))
        .map_err(e2s)?;
    Ok(())
}

/// ε (µm) along the edge against u (mm), one line per flute (methods.md §5.3).
pub fn eps_plot(path: &Path, edge: &EdgeLine, comp: &Compensation) -> Result<(), PlotError> {
    let series: Vec<Series> = per_flute(edge, |k| comp.points[k].eps * 1e3)
        .into_iter()
        .enumerate()
        .map(|(i, (f, pts))| (format!("flute {f}"), pts, colour(i)))
        .collect();
    render_plot!(path, (900, 520), |root: &DrawingArea<_, Shift>| {
        draw_lines(root, &series, "deviation ε along the edge", "ε (µm)")
    })
}

/// Predicted radial error (µm) of the finished edge along u: without compensation (−e·n of the
/// fitted axis) and the remaining error with compensation.
pub fn error_plot(path: &Path, edge: &EdgeLine, comp: &Compensation) -> Result<(), PlotError> {
    let mut series = Vec::new();
    for (i, (_, pts)) in per_flute(edge, |k| comp.points[k].before * 1e3)
        .into_iter()
        .enumerate()
    {
        let name = if i == 0 { "before (all flutes)" } else { "" };
        series.push((name.to_string(), pts, RGBColor(214, 39, 40)));
    }
    for (i, (_, pts)) in per_flute(edge, |k| comp.points[k].remaining * 1e3)
        .into_iter()
        .enumerate()
    {
        let name = if i == 0 { "after (all flutes)" } else { "" };
        series.push((name.to_string(), pts, RGBColor(31, 119, 180)));
    }
    let (rb, mb) = comp.before_stats();
    let (ra, ma) = comp.remaining_stats();
    let title = format!(
        "radial error: before rms {:.2} / max {:.2} µm, after rms {:.3} / max {:.3} µm",
        rb * 1e3,
        mb * 1e3,
        ra * 1e3,
        ma * 1e3
    );
    render_plot!(path, (900, 520), |root: &DrawingArea<_, Shift>| {
        draw_lines(root, &series, &title, "radial error (µm)")
    })
}

fn per_flute(edge: &EdgeLine, y: impl Fn(usize) -> f64) -> Vec<(usize, Vec<(f64, f64)>)> {
    let mut out: Vec<(usize, Vec<(f64, f64)>)> = Vec::new();
    for (k, p) in edge.points.iter().enumerate() {
        match out.iter_mut().find(|(f, _)| *f == p.flute) {
            Some((_, v)) => v.push((p.u, y(k))),
            None => out.push((p.flute, vec![(p.u, y(k))])),
        }
    }
    out
}

type Series = (String, Vec<(f64, f64)>, RGBColor);

fn draw_lines<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    series: &[Series],
    title: &str,
    ydesc: &str,
) -> Result<(), String> {
    root.fill(&WHITE).map_err(e2s)?;
    let all = series.iter().flat_map(|s| s.1.iter());
    let (x0, x1, y0, y1) = all.fold(
        (
            f64::INFINITY,
            f64::NEG_INFINITY,
            f64::INFINITY,
            f64::NEG_INFINITY,
        ),
        |(a, b, c, d), (x, y)| (a.min(*x), b.max(*x), c.min(*y), d.max(*y)),
    );
    if !x0.is_finite() {
        return Err("nothing to plot".into());
    }
    let pad = 0.08 * (y1 - y0).max(1e-6);
    let mut chart = ChartBuilder::on(root)
        .caption(title, ("sans-serif", 18))
        .margin(12)
        .x_label_area_size(40)
        .y_label_area_size(60)
        .build_cartesian_2d(x0..x1.max(x0 + 1e-9), (y0 - pad)..(y1 + pad))
        .map_err(e2s)?;
    chart
        .configure_mesh()
        .x_desc("u, axial position (mm)")
        .y_desc(ydesc)
        .draw()
        .map_err(e2s)?;
    let legend = series.len() <= 12;
    for (name, pts, c) in series {
        let c = *c;
        let s = chart
            .draw_series(LineSeries::new(pts.iter().copied(), c.stroke_width(1)))
            .map_err(e2s)?;
        if legend && !name.is_empty() {
            s.label(name.clone()).legend(move |(x, y)| {
                PathElement::new(vec![(x, y), (x + 18, y)], c.stroke_width(2))
            });
        }
    }
    if legend {
        draw_legend(&mut chart, SeriesLabelPosition::UpperRight)?;
    }
    Ok(())
}
