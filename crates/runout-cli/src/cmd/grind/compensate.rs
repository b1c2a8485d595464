//! `runout grind compensate`: bar clamping-error compensation for end-mill grinding (seed 004,
//! methods.md §5). Reads the probe table, builds the deviation map and fitted bar axis,
//! interpolates ε onto the edge, offsets the wheel path (CSV) and/or rewrites an NC program.

use super::{edge, q, read, EdgeFlags};
use crate::output;
use anyhow::{bail, Context, Result};
use runout_core::angle::wrap_deg180;
use runout_core::grind::*;
use runout_io::gcode::{NcProgram, RewriteOptions};
use runout_io::units::Quantity;
use serde_json::json;
use std::path::{Path, PathBuf};

/// Flags of `runout grind compensate`.
#[derive(clap::Args, Debug)]
pub struct CompensateArgs {
    /// Probe table (CSV): `layer` and/or `u_mm`, `angle_deg`, and `radius_mm` or `x_mm,y_mm[,z_mm]`.
    #[arg(long)]
    pub probe: PathBuf,
    /// Sense of the probe table's `angle_deg`, seen from the shank looking at the tip: ccw (the
    /// bar frame: right-handed about the axis towards the shank) | cw (negated on reading; only
    /// `angle_deg` is affected, x/y columns are taken as bar-frame coordinates).
    #[arg(long, default_value = "ccw")]
    pub probe_angle_sense: String,
    /// Nominal bar diameter (mm) for a cylindrical generatrix.
    #[arg(long, allow_hyphen_values = true)]
    pub bar_diameter_mm: Option<String>,
    /// Nominal generatrix table (CSV with `u_mm,radius_mm`) instead of a cylinder.
    #[arg(long)]
    pub generatrix: Option<PathBuf>,
    /// Probe-tip radius (mm) to compensate: Q = tip centre − r·N. 0 if already compensated.
    #[arg(long, allow_hyphen_values = true)]
    pub probe_tip_radius_mm: Option<String>,
    /// A radius farther than this from nominal is a probe miss (µm).
    #[arg(long, allow_hyphen_values = true, default_value = "200")]
    pub miss_limit_um: String,
    /// Duplicate grid points: error | average.
    #[arg(long, default_value = "error")]
    pub duplicates: String,
    /// Missing grid points: error | skip.
    #[arg(long, default_value = "error")]
    pub missing: String,
    /// Interpolation: first-harmonic (exact for offset + tilt) | bilinear (the seed's).
    #[arg(long, default_value = "first-harmonic")]
    pub scheme: String,
    /// Outside the probed u range: clamp | extrapolate.
    #[arg(long, default_value = "clamp")]
    pub outside: String,
    #[command(flatten)]
    pub edge: EdgeFlags,
    /// Input NC program (ISO G-code) whose linear moves are offset.
    #[arg(long)]
    pub nc: Option<PathBuf>,
    /// Output NC program (must not be an input file).
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// NC block ↔ offset mapping: `index` (k-th move ↔ k-th edge point) or `xyz` (the move's
    /// X Y Z is a bar-frame point: u = Z, α = atan2(Y, X); rotary axes must stay constant).
    #[arg(long, default_value = "index")]
    pub nc_map: String,
    /// Which NC moves are offset: feed (G1 only) | all (G0 and G1).
    #[arg(long, default_value = "feed")]
    pub nc_moves: String,
    /// Minimum decimals written in rewritten NC coordinates (4 = 0.1 µm).
    #[arg(long, default_value = "4")]
    pub nc_decimals: usize,
    /// Write the compensated path CSV (per point ε_um, wheel before/after, predicted errors); `-` for stdout.
    #[arg(long)]
    pub path_out: Option<PathBuf>,
    /// Write the JSON report; `-` for stdout.
    #[arg(long)]
    pub json: Option<PathBuf>,
    /// Directory for plots: deviation_heatmap, eps_along_edge, radial_error.
    #[arg(long)]
    pub plots: Option<PathBuf>,
    /// Plot format: svg | png.
    #[arg(long, default_value = "svg")]
    pub plot_format: String,
}

