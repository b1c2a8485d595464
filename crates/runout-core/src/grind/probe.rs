//! Probe grid: the touched points Q_ij at M layers u_i × C angles α_j, reduced to radii R_ij
//! from the grinder's rotation axis (methods.md §5.1–5.2).

use super::error::GrindError;
use super::nominal::Generatrix;
use crate::angle::{wrap_pi, wrap_tau};
use crate::error::ParamError;

/// What the probe reported for one grid point.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Touch {
    /// Probe-tip centre (or touch point if the tip radius is 0) in the bar frame (x, y, z) in mm.
    Point([f64; 3]),
    /// Measured radius from the rotation axis (mm) of the tip centre (or touch point).
    Radius(f64),
}

/// One probe row, as read from a file (methods.md §5.1).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ProbePoint {
    /// 1-based row number in the source table, used in every error message.
    pub row: usize,
    /// Layer index, if the table has one.
    pub layer: Option<i64>,
    /// Axial position u (mm from the tool tip along the work-head axis), if given.
    pub u_mm: Option<f64>,
    /// Probe angle α (rad) in the bar frame, positive in the direction of spindle rotation.
    pub angle: f64,
    /// Touched point or radius.
    pub touch: Touch,
}

/// What to do with two rows at the same grid point.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum DuplicatePolicy {
    /// Refuse (default).
    #[default]
    Error,
    /// Use the mean radius (repeated touches), noted in [`ProbeGrid::notes`].
    Average,
}

/// What to do when a layer lacks an angle that other layers have.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum MissingPolicy {
    /// Refuse (default).
    #[default]
    Error,
    /// Accept: the layer is used with the angles it has (noted in [`ProbeGrid::notes`]).
    Skip,
}

/// Options for assembling a probe grid.
#[derive(Debug, Clone, PartialEq)]
pub struct ProbeOptions {
    /// Probe-tip (ball) radius r_tip (mm): Q = tip centre − r_tip·N (methods.md §5.1). 0 if the
    /// data are already compensated.
    pub tip_radius_mm: f64,
    /// A radius farther than this from the nominal R(u) is a probe miss (mm).
    pub miss_limit_mm: f64,
    /// Two angles closer than this are the same grid angle (rad).
    pub angle_tolerance: f64,
    /// Duplicate handling.
    pub duplicates: DuplicatePolicy,
    /// Missing-point handling.
    pub missing: MissingPolicy,
}

impl Default for ProbeOptions {
    fn default() -> Self {
        ProbeOptions {
            tip_radius_mm: 0.0,
            miss_limit_mm: 0.2,
            angle_tolerance: 1e-6,
            duplicates: DuplicatePolicy::Error,
            missing: MissingPolicy::Error,
        }
    }
}

/// One probed layer: its axial position and the radii at its angles (sorted, in [0, 2π)).
#[derive(Debug, Clone, PartialEq)]
pub struct Layer {
    /// Label for messages: the layer index, or `u=…`.
    pub label: String,
    /// Axial position u_i (mm).
    pub u: f64,
    /// Probe angles α_j (rad), ascending in [0, 2π).
    pub alpha: Vec<f64>,
    /// Radii R_ij (mm) from the rotation axis, eq. R_ij = √(Q_x² + Q_y²) (methods.md §5.2).
    pub radius: Vec<f64>,
    /// Source row of each point (the first row if averaged).
    pub rows: Vec<usize>,
}

/// The probe grid: layers in increasing u, each with ≥ 3 angles.
#[derive(Debug, Clone, PartialEq)]
pub struct ProbeGrid {
    /// Layers in increasing u.
    pub layers: Vec<Layer>,
    /// The nominal generatrix used for normals and the miss check.
    pub generatrix: Generatrix,
    /// Explicit notes about how irregular input was handled (averaged duplicates, skipped points).
    pub notes: Vec<String>,
}

impl ProbeGrid {
    /// Build a grid directly from radii (mm) on a regular grid: `radius[i][j]` at `u[i]`, `alpha[j]`
    /// (rad). Used by simulations; file input goes through [`ProbeGrid::assemble`].
    pub fn from_radii(
        u: &[f64],
        alpha: &[f64],
        radius: &[Vec<f64>],
        generatrix: Generatrix,
    ) -> Result<Self, GrindError> {
        let mut points = Vec::with_capacity(u.len() * alpha.len());
        for (i, ui) in u.iter().enumerate() {
            for (j, a) in alpha.iter().enumerate() {
                points.push(ProbePoint {
                    row: points.len() + 1,
                    layer: Some(i as i64),
                    u_mm: Some(*ui),
                    angle: *a,
                    touch: Touch::Radius(radius[i][j]),
                });
            }
        }
        Self::assemble(&points, generatrix, &ProbeOptions::default())
    }

