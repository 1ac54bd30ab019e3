"""The limits of ``[design.contact]``: one builder per limit, as in :mod:`.limits`, from the rigid cluster of
the contact model (contact/cluster.py, :class:`~.contact_setup.ContactDesign`).

* :class:`KeepClosed`: the force of every ``keep_closed`` contact, an algebraic function of the stroke's
  ``s, v, a`` and the model's springs, preloads and masses, at least ``min_contact_force_N`` wherever the
  cluster holds (its follower not on a stop). Held at the Bernstein control points of each interval's
  acceleration (the acceleration is bounded everywhere, convex hull) with the position and speed at their
  Greville abscissae, as the drive's torque (:mod:`.drive_model`);
* :class:`ImpactVelocity`: the driven body's speed where the cluster meets the ``[model.events] impact``
  contact, a pinned point like the load switches (:mod:`.pins`), within ``impact_velocity_max_m_s``.

Each reports its fine-grid check (the exact polynomials between the nodes) in the checks table; the full
simulation's verdict is the verification (contact/verify.py).
"""

from __future__ import annotations

import casadi as ca
import numpy as np

from .collocation import fine_grid
from .limits import Limit, LimitGroup
from .free import model_values
from .pins import IMPACT_OBJECTIVE, crossings, pin_crossing, pin_motion


def _move_motion(mv, sol, per_interval: int):
    """Stroke position, velocity, acceleration [SI] of one solved move on its fine grid."""
    tau = fine_grid(sol.mesh, per_interval)
    y, y1, y2 = sol.evaluate(tau)[:3]
    return tau, mv.start + mv.stroke * y, y1 * mv.stroke / mv.duration, y2 * mv.stroke / mv.duration**2


#: How fast a keep_closed row is relaxed past a stop [1/m of overrun, in units of the row's scale]: 10 scales
#: within 0.1 mm, more than any force the follower could then miss.
RELAX = 1e5


class KeepClosed(Limit):
    """The force of each ``keep_closed`` contact at least ``min_contact_force_N`` while the cluster holds."""

    def on_cycle(self, g, terms):
        req = g.request
        cd = req.contact
        if cd is None or not cd.settings.keep_closed:
            return
        cl, fmin = cd.cluster, cd.settings.min_contact_force
        stiffness = g.free_stiffness  # free model parameters (design/free.py); none: the model's numbers
        greville = np.linspace(0.0, 1.0, req.mesh.degree + 1)
        for name in cd.settings.keep_closed:
            rest = cd.rest_force(name)  # the scale of the rows and the reference of the message
            scale = max(abs(rest), fmin, 1.0)
            follower = cl.joining[name]
            for k, mv in enumerate(req.moves):
                s_nodes = g.si(k, greville, "s")
                s = ca.vec(s_nodes)
                v = ca.vec(g.si(k, greville, "v"))
                a = ca.vec(g.vars[k].hull("a")) * (mv.stroke / g.T[k] ** 2)
                xd, vd, ad = cd.driven(s, v, a)
                # smooth rows: the force without the stops, relaxed steeply (RELAX per metre) past a stop, where
                # the cluster no longer holds (a 0/1 mask there made IPOPT cycle as points crossed the stop);
                # a row is relaxed by the overrun of the end of its interval that is nearer the stop, so an
                # interval that holds anywhere is held everywhere (its polynomial cannot dip between the nodes)
                force = cl.contact_force(name, xd, vd, ad, stiffness, stops=False)
                ends = [cl.overrun(name, cd.driven(s_nodes[:, j], 0 * s_nodes[:, j], 0 * s_nodes[:, j])[0])
                        for j in (0, greville.size - 1)]
                overrun = ca.repmat(ca.fmin(*ends), greville.size, 1)
                lim = LimitGroup(
                    f"keep {name} closed move {mv.index}", f"contact {name} closed", rest, "N",
                    lambda sig, rest=rest, scale=scale: rest + sig * scale, mv.index, f"keep_closed {name}",
                    describe=lambda need, rest=rest, name=name, follower=follower, fmin=fmin: (
                        f"contact {name} opens: the {follower} needs {need - rest:.3g} N more than the springs give "
                        f"at rest ({rest:.3g} N) to follow the {cl.scene.driven} with at least {fmin:g} N "
                        f"(design.contact.min_contact_force_N): a stiffer spring or a lower stitch rate"))
                g.built.limit(lim, (fmin - force) / scale - RELAX * overrun)

    def report(self, nlp, outcome):
        req = nlp.request
        cd = req.contact
        if cd is None or not cd.settings.keep_closed:
            return []
        stiffness = model_values(outcome.free_values)
        rows = []
        for name in cd.settings.keep_closed:
            low = np.inf
            for mv, sol in zip(req.moves, outcome.sols):
                _, s, v, a = _move_motion(mv, sol, req.settings.check_points)
                xd, vd, ad = cd.driven(s, v, a)
                force = np.asarray(cd.cluster.contact_force(name, xd, vd, ad, stiffness), float)
                held = np.asarray(cd.cluster.holds(name, xd), bool)
                if held.any():
                    low = min(low, float(np.min(force[held])))
            if np.isfinite(low):  # the follower rides on the driven body somewhere in the cycle
                rows.append({"name": f"contact {name} force (kept closed, >= limit)", "value": low,
                             "limit": cd.settings.min_contact_force, "unit": "N", "lower": True})
        return rows


