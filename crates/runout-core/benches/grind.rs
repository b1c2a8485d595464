//! Grinding compensation throughput: ε interpolation + w′ = w + ε·N for 100 000 edge points
//! (4 helical flutes, M 5 × C 16 probe grid). Baseline in the same run: the bare first-order
//! radial projection e(u)·n over the same points (one sin/cos pair per point), the minimum any
//! scheme must pay.

use criterion::{criterion_group, criterion_main, Criterion, Throughput};
use runout_core::grind::*;
use std::hint::black_box;

fn setup() -> (SimulatedBar, DeviationMap, EdgeLine) {
    let bar = SimulatedBar::new(3.0, [0.008, -0.004], [0.0003, 0.0005]).unwrap();
    let (u, a) = uniform_grid(2.0, 28.0, 5, 16).unwrap();
    let map = DeviationMap::new(&bar.probe(&u, &a, || 0.0).unwrap());
    let edge = EdgeLine::helical_flat(6.0, 4, 30.0, 0.0, 30.0, 25_000).unwrap();
    (bar, map, edge)
}

fn bench(c: &mut Criterion) {
    let (bar, map, edge) = setup();
    let n = edge.points.len() as u64;
    let mut g = c.benchmark_group("grind_100k_points");
    g.throughput(Throughput::Elements(n));
    g.bench_function("baseline_radial_projection", |b| {
        b.iter(|| {
            let s: f64 = edge
                .points
                .iter()
                .map(|p| {
                    let e = bar.axis_at(p.u);
                    e[0] * p.alpha.cos() + e[1] * p.alpha.sin()
                })
                .sum();
            black_box(s)
        })
    });
    for (name, scheme) in [
        ("first_harmonic", Scheme::FirstHarmonic),
        ("bilinear", Scheme::Bilinear),
    ] {
        let f = Interpolator::new(&map, scheme, RangePolicy::Clamp);
        g.bench_function(format!("interpolate_{name}"), |b| {
            b.iter(|| {
                let s: f64 = edge.points.iter().map(|p| f.eval(p.u, p.alpha).eps).sum();
                black_box(s)
            })
        });
        g.bench_function(format!("compensate_{name}"), |b| {
            b.iter(|| black_box(compensate(&f, &map.axis, &edge, None).unwrap()))
        });
    }
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
