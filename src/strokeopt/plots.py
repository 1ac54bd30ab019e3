"""Figures (matplotlib). Computation lives elsewhere; these only draw."""

from __future__ import annotations

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
    units = [("position", "mm", 1e3), ("velocity", "m/s", 1.0), ("acceleration", "m/s$^2$", 1.0),
             ("jerk", "km/s$^3$", 1e-3)]
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
    axes[0].set_title(f"{problem.name}: stroke at {spm:g} spm (dwells shaded)")
    if len(strokes) > 1:
        axes[0].legend(loc="best", fontsize=8)
    if path is not None:
        fig.savefig(path, dpi=120)
        plt.close(fig)
    return fig
