"""`StrokeFunction`: the one representation of a stroke.

A stroke is the position ``s(t)`` of the driven member over one periodic
cycle, made of pieces (a dwell, a classic law, or a piece of an optimised
collocation solution). Each piece is a CasADi Function of its local time, so
the same object

* evaluates numerically (:meth:`StrokeFunction.evaluate`, numpy in and out),
* evaluates symbolically (:meth:`StrokeFunction.casadi_function`, for
  constraints and for the prescribed motion of an integrator),

and velocity, acceleration and jerk come from algorithmic differentiation.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import casadi as ca
import numpy as np

from .._casadi import evaluate


@dataclass(frozen=True)
class Piece:
    """One piece of a stroke on ``[t_start, t_start + duration)``.

    ``position`` maps local time ``tau`` in seconds (``0 <= tau <= duration``)
    to the position in metres. ``unbounded_jerk_inside`` is True where the
    piece's own acceleration jumps inside it (a parabolic law, say): the jerk
    there is an impulse, not a number.
    """

    t_start: float
    duration: float
    position: ca.Function
    label: str = ""
    unbounded_jerk_inside: bool = False
    #: optional numpy evaluation of ``[s, v, a, jerk]`` at local times (the same function as ``position``, faster
    #: on many points than a CasADi expression with a branch per polynomial piece: :func:`polynomial_piece`)
    numeric: object = field(default=None, repr=False, compare=False)
    _built: dict = field(default_factory=dict, init=False, repr=False, compare=False)

    @property
    def _ders(self) -> ca.Function:
        """``tau -> [s, v, a, jerk]`` by CasADi's algorithmic differentiation, built on first use (a piece with a
        ``numeric`` evaluation may never need it)."""
        if "ders" not in self._built:
            tau = ca.SX.sym("tau")
            s = self.position(tau)
            v = ca.jacobian(s, tau)
            a = ca.jacobian(v, tau)
            j = ca.jacobian(a, tau)
            self._built["ders"] = ca.Function("piece_ders", [tau], [s, v, a, j])
        return self._built["ders"]

    @property
    def t_end(self) -> float:
        return self.t_start + self.duration

    def derivatives(self, tau) -> list[np.ndarray]:
        """Numeric ``[s, v, a, jerk]`` at local times ``tau``."""
        if self.numeric is not None:
            return self.numeric(np.asarray(tau, dtype=float))
        return evaluate(self._ders, tau)

    def symbolic(self, tau):
        """``[s, v, a, jerk]`` as CasADi expressions of the local time."""
        return self._ders(tau)


def law_piece(t_start: float, duration: float, s_start: float, stroke: float, law, label: str = "") -> Piece:
    """A move ``s = s_start + stroke*y(tau/duration)`` with a motion law ``y``."""
    tau = ca.SX.sym("tau")
    expr = s_start + stroke * law(tau / duration)
    jump_inside = law.characteristics.continuity < 2 and bool(law.breaks)
    return Piece(t_start, duration, ca.Function("move", [tau], [expr]), label or law.label, jump_inside)


def polynomial_piece(t_start: float, duration: float, breaks, coefficients, label: str = "") -> Piece:
    """A piece made of polynomials of the local time: ``coefficients[k]`` (ascending) on ``[breaks[k],
    breaks[k + 1])``, measured from ``breaks[k]`` (``breaks[0] = 0``). CasADi holds it as a branch per
    polynomial; numpy evaluates it by locating each time's polynomial (``numeric``), the same numbers."""
    breaks = np.asarray(breaks, dtype=float)
    coefs = [np.asarray(c, dtype=float) for c in coefficients]
    tau = ca.SX.sym("tau")

    def horner(c, u):
        acc = ca.SX(float(c[-1]))
        for ck in c[-2::-1]:
            acc = acc * u + float(ck)
        return acc

    expr = horner(coefs[-1], tau - breaks[-1])
    for k in range(len(coefs) - 2, -1, -1):
        expr = ca.if_else(tau < breaks[k + 1], horner(coefs[k], tau - breaks[k]), expr)
    width = max(len(c) for c in coefs)
    table = np.zeros((len(coefs), width))
    for k, c in enumerate(coefs):
        table[k, :len(c)] = c
    ders = [table]
    for _ in range(3):  # coefficients of v, a, jerk
        prev = ders[-1]
        ders.append(np.column_stack([prev[:, 1:] * np.arange(1, prev.shape[1]), np.zeros(len(prev))]))

    def numeric(t):
        shape = np.shape(t)
        t = np.atleast_1d(t)
        idx = np.clip(np.searchsorted(breaks, t, side="right") - 1, 0, len(coefs) - 1)
        u = t - breaks[idx]
        out = []
        for c in ders:
            rows = c[idx]
            acc = rows[:, -1].copy()
            for k in range(c.shape[1] - 2, -1, -1):
                acc = acc * u + rows[:, k]
            out.append(acc.reshape(shape))
        return out

    return Piece(t_start, duration, ca.Function("polynomials", [tau], [expr]), label, numeric=numeric)


def dwell_piece(t_start: float, duration: float, position: float, label: str = "dwell") -> Piece:
    tau = ca.SX.sym("tau")
    return Piece(t_start, duration, ca.Function("dwell", [tau], [position + 0 * tau]), label)


