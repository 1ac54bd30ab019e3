"""Contact-model results as text and figures: one simulated cycle, a speed sweep, the tolerance study.

The contact package computes (contact/simulate.py, events.py, studies.py, verify.py);
this module prints and draws what it returns: :func:`scene_text` and
:func:`plot_scene` for a :class:`~strokeopt.contact.simulate.SceneResult`, the sweep
and study tables' columns with :func:`plot_sweep` and :func:`plot_tolerance_study`.
"""

from __future__ import annotations

import matplotlib.pyplot as plt
import numpy as np

from ..contact.events import GAP_CLOSED, LAG_THRESHOLD
from ..contact.peaks import PEAK_TOLERANCE
from ..io.cycle import STITCH, cycle_of
from .figures import frame_label
from .format import drive_text, format_table

# speeds are magnitudes (toward the handover); the gap is closed below GAP_CLOSED, the threshold 'premature' uses
SWEEP_COLUMNS = [("spm", "spm"), ("impact_velocity_m_s", "impact speed m/s"), ("impact_angle_deg", "impact deg"),
                 ("lag", "lag"), ("lag_end_angle_deg", "lag end deg"),
                 ("min_gap_N_mm", f"min gap N mm (closed < {GAP_CLOSED * 1e3:g})"),
                 ("release_angle_deg", "release deg"), ("premature_release", "premature"),
                 ("peak_pad_force_N", "pad N"), ("cpu_time_s", "CPU s")]

STUDY_COLUMNS = [("method", "method"), ("switching", "switching"), ("smoothing_mm", "smoothing mm"), ("rtol", "rtol"),
                 ("impact_velocity_error_m_s", "impact v error m/s"), ("release_angle_error_deg", "release error deg"),
                 ("impact_angle_error_deg", "impact angle error deg"), ("nsteps", "steps"), ("cpu_time_s", "CPU s")]


def scene_text(problem, scene: str, summary: dict) -> str:
    """The results of one simulated cycle as a short text report."""
    sc = problem.scenes[scene]
    roles = sc.model.events
    s = summary
    lines = [f"{problem.name}: scene {scene!r} ({', '.join(sc.bodies)}; {sc.state_size} states) at {problem.cycle.rate(s['spm'])}, "
             f"stroke: {s['stroke']}, interval times {problem.timing.interval_times}"]
    if s["gap_N_mm"] is not None:
        lines.append(f"gap N used by the model: {s['gap_N_mm']:g} mm (model.contacts.{roles.gap}.gap_mm)")
    f = roles.follower or "follower"
    if s["impact_velocity_m_s"] is not None:
        lines.append(f"impact of {f} on the stop ({roles.impact}): {s['impact_velocity_m_s']:.3f} m/s "
                     f"at {s['impact_angle_deg']:.2f} deg")
    elif roles.impact in sc.elements:
        lines.append(f"impact ({roles.impact}): none in this cycle")
    if s["lag"]:
        end = f"until {s['lag_end_angle_deg']:.2f} deg" if s["lag_end_angle_deg"] is not None else "not caught up in this cycle"
        lines.append(f"{f} lags the {sc.driven}: from {s['lag_onset_angle_deg']:.2f} deg {end} "
                     f"(largest lag before the impact {s['max_lag_mm']:.2f} mm)")
    elif s["max_lag_mm"] is not None:
        lines.append(f"{f} follows the {sc.driven} (no lag above {LAG_THRESHOLD * 1e6:g} um)")
    if s["min_gap_N_mm"] is not None:
        lines.append(f"smallest remaining gap N before the impact: {s['min_gap_N_mm']:.4f} mm "
                     f"(closed below {GAP_CLOSED * 1e3:g} mm)")
    if s["release_angle_deg"] is not None:
        closed = s["min_gap_N_mm"] is not None and s["min_gap_N_mm"] < GAP_CLOSED * 1e3
        verdict = {True: "PREMATURE: " + ("gap N closed before the impact" if closed else "released before the impact"),
                   False: "after the impact, not premature",
                   None: "no impact to compare with"}[s["premature_release"]]
        lines.append(f"needle released at {s['release_angle_deg']:.2f} deg ({verdict})")
    if s["peak_pad_force_N"] is not None:
        lines.append(f"peak pad force: {s['peak_pad_force_N']:.1f} N")
    if s.get("chain"):
        return "\n".join(lines + chain_lines(s["chain"], sc.driven, s))
    belt = (f"; for comparison, not a check: the belt's breaking load is {s['belt_breaking_load_N']:g} N "
            f"({s['belt']}), which 'strokeopt solve' and 'size' check the rigid-load belt tension against"
            if s.get("belt_breaking_load_N") is not None else "")
    lines.append(f"peak force the drive supplies to the {sc.driven}: {s['peak_drive_force_N']:.1f} N (a stiff-contact "
                 f"spike of the contact model, microseconds long, not a sustained belt load{belt})")
    lines.append("peak element forces [N] (located between the output points; no design limit, only the "
                 "model's plausibility): " + ", ".join(f"{k} {v:.1f}" for k, v in s["peak_contact_forces_N"].items()))
    if s.get("implausible_forces"):
        from ..contact.plausible import implausible_text

        lines.append("IMPLAUSIBLE forces, not of the mechanism but of the model taken where it does not hold: "
                     + implausible_text(s["implausible_forces"]))
    errors = {**(s.get("peak_contact_force_errors_pct") or {}), "drive": s.get("peak_drive_force_error_pct")}
    if any(v is not None for v in errors.values()):
        known = {k: v for k, v in errors.items() if v is not None}
        worst = max(known, key=known.get)
        lines.append(("peak forces NOT CONVERGED: " + ", ".join(f"{k} ({errors[k]:.3g} %)" if errors[k] is not None else k
                                                             for k in s["unconverged_peaks"])
                      + f" above {PEAK_TOLERANCE:.0%}; tighten --rtol"
                      if s["unconverged_peaks"] else f"peak forces converged: estimated error at most {known[worst]:.2g} % "
                      f"({worst})") + "; each peak found again at 1/100 of the tolerances from the start of its stroke piece")
    if s.get("drive"):
        lines.append(drive_text(s["drive"]) + "; the contact model takes the stroke as given and models neither "
                     "the motor nor the belt")
    sw = "hard switches" if s["smoothing_mm"] == 0 else f"smoothing {s['smoothing_mm']:g} mm"
    lines.append(f"CPU time {s['cpu_time_s']:.3f} s ({s['method']}, rtol {s['rtol']:g}, atol {s['atol']:g}, {sw})")
    return "\n".join(lines)


