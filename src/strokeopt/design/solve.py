"""Optimal stroke design by direct collocation.

:func:`solve_design` states the design problem of a :class:`~strokeopt.problem.Problem`
at one stitch rate as one NLP and solves it with IPOPT (through CasADi):

* every move between its fixed dwells is a collocated trajectory (states
  position, velocity, acceleration; control jerk; see :mod:`strokeopt.collocation`),
  rest to rest at the dwell boundaries, the handover position met exactly
  (the move ends at its dwell position, which is a bound, not a penalty);
* the NLP is stated in scaled units (unit stroke, unit time per move, torques
  relative to a reference torque, the radius relative to the catalogue range's geometric mean),
  so the answer does not depend on the units the user wrote;
* objectives (``[design] objective`` or ``--objective``): see :data:`OBJECTIVES`;
* path constraints are imposed at the collocation nodes and checked on a fine
  grid between them (:attr:`Design.fine_grid`); where the fine grid shows a
  violation beyond ``check_tolerance`` the mesh is doubled and the problem
  re-solved (``refinements`` times at most).

The result is a :class:`Design`: a :class:`~strokeopt.stroke.StrokeFunction`
(one piece per dwell and per move; a move piece reproduces the collocation
polynomials exactly), the choices (pulley, motor), the objective, and a
constraint report. A problem that cannot be solved raises
:class:`~strokeopt.errors.SolverError` naming the constraint and by how much.

``design.json`` (written by :meth:`Design.write`, read by :func:`read_design`
and by ``strokeopt verify``)::

    {
      "format": "strokeopt-design", "version": 1,
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
      "cam_table": {"resolution_deg": 0.1, "columns": ["cam_angle_deg", "position_mm",
                    "velocity_m_s", "acceleration_m_s2", "motor_angle_deg"], "rows": [[...], ...]}
    }

``unit_solution`` is the collocation solution of a move in unit form
(``y = (s - start)/stroke`` over unit time; ``S``, ``V`` at the mesh interval
starts, ``A`` the node accelerations per interval): with ``mesh`` it rebuilds
the stroke exactly (:func:`read_design`). The cam table gives the motor angle
as ``position / pulley radius`` (0 at the handover position).
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any

import casadi as ca
import numpy as np

from .collocation import Mesh, MoveSolution, MoveVariables, fine_grid, node_times
from ..errors import ProblemError, SolverError
from ..motion.laws import make_law
from ..motion.stroke import Piece, StrokeFunction, dwell_piece
from ..drive.transmission import BeltPulley, Transmission

#: Objectives that need only the kinematics.
KINEMATIC_OBJECTIVES = ("min_peak_accel", "min_accel_squared", "min_jerk", "min_snap")
#: Objectives that need the drive's load torque.
TORQUE_OBJECTIVES = ("min_peak_torque", "min_rms_torque", "min_energy")
#: Every objective, with what it minimises.
OBJECTIVES = {
    "min_peak_torque": "peak |motor torque| over the cycle (epigraph form)",
    "min_rms_torque": "RMS motor torque over the cycle",
    "min_energy": "copper losses over one cycle (integral of torque squared over the moves)",
    "min_peak_accel": "peak |acceleration| of the driven member over all moves (epigraph form)",
    "min_accel_squared": "integral of acceleration squared over the moves",
    "min_jerk": "integral of jerk squared over the moves",
    "min_snap": "integral of snap (4th derivative) squared over the moves",
}
MOTOR_CHOICES = ("fixed", "enumerate", "bonmin")
PULLEY_CHOICES = ("fixed", "optimise", "continuous")

#: Default IPOPT options (plain dict, passed through to CasADi's nlpsol).
DEFAULT_SOLVER_OPTIONS = {
    "expand": True,
    "print_time": False,
    "ipopt.print_level": 0,
    "ipopt.sb": "yes",
    "ipopt.tol": 1e-9,
    # Feasible designs converge in 20-40 iterations (every solve of the test suite and the reference
    # sweep: 36 at most); an infeasible motor of a catalogue search ran to any limit given (500:
    # 7 s) before the relaxed diagnosis names its limit. Raise it in [design.solver].
    "ipopt.max_iter": 200,
}

_STATUS_OK = ("Solve_Succeeded", "Solved_To_Acceptable_Level")


# --------------------------------------------------------------------------- settings


@dataclass(frozen=True)
class DesignSettings:
    """The ``[design]`` section of a problem file (SI units inside).

    ``rest_order``: derivatives that vanish at the ends of every move
    (1: velocity; 2: velocity and acceleration, the default for a servo
    following a cam table; 3: also jerk, with the jerk continuous inside the move).
    ``jerk_max``: bound on |jerk| [m/s^3] (None: unbounded);
    ``jerk_max_from_law``: bound each move by the peak jerk of the file's
    motion law on that move instead. ``accuracy``: allowed position error at
    the handover [m]. ``check_points``: fine-grid points per mesh interval;
    ``check_tolerance``: relative violation between nodes that triggers a
    mesh refinement (at most ``refinements`` doublings).
    """

    objective: str = "min_peak_torque"
    mesh_intervals: int = 40
    collocation_degree: int = 3
    rest_order: int = 2
    jerk_max: float | None = None
    jerk_max_from_law: bool = False
    accuracy: float = 0.5e-3
    motor_choice: str = "fixed"
    pulley: str = "fixed"
    pulley_teeth_min: int | None = None
    pulley_teeth_max: int | None = None
    check_points: int = 20
    check_tolerance: float = 0.005
    refinements: int = 2
    include_pulley_inertia: bool = True
    solver_options: dict = field(default_factory=dict)

    @property
    def mesh(self) -> Mesh:
        return Mesh(self.mesh_intervals, self.collocation_degree)


def parse_design(f, *, file: str = "") -> DesignSettings:
    """Read the ``[design]`` table with the :class:`~strokeopt.problem.Fields` reader (unknown keys are errors)."""
    if f is None:
        return DesignSettings()
    objective = f.string("objective", "min_peak_torque", choices=tuple(OBJECTIVES))
    n = f.number("mesh_intervals", 40, integer=True, min=1, max=2000)
    d = f.number("collocation_degree", 3, integer=True, min=1, max=9)
    rest = f.number("rest_order", 2, integer=True, min=1, max=3)
    jerk = f.number("jerk_max_m_s3", None, positive=True)
    from_law = f.boolean("jerk_max_from_law", False)
    if from_law and jerk is not None:
        raise f.error("jerk_max_from_law", "give either jerk_max_m_s3 or jerk_max_from_law = true, not both")
    if rest == 3 and d < 2:
        raise f.error("collocation_degree", "rest_order = 3 (jerk continuous) needs collocation_degree >= 2")
    if objective == "min_snap" and d < 2:
        raise f.error("collocation_degree", "min_snap needs collocation_degree >= 2 (snap of the acceleration polynomial)")
    accuracy = f.number("handover_accuracy_mm", 0.5, positive=True) * 1e-3
    motor_choice = f.string("motor_choice", "fixed", choices=MOTOR_CHOICES)
    pulley = f.string("pulley", "fixed", choices=PULLEY_CHOICES)
    zmin = f.number("pulley_teeth_min", None, integer=True, min=8)
    zmax = f.number("pulley_teeth_max", None, integer=True, min=8)
    if zmin is not None and zmax is not None and zmax < zmin:
        raise f.error("pulley_teeth_max", f"must be at least pulley_teeth_min = {zmin}, got {zmax}")
    check_points = f.number("check_points", 20, integer=True, min=2, max=1000)
    check_tol = f.number("check_tolerance", 0.005, positive=True)
    refinements = f.number("refinements", 2, integer=True, min=0, max=6)
    pulley_inertia = f.boolean("include_pulley_inertia", True)
    solver = f.table("solver", required=False)
    options = {}
    if solver is not None:
        for key in list(solver.data):
            value = solver.raw(key)
            if not isinstance(value, (int, float, str, bool)):
                raise solver.error(key, f"solver options must be numbers, strings or booleans, got {value!r}")
            options[key] = value
        solver.finish()
    f.finish()
    return DesignSettings(objective, n, d, rest, jerk, from_law, accuracy, motor_choice, pulley, zmin, zmax,
                          check_points, check_tol, refinements, pulley_inertia, options)


# --------------------------------------------------------------------------- the NLP


@dataclass(frozen=True)
class _Move:
    index: int  # 1-based among moves
    interval: int  # 1-based interval index
    name: str
    t_start: float
    duration: float
    start: float  # position [m]
    stroke: float  # signed [m]
    jerk_bound: float | None  # [m/s^3]

    @property
    def v_scale(self) -> float:
        return abs(self.stroke) / self.duration

    @property
    def a_scale(self) -> float:
        return abs(self.stroke) / self.duration**2

    @property
    def j_scale(self) -> float:
        return abs(self.stroke) / self.duration**3


def _moves(problem, spm: float, settings: DesignSettings) -> list[_Move]:
    sch = problem.timing.schedule(spm)
    out = []
    for itv, t0, dur in zip(problem.timing.intervals, sch.t_start, sch.duration):
        if not itv.is_move:
            continue
        if not dur > 0:
            raise ProblemError(str(problem.file), f"timing.intervals[{itv.index}].span_deg",
                               f"move {itv.move_index} ({itv.name!r}) has no time (span 0 deg) for a stroke of "
                               f"{abs(itv.stroke) * 1e3:g} mm")
        bound = settings.jerk_max
        if settings.jerk_max_from_law:
            c_j = itv.law.characteristics.C_j
            if math.isinf(c_j):
                raise ProblemError(str(problem.file), "design.jerk_max_from_law",
                                   f"the motion law {itv.law.label} of move {itv.move_index} has unbounded jerk; "
                                   "give jerk_max_m_s3 instead")
            bound = c_j * abs(itv.stroke) / dur**3
        out.append(_Move(itv.move_index, itv.index, itv.name,
                         float(t0), float(dur), itv.start_position, itv.stroke, bound))
    return out


@dataclass(frozen=True)
class _Limit:
    """A group of inequality constraints ``expr <= 0`` (scaled) with what it means in SI.

    ``need(sigma)`` turns a relaxation ``expr <= sigma`` back into the SI value
    the design would need; ``limit`` is the SI limit, ``what`` names it.
    """

    name: str
    what: str
    limit: float
    unit: str
    need: Any
    move: int | None = None
    check: str = ""  # the name of the same limit in the checks table (drive.py's names), for short messages
    #: False, or a function of the solve's context returning False: the rows exist (one NLP
    #: structure for every solve) but their bound is infinite
    enforced: Any = True

    @property
    def short(self) -> str:
        return self.check or self.what

    def is_enforced(self, ctx) -> bool:
        return bool(self.enforced(ctx) if callable(self.enforced) else self.enforced)


def _number(value, ctx) -> np.ndarray:
    """A bound, start value or parameter of the NLP: a number, or a function of the solve's context."""
    return np.asarray(value(ctx) if callable(value) else value, dtype=float)


@dataclass
class _Numbers:
    """What one solve gives a built NLP: parameter values, start point and bounds."""

    p: np.ndarray
    x0: np.ndarray
    lbx: np.ndarray
    ubx: np.ndarray
    lbg: np.ndarray
    ubg: np.ndarray


