"""A model on the members of a transmission (an elastic chain) against the rigid chain.

Where it sits: after simulate.py. A model whose bodies move on the members of the problem's
transmission (``stage`` in ``[model.bodies.*]``: the knitting machine's screw, lever and sleeve) is
driven through the transmission; :func:`chain_results` puts each staged body's peak acceleration
beside the rigid chain's (the same member's acceleration when every link is rigid: the
transmission's stage kinematics of the stroke), the links' peak forces (compression and tension:
the tension of a link is what a preload spring would have to hold against lift-off) and, for a
screw, the screw torque from the force on the driven nut.
"""

from __future__ import annotations

import numpy as np


def chain_results(problem, result, stroke) -> dict:
    """Elastic against rigid for ``result`` (a :class:`~strokeopt.contact.simulate.SceneResult` of a
    staged model) driven by ``stroke``; empty for a model without stages."""
    model = problem.model
    tr = model.transmission if model is not None else None
    if tr is None:
        return {}
    sc = problem.scenes[result.scene]
    kin = stroke.evaluate(result.t)
    rigid = tr.stage_kinematics(kin.s, kin.v, kin.a, kin.j)
    bodies = []
    for name in sc.bodies:
        body = model.bodies[name]
        if body.stage is None:
            continue
        elastic = float(np.max(np.abs(result.accelerations[name])))
        rigid_peak = float(np.max(np.abs(rigid[body.stage][2])))
        unit = "rad/s^2" if body.angular else "m/s^2"
        bodies.append({"body": name, "stage": body.stage, "label": body.label, "unit": unit,
                       "elastic_peak_accel": elastic, "rigid_peak_accel": rigid_peak,
                       "ratio": elastic / rigid_peak if rigid_peak > 0 else None})
    links = []
    for name in sc.elements:
        el = model.elements[name]
        if el.kind != "link":
            continue
        f = np.asarray(result.forces[name])
        angular = any(model.bodies[b].angular for b in el.bodies if b in model.bodies)
        links.append({"link": name, "unit": "N m" if angular else "N", "peak_compression": float(max(np.max(f), 0.0)),
                      "peak_tension": float(max(-np.min(f), 0.0)), "peak_abs": float(np.max(np.abs(f))),
                      "log_decrement": el.log_decrement, "damping": el.damping, "clearance": el.clearance})
    out = {"bodies": bodies, "links": links}
    screw = getattr(tr, "screw_torque", None)
    if screw is not None and tr.screw_diameter is not None:
        peak = float(np.max(np.abs(result.drive_force)))
        out["screw"] = {"peak_nut_force_N": peak, "screw_torque_N_cm": screw(peak) * 100,
                        "screw_diameter_mm": tr.screw_diameter * 1e3, "thread_friction": tr.thread_friction,
                        "thread_angle_deg": float(np.degrees(tr.thread_angle))}
    return out
