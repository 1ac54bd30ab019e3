"""One solve with fixed parts, refined until the fine grid and the pinned points agree with it.

Fifth step of the design's flow (:mod:`.nlp`, :mod:`.solver` -> refine -> :mod:`.parts`,
:mod:`.solve`). :func:`solve_one` solves the NLP of a :class:`~.request.SolveRequest`; moves the
pinned points of the load switches (:mod:`.pins`) to the solution's crossings and re-solves until
they stay in place; re-solves with the handover accuracy enforced if the solution violates it
(a lazy constraint, :class:`~.limits.HandoverAccuracy`); then reads the solution on the fine grid
(:mod:`.fine_grid`) and doubles the mesh where a limit is exceeded between the nodes. A failed
solve raises the diagnosis of :mod:`.diagnose`.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field, replace
from typing import Any

import casadi as ca
import numpy as np

from ..transcription.collocation import Mesh
from ...io.load_units import error_unit
from .diagnose import diagnose
from .fine_grid import drive_checks_fine, fine_grid_report
from ..transcription.free import free_values, with_free_values
from ..transcription.limits import enforced_checks
from ..transcription.nlp import Nlp, prepare
from ..transcription.objectives import TIME_SCALE, free_time, is_peak_torque, needs_terms
from ..transcription.pins import pin_intervals, pin_times, pins_fit
from ..transcription.request import SolveRequest
from ..transcription.solver import STATUS_OK, solve_nlp
from ...errors import AccuracyUnreachable, SolverError

#: Re-solves that move the pinned points at most, per mesh.
PIN_ITERATIONS = 5
#: A pinned point whose torque and force stay below this share of their limits (and, for ``min_peak_torque``,
#: whose torque stays below this share of the cycle's largest torque, the peak the objective holds) before and
#: after its crossing moves sets nothing: its rows are slack, the solution stays, and no re-solve moves it (the
#: fine grid reads the true values at the crossing).
PIN_SLACK = 0.9
#: A free cycle time (min_time): re-solves at the rate found at most, and the relative change of the
#: rate below which it has settled.
RATE_ITERATIONS = 12
RATE_TOLERANCE = 1e-3
#: Solves with the handover accuracy held at most, per mesh: a term linearised about the solve's start (the
#: servo's load forces, :mod:`strokeopt.servo.kernel`) is exact at its start only, so a solution whose exact
#: error breaks the accuracy (by more than ``check_tolerance``) is solved again from itself, the term
#: linearised there (on the reference problem one or two passes settle it).
LINEAR_PASSES = 4


@dataclass
class Outcome:
    """One solve's answer: the NLP it solved, the solution, the objective [SI] and the fine-grid report."""

    nlp: Nlp
    x: np.ndarray
    sols: list
    value: float
    status: str
    solve_time: float
    iterations: int
    fine: dict
    radius: float | None = None
    motor: Any = None
    continuous_radius: float | None = None
    #: the handover error terms evaluated at the solution ((name, error [m]); None: read them from the NLP)
    handover: list | None = None
    #: a free cycle time (min_time): the rate [spm] each re-solve found, the last the answer
    rates: list = field(default_factory=list)
    #: the free model parameters found (design/free.py): element name -> value [SI]
    free_values: dict = field(default_factory=dict)

    def handover_values(self) -> list[tuple[str, float]]:
        """(name, error [m]) of every handover error term at the solution."""
        if self.handover is not None:
            return self.handover
        return [(name, float(value) if isinstance(value, (int, float)) else float(self.nlp.value(value, self.x).item()))
                for name, value in self.nlp.graph.terms.handover.terms]


def objective_value(nlp: Nlp, sol, x) -> float:
    """The objective without the smoothing term (scaled)."""
    expr = nlp.graph.cost.measure
    return float(sol["f"]) if expr is None else float(nlp.value(expr, x).item())


