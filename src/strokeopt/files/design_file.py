"""Design files: ``design.json``, ``cam_table.csv`` and ``cam_table.txt`` of a :class:`~strokeopt.design.result.Design`.

``design.json`` (written by :func:`write_design`, read by :func:`read_design` and :func:`load_design`,
and by ``strokeopt verify``, ``report --design`` and ``compare``)::

    {
      "format": "strokeopt-design", "schema_version": 2,
      "problem_file": "<absolute path>", "problem": "<name>",
      "spm": 600.0, "cycle_time_s": ..., "objective": "min_peak_torque",
      "objective_value": ..., "objective_unit": "N m",
      "status": "optimal", "motor": "<name or null>", "pulley_teeth": 28,
      "pulley_pitch_diameter_mm": ..., "mesh": {"intervals": 40, "degree": 3},
      "moves": [{"index": 1, "interval": 2, "name": ..., "t_start_s": ...,
                 "duration_s": ..., "start_position_mm": ..., "stroke_mm": (>= 0), "direction": "up"|"down",
                 "v_max_m_s": ..., "a_max_m_s2": ..., "jerk_max_m_s3": ...,
                 "C_a": ..., "unit_solution": {"S": [...], "V": [...], "A": [[...], ...]}}],
      "intervals": [{"index": 1, "name": ..., "kind": "dwell"|"move",
                     "t_start_s": ..., "duration_s": ..., "position_mm": ...}],
      "checks": [{"name": ..., "value": ..., "limit": ..., "unit": ..., "margin": ..., "ok": ...}],
      "active_constraints": [...], "solve_time_s": ...,
      "comparison": [...], "drive": {...},   (written by ``strokeopt solve --out``: as ``solve --json`` prints them)
      "cam_table": {"resolution_deg": 0.1, "master_unit": "deg", "master_counts": null,
                    "columns": ["cam_angle_deg", "position_mm", "velocity_m_s", "acceleration_m_s2",
                                "jerk_m_s3", "motor_angle_deg", "motor_speed_rpm", "motor_torque_N_m"],
                    "rows": [[...], ...]}
    }

``unit_solution`` is the collocation solution of a move in unit form
(``y = (s - start)/stroke`` over unit time; ``S``, ``V`` at the mesh interval
starts, ``A`` the node accelerations per interval): with ``mesh`` it rebuilds
the stroke exactly (:func:`read_design`). The cam table gives the motor angle
as ``position / pulley radius`` (0 at the handover position).
"""

from __future__ import annotations

import io
import json
import os
from dataclasses import dataclass
from typing import Any
from pathlib import Path

import numpy as np

from ..design.transcription.collocation import Mesh, MoveSolution, move_piece
from ..errors import ProblemError, SolverError
from ..problem import SPM_RANGE
from .design_schema import validate_reported
from .problem_file import load_problem
from ..io.fields import Fields
from ..io.load_units import from_load_units, load_key, to_load_units
from ..io.plain import to_json
from ..motion.stroke import StrokeFunction, dwell_piece


#: The master axis of the drive: 3600 positions per cam revolution (sources A.5: 0.1 deg).
MASTER_COUNTS = 3600


@dataclass(frozen=True)
class CamTableSpec:
    """How the cam table samples the cycle: every ``resolution_deg`` of the master axis (one cam cycle =
    360 deg), the master column in ``master_unit`` ``"deg"`` or ``"counts"`` (``master_counts`` per cycle)."""

    resolution_deg: float = 0.1
    master_unit: str = "deg"
    master_counts: int = MASTER_COUNTS

    @property
    def points(self) -> int:
        return int(round(360.0 / self.resolution_deg))

    @property
    def master_column(self) -> str:
        return "cam_angle_deg" if self.master_unit == "deg" else "master_counts"


