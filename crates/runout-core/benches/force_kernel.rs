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

fn bench(c: &mut Criterion) {
    let (m, chip, s) = case();
    let evals = (s.samples() * s.disks * m.cutter.teeth()) as u64;
    let mut g = c.benchmark_group("force_kernel");
    g.throughput(Throughput::Elements(evals));
    g.sample_size(20);
    g.bench_function("parallel", |b| b.iter(|| m.simulate(&chip, &s)));
    let one = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .unwrap();
    g.bench_function("one_thread", |b| {
        b.iter(|| one.install(|| m.simulate(&chip, &s)))
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
    g.bench_function("flat_general", |b| {
        b.iter(|| one.install(|| m.simulate_general(&chip, &s)))
    });
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
