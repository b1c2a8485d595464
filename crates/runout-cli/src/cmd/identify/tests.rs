//! `runout identify tests TABLE`: several per-tooth peak tests (seed 003 Table 1 style) from a
//! CSV or TOML table → per-test sine fits, regressions, K_T/K_R (seed eq. 17), pooled
//! edge-force-aware fit (methods.md §4.4, §4.6).

use super::peaks::{fit_json, peak_angle};
use super::pm;
use crate::output;
use anyhow::{anyhow, bail, Context, Result};
use runout_core::identify::{
    analyse_tests, MultiTestResult, PeakConditions, PeakTest, PooledFit, Regression,
    SineHypothesis, ToothPeaks,
};
use runout_core::MillingMode;
use runout_io::peak_table::read_peak_table;
use runout_io::units::{parse_quantity, Quantity};
use serde_json::json;
use std::path::PathBuf;

/// Arguments of `runout identify tests`.
#[derive(clap::Args, Debug)]
pub struct Args {
    /// Table of tests: CSV/TSV (columns test, fz_mm, ap_mm, peak0_N…, optional se0_N…,
    /// fx_at_peak_N, fy_at_peak_N, diameter_mm, ae_mm, mode) or TOML ([[test]] tables).
    pub table: PathBuf,
    /// Cutter diameter D (mm) for tests whose row does not give it.
    #[arg(long, allow_hyphen_values = true)]
    pub diameter_mm: Option<String>,
    /// Radial depth a_e (mm) for tests whose row does not give it.
    #[arg(long, allow_hyphen_values = true)]
    pub ae_mm: Option<String>,
    /// Milling mode up | down | slot for tests whose row does not give it [default up].
    #[arg(long)]
    pub mode: Option<String>,
    /// Peak immersion angle γ (deg) for all tests (default: from the engagement).
    #[arg(long, allow_hyphen_values = true)]
    pub peak_immersion_deg: Option<String>,
    /// Fit K + 1 points per test with the period closed (reproduces the seed's Table 2).
    #[arg(long)]
    pub closed_period: bool,
    /// Write the JSON result (schema runout.identify.tests/1); `-` for stdout.
    #[arg(long, allow_hyphen_values = true)]
    pub json: Option<PathBuf>,
}

fn q(text: &Option<String>, flag: &str, quantity: Quantity) -> Result<Option<f64>> {
    text.as_deref()
        .map(|t| parse_quantity(t, quantity).with_context(|| format!("--{flag}")))
        .transpose()
}

pub fn run(a: Args) -> Result<()> {
    if let Some(j) = &a.json {
        output::check_not_input(j, &[a.table.as_path()])?;
    }
    let table = read_peak_table(&a.table)?;
    let file = a.table.display().to_string();
    let s = &table.settings;
    let d_flag = q(&a.diameter_mm, "diameter-mm", Quantity::LengthMm)?.or(s.diameter_mm);
    let ae_flag = q(&a.ae_mm, "ae-mm", Quantity::LengthMm)?.or(s.ae_mm);
    let mode_flag = a.mode.clone().or_else(|| s.mode.clone());
    let gamma_flag = q(
        &a.peak_immersion_deg,
        "peak-immersion-deg",
        Quantity::AngleDeg,
    )?
    .or(s.peak_immersion_deg);
    let mut tests = Vec::with_capacity(table.rows.len());
    for r in &table.rows {
        let at = || format!("{file}:{} (test {})", r.line, r.label);
        let k = r.peaks_n.len();
        if let Some(t) = s.teeth {
            if t != k {
                bail!("{}: {k} peaks but teeth = {t}", at());
            }
        }
        let mode: MillingMode = r
            .mode
            .clone()
            .or_else(|| mode_flag.clone())
            .unwrap_or_else(|| "up".into())
            .parse()
            .with_context(at)?;
        let gamma = peak_angle(
            mode,
            r.ae_mm.or(ae_flag),
            r.diameter_mm.or(d_flag),
            gamma_flag,
            r.fz_mm,
            k,
        )
        .with_context(at)?;
        let mut peaks = ToothPeaks::new(r.peaks_n.clone()).with_context(at)?;
        if let Some(se) = &r.peaks_se_n {
            peaks = peaks.with_se(se.clone()).with_context(at)?;
        }
        tests.push(PeakTest {
            label: r.label.clone(),
            ap_mm: r.ap_mm,
            conditions: PeakConditions::new(r.fz_mm, gamma).with_context(at)?,
            peak_immersion_rad: gamma,
            peaks,
            fx_at_peak_n: r.fx_at_peak_n,
            fy_at_peak_n: r.fy_at_peak_n,
        });
    }
    let hyp = if a.closed_period {
        SineHypothesis::ClosedPeriod
    } else {
        SineHypothesis::Teeth
    };
    let res = analyse_tests(&tests, hyp).map_err(|e| anyhow!("{file}: {e}"))?;
    let j = result_json(&res, &file);
    if let Some(p) = &a.json {
        output::write_text(p, &(serde_json::to_string_pretty(&j)? + "\n"))?;
    }
    if a.json.as_deref() != Some(std::path::Path::new("-")) {
        print_text(&res);
    }
    Ok(())
}

