"""Every job through the Python package equals the CLI's JSON on the bundled examples; arrays out
have the documented dtypes and shapes; bad input raises with the CLI's message."""

import csv
import io

import numpy as np
import pytest

import runout


def without(d, key):
    """``d`` without the entries named ``key`` at any depth (wall-clock throughput)."""
    if isinstance(d, dict):
        return {k: without(v, key) for k, v in d.items() if k != key}
    if isinstance(d, list):
        return [without(v, key) for v in d]
    return d


def read_csv(text):
    rows = list(csv.reader(io.StringIO(text)))
    cell = {"true": 1.0, "false": 0.0}
    return rows[0], np.array([[cell.get(x, None) if x in cell else float(x) for x in r] for r in rows[1:]])


def test_chip_compare_equals_cli(cli):
    for case in ["examples/chip/section2_5.toml", "examples/chip/joints_no_rtcp.toml"]:
        got = runout.chip_compare(case)
        assert got["schema"] == "runout.chip.compare/1"
        assert without(got, "throughput_points_per_s") == without(
            cli.json("chip", "compare", case), "throughput_points_per_s")


def test_chip_eval_equals_cli_and_arrays(cli, tmp_path):
    case = "examples/chip/flank_path.toml"
    report, chips = runout.chip_eval(case, model="equivalent")
    out = tmp_path / "h.csv"
    assert report == cli.json("chip", "eval", case, "--model", "equivalent", "--out", out)
    n = report["points"]
    assert set(chips) == {"time_s", "spindle_angle_deg", "tooth", "z_mm", "h_mm"}
    for k, a in chips.items():
        assert isinstance(a, np.ndarray) and a.shape == (n,), k
        assert a.dtype == (np.int64 if k == "tooth" else np.float64), k
    assert chips["tooth"].min() == 0 and chips["tooth"].max() == report["teeth"] - 1
    assert (chips["h_mm"] >= 0).all()
    assert ((chips["spindle_angle_deg"] >= 0) & (chips["spindle_angle_deg"] < 360)).all()
    # the CLI's CSV holds the same values rounded (time and h to 1e-9, angle to 1e-4 deg)
    header, table = read_csv(out.read_text())
    assert header == ["time_s", "spindle_angle_deg", "tooth", "z_mm", "h_equivalent_mm"]
    assert table.shape == (n, 5)
    np.testing.assert_allclose(chips["time_s"], table[:, 0], rtol=0, atol=5e-10)
    np.testing.assert_array_equal(chips["tooth"], table[:, 2].astype(np.int64))
    np.testing.assert_allclose(chips["h_mm"], table[:, 4], rtol=0, atol=5e-10)
    d = np.abs(chips["spindle_angle_deg"] - table[:, 1])
    assert (np.minimum(d, 360 - d) <= 5e-5 + 1e-9).all()
    # per-tooth chips: the report's maxima are the arrays' maxima per tooth
    for i, m in enumerate(report["max_h_um_per_tooth"]):
        assert chips["h_mm"][chips["tooth"] == i].max() * 1e3 == pytest.approx(m, rel=1e-12)


def test_grind_compensate_equals_cli_and_path(cli, tmp_path):
    args = dict(bar_diameter_mm=6, probe_tip_radius_mm=1, scheme="bilinear")
    report, path, nc = runout.grind_compensate("examples/grind/probe.csv", **args)
    out = tmp_path / "path.csv"
    assert report == cli.json("grind", "compensate", "--probe", "examples/grind/probe.csv",
                              "--bar-diameter-mm", "6", "--probe-tip-radius-mm", "1",
                              "--scheme", "bilinear", "--path-out", out)
    assert nc is None
    header, table = read_csv(out.read_text())
    assert list(path) == header
    for i, k in enumerate(header):
        assert path[k].dtype == np.float64 and path[k].shape == (table.shape[0],)
        np.testing.assert_array_equal(path[k], table[:, i])


def test_grind_compensate_nc_equals_cli(cli, tmp_path):
    out = tmp_path / "out.nc"
    want = cli.json("grind", "compensate", "--probe", "examples/grind/probe.csv",
                    "--bar-diameter-mm", "6", "--probe-tip-radius-mm", "1",
                    "--edge", "examples/grind/edge.csv", "--nc", "examples/grind/flute.nc",
                    "--out", out)
    report, _, nc = runout.grind_compensate(
        "examples/grind/probe.csv", bar_diameter_mm=6, probe_tip_radius_mm=1,
        edge="examples/grind/edge.csv", nc="examples/grind/flute.nc")
    assert nc == out.read_bytes().decode()
    # the output is named `<nc_text>` (it is returned, not written)
    assert report["nc"]["output"] == "<nc_text>"
    report["nc"]["output"] = want["nc"]["output"]
    assert report == want


