//! Chip-thickness models: asymptotics, 5-axis kinematics, trait/3-D agreement, (k₁,k₂) fit,
//! properties and the force simulation driven by every model.

use proptest::prelude::*;
use runout_core::chip::compare::{error_metrics, evaluate_models, sample_grid};
use runout_core::chip::*;
use runout_core::*;
use std::f64::consts::{PI, TAU};

fn deg(d: f64) -> f64 {
    d.to_radians()
}

/// Second-order bound on |h − f sin φ| for straight feed without runout (methods eq. 2.7):
/// f²cos²φ/2R + K f²|sin φ cos φ|/2πR ≤ f²/R·(1/2 + K/4π).
fn second_order_bound(f: f64, r: f64, k: usize) -> f64 {
    f * f / r * (0.5 + k as f64 / (4.0 * PI))
}

/// Eq. (2.7) in 2-D: h = f sin φ + f² cos²φ/2R − K f² sin φ cos φ/(2πR).
fn eq27(f: f64, r: f64, k: usize, phi: f64) -> f64 {
    let (s, c) = phi.sin_cos();
    f * s + f * f * c * c / (2.0 * r) - k as f64 * f * f * s * c / (TAU * r)
}

#[test]
fn no_runout_tends_to_fz_sin_phi() {
    let cutter = Cutter::flat(10.0, 4, 30.0f64.to_radians()).unwrap();
    for f in [0.05, 0.005, 0.0005] {
        let exact = ExactChip::new(&cutter, &Runout::none(), f).unwrap();
        for q in 1..36 {
            let phi = deg(5.0 * q as f64);
            let h = exact.thickness(q % 4, 3.0, phi);
            // first order: the deviation is bounded by the second-order terms (1 % margin)
            let err = (h - f * phi.sin()).abs();
            assert!(
                err <= 1.01 * second_order_bound(f, 5.0, 4),
                "f {f} φ {phi}: {err}"
            );
        }
    }
}

#[test]
fn no_runout_matches_eq27_to_third_order() {
    let cutter = Cutter::flat(10.0, 4, 0.0).unwrap();
    let max_err = |f: f64| {
        let exact = ExactChip::new(&cutter, &Runout::none(), f).unwrap();
        (1..36)
            .map(|q| deg(5.0 * q as f64))
            .map(|phi| (exact.thickness(0, 1.0, phi) - eq27(f, 5.0, 4, phi)).abs())
            .fold(0.0, f64::max)
    };
    let (e1, e2, e3) = (max_err(0.2), max_err(0.1), max_err(0.05));
    // third order: halving f divides the residual by 2³ = 8 (±25 % for the fourth-order rest)
    for ratio in [e1 / e2, e2 / e3] {
        assert!(
            (6.0..10.0).contains(&ratio),
            "ratio {ratio} ({e1}, {e2}, {e3})"
        );
    }
    // and the residual is small in absolute terms: below f³/R² at f = 0.2, R = 5
    assert!(e1 < 0.2f64.powi(3) / 25.0, "{e1}");
}

fn straight_kin(cutter: &Cutter, runout: &Runout, fz: f64) -> ToolKinematics<StraightFeed> {
    straight_feed_kinematics(cutter, runout, fz).unwrap()
}

#[test]
fn constant_axis_cl_path_equals_3axis() {
    let cutter = Cutter::flat(8.0, 3, 35.0f64.to_radians()).unwrap();
    let runout = Runout::new(0.012, deg(-70.0))
        .unwrap()
        .with_tilt(2e-4, deg(20.0))
        .unwrap();
    let fz = 0.12;
    let flat = straight_kin(&cutter, &runout, fz);
    let v = flat.motion().v.x; // mm/s
                               // uneven collinear segments along +x, axis +z: the same motion as 3-axis straight feed
    let xs = [-3.0, -1.0, -0.7, 0.4, 2.0, 2.05, 5.0];
    let pts: Vec<ClPoint> = xs
        .iter()
        .map(|&x| ClPoint {
            p: Vec3::new(x, 0.0, 0.0),
            u: Vec3::z(),
            feed: v,
        })
        .collect();
    let path = ClPath::new(&pts).unwrap();
    let t_shift = 3.0 / v; // path time 0 is at x = −3
    let five = ToolKinematics::new(
        &cutter,
        &runout,
        60.0,
        -TAU * t_shift,
        SpindleSense::Clockwise,
        path,
    )
    .unwrap();
    let opts = NewtonOptions::default();
    for tooth in 0..3 {
        for z in [0.5, 4.0] {
            for q in 0..12 {
                let t = 0.3 + 0.07 * q as f64; // s, within the path (T = 1 s)
                let a = exact_iuct(&flat, tooth, z, t, &opts).raw;
                let b = exact_iuct(&five, tooth, z, t + t_shift, &opts).raw;
                // identical geometry; rounding of positions ~1e-15 mm
                assert!((a - b).abs() < 1e-11, "{a} {b}");
            }
        }
    }
}

