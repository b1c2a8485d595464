//! Tests of `runout_core::displacement` (methods.md §1, §7). Tolerances are stated next to each
//! assertion; Monte-Carlo tolerances come from the sampling distribution of the statistic.

use proptest::prelude::*;
use rand::{rngs::StdRng, SeedableRng};
use rand_distr::{Distribution, Normal};
use runout_core::displacement::*;
use runout_core::runout::seed::tooth_from_seed000_edge;
use runout_core::{Cutter, Runout};
use std::f64::consts::{PI, TAU};

const R_MICRO: f64 = 0.25; // mm, methods.md §1.5 / §7

fn micro(k: usize) -> Cutter {
    Cutter::flat(2.0 * R_MICRO, k, 0.0).unwrap()
}

fn radii(cutter: &Cutter, rho: f64, lambda_deg: f64) -> Vec<f64> {
    Runout::new(rho, lambda_deg.to_radians())
        .unwrap()
        .tooth_radii(cutter, 0.0)
}

fn readings(values: &[f64]) -> ToothReadings {
    ToothReadings::from_values(values, SensorSign::Radial).unwrap()
}

fn opts(cutter: Cutter) -> ToothFitOptions {
    ToothFitOptions::new(cutter)
}

// ---------------------------------------------------------------- §7 vectors

/// methods.md §7 R_k rows, in the seed's edge order k = 1..K, mapped with tooth_from_seed000_edge.
/// Tolerance 1e-9 mm: the table has 9 decimals.
#[test]
fn section7_radius_vectors() {
    let cases: [(usize, f64, &[f64]); 3] = [
        (2, 60.0, &[0.252537126, 0.247537876]),
        (3, 40.0, &[0.253850568, 0.250916561, 0.245307498]),
        (
            4,
            -120.0,
            &[0.247537876, 0.245682593, 0.252537126, 0.254342414],
        ),
    ];
    for (k, theta, expected) in cases {
        let r = radii(&micro(k), 0.005, theta);
        for (edge, want) in expected.iter().enumerate() {
            let tooth = tooth_from_seed000_edge(edge + 1, k).unwrap();
            assert!(
                (r[tooth] - want).abs() < 1e-9,
                "K={k} edge {} got {}",
                edge + 1,
                r[tooth]
            );
        }
    }
    let r = radii(&micro(2), 0.005, 60.0);
    // seed ΔR₁ = R₁ − R₂ (edges 1, 2 = our teeth 0, 1)
    assert!((r[0] - r[1] - 0.004999250).abs() < 1e-9);
}

/// §7: K = 2 inversion of ΔR₁ = 0.004999250 mm with r = 5 µm → |θ| = 60.000° (closed form
/// exact up to the 1e-9 mm rounding of ΔR₁: dθ/dΔR = 1/(2r sin θ) → 1e-9 mm ≈ 6e-6°).
#[test]
fn section7_two_tooth_inversion() {
    let p = readings(&[0.004999250, 0.0]);
    let mut o = opts(micro(2));
    o.known_offset_mm = Some(0.005);
    let fit = identify_from_teeth(&p, &o).unwrap();
    match fit.angle {
        AngleEstimate::Ambiguous { candidates_rad, .. } => {
            for c in candidates_rad {
                assert!(
                    (c.to_degrees().abs() - 60.0).abs() < 1e-4,
                    "{}",
                    c.to_degrees()
                );
            }
            assert!(candidates_rad[0] * candidates_rad[1] < 0.0);
        }
        other => panic!("expected the ±θ ambiguity, got {other:?}"),
    }
    // the seed scan finds the same pair
    o.method = ToothMethod::SeedScan;
    let scan = identify_from_teeth(&p, &o).unwrap();
    let AngleEstimate::Ambiguous { candidates_rad, .. } = scan.angle else {
        panic!("scan: expected ambiguity")
    };
    assert!((candidates_rad[0].to_degrees().abs() - 60.0).abs() < 1e-4);
}

/// K = 2: the spindle phase picks the right mirror solution.
#[test]
fn two_tooth_phase_resolves_sign() {
    for truth in [-60.0f64, 60.0, 135.0, -135.0] {
        let mut o = opts(micro(2));
        o.known_offset_mm = Some(0.005);
        o.phase_hint_rad = Some((truth + 25.0).to_radians()); // a coarse hint suffices
        let fit = identify_from_teeth(&readings(&radii(&micro(2), 0.005, truth)), &o).unwrap();
        let got = fit.angle.angle().expect("determined").to_degrees();
        assert!((got - truth).abs() < 1e-6, "{truth}: {got}");
    }
}

// ---------------------------------------------------------------- round trips

/// Noise-free round trip, K = 3..6, both methods: exact model both ways → 1e-9 mm / 1e-6 rad
/// (LM converges to machine precision on a consistent system).
#[test]
fn round_trip_exact() {
    for k in 3..=6 {
        for lambda in [-170.0, -45.0, 0.0, 33.0, 120.0] {
            let p = radii(&micro(k), 0.004, lambda);
            let fit = identify_from_teeth(&readings(&p), &opts(micro(k))).unwrap();
            assert!((fit.offset_mm - 0.004).abs() < 1e-9);
            let l = fit.angle.angle().unwrap().to_degrees();
            assert!(
                runout_core::angle::wrap_deg180(l - lambda).abs() < 1e-6,
                "K={k} {lambda} {l}"
            );
            let mut o = opts(micro(k));
            o.known_offset_mm = Some(0.004);
            o.method = ToothMethod::SeedScan;
            let scan = identify_from_teeth(&readings(&p), &o).unwrap();
            let l = scan.angle.angle().unwrap().to_degrees();
            assert!(
                runout_core::angle::wrap_deg180(l - lambda).abs() < 1e-4,
                "scan K={k} {lambda} {l}"
            );
        }
    }
}

