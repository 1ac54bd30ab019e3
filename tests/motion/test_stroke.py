"""Timing diagram and StrokeFunction over the whole periodic cycle."""

from __future__ import annotations

import numpy as np
import pytest

from strokeopt import load_problem


def test_cycle_time_and_angles(reference):
    # 500 spm = 250 cam rpm: one cam revolution in 0.24 s (sources A.2 header)
    assert reference.timing.period(500) == pytest.approx(0.24)
    sch = reference.timing.schedule(500)
    # published times put move 1 at 21.0-58.8 deg (sources A.2)
    assert sch.start_angle_deg[1] == pytest.approx(21.0)
    assert sch.end_angle_deg[1] == pytest.approx(58.8)
    assert sch.duration[1] == pytest.approx(0.0252)
    # at 600 spm the published times scale to 0.021 / 0.026 / 0.008 s for the moves (thesis Tab. 4.1)
    assert reference.timing.schedule(600).duration[[1, 3, 4]] == pytest.approx([0.021, 0.026, 0.008])


def test_nominal_times_follow_the_spans(reference_path):
    p = load_problem(reference_path, ["timing.interval_times=nominal"])
    sch = p.timing.schedule(500)
    assert sch.start_angle_deg[1] == pytest.approx(21.6)
    assert sch.end_angle_deg[1] == pytest.approx(59.0)
    assert sch.duration[1] == pytest.approx(37.4 / 1500)


def test_dwells_are_exactly_at_rest(reference):
    stroke = reference.stroke()
    sch = reference.timing.schedule(reference.spm)
    for itv, t0, dur in zip(reference.timing.intervals, sch.t_start, sch.duration):
        if itv.is_move:
            continue
        k = stroke.evaluate(np.linspace(t0, t0 + dur, 50, endpoint=False))
        assert np.all(k.s == itv.start_position)
        assert np.all(k.v == 0) and np.all(k.a == 0) and np.all(k.j == 0)


def test_positions_at_interval_ends(reference):
    stroke = reference.stroke()
    sch = reference.timing.schedule(reference.spm)
    ends = stroke.evaluate(sch.t_start + sch.duration * (1 - 1e-12)).s
    assert ends * 1e3 == pytest.approx([32, 0, 0, 35, 32, 32], abs=1e-6)  # thesis Tab. 4.1


def test_periodic_and_symbolic_equals_numeric(reference):
    stroke = reference.stroke()
    t = np.linspace(0, stroke.period, 97)
    k0, k1 = stroke.evaluate(t), stroke.evaluate(t + stroke.period)
    assert np.allclose(k0.s, k1.s) and np.allclose(k0.a, k1.a)
    fn = stroke.casadi_function()
    sym = np.array([[float(x) for x in fn(ti)] for ti in t])
    for col, arr in enumerate((k0.s, k0.v, k0.a)):
        assert np.allclose(sym[:, col], arr, rtol=1e-12, atol=1e-9)


def test_velocity_is_derivative_of_position(reference):
    stroke = reference.stroke()
    t = np.linspace(0.02, 0.035, 40)
    h = 1e-7
    fd = (stroke.evaluate(t + h).s - stroke.evaluate(t - h).s) / (2 * h)
    assert np.allclose(stroke.evaluate(t).v, fd, rtol=1e-5, atol=1e-6)


def test_jerk_unbounded_for_laws_with_acceleration_jumps(reference):
    for name, unbounded in (("parabolic", True), ("cubic", True), ("sine", False), ("poly7", False)):
        from strokeopt import make_law

        peaks = reference.with_law(make_law(name)).stroke().piece_peaks()
        assert np.isinf(peaks[1].j_max) == unbounded, name
        assert peaks[0].j_max == 0  # a dwell has no jerk


def test_reported_span_is_the_angle_the_times_give(reference):
    from strokeopt.report.motion import kinematics_summary

    # published times put move 1 at 21.0-58.8 deg: 37.8 deg, against the nominal 37.4 (thesis Tab. 4.1)
    move1 = kinematics_summary(reference, reference.stroke(), 500)["moves"][0]
    assert move1["span_deg"] == pytest.approx(37.8)
    assert move1["span_nominal_deg"] == pytest.approx(37.4)
