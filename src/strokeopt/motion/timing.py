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
        """The stroke of the classic laws of this diagram at ``spm``. A move that starts or ends at a speed (a joint
        at speed) runs VDI 2143's polynomial of degree 5 between the joints' speeds (:meth:`move_laws`)."""
        sch = self.schedule(spm)
        laws = self.move_laws(spm)
        pieces = []
        for itv, t0, dur in zip(self.intervals, sch.t_start, sch.duration):
            if itv.is_move:
                law = laws[itv.index]
                pieces.append(law_piece(t0, dur, itv.start_position, itv.stroke, law, f"{itv.name}: {law.label}"))
            else:
                pieces.append(dwell_piece(t0, dur, itv.start_position, itv.name))
        return StrokeFunction(sch.period, pieces, label=", ".join(sorted({law.label for law in laws.values()})))

    def move_laws(self, spm: float) -> dict:
        """The law each move runs (by interval index): its own, or where it starts or ends at a speed the
        polynomial of degree 5 between the speeds of its joints. A joint's speed is the mean speed of the two
        moves it joins, ``(h_a + h_b)/(T_a + T_b)`` (zero where they move apart), so a load that turns at a
        constant speed keeps it, and a single move that closes the cycle at speed turns uniformly."""
        from .laws import make_law

        sch = self.schedule(spm)
        items = list(zip(self.intervals, sch.duration))
        out = {}
        for k, (itv, dur) in enumerate(items):
            if not itv.is_move:
                continue
            before, after = items[k - 1], items[(k + 1) % len(items)]
            start = _joint_speed(before, (itv, dur)) if self.starts_at_speed(itv) else 0.0
            end = _joint_speed((itv, dur), after) if itv.end_speed else 0.0
            if start == 0.0 and end == 0.0:
                out[itv.index] = itv.law
                continue
            unit = dur / itv.stroke  # a joint's speed in the move's unit speeds (1: its mean speed)
            out[itv.index] = make_law("poly5_speeds", start_speed=round(start * unit, 12), end_speed=round(end * unit, 12))
        return out


def _joint_speed(a, b) -> float:
    """The speed at the joint of moves ``a`` then ``b`` ((interval, duration) pairs): their mean speed, zero where
    they move apart (a reversal is at rest)."""
    (ia, ta), (ib, tb) = a, b
    if ia.stroke * ib.stroke <= 0:
        return 0.0
    return (ia.stroke + ib.stroke) / (ta + tb)
