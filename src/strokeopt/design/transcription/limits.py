"""The limits of the design problem: one builder per limit.

Each :class:`Limit` owns its NLP rows (:meth:`Limit.on_move`, :meth:`Limit.on_cycle`, as
:class:`LimitGroup` s whose ``need`` and ``what`` make the message of :mod:`.diagnose`), the names of
the drive package's checks that re-read it on the fine grid (:attr:`Limit.checks`: a violation there beyond
``check_tolerance`` refines the mesh, see :mod:`.refine`) and its own rows of the checks table
(:meth:`Limit.report`). A builder writes nothing on the graph: what it adds beside its rows for others (the
objectives, the search) it returns as named terms, as an objective returns its ``Cost``, and
:func:`collect` gathers them (:class:`Terms`, one place). A new limit is one new builder in
:data:`MOVE_LIMITS` or :data:`DRIVE_LIMITS`. Built by :mod:`.nlp`; the drive's symbols they read come from
:mod:`.drive_model`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import casadi as ca
import numpy as np

from .drive_model import DriveModel
from .objectives import objective_of
from ...io.load_units import error_unit


@dataclass(frozen=True)
class LimitGroup:
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
    check: str = ""  # the name of the same limit in the checks table (the drive package's names), for short messages
    #: False, or a function of the solve's request returning False: the rows exist (one NLP
    #: structure for every solve) but their bound is infinite
    enforced: Any = True
    #: None, or a function of ``need`` giving the whole message of a violation (a limit a plain
    #: "needs X, limit Y" does not say well, e.g. a lower bound)
    describe: Any = None

    @property
    def short(self) -> str:
        return self.check or self.what

    def is_enforced(self, req) -> bool:
        return bool(self.enforced(req) if callable(self.enforced) else self.enforced)


@dataclass(frozen=True)
class HandoverError:
    """What :class:`HandoverAccuracy` adds for the objectives and the search: each term's largest error
    ``(name, expression [m])``, their ``total``, and the summed ``signed`` error and ``bound`` at the checked
    instants (the rows ``min_handover_error`` minimises); numbers 0 without a term."""

    terms: tuple = ()
    total: Any = 0.0
    signed: Any = 0.0
    bound: Any = 0.0


@dataclass(frozen=True)
class Terms:
    """The named terms the limit builders return, gathered once (:func:`collect`): ``move_sq`` the integral of
    (torque / tau_ref)^2 over the moves over the period (:class:`RmsTorque`; None when nothing builds it),
    ``mean_sq`` the same with the dwells (the RMS torque squared), ``pin_values`` the pinned points' torques,
    forces and speeds relative to their limits (None: no pin), ``pin_share`` the largest pinned torque over
    the cycle's largest, ``handover`` (:class:`HandoverError`)."""

    move_sq: Any = None
    mean_sq: Any = None
    pin_values: Any = None
    pin_share: Any = None
    handover: HandoverError = HandoverError()
    #: the signed speeds [m/s] (times each pin's weight) where the moves meet the impact contact, at crossings held
    #: there (contact_limits.ImpactVelocity, for ``min_impact_velocity``); None: not asked
    impact_speeds: Any = None


def collect(terms: dict, new: dict | None) -> dict:
    """``terms`` with a builder's returned ``new`` added: lists are joined, other values summed (a term of
    every move adds up over the moves)."""
    for key, value in (new or {}).items():
        if isinstance(value, list):
            terms[key] = terms.get(key, []) + value
        else:
            terms[key] = terms[key] + value if key in terms else value
    return terms


class Limit:
    """One kind of limit (see the module docstring); the base adds nothing."""

    #: the drive package's checks (fine grid, whole cycle) that hold this limit
    checks: tuple[str, ...] = ()

    def on_move(self, g, k: int) -> dict | None:
        """Rows of move ``k`` (``g``: the :class:`~.nlp.Graph` under construction); returns the named terms it
        adds beside its rows (summed over the moves by :func:`collect`), or None."""

    def on_cycle(self, g, terms: dict) -> dict | None:
        """Rows over the whole cycle, after every move (``terms``: what the builders returned so far); returns
        its own named terms, or None."""

    def report(self, nlp, outcome) -> list[dict]:
        """Rows of the checks table besides the drive package's (name, value, limit, unit)."""
        return []


