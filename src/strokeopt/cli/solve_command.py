"""``strokeopt solve``: one design (its check table, the classic laws beside it, the contact model's
verification), a sweep of rates, a mesh or impact study; ``solve_once`` is shared with ``report``."""

from __future__ import annotations

import sys
from pathlib import Path

from ..errors import ProblemError
from .common import _emit, _load, _plot_path, _write_figure, drive_used, progress_bar, spm_tag


def _objective(args, problem) -> str | None:
    """The objective a solve uses: --objective, else the file's."""
    return args.objective or (problem.design.objective if problem.design else None)


def solve_once(args, problem, progress=None, scenes=None):
    """One verified design as ``strokeopt solve`` and ``report`` make it (:func:`strokeopt.studies.verified.
    solve_verified`: the library's pipeline), with the drive it used (``solve --json``)."""
    from ..studies.verified import solve_verified

    verified = solve_verified(problem, objective=args.objective, verbose=getattr(args, "verbose", False),
                              progress=progress and (lambda it: progress(it, "motors")), scenes=scenes,
                              options=getattr(args, "sim_options", None))
    design = verified.design
    chosen = drive_used(args, problem, design.motor, design.pulley_teeth)
    if problem.design is not None and (problem.design.motor_choice != "fixed" or problem.design.pulley != "fixed"):
        pulley = (f"design.pulley = {problem.design.pulley}" if hasattr(problem.transmission, "radius") else
                  f"the problem's {problem.transmission.name}" + (f" of ratio {problem.transmission.ratio:g}"
                                                                  if hasattr(problem.transmission, "ratio") else ""))
        chosen["from"] = f"the solve's choice: design.motor_choice = {problem.design.motor_choice}, {pulley}"
    for row in design.free_parameters:   # a transmission's field the solve chose with the stroke (a crank radius)
        if row["parameter"].startswith("transmission."):
            chosen["from"] += f"; {row['parameter']} = {row['value']:.5g} chosen"
    return verified, chosen


def _cam_spec(args):
    """The cam table of ``solve --out`` as its options ask (checked before the solve)."""
    from ..files.design_file import CamTableSpec
    from ..files.ranges import check_master_counts, parse_cam_resolution

    spec = CamTableSpec(parse_cam_resolution(args.cam_table_resolution), args.master_unit, args.master_counts)
    if args.out is None and spec != CamTableSpec():
        raise ProblemError("--cam-table-resolution", "", "the cam table options shape the cam table of --out DIR: "
                                                         "give --out DIR (or omit them)")
    if args.master_unit == "counts":
        check_master_counts(args.master_counts, spec.points)
    return spec


def cmd_solve(args) -> int:
    from ..design.transcription.objectives import OBJECTIVES

    sweep = None
    if args.spm is not None and ":" in args.spm and args.design is None:  # with --design: refused by _load
        from ..files.ranges import parse_spm_range

        sweep = parse_spm_range(args.spm)
        args.spm = None
    if (args.workers is not None or args.scheduler is not None) and sweep is None and args.study != "impact":
        option = "--workers" if args.workers is not None else "--scheduler"
        raise ProblemError(option, "", "is for a sweep (--spm START:STOP:STEP) or --study impact: a single solve "
                                       "runs in this process")
    if sweep is not None or args.study == "impact":
        _runner(args)  # --workers, --scheduler checked before any work
    if args.objective is not None and args.objective not in OBJECTIVES:
        raise ProblemError("--objective", "", f"{args.objective!r} is not one of {', '.join(OBJECTIVES)}")
    problem = _load(args, fix_in_design=True)  # (an unwritable --out was refused before: cli.common.check_outputs)
    cam_spec = _cam_spec(args)
    progress = progress_bar(args, "solve", "solve")
    if args.study == "mesh":
        return _mesh_study(args, problem, progress)
    if args.study == "impact":
        return _impact_study(args, problem, progress)
    if args.impact_range is not None:
        raise ProblemError("--impact-range", "", "is for --study impact")
    if sweep is not None:
        return _sweep(args, problem, sweep, progress)
    return _solve_one(args, problem, cam_spec, progress)


def _mesh_study(args, problem, progress) -> int:
    """``solve --study mesh``: the same design on each mesh against the finest."""
    from ..studies.sweeps import mesh_study
    from ..report.design import plot_mesh_study
    from ..report.format import format_table, to_json

    rows = mesh_study(problem, objective=args.objective, progress=progress and (lambda it: progress(it, "mesh")))
    if args.json:
        _emit(to_json({"status": "ok", "problem": problem.name, "spm": problem.spm, "study": "mesh",
                       "drive": drive_used(args, problem), "rows": rows}))
    else:
        print(f"{problem.name} at {problem.cycle.rate(problem.spm)}: the same design on each mesh (file's motor and "
              f"pulley); error against the last (finest) mesh; violation between nodes: the largest excess over a "
              f"bound between the collocation nodes, relative to the bound (value / limit - 1)")
        print(format_table(rows, [("intervals", "intervals"), ("degree", "degree"), ("variables", "variables"),
                                  ("objective_value", "objective"), ("objective_error_pct", "error %"),
                                  ("violation_between_nodes", "violation between nodes (relative)"),
                                  ("time_s", "build + solve time s")]))
    _write_figure(lambda p: plot_mesh_study(rows, p),
                  _plot_path(args, "solve_mesh", spm_tag(problem.spm), _objective(args, problem)), args)
    return 0


