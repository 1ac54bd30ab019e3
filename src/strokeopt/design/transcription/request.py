"""What one solve needs, as one object: :class:`SolveRequest`.

Second step of the design's flow (:mod:`.settings` -> request -> :mod:`.nlp` -> :mod:`.refine`
-> :mod:`.solve`). A request names the problem, the stitch rate, the settings, the mesh, the
objective, the drive (:class:`DriveSetup`) and the parts of this solve (:class:`DriveChoice`),
the solver options, the warm start, the pinned points and the handover error terms
(:class:`ErrorTerm`). The NLP's parameter, bound and start-value functions read the request of
the solve they serve; variants of a request are made with :func:`dataclasses.replace`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from functools import cached_property
from typing import Any, Protocol

import numpy as np

from .collocation import Mesh
from .contact_setup import ContactDesign, contact_design
from .settings import DesignSettings
from ...drive.transmission import BeltPulley
from ...errors import ProblemError
from ...motion.laws import make_law
from ...servo.error_expression import ErrorExpression  # noqa: F401  (a term's form in the NLP; servo's floor)


@dataclass(frozen=True)
class Move:
    """One move of the timing diagram as the design sees it (SI units)."""

    index: int  # 1-based among moves
    interval: int  # 1-based interval index
    name: str
    t_start: float
    duration: float
    start: float  # position [m]
    stroke: float  # signed [m]
    jerk_bound: float | None  # [m/s^3]
    start_speed: bool = False  # starts at the speed the move before it ends at (timing: end = "speed")
    end_speed: bool = False  # ends at speed: the next move starts at it

    @property
    def v_scale(self) -> float:
        return abs(self.stroke) / self.duration

    @property
    def a_scale(self) -> float:
        return abs(self.stroke) / self.duration**2

    @property
    def j_scale(self) -> float:
        return abs(self.stroke) / self.duration**3


def design_moves(problem, spm: float, settings: DesignSettings) -> list[Move]:
    """The moves of ``problem`` at ``spm`` with their jerk bounds (``[design] jerk_max``)."""
    sch = problem.timing.schedule(spm)
    # the law's jerk at a stated rate (jerk_max_from_law = <spm>): the durations there; else at this rate
    law_durations = (problem.timing.schedule(settings.jerk_law_spm).duration if settings.jerk_law_spm
                     else sch.duration)
    out = []
    for itv, t0, dur, law_dur in zip(problem.timing.intervals, sch.t_start, sch.duration, law_durations):
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
                                   "bound the jerk in m/s^3 instead (--set design.jerk_max_from_law=false --set "
                                   "design.jerk_max_m_s3=VALUE), or leave it unbounded (jerk_max_from_law = false)")
            bound = c_j * abs(itv.stroke) / law_dur**3
        out.append(Move(itv.move_index, itv.index, itv.name, float(t0), float(dur), itv.start_position, itv.stroke,
                        bound, problem.timing.starts_at_speed(itv), itv.end_speed))
    return out


def initial_unit(mesh: Mesh, rest_order: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """A feasible-shaped initial guess: the 3-4-5 polynomial (4-5-6-7 for rest_order 3)."""
    law = make_law("poly7" if rest_order >= 3 else "poly5")
    h = mesh.h
    starts = np.arange(mesh.intervals + 1) * h
    y, y1 = law.derivatives(starts, order=1)
    t_nodes = (np.arange(mesh.intervals).reshape(-1, 1) + mesh.nodes.reshape(1, -1)) * h
    a = law.derivatives(t_nodes.ravel(), order=2)[2].reshape(t_nodes.shape)
    return y, y1, a


def steady_unit(mesh: Mesh) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The initial guess of a move at speed at both ends: constant speed (y = tau), a crank turning steadily."""
    starts = np.arange(mesh.intervals + 1) * mesh.h
    return starts.copy(), np.ones_like(starts), np.zeros((mesh.intervals, mesh.degree + 1))


