//! HDF5 files and MATLAB v7.3 `.mat` files (HDF5 with a 512-byte userblock), read with the
//! pure-Rust `hdf5-reader` crate (no C library).
//!
//! Channels are numeric datasets of one dimension, or two with one of them 1 (MATLAB stores a
//! 1×N vector as an N×1 dataset); the channel name is the dataset path (`/grp/Fx`; in a v7.3
//! file `rec.Fx`, as MATLAB names a struct field, a group of the file).
//!
//! A 2-D dataset holds one channel per column: the longer dimension is the samples (N×C as
//! numpy / pandas write it, or C×N as MATLAB v7.3 stores an N×C matrix). Column `k` is named
//! `/grp/D[:,k]` (0-based, numpy style; in a v7.3 file `M(:,j)`, 1-based as in MATLAB); with a
//! column-name attribute (`columns`, `column_names`, `channel_names` or `names`: one name per
//! column) the columns are also channels `/grp/D/NAME`, so the dataset works as a group
//! (`FILE:D` selects its columns by name). Attributes `fs` / `sample_rate_hz` (on the
//! dataset, its group or the root) give the sample rate, `unit` / `units` the unit. Integer and
//! float element types of 1–8 bytes are converted to f64.
//!
//! Memory: datasets are read hyperslab by hyperslab (one chunk of samples at a time; the crate
//! caches decompressed HDF5 chunks), never the whole file into memory (a file is memory-mapped or
//! read through the operating system's cache).

use super::{Catalog, Entry, Opened, Result, Source};
use crate::recording::{Format, RecordingError};
use hdf5_reader::{Dataset, Datatype, SliceInfo, SliceInfoElem};
use std::path::Path;

/// Entries listed at most (a file with more datasets is cut, with a note).
const MAX_ENTRIES: usize = 100_000;
/// Deepest group nesting followed.
const MAX_DEPTH: usize = 32;

fn herr(file: &str, what: &str, e: impl std::fmt::Display) -> RecordingError {
    RecordingError::Format {
        file: file.into(),
        message: format!("HDF5: {what}: {e}"),
    }
}

fn attr_f64(attrs: &[hdf5_reader::Attribute], names: &[&str]) -> Option<f64> {
    attrs
        .iter()
        .find(|a| names.iter().any(|n| a.name.eq_ignore_ascii_case(n)))
        .and_then(|a| a.read_as_f64().ok())
        .filter(|v| v.is_finite())
}

fn attr_text(attrs: &[hdf5_reader::Attribute], names: &[&str]) -> Option<String> {
    attrs
        .iter()
        .find(|a| names.iter().any(|n| a.name.eq_ignore_ascii_case(n)))
        .and_then(|a| a.read_string().ok())
        .map(|s| s.trim_end_matches('\0').trim().to_string())
        .filter(|s| !s.is_empty())
}

const RATE: [&str; 4] = ["fs", "sample_rate_hz", "sample_rate", "sampling_rate"];
const UNIT: [&str; 3] = ["unit", "units", "unit_string"];

#[derive(Clone, Copy, Debug)]
enum Layout {
    Vector,
    Column,
    Row,
    /// Column `k` of an N×C dataset.
    ColumnOf(u64),
    /// Row `k` of a C×N dataset.
    RowOf(u64),
}

/// Attributes naming the columns of a 2-D dataset.
const COLUMN_NAMES: [&str; 4] = ["columns", "column_names", "channel_names", "names"];

fn attr_names(attrs: &[hdf5_reader::Attribute]) -> Option<Vec<String>> {
    let a = attrs
        .iter()
        .find(|a| COLUMN_NAMES.iter().any(|n| a.name.eq_ignore_ascii_case(n)))?;
    let v = match a.read_strings() {
        Ok(v) if v.len() > 1 => v,
        _ => a
            .read_string()
            .ok()?
            .split(',')
            .map(str::to_string)
            .collect(),
    };
    Some(
        v.into_iter()
            .map(|s| s.trim_end_matches('\0').trim().to_string())
            .collect(),
    )
}

struct Walk<'a> {
    file: &'a str,
    mat73: bool,
    entries: Vec<Entry>,
    datasets: Vec<Option<(Dataset, Layout)>>,
    truncated: bool,
}

