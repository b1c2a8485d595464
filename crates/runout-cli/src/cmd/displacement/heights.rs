//! `runout displacement heights TABLE.csv`: runout at several heights → runout at the cutting
//! height (methods.md §1.3; §1.6 vector fit when the table has an angle column).

use super::*;
use runout_core::displacement::{
    runout_at_height, vector_at_height, HeightFit, HeightRegression, VectorHeightFit,
};
use runout_io::displacement::{read_height_table, HeightRow};
use runout_io::displacement_plot::{height_plot, HeightPlot};

/// Arguments of `runout displacement heights`.
#[derive(clap::Args, Debug)]
pub struct Args {
    /// CSV with `z_<mm>` and `tir_<um>` (total indicated runout) or `runout_<um>` (= TIR/2), optional
    /// `angle_<deg>` (direction of the runout from the spindle phase) for the offset + tilt fit.
    pub table: PathBuf,
    /// Height at which the runout is wanted (mm, same origin as z; the cutting edges).
    #[arg(long, allow_hyphen_values = true)]
    pub at_mm: Option<String>,
    /// Regression: `ols` (default, unbiased) or `eq6` (the seed's eq. 6, paper-compatible, biased).
    #[arg(long, allow_hyphen_values = true)]
    pub method: Option<String>,
    #[command(flatten)]
    pub out: OutputFlags,
}

pub fn run(a: Args) -> Result<()> {
    let rows = read_height_table(&a.table)?;
    let at = quantity("at-mm", &a.at_mm, Quantity::LengthMm)?.unwrap_or(0.0);
    let method = match a.method.as_deref() {
        None | Some("ols") => HeightRegression::Ols,
        Some("eq6") => HeightRegression::SeedEq6,
        Some(o) => bail!("--method: `{o}` is not `ols` or `eq6`"),
    };
    let file = a.table.display().to_string();
    let pts: Vec<(f64, f64)> = rows.iter().map(|r| (r.z_mm, r.runout_mm)).collect();
    let fit = runout_at_height(&pts, at, method).with_context(|| file.clone())?;
    let vector = vector_fit(&rows, at)
        .transpose()
        .with_context(|| file.clone())?;
    let json = to_json(&file, &fit, vector.as_ref());
    let text = to_text(&file, &fit, vector.as_ref());
    if let Some(p) = &a.out.plot {
        crate::output::check_not_input(p, &[&a.table])?;
        height_plot(p, &plot_data(&pts, &fit))?;
    }
    a.out.write(&a.table, &json, &text)
}

fn vector_fit(
    rows: &[HeightRow],
    at: f64,
) -> Option<Result<VectorHeightFit, runout_core::displacement::DisplacementError>> {
    let pts: Option<Vec<(f64, [f64; 2])>> = rows
        .iter()
        .map(|r| {
            r.angle_rad
                .map(|l| (r.z_mm, [r.runout_mm * l.cos(), r.runout_mm * l.sin()]))
        })
        .collect();
    pts.map(|p| vector_at_height(&p, at))
}

fn plot_data(pts: &[(f64, f64)], fit: &HeightFit) -> HeightPlot {
    let zs = pts.iter().map(|p| p.0).chain([fit.height_mm]);
    let (z0, z1) = zs.fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), z| {
        (a.min(z), b.max(z))
    });
    HeightPlot {
        points: pts.iter().map(|(z, r)| (*z, r * 1e3)).collect(),
        line: vec![(z0, fit.at(z0) * 1e3), (z1, fit.at(z1) * 1e3)],
        line_label: format!("{:?} fit, R² = {:.4}", fit.method, fit.r_squared),
        at: (
            fit.height_mm,
            fit.offset_mm * 1e3,
            fit.offset_se_mm.map(|s| s * 1e3),
        ),
        title: "runout vs height (r = TIR/2)".into(),
    }
}

fn to_json(file: &str, fit: &HeightFit, vector: Option<&VectorHeightFit>) -> Value {
    json!({
        "schema": "runout.displacement.heights/1",
        "input": { "file": file, "points": fit.points },
        "method": fit.method,
        "at_mm": fit.height_mm,
        "offset_um": fit.offset_mm * 1e3,
        "offset_se_um": fit.offset_se_mm.map(|s| s * 1e3),
        "slope_um_per_mm": fit.slope * 1e3,
        "slope_se_um_per_mm": fit.slope_se.map(|s| s * 1e3),
        "r_squared": fit.r_squared,
        "residual_rms_um": fit.residual_rms_mm * 1e3,
        "notes": fit.notes,
        "vector": vector.map(|v| {
            let mut j = json!({
                "offset_um": v.offset_mm * 1e3,
                "offset_se_um": v.offset_se_mm.map(|s| s * 1e3),
                "offset_at_zero_um": [v.offset_at_zero_mm[0] * 1e3, v.offset_at_zero_mm[1] * 1e3],
                "tilt_um_per_mm": [v.tilt[0] * 1e3, v.tilt[1] * 1e3],
                "residual_rms_um": v.residual_rms_mm * 1e3,
            });
            if let (Value::Object(m), Value::Object(a)) = (&mut j, angle_json(&v.angle)) {
                m.extend(a);
            }
            j
        }),
    })
}

fn to_text(file: &str, fit: &HeightFit, vector: Option<&VectorHeightFit>) -> String {
    let mut s = format!(
        "runout vs height ({file}; {} heights, {:?})\n",
        fit.points, fit.method
    );
    s += &match fit.offset_se_mm {
        Some(se) => format!(
            "runout at z = {} mm: {:.3} ± {:.3} µm (1σ)\n",
            fit.height_mm,
            fit.offset_mm * 1e3,
            se * 1e3
        ),
        None => format!(
            "runout at z = {} mm: {:.3} µm\n",
            fit.height_mm,
            fit.offset_mm * 1e3
        ),
    };
    s += &format!(
        "slope {:.4} µm/mm, R² {:.4}, residual rms {:.4} µm\n",
        fit.slope * 1e3,
        fit.r_squared,
        fit.residual_rms_mm * 1e3
    );
    if let Some(v) = vector {
        s += &format!(
            "vector fit (offset + tilt, methods.md §1.6): runout {:.3} µm, {}; tilt ({:.4}, {:.4}) µm/mm\n",
            v.offset_mm * 1e3,
            angle_text(&v.angle),
            v.tilt[0] * 1e3,
            v.tilt[1] * 1e3
        );
    }
    s + &notes_text(&fit.notes)
}