def chain_lines(chain: dict, driven: str, s: dict) -> list[str]:
    """A model on a transmission's members: elastic against rigid, the links' forces, the screw torque."""
    lines = ["", format_table(chain["bodies"], [("body", "body"), ("stage", "member"), ("elastic_peak_accel", "elastic peak"),
                                                ("rigid_peak_accel", "rigid peak"), ("ratio", "elastic/rigid"),
                                                ("unit", "unit")],
                              title="peak acceleration of each body: the elastic chain against the rigid chain")]
    rows = [{**k, "damping_text": f"{k['damping']:.4g}" + (f" (log decrement {k['log_decrement']:.4g})"
                                                              if k["log_decrement"] is not None else ""),
             "clearance_text": f"{k['clearance']:.3g}"} for k in chain["links"]]
    lines += ["", format_table(rows, [("link", "link"), ("peak_compression", "peak compression"),
                                      ("peak_tension", "peak tension"), ("unit", "unit"), ("clearance_text", "play m|rad"),
                                      ("damping_text", "damping SI")],
                               title="link forces (positive = compression); a link's peak tension is what a preload "
                                     "spring would have to hold to keep it closed")]
    if "screw" in chain:
        sc = chain["screw"]
        lines.append(f"\nscrew torque from the peak nut force {sc['peak_nut_force_N']:.1f} N (drive force on the "
                     f"{driven}): {sc['screw_torque_N_cm']:.2f} N cm (pitch diameter {sc['screw_diameter_mm']:g} mm, "
                     f"friction {sc['thread_friction']:g}, flank angle {sc['thread_angle_deg']:g} deg, raising)")
    sw = "hard switches" if s["smoothing_mm"] == 0 else f"smoothing {s['smoothing_mm']:g} mm"
    lines.append(f"CPU time {s['cpu_time_s']:.3f} s ({s['method']}, rtol {s['rtol']:g}, atol {s['atol']:g}, {sw})")
    return lines


