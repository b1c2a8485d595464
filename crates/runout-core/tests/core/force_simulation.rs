//! Force simulation tests of the foundation issue: the reference case, conventions, chip
//! conservation under runout, skipping, first-order chip, helix discretisation.

use approx::assert_abs_diff_eq;
use proptest::prelude::*;
use runout_core::*;
use std::f64::consts::PI;

const REF_COEF: ([f64; 3], [f64; 3]) = ([1889.2, 806.1, 291.0], [63.12, 113.7, -3.1]);

fn reference(runout: Runout, coef: CuttingCoefficients, helix: f64) -> (ForceModel, ArcChip) {
    let cutter = Cutter::flat(10.0, 4, f64::to_radians(helix)).unwrap();
    let cut = Cut::new(3240.0, 0.08, 1.0)
        .unwrap()
        .radial(2.0, MillingMode::Down, &cutter)
        .unwrap();
    let chip = ArcChip::new(&cutter, &runout, 0.08).unwrap();
    (
        ForceModel {
            cutter,
            runout,
            cut,
            coefficients: coef,
        },
        chip,
    )
}

fn coef() -> CuttingCoefficients {
    CuttingCoefficients::new(REF_COEF.0, REF_COEF.1).unwrap()
}

#[test]
fn reference_case_peak_at_entry_angle() {
    // Analytic: h = 0.08·sin(126.87°) = 0.064 mm, |F_xy| = hypot(K_tc h + K_te, K_rc h + K_re)·a_p = 247.361 N.
    let h = 0.08 * 0.8;
    let analytic = (1889.2 * h + 63.12f64).hypot(806.1 * h + 113.7);
    assert_abs_diff_eq!(analytic, 247.361, epsilon = 5e-4);
    let (m, chip) = reference(Runout::none(), coef(), 0.0);
    let s = m.simulate(&chip, &Sampling::new(1.0, 0.01, 1).unwrap());
    let peaks = tooth_peaks(&s, &m.cutter, &m.cut);
    for p in &peaks {
        // ±0.02 N: a 0.01° grid lands at most 0.01° after φ_st where d|F|/dφ ≈ 92 N/rad.
        assert_abs_diff_eq!(p.peak_fxy, 247.361, epsilon = 0.02);
        assert_abs_diff_eq!(p.immersion.to_degrees(), 126.87, epsilon = 0.011);
    }
    // 1° grid aligned on whole degrees misses φ_st: both public simulators give 247.149 N.
    let s1 = m.simulate(&chip, &Sampling::new(1.0, 1.0, 1).unwrap());
    let p1 = tooth_peaks(&s1, &m.cutter, &m.cut);
    assert_abs_diff_eq!(p1[0].peak_fxy, 247.149, epsilon = 0.001);
}

#[test]
fn conventions_check_pins_tooth_numbering_and_lambda() {
    let k0 = coef().without_edge();
    let expect = [
        (0.0, [147.87, 115.04, 115.01, 147.90]),
        (90.0, [115.04, 115.01, 147.90, 147.87]),
    ];
    for (lam, want) in expect {
        let (m, chip) = reference(Runout::new(0.008, f64::to_radians(lam)).unwrap(), k0, 0.0);
        let s = m.simulate(&chip, &Sampling::new(1.0, 0.01, 1).unwrap());
        let p = tooth_peaks(&s, &m.cutter, &m.cut);
        for i in 0..4 {
            assert_abs_diff_eq!(p[i].peak_fxy, want[i], epsilon = 0.05);
        }
    }
}

#[test]
fn forces_act_on_the_workpiece() {
    // Single straight tooth in a slot at φ = 90° (tooth at +x, moving −y): the workpiece is pushed
    // along the tooth velocity (−y) by F_t and along +x (outward) by F_r.
    let cutter = Cutter::flat(10.0, 1, 0.0).unwrap();
    let cut = Cut::new(1000.0, 0.1, 1.0)
        .unwrap()
        .radial(10.0, MillingMode::Slot, &cutter)
        .unwrap();
    let k = CuttingCoefficients::new([1000.0, 400.0, 100.0], [0.0; 3]).unwrap();
    let m = ForceModel {
        cutter: cutter.clone(),
        runout: Runout::none(),
        cut,
        coefficients: k,
    };
    let chip = ArcChip::new(&cutter, &Runout::none(), 0.1).unwrap();
    let s = m.simulate(&chip, &Sampling::new(1.0, 90.0, 1).unwrap());
    // sample 1 is θ = 90°: h = 0.1, F_t = 100 N, F_r = 40 N, F_a = 10 N
    assert_abs_diff_eq!(s.fx[1], 40.0, epsilon = 1e-9);
    assert_abs_diff_eq!(s.fy[1], -100.0, epsilon = 1e-9);
    assert_abs_diff_eq!(s.fz[1], -10.0, epsilon = 1e-9);
    assert_abs_diff_eq!(s.torque[1], 100.0 * 5.0 * 1e-3, epsilon = 1e-12);
}

