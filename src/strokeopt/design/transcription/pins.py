"""Pinned points at the load switches: where a move passes a position at which a load force
switches on (a spring met), the torque and the belt force jump.

The collocation nodes alone would let the optimiser hide the worst side of the jump between two
nodes. A pinned point at the crossing holds both sides of it (:func:`pin_rows`, used by
:mod:`.drive_model`); the crossing is found from the previous solution and updated until it
stops moving (:mod:`.refine`). A pin's rows touch the variables of a window of
:data:`PIN_WINDOW` mesh intervals around the crossing (part of the NLP's structure); the
interval within the window and the local time are parameters.
"""

from __future__ import annotations

import casadi as ca
import numpy as np

from .collocation import Mesh, MoveSolution, fine_grid
from .request import Move, SolveRequest

#: Mesh intervals a pinned point may move across without a new NLP structure.
PIN_WINDOW = 3
#: The objective that pins the impact position as ``impact_velocity_max_m_s`` does (objectives.py).
IMPACT_OBJECTIVE = "min_impact_velocity"


def switch_positions(drive) -> list[float]:
    """Where a load force switches on (a spring met) or a torque of the transmission's own loads jumps."""
    own = drive.own_transmission.load_switches() if drive.own_transmission is not None else ()
    return [f.contact_position for f in drive.load.forces if f.kind == "spring"] + list(own)


def pin_positions(req: SolveRequest) -> list[float]:
    """Every pinned position of a solve: the drive's load switches, and where the contact model's rigid
    cluster meets its impact contact (``[design.contact] impact_velocity_max_m_s`` or the objective
    ``min_impact_velocity``, design/contact_limits.py)."""
    out = switch_positions(req.drive) if req.drive is not None else []
    contact = req.contact
    if contact is not None and contact.impact_position is not None and (
            contact.settings.impact_velocity_max is not None or req.objective == IMPACT_OBJECTIVE):
        out = out + [p for p in [contact.impact_position] if p not in out]
    return out


def crossings(sol: MoveSolution, mv: Move, positions, tau: np.ndarray) -> np.ndarray:
    """Unit times where the move passes ``positions`` (where a load force switches on), both sides of each."""
    if not positions:
        return np.zeros(0)
    y = sol.evaluate(tau)[0]
    out = []
    for pos in positions:
        target = (pos - mv.start) / mv.stroke
        f = y - target
        for i in np.nonzero(np.sign(f[:-1]) * np.sign(f[1:]) <= 0)[0]:
            lo, hi = tau[i], tau[i + 1]
            for _ in range(3):  # three dense zooms on the exact polynomial: (1/1000)^3 of the bracket
                grid = np.linspace(lo, hi, 1001)
                g = sol.evaluate(grid)[0] - target
                j = int(np.nonzero(np.sign(g[:-1]) * np.sign(g[1:]) <= 0)[0][0])
                lo, hi = grid[j], grid[j + 1]
            out += [lo, hi]
    return np.array(out)


def pin_intervals(req: SolveRequest) -> list[tuple[int, float, int | None]]:
    """(move, switch position, mesh interval of the crossing or None) of every load switch a move passes."""
    out = []
    for k, mv in enumerate(req.moves):
        lo, hi = sorted((mv.start, mv.start + mv.stroke))
        for pos in pin_positions(req):
            if lo < pos < hi:
                tau_c = req.pin_times.get((k, pos))
                idx = None if tau_c is None else min(int(tau_c / req.mesh.h), req.mesh.intervals - 1)
                out.append((k, pos, idx))
    return out