#: The cam table's columns after the master column: (name, unit, what), the unit also in the name.
CAM_COLUMNS = [("position_mm", "mm", "bar position (problem frame, + up)"),
               ("velocity_m_s", "m/s", "bar velocity"), ("acceleration_m_s2", "m/s^2", "bar acceleration"),
               ("jerk_m_s3", "m/s^3", "bar jerk"),
               ("motor_angle_deg", "deg", "motor angle through the design's transmission (a pulley: position / pitch "
                                          "radius, 0 at 0 mm; a crank, screw or linkage: from its own zero)"),
               ("motor_speed_rpm", "rpm", "motor speed"),
               ("motor_torque_N_m", "N m", "motor torque on the design's motor and transmission (rigid load model)")]
#: A rotary load's (a sley on its shaft) in place of the first four (io/load_units.py).
CAM_COLUMNS_ROTARY = [("position_deg", "deg", "load angle (problem frame, + up)"),
                      ("velocity_rad_s", "rad/s", "load angular velocity"),
                      ("acceleration_rad_s2", "rad/s^2", "load angular acceleration"),
                      ("jerk_rad_s3", "rad/s^3", "load angular jerk")]
_CAM_FORMATS = {"cam_angle_deg": "%.4f", "master_counts": "%.0f", "position_mm": "%.6f", "velocity_m_s": "%.6f",
                "acceleration_m_s2": "%.4f", "jerk_m_s3": "%.2f", "motor_angle_deg": "%.5f",
                "motor_speed_rpm": "%.3f", "motor_torque_N_m": "%.5f", "position_deg": "%.6f",
                "velocity_rad_s": "%.6f", "acceleration_rad_s2": "%.4f", "jerk_rad_s3": "%.2f"}


def design_transmission(design):
    """The transmission a design's motor angle is read through: its pulley (radius), else the problem's own
    (a belt pulley of the problem's radius, or a screw and lever: no pulley to choose)."""
    from ..drive.transmission import BeltPulley

    if design.radius:
        return BeltPulley(2 * design.radius)
    return design.problem.transmission


def cam_table(design, resolution_deg: float = 0.1, spec: CamTableSpec | None = None) -> dict[str, np.ndarray]:
    """The stroke sampled at every ``resolution_deg`` of cam angle (the drive's master resolution), or as
    ``spec`` says (:class:`CamTableSpec`: resolution and master unit).

    Columns: the master (cam angle [deg] or master counts), then :data:`CAM_COLUMNS`: bar position [mm],
    velocity [m/s], acceleration [m/s^2], jerk [m/s^3], motor angle [deg] (position over the pulley
    radius; 0 at the 0 mm position), motor speed [rpm] and, with a motor, motor torque [N m].
    """
    from ..design.torque import design_torque

    spec = spec or CamTableSpec(resolution_deg)
    n = spec.points
    angle = np.arange(n) * (360.0 / n)
    t = angle / 360.0 * design.stroke.period
    k = design.stroke.evaluate(t)
    phi, omega, _ = design_transmission(design).motor_kinematics(k.s, k.v, k.a)
    master = angle if spec.master_unit == "deg" else np.arange(n) * (spec.master_counts / n)
    out = {spec.master_column: master, "position_mm": k.s * 1e3, "velocity_m_s": k.v,
           "acceleration_m_s2": k.a, "jerk_m_s3": k.j, "motor_angle_deg": np.degrees(phi),
           "motor_speed_rpm": omega * 60.0 / (2 * np.pi)}
    torque = design_torque(design, t=t)
    if torque is not None:
        out["motor_torque_N_m"] = torque[1].total
    for name, col in out.items():
        if not np.all(np.isfinite(col)):
            raise SolverError(f"cam table column {name} is not finite: refusing to write it")
    if design.problem.timing.rotary:  # a rotary load: its angle in deg, rad/s, rad/s^2, rad/s^3
        out = {load_key(name, True): col for name, col in out.items()}
        out["position_deg"] = np.degrees(k.s)
    return out


