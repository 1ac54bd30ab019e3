"""The result of the design: :class:`Design` (the optimal stroke, the parts, the checks) and
:class:`MoveResult` per move.

Last step of the design's flow (:mod:`.solve` makes them). Files: :mod:`strokeopt.files.design_file`
(design.json, cam table: ``write_design``); text: :mod:`strokeopt.report.design`.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from .transcription.collocation import Mesh, MoveSolution, fine_grid, move_piece
from ..drive.selection import resolve_drive
from ..io.load_units import from_load_units, to_load_units
from ..motion.stroke import StrokeFunction, dwell_piece

if TYPE_CHECKING:
    from .transcription.request import Move


def stroke_from_solutions(problem, spm: float, solutions: list[MoveSolution], label: str = "optimal") -> StrokeFunction:
    """The whole cycle's stroke: the dwells and the solved moves (exact collocation polynomials)."""
    sch = problem.timing.schedule(spm)
    pieces = []
    it = iter(solutions)
    for itv, t0, dur in zip(problem.timing.intervals, sch.t_start, sch.duration):
        if itv.is_move:
            pieces.append(move_piece(t0, dur, itv.start_position, itv.stroke, next(it), f"{itv.name}: {label}"))
        else:
            pieces.append(dwell_piece(t0, dur, itv.start_position, itv.name))
    return StrokeFunction(sch.period, pieces, label=label)


def move_direction(stroke: float) -> str:
    """``up`` or ``down``: the convention of :func:`strokeopt.report.kinematics_summary` (stroke_mm >= 0)."""
    return "up" if stroke > 0 else "down"


@dataclass(frozen=True)
class MoveResult:
    """One optimised move: SI peaks and the unit-form collocation solution."""

    index: int
    interval: int
    name: str
    t_start: float
    duration: float
    start: float
    stroke: float
    solution: MoveSolution
    v_max: float
    a_max: float
    jerk_max: float
    C_a: float  # peak |y''| on the unit move (the acceleration coefficient)

    def to_dict(self) -> dict:
        return {
            "index": self.index, "interval": self.interval, "name": self.name,
            "t_start_s": self.t_start, "duration_s": self.duration,
            "start_position_mm": self.start * 1e3, "stroke_mm": abs(self.stroke) * 1e3,
            "direction": move_direction(self.stroke),
            "v_max_m_s": self.v_max, "a_max_m_s2": self.a_max, "jerk_max_m_s3": self.jerk_max, "C_a": self.C_a,
        }


def move_results(moves: list[Move], sols: list[MoveSolution], per_interval: int = 50) -> list[MoveResult]:
    """Peaks of each move from its polynomials on a fine grid (exact polynomials, numpy)."""
    out = []
    for mv, sol in zip(moves, sols):
        tau = fine_grid(sol.mesh, per_interval)
        _, y1, y2, y3, _ = sol.evaluate(tau)
        # the jerk is one-sided at the mesh joints: include the left side too
        tn = np.arange(1, sol.mesh.intervals) * sol.mesh.h
        y3_left = sol.evaluate(tn - 1e-9 * sol.mesh.h)[3] if len(tn) else np.zeros(0)
        j_max = float(max(np.max(np.abs(y3)), np.max(np.abs(y3_left), initial=0.0)))
        c_a = float(np.max(np.abs(y2)))
        out.append(MoveResult(mv.index, mv.interval, mv.name, mv.t_start, mv.duration, mv.start, mv.stroke, sol,
                              float(np.max(np.abs(y1))) * mv.v_scale, c_a * mv.a_scale, j_max * mv.j_scale, c_a))
    return out


