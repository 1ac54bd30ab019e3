"""Characteristic values of a motion law, computed from its own derivatives: ``C_v = max|y'|``,
``C_a = max|y''|``, ``C_j = max|y'''|`` and the continuity class against a dwell (the laws of
motion/laws.py: anything with ``derivatives(x, order)`` and ``breaks``)."""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import cache

import numpy as np

#: Derivative orders by name, as reported by :attr:`Characteristics.first_jump`.
DERIVATIVE_NAMES = ("position", "velocity", "acceleration", "jerk", "snap", "crackle")


@dataclass(frozen=True)
class Characteristics:
    """Characteristic values of a law: peaks of |y'|, |y''|, |y'''| on [0, 1].

    ``C_j`` is ``inf`` where the acceleration jumps (at the ends against a dwell
    or inside): the jerk is then an impulse. ``continuity`` is the highest
    derivative order that is continuous over a dwell-move-dwell sequence
    (1: velocity continuous, acceleration jumps; 2: acceleration continuous,
    jerk jumps; 3: jerk continuous).
    """

    C_v: float
    C_a: float
    C_j: float
    continuity: int

    @property
    def first_jump(self) -> str:
        return DERIVATIVE_NAMES[self.continuity + 1]


@cache
def characteristics_of(law) -> Characteristics:
    c_v, c_a, c_j = (_peak(law, k) for k in (1, 2, 3))
    continuity = _continuity(law)
    if continuity < 2:
        c_j = math.inf
    return Characteristics(C_v=c_v, C_a=c_a, C_j=c_j, continuity=continuity)


def _peak(law, order: int, samples: int = 4001) -> float:
    """max |y^(order)| on [0, 1]: a grid that includes the law's joints (one side each),
    then a golden-section refinement around the best grid point."""
    tiny = 1e-12
    joints = [b + d for b in law.breaks for d in (-tiny, tiny)]
    x = np.unique(np.concatenate([np.linspace(0.0, 1.0, samples), joints]))
    values = np.abs(law.derivatives(x, order)[order])
    i = int(np.argmax(values))
    best = float(values[i])
    if 0 < i < len(x) - 1:
        lo, hi = x[i - 1], x[i + 1]
        f = lambda z: abs(float(law.derivatives([z], order)[order][0]))  # noqa: E731
        ratio = (math.sqrt(5) - 1) / 2
        a, b = hi - ratio * (hi - lo), lo + ratio * (hi - lo)
        fa, fb = f(a), f(b)
        for _ in range(60):
            if fa > fb:
                hi, b, fb = b, a, fa
                a = hi - ratio * (hi - lo)
                fa = f(a)
            else:
                lo, a, fa = a, b, fb
                b = lo + ratio * (hi - lo)
                fb = f(b)
        best = max(best, fa, fb)
    return best


def _continuity(law, delta: float = 1e-9) -> int:
    """Highest derivative order continuous over dwell - move - dwell."""
    scale = [1.0] + [float(np.max(np.abs(d))) + 1.0 for d in law.derivatives(np.linspace(0, 1, 2001), 4)[1:]]
    # (left value, right value) pairs at the joints: dwell/move at 0 and 1, and the law's breaks
    _, *start = law.derivatives([0.0], 4)
    _, *end = law.derivatives([1.0], 4)
    left_b = law.derivatives([b - delta for b in law.breaks] or [0.5], 4)
    right_b = law.derivatives([b + delta for b in law.breaks] or [0.5], 4)
    for k in range(1, 5):
        jumps = [abs(float(start[k - 1][0])), abs(float(end[k - 1][0]))]
        if law.breaks:
            jumps.append(float(np.max(np.abs(left_b[k] - right_b[k]))))
        if max(jumps) > 1e-6 * scale[k]:
            return k - 1
    return 4
