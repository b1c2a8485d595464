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
//!
//! `end_to_end` (issue 18: "the CLI end to end within 1.3× of the kernel") runs the SAME
//! workload — that of `benches/numpy_compare.py` at 100 revolutions (200 M evaluations; set
//! `RUNOUT_E2E_REVOLUTIONS` to change) — through the kernel alone (`ForceModel::simulate`, the
//! series in memory) and as the whole `runout simulate … --json -` process (start-up, parsing,
//! simulation, per-tooth peaks, JSON), in the same run, and prints the ratio of the medians.
//! The process is `target/release/runout` (or `$RUNOUT_BIN`); build it first with
//! `cargo build --release -p runout-cli` (without it the process half is skipped).

use criterion::{criterion_group, criterion_main, Criterion, Throughput};
use runout_core::*;
use std::cell::RefCell;
use std::path::PathBuf;
use std::time::{Duration, Instant};

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

/// The `runout simulate` arguments of the [`numpy_case`] workload (as `benches/numpy_compare.py`).
fn numpy_case_args(revolutions: f64) -> Vec<String> {
    let a = [
        "simulate",
        "--teeth",
        "4",
        "--diameter-mm",
        "10",
        "--helix-deg",
        "30",
        "--rpm",
        "3240",
        "--fz-mm",
        "0.08",
        "--ap-mm",
        "1",
        "--ae-mm",
        "2",
        "--mode",
        "down",
        "--runout-um",
        "8",
        "--runout-angle-deg",
        "0",
        "--ktc",
        "1889.2",
        "--krc",
        "806.1",
        "--kac",
        "291",
        "--kte",
        "63.12",
        "--kre",
        "113.7",
        "--kae",
        "-3.1",
        "--step-deg",
        "0.036",
        "--disks",
        "50",
        "--chip-model",
        "arc",
        "--json",
        "-",
    ];
    let mut v: Vec<String> = a.iter().map(|s| s.to_string()).collect();
    v.extend(["--revolutions".into(), revolutions.to_string()]);
    v
}

fn median(v: &[f64]) -> f64 {
    let mut v = v.to_vec();
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

/// The kernel alone and the whole `runout simulate` process on the same workload, same run.
fn end_to_end(c: &mut Criterion) {
    let revolutions: f64 = std::env::var("RUNOUT_E2E_REVOLUTIONS")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(100.0);
    let (m, chip, _) = numpy_case();
    let s = Sampling::new(revolutions, 0.036, 50).unwrap();
    let evals = (s.samples() * s.disks * m.cutter.teeth()) as u64;
    let bin = std::env::var_os("RUNOUT_BIN")
        .map(PathBuf::from)
        .unwrap_or_else(|| {
            PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../target/release/runout")
        });
    let args = numpy_case_args(revolutions);
    let mut g = c.benchmark_group("end_to_end");
    g.throughput(Throughput::Elements(evals));
    g.sample_size(10);
    // per-iteration times of the measured samples (warm-up calls included: they are few)
    let times = [RefCell::new(Vec::new()), RefCell::new(Vec::new())];
    g.bench_function("kernel", |b| {
        b.iter_custom(|iters| {
            let t0 = Instant::now();
            for _ in 0..iters {
                std::hint::black_box(m.simulate(&chip, &s));
            }
            let d = t0.elapsed();
            times[0].borrow_mut().push(d.as_secs_f64() / iters as f64);
            d
        })
    });
    let have_bin = bin.exists();
    if have_bin {
        g.bench_function("process", |b| {
            b.iter_custom(|iters| {
                let mut d = Duration::ZERO;
                for _ in 0..iters {
                    let t0 = Instant::now();
                    let out = std::process::Command::new(&bin)
                        .args(&args)
                        .output()
                        .expect("run runout");
                    d += t0.elapsed();
                    assert!(out.status.success(), "runout simulate failed: {out:?}");
                }
                times[1].borrow_mut().push(d.as_secs_f64() / iters as f64);
                d
            })
        });
    } else {
        eprintln!(
            "end_to_end/process skipped: {} not found (cargo build --release -p runout-cli)",
            bin.display()
        );
    }
    g.finish();
    if times[0].borrow().is_empty() {
        return; // filtered out
    }
    let k = median(&times[0].borrow());
    let e = evals as f64;
    eprintln!(
        "end_to_end: {:.0} M evaluations; kernel {:.3} s = {:.0} M evaluations/s",
        e / 1e6,
        k,
        e / k / 1e6
    );
    if have_bin && !times[1].borrow().is_empty() {
        let p = median(&times[1].borrow());
        eprintln!(
            "end_to_end: runout simulate process {:.3} s = {:.0} M evaluations/s; process / kernel = {:.2}× (target ≤ 1.3×)",
            p,
            e / p / 1e6,
            p / k
        );
    }
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

criterion_group!(benches, end_to_end, bench);
criterion_main!(benches);
