"""The drive in the NLP: transmission, motor, and the motor torque, speed and belt force of every move and dwell.

Built by :func:`.limits.build_drive` before the limits that read it (the drive package's load model,
:func:`~strokeopt.drive.load.load_torque`, on CasADi symbols: ``T = J(phi) phi'' + 1/2 J'(phi) phi'^2 +
loads`` through any transmission, its transfer functions by AD). A belt pulley is the constant-ratio case
with a choice: its radius is a decision variable scaled by a reference radius, free between the
catalogue's bounds, or held at a tooth count's radius by equal bounds; a fixed pulley's inertia is its
catalogue value (the inertia model times a parameter, catalogue / model). Both are one NLP structure,
so one built solver serves the whole catalogue search. Any other transmission (a screw and lever) is
the problem's own: nothing to choose, no radius. The motor is fixed (its numbers are parameters) or a
Bonmin choice among candidates (binary weights); a stepper's limits are its pull-out curve (a
piecewise-linear CasADi interpolant of the catalogue table) and its step rate.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

import casadi as ca
import numpy as np

from .pins import pin_rows
from .request import SolveRequest
from ...drive.checks import is_stepper, torque_limit
from ...drive.transmission import BeltPulley


def pulley_setting(req: SolveRequest) -> tuple[float, float, float, float]:
    """This solve's pulley: radius bounds, start radius [m] and the inertia factor (catalogue / model)."""
    drive, choice = req.drive, req.choice
    if choice.teeth is not None:
        pulley = drive.pulley(choice.teeth)
        model = float(drive.pulley_inertia(pulley.pitch_diameter))
        factor = (pulley.inertia / model if model > 0 else 0.0) if req.settings.include_pulley_inertia else 0.0
        return pulley.radius, pulley.radius, pulley.radius, factor
    lo, hi = choice.radius_bounds or drive.radius_bounds()
    start = float(np.clip(req.radius0 if req.radius0 is not None else req.problem.transmission.radius, lo, hi))
    return lo, hi, start, 1.0


def pull_out_function(motor, limits):
    """A stepper's pull-out torque over the safety factor as a CasADi function of the motor speed [rad/s]
    (either sense): the catalogue table, linear between its points, flat below the first (as
    :meth:`~strokeopt.drive.catalogue.StepperMotor.pull_out`); the step-rate limit keeps the speed
    inside the table."""
    w = np.asarray(motor.pull_out_speed, dtype=float)
    t = np.asarray(motor.pull_out_torque, dtype=float) / limits.pull_out_safety_factor
    if w[0] > 0:  # flat to standstill
        w, t = np.concatenate([[0.0], w]), np.concatenate([[t[0]], t])
    grid = np.concatenate([-w[:0:-1], w])  # mirrored: the same curve in both senses
    return ca.interpolant("pull_out", "linear", [grid.tolist()], np.concatenate([t[:0:-1], t]).tolist())


def peak_limit(motor, drive, reserve: float = 0.0) -> float:
    """The torque the design may use of the motor's limit on the drive
    (:func:`strokeopt.drive.checks.torque_limit`), less ``reserve`` (a fraction, ``[design]
    torque_reserve_pct``: left to the servo loop, whose torque command exceeds the rigid load's)."""
    return torque_limit(motor, drive.limits) * (1.0 - reserve)