    /// Assemble rows into a grid, checking everything that can be wrong with probe data: NaN,
    /// layers not contiguous or not increasing in u, fewer than 3 angles per layer, duplicate and
    /// missing grid points (by policy), and probe misses. Every error names the row or layer.
    pub fn assemble(
        points: &[ProbePoint],
        generatrix: Generatrix,
        opts: &ProbeOptions,
    ) -> Result<Self, GrindError> {
        crate::error::non_negative("probe_tip_radius_mm", opts.tip_radius_mm)?;
        crate::error::positive("miss_limit_mm", opts.miss_limit_mm)?;
        for p in points {
            check_finite(p)?;
        }
        let mut notes = Vec::new();
        let groups = group_layers(points)?;
        let mut layers = Vec::with_capacity(groups.len());
        for g in &groups {
            let layer = build_layer(g, &generatrix, opts, &mut notes)?;
            if let Some(prev) = layers.last() {
                let prev: &Layer = prev;
                if layer.u <= prev.u {
                    return Err(GrindError::LayersNotIncreasing {
                        row: g[0].row,
                        layer: layer.label.clone(),
                        u_mm: layer.u,
                        previous_u_mm: prev.u,
                    });
                }
            }
            layers.push(layer);
        }
        check_missing(&layers, opts, &mut notes)?;
        for (l, g) in layers.iter().zip(&groups) {
            if l.alpha.len() < 3 {
                return Err(GrindError::TooFewAngles {
                    layer: l.label.clone(),
                    u_mm: l.u,
                    first_row: g[0].row,
                    last_row: g[g.len() - 1].row,
                    count: l.alpha.len(),
                });
            }
        }
        if layers.len() < 2 {
            return Err(GrindError::TooFewLayers(layers.len()));
        }
        Ok(ProbeGrid {
            layers,
            generatrix,
            notes,
        })
    }

    /// Number of layers M.
    pub fn layer_count(&self) -> usize {
        self.layers.len()
    }

    /// Axial range [u_1, u_M] (mm).
    pub fn u_range(&self) -> (f64, f64) {
        (self.layers[0].u, self.layers[self.layers.len() - 1].u)
    }
}

fn check_finite(p: &ProbePoint) -> Result<(), GrindError> {
    let bad = |field: &str, value: f64| GrindError::NonFinite {
        row: p.row,
        field: field.into(),
        value,
    };
    if !p.angle.is_finite() {
        return Err(bad("angle_deg", p.angle));
    }
    if let Some(u) = p.u_mm {
        if !u.is_finite() {
            return Err(bad("u_mm", u));
        }
    }
    match p.touch {
        Touch::Point(q) => {
            for (k, name) in ["x_mm", "y_mm", "z_mm"].iter().enumerate() {
                if !q[k].is_finite() {
                    return Err(bad(name, q[k]));
                }
            }
        }
        Touch::Radius(r) => {
            if !r.is_finite() {
                return Err(bad("radius_mm", r));
            }
        }
    }
    Ok(())
}

/// Key identifying a layer: its index, or else its u value.
fn layer_key(p: &ProbePoint) -> Result<(bool, i64, u64), GrindError> {
    match (p.layer, p.u_mm) {
        (Some(i), _) => Ok((true, i, 0)),
        (None, Some(u)) => Ok((false, 0, u.to_bits())),
        (None, None) => {
            Err(
                ParamError::new(format!("row {}", p.row), "a layer index or u_mm", "neither")
                    .into(),
            )
        }
    }
}

/// Split rows into contiguous layers, refusing a layer that reappears later.
fn group_layers(points: &[ProbePoint]) -> Result<Vec<Vec<ProbePoint>>, GrindError> {
    let mut groups: Vec<Vec<ProbePoint>> = Vec::new();
    let mut seen = std::collections::HashSet::new();
    let mut current = None;
    for p in points {
        let key = layer_key(p)?;
        if current != Some(key) {
            if !seen.insert(key) {
                return Err(GrindError::LayerNotContiguous {
                    row: p.row,
                    layer: label_of(p),
                });
            }
            current = Some(key);
            groups.push(Vec::new());
        }
        groups.last_mut().expect("pushed above").push(*p);
    }
    Ok(groups)
}

fn label_of(p: &ProbePoint) -> String {
    match (p.layer, p.u_mm) {
        (Some(i), _) => i.to_string(),
        (None, Some(u)) => format!("u={u}"),
        _ => "?".into(),
    }
}