def cam_table_header(design, spec: CamTableSpec) -> list[str]:
    """The lines that state what a cam table is: problem, cycle, master axis, motor, pulley, units."""
    stitch = 60.0 / design.spm
    cycle = design.stroke.period
    trans = design_transmission(design)
    if hasattr(trans, "radius"):
        pulley = (f"{design.pulley_teeth}-tooth pulley" if design.pulley_teeth else "continuous pulley radius")
        pulley += f", pitch diameter {2 * trans.radius * 1e3:.4f} mm"
    else:
        pulley = f"none, the problem's {trans.name}"
    master = ("cam angle [deg], 0-360 per cam cycle" if spec.master_unit == "deg"
              else f"master counts, {spec.master_counts} per cam cycle")
    return [f"strokeopt cam table: {design.problem.name}, {design.objective} design at {design.spm:g} spm",
            f"cycle: one cam cycle = {cycle * 1e3:.4f} ms = {design.problem.cycle.count(f'{cycle / stitch:g}')} of "
            f"{stitch * 1e3:.4f} ms",
            f"master: {master}; {spec.points} points, one every {spec.resolution_deg:g} deg",
            f"motor: {design.motor or '(none)'}; pulley: {pulley}"]


#: The version of the design.json schema this strokeopt writes. 1: the first (its files carry ``"version": 1``
#: and no ``schema_version``; read as they are); 2: ``schema_version`` and the verdict of the verified
#: pipeline (``verdict``, ``not_judged``). A file of a newer schema is refused (upgrade strokeopt). A rotary load's
#: quantities are under their own keys, in deg and rad/s (``stroke_deg``, ``position_deg``, ``v_max_rad_s``, the cam
#: table's ``position_deg``: io/load_units.py); a rotary file written before them (mm-named keys holding rad x 1e3)
#: is read as it is.
SCHEMA_VERSION = 2


def schema_version(data: dict, file: str) -> int:
    """The schema version of the design data ``data`` read from ``file``, refused when it is not one this
    strokeopt reads."""
    version = data.get("schema_version", 1)  # none: the first schema (its files say "version": 1)
    if isinstance(version, bool) or not isinstance(version, int) or version < 1:
        raise ProblemError(file, "schema_version", f"must be a positive whole number, got {version!r}: is this a "
                                                   "design.json written by 'strokeopt solve --out DIR'?")
    if version > SCHEMA_VERSION:
        raise ProblemError(file, "schema_version", f"{version}: written by a newer strokeopt; this one reads design "
                                                   f"files up to schema {SCHEMA_VERSION} (pip install -U strokeopt, "
                                                   "or solve the problem again with this version)")
    return version


def design_json(design, resolution_deg: float = 0.1, spec: CamTableSpec | None = None,
                extra: dict | None = None) -> dict:
    """The data of ``design.json`` (see the module docstring); ``extra``: more fields of the solve's report
    (its ``comparison`` with the classic laws and the ``drive`` it used), stored as they are."""
    spec = spec or CamTableSpec(resolution_deg)
    sch = design.problem.timing.schedule(design.spm)
    out = {"format": "strokeopt-design", "schema_version": SCHEMA_VERSION, **design.summary(),
           "transmission": design.problem.transmission.name, **(extra or {})}
    out["moves"] = [{**m.to_dict(), "unit_solution": {"S": m.solution.S.tolist(), "V": m.solution.V.tolist(),
                                                      "A": m.solution.A.tolist()}} for m in design.moves]
    out["intervals"] = [{"index": itv.index, "name": itv.name, "kind": "move" if itv.is_move else "dwell",
                         "t_start_s": float(t0), "duration_s": float(dur), "position_mm": itv.start_position * 1e3}
                        for itv, t0, dur in zip(design.problem.timing.intervals, sch.t_start, sch.duration)]
    table = cam_table(design, spec=spec)
    cols = list(table)
    out["cam_table"] = {"resolution_deg": spec.resolution_deg, "master_unit": spec.master_unit,
                        "master_counts": spec.master_counts if spec.master_unit == "counts" else None,
                        "columns": cols, "rows": np.column_stack([table[c] for c in cols]).tolist()}
    return to_load_units(out, design.problem.timing.rotary)  # a rotary load: stroke_deg, v_max_rad_s, ...


