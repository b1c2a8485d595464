//! Between the passes (methods.md §3.2 steps 2–5): air cuts, spindle angle, templates, DC level, runout.

// Column-major data (`columns[c][k]`) reads clearest with index loops.
#![allow(clippy::needless_range_loop)]

use super::super::spindle::{frequency_from_air, PhaseSegment, SpindlePhase};
use super::super::template::{AngleTemplate, TemplateBuilder};
use super::super::ShankError;
#[allow(unused_imports)]
use super::*;
use crate::fit::{fit_offset_tilt, LineNoise, OffsetTiltFit};

/// Runout of the tool from the air-cut templates (methods.md §3.2 end, §1.6).
#[derive(Debug, Clone, PartialEq)]
pub struct ShankRunout {
    /// The line e(z) = e₀ + z·τ through the templates' first harmonics at the two sensor heights
    /// of every pair (z above the tip, spindle frame, angle from θ = 0), with standard errors from
    /// the templates' own first-harmonic errors ([`LineNoise::Known`]). e₀ is the offset at the
    /// tool tip (mm), τ = dE/dz the tilt (mm/mm).
    pub line: OffsetTiltFit,
    /// Height above the tip of the reported offset, mm.
    pub cutting_height_mm: f64,
    /// Per pair and height: (z above tip mm, E re, E im) in the spindle frame, mm.
    pub at_sensors: Vec<(f64, f64, f64)>,
}

impl ShankRunout {
    /// Offset vector at the cutting height (re, im) = ρ·e^{jλ}, mm; angle from θ = 0.
    pub fn offset_mm(&self) -> [f64; 2] {
        self.line.at(self.cutting_height_mm)
    }

    /// Standard error per component of the offset at the cutting height, mm (the template noise is
    /// isotropic, so both components have the same).
    pub fn offset_se_mm(&self) -> f64 {
        self.line
            .at_variance(self.cutting_height_mm)
            .map_or(f64::NAN, |v| v[0].sqrt())
    }

    /// Offset at the tool tip (z = 0), mm.
    pub fn tip_offset_mm(&self) -> [f64; 2] {
        self.line.offset_mm()
    }

    /// Standard error per component of the tilt, mm/mm.
    pub fn tilt_se(&self) -> f64 {
        self.line.tilt[0].se.unwrap_or(f64::NAN)
    }

    /// Offset magnitude ρ at the cutting height, mm.
    pub fn offset_magnitude_mm(&self) -> f64 {
        let [x, y] = self.offset_mm();
        x.hypot(y)
    }

    /// Offset angle λ from the θ = 0 reference, rad (wrapped to (−π, π]).
    pub fn offset_angle_rad(&self) -> f64 {
        let [x, y] = self.offset_mm();
        y.atan2(x)
    }

    /// Tilt magnitude, mm/mm.
    pub fn tilt_magnitude(&self) -> f64 {
        let [x, y] = self.line.tilt_vector();
        x.hypot(y)
    }

    /// Tilt direction, rad.
    pub fn tilt_angle_rad(&self) -> f64 {
        let [x, y] = self.line.tilt_vector();
        y.atan2(x)
    }
}

/// DC level of a channel: constant, or linear between two times (constant outside).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DcLevel {
    /// (time s, level mm) at the first air cut.
    pub a: (f64, f64),
    /// (time s, level mm) at the second air cut (= a if constant).
    pub b: (f64, f64),
}

impl DcLevel {
    /// Level at time t, mm.
    pub fn at(&self, t: f64) -> f64 {
        if self.b.0 <= self.a.0 || t <= self.a.0 {
            self.a.1
        } else if t >= self.b.0 {
            self.b.1
        } else {
            self.a.1 + (self.b.1 - self.a.1) * (t - self.a.0) / (self.b.0 - self.a.0)
        }
    }
}

