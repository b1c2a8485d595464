"""The README's main job from Python (run from the repository root):
identify runout and cutting coefficients from the two bundled dynamometer recordings, print the
result, and plot the forces and the per-tooth peaks with matplotlib (``pip install matplotlib``).

    python python/examples/identify.py            # writes identify_python.png
"""

import numpy as np

import runout

RECS = ["examples/identify/cut_fz0.05.txt", "examples/identify/cut_fz0.08.txt"]

report = runout.identify(RECS, config="examples/identify/cut.toml")
fit = report["full_signal"]
c = fit["coefficients"]
print(f"rho = {fit['offset_um']:.2f} ± {fit['offset_um_se']:.2f} µm, "
      f"lambda = {fit['angle_deg']:.1f} ± {fit['angle_deg_se']:.1f}° (from tooth 0)")
print(f"K_tc {c['ktc_N_per_mm2']:.1f}, K_rc {c['krc_N_per_mm2']:.1f}, K_ac {c['kac_N_per_mm2']:.1f} N/mm²; "
      f"K_te {c['kte_N_per_mm']:.2f}, K_re {c['kre_N_per_mm']:.2f}, K_ae {c['kae_N_per_mm']:.2f} N/mm")

import matplotlib  # noqa: E402

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

fig, (ax1, ax2) = plt.subplots(1, 2, figsize=(11, 4))
lines = open(RECS[1]).read().splitlines()
data = np.array([[float(x) for x in s.split(",")] for s in lines[lines.index("Time,Fx,Fy,Fz") + 2:]])
t, fx, fy = data[:, 0], data[:, 1], data[:, 2]
sel = (t > 0.3) & (t < 0.3 + 2 * 60 / 3240)  # two revolutions mid-cut
ax1.plot(t[sel], fx[sel], label="F_x")
ax1.plot(t[sel], fy[sel], label="F_y")
ax1.set_xlabel("time (s)")
ax1.set_ylabel("force on the workpiece (N)")
ax1.legend()
for r in report["recordings"]:
    peaks = [p["peak_N"] for p in r["tooth_peaks"]]
    ax2.plot(range(len(peaks)), peaks, "o-", label=f"f_z = {r['fz_mm']} mm")
ax2.set_xlabel("tooth (cutting order)")
ax2.set_ylabel("per-tooth peak |F_xy| (N)")
ax2.legend()
fig.suptitle(f"runout {fit['offset_um']:.2f} µm at {fit['angle_deg']:.1f}°")
fig.tight_layout()
fig.savefig("identify_python.png", dpi=100)
print("wrote identify_python.png")
