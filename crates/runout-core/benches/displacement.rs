//! Raw-signal runout fit (issue 5): rotating circle R = 5 mm at 3240 rpm, offset 8 µm at 30°,
//! two distance sensors at 0° and 90°, 50 kHz, 1e6 samples, SNR 25 (power). Target ≤ 50 ms.
//!
//! Variants: once-per-revolution pulse, encoder channel, no reference (speed from the spectrum
//! and refined). Baseline in the same run: the textbook dense linear least squares (per-sample
//! sin/cos into an N×3 design matrix, nalgebra QR per channel) on the encoder angles.

use criterion::{criterion_group, criterion_main, Criterion};
use nalgebra::{DMatrix, DVector};
use rand::{rngs::StdRng, SeedableRng};
use rand_distr::{Distribution, Normal};
use runout_core::displacement::*;
use std::f64::consts::{PI, TAU};

struct Sim {
    a: Vec<f64>,
    b: Vec<f64>,
    pulse: Vec<f64>,
    encoder: Vec<f64>,
}

fn simulate() -> Sim {
    let (n, fs, rho, lambda) = (1_000_000, 50_000.0, 0.008, 30f64.to_radians());
    let w = 3240.0 / 60.0 * TAU;
    let sigma = rho / 2f64.sqrt() / 5.0;
    let mut rng = StdRng::seed_from_u64(1);
    let noise = Normal::new(0.0, sigma).unwrap();
    let mut s = Sim {
        a: vec![],
        b: vec![],
        pulse: vec![],
        encoder: vec![],
    };
    for i in 0..n {
        let phi = w * i as f64 / fs;
        s.a.push(1.0 - rho * (lambda + phi).cos() + noise.sample(&mut rng));
        s.b.push(1.0 - rho * (lambda + phi - PI / 2.0).cos() + noise.sample(&mut rng));
        s.pulse
            .push(if phi.rem_euclid(TAU) < 0.2 { 5.0 } else { 0.0 });
        s.encoder.push(phi.rem_euclid(TAU));
    }
    s
}

fn input<'a>(s: &'a Sim, reference: SpindleReference<'a>) -> SignalInput<'a> {
    SignalInput {
        sample_rate_hz: 50_000.0,
        channels: vec![
            SensorChannel {
                displacement_mm: &s.a,
                angle_rad: 0.0,
                sign: SensorSign::Distance,
            },
            SensorChannel {
                displacement_mm: &s.b,
                angle_rad: PI / 2.0,
                sign: SensorSign::Distance,
            },
        ],
        reference,
        surface_radius_mm: 5.0,
        beam: BeamGeometry::ideal(),
        reference_angle_rad: 0.0,
    }
}

/// Textbook baseline: dense N×3 design matrix and QR least squares per channel.
fn dense_baseline(s: &Sim) -> [f64; 2] {
    let n = s.encoder.len();
    let x = DMatrix::from_fn(n, 3, |i, c| match c {
        0 => 1.0,
        1 => s.encoder[i].cos(),
        _ => s.encoder[i].sin(),
    });
    let qr = x.qr();
    let (q, r) = (qr.q(), qr.r());
    let solve = |y: &[f64]| {
        let qtb = q.transpose() * DVector::from_column_slice(y);
        r.solve_upper_triangular(&qtb).unwrap()
    };
    let (fa, fb) = (solve(&s.a), solve(&s.b));
    // channel a at 0°: (a, b) = −(e_x, −e_y); average with channel b at 90°
    [(-fa[1] + fb[2]) / 2.0, (fa[2] + fb[1]) / 2.0]
}

fn bench(c: &mut Criterion) {
    let s = simulate();
    let mut g = c.benchmark_group("displacement_signal_1e6x2");
    g.sample_size(20);
    g.bench_function("pulse", |b| {
        b.iter(|| fit_signal(&input(&s, SpindleReference::Pulse(&s.pulse))).unwrap())
    });
    g.bench_function("encoder", |b| {
        b.iter(|| fit_signal(&input(&s, SpindleReference::Encoder(&s.encoder))).unwrap())
    });
    g.bench_function("estimated_speed", |b| {
        b.iter(|| {
            fit_signal(&input(
                &s,
                SpindleReference::Estimate {
                    rpm_min: 600.0,
                    rpm_max: 30_000.0,
                },
            ))
            .unwrap()
        })
    });
    g.sample_size(10);
    g.bench_function("baseline_dense_qr", |b| b.iter(|| dense_baseline(&s)));
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
