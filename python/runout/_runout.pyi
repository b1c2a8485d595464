"""Type stubs of the native module ``runout._runout`` (re-exported by ``runout``).

Sources: a path (``str`` / ``os.PathLike``), ``bytes`` (the file's content), a ``(name, bytes)``
pair, or a mapping of 1-D arrays (``dict`` / pandas ``DataFrame``; converted to float64), optionally
as ``(name, mapping)``. Reports are dicts with the CLI's ``--json`` field names (units in the names).
"""

import os
from typing import Any, Dict, List, Mapping, Optional, Sequence, Tuple, Union

import numpy as np
import numpy.typing as npt

ArrayLike = npt.ArrayLike
Arrays = Mapping[str, ArrayLike]
SourceLike = Union[
    str,
    "os.PathLike[str]",
    bytes,
    Arrays,
    Tuple[str, bytes],
    Tuple[str, Arrays],
]
Report = Dict[str, Any]
Columns = Dict[str, "npt.NDArray[np.float64]"]

__version__: str

class RunoutError(ValueError):
    """A job failed: bad input or parameters; the message is the command line's."""

def shank_stiffness(
    *,
    modulus_gpa: float,
    diameter_mm: float,
    tool_length_mm: float,
    l1_mm: float,
    l2_mm: float,
    ap_mm: Optional[float] = None,
    holder_stiffness_Nm_per_rad: Optional[float] = None,
    density_kg_per_m3: Optional[float] = None,
) -> Report:
    """Shank stiffness K_δ (N/µm) of the beam model and the first bending mode (Hz).

    modulus_gpa (GPa), diameter_mm, tool_length_mm, l1_mm, l2_mm (mm from the holder face),
    ap_mm (mm), holder_stiffness_Nm_per_rad (N·m/rad), density_kg_per_m3 (kg/m³).
    Returns ``runout.shank.stiffness/1``.
    """

def shank_force(
    recording: SourceLike,
    config: SourceLike,
    *,
    sample_rate_hz: Optional[float] = None,
    series: bool = True,
) -> Tuple[Report, Optional[Columns]]:
    """Cutting force (N) and runout (µm) from shank displacement sensors (methods.md §3).

    Returns (``runout.shank.force/2``, series): series holds the time series as float64 arrays
    named as the CLI's CSV columns (``time_s``, forces in N, deflections in mm), or None.
    """

def shank_calibrate(
    recording: SourceLike,
    config: SourceLike,
    *,
    force_channel: str,
    load_point_mm: Optional[float] = None,
    load_point_channel: Optional[str] = None,
    sample_rate_hz: Optional[float] = None,
) -> Report:
    """Static calibration of K_δ (N/µm) against a load cell (N). Returns ``runout.shank.calibration/2``."""

def displacement_teeth(
    readings: SourceLike,
    *,
    teeth: int,
    diameter_mm: float,
    helix_deg: float = 0.0,
    height_mm: float = 0.0,
    method: str = "joint",
    offset_um: Optional[float] = None,
    offset_se_um: Optional[float] = None,
    noise_um: Optional[float] = None,
    phase_deg: Optional[float] = None,
    sensor: str = "distance",
    inclination_deg: float = 0.0,
    beam_offset_mm: float = 0.0,
    fz_mm: Optional[float] = None,
    hole_path_mm: Optional[float] = None,
) -> Report:
    """Runout ρ (µm), λ (deg) from per-tooth readings (``tooth``, ``reading_um``). ``runout.displacement.teeth/2``."""

def displacement_heights(
    table: SourceLike, *, at_mm: float = 0.0, method: str = "ols"
) -> Report:
    """Runout at several heights (``z_mm``, ``tir_um``/``runout_um``[, ``angle_deg``]) → at ``at_mm`` (mm).
    ``runout.displacement.heights/2``."""

