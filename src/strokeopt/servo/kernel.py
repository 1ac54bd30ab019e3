"""The servo's term of the design's handover-accuracy constraint: :class:`ServoErrorTerm`, passed to the
design as one of ``Problem.error_terms``: the full servo simulation's error over the handover window as rows
linear in the move accelerations (:mod:`.table_term`).

The design does not import this module: the problem file (:mod:`strokeopt.files.problem_file`) gives the
term to a problem with a ``[servo]`` section, and :func:`strokeopt.design.solve.solve_design` takes it
from there (or from its ``error_terms`` argument)."""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import ClassVar

import numpy as np

from .accuracy import TABLE_PHASES
from .error_expression import ErrorExpression
from .loop import tuned_gains as _tuned
from .plant import axis_from_problem
from .table_term import PositionMap, error_rows, table_response



# --------------------------------------------------------------------------- the design constraint


@dataclass(frozen=True)
class ServoErrorTerm:
    """The servo's handover error term of the design (a :class:`strokeopt.design.transcription.request.ErrorTerm`):
    the bar's error over the handover window (the end of the handover move and :data:`WINDOW_POINTS`
    instants of the simulation's grid after it) for every table phase, ``|e| + one count`` at each.

    ``e`` is the full servo simulation's error (:mod:`.table_term`: the sampled position table, its
    feed-forwards, the belt and the load forces), as rows linear in the moves' variables: exact for the
    motion, the load forces linearised about the solve's start stroke (the warm start), so the rows are
    exact at that stroke; the design re-linearises at its solution until the error there settles
    (:data:`LOAD_PASSES`). The rows enter the NLP as parameters, so a solver built for one speed serves
    another. With a continuous pulley radius or a motor choice the loop is that of the problem's own
    pulley and motor (an approximation; the solve's check row shows the full simulation beside it). The
    term has no parameters: it reads ``problem.servo`` at solve time (no term when the problem has no
    ``[servo]`` section). The problem file gives it to every problem with a ``[servo]`` section
    (``Problem.error_terms``).
    """

    name: ClassVar[str] = "servo loop and belt"

    def fixed_error(self, problem) -> float | None:
        """No part of this term is independent of the design (speed, motor and pulley set all of it)."""
        return None

    def expression(self, nlp):
        """The error [m] in the NLP under construction, or None without ``[servo]``, drive or handover move."""
        import casadi as ca

        req = nlp.request
        problem = req.problem
        if getattr(problem, "servo", None) is None or req.drive is None or not req.moves:
            return None
        if problem.timing.handover_move is None:
            return None
        b = nlp.built
        rows = held_rows(req)
        parts = []
        for part in ("motion", "load"):
            errors = b.params(f"servo {part} error constant", lambda r, p=part: _servo_numbers(r)[p][0], (rows, 1))
            for k, mv in enumerate(req.moves):
                z = ca.vec(nlp.vars[k].A)
                w_sym = b.params(f"servo {part} error rows move {mv.index}",
                                 lambda r, k=k, p=part: _servo_numbers(r)[p][1][k], (rows, z.shape[0]))
                errors = errors + ca.mtimes(w_sym, z)
            parts.append(errors)
        # a free cycle time (min_time): the rows are the error at the request's rate (time scale 1); the motion's
        # error follows the accelerations, 1/scale^2 of the unit form's (the fixed point of the rate is exact)
        quant = b.param("servo encoder count", lambda r: _servo_numbers(r)["count"])
        return ErrorExpression(parts[0] / nlp.time_scale**2 + parts[1], quant)


#: Passes of the load forces' linearisation at most: a design that holds the accuracy re-solves from its
#: solution, linearised there, until the error there is within the accuracy (``check_tolerance``) or this
#: many solves have been made with it held.
LOAD_PASSES = 4


def move_layout(mesh) -> int:
    """Variables of one move in a :class:`PositionMap`: interval-start S and V, node accelerations A (column-major)."""
    return 2 * (mesh.intervals + 1) + mesh.intervals * (mesh.degree + 1)


