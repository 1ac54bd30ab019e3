"""``strokeopt linkage PROBLEM``: a crank-driven planar linkage analysed (structure, kinematics, transmission,
crank torque) or, with ``--synthesize``, synthesised against the file's ``[synthesis]`` table."""

from __future__ import annotations

import math
import sys
import time

from .common import _emit, _plot_path, _write_figure


def add_linkage_parser(sub, problem_parent) -> None:
    """Register ``linkage`` on the sub-parsers ``sub`` (problem_parent: PROBLEM, --set, --json)."""
    from .common import DEFAULT_OUT

    p = sub.add_parser("linkage", parents=[problem_parent],
                       help="planar linkage: structure, kinematics, transmission, crank torque; --synthesize",
                       description="Analyse the crank-driven planar linkage of a linkage problem file "
                                   "([transmission] type = \"linkage\"): Gruebler mobility, loops, Grashof class of "
                                   "each four-bar loop, the groups solved together; every output's position, speed, "
                                   "acceleration and jerk over the crank angle at the file's rpm (exact: Newton "
                                   "continuation, derivatives by AD), its swing, near-dwells (within near_dwell_pct "
                                   "of the swing of an extreme), rise/fall asymmetry; the transmission index of "
                                   "every group against the file's limit (Alt's angle for a dyad); with masses or "
                                   "loads, the crank torque by the power balance checked by Newton-Euler. "
                                   "--synthesize: link lengths and free pivots fitted to the [synthesis] table "
                                   "(IPOPT, simultaneous form, seeded random starts), with the runners-up. "
                                   "Exit 1 (status 'limits exceeded' or 'targets missed') when the transmission "
                                   "index falls below its limit or a synthesis misses its RMS acceptance.",
                       epilog="Examples: strokeopt linkage problems/loom_beatup_sixbar.toml; "
                              "strokeopt linkage problems/blind_stitch_needle.toml --synthesize --json")
    p.add_argument("--synthesize", action="store_true",
                   help="fit the linkage to the file's [synthesis] targets (the file's geometry is replaced)")
    p.add_argument("--seed", type=int, help="random seed of the synthesis (default: synthesis.seed of the file)")
    p.add_argument("--starts", type=int, help="starts the synthesis solves (default: synthesis.starts)")
    p.add_argument("--plot", metavar="FILE",
                   help=f"figure file (default {DEFAULT_OUT}/<problem>_linkage.png; none with --json unless "
                        "--plot asks; 'none' for no figure)")
    p.set_defaults(run=cmd_linkage)


def cmd_linkage(args) -> int:
    from ..errors import ProblemError
    from ..linkage.files import load_linkage_file
    from ..report.format import to_json

    if args.synthesize:
        return _synthesize(args)
    for flag, value in (("--seed", args.seed), ("--starts", args.starts)):
        if value is not None:
            raise ProblemError(flag, "", "sets the synthesis: give it with --synthesize")
    problem = load_linkage_file(args.problem, args.overrides)
    from ..linkage.summary import summarize

    summary = summarize(problem)
    if args.json:
        _emit(to_json(summary))
    else:
        from ..report.linkage import linkage_text

        print(linkage_text(summary))
    _figure(args, problem, summary, "linkage")
    return _analysis_exit(summary)


def _figure(args, problem, summary, command: str, linkage=None, tags=()) -> None:
    from ..linkage.kinematics import kinematics_of
    from ..report.linkage import plot_linkage

    lk = linkage or problem.linkage
    kin = kinematics_of(lk)
    cycle = kin.solve(problem.angles)
    targets = None
    syn = problem.synthesis
    if syn.get("output") == summary["outputs"][0]["name"] and "angles_deg" in syn:
        t0 = math.degrees(lk.crank.reference_angle)
        targets = ([(a - t0) % 360 for a in syn["angles_deg"]], syn["speeds_m_s"])
    _write_figure(lambda p: plot_linkage(kin, cycle, summary, p, targets), _plot_path(args, command, *tags), args)


def _analysis_exit(summary: dict) -> int:
    from ..report.linkage import analysis_failure

    failure = analysis_failure(summary)
    if failure:
        print(f"strokeopt: {failure}", file=sys.stderr)
    return 1 if failure else 0