#[test]
fn pure_swing_about_tip_is_linear_in_height() {
    // No feed, axis swinging at Ω about +y through the tip: the axis point at height z moves at
    // z·Ω (along +x for u = +z), so h(z) ≈ (z·Ω·T/K)·sin φ, linear in z. The tilt of the previous
    // edge circle by α = Ω·T/K per tooth adds −O(R α²) (tip: h(0) ≈ −R(Kα)²/2·sin²φ ≤ 0, 2 % for higher orders).
    let cutter = Cutter::flat(10.0, 4, 0.0).unwrap();
    let omega = deg(10.0);
    let swing = ConstantSwing::new(Vec3::zeros(), Vec3::y(), omega, 0.0).unwrap();
    let kin = ToolKinematics::new(
        &cutter,
        &Runout::none(),
        600.0,
        0.0,
        SpindleSense::Clockwise,
        swing,
    )
    .unwrap();
    let tooth_time = 0.1 / 4.0; // T/K at 600 rpm
    let alpha = omega * tooth_time;
    let tilt = 5.0 * alpha * alpha;
    let opts = NewtonOptions::default();
    for q in 1..8 {
        let phi = deg(22.5 * q as f64);
        let t = kin.time_at_tooth_angle(0, 0.0, phi);
        let heights = [0.0, 5.0, 10.0, 15.0, 20.0];
        let h: Vec<f64> = heights
            .iter()
            .map(|&z| exact_iuct(&kin, 0, z, t, &opts).raw)
            .collect();
        assert!(
            h[0] <= 1e-12 && h[0] >= -1.02 * 5.0 * (4.0 * alpha).powi(2) / 2.0,
            "tip: {}",
            h[0]
        );
        for (j, &z) in heights.iter().enumerate().skip(1) {
            let f = z * alpha; // local feed per tooth at height z (mm)
            let predicted = f * phi.sin();
            // deviation: second-order chip terms + tilt term + axis turn during one tooth
            let tol = second_order_bound(f, 5.0, 4) + tilt + f * alpha;
            assert!(
                (h[j] - predicted).abs() < tol,
                "z {z} φ {phi}: {} vs {predicted} ± {tol}",
                h[j]
            );
        }
        // linearity: the second difference vanishes to second order in the local feed
        let f20 = 20.0 * alpha;
        let curvature = h[4] - 2.0 * h[3] + h[2];
        assert!(
            curvature.abs() < 2.0 * second_order_bound(f20, 5.0, 4) + tilt,
            "{curvature}"
        );
        assert!(curvature.abs() < 0.01 * h[4], "{curvature} vs {}", h[4]);
    }
}

#[test]
fn trait_arc_agrees_with_3d_arc() {
    let cutter = Cutter::flat(10.0, 4, 30.0f64.to_radians()).unwrap();
    for rho in [0.0, 0.010] {
        let runout = Runout::new(rho, deg(40.0)).unwrap();
        let fz = 0.1;
        let kin = straight_kin(&cutter, &runout, fz);
        let arc = ArcChip::new(&cutter, &runout, fz).unwrap();
        let delta_max = (0..4)
            .map(|i| runout.tooth_phase_shift(&cutter, i, 2.0).abs())
            .fold(0.0, f64::max);
        for tooth in 0..4 {
            for q in 0..72 {
                let phi = deg(5.0 * q as f64 + 1.0);
                let t = kin.time_at_tooth_angle(tooth, 2.0, phi);
                let a3 = arc_iuct(&kin, tooth, 2.0, t).max(0.0);
                let a2 = arc.thickness(tooth, 2.0, phi);
                // the 3-D ray is the effective edge at φ + δ_i: |m f (sin(φ+δ) − sin φ)| ≤ K f |δ|
                let tol = 1e-12 + 4.0 * fz * delta_max;
                assert!(
                    (a3 - a2).abs() <= tol,
                    "ρ {rho} tooth {tooth} φ {phi}: {a3} {a2}"
                );
            }
        }
    }
}

#[test]
fn exact_approaches_arc_for_tiny_feed() {
    let cutter = Cutter::flat(10.0, 4, 30.0f64.to_radians()).unwrap();
    let runout = Runout::new(0.003, deg(10.0)).unwrap();
    let fz = 1e-4; // f/R = 2e-5
    let exact = ExactChip::new(&cutter, &runout, fz).unwrap();
    let kin = straight_kin(&cutter, &runout, fz);
    for tooth in 0..4 {
        for q in 1..36 {
            let phi = deg(5.0 * q as f64);
            let t = kin.time_at_tooth_angle(tooth, 1.0, phi);
            let a = arc_iuct(&kin, tooth, 1.0, t).max(0.0);
            let e = exact.thickness(tooth, 1.0, phi);
            // arc error = second-order terms (d ≤ K f) plus the phase offset d·t̂·(δ_i − δ_p)
            let d = 4.0 * fz;
            let tol = d * d / 5.0 + d * 2.0 * 0.003 / 5.0;
            assert!((a - e).abs() < tol, "{a} {e}");
        }
    }
}