#[test]
fn zero_helix_equals_single_disk() {
    let (m, chip) = reference(Runout::new(0.01, 0.4).unwrap(), coef(), 0.0);
    let a = m.simulate(&chip, &Sampling::new(1.0, 0.5, 1).unwrap());
    let b = m.simulate(&chip, &Sampling::new(1.0, 0.5, 7).unwrap());
    for q in 0..a.len() {
        assert_abs_diff_eq!(a.fx[q], b.fx[q], epsilon = 1e-9);
        assert_abs_diff_eq!(a.fy[q], b.fy[q], epsilon = 1e-9);
        assert_abs_diff_eq!(a.fz[q], b.fz[q], epsilon = 1e-9);
    }
}

/// RMS difference of F_x, F_y between two series.
fn rms_diff(a: &ForceSeries, b: &ForceSeries) -> f64 {
    let n = a.len() as f64;
    (a.fx
        .iter()
        .zip(&b.fx)
        .chain(a.fy.iter().zip(&b.fy))
        .map(|(x, y)| (x - y).powi(2))
        .sum::<f64>()
        / (2.0 * n))
        .sqrt()
}

#[test]
fn helix_disk_refinement_converges_at_first_order() {
    // Edge forces switch on/off where each disk enters and leaves the cut, so the integrand over z
    // is discontinuous and the midpoint rule converges at O(dz) pointwise (measured rate ≈ 1).
    let (m, chip) = reference(Runout::new(0.008, 0.3).unwrap(), coef(), 30.0);
    let fine = m.simulate(&chip, &Sampling::new(1.0, 0.25, 2560).unwrap());
    let errs: Vec<f64> = [10, 20, 40, 80]
        .iter()
        .map(|&d| {
            rms_diff(
                &m.simulate(&chip, &Sampling::new(1.0, 0.25, d).unwrap()),
                &fine,
            )
        })
        .collect();
    for w in errs.windows(2) {
        let rate = (w[0] / w[1]).log2();
        assert!(w[1] < w[0], "error must decrease: {errs:?}");
        assert!(
            (0.8..=2.2).contains(&rate),
            "observed rate {rate:.2} not in [0.8, 2.2]: {errs:?}"
        );
    }
    assert!(errs[3] < 0.5, "80 disks within 0.5 N RMS of 2560: {errs:?}");
}

#[test]
fn first_order_chip_with_runout_without_skipping() {
    // Down milling a_e = 2: h_i is largest at entry φ_st (sin φ decreasing), so
    // max h_i = f_z·sin φ_st + R_i − R_{i−1} with R_i ≈ R + ρ·cos(λ + 2πi/K) (eq. 0.3).
    // Tolerance: second-order radius term ρ²/R plus the grid (f_z·|cos φ|·Δφ).
    let rho = 0.01;
    let lam = 0.9f64;
    let (m, chip) = reference(Runout::new(rho, lam).unwrap(), coef().without_edge(), 0.0);
    let step = 0.01f64;
    let s = m.simulate(&chip, &Sampling::new(1.0, step, 1).unwrap());
    let (st, _) = m.cut.immersion(&m.cutter);
    let r1 = |i: usize| 5.0 + rho * (lam + 2.0 * PI * i as f64 / 4.0).cos();
    let tol = rho * rho / 5.0 + 0.08 * st.cos().abs() * step.to_radians();
    for i in 0..4 {
        let want = 0.08 * st.sin() + r1(i) - r1((i + 3) % 4);
        assert!(
            (s.max_chip[i] - want).abs() < tol,
            "tooth {i}: {} vs {want} (tol {tol})",
            s.max_chip[i]
        );
    }
}

fn sum_of_chips(k: usize, rho: f64, lam: f64, fz: f64, phi: f64) -> f64 {
    let cutter = Cutter::flat(10.0, k, 0.0).unwrap();
    let chip = ArcChip::new(&cutter, &Runout::new(rho, lam).unwrap(), fz).unwrap();
    let at = chip.at_height(0.0);
    (0..k)
        .map(|i| at.thickness(i, phi, phi.sin(), phi.cos()))
        .sum()
}

