//! A chunk of consecutive samples of every channel, as a reader delivers them.

use super::SignalError;

/// Consecutive samples of the force channels (workpiece frame, N) and optionally a pulse channel.
///
/// All present slices must have the same length. A channel absent in the first chunk must stay
/// absent (F_z absent is averaged as 0 and reported as absent).
#[derive(Debug, Clone, Copy, Default)]
pub struct SignalChunk<'a> {
    /// F_x (N).
    pub fx: &'a [f64],
    /// F_y (N).
    pub fy: &'a [f64],
    /// F_z (N), if recorded.
    pub fz: Option<&'a [f64]>,
    /// Once-per-revolution / encoder channel (any unit), if recorded.
    pub pulse: Option<&'a [f64]>,
}

impl<'a> SignalChunk<'a> {
    /// F_x, F_y and F_z.
    pub fn xyz(fx: &'a [f64], fy: &'a [f64], fz: &'a [f64]) -> Self {
        SignalChunk {
            fx,
            fy,
            fz: Some(fz),
            pulse: None,
        }
    }
    /// The same chunk with a pulse channel.
    pub fn with_pulse(mut self, pulse: &'a [f64]) -> Self {
        self.pulse = Some(pulse);
        self
    }
    /// Number of samples.
    pub fn len(&self) -> usize {
        self.fx.len()
    }
    /// True when empty.
    pub fn is_empty(&self) -> bool {
        self.fx.is_empty()
    }
    /// Samples `a..b` of every channel.
    pub fn slice(&self, a: usize, b: usize) -> SignalChunk<'a> {
        SignalChunk {
            fx: &self.fx[a..b],
            fy: &self.fy[a..b],
            fz: self.fz.map(|v| &v[a..b]),
            pulse: self.pulse.map(|v| &v[a..b]),
        }
    }
    /// (F_x, F_y, F_z) of sample `i` (F_z = 0 when absent).
    #[inline]
    pub fn force(&self, i: usize) -> [f64; 3] {
        [self.fx[i], self.fy[i], self.fz.map_or(0.0, |v| v[i])]
    }
}

/// Checks shared by the three passes: equal lengths, stable channel set, finite values.
#[derive(Debug, Clone, Default)]
pub(crate) struct ChunkGuard {
    /// Samples seen so far (index of the next sample).
    pub next: u64,
    layout: Option<(bool, bool)>,
}

impl ChunkGuard {
    /// Validate `c` (whose first sample is `self.next`) and advance.
    pub fn check(&mut self, c: &SignalChunk, fs: f64, want_pulse: bool) -> Result<(), SignalError> {
        let n = c.fx.len();
        let start = self.next;
        let bad = |what: String| SignalError::Channels {
            sample: start,
            what,
        };
        if c.fy.len() != n
            || c.fz.is_some_and(|v| v.len() != n)
            || c.pulse.is_some_and(|v| v.len() != n)
        {
            return Err(bad(format!(
                "channel lengths differ (fx {}, fy {}, fz {:?}, pulse {:?})",
                n,
                c.fy.len(),
                c.fz.map(|v| v.len()),
                c.pulse.map(|v| v.len())
            )));
        }
        let layout = (c.fz.is_some(), c.pulse.is_some());
        match self.layout {
            None => self.layout = Some(layout),
            Some(l) if l != layout => {
                return Err(bad(format!(
                    "channel set changed (fz present {} → {}, pulse present {} → {})",
                    l.0, layout.0, l.1, layout.1
                )))
            }
            _ => {}
        }
        if want_pulse && c.pulse.is_none() {
            return Err(bad(
                "a pulse channel is configured but the chunk has none".into()
            ));
        }
        let chans: [(&'static str, Option<&[f64]>); 4] = [
            ("fx", Some(c.fx)),
            ("fy", Some(c.fy)),
            ("fz", c.fz),
            ("pulse", c.pulse),
        ];
        for (name, v) in chans {
            if let Some(v) = v {
                if let Some(i) = first_non_finite(v) {
                    let sample = start + i as u64;
                    return Err(SignalError::NonFinite {
                        channel: name,
                        sample,
                        time_s: sample as f64 / fs,
                        value: v[i],
                    });
                }
            }
        }
        self.next += n as u64;
        Ok(())
    }

    /// Whether F_z was present (after the first chunk).
    pub fn has_fz(&self) -> bool {
        self.layout.is_some_and(|l| l.0)
    }
}

/// The index of the first value of `v` that is not finite, if any. Blocks of 64 are checked
/// without an early exit (vectorised, issue 18: the guard runs on every sample of every pass),
/// and only a block holding a non-finite value is searched.
fn first_non_finite(v: &[f64]) -> Option<usize> {
    let mut at = 0;
    for block in v.chunks(64) {
        if !block.iter().fold(true, |ok, x| ok & x.is_finite()) {
            return block.iter().position(|x| !x.is_finite()).map(|i| at + i);
        }
        at += block.len();
    }
    None
}

#[cfg(test)]
mod tests {
    use super::first_non_finite;

    /// The blocked search finds the same first index as a plain scan: every length up to three
    /// blocks, a bad value (NaN, ±∞) at every position, a second one after it, and none.
    #[test]
    fn first_non_finite_is_the_first_index() {
        for len in 0..200 {
            let clean: Vec<f64> = (0..len).map(|i| i as f64 * 0.5 - 3.0).collect();
            assert_eq!(first_non_finite(&clean), None);
            for (k, bad) in [f64::NAN, f64::INFINITY, f64::NEG_INFINITY]
                .into_iter()
                .enumerate()
            {
                for at in 0..len {
                    let mut v = clean.clone();
                    v[at] = bad;
                    if at + 1 + k < len {
                        v[at + 1 + k] = f64::NAN;
                    }
                    assert_eq!(first_non_finite(&v), Some(at), "len {len}, at {at}");
                }
            }
        }
    }
}
