//! Dynamics of the shank (issue 11 item 7): F = K_δ·(δ_II − δ_I) is the static relation; the
//! tool's first bending mode limits the band in which it holds.
//!
//! **First bending mode** of the beam already used for K_δ (Euler–Bernoulli cantilever of length
//! L = l_tool, uniform E·I and mass per length m = ρ·A, A = π·d²/4, clamped at the holder face or
//! held by a rotational spring k_θ):
//!
//! f₁ = (β₁L)²/(2π) · sqrt(E·I/(ρ·A·L⁴)),   β₁L = 1.875104 for a rigid clamp
//!
//! (Timoshenko, *Vibration problems in engineering*; Blevins, *Formulas for natural frequency and
//! mode shape*, table 8-1). With a holder spring, β₁L is the first root of
//! (ch + c − s·sn)(ch + c) − (sh + sn)(sh − sn − s·c) = 0, s = 2βL/κ, κ = k_θ·L/(EI),
//! ch = cosh βL, … (w(0) = 0, EI·w''(0) = k_θ·w'(0), w''(L) = w'''(L) = 0); κ → ∞ gives
//! cos·cosh = −1, κ → 0 the rigid bar on a spring, (β₁L)⁴ → 3κ. Limits: slender beam (L/d ≳ 5;
//! shear and rotary inertia lower f₁ by a few % at L/d ≈ 5), uniform section (flutes lower E·I
//! and m; a fluted length makes f₁ lower, typically by 5–15 %), holder translation and the
//! spindle's own modes not modelled; a measured FRF or a resonance seen in the spectrum is better.
//!
//! **Sensor response.** With one mode, the deflection read at the sensors follows the force
//! through H(f) = 1/(1 − r² + 2iζr), r = f/f₁, normalised to H(0) = 1 (the static K_δ); the
//! reconstructed force is H·F. **Usable bandwidth**: the lowest frequency where the error of the
//! reconstructed harmonic |G(f)·H(f) − 1| exceeds 10 %, G = 1 without correction (for ζ ≈ 0.03
//! that is f ≈ 0.30·f₁: |H − 1| ≈ r²/(1 − r²) = 0.1 at r² = 1/11), G the deconvolution filter of
//! [`super::Deconvolver`] with one. Tooth-passing harmonics k·K·n/60 (k = 1…5) above it are
//! reported and warned about.

use super::ShankBeam;
use crate::chain::{AxisChain, Complex64, MeasuringChain};
use crate::error::ParamError;

/// Default density of a steel shank, kg/m³.
pub const STEEL_DENSITY_KG_PER_M3: f64 = 7850.0;
/// Default density of a cemented-carbide shank, kg/m³.
pub const CARBIDE_DENSITY_KG_PER_M3: f64 = 14_500.0;
/// Relative error of a reconstructed harmonic that limits the usable band (10 %).
pub const BANDWIDTH_TOLERANCE: f64 = 0.1;
/// Tooth-passing harmonics checked against the usable band (1…5).
pub const CHECKED_TOOTH_HARMONICS: usize = 5;

/// Density by material when none is given: carbide (14 500 kg/m³) for E ≥ 400 GPa (cemented
/// carbide 530–650 GPa), else steel (7 850 kg/m³; HSS and tool steels 200–230 GPa).
pub fn default_density_kg_per_m3(modulus_gpa: f64) -> f64 {
    if modulus_gpa >= 400.0 {
        CARBIDE_DENSITY_KG_PER_M3
    } else {
        STEEL_DENSITY_KG_PER_M3
    }
}

impl ShankBeam {
    /// β₁L of the first bending mode (1.875104 for a rigid clamp; see the module docs).
    pub fn first_mode_beta_l(&self) -> f64 {
        let ei = self.modulus_n_per_mm2 * self.second_moment_mm4();
        let l = self.tool_length_mm;
        let Some(k) = self.holder_rotational_stiffness_nmm_per_rad else {
            return bisect(|x| 1.0 + x.cos() * x.cosh(), 1.0, 2.5);
        };
        let kappa = k * l / ei;
        let det = |x: f64| {
            let (ch, sh, c, sn) = (x.cosh(), x.sinh(), x.cos(), x.sin());
            let s = 2.0 * x / kappa;
            (ch + c - s * sn) * (ch + c) - (sh + sn) * (sh - sn - s * c)
        };
        // det(0⁺) = 4 > 0; scan for the first sign change up to the clamped root
        let mut a = 1e-3;
        while a < 1.9 {
            let b = a + 1e-3;
            if det(a) * det(b) <= 0.0 {
                return bisect(det, a, b);
            }
            a = b;
        }
        1.875_104_068_711_961
    }