fn mean_force(
    k: usize,
    rho: f64,
    lam: f64,
    ae: f64,
    mode: MillingMode,
    fz: f64,
    coef: CuttingCoefficients,
) -> [f64; 4] {
    let cutter = Cutter::flat(10.0, k, 0.0).unwrap();
    let runout = Runout::new(rho, lam).unwrap();
    let cut = Cut::new(3000.0, fz, 1.0)
        .unwrap()
        .radial(ae, mode, &cutter)
        .unwrap();
    let chip = ArcChip::new(&cutter, &runout, fz).unwrap();
    let m = ForceModel {
        cutter,
        runout,
        cut,
        coefficients: coef,
    };
    // 0.25° divides 360/K for K ≤ 6, so every tooth samples the same immersion grid
    m.simulate(&chip, &Sampling::new(1.0, 0.25, 1).unwrap())
        .means()
}

fn mode_of(i: u8) -> MillingMode {
    [MillingMode::Up, MillingMode::Down, MillingMode::Slot][i as usize % 3]
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(48))]

    /// Runout redistributes the chip among teeth but conserves it: Σ_i h_i(φ) = K·f_z·sin φ.
    #[test]
    fn chip_is_conserved_over_a_revolution(k in 1usize..7, rho_um in 0.0f64..40.0, lam in -3.2f64..3.2, fz in 0.005f64..0.2, phi in 0.01f64..3.13) {
        let s = sum_of_chips(k, rho_um * 1e-3, lam, fz, phi);
        prop_assert!((s - k as f64 * fz * phi.sin()).abs() < 1e-12, "sum {s}");
    }

    /// Without edge coefficients the mean force over a revolution does not depend on runout.
    /// (The torque does, at second order: T = Σ F_t·R_i weights each tooth's chip by its radius.)
    #[test]
    fn mean_force_independent_of_runout(k in 1usize..7, rho_um in 0.0f64..30.0, lam in -3.2f64..3.2, ae in 0.3f64..9.9, mode in 0u8..3) {
        let c = coef().without_edge();
        let with = mean_force(k, rho_um * 1e-3, lam, ae, mode_of(mode), 0.05, c);
        let without = mean_force(k, 0.0, 0.0, ae, mode_of(mode), 0.05, c);
        for q in 0..3 {
            let scale = without[q].abs().max(1.0);
            prop_assert!((with[q] - without[q]).abs() < 1e-9 * scale, "component {q}: {} vs {}", with[q], without[q]);
        }
    }

    /// Skipping: with ρ = 30 µm against f_z = 0.02 mm a tooth cuts nothing over its whole slot
    /// engagement exactly when some earlier tooth reaches beyond it by the feed between them,
    /// ∃ m: R_{i−m} − R_i ≥ m·f_z (checked at φ = 90°, on the grid); for K ≥ 3 this always holds
    /// at this ρ/f_z, for K = 2 when |cos λ| > 1/3. The chip is conserved either way.
    #[test]
    fn skipping_teeth_and_conservation(k in 2usize..7, lam in -3.2f64..3.2, phi in 0.05f64..3.09) {
        let cutter = Cutter::flat(10.0, k, 0.0).unwrap();
        let runout = Runout::new(0.03, lam).unwrap();
        let cut = Cut::new(3000.0, 0.02, 1.0).unwrap().radial(10.0, MillingMode::Slot, &cutter).unwrap();
        let chip = ArcChip::new(&cutter, &runout, 0.02).unwrap();
        let m = ForceModel { cutter, runout, cut, coefficients: coef().without_edge() };
        let s = m.simulate(&chip, &Sampling::new(1.0, 0.5, 1).unwrap());
        let radii = m.runout.tooth_radii(&m.cutter, 0.0);
        for i in 0..k {
            let margin = (1..k).map(|mm| radii[(i + k - mm) % k] - radii[i] - mm as f64 * 0.02).fold(f64::MIN, f64::max);
            if margin.abs() > 1e-9 {
                prop_assert_eq!(s.max_chip[i] == 0.0, margin > 0.0, "tooth {} margin {} max chip {}", i, margin, s.max_chip[i]);
            }
        }
        if k >= 3 {
            prop_assert!(s.max_chip.contains(&0.0), "no tooth skipped: {:?}", s.max_chip);
        }
        let total = sum_of_chips(k, 0.03, lam, 0.02, phi);
        prop_assert!((total - k as f64 * 0.02 * phi.sin()).abs() < 1e-12);
    }
}

#[test]
fn edge_forces_make_mean_force_depend_on_runout_when_teeth_skip() {
    // Edge forces act only where h > 0: a skipping tooth contributes none, so the mean changes.
    let with = mean_force(4, 0.03, 0.0, 10.0, MillingMode::Slot, 0.02, coef());
    let without = mean_force(4, 0.0, 0.0, 10.0, MillingMode::Slot, 0.02, coef());
    assert!(
        (with[3] - without[3]).abs() > 1e-3 * without[3].abs(),
        "{with:?} vs {without:?}"
    );
}
