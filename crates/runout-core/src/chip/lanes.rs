//! Lockstep Newton solves of eq. (2.3) (methods.md §2.2–2.4) for the K previous passes of one
//! point: the passes m = 1..=K are independent, so they run side by side, four per lane vector,
//! instead of one after the other as in [`super::exact::crossing_at`].
//!
//! Every lane performs the same floating-point operations in the same order as the scalar
//! solver (start of eq. 2.7 refined by two scalar Newton steps, then 3-D Newton with Cramer's
//! rule and the quadratic stopping rule), so each crossing that decides h — and the IUCT — is
//! bit-identical to [`super::exact::reference::exact_at`] (tested in tests/core/chip_models.rs
//! over realistic 5-axis cases). A lane whose Newton solve has converged is frozen while the
//! others finish.
//!
//! Early stop of passes that cannot cut: h = R_i − max_m s_m (eq. 2.2) needs only the largest
//! crossing. After a Newton step Δx the iterate's error is bounded by C·|Δx|² (quadratic
//! convergence; C = `curvature` of the stopping rule, 20× the edge-curvature estimate, here
//! × `PRUNE_SAFETY` = 4 more), and it is 0 for an accepted iterate (that is the result). A pass
//! with s_m + bound_m < s_j − bound_j for another pass j is stopped: its converged crossing would
//! be below s_j's, so the maximum, the cutting pass and h are those of the full solve. Typically
//! only the cutting pass (and a near-tie) runs past the first iteration. Where a lane leaves the
//! vector fast path — a look-back time outside the screw interval (a CL-path junction), a
//! rotation or angle increment beyond the degree-9/10 range of [`small_sin_cos`], a spindle
//! point at z′ ≠ z — that quantity is computed per lane by the scalar functions themselves.
//!
//! The lane loops are plain fixed-size array loops compiled inside [`pulp::Arch::dispatch`]
//! (AVX-512 / AVX2 / SSE selected at run time), like the force kernel: the compiler turns the
//! pose rotation, edge state, Jacobian and Cramer solve of four passes into vector
//! instructions. Rust never contracts a·b + c into an FMA, so the vector code rounds like the
//! scalar one.

// Lane loops index several lane arrays in lockstep; `for l in 0..L` reads best there.
// `!(q < …)` is deliberate: NaN takes the scalar path, as in `small_sin_cos`.
#![allow(clippy::needless_range_loop, clippy::neg_cmp_op_on_partial_ord)]

use super::exact::{ExactIuct, NewtonOptions, Ray, RayTime};
use super::kinematics::{
    pose_near, small_sin_cos, HeightGeometry, ToolKinematics, ToolMotion, Vec3, COS_TAYLOR,
    SIN_TAYLOR, SMALL_ANGLE_SQ,
};

/// Previous passes per lane vector.
const L: usize = 4;
type F = [f64; L];

#[inline(always)]
fn lanes(f: impl FnMut(usize) -> f64) -> F {
    fill(0.0, f)
}

/// [T; L] from a function of the lane (a plain loop: `std::array::from_fn` goes through a
/// closure that is not always inlined into the SIMD entry).
#[inline(always)]
fn fill<T: Copy>(init: T, mut f: impl FnMut(usize) -> T) -> [T; L] {
    let mut a = [init; L];
    for (l, a) in a.iter_mut().enumerate() {
        *a = f(l);
    }
    a
}

/// Four 3-vectors, structure of arrays. The operations round like nalgebra's `Vector3`
/// (dot = (x·x′ + y·y′) + z·z′, cross component by component).
#[derive(Clone, Copy)]
struct V {
    x: F,
    y: F,
    z: F,
}