fn generatrix(a: &CompensateArgs) -> Result<Generatrix> {
    match (&a.generatrix, &a.bar_diameter_mm) {
        (Some(_), Some(_)) => bail!("give --bar-diameter-mm or --generatrix, not both"),
        (None, None) => {
            bail!("give the nominal bar: --bar-diameter-mm D or --generatrix table.csv")
        }
        (None, Some(d)) => Ok(Generatrix::cylinder(
            q("bar-diameter-mm", d, Quantity::LengthMm)? / 2.0,
        )?),
        (Some(p), None) => {
            let text = read(p, "generatrix")?;
            let mut rdr = csv::ReaderBuilder::new()
                .comment(Some(b'#'))
                .trim(csv::Trim::All)
                .from_reader(text.as_bytes());
            let (mut u, mut r) = (Vec::new(), Vec::new());
            let h = rdr.headers()?.clone();
            let col = |n: &str| {
                h.iter()
                    .position(|x| x.eq_ignore_ascii_case(n))
                    .with_context(|| format!("{}: missing column `{n}`", p.display()))
            };
            let (cu, cr) = (col("u_mm")?, col("radius_mm")?);
            for rec in rdr.records() {
                let rec = rec.with_context(|| format!("{}: malformed CSV", p.display()))?;
                let line = rec.position().map_or(0, |x| x.line());
                let num = |k: usize| -> Result<f64> {
                    rec[k].parse().with_context(|| {
                        format!(
                            "{}, line {line}: `{}` is not a number",
                            p.display(),
                            &rec[k]
                        )
                    })
                };
                u.push(num(cu)?);
                r.push(num(cr)?);
            }
            Generatrix::table(u, r).with_context(|| format!("generatrix {}", p.display()))
        }
    }
}

fn options(a: &CompensateArgs) -> Result<ProbeOptions> {
    Ok(ProbeOptions {
        tip_radius_mm: match &a.probe_tip_radius_mm {
            Some(t) => q("probe-tip-radius-mm", t, Quantity::LengthMm)?,
            None => 0.0,
        },
        miss_limit_mm: q("miss-limit-um", &a.miss_limit_um, Quantity::LengthUm)? * 1e-3,
        angle_tolerance: 1e-6,
        duplicates: match a.duplicates.as_str() {
            "error" => DuplicatePolicy::Error,
            "average" => DuplicatePolicy::Average,
            o => bail!("--duplicates: expected error | average, got `{o}`"),
        },
        missing: match a.missing.as_str() {
            "error" => MissingPolicy::Error,
            "skip" => MissingPolicy::Skip,
            o => bail!("--missing: expected error | skip, got `{o}`"),
        },
    })
}

fn scheme(a: &CompensateArgs) -> Result<(Scheme, RangePolicy)> {
    let s = match a.scheme.as_str() {
        "first-harmonic" => Scheme::FirstHarmonic,
        "bilinear" => Scheme::Bilinear,
        o => bail!("--scheme: expected first-harmonic | bilinear, got `{o}`"),
    };
    let r = match a.outside.as_str() {
        "clamp" => RangePolicy::Clamp,
        "extrapolate" => RangePolicy::Extrapolate,
        o => bail!("--outside: expected clamp | extrapolate, got `{o}`"),
    };
    Ok((s, r))
}