@dataclass
class DriveModel:
    """The drive's symbols of one NLP structure (see the module docstring), for the limits and objectives."""

    radius: Any  # the pulley radius [m]; None for the problem's own transmission (nothing to choose)
    r_ref: float
    inertia: Any  # of the pulley, or the own transmission's [kg m^2]
    trans: Any  # BeltPulley (radius a variable) or the problem's Transmission
    rotor: Any
    peak_lim: Any  # torque limits and rated speed of the motor (parameters, or Bonmin mixtures)
    rated: Any
    speed: Any
    peak_num: float  # the same for messages (a Bonmin choice: the loosest of the candidates)
    rated_num: float
    speed_num: float
    motor_name: str
    peak_what: str
    tau_ref: float  # torque scale [N m]: the same for every motor, so one solver serves them all
    period: Any
    v: list = field(default_factory=list)  # speed at the hull points of each move [m/s]
    omega: list = field(default_factory=list)  # motor speed at the same points [rad/s]
    torque_omega: list = field(default_factory=list)  # motor speed where each move's torque is held [rad/s]
    pull_out: Any = None  # a stepper's pull-out torque over the safety factor, a function of the speed [N m]
    forces: list = field(default_factory=list)  # belt forces of the moves, pins and dwells [N]
    pin_values: list = field(default_factory=list)  # pinned torques and forces relative to their limits
    pin_forces: list = field(default_factory=list)
    pin_torques: list = field(default_factory=list)  # pinned torques [tau_ref] (refine.pins_in_place)
    dwell_sq: Any = 0.0  # (torque/tau_ref)^2 of the dwells, each times its share of the cycle
    torques: list = field(default_factory=list)  # each move's torque at its hull points and pins [tau_ref]
    dwell_torques: list = field(default_factory=list)  # each dwell's torque at rest [tau_ref]
    pick: Any = None  # the Bonmin motor weights
    discrete: tuple | None = None  # (variable name, size) of the integer variables

    @classmethod
    def build(cls, g) -> "DriveModel":
        """The pulley radius and the motor of ``g``'s structure."""
        b, req = g.built, g.request
        drive, choice = req.drive, req.choice
        if drive.own_transmission is not None:
            radius, r_ref = None, 1.0
            trans = g.transmission  # the problem's, with its free fields (free.build_free)
            inertia = trans.inertia
        else:
            lo, hi = drive.radius_bounds()
            r_ref = float(np.sqrt(lo * hi))
            rho = b.var("radius", (1, 1), lambda r: pulley_setting(r)[0] / r_ref,
                        lambda r: pulley_setting(r)[1] / r_ref, lambda r: pulley_setting(r)[2] / r_ref)
            radius = rho * r_ref
            inertia = b.param("pulley inertia factor", lambda r: pulley_setting(r)[3]) * drive.pulley_inertia(2 * radius)
            trans = BeltPulley(2 * radius, inertia)
        pct = drive.limits.peak_limit_pct / 100
        reserve = req.settings.torque_reserve
        pick, discrete = None, None
        if choice.candidates:
            cands = choice.candidates
            pick = b.var("motor", (len(cands), 1), 0.0, 1.0, [1.0] + [0.0] * (len(cands) - 1))
            b.constrain("one motor", ca.sum1(pick) - 1.0, 0.0, 0.0)
            discrete = ("motor", len(cands))

            def mix(values):
                return ca.dot(pick, ca.DM(values))

            rotor = mix([m.rotor_inertia for m in cands])
            peak_lim = mix([peak_limit(m, drive, reserve) for m in cands])
            rated = mix([m.rated_torque for m in cands])
            speed = mix([m.rated_speed for m in cands])
            # for messages: the loosest limits of the candidates
            peak_num = max(peak_limit(m, drive, reserve) for m in cands)
            rated_num = max(m.rated_torque for m in cands)
            speed_num = max(m.rated_speed for m in cands)
            motor_name = "any catalogue motor"
        elif is_stepper(choice.motor):
            m = choice.motor
            rotor = b.param("rotor inertia", lambda r: r.choice.motor.rotor_inertia)
            peak_num, rated_num, speed_num = peak_limit(m, drive, reserve), math.nan, m.pull_out_speed[-1]
            peak_lim = b.param("peak limit", lambda r: peak_limit(r.choice.motor, r.drive, r.settings.torque_reserve))
            rated = None  # a stepper has no rated torque: its current (and heat) does not follow the load
            speed = b.param("rated speed", lambda r: r.choice.motor.pull_out_speed[-1])
            motor_name = m.name
        else:
            m = choice.motor
            rotor = b.param("rotor inertia", lambda r: r.choice.motor.rotor_inertia)
            peak_num, rated_num, speed_num = peak_limit(m, drive, reserve), m.rated_torque, m.rated_speed
            peak_lim = b.param("peak limit", lambda r: peak_limit(r.choice.motor, r.drive, r.settings.torque_reserve))
            rated = b.param("rated torque", lambda r: r.choice.motor.rated_torque)
            speed = b.param("rated speed", lambda r: r.choice.motor.rated_speed)
            motor_name = m.name  # for messages: a relaxed build (which names them) is never reused
        if rated is None:
            peak_what = (f"peak_torque (pull-out torque at standstill / safety factor "
                         f"{drive.limits.pull_out_safety_factor:g}, {motor_name}: {'%.3g' % peak_num} N m"
                         f"{', %.3g %% kept in reserve' % (100 * reserve) if reserve else ''})")
        else:
            peak_what = (f"peak_torque (peak torque, {motor_name}: {'%.3g' % peak_num} N m"
                         f"{', drive limit %g %% of rated' % drive.limits.peak_limit_pct if pct * rated_num * (1 - reserve) < peak_num + 1e-12 and not choice.candidates else ''}"
                         f"{', %.3g %% kept in reserve' % (100 * reserve) if reserve else ''})")
        period = b.param("period", lambda r: r.period) * g.time_scale
        out = cls(radius, r_ref, inertia, trans, rotor, peak_lim, rated, speed, peak_num, rated_num, speed_num,
                  motor_name, peak_what, drive.tau_ref, period)
        out.pick, out.discrete = pick, discrete
        if rated is None:
            out.pull_out = pull_out_function(choice.motor, drive.limits)
        return out

    @property
    def stepper(self) -> bool:
        return self.pull_out is not None

    def move(self, g, k: int) -> None:
        """Torque (relative to ``tau_ref``) and belt force of move ``k``, with its pinned points."""
        from ...drive.load import load_torque

        mv = g.request.moves[k]
        # Torque (linear in the acceleration) is held at the Bernstein control points of the
        # acceleration polynomial (with position and speed at their Greville abscissae), not only at
        # the nodes: the acceleration part is then bounded everywhere in the interval (convex hull),
        # so the optimiser cannot hide a torque peak between two nodes.
        # Through a position-dependent transmission the torque also depends on the speed (1/2 J'(phi) phi'^2):
        # the speed at the same Greville abscissae (a constant ratio's torque does not read it). The motor
        # speed at the speed's hull points is the load speed there over mu at the positions of the
        # velocity polynomial's Greville abscissae (a constant ratio: v / r, bounded everywhere).
        degree = g.request.mesh.degree
        greville = np.linspace(0.0, 1.0, degree + 1)
        s = ca.vec(g.si(k, greville, "s")).T
        v = ca.vec(g.vars[k].hull("v") * (mv.stroke / g.T[k])).T  # bounds the speed between nodes too
        a = ca.vec(g.vars[k].hull("a") * (mv.stroke / g.T[k] ** 2)).T
        v_g = ca.vec(g.si(k, greville, "v")).T
        terms = load_torque(self.rotor, self.trans, g.load, s, v_g, a)
        tau = terms.total / self.tau_ref
        self.torque_omega.append(terms.omega)
        s_v = ca.vec(g.si(k, np.linspace(0.0, 1.0, degree + 2), "s")).T
        self.omega.append(self.trans.motor_kinematics(s_v, v, 0 * v)[1])
        self.forces.append(terms.load_force)
        # where a load force switches on inside the move the torque jumps: the pinned points (pins.py); where the
        # transmission's own load jumps at the move's start or end (the beat-up at 360 = 0 deg), both sides there
        pin_t, pin_f = pin_rows(g, k, mv, self.rotor, self.trans)
        tau = ca.horzcat(tau, pin_t / self.tau_ref, self._end_sides(g, k, mv) / self.tau_ref)
        self.forces.append(pin_f)
        self.pin_values.append(ca.vec(pin_t) / self.peak_lim)
        self.pin_torques.append(ca.vec(pin_t) / self.tau_ref)
        self.pin_forces.append(ca.vec(pin_f))
        self.torques.append(tau)
        self.v.append(v)

    def _end_sides(self, g, k: int, mv) -> ca.MX:
        """The torque just before and just after each end of move ``k`` that lies on a jump of the transmission's
        own loads (:meth:`~strokeopt.drive.transmission.Transmission.load_switches`): the nodes hold one side only."""
        from ...drive.load import load_torque

        switches = self.trans.load_switches()
        out = []
        for tau, pos in ((0.0, mv.start), (1.0, mv.start + mv.stroke)):
            if not any(self.trans.same_position(pos, sw) for sw in switches):
                continue
            row = 0 if tau == 0.0 else -1   # the move's first or last mesh interval
            v, a = g.si(k, [tau], "v")[row, 0], g.si(k, [tau], "a")[row, 0]
            eps = 1e-9 * max(abs(mv.stroke), 1e-3)
            for side in (-eps, eps):
                out.append(load_torque(self.rotor, self.trans, g.load, ca.MX(pos + side), v, a).total)
        return ca.horzcat(*out) if out else ca.MX(1, 0)

    def dwells(self, g) -> None:
        """The dwells: at rest, torque from gravity and load forces only."""
        from ...drive.load import load_torque

        b, req = g.built, g.request
        sch = req.schedule
        for itv, dur in zip(req.problem.timing.intervals, sch.duration):
            if itv.is_move:
                continue
            terms = load_torque(self.rotor, self.trans, g.load, ca.MX(itv.start_position), ca.MX(0.0),
                                ca.MX(0.0))
            t_d = terms.total / self.tau_ref
            self.dwell_torques.append(t_d)
            self.forces.append(terms.load_force)
            share = b.param(f"dwell {itv.index} share",
                            lambda r, i=itv.index - 1: r.schedule.duration[i] / r.schedule.period)
            self.dwell_sq = self.dwell_sq + t_d**2 * share
