//! Closed-form IUCT models on the full kinematics: the arc models (methods.md eq. 2.5, 2.6) and
//! the equivalent-thickness model with parameterised compensation (eq. 2.8).
//!
//! With d_m = [A(z,t) − A(z, t′_m)]_⊥u the axis-point displacement since the pass of tooth i−m
//! (eq. 2.4), n the current ray, t̂ = σ·u × n the direction of rotation and
//! a = Ȧ/ω the axis-point velocity per radian:
//!
//! * linear arc (2.5):          h = min_m [ d_m·n + R_i − R_{i−m} ]
//! * circle intersection (2.6): h = min_m [ R_i + d_m·n − sqrt(R_{i−m}² − (d_m·t̂)²) ]
//! * equivalent (2.8):          h = min_m [ d_m·n + ΔR_m + k₁(d_m·t̂)²/(2R_{i−m}) − k₂(d_m·t̂)(a·n)/R_{i−m} ]
//!
//! t′_m = t − gap_m/ω, or with the phase refinement of §2.4 t′_m = t − gap_m/ω + (δ_i − δ_{i−m})/ω
//! (the previous *effective* edge aligned with the current ray, eq. 0.2). All results are the raw
//! minima (negative = no chip); apply max(0, ·).

use super::exact::Ray;
use super::kinematics::{HeightGeometry, ToolKinematics, ToolMotion};

/// Compensation parameters of the equivalent model, eq. (2.8).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct EquivalentParams {
    /// k₁ (circle term), analytically 1.
    pub k1: f64,
    /// k₂ (trochoid term), analytically 1.
    pub k2: f64,
    /// Evaluate d_m at the effective-edge phase (methods.md §2.4 refinement).
    pub phase_refinement: bool,
}

impl Default for EquivalentParams {
    /// k₁ = k₂ = 1 with phase refinement.
    fn default() -> Self {
        EquivalentParams {
            k1: 1.0,
            k2: 1.0,
            phase_refinement: true,
        }
    }
}

impl EquivalentParams {
    /// k₁ = k₂ = 1 without refinement: the model of methods.md App. A.3 (`eq_thickness`).
    pub fn analytic_unrefined() -> Self {
        EquivalentParams {
            k1: 1.0,
            k2: 1.0,
            phase_refinement: false,
        }
    }
}

/// Projections of one previous pass m used by all closed forms.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PassTerms {
    /// ΔR_m + d_m·n (mm): the linear-arc value for this m.
    pub linear: f64,
    /// R_i − R_{i−m} (mm).
    pub delta_r: f64,
    /// d_m·n (mm).
    pub dn: f64,
    /// d_m·t̂ (mm).
    pub dt: f64,
    /// a·n (mm/rad).
    pub an: f64,
    /// R_{i−m} (mm).
    pub r_prev: f64,
}

impl PassTerms {
    /// Circle term (d·t̂)²/(2R_{i−m}) (mm), the k₁ regressor.
    #[inline]
    pub fn circle_term(&self) -> f64 {
        self.dt * self.dt / (2.0 * self.r_prev)
    }
    /// Trochoid term −(d·t̂)(a·n)/R_{i−m} (mm), the k₂ regressor.
    #[inline]
    pub fn trochoid_term(&self) -> f64 {
        -self.dt * self.an / self.r_prev
    }
    /// Equivalent-model value for this m, eq. (2.8).
    #[inline]
    pub fn equivalent(&self, k1: f64, k2: f64) -> f64 {
        self.linear + k1 * self.circle_term() + k2 * self.trochoid_term()
    }
    /// Circle-intersection value for this m, eq. (2.6).
    #[inline]
    pub fn circle(&self) -> f64 {
        let q = (self.r_prev * self.r_prev - self.dt * self.dt).max(0.0);
        self.delta_r + self.r_prev + self.dn - q.sqrt()
    }
}

/// The closed-form IUCTs at one point (raw minima over m, mm).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ClosedForms {
    /// Linear arc model, eq. (2.5).
    pub arc: f64,
    /// Circle-intersection model, eq. (2.6).
    pub circle: f64,
    /// Equivalent model, eq. (2.8).
    pub equivalent: f64,
}

