//! Seed 003 acceptance: Table 2 from Table 1 (methods.md §4.3, §4.4, §4.6, §7).

use runout_core::identify::*;
use std::f64::consts::PI;

/// Table 1: (f_t mm, a_z mm, peaks of edges 0..3 in N).
const TABLE1: [(f64, f64, [f64; 4]); 8] = [
    (0.08, 1.00, [366.6, 307.9, 259.9, 326.6]),
    (0.10, 1.00, [427.9, 373.2, 321.3, 386.6]),
    (0.12, 1.00, [457.2, 402.6, 363.9, 417.2]),
    (0.14, 1.00, [519.9, 469.2, 422.6, 483.9]),
    (0.10, 0.50, [233.3, 206.6, 173.3, 201.3]),
    (0.10, 0.75, [341.2, 314.6, 265.3, 283.9]),
    (0.10, 1.00, [446.6, 414.6, 339.9, 363.9]),
    (0.10, 1.25, [537.2, 490.5, 398.6, 441.2]),
];

/// Table 2 as printed: C (N), A (N), φ (deg), R², α₀ (deg), ρ (mm).
const TABLE2: [(f64, f64, f64, f64, f64, f64); 8] = [
    (315.0, 53.6, 100.0, 0.998, -35.0, 0.0077),
    (376.8, 52.9, 97.2, 0.990, -37.8, 0.0079),
    (410.3, 47.3, 98.8, 1.000, -36.1, 0.0078),
    (473.5, 48.5, 98.7, 0.995, -36.3, 0.0081),
    (203.5, 30.0, 84.9, 1.000, -50.1, 0.0083),
    (301.5, 41.5, 68.3, 0.997, -66.7, 0.0078),
    (391.5, 59.6, 64.8, 0.998, -70.2, 0.0086),
    (467.1, 73.8, 70.5, 1.000, -64.5, 0.0089),
];

fn beta() -> f64 {
    (3.0f64 / 5.0).acos() // arccos((R − a_e)/R), R 5 mm, a_e 2 mm
}

fn tests() -> Vec<PeakTest> {
    TABLE1
        .iter()
        .enumerate()
        .map(|(j, (f, a, p))| PeakTest {
            label: format!("{}", j + 1),
            ap_mm: *a,
            conditions: PeakConditions::new(*f, beta()).unwrap(),
            peak_immersion_rad: beta(),
            peaks: ToothPeaks::new(p.to_vec()).unwrap(),
            fx_at_peak_n: (j == 0).then_some(315.9),
            fy_at_peak_n: (j == 0).then_some(-89.3), // seed frame +89.3 → workpiece frame
        })
        .collect()
}

#[test]
fn table2_reproduced_under_closed_period_hypothesis() {
    // Acceptance tolerances of issue 3: C ± 0.5 N, A ± 1 N, φ ± 0.5°, α₀ ± 0.5°, ρ ± 0.3 µm.
    // R² of test 2 is printed 0.990 but is 0.996 (methods.md §4.3: probable misprint) → ± 0.01.
    for (j, ((f, _, p), t2)) in TABLE1.iter().zip(TABLE2).enumerate() {
        let peaks = ToothPeaks::new(p.to_vec()).unwrap();
        let cond = PeakConditions::new(*f, beta()).unwrap();
        let fit = sine_fit(&peaks, &cond, SineHypothesis::ClosedPeriod).unwrap();
        let (c, a, phi, r2, alpha0, rho) = t2;
        let msg = format!("test {}: {fit:?}", j + 1);
        assert!((fit.mean.value - c).abs() <= 0.5, "{msg}");
        assert!((fit.amplitude.value - a).abs() <= 1.0, "{msg}");
        assert!((fit.phase.value.to_degrees() - phi).abs() <= 0.5, "{msg}");
        assert!(
            (fit.angle.value.to_degrees() - alpha0).abs() <= 0.5,
            "{msg}"
        );
        assert!((fit.offset.value - rho).abs() <= 0.3e-3, "{msg}");
        assert!((fit.r_squared - r2).abs() <= 0.01, "{msg}");
        // H1 reproduces the printed rounding much more tightly (methods.md §4.3: ≤ 0.08 N, 0.08°).
        assert!((fit.mean.value - c).abs() <= 0.1, "{msg}");
        assert!((fit.phase.value.to_degrees() - phi).abs() <= 0.1, "{msg}");
    }
}