@dataclass
class _Built:
    """Symbols of one NLP structure, and how each solve's numbers are found.

    The symbolic NLP (and its solver, with the costly derivatives) is built once per
    structure (:func:`_structure_key`); everything that changes between solves of
    one structure (speed, motor, pulley, pinned points, warm start) is a parameter
    value, a bound or a start value, each given as a function of the solve's
    :class:`_Context` and evaluated by :meth:`numbers`.
    """

    relaxed: bool = False
    w: list = field(default_factory=list)
    vars: list = field(default_factory=list)  # (shape, lb, ub, x0): numbers or functions of the context
    g: list = field(default_factory=list)
    cons: list = field(default_factory=list)  # (size, lb, ub)
    limits: list = field(default_factory=list)  # (_Limit, slack symbol or None)
    limit_exprs: list = field(default_factory=list)  # the scaled expressions (<= 0) of the limit groups
    offsets: dict = field(default_factory=dict)  # variable name -> (offset, size) in the decision vector
    p: list = field(default_factory=list)  # parameters: numbers that change between solves of one structure
    p_values: list = field(default_factory=list)  # (function of the context, shape)
    n_w: int = 0
    n_g: int = 0

    def param(self, name: str, value) -> ca.MX:
        """A number the NLP takes as a parameter, ``value(ctx)`` for each solve: one built solver serves many."""
        return self.params(name, value, (1, 1))

    def params(self, name: str, value, shape: tuple[int, int]) -> ca.MX:
        """A matrix of parameters of ``shape``, ``value(ctx)`` for each solve."""
        if not callable(value):
            raise TypeError(f"parameter {name!r}: give a function of the solve's context, not a number "
                            f"(a number would be frozen into the built solver)")
        sym = ca.MX.sym(name, shape[0] * shape[1])
        self.p.append(sym)
        self.p_values.append((value, shape))
        return ca.reshape(sym, *shape)

    def var(self, name: str, shape, lb, ub, x0) -> ca.MX:
        """A matrix symbol; ``lb``, ``ub``, ``x0`` are scalars or arrays of ``shape``, or functions of the context."""
        x = ca.MX.sym(name, *shape)
        self.w.append(ca.vec(x))
        self.offsets[name] = (self.n_w, shape[0] * shape[1])
        self.n_w += shape[0] * shape[1]
        self.vars.append((tuple(shape), lb, ub, x0))
        return x

    def constrain(self, name: str, expr, lb, ub) -> None:
        """Rows ``lb <= expr <= ub``; the bounds are numbers or functions of the context."""
        expr = ca.vec(expr)
        n = expr.shape[0]
        if n == 0:
            return
        self.g.append(expr)
        self.cons.append((n, lb, ub))
        self.n_g += n

    def numbers(self, ctx) -> _Numbers:
        """Parameter values, start point and bounds of one solve."""
        pv = []
        for (fn, shape), sym in zip(self.p_values, self.p):
            val = _number(fn, ctx)
            if val.size != sym.numel():
                raise ValueError(f"parameter {sym.name()} has {val.size} values, built with {sym.numel()}")
            pv.append(val.reshape(shape).ravel(order="F") if val.ndim == 2 else val.ravel())
        xs = ([], [], [])
        for shape, *vals in self.vars:
            for store, val in zip(xs, vals):
                arr = _number(val, ctx)
                arr = np.broadcast_to(arr.reshape(shape) if arr.size == shape[0] * shape[1] else arr, shape)
                store.append(arr.ravel(order="F"))  # ca.vec is column-major
        gs = ([], [])
        for n, *vals in self.cons:
            for store, val in zip(gs, vals):
                store.append(np.broadcast_to(_number(val, ctx), (n,)))
        cat = (lambda parts: np.concatenate(parts) if parts else np.zeros(0))
        return _Numbers(cat(pv), cat(xs[2]), cat(xs[0]), cat(xs[1]), cat(gs[0]), cat(gs[1]))

    def limit_abs(self, lim: _Limit, expr) -> None:
        """``|expr| <= 1`` (scaled) as one two-sided row each; relaxed: ``|expr| <= 1 + sigma``."""
        expr = ca.vec(expr)
        self.limit_exprs.append(ca.fabs(expr) - 1.0)
        if not self.relaxed:
            self.constrain(lim.name, expr, -1.0, 1.0)
            self.limits.append((lim, None))
            return
        slack = self.var(f"slack {lim.name}", (1, 1), 0.0, np.inf, 0.0)
        self.constrain(lim.name, expr - slack, -np.inf, 1.0)
        self.constrain(lim.name, expr + slack, -1.0, np.inf)
        self.limits.append((lim, slack))

    def limit(self, lim: _Limit, expr) -> None:
        """``expr <= 0`` (scaled); in a relaxed build ``expr <= sigma``, ``sigma >= 0`` minimised."""
        slack = None
        self.limit_exprs.append(ca.vec(expr))
        if self.relaxed:
            slack = self.var(f"slack {lim.name}", (1, 1), 0.0, np.inf, 0.0)
            expr = expr - slack
        self.constrain(lim.name, expr, -np.inf, lambda c: 0.0 if lim.is_enforced(c) else np.inf)
        self.limits.append((lim, slack))


