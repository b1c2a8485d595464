//! Shank-deflection force method (issue 6, methods.md §3): stiffness worked examples, static
//! calibration, full round trip simulate → beam deflection + air-cut pattern → force and runout,
//! bad inputs.

use proptest::prelude::*;
use rand::{rngs::StdRng, Rng, SeedableRng};
use rand_distr::Normal;
use runout_core::shank::*;
use runout_core::*;
use std::f64::consts::{PI, TAU};

fn example1() -> ShankBeam {
    ShankBeam::new(210.0, 8.0, 65.0, 10.0, 30.0).unwrap()
}

#[test]
fn patent_worked_examples_and_wrong_alternatives() {
    let e1 = example1();
    let e2 = ShankBeam::new(610.0, 12.0, 85.0, 15.0, 35.0).unwrap();
    // patent: 1.9488 and 17.2874 N/µm (± 0.0001); methods.md §7: 1.948754, 17.287361
    for (beam, patent, vector) in [(e1, 1.9488, 1.948754), (e2, 17.2874, 17.287361)] {
        let k = beam.stiffness_n_per_um();
        assert!((k - patent).abs() <= 1e-4, "{k} vs patent {patent}");
        assert!((k - vector).abs() <= 1e-6, "{k} vs {vector}");
        let ei = beam.modulus_n_per_mm2 * beam.second_moment_mm4();
        // wrong alternative 1: tip stiffness 3EI/l³ (0.461 / 3.033 N/µm)
        let tip = 3.0 * ei / beam.tool_length_mm.powi(3) / 1e3;
        // wrong alternative 2: single-point stiffness at l_II (1.706 / 13.82 N/µm)
        let l2 = beam.l2_mm;
        let single = 6.0 * ei / (l2 * l2 * (3.0 * beam.tool_length_mm - l2)) / 1e3;
        assert!((tip - patent).abs() > 0.1 * patent, "tip {tip}");
        assert!((single - patent).abs() > 0.1 * patent, "single {single}");
    }
    assert!((example1().second_moment_mm4() - 201.06).abs() < 0.01);
}

#[test]
fn load_point_and_holder_options() {
    // methods.md §3.1: example 1 with a = 64 mm gives 1.985 N/µm (+1.9 %)
    let mid = example1()
        .with_load_point(LoadPoint::MidDepth {
            axial_depth_mm: 2.0,
        })
        .unwrap();
    assert!(
        (mid.stiffness_n_per_um() - 1.985).abs() < 5e-4,
        "{}",
        mid.stiffness_n_per_um()
    );
    // holder rotation adds (l_II − l_I)·a/k_θ to the compliance
    let k_theta = 2e7;
    let held = example1().with_holder_stiffness(k_theta).unwrap();
    let expect = 1.0 / (1.0 / example1().stiffness_n_per_mm() + 20.0 * 65.0 / k_theta);
    assert!((held.stiffness_n_per_mm() - expect).abs() < 1e-9 * expect);
    // a load point between the sensors and the tip, sensor above it: x > a branch
    let low = example1()
        .with_load_point(LoadPoint::At { distance_mm: 25.0 })
        .unwrap();
    let ei = low.modulus_n_per_mm2 * low.second_moment_mm4();
    let c = (625.0 * (3.0 * 30.0 - 25.0) - 100.0 * (75.0 - 10.0)) / (6.0 * ei);
    assert!((low.stiffness_n_per_mm() - 1.0 / c).abs() < 1e-9 / c);
}

#[test]
fn bad_geometry_is_rejected_with_the_parameter_named() {
    let e = ShankBeam::new(210.0, 8.0, 65.0, 20.0, 20.0).unwrap_err();
    assert_eq!(e.param, "l2_mm");
    assert!(e.expected.contains("equal heights"), "{e}");
    let e = ShankBeam::new(210.0, 8.0, 65.0, 10.0, 70.0).unwrap_err();
    assert_eq!(e.param, "l2_mm");
    assert!(e.to_string().contains("tool_length_mm"), "{e}");
    assert_eq!(
        ShankBeam::new(210.0, 8.0, 65.0, 30.0, 10.0)
            .unwrap_err()
            .param,
        "l2_mm"
    );
    assert_eq!(
        ShankBeam::new(0.0, 8.0, 65.0, 10.0, 30.0)
            .unwrap_err()
            .param,
        "modulus_gpa"
    );
    assert_eq!(
        ShankBeam::new(210.0, -8.0, 65.0, 10.0, 30.0)
            .unwrap_err()
            .param,
        "diameter_mm"
    );
    let e = example1()
        .with_load_point(LoadPoint::MidDepth {
            axial_depth_mm: 200.0,
        })
        .unwrap_err();
    assert_eq!(e.param, "load_point_mm");
}

/// Found by a stress run of the CLI's flag properties: a subnormal holder stiffness made each
/// sensor's holder term overflow and K_δ = ∞ − ∞ = NaN (exit 0, `K_delta = NaN N/um`); a
/// subnormal modulus gave NaN too, and a sensor gap of 1e-200 mm an infinite K_δ. Now each is
/// refused, naming the key, and every accepted beam has a finite K_δ > 0.
#[test]
fn subnormal_and_degenerate_beams_are_refused() {
    for k in [5e-324, 1.29e-309, 1e-20, 0.5, -1.0, f64::NAN, 2e12] {
        let e = example1().with_holder_stiffness(k * 1e3).unwrap_err();
        assert_eq!(e.param, "holder_stiffness_Nm_per_rad", "{k}: {e}");
        assert!(e.expected.contains("N·m/rad"), "{e}");
    }
    // given in N·m/rad: the value as given in the message, not its overflowed N·mm/rad
    let e = example1()
        .with_holder_stiffness_nm_per_rad(1e308)
        .unwrap_err();
    assert_eq!(e.got, "1e308", "{e}");
    for m in [5e-324, 1e-320, 0.5, 3000.0] {
        let e = ShankBeam::new(m, 8.0, 65.0, 10.0, 30.0).unwrap_err();
        assert_eq!(e.param, "modulus_gpa", "{m}: {e}");
    }
    for l2 in [1e-200, 2.2e-308, 1e-100, 5e-4] {
        let e = ShankBeam::new(210.0, 8.0, 65.0, 0.0, l2).unwrap_err();
        assert_eq!(e.param, "l2_mm", "{l2}: {e}");
        assert!(e.expected.contains("0.001 mm apart"), "{e}");
        assert!(e.to_string().len() < 200, "{e}");
    }
    // the limits themselves are accepted, with a finite K_δ
    let soft = example1().with_holder_stiffness(1e3).unwrap();
    let k = soft.stiffness_n_per_mm();
    assert!(k.is_finite() && k > 0.0, "{k}");
    let close = ShankBeam::new(210.0, 8.0, 65.0, 0.0, 0.001).unwrap();
    assert!(close.stiffness_n_per_mm().is_finite());
}

