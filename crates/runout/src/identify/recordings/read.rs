//! Reading one recording: pass 1 over the source with a binary spill of the workpiece-frame
//! forces (and pulse), passes 2 and 3 over the spill (`runout_core::signal::analyse_replay`).

use super::fit::peak_sine_fit;
use super::{FileResult, RecordingsRequest};
use crate::job::{Progress, Source};
use crate::spill::Spill;
use anyhow::{bail, Context, Result};
use runout_core::plausibility::{ClipDetector, Finding, MAX_PLAUSIBLE_FORCE_N};
use runout_core::signal::{self, ForceComponent, PulseConfig, SignalConfig};
use runout_core::Cut;
use runout_io::recording::{
    AxisMapping, Format, FrameAxis, ReadOptions, RecordingChunk, RecordingInfo, RecordingReader,
    ResolvedAxes,
};
use runout_io::units::Quantity;
use std::hash::Hasher;
use std::io::BufRead;

/// What pass 1 saw besides the signal: flat tops at a channel's range limit and a hash of the
/// mapped samples (for the same data passed twice; compared within a run only). XXH3 over each
/// chunk's column bytes: ≈ 0.1 cycle per byte, where SipHash fed value by value (the standard
/// library's `DefaultHasher`) took ≈ 165 instructions per row (issue 18).
#[derive(Default)]
struct Watch {
    clip: [ClipDetector; 3],
    hash: twox_hash::XxHash3_64,
}

/// Rows per chunk of pass 1.
const ROWS: usize = 65_536;

/// Force unit factor to N for a channel, from its unit (none = N).
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

/// How the channels of a recording become the workpiece-frame forces.
struct Channels {
    mapping: AxisMapping,
    axes: ResolvedAxes,
    factors: Vec<f64>,
    pulse: Option<usize>,
    /// The recording's name and, per workpiece axis, its source channel: index, how messages
    /// name it, and its column in a text file (for [`implausible_force`]).
    file: String,
    sources: [Option<(usize, String, Option<usize>)>; 3],
}

fn channels(name: &str, info: &RecordingInfo, req: &RecordingsRequest) -> Result<Channels> {
    let names: Vec<String> = info.channels.iter().map(|c| c.name.clone()).collect();
    let mapping = match &req.axes {
        Some(t) => AxisMapping::parse(t)?,
        None => AxisMapping::identity_for(&names).map_err(|e| {
            anyhow::anyhow!(
                "{e}; give the mapping with --axes (e.g. \"x = Fx, y = Fy, z = Fz\"); channels: {}",
                names.join(", ")
            )
        })?,
    };
    let axes = mapping.resolve(info)?;
    if !(axes.has(FrameAxis::X) && axes.has(FrameAxis::Y)) {
        bail!("{name}: the axis mapping `{mapping}` must give both x and y");
    }
    let factors: Vec<f64> = FrameAxis::ALL
        .iter()
        .map(|&ax| {
            mapping
                .source(ax)
                .map(|s| force_factor(info, &s.channel))
                .transpose()
                .map(|f| f.unwrap_or(1.0))
        })
        .collect::<Result<_>>()?;
    let pulse = match &req.pulse_channel {
        Some(p) => Some(info.channel_index(p).with_context(|| {
            format!(
                "{name}: no pulse channel `{p}` (channels: {})",
                names.join(", ")
            )
        })?),
        None => None,
    };
    let text = matches!(info.format, Format::GenericCsv | Format::DynoWare { .. });
    let sources = FrameAxis::ALL.map(|ax| {
        let s = mapping.source(ax)?;
        let i = info.channel_index(&s.channel)?;
        let c = &info.channels[i];
        let unit = c.unit.as_deref().unwrap_or("N");
        // a text file's cell is found by its column; a binary format's channel by its name
        let column = if text {
            format!(", column {}", c.column)
        } else {
            String::new()
        };
        let name = format!("channel `{}` ({unit}{column})", c.header);
        Some((i, name, text.then_some(c.column)))
    });
    Ok(Channels {
        mapping,
        axes,
        factors,
        pulse,
        file: name.to_string(),
        sources,
    })
}

/// A sample of pass 1 beyond [`MAX_PLAUSIBLE_FORCE_N`] ([`implausible_force`]); [`analyse`]
/// adds the cell's line where the file can be read again ([`ImplausibleForce::located`]).
#[derive(Debug)]
struct ImplausibleForce {
    file: String,
    /// The sample (0-based) and, in a text file, the column of its cell.
    sample: u64,
    column: Option<usize>,
    /// What is wrong, without the file's name.
    detail: String,
}

