"""Optimal stroke design by direct collocation: :func:`solve_design`.

:func:`solve_design` states the design problem of a :class:`~strokeopt.problem.Problem`
at one stitch rate as one NLP and solves it with IPOPT (through CasADi):

* every move between its fixed dwells is a collocated trajectory (states
  position, velocity, acceleration; control jerk; see :mod:`.collocation`),
  rest to rest at the dwell boundaries, the handover position met exactly
  (the move ends at its dwell position, which is a bound, not a penalty);
* the NLP is stated in scaled units (unit stroke, unit time per move, torques
  relative to a reference torque, the radius relative to the catalogue range's geometric mean),
  so the answer does not depend on the units the user wrote;
* objectives (``[design] objective`` or ``--objective``): see :data:`.objectives.OBJECTIVES`;
* path constraints (:mod:`.limits`) are imposed at the collocation nodes and checked on a fine
  grid between them (:attr:`Design.fine_grid`); where the fine grid shows a
  violation beyond ``check_tolerance`` the mesh is doubled and the problem
  re-solved (``refinements`` times at most; :mod:`.refine`);
* the handover accuracy sums the handover error terms (:class:`~.request.ErrorTerm`) given as
  ``error_terms`` (default: ``problem.error_terms``, filled by the problem file: the servo's term
  with a ``[servo]`` section).

The flow: :mod:`.settings` -> :mod:`.request` -> :mod:`.nlp` (:mod:`.limits`, :mod:`.objectives`)
-> :mod:`.solver` -> :mod:`.refine` -> :mod:`.parts` -> here -> :mod:`.result`. The result is a
:class:`~.result.Design`: a :class:`~strokeopt.motion.stroke.StrokeFunction` (one piece per dwell
and per move; a move piece reproduces the collocation polynomials exactly), the choices (pulley,
motor), the objective, and a constraint report. A problem that cannot be solved raises
:class:`~strokeopt.errors.SolverError` naming the constraint and by how much (:mod:`.diagnose`).
"""

from __future__ import annotations

import math
import time
from dataclasses import replace

import casadi as ca

from .transcription.contact_limits import CONTACT_LIMITS
from .result import move_results
from .transcription.free import free_overrides, free_report
from .transcription.limits import DRIVE_LIMITS, ENFORCED_CHECKS, MOVE_LIMITS, enforced_checks
from .transcription.nlp import prepare
from .transcription.objectives import (OBJECTIVES, TORQUE_OBJECTIVES, free_time, needs_drive_error, needs_terms,
                                       objective_of, unknown_objective_error)
from .search.parts import choose_parts
from .search.refine import RATE_TOLERANCE, Outcome, solve_one
from .transcription.request import DriveChoice, DriveSetup, SolveRequest
from .result import Design, stroke_from_solutions
from .transcription.settings import DesignSettings
from .transcription.solver import solver_options as _solver_options
from ..drive.selection import resolve_drive
from ..drive.checks import within_limit
from ..errors import ProblemError, SolverError
from ..io.load_units import error_unit
from ..io.plain import format_value


