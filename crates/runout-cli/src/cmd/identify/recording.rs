//! `runout identify RECORDING… --config cut.toml`: runout and cutting coefficients from measured
//! force recordings — the product's main job.
//!
//! Per recording: stream the file (DynoWare text export or CSV/TSV) once, mapping instrument
//! channels to the workpiece frame and spilling the forces to a temporary binary file; the signal
//! pipeline (`runout_core::signal`) then runs its three passes (spectrum + steady-cut detection,
//! spindle-speed tracking, synchronous average + per-tooth peaks) over text once and the spill
//! twice. Then: the seed-003 sine fit of the per-tooth peaks, the mean-force coefficient
//! calibration (≥ 2 feeds), and the full-signal fit of all recordings jointly
//! (`runout_core::identify`).

use super::super::simulate::settings;
use crate::output;
use anyhow::{bail, Context, Result};
use indicatif::{ProgressBar, ProgressStyle};
use runout_core::identify::{
    calibrate_mean_forces, full_signal_fit, harmonic_start_angle, model_forces, peak_immersion,
    radius_difference, refine_start_angle, sine_fit, AveragedWaveform, Axis as FitAxis,
    Component as FitComponent, FullSignalFit, FullSignalOptions, MeanForceCalibration, MeanForces,
    PeakConditions, SineFit, SineHypothesis, ToothPeaks, WaveformCase,
};
use runout_core::signal::{
    self, Component, PulseConfig, SignalAnalysis, SignalConfig, ToothReference,
};
use runout_core::{angle::wrap_pi, Cut, Cutter, CuttingCoefficients};
use runout_io::config::identify::{identify_key_names, resolve_identify, IdentifyCase};
use runout_io::config::{Layer, Value};
use runout_io::plot::identify::{
    runout_polar, tooth_peak_bars, waveform_overlay, Curve, RunoutMark,
};
use runout_io::recording::{
    Axis, AxisMapping, Chunk as RecChunk, ReadOptions, RecordingInfo, RecordingReader,
};
use runout_io::units::Quantity;
use serde_json::{json, Value as Json};
use std::f64::consts::TAU;
use std::fs::File;
use std::io::{BufReader, BufWriter, Read, Write};
use std::path::{Path, PathBuf};

mod chain;

/// Arguments of `runout identify RECORDING…`.
#[derive(clap::Args, Debug, Default)]
pub struct RecordingArgs {
    /// Force recordings (Kistler DynoWare text export, or CSV/TSV with a header row); several
    /// recordings at different feeds are fitted jointly.
    #[arg(value_name = "RECORDING")]
    pub recordings: Vec<PathBuf>,
    /// Cut description (TOML) with the keys of the flags below.
    #[arg(long)]
    pub config: Option<PathBuf>,
    /// Number of teeth K.
    #[arg(long)]
    pub teeth: Option<String>,
    /// Cutter diameter D (mm).
    #[arg(long)]
    pub diameter_mm: Option<String>,
    /// Helix angle (deg).
    #[arg(long)]
    pub helix_deg: Option<String>,
    /// End profile: flat | ball | bull_nose | tapered (default flat).
    #[arg(long, allow_hyphen_values = true)]
    pub profile: Option<String>,
    /// Corner radius r_c of a bull_nose cutter (mm), 0 < r_c <= D/2.
    #[arg(long, allow_hyphen_values = true)]
    pub corner_radius_mm: Option<String>,
    /// Taper (half-cone) angle of a tapered cutter (deg), 0 < α < 45; D is the tip diameter.
    #[arg(long, allow_hyphen_values = true)]
    pub taper_deg: Option<String>,
    /// Flute winding on a ball, bull-nose or taper: constant_lead | constant_helix (default constant_lead).
    #[arg(long, allow_hyphen_values = true)]
    pub flute_lead: Option<String>,
    /// Nominal spindle speed (rpm); the actual speed is measured from the signal.
    #[arg(long)]
    pub rpm: Option<String>,
    /// Feed per tooth (mm): one value, or comma-separated, one per recording.
    #[arg(long)]
    pub fz_mm: Option<String>,
    /// Axial depth (mm): one value, or one per recording.
    #[arg(long)]
    pub ap_mm: Option<String>,
    /// Radial depth (mm).
    #[arg(long)]
    pub ae_mm: Option<String>,
    /// Milling mode: up | down | slot.
    #[arg(long)]
    pub mode: Option<String>,
    /// Instrument channels → workpiece frame (x feed, y feed-normal, z up), e.g. "x = -Fy, y = -Fx, z = -Fz".
    #[arg(long, allow_hyphen_values = true)]
    pub axes: Option<String>,
    /// Sample rate (Hz), when the file has neither a time column nor a sampling-rate line.
    #[arg(long)]
    pub sample_rate_hz: Option<String>,
    /// Start of the section to analyse (s); default: the steady cut, detected.
    #[arg(long)]
    pub from_s: Option<String>,
    /// End of the section to analyse (s).
    #[arg(long)]
    pub to_s: Option<String>,
    /// Component of the per-tooth peaks: fxy (resultant |F_xy|, N) | fx | fy | fz.
    #[arg(long)]
    pub peak_component: Option<String>,
    /// Once-per-revolution (or encoder) channel name.
    #[arg(long)]
    pub pulse_channel: Option<String>,
    /// Spindle angle of tooth 0 at the pulse edge (deg): makes the tooth numbering absolute.
    #[arg(long, allow_hyphen_values = true)]
    pub tooth0_angle_deg: Option<String>,
    /// Also fit the runout tilt (µm/mm).
    #[arg(long)]
    pub fit_tilt: bool,
    /// Measuring chain (the dynamometer's own dynamics): auto | rigid | modes | frf | band.
    /// auto (default) fits one second-order mode per axis and uses it where it explains the
    /// waveform significantly better; modes always; frf uses --sensor-frf; band fits only the
    /// harmonics up to --max-harmonic (or an automatic limit below the resonance).
    #[arg(long)]
    pub chain: Option<String>,
    /// Measured FRF of the dynamometer (CSV: freq_Hz, xx_re, xx_im, yy_re, yy_im[, zz_re, zz_im],
    /// normalised to H(0) = 1); implies --chain frf.
    #[arg(long)]
    pub sensor_frf: Option<String>,
    /// Start value of the sensor mode's natural frequency (Hz): one value, or x,y[,z].
    #[arg(long)]
    pub sensor_mode_hz: Option<String>,
    /// Band limit: fit only spindle harmonics 0..N (count); implies --chain band.
    #[arg(long)]
    pub max_harmonic: Option<String>,
    /// Write the JSON result (`-` for stdout).
    #[arg(long)]
    pub json: Option<PathBuf>,
    /// Directory for the plots (created if missing): waveform overlay, per-tooth peaks, polar runout.
    #[arg(long)]
    pub plot_dir: Option<PathBuf>,
    /// Plot format: svg | png.
    #[arg(long, default_value = "svg")]
    pub plot_format: String,
}