impl std::fmt::Display for ImplausibleForce {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{}: {}", self.file, self.detail)
    }
}

impl std::error::Error for ImplausibleForce {}

impl ImplausibleForce {
    /// The error with the cell's place as the reader's errors give it (`file:line:column:`),
    /// found by reading the text file `src` again up to the sample (an error path only); as it
    /// is when the recording is binary, came from a pipe, or cannot be read again.
    fn located(self, src: &Source, opts: &ReadOptions) -> anyhow::Error {
        let line = match (self.column, src.as_path()) {
            (Some(_), Some(p)) if !runout_io::formats::is_stream(p) => src
                .open_recording(opts)
                .ok()
                .and_then(|r| r.line_of_sample(self.sample).ok().flatten()),
            _ => None,
        };
        match (line, self.column) {
            (Some(line), Some(column)) => {
                anyhow::anyhow!("{}:{line}:{column}: {}", self.file, self.detail)
            }
            _ => self.into(),
        }
    }
}

/// The error for a chunk whose workpiece axis `k` (forces `v`, N) holds a sample beyond
/// [`MAX_PLAUSIBLE_FORCE_N`]: the first such sample by its number and time, and the cell of its
/// source channel as the file has it.
fn implausible_force(ch: &Channels, chunk: &RecordingChunk, k: usize, v: &[f64]) -> anyhow::Error {
    let i = v
        .iter()
        .position(|x| x.abs() > MAX_PLAUSIBLE_FORCE_N)
        .unwrap_or(0);
    let axis = ["x", "y", "z"][k];
    let (source, column) = match &ch.sources[k] {
        Some((c, name, column)) => (format!("{name} reads {:e}", chunk.channel(*c)[i]), *column),
        None => (format!("workpiece {axis} is {:e} N", v[i]), None),
    };
    let sample = chunk.first_sample + i as u64;
    ImplausibleForce {
        file: ch.file.clone(),
        sample,
        column,
        detail: format!(
            "sample {} (counted from 1; t = {} s): {source}, a force of {:e} N on workpiece {axis} — \
             not a measured force (more than {MAX_PLAUSIBLE_FORCE_N:e} N, beyond any dynamometer's \
             range); check that cell",
            sample + 1,
            chunk.time_s[i],
            v[i].abs()
        ),
    }
    .into()
}

fn signal_config(
    info: &RecordingInfo,
    req: &RecordingsRequest,
    cut: &Cut,
    pulse: bool,
) -> Result<SignalConfig> {
    let mut cfg = SignalConfig::new(info.sample_rate_hz, req.cutter.teeth(), cut.rpm())?;
    cfg.section_s = req.section_s;
    cfg.peak_component = req.peak_component;
    cfg.entry_angle_rad = Some(cut.immersion(&req.cutter).0);
    if pulse {
        cfg.pulse = Some(PulseConfig {
            pulses_per_rev: req.pulses_per_rev,
            tooth0_angle_rad: req.tooth0_angle(),
            ..PulseConfig::once_per_rev()
        });
    }
    cfg.validate()?;
    Ok(cfg)
}