def pins_in_place(nlp: Nlp, x: np.ndarray, new: dict) -> bool:
    """Whether the pinned points of ``nlp`` may stay where they are for the solution ``x``.

    ``new`` holds the solution's own crossing times. Moving the pins there must keep them in
    their windows (the NLP's structure, see pins.py) and either leave every pinned row slack (:data:`PIN_SLACK`)
    or change the torque and belt force they hold by less than a tenth
    of ``check_tolerance`` of the limits (the fine grid re-reads the true values after the
    solve). A move that does not set a limit can shift its crossing freely without a re-solve.
    """
    req = nlp.request
    old = req.pin_times

    def same(key):
        if (new.get(key) is None) != (old.get(key) is None):
            return False
        if new.get(key) is None or new[key] == old[key]:
            return True
        # a crossing whose time is a variable (pins.pin_crossing) is in place while it stays in its mesh interval
        interval = lambda tau: min(int(tau / req.mesh.h), req.mesh.intervals - 1)  # noqa: E731
        return key in nlp.graph.crossings and interval(new[key]) == interval(old[key])

    if all(same(key) for key in new):
        return True
    moved = replace(req, pin_times=new)
    terms = nlp.graph.terms
    if not pins_fit(nlp.graph.pins, pin_intervals(moved), req.mesh) or terms.pin_values is None:
        return False
    expr = terms.pin_values
    peak_held = is_peak_torque(req.objective) and terms.pin_share is not None
    share = terms.pin_share if peak_held else ca.MX(0.0)  # only min_peak_torque holds a peak at a pin
    at = ca.Function("pins", [ca.vertcat(*nlp.built.w), ca.vertcat(*nlp.built.p)], [expr, share])
    before, share_before = (np.asarray(v).ravel() for v in at(x, nlp.numbers.p))
    after, share_after = (np.asarray(v).ravel() for v in at(x, nlp.built.numbers(moved).p))
    if max(np.max(np.abs(before)), np.max(np.abs(after)), share_before.max(), share_after.max()) <= PIN_SLACK:
        return True  # slack rows before and after: they set nothing, wherever the crossing is
    return bool(np.max(np.abs(after - before), initial=0.0) <= req.settings.check_tolerance / 10)


def handover_at(nlp: Nlp, x: np.ndarray, sols: list) -> tuple[float, float, list | None]:
    """The handover error at the solution ``x`` (its move solutions ``sols``): exact (the terms' numbers taken
    with the solution as the start, where a linearised term is exact), as the solve's own numbers read it,
    and each term's exact value ((name, error [m]); None without terms)."""
    total = nlp.graph.terms.handover.total
    if not isinstance(total, (ca.MX, ca.SX)):
        return float(total), float(total), None
    linear = float(nlp.value(total, x).item())
    at = prepare(replace(nlp.request, warm=sols))
    if at.built.n_w != nlp.built.n_w:  # not the same structure: the solve's own reading
        return linear, linear, None
    values = [(name, float(at.value(v, x).item()) if isinstance(v, (ca.MX, ca.SX)) else float(v))
              for name, v in at.graph.terms.handover.terms]
    return float(at.value(at.graph.terms.handover.total, x).item()), linear, values


def solution_request(nlp: Nlp, x: np.ndarray) -> SolveRequest:
    """The request at the rate of the solution ``x``: the request's own, or with a free cycle time
    (``min_time``) the request's rate divided by the solution's time scale."""
    scale = nlp.graph.time_scale
    if not isinstance(scale, (ca.MX, ca.SX)):
        return nlp.request
    return replace(nlp.request, spm=nlp.request.spm / float(nlp.value(scale, x).item()))


def solve_one(req: SolveRequest) -> Outcome:
    """One NLP with fixed parts (or a continuous radius / a Bonmin motor), refined where the fine grid demands;
    with a free cycle time (``min_time``), re-solved at the rate found until it stays (:func:`solve_free_time`)."""
    if free_time(req.objective):
        return solve_free_time(req)
    if req.free_spans:
        return solve_free_spans(req)
    return solve_at_rate(req)


