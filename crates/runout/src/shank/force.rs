//! `shank force`: two streaming passes over the recording (bounded memory) — pass 1 surveys
//! (spindle phase, air cuts, templates), pass 2 reconstructs force and deflections and writes
//! them as computed — then runout from the air cuts and validation against a reference.

use super::config::{load_config, open, plan, Reader, Resolved};
use crate::job::{Progress, Report, Source};
use crate::spill::{Spill, SpillReader};
use crate::verdict::{AxisReport, VerdictBasis, VerdictReport};
use anyhow::{Context, Result};
use runout_core::shank::{
    analyse, ComparisonMetrics, OutputBlock, PairAxis, Reconstructor, ShankAnalysis, Survey,
};
use runout_io::recording::{BinaryLayout, BinaryWriter, CsvWriter, RecordingChunk, RecordingInfo};
use schemars::JsonSchema;
use serde::{Deserialize, Serialize};
use std::io::Write;

/// `runout shank force`: the recording, its shank.toml, and options.
#[derive(Debug, Clone)]
pub struct ForceRequest {
    /// The recording (generic CSV/TSV or DynoWare text export).
    pub recording: Source,
    /// shank.toml (see `runout_io::config::shank`); a `[dynamics] frf` file is resolved from
    /// its folder.
    pub config: Source,
    /// Sample rate (Hz) when the file has no time column; overrides the config.
    pub sample_rate_hz: Option<f64>,
    /// Channel / variable holding the sample times (or, in a binary file, a scalar sample rate
    /// in Hz) used as the time base (`--time-var`); `None`: auto-detected.
    pub time_var: Option<String>,
    /// Parse the text again in pass 2 instead of keeping a temporary binary copy.
    pub reparse: bool,
    /// The time series output, if any: its name (reported) and format.
    pub series: Option<(String, SeriesFormat)>,
}

impl ForceRequest {
    /// A request with the defaults: sample rate from the file or config, spill file, no series.
    pub fn new(recording: Source, config: Source) -> Self {
        Self {
            recording,
            config,
            sample_rate_hz: None,
            time_var: None,
            reparse: false,
            series: None,
        }
    }
}

/// Format of the force/deflection time series.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum SeriesFormat {
    /// CSV with fixed decimals (time to 1/(100 f_s), forces 0.1 mN, deflections 0.01 nm).
    Csv,
    /// Binary layout runout.binary/1 with this element type.
    Binary(BinaryLayout),
}

/// A sensor pair as configured.
#[derive(Debug, Clone, Serialize, Deserialize, JsonSchema)]
pub struct PairReport {
    pub axis: String,
    pub sensor_I: String,
    pub sensor_II: String,
    pub sign: f64,
}

/// The beam used.
#[derive(Debug, Clone, Serialize, Deserialize, JsonSchema)]
pub struct BeamReport {
    pub modulus_gpa: f64,
    pub diameter_mm: f64,
    pub tool_length_mm: f64,
    pub l1_mm: f64,
    pub l2_mm: f64,
    pub load_point_mm: f64,
}

/// Spindle speed measured.
#[derive(Debug, Clone, Serialize, Deserialize, JsonSchema)]
pub struct SpindleReport {
    pub source: String,
    pub rpm: f64,
    pub rpm_se: f64,
    pub nominal_rpm: f64,
}

/// Runout at one sensor height.
#[derive(Debug, Clone, Serialize, Deserialize, JsonSchema)]
pub struct SensorRunout {
    pub height_above_tip_mm: f64,
    pub runout_um: f64,
    pub angle_deg: f64,
}

/// Runout offset + tilt from the air cuts.
#[derive(Debug, Clone, Serialize, Deserialize, JsonSchema)]
pub struct RunoutReport {
    pub offset_um: f64,
    #[serde(alias = "offset_se_um")]
    pub offset_um_se: f64,
    pub angle_deg: f64,
    pub at_height_above_tip_mm: f64,
    pub tip_offset_um: f64,
    pub tip_angle_deg: f64,
    pub tilt_um_per_mm: f64,
    #[serde(alias = "tilt_se_um_per_mm")]
    pub tilt_um_per_mm_se: f64,
    pub tilt_angle_deg: f64,
    pub angle_reference: String,
    pub per_sensor: Vec<SensorRunout>,
}

/// Force statistics of one axis over the cut.
#[derive(Debug, Clone, Serialize, Deserialize, JsonSchema)]
pub struct AxisForce {
    pub axis: String,
    pub mean_N: f64,
    pub rms_N: f64,
    pub min_N: f64,
    pub max_N: f64,
}

