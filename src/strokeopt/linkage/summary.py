"""What an engineer asks of a crank-driven linkage, as one dict: structure, the outputs over the input angle
(position, speed, acceleration, jerk at the machine's speed), swing, near-dwells by the file's criterion,
forward/return asymmetry, transmission quality against the file's limit, and the crank torque."""

from __future__ import annotations

import math

import numpy as np

from .dynamics import analyse_dynamics
from .kinematics import Cycle, Kinematics, kinematics_of

TABLE_STEP_DEG = 10.0


def _units(kind: str) -> tuple[str, float]:
    """The unit of an output's position and its scale from SI: angles in deg, lengths in mm."""
    return ("deg", math.degrees(1.0)) if kind == "angle" else ("mm", 1e3)


def near_dwells(theta: np.ndarray, y: np.ndarray, share: float) -> list[dict]:
    """Crank-angle spans where the output stays within ``share`` of its swing of an extreme."""
    swing = y.max() - y.min()
    out = []
    for name, inside in (("maximum", y >= y.max() - share * swing), ("minimum", y <= y.min() + share * swing)):
        k0 = int(np.argmax(y) if name == "maximum" else np.argmin(y))
        n, step = len(y), theta[1] - theta[0]
        lo = hi = k0
        while inside[(lo - 1) % n] and hi - lo < n - 1:
            lo -= 1
        while inside[(hi + 1) % n] and hi - lo < n - 1:
            hi += 1
        out.append({"at": name, "from_deg": _deg(theta[0] + lo * step), "to_deg": _deg(theta[0] + hi * step),
                    "length_deg": round(math.degrees((hi - lo) * step), 6)})
    return out


def _deg(t: float) -> float:
    return round(math.degrees(t) % 360, 6)


def output_summary(kin: Kinematics, cycle: Cycle, name: str, omega: float, share: float) -> dict:
    out = next(o for o in kin.linkage.outputs if o.name == name)
    unit, scale = _units(out.kind)
    y, d1, d2, d3 = kin.output(cycle, name)
    v, a, j = d1 * omega, d2 * omega ** 2, d3 * omega ** 3
    th = cycle.theta
    k_min, k_max = int(np.argmin(y)), int(np.argmax(y))
    rise = math.degrees((th[k_max] - th[k_min]) % (2 * math.pi))
    speed_unit = "rad/s" if out.kind == "angle" else "m/s"
    step = max(1, int(round(math.radians(TABLE_STEP_DEG) / (th[1] - th[0]))))
    rows = [{"angle_deg": _deg(th[k]), "position": float(y[k] * scale), "speed": float(v[k]),
             "acceleration": float(a[k]), "jerk": float(j[k])} for k in range(0, len(th), step)]
    peak = lambda x: {"max_abs": float(np.abs(x).max()), "at_deg": _deg(th[int(np.argmax(np.abs(x)))])}  # noqa: E731
    return {"name": name, "kind": out.kind, "unit": unit, "speed_unit": speed_unit,
            "acceleration_unit": speed_unit.replace("/s", "/s^2"), "jerk_unit": speed_unit.replace("/s", "/s^3"),
            f"swing_{unit}": float((y.max() - y.min()) * scale),
            "minimum_at_deg": _deg(th[k_min]), "maximum_at_deg": _deg(th[k_max]),
            "rise_deg": round(rise, 6), "fall_deg": round(360 - rise, 6),
            "asymmetry_rise_over_fall": rise / (360 - rise),
            "near_dwells": near_dwells(th, y, share),
            "peaks": {"speed": peak(v), "acceleration": peak(a), "jerk": peak(j)}, "table": rows}


#: The classic guidance for a dyad's least transmission angle (Alt's) [deg]: aim for 40, 30 at worst; below it
#: the joint force grows as 1 / sin of the angle for the same output torque. Warned of, not judged: the file's
#: ``min_transmission_index`` is the limit.
CLASSIC_TRANSMISSION_ANGLE_DEG = (40.0, 30.0)


def transmission_summary(kin: Kinematics, cycle: Cycle, limit: float) -> list[dict]:
    out = []
    for g, group in enumerate(cycle.groups):
        idx = cycle.index[:, g]
        k = int(np.argmin(idx))
        row = {"group": group.kind, "links": list(group.links), "min_index": float(idx[k]),
               "at_deg": _deg(cycle.theta[k]),
               "limit": limit, "ok": bool(idx[k] >= limit)}
        if group.kind == "dyad":   # Alt's transmission angle: the index is its sine
            row["min_transmission_angle_deg"] = math.degrees(math.asin(min(1.0, idx[k])))
            row["below_classic_guidance"] = row["min_transmission_angle_deg"] < CLASSIC_TRANSMISSION_ANGLE_DEG[1]
        out.append(row)
    return out


