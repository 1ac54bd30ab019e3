"""What accuracy costs in stitch rate: the highest rate for each required handover accuracy.

Beside the flow: :func:`tradeoff` (``strokeopt tradeoff``) runs the accuracy
prediction (:mod:`.accuracy`) with the problem's classic law over the stitch
rate, and the design solve with the handover accuracy constraint for the
optimal stroke; its text and figure are drawn by :mod:`strokeopt.report.servo`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np

from ..drive.checks import within_limit
from ..drive.sizing import bisect_highest
from ..errors import ProblemError, SolverError
from ..servo.accuracy import TORQUE_BASIS, handover_accuracy
from ..servo.loop import tuned_gains
from ..servo.plant import axis_from_problem
from ..servo.settings import settings_of, shortest_move
from .confirm import (RATE_BRACKET, RESERVE_STEPS, Trial, binding_of, confirm, failed_fields, least_error,
                      more_reserve, search_below)


# --------------------------------------------------------------------------- what accuracy costs in time

#: Required handover accuracies of the trade-off [mm].
DEFAULT_ACCURACIES_MM = (0.02, 0.03, 0.05, 0.1, 0.2, 0.3, 0.5, 1.0)


#: The stitch-rate resolutions a trade-off search takes [spm]: below 0.1 spm the rate is finer than a min_time
#: solve settles it (design/search/refine.py RATE_TOLERANCE); above 500 spm the search has no rate left between
#: its lowest rate and the drive's limit.
RESOLUTION_RANGE_SPM = (0.1, 500.0)

@dataclass
class TradeoffPoint:
    accuracy: float  # m
    stroke: str  # "modified_sine" (the problem's law) or "optimal"
    max_spm: float | None
    binding: str
    handover_error: float | None = None  # m, at confirmed_spm
    detail: str = ""
    #: the rate the full simulation confirmed (max_spm is it rounded down to the resolution; None: max_spm)
    confirmed_spm: float | None = None
    #: the lowest rate above it that was simulated and failed (None: none was, the binding limit is the design's
    #: or the drive's own bound), the error the simulation found there [m] and why it failed
    failed_spm: float | None = None
    failed_error: float | None = None
    failed_reason: str = ""
    #: the highest rate each start of :func:`tradeoff_optimal` confirmed, on the grid (None: none), the starts in
    #: order (empty: a single start from the problem's own rate)
    start_spm: tuple = ()

    @property
    def starts_at_best(self) -> int | None:
        """How many starts confirmed the answer's grid rate (None: a single start)."""
        if len(self.start_spm) < 2 or self.max_spm is None:
            return None
        return sum(1 for r in self.start_spm if r == self.max_spm)

    def as_dict(self) -> dict:
        confirmed = self.max_spm if self.confirmed_spm is None else self.confirmed_spm
        starts = {} if len(self.start_spm) < 2 else {
            "starts": len(self.start_spm), "starts_at_best": self.starts_at_best,
            "start_max_spm": list(self.start_spm)}
        return {**starts, "accuracy_mm": round(self.accuracy * 1e3, 9), "stroke": self.stroke, "max_spm": self.max_spm,
                "binding": self.binding, "confirmed_spm": None if confirmed is None else round(confirmed, 1),
                "handover_error_mm": None if self.handover_error is None else self.handover_error * 1e3,
                "failed_spm": None if self.failed_spm is None else round(self.failed_spm, 1),
                "failed_error_mm": None if self.failed_error is None else self.failed_error * 1e3,
                "failed_reason": self.failed_reason, "detail": self.detail}


