//! The `runout` Python package's native module (`runout._runout`): every job of the facade crate
//! `runout` with NumPy arrays in and out.
//!
//! Conventions (the same for every function):
//! * an input source is a path (`str` / `os.PathLike`), `bytes` (the file's content), a
//!   `(name, bytes)` pair (the name is used in messages), or a mapping of 1-D arrays
//!   (`{"Fx": array, ...}`, a `dict` or a pandas `DataFrame`; values converted to float64),
//!   optionally as `(name, mapping)`;
//! * the report is a plain `dict` with the field names (and units) of the CLI's `--json`, made by
//!   serialising the typed report with serde (`json.loads` of `runout::to_json`);
//! * a failure raises `runout.RunoutError` (a `ValueError`) with the CLI's message;
//! * the GIL is released while the job runs (`Python::detach`), so threads run jobs in parallel.

use numpy::{PyArray1, PyReadonlyArray1};
use pyo3::create_exception;
use pyo3::exceptions::{PyTypeError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::{PyBytes, PyDict, PyTuple};
use runout::{NoProgress, Source};
use std::io::Write;
use std::sync::{Arc, Mutex};

create_exception!(
    _runout,
    RunoutError,
    PyValueError,
    "A job failed: bad input or parameters. The message is the command line's (file, line, parameter and what was expected)."
);

/// The CLI's message for a failed job (`runout_io::report::chain_of`).
fn job_error(e: anyhow::Error) -> PyErr {
    RunoutError::new_err(runout_io::report::chain_of(e.chain()))
}

/// Run `f` without the GIL; a failure becomes `RunoutError`.
fn run<T: Send>(py: Python<'_>, f: impl FnOnce() -> anyhow::Result<T> + Send) -> PyResult<T> {
    py.detach(f).map_err(job_error)
}

/// A report as a `dict` with the JSON's field names.
fn to_dict<'py, R: runout::Report>(py: Python<'py>, r: &R) -> PyResult<Bound<'py, PyAny>> {
    let text = runout::to_json(r).map_err(|e| RunoutError::new_err(e.to_string()))?;
    py.import("json")?.call_method1("loads", (text,))
}

/// A 1-D float64 array from any array-like (`what` names it in messages).
fn float_array(py: Python<'_>, obj: &Bound<'_, PyAny>, what: &str) -> PyResult<Arc<[f64]>> {
    let np = py.import("numpy")?;
    let f64_ = np.getattr("float64")?;
    let a = np
        .call_method1("ascontiguousarray", (obj, f64_))
        .map_err(|e| {
            PyTypeError::new_err(format!(
                "{what}: expected an array of numbers ({})",
                e.value(py)
            ))
        })?;
    let ndim: usize = a.getattr("ndim")?.extract()?;
    let a = match ndim {
        0 => a.call_method1("reshape", (1,))?,
        1 => a,
        _ => {
            let shape = a.getattr("shape")?.str()?.to_string();
            return Err(PyValueError::new_err(format!(
                "{what}: expected a 1-D array, got shape {shape}"
            )));
        }
    };
    let a: PyReadonlyArray1<'_, f64> = a.extract()?;
    Ok(Arc::from(a.as_slice()?))
}

/// Named arrays from a mapping (`dict`, pandas `DataFrame`: anything with `.items()`).
fn arrays(
    py: Python<'_>,
    obj: &Bound<'_, PyAny>,
    what: &str,
) -> PyResult<runout_io::formats::Arrays> {
    let mut columns = Vec::new();
    for item in obj.call_method0("items")?.try_iter()? {
        let item = item?;
        let (k, v): (Bound<'_, PyAny>, Bound<'_, PyAny>) = item.extract()?;
        let name = k.str()?.to_string();
        let values = float_array(py, &v, &format!("{what} `{name}`"))?;
        columns.push((name, values));
    }
    if columns.is_empty() {
        return Err(PyValueError::new_err(format!("{what}: no arrays given")));
    }
    Ok(runout_io::formats::Arrays { columns })
}

/// A job input: path, bytes, `(name, bytes)`, mapping of arrays or `(name, mapping)`.
fn source(py: Python<'_>, obj: &Bound<'_, PyAny>, what: &str) -> PyResult<Source> {
    if let Ok(t) = obj.cast::<PyTuple>() {
        if t.len() == 2 {
            let name: String = t.get_item(0)?.extract().map_err(|_| {
                PyTypeError::new_err(format!("{what}: a (name, data) pair needs a str name"))
            })?;
            return named_source(py, name, &t.get_item(1)?, what);
        }
    }
    if obj.is_instance_of::<PyBytes>() || obj.hasattr("items")? {
        return named_source(py, format!("<{what}>"), obj, what);
    }
    let os = py.import("os")?;
    let path =
        os.call_method1("fspath", (obj,)).map_err(|_| {
            PyTypeError::new_err(format!(
            "{what}: expected a path, bytes, a (name, bytes) pair or a mapping of arrays, got {}",
            obj.get_type().name().map(|n| n.to_string()).unwrap_or_default()
        ))
        })?;
    let path: std::path::PathBuf = path.extract()?;
    Ok(Source::path(path))
}

fn named_source(
    py: Python<'_>,
    name: String,
    obj: &Bound<'_, PyAny>,
    what: &str,
) -> PyResult<Source> {
    if let Ok(b) = obj.cast::<PyBytes>() {
        return Ok(Source::bytes(name, b.as_bytes().to_vec()));
    }
    if obj.hasattr("items")? {
        return Ok(Source::arrays(name, arrays(py, obj, what)?));
    }
    Err(PyTypeError::new_err(format!(
        "{what}: the data of a (name, data) pair must be bytes or a mapping of arrays"
    )))
}

fn opt_source(
    py: Python<'_>,
    obj: Option<&Bound<'_, PyAny>>,
    what: &str,
) -> PyResult<Option<Source>> {
    obj.map(|o| source(py, o, what)).transpose()
}

/// Columns as a dict of float64 arrays.
fn columns_dict<'py>(
    py: Python<'py>,
    names: &[String],
    columns: Vec<Vec<f64>>,
) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    for (n, c) in names.iter().zip(columns) {
        d.set_item(n, PyArray1::from_vec(py, c))?;
    }
    Ok(d)
}

/// A `Write` into shared memory (the job's writer is `Box<dyn Write>`, so it must own it).
#[derive(Clone, Default)]
struct SharedBuf(Arc<Mutex<Vec<u8>>>);