pub fn compensate_cmd(a: CompensateArgs) -> Result<()> {
    let probe_text = read(&a.probe, "probe table")?;
    let pname = a.probe.display().to_string();
    let mut points = runout_io::grind::read_probe_csv(&probe_text, &pname)?;
    match a.probe_angle_sense.as_str() {
        "ccw" => {}
        "cw" => points.iter_mut().for_each(|p| p.angle = -p.angle),
        o => bail!("--probe-angle-sense: expected ccw | cw, got `{o}`"),
    }
    let opts = options(&a)?;
    let grid = ProbeGrid::assemble(&points, generatrix(&a)?, &opts)
        .with_context(|| format!("{pname} (rows are file line numbers)"))?;
    let map = DeviationMap::new(&grid);
    let (sch, range) = scheme(&a)?;
    let interp = Interpolator::new(&map, sch, range);
    let bar_d = 2.0 * grid.generatrix.radius(grid.u_range().0);
    let (edge, wheel, edge_path) = edge(&a.edge, bar_d, grid.u_range().1)?;

    let mut inputs: Vec<&Path> = vec![a.probe.as_path()];
    inputs.extend(a.generatrix.as_deref());
    inputs.extend(edge_path.as_deref());
    inputs.extend(a.nc.as_deref());
    for out in [&a.out, &a.path_out, &a.json].into_iter().flatten() {
        output::check_not_input(out, &inputs)?;
        if a.nc.as_deref().is_some_and(|n| output::same_file(out, n)) {
            bail!(
                "refusing to write {}: it is the input NC program",
                out.display()
            );
        }
    }
    let comp = compensate(&interp, &map.axis, &edge, wheel.as_deref())?;

    let nc_summary = match (&a.nc, &a.out) {
        (Some(nc), Some(out)) => Some(rewrite_nc(&a, nc, out, &interp, &comp)?),
        (Some(_), None) => bail!("--nc needs --out for the compensated program"),
        (None, Some(_)) => bail!("--out needs --nc (the program to compensate)"),
        (None, None) => None,
    };
    if let Some(p) = &a.path_out {
        let w = output::create(p)?;
        runout_io::grind::write_path_csv(w, &edge, &comp)
            .with_context(|| format!("writing {}", p.display()))?;
    }
    if let Some(dir) = &a.plots {
        plots(dir, &a.plot_format, &map, &edge, &comp)?;
    }
    let report = report_json(&a, &opts, &grid, &map, &comp, nc_summary.as_ref());
    if let Some(j) = &a.json {
        output::write_text(j, &(serde_json::to_string_pretty(&report)? + "\n"))?;
    }
    let to_stdout = |p: &Option<PathBuf>| p.as_deref() == Some(Path::new("-"));
    if !to_stdout(&a.json) && !to_stdout(&a.path_out) {
        print_text(&grid, &map, &comp, nc_summary.as_ref());
    }
    Ok(())
}

/// Summary of the NC rewrite.
struct NcSummary {
    output: String,
    blocks: usize,
    offset_blocks: usize,
    mapping: String,
    changed_lines: usize,
}

fn rewrite_nc(
    a: &CompensateArgs,
    nc: &Path,
    out: &Path,
    interp: &Interpolator,
    comp: &Compensation,
) -> Result<NcSummary> {
    let text = read(nc, "NC program")?;
    let prog = NcProgram::parse(&text).with_context(|| format!("{}", nc.display()))?;
    let all = match a.nc_moves.as_str() {
        "feed" => false,
        "all" => true,
        o => bail!("--nc-moves: expected feed | all, got `{o}`"),
    };
    let blocks = prog.motion_blocks();
    let eligible: Vec<usize> = (0..blocks.len())
        .filter(|&k| all || !blocks[k].rapid)
        .collect();
    let mut offsets: Vec<Option<[f64; 3]>> = vec![None; blocks.len()];
    match a.nc_map.as_str() {
        "index" => {
            if eligible.len() != comp.points.len() {
                bail!(
                    "{}: {} {} moves but the edge has {} points; --nc-map index pairs them one to one \
                     (use an edge CSV with one point per move, or --nc-map xyz if X Y Z are bar-frame points)",
                    nc.display(),
                    eligible.len(),
                    if all { "G0/G1" } else { "G1" },
                    comp.points.len()
                );
            }
            for (k, &b) in eligible.iter().enumerate() {
                offsets[b] = Some(comp.points[k].offset);
            }
        }
        "xyz" => {
            if let Some(&f) = eligible.first() {
                for &b in &eligible {
                    if blocks[b].target[3..] != blocks[f].target[3..] {
                        bail!(
                            "{}: line {}: rotary axes (A B C) change between offset moves, so X Y Z are not \
                             bar-frame points; --nc-map xyz needs a program in the bar frame (use --nc-map index)",
                            nc.display(),
                            blocks[b].line
                        );
                    }
                }
            }
            for &b in &eligible {
                let t = blocks[b].target;
                let (Some(x), Some(y), Some(z)) = (t[0], t[1], t[2]) else {
                    bail!(
                        "{}: line {}: X, Y and Z must all be known for --nc-map xyz",
                        nc.display(),
                        blocks[b].line
                    );
                };
                let scale = if blocks[b].inch { 25.4 } else { 1.0 };
                let (x, y, z) = (x * scale, y * scale, z * scale);
                let alpha = y.atan2(x);
                let eps = interp.eval(z, alpha).eps;
                offsets[b] = Some([eps * alpha.cos(), eps * alpha.sin(), 0.0]);
            }
        }
        o => bail!("--nc-map: expected index | xyz, got `{o}`"),
    }
    let new = prog
        .rewrite(
            &offsets,
            &RewriteOptions {
                decimals: a.nc_decimals,
            },
        )
        .with_context(|| format!("{}", nc.display()))?;
    let changed_lines = text
        .split_inclusive('\n')
        .zip(new.split_inclusive('\n'))
        .filter(|(x, y)| x != y)
        .count();
    output::write_text(out, &new)?;
    Ok(NcSummary {
        output: out.display().to_string(),
        blocks: blocks.len(),
        offset_blocks: eligible.len(),
        mapping: a.nc_map.clone(),
        changed_lines,
    })
}