proptest! {
    /// Every beam the constructors accept has a finite K_δ > 0 and a finite first bending mode:
    /// inputs over the accepted ranges (moduli 1–2000 GPa, diameters 1 µm–2 m, sensors from the
    /// holder face to the tip at least 1 µm apart, holders 1–1e12 N·m/rad, log-uniform).
    #[test]
    fn every_accepted_beam_has_a_finite_positive_stiffness(
        log_e in 0.0f64..3.3,
        log_d in -3.0f64..3.3,
        log_l in -2.0f64..5.0,
        u1 in 0.0f64..1.0,
        u2 in 0.0f64..1.0,
        log_k in prop::option::of(0.0f64..12.0),
    ) {
        let lt = 10f64.powf(log_l);
        let l1 = u1 * lt;
        let l2 = l1 + 1e-3 + u2 * (lt - l1);
        let beam = ShankBeam::new(10f64.powf(log_e), 10f64.powf(log_d), lt, l1, l2);
        let Ok(mut beam) = beam else { return Ok(()) }; // (l2 beyond the tip: refused)
        if let Some(lk) = log_k {
            beam = beam.with_holder_stiffness(10f64.powf(lk) * 1e3).unwrap();
        }
        let k = beam.stiffness_n_per_mm();
        prop_assert!(k.is_finite() && k > 0.0, "{beam:?}: {k}");
        let f1 = beam.first_bending_mode_hz(7850.0).unwrap();
        prop_assert!(f1.is_finite() && f1 > 0.0, "{beam:?}: {f1}");
    }
}

/// Δ for a load F at a on the true shank (bending scale s, holder k_θ).
fn true_delta(beam: &ShankBeam, s: f64, k_theta: f64, f: f64, a: f64) -> f64 {
    let ei = beam.modulus_n_per_mm2 * beam.second_moment_mm4();
    let b =
        ShankBeam::bending_shape_mm3(beam.l2_mm, a) - ShankBeam::bending_shape_mm3(beam.l1_mm, a);
    f * (s * b / (6.0 * ei) + (beam.l2_mm - beam.l1_mm) * a / k_theta)
}

#[test]
fn static_calibration_recovers_stiffness_and_holder_compliance() {
    let beam = example1();
    let (s_true, k_theta) = (1.03, 2e7);
    let truth = beam.with_holder_stiffness(k_theta).unwrap();
    let k_true = 1.0
        / (1.0 / truth.stiffness_n_per_mm() + (s_true - 1.0) * (1.0 / beam.stiffness_n_per_mm()));
    let mut rng = StdRng::seed_from_u64(7);
    let noise = Normal::new(0.0, 5e-5).unwrap(); // 0.05 µm sensor noise
    let mut steps = Vec::new();
    for a in [35.0, 50.0, 64.0] {
        for f in [0.0, 20.0, 40.0, 60.0, 80.0, 100.0] {
            steps.push(LoadStep {
                force_n: f,
                load_point_mm: a,
                delta_mm: 0.002 + true_delta(&beam, s_true, k_theta, f, a) + rng.sample(noise),
            });
        }
    }
    let cal = calibrate(&beam, &steps).unwrap();
    // tolerance: 4 standard errors, and the SE itself small (noise 0.05 µm on Δ ≈ 60 µm)
    assert!((cal.stiffness_n_per_mm - k_true).abs() < 4.0 * cal.stiffness_se_n_per_mm);
    assert!(cal.stiffness_se_n_per_mm < 0.003 * k_true, "{cal:?}");
    let (c, c_se) = cal.holder_compliance_rad_per_nmm.unwrap();
    assert!(
        (c - 1.0 / k_theta).abs() < 4.0 * c_se,
        "{c} ± {c_se} vs {}",
        1.0 / k_theta
    );
    assert!(c_se < 0.1 / k_theta, "{c_se} vs {}", 1.0 / k_theta);
    let (s, s_se) = cal.beam_scale.unwrap();
    assert!((s - s_true).abs() < 4.0 * s_se);
    assert!((cal.offset_mm - 0.002).abs() < 1e-4);
    assert!(cal.r_squared > 0.9999);
    // one load point: K only, holder not identifiable
    let one: Vec<LoadStep> = steps
        .iter()
        .copied()
        .filter(|s| s.load_point_mm == 64.0)
        .collect();
    let cal1 = calibrate(
        &beam
            .with_load_point(LoadPoint::At { distance_mm: 64.0 })
            .unwrap(),
        &one,
    )
    .unwrap();
    assert!(cal1.holder_compliance_rad_per_nmm.is_none());
    let k64 = 1.0 / true_delta(&beam, s_true, k_theta, 1.0, 64.0);
    assert!((cal1.stiffness_n_per_mm - k64).abs() < 4.0 * cal1.stiffness_se_n_per_mm);
    // degenerate: a single force
    let flat: Vec<LoadStep> = (0..5)
        .map(|_| LoadStep {
            force_n: 50.0,
            load_point_mm: 64.0,
            delta_mm: 0.02,
        })
        .collect();
    assert!(matches!(
        calibrate(&beam, &flat),
        Err(ShankError::Calibration(_))
    ));
}

/// The synthetic recording of the round trip.
struct Synthetic {
    columns: Vec<Vec<f64>>,
    truth_fx: Vec<f64>,
    truth_fy: Vec<f64>,
    cut: (usize, usize),
    f_true: f64,
    e0: (f64, f64),
    tilt: (f64, f64),
}

const FS: f64 = 20_000.0;
const RPM: f64 = 3000.0;