def solve_design(problem, *, objective: str | None = None, spm: float | None = None,
                 settings: DesignSettings | None = None, warm_start=None, verbose: bool = False, progress=None,
                 handover_check=None, hold_accuracy: bool = False) -> Design:
    """Solve the design problem of ``problem`` at ``spm`` (default: the file's).

    ``objective`` overrides ``[design] objective``; ``settings`` replaces ``[design]`` (its mesh, its
    ``solver_options`` passed to ``casadi.nlpsol`` over the defaults); ``warm_start`` is a previous
    :class:`Design` (or its move solutions) to start from; ``progress`` wraps the motors of a catalogue
    search (tqdm). The handover error terms are ``problem.error_terms`` (:class:`~.request.ErrorTerm`; a
    problem with none does not check the accuracy). ``handover_check``: a callable ``design -> (error [m],
    what)`` giving the handover error of a full simulation of the design (the verified pipeline passes the
    servo model's, which this package does not import); the check table then reports that number, with the
    design's own terms beside it. ``hold_accuracy``: a ``min_time`` holds the handover accuracy from its first
    solve (as it does warm-started from a design that held it), not once a solution breaks it: where the accuracy
    binds, the rate a first solve without it finds may be one where no stroke meets it.
    Raises :class:`SolverError` naming the constraint that cannot be met.
    """
    req = _request(problem, objective, spm, settings, warm_start, verbose, hold_accuracy)
    settings, drive, terms = req.settings, req.drive, req.error_terms
    t_start = time.perf_counter()
    notes: list[str] = []
    if drive is None:
        best = solve_one(req)
        teeth, pd, motor = None, None, None
    else:
        best, teeth, notes = choose_parts(req, progress)
        # the handover accuracy terms at the chosen design (lazy: re-solved with them only if violated); at the
        # spans a max_duration found (its request's problem), which it keeps
        own = drive.own_transmission is not None
        choice = DriveChoice(best.motor, teeth, None if teeth or own else drive.radius_bounds())
        found = best.nlp.request
        best = _with_terms(replace(req, choice=choice, spm=found.spm, problem=found.problem,
                                   spans_fixed=found.spans_fixed), best)
        motor = best.motor
        pd = None if best.radius is None else 2 * best.radius
    wall = time.perf_counter() - t_start
    spm = best.nlp.request.spm  # the request's, or the highest rate of min_time
    problem = best.nlp.request.problem  # the file's, or with the spans a max_duration found (--set texts)
    free = free_report(settings, problem.model, best.free_values) if best.free_values else []
    if free:  # the design's problem: the file's with the values found (recorded as --set texts in design.json)
        problem = problem.with_overrides(free_overrides(problem.model, best.free_values))
    nlp, sols = best.nlp, best.sols
    stroke = stroke_from_solutions(problem, spm, sols, label=f"optimal ({req.objective})")
    moves = move_results(nlp.request.moves, sols)
    resolved = None if drive is None else resolve_drive(  # the parts chosen, resolved once and handed on
        problem, motor=motor, pulley_teeth=teeth, pitch_diameter=pd, include_pulley_inertia=settings.include_pulley_inertia)
    checks, active = _report_checks(best)
    design = Design(problem, spm, req.objective, best.value, nlp.graph.cost.unit, stroke, moves, nlp.request.mesh,
                    best.status, wall, best.iterations, checks=checks, active_constraints=active, fine_grid=best.fine,
                    notes=notes + _settings_notes(settings, free, nlp, drive), drive=resolved, settings=settings,
                    accuracy_enforced=bool(nlp.request.enforce_accuracy and terms), free_parameters=free)
    if handover_check is not None and (any(c["name"].startswith(HANDOVER_CHECK) for c in checks) or (
            drive is not None and any(itv.handover for itv in problem.timing.intervals))):
        # a drive without a design term (a crank's varying ratio: no linear servo term) is checked all the same
        design = replace(design, checks=verified_handover(checks, *handover_check(design), settings.check_tolerance,
                                                          limit_of(settings, problem)))
    return _judge(design, best, drive, terms)


def _request(problem, objective, spm, settings, warm_start, verbose, hold_accuracy=False) -> SolveRequest:
    """The solve request of :func:`solve_design`: its arguments checked, the drive set up."""
    settings = settings or getattr(problem, "design", None) or DesignSettings()
    objective = objective or settings.objective
    if objective not in OBJECTIVES:
        raise unknown_objective_error(objective)
    if settings.outer:  # a number the collocation does not carry: only the verified solve searches it
        raise ProblemError(str(problem.file), f"design.free.{settings.outer[0].name}",
                           "is searched around the verified solve (solve_verified, 'strokeopt solve'), one verified "
                           "solve per value; this design solve and the studies built on it take the file's value: "
                           "fix it with --set or remove the entry")
    spm = float(spm if spm is not None else problem.spm)
    if not (math.isfinite(spm) and spm > 0):
        raise ProblemError("--spm", "", f"must be positive, got {spm!r}")
    terms = tuple(getattr(problem, "error_terms", ()))
    warm = warm_start.solutions if isinstance(warm_start, Design) else warm_start
    radius0 = warm_start.radius if isinstance(warm_start, Design) else None
    options = _solver_options(settings, None, verbose)
    drive = DriveSetup(problem, settings) if getattr(problem, "drive", None) is not None else None
    if drive is None and objective in TORQUE_OBJECTIVES:
        raise needs_drive_error(problem, objective)
    if drive is not None:
        _check_fixed_accuracy(problem, settings, terms)
        if needs_terms(objective) and (settings.motor_choice != "fixed" or (
                settings.pulley != "fixed" and drive.own_transmission is None)):
            raise ProblemError(str(problem.file), "design.objective", f"{objective} compares strokes on one drive (the "
                               "servo's error term is exact for a fixed motor and pulley only): give --motor and "
                               "--pulley-teeth, or design.motor_choice = \"fixed\" and design.pulley = \"fixed\"")
    # a min_time warm-started from a design that held its accuracy holds it from the first solve: the rate a
    # solve without it finds is the one the accuracy then pulls back from (continuation, studies/tradeoff.py)
    held = free_time(objective) and (hold_accuracy or bool(getattr(warm_start, "accuracy_enforced", False)))
    return SolveRequest(problem, spm, settings, settings.mesh, objective, drive, None, options, warm, radius0,
                        error_terms=terms, enforce_accuracy=held)


