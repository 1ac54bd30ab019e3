"""What every figure shares: the coordinates its axes are in, and dwell bands on a cam-angle axis.

Every figure and table gives positions and velocities in the problem's coordinates: the problem
file's positions (``timing.start_position_mm`` and the moves' strokes; + is a move with
``direction = "up"``; 0 is the handover point of the reference problem). The contact model computes
in its own coordinates (from the start of the handover move, + toward the handover); its results
are turned into the problem's before they are drawn (:meth:`~strokeopt.contact.simulate.SceneResult.problem_position`).
"""

from __future__ import annotations

#: the axis-label suffix naming the problem's coordinates
PROBLEM_FRAME = "problem frame, + up"


def frame_label(quantity: str, unit: str) -> str:
    """An axis label of a position or velocity in the problem's coordinates: 'position [mm]\\n(problem frame, + up)'."""
    return f"{quantity} [{unit}]\n({PROBLEM_FRAME})"


def shade_dwells(ax, timing, spm) -> None:
    """Grey bands over the dwells of a timing diagram (x axis: cam angle in degrees)."""
    sch = timing.schedule(spm)
    for itv, a0, a1 in zip(timing.intervals, sch.start_angle_deg, sch.end_angle_deg):
        if not itv.is_move:
            ax.axvspan(a0, a1, color="0.9", zorder=0, lw=0)
