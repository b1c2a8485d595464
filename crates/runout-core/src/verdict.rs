//! The verdict on an identified runout and what it does to the cut (issue 15): pass/fail against
//! a runout tolerance, per-tooth actual radius, maximum chip and load share, the tooth that
//! wears first, the slot oversize, and the feed per tooth that keeps the most loaded tooth at
//! the nominal chip — with the productivity that costs.
//!
//! Pure computation from the identified runout (ρ ± SE, λ) and the cut (cutter, f_z); the
//! reports of the jobs carry the result as a field, so the text, the JSON and the HTML report
//! show the same numbers.
//!
//! **Tolerance.** Runout tolerances of tool holders and collets are given as *total indicated
//! runout* (TIR: the full swing of a dial gauge on a rotating test mandrel), so the verdict
//! compares TIR = 2ρ (a parallel offset ρ swings the gauge by 2ρ) with the tolerance. The default
//! ([`default_tolerance_tir_mm`]) is the **ISO 15488 (DIN 6499) collet run-out tolerance,
//! class 1** (the precision class, Table 4): 10 µm for clamping diameters 1–10 mm and 15 µm for
//! 10–26 mm, measured on a test mandrel at 6–50 mm from the collet face (Table 4 of ISO 15488:2003
//! "Collets with 8° setting angle for tool shanks", as reproduced by a collet maker:
//! <http://accufixtools.com/TechnicalInfo.aspx>). Normal collets are class 2 (15 / 20 µm); shrink-fit
//! and hydraulic holders are sold at ≤ 3 µm. Larger tools (> 26 mm) keep the 15 µm of the largest
//! class-1 row. A shop with its own limit passes it (`--tolerance-um`).
//!
//! **Status.** With the standard error SE of ρ: *pass* when 2(ρ + 2·SE) ≤ tolerance, *fail* when
//! 2(ρ − 2·SE) > tolerance, otherwise *marginal* (the tolerance lies inside the ±2σ interval of
//! the TIR: the measurement cannot decide).
//!
//! **Cut.** Tooth radii R_i = |R·u(ψ_i) + e| (methods.md §0, eq. 0.1); the largest chip of each
//! tooth from the arc model at φ = 90° (methods.md §0, eq. 0.4):
//! h_i = max(0, min_m [m·f_z + R_i − R_{i−m}]). Over one revolution the teeth remove K·f_z
//! together (the radius terms telescope), so tooth i's share of the load is
//! s_i = h_i / Σ_j h_j and Σ s_i = 1; the tooth with the largest h_i carries the most load and
//! wears (or chips) first; a tooth with h_i = 0 does not cut. The nominal chip (no runout) is
//! h_nom = f_z; the feed per tooth that keeps the most loaded tooth at h_nom is, to first order in
//! the chip (h_max grows with f_z one for one while every tooth cuts),
//! f_z' = f_z · h_nom / h_max, and the productivity cost (metal removal rate lost) is
//! 1 − f_z'/f_z. The slot (and every wall) is cut by the largest radius: oversize
//! 2·(max_i R_i − R) ≤ 2ρ (methods.md §1.7), equal to 2ρ when a tooth points along e.

use crate::chip::{ArcChip, ChipThickness};
use crate::cutter::Cutter;
use crate::error::ParamError;
use crate::runout::Runout;
use serde::{Deserialize, Serialize};
use std::f64::consts::FRAC_PI_2;

/// Source of the default tolerance, as reported.
pub const DEFAULT_TOLERANCE_SOURCE: &str =
    "ISO 15488 (DIN 6499) collet run-out tolerance, class 1 (Table 4): TIR 10 µm for 1–10 mm, 15 µm for 10–26 mm";

/// The default runout tolerance (TIR, mm) for a cutter (shank) of `diameter_mm`: ISO 15488 class 1
/// (see the module documentation): 0.010 mm up to 10 mm, 0.015 mm above. Unknown diameter: the
/// stricter 0.010 mm.
///
/// ```
/// use runout_core::verdict::default_tolerance_tir_mm;
/// assert_eq!(default_tolerance_tir_mm(Some(10.0)), 0.010);
/// assert_eq!(default_tolerance_tir_mm(Some(12.0)), 0.015);
/// assert_eq!(default_tolerance_tir_mm(None), 0.010);
/// ```
pub fn default_tolerance_tir_mm(diameter_mm: Option<f64>) -> f64 {
    match diameter_mm {
        Some(d) if d > 10.0 => 0.015,
        _ => 0.010,
    }
}