fn plots(
    dir: &Path,
    fmt: &str,
    map: &DeviationMap,
    edge: &EdgeLine,
    comp: &Compensation,
) -> Result<()> {
    if fmt != "svg" && fmt != "png" {
        bail!("--plot-format: expected svg | png, got `{fmt}`");
    }
    std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
    let p = |n: &str| dir.join(format!("{n}.{fmt}"));
    runout_io::grind::plot::deviation_heatmap(&p("deviation_heatmap"), map)?;
    runout_io::grind::plot::eps_plot(&p("eps_along_edge"), edge, comp)?;
    runout_io::grind::plot::error_plot(&p("radial_error"), edge, comp)?;
    Ok(())
}

/// Offset vector in the bar frame → magnitude (µm), bar-frame angle (deg) and the runout angle
/// λ of `conventions.md` (spindle frame, positive in the direction of rotation = −α).
fn polar_um(v: [f64; 2]) -> (f64, f64, f64) {
    let ang = v[1].atan2(v[0]).to_degrees();
    (v[0].hypot(v[1]) * 1e3, ang, wrap_deg180(-ang))
}

fn um2(v: [f64; 2]) -> [f64; 2] {
    [v[0] * 1e3, v[1] * 1e3]
}

/// JSON report, schema `runout.grind.compensate/1`.
fn report_json(
    a: &CompensateArgs,
    opts: &ProbeOptions,
    grid: &ProbeGrid,
    map: &DeviationMap,
    comp: &Compensation,
    nc: Option<&NcSummary>,
) -> serde_json::Value {
    let ax = &map.axis;
    let (o_mag, o_ang, o_lambda) = polar_um(ax.offset);
    let (u0, u1) = grid.u_range();
    let (rb, mb) = comp.before_stats();
    let (ra, ma) = comp.remaining_stats();
    let eps: Vec<f64> = comp.points.iter().map(|p| p.eps * 1e3).collect();
    let (emin, emax) = eps
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), x| {
            (l.min(*x), h.max(*x))
        });
    json!({
        "schema": "runout.grind.compensate/1",
        "inputs": {
            "probe": a.probe.display().to_string(),
            "edge": a.edge.kind,
            "scheme": format!("{:?}", comp.scheme),
            "outside_probed_range": format!("{:?}", comp.range),
            "probe_angle_sense": a.probe_angle_sense,
            "probe_tip_radius_mm": opts.tip_radius_mm,
            "miss_limit_um": opts.miss_limit_mm * 1e3,
            "duplicates": format!("{:?}", opts.duplicates),
            "missing": format!("{:?}", opts.missing),
        },
        "frame": "bar frame: u from the tool tip along the work-head axis; x, y right-handed, α counter-clockwise about +u (= −spindle-frame angle, conventions.md)",
        "grid": {
            "layers": grid.layer_count(),
            "u_range_mm": [u0, u1],
            "notes": grid.notes,
        },
        "layers": map.layers.iter().map(|l| json!({
            "u_mm": l.u,
            "angles": l.alpha.len(),
            "r_avg_mm": l.r_avg,
            "mean_radius_mm": l.mean,
            "first_harmonic_um": [l.c * 1e3, l.s * 1e3],
            "max_abs_delta_um": l.delta.iter().fold(0.0f64, |m, d| m.max(d.abs())) * 1e3,
            "form_rms_um": l.form_rms * 1e3,
            "form_max_um": l.form_max * 1e3,
            "harmonic_fit_condition": l.condition,
        })).collect::<Vec<_>>(),
        "axis": {
            "offset_at_u0_um": um2(ax.offset),
            "offset_um": o_mag,
            "offset_angle_bar_deg": o_ang,
            "runout_angle_deg": o_lambda,
            "offset_se_um": ax.offset_se.map(um2),
            "tilt_um_per_mm": um2(ax.tilt),
            "tilt_se_um_per_mm": ax.tilt_se.map(um2),
            "layer_residual_rms_um": ax.residual_rms * 1e3,
            "uncertainty": "standard errors from the residual scatter of the per-layer first harmonics about the line (null with 2 layers)",
        },
        "compensation": {
            "points": comp.points.len(),
            "outside_probed_range": comp.outside_count(),
            "eps_min_um": emin,
            "eps_max_um": emax,
            "predicted_before_rms_um": rb * 1e3,
            "predicted_before_max_um": mb * 1e3,
            "predicted_remaining_rms_um": ra * 1e3,
            "predicted_remaining_max_um": ma * 1e3,
            "remaining_definition": "ε − e(u)·n with e the fitted rigid axis (interpolation error, noise, form)",
            "eps_um": eps,
            "remaining_um": comp.points.iter().map(|p| p.remaining * 1e3).collect::<Vec<_>>(),
        },
        "nc": nc.map(|n| json!({
            "output": n.output,
            "linear_moves": n.blocks,
            "offset_moves": n.offset_blocks,
            "mapping": n.mapping,
            "changed_lines": n.changed_lines,
        })),
    })
}