impl Walk<'_> {
    fn name(&self, path: &str) -> String {
        if self.mat73 {
            path.trim_start_matches('/').replace('/', ".")
        } else {
            path.to_string()
        }
    }

    fn group(
        &mut self,
        g: &hdf5_reader::group::Group,
        path: &str,
        rate: Option<f64>,
        depth: usize,
    ) -> Result<()> {
        let (groups, datasets) = g.members().map_err(|e| {
            herr(
                self.file,
                &format!("group `{}`", if path.is_empty() { "/" } else { path }),
                e,
            )
        })?;
        for d in datasets {
            if self.entries.len() >= MAX_ENTRIES {
                self.truncated = true;
                return Ok(());
            }
            let dpath = format!("{path}/{}", d.name());
            if d.name().starts_with('#') {
                continue;
            }
            self.dataset(d, &dpath, path, rate);
        }
        if depth >= MAX_DEPTH {
            return Ok(());
        }
        for sub in groups {
            if sub.name().starts_with('#') {
                continue;
            }
            let gpath = format!("{path}/{}", sub.name());
            let attrs = sub.attributes().unwrap_or_default();
            let r = attr_f64(&attrs, &RATE).or(rate);
            self.group(&sub, &gpath, r, depth + 1)?;
        }
        Ok(())
    }

    fn dataset(&mut self, d: Dataset, dpath: &str, gpath: &str, rate: Option<f64>) {
        let shape = d.shape().to_vec();
        let attrs = d.attributes();
        // a malformed file may announce dimensions whose product overflows
        let n: u64 = shape
            .iter()
            .try_fold(1u64, |a, &d| a.checked_mul(d))
            .unwrap_or(u64::MAX);
        let dtype = d.dtype().clone();
        let (numeric, tname) = match &dtype {
            Datatype::FloatingPoint { size, .. } if *size == 4 || *size == 8 => {
                (true, format!("f{}", size * 8))
            }
            Datatype::FixedPoint { size, signed, .. } if matches!(size, 1 | 2 | 4 | 8) => (
                true,
                format!("{}{}", if *signed { "i" } else { "u" }, size * 8),
            ),
            other => (false, format!("{other:?}").chars().take(40).collect()),
        };
        // a MATLAB char / cell / struct … stored as numbers is not a channel
        let class_ok = attr_text(&attrs, &["MATLAB_class"]).is_none_or(|c| {
            matches!(
                c.as_str(),
                "double"
                    | "single"
                    | "int8"
                    | "uint8"
                    | "int16"
                    | "uint16"
                    | "int32"
                    | "uint32"
                    | "int64"
                    | "uint64"
                    | "logical"
            )
        });
        let layout = match shape.as_slice() {
            [_] => Some(Layout::Vector),
            [_, 1] => Some(Layout::Column),
            [1, _] => Some(Layout::Row),
            [] => Some(Layout::Vector),
            &[r, c] if numeric && class_ok && r > 0 && c > 0 => {
                self.matrix(&d, dpath, gpath, rate, r, c, &dtype);
                return;
            }
            _ => None,
        };
        let name = self.name(dpath);
        let group = (!gpath.is_empty()).then(|| self.name(gpath));
        let short = d.name().to_string();
        let mut e = Entry::numeric(name, group, short, n);
        e.dtype = tname;
        e.unit = attr_text(&attrs, &UNIT);
        e.sample_rate_hz = attr_f64(&attrs, &RATE).or(rate);
        if let Some(c) = attr_text(&attrs, &["MATLAB_class"]) {
            if !numeric
                || !matches!(
                    c.as_str(),
                    "double"
                        | "single"
                        | "int8"
                        | "uint8"
                        | "int16"
                        | "uint16"
                        | "int32"
                        | "uint32"
                        | "int64"
                        | "uint64"
                        | "logical"
                )
            {
                e.readable = false;
                e.note = Some(format!("MATLAB class {c}, not a channel"));
            }
        }
        if !numeric {
            e.readable = false;
            e.note.get_or_insert_with(|| "not a numeric dataset".into());
        }
        if layout.is_none() {
            e.readable = false;
            let dims = shape
                .iter()
                .map(|d| d.to_string())
                .collect::<Vec<_>>()
                .join("×");
            e.note = Some(format!("{dims} dataset, not a vector"));
        }
        let keep = e.readable;
        if keep && n == 1 {
            let mut v = Vec::new();
            if let Some(l) = layout {
                if read_into(&d, l, shape.len(), 0, 1, &mut v).is_ok() {
                    e.scalar = v.first().copied();
                }
            }
        }
        self.entries.push(e);
        self.datasets
            .push(if keep { layout.map(|l| (d, l)) } else { None });
    }
}

