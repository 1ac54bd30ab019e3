"""What every figure shares: dwell bands on a cam-angle axis."""

from __future__ import annotations


def shade_dwells(ax, timing, spm) -> None:
    """Grey bands over the dwells of a timing diagram (x axis: cam angle in degrees)."""
    sch = timing.schedule(spm)
    for itv, a0, a1 in zip(timing.intervals, sch.start_angle_deg, sch.end_angle_deg):
        if not itv.is_move:
            ax.axvspan(a0, a1, color="0.9", zorder=0, lw=0)