impl Write for SharedBuf {
    fn write(&mut self, b: &[u8]) -> std::io::Result<usize> {
        self.0.lock().expect("not poisoned").extend_from_slice(b);
        Ok(b.len())
    }
    fn flush(&mut self) -> std::io::Result<()> {
        Ok(())
    }
}

fn choice<T: Copy>(what: &str, got: &str, options: &[(&str, T)]) -> PyResult<T> {
    options
        .iter()
        .find(|(n, _)| *n == got)
        .map(|(_, v)| *v)
        .ok_or_else(|| {
            let names: Vec<&str> = options.iter().map(|(n, _)| *n).collect();
            RunoutError::new_err(format!("{what}: `{got}` is not {}", names.join(" | ")))
        })
}

// ---------------------------------------------------------------------------------------------
// shank

/// Shank stiffness K_δ of the beam model (methods.md §3) and the tool's first bending mode.
///
/// Args: modulus_gpa (GPa), diameter_mm, tool_length_mm (from the holder face), l1_mm, l2_mm
/// (sensor heights from the holder face, mm), ap_mm (load at mid axial depth; default the tip),
/// holder_stiffness_Nm_per_rad (N·m/rad; default rigid), density_kg_per_m3 (kg/m³).
/// Returns the `runout.shank.stiffness/1` report as a dict (`stiffness_N_per_um`,
/// `first_bending_mode_hz`, …).
#[pyfunction]
#[pyo3(signature = (*, modulus_gpa, diameter_mm, tool_length_mm, l1_mm, l2_mm, ap_mm=None, holder_stiffness_Nm_per_rad=None, density_kg_per_m3=None))]
#[allow(non_snake_case, clippy::too_many_arguments)]
fn shank_stiffness<'py>(
    py: Python<'py>,
    modulus_gpa: f64,
    diameter_mm: f64,
    tool_length_mm: f64,
    l1_mm: f64,
    l2_mm: f64,
    ap_mm: Option<f64>,
    holder_stiffness_Nm_per_rad: Option<f64>,
    density_kg_per_m3: Option<f64>,
) -> PyResult<Bound<'py, PyAny>> {
    let req = runout::shank::StiffnessRequest {
        modulus_gpa,
        diameter_mm,
        tool_length_mm,
        l1_mm,
        l2_mm,
        ap_mm,
        holder_stiffness_Nm_per_rad,
        density_kg_per_m3,
    };
    let r = run(py, || runout::shank::stiffness(&req))?;
    to_dict(py, &r)
}

/// Cutting force F = K_δ·(δ_II − δ_I) and runout from a shank recording (methods.md §3).
///
/// Args: recording (source: path, bytes or arrays, displacement channels in the units the config
/// names, time `time_s` or a rate `fs` in Hz), config (shank.toml source), sample_rate_hz (Hz,
/// overrides the file and config), series (return the time series).
/// Returns (report dict `runout.shank.force/2`, series) where series is a dict of float64 arrays
/// named as the CLI's CSV columns (`time_s`, forces in N, deflections in mm …), or None.
#[pyfunction]
#[pyo3(signature = (recording, config, *, sample_rate_hz=None, series=true))]
fn shank_force<'py>(
    py: Python<'py>,
    recording: &Bound<'py, PyAny>,
    config: &Bound<'py, PyAny>,
    sample_rate_hz: Option<f64>,
    series: bool,
) -> PyResult<(Bound<'py, PyAny>, Option<Bound<'py, PyDict>>)> {
    let mut req = runout::shank::ForceRequest::new(
        source(py, recording, "recording")?,
        source(py, config, "config")?,
    );
    req.sample_rate_hz = sample_rate_hz;
    let buf = SharedBuf::default();
    if series {
        req.series = Some((
            "<arrays>".into(),
            runout::shank::SeriesFormat::Binary(runout_io::recording::BinaryLayout::F64),
        ));
    }
    let out = buf.clone();
    let (report, cols) = run(py, move || {
        let sink: Option<Box<dyn Write>> = series.then(|| Box::new(out) as Box<dyn Write>);
        let report = runout::shank::force_to(&req, sink, &mut NoProgress)?;
        let cols = if series {
            let bytes = std::mem::take(&mut *buf.0.lock().expect("not poisoned"));
            Some(runout_io::recording::read_binary(&bytes[..])?.1)
        } else {
            None
        };
        Ok((report, cols))
    })?;
    let names = report
        .output
        .as_ref()
        .map(|o| o.columns.clone())
        .unwrap_or_default();
    let cols = cols.map(|c| columns_dict(py, &names, c)).transpose()?;
    Ok((to_dict(py, &report)?, cols))
}

/// Static calibration of K_δ from a recording of the first pair's sensors and a load cell.
///
/// Args: recording, config (sources), force_channel (load-cell channel, N, positive towards the
/// pair's +axis), load_point_mm (constant load distance from the holder face, mm) or
/// load_point_channel (a channel with it, mm), sample_rate_hz (Hz).
/// Returns the `runout.shank.calibration/2` report as a dict.
#[pyfunction]
#[pyo3(signature = (recording, config, *, force_channel, load_point_mm=None, load_point_channel=None, sample_rate_hz=None))]
fn shank_calibrate<'py>(
    py: Python<'py>,
    recording: &Bound<'py, PyAny>,
    config: &Bound<'py, PyAny>,
    force_channel: String,
    load_point_mm: Option<f64>,
    load_point_channel: Option<String>,
    sample_rate_hz: Option<f64>,
) -> PyResult<Bound<'py, PyAny>> {
    use runout::shank::LoadPointFrom;
    let load_point = match (load_point_mm, load_point_channel) {
        (Some(mm), None) => LoadPointFrom::Fixed(mm),
        (None, Some(c)) => LoadPointFrom::Channel(c),
        _ => {
            return Err(RunoutError::new_err(
                "give exactly one of load_point_mm and load_point_channel",
            ))
        }
    };
    let req = runout::shank::CalibrateRequest {
        recording: source(py, recording, "recording")?,
        config: source(py, config, "config")?,
        force_channel,
        load_point,
        sample_rate_hz,
    };
    let r = run(py, || runout::shank::calibrate(&req))?;
    to_dict(py, &r)
}

// ---------------------------------------------------------------------------------------------
// displacement

fn cutter(
    teeth: Option<usize>,
    diameter_mm: Option<f64>,
    helix_deg: f64,
) -> PyResult<Option<runout_core::Cutter>> {
    match (teeth, diameter_mm) {
        (Some(k), Some(d)) => runout_core::Cutter::flat(d, k, helix_deg.to_radians())
            .map(Some)
            .map_err(|e| RunoutError::new_err(e.to_string())),
        (None, None) => Ok(None),
        _ => Err(RunoutError::new_err("teeth and diameter_mm go together")),
    }
}