@dataclass(frozen=True)
class Design:
    """An optimised stroke with its choices and its constraint report. Immutable: a judged design is a new
    one (``dataclasses.replace``: :func:`strokeopt.studies.verified.verify_design` adds the verification)."""

    problem: Any
    spm: float
    objective: str
    objective_value: float
    objective_unit: str
    stroke: StrokeFunction
    moves: list[MoveResult]
    mesh: Mesh
    status: str
    solve_time_s: float
    iterations: int
    checks: list[dict] = field(default_factory=list)
    active_constraints: list[str] = field(default_factory=list)
    fine_grid: dict = field(default_factory=dict)
    notes: list[str] = field(default_factory=list)
    #: the resolved drive (drive/selection.py): motor, transmission with its pulley, belt, limits -- the
    #: catalogue entries the design was solved with, handed on (nothing looks them up by name again); the
    #: design's motor, pulley and pitch diameter are its (None without a [drive])
    drive: Any = field(default=None, repr=False)
    settings: Any = field(default=None, repr=False)  # the DesignSettings it was solved with
    #: the handover accuracy was held in its solve (a min_time warm-started from it holds it from the start)
    accuracy_enforced: bool = field(default=False, repr=False)
    #: the design re-simulated in its contact model and judged (contact/verify.py ``design_verification``), or None
    verification: dict | None = None
    #: the free model parameters found ([design.free], design/free.py): one row each
    free_parameters: list = field(default_factory=list)

    def __repr__(self) -> str:  # a line, not pages of collocation coefficients
        parts = [f"{self.objective} {self.objective_value:.6g} {self.objective_unit}", f"{self.spm:g} spm",
                 f"{len(self.moves)} moves", f"mesh {self.mesh.intervals}x{self.mesh.degree}"]
        if self.motor:
            parts.append(f"motor {self.motor}")
        if self.pulley_teeth:
            parts.append(f"pulley {self.pulley_teeth} teeth")
        return f"Design({self.status}: {', '.join(parts)})"

    @property
    def motor(self) -> str | None:
        """The name of the design's motor (its resolved drive's)."""
        return None if self.drive is None else self.drive.motor

    @property
    def pulley_teeth(self) -> int | None:
        """The tooth count of the design's pulley; None for a continuous radius or another transmission."""
        return None if self.drive is None else self.drive.pulley_teeth

    @property
    def pitch_diameter(self) -> float | None:
        """The pitch diameter [m] of the design's pulley (a catalogue pulley's or the continuous one)."""
        radius = None if self.drive is None else self.drive.radius
        return None if radius is None else 2 * radius

    @property
    def motor_spec(self):
        """The design's motor or stepper (the catalogue entry of the resolved drive), None without a drive."""
        return None if self.drive is None else self.drive.actuator

    @property
    def solutions(self) -> list[MoveSolution]:
        return [m.solution for m in self.moves]

    @property
    def radius(self) -> float | None:
        return None if self.pitch_diameter is None else self.pitch_diameter / 2

    def summary(self) -> dict:
        """The JSON report of ``strokeopt solve`` (without the cam table)."""
        return to_load_units({
            "status": self.status,
            "problem": self.problem.name,
            "problem_file": str(Path(self.problem.file).resolve()),
            "overrides": list(getattr(self.problem, "overrides", ())),  # the --set texts it was solved with
            "objective": self.objective,
            "objective_value": self.objective_value,
            "objective_unit": self.objective_unit,
            "spm": self.spm,
            "cycle_time_s": self.stroke.period,
            "motor": self.motor,
            "pulley_teeth": self.pulley_teeth,
            "pulley_pitch_diameter_mm": None if self.pitch_diameter is None else self.pitch_diameter * 1e3,
            "mesh": {"intervals": self.mesh.intervals, "degree": self.mesh.degree},
            "moves": [m.to_dict() for m in self.moves],
            "checks": self.checks,
            "active_constraints": self.active_constraints,
            "fine_grid": self.fine_grid,
            "solve_time_s": self.solve_time_s,
            "iterations": self.iterations,
            "notes": self.notes,
            **({"verification": self.verification} if self.verification is not None else {}),
            **({"free_parameters": self.free_parameters} if self.free_parameters else {}),
        }, _rotary(self.problem))

    def check_value(self, name: str) -> float | None:
        """The value of the check ``name`` (``peak_torque``, ``rms_torque``...), None when not checked."""
        return next((c["value"] for c in self.checks if c["name"] == name), None)


