//! Exact IUCT, methods.md eq. (2.2)–(2.3): the previous teeth's trochoidal edge trajectories
//! intersected with the current radial ray, by Newton's method with the analytic Jacobian.
//!
//! h_i(z,t) = max(0, R_i(z) − max_{m=1..K} s_m), where s_m solves
//! E_{i−m}(z′, t + τ) − A(z,t) − s·n = 0 for x = (τ, z′, s) (τ = t′ − t), n = (E_i − A)/|E_i − A|.
//! Jacobian J = [∂E/∂t, ∂E/∂z, −n] (see [`super::EdgeState`]); the 3×3 step is solved by Cramer's rule
//! (no allocation). Start: the previous effective edge aligned with the ray,
//! τ₀ = −gap/ω + (δ_i − δ_{i−m})/ω (methods.md eq. 0.2), corrected by the second-order crossing
//! angle of eq. (2.7); z′ = z. Converged when the step is below
//! `tol_mm` in every component (τ scaled by the edge speed ω·R), or when quadratic convergence
//! puts the next step below it (saves the confirming iteration: +17 % in 3-axis, +25 % in 5-axis
//! throughput, `benches/chip.rs`).
//!
//! 5-axis: where the motion is a constant screw around the ray's time ([`RigidStep`]: constant
//! swing, a CL-path segment), the look-back poses are reached by rotating the ray's pose through
//! the small angle rate·τ, and the spindle point at an iterate z′ by turning the prepared one
//! through ψ(z′) − ψ(z) ([`ToolKinematics::spindle_point_near`]) — series sin/cos, no libm call
//! per iteration; the same values to rounding (tests/core/chip_models.rs). Measured in the same run
//! (thread CPU time, `benches/chip.rs` points): 1.10 → 1.38 M points/s on the swing, 0.81 → 1.22 M
//! on the CL path, 3-axis unchanged. A second-order analytic start for (τ, z′, s) in the turning
//! frame was tried: it brings the swing to 1.00 Newton iteration per pass (from 2.2) but costs
//! more than the iteration it saves (0.70 M points/s), so the start stays the planar one.
//!
//! Lockstep passes (issue 18 item 3): a callgrind profile showed the solver bound by instruction
//! throughput (≈ 6 000 instructions per point, IPC ≈ 2.8), not by latency, trigonometry or
//! allocation, so [`exact_at_time`] solves the K independent passes side by side in SIMD lanes
//! (`chip::lanes`, same operations per lane → bit-identical to [`reference::exact_at`]), stops
//! the passes whose crossing is bounded below another's (they cannot decide the max of eq. 2.2),
//! and shares the pose, screw and spindle sin/cos of a time between the rays of every tooth and
//! height at that time ([`RayTime`]). Measured in one run (thread CPU time, `benches/chip.rs`,
//! load average 9–12 on 2 cores): 1.49 → 2.72 M points/s per core on the swing (1.83×),
//! 1.26 → 2.51 M on the CL path (2.00×), 2.85 → 3.92 M in 3-axis (1.37×), scalar reference →
//! lockstep.

use super::kinematics::{
    pose_near, small_sin_cos, HeightGeometry, Pose, RigidStep, ToolKinematics, ToolMotion, Vec3,
};
use super::lanes;

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
    /// Newton iterations summed over m (a pass stopped early because it cannot decide h counts
    /// the iterations it made).
    pub iterations: u32,
    /// True when every Newton solve that decides h met the tolerance (a pass whose crossing is
    /// bounded below another pass's, s_m + C·|Δx|² < s_j − C·|Δx_j|², is stopped early and does
    /// not count; see `chip::lanes`).
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
    let inv = 1.0 / c0.dot(&c12);
    Vec3::new(
        b.dot(&c12) * inv,
        c0.dot(&b.cross(c2)) * inv,
        c0.dot(&c1.cross(b)) * inv,
    )
}

