"""The GIL is released while a job runs (``Python::detach``).

Two checks: (1) while a job runs in a thread, the main thread keeps running Python code (the
longest pause between its iterations is a small part of the job's time; with the GIL held it would
be the whole job); (2) two jobs in two threads take clearly less wall time than the same two jobs
one after the other. With the GIL held the ratio would be ≥ 1; on 2 free cores it is ≈ 0.5. The
test asserts ratio < 0.8 (margin for a shared, loaded CI machine) and prints the measured ratio.
Each job is single-threaded (``RAYON_NUM_THREADS=1``, conftest), so the serial run does not
already use both cores.
"""

import os
import threading
import time

import pytest

import runout

CASE = "examples/chip/section2_5.toml"


def job():
    return runout.chip_compare(CASE)


def test_python_runs_while_a_job_runs():
    t0 = time.perf_counter()
    job()
    alone = time.perf_counter() - t0
    th = threading.Thread(target=job)
    stamps = []
    th.start()
    while th.is_alive():
        stamps.append(time.perf_counter())
        sum(range(1000))  # pure-Python work, needs the GIL
    th.join()
    gaps = [b - a for a, b in zip(stamps, stamps[1:])]
    print(f"job alone {alone:.3f} s; main-thread iterations {len(stamps)}, longest pause {max(gaps):.4f} s")
    assert len(stamps) > 100
    assert max(gaps) < 0.25 * alone


@pytest.mark.skipif((os.cpu_count() or 1) < 2, reason="needs 2 cores")
def test_two_jobs_in_threads_are_faster_than_serial():
    ratios = []
    for _ in range(2):
        t0 = time.perf_counter()
        job()
        job()
        serial = time.perf_counter() - t0
        threads = [threading.Thread(target=job) for _ in range(2)]
        t0 = time.perf_counter()
        for t in threads:
            t.start()
        for t in threads:
            t.join()
        concurrent = time.perf_counter() - t0
        ratios.append(concurrent / serial)
        print(f"serial {serial:.3f} s, two threads {concurrent:.3f} s, ratio {concurrent / serial:.2f}")
    assert min(ratios) < 0.8, ratios
