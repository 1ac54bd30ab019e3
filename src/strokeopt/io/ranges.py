"""Reading a stitch rate or a range of them from the command line: ``--spm 600`` or ``--spm 300:1200:20``.

One parser for every command that takes a stitch rate (one value everywhere, a sweep in ``simulate`` and
``solve``), so a rate means the same and is refused with the same messages everywhere: every rate finite and
within :data:`~strokeopt.problem.SPM_RANGE`, a range increasing and at most :data:`MAX_POINTS` rates long.
"""

from __future__ import annotations

import math

from ..errors import ProblemError
from ..problem import SPM_RANGE

#: The most rates a sweep may hold: each is a simulation or a design solve (a second or more each).
MAX_POINTS = 2000


def parse_spm_range(text: str, option: str = "--spm") -> list[float]:
    """``"600"`` -> [600.0]; ``"300:1200:20"`` -> 300, 320, ..., 1200 (START:STOP:STEP, STOP included
    when a whole number of steps reaches it, never passed). Raises ProblemError naming ``option``."""
    parts = text.split(":")
    try:
        nums = [float(p) for p in parts]
    except ValueError:
        raise ProblemError(option, "", f"expected SPM or START:STOP:STEP, got {text!r}") from None
    if len(nums) not in (1, 3):
        raise ProblemError(option, "", f"expected SPM or START:STOP:STEP, got {text!r}")
    if not all(math.isfinite(x) for x in nums):
        raise ProblemError(option, "", f"every number must be finite, got {text!r}")
    lo, hi = SPM_RANGE
    for x in nums[:2]:
        if not lo <= x <= hi:
            raise ProblemError(option, "", f"{x:g} spm is outside the plausible range [{lo:g}, {hi:g}] (in {text!r})")
    if len(nums) == 1:
        return nums
    start, stop, step = nums
    if not step > 0 or stop < start:
        raise ProblemError(option, "", f"START:STOP:STEP needs STEP > 0 and STOP >= START, got {text!r}")
    count = int((stop - start) / step + 1e-9) + 1
    if count > MAX_POINTS:
        raise ProblemError(option, "", f"{text!r} is {count} stitch rates, more than {MAX_POINTS}: use a larger STEP")
    return [float(start + k * step) for k in range(count)]


def parse_spm(text: str, option: str = "--spm") -> float:
    """One stitch rate (``--spm 600``), checked as :func:`parse_spm_range` checks a range's rates."""
    values = parse_spm_range(text, option)
    if len(values) != 1:
        raise ProblemError(option, "", f"expected one stitch rate here, not a range, got {text!r}")
    return values[0]