/// Distance sensor: P = −reading; beam inclined 5° and offset 50 µm on R = 0.25 mm: the readings
/// are ΔL′ = ΔL·sec α_i·R/sqrt(R² − b²) (methods.md §1.4); the correction recovers ρ exactly.
#[test]
fn distance_sign_and_beam_correction() {
    let c = micro(4);
    let p = radii(&c, 0.006, 70.0);
    let beam = BeamGeometry::new(5f64.to_radians(), 0.05).unwrap();
    let f = beam.amplitude_factor(R_MICRO).unwrap();
    let seen: Vec<f64> = p.iter().map(|v| -(v / f) + 3.0).collect();
    let r = ToothReadings::from_values(&seen, SensorSign::Distance).unwrap();
    let mut o = opts(c.clone());
    o.beam = beam;
    let fit = identify_from_teeth(&r, &o).unwrap();
    assert!((fit.offset_mm - 0.006).abs() < 1e-9);
    assert!((fit.angle.angle().unwrap().to_degrees() - 70.0).abs() < 1e-6);
    // without the correction, ρ is 0.38 % + 2.06 % too large
    let raw = identify_from_teeth(&r, &opts(c)).unwrap();
    assert!((raw.offset_mm / 0.006 - 1.0 / f).abs() < 1e-6);
}

/// Repeated readings: averaged, and their scatter gives σ_P (noise_source = repeats).
#[test]
fn repeats_estimate_noise() {
    let c = micro(3);
    let p = radii(&c, 0.005, 10.0);
    let mut rng = StdRng::seed_from_u64(7);
    let noise = Normal::new(0.0, 1e-4).unwrap();
    let pairs: Vec<(usize, f64)> = (0..300)
        .map(|j| (j % 3, p[j % 3] + noise.sample(&mut rng)))
        .collect();
    let r = ToothReadings::new(3, &pairs, SensorSign::Radial).unwrap();
    let fit = identify_from_teeth(&r, &opts(c)).unwrap();
    assert_eq!(fit.noise_source, NoiseSource::Repeats);
    // pooled sd of 297 dof: relative sampling sd 1/sqrt(2·297) = 4 %, 4σ → 17 %
    assert!((fit.noise_mm.unwrap() / 1e-4 - 1.0).abs() < 0.17);
    // 100 repeats: σ_λ ≈ σ_P·sqrt(2/3)/(ρ·10) = 0.094°; error within 4σ
    let se = fit.angle.se().unwrap();
    assert!((se.to_degrees() - 0.0936).abs() < 0.02);
    assert!((fit.angle.angle().unwrap().to_degrees() - 10.0).abs() < 4.0 * se.to_degrees());
}

// ---------------------------------------------------------------- Monte-Carlo §1.5

fn sd(v: &[f64]) -> f64 {
    let m = v.iter().sum::<f64>() / v.len() as f64;
    (v.iter().map(|x| (x - m).powi(2)).sum::<f64>() / (v.len() - 1) as f64).sqrt()
}

/// Monte-Carlo of the joint fit: returns (sd of ρ, sd of λ) in µm and degrees, and the mean
/// reported σ_λ (degrees).
fn monte_carlo_joint(k: usize, rho: f64, sigma: f64, trials: usize, seed: u64) -> (f64, f64, f64) {
    let c = micro(k);
    let truth = radii(&c, rho, 40.0);
    let mut rng = StdRng::seed_from_u64(seed);
    let noise = Normal::new(0.0, sigma).unwrap();
    let (mut rhos, mut lambdas, mut ses) = (vec![], vec![], vec![]);
    for _ in 0..trials {
        let p: Vec<f64> = truth.iter().map(|v| v + noise.sample(&mut rng)).collect();
        let mut o = opts(c.clone());
        o.noise_mm = Some(sigma);
        let fit = identify_from_teeth(&readings(&p), &o).unwrap();
        rhos.push(fit.offset_mm * 1e3);
        let l = fit.angle.angle().unwrap();
        lambdas.push(runout_core::angle::wrap_deg180(l.to_degrees() - 40.0));
        ses.push(fit.angle.se().unwrap().to_degrees());
    }
    (
        sd(&rhos),
        sd(&lambdas),
        ses.iter().sum::<f64>() / trials as f64,
    )
}