/// The current tooth's ray and the local motion quantities of methods.md §2.4.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Ray {
    /// A(z,t) (mm).
    pub origin: Vec3,
    /// n (unit).
    pub dir: Vec3,
    /// t̂ = σ·u × n: direction of the edge motion for increasing spindle angle.
    pub tangent: Vec3,
    /// Tool axis u(t).
    pub axis: Vec3,
    /// a = Ȧ/ω, axis-point velocity per radian of spindle rotation (mm/rad).
    pub axis_rate: Vec3,
    /// R_i(z) = |E_i − A| (mm).
    pub radius: f64,
    /// (sin Θ(t), cos Θ(t)) of the spindle angle at the ray's time.
    pub spin: (f64, f64),
    /// The motion around the ray's time, when it is a constant screw there: look-back poses
    /// are then reached by incremental rotation ([`RigidStep`]).
    pub step: Option<RigidStep>,
}

/// Everything of a [`Ray`] that depends on the time t only (pose, its screw, spindle angle):
/// shared by the rays of every tooth and height at that time (no pose or libm `sin_cos` per ray).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RayTime {
    /// Time t (s).
    pub t: f64,
    /// The tool pose at t.
    pub pose: Pose,
    /// (sin Θ(t), cos Θ(t)).
    pub spin: (f64, f64),
    /// The motion around t as a constant screw, when it is one ([`ToolMotion::rigid_step`]).
    pub step: Option<RigidStep>,
}

impl RayTime {
    /// Prepare time `t`.
    #[inline]
    pub fn new<M: ToolMotion>(kin: &ToolKinematics<M>, t: f64) -> Self {
        let step = kin.motion().rigid_step(t);
        let pose = match &step {
            Some(s) => s.pose,
            None => kin.motion().pose(t),
        };
        RayTime {
            t,
            pose,
            spin: kin.spindle_angle(t).sin_cos(),
            step,
        }
    }
}

impl Ray {
    /// Ray of `tooth` at height `z`, time `t` (slow path: prepares the height).
    pub fn new<M: ToolMotion>(kin: &ToolKinematics<M>, tooth: usize, z: f64, t: f64) -> Self {
        Self::at(kin, &kin.at_height(z), tooth, t)
    }

    /// Ray of `tooth` at time `t` on the prepared height `geo`.
    #[inline]
    pub fn at<M: ToolMotion>(
        kin: &ToolKinematics<M>,
        geo: &HeightGeometry,
        tooth: usize,
        t: f64,
    ) -> Self {
        Self::at_time(kin, geo, tooth, &RayTime::new(kin, t))
    }

    /// Ray of `tooth` on the prepared height `geo` at the prepared time `time`.
    #[inline]
    pub fn at_time<M: ToolMotion>(
        kin: &ToolKinematics<M>,
        geo: &HeightGeometry,
        tooth: usize,
        time: &RayTime,
    ) -> Self {
        Ray {
            step: time.step,
            ..Self::at_time_without_step(kin, geo, tooth, time)
        }
    }

    /// [`Self::at_time`] with `step` left `None` (for solvers that take the screw from `time`).
    #[inline]
    pub(super) fn at_time_without_step<M: ToolMotion>(
        kin: &ToolKinematics<M>,
        geo: &HeightGeometry,
        tooth: usize,
        time: &RayTime,
    ) -> Self {
        let (pose, spin, step) = (&time.pose, time.spin, None);
        let st = kin.edge_from_pose_sc(pose, &geo.points[tooth], geo.z, spin.0, spin.1);
        let r = st.pos - st.axis_point;
        let radius = r.norm();
        let dir = r * (1.0 / radius);
        Ray {
            origin: st.axis_point,
            dir,
            tangent: pose.u.cross(&dir) * kin.sense().sigma(),
            axis: pose.u,
            axis_rate: (pose.v + pose.w.cross(&pose.u) * geo.z) * kin.inv_omega(),
            radius,
            spin,
            step,
        }
    }