class JerkBound(Limit):
    """|jerk| of each move within ``[design] jerk_max`` (or the file's law), everywhere (Bernstein hull)."""

    def on_move(self, g, k):
        mv, b, x = g.request.moves[k], g.built, g.vars[k]
        if mv.jerk_bound is None:
            return
        # the bound on the unit jerk; a bound in m/s^3 allows the unit jerk to grow with the cube of a
        # free cycle time (a bound from the file's law at the design's rate scales with the law's own jerk:
        # constant; at a stated rate, jerk_max_from_law = <spm>, it is a bound in m/s^3)
        jb = b.param(f"jerk bound {mv.index}", lambda r, k=k: r.moves[k].jerk_bound / r.moves[k].j_scale)
        settings = g.request.settings
        if not settings.jerk_max_from_law or settings.jerk_law_spm:
            jb = jb * g.time_scale**3
        if g.request.free_spans:  # the move's time a variable (max_duration): the bound in m/s^3 at its time
            jb = jb * (g.T[k] / b.param(f"time of move {mv.index}", lambda r, k=k: r.moves[k].duration))**3
        hull = x.hull("j") / jb  # Bernstein coefficients: bounds the jerk everywhere, not only at nodes
        lim = LimitGroup(f"jerk bound move {mv.index}", "jerk bound", mv.jerk_bound, "m/s^3",
                         lambda sig, jb=mv.jerk_bound: jb * (1 + sig), mv.index)
        b.limit_abs(lim, hull)

    def report(self, nlp, outcome):
        unit = "rad/s^3" if nlp.request.problem.timing.rotary else "m/s^3"  # a rotary load's jerk (a sley's)
        return [{"name": f"jerk move {mv.index}", "value": row["jerk_max_fine_m_s3"], "limit": mv.jerk_bound,
                 "unit": unit}
                for mv, row in zip(nlp.request.moves, outcome.fine["moves"]) if mv.jerk_bound is not None]


class PeakTorque(Limit):
    """|motor torque| within the motor's peak torque (or the drive's overload limit), moves and dwells."""

    checks = ("peak_torque", "overload")

    def on_move(self, g, k):
        dm, mv = g.drive_model, g.request.moves[k]
        if dm.stepper:  # a stepper's peak is its pull-out curve's (PullOut)
            return
        lim = LimitGroup(f"peak torque move {mv.index}", dm.peak_what, dm.peak_num, "N m",
                         lambda sig, pl=dm.peak_num, tr=dm.tau_ref: pl + sig * tr, mv.index, "peak_torque")
        g.built.limit_abs(lim, dm.torques[k] * (dm.tau_ref / dm.peak_lim))

    def on_cycle(self, g, terms):
        dm = g.drive_model
        if dm.dwell_torques and not dm.stepper:
            tau_d = ca.vertcat(*dm.dwell_torques)
            lim = LimitGroup("peak torque dwells", dm.peak_what + " holding in the dwells", dm.peak_num, "N m",
                             lambda sig, pl=dm.peak_num, tr=dm.tau_ref: pl + sig * tr, None, "peak_torque")
            g.built.limit_abs(lim, tau_d * (dm.tau_ref / dm.peak_lim))