@dataclass(frozen=True)
class Kinematics:
    """Sampled stroke: time [s], position [m], velocity [m/s], acceleration [m/s^2], jerk [m/s^3]."""

    t: np.ndarray
    s: np.ndarray
    v: np.ndarray
    a: np.ndarray
    j: np.ndarray


@dataclass(frozen=True)
class PiecePeaks:
    """Peaks of |v|, |a|, |jerk| over one piece. ``j_max`` is inf where the acceleration jumps."""

    v_max: float
    a_max: float
    j_max: float


class StrokeFunction:
    """Position of the driven member over one periodic cycle of ``period`` seconds.

    Parameters
    ----------
    period:
        Cycle time in seconds; the pieces must tile ``[0, period)``.
    pieces:
        The pieces in time order.
    label:
        What the stroke is (a law name, "optimal", ...), for plots and reports.
    """

    def __init__(self, period: float, pieces: list[Piece], label: str = ""):
        if not pieces:
            raise ValueError("a stroke needs at least one piece")
        t = 0.0
        for p in pieces:
            if abs(p.t_start - t) > 1e-12 * max(1.0, period) or p.duration < 0:
                raise ValueError(f"pieces must tile the cycle: piece {p.label!r} starts at {p.t_start}, expected {t}")
            t = p.t_end
        if abs(t - period) > 1e-9 * period:
            raise ValueError(f"pieces end at {t} s, not at the period {period} s")
        self.period = float(period)
        self.pieces = tuple(pieces)
        self.label = label
        self._fn = None

    def __repr__(self) -> str:
        return f"StrokeFunction({self.label!r}, period={self.period:g} s, {len(self.pieces)} pieces)"

    @property
    def breakpoints(self) -> np.ndarray:
        """Times where pieces join (where a derivative may jump), 0 and the period included."""
        return np.array([p.t_start for p in self.pieces] + [self.period])

    def evaluate(self, t) -> Kinematics:
        """Numeric s, v, a, jerk at times ``t`` (taken modulo the period).

        At a joint the piece that starts there is used.
        """
        t = np.atleast_1d(np.asarray(t, dtype=float))
        tm = np.mod(t, self.period)
        out = [np.zeros_like(tm) for _ in range(4)]
        starts = np.array([p.t_start for p in self.pieces])
        idx = np.clip(np.searchsorted(starts, tm, side="right") - 1, 0, len(self.pieces) - 1)
        for k, p in enumerate(self.pieces):
            mask = idx == k
            if np.any(mask):
                for o, val in zip(out, p.derivatives(tm[mask] - p.t_start)):
                    o[mask] = val
        return Kinematics(t, *out)

    def sample(self, n: int = 3601) -> Kinematics:
        """``n`` equally spaced samples over one cycle, both ends included."""
        return self.evaluate(np.linspace(0.0, self.period, n))

    def casadi_function(self) -> ca.Function:
        """``stroke(t) -> [s, v, a, jerk]`` as a CasADi Function (t in seconds, any real).

        Built from the pieces with ``if_else``; evaluate it on SX/MX symbols to
        use the stroke inside an integrator or an optimisation problem.
        """
        if self._fn is None:
            t = ca.SX.sym("t")
            tm = ca.fmod(ca.fmod(t, self.period) + self.period, self.period)
            outs = [ca.SX(0)] * 4
            for p in self.pieces:  # a later piece overrides from its start on
                vals = p.symbolic(tm - p.t_start)
                outs = [ca.if_else(tm >= p.t_start, val, o) for val, o in zip(vals, outs)]
            self._fn = ca.Function("stroke", [t], outs, ["t"], ["s", "v", "a", "jerk"])
        return self._fn

    def piece_peaks(self, samples: int = 20_001) -> list[PiecePeaks]:
        """Peaks of |v|, |a|, |jerk| of each piece (dense sampling of the exact derivatives).

        The jerk is unbounded (``inf``) where the acceleration jumps, inside a
        piece or at its joints with its neighbours.
        """
        n = len(self.pieces)
        ends = []  # (a at start, a at end) of each piece
        peaks = []
        for p in self.pieces:
            tau = np.linspace(0.0, p.duration, samples)
            _, v, a, j = p.derivatives(tau)
            ends.append((a[0], a[-1]))
            peaks.append([float(np.max(np.abs(v))), float(np.max(np.abs(a))), float(np.max(np.abs(j)))])
        a_scale = max(max(pk[1] for pk in peaks), 1e-300)
        result = []
        for k, p in enumerate(self.pieces):
            jump_before = abs(ends[k][0] - ends[(k - 1) % n][1]) > 1e-6 * a_scale
            jump_after = abs(ends[k][1] - ends[(k + 1) % n][0]) > 1e-6 * a_scale
            v_max, a_max, j_max = peaks[k]
            # a jump at a joint is an impulse of the piece that moves there (not of a dwell beside it)
            if p.unbounded_jerk_inside or ((jump_before or jump_after) and a_max > 0):
                j_max = math.inf
            result.append(PiecePeaks(v_max, a_max, j_max))
        return result
