"""A number of the model the collocation does not carry, chosen around the verified solve: ``[design.free.NAME]``
with ``field``/``range`` or ``moves``/``range_mm`` (design/transcription/settings.py ``OuterFree``).

The impact point of the needle bar (gap N smaller and the pad's gap H larger by the same amount, seed digest A)
moves where the stroke meets the stop: a pinned position of the collocation, not one of its variables. So the
number is searched around the whole verified solve (:func:`~.verified.solve_verified`: the design, the full servo
simulation, the contact scene): a scan of ``[lower, upper]``, then golden-section search around its best point to
:data:`TOLERANCE` of the range, each point the problem with that value's ``--set`` texts solved and judged (:func:`solve_outer`
says why the scan is printed with the answer). A point whose
design fails (no stroke meets the limits, or the scene's criteria fail: a premature release, a lag) counts as
infinitely bad, so the search closes in on the best point that passes; the answer names what stops it going
further (the criterion that fails next to it, or the range's bound). A spring's stiffness freed at the same time
(``[design.free.k2]``) stays a variable of each solve.

The design returned is the verified solve at the value found: its problem carries the value's ``--set`` texts
(design.json records them, so ``verify``, ``report`` and ``compare`` see the same geometry), its free parameters
list the number with its bounds, its notes say how it was found.
"""

from __future__ import annotations

import math
from dataclasses import replace

from ..errors import ProblemError, SolverError
from ..io.fields import number_in

#: The search stops when its bracket is this share of the range.
TOLERANCE = 0.01
#: Points of the first scan of the range (both bounds among them); the golden section then narrows the bracket
#: around the best of them.
SCAN_POINTS = 6
_GOLDEN = (math.sqrt(5.0) - 1.0) / 2.0


def solve_outer(problem, settings, solve, progress=None):
    """The verified design at the best value of ``settings.outer[0]``; ``solve(problem, settings, warm)`` is the
    verified solve of one point (:func:`~.verified.solve_verified` with the caller's options, ``settings`` without
    the outer entry, ``warm`` a design to start from or None). ``progress``: a callable wrapping an iterable (tqdm),
    advanced once per point.

    Each point is the solve a user gets for that value (``strokeopt solve`` with its ``--set`` texts, from the same
    start), so the answer can be solved again from design.json. That solve is a local optimum of a non-convex NLP
    (the stroke's shape, the crossing of the stop): from another start its value can differ by a fifth or more (the
    impact velocity at a 3 mm shift: 0.706 m/s from the classic law, 0.553 m/s warm-started from a neighbouring
    design), and nearby values can fall into different optima. So the range is first scanned on
    :data:`SCAN_POINTS` points (printed with the answer), then the bracket around the best narrowed by golden
    section."""
    outer = settings.outer[0]
    inner = replace(settings, outer=())
    where = f"design.free.{outer.name}"
    nominal = {f: number_in(problem.data, f, problem.file, where) for f, _ in outer.moves}
    for bound in (outer.lower, outer.upper):  # both ends must be problems the file accepts
        sets = outer.overrides(bound, nominal)
        try:
            problem.with_overrides(sets)
        except ProblemError as exc:
            raise ProblemError(str(problem.file), f"{where}.{'range' if outer.absolute else 'range_mm'}",
                               f"at {bound:g} ({_said(sets)}) the problem refuses {exc.field}: {exc.message}"
                               ) from None
    points: dict[float, tuple] = {}
    bar = iter(progress(iter(int, 1))) if progress is not None else None  # an endless iterator advanced per point

    def at(d: float):
        if d not in points:
            try:
                verified = solve(problem.with_overrides(outer.overrides(d, nominal)), inner, None)
                points[d] = (verified.design.objective_value if verified.ok else math.inf, verified,
                             None if verified.ok else verified.verdict)
            except (SolverError, ProblemError) as exc:
                points[d] = (math.inf, None, str(exc))
            if bar is not None:
                next(bar, None)
        return points[d][0]

    lo, hi = outer.lower, outer.upper
    scan = [lo + (hi - lo) * i / (SCAN_POINTS - 1) for i in range(SCAN_POINTS)]
    for x in scan:
        at(x)
    i = min(range(len(scan)), key=lambda i: (points[scan[i]][0], i))
    a, b = scan[max(i - 1, 0)], scan[min(i + 1, len(scan) - 1)]
    c, d = b - _GOLDEN * (b - a), a + _GOLDEN * (b - a)
    while b - a > TOLERANCE * (hi - lo):
        if at(c) <= at(d):
            b, d = d, c
            c = b - _GOLDEN * (b - a)
        else:
            a, c = c, d
            d = a + _GOLDEN * (b - a)
    best = min(points, key=lambda x: (points[x][0], x))
    value, verified, why = points[best]
    if verified is None or not math.isfinite(value):
        failed = "; ".join(f"{x:g}: {points[x][2]}" for x in sorted(points))
        raise SolverError(f"no value of {where} in [{lo:g}, {hi:g}] gives a design that passes "
                          f"({len(points)} tried): {failed[:600]}")
    return _with_outer(verified, outer, best, points, scan, outer.overrides(best, nominal))


def _said(sets: list) -> str:
    """``--set`` texts as words: ``model.contacts.c32.gap_mm = 2.421, ...``."""
    return ", ".join(f"{t.split('=')[0]} = {float(t.split('=')[1]):.4g}" for t in sets)


def _binds(outer, best: float, points: dict, unit: str) -> str:
    """What stops the search going further from ``best``: the range's bound, else the points tried beside it (their
    values, or why they fail: a criterion of the scene, no stroke within the limits)."""
    if best in (outer.lower, outer.upper):
        return f"the range's {'lower' if best == outer.lower else 'upper'} bound"
    xs = sorted(points)
    i = xs.index(best)
    beside = [xs[j] for j in (i - 1, i + 1) if 0 <= j < len(xs)]

    def said(x):
        value, _, why = points[x]
        return f"{x:.4g}: {value:.4g} {unit}" if math.isfinite(value) else f"{x:.4g}: fails ({why})"

    return "the points tried beside it are worse: " + "; ".join(said(x) for x in beside)


def _with_outer(verified, outer, best: float, points: dict, scan: list, sets: list):
    design = verified.design
    what = outer.describe()
    unit = design.objective_unit
    scanned = ", ".join(f"{x:g}: " + (f"{points[x][0]:.4g}" if math.isfinite(points[x][0]) else "fails") for x in scan)
    row = {"parameter": f"design.free.{outer.name} ({what})", "value": best, "lower": outer.lower,
           "upper": outer.upper, "at_bound": "lower" if best == outer.lower else "upper" if best == outer.upper else None}
    note = (f"design.free.{outer.name} = {best:.4g} chosen in [{outer.lower:g}, {outer.upper:g}] ({_said(sets)}) by "
            f"a scan and golden-section search over {len(points)} verified points (scan, {design.objective} {unit}: "
            f"{scanned}); what binds it: {_binds(outer, best, points, unit)}")
    design = replace(design, free_parameters=[*design.free_parameters, row], notes=[*design.notes, note])
    return replace(verified, design=design)