def _cam_units(spec: CamTableSpec) -> dict:
    units = {name: unit for name, unit, _ in CAM_COLUMNS + CAM_COLUMNS_ROTARY}
    units[spec.master_column] = "deg" if spec.master_unit == "deg" else "counts"
    return units


def cam_table_csv(design, spec: CamTableSpec, table: dict | None = None) -> str:
    """The text of ``cam_table.csv``: ``#`` lines stating the cycle, the master axis, the motor, the pulley and
    every column's unit, the column names, then a row per master point."""
    table = table if table is not None else cam_table(design, spec=spec)
    units = _cam_units(spec)
    what = {name: text for name, _, text in CAM_COLUMNS + CAM_COLUMNS_ROTARY}
    what[spec.master_column] = "master axis"
    header = [f"# {line}" for line in cam_table_header(design, spec)]
    header += [f"# column {c} [{units[c]}]: {what[c]}" for c in table]
    buffer = io.StringIO()
    np.savetxt(buffer, np.column_stack(list(table.values())), delimiter=",",
               header="\n".join(header) + "\n" + ",".join(table), comments="",
               fmt=[_CAM_FORMATS[c] for c in table])
    return buffer.getvalue()


def write_cam_table(design, out_dir: str | Path, spec: CamTableSpec | None = None) -> list[Path]:
    """Write ``cam_table.csv`` (every column; ``#`` lines stating the cycle, the master axis, the motor,
    the pulley and every column's unit, then the column names) and ``cam_table.txt`` into ``out_dir``.

    ``cam_table.txt`` is the plain ASCII point table the Lenze Global Drive Cam Loader imports (a
    ``.txt`` file): one point per line, master position and slave position (the motor angle [deg]) in
    fixed-width columns separated by blanks, the master ascending, a comment only after the data
    behind ``//`` (the first line's says what the columns are).
    """
    spec = spec or CamTableSpec()
    out = Path(out_dir)
    table = cam_table(design, spec=spec)
    units = _cam_units(spec)
    p_csv = out / "cam_table.csv"
    p_csv.write_text(cam_table_csv(design, spec, table), encoding="utf-8")
    p_txt = out / "cam_table.txt"
    master, slave = table[spec.master_column], table["motor_angle_deg"]
    mfmt = "{:12.0f}" if spec.master_unit == "counts" else "{:12.4f}"
    lines = [f"{mfmt.format(m)} {s:14.5f}" for m, s in zip(master, slave)]
    lines[0] += (f" // strokeopt {design.problem.name} at {design.spm:g} spm: master {units[spec.master_column]}"
                 f" ({spec.points} points per cam cycle), slave motor angle deg")
    p_txt.write_text("\n".join(lines) + "\n", encoding="utf-8")
    return [p_csv, p_txt]


def write_design(design, out_dir: str | Path, resolution_deg: float = 0.1, spec: CamTableSpec | None = None,
                 extra: dict | None = None) -> list[Path]:
    """Write ``design.json`` and the cam table (:func:`write_cam_table`) into ``out_dir``; returns the paths."""
    spec = spec or CamTableSpec(resolution_deg)
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    data = design_json(design, spec=spec, extra=extra)
    p_json = out / "design.json"
    p_json.write_text(to_json(data) + "\n", encoding="utf-8")
    return [p_json, *write_cam_table(design, out, spec)]