class ImpactVelocity(Limit):
    """The driven body's speed where the cluster meets the impact contact within ``impact_velocity_max_m_s``."""

    def on_cycle(self, g, terms):
        req = g.request
        cd = req.contact
        out = {}
        if req.objective == IMPACT_OBJECTIVE:  # the objective's speeds, at crossings held at the stop
            out["impact_speeds"] = [v for _, v in impact_speeds(g, crossing=True)]
        vmax = None if cd is None else cd.settings.impact_velocity_max
        speeds = impact_speeds(g) if vmax is not None else []
        for mv, speed in speeds:
            lim = LimitGroup(f"impact velocity move {mv.index}", f"impact velocity ({cd.impact[0]} meets "
                             f"{req.problem.model.events.impact})", vmax, "m/s",
                             lambda sig: vmax * (1 + sig), mv.index, "impact velocity")
            g.built.limit_abs(lim, speed / vmax)
        if speeds:  # the pins move with the solution: refine.pins_in_place compares these too
            out["pin_values"] = [speed / vmax for _, speed in speeds]
        return out

    def report(self, nlp, outcome):
        req = nlp.request
        cd = req.contact
        if cd is None or cd.settings.impact_velocity_max is None or cd.impact_position is None:
            return []
        speeds = []
        for mv, sol in zip(req.moves, outcome.sols):
            if cd.closes_impact(mv):
                tau = crossings(sol, mv, [cd.impact_position], fine_grid(sol.mesh, req.settings.check_points))
                if len(tau):
                    speeds.append(abs(float(sol.evaluate(tau[:1])[1][0])) * abs(mv.stroke) / mv.duration)
        if not speeds:
            return []
        return [{"name": f"impact velocity ({req.problem.model.events.impact})", "value": max(speeds),
                 "limit": cd.settings.impact_velocity_max, "unit": "m/s"}]


def impact_speeds(g, crossing: bool = False) -> list:
    """``(move, signed speed [m/s] times the pin's weight)`` where each move that closes the impact contact meets
    its position (the pins of :func:`.pins.pin_positions`); empty without an impact pin. ``crossing``: at a crossing
    time that is a variable held at the position (:func:`.pins.pin_crossing`, for the objective), else at the pin's
    time (:func:`.pins.pin_motion`, for the limit)."""
    req = g.request
    cd = req.contact
    if cd is None or cd.impact_position is None:
        return []
    out = []
    for k, pos, first in g.pins:
        mv = req.moves[k]
        if pos == cd.impact_position and cd.closes_impact(mv):
            weight, v = pin_crossing(g, k, pos, first) if crossing else pin_motion(g, k, pos, first)[:2]
            out.append((mv, weight * v))
    return out


#: The limits of ``[design.contact]``, built after the moves and the drive (:func:`.nlp.build_graph`).
CONTACT_LIMITS = (KeepClosed(), ImpactVelocity())
