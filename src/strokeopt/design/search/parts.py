"""Choosing the parts: the motor (fixed, enumerated, or Bonmin) and the pulley (fixed, or the
continuous radius then the nearest tooth counts).

Sixth step of the design's flow (:mod:`.refine` -> parts -> :mod:`.solve`): every candidate is a
:func:`~.refine.solve_one` of a variant of one :class:`~.request.SolveRequest`, without the
handover error terms (they are checked once at the chosen design).
"""

from __future__ import annotations

import math
from dataclasses import replace

from .bounds import best_bound_first, cannot_win, near_limit, prune
from .diagnose import feasible_start
from .refine import Outcome, solve_one
from ..transcription.objectives import needs_terms
from ..transcription.request import DriveChoice, SolveRequest
from ...errors import LimitError, ProblemError, SolverError


def choose_parts(req: SolveRequest, progress=None):
    """Motor (fixed, enumerated, or Bonmin) and pulley (fixed, or continuous radius then nearest tooth counts).

    Enumeration prunes twice. Before any NLP, a motor whose rigid torque bound exceeds its limit is dropped
    (:func:`.bounds.prune`). Then the motors are tried best bound first where the bound bounds the objective
    (:func:`.bounds.best_bound_first`), and the search ends when the best design found is at least as good as
    every bound left; a motor's continuous-radius optimum is a lower bound of its tooth-count optima, so a
    motor whose continuous optimum is no better than the best design found is not solved for tooth counts.
    """
    spm, settings = req.spm, req.settings
    if not (needs_terms(req.objective) or req.enforce_accuracy):
        req = replace(req, error_terms=())  # the handover accuracy is checked at the chosen design (solve.py)
    notes = []
    motors = _candidates(req, notes)
    failures = []
    candidates = len(motors)
    if settings.prune_catalogue and len(motors) > 1:  # motors a rigid bound rules out: no NLP for them
        motors, failures = prune(req, motors)
        if failures:
            notes.append(f"{len(failures)} of {candidates} motors ruled out before solving (their "
                         "least peak torque with any pulley exceeds their limit): "
                         + ", ".join(m.name for m, _ in failures))
    ordered = best_bound_first(req, motors) if settings.prune_catalogue else [(m, None) for m in motors]
    results, unsolved, total_time = _search(req, ordered, failures, progress)
    if unsolved:
        notes.append(f"{len(unsolved)} motors not solved: their least peak torque with any pulley is above the "
                     f"best design's {min(r[0].value for r in results):.4g} N m: " + ", ".join(unsolved))
    if not results:
        raise _no_motor(failures, spm)
    best, teeth = _best(results)
    if candidates > 1:
        notes.append(f"motor chosen among {candidates} by enumeration ({len(failures)} infeasible): "
                     f"lowest {req.objective}")
    best.solve_time = total_time
    return best, teeth, notes


def _search(req: SolveRequest, ordered: list, failures: list, progress):
    """Every motor of ``ordered`` ((motor, objective bound)) with its best pulley, in that order, each phase-1
    solve warm-started from the previous motor's: ``(results, names not solved, solve time)``; ``results`` are
    ``(Outcome, teeth)``, a failed motor is appended to ``failures``."""
    problem, settings, drive = req.problem, req.settings, req.drive
    warm, radius0 = req.warm, req.radius0
    results, unsolved, total_time = [], [], 0.0
    steps = progress(ordered) if progress is not None and len(ordered) > 1 else ordered
    for motor, bound in steps:
        best = min((r[0].value for r in results), default=None)
        if cannot_win(bound, best, settings.check_tolerance):
            unsolved.append(motor.name)
            continue
        try:
            if settings.pulley == "fixed":
                one = replace(req, choice=DriveChoice(motor, problem.pulley_teeth), warm=warm, radius0=None)
            else:
                # with tooth counts to follow ("optimise"), the belt of the continuous radius is rated as the
                # largest pulley's: a relaxation, so a motor is not dropped for a rating its pulleys beat
                belt_teeth = drive.teeth_range[1] if settings.pulley == "optimise" else None
                one = replace(req, choice=DriveChoice(motor, None, drive.radius_bounds(), belt_teeth=belt_teeth),
                              warm=warm, radius0=radius0)
            if settings.prune_catalogue and near_limit(req, motor):  # a likely failure: its limits checked first
                one = replace(one, warm=feasible_start(one))
            out = solve_one(one)
            if settings.pulley != "fixed":
                radius0 = out.radius
            warm = out.sols
            total_time += out.solve_time
            if settings.pulley != "optimise":
                results.append((out, problem.pulley_teeth if settings.pulley == "fixed" else None))
            elif best is None or out.value < best:  # else its tooth counts cannot win either
                teeth_out, teeth = nearest_teeth(req, motor, out)
                results.append((teeth_out, teeth))
                total_time += teeth_out.solve_time
        except SolverError as exc:
            failures.append((motor, exc))
    return results, unsolved, total_time