impl RecordingArgs {
    fn layer(&self) -> Layer {
        let pairs: [(&str, &Option<String>); 23] = [
            ("chain", &self.chain),
            ("sensor_frf", &self.sensor_frf),
            ("sensor_mode_hz", &self.sensor_mode_hz),
            ("max_harmonic", &self.max_harmonic),
            ("teeth", &self.teeth),
            ("diameter_mm", &self.diameter_mm),
            ("helix_deg", &self.helix_deg),
            ("profile", &self.profile),
            ("corner_radius_mm", &self.corner_radius_mm),
            ("taper_deg", &self.taper_deg),
            ("flute_lead", &self.flute_lead),
            ("rpm", &self.rpm),
            ("fz_mm", &self.fz_mm),
            ("ap_mm", &self.ap_mm),
            ("ae_mm", &self.ae_mm),
            ("mode", &self.mode),
            ("axes", &self.axes),
            ("sample_rate_hz", &self.sample_rate_hz),
            ("from_s", &self.from_s),
            ("to_s", &self.to_s),
            ("peak_component", &self.peak_component),
            ("pulse_channel", &self.pulse_channel),
            ("tooth0_angle_deg", &self.tooth0_angle_deg),
        ];
        let mut values: std::collections::BTreeMap<String, Value> = pairs
            .into_iter()
            .filter_map(|(k, v)| v.as_ref().map(|v| (k.to_string(), Value::Text(v.clone()))))
            .collect();
        if self.fit_tilt {
            values.insert("fit_tilt".into(), Value::Text("true".into()));
        }
        Layer {
            origin: "command line".into(),
            values,
        }
    }
}

/// What the chain selection, tooth numbering, consistency and verdicts gave.
struct Extra {
    decision: chain::ChainDecision,
    given: Option<runout_core::chain::MeasuringChain>,
    renumbered: Vec<(usize, usize)>,
    consistency: Option<chain::Consistency>,
    verdicts: chain::Verdicts,
}

/// What one recording gave.
struct FileResult {
    path: PathBuf,
    info: RecordingInfo,
    axes: String,
    cut: Cut,
    analysis: SignalAnalysis,
    mean_force: [f64; 3],
    start_angle: f64,
    sine: Result<SineFit, String>,
    reader_warnings: Vec<String>,
}

pub fn run(a: RecordingArgs) -> Result<()> {
    if a.recordings.is_empty() {
        bail!("no recording given: `runout identify RECORDING… --config cut.toml` (or `runout identify peaks|tests`)");
    }
    let s = settings(a.config.as_deref(), a.layer(), &identify_key_names())?;
    let case = resolve_identify(&s, a.recordings.len())?;
    let mut inputs: Vec<&Path> = a.recordings.iter().map(|p| p.as_path()).collect();
    if let Some(c) = &a.config {
        inputs.push(c);
    }
    if let Some(j) = &a.json {
        output::check_not_input(j, &inputs)?;
    }
    let ext = match a.plot_format.as_str() {
        "svg" | "png" => a.plot_format.as_str(),
        other => bail!("--plot-format: expected svg or png, got `{other}`"),
    };

    let mut files = Vec::new();
    for (i, path) in a.recordings.iter().enumerate() {
        let r = analyse_file(path, &case, &case.cuts[i])
            .with_context(|| format!("analysing {}", path.display()))?;
        files.push(r);
    }
    let calibration = mean_force_calibration(&case, &files);
    let guess = calibration
        .as_ref()
        .ok()
        .map(coefficients_of)
        .unwrap_or_else(default_coefficients);
    for f in files.iter_mut() {
        f.start_angle = initial_start_angle(&case.cutter, f, &guess);
    }
    let rigid = fit_all(&case, &mut files);
    // Tooth numbering consistent across the recordings of the joint fit, then the chain.
    let mut renumbered = Vec::new();
    if let (Ok(f), true) = (&rigid, files.len() > 1) {
        renumbered = chain::align_tooth_numbering(&case, &mut files, f);
    }
    let rigid = if renumbered.is_empty() {
        rigid
    } else {
        fit_all(&case, &mut files)
    };
    let (fit, decision, given) = chain::select_chain(&case, &mut files, rigid)?;
    let consistency = fit
        .as_ref()
        .ok()
        .and_then(|f| chain::consistency(&case, &files, f, given.as_ref()));
    let verdicts = fit
        .as_ref()
        .map(|f| chain::verdicts(f, &decision, &files))
        .unwrap_or_default();
    let extra = Extra {
        decision,
        given,
        renumbered,
        consistency,
        verdicts,
    };
    let report = report_json(&case, &files, &calibration, &fit, &extra);
    if let Some(j) = &a.json {
        output::write_text(j, &(serde_json::to_string_pretty(&report)? + "\n"))?;
    }
    if a.json.as_deref() != Some(Path::new("-")) {
        print_text(&case, &files, &calibration, &fit, &extra);
    }
    if let Some(dir) = &a.plot_dir {
        std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
        write_plots(dir, ext, &case, &files, &fit, &extra)?;
    }
    Ok(())
}

// ---------------------------------------------------------------------------------------------
// Reading: pass 1 over the text with a binary spill; passes 2 and 3 over the spill.

/// Forces (and pulse) of a recording in the workpiece frame, spilled as little-endian f64 rows.
struct Spill {
    path: PathBuf,
    columns: usize,
    rows: u64,
}

impl Drop for Spill {
    fn drop(&mut self) {
        let _ = std::fs::remove_file(&self.path);
    }
}

/// Force unit factor to N for a channel, from its unit (none = N, with a note).
fn force_factor(info: &RecordingInfo, channel: &str) -> Result<f64> {
    let idx = info
        .channel_index(channel)
        .with_context(|| format!("{}: no channel `{channel}`", info.file))?;
    match &info.channels[idx].unit {
        None => Ok(1.0),
        Some(u) => Quantity::ForceN.unit_factor(u).ok_or_else(|| {
            anyhow::anyhow!(
                "{}: channel `{channel}` has unit `{u}`, expected a force (N or kN)",
                info.file
            )
        }),
    }
}