/// Shank force against the reference channel of one axis.
#[derive(Debug, Clone, Serialize, Deserialize, JsonSchema)]
pub struct AxisValidation {
    pub axis: String,
    pub samples: u64,
    pub rms_error_N: f64,
    pub rms_reference_N: f64,
    pub relative_rms_error: f64,
    pub max_abs_error_N: f64,
    pub peak_error_N: f64,
    pub correlation: f64,
}

/// Validation against a reference force (a dynamometer in the same recording).
#[derive(Debug, Clone, Serialize, Deserialize, JsonSchema)]
pub struct Validation {
    pub reference_axes: Option<String>,
    pub per_axis: Vec<AxisValidation>,
}

/// The dynamic correction applied.
#[derive(Debug, Clone, Serialize, Deserialize, JsonSchema)]
pub struct Correction {
    pub source: String,
    pub deconvolution_floor: f64,
    pub method: String,
}

/// A tooth-passing harmonic beyond the usable band.
#[derive(Debug, Clone, Serialize, Deserialize, JsonSchema)]
pub struct ToothHarmonic {
    pub harmonic: usize,
    pub frequency_hz: f64,
}

/// A resonance seen in the cut's spectrum.
#[derive(Debug, Clone, Serialize, Deserialize, JsonSchema)]
pub struct SpectralResonance {
    pub frequency_hz: f64,
    pub damping: Option<f64>,
    pub prominence: f64,
    pub frames: usize,
    pub static_usable_bandwidth_hz: Option<f64>,
    pub method: String,
}

/// Bending mode, usable bandwidth and correction (issue 11 item 7).
#[derive(Debug, Clone, Serialize, Deserialize, JsonSchema)]
pub struct Dynamics {
    pub first_bending_mode_hz: f64,
    pub first_bending_mode_source: String,
    pub beam_damping: f64,
    pub density_kg_per_m3: f64,
    pub density_source: String,
    pub bandwidth_criterion: String,
    pub uncorrected_bandwidth_hz: f64,
    pub corrected_bandwidth_hz: Option<f64>,
    pub usable_bandwidth_hz: f64,
    pub correction: Option<Correction>,
    pub teeth: Option<usize>,
    pub tooth_frequency_hz: Option<f64>,
    pub tooth_harmonics_beyond_band: Vec<ToothHarmonic>,
    pub spectral_resonance: Option<SpectralResonance>,
}

/// The time series written.
#[derive(Debug, Clone, Serialize, Deserialize, JsonSchema)]
pub struct OutputReport {
    pub path: String,
    pub columns: Vec<String>,
}

/// `runout.shank.force/2`: force, deflections and runout from a shank recording.
#[derive(Debug, Clone, Serialize, Deserialize, JsonSchema)]
pub struct ForceReport {
    /// `runout.shank.force/2`
    #[schemars(extend("const" = "runout.shank.force/2"))]
    pub schema: String,
    /// The result first: the runout offset ρ ± SE and tilt ± SE from the air cuts, the mean
    /// forces over the cut, the status and its reasons (issue 21).
    #[serde(default)]
    pub answer: crate::answer::Answer,
    pub recording: String,
    pub format: String,
    pub samples: u64,
    pub sample_rate_hz: f64,
    pub duration_s: f64,
    pub pairs: Vec<PairReport>,
    pub stiffness_N_per_um: f64,
    pub stiffness_source: String,
    pub beam: BeamReport,
    pub spindle: SpindleReport,
    pub air_cut_s: Vec<[f64; 2]>,
    pub cut_s: Option<[f64; 2]>,
    pub template_revolutions: usize,
    pub air_residual_rms_um: Vec<f64>,
    pub runout: RunoutReport,
    pub force_over_cut: Vec<AxisForce>,
    pub validation: Option<Validation>,
    pub dynamics: Dynamics,
    pub saturated_samples: u64,
    pub lowpass_hz: Option<f64>,
    pub output: Option<OutputReport>,
    pub warnings: Vec<String>,
    /// Pass/fail against the runout tolerance at the cutting height, the consequences for the
    /// cut, and the runout at the tip against the gauge line (issue 15).
    pub verdict: Option<VerdictReport>,
    /// What the plots show (thinned, bounded): not part of the JSON.
    #[serde(skip)]
    #[schemars(skip)]
    pub plot: ForcePlotData,
}

