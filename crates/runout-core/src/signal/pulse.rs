//! Rising-edge detection with hysteresis on a once-per-revolution or encoder channel.
//!
//! An edge is armed when the channel falls below the low threshold and fires when it then reaches
//! the high one; the edge time is the linear interpolation of the high-threshold crossing between
//! the two samples that straddle it (sub-sample timing). Noise smaller than the hysteresis band
//! (high − low) cannot produce an edge.

/// Hysteresis edge detector.
#[derive(Debug, Clone)]
pub(crate) struct EdgeDetector {
    lo: f64,
    hi: f64,
    armed: bool,
    prev: Option<(f64, f64)>,
}

impl EdgeDetector {
    /// Thresholds `lo < hi`.
    pub fn new(lo: f64, hi: f64) -> Self {
        EdgeDetector {
            lo,
            hi,
            armed: false,
            prev: None,
        }
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
                ((self.hi - vp) / (v - vp)).clamp(0.0, 1.0)
            } else {
                1.0
            };
            return Some(tp + w * (t - tp));
        }
        None
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
        let mut d = EdgeDetector::new(0.3, 0.7);
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
        let mut d = EdgeDetector::new(0.3, 0.7);
        assert_eq!(d.push(0.0, 1.0), None);
        assert_eq!(d.push(1.0, 1.0), None);
    }
}