def tradeoff_classic(problem, accuracies=None, *, resolution: float = 10.0, step: float = 50.0,
                     lowest: float = 100.0, progress=None) -> list[TradeoffPoint]:
    """Highest stitch rate with the problem's classic law for each required handover accuracy [m].

    A rate is feasible when every sizing check of the problem's motor and
    pulley passes (:mod:`strokeopt.drive.sizing`), the servo's torque command stays within its
    limit, the sampling is shorter than every move, and the handover error is
    at most the accuracy *at this rate and at every lower one* (so the curve
    is monotone by definition: the error need not rise strictly with speed).
    The binding limit is the one that fails just above the highest rate. ``progress(step, text)``:
    called with a line per simulated rate (the grid's and the bisections').
    """
    from ..drive.sizing import max_spm as drive_max_spm

    accuracies = sorted(a * 1e-3 for a in DEFAULT_ACCURACIES_MM) if accuracies is None else sorted(accuracies)
    settings = settings_of(problem)
    axis = axis_from_problem(problem, settings)
    gains = tuned_gains(axis, settings)
    spec = problem.drive
    cat = spec.catalogue()
    motor = cat.motor(spec.motor, (spec.file, "drive.motor"))
    pulley = next(p for p in cat.pulleys_of(spec.profile) if p.teeth == problem.pulley_teeth)
    kin = problem.stroke().sample(3601)
    drive_max, drive_binding = drive_max_spm(kin, problem.spm, motor, pulley, spec.load, spec.limits,
                                             spec.belt_spec(cat), resolution=1.0)
    drive_max = drive_max or 0.0
    # the sampling: the shortest move must stay longer than a control cycle
    move = shortest_move(problem.timing, problem.spm)
    sampling_max = problem.spm * move / max(settings.control_cycle, settings.position_sampling)
    cache: dict = {}

    def evaluate(spm: float):  # a line per simulated rate, the grid's and the bisections'
        spm = round(spm, 6)
        if spm not in cache:
            res = handover_accuracy(problem, spm=spm, settings=settings, axis=axis, gains=gains)
            cache[spm] = (res.handover_error, res.torque_limited)
            if progress:
                progress(problem.default_law.name, f"{spm:.1f} spm: handover error {res.handover_error * 1e3:.4f} mm"
                         + (" (torque command limited)" if res.torque_limited else ""))
        return cache[spm]

    top = min(drive_max, sampling_max * (1 - 1e-9))
    top_binding = drive_binding if drive_max <= sampling_max else "sampling"
    grid = list(np.arange(lowest, top, step)) + [top]
    errors = []
    for spm in grid:
        e, sat = evaluate(spm)
        errors.append((spm, e, sat))
    points = []
    best = None
    for acc in accuracies:
        def ok(x, acc=acc):
            e, sat = evaluate(x)
            return within_limit(e, acc) and not sat  # a classic law's table: no tolerance
        prev = None
        fail = None
        for spm, e, sat in errors:
            if within_limit(e, acc) and not sat:
                prev = spm
            else:
                fail = (spm, "torque_limit" if sat else "handover_accuracy")
                break
        failed = None  # the first failing rate above the highest
        if fail is None:
            max_spm, binding = top, top_binding
        elif prev is None:
            max_spm, binding, failed = None, fail[1], fail[0]
        else:
            max_spm, failed = bisect_highest(ok, prev, fail[0], resolution)
            e_hi, sat_hi = evaluate(failed)
            binding = "torque_limit" if sat_hi else "handover_accuracy"
        if best is not None and (max_spm is None or max_spm < best):
            max_spm = best  # the error stays within a looser accuracy wherever it met a tighter one
        if max_spm is not None:
            max_spm = math.floor(max_spm / resolution) * resolution if max_spm != top else math.floor(top)
            best = max_spm
        err = evaluate(max_spm)[0] if max_spm else None
        if failed is not None and max_spm is not None and failed <= max_spm:
            failed = None
        e_f, sat_f = evaluate(failed) if failed is not None else (None, False)
        why = "" if failed is None else ("torque limit: the torque command passes its limit" if sat_f else
                                         f"handover accuracy: the simulation gives {e_f * 1e3:.4f} mm")
        points.append(TradeoffPoint(acc, problem.default_law.name, max_spm, binding, err, failed_spm=failed,
                                    failed_error=e_f, failed_reason=why))
    return points