fn sensor(
    sensor: &str,
    inclination_deg: f64,
    beam_offset_mm: f64,
) -> PyResult<runout::displacement::Sensor> {
    use runout_core::displacement::{BeamGeometry, SensorSign};
    let sign = choice(
        "sensor",
        sensor,
        &[
            ("distance", SensorSign::Distance),
            ("radial", SensorSign::Radial),
        ],
    )?;
    let beam = BeamGeometry::new(inclination_deg.to_radians(), beam_offset_mm)
        .map_err(|e| RunoutError::new_err(e.to_string()))?;
    Ok(runout::displacement::Sensor { sign, beam })
}

/// Runout (ρ, λ) from per-tooth displacement readings (methods.md §1.5, seed 000).
///
/// Args: readings (table source: columns `tooth` (0-based) or `seed_edge` (1-based) and
/// `reading_um` or `reading_mm`; a mapping of arrays works), teeth, diameter_mm, helix_deg (deg),
/// height_mm (mm above the tip), method (`joint` | `scan`), offset_um / offset_se_um (µm, known
/// ρ at this height and its SE), noise_um (µm, σ of one reading), phase_deg (deg, approximate
/// runout direction), sensor (`distance` | `radial`), inclination_deg (deg), beam_offset_mm (mm),
/// fz_mm (mm, feed per tooth), hole_path_mm (mm).
/// Returns the `runout.displacement.teeth/2` report as a dict (`offset_um`, `angle_deg`, …).
#[pyfunction]
#[pyo3(signature = (readings, *, teeth, diameter_mm, helix_deg=0.0, height_mm=0.0, method="joint", offset_um=None, offset_se_um=None, noise_um=None, phase_deg=None, sensor="distance", inclination_deg=0.0, beam_offset_mm=0.0, fz_mm=None, hole_path_mm=None))]
#[allow(clippy::too_many_arguments)]
fn displacement_teeth<'py>(
    py: Python<'py>,
    readings: &Bound<'py, PyAny>,
    teeth: usize,
    diameter_mm: f64,
    helix_deg: f64,
    height_mm: f64,
    method: &str,
    offset_um: Option<f64>,
    offset_se_um: Option<f64>,
    noise_um: Option<f64>,
    phase_deg: Option<f64>,
    sensor: &str,
    inclination_deg: f64,
    beam_offset_mm: f64,
    fz_mm: Option<f64>,
    hole_path_mm: Option<f64>,
) -> PyResult<Bound<'py, PyAny>> {
    use runout_core::displacement::{ToothFitOptions, ToothMethod};
    let c = cutter(Some(teeth), Some(diameter_mm), helix_deg)?.expect("both given");
    let s = self::sensor(sensor, inclination_deg, beam_offset_mm)?;
    let mut opts = ToothFitOptions::new(c);
    opts.height_mm = height_mm;
    opts.method = choice(
        "method",
        method,
        &[
            ("joint", ToothMethod::Joint),
            ("scan", ToothMethod::SeedScan),
        ],
    )?;
    opts.known_offset_mm = offset_um.map(|x| x * 1e-3);
    opts.known_offset_se_mm = offset_se_um.map(|x| x * 1e-3);
    opts.noise_mm = noise_um.map(|x| x * 1e-3);
    opts.beam = s.beam;
    opts.phase_hint_rad = phase_deg.map(f64::to_radians);
    let req = runout::displacement::TeethRequest {
        readings: source(py, readings, "readings")?,
        options: opts,
        sign: s.sign,
        fz_mm,
        hole_path_mm,
    };
    let r = run(py, || runout::displacement::teeth(&req))?;
    to_dict(py, &r)
}

/// Runout at several heights → runout at the cutting height (methods.md §1.3, §1.6).
///
/// Args: table (source: `z_mm` and `tir_um` or `runout_um`, optional `angle_deg`), at_mm (mm,
/// the height wanted, same origin as z), method (`ols` | `eq6`).
/// Returns the `runout.displacement.heights/2` report as a dict.
#[pyfunction]
#[pyo3(signature = (table, *, at_mm=0.0, method="ols"))]
fn displacement_heights<'py>(
    py: Python<'py>,
    table: &Bound<'py, PyAny>,
    at_mm: f64,
    method: &str,
) -> PyResult<Bound<'py, PyAny>> {
    use runout_core::displacement::HeightRegression;
    let req = runout::displacement::HeightsRequest {
        table: source(py, table, "table")?,
        at_mm,
        method: choice(
            "method",
            method,
            &[
                ("ols", HeightRegression::Ols),
                ("eq6", HeightRegression::SeedEq6),
            ],
        )?,
    };
    let r = run(py, || runout::displacement::heights(&req))?;
    to_dict(py, &r)
}