#[test]
fn section7_vectors_h1_and_h0() {
    let peaks = ToothPeaks::new(TABLE1[0].2.to_vec()).unwrap();
    let cond = PeakConditions::new(0.08, beta()).unwrap();
    let h1 = sine_fit(&peaks, &cond, SineHypothesis::ClosedPeriod).unwrap();
    // methods.md §7: C 314.96, A 53.60, φ 100.05°, α₀ −34.95°, ρ 7.70 µm (2-decimal rounding)
    assert!((h1.mean.value - 314.96).abs() < 0.006);
    assert!((h1.amplitude.value - 53.60).abs() < 0.006);
    assert!((h1.phase.value.to_degrees() - 100.05).abs() < 0.006);
    assert!((h1.angle.value.to_degrees() + 34.95).abs() < 0.006);
    assert!((h1.offset.value * 1e3 - 7.70).abs() < 0.006);
    let h0 = sine_fit(&peaks, &cond, SineHypothesis::Teeth).unwrap();
    // H0: C 315.25, A 54.16, φ 99.94°, R² 0.9973
    assert!((h0.mean.value - 315.25).abs() < 0.006);
    assert!((h0.amplitude.value - 54.16).abs() < 0.006);
    assert!((h0.phase.value.to_degrees() - 99.94).abs() < 0.006);
    assert!((h0.r_squared - 0.9973).abs() < 0.00006);
    assert_eq!(h0.dof, 1);
    // K = 4 DFT closed form: C = mean, a = (F1 − F3)/2, b = (F0 − F2)/2 (methods.md §4.2)
    let f = &TABLE1[0].2;
    let (a, b) = ((f[1] - f[3]) / 2.0, (f[0] - f[2]) / 2.0);
    assert!((h0.amplitude.value - a.hypot(b)).abs() < 1e-9);
    // residual-based standard errors: σ̂² = RSS/1, Var(C) = σ̂²/4, Var(a) = Var(b) = σ̂²/2
    let rss: f64 = f.iter().zip(&h0.fitted).map(|(v, p)| (v - p).powi(2)).sum();
    assert!((h0.mean.se.unwrap() - (rss / 4.0).sqrt()).abs() < 1e-9);
    assert!((h0.amplitude.se.unwrap() - (rss / 2.0).sqrt()).abs() < 1e-9);
    assert!((h0.phase.se.unwrap() - (rss / 2.0).sqrt() / h0.amplitude.value).abs() < 1e-9);
    assert_eq!(h0.error_source, ErrorSource::Residuals);
}