fn regression_json(r: &Option<Regression>, slope_unit: &str) -> serde_json::Value {
    match r {
        None => serde_json::Value::Null,
        Some(r) => json!({
            format!("slope_{slope_unit}"): r.slope,
            format!("slope_{slope_unit}_se"): r.slope_se.is_finite().then_some(r.slope_se),
            "intercept_N": r.intercept,
            "intercept_N_se": r.intercept_se.is_finite().then_some(r.intercept_se),
            "with_intercept": r.with_intercept,
            "r_squared": r.r_squared,
            "points": r.n,
        }),
    }
}

fn pooled_json(p: &Option<PooledFit>) -> serde_json::Value {
    match p {
        None => serde_json::Value::Null,
        Some(p) => json!({
            "edge_model": p.edge_model,
            "offset_um": p.offset.value * 1e3,
            "offset_um_se": p.offset.se.map(|s| s * 1e3),
            "angle_deg": p.angle.value.to_degrees(),
            "angle_deg_se": p.angle.se.map(f64::to_degrees),
            "k_lumped_N_per_mm2": p.k_lumped.value,
            "k_lumped_N_per_mm2_se": p.k_lumped.se,
            "constant_N": p.constant_n.map(|e| e.value),
            "constant_N_se": p.constant_n.and_then(|e| e.se),
            "edge_N_per_mm": p.edge_n_per_mm.map(|e| e.value),
            "edge_N_per_mm_se": p.edge_n_per_mm.and_then(|e| e.se),
            "residual_rms_N": p.residual_rms,
            "r_squared": p.r_squared,
            "peaks": p.n,
            "residual_dof": p.dof,
            "condition_number": p.condition,
        }),
    }
}

/// JSON, schema `runout.identify.tests/1`.
fn result_json(r: &MultiTestResult, file: &str) -> serde_json::Value {
    let tests: Vec<serde_json::Value> = r
        .tests
        .iter()
        .enumerate()
        .map(|(i, t)| {
            let mut j = fit_json(
                &t.fit,
                json!({"fz_mm": t.fz_mm, "ap_mm": t.ap_mm,
                       "peak_immersion_deg": t.fit.conditions.sin_gamma.asin().to_degrees()}),
            );
            let o = j.as_object_mut().expect("object");
            o.remove("schema");
            o.remove("method");
            o.insert("label".into(), json!(t.label));
            o.insert("kt_N_per_mm2".into(), json!(t.coefficients.map(|c| c.kt)));
            o.insert("kr_N_per_mm2".into(), json!(t.coefficients.map(|c| c.kr)));
            o.insert("k_N_per_mm2".into(), json!(t.coefficients.map(|c| c.k)));
            o.insert(
                "offset_edge_corrected_um".into(),
                json!(r.edge_corrected_offsets.as_ref().map(|v| v[i] * 1e3)),
            );
            j
        })
        .collect();
    json!({
        "schema": "runout.identify.tests/1",
        "table": file,
        "method": "seed003 per-tooth peak sine fit per test (methods.md 4.2); regressions 4.4; K_T/K_R seed eq. 17 (F_y in the workpiece frame); pooled edge-aware fit 4.6",
        "tests": tests,
        "amplitude_vs_ap": regression_json(&r.amplitude_vs_ap, "N_per_mm"),
        "amplitude_vs_ap_origin": regression_json(&r.amplitude_vs_ap_origin, "N_per_mm"),
        "mean_vs_fz_ap": regression_json(&r.mean_vs_fz_ap, "N_per_mm2"),
        "mean_vs_fz_ap_origin": regression_json(&r.mean_vs_fz_ap_origin, "N_per_mm2"),
        "vector_mean": {"offset_um": r.vector_mean.0 * 1e3, "angle_deg": r.vector_mean.1.to_degrees()},
        "arithmetic_mean": {"offset_um": r.arithmetic_mean.0 * 1e3, "angle_deg": r.arithmetic_mean.1.to_degrees()},
        "pooled_edge_aware": pooled_json(&r.pooled),
        "pooled_no_edge": pooled_json(&r.pooled_no_edge),
    })
}