    /// Axis displacement d = [A(z,t) − A(z,t+τ)]_⊥u since time t + τ (mm), eq. (2.4).
    #[inline]
    pub fn displacement<M: ToolMotion>(
        &self,
        kin: &ToolKinematics<M>,
        z: f64,
        t: f64,
        tau: f64,
    ) -> Vec3 {
        let pose = pose_near(kin.motion(), self.step.as_ref(), t + tau);
        let d = self.origin - (pose.p + pose.u * z);
        d - self.axis * d.dot(&self.axis)
    }
}

/// Start for the crossing of the previous tooth aligned at look-back τ₀ (methods.md §2.4):
/// R_p sin ψ + (a·t̂)ψ = d·t̂, from ψ₀ = d·t̂/(R_p + a·t̂) (eq. 2.7) refined by two scalar Newton
/// steps, then s = R_p cos ψ − d·n + ψ a·n. For straight feed this is already the exact crossing,
/// so the 3-D Newton below converges in one step; otherwise it is a third-order start.
/// Returns the start x and (sin ψ, cos ψ) (the last step δ is applied to them to first order:
/// |δ| ≲ 1e-9 rad after the first step, so the neglected δ²/2 is below 1e-18).
#[inline]
fn start_point<M: ToolMotion>(
    kin: &ToolKinematics<M>,
    ray: &Ray,
    z: f64,
    t: f64,
    tau0: f64,
    r_prev: f64,
) -> ([f64; 3], (f64, f64)) {
    let d = ray.displacement(kin, z, t, tau0);
    let dt = d.dot(&ray.tangent);
    let at = ray.axis_rate.dot(&ray.tangent);
    let mut psi = dt / (r_prev + at);
    let (mut sn, mut cs) = small_sin_cos(psi);
    psi -= (r_prev * sn + at * psi - dt) / (r_prev * cs + at);
    (sn, cs) = small_sin_cos(psi);
    let step = (r_prev * sn + at * psi - dt) / (r_prev * cs + at);
    psi -= step;
    (sn, cs) = (sn - cs * step, cs + sn * step);
    let s = r_prev * cs - d.dot(&ray.dir) + psi * ray.axis_rate.dot(&ray.dir);
    ([tau0 + psi * kin.inv_omega(), z, s], (sn, cs))
}

