//! Configuration files (TOML) whose keys carry their unit in the name, and whose values may be
//! plain numbers or strings with a matching unit suffix (`"8um"`). Every key also exists as a
//! command-line flag; flags override the file.

pub mod chip;
pub mod identify;
pub mod shank;
pub mod simulate;

use crate::units::{parse_quantity, Quantity};
use serde::Deserialize;
use std::collections::BTreeMap;

/// A config value: a number, or a string that may carry a unit suffix.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(untagged)]
pub enum Value {
    /// A TOML number.
    Number(f64),
    /// A TOML string such as `"8um"` or `"down"`.
    Text(String),
}

/// Error in a configuration: names the key (and the file) and what was expected.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum ConfigError {
    /// The TOML itself is malformed or has an unknown key (message includes line and column).
    #[error("{file}: {message}")]
    Parse {
        /// The file.
        file: String,
        /// The TOML parser's message.
        message: String,
    },
    /// A key has a bad value (from the command line: named as its flag too, `--fz-mm`).
    #[error("{}", key_error(.source_name, .key, .message))]
    Key {
        /// File name or "command line".
        source_name: String,
        /// The key or flag.
        key: String,
        /// What is wrong.
        message: String,
    },
    /// A required key is missing everywhere.
    #[error("missing `{key}` ({what}): give it in the config file or as --{flag}")]
    Missing {
        /// The key.
        key: String,
        /// The flag.
        flag: String,
        /// What it is.
        what: String,
    },
}

/// `file: key \`fz_mm\`: …`, or `--fz-mm (key \`fz_mm\`): …` for a flag (the same key in a
/// config file).
fn key_error(source_name: &str, key: &str, message: &str) -> String {
    if source_name == "command line" {
        let flags: Vec<String> = key
            .split('/')
            .map(|k| format!("--{}", k.replace('_', "-")))
            .collect();
        format!("{} (key `{key}`): {message}", flags.join("/"))
    } else {
        format!("{source_name}: key `{key}`: {message}")
    }
}

/// One layer of key → value settings with its origin (file name or "command line").
#[derive(Debug, Clone, Default)]
pub struct Layer {
    /// Where these settings came from.
    pub origin: String,
    /// Key → value.
    pub values: BTreeMap<String, Value>,
}

/// Settings from a config file overlaid by command-line flags.
#[derive(Debug, Clone, Default)]
pub struct Settings {
    layers: Vec<Layer>,
}

impl Settings {
    /// Empty settings.
    pub fn new() -> Self {
        Settings::default()
    }

    /// Add a layer; later layers override earlier ones.
    pub fn push(&mut self, layer: Layer) {
        self.layers.push(layer);
    }

    fn lookup(&self, key: &str) -> Option<(&str, &Value)> {
        self.layers
            .iter()
            .rev()
            .find_map(|l| l.values.get(key).map(|v| (l.origin.as_str(), v)))
    }

    /// Where `key` was set (file name or "command line"), if anywhere.
    pub fn origin(&self, key: &str) -> Option<&str> {
        self.lookup(key).map(|(o, _)| o)
    }

    /// True if any layer sets `key`.
    pub fn has(&self, key: &str) -> bool {
        self.lookup(key).is_some()
    }

    /// Number of quantity `q` under `key`, or `None` when unset.
    pub fn quantity(&self, key: &str, q: Quantity) -> Result<Option<f64>, ConfigError> {
        match self.lookup(key) {
            None => Ok(None),
            Some((origin, Value::Number(v))) => {
                if v.is_finite() {
                    Ok(Some(*v))
                } else {
                    Err(ConfigError::Key {
                        source_name: origin.into(),
                        key: key.into(),
                        message: format!("{v} is not finite (expected {q})"),
                    })
                }
            }
            Some((origin, Value::Text(t))) => {
                parse_quantity(t, q)
                    .map(Some)
                    .map_err(|e| ConfigError::Key {
                        source_name: origin.into(),
                        key: key.into(),
                        message: e.to_string(),
                    })
            }
        }
    }

    /// Required quantity.
    pub fn require(&self, key: &str, q: Quantity, what: &str) -> Result<f64, ConfigError> {
        self.quantity(key, q)?.ok_or_else(|| ConfigError::Missing {
            key: key.into(),
            flag: key.replace('_', "-"),
            what: what.into(),
        })
    }

    /// Quantity with a default.
    pub fn or(&self, key: &str, q: Quantity, default: f64) -> Result<f64, ConfigError> {
        Ok(self.quantity(key, q)?.unwrap_or(default))
    }