impl V {
    #[inline(always)]
    fn splat(v: &Vec3) -> V {
        V {
            x: [v.x; L],
            y: [v.y; L],
            z: [v.z; L],
        }
    }
    #[inline(always)]
    fn set(&mut self, l: usize, v: &Vec3) {
        (self.x[l], self.y[l], self.z[l]) = (v.x, v.y, v.z);
    }
    #[inline(always)]
    fn add(&self, o: &V) -> V {
        V {
            x: lanes(|l| self.x[l] + o.x[l]),
            y: lanes(|l| self.y[l] + o.y[l]),
            z: lanes(|l| self.z[l] + o.z[l]),
        }
    }
    #[inline(always)]
    fn sub(&self, o: &V) -> V {
        V {
            x: lanes(|l| self.x[l] - o.x[l]),
            y: lanes(|l| self.y[l] - o.y[l]),
            z: lanes(|l| self.z[l] - o.z[l]),
        }
    }
    #[inline(always)]
    fn neg(&self) -> V {
        V {
            x: lanes(|l| -self.x[l]),
            y: lanes(|l| -self.y[l]),
            z: lanes(|l| -self.z[l]),
        }
    }
    #[inline(always)]
    fn mul(&self, s: &F) -> V {
        V {
            x: lanes(|l| self.x[l] * s[l]),
            y: lanes(|l| self.y[l] * s[l]),
            z: lanes(|l| self.z[l] * s[l]),
        }
    }
    #[inline(always)]
    fn dot(&self, o: &V) -> F {
        lanes(|l| self.x[l] * o.x[l] + self.y[l] * o.y[l] + self.z[l] * o.z[l])
    }
    #[inline(always)]
    fn cross(&self, o: &V) -> V {
        V {
            x: lanes(|l| self.y[l] * o.z[l] - self.z[l] * o.y[l]),
            y: lanes(|l| self.z[l] * o.x[l] - self.x[l] * o.z[l]),
            z: lanes(|l| self.x[l] * o.y[l] - self.y[l] * o.x[l]),
        }
    }
}

/// Tool poses of the four lanes (the fields of [`super::Pose`]).
struct Poses {
    p: V,
    u: V,
    e1: V,
    v: V,
    w: V,
}

/// [`small_sin_cos`] of every lane: the degree-9/10 polynomials in lanes, and the scalar
/// function for the active lanes outside their range (|x| ≥ 1/8).
#[inline(always)]
fn sin_cos(x: &F, active: &[bool; L]) -> (F, F) {
    let q = lanes(|l| x[l] * x[l]);
    let ps = lanes(|l| {
        SIN_TAYLOR[..4]
            .iter()
            .rev()
            .fold(0.0, |acc, c| acc * q[l] + c)
    });
    let pc = lanes(|l| {
        COS_TAYLOR[..5]
            .iter()
            .rev()
            .fold(0.0, |acc, c| acc * q[l] + c)
    });
    let mut s = lanes(|l| x[l] + x[l] * q[l] * ps[l]);
    let mut c = lanes(|l| 1.0 + q[l] * pc[l]);
    for l in 0..L {
        // `!(q < …)`: NaN goes to the scalar function like in `small_sin_cos`
        if active[l] && !(q[l] < SMALL_ANGLE_SQ) {
            (s[l], c[l]) = small_sin_cos(x[l]);
        }
    }
    (s, c)
}

