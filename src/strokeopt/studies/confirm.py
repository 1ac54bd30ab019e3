"""The confirming search of one accuracy of the trade-off (:mod:`.tradeoff`): a design's full servo simulation
judged against the accuracy and the torque limit (:func:`confirm`), and below a rate it rejects, the highest grid
rate whose most accurate stroke the simulation confirms (:func:`search_below`)."""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

from ..drive.checks import within_limit
from ..errors import AccuracyUnreachable, SolverError
from ..servo.accuracy import handover_accuracy


def binding_of(reason: str) -> str:
    """The limit a failed design names first (its first line names the worst violated limit)."""
    text = (reason.splitlines() or [""])[0].lower().replace("_", " ")
    for key, name in (("handover accuracy", "handover_accuracy"), ("torque limit", "torque_limit"),
                      ("rms", "rms_torque"), ("peak torque", "peak_torque"),
                      ("speed", "peak_speed"), ("belt", "belt_tension"), ("jerk", "jerk"), ("inertia", "inertia_ratio")):
        if key in text:
            return name
    return "solver"


#: The smallest relative step down of the confirming search of :func:`.tradeoff.tradeoff_optimal`.
CONFIRM_TOLERANCE = 2e-3
#: Trial rates of the confirming search at most, per accuracy.
CONFIRM_TRIALS = 6
#: Re-solves of ``min_time`` with a torque reserve at most, per accuracy: where the servo's torque command
#: passes the torque limit that the rigid load of the design meets, the design keeps the excess unused
#: (``[design] torque_reserve_pct``) and is solved again; the margin added to each step.
RESERVE_STEPS = 2
RESERVE_MARGIN = 2e-3
#: The bracket of rates at which ``min_time`` stops halving (``DesignSettings.rate_bracket``): about the
#: resolution of the answer (10 spm at 600-900 spm); the confirming search tries the grid rates below it.
RATE_BRACKET = 1e-2
#: The step down after a trial rate without a design (its most accurate stroke misses the accuracy there).
NO_DESIGN_STEP = 0.95
#: The objective of the confirming search's designs: at each trial rate the most accurate stroke (its term
#: minimised), so the search asks whether *a* stroke meets the accuracy there; one solve, no pinned torques.
SEARCH_OBJECTIVE = "min_handover_error"
#: Consecutive hopeless trial rates (no design: the most accurate stroke's term misses the accuracy there; or
#: a simulated error no smaller than at the rate above) after which the confirming search gives up: lower
#: rates do not help once the error is set by the table, the encoder and the belt's vibration rather than by
#: the speed.
NO_DESIGN_TRIALS = 2


@dataclass
class Trial:
    """A design at one rate and its full simulation: ``excess`` > 0 fails (max of error/accuracy and
    torque command/limit, minus 1; inf when the design has no solution)."""

    spm: float
    excess: float
    reason: str = ""
    design: object = None
    result: object = None

    @property
    def ok(self) -> bool:
        return self.excess <= 0.0


def confirm(problem, design, spm: float, acc: float) -> Trial:
    """The full servo simulation of ``design``'s stroke at its rate: does it meet ``acc`` within the torque
    limit? The accuracy within the design's ``check_tolerance``: the design holds its error term at
    instants of the handover window, and between two of them the error may peak that much higher."""
    res = handover_accuracy(problem, design.stroke, spm)
    tol = design.settings.check_tolerance if design.settings is not None else 0.0
    excess = max(res.handover_error / (acc * (1 + tol)), res.peak_torque_command / res.torque_limit) - 1.0  # <= 0:
    # within_limit(error, acc, tol) and the torque command within its limit
    reason = ""
    if res.torque_limited:
        reason = (f"torque limit: the servo's torque command reaches {res.peak_torque_command:.2f} N m, "
                  f"limit {res.torque_limit:.2f} N m")
    elif not within_limit(res.handover_error, acc, tol):
        reason = f"handover accuracy: the full simulation of the design gives {res.handover_error * 1e3:.4f} mm"
    return Trial(spm, excess, reason, design, res)


def failed_fields(trial: Trial) -> dict:
    """The failed-rate fields of a :class:`TradeoffPoint` from a rejected trial."""
    error = None if trial.result is None else trial.result.handover_error
    return {"failed_spm": trial.spm, "failed_error": error, "failed_reason": trial.reason.splitlines()[0]}


def more_reserve(reserve: float, res) -> float:
    """The torque reserve that leaves the servo's torque command of ``res`` (an accuracy result) within its limit."""
    return 1.0 - (1.0 - reserve) * res.torque_limit / res.peak_torque_command * (1.0 - RESERVE_MARGIN)