def integration_map(mesh) -> np.ndarray:
    """``(S, V, vec(A))`` of a move from rest as a matrix of ``vec(A)``: the interval-start positions and
    speeds are the exact integrals of the acceleration polynomials (what the collocation's continuity rows
    hold). The term's rows then touch the accelerations alone, which keeps the dense block they make in
    the solver's factorisation a third of the size."""
    n, d, h = mesh.intervals, mesh.degree, mesh.h
    na = n * (d + 1)
    m = mesh.matrices([1.0])
    out = np.zeros((move_layout(mesh), na))
    out[2 * (n + 1):] = np.eye(na)
    s_row, v_row = np.zeros(na), np.zeros(na)
    for i in range(n):
        out[i], out[n + 1 + i] = s_row, v_row
        s_row = s_row + h * v_row + h**2 * _spread(m["s"][0], n, i)
        v_row = v_row + h * _spread(m["v"][0], n, i)
    out[n], out[2 * n + 1] = s_row, v_row
    return out


def _spread(coefficients: np.ndarray, n: int, i: int) -> np.ndarray:
    """A row over ``vec(A)`` with ``coefficients`` on interval ``i``'s node accelerations."""
    row = np.zeros(n * len(coefficients))
    row[np.arange(len(coefficients)) * n + i] = coefficients
    return row


def position_map(req, times: np.ndarray) -> PositionMap:
    """The stroke of a solve at ``times`` (seconds from the cycle start, within one cycle) as a
    :class:`PositionMap` of the moves' unit variables (``S``, ``V``, ``A`` of each move, :func:`move_layout`):
    a dwell's position is a constant, a move's ``start + stroke * (S_i + h theta V_i + h^2 (A_i . m_s(theta)))``."""
    timing = req.problem.timing
    sch = req.schedule
    mesh = req.mesh
    n, h = mesh.intervals, mesh.h
    times = np.asarray(times, dtype=float)
    which = np.clip(np.searchsorted(sch.t_start, times, side="right") - 1, 0, len(timing.intervals) - 1)
    const = np.zeros(len(times))
    mats = [np.zeros((len(times), move_layout(mesh))) for _ in req.moves]
    by_interval = {mv.interval: (k, mv) for k, mv in enumerate(req.moves)}
    for i, itv in enumerate(timing.intervals):
        sel = np.flatnonzero(which == i)
        if not len(sel):
            continue
        if itv.index not in by_interval:
            const[sel] = itv.start_position
            continue
        k, mv = by_interval[itv.index]
        tau = np.clip((times[sel] - sch.t_start[i]) / sch.duration[i], 0.0, 1.0)
        j = np.minimum((tau / h).astype(int), n - 1)
        theta = tau / h - j
        m_s = mesh.matrices(theta)["s"]  # (points, d + 1)
        const[sel] = mv.start
        rows = mats[k]
        rows[sel, j] = mv.stroke
        rows[sel, n + 1 + j] = mv.stroke * h * theta
        for c in range(mesh.degree + 1):
            rows[sel, 2 * (n + 1) + c * n + j] = mv.stroke * h**2 * m_s[:, c]
    return PositionMap(const, tuple(mats))


def check_instants(resp, t_end: float, window: float) -> np.ndarray:
    """The instants the term checks as ``(j, w)`` rows of the simulation's grid (the error ``(1 - w) e[j] +
    w e[j + 1]``): the end of the handover move ``t_end`` (seconds, the loop delay included), interpolated
    as the simulation reads it, and :data:`WINDOW_POINTS` grid instants spread evenly over the window after it."""
    h = resp.period / resp.n
    t0 = resp.t[0]
    pos = (t_end - t0) / h
    first = int(np.floor(pos))
    out = [(first, pos - first)]
    last = int(np.floor((t_end + window - t0) / h + 1e-9))
    start = first + 1
    picks = np.unique(np.round(np.linspace(start, max(start, last), WINDOW_POINTS)).astype(int))
    picks = np.concatenate([picks, np.full(WINDOW_POINTS - len(picks), picks[-1])])  # a short window repeats
    out += [(int(p), 0.0) for p in picks]
    return np.array(out, dtype=float)


