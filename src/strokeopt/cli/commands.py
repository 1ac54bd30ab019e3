"""The commands: each parses nothing and prints nothing of its own -- it loads the problem, calls the
library and hands the result to report/ (text, JSON, figures). Exit code 0, or 1 for a failed check."""

from __future__ import annotations

import sys

from ..errors import ProblemError
from .common import (_emit, _load, _plot_path, _write_figure, drive_used, progress_bar, require_belt_drive, spm_tag,
                     step_angle)


def cmd_laws(args) -> int:
    from ..motion.laws import law_table
    from ..report.format import format_table, to_json

    laws = None
    if args.law:  # --law NAME:PARAM=VALUE (repeatable): those laws at those parameters
        from ..motion.laws import make_law
        from .common import _law_option

        laws = [make_law(name, where=("command line", "--law"), **params)
                for name, params in map(_law_option, args.law)]
    rows = law_table(laws)
    if args.json:
        _emit(to_json({"status": "ok", "laws": rows}))
        _laws_figure(args, laws)
        return 0
    for r in rows:
        r["params"] = ", ".join(f"{k} = {v:g}" for k, v in r["params"].items()) or None
    print(format_table(rows, [("law", "law"), ("params", "parameters"), ("C_v", "C_v"), ("C_a", "C_a"),
                              ("C_j", "C_j"), ("continuity", "continuity"), ("first_jump", "first jump")],
                       title="Motion laws, unit rise (v = C_v h/T, a = C_a h/T^2, jerk = C_j h/T^3)"))
    print("\nC_j '-': the acceleration jumps (at the ends against a dwell, or inside), so the jerk is an impulse.")
    _laws_figure(args, laws)
    return 0


def _laws_figure(args, laws=None) -> None:
    if args.plot and args.plot.lower() != "none":
        from pathlib import Path

        from ..motion.laws import LAW_NAMES, make_law
        from ..report.motion import plot_laws

        laws = laws or [make_law(n) for n in LAW_NAMES]
        _write_figure(lambda p: plot_laws(laws, p), Path(args.plot), args)


def cmd_kinematics(args) -> int:
    from ..report.motion import plot_kinematics
    from ..report.motion import kinematics_summary, kinematics_text
    from ..io.load_units import to_load_units
    from ..report.format import drive_text, to_json

    problem = _load(args)
    stroke = args.design_stroke or problem.stroke()
    summary = kinematics_summary(problem, stroke, problem.spm, step_angle(problem))
    if args.design_stroke is not None:  # the table's law column: the design's stroke, not the file's law
        for row in summary["intervals"] + summary["moves"]:
            if row.get("law") is not None:
                row["law"] = stroke.label
    summary = {"status": "ok", **summary, "drive": drive_used(args, problem)}
    from ..report.linkage import analysis_failure, linkage_text, plot_analysis

    own = problem.transmission.analysis(problem)   # a linkage's outputs over the crank angle, its transmission index
    if own is not None:
        summary.update(status=own["status"], transmission_analysis=own)
    if args.json:  # a rotary load's keys and positions in deg (io/load_units.py), as design.json's
        _emit(to_json(to_load_units(summary, problem.timing.rotary)))
    else:
        print(kinematics_text(summary))
        print(drive_text(summary["drive"]))
        if own is not None:
            print("\n" + linkage_text(own))
    path = _plot_path(args, "kinematics", spm_tag(problem.spm), stroke.label)
    if own is not None:
        _write_figure(lambda p: plot_analysis(problem, own, p), path, args)
    else:
        _write_figure(lambda p: plot_kinematics(problem, stroke, problem.spm, p), path, args)
    failure = None if own is None else analysis_failure(own)
    if failure:
        print(f"strokeopt: {failure}", file=sys.stderr)
    return 1 if failure else 0