class Speed(Limit):
    """|motor speed| within the motor's rated speed (a stepper: the step rate within its pull-out table's last)."""

    checks = ("peak_speed", "step_rate")

    def on_move(self, g, k):
        dm, mv = g.drive_model, g.request.moves[k]
        if dm.stepper:
            unit, scale, check = "Hz", 1 / g.request.choice.motor.step_angle, "step_rate"
            what = f"step_rate (step rate, {dm.motor_name}: the pull-out table's last)"
        else:
            unit, scale, check = "rpm", 60 / (2 * math.pi), "peak_speed"
            what = f"peak_speed (motor speed, {dm.motor_name}: rated)"
        lim = LimitGroup(f"speed move {mv.index}", what, dm.speed_num * scale, unit,
                         lambda sig, sp=dm.speed_num * scale: sp * (1 + sig), mv.index, check)
        g.built.limit_abs(lim, dm.omega[k] / dm.speed)


class PullOut(Limit):
    """A stepper's torque demand under its pull-out curve over the safety factor at the speed of each point
    where the torque is held (:func:`.drive_model.pull_out_function`). ``[design] enforce_pull_out = false``
    keeps the rows but not their bound: the design is then solved without it and the check reports by how
    much the curve is exceeded."""

    checks = ("pull_out_torque",)

    def on_move(self, g, k):
        dm, mv = g.drive_model, g.request.moves[k]
        if not dm.stepper:
            return
        n = dm.torque_omega[k].shape[1]
        tau = dm.torques[k][:, :n] * dm.tau_ref
        avail = dm.pull_out(dm.torque_omega[k])
        sf = g.request.drive.limits.pull_out_safety_factor
        what = f"pull_out_torque (torque demand under the pull-out curve / safety factor {sf:g}, {dm.motor_name})"
        # the need: the curve's standstill value plus the largest excess over the curve at any speed
        lim = LimitGroup(f"pull-out torque move {mv.index}", what, dm.peak_num, "N m",
                         lambda sig, pl=dm.peak_num, tr=dm.tau_ref: pl + sig * tr, mv.index, "pull_out_torque",
                         enforced=lambda r: r.settings.enforce_pull_out,
                         describe=lambda need, pl=dm.peak_num, w=what: (
                             f"{w}: the demand exceeds the curve by up to {need - pl:.4g} N m "
                             f"({100 * (need - pl) / pl:.1f} % of the standstill value {pl:.4g} N m)"))
        g.built.limit(lim, ca.vertcat(ca.vec(tau - avail), ca.vec(-tau - avail)) / dm.tau_ref)

    def on_cycle(self, g, terms):
        dm = g.drive_model
        if dm.stepper and dm.dwell_torques:  # holding at rest: the curve at standstill
            tau_d = ca.vertcat(*dm.dwell_torques) * (dm.tau_ref / dm.peak_lim)
            lim = LimitGroup("pull-out torque dwells", dm.peak_what + " holding in the dwells", dm.peak_num, "N m",
                             lambda sig, pl=dm.peak_num, tr=dm.tau_ref: pl + sig * tr, None, "pull_out_torque",
                             enforced=lambda r: r.settings.enforce_pull_out)
            g.built.limit(lim, ca.vertcat(tau_d - 1.0, -tau_d - 1.0) * (dm.peak_num / dm.tau_ref))


