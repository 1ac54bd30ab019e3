"""The motor torque of a design's stroke on its own motor and pulley (the drive package's load model).

One place for what the solve's figure, the cam table's torque column and the design report draw:
:func:`design_drive` (the drive setup and the transmission of the design's pulley) and
:func:`design_torque` (the torque terms over the cycle, or at given times).
"""

from __future__ import annotations

import numpy as np

from .transcription.request import DriveSetup
from .transcription.settings import DesignSettings


def design_drive(design):
    """The drive setup of the design's problem and the transmission of the design's pulley (the problem's own
    transmission when it is not a belt pulley)."""
    drive = DriveSetup(design.problem, getattr(design.problem, "design", None) or DesignSettings())
    return drive, design.drive.transmission


def design_torque(design, samples: int = 3601, t=None):
    """The motor torque of the design's stroke over the cycle on its own motor and pulley:
    ``(t, TorqueTerms)`` (``.omega`` the motor speed, ``.total`` the torque), or None without a drive.
    ``t``: the times [s] to evaluate at (default ``samples`` points over one cycle)."""
    if design.motor_spec is None or design.problem.drive is None:
        return None
    from ..drive.load import load_torque

    drive, trans = design_drive(design)
    k = design.stroke.sample(samples) if t is None else design.stroke.evaluate(np.asarray(t, float))
    return k.t, load_torque(design.motor_spec, trans, drive.load, k.s, k.v, k.a)


def design_torque_path(design, samples: int = 1441):
    """:func:`design_torque` on ``samples`` points over the cycle plus the instants its peak is read at: both
    sides of every crossing of a load-force switch (a spring met: the torque jumps there) and a zoom on the
    largest |torque|, so that the path's peak is the peak the checks report on their fine grid (a uniform
    grid misses the jump by a few per cent). ``(t, TorqueTerms)``, or None without a drive."""
    first = design_torque(design, samples)
    if first is None:
        return None
    t, terms = first
    stroke = design.stroke
    drive, _ = design_drive(design)
    extra = []
    s = stroke.evaluate(t).s
    for pos in [f.contact_position for f in drive.load.forces if f.kind == "spring"]:
        f = s - pos
        for i in np.nonzero(np.sign(f[:-1]) * np.sign(f[1:]) <= 0)[0]:
            extra += _zoom(lambda x: stroke.evaluate(x).s - pos, t[i], t[i + 1])
    i = int(np.argmax(np.abs(terms.total)))
    lo, hi = t[max(i - 1, 0)], t[min(i + 1, len(t) - 1)]
    for _ in range(3):  # the largest |torque| between its neighbours, to (2/1000)^3 of their span
        grid = np.linspace(lo, hi, 1001)
        j = int(np.argmax(np.abs(design_torque(design, t=grid)[1].total)))
        lo, hi = grid[max(j - 1, 0)], grid[min(j + 1, len(grid) - 1)]
        extra.append(grid[j])
    times = np.unique(np.concatenate([t, np.asarray(extra, float)]))
    return design_torque(design, t=times)


def _zoom(f, lo: float, hi: float) -> list[float]:
    """Both sides of the sign change of ``f`` in ``[lo, hi]``, three dense zooms of 1001 points."""
    for _ in range(3):
        grid = np.linspace(lo, hi, 1001)
        g = f(grid)
        changes = np.nonzero(np.sign(g[:-1]) * np.sign(g[1:]) <= 0)[0]
        if len(changes) == 0:
            break
        lo, hi = grid[changes[0]], grid[changes[0] + 1]
    return [lo, hi]
