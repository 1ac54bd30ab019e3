"""Model parameters as design variables: ``[design.free]``.

``[design.free.k2]`` ``stiffness_N_m = [900, 3000]`` makes the stiffness of the contact model's spring k2 a
variable of the same NLP as the stroke, between the bounds (N/m; equal bounds fix it there): the design then
answers "the softest k2 with which this stroke keeps the follower on the shell" and co-designs stroke and
spring. The installed length stays, so the spring's preload force scales with its stiffness. It enters

* the contact limits (design/contact_limits.py: the cluster's contact forces), and
* the drive's load, through every ``[[drive.load_forces]]`` that takes its numbers from the spring
  (``model_spring = "k2"``, drive/spec.py): one source for the spring, so the torque sees the same k2.

``[design.free.transmission]`` ``crank_radius_mm = [18, 30]`` frees a field of the problem's own transmission the
same way (the fields it offers: :attr:`~strokeopt.drive.transmission.Transmission.free_fields`): the NLP's
transmission is :meth:`~strokeopt.drive.transmission.Transmission.with_free` of a variable, its range held by
:meth:`~strokeopt.drive.transmission.Transmission.reach_rows`, so the torque, speeds and pinned points all see the
one radius.

After the solve the design's problem is the file's with the values found (``--set`` overrides the design
records: ``verify`` and every command reading the design see the same spring and crank).
"""

from __future__ import annotations

import casadi as ca
import numpy as np

from ...drive.spec import with_model_springs
from ...errors import ProblemError

FIELD = "design.free"
#: the prefix of a free transmission field's name (``transmission.crank_radius_mm``), as in the problem file
TRANSMISSION = "transmission."


def check_free(free: tuple, model, drive, file: str, transmission=None, positions=(0.0, 0.0)) -> None:
    """Every ``[design.free.<element>]`` names a linear spring or contact of ``[model]`` (ProblemError), and no
    drive load force states that spring's numbers itself (it must take them: ``model_spring``); every field of
    ``[design.free.transmission]`` is one the transmission offers, within bounds it can take, on a drive."""
    for name, lo, hi in free:
        fld = f"{FIELD}.{name}"
        if name.startswith(TRANSMISSION):
            _check_transmission(fld, name[len(TRANSMISSION):], lo, hi, transmission, drive, file, positions)
            continue
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


def check_outer(outer: tuple, data: dict, file: str) -> None:
    """Every field a ``[design.free]`` entry outside the collocation moves (settings.OuterFree) is a number of the
    problem file (ProblemError naming the entry); that its range gives problems the file accepts is checked when the
    search starts (studies/outer.py)."""
    from ...io.fields import number_in

    for o in outer:
        key = f"{FIELD}.{o.name}.{'field' if o.absolute else 'moves'}"
        for path, _ in o.moves:
            if path.startswith(f"{FIELD}.") or path.startswith("design.free"):
                raise ProblemError(file, key, f"{path}: a design variable cannot move the design's own settings")
            try:
                number_in(data, path, file, key)
            except ProblemError as exc:
                raise ProblemError(file, key, f"{path}: {exc.message}") from None


def _check_transmission(fld: str, key: str, lo: float, hi: float, transmission, drive, file: str,
                        positions: tuple) -> None:
    offered = getattr(transmission, "free_fields", {})
    if key not in offered:
        name = getattr(transmission, "name", "transmission")
        raise ProblemError(file, fld, f"the {name} has no field {key!r} a design may free" + (
            f"; it offers: {', '.join(offered)}" if offered else
            " (a belt pulley's radius is [design] pulley = \"continuous\" or \"catalogue\")"))
    if drive is None:
        raise ProblemError(file, fld, "a free transmission field is chosen for the drive: the problem has no [drive]")
    why = transmission.free_error(key, lo, hi, positions)
    if why is not None:
        raise ProblemError(file, fld, why)


