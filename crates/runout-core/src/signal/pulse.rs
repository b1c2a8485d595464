//! The one rising-edge detector of the project (once-per-revolution or encoder channels), used by
//! the streaming signal chain (`signal`), the shank method (`shank`) and the displacement signal
//! method (`displacement::signal`).
//!
//! Behaviour, for thresholds `low ≤ high` and an interpolation `level`:
//! * **hysteresis**: the detector is armed by a sample strictly below `low` and fires at the first
//!   following sample at or above `high`; it is then disarmed until the channel is below `low`
//!   again. Noise smaller than the band high − low cannot produce an edge; with `low = high` there
//!   is no hysteresis (every upward crossing is an edge).
//! * **edge time**: the linear interpolation of the `level` crossing between the previous sample
//!   (t_p, v_p) and the firing one (t, v): t_p + w·(t − t_p), w = clamp((level − v_p)/(v − v_p),
//!   0, 1) (w = 1 if v ≤ v_p); sub-sample timing.
//! * a channel already high at the start is not an edge (nothing armed it); the first sample
//!   cannot fire (no previous sample).
//!
//! The three threshold policies in use (see `tests::the_three_policies_on_the_same_signals`):
//! [`PulseEdgeDetector::new`] with explicit thresholds (the signal chain uses 30 % / 70 % of the
//! range, edge at the 70 % crossing), [`PulseEdgeDetector::mid_with_hysteresis`] (shank: mid ±10 %
//! of the swing, edge at mid) and [`PulseEdgeDetector::mid_level`] (displacement: mid, no
//! hysteresis, edge at mid).

/// Hysteresis rising-edge detector (module docs).
#[derive(Debug, Clone)]
pub struct PulseEdgeDetector {
    lo: f64,
    hi: f64,
    level: f64,
    armed: bool,
    prev: Option<(f64, f64)>,
}

impl PulseEdgeDetector {
    /// Thresholds `lo < hi`; the edge time is the interpolated crossing of `hi`.
    pub fn new(lo: f64, hi: f64) -> Self {
        Self::with_level(lo, hi, hi)
    }

    /// Thresholds `lo ≤ hi` and the interpolation level of the edge time.
    pub fn with_level(lo: f64, hi: f64, level: f64) -> Self {
        PulseEdgeDetector {
            lo,
            hi,
            level,
            armed: false,
            prev: None,
        }
    }

    /// Thresholds halfway between `min` and `max` of the channel ± 10 % of the swing; edge time
    /// at the mid level. `None` if the channel does not swing.
    pub fn mid_with_hysteresis(min: f64, max: f64) -> Option<Self> {
        let swing = max - min;
        if !(swing.is_finite() && swing > 0.0) {
            return None;
        }
        let mid = (min + max) / 2.0;
        let (hi, lo) = (mid + 0.1 * swing, mid - 0.1 * swing);
        Some(Self::with_level(lo, hi, (hi + lo) / 2.0))
    }

    /// One threshold at the mid level 0.5·(min + max), no hysteresis; edge time at that level.
    pub fn mid_level(min: f64, max: f64) -> Self {
        let thr = 0.5 * (min + max);
        Self::with_level(thr, thr, thr)
    }

    /// Feed the value `v` at time `t` (s); returns the time of a rising edge ending here.
    #[inline]
    pub fn push(&mut self, t: f64, v: f64) -> Option<f64> {
        let prev = self.prev.replace((t, v));
        if v < self.lo {
            self.armed = true;
            return None;
        }
        if self.armed && v >= self.hi {
            self.armed = false;
            let (tp, vp) = prev?;
            let w = if v > vp {
                ((self.level - vp) / (v - vp)).clamp(0.0, 1.0)
            } else {
                1.0
            };
            return Some(tp + w * (t - tp));
        }
        None
    }

    /// All edge times of a channel given as (t, v) samples.
    pub fn edges(mut self, samples: impl IntoIterator<Item = (f64, f64)>) -> Vec<f64> {
        samples
            .into_iter()
            .filter_map(|(t, v)| self.push(t, v))
            .collect()
    }
}

/// Running minimum and maximum of the pulse channel (pass 1), to set the thresholds.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Range {
    pub min: f64,
    pub max: f64,
}

impl Default for Range {
    fn default() -> Self {
        Range {
            min: f64::INFINITY,
            max: f64::NEG_INFINITY,
        }
    }
}