/// Runout vector from a raw displacement signal (methods.md §1.2): first harmonic by linear
/// least squares, per-revolution TIR, optional per-tooth extrema.
///
/// Args: recording (source: `time_s` or `time_ms`, `disp_<name>_um|mm` channels, optional
/// `pulse` or `encoder_deg`), sensor_angles_deg (deg per `disp_*` channel), reference (`auto` |
/// `pulse` | `encoder` | `none`), rpm_min / rpm_max (rpm), surface_diameter_mm (mm),
/// tooth0_deg (deg), from_s / to_s (s, section), teeth, diameter_mm, helix_deg, height_mm,
/// sensor, inclination_deg, beam_offset_mm, fz_mm, hole_path_mm.
/// Returns the `runout.displacement.signal/2` report as a dict.
#[pyfunction]
#[pyo3(signature = (recording, *, sensor_angles_deg=None, reference="auto", rpm_min=60.0, rpm_max=60000.0, surface_diameter_mm=None, tooth0_deg=0.0, from_s=None, to_s=None, teeth=None, diameter_mm=None, helix_deg=0.0, height_mm=0.0, sensor="distance", inclination_deg=0.0, beam_offset_mm=0.0, fz_mm=None, hole_path_mm=None))]
#[allow(clippy::too_many_arguments)]
fn displacement_signal<'py>(
    py: Python<'py>,
    recording: &Bound<'py, PyAny>,
    sensor_angles_deg: Option<Vec<f64>>,
    reference: &str,
    rpm_min: f64,
    rpm_max: f64,
    surface_diameter_mm: Option<f64>,
    tooth0_deg: f64,
    from_s: Option<f64>,
    to_s: Option<f64>,
    teeth: Option<usize>,
    diameter_mm: Option<f64>,
    helix_deg: f64,
    height_mm: f64,
    sensor: &str,
    inclination_deg: f64,
    beam_offset_mm: f64,
    fz_mm: Option<f64>,
    hole_path_mm: Option<f64>,
) -> PyResult<Bound<'py, PyAny>> {
    use runout::displacement::ReferenceChoice;
    if let (Some(f), Some(t)) = (from_s, to_s) {
        if t <= f {
            return Err(RunoutError::new_err(format!(
                "to_s ({t} s) must be after from_s ({f} s)"
            )));
        }
    }
    let req = runout::displacement::SignalRequest {
        recording: source(py, recording, "recording")?,
        section: runout_io::displacement::SignalSection {
            from_s,
            to_s,
            ..Default::default()
        },
        read: Default::default(),
        sensor_angles_rad: sensor_angles_deg.map(|v| v.into_iter().map(f64::to_radians).collect()),
        sensor: self::sensor(sensor, inclination_deg, beam_offset_mm)?,
        reference: choice(
            "reference",
            reference,
            &[
                ("auto", ReferenceChoice::Auto),
                ("pulse", ReferenceChoice::Pulse),
                ("encoder", ReferenceChoice::Encoder),
                ("none", ReferenceChoice::None),
            ],
        )?,
        rpm_range: (rpm_min, rpm_max),
        surface_diameter_mm,
        tooth0_rad: tooth0_deg.to_radians(),
        cutter: cutter(teeth, diameter_mm, helix_deg)?,
        height_mm,
        fz_mm,
        hole_path_mm,
    };
    let r = run(py, || runout::displacement::signal(&req))?;
    to_dict(py, &r)
}

// ---------------------------------------------------------------------------------------------
// grind

#[allow(clippy::too_many_arguments)]
fn generated_edge(
    ball: bool,
    edge_diameter_mm: Option<f64>,
    flutes: usize,
    helix_deg: f64,
    edge_from_mm: f64,
    edge_to_mm: Option<f64>,
    points_per_flute: usize,
    edge_phase_deg: f64,
) -> runout::grind::GeneratedEdge {
    runout::grind::GeneratedEdge {
        ball,
        diameter_mm: edge_diameter_mm,
        flutes,
        helix_deg,
        from_mm: edge_from_mm,
        to_mm: edge_to_mm,
        points_per_flute,
        phase_rad: edge_phase_deg.to_radians(),
    }
}

fn range_policy(outside: &str) -> PyResult<runout_core::grind::RangePolicy> {
    use runout_core::grind::RangePolicy;
    choice(
        "outside",
        outside,
        &[
            ("clamp", RangePolicy::Clamp),
            ("extrapolate", RangePolicy::Extrapolate),
        ],
    )
}

/// Parse a CSV of numbers (header row, then rows) into named float64 columns (`true`/`false`
/// cells as 1/0).
fn csv_columns(text: &str) -> anyhow::Result<(Vec<String>, Vec<Vec<f64>>)> {
    let mut lines = text.lines();
    let names: Vec<String> = lines
        .next()
        .unwrap_or("")
        .split(',')
        .map(|s| s.trim().to_string())
        .collect();
    let mut cols = vec![Vec::new(); names.len()];
    for line in lines.filter(|l| !l.trim().is_empty()) {
        for (c, cell) in cols.iter_mut().zip(line.split(',')) {
            c.push(match cell.trim() {
                "true" => 1.0,
                "false" => 0.0,
                t => t.parse::<f64>().unwrap_or(f64::NAN),
            });
        }
    }
    Ok((names, cols))
}