def free_elements(settings) -> dict:
    """Element name -> (lower, upper) stiffness [N/m] of the free model parameters of ``settings`` (DesignSettings)."""
    return {name: (lo, hi) for name, lo, hi in getattr(settings, "free", ()) if not name.startswith(TRANSMISSION)}


def free_transmission(settings) -> dict:
    """Field -> (lower, upper) in the field's unit of the free transmission fields of ``settings``."""
    return {name[len(TRANSMISSION):]: (lo, hi) for name, lo, hi in getattr(settings, "free", ())
            if name.startswith(TRANSMISSION)}


def model_values(values: dict) -> dict:
    """The free model parameters of ``values`` (:func:`free_values`): element name -> stiffness [N/m]."""
    return {name: v for name, v in values.items() if not name.startswith(TRANSMISSION)}


def with_free_values(drive, values: dict):
    """A copy of the design's drive (DriveSetup) with the values found: its load's springs and its own
    transmission's free fields."""
    from copy import copy

    from ...drive.spec import with_model_springs

    drive = copy(drive)
    drive.load = with_model_springs(drive.load, model_values(values))
    fields = {name[len(TRANSMISSION):]: v for name, v in values.items() if name.startswith(TRANSMISSION)}
    if fields:
        drive.own_transmission = drive.own_transmission.with_free(fields)
    return drive


def free_key(model, name: str) -> str:
    """The problem-file path of a free element's stiffness (``model.springs.k2.stiffness_N_m``) or transmission
    field (``transmission.crank_radius_mm``, its name)."""
    if name.startswith(TRANSMISSION):
        return name
    return f"model.{'springs' if name in model.springs else 'contacts'}.{name}.stiffness_N_m"


def build_free(g) -> None:
    """The free parameters' variables (scaled by their upper bounds), the drive's load with them (``g.load``) and
    its own transmission with them (``g.transmission``, its range held)."""
    req = g.request
    g.load = req.drive.load if req.drive is not None else None
    g.transmission = req.drive.own_transmission if req.drive is not None else None
    fields = free_transmission(req.settings)
    if fields and g.transmission is not None:
        own = g.transmission
        values = {key: g.built.var(f"free {key}", (1, 1), lo / hi, 1.0,
                                   float(np.clip(getattr(own, own.free_fields[key][0]) / own.free_fields[key][1],
                                                 lo, hi)) / hi) * hi for key, (lo, hi) in fields.items()}
        g.free_fields = values
        g.transmission = own.with_free(values)
        x_min, x_max = req.problem.timing.position_range
        rows = g.transmission.reach_rows(x_min, x_max)
        if rows:
            g.built.constrain(f"{own.label}'s range (the free {', '.join(fields)})", ca.vertcat(*rows), 0.0, ca.inf)
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
    """Element name -> the value found [SI] of every free model parameter, ``transmission.<field>`` -> the value in
    the field's unit of every free transmission field, at the solution ``x``."""
    g = nlp.graph
    out = {name: float(nlp.value(sym, x).item()) for name, sym in getattr(g, "free_stiffness", {}).items()}
    out.update({TRANSMISSION + key: float(nlp.value(sym, x).item()) for key, sym in getattr(g, "free_fields", {}).items()})
    return out


def free_overrides(model, values: dict) -> list[str]:
    """``--set`` texts that put the values found into the problem file."""
    return [f"{free_key(model, name)}={value!r}" for name, value in values.items()]


def free_report(settings, model, values: dict) -> list[dict]:
    """One row per free parameter: its problem-file path, the value found, bounds, and whether it sits on a bound."""
    rows = []
    bounds = {name: (lo, hi) for name, lo, hi in settings.free}
    for name, value in values.items():
        lo, hi = bounds[name]
        key = free_key(model, name)
        at = "lower" if value <= lo * (1 + 1e-6) else "upper" if value >= hi * (1 - 1e-6) else None
        rows.append({"parameter": key, "value": value, "lower": lo, "upper": hi, "at_bound": at})
    return rows
