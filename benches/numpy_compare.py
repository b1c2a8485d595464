#!/usr/bin/env python3
"""The force-simulation workload of issue 18 in NumPy and in `runout simulate`, same run.

Workload (default): K = 4, D = 10 mm, helix 30°, 50 axial disks, 0.036° angular steps,
100 revolutions → 10 000 × 100 × 4 × 50 = 200 M tooth × disk × angle evaluations of the
mechanistic model with the arc chip and runout (docs/methods.md §4.1, eq. 0.4):

    h = max(0, min_m [f_{i,m} sin φ + R_i(z) − R_{i−m}(z)]),  R_i(z) = |R·u(ψ_i(z)) + e|
    dF_t = (K_tc h + K_te) dz, dF_r = (K_rc h + K_re) dz (edge terms only where h > 0)
    F_x = Σ dF_t cos φ + dF_r sin φ,  F_y = Σ −dF_t sin φ + dF_r cos φ

The NumPy side is a straightforward vectorised implementation (blocks of angles × disks × teeth,
float64), written independently of the Rust code from the equations above. Both are timed as a
user would run them (the NumPy time excludes the interpreter start and the import; the runout
time is the whole process). The per-tooth peaks of |F_xy| are compared (they must agree to
0.01 N: same model, same sampling).

    python3 benches/numpy_compare.py [--revolutions 100] [--repeats 5] [--runout PATH]

Prints both rates (M evaluations/s), the wall-time ratio and the largest peak difference.
Needs numpy; builds nothing itself (pass --runout or build `target/release/runout` first).

The kernel alone on this same workload, against the same whole `runout simulate` process in the
same run (issue 18: "the CLI end to end within 1.3× of the kernel"), is the criterion group
`cargo bench -p runout-core --bench force_kernel -- end_to_end`, which prints the ratio.
"""

import argparse
import json
import math
import os
import statistics
import subprocess
import sys
import time

import numpy as np

K, D, HELIX_DEG, DISKS, STEP_DEG = 4, 10.0, 30.0, 50, 0.036
RPM, FZ, AP, AE, MODE = 3240.0, 0.08, 1.0, 2.0, "down"
RUNOUT_UM, RUNOUT_DEG = 8.0, 0.0
KTC, KRC, KAC, KTE, KRE, KAE = 1889.2, 806.1, 291.0, 63.12, 113.7, -3.1


def numpy_forces(revolutions, block=2000):
    """F_x, F_y per angle sample and the per-tooth |F_xy| peaks (owner = last tooth to enter)."""
    r = D / 2
    tanb = math.tan(math.radians(HELIX_DEG))
    pitch = 2 * math.pi / K
    tip = -pitch * np.arange(K)  # ψ_i(0): teeth in cutting order lag by one pitch
    dz = AP / DISKS
    z = (np.arange(DISKS) + 0.5) * dz
    psi = tip[None, :] - z[:, None] * tanb / r  # (disk, tooth)
    e = RUNOUT_UM * 1e-3 * np.array([math.cos(math.radians(RUNOUT_DEG)), math.sin(math.radians(RUNOUT_DEG))])
    radii = np.hypot(r * np.cos(psi) + e[0], r * np.sin(psi) + e[1])  # (disk, tooth)
    a = math.acos(1 - AE / r)
    st, ex = (math.pi - a, math.pi) if MODE == "down" else (0.0, a)
    width = ex - st
    # arc-chip terms per (disk, tooth, m): f_{i,m} = f_z·m (uniform pitch), R_i − R_{i−m}
    m = np.arange(1, K + 1)
    feed = FZ * m  # (m,)
    prev = (np.arange(K)[:, None] - m[None, :]) % K  # (tooth, m)
    dr = radii[:, :, None] - radii[:, prev]  # (disk, tooth, m)
    n = int(math.ceil(revolutions * 360.0 / STEP_DEG - 1e-9))
    step = math.radians(STEP_DEG)
    fx = np.empty(n)
    fy = np.empty(n)
    for b0 in range(0, n, block):
        theta = step * np.arange(b0, min(n, b0 + block))
        phi_raw = theta[:, None, None] + psi[None, :, :]  # (angle, disk, tooth)
        rel = np.mod(phi_raw - st, 2 * math.pi)
        inside = rel <= width
        s = np.sin(phi_raw)
        c = np.cos(phi_raw)
        h = np.min(feed[None, None, None, :] * s[..., None] + dr[None, :, :, :], axis=-1)
        cut = inside & (h > 0)
        h = np.where(cut, h, 0.0)
        ft = np.where(cut, (KTC * h + KTE) * dz, 0.0)
        fr = np.where(cut, (KRC * h + KRE) * dz, 0.0)
        fx[b0:b0 + len(theta)] = (ft * c + fr * s).sum(axis=(1, 2))
        fy[b0:b0 + len(theta)] = (-ft * s + fr * c).sum(axis=(1, 2))
    theta = step * np.arange(n)
    rel0 = np.mod(theta[:, None] + tip[None, :] - st, 2 * math.pi)
    owner = np.argmin(rel0, axis=1)
    fxy = np.hypot(fx, fy)
    peaks = [float(fxy[owner == i].max()) for i in range(K)]
    return n, peaks