def cmd_size(args) -> int:
    from ..drive.sizing import optimal_radius
    from ..report.drive import plot_sizing, sizing_text
    from ..report.format import to_json

    problem = _load(args)
    if problem.drive is None:
        raise ProblemError(args.problem, "drive", "the problem has no [drive] section to size from (the motor or "
                                                  "its catalogues, the limits, the load's moving mass or inertia "
                                                  "where the transmission's own bodies do not carry it)")
    if args.continuous_radius and not hasattr(problem.transmission, "radius"):
        raise ProblemError("--continuous-radius", "", f"needs a belt pulley; the problem's transmission is a "
                                                      f"{problem.transmission.name}")
    catalogue = problem.drive.catalogue(args.catalogue)
    sizing, report = size_report(args, problem, catalogue)
    own = report.get("transmission_analysis")
    feasible = report["status"] == "ok"
    if args.continuous_radius:
        spec = problem.drive
        model = lambda d: catalogue.pulley_inertia(spec.profile, d)  # noqa: E731
        motors = {c.motor.name: c.motor for c in sizing.candidates}
        report["continuous_radius"] = [optimal_radius(m, spec.load, sizing.kinematics, model).row()
                                       for m in motors.values()]
    if args.json:
        _emit(to_json(report))
    else:
        if own is not None and own.get("dynamics") is not None:
            from ..report.linkage import dynamics_text

            print(dynamics_text(own) + "\n")
        print(sizing_text(sizing, report, explain=args.explain))
    best = sizing.candidates[0]  # the figure's pair
    _write_figure(lambda p: plot_sizing(sizing, None, p),
                  _plot_path(args, "size", spm_tag(problem.spm), sizing.inputs["law"], best.motor.name,
                             f"z{best.pulley.teeth}" if best.pulley.teeth is not None else best.pulley.name), args)
    if not feasible:
        print(f"strokeopt: {report['verdict']}", file=sys.stderr)
        return 1
    return 0


def size_report(args, problem, catalogue):
    """The sizing of ``size`` (every catalogue motor with every pulley or gearbox the problem allows) and its JSON
    report, with the transmission's own analysis where it has one (a linkage's crank torque, Newton-Euler's)."""
    from ..drive.sizing import size_drive
    from ..report.drive import sizing_verdict

    progress = progress_bar(args, "max spm", "pair", when=getattr(args, "max_spm", False))
    sizing = size_drive(problem, catalogue=catalogue, motors=args.motor, teeth=getattr(args, "pulley_teeth", None),
                        find_max_spm=getattr(args, "max_spm", False), progress=progress, stroke=args.design_stroke)
    feasible = any(c.feasible for c in sizing.candidates)
    explain = getattr(args, "explain", False)
    report = {"status": "ok" if feasible else "infeasible", **sizing.to_dict(explain=explain),
              "cycle": problem.cycle.noun,  # the machine's cycle: stitch, pick (io/cycle.py)
              "drive": {"motors": args.motor or "every catalogue motor",
                        "pulley_teeth": getattr(args, "pulley_teeth", None) or "the problem's pulley_teeth_min..max",
                        "from": args.drive_from}}
    if not hasattr(problem.transmission, "radius"):  # no pulley to choose: the problem's transmission
        report["drive"]["pulley_teeth"] = None
        report["drive"]["transmission"] = problem.transmission.name
        report["drive"]["gearboxes"] = problem.drive.gearbox_file   # chosen from this catalogue (None: the ratio)
    report["verdict"] = sizing_verdict(sizing)
    own = problem.transmission.analysis(problem, with_dynamics=True)   # a linkage's crank torque, Newton-Euler
    if own is not None:
        report["transmission_analysis"] = own
    return sizing, report


def cmd_bench(args) -> int:
    from ..bench.registry import format_results
    from ..bench.run import run_benchmarks
    from ..report.format import to_json

    if args.list:
        from ..bench.run import benchmark_names

        names = benchmark_names()
        if args.json:
            _emit(to_json({"status": "ok", "benchmarks": [{"name": n, "description": d} for n, d in names]}))
        else:
            print("\n".join(f"{n:<28s} {d}" for n, d in names))
        return 0

    def progress(name, k, n, seconds):  # one line per benchmark on stderr (stdout: the results)
        print(f"bench {k}/{n} {name}: " + ("running" if seconds is None else f"done in {seconds:.1f} s"),
              file=sys.stderr, flush=True)

    results = run_benchmarks(args.only, progress)
    missed = [r.name for r in results if r.meets_target is False]
    if args.json:
        _emit(to_json({"status": "targets missed" if missed else "ok", "benchmarks": [r.as_dict() for r in results]}))
    else:
        print(format_results(results))
    if missed and args.check:
        print(f"strokeopt: targets missed: {', '.join(missed)}", file=sys.stderr)
        return 1
    return 0


