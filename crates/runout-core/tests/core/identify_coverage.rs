//! Coverage of the full-signal fit's standard error of ρ with an unmodelled sensor resonance
//! (issue 11 item 6): over 200 simulated recordings the true ρ lies within ±2 SE of the rigid
//! fit's ρ in ≥ 90 % of the fits.
//!
//! Set-up (cheap, and a *small* model error): K = 3, Ø10 straight flutes (one axial disk),
//! 6000 rpm (f_rev 100 Hz, tooth passing 300 Hz), down milling a_e 3 mm, a_p 2 mm, f_z 0.05 mm,
//! 15 kHz (150 samples per revolution), F_x and F_y. The dynamometer has one mode at 6 kHz with
//! ζ 0.2 on x and y (peak gain 2.5, below the recording's Nyquist frequency so nothing large
//! folds onto the runout lines), which the fit does not model (`FullSignalOptions::default()`):
//! |H| − 1 is 2.1 %, 3.8 % and 6.1 % at tooth-passing harmonics 3, 4, 5 (900–1500 Hz), the
//! straight flutes' sharp entry rings it, and the fits reach R² ≈ 0.973. The recording is made
//! as in `identify_chain.rs`: cut simulated 8× oversampled, run through the mode, decimated,
//! then white noise (2 % of each component's peak) plus coloured AR(1) noise (φ = 0.9, 0.5 %),
//! 2 revolutions of settling and 10 averaged. Each recording draws ρ uniform in 5–15 µm, λ
//! uniform in 0–360° and its own noise seed. 200 fits take < 1 s in release on 2 cores.
//!
//! Figures (200 fits; a binomial 90 % over 200 has a standard deviation of 2.1 %):
//! * reported SE (the larger of classic and robust): **91.5 %**; robust alone 90.0 %; classic
//!   alone **80.0 %** — the classic SE is too small (it spreads the misfit over all harmonics
//!   and takes the noise as white);
//! * the first robust version (plain harmonic-cluster sandwich, no small-sample factor) covered
//!   85 % (reported 88 %) — see the covariance module docs for the change;
//! * the mode's effect is partly a parameter change: ρ comes out 0.30 µm low on average (RMS
//!   error 0.52 µm, mean reported SE 0.41 µm); no residual-based SE sees the part of the model
//!   error that the parameters absorb, which is why coverage is asserted at 90 % and not 95 %;
//! * for comparison, without the mode (f_n 100 kHz) the reported SE covers 93.5 % (classic
//!   87 %, coloured noise alone), and with a sharp mode (ζ 0.05, R² 0.83) 97 % (classic 97 %:
//!   the large misfit inflates s²).

use rand::{rngs::StdRng, Rng, SeedableRng};
use rand_distr::{Distribution, Normal};
use rayon::prelude::*;
use runout_core::chain::{AxisChain, SensorMode};
use runout_core::identify::*;
use runout_core::*;

const OVERSAMPLE: usize = 8;
const SPR: usize = 150;
const SETTLE: usize = 2;
const REVS: usize = 10;
const FITS: usize = 200;
const KC: [f64; 6] = [1900.0, 800.0, 0.0, 30.0, 40.0, 0.0];

struct Outcome {
    rho_um: f64,
    fit_um: f64,
    se_um: f64,
    classic_um: f64,
    robust_um: f64,
    r2: f64,
}