fn progress(path: &Path, total: u64) -> ProgressBar {
    let pb = ProgressBar::new(total.max(1));
    if let Ok(style) = ProgressStyle::with_template(
        "{msg} [{bar:30}] {percent:>3}% {binary_bytes_per_sec} eta {eta}",
    ) {
        pb.set_style(style.progress_chars("=> "));
    }
    pb.set_message(
        path.file_name()
            .map(|n| n.to_string_lossy().into_owned())
            .unwrap_or_default(),
    );
    pb
}

fn analyse_file(path: &Path, case: &IdentifyCase, cut: &Cut) -> Result<FileResult> {
    let mut opts = ReadOptions::new();
    if let Some(fs) = case.sample_rate_hz {
        opts = opts.sample_rate_hz(fs);
    }
    let mut reader = runout_io::recording::open_recording(path, &opts)?;
    let info = reader.info().clone();
    let names: Vec<String> = info.channels.iter().map(|c| c.name.clone()).collect();
    let mapping = match &case.axes {
        Some(t) => AxisMapping::parse(t)?,
        None => AxisMapping::identity_for(&names).map_err(|e| {
            anyhow::anyhow!(
                "{e}; give the mapping with --axes (e.g. \"x = Fx, y = Fy, z = Fz\"); channels: {}",
                names.join(", ")
            )
        })?,
    };
    let axes = mapping.resolve(&info)?;
    if !(axes.has(Axis::X) && axes.has(Axis::Y)) {
        bail!(
            "{}: the axis mapping `{mapping}` must give both x and y",
            path.display()
        );
    }
    let factors: Vec<f64> = Axis::ALL
        .iter()
        .map(|&ax| {
            mapping
                .source(ax)
                .map(|s| force_factor(&info, &s.channel))
                .transpose()
                .map(|f| f.unwrap_or(1.0))
        })
        .collect::<Result<_>>()?;
    let pulse_idx = match &case.pulse_channel {
        Some(p) => Some(info.channel_index(p).with_context(|| {
            format!(
                "{}: no pulse channel `{p}` (channels: {})",
                path.display(),
                names.join(", ")
            )
        })?),
        None => None,
    };
    let has_z = axes.has(Axis::Z);

    let mut cfg = SignalConfig::new(info.sample_rate_hz, case.cutter.teeth(), cut.rpm())?;
    cfg.section_s = case.section_s;
    cfg.peak_component = match case.peak_component.as_str() {
        "fx" => Component::Fx,
        "fy" => Component::Fy,
        "fz" => Component::Fz,
        _ => Component::Fxy,
    };
    cfg.entry_angle_rad = Some(cut.immersion(&case.cutter).0);
    if pulse_idx.is_some() {
        cfg.pulse = Some(PulseConfig {
            pulses_per_rev: case.pulses_per_rev,
            tooth0_angle_rad: case.tooth0_angle,
            ..PulseConfig::once_per_rev()
        });
    }
    cfg.validate()?;

    let columns = 3 + pulse_idx.is_some() as usize;
    let spill_path = std::env::temp_dir().join(format!(
        "runout-spill-{}-{}.bin",
        std::process::id(),
        spill_counter()
    ));
    let mut spill = Spill {
        path: spill_path,
        columns,
        rows: 0,
    };
    let pb = progress(
        path,
        info.file_bytes.unwrap_or(0) + 2 * 8 * columns as u64 * info.expected_samples.unwrap_or(0),
    );
    let mut pass = 0;
    let analysis = signal::analyse_replay::<anyhow::Error, _>(&cfg, |sink| {
        pass += 1;
        if pass == 1 {
            first_pass(
                &mut reader,
                &axes,
                &factors,
                pulse_idx,
                has_z,
                &mut spill,
                &pb,
                sink,
            )
        } else {
            replay_spill(&spill, has_z, &pb, sink)
        }
    })?;
    pb.finish_and_clear();
    let reader_warnings = reader.warnings().to_vec();

    let avg = &analysis.average;
    let mean = |c: Component| {
        let m = &avg.component(c).mean;
        m.iter().sum::<f64>() / m.len().max(1) as f64
    };
    let mean_force = [
        mean(Component::Fx),
        mean(Component::Fy),
        if avg.has_fz {
            mean(Component::Fz)
        } else {
            f64::NAN
        },
    ];
    let sine = peak_sine_fit(&case.cutter, cut, &analysis);
    Ok(FileResult {
        path: path.to_path_buf(),
        info,
        axes: mapping.to_string(),
        cut: *cut,
        analysis,
        mean_force,
        start_angle: f64::NAN,
        sine,
        reader_warnings,
    })
}

fn spill_counter() -> usize {
    use std::sync::atomic::{AtomicUsize, Ordering};
    static N: AtomicUsize = AtomicUsize::new(0);
    N.fetch_add(1, Ordering::Relaxed)
}

#[allow(clippy::too_many_arguments)]
fn first_pass<R: std::io::BufRead>(
    reader: &mut RecordingReader<R>,
    axes: &runout_io::recording::ResolvedAxes,
    factors: &[f64],
    pulse: Option<usize>,
    has_z: bool,
    spill: &mut Spill,
    pb: &ProgressBar,
    sink: &mut signal::ChunkSink<'_>,
) -> Result<()> {
    let mut w = BufWriter::new(
        File::create(&spill.path)
            .with_context(|| format!("creating temporary file {}", spill.path.display()))?,
    );
    let mut chunk = RecChunk::default();
    let (mut fx, mut fy, mut fz) = (Vec::new(), Vec::new(), Vec::new());
    loop {
        let n = reader.read_chunk(&mut chunk, 65_536)?;
        if n == 0 {
            break;
        }
        axes.map_chunk(&chunk, Axis::X, &mut fx);
        axes.map_chunk(&chunk, Axis::Y, &mut fy);
        if !axes.map_chunk(&chunk, Axis::Z, &mut fz) {
            fz.clear();
            fz.resize(n, 0.0);
        }
        for (v, f) in [
            (&mut fx, factors[0]),
            (&mut fy, factors[1]),
            (&mut fz, factors[2]),
        ] {
            if f != 1.0 {
                v.iter_mut().for_each(|x| *x *= f);
            }
        }
        let pv = pulse.map(|i| chunk.channel(i));
        for q in 0..n {
            for v in [fx[q], fy[q], fz[q]].into_iter().chain(pv.map(|p| p[q])) {
                w.write_all(&v.to_le_bytes())?;
            }
        }
        spill.rows += n as u64;
        let c = signal::Chunk {
            fx: &fx,
            fy: &fy,
            fz: has_z.then_some(&fz[..]),
            pulse: pv,
        };
        sink(c)?;
        pb.set_position(reader.bytes_read());
    }
    w.flush()?;
    Ok(())
}

