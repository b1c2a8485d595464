//! `runout displacement <teeth|heights|signal> …`: runout identified in position from displacement
//! readings (methods.md §1, seed 000). Shared flags, parsing and output helpers live here; each
//! input kind has its own file.

mod heights;
mod signal;
mod teeth;

use anyhow::{bail, Context, Result};
use runout_core::displacement::{
    consequences, AngleEstimate, BeamGeometry, Consequences, SensorSign,
};
use runout_core::{Cutter, Runout};
use runout_io::units::{parse_quantity, Quantity};
use serde_json::{json, Value};
use std::path::{Path, PathBuf};

/// Input kinds of `runout displacement`.
#[derive(clap::Subcommand, Debug)]
pub enum Kind {
    /// Per-tooth readings (CSV `tooth,reading_um` or `seed_edge,reading_um`) → offset and angle.
    Teeth(teeth::Args),
    /// Runout at several heights (CSV `z_mm,tir_um[,angle_deg]`) → runout at the cutting height.
    Heights(heights::Args),
    /// Raw signal (CSV `time_s,disp_a_um[,disp_b_um…][,pulse|encoder_deg]`) → runout vector.
    Signal(signal::Args),
}

/// Arguments of `runout displacement`.
#[derive(clap::Args, Debug)]
pub struct Args {
    #[command(subcommand)]
    pub kind: Kind,
}

/// Run `runout displacement`.
pub fn run(a: Args) -> Result<()> {
    match a.kind {
        Kind::Teeth(a) => teeth::run(a),
        Kind::Heights(a) => heights::run(a),
        Kind::Signal(a) => signal::run(a),
    }
}

/// Output flags shared by every kind.
#[derive(clap::Args, Debug, Default)]
pub struct OutputFlags {
    /// Write the JSON result (schema `runout.displacement.<kind>/1`); `-` for stdout.
    #[arg(long, allow_hyphen_values = true)]
    pub json: Option<PathBuf>,
    /// Write the human-readable report here instead of stdout (`-` = stdout).
    #[arg(long, allow_hyphen_values = true)]
    pub text: Option<PathBuf>,
    /// Plot (.svg or .png).
    #[arg(long, allow_hyphen_values = true)]
    pub plot: Option<PathBuf>,
}

impl OutputFlags {
    /// Refuse outputs that overwrite `input`; then write JSON and text (text to stdout unless
    /// the JSON goes there).
    pub fn write(&self, input: &Path, json: &Value, text: &str) -> Result<()> {
        for out in [&self.json, &self.text, &self.plot].into_iter().flatten() {
            crate::output::check_not_input(out, &[input])?;
        }
        if let Some(j) = &self.json {
            crate::output::write_text(j, &(serde_json::to_string_pretty(json)? + "\n"))?;
        }
        let json_on_stdout = self.json.as_deref() == Some(Path::new("-"));
        match &self.text {
            Some(t) => crate::output::write_text(t, text)?,
            None if !json_on_stdout => crate::output::write_text(Path::new("-"), text)?,
            None => {}
        }
        Ok(())
    }
}

/// Parse an optional flag value of quantity `q`; the error names the flag.
pub fn quantity(flag: &str, v: &Option<String>, q: Quantity) -> Result<Option<f64>> {
    v.as_deref()
        .map(|t| parse_quantity(t, q).with_context(|| format!("--{flag}")))
        .transpose()
}

/// An optional flag in µm (suffixes allowed), returned in mm.
pub fn um_as_mm(flag: &str, v: &Option<String>) -> Result<Option<f64>> {
    Ok(quantity(flag, v, Quantity::LengthUm)?.map(|x| x * 1e-3))
}

/// A count flag (integer ≥ 1).
pub fn count(flag: &str, v: &Option<String>) -> Result<Option<usize>> {
    v.as_deref()
        .map(|t| {
            t.trim()
                .parse::<usize>()
                .ok()
                .filter(|n| *n >= 1)
                .with_context(|| format!("--{flag}: `{t}` is not an integer >= 1"))
        })
        .transpose()
}

