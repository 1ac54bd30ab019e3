"""The timing diagram: dwells and moves on the cam circle.

One cycle of the machine is one revolution of the (virtual) cam. The cam
angle runs uniformly in time, ``angle = 360 deg * t / period``, and the cycle
time follows from the stitch rate: ``period = 60 / (spm * cam_revolutions_per_stitch)``
(the needle bar: half a cam revolution per stitch, 500 spm = 250 cam rpm).

Interval times are either

* ``"nominal"``: in proportion to the angle spans, or
* ``"published"``: in proportion to tabulated times (the thesis computed its
  kinematic figures with rounded times, thesis Tab. 4.1, which are not exactly
  proportional to the spans); scaled to the cycle time at any other speed.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from .laws import MotionLaw
from .stroke import StrokeFunction, dwell_piece, law_piece

#: Plausible stitch rates [spm] (``machine.spm``, ``--spm``): from one stitch a minute (a slow indexing
#: machine) to 20000 spm, twice the fastest textile machines; outside it a cycle is either too long for the
#: servo simulation's time grid or too short for any move to be driven.
SPM_RANGE = (1.0, 20000.0)

INTERVAL_TIMES = ("nominal", "published")


@dataclass(frozen=True)
class Interval:
    """One interval of the cycle. Positions in metres (radians for a rotary load: TimingDiagram.unit),
    measured as the problem states (up positive)."""

    index: int  # 1-based position in the cycle
    name: str
    span_deg: float  # nominal angle span
    start_position: float
    end_position: float
    law: MotionLaw | None  # None for a dwell
    published_time_s: float | None = None
    handover: bool = False  # the move that ends at the handover position
    move_index: int | None = None  # 1-based among the moves
    #: the move ends at speed: the next interval is a move that starts at it (speed and, with the design's rest
    #: order, acceleration continuous across the joint); False: at rest (a dwell or a stop follows)
    end_speed: bool = False

    @property
    def is_move(self) -> bool:
        return self.law is not None

    @property
    def stroke(self) -> float:
        """Signed stroke in metres (end - start)."""
        return self.end_position - self.start_position


@dataclass(frozen=True)
class Schedule:
    """Start times, durations and cam angles of the intervals at one speed."""

    spm: float
    period: float
    t_start: np.ndarray
    duration: np.ndarray

    @property
    def start_angle_deg(self) -> np.ndarray:
        return 360.0 * self.t_start / self.period

    @property
    def end_angle_deg(self) -> np.ndarray:
        return 360.0 * (self.t_start + self.duration) / self.period


@dataclass(frozen=True)
class TimingDiagram:
    intervals: tuple[Interval, ...]
    cam_revolutions_per_stitch: float = 0.5
    interval_times: str = "nominal"
    #: the SI unit of the load's positions: "m" (a linear load, the file in mm) or "rad" (a rotary load such
    #: as a sley on its shaft, the file in deg); the design's equations are the same for both
    unit: str = "m"
    #: how far the load advances in one cycle (SI): 0 for a reciprocating load, a turn (2 pi) for a crank that
    #: turns once a cycle; the positions of the next cycle are this cycle's plus it
    advance: float = 0.0

    @property
    def rotary(self) -> bool:
        return self.unit == "rad"

    @property
    def moves(self) -> tuple[Interval, ...]:
        return tuple(i for i in self.intervals if i.is_move)

    def starts_at_speed(self, interval: Interval) -> bool:
        """Whether ``interval`` (a move) starts at speed: the interval before it (cyclically) ends at speed."""
        return self.intervals[interval.index - 2].end_speed

    @property
    def at_speed(self) -> bool:
        """Whether any move joins the next at speed."""
        return any(i.end_speed for i in self.intervals)

    @property
    def position_range(self) -> tuple[float, float]:
        """The lowest and highest position the intervals start or end at (SI)."""
        ends = [p for i in self.intervals for p in (i.start_position, i.end_position)]
        return min(ends), max(ends)

    @property
    def handover_move(self) -> Interval | None:
        return next((i for i in self.intervals if i.handover), None)

    def period(self, spm: float) -> float:
        """Cycle (cam revolution) time in seconds at ``spm`` stitches per minute."""
        return 60.0 / (spm * self.cam_revolutions_per_stitch)

    def schedule(self, spm: float) -> Schedule:
        period = self.period(spm)
        if self.interval_times == "published":
            weights = np.array([i.published_time_s for i in self.intervals], dtype=float)
        else:
            weights = np.array([i.span_deg for i in self.intervals], dtype=float)
        duration = period * weights / weights.sum()
        t_start = np.concatenate([[0.0], np.cumsum(duration)[:-1]])
        return Schedule(spm, period, t_start, duration)

    def angle_deg(self, t, spm: float):
        return 360.0 * np.asarray(t) / self.period(spm)

    def time_s(self, angle_deg, spm: float):
        return np.asarray(angle_deg) / 360.0 * self.period(spm)

    def with_law(self, law: MotionLaw) -> "TimingDiagram":
        """The same diagram with every move following ``law``."""
        return replace(self, intervals=tuple(replace(i, law=law) if i.is_move else i for i in self.intervals))

    def stroke(self, spm: float) -> StrokeFunction:
        """The stroke of the classic laws of this diagram at ``spm``."""
        sch = self.schedule(spm)
        pieces = []
        for itv, t0, dur in zip(self.intervals, sch.t_start, sch.duration):
            if itv.is_move:
                pieces.append(law_piece(t0, dur, itv.start_position, itv.stroke, itv.law, f"{itv.name}: {itv.law.label}"))
            else:
                pieces.append(dwell_piece(t0, dur, itv.start_position, itv.name))
        laws = {i.law.label for i in self.moves}
        return StrokeFunction(sch.period, pieces, label=", ".join(sorted(laws)))