fn replay_spill(
    spill: &Spill,
    has_z: bool,
    pb: &ProgressBar,
    sink: &mut signal::ChunkSink<'_>,
) -> Result<()> {
    const ROWS: usize = 65_536;
    let mut r = BufReader::new(
        File::open(&spill.path)
            .with_context(|| format!("reading temporary file {}", spill.path.display()))?,
    );
    let c = spill.columns;
    let mut buf = vec![0u8; ROWS * c * 8];
    let mut cols: Vec<Vec<f64>> = vec![Vec::with_capacity(ROWS); c];
    let mut left = spill.rows;
    while left > 0 {
        let n = (left as usize).min(ROWS);
        r.read_exact(&mut buf[..n * c * 8])?;
        cols.iter_mut().for_each(Vec::clear);
        for row in buf[..n * c * 8].chunks_exact(c * 8) {
            for (j, b) in row.chunks_exact(8).enumerate() {
                cols[j].push(f64::from_le_bytes(b.try_into().unwrap_or([0; 8])));
            }
        }
        let ch = signal::Chunk {
            fx: &cols[0],
            fy: &cols[1],
            fz: has_z.then_some(&cols[2][..]),
            pulse: cols.get(3).map(|v| &v[..]),
        };
        sink(ch)?;
        pb.inc((n * c * 8) as u64);
        left -= n as u64;
    }
    Ok(())
}

// ---------------------------------------------------------------------------------------------
// Methods on the averaged signal.

fn peak_sine_fit(cutter: &Cutter, cut: &Cut, an: &SignalAnalysis) -> Result<SineFit, String> {
    let peaks: Vec<f64> = an.average.tooth_peaks.iter().map(|p| p.peak).collect();
    let se: Vec<f64> = an.average.tooth_peaks.iter().map(|p| p.se).collect();
    let mut tp = ToothPeaks::new(peaks).map_err(|e| e.to_string())?;
    if se.iter().all(|s| s.is_finite() && *s > 0.0) {
        tp = tp.with_se(se).map_err(|e| e.to_string())?;
    }
    let cond =
        PeakConditions::new(cut.fz(), peak_immersion(cutter, cut)).map_err(|e| e.to_string())?;
    sine_fit(&tp, &cond, SineHypothesis::Teeth).map_err(|e| e.to_string())
}

fn mean_force_calibration(
    case: &IdentifyCase,
    files: &[FileResult],
) -> Result<MeanForceCalibration, String> {
    let feeds: Vec<f64> = files.iter().map(|f| f.cut.fz()).collect();
    let distinct = {
        let mut v = feeds.clone();
        v.sort_by(f64::total_cmp);
        v.dedup_by(|a, b| (*a - *b).abs() < 1e-12);
        v.len()
    };
    if distinct < 2 {
        return Err("needs recordings at ≥ 2 different feeds".into());
    }
    let c0 = &files[0].cut;
    if files.iter().any(|f| {
        (f.cut.ap() - c0.ap()).abs() > 1e-12
            || f.cut.immersion(&case.cutter) != c0.immersion(&case.cutter)
    }) {
        return Err("needs the same a_p and engagement in every recording".into());
    }
    let data: Vec<MeanForces> = files
        .iter()
        .map(|f| MeanForces {
            fz_mm: f.cut.fz(),
            fx_n: f.mean_force[0],
            fy_n: f.mean_force[1],
            fz_n: f.mean_force[2].is_finite().then_some(f.mean_force[2]),
        })
        .collect();
    if !case.cutter.is_flat() {
        // κ(z) and the per-disk window: the general design (400 disks: the integrals per disk
        // are exact, the disks only sample R(z) and κ(z))
        let design = runout_core::identify::MeanForceDesign::new(
            &runout_core::edge::EdgeTable::new(&case.cutter, c0, 400),
        );
        return runout_core::identify::calibrate_mean_forces_general(&design, &data)
            .map_err(|e| e.to_string());
    }
    let (st, ex) = c0.immersion(&case.cutter);
    calibrate_mean_forces(case.cutter.teeth(), c0.ap(), st, ex, &data).map_err(|e| e.to_string())
}

fn coefficients_of(c: &MeanForceCalibration) -> CuttingCoefficients {
    CuttingCoefficients::from_array([
        c.ktc.value,
        c.krc.value,
        c.kac.map_or(0.0, |e| e.value),
        c.kte.value,
        c.kre.value,
        c.kae.map_or(0.0, |e| e.value),
    ])
}

/// A typical coefficient ratio: only the phase of the tooth-passing harmonic is used.
fn default_coefficients() -> CuttingCoefficients {
    CuttingCoefficients::from_array([2000.0, 800.0, 300.0, 0.0, 0.0, 0.0])
}

/// Reference for the branch of the harmonic alignment: the pipeline's tooth-0 period start maps
/// to the entry angle φ_st, which keeps its tooth numbering.
fn branch_reference(cutter: &Cutter, f: &FileResult) -> f64 {
    let avg = &f.analysis.average;
    let (st, _) = f.cut.immersion(cutter);
    let b0 = avg
        .tooth_peaks
        .first()
        .map(|p| p.period_start)
        .unwrap_or(0.0);
    avg.angle_origin - b0 + st
}

/// First estimate of the spindle angle of bin 0 (absolute with a pulse + tooth-0 angle,
/// otherwise from the tooth-passing harmonic, methods.md §4.7).
fn initial_start_angle(cutter: &Cutter, f: &FileResult, kc: &CuttingCoefficients) -> f64 {
    if f.analysis.average.tooth_reference == ToothReference::Absolute {
        return f.analysis.average.angle_origin;
    }
    let mut probe = waveform_case(cutter, f);
    probe.waveform.start_angle = 0.0;
    harmonic_start_angle(&probe, [0.0; 2], [0.0; 2], kc, branch_reference(cutter, f))
}

