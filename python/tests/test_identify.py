"""The main job through the Python package: equal to the CLI's JSON on the bundled example, from
files, bytes and NumPy arrays; the peak-table jobs; the batch row."""

import numpy as np
import pytest

import runout

RECS = ["examples/identify/cut_fz0.05.txt", "examples/identify/cut_fz0.08.txt"]
CONFIG = "examples/identify/cut.toml"


def dynoware_arrays(path):
    """The example's channels as NumPy arrays (names row, units row, then data)."""
    lines = open(path).read().splitlines()
    i = lines.index("Time,Fx,Fy,Fz")
    data = np.array([[float(x) for x in line.split(",")] for line in lines[i + 2:]])
    return {"Fx": data[:, 1], "Fy": data[:, 2], "Fz": data[:, 3], "fs": 10000.0}


def test_identify_equals_cli(cli):
    got = runout.identify(RECS, config=CONFIG)
    assert got["schema"] == "runout.identify.recording/3"
    assert got == cli.json("identify", *RECS, "--config", CONFIG)
    fit = got["full_signal"]
    # the example's known runout: 8 µm at −50° (examples/identify/README.md)
    assert abs(fit["offset_um"] - 8.0) < 0.5 and abs(fit["angle_deg"] + 50.0) < 5.0
    # keyword arguments are config keys, as the CLI's flags
    one = runout.identify(RECS[1], config=CONFIG, fz_mm=0.08)
    assert one == cli.json("identify", RECS[1], "--config", CONFIG, "--fz-mm", "0.08")


def test_identify_from_bytes_and_arrays():
    ref = runout.identify(RECS, config=CONFIG)
    blobs = [(p, open(p, "rb").read()) for p in RECS]
    assert runout.identify(blobs, config=("cut.toml", open(CONFIG, "rb").read())) == ref
    arrays = [(p, dynoware_arrays(p)) for p in RECS]
    got = runout.identify(arrays, config=CONFIG)
    # the same samples, the time base from fs instead of the time column: the same fit
    a, b = got["full_signal"], ref["full_signal"]
    for k in ["offset_um", "offset_um_se", "angle_deg", "angle_deg_se", "r_squared"]:
        assert a[k] == pytest.approx(b[k], rel=1e-9, abs=1e-12), k
    assert got["recordings"][0]["format"] == "arrays"
    assert got["recordings"][0]["samples"] == ref["recordings"][0]["samples"]


def test_identify_bad_input(cli, tmp_path):
    p = tmp_path / "bad.txt"
    p.write_text("Time,Fx,Fy,Fz\ns,N,N,N\n0,1,2,3\n0.0001,1,x,3\n")
    message = cli.error("identify", p, "--config", CONFIG, "--fz-mm", "0.05")
    with pytest.raises(runout.RunoutError) as e:
        runout.identify(str(p), config=CONFIG, fz_mm=0.05)
    assert str(e.value) == message
    with pytest.raises(runout.RunoutError, match="unknown keyword argument `fz`"):
        runout.identify(RECS, config=CONFIG, fz=0.05)
    with pytest.raises(runout.RunoutError, match="fz_mm"):
        runout.identify(RECS, config=CONFIG, fz_mm=-1)
    with pytest.raises(runout.RunoutError, match="not a finite number"):
        runout.identify({"Fx": [1.0, np.nan], "Fy": [0.0, 0.0], "fs": 100.0}, config=CONFIG,
                        fz_mm=0.05)


def test_identify_peaks_and_tests_equal_cli(cli):
    got = runout.identify_peaks([366.6, 307.9, 259.9, 326.6], fz_mm=0.08, ae_mm=2, diameter_mm=10)
    assert got == cli.json("identify", "peaks", "--teeth", "4", "--fz-mm", "0.08", "--ae-mm", "2",
                           "--diameter-mm", "10", "--peaks-N", "366.6,307.9,259.9,326.6")
    for t in ["examples/seed003_table1.csv", "examples/seed003_table1.toml"]:
        assert runout.identify_tests(t) == cli.json("identify", "tests", t)
    with pytest.raises(runout.RunoutError, match="mode"):
        runout.identify_peaks([1.0, 2.0], fz_mm=0.1, mode="sideways")


def test_batch_row(tmp_path):
    row = runout.batch_row(RECS[1], config=CONFIG, fz_mm=0.08)
    assert list(row) == runout.SUMMARY_COLUMNS
    assert row["status"] == "ok" and row["file"] == RECS[1]
    ref = runout.identify(RECS[1], config=CONFIG, fz_mm=0.08)["full_signal"]
    assert row["offset_um"] == ref["offset_um"] and row["kae_se_N_per_mm"] == ref["coefficients"]["kae_N_per_mm_se"]
    bad = runout.batch_row(("broken.txt", b"nothing"), config=CONFIG, fz_mm=0.08)
    assert bad["status"] == "error" and "broken.txt" in bad["error"] and bad["offset_um"] is None
