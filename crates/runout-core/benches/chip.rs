//! IUCT model throughput (points/s, one thread): exact (Newton, methods.md eq. 2.2–2.3; the
//! lockstep solver and its scalar baseline `exact::reference`, bit-identical values) vs
//! equivalent (eq. 2.8; bulk Hermite look-back of `chip::lookback`, and the direct per-point
//! evaluation) vs arc (eq. 2.5), on the general 3-D kinematics and on the 3-axis trait path used
//! by the force simulation. Cases: R 5, K 4, helix 30°, f_z 0.1, ρ 10 µm (methods.md
//! §2.5) in straight feed and with a 60°/s swing about y.
//!
//! Two measurements: criterion's wall time, and a final summary with the thread's CPU time read
//! from `/proc/thread-self/schedstat` (Linux; tick resolution, hence ≥ 200 ms windows, best of
//! 5) — the "per core" figure, robust to other processes sharing the cores. The summary prints
//! points/s of every model, the speed ratios and a libm `sin_cos` baseline, all from this run.

use criterion::measurement::{Measurement, WallTime};
use criterion::{BenchmarkGroup, Criterion, Throughput};
use runout_core::chip::compare::{
    arc_values, equivalent_values, equivalent_values_direct, exact_values, exact_values_reference,
    sample_grid, Motion, SamplePoint,
};
use runout_core::chip::kinematics::small_sin_cos;
use runout_core::chip::*;
use runout_core::{ArcChip, ChipAtHeight, ChipThickness, Cutter, Runout};
use std::hint::black_box;
use std::time::Instant;

/// CPU time of the calling thread (ns), or wall time when schedstat is unavailable.
fn thread_cpu_ns() -> u64 {
    std::fs::read_to_string("/proc/thread-self/schedstat")
        .ok()
        .and_then(|s| s.split_whitespace().next()?.parse().ok())
        .unwrap_or_else(|| {
            use std::sync::OnceLock;
            static T0: OnceLock<Instant> = OnceLock::new();
            T0.get_or_init(Instant::now).elapsed().as_nanos() as u64
        })
}

fn kin(motion: Motion) -> ToolKinematics<Motion> {
    let cutter = Cutter::flat(10.0, 4, 30.0f64.to_radians()).unwrap();
    let runout = Runout::new(0.010, 40f64.to_radians()).unwrap();
    ToolKinematics::new(
        &cutter,
        &runout,
        6000.0,
        0.0,
        SpindleSense::CounterClockwise,
        motion,
    )
    .unwrap()
}

fn straight() -> Motion {
    Motion::Straight(StraightFeed {
        p0: Vec3::zeros(),
        v: Vec3::new(40.0, 0.0, 0.0),
        u: Vec3::z(),
        e1: Vec3::x(),
    })
}

fn swing() -> Motion {
    Motion::Swing(
        ConstantSwing::new(
            Vec3::new(40.0, 0.0, 0.0),
            Vec3::y(),
            60f64.to_radians(),
            0.0,
        )
        .unwrap(),
    )
}

/// A flank-milling-like CL path: a point every 1 mm along x (0.4 mm of feed per revolution, so
/// 40 % of the look-back windows span a junction), the axis leaning 0.5° more per point about
/// alternating directions.
fn cl_path() -> Motion {
    let pts: Vec<ClPoint> = (0..40)
        .map(|n| {
            let a = (0.5 * n as f64).to_radians();
            let b = if n % 2 == 0 { 0.0 } else { 0.3f64.to_radians() };
            ClPoint {
                p: Vec3::new(n as f64 - 10.0, 0.02 * (n as f64).powi(2), 0.0),
                u: Vec3::new(a.sin(), b.sin(), a.cos() * b.cos()).normalize(),
                feed: 40.0,
            }
        })
        .collect();
    Motion::Path(ClPath::new(&pts).unwrap())
}

fn points() -> Vec<SamplePoint> {
    // 25 revolutions from t = 0.01 s: covers 10 mm of the CL path (10 junctions)
    sample_grid(4, &[0.0, 5.0, 10.0], 0.01, 0.25, 360)
}

fn general<T: Measurement>(c: &mut Criterion<T>, name: &str, kin: &ToolKinematics<Motion>) {
    let pts = points();
    let mut g = c.benchmark_group(name);
    g.throughput(Throughput::Elements(pts.len() as u64));
    let params = EquivalentParams::default();
    g.bench_function("exact", |b| b.iter(|| exact_values(kin, black_box(&pts))));
    g.bench_function("exact_reference", |b| {
        b.iter(|| exact_values_reference(kin, black_box(&pts)))
    });
    g.bench_function("equivalent", |b| {
        b.iter(|| equivalent_values(kin, black_box(&pts), &params))
    });
    g.bench_function("equivalent_direct", |b| {
        b.iter(|| equivalent_values_direct(kin, black_box(&pts), &params))
    });
    g.bench_function("arc", |b| b.iter(|| arc_values(kin, black_box(&pts))));
    g.finish();
}

fn phis() -> Vec<(f64, f64, f64)> {
    (0..1080)
        .map(|q| {
            let p = (q as f64 / 6.0).to_radians();
            (p, p.sin(), p.cos())
        })
        .collect()
}

