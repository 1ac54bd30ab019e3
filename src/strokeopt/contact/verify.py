"""Verifying a design by re-simulation: its optimised stroke through a scene of the contact model.

A design (design/) is solved on a rigid model of the drive; :func:`verify` runs its
stroke, at its stitch rate, through a scene of its problem's contact model
(simulate.py) and returns the :class:`~strokeopt.contact.simulate.SceneResult`, the
same results ``strokeopt simulate`` reports for a classic law. It takes the
``Design`` a solve returns, or a :class:`DesignStroke` read back from a
``design.json`` by :func:`load_design` (what ``strokeopt verify`` does).
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Any

from ..io.design_file import design_overrides, read_design
from ..errors import ProblemError
from ..io.problem_file import load_problem
from .simulate import SceneResult, SimulationOptions, simulate_scene


@dataclass(frozen=True)
class DesignStroke:
    """What verification needs of a design: its problem, its stroke and the stitch rate it was solved at.

    ``source``: the design file it was read from; ``objective``: the objective it was solved for.
    A solve's ``Design`` has the same ``problem``, ``stroke`` and ``spm``.
    """

    problem: Any
    stroke: Any
    spm: float
    source: str = ""
    objective: str | None = None


def load_design(path, problem_file=None, overrides=()) -> DesignStroke:
    """Read a ``design.json`` and the problem it was solved for, at the design's stitch rate.

    ``problem_file`` replaces the file the design names (a relative name the design names is
    also looked for next to the design file); ``overrides`` are ``--set`` texts for it.
    """
    data, stroke = read_design(path)
    file = design_problem_file(path, data, problem_file)
    problem = load_problem(file, [*design_overrides(data), *overrides, f"machine.spm={float(data['spm'])!r}"])
    return DesignStroke(problem, stroke, problem.spm, str(path), data.get("objective"))


def design_problem_file(path, data: dict, problem_file=None) -> Path:
    """The problem file of the design ``data`` read from ``path``: ``problem_file`` if given, else the
    one the design names (a relative name also looked for next to the design file)."""
    problem_file = problem_file or data.get("problem_file")
    if not problem_file:
        raise ProblemError(str(path), "problem_file", "is missing: pass --problem FILE")
    file = Path(problem_file)
    if not file.is_absolute() and not file.exists() and (Path(path).parent / file).exists():
        file = Path(path).parent / file
    return file


def verify(design, scene: str, options: SimulationOptions | None = None) -> SceneResult:
    """Re-simulate ``design`` (a solve's ``Design``, a :class:`DesignStroke`, or the path of a design.json):
    its stroke, at its stitch rate, through ``scene`` of its problem's contact model."""
    if isinstance(design, (str, Path)):
        design = load_design(design)
    return simulate_scene(design.problem, scene, design.spm, stroke=design.stroke, options=options)