impl Report for ForceReport {
    const SCHEMA: &'static str = "runout.shank.force/2";
}

/// The data behind the plots of `shank force`, thinned to a bounded size.
#[derive(Debug, Clone, Default)]
pub struct ForcePlotData {
    /// Displacement channel names, 2 per pair.
    pub sensor_names: Vec<String>,
    /// Pair axes (`x`, `y`).
    pub axes: Vec<char>,
    /// A reference force is recorded.
    pub has_reference: bool,
    /// Raw displacements (mm) per sample kept.
    pub raw: Thinned,
    /// Output rows without the time (forces, deflections, references, saturated).
    pub series: Thinned,
    /// The output rows of 5 revolutions mid-cut.
    pub zoomed: Vec<(f64, Vec<f64>)>,
    /// Air-cut templates (mm per angle bin), one per displacement channel.
    pub templates: Vec<Vec<f64>>,
}

/// Keeps a bounded, evenly thinned copy of a stream for plots.
#[derive(Debug, Clone)]
pub struct Thinned {
    stride: u64,
    seen: u64,
    /// (time s, values) of the rows kept.
    pub rows: Vec<(f64, Vec<f64>)>,
}

impl Default for Thinned {
    fn default() -> Self {
        Self::new()
    }
}

impl Thinned {
    /// Empty.
    pub fn new() -> Self {
        Self {
            stride: 1,
            seen: 0,
            rows: Vec::new(),
        }
    }

    /// All of `rows`, not thinned.
    pub fn from_rows(rows: Vec<(f64, Vec<f64>)>) -> Self {
        Self {
            stride: 1,
            seen: 0,
            rows,
        }
    }

    fn push(&mut self, t: f64, v: impl FnOnce() -> Vec<f64>) {
        if self.seen.is_multiple_of(self.stride) {
            self.rows.push((t, v()));
            if self.rows.len() >= 8000 {
                let mut i = 0;
                self.rows.retain(|_| {
                    i += 1;
                    i % 2 == 1
                });
                self.stride *= 2;
            }
        }
        self.seen += 1;
    }
}

/// Output sink: CSV or binary.
enum Sink {
    Csv(CsvWriter<Box<dyn Write>>),
    Bin(BinaryWriter<Box<dyn Write>>),
}

impl Sink {
    fn row(&mut self, v: &[f64]) -> std::io::Result<()> {
        match self {
            Sink::Csv(w) => w.write_row(v),
            Sink::Bin(w) => w.write_row(v),
        }
    }

    fn finish(self) -> std::io::Result<()> {
        match self {
            Sink::Csv(w) => w.finish().map(|_| ()),
            Sink::Bin(w) => w.finish().map(|_| ()),
        }?;
        Ok(())
    }
}

/// Per-axis statistics of the force over the cut.
#[derive(Default, Clone)]
struct Stats {
    n: u64,
    sum: f64,
    sum2: f64,
    min: f64,
    max: f64,
}

impl Stats {
    fn push(&mut self, v: f64) {
        if !v.is_finite() {
            return;
        }
        if self.n == 0 {
            self.min = v;
            self.max = v;
        }
        self.n += 1;
        self.sum += v;
        self.sum2 += v * v;
        self.min = self.min.min(v);
        self.max = self.max.max(v);
    }
}

/// Where pass 2 reads from.
enum Pass2 {
    Text(Box<Reader>),
    Spill(SpillReader),
}

/// [`force_to`] without a time series output.
pub fn force(req: &ForceRequest, progress: &mut dyn Progress) -> Result<ForceReport> {
    force_to(req, None, progress)
}