def _initial_unit(mesh: Mesh, rest_order: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """A feasible-shaped initial guess: the 3-4-5 polynomial (4-5-6-7 for rest_order 3)."""
    law = make_law("poly7" if rest_order >= 3 else "poly5")
    h = mesh.h
    starts = np.arange(mesh.intervals + 1) * h
    y, y1 = law.derivatives(starts, order=1)
    t_nodes = (np.arange(mesh.intervals).reshape(-1, 1) + mesh.nodes.reshape(1, -1)) * h
    a = law.derivatives(t_nodes.ravel(), order=2)[2].reshape(t_nodes.shape)
    return y, y1, a


@dataclass(frozen=True)
class DriveChoice:
    """The parts of one solve: a motor (or the candidates of a Bonmin choice) and a pulley.

    ``teeth`` None means a continuous pulley radius between ``radius_bounds``.
    """

    motor: Any = None  # ServoMotor
    teeth: int | None = None
    radius_bounds: tuple[float, float] | None = None
    candidates: tuple = ()  # motors for the Bonmin choice

    @property
    def label(self) -> str:
        parts = []
        if self.motor is not None:
            parts.append(self.motor.name)
        if self.candidates:
            parts.append("one of " + ", ".join(m.name for m in self.candidates))
        parts.append(f"{self.teeth} teeth" if self.teeth else "continuous radius")
        return ", ".join(parts)


class _DriveSetup:
    """What the NLP needs of ``problem.drive``: catalogue, load, limits, belt."""

    def __init__(self, problem, settings: DesignSettings):
        spec = problem.drive
        self.problem = problem
        self.spec = spec
        self.file = str(problem.file)
        self.catalogue = spec.catalogue()
        self.load = spec.load
        self.limits = spec.limits
        self.belt = spec.belt_spec(self.catalogue)
        self.profile = spec.profile
        self.settings = settings
        zmin = settings.pulley_teeth_min if settings.pulley_teeth_min is not None else spec.teeth_min
        zmax = settings.pulley_teeth_max if settings.pulley_teeth_max is not None else spec.teeth_max
        self.teeth_range = (zmin, zmax)
        if zmax < zmin:
            raise ProblemError(self.file, "design.pulley_teeth_max", f"{zmax} is below pulley_teeth_min {zmin}")
        #: torque scale of the NLP [N m]: the largest peak torque in the catalogue
        self.tau_ref = max([m.peak_torque for m in self.catalogue.motors.values()] or [1.0])

    def pulley(self, teeth: int):
        found = self.catalogue.pulleys_of(self.profile, teeth, teeth)
        if not found:
            from ..drive.catalogue import Pulley
            from ..drive.transmission import pitch_diameter

            pd = pitch_diameter(self.profile, teeth)
            return Pulley(f"{self.profile}-{teeth}", self.profile, teeth, pd,
                          float(self.catalogue.pulley_inertia(self.profile, pd)), "model")
        return found[0]

    def pulley_inertia(self, pitch_diameter):
        if not self.settings.include_pulley_inertia:
            return 0.0
        return self.catalogue.pulley_inertia(self.profile, pitch_diameter)

    def motors(self) -> list:
        return list(self.catalogue.motors.values())

    def fixed_motor(self):
        if self.spec.motor is None:
            raise ProblemError(self.file, "drive.motor", "is needed with design.motor_choice = \"fixed\" "
                                                         "(or choose: motor_choice = \"enumerate\" or \"bonmin\")")
        return self.catalogue.motor(self.spec.motor, (self.file, "drive.motor"))

    def radius_bounds(self) -> tuple[float, float]:
        from ..drive.transmission import pitch_diameter

        return pitch_diameter(self.profile, self.teeth_range[0]) / 2, pitch_diameter(self.profile, self.teeth_range[1]) / 2

    def transmission(self, teeth: int):
        p = self.pulley(teeth)
        return BeltPulley(p.pitch_diameter, inertia=p.inertia if self.settings.include_pulley_inertia else 0.0)

    def allowable_belt_force(self, teeth: int | None) -> float | None:
        """Largest effective belt tension [N] the belt checks accept (width and breaking, thesis appendix 2)."""
        found = self.belt_limit(teeth)
        return None if found is None else found[1]

    def belt_limit(self, teeth: int | None) -> tuple[str, float, float, str] | None:
        """The belt check that binds first: (drive.py's check name, allowable tension [N], the check's limit, unit)."""
        if self.belt is None:
            return None
        from ..drive.checks import belt_load

        grooves = teeth if teeth is not None else self.teeth_range[0]  # conservative for a continuous radius
        unit = belt_load(1.0, grooves, self.belt)  # everything is linear in the tension
        width_limit = self.belt.belt.width_factor
        breaking_limit = self.belt.belt.breaking_tension[self.belt.cord]
        width = width_limit / unit.required_width_factor
        breaking = breaking_limit / unit.breaking_load
        if width <= breaking:
            return "belt_width", width, width_limit, "-"
        return "belt_breaking", breaking, breaking_limit, "N"

    def handover_force(self) -> float:
        """|Effective belt tension| [N] at rest at the handover position (gravity and load forces)."""
        from ..drive.load import load_torque

        move = self.problem.timing.handover_move
        s = np.array([move.end_position if move is not None else 0.0])
        terms = load_torque(1e-5, BeltPulley(0.02), self.load, s, np.zeros(1), np.zeros(1))
        return float(abs(np.asarray(terms.load_force).ravel()[0]))


@dataclass
class _Context:
    """What the objective and constraint builders see of one NLP."""

    problem: Any
    settings: DesignSettings
    mesh: Mesh
    moves: list
    vars: list  # MoveVariables per move
    built: _Built
    drive: _DriveSetup | None = None
    choice: DriveChoice | None = None
    extra: dict = field(default_factory=dict)
    T: list = field(default_factory=list)  # move durations (parameters)
    graph: Any = None  # the built structure (_Graph)
    numbers: Any = None  # this solve's parameter values, start point and bounds (_Numbers)

    def si(self, m: int, theta, kind: str) -> ca.MX:
        """Values of move ``m`` at local points ``theta`` of every interval (N x len(theta)) in SI units."""
        mv, x = self.moves[m], self.vars[m]
        unit = x.at(theta, kind)
        if kind == "s":
            return mv.start + mv.stroke * unit
        return unit * (mv.stroke / self.T[m] ** {"v": 1, "a": 2, "j": 3}[kind])


def _start_values(mesh: Mesh, settings: DesignSettings, warm: list | None, k: int) -> tuple:
    """Start point of move ``k``: the warm start's solution on the same mesh, else the 3-4-5 law."""
    if warm is not None and k < len(warm) and warm[k].mesh == mesh:
        return warm[k].S, warm[k].V, warm[k].A
    return _initial_unit(mesh, settings.rest_order)


def _add_moves(ctx: _Context) -> None:
    b, settings, mesh, moves = ctx.built, ctx.settings, ctx.mesh, ctx.moves
    n, d = mesh.intervals, mesh.degree
    ctx.T = [b.param(f"T{mv.index}", lambda c, k=k: c.moves[k].duration) for k, mv in enumerate(moves)]
    for k, mv in enumerate(moves):
        s_lb, s_ub = np.full(n + 1, -np.inf), np.full(n + 1, np.inf)
        s_lb[0] = s_ub[0] = 0.0
        s_lb[-1] = s_ub[-1] = 1.0  # the end position is met exactly (the handover, for the handover move)
        v_lb, v_ub = np.full(n + 1, -np.inf), np.full(n + 1, np.inf)
        v_lb[[0, -1]] = v_ub[[0, -1]] = 0.0
        S = b.var(f"S{mv.index}", (n + 1, 1), s_lb, s_ub, lambda c, k=k: c.extra["start"][k][0])
        V = b.var(f"V{mv.index}", (n + 1, 1), v_lb, v_ub, lambda c, k=k: c.extra["start"][k][1])
        rest = settings.rest_order >= 2
        a0 = b.var(f"a0_{mv.index}", (1, 1), 0.0 if rest else -np.inf, 0.0 if rest else np.inf,
                   0.0 if rest else (lambda c, k=k: c.extra["start"][k][2][0, 0]))
        a_lb, a_ub = np.full((n, d), -np.inf), np.full((n, d), np.inf)
        if rest:
            a_lb[-1, -1] = a_ub[-1, -1] = 0.0
        Acol = b.var(f"A{mv.index}", (n, d), a_lb, a_ub, lambda c, k=k: c.extra["start"][k][2][:, 1:])
        x = MoveVariables(mesh, S, V, a0, Acol)
        ctx.vars.append(x)
        b.constrain(f"move {mv.index} collocation", x.defects(), 0.0, 0.0)
        if settings.rest_order >= 3:
            b.constrain(f"move {mv.index} rest (jerk)", ca.vertcat(x.at([0.0], "j")[0, 0], x.at([1.0], "j")[-1, 0]),
                        0.0, 0.0)
        if settings.rest_order >= 3 or ctx.extra["objective"] == "min_snap":
            b.constrain(f"move {mv.index} jerk continuity", x.jerk_joints(), 0.0, 0.0)
        if mv.jerk_bound is not None:
            # the bound on the unit jerk
            jb = b.param(f"jerk bound {mv.index}", lambda c, k=k: c.moves[k].jerk_bound / c.moves[k].j_scale)
            hull = x.hull("j") / jb  # Bernstein coefficients: bounds the jerk everywhere, not only at nodes
            lim = _Limit(f"jerk bound move {mv.index}", "jerk bound", mv.jerk_bound, "m/s^3",
                         lambda sig, jb=mv.jerk_bound: jb * (1 + sig), mv.index)
            b.limit_abs(lim, hull)


@dataclass
class _Graph:
    """One built NLP structure: symbols, the objective, structure-level extras, its solvers by options."""

    problem: Any
    built: _Built
    vars: list
    T: list
    extra: dict
    f: Any
    solvers: dict = field(default_factory=dict)
    pins: tuple = ()  # the pins' windows (move, switch position, first mesh interval or None)


_GRAPHS: dict = {}  # structure key -> [_Graph] (one per set of pin windows); see _build
_GRAPH_CACHE_SIZE = 16


def clear_cache() -> None:
    """Forget every built NLP and solver (a benchmark times builds with this)."""
    _GRAPHS.clear()


def _build(problem, spm: float, settings: DesignSettings, mesh: Mesh, objective: str, warm: list | None,
           drive: _DriveSetup | None = None, choice: DriveChoice | None = None, relaxed: bool = False,
           radius0: float | None = None, pin_times: dict | None = None, enforce_accuracy: bool = False,
           with_terms: bool = True):
    """The NLP of one solve: the built structure (from the cache when one fits) and this solve's numbers."""
    moves = _moves(problem, spm, settings)
    ctx = _Context(problem, settings, mesh, moves, [], _Built(relaxed=relaxed), drive, choice)
    e = ctx.extra
    e.update(spm=spm, objective=objective, warm=warm, radius0=radius0, relaxed=relaxed,
             enforce_accuracy=enforce_accuracy and with_terms, with_terms=with_terms,
             period=float(problem.timing.period(spm)))
    e["cache"] = {}  # numbers a parameter function computes once per solve
    e["schedule"] = problem.timing.schedule(spm)
    e["start"] = [_start_values(mesh, settings, warm, k) for k in range(len(moves))]
    e["pin_times"] = dict(pin_times or {})
    if drive is not None and pin_times is None and warm is None:
        y0, v0, a_nodes = _initial_unit(mesh, settings.rest_order)
        e["pin_times"] = _initial_pin_times(ctx, drive, [MoveSolution(mesh, y0, v0, a_nodes)] * len(moves))
    if drive is not None and pin_times is None and warm is not None and all(w.mesh == mesh for w in warm):
        e["pin_times"] = _initial_pin_times(ctx, drive, warm)
    crossings = _pin_intervals(ctx) if drive is not None else []
    key = _structure_key(ctx)
    graph = next((g for g in _GRAPHS.get(key, []) if g.problem is problem and _pins_fit(g.pins, crossings, mesh)),
                 None)
    if graph is None:
        e["pins"] = _pin_windows(crossings, mesh)
        graph = _build_graph(ctx)
        graph.pins = e["pins"]
        if not relaxed:  # a relaxed build names the motor in its limits: built for the one diagnosis
            if sum(len(gs) for gs in _GRAPHS.values()) >= _GRAPH_CACHE_SIZE:
                _GRAPHS.pop(next(iter(_GRAPHS)))
            _GRAPHS.setdefault(key, []).append(graph)
    e["pins"] = graph.pins
    ctx.graph, ctx.built, ctx.vars, ctx.T = graph, graph.built, graph.vars, graph.T
    for name, value in graph.extra.items():
        e.setdefault(name, value)
    ctx.numbers = graph.built.numbers(ctx)
    return ctx, graph.f


def _build_graph(ctx: _Context) -> _Graph:
    """Build the symbolic NLP of ``ctx``'s structure."""
    per_solve = set(ctx.extra)
    _add_moves(ctx)
    if ctx.drive is not None:
        _add_drive(ctx)
    b = ctx.built
    f = _objective(ctx, ctx.extra["objective"])
    if b.relaxed:
        f = sum(s for _, s in b.limits if s is not None) * 1e3 + 1e-6 * f
    extra = {k: v for k, v in ctx.extra.items() if k not in per_solve}
    return _Graph(ctx.problem, b, ctx.vars, ctx.T, extra, f)


def _pulley_setting(ctx: _Context) -> tuple[float, float, float, float]:
    """This solve's pulley: radius bounds, start radius [m] and the inertia factor (catalogue / model)."""
    drive, choice = ctx.drive, ctx.choice
    if choice.teeth is not None:
        pulley = drive.pulley(choice.teeth)
        model = float(drive.pulley_inertia(pulley.pitch_diameter))
        factor = (pulley.inertia / model if model > 0 else 0.0) if ctx.settings.include_pulley_inertia else 0.0
        return pulley.radius, pulley.radius, pulley.radius, factor
    lo, hi = choice.radius_bounds or drive.radius_bounds()
    radius0 = ctx.extra.get("radius0")
    start = float(np.clip(radius0 if radius0 is not None else ctx.problem.transmission.radius, lo, hi))
    return lo, hi, start, 1.0


def _add_drive(ctx: _Context) -> None:
    """Motor torque, speed, belt tension and inertia limits at every node (drive.py's load model)."""
    from ..drive.load import load_torque

    b, drive, choice, mesh = ctx.built, ctx.drive, ctx.choice, ctx.mesh
    # The pulley radius is a decision variable scaled by a reference radius: free between the
    # catalogue's bounds, or held at a tooth count's radius by equal bounds. A fixed pulley's
    # inertia is its catalogue value: the inertia model times a parameter (catalogue / model).
    # Both cases are one NLP structure, so one built solver serves the whole catalogue search.
    lo, hi = drive.radius_bounds()
    r_ref = float(np.sqrt(lo * hi))
    rho = b.var("radius", (1, 1), lambda c: _pulley_setting(c)[0] / r_ref, lambda c: _pulley_setting(c)[1] / r_ref,
                lambda c: _pulley_setting(c)[2] / r_ref)
    radius = rho * r_ref
    inertia = b.param("pulley inertia factor", lambda c: _pulley_setting(c)[3]) * drive.pulley_inertia(2 * radius)
    trans = BeltPulley(2 * radius, inertia)
    # the motor: fixed, or a Bonmin choice among candidates (binary weights)
    pct = drive.limits.peak_limit_pct / 100

    def peak_limit(m):  # the motor's peak torque, or the drive's overload limit if lower
        return min(m.peak_torque, pct * m.rated_torque)

    if choice.candidates:
        cands = choice.candidates
        pick = b.var("motor", (len(cands), 1), 0.0, 1.0, [1.0] + [0.0] * (len(cands) - 1))
        b.constrain("one motor", ca.sum1(pick) - 1.0, 0.0, 0.0)
        ctx.extra.update(discrete=("motor", len(cands)), pick=pick)

        def mix(values):
            return ca.dot(pick, ca.DM(values))

        rotor = mix([m.rotor_inertia for m in cands])
        peak_lim = mix([peak_limit(m) for m in cands])
        rated = mix([m.rated_torque for m in cands])
        speed = mix([m.rated_speed for m in cands])
        # for messages: the loosest limits of the candidates
        peak_num = max(peak_limit(m) for m in cands)
        rated_num = max(m.rated_torque for m in cands)
        speed_num = max(m.rated_speed for m in cands)
        motor_name = "any catalogue motor"
    else:
        m = choice.motor
        rotor = b.param("rotor inertia", lambda c: c.choice.motor.rotor_inertia)
        peak_num, rated_num, speed_num = peak_limit(m), m.rated_torque, m.rated_speed
        peak_lim = b.param("peak limit", lambda c: peak_limit(c.choice.motor))
        rated = b.param("rated torque", lambda c: c.choice.motor.rated_torque)
        speed = b.param("rated speed", lambda c: c.choice.motor.rated_speed)
        motor_name = m.name  # for messages: a relaxed build (which names them) is never reused
    tau_ref = drive.tau_ref  # a scale: the same for every motor, so one solver serves them all
    ctx.extra.update(radius=radius, r_ref=r_ref, tau_ref=tau_ref, trans=trans, rotor=rotor)
    peak_what = (f"peak_torque (peak torque, {motor_name}: {'%.3g' % peak_num} N m"
                 f"{', drive limit %g %% of rated' % drive.limits.peak_limit_pct if pct * (rated_num) < peak_num + 1e-12 and not choice.candidates else ''})")
    torques, forces = [], []
    pin_torques, pin_forces = [], []  # the pinned points, relative to their limits (see _pins_in_place)
    sum_sq = 0.0  # integral of (torque/tau_ref)^2 over the moves, divided by the period
    x_q, w_q = mesh.quadrature
    period = b.param("period", lambda c: c.extra["period"])
    greville = np.linspace(0.0, 1.0, mesh.degree + 1)
    for k, mv in enumerate(ctx.moves):
        # Torque (linear in the acceleration) is held at the Bernstein control points of the
        # acceleration polynomial (with position and speed at their Greville abscissae), not only at
        # the nodes: the acceleration part is then bounded everywhere in the interval (convex hull),
        # so the optimiser cannot hide a torque peak between two nodes.
        s = ca.vec(ctx.si(k, greville, "s")).T
        v = ca.vec(ctx.vars[k].hull("v") * (mv.stroke / ctx.T[k])).T  # bounds the speed between nodes too
        a = ca.vec(ctx.vars[k].hull("a") * (mv.stroke / ctx.T[k] ** 2)).T
        terms = load_torque(rotor, trans, drive.load, s, 0 * s, a)
        tau = terms.total / tau_ref
        forces.append(terms.load_force)
        # where a load force switches on inside the move (a spring met), the torque jumps: the
        # collocation nodes alone would let the optimiser hide the worst side of the jump between
        # two nodes. A pinned point at the crossing (found from the previous solution, updated
        # until it stops moving, see _solve_one) holds both sides of the jump.
        pin_t, pin_f = _pins(ctx, k, mv, rotor, trans)
        tau = ca.horzcat(tau, pin_t / tau_ref)
        forces.append(pin_f)
        pin_torques.append(ca.vec(pin_t) / peak_lim)
        pin_forces.append(ca.vec(pin_f))
        torques.append(tau)
        lim = _Limit(f"peak torque move {mv.index}", peak_what, peak_num, "N m",
                     lambda sig, pl=peak_num, tr=tau_ref: pl + sig * tr, mv.index, "peak_torque")
        b.limit_abs(lim, tau * (tau_ref / peak_lim))
        # speed: |v| / r <= the motor's rated speed
        omega = v / radius
        rpm = 60 / (2 * math.pi)
        lim = _Limit(f"speed move {mv.index}", f"peak_speed (motor speed, {motor_name}: rated)", speed_num * rpm,
                     "rpm", lambda sig, sp=speed_num * rpm: sp * (1 + sig), mv.index, "peak_speed")
        b.limit_abs(lim, omega / speed)
        # integral of torque squared over the move (Gauss-Legendre points)
        # accumulated along the move in a chain of variables, one link per mesh interval: a single
        # sum over every node would make one dense Jacobian row (costly to differentiate)
        sq, vq, aq = (ctx.si(k, x_q, kind) for kind in ("s", "v", "a"))  # N x len(x_q)
        tq = load_torque(rotor, trans, drive.load, sq, vq, aq).total / tau_ref
        per_interval = ca.mtimes(tq**2, ca.DM(w_q)) * (mesh.h * ctx.T[k] / period)
        Q = b.var(f"torque2 move {mv.index}", (mesh.intervals + 1, 1), -np.inf, np.inf, 0.0)
        b.constrain(f"torque2 move {mv.index}", ca.vertcat(Q[0], Q[1:] - Q[:-1] - per_interval), 0.0, 0.0)
        sum_sq = sum_sq + Q[-1]
    # the dwells: at rest, torque from gravity and load forces only
    sch = ctx.problem.timing.schedule(ctx.extra["spm"])
    dwell_sq = 0.0
    dwell_tau = []
    for itv, dur in zip(ctx.problem.timing.intervals, sch.duration):
        if itv.is_move:
            continue
        terms = load_torque(rotor, trans, drive.load, ca.MX(itv.start_position), ca.MX(0.0), ca.MX(0.0))
        t_d = terms.total / tau_ref
        dwell_tau.append(t_d)
        forces.append(terms.load_force)
        share = b.param(f"dwell {itv.index} share",
                        lambda c, i=itv.index - 1: c.extra["schedule"].duration[i] / c.extra["schedule"].period)
        dwell_sq = dwell_sq + t_d**2 * share
    if dwell_tau:
        tau_d = ca.vertcat(*dwell_tau)
        lim = _Limit("peak torque dwells", peak_what + " holding in the dwells", peak_num, "N m",
                     lambda sig, pl=peak_num, tr=tau_ref: pl + sig * tr, None, "peak_torque")
        b.limit_abs(lim, tau_d * (tau_ref / peak_lim))
    mean_sq = sum_sq + dwell_sq  # (RMS torque / tau_ref)^2
    lim = _Limit("RMS torque", f"rms_torque (RMS torque, {motor_name}: rated torque)", rated_num, "N m",
                 lambda sig, r=rated_num, tr=tau_ref: math.sqrt(r**2 + sig * tr**2), None, "rms_torque")
    b.limit(lim, mean_sq - (rated / tau_ref) ** 2)
    ctx.extra.update(torques=torques, dwell_torques=dwell_tau, mean_sq=mean_sq, move_sq=sum_sq)
    # belt tension
    belt = drive.belt_limit(choice.teeth)
    if belt is not None:
        # the tension the belt checks allow; said in the units of the check that binds (drive.py's names)
        check, f_allow, belt_lim, belt_unit = belt
        f_lim = b.param("belt force limit", lambda c: c.drive.belt_limit(c.choice.teeth)[1])
        allf = ca.horzcat(*[ca.reshape(f, 1, -1) for f in forces]) / f_lim
        pin_torques += [f / f_lim for f in pin_forces]
        what = {"belt_width": "belt_width (width factor the belt tension requires)",
                "belt_breaking": "belt_breaking (belt tension with safety factor, against the breaking load)"}[check]
        lim = _Limit("belt tension", what, belt_lim, belt_unit, lambda sig, bl=belt_lim: bl * (1 + sig), None, check)
        b.limit_abs(lim, allf)
    ctx.extra["pin_values"] = ca.vertcat(*pin_torques) if pin_torques else None
    # inertia ratio: a constraint only when the radius is free (a chosen pulley is checked, not held)
    if not choice.candidates:
        reflected = inertia + drive.load.moving_mass * radius**2
        lim = _Limit("inertia ratio", "inertia_ratio (load/rotor inertia ratio)", drive.limits.max_inertia_ratio,
                     "-", lambda sig, mr=drive.limits.max_inertia_ratio: mr * (1 + sig), None, "inertia_ratio",
                     enforced=lambda c: c.choice.teeth is None)
        b.limit(lim, reflected / (rotor * drive.limits.max_inertia_ratio) - 1.0)
    # handover accuracy: the error terms registered in HANDOVER_ERROR_TERMS (servo.py)
    terms = ([t for t in (term(ctx) for term in HANDOVER_ERROR_TERMS) if t is not None]
             if ctx.extra.get("with_terms", True) else [])
    ctx.extra["handover_terms"] = terms
    total = sum(v for _, v in terms) if terms else 0.0
    ctx.extra["handover_total"] = total
    # A lazy constraint: a term may sum over a whole move (a servo tracking error), which makes a
    # dense Hessian block that is costly to build and factorise. The solve runs without it, checks
    # it at the solution, and only if it is violated re-solves with it (see _solve_one).
    if terms and isinstance(total, (ca.MX, ca.SX)) and ctx.extra.get("enforce_accuracy"):
        acc = ctx.settings.accuracy
        lim = _Limit("handover accuracy", "handover accuracy", acc, "m", lambda sig, ac=acc: ac * (1 + sig))
        b.limit(lim, total / acc - 1.0)


def _switch_positions(drive: _DriveSetup) -> list[float]:
    return [f.contact_position for f in drive.load.forces if f.kind == "spring"]


#: Mesh intervals a pinned point may move across without a new NLP structure (see _pins).
_PIN_WINDOW = 3


def _pin_intervals(ctx: _Context) -> list[tuple[int, float, int | None]]:
    """(move, switch position, mesh interval of the crossing or None) of every load switch a move passes."""
    out = []
    for k, mv in enumerate(ctx.moves):
        lo, hi = sorted((mv.start, mv.start + mv.stroke))
        for pos in _switch_positions(ctx.drive):
            if lo < pos < hi:
                tau_c = ctx.extra["pin_times"].get((k, pos))
                idx = None if tau_c is None else min(int(tau_c / ctx.mesh.h), ctx.mesh.intervals - 1)
                out.append((k, pos, idx))
    return out


def _pin_windows(intervals: list, mesh: Mesh) -> tuple:
    """The first mesh interval of each pin's window: the window centred on the crossing's interval."""
    w = min(_PIN_WINDOW, mesh.intervals)
    return tuple((k, pos, None if idx is None else int(np.clip(idx - w // 2, 0, mesh.intervals - w)))
                 for k, pos, idx in intervals)


def _pins_fit(windows: tuple, intervals: list, mesh: Mesh) -> bool:
    """Whether every crossing of ``intervals`` lies in its pin's window (a built structure serves it)."""
    w = min(_PIN_WINDOW, mesh.intervals)
    return len(windows) == len(intervals) and all(
        (k, pos) == (k2, pos2) and (first is None) == (idx is None) and (idx is None or first <= idx < first + w)
        for (k, pos, first), (k2, pos2, idx) in zip(windows, intervals))


def _pin_basis(ctx: _Context, k: int, pos: float, first: int | None) -> tuple[np.ndarray, ...]:
    """This solve's crossing in its pin's window: one-hot interval, basis rows (acceleration,
    velocity increment) at the local time, weight (0: the move does not cross)."""
    mesh = ctx.mesh
    w = min(_PIN_WINDOW, mesh.intervals)
    onehot = np.zeros(w)
    tau_c = ctx.extra["pin_times"].get((k, pos))
    if tau_c is None or first is None:
        m = mesh.matrices([0.0])
        onehot[0] = 1.0
        return onehot, m["a"][0], m["v"][0], 0.0
    idx = min(int(tau_c / mesh.h), mesh.intervals - 1)
    m = mesh.matrices([tau_c / mesh.h - idx])
    onehot[idx - first] = 1.0
    return onehot, m["a"][0], m["v"][0], 1.0


def _pins(ctx: _Context, k: int, mv: _Move, rotor, trans):
    """Torque and belt force (row vectors) on both sides of every load switch the move passes.

    A pin's rows touch the variables of a window of :data:`_PIN_WINDOW` mesh intervals around
    the crossing (part of the NLP's structure, :func:`_pin_windows`); the interval within the
    window and the local time are parameters, so the crossing may move across the window
    between solves without a new build. A switch the move does not cross gets a zero weight.
    """
    from ..drive.load import load_torque

    b, mesh, x = ctx.built, ctx.mesh, ctx.vars[k]
    d1 = mesh.degree + 1
    w = min(_PIN_WINDOW, mesh.intervals)
    taus, forces = [], []
    for k_, pos, first in ctx.extra["pins"]:
        if k_ != k:
            continue
        first_ = 0 if first is None else first

        def basis(part, first=first, pos=pos):
            return lambda c: _pin_basis(c, k, pos, first)[part]

        e = b.params(f"pin e{k}.{pos}", basis(0), (w, 1))
        la = b.params(f"pin a{k}.{pos}", basis(1), (d1, 1))
        lv = b.params(f"pin v{k}.{pos}", basis(2), (d1, 1))
        weight = b.param(f"pin w{k}.{pos}", basis(3))
        A = x.A[first_:first_ + w, :]
        a_unit = ca.mtimes(e.T, ca.mtimes(A, la))
        v_unit = ca.mtimes(e.T, x.V[first_:first_ + w]) + mesh.h * ca.mtimes(e.T, ca.mtimes(A, lv))
        v = v_unit * mv.stroke / ctx.T[k]
        a = a_unit * mv.stroke / ctx.T[k] ** 2
        eps = 1e-9 * max(abs(mv.stroke), 1e-3)
        for side in (-eps, eps):
            terms = load_torque(rotor, trans, ctx.drive.load, ca.MX(pos + side), v, a)
            taus.append(weight * terms.total)
            forces.append(weight * terms.load_force)
    return (ca.horzcat(*taus) if taus else ca.MX(1, 0)), (ca.horzcat(*forces) if forces else ca.MX(1, 0))


def _initial_pin_times(ctx: _Context, drive: _DriveSetup, sols: list[MoveSolution]) -> dict:
    out = {}
    for k, mv in enumerate(ctx.moves):
        lo, hi = sorted((mv.start, mv.start + mv.stroke))
        for pos in _switch_positions(drive):
            if lo < pos < hi:
                cross = _crossings(sols[k], mv, [pos], fine_grid(sols[k].mesh, 4))
                out[(k, pos)] = float(cross[0]) if len(cross) else None
    return out


def _pin_times(ctx: _Context, sols: list[MoveSolution]) -> dict:
    """Unit times where each move of ``sols`` first passes each load switch (None: it does not)."""
    out = {}
    for k, pos, _ in ctx.extra.get("pins", []):
        mv, sol = ctx.moves[k], sols[k]
        cross = _crossings(sol, mv, [pos], fine_grid(sol.mesh, 4))
        out[(k, pos)] = float(cross[0]) if len(cross) else None
    return out


#: The terms of the position error at the handover, summed and held within
#: ``[design] handover_accuracy_mm``. Each is a function of the NLP context
#: returning ``(name, error in metres)`` (a number, or a CasADi expression of the
#: design variables, e.g. a servo tracking error that depends on the
#: acceleration near the handover), or None when it does not apply.
#: servo.py registers its term here (servo tracking, belt stretch under inertia and
#: load forces with the catalogue's belt stiffness, encoder count): one mechanism,
#: one set of belt data. Without a term the requirement is reported as not checked.
HANDOVER_ERROR_TERMS: list = []


#: Weight of the jerk-squared regularisation added to epigraph (peak) objectives.
SMOOTHING = 1e-7


def _smoothing(ctx: _Context):
    """A tiny integral of jerk squared (unit form, relative to the 3-4-5 law's 720 per move).

    A peak objective is set by one move; without this the moves that do not set the peak could
    take any feasible shape. It changes the peak by far less than the solver tolerance matters.
    """
    return SMOOTHING * sum(x.integral("j") for x in ctx.vars) / 720.0


def _objective(ctx: _Context, objective: str):
    """The scaled objective expression; records in ctx.extra how to turn it back into SI."""
    moves, xs, b = ctx.moves, ctx.vars, ctx.built
    if objective == "min_peak_accel":
        a_ref = max(mv.a_scale for mv in moves)
        z = b.var("peak_accel", (1, 1), 0.0, np.inf, 6.0 * max(mv.a_scale for mv in moves) / a_ref)
        for mv, x, T in zip(moves, xs, ctx.T):
            a = (abs(mv.stroke) / T**2 / a_ref) * x.hull("a")  # bounds the acceleration everywhere, not only at the nodes
            b.constrain(f"peak accel epigraph move {mv.index}", ca.vertcat(ca.vec(z - a), ca.vec(z + a)), 0.0, np.inf)
        ctx.extra.update(scale=a_ref, unit="m/s^2", transform=lambda f, c: f * a_ref)
        ctx.extra["objective_expr"] = z
        return z + _smoothing(ctx)
    if objective in ("min_accel_squared", "min_jerk", "min_snap"):
        kind, power = {"min_accel_squared": ("a", 3), "min_jerk": ("j", 5), "min_snap": ("snap", 7)}[objective]
        # integral over the move of (stroke/T^p * y^(k))^2 dt = stroke^2 / T^(2p-1) * integral over unit time
        ref = max(mv.stroke**2 / mv.duration**power for mv in moves)
        total = sum((mv.stroke**2 / T**power / ref) * x.integral(kind) for mv, x, T in zip(moves, xs, ctx.T))
        unit = {"a": "m^2/s^3", "j": "m^2/s^5", "snap": "m^2/s^7"}[kind]
        ctx.extra.update(scale=ref, unit=unit, transform=lambda f, c: f * ref)
        return total
    if ctx.drive is None:
        raise ProblemError(str(ctx.problem.file), "design.objective",
                           f"objective {objective!r} needs the drive (motor, load): add a [drive] section, or choose "
                           f"one of {', '.join(KINEMATIC_OBJECTIVES)}")
    tau_ref = ctx.extra["tau_ref"]
    if objective == "min_peak_torque":
        # The epigraph bound is one value, held as a chain of equal copies, one per mesh interval:
        # a single variable in every epigraph row would be a dense Jacobian column, which together
        # with a dense row (an accuracy term summing over the whole move) makes CasADi's
        # derivative generation slow.
        n = ctx.mesh.intervals
        Z = b.var("peak_torque", (n * len(moves) + 1, 1), 0.0, np.inf, 1.0)
        b.constrain("peak torque chain", Z[1:] - Z[:-1], 0.0, 0.0)
        d1 = ctx.mesh.degree + 1
        for k, (mv, tau) in enumerate(zip(moves, ctx.extra["torques"])):
            zk = Z[k * n:(k + 1) * n]
            zrow = ca.horzcat(ca.repmat(zk, d1, 1).T, ca.repmat(zk[0], 1, tau.shape[1] - n * d1))
            b.constrain(f"peak torque epigraph move {mv.index}", ca.vertcat((zrow - tau).T, (zrow + tau).T),
                        0.0, np.inf)
        if ctx.extra["dwell_torques"]:
            tau_d = ca.vertcat(*ctx.extra["dwell_torques"])
            b.constrain("peak torque epigraph dwells", ca.vertcat(Z[-1] - tau_d, Z[-1] + tau_d), 0.0, np.inf)
        ctx.extra.update(unit="N m", transform=lambda f, c: f * tau_ref)
        ctx.extra["objective_expr"] = Z[0]
        return Z[0] + _smoothing(ctx)
    if objective == "min_rms_torque":
        ctx.extra.update(unit="N m", transform=lambda f, c: math.sqrt(max(f, 0.0)) * tau_ref)
        return ctx.extra["mean_sq"]
    if objective == "min_energy":
        ctx.extra.update(unit="N^2 m^2 s", transform=lambda f, c: f * tau_ref**2 * c.extra["period"])
        return ctx.extra["move_sq"]
    raise ProblemError("--objective", "", f"{objective!r} is not one of {', '.join(OBJECTIVES)}")


def _solver_options(settings: DesignSettings, extra: dict | None, verbose: bool) -> dict:
    opts = dict(DEFAULT_SOLVER_OPTIONS)
    if verbose:
        opts.update({"ipopt.print_level": 5, "print_time": True})
        opts.pop("ipopt.sb", None)
    opts.update(settings.solver_options)
    opts.update(extra or {})
    return opts


def _structure_key(ctx: _Context) -> tuple:
    """What fixes the NLP's structure: solves that share it share one built NLP and solver (their numbers differ)."""
    choice = ctx.choice
    e = ctx.extra
    return (id(ctx.problem), repr(ctx.settings), ctx.mesh, e["objective"], e["relaxed"], e["with_terms"],
            e["enforce_accuracy"], tuple(mv.jerk_bound is None for mv in ctx.moves),
            None if choice is None else tuple(m.name for m in choice.candidates),
            ctx.drive is not None and ctx.drive.belt is None, tuple(HANDOVER_ERROR_TERMS))


def _solve_nlp(ctx: _Context, f, options: dict):
    """Solve the NLP of ``ctx``; the solver (CasADi's costly derivative generation) is built once per
    structure and options."""
    b = ctx.built
    opts = dict(options)
    plugin = opts.pop("plugin", "ipopt")
    key = repr(sorted(options.items()))
    solver = ctx.graph.solvers.get(key)
    if solver is None:
        w, g, p = ca.vertcat(*b.w), ca.vertcat(*b.g), ca.vertcat(*b.p)
        if plugin == "bonmin":
            opts = {k: v for k, v in opts.items() if not k.startswith("ipopt.")}
            opts.update({"bonmin.print_level": 0, "bonmin.bb_log_level": 0, "bonmin.nlp_log_level": 0,
                         "bonmin.fp_log_level": 0, "bonmin.lp_log_level": 0, "bonmin.milp_log_level": 0,
                         "bonmin.oa_log_level": 0})
            if "discrete" in ctx.extra:
                discrete = np.zeros(w.shape[0], dtype=bool)
                offset, count = b.offsets[ctx.extra["discrete"][0]]
                discrete[offset:offset + count] = True
                opts["discrete"] = discrete.tolist()
        solver = ca.nlpsol("design", plugin, {"x": w, "f": f, "g": g, "p": p}, opts)
        ctx.graph.solvers[key] = solver
    nums = ctx.numbers
    args = dict(x0=nums.x0, lbx=nums.lbx, ubx=nums.ubx, lbg=nums.lbg, ubg=nums.ubg, p=nums.p)
    if plugin == "bonmin" and not options.get("ipopt.print_level", 0):
        with _quiet_stdout():  # Bonmin's branch-and-bound log ignores its log-level options
            sol = solver(**args)
    else:
        sol = solver(**args)
    return sol, solver.stats(), solver


class _quiet_stdout:
    """Silence the C-level stdout (file descriptor 1) for a block."""

    def __enter__(self):
        import os
        import sys

        sys.stdout.flush()
        self._saved = os.dup(1)
        self._null = os.open(os.devnull, os.O_WRONLY)
        os.dup2(self._null, 1)
        # CasADi routes part of its plugins' printing through Python's sys.stdout
        self._py = sys.stdout
        sys.stdout = open(os.devnull, "w")
        return self

    def __exit__(self, *exc):
        import ctypes
        import os

        try:  # C stdio buffers: flush them while fd 1 still points to /dev/null
            ctypes.CDLL(None).fflush(None)
        except (OSError, AttributeError):
            pass
        import sys

        os.dup2(self._saved, 1)
        os.close(self._saved)
        os.close(self._null)
        sys.stdout.close()
        sys.stdout = self._py
        return False


def _value(ctx: _Context, expr, x: np.ndarray) -> np.ndarray:
    """Numeric value of an expression of the NLP's variables and parameters at ``x``."""
    b = ctx.built
    fn = ca.Function("value", [ca.vertcat(*b.w), ca.vertcat(*b.p)], [expr])
    return np.asarray(fn(x, ctx.numbers.p))


def _unpack(ctx: _Context, x: np.ndarray) -> list[MoveSolution]:
    """Numeric MoveSolutions from the solution vector."""
    out = []
    n, d = ctx.mesh.intervals, ctx.mesh.degree
    flat = _value(ctx, ca.vertcat(*[ca.vertcat(x_.S, x_.V, ca.vec(x_.A)) for x_ in ctx.vars]), x).ravel()
    size = 2 * (n + 1) + n * (d + 1)
    for k in range(len(ctx.vars)):
        chunk = flat[k * size:(k + 1) * size]
        A = chunk[2 * (n + 1):].reshape(d + 1, n).T  # ca.vec is column-major
        out.append(MoveSolution(ctx.mesh, chunk[: n + 1], chunk[n + 1: 2 * (n + 1)], A))
    return out


# --------------------------------------------------------------------------- the result


def move_piece(t_start: float, duration: float, start: float, stroke: float, sol: MoveSolution, label: str) -> Piece:
    """A stroke piece reproducing the collocation polynomials of one move exactly (one branch per mesh interval)."""
    tau = ca.SX.sym("tau")
    h = sol.mesh.h * duration
    coefs = sol.position_polynomials(duration, start, stroke)
    breaks = np.arange(sol.mesh.intervals) * h

    def horner(c, u):
        acc = ca.SX(float(c[-1]))
        for ck in c[-2::-1]:
            acc = acc * u + float(ck)
        return acc

    expr = horner(coefs[-1], tau - breaks[-1])
    for k in range(len(coefs) - 2, -1, -1):
        expr = ca.if_else(tau < breaks[k + 1], horner(coefs[k], tau - breaks[k]), expr)
    return Piece(t_start, duration, ca.Function("optimal_move", [tau], [expr]), label)


def stroke_from_solutions(problem, spm: float, solutions: list[MoveSolution], label: str = "optimal") -> StrokeFunction:
    sch = problem.timing.schedule(spm)
    pieces = []
    it = iter(solutions)
    for itv, t0, dur in zip(problem.timing.intervals, sch.t_start, sch.duration):
        if itv.is_move:
            pieces.append(move_piece(t0, dur, itv.start_position, itv.stroke, next(it), f"{itv.name}: {label}"))
        else:
            pieces.append(dwell_piece(t0, dur, itv.start_position, itv.name))
    return StrokeFunction(sch.period, pieces, label=label)


def _direction(stroke: float) -> str:
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
            "direction": _direction(self.stroke),
            "v_max_m_s": self.v_max, "a_max_m_s2": self.a_max, "jerk_max_m_s3": self.jerk_max, "C_a": self.C_a,
        }


@dataclass
class Design:
    """An optimised stroke with its choices and its constraint report."""

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
    pulley_teeth: int | None = None
    pitch_diameter: float | None = None
    motor: str | None = None
    notes: list[str] = field(default_factory=list)
    motor_spec: Any = field(default=None, repr=False)  # the ServoMotor
    settings: Any = field(default=None, repr=False)  # the DesignSettings it was solved with

    @property
    def solutions(self) -> list[MoveSolution]:
        return [m.solution for m in self.moves]

    @property
    def radius(self) -> float | None:
        return None if self.pitch_diameter is None else self.pitch_diameter / 2

    def summary(self) -> dict:
        """The JSON report of ``strokeopt solve`` (without the cam table)."""
        return {
            "status": self.status,
            "problem": self.problem.name,
            "problem_file": str(Path(self.problem.file).resolve()),
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
        }

    def cam_table(self, resolution_deg: float = 0.1) -> dict[str, np.ndarray]:
        """The stroke sampled at every ``resolution_deg`` of cam angle (the drive's master resolution).

        Columns: cam angle [deg], position [mm], velocity [m/s], acceleration [m/s^2], motor angle [deg]
        (position over the pulley radius; 0 at the 0 mm position).
        """
        n = int(round(360.0 / resolution_deg))
        angle = np.arange(n) * resolution_deg
        k = self.stroke.evaluate(angle / 360.0 * self.stroke.period)
        r = self.radius if self.radius else self.problem.transmission.radius
        return {"cam_angle_deg": angle, "position_mm": k.s * 1e3, "velocity_m_s": k.v,
                "acceleration_m_s2": k.a, "motor_angle_deg": np.degrees(k.s / r)}

    def to_json_dict(self, resolution_deg: float = 0.1) -> dict:
        sch = self.problem.timing.schedule(self.spm)
        out = {"format": "strokeopt-design", "version": 1, **self.summary()}
        out["moves"] = [{**m.to_dict(), "unit_solution": {"S": m.solution.S.tolist(), "V": m.solution.V.tolist(),
                                                          "A": m.solution.A.tolist()}} for m in self.moves]
        out["intervals"] = [{"index": itv.index, "name": itv.name, "kind": "move" if itv.is_move else "dwell",
                             "t_start_s": float(t0), "duration_s": float(dur), "position_mm": itv.start_position * 1e3}
                            for itv, t0, dur in zip(self.problem.timing.intervals, sch.t_start, sch.duration)]
        table = self.cam_table(resolution_deg)
        cols = list(table)
        out["cam_table"] = {"resolution_deg": resolution_deg, "columns": cols,
                            "rows": np.column_stack([table[c] for c in cols]).tolist()}
        return out

    def write(self, out_dir: str | Path, resolution_deg: float = 0.1) -> list[Path]:
        """Write ``design.json`` and ``cam_table.csv`` into ``out_dir``; returns the paths."""
        from ..report.format import to_json

        out = Path(out_dir)
        out.mkdir(parents=True, exist_ok=True)
        data = self.to_json_dict(resolution_deg)
        p_json = out / "design.json"
        p_json.write_text(to_json(data) + "\n", encoding="utf-8")
        p_csv = out / "cam_table.csv"
        table = self.cam_table(resolution_deg)
        header = ",".join(table)
        np.savetxt(p_csv, np.column_stack(list(table.values())), delimiter=",", header=header, comments="",
                   fmt=["%.1f", "%.6f", "%.6f", "%.4f", "%.5f"])
        return [p_json, p_csv]


def check_out_dir(path: str | Path, option: str = "--out") -> Path:
    """Check before a solve that ``path`` is a directory or can be created as one (:meth:`Design.write`).

    Raises :class:`ProblemError` naming ``option`` otherwise, so a long solve does not end on a bad path.
    """
    import os

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


def read_design(path: str | Path) -> tuple[dict, StrokeFunction]:
    """Read a ``design.json``: its data and the exact optimal :class:`StrokeFunction` rebuilt from it."""
    import json

    path = Path(path)
    try:
        data = json.loads(path.read_text(encoding="utf-8"))
    except FileNotFoundError:
        raise ProblemError(str(path), "", "no such file") from None
    except (OSError, ValueError) as exc:
        raise ProblemError(str(path), "", f"is not a readable design file: {exc}") from None
    if not isinstance(data, dict) or data.get("format") != "strokeopt-design":
        raise ProblemError(str(path), "format", "is not a strokeopt design file (format != 'strokeopt-design')")
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


# --------------------------------------------------------------------------- checks


def _fine_grid_report(moves: list[_Move], sols: list[MoveSolution], per_interval: int) -> tuple[dict, list[dict]]:
    """Peaks on a fine grid between collocation nodes and the jerk-bound violations there."""
    rows = []
    worst = 0.0
    for mv, sol in zip(moves, sols):
        tau = fine_grid(sol.mesh, per_interval)
        y, y1, y2, y3, _ = sol.evaluate(tau)
        tn = node_times(sol.mesh)
        _, _, a_n, j_n, _ = sol.evaluate(tn)
        row = {"move": mv.index,
               "a_max_nodes_m_s2": float(np.max(np.abs(a_n))) * mv.a_scale,
               "a_max_fine_m_s2": float(np.max(np.abs(y2))) * mv.a_scale,
               "position_error_end_mm": abs(float(y[-1]) - 1.0) * abs(mv.stroke) * 1e3}
        if mv.jerk_bound is not None:
            jmax = float(np.max(np.abs(y3))) * mv.j_scale
            viol = max(0.0, jmax / mv.jerk_bound - 1.0)
            row.update(jerk_max_fine_m_s3=jmax, jerk_bound_m_s3=mv.jerk_bound, jerk_violation=viol)
            worst = max(worst, viol)
        rows.append(row)
    return {"points_per_interval": per_interval, "worst_relative_violation": worst, "moves": rows}, rows


def _move_results(moves: list[_Move], sols: list[MoveSolution], per_interval: int = 50) -> list[MoveResult]:
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


# --------------------------------------------------------------------------- solve


@dataclass
class _Outcome:
    ctx: _Context
    x: np.ndarray
    sols: list
    value: float
    status: str
    solve_time: float
    iterations: int
    fine: dict
    radius: float | None = None
    motor: Any = None
    continuous_radius: float | None = None


def _crossings(sol: MoveSolution, mv: _Move, positions, tau: np.ndarray) -> np.ndarray:
    """Unit times where the move passes ``positions`` (where a load force switches on), both sides of each."""
    if not positions:
        return np.zeros(0)
    y = sol.evaluate(tau)[0]
    out = []
    for pos in positions:
        target = (pos - mv.start) / mv.stroke
        f = y - target
        for i in np.nonzero(np.sign(f[:-1]) * np.sign(f[1:]) <= 0)[0]:
            lo, hi = tau[i], tau[i + 1]
            for _ in range(3):  # three dense zooms on the exact polynomial: (1/1000)^3 of the bracket
                grid = np.linspace(lo, hi, 1001)
                g = sol.evaluate(grid)[0] - target
                j = int(np.nonzero(np.sign(g[:-1]) * np.sign(g[1:]) <= 0)[0][0])
                lo, hi = grid[j], grid[j + 1]
            out += [lo, hi]
    return np.array(out)


def _fine_cycle(problem, spm: float, moves: list[_Move], sols: list[MoveSolution], per_interval: int,
                switch_positions=()):
    """Times, positions, speeds, accelerations over one whole cycle: fine grids in the moves, dwell ends.

    ``switch_positions``: positions where a load force switches (a spring met): the grid gets the
    crossing times, both sides, so a jump of the load is read at its worst.
    """
    sch = problem.timing.schedule(spm)
    ts, ss, vs, as_ = [], [], [], []
    it = iter(zip(moves, sols))
    for itv, t0, dur in zip(problem.timing.intervals, sch.t_start, sch.duration):
        if itv.is_move:
            mv, sol = next(it)
            tau = fine_grid(sol.mesh, per_interval)
            tau = np.unique(np.concatenate([tau, _crossings(sol, mv, switch_positions, tau)]))
            y, y1, y2, _, _ = sol.evaluate(tau)
            ts.append(t0 + tau * dur)
            ss.append(mv.start + mv.stroke * y)
            vs.append(y1 * mv.stroke / dur)
            as_.append(y2 * mv.stroke / dur**2)
        else:
            ts.append(np.array([t0, t0 + dur]))
            ss.append(np.full(2, itv.start_position))
            vs.append(np.zeros(2))
            as_.append(np.zeros(2))
    return tuple(np.concatenate(x) for x in (ts, ss, vs, as_))


def _drive_checks_fine(drive: _DriveSetup, motor, teeth: int | None, radius: float, problem, spm, moves, sols,
                       per_interval: int) -> list:
    """drive.py's checks of the solution, on a fine grid over the whole cycle."""
    from ..drive.checks import drive_checks

    switches = [f.contact_position for f in drive.load.forces if f.kind == "spring"]
    t, s, v, a = _fine_cycle(problem, spm, moves, sols, per_interval, switches)
    if teeth is not None:
        trans = drive.transmission(teeth)
    else:
        trans = BeltPulley(2 * radius, inertia=float(drive.pulley_inertia(2 * radius)))
    grooves = teeth if teeth is not None else drive.teeth_range[0]
    return drive_checks(motor, trans, drive.load, t, s, v, a, limits=drive.limits, belt=drive.belt, grooves=grooves)


_ENFORCED = {"peak_torque", "overload", "rms_torque", "peak_speed", "belt_width", "belt_breaking"}


_PIN_ITERATIONS = 5


def _objective_value(ctx: _Context, sol, x) -> float:
    """The objective without the smoothing term (scaled)."""
    expr = ctx.extra.get("objective_expr")
    return float(sol["f"]) if expr is None else float(_value(ctx, expr, x).item())


def _pins_in_place(ctx: _Context, x: np.ndarray, new: dict) -> bool:
    """Whether the pinned points of ``ctx`` may stay where they are for the solution ``x``.

    ``new`` holds the solution's own crossing times. Moving the pins there must keep them in
    their windows (the NLP's structure, see _pins) and change the torque and belt force they hold by less than a tenth
    of ``check_tolerance`` of the limits (the fine grid re-reads the true values after the
    solve). A move that does not set a limit can shift its crossing freely without a re-solve.
    """
    old = ctx.extra["pin_times"]
    if all((new.get(key) is None) == (old.get(key) is None) and (new.get(key) is None or new[key] == old[key])
           for key in new):
        return True
    moved = replace(ctx, extra=dict(ctx.extra, pin_times=new, cache={}))
    if not _pins_fit(ctx.extra["pins"], _pin_intervals(moved), ctx.mesh) or ctx.extra.get("pin_values") is None:
        return False
    expr = ctx.extra["pin_values"]
    before = _value(ctx, expr, x).ravel()
    after = np.asarray(ca.Function("pins", [ca.vertcat(*ctx.built.w), ca.vertcat(*ctx.built.p)], [expr])(
        x, ctx.built.numbers(moved).p)).ravel()
    return bool(np.max(np.abs(after - before), initial=0.0) <= ctx.settings.check_tolerance / 10)


def _solve_one(problem, spm, settings, mesh, objective, warm, drive, choice, options, radius0=None,
               with_terms: bool = True) -> _Outcome:
    """One NLP with fixed parts (or a continuous radius / a Bonmin motor), refined where the fine grid demands."""
    total_time, iterations = 0.0, 0
    for attempt in range(settings.refinements + 1):
        pin_times = None
        enforce = False
        for _ in range(_PIN_ITERATIONS):
            t0 = time.perf_counter()
            ctx, f = _build(problem, spm, settings, mesh, objective, warm, drive, choice, radius0=radius0,
                            pin_times=pin_times, enforce_accuracy=enforce, with_terms=with_terms)
            sol, stats, _ = _solve_nlp(ctx, f, options)
            total_time += time.perf_counter() - t0
            iterations += int(stats.get("iter_count", 0) or 0)
            status = str(stats.get("return_status", "unknown"))
            ok = stats.get("success", False) if choice is not None and choice.candidates else status in _STATUS_OK
            if not ok:
                raise _diagnose(problem, spm, settings, mesh, objective, drive, choice, status, options, radius0,
                                with_terms=with_terms, enforce_accuracy=enforce)
            x = np.asarray(sol["x"]).ravel()
            sols = _unpack(ctx, x)
            new = _pin_times(ctx, sols)
            total = ctx.extra.get("handover_total", 0.0)
            violated = (not enforce and isinstance(total, (ca.MX, ca.SX))
                        and float(_value(ctx, total, x).item()) > settings.accuracy)
            if not violated and _pins_in_place(ctx, x, new):
                break
            pin_times, warm, enforce = new, sols, enforce or violated
        fine, _ = _fine_grid_report(ctx.moves, sols, settings.check_points)
        radius = motor = None
        worst = fine["worst_relative_violation"]
        if drive is not None:
            r_expr = ctx.extra["radius"]
            radius = float(r_expr) if isinstance(r_expr, float) else float(_value(ctx, r_expr, x).item())
            motor = choice.motor
            if choice.candidates:
                pick = _value(ctx, ctx.extra["pick"], x).ravel()
                motor = choice.candidates[int(np.argmax(pick))]
            checks = _drive_checks_fine(drive, motor, choice.teeth, radius, problem, spm, ctx.moves, sols,
                                        settings.check_points)
            over = [max(0.0, -c.margin) for c in checks if c.name in _ENFORCED and math.isfinite(c.margin)]
            if objective == "min_peak_torque":  # the epigraph held at the nodes; the fine grid reads the peak
                nlp_peak = ctx.extra["transform"](_objective_value(ctx, sol, x), ctx)
                fine_peak = next(c.value for c in checks if c.name == "peak_torque")
                fine["peak_torque_nodes_N_m"] = nlp_peak
                fine["peak_torque_fine_N_m"] = fine_peak
                over.append(max(0.0, fine_peak / nlp_peak - 1.0))
            worst = max([worst] + over)
            fine["drive_checks"] = [c.as_dict() for c in checks]
            fine["worst_relative_violation"] = worst
        if worst <= settings.check_tolerance or attempt == settings.refinements:
            break
        mesh = Mesh(mesh.intervals * 2, mesh.degree)
        warm = None
    value = ctx.extra["transform"](_objective_value(ctx, sol, x), ctx)
    return _Outcome(ctx, x, sols, value, "optimal" if status == "Solve_Succeeded" else "acceptable", total_time,
                    iterations, fine, radius, motor)


def solve_design(problem, *, objective: str | None = None, spm: float | None = None,
                 settings: DesignSettings | None = None, mesh: Mesh | None = None, warm_start=None,
                 solver_options: dict | None = None, verbose: bool = False, progress=None) -> Design:
    """Solve the design problem of ``problem`` at ``spm`` (default: the file's).

    ``objective`` overrides ``[design] objective``; ``mesh`` overrides its mesh;
    ``warm_start`` is a previous :class:`Design` (or its move solutions) to start from;
    ``solver_options`` are passed to ``casadi.nlpsol`` over the defaults; ``progress`` wraps the
    motors of a catalogue search (tqdm).
    Raises :class:`SolverError` naming the constraint that cannot be met.
    """
    settings = settings or getattr(problem, "design", None) or DesignSettings()
    objective = objective or settings.objective
    if objective not in OBJECTIVES:
        raise ProblemError("--objective", "", f"{objective!r} is not one of {', '.join(OBJECTIVES)}")
    spm = float(spm if spm is not None else problem.spm)
    if not (math.isfinite(spm) and spm > 0):
        raise ProblemError("--spm", "", f"must be positive, got {spm!r}")
    mesh = mesh or settings.mesh
    warm = warm_start.solutions if isinstance(warm_start, Design) else warm_start
    radius0 = warm_start.radius if isinstance(warm_start, Design) else None
    options = _solver_options(settings, solver_options, verbose)
    drive = _DriveSetup(problem, settings) if getattr(problem, "drive", None) is not None else None
    if drive is None and objective in TORQUE_OBJECTIVES:
        raise ProblemError(str(problem.file), "design.objective",
                           f"objective {objective!r} needs the drive (motor, load): add a [drive] section, or choose "
                           f"one of {', '.join(KINEMATIC_OBJECTIVES)}")
    _check_static_accuracy(problem, settings, drive)
    t_start = time.perf_counter()
    notes: list[str] = []
    if drive is None:
        best = _solve_one(problem, spm, settings, mesh, objective, warm, None, None, options)
        teeth, pd, motor = None, None, None
    else:
        best, teeth, notes = _choose_parts(problem, spm, settings, mesh, objective, warm, drive, options, radius0,
                                           progress)
        # the handover accuracy terms at the chosen design (lazy: re-solved with them only if violated)
        choice = DriveChoice(best.motor, teeth, None if teeth else drive.radius_bounds())
        best = _with_terms(problem, spm, settings, objective, drive, choice, options, best)
        motor = best.motor
        pd = 2 * best.radius
    wall = time.perf_counter() - t_start
    ctx, sols = best.ctx, best.sols
    stroke = stroke_from_solutions(problem, spm, sols, label=f"optimal ({objective})")
    moves = _move_results(ctx.moves, sols)
    design = Design(problem, spm, objective, best.value, ctx.extra["unit"], stroke, moves, best.ctx.mesh,
                    best.status, wall, best.iterations, fine_grid=best.fine, pulley_teeth=teeth, pitch_diameter=pd,
                    motor=None if motor is None else motor.name, notes=notes)
    design.motor_spec = motor
    design.settings = settings
    design.checks, design.active_constraints = _report_checks(best, design)
    failed = [c for c in design.checks if not c["ok"]]
    if failed:  # beyond check_tolerance after every refinement: not a design to build
        from ..report.format import format_value

        design.status = "limits exceeded"
        design.notes.insert(0, "limits exceeded between collocation nodes: " + "; ".join(
            f"{c['name']} {format_value(c['value'])} {c['unit']} > limit {format_value(c['limit'])} "
            f"({-100 * c['margin']:.2f} % over)" for c in failed) + "; use more mesh intervals ([design] "
            "mesh_intervals) or refinements")
    if drive is not None:
        # the objective as the fine grid reads it (the NLP saw the nodes)
        design.objective_value = _fine_objective(design, best) if objective in TORQUE_OBJECTIVES else best.value
    if drive is not None and not best.ctx.extra.get("handover_terms"):
        design.notes.append(f"handover accuracy {settings.accuracy * 1e3:g} mm NOT checked: the problem has no "
                            f"[servo] section (servo loop and belt model)")
    if best.fine["worst_relative_violation"] > settings.check_tolerance:
        design.notes.append(f"between collocation nodes a limit is exceeded by "
                            f"{100 * best.fine['worst_relative_violation']:.2f} % (more than check_tolerance "
                            f"{100 * settings.check_tolerance:g} %) after {settings.refinements} refinements: "
                            f"use more mesh intervals")
    return design


def _with_terms(problem, spm, settings, objective, drive, choice, options, best: _Outcome) -> _Outcome:
    """Evaluate the handover error terms at ``best`` (same variables; the terms add parameters only);
    if they exceed the allowed error, re-solve the chosen parts with them enforced."""
    t0 = time.perf_counter()
    ctx, _ = _build(problem, spm, settings, best.ctx.mesh, objective, best.sols, drive, choice,
                    radius0=best.radius, pin_times=best.ctx.extra.get("pin_times"), with_terms=True)
    total = ctx.extra.get("handover_total", 0.0)
    if ctx.built.n_w == best.ctx.built.n_w:
        value = float(_value(ctx, total, best.x).item()) if isinstance(total, (ca.MX, ca.SX)) else float(total)
        if value <= settings.accuracy:
            best.ctx.extra["handover_terms"] = [(n, float(_value(ctx, v, best.x).item())
                                                 if isinstance(v, (ca.MX, ca.SX)) else float(v))
                                                for n, v in ctx.extra["handover_terms"]]
            best.solve_time += time.perf_counter() - t0
            return best
    out = _solve_one(problem, spm, settings, best.ctx.mesh, objective, best.sols, drive, choice, options,
                     best.radius, with_terms=True)
    out.solve_time += best.solve_time
    return out


def _fine_objective(design: "Design", best: _Outcome) -> float:
    checks = {c["name"]: c for c in best.fine.get("drive_checks", [])}
    if design.objective == "min_peak_torque" and "peak_torque" in checks:
        return float(checks["peak_torque"]["value"])
    if design.objective == "min_rms_torque" and "rms_torque" in checks:
        return float(checks["rms_torque"]["value"])
    return best.value


def _choose_parts(problem, spm, settings, mesh, objective, warm, drive: _DriveSetup, options, radius0, progress=None):
    """Motor (fixed, enumerated, or Bonmin) and pulley (fixed, or continuous radius then nearest tooth counts).

    Enumeration prunes: the continuous-radius optimum of a motor is a lower bound of its
    tooth-count optima, so a motor whose continuous optimum is no better than the best
    design found so far is not solved for tooth counts.
    """
    notes = []
    if settings.motor_choice == "bonmin":
        cands = tuple(drive.motors())
        bonmin_opts = {k: v for k, v in options.items() if k not in ("ipopt.max_iter",)}
        bonmin_opts["plugin"] = "bonmin"
        try:
            first = _solve_one(problem, spm, settings, mesh, objective, warm, drive,
                               DriveChoice(None, None if settings.pulley != "fixed" else problem.pulley_teeth,
                                           drive.radius_bounds() if settings.pulley != "fixed" else None, cands),
                               bonmin_opts, radius0, with_terms=False)
        except SolverError as exc:
            raise SolverError(f"no motor of the catalogue meets the limits at {spm:g} spm (Bonmin): {exc.reason}") from None
        motors = [first.motor]
        notes.append(f"motor chosen by Bonmin among {len(cands)} candidates (a heuristic for this non-convex problem)")
    elif settings.motor_choice == "enumerate":
        motors = drive.motors()
    else:
        motors = [drive.fixed_motor()]
    failures = []
    # phase 1: every motor with its own best pulley radius (continuous), or the fixed pulley
    first_pass = []
    for motor in (progress(motors) if progress is not None and len(motors) > 1 else motors):
        try:
            if settings.pulley == "fixed":
                out = _solve_one(problem, spm, settings, mesh, objective, warm, drive,
                                 DriveChoice(motor, problem.pulley_teeth), options,
                                 with_terms=False)
            else:
                out = _solve_one(problem, spm, settings, mesh, objective, warm, drive,
                                 DriveChoice(motor, None, drive.radius_bounds()), options, radius0,
                                 with_terms=False)
                radius0 = out.radius
            warm = out.sols
            first_pass.append((out, motor))
        except SolverError as exc:
            failures.append((motor, exc))
    total_time = sum(o.solve_time for o, _ in first_pass)
    # phase 2: tooth counts next to the continuous optimum, best lower bounds first
    results = []
    if settings.pulley in ("fixed", "continuous"):
        results = [(o, problem.pulley_teeth if settings.pulley == "fixed" else None) for o, _ in first_pass]
    else:
        for cont, motor in sorted(first_pass, key=lambda r: r[0].value):
            if results and cont.value >= min(r[0].value for r in results):
                continue
            try:
                out, teeth = _nearest_teeth(problem, spm, settings, mesh, objective, drive, motor, options, cont)
                results.append((out, teeth))
                total_time += out.solve_time
            except SolverError as exc:
                failures.append((motor, exc))
    if not results:
        if len(failures) == 1:
            raise failures[0][1]
        # the motor that comes closest first; one line per motor after it
        failures.sort(key=lambda f: getattr(f[1], "excess", math.inf))
        m0, e0 = failures[0]
        lines = [f"no motor of the catalogue can drive this design at {spm:g} spm; closest {m0.name}: "
                 f"{getattr(e0, 'short', e0.reason.splitlines()[0])}"]
        lines += [f"  {m.name}: {getattr(e, 'short', e.reason.splitlines()[0])}" for m, e in failures]
        raise SolverError("\n".join(lines))
    best, teeth = min(results, key=lambda r: r[0].value)
    if len(motors) > 1:
        notes.append(f"motor chosen among {len(motors)} by enumeration ({len(failures)} infeasible): "
                     f"lowest {objective}")
    best.solve_time = total_time
    return best, teeth, notes


def _nearest_teeth(problem, spm, settings, mesh, objective, drive, motor, options, cont: _Outcome):
    """Re-solve with the tooth counts either side of the continuous optimum; keep the better."""
    from ..drive.transmission import PROFILE_PITCH

    z = 2 * math.pi * cont.radius / PROFILE_PITCH[drive.profile]
    available = [p.teeth for p in drive.catalogue.pulleys_of(drive.profile, *drive.teeth_range)]
    if not available:
        raise ProblemError(drive.file, "design.pulley_teeth_min", f"the catalogue has no {drive.profile} pulley "
                                                                  f"with {drive.teeth_range[0]}-{drive.teeth_range[1]} teeth")
    below = [n for n in available if n <= z]
    above = [n for n in available if n >= z]
    candidates = sorted({max(below) if below else min(available), min(above) if above else max(available)})
    best, failures = None, []
    for teeth in candidates:
        try:
            out = _solve_one(problem, spm, settings, mesh, objective, cont.sols, drive, DriveChoice(motor, teeth),
                             options, with_terms=False)
        except SolverError as exc:
            failures.append(exc)
            continue
        if best is None or out.value < best[0].value:
            best = (out, teeth)
    if best is None:
        raise failures[0]
    best[0].continuous_radius = cont.radius
    return best


def _check_static_accuracy(problem, settings, drive) -> None:
    """Handover error terms that do not depend on the design: checked before solving."""
    if drive is None:
        return
    ctx = _Context(problem, settings, settings.mesh, [], [], _Built(), drive, None)
    terms = [t for t in (term(ctx) for term in HANDOVER_ERROR_TERMS) if t is not None]
    fixed = [(n, v) for n, v in terms if isinstance(v, (int, float))]
    total = sum(v for _, v in fixed)
    if total > settings.accuracy:
        parts = ", ".join(f"{_term_name(n)} {v * 1e3:.3f} mm" for n, v in fixed)
        raise SolverError(f"handover accuracy cannot be met: {parts} exceeds the allowed "
                          f"{settings.accuracy * 1e3:g} mm by {(total - settings.accuracy) * 1e3:.3f} mm")


def _report_checks(best: _Outcome, design: "Design") -> tuple[list[dict], list[str]]:
    """Every check with its margin (fine grid), and the constraints active at the solution.

    One rule for every check: ok when the value exceeds the limit by less than
    ``check_tolerance`` (the violation between collocation nodes the design accepts
    before it refines the mesh; the margin shows the exact value).
    """
    ctx = best.ctx
    tol = ctx.settings.check_tolerance
    checks = []
    for mv, row in zip(ctx.moves, best.fine["moves"]):
        if mv.jerk_bound is not None:
            checks.append({"name": f"jerk move {mv.index}", "value": row["jerk_max_fine_m_s3"], "limit": mv.jerk_bound,
                           "unit": "m/s^3"})
    checks += [dict(c) for c in best.fine.get("drive_checks", [])]
    for name, value in ctx.extra.get("handover_terms", []):
        v = float(value) if isinstance(value, (int, float)) else float(_value(ctx, value, best.x).item())
        checks.append({"name": f"handover accuracy ({_term_name(name)})", "value": v * 1e3,
                       "limit": ctx.settings.accuracy * 1e3, "unit": "mm"})
    for c in checks:
        value, limit = float(c["value"]), float(c["limit"])
        c["margin"] = 1.0 - value / limit if limit > 0 else (-math.inf if value > 0 else 0.0)
        c["ok"] = bool(value <= limit * (1 + tol))
    active = []
    # active limit groups: the largest scaled residual of each group within 1e-4 of its bound
    for (lim, _), g in zip(ctx.built.limits, _limit_values(ctx, best.x)):
        if lim.is_enforced(ctx) and g > -1e-4:
            active.append(lim.name)
    for mv in ctx.moves:
        itv = ctx.problem.timing.intervals[mv.interval - 1]
        if itv.handover:
            active.append(f"handover position: end of move {mv.index} at {(mv.start + mv.stroke) * 1e3:g} mm (exact)")
    return checks, active


def _term_name(name: str) -> str:
    """A handover error term's name as a reader sees it: without the module that registered it ("(servo.py)")."""
    import re

    return re.sub(r"\s*\([\w.]+\.py\)", "", name).strip()


def _limit_values(ctx: _Context, x: np.ndarray) -> list[float]:
    """Largest scaled residual (``expr``, satisfied when <= 0) of every limit group at ``x``."""
    exprs = ctx.built.limit_exprs
    if not exprs:
        return []
    return [float(v) for v in _value(ctx, ca.vertcat(*[ca.mmax(e) for e in exprs]), x).ravel()]


def _diagnose(problem, spm, settings, mesh, objective, drive, choice, status, options, radius0,
              with_terms: bool = False, enforce_accuracy: bool = False) -> SolverError:
    """Why a solve failed: relax every limit group of the NLP that failed, minimise the total excess, name the worst."""
    where = f" for motor {choice.motor.name}" if choice is not None and choice.motor is not None else ""
    try:
        ctx, f = _build(problem, spm, settings, mesh, objective, None, drive, choice, relaxed=True, radius0=radius0,
                        with_terms=with_terms, enforce_accuracy=enforce_accuracy)
        opts = {k: v for k, v in options.items() if k != "plugin"}
        sol, stats, _ = _solve_nlp(ctx, f, opts)
    except (RuntimeError, ValueError) as exc:  # pragma: no cover - a relaxed problem is always feasible
        return SolverError(f"the design problem at {spm:g} spm{where} could not be solved (IPOPT: {status}; {exc})")
    if str(stats.get("return_status")) not in _STATUS_OK:
        return SolverError(f"the design problem at {spm:g} spm{where} could not be solved (IPOPT: {status}); "
                           f"even with every limit relaxed: check the timing and the rest conditions")
    x = np.asarray(sol["x"]).ravel()
    violated = []  # (relative excess, limit group, slack), worst first
    for lim, slack in ctx.built.limits:
        sig = float(_value(ctx, slack, x).item()) if slack is not None and lim.is_enforced(ctx) else 0.0
        if sig > 1e-6:
            need = lim.need(sig)
            violated.append((need / lim.limit - 1 if lim.limit else math.inf, lim, need))
    if not violated:
        hint = (f"raise the iteration limit ({options.get('ipopt.max_iter')}: [design.solver] "
                f"\"ipopt.max_iter\" = 1000), " if status == "Maximum_Iterations_Exceeded" else "")
        return SolverError(f"IPOPT did not converge at {spm:g} spm{where} ({status}) although the limits can be met: "
                           f"{hint}try more mesh intervals, or --verbose to see the solver log")
    violated.sort(key=lambda v: -v[0])
    excess, lim, need = violated[0]
    subject = f"move {lim.move} too short" if lim.move is not None else "the design cannot meet the limits"
    motor = f" for motor {choice.motor.name}" if choice is not None and choice.motor is not None else ""
    lines = [f"{subject}{motor} at {spm:g} spm: {_need_text(lim, need, lim.what)}"]
    seen = {lim.name}
    for _, other, other_need in violated[1:]:
        if other.name not in seen and len(seen) < 5:
            seen.add(other.name)
            where_ = f" (move {other.move})" if other.move is not None else ""
            lines.append(f"  also{where_}: {_need_text(other, other_need, other.what)}")
    err = SolverError("\n".join(lines))
    err.excess = excess  # relative excess of the worst limit: ranks the motors of a catalogue search
    err.short = _need_text(lim, need, lim.short)
    return err


def _need_text(lim: _Limit, need: float, name: str) -> str:
    """``<name> needs X <unit>, limit Y <unit> (Z % over)``: a violated limit group and by how much."""
    over = f" ({100 * (need / lim.limit - 1):.1f} % over)" if lim.limit else ""
    unit, shown_need, shown_lim = lim.unit, need, lim.limit
    if unit == "m":
        shown_need, shown_lim, unit = need * 1e3, lim.limit * 1e3, "mm"
    unit = "" if unit == "-" else f" {unit}"
    return f"{name} needs {shown_need:.4g}{unit}, limit {shown_lim:.4g}{unit}{over}"


# --------------------------------------------------------------------------- comparison and report


def _stroke_measures(design: "Design", stroke: StrokeFunction, samples: int = 20_001) -> dict:
    """Peak acceleration and jerk over the moves, integrals of a^2 and jerk^2, and (with a drive) torques."""
    problem, spm = design.problem, design.spm
    sch = problem.timing.schedule(spm)
    a_max = j_max = 0.0
    int_a2 = int_j2 = 0.0
    peaks = stroke.piece_peaks(samples=2001)
    for itv, t0, dur, pk in zip(problem.timing.intervals, sch.t_start, sch.duration, peaks):
        if not itv.is_move:
            continue
        a_max = max(a_max, pk.a_max)
        j_max = max(j_max, pk.j_max)
        t = np.linspace(t0, t0 + dur, 2001)[:-1] + dur / 4000
        k = stroke.evaluate(t)
        int_a2 += float(np.sum(k.a**2) * dur / len(t))
        int_j2 += math.inf if math.isinf(pk.j_max) else float(np.sum(k.j**2) * dur / len(t))
    row = {"a_max_m_s2": a_max, "jerk_max_m_s3": j_max, "accel_squared": int_a2, "jerk_squared": int_j2}
    if design.motor_spec is not None and problem.drive is not None:
        from ..drive.checks import drive_checks
        from ..drive.load import load_torque

        drive = _DriveSetup(problem, getattr(problem, "design", None) or DesignSettings())
        trans = drive.transmission(design.pulley_teeth) if design.pulley_teeth else \
            BeltPulley(design.pitch_diameter, inertia=float(drive.pulley_inertia(design.pitch_diameter)))
        k = stroke.sample(samples)
        grooves = design.pulley_teeth if design.pulley_teeth else drive.teeth_range[0]
        found = drive_checks(design.motor_spec, trans, drive.load, k.t, k.s, k.v, k.a, limits=drive.limits,
                             belt=drive.belt, grooves=grooves)
        checks = {c.name: c.value for c in found}
        row["_failed"] = [c.name for c in found if c.name in _ENFORCED and not c.ok]
        tau = load_torque(design.motor_spec, trans, drive.load, k.s, k.v, k.a).total
        moving = np.zeros_like(k.t, dtype=bool)
        for itv, t0, dur in zip(problem.timing.intervals, sch.t_start, sch.duration):
            if itv.is_move:
                moving |= (k.t >= t0) & (k.t <= t0 + dur)
        dt = k.t[1] - k.t[0]
        row.update(peak_torque_N_m=checks["peak_torque"], rms_torque_N_m=checks["rms_torque"],
                   energy=float(np.sum(tau[moving] ** 2) * dt),
                   peak_speed_rpm=checks["peak_speed"])
    return row


_MEASURE_OF = {"min_peak_torque": "peak_torque_N_m", "min_rms_torque": "rms_torque_N_m", "min_energy": "energy",
               "min_peak_accel": "a_max_m_s2", "min_accel_squared": "accel_squared", "min_jerk": "jerk_squared"}


def compare_with_laws(design: "Design", laws=None) -> list[dict]:
    """The optimal stroke against classic laws on the same timing and drive (motor and pulley of the design).

    ``laws``: MotionLaw objects (default: every classic law, the problem's own law with its parameters).
    Each row: law, peak acceleration and jerk, integrals, peak and RMS torque (with a drive), and
    ``vs_optimal_pct``: how much larger the law's value of the design's objective measure is;
    ``feasible`` and ``violates``: whether the law meets the design problem's own constraints (rest
    order, jerk bounds, drive.py's enforced checks on the design's motor and pulley; the laws'
    handover accuracy is not checked) and which it breaks. The optimum comes first, then the
    feasible laws, then the infeasible ones: a law that breaks a constraint does not beat the optimum.
    """
    from ..motion.laws import LAW_NAMES

    problem = design.problem
    if laws is None:
        own = problem.default_law
        laws = [own if name == own.name else make_law(name) for name in LAW_NAMES]
    measure = _MEASURE_OF.get(design.objective)
    settings = design.settings or getattr(problem, "design", None) or DesignSettings()
    opt = {"law": "optimal", **_stroke_measures(design, design.stroke)}
    opt.pop("_failed", None)  # the design's own checks (fine grid) say whether it is feasible
    failed = [c["name"] for c in design.checks if not c["ok"]]
    opt.update(feasible=not failed, violates=failed)
    rows = [opt]
    for law in laws:
        stroke = problem.with_law(law).stroke(design.spm)
        row = {"law": law.label, **_stroke_measures(design, stroke)}
        violates = _law_violations(problem, design.spm, settings, law) + row.pop("_failed", [])
        if law.characteristics.continuity < 2:  # the acceleration jumps at the dwells: the jerk is an impulse
            row.update(jerk_max_m_s3=math.inf, jerk_squared=math.inf)
        row.update(feasible=not violates, violates=violates)
        rows.append(row)
    for r in rows:
        base = opt.get(measure) if measure else None
        val = r.get(measure) if measure else None
        pct = 100.0 * (val / base - 1.0) if base and val is not None and math.isfinite(val) else None
        r["vs_optimal_pct"] = 0.0 if pct is not None and abs(pct) < 1e-6 else pct  # equal up to round-off: 0
    # a law that breaks the problem's constraints does not compete with the optimum: listed last
    return [opt] + [r for r in rows[1:] if r["feasible"]] + [r for r in rows[1:] if not r["feasible"]]


_REST_NAMES = {1: "rest (velocity)", 2: "rest (acceleration)", 3: "rest (jerk)"}


def _law_violations(problem, spm: float, settings: DesignSettings, law) -> list[str]:
    """The constraints of the design problem (rest order, jerk bounds) a classic law breaks on its moves."""
    out = []
    c = law.characteristics
    if c.continuity < settings.rest_order:
        # the first derivative that does not vanish at the dwells (the design holds 1..rest_order at zero)
        out.append(_REST_NAMES[c.continuity + 1])
    c_j = c.C_j
    if settings.rest_order < 2 and math.isinf(c_j):
        # the design itself may jump in acceleration at the dwells (rest_order 1): only the jerk inside counts
        from ..motion.laws import _peak

        inner = law.derivatives([x + d for x in law.breaks for d in (-1e-9, 1e-9)] or [0.5], 2)[2]
        jumps = np.abs(inner[0::2] - inner[1::2]) if law.breaks else np.zeros(1)
        c_j = math.inf if np.max(jumps) > 1e-6 * (c.C_a + 1.0) else _peak(law, 3)
    for mv in _moves(problem, spm, settings):
        if mv.jerk_bound is not None and c_j * mv.j_scale > mv.jerk_bound * (1 + settings.check_tolerance):
            out.append("jerk bound")
            break
    return out


def feasible_text(row: dict) -> str:
    """``yes``, or ``no: `` and the constraints a comparison row breaks."""
    return "yes" if row.get("feasible", True) else "no: " + ", ".join(row.get("violates") or ["?"])


def _pulley_text(design: "Design") -> str:
    return (f"{design.pulley_teeth} teeth" if design.pulley_teeth is not None
            else "continuous radius (design.pulley = \"continuous\": no catalogue tooth count)")


def design_text(design: "Design", comparison: list[dict] | None = None) -> str:
    """A readable account of a design: choices, objective, moves, checks with margins, active constraints."""
    from ..report.format import format_table, format_value

    lines = [f"{design.problem.name}: optimal stroke at {design.spm:g} spm ({design.status}, "
             f"{design.solve_time_s:.2f} s, mesh {design.mesh.intervals} x degree {design.mesh.degree})",
             f"objective {design.objective}: {format_value(design.objective_value)} {design.objective_unit}"]
    if design.motor is not None:
        lines.append(f"motor {design.motor}; pulley {_pulley_text(design)}, pitch diameter "
                     f"{design.pitch_diameter * 1e3:.2f} mm")
    lines.append("")
    lines.append(format_table([m.to_dict() for m in design.moves],
                              [("index", "move"), ("name", "interval"), ("stroke_mm", "stroke mm"),
                               ("direction", "direction"),
                               ("duration_s", "time s"), ("v_max_m_s", "v_max m/s"), ("a_max_m_s2", "a_max m/s2"),
                               ("jerk_max_m_s3", "jerk_max m/s3"), ("C_a", "C_a")]))
    if design.checks:
        lines.append("")
        lines.append(format_table(design.checks, [("name", "check"), ("value", "value"), ("limit", "limit"),
                                                  ("unit", "unit"), ("margin", "margin"), ("ok", "ok")],
                                  title=f"checks (fine grid between collocation nodes; margin = 1 - value/limit; ok: "
                                        f"within the limit + check_tolerance "
                                        f"{100 * (design.settings or DesignSettings()).check_tolerance:g} %)"))
    lines.append("")
    lines.append("active constraints: " + ("; ".join(design.active_constraints) or "none"))
    if comparison:
        cols = [("law", "stroke"), ("a_max_m_s2", "a_max m/s2"), ("jerk_max_m_s3", "jerk_max m/s3")]
        if "peak_torque_N_m" in comparison[0]:
            cols += [("peak_torque_N_m", "peak torque N m"), ("rms_torque_N_m", "RMS torque N m")]
        cols.append(("vs_optimal_pct", f"{design.objective} vs optimal %"))
        cols.append(("feasible_text", "feasible"))
        lines.append("")
        motor = f" with {design.motor}, {_pulley_text(design)}" if design.motor else ""
        shown = [{**r, "feasible_text": feasible_text(r)} for r in comparison]
        lines.append(format_table(shown, cols, title=f"comparison with the classic laws{motor}"))
        if any(not r.get("feasible", True) for r in comparison):
            lines.append("laws marked 'no' break the problem's constraints (listed last): a lower value there "
                         "does not beat the optimum")
        beaten = [r for r in comparison[1:] if r.get("feasible", True) and (r.get("vs_optimal_pct") or 0.0) < 0]
        if beaten:
            lines.append(f"{beaten[0]['law']} is {-beaten[0]['vs_optimal_pct']:.3g} % below the optimal stroke and "
                         f"feasible: the collocation mesh resolves the optimum only to about that accuracy (this "
                         f"law may itself be the exact optimum); `strokeopt solve --study mesh` shows the error "
                         f"against the mesh size")
        if comparison[0].get("peak_torque_N_m") is not None and design.checks and any(
                c["name"].startswith("handover accuracy") for c in design.checks):
            lines.append("feasible: rest order, jerk bound and drive checks; the laws' handover accuracy is not "
                         "checked")
    for note in design.notes:
        lines.append(f"note: {note}")
    return "\n".join(lines)


# --------------------------------------------------------------------------- sweeps and studies


def design_summary(design: "Design") -> dict:
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
                   "direction": _direction(m.stroke)} for m in design.moves],
        "active_constraints": design.active_constraints,
        "solve_time_s": design.solve_time_s,
    }
    full = design.summary()
    for key in ("problem", "problem_file", "cycle_time_s", "pulley_pitch_diameter_mm", "mesh", "checks",
                "iterations", "notes"):
        out[key] = full[key]
    return out