/// Poses at the times t + τ_l ([`pose_near`] of every active lane): the incremental screw
/// rotation of [`super::RigidStep::pose_at`] in lanes, and the scalar function for the active
/// lanes where it does not apply with a rotation in the degree-9/10 range of [`small_sin_cos`]
/// (a look-back across a CL-path junction, a motion without screw).
#[inline(always)]
fn poses<M: ToolMotion>(
    kin: &ToolKinematics<M>,
    time: &RayTime,
    tau: &F,
    active: &[bool; L],
) -> Poses {
    let tl = lanes(|l| time.t + tau[l]);
    let mut scalar = *active;
    let mut out = match &time.step {
        Some(st) => {
            let dt = lanes(|l| tl[l] - st.t);
            let angle = lanes(|l| st.rate * dt[l]);
            for l in 0..L {
                scalar[l] &=
                    !((tl[l] >= st.lo) & (tl[l] < st.hi) & (angle[l] * angle[l] < SMALL_ANGLE_SQ));
            }
            let (s, c) = sin_cos(&angle, &[false; L]);
            let one_c = lanes(|l| 1.0 - c[l]);
            let [cu, pu, ce, pe] = &st.terms;
            let u0 = V::splat(&st.pose.u);
            let u = u0.add(&V::splat(cu).mul(&s)).add(&V::splat(pu).mul(&one_c));
            let e1 = V::splat(&st.pose.e1)
                .add(&V::splat(ce).mul(&s))
                .add(&V::splat(pe).mul(&one_c));
            let vc = V::splat(&st.vc);
            let w = V::splat(&st.pose.w);
            let (p, v) = if st.pivot == 0.0 {
                (V::splat(&st.pose.p).add(&vc.mul(&dt)), vc)
            } else {
                let pivot = [st.pivot; L];
                (
                    V::splat(&st.pose.p)
                        .add(&vc.mul(&dt))
                        .add(&u0.sub(&u).mul(&pivot)),
                    vc.sub(&w.cross(&u).mul(&pivot)),
                )
            };
            Poses { p, u, e1, v, w }
        }
        None => {
            let p = V::splat(&time.pose.p);
            let u = V::splat(&time.pose.u);
            let e1 = V::splat(&time.pose.e1);
            let v = V::splat(&time.pose.v);
            let w = V::splat(&time.pose.w);
            Poses { p, u, e1, v, w }
        }
    };
    for l in 0..L {
        if scalar[l] {
            let q = pose_near(kin.motion(), time.step.as_ref(), tl[l]);
            out.p.set(l, &q.p);
            out.u.set(l, &q.u);
            out.e1.set(l, &q.e1);
            out.v.set(l, &q.v);
            out.w.set(l, &q.w);
        }
    }
    out
}

/// Crossings of up to four previous passes m0.. m0 + n − 1 (padding lanes repeat the last one
/// and are never active): s, iterations, converged per lane.
struct Solved {
    s: F,
    iterations: [u32; L],
    converged: [bool; L],
    /// Stopped early: s_m + bound < s_j − bound_j for another pass j, so m does not cut.
    pruned: [bool; L],
}

/// Safety factor on the quadratic-convergence error bound C·|Δx|² (C = `curvature` of
/// `crossing_at`, itself 20× the edge-curvature estimate) used to stop passes that cannot decide h.
const PRUNE_SAFETY: f64 = 4.0;