def solve_free_spans(req: SolveRequest) -> Outcome:
    """``max_duration``: one solve with the moves' times free (their sum fixed), then the problem with the spans
    found (``--set timing.intervals[k].span_deg=...``, recorded in the design) solved again with its spans fixed
    from that solution: the design at the spans found, every number its own; the outcome's value is the
    lengthened move's time."""
    first = solve_at_rate(req)
    times = [float(first.nlp.value(t, first.x).item()) for t in first.nlp.graph.T]
    period = req.period   # a cam revolution: 360 deg of span
    problem = req.problem.with_overrides([f"timing.intervals[{mv.interval}].span_deg={360.0 * t / period!r}"
                                          for mv, t in zip(req.moves, times)])
    final = solve_at_rate(replace(req, problem=problem, spans_fixed=True, warm=first.sols, mesh=first.nlp.request.mesh,
                                  pin_times=None))
    return replace(final, solve_time=first.solve_time + final.solve_time, iterations=first.iterations + final.iterations)


def solve_free_time(req: SolveRequest) -> Outcome:
    """The highest rate as a fixed point: the NLP's numbers that depend on the rate (the servo term's
    kernel weights and load error, the period) are computed at the request's rate ``r`` and are exact
    at time scale 1; the solve gives a rate ``F(r)`` (the request's over the time scale). The rate
    has settled when ``F(r)`` is within :data:`RATE_TOLERANCE` of ``r``. Until a rate that solves
    faster than itself (``F(r) > r``) and one that solves slower are known, the next rate is
    ``F(r)``; then the middle of that bracket (a rate without a design counts as too fast): where
    the handover error binds, the error changes with the rate in a way the frozen numbers do not see,
    ``F`` jumps (the handover error's phase in the belt's vibration changes with the rate), and the plain
    iteration jumps about with it. A bracket narrower than ``settings.rate_bracket`` that never settled
    (``F`` jumps there) ends in a solve at its lower rate with the rate capped there
    (``rate_cap``). The outcome is read at the last rate (time scale 1: every number exact)."""
    spm, warm, radius0, mesh = req.spm, req.warm, req.radius0, req.mesh
    total_time, iterations, rates = 0.0, 0, []
    lo = hi = None  # the highest rate known to solve faster than itself, the lowest known not to
    cap = False
    for _ in range(RATE_ITERATIONS):
        try:
            out = solve_at_rate(replace(req, spm=spm, warm=warm, radius0=radius0, mesh=mesh, rate_cap=cap))
        except SolverError:
            if lo is None or cap:  # no rate known that solves: the reason is the limits', not the rate's
                raise
            rates.append(math.nan)
            rate = 0.0  # no design with this rate's numbers: too fast
        else:
            total_time += out.solve_time
            iterations += out.iterations
            rate = solution_request(out.nlp, out.x).spm
            rates.append(rate)
            warm, radius0, mesh = out.sols, out.radius, out.nlp.request.mesh
            req = replace(req, enforce_accuracy=out.nlp.request.enforce_accuracy)  # a binding accuracy stays held
            if cap or abs(rate - spm) <= RATE_TOLERANCE * spm:
                spm = rate
                break
        if rate > spm and (hi is None or spm < hi):
            lo = spm
        elif rate < spm and (lo is None or spm > lo):
            hi = spm
        if lo is None or hi is None:
            spm = rate
        elif hi - lo <= req.settings.rate_bracket * lo:
            spm, cap = lo, True
        else:
            spm = 0.5 * (lo + hi)
    else:
        raise SolverError(f"min_time: the stitch rate did not settle within {RATE_ITERATIONS} re-solves "
                          f"(relative change {RATE_TOLERANCE:g}): " + ", ".join(f"{r:.2f}" for r in rates) + " spm")
    nlp = out.nlp
    final = prepare(replace(nlp.request, spm=spm, warm=out.sols))  # the same structure, its numbers at the rate found
    x = out.x.copy()
    offset, _ = final.built.offsets[TIME_SCALE]
    x[offset] = 1.0
    out = replace(out, nlp=final, x=x, solve_time=total_time, iterations=iterations, rates=rates, handover=None)
    out.value = final.graph.cost.transform(objective_value(final, None, x), final.request)
    return out


