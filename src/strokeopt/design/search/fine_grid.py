"""The solution read on a fine grid between the collocation nodes.

After a solve (:mod:`.refine`): the peaks of every move from its exact polynomials
(:func:`move_results`), the jerk bounds between nodes (:func:`fine_grid_report`) and the drive package's
checks over the whole cycle (:func:`drive_checks_fine`), which decide whether the mesh is refined.
"""

from __future__ import annotations

import numpy as np

from ..transcription.collocation import MoveSolution, fine_grid, node_times
from ..transcription.pins import crossings, switch_positions
from ..transcription.request import DriveSetup, Move
from ...drive.transmission import BeltPulley


def fine_grid_report(moves: list[Move], sols: list[MoveSolution], per_interval: int) -> tuple[dict, list[dict]]:
    """Peaks on a fine grid between collocation nodes and the jerk-bound violations there."""
    rows = []
    worst = 0.0
    for mv, sol in zip(moves, sols):
        tau = fine_grid(sol.mesh, per_interval)
        y, y1, y2, y3, _ = sol.evaluate(tau)
        tn = node_times(sol.mesh)
        _, _, a_n, j_n, _ = sol.evaluate(tn)
        row = {"move": mv.index,
               "a_max_nodes_m_s2": float(np.max(np.abs(a_n))) * mv.a_scale,
               "a_max_fine_m_s2": float(np.max(np.abs(y2))) * mv.a_scale,
               "position_error_end_mm": abs(float(y[-1]) - 1.0) * abs(mv.stroke) * 1e3}
        if mv.jerk_bound is not None:
            jmax = float(np.max(np.abs(y3))) * mv.j_scale
            viol = max(0.0, jmax / mv.jerk_bound - 1.0)
            row.update(jerk_max_fine_m_s3=jmax, jerk_bound_m_s3=mv.jerk_bound, jerk_violation=viol)
            worst = max(worst, viol)
        rows.append(row)
    return {"points_per_interval": per_interval, "worst_relative_violation": worst, "moves": rows}, rows


def fine_cycle(problem, spm: float, moves: list[Move], sols: list[MoveSolution], per_interval: int,
                switch_positions=()):
    """Times, positions, speeds, accelerations over one whole cycle: fine grids in the moves, dwell ends.

    ``switch_positions``: positions where a load force switches (a spring met): the grid gets the
    crossing times, both sides, so a jump of the load is read at its worst.
    """
    sch = problem.timing.schedule(spm)
    ts, ss, vs, as_ = [], [], [], []
    it = iter(zip(moves, sols))
    for itv, t0, dur in zip(problem.timing.intervals, sch.t_start, sch.duration):
        if itv.is_move:
            mv, sol = next(it)
            tau = fine_grid(sol.mesh, per_interval)
            tau = np.unique(np.concatenate([tau, crossings(sol, mv, switch_positions, tau)]))
            y, y1, y2, _, _ = sol.evaluate(tau)
            ts.append(t0 + tau * dur)
            ss.append(mv.start + mv.stroke * y)
            vs.append(y1 * mv.stroke / dur)
            as_.append(y2 * mv.stroke / dur**2)
        else:
            ts.append(np.array([t0, t0 + dur]))
            ss.append(np.full(2, itv.start_position))
            vs.append(np.zeros(2))
            as_.append(np.zeros(2))
    return tuple(np.concatenate(x) for x in (ts, ss, vs, as_))


def drive_checks_fine(drive: DriveSetup, motor, choice, radius: float, rated, sols, per_interval: int) -> list:
    """The drive package's checks of the solution (``rated``: the request at the rate it runs at), on a fine
    grid over the whole cycle, on ``motor`` and ``choice``'s pulley (``teeth``, or the continuous ``radius``,
    its belt rated as ``choice.belt_teeth`` teeth -- None: the fewest of the range); the problem's own
    transmission (a screw and lever) has no pulley and no belt."""
    from ...drive.checks import drive_checks

    teeth, belt_teeth = choice.teeth, choice.belt_teeth
    switches = switch_positions(drive)
    t, s, v, a = fine_cycle(rated.problem, rated.spm, rated.moves, sols, per_interval, switches)
    if drive.own_transmission is not None:
        return drive_checks(motor, drive.own_transmission, drive.load, t, s, v, a, limits=drive.limits)
    if teeth is not None:
        trans = drive.transmission(teeth)
    else:
        trans = BeltPulley(2 * radius, inertia=float(drive.pulley_inertia(2 * radius)))
    grooves = teeth if teeth is not None else (belt_teeth or drive.teeth_range[0])
    return drive_checks(motor, trans, drive.load, t, s, v, a, limits=drive.limits, belt=drive.belt, grooves=grooves)
