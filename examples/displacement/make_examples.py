#!/usr/bin/env python3
"""Write the bundled displacement examples (standard library only, fixed seed).

Known runout: offset e0 = 6 µm at 25° at the tool tip (z = 0) plus a tilt of 0.05 µm/mm at 70°,
4-tooth Ø10 mm end mill, 30° helix. Angles are measured from tooth 0 in the direction of rotation
(docs/conventions.md). Run from the repository root:

    python3 examples/displacement/make_examples.py
"""
import math
import random
from pathlib import Path

HERE = Path(__file__).resolve().parent
RNG = random.Random(20261125)
K, D = 4, 10.0
RHO0_UM, LAM0_DEG = 6.0, 25.0          # runout at z = 0
TILT_UM_PER_MM, TILT_DEG = 0.05, 70.0   # change of the runout vector per mm of height


def runout_at(z_mm):
    """Runout vector (µm) at height z: e(z) = e0 + z·τ."""
    ex = RHO0_UM * math.cos(math.radians(LAM0_DEG)) + z_mm * TILT_UM_PER_MM * math.cos(math.radians(TILT_DEG))
    ey = RHO0_UM * math.sin(math.radians(LAM0_DEG)) + z_mm * TILT_UM_PER_MM * math.sin(math.radians(TILT_DEG))
    return ex, ey


def teeth():
    """Per-tooth readings of a distance laser at z = 0 (3 readings per tooth, σ 0.3 µm)."""
    r_um = D / 2 * 1000.0
    ex, ey = runout_at(0.0)
    gap_um = 400.0
    rows = ["tooth,reading_um"]
    for i in range(K):
        a = -2 * math.pi * i / K  # ψ_i = −2πi/K (conventions.md: cutting order)
        radius = math.hypot(r_um * math.cos(a) + ex, r_um * math.sin(a) + ey)
        for _ in range(3):
            rows.append(f"{i},{gap_um + r_um - radius + RNG.gauss(0, 0.3):.3f}")
    (HERE / "teeth.csv").write_text("\n".join(rows) + "\n")


def heights():
    """Runout (TIR, dial indicator) at 5 heights with its direction, σ 0.2 µm."""
    rows = ["z_mm,tir_um,angle_deg"]
    for z in (2.0, 6.0, 10.0, 14.0, 18.0):
        ex, ey = runout_at(z)
        rho = math.hypot(ex, ey)
        ang = math.degrees(math.atan2(ey, ex))
        rows.append(f"{z:.1f},{2 * rho + RNG.gauss(0, 0.2):.3f},{ang + RNG.gauss(0, 1.0):.2f}")
    (HERE / "heights.csv").write_text("\n".join(rows) + "\n")


def signal():
    """Two distance probes at 0° and 90° on the shank at z = 0, 20 kHz, 3000 rpm ± 0.3 % wander,
    1 s, a once-per-revolution TTL pulse, 0.05 µm white noise and 0.5 µm/s drift."""
    fs, rpm = 20_000.0, 3000.0
    ex, ey = runout_at(0.0)
    rho, lam = math.hypot(ex, ey), math.atan2(ey, ex)
    rows = ["time_s,disp_a_um,disp_b_um,pulse"]
    phi = 0.0
    for n in range(int(fs)):
        t = n / fs
        w = rpm / 60 * 2 * math.pi * (1 + 0.003 * math.sin(2 * math.pi * 0.7 * t))
        drift = 0.5 * t
        a = -rho * math.cos(lam + phi) + drift + RNG.gauss(0, 0.05)
        b = -rho * math.cos(lam + phi - math.pi / 2) + drift + RNG.gauss(0, 0.05)
        pulse = 1 if (phi % (2 * math.pi)) < 0.3 else 0
        rows.append(f"{t:.6f},{a:.4f},{b:.4f},{pulse}")
        phi += w / fs
    (HERE / "signal.csv").write_text("\n".join(rows) + "\n")


if __name__ == "__main__":
    teeth()
    heights()
    signal()