def _sweep(args, problem, sweep: list, progress) -> int:
    """``solve --spm START:STOP:STEP``: the verified design at each rate, on the study runner."""
    from ..studies.sweeps import fastest_feasible, sweep_design
    from ..report.design import plot_design_sweep
    from ..report.format import format_table, to_json

    runner = _runner(args, len(sweep))
    rows = sweep_design(problem, sweep, objective=args.objective, runner=runner,
                        progress=progress and (lambda it: progress(it, "spm")))
    best = fastest_feasible(rows)
    at_end = best is not None and all(r["feasible"] for r in rows)  # the sweep found no limit
    if args.json:
        _emit(to_json({"status": "ok" if best is not None else "infeasible", "problem": problem.name,
                       "objective": args.objective or (problem.design.objective if problem.design else None),
                       "runner": _chained(runner), "rows": rows, "fastest_feasible_spm": best,
                       "fastest_feasible_is_sweep_end": at_end}))
    else:
        cycle = problem.cycle  # the machine's cycle: stitch, pick (io/cycle.py)
        unit = next((r["objective_unit"] for r in rows if r.get("objective_unit")), "")
        print(format_table(rows, [("spm", cycle.rate_unit), ("feasible", "feasible"),
                                  ("objective_value", f"objective {unit}".strip()), ("motor", "motor"),
                                  ("pulley_teeth", "z"), ("peak_torque_N_m", "peak N m"), ("rms_torque_N_m", "RMS N m"),
                                  ("handover_error_mm", "handover mm"), ("solve_time_s", "solve + verify s"),
                                  ("reason", "why not")],
                           title=f"{problem.name}: optimal design ({_objective(args, problem)}) over the "
                                 f"{cycle.rate_name} ({_chained(runner)}); "
                                 "feasible: within every limit, its handover error from the full servo simulation, "
                                 "and verified in its contact scenes", text=("reason",)))
        print(f"\nno feasible {cycle.rate_name} in the sweep" if best is None else
              f"\nfastest feasible {cycle.rate_name}: >= {cycle.rate(best)} (the end of the sweep; every rate was "
              "feasible)" if at_end else f"\nfastest feasible {cycle.rate_name}: {cycle.rate(best)}")
    _write_figure(lambda p: plot_design_sweep(rows, p, _objective(args, problem), problem.cycle),
                  _plot_path(args, "solve_sweep", spm_tag(sweep), _objective(args, problem)), args)
    if _report_failed_tasks(rows, "spm", "spm"):
        return 1
    if best is None:
        print(f"strokeopt: infeasible: no {problem.cycle.rate_name} of the sweep meets every limit (column 'why not')",
              file=sys.stderr)
        return 1
    return 0


def _solve_one(args, problem, cam_spec, progress) -> int:
    """One verified design: its text (or JSON), design.json and report.html with --out, its figure, the exit."""
    from ..report.design import design_text, plot_design
    from ..report.format import drive_text, to_json

    verified, chosen = solve_once(args, problem, progress)
    design, comparison = verified.design, verified.comparison
    summary = {**verified.summary(), "drive": chosen}
    if args.json:
        _emit(to_json(summary))
    else:
        print(design_text(design, comparison))
        if design.verification is not None:
            from ..report.contact import verification_text

            print(verification_text(design.verification))
        print(drive_text(chosen))
        print(f"verdict: {verified.verdict}")
    if args.out is not None:
        _write_outputs(args, verified, summary, chosen, cam_spec)
    elif getattr(design.settings, "cam_tables", ()):
        print(f"note: design.cam_tables asks for {', '.join(design.settings.cam_tables)}: they are written with "
              "--out DIR (beside design.json)", file=sys.stderr)
    # one figure: --plot FILE, else into --out DIR beside design.json, else strokeopt-out/
    fig_path = _plot_path(args, "solve", spm_tag(design.spm), design.objective)
    if fig_path is not None and args.plot is None and args.out is not None:
        fig_path = Path(args.out) / fig_path.name
    _write_figure(lambda p: plot_design(design, problem.stroke(design.spm), p), fig_path, args)
    if design.status == "limits exceeded":
        print(f"strokeopt: {design.notes[0]}", file=sys.stderr)
        return 1
    if design.status == "verification failed":
        print(f"strokeopt: {design.verification['verdict']}", file=sys.stderr)
        return 1
    if getattr(args, "strict", False) and not verified.strict_ok():
        print(f"strokeopt: --strict: {verified.verdict}", file=sys.stderr)
        return 1
    return 0