def cmd_accuracy(args) -> int:
    from ..report.format import to_json
    from ..report.servo import accuracy_text, plot_accuracy
    from ..report.machine import machine_of
    from ..servo.accuracy import accuracy_report

    problem = _load(args)
    stroke, label, extra = args.design_stroke, "", []
    if stroke is not None:
        label = f"optimal ({args.design_data.get('objective', 'design')})"
        extra = [(label, stroke)]  # its row in the table of the classic laws
    progress = progress_bar(args, "laws", "law", when=bool(args.compare_laws or extra))
    # with --design the whole report is of the design's stroke on its drive; the classic laws follow as a table
    # a design's stroke is judged within its check tolerance (as its solve judged it), a classic law's exactly
    tol = problem.design.check_tolerance if stroke is not None and problem.design is not None else 0.0
    report, result = accuracy_report(problem, problem.spm, stroke=stroke, label=label,
                                     compare_laws=args.compare_laws or bool(extra), extra_strokes=extra,
                                     progress=progress, tolerance=tol)
    report = {"status": report.pop("status"), **report, "drive": drive_used(args, problem)}
    if args.json:
        _emit(to_json(report))
    else:
        print(accuracy_text(report))
    tags = [f"design_{extra[0][0]}" if extra else report["label"], report["motor"]]
    output = machine_of(problem).output   # what the stroke moves: the bar, a rotary load
    _write_figure(lambda p: plot_accuracy(result, p, report["motor"], output=output, cycle=problem),
                  _plot_path(args, "accuracy", spm_tag(problem.spm), *tags), args)
    if report["status"] != "ok":
        print(f"strokeopt: {report['verdict']}", file=sys.stderr)
        return 1
    return 0


def cmd_tradeoff(args) -> int:
    from ..report.format import to_json
    from ..report.servo import plot_tradeoff, tradeoff_text
    from ..design.transcription.settings import ACCURACY_RANGE_MM
    from ..studies.runner import check_reachable, study_runner
    from ..studies.tradeoff import DEFAULT_ACCURACIES_MM, RESOLUTION_RANGE_SPM, STARTS_MAX, print_step, tradeoff

    problem = _load(args)
    require_belt_drive(problem, "tradeoff")
    accuracies = None
    if args.accuracies is not None:
        try:
            accuracies = [float(x) * 1e-3 for x in args.accuracies.split(",")]
        except ValueError:
            raise ProblemError("--accuracies", "", f"expected comma-separated millimetres (0.05,0.1), got "
                                                   f"{args.accuracies!r}") from None
        twice = sorted({a for a in accuracies if accuracies.count(a) > 1})
        if twice:
            raise ProblemError("--accuracies", "", f"{', '.join(f'{a * 1e3:g}' for a in twice)} mm given twice: give "
                                                   "each accuracy once")
        lo, hi = ACCURACY_RANGE_MM
        if not all(lo * 1e-3 <= a <= hi * 1e-3 for a in accuracies):
            raise ProblemError("--accuracies", "", f"every accuracy must lie in [{lo:g}, {hi:g}] mm, the range of "
                                                   f"[design] handover_accuracy_mm, got {args.accuracies!r}")
    lo, hi = RESOLUTION_RANGE_SPM
    if not lo <= args.resolution <= hi:
        raise ProblemError("--resolution", "", f"must lie in [{lo:g}, {hi:g}] spm (finer than the rate settles to, "
                                               f"or coarser than the search's span), got {args.resolution!r}")
    try:
        starts = int(str(args.starts).strip())
    except ValueError:
        starts = None
    if starts is None or not 1 <= starts <= STARTS_MAX:
        raise ProblemError("--starts", "", f"expected a whole number of starts per accuracy in 1..{STARTS_MAX}, got "
                                           f"{args.starts!r}")
    if starts > 1 and args.strokes == "classic":
        raise ProblemError("--starts", "", "is for the optimal stroke (--strokes optimal or both): the classic law's "
                                           "rates are simulated, not solved from a start")
    runner = study_runner(args.workers, args.scheduler, tasks=len(accuracies or DEFAULT_ACCURACIES_MM) * starts)
    if args.strokes == "classic":
        runner = None  # the classic law alone starts no worker (the options were still checked)
    else:
        check_reachable(runner)  # an unreachable scheduler: before the classic law's simulations
    report = tradeoff(problem, accuracies, strokes=args.strokes, resolution=args.resolution,
                      progress=None if args.json else print_step, runner=runner, starts=starts)
    if runner is not None:
        report["runner"] = runner.describe()
    report = {"status": "ok", **report, "drive": drive_used(args, problem)}
    if args.json:
        _emit(to_json(report))
    else:
        print(tradeoff_text(report))
    _write_figure(lambda p: plot_tradeoff(report, p),
                  _plot_path(args, "tradeoff", args.strokes, report["law"], report["motor"]), args)
    return 0