@dataclass
class _Pinned:
    """One mesh's solve with its pinned points in place (:func:`solve_pinned`)."""

    nlp: Nlp
    sol: dict
    x: np.ndarray
    sols: list
    status: str
    handover: list | None  # each term's exact error at the solution
    error: float  # the handover error at the solution, exact [m]
    solve_time: float
    iterations: int


def _accuracy_unreachable(req: SolveRequest, nlp: Nlp, error: float) -> AccuracyUnreachable:
    """The error of a most accurate stroke (``min_handover_error``) whose error still breaks the accuracy."""
    settings, choice = req.settings, req.choice
    motor = f" for motor {choice.motor.name}" if choice is not None and choice.motor is not None else ""
    scale, unit = error_unit(req.problem.timing.rotary)
    short = (f"handover accuracy needs {error * scale:.4g} {unit} (the most accurate stroke), limit "
             f"{settings.accuracy * scale:.4g} {unit} ({100 * (error / settings.accuracy - 1):.1f} % over)")
    return AccuracyUnreachable(f"the design cannot meet the limits{motor} at {nlp.request.spm:g} spm: {short}",
                               error / settings.accuracy - 1, short, error)


def solve_pinned(req: SolveRequest, mesh, warm) -> _Pinned:
    """The NLP on one mesh, re-solved until its pinned points stay in place, with the handover accuracy held
    once a solution breaks it (lazy), and re-solved from its own solution while the exact error there breaks
    it (:data:`LINEAR_PASSES`; the last solution that held it is kept)."""
    settings, choice = req.settings, req.choice
    total_time, iterations = 0.0, 0
    pins = None
    enforce = req.enforce_accuracy and bool(req.error_terms)
    held = None  # the last solution whose only fault is pins short of its crossings
    passes = 0  # solves with the accuracy held
    kept = None  # the last solution with the accuracy held whose exact error holds it too
    for _ in range(PIN_ITERATIONS):
        t0 = time.perf_counter()
        nlp = prepare(replace(req, mesh=mesh, warm=warm, pin_times=pins,
                              enforce_accuracy=enforce and bool(req.error_terms)))
        sol, stats, _ = solve_nlp(nlp, req.options)
        total_time += time.perf_counter() - t0
        iterations += int(stats.get("iter_count", 0) or 0)
        status = str(stats.get("return_status", "unknown"))
        ok = stats.get("success", False) if choice is not None and choice.candidates else status in STATUS_OK
        if not ok and held is not None:
            # moving the pins made IPOPT fail (a restoration failure next to the impact pin): keep the
            # solution before it; the fine grid reads the limits at the true crossings and reports what
            # the pins miss
            nlp, sol, x, sols, status, handover, error = held
            break
        if not ok:
            raise diagnose(nlp.request, status)
        x = np.asarray(sol["x"]).ravel()
        sols = nlp.unpack(x)
        new = pin_times(nlp.request, nlp.graph.pins, sols)
        error, linear, handover = handover_at(nlp, x, sols)
        needs = needs_terms(req.objective)  # the terms are the objective (min_handover_error)
        passes += enforce or needs
        violated = error > settings.accuracy * (1 + (settings.check_tolerance if enforce else 0.0))
        current = (nlp, sol, x, sols, status, handover, error)
        # terms linearised about the start: re-solved from the solution while they have not settled there
        if needs:  # the most accurate stroke: the least exact error of the passes
            kept = current if kept is None or error < kept[-1] else kept
            again = abs(error - linear) > settings.check_tolerance * settings.accuracy and passes < LINEAR_PASSES
        else:  # a held accuracy: until a solution holds it exactly (the load's jumps would cycle on)
            again = violated and passes < LINEAR_PASSES and kept is None
            kept = current if enforce and not violated else kept
        if not again and kept is not None and kept is not current and (needs or (violated and enforce)):
            nlp, sol, x, sols, status, handover, error = kept  # passes spent: the best, or the last that held it
            violated = needs and error > settings.accuracy
            break
        if violated and needs and not again:  # the least error there is: no stroke meets the accuracy
            raise _accuracy_unreachable(req, nlp, error)
        if not (violated and not enforce and not needs) and not again and pins_in_place(nlp, x, new):
            break
        held = current if not violated else None
        pins, warm, enforce = new, sols, enforce or (violated and not needs)
    else:
        if (violated or needs) and kept is not None:  # the pins' re-solves ended on a worse solution
            nlp, sol, x, sols, status, handover, error = kept
    if needs and error > settings.accuracy:
        raise _accuracy_unreachable(req, nlp, error)
    return _Pinned(nlp, sol, x, sols, status, handover, error, total_time, iterations)