def check_out_dir(path: str | Path, option: str = "--out") -> Path:
    """Check before a solve that ``path`` is a directory or can be created as one (:func:`write_design`).

    Raises :class:`ProblemError` naming ``option`` otherwise, so a long solve does not end on a bad path.
    """
    out = Path(path)
    if out.exists():
        if not out.is_dir():
            raise ProblemError(option, "", f"{str(path)!r} exists and is not a directory: give a directory "
                                           "(design.json and cam_table.csv are written into it)")
        if not os.access(out, os.W_OK):
            raise ProblemError(option, "", f"directory {str(path)!r} is not writable")
        return out
    parent = out.absolute().parent
    while not parent.exists():
        parent = parent.parent
    if not parent.is_dir():
        raise ProblemError(option, "", f"cannot create directory {str(path)!r}: {str(parent)!r} is not a directory")
    if not os.access(parent, os.W_OK):
        raise ProblemError(option, "", f"cannot create directory {str(path)!r}: {str(parent)!r} is not writable")
    return out


def validate_design(data: dict, file: str) -> None:
    """Check what :func:`read_design` rebuilds the stroke from, as a problem file is checked: every field
    present, of its type, finite and in range, every ``unit_solution`` of the mesh's shape; then the rest a
    command reads (design_schema.py: the moves' peaks, the checks, the drive, the comparison). Raises
    :class:`ProblemError` naming the file and the field (``moves[1].unit_solution.S``)."""
    top = Fields(data, file)
    mesh = top.table("mesh")
    n = mesh.number("intervals", integer=True, min=1, max=2000)  # the ranges of [design] (design/settings.py)
    d = mesh.number("degree", integer=True, min=1, max=9)
    moves = top.tables("moves")
    intervals = top.tables("intervals")
    if not intervals:
        raise top.error("intervals", "is empty: the design file is incomplete")
    move_of = {}
    for m in moves:
        move_of[m.number("interval", integer=True, min=1, max=len(intervals))] = m
        m.number("stroke_mm", min=0.0, max=1e5)  # the ranges of [timing] (io/problem_file.py)
        if m.has("direction"):
            m.string("direction", choices=("up", "down"))
        u = m.table("unit_solution")
        for key, shape in (("S", (n + 1,)), ("V", (n + 1,)), ("A", (n, d + 1))):
            _finite_array(u, key, shape)
    for k, itv in enumerate(intervals, 1):
        if itv.number("index", integer=True, min=1, max=len(intervals)) != k:
            raise itv.error("index", f"must be {k} (intervals in cycle order)")
        itv.string("name")
        kind = itv.string("kind", choices=("move", "dwell"))
        itv.number("t_start_s", min=0.0, max=3600.0)
        itv.number("duration_s", min=0.0, max=3600.0)
        itv.number("position_mm", min=-1e5, max=1e5)
        if kind == "move" and k not in move_of:
            raise itv.error("kind", f"interval {k} is a move, but no entry of moves has interval = {k}")
    top.number("spm", min=SPM_RANGE[0], max=SPM_RANGE[1])
    top.number("cycle_time_s", positive=True, max=3600.0)
    if data.get("pulley_teeth") is not None:
        top.number("pulley_teeth", integer=True, min=1, max=10**4)
    overrides = data.get("overrides", [])
    if not isinstance(overrides, list) or not all(isinstance(o, str) and "=" in o for o in overrides):
        raise top.error("overrides", "must be a list of the --set texts ('key.path=value') the design was solved "
                                     "with: the design file is damaged")
    validate_reported(top)  # the numbers, checks, drive and comparison every other command reads


def design_overrides(data: dict) -> list[str]:
    """The ``--set`` texts a design was solved with, less its stitch rate (the design's own ``spm`` rules)."""
    return [o for o in data.get("overrides", []) if o.split("=", 1)[0].strip() != "machine.spm"]


def _finite_array(f: Fields, key: str, shape: tuple[int, ...]) -> None:
    value = f.raw(key)
    try:
        arr = np.asarray(value, dtype=float)
    except (TypeError, ValueError):
        raise f.error(key, "must be an array of numbers (a rectangular one)") from None
    if arr.shape != shape:
        raise f.error(key, f"has shape {arr.shape}, the mesh needs {shape}: the design file is damaged "
                           "(write it again with strokeopt solve --out)")
    if not np.all(np.isfinite(arr)) or any(isinstance(v, bool) for v in np.ravel(np.asarray(value, dtype=object))):
        raise f.error(key, "must hold finite numbers only: the design file is damaged")