fn waveform_case(cutter: &Cutter, f: &FileResult) -> WaveformCase {
    let avg = &f.analysis.average;
    let comp = |c: Component, axis: FitAxis| {
        let x = avg.component(c);
        let values = x.mean.clone();
        let se = Some(x.se.clone()).filter(|s| s.iter().all(|v| v.is_finite() && *v > 0.0));
        FitComponent { axis, values, se }
    };
    let mut components = vec![
        comp(Component::Fx, FitAxis::X),
        comp(Component::Fy, FitAxis::Y),
    ];
    if avg.has_fz {
        components.push(comp(Component::Fz, FitAxis::Z));
    }
    WaveformCase {
        cutter: cutter.clone(),
        cut: f.cut,
        waveform: AveragedWaveform {
            start_angle: f.start_angle,
            components,
            revolutions: avg.revolutions,
        },
    }
}

/// Full-signal fit of all recordings. Without an absolute angle, each recording's start angle is
/// first searched within ±8° without runout, then refined against the fitted runout (±1°, coefficients re-solved linearly) and the fit
/// repeated until no start angle moves by more than 0.005° (at most 3 refits).
fn fit_all(case: &IdentifyCase, files: &mut [FileResult]) -> Result<FullSignalFit, String> {
    let opts = FullSignalOptions {
        fit_tilt: case.fit_tilt,
        ..FullSignalOptions::default()
    };
    let cases = |files: &[FileResult]| {
        files
            .iter()
            .map(|f| waveform_case(&case.cutter, f))
            .collect::<Vec<_>>()
    };
    // The harmonic start can be several degrees off when edge forces dominate (straight flutes):
    // first a wide search without runout (runout modulates amplitudes, not the timing).
    for f in files
        .iter_mut()
        .filter(|f| f.analysis.average.tooth_reference != ToothReference::Absolute)
    {
        let wc = waveform_case(&case.cutter, f);
        // a ball, bull nose or taper: the harmonic phase of a start model without the lead angle
        // can be far off (the tooth-passing harmonic mixes windows that differ per disk), so
        // the search spans half a tooth pitch
        let half = if case.cutter.is_flat() {
            8f64.to_radians()
        } else {
            std::f64::consts::PI / case.cutter.teeth() as f64
        };
        f.start_angle = refine_start_angle(&wc, f.start_angle, half, [0.0; 2], [0.0; 2]).0;
    }
    let mut fit = full_signal_fit(&cases(files), &opts).map_err(|e| e.to_string())?;
    // A ball, bull nose or taper couples the start angle more strongly with λ (the runout is
    // seen through a few small per-disk windows): wider steps and more alternations. Measured
    // on a ball at a_p 0.2 mm: the runout-free search lands 1–2° off, which ±1° steps do not
    // recover (R² 0.95 instead of 0.9999).
    let (half, rounds) = if case.cutter.is_flat() {
        (1f64.to_radians(), 3)
    } else {
        (4f64.to_radians(), 8)
    };
    for _ in 0..rounds {
        let e = [fit.vector[0].value, fit.vector[1].value];
        let tau = fit.tilt.map_or([0.0; 2], |t| [t[0].value, t[1].value]);
        let mut moved = 0.0f64;
        for f in files
            .iter_mut()
            .filter(|f| f.analysis.average.tooth_reference != ToothReference::Absolute)
        {
            let wc = waveform_case(&case.cutter, f);
            let (t, _) = refine_start_angle(&wc, f.start_angle, half, e, tau);
            moved = moved.max(wrap_pi(t - f.start_angle).abs());
            f.start_angle = t;
        }
        if moved < 0.005f64.to_radians() {
            break;
        }
        let o = FullSignalOptions {
            initial_runout: Some(e),
            ..opts.clone()
        };
        fit = full_signal_fit(&cases(files), &o).map_err(|e| e.to_string())?;
    }
    Ok(fit)
}

// ---------------------------------------------------------------------------------------------
// Reporting.

fn est(v: f64, se: Option<f64>, scale: f64) -> (f64, Json) {
    (v * scale, se.map_or(Json::Null, |s| json!(s * scale)))
}

fn sine_json(s: &Result<SineFit, String>) -> Json {
    match s {
        Err(e) => json!({ "error": e }),
        Ok(f) => {
            let (c, c_se) = est(f.mean.value, f.mean.se, 1.0);
            let (a, a_se) = est(f.amplitude.value, f.amplitude.se, 1.0);
            let (p, p_se) = est(f.phase.value, f.phase.se, 1f64.to_degrees());
            let (o, o_se) = est(f.offset.value, f.offset.se, 1e3);
            let (l, l_se) = est(f.angle.value, f.angle.se, 1f64.to_degrees());
            json!({
                "method": "seed 003 sine fit of per-tooth peaks (methods.md §4.2)",
                "mean_N": c, "mean_N_se": c_se, "amplitude_N": a, "amplitude_N_se": a_se,
                "phase_deg": p, "phase_deg_se": p_se, "offset_um": o, "offset_um_se": o_se,
                "angle_deg": l, "angle_deg_se": l_se, "r_squared": f.r_squared,
            })
        }
    }
}

fn fit_json(fit: &Result<FullSignalFit, String>, files: &[FileResult]) -> Json {
    let f = match fit {
        Err(e) => return json!({ "error": e }),
        Ok(f) => f,
    };
    let names = [
        "ktc_N_per_mm2",
        "krc_N_per_mm2",
        "kac_N_per_mm2",
        "kte_N_per_mm",
        "kre_N_per_mm",
        "kae_N_per_mm",
    ];
    let mut coef = serde_json::Map::new();
    for (i, n) in names.iter().enumerate() {
        coef.insert(n.to_string(), json!(f.coefficients[i]));
        coef.insert(
            format!("{n}_se"),
            f.coefficient_se[i].map_or(Json::Null, |s| json!(s)),
        );
    }
    let (o, o_se) = est(f.offset.value, f.offset.se, 1e3);
    let (l, l_se) = est(f.angle.value, f.angle.se, 1f64.to_degrees());
    json!({
        "method": "full-signal non-linear least squares of the averaged waveforms (all recordings jointly)",
        "offset_um": o, "offset_um_se": o_se, "angle_deg": l, "angle_deg_se": l_se,
        "tilt_um_per_mm": f.tilt.map(|t| [t[0].value * 1e3, t[1].value * 1e3]),
        "tilt_um_per_mm_se": f.tilt.map(|t| [t[0].se.map(|s| s * 1e3), t[1].se.map(|s| s * 1e3)]),
        "observability": f.observability,
        "coefficients": coef,
        "parameters": f.parameters,
        "correlation": f.correlation,
        "residual_rms_N": f.residual_rms_n,
        "r_squared": f.r_squared,
        "condition": f.condition,
        "ill_conditioned": f.ill_conditioned,
        "disks": f.disks,
        "start_angle_deg": files.iter().map(|x| x.start_angle.to_degrees()).collect::<Vec<_>>(),
        "warnings": f.warnings,
    })
}

