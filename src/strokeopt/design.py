"""Optimal stroke design by direct collocation.

:func:`solve_design` states the design problem of a :class:`~strokeopt.problem.Problem`
at one stitch rate as one NLP and solves it with IPOPT (through CasADi):

* every move between its fixed dwells is a collocated trajectory (states
  position, velocity, acceleration; control jerk; see :mod:`strokeopt.collocation`),
  rest to rest at the dwell boundaries, the handover position met exactly
  (the move ends at its dwell position, which is a bound, not a penalty);
* the NLP is stated in scaled units (unit stroke, unit time per move, torques
  relative to a reference torque, the radius relative to the file's pulley),
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
      "problem_file": "<path as given>", "problem": "<name>",
      "spm": 600.0, "cycle_time_s": ..., "objective": "min_peak_torque",
      "objective_value": ..., "objective_unit": "N m",
      "status": "optimal", "motor": "<name or null>", "pulley_teeth": 28,
      "pulley_pitch_diameter_mm": ..., "mesh": {"intervals": 40, "degree": 3},
      "moves": [{"index": 1, "interval": 2, "name": ..., "t_start_s": ...,
                 "duration_s": ..., "start_position_mm": ..., "stroke_mm": (signed),
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
from .errors import ProblemError, SolverError
from .laws import make_law
from .stroke import Piece, StrokeFunction, dwell_piece

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
PULLEY_CHOICES = ("fixed", "optimise")

#: Default IPOPT options (plain dict, passed through to CasADi's nlpsol).
DEFAULT_SOLVER_OPTIONS = {
    "expand": True,
    "print_time": False,
    "ipopt.print_level": 0,
    "ipopt.sb": "yes",
    "ipopt.tol": 1e-9,
    "ipopt.max_iter": 500,
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
                          check_points, check_tol, refinements, options)


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
        out.append(_Move(itv.move_index, itv.index, itv.name, float(t0), float(dur), itv.start_position,
                         itv.stroke, bound))
    return out


@dataclass
class _Built:
    """Symbols and bookkeeping of one NLP."""

    w: list = field(default_factory=list)
    lbw: list = field(default_factory=list)
    ubw: list = field(default_factory=list)
    w0: list = field(default_factory=list)
    g: list = field(default_factory=list)
    lbg: list = field(default_factory=list)
    ubg: list = field(default_factory=list)
    groups: list = field(default_factory=list)  # (name, slice in g, scale, limit description)
    n_g: int = 0

    def var(self, name: str, shape, lb, ub, x0) -> ca.MX:
        """A matrix symbol; ``lb``, ``ub``, ``x0`` are scalars or arrays of ``shape``."""
        x = ca.MX.sym(name, *shape)
        self.w.append(ca.vec(x))
        for store, val in ((self.lbw, lb), (self.ubw, ub), (self.w0, x0)):
            arr = np.asarray(val, dtype=float)
            arr = np.broadcast_to(arr.reshape(shape) if arr.size == shape[0] * shape[1] else arr, shape)
            store.append(arr.ravel(order="F").copy())  # ca.vec is column-major
        return x

    def constrain(self, name: str, expr, lb, ub) -> None:
        expr = ca.vec(expr)
        n = expr.shape[0]
        if n == 0:
            return
        self.g.append(expr)
        self.lbg.append(np.broadcast_to(np.asarray(lb, dtype=float), (n,)).copy())
        self.ubg.append(np.broadcast_to(np.asarray(ub, dtype=float), (n,)).copy())
        self.groups.append((name, slice(self.n_g, self.n_g + n)))
        self.n_g += n


def _initial_unit(mesh: Mesh, rest_order: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """A feasible-shaped initial guess: the 3-4-5 polynomial (4-5-6-7 for rest_order 3)."""
    law = make_law("poly7" if rest_order >= 3 else "poly5")
    h = mesh.h
    starts = np.arange(mesh.intervals + 1) * h
    y, y1, _ = law.derivatives(starts, order=2)[:3]
    t_nodes = (np.arange(mesh.intervals).reshape(-1, 1) + mesh.nodes.reshape(1, -1)) * h
    a = law.derivatives(t_nodes.ravel(), order=2)[2].reshape(t_nodes.shape)
    return y, y1, a


@dataclass
class _Context:
    """What the objective and constraint builders see of one NLP."""

    problem: Any
    settings: DesignSettings
    mesh: Mesh
    moves: list
    vars: list  # MoveVariables per move
    built: _Built
    extra: dict = field(default_factory=dict)

    def si_nodes(self, m: int, kind: str) -> ca.MX:
        """Values at every node (N x (d+1)) of move ``m`` in SI units: s [m], v, a, j."""
        mv, x = self.moves[m], self.vars[m]
        unit = x.at(self.mesh.nodes, kind)
        if kind == "s":
            return mv.start + mv.stroke * unit
        return unit * (mv.stroke / mv.duration ** {"v": 1, "a": 2, "j": 3}[kind])


def _build(problem, spm: float, settings: DesignSettings, mesh: Mesh, objective: str, warm: list | None):
    moves = _moves(problem, spm, settings)
    b = _Built()
    xs = []
    n, d = mesh.intervals, mesh.degree
    for k, mv in enumerate(moves):
        if warm is not None and k < len(warm) and warm[k].mesh == mesh:
            y0, v0, A = warm[k].S, warm[k].V, warm[k].A
            a_init = A[:, 1:]
            a0_init = A[0, 0]
        else:
            y0, v0, a_nodes = _initial_unit(mesh, settings.rest_order)
            a_init, a0_init = a_nodes[:, 1:], a_nodes[0, 0]
        s_lb = np.full(n + 1, -np.inf)
        s_ub = np.full(n + 1, np.inf)
        s_lb[0] = s_ub[0] = 0.0
        s_lb[-1] = s_ub[-1] = 1.0  # the end position is met exactly (the handover, for the handover move)
        v_lb = np.full(n + 1, -np.inf)
        v_ub = np.full(n + 1, np.inf)
        v_lb[[0, -1]] = v_ub[[0, -1]] = 0.0
        S = b.var(f"S{mv.index}", (n + 1, 1), s_lb, s_ub, y0)
        V = b.var(f"V{mv.index}", (n + 1, 1), v_lb, v_ub, v0)
        rest = 0.0 if settings.rest_order >= 2 else None
        a0 = b.var(f"a0_{mv.index}", (1, 1), -np.inf if rest is None else 0.0, np.inf if rest is None else 0.0,
                   0.0 if rest is not None else a0_init)
        a_lb = np.full((n, d), -np.inf)
        a_ub = np.full((n, d), np.inf)
        if rest is not None:
            a_lb[-1, -1] = a_ub[-1, -1] = 0.0
        Acol = b.var(f"A{mv.index}", (n, d), a_lb, a_ub, a_init)
        xs.append(MoveVariables(mesh, S, V, a0, Acol))
        b.constrain(f"move {mv.index} collocation", xs[-1].defects(), 0.0, 0.0)
        if settings.rest_order >= 3:
            j_ends = ca.vertcat(xs[-1].at([0.0], "j")[0, 0], xs[-1].at([1.0], "j")[-1, 0])
            b.constrain(f"move {mv.index} rest (jerk)", j_ends, 0.0, 0.0)
        if settings.rest_order >= 3 or objective == "min_snap":
            b.constrain(f"move {mv.index} jerk continuity", xs[-1].jerk_joints(), 0.0, 0.0)
        if mv.jerk_bound is not None:
            jb = mv.jerk_bound / mv.j_scale  # bound on the unit jerk
            b.constrain(f"jerk bound move {mv.index}", xs[-1].hull("j") / jb, -1.0, 1.0)
    ctx = _Context(problem, settings, mesh, moves, xs, b)
    f = _objective(ctx, objective)
    return ctx, f


def _objective(ctx: _Context, objective: str):
    """The scaled objective expression; records in ctx.extra how to turn it back into SI."""
    moves, xs, b = ctx.moves, ctx.vars, ctx.built
    if objective == "min_peak_accel":
        a_ref = max(mv.a_scale for mv in moves)
        z = b.var("peak_accel", (1, 1), 0.0, np.inf, 6.0 * max(mv.a_scale for mv in moves) / a_ref)
        for mv, x in zip(moves, xs):
            ratio = mv.a_scale / a_ref
            a = ratio * x.hull("a")  # bounds the acceleration everywhere, not only at the nodes
            b.constrain(f"peak accel epigraph move {mv.index}", ca.vertcat(ca.vec(z - a), ca.vec(z + a)), 0.0, np.inf)
        ctx.extra.update(scale=a_ref, unit="m/s^2")
        return z
    if objective in ("min_accel_squared", "min_jerk", "min_snap"):
        kind, power = {"min_accel_squared": ("a", 3), "min_jerk": ("j", 5), "min_snap": ("snap", 7)}[objective]
        # integral over the move of (stroke/T^p * y^(k))^2 dt = stroke^2 / T^(2p-1) * integral over unit time
        weights = [mv.stroke**2 / mv.duration**power for mv in moves]
        ref = max(weights)
        total = sum((w / ref) * x.integral(kind) for w, x in zip(weights, xs))
        unit = {"a": "m^2/s^3", "j": "m^2/s^5", "snap": "m^2/s^7"}[kind]
        ctx.extra.update(scale=ref, unit=unit)
        return total
    raise ProblemError(str(ctx.problem.file), "design.objective",
                       f"objective {objective!r} needs the drive model (load torque); it is not available here")


def _solver_options(settings: DesignSettings, extra: dict | None, verbose: bool) -> dict:
    opts = dict(DEFAULT_SOLVER_OPTIONS)
    if verbose:
        opts.update({"ipopt.print_level": 5, "print_time": True})
        opts.pop("ipopt.sb", None)
    opts.update(settings.solver_options)
    opts.update(extra or {})
    return opts


def _solve_nlp(ctx: _Context, f, options: dict):
    b = ctx.built
    w = ca.vertcat(*b.w)
    g = ca.vertcat(*b.g)
    opts = dict(options)
    plugin = opts.pop("plugin", "ipopt")
    solver = ca.nlpsol("design", plugin, {"x": w, "f": f, "g": g}, opts)
    sol = solver(x0=np.concatenate(b.w0), lbx=np.concatenate(b.lbw), ubx=np.concatenate(b.ubw),
                 lbg=np.concatenate(b.lbg), ubg=np.concatenate(b.ubg))
    stats = solver.stats()
    return sol, stats


def _unpack(ctx: _Context, x: np.ndarray) -> list[MoveSolution]:
    """Numeric MoveSolutions from the solution vector (same order as the variables were created)."""
    out = []
    n, d = ctx.mesh.intervals, ctx.mesh.degree
    fn = ca.Function("unpack", [ca.vertcat(*ctx.built.w)],
                     [ca.vertcat(*[ca.vertcat(x_.S, x_.V, ca.vec(x_.A)) for x_ in ctx.vars])])
    flat = np.asarray(fn(x)).ravel()
    size = 2 * (n + 1) + n * (d + 1)
    for k in range(len(ctx.vars)):
        chunk = flat[k * size:(k + 1) * size]
        S = chunk[: n + 1]
        V = chunk[n + 1: 2 * (n + 1)]
        A = chunk[2 * (n + 1):].reshape(d + 1, n).T  # ca.vec is column-major
        out.append(MoveSolution(ctx.mesh, S, V, A))
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
            "start_position_mm": self.start * 1e3, "stroke_mm": self.stroke * 1e3,
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
            "problem_file": str(self.problem.file),
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
        from .report import to_json

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
                pieces.append(move_piece(t0, dur, pos, m["stroke_mm"] * 1e-3, sol, f"{itv['name']}: optimal"))
            else:
                pieces.append(dwell_piece(t0, dur, pos, itv["name"]))
        stroke = StrokeFunction(float(data["cycle_time_s"]), pieces, label="optimal")
    except (KeyError, TypeError, ValueError) as exc:
        raise ProblemError(str(path), "", f"design file is incomplete or malformed: {exc!r}") from None
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


def solve_design(problem, *, objective: str | None = None, spm: float | None = None,
                 settings: DesignSettings | None = None, mesh: Mesh | None = None, warm_start=None,
                 solver_options: dict | None = None, verbose: bool = False) -> Design:
    """Solve the design problem of ``problem`` at ``spm`` (default: the file's).

    ``objective`` overrides ``[design] objective``; ``mesh`` overrides its mesh;
    ``warm_start`` is a previous :class:`Design` (or its move solutions) to start from;
    ``solver_options`` are passed to ``casadi.nlpsol`` over the defaults.
    """
    settings = settings or getattr(problem, "design", None) or DesignSettings()
    objective = objective or settings.objective
    if objective not in OBJECTIVES:
        raise ProblemError("--objective", "", f"{objective!r} is not one of {', '.join(OBJECTIVES)}")
    spm = float(spm if spm is not None else problem.spm)
    mesh = mesh or settings.mesh
    warm = warm_start.solutions if isinstance(warm_start, Design) else warm_start
    options = _solver_options(settings, solver_options, verbose)
    total_time = 0.0
    iterations = 0
    for attempt in range(settings.refinements + 1):
        t0 = time.perf_counter()
        ctx, f = _build(problem, spm, settings, mesh, objective, warm)
        sol, stats = _solve_nlp(ctx, f, options)
        total_time += time.perf_counter() - t0
        iterations += int(stats.get("iter_count", 0))
        status = stats.get("return_status", "unknown")
        if status not in _STATUS_OK:
            raise _diagnose(problem, spm, settings, mesh, objective, ctx, status, options)
        sols = _unpack(ctx, np.asarray(sol["x"]).ravel())
        report, _ = _fine_grid_report(ctx.moves, sols, settings.check_points)
        if report["worst_relative_violation"] <= settings.check_tolerance or attempt == settings.refinements:
            break
        mesh = Mesh(mesh.intervals * 2, mesh.degree)
        warm = None
    value = float(sol["f"]) * ctx.extra["scale"]
    stroke = stroke_from_solutions(problem, spm, sols, label=f"optimal ({objective})")
    moves = _move_results(ctx.moves, sols)
    design = Design(problem, spm, objective, value, ctx.extra["unit"], stroke, moves, mesh,
                    "optimal" if status == "Solve_Succeeded" else "acceptable", total_time, iterations,
                    fine_grid=report)
    design.checks, design.active_constraints = _kinematic_checks(ctx, moves, report)
    if report["worst_relative_violation"] > settings.check_tolerance:
        design.notes.append(f"between collocation nodes a bound is exceeded by "
                            f"{100 * report['worst_relative_violation']:.2f} % (more than check_tolerance): "
                            f"use more mesh intervals")
    return design


def _kinematic_checks(ctx: _Context, moves: list[MoveResult], report: dict) -> tuple[list[dict], list[str]]:
    checks, active = [], []
    for mv, row in zip(ctx.moves, report["moves"]):
        if mv.jerk_bound is not None:
            value = row["jerk_max_fine_m_s3"]
            margin = 1.0 - value / mv.jerk_bound
            checks.append({"name": f"jerk move {mv.index}", "value": value, "limit": mv.jerk_bound,
                           "unit": "m/s^3", "margin": margin, "ok": margin >= -ctx.settings.check_tolerance})
            if margin < 1e-3:
                active.append(f"jerk bound move {mv.index}")
    for mv in ctx.moves:
        if ctx.problem.timing.intervals[mv.interval - 1].handover:
            active.append(f"handover position (end of move {mv.index}, {mv.start + mv.stroke:+.4g} m, exact)")
    return checks, active


def _diagnose(problem, spm, settings, mesh, objective, ctx, status, options) -> SolverError:
    """Why a solve failed: relax each bound in turn and report what it would need."""
    for mv in ctx.moves:
        if mv.jerk_bound is None:
            continue
        relaxed = replace(settings, jerk_max=None, jerk_max_from_law=False)
        one = replace(problem)  # the same problem; only the move's need is read
        need = _min_peak_jerk(one, spm, relaxed, mesh, mv)
        if need > mv.jerk_bound * (1 + 1e-6):
            return SolverError(f"move {mv.index} ({mv.name}) too short for the jerk bound at {spm:g} spm: needs "
                               f"{need:.4g} m/s^3, bound {mv.jerk_bound:.4g} m/s^3 "
                               f"({100 * (need / mv.jerk_bound - 1):.1f} % over)")
    return SolverError(f"the design problem at {spm:g} spm could not be solved (IPOPT: {status}); "
                       f"no single bound explains it: try more mesh intervals or --verbose")


def _min_peak_jerk(problem, spm, settings, mesh, mv: _Move) -> float:
    """Smallest achievable peak |jerk| [m/s^3] of one move under the rest conditions (unit problem, then scaled)."""
    b = _Built()
    n, d = mesh.intervals, mesh.degree
    y0, v0, a_nodes = _initial_unit(mesh, settings.rest_order)
    s_lb, s_ub = np.full(n + 1, -np.inf), np.full(n + 1, np.inf)
    s_lb[0] = s_ub[0] = 0.0
    s_lb[-1] = s_ub[-1] = 1.0
    v_lb, v_ub = np.full(n + 1, -np.inf), np.full(n + 1, np.inf)
    v_lb[[0, -1]] = v_ub[[0, -1]] = 0.0
    S = b.var("S", (n + 1, 1), s_lb, s_ub, y0)
    V = b.var("V", (n + 1, 1), v_lb, v_ub, v0)
    rest = settings.rest_order >= 2
    a0 = b.var("a0", (1, 1), 0.0 if rest else -np.inf, 0.0 if rest else np.inf, 0.0)
    a_lb, a_ub = np.full((n, d), -np.inf), np.full((n, d), np.inf)
    if rest:
        a_lb[-1, -1] = a_ub[-1, -1] = 0.0
    Acol = b.var("A", (n, d), a_lb, a_ub, a_nodes[:, 1:])
    x = MoveVariables(mesh, S, V, a0, Acol)
    b.constrain("collocation", x.defects(), 0.0, 0.0)
    z = b.var("z", (1, 1), 0.0, np.inf, 60.0)
    j = x.hull("j")
    b.constrain("epigraph", ca.vertcat(ca.vec(z - j), ca.vec(z + j)), 0.0, np.inf)
    ctx = _Context(problem, settings, mesh, [mv], [x], b)
    sol, stats = _solve_nlp(ctx, z, dict(DEFAULT_SOLVER_OPTIONS))
    return float(sol["f"]) * mv.j_scale
