//! Recordings held as arrays in memory (one `f64` vector per channel), e.g. NumPy arrays from the
//! Python package: delivered through the same [`BinaryRecording`] as the binary formats, so every
//! job reads them as it reads a file, without a round trip through text.

use super::{BinaryRecording, Catalog, Entry, Opened, Source};
use crate::recording::{header, Format, ReadOptions, RecordingError, RecordingReader};
use std::sync::Arc;

/// Named channels in memory. A name may carry its unit as a text header does (`Fx [N]`, `fx_N`);
/// `t`/`time`/`time_s` is taken as the time vector and `fs` (one value) as the sample rate, as in
/// a `.mat` file.
#[derive(Debug, Clone, Default)]
pub struct Arrays {
    /// (name, samples) per channel, in order.
    pub columns: Vec<(String, Arc<[f64]>)>,
}

struct ArraySource(Vec<Arc<[f64]>>);

impl Source for ArraySource {
    fn read(
        &mut self,
        entry: usize,
        start: u64,
        n: usize,
        out: &mut Vec<f64>,
    ) -> Result<(), RecordingError> {
        let a = &self.0[entry];
        let s = (start as usize).min(a.len());
        let e = s.saturating_add(n).min(a.len());
        out.extend_from_slice(&a[s..e]);
        Ok(())
    }
}

/// Open arrays as a recording named `name` in messages. Every value must be finite (the first
/// that is not is named by channel and sample index, as a text reader names the line).
pub fn recording_from_arrays(
    name: &str,
    arrays: &Arrays,
    options: &ReadOptions,
) -> Result<RecordingReader<std::io::Empty>, RecordingError> {
    let vectors = || arrays.columns.iter().filter(|(_, v)| v.len() > 1);
    if let Some((first, v0)) = vectors().next() {
        if let Some((other, v)) = vectors().find(|(_, v)| v.len() != v0.len()) {
            return Err(RecordingError::Format {
                file: name.into(),
                message: format!(
                    "array `{other}` has {} samples but `{first}` has {}; channels of one recording must have equal lengths",
                    v.len(),
                    v0.len()
                ),
            });
        }
    }
    let mut entries = Vec::with_capacity(arrays.columns.len());
    for (col, values) in &arrays.columns {
        if let Some(i) = values.iter().position(|v| !v.is_finite()) {
            return Err(RecordingError::Format {
                file: name.into(),
                message: format!(
                    "array `{col}`, sample {i}: {} is not a finite number",
                    values[i]
                ),
            });
        }
        let (short, unit) = header::split_unit(col);
        let mut e = Entry::numeric(col.clone(), None, short, values.len() as u64);
        e.unit = unit;
        if values.len() == 1 {
            e.scalar = Some(values[0]);
        }
        entries.push(e);
    }
    let bytes = arrays.columns.iter().map(|(_, v)| v.len() as u64 * 8).sum();
    let opened = Opened {
        catalog: Catalog {
            format: Format::Arrays,
            entries,
            metadata: Vec::new(),
        },
        source: Box::new(ArraySource(
            arrays.columns.iter().map(|(_, v)| v.clone()).collect(),
        )),
    };
    let rec = BinaryRecording::new(opened, name, None, options, Some(bytes))?;
    Ok(RecordingReader::from_binary(std::io::empty(), rec))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::recording::RecordingChunk as Chunk;

    fn arrays(cols: &[(&str, Vec<f64>)]) -> Arrays {
        Arrays {
            columns: cols
                .iter()
                .map(|(n, v)| (n.to_string(), Arc::from(v.as_slice())))
                .collect(),
        }
    }

    #[test]
    fn arrays_read_like_the_same_csv() {
        let t: Vec<f64> = (0..5000).map(|k| k as f64 / 1000.0).collect();
        let fx: Vec<f64> = t.iter().map(|t| (7.0 * t).sin()).collect();
        let a = arrays(&[("time_s", t.clone()), ("Fx [N]", fx.clone())]);
        let mut r = recording_from_arrays("mem", &a, &ReadOptions::new()).unwrap();
        assert_eq!(r.info().sample_rate_hz, 1000.0);
        assert_eq!(r.info().channels.len(), 1);
        assert_eq!(r.info().channels[0].name, "Fx");
        assert_eq!(r.info().channels[0].unit.as_deref(), Some("N"));
        let mut got = Vec::new();
        let mut c = Chunk::default();
        while r.read_chunk(&mut c, 777).unwrap() > 0 {
            got.extend_from_slice(c.channel(0));
        }
        assert_eq!(got, fx);
        // a rate instead of a time vector
        let a = arrays(&[("Fx", fx.clone()), ("fs", vec![2000.0])]);
        let r = recording_from_arrays("mem", &a, &ReadOptions::new()).unwrap();
        assert_eq!(r.info().sample_rate_hz, 2000.0);
    }

    #[test]
    fn bad_arrays_are_named() {
        let a = arrays(&[("Fx", vec![0.0, f64::NAN]), ("fs", vec![10.0])]);
        let e = recording_from_arrays("mem", &a, &ReadOptions::new())
            .err()
            .unwrap()
            .to_string();
        assert!(e.contains("mem") && e.contains("`Fx`, sample 1"), "{e}");
        let a = arrays(&[("Fx", vec![0.0, 1.0, 2.0]), ("Fy", vec![0.0, 1.0, 2.0])]);
        let e = recording_from_arrays("mem", &a, &ReadOptions::new())
            .err()
            .unwrap()
            .to_string();
        assert!(e.contains("sample"), "{e}");
        let a = arrays(&[("Fx", vec![0.0, 1.0, 2.0]), ("Fy", vec![0.0, 1.0])]);
        let e = recording_from_arrays("mem", &a, &ReadOptions::new().sample_rate_hz(10.0))
            .err()
            .unwrap()
            .to_string();
        assert!(e.contains("`Fy` has 2 samples but `Fx` has 3"), "{e}");
    }
}