/// K = 2: the radius difference R₀ − R₁ from the two per-tooth peaks (the sine fit is
/// degenerate there), µm ± SE.
fn radius_difference_um(cutter: &Cutter, f: &FileResult) -> Option<(f64, Option<f64>)> {
    if cutter.teeth() != 2 {
        return None;
    }
    let p = &f.analysis.average.tooth_peaks;
    let mut tp = ToothPeaks::new(p.iter().map(|p| p.peak).collect()).ok()?;
    let se: Vec<f64> = p.iter().map(|p| p.se).collect();
    if se.iter().all(|s| s.is_finite() && *s > 0.0) {
        tp = tp.with_se(se).ok()?;
    }
    let cond = PeakConditions::new(f.cut.fz(), peak_immersion(cutter, &f.cut)).ok()?;
    let d = radius_difference(&tp, &cond).ok()?;
    Some((d.value * 1e3, d.se.map(|s| s * 1e3)))
}

/// R₀ − R₁ (µm) at the tool tip from a fitted runout (the full-signal check of the peak value).
fn fitted_radius_difference_um(cutter: &Cutter, fit: &FullSignalFit) -> Option<f64> {
    if cutter.teeth() != 2 {
        return None;
    }
    let r = runout_core::Runout::new(fit.offset.value, fit.angle.value).ok()?;
    Some((r.tooth_radius(cutter, 0, 0.0) - r.tooth_radius(cutter, 1, 0.0)) * 1e3)
}

/// K = 2: the peaks' radius difference as a check of the full-signal fit (issue 11 item 4): a
/// warning per recording where they disagree by more than max(3 SE, 30 % of the fitted value,
/// 1 µm) — the proportional-peak model is biased by edge forces and helix smearing, hence the
/// generous bound; a sign flip or a factor of two points at a wrong fit or tooth numbering.
fn radius_difference_warnings(
    cutter: &Cutter,
    files: &[FileResult],
    fit: &FullSignalFit,
) -> Vec<String> {
    let Some(d_fit) = fitted_radius_difference_um(cutter, fit) else {
        return Vec::new();
    };
    files
        .iter()
        .filter_map(|f| {
            let (d, se) = radius_difference_um(cutter, f)?;
            let bound = (3.0 * se.unwrap_or(0.0)).max(0.3 * d_fit.abs()).max(1.0);
            ((d - d_fit).abs() > bound).then(|| {
                format!(
                    "{}: the two peaks give R₀ − R₁ = {d:.2} µm, the full-signal fit {d_fit:.2} µm \
                     (more than {bound:.2} µm apart): check the fit and the tooth numbering",
                    f.path.display()
                )
            })
        })
        .collect()
}

fn report_json(
    case: &IdentifyCase,
    files: &[FileResult],
    cal: &Result<MeanForceCalibration, String>,
    fit: &Result<FullSignalFit, String>,
    extra: &Extra,
) -> Json {
    let c = &case.cutter;
    let recs: Vec<Json> = files
        .iter()
        .map(|f| {
            let a = &f.analysis;
            let (st, ex) = f.cut.immersion(c);
            json!({
                "file": f.path.display().to_string(),
                "format": f.info.format,
                "metadata": f.info.metadata,
                "sample_rate_hz": f.info.sample_rate_hz,
                "samples": a.scan.samples,
                "axes": f.axes,
                "fz_mm": f.cut.fz(), "ap_mm": f.cut.ap(), "entry_deg": st.to_degrees(), "exit_deg": ex.to_degrees(),
                "spindle": {
                    "rpm": a.speed.rpm, "rpm_se": a.speed.rpm_se, "nominal_rpm": a.speed.nominal_rpm,
                    "deviation_percent": 100.0 * a.speed.deviation, "method": format!("{:?}", a.speed.method),
                },
                "section": { "from_s": a.scan.section.from_s, "to_s": a.scan.section.to_s, "overridden": a.scan.section.overridden },
                "revolutions_averaged": a.average.revolutions,
                "offset_subtracted_N": a.average.offset_subtracted,
                "tooth_reference": a.average.tooth_reference,
                "mean_force_N": { "fx": f.mean_force[0], "fy": f.mean_force[1], "fz": f.mean_force[2].is_finite().then_some(f.mean_force[2]) },
                "peak_component": format!("{:?}", a.average.peak_component),
                "tooth_peaks": a.average.tooth_peaks.iter().map(|p| json!({"tooth": p.tooth, "peak_N": p.peak, "peak_N_se": p.se, "spindle_angle_deg": p.angle.to_degrees()})).collect::<Vec<_>>(),
                "sine_fit": sine_json(&f.sine),
                "radius_difference_um": radius_difference_um(c, f).map(|d| d.0),
                "radius_difference_um_se": radius_difference_um(c, f).and_then(|d| d.1),
                "warnings": a.warnings.iter().chain(&f.reader_warnings).collect::<Vec<_>>(),
            })
        })
        .collect();
    let cal_json = match cal {
        Err(e) => json!({ "skipped": e }),
        Ok(k) => serde_json::to_value(k).unwrap_or(Json::Null),
    };
    json!({
        "schema": "runout.identify.recording/1",
        "conventions": "angles from tooth 0 in the direction of rotation; forces on the workpiece; tooth 0 is absolute only with a pulse channel and tooth0_angle_deg, otherwise the first tooth period of the average",
        "inputs": {
            "teeth": c.teeth(), "diameter_mm": c.diameter(), "helix_deg": c.helix().to_degrees(),
            "profile": c.profile(), "flute_lead": c.lead(),
            "nominal_rpm": files.first().map(|f| f.cut.rpm()),
            "peak_component": case.peak_component, "fit_tilt": case.fit_tilt,
            "section_s": case.section_s,
        },
        "recordings": recs,
        "mean_force_calibration": cal_json,
        "full_signal": fit_json(fit, files),
        "measuring_chain": {
            "decision": extra.decision,
            "fit": fit.as_ref().ok().and_then(|f| f.chain.as_ref()),
        },
        "tooth_numbering_aligned": extra.renumbered.iter().map(|(c, j)| json!({"recording": c, "shifted_by_teeth": j})).collect::<Vec<_>>(),
        "consistency": extra.consistency,
        "status": extra.verdicts,
        "fitted_radius_difference_um": fit.as_ref().ok().and_then(|f| fitted_radius_difference_um(c, f)),
        "radius_difference_warnings": fit.as_ref().map(|f| radius_difference_warnings(c, files, f)).unwrap_or_default(),
    })
}