/// Force history from the force model (one revolution, periodic), the beam's deflections at the
/// two sensor heights, runout offset + tilt and shank form error rotating with the spindle, gap
/// offsets, a slow drift, 0.1 % spindle-speed error, Gaussian sensor noise; optional pulse.
fn synthetic(air_before: f64, cut_revs: f64, air_after: f64, pulse: bool, seed: u64) -> Synthetic {
    let cutter = Cutter::flat(8.0, 3, 30.0f64.to_radians()).unwrap();
    let tool_runout = Runout::new(0.010, 30f64.to_radians()).unwrap();
    let cut = Cut::new(RPM, 0.05, 2.0)
        .unwrap()
        .radial(2.0, MillingMode::Down, &cutter)
        .unwrap();
    let coefficients =
        CuttingCoefficients::new([1889.2, 806.1, 291.0], [63.12, 113.7, -3.1]).unwrap();
    let chip = ArcChip::new(&cutter, &tool_runout, 0.05).unwrap();
    let model = ForceModel {
        cutter,
        runout: tool_runout,
        cut,
        coefficients,
    };
    let series = model.simulate(&chip, &Sampling::new(1.0, 0.2, 20).unwrap());
    let per_rev = series.fx.len();
    let force_at = |th: f64, v: &[f64]| {
        let u = (th / TAU).rem_euclid(1.0) * per_rev as f64;
        let i = u.floor() as usize % per_rev;
        let w = u - u.floor();
        v[i] * (1.0 - w) + v[(i + 1) % per_rev] * w
    };
    let beam = example1();
    let (c1, c2) = (
        beam.compliance_at_mm_per_n(10.0),
        beam.compliance_at_mm_per_n(30.0),
    );
    let f_true = RPM / 60.0 * 1.001;
    let total = ((air_before + cut_revs + air_after) / f_true * FS) as usize;
    let e0 = (0.010 * (0.7f64).cos(), 0.010 * (0.7f64).sin());
    let tilt = (0.0002 * (2.1f64).cos(), 0.0002 * (2.1f64).sin());
    let e_at = |z: f64| (e0.0 + z * tilt.0, e0.1 + z * tilt.1);
    let (z1, z2) = (55.0, 35.0);
    let mut rng = StdRng::seed_from_u64(seed);
    let noise = Normal::new(0.0, 5e-5).unwrap(); // 0.05 µm
    let mut cols = vec![Vec::with_capacity(total); 4 + usize::from(pulse)];
    let (mut tfx, mut tfy) = (Vec::new(), Vec::new());
    let start = (air_before / f_true * FS) as usize;
    let end = ((air_before + cut_revs) / f_true * FS) as usize;
    for k in 0..total {
        let t = k as f64 / FS;
        let th = TAU * f_true * t;
        let rev = th / TAU;
        let env = if k < start || k >= end {
            0.0
        } else {
            let r_in = (rev - air_before).min(air_before + cut_revs - rev);
            (r_in / 2.0).clamp(0.0, 1.0) // 2-revolution entry and exit ramps
        };
        let (fx, fy) = (
            env * force_at(th, &series.fx),
            env * force_at(th, &series.fy),
        );
        tfx.push(fx);
        tfy.push(fy);
        let drift = 0.0005 * t / 7.0;
        for (axis, f_wp) in [(0, fx), (1, fy)] {
            for (h, (z, c, gap)) in [(z1, c1, 0.5), (z2, c2, 0.48)].into_iter().enumerate() {
                let e = e_at(z);
                // runout seen by an x sensor: Re(E e^{jθ}); by a y sensor: −Im(E e^{jθ})
                let (re, im) = (
                    e.0 * th.cos() - e.1 * th.sin(),
                    e.0 * th.sin() + e.1 * th.cos(),
                );
                let runout = if axis == 0 { re } else { -im };
                let form = 0.0015 * (2.0 * th + 0.3 + h as f64).cos() / (1.0 + h as f64)
                    + 0.0005 * (3.0 * th + 1.1 * axis as f64).sin();
                let deflection = c * (-f_wp); // force on the tool = −force on the workpiece
                cols[2 * axis + h]
                    .push(gap + runout + form + deflection + drift * h as f64 + rng.sample(noise));
            }
        }
        if pulse {
            cols[4].push(if rev.fract() < 0.05 { 5.0 } else { 0.0 });
        }
    }
    Synthetic {
        columns: cols,
        truth_fx: tfx,
        truth_fy: tfy,
        cut: (start, end),
        f_true,
        e0,
        tilt,
    }
}

fn setup(pulse: bool) -> ShankSetup {
    let mut s = ShankSetup::new(
        example1(),
        vec![
            SensorPair {
                axis: PairAxis::X,
                sign: 1.0,
            },
            SensorPair {
                axis: PairAxis::Y,
                sign: 1.0,
            },
        ],
        FS,
        RPM,
    );
    s.has_pulse = pulse;
    s
}

fn rms_error(est: &[f64], truth: &[f64], range: (usize, usize)) -> f64 {
    let (mut se, mut st) = (0.0, 0.0);
    for k in range.0..range.1 {
        se += (est[k] - truth[k]).powi(2);
        st += truth[k].powi(2);
    }
    (se / st).sqrt()
}

