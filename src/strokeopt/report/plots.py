"""Figures (matplotlib). Computation lives elsewhere; these only draw."""

from __future__ import annotations

import math
from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np


def shade_dwells(ax, timing, spm) -> None:
    """Grey bands over the dwells of a timing diagram (x axis: cam angle in degrees)."""
    sch = timing.schedule(spm)
    for itv, a0, a1 in zip(timing.intervals, sch.start_angle_deg, sch.end_angle_deg):
        if not itv.is_move:
            ax.axvspan(a0, a1, color="0.9", zorder=0, lw=0)


def plot_kinematics(problem, strokes, spm: float, path: str | Path | None = None, n: int = 3601):
    """Position, velocity, acceleration and jerk over the cam angle; one line per stroke.

    ``strokes`` is a StrokeFunction or a list of them. Dwells are shaded, the
    handover point is marked. Returns the figure; writes it when ``path`` is given.
    """
    if not isinstance(strokes, (list, tuple)):
        strokes = [strokes]
    fig, axes = plt.subplots(4, 1, sharex=True, figsize=(9, 9), constrained_layout=True)
    j_peak = max(float(np.max(np.abs(s.sample(n).j))) for s in strokes)
    jerk_unit = ("km/s$^3$", 1e-3) if j_peak >= 1e4 else ("m/s$^3$", 1.0)
    units = [("position", "mm", 1e3), ("velocity", "m/s", 1.0), ("acceleration", "m/s$^2$", 1.0),
             ("jerk", *jerk_unit)]
    for stroke in strokes:
        k = stroke.sample(n)
        angle = 360.0 * k.t / stroke.period
        for ax, y, (_, _, scale) in zip(axes, (k.s, k.v, k.a, k.j), units):
            ax.plot(angle, y * scale, lw=1.4, label=stroke.label)
    for ax, (name, unit, _) in zip(axes, units):
        shade_dwells(ax, problem.timing, spm)
        ax.set_ylabel(f"{name} [{unit}]")
        ax.grid(True, alpha=0.3)
        ax.axhline(0, color="0.5", lw=0.6)
    move = problem.timing.handover_move
    if move is not None:
        sch = problem.timing.schedule(spm)
        a_end = sch.end_angle_deg[move.index - 1]
        for ax in axes:
            ax.axvline(a_end, color="tab:red", ls="--", lw=1)
        axes[0].annotate(f"handover ({move.end_position * 1e3:g} mm)", (a_end, move.end_position * 1e3),
                         xytext=(8, 12), textcoords="offset points", color="tab:red")
    axes[-1].set_xlabel("cam angle [deg]")
    axes[-1].set_xlim(0, 360)
    axes[-1].set_xticks(np.arange(0, 361, 30))
    has_dwell = any(not i.is_move for i in problem.timing.intervals)
    axes[0].set_title(f"{problem.name}: stroke at {spm:g} spm" + (" (dwells shaded)" if has_dwell else ""))
    if len(strokes) > 1:
        axes[0].legend(loc="best", fontsize=8)
    if path is not None:
        fig.savefig(path, dpi=120)
        plt.close(fig)
    return fig