/// True when every recording is a full slot (entry 0, exit π), where the mean-force calibration
/// is unbiased by runout.
fn slotting(case: &IdentifyCase) -> bool {
    case.cuts.iter().all(|c| {
        let (st, ex) = c.immersion(&case.cutter);
        st.abs() < 1e-9 && (ex - std::f64::consts::PI).abs() < 1e-9
    })
}

fn pm(se: Option<f64>, scale: f64, digits: usize) -> String {
    se.filter(|s| s.is_finite())
        .map_or_else(|| "(no SE)".into(), |s| format!("± {:.digits$}", s * scale))
}

/// The profile in the config vocabulary (`profile = …`, `corner_radius_mm`, `taper_deg`).
fn profile_label(p: &runout_core::RadiusProfile) -> String {
    use runout_core::RadiusProfile::*;
    match p {
        Flat => "flat".into(),
        Ball => "ball".into(),
        BullNose { corner_mm } => format!("bull_nose (corner radius {corner_mm} mm)"),
        Tapered { taper_deg } => format!("tapered ({taper_deg}°)"),
    }
}

fn print_text(
    case: &IdentifyCase,
    files: &[FileResult],
    cal: &Result<MeanForceCalibration, String>,
    fit: &Result<FullSignalFit, String>,
    extra: &Extra,
) {
    println!(
        "runout identify: K = {}, D = {} mm, helix {:.1}°, profile {}",
        case.cutter.teeth(),
        case.cutter.diameter(),
        case.cutter.helix().to_degrees(),
        profile_label(case.cutter.profile())
    );
    for f in files {
        let a = &f.analysis;
        println!(
            "\n{} ({} samples at {} Hz; axes {})",
            f.path.display(),
            a.scan.samples,
            f.info.sample_rate_hz,
            f.axes
        );
        println!(
            "  spindle {:.2} ± {:.2} rpm (nominal {:.0}, {:+.2} %); steady cut {:.3}–{:.3} s{}, {} revolutions averaged",
            a.speed.rpm,
            a.speed.rpm_se,
            a.speed.nominal_rpm,
            100.0 * a.speed.deviation,
            a.scan.section.from_s,
            a.scan.section.to_s,
            if a.scan.section.overridden { " (given)" } else { " (detected)" },
            a.average.revolutions
        );
        let peaks: Vec<String> = a
            .average
            .tooth_peaks
            .iter()
            .map(|p| format!("{:.1} ± {:.1}", p.peak, p.se))
            .collect();
        println!(
            "  per-tooth peaks of {:?} (N): {}",
            a.average.peak_component,
            peaks.join(", ")
        );
        match &f.sine {
            Ok(s) => println!(
                "  sine fit (seed 003): ρ = {:.2} {} µm, λ = {:.1} {}°, R² = {:.4}",
                s.offset.value * 1e3,
                pm(s.offset.se, 1e3, 2),
                s.angle.value.to_degrees(),
                pm(s.angle.se, 1f64.to_degrees(), 1),
                s.r_squared
            ),
            Err(e) => println!("  sine fit (seed 003): not available: {e}"),
        }
        if let Some((d, se)) = radius_difference_um(&case.cutter, f) {
            println!(
                "  radius difference R₀ − R₁ from the two peaks: {d:.2} {} µm (how unevenly the teeth cut; λ needs the full-signal fit)",
                pm(se, 1.0, 2)
            );
        }
        for w in a.warnings.iter().chain(&f.reader_warnings) {
            println!("  warning: {w}");
        }
    }
    match cal {
        Ok(k) => println!(
            "\nmean-force calibration: K_tc {:.1}, K_rc {:.1} N/mm², K_te {:.2}, K_re {:.2} N/mm{}",
            k.ktc.value,
            k.krc.value,
            k.kte.value,
            k.kre.value,
            if slotting(case) {
                ""
            } else {
                "\n  (start value only: with runout at partial immersion teeth lose contact near sin φ = 0, which biases it; the full-signal fit models this)"
            }
        ),
        Err(e) => println!("\nmean-force calibration: skipped ({e})"),
    }
    println!("measuring chain: {}", extra.decision.reason);
    if let Ok(Some(c)) = fit.as_ref().map(|f| f.chain.as_ref()) {
        for m in &c.modes {
            println!(
                "  mode on {:?}: {:.1} {} Hz, ζ {:.4} {}",
                m.axis,
                m.frequency_hz.value,
                pm(m.frequency_hz.se, 1.0, 1),
                m.damping.value,
                pm(m.damping.se, 1.0, 4)
            );
        }
        println!(
            "  harmonics fitted: 0..{} of the spindle frequency; R² {:.4} (rigid model on the same band {:.4})",
            c.max_harmonic.iter().max().unwrap_or(&0),
            fit.as_ref().map(|f| f.r_squared).unwrap_or(f64::NAN),
            c.rigid_r_squared
        );
    }
    for (c, j) in &extra.renumbered {
        println!(
            "tooth numbering of {} shifted by {j} tooth pitch(es) to agree with the other recordings",
            files[*c].path.display()
        );
    }
    let status = |p: &str| extra.verdicts.parameters.iter().find(|v| v.parameter == p);
    let shown = |p: &str| status(p).is_none_or(|v| v.status == "identified");
    match fit {
        Ok(f) => {
            let head = if shown("offset") && shown("angle") {
                "full-signal fit"
            } else {
                "full-signal fit (NOT IDENTIFIED, see below)"
            };
            println!(
                "{head}: ρ = {:.2} {} µm, λ = {:.1} {}° (from tooth 0, in the rotation direction)",
                f.offset.value * 1e3,
                pm(f.offset.se, 1e3, 2),
                f.angle.value.to_degrees(),
                pm(f.angle.se, 1f64.to_degrees(), 1)
            );
            if let Some(d) = fitted_radius_difference_um(&case.cutter, f) {
                println!("  radius difference R₀ − R₁ of the fitted runout: {d:.2} µm");
                for w in radius_difference_warnings(&case.cutter, files, f) {
                    println!("  warning: {w}");
                }
            }
            let names = ["K_tc", "K_rc", "K_ac", "K_te", "K_re", "K_ae"];
            let keys = ["ktc", "krc", "kac", "kte", "kre", "kae"];
            let units = ["N/mm²", "N/mm²", "N/mm²", "N/mm", "N/mm", "N/mm"];
            let parts: Vec<String> = (0..6)
                .map(|i| {
                    let value = format!(
                        "{:.1} {} {}",
                        f.coefficients[i],
                        pm(f.coefficient_se[i], 1.0, 1),
                        units[i]
                    );
                    if f.coefficient_se[i].is_some() && !shown(keys[i]) {
                        format!("{} not identified ({value})", names[i])
                    } else {
                        format!("{} {value}", names[i])
                    }
                })
                .collect();
            println!("  {}", parts.join(", "));
            println!(
                "  residual RMS {:.2} N, R² {:.4}, condition {:.2e}{}",
                f.residual_rms_n,
                f.r_squared,
                f.condition,
                if f.ill_conditioned {
                    " (ILL-CONDITIONED)"
                } else {
                    ""
                }
            );
            for w in &f.warnings {
                println!("  warning: {w}");
            }
            for r in &extra.verdicts.fit {
                println!("  NOT IDENTIFIED (any parameter): {r}");
            }
            for v in &extra.verdicts.parameters {
                if let Some(r) = &v.reason {
                    println!("  not identified: {}: {r}", v.parameter);
                }
            }
            if let Some(c) = &extra.consistency {
                println!(
                    "  per recording (coefficients and chain of the joint fit held): ρ spread {:.1} %, λ spread {:.1}°",
                    c.offset_spread_percent, c.angle_spread_deg
                );
                for r in &c.recordings {
                    println!(
                        "    {}: ρ = {:.2} {} µm, λ = {:.1} {}°{}",
                        r.file,
                        r.offset_um,
                        pm(r.offset_um_se, 1.0, 2),
                        r.angle_deg,
                        pm(r.angle_deg_se, 1.0, 1),
                        if r.disagrees { "  (DISAGREES)" } else { "" }
                    );
                }
                for w in &c.warnings {
                    println!("  warning: {w}");
                }
            }
        }
        Err(e) => println!("full-signal fit: failed: {e}"),
    }
}