def pin_windows(intervals: list, mesh: Mesh) -> tuple:
    """The first mesh interval of each pin's window: the window centred on the crossing's interval."""
    w = min(PIN_WINDOW, mesh.intervals)
    return tuple((k, pos, None if idx is None else int(np.clip(idx - w // 2, 0, mesh.intervals - w)))
                 for k, pos, idx in intervals)


def pins_fit(windows: tuple, intervals: list, mesh: Mesh) -> bool:
    """Whether every crossing of ``intervals`` lies in its pin's window (a built structure serves it)."""
    w = min(PIN_WINDOW, mesh.intervals)
    return len(windows) == len(intervals) and all(
        (k, pos) == (k2, pos2) and (first is None) == (idx is None) and (idx is None or first <= idx < first + w)
        for (k, pos, first), (k2, pos2, idx) in zip(windows, intervals))


def pin_basis(req: SolveRequest, k: int, pos: float, first: int | None) -> tuple[np.ndarray, ...]:
    """This solve's crossing in its pin's window: one-hot interval, basis rows (acceleration,
    velocity increment) at the local time, weight (0: the move does not cross)."""
    mesh = req.mesh
    w = min(PIN_WINDOW, mesh.intervals)
    onehot = np.zeros(w)
    tau_c = req.pin_times.get((k, pos))
    if tau_c is None or first is None:
        m = mesh.matrices([0.0])
        onehot[0] = 1.0
        return onehot, m["a"][0], m["v"][0], 0.0
    idx = min(int(tau_c / mesh.h), mesh.intervals - 1)
    m = mesh.matrices([tau_c / mesh.h - idx])
    onehot[idx - first] = 1.0
    return onehot, m["a"][0], m["v"][0], 1.0


def pin_motion(g, k: int, pos: float, first: int | None):
    """Velocity and acceleration [SI] of move ``k`` where it passes ``pos`` (the pin's window starting at mesh
    interval ``first``), and the pin's weight (0: the move does not cross). The interval within the window and
    the local time are parameters, so the crossing may move across the window between solves without a new build."""
    if (k, pos) in g.pin_motions:  # the drive's rows and the contact limits read the same pin
        return g.pin_motions[(k, pos)]
    b, mesh, x, mv = g.built, g.request.mesh, g.vars[k], g.request.moves[k]
    d1 = mesh.degree + 1
    w = min(PIN_WINDOW, mesh.intervals)
    first_ = 0 if first is None else first

    def basis(part):
        return lambda r: pin_basis(r, k, pos, first)[part]

    e = b.params(f"pin e{k}.{pos}", basis(0), (w, 1))
    la = b.params(f"pin a{k}.{pos}", basis(1), (d1, 1))
    lv = b.params(f"pin v{k}.{pos}", basis(2), (d1, 1))
    weight = b.param(f"pin w{k}.{pos}", basis(3))
    A = x.A[first_:first_ + w, :]
    a_unit = ca.mtimes(e.T, ca.mtimes(A, la))
    v_unit = ca.mtimes(e.T, x.V[first_:first_ + w]) + mesh.h * ca.mtimes(e.T, ca.mtimes(A, lv))
    out = g.pin_motions[(k, pos)] = (weight, v_unit * mv.stroke / g.T[k], a_unit * mv.stroke / g.T[k] ** 2)
    return out


def _local_time(req: SolveRequest, k: int, pos: float) -> float:
    """The local time (0-1) in its mesh interval of the move's last crossing of ``pos`` (0.5: none yet)."""
    tau_c = req.pin_times.get((k, pos))
    if tau_c is None:
        return 0.5
    idx = min(int(tau_c / req.mesh.h), req.mesh.intervals - 1)
    return float(np.clip(tau_c / req.mesh.h - idx, 0.0, 1.0))


def pin_crossing(g, k: int, pos: float, first: int | None):
    """``(weight, v [m/s])`` of move ``k`` where it passes ``pos``, the crossing's local time a variable of the NLP
    in the mesh interval of the last solve's crossing (a parameter), held there by the row ``s = pos``: a value
    minimised at the crossing (``min_impact_velocity``) cannot move away from it, as it could from a pin at a fixed
    time (:func:`pin_motion`); the crossing may move to a neighbouring interval between solves
    (``refine.pins_in_place`` compares the intervals of these, :attr:`Graph.crossings`)."""
    key = ("crossing", k, pos)
    if key in g.pin_motions:
        return g.pin_motions[key]
    b, mesh, x, mv = g.built, g.request.mesh, g.vars[k], g.request.moves[k]
    w = min(PIN_WINDOW, mesh.intervals)
    first_ = 0 if first is None else first

    def basis(part):
        return lambda r: pin_basis(r, k, pos, first)[part]

    e = b.params(f"crossing e{k}.{pos}", basis(0), (w, 1))
    weight = b.param(f"crossing w{k}.{pos}", basis(3))
    theta = b.var(f"crossing time {k}.{pos}", (1, 1), 0.0, 1.0, lambda r: _local_time(r, k, pos))
    rows = mesh.symbolic_rows(theta)
    A = ca.mtimes(e.T, x.A[first_:first_ + w, :])
    V = ca.mtimes(e.T, x.V[first_:first_ + w])
    S = ca.mtimes(e.T, x.S[first_:first_ + w])
    s_unit = S + mesh.h * theta * V + mesh.h ** 2 * ca.mtimes(A, rows["s"].T)
    v_unit = V + mesh.h * ca.mtimes(A, rows["v"].T)
    b.constrain(f"crossing of move {mv.index} at {pos * 1e3:g} mm", weight * (s_unit - (pos - mv.start) / mv.stroke),
                0.0, 0.0)
    g.crossings.add((k, pos))
    out = g.pin_motions[key] = (weight, v_unit * mv.stroke / g.T[k])
    return out


def pin_rows(g, k: int, mv: Move, rotor, trans):
    """Torque and belt force (row vectors) on both sides of every pinned point the move passes
    (:func:`pin_motion`); a pin the move does not cross gets a zero weight."""
    from ...drive.load import load_torque

    taus, forces = [], []
    for k_, pos, first in g.pins:
        if k_ != k:
            continue
        weight, v, a = pin_motion(g, k, pos, first)
        eps = 1e-9 * max(abs(mv.stroke), 1e-3)
        for side in (-eps, eps):
            terms = load_torque(rotor, trans, g.load, ca.MX(pos + side), v, a)
            taus.append(weight * terms.total)
            forces.append(weight * terms.load_force)
    return (ca.horzcat(*taus) if taus else ca.MX(1, 0)), (ca.horzcat(*forces) if forces else ca.MX(1, 0))


def initial_pin_times(req: SolveRequest, sols: list[MoveSolution]) -> dict:
    """Unit times where each move of ``sols`` first passes each load switch it spans (None: it does not)."""
    out = {}
    for k, mv in enumerate(req.moves):
        lo, hi = sorted((mv.start, mv.start + mv.stroke))
        for pos in pin_positions(req):
            if lo < pos < hi:
                cross = crossings(sols[k], mv, [pos], fine_grid(sols[k].mesh, 4))
                out[(k, pos)] = float(cross[0]) if len(cross) else None
    return out


def pin_times(req: SolveRequest, pins: tuple, sols: list[MoveSolution]) -> dict:
    """Unit times where each move of ``sols`` first passes each pinned load switch (None: it does not)."""
    out = {}
    for k, pos, _ in pins:
        mv, sol = req.moves[k], sols[k]
        cross = crossings(sol, mv, [pos], fine_grid(sol.mesh, 4))
        out[(k, pos)] = float(cross[0]) if len(cross) else None
    return out
