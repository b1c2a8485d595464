//! Force-simulation kernel throughput in tooth×disk×angle evaluations per second.
//!
//! Goal (foundation issue): ≥ 200 million evaluations/s on the 2-core machine. The serial run
//! (a one-thread rayon pool) in the same benchmark is the baseline for the parallel speed-up.
//!
//! Issue 12: `profile/flat` and `profile/ball` run the same cut (K 4, Ø10, 30° helix, a_p = R =
//! 5 mm, a_e 5 mm down milling, 50 disks, 0.1°) on one thread, a flat end mill (cylindrical
//! kernel) and a ball end mill (κ(z) kernel: lead angle, per-disk window and edge length); the
//! goal is ball ≥ flat / 1.5 in evaluations per second. `profile/flat_general` is the flat cutter
//! forced through the κ(z) kernel.
//!
//! Issue 18: every group also runs the kernel as it was before (`force::baseline`, the scalar
//! per-sample loop) in the same run, as `*_baseline`: the ratio of the two is the speed-up.
//! `numpy_workload` is the workload of `benches/numpy_compare.py` (K 4, Ø10, 30° helix, a_p 1,
//! a_e 2 mm down, 50 disks, 0.036°) over 10 revolutions (20 M evaluations); target ≥ 600 M
//! evaluations/s on 2 cores. `identify_sums` is the identification's basis sums with
//! derivatives (384 samples × 193 disks, ball end mill) against its old loop.

use criterion::{criterion_group, criterion_main, Criterion, Throughput};
use runout_core::*;

fn case() -> (ForceModel, ArcChip, Sampling) {
    case_with(RadiusProfile::Flat)
}

fn case_with(profile: RadiusProfile) -> (ForceModel, ArcChip, Sampling) {
    let cutter = Cutter::new(
        10.0,
        vec![std::f64::consts::TAU / 4.0; 4],
        30.0f64.to_radians(),
        f64::INFINITY,
        profile,
    )
    .unwrap();
    let runout = Runout::new(0.008, 0.5).unwrap();
    let cut = Cut::new(3240.0, 0.08, 5.0)
        .unwrap()
        .radial(5.0, MillingMode::Down, &cutter)
        .unwrap();
    let coef = CuttingCoefficients::new([1889.2, 806.1, 291.0], [63.12, 113.7, -3.1]).unwrap();
    let chip = ArcChip::new(&cutter, &runout, 0.08).unwrap();
    let sampling = Sampling::new(10.0, 0.1, 50).unwrap();
    (
        ForceModel {
            cutter,
            runout,
            cut,
            coefficients: coef,
        },
        chip,
        sampling,
    )
}

fn numpy_case() -> (ForceModel, ArcChip, Sampling) {
    let cutter = Cutter::flat(10.0, 4, 30f64.to_radians()).unwrap();
    let runout = Runout::new(0.008, 0.0).unwrap();
    let cut = Cut::new(3240.0, 0.08, 1.0)
        .unwrap()
        .radial(2.0, MillingMode::Down, &cutter)
        .unwrap();
    let coef = CuttingCoefficients::new([1889.2, 806.1, 291.0], [63.12, 113.7, -3.1]).unwrap();
    let chip = ArcChip::new(&cutter, &runout, 0.08).unwrap();
    let sampling = Sampling::new(10.0, 0.036, 50).unwrap();
    (
        ForceModel {
            cutter,
            runout,
            cut,
            coefficients: coef,
        },
        chip,
        sampling,
    )
}

fn bench(c: &mut Criterion) {
    let (m, chip, s) = numpy_case();
    let evals = (s.samples() * s.disks * m.cutter.teeth()) as u64;
    let mut g = c.benchmark_group("numpy_workload");
    g.throughput(Throughput::Elements(evals));
    g.sample_size(10);
    g.bench_function("parallel", |b| b.iter(|| m.simulate(&chip, &s)));
    g.bench_function("parallel_baseline", |b| {
        b.iter(|| force::baseline::simulate(&m, &chip, &s))
    });
    g.finish();

    let (m, chip, s) = case();
    let evals = (s.samples() * s.disks * m.cutter.teeth()) as u64;
    let mut g = c.benchmark_group("force_kernel");
    g.throughput(Throughput::Elements(evals));
    g.sample_size(20);
    g.bench_function("parallel", |b| b.iter(|| m.simulate(&chip, &s)));
    g.bench_function("parallel_baseline", |b| {
        b.iter(|| force::baseline::simulate(&m, &chip, &s))
    });
    let one = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .unwrap();
    g.bench_function("one_thread", |b| {
        b.iter(|| one.install(|| m.simulate(&chip, &s)))
    });
    g.bench_function("one_thread_baseline", |b| {
        b.iter(|| one.install(|| force::baseline::simulate(&m, &chip, &s)))
    });
    g.finish();

    let mut g = c.benchmark_group("profile");
    g.throughput(Throughput::Elements(evals));
    g.sample_size(20);
    let (ball, ball_chip, _) = case_with(RadiusProfile::Ball);
    g.bench_function("flat", |b| b.iter(|| one.install(|| m.simulate(&chip, &s))));
    g.bench_function("ball", |b| {
        b.iter(|| one.install(|| ball.simulate(&ball_chip, &s)))
    });
    g.bench_function("ball_baseline", |b| {
        b.iter(|| one.install(|| force::baseline::simulate(&ball, &ball_chip, &s)))
    });
    g.bench_function("flat_general", |b| {
        b.iter(|| one.install(|| m.simulate_general(&chip, &s)))
    });
    g.finish();

    // identification: basis sums with runout derivatives, ball end mill, 384 × 193 disks
    let rev = identify::RevolutionModel::new(&ball.cutter, &ball.cut, 0.0, 384, 193);
    let mut g = c.benchmark_group("identify_sums");
    g.throughput(Throughput::Elements((384 * 193 * 4) as u64));
    g.sample_size(20);
    g.bench_function("kernel", |b| {
        b.iter(|| rev.sums([0.007, 0.004], [0.0, 0.0], false))
    });
    g.bench_function("baseline", |b| {
        b.iter(|| rev.sums_baseline([0.007, 0.004], [0.0, 0.0], 2, false))
    });
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
