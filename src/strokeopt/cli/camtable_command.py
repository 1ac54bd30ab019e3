"""``strokeopt camtable DESIGN.json --format FMT --out FILE [--check]``: a verified design as the cam table a
controller loads (files/cam_formats.py), and the check that what the controller interpolates between the
points is the stroke that was verified."""

from __future__ import annotations

import sys
from dataclasses import replace
from pathlib import Path

from ..errors import ProblemError
from .common import _emit, _load, _probe_dir


def _design(args):
    from ..design.result import design_from_data
    from ..files.design_file import design_problem_file, read_design

    args.design = args.file
    args.problem = str(design_problem_file(args.design, read_design(args.design)[0], args.problem))
    problem = _load(args)
    return design_from_data(problem, args.design_data, args.design_stroke)


def _tolerance(args, rotary: bool) -> float:
    """The position tolerance in the load's SI unit (m, or rad for a rotary load)."""
    import math

    from ..files.cam_formats import DEFAULT_TOLERANCE

    value = DEFAULT_TOLERANCE if args.tolerance is None else args.tolerance
    if not math.isfinite(value) or value <= 0:
        raise ProblemError("--tolerance", "", f"must be a positive number ({'deg' if rotary else 'mm'}), got {value!r}")
    return math.radians(value) if rotary else value * 1e-3


def cmd_camtable(args) -> int:
    from ..files import cam_formats as cf
    from ..files.design_file import CamTableSpec, cam_table_header
    from ..io.plain import to_json

    if args.points is not None and args.points not in cf.POINT_CHOICES:
        raise ProblemError("--points", "", f"{args.points} is not one of {', '.join(map(str, cf.POINT_CHOICES))} (a "
                                           "divisor of 36000: every point on a 0.01 deg master position)")
    out = Path(args.out_file)
    if out.is_dir():
        raise ProblemError("--out", "", f"{str(out)!r} is a directory: give the table's file name, such as "
                                        f"{str(out / ('cam_' + args.format + '.csv'))!r}")
    _probe_dir(out.absolute().parent, "--out", "the cam table")
    design = _design(args)
    rotary = design.problem.timing.rotary
    unit, scale = ("mdeg", 180e3 / 3.141592653589793) if rotary else ("um", 1e6)
    tol = _tolerance(args, rotary)
    needed = cf.points_needed(design, args.format, tol)
    n = args.points or needed
    if n is None:
        raise ProblemError("--tolerance", "", f"{tol * scale:g} {unit} is not met by a "
                                              f"{args.format} table of up to {cf.POINT_CHOICES[-1]} points")
    header = cam_table_header(design, CamTableSpec(360.0 / n))
    try:
        cf.write_table(design, args.format, n, out, header)
    except OSError as exc:
        raise ProblemError("--out", "", f"cannot write {str(out)!r}: {exc.strerror or exc}") from None
    interpolation = cf.FORMATS[args.format][0]
    report = {"status": "ok", "design": str(args.file), "format": args.format, "file": str(out), "points": n,
              "step_deg": 360.0 / n, "interpolation": interpolation, f"tolerance_{unit}": tol * scale,
              "points_needed": needed}
    code = 0
    if args.check:
        table = cf.read_segments(out, args.format)  # the file as written, read back as its controller reads it
        dev = cf.deviation(design, table)
        report["check"] = {"position_motor_deg": dev.position_deg, f"position_load_{unit}": dev.position_load * scale,
                           "velocity_motor_rpm": dev.velocity_rpm, "acceleration_motor_rad_s2": dev.acceleration_rad_s2,
                           "acceleration_share_of_peak": dev.acceleration_share,
                           "within_tolerance": bool(dev.position_load <= tol)}
        from ..studies.verified import verify_design

        stroke = cf.segment_stroke(design, table, f"{args.format} cam table, {n} points")
        from ..design.compare import stroke_drive_checks
        from ..design.transcription.limits import ENFORCED_CHECKS

        # a linear table has no acceleration between its points: its torques would be the load's without inertia
        rigid = (stroke_drive_checks(design, stroke) or []) if interpolation != "linear" else []
        report["drive_checks"] = [{"name": c.name, "value": c.value, "design_value": design.check_value(c.name),
                                   "limit": c.limit, "unit": c.unit, "ok": c.ok}
                                  for c in rigid if c.name in ENFORCED_CHECKS]
        verified = verify_design(replace(design, stroke=stroke))
        row = next((c for c in verified.design.checks if c["name"].startswith("handover accuracy")), None)
        report["resimulated"] = {"verdict": verified.verdict, "status": verified.status, "ok": verified.ok,
                                 "handover_error": None if row is None else row["value"],
                                 "handover_unit": None if row is None else row["unit"]}
        if not report["check"]["within_tolerance"] or not verified.ok or not all(c["ok"] for c in report["drive_checks"]):
            report["status"] = "check failed"
            code = 1
    if args.json:
        _emit(to_json(report))
    else:
        _print(report, args, unit)
    if code:
        print(f"strokeopt: the cam table's check failed ({out})", file=sys.stderr)
    return code


def _print(report: dict, args, unit: str) -> None:
    n = report["points"]
    print(f"cam table {report['format']} of {args.file}: {n} points a cam cycle (one every {report['step_deg']:g} deg), "
          f"{report['interpolation']} interpolation between them")
    needed = report["points_needed"]
    print(f"points needed for {report[f'tolerance_{unit}']:g} {unit}: {needed if needed else 'more than the most'}")
    print(f"written {report['file']}")
    check = report.get("check")
    if check:
        ok = "within" if check["within_tolerance"] else "NOT within"
        print(f"check (the file read back and interpolated as its controller does, against the verified stroke):\n"
              f"  position      {check['position_motor_deg']:.3g} deg motor = {check[f'position_load_{unit}']:.3g} "
              f"{unit} load ({ok} {report[f'tolerance_{unit}']:g} {unit})\n"
              f"  velocity      {check['velocity_motor_rpm']:.3g} rpm motor\n"
              f"  acceleration  {check['acceleration_motor_rad_s2']:.4g} rad/s^2 motor "
              f"({100 * check['acceleration_share_of_peak']:.3g} % of the peak)")
        rows = report["drive_checks"]
        if report["interpolation"] == "linear":
            print("the drive's limits: judged on the design, not on a linear table (no acceleration between points)")
        elif rows:
            print("the drive's limits with the table's stroke: " + "; ".join(
                f"{c['name']} {c['value']:.4g} (design {_g(c['design_value'])}) of {c['limit']:.4g} {c['unit']} "
                f"{'ok' if c['ok'] else 'EXCEEDED'}"
                for c in rows))
        print(f"re-simulated with the table's stroke: {report['resimulated']['verdict']}")


def _g(value) -> str:
    return "-" if value is None else f"{value:.4g}"
