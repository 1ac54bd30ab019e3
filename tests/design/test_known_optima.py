"""Known optima of a rest-to-rest move (docs/architecture.md, "Known optima"), each a problem file under
problems/known_optima/ solved at the file's default mesh; within 0.5 %."""

from __future__ import annotations

import math
from pathlib import Path

import pytest

from strokeopt import load_problem
from strokeopt.design.solve import solve_design

KNOWN = Path(__file__).resolve().parents[2] / "problems" / "known_optima"

# (file, peak-acceleration coefficient C_a = max|a| T^2/h, source)
COEFFICIENTS = [
    ("min_peak_accel.toml", 4.0),  # docs/architecture.md: constant acceleration (parabolic), 4 h/T^2
    ("min_accel_squared.toml", 6.0),  # docs/architecture.md: cubic 3-2 polynomial, 6 h/T^2
    ("min_jerk.toml", 5.7735),  # docs/architecture.md: 3-4-5 polynomial, 5.7735 h/T^2
    ("min_snap.toml", 7.5132),  # docs/architecture.md: 4-5-6-7 polynomial, 7.5132 h/T^2
    ("jerk_bounded_peak_accel.toml", 4.445),  # issue 4 "what we already measured": 4.445 with modified sine's jerk bound
]


@pytest.mark.parametrize("name, c_a", COEFFICIENTS)
def test_peak_acceleration_coefficient(name, c_a):
    design = solve_design(load_problem(KNOWN / name))
    assert design.status == "optimal"
    for move in design.moves:
        assert move.C_a == pytest.approx(c_a, rel=0.005)
        # the coefficient is the SI peak over h/T^2 (1 m in 1 s)
        assert move.a_max == pytest.approx(c_a * abs(move.stroke) / move.duration**2, rel=0.005)


def test_jerk_bounded_optimum_beats_modified_sine():
    # issue 4: 4.445 against 5.373 for the modified sine chi = 0.095 with the same peak jerk
    problem = load_problem(KNOWN / "jerk_bounded_peak_accel.toml")
    design = solve_design(problem)
    law = problem.default_law.characteristics
    assert law.C_a == pytest.approx(5.373, rel=0.002)  # sources A.3
    assert design.moves[0].C_a < 0.85 * law.C_a
    # the jerk bound holds between the collocation nodes too, and is active
    for move in design.moves:
        assert move.jerk_max <= law.C_j * abs(move.stroke) / move.duration**3 * (1 + 1e-6)
    assert any("jerk bound" in c for c in design.active_constraints)


def test_inertia_matching_radius():
    # docs/architecture.md: (J/r + m r) a is smallest at r = sqrt(J/m); J = 0.23 kg cm^2 (055U2B30, thesis Tab. 4.5), m = 0.2 kg
    design = solve_design(load_problem(KNOWN / "inertia_matching.toml"))
    r_star = math.sqrt(0.23e-4 / 0.2)
    assert design.radius == pytest.approx(r_star, rel=0.005)
    # and the peak torque is the closed form (J/r + m r) * 4 h/T^2 at that radius
    move = design.moves[0]
    expected = (0.23e-4 / r_star + 0.2 * r_star) * 4 * abs(move.stroke) / move.duration**2
    assert design.objective_value == pytest.approx(expected, rel=0.005)


def test_objective_values_are_the_closed_forms():
    # integral of jerk^2 of the 3-4-5 polynomial is 720 h^2/T^5 per move (two moves: 1440)
    assert solve_design(load_problem(KNOWN / "min_jerk.toml")).objective_value == pytest.approx(1440, rel=1e-6)
    # integral of a^2 of the cubic is 12 h^2/T^3 per move
    assert solve_design(load_problem(KNOWN / "min_accel_squared.toml")).objective_value == pytest.approx(24, rel=1e-6)