/// One recording through the signal pipeline and the sine fit of its peaks.
pub(super) fn analyse(
    src: &Source,
    req: &RecordingsRequest,
    cut: &Cut,
    progress: &mut dyn Progress,
) -> Result<FileResult> {
    let mut opts = ReadOptions::new();
    if let Some(fs) = req.sample_rate_hz {
        opts = opts.sample_rate_hz(fs);
    }
    opts.time_column = req.time_var.clone();
    let mut reader = src.open_recording(&opts)?;
    let info = reader.info().clone();
    let ch = channels(src.name(), &info, req)?;
    let cfg = signal_config(&info, req, cut, ch.pulse.is_some())?;
    let columns = 3 + ch.pulse.is_some() as usize;
    let path = Spill::temp_path("identify");
    let mut spill = Spill::create(path.clone(), columns)
        .with_context(|| format!("creating temporary file {}", path.display()))?;
    let total =
        info.file_bytes.unwrap_or(0) + 2 * 8 * columns as u64 * info.expected_samples.unwrap_or(0);
    progress.begin(src.name(), Some(total));
    let has_z = ch.axes.has(FrameAxis::Z);
    let mut pass = 0;
    let mut watch = Watch::default();
    let analysis = signal::analyse_replay::<anyhow::Error, _>(&cfg, |sink| {
        pass += 1;
        if pass == 1 {
            first_pass(&mut reader, &ch, &mut spill, progress, sink, &mut watch)
        } else {
            replay(&mut spill, has_z, progress, sink)
        }
    })
    .map_err(|e| match e.downcast::<ImplausibleForce>() {
        Ok(f) => f.located(src, &opts),
        Err(e) => e,
    })?;
    progress.end();
    let reader_warnings = reader.warnings().to_vec();
    let names = ["x", "y", "z"];
    let clipped: Vec<Finding> = watch
        .clip
        .iter()
        .zip(names)
        .filter(|(_, a)| *a != "z" || has_z)
        .filter_map(|(d, a)| d.finding(&format!("{} (workpiece {a})", src.name()), "N"))
        .collect();
    let avg = &analysis.average;
    let mean = |c: ForceComponent| {
        let m = &avg.component(c).mean;
        m.iter().sum::<f64>() / m.len().max(1) as f64
    };
    let fz = if avg.has_fz {
        mean(ForceComponent::Fz)
    } else {
        f64::NAN
    };
    let mean_force = [mean(ForceComponent::Fx), mean(ForceComponent::Fy), fz];
    let sine = peak_sine_fit(&req.cutter, cut, &analysis);
    Ok(FileResult {
        name: src.name().to_string(),
        info,
        axes: ch.mapping.to_string(),
        cut: *cut,
        analysis,
        mean_force,
        start_angle: f64::NAN,
        sine,
        reader_warnings,
        clipped,
        content_hash: watch.hash.finish(),
    })
}

/// Pass 1: the source in chunks, mapped to the workpiece frame in N, spilled and fed on.
///
/// Pipelined (issue 18): a second thread reads the next chunks (up to [`AHEAD`] ahead, their
/// buffers recycled) while this one maps, spills and averages the current one; a text
/// recording's rows are parsed on one worker per core (up to 4,
/// `RecordingReader::for_each_chunk`). Chunks arrive in order and the first read error is
/// returned after the chunks before it, as in a single loop.
fn first_pass<R: BufRead + Send>(
    reader: &mut RecordingReader<R>,
    ch: &Channels,
    spill: &mut Spill,
    progress: &mut dyn Progress,
    sink: &mut signal::ChunkSink<'_>,
    watch: &mut Watch,
) -> Result<()> {
    use std::sync::mpsc;
    type Parsed =
        std::result::Result<(RecordingChunk, usize, u64), runout_io::recording::RecordingError>;
    std::thread::scope(|scope| {
        let (full_tx, full_rx) = mpsc::sync_channel::<Parsed>(AHEAD);
        let (free_tx, free_rx) = mpsc::channel::<RecordingChunk>();
        for _ in 0..AHEAD + 1 {
            free_tx.send(RecordingChunk::default()).ok();
        }
        scope.spawn(move || {
            // ends at the end of the data, at an error, or when the consumer has stopped
            let Ok(mut chunk) = free_rx.recv() else {
                return;
            };
            let workers = std::thread::available_parallelism().map_or(1, |n| n.get().min(4));
            let read = reader.for_each_chunk(&mut chunk, ROWS, workers, |chunk, n, bytes| {
                let Ok(next) = free_rx.recv() else {
                    return false;
                };
                let full = std::mem::replace(chunk, next);
                full_tx.send(Ok((full, n, bytes))).is_ok()
            });
            if let Err(e) = read {
                full_tx.send(Err(e)).ok();
            }
        });
        let mut out = RecordingChunk {
            values: vec![Vec::new(); 3],
            ..Default::default()
        };
        for parsed in full_rx {
            let (chunk, n, bytes_read) = parsed?;
            map_chunk(&chunk, n, ch, &mut out, spill, sink, watch)?;
            progress.set_position(bytes_read);
            free_tx.send(chunk).ok();
        }
        Ok(())
    })
}

/// Chunks parsed ahead of the one being mapped and averaged.
const AHEAD: usize = 2;

