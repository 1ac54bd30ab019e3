"""Linkage reports: the text of a linkage summary (strokeopt.linkage.summary), of a synthesis, and the
figure: the mechanism at several poses with its output paths, the output over the input angle, and the
transmission index over the cycle. Formats and draws only: the numbers come from strokeopt.linkage."""

from __future__ import annotations

import math

import numpy as np

from ..linkage.summary import CLASSIC_TRANSMISSION_ANGLE_DEG
from .format import format_table


def linkage_text(s: dict) -> str:
    st = s["structure"]
    lines = [f"{s['problem']}  ({s['file']})",
             f"crank {s['rpm']:g} rpm = {s['omega_rad_s']:.4f} rad/s",
             f"structure: mobility {st['mobility']}, {st['links']} links (with the ground), "
             f"{st['revolute_joints']} revolute joints, {st['independent_loops']} independent loops"]
    for g in st["groups"]:
        if g["kind"] != "placement":
            lines.append(f"  group solved together: {g['kind']} of links {', '.join(g['links'])} "
                         f"(joints {', '.join(g['joints'])}; attached to {', '.join(g['attached_to'])})")
    for f in st["four_bar_loops"]:
        lines.append(f"  four-bar loop {'-'.join(f['joints'])} ({', '.join(f['links'])}): {f['grashof']}, "
                     f"{f['class']} relative to {f['relative_to']}")
        if f.get("near_change_point"):
            lines.append(f"  WARNING: loop {'-'.join(f['joints'])} is {f['change_point_distance_mm']:.3g} mm from a change "
                         "point (shortest + "
                         "longest = sum of the other two): a link tolerance of that size can let it fold onto a line "
                         "and pass into its other branch (toggle)")
    c = s["closure"]
    lines.append(f"closure: {c['angles']} input angles, largest residual {c['max_residual_m']:.1e} m, pose after one "
                 f"turn off by {c['return_error_m']:.1e} m")
    for o in s["outputs"]:
        lines += ["", _output_text(o, s["near_dwell_pct"])]
    lines.append("")
    for t in s["transmission"]:
        verdict = "ok" if t["ok"] else "BELOW THE LIMIT"
        if "min_transmission_angle_deg" in t:   # a dyad: its quality in degrees (the index is the angle's sine)
            angle = t["min_transmission_angle_deg"]
            limit = math.degrees(math.asin(min(1.0, t["limit"])))
            lines.append(f"transmission angle of the {t['group']} {', '.join(t['links'])}: least {angle:.1f} deg at "
                         f"{t['at_deg']:g} deg (Alt's; index {t['min_index']:.3f}); the file's limit {limit:.1f} deg "
                         f"(min_transmission_index {t['limit']:g}): {verdict}")
            if t.get("below_classic_guidance"):
                lines.append(f"  WARNING: {angle:.1f} deg is below the classic guidance for a transmission angle "
                             f"({CLASSIC_TRANSMISSION_ANGLE_DEG[0]:g} deg, {CLASSIC_TRANSMISSION_ANGLE_DEG[1]:g} at "
                             f"worst): the joint force there is {1 / math.sin(math.radians(angle)):.3g} times the part "
                             "that turns the output")
        else:
            lines.append(f"transmission index of the {t['group']} {', '.join(t['links'])}: min {t['min_index']:.3f} at "
                         f"{t['at_deg']:g} deg; limit {t['limit']:g}: {verdict}")
    if "dynamics" in s:
        lines += ["", _dynamics_text(s["dynamics"])]
    return "\n".join(lines)