def tradeoff_optimal(problem, accuracies=None, *, resolution: float = 10.0, lowest: float = 100.0,
                     start: float | None = None, progress=None, runner=None, starts: int = 1) -> list[TradeoffPoint]:
    """Highest stitch rate with the optimal stroke for each accuracy [m], by ``min_time``.

    First, in this process, the drive's own highest rate (``min_time`` with no accuracy held, confirmed as below):
    it answers every accuracy its simulated error meets. Each other accuracy is a task of the study runner (``runner``, :mod:`.runner`; None: in this process, one after the
    other): one ``min_time`` design solve (the highest rate within every design limit and the design's handover
    error term, :class:`.kernel.ServoErrorTerm`) from the problem's own rate and stroke (:func:`_min_time`), then
    its full simulation (:func:`handover_accuracy`: table sampling, load forces, the handover window, the torque
    command). A rate counts only when the full simulation meets the accuracy without the torque command passing
    its limit: the design's own term is the simulation's error at instants of the handover window, but not its
    torque command. When the simulation rejects the ``min_time`` design, the rate is searched below it with the
    most accurate stroke at fixed rates, each confirmed the same way (a step down by the simulation's excess; a
    safeguarded secant to the resolution). The tasks do not depend on each other, so an accuracy's answer does not
    depend on which others are asked. Where an accuracy's own starts confirm no rate, the next looser rung of a
    fixed ladder (:data:`DEFAULT_ACCURACIES_MM`, whether asked or not: solved the same way, here, where not asked)
    answers it with its confirmed design where that meets it, or, where ``min_time`` found no design, gives the
    start of one more solve here: the answer is the same whichever accuracies are asked (0.02 mm alone is tried
    from the 0.03 mm rung's design, as in the default list). An accuracy still without a rate gets the error of the
    most accurate stroke at ``spm0`` (:func:`_no_rate`: what it misses by). Last, a tighter accuracy's rate is given to every
    looser one below it (its design meets them): a tighter accuracy never gets a higher rate than a looser one.
    ``starts`` > 1: each accuracy from that many start rates (:func:`start_rates`, over one period of the belt
    mode's phase in the handover window), each a task; the highest confirmed rate is kept and the point records
    what each start confirmed (:attr:`TradeoffPoint.start_spm`). The motor and pulley are the problem's
    (``drive.motor``, ``pulley_teeth``), as for the classic law, so the two curves compare strokes on one drive. ``progress(step, text)`` is called once per step (a line per solve or simulation; on workers
    the lines are printed on the workers' standard error).
    """
    from .runner import run_study

    accuracies = sorted(a * 1e-3 for a in DEFAULT_ACCURACIES_MM) if accuracies is None else sorted(accuracies)
    spm0 = problem.spm if start is None else start
    here = runner is None or runner.in_process
    say = (progress or _quiet) if here else (print_step if progress is not None else _quiet)
    loosest_first = sorted(accuracies, reverse=True)
    # the drive's own highest rate (no accuracy held), in this process: it answers every accuracy its error meets
    own = {}
    top_point, top, _ = _one_accuracy(problem, math.inf, resolution, lowest, spm0, progress or _quiet)
    for acc in loosest_first:
        if top is not None and within_limit(top.result.handover_error, acc):
            own[acc] = (replace(top_point, accuracy=acc), top, False)
    rates = start_rates(problem, spm0, starts)

    least: dict = {}  # accuracy -> the most accurate stroke at the first start rate where that start found no rate

    def own_starts(accs) -> dict:  # each accuracy from each start rate, every pair a task of the runner
        # the tightest first: they take the longest, so on workers the others fill in beside them
        items = [(acc, rate, k == 0) for acc in sorted(accs) for k, rate in enumerate(rates)]
        outcomes = run_study(_accuracy_step, items, (problem, resolution, lowest, say, len(rates) > 1),
                             runner=runner, chained=False) if items else []
        rows = {}
        for o in outcomes:
            acc = o.item[0]
            row = o.row if o.ok else (TradeoffPoint(acc, "optimal", None, "solver", None, o.error), None, False, None)
            rows.setdefault(acc, []).append(row[:3])
            if row[3] is not None:
                least[acc] = row[3]
        return {acc: _best_start(found) for acc, found in rows.items()}

    own.update(own_starts([acc for acc in loosest_first if acc not in own]))
    rungs = sorted(a * 1e-3 for a in DEFAULT_ACCURACIES_MM)
    answers: dict = {}

    def answer(acc):
        """``(point, confirmed trial or None)`` of one accuracy: its own starts; where they confirm no rate, the
        design of the next looser rung of the fixed ladder :data:`DEFAULT_ACCURACIES_MM` (asked or not, solved the
        same way) where it meets this accuracy, else a solve from that design where min_time found none."""
        if acc in answers:
            return answers[acc]
        if acc in own:
            point, trial, no_design = own[acc]
        elif top is not None and within_limit(top.result.handover_error, acc):
            point, trial, no_design = replace(top_point, accuracy=acc), top, False
        else:  # a rung not asked: its own starts, as an asked accuracy's
            point, trial, no_design = own_starts([acc])[acc]
        own_point = point
        rung = next((r for r in rungs if r > acc * (1 + 1e-9)), None)
        if trial is None and rung is not None:
            looser, near = answer(rung)[1], answers[rung][0]
            if looser is not None and within_limit(looser.result.handover_error, acc):
                point, trial = replace(near, accuracy=acc, detail=near.detail + f" (the design of {rung * 1e3:g} mm)"), \
                    looser
                if progress is not None:
                    progress(_tag(acc), f"{looser.spm:.1f} spm: the design of {rung * 1e3:g} mm meets it "
                                        f"({looser.result.handover_error * 1e3:.4f} mm)")
            elif no_design and looser is not None:  # from the looser rung's design (its own starts found none)
                if progress is not None:
                    progress(_tag(acc), f"its own starts found no design; again from the design of {rung * 1e3:g} mm "
                                        f"({looser.spm:.1f} spm)")
                point, trial, _ = _one_accuracy(problem, acc, resolution, lowest, spm0, progress or _quiet, looser)
                point = replace(point, detail=point.detail + f" (from the design of {rung * 1e3:g} mm: its own starts "
                                                             "found no design)")
        if point.start_spm != own_point.start_spm:  # answered from the rung: what the own starts found stays
            point = replace(point, start_spm=own_point.start_spm)
        answers[acc] = (point, trial)
        return answers[acc]

    points = {acc: answer(acc)[0] for acc in loosest_first}
    for acc, point in points.items():
        if point.max_spm is None:  # no rate: what the most accurate stroke at the problem's rate misses it by
            points[acc] = _no_rate(problem, point, spm0, resolution, progress or _quiet, least.get(acc))
    best = None  # tightest first: a tighter accuracy's design meets every looser one
    for acc in accuracies:
        if best is not None and (points[acc].max_spm is None or points[acc].max_spm < best.max_spm):
            points[acc] = replace(best, accuracy=acc, detail=best.detail + f" (the design of {best.accuracy * 1e3:g} mm)")
        elif points[acc].max_spm is not None:
            best = points[acc]
    return [points[a] for a in accuracies]