fn print_text(r: &MultiTestResult) {
    println!("runout identify tests: {} tests", r.tests.len());
    println!("test   f_z mm  a_p mm   C (N)    A (N)   φ (deg)    R²    ρ (µm)      λ (deg)   K_T, K_R (N/mm²)");
    for t in &r.tests {
        let f = &t.fit;
        let k = t
            .coefficients
            .map(|c| format!("{:.1}, {:.1}", c.kt, c.kr))
            .unwrap_or_default();
        println!(
            "{:<6} {:>6.3} {:>7.3} {:>7.2} {:>8.2} {:>8.2} {:>6.3} {:>6.2} {:<8} {:>7.2}   {}",
            t.label,
            t.fz_mm,
            t.ap_mm,
            f.mean.value,
            f.amplitude.value,
            f.phase.value.to_degrees(),
            f.r_squared,
            f.offset.value * 1e3,
            pm(f.offset.se.map(|s| s * 1e3), 2),
            f.angle.value.to_degrees(),
            k
        );
    }
    let line = |name: &str, r: &Option<Regression>, x: &str| {
        if let Some(r) = r {
            println!(
                "{name}: {:.2} {} {:.1}·{x} (R² {:.4}, {} points)",
                r.intercept,
                if r.slope >= 0.0 { "+" } else { "-" },
                r.slope.abs(),
                r.r_squared,
                r.n
            );
        }
    };
    line("A vs a_p (N)", &r.amplitude_vs_ap, "a_p");
    line(
        "A vs a_p through origin (N)",
        &r.amplitude_vs_ap_origin,
        "a_p",
    );
    line("C vs f_z·a_p (N)", &r.mean_vs_fz_ap, "f_z·a_p");
    line(
        "C vs f_z·a_p through origin (N)",
        &r.mean_vs_fz_ap_origin,
        "f_z·a_p",
    );
    println!(
        "runout: vector mean {:.2} µm at {:.2}°; arithmetic means {:.2} µm, {:.2}°",
        r.vector_mean.0 * 1e3,
        r.vector_mean.1.to_degrees(),
        r.arithmetic_mean.0 * 1e3,
        r.arithmetic_mean.1.to_degrees()
    );
    for (name, p) in [
        ("pooled fit, edge force C0 + E·a_p", &r.pooled),
        ("pooled fit, no edge force", &r.pooled_no_edge),
    ] {
        if let Some(p) = p {
            println!(
                "{name}: ρ = {:.2} µm {}, λ = {:.2}° {}, residual rms {:.2} N",
                p.offset.value * 1e3,
                pm(p.offset.se.map(|s| s * 1e3), 2),
                p.angle.value.to_degrees(),
                pm(p.angle.se.map(f64::to_degrees), 2),
                p.residual_rms
            );
        }
    }
    if r.pooled.is_none() {
        println!("(pooled edge-aware fit needs >= 2 distinct feeds and K >= 3)");
    }
}
