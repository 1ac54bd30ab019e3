"""Model parameters as design variables: ``[design.free]``.

``[design.free.k2]`` ``stiffness_N_m = [900, 3000]`` makes the stiffness of the contact model's spring k2 a
variable of the same NLP as the stroke, between the bounds (N/m; equal bounds fix it there): the design then
answers "the softest k2 with which this stroke keeps the follower on the shell" and co-designs stroke and
spring. The installed length stays, so the spring's preload force scales with its stiffness. It enters

* the contact limits (design/contact_limits.py: the cluster's contact forces), and
* the drive's load, through every ``[[drive.load_forces]]`` that takes its numbers from the spring
  (``model_spring = "k2"``, drive/spec.py): one source for the spring, so the torque sees the same k2.

After the solve the design's problem is the file's with the value found (a ``--set`` override the design
records: ``verify`` and every command reading the design see the same spring).
"""

from __future__ import annotations

import numpy as np

from ...drive.spec import with_model_springs
from ...errors import ProblemError

FIELD = "design.free"


def check_free(free: tuple, model, drive, file: str) -> None:
    """Every ``[design.free.<element>]`` names a linear spring or contact of ``[model]`` (ProblemError), and no
    drive load force states that spring's numbers itself (it must take them: ``model_spring``)."""
    for name, _, _ in free:
        fld = f"{FIELD}.{name}"
        if model is None:
            raise ProblemError(file, fld, "the problem has no [model] section")
        if name not in model.elements:
            raise ProblemError(file, fld, f"unknown parameter: the model has no spring or contact {name!r}; it has: "
                                          f"{', '.join(model.elements)}")
        el = model.elements[name]
        if el.force_law is not None or el.kind == "grip":
            raise ProblemError(file, fld, f"{name!r} has no stiffness_N_m to free (a force law or a grip)")
        if drive is not None:
            twins = [f.name for f in drive.load.forces if f.kind == "spring" and f.spring is None
                     and f.stiffness == el.stiffness]
            if twins:
                raise ProblemError(file, "drive.load_forces", f"{twins[0]!r} states the stiffness of the free spring "
                                                              f"{name!r} itself: take it from the model "
                                                              f"(model_spring = \"{name}\") so both move together")


def free_elements(settings) -> dict:
    """Element name -> (lower, upper) stiffness [N/m] of the free parameters of ``settings`` (DesignSettings)."""
    return {name: (lo, hi) for name, lo, hi in getattr(settings, "free", ())}


def free_key(model, name: str) -> str:
    """The problem-file path of a free element's stiffness (``model.springs.k2.stiffness_N_m``)."""
    return f"model.{'springs' if name in model.springs else 'contacts'}.{name}.stiffness_N_m"


def build_free(g) -> None:
    """The free parameters' variables (scaled by their upper bounds) and the drive's load with them (``g.load``)."""
    req = g.request
    g.load = req.drive.load if req.drive is not None else None
    free = free_elements(req.settings)
    if not free:
        return
    elements = req.problem.model.elements
    stiffness = {}
    for name, (lo, hi) in free.items():
        start = float(np.clip(elements[name].stiffness, lo, hi)) / hi
        stiffness[name] = g.built.var(f"free {name} stiffness", (1, 1), lo / hi, 1.0, start) * hi
    g.free_stiffness = stiffness
    if g.load is not None:
        g.load = with_model_springs(g.load, stiffness)


def free_values(nlp, x) -> dict:
    """Element name -> the value found [SI] of every free parameter at the solution ``x``."""
    return {name: float(nlp.value(sym, x).item()) for name, sym in getattr(nlp.graph, "free_stiffness", {}).items()}


def free_overrides(model, values: dict) -> list[str]:
    """``--set`` texts that put the values found into the problem file."""
    return [f"{free_key(model, name)}={value!r}" for name, value in values.items()]


def free_report(settings, model, values: dict) -> list[dict]:
    """One row per free parameter: its problem-file path, the value found, bounds, and whether it sits on a bound."""
    rows = []
    for name, value in values.items():
        lo, hi = free_elements(settings)[name]
        key = free_key(model, name)
        at = "lower" if value <= lo * (1 + 1e-6) else "upper" if value >= hi * (1 - 1e-6) else None
        rows.append({"parameter": key, "value": value, "lower": lo, "upper": hi, "at_bound": at})
    return rows