def _settings_notes(settings: DesignSettings, free: list, nlp, drive) -> list[str]:
    """The notes that say what the settings did: free parameters found, the jerk bound, the torque reserve."""
    notes = []
    for row in free:
        notes.append(f"free parameter {row['parameter']} = {row['value']:.5g} (bounds {row['lower']:g} "
                     f"to {row['upper']:g})" + (f": at its {row['at_bound']} bound" if row["at_bound"] else ""))
    if settings.jerk_max_from_law and settings.jerk_law_spm:
        notes.append(f"jerk bound: the peak jerk of each move's law at {settings.jerk_law_spm:g} spm ([design] "
                     f"jerk_max_from_law = {settings.jerk_law_spm:g}), in m/s^3 at every rate (" + ", ".join(
                         f"move {mv.index} {mv.jerk_bound:.4g}" for mv in nlp.request.moves) + ")")
    if settings.torque_reserve and drive is not None:
        notes.append(f"torque reserve: the design uses at most {100 * (1 - settings.torque_reserve):.3g} % of "
                     f"the torque limit, {100 * settings.torque_reserve:.3g} % kept in reserve for the servo "
                     "loop ([design] torque_reserve_pct)")
    return notes


def _judge(design: Design, best: Outcome, drive, terms: tuple) -> Design:
    """The design with its status and notes from its checks: limits exceeded (not enforced, between nodes, or by
    the full simulation), the objective as the fine grid reads it, the rate note of a free cycle time."""
    settings, problem = design.settings, design.problem
    status, notes = design.status, list(design.notes)
    failed = [c for c in design.checks if not c["ok"] and "design_term" not in c]
    held = enforced_checks(settings, drive is not None and drive.stepper)
    relaxed = [c for c in failed if c["name"] in ENFORCED_CHECKS - held]
    failed = [c for c in failed if c not in relaxed]
    if relaxed:  # the stepper's pull-out curve not held ([design] enforce_pull_out = false): said, not hidden
        status = "limits exceeded"
        notes.insert(0, "limits exceeded, not enforced ([design] enforce_pull_out = false): " + "; ".join(
            f"{c['name']} {format_value(c['value'])} {c['unit']} > limit {format_value(c['limit'])} {c['unit']} "
            f"({-100 * c['margin']:.1f} % over)" for c in relaxed) + ": the motor cannot make this move")
    if failed:  # beyond check_tolerance after every refinement: not a design to build
        status = "limits exceeded"
        notes.insert(0, "limits exceeded between collocation nodes: " + "; ".join(
            f"{c['name']} {format_value(c['value'])} {c['unit']} > limit {format_value(c['limit'])} "
            f"({-100 * c['margin']:.2f} % over)" for c in failed) + "; use more mesh intervals ([design] "
            "mesh_intervals) or refinements")
    verified = [c for c in design.checks if not c["ok"] and "design_term" in c]
    if verified:  # the design's terms held, the full simulation of the design does not
        status = "limits exceeded"
        notes.insert(0, "; ".join(
            f"{c['name']} {format_value(c['value'])} {c['unit']} > limit {format_value(c['limit'])} "
            f"({-100 * c['margin']:.2f} % over), " + (f"although the design's term gives {format_value(c['design_term'])} "
                                                     f"{c['unit']}" if c["design_term"] is not None else
                                                     "which the design does not hold (no linear servo term)")
            for c in verified)
            + ": tighten [design] accuracy_mm or lower the stitch rate")
    value = design.objective_value
    if drive is not None:
        # the objective as the fine grid reads it (the NLP saw the nodes)
        value = _fine_objective(design, best) if design.objective in TORQUE_OBJECTIVES else best.value
    if free_time(design.objective):
        notes.insert(0, _rate_note(design, best))
    handover = any(itv.handover for itv in problem.timing.intervals)  # a machine without one has nothing to check
    checked = any(c["name"].startswith(HANDOVER_CHECK) for c in design.checks)   # by a term or the full simulation
    if drive is not None and handover and not best.handover_values() and not checked:
        why = ("the problem has no [servo] section (servo loop and belt model)" if not terms
               and getattr(problem, "servo", None) is None else "no handover error term applies (error_terms)")
        scale, unit = error_unit(problem.timing.rotary)
        notes.append(f"handover accuracy {settings.accuracy * scale:g} {unit} NOT checked: {why}")
    if best.fine["worst_relative_violation"] > settings.check_tolerance:
        notes.append(f"between collocation nodes a limit is exceeded by "
                            f"{100 * best.fine['worst_relative_violation']:.2f} % (more than check_tolerance "
                            f"{100 * settings.check_tolerance:g} %) after {settings.refinements} refinements: "
                            f"use more mesh intervals")
    return replace(design, status=status, notes=notes, objective_value=value)


