//! Round trips through a resonant measuring chain (issue 11 acceptance): a 2-flute Ø20 end mill,
//! helix 40°, slot a_p 4 mm, 7500 rpm, 12 kHz, five feeds, ρ 10 µm, seen through a dynamometer
//! mode at 1100 Hz with ζ 0.03 on x and y (harmonic 8.8 of the spindle frequency, among the
//! tooth-passing harmonics); and K = 4, down milling, a mode at 2 kHz.
//!
//! The "measurement" is made as a real one is: the cut force is simulated 8× oversampled, passed
//! through the mode in the time domain (exact first-order-hold integration of the mode's ODE,
//! not the fit's frequency-domain formula), decimated to 12 kHz, and then noise is added: white
//! (2 % of each component's peak, the level) plus coloured AR(1) noise (φ = 0.9, 0.5 %:
//! its power at the spindle frequency is ≈ 14× that of white noise of the same σ), over 20
//! revolutions after 5 revolutions of settling; then averaged synchronously.
//!
//! Tolerances (the issue's): ρ ±0.5 µm, λ ±5°, K_tc, K_rc, K_te, K_re ±3 %, mode frequency ±2 %,
//! R² ≥ 0.98. The first-order hold's sinc²(πf/f_s) at the oversampled rate is < 0.3 % up to the
//! 20th harmonic, well inside them.

use rand::{rngs::StdRng, SeedableRng};
use rand_distr::{Distribution, Normal};
use runout_core::chain::{AxisChain, Complex64, FrfCurve, MeasuringChain, SensorMode};
use runout_core::identify::*;
use runout_core::*;

const OVERSAMPLE: usize = 8;

#[derive(Clone, Copy)]
struct Setup {
    teeth: usize,
    diameter: f64,
    helix_deg: f64,
    rpm: f64,
    sample_rate: f64,
    ap: f64,
    ae: f64,
    mode: MillingMode,
    rho_um: f64,
    lambda_deg: f64,
    kc: [f64; 6],
    sensor: SensorMode,
}

fn two_flute() -> Setup {
    Setup {
        teeth: 2,
        diameter: 20.0,
        helix_deg: 40.0,
        rpm: 7500.0,
        sample_rate: 12_000.0,
        ap: 4.0,
        ae: 20.0,
        mode: MillingMode::Slot,
        rho_um: 10.0,
        lambda_deg: 137.0,
        kc: [2100.0, 750.0, 0.0, 25.0, 35.0, 0.0],
        sensor: SensorMode::new(1100.0, 0.03, 1.0).unwrap(),
    }
}

fn four_flute() -> Setup {
    Setup {
        teeth: 4,
        diameter: 12.0,
        helix_deg: 30.0,
        rpm: 6000.0,
        sample_rate: 12_000.0,
        ap: 3.0,
        ae: 4.0,
        mode: MillingMode::Down,
        rho_um: 10.0,
        lambda_deg: -61.0,
        kc: [1900.0, 800.0, 0.0, 30.0, 40.0, 0.0],
        sensor: SensorMode::new(2000.0, 0.03, 1.0).unwrap(),
    }
}

const FEEDS: [f64; 5] = [0.04, 0.06, 0.08, 0.10, 0.12];

fn cutter_cut(s: &Setup, fz: f64) -> (Cutter, Cut) {
    let cutter = Cutter::flat(s.diameter, s.teeth, s.helix_deg.to_radians()).unwrap();
    let cut = Cut::new(s.rpm, fz, s.ap)
        .unwrap()
        .radial(s.ae, s.mode, &cutter)
        .unwrap();
    (cutter, cut)
}

fn samples_per_rev(s: &Setup) -> usize {
    (s.sample_rate * 60.0 / s.rpm).round() as usize
}