def _sim_options(args):
    from ..contact.simulate import SimulationOptions

    # hard contact switches only: smoothing them is a numerical study device (SimulationOptions.smoothing,
    # --study tolerance shows its bias), not a model option; at ordinary widths it changes the answer
    options = SimulationOptions(method=args.method, rtol=args.rtol, atol=args.atol, verbose=args.verbose)
    try:
        options.check()
    except ProblemError as exc:  # the library names its field; the command line names its option
        raise ProblemError(f"--{exc.field}", "", exc.message) from None
    return options


def _scene_name(args, problem) -> str:
    if not problem.scenes:
        raise ProblemError(str(problem.file), "scenes", "the problem defines no [scenes.*] (and [model]) to simulate")
    name = args.scene or ("release" if "release" in problem.scenes else next(iter(problem.scenes)))
    if name not in problem.scenes:
        from ..io.fields import did_you_mean

        raise ProblemError(str(problem.file), "--scene", f"no scene {name!r}{did_you_mean(name, problem.scenes)}; "
                                                         f"the problem has: {', '.join(problem.scenes)}")
    return name


def _belt_breaking(problem) -> dict:
    """The belt's breaking load [N] (catalogue, the drive's cord), to print beside a contact-model force."""
    drive = getattr(problem, "drive", None)
    if drive is None or drive.belt is None:
        return {}
    belt = drive.catalogue().belt(drive.belt, (str(problem.file), "drive.belt"))
    load = belt.breaking_tension.get(drive.belt_cord)
    return {} if load is None else {"belt_breaking_load_N": load, "belt": f"{belt.name}, {drive.belt_cord} cord"}


def _report_scene(args, problem, scene, result, extra=None, kind: str = "simulate", status: str = "ok") -> int:
    from ..report.contact import plot_scene, scene_text
    from ..report.format import to_json

    summary = {"status": status, **(extra or {}), **result.summary(), **_belt_breaking(problem),
               "drive": drive_used(args, problem)}
    if args.verbose:
        print(f"integrator: {result.options.method}, {result.stats['nsteps']} steps, "
              f"{result.stats['n_output']} output points", file=sys.stderr)
    if args.json:
        _emit(to_json(summary))
    else:
        print(scene_text(problem, scene, summary))
    what = extra.get("objective", result.stroke_label) if extra else result.stroke_label  # verify: the design's
    if extra and "chain" in extra:  # a model on a transmission's members: elastic against rigid
        from ..report.contact import plot_chain

        stroke = args.design_stroke or problem.stroke()
        _write_figure(lambda p: plot_chain(result, problem, stroke, p),
                      _plot_path(args, kind, scene, spm_tag(result.spm), what), args)
        return 0
    _write_figure(lambda p: plot_scene(result, p), _plot_path(args, kind, scene, spm_tag(result.spm), what), args)
    return 0