    /// A non-negative integer (counts such as `teeth`, `disks`).
    pub fn count(&self, key: &str) -> Result<Option<usize>, ConfigError> {
        match self.quantity(key, Quantity::Dimensionless)? {
            None => Ok(None),
            Some(v) if v >= 0.0 && v.fract() == 0.0 && v < 1e9 => Ok(Some(v as usize)),
            Some(v) => {
                let origin = self
                    .lookup(key)
                    .map(|(o, _)| o.to_string())
                    .unwrap_or_default();
                Err(ConfigError::Key {
                    source_name: origin,
                    key: key.into(),
                    message: format!(
                        "{} is not a whole number >= 0",
                        runout_core::limits::show(v)
                    ),
                })
            }
        }
    }

    /// A text value (e.g. `mode`).
    pub fn text(&self, key: &str) -> Result<Option<String>, ConfigError> {
        match self.lookup(key) {
            None => Ok(None),
            Some((_, Value::Text(t))) => Ok(Some(t.clone())),
            Some((origin, Value::Number(v))) => Err(ConfigError::Key {
                source_name: origin.into(),
                key: key.into(),
                message: format!("expected a word, got the number {v}"),
            }),
        }
    }

    /// A word naming one variant of the serde enum `T` (`snake_case` names, e.g. `chip_model =
    /// "exact"`; [`word`]), or `None` when unset; an unknown word is an error naming the key and
    /// where it was set, and listing the accepted words.
    pub fn choice<T: serde::de::DeserializeOwned>(
        &self,
        key: &str,
    ) -> Result<Option<T>, ConfigError> {
        let Some(t) = self.text(key)? else {
            return Ok(None);
        };
        word(&t).map(Some).map_err(|message| ConfigError::Key {
            source_name: self.origin(key).unwrap_or("config").into(),
            key: key.into(),
            message,
        })
    }

    /// A list of quantities: a TOML array or a comma-separated string (`"90,85,95,90"`).
    pub fn list(&self, key: &str, q: Quantity) -> Result<Option<Vec<f64>>, ConfigError> {
        match self.lookup(key) {
            None => Ok(None),
            Some((origin, Value::Number(v))) => Ok(Some(vec![*v])).and_then(|l| {
                if v.is_finite() {
                    Ok(l)
                } else {
                    Err(ConfigError::Key {
                        source_name: origin.into(),
                        key: key.into(),
                        message: "not finite".into(),
                    })
                }
            }),
            Some((origin, Value::Text(t))) => t
                .split(',')
                .map(|p| {
                    parse_quantity(p, q).map_err(|e| ConfigError::Key {
                        source_name: origin.into(),
                        key: key.into(),
                        message: e.to_string(),
                    })
                })
                .collect::<Result<Vec<_>, _>>()
                .map(Some),
        }
    }
}

/// A TOML error as `line L, column C[, key `k`]: message` (the key when the error points at
/// a value, e.g. an unknown word), without the source snippet the parser's own
/// display adds (which would echo a whole long line) and with every `quoted` part of the
/// message clipped to 80 characters.
pub fn toml_error(text: &str, e: &toml::de::Error) -> String {
    let msg = clip_quoted(e.message().trim());
    match e.span().and_then(|s| text.get(..s.start)) {
        Some(before) => {
            let line = before.matches('\n').count() + 1;
            let this_line = &before[before.rfind('\n').map_or(0, |i| i + 1)..];
            let col = this_line.chars().count() + 1;
            // the key whose value is wrong (`axis = "z"`), when the error points at a value
            let key = this_line
                .split_once('=')
                .map(|(k, _)| k.trim().trim_matches('"'))
                .filter(|k| !k.is_empty() && !k.contains(char::is_whitespace));
            match key {
                Some(k) => {
                    format!("TOML parse error at line {line}, column {col}, key `{k}`: {msg}")
                }
                None => format!("TOML parse error at line {line}, column {col}: {msg}"),
            }
        }
        None => format!("TOML parse error: {msg}"),
    }
}

/// Clip each `…`-quoted part of a message to 80 characters, and the whole to 400.
pub fn clip_quoted(msg: &str) -> String {
    let clipped = msg
        .split('`')
        .enumerate()
        .map(|(i, p)| {
            if i % 2 == 1 {
                crate::textfile::quote(p)
            } else {
                p.to_string()
            }
        })
        .collect::<Vec<_>>()
        .join("`");
    match clipped.char_indices().nth(400) {
        Some((i, _)) => format!("{}…", &clipped[..i]),
        None => clipped,
    }
}