/// One recording through `chain` (per axis), averaged; `seed` for the noise.
fn recording(s: &Setup, fz: f64, chain: &MeasuringChain, seed: u64) -> WaveformCase {
    let (cutter, cut) = cutter_cut(s, fz);
    let runout = Runout::new(s.rho_um * 1e-3, s.lambda_deg.to_radians()).unwrap();
    let chip = ArcChip::new(&cutter, &runout, fz).unwrap();
    let model = ForceModel {
        cutter: cutter.clone(),
        runout,
        cut,
        coefficients: CuttingCoefficients::from_array(s.kc),
    };
    let n = samples_per_rev(s);
    let lag_deg = (s.ap * s.helix_deg.to_radians().tan() / (s.diameter / 2.0)).to_degrees();
    let disks = (lag_deg / 0.05).ceil().max(1.0) as usize;
    let settle = 5;
    let revs = 20;
    let step = 360.0 / (n * OVERSAMPLE) as f64;
    let series = model.simulate(
        &chip,
        &Sampling::new((settle + revs) as f64, step, disks).unwrap(),
    );
    let fs_fine = s.sample_rate * OVERSAMPLE as f64;
    let mut rng = StdRng::seed_from_u64(seed);
    let white = Normal::new(0.0, 1.0).unwrap();
    let mut channel = |v: &[f64], axis: FrameAxis| -> Vec<f64> {
        let filtered = chain.axis(axis).filter(fs_fine, v);
        let kept: Vec<f64> = filtered
            .iter()
            .step_by(OVERSAMPLE)
            .skip(settle * n)
            .take(revs * n)
            .copied()
            .collect();
        let peak = kept.iter().fold(0.0f64, |m, x| m.max(x.abs()));
        let sigma = 0.02 * peak;
        let mut ar = 0.0;
        kept.iter()
            .map(|x| {
                ar = 0.9 * ar + (1.0f64 - 0.81).sqrt() * white.sample(&mut rng);
                x + sigma * white.sample(&mut rng) + 0.25 * sigma * ar
            })
            .collect()
    };
    let fx = channel(&series.fx, FrameAxis::X);
    let fy = channel(&series.fy, FrameAxis::Y);
    WaveformCase {
        cutter,
        cut,
        waveform: AveragedWaveform::average(0.0, n, &[(FrameAxis::X, &fx), (FrameAxis::Y, &fy)])
            .unwrap(),
    }
}

fn xy_mode(m: SensorMode) -> MeasuringChain {
    MeasuringChain {
        x: AxisChain::Modes(vec![m]),
        y: AxisChain::Modes(vec![m]),
        z: AxisChain::Rigid,
    }
}

fn chain_options(s: &Setup, model: ChainModel, free_angle: bool) -> FullSignalOptions {
    FullSignalOptions {
        chain: Some(ChainOptions {
            model,
            spindle_hz: vec![s.rpm / 60.0; FEEDS.len()],
            samples_per_rev: vec![None; FEEDS.len()],
            free_start_angle: vec![free_angle; FEEDS.len()],
        }),
        ..FullSignalOptions::default()
    }
}

fn angle_error_deg(a: f64, b_deg: f64) -> f64 {
    (runout_core::angle::wrap_pi(a - b_deg.to_radians())).to_degrees()
}

/// ρ ±0.5 µm, λ ±5°, K_tc, K_rc, K_te, K_re ±3 %.
fn assert_recovered(s: &Setup, fit: &FullSignalFit, what: &str) {
    let rho = fit.offset.value * 1e3;
    let dl = angle_error_deg(fit.angle.value, s.lambda_deg);
    assert!(
        (rho - s.rho_um).abs() <= 0.5,
        "{what}: ρ {rho:.3} µm vs {}",
        s.rho_um
    );
    assert!(dl.abs() <= 5.0, "{what}: λ off by {dl:.2}°");
    for i in [0, 1, 3, 4] {
        let rel = fit.coefficients[i] / s.kc[i] - 1.0;
        assert!(
            rel.abs() <= 0.03,
            "{what}: coefficient {i}: {} vs {} ({:+.2} %)",
            fit.coefficients[i],
            s.kc[i],
            100.0 * rel
        );
    }
}

fn resonant_set(s: &Setup) -> Vec<WaveformCase> {
    FEEDS
        .iter()
        .enumerate()
        .map(|(i, &fz)| recording(s, fz, &xy_mode(s.sensor), 11 + i as u64))
        .collect()
}

