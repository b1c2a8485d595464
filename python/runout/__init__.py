"""runout: cutter runout in milling — the jobs of the ``runout`` program on NumPy arrays.

Every function takes its inputs as a path (``str`` / ``os.PathLike``), ``bytes`` (the file's
content), a ``(name, bytes)`` pair, or a mapping of 1-D arrays (``dict``, pandas ``DataFrame``;
converted to float64), and returns the report as a plain ``dict`` with the field names of the
command line's ``--json`` (units in the names: ``_mm``, ``_um``, ``_N``, ``_deg``, ``_s``, ``_hz``).
Waveforms and per-tooth chips come back as dicts of NumPy arrays. A failure raises
:class:`RunoutError` (a ``ValueError``) with the command line's message. The GIL is released while
a job runs, so threads run jobs in parallel.

Units (docs/conventions.md): lengths mm (runout offsets µm), forces N, time s, angles degrees,
stiffness N/µm.
"""

from ._runout import (  # noqa: F401
    SUMMARY_COLUMNS,
    SUMMARY_TEXT_COLUMNS,
    RunoutError,
    __version__,
    batch,
    batch_row,
    identify,
    identify_peaks,
    identify_tests,
    chip_compare,
    chip_eval,
    displacement_heights,
    displacement_signal,
    displacement_teeth,
    grind_check,
    grind_compensate,
    shank_calibrate,
    shank_force,
    shank_stiffness,
    simulate,
)

__all__ = [
    "SUMMARY_COLUMNS",
    "SUMMARY_TEXT_COLUMNS",
    "RunoutError",
    "batch",
    "batch_row",
    "identify",
    "identify_peaks",
    "identify_tests",
    "chip_compare",
    "chip_eval",
    "displacement_heights",
    "displacement_signal",
    "displacement_teeth",
    "grind_check",
    "grind_compensate",
    "shank_calibrate",
    "shank_force",
    "shank_stiffness",
    "simulate",
]