/// Newton solve of eq. (2.3) for the previous tooth m passes before `tooth` on height `geo`.
#[inline]
pub fn crossing_at<M: ToolMotion>(
    kin: &ToolKinematics<M>,
    geo: &HeightGeometry,
    ray: &Ray,
    tooth: usize,
    m: usize,
    t: f64,
    opts: &NewtonOptions,
) -> RayCrossing {
    let prev = geo.previous(tooth, m);
    let z = geo.z;
    let sp0 = geo.points[prev];
    let r_prev = geo.radius[prev];
    let idx = geo.pass_index(tooth, m);
    let tau0 = geo.tau_aligned[idx];
    let (mut x, mut turn) = start_point(kin, ray, z, t, tau0, r_prev);
    // sin/cos of Θ(t + τ₀) by the addition theorem; the Newton iterates differ from τ₀ by a
    // small angle ε = ω(τ − τ₀) whose sin/cos come from `small_sin_cos` (no libm in the loop)
    let (sa, ca) = geo.turn_aligned[idx];
    let (st0, ct0) = ray.spin;
    let (sb, cb) = (st0 * ca + ct0 * sa, ct0 * ca - st0 * sa);
    let speed = kin.omega() * r_prev;
    let tan_helix = kin.cutter().tan_helix();
    let curvature = 10.0 * (1.0 + tan_helix * tan_helix) / r_prev;
    let minus_n = -ray.dir;
    let mut iterations = 0;
    let mut converged = false;
    while iterations < opts.max_iter {
        iterations += 1;
        // straight feed keeps z′ = z exactly (the u-row decouples), so the cached point is used
        let sp = if x[1] == z {
            sp0
        } else {
            kin.spindle_point_near(geo, prev, x[1])
        };
        if iterations > 1 {
            turn = small_sin_cos(kin.omega() * (x[0] - tau0));
        }
        let (se, ce) = turn;
        let pose = pose_near(kin.motion(), ray.step.as_ref(), t + x[0]);
        let st = kin.edge_from_pose_sc(&pose, &sp, x[1], sb * ce + cb * se, cb * ce - sb * se);
        let f = st.pos - ray.origin - ray.dir * x[2];
        let dx = solve3(&st.d_dt, &st.d_dz, &minus_n, &(-f));
        x[0] += dx[0];
        x[1] += dx[1];
        x[2] += dx[2];
        let step = (dx[0] * speed).abs().max(dx[1].abs()).max(dx[2].abs());
        // converged when this step is below the tolerance, or when the next one must be: Newton
        // converges quadratically, |e_{k+1}| ≤ C·|e_k|² with C ≈ (1 + tan²β)/(2R) from the edge
        // curvature in t′ and z′; with the safety factor 20 in `curvature` the accepted iterate is
        // within tol (tested against an 8-iteration solve without early exit in tests/core/chip_models.rs)
        if step < opts.tol_mm || curvature * step * step < opts.tol_mm {
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

/// Newton solve of eq. (2.3) for one previous pass m (slow path: prepares the height).
pub fn ray_crossing<M: ToolMotion>(
    kin: &ToolKinematics<M>,
    tooth: usize,
    m: usize,
    z: f64,
    t: f64,
    opts: &NewtonOptions,
) -> RayCrossing {
    let geo = kin.at_height(z);
    let ray = Ray::at(kin, &geo, tooth, t);
    crossing_at(kin, &geo, &ray, tooth, m, t, opts)
}

/// Exact IUCT of `tooth` at height `z` and time `t`, eq. (2.2): min over the K previous passes.
/// Slow path (prepares the height each call); loops use [`exact_at`].
///
/// ```
/// use runout_core::chip::*;
/// use runout_core::{Cutter, Runout};
/// // methods.md §7: App. A.3 defaults, edge 0, z = 5, t = T + (5/48)T → 92.987 µm
/// let cutter = Cutter::flat(10.0, 4, 30.0f64.to_radians()).unwrap();
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
    exact_at(kin, &kin.at_height(z), tooth, t, opts)
}

/// Exact IUCT on a prepared height, eq. (2.2).
#[inline]
pub fn exact_at<M: ToolMotion>(
    kin: &ToolKinematics<M>,
    geo: &HeightGeometry,
    tooth: usize,
    t: f64,
    opts: &NewtonOptions,
) -> ExactIuct {
    exact_at_time(kin, geo, tooth, &RayTime::new(kin, t), opts)
}

/// Exact IUCT on a prepared height at a prepared time, eq. (2.2): the K Newton solves of
/// eq. (2.3) run in lockstep, four previous passes per lane vector (`chip::lanes`), with the same
/// operations in the same order as [`crossing_at`] in every lane, so the result is bit-identical
/// to [`reference::exact_at`] (tested in tests/core/chip_models.rs).
#[inline]
pub fn exact_at_time<M: ToolMotion>(
    kin: &ToolKinematics<M>,
    geo: &HeightGeometry,
    tooth: usize,
    time: &RayTime,
    opts: &NewtonOptions,
) -> ExactIuct {
    lanes::exact(kin, geo, tooth, time, opts)
}

/// The scalar solver, one previous pass after the other: the baseline of the lockstep
/// [`exact_at_time`] (same values bit for bit; `benches/chip.rs` measures both in one run).
#[doc(hidden)]
pub mod reference {
    use super::*;

    /// Exact IUCT on a prepared height, eq. (2.2), by [`crossing_at`] for m = 1..=K in turn.
    pub fn exact_at<M: ToolMotion>(
        kin: &ToolKinematics<M>,
        geo: &HeightGeometry,
        tooth: usize,
        t: f64,
        opts: &NewtonOptions,
    ) -> ExactIuct {
        let ray = Ray::at(kin, geo, tooth, t);
        let mut best = f64::NEG_INFINITY;
        let mut cutting_m = 1;
        let mut iterations = 0;
        let mut converged = true;
        for m in 1..=geo.teeth() {
            let c = crossing_at(kin, geo, &ray, tooth, m, t, opts);
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
}