fn one(i: usize) -> Outcome {
    let mut rng = StdRng::seed_from_u64(1000 + i as u64);
    let rho_um = rng.random_range(5.0..15.0);
    let lambda = rng.random_range(0.0..std::f64::consts::TAU);
    let cutter = Cutter::flat(10.0, 3, 0.0).unwrap();
    let cut = Cut::new(6000.0, 0.05, 2.0)
        .unwrap()
        .radial(3.0, MillingMode::Down, &cutter)
        .unwrap();
    let runout = Runout::new(rho_um * 1e-3, lambda).unwrap();
    let chip = ArcChip::new(&cutter, &runout, 0.05).unwrap();
    let model = ForceModel {
        cutter: cutter.clone(),
        runout,
        cut,
        coefficients: CuttingCoefficients::from_array(KC),
    };
    let step = 360.0 / (SPR * OVERSAMPLE) as f64;
    let series = model.simulate(
        &chip,
        &Sampling::new((SETTLE + REVS) as f64, step, 1).unwrap(),
    );
    let mode = AxisChain::Modes(vec![SensorMode::new(6000.0, 0.2, 1.0).unwrap()]);
    let fs_fine = 15_000.0 * OVERSAMPLE as f64;
    let white = Normal::new(0.0, 1.0).unwrap();
    let mut channel = |v: &[f64]| -> Vec<f64> {
        let kept: Vec<f64> = mode
            .filter(fs_fine, v)
            .into_iter()
            .step_by(OVERSAMPLE)
            .skip(SETTLE * SPR)
            .take(REVS * SPR)
            .collect();
        let sigma = 0.02 * kept.iter().fold(0.0f64, |m, x| m.max(x.abs()));
        let mut ar = 0.0;
        kept.iter()
            .map(|x| {
                ar = 0.9 * ar + (1.0f64 - 0.81).sqrt() * white.sample(&mut rng);
                x + sigma * white.sample(&mut rng) + 0.25 * sigma * ar
            })
            .collect()
    };
    let fx = channel(&series.fx);
    let fy = channel(&series.fy);
    let case = WaveformCase {
        cutter,
        cut,
        waveform: AveragedWaveform::average(0.0, SPR, &[(FrameAxis::X, &fx), (FrameAxis::Y, &fy)])
            .unwrap(),
    };
    let fit = full_signal_fit(&[case], &FullSignalOptions::default()).unwrap();
    Outcome {
        rho_um,
        fit_um: fit.offset.value * 1e3,
        se_um: fit.offset.se.unwrap() * 1e3,
        classic_um: fit.offset_se_parts.classic * 1e3,
        robust_um: fit.offset_se_parts.robust * 1e3,
        r2: fit.r_squared,
    }
}

#[test]
fn two_se_of_rho_cover_the_truth_in_90_percent_of_fits_with_an_unmodelled_mode() {
    let fits: usize = std::env::var("RUNOUT_COVERAGE_FITS")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(FITS);
    let out: Vec<Outcome> = (0..fits).into_par_iter().map(one).collect();
    let covered = |se: &dyn Fn(&Outcome) -> f64| {
        out.iter()
            .filter(|o| (o.fit_um - o.rho_um).abs() <= 2.0 * se(o))
            .count() as f64
            / out.len() as f64
    };
    let reported = covered(&|o| o.se_um);
    let classic = covered(&|o| o.classic_um);
    let robust = covered(&|o| o.robust_um);
    let mean = |f: &dyn Fn(&Outcome) -> f64| out.iter().map(f).sum::<f64>() / out.len() as f64;
    let rms_err = mean(&|o| (o.fit_um - o.rho_um).powi(2)).sqrt();
    let bias = mean(&|o| o.fit_um - o.rho_um);
    eprintln!(
        "mean error {bias:.3} µm; mean |error|/SE {:.3}",
        mean(&|o| (o.fit_um - o.rho_um).abs() / o.se_um)
    );
    eprintln!(
        "{} fits: coverage of ±2 SE: reported {:.1} %, classic {:.1} %, robust {:.1} %; \
         RMS error {:.3} µm, mean SE reported {:.3}, classic {:.3}, robust {:.3} µm; mean R² {:.4}",
        out.len(),
        100.0 * reported,
        100.0 * classic,
        100.0 * robust,
        rms_err,
        mean(&|o| o.se_um),
        mean(&|o| o.classic_um),
        mean(&|o| o.robust_um),
        mean(&|o| o.r2),
    );
    assert!(
        reported >= 0.9,
        "coverage {:.1} % (classic {:.1} %, robust {:.1} %)",
        100.0 * reported,
        100.0 * classic,
        100.0 * robust
    );
}
