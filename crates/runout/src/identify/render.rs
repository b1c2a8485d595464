//! The identify reports as text (what the CLI prints).

use super::{PeaksReport, PooledReport, TestsReport};
use runout_core::identify::SineHypothesis;
use std::fmt::Write;

/// An optional standard error as `± x` with `digits` decimals, or `(no SE)`.
pub fn pm(se: Option<f64>, digits: usize) -> String {
    match se {
        Some(s) if s.is_finite() => format!("± {s:.digits$}"),
        _ => "(no SE)".to_string(),
    }
}

/// `identify peaks` as text.
pub fn peaks(r: &PeaksReport) -> String {
    let f = &r.fit;
    let mut s = String::new();
    let hyp = match f.hypothesis {
        SineHypothesis::Teeth => "K peaks",
        SineHypothesis::ClosedPeriod => "closed period, K + 1 points",
    };
    let _ = writeln!(
        s,
        "runout identify peaks: K = {}, sine fit ({hyp}), peak angle γ = {:.2}°",
        f.inputs.teeth, f.inputs.peak_immersion_deg
    );
    s += "tooth  peak (N)  fitted (N)\n";
    for (i, (p, q)) in f.inputs.peaks_N.iter().zip(&f.fitted_N).enumerate() {
        let _ = writeln!(s, "{i:>5}  {p:>8.2}  {q:>10.2}");
    }
    let _ = writeln!(s, "mean C      {:>9.2} N {}", f.mean_N, pm(f.mean_N_se, 2));
    let _ = writeln!(
        s,
        "amplitude A {:>9.2} N {}",
        f.amplitude_N,
        pm(f.amplitude_N_se, 2)
    );
    let _ = writeln!(
        s,
        "phase φ     {:>9.2}° {}",
        f.phase_deg,
        pm(f.phase_deg_se, 2)
    );
    let _ = writeln!(
        s,
        "R² = {:.4}, residual dof {}",
        f.r_squared, f.residual_dof
    );
    let _ = writeln!(
        s,
        "runout offset ρ = {:.2} µm {}, angle λ = {:.2}° {} (from tooth 0, in the rotation direction)",
        f.offset_um,
        pm(f.offset_um_se, 2),
        f.angle_deg,
        pm(f.angle_deg_se, 2)
    );
    for w in &r.warnings {
        let _ = writeln!(s, "warning: {w}");
    }
    s
}

/// `identify tests` as text.
pub fn tests(r: &TestsReport) -> String {
    let mut s = format!("runout identify tests: {} tests\n", r.tests.len());
    s += "test   f_z mm  a_p mm   C (N)    A (N)   φ (deg)    R²    ρ (µm)      λ (deg)   K_T, K_R (N/mm²)\n";
    for t in &r.tests {
        let f = &t.fit;
        let k = match (t.kt_N_per_mm2, t.kr_N_per_mm2) {
            (Some(kt), Some(kr)) => format!("{kt:.1}, {kr:.1}"),
            _ => String::new(),
        };
        let _ = writeln!(
            s,
            "{:<6} {:>6.3} {:>7.3} {:>7.2} {:>8.2} {:>8.2} {:>6.3} {:>6.2} {:<8} {:>7.2}   {}",
            t.label,
            f.inputs.fz_mm,
            f.inputs.ap_mm,
            f.mean_N,
            f.amplitude_N,
            f.phase_deg,
            f.r_squared,
            f.offset_um,
            pm(f.offset_um_se, 2),
            f.angle_deg,
            k
        );
    }
    let mut line = |name: &str, r: Option<(f64, f64, f64, usize)>, x: &str| {
        if let Some((intercept, slope, r2, n)) = r {
            let sign = if slope >= 0.0 { "+" } else { "-" };
            let _ = writeln!(
                s,
                "{name}: {intercept:.2} {sign} {:.1}·{x} (R² {r2:.4}, {n} points)",
                slope.abs()
            );
        }
    };
    let a = |r: &Option<super::RegressionPerMm>| {
        r.as_ref()
            .map(|r| (r.intercept_N, r.slope_N_per_mm, r.r_squared, r.points))
    };
    let c = |r: &Option<super::RegressionPerMm2>| {
        r.as_ref()
            .map(|r| (r.intercept_N, r.slope_N_per_mm2, r.r_squared, r.points))
    };
    line("A vs a_p (N)", a(&r.amplitude_vs_ap), "a_p");
    line(
        "A vs a_p through origin (N)",
        a(&r.amplitude_vs_ap_origin),
        "a_p",
    );
    line("C vs f_z·a_p (N)", c(&r.mean_vs_fz_ap), "f_z·a_p");
    line(
        "C vs f_z·a_p through origin (N)",
        c(&r.mean_vs_fz_ap_origin),
        "f_z·a_p",
    );
    let _ = writeln!(
        s,
        "runout: vector mean {:.2} µm at {:.2}°; arithmetic means {:.2} µm, {:.2}°",
        r.vector_mean.offset_um,
        r.vector_mean.angle_deg,
        r.arithmetic_mean.offset_um,
        r.arithmetic_mean.angle_deg
    );
    s += &pooled_lines(r);
    s
}

fn pooled_lines(r: &TestsReport) -> String {
    let mut s = String::new();
    let fits: [(&str, &Option<PooledReport>); 2] = [
        ("pooled fit, edge force C0 + E·a_p", &r.pooled_edge_aware),
        ("pooled fit, no edge force", &r.pooled_no_edge),
    ];
    for (name, p) in fits {
        if let Some(p) = p {
            let _ = writeln!(
                s,
                "{name}: ρ = {:.2} µm {}, λ = {:.2}° {}, residual rms {:.2} N",
                p.offset_um,
                pm(p.offset_um_se, 2),
                p.angle_deg,
                pm(p.angle_deg_se, 2),
                p.residual_rms_N
            );
        }
    }
    if r.pooled_edge_aware.is_none() {
        s += "(pooled edge-aware fit needs >= 2 distinct feeds and K >= 3)\n";
    }
    s
}