/// Tool-grinder compensation of the bar clamping error (methods.md §5, seed 004).
///
/// Args: probe (table source: `layer` and/or `u_mm`, `angle_deg`, and `radius_mm` or
/// `x_mm,y_mm[,z_mm]`), bar_diameter_mm (mm, nominal bar) or generatrix (table source),
/// probe_angle_sense (`ccw` | `cw`), probe_tip_radius_mm (mm), miss_limit_um (µm), duplicates
/// (`error` | `average`), missing (`error` | `skip`), scheme (`first-harmonic` | `bilinear`),
/// outside (`clamp` | `extrapolate`), edge (`flat` | `ball` | an edge table source), edge_diameter_mm
/// (mm), flutes, helix_deg (deg), edge_from_mm / edge_to_mm (mm from the tip), points_per_flute,
/// edge_phase_deg (deg), nc (NC program source), nc_map (`index` | `xyz`), nc_moves (`feed` |
/// `all`), nc_decimals.
/// Returns (report dict `runout.grind.compensate/2`, path, nc_text): path is a dict of float64
/// arrays with the columns of the CLI's `--path-out` CSV (mm, µm), nc_text the compensated
/// program (or None).
#[pyfunction]
#[pyo3(signature = (probe, *, bar_diameter_mm=None, generatrix=None, probe_angle_sense="ccw", probe_tip_radius_mm=0.0, miss_limit_um=200.0, duplicates="error", missing="error", scheme="first-harmonic", outside="clamp", edge=None, edge_diameter_mm=None, flutes=4, helix_deg=30.0, edge_from_mm=0.0, edge_to_mm=None, points_per_flute=200, edge_phase_deg=0.0, nc=None, nc_map="index", nc_moves="feed", nc_decimals=4))]
#[allow(clippy::too_many_arguments)]
fn grind_compensate<'py>(
    py: Python<'py>,
    probe: &Bound<'py, PyAny>,
    bar_diameter_mm: Option<f64>,
    generatrix: Option<&Bound<'py, PyAny>>,
    probe_angle_sense: &str,
    probe_tip_radius_mm: f64,
    miss_limit_um: f64,
    duplicates: &str,
    missing: &str,
    scheme: &str,
    outside: &str,
    edge: Option<&Bound<'py, PyAny>>,
    edge_diameter_mm: Option<f64>,
    flutes: usize,
    helix_deg: f64,
    edge_from_mm: f64,
    edge_to_mm: Option<f64>,
    points_per_flute: usize,
    edge_phase_deg: f64,
    nc: Option<&Bound<'py, PyAny>>,
    nc_map: &str,
    nc_moves: &str,
    nc_decimals: usize,
) -> PyResult<(Bound<'py, PyAny>, Bound<'py, PyDict>, Option<String>)> {
    use runout::grind::{AngleSense, EdgeSpec, GeneratrixFrom, NcMapping, NcRequest};
    use runout_core::grind::{DuplicatePolicy, MissingPolicy, ProbeOptions, Scheme};
    let generatrix = match (opt_source(py, generatrix, "generatrix")?, bar_diameter_mm) {
        (Some(_), Some(_)) => {
            return Err(RunoutError::new_err(
                "give bar_diameter_mm or generatrix, not both",
            ))
        }
        (None, None) => {
            return Err(RunoutError::new_err(
                "give the nominal bar: bar_diameter_mm or a generatrix table",
            ))
        }
        (None, Some(d)) => GeneratrixFrom::Cylinder(d),
        (Some(s), None) => GeneratrixFrom::Table(s),
    };
    let gen = |ball| {
        EdgeSpec::Generated(generated_edge(
            ball,
            edge_diameter_mm,
            flutes,
            helix_deg,
            edge_from_mm,
            edge_to_mm,
            points_per_flute,
            edge_phase_deg,
        ))
    };
    let edge = match edge {
        None => gen(false),
        Some(e) => match e.extract::<String>().ok().as_deref() {
            Some("flat") => gen(false),
            Some("ball") => gen(true),
            _ => EdgeSpec::Csv(source(py, e, "edge")?),
        },
    };
    let nc = match nc {
        None => None,
        Some(n) => Some(NcRequest {
            program: source(py, n, "nc")?,
            output: "<nc_text>".into(),
            mapping: choice(
                "nc_map",
                nc_map,
                &[("index", NcMapping::Index), ("xyz", NcMapping::Xyz)],
            )?,
            all_moves: choice("nc_moves", nc_moves, &[("feed", false), ("all", true)])?,
            decimals: nc_decimals,
        }),
    };
    let req = runout::grind::CompensateRequest {
        probe: source(py, probe, "probe")?,
        angle_sense: choice(
            "probe_angle_sense",
            probe_angle_sense,
            &[("ccw", AngleSense::Ccw), ("cw", AngleSense::Cw)],
        )?,
        generatrix,
        options: ProbeOptions {
            tip_radius_mm: probe_tip_radius_mm,
            miss_limit_mm: miss_limit_um * 1e-3,
            angle_tolerance: 1e-6,
            duplicates: choice(
                "duplicates",
                duplicates,
                &[
                    ("error", DuplicatePolicy::Error),
                    ("average", DuplicatePolicy::Average),
                ],
            )?,
            missing: choice(
                "missing",
                missing,
                &[
                    ("error", MissingPolicy::Error),
                    ("skip", MissingPolicy::Skip),
                ],
            )?,
        },
        scheme: choice(
            "scheme",
            scheme,
            &[
                ("first-harmonic", Scheme::FirstHarmonic),
                ("bilinear", Scheme::Bilinear),
            ],
        )?,
        range: range_policy(outside)?,
        edge,
        nc,
    };
    let (r, path) = run(py, || {
        let r = runout::grind::compensate(&req)?;
        let mut csv = Vec::new();
        runout::grind::render::compensate_path_csv(&mut csv, &r)?;
        let path = csv_columns(&String::from_utf8_lossy(&csv))?;
        Ok((r, path))
    })?;
    let nc_text = r.detail.nc_text.clone();
    Ok((
        to_dict(py, &r)?,
        columns_dict(py, &path.0, path.1)?,
        nc_text,
    ))
}

/// The simulation check of the grinding compensation (methods.md §5.5): a bar with a known
/// clamping error probed, compensated, and the residual reported.
///
/// Args: bar_diameter_mm (mm), offset_um (x, y µm), tilt_um_per_mm (x, y µm/mm), layers,
/// angles, u_from_mm / u_to_mm (mm from the tip), noise_um (µm), draws, seed, outside, edge
/// (`flat` | `ball`), edge_diameter_mm, flutes, helix_deg, edge_from_mm, edge_to_mm,
/// points_per_flute, edge_phase_deg.
/// Returns the `runout.grind.check/2` report as a dict.
#[pyfunction]
#[pyo3(signature = (*, bar_diameter_mm=6.0, offset_um=(8.0, -4.0), tilt_um_per_mm=(0.3, 0.5), layers=5, angles=8, u_from_mm=2.0, u_to_mm=28.0, noise_um=0.0, draws=1, seed=1, outside="clamp", edge="flat", edge_diameter_mm=None, flutes=4, helix_deg=30.0, edge_from_mm=0.0, edge_to_mm=None, points_per_flute=200, edge_phase_deg=0.0))]
#[allow(clippy::too_many_arguments)]
fn grind_check<'py>(
    py: Python<'py>,
    bar_diameter_mm: f64,
    offset_um: (f64, f64),
    tilt_um_per_mm: (f64, f64),
    layers: usize,
    angles: usize,
    u_from_mm: f64,
    u_to_mm: f64,
    noise_um: f64,
    draws: usize,
    seed: u64,
    outside: &str,
    edge: &str,
    edge_diameter_mm: Option<f64>,
    flutes: usize,
    helix_deg: f64,
    edge_from_mm: f64,
    edge_to_mm: Option<f64>,
    points_per_flute: usize,
    edge_phase_deg: f64,
) -> PyResult<Bound<'py, PyAny>> {
    let ball = choice(
        "edge (the check generates its edge)",
        edge,
        &[("flat", false), ("ball", true)],
    )?;
    let req = runout::grind::CheckRequest {
        bar_diameter_mm,
        offset_um: [offset_um.0, offset_um.1],
        tilt_um_per_mm: [tilt_um_per_mm.0, tilt_um_per_mm.1],
        layers,
        angles,
        u_range_mm: [u_from_mm, u_to_mm],
        noise_um,
        draws,
        seed,
        range: range_policy(outside)?,
        edge: generated_edge(
            ball,
            edge_diameter_mm,
            flutes,
            helix_deg,
            edge_from_mm,
            edge_to_mm,
            points_per_flute,
            edge_phase_deg,
        ),
    };
    let r = run(py, || runout::grind::check(&req))?;
    to_dict(py, &r)
}

// ---------------------------------------------------------------------------------------------
// chip

/// Chip-thickness models (arc, circle, equivalent) against the exact IUCT on a case set
/// (methods.md §2).
///
/// Args: config (case-set TOML source; toolpaths it names are resolved from its folder),
/// case (only cases whose name contains it), phase_refinement (the equivalent model's
/// effective-edge phase refinement, §2.4), fit_k (fit (k₁, k₂) per case).
/// Returns the `runout.chip.compare/1` report as a dict.
#[pyfunction]
#[pyo3(signature = (config, *, case=None, phase_refinement=true, fit_k=false))]
fn chip_compare<'py>(
    py: Python<'py>,
    config: &Bound<'py, PyAny>,
    case: Option<String>,
    phase_refinement: bool,
    fit_k: bool,
) -> PyResult<Bound<'py, PyAny>> {
    let req = runout::chip::CompareRequest {
        config: source(py, config, "config")?,
        case,
        phase_refinement,
        fit_k,
    };
    let r = run(py, || runout::chip::compare(&req))?;
    to_dict(py, &r)
}

