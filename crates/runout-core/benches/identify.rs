//! Identification speed. Target (issue 3): full-signal identification of 20 averaged revolutions
//! < 0.5 s. Same run: the building blocks as baselines — one evaluation of the one-revolution
//! model, the frequency-domain estimate, the seed-003 sine fit, and simulating the recording.

use criterion::{criterion_group, criterion_main, Criterion};
use rand::{rngs::StdRng, SeedableRng};
use rand_distr::{Distribution, Normal};
use runout_core::identify::*;
use runout_core::*;

/// K 4, D 10, helix 30°, down-milling a_e 3, a_p 2, f_z 0.08, ρ 8 µm at 30°; 20 revolutions at
/// 1°, 2 % noise, averaged → one revolution of F_x, F_y, F_z (360 samples each).
fn case() -> (WaveformCase, ForceModel, ArcChip, Sampling) {
    let cutter = Cutter::flat(10.0, 4, 30.0).unwrap();
    let runout = Runout::new(0.008, 30f64.to_radians()).unwrap();
    let cut = Cut::new(3000.0, 0.08, 2.0)
        .unwrap()
        .radial(3.0, MillingMode::Down, &cutter)
        .unwrap();
    let coefficients =
        CuttingCoefficients::new([1889.2, 806.1, 291.0], [63.12, 113.7, -3.1]).unwrap();
    let model = ForceModel {
        cutter: cutter.clone(),
        runout,
        cut,
        coefficients,
    };
    let chip = ArcChip::new(&cutter, &runout, 0.08).unwrap();
    let sampling = Sampling::new(20.0, 1.0, 264).unwrap();
    let s = model.simulate(&chip, &sampling);
    let mut rng = StdRng::seed_from_u64(1);
    let mut noisy = |v: &[f64]| -> Vec<f64> {
        let sd = 0.02 * v.iter().fold(0.0f64, |m, x| m.max(x.abs()));
        let n = Normal::new(0.0, sd).unwrap();
        v.iter().map(|x| x + n.sample(&mut rng)).collect()
    };
    let (x, y, z) = (noisy(&s.fx), noisy(&s.fy), noisy(&s.fz));
    let waveform =
        AveragedWaveform::average(0.0, 360, &[(Axis::X, &x), (Axis::Y, &y), (Axis::Z, &z)])
            .unwrap();
    (
        WaveformCase {
            cutter,
            cut,
            waveform,
        },
        model,
        chip,
        sampling,
    )
}

fn bench(c: &mut Criterion) {
    let (case, model, chip, sampling) = case();
    let fit = full_signal_fit(std::slice::from_ref(&case), &FullSignalOptions::default()).unwrap();
    eprintln!(
        "full-signal fit: ρ {:.3} µm, λ {:.2}°, {} disks, {} evaluations",
        fit.offset.value * 1e3,
        fit.angle.value.to_degrees(),
        fit.disks,
        fit.evaluations
    );
    let mut g = c.benchmark_group("identify");
    g.sample_size(10);
    g.bench_function("full_signal_fit_20rev", |b| {
        b.iter(|| full_signal_fit(std::slice::from_ref(&case), &FullSignalOptions::default()))
    });
    let rev = RevolutionModel::new(&case.cutter, &case.cut, 0.0, 360, fit.disks);
    g.bench_function("model_evaluation_one_rev", |b| {
        b.iter(|| rev.sums([0.007, 0.004], [0.0, 0.0], false))
    });
    let kc = CuttingCoefficients::from_array(fit.coefficients);
    g.bench_function("frequency_estimate", |b| {
        b.iter(|| frequency_estimate(std::slice::from_ref(&case), &kc, fit.disks))
    });
    let peaks = ToothPeaks::new(vec![366.6, 307.9, 259.9, 326.6]).unwrap();
    let cond = PeakConditions::new(0.08, 0.927).unwrap();
    g.bench_function("sine_fit", |b| {
        b.iter(|| sine_fit(&peaks, &cond, SineHypothesis::Teeth))
    });
    g.bench_function("simulate_20rev_recording", |b| {
        b.iter(|| model.simulate(&chip, &sampling))
    });
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
