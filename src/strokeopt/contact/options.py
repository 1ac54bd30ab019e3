"""How a contact scene is integrated: :class:`SimulationOptions` (checked like a file's fields)."""

from __future__ import annotations

import math
from dataclasses import dataclass

from ..errors import ProblemError
from .scene import TOLERANCE_RANGES

METHODS = ("cvodes", "idas")


@dataclass(frozen=True)
class SimulationOptions:
    """How to integrate.

    ``rtol``/``atol`` go to the integrator; ``atol`` is in the scaled states (positions in mm,
    velocities in m/s). ``smoothing`` (m) = 0 for hard switches. ``resolution_deg``: output grid
    spacing in the longest stroke piece (shorter pieces get the same number of points, so a finer
    spacing). ``restart_at_switches``: integrate piecewise between detected contact switches
    (restarting the integrator at each) instead of across them; slower, kept for the
    comparison of the tolerance study. ``integrator_options`` pass straight to ``casadi.integrator``.
    ``verbose``: let SUNDIALS print its own messages (otherwise only the SolverError says why).
    ``max_steps``: the integrator steps the cycle may take (None: the scene's budget at this tolerance,
    :meth:`~strokeopt.contact.scene.Scene.step_budget`); a scene that needs more stops (SolverError).
    ``peaks``: locate each peak force between the output points with an error estimate (peaks.py); False: the
    output grid's largest values, without an estimate, for a study that judges no force by its size (the
    tolerance study: lag, impact velocity, release; the plausibility bound is far above any grid error).
    ``estimate``: each located peak's error estimate (found again at 1/100 of the tolerances from its stroke piece's
    start: at rtol 1e-10 that is most of the run, 34 of the handover scene's 34 s against 13 s without); False: the
    peaks located, not estimated (``peak_forces_converged`` None), for a reference run the others are judged against.
    """

    method: str = "cvodes"
    rtol: float = 1e-5
    atol: float = 1e-6
    smoothing: float = 0.0
    resolution_deg: float = 0.25
    max_steps: int | None = None
    restart_at_switches: bool = False
    integrator_options: dict | None = None
    verbose: bool = False
    peaks: bool = True
    estimate: bool = True

    def check(self) -> None:
        if self.method not in METHODS:
            raise ProblemError("options", "method", f"{self.method!r} is not one of {', '.join(METHODS)}")
        for name in ("rtol", "atol", "resolution_deg"):
            value, (lo, hi) = getattr(self, name), TOLERANCE_RANGES.get(name, (0.0, math.inf))  # scene.py: why
            if not (isinstance(value, (int, float)) and math.isfinite(value) and value > 0 and lo <= value <= hi):
                raise ProblemError("options", name, "must be a positive number" + (
                    f" in [{lo:g}, {hi:g}]" if name in TOLERANCE_RANGES else "") + f", got {value!r}")
        if not (math.isfinite(self.smoothing) and self.smoothing >= 0):
            raise ProblemError("options", "smoothing", f"must be zero (hard switches) or positive, got {self.smoothing!r}")
        if self.max_steps is not None and not (isinstance(self.max_steps, int) and self.max_steps >= 1):
            raise ProblemError("options", "max_steps", f"must be a whole number of steps >= 1, got {self.max_steps!r}")