fn fitted_modes() -> ChainModel {
    ChainModel::FitModes {
        axes: vec![(FrameAxis::X, None), (FrameAxis::Y, None)],
        fit_gain: false,
    }
}

fn check_fitted_modes(s: &Setup) {
    let cases = resonant_set(s);
    // the rigid fit of the same data is poor (the failure mode)
    let rigid = full_signal_fit(&cases, &FullSignalOptions::default()).unwrap();
    let fit = full_signal_fit(&cases, &chain_options(s, fitted_modes(), true)).unwrap();
    let chain = fit.chain.as_ref().unwrap();
    eprintln!(
        "K = {}: rigid R² {:.3}, ρ {:.2} µm; fitted modes R² {:.4}, ρ {:.3} ± {:.3} µm, λ {:.2}°, modes {:?}",
        s.teeth,
        rigid.r_squared,
        rigid.offset.value * 1e3,
        fit.r_squared,
        fit.offset.value * 1e3,
        fit.offset.se.unwrap() * 1e3,
        fit.angle.value.to_degrees(),
        chain
            .modes
            .iter()
            .map(|m| (m.frequency_hz.value, m.damping.value, m.gain.value))
            .collect::<Vec<_>>()
    );
    // the rigid fit of the same data misses the acceptance on at least one count
    let rigid_fails = rigid.r_squared < 0.98
        || (rigid.offset.value * 1e3 - s.rho_um).abs() > 0.5
        || angle_error_deg(rigid.angle.value, s.lambda_deg).abs() > 5.0
        || [0, 1, 3, 4]
            .iter()
            .any(|&i| (rigid.coefficients[i] / s.kc[i] - 1.0).abs() > 0.03);
    assert!(rigid_fails, "the rigid fit should fail on resonant data");
    assert!(fit.r_squared >= 0.98, "R² {}", fit.r_squared);
    assert!(chain.rigid_r_squared < fit.r_squared);
    assert_recovered(s, &fit, "fitted modes");
    for m in &chain.modes {
        let rel = m.frequency_hz.value / s.sensor.frequency_hz - 1.0;
        assert!(
            rel.abs() <= 0.02,
            "mode {:?}: {:+.2} %",
            m.axis,
            100.0 * rel
        );
    }
    for d in &chain.start_angle_shift {
        assert!(d.value.to_degrees().abs() < 1.0, "angle shift {d:?}");
    }
}

#[test]
fn two_flutes_through_a_1100_hz_mode_fitted_modes() {
    check_fitted_modes(&two_flute());
}

#[test]
fn four_flutes_down_milling_through_a_2_khz_mode_fitted_modes() {
    check_fitted_modes(&four_flute());
}

/// The mode's FRF, as an impact-test export would give it (10 Hz steps to 5 kHz).
fn measured_frf(m: SensorMode) -> MeasuringChain {
    let freq: Vec<f64> = (0..=500).map(|i| i as f64 * 10.0).collect();
    let vals: Vec<Complex64> = freq.iter().map(|&f| m.unit_response(f)).collect();
    let c = FrfCurve::new("frf", freq, vals).unwrap();
    MeasuringChain {
        x: AxisChain::Frf(c.clone()),
        y: AxisChain::Frf(c),
        z: AxisChain::Rigid,
    }
}

#[test]
fn two_flutes_through_a_1100_hz_mode_measured_frf() {
    let s = two_flute();
    let cases = resonant_set(&s);
    let fit = full_signal_fit(
        &cases,
        &chain_options(&s, ChainModel::Known(measured_frf(s.sensor)), false),
    )
    .unwrap();
    assert!(fit.r_squared >= 0.98, "R² {}", fit.r_squared);
    assert_recovered(&s, &fit, "measured FRF");
    // the FRF ends at 5 kHz = harmonic 40
    assert_eq!(fit.chain.as_ref().unwrap().max_harmonic, vec![40; 5]);
}