def read_design(path: str | Path) -> tuple[dict, StrokeFunction]:
    """Read a ``design.json``: its data and the exact optimal :class:`StrokeFunction` rebuilt from it."""
    path = Path(path)
    try:
        data = json.loads(path.read_text(encoding="utf-8"))
    except FileNotFoundError:
        raise ProblemError(str(path), "", "no such file") from None
    except (OSError, ValueError) as exc:
        if path.suffix.lower() == ".toml":
            raise ProblemError(str(path), "", "is a problem file; a design file is the design.json that "
                                              "'strokeopt solve PROBLEM --out DIR' writes (DIR/design.json)") from None
        if isinstance(exc, json.JSONDecodeError):
            raise ProblemError(str(path), "", f"is not JSON ({exc.msg.lower()} at line {exc.lineno}, column "
                                              f"{exc.colno}): a design file is the design.json 'strokeopt solve "
                                              "PROBLEM --out DIR' writes") from None
        raise ProblemError(str(path), "", f"is not a readable design file: {exc}") from None
    if not isinstance(data, dict) or data.get("format") != "strokeopt-design":
        raise ProblemError(str(path), "format", "is not a strokeopt design file (format != 'strokeopt-design')")
    schema_version(data, str(path))
    data = from_load_units(data)  # a rotary load's stroke_deg, position_deg, ... read as the linear keys
    validate_design(data, str(path))
    try:
        mesh = Mesh(int(data["mesh"]["intervals"]), int(data["mesh"]["degree"]))
        moves = {m["interval"]: m for m in data["moves"]}
        pieces = []
        for itv in data["intervals"]:
            t0, dur, pos = itv["t_start_s"], itv["duration_s"], itv["position_mm"] * 1e-3
            if itv["kind"] == "move":
                m = moves[itv["index"]]
                u = m["unit_solution"]
                sol = MoveSolution(mesh, np.asarray(u["S"], float), np.asarray(u["V"], float), np.asarray(u["A"], float))
                sign = {"up": 1.0, "down": -1.0, None: 1.0}[m.get("direction")]  # older files: stroke_mm signed
                pieces.append(move_piece(t0, dur, pos, sign * m["stroke_mm"] * 1e-3, sol, f"{itv['name']}: optimal"))
            else:
                pieces.append(dwell_piece(t0, dur, pos, itv["name"]))
        stroke = StrokeFunction(float(data["cycle_time_s"]), pieces, label="optimal")
    except KeyError as exc:
        raise ProblemError(str(path), str(exc.args[0]), "is missing: the design file is incomplete (write it "
                                                        "again with strokeopt solve --out)") from None
    except (TypeError, ValueError) as exc:
        raise ProblemError(str(path), "", f"design file is malformed: {exc}") from None
    return data, stroke


@dataclass(frozen=True)
class DesignStroke:
    """What verification needs of a design: its problem, its stroke and the stitch rate it was solved at.

    ``source``: the design file it was read from; ``objective``: the objective it was solved for.
    A solve's ``Design`` has the same ``problem``, ``stroke`` and ``spm``.
    """

    problem: Any
    stroke: Any
    spm: float
    source: str = ""
    objective: str | None = None


def load_design(path, problem_file=None, overrides=()) -> DesignStroke:
    """Read a ``design.json`` and the problem it was solved for, at the design's stitch rate.

    ``problem_file`` replaces the file the design names (a relative name the design names is
    also looked for next to the design file); ``overrides`` are ``--set`` texts for it.
    """
    data, stroke = read_design(path)
    file = design_problem_file(path, data, problem_file)
    # the design's rate, not an override the user typed: the problem's --set list stays the design's own
    problem = load_problem(file, [*design_overrides(data), *overrides]).with_spm(float(data["spm"]))
    check_design_fits(data, problem, str(path))
    return DesignStroke(problem, stroke, problem.spm, str(path), data.get("objective"))