fn trait_sum<C: ChipThickness>(model: &C, phis: &[(f64, f64, f64)]) -> f64 {
    let ev = model.at_height(5.0);
    let mut s = 0.0;
    for tooth in 0..4 {
        for &(phi, sn, cs) in phis {
            s += ev.thickness(tooth, black_box(phi), sn, cs);
        }
    }
    s
}

fn trait_bench<T: Measurement, C: ChipThickness>(g: &mut BenchmarkGroup<'_, T>, model: &C) {
    let p = phis();
    g.bench_function(model.name(), |b| b.iter(|| trait_sum(model, &p)));
}

fn trait_models() -> (ExactChip, EquivalentChip, ArcChip) {
    let cutter = Cutter::flat(10.0, 4, 30.0f64.to_radians()).unwrap();
    let runout = Runout::new(0.010, 40f64.to_radians()).unwrap();
    (
        ExactChip::new(&cutter, &runout, 0.1).unwrap(),
        EquivalentChip::new(&cutter, &runout, 0.1, EquivalentParams::default()).unwrap(),
        ArcChip::new(&cutter, &runout, 0.1).unwrap(),
    )
}

fn all<T: Measurement>(c: &mut Criterion<T>, tag: &str) {
    general(c, &format!("chip_3axis_{tag}"), &kin(straight()));
    general(c, &format!("chip_5axis_swing_{tag}"), &kin(swing()));
    general(c, &format!("chip_5axis_cl_path_{tag}"), &kin(cl_path()));
    let (e, q, a) = trait_models();
    let mut g = c.benchmark_group(format!("chip_trait_3axis_{tag}"));
    g.throughput(Throughput::Elements(4 * phis().len() as u64));
    trait_bench(&mut g, &e);
    trait_bench(&mut g, &q);
    trait_bench(&mut g, &a);
    g.finish();
}

/// Best-of-5 CPU-time throughput (points/s) of `f` evaluating `n` points per call.
fn rate(n: usize, mut f: impl FnMut() -> f64) -> f64 {
    let mut best = f64::INFINITY;
    for _ in 0..5 {
        let t0 = thread_cpu_ns();
        let mut reps = 0;
        while thread_cpu_ns() - t0 < 200_000_000 {
            black_box(f());
            reps += 1;
        }
        best = best.min((thread_cpu_ns() - t0) as f64 / reps as f64);
    }
    n as f64 / (best * 1e-9)
}

fn summary() {
    println!("\n== IUCT throughput summary (thread CPU time, best of 5, points/s) ==");
    let xs: Vec<f64> = (0..4096).map(|q| q as f64 * 0.37).collect();
    let sc = rate(xs.len(), || {
        xs.iter().map(|x| black_box(*x).sin_cos().0).sum()
    });
    let small: Vec<f64> = (0..4096).map(|q| (q as f64 - 2048.0) * 1e-4).collect();
    let ss = rate(small.len(), || {
        small.iter().map(|x| small_sin_cos(black_box(*x)).0).sum()
    });
    println!(
        "  machine baseline: libm sin_cos {:.1} ns/call; small_sin_cos (|x| ≤ 0.2) {:.1} ns/call",
        1e9 / sc,
        1e9 / ss
    );
    let pts = points();
    let params = EquivalentParams::default();
    for (name, k) in [
        ("3-axis", kin(straight())),
        ("5-axis swing", kin(swing())),
        ("5-axis CL path", kin(cl_path())),
    ] {
        let ex = rate(pts.len(), || exact_values(&k, &pts).iter().sum());
        let ex_ref = rate(pts.len(), || exact_values_reference(&k, &pts).iter().sum());
        let eq = rate(pts.len(), || {
            equivalent_values(&k, &pts, &params).iter().sum()
        });
        let dir = rate(pts.len(), || {
            equivalent_values_direct(&k, &pts, &params).iter().sum()
        });
        let ar = rate(pts.len(), || arc_values(&k, &pts).iter().sum());
        println!(
            "{name:>14} general: exact {:.3e} (scalar reference {:.3e}: {:.2}×)",
            ex,
            ex_ref,
            ex / ex_ref
        );
        println!(
            "{name:>14} general: exact {:.3e}  equivalent {:.3e} ({:.1}× exact; direct per point {:.3e}, {:.1}×)  arc {:.3e} ({:.1}× exact)",
            ex, eq, eq / ex, dir, dir / ex, ar, ar / ex
        );
    }
    let (e, q, a) = trait_models();
    let p = phis();
    let n = 4 * p.len();
    let ex = rate(n, || trait_sum(&e, &p));
    let eq = rate(n, || trait_sum(&q, &p));
    let ar = rate(n, || trait_sum(&a, &p));
    println!(
        "  3-axis trait:  exact {:.3e}  equivalent {:.3e} ({:.1}× exact)  arc {:.3e} ({:.1}× exact)",
        ex, eq, eq / ex, ar, ar / ex
    );
}

fn main() {
    let mut wall: Criterion<WallTime> = Criterion::default().configure_from_args();
    all(&mut wall, "wall");
    summary();
    wall.final_summary();
}