/// Band-limited rigid fit of `s`'s resonant set on harmonics 0..=kmax; also returns
/// max(|H| − 1) over the band.
fn band_fit(s: &Setup, kmax: usize) -> (FullSignalFit, f64) {
    let cases = resonant_set(s);
    let fit = full_signal_fit(
        &cases,
        &chain_options(s, ChainModel::BandLimit { max_harmonic: kmax }, true),
    )
    .unwrap();
    let f_rev = s.rpm / 60.0;
    let h_max = (1..=kmax)
        .map(|k| s.sensor.unit_response(k as f64 * f_rev).norm() - 1.0)
        .fold(0.0, f64::max);
    eprintln!(
        "K = {} band 0..{kmax}: R² {:.4}, ρ {:.3} ± {:.3} µm, λ {:.2}°, kc {:?}, max |H| − 1 {:.3}",
        s.teeth,
        fit.r_squared,
        fit.offset.value * 1e3,
        fit.offset.se.unwrap() * 1e3,
        fit.angle.value.to_degrees(),
        fit.coefficients,
        h_max
    );
    assert_eq!(fit.chain.as_ref().unwrap().max_harmonic, vec![kmax; 5]);
    (fit, h_max)
}

/// The band-limited rigid fit (the cheap fallback) where the band holds enough harmonics below
/// the mode: K = 4, 2 kHz mode at 6000 rpm, harmonics 0..5 (≤ 500 Hz, |H| − 1 ≤ 6.7 %). The
/// chain still acts inside the band, so the coefficients carry up to that bias: asserted within
/// (max |H| − 1 in the band) + 3 %; the runout (a ratio of harmonics, where it largely cancels)
/// at the issue's ±0.5 µm and ±5°.
#[test]
fn four_flutes_through_a_2_khz_mode_band_limit() {
    let s = four_flute();
    let (fit, h_max) = band_fit(&s, 5);
    assert!(fit.r_squared >= 0.98, "R² {}", fit.r_squared);
    let rho = fit.offset.value * 1e3;
    assert!((rho - s.rho_um).abs() <= 0.5, "ρ {rho}");
    assert!(angle_error_deg(fit.angle.value, s.lambda_deg).abs() <= 5.0);
    for i in [0, 1, 3, 4] {
        let rel = (fit.coefficients[i] / s.kc[i] - 1.0).abs();
        assert!(rel <= h_max + 0.03, "coefficient {i}: {rel}");
    }
}

/// Where the band below the mode is too narrow — 2 flutes, 1100 Hz mode at 7500 rpm: harmonics
/// 0..4 already reach |H| − 1 = 26 % — the band limit cannot place the runout to ±0.5 µm; the
/// fit says so through its SE (> 25 % of ρ: reported not identified) instead of a confident wrong
/// value, and the truth stays within 2 SE.
#[test]
fn two_flutes_band_limit_below_a_low_mode_reports_its_uncertainty() {
    let s = two_flute();
    let (fit, _) = band_fit(&s, 4);
    let rho = fit.offset.value * 1e3;
    let se = fit.offset.se.unwrap() * 1e3;
    assert!(
        se > 0.25 * rho,
        "SE {se} µm should flag ρ {rho} µm as not identified"
    );
    assert!((rho - s.rho_um).abs() <= 2.0 * se, "ρ {rho} ± {se}");
}