def design_summary(design: Design) -> dict:
    """The JSON report of ``strokeopt solve``: the fields scripts rely on, then the details."""
    checks = {c["name"]: c for c in design.checks}
    out = {
        "status": design.status,
        "objective": design.objective,
        "objective_value": design.objective_value,
        "objective_unit": design.objective_unit,
        "motor": design.motor,
        "pulley_teeth": design.pulley_teeth,
        "spm": design.spm,
        "peak_torque_N_m": checks["peak_torque"]["value"] if "peak_torque" in checks else None,
        "rms_torque_N_m": checks["rms_torque"]["value"] if "rms_torque" in checks else None,
        "moves": [{"index": m.index, "v_max_m_s": m.v_max, "a_max_m_s2": m.a_max, "jerk_max_m_s3": m.jerk_max,
                   "C_a": m.C_a, "duration_s": m.duration, "stroke_mm": abs(m.stroke) * 1e3,
                   "direction": move_direction(m.stroke)} for m in design.moves],
        "active_constraints": design.active_constraints,
        "solve_time_s": design.solve_time_s,
    }
    if "peak_torque" in checks:  # min(motor peak, drive peak limit x rated): the limit of every command
        out["torque_limit_N_m"] = checks["peak_torque"]["limit"]
    full = design.summary()
    for key in ("problem", "problem_file", "cycle_time_s", "pulley_pitch_diameter_mm", "mesh", "checks",
                "iterations", "notes"):
        out[key] = full[key]
    if design.verification is not None:
        out["verification"] = design.verification
    if design.free_parameters:
        out["free_parameters"] = design.free_parameters
    return to_load_units(out, _rotary(design.problem))   # a rotary load's keys in deg, rad/s (io/load_units.py)


def _rotary(problem) -> bool:
    return bool(getattr(getattr(problem, "timing", None), "rotary", False))


def design_from_data(problem, data: dict, stroke: StrokeFunction) -> Design:
    """The :class:`Design` a ``design.json`` holds (``data`` and ``stroke`` as
    :func:`strokeopt.files.design_file.read_design` returns them), on ``problem`` (the problem it was
    solved for, at its stitch rate): its numbers are the file's, its motor the catalogue's."""
    data = from_load_units(data)  # a rotary load's keys (stroke_deg, v_max_rad_s, ...) as the linear ones
    mesh = Mesh(int(data["mesh"]["intervals"]), int(data["mesh"]["degree"]))
    moves = []
    for m in data["moves"]:
        u = m["unit_solution"]
        sign = -1.0 if m.get("direction") == "down" else 1.0
        solution = MoveSolution(mesh, *(np.asarray(u[k], float) for k in ("S", "V", "A")))
        moves.append(MoveResult(m["index"], m["interval"], m["name"], m["t_start_s"], m["duration_s"],
                                m["start_position_mm"] * 1e-3, sign * m["stroke_mm"] * 1e-3, solution,
                                m["v_max_m_s"], m["a_max_m_s2"], m["jerk_max_m_s3"], m["C_a"]))
    pd = data.get("pulley_pitch_diameter_mm")
    settings = getattr(problem, "design", None)
    drive = None
    if data.get("motor") is not None and getattr(problem, "drive", None) is not None:  # the file's names, resolved once
        drive = resolve_drive(problem, motor=data["motor"], pulley_teeth=data.get("pulley_teeth"),
                              pitch_diameter=None if pd is None else pd * 1e-3,
                              include_pulley_inertia=getattr(settings, "include_pulley_inertia", True))
    return Design(problem, float(data["spm"]), data["objective"], data["objective_value"], data["objective_unit"],
                  stroke, moves, mesh, data["status"], data["solve_time_s"], data.get("iterations", 0),
                  checks=list(data.get("checks", [])), active_constraints=list(data.get("active_constraints", [])),
                  fine_grid=dict(data.get("fine_grid", {})), notes=list(data.get("notes", [])), drive=drive,
                  settings=settings)