impl Walk<'_> {
    /// A 2-D dataset: one entry per column (and per named column).
    #[allow(clippy::too_many_arguments)]
    fn matrix(
        &mut self,
        d: &Dataset,
        dpath: &str,
        gpath: &str,
        rate: Option<f64>,
        r: u64,
        c: u64,
        dtype: &Datatype,
    ) {
        let attrs = d.attributes();
        // the longer dimension is the samples
        let (n, cols, tall) = if r >= c { (r, c, true) } else { (c, r, false) };
        let tname = match dtype {
            Datatype::FloatingPoint { size, .. } => format!("f{}", size * 8),
            Datatype::FixedPoint { size, signed, .. } => {
                format!("{}{}", if *signed { "i" } else { "u" }, size * 8)
            }
            _ => "?".into(),
        };
        let names = attr_names(&attrs).filter(|v| v.len() as u64 == cols);
        let base = self.name(dpath);
        let group = (!gpath.is_empty()).then(|| self.name(gpath));
        let unit = attr_text(&attrs, &UNIT);
        let fs = attr_f64(&attrs, &RATE).or(rate);
        let dims = format!("{r}×{c}");
        for k in 0..cols.min(MAX_ENTRIES as u64) {
            if self.entries.len() >= MAX_ENTRIES {
                self.truncated = true;
                return;
            }
            let layout = if tall {
                Layout::ColumnOf(k)
            } else {
                Layout::RowOf(k)
            };
            let short = if self.mat73 {
                format!("{}(:,{})", d.name(), k + 1)
            } else {
                format!("{}[:,{k}]", d.name())
            };
            let full = match &group {
                Some(g) if self.mat73 => format!("{g}.{short}"),
                Some(g) => format!("{g}/{short}"),
                None if self.mat73 => short.clone(),
                None => format!("/{short}"),
            };
            let note = format!(
                "column {} of the {dims} dataset `{base}`{}",
                if self.mat73 { k + 1 } else { k },
                if tall { "" } else { " (stored channel by row)" }
            );
            let push = |w: &mut Self, name: String, group: Option<String>, short: String| {
                let mut e = Entry::numeric(name, group, short, n);
                e.dtype = tname.clone();
                e.unit = unit.clone();
                e.sample_rate_hz = fs;
                e.note = Some(note.clone());
                w.entries.push(e);
                w.datasets.push(Some((d.clone(), layout)));
            };
            push(self, full, group.clone(), short);
            if let Some(names) = &names {
                let cname = names[k as usize].clone();
                if !cname.is_empty() {
                    let sep = if self.mat73 { "." } else { "/" };
                    push(
                        self,
                        format!("{base}{sep}{cname}"),
                        Some(base.clone()),
                        cname,
                    );
                }
            }
        }
    }
}