#[test]
fn equivalent_trait_equals_general_model() {
    let cutter = Cutter::new(
        12.0,
        vec![deg(80.0), deg(100.0), deg(80.0), deg(100.0)],
        40.0f64.to_radians(),
        30.0,
        RadiusProfile::Flat,
    )
    .unwrap();
    let runout = Runout::new(0.015, deg(130.0)).unwrap();
    for params in [
        EquivalentParams::default(),
        EquivalentParams {
            k1: 0.95,
            k2: 0.9,
            phase_refinement: false,
        },
    ] {
        let fast = EquivalentChip::new(&cutter, &runout, 0.08, params).unwrap();
        let kin = straight_kin(&cutter, &runout, 0.08);
        for z in [0.0, 7.0] {
            let ev = fast.at_height(z);
            for tooth in 0..4 {
                for q in 0..90 {
                    let phi = deg(4.0 * q as f64);
                    let (s, c) = phi.sin_cos();
                    let t = kin.time_at_tooth_angle(tooth, z, phi);
                    let g = equivalent_iuct(&kin, tooth, z, t, &params).max(0.0);
                    // same formula, different algebra: rounding only
                    assert!((ev.thickness(tooth, phi, s, c) - g).abs() < 1e-12);
                }
            }
        }
    }
}

#[test]
fn fitted_compensation_improves_on_analytic() {
    let cutter = Cutter::flat(6.0, 4, 30.0f64.to_radians()).unwrap();
    let runout = Runout::new(0.010, deg(40.0)).unwrap();
    let kin = straight_kin(&cutter, &runout, 0.2);
    let calib = calibration_grid(&kin, &[3.0], 24, 0.0);
    let fit = fit_compensation(&kin, &calib, false).unwrap();
    assert!(fit.condition < 1e3, "{}", fit.condition);
    // a second-order model: the k's stay near their analytic value 1
    assert!(
        (fit.params.k1 - 1.0).abs() < 0.2 && (fit.params.k2 - 1.0).abs() < 0.2,
        "{:?}",
        fit.params
    );
    // on an independent grid the fitted model is no worse than k = 1 (pooled metric)
    let pts = sample_grid(4, &[1.0, 5.0], 0.013, 1.0, 90);
    let fitted = evaluate_models(&kin, &pts, &fit.params);
    let analytic = evaluate_models(&kin, &pts, &EquivalentParams::analytic_unrefined());
    let ef = error_metrics(&fitted.equivalent, &fitted.exact).normalised_mae;
    let ea = error_metrics(&analytic.equivalent, &analytic.exact).normalised_mae;
    assert!(ef <= ea * 1.001, "fitted {ef} analytic {ea}");
    assert!(fit.rms_residual_mm < 1e-3);
}

#[test]
fn fit_rejects_too_few_points() {
    let cutter = Cutter::flat(6.0, 4, 30.0f64.to_radians()).unwrap();
    let kin = straight_kin(&cutter, &Runout::none(), 0.1);
    let err = fit_compensation(&kin, &calibration_grid(&kin, &[1.0], 0, 0.0), true).unwrap_err();
    assert!(err.param.contains("calibration_points"));
}

