//! Keys of a force-simulation case (`runout simulate`), their units, and their resolution into
//! the library's model types.

use super::{ConfigError, Settings};
use crate::units::Quantity;
use runout_core::{
    limits, Cut, Cutter, CuttingCoefficients, FluteLead, MillingMode, ParamError, RadiusProfile,
    Runout, Sampling,
};

/// Every key of a simulation case: (key, quantity, help). The CLI flag is `--key-with-dashes`.
pub const SIMULATE_KEYS: &[(&str, Quantity, &str)] = &[
    ("teeth", Quantity::Dimensionless, "number of teeth K"),
    ("diameter_mm", Quantity::LengthMm, "cutter diameter D (mm)"),
    (
        "helix_deg",
        Quantity::AngleDeg,
        "helix angle (deg), 0 for straight flutes [default 0]",
    ),
    (
        "pitch_deg",
        Quantity::AngleDeg,
        "variable pitch angles (deg), K values summing to 360 [default uniform]",
    ),
    (
        "flute_length_mm",
        Quantity::LengthMm,
        "flute length (mm) [default unbounded]",
    ),
    (
        "profile",
        Quantity::Dimensionless,
        "end profile: flat | ball | bull_nose | tapered [default flat]",
    ),
    (
        "corner_radius_mm",
        Quantity::LengthMm,
        "corner radius r_c of a bull_nose cutter (mm), 0 < r_c <= D/2",
    ),
    (
        "taper_deg",
        Quantity::AngleDeg,
        "taper (half-cone) angle of a tapered cutter (deg), 0 < α < 45; D is the tip diameter",
    ),
    (
        "flute_lead",
        Quantity::Dimensionless,
        "flute winding on a ball, bull-nose or taper: constant_lead | constant_helix [default constant_lead]",
    ),
    ("rpm", Quantity::SpeedRpm, "spindle speed (rpm)"),
    ("fz_mm", Quantity::LengthMm, "feed per tooth f_z (mm)"),
    ("ap_mm", Quantity::LengthMm, "axial depth of cut a_p (mm)"),
    (
        "ae_mm",
        Quantity::LengthMm,
        "radial depth of cut a_e (mm); not needed for slot or explicit angles",
    ),
    ("mode", Quantity::Dimensionless, "up | down | slot"),
    (
        "entry_deg",
        Quantity::AngleDeg,
        "explicit entry immersion angle (deg), with exit_deg, instead of ae_mm/mode",
    ),
    (
        "exit_deg",
        Quantity::AngleDeg,
        "explicit exit immersion angle (deg)",
    ),
    (
        "runout_um",
        Quantity::LengthUm,
        "runout offset ρ (µm) [default 0]",
    ),
    (
        "runout_angle_deg",
        Quantity::AngleDeg,
        "runout angle λ from tooth 0 in the rotation direction (deg) [default 0]",
    ),
    (
        "tilt_um_per_mm",
        Quantity::TiltUmPerMm,
        "runout tilt |τ| (µm per mm of height) [default 0]",
    ),
    (
        "tilt_angle_deg",
        Quantity::AngleDeg,
        "direction of the tilt in the spindle frame (deg) [default 0]",
    ),
    (
        "ktc",
        Quantity::ForcePerArea,
        "tangential shear coefficient K_tc (N/mm²)",
    ),
    (
        "krc",
        Quantity::ForcePerArea,
        "radial shear coefficient K_rc (N/mm²)",
    ),
    (
        "kac",
        Quantity::ForcePerArea,
        "axial shear coefficient K_ac (N/mm²) [default 0]",
    ),
    (
        "kte",
        Quantity::ForcePerLength,
        "tangential edge coefficient K_te (N/mm) [default 0]",
    ),
    (
        "kre",
        Quantity::ForcePerLength,
        "radial edge coefficient K_re (N/mm) [default 0]",
    ),
    (
        "kae",
        Quantity::ForcePerLength,
        "axial edge coefficient K_ae (N/mm) [default 0]",
    ),
    (
        "revolutions",
        Quantity::Dimensionless,
        "spindle revolutions simulated [default 2]",
    ),
    (
        "step_deg",
        Quantity::AngleDeg,
        "angular step (deg) [default 0.5]",
    ),
    (
        "disks",
        Quantity::Dimensionless,
        "axial disks [default 1 without helix, 50 with]",
    ),
    (
        "chip_model",
        Quantity::Dimensionless,
        "chip-thickness model: arc | exact | equivalent (docs/methods.md §2) [default arc]",
    ),
];