def _no_rate(problem, point: TradeoffPoint, spm0: float, resolution: float, say, least: Trial | None = None):
    """An accuracy without a confirmed rate, answered with the most accurate stroke at ``spm0`` (``least``, the
    :func:`least_error` of its first start's task where that found no rate; else solved here): the error it
    reaches there (the rejected rate's fields), or the rate where the simulation confirms it."""
    acc = point.accuracy
    t = least if least is not None else least_error(problem, _fixed_drive(problem, acc), spm0, acc)
    if t.ok:  # min_time found no design, but the most accurate stroke at the problem's rate meets it
        say(_tag(acc), f"{spm0:g} spm: the most accurate stroke meets it ({t.result.handover_error * 1e3:.4f} mm)")
        return replace(point, max_spm=math.floor(spm0 / resolution + 1e-9) * resolution, confirmed_spm=spm0,
                       handover_error=t.result.handover_error,
                       detail=f"{point.detail}; the most accurate stroke at {spm0:g} spm meets it")
    error = t.result.handover_error if t.result is not None else (acc * (1 + t.excess) if math.isfinite(t.excess) else None)
    if error is None:
        say(_tag(acc), f"{spm0:g} spm: no most accurate stroke ({t.reason.splitlines()[0]})")
        return point
    say(_tag(acc), f"{spm0:g} spm: the most accurate stroke reaches {error * 1e3:.4f} mm")
    return replace(point, binding=binding_of(t.reason), failed_spm=spm0, failed_error=error,
                   failed_reason=f"the most accurate stroke at {spm0:g} spm reaches {error * 1e3:.4f} mm",
                   detail=f"no rate: the most accurate stroke at {spm0:g} spm reaches {error * 1e3:.4f} mm ({point.detail})")


def _fixed_drive(problem, acc: float):
    """The design settings of one accuracy of the optimal stroke: the problem's motor and pulley (the classic law's
    drive), the accuracy held, ``min_time``'s rate bracket."""
    from ..design.transcription.settings import DesignSettings

    base = problem.design or DesignSettings()
    return replace(base, accuracy=acc, motor_choice="fixed", pulley="fixed", rate_bracket=RATE_BRACKET)


def _design_bound(design) -> str:
    """The limit a ``min_time`` design names first as what bounds its rate."""
    return binding_of(design.notes[0].split("bound by:", 1)[-1])


def _quiet(step, text) -> None:
    return None


def print_step(step, text) -> None:
    """A step's line on standard error (what ``strokeopt tradeoff`` prints; on a worker, the worker's)."""
    import sys

    print(f"tradeoff {step}: {text}", file=sys.stderr, flush=True)


def _tag(acc: float) -> str:
    return f"optimal {acc * 1e3:g} mm" if math.isfinite(acc) else "optimal, no accuracy held"