def test_grind_check_equals_cli(cli):
    flags = ["--flutes", "1", "--edge-from-mm", "2", "--edge-phase-deg", "18",
             "--points-per-flute", "2001", "--noise-um", "0.5", "--draws", "50"]
    got = runout.grind_check(flutes=1, edge_from_mm=2, edge_phase_deg=18,
                             points_per_flute=2001, noise_um=0.5, draws=50)
    assert got == cli.json("grind", "check", *flags)


def test_shank_stiffness_equals_cli(cli):
    got = runout.shank_stiffness(modulus_gpa=210, diameter_mm=8, tool_length_mm=65,
                                 l1_mm=10, l2_mm=30)
    assert got == cli.json("shank", "stiffness", "--modulus-gpa", "210", "--diameter-mm", "8",
                           "--tool-length-mm", "65", "--l1-mm", "10", "--l2-mm", "30")
    assert got["stiffness_N_per_um"] > 0


def heights_table():
    z = np.arange(1.0, 6.0)
    tir = 2.0 * (3.0 + 0.4 * z) + np.array([0.1, -0.05, 0.02, 0.0, -0.07])
    return z, tir


def test_displacement_heights_from_arrays_equals_cli_on_the_file(cli, tmp_path):
    z, tir = heights_table()
    p = tmp_path / "h.csv"
    p.write_text("z_mm,tir_um\n" + "".join(f"{float(a)!r},{float(b)!r}\n" for a, b in zip(z, tir)))
    want = cli.json("displacement", "heights", p, "--at-mm", "2")
    # the same table as NumPy arrays (named like the file), as bytes, and as the path
    assert runout.displacement_heights((str(p), {"z_mm": z, "tir_um": tir}), at_mm=2) == want
    assert runout.displacement_heights((str(p), p.read_bytes()), at_mm=2) == want
    assert runout.displacement_heights(p, at_mm=2) == want
    # integer and float32 arrays are converted to float64
    got = runout.displacement_heights({"z_mm": z.astype(np.int64), "tir_um": tir.astype(np.float32)})
    assert got["schema"] == "runout.displacement.heights/2"


def test_displacement_teeth_from_arrays(cli, tmp_path):
    k, rho, lam = 4, 0.006, np.radians(-30)  # mm, rad
    teeth = np.repeat(np.arange(k), 3)
    readings_um = -1e3 * rho * np.cos(lam + 2 * np.pi * teeth / k) + 0.05 * np.tile([1, -1, 0], k)
    p = tmp_path / "t.csv"
    p.write_text("tooth,reading_um\n" + "".join(f"{t},{float(r)!r}\n" for t, r in zip(teeth, readings_um)))
    want = cli.json("displacement", "teeth", p, "--teeth", "4", "--diameter-mm", "10")
    got = runout.displacement_teeth((str(p), {"tooth": teeth, "reading_um": readings_um}),
                                    teeth=4, diameter_mm=10)
    assert got == want


# --- bad input --------------------------------------------------------------------------------

def test_errors_carry_the_cli_message(cli, tmp_path):
    p = tmp_path / "bad.csv"
    p.write_text("z_mm,tir_um\n1,2\n2,x\n3,4\n")
    message = cli.error("displacement", "heights", p)
    with pytest.raises(runout.RunoutError) as e:
        runout.displacement_heights(p)
    assert str(e.value) == message
    assert f"{p}:3" in message
    assert isinstance(e.value, ValueError)
    # a missing file
    message = cli.error("chip", "compare", tmp_path / "none.toml")
    with pytest.raises(runout.RunoutError) as e:
        runout.chip_compare(tmp_path / "none.toml")
    assert str(e.value) == message


def test_bad_arguments_raise():
    z, tir = heights_table()
    with pytest.raises(ValueError, match="1-D array, got shape"):
        runout.displacement_heights({"z_mm": np.c_[z, z], "tir_um": tir})
    with pytest.raises(TypeError, match="array of numbers"):
        runout.displacement_heights({"z_mm": ["a", "b"], "tir_um": [1, 2]})
    with pytest.raises(TypeError, match="expected a path, bytes"):
        runout.displacement_heights(42)
    with pytest.raises(ValueError, match="no arrays"):
        runout.displacement_heights({})
    with pytest.raises(runout.RunoutError, match="method: `ridge` is not ols | eq6"):
        runout.displacement_heights({"z_mm": z, "tir_um": tir}, method="ridge")
    with pytest.raises(runout.RunoutError, match="is not finite"):
        runout.displacement_heights({"z_mm": z, "tir_um": tir * np.nan})
    with pytest.raises(runout.RunoutError, match="teeth and diameter_mm"):
        runout.displacement_signal({"time_s": [0, 1.0], "disp_a_um": [0, 1.0]}, teeth=4)
    with pytest.raises(TypeError):
        runout.grind_check(layers="five")