/// `--sensor distance|radial`.
pub fn sensor_sign(v: &Option<String>) -> Result<SensorSign> {
    match v.as_deref().map(str::trim) {
        None | Some("distance") => Ok(SensorSign::Distance),
        Some("radial") => Ok(SensorSign::Radial),
        Some(o) => bail!("--sensor: `{o}` is not `distance` (reading grows away from the tool) or `radial` (reading grows with the radius)"),
    }
}

/// Cutter flags shared by teeth and signal.
#[derive(clap::Args, Debug, Default)]
pub struct CutterFlags {
    /// Number of teeth K.
    #[arg(long, allow_hyphen_values = true)]
    pub teeth: Option<String>,
    /// Nominal cutter diameter D (mm).
    #[arg(long, allow_hyphen_values = true)]
    pub diameter_mm: Option<String>,
    /// Helix angle (deg), 0 for straight flutes.
    #[arg(long, allow_hyphen_values = true)]
    pub helix_deg: Option<String>,
    /// Height z of the readings above the tool tip (mm); tooth angles follow the helix.
    #[arg(long, allow_hyphen_values = true)]
    pub height_mm: Option<String>,
    /// Feed per tooth f_z (mm) for the predicted per-tooth chip loads.
    #[arg(long, allow_hyphen_values = true)]
    pub fz_mm: Option<String>,
    /// Diameter of a circular tool path (mm) for the predicted hole diameter.
    #[arg(long, allow_hyphen_values = true)]
    pub hole_path_mm: Option<String>,
}

impl CutterFlags {
    /// The cutter, when --teeth and --diameter-mm are given.
    pub fn cutter(&self) -> Result<Option<Cutter>> {
        let k = count("teeth", &self.teeth)?;
        let d = quantity("diameter-mm", &self.diameter_mm, Quantity::LengthMm)?;
        let helix = quantity("helix-deg", &self.helix_deg, Quantity::AngleDeg)?.unwrap_or(0.0);
        match (k, d) {
            (Some(k), Some(d)) => Ok(Some(Cutter::flat(d, k, helix)?)),
            (None, None) => Ok(None),
            _ => bail!("--teeth and --diameter-mm go together"),
        }
    }
    /// Height (mm), default 0.
    pub fn height(&self) -> Result<f64> {
        Ok(quantity("height-mm", &self.height_mm, Quantity::LengthMm)?.unwrap_or(0.0))
    }
    /// Consequences (§1.7) of a determined runout.
    pub fn consequences(&self, cutter: &Cutter, runout: &Runout) -> Result<Consequences> {
        let fz = quantity("fz-mm", &self.fz_mm, Quantity::LengthMm)?;
        let hole = quantity("hole-path-mm", &self.hole_path_mm, Quantity::LengthMm)?;
        Ok(consequences(cutter, runout, self.height()?, fz, hole)?)
    }
}

/// Beam flags (methods.md §1.4).
#[derive(clap::Args, Debug, Default)]
pub struct BeamFlags {
    /// Sensor output: `distance` (default; grows away from the tool, triangulation lasers) or `radial`.
    #[arg(long, allow_hyphen_values = true)]
    pub sensor: Option<String>,
    /// Beam inclination to the surface normal (deg), seed eq. (9).
    #[arg(long, allow_hyphen_values = true)]
    pub inclination_deg: Option<String>,
    /// Lateral offset of the beam from the spindle axis (mm), methods.md §1.4.
    #[arg(long, allow_hyphen_values = true)]
    pub beam_offset_mm: Option<String>,
}

