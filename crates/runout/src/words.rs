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