@dataclass(frozen=True)
class DriveChoice:
    """The parts of one solve: a motor (or the candidates of a Bonmin choice) and a pulley.

    ``teeth`` None means a continuous pulley radius between ``radius_bounds``.
    """

    motor: Any = None  # ServoMotor
    teeth: int | None = None
    radius_bounds: tuple[float, float] | None = None
    candidates: tuple = ()  # motors for the Bonmin choice
    #: with a continuous radius, the tooth count whose belt rating the belt is checked with; None: the
    #: fewest of the range (conservative). The catalogue search's first pass takes the most (a
    #: relaxation: its radius only guides the tooth counts, each checked with its own rating).
    belt_teeth: int | None = None

    @property
    def belt_grooves(self) -> int | None:
        """The tooth count the belt checks use: the pulley's, else :attr:`belt_teeth`."""
        return self.teeth if self.teeth is not None else self.belt_teeth

    @property
    def label(self) -> str:
        parts = []
        if self.motor is not None:
            parts.append(self.motor.name)
        if self.candidates:
            parts.append("one of " + ", ".join(m.name for m in self.candidates))
        parts.append(f"{self.teeth} teeth" if self.teeth else "continuous radius")
        return ", ".join(parts)


class DriveSetup:
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
        #: the problem's own transmission when it is not a belt pulley (a screw and lever): nothing to
        #: choose, no belt; None for a belt pulley (its radius is the design's to choose)
        self.own_transmission = None if isinstance(problem.transmission, BeltPulley) else problem.transmission
        if self.own_transmission is not None and settings.pulley != "fixed":
            raise ProblemError(self.file, "design.pulley", f"{settings.pulley!r} chooses a belt pulley; the "
                                                           f"transmission is a {problem.transmission.name} (use \"fixed\")")
        self.stepper = spec.motor is not None and spec.motor in self.catalogue.steppers
        if self.stepper and settings.motor_choice == "bonmin":
            raise ProblemError(self.file, "design.motor_choice", "bonmin mixes servo motors' limits; a stepper's "
                                                                 "pull-out curve is not a number to mix: use \"fixed\" "
                                                                 "or \"enumerate\"")
        #: torque scale of the NLP [N m]: the largest peak torque in the catalogue (a stepper: the largest
        #: holding torque of the steppers), the same for every motor, so one solver serves them all
        self.tau_ref = max([m.holding_torque for m in self.catalogue.steppers.values()] if self.stepper else
                           [m.peak_torque for m in self.catalogue.motors.values()] or [1.0])

    def pulley(self, teeth: int):
        from ...drive.selection import catalogue_pulley

        return catalogue_pulley(self.catalogue, self.profile, teeth)

    def pulley_inertia(self, pitch_diameter):
        if not self.settings.include_pulley_inertia:
            return 0.0
        return self.catalogue.pulley_inertia(self.profile, pitch_diameter)

    def motors(self) -> list:
        """The motors a catalogue search tries: the steppers when the file's motor is one, else the servo motors."""
        return list((self.catalogue.steppers if self.stepper else self.catalogue.motors).values())

    def fixed_motor(self):
        if self.spec.motor is None:
            raise ProblemError(self.file, "drive.motor", "is needed with design.motor_choice = \"fixed\" "
                                                         "(or choose: motor_choice = \"enumerate\" or \"bonmin\")")
        return self.catalogue.actuator(self.spec.motor, (self.file, "drive.motor"))

    def radius_bounds(self) -> tuple[float, float]:
        from ...drive.transmission import pitch_diameter

        return pitch_diameter(self.profile, self.teeth_range[0]) / 2, pitch_diameter(self.profile, self.teeth_range[1]) / 2

    def transmission(self, teeth: int):
        p = self.pulley(teeth)
        return BeltPulley(p.pitch_diameter, inertia=p.inertia if self.settings.include_pulley_inertia else 0.0)

    def allowable_belt_force(self, teeth: int | None) -> float | None:
        """Largest effective belt tension [N] the belt checks accept (width and breaking, thesis appendix 2)."""
        found = self.belt_limit(teeth)
        return None if found is None else found[1]

    def belt_limit(self, teeth: int | None) -> tuple[str, float, float, str] | None:
        """The belt check that binds first: (the drive package's check name, allowable tension [N], the check's limit, unit)."""
        if self.belt is None:
            return None
        from ...drive.checks import belt_load

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
        from ...drive.load import load_torque

        move = self.problem.timing.handover_move
        s = np.array([move.end_position if move is not None else 0.0])
        terms = load_torque(1e-5, BeltPulley(0.02), self.load, s, np.zeros(1), np.zeros(1))
        return float(abs(np.asarray(terms.load_force).ravel()[0]))