/// Pass, marginal (undecided within ±2σ) or fail.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Status {
    /// 2(ρ + 2·SE) ≤ tolerance.
    Pass,
    /// The tolerance lies within 2(ρ ± 2·SE).
    Marginal,
    /// 2(ρ − 2·SE) > tolerance.
    Fail,
}

impl Status {
    /// `pass`, `marginal`, `fail`.
    pub fn as_str(&self) -> &'static str {
        match self {
            Status::Pass => "pass",
            Status::Marginal => "marginal",
            Status::Fail => "fail",
        }
    }
}

/// What the verdict is computed from.
#[derive(Debug, Clone)]
pub struct VerdictInput {
    /// Offset ρ (mm) and angle λ of the identified runout (tilt ignored: the verdict is at one
    /// height; see [`axis_split`] for tip vs upper height).
    pub runout: Runout,
    /// Standard error of ρ (mm), if known (unknown: taken as 0 for the status).
    pub offset_se_mm: Option<f64>,
    /// The cutter, for the per-tooth consequences (none: only the status and 2ρ).
    pub cutter: Option<Cutter>,
    /// Height of the verdict above the tip (mm), for the helix lag of the tooth angles.
    pub height_mm: f64,
    /// Feed per tooth f_z (mm), for the chips, loads and compensated feed.
    pub fz_mm: Option<f64>,
    /// Tolerance on TIR (mm); `None`: [`default_tolerance_tir_mm`] of the cutter diameter.
    pub tolerance_tir_mm: Option<f64>,
}

/// One tooth's share of the cut.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ToothOutcome {
    /// Tooth number (cutting order).
    pub tooth: usize,
    /// Actual radius R_i (mm), eq. 0.1.
    pub radius_mm: f64,
    /// Largest chip h_i (mm), arc model at φ = 90° (eq. 0.4), when f_z is known.
    pub max_chip_mm: Option<f64>,
    /// Load share h_i / Σ h_j, when f_z is known.
    pub load_share: Option<f64>,
}

/// The verdict and its consequences.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Verdict {
    /// Pass / marginal / fail.
    pub status: Status,
    /// TIR = 2ρ (mm).
    pub tir_mm: f64,
    /// Standard error of the TIR, 2·SE(ρ) (mm).
    pub tir_se_mm: Option<f64>,
    /// Tolerance on TIR (mm).
    pub tolerance_tir_mm: f64,
    /// Where the tolerance comes from (`given` or [`DEFAULT_TOLERANCE_SOURCE`]).
    pub tolerance_source: String,
    /// Per tooth (empty without a cutter).
    pub teeth: Vec<ToothOutcome>,
    /// Slot / wall oversize 2·(max R_i − R) (mm), without a cutter the bound 2ρ.
    pub slot_oversize_mm: f64,
    /// Nominal largest chip f_z (mm).
    pub nominal_chip_mm: Option<f64>,
    /// Largest chip of any tooth (mm).
    pub max_chip_mm: Option<f64>,
    /// The tooth with the largest chip: carries most load, wears or chips first.
    pub most_loaded_tooth: Option<usize>,
    /// Teeth that do not cut (h_i = 0).
    pub idle_teeth: Vec<usize>,
    /// Feed per tooth that keeps the most loaded tooth at the nominal chip, f_z·h_nom/h_max (mm).
    pub compensated_fz_mm: Option<f64>,
    /// Metal removal rate lost at the compensated feed, 100·(1 − f_z'/f_z) (%).
    pub productivity_loss_percent: Option<f64>,
}