def cmd_simulate(args) -> int:
    from ..contact.simulate import simulate_scene
    from ..contact.studies import lag_onset_spm, sweep_spm, tolerance_study
    from ..files.ranges import parse_spm_range
    from ..report.contact import STUDY_COLUMNS, SWEEP_COLUMNS, plot_sweep, plot_tolerance_study
    from ..report.format import format_table, to_json

    spms = parse_spm_range(args.spm) if args.spm is not None else None
    if spms is not None:
        args.spm = spms if len(spms) > 1 else str(spms[0])
    problem = _load(args)
    scene = _scene_name(args, problem)
    options = _sim_options(args)
    if args.vary:
        return _simulate_vary(args, problem, scene, options)
    if args.study == "tolerance":
        if isinstance(args.spm, list):
            raise ProblemError("--spm", "", "the tolerance study runs at one speed, not a range")
        if args.design_stroke is not None:
            raise ProblemError("--design", "", "the tolerance study runs the problem's law: omit --design or --study")
        study = tolerance_study(problem, scene, problem.spm, progress=not args.json)
        if args.json:
            _emit(to_json({"status": "ok", **study}))
        else:
            ref = study["reference"]
            print(f"work-precision of scene {scene!r} at {study['spm']:g} spm against a reference at rtol "
                  f"{ref['rtol']:g} (impact {ref['impact_velocity_m_s']:.4f} m/s at {ref['impact_angle_deg']:.3f} deg, "
                  f"release {ref['release_angle_deg']:.3f} deg; {ref['cpu_time_s']:.2f} s CPU)")
            print(format_table([r for r in study["rows"] if "failed" not in r], STUDY_COLUMNS))
            for r in study["rows"]:
                if "failed" in r:
                    print(f"failed: {r['method']} rtol {r['rtol']:g} smoothing {r['smoothing_mm']:g} mm: {r['failed']}")
        _write_figure(lambda p: plot_tolerance_study(study, p), _plot_path(args, "simulate_tolerance", scene, spm_tag(problem.spm), problem.stroke().label),
                      args)
        return 0
    if isinstance(args.spm, list):
        rows = sweep_spm(problem, scene, args.spm, options, progress=not args.json)
        onset = lag_onset_spm(rows)
        premature = lag_onset_spm(rows, "premature_release")
        if args.json:
            _emit(to_json({"status": "ok", "scene": scene, "lag_onset_spm": onset,
                           "premature_release_onset_spm": premature, "rows": rows}))
        else:
            print(format_table(rows, SWEEP_COLUMNS, title=f"{problem.name}: scene {scene!r}, speed sweep "
                                                          f"(interval times {problem.timing.interval_times})"))
            if onset is None:
                print("\nthe follower lags at no speed of the sweep")
            else:
                print(f"\nthe follower lags from {onset:g} spm" + (" (the first speed of the sweep: start lower to "
                                                                   "find the onset)" if onset == rows[0]["spm"] else ""))
            if premature is not None:
                print(f"premature release from {premature:g} spm: gap N closes before the impact (columns "
                      f"'premature', 'min gap N mm')")
        _write_figure(lambda p: plot_sweep(rows, p, problem.cycle),
                      _plot_path(args, "simulate_sweep", scene, spm_tag(args.spm), problem.stroke().label), args)
        return 0
    result = simulate_scene(problem, scene, problem.spm, stroke=args.design_stroke, options=options)
    from ..contact.chain import chain_results
    from ..contact.plausible import implausible_text, scene_implausible

    stroke = args.design_stroke or problem.stroke()
    chain = chain_results(problem, result, stroke)  # a model on a transmission
    # a peak beyond what the scene's bodies and springs can load an element with is the model taken where it
    # does not hold (contact/plausible.py): reported with its limit, never "ok"
    implausible = scene_implausible(problem, result, stroke)
    extra = {**({"chain": chain} if chain else {}), **({"implausible_forces": implausible} if implausible else {})}
    _report_scene(args, problem, scene, result, extra or None, status="implausible forces" if implausible else "ok")
    if implausible:
        print(f"strokeopt: implausible forces in scene {scene!r}: {implausible_text(implausible)} (more than the "
              "scene's bodies and springs can load any element with: contact/plausible.py)", file=sys.stderr)
        return 1
    return 0