#[test]
fn force_simulation_with_every_model() {
    // reference case of the force module (arc: 247.361 N); exact and equivalent differ from
    // the arc model only by the second-order chip terms, f/R = 0.016 → well below 2 %.
    let cutter = Cutter::flat(10.0, 4, 0.0).unwrap();
    let cut = Cut::new(3240.0, 0.08, 1.0)
        .unwrap()
        .radial(2.0, MillingMode::Down, &cutter)
        .unwrap();
    let k = CuttingCoefficients::new([1889.2, 806.1, 291.0], [63.12, 113.7, -3.1]).unwrap();
    let runout = Runout::new(0.008, 0.0).unwrap();
    let model = ForceModel {
        cutter: cutter.clone(),
        runout,
        cut,
        coefficients: k,
    };
    let sampling = Sampling::new(1.0, 0.25, 1).unwrap();
    let peak = |s: &ForceSeries| s.fxy().into_iter().fold(0.0, f64::max);
    let arc = model.simulate(&ArcChip::new(&cutter, &runout, 0.08).unwrap(), &sampling);
    let exact = model.simulate(&ExactChip::new(&cutter, &runout, 0.08).unwrap(), &sampling);
    let eq = model.simulate(
        &EquivalentChip::new(&cutter, &runout, 0.08, EquivalentParams::default()).unwrap(),
        &sampling,
    );
    let (pa, pe, pq) = (peak(&arc), peak(&exact), peak(&eq));
    assert!((pe - pa).abs() / pa < 0.02, "{pe} {pa}");
    // equivalent tracks exact to the third-order rest (≪ 0.1 %)
    assert!((pq - pe).abs() / pe < 1e-3, "{pq} {pe}");
    // chip values: third-order rest 2·d³/R² with d = 2 f_z (ρ < f_z: at most the pass m = 2 is
    // active, at the entry/exit where the largest tooth's previous pass is two pitches back)
    let tol = 2.0 * (2.0f64 * 0.08).powi(3) / 25.0;
    for (a, b) in exact.chip.iter().flatten().zip(eq.chip.iter().flatten()) {
        assert!((a - b).abs() < tol, "{a} {b}");
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(48))]

    /// Realistic ranges: R 0.5–8 mm, K 2–6, f_z/R 0.2–3 %, ρ ≤ 20 µm, helix 0–45°.
    #[test]
    fn models_consistent(
        r in 0.5f64..8.0, k in 2usize..7, fz_rel in 0.002f64..0.03, rho_um in 0.0f64..20.0,
        lam in 0.0f64..360.0, helix in 0.0f64..45.0, phi in 0.0f64..360.0, z in 0.0f64..5.0,
        tooth_sel in 0usize..6,
    ) {
        let tooth = tooth_sel % k;
        let fz = fz_rel * r;
        let cutter = Cutter::flat(2.0 * r, k, f64::to_radians(helix)).unwrap();
        let runout = Runout::new(rho_um * 1e-3, deg(lam)).unwrap();
        let kin = straight_kin(&cutter, &runout, fz);
        let t = kin.time_at_tooth_angle(tooth, z, deg(phi));
        let e = exact_iuct(&kin, tooth, z, t, &NewtonOptions::default());
        prop_assert!(e.converged);
        // the scalar straight-feed solver of the trait path is the same exact model
        let trait_h = ExactChip::new(&cutter, &runout, fz).unwrap().thickness(tooth, z, deg(phi));
        prop_assert!((trait_h - e.h()).abs() < 1e-11, "trait {} 3-D {}", trait_h, e.h());
        // one revolution later the geometry is translated by K f_z: same h (steady feed)
        let e2 = exact_iuct(&kin, tooth, z, t + kin.period(), &NewtonOptions::default());
        prop_assert!((e.raw - e2.raw).abs() < 1e-10);
        // h never exceeds the radius difference + the feed since the tooth itself last passed
        prop_assert!(e.h() <= k as f64 * fz + 1e-12);
        let c = closed_forms(&kin, tooth, z, t, &EquivalentParams::default());
        // arc: second-order error (d ≤ K f) + phase offset term (δ ≤ ρ/(R−ρ))
        let d = k as f64 * fz;
        let rho = rho_um * 1e-3;
        let arc_tol = d * d / r + 2.0 * d * 2.0 * rho / (r - rho) + 1e-12;
        prop_assert!((c.arc.max(0.0) - e.h()).abs() <= arc_tol);
        // equivalent: third-order rest, C·d³/R² with C = 2 (≥ 3× the largest seen)
        let eq_tol = 2.0 * d * d * d / (r * r) + 1e-12;
        prop_assert!((c.equivalent.max(0.0) - e.h()).abs() <= eq_tol,
            "eq {} exact {} tol {}", c.equivalent, e.h(), eq_tol);
    }
}

#[test]
fn small_sin_cos_matches_libm() {
    // Taylor degree 15/16 (or 9/10 below 1/8): truncation < 1e-19, so only rounding remains
    for q in -2000..=2000 {
        let x = q as f64 * 3.1e-4; // |x| ≤ 0.62 (also exercises the libm fallback above 0.5)
        let (s, c) = runout_core::chip::kinematics::small_sin_cos(x);
        assert!(
            (s - x.sin()).abs() < 3e-16 && (c - x.cos()).abs() < 3e-16,
            "{x}"
        );
    }
}

