"""The handover error of the full servo simulation as rows linear in the design's variables.

The full simulation (:func:`.accuracy.handover_accuracy`) drives the loop with the stroke's position table
(a point every table interval, interpolated; the speed and acceleration feed-forwards its differences), the
load forces on the bar where the commanded stroke puts it, and their torque in the feed-forward read at the
table points; the error is the commanded stroke less the bar's position, on the simulation's time grid,
worst of :data:`.accuracy.TABLE_PHASES`. Everything but the load forces is linear in the table positions,
and the loop is time-invariant, so

* :class:`TableResponse` holds three periodic responses of the bar on that grid (cached per loop and rate):
  to one unit table point (its reference, speed and inertia feed-forwards), to a unit load force at one grid
  instant and to a unit torque in the feed-forward held around one table point. The grid has a whole number
  of steps per table interval and per table phase, so every other table point and phase is the same
  response shifted by whole steps;
* :func:`error_rows` gives the error at chosen grid instants and phases as ``e0 + G (z - z0)``: ``z`` the
  variables of every move, positions linear in them (a :class:`PositionMap`), the load forces linearised
  about the stroke ``z0`` (their jumps, where a spring starts to act, spread over the stroke's travel in one
  sample). At ``z0`` the rows are the simulation's errors at those instants, to rounding.
"""

from __future__ import annotations

from dataclasses import dataclass
from types import SimpleNamespace

import numpy as np

from .accuracy import TABLE_PHASES
from .loop import STEPS_PER_CYCLE, Gains, build_loop, cycle_grid, periodic_response, reference_signals, table_interval
from .plant import DriveAxis
from .settings import ServoSettings


@dataclass(frozen=True)
class TableResponse:
    """Periodic responses of the bar position on the simulation's grid ``t`` (``n`` steps a cycle, ``t[0]``
    and ``t[n]`` the same instant), each a sequence over ``n`` steps: ``table`` to a unit point of the
    position table at time 0 (phase 0), ``force`` to a unit load force at grid instant 0, ``feedforward`` to
    a unit torque in the feed-forward over the control cycle around table point 0. Table point ``k`` at
    phase ``p`` is ``steps * k + shifts[p]`` grid steps later."""

    period: float
    t: np.ndarray
    table_interval: float
    points: int  # table points a cycle
    steps: int  # grid steps a table interval
    shifts: tuple  # grid steps of each table phase
    delay: float
    table: np.ndarray
    force: np.ndarray
    feedforward: np.ndarray

    @property
    def n(self) -> int:
        return len(self.t) - 1

    def table_times(self, phase: int) -> np.ndarray:
        """The instants of the table points the drive reads at phase index ``phase``."""
        return (np.arange(self.points) * self.steps + self.shifts[phase]) * (self.period / self.n)

    def shifted(self, response: np.ndarray, grid: np.ndarray, phase: int) -> np.ndarray:
        """``response`` at each grid index of ``grid`` for every table point at ``phase``: (len(grid), points)."""
        lag = grid.reshape(-1, 1) - self.steps * np.arange(self.points).reshape(1, -1) - self.shifts[phase]
        return response[np.mod(lag, self.n)]


class _UnitPoint:
    """A 'stroke' whose position table is one at the table points ``k = 0 (mod points)``, zero elsewhere."""

    def __init__(self, period: float, tc: float):
        self.period, self.tc, self.points = period, tc, int(round(period / tc))

    def evaluate(self, t):
        k = np.mod(np.round(np.asarray(t, dtype=float) / self.tc).astype(int), self.points)
        return SimpleNamespace(s=(k == 0).astype(float))


_RESPONSES: dict = {}


def table_response(axis: DriveAxis, settings: ServoSettings, gains: Gains, period: float) -> TableResponse:
    """The :class:`TableResponse` of a loop at a cycle of ``period`` seconds (cached; the load is not part of it)."""
    key = (axis.motor_inertia, axis.radius, axis.mass, axis.belt_stiffness, axis.belt_damping, settings, gains,
           round(period, 12))
    if key in _RESPONSES:
        return _RESPONSES[key]
    loop = build_loop(axis, settings, gains)
    t = cycle_grid(period, settings)
    n = len(t) - 1
    tc = table_interval(period, settings)
    shifts = tuple(phase * STEPS_PER_CYCLE for phase in TABLE_PHASES)
    if any(abs(s - round(s)) > 1e-9 for s in shifts):
        raise ValueError("every table phase must be a whole number of simulation steps")
    unit = _UnitPoint(period, tc)
    u_table = reference_signals(loop, unit, t, forces=False, load_ff=False)
    u_force = np.zeros_like(u_table)
    u_force[3, 0] = u_force[3, -1] = 1.0
    u_ff = np.zeros_like(u_table)
    kc = np.mod(np.round(t / tc).astype(int), unit.points)  # the table point each instant's feed-forward reads
    u_ff[2] = (kc == 0).astype(float)
    outputs = periodic_response(loop.system, t, u_table, u_force, u_ff)
    x = [out[2][:n] for out in outputs]
    if len(_RESPONSES) > 16:
        _RESPONSES.pop(next(iter(_RESPONSES)))
    _RESPONSES[key] = TableResponse(period, t, tc, unit.points, STEPS_PER_CYCLE, tuple(int(round(s)) for s in shifts),
                                    settings.sum_small_time_constants, *x)
    return _RESPONSES[key]