def _servo_numbers(req) -> dict:
    """The numbers of :class:`ServoErrorTerm` for one solve (speed, motor, pulley, start stroke): the error
    rows per move, their constant, the encoder count. Computed once per solve (``req.cache``, the solve's
    :class:`~strokeopt.design.transcription.request.SolveRequest`)."""
    cache = req.cache
    if "servo" in cache:
        return cache["servo"]
    problem = req.problem
    settings = problem.servo
    timing = problem.timing
    move_h = timing.handover_move
    choice = req.choice
    motor = choice.motor if choice is not None and choice.motor is not None else None
    teeth = choice.teeth if choice is not None and choice.teeth is not None else problem.pulley_teeth
    axis = axis_from_problem(problem, settings, motor=motor, pulley_teeth=teeth)
    gains = _tuned(axis, settings)
    sch = req.schedule
    period = float(sch.period)
    resp = table_response(axis, settings, gains, period)
    t_h = float(sch.t_start[move_h.index - 1] + sch.duration[move_h.index - 1])
    instants = check_instants(resp, t_h + settings.sum_small_time_constants, settings.handover_window / 360.0 * period)
    z0 = [np.concatenate([s, v, np.asarray(a).ravel(order="F")]) for s, v, a in req.start]
    to_a = integration_map(req.mesh)
    a0 = [np.asarray(a).ravel(order="F") for _, _, a in req.start]
    out = {"count": 2 * math.pi * axis.radius / settings.encoder_counts}
    parts = error_rows(resp, axis, settings, instants, lambda t: position_map(req, t), z0)
    held = np.sort(np.argsort(-np.abs(parts[0][0] + parts[1][0]), kind="stable")[:held_rows(req)])
    for part, (e0, rows) in zip(("motion", "load"), parts):
        rows = [g[held] @ to_a for g in rows]
        out[part] = ((e0[held] - sum(g @ a for g, a in zip(rows, a0))).reshape(-1, 1), rows)
    cache["servo"] = out
    return cache["servo"]


def held_rows(req) -> int:
    """Rows of the term in the NLP of the solve ``req``: the :data:`HELD_ROWS` largest errors at its start stroke
    of the ``(WINDOW_POINTS + 1) * len(TABLE_PHASES)`` the window has; all of them where it has fewer or where the
    objective minimises the term (``req.terms_minimised``)."""
    every = (WINDOW_POINTS + 1) * len(TABLE_PHASES)
    return every if getattr(req, "terms_minimised", False) else min(HELD_ROWS, every)


#: Rows of the term a solve with the accuracy held has: the instants (and table phases) of the window with the
#: largest error at the solve's start stroke, where the term is exact. Every row is a dense pair of constraint
#: rows over the moves' accelerations, and with all 100 the factorisation of IPOPT's linear system took two
#: thirds of a solve with the accuracy held; at a solution that holds it, 3 to 7 rows are within 10 % of the largest error, 12 to 36 within
#: 30 %. A row left out is in the exact check of the solution (the term taken again with the solution as its
#: start: its largest errors are its rows), and a solution that breaks the accuracy there is solved again from
#: itself, as for the load forces' linearisation (:data:`LOAD_PASSES`).
HELD_ROWS = 32

#: Grid instants after the end of the handover move checked in the design, spread evenly over the
#: handover window (the end of the move is one more), for each of the simulation's table phases: the full
#: simulation takes the largest error over the window's grid, and a design that checked the end alone would
#: place a zero of the residual vibration there. Each instant is a pair of linear rows of the NLP
#: (:class:`ErrorExpression`). 24 instants space the 5.4 ms window at 617 spm by 1/11 of the 1.9 ms belt
#: period of the reference drive.
WINDOW_POINTS = 24