def verification_text(block: dict) -> str:
    """The verification block (contact/verify.py ``verification``): one row per criterion, then the verdict."""
    def shown(value, unit):
        if value is None:
            return "-"
        if isinstance(value, bool):
            return "yes" if value else "no"
        return f"{value:.4g} {unit}".strip()

    rows = [{"criterion": r["criterion"], "value": shown(r["value"], r["unit"]),
             "limit": "none (not judged)" if r["limit"] is None else shown(r["limit"], r["unit"]),
             "result": {True: "pass", False: "FAIL", None: "-"}[r["ok"]]} for r in block["criteria"]]
    from .format import format_table

    table = format_table(rows, [("criterion", "criterion"), ("value", "value"), ("limit", "limit"),
                                ("result", "result")],
                         title=f"verification: the stroke re-simulated in scene {block['scene']!r} "
                               f"(contact model, CVODES) at {block['spm']:g} spm")
    return f"{table}\n{block['verdict']}"


def _angular_bodies(problem) -> set:
    """The bodies of ``problem``'s model on an angular coordinate (their positions in rad)."""
    model = getattr(problem, "model", None) if problem is not None else None
    return {n for n, b in (model.bodies.items() if model is not None else ()) if getattr(b, "angular", False)}


def plot_scene(r, path=None, problem=None, window=None):
    """Velocities and positions of the scene's bodies and the remaining gap N (else the drive force) over the
    whole cam cycle; impact, lag end and release marked. One quantity and one unit per axis: with ``problem``,
    bodies on an angular coordinate (a lever) get their own axes in rad/s and mrad. ``window``: (from, to)
    cam angles of a detail instead of the whole cycle."""
    from .figures import PRINT_WIDTH_IN, legend_outside

    ang = r.angle_deg
    m = r.metrics
    angular = _angular_bodies(problem) & set(r.positions)
    linear = [b for b in r.velocities if b not in angular]
    rows = 3 + (2 if angular else 0)
    fig, axes = plt.subplots(rows, 1, sharex=True, figsize=(PRINT_WIDTH_IN, 2.0 * rows + 0.5), constrained_layout=True)
    ax = axes[0]
    for b in linear:
        ax.plot(ang, r.problem_velocity(b), lw=1.2 if b == r.driven else 1.0,
                label=b + (" (driven)" if b == r.driven else ""))
    ax.set_ylabel(frame_label("velocity", "m/s"))
    ax = axes[1]
    for b in linear:
        ax.plot(ang, r.problem_position(b) * 1e3, lw=1.0, label=b)
    ax.set_ylabel(frame_label("position", "mm"))
    if angular:
        for b in angular:
            axes[2].plot(ang, r.velocities[b], lw=1.0, label=b)
            axes[3].plot(ang, r.positions[b] * 1e3, lw=1.0, label=b)
        axes[2].set_ylabel("angular velocity\n[rad/s]")
        axes[3].set_ylabel("angle [mrad]")
    ax = axes[-1]
    if r.remaining_gap is not None:
        ax.plot(ang, r.remaining_gap * 1e3, color="tab:purple", label=f"remaining gap N (N = {m['gap_N_mm']:g} mm)")
        ax.axhline(0, color="0.5", lw=0.6)
        ax.set_ylabel("remaining gap N [mm]")
    else:
        ax.plot(ang, r.drive_force, color="tab:gray", label="drive force")
        ax.set_ylabel("drive force [N]")
    # the event lines are named in the legends (placed beside the data), not by text on the curves
    for ax in axes:
        ax.grid(True, alpha=0.3)
        for key, color, text in (("lag_end_angle_deg", "tab:orange", "lag end"), ("impact_angle_deg", "tab:red", "impact"),
                                 ("release_angle_deg", "tab:green", "release")):
            if m.get(key) is not None:
                ax.axvline(m[key], color=color, ls="--", lw=1, label=f"{text} {m[key]:.1f} deg")
    for ax in axes:
        if ax is not axes[1] or angular:
            legend_outside(ax)
    if window is None:
        axes[-1].set_xlim(float(ang[0]), float(ang[-1]))
        axes[-1].set_xticks(np.arange(0, 361, 45))
        axes[-1].set_xlabel("cam angle [deg] (360 deg = one cam cycle)")
    else:
        axes[-1].set_xlim(*window)
        axes[-1].set_xlabel(f"cam angle [deg] (detail of the events, {window[0]:g}-{window[1]:g} deg)")
        for ax in axes:  # each axis scaled to what the detail shows
            ax.relim(visible_only=True)
            lines = [ln for ln in ax.get_lines() if len(np.atleast_1d(ln.get_xdata())) > 2]
            ys = [np.asarray(ln.get_ydata())[(np.asarray(ln.get_xdata()) >= window[0])
                                             & (np.asarray(ln.get_xdata()) <= window[1])] for ln in lines]
            ys = [y for y in ys if y.size]
            if ys:
                lo, hi = min(float(y.min()) for y in ys), max(float(y.max()) for y in ys)
                pad = 0.06 * (hi - lo or 1.0)
                ax.set_ylim(lo - pad, hi + pad)
    iv = m.get("impact_velocity_m_s")
    axes[0].set_title(f"scene {r.scene}, {r.stroke_label or 'stroke'} at {cycle_of(problem).rate(r.spm)}"
                      + (f": impact {iv:.2f} m/s" if iv is not None else ""))
    if path is not None:
        from .figures import fit_titles

        fit_titles(fig)  # no title wider than its axes
        fig.savefig(path, dpi=120)
        plt.close(fig)
    return fig


