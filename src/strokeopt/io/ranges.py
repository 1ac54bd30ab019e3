"""A value or a START:STOP:STEP range of them from the command line (``--spm 300:1200:20``, ``--vary
FIELD=0:5:1``): one parser, so a range means the same and is refused with the same messages everywhere."""

from __future__ import annotations

import math

from ..errors import ProblemError

#: The most values a range may hold: each is a simulation or a design solve (a second or more each).
MAX_POINTS = 2000


def parse_range(text: str, option: str, what: str = "VALUE", plausible=(-math.inf, math.inf), unit: str = "",
                plural: str = "values") -> list[float]:
    """``"6"`` -> [6.0]; ``"0:5:1"`` -> 0, 1, ..., 5 (START:STOP:STEP as :func:`parse_spm_range`, whose rules it
    is); every number finite, START and STOP within ``plausible``. Raises ProblemError naming ``option``."""
    parts = text.split(":")
    try:
        nums = [float(p) for p in parts]
    except ValueError:
        raise ProblemError(option, "", f"expected {what} or START:STOP:STEP, got {text!r}") from None
    if len(nums) not in (1, 3):
        raise ProblemError(option, "", f"expected {what} or START:STOP:STEP, got {text!r}")
    if not all(math.isfinite(x) for x in nums):
        raise ProblemError(option, "", f"every number must be finite, got {text!r}")
    lo, hi = plausible
    for x in nums[:2]:
        if not lo <= x <= hi:
            raise ProblemError(option, "", f"{x:g}{' ' + unit if unit else ''} is outside the plausible range "
                                           f"[{lo:g}, {hi:g}] (in {text!r})")
    if len(nums) == 1:
        return nums
    start, stop, step = nums
    if not step > 0 or stop < start:
        raise ProblemError(option, "", f"START:STOP:STEP needs STEP > 0 and STOP >= START, got {text!r}")
    count = int((stop - start) / step + 1e-9) + 1
    if count > MAX_POINTS:
        raise ProblemError(option, "", f"{text!r} is {count} {plural}, more than {MAX_POINTS}: use a larger STEP")
    return [float(start + k * step) for k in range(count)]
