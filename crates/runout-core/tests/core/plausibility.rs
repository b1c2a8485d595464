//! Plausibility guards: each one triggered and not triggered on realistic data.

use proptest::prelude::*;
use runout_core::plausibility::*;
use runout_core::*;

/// Simulated |F| signal of a 4-flute cut (example case), with 2 % white noise, as channel Fx.
fn force_signal() -> Vec<f64> {
    let cutter = Cutter::flat(10.0, 4, 30.0f64.to_radians()).unwrap();
    let runout = Runout::new(0.008, -0.87).unwrap();
    let cut = Cut::new(3240.0, 0.08, 2.0)
        .unwrap()
        .radial(2.0, MillingMode::Down, &cutter)
        .unwrap();
    let k = CuttingCoefficients::new([1889.2, 806.1, 291.0], [63.12, 113.7, -3.1]).unwrap();
    let chip = ArcChip::new(&cutter, &runout, 0.08).unwrap();
    let model = ForceModel {
        cutter,
        runout,
        cut,
        coefficients: k,
    };
    let s = model.simulate(
        &chip,
        &Sampling::new(20.0, 360.0 * 3240.0 / 60.0 / 50_000.0, 20).unwrap(),
    );
    // deterministic pseudo-noise (xorshift), σ ≈ 2 % of the peak
    let peak = s.fx.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    let mut state = 0x9e3779b97f4a7c15u64;
    s.fx.iter()
        .map(|v| {
            let mut u = 0.0;
            for _ in 0..12 {
                state ^= state << 13;
                state ^= state >> 7;
                state ^= state << 17;
                u += (state >> 11) as f64 / (1u64 << 53) as f64;
            }
            v + 0.02 * peak * (u - 6.0)
        })
        .collect()
}

/// A 16-bit ADC over ±`range`: quantised, and clamped at the range.
fn adc(signal: &[f64], range: f64) -> Vec<f64> {
    let lsb = range / 32768.0;
    signal
        .iter()
        .map(|v| (v / lsb).round().clamp(-32768.0, 32767.0) * lsb)
        .collect()
}

#[test]
fn clipping_is_found_on_a_clipped_adc_and_not_on_a_quantised_one() {
    let f = force_signal();
    let peak = f.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    // range above the peak: quantised only
    let mut ok = ClipDetector::new();
    ok.push(&adc(&f, 1.5 * peak));
    assert!(ok.finding("Fx", "N").is_none());
    // range at 80 % of the peak: every tooth's peak is cut
    let mut bad = ClipDetector::new();
    for chunk in adc(&f, 0.8 * peak).chunks(1000) {
        bad.push(chunk); // streaming: chunk boundaries must not matter
    }
    let finding = bad.finding("Fx", "N").expect("clipped");
    assert_eq!(finding.severity, Severity::NotIdentified);
    assert!(finding.message.contains("Fx"), "{}", finding.message);
}

#[test]
fn a_slow_quantised_drift_with_one_flat_top_is_not_clipping() {
    // 0.2 Hz drift of ±0.5 µm sampled at 50 kHz by a 16-bit ADC over ±1 µm: the largest code
    // repeats for many samples, but only once
    let drift: Vec<f64> = (0..200_000)
        .map(|q| 0.5 * (std::f64::consts::TAU * 0.2 * q as f64 / 50_000.0).sin())
        .collect();
    let mut d = ClipDetector::new();
    d.push(&adc(&drift, 1.0));
    assert!(d.finding("dx", "µm").is_none());
}

#[test]
fn runout_guard_flags_the_bull_nose_as_flat_case_and_runout_above_the_feed() {
    // issue 21: a bull-nose cut at a_p below its corner radius described as flat gave 1 495 µm
    let f = runout_size(1.495, 5.0, 0.08);
    assert_eq!(f.len(), 1);
    assert_eq!(f[0].code, "runout_too_large");
    assert!(f[0].hint.contains("profile"));
    // 100 µm at f_z 80 µm on Ø10: plausible size, but larger than the feed
    let f = runout_size(0.1, 5.0, 0.08);
    assert_eq!(f.len(), 1);
    assert_eq!(
        (f[0].code, f[0].severity),
        ("runout_exceeds_feed", Severity::Warning)
    );
    // micro-milling Ø0.5: 30 µm is 12 % of the radius
    assert_eq!(runout_size(0.030, 0.25, 0.005)[0].code, "runout_too_large");
    assert_eq!(runout_size(f64::NAN, 5.0, 0.08)[0].code, "runout_too_large");
}

