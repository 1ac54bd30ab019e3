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