/// Axial position of a layer: the u_mm column (must agree within the layer), else the mean z.
fn layer_u(g: &[ProbePoint]) -> Result<f64, GrindError> {
    if let Some(u0) = g[0].u_mm {
        for p in g {
            match p.u_mm {
                Some(u) if (u - u0).abs() <= 1e-9 => {}
                other => {
                    return Err(ParamError::new(
                        format!("row {} u_mm", p.row),
                        format!("the layer's u = {u0} mm (row {})", g[0].row),
                        format!("{other:?}"),
                    )
                    .into())
                }
            }
        }
        return Ok(u0);
    }
    let mut sum = 0.0;
    for p in g {
        match p.touch {
            Touch::Point(q) => sum += q[2],
            Touch::Radius(_) => {
                return Err(ParamError::new(
                    format!("row {}", p.row),
                    "u_mm for a layer given by measured radius",
                    "no u_mm",
                )
                .into())
            }
        }
    }
    Ok(sum / g.len() as f64)
}

fn build_layer(
    g: &[ProbePoint],
    gen: &Generatrix,
    opts: &ProbeOptions,
    notes: &mut Vec<String>,
) -> Result<Layer, GrindError> {
    let u = layer_u(g)?;
    let label = match g[0].layer {
        Some(i) => i.to_string(),
        None => format!("u={u}"),
    };
    let nominal = gen.radius(u);
    // (alpha, radius sum, count, first row)
    let mut pts: Vec<(f64, f64, usize, usize)> = Vec::with_capacity(g.len());
    for p in g {
        let alpha = wrap_tau(p.angle);
        let r = compensated_radius(p, u, alpha, gen, opts.tip_radius_mm);
        if (r - nominal).abs() > opts.miss_limit_mm {
            return Err(GrindError::ProbeMiss {
                row: p.row,
                radius_mm: r,
                nominal_mm: nominal,
                u_mm: u,
                distance_um: (r - nominal).abs() * 1e3,
                limit_um: opts.miss_limit_mm * 1e3,
            });
        }
        match pts
            .iter_mut()
            .find(|q| wrap_pi(q.0 - alpha).abs() <= opts.angle_tolerance)
        {
            Some(q) => match opts.duplicates {
                DuplicatePolicy::Error => {
                    return Err(GrindError::Duplicate {
                        row: p.row,
                        first_row: q.3,
                        layer: label.clone(),
                        angle_deg: alpha.to_degrees(),
                    })
                }
                DuplicatePolicy::Average => {
                    notes.push(format!(
                        "row {}: repeated point at layer {label}, angle {:.4}° averaged with row {}",
                        p.row,
                        alpha.to_degrees(),
                        q.3
                    ));
                    q.1 += r;
                    q.2 += 1;
                }
            },
            None => pts.push((alpha, r, 1, p.row)),
        }
    }
    pts.sort_by(|a, b| a.0.total_cmp(&b.0));
    Ok(Layer {
        label,
        u,
        alpha: pts.iter().map(|q| q.0).collect(),
        radius: pts.iter().map(|q| q.1 / q.2 as f64).collect(),
        rows: pts.iter().map(|q| q.3).collect(),
    })
}

/// R_ij of the probe-tip-compensated touch point Q = C − r_tip·N(u, α) (methods.md §5.1–5.2).
fn compensated_radius(p: &ProbePoint, u: f64, alpha: f64, gen: &Generatrix, tip: f64) -> f64 {
    let c = match p.touch {
        Touch::Point(q) => q,
        Touch::Radius(r) => [r * alpha.cos(), r * alpha.sin(), u],
    };
    if tip == 0.0 {
        return c[0].hypot(c[1]);
    }
    let n = gen.normal(u, alpha);
    (c[0] - tip * n[0]).hypot(c[1] - tip * n[1])
}

/// Every layer must have every grid angle that any layer has (unless the policy is `Skip`).
fn check_missing(
    layers: &[Layer],
    opts: &ProbeOptions,
    notes: &mut Vec<String>,
) -> Result<(), GrindError> {
    let mut all: Vec<f64> = Vec::new();
    for l in layers {
        for a in &l.alpha {
            if !all
                .iter()
                .any(|b| wrap_pi(b - a).abs() <= opts.angle_tolerance)
            {
                all.push(*a);
            }
        }
    }
    all.sort_by(|a, b| a.total_cmp(b));
    for l in layers {
        for a in &all {
            let present = l
                .alpha
                .iter()
                .any(|b| wrap_pi(b - a).abs() <= opts.angle_tolerance);
            if present {
                continue;
            }
            match opts.missing {
                MissingPolicy::Error => {
                    return Err(GrindError::Missing {
                        layer: l.label.clone(),
                        u_mm: l.u,
                        angle_deg: a.to_degrees(),
                    })
                }
                MissingPolicy::Skip => notes.push(format!(
                    "layer {} (u = {} mm): no point at angle {:.4}°, layer used with its {} angles",
                    l.label,
                    l.u,
                    a.to_degrees(),
                    l.alpha.len()
                )),
            }
        }
    }
    Ok(())
}