def displacement_signal(
    recording: SourceLike,
    *,
    sensor_angles_deg: Optional[Sequence[float]] = None,
    reference: str = "auto",
    rpm_min: float = 60.0,
    rpm_max: float = 60000.0,
    surface_diameter_mm: Optional[float] = None,
    tooth0_deg: float = 0.0,
    from_s: Optional[float] = None,
    to_s: Optional[float] = None,
    teeth: Optional[int] = None,
    diameter_mm: Optional[float] = None,
    helix_deg: float = 0.0,
    height_mm: float = 0.0,
    sensor: str = "distance",
    inclination_deg: float = 0.0,
    beam_offset_mm: float = 0.0,
    fz_mm: Optional[float] = None,
    hole_path_mm: Optional[float] = None,
) -> Report:
    """Runout vector from a raw displacement signal (``time_s``, ``disp_<name>_um``, ``pulse``…).
    ``runout.displacement.signal/2``."""

def grind_compensate(
    probe: SourceLike,
    *,
    bar_diameter_mm: Optional[float] = None,
    generatrix: Optional[SourceLike] = None,
    probe_angle_sense: str = "ccw",
    probe_tip_radius_mm: float = 0.0,
    miss_limit_um: float = 200.0,
    duplicates: str = "error",
    missing: str = "error",
    scheme: str = "first-harmonic",
    outside: str = "clamp",
    edge: Optional[Union[str, SourceLike]] = None,
    edge_diameter_mm: Optional[float] = None,
    flutes: int = 4,
    helix_deg: float = 30.0,
    edge_from_mm: float = 0.0,
    edge_to_mm: Optional[float] = None,
    points_per_flute: int = 200,
    edge_phase_deg: float = 0.0,
    nc: Optional[SourceLike] = None,
    nc_map: str = "index",
    nc_moves: str = "feed",
    nc_decimals: int = 4,
) -> Tuple[Report, Columns, Optional[str]]:
    """Grinding compensation of the bar clamping error (methods.md §5).

    Returns (``runout.grind.compensate/2``, path columns as in ``--path-out`` (mm, µm), the
    compensated NC program text or None).
    """

def grind_check(
    *,
    bar_diameter_mm: float = 6.0,
    offset_um: Tuple[float, float] = (8.0, -4.0),
    tilt_um_per_mm: Tuple[float, float] = (0.3, 0.5),
    layers: int = 5,
    angles: int = 8,
    u_from_mm: float = 2.0,
    u_to_mm: float = 28.0,
    noise_um: float = 0.0,
    draws: int = 1,
    seed: int = 1,
    outside: str = "clamp",
    edge: str = "flat",
    edge_diameter_mm: Optional[float] = None,
    flutes: int = 4,
    helix_deg: float = 30.0,
    edge_from_mm: float = 0.0,
    edge_to_mm: Optional[float] = None,
    points_per_flute: int = 200,
    edge_phase_deg: float = 0.0,
) -> Report:
    """Simulation check of the grinding compensation (methods.md §5.5). ``runout.grind.check/2``."""

def chip_compare(
    config: SourceLike,
    *,
    case: Optional[str] = None,
    phase_refinement: bool = True,
    fit_k: bool = False,
) -> Report:
    """Chip-thickness models against the exact IUCT on a case set. ``runout.chip.compare/1``."""

def chip_eval(
    config: SourceLike, *, case: Optional[str] = None, model: str = "exact"
) -> Tuple[Report, Dict[str, np.ndarray]]:
    """Chip thickness along a case's motion.

    Returns (``runout.chip.eval/1``, chips): ``time_s`` (s), ``spindle_angle_deg`` (deg),
    ``tooth`` (int64), ``z_mm`` (mm), ``h_mm`` (mm), one element per point.
    """

SUMMARY_COLUMNS: List[str]
"""Columns of the batch summary (``runout batch``'s CSV header, ``batch_row``'s keys)."""
SUMMARY_TEXT_COLUMNS: List[str]
"""The summary's text columns; the others are float (None / empty when not available)."""