#[inline(always)]
#[allow(clippy::too_many_arguments)]
fn solve_passes<M: ToolMotion>(
    kin: &ToolKinematics<M>,
    geo: &HeightGeometry,
    ray: &Ray,
    time: &RayTime,
    tooth: usize,
    m0: usize,
    n: usize,
    opts: &NewtonOptions,
) -> Solved {
    let z = geo.z;
    let m_of = |l: usize| m0 + l.min(n - 1);
    let prev: [usize; L] = fill(0, |l| geo.previous(tooth, m_of(l)));
    let idx: [usize; L] = fill(0, |l| geo.pass_index(tooth, m_of(l)));
    let r_prev = lanes(|l| geo.radius[prev[l]]);
    let tau0 = lanes(|l| geo.tau_aligned[idx[l]]);
    let live: [bool; L] = fill(false, |l| l < n);

    // start, as `start_point`
    let origin = V::splat(&ray.origin);
    let dir = V::splat(&ray.dir);
    let rate = V::splat(&ray.axis_rate);
    let (mut x0, mut x1, mut x2, mut se, mut ce) = ([0.0; L], [z; L], [0.0; L], [0.0; L], [0.0; L]);
    {
        let pose = poses(kin, time, &tau0, &live);
        let axis = V::splat(&ray.axis);
        let tangent = V::splat(&ray.tangent);
        let d = origin.sub(&pose.p.add(&pose.u.mul(&[z; L])));
        let d = d.sub(&axis.mul(&d.dot(&axis)));
        let dt = d.dot(&tangent);
        let at = rate.dot(&tangent);
        let mut psi = lanes(|l| dt[l] / (r_prev[l] + at[l]));
        let (sn, cs) = sin_cos(&psi, &live);
        psi = lanes(|l| {
            psi[l] - (r_prev[l] * sn[l] + at[l] * psi[l] - dt[l]) / (r_prev[l] * cs[l] + at[l])
        });
        let (sn, cs) = sin_cos(&psi, &live);
        let step =
            lanes(|l| (r_prev[l] * sn[l] + at[l] * psi[l] - dt[l]) / (r_prev[l] * cs[l] + at[l]));
        psi = lanes(|l| psi[l] - step[l]);
        let dn = d.dot(&dir);
        let an = rate.dot(&dir);
        for l in 0..L {
            se[l] = sn[l] - cs[l] * step[l];
            ce[l] = cs[l] + sn[l] * step[l];
            x2[l] = r_prev[l] * ce[l] - dn[l] + psi[l] * an[l];
            x0[l] = tau0[l] + psi[l] * kin.inv_omega();
        }
    }

    // sin/cos of Θ(t + τ₀) by the addition theorem, as `crossing_at`
    let (st0, ct0) = ray.spin;
    let sb = lanes(|l| st0 * geo.turn_aligned[idx[l]].1 + ct0 * geo.turn_aligned[idx[l]].0);
    let cb = lanes(|l| ct0 * geo.turn_aligned[idx[l]].1 - st0 * geo.turn_aligned[idx[l]].0);
    let omega = kin.omega();
    let speed = lanes(|l| omega * r_prev[l]);
    let tan_helix = kin.cutter().tan_helix();
    let curvature = lanes(|l| 10.0 * (1.0 + tan_helix * tan_helix) / r_prev[l]);
    let minus_n = dir.neg();
    let sigma = [kin.sense().sigma(); L];
    let omegas = [omega; L];

    let mut active = live;
    let mut iterations = [0u32; L];
    let mut converged = [false; L];
    let mut pruned = [false; L];
    // bound on |s − s_final| per lane: none before the first step, 0 once converged (the
    // accepted iterate is the result)
    let mut bound = [f64::INFINITY; L];
    let mut it = 0;
    while it < opts.max_iter && active != [false; L] {
        it += 1;
        // straight feed keeps z′ = z exactly, so the cached point is used
        let sp: [_; L] = fill(geo.points[0], |l| {
            if x1[l] == z || !active[l] {
                geo.points[prev[l]]
            } else {
                kin.spindle_point_near(geo, prev[l], x1[l])
            }
        });
        if it > 1 {
            (se, ce) = sin_cos(&lanes(|l| omega * (x0[l] - tau0[l])), &active);
        }
        let pose = poses(kin, time, &x0, &active);
        // edge state, as `ToolKinematics::edge_from_pose_sc`
        let sn = lanes(|l| sb[l] * ce[l] + cb[l] * se[l]);
        let cs = lanes(|l| cb[l] * ce[l] - sb[l] * se[l]);
        let e2 = pose.u.cross(&pose.e1).mul(&sigma);
        let a = lanes(|l| sp[l].xy[0] * cs[l] - sp[l].xy[1] * sn[l]);
        let b = lanes(|l| sp[l].xy[0] * sn[l] + sp[l].xy[1] * cs[l]);
        let da = lanes(|l| sp[l].dxy[0] * cs[l] - sp[l].dxy[1] * sn[l]);
        let db = lanes(|l| sp[l].dxy[0] * sn[l] + sp[l].dxy[1] * cs[l]);
        let radial = pose.e1.mul(&a).add(&e2.mul(&b));
        let rel = pose.u.mul(&x1).add(&radial);
        let spin = e2.mul(&a).sub(&pose.e1.mul(&b)).mul(&omegas);
        let pos = pose.p.add(&rel);
        let d_dt = pose.v.add(&pose.w.cross(&rel)).add(&spin);
        let d_dz = pose.u.add(&pose.e1.mul(&da)).add(&e2.mul(&db));
        // residual and Cramer's rule, as `solve3`
        let rhs = pos.sub(&origin).sub(&dir.mul(&x2)).neg();
        let c12 = d_dz.cross(&minus_n);
        let det = d_dt.dot(&c12);
        let inv = lanes(|l| 1.0 / det[l]);
        let b0 = rhs.dot(&c12);
        let b1 = d_dt.dot(&rhs.cross(&minus_n));
        let b2 = d_dt.dot(&d_dz.cross(&rhs));
        let dx0 = lanes(|l| b0[l] * inv[l]);
        let dx1 = lanes(|l| b1[l] * inv[l]);
        let dx2 = lanes(|l| b2[l] * inv[l]);
        let step = lanes(|l| {
            (dx0[l] * speed[l])
                .abs()
                .max(dx1[l].abs())
                .max(dx2[l].abs())
        });
        for l in 0..L {
            if active[l] {
                x0[l] += dx0[l];
                x1[l] += dx1[l];
                x2[l] += dx2[l];
                iterations[l] = it;
                let quad = curvature[l] * step[l] * step[l];
                if step[l] < opts.tol_mm || quad < opts.tol_mm {
                    converged[l] = true;
                    active[l] = false;
                    bound[l] = 0.0;
                } else {
                    bound[l] = PRUNE_SAFETY * quad;
                }
            }
        }
        // a pass whose crossing is certainly below another's does not decide h (eq. 2.2)
        let mut floor = f64::NEG_INFINITY;
        for l in 0..L {
            if live[l] {
                floor = floor.max(x2[l] - bound[l]);
            }
        }
        for l in 0..L {
            if active[l] && x2[l] + bound[l] < floor {
                active[l] = false;
                pruned[l] = true;
            }
        }
    }
    Solved {
        s: x2,
        iterations,
        converged,
        pruned,
    }
}