/// Force, deflections and runout; the time series (`req.series`) is written to `out` as it is
/// computed.
pub fn force_to(
    req: &ForceRequest,
    out: Option<Box<dyn Write>>,
    progress: &mut dyn Progress,
) -> Result<ForceReport> {
    let mut r = load_config(&req.config, req.sample_rate_hz)?;
    r.time_var = req.time_var.clone();
    let (plan, info) = plan(&req.recording, &r)?;
    r.setup.sample_rate_hz = info.sample_rate_hz;
    r.setup.start_time_s = info.start_time_s;
    let nd = r.setup.displacement_channels();
    let nkeep = nd + usize::from(r.setup.has_pulse);
    progress.begin("pass 1/2", info.file_bytes);
    // pass 1
    let mut survey = Survey::new(&r.setup)?;
    let mut reader = open(&req.recording, &r, &plan.names)?;
    let mut chunk = RecordingChunk::default();
    let mut raw = Thinned::new();
    let mut spill = if req.reparse {
        None
    } else {
        let path = Spill::temp_path("shank");
        Some(
            Spill::create(path.clone(), plan.names.len()).with_context(|| {
                format!(
                    "creating the temporary file {} (or use --reparse)",
                    path.display()
                )
            })?,
        )
    };
    while reader.read_chunk(&mut chunk, 65_536)? > 0 {
        scale_chunk(&mut chunk, &plan.scales);
        if let Some(sp) = spill.as_mut() {
            sp.write(&chunk)
                .with_context(|| format!("writing {} (or use --reparse)", sp.path().display()))?;
        }
        let cols: Vec<&[f64]> = chunk.values.iter().map(Vec::as_slice).collect();
        survey.push(&cols[..nkeep])?;
        for k in 0..chunk.len() {
            raw.push(chunk.time_s[k], || {
                (0..nd).map(|c| chunk.values[c][k]).collect()
            });
        }
        progress.set_position(reader.bytes_read());
    }
    progress.end();
    let samples = survey.samples();
    let survey = survey.finish()?;
    let analysis = analyse(&survey).with_context(|| info.file.clone())?;
    // pass 2
    let mut rec = Reconstructor::new(&survey, &analysis)?;
    let columns = rec.column_names();
    let mut sink = match (&req.series, out) {
        (Some((_, SeriesFormat::Binary(layout))), Some(w)) => Some(Sink::Bin(BinaryWriter::new(
            w,
            &columns,
            *layout,
            serde_json::Value::Object(
                [
                    ("sample_rate_hz".to_string(), info.sample_rate_hz.into()),
                    ("source".to_string(), info.file.clone().into()),
                    (
                        "saturated".to_string(),
                        "1 = sensor saturated, force NaN".into(),
                    ),
                ]
                .into_iter()
                .collect(),
            ),
        )?)),
        (_, Some(w)) => {
            // fixed decimals: time to 1/(100 f_s), forces 0.1 mN, deflections 0.01 nm
            let dt_dec = (info.sample_rate_hz.log10().ceil() as u32 + 2).min(12);
            let decimals: Vec<u32> = columns
                .iter()
                .map(|c| match c.as_str() {
                    "time_s" => dt_dec,
                    "saturated" => 0,
                    c if c.ends_with("_um") => 5,
                    _ => 4,
                })
                .collect();
            Some(Sink::Csv(
                CsvWriter::new(w, &columns)?.with_decimals(&decimals)?,
            ))
        }
        (_, None) => None,
    };
    progress.begin("pass 2/2", info.file_bytes);
    let mut warnings: Vec<String> = reader.warnings().to_vec();
    let mut source = match spill.as_mut() {
        Some(sp) => {
            let path = sp.path().display().to_string();
            Pass2::Spill(sp.reader().with_context(|| format!("reading {path}"))?)
        }
        None => Pass2::Text(Box::new(open(&req.recording, &r, &plan.names)?)),
    };
    let mut block = OutputBlock::default();
    let mut series = Thinned::new();
    let mut stats = vec![Stats::default(); r.setup.pairs.len()];
    let spr = r.setup.sample_rate_hz / analysis.spindle.mean_frequency_hz();
    let zoom = analysis.cut.map(|c| {
        let mid = (c.start + c.end) / 2;
        (
            mid.saturating_sub((2.5 * spr) as u64),
            mid + (2.5 * spr) as u64,
        )
    });
    let mut zoomed: Vec<(f64, Vec<f64>)> = Vec::new();
    // sensor I and II displacements per pair during the cut, for the sensor-senses guard
    // (`plausibility::sensor_senses`): the first SENSES_MAX samples suffice for a correlation
    const SENSES_MAX: usize = 200_000;
    let mut senses: Vec<(Vec<f64>, Vec<f64>)> = vec![(Vec::new(), Vec::new()); r.setup.pairs.len()];
    let mut row = vec![0.0; columns.len()];
    let mut consume = |out: &OutputBlock, sink: &mut Option<Sink>| -> Result<()> {
        let np = out.force_n.len();
        for i in 0..out.len() {
            row[0] = out.time_s[i];
            let mut c = 1;
            for d in 0..np {
                row[c] = out.force_n[d][i];
                c += 1;
            }
            for d in 0..np {
                row[c] = out.delta_i_um[d][i];
                row[c + 1] = out.delta_ii_um[d][i];
                c += 2;
            }
            for rv in &out.reference_n {
                row[c] = rv[i];
                c += 1;
            }
            row[c] = f64::from(u8::from(out.saturated[i]));
            if let Some(s) = sink.as_mut() {
                s.row(&row)?;
            }
            let n = out.sample[i];
            if analysis.cut.is_none_or(|c| n >= c.start && n < c.end) {
                for (st, f) in stats.iter_mut().zip(&out.force_n) {
                    st.push(f[i]);
                }
                for (d, (a, b)) in senses.iter_mut().enumerate() {
                    if a.len() < SENSES_MAX && d < out.delta_i_um.len() {
                        a.push(out.delta_i_um[d][i]);
                        b.push(out.delta_ii_um[d][i]);
                    }
                }
            }
            series.push(out.time_s[i], || row[1..].to_vec());
            if zoom.is_some_and(|(z0, z1)| n >= z0 && n < z1) {
                zoomed.push((out.time_s[i], row[1..].to_vec()));
            }
        }
        Ok(())
    };
    loop {
        let n = match &mut source {
            Pass2::Text(rd) => {
                let n = rd.read_chunk(&mut chunk, 65_536)?;
                scale_chunk(&mut chunk, &plan.scales);
                progress.set_position(rd.bytes_read());
                n
            }
            Pass2::Spill(sr) => {
                let n = sr
                    .read_chunk(&mut chunk)
                    .context("reading the temporary file")?;
                progress.advance(n as u64 * info.file_bytes.unwrap_or(0) / samples.max(1));
                n
            }
        };
        if n == 0 {
            break;
        }
        let cols: Vec<&[f64]> = chunk.values.iter().map(Vec::as_slice).collect();
        rec.push(&cols, &mut block)?;
        consume(&block, &mut sink)?;
    }
    drop(source);
    drop(spill);
    rec.finish(&mut block);
    consume(&block, &mut sink)?;
    progress.end();
    if let Some(s) = sink {
        s.finish().context("writing the output")?;
    }
    let comparison = rec.comparison();
    let mut analysis = analysis;
    analysis.spectral_resonance = rec.spectral_resonance();
    warnings.extend(analysis.warnings.iter().cloned());
    let mut not_to_use = Vec::new();
    for (p, (a, b)) in r.setup.pairs.iter().zip(&senses) {
        let axis = p.axis.letter().to_string();
        if let Some(f) = runout_core::plausibility::sensor_senses(a, b, &axis) {
            let w = format!("{f} (the forces and the runout of this recording are not to be used)");
            warnings.push(w.clone());
            not_to_use.push(w);
        }
    }
    let axes: Vec<PairAxis> = r.setup.pairs.iter().map(|p| p.axis).collect();
    let seen_usable = analysis.spectral_resonance.map(|seen| {
        let (usable, w) = runout_core::shank::spectral_check(
            &analysis.bandwidth,
            &r.setup.dynamics,
            &axes,
            &seen,
            r.setup.sample_rate_hz,
        );
        warnings.extend(w);
        usable
    });
    let mut report = summary(
        req,
        &r,
        &info,
        samples,
        &analysis,
        seen_usable,
        &stats,
        comparison.as_deref(),
        plan.reference.as_ref().map(|m| m.to_string()),
        warnings,
        columns,
    );
    report.plot = ForcePlotData {
        sensor_names: r
            .cfg
            .pair
            .iter()
            .flat_map(|p| [p.sensor_i.clone(), p.sensor_ii.clone()])
            .collect(),
        axes: r.setup.pairs.iter().map(|p| p.axis.letter()).collect(),
        has_reference: r.setup.has_reference,
        raw,
        series,
        zoomed,
        templates: analysis.templates.iter().map(|t| t.bins.clone()).collect(),
    };
    report.answer = force_answer(&report, r.setup.has_pulse, not_to_use);
    Ok(report)
}

