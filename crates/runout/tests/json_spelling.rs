//! Issue 21 items 4 and 6: one spelling in every JSON output and schema.
//!
//! * Standard errors are `<name>_se`, the unit kept in the name before `_se`
//!   (`offset_um_se`, `kac_N_per_mm2_se`, `rpm_se`): no `offset_se_um`, no bare `se`.
//! * Enum values are snake_case or words, never Rust's Debug spelling (`PhaseTracking`,
//!   `GenericCsv`, `FirstHarmonic`, `Joint`), neither as values nor as keys.
//!
//! Scanned: every CLI snapshot (`crates/runout-cli/tests/cli/snapshots`, the JSON the CLI writes)
//! and every published schema (`docs/schema`).

use serde_json::Value;
use std::path::PathBuf;

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../..")
}

/// The JSON body of an insta snapshot file.
fn snapshot_body(text: &str) -> &str {
    let rest = text.strip_prefix("---").expect("snapshot header");
    let end = rest.find("\n---\n").expect("end of header");
    &rest[end + 5..]
}

/// Every JSON document to scan: (name, value, is a schema).
fn documents() -> Vec<(String, Value, bool)> {
    let mut out = Vec::new();
    let snaps = root().join("crates/runout-cli/tests/cli/snapshots");
    for e in std::fs::read_dir(&snaps).unwrap() {
        let p = e.unwrap().path();
        let text = std::fs::read_to_string(&p).unwrap();
        let v: Value = serde_json::from_str(snapshot_body(&text))
            .unwrap_or_else(|e| panic!("{}: {e}", p.display()));
        out.push((p.display().to_string(), v, false));
    }
    for e in std::fs::read_dir(root().join("docs/schema")).unwrap() {
        let p = e.unwrap().path();
        let v: Value = serde_json::from_str(&std::fs::read_to_string(&p).unwrap()).unwrap();
        out.push((p.display().to_string(), v, true));
    }
    assert!(out.len() >= 30, "{} documents", out.len());
    out
}

/// Every (path, key) of objects and (path, key of the string's parent, string) of values.
fn walk(
    v: &Value,
    path: &str,
    key: &str,
    keys: &mut Vec<(String, String)>,
    strings: &mut Vec<(String, String, String)>,
) {
    match v {
        Value::Object(m) => {
            for (k, x) in m {
                keys.push((path.to_string(), k.clone()));
                walk(x, &format!("{path}/{k}"), k, keys, strings);
            }
        }
        Value::Array(a) => {
            for (i, x) in a.iter().enumerate() {
                walk(x, &format!("{path}/{i}"), key, keys, strings);
            }
        }
        Value::String(s) => strings.push((path.to_string(), key.to_string(), s.clone())),
        _ => {}
    }
}

/// A key that spells a standard error another way than `<name>_se`: a `se` word that is not
/// the last, or `se` alone.
fn bad_se_key(key: &str) -> bool {
    let words: Vec<&str> = key.split('_').collect();
    key == "se" || words[..words.len() - 1].contains(&"se")
}

/// Rust's Debug spelling of an enum value: PascalCase with two or more humps
/// (`PhaseTracking`), or one of the single-word variant names of the reports' enums.
fn debug_spelling(s: &str) -> bool {
    const SINGLE: &[&str] = &[
        "Joint",
        "Scan",
        "Clamp",
        "Extrapolate",
        "Error",
        "Skip",
        "Average",
        "Bilinear",
        "Fxy",
        "Arrays",
        "Hdf5",
        "Parquet",
        "Mat",
        "Tdms",
        "Pulse",
        "Spectrum",
        "Ols",
        "Up",
        "Down",
        "Slot",
        "Arc",
        "Exact",
        "Equivalent",
        "Flat",
        "Ball",
        "Distance",
        "Radial",
        "Ccw",
        "Cw",
        "Index",
        "Xyz",
        "Feed",
    ];
    if SINGLE.contains(&s) {
        return true;
    }
    let ascii = !s.is_empty() && s.chars().all(|c| c.is_ascii_alphanumeric());
    let first_upper = s.chars().next().is_some_and(|c| c.is_ascii_uppercase());
    let uppers = s.chars().filter(char::is_ascii_uppercase).count();
    let lowers = s.chars().filter(char::is_ascii_lowercase).count();
    ascii && first_upper && uppers >= 2 && lowers >= 2
}

#[test]
fn the_checkers_find_what_they_look_for() {
    for bad in [
        "offset_se_um",
        "angle_se_deg",
        "se",
        "stiffness_se_N_per_um",
        "tir_se_um",
    ] {
        assert!(bad_se_key(bad), "{bad}");
    }
    for good in [
        "offset_um_se",
        "rpm_se",
        "kac_N_per_mm2_se",
        "value_se",
        "section_s",
        "seed",
    ] {
        assert!(!bad_se_key(good), "{good}");
    }
    for bad in [
        "PhaseTracking",
        "GenericCsv",
        "FirstHarmonic",
        "DynoWare",
        "Joint",
        "Fxy",
    ] {
        assert!(debug_spelling(bad), "{bad}");
    }
    for good in [
        "phase_tracking",
        "joint",
        "OLS",
        "Fx",
        "TIR",
        "first-harmonic",
        "Force",
    ] {
        assert!(!debug_spelling(good), "{good}");
    }
}

#[test]
fn standard_errors_are_spelled_name_se_everywhere() {
    let mut bad = Vec::new();
    for (name, v, _) in documents() {
        let (mut keys, mut strings) = (Vec::new(), Vec::new());
        walk(&v, "", "", &mut keys, &mut strings);
        for (path, k) in keys {
            if bad_se_key(&k) {
                bad.push(format!("{name}: {path}/{k}"));
            }
        }
    }
    assert!(bad.is_empty(), "SE keys not spelled `<name>_se`: {bad:#?}");
}

#[test]
fn json_has_no_debug_spellings_of_enums() {
    // values read from the data (channel and group names) are the user's words, not ours
    const DATA: &[&str] = &[
        "name", "short", "group", "channel", "channels", "file", "unit",
    ];
    let mut bad = Vec::new();
    for (name, v, schema) in documents() {
        if schema {
            continue; // a schema's keys and titles are Rust type names by design
        }
        let (mut keys, mut strings) = (Vec::new(), Vec::new());
        walk(&v, "", "", &mut keys, &mut strings);
        for (path, k) in keys {
            if k.chars().next().is_some_and(|c| c.is_ascii_uppercase()) {
                bad.push(format!("{name}: key {path}/{k}"));
            }
        }
        for (path, key, s) in strings {
            if !DATA.contains(&key.as_str()) && debug_spelling(&s) {
                bad.push(format!("{name}: {path} = {s:?}"));
            }
        }
    }
    assert!(bad.is_empty(), "Debug spellings in the JSON: {bad:#?}");
}