def check_design_fits(data: dict, problem, file: str) -> None:
    """A design is refused on a problem it was not solved for: another transmission, or a timing whose
    intervals (kind, start position, duration at the design's rate) differ from the design's -- its stroke
    would be read on the wrong machine. Names the first difference."""
    kind = data.get("transmission")
    if kind is not None and kind != problem.transmission.name:
        raise ProblemError(file, "transmission", f"the design was solved for a {kind} transmission; "
                                                 f"{problem.file} has a {problem.transmission.name}: a design of "
                                                 "another problem")
    if data.get("pulley_teeth") is not None and problem.transmission.name != "belt_pulley":
        raise ProblemError(file, "pulley_teeth", f"{data['pulley_teeth']} teeth, but {problem.file} has a "
                                                 f"{problem.transmission.label}, no pulley: the design file is damaged or "
                                                 "of another problem")
    rows = data.get("intervals", [])
    sch = problem.timing.schedule(float(data["spm"]))
    if len(rows) != len(problem.timing.intervals):
        raise ProblemError(file, "intervals", f"the design has {len(rows)} intervals, {problem.file} has "
                                              f"{len(problem.timing.intervals)}: a design of another problem")
    for row, itv, dur in zip(rows, problem.timing.intervals, sch.duration):
        where = f"intervals[{itv.index}]"
        if row["kind"] != ("move" if itv.is_move else "dwell"):
            raise ProblemError(file, where, f"is a {row['kind']} in the design, a {'move' if itv.is_move else 'dwell'} "
                                            f"in {problem.file}: a design of another problem")
        if abs(row["position_mm"] - itv.start_position * 1e3) > POSITION_TOLERANCE_MM:
            raise ProblemError(file, where, f"starts at {row['position_mm']:g} mm in the design, at "
                                            f"{itv.start_position * 1e3:g} mm in {problem.file}: a design of another "
                                            "problem (or of an edited stroke: solve it again)")
        move = next((m for m in data.get("moves", []) if m.get("interval") == itv.index), None)
        if itv.is_move and move is not None and "direction" in move:
            stroke = (1 if move["direction"] == "up" else -1) * move["stroke_mm"] * 1e-3
            if abs(stroke - itv.stroke) > POSITION_TOLERANCE_MM * 1e-3:
                raise ProblemError(file, f"moves[{move.get('index')}]", f"moves {move['stroke_mm']:g} mm "
                                   f"{move['direction']} in the design, {abs(itv.stroke) * 1e3:g} mm "
                                   f"{'up' if itv.stroke > 0 else 'down'} in {problem.file}: the stroke does not "
                                   "join its dwells (solve it again)")
        if abs(row["duration_s"] - dur) > 1e-9 * max(1.0, dur):
            raise ProblemError(file, where, f"lasts {row['duration_s'] * 1e3:.6g} ms in the design, "
                                            f"{dur * 1e3:.6g} ms in {problem.file} at {data['spm']:g} spm: a design "
                                            "of another timing (solve it again)")


#: How far a design's interval position may lie from its problem's [mm] (a number written and read back).
POSITION_TOLERANCE_MM = 1e-6


def design_problem_file(path, data: dict, problem_file=None) -> Path:
    """The problem file of the design ``data`` read from ``path``: ``problem_file`` if given, else the
    one the design names (a relative name also looked for next to the design file)."""
    problem_file = problem_file or data.get("problem_file")
    if not problem_file:
        raise ProblemError(str(path), "problem_file", "is missing: pass --problem FILE")
    file = Path(problem_file)
    if not file.is_absolute() and not file.exists() and (Path(path).parent / file).exists():
        file = Path(path).parent / file
    if not file.exists() and problem_file == data.get("problem_file"):
        raise ProblemError(str(path), "problem_file", f"names {str(file)!r}, which does not exist here (a design "
                                                      "moved from another machine?): pass --problem FILE")
    return file