/// Issue 11 acceptance: the runout is consistent across five feeds when fitted per recording
/// with the joint fit's coefficients and chain held (a single recording cannot separate shear
/// from edge coefficients): spread of ρ ≤ 10 %, of λ ≤ 5°. A single recording's information on
/// the runout scales with ρ/f_z (the noise is a fraction of the force, which grows with f_z),
/// and with two teeth the offset across the tooth line is seen only through the helix lag: at
/// f_z 0.10–0.12 mm one recording gives SE(λ) ≈ 100° (measured), so the per-recording check uses
/// five feeds from 0.02 to 0.06 mm (SE(λ) 2–10°), where it is meaningful.
#[test]
fn per_recording_runout_is_consistent_across_feeds() {
    let s = two_flute();
    let cases: Vec<WaveformCase> = [0.02, 0.03, 0.04, 0.05, 0.06]
        .iter()
        .enumerate()
        .map(|(i, &fz)| recording(&s, fz, &xy_mode(s.sensor), 31 + i as u64))
        .collect();
    let joint = full_signal_fit(&cases, &chain_options(&s, fitted_modes(), false)).unwrap();
    let modes = &joint.chain.as_ref().unwrap().modes;
    let mode_of = |a: FrameAxis| {
        modes
            .iter()
            .find(|m| m.axis == a)
            .map_or(AxisChain::Rigid, |m| {
                AxisChain::Modes(vec![SensorMode::new(
                    m.frequency_hz.value,
                    m.damping.value,
                    m.gain.value,
                )
                .unwrap()])
            })
    };
    let chain = MeasuringChain {
        x: mode_of(FrameAxis::X),
        y: mode_of(FrameAxis::Y),
        z: AxisChain::Rigid,
    };
    let mut rho = Vec::new();
    let mut lam = Vec::new();
    for case in &cases {
        let opts = FullSignalOptions {
            chain: Some(ChainOptions {
                model: ChainModel::Known(chain.clone()),
                spindle_hz: vec![s.rpm / 60.0],
                samples_per_rev: vec![None],
                free_start_angle: vec![false],
            }),
            initial_runout: Some([joint.vector[0].value, joint.vector[1].value]),
            fixed_coefficients: Some(joint.coefficients),
            ..FullSignalOptions::default()
        };
        let fit = full_signal_fit(std::slice::from_ref(case), &opts).unwrap();
        eprintln!(
            "fz {}: ρ {:.3} ± {:.3} µm, λ {:.2} ± {:.2}°",
            case.cut.fz(),
            fit.offset.value * 1e3,
            fit.offset.se.unwrap() * 1e3,
            fit.angle.value.to_degrees(),
            fit.angle.se.unwrap().to_degrees()
        );
        rho.push(fit.offset.value * 1e3);
        lam.push(fit.angle.value.to_degrees());
    }
    let mean = rho.iter().sum::<f64>() / rho.len() as f64;
    let spread =
        rho.iter().cloned().fold(f64::MIN, f64::max) - rho.iter().cloned().fold(f64::MAX, f64::min);
    let lspread =
        lam.iter().cloned().fold(f64::MIN, f64::max) - lam.iter().cloned().fold(f64::MAX, f64::min);
    assert!(
        spread / mean <= 0.10,
        "ρ spread {:.1} %",
        100.0 * spread / mean
    );
    assert!(lspread <= 5.0, "λ spread {lspread:.2}°");
}

/// The mode scan evaluates its grid in parallel (rayon): the fit must be the same, bit for bit,
/// on one thread and on several (every float compared through its shortest round-trip `Debug`
/// form, so equal strings mean equal bits). One axial disk: the model's disk sums are split by
/// thread count (`model` module), which is why the CLI snapshots pin one thread; with a single
/// disk nothing else depends on it, so a difference here could only come from the scan.
#[test]
fn fitted_modes_fit_is_identical_at_any_thread_count() {
    let s = two_flute();
    let cases = resonant_set(&s);
    let options = FullSignalOptions {
        disks: Some(1),
        ..chain_options(&s, fitted_modes(), true)
    };
    let run = |threads: usize| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap()
            .install(|| format!("{:?}", full_signal_fit(&cases, &options).unwrap()))
    };
    let one = run(1);
    assert_eq!(one, run(2), "1 vs 2 threads");
    assert_eq!(one, run(3), "1 vs 3 threads");
}

/// [`on_pool`] runs a fit as one task on the thread pool with the grouping of its caller: the
/// same fit, bit for bit, as the fit called from this thread, outside the pool (issue 18: the
/// CLI runs its fits this way). The default number of disks: the model groups their sums by
/// where it is called from, which is what `on_pool` must carry over.
#[test]
fn a_fit_on_the_pool_equals_the_fit_called_from_outside() {
    let s = two_flute();
    let cases = resonant_set(&s);
    let options = chain_options(&s, fitted_modes(), true);
    let here = format!("{:?}", full_signal_fit(&cases, &options).unwrap());
    let pooled = on_pool(|| format!("{:?}", full_signal_fit(&cases, &options).unwrap()));
    assert_eq!(here, pooled);
}