#[test]
fn round_trip_force_and_runout_over_300_revolutions() {
    for pulse in [false, true] {
        let syn = synthetic(20.0, 300.0, 20.0, pulse, 11 + u64::from(pulse));
        let cols: Vec<&[f64]> = syn.columns.iter().map(Vec::as_slice).collect();
        let (analysis, out, _) = process_in_memory(&setup(pulse), &cols).unwrap();
        assert_eq!(
            analysis.air_segments.len(),
            2,
            "{:?}",
            analysis.air_segments
        );
        // spindle: 0.1 % off nominal, recovered to 1e-6 relative (phase drift < 0.001 rev over 340 revolutions)
        let f = analysis.spindle.mean_frequency_hz();
        assert!(
            (f / syn.f_true - 1.0).abs() < 1e-6,
            "pulse {pulse}: f {f} vs {}",
            syn.f_true
        );
        // force within 2 % RMS of the truth over the cut (sensor noise alone gives ≈ 0.2 %)
        let ex = rms_error(&out.force_n[0], &syn.truth_fx, syn.cut);
        let ey = rms_error(&out.force_n[1], &syn.truth_fy, syn.cut);
        eprintln!(
            "pulse {pulse}: relative RMS force error x {ex:.5} y {ey:.5}; f error {:.2e}; tip offset error {:.3} µm; tilt error {:.4} µm/mm",
            f / syn.f_true - 1.0,
            (analysis.runout.tip_offset_mm()[0] - syn.e0.0).hypot(analysis.runout.tip_offset_mm()[1] - syn.e0.1) * 1e3,
            (analysis.runout.line.tilt[0].value - syn.tilt.0).hypot(analysis.runout.line.tilt[1].value - syn.tilt.1) * 1e3,
        );
        assert!(
            ex < 0.02 && ey < 0.02,
            "pulse {pulse}: relative RMS errors {ex} {ey}"
        );
        // the detected cut brackets the true one within 2 revolutions of margin
        let c = analysis.cut.unwrap();
        let spr = FS / syn.f_true;
        assert!(
            (c.start as f64) <= syn.cut.0 as f64 + 1.0
                && (c.start as f64) > syn.cut.0 as f64 - 3.0 * spr
        );
        assert!(
            (c.end as f64) >= syn.cut.1 as f64 - 1.0
                && (c.end as f64) < syn.cut.1 as f64 + 3.0 * spr
        );
        // runout from the air-cut templates: offset at the tip and tilt (θ = 0 is t = 0 here,
        // or the pulse edge, which the synthetic puts at θ = 0 too)
        let r = &analysis.runout;
        let [ox, oy] = r.tip_offset_mm();
        let [tx, ty] = r.line.tilt_vector();
        // offset within 0.1 µm and tilt within 0.005 µm/mm per component (noise 0.05 µm averaged
        // over 40 revolutions; the pulse edge is quantised to 1/20 kHz → ≤ 0.9° of phase)
        let tol_o = if pulse { 0.0002 } else { 0.0001 };
        assert!(
            (ox - syn.e0.0).abs() < tol_o && (oy - syn.e0.1).abs() < tol_o,
            "pulse {pulse}: {ox} {oy} vs {:?}",
            syn.e0
        );
        assert!(
            (tx - syn.tilt.0).abs() < 5e-6 && (ty - syn.tilt.1).abs() < 5e-6,
            "{tx} {ty} vs {:?}",
            syn.tilt
        );
        assert!(r.offset_se_mm() < 1e-4);
        assert!(analysis.saturated_samples == 0);
        assert!(analysis.warnings.is_empty(), "{:?}", analysis.warnings);
    }
}

#[test]
fn low_pass_keeps_the_force_and_validation_metrics_agree() {
    let syn = synthetic(10.0, 40.0, 10.0, false, 5);
    let mut s = setup(false);
    s.has_reference = true;
    // tooth frequency 150 Hz: a 2 kHz cutoff keeps the force's harmonics up to ~13×
    s.lowpass = Some((4, 2000.0));
    let mut cols: Vec<&[f64]> = syn.columns.iter().map(Vec::as_slice).collect();
    cols.push(&syn.truth_fx);
    cols.push(&syn.truth_fy);
    let (_, out, cmp) = process_in_memory(&s, &cols).unwrap();
    assert_eq!(out.len(), syn.truth_fx.len());
    let cmp = cmp.unwrap();
    let ex = rms_error(&out.force_n[0], &syn.truth_fx, syn.cut);
    assert!(ex < 0.02, "{ex}");
    // streaming metrics agree with the direct computation over the detected cut
    assert!(cmp[0].relative_rms_error < 0.03, "{:?}", cmp[0]);
    assert!(cmp[0].correlation > 0.999, "{:?}", cmp[0]);
    assert!(
        cmp[0].peak_error_n.abs() < 0.03 * cmp[0].rms_reference_n * 3.0,
        "{:?}",
        cmp[0]
    );
}

#[test]
fn no_air_cut_is_an_error() {
    // the cut starts after 2 revolutions and runs to the end
    let syn = synthetic(2.0, 40.0, 0.0, false, 3);
    let cols: Vec<&[f64]> = syn.columns.iter().map(Vec::as_slice).collect();
    let err = process_in_memory(&setup(false), &cols).unwrap_err();
    assert!(matches!(err, ShankError::NoAirCut(_)), "{err}");
    assert!(err.to_string().contains("air_cut_s"), "{err}");
    // a given air cut that is too short
    let mut s = setup(false);
    s.air_cut_s = vec![(0.0, 0.03)];
    let err = process_in_memory(&s, &cols).unwrap_err();
    assert!(err.to_string().contains("at least 5"), "{err}");
}

#[test]
fn saturated_samples_are_flagged_not_used() {
    let mut syn = synthetic(10.0, 30.0, 10.0, false, 9);
    // clip sensor II of x at its maximum over 200 samples in the middle of the cut
    let mid = (syn.cut.0 + syn.cut.1) / 2;
    let rail = syn.columns[1].iter().cloned().fold(f64::MIN, f64::max) + 0.001;
    for v in &mut syn.columns[1][mid..mid + 200] {
        *v = rail;
    }
    let cols: Vec<&[f64]> = syn.columns.iter().map(Vec::as_slice).collect();
    let (analysis, out, _) = process_in_memory(&setup(false), &cols).unwrap();
    assert_eq!(analysis.saturated_samples, 200);
    assert!(analysis.warnings.iter().any(|w| w.contains("saturated")));
    assert!(out.saturated[mid..mid + 200].iter().all(|&s| s));
    assert!(out.force_n[0][mid..mid + 200].iter().all(|f| f.is_nan()));
    assert!(!out.saturated[mid - 1] && !out.saturated[mid + 200]);
    // explicit sensor range flags too
    let mut s = setup(false);
    s.sensor_range_mm = Some((-1.0, rail));
    let (_, out, _) = process_in_memory(&s, &cols).unwrap();
    assert!(out.force_n[0][mid].is_nan());
}

