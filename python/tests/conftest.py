"""pytest set-up: the repository root, the CLI binary, and one rayon thread.

The jobs' results are compared with the CLI's ``--json`` in the same run. ``RAYON_NUM_THREADS=1``
(as in the CLI snapshot tests) makes the full-signal fit's sums run in a fixed order, so both
sides agree to the last digit; it must be set before the native module starts its pool.
"""

import json
import os
import pathlib
import subprocess

os.environ.setdefault("RAYON_NUM_THREADS", "1")

import pytest  # noqa: E402

ROOT = pathlib.Path(__file__).resolve().parents[2]


def _binary() -> pathlib.Path:
    b = os.environ.get("RUNOUT_BIN")
    if b:
        return pathlib.Path(b)
    target = pathlib.Path(os.environ.get("CARGO_TARGET_DIR", ROOT / "target"))
    return target / "release" / "runout"


@pytest.fixture(scope="session")
def root() -> pathlib.Path:
    return ROOT


@pytest.fixture(scope="session")
def runout_bin() -> pathlib.Path:
    b = _binary()
    if not b.exists():
        pytest.fail(f"the CLI binary {b} is missing: `cargo build --release -p runout-cli` (or set RUNOUT_BIN)")
    return b


@pytest.fixture(autouse=True)
def at_root(monkeypatch):
    # the CLI examples name their inputs relative to the repository root
    monkeypatch.chdir(ROOT)


class Cli:
    def __init__(self, binary):
        self.binary = binary

    def run(self, *args, check=True):
        env = dict(os.environ, RAYON_NUM_THREADS="1", RUST_BACKTRACE="0")
        p = subprocess.run([str(self.binary), *map(str, args)], cwd=ROOT, env=env,
                           capture_output=True, text=True)
        # 3 = the report is written but the runout is not (fully) identified (exit-code table)
        if check and p.returncode not in (0, 3):
            raise AssertionError(f"runout {' '.join(map(str, args))}: {p.stderr}")
        return p

    def json(self, *args):
        """The CLI's JSON report without its `provenance` stamp (the CLI's command line, input
        hashes and time; the Python functions return the report itself)."""
        report = json.loads(self.run(*args, "--json", "-").stdout)
        assert report.pop("provenance")["tool"].startswith("runout "), args
        return report

    def error(self, *args):
        p = self.run(*args, check=False)
        assert p.returncode == 1, p
        first = p.stderr.strip()
        assert first.startswith("error: "), first
        return first[len("error: "):]


@pytest.fixture(scope="session")
def cli(runout_bin) -> Cli:
    return Cli(runout_bin)