/// methods.md §1.5 Monte-Carlo, K = 3, r = 5 µm, σ_P = 0.1 µm: table "r ± 0.08 µm, θ sd 1.0°";
/// the formulas give σ_r = σ_P·sqrt(2/K) = 0.0816 µm, σ_θ = σ_r/r = 0.936°.
/// 3000 trials: the sample sd has relative sampling sd 1/sqrt(2·2999) = 1.3 %; tolerance 4 × that
/// = 5.2 % around the formula values. The table's rounded 1.0° is 7 % above the formula
/// (their own Monte-Carlo noise); we test the formula the spec also states.
#[test]
fn monte_carlo_k3_matches_section_1_5() {
    let (sr, sl, se) = monte_carlo_joint(3, 0.005, 1e-4, 3000, 11);
    let (fr, fl) = (
        0.1 * (2.0f64 / 3.0).sqrt(),
        (0.1 * (2.0f64 / 3.0).sqrt() / 5.0).to_degrees(),
    );
    eprintln!("K=3 MC: sd r {sr:.4} µm (formula {fr:.4}), sd θ {sl:.3}° (formula {fl:.3}°), reported σ_θ {se:.3}°");
    assert!((sr / fr - 1.0).abs() < 0.052, "sd r {sr} vs {fr}");
    assert!((sl / fl - 1.0).abs() < 0.052, "sd θ {sl} vs {fl}");
    // the fit's own σ_λ is the exact-model version of the same formula (within 1 %)
    assert!((se / fl - 1.0).abs() < 0.01, "reported σ_θ {se} vs {fl}");
}

/// §1.5 table, K = 4, r = 2 µm, σ_P = 0.3 µm: "r ± 0.22 µm, θ sd 6.2°"; formulas 0.212 µm, 6.08°.
/// 3000 trials, tolerance 5.2 % (as above) on ρ; on θ 8 % (the 5 % + the nonlinearity at
/// σ_θ ≈ 0.1 rad, which widens the distribution by ~σ_θ²/2 ≈ 1–2 %).
#[test]
fn monte_carlo_k4_noisy() {
    let (sr, sl, _) = monte_carlo_joint(4, 0.002, 3e-4, 3000, 12);
    let (fr, fl) = (
        0.3 * 0.5f64.sqrt(),
        (0.3 * 0.5f64.sqrt() / 2.0).to_degrees(),
    );
    eprintln!("K=4 MC: sd r {sr:.4} µm (formula {fr:.4}), sd θ {sl:.3}° (formula {fl:.3}°)");
    assert!((sr / fr - 1.0).abs() < 0.052, "sd r {sr} vs {fr}");
    assert!((sl / fl - 1.0).abs() < 0.08, "sd θ {sl} vs {fl}");
}

/// §1.5 table, K = 2, r = 5 µm known, θ = 90°, σ_P = 0.1 µm: "sd of |θ| 0.8°";
/// formula σ_P/(√2·r·|sin θ|) = 0.810°. 3000 trials, tolerance 5.2 %.
#[test]
fn monte_carlo_k2_known_offset() {
    let c = micro(2);
    let truth = radii(&c, 0.005, 90.0);
    let mut rng = StdRng::seed_from_u64(13);
    let noise = Normal::new(0.0, 1e-4).unwrap();
    let mut abs_theta = vec![];
    for _ in 0..3000 {
        let p: Vec<f64> = truth.iter().map(|v| v + noise.sample(&mut rng)).collect();
        let mut o = opts(c.clone());
        o.known_offset_mm = Some(0.005);
        o.noise_mm = Some(1e-4);
        let fit = identify_from_teeth(&readings(&p), &o).unwrap();
        let AngleEstimate::Ambiguous {
            candidates_rad,
            se_rad,
            ..
        } = fit.angle
        else {
            panic!("expected ambiguity")
        };
        abs_theta.push(candidates_rad[0].to_degrees().abs());
        assert!((se_rad.unwrap().to_degrees() - 0.810).abs() < 0.02);
    }
    let f = (1e-4 / (2f64.sqrt() * 0.005)).to_degrees();
    eprintln!("K=2 MC: sd |θ| {:.3}° (formula {f:.3}°)", sd(&abs_theta));
    assert!(
        (sd(&abs_theta) / f - 1.0).abs() < 0.052,
        "{} vs {f}",
        sd(&abs_theta)
    );
}

// ---------------------------------------------------------------- §1.3 OLS vs eq. (6)

fn mc_heights(slope_um_mm: f64, sigma_um: f64, trials: usize, seed: u64) -> (Vec<f64>, Vec<f64>) {
    let mut rng = StdRng::seed_from_u64(seed);
    let noise = Normal::new(0.0, sigma_um * 1e-3).unwrap();
    let (mut ols, mut eq6) = (vec![], vec![]);
    for _ in 0..trials {
        let pts: Vec<(f64, f64)> = (1..=5)
            .map(|z| {
                let z = z as f64;
                (z, (3.0 + slope_um_mm * z) * 1e-3 + noise.sample(&mut rng))
            })
            .collect();
        ols.push(
            runout_at_height(&pts, 0.0, HeightRegression::Ols)
                .unwrap()
                .offset_mm
                * 1e3,
        );
        if let Ok(f) = runout_at_height(&pts, 0.0, HeightRegression::SeedEq6) {
            eq6.push(f.offset_mm * 1e3);
        }
    }
    (ols, eq6)
}

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

