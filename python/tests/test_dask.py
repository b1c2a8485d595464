"""The Dask recipe of docs/batch.md on a 2-worker LocalCluster: 50 generated recordings (some
broken) mapped with ``runout.batch_row``; the summary equals ``runout batch``'s on the same files,
and both throughputs are printed (same run, same machine)."""

import glob
import os
import time

import numpy as np
import pytest

import runout

pd = pytest.importorskip("pandas")
distributed = pytest.importorskip("dask.distributed")
db = pytest.importorskip("dask.bag")

CONFIG = """teeth = 4
diameter_mm = 10.0
helix_deg = 0.0
rpm = 3240
fz_mm = 0.05
ap_mm = 2.0
ae_mm = 2.0
mode = "down"
axes = "x = Fx, y = Fy, z = Fz"
peak_component = "fxy"
"""


def simulate(cli, path, i):
    cli.run("simulate", "--teeth", "4", "--diameter-mm", "10", "--helix-deg", "0", "--rpm", "3240",
            "--fz-mm", "0.05", "--ap-mm", "2", "--ae-mm", "2", "--mode", "down",
            "--ktc", "1889.2", "--krc", "806.1", "--kac", "291", "--kte", "63.12",
            "--kre", "113.7", "--kae", "-3.1", "--revolutions", "14", "--disks", "1",
            "--sample-rate-hz", "5000", "--noise-percent", "2", "--air-cut-s", "0.05",
            "--runout-um", str(4 + i % 6), "--runout-angle-deg", str(-120 + 37 * (i % 6)),
            "--seed", str(i + 1), "--recording", path)


@pytest.fixture(scope="module")
def recordings(cli, tmp_path_factory):
    d = tmp_path_factory.mktemp("dask")
    (d / "cut.toml").write_text(CONFIG)
    cuts = d / "cuts"
    cuts.mkdir()
    bases = []
    for i in range(6):
        p = d / f"base{i}.txt"
        simulate(cli, p, i)
        bases.append(p.read_bytes())
    bad = []
    for i in range(50):
        p = cuts / f"cut{i:02}.txt"
        if i % 9 == 4:
            p.write_bytes(b"not a recording\n" if i % 2 else bases[0][: len(bases[0]) // 30])
            bad.append(str(p))
        else:
            p.write_bytes(bases[i % 6])
    return d, sorted(glob.glob(str(cuts / "*.txt"))), bad


def normalise(df):
    df = df.drop(columns=["time"]).sort_values("file").reset_index(drop=True)
    text = list(runout.SUMMARY_TEXT_COLUMNS)
    text.remove("time")
    df[text] = df[text].fillna("").astype(str)
    return df


def test_dask_summary_equals_runout_batch(cli, recordings):
    d, files, bad = recordings
    # the CLI batch, single process, 2 threads
    t0 = time.perf_counter()
    cli.run("batch", *files, "--config", d / "cut.toml", "--summary", d / "summary.csv",
            "--threads", "2")
    cli_s = time.perf_counter() - t0
    # exact: the CSV holds shortest round-trip floats; pandas ≥ 3 parses them exactly by default
    # (and deprecates the option), earlier versions need float_precision="round_trip"
    exact = {} if int(pd.__version__.split(".")[0]) >= 3 else {"float_precision": "round_trip"}
    want = pd.read_csv(d / "summary.csv", keep_default_na=False, na_values=[""], **exact)
    assert len(want) == 50 and (want.status == "error").sum() == len(bad)

    # the recipe: a 2-worker LocalCluster, config as bytes with the tasks
    config = ("cut.toml", (d / "cut.toml").read_bytes())
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                                  dashboard_address=None) as cluster, \
            distributed.Client(cluster) as client:
        client.wait_for_workers(2)
        t0 = time.perf_counter()
        rows = db.from_sequence(files, partition_size=5).map(runout.batch_row, config=config)
        got = pd.DataFrame(rows.compute(), columns=runout.SUMMARY_COLUMNS)
        dask_s = time.perf_counter() - t0
        # byte blobs (no shared filesystem): the names are what the summary shows
        blobs = db.from_sequence(files, partition_size=5).map(lambda f: (f, open(f, "rb").read()))
        from_blobs = pd.DataFrame(blobs.map(runout.batch_row, config=config).compute(),
                                  columns=runout.SUMMARY_COLUMNS)
    print(f"50 recordings: runout batch (2 threads) {50 / cli_s:.1f} recordings/s; "
          f"Dask LocalCluster (2 workers) {50 / dask_s:.1f} recordings/s")
    pd.testing.assert_frame_equal(normalise(got), normalise(want), check_exact=True)
    # from bytes: the same values; `time` is the header's or empty (bytes have no file time)
    pd.testing.assert_frame_equal(normalise(from_blobs), normalise(want), check_exact=True)
    assert sorted(got.file[got.status == "error"]) == sorted(bad)
    assert (got.offset_um[got.status == "ok"] > 2).all()