fn write_plots(
    dir: &Path,
    ext: &str,
    case: &IdentifyCase,
    files: &[FileResult],
    fit: &Result<FullSignalFit, String>,
    extra: &Extra,
) -> Result<()> {
    let mut marks = Vec::new();
    for (i, f) in files.iter().enumerate() {
        let avg = &f.analysis.average;
        let deg: Vec<f64> = (0..avg.bins)
            .map(|j| (f.start_angle + TAU * j as f64 / avg.bins as f64).to_degrees())
            .collect();
        let mx = &f.analysis.average.component(Component::Fx).mean;
        let my = &f.analysis.average.component(Component::Fy).mean;
        let mz = &f.analysis.average.component(Component::Fz).mean;
        let measured = [
            Curve {
                label: "F_x (N)",
                values: mx,
            },
            Curve {
                label: "F_y (N)",
                values: my,
            },
            Curve {
                label: "F_z (N)",
                values: mz,
            },
        ];
        let n = if avg.has_fz { 3 } else { 2 };
        if let Ok(fit) = fit {
            let kc = CuttingCoefficients::from_array(fit.coefficients);
            let tau = fit.tilt.map_or([0.0; 2], |t| [t[0].value, t[1].value]);
            let mut pred = model_forces(
                &waveform_case(&case.cutter, f),
                f.start_angle,
                [fit.vector[0].value, fit.vector[1].value],
                tau,
                &kc,
            );
            // the model as the sensor records it (chain and resampling), when a chain was used
            if fit.chain.is_some() {
                let chain = chain::chain_of(fit, extra.given.as_ref());
                let f_rev = f.analysis.speed.rpm / 60.0;
                let spr = Some(f.info.sample_rate_hz / f_rev);
                let band = matches!(extra.decision.used.as_str(), "band_limit");
                for (p, axis) in pred.iter_mut().zip([&chain.x, &chain.y, &chain.z]) {
                    if !band {
                        *p = axis.apply_periodic(p, f_rev, spr);
                    }
                }
            }
            let predicted = [
                Curve {
                    label: "F_x (N)",
                    values: &pred[0],
                },
                Curve {
                    label: "F_y (N)",
                    values: &pred[1],
                },
                Curve {
                    label: "F_z (N)",
                    values: &pred[2],
                },
            ];
            let title = format!(
                "{}: averaged ({} rev) vs full-signal model{}",
                file_label(&f.path),
                avg.revolutions,
                match extra.decision.used.as_str() {
                    "rigid" => "",
                    "band_limit" => " (rigid, fitted on the band)",
                    _ => " through the measuring chain",
                }
            );
            waveform_overlay(
                &dir.join(format!("waveform_{i}.{ext}")),
                &deg,
                &measured[..n],
                &predicted[..n],
                &title,
            )?;
        }
        if let Ok(s) = &f.sine {
            let peaks: Vec<f64> = avg.tooth_peaks.iter().map(|p| p.peak).collect();
            let se: Vec<f64> = avg.tooth_peaks.iter().map(|p| p.se).collect();
            let title = format!(
                "{}: per-tooth peaks of {:?}",
                file_label(&f.path),
                avg.peak_component
            );
            tooth_peak_bars(
                &dir.join(format!("tooth_peaks_{i}.{ext}")),
                &peaks,
                &se,
                s.mean.value,
                s.amplitude.value,
                s.phase.value,
                &title,
            )?;
            marks.push((
                format!("sine fit {}", file_label(&f.path)),
                s.offset.value * 1e3,
                s.angle.value.to_degrees(),
                s.offset.se,
                s.angle.se,
            ));
        }
    }
    if let Ok(fit) = fit {
        marks.push((
            "full-signal fit".into(),
            fit.offset.value * 1e3,
            fit.angle.value.to_degrees(),
            fit.offset.se,
            fit.angle.se,
        ));
    }
    let rm: Vec<RunoutMark> = marks
        .iter()
        .map(|(l, o, a, ose, ase)| RunoutMark {
            label: l,
            offset_um: *o,
            angle_deg: *a,
            offset_se_um: ose.map_or(f64::NAN, |s| s * 1e3),
            angle_se_deg: ase.map_or(f64::NAN, |s| s.to_degrees()),
        })
        .collect();
    runout_polar(
        &dir.join(format!("runout_polar.{ext}")),
        &rm,
        case.cutter.teeth(),
        "identified runout (±1 SE)",
    )?;
    Ok(())
}

fn file_label(p: &Path) -> String {
    p.file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default()
}
