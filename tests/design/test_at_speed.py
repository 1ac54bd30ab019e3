"""Moves that join at speed (``[[timing.intervals]] end = "speed"``) and a load that turns once a cycle
(``[timing] advance_deg``): the collocation holds speed and acceleration continuous across the joint, the cycle
closes modulo the turn, and the known optimum of such a cycle is reproduced."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
from scipy.interpolate import CubicSpline

from strokeopt import ProblemError, load_problem
from strokeopt.design.solve import solve_design

FILE = Path(__file__).resolve().parents[2] / "problems" / "known_optima" / "turning_spline.toml"


def test_the_least_acceleration_squared_through_positions_is_the_periodic_cubic_spline():
    # Holladay's theorem (de Boor, A Practical Guide to Splines, ch. V): of all periodic C2 motions through the
    # positions at the joints, the periodic cubic spline has the least integral of acceleration squared; the
    # collocation's polynomials (degree 5) hold cubics exactly, so the design must meet it to solver precision
    problem = load_problem(FILE)
    assert problem.timing.advance == pytest.approx(2 * math.pi) and problem.timing.at_speed
    design = solve_design(problem)
    T = problem.period
    t1 = T * 90 / 360
    periodic = CubicSpline([0.0, t1, T], np.radians([0.0, 120 - 360 * t1 / T, 0.0]), bc_type="periodic")
    t = np.linspace(0.0, T, 200_001)
    reference = np.trapezoid(periodic(t, 2) ** 2, t)
    assert design.status == "optimal" and design.objective_value == pytest.approx(reference, rel=1e-7)
    assert design.objective_unit == "rad^2/s^3"   # a rotary load's (it said m^2/s^3)
    # the motion itself, and continuous speed and acceleration across the joint and the cycle's wrap
    k = design.stroke.evaluate(t[:-1])
    np.testing.assert_allclose(k.s, periodic(t[:-1]) + 2 * math.pi * t[:-1] / T, atol=1e-7)
    for at in (t1, 0.0):
        for q in ("v", "a"):
            pair = getattr(design.stroke.evaluate([(at - 1e-9) % T, at + 1e-9]), q)
            assert pair[0] == pytest.approx(pair[1], rel=1e-5, abs=1e-6), (at, q)
    assert abs(design.stroke.evaluate([0.0]).v[0]) > 1.0   # it never stops


def _variant(tmp_path, old: str, new: str, base: Path = FILE) -> Path:
    text = base.read_text(encoding="utf-8")
    assert old in text
    path = tmp_path / "variant.toml"
    path.write_text(text.replace(old, new), encoding="utf-8")
    return path


SECOND = 'name = "second"\nspan_deg = 270\nstroke_deg = 240\ndirection = "up"\nend = "speed"'


@pytest.mark.parametrize("old, new, field, words", [
    # a move at speed hands it to a move, not to a dwell
    (SECOND, 'name = "second"\nspan_deg = 270', "timing.intervals[1].end", "is the dwell 'second', which starts at rest"),
    (SECOND, 'name = "second"\nspan_deg = 270\nend = "speed"', "timing.intervals[2].end", "a dwell"),
    ("advance_deg = 360", "advance_deg = 0", "timing.intervals", "the strokes do not close the cycle"),
    ('end = "speed"', 'end = "fast"', "timing.intervals[1].end", "fast"),
])
def test_bad_at_speed_timing_is_refused_by_name(tmp_path, old, new, field, words):
    with pytest.raises(ProblemError) as err:
        load_problem(_variant(tmp_path, old, new))
    assert err.value.field == field and words in err.value.message


def test_advance_on_a_linear_load_is_refused():
    reference = Path(__file__).resolve().parents[2] / "problems" / "deco2000_needle_bar.toml"
    with pytest.raises(ProblemError) as err:
        load_problem(reference, ["timing.advance_deg=360"])
    assert err.value.field == "timing.advance_deg"