def search_below(problem, hi: Trial, settings, acc: float, resolution: float, lowest: float, warm, say):
    """The highest rate below the rejected ``hi`` whose design (:data:`SEARCH_OBJECTIVE` at that rate) the full
    simulation confirms, on the grid of the resolution (the answer is reported on it): first the grid rate just
    below ``hi``, then steps down by the simulation's excess (torque and error grow about with the square of
    the rate), then a secant through the
    latest two trials, kept inside the bracket of the confirmed and the rejected rate (else its middle), each
    trial rounded to a grid rate inside the bracket, until no grid rate is left between them. Returns the
    confirmed trial (None: none) and the lowest rejected one above it."""
    from ..design.solve import solve_design

    def trial(spm: float) -> Trial:
        nonlocal warm, settings
        for _ in range(1 + RESERVE_STEPS):
            try:
                d = solve_design(problem, objective=SEARCH_OBJECTIVE, spm=spm, settings=settings, warm_start=warm)
            except SolverError as exc:
                say(f"{spm:.1f} spm: no design ({exc.reason.splitlines()[0]})")
                return Trial(spm, math.inf, exc.reason)
            warm = d
            t = confirm(problem, d, spm, acc)
            tol = d.settings.check_tolerance if d.settings is not None else 0.0
            res = t.result
            if t.ok or not res.torque_limited or not within_limit(res.handover_error, acc, tol):
                break
            # the loop's torque command passes the limit the rigid load meets: more in reserve, here and above
            settings = replace(settings, torque_reserve=more_reserve(settings.torque_reserve, res))
            say(f"{spm:.1f} spm: {t.reason}; again with {100 * settings.torque_reserve:.1f} % of the torque limit "
                "in reserve")
        say(f"{spm:.1f} spm: " + ("confirmed" if t.ok else t.reason))
        return t

    def step_down(t: Trial) -> float:
        factor = 1.0 / math.sqrt(1.0 + t.excess) if math.isfinite(t.excess) else NO_DESIGN_STEP
        return t.spm * min(factor, 1.0 - CONFIRM_TOLERANCE)

    def on_grid(x: float, floor: float) -> float | None:
        """The grid rate nearest ``x`` strictly between ``floor`` and the rejected rate (None: none is left)."""
        first = math.floor(floor / resolution + 1e-9) + 1
        last = math.ceil(hi.spm / resolution - 1e-9) - 1
        if last < first:
            return None
        return resolution * min(max(round(x / resolution), first), last)

    lo, trials, no_design = None, 0, 0
    x = on_grid(hi.spm, lowest - resolution)  # the most accurate stroke may meet it just below the rejected one
    while lo is None:
        if x is None or x < lowest or trials >= CONFIRM_TRIALS or no_design >= NO_DESIGN_TRIALS:
            return None, hi
        t, trials = trial(x), trials + 1
        hopeless = t.design is None or (not t.ok and math.isfinite(hi.excess) and t.excess >= hi.excess)
        no_design = no_design + 1 if hopeless else 0
        if t.ok:
            lo = t
        else:
            hi = t
            x = on_grid(min(step_down(t), t.spm - resolution), lowest - resolution)
    last = [hi, lo]  # the two latest finite trials: a secant through them, kept inside the bracket
    while trials < CONFIRM_TRIALS:
        a, b = last[-2], last[-1]
        mid = 0.5 * (lo.spm + hi.spm)
        x = (b.spm - b.excess * (b.spm - a.spm) / (b.excess - a.excess)
             if math.isfinite(a.excess) and b.excess != a.excess else mid)
        if not lo.spm < x < hi.spm:
            x = mid
        x = on_grid(x, lo.spm)
        if x is None:
            break
        t, trials = trial(x), trials + 1
        if t.ok:
            lo = t
        else:
            hi = t
        if math.isfinite(t.excess):
            last.append(t)
    return lo, hi


def least_error(problem, settings, spm: float, acc: float) -> Trial:
    """What an accuracy without a rate misses by: the most accurate stroke at ``spm`` (:data:`SEARCH_OBJECTIVE`,
    the drive of ``settings``) and its full simulation. Where the design finds its least error above the accuracy
    (the usual case: it then has no design to simulate), the trial's result is None and its ``excess`` that error's
    (the design's exact term at its solution: the simulation's error at the window's checked instants); where it
    finds no design (another limit), the excess is inf and the reason says why."""
    from ..design.solve import solve_design

    try:
        design = solve_design(problem, objective=SEARCH_OBJECTIVE, spm=spm, settings=settings)
    except AccuracyUnreachable as exc:
        return Trial(spm, exc.least_error / acc - 1.0, exc.reason)
    except SolverError as exc:
        return Trial(spm, math.inf, exc.reason)
    return confirm(problem, design, spm, acc)