#[test]
fn secondary_regressions_and_cutting_coefficients() {
    let r = analyse_tests(&tests(), SineHypothesis::ClosedPeriod).unwrap();
    // K_T ≈ 4081.6, K_R ≈ 3116.6 N/mm² within 0.5 % (issue 3 acceptance)
    let k = r.tests[0].coefficients.unwrap();
    assert!((k.kt / 4081.6 - 1.0).abs() < 0.005, "{k:?}");
    assert!((k.kr / 3116.6 - 1.0).abs() < 0.005, "{k:?}");
    assert!((k.k / 5136.0 - 1.0).abs() < 0.005, "{k:?}");
    // methods.md §4.4, tests 5–8: A = 59.8 a − 1.1 (paper 59.9 a), through origin 58.7 a (R² 0.993);
    // C = 32.6 + 3523.2 f a (paper 32.7 + 3523.1, R² 0.997); from the H1 C values 32.8 + 3521.3
    // (the spec's figure used slightly different C values) → slope ± 0.1 %, intercept ± 0.3 N
    let depth = &r.tests[4..8];
    let ap: Vec<f64> = depth.iter().map(|t| t.ap_mm).collect();
    let amp: Vec<f64> = depth.iter().map(|t| t.fit.amplitude.value).collect();
    let c: Vec<f64> = depth.iter().map(|t| t.fit.mean.value).collect();
    let fa: Vec<f64> = depth.iter().map(|t| t.fz_mm * t.ap_mm).collect();
    let a1 = fit_line(&ap, &amp, true).unwrap();
    assert!(
        (a1.slope - 59.8).abs() < 0.1 && (a1.intercept + 1.1).abs() < 0.1,
        "{a1:?}"
    );
    assert!((a1.r_squared - 0.993).abs() < 0.001, "{a1:?}");
    let a0 = fit_line(&ap, &amp, false).unwrap();
    assert!((a0.slope - 58.7).abs() < 0.1, "{a0:?}");
    let c1 = fit_line(&fa, &c, true).unwrap();
    assert!(
        (c1.slope - 3523.2).abs() < 3.5 && (c1.intercept - 32.6).abs() < 0.3,
        "{c1:?}"
    );
    assert!((c1.r_squared - 0.997).abs() < 0.001, "{c1:?}");
    // mean A over tests 1–4: 50.6 (paper 50.7)
    let mean_a: f64 = r.tests[..4]
        .iter()
        .map(|t| t.fit.amplitude.value)
        .sum::<f64>()
        / 4.0;
    assert!((mean_a - 50.6).abs() < 0.05);
    // means: α₀ −49.59° (arithmetic), ρ 8.14 µm; vector mean 7.91 µm at −50.0° (methods.md §4.3)
    assert!((r.arithmetic_mean.1.to_degrees() + 49.59).abs() < 0.05); // fitted: −49.57
    assert!((r.arithmetic_mean.0 * 1e3 - 8.16).abs() < 0.01); // §4.6 table: 8.16 (paper 8.1)
    assert!((r.vector_mean.0 * 1e3 - 7.91).abs() < 0.01);
    assert!((r.vector_mean.1.to_degrees() + 50.0).abs() < 0.05);
}