def _rate_note(design: Design, best: Outcome) -> str:
    """What a free cycle time found: the highest rate, the limits that bind it, the re-solves it took."""
    binding = [name for name in design.active_constraints if not name.startswith("handover position")]
    if best.nlp.request.rate_cap:  # a bracket of rates: just above, the design's numbers at that rate fail
        binding = [n for n in binding if n != "handover accuracy"]
        bracket = best.nlp.request.settings.rate_bracket
        binding.insert(0, f"handover accuracy (bracketed within {100 * bracket:g} %: a little faster, no "
                          "design meets it with the error term taken at its own rate)")
    return (f"highest stitch rate {design.spm:.1f} spm (stitch period {60e3 / design.spm:.3f} ms), bound by: "
            f"{'; '.join(binding) or 'no limit (the time scale reached its bound)'}; the rate settled within "
            f"{100 * RATE_TOLERANCE:g} % after {len(best.rates)} solves ("
            + " -> ".join(f"{r:.1f}" for r in best.rates) + " spm)")


def _with_terms(req: SolveRequest, best: Outcome) -> Outcome:
    """Evaluate the handover error terms at ``best`` (same variables; the terms add parameters only);
    if they exceed the allowed error, re-solve the chosen parts with them enforced."""
    t0 = time.perf_counter()
    nlp = prepare(replace(req, mesh=best.nlp.request.mesh, warm=best.sols, radius0=best.radius,
                          pin_times=best.nlp.request.pin_times))
    total = nlp.graph.terms.handover.total
    if nlp.built.n_w == best.nlp.built.n_w:
        value = float(nlp.value(total, best.x).item()) if isinstance(total, (ca.MX, ca.SX)) else float(total)
        if value <= req.settings.accuracy:
            best.handover = [(n, float(nlp.value(v, best.x).item()) if isinstance(v, (ca.MX, ca.SX)) else float(v))
                             for n, v in nlp.graph.terms.handover.terms]
            best.solve_time += time.perf_counter() - t0
            return best
    out = solve_one(replace(req, mesh=best.nlp.request.mesh, warm=best.sols, radius0=best.radius))
    out.solve_time += best.solve_time
    return out


def _fine_objective(design: Design, best: Outcome) -> float:
    checks = {c["name"]: c for c in best.fine.get("drive_checks", [])}
    check = objective_of(design.objective).fine_check
    if check in checks:  # the objective's own check, read on the fine grid
        return float(checks[check]["value"])
    return best.value


def _check_fixed_accuracy(problem, settings: DesignSettings, terms: tuple) -> None:
    """Handover error terms that do not depend on the design: checked before solving."""
    fixed = [(t.name, v) for t in terms for v in [t.fixed_error(problem)] if v is not None]
    total = sum(v for _, v in fixed)
    if total > settings.accuracy:
        scale, unit = error_unit(problem.timing.rotary)
        parts = ", ".join(f"{n} {v * scale:.3f} {unit}" for n, v in fixed)
        raise SolverError(f"handover accuracy cannot be met: {parts} exceeds the allowed "
                          f"{settings.accuracy * scale:g} {unit} by {(total - settings.accuracy) * scale:.3f} {unit}")


#: The name every handover accuracy check row starts with (:class:`.limits.HandoverAccuracy`).
HANDOVER_CHECK = "handover accuracy"