#[test]
fn straight_feed_exact_solvers_agree_on_general_cutters() {
    // scalar exact (trait path) vs 3-D Newton: variable pitch, tilt, ball / bull-nose profiles
    let pitch = vec![deg(85.0), deg(95.0), deg(85.0), deg(95.0)];
    let cutters = [
        Cutter::new(
            10.0,
            pitch.clone(),
            35.0f64.to_radians(),
            30.0,
            RadiusProfile::Ball,
        )
        .unwrap(),
        Cutter::new(
            10.0,
            pitch,
            20.0f64.to_radians(),
            30.0,
            RadiusProfile::BullNose { corner_mm: 1.5 },
        )
        .unwrap(),
    ];
    let runout = Runout::new(0.012, deg(-30.0))
        .unwrap()
        .with_tilt(3e-4, deg(60.0))
        .unwrap();
    for cutter in &cutters {
        let exact = ExactChip::new(cutter, &runout, 0.06).unwrap();
        let kin = exact.kinematics();
        for z in [0.3, 1.0, 4.0, 8.0] {
            let ev = exact.at_height(z);
            for tooth in 0..4 {
                for q in 0..48 {
                    let phi = deg(7.5 * q as f64 + 0.2);
                    let (s, c) = phi.sin_cos();
                    let t = kin.time_at_tooth_angle(tooth, z, phi);
                    let e3 = exact_iuct(&kin, tooth, z, t, &NewtonOptions::default());
                    assert!(e3.converged);
                    // both converged to 1e-12 mm; rounding of the different algebra ~1e-14
                    assert!(
                        (ev.thickness(tooth, phi, s, c) - e3.h()).abs() < 1e-11,
                        "z {z} tooth {tooth} φ {phi}"
                    );
                }
            }
        }
    }
}

#[test]
fn circular_feed_of_large_radius_approaches_straight_feed() {
    // a circle of radius r_c bends the feed by f/r_c per tooth: the chip differs from straight
    // feed by O(h·(R/r_c)) — below 0.3 % of f for r_c = 5 m
    let cutter = Cutter::flat(10.0, 4, 30.0f64.to_radians()).unwrap();
    let runout = Runout::new(0.01, deg(40.0)).unwrap();
    let fz = 0.1;
    let speed = fz * 4.0 * 6000.0 / 60.0;
    let straight = ToolKinematics::new(
        &cutter,
        &runout,
        6000.0,
        0.0,
        SpindleSense::Clockwise,
        StraightFeed::along_x(speed),
    )
    .unwrap();
    // centre below the path so that at α = 90° the tip moves along +x (clockwise circle)
    let mut circ = CircularFeed::new(Vec3::new(0.0, -5000.0, 0.0), 5000.0, speed, false).unwrap();
    circ.start_angle = std::f64::consts::FRAC_PI_2;
    let circular =
        ToolKinematics::new(&cutter, &runout, 6000.0, 0.0, SpindleSense::Clockwise, circ).unwrap();
    let opts = NewtonOptions::default();
    for tooth in 0..4 {
        for q in 0..36 {
            let t = 0.01 + 0.01 * q as f64 / 36.0;
            let a = exact_iuct(&straight, tooth, 2.0, t, &opts).h();
            let b = exact_iuct(&circular, tooth, 2.0, t, &opts).h();
            assert!((a - b).abs() < 3e-3 * fz, "{a} {b}");
        }
    }
}

#[test]
fn compensation_fit_round_trip_recovers_known_k() {
    // targets from eq. (2.8) with known (k₁, k₂) plus Gaussian noise σ = 0.05 µm → the fit must
    // recover them within 4 standard errors, and the standard errors must be consistent with σ
    use rand::SeedableRng;
    use rand_distr::{Distribution, Normal};
    let cutter = Cutter::flat(6.0, 4, 30.0f64.to_radians()).unwrap();
    let runout = Runout::new(0.010, deg(40.0)).unwrap();
    let kin = straight_kin(&cutter, &runout, 0.2);
    let truth = EquivalentParams {
        k1: 0.93,
        k2: 1.08,
        phase_refinement: true,
    };
    let calib = calibration_grid(&kin, &[0.0, 3.0], 45, 0.0);
    let noise = Normal::new(0.0, 5e-5).unwrap();
    let mut rng = rand::rngs::StdRng::seed_from_u64(7);
    let targets: Vec<f64> = calib
        .iter()
        .map(|q| equivalent_iuct(&kin, q.tooth, q.z, q.t, &truth))
        .map(|h| {
            if h > 0.0 {
                h + noise.sample(&mut rng)
            } else {
                h
            }
        })
        .collect();
    let fit = fit_compensation_to(&kin, &calib, &targets, true).unwrap();
    for (got, want, se) in [
        (fit.params.k1, truth.k1, fit.std_error[0]),
        (fit.params.k2, truth.k2, fit.std_error[1]),
    ] {
        assert!(se > 0.0 && se < 0.05, "se {se}");
        assert!((got - want).abs() < 4.0 * se, "{got} vs {want} ± {se}");
    }
    // residual ≈ σ (n ≈ 200: ±15 %)
    assert!(
        (fit.rms_residual_mm / 5e-5 - 1.0).abs() < 0.15,
        "{}",
        fit.rms_residual_mm
    );
    // wrong number of targets is a parameter error, not a panic
    assert!(fit_compensation_to(&kin, &calib, &targets[1..], true).is_err());
}