impl BeamFlags {
    /// The beam geometry.
    pub fn beam(&self) -> Result<BeamGeometry> {
        let inc =
            quantity("inclination-deg", &self.inclination_deg, Quantity::AngleDeg)?.unwrap_or(0.0);
        let b =
            quantity("beam-offset-mm", &self.beam_offset_mm, Quantity::LengthMm)?.unwrap_or(0.0);
        Ok(BeamGeometry::new(inc.to_radians(), b)?)
    }
    /// JSON echo.
    pub fn json(&self) -> Result<Value> {
        let b = self.beam()?;
        Ok(json!({
            "sensor": format!("{:?}", sensor_sign(&self.sensor)?).to_lowercase(),
            "inclination_deg": b.inclination().to_degrees(),
            "beam_offset_mm": b.offset(),
        }))
    }
}

/// JSON fields of an angle estimate (degrees).
pub fn angle_json(a: &AngleEstimate) -> Value {
    let se = a.se().map(f64::to_degrees);
    match a {
        AngleEstimate::Determined { angle_rad, .. } => json!({
            "angle_status": "determined", "angle_deg": angle_rad.to_degrees(), "angle_se_deg": se,
        }),
        AngleEstimate::Ambiguous {
            candidates_rad,
            reason,
            ..
        } => json!({
            "angle_status": "ambiguous", "angle_deg": null, "angle_se_deg": se,
            "angle_candidates_deg": [candidates_rad[0].to_degrees(), candidates_rad[1].to_degrees()],
            "angle_reason": reason,
        }),
        AngleEstimate::Undetermined {
            reason,
            rejected_rad,
            ..
        } => json!({
            "angle_status": "undetermined", "angle_deg": null, "angle_se_deg": se,
            "angle_rejected_deg": rejected_rad.map(f64::to_degrees), "angle_reason": reason,
        }),
    }
}

/// Text line of an angle estimate.
pub fn angle_text(a: &AngleEstimate) -> String {
    let se = |s: Option<f64>| {
        s.map_or("σ unknown".to_string(), |s| {
            format!("± {:.2}° (1σ)", s.to_degrees())
        })
    };
    match a {
        AngleEstimate::Determined { angle_rad, se_rad } => {
            format!("angle λ = {:.2}° {}", angle_rad.to_degrees(), se(*se_rad))
        }
        AngleEstimate::Ambiguous {
            candidates_rad,
            se_rad,
            reason,
        } => format!(
            "angle λ = {:.2}° or {:.2}° {} — AMBIGUOUS: {reason}",
            candidates_rad[0].to_degrees(),
            candidates_rad[1].to_degrees(),
            se(*se_rad)
        ),
        AngleEstimate::Undetermined { reason, .. } => format!("angle λ UNDETERMINED: {reason}"),
    }
}

/// JSON of the consequences (§1.7).
pub fn consequences_json(c: &Consequences) -> Value {
    json!({
        "height_mm": c.height_mm,
        "tooth_radii_mm": c.tooth_radii_mm,
        "slot_width_mm": c.slot_width_mm,
        "hole_diameter_mm": c.hole_diameter_mm,
        "fz_mm": c.fz_mm,
        "chip_load_um": c.chip_load_mm.as_ref().map(|v| v.iter().map(|h| h * 1e3).collect::<Vec<_>>()),
    })
}

/// Text of the consequences.
pub fn consequences_text(c: &Consequences) -> String {
    let mut s = String::from("predicted (methods.md §1.7):\n");
    for (i, r) in c.tooth_radii_mm.iter().enumerate() {
        s += &format!("  tooth {i}: radius {r:.6} mm");
        if let Some(h) = &c.chip_load_mm {
            s += &format!(", chip load {:.3} µm", h[i] * 1e3);
        }
        s += "\n";
    }
    s += &format!("  slot width {:.6} mm\n", c.slot_width_mm);
    if let Some(d) = c.hole_diameter_mm {
        s += &format!("  hole diameter {d:.6} mm\n");
    }
    s
}

/// Notes as text lines.
pub fn notes_text(notes: &[String]) -> String {
    notes.iter().map(|n| format!("note: {n}\n")).collect()
}