/// The answer of `shank force` (issue 21 item 1): ρ ± SE and the tilt ± SE from the air-cut
/// templates (SE test: `crate::answer::se_test`), and the mean force per axis over the cut.
/// `not identified` when the sensors of a pair move in opposite senses (`reasons`: the forces
/// and the runout are not to be used) or ρ fails its SE or size test. Without a pulse channel
/// the angle has an arbitrary origin: reported `not measured`, which does not lower the status
/// (the input cannot give it). The runout at each sensor height is a cross-check.
fn force_answer(
    r: &ForceReport,
    has_pulse: bool,
    not_to_use: Vec<String>,
) -> crate::answer::Answer {
    use crate::answer::{Answer, CrossCheck, Quantity, RunoutAnswer, NOT_IDENTIFIED};
    use runout_core::plausibility::{runout_size, Severity};
    let ro = &r.runout;
    let mut reasons = not_to_use;
    let mut warnings = Vec::new();
    let forces_ok = reasons.is_empty();
    if let Some(x) = crate::answer::se_test(
        "runout ρ",
        ro.offset_um,
        Some(ro.offset_um_se),
        "µm",
        "record longer air cuts (more revolutions) before and after the cut",
    ) {
        reasons.push(x);
    }
    for f in runout_size(ro.offset_um * 1e-3, r.beam.diameter_mm / 2.0, 0.0) {
        match f.severity {
            Severity::NotIdentified => reasons.push(f.to_string()),
            Severity::Warning => warnings.push(f.to_string()),
        }
    }
    if r.saturated_samples > 0 {
        warnings.push(format!(
            "{} samples saturated (a sensor at its range limit): check the sensors' range and \
             distance to the shank",
            r.saturated_samples
        ));
    }
    let rho_ok = reasons.is_empty();
    let mut results = vec![if rho_ok {
        Quantity::identified(
            "tilt",
            "µm/mm",
            ro.tilt_um_per_mm,
            Some(ro.tilt_um_per_mm_se),
        )
    } else {
        Quantity::not_identified("tilt", "µm/mm")
    }];
    for a in &r.force_over_cut {
        let name = format!("mean force F_{} over the cut", a.axis);
        results.push(if forces_ok {
            Quantity::identified(&name, "N", a.mean_N, None)
        } else {
            Quantity::not_identified(&name, "N")
        });
    }
    Answer {
        status: Answer::status_of(rho_ok, true).into(),
        method: "runout offset + tilt from the air-cut templates of the sensors at two heights; \
                 force F = K_δ·(δ_II − δ_I) after subtracting the air-cut template \
                 (docs/methods.md §3.1, §3.2)"
            .into(),
        runout: Some(RunoutAnswer {
            offset_um: rho_ok.then_some(ro.offset_um),
            offset_um_se: rho_ok.then_some(ro.offset_um_se),
            angle_deg: (rho_ok && has_pulse).then_some(ro.angle_deg),
            angle_deg_se: None,
            angle: if !rho_ok {
                NOT_IDENTIFIED.into()
            } else if has_pulse {
                "identified (from the pulse mark; no SE)".into()
            } else {
                "not measured (no pulse channel: the angle origin is arbitrary)".into()
            },
        }),
        results,
        reasons,
        warnings,
        cross_checks: ro
            .per_sensor
            .iter()
            .map(|p| CrossCheck {
                estimate: format!(
                    "runout at the sensor {:.1} mm above the tip",
                    p.height_above_tip_mm
                ),
                values: vec![Quantity::cross_check("runout", "µm", p.runout_um, None)],
                why_it_may_differ: "at the sensor's height, not the cutting height: differs from \
                                    ρ by the tilt times the height difference"
                    .into(),
            })
            .collect(),
    }
}

