#!/usr/bin/env python3
"""Whole-process A/B of `runout identify` on one recording: every round runs each binary once,
in a random order, so that the machine's drift (load, the host of a virtual machine) falls on all
binaries alike. Prints the median, first quartile, minimum and mean wall time, the rate and the
median CPU time (user + system) of each binary.

    python3 benches/identify_ab.py FILE --config CUT.toml --rounds 25 BINARY [BINARY ...]

A binary may be a wrapper script (e.g. one that sets an environment variable) to compare two
settings of one build.
"""
import argparse
import os
import random
import resource
import statistics
import subprocess
import time


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("file", help="the recording")
    ap.add_argument("binaries", nargs="+", help="runout binaries (or wrappers) to compare")
    ap.add_argument("--config", required=True, help="the cut's TOML (as for `identify --config`)")
    ap.add_argument("--rounds", type=int, default=21)
    a = ap.parse_args()
    wall = {b: [] for b in a.binaries}
    cpu = {b: [] for b in a.binaries}
    for _ in range(a.rounds):
        order = a.binaries[:]
        random.shuffle(order)
        for b in order:
            r0 = resource.getrusage(resource.RUSAGE_CHILDREN)
            t0 = time.perf_counter()
            subprocess.run(
                [b, "identify", a.file, "--config", a.config, "--json", "-", "--quiet"],
                stdout=subprocess.DEVNULL,
                stderr=subprocess.DEVNULL,
                check=True,
            )
            wall[b].append(time.perf_counter() - t0)
            r1 = resource.getrusage(resource.RUSAGE_CHILDREN)
            cpu[b].append(r1.ru_utime - r0.ru_utime + r1.ru_stime - r0.ru_stime)
    size = os.path.getsize(a.file)
    print(f"{a.file}: {size / 1e6:.1f} MB, {a.rounds} rounds, load average {os.getloadavg()[0]:.2f}")
    for b in a.binaries:
        s = sorted(wall[b])
        m = statistics.median(s)
        print(
            f"{b}: median {m:.3f} s = {size / m / 1e6:.0f} MB/s, p25 {s[len(s) // 4]:.3f} s, "
            f"min {s[0]:.3f} s, mean {statistics.mean(s):.3f} s, CPU median {statistics.median(cpu[b]):.3f} s"
        )


if __name__ == "__main__":
    main()
