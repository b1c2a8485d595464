//! Exact IUCT, methods.md eq. (2.2)–(2.3): the previous teeth's trochoidal edge trajectories
//! intersected with the current radial ray, by Newton's method with the analytic Jacobian.
//!
//! h_i(z,t) = max(0, R_i(z) − max_{m=1..K} s_m), where s_m solves
//! E_{i−m}(z′, t + τ) − A(z,t) − s·n = 0 for x = (τ, z′, s) (τ = t′ − t), n = (E_i − A)/|E_i − A|.
//! Jacobian J = [∂E/∂t, ∂E/∂z, −n] (see [`EdgeState`]); the 3×3 step is solved by Cramer's rule
//! (no allocation). Start: τ₀ = −gap/ω + (δ_i − δ_{i−m})/ω (previous effective edge aligned with
//! the ray, methods.md (0.2)), z′ = z, s = R_{i−m}(z). Converged when the step is below
//! `tol_mm` in every component (τ scaled by the edge speed ω·R).

use super::kinematics::{EdgeState, SpindlePoint, ToolKinematics, ToolMotion, Vec3};
use crate::angle::wrap_pi;

/// Newton settings: convergence tolerance (mm) and iteration cap per previous tooth.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct NewtonOptions {
    /// |Δx|∞ tolerance (mm; the time step is scaled by ω·R), default 1e-12.
    pub tol_mm: f64,
    /// Maximum iterations per previous tooth, default 30.
    pub max_iter: u32,
}

impl Default for NewtonOptions {
    fn default() -> Self {
        NewtonOptions {
            tol_mm: 1e-12,
            max_iter: 30,
        }
    }
}

/// Exact IUCT at one point.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ExactIuct {
    /// R_i − max_m s_m (mm): negative when the tooth does not cut (eq. 2.2 before max(0, ·)).
    pub raw: f64,
    /// Effective radius R_i(z) of the current tooth (mm).
    pub radius: f64,
    /// The m (1..=K) whose previous pass left the surface (largest s_m).
    pub cutting_m: usize,
    /// Newton iterations summed over m.
    pub iterations: u32,
    /// True when every Newton solve met the tolerance.
    pub converged: bool,
}

impl ExactIuct {
    /// h = max(0, raw) (mm), eq. (2.2).
    pub fn h(&self) -> f64 {
        self.raw.max(0.0)
    }
}

/// Crossing of one previous tooth's trajectory with the ray.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RayCrossing {
    /// τ = t′ − t (s).
    pub tau: f64,
    /// Height z′ of the crossing edge point (mm).
    pub z: f64,
    /// Ray parameter s (mm from the axis point).
    pub s: f64,
    /// Iterations used.
    pub iterations: u32,
    /// Tolerance met.
    pub converged: bool,
}

/// Solve J·x = b for J = [c0 c1 c2] (columns) by Cramer's rule.
#[inline]
fn solve3(c0: &Vec3, c1: &Vec3, c2: &Vec3, b: &Vec3) -> Vec3 {
    let c12 = c1.cross(c2);
    let det = c0.dot(&c12);
    Vec3::new(
        b.dot(&c12) / det,
        c0.dot(&b.cross(c2)) / det,
        c0.dot(&c1.cross(b)) / det,
    )
}

/// The current tooth's ray: axis point A, unit direction n, effective radius R_i.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Ray {
    /// A(z,t) (mm).
    pub origin: Vec3,
    /// n (unit).
    pub dir: Vec3,
    /// R_i(z) = |E_i − A| (mm).
    pub radius: f64,
    /// Spindle-frame angle ψ_i + δ_i of the effective edge (rad).
    pub phase: f64,
}

impl Ray {
    /// Ray of `tooth` at height `z`, time `t`.
    pub fn new<M: ToolMotion>(kin: &ToolKinematics<M>, tooth: usize, z: f64, t: f64) -> Self {
        let sp = kin.spindle_point(tooth, z);
        let st = kin.edge_at(&sp, z, t, 0.0);
        Self::from_edge(&st, &sp)
    }

    /// Ray from an evaluated edge state.
    #[inline]
    pub fn from_edge(st: &EdgeState, sp: &SpindlePoint) -> Self {
        let r = st.pos - st.axis_point;
        let radius = r.norm();
        Ray {
            origin: st.axis_point,
            dir: r / radius,
            radius,
            phase: sp.angle(),
        }
    }
}

