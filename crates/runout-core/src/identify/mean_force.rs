//! Cutting-coefficient calibration from mean forces over several feeds (Altintas' linear
//! regression, issue 3 item 6), for any immersion [φ_st, φ_ex] (slotting, up, down, explicit).
//!
//! Averaging the mechanistic model (`force` module, forces on the workpiece) over one revolution
//! with h = f_z sin φ, K teeth and axial depth a (helix and pitch do not change the mean):
//!
//! F̄_x = c·[ f_z (K_tc I_sc + K_rc I_ss) + K_te I_c + K_re I_s ]
//! F̄_y = c·[ f_z (−K_tc I_ss + K_rc I_sc) − K_te I_s + K_re I_c ]
//! F̄_z = −c·[ f_z K_ac I_s + K_ae (φ_ex − φ_st) ],      c = K·a/(2π),
//!
//! I_sc = ∫ sin φ cos φ dφ = [sin² φ/2], I_ss = ∫ sin² φ dφ = [φ/2 − sin 2φ/4],
//! I_c = ∫ cos φ dφ = [sin φ], I_s = ∫ sin φ dφ = [−cos φ], all from φ_st to φ_ex.
//!
//! Each measured mean is regressed on f_z: F̄_q = s_q·f_z + e_q (slope, intercept with standard
//! errors σ̂²(XᵀX)⁻¹); the 2×2 rotations above are inverted:
//! K_tc = (I_sc s_x − I_ss s_y)/(c D), K_rc = (I_ss s_x + I_sc s_y)/(c D), D = I_sc² + I_ss²;
//! K_te = (I_c e_x − I_s e_y)/(c D_e), K_re = (I_s e_x + I_c e_y)/(c D_e), D_e = I_c² + I_s²;
//! K_ac = −s_z/(c I_s), K_ae = −e_z/(c (φ_ex − φ_st)). Standard errors propagate linearly
//! (the x and y regressions are independent). With exactly 2 feeds the fit has no residual
//! degrees of freedom: coefficients but no standard errors.
//!
//! Runout: while every tooth stays in contact the runout terms cancel exactly in the mean
//! (Σ_i ΔR_i = 0). Where the engagement starts or ends at sin φ = 0 (up-milling entry,
//! down-milling exit) teeth with ΔR < 0 lose contact and the clipped chip area ∝ ΔR²/f_z varies
//! with the feed, which **biases** the regression: with ρ = 5 µm, f_z 0.06–0.12 mm, a_e/D = 0.25
//! the tests measured K_rc +12 % (up) and K_te −11 % (down); slotting stays within 0.5 %. Use
//! these values as start values and refine with [`super::full_signal_fit`], which models it.

use super::error::IdentifyError;
use super::lsq::{fit_line, Regression};
use super::sine_fit::Estimate;
use crate::error::{finite, positive, ParamError};
use serde::Serialize;

/// Mean forces (N, workpiece frame, averaged over whole revolutions) at one feed.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct MeanForces {
    /// Feed per tooth f_z (mm).
    pub fz_mm: f64,
    /// Mean F_x (N).
    pub fx_n: f64,
    /// Mean F_y (N).
    pub fy_n: f64,
    /// Mean F_z (N), if measured.
    pub fz_n: Option<f64>,
}

/// Calibrated coefficients with the per-component regressions.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct MeanForceCalibration {
    /// K_tc (N/mm²).
    pub ktc: Estimate,
    /// K_rc (N/mm²).
    pub krc: Estimate,
    /// K_ac (N/mm²), when F_z was measured.
    pub kac: Option<Estimate>,
    /// K_te (N/mm).
    pub kte: Estimate,
    /// K_re (N/mm).
    pub kre: Estimate,
    /// K_ae (N/mm), when F_z was measured.
    pub kae: Option<Estimate>,
    /// Regression of F̄_x on f_z (slope N/mm, intercept N).
    pub fit_x: Regression,
    /// Regression of F̄_y on f_z.
    pub fit_y: Regression,
    /// Regression of F̄_z on f_z, when measured.
    pub fit_z: Option<Regression>,
}

/// The immersion integrals (I_sc, I_ss, I_c, I_s, width) over [φ_st, φ_ex].
pub fn immersion_integrals(entry_rad: f64, exit_rad: f64) -> [f64; 5] {
    let (a, b) = (entry_rad, exit_rad);
    let isc = (b.sin().powi(2) - a.sin().powi(2)) / 2.0;
    let iss = (b / 2.0 - (2.0 * b).sin() / 4.0) - (a / 2.0 - (2.0 * a).sin() / 4.0);
    let ic = b.sin() - a.sin();
    let is = a.cos() - b.cos();
    [isc, iss, ic, is, b - a]
}

