#!/usr/bin/env python3
"""Independent ball-end milling force model (Lee & Altintas 1996; Engin & Altintas 2001).

Cross-check for runout's Rust force kernel (issue 12). Written from the papers, not from the
Rust code, and discretised differently: the ball is sampled uniformly in the polar angle κ
(z = R0(1 − cos κ), R(z) = R0 sin κ, dz = R0 sin κ dκ), the cylinder above it uniformly in z.

Model (Lee & Altintas 1996, eqs. for the ball part; E&A 2001 transformation matrix):
  lag            ψ(z) = z tan i0 / R0                  (constant lead)
  immersion      φ_i(z, θ) = θ − 2π i / K − ψ(z)       (clockwise from +y)
  runout radius  R_i(z) = |R(z)(cos ψ_i, sin ψ_i) + ρ(cos λ, sin λ)|, ψ_i = −2πi/K − ψ(z)
  chip           h = max(0, min_m [m f_t sin φ + R_i − R_{i−m}]) · sin κ
  chip width     db = dz / sin κ
  dF_t = K_tc h db + K_te db,  dF_r = K_rc h db + K_re db,  dF_a = K_ac' h db + K_ae' db
  forces on the tool (E&A):
    dF_x = −dF_t cos φ − dF_r sin κ sin φ − dF_a cos κ sin φ
    dF_y =  dF_t sin φ − dF_r sin κ cos φ − dF_a cos κ cos φ
    dF_z =               dF_r cos κ       − dF_a sin κ
  In E&A the axial force of a flat end (κ = 90°) acts along −z on the tool; runout's convention
  has it along +z (its F_z on the workpiece is −Σ dF_a), so K_a' = −K_a. Forces on the
  workpiece are the negatives.
Engagement (geometric): material at height z occupies y ≥ R(z) − a_e (up milling) or
  y ≤ −(R(z) − a_e) (down milling) in front of the tool (x ≥ 0), with the tooth point at
  (x, y) = R(z)(sin φ, cos φ); slot: x ≥ 0.

Input: one JSON object on argv[1]; output: JSON with per-tooth peaks of |F_xy| (own
contribution of each tooth) and the revolution-mean forces.
"""
import json
import sys

import numpy as np


def main():
    p = json.loads(sys.argv[1])
    R0, K, i0 = p["radius"], p["teeth"], np.radians(p["helix_deg"])
    ft, ap, ae, mode = p["fz"], p["ap"], p["ae"], p["mode"]
    rho, lam = p["rho"], p["lambda"]
    ktc, krc, kac, kte, kre, kae = p["k"]
    kac, kae = -kac, -kae  # E&A axial sign (see docstring)
    nk = p["points"]
    # edge points: ball by polar angle κ, cylinder by z
    zmax_ball = min(ap, R0)
    kmax = np.arccos(1.0 - zmax_ball / R0)
    edges = np.linspace(0.0, kmax, nk + 1)
    kap = 0.5 * (edges[1:] + edges[:-1])
    z = R0 * (1.0 - np.cos(kap))
    dz = R0 * (np.cos(edges[:-1]) - np.cos(edges[1:]))  # exact dz of each κ-interval
    Rz = R0 * np.sin(kap)
    if ap > R0:
        nc = nk
        ze = np.linspace(R0, ap, nc + 1)
        zc = 0.5 * (ze[1:] + ze[:-1])
        z = np.concatenate([z, zc])
        dz = np.concatenate([dz, np.diff(ze)])
        Rz = np.concatenate([Rz, np.full(nc, R0)])
        kap = np.concatenate([kap, np.full(nc, np.pi / 2)])
    sk, ck = np.sin(kap), np.cos(kap)
    db = dz / sk
    lag = z * np.tan(i0) / R0
    e = rho * np.array([np.cos(lam), np.sin(lam)])
    psi = np.array([-2.0 * np.pi * i / K - lag for i in range(K)])  # (K, n)
    px = Rz * np.cos(psi) + e[0]
    py = Rz * np.sin(psi) + e[1]
    Ri = np.hypot(px, py)
    nth = int(round(360.0 / p["step_deg"]))
    theta = np.arange(nth) * np.radians(p["step_deg"])
    own = np.zeros((K, nth, 2))
    tot = np.zeros((nth, 3))
    for i in range(K):
        phi = theta[:, None] + psi[i][None, :]  # (nth, n)
        s, c = np.sin(phi), np.cos(phi)
        cand = np.stack([m * ft * s + (Ri[i] - Ri[(i - m) % K])[None, :] for m in range(1, K + 1)])
        h = np.maximum(0.0, cand.min(axis=0)) * sk[None, :]
        x, y = Rz[None, :] * s, Rz[None, :] * c
        front = x >= 0.0
        if mode == "up":
            cut = front & (y >= (Rz - ae)[None, :] - 1e-15)
        elif mode == "down":
            cut = front & (y <= -(Rz - ae)[None, :] + 1e-15)
        else:
            cut = front
        cut &= h > 0.0
        dft = np.where(cut, (ktc * h + kte) * db[None, :], 0.0)
        dfr = np.where(cut, (krc * h + kre) * db[None, :], 0.0)
        dfa = np.where(cut, (kac * h + kae) * db[None, :], 0.0)
        fx_tool = -dft * c - dfr * sk * s - dfa * ck * s
        fy_tool = dft * s - dfr * sk * c - dfa * ck * c
        fz_tool = dfr * ck - dfa * sk
        own[i, :, 0] = -fx_tool.sum(axis=1)
        own[i, :, 1] = -fy_tool.sum(axis=1)
        tot[:, 0] -= fx_tool.sum(axis=1)
        tot[:, 1] -= fy_tool.sum(axis=1)
        tot[:, 2] -= fz_tool.sum(axis=1)
    peaks = np.hypot(own[:, :, 0], own[:, :, 1]).max(axis=1)
    print(json.dumps({"peaks": peaks.tolist(), "mean": tot.mean(axis=0).tolist(),
                      "peak_fxy": float(np.hypot(tot[:, 0], tot[:, 1]).max())}))


if __name__ == "__main__":
    main()
