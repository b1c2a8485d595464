//! First harmonic of each channel by linear least squares on (1, cos φ, sin φ), methods.md §1.6:
//! one pass over the samples accumulates the normal equations (no global search), through the
//! shared [`crate::fit::HarmonicSums`].

use super::track::SpindleTrack;
pub(crate) use crate::fit::HarmonicFit;
use crate::fit::HarmonicSums;

/// Fit every channel in `channels` (same length, indexed like the track) on the track's angles.
pub(crate) fn fit_harmonics(track: &SpindleTrack, channels: &[&[f64]]) -> Option<Vec<HarmonicFit>> {
    let shift = channels
        .iter()
        .map(|x| x.first().copied().unwrap_or(0.0))
        .collect();
    let mut sums = HarmonicSums::new(shift);
    track.for_each(|i, c, s| sums.push(c, s, channels.iter().map(|x| x[i])));
    sums.solve()
}