def _simulate_vary(args, problem, scene, options) -> int:
    """``simulate --vary``: the scene at one rate over the values of one field or several moved together."""
    from ..report.contact import SWEEP_COLUMNS, plot_sweep
    from ..report.format import format_table, to_json
    from ..studies.runner import study_runner
    from ..studies.vary import parse_vary, vary_scene

    if isinstance(args.spm, list):
        raise ProblemError("--vary", "", "varies a number at one rate: give --spm one rate, not a sweep")
    if args.study is not None:
        raise ProblemError("--vary", "", "runs one scene at one rate: omit --study")
    varies = parse_vary(args.vary, problem)
    runner = study_runner(args.workers, args.scheduler, tasks=len(varies[0].values))
    rows = vary_scene(problem, scene, problem.spm, varies, options, runner=runner, progress=not args.json,
                      stroke=args.design_stroke)
    flat = [{**{v.field: r["varied"][v.field] for v in varies}, **r} for r in rows]
    first = next((r for r in flat if r.get("premature_release")), None)
    failed = [r for r in flat if "failed" in r]
    if args.json:
        _emit(to_json({"status": "failed" if failed else "ok", "scene": scene, "spm": problem.spm,
                       "varied": [{"field": v.field, "nominal": v.nominal,
                                   "values": [v.value(k) for k in range(len(v.values))]} for v in varies],
                       "runner": runner.describe(), "rows": rows}))
    else:
        columns = [(v.field, v.field) for v in varies] + [c for c in SWEEP_COLUMNS if c[0] != "spm"]
        columns.insert(len(columns) - 1, ("peak_drive_force_N", "drive N"))
        print(format_table([r for r in flat if "failed" not in r], columns,
                           title=f"{problem.name}: scene {scene!r} at {problem.cycle.rate(problem.spm)}, "
                                 + " and ".join(f"{v.field} (file: {v.nominal:g})" for v in varies) + " varied"))
        what = " and ".join(v.field for v in varies)
        lagging = [r for r in flat if r.get("lag")]
        print("\nthe follower lags at no step" if not lagging else "\nthe follower lags at every step" if len(lagging) == len(
            flat) - len(failed) else f"\nthe follower lags at {what} = " + "; ".join(
            ", ".join(f"{r[v.field]:g}" for v in varies) for r in lagging))
        if first is not None:
            print(f"premature release from {what} = " + ", ".join(f"{first[v.field]:g}" for v in varies)
                  + ": gap N closes before the impact (columns 'premature', 'min gap N mm')")
        else:
            print("no premature release: gap N stays open until the impact at every step")
        for r in failed:
            print(f"failed at {', '.join(f'{v.field} = {r[v.field]:g}' for v in varies)}: {r['failed']}")
        print(f"ran on {runner.describe()}")
    label = varies[0].field + (f" (moved with {', '.join(v.field for v in varies[1:])})" if len(varies) > 1 else "")
    _write_figure(lambda p: plot_sweep(rows, p, problem.cycle, varied=varies[0].field, label=label),
                  _plot_path(args, "simulate_vary", scene, spm_tag(problem.spm),
                             (args.design_stroke or problem.stroke()).label), args)
    return 1 if failed else 0


def cmd_verify(args) -> int:
    from ..design.result import design_from_data
    from ..files.design_file import design_problem_file
    from ..studies.verified import verify_design

    if args.design is None:  # verify DESIGN.json [--problem FILE]: the problem recorded in the design
        from ..files.design_file import read_design

        args.design = args.file
        args.problem = str(design_problem_file(args.design, read_design(args.design)[0], args.problem))
    elif args.problem is not None:
        raise ProblemError("--problem", "", f"give the problem once: as {args.file} with --design, or as --problem "
                                            "with a DESIGN.json argument")
    else:
        args.problem = args.file
    problem = _load(args)
    design = design_from_data(problem, args.design_data, args.design_stroke)
    scene = _scene_name(args, problem)
    # the library's judgement (studies/verified.py): the full servo simulation made again on this problem, the
    # design judged in this scene by the problem's [design.contact] limits
    verified = verify_design(design, scene=scene, options=_sim_options(args))
    result, block = verified.scenes[scene], verified.verification
    _report_scene(args, problem, scene, result, {"design": str(args.design), "objective": design.objective,
                                                 "verification": block, "verdict": verified.verdict},
                  kind="verify", status=block["status"])
    if not args.json:
        from ..report.contact import verification_text

        print(verification_text(block))
    if block["status"] != "ok":
        print(f"strokeopt: {block['verdict']}", file=sys.stderr)
        return 1
    return 0