#[test]
fn equal_sensor_heights_and_bad_setup() {
    let mut s = setup(false);
    s.pairs.clear();
    assert!(matches!(Survey::new(&s), Err(ShankError::Param(p)) if p.param == "pairs"));
    let mut s = setup(false);
    s.nominal_rpm = 200_000.0; // 6 samples per revolution
    assert!(matches!(Survey::new(&s), Err(ShankError::Param(p)) if p.param == "sample_rate_hz"));
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(24))]

    /// The stiffness equals the patent formula for any valid geometry with the tip load.
    #[test]
    fn stiffness_matches_the_closed_form(
        e in 70.0f64..700.0, d in 3.0f64..25.0, lt in 40.0f64..150.0, f1 in 0.0f64..0.4, f2 in 0.45f64..1.0,
    ) {
        let (l1, l2) = (f1 * lt, f2 * lt);
        let beam = ShankBeam::new(e, d, lt, l1, l2).unwrap();
        let i = PI * d.powi(4) / 64.0;
        let k = 6.0 * e * 1e3 * i / (l2 * l2 * (3.0 * lt - l2) - l1 * l1 * (3.0 * lt - l1));
        prop_assert!((beam.stiffness_n_per_mm() - k).abs() < 1e-9 * k);
    }

    /// Static calibration is exact on noiseless steps for any holder stiffness and scale.
    #[test]
    fn calibration_is_exact_without_noise(s_true in 0.9f64..1.2, log_k in 6.5f64..9.0) {
        let beam = example1();
        let k_theta = 10f64.powf(log_k);
        let steps: Vec<LoadStep> = [40.0, 52.0, 64.0]
            .iter()
            .flat_map(|&a| [10.0, 50.0, 90.0].map(move |f| (a, f)))
            .map(|(a, f)| LoadStep { force_n: f, load_point_mm: a, delta_mm: true_delta(&beam, s_true, k_theta, f, a) })
            .collect();
        let cal = calibrate(&beam, &steps).unwrap();
        let k = 1.0 / true_delta(&beam, s_true, k_theta, 1.0, 65.0);
        prop_assert!((cal.stiffness_n_per_mm / k - 1.0).abs() < 1e-8);
        prop_assert!((cal.holder_compliance_rad_per_nmm.unwrap().0 * k_theta - 1.0).abs() < 1e-5);
    }

    /// The spindle frequency from two air cuts is recovered for any speed error within ±1 %.
    #[test]
    fn spindle_frequency_from_phase_advance(err in -0.01f64..0.01, phase in 0.0f64..TAU, gap in 2.0f64..8.0) {
        let f_true = 50.0 * (1.0 + err);
        let sig = |t: f64| 0.004 * (TAU * f_true * t + phase).cos() + 0.001 * (2.0 * TAU * f_true * t).cos();
        let a: Vec<f64> = (0..3000).map(|k| sig(k as f64 / FS)).collect();
        let b: Vec<f64> = (0..3000).map(|k| sig(gap + k as f64 / FS)).collect();
        let (f, _, _) = frequency_from_air(
            &[PhaseSegment { x: &a, t_start: 0.0 }, PhaseSegment { x: &b, t_start: gap }], FS, 50.0);
        // what matters is the phase propagated across the gap: < 1e-3 rad (0.06°)
        prop_assert!(((f - f_true) * TAU * gap).abs() < 1e-3, "{} vs {}", f, f_true);
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(8))]

    /// Round trip over realistic ranges: runout 2–20 µm at any angle, tilt up to 0.5 µm/mm,
    /// spindle-speed error up to ±0.5 %, sensor sign conventions of either kind.
    #[test]
    fn round_trip_over_realistic_ranges(
        rho_um in 2.0f64..20.0, lam in 0.0f64..TAU, tilt_um in 0.0f64..0.5, tilt_dir in 0.0f64..TAU,
        speed_err in -0.005f64..0.005, sign_x in prop_oneof![Just(1.0), Just(-1.0)], seed in 0u64..1000,
    ) {
        let beam = example1();
        let syn = SyntheticShank {
            beam,
            sample_rate_hz: FS,
            rpm: RPM * (1.0 + speed_err),
            revolutions: (8.0, 40.0, 8.0),
            offset_mm: (rho_um * 1e-3 * lam.cos(), rho_um * 1e-3 * lam.sin()),
            tilt: (tilt_um * 1e-3 * tilt_dir.cos(), tilt_um * 1e-3 * tilt_dir.sin()),
            form_mm: (0.001, 0.0005),
            gap_mm: (0.5, 0.45),
            drift_mm: 0.0003,
            ramp_revolutions: 1.0,
            pulse: false,
            chain: Default::default(),
        };
        // a simple 3-tooth force pattern per revolution
        let n = 720;
        let fx: Vec<f64> = (0..n).map(|i| 60.0 * ((3.0 * TAU * i as f64 / n as f64).sin()).max(0.0)).collect();
        let fy: Vec<f64> = (0..n).map(|i| -150.0 * ((3.0 * TAU * i as f64 / n as f64 + 0.4).sin()).max(0.0)).collect();
        let mut rng = StdRng::seed_from_u64(seed);
        let noise = Normal::new(0.0, 5e-5).unwrap();
        let mut rec = syn.generate(&fx, &fy, || rng.sample(noise));
        // a sensor pair mounted the other way round reads the negated displacement
        for c in &mut rec.columns[..2] {
            c.iter_mut().for_each(|v| *v *= sign_x);
        }
        let mut s = setup(false);
        s.pairs[0].sign = sign_x;
        let cols: Vec<&[f64]> = rec.columns.iter().map(Vec::as_slice).collect();
        let (an, out, _) = process_in_memory(&s, &cols).unwrap();
        let ex = rms_error(&out.force_n[0], &rec.force_n[0], rec.cut);
        let ey = rms_error(&out.force_n[1], &rec.force_n[1], rec.cut);
        prop_assert!(ex < 0.02 && ey < 0.02, "errors {} {}", ex, ey);
        // offset within 0.1 µm and tilt within 0.005 µm/mm (16 air revolutions, 0.05 µm noise)
        let r = &an.runout;
        let ([ox, oy], [tx, ty]) = (r.tip_offset_mm(), r.line.tilt_vector());
        prop_assert!((ox - syn.offset_mm.0).hypot(oy - syn.offset_mm.1) < 1e-4, "{} {} vs {:?}", ox, oy, syn.offset_mm);
        prop_assert!((tx - syn.tilt.0).hypot(ty - syn.tilt.1) < 5e-6, "{} {} vs {:?}", tx, ty, syn.tilt);
    }
}

