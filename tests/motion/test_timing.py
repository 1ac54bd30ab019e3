"""The timing diagram (motion/timing.py): cam period, interval times, the classic-law stroke."""

from __future__ import annotations

import numpy as np
import pytest

from strokeopt import make_law

# thesis Tab. 4.1: interval end angles of the new mechanism, upper needle bar [deg]
END_ANGLES_DEG = [21.6, 59.0, 228.6, 275.1, 290.1, 360.0]
# thesis Tab. 4.1: interval times at 500 and 600 spm [s]
TIMES_500 = [0.014, 0.0252, 0.1128, 0.0312, 0.0096, 0.0472]
TIMES_600 = [0.012, 0.021, 0.094, 0.026, 0.008, 0.039]


def test_cam_period_is_two_stitches(reference):
    # sources A: 500 spm = 250 rpm of the virtual cam, one cam revolution = two stitches
    assert reference.timing.period(500) == pytest.approx(60 / 250, rel=1e-12)
    assert reference.timing.period(600) == pytest.approx(0.2, rel=1e-12)


def test_nominal_times_follow_the_spans(reference):
    timing = reference.timing.__class__(reference.timing.intervals, reference.timing.cam_revolutions_per_stitch,
                                        "nominal")
    sch = timing.schedule(500)
    # thesis Tab. 4.1 angles, exact for nominal times
    assert sch.end_angle_deg == pytest.approx(END_ANGLES_DEG, abs=1e-9)
    assert sch.duration.sum() == pytest.approx(sch.period, rel=1e-12)
    assert sch.t_start[0] == 0.0


def test_published_times_are_those_of_the_thesis(reference):
    # thesis Tab. 4.1 time columns; the reference problem computes with interval_times = "published".
    # At 500 spm the printed times add to the cycle (0.24 s) and are used as printed.
    assert reference.timing.interval_times == "published"
    sch = reference.timing.schedule(500)
    assert sch.duration == pytest.approx(TIMES_500, rel=1e-9)
    # At 600 spm they are the 500 spm times scaled; the thesis printed them to 1 ms: half a unit of that digit
    sch = reference.timing.schedule(600)
    assert sch.duration == pytest.approx(TIMES_600, abs=0.5e-3)
    assert sch.duration.sum() == pytest.approx(sch.period, rel=1e-12)


def test_angle_and_time_are_inverse(reference):
    t = np.array([0.0, 0.01, 0.1, 0.2])
    assert reference.timing.time_s(reference.timing.angle_deg(t, 600), 600) == pytest.approx(t, abs=1e-15)


def test_moves_and_handover(reference):
    moves = reference.timing.moves
    assert [m.move_index for m in moves] == [1, 2, 3]
    assert [abs(m.stroke) * 1e3 for m in moves] == pytest.approx([32, 35, 3])  # thesis Tab. 4.1 strokes
    assert reference.timing.handover_move is moves[0]


def test_stroke_closes_the_cycle_and_rests_in_the_dwells(reference):
    stroke = reference.stroke(600)
    sch = reference.timing.schedule(600)
    assert stroke.period == pytest.approx(sch.period)
    ends = sch.t_start + sch.duration
    k = stroke.evaluate(np.concatenate([sch.t_start, ends]))
    positions = [i.start_position for i in reference.timing.intervals] + [i.end_position for i in reference.timing.intervals]
    assert k.s == pytest.approx(positions, abs=1e-12)
    assert np.abs(k.v) == pytest.approx(np.zeros(len(positions)), abs=1e-9)


def test_with_law_changes_every_move_and_no_dwell(reference):
    poly5 = make_law("poly5")
    timing = reference.timing.with_law(poly5)
    assert all(m.law == poly5 for m in timing.moves)
    assert [i.is_move for i in timing.intervals] == [i.is_move for i in reference.timing.intervals]
