"""Motion laws: characteristic values, continuity classes, symmetry, symbolic = numeric."""

from __future__ import annotations

import math

import casadi as ca
import numpy as np
import pytest

from strokeopt import LAW_NAMES, ProblemError, make_law

# Closed forms of the characteristic values (textbook cam-law results; the laws
# compute theirs from their own derivatives, these are independent checks).
CLOSED_FORM = {
    #  law: (C_v, C_a, C_j or inf, continuity)
    "parabolic": (2.0, 4.0, math.inf, 1),
    "cubic": (1.5, 6.0, math.inf, 1),
    "cosine": (math.pi / 2, math.pi**2 / 2, math.inf, 1),
    "sine": (2.0, 2 * math.pi, 4 * math.pi**2, 2),
    "poly5": (1.875, 10 / math.sqrt(3), 60.0, 2),
    "poly7": (2.1875, 7.513188404, 52.5, 3),
}


@pytest.mark.parametrize("name", list(CLOSED_FORM))
def test_characteristic_values_match_closed_forms(name):
    c = make_law(name).characteristics
    cv, ca_, cj, cont = CLOSED_FORM[name]
    assert c.C_v == pytest.approx(cv, rel=1e-8)
    assert c.C_a == pytest.approx(ca_, rel=1e-8)
    assert c.C_j == pytest.approx(cj, rel=1e-8) if math.isfinite(cj) else math.isinf(c.C_j)
    assert c.continuity == cont


def test_modified_sine_classic_value():
    # chi = 1/8 is the classic modified sine, C_a = 5.528 (thesis 4.4)
    assert make_law("modified_sine", chi=0.125).characteristics.C_a == pytest.approx(5.528, abs=5e-4)


def test_modified_sine_thesis_chi():
    # chi = 0.095: C_a ~ 5.373, C_v ~ 1.710 (thesis 4.4, as printed: 3-4 digits)
    c = make_law("modified_sine", chi=0.095).characteristics
    assert c.C_a == pytest.approx(5.373, abs=5e-4)
    assert c.C_v == pytest.approx(1.710, abs=5e-4)
    assert c.continuity == 2


def test_modified_sine_tends_to_cosine_as_chi_vanishes():
    cosine = make_law("cosine").characteristics
    errors = [abs(make_law("modified_sine", chi=chi).characteristics.C_a - cosine.C_a) for chi in (0.05, 0.01, 0.001)]
    assert errors[0] > errors[1] > errors[2]
    assert errors[2] < 1e-3 * cosine.C_a


def test_modified_sine_at_quarter_is_the_cycloid():
    x = np.linspace(0, 1, 1001)
    assert np.allclose(make_law("modified_sine", chi=0.25)(x), make_law("sine")(x), atol=1e-12)


@pytest.mark.parametrize("name", LAW_NAMES)
def test_unit_rise_and_symmetry(name):
    law = make_law(name)
    x = np.linspace(0, 1, 401)
    y = law(x)
    assert law(0.0) == pytest.approx(0.0, abs=1e-14)
    assert law(1.0) == pytest.approx(1.0, abs=1e-14)
    assert np.all(np.diff(y) >= -1e-14)  # a rise never goes back
    # all these laws are point-symmetric about the middle: y(x) + y(1-x) = 1
    assert np.allclose(y + law(1 - x), 1.0, atol=1e-12)
    # velocity vanishes at both ends: the move joins its dwells smoothly in position and velocity
    _, y1 = law.derivatives([0.0, 1.0], order=1)
    assert np.allclose(y1, 0.0, atol=1e-12)


@pytest.mark.parametrize("name", LAW_NAMES)
def test_symbolic_equals_numeric_and_ad_matches_finite_differences(name):
    law = make_law(name)
    x = ca.MX.sym("x")
    f = ca.Function("f", [x], [law(x)])
    pts = np.array([0.03, 0.2, 0.37, 0.61, 0.88])
    assert np.allclose([float(f(p)) for p in pts], law(pts), atol=1e-14)
    y, y1, y2, _ = law.derivatives(pts)
    h = 1e-5
    fd1 = (law(pts + h) - law(pts - h)) / (2 * h)
    fd2 = (law(pts + h) - 2 * law(pts) + law(pts - h)) / h**2
    assert np.allclose(y1, fd1, atol=1e-7)
    assert np.allclose(y2, fd2, atol=1e-3)


@pytest.mark.parametrize("name", ["parabolic", "cubic", "cosine"])
def test_acceleration_jumps_against_dwell_or_inside(name):
    law = make_law(name)
    _, _, y2 = law.derivatives([0.0], order=2)
    jumps_at_end = abs(y2[0]) > 1
    jumps_inside = bool(law.breaks) and abs(np.diff(law.derivatives([0.5 - 1e-9, 0.5 + 1e-9], 2)[2])[0]) > 1
    assert jumps_at_end or jumps_inside


def test_poly7_is_continuous_to_jerk():
    _, _, y2, y3, y4 = make_law("poly7").derivatives([0.0, 1.0], order=4)
    assert np.allclose(y2, 0) and np.allclose(y3, 0) and np.all(np.abs(y4) > 100)


@pytest.mark.parametrize("bad", [{"chi": 0.0}, {"chi": 0.3}, {"chi": -0.1}, {"chi": "x"}])
def test_bad_chi(bad):
    with pytest.raises(ProblemError, match="chi"):
        make_law("modified_sine", **bad)


def test_unknown_law_and_parameter():
    with pytest.raises(ProblemError, match="unknown motion law 'trapezoid'"):
        make_law("trapezoid")
    with pytest.raises(ProblemError, match="takes no parameter chi"):
        make_law("poly5", chi=0.1)
