"""`runout.simulate` equals `runout simulate --json` (without its provenance stamp) on the bundled
example; its arrays have the documented dtypes and shapes and hold the CLI's `--out` CSV at full
precision; bad input raises with the CLI's message."""

import csv

import numpy as np
import pytest

import runout

CASE = "examples/simulate.toml"


def read_csv(path):
    with open(path, newline="") as f:
        rows = list(csv.reader(f))
    return rows[0], np.array([[float(x) for x in r] for r in rows[1:]])


def test_simulate_equals_cli_and_series(cli, tmp_path):
    out = tmp_path / "forces.csv"
    report, series = runout.simulate(CASE)
    assert report["schema"] == "runout.simulate/1"
    assert report == cli.json("simulate", CASE, "--out", out)
    n, k = report["samples"], report["inputs"]["teeth"]
    assert n > 1000 and k == 4
    assert set(series) == {"time_s", "angle_deg", "fx_N", "fy_N", "fz_N", "torque_Nm", "h_mm"}
    for name, a in series.items():
        assert isinstance(a, np.ndarray) and a.dtype == np.float64, name
        assert a.shape == ((k, n) if name == "h_mm" else (n,)), (name, a.shape)
    # the CSV holds the same series, rounded as written: time to 1e-9 s, angle to 1e-4 deg,
    # forces and torque to 1e-6, chips to 1e-7 mm (half a unit in the last place allowed)
    header, table = read_csv(out)
    assert header == ["time_s", "angle_deg", "fx_N", "fy_N", "fz_N", "torque_Nm"] + [
        f"h{i}_mm" for i in range(k)]
    assert table.shape == (n, 6 + k)
    for j, (name, atol) in enumerate([("time_s", 5e-10), ("angle_deg", 5e-5), ("fx_N", 5e-7),
                                      ("fy_N", 5e-7), ("fz_N", 5e-7), ("torque_Nm", 5e-7)]):
        np.testing.assert_allclose(series[name], table[:, j], rtol=0, atol=atol * (1 + 1e-9),
                                   err_msg=name)
    np.testing.assert_allclose(series["h_mm"], table[:, 6:].T, rtol=0, atol=5e-8 * (1 + 1e-9))
    # the report's means are the arrays' means (the same sums, summed in a possibly different
    # order: 1e-12 relative)
    for axis in "xyz":
        assert series[f"f{axis}_N"].mean() == pytest.approx(report[f"mean_f{axis}_N"], rel=1e-12)
    assert series["torque_Nm"].mean() == pytest.approx(report["mean_torque_Nm"], rel=1e-12)
    # per-tooth chips: each tooth's largest chip at the lowest disk is at most its largest over
    # all disks (the report's), and the tooth cuts (a chip > 0 somewhere)
    for i, p in enumerate(report["tooth_peaks"]):
        assert p["tooth"] == i
        assert 0 < series["h_mm"][i].max() <= p["max_chip_mm"] * (1 + 1e-12)
    assert (series["h_mm"] >= 0).all()


def test_simulate_keywords_are_the_cli_flags(cli):
    report, series = runout.simulate(CASE, runout_um=12, chip_model="exact", revolutions=1,
                                     sample_rate_hz=20000)
    assert report == cli.json("simulate", CASE, "--runout-um", "12", "--chip-model", "exact",
                              "--revolutions", "1", "--sample-rate-hz", "20000")
    assert report["inputs"]["runout_um"] == 12 and report["inputs"]["chip_model"] == "exact"
    # 20 kHz at 3240 rpm: a step of 360·3240/60/20000 = 0.972 deg
    assert report["inputs"]["step_deg"] == pytest.approx(0.972, rel=1e-12)
    assert np.diff(series["angle_deg"]) == pytest.approx(0.972, rel=1e-9)
    # a case from keywords alone (no config file)
    keys = dict(teeth=2, diameter_mm=8, helix_deg=0, rpm=6000, fz_mm=0.05, ap_mm=1, ae_mm=8,
                mode="slot", ktc=1000, krc=400, kac=0, kte=0, kre=0, kae=0, revolutions=1,
                step_deg=1, disks=1)
    report, series = runout.simulate(**keys)
    flags = [a for key, v in keys.items() for a in (f"--{key.replace('_', '-')}", str(v))]
    assert report == cli.json("simulate", *flags)
    assert series["h_mm"].shape == (2, report["samples"])


def test_simulate_errors_carry_the_cli_message(cli, tmp_path):
    bad = tmp_path / "bad.toml"
    bad.write_text(open(CASE).read().replace("teeth = 4 ", 'teeth = "four" '))
    message = cli.error("simulate", bad)
    with pytest.raises(runout.RunoutError) as e:
        runout.simulate(bad)
    assert str(e.value) == message
    assert str(bad) in message and "teeth" in message
    # a missing file
    message = cli.error("simulate", tmp_path / "none.toml")
    with pytest.raises(runout.RunoutError) as e:
        runout.simulate(tmp_path / "none.toml")
    assert str(e.value) == message
    # an unknown keyword lists the keys; a bad value names the key
    with pytest.raises(runout.RunoutError, match="unknown keyword argument `runout`.*runout_um"):
        runout.simulate(CASE, runout=8)
    with pytest.raises(runout.RunoutError, match="chip_model"):
        runout.simulate(CASE, chip_model="parabola")