def summarize(problem, with_dynamics: bool | None = None) -> dict:
    """The whole analysis of a LinkageProblem (kinematics at its rpm, dynamics where the file has masses
    or loads); ``status`` 'limits exceeded' when the transmission index falls below the file's limit."""
    kin = kinematics_of(problem.linkage)
    cycle = kin.solve(problem.angles)
    share = problem.near_dwell_pct / 100
    trans = transmission_summary(kin, cycle, problem.min_transmission_index)
    summary = {"status": "ok" if all(t["ok"] for t in trans) else "limits exceeded",
               "problem": problem.name, "file": problem.file, "rpm": problem.rpm, "omega_rad_s": problem.omega,
               "structure": kin.structure.to_dict(),
               "link_lengths_mm": {link.name: {f"{a}-{b}": round(problem.linkage.length(a, b) * 1e3, 4)
                                               for i, a in enumerate(link.joints) for b in link.joints[i + 1:]}
                                   for link in problem.linkage.links},
               "closure": {"angles": len(cycle.theta), "max_residual_m": float(cycle.residual.max()),
                           "return_error_m": cycle.return_error, "steps": cycle.substeps},
               "outputs": [output_summary(kin, cycle, o.name, problem.omega, share) for o in problem.linkage.outputs],
               "transmission": trans, "near_dwell_pct": problem.near_dwell_pct}
    has_mass = any(link.mass > 0 or link.inertia_cg > 0 for link in problem.linkage.links) or problem.linkage.loads
    if with_dynamics or (with_dynamics is None and has_mass):
        dyn = analyse_dynamics(kin, cycle, problem.omega)
        summary.update(dynamics=dyn.to_dict(), terms=dynamics_table(dyn), gravity_m_s2=problem.linkage.gravity,
                       process_loads=[{"name": ld.name, "link": ld.link, "joint": ld.joint,
                                       "from_deg": round(math.degrees(ld.start), 6),
                                       "to_deg": round(math.degrees(ld.end), 6), "force_start_N": ld.force_start,
                                       "force_end_N": ld.force_end, "direction_deg": round(math.degrees(ld.direction), 6)}
                                      for ld in problem.linkage.loads],
                       note=None if has_mass else "the file states no masses, inertias or process loads: the crank "
                                                  "needs no torque, and a sizing checks only the motors' speed and the "
                                                  "gearboxes' inertia")
    return summary


def dynamics_table(dyn, step_deg: float = TABLE_STEP_DEG) -> list[dict]:
    """The crank torque's terms every ``step_deg`` of crank: reduced inertia J and J', the inertia term
    J' omega^2 / 2, gravity V', the process loads, the power-balance torque and Newton-Euler's."""
    th = dyn.theta
    step = max(1, int(round(math.radians(step_deg) / (th[1] - th[0]))))
    return [{"angle_deg": _deg(th[k]), "J_kg_m2": float(dyn.J[k]), "dJ_kg_m2_rad": float(dyn.dJ[k]),
             "inertia_torque_N_m": float(0.5 * dyn.dJ[k] * dyn.omega ** 2),
             "gravity_torque_N_m": float(dyn.gravity_torque[k]), "process_torque_N_m": float(dyn.load_torque[k]) + 0.0,
             "torque_N_m": float(dyn.torque[k]), "torque_newton_euler_N_m": float(dyn.torque_ne[k])}
            for k in range(0, len(th), step)]


def measures(summary: dict, output: str) -> dict:
    """The scalar results of an analysis a tolerance study scatters (units in the names): the swing and the
    near-dwells of ``output``, the least transmission index, and with dynamics the crank torque's peak and RMS."""
    o = next(x for x in summary["outputs"] if x["name"] == output)
    unit = o["unit"]
    out = {f"{output}_swing_{unit}": o[f"swing_{unit}"]}
    for d in o["near_dwells"]:
        out[f"{output}_dwell_at_{d['at']}_deg"] = float(d["length_deg"])
    if summary["transmission"]:
        out["min_transmission_index"] = min(float(t["min_index"]) for t in summary["transmission"])
    if "dynamics" in summary:
        t = summary["dynamics"]["torque_N_m"]
        out.update(crank_torque_peak_N_m=max(abs(t["max"]), abs(t["min"])), crank_torque_rms_N_m=t["rms"])
    return out