/// The verdict on `input` (module documentation for the equations).
///
/// ```
/// use runout_core::{Cutter, Runout};
/// use runout_core::verdict::{verdict, Status, VerdictInput};
/// // K = 4, ρ = 10 µm at λ = 0, f_z = 0.05 mm: tooth 0 is 10 µm long, tooth 2 10 µm short;
/// // tooth 3 follows the short tooth 2 and takes the largest chip
/// let v = verdict(&VerdictInput {
///     runout: Runout::new(0.010, 0.0).unwrap(),
///     offset_se_mm: Some(0.0005),
///     cutter: Some(Cutter::flat(10.0, 4, 0.0).unwrap()),
///     height_mm: 0.0,
///     fz_mm: Some(0.05),
///     tolerance_tir_mm: None,
/// }).unwrap();
/// assert_eq!(v.status, Status::Fail); // TIR 20 µm > 10 µm
/// assert_eq!(v.most_loaded_tooth, Some(3));
/// ```
pub fn verdict(input: &VerdictInput) -> Result<Verdict, ParamError> {
    let rho = input.runout.offset();
    let se = input.offset_se_mm;
    if let Some(s) = se {
        if !(s.is_finite() && s >= 0.0) {
            return Err(ParamError::new(
                "offset_um_se",
                "a finite SE >= 0 µm",
                s * 1e3,
            ));
        }
    }
    if !input.height_mm.is_finite() {
        return Err(ParamError::new(
            "height_mm",
            "a finite height",
            input.height_mm,
        ));
    }
    let (tol, source) = match input.tolerance_tir_mm {
        Some(t) if t.is_finite() && t > 0.0 => (t, "given".to_string()),
        Some(t) => {
            return Err(ParamError::new(
                "tolerance_um",
                "a tolerance > 0 µm (total indicated runout)",
                t * 1e3,
            ))
        }
        None => (
            default_tolerance_tir_mm(input.cutter.as_ref().map(Cutter::diameter)),
            DEFAULT_TOLERANCE_SOURCE.to_string(),
        ),
    };
    let s = se.unwrap_or(0.0);
    let status = if 2.0 * (rho + 2.0 * s) <= tol {
        Status::Pass
    } else if 2.0 * (rho - 2.0 * s) > tol {
        Status::Fail
    } else {
        Status::Marginal
    };
    let mut v = Verdict {
        status,
        tir_mm: 2.0 * rho,
        tir_se_mm: se.map(|s| 2.0 * s),
        tolerance_tir_mm: tol,
        tolerance_source: source,
        teeth: vec![],
        slot_oversize_mm: 2.0 * rho,
        nominal_chip_mm: input.fz_mm,
        max_chip_mm: None,
        most_loaded_tooth: None,
        idle_teeth: vec![],
        compensated_fz_mm: None,
        productivity_loss_percent: None,
    };
    let Some(cutter) = &input.cutter else {
        return Ok(v);
    };
    let z = input.height_mm;
    let runout = Runout::new(rho, input.runout.angle())?;
    let radii = runout.tooth_radii(cutter, z);
    let r_nom = cutter.radius_at(z);
    let r_max = radii.iter().cloned().fold(f64::NEG_INFINITY, f64::max);
    v.slot_oversize_mm = 2.0 * (r_max - r_nom);
    let chips: Option<Vec<f64>> = match input.fz_mm {
        Some(fz) => {
            let model = ArcChip::new(cutter, &runout, fz)?;
            Some(
                (0..cutter.teeth())
                    .map(|i| model.thickness(i, z, FRAC_PI_2))
                    .collect(),
            )
        }
        None => None,
    };
    let total: f64 = chips.iter().flatten().sum();
    v.teeth = radii
        .iter()
        .enumerate()
        .map(|(i, r)| ToothOutcome {
            tooth: i,
            radius_mm: *r,
            max_chip_mm: chips.as_ref().map(|h| h[i]),
            load_share: chips
                .as_ref()
                .map(|h| if total > 0.0 { h[i] / total } else { 0.0 }),
        })
        .collect();
    if let (Some(h), Some(fz)) = (&chips, input.fz_mm) {
        // the first of equal maxima (no runout: tooth 0)
        let (imax, hmax) =
            h.iter()
                .enumerate()
                .fold((0, f64::NEG_INFINITY), |(bi, bh), (i, &x)| {
                    if x > bh * (1.0 + 1e-12) {
                        (i, x)
                    } else {
                        (bi, bh)
                    }
                });
        v.max_chip_mm = Some(hmax);
        v.most_loaded_tooth = Some(imax);
        v.idle_teeth = (0..h.len()).filter(|&i| h[i] <= 0.0).collect();
        // h_max ≥ f_z always (the shares average 1/K); guard the division anyway
        let comp = if hmax > fz { fz * fz / hmax } else { fz };
        v.compensated_fz_mm = Some(comp);
        v.productivity_loss_percent = Some(100.0 * (1.0 - comp / fz));
    }
    Ok(v)
}

