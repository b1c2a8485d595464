//! `runout chip compare CONFIG` and `runout chip eval CONFIG`: instantaneous undeformed chip
//! thickness (IUCT) with runout, methods.md §2 — exact (eq. 2.2–2.3), arc (2.5), circle
//! intersection (2.6), equivalent (2.8) on 3-axis and 5-axis kinematics (eq. 2.1).

use crate::output;
use anyhow::{bail, Result};
use runout_core::angle::wrap_tau;
use runout_core::chip::compare::{
    arc_values, equivalent_values, evaluate_models, exact_values, ErrorAccumulator, ErrorMetrics,
    ModelValues, SamplePoint,
};
use runout_core::chip::{
    arc_at, calibration_grid, closed_forms_at, exact_at, fit_compensation, EquivalentParams,
    NewtonOptions, ToolMotion,
};
use runout_io::config::chip::{read_cases, ChipCase};
use runout_io::plot::chip::{chip_angle_plot, chip_map_plot, ChipMap, ToothCurve};
use serde_json::json;
use std::io::Write;
use std::path::{Path, PathBuf};
use std::time::Instant;

/// Arguments of `runout chip`.
#[derive(clap::Args, Debug)]
pub struct Args {
    #[command(subcommand)]
    pub command: ChipCommand,
}

/// `runout chip` subcommands.
#[derive(clap::Subcommand, Debug)]
pub enum ChipCommand {
    /// Compare the arc, circle-intersection and equivalent models against the exact IUCT on a
    /// case set (examples/chip/*.toml): errors and throughput.
    Compare(CompareArgs),
    /// Evaluate the chip thickness h along the motion of one case (3-axis or 5-axis toolpath).
    Eval(EvalArgs),
}

/// Arguments of `runout chip compare`.
#[derive(clap::Args, Debug)]
pub struct CompareArgs {
    /// Case-set file (TOML: [defaults] and [[case]] tables).
    pub config: PathBuf,
    /// Only the cases whose name contains this text.
    #[arg(long)]
    pub case: Option<String>,
    /// Equivalent model without the effective-edge phase refinement (methods.md §2.4).
    #[arg(long)]
    pub no_phase_refinement: bool,
    /// Also fit (k₁, k₂) per case on 12 calibration angles per tooth and report that model.
    #[arg(long)]
    pub fit_k: bool,
    /// Write the JSON result (schema runout.chip.compare/1); `-` for stdout.
    #[arg(long)]
    pub json: Option<PathBuf>,
}

/// Arguments of `runout chip eval`.
#[derive(clap::Args, Debug)]
pub struct EvalArgs {
    /// Case file (TOML, same format as for compare).
    pub config: PathBuf,
    /// Case to evaluate (name contains this text); default the first case.
    #[arg(long)]
    pub case: Option<String>,
    /// Model: exact | equivalent | arc | circle.
    #[arg(long, default_value = "exact")]
    pub model: String,
    /// CSV of h per tooth/height/time (time_s, spindle_angle_deg, tooth, z_mm, h_<model>_mm); `-` for stdout.
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// Plot h (µm) vs spindle angle per tooth at one height (.svg or .png).
    #[arg(long)]
    pub plot: Option<PathBuf>,
    /// Height of the angle plot (mm); default the lowest height of the case.
    #[arg(long)]
    pub plot_height_mm: Option<f64>,
    /// Spindle revolutions shown in the angle plot (count).
    #[arg(long, default_value_t = 2.0)]
    pub plot_revolutions: f64,
    /// Map of the peak h per spindle revolution over path time × height (.svg or .png).
    #[arg(long)]
    pub map: Option<PathBuf>,
    /// Write the JSON summary (schema runout.chip.eval/1); `-` for stdout.
    #[arg(long)]
    pub json: Option<PathBuf>,
}

pub fn run(a: Args) -> Result<()> {
    match a.command {
        ChipCommand::Compare(c) => compare(c),
        ChipCommand::Eval(e) => eval(e),
    }
}

fn select(cases: Vec<ChipCase>, filter: Option<&str>, file: &Path) -> Result<Vec<ChipCase>> {
    let chosen: Vec<ChipCase> = match filter {
        Some(f) => cases.into_iter().filter(|c| c.name.contains(f)).collect(),
        None => cases,
    };
    if chosen.is_empty() {
        bail!(
            "{}: no case matches --case {:?}",
            file.display(),
            filter.unwrap_or("")
        );
    }
    Ok(chosen)
}

