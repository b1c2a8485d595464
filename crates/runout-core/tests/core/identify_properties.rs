//! Property tests of the peak-based methods over realistic ranges: exact recovery from
//! model-generated peaks, and Monte-Carlo calibration of the reported standard errors.

use proptest::prelude::*;
use rand::{rngs::StdRng, SeedableRng};
use rand_distr::{Distribution, Normal};
use runout_core::identify::*;
use runout_core::runout::seed::seed003_phase_from_lambda;
use std::f64::consts::PI;

/// First-order per-tooth peaks: F_i = K_l·a·(f sin γ + ΔR_i) + edge (`kla` = K_l·a), ΔR_i = −2ρ sin(π/K) sin(λ + (2i−1)π/K).
fn peaks(k: usize, kla: f64, f: f64, sg: f64, rho: f64, lambda: f64, edge: f64) -> Vec<f64> {
    (0..k)
        .map(|i| {
            let dr = -2.0
                * rho
                * (PI / k as f64).sin()
                * (lambda + (2.0 * i as f64 - 1.0) * PI / k as f64).sin();
            kla * (f * sg + dr) + edge
        })
        .collect()
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 64, ..ProptestConfig::default() })]

    /// Noise-free first-order peaks: the sine fit returns ρ and λ exactly (eq. 12 and
    /// λ = φ − π + π/K are exact for this model), for K = 3..8 and both hypotheses.
    #[test]
    fn sine_fit_exact_on_first_order_peaks(k in 3usize..9, rho_um in 1.0f64..30.0, lam in -179.0f64..179.0,
                                            f in 0.03f64..0.2, g_deg in 20.0f64..90.0, closed in any::<bool>()) {
        let sg = g_deg.to_radians().sin();
        let rho = rho_um * 1e-3;
        prop_assume!(2.0 * rho * (PI / k as f64).sin() < f * sg); // every tooth cuts
        let p = ToothPeaks::new(peaks(k, 3000.0, f, sg, rho, lam.to_radians(), 0.0)).unwrap();
        let cond = PeakConditions::new(f, g_deg.to_radians()).unwrap();
        let hyp = if closed { SineHypothesis::ClosedPeriod } else { SineHypothesis::Teeth };
        let fit = sine_fit(&p, &cond, hyp).unwrap();
        // (H1 double-weights tooth 0, but the data are an exact sine: same answer)
        prop_assert!((fit.offset.value - rho).abs() < 1e-9, "{fit:?}");
        let dl = runout_core::angle::wrap_pi(fit.angle.value - lam.to_radians());
        prop_assert!(dl.abs() < 1e-9);
        let phase = seed003_phase_from_lambda(lam.to_radians(), k);
        prop_assert!(runout_core::angle::wrap_pi(fit.phase.value - phase).abs() < 1e-9);
    }

    /// Pooled edge-aware fit (methods.md §4.6) recovers ρ, λ, C₀, E and K exactly from
    /// noise-free peaks of tests at ≥ 2 feeds and depths.
    #[test]
    fn pooled_fit_exact(k in 3usize..7, rho_um in 2.0f64..20.0, lam in -179.0f64..179.0,
                        c0 in 0.0f64..50.0, e in 0.0f64..150.0, kl in 1000.0f64..6000.0) {
        let sg: f64 = 0.8;
        let gamma = sg.asin();
        let conds = [(0.08, 1.0), (0.12, 1.0), (0.1, 0.5), (0.1, 1.5)];
        prop_assume!(2.0 * rho_um * 1e-3 * (PI / k as f64).sin() < 0.08 * sg);
        let tests: Vec<PeakTest> = conds.iter().enumerate().map(|(j, &(f, a))| PeakTest {
            label: format!("{j}"),
            ap_mm: a,
            conditions: PeakConditions::new(f, gamma).unwrap(),
            peak_immersion_rad: gamma,
            peaks: ToothPeaks::new(peaks(k, kl * a, f, sg, rho_um * 1e-3, lam.to_radians(), c0 + e * a)).unwrap(),
            fx_at_peak_n: None,
            fy_at_peak_n: None,
        }).collect();
        let fit = pooled_fit(&tests, EdgeModel::ConstantPlusDepth).unwrap();
        prop_assert!((fit.offset.value * 1e3 - rho_um).abs() < 1e-6, "{fit:?}");
        prop_assert!(runout_core::angle::wrap_pi(fit.angle.value - lam.to_radians()).abs() < 1e-6);
        prop_assert!((fit.constant_n.unwrap().value - c0).abs() < 1e-6);
        prop_assert!((fit.edge_n_per_mm.unwrap().value - e).abs() < 1e-6);
        prop_assert!((fit.k_lumped.value - kl).abs() < 1e-6 * kl);
    }
}

#[test]
fn sine_fit_standard_errors_are_calibrated() {
    // Monte Carlo, K = 6 (3 residual dof), σ = 2 N on each peak: the spread of ρ and λ over 2000
    // trials matches the delta-method SE from the known per-tooth σ within 10 %, and the
    // residual-based SE (σ̂² = RSS/3) is right on average (mean of σ̂² within 10 % of σ²).
    let (k, f, sg, rho, lam) = (6, 0.1, 0.8, 0.008, 0.7);
    let clean = peaks(k, 3000.0, f, sg, rho, lam, 20.0);
    let cond = PeakConditions {
        fz_mm: f,
        sin_gamma: sg,
    };
    let mut rng = StdRng::seed_from_u64(3);
    let noise = Normal::new(0.0, 2.0).unwrap();
    let (mut rhos, mut lams, mut s2) = (Vec::new(), Vec::new(), Vec::new());
    let mut se_known = (0.0, 0.0);
    for _ in 0..2000 {
        let p: Vec<f64> = clean.iter().map(|v| v + noise.sample(&mut rng)).collect();
        let known = sine_fit(
            &ToothPeaks::new(p.clone())
                .unwrap()
                .with_se(vec![2.0; k])
                .unwrap(),
            &cond,
            SineHypothesis::Teeth,
        )
        .unwrap();
        let resid = sine_fit(&ToothPeaks::new(p).unwrap(), &cond, SineHypothesis::Teeth).unwrap();
        se_known = (known.offset.se.unwrap(), known.angle.se.unwrap());
        rhos.push(known.offset.value);
        lams.push(known.angle.value);
        s2.push(resid.residual_rms.powi(2) * k as f64 / 3.0);
    }
    let sd = |v: &[f64]| {
        let m = v.iter().sum::<f64>() / v.len() as f64;
        (v.iter().map(|x| (x - m).powi(2)).sum::<f64>() / (v.len() - 1) as f64).sqrt()
    };
    assert!(
        (sd(&rhos) / se_known.0 - 1.0).abs() < 0.1,
        "{} vs {}",
        sd(&rhos),
        se_known.0
    );
    assert!(
        (sd(&lams) / se_known.1 - 1.0).abs() < 0.1,
        "{} vs {}",
        sd(&lams),
        se_known.1
    );
    let mean_s2 = s2.iter().sum::<f64>() / s2.len() as f64;
    assert!((mean_s2 / 4.0 - 1.0).abs() < 0.1, "{mean_s2}");
}
