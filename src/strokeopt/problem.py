"""The design problem: one validated, typed object, SI units inside.

A :class:`Problem` is made by :func:`strokeopt.io.problem_file.load_problem`
from a problem file; this module holds the object and nothing that reads files.
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import TYPE_CHECKING

from .drive.transmission import Transmission
from .errors import ProblemError
from .motion.laws import MotionLaw
from .motion.timing import SPM_RANGE, TimingDiagram  # noqa: F401 (SPM_RANGE: read from here too)

if TYPE_CHECKING:
    from .contact.model import Model
    from .contact.scene import Scene
    from .design.settings import DesignSettings
    from .drive.spec import DriveSpec
    from .servo.settings import ServoSettings


@dataclass(frozen=True)
class Problem:
    """A validated design problem, SI units inside."""

    file: Path
    name: str
    description: str
    spm: float
    timing: TimingDiagram
    default_law: MotionLaw
    transmission: Transmission  # [transmission]: the toothed pulley, with its teeth (no inertia: the ideal drive), or a screw and lever
    data: dict = field(repr=False)  # the raw data after overrides, for reporting
    model: Model | None = field(default=None, repr=False)  # [model]: the contact model (contact/model.py)
    scenes: dict[str, Scene] | None = field(default=None, repr=False)  # [scenes.*] (contact/scene.py)
    drive: DriveSpec | None = field(default=None, repr=False)  # [drive]: motor, load, limits (drive/spec.py)
    design: DesignSettings | None = field(default=None, repr=False)  # [design]: optimal stroke (design/settings.py)
    servo: "ServoSettings | None" = field(default=None, repr=False)  # [servo]: servo loop and belt (servo/settings.py)
    #: the ``--set`` texts applied to the file (a design records them, so every command that reads it
    #: sees the same problem)
    overrides: tuple = field(default=(), repr=False)
    #: the terms of the handover position error the design holds (design.request.ErrorTerm; the
    #: problem file gives the servo's term with a [servo] section)
    error_terms: tuple = field(default=(), repr=False)

    @property
    def pulley_teeth(self) -> int | None:
        """Tooth count of the problem's pulley (``transmission.pulley_teeth``); None without a pulley."""
        return getattr(self.transmission, "teeth", None)

    @property
    def period(self) -> float:
        return self.timing.period(self.spm)

    def stroke(self, spm: float | None = None):
        """The classic-law stroke of this problem at ``spm`` (default: the problem's)."""
        return self.timing.stroke(self.spm if spm is None else spm)

    def with_law(self, law: MotionLaw) -> "Problem":
        """The same problem with every move following ``law``."""
        return replace(self, timing=self.timing.with_law(law), default_law=law)

    def with_spm(self, spm: float) -> "Problem":
        if not (isinstance(spm, (int, float)) and SPM_RANGE[0] <= spm <= SPM_RANGE[1]):
            raise ProblemError(str(self.file), "machine.spm", f"{spm!r} is outside the plausible range "
                                                              f"[{SPM_RANGE[0]:g}, {SPM_RANGE[1]:g}]")
        return replace(self, spm=float(spm))