/// Chip thickness h per tooth, height and time along a case's motion (3- or 5-axis).
///
/// Args: config (case TOML source), case (name contains it; default the first), model
/// (`exact` | `equivalent` | `arc` | `circle`).
/// Returns (report dict `runout.chip.eval/1`, chips): chips is a dict of arrays, one element per
/// evaluated point: `time_s` (s), `spindle_angle_deg` (deg, [0, 360)), `tooth` (int64, 0-based in
/// cutting order), `z_mm` (mm), `h_mm` (mm, ≥ 0) — the CLI's `--csv` columns at full precision.
#[pyfunction]
#[pyo3(signature = (config, *, case=None, model="exact"))]
fn chip_eval<'py>(
    py: Python<'py>,
    config: &Bound<'py, PyAny>,
    case: Option<String>,
    model: &str,
) -> PyResult<(Bound<'py, PyAny>, Bound<'py, PyDict>)> {
    use runout::chip::ChipModel;
    let req = runout::chip::EvalRequest {
        config: source(py, config, "config")?,
        case,
        model: choice(
            "model",
            model,
            &[
                ("exact", ChipModel::Exact),
                ("equivalent", ChipModel::Equivalent),
                ("arc", ChipModel::Arc),
                ("circle", ChipModel::Circle),
            ],
        )?,
    };
    let (r, t, ang, tooth, z) = run(py, || {
        let r = runout::chip::eval(&req)?;
        let case = r
            .detail
            .case
            .as_ref()
            .ok_or_else(|| anyhow::anyhow!("chip eval: no case evaluated"))?;
        let n = case.points.len();
        let (mut t, mut ang, mut tooth, mut z) = (
            Vec::with_capacity(n),
            Vec::with_capacity(n),
            Vec::with_capacity(n),
            Vec::with_capacity(n),
        );
        for q in &case.points {
            t.push(q.t);
            ang.push(
                case.kin
                    .spindle_angle(q.t)
                    .rem_euclid(std::f64::consts::TAU)
                    .to_degrees(),
            );
            tooth.push(q.tooth as i64);
            z.push(q.z);
        }
        Ok((r, t, ang, tooth, z))
    })?;
    let d = PyDict::new(py);
    d.set_item("time_s", PyArray1::from_vec(py, t))?;
    d.set_item("spindle_angle_deg", PyArray1::from_vec(py, ang))?;
    d.set_item("tooth", PyArray1::from_vec(py, tooth))?;
    d.set_item("z_mm", PyArray1::from_vec(py, z))?;
    d.set_item("h_mm", PyArray1::from_vec(py, r.detail.h_mm.clone()))?;
    Ok((to_dict(py, &r)?, d))
}

// ---------------------------------------------------------------------------------------------
// keyword arguments as a settings layer (config keys, as in a TOML config)

/// `**keys` as a settings layer over a config (numbers, strings, booleans, lists of numbers or
/// strings — a list is what a TOML array is, e.g. `fz_mm=[0.05, 0.08]`); unknown keys are an
/// error listing the known ones.
fn layer(keys: Option<&Bound<'_, PyDict>>, known: &[&str]) -> PyResult<runout_io::config::Layer> {
    use runout_io::config::{Layer, Value};
    let mut values = std::collections::BTreeMap::new();
    for (k, v) in keys.into_iter().flat_map(|d| d.iter()) {
        let key: String = k.extract()?;
        if !known.contains(&key.as_str()) {
            return Err(RunoutError::new_err(format!(
                "unknown keyword argument `{key}`; known keys: {}",
                known.join(", ")
            )));
        }
        let value = if v.is_instance_of::<pyo3::types::PyBool>() {
            Value::Text(v.extract::<bool>()?.to_string())
        } else if let Ok(x) = v.extract::<f64>() {
            Value::Number(x)
        } else if let Ok(t) = v.extract::<String>() {
            Value::Text(t)
        } else if let Ok(xs) = v.extract::<Vec<f64>>() {
            Value::Text(
                xs.iter()
                    .map(|x| x.to_string())
                    .collect::<Vec<_>>()
                    .join(","),
            )
        } else if let Ok(ts) = v.extract::<Vec<String>>() {
            Value::Text(ts.join(","))
        } else {
            return Err(PyTypeError::new_err(format!(
                "keyword argument `{key}`: expected a number, a string, a bool or a list of them"
            )));
        };
        values.insert(key, value);
    }
    Ok(Layer {
        origin: "keyword arguments".into(),
        values,
    })
}

// ---------------------------------------------------------------------------------------------
// identify, simulate, batch

/// A list of sources, or one source.
fn sources(py: Python<'_>, obj: &Bound<'_, PyAny>, what: &str) -> PyResult<Vec<Source>> {
    if obj.is_instance_of::<pyo3::types::PyList>() {
        let mut v = Vec::new();
        for (i, item) in obj.try_iter()?.enumerate() {
            v.push(source(py, &item?, &format!("{what}[{i}]"))?);
        }
        return Ok(v);
    }
    Ok(vec![source(py, obj, what)?])
}

/// Runout offset ρ (µm) and angle λ (deg) with standard errors, and the six cutting coefficients
/// (N/mm², N/mm), from force recordings (methods.md §4; the CLI's `runout identify`).
///
/// Args: recordings (a source or a list of sources: paths, bytes, or arrays such as
/// `{"Fx": fx, "Fy": fy, "Fz": fz, "fs": 10000.0}` with forces in N and `fs` in Hz or a
/// `time_s` array), config (cut.toml source, optional), and any config key as a keyword
/// argument overriding the config (`fz_mm=[0.05, 0.08]` (mm, one per recording), `teeth`,
/// `diameter_mm`, `helix_deg` (deg), `rpm`, `ap_mm`, `ae_mm`, `mode`, `axes`,
/// `sample_rate_hz` (Hz), `chain`, …).
/// Returns the `runout.identify.recording/3` report as a dict (`full_signal.offset_um`, …).
#[pyfunction]
#[pyo3(signature = (recordings, config=None, **keys))]
fn identify<'py>(
    py: Python<'py>,
    recordings: &Bound<'py, PyAny>,
    config: Option<&Bound<'py, PyAny>>,
    keys: Option<&Bound<'py, PyDict>>,
) -> PyResult<Bound<'py, PyAny>> {
    let recs = sources(py, recordings, "recordings")?;
    let config = opt_source(py, config, "config")?;
    let flags = layer(keys, &runout_io::config::identify::identify_key_names())?;
    let r = run(py, move || {
        let req = runout::identify::resolve(config.as_ref(), flags, recs)?;
        runout::identify::recordings(&req, &mut NoProgress)
    })?;
    to_dict(py, &r)
}