/// The key path of the first non-finite float (`nan`, `inf`) anywhere in a TOML value.
pub(crate) fn non_finite_key(v: &toml::Value, path: &str) -> Option<String> {
    match v {
        toml::Value::Float(f) if !f.is_finite() => Some(path.to_string()),
        toml::Value::Array(a) => a
            .iter()
            .enumerate()
            .find_map(|(i, x)| non_finite_key(x, &format!("{path}[{i}]"))),
        toml::Value::Table(t) => t.iter().find_map(|(k, x)| {
            let p = if path.is_empty() {
                k.clone()
            } else {
                format!("{path}.{k}")
            };
            non_finite_key(x, &p)
        }),
        _ => None,
    }
}

/// Refuse `nan` and `inf` anywhere in a parsed TOML document (every number the toolkit reads
/// is finite), naming the key.
pub fn reject_non_finite(file: &str, table: &toml::Table) -> Result<(), ConfigError> {
    for (k, v) in table {
        if let Some(key) = non_finite_key(v, k) {
            return Err(ConfigError::Key {
                source_name: file.into(),
                key,
                message: "expected a finite number, got nan or inf".into(),
            });
        }
    }
    Ok(())
}

/// Read a TOML config file's text into a [`Layer`], accepting only `known` keys.
///
/// Arrays become comma-separated text (for [`Settings::list`]). Unknown keys and malformed TOML
/// are errors naming the file, and line and column where the TOML parser gives them.
///
/// ```
/// use runout_io::config::{layer_from_toml, Value};
/// let l = layer_from_toml("a.toml", "teeth = 4\nmode = \"down\"", &["teeth", "mode"]).unwrap();
/// assert_eq!(l.values["teeth"], Value::Number(4.0));
/// let e = layer_from_toml("a.toml", "teth = 4", &["teeth"]).unwrap_err();
/// assert!(e.to_string().contains("teth"));
/// ```
pub fn layer_from_toml(file: &str, text: &str, known: &[&str]) -> Result<Layer, ConfigError> {
    let table: toml::Table = text
        .parse()
        .map_err(|e: toml::de::Error| ConfigError::Parse {
            file: file.into(),
            message: toml_error(text, &e),
        })?;
    reject_non_finite(file, &table)?;
    let mut values = BTreeMap::new();
    for (k, v) in table {
        if !known.contains(&k.as_str()) {
            let line = text
                .lines()
                .position(|l| l.trim_start().starts_with(k.as_str()))
                .map(|p| p + 1);
            let at = line.map(|l| format!(" (line {l})")).unwrap_or_default();
            return Err(ConfigError::Parse {
                file: file.into(),
                message: format!("unknown key `{k}`{at}; known keys: {}", known.join(", ")),
            });
        }
        let key_err = |message: String| ConfigError::Key {
            source_name: file.into(),
            key: k.clone(),
            message,
        };
        let value = match v {
            toml::Value::Integer(i) => Value::Number(i as f64),
            toml::Value::Float(f) => Value::Number(f),
            toml::Value::String(s) => Value::Text(s),
            toml::Value::Boolean(b) => Value::Text(b.to_string()),
            toml::Value::Array(a) => {
                let parts: Result<Vec<String>, ConfigError> = a
                    .into_iter()
                    .map(|x| match x {
                        toml::Value::Integer(i) => Ok(i.to_string()),
                        toml::Value::Float(f) => Ok(f.to_string()),
                        toml::Value::String(s) => Ok(s),
                        other => Err(key_err(format!("array element {other} is not a number"))),
                    })
                    .collect();
                Value::Text(parts?.join(","))
            }
            other => {
                return Err(key_err(format!(
                    "expected a number or a string, got {}",
                    other.type_str()
                )))
            }
        };
        values.insert(k, value);
    }
    Ok(Layer {
        origin: file.into(),
        values,
    })
}

/// One word of a closed vocabulary as the serde enum `T` (unit variants, e.g.
/// `rename_all = "snake_case"`): surrounding spaces ignored, case-insensitive. An unknown word
/// is an error listing the accepted ones (serde's `unknown variant `x`, expected one of `a`,
/// `b``, quoted parts clipped).
///
/// ```
/// use runout_io::config::{word, ProfileKind};
/// assert_eq!(word::<ProfileKind>(" Bull_Nose ").unwrap(), ProfileKind::BullNose);
/// let e = word::<ProfileKind>("round").unwrap_err();
/// assert!(e.contains("`round`") && e.contains("`flat`, `ball`, `bull_nose`, `tapered`"), "{e}");
/// ```
pub fn word<T: serde::de::DeserializeOwned>(text: &str) -> Result<T, String> {
    use serde::de::value::{Error, StrDeserializer};
    use serde::de::IntoDeserializer;
    let t = text.trim();
    let as_is: StrDeserializer<'_, Error> = t.into_deserializer();
    T::deserialize(as_is).or_else(|e| {
        let lower = t.to_ascii_lowercase();
        let d: StrDeserializer<'_, Error> = lower.as_str().into_deserializer();
        T::deserialize(d).map_err(|_| clip_quoted(&e.to_string()))
    })
}

