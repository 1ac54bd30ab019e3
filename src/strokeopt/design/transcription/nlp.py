"""The NLP of one solve: the builder (:class:`Built`), the built structure (:class:`Graph`),
the bounded cache of built structures (:class:`NlpCache`) and one solve's numbers (:class:`Nlp`).

Third step of the design's flow (:mod:`.request` -> nlp -> :mod:`.solver` -> :mod:`.refine`).
The symbolic NLP (and its solver, with the costly derivatives) is built once per structure
(:func:`structure_key`): the moves (:func:`add_moves`, collocation of :mod:`.collocation`), the
drive's load model and limits (:mod:`.limits`) and the objective (:mod:`.objectives`).
Everything that changes between solves of one structure (speed, motor, pulley, pinned points,
warm start) is a parameter value, a bound or a start value, each a function of the solve's
:class:`~.request.SolveRequest`.
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace
from typing import Any

import casadi as ca
import numpy as np

from .collocation import MoveSolution, MoveVariables
from .contact_limits import CONTACT_LIMITS
from .free import build_free
from .limits import MOVE_LIMITS, LimitGroup, Terms, build_drive, collect, gathered
from .objectives import TIME_SCALE, TIME_SCALE_BOUNDS, build_objective, free_time, objective_of
from .pins import initial_pin_times, pin_intervals, pin_windows, pins_fit
from .request import SolveRequest, initial_unit


def _number(value, req) -> np.ndarray:
    """A bound, start value or parameter of the NLP: a number, or a function of the solve's request."""
    return np.asarray(value(req) if callable(value) else value, dtype=float)


@dataclass
class Numbers:
    """What one solve gives a built NLP: parameter values, start point and bounds."""

    p: np.ndarray
    x0: np.ndarray
    lbx: np.ndarray
    ubx: np.ndarray
    lbg: np.ndarray
    ubg: np.ndarray


@dataclass
class Built:
    """Symbols of one NLP structure, and how each solve's numbers are found.

    The symbolic NLP (and its solver, with the costly derivatives) is built once per
    structure (:func:`structure_key`); everything that changes between solves of
    one structure (speed, motor, pulley, pinned points, warm start) is a parameter
    value, a bound or a start value, each given as a function of the solve's
    :class:`~.request.SolveRequest` and evaluated by :meth:`numbers`.
    """

    relaxed: bool = False
    w: list = field(default_factory=list)
    vars: list = field(default_factory=list)  # (shape, lb, ub, x0): numbers or functions of the request
    g: list = field(default_factory=list)
    cons: list = field(default_factory=list)  # (size, lb, ub)
    limits: list = field(default_factory=list)  # (LimitGroup, slack symbol or None)
    limit_exprs: list = field(default_factory=list)  # the scaled expressions (<= 0) of the limit groups
    offsets: dict = field(default_factory=dict)  # variable name -> (offset, size) in the decision vector
    p: list = field(default_factory=list)  # parameters: numbers that change between solves of one structure
    p_values: list = field(default_factory=list)  # (function of the request, shape)
    n_w: int = 0
    n_g: int = 0

    def param(self, name: str, value) -> ca.MX:
        """A number the NLP takes as a parameter, ``value(req)`` for each solve: one built solver serves many."""
        return self.params(name, value, (1, 1))

    def params(self, name: str, value, shape: tuple[int, int]) -> ca.MX:
        """A matrix of parameters of ``shape``, ``value(req)`` for each solve."""
        if not callable(value):
            raise TypeError(f"parameter {name!r}: give a function of the solve's request, not a number "
                            f"(a number would be frozen into the built solver)")
        sym = ca.MX.sym(name, shape[0] * shape[1])
        self.p.append(sym)
        self.p_values.append((value, shape))
        return ca.reshape(sym, *shape)

    def var(self, name: str, shape, lb, ub, x0) -> ca.MX:
        """A matrix symbol; ``lb``, ``ub``, ``x0`` are scalars or arrays of ``shape``, or functions of the request."""
        x = ca.MX.sym(name, *shape)
        self.w.append(ca.vec(x))
        self.offsets[name] = (self.n_w, shape[0] * shape[1])
        self.n_w += shape[0] * shape[1]
        self.vars.append((tuple(shape), lb, ub, x0))
        return x

    def constrain(self, name: str, expr, lb, ub) -> None:
        """Rows ``lb <= expr <= ub``; the bounds are numbers or functions of the request."""
        expr = ca.vec(expr)
        n = expr.shape[0]
        if n == 0:
            return
        self.g.append(expr)
        self.cons.append((n, lb, ub))
        self.n_g += n

    def numbers(self, req) -> Numbers:
        """Parameter values, start point and bounds of one solve."""
        pv = []
        for (fn, shape), sym in zip(self.p_values, self.p):
            val = _number(fn, req)
            if val.size != sym.numel():
                raise ValueError(f"parameter {sym.name()} has {val.size} values, built with {sym.numel()}")
            pv.append(val.reshape(shape).ravel(order="F") if val.ndim == 2 else val.ravel())
        xs = ([], [], [])
        for shape, *vals in self.vars:
            for store, val in zip(xs, vals):
                arr = _number(val, req)
                arr = np.broadcast_to(arr.reshape(shape) if arr.size == shape[0] * shape[1] else arr, shape)
                store.append(arr.ravel(order="F"))  # ca.vec is column-major
        gs = ([], [])
        for n, *vals in self.cons:
            for store, val in zip(gs, vals):
                store.append(np.broadcast_to(_number(val, req), (n,)))
        cat = (lambda parts: np.concatenate(parts) if parts else np.zeros(0))
        return Numbers(cat(pv), cat(xs[2]), cat(xs[0]), cat(xs[1]), cat(gs[0]), cat(gs[1]))

    def limit_abs(self, lim: LimitGroup, expr) -> None:
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

    def limit(self, lim: LimitGroup, expr) -> None:
        """``expr <= 0`` (scaled); in a relaxed build ``expr <= sigma``, ``sigma >= 0`` minimised."""
        slack = None
        self.limit_exprs.append(ca.vec(expr))
        if self.relaxed:
            slack = self.var(f"slack {lim.name}", (1, 1), 0.0, np.inf, 0.0)
            expr = expr - slack
        self.constrain(lim.name, expr, -np.inf, lambda c: 0.0 if lim.is_enforced(c) else np.inf)
        self.limits.append((lim, slack))