def runout_command(binary, revolutions):
    return [
        binary, "simulate",
        "--teeth", str(K), "--diameter-mm", str(D), "--helix-deg", str(HELIX_DEG),
        "--rpm", str(RPM), "--fz-mm", str(FZ), "--ap-mm", str(AP), "--ae-mm", str(AE), "--mode", MODE,
        "--runout-um", str(RUNOUT_UM), "--runout-angle-deg", str(RUNOUT_DEG),
        "--ktc", str(KTC), "--krc", str(KRC), "--kac", str(KAC),
        "--kte", str(KTE), "--kre", str(KRE), "--kae", str(KAE),
        "--revolutions", str(revolutions), "--step-deg", str(STEP_DEG), "--disks", str(DISKS),
        "--chip-model", "arc", "--json", "-",
    ]


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--revolutions", type=float, default=100.0)
    ap.add_argument("--repeats", type=int, default=5)
    root = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
    ap.add_argument("--runout", default=os.path.join(root, "target", "release", "runout"))
    args = ap.parse_args()
    if not os.path.exists(args.runout):
        sys.exit(f"{args.runout}: not found; build it with `cargo build --release -p runout-cli`")

    cmd = runout_command(args.runout, args.revolutions)
    rust_times, rust_peaks = [], None
    for _ in range(args.repeats):
        t0 = time.perf_counter()
        out = subprocess.run(cmd, check=True, capture_output=True, text=True).stdout
        rust_times.append(time.perf_counter() - t0)
        rust_peaks = [p["peak_fxy_N"] for p in json.loads(out)["tooth_peaks"]]
    np_times, np_peaks, n = [], None, 0
    for _ in range(max(1, min(args.repeats, 3))):
        t0 = time.perf_counter()
        n, np_peaks = numpy_forces(args.revolutions)
        np_times.append(time.perf_counter() - t0)
    evals = n * K * DISKS
    tr, tn = statistics.median(rust_times), statistics.median(np_times)
    diff = max(abs(a - b) for a, b in zip(rust_peaks, np_peaks))
    print(f"workload: {n} angles × {K} teeth × {DISKS} disks = {evals / 1e6:.0f} M evaluations")
    print(f"runout simulate (whole process, median of {len(rust_times)}): {tr:.3f} s = {evals / tr / 1e6:.0f} M evaluations/s")
    print(f"NumPy {np.__version__} (median of {len(np_times)}): {tn:.3f} s = {evals / tn / 1e6:.1f} M evaluations/s")
    print(f"ratio (wall): runout is {tn / tr:.1f}× NumPy")
    print(f"per-tooth peak |F_xy| (N): runout {[round(p, 3) for p in rust_peaks]}, NumPy {[round(p, 3) for p in np_peaks]}; max difference {diff:.4f} N")
    if diff > 0.01:
        sys.exit(f"peaks differ by {diff:.4f} N > 0.01 N: the two implementations disagree")


if __name__ == "__main__":
    main()