def identify(
    recordings: Union[SourceLike, Sequence[SourceLike]],
    config: Optional[SourceLike] = None,
    **keys: Union[float, int, str, bool, Sequence[float], Sequence[str]],
) -> Report:
    """Runout ρ (µm), λ (deg) ± SE and the cutting coefficients (N/mm², N/mm) from force recordings.

    ``recordings``: one source or a list (forces in N; arrays as ``{"Fx": …, "Fy": …, "Fz": …,
    "fs": 10000.0}``); ``config``: cut.toml; ``keys``: config keys overriding it (``fz_mm`` (mm,
    one per recording), ``teeth``, ``diameter_mm``, ``helix_deg``, ``rpm``, ``ap_mm``, ``ae_mm``,
    ``mode``, ``axes``, ``sample_rate_hz`` (Hz), ``chain``, …). Returns
    ``runout.identify.recording/3`` (the CLI's ``--json``).
    """

def simulate(
    config: Optional[SourceLike] = None,
    *,
    sample_rate_hz: Optional[float] = None,
    **keys: Union[float, int, str, bool, Sequence[float], Sequence[str]],
) -> Tuple[Report, Dict[str, np.ndarray]]:
    """Mechanistic milling forces (N) with runout (methods.md §0, §4.1); the CLI's ``runout simulate``.

    ``config``: case TOML; ``sample_rate_hz`` (Hz) sets the angular step; ``keys``: case keys
    overriding it (``teeth``, ``diameter_mm`` (mm), ``helix_deg`` (deg), ``rpm``, ``fz_mm``,
    ``ap_mm``, ``ae_mm`` (mm), ``mode``, ``runout_um`` (µm), ``runout_angle_deg`` (deg),
    ``ktc``/``krc``/``kac`` (N/mm²), ``kte``/``kre``/``kae`` (N/mm), ``revolutions``, ``step_deg``
    (deg), ``disks``, ``chip_model`` (arc | exact | equivalent), …).

    Returns (``runout.simulate/1`` as the CLI's ``--json``, series): float64 arrays of one element
    per sample — ``time_s`` (s), ``angle_deg`` (spindle angle, deg), ``fx_N``, ``fy_N``, ``fz_N``
    (N, on the workpiece), ``torque_Nm`` (N·m) — and ``h_mm`` of shape (teeth, samples): each
    tooth's chip thickness at the lowest disk (mm).
    """

def identify_peaks(
    peaks_N: ArrayLike,
    *,
    fz_mm: float,
    peaks_se_N: Optional[ArrayLike] = None,
    mode: str = "up",
    ae_mm: Optional[float] = None,
    diameter_mm: Optional[float] = None,
    peak_immersion_deg: Optional[float] = None,
    closed_period: bool = False,
) -> Report:
    """Seed-003 sine fit of per-tooth peaks (N). ``runout.identify.peaks/2``."""

def identify_tests(
    table: SourceLike,
    *,
    diameter_mm: Optional[float] = None,
    ae_mm: Optional[float] = None,
    mode: Optional[str] = None,
    peak_immersion_deg: Optional[float] = None,
    closed_period: bool = False,
) -> Report:
    """Several peak tests: per-test fits, regressions, K_T/K_R, pooled fit. ``runout.identify.tests/1``."""

def batch_row(
    recording: SourceLike,
    config: Optional[SourceLike] = None,
    **keys: Union[float, int, str, bool, Sequence[float], Sequence[str]],
) -> Dict[str, Union[str, float, None]]:
    """One recording identified, as its ``runout batch`` summary row (keys ``SUMMARY_COLUMNS``).

    A recording that cannot be identified gives ``status="error"`` and the message (no exception).
    """

def batch(
    inputs: Union[str, Sequence[str]],
    config: SourceLike,
    summary: Union[str, "os.PathLike[str]"],
    *,
    threads: Optional[int] = None,
    retry_errors: bool = False,
    **keys: Union[float, int, str, bool, Sequence[float], Sequence[str]],
) -> Report:
    """``runout batch`` in-process: folders / glob patterns / files → summary CSV. ``runout.batch/1``."""
