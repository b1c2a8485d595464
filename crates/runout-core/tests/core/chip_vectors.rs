//! methods.md §7 IUCT test vectors and the exact solver against an independent brute force.

use runout_core::chip::*;
use runout_core::{Cutter, Runout};
use std::f64::consts::TAU;

/// The kinematics of methods.md App. A.3 `Cut(...)`: CCW spindle, e₁ = +x, feed +x, swing
/// Ω about `w` through the tip.
fn app_a3(
    r: f64,
    k: usize,
    fz: f64,
    rho: f64,
    omega_swing: f64,
    w: Vec3,
) -> ToolKinematics<Motion> {
    let cutter = Cutter::flat(2.0 * r, k, 30.0f64.to_radians()).unwrap();
    let runout = Runout::new(rho, 40f64.to_radians()).unwrap();
    let v = Vec3::new(fz * k as f64 * 100.0, 0.0, 0.0); // 6000 rpm: T = 0.01 s
    let motion = if omega_swing == 0.0 {
        Motion::Straight(StraightFeed {
            p0: Vec3::zeros(),
            v,
            u: Vec3::z(),
            e1: Vec3::x(),
        })
    } else {
        let s = ConstantSwing::new(v, w, omega_swing, 0.0).unwrap();
        Motion::Swing(ConstantSwing { e1: Vec3::x(), ..s })
    };
    ToolKinematics::new(
        &cutter,
        &runout,
        6000.0,
        0.0,
        SpindleSense::CounterClockwise,
        motion,
    )
    .unwrap()
}

use runout_core::chip::compare::Motion;

#[test]
fn methods_section7_vectors() {
    // Reference values of methods.md §7 are printed to 3 decimals in µm: tolerance 0.5 nm.
    let kin = app_a3(5.0, 4, 0.1, 0.010, 0.0, Vec3::y());
    for (frac, ex, arc, eq) in [
        (5.0, 92.987, 93.039, 93.146),
        (10.0, 68.603, 67.631, 68.711),
    ] {
        let t = 0.01 * (1.0 + frac / 48.0);
        let e = exact_iuct(&kin, 0, 5.0, t, &NewtonOptions::default());
        let c = closed_forms(&kin, 0, 5.0, t, &EquivalentParams::analytic_unrefined());
        assert!(e.converged);
        assert!((e.h() * 1e3 - ex).abs() < 5e-4, "exact {}", e.h() * 1e3);
        assert!((c.arc * 1e3 - arc).abs() < 5e-4, "arc {}", c.arc * 1e3);
        assert!(
            (c.equivalent * 1e3 - eq).abs() < 5e-4,
            "eq {}",
            c.equivalent * 1e3
        );
        // the phase refinement (§2.4) must move the equivalent value towards the exact one
        let r = closed_forms(&kin, 0, 5.0, t, &EquivalentParams::default());
        assert!((r.equivalent - e.h()).abs() < (c.equivalent - e.h()).abs());
    }
}

// ---- independent brute force: App. A.3 kinematics written out with rotation matrices ----

/// Rodrigues rotation matrix (row-major) about unit `w` by `ang`.
fn rot(w: [f64; 3], ang: f64) -> [[f64; 3]; 3] {
    let n = (w[0] * w[0] + w[1] * w[1] + w[2] * w[2]).sqrt();
    let [x, y, z] = [w[0] / n, w[1] / n, w[2] / n];
    let (s, c) = ang.sin_cos();
    let k = [[0.0, -z, y], [z, 0.0, -x], [-y, x, 0.0]];
    let mut r = [[0.0; 3]; 3];
    for i in 0..3 {
        for j in 0..3 {
            let kk: f64 = (0..3).map(|q| k[i][q] * k[q][j]).sum();
            r[i][j] = if i == j { 1.0 } else { 0.0 } + s * k[i][j] + (1.0 - c) * kk;
        }
    }
    r
}

struct Brute {
    r: f64,
    k: usize,
    tb: f64,
    om: f64,
    v: f64,
    rho: f64,
    lam: f64,
    swing: f64,
    w: [f64; 3],
}