    /// First bending natural frequency f₁ = (β₁L)²/(2π)·sqrt(EI/(ρA·L⁴)), Hz, for a density in
    /// kg/m³ (module docs: formula and limits).
    pub fn first_bending_mode_hz(&self, density_kg_per_m3: f64) -> Result<f64, ParamError> {
        crate::error::positive("density_kg_per_m3", density_kg_per_m3)?;
        // N·mm² → kg·mm³/s² (1 N = 10³ kg·mm/s²); kg/m³ → kg/mm³
        let ei = self.modulus_n_per_mm2 * self.second_moment_mm4() * 1e3;
        let m = density_kg_per_m3 * 1e-9 * std::f64::consts::PI * self.diameter_mm.powi(2) / 4.0;
        let bl = self.first_mode_beta_l();
        Ok(bl * bl / std::f64::consts::TAU * (ei / (m * self.tool_length_mm.powi(4))).sqrt())
    }
}

fn bisect(f: impl Fn(f64) -> f64, mut a: f64, mut b: f64) -> f64 {
    let fa0 = f(a);
    for _ in 0..200 {
        let m = 0.5 * (a + b);
        if (f(m) > 0.0) == (fa0 > 0.0) {
            a = m;
        } else {
            b = m;
        }
    }
    0.5 * (a + b)
}

/// The dynamic model and optional correction of a shank set-up.
#[derive(Debug, Clone, PartialEq)]
pub struct ShankDynamics {
    /// Density of the tool, kg/m³ (for the beam's first bending mode).
    pub density_kg_per_m3: f64,
    /// Damping ratio assumed for the beam mode (bandwidth estimate only).
    pub beam_damping: f64,
    /// Teeth of the cutter (tooth-passing harmonics checked against the band), if known.
    pub teeth: Option<usize>,
    /// Correction of the force by deconvolution, if any.
    pub correction: Option<Correction>,
}

/// A deconvolution of the force by a chain (mode or measured FRF) per sensor-pair axis.
#[derive(Debug, Clone, PartialEq)]
pub struct Correction {
    /// H per axis (x, y used; z ignored).
    pub chain: MeasuringChain,
    /// Where H comes from (for reports).
    pub source: String,
    /// Floor ε of the regularised inverse G = (1/H)·|H|⁴/(|H|⁴ + ε⁴) (dimensionless).
    pub floor: f64,
}

impl ShankDynamics {
    /// Steel or carbide density by modulus, ζ = 0.03, teeth unknown, no correction.
    pub fn for_beam(beam: &ShankBeam) -> Self {
        Self {
            density_kg_per_m3: default_density_kg_per_m3(beam.modulus_n_per_mm2 / 1e3),
            beam_damping: 0.03,
            teeth: None,
            correction: None,
        }
    }
}

/// The regularised inverse of H: G = (1/H)·|H|⁴/(|H|⁴ + ε⁴) = H*·|H|²/(|H|⁴ + ε⁴), 0 where H is
/// unknown (above a measured FRF). Bias |G·H − 1| = ε⁴/(|H|⁴ + ε⁴): 10⁻⁴ (ε = 0.1) at |H| ≥ 1,
/// i.e. everywhere below a single mode; ≤ 10 % where |H| ≥ 9^{1/4}·ε = 1.73ε; noise gain
/// |G| ≤ 3^{3/4}/(4ε) = 0.57/ε (5.7 for ε = 0.1).
pub fn regularised_inverse(h: Option<Complex64>, floor: f64) -> Complex64 {
    match h {
        Some(h) => {
            let a2 = h.norm_sqr();
            h.conj() * (a2 / (a2 * a2 + floor.powi(4)))
        }
        None => Complex64::new(0.0, 0.0),
    }
}

/// The correction applied at `f_hz`: [`regularised_inverse`] of H, times a raised-cosine taper
/// from 1 at 0.9·f_max to 0 at f_max of a measured FRF (its impulse response stays short); 0
/// above the FRF.
pub fn correction_gain(h: &AxisChain, floor: f64, f_hz: f64) -> Complex64 {
    let taper = match h {
        AxisChain::Frf(c) => {
            let top = c.max_frequency_hz();
            let a = 0.9 * top;
            if f_hz <= a {
                1.0
            } else if f_hz >= top {
                0.0
            } else {
                0.5 * (1.0 + (std::f64::consts::PI * (f_hz - a) / (top - a)).cos())
            }
        }
        _ => 1.0,
    };
    regularised_inverse(h.response(f_hz), floor) * taper
}

