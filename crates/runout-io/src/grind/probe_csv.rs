//! Probe table reader (methods.md §5.1). Columns (header, any order, case-insensitive):
//! `layer` (integer index) and/or `u_mm` (axial position from the tool tip), `angle_deg` (probe
//! angle in the bar frame), and either `x_mm, y_mm[, z_mm]` (touched point or probe-tip centre)
//! or `radius_mm` (measured radius). Lines starting with `#` are comments.

use super::csv_table::{CsvError, Table};
use runout_core::grind::{ProbePoint, Touch};

const KNOWN: [&str; 7] = [
    "layer",
    "u_mm",
    "angle_deg",
    "x_mm",
    "y_mm",
    "z_mm",
    "radius_mm",
];

/// Read probe rows; `ProbePoint::row` is the file line number, so the grid checks of
/// `runout_core::grind::ProbeGrid::assemble` name file lines.
///
/// ```
/// let text = "layer,u_mm,angle_deg,radius_mm\n0,5,0,3.004\n0,5,120,2.998\n";
/// let p = runout_io::grind::read_probe_csv(text, "probe.csv").unwrap();
/// assert_eq!(p.len(), 2);
/// assert_eq!(p[1].row, 3);
/// assert!((p[1].angle.to_degrees() - 120.0).abs() < 1e-12);
/// ```
pub fn read_probe_csv(text: &str, file: &str) -> Result<Vec<ProbePoint>, CsvError> {
    let t = Table::parse(text, file, &KNOWN)?;
    let by_radius = t.has("radius_mm");
    let by_point = t.has("x_mm") || t.has("y_mm");
    match (by_radius, by_point) {
        (true, true) => {
            return Err(t.err(
                None,
                "give either `radius_mm` or `x_mm, y_mm[, z_mm]`, not both".into(),
            ))
        }
        (false, false) => {
            return Err(t.err(
                None,
                "missing the measurement: a `radius_mm` column or `x_mm, y_mm[, z_mm]` columns"
                    .into(),
            ))
        }
        _ => {}
    }
    if by_point && !(t.has("x_mm") && t.has("y_mm")) {
        return Err(t.err(None, "`x_mm` and `y_mm` must both be given".into()));
    }
    if !t.has("angle_deg") {
        return Err(t.err(None, "missing column `angle_deg`".into()));
    }
    if !t.has("layer") && !t.has("u_mm") {
        return Err(t.err(None, "missing `layer` or `u_mm` column".into()));
    }
    if by_point && !t.has("z_mm") && !t.has("u_mm") {
        return Err(t.err(None, "points need `z_mm` or a `u_mm` column".into()));
    }
    let mut out = Vec::with_capacity(t.rows.len());
    for r in 0..t.rows.len() {
        let line = t.rows[r].0;
        let layer = match t.opt(r, "layer")? {
            None if t.has("layer") => {
                return Err(t.err(Some(line), "column `layer` is empty".into()))
            }
            None => None,
            Some(v) if v.fract() == 0.0 && v.abs() < 1e15 => Some(v as i64),
            Some(v) => {
                return Err(t.err(Some(line), format!("column `layer`: {v} is not an integer")))
            }
        };
        let u_mm = if t.has("u_mm") {
            Some(t.get(r, "u_mm")?)
        } else {
            None
        };
        let touch = if by_radius {
            Touch::Radius(t.get(r, "radius_mm")?)
        } else {
            let z = match t.opt(r, "z_mm")? {
                Some(z) => z,
                None => t.get(r, "u_mm")?,
            };
            Touch::Point([t.get(r, "x_mm")?, t.get(r, "y_mm")?, z])
        };
        out.push(ProbePoint {
            row: line,
            layer,
            u_mm,
            angle: t.get(r, "angle_deg")?.to_radians(),
            touch,
        });
    }
    Ok(out)
}