/// The chip-thickness model of a force simulation (`chip_model`): arc (methods.md eq. 0.4),
/// exact (eq. 2.2–2.3), equivalent (eq. 2.8).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ForceChipModel {
    /// Circular-arc approximation h = f_z sin φ with runout (eq. 0.4).
    #[default]
    Arc,
    /// Exact trochoidal chip (Newton, eq. 2.2–2.3).
    Exact,
    /// Equivalent chip with compensation (eq. 2.8).
    Equivalent,
}

impl ForceChipModel {
    /// `arc`, `exact` or `equivalent`.
    pub fn name(self) -> &'static str {
        match self {
            ForceChipModel::Arc => "arc",
            ForceChipModel::Exact => "exact",
            ForceChipModel::Equivalent => "equivalent",
        }
    }
}

/// Names of all keys.
pub fn simulate_key_names() -> Vec<&'static str> {
    SIMULATE_KEYS.iter().map(|k| k.0).collect()
}

/// A fully resolved simulation case.
#[derive(Debug, Clone)]
pub struct SimulateCase {
    /// The cutter.
    pub cutter: Cutter,
    /// Its runout.
    pub runout: Runout,
    /// Cutting conditions.
    pub cut: Cut,
    /// Coefficients.
    pub coefficients: CuttingCoefficients,
    /// Sampling.
    pub sampling: Sampling,
    /// Chip-thickness model.
    pub chip_model: ForceChipModel,
}

/// A model error for `e.param`, attributed to the layer that set that key.
fn key_err(s: &Settings, e: ParamError) -> ConfigError {
    let origin = s.origin(&e.param).unwrap_or("defaults").to_string();
    ConfigError::Key {
        source_name: origin,
        key: e.param.clone(),
        message: format!("expected {}, got {}", e.expected, e.got),
    }
}

/// The cutter keys (`teeth`, `diameter_mm`, `helix_deg`, `pitch_deg`, `flute_length_mm`).
pub fn resolve_cutter(s: &Settings) -> Result<Cutter, ConfigError> {
    let teeth = s.count("teeth")?.ok_or_else(|| ConfigError::Missing {
        key: "teeth".into(),
        flag: "teeth".into(),
        what: "number of teeth".into(),
    })?;
    // before anything is allocated per tooth
    limits::teeth("teeth", teeth).map_err(|e| key_err(s, e))?;
    let d = s.require("diameter_mm", Quantity::LengthMm, "cutter diameter")?;
    let helix = s.or("helix_deg", Quantity::AngleDeg, 0.0)?;
    let flute = s.or("flute_length_mm", Quantity::LengthMm, f64::INFINITY)?;
    let profile = resolve_profile(s, d)?;
    let lead: FluteLead = s.choice("flute_lead")?.unwrap_or_default();
    let cutter = match s.list("pitch_deg", Quantity::AngleDeg)? {
        None => Cutter::new(
            d,
            vec![std::f64::consts::TAU / teeth as f64; teeth],
            helix.to_radians(),
            flute,
            profile.clone(),
        ),
        Some(p) => {
            if p.len() != teeth {
                return Err(ConfigError::Key {
                    source_name: s.origin("pitch_deg").unwrap_or("config").into(),
                    key: "pitch_deg".into(),
                    message: format!(
                        "expected {teeth} pitch angles (one per tooth), got {}",
                        p.len()
                    ),
                });
            }
            Cutter::new(
                d,
                p.iter().map(|x| x.to_radians()).collect(),
                helix.to_radians(),
                flute,
                profile,
            )
        }
    }
    .map_err(|e| key_err(s, e))?
    .with_lead(lead);

    Ok(cutter)
}

/// The end-profile keys (`profile`, `corner_radius_mm`, `taper_deg`) for a cutter of
/// diameter `d` (mm), through the shared vocabulary [`super::radius_profile`].
pub fn resolve_profile(s: &Settings, d: f64) -> Result<RadiusProfile, ConfigError> {
    let name = s.text("profile")?.unwrap_or_else(|| "flat".into());
    let corner = s.quantity("corner_radius_mm", Quantity::LengthMm)?;
    let taper = s.quantity("taper_deg", Quantity::AngleDeg)?;
    super::radius_profile(&name, d, corner, taper).map_err(|(key, message)| ConfigError::Key {
        source_name: s.origin(&key).unwrap_or("config").into(),
        key,
        message,
    })
}