@dataclass
class Graph:
    """One built NLP structure: the symbols, the objective, what the builders name, its solvers by options.

    ``request`` is the request it was built for (its problem, mesh and moves fix the structure);
    the builders of :mod:`.limits` and :mod:`.objectives` fill the named expressions.
    """

    request: SolveRequest
    built: Built
    pins: tuple = ()  # the pins' windows (move, switch position, first mesh interval or None)
    vars: list = field(default_factory=list)  # MoveVariables per move
    T: list = field(default_factory=list)  # move durations (parameters, times the time scale)
    #: the cycle time relative to the request's (1.0; a decision variable of a free-time objective)
    time_scale: Any = 1.0
    f: Any = None  # the expression the solver minimises (the cost's, or the relaxed build's slack sum)
    cost: Any = None  # the objective's Cost (objectives.py): its measure, unit and transform to SI
    solvers: dict = field(default_factory=dict)
    # the drive (see limits.build_drive): its radius, motor and torques are the DriveModel's
    drive_model: Any = None
    #: what the limit builders return beside their rows, gathered once (limits.Terms: the torque squared, the
    #: pinned points, the handover error)
    terms: Terms = Terms()
    pin_motions: dict = field(default_factory=dict)  # (move, position) -> (weight, v, a) at the pin (pins.pin_motion)
    crossings: set = field(default_factory=set)  # (move, position) of the pins whose crossing time is a variable
    load: Any = None  # the drive's load, with the free model parameters in it (free.build_free)
    free_stiffness: dict = field(default_factory=dict)  # element name -> stiffness symbol (free.build_free)
    #: the problem's own transmission with its free fields (free.build_free); None on a belt
    transmission: Any = None
    free_fields: dict = field(default_factory=dict)  # transmission field -> its symbol, the file's unit (free.py)

    @property
    def problem(self):
        return self.request.problem

    def si(self, m: int, theta, kind: str) -> ca.MX:
        """Values of move ``m`` at local points ``theta`` of every interval (N x len(theta)) in SI units."""
        mv, x = self.request.moves[m], self.vars[m]
        unit = x.at(theta, kind)
        if kind == "s":
            return mv.start + mv.stroke * unit
        return unit * (mv.stroke / self.T[m] ** {"v": 1, "a": 2, "j": 3}[kind])