impl Range {
    #[inline]
    pub fn push(&mut self, v: f64) {
        self.min = self.min.min(v);
        self.max = self.max.max(v);
    }
    /// Thresholds at 30 % and 70 % of the range, or None when the channel is flat.
    pub fn thresholds(&self) -> Option<(f64, f64)> {
        let d = self.max - self.min;
        (d > 0.0 && d.is_finite()).then_some((self.min + 0.3 * d, self.min + 0.7 * d))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn edge_time_is_interpolated_and_noise_is_ignored() {
        let mut d = PulseEdgeDetector::new(0.3, 0.7);
        // ramp from 0 to 1 between t = 1 and t = 2: the 0.7 crossing is at t = 1.7
        let samples = [
            (0.0, 0.0),
            (1.0, 0.0),
            (2.0, 1.0),
            (3.0, 0.6),
            (4.0, 0.9),
            (5.0, 0.1),
            (6.0, 0.8),
        ];
        let edges: Vec<f64> = samples.iter().filter_map(|&(t, v)| d.push(t, v)).collect();
        // the dip to 0.6 stays above 0.3: no re-arm, no edge at t = 4
        assert_eq!(edges.len(), 2);
        assert!((edges[0] - 1.7).abs() < 1e-12);
        assert!((edges[1] - (5.0 + 0.6 / 0.7)).abs() < 1e-12);
    }

    #[test]
    fn a_pulse_high_at_the_start_is_not_an_edge() {
        let mut d = PulseEdgeDetector::new(0.3, 0.7);
        assert_eq!(d.push(0.0, 1.0), None);
        assert_eq!(d.push(1.0, 1.0), None);
    }

    /// The signals the three former detectors (signal chain, shank, displacement) saw, through
    /// the three threshold policies; the differences are stated, each assertion could fail.
    #[test]
    fn the_three_policies_on_the_same_signals() {
        let signal_chain = |x: &[f64]| {
            let (lo, hi) = range(x);
            let d = hi - lo;
            PulseEdgeDetector::new(lo + 0.3 * d, lo + 0.7 * d).edges(idx(x))
        };
        let shank = |x: &[f64]| {
            let (lo, hi) = range(x);
            PulseEdgeDetector::mid_with_hysteresis(lo, hi)
                .unwrap()
                .edges(idx(x))
        };
        let displacement = |x: &[f64]| {
            let (lo, hi) = range(x);
            PulseEdgeDetector::mid_level(lo, hi).edges(idx(x))
        };
        // 1. clean square pulse 0/5 V, 100 samples per revolution, 10 high: one sample rise, so
        //    all three fire at the same sample; times differ inside it by the level: the
        //    chain interpolates 70 % (3.5 V), the others 50 % (2.5 V) of the 0 → 5 step.
        let square: Vec<f64> = (0..1000)
            .map(|i| if i % 100 < 10 { 5.0 } else { 0.0 })
            .collect();
        let (a, b, c) = (signal_chain(&square), shank(&square), displacement(&square));
        assert_eq!((a.len(), b.len(), c.len()), (9, 9, 9)); // high at the start: not an edge
        for i in 0..9 {
            let step = (100 * (i + 1)) as f64;
            assert!((a[i] - (step - 1.0 + 0.7)).abs() < 1e-12);
            assert!((b[i] - (step - 1.0 + 0.5)).abs() < 1e-12);
            assert!((c[i] - (step - 1.0 + 0.5)).abs() < 1e-12);
        }
        // 2. slow ramp 0 → 1 over 20 samples: the displacement policy finds the 50 % crossing
        //    (sample 10); the chain the 70 % one, 0.2 of the rise = 4 samples later; the shank
        //    policy fires at 60 % (sample 12) and interpolates 50 % only between samples 11 and
        //    12, so its time clamps to sample 11: 1 sample late on edges slower than the band.
        let ramp: Vec<f64> = (0..400)
            .map(|i| ((i % 100) as f64 / 20.0).min(1.0) * f64::from(u8::from(i % 100 < 50)))
            .collect();
        let (a, b, c) = (signal_chain(&ramp), shank(&ramp), displacement(&ramp));
        assert_eq!((a.len(), b.len(), c.len()), (4, 4, 4)); // low at the start: armed
        for i in 0..4 {
            let r = (100 * i) as f64;
            assert!((c[i] - (r + 10.0)).abs() < 1e-9, "{c:?}");
            assert!((b[i] - (r + 11.0)).abs() < 1e-9, "{b:?}");
            assert!((a[i] - (r + 14.0)).abs() < 1e-9, "{a:?}");
        }
        // 3. chatter of ±0.3 V around the mid level on every rise: the hysteresis policies see
        //    one edge per revolution; the displacement policy (no hysteresis) sees three.
        let chatter: Vec<f64> = (0..400)
            .map(|i| match i % 100 {
                0..=4 => 0.0,
                5 => 2.8,
                6 => 2.2,
                7 => 2.8,
                8 => 2.2,
                9..=30 => 5.0,
                _ => 0.0,
            })
            .collect();
        let (a, b, c) = (
            signal_chain(&chatter),
            shank(&chatter),
            displacement(&chatter),
        );
        assert_eq!((a.len(), b.len(), c.len()), (4, 4, 12));
    }

    fn range(x: &[f64]) -> (f64, f64) {
        x.iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &v| {
                (a.min(v), b.max(v))
            })
    }

    fn idx(x: &[f64]) -> impl Iterator<Item = (f64, f64)> + '_ {
        x.iter().enumerate().map(|(i, &v)| (i as f64, v))
    }
}