proptest! {
    /// Typical holder runouts (1–40 µm) on Ø2–20 cutters at feeds above the runout: no finding.
    #[test]
    fn typical_runouts_pass(rho_um in 1.0f64..40.0, r in 1.0f64..10.0, extra in 0.0f64..0.2) {
        let fz = rho_um * 1e-3 + extra;
        prop_assert!(runout_size(rho_um * 1e-3, r, fz).is_empty());
    }

    /// Coefficient sets across the metals (aluminium to superalloys): no finding.
    #[test]
    fn published_like_coefficients_pass(
        ktc in 500.0f64..4500.0, krc_ratio in 0.2f64..0.9, kac_ratio in -0.4f64..0.4,
        kte in 5.0f64..120.0, kre in 5.0f64..200.0, kae in -20.0f64..40.0,
    ) {
        let k = CuttingCoefficients::new([ktc, krc_ratio * ktc, kac_ratio * ktc], [kte, kre, kae]).unwrap();
        prop_assert!(coefficients(&k, None).is_empty());
    }
}

#[test]
fn coefficients_outside_the_metal_ranges_are_not_identified() {
    let ok = CuttingCoefficients::new([1889.2, 806.1, 291.0], [63.12, 113.7, -3.1]).unwrap();
    assert!(coefficients(&ok, Some([1.3, 2.6, 4.5, 0.1, 0.1, 0.1])).is_empty());
    // issue 21 shape: a negative radial edge coefficient with a small SE
    let neg = CuttingCoefficients::new([1889.2, 806.1, 291.0], [63.12, -2.9, -3.1]).unwrap();
    let f = coefficients(&neg, Some([1.3, 2.6, 4.5, 0.1, 0.2, 0.1]));
    assert_eq!(f.len(), 1);
    assert_eq!(f[0].subject, "K_re");
    assert!(f[0].message.contains("negative"), "{}", f[0].message);
    // the same value with an SE that reaches zero is not judged implausible
    assert!(coefficients(&neg, Some([1.3, 2.6, 4.5, 0.1, 2.0, 0.1])).is_empty());
    // a diameter entered in inches gives a K_tc 25× too small
    let tiny =
        CuttingCoefficients::new([1889.2 / 25.4, 806.1 / 25.4, 11.0], [2.5, 4.5, 0.0]).unwrap();
    assert!(coefficients(&tiny, None)
        .iter()
        .any(|f| f.subject == "K_tc"));
}

#[test]
fn the_same_samples_under_two_names_are_found() {
    let items = vec![
        ("a.txt".to_string(), 11u64),
        ("b.txt".to_string(), 12),
        ("copy of a.txt".to_string(), 11),
    ];
    let f = duplicates(&items);
    assert_eq!(f.len(), 1);
    assert!(f[0].message.contains("copy of a.txt") && f[0].message.contains("a.txt"));
    assert!(duplicates(&items[..2]).is_empty());
}

#[test]
fn shank_sensors_of_opposite_sense_are_found() {
    // sensor II sees 40 % of sensor I's deflection, plus its own noise and a drift
    let a: Vec<f64> = (0..20_000)
        .map(|q| {
            let t = q as f64 / 50_000.0;
            3.0 * (std::f64::consts::TAU * 216.0 * t).sin() + 0.3 * (t * 7.0).sin()
        })
        .collect();
    let b: Vec<f64> = a
        .iter()
        .enumerate()
        .map(|(q, v)| {
            0.4 * v + 0.2 * ((q * 7919 % 1000) as f64 / 1000.0 - 0.5) + 1e-3 * q as f64 / 20_000.0
        })
        .collect();
    assert!(sensor_senses(&a, &b, "x").is_none());
    let flipped: Vec<f64> = b.iter().map(|v| -v).collect();
    let f = sensor_senses(&a, &flipped, "x").expect("opposite senses");
    assert!(f.hint.contains("-x"), "{}", f.hint);
    assert_eq!(worst(&[f]), Some(Severity::NotIdentified));
}

