//! Signal-pipeline throughput: 10 minutes × 3 force channels at 50 kHz (30 M rows) fed in chunks
//! of 50,000 rows through the three passes (scan, phase tracking, synchronous average).
//!
//! Target (issue 3): parse + average + identify ≥ 100 MB/s of CSV ≈ 3–4 M rows/s end to end, so
//! the pipeline alone must run well above that. Baseline in the same run: three passes that only
//! sum the samples of the same chunks (the cost of touching the data three times).
//!
//! Memory is bounded by design, whatever the recording length (see `signal` module doc): the
//! stream is replayed from two 50,000-row buffers (air cut, cutting), so the benchmark itself holds
//! ≈ 2.4 MB of samples; the pipeline holds the Welch buffers (L = 4096 → 2·4096 + 16,384 +
//! 8,193 f64), ≤ 2¹⁵ envelope blocks, one revolution of samples and 4·M running statistics.

use criterion::{criterion_group, criterion_main, Criterion, Throughput};
use rand::{rngs::StdRng, SeedableRng};
use rand_distr::{Distribution, Normal};
use runout_core::signal::{
    analyse_replay, ChunkSink, PhaseTracker, SignalChunk, SignalConfig, SignalError, SpindleScan,
    SyncAverager,
};
use runout_core::*;

const FS: f64 = 50_000.0;
const RPM: f64 = 6000.0; // 500 samples per revolution: a 50,000-row chunk is 100 revolutions
const CHUNK: usize = 50_000;
const CHUNKS: usize = 600; // 600 × 50,000 rows = 30 M rows = 10 min at 50 kHz

struct Buffers {
    air: [Vec<f64>; 3],
    cut: [Vec<f64>; 3],
}

fn buffers() -> Buffers {
    let cutter = Cutter::flat(10.0, 3, 30.0f64.to_radians()).unwrap();
    let runout = Runout::new(0.010, 0.7).unwrap();
    let cut = Cut::new(RPM, 0.06, 2.0)
        .unwrap()
        .radial(3.0, MillingMode::Down, &cutter)
        .unwrap();
    let k = CuttingCoefficients::new([1889.2, 806.1, 291.0], [63.12, 113.7, -3.1]).unwrap();
    let chip = ArcChip::new(&cutter, &runout, 0.06).unwrap();
    let model = ForceModel {
        cutter: cutter.clone(),
        runout,
        cut,
        coefficients: k,
    };
    let step = 360.0 * RPM / 60.0 / FS;
    let s = model.simulate(&chip, &Sampling::new(100.0, step, 10).unwrap());
    let mut rng = StdRng::seed_from_u64(1);
    let noise = Normal::new(0.0, 5.0).unwrap();
    let mut mk = |v: &[f64], gain: f64| -> Vec<f64> {
        (0..CHUNK)
            .map(|i| gain * v[i % v.len()] + noise.sample(&mut rng))
            .collect()
    };
    Buffers {
        cut: [mk(&s.fx, 1.0), mk(&s.fy, 1.0), mk(&s.fz, 1.0)],
        air: [mk(&s.fx, 0.0), mk(&s.fy, 0.0), mk(&s.fz, 0.0)],
    }
}

/// Replay: 2 chunks of air cut, 596 of cutting, 2 of air cut.
fn replay<'b>(b: &'b Buffers) -> impl FnMut(&mut ChunkSink<'_>) -> Result<(), SignalError> + 'b {
    move |sink| {
        for i in 0..CHUNKS {
            let v = if !(2..CHUNKS - 2).contains(&i) {
                &b.air
            } else {
                &b.cut
            };
            sink(SignalChunk::xyz(&v[0], &v[1], &v[2]))?;
        }
        Ok(())
    }
}

fn bench(c: &mut Criterion) {
    let b = buffers();
    let cfg = SignalConfig::new(FS, 3, RPM).unwrap();
    // check once that the pipeline does its job on this stream
    let a = analyse_replay(&cfg, replay(&b)).unwrap();
    assert!((a.speed.rpm - RPM).abs() < 0.01, "{:?}", a.speed);
    assert!(a.average.revolutions > 59_000, "{}", a.average.revolutions);
    eprintln!(
        "pipeline check: {:.4} ± {:.4} rpm, section {:.3}–{:.3} s, {} revolutions averaged",
        a.speed.rpm,
        a.speed.rpm_se,
        a.scan.section.from_s,
        a.scan.section.to_s,
        a.average.revolutions
    );

    let mut g = c.benchmark_group("signal_10min_3ch_50kHz");
    g.throughput(Throughput::Elements((CHUNK * CHUNKS) as u64));
    g.sample_size(10);
    g.bench_function("pipeline_3_passes", |bench| {
        bench.iter(|| analyse_replay(&cfg, replay(&b)).unwrap())
    });
    g.bench_function("pass1_scan", |bench| {
        bench.iter(|| {
            let mut p = SpindleScan::new(&cfg).unwrap();
            replay(&b)(&mut |c| p.push(c)).unwrap();
            p.finish().unwrap()
        })
    });
    g.bench_function("pass2_phase_tracking", |bench| {
        bench.iter(|| {
            let mut p = PhaseTracker::new(&cfg, &a.scan).unwrap();
            replay(&b)(&mut |c| p.push(c)).unwrap();
            p.finish().unwrap()
        })
    });
    g.bench_function("pass3_sync_average", |bench| {
        bench.iter(|| {
            let mut p = SyncAverager::new(&cfg, &a.scan, &a.speed).unwrap();
            replay(&b)(&mut |c| p.push(c)).unwrap();
            p.finish().unwrap()
        })
    });
    g.bench_function("baseline_3_passes_sum_only", |bench| {
        bench.iter(|| {
            let mut total = 0.0;
            for _ in 0..3 {
                let mut f = replay(&b);
                f(&mut |c: SignalChunk| {
                    total += c.fx.iter().sum::<f64>()
                        + c.fy.iter().sum::<f64>()
                        + c.fz.map_or(0.0, |z| z.iter().sum());
                    Ok(())
                })
                .unwrap();
            }
            std::hint::black_box(total)
        })
    });
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