def _accuracy_step(shared, item, warm):
    """One accuracy of :func:`tradeoff_optimal` from one start rate (a task; ``item`` = (accuracy, rate, the first
    start)): its point, its confirmed trial, whether min_time found no design, and where the first start confirms no
    rate, the most accurate stroke at its rate (:func:`least_error`; the answer's words should nothing else give
    one: solved here, beside the other tasks, rather than after them all)."""
    problem, resolution, lowest, say, several = shared
    acc, spm0, first = item
    tag = _tag(acc) + (f", start {spm0:.1f} spm" if several else "")
    point, trial, no_design = _one_accuracy(problem, acc, resolution, lowest, spm0, say, tag=tag)
    least = least_error(problem, _fixed_drive(problem, acc), spm0, acc) if trial is None and first else None
    return (point, trial, no_design, least), None


#: The most starts per accuracy (``strokeopt tradeoff --starts``).
STARTS_MAX = 12


def start_rates(problem, spm0: float, count: int) -> list[float]:
    """The start rates of :func:`tradeoff_optimal`: ``spm0`` and ``count - 1`` more spread over one period of the
    belt mode's phase in the handover window. The handover move lasts ``T`` at ``spm0`` (a move's time goes with
    one over the rate) and the belt mode rings at ``f`` (the servo's plant,
    :attr:`~strokeopt.servo.plant.DriveAxis.resonance_hz`): at ``spm0 / (1 - k / (count f T))`` the move is ``k /
    count`` of the mode's period shorter (of half the move where the period is longer). Deterministic: the same
    starts on every run."""
    if count <= 1:
        return [spm0]
    timing = problem.timing
    move = timing.handover_move or timing.moves[0]
    duration = float(timing.schedule(spm0).duration[move.index - 1])
    settings = settings_of(problem)
    f = axis_from_problem(problem, settings).resonance_hz
    period = min(1.0 / f, 0.5 * duration)  # a mode slower than the move: starts over half the move's time
    return [spm0 / (1.0 - k / count * period / duration) for k in range(count)]


def _best_start(rows: list) -> tuple:
    """One accuracy's answer from its starts' ``(point, trial, no_design)``: the highest confirmed rate (the first
    start of equals), the rate each start confirmed on the point (:attr:`TradeoffPoint.start_spm`); no design only
    where no start found one."""
    confirmed = [r for r in rows if r[1] is not None]
    point, trial, _ = max(confirmed, key=lambda r: r[1].spm) if confirmed else rows[0]
    if len(rows) > 1:
        point = replace(point, start_spm=tuple(r[0].max_spm for r in rows))
    return point, trial, all(r[2] for r in rows)


def _one_accuracy(problem, acc: float, resolution: float, lowest: float, spm0: float, say, looser=None, tag=None):
    """The highest confirmed rate at one accuracy: ``(point, confirmed trial or None, min_time found no design)``;
    ``looser``: a looser accuracy's confirmed trial, the last start of :func:`_min_time`; ``tag``: of the lines."""
    from ..design.solve import solve_design

    settings = _fixed_drive(problem, acc)  # the same drive as the classic law: the problem's motor and pulley
    reserve = settings.torque_reserve
    tag = tag or _tag(acc)
    try:
        d = _min_time(problem, spm0, settings, looser, lambda text: say(tag, text))
    except SolverError as exc:
        say(tag, f"min_time: no design ({exc.reason.splitlines()[0]})")
        return TradeoffPoint(acc, "optimal", None, binding_of(exc.reason), None, exc.reason), None, True
    warm = d
    binding = _design_bound(d)
    say(tag, f"min_time {d.spm:.1f} spm ({binding}); full simulation")
    top, hi = d.spm, confirm(problem, d, d.spm, acc)
    if not hi.ok:
        say(tag, f"{top:.1f} spm: {hi.reason}")
    for _ in range(RESERVE_STEPS):
        res = hi.result
        if hi.ok or not res.torque_limited:
            break
        # the loop's torque command passes the limit the rigid load meets: keep the excess in reserve
        reserve = more_reserve(reserve, res)
        settings = replace(settings, torque_reserve=reserve)
        try:
            d = solve_design(problem, objective="min_time", spm=d.spm, settings=settings, warm_start=d)
        except SolverError as exc:
            say(tag, f"min_time with {100 * reserve:.1f} % torque reserve: no design ({exc.reason.splitlines()[0]})")
            break
        # the reserve is the servo's torque command's; where the design's own bound is the accuracy, that binds too
        warm = d
        binding = "handover_accuracy" if _design_bound(d) == "handover_accuracy" else "torque_limit"
        say(tag, f"min_time {d.spm:.1f} spm with {100 * reserve:.1f} % of the torque limit in reserve for the "
                 "loop; full simulation")
        top, hi = d.spm, confirm(problem, d, d.spm, acc)
        if not hi.ok:
            say(tag, f"{top:.1f} spm: {hi.reason}")
    if hi.ok:
        found, lo = top, hi
    else:
        lo, hi = search_below(problem, hi, settings, acc, resolution, lowest, warm, lambda text: say(tag, text))
        found = None if lo is None else lo.spm
        binding = binding_of(hi.reason)  # what fails just above the highest confirmed rate
    if found is None:
        return (TradeoffPoint(acc, "optimal", None, binding, None, f"at {hi.spm:.1f} spm: {hi.reason}", **failed_fields(hi)),
                None, False)
    max_spm = math.floor(found / resolution + 1e-9) * resolution
    error = lo.result.handover_error
    detail = (f"min_time {d.spm:.1f} spm; at {found:.1f} spm the full simulation gives {error * 1e3:.4f} mm"
              + ("" if hi.ok else f"; above, at {hi.spm:.1f} spm: {hi.reason}"))
    say(tag, f"the highest confirmed rate: {found:.1f} spm ({error * 1e3:.4f} mm)")
    return (TradeoffPoint(acc, "optimal", max_spm, binding, error, detail, confirmed_spm=found,
                          **({} if hi.ok else failed_fields(hi))), lo, False)


