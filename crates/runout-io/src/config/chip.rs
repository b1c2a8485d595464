//! Chip-thickness case sets (`runout chip compare`, `runout chip eval`): TOML with an optional
//! `[defaults]` table merged into every `[[case]]` table. Keys carry their unit in the name.
//!
//! ```toml
//! [defaults]
//! teeth = 4
//! diameter_mm = 10.0
//! rpm = 6000.0
//! heights_mm = [0.0, 5.0]
//!
//! [[case]]
//! name = "3-axis f_z 0.1"
//! fz_mm = 0.1
//! runout_um = 10.0
//! ```
//!
//! Motions (methods.md §2.1): `straight` (feed +x, axis +z), `circular` (`path_radius_mm`,
//! `path_ccw`), `swing` (`swing_axis`, `swing_deg_s`, `pivot_mm`), `path` (`toolpath` = APT/CSV
//! file relative to the config, `feed_mm_min` fills a missing feed), `joints` (`joints` = joint CSV
//! of a machine without RTCP, `pivot_mm` = head pivot length).

use crate::toolpath::{joint_points, parse_joint_csv, read_toolpath};
use runout_core::chip::compare::{sample_grid, Motion, SamplePoint};
use runout_core::chip::{
    CircularFeed, ClPath, ConstantSwing, JointPath, SpindleSense, StraightFeed, ToolKinematics,
    Vec3,
};
use runout_core::{limits, Cutter, RadiusProfile, Runout};
use serde::Deserialize;
use std::f64::consts::TAU;
use std::path::Path;

/// One case as written in the file (after merging `[defaults]`).
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ChipCaseSpec {
    /// Case name.
    pub name: String,
    /// Number of teeth K.
    pub teeth: usize,
    /// Cutter diameter (mm).
    pub diameter_mm: f64,
    /// Helix angle (deg).
    #[serde(default)]
    pub helix_deg: f64,
    /// Variable pitch (deg), K values summing to 360.
    #[serde(default)]
    pub pitch_deg: Option<Vec<f64>>,
    /// Radius profile: flat | ball | bull_nose | tapered (the vocabulary of every command,
    /// [`super::radius_profile`]).
    #[serde(default = "default_profile")]
    pub profile: String,
    /// Corner radius of a bull-nose cutter (mm); older name of `corner_radius_mm`.
    #[serde(default)]
    pub corner_mm: Option<f64>,
    /// Corner radius of a bull-nose cutter (mm).
    #[serde(default)]
    pub corner_radius_mm: Option<f64>,
    /// Taper (half-cone) angle of a tapered cutter (deg).
    #[serde(default)]
    pub taper_deg: Option<f64>,
    /// Spindle speed (rpm).
    pub rpm: f64,
    /// Spindle rotation seen from above: cw | ccw.
    #[serde(default)]
    pub spindle: Spindle,
    /// Feed per tooth (mm) for straight, circular and swing motion.
    #[serde(default)]
    pub fz_mm: Option<f64>,
    /// Runout offset ρ (µm).
    #[serde(default)]
    pub runout_um: f64,
    /// Runout angle λ (deg) from tooth 0 in the direction of rotation.
    #[serde(default)]
    pub runout_angle_deg: f64,
    /// Tilt |τ| (µm per mm of height).
    #[serde(default)]
    pub tilt_um_per_mm: f64,
    /// Tilt direction (deg, spindle frame).
    #[serde(default)]
    pub tilt_angle_deg: f64,
    /// Motion: straight | circular | swing | path | joints.
    #[serde(default)]
    pub motion: MotionKind,
    /// Swing axis (workpiece frame), for `swing`.
    #[serde(default)]
    pub swing_axis: Option<[f64; 3]>,
    /// Swing rate (deg/s), for `swing`.
    #[serde(default)]
    pub swing_deg_s: f64,
    /// Pivot height above the tip (mm), for `swing`; pivot length of the head, for `joints`.
    #[serde(default)]
    pub pivot_mm: f64,
    /// Path radius (mm), for `circular`.
    #[serde(default)]
    pub path_radius_mm: Option<f64>,
    /// Counter-clockwise circle (seen from above), for `circular`.
    #[serde(default = "default_true")]
    pub path_ccw: bool,
    /// CL file (APT or CSV), for `path`; relative to the config file.
    #[serde(default)]
    pub toolpath: Option<String>,
    /// Joint CSV (`x_mm,y_mm,z_mm,a_deg,c_deg[,feed_mm_min]`), for `joints` (machine without
    /// RTCP, head-head A/C kinematics with pivot length `pivot_mm`); relative to the config file.
    #[serde(default)]
    pub joints: Option<String>,
    /// Feed (mm/min) for CL points without one.
    #[serde(default)]
    pub feed_mm_min: Option<f64>,
    /// Heights z above the tip to evaluate (mm).
    pub heights_mm: Vec<f64>,
    /// Time samples per spindle revolution.
    #[serde(default = "default_samples")]
    pub samples_per_rev: usize,
    /// Number of revolutions sampled (for `path`: 0 = the whole path).
    #[serde(default = "default_revolutions")]
    pub revolutions: f64,
    /// Start of the sampling (s); default one revolution after t = 0 so that every previous pass
    /// lies on the motion.
    #[serde(default)]
    pub start_s: Option<f64>,
}