#[test]
fn missing_channels_are_an_error_not_a_panic() {
    let syn = synthetic(8.0, 10.0, 8.0, false, 2);
    let cols: Vec<&[f64]> = syn.columns.iter().map(Vec::as_slice).collect();
    let err = process_in_memory(&setup(false), &cols[..3]).unwrap_err();
    assert!(matches!(err, ShankError::Input(_)), "{err}");
    let mut survey = Survey::new(&setup(false)).unwrap();
    survey.push(&cols).unwrap();
    let res = survey.finish().unwrap();
    let an = analyse(&res).unwrap();
    let mut rec = Reconstructor::new(&res, &an).unwrap();
    let mut out = OutputBlock::default();
    assert!(rec.push(&cols[..2], &mut out).is_err());
    assert!(rec.push(&cols, &mut out).is_ok());
    assert_eq!(out.len(), cols[0].len());
}

// ---- issue 11 item 7: bending mode, bandwidth, correction -------------------------------

/// f₁ of the beam against the textbook cantilever formula 1.875104²/(2π)·sqrt(EI/(ρA·L⁴)),
/// evaluated here independently in SI units; a holder spring lowers it.
#[test]
fn cantilever_first_mode_matches_the_textbook_formula() {
    for (e_gpa, d, l, rho) in [
        (210.0, 8.0, 65.0, 7850.0),
        (600.0, 12.0, 85.0, 14_500.0),
        (210.0, 20.0, 120.0, 7850.0),
    ] {
        let beam = ShankBeam::new(e_gpa, d, l, 10.0, 30.0).unwrap();
        let (e, d_m, l_m) = (e_gpa * 1e9, d * 1e-3, l * 1e-3);
        let i = PI * d_m.powi(4) / 64.0;
        let a = PI * d_m * d_m / 4.0;
        let want = 1.875_104_f64.powi(2) / TAU * (e * i / (rho * a * l_m.powi(4))).sqrt();
        let got = beam.first_bending_mode_hz(rho).unwrap();
        assert!((got / want - 1.0).abs() < 1e-6, "{got} vs {want} Hz");
    }
    // the example tool (steel d 8, L 65 mm): 1370 Hz
    let f1 = example1()
        .first_bending_mode_hz(STEEL_DENSITY_KG_PER_M3)
        .unwrap();
    assert!((f1 - 1370.0).abs() < 5.0, "{f1}");
    // a holder of k_θ = 3EI/L lowers it (κ = 3: βL from the spring-clamped equation < 1.875)
    let ei = example1().modulus_n_per_mm2 * example1().second_moment_mm4();
    let held = example1().with_holder_stiffness(3.0 * ei / 65.0).unwrap();
    let fh = held.first_bending_mode_hz(STEEL_DENSITY_KG_PER_M3).unwrap();
    assert!(fh < 0.9 * f1 && fh > 0.5 * f1, "{fh} vs {f1}");
    // default density by modulus
    assert_eq!(default_density_kg_per_m3(210.0), 7850.0);
    assert_eq!(default_density_kg_per_m3(600.0), 14_500.0);
    assert!(example1().first_bending_mode_hz(0.0).is_err());
}

fn mode_chain(hz: f64, zeta: f64) -> chain::MeasuringChain {
    let axis = chain::AxisChain::Modes(vec![chain::SensorMode::new(hz, zeta, 1.0).unwrap()]);
    chain::MeasuringChain {
        x: axis.clone(),
        y: axis,
        z: chain::AxisChain::Rigid,
    }
}

/// Usable band without correction: |H − 1| = 10 % at r ≈ sqrt(1/11) = 0.3015 (ζ → 0); the
/// warning names the harmonics above it only when the teeth are known; with a correction the
/// band grows to where |H| = 1.73ε and the warning goes.
#[test]
fn bandwidth_and_tooth_harmonic_warning() {
    let beam = example1();
    let mut dynamics = ShankDynamics::for_beam(&beam);
    let f1 = beam.first_bending_mode_hz(7850.0).unwrap();
    let axes = [PairAxis::X, PairAxis::Y];
    // 3 teeth at 3000 rpm: 150 Hz, harmonics to 750 Hz; band ≈ 0.30·1370 = 410 Hz
    let (b, w) = bandwidth(&beam, &dynamics, &axes, 50.0, FS).unwrap();
    assert!(w.is_none(), "no teeth given: {w:?}");
    let r = b.uncorrected_hz / f1;
    assert!((r - (1.0f64 / 11.0).sqrt()).abs() < 0.005, "{r}");
    assert!(b.harmonics_beyond.is_empty());
    dynamics.teeth = Some(3);
    let (b, w) = bandwidth(&beam, &dynamics, &axes, 50.0, FS).unwrap();
    let w = w.expect("harmonics 3–5 (450–750 Hz) above ≈ 410 Hz");
    assert_eq!(
        b.harmonics_beyond.iter().map(|h| h.0).collect::<Vec<_>>(),
        vec![3, 4, 5]
    );
    assert!(
        w.contains("tooth-passing harmonics 3–5") && w.contains("1370 Hz"),
        "{w}"
    );
    // one tooth at 3000 rpm: harmonics to 250 Hz, inside the band
    dynamics.teeth = Some(1);
    assert!(bandwidth(&beam, &dynamics, &axes, 50.0, FS)
        .unwrap()
        .1
        .is_none());
    // corrected by the beam's own mode: band up to |H| = 1.73·0.1 → r ≈ 2.6
    dynamics.teeth = Some(3);
    dynamics.correction = Some(Correction {
        chain: mode_chain(f1, 0.03),
        source: "beam mode".into(),
        floor: 0.1,
    });
    let (b, w) = bandwidth(&beam, &dynamics, &axes, 50.0, FS).unwrap();
    let rc = b.corrected_hz.unwrap() / f1;
    let want = (1.0 + 1.0 / (9f64.powf(0.25) * 0.1)).sqrt();
    assert!((rc - want).abs() < 0.02 * want, "{rc} vs {want}");
    assert!(w.is_none(), "{w:?}");
    // …but 3 teeth at 30 000 rpm (1.5 kHz tooth passing) reach beyond even that
    let (_, w) = bandwidth(&beam, &dynamics, &axes, 500.0, FS).unwrap();
    assert!(w.unwrap().contains("corrected bandwidth"));
}