impl crate::answer::Answered for ForceReport {
    fn answer(&self) -> &crate::answer::Answer {
        &self.answer
    }
}

fn scale_chunk(chunk: &mut RecordingChunk, scales: &[f64]) {
    for (v, s) in chunk.values.iter_mut().zip(scales) {
        if *s != 1.0 {
            v.iter_mut().for_each(|x| *x *= s);
        }
    }
}

#[allow(clippy::too_many_arguments)]
fn summary(
    req: &ForceRequest,
    r: &Resolved,
    info: &RecordingInfo,
    samples: u64,
    an: &ShankAnalysis,
    seen_usable_hz: Option<f64>,
    stats: &[Stats],
    cmp: Option<&[ComparisonMetrics]>,
    reference_axes: Option<String>,
    warnings: Vec<String>,
    columns: Vec<String>,
) -> ForceReport {
    let s = &r.setup;
    let fs = s.sample_rate_hz;
    let t = |n: u64| s.start_time_s + n as f64 / fs;
    let ro = &an.runout;
    let deg = |x: f64, y: f64| y.atan2(x).to_degrees();
    let (spindle_source, rpm_se) = match &an.spindle {
        runout_core::shank::SpindlePhase::Constant {
            source,
            frequency_se_hz,
            ..
        } => (source.clone(), frequency_se_hz * 60.0),
        runout_core::shank::SpindlePhase::Pulses { .. } => (
            "once-per-revolution pulse".to_string(),
            an.spindle.frequency_se_hz() * 60.0,
        ),
    };
    let angle_ref = if s.has_pulse {
        "from the pulse mark's rising edge (theta = 0), in the direction of rotation"
    } else {
        "from an arbitrary spindle-angle origin (theta = 0 at the first sample; no pulse channel): only magnitudes and the offset-to-tilt angle are meaningful"
    };
    let letter = |a: PairAxis| a.letter().to_string();
    let mut report = ForceReport {
        schema: ForceReport::SCHEMA.into(),
        recording: info.file.clone(),
        format: crate::words::serde_name(&info.format),
        samples,
        sample_rate_hz: fs,
        duration_s: samples as f64 / fs,
        pairs: r
            .cfg
            .pair
            .iter()
            .map(|p| PairReport {
                axis: p.axis.name().into(),
                sensor_I: p.sensor_i.clone(),
                sensor_II: p.sensor_ii.clone(),
                sign: p.sign,
            })
            .collect(),
        stiffness_N_per_um: s.stiffness_n_per_mm / 1e3,
        stiffness_source: r.stiffness_source.clone(),
        beam: BeamReport {
            modulus_gpa: s.beam.modulus_n_per_mm2 / 1e3,
            diameter_mm: s.beam.diameter_mm,
            tool_length_mm: s.beam.tool_length_mm,
            l1_mm: s.beam.l1_mm,
            l2_mm: s.beam.l2_mm,
            load_point_mm: s.beam.load_distance_mm(),
        },
        spindle: SpindleReport {
            source: spindle_source,
            rpm: an.spindle.mean_frequency_hz() * 60.0,
            rpm_se,
            nominal_rpm: s.nominal_rpm,
        },
        air_cut_s: an
            .air_segments
            .iter()
            .map(|g| [t(g.start), t(g.end)])
            .collect(),
        cut_s: an.cut.map(|c| [t(c.start), t(c.end)]),
        template_revolutions: an.templates[0].revolutions,
        air_residual_rms_um: an.air_residual_rms_mm.iter().map(|v| v * 1e3).collect(),
        runout: RunoutReport {
            offset_um: ro.offset_magnitude_mm() * 1e3,
            offset_um_se: ro.offset_se_mm() * 1e3,
            angle_deg: ro.offset_angle_rad().to_degrees(),
            at_height_above_tip_mm: ro.cutting_height_mm,
            tip_offset_um: ro.tip_offset_mm()[0].hypot(ro.tip_offset_mm()[1]) * 1e3,
            tip_angle_deg: deg(ro.tip_offset_mm()[0], ro.tip_offset_mm()[1]),
            tilt_um_per_mm: ro.tilt_magnitude() * 1e3,
            tilt_um_per_mm_se: ro.tilt_se() * 1e3,
            tilt_angle_deg: ro.tilt_angle_rad().to_degrees(),
            angle_reference: angle_ref.into(),
            per_sensor: ro
                .at_sensors
                .iter()
                .map(|(z, x, y)| SensorRunout {
                    height_above_tip_mm: *z,
                    runout_um: x.hypot(*y) * 1e3,
                    angle_deg: deg(*x, *y),
                })
                .collect(),
        },
        force_over_cut: s
            .pairs
            .iter()
            .zip(stats)
            .map(|(p, st)| {
                let n = st.n.max(1) as f64;
                AxisForce {
                    axis: letter(p.axis),
                    mean_N: st.sum / n,
                    rms_N: (st.sum2 / n).sqrt(),
                    min_N: st.min,
                    max_N: st.max,
                }
            })
            .collect(),
        validation: cmp.map(|m| Validation {
            reference_axes,
            per_axis: s
                .pairs
                .iter()
                .zip(m)
                .map(|(p, c)| AxisValidation {
                    axis: letter(p.axis),
                    samples: c.samples,
                    rms_error_N: c.rms_error_n,
                    rms_reference_N: c.rms_reference_n,
                    relative_rms_error: c.relative_rms_error,
                    max_abs_error_N: c.max_abs_error_n,
                    peak_error_N: c.peak_error_n,
                    correlation: c.correlation,
                })
                .collect(),
        }),
        dynamics: dynamics(r, an, seen_usable_hz),
        saturated_samples: an.saturated_samples,
        lowpass_hz: s.lowpass.map(|l| l.1),
        output: req.series.as_ref().map(|(path, _)| OutputReport {
            path: path.clone(),
            columns,
        }),
        warnings,
        verdict: None,
        answer: crate::answer::Answer::default(),
        plot: ForcePlotData::default(),
    };
    match verdict_of(&report, s.has_pulse) {
        Ok(v) => report.verdict = Some(v),
        Err(e) => report.warnings.push(format!("no verdict: {e:#}")),
    }
    report
}