fn read_into(
    d: &Dataset,
    layout: Layout,
    ndim: usize,
    start: u64,
    n: usize,
    out: &mut Vec<f64>,
) -> std::result::Result<(), String> {
    let range = SliceInfoElem::Slice {
        start,
        end: start + n as u64,
        step: 1,
    };
    let sel = SliceInfo {
        selections: match (layout, ndim) {
            (_, 0) => vec![],
            (Layout::Vector, _) => vec![range],
            (Layout::Column, _) => vec![range, SliceInfoElem::Index(0)],
            (Layout::Row, _) => vec![SliceInfoElem::Index(0), range],
            (Layout::ColumnOf(k), _) => vec![range, SliceInfoElem::Index(k)],
            (Layout::RowOf(k), _) => vec![SliceInfoElem::Index(k), range],
        },
    };
    macro_rules! rd {
        ($t:ty) => {{
            let a = if ndim == 0 {
                d.read_array::<$t>()
            } else {
                d.read_slice::<$t>(&sel)
            }
            .map_err(|e| e.to_string())?;
            out.extend(a.iter().map(|&x| x as f64));
        }};
    }
    match d.dtype() {
        Datatype::FloatingPoint { size: 4, .. } => rd!(f32),
        Datatype::FloatingPoint { size: 8, .. } => rd!(f64),
        Datatype::FixedPoint { size, signed, .. } => match (size, signed) {
            (1, true) => rd!(i8),
            (1, false) => rd!(u8),
            (2, true) => rd!(i16),
            (2, false) => rd!(u16),
            (4, true) => rd!(i32),
            (4, false) => rd!(u32),
            (8, true) => rd!(i64),
            (8, false) => rd!(u64),
            _ => return Err("unsupported integer size".into()),
        },
        other => return Err(format!("unsupported element type {other:?}")),
    }
    Ok(())
}

struct H5Source {
    file: String,
    names: Vec<String>,
    datasets: Vec<Option<(Dataset, Layout)>>,
}

impl Source for H5Source {
    fn read(&mut self, entry: usize, start: u64, n: usize, out: &mut Vec<f64>) -> Result<()> {
        let Some((d, l)) = &self.datasets[entry] else {
            return Err(RecordingError::Format {
                file: self.file.clone(),
                message: format!("`{}` is not a readable numeric vector", self.names[entry]),
            });
        };
        read_into(d, *l, d.shape().len(), start, n, out).map_err(|e| RecordingError::Format {
            file: self.file.clone(),
            message: format!(
                "HDF5 dataset `{}`: cannot read samples {start}..{}: {e}",
                self.names[entry],
                start + n as u64
            ),
        })
    }
}

fn build(f: hdf5_reader::Hdf5File, file: &str, mat73: bool) -> Result<Opened> {
    let root = f.root_group().map_err(|e| herr(file, "root group", e))?;
    let rattrs = root.attributes().unwrap_or_default();
    let mut w = Walk {
        file,
        mat73,
        entries: Vec::new(),
        datasets: Vec::new(),
        truncated: false,
    };
    w.group(&root, "", attr_f64(&rattrs, &RATE), 0)?;
    let mut metadata: Vec<(String, String)> = rattrs
        .iter()
        .filter_map(|a| {
            a.read_string()
                .ok()
                .or_else(|| a.read_as_f64().ok().map(|v| v.to_string()))
                .map(|v| (a.name.clone(), v))
        })
        .collect();
    if w.truncated {
        metadata.push((
            "note".into(),
            format!("only the first {MAX_ENTRIES} datasets are listed"),
        ));
    }
    let names = w.entries.iter().map(|e| e.name.clone()).collect();
    Ok(Opened {
        catalog: Catalog {
            format: if mat73 {
                Format::Mat {
                    version: "7.3".into(),
                }
            } else {
                Format::Hdf5
            },
            entries: w.entries,
            metadata,
        },
        source: Box::new(H5Source {
            file: file.into(),
            names,
            datasets: w.datasets,
        }),
    })
}

fn is_mat73(head: &[u8]) -> bool {
    head.starts_with(b"MATLAB 7.3 MAT-file")
}

/// Open an HDF5 / MAT v7.3 file.
pub fn open_path(path: &Path, file: &str) -> Result<Opened> {
    let mut head = [0u8; 20];
    let mat73 = std::fs::File::open(path)
        .and_then(|mut f| std::io::Read::read_exact(&mut f, &mut head))
        .is_ok()
        && is_mat73(&head);
    let f = hdf5_reader::Hdf5File::open(path).map_err(|e| herr(file, "cannot open", e))?;
    build(f, file, mat73)
}

/// Open an HDF5 / MAT v7.3 file held in memory.
pub fn open_bytes(bytes: &[u8], file: &str) -> Result<Opened> {
    let f = hdf5_reader::Hdf5File::from_vec(bytes.to_vec())
        .map_err(|e| herr(file, "cannot open", e))?;
    build(f, file, is_mat73(bytes))
}