def sweep_design(problem, spms, *, objective: str | None = None, settings: DesignSettings | None = None,
              progress=None) -> list[dict]:
    """Solve at each stitch rate in ``spms`` (ascending), each solve warm-started from the previous.

    Returns one row per rate: ``spm``, ``feasible``, the objective, motor, pulley, peak and RMS torque,
    and for an infeasible rate the reason. ``progress``: a callable wrapping the iterable (tqdm).
    """
    rows = []
    warm = None
    it = progress(list(spms)) if progress is not None else list(spms)
    for spm in it:
        t0 = time.perf_counter()
        try:
            d = solve_design(problem, objective=objective, spm=spm, settings=settings, warm_start=warm)
        except SolverError as exc:
            first, *rest = exc.reason.splitlines()  # the first line says the worst limit; details follow
            rows.append({"spm": float(spm), "feasible": False, "reason": first,
                         **({"details": [r.strip() for r in rest]} if rest else {}),
                         "solve_time_s": time.perf_counter() - t0})
            continue
        warm = d
        if d.status == "limits exceeded":
            rows.append({"spm": float(spm), "feasible": False, "reason": d.notes[0],
                         "solve_time_s": time.perf_counter() - t0})
            continue
        s = design_summary(d)
        rows.append({"spm": float(spm), "feasible": True, "objective_value": d.objective_value,
                     "motor": d.motor, "pulley_teeth": d.pulley_teeth, "peak_torque_N_m": s["peak_torque_N_m"],
                     "rms_torque_N_m": s["rms_torque_N_m"],
                     "a_max_m_s2": max(m.a_max for m in d.moves), "solve_time_s": time.perf_counter() - t0})
    return rows


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
        design = solve_design(problem, objective=objective, spm=spm, settings=settings, mesh=Mesh(n, d))
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
