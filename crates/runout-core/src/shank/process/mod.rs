//! The two-pass streaming pipeline of the shank method (methods.md §3.2 steps 1–8):
//!
//! 1. [`Survey`] (pass 1, streaming): per nominal revolution ("block") the mean and standard
//!    deviation of the raw difference x_II − x_I of each sensor pair; the first and last
//!    `max_template_revolutions` revolutions of raw samples (bounded buffers); pulse edges;
//!    clipped (flat-at-the-rail) runs.
//! 2. [`analyse`]: air-cut segments (given, or the leading/trailing runs of blocks that match the
//!    first/last revolutions, one block of margin at the cut side), spindle angle (pulse, else 1×
//!    phase advance between the air cuts), angle templates per channel, DC level (constant, or
//!    linear between the two air cuts = drift correction), runout offset + tilt (§1.6).
//! 3. [`Reconstructor`] (pass 2, streaming): δ = x − g(θ(t)) − dc(t), Δ = δ_II − δ_I,
//!    F_workpiece = −sign·K_δ·Δ (force on the workpiece, conventions.md), optional zero-phase
//!    low-pass, saturated samples flagged and their force set to NaN, optional comparison with a
//!    reference dynamometer channel; optional deconvolution of the force by the tool's bending
//!    response ([`super::Deconvolver`], before the low-pass).
//!
//! Memory: O(max_template_revolutions × samples per revolution) plus one f32 pair per pair and
//! revolution, plus the low-pass and deconvolution blocks (a few thousand samples per column),
//! independent of the record length otherwise.
//!
//! One module per concept: [`setup`] (pairs, layout), [`survey`] (pass 1), [`analysis`]
//! (between the passes), [`reconstruct`] (pass 2), [`comparison`] (against a reference).

mod analysis;
mod comparison;
mod reconstruct;
mod setup;
mod survey;

pub use analysis::*;
pub use comparison::*;
pub use reconstruct::*;
pub use setup::*;
pub use survey::*;

use super::ShankError;

/// Convenience for small records held in memory: both passes over `columns`.
/// Returns the analysis (with the resonance seen in the cut spectrum and its warning) and the
/// full output.
pub fn process_in_memory(
    setup: &ShankSetup,
    columns: &[&[f64]],
) -> Result<(ShankAnalysis, OutputBlock, Option<Vec<ComparisonMetrics>>), ShankError> {
    let mut survey = Survey::new(setup)?;
    survey.push(columns)?;
    let result = survey.finish()?;
    let mut analysis = analyse(&result)?;
    let mut rec = Reconstructor::new(&result, &analysis)?;
    let mut all = OutputBlock::default();
    let mut part = OutputBlock::default();
    rec.push(columns, &mut part)?;
    append(&mut all, &part);
    rec.finish(&mut part);
    append(&mut all, &part);
    let cmp = rec.comparison();
    analysis.spectral_resonance = rec.spectral_resonance();
    if let Some(seen) = &analysis.spectral_resonance {
        let axes: Vec<PairAxis> = setup.pairs.iter().map(|p| p.axis).collect();
        let (_, w) = super::spectral_check(
            &analysis.bandwidth,
            &setup.dynamics,
            &axes,
            seen,
            setup.sample_rate_hz,
        );
        analysis.warnings.extend(w);
    }
    Ok((analysis, all, cmp))
}

/// Append `b` to `a`.
pub fn append(a: &mut OutputBlock, b: &OutputBlock) {
    a.sample.extend_from_slice(&b.sample);
    a.time_s.extend_from_slice(&b.time_s);
    a.saturated.extend_from_slice(&b.saturated);
    for (x, y) in [
        (&mut a.force_n, &b.force_n),
        (&mut a.delta_i_um, &b.delta_i_um),
        (&mut a.delta_ii_um, &b.delta_ii_um),
        (&mut a.reference_n, &b.reference_n),
    ] {
        x.resize_with(y.len(), Vec::new);
        for (u, v) in x.iter_mut().zip(y) {
            u.extend_from_slice(v);
        }
    }
}