class RmsTorque(Limit):
    """RMS motor torque over the cycle within the rated torque; owns the integral of torque squared."""

    checks = ("rms_torque",)

    def on_move(self, g, k):
        # integral of torque squared over the move (Gauss-Legendre points), accumulated along the
        # move in a chain of variables, one link per mesh interval: a single sum over every node
        # would make one dense Jacobian row (costly to differentiate)
        from ...drive.load import load_torque

        dm, b, mesh, mv = g.drive_model, g.built, g.request.mesh, g.request.moves[k]
        if dm.rated is None and not objective_of(g.request.objective).torque_squared:  # a stepper: not asked for
            return
        x_q, w_q = mesh.quadrature
        sq, vq, aq = (g.si(k, x_q, kind) for kind in ("s", "v", "a"))  # N x len(x_q)
        tq = load_torque(dm.rotor, dm.trans, g.load, sq, vq, aq).total / dm.tau_ref
        per_interval = ca.mtimes(tq**2, ca.DM(w_q)) * (mesh.h * g.T[k] / dm.period)
        Q = b.var(f"torque2 move {mv.index}", (mesh.intervals + 1, 1), -np.inf, np.inf, 0.0)
        b.constrain(f"torque2 move {mv.index}", ca.vertcat(Q[0], Q[1:] - Q[:-1] - per_interval), 0.0, 0.0)
        return {"move_sq": Q[-1]}

    def on_cycle(self, g, terms):
        dm = g.drive_model
        if "move_sq" not in terms:  # a stepper that no objective asks it of
            return None
        mean_sq = terms["move_sq"] + dm.dwell_sq   # the RMS torque squared over the cycle, dwells included
        if dm.rated is not None:  # a stepper: no rated torque to hold (its current does not follow the load)
            lim = LimitGroup("RMS torque", f"rms_torque (RMS torque, {dm.motor_name}: rated torque)", dm.rated_num,
                             "N m", lambda sig, r=dm.rated_num, tr=dm.tau_ref: math.sqrt(r**2 + sig * tr**2), None,
                             "rms_torque")
            g.built.limit(lim, mean_sq - (dm.rated / dm.tau_ref) ** 2)
        return {"mean_sq": mean_sq}


class BeltTension(Limit):
    """The effective belt tension within what the belt checks allow (width and breaking, the one that binds)."""

    checks = ("belt_width", "belt_breaking")

    def on_cycle(self, g, terms):
        dm, req = g.drive_model, g.request
        belt = req.drive.belt_limit(req.choice.belt_grooves)
        if belt is None:
            return None
        # the tension the belt checks allow; said in the units of the check that binds (the drive package's names)
        check, f_allow, belt_lim, belt_unit = belt
        f_lim = g.built.param("belt force limit", lambda r: r.drive.belt_limit(r.choice.belt_grooves)[1])
        allf = ca.horzcat(*[ca.reshape(f, 1, -1) for f in dm.forces]) / f_lim
        what = {"belt_width": "belt_width (width factor the belt tension requires)",
                "belt_breaking": "belt_breaking (belt tension with safety factor, against the breaking load)"}[check]
        lim = LimitGroup("belt tension", what, belt_lim, belt_unit, lambda sig, bl=belt_lim: bl * (1 + sig), None,
                         check)
        g.built.limit_abs(lim, allf)
        return {"pin_values": [f / f_lim for f in dm.pin_forces]}  # the pins' belt forces (refine.pins_in_place)


class InertiaRatio(Limit):
    """Load/rotor inertia ratio: a constraint only when the radius is free (a chosen pulley is checked, not held)."""

    def on_cycle(self, g, terms):
        dm, req = g.drive_model, g.request
        if req.choice.candidates or dm.radius is None:  # nothing to choose: the ratio is checked, not held
            return None
        limits = req.drive.limits
        reflected = dm.inertia + req.drive.load.moving_mass * dm.radius**2
        lim = LimitGroup("inertia ratio", "inertia_ratio (load/rotor inertia ratio)", limits.max_inertia_ratio,
                         "-", lambda sig, mr=limits.max_inertia_ratio: mr * (1 + sig), None, "inertia_ratio",
                         enforced=lambda r: r.choice.teeth is None)
        g.built.limit(lim, reflected / (dm.rotor * limits.max_inertia_ratio) - 1.0)


