//! The grind reports as text (what the CLI prints), plots and the path CSV.

use super::compensate::polar_um;
use super::{CheckReport, CompensateReport};
use anyhow::{Context, Result};
use std::fmt::Write as _;
use std::path::Path;

/// `grind compensate` text.
pub fn compensate_text(r: &CompensateReport) -> String {
    r.answer.text() + &compensate_body(r)
}

fn compensate_body(r: &CompensateReport) -> String {
    let (Some(map), Some(comp)) = (&r.detail.map, &r.detail.compensation) else {
        return String::new();
    };
    let mut s = String::new();
    let ax = &map.axis;
    let [u0, u1] = r.grid.u_range_mm;
    let (o_mag, o_ang, lambda) = polar_um(ax.offset_mm());
    let _ = writeln!(
        s,
        "runout grind compensate: {} layers, u {u0}..{u1} mm, scheme {}, outside range: {}",
        r.grid.layers,
        crate::words::plain(&comp.scheme),
        crate::words::plain(&comp.range)
    );
    for n in &r.grid.notes {
        let _ = writeln!(s, "note: {n}");
    }
    let se = |v: Option<[f64; 2]>, d: usize| {
        v.map_or("n/a".to_string(), |s| {
            format!("± ({:.d$}, {:.d$})", s[0] * 1e3, s[1] * 1e3)
        })
    };
    let _ = writeln!(
        s,
        "bar axis at u = 0: offset ({:.2}, {:.2}) µm {} = {:.2} µm at {:.1}° (runout angle λ {:.1}°)",
        ax.offset[0].value * 1e3,
        ax.offset[1].value * 1e3,
        se(ax.offset_se(), 2),
        o_mag,
        o_ang,
        lambda
    );
    let _ = writeln!(
        s,
        "tilt ({:.3}, {:.3}) µm/mm {}; layer residual rms {:.3} µm",
        ax.tilt[0].value * 1e3,
        ax.tilt[1].value * 1e3,
        se(ax.tilt_se(), 3),
        ax.residual_rms * 1e3
    );
    let _ = writeln!(
        s,
        "layer  u (mm)   max|δ| (µm)  first harmonic (µm)   form rms/max (µm)"
    );
    for (i, l) in map.layers.iter().enumerate() {
        let md = l.delta.iter().fold(0.0f64, |m, d| m.max(d.abs()));
        let _ = writeln!(
            s,
            "{i:>5}  {:>7.3}  {:>11.3}  ({:>7.3}, {:>7.3})    {:.3} / {:.3}",
            l.u,
            md * 1e3,
            l.c * 1e3,
            l.s * 1e3,
            l.form_rms * 1e3,
            l.form_max * 1e3
        );
    }
    let (rb, mb) = comp.before_stats();
    let (ra, ma) = comp.remaining_stats();
    let _ = writeln!(
        s,
        "{} edge points ({} outside the probed range); predicted radial error before rms {:.3} / max {:.3} µm, after rms {:.4} / max {:.4} µm",
        comp.points.len(),
        comp.outside_count(),
        rb * 1e3,
        mb * 1e3,
        ra * 1e3,
        ma * 1e3
    );
    if let Some(n) = &r.nc {
        let _ = writeln!(
            s,
            "NC: {} linear moves, {} offset ({} mapping), {} lines changed → {}",
            n.linear_moves, n.offset_moves, n.mapping, n.changed_lines, n.output
        );
    }
    s
}

/// The compensated path CSV (per point ε, wheel before/after, predicted errors).
pub fn compensate_path_csv(w: impl std::io::Write, r: &CompensateReport) -> Result<()> {
    let (Some(edge), Some(comp)) = (&r.detail.edge, &r.detail.compensation) else {
        return Ok(());
    };
    Ok(runout_io::grind::write_path_csv(w, edge, comp)?)
}

/// Plots of `grind compensate` into `dir` (created): deviation_heatmap, eps_along_edge,
/// radial_error, as `fmt` (svg | png).
pub fn compensate_plots(dir: &Path, fmt: &str, r: &CompensateReport) -> Result<()> {
    let (Some(map), Some(edge), Some(comp)) =
        (&r.detail.map, &r.detail.edge, &r.detail.compensation)
    else {
        return Ok(());
    };
    std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
    let p = |n: &str| dir.join(format!("{n}.{fmt}"));
    runout_io::grind::plot::deviation_heatmap(&p("deviation_heatmap"), map)?;
    runout_io::grind::plot::eps_plot(&p("eps_along_edge"), edge, comp)?;
    runout_io::grind::plot::error_plot(&p("radial_error"), edge, comp)?;
    Ok(())
}

/// `grind check` text.
pub fn check_text(r: &CheckReport) -> String {
    r.answer.text() + &check_body(r)
}

fn check_body(r: &CheckReport) -> String {
    let i = &r.inputs;
    let (off, tilt) = (i.offset_um, i.tilt_um_per_mm);
    let [u0, u1] = i.u_range_mm;
    let mut s = format!(
        "runout grind check: bar D {} mm, offset ({}, {}) µm, tilt ({}, {}) µm/mm, M{}×C{} on u {u0}..{u1} mm, noise {} µm, {} draw(s), {} edge points\n",
        i.bar_diameter_mm, off[0], off[1], tilt[0], tilt[1], i.layers, i.angles, i.noise_um, i.draws, i.edge_points
    );
    s += "                     interp. rms / max (µm)   radius error (µm)   profile error (µm)\n";
    let _ = writeln!(
        s,
        "no compensation      {:>22}   {:>17.3}   {:>18.3}",
        "-", r.uncompensated.radius_error_um, r.uncompensated.profile_error_um
    );
    for (name, c) in [
        ("seed (bilinear)", &r.bilinear),
        ("first harmonic", &r.first_harmonic),
    ] {
        let _ = writeln!(
            s,
            "{name:<19}  {:>10.3} / {:>9.3}   {:>17.3}   {:>18.3}",
            c.interpolation_rms_um,
            c.interpolation_max_um,
            c.radius_error_after_um,
            c.profile_error_after_um
        );
    }
    s
}