#: Designs whose objectives differ by less than this (relative) tie: the solver's tolerance, not a better design.
TIE = 1e-6


def _best(results: list):
    """The best ``(Outcome, teeth)``; among designs that tie (:data:`TIE`), the one with the smallest motor (the
    least rated torque): where the rate or the objective is set by the stroke and the belt, not the motor (min_time
    at the jerk bound and the belt's limit), any motor that reaches it would do and the smallest is the one to buy."""
    lowest = min(r[0].value for r in results)
    tied = [r for r in results if r[0].value <= lowest + TIE * abs(lowest)]
    return min(tied, key=lambda r: (getattr(r[0].motor, "rated_torque", None) or 0.0, r[0].value))


def _no_motor(failures: list, spm) -> SolverError:
    """The error of a search that found no design: the one motor's, or the closest first, one line a motor."""
    if len(failures) == 1:
        return failures[0][1]
    failures.sort(key=lambda f: f[1].excess if isinstance(f[1], LimitError) else math.inf)
    m0, e0 = failures[0]
    lines = [f"no motor of the catalogue can drive this design at {spm:g} spm; closest {m0.name}: {_short(e0)}"]
    lines += [f"  {m.name}: {_short(e)}" for m, e in failures]
    return SolverError("\n".join(lines))


def _candidates(req: SolveRequest, notes: list) -> list:
    """The motors a search tries: Bonmin's choice (a heuristic, said in ``notes``), every motor of the catalogue
    (``enumerate``), or the file's (``fixed``)."""
    problem, spm, settings, drive, options = req.problem, req.spm, req.settings, req.drive, req.options
    if settings.motor_choice == "bonmin":
        cands = tuple(drive.motors())
        bonmin_opts = {k: v for k, v in options.items() if k not in ("ipopt.max_iter",)}
        bonmin_opts["plugin"] = "bonmin"
        try:
            first = solve_one(replace(req, choice=DriveChoice(
                None, None if settings.pulley != "fixed" else problem.pulley_teeth,
                drive.radius_bounds() if settings.pulley != "fixed" else None, cands), options=bonmin_opts))
        except SolverError as exc:
            raise SolverError(f"no motor of the catalogue meets the limits at {spm:g} spm (Bonmin): {exc.reason}") from None
        notes.append(f"motor chosen by Bonmin among {len(cands)} candidates (a heuristic for this non-convex problem)")
        return [first.motor]
    if settings.motor_choice == "enumerate":
        return drive.motors()
    return [drive.fixed_motor()]

def nearest_teeth(req: SolveRequest, motor, cont: Outcome):
    """Re-solve with the tooth counts either side of the continuous optimum; keep the better."""
    drive = req.drive
    from ...drive.transmission import PROFILE_PITCH

    z = 2 * math.pi * cont.radius / PROFILE_PITCH[drive.profile]
    available = [p.teeth for p in drive.catalogue.pulleys_of(drive.profile, *drive.teeth_range)]
    if not available:
        raise ProblemError(drive.file, "design.pulley_teeth_min", f"the catalogue has no {drive.profile} pulley "
                                                                  f"with {drive.teeth_range[0]}-{drive.teeth_range[1]} teeth")
    below = [n for n in available if n <= z]
    above = [n for n in available if n >= z]
    candidates = sorted({max(below) if below else min(available), min(above) if above else max(available)})
    best, failures = None, []
    for teeth in candidates:
        try:
            out = solve_one(replace(req, choice=DriveChoice(motor, teeth), warm=cont.sols, radius0=None))
        except SolverError as exc:
            failures.append(exc)
            continue
        if best is None or out.value < best[0].value:
            best = (out, teeth)
    if best is None:
        raise failures[0]
    best[0].continuous_radius = cont.radius
    return best


def _short(err: SolverError) -> str:
    """A failed solve in one line: the worst limit and by how much (a :class:`LimitError`), else its first line."""
    return err.short if isinstance(err, LimitError) else err.reason.splitlines()[0]