/// Terms of pass m for `tooth` at time `t` on the prepared height `geo` (eq. 2.4 displacement).
#[inline]
pub fn pass_terms<M: ToolMotion>(
    kin: &ToolKinematics<M>,
    geo: &HeightGeometry,
    ray: &Ray,
    tooth: usize,
    m: usize,
    t: f64,
    refine: bool,
) -> PassTerms {
    let idx = geo.pass_index(tooth, m);
    let tau = if refine {
        geo.tau_aligned[idx]
    } else {
        geo.tau_nominal[idx]
    };
    let d = ray.displacement(kin, geo.z, t, tau);
    let r_prev = geo.radius[geo.previous(tooth, m)];
    let delta_r = ray.radius - r_prev;
    let dn = d.dot(&ray.dir);
    PassTerms {
        linear: delta_r + dn,
        delta_r,
        dn,
        dt: d.dot(&ray.tangent),
        an: ray.axis_rate.dot(&ray.dir),
        r_prev,
    }
}

/// Arc, circle-intersection and equivalent IUCT of `tooth` at height `z`, time `t`
/// (slow path: prepares the height each call).
pub fn closed_forms<M: ToolMotion>(
    kin: &ToolKinematics<M>,
    tooth: usize,
    z: f64,
    t: f64,
    params: &EquivalentParams,
) -> ClosedForms {
    closed_forms_at(kin, &kin.at_height(z), tooth, t, params)
}

/// Arc, circle-intersection and equivalent IUCT on a prepared height.
pub fn closed_forms_at<M: ToolMotion>(
    kin: &ToolKinematics<M>,
    geo: &HeightGeometry,
    tooth: usize,
    t: f64,
    params: &EquivalentParams,
) -> ClosedForms {
    let ray = Ray::at(kin, geo, tooth, t);
    let mut out = ClosedForms {
        arc: f64::INFINITY,
        circle: f64::INFINITY,
        equivalent: f64::INFINITY,
    };
    for m in 1..=geo.teeth() {
        let base = pass_terms(kin, geo, &ray, tooth, m, t, false);
        out.arc = out.arc.min(base.linear);
        out.circle = out.circle.min(base.circle());
        let eq = if params.phase_refinement {
            pass_terms(kin, geo, &ray, tooth, m, t, true)
        } else {
            base
        };
        out.equivalent = out.equivalent.min(eq.equivalent(params.k1, params.k2));
    }
    out
}

/// Equivalent IUCT only (raw, mm), eq. (2.8) (slow path: prepares the height each call).
pub fn equivalent_iuct<M: ToolMotion>(
    kin: &ToolKinematics<M>,
    tooth: usize,
    z: f64,
    t: f64,
    params: &EquivalentParams,
) -> f64 {
    equivalent_at(kin, &kin.at_height(z), tooth, t, params)
}

/// Equivalent IUCT (raw, mm) on a prepared height, eq. (2.8): no iteration, no branches
/// besides the min.
#[inline]
pub fn equivalent_at<M: ToolMotion>(
    kin: &ToolKinematics<M>,
    geo: &HeightGeometry,
    tooth: usize,
    t: f64,
    params: &EquivalentParams,
) -> f64 {
    let ray = Ray::at(kin, geo, tooth, t);
    let mut h = f64::INFINITY;
    for m in 1..=geo.teeth() {
        let p = pass_terms(kin, geo, &ray, tooth, m, t, params.phase_refinement);
        h = h.min(p.equivalent(params.k1, params.k2));
    }
    h
}

/// Linear arc IUCT only (raw, mm), eq. (2.5) (slow path).
pub fn arc_iuct<M: ToolMotion>(kin: &ToolKinematics<M>, tooth: usize, z: f64, t: f64) -> f64 {
    arc_at(kin, &kin.at_height(z), tooth, t)
}

/// Linear arc IUCT (raw, mm) on a prepared height, eq. (2.5).
#[inline]
pub fn arc_at<M: ToolMotion>(
    kin: &ToolKinematics<M>,
    geo: &HeightGeometry,
    tooth: usize,
    t: f64,
) -> f64 {
    let ray = Ray::at(kin, geo, tooth, t);
    let mut h = f64::INFINITY;
    for m in 1..=geo.teeth() {
        h = h.min(pass_terms(kin, geo, &ray, tooth, m, t, false).linear);
    }
    h
}
