"""Studies over many solves: the stitch-rate sweep (:func:`sweep_design`, :func:`fastest_feasible`),
the accuracy/time study of the mesh (:func:`mesh_study`) and what quietness costs (:func:`impact_study`).

The sweep and the impact study solve through the one verified pipeline (:func:`.verified.solve_verified`), each
rate or limit a task of the study runner (:mod:`.runner`: in this process, on local worker processes or on a Dask
cluster); the mesh study times the bare collocation (the file's motor and pulley), in this process.
Figures: :mod:`strokeopt.report.design`.
"""

from __future__ import annotations

import time
from dataclasses import replace

from ..design.transcription.nlp import clear_cache
from ..design.transcription.settings import DesignSettings
from ..design.solve import solve_design
from ..errors import ProblemError, SolverError
from .runner import StudyRunner, TaskOutcome, run_study
from .verified import solve_checked, solve_verified, verify_design


def sweep_design(problem, spms, *, objective: str | None = None, settings: DesignSettings | None = None,
                 progress=None, runner: StudyRunner | None = None) -> list[dict]:
    """The verified design (:func:`~.verified.solve_verified`) at each stitch rate in ``spms`` (ascending),
    each solve warm-started from the previous.

    Returns one row per rate: ``spm``, ``feasible`` (solved, within every limit and its verification
    passed), the objective, motor, pulley, peak and RMS torque, the handover error of the full servo
    simulation, and for an infeasible rate the reason. ``progress``: a callable wrapping the iterable (tqdm).

    ``runner`` (:class:`~.runner.StudyRunner`; None: in this process) says where the rates are solved. With
    one worker the rates are one chain, each warm-started from the previous: today's answer. With N workers
    the rates are split into N contiguous runs solved side by side; each run's first rate starts cold (as
    ``strokeopt solve --spm RATE`` solves it) and the others are warm-started within their run. Where the
    optimum is unique the table is the same to the solver's tolerance (the known optima: 1e-6 relative,
    tests/studies/test_runner.py); where the start decides which local optimum IPOPT finds, a run's first rate may
    differ from the chain's: the reference problem on the thesis drive at 520 spm, warm-started from 500 spm,
    0.94399 N m peak torque, solved cold 0.94506 N m (0.11 %; `strokeopt bench --only study_sweep_workers`
    prints the largest difference of its sweep). A rate whose task fails (an error, not an infeasible rate) is
    a row with ``task_failed`` and the error; the other rows are kept.
    """
    outcomes = run_study(_sweep_step, [float(s) for s in spms], (problem, objective, settings),
                         runner=runner, progress=progress, finish=_sweep_verify)
    return [o.row if o.ok else _failed_row({"spm": o.item}, o) for o in outcomes]


def _sweep_step(shared, spm: float, warm):
    """The solve of one rate of :func:`sweep_design` (the design the next rate starts from); its verification is
    :func:`_sweep_verify`, a task of its own. The payload: the infeasible rate's row, or the design and its full
    servo simulation."""
    problem, objective, settings = shared
    t0 = time.perf_counter()
    try:
        design, accuracy = solve_checked(problem, objective=objective, spm=spm, settings=settings, warm_start=warm)
    except SolverError as exc:
        first, *rest = exc.reason.splitlines()  # the first line says the worst limit; details follow
        return {"spm": float(spm), "feasible": False, "reason": first,
                **({"details": [r.strip() for r in rest]} if rest else {}),
                "solve_time_s": time.perf_counter() - t0}, warm
    return (design, accuracy, time.perf_counter() - t0), design


def _sweep_verify(shared, spm: float, payload) -> dict:
    """The row of one rate: its design verified in its contact scenes (:func:`~.verified.verify_design`)."""
    if isinstance(payload, dict):  # no design at this rate
        return payload
    design, accuracy, seconds = payload
    t0 = time.perf_counter()
    verified = verify_design(design, accuracy=accuracy)
    seconds += time.perf_counter() - t0
    d = verified.design
    if not verified.ok:
        return {"spm": float(spm), "feasible": False, "reason": verified.verdict, "solve_time_s": seconds}
    return {"spm": float(spm), "feasible": True, "objective_value": d.objective_value, "objective_unit": d.objective_unit,
            "motor": d.motor, "pulley_teeth": d.pulley_teeth, "peak_torque_N_m": d.check_value("peak_torque"),
            "rms_torque_N_m": d.check_value("rms_torque"),
            "handover_error_mm": None if verified.accuracy is None else verified.accuracy.handover_error * 1e3,
            "a_max_m_s2": max(m.a_max for m in d.moves), "solve_time_s": seconds}


def _failed_row(row: dict, outcome: TaskOutcome) -> dict:
    """The row of an item whose task failed or was lost: its inputs, ``feasible`` False and the error."""
    return {**row, "feasible": False, "reason": f"task failed: {outcome.error}" if not outcome.lost
            else outcome.error, "task_failed": True}


def failed_tasks(rows: list[dict]) -> list[dict]:
    """The rows of a study whose task failed or was lost (not an infeasible design: an error to report)."""
    return [r for r in rows if r.get("task_failed")]


def fastest_feasible(rows: list[dict]) -> float | None:
    """The highest stitch rate of a sweep below which every rate was feasible (None: the first failed)."""
    best = None
    for r in sorted(rows, key=lambda r: r["spm"]):
        if not r["feasible"]:
            break
        best = r["spm"]
    return best


#: Meshes of the accuracy/time study: (intervals, degree); the last is the reference.
STUDY_MESHES = ((10, 2), (20, 2), (40, 2), (10, 3), (20, 3), (40, 3), (80, 3), (160, 4))