/// Mechanistic milling forces with runout (methods.md §0 and §4.1: the forces of every tooth on
/// every axial disk, the chip thickness by the chosen model); the CLI's `runout simulate`.
///
/// Args: config (case TOML source, optional), sample_rate_hz (Hz: sets the angular step to
/// 360·rpm/(60·rate), as `--sample-rate-hz`), and any case key as a keyword argument overriding
/// the config (`teeth`, `diameter_mm` (mm), `helix_deg` (deg), `pitch_deg` (deg, list), `rpm`,
/// `fz_mm`, `ap_mm`, `ae_mm` (mm), `mode` (up | down | slot), `entry_deg`/`exit_deg` (deg),
/// `runout_um` (µm), `runout_angle_deg` (deg), `tilt_um_per_mm`, `tilt_angle_deg`, `ktc`, `krc`,
/// `kac` (N/mm²), `kte`, `kre`, `kae` (N/mm), `revolutions`, `step_deg` (deg), `disks`,
/// `chip_model` (arc | exact | equivalent), …).
/// Returns (report dict `runout.simulate/1` — the CLI's `--json`: inputs, tooth radii, mean
/// forces, per-tooth peaks —, series): series is a dict of float64 arrays with one element per
/// sample (the CLI's `--out` CSV at full precision): `time_s` (s), `angle_deg` (spindle angle
/// θ, deg, tooth 0's tip at immersion θ), `fx_N`, `fy_N`, `fz_N` (N, on the workpiece),
/// `torque_Nm` (N·m), and `h_mm` of shape (teeth, samples): each tooth's chip thickness at the
/// lowest disk (mm; the CSV's `h<i>_mm`).
#[pyfunction]
#[pyo3(signature = (config=None, *, sample_rate_hz=None, **keys))]
fn simulate<'py>(
    py: Python<'py>,
    config: Option<&Bound<'py, PyAny>>,
    sample_rate_hz: Option<f64>,
    keys: Option<&Bound<'py, PyDict>>,
) -> PyResult<(Bound<'py, PyAny>, Bound<'py, PyDict>)> {
    let config = opt_source(py, config, "config")?;
    let flags = layer(keys, &runout_io::config::simulate::simulate_key_names())?;
    let r = run(py, move || {
        let mut req = runout::simulate::SimulateRequest::from_config(config.as_ref(), flags)?;
        req.sample_rate_hz = sample_rate_hz;
        runout::simulate::simulate(&req)
    })?;
    let s = &r.detail.series;
    let d = PyDict::new(py);
    d.set_item("time_s", PyArray1::from_slice(py, &s.time))?;
    d.set_item(
        "angle_deg",
        PyArray1::from_iter(py, s.angle.iter().map(|a| a.to_degrees())),
    )?;
    d.set_item("fx_N", PyArray1::from_slice(py, &s.fx))?;
    d.set_item("fy_N", PyArray1::from_slice(py, &s.fy))?;
    d.set_item("fz_N", PyArray1::from_slice(py, &s.fz))?;
    d.set_item("torque_Nm", PyArray1::from_slice(py, &s.torque))?;
    let h = numpy::PyArray2::from_vec2(py, &s.chip)
        .map_err(|e| RunoutError::new_err(format!("simulate: chip thickness table: {e}")))?;
    d.set_item("h_mm", h)?;
    Ok((to_dict(py, &r)?, d))
}

fn parse_mode(mode: &str) -> PyResult<runout_core::MillingMode> {
    mode.parse()
        .map_err(|e: <runout_core::MillingMode as std::str::FromStr>::Err| {
            RunoutError::new_err(format!("mode: {e}"))
        })
}

fn hypothesis(closed_period: bool) -> runout_core::identify::SineHypothesis {
    if closed_period {
        runout_core::identify::SineHypothesis::ClosedPeriod
    } else {
        runout_core::identify::SineHypothesis::Teeth
    }
}

/// Seed-003 sine fit of one per-tooth peak table (methods.md §4.2): runout ρ (µm), λ (deg).
///
/// Args: peaks_N (per-tooth peak forces, N, teeth in cutting order), fz_mm (mm), peaks_se_N
/// (N), mode (`up` | `down` | `slot`), ae_mm (mm), diameter_mm (mm), peak_immersion_deg (deg),
/// closed_period (K + 1 points, the seed's Table 2).
/// Returns the `runout.identify.peaks/2` report as a dict.
#[pyfunction]
#[pyo3(signature = (peaks_N, *, fz_mm, peaks_se_N=None, mode="up", ae_mm=None, diameter_mm=None, peak_immersion_deg=None, closed_period=false))]
#[allow(non_snake_case, clippy::too_many_arguments)]
fn identify_peaks<'py>(
    py: Python<'py>,
    peaks_N: &Bound<'py, PyAny>,
    fz_mm: f64,
    peaks_se_N: Option<&Bound<'py, PyAny>>,
    mode: &str,
    ae_mm: Option<f64>,
    diameter_mm: Option<f64>,
    peak_immersion_deg: Option<f64>,
    closed_period: bool,
) -> PyResult<Bound<'py, PyAny>> {
    let peaks = float_array(py, peaks_N, "peaks_N")?.to_vec();
    let mut req = runout::identify::PeaksRequest::new(peaks, fz_mm);
    req.peaks_se_N = peaks_se_N
        .map(|a| float_array(py, a, "peaks_se_N").map(|v| v.to_vec()))
        .transpose()?;
    req.mode = parse_mode(mode)?;
    req.ae_mm = ae_mm;
    req.diameter_mm = diameter_mm;
    req.peak_immersion_deg = peak_immersion_deg;
    req.hypothesis = hypothesis(closed_period);
    let r = run(py, || runout::identify::peaks(&req))?;
    to_dict(py, &r)
}

