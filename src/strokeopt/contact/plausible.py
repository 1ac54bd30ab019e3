"""How large a force the contact model can plausibly report: a limit per element, derived from the model.

The rule (one per scene, from the model's masses, stiffnesses, force laws and springs and the stroke it
is driven by; no number of a particular mechanism):

* every body may move at up to twice the speed the stroke gives it when the chain is rigid (its
  transmission member's speed; the driven body's speed for a model on one axis): a light body struck by
  the driven one, whose motion is imposed, leaves an elastic impact at twice the striker's speed;
* the energy at stake is the kinetic energy of every body of the scene at that speed plus what every
  spring of the scene holds when compressed by its preload and the full travel of both its bodies:
  ``E = 1/2 sum m (2 w)^2 + sum_springs int law``;
* an element carries at most the elastic force at which it stores all of ``E`` (``sqrt(2 k E)`` for a
  linear stiffness, the force law's own curve for a pad), plus its damping at the largest closing speed
  (``b (2 w_a + 2 w_b)``), plus the force that accelerates every body of the scene at twice its rigid
  peak acceleration (``sum m 2 a``);
* the drive force carries at most the limits of the elements on the driven body plus its own inertia.

A reported peak beyond its limit is then not a force of the mechanism but of the model taken where it does
not hold: contacts pushed into each other by a stroke the stops cannot take, a stiffness the integrator did
not resolve (every stroke x1000 on the reference problem, read past its stops: 1.59e10 N through the pad,
c32 and c13 against limits of 1.0e8 to 3.4e8 N). Its verdict is "verification failed", never "ok" (verify.py; ``strokeopt simulate`` exits 1).

Why not the catalogue: the contact model takes the stroke as given (an infinitely stiff drive), so the
force the drive supplies in a 1e9 N/m impact is a spike of microseconds the belt never sees as tension:
on the unmodified reference problem it is 4685 N against the belt's breaking load of 1990 N and the
055U2B30's peak torque over the pulley's radius (about 300 N). Either limit would call the reference
absurd; the energy limit leaves it 26 times below (c21 4682 N against 121 kN; the drive 4685 N against
362 kN).
"""

from __future__ import annotations

import math

import numpy as np

from .model import FRAME

#: How much faster than its rigid motion a body may move, and how much harder it may be accelerated: an
#: elastic impact of a light body on the driven one (imposed motion) leaves it at twice the striker's speed.
REBOUND = 2.0


def _law_energy(el, c: float) -> float:
    """Elastic energy of ``el`` compressed by ``c`` (J, or J per rad for a torsion: N m rad)."""
    if el.force_law is None:
        return 0.5 * el.stiffness * c * c
    return sum(k * c ** (i + 1) / (i + 1) for i, k in enumerate(el.force_law.coefficients))


def _force_at_energy(el, energy: float) -> float:
    """The largest elastic force ``el`` reaches while storing at most ``energy``."""
    if energy <= 0:
        return 0.0
    if el.force_law is None:
        return math.sqrt(2.0 * max(el.stiffness, 0.0) * energy)
    lo, hi = 0.0, 1e-3
    while _law_energy(el, hi) < energy and hi < 1e3:
        hi *= 2.0
    for _ in range(200):
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if _law_energy(el, mid) < energy else (lo, mid)
    return float(np.max(np.abs(el.elastic_force(np.linspace(0.0, hi, 201)))))


def _rigid_motion(problem, scene, stroke, t) -> dict:
    """``{body: (travel, peak speed, peak acceleration)}`` of every body of ``scene`` when the chain is rigid:
    on one axis the stroke's own; on a transmission's members each member's (its stage's kinematics)."""
    kin = stroke.evaluate(np.asarray(t, float))
    s, v, a = (np.asarray(x, float).ravel() for x in (kin.s, kin.v, kin.a))
    model = problem.model
    stages = (model.transmission.stage_kinematics(s, v, a, np.asarray(kin.j, float).ravel())
              if model.transmission is not None else {})
    out = {}
    for name in scene.bodies:
        stage = model.bodies[name].stage
        q, dq, ddq = stages[stage][:3] if stage in stages else (s, v, a)
        q, dq, ddq = (np.asarray(x, float).ravel() for x in (q, dq, ddq))
        out[name] = (float(np.ptp(q)), float(np.max(np.abs(dq))), float(np.max(np.abs(ddq))))
    return out