impl Brute {
    fn frame(&self, t: f64) -> ([f64; 3], [f64; 3], [f64; 3]) {
        let q = rot(self.w, self.swing * t);
        let u = [q[0][2], q[1][2], q[2][2]];
        let e1 = [q[0][0], q[1][0], q[2][0]];
        let e2 = [
            u[1] * e1[2] - u[2] * e1[1],
            u[2] * e1[0] - u[0] * e1[2],
            u[0] * e1[1] - u[1] * e1[0],
        ];
        (u, e1, e2)
    }
    fn axis(&self, z: f64, t: f64) -> [f64; 3] {
        let u = self.frame(t).0;
        [self.v * t + z * u[0], z * u[1], z * u[2]]
    }
    fn edge(&self, j: usize, z: f64, t: f64) -> [f64; 3] {
        let (_, e1, e2) = self.frame(t);
        let th = self.om * t - TAU * j as f64 / self.k as f64 - z * self.tb / self.r;
        let a = self.om * t + self.lam;
        let ax = self.axis(z, t);
        let mut p = [0.0; 3];
        for q in 0..3 {
            p[q] = ax[q]
                + self.rho * (a.cos() * e1[q] + a.sin() * e2[q])
                + self.r * (th.cos() * e1[q] + th.sin() * e2[q]);
        }
        p
    }
    /// Point of edge j at time t′ lying in the plane ⊥ u(t) through `a0` (bisection in z′),
    /// relative to `a0`.
    fn in_plane(&self, j: usize, z: f64, tp: f64, a0: [f64; 3], u: [f64; 3]) -> [f64; 3] {
        let f = |zz: f64| {
            let e = self.edge(j, zz, tp);
            let d = [e[0] - a0[0], e[1] - a0[1], e[2] - a0[2]];
            (d, d[0] * u[0] + d[1] * u[1] + d[2] * u[2])
        };
        let (mut lo, mut hi) = (z - 2.0, z + 2.0);
        for _ in 0..60 {
            let mid = 0.5 * (lo + hi);
            if f(mid).1 > 0.0 {
                hi = mid;
            } else {
                lo = mid;
            }
        }
        f(0.5 * (lo + hi)).0
    }
    /// h = R_i − max_m s_m by dense sampling of t′ and bisection on the sign of the distance
    /// to the ray (nearest crossing with s > 0 to the nominal pass time).
    fn iuct(&self, i: usize, z: f64, t: f64) -> f64 {
        let a0 = self.axis(z, t);
        let u = self.frame(t).0;
        let e = self.edge(i, z, t);
        let r = [e[0] - a0[0], e[1] - a0[1], e[2] - a0[2]];
        let ri = (r[0] * r[0] + r[1] * r[1] + r[2] * r[2]).sqrt();
        let n = [r[0] / ri, r[1] / ri, r[2] / ri];
        // side of the ray: component along u × n
        let side = [
            u[1] * n[2] - u[2] * n[1],
            u[2] * n[0] - u[0] * n[2],
            u[0] * n[1] - u[1] * n[0],
        ];
        let dot = |a: [f64; 3], b: [f64; 3]| a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
        let period = TAU / self.om;
        let mut best = f64::NEG_INFINITY;
        for m in 1..=self.k {
            let j = (i + self.k * m - m) % self.k;
            let centre = t - m as f64 * period / self.k as f64;
            let samples = 400;
            let half = 0.2 * period / self.k as f64;
            let g = |tp: f64| {
                let p = self.in_plane(j, z, tp, a0, u);
                (dot(p, side), dot(p, n))
            };
            let mut found: Option<(f64, f64)> = None; // (|tp − centre|, s)
            let mut prev = (centre - half, g(centre - half));
            for q in 1..=samples {
                let tp = centre - half + 2.0 * half * q as f64 / samples as f64;
                let cur = (tp, g(tp));
                if prev.1 .0.signum() != cur.1 .0.signum() && cur.1 .1 > 0.0 {
                    let (mut lo, mut hi) = (prev.0, cur.0);
                    let slo = prev.1 .0.signum();
                    for _ in 0..60 {
                        let mid = 0.5 * (lo + hi);
                        if g(mid).0.signum() == slo {
                            lo = mid;
                        } else {
                            hi = mid;
                        }
                    }
                    let s = g(0.5 * (lo + hi)).1;
                    let dist = (0.5 * (lo + hi) - centre).abs();
                    if found.is_none_or(|f| dist < f.0) {
                        found = Some((dist, s));
                    }
                }
                prev = cur;
            }
            best = best.max(found.expect("a crossing in the window").1);
        }
        ri - best
    }
}

fn check_against_brute(r: f64, k: usize, fz: f64, rho: f64, swing: f64, w: Vec3, heights: &[f64]) {
    let kin = app_a3(r, k, fz, rho, swing, w);
    let b = Brute {
        r,
        k,
        tb: 30f64.to_radians().tan(),
        om: TAU * 100.0,
        v: fz * k as f64 * 100.0,
        rho,
        lam: 40f64.to_radians(),
        swing,
        w: [w.x, w.y, w.z],
    };
    let opts = NewtonOptions::default();
    for &z in heights {
        for tooth in 0..k {
            for q in 0..4 {
                let t = 0.01 * (1.0 + (q as f64 + 0.3) / 4.0);
                let e = exact_iuct(&kin, tooth, z, t, &opts);
                let bf = b.iuct(tooth, z, t);
                // bisection to 2^-60 of the window; the in-plane bisection to 4·2^-60 mm:
                // the brute force is good to ~1e-9 mm, the exact solver to 1e-12 mm.
                assert!(
                    (e.raw - bf).abs() < 1e-6,
                    "R{r} K{k} z{z} tooth{tooth} t{t}: exact {} brute {}",
                    e.raw,
                    bf
                );
            }
        }
    }
}

#[test]
fn exact_matches_brute_force_3axis() {
    check_against_brute(5.0, 4, 0.1, 0.010, 0.0, Vec3::y(), &[0.0, 5.0]);
    check_against_brute(4.0, 3, 0.15, 0.020, 0.0, Vec3::y(), &[2.0]);
    // micro-milling with edge skipping (ρ comparable to f_z)
    check_against_brute(0.25, 2, 0.002, 0.002, 0.0, Vec3::y(), &[0.1]);
}

#[test]
fn exact_matches_brute_force_5axis_swing() {
    check_against_brute(
        5.0,
        4,
        0.1,
        0.010,
        60f64.to_radians(),
        Vec3::y(),
        &[0.0, 10.0, 20.0],
    );
    check_against_brute(
        5.0,
        4,
        0.1,
        0.010,
        60f64.to_radians(),
        Vec3::new(1.0, 0.3, 0.0),
        &[10.0],
    );
}