/// The end-profile vocabulary shared by every command that describes a cutter (`simulate`,
/// `identify`, `chip`): `profile = flat | ball | bull_nose | tapered`, with `corner_radius_mm`
/// (bull nose only) and `taper_deg` (tapered only).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ProfileKind {
    /// Flat end.
    #[default]
    Flat,
    /// Ball end (radius D/2).
    Ball,
    /// Bull nose (corner radius `corner_radius_mm`).
    BullNose,
    /// Tapered (half-cone angle `taper_deg`).
    Tapered,
}

impl ProfileKind {
    /// Every profile, in the order messages list them.
    pub const ALL: [ProfileKind; 4] = [
        ProfileKind::Flat,
        ProfileKind::Ball,
        ProfileKind::BullNose,
        ProfileKind::Tapered,
    ];

    /// The word as written in a config.
    pub fn name(self) -> &'static str {
        match self {
            ProfileKind::Flat => "flat",
            ProfileKind::Ball => "ball",
            ProfileKind::BullNose => "bull_nose",
            ProfileKind::Tapered => "tapered",
        }
    }
}

/// Resolve `profile`, `corner_radius_mm` and `taper_deg` into a [`runout_core::RadiusProfile`]
/// for a cutter of `diameter_mm`. Errors are `(key, message)`: a bad combination names the
/// parameter that does not fit (a corner radius on anything but a bull nose, a taper on anything
/// but a tapered cutter, a corner radius above R, a missing corner radius or taper angle).
///
/// ```
/// use runout_io::config::radius_profile;
/// use runout_core::RadiusProfile;
/// assert_eq!(radius_profile("ball", 6.0, None, None).unwrap(), RadiusProfile::Ball);
/// let (key, msg) = radius_profile("bull_nose", 6.0, Some(4.0), None).unwrap_err();
/// assert_eq!(key, "corner_radius_mm");
/// assert!(msg.contains("R = 3"), "{msg}");
/// assert_eq!(radius_profile("ball", 6.0, None, Some(5.0)).unwrap_err().0, "taper_deg");
/// ```
pub fn radius_profile(
    name: &str,
    diameter_mm: f64,
    corner_radius_mm: Option<f64>,
    taper_deg: Option<f64>,
) -> Result<runout_core::RadiusProfile, (String, String)> {
    use runout_core::RadiusProfile;
    let r = diameter_mm / 2.0;
    let err = |k: &str, m: String| Err((k.to_string(), m));
    let kind: ProfileKind = word(name).map_err(|_| {
        let names: Vec<&str> = ProfileKind::ALL.iter().map(|k| k.name()).collect();
        (
            "profile".to_string(),
            format!(
                "expected one of {}, got `{}`",
                names.join(", "),
                clip_quoted(name.trim())
            ),
        )
    })?;
    let name = kind.name();
    if let Some(c) = corner_radius_mm {
        if kind != ProfileKind::BullNose {
            return err(
                "corner_radius_mm",
                format!(
                    "a corner radius is only for profile = bull_nose (a ball's is D/2), got {c} mm with profile = {name}"
                ),
            );
        }
    }
    if let Some(t) = taper_deg {
        if kind != ProfileKind::Tapered {
            return err(
                "taper_deg",
                format!(
                    "a taper angle is only for profile = tapered, got {t}° with profile = {name}"
                ),
            );
        }
    }
    match kind {
        ProfileKind::Flat => Ok(RadiusProfile::Flat),
        ProfileKind::Ball => Ok(RadiusProfile::Ball),
        ProfileKind::BullNose => {
            let Some(c) = corner_radius_mm else {
                return err(
                    "corner_radius_mm",
                    "profile = bull_nose needs the corner radius (mm)".into(),
                );
            };
            if !(c.is_finite() && c > 0.0 && c <= r) {
                return err(
                    "corner_radius_mm",
                    format!("expected a corner radius in (0, R = {r}] mm, got {c}"),
                );
            }
            Ok(RadiusProfile::BullNose { corner_mm: c })
        }
        ProfileKind::Tapered => {
            let Some(t) = taper_deg else {
                return err(
                    "taper_deg",
                    "profile = tapered needs the taper (half-cone) angle (deg)".into(),
                );
            };
            if !(t.is_finite() && t > 0.0 && t < 45.0) {
                return err(
                    "taper_deg",
                    format!("expected a taper (half-cone) angle in (0, 45) degrees, got {t}"),
                );
            }
            Ok(RadiusProfile::Tapered { taper_deg: t })
        }
    }
}
