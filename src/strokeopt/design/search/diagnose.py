"""Why a design cannot be solved: the limit that cannot be met, and by how much.

Called by :mod:`.refine` when IPOPT fails: the same NLP is built relaxed (every limit group
``expr <= sigma``, the total excess minimised; :class:`~.nlp.Built`), and the worst excess is
named in the words of its :class:`~.limits.LimitGroup` (a :class:`~strokeopt.errors.SolverError`).
"""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np

from ..transcription.limits import LimitGroup
from ..transcription.nlp import prepare
from ..transcription.request import SolveRequest
from ..transcription.solver import STATUS_OK, solve_nlp
from ...errors import LimitError, SolverError
from ...io.load_units import error_unit


def diagnose(req: SolveRequest, status: str) -> SolverError:
    """Why the solve of ``req`` failed: relax every limit group of its NLP, minimise the total excess, name the worst."""
    error, _ = _relaxed(req, status)
    if error is None:
        where = f" for motor {req.choice.motor.name}" if req.choice is not None and req.choice.motor is not None else ""
        hint = (f"raise the iteration limit ({req.options.get('ipopt.max_iter')}: [design.solver] "
                f"\"ipopt.max_iter\" = 1000), " if status == "Maximum_Iterations_Exceeded" else "")
        return SolverError(f"IPOPT did not converge at {req.spm:g} spm{where} ({status}) although the limits can be "
                           f"met: {hint}try more mesh intervals, or --verbose to see the solver log")
    return error


def feasible_start(req: SolveRequest) -> list:
    """A start for ``req`` that meets every limit: the relaxed NLP's solution when its excess is zero; else the
    diagnosis is raised (a :class:`LimitError`), with no solve of ``req`` itself. For a candidate near its limits
    this is cheaper than letting IPOPT prove the infeasibility (its restoration phase)."""
    error, sols = _relaxed(req, "not solved: its limits were checked first")
    if error is not None:
        raise error
    return sols


def _relaxed(req: SolveRequest, status: str) -> tuple[SolverError | None, list | None]:
    """``(error, None)`` naming the worst exceeded limit of ``req`` relaxed (or why the relaxed problem failed),
    or ``(None, solution)`` when no limit is exceeded."""
    spm, choice, options = req.spm, req.choice, req.options
    where = f" for motor {choice.motor.name}" if choice is not None and choice.motor is not None else ""
    try:
        nlp = prepare(replace(req, warm=None, relaxed=True, pin_times=None))
        opts = {k: v for k, v in options.items() if k != "plugin"}
        sol, stats, _ = solve_nlp(nlp, opts)
    except (RuntimeError, ValueError) as exc:  # pragma: no cover - a relaxed problem is always feasible
        return SolverError(f"the design problem at {spm:g} spm{where} could not be solved (IPOPT: {status}; {exc})"), None
    if str(stats.get("return_status")) not in STATUS_OK:
        short = jerk_shortfall(req)  # a jerk bound far below any stroke's (its relaxation too large to solve)
        if short is not None:
            return SolverError(short), None
        return SolverError(f"the design problem at {spm:g} spm{where} could not be solved (IPOPT: {status}); "
                           f"even with every limit relaxed: check the timing and the rest conditions"), None
    x = np.asarray(sol["x"]).ravel()
    violated = []  # (relative excess, limit group, slack), worst first
    for lim, slack in nlp.built.limits:
        sig = float(nlp.value(slack, x).item()) if slack is not None and lim.is_enforced(nlp.request) else 0.0
        if sig > 1e-6:
            need = lim.need(sig)
            violated.append((need / lim.limit - 1 if lim.limit else math.inf, lim, need))
    if not violated:
        return None, nlp.unpack(x)
    violated.sort(key=lambda v: -v[0])
    excess, lim, need = violated[0]
    subject = f"move {lim.move} too short" if lim.move is not None else "the design cannot meet the limits"
    # a limit with its own message (the contact model's) is not the motor's: the motor is not named
    motor = (f" for motor {choice.motor.name}" if choice is not None and choice.motor is not None
             and lim.describe is None else "")
    lines = [f"{subject}{motor} at {spm:g} spm: {need_text(lim, need, lim.what)}"]
    seen = {lim.name}
    for _, other, other_need in violated[1:]:
        if other.name not in seen and len(seen) < 5:
            seen.add(other.name)
            where_ = f" (move {other.move})" if other.move is not None else ""
            lines.append(f"  also{where_}: {need_text(other, other_need, other.what)}")
    # the relative excess of the worst limit ranks the motors of a catalogue search
    return LimitError("\n".join(lines), excess, need_text(lim, need, lim.short)), None


def need_text(lim: LimitGroup, need: float, name: str) -> str:
    """``<name> needs X <unit>, limit Y <unit> (Z % over)``: a violated limit group and by how much (or the
    group's own words, :attr:`~.limits.LimitGroup.describe`)."""
    if lim.describe is not None:
        return lim.describe(need)
    over = f" ({100 * (need / lim.limit - 1):.1f} % over)" if lim.limit else ""
    unit, shown_need, shown_lim = lim.unit, need, lim.limit
    if unit in ("m", "rad"):   # a position: mm, or deg for a rotary load
        scale, shown_unit = error_unit(unit == "rad")
        shown_need, shown_lim, unit = need * scale, lim.limit * scale, shown_unit
    unit = "" if unit == "-" else f" {unit}"
    return f"{name} needs {shown_need:.4g}{unit}, limit {shown_lim:.4g}{unit}{over}"


#: The least peak jerk of a move at rest at both ends in velocity and acceleration: ``32 h / T^3`` (jerk
#: +J, -J, -J, +J for a quarter of the move each); a bound below it leaves the move no stroke.
REST_TO_REST_JERK = 32.0


def jerk_shortfall(req: SolveRequest) -> str | None:
    """The first move whose jerk bound no stroke at rest at both ends meets, in the diagnosis's words (None: none)."""
    if req.settings.rest_order < 2:
        return None
    for mv in req.moves:
        if mv.start_speed or mv.end_speed:  # the least jerk is a rest-to-rest move's
            continue
        need = REST_TO_REST_JERK * abs(mv.stroke) / mv.duration**3
        if mv.jerk_bound is not None and mv.jerk_bound < need * (1 - 1e-9):
            return (f"move {mv.index} too short at {req.spm:g} spm: jerk bound needs at least {need:.4g} m/s^3 "
                    f"(32 h / T^3 for {abs(mv.stroke) * 1e3:g} mm in {mv.duration * 1e3:.4g} ms at rest at both ends), "
                    f"limit {mv.jerk_bound:.4g} m/s^3 ({100 * (need / mv.jerk_bound - 1):.4g} % over)")
    return None