/// Result of the analysis between the two passes.
#[derive(Debug, Clone)]
pub struct ShankAnalysis {
    /// Air-cut segments used (before and after the cut).
    pub air_segments: Vec<SampleRange>,
    /// Samples between the air cuts (the cut), if any.
    pub cut: Option<SampleRange>,
    /// Air revolutions found before and after the cut (detection), for messages.
    pub air_revolutions_found: (usize, usize),
    /// Spindle angle.
    pub spindle: SpindlePhase,
    /// One template per displacement channel (pair 0 I, pair 0 II, …).
    pub templates: Vec<AngleTemplate>,
    /// DC level per displacement channel.
    pub dc: Vec<DcLevel>,
    /// Runout from the templates.
    pub runout: ShankRunout,
    /// Clipped sample ranges (merged over channels).
    pub saturated: Vec<SampleRange>,
    /// Samples flagged as saturated (clipped runs + out-of-range).
    pub saturated_samples: u64,
    /// Non-fatal findings.
    pub warnings: Vec<String>,
    /// K_δ, N/mm.
    pub stiffness_n_per_mm: f64,
    /// RMS of x − g − dc over the air cuts per channel (template quality), mm.
    pub air_residual_rms_mm: Vec<f64>,
    /// First bending mode, usable bandwidth and tooth-passing check (issue 11 item 7).
    pub bandwidth: super::super::ShankBandwidth,
    /// Resonance seen in the cut spectrum (set after pass 2 by [`process_in_memory`], or from
    /// [`Reconstructor::spectral_resonance`]).
    pub spectral_resonance: Option<super::super::SpectralResonance>,
}

/// Detect the air cuts from the block statistics (see the module docs).
fn detect_air(survey: &SurveyResult) -> Result<(Vec<SampleRange>, (usize, usize)), ShankError> {
    let s = &survey.setup;
    let np = s.pairs.len();
    let nb = survey.blocks.len() / np;
    let m0 = s.min_air_revolutions;
    let l = survey.block_len as u64;
    if nb < m0 {
        return Err(ShankError::NoAirCut(format!(
            "the record has {nb} revolutions; at least {m0} air-cut revolutions are needed"
        )));
    }
    let stat = |b: usize, d: usize| survey.blocks[b * np + d];
    let median = |v: &mut Vec<f64>| {
        v.sort_by(f64::total_cmp);
        v[v.len() / 2]
    };
    // noise of the raw difference from the head's first blocks (first differences / √2)
    let noise: Vec<f64> = (0..np)
        .map(|d| {
            let (a, b) = (&survey.head[2 * d], &survey.head[2 * d + 1]);
            let n = (m0 * survey.block_len).min(a.len());
            let diffs: Vec<f64> = (1..n)
                .map(|k| (b[k] - a[k]) - (b[k - 1] - a[k - 1]))
                .collect();
            let ms = diffs.iter().map(|v| v * v).sum::<f64>() / diffs.len().max(1) as f64;
            (ms / 2.0).sqrt()
        })
        .collect();
    let base = |range: std::ops::Range<usize>, d: usize| {
        let mut m: Vec<f64> = range.clone().map(|b| f64::from(stat(b, d).0)).collect();
        let mut sd: Vec<f64> = range.map(|b| f64::from(stat(b, d).1)).collect();
        (median(&mut m), median(&mut sd))
    };
    let start: Vec<(f64, f64)> = (0..np).map(|d| base(0..m0, d)).collect();
    let end: Vec<(f64, f64)> = (0..np).map(|d| base(nb - m0..nb, d)).collect();
    let tol: Vec<f64> = (0..np)
        .map(|d| (0.1 * start[d].1).max(8.0 * noise[d]).max(1e-6))
        .collect();
    let is_air = |b: usize, base: &[(f64, f64)]| {
        (0..np).all(|d| {
            let (m, sd) = stat(b, d);
            (f64::from(m) - base[d].0).abs() <= tol[d]
                && (f64::from(sd) - start[d].1).abs() <= tol[d]
        })
    };
    if !(0..m0).all(|b| is_air(b, &start)) {
        return Err(ShankError::NoAirCut(format!(
            "the first {m0} revolutions differ from each other by more than the tolerance \
             ({:.3} µm): the record does not start with a stable air cut; give air_cut_s",
            tol[0] * 1e3
        )));
    }
    let lead = (0..nb).take_while(|&b| is_air(b, &start)).count();
    if lead == nb {
        return Ok((
            vec![SampleRange {
                start: 0,
                end: survey.samples,
            }],
            (nb, 0),
        ));
    }
    let trail = (0..nb).rev().take_while(|&b| is_air(b, &end)).count();
    let before = lead.saturating_sub(1);
    let after = trail.saturating_sub(1);
    let mut segs = Vec::new();
    if before >= m0 {
        segs.push(SampleRange {
            start: 0,
            end: before as u64 * l,
        });
    }
    if after >= m0 {
        let start = (nb - after) as u64 * l;
        segs.push(SampleRange {
            start,
            end: survey.samples,
        });
    }
    if segs.is_empty() {
        return Err(ShankError::NoAirCut(format!(
            "found {lead} air-cut revolutions before the cut and {trail} after (1 of each is \
             margin); at least {m0} stable revolutions are needed; record the spindle running \
             idle before the cut or give air_cut_s"
        )));
    }
    Ok((segs, (lead, trail)))
}