def add_moves(g: Graph) -> None:
    """The collocated moves: position, velocity, acceleration at rest at both ends, the end met exactly."""
    b, req = g.built, g.request
    settings, mesh, moves = req.settings, req.mesh, req.moves
    n, d = mesh.intervals, mesh.degree
    if free_time(req.objective):  # every duration is the cycle time times its fixed fraction of the cycle
        g.time_scale = b.var(TIME_SCALE, (1, 1), lambda r: 1.0 if r.rate_cap else TIME_SCALE_BOUNDS[0],
                             TIME_SCALE_BOUNDS[1], 1.0)
    if not req.free_spans:
        g.T = [b.param(f"T{mv.index}", lambda r, k=k: r.moves[k].duration) * g.time_scale
               for k, mv in enumerate(moves)]
    else:  # max_duration: every move's time a variable, their sum the request's (the dwells keep theirs)
        g.T = [b.var(f"T{mv.index} free", (1, 1), lambda r, k=k: max(0.05 * r.moves[k].duration, 1e-4),
                     lambda r: r.period, lambda r, k=k: r.moves[k].duration) for k, mv in enumerate(moves)]
        b.constrain("moves' times", sum(g.T) - b.param("moves' time", lambda r: sum(m.duration for m in r.moves)),
                    0.0, 0.0)
    for k, mv in enumerate(moves):
        s_lb, s_ub = np.full(n + 1, -np.inf), np.full(n + 1, np.inf)
        s_lb[0] = s_ub[0] = 0.0
        s_lb[-1] = s_ub[-1] = 1.0  # the end position is met exactly (the handover, for the handover move)
        v_lb, v_ub = np.full(n + 1, -np.inf), np.full(n + 1, np.inf)
        at_rest = [i for i, speed in ((0, mv.start_speed), (-1, mv.end_speed)) if not speed]  # an end at speed: free
        v_lb[at_rest] = v_ub[at_rest] = 0.0
        S = b.var(f"S{mv.index}", (n + 1, 1), s_lb, s_ub, lambda r, k=k: r.start[k][0])
        V = b.var(f"V{mv.index}", (n + 1, 1), v_lb, v_ub, lambda r, k=k: r.start[k][1])
        rest = settings.rest_order >= 2
        rest0 = rest and not mv.start_speed
        a0 = b.var(f"a0_{mv.index}", (1, 1), 0.0 if rest0 else -np.inf, 0.0 if rest0 else np.inf,
                   0.0 if rest0 else (lambda r, k=k: r.start[k][2][0, 0]))
        a_lb, a_ub = np.full((n, d), -np.inf), np.full((n, d), np.inf)
        if rest and not mv.end_speed:
            a_lb[-1, -1] = a_ub[-1, -1] = 0.0
        Acol = b.var(f"A{mv.index}", (n, d), a_lb, a_ub, lambda r, k=k: r.start[k][2][:, 1:])
        x = MoveVariables(mesh, S, V, a0, Acol)
        g.vars.append(x)
        b.constrain(f"move {mv.index} collocation", x.defects(), 0.0, 0.0)
        if settings.monotonic:  # the unit speed (the stroke's direction) never below zero, everywhere
            b.constrain(f"move {mv.index} direction", x.hull("v"), 0.0, np.inf)
        ends = [e for e, speed in ((x.at([0.0], "j")[0, 0], mv.start_speed), (x.at([1.0], "j")[-1, 0], mv.end_speed))
                if not speed]
        if settings.rest_order >= 3 and ends:
            b.constrain(f"move {mv.index} rest (jerk)", ca.vertcat(*ends), 0.0, 0.0)
        if settings.rest_order >= 3 or objective_of(req.objective).jerk_continuous:
            b.constrain(f"move {mv.index} jerk continuity", x.jerk_joints(), 0.0, 0.0)
        for lim in MOVE_LIMITS:
            lim.on_move(g, k)
    add_speed_joints(g)


def add_speed_joints(g: Graph) -> None:
    """Where a move ends at speed (timing: end = "speed"), the next move (cyclically) starts with the same speed,
    and with the same acceleration (rest order 2) and jerk (rest order 3) as the design holds them at a dwell:
    each derivative in SI, over the larger of the two moves' scales."""
    moves, order = g.request.moves, g.request.settings.rest_order
    for k, mv in enumerate(moves):
        if not mv.end_speed:
            continue
        j = (k + 1) % len(moves)
        nxt = moves[j]
        rows = []
        for power, kind in ((1, "v"), (2, "a"), (3, "j"))[:max(order, 1)]:
            end = g.vars[k].at([1.0], kind)[-1, 0] * mv.stroke / g.T[k] ** power
            start = g.vars[j].at([0.0], kind)[0, 0] * nxt.stroke / g.T[j] ** power
            scale = ca.fmax(abs(mv.stroke) / g.T[k] ** power, abs(nxt.stroke) / g.T[j] ** power)
            rows.append((end - start) / scale)
        g.built.constrain(f"move {mv.index} -> move {nxt.index} at speed", ca.vertcat(*rows), 0.0, 0.0)


def build_graph(req: SolveRequest, pins: tuple) -> Graph:
    """Build the symbolic NLP of ``req``'s structure."""
    g = Graph(req, Built(relaxed=req.relaxed), pins)
    add_moves(g)
    build_free(g)
    terms = build_drive(g) if req.drive is not None else {}
    for lim in CONTACT_LIMITS:
        collect(terms, lim.on_cycle(g, terms))
    g.terms = gathered(terms)
    g.cost = build_objective(g)
    f = g.cost.f
    if g.built.relaxed:
        f = sum(s for _, s in g.built.limits if s is not None) * 1e3 + 1e-6 * f
    g.f = f
    return g