def plot_sizing(sizing, candidate=None, path=None):
    """The classic sizing picture for ``candidate`` (default: the best ranked):
    the cycle's torque-speed trajectory over the motor's continuous and peak
    envelopes and the drive's peak limit, and the torque terms over the cam angle.
    ``sizing`` is a :class:`strokeopt.drive.Sizing`."""
    c = candidate or sizing.candidates[0]
    terms = sizing.torque_curve(c)
    rpm = 60 / (2 * math.pi)
    fig, (ax1, ax2) = plt.subplots(1, 2, figsize=(12, 4.8), constrained_layout=True)
    m = c.motor
    w = np.linspace(-m.rated_speed, m.rated_speed, 101)
    drive_peak = min(m.peak_torque, sizing.limits.peak_limit_pct / 100 * m.rated_torque)
    for sign in (1, -1):
        ax1.plot(w * rpm, sign * m.continuous_torque(w), color="tab:green",
                 label="continuous (thermal)" if sign > 0 else None)
        ax1.plot(w * rpm, sign * m.peak_envelope(w), color="tab:red", label="motor peak" if sign > 0 else None)
        ax1.plot(w * rpm, sign * np.full_like(w, drive_peak), color="tab:red", ls=":",
                 label=f"drive limit ({sizing.limits.peak_limit_pct:g} % rated)" if sign > 0 else None)
    for x in (-m.rated_speed * rpm, m.rated_speed * rpm):
        ax1.axvline(x, color="0.5", lw=0.8, ls="--")
    ax1.plot(terms.omega * rpm, terms.total, color="tab:blue", lw=1.2, label="cycle")
    rms = c.check("rms_torque").value
    ax1.axhline(rms, color="tab:blue", ls="--", lw=0.8, label=f"RMS {rms:.2f} N m")
    ax1.set_xlabel("motor speed [rpm]")
    ax1.set_ylabel("motor torque [N m]")
    ax1.set_title(f"{m.name}, pulley z{c.pulley.teeth}, {sizing.spm:g} spm")
    ax1.grid(True, alpha=0.3)
    ax1.legend(fontsize=8, loc="best")
    angle = 360.0 * sizing.kinematics.t / sizing.period
    ax2.plot(angle, terms.total, color="k", lw=1.5, label="total")
    for name, val in terms.as_dict().items():
        val = np.broadcast_to(val, angle.shape)
        if np.max(np.abs(val)) > 1e-9:
            ax2.plot(angle, val, lw=0.9, label=name, ls="--" if name == "rotor_inertia" else "-")
    ax2.set_xlabel("cam angle [deg]")
    ax2.set_ylabel("motor torque [N m]")
    ax2.set_xlim(0, 360)
    ax2.set_xticks(np.arange(0, 361, 45))
    ax2.grid(True, alpha=0.3)
    ax2.legend(fontsize=8, loc="best")
    ax2.set_title(f"torque over the cycle (binding: {c.binding})")
    if path is not None:
        fig.savefig(path, dpi=110)
        plt.close(fig)
    return fig



def plot_scene(r, path=None):
    """Driven and follower velocities and the remaining gap N over the cam angle; impact and release marked."""
    ang = r.angle_deg
    m = r.metrics
    fig, axes = plt.subplots(3, 1, sharex=True, figsize=(9, 8), constrained_layout=True)
    ax = axes[0]
    for b in r.velocities:
        ax.plot(ang, r.velocities[b], lw=1.2 if b == r.driven else 1.0, label=b + (" (driven)" if b == r.driven else ""))
    ax.set_ylabel("velocity [m/s]")
    ax.legend(fontsize=8, loc="best")
    ax = axes[1]
    for b in r.positions:
        ax.plot(ang, r.positions[b] * 1e3, lw=1.0, label=b)
    ax.set_ylabel("position [mm]\n(toward handover)")
    ax = axes[2]
    if r.remaining_gap is not None:
        ax.plot(ang, r.remaining_gap * 1e3, color="tab:purple", label=f"remaining gap N (N = {m['gap_N_mm']:g} mm)")
        ax.axhline(0, color="0.5", lw=0.6)
        ax.set_ylabel("remaining gap N [mm]")
    else:
        ax.plot(ang, r.drive_force, color="tab:gray", label="drive force")
        ax.set_ylabel("drive force [N]")
    # the event lines are named in the legends (placed clear of the data), not by text on the curves
    for ax in axes:
        ax.grid(True, alpha=0.3)
        for key, color, text in (("lag_end_angle_deg", "tab:orange", "lag end"), ("impact_angle_deg", "tab:red", "impact"),
                                 ("release_angle_deg", "tab:green", "release")):
            if m.get(key) is not None:
                ax.axvline(m[key], color=color, ls="--", lw=1, label=f"{text} {m[key]:.1f} deg")
    axes[0].legend(fontsize=8, loc="best")
    axes[2].legend(fontsize=8, loc="best")
    lo = m.get("lag_onset_angle_deg") or 0.0
    axes[-1].set_xlim(max(0.0, min(lo, 20.0) - 5), 90.0)
    axes[-1].set_xlabel("cam angle [deg]")
    iv = m.get("impact_velocity_m_s")
    axes[0].set_title(f"scene {r.scene} at {r.spm:g} spm: impact "
                      + (f"{iv:.2f} m/s" if iv is not None else "none"))
    if path is not None:
        fig.savefig(path, dpi=120)
        plt.close(fig)
    return fig


