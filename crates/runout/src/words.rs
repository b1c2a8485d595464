//! Names of options and enum values in the user's words (issue 21 item 4): `ConstantLead` →
//! `constant lead`, `Ols` → `OLS`, instead of Rust's Debug spelling in text reports and messages.

/// The Debug name of a field-less enum value in plain lower-case words; well-known acronyms
/// (OLS, FRF) in capitals.
///
/// ```
/// # #[derive(Debug)] enum Method { Joint, ConstantLead, Ols }
/// assert_eq!(runout::words::plain(&Method::Joint), "joint");
/// assert_eq!(runout::words::plain(&Method::ConstantLead), "constant lead");
/// assert_eq!(runout::words::plain(&Method::Ols), "OLS");
/// ```
pub fn plain<T: std::fmt::Debug>(value: &T) -> String {
    let debug = format!("{value:?}");
    let mut out = String::new();
    for (i, c) in debug.chars().enumerate() {
        if c.is_uppercase() && i > 0 {
            out.push(' ');
        }
        out.extend(c.to_lowercase());
    }
    out.split(' ')
        .map(|w| match w {
            "ols" | "frf" | "tir" => w.to_uppercase(),
            _ => w.to_string(),
        })
        .collect::<Vec<_>>()
        .join(" ")
}

/// The Debug name of a field-less enum value in snake_case, for JSON values (issue 21 item 4):
/// `PhaseTracking` → `phase_tracking`, `Fxy` → `fxy`, `GenericCsv` → `generic_csv`. For an enum
/// with fields (`DynoWare { version }`) only the variant's name is used.
///
/// ```
/// # #[derive(Debug)] enum Method { PhaseTracking, Fxy, GenericCsv }
/// assert_eq!(runout::words::snake(&Method::PhaseTracking), "phase_tracking");
/// assert_eq!(runout::words::snake(&Method::Fxy), "fxy");
/// assert_eq!(runout::words::snake(&Method::GenericCsv), "generic_csv");
/// ```
pub fn snake<T: std::fmt::Debug>(value: &T) -> String {
    let debug = format!("{value:?}");
    let name = debug
        .split(|c: char| !c.is_alphanumeric())
        .next()
        .unwrap_or_default();
    let mut out = String::new();
    for (i, c) in name.chars().enumerate() {
        if c.is_uppercase() && i > 0 {
            out.push('_');
        }
        out.extend(c.to_lowercase());
    }
    out
}

/// The serialised (serde) name of an enum value: the string, or the one key of an enum with
/// fields (`{"dynoware": {…}}` → `dynoware`).
pub fn serde_name<T: serde::Serialize>(value: &T) -> String {
    match serde_json::to_value(value) {
        Ok(serde_json::Value::String(s)) => s,
        Ok(serde_json::Value::Object(m)) if m.len() == 1 => {
            m.keys().next().cloned().unwrap_or_default()
        }
        Ok(v) => v.to_string(),
        Err(_) => String::new(),
    }
}
