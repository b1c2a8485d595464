//! The chip reports as text (what the CLI prints), CSV and plots.

use super::eval::per_tooth_max;
use super::{CompareReport, EvalReport};
use anyhow::{Context, Result};
use runout_core::angle::wrap_tau;
use runout_core::chip::compare::SamplePoint;
use runout_io::config::chip::ChipCase;
use runout_io::plot::chip::{chip_angle_plot, chip_map_plot, ChipMap, ToothCurve};
use std::fmt::Write as _;
use std::path::Path;

/// `chip compare` text.
pub fn compare_text(r: &CompareReport) -> String {
    let mut s = String::new();
    let p = &r.equivalent_model;
    let _ = writeln!(s, "runout chip compare {}", r.config);
    s += "  A = mean |Δh|/h over points with h_exact > 5 % of max h_exact;  B = normalised MAE Σ|Δh|/Σh\n";
    let _ = writeln!(
        s,
        "  equivalent model: k1 = {}, k2 = {}, phase refinement {}",
        p.k1,
        p.k2,
        if p.phase_refinement { "on" } else { "off" }
    );
    let pooled = r.pooled.list();
    let _ = write!(s, "{:<34} {:>7}", "case", "points");
    for (n, _) in &pooled {
        let _ = write!(s, " {:>22}", format!("{n} A / B (%)"));
    }
    s.push('\n');
    let row = |s: &mut String, name: &str, pts: String, ms: &[(&str, &super::Metrics)]| {
        let _ = write!(s, "{name:<34} {pts:>7}");
        for (_, m) in ms {
            let _ = write!(
                s,
                " {:>22}",
                format!(
                    "{:.3} / {:.3}",
                    m.mean_relative_error_percent, m.normalised_mae_percent
                )
            );
        }
        s.push('\n');
    };
    for c in &r.cases {
        row(
            &mut s,
            &c.name,
            c.points.to_string(),
            &c.errors_vs_exact.list(),
        );
        if let Some(f) = &c.fitted_k {
            let _ = writeln!(
                s,
                "{:>42} fitted k1 = {:.4} ± {:.4}, k2 = {:.4} ± {:.4} (standard errors; condition {:.1}, rms residual {:.4} µm)",
                "", f.k1, f.k1_std_error, f.k2, f.k2_std_error, f.condition, f.rms_residual_um
            );
        }
    }
    let total: usize = r.cases.iter().map(|c| c.points).sum();
    row(&mut s, "pooled", total.to_string(), &pooled);
    let t = &r.throughput_points_per_s;
    let _ = writeln!(
        s,
        "throughput (points/s, wall time, 1 thread, general 3-D path): exact {:.3e}, equivalent {:.3e} ({:.1}×), arc {:.3e} ({:.1}×)",
        t.exact,
        t.equivalent,
        t.equivalent / t.exact,
        t.arc,
        t.arc / t.exact
    );
    s
}

fn case_of(r: &EvalReport) -> Result<&ChipCase> {
    r.detail.case.as_ref().context("no case in the report")
}

/// `chip eval` text.
pub fn eval_text(r: &EvalReport) -> String {
    let Ok(case) = case_of(r) else {
        return String::new();
    };
    let h = &r.detail.h_mm;
    let teeth = case.kin.cutter().teeth();
    let mut s = format!(
        "runout chip eval: case `{}`, model {}, motion {}, {} points ({} teeth × {} heights × {} times)\n",
        case.name,
        r.model,
        case.spec.motion.name(),
        h.len(),
        teeth,
        case.spec.heights_mm.len(),
        h.len() / (teeth * case.spec.heights_mm.len()).max(1)
    );
    s += "tooth  max h (µm)\n";
    for (i, m) in per_tooth_max(case, h).iter().enumerate() {
        let _ = writeln!(s, "{i:>5}  {:>10.3}", m * 1e3);
    }
    s
}

/// The h CSV: `time_s, spindle_angle_deg, tooth, z_mm, h_<model>_mm`.
pub fn eval_csv(mut w: impl std::io::Write, r: &EvalReport) -> Result<()> {
    let case = case_of(r)?;
    writeln!(w, "time_s,spindle_angle_deg,tooth,z_mm,h_{}_mm", r.model)?;
    for (q, v) in case.points.iter().zip(&r.detail.h_mm) {
        writeln!(
            w,
            "{:.9},{:.4},{},{},{:.9}",
            q.t,
            wrap_tau(case.kin.spindle_angle(q.t)).to_degrees(),
            q.tooth,
            q.z,
            v
        )?;
    }
    w.flush()?;
    Ok(())
}

/// h (µm) vs spindle angle per tooth at height `height_mm` (default the lowest), first
/// `revolutions` revolutions.
pub fn eval_angle_plot(
    path: &Path,
    r: &EvalReport,
    height_mm: Option<f64>,
    revolutions: f64,
) -> Result<()> {
    let case = case_of(r)?;
    let hs = &case.spec.heights_mm;
    let z = match height_mm {
        None => hs.iter().copied().fold(f64::INFINITY, f64::min),
        Some(z) => *hs.iter().find(|h| (**h - z).abs() < 1e-9).ok_or_else(|| {
            anyhow::anyhow!(
                "--plot-height-mm {}: not one of heights_mm {hs:?}",
                runout_core::limits::show(z)
            )
        })?,
    };
    let kin = &case.kin;
    let h = &r.detail.h_mm;
    let t_end = case.points.first().map(|p| p.t).unwrap_or(0.0) + revolutions * kin.period();
    let theta0 = case
        .points
        .first()
        .map(|p| kin.spindle_angle(p.t))
        .unwrap_or(0.0);
    let base = (wrap_tau(theta0) - theta0).to_degrees();
    let curves: Vec<ToothCurve> = (0..kin.cutter().teeth())
        .map(|tooth| ToothCurve {
            tooth,
            points: case
                .points
                .iter()
                .zip(h)
                .filter(|(q, _)| q.tooth == tooth && q.z == z && q.t <= t_end)
                .map(|(q, v)| (kin.spindle_angle(q.t).to_degrees() + base, v * 1e3))
                .collect(),
        })
        .collect();
    let title = format!("{}: h ({}) at z = {z} mm", case.name, r.model);
    Ok(chip_angle_plot(path, &curves, &title)?)
}

/// Map of the peak h (µm) over teeth and samples within each spindle revolution, per height.
pub fn eval_map_plot(path: &Path, r: &EvalReport) -> Result<()> {
    let case = case_of(r)?;
    let h = &r.detail.h_mm;
    let period = case.kin.period();
    let heights = {
        let mut v = case.spec.heights_mm.clone();
        v.sort_by(f64::total_cmp);
        v.dedup();
        v
    };
    let t0 = case.points.first().map(|p| p.t).unwrap_or(0.0);
    let bin = |q: &SamplePoint| ((q.t - t0) / period).floor().max(0.0) as usize;
    let bins = case.points.iter().map(bin).max().unwrap_or(0) + 1;
    let mut values = vec![vec![0.0f64; heights.len()]; bins];
    for (q, v) in case.points.iter().zip(h) {
        let iy = heights.iter().position(|z| *z == q.z).unwrap_or(0);
        let cell = &mut values[bin(q)][iy];
        *cell = cell.max(v * 1e3);
    }
    let map = ChipMap {
        time_s: (0..bins).map(|b| t0 + (b as f64 + 0.5) * period).collect(),
        height_mm: heights,
        values,
    };
    let title = format!("{}: peak h per revolution ({})", case.name, r.model);
    Ok(chip_map_plot(path, &map, &title)?)
}