/// Relative RMS error sqrt(Σ|E(kf)|²|F_k|² / Σ|F_k|²) of a periodic force whose harmonic k is
/// reconstructed as (1 + E(kf))·F_k (Parseval), from one revolution `f` sampled uniformly at
/// spindle frequency `spindle_hz`: E = H − 1 for the static relation through a chain H,
/// E = G·H − 1 after the deconvolution G.
fn harmonic_error(f: &[f64], spindle_hz: f64, e: impl Fn(f64) -> f64) -> f64 {
    let n = f.len();
    let (mut num, mut den) = (0.0, 0.0);
    for k in 0..=n / 2 {
        let (mut re, mut im) = (0.0, 0.0);
        for (i, v) in f.iter().enumerate() {
            let ph = TAU * (k * i) as f64 / n as f64;
            re += v * ph.cos();
            im -= v * ph.sin();
        }
        let w = if k == 0 || 2 * k == n { 1.0 } else { 2.0 };
        let p = w * (re * re + im * im);
        num += p * e(k as f64 * spindle_hz).powi(2);
        den += p;
    }
    (num / den).sqrt()
}

/// A synthetic shank recording through a bending mode at 900 Hz (ζ 0.03) on x and y: the static
/// F = K_δ·Δ is wrong by what the harmonics of the force through H predict; deconvolved by that
/// mode it matches the true force as closely as a rigid recording does.
#[test]
fn bending_mode_round_trip_wrong_without_correction_right_with_it() {
    let cutter = Cutter::flat(8.0, 3, 30.0f64.to_radians()).unwrap();
    let tool_runout = Runout::new(0.010, 30f64.to_radians()).unwrap();
    let cut = Cut::new(RPM, 0.05, 2.0)
        .unwrap()
        .radial(2.0, MillingMode::Down, &cutter)
        .unwrap();
    let coefficients =
        CuttingCoefficients::new([1889.2, 806.1, 291.0], [63.12, 113.7, -3.1]).unwrap();
    let chip = ArcChip::new(&cutter, &tool_runout, 0.05).unwrap();
    let series = ForceModel {
        cutter,
        runout: tool_runout,
        cut,
        coefficients,
    }
    .simulate(&chip, &Sampling::new(1.0, 0.2, 20).unwrap());
    let (mode_hz, zeta) = (900.0, 0.03);
    let make = |chain: chain::MeasuringChain| SyntheticShank {
        beam: example1(),
        sample_rate_hz: FS,
        rpm: RPM,
        revolutions: (10.0, 60.0, 10.0),
        offset_mm: (0.008, -0.003),
        tilt: (0.0001, 0.0),
        form_mm: (0.001, 0.0005),
        gap_mm: (0.5, 0.45),
        drift_mm: 0.0002,
        ramp_revolutions: 1.0,
        pulse: false,
        chain,
    };
    let run_lp = |syn: &SyntheticShank, correction: Option<Correction>, lowpass| {
        let mut rng = StdRng::seed_from_u64(21);
        let noise = Normal::new(0.0, 5e-5).unwrap(); // 0.05 µm sensor noise
        let rec = syn.generate(&series.fx, &series.fy, || rng.sample(noise));
        // one steady revolution of the true force as sampled (400 samples at 3000 rpm, 20 kHz)
        let spr = (FS * 60.0 / RPM) as usize;
        let mid = (rec.cut.0 + rec.cut.1) / 2;
        let one_rev = [
            rec.force_n[0][mid..mid + spr].to_vec(),
            rec.force_n[1][mid..mid + spr].to_vec(),
        ];
        let mut s = setup(false);
        s.dynamics.teeth = Some(3);
        s.dynamics.correction = correction;
        s.lowpass = lowpass;
        let cols: Vec<&[f64]> = rec.columns.iter().map(Vec::as_slice).collect();
        let (an, out, _) = process_in_memory(&s, &cols).unwrap();
        assert_eq!(out.len(), rec.force_n[0].len());
        // the cut without its entry/exit revolution (the ramp's corners are not periodic)
        let spr = (FS * 60.0 / RPM) as usize;
        let range = (rec.cut.0 + 2 * spr, rec.cut.1 - 2 * spr);
        (
            rms_error(&out.force_n[0], &rec.force_n[0], range),
            rms_error(&out.force_n[1], &rec.force_n[1], range),
            an,
            one_rev,
        )
    };
    let run = |syn: &SyntheticShank, correction| run_lp(syn, correction, None);
    let rigid = run(&make(Default::default()), None);
    let through = make(mode_chain(mode_hz, zeta));
    let plain = run(&through, None);
    let corrected = run(
        &through,
        Some(Correction {
            chain: mode_chain(mode_hz, zeta),
            source: "900 Hz mode".into(),
            floor: 0.1,
        }),
    );
    let h = mode_chain(mode_hz, zeta).x;
    let spindle = RPM / 60.0;
    let h_at = |f: f64| h.response(f).unwrap();
    let static_error = |f: f64| (h_at(f) - 1.0).norm();
    let corrected_error = |f: f64| (regularised_inverse(Some(h_at(f)), 0.1) * h_at(f) - 1.0).norm();
    let rev = &plain.3;
    let pred = [0, 1].map(|a| harmonic_error(&rev[a], spindle, static_error));
    let pred_c = [0, 1].map(|a| harmonic_error(&rev[a], spindle, corrected_error));
    eprintln!(
        "rigid {:.4} {:.4}; through the mode {:.4} {:.4} (predicted {:.4} {:.4}); corrected {:.4} {:.4} (predicted {:.4} {:.4})",
        rigid.0, rigid.1, plain.0, plain.1, pred[0], pred[1], corrected.0, corrected.1, pred_c[0], pred_c[1]
    );
    // without correction: wrong (49 % / 19 %), by what the force's harmonics through H predict,
    // within 5 % (noise, template, the first-order hold's sinc² ≤ 0.7 % below 900 Hz at 20 kHz)
    for (e, p) in [(plain.0, pred[0]), (plain.1, pred[1])] {
        assert!(e > 0.05, "uncorrected error {e}");
        assert!((e / p - 1.0).abs() < 0.05, "{e} vs predicted {p}");
    }
    // with it: what remains is the force's content where the regularised inverse fades out
    // (above ≈ 2.6 kHz: the tooth-entry steps of down milling), as predicted by |G·H − 1|, plus
    // sensor noise amplified by |G| ≤ 5.7 — within 0.005 of the prediction (the rigid round trip's
    // error from noise and template alone is 0.003), and within 2 % RMS
    for (c, p) in [(corrected.0, pred_c[0]), (corrected.1, pred_c[1])] {
        assert!(c < 0.02, "corrected error {c}");
        assert!((c - p).abs() < 0.005, "corrected {c} vs predicted {p}");
    }
    // followed by a zero-phase low-pass at 3 kHz (both streaming stages chained): rows aligned
    // (checked inside `run_lp`), and the force content above 3 kHz removed changes little
    let with_lp = run_lp(
        &through,
        Some(Correction {
            chain: mode_chain(mode_hz, zeta),
            source: "900 Hz mode".into(),
            floor: 0.1,
        }),
        Some((4, 3000.0)),
    );
    assert!(
        with_lp.0 < 0.02 && with_lp.1 < 0.02,
        "{} {}",
        with_lp.0,
        with_lp.1
    );
    assert!(
        (with_lp.0 - corrected.0).abs() < 0.003,
        "{} vs {}",
        with_lp.0,
        corrected.0
    );
    // the analysis reports the correction's band and no warning (harmonics 1–5 ≤ 750 Hz)
    assert!(corrected.2.bandwidth.corrected_hz.unwrap() > 2000.0);
    assert!(
        corrected.2.warnings.is_empty(),
        "{:?}",
        corrected.2.warnings
    );
    // and warns without it (example tool: f₁ = 1370 Hz, band ≈ 410 Hz)
    assert!(
        plain.2.warnings.iter().any(|w| w.contains("tooth-passing")),
        "{:?}",
        plain.2.warnings
    );
}

