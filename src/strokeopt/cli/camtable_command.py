"""``strokeopt camtable DESIGN.json --format FMT --out FILE [--check]``: a verified design as the cam table a
controller loads (files/cam_formats.py), and the check that what the controller interpolates between the
points is the stroke that was verified."""

from __future__ import annotations

import math
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
    from ..files.cam_formats import DEFAULT_TOLERANCE

    value = DEFAULT_TOLERANCE if args.tolerance is None else args.tolerance
    if not math.isfinite(value) or value <= 0:
        raise ProblemError("--tolerance", "", f"must be a positive number ({'deg' if rotary else 'mm'}), got {value!r}")
    return math.radians(value) if rotary else value * 1e-3


def _target(args) -> tuple[Path, bool]:
    """The table file and whether it is written (``--out``) or an existing one checked (``--check-file``)."""
    if (args.out_file is None) == (args.check_file is None):
        raise ProblemError("--out", "", "give --out FILE (write a table) or --check-file FILE (check a table that "
                                        "exists, e.g. one edited by hand), one of them")
    if args.check_file is not None:
        path = Path(args.check_file)
        if not path.is_file():
            raise ProblemError(str(path), "", "no such file (--check-file: a cam table to check)")
        return path, False
    out = Path(args.out_file)
    if out.is_dir():
        raise ProblemError("--out", "", f"{str(out)!r} is a directory: give the table's file name, such as "
                                        f"{str(out / ('cam_' + args.format + '.csv'))!r}")
    if out.exists() and out.resolve() == Path(args.file).resolve():
        raise ProblemError("--out", "", f"{str(out)!r} is the design file itself: give the table another name")
    if out.exists() and not _is_cam_table(out):
        raise ProblemError("--out", "", f"{str(out)!r} exists and is not a cam table strokeopt wrote: give another "
                                        "name, or remove it first (a table is only written over a table)")
    _probe_dir(out.absolute().parent, "--out", "the cam table")
    return out, True


def _is_cam_table(path: Path) -> bool:
    try:
        with path.open(encoding="utf-8") as handle:
            return handle.readline().startswith("# strokeopt cam table")
    except (OSError, UnicodeDecodeError):
        return False


def cmd_camtable(args) -> int:
    from ..design.compare import stroke_drive_checks
    from ..design.transcription.limits import ENFORCED_CHECKS
    from ..files import cam_formats as cf
    from ..files.design_file import CamTableSpec, cam_table_header
    from ..io.plain import to_json
    from ..studies.verified import verify_design

    if args.points is not None and args.points not in cf.POINT_CHOICES:
        raise ProblemError("--points", "", f"{args.points} is not one of the table sizes "
                                           f"{', '.join(map(str, cf.POINT_CHOICES))}: from 36 to 36000 segments "
                                           "a cam cycle, dividing 36000 (every point on a 0.01 deg master position)")
    path, write = _target(args)
    design = _design(args)
    rotary = design.problem.timing.rotary
    unit, scale = ("mdeg", math.degrees(1.0) * 1e3) if rotary else ("um", 1e6)
    tol = _tolerance(args, rotary)
    needed = cf.points_needed(design, args.format, tol)
    if write:
        n = args.points or needed
        if n is None:
            raise ProblemError("--tolerance", "", f"{tol * scale:g} {unit} is not met by a "
                                                  f"{args.format} table of up to {cf.POINT_CHOICES[-1]} segments")
        try:
            cf.write_table(design, args.format, n, path, cam_table_header(design, CamTableSpec(360.0 / n)))
        except OSError as exc:
            raise ProblemError("--out", "", f"cannot write {str(path)!r}: {exc.strerror or exc}") from None
        table = cf.read_segments(path, args.format) if args.check else None  # read back as its controller reads it
    else:
        table = cf.read_segments(path, args.format)
        n = table.n
    interpolation = cf.FORMATS[args.format][0]
    report = {"status": "ok", "design": str(args.file), "format": args.format, "file": str(path),
              "written": write, "points": n, "rows": n + 1 if args.format in ("xyva", "poly5") else n,
              "step_deg": 360.0 / n, "interpolation": interpolation, f"tolerance_{unit}": tol * scale,
              "points_needed": needed}
    code = 0
    if table is not None:
        dev = cf.deviation(design, table)
        report["check"] = {"position_motor_deg": dev.position_deg, f"position_load_{unit}": dev.position_load * scale,
                           "velocity_motor_rpm": dev.velocity_rpm, "acceleration_motor_rad_s2": dev.acceleration_rad_s2,
                           "acceleration_share_of_peak": dev.acceleration_share,
                           "within_tolerance": bool(dev.position_load <= tol)}
        stroke = cf.segment_stroke(design, table, f"{args.format} cam table, {n} points")
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
        print(f"strokeopt: the cam table's check failed ({path}): {_failure(report, unit)}", file=sys.stderr)
    return code


def _failure(report: dict, unit: str) -> str:
    """What failed, with the numbers: the position deviation, a drive limit, the re-simulated verdict."""
    check, why = report["check"], []
    if not check["within_tolerance"]:
        why.append(f"position {check[f'position_load_{unit}']:.3g} {unit} over the tolerance "
                   f"{report[f'tolerance_{unit}']:g} {unit}")
    why += [f"{c['name']} {c['value']:.4g} over {c['limit']:.4g} {c['unit']}" for c in report["drive_checks"]
            if not c["ok"]]
    if not report["resimulated"]["ok"]:
        why.append(report["resimulated"]["verdict"])
    return "; ".join(why)


def _print(report: dict, args, unit: str) -> None:
    n = report["points"]
    closing = " (the last closing the cycle at 360 deg)" if report["rows"] > n else ""
    print(f"cam table {report['format']} of {args.file}: {n} segments a cam cycle (one every {report['step_deg']:g} "
          f"deg), {report['rows']} rows{closing}, {report['interpolation']} interpolation between the points")
    needed = report["points_needed"]
    print(f"segments needed for {report[f'tolerance_{unit}']:g} {unit}: {needed if needed else 'more than 36000'}")
    print(f"{'written' if report['written'] else 'checked'} {report['file']}")
    check = report.get("check")
    if check:
        ok = "within" if check["within_tolerance"] else "NOT within"
        linear = (" -- a linear table has none between its points; the drive differentiates its steps"
                  if report["interpolation"] == "linear" else "")
        print(f"check (the file read back and interpolated as its controller does, against the verified stroke):\n"
              f"  position      {check['position_motor_deg']:.3g} deg motor = {check[f'position_load_{unit}']:.3g} "
              f"{unit} load ({ok} {report[f'tolerance_{unit}']:g} {unit})\n"
              f"  velocity      {check['velocity_motor_rpm']:.3g} rpm motor\n"
              f"  acceleration  {check['acceleration_motor_rad_s2']:.4g} rad/s^2 motor "
              f"({100 * check['acceleration_share_of_peak']:.3g} % of the peak{linear})")
        rows = report["drive_checks"]
        if report["interpolation"] == "linear":
            print("the drive's limits: judged on the design, not on a linear table (no acceleration between points)")
        elif rows:
            print("the drive's limits with the table's stroke (design's in brackets): " + "; ".join(
                f"{c['name']} {c['value']:.4g} ({_g(c['design_value'])}) of {c['limit']:.4g}"
                f"{'' if c['unit'] == '-' else ' ' + c['unit']} {'ok' if c['ok'] else 'EXCEEDED'}" for c in rows))
        print(f"re-simulated with the table's stroke: {report['resimulated']['verdict']}")


def _g(value) -> str:
    return "-" if value is None else f"{value:.4g}"