#[test]
fn joint_path_velocities_match_finite_differences() {
    // analytic Ṗ and Ω (used by the Newton Jacobian) vs central differences of P and u, e₁
    let blocks = [
        JointPoint {
            xyz: Vec3::new(0.0, 0.0, 200.0),
            a: deg(0.0),
            c: deg(0.0),
            feed: 30.0,
        },
        JointPoint {
            xyz: Vec3::new(20.0, 5.0, 198.0),
            a: deg(12.0),
            c: deg(30.0),
            feed: 30.0,
        },
        JointPoint {
            xyz: Vec3::new(40.0, 8.0, 195.0),
            a: deg(20.0),
            c: deg(45.0),
            feed: 30.0,
        },
    ];
    let path = JointPath::new(&blocks, 150.0).unwrap();
    let h = 1e-6;
    for q in 1..20 {
        let t = path.duration() * q as f64 / 20.0 + 1e-4;
        let (a, b, c) = (path.pose(t - h), path.pose(t), path.pose(t + h));
        let v_fd = (c.p - a.p) / (2.0 * h);
        let u_fd = (c.u - a.u) / (2.0 * h);
        let e_fd = (c.e1 - a.e1) / (2.0 * h);
        // central differences: O(h²·|third derivative|) ≈ 1e-9 relative; rounding 1e-16/h ≈ 1e-10
        assert!(
            (v_fd - b.v).norm() < 1e-6 * b.v.norm().max(1.0),
            "{v_fd} {}",
            b.v
        );
        assert!((u_fd - b.w.cross(&b.u)).norm() < 1e-7);
        assert!((e_fd - b.w.cross(&b.e1)).norm() < 1e-7);
        assert!((b.u.norm() - 1.0).abs() < 1e-14 && b.u.dot(&b.e1).abs() < 1e-14);
    }
}

#[test]
fn joint_path_without_rotation_is_straight_feed() {
    let cutter = Cutter::flat(8.0, 3, 30.0f64.to_radians()).unwrap();
    let runout = Runout::new(0.01, deg(15.0)).unwrap();
    let flat = straight_kin(&cutter, &runout, 0.1);
    let v = flat.motion().v.x;
    let blocks = [
        JointPoint {
            xyz: Vec3::new(-5.0, 0.0, 100.0),
            a: 0.0,
            c: 0.0,
            feed: v,
        },
        JointPoint {
            xyz: Vec3::new(5.0, 0.0, 100.0),
            a: 0.0,
            c: 0.0,
            feed: v,
        },
    ];
    let path = JointPath::new(&blocks, 100.0).unwrap(); // tip at z = 0
    let shift = 5.0 / v;
    let joints = ToolKinematics::new(
        &cutter,
        &runout,
        60.0,
        -TAU * shift,
        SpindleSense::Clockwise,
        path,
    )
    .unwrap();
    let opts = NewtonOptions::default();
    for tooth in 0..3 {
        for q in 0..10 {
            let t = 1.0 + 0.1 * q as f64;
            let a = exact_iuct(&flat, tooth, 2.0, t, &opts).raw;
            let b = exact_iuct(&joints, tooth, 2.0, t + shift, &opts);
            assert!(b.converged && (a - b.raw).abs() < 1e-11, "{a} {}", b.raw);
        }
    }
}

#[test]
fn newton_stopping_rule_accepts_only_converged_iterates() {
    // The exact solver stops when a step is below 1e-12 mm or when quadratic convergence
    // guarantees the next one is (C·|dx|² < tol). Reference: 8 iterations with no early exit
    // (tol 0: from the third-order start this is machine precision). The accepted results must
    // agree to the 1e-12 mm tolerance on 3-axis, swing, CL-path and micro-milling cases.
    use runout_core::chip::compare::Motion;
    let strict = NewtonOptions {
        tol_mm: 0.0,
        max_iter: 8,
    };
    let swing = |axis: Vec3| {
        Motion::Swing(ConstantSwing::new(Vec3::new(40.0, 0.0, 0.0), axis, deg(60.0), 0.0).unwrap())
    };
    let path = ClPath::new(
        &(0..5)
            .map(|n| ClPoint {
                p: Vec3::new(0.4 * n as f64, 0.03 * (n * n) as f64, 0.0),
                u: Vec3::new(deg(2.0 * n as f64).sin(), 0.0, deg(2.0 * n as f64).cos()),
                feed: 40.0,
            })
            .collect::<Vec<_>>(),
    )
    .unwrap();
    let cases = [
        (
            Cutter::flat(10.0, 4, 30.0f64.to_radians()).unwrap(),
            0.010,
            Motion::Straight(StraightFeed::along_x(40.0)),
        ),
        (
            Cutter::flat(10.0, 4, 45.0f64.to_radians()).unwrap(),
            0.010,
            swing(Vec3::y()),
        ),
        (
            Cutter::flat(6.0, 3, 30.0f64.to_radians()).unwrap(),
            0.020,
            swing(Vec3::new(1.0, 0.3, 0.0)),
        ),
        (
            Cutter::flat(10.0, 4, 30.0f64.to_radians()).unwrap(),
            0.010,
            Motion::Path(path),
        ),
        (
            Cutter::flat(0.5, 2, 30.0f64.to_radians()).unwrap(),
            0.002,
            Motion::Straight(StraightFeed::along_x(0.4)),
        ),
    ];
    for (cutter, rho, motion) in cases {
        let runout = Runout::new(rho, deg(40.0)).unwrap();
        let kin = ToolKinematics::new(
            &cutter,
            &runout,
            6000.0,
            0.2,
            SpindleSense::Clockwise,
            motion,
        )
        .unwrap();
        let mut worst: f64 = 0.0;
        for z in [0.0, 4.0, 10.0] {
            let geo = kin.at_height(z);
            for q in 0..90 {
                let t = 0.02 + 0.01 * q as f64 / 90.0;
                for tooth in 0..cutter.teeth() {
                    let a = exact_at(&kin, &geo, tooth, t, &NewtonOptions::default());
                    let b = exact_at(&kin, &geo, tooth, t, &strict);
                    assert!(a.converged);
                    worst = worst.max((a.raw - b.raw).abs());
                }
            }
        }
        assert!(worst <= 1e-12, "R {} ρ {rho}: {worst:e}", cutter.radius());
    }
}