/// The cut keys (`rpm`, `mode`, `ae_mm` or `entry_deg`/`exit_deg`) with a given feed per tooth
/// and axial depth (mm), for `cutter`.
pub fn resolve_cut(s: &Settings, cutter: &Cutter, fz: f64, ap: f64) -> Result<Cut, ConfigError> {
    let d = cutter.diameter();
    let rpm = s.require("rpm", Quantity::SpeedRpm, "spindle speed")?;
    let base = Cut::new(rpm, fz, ap).map_err(|e| key_err(s, e))?;
    if ap > cutter.flute_length() {
        return Err(ConfigError::Key {
            source_name: s.origin("ap_mm").unwrap_or("config").into(),
            key: "ap_mm".into(),
            message: format!(
                "expected an axial depth within the flute length {} mm, got {}",
                runout_core::limits::show(cutter.flute_length()),
                runout_core::limits::show(ap)
            ),
        });
    }
    let cut = if s.has("entry_deg") || s.has("exit_deg") {
        let en = s.require("entry_deg", Quantity::AngleDeg, "entry angle")?;
        let ex = s.require("exit_deg", Quantity::AngleDeg, "exit angle")?;
        base.angles(en.to_radians(), ex.to_radians())
    } else {
        let mode_text = s.text("mode")?.ok_or_else(|| ConfigError::Missing {
            key: "mode".into(),
            flag: "mode".into(),
            what: "up, down or slot".into(),
        })?;
        let mode: MillingMode = mode_text.parse().map_err(|e| key_err(s, e))?;
        let ae = if mode == MillingMode::Slot {
            d
        } else {
            s.require("ae_mm", Quantity::LengthMm, "radial depth of cut")?
        };
        base.radial(ae, mode, cutter)
    }
    .map_err(|e| key_err(s, e))?;
    Ok(cut)
}

/// Resolve the settings into model types, checking every value.
///
/// ```
/// use runout_io::config::{layer_from_toml, Settings, simulate::{resolve_simulate, simulate_key_names}};
/// let text = "teeth = 4\ndiameter_mm = 10\nrpm = 3240\nfz_mm = 0.08\nap_mm = 1\nae_mm = 2\nmode = \"down\"\nktc = 1889.2\nkrc = 806.1\nrunout_um = \"8um\"";
/// let mut s = Settings::new();
/// s.push(layer_from_toml("case.toml", text, &simulate_key_names()).unwrap());
/// let case = resolve_simulate(&s).unwrap();
/// assert!((case.runout.offset() - 0.008).abs() < 1e-15);
/// ```
pub fn resolve_simulate(s: &Settings) -> Result<SimulateCase, ConfigError> {
    let cutter = resolve_cutter(s)?;
    let helix = cutter.helix().to_degrees();
    let fz = s.require("fz_mm", Quantity::LengthMm, "feed per tooth")?;
    let ap = s.require("ap_mm", Quantity::LengthMm, "axial depth of cut")?;
    let cut = resolve_cut(s, &cutter, fz, ap)?;

    let rho = s.or("runout_um", Quantity::LengthUm, 0.0)? * 1e-3;
    let lam = s.or("runout_angle_deg", Quantity::AngleDeg, 0.0)?;
    let tilt = s.or("tilt_um_per_mm", Quantity::TiltUmPerMm, 0.0)? * 1e-3;
    let tilt_ang = s.or("tilt_angle_deg", Quantity::AngleDeg, 0.0)?;
    let runout = Runout::new(rho, lam.to_radians())
        .and_then(|r| r.with_tilt(tilt, tilt_ang.to_radians()))
        .and_then(|r| limits::runout_vs_radius("runout_um", rho, cutter.radius()).map(|_| r))
        .map_err(|e| key_err(s, e))?;

    for (k, q) in [
        ("ktc", Quantity::ForcePerArea),
        ("krc", Quantity::ForcePerArea),
        ("kac", Quantity::ForcePerArea),
        ("kte", Quantity::ForcePerLength),
        ("kre", Quantity::ForcePerLength),
        ("kae", Quantity::ForcePerLength),
    ] {
        if let Some(v) = s.quantity(k, q)? {
            limits::within(
                k,
                v,
                -limits::MAX_COEFFICIENT,
                limits::MAX_COEFFICIENT,
                "N/mm² (shear) or N/mm (edge)",
            )
            .map_err(|e| key_err(s, e))?;
        }
    }
    let coefficients = CuttingCoefficients::new(
        [
            s.require("ktc", Quantity::ForcePerArea, "K_tc")?,
            s.require("krc", Quantity::ForcePerArea, "K_rc")?,
            s.or("kac", Quantity::ForcePerArea, 0.0)?,
        ],
        [
            s.or("kte", Quantity::ForcePerLength, 0.0)?,
            s.or("kre", Quantity::ForcePerLength, 0.0)?,
            s.or("kae", Quantity::ForcePerLength, 0.0)?,
        ],
    )
    .map_err(|e| key_err(s, e))?;

    let revolutions = s.or("revolutions", Quantity::Dimensionless, 2.0)?;
    let step = s.or("step_deg", Quantity::AngleDeg, 0.5)?;
    let disks = s
        .count("disks")?
        .unwrap_or(if helix == 0.0 { 1 } else { 50 });
    let sampling = Sampling::new(revolutions, step, disks)
        .and_then(|sm| {
            limits::within(
                "revolutions",
                revolutions,
                limits::MIN_SIMULATED_REVOLUTIONS,
                limits::MAX_REVOLUTIONS,
                "(every tooth's peak needs a full revolution)",
            )
            .map(|_| sm)
        })
        .map_err(|e| key_err(s, e))?;
    let chip_model: ForceChipModel = s.choice("chip_model")?.unwrap_or_default();
    let case = SimulateCase {
        cutter,
        runout,
        cut,
        coefficients,
        sampling,
        chip_model,
    };
    case.check_work()?;
    Ok(case)
}