/// Lowest frequency in (0, f_limit] where |G(f)·H(f) − 1| > [`BANDWIDTH_TOLERANCE`] (G = 1
/// without correction, else [`correction_gain`]; H unknown counts as exceeded); f_limit if none.
/// Scanned in steps of f_limit/20 000, refined by bisection.
pub fn usable_bandwidth_hz(h: &AxisChain, floor: Option<f64>, f_limit: f64) -> f64 {
    let bad = |f: f64| {
        let hf = h.response(f);
        let g = floor.map_or(Complex64::new(1.0, 0.0), |e| correction_gain(h, e, f));
        hf.is_none_or(|hv| (g * hv - 1.0).norm() > BANDWIDTH_TOLERANCE)
    };
    let steps = 20_000;
    let df = f_limit / steps as f64;
    for i in 1..=steps {
        let f = i as f64 * df;
        if bad(f) {
            let (mut a, mut b) = (f - df, f);
            for _ in 0..60 {
                let m = 0.5 * (a + b);
                if bad(m) {
                    b = m;
                } else {
                    a = m;
                }
            }
            return b;
        }
    }
    f_limit
}

/// Bandwidth of the force from the shank and its check against the tooth-passing harmonics.
#[derive(Debug, Clone, PartialEq)]
pub struct ShankBandwidth {
    /// First bending mode of the beam model, Hz.
    pub beam_mode_hz: f64,
    /// Damping ratio assumed for it.
    pub beam_damping: f64,
    /// Density used, kg/m³.
    pub density_kg_per_m3: f64,
    /// Usable band without correction (beam mode, |H − 1| ≤ 10 %), Hz.
    pub uncorrected_hz: f64,
    /// Usable band with the correction (|G·H − 1| ≤ 10 % for its H, smallest over the axes), Hz.
    pub corrected_hz: Option<f64>,
    /// Tooth-passing frequency K·n/60, Hz (if the teeth are known).
    pub tooth_frequency_hz: Option<f64>,
    /// Tooth-passing harmonics (k, f_k Hz), k ≤ 5, above the band in use.
    pub harmonics_beyond: Vec<(usize, f64)>,
}

impl ShankBandwidth {
    /// The band in use: corrected if a correction is applied, else uncorrected, Hz.
    pub fn usable_hz(&self) -> f64 {
        self.corrected_hz.unwrap_or(self.uncorrected_hz)
    }
}

/// Bandwidth of `beam` with `dynamics` for a spindle at `spindle_hz`, sampled at `fs`, for the
/// sensor-pair axes `axes` (x: 0, y: 1). Returns the report and its warning, if any.
pub fn bandwidth(
    beam: &ShankBeam,
    dynamics: &ShankDynamics,
    axes: &[super::PairAxis],
    spindle_hz: f64,
    fs: f64,
) -> Result<(ShankBandwidth, Option<String>), ParamError> {
    let f1 = beam.first_bending_mode_hz(dynamics.density_kg_per_m3)?;
    let mode = crate::chain::SensorMode::new(f1, dynamics.beam_damping, 1.0)?;
    let nyquist = fs / 2.0;
    let uncorrected = usable_bandwidth_hz(&AxisChain::Modes(vec![mode]), None, nyquist);
    let corrected = dynamics.correction.as_ref().map(|c| {
        axes.iter()
            .map(|a| {
                let h = match a {
                    super::PairAxis::X => &c.chain.x,
                    super::PairAxis::Y => &c.chain.y,
                };
                usable_bandwidth_hz(h, Some(c.floor), nyquist)
            })
            .fold(f64::INFINITY, f64::min)
    });
    let band = corrected.unwrap_or(uncorrected);
    let tooth = dynamics.teeth.map(|k| k as f64 * spindle_hz);
    let beyond: Vec<(usize, f64)> = tooth
        .map(|ft| {
            (1..=CHECKED_TOOTH_HARMONICS)
                .map(|k| (k, k as f64 * ft))
                .filter(|&(_, f)| f > band)
                .collect()
        })
        .unwrap_or_default();
    let warning = beyond.first().map(|&(k0, f0)| {
        let (k1, f1h) = *beyond.last().expect("non-empty");
        let range = if k0 == k1 {
            format!("{k0} ({f0:.0} Hz)")
        } else {
            format!("{k0}–{k1} ({f0:.0}–{f1h:.0} Hz)")
        };
        match &dynamics.correction {
            None => format!(
                "tooth-passing harmonics {range} lie above the usable bandwidth {uncorrected:.0} Hz \
                 of the static relation F = K_delta*Delta (first bending mode of the tool \
                 {f1:.0} Hz from the beam model, damping {:.2}; the force harmonic there is off \
                 by more than 10 %): correct with [dynamics] sensor_mode_hz (\"beam\" or a \
                 measured resonance, Hz) or frf, or set lowpass_hz below {uncorrected:.0} Hz",
                dynamics.beam_damping
            ),
            Some(c) => format!(
                "tooth-passing harmonics {range} lie above the corrected bandwidth {band:.0} Hz \
                 ({}: |H| below {:.2} of the static response, the deconvolution fades out): \
                 those harmonics of the force are not recovered",
                c.source,
                9f64.powf(0.25) * c.floor
            ),
        }
    });
    Ok((
        ShankBandwidth {
            beam_mode_hz: f1,
            beam_damping: dynamics.beam_damping,
            density_kg_per_m3: dynamics.density_kg_per_m3,
            uncorrected_hz: uncorrected,
            corrected_hz: corrected,
            tooth_frequency_hz: tooth,
            harmonics_beyond: beyond,
        },
        warning,
    ))
}