def solve_at_rate(req: SolveRequest) -> Outcome:
    """One NLP with fixed parts (or a continuous radius / a Bonmin motor), refined where the fine grid demands."""
    settings, choice, drive = req.settings, req.choice, req.drive
    total_time, iterations = 0.0, 0
    warm, mesh = req.warm, req.mesh
    for attempt in range(settings.refinements + 1):
        pinned = solve_pinned(req, mesh, warm)
        total_time += pinned.solve_time
        iterations += pinned.iterations
        nlp, sol, x, sols, status = pinned.nlp, pinned.sol, pinned.x, pinned.sols, pinned.status
        rated = solution_request(nlp, x)  # the rate the solution runs at
        fine, _ = fine_grid_report(rated.moves, sols, settings.check_points)
        radius = motor = None
        worst = fine["worst_relative_violation"]
        found = free_values(nlp, x)
        if drive is not None and found:  # the checks see the load and transmission with the free parameters found
            drive = with_free_values(drive, found)
        if drive is not None:
            dm = nlp.graph.drive_model
            radius = None if dm.radius is None else float(nlp.value(dm.radius, x).item())
            motor = choice.motor
            if choice.candidates:
                pick = nlp.value(dm.pick, x).ravel()
                motor = choice.candidates[int(np.argmax(pick))]
            checks = drive_checks_fine(drive, motor, choice, radius, rated, sols, settings.check_points)
            over = [max(0.0, -c.margin) for c in checks if c.name in enforced_checks(settings, drive.stepper) and math.isfinite(c.margin)]
            if is_peak_torque(req.objective):  # the epigraph held at the nodes; the fine grid reads the peak
                nlp_peak = nlp.graph.cost.transform(objective_value(nlp, sol, x), nlp.request)
                fine_peak = next(c.value for c in checks if c.name == "peak_torque")
                fine["peak_torque_nodes_N_m"] = nlp_peak
                fine["peak_torque_fine_N_m"] = fine_peak
                over.append(max(0.0, fine_peak / nlp_peak - 1.0))
            worst = max([worst] + over)
            fine["drive_checks"] = [c.as_dict() for c in checks]
            fine["worst_relative_violation"] = worst
        if worst <= settings.check_tolerance or attempt == settings.refinements:
            break
        mesh = Mesh(mesh.intervals * 2, mesh.degree)
        warm = None
    value = nlp.graph.cost.transform(objective_value(nlp, sol, x), nlp.request)
    if needs_terms(req.objective):  # the error at the solution, exact (the solve's own rows are exact at its start)
        value = pinned.error * 1e3
    return Outcome(nlp, x, sols, value, "optimal" if status == "Solve_Succeeded" else "acceptable", total_time,
                   iterations, fine, radius, motor, handover=pinned.handover, free_values=found)