/// Between the passes: segments, spindle angle, templates, DC, runout (see the module docs).
pub fn analyse(survey: &SurveyResult) -> Result<ShankAnalysis, ShankError> {
    let s = &survey.setup;
    let fs = s.sample_rate_hz;
    let dt = 1.0 / fs;
    let nd = s.displacement_channels();
    let mut warnings = Vec::new();
    let (mut segments, found) = if s.air_cut_s.is_empty() {
        detect_air(survey)?
    } else {
        let segs: Vec<SampleRange> = survey
            .given
            .iter()
            .map(|(r, _)| SampleRange {
                // a window past the end of the recording is empty (and refused below)
                start: r.start.min(survey.samples),
                end: r.end.min(survey.samples).max(r.start.min(survey.samples)),
            })
            .collect();
        let spr = s.samples_per_rev();
        for r in &segs {
            if (r.len() as f64) < s.min_air_revolutions as f64 * spr {
                return Err(ShankError::NoAirCut(format!(
                    "the given air cut {:.4}–{:.4} s holds {:.1} revolutions; at least {} are needed",
                    s.start_time_s + r.start as f64 * dt,
                    s.start_time_s + r.end as f64 * dt,
                    r.len() as f64 / spr,
                    s.min_air_revolutions
                )));
            }
        }
        (segs, (0, 0))
    };
    let cut = if segments.len() == 2 {
        Some(SampleRange {
            start: segments[0].end,
            end: segments[1].start,
        })
    } else if segments[0].start == 0 && segments[0].end < survey.samples {
        Some(SampleRange {
            start: segments[0].end,
            end: survey.samples,
        })
    } else if segments[0].start > 0 {
        Some(SampleRange {
            start: 0,
            end: segments[0].start,
        })
    } else {
        None
    };
    // bound the data used per segment: the first revolutions of a leading or given segment,
    // the last ones of a trailing segment (all held in the pass-1 buffers)
    let cap = (s.max_template_revolutions as f64 * s.samples_per_rev()).ceil() as u64;
    for r in segments.iter_mut() {
        if r.start == 0 || !s.air_cut_s.is_empty() {
            r.end = r.end.min(r.start + cap);
        } else {
            r.start = r.start.max(r.end.saturating_sub(cap));
        }
    }
    let data: Vec<Vec<Vec<f64>>> = segments
        .iter()
        .map(|r| {
            survey.samples_of(*r).ok_or_else(|| {
                ShankError::Input(format!(
                    "air-cut samples {}–{} were not kept in memory",
                    r.start, r.end
                ))
            })
        })
        .collect::<Result<_, _>>()?;
    if segments.len() == 1 && cut.is_some() {
        warnings.push(
            "only one air-cut segment: the spindle speed comes from that segment alone and no \
             drift correction is possible; record an idle segment after the cut too"
                .into(),
        );
    }
    // spindle angle
    let f_nom = s.nominal_rpm / 60.0;
    let spindle = match &survey.pulse_edges_s {
        Some(e) if e.len() >= 2 => SpindlePhase::Pulses { edges_s: e.clone() },
        _ => {
            if s.has_pulse {
                warnings.push("the pulse channel has fewer than 2 edges; spindle angle estimated from the 1× component instead".into());
            }
            // reference channel: the one with the largest 1× amplitude in the first segment
            let best = (0..nd)
                .max_by(|&a, &b| {
                    let pa = super::super::spindle::phasor(&data[0][a], 0.0, fs, f_nom).0;
                    let pb = super::super::spindle::phasor(&data[0][b], 0.0, fs, f_nom).0;
                    pa.total_cmp(&pb)
                })
                .unwrap_or(0);
            let segs: Vec<PhaseSegment> = segments
                .iter()
                .zip(&data)
                .map(|(r, d)| PhaseSegment {
                    x: &d[best],
                    t_start: s.start_time_s + r.start as f64 * dt,
                })
                .collect();
            let (f, se, source) = frequency_from_air(&segs, fs, f_nom);
            SpindlePhase::Constant {
                frequency_hz: f,
                frequency_se_hz: se,
                t0_s: s.start_time_s,
                source,
            }
        }
    };
    let f_est = spindle.mean_frequency_hz();
    if ((f_est - f_nom) / f_nom).abs() > 0.02 {
        warnings.push(format!(
            "spindle speed {:.2} rpm differs from the nominal {:.2} rpm by more than 2 %",
            f_est * 60.0,
            s.nominal_rpm
        ));
    }
    // templates
    let spr = fs / f_est;
    let bins = if s.template_bins > 0 {
        s.template_bins
    } else {
        ((spr / 2.0).floor() as usize).clamp(16, 2048)
    };
    let mut builders: Vec<TemplateBuilder> = (0..nd).map(|_| TemplateBuilder::new(bins)).collect();
    let sat = saturated_ranges(survey);
    for (r, d) in segments.iter().zip(&data) {
        let mut hint = 0;
        let mut sp = 0;
        for k in 0..d[0].len() {
            let n = r.start + k as u64;
            if is_in(&sat, n, &mut sp) {
                continue;
            }
            let th = spindle.angle(s.start_time_s + n as f64 * dt, &mut hint);
            for (c, b) in builders.iter_mut().enumerate() {
                b.push(th, d[c][k]);
            }
        }
    }
    let templates: Vec<AngleTemplate> = builders
        .into_iter()
        .map(|b| b.finish(spr))
        .collect::<Option<_>>()
        .ok_or_else(|| {
            ShankError::NoAirCut("the air-cut segments hold no usable samples".into())
        })?;
    let revs = templates[0].revolutions;
    if revs < s.min_air_revolutions {
        return Err(ShankError::NoAirCut(format!(
            "the air cuts hold {revs} complete revolutions; at least {} are needed",
            s.min_air_revolutions
        )));
    }
    // DC level per segment, drift line
    let mut dc = Vec::new();
    let mut air_rms = Vec::new();
    for c in 0..nd {
        let mut levels = Vec::new();
        let (mut ss, mut cnt) = (0.0, 0usize);
        for (r, d) in segments.iter().zip(&data) {
            let mut hint = 0;
            let mut acc = 0.0;
            for (k, v) in d[c].iter().enumerate() {
                let t = s.start_time_s + (r.start + k as u64) as f64 * dt;
                acc += v - templates[c].value(spindle.angle(t, &mut hint));
            }
            let level = acc / d[c].len() as f64;
            let tc = s.start_time_s + (r.start as f64 + r.len() as f64 / 2.0) * dt;
            levels.push((tc, level, d[c].len() as f64));
        }
        let level = if s.drift_correction && levels.len() == 2 {
            DcLevel {
                a: (levels[0].0, levels[0].1),
                b: (levels[1].0, levels[1].1),
            }
        } else {
            let w: f64 = levels.iter().map(|l| l.2).sum();
            let m = levels.iter().map(|l| l.1 * l.2).sum::<f64>() / w;
            DcLevel {
                a: (levels[0].0, m),
                b: (levels[0].0, m),
            }
        };
        for (r, d) in segments.iter().zip(&data) {
            let mut hint = 0;
            for (k, v) in d[c].iter().enumerate() {
                let t = s.start_time_s + (r.start + k as u64) as f64 * dt;
                let e = v - templates[c].value(spindle.angle(t, &mut hint)) - level.at(t);
                ss += e * e;
                cnt += 1;
            }
        }
        dc.push(level);
        air_rms.push((ss / cnt.max(1) as f64).sqrt());
    }
    let runout = runout_from_templates(s, &templates);
    let saturated_samples = sat.iter().map(|r| r.len()).sum::<u64>();
    if saturated_samples > 0 {
        warnings.push(format!(
            "{saturated_samples} displacement samples are saturated (clipped at the sensor's range); their force is not computed (NaN) and they are flagged in the output"
        ));
    }
    let axes: Vec<PairAxis> = s.pairs.iter().map(|p| p.axis).collect();
    let (bandwidth, band_warning) = super::super::bandwidth(&s.beam, &s.dynamics, &axes, f_est, fs)
        .map_err(ShankError::Param)?;
    warnings.extend(band_warning);
    Ok(ShankAnalysis {
        bandwidth,
        spectral_resonance: None,
        air_segments: segments,
        cut,
        air_revolutions_found: found,
        spindle,
        templates,
        dc,
        runout,
        saturated: sat,
        saturated_samples,
        warnings,
        stiffness_n_per_mm: s.stiffness_n_per_mm,
        air_residual_rms_mm: air_rms,
    })
}