def force_limits(problem, scene_name: str, stroke, t) -> dict:
    """The plausible peak force of every element of ``scene_name`` and of the drive (key ``"drive"``) for a
    cycle driven by ``stroke`` sampled at times ``t`` [N, or N m on an angular coordinate] (the module's rule)."""
    model = problem.model
    scene = problem.scenes[scene_name]
    rigid = _rigid_motion(problem, scene, stroke, t)
    elements = [model.elements[e] for e in scene.elements]
    energy = sum(0.5 * model.bodies[b].mass * (REBOUND * w) ** 2 for b, (_, w, _) in rigid.items())
    for el in elements:
        if el.kind == "spring":
            travel = sum(rigid[b][0] for b in el.bodies if b != FRAME)
            energy += max(_law_energy(el, el.offset + travel), 0.0)

    def angular(names) -> bool:
        return any(model.bodies[b].angular for b in names if b != FRAME)

    limits = {}
    for el in elements:
        kind = angular(el.bodies)
        inertial = sum(model.bodies[b].mass * REBOUND * acc for b, (_, _, acc) in rigid.items()
                       if model.bodies[b].angular == kind)
        closing = sum(REBOUND * rigid[b][1] for b in el.bodies if b != FRAME)
        limits[el.name] = _force_at_energy(el, energy) + el.damping * closing + inertial
    driven = scene.driven
    limits["drive"] = (model.bodies[driven].mass * REBOUND * rigid[driven][2]
                       + sum(limits[el.name] for el in elements if driven in el.bodies))
    return limits


def implausible_peaks(result, limits: dict) -> list[dict]:
    """The peaks of ``result`` (a :class:`~strokeopt.contact.simulate.SceneResult`) beyond ``limits``
    (:func:`force_limits`): ``{"force", "value", "limit"}`` each, largest excess first; a peak that is not a
    finite number is beyond every limit."""
    m = result.metrics
    peaks = dict(m.get("peak_contact_forces_N") or {})
    if m.get("peak_drive_force_N") is not None:
        peaks["drive"] = m["peak_drive_force_N"]
    out = []
    for name, value in peaks.items():
        limit = limits.get(name)
        if limit is None or value is None:
            continue
        if not (math.isfinite(value) and abs(value) <= limit):
            out.append({"force": name, "value": float(value), "limit": float(limit)})
    return sorted(out, key=lambda r: -(abs(r["value"]) / r["limit"] if r["limit"] > 0 else math.inf))


def scene_implausible(problem, result, stroke) -> list[dict]:
    """:func:`implausible_peaks` of ``result`` against the limits of its scene driven by ``stroke``."""
    model = problem.model
    if model is None or not problem.scenes or result.scene not in problem.scenes:
        return []
    rows = implausible_peaks(result, force_limits(problem, result.scene, stroke, result.t))
    for r in rows:  # a torsion link's moment, or a force
        names = [model.driven] if r["force"] == "drive" else model.elements[r["force"]].bodies
        bodies = [model.bodies[b] for b in names if b != FRAME]
        r["unit"] = "N m" if any(b.angular for b in bodies) else "N"
    return rows


def implausible_text(rows: list[dict]) -> str:
    """One phrase naming the implausible peaks with their limits (the rule: contact/plausible.py)."""
    def name(r):
        return "the drive force" if r["force"] == "drive" else f"peak force of {r['force']}"

    return "; ".join(f"{name(r)} {r['value']:.4g} {r.get('unit', 'N')} > plausible {r['limit']:.4g} "
                     f"{r.get('unit', 'N')}" for r in rows)
