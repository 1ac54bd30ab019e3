"""`strokeopt` command line: parse, call the public API, print or write. Thin on purpose.

Exit codes: 0 success, 2 bad input (problem file, option, catalogue) with a
one-line message naming the file and the field, 1 a solve or a check that
failed for a stated reason.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from .errors import ProblemError, SolverError, StrokeoptError

DEFAULT_OUT = Path("strokeopt-out")


def _problem_parent() -> argparse.ArgumentParser:
    """Options every command on a problem file takes."""
    p = argparse.ArgumentParser(add_help=False)
    p.add_argument("problem", metavar="PROBLEM", help="design problem file (TOML), e.g. problems/deco2000_needle_bar.toml")
    p.add_argument("--set", dest="overrides", action="append", default=[], metavar="KEY.PATH=VALUE",
                   help="override a value of the problem file, validated like the file "
                        "(repeatable; arrays 1-based: --set 'timing.intervals[2].law=poly5')")
    p.add_argument("--json", action="store_true", help="print only JSON on stdout (for scripts)")
    p.add_argument("--verbose", action="store_true", help="print solver and integrator output")
    return p


def _stroke_options(p: argparse.ArgumentParser, sweep: bool = False, law: bool = True) -> None:
    """--spm (and a START:STOP:STEP sweep where the command has one), --law, --chi."""
    p.add_argument("--spm", help="stitches per minute" + (", or a sweep START:STOP:STEP" if sweep else "")
                   + " (default: machine.spm of the file)")
    if law:
        p.add_argument("--law", help="use this motion law for every move (see 'strokeopt laws')")
        p.add_argument("--chi", type=float, help="shape parameter chi of the modified sine law (0 < chi <= 0.25)")


def _plot_option(p: argparse.ArgumentParser, name: str | None) -> None:
    where = f"default {DEFAULT_OUT}/<problem>_{name}.png; " if name else ""
    p.add_argument("--plot", metavar="FILE", help=f"figure file ({where}'none' for no figure)")


def _spm_value(text: str) -> float:
    try:
        value = float(text)
    except ValueError:
        raise ProblemError("--spm", "", f"expected a number of stitches per minute, got {text!r}") from None
    if not value > 0 or value != value or value == float("inf"):
        raise ProblemError("--spm", "", f"must be positive, got {text}")
    return value


def _load(args):
    from .motion.laws import make_law
    from .io.problem_file import load_problem

    overrides = list(args.overrides)
    if getattr(args, "spm", None) is not None and not isinstance(args.spm, list):
        overrides.append(f"machine.spm={_spm_value(args.spm)!r}")
    problem = load_problem(args.problem, overrides)
    law_name = getattr(args, "law", None)
    chi = getattr(args, "chi", None)
    if law_name is not None or chi is not None:
        name = law_name or problem.default_law.name
        params = {} if law_name and law_name != problem.default_law.name else dict(problem.default_law.params)
        if chi is not None:
            params["chi"] = chi
        problem = problem.with_law(make_law(name, where=("command line", "--law/--chi"), **params))
    return problem


def _plot_path(args, default_name: str) -> Path | None:
    """Where to write the figure: --plot FILE, none with --plot none, else strokeopt-out/<name>."""
    if args.plot is not None:
        return None if args.plot.lower() == "none" else Path(args.plot)
    stem = Path(args.problem).stem if hasattr(args, "problem") else "strokeopt"
    return DEFAULT_OUT / f"{stem}_{default_name}.png"


def _write_figure(figure_fn, path: Path | None, args) -> None:
    if path is None:
        return
    import matplotlib

    matplotlib.use("Agg")
    path.parent.mkdir(parents=True, exist_ok=True)
    figure_fn(path)
    print(f"figure written to {path}", file=sys.stderr if args.json else sys.stdout)


# --------------------------------------------------------------------------- commands


def cmd_laws(args) -> int:
    from .motion.laws import law_table
    from .report.format import format_table, to_json

    rows = law_table()
    if args.json:
        _emit(to_json({"laws": rows}))
        return 0
    for r in rows:
        r["params"] = ", ".join(f"{k} = {v:g}" for k, v in r["params"].items()) or None
    print(format_table(rows, [("law", "law"), ("params", "parameters"), ("C_v", "C_v"), ("C_a", "C_a"),
                              ("C_j", "C_j"), ("continuity", "continuity"), ("first_jump", "first jump")],
                       title="Classic motion laws, unit rise (v = C_v h/T, a = C_a h/T^2, jerk = C_j h/T^3)"))
    print("\nC_j '-': the acceleration jumps (at the ends against a dwell, or inside), so the jerk is an impulse.")
    return 0


def cmd_kinematics(args) -> int:
    from .report.motion import plot_kinematics
    from .report.motion import kinematics_summary, kinematics_text
    from .report.format import to_json

    problem = _load(args)
    stroke = problem.stroke()
    summary = kinematics_summary(problem, stroke, problem.spm)
    if args.json:
        _emit(to_json(summary))
    else:
        print(kinematics_text(summary))
    _write_figure(lambda p: plot_kinematics(problem, stroke, problem.spm, p), _plot_path(args, "kinematics"), args)
    return 0


def cmd_size(args) -> int:
    from .drive.sizing import optimal_radius, size_drive
    from .report.format import format_table, to_json

    problem = _load(args)
    if problem.drive is None:
        raise ProblemError(args.problem, "drive", "the problem has no [drive] section (motor, moving_mass_kg, ...)")
    catalogue = problem.drive.catalogue(args.catalogue)
    progress = None
    if args.max_spm and not args.json:
        from tqdm import tqdm

        progress = lambda it: tqdm(it, desc="max spm", unit="pair", file=sys.stderr, leave=False)  # noqa: E731
    sizing = size_drive(problem, catalogue=catalogue, motors=args.motor, teeth=args.pulley_teeth,
                        find_max_spm=args.max_spm, progress=progress)
    report = sizing.to_dict(explain=args.explain)
    if args.continuous_radius:
        spec = problem.drive
        model = lambda d: catalogue.pulley_inertia(spec.profile, d)  # noqa: E731
        motors = {c.motor.name: c.motor for c in sizing.candidates}
        report["continuous_radius"] = []
        for m in motors.values():
            opt = optimal_radius(m, spec.load, sizing.kinematics, model)
            report["continuous_radius"].append({
                "motor": m.name, "pitch_radius_mm": opt.radius * 1e3, "pitch_diameter_mm": 2e3 * opt.radius,
                "teeth_equivalent": opt.teeth_equivalent, "peak_torque_N_m": opt.peak_torque,
                "pulley_inertia_kg_cm2": opt.pulley_inertia * 1e4})
    if args.json:
        _emit(to_json(report))
    else:
        inp = report["inputs"]
        forces = "; ".join(f"{f['name']} ({f['kind']}, {f['force_N']:g} N + {f['stiffness_N_m']:g} N/m "
                           f"beyond {f['contact_position_mm']:g} mm, pushing {f['direction']})"
                           for f in inp["load_forces"]) or "none"
        print(f"{report['problem']} at {report['spm']:g} spm (cycle {report['cycle_time_s'] * 1e3:.1f} ms, "
              f"{inp['law']}, {inp['samples']} samples over the whole cycle)")
        print(f"load: moving mass {inp['moving_mass_kg']:g} kg, gravity {inp['gravity_m_s2']:g} m/s^2 along the "
              f"axis, load forces: {forces}")
        print(f"limits: drive peak {inp['peak_limit_pct']:g} % of rated torque, inertia ratio <= "
              f"{inp['max_inertia_ratio']:g}; belt {inp['belt']} ({inp['belt_cord']} cord, service factor "
              f"{inp['belt_service_factor']})")
        print("ranked: feasible first, then by overload (peak / rated torque); 'binding' = the check with the "
              "least margin\n")
        cols = [("motor", "motor"), ("pulley_teeth", "z"), ("pulley_pitch_diameter_mm", "PD mm"),
                ("peak_torque_N_m", "peak N m"), ("rms_torque_N_m", "RMS N m"), ("overload_pct", "overload %"),
                ("peak_speed_rpm", "speed rpm"), ("inertia_ratio", "J ratio"), ("feasible", "feasible"),
                ("binding", "binding"), ("margin", "margin")]
        if args.max_spm:
            cols += [("max_spm", "max spm"), ("max_spm_binding", "limited by")]
        print(format_table(report["candidates"], cols))
        if args.max_spm:
            print(f"\nmax spm: bisection per pair to {sizing.max_spm_resolution:g} spm (rounded down); "
                  "'limited by' is the check that fails just above it")
        if args.explain:
            rows = []
            for c in sizing.candidates:
                rows.append({"motor": c.motor.name, "z": c.pulley.teeth, "angle": c.peak_angle_deg,
                             **{k: v for k, v in c.peak_terms.items()}})
            keys = [k for k in rows[0] if k not in ("motor", "z", "angle")]
            print("\nmotor torque at the instant of the peak, by term [N m] (they add up to the total):")
            print(format_table(rows, [("motor", "motor"), ("z", "z"), ("angle", "cam deg")] + [(k, k) for k in keys]))
            best = sizing.candidates[0]
            print(f"\nchecks of {best.motor.name} with z{best.pulley.teeth}:")
            print(format_table([c.as_dict() for c in best.checks], [("name", "check"), ("value", "value"),
                               ("limit", "limit"), ("unit", "unit"), ("margin", "margin"), ("ok", "ok")]))
        if args.continuous_radius:
            print("\ncontinuous pulley radius minimising the peak torque (pulley inertia from the catalogue's model):")
            print(format_table(report["continuous_radius"], [
                ("motor", "motor"), ("pitch_radius_mm", "radius mm"), ("pitch_diameter_mm", "PD mm"),
                ("teeth_equivalent", "teeth (not rounded)"), ("peak_torque_N_m", "peak N m")]))
    _write_figure(lambda p: sizing.plot(p), _plot_path(args, "sizing"), args)
    return 0


def cmd_bench(args) -> int:
    from .bench.registry import format_results
    from .bench.run import run_benchmarks
    from .report.format import to_json

    results = run_benchmarks(args.only)
    if args.json:
        _emit(to_json({"benchmarks": [r.as_dict() for r in results]}))
    else:
        print(format_results(results))
    return 0


def cmd_accuracy(args) -> int:
    from .report.format import to_json
    from .servo.loop import accuracy_report, accuracy_text

    stroke, label, extra = None, "", []
    if args.design:
        from .io.design_file import read_design

        data, stroke = read_design(args.design)
        if args.spm is not None and abs(_spm_value(args.spm) - float(data["spm"])) > 1e-9:
            raise ProblemError(args.design, "spm", f"the design was solved at {data['spm']:g} spm, not at {args.spm} "
                                                   "spm: omit --spm or solve the design at that rate")
        args.spm = str(data["spm"])
        label = f"optimal ({data.get('objective', 'design')})"
        extra = [(label, stroke)]  # its row in the table of the classic laws
        drive_used = _design_drive(args, data)
    problem = _load(args)
    progress = None
    if (args.compare_laws or extra) and not args.json:
        from tqdm import tqdm

        def progress(items):
            return tqdm(items, desc="laws", unit="law", file=sys.stderr, leave=False)
    # with --design the whole report is of the design's stroke on its drive; the classic laws follow as a table
    report, result = accuracy_report(problem, problem.spm, stroke=stroke, label=label,
                                     compare_laws=args.compare_laws or bool(extra), extra_strokes=extra,
                                     progress=progress)
    if args.design:
        report["drive_from_design"] = {"design": str(args.design), **drive_used}
    if args.json:
        _emit(to_json(report))
    else:
        print(accuracy_text(report))
    _write_figure(lambda p: result.plot(p), _plot_path(args, "accuracy"), args)
    return 0


def _design_drive(args, data: dict) -> dict:
    """Make ``args.overrides`` use the motor and pulley a design.json was solved with (the design's
    stroke is only right on its own drive); a --set forcing another motor or pulley is an error."""
    from .io.fields import parse_override

    design = {"motor": data.get("motor"), "pulley_teeth": data.get("pulley_teeth")}
    keys = {"motor": ("drive", "motor"), "pulley_teeth": ("transmission", "pulley_teeth")}
    used = {}
    for name, path in keys.items():
        value = design[name]
        if value is None:
            continue
        for text in args.overrides:
            key, forced = parse_override(text)
            if tuple(key) == path and forced != value:
                raise ProblemError(args.design, name, f"the design was solved with {name} {value}, but --set {text} "
                                                      "forces another: omit the --set or solve the design for it")
        args.overrides.append(f"{'.'.join(path)}={value!r}" if name == "pulley_teeth"
                              else f'{".".join(path)}="{value}"')
        used[name] = value
    return used


def cmd_tradeoff(args) -> int:
    from .report.format import to_json
    from .servo.tradeoff import plot_tradeoff, tradeoff, tradeoff_text

    problem = _load(args)
    accuracies = None
    if args.accuracies:
        try:
            accuracies = [float(x) * 1e-3 for x in args.accuracies.split(",")]
        except ValueError:
            raise ProblemError("--accuracies", "", f"expected comma-separated millimetres, got {args.accuracies!r}") from None
        if not all(a > 0 and a != float("inf") for a in accuracies):
            raise ProblemError("--accuracies", "", f"every accuracy must be positive, got {args.accuracies!r}")
    if not args.resolution > 0:
        raise ProblemError("--resolution", "", f"must be positive, got {args.resolution!r}")
    progress = None
    if not args.json:
        from tqdm import tqdm

        def progress(items):
            return tqdm(items, desc="tradeoff", file=sys.stderr, leave=False)
    report = tradeoff(problem, accuracies, strokes=args.strokes, resolution=args.resolution, progress=progress)
    if args.json:
        _emit(to_json(report))
    else:
        print(tradeoff_text(report))
    _write_figure(lambda p: plot_tradeoff(report, p), _plot_path(args, "tradeoff"), args)
    return 0


def _sim_options(args):
    from .contact.simulate import SimulationOptions

    # hard contact switches only: smoothing them is a numerical study device (SimulationOptions.smoothing,
    # --study tolerance shows its bias), not a model option; at ordinary widths it changes the answer
    return SimulationOptions(method=args.method, rtol=args.rtol, atol=args.atol, verbose=args.verbose)


def _scene_name(args, problem) -> str:
    from .errors import ProblemError

    if not problem.scenes:
        raise ProblemError(str(problem.file), "scenes", "the problem defines no [scenes.*] (and [model]) to simulate")
    name = args.scene or ("release" if "release" in problem.scenes else next(iter(problem.scenes)))
    if name not in problem.scenes:
        raise ProblemError(str(problem.file), "--scene", f"no scene {name!r}; the problem has: {', '.join(problem.scenes)}")
    return name


def _report_scene(args, problem, scene, result, extra=None, kind: str = "simulate") -> None:
    from .report.format import to_json
    from .contact.simulate import scene_text

    summary = {**(extra or {}), **result.summary()}
    if args.verbose:
        print(f"integrator: {result.options.method}, {result.stats['nsteps']} steps, "
              f"{result.stats['n_output']} output points", file=sys.stderr)
    if args.json:
        _emit(to_json(summary))
    else:
        print(scene_text(problem, scene, summary))
    _write_figure(lambda p: result.plot(p), _plot_path(args, f"{kind}_{scene}"), args)


def cmd_simulate(args) -> int:
    from .report.format import format_table, to_json
    from .report.contact import plot_sweep, plot_tolerance_study
    from .contact.simulate import STUDY_COLUMNS, SWEEP_COLUMNS, lag_onset_spm, parse_spm_range, simulate_scene, sweep_spm, tolerance_study

    spms = parse_spm_range(args.spm) if args.spm is not None else None
    if spms is not None:
        args.spm = spms if len(spms) > 1 else str(spms[0])
    problem = _load(args)
    scene = _scene_name(args, problem)
    options = _sim_options(args)
    if args.study == "tolerance":
        if isinstance(args.spm, list):
            from .errors import ProblemError

            raise ProblemError("--spm", "", "the tolerance study runs at one speed, not a range")
        study = tolerance_study(problem, scene, problem.spm, progress=not args.json)
        if args.json:
            _emit(to_json(study))
        else:
            ref = study["reference"]
            print(f"work-precision of scene {scene!r} at {study['spm']:g} spm against a reference at rtol "
                  f"{ref['rtol']:g} (impact {ref['impact_velocity_m_s']:.4f} m/s at {ref['impact_angle_deg']:.3f} deg, "
                  f"release {ref['release_angle_deg']:.3f} deg; {ref['cpu_time_s']:.2f} s CPU)")
            print(format_table([r for r in study["rows"] if "failed" not in r], STUDY_COLUMNS))
            for r in study["rows"]:
                if "failed" in r:
                    print(f"failed: {r['method']} rtol {r['rtol']:g} smoothing {r['smoothing_mm']:g} mm: {r['failed']}")
        _write_figure(lambda p: plot_tolerance_study(study, p), _plot_path(args, f"tolerance_{scene}"), args)
        return 0
    if isinstance(args.spm, list):
        rows = sweep_spm(problem, scene, args.spm, options, progress=not args.json)
        onset = lag_onset_spm(rows)
        premature = lag_onset_spm(rows, "premature_release")
        if args.json:
            _emit(to_json({"scene": scene, "lag_onset_spm": onset, "premature_release_onset_spm": premature,
                           "rows": rows}))
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
        _write_figure(lambda p: plot_sweep(rows, p), _plot_path(args, f"sweep_{scene}"), args)
        return 0
    result = simulate_scene(problem, scene, problem.spm, options=options)
    _report_scene(args, problem, scene, result)
    return 0


def cmd_verify(args) -> int:
    from .io.design_file import read_design
    from .errors import ProblemError
    from .io.problem_file import load_problem
    from .contact.simulate import simulate_scene

    data, stroke = read_design(args.design)
    problem_file = args.problem or data.get("problem_file")
    if not problem_file:
        raise ProblemError(args.design, "problem_file", "is missing: pass --problem FILE")
    path = Path(problem_file)
    if not path.is_absolute() and not path.exists() and (Path(args.design).parent / path).exists():
        path = Path(args.design).parent / path
    problem = load_problem(path, list(args.overrides) + [f"machine.spm={float(data['spm'])!r}"])
    args.problem = str(path)
    scene = _scene_name(args, problem)
    result = simulate_scene(problem, scene, problem.spm, stroke=stroke, options=_sim_options(args))
    _report_scene(args, problem, scene, result, {"design": str(args.design), "objective": data.get("objective")},
                  kind="verify")
    return 0


def cmd_solve(args) -> int:
    from .design.objectives import OBJECTIVES
    from .design.compare import compare_with_laws
    from .design.solve import solve_design
    from .design.studies import fastest_feasible, mesh_study, sweep_design
    from .io.design_file import check_out_dir
    from .report.design import design_summary, design_text
    from .report.design import plot_design_sweep, plot_mesh_study
    from .report.motion import plot_kinematics
    from .report.format import format_table, to_json

    sweep = None
    if args.spm is not None and ":" in args.spm:
        parts = args.spm.split(":")
        if len(parts) != 3:
            raise ProblemError("--spm", "", f"expected N or START:STOP:STEP, got {args.spm!r}")
        start, stop, step = (_spm_value(x) for x in parts)
        if stop < start:
            raise ProblemError("--spm", "", f"STOP {stop:g} is below START {start:g}")
        sweep = [start + k * step for k in range(int((stop - start) / step + 1e-9) + 1)]
        args.spm = None
    if args.objective is not None and args.objective not in OBJECTIVES:
        raise ProblemError("--objective", "", f"{args.objective!r} is not one of {', '.join(OBJECTIVES)}")
    if args.out is not None:
        check_out_dir(args.out)  # before the solve, not after it
    problem = _load(args)
    progress = None
    if not args.json:
        from tqdm import tqdm

        progress = lambda it, desc="solve": tqdm(it, desc=desc, unit="solve", file=sys.stderr, leave=False)  # noqa: E731
    if args.study == "mesh":
        rows = mesh_study(problem, objective=args.objective, progress=progress and (lambda it: progress(it, "mesh")))
        if args.json:
            _emit(to_json({"problem": problem.name, "spm": problem.spm, "study": "mesh", "rows": rows}))
        else:
            print(f"{problem.name} at {problem.spm:g} spm: the same design on each mesh (file's motor and pulley); "
                  f"error against the last (finest) mesh")
            print(format_table(rows, [("intervals", "intervals"), ("degree", "degree"), ("variables", "variables"),
                                      ("objective_value", "objective"), ("objective_error_pct", "error %"),
                                      ("violation_between_nodes", "violation between nodes"),
                                      ("time_s", "time s")]))
        _write_figure(lambda p: plot_mesh_study(rows, p), _plot_path(args, "mesh_study"), args)
        return 0
    if sweep is not None:
        rows = sweep_design(problem, sweep, objective=args.objective,
                         progress=progress and (lambda it: progress(it, "spm")))
        best = fastest_feasible(rows)
        at_end = best is not None and all(r["feasible"] for r in rows)  # the sweep found no limit
        if args.json:
            _emit(to_json({"problem": problem.name, "objective": args.objective or
                           (problem.design.objective if problem.design else None), "rows": rows,
                           "fastest_feasible_spm": best, "fastest_feasible_is_sweep_end": at_end}))
        else:
            print(format_table(rows, [("spm", "spm"), ("feasible", "feasible"), ("objective_value", "objective"),
                                      ("motor", "motor"), ("pulley_teeth", "z"), ("peak_torque_N_m", "peak N m"),
                                      ("rms_torque_N_m", "RMS N m"), ("solve_time_s", "time s"),
                                      ("reason", "why not")],
                               title=f"{problem.name}: optimal design over the stitch rate (warm-started)"))
            print("\nno feasible stitch rate in the sweep" if best is None else
                  f"\nfastest feasible stitch rate: >= {best:g} spm (the end of the sweep; every rate was feasible)"
                  if at_end else f"\nfastest feasible stitch rate: {best:g} spm")
        _write_figure(lambda p: plot_design_sweep(rows, p), _plot_path(args, "solve_sweep"), args)
        return 0
    design = solve_design(problem, objective=args.objective, verbose=args.verbose,
                          progress=progress and (lambda it: progress(it, "motors")))
    comparison = compare_with_laws(design)
    if args.json:
        _emit(to_json({**design_summary(design), "comparison": comparison}))
    else:
        print(design_text(design, comparison))
    if args.out is not None:
        written = design.write(args.out)
        law_stroke = problem.stroke(design.spm)
        fig_path = Path(args.out) / "stroke.png"
        _write_figure(lambda p: plot_kinematics(problem, [design.stroke, law_stroke], design.spm, p), fig_path, args)
        for path in written:
            print(f"written {path}", file=sys.stderr if args.json else sys.stdout)
    _write_figure(lambda p: plot_kinematics(problem, [design.stroke, problem.stroke(design.spm)], design.spm, p),
                  _plot_path(args, "solve"), args)
    if design.status == "limits exceeded":
        print(f"strokeopt: {design.notes[0]}", file=sys.stderr)
        return 1
    return 0


def _simulation_arguments(p) -> None:
    p.add_argument("--scene", help="scene of the problem file ([scenes.NAME]; default: release, else the first)")
    p.add_argument("--method", default="cvodes", choices=("cvodes", "idas"), help="SUNDIALS integrator (default cvodes)")
    p.add_argument("--rtol", type=float, default=1e-5, help="relative tolerance (default 1e-5: impact velocity to ~1e-4 m/s)")
    p.add_argument("--atol", type=float, default=1e-6,
                   help="absolute tolerance in scaled states: positions in mm, velocities in m/s (default 1e-6)")


# --------------------------------------------------------------------------- parser


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="strokeopt",
        description="Design servo-driven reciprocating mechanisms (electronic cams): motion laws, "
                    "kinematics, drive sizing, optimal strokes and contact-model verification.",
        epilog="Start with: strokeopt solve problems/deco2000_needle_bar.toml  "
               "(each command has --help with an example).",
    )
    sub = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")
    problem = _problem_parent()

    p = sub.add_parser("laws", help="table of the classic motion laws and their characteristic values",
                       description="The classic motion laws on a unit rise and their characteristic values "
                                   "C_v, C_a, C_j (computed from the laws, not typed in).",
                       epilog="Example: strokeopt laws --json")
    p.add_argument("--json", action="store_true", help="print only JSON on stdout")
    p.set_defaults(run=cmd_laws)

    p = sub.add_parser("kinematics", parents=[problem], help="peak speed, acceleration and jerk of each interval",
                       description="Kinematics of the problem's stroke: per interval the stroke, span, time, peak "
                                   "bar speed, acceleration and jerk, and peak pulley speed and acceleration; "
                                   "a figure of position, velocity, acceleration and jerk over the cam angle.",
                       epilog="Example: strokeopt kinematics problems/deco2000_needle_bar.toml --spm 600 --law poly5")
    _stroke_options(p)
    _plot_option(p, "kinematics")
    p.set_defaults(run=cmd_kinematics)

    p = sub.add_parser("size", parents=[problem], help="rank motors and pulleys: torque, RMS, speed, inertia, belt checks",
                       description="Drive sizing: every catalogue motor with every allowed pulley, over the whole "
                                   "cycle of the problem's stroke: peak torque against the motor's peak and the "
                                   "drive's peak limit (overload = peak / rated), RMS torque against the rated "
                                   "torque, peak speed against the rated speed, load/rotor inertia ratio, belt width "
                                   "and breaking checks (thesis appendix 2). The load is the [drive] section of the "
                                   "problem: moving mass, gravity, load forces.",
                       epilog="Example: strokeopt size problems/deco2000_needle_bar.toml --spm 600 --max-spm "
                              "--motor 055U2B30 --explain")
    _stroke_options(p)
    p.add_argument("--motor", action="append", metavar="NAME", help="only this catalogue motor (repeatable)")
    p.add_argument("--pulley-teeth", type=int, action="append", metavar="Z", help="only this pulley (repeatable)")
    p.add_argument("--catalogue", action="append", default=[], metavar="FILE",
                   help="an extra catalogue file (motors, pulleys, belts; repeatable)")
    p.add_argument("--max-spm", action="store_true",
                   help="also find each pair's highest stitch rate with every check passing (bisection, 1 spm)")
    p.add_argument("--continuous-radius", action="store_true",
                   help="also the pulley radius minimising each motor's peak torque (not rounded to teeth)")
    p.add_argument("--explain", action="store_true", help="torque breakdown at the peak and every check's margin")
    _plot_option(p, "sizing")
    p.set_defaults(run=cmd_size)

    p = sub.add_parser("solve", parents=[problem], help="optimal stroke, pulley and motor by direct collocation",
                       description="Solve the design problem of the file ([design], [drive]): the stroke of every move "
                                   "between its fixed dwells by direct collocation (IPOPT), with the pulley radius "
                                   "(continuous, then the nearest catalogue tooth counts) and the motor (enumerated "
                                   "or Bonmin) as decisions. Prints the motor, pulley, objective, every check with its "
                                   "margin, the active constraints and a comparison with the classic laws on the same "
                                   "drive. --spm START:STOP:STEP sweeps the stitch rate (warm-started) and prints the "
                                   "fastest feasible rate; --study mesh prints what accuracy costs in time. "
                                   "Objectives: min_peak_torque, min_rms_torque, min_energy, min_peak_accel, "
                                   "min_accel_squared, min_jerk, min_snap.",
                       epilog="Examples: strokeopt solve problems/deco2000_needle_bar.toml; "
                              "strokeopt solve problems/deco2000_needle_bar.toml --spm 600 --out out/; "
                              "strokeopt solve problems/deco2000_needle_bar.toml --spm 400:900:50; "
                              "strokeopt solve problems/known_optima/min_jerk.toml")
    p.add_argument("--objective", help="objective (overrides design.objective of the file)")
    _stroke_options(p, sweep=True, law=False)
    p.add_argument("--out", metavar="DIR", help="write design.json, cam_table.csv (0.1 deg) and stroke.png into DIR")
    p.add_argument("--study", choices=("mesh",), help="'mesh': objective error, violation between nodes and time "
                                                      "over mesh sizes and collocation degrees")
    p.add_argument("--plot", metavar="FILE", help=f"figure file (default {DEFAULT_OUT}/<problem>_solve.png; "
                                                  "'none' for no figure)")
    p.set_defaults(run=cmd_solve)

    p = sub.add_parser("bench", help="speed benchmarks, each against a reference measured in the same run",
                       description="Run the registered benchmarks (strokeopt/bench.py): each times a capability "
                                   "and a reference implementation side by side and prints the ratio and its target.",
                       epilog="Example: strokeopt bench --only size_catalogue")
    p.add_argument("--only", action="append", metavar="NAME", help="run only this benchmark (repeatable)")
    p.add_argument("--json", action="store_true", help="print only JSON on stdout")
    p.set_defaults(run=cmd_bench)

    p = sub.add_parser("simulate", parents=[problem],
                       help="contact model over one cycle: impact, lag, gap N, needle release (CasADi CVODES)",
                       description="Integrate a scene of the problem's contact model ([model], [scenes.NAME]) over one "
                                   "cam cycle with its driven body following the problem's stroke, from rest. Prints the "
                                   "impact velocity and angle of the control member on the stop, the lag behind the "
                                   "shell and when it ends, the smallest remaining gap N before the impact, the needle "
                                   "release angle and whether it was premature, peak pad, contact and drive forces. "
                                   "--spm START:STOP:STEP sweeps the speed; --study tolerance prints a work-precision "
                                   "table. Cam angles: 360 deg per cycle, 0 at the start of the first interval.",
                       epilog="Examples: strokeopt simulate problems/deco2000_needle_bar.toml --scene release --spm 600; "
                              "strokeopt simulate problems/deco2000_needle_bar.toml --spm 300:1200:20 --plot sweep.png; "
                              "strokeopt simulate problems/deco2000_needle_bar.toml --set "
                              "model.springs.k2.stiffness_N_m=1240 --set model.contacts.c32.gap_mm=6.5")
    _stroke_options(p, sweep=True)
    _simulation_arguments(p)
    p.add_argument("--study", choices=("tolerance",),
                   help="'tolerance': error of impact velocity and release angle against a tight reference vs CPU "
                        "time, over tolerances and smoothing widths")
    p.add_argument("--plot", metavar="FILE", help=f"figure file (default {DEFAULT_OUT}/<problem>_simulate_<scene>.png; "
                                                  "'none' for no figure)")
    p.set_defaults(run=cmd_simulate)

    p = sub.add_parser("verify", help="simulate a scene with the stroke of a design.json (written by the design solve)",
                       description="Re-simulate an optimised stroke: read DESIGN.json (its exact stroke, speed and "
                                   "problem file) and integrate a scene of the problem's contact model with it, "
                                   "reporting the same results as 'simulate'.",
                       epilog="Example: strokeopt solve problems/deco2000_needle_bar.toml --out out && "
                              "strokeopt verify out/design.json --scene release")
    p.add_argument("design", metavar="DESIGN.json", help="design file written by the design solve")
    p.add_argument("--problem", help="problem file (default: the problem_file recorded in DESIGN.json)")
    p.add_argument("--set", dest="overrides", action="append", default=[], metavar="KEY.PATH=VALUE",
                   help="override a value of the problem file (e.g. --set model.springs.k2.stiffness_N_m=1240)")
    p.add_argument("--json", action="store_true", help="print only JSON on stdout (for scripts)")
    p.add_argument("--verbose", action="store_true", help="print integrator output")
    _simulation_arguments(p)
    p.add_argument("--plot", metavar="FILE", help=f"figure file (default {DEFAULT_OUT}/<problem>_verify_<scene>.png; "
                                                  "'none' for no figure)")
    p.set_defaults(run=cmd_verify)

    p = sub.add_parser("accuracy", parents=[problem], help="handover accuracy: servo loop, belt stretch, encoder",
                       description="Predict how far the bar is from its commanded position at the handover and over "
                                   "the cycle, from the cascade position/speed loop of the servo drive (sampling, "
                                   "feed-forwards, gains by a stated rule, [servo]), the belt as a spring between "
                                   "motor and bar, and the encoder resolution; the error is split into servo "
                                   "tracking, belt stretch (inertia and load forces) and encoder quantisation. "
                                   "--compare-laws adds the handover error and the residual vibration of every "
                                   "classic law on the same drive.",
                       epilog="Example: strokeopt accuracy problems/deco2000_needle_bar.toml --spm 600 --compare-laws")
    _stroke_options(p)
    p.add_argument("--compare-laws", action="store_true",
                   help="also report handover error and residual vibration of every classic law")
    p.add_argument("--design", metavar="DESIGN_JSON",
                   help="predict for the optimal stroke of a design.json (strokeopt solve --out) on the motor and "
                        "pulley it was solved with, at its rate; the classic laws follow as a table")
    _plot_option(p, "accuracy")
    p.set_defaults(run=cmd_accuracy)

    p = sub.add_parser("tradeoff", parents=[problem], help="what accuracy costs: highest stitch rate per handover accuracy",
                       description="For required handover accuracies (default 0.02 to 1 mm) find the highest stitch "
                                   "rate at which the handover error (strokeopt accuracy) and every drive limit still "
                                   "hold, with the problem's classic law and, separately, with the optimal stroke "
                                   "(strokeopt solve with the accuracy constraint, on the problem's motor and pulley); "
                                   "each point names its binding limit. The optimal stroke needs one design solve "
                                   "per trial rate: it takes minutes.",
                       epilog="Example: strokeopt tradeoff problems/deco2000_needle_bar.toml --strokes classic "
                              "--accuracies 0.05,0.1,0.5")
    p.add_argument("--accuracies", metavar="MM,MM,...", help="required accuracies in mm (default 0.02,0.03,0.05,0.1,0.2,0.3,0.5,1)")
    p.add_argument("--strokes", choices=("both", "classic", "optimal"), default="both",
                   help="which strokes to compare (default both)")
    p.add_argument("--resolution", type=float, default=10.0, help="stitch-rate resolution of the search [spm] (default 10)")
    _plot_option(p, "tradeoff")
    p.set_defaults(run=cmd_tradeoff)
    return parser


def _check_plot_format(args) -> None:
    """A --plot file name matplotlib cannot write is bad input: say so before any work is done."""
    plot = getattr(args, "plot", None)
    if plot is None or plot.lower() == "none":
        return
    from matplotlib.backend_bases import FigureCanvasBase

    formats = FigureCanvasBase.get_supported_filetypes()
    suffix = Path(plot).suffix.lower().lstrip(".")
    if suffix not in formats:
        raise ProblemError("--plot", plot, f"cannot write a figure as {suffix or 'a file without extension'!r}; "
                                           f"use one of .{', .'.join(sorted(formats))}")


_JSON_OUT = None  # where --json output goes while solver logs are sent to stderr


def _emit(text: str) -> None:
    """Print the command's JSON (stdout, also when --verbose sends every log to stderr)."""
    print(text, file=_JSON_OUT or sys.stdout)


