//! One path from a case file and flags to the settings a job resolves (issue 13 item 7): an
//! optional TOML case file ([`Source`]) overlaid by the values given on the command line (or by
//! a library caller), each a text that may carry a unit suffix (`"8um"`). The jobs then resolve
//! the settings into core types through the resolvers of [`runout_io::config`].

use crate::job::Source;
use anyhow::{Context, Result};
use runout_io::config::{layer_from_toml, Layer, Settings, Value};

/// The values given as flags (`None` = not given), as a settings layer named `command line`
/// (errors then name the flag, `--fz-mm (key \`fz_mm\`)`).
pub fn flag_layer<'a>(pairs: impl IntoIterator<Item = (&'a str, &'a Option<String>)>) -> Layer {
    Layer {
        origin: "command line".into(),
        values: pairs
            .into_iter()
            .filter_map(|(k, v)| v.as_ref().map(|v| (k.to_string(), Value::Text(v.clone()))))
            .collect(),
    }
}

/// Plain `(key, value)` pairs as a settings layer named `command line`.
pub fn value_layer<'a>(pairs: impl IntoIterator<Item = (&'a str, &'a str)>) -> Layer {
    Layer {
        origin: "command line".into(),
        values: pairs
            .into_iter()
            .map(|(k, v)| (k.to_string(), Value::Text(v.to_string())))
            .collect(),
    }
}

/// Settings from an optional TOML case file (keys limited to `known`) overlaid by `flags`.
pub fn settings(config: Option<&Source>, flags: Layer, known: &[&str]) -> Result<Settings> {
    let mut s = Settings::new();
    if let Some(src) = config {
        let text = src
            .read_text()
            .with_context(|| format!("reading config {}", src.name()))?;
        s.push(layer_from_toml(src.name(), &text, known)?);
    }
    s.push(flags);
    Ok(s)
}

#[cfg(test)]
mod tests {
    use super::*;
    use runout_io::units::Quantity;

    #[test]
    fn flags_override_the_file_and_name_their_origin() {
        let cfg = Source::bytes("case.toml", &b"rpm = 3000\nfz_mm = 0.05\n"[..]);
        let fz = Some("0.08mm".to_string());
        let none = None;
        let s = settings(
            Some(&cfg),
            flag_layer([("fz_mm", &fz), ("ap_mm", &none)]),
            &["rpm", "fz_mm", "ap_mm"],
        )
        .unwrap();
        assert_eq!(s.quantity("rpm", Quantity::SpeedRpm).unwrap(), Some(3000.0));
        assert_eq!(s.quantity("fz_mm", Quantity::LengthMm).unwrap(), Some(0.08));
        assert_eq!(s.origin("fz_mm"), Some("command line"));
        assert_eq!(s.origin("rpm"), Some("case.toml"));
        assert!(!s.has("ap_mm"));
        // an unknown key in the file is named with the file
        let bad = Source::bytes("bad.toml", &b"rpmm = 3000\n"[..]);
        let e = settings(Some(&bad), value_layer([]), &["rpm"]).unwrap_err();
        assert!(format!("{e:#}").contains("bad.toml"), "{e:#}");
    }
}