/// Points per second of `f` over `n` points: repeated until 50 ms have elapsed.
fn throughput(n: usize, mut f: impl FnMut() -> Vec<f64>) -> f64 {
    let start = Instant::now();
    let mut reps = 0usize;
    while reps < 2 || start.elapsed().as_secs_f64() < 0.05 {
        std::hint::black_box(f());
        reps += 1;
    }
    (n * reps) as f64 / start.elapsed().as_secs_f64()
}

/// Per-model results of one case.
struct CaseResult {
    name: String,
    points: usize,
    metrics: Vec<(&'static str, ErrorMetrics)>,
    rates: [f64; 3],
    fit: Option<runout_core::chip::CompensationFit>,
}

fn fitted_values(
    case: &ChipCase,
    params: &EquivalentParams,
) -> Result<(Vec<f64>, runout_core::chip::CompensationFit)> {
    let kin = &case.kin;
    let t0 = case.points.first().map(|p| p.t).unwrap_or(0.0);
    let calib = calibration_grid(kin, &case.spec.heights_mm, 12, t0);
    let fit = fit_compensation(kin, &calib, params.phase_refinement)
        .map_err(|e| anyhow::anyhow!("case `{}`: fitting (k1, k2): {e}", case.name))?;
    Ok((equivalent_values(kin, &case.points, &fit.params), fit))
}

fn compare_case(
    case: &ChipCase,
    params: &EquivalentParams,
    fit_k: bool,
    pooled: &mut [ErrorAccumulator; 4],
) -> Result<CaseResult> {
    let kin = &case.kin;
    let pts = &case.points;
    let v: ModelValues = evaluate_models(kin, pts, params);
    if v.unconverged > 0 {
        eprintln!(
            "warning: case `{}`: the exact solver missed 1e-12 mm at {} of {} points",
            case.name,
            v.unconverged,
            pts.len()
        );
    }
    let models: [(&'static str, &Vec<f64>); 3] = [
        ("arc", &v.arc),
        ("circle", &v.circle),
        ("equivalent", &v.equivalent),
    ];
    let mut metrics = Vec::new();
    for (q, (name, vals)) in models.iter().enumerate() {
        let mut acc = ErrorAccumulator::default();
        acc.add(vals, &v.exact);
        pooled[q].add(vals, &v.exact);
        metrics.push((*name, acc.metrics()));
    }
    let mut fit = None;
    if fit_k {
        let (vals, f) = fitted_values(case, params)?;
        let mut acc = ErrorAccumulator::default();
        acc.add(&vals, &v.exact);
        pooled[3].add(&vals, &v.exact);
        metrics.push(("equivalent_fitted_k", acc.metrics()));
        fit = Some(f);
    }
    let rates = [
        throughput(pts.len(), || exact_values(kin, pts)),
        throughput(pts.len(), || equivalent_values(kin, pts, params)),
        throughput(pts.len(), || arc_values(kin, pts)),
    ];
    Ok(CaseResult {
        name: case.name.clone(),
        points: pts.len(),
        metrics,
        rates,
        fit,
    })
}

/// The case file and every file its cases name (toolpaths, joint tables; relative to the case
/// file), for the output-is-not-an-input check.
fn case_inputs(config: &Path, cases: &[ChipCase]) -> Vec<PathBuf> {
    let base = config.parent().unwrap_or(Path::new("."));
    let mut v = vec![config.to_path_buf()];
    for c in cases {
        for f in [&c.spec.toolpath, &c.spec.joints].into_iter().flatten() {
            v.push(base.join(f));
        }
    }
    v
}

fn compare(a: CompareArgs) -> Result<()> {
    let cases = select(read_cases(&a.config)?, a.case.as_deref(), &a.config)?;
    if let Some(j) = &a.json {
        let inputs = case_inputs(&a.config, &cases);
        output::check_not_input(j, &inputs.iter().map(|p| p.as_path()).collect::<Vec<_>>())?;
    }
    let params = EquivalentParams {
        phase_refinement: !a.no_phase_refinement,
        ..EquivalentParams::default()
    };
    let mut pooled = [ErrorAccumulator::default(); 4];
    let mut results = Vec::new();
    for c in &cases {
        for w in &c.warnings {
            eprintln!("warning: {w}");
        }
        results.push(compare_case(c, &params, a.fit_k, &mut pooled)?);
    }
    let names = ["arc", "circle", "equivalent", "equivalent_fitted_k"];
    let n_models = if a.fit_k { 4 } else { 3 };
    let pooled: Vec<(&str, ErrorMetrics)> = (0..n_models)
        .map(|q| (names[q], pooled[q].metrics()))
        .collect();
    let total_pts: usize = results.iter().map(|r| r.points).sum();
    let pooled_rate = |q: usize| {
        total_pts as f64
            / results
                .iter()
                .map(|r| r.points as f64 / r.rates[q])
                .sum::<f64>()
    };
    let rates = [pooled_rate(0), pooled_rate(1), pooled_rate(2)];
    if let Some(j) = &a.json {
        let v = compare_json(&a.config, &params, &results, &pooled, rates);
        output::write_text(j, &(serde_json::to_string_pretty(&v)? + "\n"))?;
    }
    if a.json.as_deref() != Some(Path::new("-")) {
        print_compare(&a.config, &params, &results, &pooled, rates);
    }
    Ok(())
}

fn metrics_json(m: &ErrorMetrics) -> serde_json::Value {
    json!({
        "mean_relative_error_percent": m.mean_relative * 100.0,
        "normalised_mae_percent": m.normalised_mae * 100.0,
        "max_abs_error_um": m.max_abs_mm * 1e3,
        "points_in_relative_metric": m.points_relative,
    })
}

fn compare_json(
    config: &Path,
    params: &EquivalentParams,
    results: &[CaseResult],
    pooled: &[(&str, ErrorMetrics)],
    rates: [f64; 3],
) -> serde_json::Value {
    let case = |r: &CaseResult| {
        let mut models = serde_json::Map::new();
        for (name, m) in &r.metrics {
            models.insert(name.to_string(), metrics_json(m));
        }
        json!({
            "name": r.name,
            "points": r.points,
            "errors_vs_exact": models,
            "throughput_points_per_s": {"exact": r.rates[0], "equivalent": r.rates[1], "arc": r.rates[2]},
            "fitted_k": r.fit.map(|f| json!({
                "k1": f.params.k1, "k2": f.params.k2,
                "k1_std_error": f.std_error[0], "k2_std_error": f.std_error[1],
                "condition": f.condition,
                "rms_residual_um": f.rms_residual_mm * 1e3, "calibration_points": f.points,
            })),
        })
    };
    let mut pooled_m = serde_json::Map::new();
    for (name, m) in pooled {
        pooled_m.insert(name.to_string(), metrics_json(m));
    }
    json!({
        "schema": "runout.chip.compare/1",
        "config": config.display().to_string(),
        "metrics": {
            "mean_relative_error": "mean |h_model - h_exact| / h_exact over points with h_exact > 5 % of the case's max h_exact",
            "normalised_mae": "sum |h_model - h_exact| / sum h_exact over all points",
        },
        "equivalent_model": {"k1": params.k1, "k2": params.k2, "phase_refinement": params.phase_refinement},
        "cases": results.iter().map(case).collect::<Vec<_>>(),
        "pooled": pooled_m,
        "throughput_points_per_s": {"exact": rates[0], "equivalent": rates[1], "arc": rates[2],
            "note": "wall time, one thread, all cases pooled; general 3-D kinematics path"},
    })
}

fn print_compare(
    config: &Path,
    params: &EquivalentParams,
    results: &[CaseResult],
    pooled: &[(&str, ErrorMetrics)],
    rates: [f64; 3],
) {
    println!("runout chip compare {}", config.display());
    println!("  A = mean |Δh|/h over points with h_exact > 5 % of max h_exact;  B = normalised MAE Σ|Δh|/Σh");
    println!(
        "  equivalent model: k1 = {}, k2 = {}, phase refinement {}",
        params.k1,
        params.k2,
        if params.phase_refinement { "on" } else { "off" }
    );
    let names: Vec<&str> = pooled.iter().map(|p| p.0).collect();
    print!("{:<34} {:>7}", "case", "points");
    for n in &names {
        print!(" {:>22}", format!("{n} A / B (%)"));
    }
    println!();
    let row = |name: &str, pts: String, ms: &[(&str, ErrorMetrics)]| {
        print!("{name:<34} {pts:>7}");
        for (_, m) in ms {
            print!(
                " {:>22}",
                format!(
                    "{:.3} / {:.3}",
                    m.mean_relative * 100.0,
                    m.normalised_mae * 100.0
                )
            );
        }
        println!();
    };
    for r in results {
        row(&r.name, r.points.to_string(), &r.metrics);
        if let Some(f) = r.fit {
            println!(
                "{:>42} fitted k1 = {:.4} ± {:.4}, k2 = {:.4} ± {:.4} (standard errors; condition {:.1}, rms residual {:.4} µm)",
                "",
                f.params.k1,
                f.std_error[0],
                f.params.k2,
                f.std_error[1],
                f.condition,
                f.rms_residual_mm * 1e3
            );
        }
    }
    let total: usize = results.iter().map(|r| r.points).sum();
    row("pooled", total.to_string(), pooled);
    println!(
        "throughput (points/s, wall time, 1 thread, general 3-D path): exact {:.3e}, equivalent {:.3e} ({:.1}×), arc {:.3e} ({:.1}×)",
        rates[0],
        rates[1],
        rates[1] / rates[0],
        rates[2],
        rates[2] / rates[0]
    );
}

/// h (mm, ≥ 0) of `model` at every point of the case.
fn eval_model(case: &ChipCase, model: &str) -> Result<Vec<f64>> {
    let kin = &case.kin;
    let params = EquivalentParams::default();
    if model == "equivalent" {
        // the bulk evaluator (one look-back per time, shared by teeth and heights)
        return Ok(equivalent_values(kin, &case.points, &params));
    }
    let opts = NewtonOptions::default();
    let mut geo: Option<runout_core::chip::HeightGeometry> = None;
    let mut out = Vec::with_capacity(case.points.len());
    for q in &case.points {
        if geo.as_ref().is_none_or(|g| g.z != q.z) {
            geo = Some(kin.at_height(q.z));
        }
        let g = geo.as_ref().expect("set above");
        let h = match model {
            "exact" => {
                let e = exact_at(kin, g, q.tooth, q.t, &opts);
                if !e.converged {
                    bail!(
                        "exact solver did not converge (tooth {}, z {} mm, t {} s)",
                        q.tooth,
                        q.z,
                        q.t
                    );
                }
                e.raw
            }
            "arc" => arc_at(kin, g, q.tooth, q.t),
            "circle" => closed_forms_at(kin, g, q.tooth, q.t, &params).circle,
            other => bail!("--model: expected exact, equivalent, arc or circle, got `{other}`"),
        };
        out.push(h.max(0.0));
    }
    Ok(out)
}

fn eval(a: EvalArgs) -> Result<()> {
    let case = select(read_cases(&a.config)?, a.case.as_deref(), &a.config)?.remove(0);
    let inputs = case_inputs(&a.config, std::slice::from_ref(&case));
    let inputs: Vec<&Path> = inputs.iter().map(|p| p.as_path()).collect();
    for out in [&a.out, &a.plot, &a.map, &a.json].into_iter().flatten() {
        output::check_not_input(out, &inputs)?;
    }
    if a.plot_revolutions.is_nan() || a.plot_revolutions <= 0.0 {
        bail!(
            "--plot-revolutions: expected a count > 0, got {}",
            a.plot_revolutions
        );
    }
    for w in &case.warnings {
        eprintln!("warning: {w}");
    }
    let h = eval_model(&case, &a.model)?;
    if let Some(out) = &a.out {
        write_eval_csv(out, &case, &a.model, &h)?;
    }
    if let Some(p) = &a.plot {
        let z = plot_height(&case, a.plot_height_mm)?;
        let curves = angle_curves(&case, &h, z, a.plot_revolutions);
        let title = format!("{}: h ({}) at z = {z} mm", case.name, a.model);
        chip_angle_plot(p, &curves, &title)?;
    }
    if let Some(p) = &a.map {
        let map = revolution_map(&case, &h);
        let title = format!("{}: peak h per revolution ({})", case.name, a.model);
        chip_map_plot(p, &map, &title)?;
    }
    let summary = eval_json(&case, &a.model, &h);
    if let Some(j) = &a.json {
        output::write_text(j, &(serde_json::to_string_pretty(&summary)? + "\n"))?;
    }
    let to_stdout = |p: &Option<PathBuf>| p.as_deref() == Some(Path::new("-"));
    if !to_stdout(&a.json) && !to_stdout(&a.out) {
        print_eval(&case, &a.model, &h);
    }
    Ok(())
}

fn spindle_deg<M: ToolMotion>(kin: &runout_core::chip::ToolKinematics<M>, t: f64) -> f64 {
    wrap_tau(kin.spindle_angle(t)).to_degrees()
}

fn write_eval_csv(dest: &Path, case: &ChipCase, model: &str, h: &[f64]) -> Result<()> {
    let mut w = output::create(dest)?;
    writeln!(w, "time_s,spindle_angle_deg,tooth,z_mm,h_{model}_mm")?;
    for (q, v) in case.points.iter().zip(h) {
        writeln!(
            w,
            "{:.9},{:.4},{},{},{:.9}",
            q.t,
            spindle_deg(&case.kin, q.t),
            q.tooth,
            q.z,
            v
        )?;
    }
    w.flush()?;
    Ok(())
}

fn plot_height(case: &ChipCase, want: Option<f64>) -> Result<f64> {
    let hs = &case.spec.heights_mm;
    Ok(match want {
        None => hs.iter().copied().fold(f64::INFINITY, f64::min),
        Some(z) => *hs
            .iter()
            .find(|h| (**h - z).abs() < 1e-9)
            .ok_or_else(|| anyhow::anyhow!("--plot-height-mm {z}: not one of heights_mm {hs:?}"))?,
    })
}

/// h (µm) vs unwrapped spindle angle (deg) per tooth at height `z`, first `revs` revolutions.
fn angle_curves(case: &ChipCase, h: &[f64], z: f64, revs: f64) -> Vec<ToothCurve> {
    let kin = &case.kin;
    let t_end = case.points.first().map(|p| p.t).unwrap_or(0.0) + revs * kin.period();
    let theta0 = case
        .points
        .first()
        .map(|p| kin.spindle_angle(p.t))
        .unwrap_or(0.0);
    let base = (wrap_tau(theta0) - theta0).to_degrees();
    (0..kin.cutter().teeth())
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
        .collect()
}

/// Peak h (µm) over teeth and samples within each spindle revolution, per height.
fn revolution_map(case: &ChipCase, h: &[f64]) -> ChipMap {
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
    ChipMap {
        time_s: (0..bins).map(|b| t0 + (b as f64 + 0.5) * period).collect(),
        height_mm: heights,
        values,
    }
}

fn per_tooth_max(case: &ChipCase, h: &[f64]) -> Vec<f64> {
    let mut m = vec![0.0f64; case.kin.cutter().teeth()];
    for (q, v) in case.points.iter().zip(h) {
        m[q.tooth] = m[q.tooth].max(*v);
    }
    m
}

fn eval_json(case: &ChipCase, model: &str, h: &[f64]) -> serde_json::Value {
    let s = &case.spec;
    json!({
        "schema": "runout.chip.eval/1",
        "case": case.name,
        "model": model,
        "motion": s.motion,
        "teeth": s.teeth,
        "diameter_mm": s.diameter_mm,
        "rpm": s.rpm,
        "runout_um": s.runout_um,
        "runout_angle_deg": s.runout_angle_deg,
        "heights_mm": s.heights_mm,
        "points": h.len(),
        "max_h_um_per_tooth": per_tooth_max(case, h).iter().map(|v| v * 1e3).collect::<Vec<_>>(),
        "warnings": case.warnings,
    })
}

fn print_eval(case: &ChipCase, model: &str, h: &[f64]) {
    println!(
        "runout chip eval: case `{}`, model {model}, motion {}, {} points ({} teeth × {} heights × {} times)",
        case.name,
        case.spec.motion,
        h.len(),
        case.kin.cutter().teeth(),
        case.spec.heights_mm.len(),
        h.len() / (case.kin.cutter().teeth() * case.spec.heights_mm.len()).max(1)
    );
    println!("tooth  max h (µm)");
    for (i, m) in per_tooth_max(case, h).iter().enumerate() {
        println!("{i:>5}  {:>10.3}", m * 1e3);
    }
}