@dataclass(frozen=True)
class PositionMap:
    """The stroke's position at given instants as ``const + sum over moves of M[m] @ z[m]``."""

    const: np.ndarray
    matrices: tuple

    def at(self, z: list) -> np.ndarray:
        return self.const + sum((m @ zm for m, zm in zip(self.matrices, z)), np.zeros_like(self.const))


def _local_derivative(force, s: np.ndarray, travel: np.ndarray) -> np.ndarray:
    """dF/ds along the positions ``s`` by a central difference over ``travel`` (at least 1 um): a jump of the
    force (a spring that starts to act with its preload) is spread over the travel of one sample."""
    step = np.maximum(travel, 1e-6)
    return (force(s + step) - force(s - step)) / (2 * step)


def _travel(s: np.ndarray) -> np.ndarray:
    """Half the travel between each sample's neighbours of a periodic sequence of positions."""
    return 0.5 * np.abs(np.roll(s, -1) - np.roll(s, 1))


def _product(left: np.ndarray, positions: np.ndarray) -> np.ndarray:
    """``left @ positions`` over the rows of ``positions`` that are not zero (a move's instants: the dwells'
    positions are constants, most of the cycle)."""
    rows = np.flatnonzero(np.any(positions != 0.0, axis=1))
    return left[:, rows] @ positions[rows]


def error_rows(resp: TableResponse, axis: DriveAxis, settings: ServoSettings, instants: np.ndarray,
               position_map, z0: list) -> tuple[tuple[np.ndarray, list], tuple[np.ndarray, list]]:
    """The bar error at ``instants`` (rows: ``(j, w)`` = the error ``(1 - w) e[j] + w e[j + 1]`` at grid
    indices ``j``, ``j + 1``) for every table phase, phase after phase, as ``e0 + G (z - z0)``, in two parts:
    the motion's (exact: linear) and the load forces' (linearised about the stroke ``z0``), each ``(e0, G)``
    with ``G`` per move. ``position_map(times)`` is the :class:`PositionMap` of the stroke at ``times``
    (seconds from the cycle start)."""
    n, d, r = resp.n, resp.delay, axis.radius
    grid_t = resp.t[:n]
    idx = np.concatenate([instants[:, 0], instants[:, 0] + 1]).astype(int)
    grid = np.mod(idx, n)
    weights = np.concatenate([1 - instants[:, 1], instants[:, 1]])
    rows = len(instants)

    def combine(values: np.ndarray) -> np.ndarray:  # values at the grid indices -> values at the instants
        values = values * weights.reshape(-1, *([1] * (values.ndim - 1)))
        return values[:rows] + values[rows:]

    force = (lambda s: axis.external_force(s)) if axis.load is not None else None
    commanded = position_map(np.mod(grid_t[grid] - d, resp.period))
    motion, load = ([], []), ([], [])
    if force is not None:  # the load force where the commanded stroke puts the bar, on every grid instant
        bar = position_map(np.mod(grid_t - d, resp.period))
        s_bar = bar.at(z0)
        df_bar = _local_derivative(force, s_bar, _travel(s_bar))
        lag_f = resp.force[np.mod(grid.reshape(-1, 1) - np.arange(n).reshape(1, -1), n)]  # (2 rows, n)
        x_force0 = lag_f @ force(s_bar)
        g_force = [_product(lag_f * df_bar, m) for m in bar.matrices]
    for phase in range(len(resp.shifts)):
        table = position_map(np.mod(resp.table_times(phase), resp.period))
        p0 = table.at(z0)
        lag_t = resp.shifted(resp.table, grid, phase)
        motion[0].append(combine(commanded.at(z0) - lag_t @ p0))
        motion[1].append([combine(mc - _product(lag_t, mt)) for mc, mt in zip(commanded.matrices, table.matrices)])
        e_vals = np.zeros(len(grid))
        g_vals = [np.zeros((len(grid), m.shape[1])) for m in table.matrices]
        if force is not None:
            e_vals = e_vals - x_force0
            g_vals = [gv - gf for gv, gf in zip(g_vals, g_force)]
            if settings.load_feedforward:  # the feed-forward torque -r F(table point) cancels most of it
                lag_ff = resp.shifted(resp.feedforward, grid, phase)
                df_table = _local_derivative(force, p0, _travel(p0))
                e_vals = e_vals - lag_ff @ (-r * force(p0))
                g_vals = [gv + r * _product(lag_ff * df_table, mt) for gv, mt in zip(g_vals, table.matrices)]
        load[0].append(combine(e_vals))
        load[1].append([combine(gv) for gv in g_vals])
    return tuple((np.concatenate(e0), [np.vstack([part[m] for part in g]) for m in range(len(z0))])
                 for e0, g in (motion, load))
