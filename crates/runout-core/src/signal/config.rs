//! What the pipeline is told about a recording: sample rate, teeth, nominal speed, choices.

use super::SignalError;
use crate::error::{positive, ParamError};
use serde::{Deserialize, Serialize};

/// A force component (or the resultant |F_xy|) on the workpiece (`conventions.md`, "Frames").
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum ForceComponent {
    /// F_x (feed direction).
    Fx,
    /// F_y (feed-normal direction).
    Fy,
    /// F_z (tool axis, up).
    Fz,
    /// Resultant |F_xy| = √(F_x² + F_y²).
    Fxy,
}

impl ForceComponent {
    /// All four, in the order of [`super::SyncAverage::components`].
    pub const ALL: [ForceComponent; 4] = [
        ForceComponent::Fx,
        ForceComponent::Fy,
        ForceComponent::Fz,
        ForceComponent::Fxy,
    ];

    /// Index into [`ForceComponent::ALL`].
    pub fn index(self) -> usize {
        match self {
            ForceComponent::Fx => 0,
            ForceComponent::Fy => 1,
            ForceComponent::Fz => 2,
            ForceComponent::Fxy => 3,
        }
    }

    /// Name with unit, as used in result fields (`fx_N`, …, `fxy_N`).
    pub fn name(self) -> &'static str {
        ["fx_N", "fy_N", "fz_N", "fxy_N"][self.index()]
    }

    /// Value of this component from (F_x, F_y, F_z).
    #[inline]
    pub fn of(self, f: [f64; 3]) -> f64 {
        match self {
            ForceComponent::Fx => f[0],
            ForceComponent::Fy => f[1],
            ForceComponent::Fz => f[2],
            // forces are far from overflow: the plain root is exact enough and 5× faster than hypot
            ForceComponent::Fxy => (f[0] * f[0] + f[1] * f[1]).sqrt(),
        }
    }

    /// [`Self::of`] of samples `i` = 0..`out.len()` of (`fx`, `fy`, `fz`; no `fz` = 0) into
    /// `out`, in a loop compiled for the detected instruction set, so that the roots of |F_xy|
    /// are taken several per instruction. One by one, inside the loops of passes 2 and 3, they
    /// were ≈ 10 % of pass 3 on this project's AMD EPYC (Zen 3) build machine (issue 18). A
    /// square root is correctly rounded in either form: the same bits as [`Self::of`].
    pub(crate) fn of_each(self, fx: &[f64], fy: &[f64], fz: Option<&[f64]>, out: &mut [f64]) {
        let n = out.len();
        let (fx, fy) = (&fx[..n], &fy[..n]);
        match self {
            ForceComponent::Fx => out.copy_from_slice(fx),
            ForceComponent::Fy => out.copy_from_slice(fy),
            ForceComponent::Fz => match fz {
                Some(z) => out.copy_from_slice(&z[..n]),
                None => out.fill(0.0),
            },
            ForceComponent::Fxy => pulp::Arch::new().dispatch(Modulus { x: fx, y: fy, out }),
        }
    }
}

/// The loop of [`ForceComponent::of_each`] for |F_xy|, as a [`pulp::WithSimd`] operation.
struct Modulus<'a> {
    x: &'a [f64],
    y: &'a [f64],
    out: &'a mut [f64],
}

impl pulp::WithSimd for Modulus<'_> {
    type Output = ();
    #[inline(always)]
    fn with_simd<S: pulp::Simd>(self, _simd: S) {
        for ((o, &x), &y) in self.out.iter_mut().zip(self.x).zip(self.y) {
            *o = ForceComponent::Fxy.of([x, y, 0.0]);
        }
    }
}

impl std::str::FromStr for ForceComponent {
    type Err = ParamError;
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        match s.trim().to_ascii_lowercase().as_str() {
            "fx" => Ok(ForceComponent::Fx),
            "fy" => Ok(ForceComponent::Fy),
            "fz" => Ok(ForceComponent::Fz),
            "fxy" | "|fxy|" => Ok(ForceComponent::Fxy),
            _ => Err(ParamError::new(
                "peak_component",
                "one of fx, fy, fz, fxy",
                s,
            )),
        }
    }
}

/// A once-per-revolution mark or an encoder channel (`conventions.md`, "Signals").
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PulseConfig {
    /// Rising edges per spindle revolution (1 for a once-per-rev mark, N for an N-line encoder).
    /// With N > 1 the first edge of the section is taken as the revolution start, so the angle is
    /// relative (an encoder's index channel is a once-per-rev mark: pass that for an absolute
    /// angle); the angle between edges is interpolated piecewise linearly.
    pub pulses_per_rev: usize,
    /// Spindle angle θ (rad; tooth 0's tip at immersion θ, as in `ForceSeries::angle`) at the
    /// rising edge (high-threshold crossing) of the once-per-rev mark. `None`: the angle is
    /// relative to that edge. Only with `pulses_per_rev` = 1.
    pub tooth0_angle_rad: Option<f64>,
    /// Hysteresis thresholds (low, high) in the channel's unit; `None`: 30 % and 70 % of the
    /// channel's range, found in pass 1.
    pub thresholds: Option<(f64, f64)>,
}