def mesh_study(problem, *, objective: str | None = None, spm: float | None = None,
               settings: DesignSettings | None = None, meshes=STUDY_MESHES, progress=None) -> list[dict]:
    """What accuracy costs in time: the same design on each mesh against the last (finest) one.

    The parts are held fixed (the file's motor and pulley) so the study sees the discretisation
    only. Rows: intervals, degree, variables, objective, its error against the reference [%],
    the largest relative violation of a bound between collocation nodes (fine grid), solve time.
    """
    settings = replace(settings or getattr(problem, "design", None) or DesignSettings(),
                       motor_choice="fixed", pulley="fixed" if getattr(problem, "drive", None) else "fixed",
                       refinements=0)
    rows = []
    it = progress(list(meshes)) if progress is not None else list(meshes)
    for n, d in it:
        clear_cache()  # every mesh is timed with its build
        t0 = time.perf_counter()
        design = solve_design(problem, objective=objective, spm=spm,
                              settings=replace(settings, mesh_intervals=n, collocation_degree=d))
        elapsed = time.perf_counter() - t0
        nodes = n * (d + 1) + 2 * (n + 1)
        rows.append({"intervals": n, "degree": d, "variables": nodes * len(design.moves),
                     "objective_value": design.objective_value,
                     "violation_between_nodes": float(design.fine_grid["worst_relative_violation"]),
                     "time_s": elapsed})
    ref = rows[-1]["objective_value"]
    for r in rows:
        r["objective_error_pct"] = 100.0 * abs(r["objective_value"] / ref - 1.0) if ref else None
    rows[-1]["reference"] = True
    return rows


#: The most impact-velocity limits one study solves (each a solve and a simulation, a few seconds).
IMPACT_POINTS_MAX = 20


def impact_study(problem, velocities, *, objective: str | None = None, spm: float | None = None,
                 settings: DesignSettings | None = None, progress=None, runner: StudyRunner | None = None) -> list[dict]:
    """What quietness costs: the design solved under each impact-velocity limit of ``velocities`` [m/s]
    (``[design.contact] impact_velocity_max_m_s`` replaced, the rest of ``[design.contact]`` and
    ``[design.free]`` as in the file), from the loosest to the tightest, each warm-started from the previous
    and verified by re-simulation (contact/verify.py). One row per limit: the objective, peak torque, the free
    parameters found, the simulated impact velocity and lag, the verdict; an infeasible limit with its reason.

    ``runner``: where the limits are solved, each a task (see :func:`sweep_design`: with N workers the limits
    are N contiguous runs, each warm-started within its run; one worker is the single chain). A limit whose task
    fails is a row with ``task_failed``; the others are kept.
    """
    settings = settings or getattr(problem, "design", None) or DesignSettings()
    if settings.contact is None:
        raise ProblemError(str(problem.file), "design.contact", "the impact study needs a [design.contact] section "
                                                                "(the contact model the impact velocity is held in)")
    values = sorted((float(v) for v in velocities), reverse=True)
    outcomes = run_study(_impact_step, values, (problem, objective, spm, settings), runner=runner,
                         progress=progress)
    rows = [o.row if o.ok else _failed_row({"impact_velocity_max_m_s": o.item}, o) for o in outcomes]
    return sorted(rows, key=lambda r: r["impact_velocity_max_m_s"])


def _impact_step(shared, vmax: float, warm):
    """One limit of :func:`impact_study`: its row and the design the next (tighter) limit starts from."""
    problem, objective, spm, settings = shared
    t0 = time.perf_counter()
    limited = replace(settings, contact=replace(settings.contact, impact_velocity_max=vmax))
    row = {"impact_velocity_max_m_s": vmax}
    try:
        verified = _solved_afresh_if_short(problem, objective, spm, limited, warm)
    except SolverError as exc:
        return {**row, "feasible": False, "reason": exc.reason.splitlines()[0],
                "solve_time_s": time.perf_counter() - t0}, warm
    d = verified.design
    block = verified.verification
    crit = {c["criterion"]: c for c in (block or {}).get("criteria", [])}
    row.update({"feasible": d.status != "limits exceeded", "objective_value": d.objective_value,
                "objective_unit": d.objective_unit, "peak_torque_N_m": d.check_value("peak_torque"),
                **{f"{p['parameter']}": p["value"] for p in d.free_parameters},
                "simulated_impact_velocity_m_s": crit.get("impact velocity", {}).get("value"),
                "max_lag_mm": crit.get("lag", {}).get("value"),
                "verified": None if block is None else block["status"] == "ok",
                "verdict": None if block is None else block["verdict"],
                "solve_time_s": time.perf_counter() - t0})
    if d.status == "limits exceeded":
        row["reason"] = d.notes[0]
    return row, d


def _solved_afresh_if_short(problem, objective, spm, settings, warm):
    """The verified design warm-started from ``warm``; where that fails or ends short of a limit (the previous
    limit's stroke may start IPOPT where it cannot restore feasibility), solved afresh, kept if it does better."""
    def solve(start):
        return solve_verified(problem, objective=objective, spm=spm, settings=settings, warm_start=start,
                              compare=False)

    warmed = None
    try:
        warmed = solve(warm)
    except SolverError:
        if warm is None:
            raise
    if warmed is not None and (warm is None or warmed.design.status != "limits exceeded"):
        return warmed
    try:
        fresh = solve(None)
    except SolverError:
        if warmed is None:
            raise
        return warmed
    return fresh if warmed is None or fresh.design.status != "limits exceeded" else warmed