/// The incremental poses of [`RigidStep`] (used by the exact solver's look-back) equal the
/// motion's own poses to rounding: |ΔP| ≤ 1e-12 mm and |Δu|, |Δe₁| ≤ 1e-14 over a look-back of up
/// to one revolution (10 ms at 6000 rpm), on a swing about a pivot and across the junctions of a
/// CL path (where the step must decline and the solver falls back to `pose`).
#[test]
fn rigid_step_poses_equal_direct_poses() {
    let swing = ConstantSwing::new(
        Vec3::new(40.0, 3.0, -1.0),
        Vec3::new(0.2, 1.0, 0.1),
        1.3,
        25.0,
    )
    .unwrap();
    let pts: Vec<ClPoint> = (0..12)
        .map(|n| {
            let a = (2.0 * n as f64).to_radians();
            ClPoint {
                p: Vec3::new(n as f64 * 0.3, 0.01 * (n as f64).powi(2), 0.0),
                u: Vec3::new(a.sin(), 0.1 * a.sin(), a.cos()).normalize(),
                feed: 40.0,
            }
        })
        .collect();
    let path = ClPath::new(&pts).unwrap();
    assert_eq!(rigid_step_mismatches("swing", &swing), 0);
    let declined = rigid_step_mismatches("path", &path);
    assert!(
        declined > 0,
        "the CL path's junctions must make the step decline"
    );
}

/// Compares `pose_at` with `pose` over look-backs of up to 10 ms; returns how often the step
/// declined (outside its screw interval).
fn rigid_step_mismatches<M: ToolMotion>(name: &str, motion: &M) -> usize {
    let mut declined = 0;
    for q in 0..200 {
        let t = 0.002 + 0.0004 * q as f64;
        let step = motion.rigid_step(t).expect("a constant screw");
        assert_eq!(step.pose, motion.pose(t), "{name}: the step's own pose");
        for j in 0..=20 {
            let t2 = t - 0.0005 * j as f64;
            let direct = motion.pose(t2);
            match step.pose_at(t2) {
                Some(p) => {
                    assert!((p.p - direct.p).norm() <= 1e-12, "{name} t {t} → {t2}: P");
                    assert!((p.u - direct.u).norm() <= 1e-14, "{name}: u");
                    assert!((p.e1 - direct.e1).norm() <= 1e-14, "{name}: e1");
                    assert!((p.v - direct.v).norm() <= 1e-11, "{name}: v");
                    assert!((p.w - direct.w).norm() <= 1e-15, "{name}: w");
                }
                None => declined += 1,
            }
        }
    }
    declined
}

/// `spindle_point_near` (series rotation from the prepared height) equals `spindle_point`.
#[test]
fn spindle_point_near_equals_spindle_point() {
    for profile in [
        RadiusProfile::Flat,
        RadiusProfile::Ball,
        RadiusProfile::BullNose { corner_mm: 1.5 },
    ] {
        let cutter = Cutter::new(
            10.0,
            vec![1.4, 1.7, 1.5, TAU - 4.6],
            35.0f64.to_radians(),
            30.0,
            profile.clone(),
        )
        .unwrap();
        let runout = Runout::new(0.012, 0.7)
            .unwrap()
            .with_tilt_vector([2e-4, -1e-4]);
        let kin = straight_kin(&cutter, &runout, 0.1);
        for z in [0.3, 2.0, 5.0] {
            let geo = kin.at_height(z);
            for tooth in 0..4 {
                for dz in [-0.2, -1e-3, 1e-6, 0.05, 0.3] {
                    let a = kin.spindle_point(tooth, z + dz);
                    let b = kin.spindle_point_near(&geo, tooth, z + dz);
                    for c in 0..2 {
                        assert!(
                            (a.xy[c] - b.xy[c]).abs() <= 1e-13,
                            "{profile:?} z {z} dz {dz}"
                        );
                        assert!(
                            (a.dxy[c] - b.dxy[c]).abs() <= 1e-12,
                            "{profile:?} z {z} dz {dz}"
                        );
                    }
                }
            }
        }
    }
}