class ErrorTerm(Protocol):
    """A term of the position error at the handover, summed and held within ``[design] handover_accuracy_mm``.

    Terms are passed to :func:`~strokeopt.design.solve.solve_design` (``error_terms``; by default
    ``problem.error_terms``, which the problem file fills). A term is hashable and compares by its
    type and parameters (it is part of the NLP cache key); it holds no per-problem state.

    * ``name``: how the checks table names it (``handover accuracy (<name>)``);
    * ``fixed_error(problem)``: the part that does not depend on the design [m] (checked before
      solving), or None;
    * ``expression(nlp)``: the error as an :class:`ErrorExpression` of the NLP under construction
      (:class:`~strokeopt.design.nlp.Graph`: ``nlp.request``, ``nlp.built.params``, ``nlp.si``), or
      None when the term does not apply to this problem. Numbers that change between solves enter
      as parameters, functions of the solve's :class:`SolveRequest` (its ``cache`` holds what they
      compute once per solve). ``nlp.request.terms_minimised``: the objective is built from the terms
      (``min_handover_error``), so a term that holds a subset of its instants holds them all.
    """

    name: str

    def fixed_error(self, problem) -> float | None: ...

    def expression(self, nlp) -> Any: ...


@dataclass
class SolveRequest:
    """Everything one solve needs; the NLP's numbers (parameters, bounds, start values) are functions of it.

    ``pin_times``: unit times where each move passes each load switch (see :mod:`.pins`); None: found
    from the warm start (or the initial guess). ``cache``: numbers a parameter function computes once
    per solve (not copied by :func:`dataclasses.replace`). ``rate_cap``: with a free cycle time
    (``min_time``), the rate may not exceed ``spm`` (the time scale is at least 1).
    """

    problem: Any
    spm: float
    settings: DesignSettings
    mesh: Mesh
    objective: str
    drive: DriveSetup | None = None
    choice: DriveChoice | None = None
    options: dict = field(default_factory=dict)
    warm: list | None = None
    radius0: float | None = None
    relaxed: bool = False
    enforce_accuracy: bool = False
    error_terms: tuple = ()
    pin_times: dict | None = None
    rate_cap: bool = False
    #: with ``max_duration``: the moves' times fixed at the problem's spans (the solve again at the spans found)
    spans_fixed: bool = False
    cache: dict = field(default_factory=dict, init=False, repr=False, compare=False)

    @property
    def free_spans(self) -> bool:
        """Whether the moves' times are decision variables (``max_duration``, before its spans are fixed)."""
        from .objectives import objective_of

        return objective_of(self.objective).free_spans and not self.spans_fixed

    @property
    def terms_minimised(self) -> bool:
        """Whether the objective is built from the handover error terms (``min_handover_error``): a term then keeps
        every instant it checks (one left out of a minimised maximum is free to grow, and did: IPOPT stopped at
        its iteration limit), where a held accuracy may hold the largest ones alone (the solution's exact check
        sees the rest)."""
        from .objectives import needs_terms

        return needs_terms(self.objective)

    @cached_property
    def moves(self) -> list[Move]:
        return design_moves(self.problem, self.spm, self.settings)

    @cached_property
    def contact(self) -> ContactDesign | None:
        """The contact limits of ``[design.contact]`` (None without it)."""
        return contact_design(self.problem, self.settings)

    @cached_property
    def schedule(self):
        return self.problem.timing.schedule(self.spm)

    @cached_property
    def period(self) -> float:
        return float(self.problem.timing.period(self.spm))

    @cached_property
    def start(self) -> list[tuple]:
        """Start point of every move: the warm start's solution on the same mesh, else the 3-4-5 law."""
        out = []
        for k in range(len(self.moves)):
            warm = self.warm
            if warm is not None and k < len(warm) and warm[k].mesh == self.mesh:
                out.append((warm[k].S, warm[k].V, warm[k].A))
            elif self.moves[k].start_speed and self.moves[k].end_speed:  # at speed at both ends: a steady move
                out.append(steady_unit(self.mesh))
            else:
                out.append(initial_unit(self.mesh, self.settings.rest_order))
        return out