/// Calibrate the six coefficients from mean forces at ≥ 2 distinct feeds, for a cutter with
/// `teeth` teeth at axial depth `ap_mm` and immersion [`entry_rad`, `exit_rad`].
///
/// ```
/// use runout_core::identify::{calibrate_mean_forces, immersion_integrals, MeanForces};
/// // forward model with K_tc 1889.2, K_rc 806.1, K_te 63.12, K_re 113.7 (slot, K 4, a 1 mm)
/// let (st, ex) = (0.0, std::f64::consts::PI);
/// let [isc, iss, ic, is, _] = immersion_integrals(st, ex);
/// let c = 4.0 * 1.0 / std::f64::consts::TAU;
/// let m = |f: f64| MeanForces {
///     fz_mm: f,
///     fx_n: c * (f * (1889.2 * isc + 806.1 * iss) + 63.12 * ic + 113.7 * is),
///     fy_n: c * (f * (-1889.2 * iss + 806.1 * isc) - 63.12 * is + 113.7 * ic),
///     fz_n: None,
/// };
/// let cal = calibrate_mean_forces(4, 1.0, st, ex, &[m(0.05), m(0.1)]).unwrap();
/// assert!((cal.ktc.value - 1889.2).abs() < 1e-9 && (cal.kre.value - 113.7).abs() < 1e-9);
/// ```
pub fn calibrate_mean_forces(
    teeth: usize,
    ap_mm: f64,
    entry_rad: f64,
    exit_rad: f64,
    data: &[MeanForces],
) -> Result<MeanForceCalibration, IdentifyError> {
    if teeth == 0 {
        return Err(ParamError::new("teeth", "an integer >= 1", 0).into());
    }
    positive("ap_mm", ap_mm)?;
    if exit_rad.is_nan() || entry_rad.is_nan() || exit_rad <= entry_rad {
        return Err(ParamError::new(
            "exit_deg",
            "an exit angle after the entry angle",
            exit_rad.to_degrees(),
        )
        .into());
    }
    for (i, d) in data.iter().enumerate() {
        positive(&format!("fz_mm[{i}]"), d.fz_mm)?;
        finite(&format!("fx_N[{i}]"), d.fx_n)?;
        finite(&format!("fy_N[{i}]"), d.fy_n)?;
    }
    let mut feeds: Vec<f64> = data.iter().map(|d| d.fz_mm).collect();
    feeds.sort_by(f64::total_cmp);
    feeds.dedup();
    if feeds.len() < 2 {
        return Err(IdentifyError::too_few(
            "mean-force calibration",
            "at least 2 distinct feeds",
            format!("{} distinct feed(s)", feeds.len()),
        ));
    }
    let f: Vec<f64> = data.iter().map(|d| d.fz_mm).collect();
    let fx: Vec<f64> = data.iter().map(|d| d.fx_n).collect();
    let fy: Vec<f64> = data.iter().map(|d| d.fy_n).collect();
    let fit_x = fit_line(&f, &fx, true)?;
    let fit_y = fit_line(&f, &fy, true)?;
    let has_z = data.iter().all(|d| d.fz_n.is_some());
    let fit_z = if has_z {
        let fz: Vec<f64> = data.iter().map(|d| d.fz_n.unwrap_or(0.0)).collect();
        Some(fit_line(&f, &fz, true)?)
    } else {
        None
    };

    let [isc, iss, ic, is, width] = immersion_integrals(entry_rad, exit_rad);
    let c = teeth as f64 * ap_mm / std::f64::consts::TAU;
    let d = isc * isc + iss * iss;
    let de = ic * ic + is * is;
    if !(d > 1e-12 && de > 1e-12) {
        return Err(IdentifyError::singular(
            "mean-force calibration",
            "engagement too small",
        ));
    }
    let se = |v: f64| v.is_finite().then_some(v);
    let comb = |a: f64, b: f64, ra: &Regression, rb: &Regression, slope: bool, den: f64| {
        let (va, vb, sa, sb) = if slope {
            (ra.slope, rb.slope, ra.slope_se, rb.slope_se)
        } else {
            (ra.intercept, rb.intercept, ra.intercept_se, rb.intercept_se)
        };
        Estimate {
            value: (a * va + b * vb) / (c * den),
            se: se(((a * sa).powi(2) + (b * sb).powi(2)).sqrt() / (c * den)),
        }
    };
    let z_est = |r: &Regression| {
        if is.abs() < 1e-12 {
            return (
                None,
                Some(Estimate {
                    value: -r.intercept / (c * width),
                    se: se(r.intercept_se / (c * width)),
                }),
            );
        }
        (
            Some(Estimate {
                value: -r.slope / (c * is),
                se: se(r.slope_se / (c * is).abs()),
            }),
            Some(Estimate {
                value: -r.intercept / (c * width),
                se: se(r.intercept_se / (c * width)),
            }),
        )
    };
    let (kac, kae) = fit_z.as_ref().map(z_est).unwrap_or((None, None));
    Ok(MeanForceCalibration {
        ktc: comb(isc, -iss, &fit_x, &fit_y, true, d),
        krc: comb(iss, isc, &fit_x, &fit_y, true, d),
        kac,
        kte: comb(ic, -is, &fit_x, &fit_y, false, de),
        kre: comb(is, ic, &fit_x, &fit_y, false, de),
        kae,
        fit_x,
        fit_y,
        fit_z,
    })
}
