//! Edge / wheel-path point reader. Columns: `x_mm, y_mm, z_mm` (edge point F_k in the bar frame,
//! required), optional `nx, ny, nz` (offset direction N_k, unitless, normalised on use) and
//! optional `wx_mm, wy_mm, wz_mm` (wheel position w_k to be offset; else the edge point is).

use super::csv_table::{CsvError, Table};

const KNOWN: [&str; 9] = [
    "x_mm", "y_mm", "z_mm", "nx", "ny", "nz", "wx_mm", "wy_mm", "wz_mm",
];

/// Points read from an edge CSV.
#[derive(Debug, Clone, PartialEq)]
pub struct EdgeTable {
    /// Edge points (mm).
    pub points: Vec<[f64; 3]>,
    /// Offset directions, if given.
    pub normals: Option<Vec<[f64; 3]>>,
    /// Wheel positions (mm), if given.
    pub wheel: Option<Vec<[f64; 3]>>,
    /// File line of each point.
    pub lines: Vec<usize>,
}

fn triple(t: &Table, r: usize, names: [&str; 3]) -> Result<[f64; 3], CsvError> {
    let mut v = [0.0; 3];
    for (k, n) in names.iter().enumerate() {
        v[k] = t.get(r, n)?;
        if !v[k].is_finite() {
            return Err(t.err(
                Some(t.rows[r].0),
                format!("column `{}` is not finite", crate::textfile::quote(n)),
            ));
        }
    }
    Ok(v)
}

/// Read an edge CSV.
///
/// ```
/// let e = runout_io::grind::read_edge_csv("x_mm,y_mm,z_mm\n3,0,1\n0,3,2\n", "e.csv").unwrap();
/// assert_eq!(e.points[1], [0.0, 3.0, 2.0]);
/// assert!(e.normals.is_none() && e.wheel.is_none());
/// ```
pub fn read_edge_csv(text: &str, file: &str) -> Result<EdgeTable, CsvError> {
    let t = Table::parse(text, file, &KNOWN)?;
    let group = |names: [&str; 3]| -> Result<bool, CsvError> {
        let n = names.iter().filter(|c| t.has(c)).count();
        match n {
            0 => Ok(false),
            3 => Ok(true),
            _ => Err(t.err(
                None,
                format!("columns {} must be given together", names.join(", ")),
            )),
        }
    };
    if !group(["x_mm", "y_mm", "z_mm"])? {
        return Err(t.err(None, "missing columns x_mm, y_mm, z_mm".into()));
    }
    let has_n = group(["nx", "ny", "nz"])?;
    let has_w = group(["wx_mm", "wy_mm", "wz_mm"])?;
    let mut e = EdgeTable {
        points: Vec::new(),
        normals: has_n.then(Vec::new),
        wheel: has_w.then(Vec::new),
        lines: Vec::new(),
    };
    for r in 0..t.rows.len() {
        e.points.push(triple(&t, r, ["x_mm", "y_mm", "z_mm"])?);
        if let Some(n) = e.normals.as_mut() {
            n.push(triple(&t, r, ["nx", "ny", "nz"])?);
        }
        if let Some(w) = e.wheel.as_mut() {
            w.push(triple(&t, r, ["wx_mm", "wy_mm", "wz_mm"])?);
        }
        e.lines.push(t.rows[r].0);
    }
    Ok(e)
}