/// The bending resonance seen in the cut spectrum: a recording through a 900 Hz mode (ζ 0.03)
/// with a broadband random force (3 N RMS, the chip-to-chip part of a real cutting force) shows
/// it between the spindle lines; the fit to the peak's shape gives f and ζ; a rigid recording
/// shows none; the checks warn without a correction and with a correction at the wrong frequency.
#[test]
fn resonance_seen_in_the_cut_spectrum() {
    let cutter = Cutter::flat(8.0, 3, 30.0f64.to_radians()).unwrap();
    let tool_runout = Runout::new(0.010, 0.5).unwrap();
    let cut = Cut::new(RPM, 0.05, 2.0)
        .unwrap()
        .radial(2.0, MillingMode::Down, &cutter)
        .unwrap();
    let coefficients =
        CuttingCoefficients::new([1889.2, 806.1, 291.0], [63.12, 113.7, -3.1]).unwrap();
    let chip = ArcChip::new(&cutter, &tool_runout, 0.05).unwrap();
    let series = ForceModel {
        cutter,
        runout: tool_runout,
        cut,
        coefficients,
    }
    .simulate(&chip, &Sampling::new(1.0, 0.2, 20).unwrap());
    let run = |chain: chain::MeasuringChain, correction: Option<Correction>| {
        let syn = SyntheticShank {
            beam: example1(),
            sample_rate_hz: FS,
            rpm: RPM * 1.001,
            revolutions: (10.0, 150.0, 10.0),
            offset_mm: (0.008, -0.003),
            tilt: (0.0001, 0.0),
            form_mm: (0.001, 0.0005),
            gap_mm: (0.5, 0.45),
            drift_mm: 0.0002,
            ramp_revolutions: 1.0,
            pulse: false,
            chain,
        };
        let mut rng = StdRng::seed_from_u64(3);
        let noise = Normal::new(0.0, 5e-5).unwrap();
        let rec = syn.generate_with_random_force(&series.fx, &series.fy, 3.0, || rng.sample(noise));
        let mut s = setup(false);
        s.dynamics.teeth = Some(3);
        s.dynamics.correction = correction;
        let cols: Vec<&[f64]> = rec.columns.iter().map(Vec::as_slice).collect();
        process_in_memory(&s, &cols).unwrap().0
    };
    let an = run(mode_chain(900.0, 0.03), None);
    let seen = an.spectral_resonance.expect("resonance seen");
    // 150 revolutions of 400 samples: 3 frames of 16 384; f within 1 % (0.1 % grid, line
    // masking), ζ within 0.01 (3 frames × 2 axes of a χ² spectrum)
    assert!((seen.frequency_hz / 900.0 - 1.0).abs() < 0.01, "{seen:?}");
    assert!((seen.damping.unwrap() - 0.03).abs() < 0.01, "{seen:?}");
    assert!(seen.prominence > 100.0 && seen.frames == 3, "{seen:?}");
    let w = an
        .warnings
        .iter()
        .find(|w| w.contains("seen in the cut spectrum"))
        .expect("warning");
    assert!(
        w.contains("sensor_mode_hz = 900") && w.contains("harmonics 2 (300 Hz)"),
        "{w}"
    );
    // the static relation's band with the mode seen: ≈ 0.30·900 Hz
    let (usable, _) = spectral_check(
        &an.bandwidth,
        &setup(false).dynamics,
        &[PairAxis::X, PairAxis::Y],
        &seen,
        FS,
    );
    assert!((usable / 900.0 - 0.30).abs() < 0.01, "{usable}");
    // a rigid tool: the broadband force is white, no resonance
    let rigid = run(Default::default(), None);
    assert!(
        rigid.spectral_resonance.is_none(),
        "{:?}",
        rigid.spectral_resonance
    );
    // corrected by the right mode: no warning; by the beam's 1370 Hz mode: the mismatch is
    // named (its |H| peaks at f_n·sqrt(1 − 2ζ²) = 1369 Hz)
    let right = run(
        mode_chain(900.0, 0.03),
        Some(Correction {
            chain: mode_chain(900.0, 0.03),
            source: "900 Hz".into(),
            floor: 0.1,
        }),
    );
    assert!(right.warnings.is_empty(), "{:?}", right.warnings);
    let wrong = run(
        mode_chain(900.0, 0.03),
        Some(Correction {
            chain: mode_chain(1370.0, 0.03),
            source: "beam mode".into(),
            floor: 0.1,
        }),
    );
    assert!(
        wrong
            .warnings
            .iter()
            .any(|w| w.contains("has its resonance at 1369 Hz")),
        "{:?}",
        wrong.warnings
    );
}