impl PulseConfig {
    /// A once-per-revolution mark with thresholds from the channel's range.
    pub fn once_per_rev() -> Self {
        PulseConfig {
            pulses_per_rev: 1,
            tooth0_angle_rad: None,
            thresholds: None,
        }
    }
}

/// Configuration of the signal pipeline (`SignalConfig::new` for the defaults).
#[derive(Debug, Clone, PartialEq)]
pub struct SignalConfig {
    /// Sample rate f_s (Hz).
    pub sample_rate_hz: f64,
    /// Number of teeth K.
    pub teeth: usize,
    /// Nominal spindle speed n (rpm): the search for the tooth-passing line starts at K·n/60.
    pub nominal_rpm: f64,
    /// Relative half-width of the band around K·n/60 searched for the tooth-passing line
    /// (default 0.10: the true speed must be within ±10 % of nominal).
    pub search_band: f64,
    /// Bins per revolution of the synchronous average; `None`: ≈ samples per revolution,
    /// clamped to [64, 4096].
    pub bins_per_rev: Option<usize>,
    /// Force component whose per-tooth peaks are reported (default |F_xy|).
    pub peak_component: ForceComponent,
    /// Section (from_s, to_s) to use instead of the automatic steady-cut detection.
    pub section_s: Option<(f64, f64)>,
    /// Pulse / encoder channel description, when the chunks carry one.
    pub pulse: Option<PulseConfig>,
    /// Entry immersion angle φ_st (rad) of the cut (`Cut::immersion`). With a pulse channel and
    /// `tooth0_angle_rad` it makes tooth periods absolute: tooth i owns θ ∈ [φ_st + 2πi/K,
    /// φ_st + 2π(i+1)/K) as in `force::tooth_peaks`.
    pub entry_angle_rad: Option<f64>,
    /// Subtract the air-cut mean force (the instrument's static offset, found by the steady-cut
    /// detector) before averaging (default true; nothing is subtracted when there is no air cut).
    pub subtract_air_offset: bool,
}

impl SignalConfig {
    /// Defaults for a recording at `sample_rate_hz` of a `teeth`-tooth cutter at `nominal_rpm`.
    pub fn new(sample_rate_hz: f64, teeth: usize, nominal_rpm: f64) -> Result<Self, SignalError> {
        let c = SignalConfig {
            sample_rate_hz,
            teeth,
            nominal_rpm,
            search_band: 0.10,
            bins_per_rev: None,
            peak_component: ForceComponent::Fxy,
            section_s: None,
            pulse: None,
            entry_angle_rad: None,
            subtract_air_offset: true,
        };
        c.validate()?;
        Ok(c)
    }

    /// Check every field; the accumulators call this too.
    pub fn validate(&self) -> Result<(), SignalError> {
        positive("sample_rate_hz", self.sample_rate_hz)?;
        positive("nominal_rpm", self.nominal_rpm)?;
        if self.teeth == 0 || self.teeth > 64 {
            return Err(ParamError::new("teeth", "an integer in 1..=64", self.teeth).into());
        }
        if !(self.search_band > 0.0 && self.search_band < 0.5) {
            return Err(
                ParamError::new("search_band", "a fraction in (0, 0.5)", self.search_band).into(),
            );
        }
        let tp = self.tooth_passing_hz() * (1.0 + self.search_band);
        if tp >= 0.5 * self.sample_rate_hz {
            return Err(ParamError::new(
                "sample_rate_hz",
                format!("> 2 × the tooth-passing band edge {tp:.1} Hz (Nyquist)"),
                self.sample_rate_hz,
            )
            .into());
        }
        if self.samples_per_rev() > 1e7 {
            // either may be wrong (a header's sampling rate of 1e308 Hz, a speed of 0.001 rpm):
            // the message names both
            return Err(ParamError::new(
                "sample_rate_hz, nominal_rpm",
                "a sample rate and speed giving at most 10^7 samples per revolution",
                {
                    // plain digits in the usual ranges, the exponent form outside them
                    let g = |v: f64| {
                        if (1e-4..1e9).contains(&v.abs()) {
                            format!("{v}")
                        } else {
                            format!("{v:e}")
                        }
                    };
                    format!(
                        "{} Hz at {} rpm = {:.3e} samples per revolution",
                        g(self.sample_rate_hz),
                        g(self.nominal_rpm),
                        self.samples_per_rev()
                    )
                },
            )
            .into());
        }
        if let Some(m) = self.bins_per_rev {
            if !(8..=65536).contains(&m) {
                return Err(ParamError::new("bins_per_rev", "an integer in 8..=65536", m).into());
            }
        }
        if let Some((a, b)) = self.section_s {
            if !(a.is_finite() && b.is_finite() && a >= 0.0 && b > a) {
                return Err(ParamError::new(
                    "from_s/to_s",
                    "finite times with 0 <= from_s < to_s",
                    format!("{}..{}", crate::limits::show(a), crate::limits::show(b)),
                )
                .into());
            }
        }
        if let Some(p) = &self.pulse {
            if p.pulses_per_rev == 0 || p.pulses_per_rev > 100_000 {
                return Err(ParamError::new(
                    "pulses_per_rev",
                    "an integer in 1..=100000",
                    p.pulses_per_rev,
                )
                .into());
            }
            if let Some((lo, hi)) = p.thresholds {
                if !(lo.is_finite() && hi.is_finite() && lo < hi) {
                    return Err(ParamError::new(
                        "pulse_thresholds",
                        "finite (low, high) with low < high",
                        format!("({lo}, {hi})"),
                    )
                    .into());
                }
            }
            if let Some(a) = p.tooth0_angle_rad {
                crate::error::finite("tooth0_angle_rad", a)?;
                if p.pulses_per_rev != 1 {
                    return Err(ParamError::new(
                        "tooth0_angle_rad",
                        "no tooth-0 angle with an N-line encoder (pulses_per_rev > 1): give its index channel as a once-per-rev pulse",
                        a,
                    )
                    .into());
                }
            }
        }
        if let Some(a) = self.entry_angle_rad {
            crate::error::finite("entry_angle_rad", a)?;
        }
        Ok(())
    }