def plot_sweep(rows: list[dict], path=None, cycle=STITCH, varied: str | None = None, label: str | None = None):
    """Impact velocity and min remaining gap N over the machine's rate (``cycle``: its cycle, io/cycle.py), or over
    the problem field ``varied`` of ``simulate --vary`` rows (studies/vary.py: the first field varied; ``label``:
    the axis's words for it)."""
    cycle = cycle_of(cycle)
    rows = [r for r in rows if "failed" not in r]
    x = [r["varied"][varied] if varied else r["spm"] for r in rows]
    fig, axes = plt.subplots(2, 1, sharex=True, figsize=(8, 6), constrained_layout=True)
    axes[0].plot(x, [np.nan if r["impact_velocity_m_s"] is None else r["impact_velocity_m_s"] for r in rows], "o-", ms=3)
    axes[0].set_ylabel("impact speed [m/s]\n(toward the handover)")
    axes[1].plot(x, [np.nan if r["min_gap_N_mm"] is None else r["min_gap_N_mm"] for r in rows], "o-", ms=3,
                 color="tab:purple")
    axes[1].set_ylabel("min remaining gap N [mm]")
    axes[1].axhline(GAP_CLOSED * 1e3, color="tab:red", ls=":", lw=1, label=f"closed below {GAP_CLOSED * 1e3:g} mm")
    premature = [xi for xi, r in zip(x, rows) if r.get("premature_release")]
    if premature:
        axes[1].plot(premature, [GAP_CLOSED * 1e3] * len(premature), "x", color="tab:red", ms=7,
                     label="premature release")
    axes[1].legend(fontsize=8, loc="best")
    onset = None if varied else next((xi for xi, r in zip(x, rows) if r.get("lag")), None)
    lagging = [(xi, r["impact_velocity_m_s"]) for xi, r in zip(x, rows) if varied and r.get("lag")
               and r["impact_velocity_m_s"] is not None]
    if lagging:  # a field varied need not make the lag monotonic: each step that lags is marked
        axes[0].plot(*zip(*lagging), "o", mfc="none", color="tab:orange", ms=9, label="follower lags")
    for ax in axes:
        ax.grid(True, alpha=0.3)
        if onset is not None:
            ax.axvline(onset, color="tab:orange", ls="--", lw=1, label=f"follower lags from {cycle.rate(onset)}")
    if onset is not None or lagging:
        axes[0].legend(fontsize=8, loc="best")  # named in a legend placed clear of the curve
    axes[1].set_xlabel((label or varied) if varied else f"{cycle.rate_name} [{cycle.rate_unit}]")
    what = f"{label or varied} varied at {cycle.rate(rows[0]['spm'])}" if varied and rows else "speed sweep"
    axes[0].set_title(f"scene {rows[0]['scene']}, {rows[0].get('stroke') or 'stroke'}: {what}" if rows else what)
    if path is not None:
        from .figures import fit_titles

        fit_titles(fig)  # no title wider than its axes
        fig.savefig(path, dpi=120)
        plt.close(fig)
    return fig