fn default_profile() -> String {
    "flat".into()
}
/// `spindle = cw | ccw`: the spindle's rotation seen from above.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Spindle {
    /// Clockwise.
    #[default]
    Cw,
    /// Counter-clockwise.
    Ccw,
}

/// `motion = straight | circular | swing | path | joints`: how the tool moves in a case.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum MotionKind {
    /// Straight feed along x (`fz_mm`).
    #[default]
    Straight,
    /// Circular path (`path_radius_mm`, `path_ccw`).
    Circular,
    /// Straight feed with a constant swing of the tool axis (`swing_axis`, `swing_deg_s`).
    Swing,
    /// A CL toolpath file (`toolpath`).
    Path,
    /// Machine joints of a head-head A/C machine without RTCP (`joints`).
    Joints,
}

impl MotionKind {
    /// The word as written in a case file.
    pub fn name(self) -> &'static str {
        match self {
            MotionKind::Straight => "straight",
            MotionKind::Circular => "circular",
            MotionKind::Swing => "swing",
            MotionKind::Path => "path",
            MotionKind::Joints => "joints",
        }
    }
}
fn default_true() -> bool {
    true
}
fn default_samples() -> usize {
    360
}
fn default_revolutions() -> f64 {
    1.0
}

/// Error in a chip case file.
#[derive(Debug, thiserror::Error)]
pub enum ChipConfigError {
    /// Unreadable file.
    #[error("{file}: cannot read: {}", crate::report::io_problem(.error))]
    Io {
        /// File.
        file: String,
        /// Cause. (part of the message, not a `source()`: printed once)
        error: std::io::Error,
    },
    /// TOML/serde error (with line and column).
    #[error("{file}: {message}")]
    Parse {
        /// File.
        file: String,
        /// Message.
        message: String,
    },
    /// A case has an invalid value.
    #[error("{file}: case `{case}`: {message}")]
    Case {
        /// File.
        file: String,
        /// Case name.
        case: String,
        /// What is wrong.
        message: String,
    },
}

/// A resolved case: kinematics and the evaluation grid.
#[derive(Debug, Clone)]
pub struct ChipCase {
    /// Name.
    pub name: String,
    /// The spec it came from.
    pub spec: ChipCaseSpec,
    /// Kinematics (methods.md eq. 2.1).
    pub kin: ToolKinematics<Motion>,
    /// Evaluation points (tooth × height × time).
    pub points: Vec<SamplePoint>,
    /// Warnings (toolpath normalisation …).
    pub warnings: Vec<String>,
}

/// `key = "word"` of `t` checked against the vocabulary `T` (exactly, as serde reads it): an
/// unknown word is `key `k`: unknown variant …, expected …`.
fn word_key<T: serde::de::DeserializeOwned>(t: &toml::Table, key: &str) -> Result<(), String> {
    use serde::de::value::{Error, StrDeserializer};
    use serde::de::IntoDeserializer;
    match t.get(key) {
        Some(toml::Value::String(w)) => {
            let d: StrDeserializer<'_, Error> = w.as_str().into_deserializer();
            T::deserialize(d)
                .map(|_| ())
                .map_err(|e| format!("key `{key}`: {}", super::clip_quoted(&e.to_string())))
        }
        _ => Ok(()),
    }
}

