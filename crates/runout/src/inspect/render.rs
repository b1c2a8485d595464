//! `inspect` as a table.

use super::InspectReport;
use std::fmt::Write as _;

/// One row per entry, then the file's metadata as `# name: value`.
pub fn text(r: &InspectReport) -> String {
    let mut s = String::new();
    let _ = writeln!(s, "{}: {:?}", r.file, r.format);
    let _ = writeln!(
        s,
        "{:<32} {:>10} {:<22} {:<8} {:>12} {:>10}  note",
        "name", "samples", "type", "unit", "rate_Hz", "start_s"
    );
    let opt = |v: Option<f64>| v.map_or("-".to_string(), |x| format!("{x}"));
    for e in &r.entries {
        let _ = writeln!(
            s,
            "{:<32} {:>10} {:<22} {:<8} {:>12} {:>10}  {}",
            e.name,
            e.len,
            e.dtype,
            e.unit.as_deref().unwrap_or("-"),
            opt(e.sample_rate_hz),
            opt(e.start_time_s),
            match (e.scalar, &e.note) {
                (Some(v), _) => format!("value {v}"),
                (None, Some(n)) => n.clone(),
                _ => String::new(),
            }
        );
    }
    for (k, v) in &r.metadata {
        let _ = writeln!(s, "# {k}: {v}");
    }
    s
}