#[test]
fn pooled_edge_aware_fit_matches_section_4_6() {
    let t = tests();
    // methods.md §4.6: none ρ 8.10 ± 1.13 µm, α₀ −50.7 ± 7.9°, rms 26.6 N;
    // constant ρ 9.86 ± 1.06 µm, rms 18.7 N; constant + E·a: ρ 12.3 ± 1.3 µm, α₀ −50.7 ± 4.3°, rms 14.0 N
    let none = pooled_fit(&t, EdgeModel::None).unwrap();
    let cst = pooled_fit(&t, EdgeModel::Constant).unwrap();
    let edge = pooled_fit(&t, EdgeModel::ConstantPlusDepth).unwrap();
    let um = |e: &Estimate| (e.value * 1e3, e.se.unwrap() * 1e3);
    let deg = |e: &Estimate| (e.value.to_degrees(), e.se.unwrap().to_degrees());
    println!(
        "none {:?} {:?} {}",
        um(&none.offset),
        deg(&none.angle),
        none.residual_rms
    );
    println!(
        "cst {:?} {:?} {}",
        um(&cst.offset),
        deg(&cst.angle),
        cst.residual_rms
    );
    println!(
        "edge {:?} {:?} {}",
        um(&edge.offset),
        deg(&edge.angle),
        edge.residual_rms
    );
    assert!((um(&none.offset).0 - 8.10).abs() < 0.05);
    assert!((deg(&none.angle).0 + 50.7).abs() < 0.1);
    assert!((none.residual_rms - 26.6).abs() < 0.1);
    assert!((um(&cst.offset).0 - 9.86).abs() < 0.05);
    assert!((cst.residual_rms - 18.7).abs() < 0.1);
    assert!((um(&edge.offset).0 - 12.3).abs() < 0.05);
    assert!((deg(&edge.angle).0 + 50.7).abs() < 0.1);
    assert!((edge.residual_rms - 14.0).abs() < 0.1);
    // standard errors as in §4.6 (the spec's script: σ̂² = RSS/(n − p) covariance)
    assert!(
        (um(&edge.offset).1 - 1.3).abs() < 0.1,
        "{:?}",
        um(&edge.offset)
    );
    assert!(
        (deg(&edge.angle).1 - 4.3).abs() < 0.2,
        "{:?}",
        deg(&edge.angle)
    );
    assert!(
        (um(&none.offset).1 - 1.13).abs() < 0.05,
        "{:?}",
        um(&none.offset)
    );
    let r = analyse_tests(&t, SineHypothesis::Teeth).unwrap();
    assert_eq!(r.pooled.unwrap().edge_model, EdgeModel::ConstantPlusDepth);
    assert_eq!(r.edge_corrected_offsets.unwrap().len(), 8);
    // §4.6 table, per-test ρ (µm) with C − 32.7 N and with C − 114.2·a_z (H1 fits)
    let r = analyse_tests(&t, SineHypothesis::ClosedPeriod).unwrap();
    let c327 = [8.59, 8.70, 8.50, 8.71, 9.94, 8.73, 9.40, 9.61];
    let c1142 = [12.1, 11.4, 10.8, 10.7, 11.6, 10.9, 12.2, 12.9];
    for (j, tr) in r.tests.iter().enumerate() {
        let a = tr.fit.edge_corrected_offset(32.7) * 1e3;
        let b = tr.fit.edge_corrected_offset(114.2 * tr.ap_mm) * 1e3;
        assert!((a - c327[j]).abs() < 0.011, "test {}: {a}", j + 1);
        assert!((b - c1142[j]).abs() < 0.051, "test {}: {b}", j + 1);
    }
}

#[test]
fn degenerate_and_exactly_determined_cases() {
    let cond = PeakConditions::new(0.1, PI / 2.0).unwrap();
    let e = sine_fit(
        &ToothPeaks::new(vec![110.0, 90.0]).unwrap(),
        &cond,
        SineHypothesis::Teeth,
    )
    .unwrap_err();
    match &e {
        IdentifyError::DegenerateTwoTeeth {
            mean_n,
            a_sin_phi_n,
        } => {
            assert_eq!((*mean_n, *a_sin_phi_n), (100.0, 10.0));
        }
        other => panic!("{other:?}"),
    }
    assert!(e.to_string().contains("full-signal"));
    // K = 3: exactly determined → fitted values equal the peaks, R² = 1, no standard errors
    let p3 = ToothPeaks::new(vec![120.0, 95.0, 100.0]).unwrap();
    let f3 = sine_fit(&p3, &cond, SineHypothesis::Teeth).unwrap();
    assert_eq!(f3.dof, 0);
    assert!(f3.offset.se.is_none() && f3.error_source == ErrorSource::Unavailable);
    assert!((f3.r_squared - 1.0).abs() < 1e-12);
    for (a, b) in f3.fitted.iter().zip(p3.values()) {
        assert!((a - b).abs() < 1e-9);
    }
    // with per-tooth standard errors, K = 3 does get standard errors (propagated)
    let f3s = sine_fit(
        &p3.with_se(vec![1.0; 3]).unwrap(),
        &cond,
        SineHypothesis::Teeth,
    )
    .unwrap();
    assert_eq!(f3s.error_source, ErrorSource::PerToothSe);
    // Var(C) = 1/3 for unit errors, Var(a) = Var(b) = 2/3
    assert!((f3s.mean.se.unwrap() - (1.0f64 / 3.0).sqrt()).abs() < 1e-12);
    assert!((f3s.amplitude.se.unwrap() - (2.0f64 / 3.0).sqrt()).abs() < 1e-12);
}