/// One parsed chunk of pass 1 (`n` rows): mapped to the workpiece frame in N (`out`), watched, spilled and
/// fed to the signal pipeline.
fn map_chunk(
    chunk: &RecordingChunk,
    n: usize,
    ch: &Channels,
    out: &mut RecordingChunk,
    spill: &mut Spill,
    sink: &mut signal::ChunkSink<'_>,
    watch: &mut Watch,
) -> Result<()> {
    let has_z = ch.axes.has(FrameAxis::Z);
    {
        out.time_s.clone_from(&chunk.time_s); // the spill counts rows by the time column
        out.values.truncate(3);
        let [fx, fy, fz] = &mut out.values[..] else {
            unreachable!("three force columns")
        };
        ch.axes.map_chunk(chunk, FrameAxis::X, fx);
        ch.axes.map_chunk(chunk, FrameAxis::Y, fy);
        if !ch.axes.map_chunk(chunk, FrameAxis::Z, fz) {
            fz.clear();
            fz.resize(n, 0.0);
        }
        for (v, f) in [fx, fy, fz].into_iter().zip(&ch.factors) {
            if *f != 1.0 {
                v.iter_mut().for_each(|x| *x *= f);
            }
        }
        for (k, v) in out
            .values
            .iter()
            .take(if has_z { 3 } else { 2 })
            .enumerate()
        {
            watch.clip[k].push(v);
            watch.hash.write(bytemuck::cast_slice(v));
            // the detector's extremes: nothing to scan while the forces are plausible
            if watch.clip[k].max_abs() > MAX_PLAUSIBLE_FORCE_N {
                return Err(implausible_force(ch, chunk, k, v));
            }
        }
        if let Some(i) = ch.pulse {
            out.values.push(chunk.channel(i).to_vec());
        }
        spill.write(out)?;
        sink(as_signal(out, has_z))?;
    }
    Ok(())
}

/// A spilled or mapped chunk (fx, fy, fz[, pulse]) as the signal pipeline's chunk.
fn as_signal(c: &RecordingChunk, has_z: bool) -> signal::SignalChunk<'_> {
    signal::SignalChunk {
        fx: &c.values[0],
        fy: &c.values[1],
        fz: has_z.then_some(&c.values[2][..]),
        pulse: c.values.get(3).map(|v| &v[..]),
    }
}

/// Passes 2 and 3: the spill mapped, its blocks fed as they lie in the file; where the process
/// does not allow mapped files, read back on a second thread (issue 18: reading and decoding
/// the next blocks overlaps the pipeline's work on the current one; blocks arrive in order,
/// a read error after the blocks before it).
fn replay(
    spill: &mut Spill,
    has_z: bool,
    progress: &mut dyn Progress,
    sink: &mut signal::ChunkSink<'_>,
) -> Result<()> {
    let path = spill.path().to_path_buf();
    let context = || format!("reading temporary file {}", path.display());
    if let Some(mut blocks) = spill.mapped().with_context(context)? {
        // the file's pages themselves (`runout_io::mapped`): no copy, no reading thread
        while let Some(cols) = blocks.next_block().with_context(context)? {
            sink(signal::SignalChunk {
                fx: cols[0],
                fy: cols[1],
                fz: has_z.then(|| cols[2]),
                pulse: cols.get(3).copied(),
            })?;
            progress.advance((cols[0].len() * cols.len() * 8) as u64);
        }
        return blocks.finish().with_context(context);
    }
    use std::sync::mpsc;
    let mut r = spill.reader().with_context(context)?;
    std::thread::scope(|scope| {
        let (full_tx, full_rx) = mpsc::sync_channel::<std::io::Result<RecordingChunk>>(AHEAD);
        let (free_tx, free_rx) = mpsc::channel::<RecordingChunk>();
        for _ in 0..AHEAD + 1 {
            free_tx.send(RecordingChunk::default()).ok();
        }
        scope.spawn(move || {
            // ends at the end of the spill, at an error, or when the consumer has stopped
            while let Ok(mut chunk) = free_rx.recv() {
                match r.read_chunk(&mut chunk) {
                    Ok(0) => break,
                    Ok(_) => {
                        if full_tx.send(Ok(chunk)).is_err() {
                            break;
                        }
                    }
                    Err(e) => {
                        full_tx.send(Err(e)).ok();
                        break;
                    }
                }
            }
        });
        for read in full_rx {
            let chunk = read?;
            sink(as_signal(&chunk, has_z))?;
            progress.advance((chunk.values[0].len() * chunk.values.len() * 8) as u64);
            free_tx.send(chunk).ok();
        }
        Ok(())
    })
}