def structure_key(req: SolveRequest) -> tuple:
    """What fixes the NLP's structure besides the problem: solves that share it share one built NLP and
    solver (their numbers differ). The error terms enter by type and parameters (they compare by value)."""
    choice = req.choice
    return (repr(req.settings), req.mesh, req.objective, req.free_spans, req.relaxed, tuple(req.error_terms),
            req.enforce_accuracy, tuple((mv.jerk_bound is None, mv.start_speed, mv.end_speed) for mv in req.moves),
            None if choice is None else tuple(m.name for m in choice.candidates),
            req.drive is not None and req.drive.belt is None)


class NlpCache:
    """Built NLP structures by :func:`structure_key`, at most ``size`` of them (the oldest key goes first).

    A structure serves only the problem object it was built for (it holds it, so the identity
    test is safe) and pinned points that lie in its pin windows; one key may hold several.
    """

    def __init__(self, size: int = 16):
        self.size = size
        self._graphs: dict = {}  # structure key -> [Graph]

    def find(self, key: tuple, problem, crossings: list, mesh) -> Graph | None:
        return next((g for g in self._graphs.get(key, [])
                     if g.problem is problem and pins_fit(g.pins, crossings, mesh)), None)

    def add(self, key: tuple, graph: Graph) -> None:
        if len(self) >= self.size:
            self._graphs.pop(next(iter(self._graphs)))
        self._graphs.setdefault(key, []).append(graph)

    def clear(self) -> None:
        self._graphs.clear()

    def __len__(self) -> int:
        return sum(len(gs) for gs in self._graphs.values())


#: The built structures of this process (bounded: see NlpCache).
NLP_CACHE = NlpCache()


def clear_cache() -> None:
    """Forget every built NLP and solver (a benchmark times builds with this)."""
    NLP_CACHE.clear()


@dataclass
class Nlp:
    """One solve's NLP: its request, the built structure that serves it and the numbers of this solve."""

    request: SolveRequest
    graph: Graph
    numbers: Numbers

    @property
    def built(self) -> Built:
        return self.graph.built

    def value(self, expr, x: np.ndarray) -> np.ndarray:
        """Numeric value of an expression of the NLP's variables and parameters at ``x``."""
        b = self.graph.built
        fn = ca.Function("value", [ca.vertcat(*b.w), ca.vertcat(*b.p)], [expr])
        return np.asarray(fn(x, self.numbers.p))

    def unpack(self, x: np.ndarray) -> list[MoveSolution]:
        """Numeric MoveSolutions from the solution vector."""
        out = []
        mesh = self.request.mesh
        n, d = mesh.intervals, mesh.degree
        flat = self.value(ca.vertcat(*[ca.vertcat(x_.S, x_.V, ca.vec(x_.A)) for x_ in self.graph.vars]), x).ravel()
        size = 2 * (n + 1) + n * (d + 1)
        for k in range(len(self.graph.vars)):
            chunk = flat[k * size:(k + 1) * size]
            A = chunk[2 * (n + 1):].reshape(d + 1, n).T  # ca.vec is column-major
            out.append(MoveSolution(mesh, chunk[: n + 1], chunk[n + 1: 2 * (n + 1)], A))
        return out

    def limit_values(self, x: np.ndarray) -> list[float]:
        """Largest scaled residual (``expr``, satisfied when <= 0) of every limit group at ``x``."""
        exprs = self.graph.built.limit_exprs
        if not exprs:
            return []
        return [float(v) for v in self.value(ca.vertcat(*[ca.mmax(e) for e in exprs]), x).ravel()]


def prepare(req: SolveRequest, cache: NlpCache = NLP_CACHE) -> Nlp:
    """The NLP of one solve: the built structure (from the cache when one fits) and this solve's numbers."""
    mesh = req.mesh
    pin_times = dict(req.pin_times or {})
    pinned = req.drive is not None or req.contact is not None
    if pinned and req.pin_times is None and req.warm is None:
        y0, v0, a_nodes = initial_unit(mesh, req.settings.rest_order)
        pin_times = initial_pin_times(req, [MoveSolution(mesh, y0, v0, a_nodes)] * len(req.moves))
    if pinned and req.pin_times is None and req.warm is not None and all(w.mesh == mesh
                                                                                          for w in req.warm):
        pin_times = initial_pin_times(req, req.warm)
    req = replace(req, pin_times=pin_times)
    crossings = pin_intervals(req) if pinned else []
    key = structure_key(req)
    graph = cache.find(key, req.problem, crossings, mesh)
    if graph is None:
        graph = build_graph(req, pin_windows(crossings, mesh))
        if not req.relaxed:  # a relaxed build names the motor in its limits: built for the one diagnosis
            cache.add(key, graph)
    return Nlp(req, graph, graph.built.numbers(req))