/// The verdict at the cutting height (issue 15): the cutter is the shank's diameter with the
/// `[shank] teeth` of the config (no feed in a shank config: radii, no chips); the angle only with
/// a pulse mark (else the teeth cannot be told apart); tip against the gauge line (holder face,
/// `tool_length_mm` above the tip) from the offset + tilt fit.
fn verdict_of(r: &ForceReport, has_pulse: bool) -> Result<VerdictReport> {
    let ro = &r.runout;
    let v = VerdictReport::new(
        VerdictBasis {
            offset_um: ro.offset_um,
            offset_um_se: Some(ro.offset_um_se),
            angle_deg: has_pulse.then_some(ro.angle_deg),
            teeth: r.dynamics.teeth,
            diameter_mm: Some(r.beam.diameter_mm),
            helix_deg: 0.0,
            height_mm: ro.at_height_above_tip_mm,
            fz_mm: None,
        },
        None,
    )?;
    let l = r.beam.tool_length_mm;
    let (tx, ty) = {
        let a = ro.tip_angle_deg.to_radians();
        (ro.tip_offset_um * a.cos(), ro.tip_offset_um * a.sin())
    };
    let ta = ro.tilt_angle_deg.to_radians();
    let (gx, gy) = (
        tx + l * ro.tilt_um_per_mm * ta.cos(),
        ty + l * ro.tilt_um_per_mm * ta.sin(),
    );
    let axis = AxisReport::from_polar(
        (ro.tip_offset_um, ro.tip_angle_deg),
        (gx.hypot(gy), gy.atan2(gx).to_degrees()),
        l,
        "gauge line (holder face)",
    )?;
    Ok(v.with_axis(Some(axis)))
}