/// Parse the case specs of a case-set file (defaults merged).
pub fn parse_case_specs(file: &str, text: &str) -> Result<Vec<ChipCaseSpec>, ChipConfigError> {
    let perr = |message: String| ChipConfigError::Parse {
        file: file.into(),
        message,
    };
    let mut doc: toml::Table =
        toml::from_str(text).map_err(|e| perr(super::toml_error(text, &e)))?;
    if let Some(key) = doc.iter().find_map(|(k, v)| super::non_finite_key(v, k)) {
        return Err(perr(format!(
            "key `{key}`: expected a finite number, got nan or inf"
        )));
    }
    let defaults = match doc.remove("defaults") {
        Some(toml::Value::Table(t)) => t,
        Some(_) => return Err(perr("`defaults` must be a table".into())),
        None => toml::Table::new(),
    };
    let cases = match doc.remove("case") {
        Some(toml::Value::Array(a)) => a,
        _ => return Err(perr("expected one or more [[case]] tables".into())),
    };
    if let Some(k) = doc.keys().next() {
        return Err(perr(format!(
            "unknown top-level key `{k}` (expected [defaults] and [[case]])"
        )));
    }
    cases
        .into_iter()
        .enumerate()
        .map(|(n, c)| {
            let toml::Value::Table(t) = c else {
                return Err(perr(format!("case {}: not a table", n + 1)));
            };
            let mut merged = defaults.clone();
            merged.extend(t);
            // the words first, so that an unknown one is named with its key
            word_key::<MotionKind>(&merged, "motion")
                .and_then(|_| word_key::<Spindle>(&merged, "spindle"))
                .map_err(|message| match merged.get("name") {
                    Some(toml::Value::String(name)) => ChipConfigError::Case {
                        file: file.into(),
                        case: name.clone(),
                        message,
                    },
                    _ => perr(format!("case {}: {message}", n + 1)),
                })?;
            toml::Value::Table(merged)
                .try_into::<ChipCaseSpec>()
                .map_err(|e| {
                    perr(format!(
                        "case {}: {}",
                        n + 1,
                        super::clip_quoted(e.message())
                    ))
                })
        })
        .collect()
}

/// Read and resolve every case of `path`.
pub fn read_cases(path: &Path) -> Result<Vec<ChipCase>, ChipConfigError> {
    let file = path.display().to_string();
    let text = crate::textfile::read_text(path).map_err(|e| ChipConfigError::Parse {
        file: file.clone(),
        message: match e.line() {
            Some(l) => format!("line {l}: {}", e.message),
            None => e.message,
        },
    })?;
    let base = path.parent().unwrap_or(Path::new("."));
    parse_case_specs(&file, &text)?
        .into_iter()
        .map(|s| resolve_case(&file, base, s))
        .collect()
}

fn cutter_of(s: &ChipCaseSpec) -> Result<Cutter, String> {
    if s.corner_mm.is_some() && s.corner_radius_mm.is_some() {
        return Err(
            "corner_radius_mm: give either corner_radius_mm or its older name corner_mm, not both"
                .into(),
        );
    }
    let profile: RadiusProfile = super::radius_profile(
        &s.profile,
        s.diameter_mm,
        s.corner_radius_mm.or(s.corner_mm),
        s.taper_deg,
    )
    .map_err(|(k, m)| format!("{k}: {m}"))?;
    let pitch = match &s.pitch_deg {
        Some(p) if p.len() != s.teeth => {
            return Err(format!(
                "pitch_deg: expected {} values, got {}",
                s.teeth,
                p.len()
            ))
        }
        Some(p) => p.iter().map(|d| d.to_radians()).collect(),
        // checked before anything is allocated per tooth
        None => {
            limits::teeth("teeth", s.teeth).map_err(|e| e.to_string())?;
            vec![TAU / s.teeth as f64; s.teeth]
        }
    };
    Cutter::new(
        s.diameter_mm,
        pitch,
        s.helix_deg.to_radians(),
        f64::INFINITY,
        profile,
    )
    .map_err(|e| e.to_string())
}

fn runout_of(s: &ChipCaseSpec, cutter: &Cutter) -> Result<Runout, String> {
    Runout::new(s.runout_um * 1e-3, s.runout_angle_deg.to_radians())
        .and_then(|r| r.with_tilt(s.tilt_um_per_mm * 1e-3, s.tilt_angle_deg.to_radians()))
        .and_then(|r| {
            limits::runout_vs_radius("runout_um", s.runout_um * 1e-3, cutter.radius()).map(|_| r)
        })
        .map_err(|e| e.to_string())
}

fn feed_speed(s: &ChipCaseSpec) -> Result<f64, String> {
    let fz = s.fz_mm.ok_or("fz_mm: required for this motion")?;
    limits::positive_at_most("fz_mm", fz, limits::MAX_FZ_MM, "mm").map_err(|e| e.to_string())?;
    Ok(fz * s.teeth as f64 * s.rpm / 60.0)
}