fn print_text(grid: &ProbeGrid, map: &DeviationMap, comp: &Compensation, nc: Option<&NcSummary>) {
    let ax = &map.axis;
    let (u0, u1) = grid.u_range();
    let (o_mag, o_ang, lambda) = polar_um(ax.offset);
    println!(
        "runout grind compensate: {} layers, u {u0}..{u1} mm, scheme {:?}, outside range: {:?}",
        grid.layer_count(),
        comp.scheme,
        comp.range
    );
    for n in &grid.notes {
        println!("note: {n}");
    }
    let se = |v: Option<[f64; 2]>, d: usize| {
        v.map_or("n/a".to_string(), |s| {
            format!("± ({:.d$}, {:.d$})", s[0] * 1e3, s[1] * 1e3)
        })
    };
    println!(
        "bar axis at u = 0: offset ({:.2}, {:.2}) µm {} = {:.2} µm at {:.1}° (runout angle λ {:.1}°)",
        ax.offset[0] * 1e3,
        ax.offset[1] * 1e3,
        se(ax.offset_se, 2),
        o_mag,
        o_ang,
        lambda
    );
    println!(
        "tilt ({:.3}, {:.3}) µm/mm {}; layer residual rms {:.3} µm",
        ax.tilt[0] * 1e3,
        ax.tilt[1] * 1e3,
        se(ax.tilt_se, 3),
        ax.residual_rms * 1e3
    );
    println!("layer  u (mm)   max|δ| (µm)  first harmonic (µm)   form rms/max (µm)");
    for (i, l) in map.layers.iter().enumerate() {
        let md = l.delta.iter().fold(0.0f64, |m, d| m.max(d.abs()));
        println!(
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
    println!(
        "{} edge points ({} outside the probed range); predicted radial error before rms {:.3} / max {:.3} µm, after rms {:.4} / max {:.4} µm",
        comp.points.len(),
        comp.outside_count(),
        rb * 1e3,
        mb * 1e3,
        ra * 1e3,
        ma * 1e3
    );
    if let Some(n) = nc {
        println!(
            "NC: {} linear moves, {} offset ({} mapping), {} lines changed → {}",
            n.blocks, n.offset_blocks, n.mapping, n.changed_lines, n.output
        );
    }
}