/// The bending mode, usable bandwidth and correction (issue 11 item 7).
fn dynamics(r: &Resolved, an: &ShankAnalysis, seen_usable_hz: Option<f64>) -> Dynamics {
    let b = &an.bandwidth;
    Dynamics {
        first_bending_mode_hz: b.beam_mode_hz,
        first_bending_mode_source: "Euler-Bernoulli cantilever from the [shank] beam: f1 = (beta1 L)^2/(2 pi) sqrt(E I/(rho A L^4)), beta1 L = 1.8751 clamped (holder spring lowers it)".into(),
        beam_damping: b.beam_damping,
        density_kg_per_m3: b.density_kg_per_m3,
        density_source: r.density_source.clone(),
        bandwidth_criterion: "lowest frequency where the reconstructed force harmonic is off by more than 10 %: |G(f) H(f) - 1| > 0.1 (G = 1 without correction)".into(),
        uncorrected_bandwidth_hz: b.uncorrected_hz,
        corrected_bandwidth_hz: b.corrected_hz,
        usable_bandwidth_hz: b.usable_hz(),
        correction: r.setup.dynamics.correction.as_ref().map(|c| Correction {
            source: c.source.clone(),
            deconvolution_floor: c.floor,
            method: "overlap-save FFT blocks, G = (1/H) |H|^4/(|H|^4 + eps^4)".into(),
        }),
        teeth: r.setup.dynamics.teeth,
        tooth_frequency_hz: b.tooth_frequency_hz,
        tooth_harmonics_beyond_band: b
            .harmonics_beyond
            .iter()
            .map(|(k, f)| ToothHarmonic {
                harmonic: *k,
                frequency_hz: *f,
            })
            .collect(),
        spectral_resonance: an.spectral_resonance.map(|s| SpectralResonance {
            frequency_hz: s.frequency_hz,
            damping: s.damping,
            prominence: s.prominence,
            frames: s.frames,
            static_usable_bandwidth_hz: seen_usable_hz,
            method: "Welch spectrum of the uncorrected force over the cut between the spindle lines; f and damping fitted to the peak (docs/shank.md)".into(),
        }),
    }
}
