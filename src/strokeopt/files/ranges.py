"""Reading a stitch rate or a range of them from the command line: ``--spm 600`` or ``--spm 300:1200:20``.

One parser for every command that takes a stitch rate (one value everywhere, a sweep in ``simulate`` and
``solve``), so a rate means the same and is refused with the same messages everywhere: every rate finite and
within :data:`~strokeopt.problem.SPM_RANGE`, a range increasing and at most :data:`MAX_POINTS` rates long.
"""

from __future__ import annotations

import math

from ..errors import ProblemError
from ..io.ranges import MAX_POINTS, parse_range  # noqa: F401  (MAX_POINTS: the readers of a sweep's length)
from ..problem import SPM_RANGE


def parse_spm_range(text: str, option: str = "--spm") -> list[float]:
    """``"600"`` -> [600.0]; ``"300:1200:20"`` -> 300, 320, ..., 1200 (START:STOP:STEP, STOP included
    when a whole number of steps reaches it, never passed). Raises ProblemError naming ``option``."""
    lo, hi = SPM_RANGE
    return parse_range(text, option, "SPM", (lo, hi), "spm", "stitch rates")


def parse_spm(text: str, option: str = "--spm") -> float:
    """One stitch rate (``--spm 600``), checked as :func:`parse_spm_range` checks a range's rates."""
    values = parse_spm_range(text, option)
    if len(values) != 1:
        raise ProblemError(option, "", f"expected one stitch rate here, not a range, got {text!r}")
    return values[0]


#: The cam table's master resolution: from 0.001 deg (360 000 points per cycle) to 45 deg (8 points).
CAM_RESOLUTION_DEG = (0.001, 45.0)
#: The master axis counts per cam cycle (``--master-counts``): an encoder's or a bus's 32-bit position.
MASTER_COUNTS_RANGE = (8, 2**31)


def parse_cam_resolution(text: str, option: str = "--cam-table-resolution") -> float:
    """The cam table's resolution in degrees of the master axis: ``"0.1"`` or ``"0.1deg"`` (degrees per
    point), or ``"720/cycle"`` (points per cam cycle). Every point count must be whole (360 deg divided
    into equal steps) and the resolution within :data:`CAM_RESOLUTION_DEG`."""
    raw = text.strip().lower()
    lo, hi = CAM_RESOLUTION_DEG
    try:
        if raw.endswith("/cycle"):
            points = float(raw[: -len("/cycle")])
            if not (math.isfinite(points) and points == round(points) and points > 0):
                raise ProblemError(option, "", f"points per cycle must be a whole number, got {text!r}")
            deg = 360.0 / points
        else:
            deg = float(raw[:-3] if raw.endswith("deg") else raw)
    except ValueError:
        raise ProblemError(option, "", f"expected degrees per point (0.1 or 0.1deg) or points per cam cycle "
                                       f"(3600/cycle), got {text!r}") from None
    if not (math.isfinite(deg) and lo <= deg <= hi):
        raise ProblemError(option, "", f"{text!r} is {deg:g} deg per point, outside the plausible range "
                                       f"[{lo:g}, {hi:g}] deg ({round(360 / hi)} to {round(360 / lo)} points per cycle)")
    points = 360.0 / deg
    if abs(points - round(points)) > 1e-6 * points:
        raise ProblemError(option, "", f"{deg:g} deg does not divide the 360 deg cam cycle into whole points "
                                       f"({points:.4g}): use e.g. {360 / max(round(points), 1):g}deg or "
                                       f"{max(round(points), 1)}/cycle")
    return 360.0 / round(points)


def check_master_counts(counts: int, points: int, option: str = "--master-counts") -> int:
    """The master counts per cam cycle: within :data:`MASTER_COUNTS_RANGE` and a whole number of counts
    per table point (a point falls on a count)."""
    lo, hi = MASTER_COUNTS_RANGE
    if not lo <= counts <= hi:
        raise ProblemError(option, "", f"{counts} is outside the plausible range [{lo}, {hi}] counts per cam cycle")
    if counts % points:
        raise ProblemError(option, "", f"{counts} counts per cycle is not a whole number of counts per table "
                                       f"point ({points} points): choose a resolution whose point count divides it")
    return counts