/// Frequency of the largest |H| of a chain below `f_limit` (its resonance), Hz; `None` for a
/// rigid chain. Scanned in steps of f_limit/20 000.
pub fn chain_peak_hz(h: &AxisChain, f_limit: f64) -> Option<f64> {
    if h.is_rigid() {
        return None;
    }
    (1..=20_000)
        .map(|i| i as f64 * f_limit / 20_000.0)
        .filter_map(|f| h.response(f).map(|v| (f, v.norm())))
        .max_by(|a, b| a.1.total_cmp(&b.1))
        .map(|p| p.0)
}

/// What a resonance seen in the cut spectrum ([`super::SpectralResonance`]) says about the
/// set-up: the usable band of the static relation with that mode (fitted damping, else the beam
/// damping) and a warning when tooth-passing harmonics lie above it without a correction, or when
/// a correction's resonance is more than 5 % away from the one seen.
pub fn spectral_check(
    band: &ShankBandwidth,
    dynamics: &ShankDynamics,
    axes: &[super::PairAxis],
    seen: &super::SpectralResonance,
    fs: f64,
) -> (f64, Option<String>) {
    let zeta = seen.damping.unwrap_or(dynamics.beam_damping);
    let usable = crate::chain::SensorMode::new(seen.frequency_hz, zeta, 1.0)
        .map(|m| usable_bandwidth_hz(&AxisChain::Modes(vec![m]), None, fs / 2.0))
        .unwrap_or(f64::NAN);
    let f_r = seen.frequency_hz;
    let seen_text = format!(
        "a resonance at {f_r:.0} Hz (damping {}) is seen in the cut spectrum ({:.0}× above the broadband level; beam model {:.0} Hz)",
        seen.damping.map_or("not fitted".to_string(), |z| format!("{z:.3}")),
        seen.prominence,
        band.beam_mode_hz
    );
    let warning = match &dynamics.correction {
        None => {
            let beyond: Vec<(usize, f64)> = band
                .tooth_frequency_hz
                .map(|ft| {
                    (1..=CHECKED_TOOTH_HARMONICS)
                        .map(|k| (k, k as f64 * ft))
                        .filter(|&(_, f)| f > usable)
                        .collect()
                })
                .unwrap_or_default();
            (!beyond.is_empty() || (f_r / band.beam_mode_hz - 1.0).abs() > 0.2).then(|| {
                let harmonics = if beyond.is_empty() {
                    String::new()
                } else {
                    format!(
                        "; tooth-passing harmonics {} lie above it",
                        beyond
                            .iter()
                            .map(|(k, f)| format!("{k} ({f:.0} Hz)"))
                            .collect::<Vec<_>>()
                            .join(", ")
                    )
                };
                format!(
                    "{seen_text}: with it the static relation is usable to {usable:.0} Hz{harmonics}; \
                     correct with [dynamics] sensor_mode_hz = {f_r:.0} (sensor_damping = {zeta:.3}) \
                     or a measured FRF"
                )
            })
        }
        Some(c) => {
            let fs2 = fs / 2.0;
            let peaks: Vec<f64> = axes
                .iter()
                .filter_map(|a| {
                    chain_peak_hz(
                        match a {
                            super::PairAxis::X => &c.chain.x,
                            super::PairAxis::Y => &c.chain.y,
                        },
                        fs2,
                    )
                })
                .collect();
            peaks
                .iter()
                .find(|p| (f_r / **p - 1.0).abs() > 0.05)
                .map(|p| {
                    format!(
                        "{seen_text}, but the correction ({}) has its resonance at {p:.0} Hz: \
                         the corrected force is wrong near both; check the correction",
                        c.source
                    )
                })
        }
    };
    (usable, warning)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn clamped_root_and_soft_holder_limit() {
        let beam = ShankBeam::new(210.0, 8.0, 65.0, 10.0, 30.0).unwrap();
        assert!((beam.first_mode_beta_l() - 1.875_104_068_711_961).abs() < 1e-12);
        // very stiff holder → clamped; very soft → rigid bar on a spring, (βL)⁴ = 3κ
        let ei = beam.modulus_n_per_mm2 * beam.second_moment_mm4();
        let stiff = beam.with_holder_stiffness(1e6 * ei / 65.0).unwrap();
        assert!((stiff.first_mode_beta_l() - 1.875104).abs() < 1e-5);
        // (κ = k_θ·L/EI = 1e-3 on a 40 mm shank: k_θ = 400 N·m/rad, above the 1 N·m/rad floor
        // of `limits`, which the 8 mm shank's 0.65 N·m/rad is not)
        let kappa = 1e-3;
        let thick = ShankBeam::new(210.0, 40.0, 65.0, 10.0, 30.0).unwrap();
        let ei = thick.modulus_n_per_mm2 * thick.second_moment_mm4();
        let soft = thick.with_holder_stiffness(kappa * ei / 65.0).unwrap();
        let want = (3.0 * kappa).powf(0.25);
        assert!(
            (soft.first_mode_beta_l() / want - 1.0).abs() < 1e-3,
            "{} vs {want}",
            soft.first_mode_beta_l()
        );
    }

    #[test]
    fn regularised_inverse_properties() {
        let eps = 0.1;
        // DC exact to ε⁴, 10 % bias at |H| = 1.73ε, bounded gain
        let g = regularised_inverse(Some(Complex64::new(1.0, 0.0)), eps);
        assert!((g.re - 1.0).abs() < 1.01e-4 && g.im == 0.0);
        let h = Complex64::new(0.0, 9f64.powf(0.25) * eps);
        assert!(((regularised_inverse(Some(h), eps) * h - 1.0).norm() - 0.1).abs() < 1e-12);
        let max = (1..10_000)
            .map(|i| regularised_inverse(Some(Complex64::new(i as f64 * 1e-4, 0.0)), eps).norm())
            .fold(0.0, f64::max);
        assert!((max - 3f64.powf(0.75) / (4.0 * eps)).abs() < 1e-3, "{max}");
    }

    /// A measured FRF limits the corrected band to where its taper keeps the gain within 10 %:
    /// 0.5·(1 + cos πx) = 0.9 at x = 0.205 of the top 10 %, i.e. 1841 Hz for a table to 2 kHz.
    #[test]
    fn measured_frf_band_ends_in_its_taper() {
        let m = crate::chain::SensorMode::new(900.0, 0.03, 1.0).unwrap();
        let freq: Vec<f64> = (0..=400).map(|i| i as f64 * 5.0).collect();
        let vals = freq.iter().map(|&f| m.unit_response(f)).collect();
        let frf = AxisChain::Frf(crate::chain::FrfCurve::new("frf", freq, vals).unwrap());
        let band = usable_bandwidth_hz(&frf, Some(0.1), 10_000.0);
        // (less ≈ 2 Hz: the regularisation's own 1 % bias at |H(1840 Hz)| = 0.31 adds to it)
        let x = 0.8f64.acos() / std::f64::consts::PI;
        assert!((band - (1800.0 + 200.0 * x)).abs() < 5.0, "{band}");
        // the same mode as a model reaches ≈ 2.6·f₁
        let model = usable_bandwidth_hz(&AxisChain::Modes(vec![m]), Some(0.1), 10_000.0);
        assert!(model > 2300.0, "{model}");
    }
}