impl SimulateCase {
    /// The work and memory of this simulation against [`runout_core::limits`]: chip evaluations
    /// (samples × disks × K × K look-back teeth, × K again for the exact model) and the size of
    /// the result (samples × (4 + K) values). Checked before anything is simulated; call it again
    /// after changing `sampling`.
    pub fn check_work(&self) -> Result<(), ConfigError> {
        let k = self.cutter.teeth() as f64;
        let n = self.sampling.revolutions * std::f64::consts::TAU / self.sampling.step;
        let per = if self.chip_model == ForceChipModel::Exact {
            k * k * k
        } else {
            k * k
        };
        let evaluations = n * self.sampling.disks as f64 * per;
        let err = |e: ParamError| ConfigError::Key {
            source_name: "simulation size".into(),
            key: "teeth, disks, revolutions, step_deg".into(),
            message: format!("expected {}, got {}", e.expected, e.got),
        };
        limits::work(
            "teeth",
            "chip evaluations",
            evaluations,
            limits::MAX_EVALUATIONS,
        )
        .and_then(|_| limits::result_size("revolutions", n, 4.0 + k))
        .map_err(err)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::config::{Layer, Value};

    fn settings(pairs: &[(&str, &str)]) -> Settings {
        let mut s = Settings::new();
        s.push(Layer {
            origin: "case.toml".into(),
            values: pairs
                .iter()
                .map(|(k, v)| (k.to_string(), Value::Text(v.to_string())))
                .collect(),
        });
        s
    }

    #[test]
    fn choices_are_serde_enums_and_unknown_words_name_the_key_and_the_choices() {
        let s = settings(&[("chip_model", " exact "), ("flute_lead", "constant_helix")]);
        assert_eq!(s.choice("chip_model").unwrap(), Some(ForceChipModel::Exact));
        assert_eq!(
            s.choice("flute_lead").unwrap(),
            Some(FluteLead::ConstantHelix)
        );
        assert_eq!(s.choice::<ForceChipModel>("absent").unwrap(), None);
        let e = settings(&[("chip_model", "trochoid")])
            .choice::<ForceChipModel>("chip_model")
            .unwrap_err()
            .to_string();
        assert!(
            e.starts_with("case.toml: key `chip_model`")
                && e.contains("`trochoid`")
                && e.contains("`arc`, `exact`, `equivalent`"),
            "{e}"
        );
    }
}