def verified_handover(checks: list[dict], value: float, what: str, tol: float,
                      limit_unit: tuple[float, str] | None = None) -> list[dict]:
    """The check rows with the handover accuracy rows replaced by one row: ``value`` [m] of a full simulation
    (``what`` names it), judged by the one pass rule within ``tol``, the design's own term beside it as
    ``design_term`` (kept when the rows already hold a full simulation's). The solve and
    :func:`strokeopt.studies.verified.verify_design` both make the row here. Where the design has no term (a
    transmission of varying ratio), the row is added with ``design_term`` None, against ``limit_unit``
    (:func:`limit_of`)."""
    terms = [c for c in checks if c["name"].startswith(HANDOVER_CHECK)]
    if terms:
        limit, unit = float(terms[0]["limit"]), terms[0]["unit"]   # the rows' unit: mm, or deg for a rotary load
        term = next((c["design_term"] for c in terms if "design_term" in c), sum(float(c["value"]) for c in terms))
    else:
        (limit, unit), term = limit_unit, None
    shown = value * error_unit(unit == "deg")[0]
    row = {"name": f"{HANDOVER_CHECK} ({what})", "value": shown, "limit": limit, "unit": unit,
           "margin": 1.0 - shown / limit if limit > 0 else -math.inf,
           "ok": within_limit(shown, limit, tol), "design_term": term}
    return [c for c in checks if c not in terms] + [row]


def limit_of(settings, problem) -> tuple[float, str]:
    """The handover accuracy of ``settings`` in the unit of the check rows (mm, or deg on a rotary load)."""
    scale, unit = error_unit(problem.timing.rotary)
    return settings.accuracy * scale, unit


def _need(lim, sigma: float) -> float | None:
    """The SI value a limit group's scaled residual ``sigma`` stands for, or None where it has none."""
    try:
        value = float(lim.need(sigma))
    except (TypeError, ValueError, ZeroDivisionError):
        return None
    return value if math.isfinite(value) else None


def transmission_checks(problem) -> list[dict]:
    """The limits of the transmission's own analysis (a turning crank's linkage: its least transmission index
    against the file's ``min_transmission_index``, a lower bound) as check rows; none for another transmission."""
    own = problem.transmission.analysis(problem)
    if own is None:
        return []
    return [{"name": f"transmission index ({', '.join(t['links'])})", "value": float(t["min_index"]),
             "limit": float(t["limit"]), "unit": "-", "lower": True} for t in own["transmission"]]


def _report_checks(best: Outcome) -> tuple[list[dict], list[str]]:
    """Every check with its margin (fine grid), and the constraints active at the solution.

    One rule for every check: ok when the value exceeds the limit by less than
    ``check_tolerance`` (the violation between collocation nodes the design accepts
    before it refines the mesh; the margin shows the exact value).
    """
    nlp = best.nlp
    req = nlp.request
    tol = req.settings.check_tolerance
    checks = [row for lim in MOVE_LIMITS for row in lim.report(nlp, best)]
    checks += [dict(c) for c in best.fine.get("drive_checks", [])]
    if req.drive is not None:
        checks += [row for lim in DRIVE_LIMITS for row in lim.report(nlp, best)]
    checks += [row for lim in CONTACT_LIMITS for row in lim.report(nlp, best)]
    checks += transmission_checks(req.problem)
    for c in checks:
        value, limit = float(c["value"]), float(c["limit"])
        if c.pop("lower", False):  # a lower bound (a contact force): the margin is what it has above the limit
            scale = max(abs(limit), 1.0)
            c["margin"] = (value - limit) / scale
            c["ok"] = bool(value >= limit - tol * scale)
            continue
        c["margin"] = 1.0 - value / limit if limit > 0 else (-math.inf if value > 0 else 0.0)
        c["ok"] = within_limit(value, limit, tol)
    active = []
    # active limit groups: the value the largest scaled residual stands for within 1e-4 of the limit (a limit
    # held in squares, the RMS torque's, has a residual scaled by the torque reference squared: 5.25 N m against
    # 8 N m was a residual of -4e-5, "active"); a group without an SI reading (a lower bound): the residual itself
    for (lim, _), g in zip(nlp.built.limits, nlp.limit_values(best.x)):
        if not lim.is_enforced(req):
            continue
        value = _need(lim, g) if lim.describe is None and lim.limit > 0 else None
        if (value >= lim.limit * (1 - 1e-4)) if value is not None else g > -1e-4:
            active.append(lim.name)
    scale, unit = error_unit(req.problem.timing.rotary)
    for mv in req.moves:
        itv = req.problem.timing.intervals[mv.interval - 1]
        if itv.handover:
            active.append(f"handover position: end of move {mv.index} at {(mv.start + mv.stroke) * scale:g} {unit} (exact)")
    return checks, active