/// A 5-axis motion of the lockstep test: a swing (random axis ⊥-ish to the tool, 10–120°/s,
/// pivot 0–40 mm) or a CL path (a point every `step` mm, the axis leaning `tilt` degrees more
/// per point about alternating directions).
fn lockstep_motion(
    kind: usize,
    feed: f64,
    rate_deg: f64,
    axis_deg: f64,
    pivot: f64,
    tilt_deg: f64,
) -> runout_core::chip::compare::Motion {
    use runout_core::chip::compare::Motion;
    match kind {
        0 => Motion::Straight(StraightFeed::along_x(feed)),
        1 => Motion::Swing(
            ConstantSwing::new(
                Vec3::new(feed, 0.0, 0.0),
                Vec3::new(deg(axis_deg).cos(), deg(axis_deg).sin(), 0.1),
                deg(rate_deg),
                pivot,
            )
            .unwrap(),
        ),
        _ => Motion::Path(
            ClPath::new(
                &(0..30)
                    .map(|n| {
                        let a = deg(tilt_deg * n as f64);
                        let b = if n % 2 == 0 { 0.0 } else { deg(0.5 * tilt_deg) };
                        ClPoint {
                            p: Vec3::new(0.8 * n as f64 - 8.0, 0.01 * (n * n) as f64, 0.0),
                            u: Vec3::new(a.sin(), b.sin(), a.cos() * b.cos()).normalize(),
                            feed,
                        }
                    })
                    .collect::<Vec<_>>(),
            )
            .unwrap(),
        ),
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(64))]

    /// The lockstep exact solver (`exact_at`: K previous passes side by side in SIMD lanes,
    /// passes that cannot decide h stopped early) equals the scalar one-pass-after-the-other
    /// baseline `exact::reference::exact_at` BIT FOR BIT in h (raw), R_i and the cutting pass:
    /// tolerance 0, because every lane performs the scalar solver's operations in the same order
    /// and the early stop only drops passes whose crossing is bounded below another's.
    /// Realistic 5-axis flank-milling cases: swing 10–120°/s about tilted axes with pivots,
    /// CL paths tilting 0.1–3° per point (junctions inside look-back windows), straight feed;
    /// R 2–8 mm, K 2–6 (two lane chunks for K > 4), helix 0–45°, runout 2–20 µm, f_z 0.02–0.25 mm.
    #[test]
    fn lockstep_exact_equals_scalar_reference(
        kind in 0usize..3, r in 2.0f64..8.0, k in 2usize..7, helix in 0.0f64..45.0,
        rho_um in 2.0f64..20.0, lam in 0.0f64..360.0, fz in 0.02f64..0.25,
        rate_deg in 10.0f64..120.0, axis_deg in 0.0f64..360.0, pivot in 0.0f64..40.0,
        tilt_deg in 0.1f64..3.0, ccw in any::<bool>(), t0 in 0.0f64..0.05,
    ) {
        let cutter = Cutter::flat(2.0 * r, k, deg(helix)).unwrap();
        let runout = Runout::new(rho_um * 1e-3, deg(lam)).unwrap();
        let rpm = 6000.0;
        let feed = fz * k as f64 * rpm / 60.0;
        let sense = if ccw { SpindleSense::CounterClockwise } else { SpindleSense::Clockwise };
        let motion = lockstep_motion(kind, feed, rate_deg, axis_deg, pivot, tilt_deg);
        let kin = ToolKinematics::new(&cutter, &runout, rpm, 0.3, sense, motion).unwrap();
        let opts = NewtonOptions::default();
        for z in [0.0, 0.37 * r, 2.0 * r] {
            let geo = kin.at_height(z);
            for q in 0..24 {
                let t = 0.01 + t0 + kin.period() * q as f64 / 24.0;
                for tooth in 0..k {
                    let a = exact_at(&kin, &geo, tooth, t, &opts);
                    let b = exact::reference::exact_at(&kin, &geo, tooth, t, &opts);
                    prop_assert!(a.raw.to_bits() == b.raw.to_bits(), "h {} vs {}", a.raw, b.raw);
                    prop_assert!(a.radius.to_bits() == b.radius.to_bits());
                    prop_assert_eq!(a.cutting_m, b.cutting_m);
                    prop_assert!(a.converged && b.converged);
                    prop_assert!(a.iterations <= b.iterations);
                }
            }
        }
    }
}