/// Mean (F_x, F_y) of one revolution simulated by the force model (no runout), K_tc 2 000,
/// K_rc 1 000 N/mm² (the guard's ratio 0.5), edge coefficients `edge` (K_te, K_re) in N/mm.
fn simulated_mean(cutter: Cutter, ap: f64, ae: f64, fz: f64, edge: (f64, f64)) -> [f64; 2] {
    let runout = Runout::new(0.0, 0.0).unwrap();
    let cut = Cut::new(3000.0, fz, ap)
        .unwrap()
        .radial(ae, MillingMode::Down, &cutter)
        .unwrap();
    let k = CuttingCoefficients::new([2000.0, 1000.0, 0.0], [edge.0, edge.1, 0.0]).unwrap();
    let chip = ArcChip::new(&cutter, &runout, fz).unwrap();
    let model = ForceModel {
        cutter,
        runout,
        cut,
        coefficients: k,
    };
    let s = model.simulate(&chip, &Sampling::new(1.0, 0.02, 200).unwrap());
    let mean = |v: &[f64]| v.iter().sum::<f64>() / v.len() as f64;
    [mean(&s.fx), mean(&s.fy)]
}

/// `MeanForceGeometry` against the force model itself (an independent path: the simulator's
/// per-sample chip thickness and force projection, summed over 18 000 angles × 200 disks):
/// on a flat-end cutter the shear part |F̄| = K_tc·f_z·|shear| and the edge part |edge| to
/// 1e-4 (the 0.02° angle grid cuts the window edges; measured 9e-6 and 7e-6). On a
/// ball-end cutter at a small depth (the PHM 2010 cut, where the local radius is ≤ 1.08 mm of
/// the nominal 3) the guard ignores the lead angle's projection of the radial force, so it
/// agrees to 15 % (measured 9.6 %) — ample for a check against a 40× range — while the nominal-radius formula it
/// replaced was off by a factor 4.6.
#[test]
fn mean_force_geometry_matches_the_force_model() {
    let flat = Cutter::flat(10.0, 4, 30f64.to_radians()).unwrap();
    let cut = Cut::new(3000.0, 0.05, 2.0)
        .unwrap()
        .radial(2.0, MillingMode::Down, &flat)
        .unwrap();
    let g = MeanForceGeometry::new(&flat, &cut);
    let m = simulated_mean(flat.clone(), 2.0, 2.0, 0.05, (0.0, 0.0));
    let shear = 2000.0 * 0.05 * g.shear[0].hypot(g.shear[1]);
    let rel = (m[0].hypot(m[1]) - shear).abs() / shear;
    assert!(
        rel < 1e-4,
        "flat shear: model {m:?} vs guard {shear} ({rel:.2e})"
    );
    let (kte, kre) = FORCE_MAGNITUDE_EDGE_N_PER_MM;
    let with_edge = simulated_mean(flat.clone(), 2.0, 2.0, 0.05, (kte, kre));
    let edge_model = (with_edge[0] - m[0]).hypot(with_edge[1] - m[1]);
    let edge = g.edge[0].hypot(g.edge[1]);
    let rel = (edge_model - edge).abs() / edge;
    assert!(
        rel < 1e-4,
        "flat edge: model {edge_model} vs guard {edge} ({rel:.2e})"
    );

    let ball = Cutter::new(
        6.0,
        vec![std::f64::consts::TAU / 3.0; 3],
        30f64.to_radians(),
        f64::INFINITY,
        RadiusProfile::Ball,
    )
    .unwrap();
    let cut = Cut::new(3000.0, 0.0498, 0.2)
        .unwrap()
        .radial(0.125, MillingMode::Down, &ball)
        .unwrap();
    let g = MeanForceGeometry::new(&ball, &cut);
    let m = simulated_mean(ball.clone(), 0.2, 0.125, 0.0498, (0.0, 0.0));
    let shear = 2000.0 * 0.0498 * g.shear[0].hypot(g.shear[1]);
    let rel = (m[0].hypot(m[1]) - shear).abs() / shear;
    assert!(
        rel < 0.15,
        "ball shear: model {m:?} vs guard {shear} ({rel:.2e})"
    );
}