def plot_sweep(rows: list[dict], path=None):
    """Impact velocity and min remaining gap N vs spm."""
    spm = [r["spm"] for r in rows]
    fig, axes = plt.subplots(2, 1, sharex=True, figsize=(8, 6), constrained_layout=True)
    axes[0].plot(spm, [np.nan if r["impact_velocity_m_s"] is None else r["impact_velocity_m_s"] for r in rows], "o-", ms=3)
    axes[0].set_ylabel("impact velocity [m/s]")
    axes[1].plot(spm, [np.nan if r["min_gap_N_mm"] is None else r["min_gap_N_mm"] for r in rows], "o-", ms=3,
                 color="tab:purple")
    axes[1].set_ylabel("min remaining gap N [mm]")
    from ..contact.simulate import lag_onset_spm

    onset = lag_onset_spm(rows)
    for ax in axes:
        ax.grid(True, alpha=0.3)
        if onset is not None:
            ax.axvline(onset, color="tab:orange", ls="--", lw=1, label=f"follower lags from {onset:g} spm")
    if onset is not None:
        axes[0].legend(fontsize=8, loc="best")  # named in a legend placed clear of the curve
    axes[1].set_xlabel("speed [spm]")
    axes[0].set_title(f"scene {rows[0]['scene']}: speed sweep" if rows else "speed sweep")
    if path is not None:
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
        fig.savefig(path, dpi=120)
        plt.close(fig)
    return fig


def plot_mesh_study(rows: list[dict], path=None):
    """Work-precision of the design collocation: objective error and violation between nodes vs solve time."""
    fig, axes = plt.subplots(1, 2, figsize=(10, 4), constrained_layout=True)
    for degree in sorted({r["degree"] for r in rows}):
        sel = [r for r in rows if r["degree"] == degree and not r.get("reference")]
        if not sel:
            continue
        t = [r["time_s"] for r in sel]
        axes[0].loglog(t, [max(r["objective_error_pct"], 1e-9) for r in sel], "o-", label=f"degree {degree}")
        axes[1].semilogx(t, [100 * r["violation_between_nodes"] for r in sel], "o-", label=f"degree {degree}")
        for r in sel:
            axes[0].annotate(str(r["intervals"]), (r["time_s"], max(r["objective_error_pct"], 1e-9)), fontsize=7,
                             xytext=(3, 3), textcoords="offset points")
    axes[0].set_ylabel("objective error vs finest mesh [%]")
    axes[1].set_ylabel("largest bound violation between nodes [%]")
    for ax in axes:
        ax.set_xlabel("build + solve time [s]")
        ax.grid(True, which="both", alpha=0.3)
        ax.legend(fontsize=8)
    axes[0].set_title("what accuracy costs in time (labels: mesh intervals)")
    if path is not None:
        fig.savefig(path, dpi=120)
        plt.close(fig)
    return fig


def plot_design_sweep(rows: list[dict], path=None):
    """Optimal objective (and peak torque) over the stitch rate of a design sweep; infeasible rates marked."""
    fig, ax = plt.subplots(figsize=(8, 4), constrained_layout=True)
    ok = [r for r in rows if r["feasible"]]
    bad = [r for r in rows if not r["feasible"]]
    if ok:
        ax.plot([r["spm"] for r in ok], [r["objective_value"] for r in ok], "o-", label="optimal objective")
        if ok[0].get("peak_torque_N_m") is not None:
            ax.plot([r["spm"] for r in ok], [r["peak_torque_N_m"] for r in ok], "s--", label="peak torque [N m]")
    for r in bad:
        ax.axvline(r["spm"], color="tab:red", alpha=0.4, lw=1)
    ax.set_xlabel("stitches per minute")
    ax.set_ylabel("objective")
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize=8)
    ax.set_title("optimal design over the stitch rate (red: infeasible)")
    if path is not None:
        fig.savefig(path, dpi=120)
        plt.close(fig)
    return fig