/// Exact IUCT of eq. (2.2) with the lockstep solves (see the module documentation).
#[inline(always)]
fn exact_impl<M: ToolMotion>(
    kin: &ToolKinematics<M>,
    geo: &HeightGeometry,
    tooth: usize,
    time: &RayTime,
    opts: &NewtonOptions,
) -> ExactIuct {
    let ray = Ray::at_time_without_step(kin, geo, tooth, time);
    let k = geo.teeth();
    let mut best = f64::NEG_INFINITY;
    let mut cutting_m = 1;
    let mut iterations = 0;
    let mut converged = true;
    let mut m0 = 1;
    while m0 <= k {
        let n = (k + 1 - m0).min(L);
        let c = solve_passes(kin, geo, &ray, time, tooth, m0, n, opts);
        for l in 0..n {
            iterations += c.iterations[l];
            if c.pruned[l] {
                continue;
            }
            converged &= c.converged[l];
            if c.s[l] > best {
                best = c.s[l];
                cutting_m = m0 + l;
            }
        }
        m0 += L;
    }
    ExactIuct {
        raw: ray.radius - best,
        radius: ray.radius,
        cutting_m,
        iterations,
        converged,
    }
}

/// [`exact_impl`] as a [`pulp::WithSimd`] operation, so that it is inlined into pulp's
/// `#[target_feature]` entry of the detected instruction set.
struct Job<'a, M> {
    kin: &'a ToolKinematics<M>,
    geo: &'a HeightGeometry,
    tooth: usize,
    time: &'a RayTime,
    opts: &'a NewtonOptions,
}

impl<M: ToolMotion> pulp::WithSimd for Job<'_, M> {
    type Output = ExactIuct;
    #[inline(always)]
    fn with_simd<S: pulp::Simd>(self, _simd: S) -> ExactIuct {
        exact_impl(self.kin, self.geo, self.tooth, self.time, self.opts)
    }
}

/// Exact IUCT of `tooth` on `geo` at `time`, eq. (2.2), with the SIMD instruction set detected
/// at run time.
#[inline]
pub(super) fn exact<M: ToolMotion>(
    kin: &ToolKinematics<M>,
    geo: &HeightGeometry,
    tooth: usize,
    time: &RayTime,
    opts: &NewtonOptions,
) -> ExactIuct {
    pulp::Arch::new().dispatch(Job {
        kin,
        geo,
        tooth,
        time,
        opts,
    })
}