/// Runout at the tip against runout higher up the tool (gauge line / upper sensor): whether the
/// runout is a parallel offset (same at both heights) or a tilt of the tool axis.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct AxisSplit {
    /// |e(0)| at the tip (mm).
    pub tip_offset_mm: f64,
    /// |e(h)| at the upper height (mm).
    pub upper_offset_mm: f64,
    /// The upper height h above the tip (mm).
    pub upper_height_mm: f64,
    /// |τ| = |e(h) − e(0)| / h (mm per mm).
    pub tilt_mm_per_mm: f64,
    /// `tilt` when the axis inclination changes the runout over h by more than half the tip
    /// runout (|e(h) − e(0)| > |e(0)|/2), else `offset`.
    pub dominated_by: String,
}

/// Split a runout known as vectors at the tip `tip_mm` and at `upper_height_mm` above it
/// (`upper_mm`), with e(z) = e₀ + z·τ (methods.md §1.6).
///
/// ```
/// use runout_core::verdict::axis_split;
/// let s = axis_split([0.002, 0.0], [0.012, 0.0], 50.0).unwrap();
/// assert!((s.tilt_mm_per_mm - 0.0002).abs() < 1e-15);
/// assert_eq!(s.dominated_by, "tilt");
/// ```
pub fn axis_split(
    tip_mm: [f64; 2],
    upper_mm: [f64; 2],
    upper_height_mm: f64,
) -> Result<AxisSplit, ParamError> {
    if !(upper_height_mm.is_finite() && upper_height_mm > 0.0) {
        return Err(ParamError::new(
            "gauge_height_mm",
            "a height > 0 mm above the tip",
            upper_height_mm,
        ));
    }
    let d = (upper_mm[0] - tip_mm[0]).hypot(upper_mm[1] - tip_mm[1]);
    let tip = tip_mm[0].hypot(tip_mm[1]);
    Ok(AxisSplit {
        tip_offset_mm: tip,
        upper_offset_mm: upper_mm[0].hypot(upper_mm[1]),
        upper_height_mm,
        tilt_mm_per_mm: d / upper_height_mm,
        dominated_by: if d > 0.5 * tip { "tilt" } else { "offset" }.into(),
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    fn input(k: usize, rho_um: f64, lambda_deg: f64, fz: f64) -> VerdictInput {
        VerdictInput {
            runout: Runout::new(rho_um * 1e-3, lambda_deg.to_radians()).unwrap(),
            offset_se_mm: None,
            cutter: Some(Cutter::flat(10.0, k, 0.0).unwrap()),
            height_mm: 0.0,
            fz_mm: Some(fz),
            tolerance_tir_mm: None,
        }
    }

    /// The issue's hand case: K = 4, D 10, ρ 10 µm at λ = 0, f_z 0.05 mm.
    /// ψ_i = −90°·i, so R_i = sqrt(R² + ρ² + 2Rρ cos(90°·i)) (eq. 0.1), R = 5 mm:
    /// R_0 = 5.010, R_1 = R_3 = sqrt(25 + 1e-4) = 5.00000999999, R_2 = 4.990.
    /// Arc chips (eq. 0.4, φ = 90°), m = 1 is the minimum for every tooth here:
    /// h_0 = f_z + R_0 − R_3 = 0.05 + 0.00999001 = 0.05999001,
    /// h_1 = f_z + R_1 − R_0 = 0.04000999, h_2 = 0.05 + R_2 − R_1 = 0.03999001,
    /// h_3 = 0.05 + R_3 − R_2 = 0.06000999. Σ = 0.2 = K·f_z.
    /// Most loaded: tooth 3 (0.06001 mm); f_z' = 0.05²/0.06000999 = 0.0416597 mm,
    /// productivity loss 16.68 %.
    #[test]
    fn k4_rho10_fz005_by_hand() {
        let v = verdict(&input(4, 10.0, 0.0, 0.05)).unwrap();
        let r1 = (25.0f64 + 1e-4).sqrt();
        let r = [5.010, r1, 4.990, r1];
        for (t, want) in v.teeth.iter().zip(r) {
            assert!((t.radius_mm - want).abs() < 1e-12, "{t:?}");
        }
        let h = [
            0.05 + 5.010 - r1,
            0.05 + r1 - 5.010,
            0.05 + 4.990 - r1,
            0.05 + r1 - 4.990,
        ];
        for (t, want) in v.teeth.iter().zip(h) {
            assert!((t.max_chip_mm.unwrap() - want).abs() < 1e-12, "{t:?}");
            assert!((t.load_share.unwrap() - want / 0.2).abs() < 1e-12);
        }
        assert_eq!(v.most_loaded_tooth, Some(3));
        assert!((v.max_chip_mm.unwrap() - 0.06000999).abs() < 1e-8);
        let comp = 0.05 * 0.05 / h[3];
        assert!((v.compensated_fz_mm.unwrap() - comp).abs() < 1e-15);
        assert!((comp - 0.0416597).abs() < 1e-7);
        assert!((v.productivity_loss_percent.unwrap() - 16.680).abs() < 1e-3);
        // slot oversize 2(R_0 − R) = 2ρ exactly (tooth 0 points along e)
        assert!((v.slot_oversize_mm - 0.020).abs() < 1e-12);
        // TIR 20 µm against the default 10 µm (D = 10 mm, ISO 15488 class 1)
        assert_eq!(v.status, Status::Fail);
        assert!((v.tir_mm - 0.020).abs() < 1e-15);
        assert_eq!(v.tolerance_tir_mm, 0.010);
        assert!(v.idle_teeth.is_empty());
    }

    /// K = 2, ρ 10 µm, f_z 5 µm: tooth 1 is 20 µm smaller and never cuts; tooth 0 takes 2·f_z,
    /// all the load; f_z' = f_z/2, half the productivity.
    #[test]
    fn a_tooth_that_does_not_cut() {
        let v = verdict(&input(2, 10.0, 0.0, 0.005)).unwrap();
        assert!((v.teeth[0].max_chip_mm.unwrap() - 0.010).abs() < 1e-12);
        assert_eq!(v.teeth[1].max_chip_mm, Some(0.0));
        assert_eq!(v.idle_teeth, vec![1]);
        assert_eq!(v.teeth[0].load_share, Some(1.0));
        assert!((v.compensated_fz_mm.unwrap() - 0.0025).abs() < 1e-12);
        assert!((v.productivity_loss_percent.unwrap() - 50.0).abs() < 1e-9);
    }

    /// Status with the ±2σ band, tolerance 20 µm TIR: ρ = 9 ± 0.4 µm → 2(9 + 0.8) = 19.6 ≤ 20:
    /// pass; ρ = 9.9 ± 0.4 → TIR interval 18.2..21.4 contains 20: marginal; ρ = 11 ± 0.4 →
    /// 2(11 − 0.8) = 20.4 > 20: fail.
    #[test]
    fn status_bands() {
        let st = |rho: f64, se: f64| {
            let mut i = input(4, rho, 0.0, 0.05);
            i.offset_se_mm = Some(se * 1e-3);
            i.tolerance_tir_mm = Some(0.020);
            verdict(&i).unwrap().status
        };
        assert_eq!(st(9.0, 0.4), Status::Pass);
        assert_eq!(st(9.1, 0.4), Status::Pass);
        assert_eq!(st(9.9, 0.4), Status::Marginal);
        assert_eq!(st(11.0, 0.4), Status::Fail);
        // without an SE the status is a plain comparison
        assert_eq!(st(10.0, 0.0), Status::Pass);
        assert_eq!(st(10.01, 0.0), Status::Fail);
    }

    #[test]
    fn bad_inputs_are_named() {
        let mut i = input(4, 5.0, 0.0, 0.05);
        i.tolerance_tir_mm = Some(0.0);
        assert!(verdict(&i)
            .unwrap_err()
            .to_string()
            .contains("tolerance_um"));
        let mut i = input(4, 5.0, 0.0, 0.05);
        i.offset_se_mm = Some(f64::NAN);
        assert!(verdict(&i)
            .unwrap_err()
            .to_string()
            .contains("offset_um_se"));
        assert!(axis_split([0.0; 2], [0.0; 2], 0.0)
            .unwrap_err()
            .to_string()
            .contains("gauge_height_mm"));
    }

    #[test]
    fn without_a_cutter_only_the_status_and_the_bound() {
        let v = verdict(&VerdictInput {
            runout: Runout::new(0.003, 1.0).unwrap(),
            offset_se_mm: None,
            cutter: None,
            height_mm: 0.0,
            fz_mm: Some(0.05),
            tolerance_tir_mm: None,
        })
        .unwrap();
        assert_eq!(v.status, Status::Pass);
        assert!(v.teeth.is_empty() && v.compensated_fz_mm.is_none());
        assert!((v.slot_oversize_mm - 0.006).abs() < 1e-15);
    }

    #[test]
    fn parallel_offset_is_not_tilt() {
        let s = axis_split([0.005, 0.0], [0.0052, 0.0], 40.0).unwrap();
        assert_eq!(s.dominated_by, "offset");
        assert!((s.tilt_mm_per_mm - 0.0002 / 40.0).abs() < 1e-15);
    }

    proptest! {
        /// Over realistic ranges (K 2–8, D 1–25 mm, ρ 0–30 µm, f_z 2–200 µm, any λ, helix
        /// 0–45° at a height within the flute): the shares sum to 1 (the teeth remove K·f_z per
        /// revolution together), every share is in [0, 1], the most loaded tooth has the largest
        /// chip ≥ f_z, the compensated feed is ≤ f_z and > 0, and the slot oversize ≤ 2ρ.
        #[test]
        fn shares_sum_to_one_and_compensation_slows_down(
            k in 2usize..=8,
            d in 1.0f64..25.0,
            rho_um in 0.0f64..30.0,
            lambda in -180.0f64..180.0,
            fz_um in 2.0f64..200.0,
            helix in 0.0f64..45.0,
            zf in 0.0f64..1.0,
        ) {
            let cutter = Cutter::flat(d, k, helix.to_radians()).unwrap();
            let v = verdict(&VerdictInput {
                runout: Runout::new(rho_um * 1e-3, lambda.to_radians()).unwrap(),
                offset_se_mm: Some(0.1e-3),
                cutter: Some(cutter),
                height_mm: zf * d,
                fz_mm: Some(fz_um * 1e-3),
                tolerance_tir_mm: None,
            }).unwrap();
            let fz = fz_um * 1e-3;
            let sum: f64 = v.teeth.iter().map(|t| t.load_share.unwrap()).sum();
            prop_assert!((sum - 1.0).abs() < 1e-9, "sum {sum}");
            let hsum: f64 = v.teeth.iter().map(|t| t.max_chip_mm.unwrap()).sum();
            prop_assert!((hsum - k as f64 * fz).abs() < 1e-9 * k as f64, "Σh {hsum}");
            for t in &v.teeth {
                let s = t.load_share.unwrap();
                prop_assert!((0.0..=1.0 + 1e-12).contains(&s));
            }
            let hmax = v.max_chip_mm.unwrap();
            prop_assert!(hmax >= fz * (1.0 - 1e-9));
            let imax = v.most_loaded_tooth.unwrap();
            prop_assert_eq!(v.teeth[imax].max_chip_mm.unwrap(), hmax);
            let c = v.compensated_fz_mm.unwrap();
            prop_assert!(c <= fz && c > 0.0);
            prop_assert!(v.slot_oversize_mm <= 2.0 * rho_um * 1e-3 + 1e-12);
            let loss = v.productivity_loss_percent.unwrap();
            prop_assert!((0.0..100.0).contains(&loss));
        }
    }
}