/// Start value of τ for previous tooth `prev` passing `m` gaps before `tooth`: the previous
/// effective edge aligned with the current one (methods.md §2.4 refinement).
#[inline]
pub fn aligned_tau<M: ToolMotion>(
    kin: &ToolKinematics<M>,
    tooth: usize,
    m: usize,
    ray_phase: f64,
    prev_phase: f64,
) -> f64 {
    let gap = kin.gap_time(tooth, m);
    -gap + wrap_pi(ray_phase - prev_phase + gap * kin.omega()) / kin.omega()
}

/// Newton solve of eq. (2.3) for the previous tooth `prev` (m gaps before `tooth`).
pub fn ray_crossing<M: ToolMotion>(
    kin: &ToolKinematics<M>,
    ray: &Ray,
    tooth: usize,
    m: usize,
    z: f64,
    t: f64,
    opts: &NewtonOptions,
) -> RayCrossing {
    let k = kin.cutter().teeth();
    let prev = (tooth + k * m - m) % k;
    let sp0 = kin.spindle_point(prev, z);
    let mut x = [aligned_tau(kin, tooth, m, ray.phase, sp0.angle()), z, sp0.radius()];
    let speed = kin.omega() * ray.radius;
    let mut iterations = 0;
    let mut converged = false;
    while iterations < opts.max_iter {
        iterations += 1;
        let sp = if x[1] == z {
            sp0
        } else {
            kin.spindle_point(prev, x[1])
        };
        let st = kin.edge_at(&sp, x[1], t, x[0]);
        let f = st.pos - ray.origin - ray.dir * x[2];
        let dx = solve3(&st.d_dt, &st.d_dz, &(-ray.dir), &(-f));
        x[0] += dx[0];
        x[1] += dx[1];
        x[2] += dx[2];
        if (dx[0] * speed).abs() < opts.tol_mm
            && dx[1].abs() < opts.tol_mm
            && dx[2].abs() < opts.tol_mm
        {
            converged = true;
            break;
        }
    }
    RayCrossing {
        tau: x[0],
        z: x[1],
        s: x[2],
        iterations,
        converged,
    }
}

/// Exact IUCT of `tooth` at height `z` and time `t`, eq. (2.2): min over the K previous passes.
///
/// ```
/// use runout_core::chip::*;
/// use runout_core::{Cutter, Runout};
/// // methods.md §7: App. A.3 defaults, edge 0, z = 5, t = T + (5/48)T → 92.987 µm
/// let cutter = Cutter::flat(10.0, 4, 30.0).unwrap();
/// let runout = Runout::new(0.010, 40f64.to_radians()).unwrap();
/// let motion = StraightFeed { p0: Vec3::zeros(), v: Vec3::new(40.0, 0.0, 0.0), u: Vec3::z(), e1: Vec3::x() };
/// let kin = ToolKinematics::new(&cutter, &runout, 6000.0, 0.0, SpindleSense::CounterClockwise, motion).unwrap();
/// let t = 0.01 * (1.0 + 5.0 / 48.0);
/// let h = exact_iuct(&kin, 0, 5.0, t, &NewtonOptions::default()).h();
/// assert!((h * 1e3 - 92.987).abs() < 5e-4);
/// ```
pub fn exact_iuct<M: ToolMotion>(
    kin: &ToolKinematics<M>,
    tooth: usize,
    z: f64,
    t: f64,
    opts: &NewtonOptions,
) -> ExactIuct {
    let ray = Ray::new(kin, tooth, z, t);
    exact_on_ray(kin, &ray, tooth, z, t, opts)
}

/// Exact IUCT for an already computed ray.
#[inline]
pub fn exact_on_ray<M: ToolMotion>(
    kin: &ToolKinematics<M>,
    ray: &Ray,
    tooth: usize,
    z: f64,
    t: f64,
    opts: &NewtonOptions,
) -> ExactIuct {
    let mut best = f64::NEG_INFINITY;
    let mut cutting_m = 1;
    let mut iterations = 0;
    let mut converged = true;
    for m in 1..=kin.cutter().teeth() {
        let c = ray_crossing(kin, ray, tooth, m, z, t, opts);
        iterations += c.iterations;
        converged &= c.converged;
        if c.s > best {
            best = c.s;
            cutting_m = m;
        }
    }
    ExactIuct {
        raw: ray.radius - best,
        radius: ray.radius,
        cutting_m,
        iterations,
        converged,
    }
}