/// methods.md §1.3: 5 heights 1..5 mm, r₀ = 3 µm, 4000 trials.
/// (a) slope 0.4 µm/mm, σ = 0.1 µm: OLS mean 3.00 µm, sd 0.105 µm (theory σ·sqrt(1/5 + 9/10));
///     mean within 4 standard errors (4·0.105/√4000 = 0.0066 µm), sd within 5 % (4 × 1.1 %).
/// (b) slope 0.1 µm/mm, σ = 0.2 µm: eq. (6) median 2.64 µm in the spec; its sampling sd (heavy
///     tails, ~1.25·IQR-based ~0.5 µm/√4000 ≈ 0.01 µm) → accept 2.54..2.74; OLS stays unbiased.
#[test]
fn ols_unbiased_where_eq6_is_biased() {
    let (ols, _) = mc_heights(0.4, 0.1, 4000, 21);
    let m = ols.iter().sum::<f64>() / ols.len() as f64;
    let theory = 0.1 * (0.2f64 + 0.9).sqrt();
    assert!(
        (m - 3.0).abs() < 4.0 * theory / 4000f64.sqrt(),
        "OLS mean {m}"
    );
    assert!(
        (sd(&ols) / theory - 1.0).abs() < 0.05,
        "OLS sd {}",
        sd(&ols)
    );

    let (ols, eq6) = mc_heights(0.1, 0.2, 4000, 22);
    let m = ols.iter().sum::<f64>() / ols.len() as f64;
    let theory = 0.2 * (0.2f64 + 0.9).sqrt();
    assert!(
        (m - 3.0).abs() < 4.0 * theory / 4000f64.sqrt(),
        "OLS mean {m}"
    );
    let med = median(eq6);
    eprintln!("heights MC (slope 0.1, σ 0.2): OLS mean {m:.4} µm, eq. (6) median {med:.4} µm");
    assert!((2.54..2.74).contains(&med), "eq. (6) median {med}");
}

/// Vector fit (§1.6) with offset and tilt in different axial planes: exact recovery of E₀ and T,
/// while |e(z)| is not linear in z.
#[test]
fn vector_height_fit_recovers_offset_and_tilt() {
    let truth = Runout::new(0.004, 20f64.to_radians())
        .unwrap()
        .with_tilt(0.0015, 200f64.to_radians())
        .unwrap();
    let pts: Vec<(f64, [f64; 2])> = (0..6)
        .map(|i| {
            let z = 10.0 + 4.0 * i as f64;
            (z, truth.vector_at(z))
        })
        .collect();
    let fit = vector_at_height(&pts, 2.0).unwrap();
    let e = truth.vector_at(2.0);
    assert!((fit.offset_mm - e[0].hypot(e[1])).abs() < 1e-12);
    assert!((fit.angle.angle().unwrap() - e[1].atan2(e[0])).abs() < 1e-9);
    assert!((fit.line.tilt[0].value - truth.tilt()[0]).abs() < 1e-12);
    // the magnitude-only OLS is visibly wrong here (|e(z)| is not a line)
    let mag: Vec<(f64, f64)> = pts.iter().map(|(z, v)| (*z, v[0].hypot(v[1]))).collect();
    let ols = runout_at_height(&mag, 2.0, HeightRegression::Ols).unwrap();
    assert!((ols.offset_mm - fit.offset_mm).abs() > 1e-4);
}

// ---------------------------------------------------------------- raw signal

struct Sim {
    a: Vec<f64>,
    b: Vec<f64>,
    pulse: Vec<f64>,
    encoder: Vec<f64>,
}

/// Rotating circle, offset ρ at λ (spindle frame, mark frame), distance sensors at 0° and 90°
/// (reading = −radial + 1 mm stand-off), noise σ, TTL once-per-rev mark at φ ≡ 0.
fn simulate(n: usize, fs: f64, rpm: f64, rho: f64, lambda: f64, sigma: f64, seed: u64) -> Sim {
    let w = rpm / 60.0 * TAU;
    let mut rng = StdRng::seed_from_u64(seed);
    let noise = Normal::new(0.0, sigma).unwrap();
    let mut s = Sim {
        a: vec![],
        b: vec![],
        pulse: vec![],
        encoder: vec![],
    };
    for i in 0..n {
        let phi = w * i as f64 / fs + 0.3; // recording starts 0.3 rad after the mark
        s.a.push(1.0 - rho * (lambda + phi).cos() + noise.sample(&mut rng));
        s.b.push(1.0 - rho * (lambda + phi - PI / 2.0).cos() + noise.sample(&mut rng));
        s.pulse
            .push(if phi.rem_euclid(TAU) < 0.2 { 5.0 } else { 0.0 });
        s.encoder.push(phi.rem_euclid(TAU));
    }
    s
}

