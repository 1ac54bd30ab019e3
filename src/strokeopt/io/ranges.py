"""Reading a stitch rate or a range of them from the command line: ``--spm 600`` or ``--spm 300:1200:20``.

One parser for every command that sweeps the stitch rate (``simulate``, ``solve``), so a
range means the same and is refused with the same messages everywhere.
"""

from __future__ import annotations

import math

from ..errors import ProblemError


def parse_spm_range(text: str, option: str = "--spm") -> list[float]:
    """``"600"`` -> [600.0]; ``"300:1200:20"`` -> 300, 320, ..., 1200 (START:STOP:STEP, STOP included
    when a whole number of steps reaches it, never passed). Raises ProblemError naming ``option``."""
    parts = text.split(":")
    try:
        nums = [float(p) for p in parts]
    except ValueError:
        raise ProblemError(option, "", f"expected SPM or START:STOP:STEP, got {text!r}") from None
    if len(nums) == 1:
        values = nums
    elif len(nums) == 3:
        start, stop, step = nums
        if not step > 0 or stop < start:
            raise ProblemError(option, "", f"START:STOP:STEP needs STEP > 0 and STOP >= START, got {text!r}")
        if not all(math.isfinite(x) for x in nums):
            raise ProblemError(option, "", f"speeds must be positive, got {text!r}")
        values = [start + k * step for k in range(int((stop - start) / step + 1e-9) + 1)]
    else:
        raise ProblemError(option, "", f"expected SPM or START:STOP:STEP, got {text!r}")
    if not all(math.isfinite(x) and x > 0 for x in values):
        raise ProblemError(option, "", f"speeds must be positive, got {text!r}")
    return [float(x) for x in values]
