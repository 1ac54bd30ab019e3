"""Rigid lower bounds that rule a catalogue motor out before any NLP is solved for it.

Every rest-to-rest move of stroke ``h`` in time ``T`` reaches a peak acceleration of at least ``4 h / T^2``
(the parabolic law is the least: docs/architecture.md, known optima), and more under a jerk bound (the
symmetric trapezoid of acceleration: :func:`least_peak_acceleration`). At
that instant a belt pulley of radius ``r`` asks the motor for ``|J a / r + r (m a - F)|`` with ``F`` the load
forces and gravity on the bar, so its peak torque is at least ``min over r of (J/r + m r) a - r |F|max``
(``J`` the rotor's inertia and the smallest pulley's: a larger pulley's only adds). The minimum over the pulleys the search may
take is found exactly (``r* = sqrt(J a / (m a - |F|))`` clipped to the range). A motor whose bound exceeds its
torque limit cannot carry the design at this rate with any pulley: :func:`prune` drops it with that reason,
and the answer of the search is the exhaustive one (a dropped motor would have failed its solve). Where the
objective is the peak torque itself, the bound also orders the search (:func:`best_bound_first`): once a
design is at least as good as the next motor's bound, no motor left can win (:func:`cannot_win`).

The bound is not made where it would not be one: a stepper (its limit is a curve over the speed), the
problem's own transmission (a screw and lever: no pulley to choose), members between motor and load, free
model parameters (the load forces are decision variables), a free cycle time (min_time: no fixed ``T``).
"""

from __future__ import annotations

import math

import numpy as np

from ..transcription.drive_model import peak_limit
from ..transcription.objectives import free_time, is_peak_torque
from ...drive.checks import is_stepper
from ...errors import LimitError


def torque_lower_bound(req, motor) -> tuple[float, int] | None:
    """``(bound [N m], move index)``: the least peak torque any stroke of ``req`` asks of ``motor`` with any
    pulley of the search, and the move that sets it; None where no such bound is made (see the module)."""
    drive, settings = req.drive, req.settings
    if (drive is None or drive.own_transmission is not None or is_stepper(motor) or free_time(req.objective)
            or settings.free or drive.load.members or drive.load.has_friction or drive.load.efficiency != 1.0):
        return None  # (friction and losses help braking: the rigid bound below would not hold)
    load = drive.load
    positions = [p for mv in req.moves for p in np.linspace(mv.start, mv.start + mv.stroke, 201)]
    s = np.asarray(positions)
    f_ext = sum((f(s) for f in load.forces), np.zeros_like(s))
    f_max = float(np.max(np.abs(load.moving_mass * load.gravity + f_ext)))  # |m g + F|, g signed
    if settings.pulley == "fixed":
        lo = hi = drive.pulley(req.problem.pulley_teeth).radius
    else:
        lo, hi = drive.radius_bounds()
    # the pulley's inertia grows with its radius: the smallest pulley's is less than any other's
    j, m = motor.rotor_inertia + float(drive.pulley_inertia(2 * lo)), load.moving_mass
    best = None
    for mv in req.moves:
        if mv.start_speed or mv.end_speed:  # the bound is a rest-to-rest move's: one at speed may not accelerate
            continue
        a = least_peak_acceleration(abs(mv.stroke), mv.duration, mv.jerk_bound)
        slope = m * a - f_max
        r = hi if slope <= 0 else min(max(math.sqrt(j * a / slope), lo), hi)
        bound = j * a / r + r * slope
        if best is None or bound > best[0]:
            best = (bound, mv.index)
    return best


def least_peak_acceleration(h: float, T: float, jerk: float | None) -> float:
    """The least peak |acceleration| of a rest-to-rest move of stroke ``h`` in ``T`` (v = a = 0 at both ends)
    with ``|jerk| <= jerk`` (None: unbounded): the symmetric trapezoid of acceleration, ``a`` from
    ``h = a (T/2 - a/jerk) T/2``; ``4 h / T^2`` without a bound. A bound below ``32 h / T^3`` admits no move:
    the solve says so, the bound here stays the unbounded one."""
    if jerk is None or not math.isfinite(jerk) or jerk * T**3 < 32.0 * h:
        return 4.0 * h / T**2
    return jerk * T / 4.0 * (1.0 - math.sqrt(1.0 - 32.0 * h / (jerk * T**3)))


def best_bound_first(req, motors: list) -> list[tuple[object, float | None]]:
    """``motors`` with the bound each gives the objective, best first: where the objective is the peak torque
    (min_peak_torque) its :func:`torque_lower_bound` bounds every design of the motor, so a search that has a
    design at least as good as a motor's bound need not solve that motor (:func:`cannot_win`). For any other
    objective the bound says nothing of the objective: the smallest motor (least rated torque) first, bounds None,
    so where designs tie the smallest motor is the one the search keeps (parts.py)."""
    if not is_peak_torque(req.objective):
        return [(m, None) for m in sorted(motors, key=lambda m: getattr(m, "rated_torque", None) or 0.0)]
    bounds = [(m, (torque_lower_bound(req, m) or (None,))[0]) for m in motors]
    return sorted(bounds, key=lambda mb: -math.inf if mb[1] is None else mb[1])


def cannot_win(bound: float | None, best: float | None, tol: float) -> bool:
    """Whether a motor whose objective bound is ``bound`` cannot beat the best design found (``best``, same unit):
    its bound exceeds it by more than the design's ``check_tolerance`` (the objective is read at the collocation
    nodes, the bound holds for the continuous stroke)."""
    return bound is not None and best is not None and bound > best * (1 + tol)


#: A motor whose rigid torque bound is at least this share of its torque limit is checked for feasibility before
#: it is solved (:func:`near_limit`): where it fails, IPOPT would spend its restoration phase proving it.
NEAR_LIMIT_SHARE = 0.85


def near_limit(req, motor) -> bool:
    """Whether ``motor``'s torque bound reaches :data:`NEAR_LIMIT_SHARE` of its limit (False: no bound made)."""
    found = torque_lower_bound(req, motor)
    return found is not None and found[0] >= NEAR_LIMIT_SHARE * peak_limit(motor, req.drive, req.settings.torque_reserve)


def prune(req, motors: list) -> tuple[list, list]:
    """``(kept, dropped)``: the motors whose torque lower bound exceeds their torque limit (beyond the design's
    check_tolerance) dropped, each as ``(motor, LimitError)`` naming the bound, the move and the limit."""
    kept, dropped = [], []
    tol = req.settings.check_tolerance
    for motor in motors:
        found = torque_lower_bound(req, motor)
        limit = peak_limit(motor, req.drive, req.settings.torque_reserve)
        if found is None or found[0] <= limit * (1 + tol):
            kept.append(motor)
            continue
        bound, move = found
        short = (f"peak_torque needs at least {bound:.4g} N m with any pulley (move {move}: peak acceleration at "
                 f"least the jerk-bounded least one), limit {limit:.4g} N m ({100 * (bound / limit - 1):.1f} % over)")
        dropped.append((motor, LimitError(f"the design cannot meet the limits for motor {motor.name} at "
                                          f"{req.spm:g} spm: {short} (a bound, no solve needed)",
                                          bound / limit - 1, short)))
    return kept, dropped