class HandoverAccuracy(Limit):
    """The sum of the request's handover error terms (:class:`~.request.ErrorTerm`) within ``accuracy``.

    A lazy constraint: a term may sum over a whole move (a servo tracking error), which makes a
    dense Hessian block that is costly to build and factorise. The solve runs without it, checks
    it at the solution, and only if it is violated re-solves with it (``enforce_accuracy``).
    """

    def on_cycle(self, g, terms):
        req = g.request
        terms = [(t.name, e) for t in req.error_terms for e in [t.expression(g)] if e is not None]
        if not terms:
            return None
        signed = sum(e.signed for _, e in terms)
        bound = sum(e.bound for _, e in terms)
        if isinstance(signed, (ca.MX, ca.SX)) and req.enforce_accuracy:
            acc = req.settings.accuracy
            lim = LimitGroup("handover accuracy", "handover accuracy", acc, "rad" if req.problem.timing.rotary else "m",
                             lambda sig, ac=acc: ac * (1 + sig))
            g.built.limit(lim, ca.vertcat(signed + bound, bound - signed) / acc - 1.0)
        return {"handover": HandoverError(tuple((name, _largest(e.signed, e.bound)) for name, e in terms),
                                          _largest(signed, bound), signed, bound)}

    def report(self, nlp, outcome):
        scale, unit = error_unit(nlp.request.problem.timing.rotary)   # mm, or deg for a rotary load
        return [{"name": f"handover accuracy ({name})", "value": value * scale,
                 "limit": nlp.request.settings.accuracy * scale, "unit": unit}
                for name, value in outcome.handover_values()]


def _largest(signed, bound):
    """The largest error over the checked instants: ``max |signed| + bound`` (for reports, not a constraint)."""
    if isinstance(signed, (ca.MX, ca.SX)):
        return ca.mmax(ca.fabs(signed)) + bound
    return abs(signed) + bound


#: Limits of the kinematics, built with every move.
MOVE_LIMITS = (JerkBound(),)
#: Limits of the drive, built with a [drive] section, in this order.
DRIVE_LIMITS = (PeakTorque(), Speed(), PullOut(), RmsTorque(), BeltTension(), InertiaRatio(), HandoverAccuracy())
#: the drive package's checks the design holds: a fine-grid violation of one of them refines the mesh.
ENFORCED_CHECKS = frozenset(c for lim in DRIVE_LIMITS for c in lim.checks)
#: a stepper's checks of its pull-out curve (its peak torque is the curve's at standstill)
PULL_OUT_CHECKS = frozenset(("pull_out_torque", "peak_torque"))


def enforced_checks(settings, stepper: bool) -> frozenset:
    """The checks a design with ``settings`` holds (:data:`ENFORCED_CHECKS`; on a ``stepper`` without its pull-out
    curve when ``[design] enforce_pull_out = false``: those are reported, a violation does not refine the mesh)."""
    if settings.enforce_pull_out or not stepper:
        return ENFORCED_CHECKS
    return ENFORCED_CHECKS - PULL_OUT_CHECKS


def build_drive(g) -> dict:
    """The drive's symbols (:class:`DriveModel`, ``g.drive_model``) and every drive limit, move by move then over
    the cycle; returns the terms they return (:func:`collect`) with the pinned torques' (``pin_values``,
    ``pin_share``)."""
    dm = g.drive_model = DriveModel.build(g)
    terms: dict = {}
    for k in range(len(g.request.moves)):
        dm.move(g, k)
        for lim in DRIVE_LIMITS:
            collect(terms, lim.on_move(g, k))
    dm.dwells(g)
    for lim in DRIVE_LIMITS:
        collect(terms, lim.on_cycle(g, terms))
    collect(terms, {"pin_values": list(dm.pin_values)})
    if dm.pin_torques:  # the largest pinned torque over the largest torque of the cycle (refine.pins_in_place)
        peak = ca.mmax(ca.fabs(ca.vertcat(*[ca.vec(t) for t in dm.torques + dm.dwell_torques])))
        terms["pin_share"] = ca.mmax(ca.fabs(ca.vertcat(*dm.pin_torques))) / ca.fmax(peak, 1e-12)
    return terms


def gathered(terms: dict) -> Terms:
    """The :class:`Terms` of the builders' returned ``terms`` (the pins' values stacked)."""
    pins = terms.get("pin_values") or []
    impact = terms.get("impact_speeds") or []
    return Terms(terms.get("move_sq"), terms.get("mean_sq"), ca.vertcat(*pins) if pins else None,
                 terms.get("pin_share"), terms.get("handover", HandoverError()), ca.vertcat(*impact) if impact else None)