class _LogsToStderr:
    """With --json --verbose: every log (IPOPT and SUNDIALS through CasADi, which print via
    Python's sys.stdout or the C stdout) goes to stderr, so stdout carries only the JSON."""

    def __enter__(self):
        import os

        global _JSON_OUT
        sys.stdout.flush()
        self._saved_fd = os.dup(1)
        _JSON_OUT = os.fdopen(os.dup(self._saved_fd), "w")
        os.dup2(2, 1)
        self._saved_stdout = sys.stdout
        sys.stdout = sys.stderr
        return self

    def __exit__(self, *exc):
        import os

        global _JSON_OUT
        _JSON_OUT.flush()
        _JSON_OUT.close()
        _JSON_OUT = None
        sys.stdout = self._saved_stdout
        os.dup2(self._saved_fd, 1)
        os.close(self._saved_fd)
        return False


def main(argv: list[str] | None = None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    try:
        _check_plot_format(args)
        if getattr(args, "json", False) and getattr(args, "verbose", False):
            with _LogsToStderr():
                return args.run(args)
        return args.run(args)
    except ProblemError as exc:
        print(f"strokeopt: error: {exc}", file=sys.stderr)
        return 2
    except SolverError as exc:
        print(f"strokeopt: failed: {exc}", file=sys.stderr)
        return 1
    except StrokeoptError as exc:
        print(f"strokeopt: error: {exc}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print("strokeopt: interrupted", file=sys.stderr)
        return 130
    except BrokenPipeError:  # e.g. `strokeopt size ... | head`: the reader left, nothing to report
        import os

        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
        return 0


if __name__ == "__main__":
    sys.exit(main())