/// Motion of a case and the warnings of reading its toolpath.
fn motion_of(s: &ChipCaseSpec, base: &Path) -> Result<(Motion, Vec<String>), String> {
    if let Some(f) = s.feed_mm_min {
        limits::feed_mm_min("feed_mm_min", f).map_err(|e| e.to_string())?;
    }
    let along_x = |v: f64| Vec3::new(v, 0.0, 0.0);
    Ok(match s.motion {
        MotionKind::Straight => (
            Motion::Straight(StraightFeed::along_x(feed_speed(s)?)),
            vec![],
        ),
        MotionKind::Circular => {
            let r = s
                .path_radius_mm
                .ok_or("path_radius_mm: required for circular")?;
            let c = CircularFeed::new(Vec3::zeros(), r, feed_speed(s)?, s.path_ccw)
                .map_err(|e| e.to_string())?;
            (Motion::Circular(c), vec![])
        }
        MotionKind::Swing => {
            let a = s.swing_axis.ok_or("swing_axis: required for swing")?;
            let w = ConstantSwing::new(
                along_x(feed_speed(s)?),
                Vec3::new(a[0], a[1], a[2]),
                s.swing_deg_s.to_radians(),
                s.pivot_mm,
            )
            .map_err(|e| e.to_string())?;
            (Motion::Swing(w), vec![])
        }
        MotionKind::Path => {
            let file = s.toolpath.as_ref().ok_or("toolpath: required for path")?;
            let full = base.join(file);
            let mut tp = read_toolpath(&full).map_err(|e| e.to_string())?;
            let name = full.display().to_string();
            let cl = tp
                .cl_points(&name, s.feed_mm_min)
                .map_err(|e| e.to_string())?;
            let path = ClPath::new(&cl).map_err(|e| format!("{name}: {e}"))?;
            (Motion::Path(path), tp.warnings)
        }
        MotionKind::Joints => {
            let file = s
                .joints
                .as_ref()
                .ok_or("joints: required for motion joints")?;
            let full = base.join(file);
            let name = full.display().to_string();
            let text = crate::textfile::read_text(&full).map_err(|e| e.to_string())?;
            let blocks = parse_joint_csv(&name, &text).map_err(|e| e.to_string())?;
            let pts = joint_points(&name, &blocks, s.feed_mm_min).map_err(|e| e.to_string())?;
            let path = JointPath::new(&pts, s.pivot_mm).map_err(|e| format!("{name}: {e}"))?;
            (Motion::Joints(path), vec![])
        }
    })
}

/// Resolve one spec (toolpaths relative to `base`).
pub fn resolve_case(
    file: &str,
    base: &Path,
    spec: ChipCaseSpec,
) -> Result<ChipCase, ChipConfigError> {
    let err = |message: String| ChipConfigError::Case {
        file: file.into(),
        case: spec.name.clone(),
        message,
    };
    let cutter = cutter_of(&spec).map_err(err)?;
    let runout = runout_of(&spec, &cutter).map_err(err)?;
    let sense = match spec.spindle {
        Spindle::Cw => SpindleSense::Clockwise,
        Spindle::Ccw => SpindleSense::CounterClockwise,
    };
    let (motion, warnings) = motion_of(&spec, base).map_err(err)?;
    let duration = match &motion {
        Motion::Path(p) => Some(p.duration()),
        Motion::Joints(p) => Some(p.duration()),
        _ => None,
    };
    let kin = ToolKinematics::new(&cutter, &runout, spec.rpm, 0.0, sense, motion)
        .map_err(|e| err(e.to_string()))?;
    if spec.heights_mm.is_empty()
        || spec
            .heights_mm
            .iter()
            .any(|z| !(z.is_finite() && *z >= 0.0))
    {
        return Err(err(
            "heights_mm: expected one or more heights >= 0 (mm)".into()
        ));
    }
    limits::count(
        "samples_per_rev",
        spec.samples_per_rev,
        limits::MAX_SAMPLES_PER_REV,
    )
    .and_then(|_| {
        limits::within(
            "revolutions",
            spec.revolutions,
            0.0,
            limits::MAX_REVOLUTIONS,
            "(0 = the whole path)",
        )
    })
    .map_err(|e| err(e.to_string()))?;
    let period = kin.period();
    let t0 = spec.start_s.unwrap_or(period);
    let span = match (duration, spec.revolutions) {
        (Some(d), 0.0) => d - t0,
        (_, r) => r * period,
    };
    if span.is_nan() || span <= 0.0 {
        return Err(err(format!(
            "nothing to sample: start {t0:.4} s, span {span:.4} s (path shorter than one revolution?)"
        )));
    }
    let samples = ((span / period) * spec.samples_per_rev as f64)
        .round()
        .max(1.0);
    // the grid's size, checked before it is allocated (a tiny feed makes a long path)
    let grid = samples * (cutter.teeth() * spec.heights_mm.len()) as f64;
    limits::work(
        "samples_per_rev",
        &format!(
            "evaluation points ({:.4e} s of path = {:.4e} revolutions)",
            span,
            span / period
        ),
        grid,
        limits::MAX_SAMPLES as f64,
    )
    .map_err(|e| err(e.to_string()))?;
    let samples = samples as usize;
    let points = sample_grid(cutter.teeth(), &spec.heights_mm, t0, span, samples);
    Ok(ChipCase {
        name: spec.name.clone(),
        spec,
        kin,
        points,
        warnings,
    })
}
