"""The trade-off's reference search (tests only): the highest rate of the optimal stroke by bisection on the
rate, one design solve per trial, each confirmed by the full servo simulation. ``strokeopt tradeoff`` uses the
min_time continuation of :func:`strokeopt.studies.tradeoff.tradeoff_optimal`; tests/design/test_min_time.py holds the
two against each other."""

from __future__ import annotations

import math
from dataclasses import replace

from strokeopt.drive.checks import within_limit
from strokeopt.drive.sizing import bisect_highest
from strokeopt.errors import SolverError
from strokeopt.servo.accuracy import handover_accuracy
from strokeopt.studies.confirm import binding_of as _binding_of
from strokeopt.studies.tradeoff import DEFAULT_ACCURACIES_MM, TradeoffPoint


def tradeoff_optimal_bisection(problem, accuracies=None, *, resolution: float = 10.0, lowest: float = 100.0,
                     start: float | None = None, progress=None) -> list[TradeoffPoint]:
    """Highest stitch rate with the optimal stroke by bisection (the reference of
    :func:`strokeopt.studies.tradeoff.tradeoff_optimal`): ``design.solve_design`` with the handover
    accuracy constraint, which includes :class:`.kernel.ServoErrorTerm`, for each accuracy [m].

    Bisection on the rate, one design solve per trial (warm-started). A rate
    counts only when the design solves *and* its full simulation
    (:func:`handover_accuracy`: table sampling, load forces, the handover
    window) meets the accuracy without the torque command passing its limit:
    the design's own term sees the end of the move with a continuous
    reference only. The binding limit is what fails just above the highest rate. Tighter accuracies are solved first; a looser accuracy
    starts from the rate the tighter one reached (the curve is monotone). The
    motor and pulley are the problem's (``drive.motor``, ``pulley_teeth``), as
    for the classic law, so the two curves compare strokes on one drive.
    """
    from strokeopt.design.transcription.settings import DesignSettings
    from strokeopt.design.solve import solve_design

    accuracies = sorted(a * 1e-3 for a in DEFAULT_ACCURACIES_MM) if accuracies is None else sorted(accuracies)
    base = problem.design or DesignSettings()
    start = problem.spm if start is None else start
    points = []
    lo_known = None
    warm = None
    for acc in accuracies:
        if progress:
            progress(f"optimal {acc * 1e3:g} mm", "bisection")
        # the same drive as the classic law: the problem's motor and pulley
        settings = replace(base, accuracy=acc, motor_choice="fixed", pulley="fixed")
        reasons: dict = {}
        designs: dict = {}

        def ok(spm, settings=settings, acc=acc):
            nonlocal warm
            try:
                d = solve_design(problem, spm=spm, settings=settings, warm_start=warm)
            except SolverError as exc:
                reasons[round(spm, 6)] = exc.reason
                return False
            warm = d
            # the design's accuracy term is the loop with a continuous reference at the end of the move:
            # the rate counts only if the full simulation (table, load forces, window) agrees
            res = handover_accuracy(problem, d.stroke, spm)
            if res.torque_limited:
                reasons[round(spm, 6)] = (f"torque limit: the servo's torque command reaches "
                                          f"{res.peak_torque_command:.2f} N m, limit {res.torque_limit:.2f} N m")
                return False
            if not within_limit(res.handover_error, acc):
                reasons[round(spm, 6)] = (f"handover accuracy: the full simulation of the design gives "
                                          f"{res.handover_error * 1e3:.4f} mm")
                return False
            designs[spm] = (d, res)
            return True

        lo = lo_known if lo_known is not None else None
        if lo is None:
            x = start
            while x >= lowest and not ok(x):
                x /= 1.5
            lo = x if x >= lowest else None
        if lo is None:
            reason = reasons.get(round(x * 1.5, 6), "")
            points.append(TradeoffPoint(acc, "optimal", None, _binding_of(reason), None, reason))
            continue
        hi = lo * 1.25
        while ok(hi):
            lo, hi = hi, hi * 1.25
        found = bisect_highest(ok, lo, hi, resolution)[0]
        max_spm = math.floor(found / resolution) * resolution
        fail_reason = reasons.get(min(reasons, key=lambda k: abs(k - found)), "") if reasons else ""
        error, detail = None, fail_reason
        if found in designs:
            error = designs[found][1].handover_error
            detail = f"at {found:.1f} spm the full simulation gives {error * 1e3:.4f} mm; above: {fail_reason}"
        points.append(TradeoffPoint(acc, "optimal", max_spm, _binding_of(fail_reason), error, detail))
        lo_known = max_spm
    return points