def _synthesize(args) -> int:
    from ..errors import ProblemError
    from ..linkage.kinematics import Kinematics
    from ..linkage.files import load_linkage_file
    from ..linkage.summary import summarize
    from ..linkage.synthesis import synthesize
    from ..report.format import to_json
    from ..report.linkage import synthesis_text

    # the ranges of the file's synthesis.starts and synthesis.seed (linkage/targets.py)
    if args.starts is not None and not 1 <= args.starts <= 200:
        raise ProblemError("--starts", "", f"{args.starts}: the synthesis solves 1 to 200 starts")
    if args.seed is not None and not 0 <= args.seed <= 2**31:
        raise ProblemError("--seed", "", f"{args.seed}: a seed is 0 to 2^31")
    problem = load_linkage_file(args.problem, args.overrides, check_cycle=False)
    if not problem.synthesis:
        raise ProblemError(args.problem, "synthesis", "--synthesize needs a [synthesis] section (targets, bounds)")
    result = synthesize(problem, starts=args.starts, seed=args.seed)
    rms_max = float(problem.synthesis.get("rms_max_m_s", math.inf))
    report = result.to_dict(Kinematics(problem.linkage))
    report = {"status": "ok" if report["best"]["rms_m_s"] <= rms_max else "targets missed", **report}
    problem.linkage = problem.linkage.with_reference(result.best.coords)
    summary = summarize(problem)
    report["analysis"] = summary
    if args.json:
        _emit(to_json(report))
    else:
        print(synthesis_text(report, rms_max))
        from ..report.linkage import linkage_text

        print("\nthe best linkage:\n" + linkage_text(summary))
    _figure(args, problem, summary, "linkage_synthesis")
    if report["status"] != "ok":
        print(f"strokeopt: the best fit, RMS {report['best']['rms_m_s']:.4f} m/s, misses the acceptance "
              f"{rms_max:g} m/s", file=sys.stderr)
        return 1
    return 0


def stated_report(args, problem, out) -> int:
    """``strokeopt report`` of a problem that states its motion and nothing to design (no ``[design]``) where its
    transmission has an analysis of its own (a linkage's crank at constant speed): the linkage's structure,
    kinematics, transmission quality, crank torque and the drive ``size`` chooses (and, ``--servo SERVO.toml``,
    the linkage against a servo driving its output) as one HTML page."""
    from datetime import datetime, timezone

    from ..errors import ProblemError
    from ..linkage.dynamics import analyse_dynamics
    from ..linkage.kinematics import kinematics_of
    from ..report.design_report import versions
    from ..report.format import to_json
    from ..report.linkage_report import LinkageReportData, linkage_report
    from .commands import size_report

    for attr, option in (("objective", "--objective"), ("scene", "--scene"), ("design", "--design")):
        if getattr(args, attr, None):
            raise ProblemError(option, "", f"{args.problem} states its motion and no [design]: {option} does not "
                                           "apply to its report (omit it)")
    t0 = time.perf_counter()
    linkage = problem.transmission.at_constant_speed(problem)
    servo = _servo_comparison(args, linkage)   # the bad input of --servo before the page is drawn
    kin = kinematics_of(linkage.linkage)
    cycle = kin.solve(linkage.angles)
    if problem.drive is None:
        raise ProblemError(args.problem, "drive", "the report sizes a motor for the crank: the problem has no [drive]")
    _, size = size_report(args, problem, problem.drive.catalogue(getattr(args, "catalogue", None) or ()))
    data = LinkageReportData(problem.transmission.analysis(problem), size, kin, cycle,
                             analyse_dynamics(kin, cycle, linkage.omega), servo, args.servo or "",
                             list(args.overrides), versions(), datetime.now(timezone.utc).strftime("%Y-%m-%d %H:%M UTC"))
    text = linkage_report(data)
    out.write_text(text, encoding="utf-8")
    info = {"status": "ok", "report": str(out), "size_bytes": len(text.encode("utf-8")),
            "build_time_s": time.perf_counter() - t0, "servo": args.servo}
    if args.json:
        _emit(to_json(info))
    else:
        print(f"written {out} ({info['size_bytes'] / 1024:.0f} KB, built in {info['build_time_s']:.2f} s"
              + (f"; against the servo of {args.servo}" if args.servo else "") + ")")
    return 0


def _servo_comparison(args, linkage):
    """``--servo SERVO.toml``: the linkage against its output on a servo (studies/linkage_servo.py), or None."""
    if not getattr(args, "servo", None):
        return None
    from ..files.problem_file import load_problem
    from ..studies.linkage_servo import compare_linkage_servo

    return compare_linkage_servo(linkage, load_problem(args.servo))
