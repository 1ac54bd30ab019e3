"""The objectives of the design: one function per objective, in :data:`REGISTRY`.

Each builder takes the :class:`~.nlp.Graph` under construction (after the moves and the drive's
limits, :mod:`.limits`), adds the variables and rows its form needs (an epigraph) and returns its
:class:`Cost`: the scaled expression the solver minimises, what it measures without the smoothing term,
and how to turn that value back into SI. It writes nothing else on the graph. Read by :mod:`.settings`
(the choices of ``[design] objective``) and :mod:`.nlp`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, Callable

import casadi as ca
import numpy as np

from ...errors import ProblemError
from ...io.load_units import error_unit

#: Weight of the jerk-squared regularisation added to epigraph (peak) objectives.
SMOOTHING = 1e-7

#: The decision variable of a free-time objective: the cycle time relative to the request's (every
#: interval keeps its fixed fraction of the cycle), and its bounds (one solve may move the rate 4x).
TIME_SCALE = "time scale"
TIME_SCALE_BOUNDS = (0.25, 4.0)


@dataclass(frozen=True)
class Cost:
    """What an objective builder returns: ``f``, the scaled expression the solver minimises; ``measure``, the
    objective without its smoothing term (None: ``f`` itself); ``unit`` and ``transform`` (scaled value,
    request -> SI value) of the number the design reports."""

    f: Any
    unit: str
    transform: Callable
    measure: Any = None


def _smoothing(g):
    """A tiny integral of jerk squared (unit form, relative to the 3-4-5 law's 720 per move).

    A peak objective is set by one move; without this the moves that do not set the peak could
    take any feasible shape. It changes the peak by far less than the solver tolerance matters.
    """
    return SMOOTHING * sum(x.integral("j") for x in g.vars) / 720.0


def min_peak_accel(g):
    moves, b = g.request.moves, g.built
    a_ref = max(mv.a_scale for mv in moves)
    z = b.var("peak_accel", (1, 1), 0.0, np.inf, 6.0 * max(mv.a_scale for mv in moves) / a_ref)
    for mv, x, T in zip(moves, g.vars, g.T):
        a = (abs(mv.stroke) / T**2 / a_ref) * x.hull("a")  # bounds the acceleration everywhere, not only at the nodes
        b.constrain(f"peak accel epigraph move {mv.index}", ca.vertcat(ca.vec(z - a), ca.vec(z + a)), 0.0, np.inf)
    return Cost(z + _smoothing(g), _load_unit(g, "m/s^2"), lambda f, r: f * a_ref, z)


def _load_unit(g, unit: str) -> str:
    """A kinematic objective's unit for the load: rad where a rotary load's positions are angles."""
    return unit.replace("m", "rad", 1) if g.problem.timing.rotary else unit


def _integral_objective(kind: str, power: int, unit: str):
    """The integral over the moves of the squared ``kind`` derivative."""

    def build(g):
        moves = g.request.moves
        # integral over the move of (stroke/T^p * y^(k))^2 dt = stroke^2 / T^(2p-1) * integral over unit time
        ref = max(mv.stroke**2 / mv.duration**power for mv in moves)
        total = sum((mv.stroke**2 / T**power / ref) * x.integral(kind) for mv, x, T in zip(moves, g.vars, g.T))
        return Cost(total, _load_unit(g, unit), lambda f, r: f * ref)

    return build


def min_peak_torque(g):
    # The epigraph bound is one value, held as a chain of equal copies, one per mesh interval:
    # a single variable in every epigraph row would be a dense Jacobian column, which together
    # with a dense row (an accuracy term summing over the whole move) makes CasADi's
    # derivative generation slow.
    b, mesh, moves = g.built, g.request.mesh, g.request.moves
    tau_ref = g.drive_model.tau_ref
    n = mesh.intervals
    Z = b.var("peak_torque", (n * len(moves) + 1, 1), 0.0, np.inf, 1.0)
    b.constrain("peak torque chain", Z[1:] - Z[:-1], 0.0, 0.0)
    d1 = mesh.degree + 1
    for k, (mv, tau) in enumerate(zip(moves, g.drive_model.torques)):
        zk = Z[k * n:(k + 1) * n]
        zrow = ca.horzcat(ca.repmat(zk, d1, 1).T, ca.repmat(zk[0], 1, tau.shape[1] - n * d1))
        b.constrain(f"peak torque epigraph move {mv.index}", ca.vertcat((zrow - tau).T, (zrow + tau).T),
                    0.0, np.inf)
    if g.drive_model.dwell_torques:
        tau_d = ca.vertcat(*g.drive_model.dwell_torques)
        b.constrain("peak torque epigraph dwells", ca.vertcat(Z[-1] - tau_d, Z[-1] + tau_d), 0.0, np.inf)
    return Cost(Z[0] + _smoothing(g), "N m", lambda f, r: f * tau_ref, Z[0])


def min_rms_torque(g):
    tau_ref = g.drive_model.tau_ref
    return Cost(g.terms.mean_sq, "N m", lambda f, r: math.sqrt(max(f, 0.0)) * tau_ref)


def min_energy(g):
    tau_ref = g.drive_model.tau_ref
    return Cost(g.terms.move_sq, "N^2 m^2 s", lambda f, r: f * tau_ref**2 * r.period)


def min_time(g):
    """The shortest cycle: the time scale (:data:`TIME_SCALE`, the cycle time over the request's) under
    every limit. Its value is the stitch period [s] (``60 / spm``); the rate it allows is the request's
    divided by the scale. The numbers computed at the request's rate (the servo term's kernel and load
    error) are exact at scale 1: :func:`~.refine.solve_one` re-solves at the new rate until it stays."""
    return Cost(g.time_scale + _smoothing(g), "s", lambda f, r: f * 60.0 / r.spm, g.time_scale)


def max_duration(g):
    """The longest time of the move ``[design] lengthen`` names, the moves' times free with their sum fixed
    (``free_spans``: the dwells keep theirs): the NLP minimises its time's negative relative to the request's.
    Its value is the time [s]; :func:`~.refine.solve_free_spans` solves again at the spans found."""
    k = lengthened(g.request)
    nominal = g.built.param("lengthened time", lambda r, k=k: r.moves[k].duration)
    # the solve at the spans found keeps the first solve's stroke: nothing to minimise there (no smoothing either)
    f = -g.T[k] / nominal + (_smoothing(g) if g.request.free_spans else 0)
    return Cost(f, "s", lambda f, r, k=k: -f * r.moves[k].duration, -g.T[k] / nominal)


def lengthened(req) -> int:
    """The position among the request's moves of the move ``[design] lengthen`` names (a ProblemError naming the
    field where no move has that name)."""
    names = [mv.name for mv in req.moves]
    if req.settings.lengthen not in names:
        raise ProblemError(str(req.problem.file), "design.lengthen", f"{req.settings.lengthen!r} is no move of "
                                                                     f"[timing]: {', '.join(names)}")
    return names.index(req.settings.lengthen)


def min_handover_error(g):
    """The most accurate stroke at this rate: the largest handover error of the design's terms over the checked
    instants (:class:`~.limits.HandoverAccuracy`, epigraph form), relative to ``[design] handover_accuracy_mm``."""
    signed, bound = g.terms.handover.signed, g.terms.handover.bound
    if not isinstance(signed, (ca.MX, ca.SX)):
        raise ProblemError(str(g.problem.file), "design.objective",
                           "min_handover_error needs a handover error term: a [servo] section (the servo loop and "
                           "belt) and a move that ends at the handover")
    b, scale = g.built, g.request.settings.accuracy
    z = b.var("handover error", (1, 1), 0.0, np.inf, 1.0)
    b.constrain("handover error epigraph", ca.vertcat(z - (signed + bound) / scale, z - (bound - signed) / scale),
                0.0, np.inf)
    shown, unit = error_unit(g.problem.timing.rotary)   # mm, or deg for a rotary load
    return Cost(z + _smoothing(g), unit, lambda f, r: f * scale * shown, z)


def min_stiffness(g):
    """The softest springs: the free model stiffnesses of ``[design.free]`` (design/free.py), each relative to its
    upper bound, summed; the stroke is the one of least jerk among those the limits allow with them."""
    free = g.free_stiffness
    if not free:
        raise ProblemError(str(g.problem.file), "design.objective", "min_stiffness needs a free stiffness in "
                                                                   "[design.free] (e.g. [design.free.k2] stiffness_N_m "
                                                                   "= [900, 3000])")
    from .free import free_elements

    bounds = {name: hi for name, (_, hi) in free_elements(g.request.settings).items()}
    expr = sum(k / bounds[name] for name, k in free.items())
    if len(free) == 1:
        hi = next(iter(bounds.values()))
        return Cost(expr + 1e3 * _smoothing(g), "N/m", lambda f, r: f * hi, expr)
    return Cost(expr + 1e3 * _smoothing(g), "-", lambda f, r: f, expr)


def min_impact_velocity(g):
    """The gentlest impact: the speed with which the driven body's cluster meets the impact contact of ``[model.events]``
    (the needle bar's control member on its stop), at a crossing of every move that closes it, held at the stop's
    position (contact_limits.ImpactVelocity, pins.pin_crossing), relative to the moves' mean speed, under every
    limit of the design (``[design.contact] keep_closed``: no lag)."""
    speeds = g.terms.impact_speeds
    if speeds is None:
        raise ProblemError(str(g.problem.file), "design.objective",
                           "min_impact_velocity needs [design.contact] and a [model.events] impact contact that a move "
                           "closes (the contact the driven body's cluster meets)")
    b, scale = g.built, _impact_speed_scale(g.request)
    z = b.var("impact velocity", (1, 1), 0.0, np.inf, 1.0)
    b.constrain("impact velocity epigraph", ca.vertcat(z - speeds / scale, z + speeds / scale), 0.0, np.inf)
    return Cost(z + _smoothing(g), "m/s", lambda f, r: max(f, 0.0) * _impact_speed_scale(r), z)


def _impact_speed_scale(req) -> float:
    """The speed the impact velocity is measured against in the NLP: the largest mean speed of the moves that close
    the impact contact [m/s]."""
    return max((abs(mv.stroke) / mv.duration for mv in req.moves if req.contact.closes_impact(mv)), default=1.0)


@dataclass(frozen=True)
class Objective:
    """An objective: what it minimises, whether it needs the drive, its builder, and whether the cycle
    time is a decision variable (``free_time``: :data:`TIME_SCALE`)."""

    name: str
    description: str
    needs_drive: bool
    build: Callable
    free_time: bool = False
    needs_terms: bool = False  # the handover error terms are part of every solve (not checked afterwards)
    #: the drive check whose fine-grid value is the objective's own (the epigraph holds it at the nodes only)
    fine_check: str | None = None
    #: the key of the same measure in the comparison with the classic laws (design/compare.py)
    compare_measure: str | None = None
    #: what its value is, for an axis label
    quantity: str = "objective value"
    #: it reads the integral of torque squared (limits.RmsTorque builds it even where no rated torque is held)
    torque_squared: bool = False
    #: it holds the jerk continuous between mesh intervals (its integrand is the jerk's derivative)
    jerk_continuous: bool = False
    #: the moves' times are decision variables (their sum fixed): ``max_duration``
    free_spans: bool = False


REGISTRY = {o.name: o for o in (
    Objective("min_peak_torque", "peak |motor torque| over the cycle (epigraph form)", True, min_peak_torque,
              fine_check="peak_torque", compare_measure="peak_torque_N_m", quantity="peak motor torque"),
    Objective("min_rms_torque", "RMS motor torque over the cycle", True, min_rms_torque, fine_check="rms_torque",
              compare_measure="rms_torque_N_m", quantity="RMS motor torque", torque_squared=True),
    Objective("min_energy", "copper losses over one cycle (integral of torque squared over the moves)", True,
              min_energy, compare_measure="energy", torque_squared=True),
    Objective("min_peak_accel", "peak |acceleration| of the driven member over all moves (epigraph form)", False,
              min_peak_accel, compare_measure="a_max_m_s2"),
    Objective("min_accel_squared", "integral of acceleration squared over the moves", False,
              _integral_objective("a", 3, "m^2/s^3"), compare_measure="accel_squared"),
    Objective("min_jerk", "integral of jerk squared over the moves", False, _integral_objective("j", 5, "m^2/s^5"),
              compare_measure="jerk_squared"),
    Objective("min_snap", "integral of snap (4th derivative) squared over the moves", False,
              _integral_objective("snap", 7, "m^2/s^7"), jerk_continuous=True),
    Objective("min_stiffness", "the free model stiffnesses of [design.free] (the softest springs the limits allow), "
              "each relative to its upper bound", False, min_stiffness, quantity="spring stiffness"),
    Objective("min_impact_velocity", "the speed with which the driven body's cluster meets the impact contact of "
              "[model.events] ([design.contact]; the needle bar's control member on its stop)", False,
              min_impact_velocity, quantity="impact velocity"),
    Objective("min_handover_error", "largest handover error of the design's terms (the servo loop and belt) over "
              "the handover window: the most accurate stroke at this rate", True, min_handover_error,
              needs_terms=True),
    Objective("min_time", "shortest stitch period (highest stitch rate) within every limit of the design, the "
              "interval times fixed fractions of the cycle", True, min_time, free_time=True, quantity="stitch period"),
    Objective("max_duration", "longest time of the move [design] lengthen names within every limit of the design, "
              "the other moves' times giving it theirs (the dwells and the cycle time fixed)", False, max_duration,
              free_spans=True, quantity="time of the lengthened move"),
)}
#: Every objective, with what it minimises.
OBJECTIVES = {name: o.description for name, o in REGISTRY.items()}
#: Objectives that need only the kinematics.
KINEMATIC_OBJECTIVES = tuple(name for name, o in REGISTRY.items() if not o.needs_drive)
#: Objectives that need the drive's load torque.
TORQUE_OBJECTIVES = tuple(name for name, o in REGISTRY.items() if o.needs_drive)


#: What a name the registry does not hold asks for: nothing beyond the defaults (no measure, no flag).
NO_OBJECTIVE = Objective("", "", False, None)


def objective_of(name: str | None) -> Objective:
    """The registry's entry of ``name``; :data:`NO_OBJECTIVE` for no objective or a name it does not hold."""
    return REGISTRY.get(name or "", NO_OBJECTIVE)


def is_peak_torque(objective: str | None) -> bool:
    """Whether ``objective``'s value is the peak motor torque (a bound of the peak bounds it; a pin may hold it)."""
    return objective_of(objective).fine_check == "peak_torque"


def free_time(objective: str) -> bool:
    """Whether ``objective`` makes the cycle time a decision variable."""
    return objective_of(objective).free_time


def needs_terms(objective: str) -> bool:
    """Whether ``objective`` is built from the handover error terms (they are then in every solve)."""
    return objective_of(objective).needs_terms


def needs_drive_error(problem, objective: str) -> ProblemError:
    return ProblemError(str(problem.file), "design.objective",
                        f"objective {objective!r} needs the drive (motor, load): add a [drive] section, or choose "
                        f"one of {', '.join(KINEMATIC_OBJECTIVES)}")


def unknown_objective_error(objective: str) -> ProblemError:
    return ProblemError("--objective", "", f"{objective!r} is not one of {', '.join(OBJECTIVES)}")


def build_objective(g) -> Cost:
    """The :class:`Cost` of ``g``'s request's objective."""
    objective = g.request.objective
    found = REGISTRY.get(objective)
    if found is None:
        raise unknown_objective_error(objective)
    if found.needs_drive and g.request.drive is None:
        raise needs_drive_error(g.problem, objective)
    return found.build(g)