def _output_text(o: dict, pct: float) -> str:
    u, su = o["unit"], o["speed_unit"]
    lines = [f"output {o['name']} ({o['kind']}): swing {o['swing_' + u]:.4g} {u}; minimum at {o['minimum_at_deg']:g} "
             f"deg, maximum at {o['maximum_at_deg']:g} deg; rise {o['rise_deg']:.1f} deg, fall {o['fall_deg']:.1f} deg "
             f"of crank (asymmetry {o['asymmetry_rise_over_fall']:.3f})"]
    for d in o["near_dwells"]:
        lines.append(f"  near-dwell at the {d['at']} (within {pct:g} % of the swing): {d['from_deg']:g} -> "
                     f"{d['to_deg']:g} deg, {d['length_deg']:.1f} deg of crank")
    p = o["peaks"]
    lines.append(f"  peaks: |speed| {p['speed']['max_abs']:.4g} {su} at {p['speed']['at_deg']:g} deg, |acceleration| "
                 f"{p['acceleration']['max_abs']:.4g} {o['acceleration_unit']} at {p['acceleration']['at_deg']:g} deg, "
                 f"|jerk| {p['jerk']['max_abs']:.4g} {o['jerk_unit']} at {p['jerk']['at_deg']:g} deg")
    rows = o["table"][::max(1, len(o["table"]) // 24)]
    lines.append(format_table(rows, [("angle_deg", "crank deg"), ("position", f"position {u}"),
                                     ("speed", f"speed {su}"), ("acceleration", f"accel {o['acceleration_unit']}"),
                                     ("jerk", f"jerk {o['jerk_unit']}")]))
    return "\n".join(lines)


def _dynamics_text(d: dict) -> str:
    t = d["torque_N_m"]
    j = d["reduced_inertia_kg_m2"]
    lines = [f"crank torque at constant speed (power balance): max {t['max']:.4g} N m at {t['max_at_deg']:g} deg, "
             f"min {t['min']:.4g} N m at {t['min_at_deg']:g} deg, RMS {t['rms']:.4g} N m",
             f"  reduced inertia at the crank {j['min']:.4g} .. {j['max']:.4g} kg m^2; Newton-Euler torque differs by "
             f"{d['newton_euler_max_relative_difference']:.1e} of the peak",
             "  peak joint reactions: " + ", ".join(f"{k} {v:.4g} N" for k, v in d["peak_reactions_N"].items())]
    return "\n".join(lines)


def synthesis_text(r: dict, rms_max: float) -> str:
    b = r["best"]
    lines = [f"synthesis: {r['starts_solved']} starts solved (best-fitting of {r['screened_feasible']} that turn fully "
             f"among {r['geometries_screened']} random geometries), {r['seconds']:.1f} s",
             f"best: RMS {b['rms_m_s']:.4f} m/s (acceptance {rms_max:g}), largest error {b['max_error_m_s']:.4f}, "
             f"min transmission index {b['min_transmission_index']:.3f}, IPOPT {b['ipopt']}"]
    if "swing_deg" in b:
        lines.append(f"  swing {b['swing_deg']:.3f} deg, minimum at {b['minimum_at_deg']:g} deg, maximum at "
                     f"{b['maximum_at_deg']:g} deg")
    lines.append(format_table(b["targets"], [("angle_deg", "crank deg"), ("target", "target"), ("model", "linkage"),
                                             ("error", "error")]))
    for k, c in enumerate(r["runners_up"], 1):
        lines.append(f"runner-up {k}: RMS {c['rms_m_s']:.4f} m/s" + (f", swing {c['swing_deg']:.3f} deg"
                                                                      if "swing_deg" in c else "")
                     + "; joints mm " + ", ".join(f"{n} ({x:g}, {y:g})" for n, (x, y) in c["joints_mm"].items()))
    lines.append(r["note"])
    if r.get("targets_note"):
        lines.append(r["targets_note"])
    lines.append("best joints (paste into [[transmission.joints]], mm):")
    lines += [f"  {n}: x_mm = {x}, y_mm = {y}" for n, (x, y) in b["joints_mm"].items()]
    return "\n".join(lines)


def plot_linkage(kin, cycle, summary: dict, path, targets=None, poses: int = 6) -> None:
    """Mechanism at ``poses`` input angles with the joint paths; the first output and its speed over the
    input angle (with the table's speeds when given); the transmission index per group with the limit."""
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(2, 2, figsize=(11, 8.5))
    _draw_mechanism(ax[0, 0], kin, cycle, poses)
    deg = np.degrees(cycle.theta - cycle.theta[0])
    o = summary["outputs"][0]
    y = kin.output(cycle, o["name"])
    scale = math.degrees(1) if o["kind"] == "angle" else 1e3
    ax[0, 1].plot(deg, y[0] * scale)
    ax[0, 1].set(xlabel="crank angle from the reference [deg]", ylabel=f"{o['name']} [{o['unit']}]",
                 title=f"{o['name']}: swing {o['swing_' + o['unit']]:.3g} {o['unit']}")
    ax[1, 0].plot(deg, y[1] * summary["omega_rad_s"], label="linkage")
    if targets is not None:
        ax[1, 0].plot(*targets, "o", label="table")
        ax[1, 0].legend()
    ax[1, 0].set(xlabel="crank angle from the reference [deg]", ylabel=f"speed [{o['speed_unit']}]")
    _draw_transmission(ax[1, 1], cycle, summary["transmission"])
    for a in ax.flat:
        a.grid(alpha=0.3)
    fig.suptitle(summary["problem"])
    fig.tight_layout()
    if path is None:   # the caller's (the HTML report inlines it)
        return fig
    fig.savefig(path)
    plt.close(fig)


def _draw_mechanism(ax, kin, cycle, poses: int) -> None:
    lk, st = kin.linkage, kin.structure
    n = len(cycle.theta)
    fn = kin.closure.function("positions")
    allpts = np.asarray(fn.map(n)(cycle.q.T, cycle.theta[None, :], np.repeat(kin.p[:, None], n, 1))).T * 1e3
    names = [j.name for j in lk.joints]
    for i, name in enumerate(names):
        if name in st.unknown:
            ax.plot(allpts[:, 2 * i], allpts[:, 2 * i + 1], lw=0.8, alpha=0.6)
    colors = iter(np.linspace(0.2, 0.9, poses))
    for k in np.linspace(0, n, poses, endpoint=False).astype(int):
        c = str(next(colors))
        pts = allpts[k].reshape(-1, 2)
        for link in lk.links:
            idx = [names.index(j) for j in link.joints] + [names.index(link.joints[0])]
            ax.plot(pts[idx, 0], pts[idx, 1], "-o", color=c, ms=3, lw=1.2)
    ground = [names.index(j.name) for j in lk.joints if j.ground]
    ax.plot(allpts[0].reshape(-1, 2)[ground, 0], allpts[0].reshape(-1, 2)[ground, 1], "k^", ms=9)
    for i, name in enumerate(names):
        ax.annotate(name, allpts[0, 2 * i:2 * i + 2], fontsize=8)
    ax.set(aspect="equal", xlabel="x [mm]", ylabel="y [mm]", title=f"{poses} poses, 360 deg / {poses} apart; paths")


def _draw_transmission(ax, cycle, transmission: list[dict]) -> None:
    """The transmission index of every group over the crank angle, with the file's limit."""
    deg = np.degrees(cycle.theta - cycle.theta[0])
    for g, t in enumerate(transmission):
        ax.plot(deg, cycle.index[:, g], label=f"{t['group']} {', '.join(t['links'])}")
    if transmission:
        ax.axhline(transmission[0]["limit"], color="r", ls="--", label="limit")
    ax.set(xlabel="crank angle from the reference [deg]", ylabel="transmission index", ylim=(0, 1.05))
    ax.legend(fontsize=7)


SIZE_COLUMNS = [("gearbox", "gearbox"), ("ratio", "i"), ("motor", "motor"), ("rated_torque_N_m", "rated N m"),
                ("peak_torque_N_m", "peak N m"), ("rms_torque_N_m", "RMS N m"), ("motor_speed_rpm", "motor rpm"),
                ("inertia_ratio", "inertia ratio"), ("feasible", "fits"), ("binding", "binding"), ("margin", "margin")]
TERM_COLUMNS = [("angle_deg", "crank deg"), ("J_kg_m2", "J kg m^2"), ("dJ_kg_m2_rad", "J' kg m^2/rad"),
                ("inertia_torque_N_m", "J'w^2/2 N m"), ("gravity_torque_N_m", "gravity N m"),
                ("process_torque_N_m", "process N m"), ("torque_N_m", "crank N m"),
                ("torque_newton_euler_N_m", "Newton-Euler N m")]


def dynamics_text(s: dict) -> str:
    """The crank torque of a linkage at constant crank speed (``summarize(..., with_dynamics=True)``): the process
    loads, the power balance and its terms, Newton-Euler's check."""
    lines = [f"crank {s['rpm']:g} rpm = {s['omega_rad_s']:.4f} rad/s, constant; gravity {s['gravity_m_s2']:g} m/s^2 "
             "along -y"]
    for ld in s["process_loads"]:
        lines.append(f"process load {ld['name']} on {ld['link']} at {ld['joint']}: {ld['force_start_N']:g} -> "
                     f"{ld['force_end_N']:g} N over crank {ld['from_deg']:g} -> {ld['to_deg']:g} deg, "
                     f"{ld['direction_deg']:g} deg from the link's line")
    lines += [f"note: {s['note']}"] if s.get("note") else []
    lines += [_dynamics_text(s["dynamics"]), format_table(s["terms"][::max(1, len(s["terms"]) // 36)], TERM_COLUMNS)]
    return "\n".join(lines)


def plot_linkage_size(kin, cycle, dyn, summary: dict, path, poses: int = 6) -> None:
    """The mechanism at ``poses`` input angles with the joint paths, the transmission index over the cycle, the
    crank torque by term (``dyn``: linkage.dynamics.Dynamics; Newton-Euler's as dots) and the reduced inertia J
    with J'."""
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(2, 2, figsize=(11, 8.5))
    _draw_mechanism(ax[0, 0], kin, cycle, poses)
    _draw_transmission(ax[0, 1], cycle, summary["transmission"])
    deg = np.degrees(dyn.theta - dyn.theta[0])
    for y, label in ((0.5 * dyn.dJ * dyn.omega ** 2, "inertia J'w^2/2"), (dyn.gravity_torque, "gravity"),
                     (dyn.load_torque, "process loads"), (dyn.torque, "crank torque (power balance)")):
        ax[1, 0].plot(deg, y, lw=2 if y is dyn.torque else 1, label=label)
    ax[1, 0].plot(deg[::6], dyn.torque_ne[::6], "k.", ms=3, label="Newton-Euler")
    ax[1, 0].set(xlabel="crank angle from the reference [deg]", ylabel="torque on the crank [N m]")
    ax[1, 0].legend(fontsize=7)
    ax[1, 1].plot(deg, dyn.J, label="J")
    twin = ax[1, 1].twinx()
    twin.plot(deg, dyn.dJ, color="tab:orange", label="J'")
    ax[1, 1].set(xlabel="crank angle from the reference [deg]", ylabel="reduced inertia J [kg m^2] (blue)")
    twin.set_ylabel("J' [kg m^2/rad] (orange)")
    for a in ax.flat:
        a.grid(alpha=0.3)
    fig.suptitle(f"{summary['problem']}: the crank at a constant {summary['rpm']:g} rpm")
    fig.tight_layout()
    if path is None:
        return fig
    fig.savefig(path)
    plt.close(fig)


def plot_analysis(problem, summary: dict, path) -> None:
    """The figure of a linkage transmission's own analysis (``Transmission.analysis``): the mechanism, its first
    output over the crank angle (with the file's synthesis targets where they are of that output), the
    transmission index."""
    from ..linkage.kinematics import kinematics_of

    tr = problem.transmission
    kin = kinematics_of(tr.linkage)
    cycle = kin.solve(tr.samples)
    syn = problem.data.get("synthesis") or {}
    targets = None
    if syn.get("output") == summary["outputs"][0]["name"] and "angles_deg" in syn:
        t0 = math.degrees(tr.linkage.crank.reference_angle)
        targets = ([(a - t0) % 360 for a in syn["angles_deg"]], syn["speeds_m_s"])
    plot_linkage(kin, cycle, summary, path, targets)


def analysis_failure(summary: dict) -> str | None:
    """The limit a transmission's own analysis fails (its transmission index), in one line; None when it passes."""
    if summary["status"] == "ok":
        return None
    bad = next(t for t in summary["transmission"] if not t["ok"])
    return (f"the transmission index of {', '.join(bad['links'])} falls to {bad['min_index']:.3g} at {bad['at_deg']:g} "
            f"deg, below the limit {bad['limit']:g}")