fn input<'a>(s: &'a Sim, fs: f64, reference: SpindleReference<'a>) -> SignalInput<'a> {
    SignalInput {
        sample_rate_hz: fs,
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

/// Issue 5 raw-signal case: R = 5 mm at 3240 rpm, ρ = 8 µm at 30°, sensors at 0° and 90°, 50 kHz,
/// 1e6 samples, SNR 25 taken as the power ratio (signal rms 5.66 µm / noise 1.13 µm, the most
/// demanding reading of "SNR 25"). Target: offset within 0.05 µm, angle within 0.5°.
/// Expected accuracy σ_ρ ≈ σ/sqrt(N_total/2)·… ≈ 1.6 nm, σ_λ ≈ 0.01°; with the pulse the
/// mark quantisation (±½ sample = ±0.19°/rev, averaged over 1080 revs) adds < 0.01°.
#[test]
fn raw_signal_issue_case() {
    let (n, fs) = (1_000_000, 50_000.0);
    let sigma = 0.008 / 2f64.sqrt() / 5.0;
    let s = simulate(n, fs, 3240.0, 0.008, 30f64.to_radians(), sigma, 31);
    // with the once-per-rev mark: λ is relative to the mark
    let (fit, track) = fit_signal(&input(&s, fs, SpindleReference::Pulse(&s.pulse))).unwrap();
    eprintln!(
        "signal/pulse: ρ {:.5} µm, λ {:.4}°",
        fit.offset_mm * 1e3,
        fit.angle.angle().unwrap().to_degrees()
    );
    assert!((fit.offset_mm - 0.008).abs() < 0.05e-3, "{}", fit.offset_mm);
    let l = fit.angle.angle().unwrap().to_degrees();
    assert!((l - 30.0).abs() < 0.5, "{l}");
    assert!((fit.rpm - 3240.0).abs() < 0.1);
    assert!(fit.channel_agreement_chi2.unwrap() < 25.0);
    // reported σ matches the expected order (σ/sqrt(N) scaling)
    assert!(fit.offset_se_mm < 5e-6 && fit.offset_se_mm > 5e-7);
    // seed eq. (5) per revolution: half TIR ≈ ρ + noise extremes (biased up by noise, ~3σ)
    let revs =
        per_revolution_runout(&input(&s, fs, SpindleReference::Pulse(&s.pulse)), &track).unwrap();
    assert!(revs[0].mean_mm > 0.008 && revs[0].mean_mm < 0.008 + 5.0 * sigma);

    // encoder: same answer
    let (enc, _) = fit_signal(&input(&s, fs, SpindleReference::Encoder(&s.encoder))).unwrap();
    assert!((enc.offset_mm - 0.008).abs() < 0.05e-3);
    assert!((enc.angle.angle().unwrap().to_degrees() - 30.0).abs() < 0.5);

    // no reference: speed from the spectrum, angle relative to the first sample (φ₀ = 0.3 rad)
    let est = input(
        &s,
        fs,
        SpindleReference::Estimate {
            rpm_min: 600.0,
            rpm_max: 30000.0,
        },
    );
    let (fit, _) = fit_signal(&est).unwrap();
    eprintln!(
        "signal/estimated: rpm {:.5}, ρ {:.5} µm, λ−φ₀ {:.4}°",
        fit.rpm,
        fit.offset_mm * 1e3,
        fit.angle.angle().unwrap().to_degrees() - 0.3f64.to_degrees()
    );
    assert!((fit.rpm - 3240.0).abs() < 1e-3, "{}", fit.rpm);
    assert!((fit.offset_mm - 0.008).abs() < 0.05e-3);
    let l = fit.angle.angle().unwrap().to_degrees();
    assert!(
        runout_core::angle::wrap_deg180(l - 30.0 - 0.3f64.to_degrees()).abs() < 0.5,
        "{l}"
    );
}

/// Noise-free signals (exact data) are fitted exactly, not rejected for a zero residual.
#[test]
fn noise_free_signal_is_exact() {
    let (fs, rpm, n) = (10_000.0, 600.0, 10_000);
    let s = simulate(n, fs, rpm, 0.004, -2.0, 0.0, 1);
    let (fit, _) = fit_signal(&input(&s, fs, SpindleReference::Encoder(&s.encoder))).unwrap();
    assert!((fit.offset_mm - 0.004).abs() < 1e-12);
    assert!((fit.angle.angle().unwrap() + 2.0).abs() < 1e-9);
}

/// Off-axis beam (methods.md §1.4) checked against the exact geometry, not the formula: a beam
/// parallel to the sensor axis but offset by b = 50 µm on a round section R = 0.25 mm hits the
/// surface at x = c_x + sqrt(R² − (b − c_y)²). Uncorrected, the offset is sec α_b = 1.0206 too large
/// and the angle off by α_b = 11.54°; corrected, ρ is within 0.1 % and λ within 0.05° (the
/// neglected terms are O(ρ²/R) and land in the 0th/2nd harmonics; noise-free).
#[test]
fn off_axis_beam_signal_matches_exact_geometry() {
    let (r, b, rho, lam) = (0.25, 0.05, 0.005, 50f64.to_radians());
    let (fs, rpm, n) = (10_000.0, 600.0, 20_000);
    let w = rpm / 60.0 * TAU;
    let (mut d, mut enc) = (vec![], vec![]);
    for i in 0..n {
        let phi = w * i as f64 / fs;
        let (cx, cy) = (rho * (lam + phi).cos(), rho * (lam + phi).sin());
        d.push(cx + (r * r - (b - cy) * (b - cy)).sqrt());
        enc.push(phi);
    }
    let mk = |beam| SignalInput {
        sample_rate_hz: fs,
        channels: vec![SensorChannel {
            displacement_mm: &d,
            angle_rad: 0.0,
            sign: SensorSign::Radial,
        }],
        reference: SpindleReference::Encoder(&enc),
        surface_radius_mm: r,
        beam,
        reference_angle_rad: 0.0,
    };
    let (raw, _) = fit_signal(&mk(BeamGeometry::ideal())).unwrap();
    assert!((raw.offset_mm / rho - 1.0 / (1.0 - 0.04f64).sqrt()).abs() < 1e-3);
    let (fit, _) = fit_signal(&mk(BeamGeometry::new(0.0, b).unwrap())).unwrap();
    assert!(
        (fit.offset_mm / rho - 1.0).abs() < 1e-3,
        "{}",
        fit.offset_mm
    );
    let l = fit.angle.angle().unwrap().to_degrees();
    assert!((l - 50.0).abs() < 0.05, "{l}");
    // uncorrected, the sensor direction is taken as β instead of β + α_b: λ comes out α_b too small
    assert!(
        (raw.angle.angle().unwrap().to_degrees() - l + 0.2f64.asin().to_degrees()).abs() < 0.05
    );
}

/// A toothed profile (K = 3, R = 0.25 mm) read slowly: per-tooth extrema in the angular windows
/// recover R_i to the sampling resolution (peak curvature c·(Δφ/2)² < 1e-9 mm), and the
/// identification gives the runout back (1e-6 mm, 0.01°).
#[test]
fn per_tooth_extrema_from_signal() {
    let c = micro(3);
    let truth = Runout::new(0.005, 75f64.to_radians()).unwrap();
    let r = truth.tooth_radii(&c, 0.0);
    let (fs, rpm, n) = (10_000.0, 60.0, 30_000); // 3 revolutions, 0.036° per sample
    let beta = 0.7; // sensor angle
    let phi_ref = 0.2; // tooth 0 sits 0.2 rad after the mark
    let w = rpm / 60.0 * TAU;
    let (mut d, mut pulse) = (vec![], vec![]);
    for i in 0..n {
        let phi = w * i as f64 / fs - 0.1;
        let v = (0..3)
            .map(|t| {
                let centre = beta - c.tooth_angle(t, 0.0) - phi_ref;
                r[t] - 0.01 * runout_core::angle::wrap_pi(phi - centre).powi(2)
            })
            .fold(f64::NEG_INFINITY, f64::max);
        d.push(v);
        pulse.push(if phi.rem_euclid(TAU) < 0.3 { 1.0 } else { 0.0 });
    }
    let inp = SignalInput {
        sample_rate_hz: fs,
        channels: vec![SensorChannel {
            displacement_mm: &d,
            angle_rad: beta,
            sign: SensorSign::Radial,
        }],
        reference: SpindleReference::Pulse(&pulse),
        surface_radius_mm: R_MICRO,
        beam: BeamGeometry::ideal(),
        reference_angle_rad: phi_ref,
    };
    let track = spindle_track(&inp).unwrap();
    let tr = per_tooth_extrema(&inp, &track, 0, &c, 0.0).unwrap();
    assert_eq!(tr.samples()[0].len(), track.revolutions.len());
    for (p, want) in tr.positions().iter().zip(&r) {
        assert!((p - want).abs() < 1e-7, "{p} vs {want}");
    }
    let fit = identify_from_teeth(&tr, &opts(c)).unwrap();
    assert!((fit.offset_mm - 0.005).abs() < 1e-6);
    assert!((fit.angle.angle().unwrap().to_degrees() - 75.0).abs() < 0.01);
}

// ---------------------------------------------------------------- bad inputs, ill-posed cases

#[test]
fn bad_inputs_give_clear_errors() {
    // fewer readings than teeth
    let e = ToothReadings::new(4, &[(0, 0.1), (1, 0.1), (3, 0.1)], SensorSign::Radial).unwrap_err();
    assert!(matches!(e, DisplacementError::MissingTooth { ref missing, .. } if missing == &[2]));
    assert!(e.to_string().contains("tooth [2]"));
    // readings for 3 teeth, cutter with 4
    let e = identify_from_teeth(&readings(&[0.0, 0.001, 0.002]), &opts(micro(4))).unwrap_err();
    assert!(e.to_string().contains("4-tooth"), "{e}");
    // NaN
    let e = ToothReadings::from_values(&[0.0, f64::NAN, 0.0], SensorSign::Radial).unwrap_err();
    assert!(matches!(e, DisplacementError::NotFinite { index: 1, .. }));
    // |ΔR| > 2r
    let mut o = opts(micro(2));
    o.known_offset_mm = Some(0.002);
    let e = identify_from_teeth(&readings(&[0.005, 0.0]), &o).unwrap_err();
    assert!(
        matches!(e, DisplacementError::InconsistentDifference { .. }),
        "{e}"
    );
    // … but within 3σ of the noise it is clamped and flagged
    o.noise_mm = Some(0.0005);
    let f = identify_from_teeth(&readings(&[0.0045, 0.0]), &o).unwrap();
    assert!(f.notes.iter().any(|n| n.contains("clamped")));
    // K = 2 without the offset
    let e = identify_from_teeth(&readings(&[0.001, 0.0]), &opts(micro(2))).unwrap_err();
    assert!(matches!(e, DisplacementError::NeedsOffset { .. }));
    // heights all equal
    let e =
        runout_at_height(&[(2.0, 0.003), (2.0, 0.004)], 0.0, HeightRegression::Ols).unwrap_err();
    assert!(matches!(e, DisplacementError::HeightsEqual { .. }));
    let e = runout_at_height(&[(2.0, 0.003)], 0.0, HeightRegression::Ols).unwrap_err();
    assert!(matches!(
        e,
        DisplacementError::TooFew {
            got: 1,
            need: 2,
            ..
        }
    ));
    let e =
        runout_at_height(&[(1.0, f64::NAN), (2.0, 0.1)], 0.0, HeightRegression::Ols).unwrap_err();
    assert!(matches!(e, DisplacementError::NotFinite { .. }));
    // signals: no channel, reference of the wrong length, constant pulse, one mark
    let x = vec![0.0; 1000];
    let short = vec![0.0; 10];
    let mut inp = SignalInput {
        sample_rate_hz: 1000.0,
        channels: vec![],
        reference: SpindleReference::Pulse(&x),
        surface_radius_mm: 5.0,
        beam: BeamGeometry::ideal(),
        reference_angle_rad: 0.0,
    };
    assert!(fit_signal(&inp)
        .unwrap_err()
        .to_string()
        .contains("no displacement channel"));
    inp.channels.push(SensorChannel {
        displacement_mm: &x,
        angle_rad: 0.0,
        sign: SensorSign::Radial,
    });
    assert!(fit_signal(&inp)
        .unwrap_err()
        .to_string()
        .contains("constant"));
    inp.reference = SpindleReference::Pulse(&short);
    assert!(fit_signal(&inp)
        .unwrap_err()
        .to_string()
        .contains("reference channel has 10"));
    let mut one = vec![0.0; 1000];
    one[500] = 1.0;
    inp.reference = SpindleReference::Pulse(&one);
    assert!(fit_signal(&inp)
        .unwrap_err()
        .to_string()
        .contains("1 once-per-revolution mark"));
}

/// Ill-posed cases are flagged, never a silently wrong angle (methods.md §1.5).
#[test]
fn ill_posed_cases_are_flagged() {
    // K = 3, ρ = 0.2 µm with σ_P = 0.1 µm: σ_λ ≈ 0.1·0.82/0.2 rad = 23° > 10°
    let mut o = opts(micro(3));
    o.noise_mm = Some(1e-4);
    let fit = identify_from_teeth(&readings(&radii(&micro(3), 0.0002, 50.0)), &o).unwrap();
    assert!(
        matches!(fit.angle, AngleEstimate::Undetermined { .. }),
        "{:?}",
        fit.angle
    );
    // K = 2 near θ = 0: σ_λ = σ_P/(√2 ρ sin 2°) = 23° → undetermined even with the hint
    let mut o = opts(micro(2));
    o.known_offset_mm = Some(0.005);
    o.noise_mm = Some(1e-4);
    o.phase_hint_rad = Some(0.0);
    let fit = identify_from_teeth(&readings(&radii(&micro(2), 0.005, 2.0)), &o).unwrap();
    let AngleEstimate::Undetermined { reason, .. } = &fit.angle else {
        panic!("{:?}", fit.angle)
    };
    assert!(reason.contains("K = 2"));
    // K = 3 without any noise information: determined but flagged, se unknown
    let fit =
        identify_from_teeth(&readings(&radii(&micro(3), 0.005, 50.0)), &opts(micro(3))).unwrap();
    assert_eq!(fit.noise_source, NoiseSource::Unknown);
    assert!(fit.angle.se().is_none() && fit.notes.iter().any(|n| n.contains("no noise estimate")));
    // K ≥ 3 consistency check against the height-regression offset (§1.5 step 4)
    let mut o = opts(micro(4));
    o.noise_mm = Some(1e-4);
    o.known_offset_mm = Some(0.003);
    o.known_offset_se_mm = Some(1e-4);
    let fit = identify_from_teeth(&readings(&radii(&micro(4), 0.005, 50.0)), &o).unwrap();
    assert!(fit.notes.iter().any(|n| n.contains("inconsistent offsets")));
}

// ---------------------------------------------------------------- consequences

/// §1.7 with the simulate reference cutter (D10, 4 teeth, ρ = 8 µm, λ = 0): radii from
/// `Runout::tooth_radius`, slot width 2·max R_i, and at φ = 90° the chip loads telescope:
/// Σ h_i = K·f_z when every tooth cuts (h_i = f_z + R_i − R_{i−1}).
#[test]
fn consequences_reference_cutter() {
    let c = Cutter::flat(10.0, 4, 30.0f64.to_radians()).unwrap();
    let r = Runout::new(0.008, 0.0).unwrap();
    let q = consequences(&c, &r, 0.0, Some(0.08), Some(20.0)).unwrap();
    assert!((q.tooth_radii_mm[0] - 5.008).abs() < 1e-12);
    assert!((q.slot_width_mm - 10.016).abs() < 1e-12);
    assert!((q.hole_diameter_mm.unwrap() - 30.016).abs() < 1e-12);
    let h = q.chip_load_mm.unwrap();
    assert!((h.iter().sum::<f64>() - 0.32).abs() < 1e-12);
    // tooth 0 follows tooth 3: h₀ = f_z + R₀ − R₃ (exact radii; first order f_z + ρ)
    let rr = &q.tooth_radii_mm;
    assert!((h[0] - (0.08 + rr[0] - rr[3])).abs() < 1e-12);
    assert!((h[0] - 0.088).abs() < 1e-5);
}

// ---------------------------------------------------------------- properties

proptest! {
    #![proptest_config(ProptestConfig::with_cases(48))]

    /// Noise-free identification over realistic ranges (R 0.1–6 mm, ρ 1–30 µm, K 3–6, any λ,
    /// helix 0–45° read at z 0–3 mm): ρ within 1e-9 mm, λ within 1e-6 rad.
    #[test]
    fn prop_joint_exact(k in 3usize..=6, d in 0.2f64..12.0, rho_um in 1.0f64..30.0,
                        lam in -179.0f64..180.0, helix in 0.0f64..45.0, z in 0.0f64..3.0) {
        let c = Cutter::flat(d, k, f64::to_radians(helix)).unwrap();
        let t = Runout::new(rho_um * 1e-3, lam.to_radians()).unwrap();
        let mut o = opts(c.clone());
        o.height_mm = z;
        let fit = identify_from_teeth(&readings(&t.tooth_radii(&c, z)), &o).unwrap();
        prop_assert!((fit.offset_mm - rho_um * 1e-3).abs() < 1e-9);
        let dl = runout_core::angle::wrap_pi(fit.angle.angle().unwrap() - lam.to_radians());
        prop_assert!(dl.abs() < 1e-6);
    }

    /// K = 2 closed form: for θ' in 5°..175° the truth is one of the two candidates (1e-6 rad).
    #[test]
    fn prop_two_teeth_candidates(d in 0.2f64..12.0, rho_um in 1.0f64..30.0, lam in -175.0f64..175.0) {
        prop_assume!(lam.abs() > 5.0);
        let c = Cutter::flat(d, 2, 0.0).unwrap();
        let t = Runout::new(rho_um * 1e-3, lam.to_radians()).unwrap();
        let mut o = opts(c.clone());
        o.known_offset_mm = Some(rho_um * 1e-3);
        let fit = identify_from_teeth(&readings(&t.tooth_radii(&c, 0.0)), &o).unwrap();
        let AngleEstimate::Ambiguous { candidates_rad, .. } = fit.angle else { panic!() };
        let best = candidates_rad.iter().map(|c| runout_core::angle::wrap_pi(c - lam.to_radians()).abs())
            .fold(f64::INFINITY, f64::min);
        prop_assert!(best < 1e-6);
    }

    /// The seed's scan with ρ known recovers λ for K = 3..6 (1° grid + Gauss–Newton to 1e−6 rad;
    /// tolerance 1e−5 rad).
    #[test]
    fn prop_seed_scan(k in 3usize..=6, rho_um in 2.0f64..30.0, lam in -179.0f64..180.0) {
        let c = micro(k);
        let t = Runout::new(rho_um * 1e-3, lam.to_radians()).unwrap();
        let mut o = opts(c.clone());
        o.method = ToothMethod::SeedScan;
        o.known_offset_mm = Some(rho_um * 1e-3);
        let fit = identify_from_teeth(&readings(&t.tooth_radii(&c, 0.0)), &o).unwrap();
        let dl = runout_core::angle::wrap_pi(fit.angle.angle().unwrap() - lam.to_radians());
        prop_assert!(dl.abs() < 1e-5);
    }

    /// Vector fit (§1.6) on noise-free offset + tilt data: E₀ and T exact (1e-12), any planes.
    #[test]
    fn prop_vector_fit_exact(e0x in -0.02f64..0.02, e0y in -0.02f64..0.02, tx in -0.002f64..0.002,
                             ty in -0.002f64..0.002, n in 2usize..8) {
        let truth = Runout::from_vector([e0x, e0y]).with_tilt_vector([tx, ty]);
        let pts: Vec<(f64, [f64; 2])> = (0..n).map(|i| {
            let z = 5.0 + 3.0 * i as f64;
            (z, truth.vector_at(z))
        }).collect();
        let f = vector_at_height(&pts, 0.0).unwrap();
        let ([ox, oy], [fx, fy]) = (f.line.offset_mm(), f.line.tilt_vector());
        prop_assert!((ox - e0x).abs() < 1e-12 && (oy - e0y).abs() < 1e-12);
        prop_assert!((fx - tx).abs() < 1e-12 && (fy - ty).abs() < 1e-12);
    }

    /// OLS on noise-free lines is exact at any evaluation height (1e-12 mm).
    #[test]
    fn prop_ols_exact(r0 in 0.0f64..0.02, slope in -0.002f64..0.002, zc in -5.0f64..5.0, n in 2usize..8) {
        let pts: Vec<(f64, f64)> = (0..n).map(|i| (1.0 + i as f64, r0 + slope * (1.0 + i as f64))).collect();
        let f = runout_at_height(&pts, zc, HeightRegression::Ols).unwrap();
        prop_assert!((f.offset_mm - (r0 + slope * zc)).abs() < 1e-12);
    }

    /// Raw signal with a TTL pulse, short records (~200 revolutions of ~102 samples), σ = ρ/10:
    /// σ_e ≈ σ/sqrt(N) per component ≈ 0.07 % of ρ → ρ within 1 %. The angle carries the mark's
    /// quantisation: a TTL edge is known to ±½ sample = ±180°/102 = ±1.77°, plus 0.2° for noise.
    #[test]
    fn prop_signal_round_trip(rho_um in 2.0f64..30.0, lam in -179.0f64..180.0, seed in 0u64..1000) {
        let (fs, rpm, n) = (10_000.0, 5900.0, 20_000);
        let s = simulate(n, fs, rpm, rho_um * 1e-3, lam.to_radians(), rho_um * 1e-4, seed);
        let (fit, _) = fit_signal(&input(&s, fs, SpindleReference::Pulse(&s.pulse))).unwrap();
        prop_assert!((fit.offset_mm / (rho_um * 1e-3) - 1.0).abs() < 0.01);
        let dl = runout_core::angle::wrap_deg180(fit.angle.angle().unwrap().to_degrees() - lam);
        prop_assert!(dl.abs() < 1.77 + 0.2, "{}", dl);
        // with the encoder there is no quantisation: 0.2°
        let (fit, _) = fit_signal(&input(&s, fs, SpindleReference::Encoder(&s.encoder))).unwrap();
        let dl = runout_core::angle::wrap_deg180(fit.angle.angle().unwrap().to_degrees() - lam);
        prop_assert!(dl.abs() < 0.2, "{}", dl);
    }
}