def _min_time(problem, spm0: float, settings, looser: Trial | None, say):
    """The ``min_time`` design of one accuracy, from the first of two starts that gives one: the problem's own
    rate and stroke (the accuracy held once a solution breaks it), then the same with the accuracy held from the
    first solve (where the rate a first solve without it finds is one where no stroke meets it); neither depends on
    which other accuracies are asked. With ``looser`` (where both found none): from the design a looser accuracy
    confirmed alone (it holds a looser accuracy at a higher rate; the rate comes down from it)."""
    from ..design.solve import solve_design

    starts = [(f"from {spm0:g} spm", lambda: dict(spm=spm0)),
              (f"from {spm0:g} spm with the accuracy held from the first solve",
               lambda: dict(spm=spm0, hold_accuracy=True))]
    if looser is not None:  # the first two found no design (tradeoff_optimal): this start alone
        starts = [(f"from the design confirmed at {looser.spm:.1f} spm for a looser accuracy",
                   lambda: dict(spm=looser.spm, warm_start=looser.design, hold_accuracy=True))]
    for k, (where, start) in enumerate(starts):
        try:
            return solve_design(problem, objective="min_time", settings=settings, **start())
        except SolverError as exc:
            if k == len(starts) - 1:
                raise
            say(f"min_time {where}: no design ({exc.reason.splitlines()[0]}); again {starts[k + 1][0]}")


def tradeoff(problem, accuracies=None, *, strokes: str = "both", resolution: float = 10.0, step: float = 50.0,
             progress=None, runner=None, starts: int = 1) -> dict:
    """The report of ``strokeopt tradeoff``: for each required handover accuracy the highest
    stitch rate with the problem's classic law and with the optimal stroke, and the binding limit.
    ``progress(step, text)``: called with a line at every step (a simulated rate, a design solve).
    ``runner``: where the optimal stroke's accuracies are solved (:func:`tradeoff_optimal`)."""
    from ..design.transcription.settings import DesignSettings

    if strokes not in ("both", "classic", "optimal"):
        raise ProblemError("--strokes", "", f"{strokes!r} is not one of both, classic, optimal")
    points = []
    if strokes in ("both", "classic"):
        points += tradeoff_classic(problem, accuracies, resolution=resolution, step=max(step, resolution),
                                   progress=progress)
    if strokes in ("both", "optimal"):
        points += tradeoff_optimal(problem, accuracies, resolution=resolution, progress=progress, runner=runner,
                                   starts=starts)
    return {"problem": problem.name, "motor": problem.drive.motor, "pulley_teeth": problem.pulley_teeth,
            "law": problem.default_law.label, "resolution_spm": resolution, "torque_basis": TORQUE_BASIS,
            "check_tolerance_pct": 100 * (problem.design or DesignSettings()).check_tolerance, "starts": starts,
            **({"start_rates_spm": [round(r, 1) for r in start_rates(problem, problem.spm, starts)]}
               if strokes != "classic" and starts > 1 else {}),
            "points": [p.as_dict() for p in points]}