def plot_tolerance_study(study: dict, path=None):
    """Work-precision: error of impact velocity and release angle vs CPU time."""
    fig, axes = plt.subplots(1, 2, figsize=(10, 4), constrained_layout=True)
    groups = {}
    for r in study["rows"]:
        if "failed" in r:
            continue
        groups.setdefault((r["method"], r["switching"], r["smoothing_mm"]), []).append(r)
    for (mth, switching, eps), rows in groups.items():
        label = f"{mth}, " + {"hard": "hard switches", "restarts": "restarts at switches"}.get(
            switching, f"smoothing {eps:g} mm")
        cpu = [r["cpu_time_s"] for r in rows]
        for ax, key in zip(axes, ("impact_velocity_error_m_s", "release_angle_error_deg")):
            ax.loglog(cpu, [max(r[key], 1e-12) if r[key] is not None else np.nan for r in rows], "o-", label=label)
    axes[0].set_ylabel("impact velocity error [m/s]")
    axes[1].set_ylabel("release angle error [deg]")
    from matplotlib.ticker import FuncFormatter, LogLocator, NullFormatter

    for ax in axes:
        ax.set_xlabel("CPU time [s]")
        ax.grid(True, which="both", alpha=0.3)
        # plain decimals at 1, 2, 5 x 10^k; unlabelled minor ticks (a few tenths of a decade otherwise overlap)
        ax.xaxis.set_major_locator(LogLocator(base=10, subs=(1.0, 2.0, 5.0)))
        ax.xaxis.set_major_formatter(FuncFormatter(lambda v, _: f"{v:g}"))
        ax.xaxis.set_minor_formatter(NullFormatter())
    axes[0].axhline(1e-3, color="0.5", ls=":", lw=1)
    axes[1].axhline(0.1, color="0.5", ls=":", lw=1)
    handles, labels = axes[0].get_legend_handles_labels()
    fig.legend(handles, labels, loc="outside lower center", ncol=3, fontsize=8)  # below the plots, off the data
    fig.suptitle(f"work-precision, scene {study['scene']} at {study['spm']:g} spm")
    if path is not None:
        from .figures import fit_titles

        fit_titles(fig)  # no title wider than its axes
        fig.savefig(path, dpi=120)
        plt.close(fig)
    return fig


def plot_chain(r, problem, stroke, path=None):
    """A model on a transmission's members over the whole cam cycle: each staged free body's acceleration
    against the rigid chain's (its member's, from the stroke), one axis per body (its own unit), and the
    links' forces, one axis per unit (N for links between sliding bodies, N m for a lever's torsion)."""
    from .figures import PRINT_WIDTH_IN, legend_outside

    model = problem.model
    tr = model.transmission
    sc = problem.scenes[r.scene]
    kin = stroke.evaluate(r.t)
    rigid = tr.stage_kinematics(kin.s, kin.v, kin.a, kin.j)
    free = [b for b in sc.free_bodies if model.bodies[b].stage is not None]
    links = [e for e in sc.elements if model.elements[e].kind == "link"]
    by_unit: dict = {}
    for e in links:
        angular = any(model.bodies[b].angular for b in model.elements[e].bodies if b in model.bodies)
        by_unit.setdefault("N m" if angular else "N", []).append(e)
    rows = len(free) + len(by_unit)
    fig, axes = plt.subplots(rows, 1, sharex=True, figsize=(PRINT_WIDTH_IN, 1.75 * rows + 0.8),
                             constrained_layout=True)
    ang = r.angle_deg
    for ax, b in zip(axes, free):
        body = model.bodies[b]
        unit = "rad/s$^2$" if body.angular else "m/s$^2$"
        ax.plot(ang, r.accelerations[b], lw=0.9, label=f"{b} (elastic)")
        ax.plot(ang, rigid[body.stage][2], "k--", lw=1.0, label=f"rigid chain ({body.stage})")
        ax.set_ylabel(f"{b} acc.\n[{unit}]")
        legend_outside(ax)
    for ax, (unit, names) in zip(axes[len(free):], by_unit.items()):
        for e in names:
            ax.plot(ang, np.asarray(r.forces[e]), lw=0.9, label=e)
        ax.set_ylabel(("link torque" if unit == "N m" else "link force") + f"\n[{unit}] (+ compr.)")
        ax.axhline(0, color="0.5", lw=0.6)
        legend_outside(ax)
    for ax in axes:
        ax.grid(True, alpha=0.3)
    axes[-1].set_xlim(float(ang[0]), float(ang[-1]))
    axes[-1].set_xticks(np.arange(0, 361, 45))
    axes[-1].set_xlabel(f"cam angle [deg] (360 deg = one cycle of {r.period * 1e3:.1f} ms)")
    axes[0].set_title(f"{problem.name}: scene {r.scene!r}, {r.stroke_label}: elastic chain against the rigid chain",
                      fontsize=10)
    if path is not None:
        from .figures import fit_titles

        fit_titles(fig)  # no title wider than its axes
        fig.savefig(path, dpi=110)
        plt.close(fig)
    return fig