def _write_outputs(args, verified, summary: dict, chosen, cam_spec) -> None:
    """``solve --out DIR``: design.json (and the cam table) and report.html, each path named as written."""
    from ..files.design_file import write_design
    from ..report.design_report import gather, write_report

    stream = sys.stderr if args.json else sys.stdout
    for path in write_design(verified.design, args.out, spec=cam_spec, extra={
            "comparison": verified.comparison, "drive": chosen, "verdict": verified.verdict,
            "not_judged": summary["not_judged"]}):
        print(f"written {path}", file=stream)
    formats = getattr(verified.design.settings, "cam_tables", ())
    if formats:  # [design] cam_tables: the controllers' formats (strokeopt camtable writes and checks one)
        from ..files.cam_formats import write_tables

        for path, n in write_tables(verified.design, Path(args.out), formats):
            print(f"written {path} ({n} points a cam cycle)", file=stream)
    info = write_report(gather(verified, summary), Path(args.out) / "report.html")  # `strokeopt report`
    print(f"written {info['report']}", file=stream)


def _impact_range(text: str | None) -> list[float]:
    """``--impact-range MIN:MAX[:POINTS]`` -> the impact-velocity limits [m/s]."""
    from ..studies.sweeps import IMPACT_POINTS_MAX

    if text is None:
        raise ProblemError("--impact-range", "", "--study impact needs the limits: --impact-range MIN:MAX[:POINTS] "
                                                 "in m/s, e.g. 1.6:2.9:8")
    parts = text.split(":")
    try:
        lo, hi = float(parts[0]), float(parts[1])
        n = int(parts[2]) if len(parts) == 3 else 8
    except (ValueError, IndexError):
        raise ProblemError("--impact-range", "", f"expected MIN:MAX[:POINTS], got {text!r}") from None
    # the limits a stop is met at: 0.01-100 m/s, as design.contact.impact_velocity_max_m_s
    if len(parts) > 3 or not (0.01 <= lo < hi <= 100.0) or not 2 <= n <= IMPACT_POINTS_MAX:
        raise ProblemError("--impact-range", "", f"needs 0.01 <= MIN < MAX <= 100 (m/s) and 2 <= POINTS <= "
                                                 f"{IMPACT_POINTS_MAX}, got {text!r}")
    return [lo + (hi - lo) * k / (n - 1) for k in range(n)]


def _impact_study(args, problem, progress) -> int:
    from ..studies.sweeps import impact_study
    from ..report.design import impact_study_text, plot_impact_study
    from ..report.format import to_json

    velocities = _impact_range(args.impact_range)
    runner = _runner(args, len(velocities))
    rows = impact_study(problem, velocities, objective=args.objective, runner=runner,
                        progress=progress and (lambda it: progress(it, "limit")))
    good = [r for r in rows if r["feasible"] and r.get("verified") is not False]
    objective = _objective(args, problem)
    report = {"status": "ok" if good else "infeasible", "problem": problem.name, "spm": problem.spm,
              "study": "impact", "objective": objective, "drive": drive_used(args, problem),
              "runner": _chained(runner, "limits"), "rows": rows}
    if args.json:
        _emit(to_json(report))
    else:
        print(impact_study_text(report))
    _write_figure(lambda p: plot_impact_study(rows, p, objective, f"{problem.name}, {problem.spm:g} spm"),
                  _plot_path(args, "solve_impact", spm_tag(problem.spm), objective), args)
    if _report_failed_tasks(rows, "impact_velocity_max_m_s", "m/s impact-velocity limit"):
        return 1
    if not good:
        print("strokeopt: infeasible: no impact-velocity limit of the study gives a verified design", file=sys.stderr)
        return 1
    return 0


def _runner(args, tasks: int | None = None):
    """Where a study's tasks run: --workers, --scheduler, else $STROKEOPT_SCHEDULER, else one process per core
    (studies/runner.py; checked like a file's fields)."""
    from ..studies.runner import study_runner

    return study_runner(args.workers, args.scheduler, tasks=tasks)


def _chained(runner, points: str = "rates") -> str:
    """How a study's ``points`` (rates, limits) were warm-started, for its title and JSON."""
    if runner.in_process:
        return "warm-started, in this process"
    return f"warm-started within each worker's run of {points}, on {runner.describe()}"


def _report_failed_tasks(rows: list[dict], key: str, unit: str) -> bool:
    """One line on stderr per point whose task failed or was lost (an error, not an infeasible design), with
    its input; the other points' rows were reported. True when there was one."""
    from ..studies.sweeps import failed_tasks

    failed = failed_tasks(rows)
    for r in failed:
        print(f"strokeopt: failed: the task of {r[key]:g} {unit}: {r['reason']}", file=sys.stderr)
    return bool(failed)