/// Clipped runs of all channels merged into sorted ranges.
fn saturated_ranges(survey: &SurveyResult) -> Vec<SampleRange> {
    let mut all: Vec<SampleRange> = survey
        .flat_runs
        .iter()
        .flatten()
        .map(|&(a, b, _)| SampleRange { start: a, end: b })
        .chain(
            survey
                .range_runs
                .iter()
                .map(|&(a, b)| SampleRange { start: a, end: b }),
        )
        .collect();
    all.sort_by_key(|r| r.start);
    let mut merged: Vec<SampleRange> = Vec::new();
    for r in all {
        match merged.last_mut() {
            Some(m) if r.start <= m.end => m.end = m.end.max(r.end),
            _ => merged.push(r),
        }
    }
    merged
}

/// Is sample n inside a sorted range list (sequential access via `pos`)?
pub(super) fn is_in(ranges: &[SampleRange], n: u64, pos: &mut usize) -> bool {
    while *pos < ranges.len() && ranges[*pos].end <= n {
        *pos += 1;
    }
    *pos < ranges.len() && ranges[*pos].start <= n
}

/// Offset and tilt from the first harmonics at the two heights of each pair (methods.md §1.6):
/// E_wp = sign·E·e^{−jβ} (β = 0 for x, π/2 for y) at the heights z = l_tool − l above the tip; one
/// line E(z) = e₀ + z·τ through all of them ([`fit_offset_tilt`]; with every pair at the same two
/// heights it passes through the pair-averaged E_I and E_II), unweighted, each point carrying its
/// template's first-harmonic standard error.
fn runout_from_templates(s: &ShankSetup, templates: &[AngleTemplate]) -> ShankRunout {
    let zi = s.beam.tool_length_mm - s.beam.l1_mm;
    let zii = s.beam.tool_length_mm - s.beam.l2_mm;
    let rot = |e: (f64, f64), p: &SensorPair| {
        let (c, sn) = (p.axis.beta().cos(), p.axis.beta().sin());
        (p.sign * (e.0 * c + e.1 * sn), p.sign * (e.1 * c - e.0 * sn))
    };
    let se = |t: &AngleTemplate| {
        let (a, b) = t.first_harmonic_se;
        ((a * a + b * b) / 2.0).sqrt()
    };
    let mut points = Vec::with_capacity(2 * s.pairs.len());
    let mut sigma = Vec::with_capacity(2 * s.pairs.len());
    for (d, p) in s.pairs.iter().enumerate() {
        for (k, z) in [(2 * d, zi), (2 * d + 1, zii)] {
            let e = rot(templates[k].first_harmonic, p);
            points.push((z, [e.0, e.1]));
            sigma.push(se(&templates[k]));
        }
    }
    let line = fit_offset_tilt(&points, &LineNoise::Known(sigma))
        .unwrap_or_else(|_| OffsetTiltFit::undetermined(points.len()));
    ShankRunout {
        line,
        cutting_height_mm: s.cutting_height_mm,
        at_sensors: points.iter().map(|(z, e)| (*z, e[0], e[1])).collect(),
    }
}