    /// Nominal spindle frequency n/60 (Hz).
    pub fn spindle_hz(&self) -> f64 {
        self.nominal_rpm / 60.0
    }
    /// Nominal tooth-passing frequency K·n/60 (Hz).
    pub fn tooth_passing_hz(&self) -> f64 {
        self.teeth as f64 * self.spindle_hz()
    }
    /// Nominal samples per revolution f_s·60/n.
    pub fn samples_per_rev(&self) -> f64 {
        self.sample_rate_hz / self.spindle_hz()
    }
    /// Bins per revolution actually used.
    pub fn bins(&self) -> usize {
        self.bins_per_rev
            .unwrap_or_else(|| (self.samples_per_rev().round() as usize).clamp(64, 4096))
    }
    /// True when tooth periods are absolute (pulse with tooth-0 angle, and the entry angle).
    pub fn absolute_teeth(&self) -> bool {
        self.entry_angle_rad.is_some() && self.pulse.is_some_and(|p| p.tooth0_angle_rad.is_some())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Too many samples per revolution: the message names the sample rate and the speed (the
    /// rate of a header such as `Sampling rate [Hz]: 1e308` used to be blamed on the speed).
    #[test]
    fn too_many_samples_per_revolution_names_rate_and_speed() {
        let e = SignalConfig::new(1e308, 4, 3240.0).unwrap_err().to_string();
        assert!(e.contains("sample_rate_hz, nominal_rpm"), "{e}");
        assert!(e.contains("1e308 Hz at 3240 rpm"), "{e}");
        assert!(SignalConfig::new(1e4, 4, 3240.0).is_ok());
        let e = SignalConfig::new(1e4, 4, 1e-5).unwrap_err().to_string();
        assert!(e.contains("10000 Hz at 1e-5 rpm = 6.000e10"), "{e}");
    }

    proptest::proptest! {
        /// The vectorised [`ForceComponent::of_each`] gives the bits of [`ForceComponent::of`]
        /// for every component, with and without F_z, at any length (the vector loops' tails),
        /// for forces from 0 over subnormal to 1e150 N (|F_xy|² still finite).
        #[test]
        fn of_each_is_of_sample_by_sample(
            samples in proptest::collection::vec(
                (-1e150f64..1e150, -1e150f64..1e150, -1e150f64..1e150, 0..4u8), 0..40),
            scale in proptest::sample::select(vec![1.0, 1e-300, 1e-310]),
        ) {
            let fx: Vec<f64> = samples.iter().map(|s| s.0 * scale * f64::from(s.3 != 0)).collect();
            let fy: Vec<f64> = samples.iter().map(|s| s.1 * scale).collect();
            let fz: Vec<f64> = samples.iter().map(|s| s.2).collect();
            for c in ForceComponent::ALL {
                for z in [Some(&fz[..]), None] {
                    let mut out = vec![f64::NAN; fx.len()];
                    c.of_each(&fx, &fy, z, &mut out);
                    for (i, o) in out.iter().enumerate() {
                        let f = [fx[i], fy[i], z.map_or(0.0, |z| z[i])];
                        proptest::prop_assert_eq!(o.to_bits(), c.of(f).to_bits(), "{:?} sample {}", c, i);
                    }
                }
            }
        }
    }
}