/// Several peak tests (methods.md §4.6): per-test sine fits, regressions, K_T/K_R, pooled fit.
///
/// Args: table (source: CSV/TSV with `test, fz_mm, ap_mm, peak0_N…` or TOML `[[test]]` — a
/// TOML given as bytes needs a `(name.toml, bytes)` pair), diameter_mm, ae_mm (mm), mode,
/// peak_immersion_deg (deg): values the rows do not give; closed_period.
/// Returns the `runout.identify.tests/1` report as a dict.
#[pyfunction]
#[pyo3(signature = (table, *, diameter_mm=None, ae_mm=None, mode=None, peak_immersion_deg=None, closed_period=false))]
fn identify_tests<'py>(
    py: Python<'py>,
    table: &Bound<'py, PyAny>,
    diameter_mm: Option<f64>,
    ae_mm: Option<f64>,
    mode: Option<&str>,
    peak_immersion_deg: Option<f64>,
    closed_period: bool,
) -> PyResult<Bound<'py, PyAny>> {
    let mut req = runout::identify::TestsRequest::new(source(py, table, "table")?);
    req.defaults = runout::identify::TestsDefaults {
        diameter_mm,
        ae_mm,
        mode: mode.map(parse_mode).transpose()?,
        peak_immersion_deg,
    };
    req.hypothesis = hypothesis(closed_period);
    let r = run(py, || runout::identify::tests(&req))?;
    to_dict(py, &r)
}

fn row_dict<'py>(py: Python<'py>, row: &runout::batch::Row) -> PyResult<Bound<'py, PyAny>> {
    let text = serde_json::to_string(row).map_err(|e| RunoutError::new_err(e.to_string()))?;
    py.import("json")?.call_method1("loads", (text,))
}

/// One recording identified and reduced to its summary row — what `runout batch` writes for it
/// (docs/batch.md; the function to map over files or byte blobs on Dask or Spark).
///
/// Args: recording (one source: path, bytes, `(name, bytes)`, arrays), config (cut.toml source),
/// and config keys as keyword arguments (as for `identify`; `fz_mm` one value).
/// Returns a dict with the columns `runout.SUMMARY_COLUMNS` (`file`, `status` ok | error,
/// `error`, `time`, `offset_um`, `offset_se_um`, `angle_deg`, …; None when not available). A
/// recording that cannot be identified gives `status = "error"` with the message (no exception);
/// bad arguments or config keys raise `RunoutError`. Runs on one thread (parallelism across
/// recordings), so the numbers equal `runout batch`'s to the last digit.
#[pyfunction]
#[pyo3(signature = (recording, config=None, **keys))]
fn batch_row<'py>(
    py: Python<'py>,
    recording: &Bound<'py, PyAny>,
    config: Option<&Bound<'py, PyAny>>,
    keys: Option<&Bound<'py, PyDict>>,
) -> PyResult<Bound<'py, PyAny>> {
    let rec = source(py, recording, "recording")?;
    let config = opt_source(py, config, "config")?;
    let flags = layer(keys, &runout_io::config::identify::identify_key_names())?;
    let row = py.detach(move || {
        let name = rec.name().to_string();
        let path = rec.as_path().map(|p| p.to_path_buf());
        let result = runout::batch::identify_row(rec, config.as_ref(), flags);
        runout::batch::finish_row(&name, path.as_deref(), result)
    });
    row_dict(py, &row)
}

/// `runout batch` from Python: identify every recording of `inputs` (folders, glob patterns,
/// files) in parallel into the summary CSV `summary` (resumable; docs/batch.md).
///
/// Args: inputs (str or list of str), config (cut.toml path), summary (CSV path), threads
/// (default the cores), retry_errors, and config keys as keyword arguments.
/// Returns the `runout.batch/1` report as a dict (`analysed`, `ok`, `failed`, `recordings_per_s`…).
#[pyfunction]
#[pyo3(signature = (inputs, config, summary, *, threads=None, retry_errors=false, **keys))]
fn batch<'py>(
    py: Python<'py>,
    inputs: &Bound<'py, PyAny>,
    config: &Bound<'py, PyAny>,
    summary: std::path::PathBuf,
    threads: Option<usize>,
    retry_errors: bool,
    keys: Option<&Bound<'py, PyDict>>,
) -> PyResult<Bound<'py, PyAny>> {
    let specs: Vec<String> = match inputs.extract::<String>() {
        Ok(s) => vec![s],
        Err(_) => inputs.extract()?,
    };
    let config = source(py, config, "config")?;
    let flags = layer(keys, &runout_io::config::identify::identify_key_names())?;
    let r = run(py, move || {
        let mut files = Vec::new();
        for s in &specs {
            files.extend(runout::batch::expand(s)?);
        }
        let req = runout::batch::BatchRequest {
            files,
            summary,
            threads,
            retry_errors,
            parquet: None,
        };
        runout::batch::run(
            &req,
            |p: &std::path::Path| {
                runout::batch::identify_row(Source::path(p), Some(&config), flags.clone())
            },
            &|_| {},
        )
    })?;
    to_dict(py, &r)
}

/// The native module.
#[pymodule]
fn _runout(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add("RunoutError", m.py().get_type::<RunoutError>())?;
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    m.add_function(wrap_pyfunction!(shank_stiffness, m)?)?;
    m.add_function(wrap_pyfunction!(shank_force, m)?)?;
    m.add_function(wrap_pyfunction!(shank_calibrate, m)?)?;
    m.add_function(wrap_pyfunction!(displacement_teeth, m)?)?;
    m.add_function(wrap_pyfunction!(displacement_heights, m)?)?;
    m.add_function(wrap_pyfunction!(displacement_signal, m)?)?;
    m.add_function(wrap_pyfunction!(grind_compensate, m)?)?;
    m.add_function(wrap_pyfunction!(grind_check, m)?)?;
    m.add_function(wrap_pyfunction!(chip_compare, m)?)?;
    m.add_function(wrap_pyfunction!(chip_eval, m)?)?;
    m.add_function(wrap_pyfunction!(identify, m)?)?;
    m.add_function(wrap_pyfunction!(identify_peaks, m)?)?;
    m.add_function(wrap_pyfunction!(identify_tests, m)?)?;
    m.add_function(wrap_pyfunction!(simulate, m)?)?;
    m.add_function(wrap_pyfunction!(batch_row, m)?)?;
    m.add_function(wrap_pyfunction!(batch, m)?)?;
    m.add("SUMMARY_COLUMNS", runout::batch::columns())?;
    m.add(
        "SUMMARY_TEXT_COLUMNS",
        runout::batch::TEXT_COLUMNS
            .iter()
            .map(|s| s.to_string())
            .collect::<Vec<_>>(),
    )?;
    Ok(())
}
