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
    # all but the double harmonic are point-symmetric about the middle: y(x) + y(1-x) = 1
    symmetric = bool(np.allclose(y + law(1 - x), 1.0, atol=1e-12))
    assert symmetric == (name != "double_harmonic")
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


# --------------------------------------------------------------------------- the cam handbooks' laws

def _peaks(name, **params):
    c = make_law(name, **params).characteristics
    return c.C_v, c.C_a, c.C_j


def test_modified_trapezoid_published_values():
    # Norton, Cam Design and Manufacturing Handbook (2nd ed., 2009), SCCA family: modified trapezoid
    # C_v 2.0000, C_a 4.8881, C_j 61.426 (the acceptance: C_a within 0.1 % of 4.888)
    c_v, c_a, c_j = _peaks("modified_trapezoid")
    assert c_v == pytest.approx(2.0, rel=1e-6)
    assert c_a == pytest.approx(4.8881, rel=1e-4)
    assert c_j == pytest.approx(61.426, rel=1e-4)
    assert make_law("modified_trapezoid").characteristics.continuity == 2


@pytest.mark.parametrize("shares, same_as", [
    # Norton's SCCA table: (b, c) = (0.25, 0) modified sine, (0.5, 0) cycloidal, (0, 0) simple harmonic,
    # (0, 1) constant acceleration -- the family written once reproduces the laws written on their own
    ((0.25, 0.0), ("modified_sine", {"chi": 0.125})),
    ((0.5, 0.0), ("sine", {})),
    ((0.0, 0.0), ("cosine", {})),
    ((0.0, 1.0), ("parabolic", {})),
])
def test_scca_family_members_are_the_classic_laws(shares, same_as):
    family = make_law("scca", sine_share=shares[0], constant_accel_share=shares[1])
    name, params = same_as
    x = np.linspace(0, 1, 801)
    assert np.allclose(family(x), make_law(name, **params)(x), atol=1e-12)


def test_trapezoidal_velocity_with_a_third_at_constant_speed():
    # the acceptance (and the closed form: C_v = 1/(1 - t_a), C_a = C_v/t_a with t_a = 1/3)
    c_v, c_a, _ = _peaks("trapezoidal_velocity", constant_speed_share=1 / 3)
    assert c_v == pytest.approx(1.5, rel=1e-9)
    assert c_a == pytest.approx(4.5, rel=1e-9)


def test_modified_constant_velocity_mcv50_published_values():
    # Makino's MCV50 (modified sine, half the move at constant velocity), as the Japanese cam-curve tables
    # list it: V_m 1.28, A_m 8.01, J_m 201.4 (3-4 digits as printed)
    c_v, c_a, c_j = _peaks("modified_sine_cv", chi=0.125, constant_speed_share=0.5)
    assert c_v == pytest.approx(1.28, abs=5e-3)
    assert c_a == pytest.approx(8.01, abs=5e-3)
    assert c_j == pytest.approx(201.4, abs=5e-2)


def test_trapezoidal_acceleration_closed_form():
    # straight jerk ramps over 1/8 of the move, constant acceleration between (Norton's "trapezoidal
    # acceleration"): the areas give C_v = 2, C_a = 16/3 and C_j = C_a/(1/8) = 128/3
    c_v, c_a, c_j = _peaks("trapezoidal_acceleration")
    assert (c_v, c_a, c_j) == pytest.approx((2.0, 16 / 3, 128 / 3), rel=1e-9)


@pytest.mark.parametrize("name, params, base", [
    ("trapezoidal_velocity", {}, ("parabolic", {})),
    ("s_curve", {"ramp_share": 0.5}, ("trapezoidal_acceleration", {})),
    ("s_curve", {"ramp_share": 1.0}, ("s_curve", {"ramp_share": 1.0, "constant_speed_share": 0.0})),
    ("modified_sine_cv", {"chi": 0.095}, ("modified_sine", {"chi": 0.095})),
])
@pytest.mark.parametrize("share", [0.1, 1 / 3, 0.6])
def test_constant_speed_share_scales_the_base_law(name, params, base, share):
    # a cruise of share c inserted into a symmetric law of C_v, C_a, C_j: the accelerating part runs in
    # (1 - c) of the time at a stroke share s = (1 - c)/((1 - c) + C_v c), so
    # C_v' = C_v/((1 - c) + C_v c), C_a' = C_v'/(1 - c) * C_a/C_v, C_j' = C_a'/(1 - c) * C_j/C_a
    b_v, b_a, b_j = _peaks(base[0], **base[1])
    c_v, c_a, c_j = _peaks(name, **params, constant_speed_share=share)
    k = 1 - share
    assert c_v == pytest.approx(b_v / (k + b_v * share), rel=1e-8)
    assert c_a == pytest.approx(b_a / (k * (k + b_v * share)), rel=1e-8)
    assert c_j == pytest.approx(b_j / (k**2 * (k + b_v * share)), rel=1e-8)


def test_poly9_against_its_polynomial():
    # y = 126x^5 - 420x^6 + 540x^7 - 315x^8 + 70x^9: derivatives by numpy's polynomial class on a fine grid
    p = np.polynomial.Polynomial([0, 0, 0, 0, 0, 126, -420, 540, -315, 70])
    x = np.linspace(0, 1, 200001)
    c_v, c_a, c_j = _peaks("poly9")
    for order, value in ((1, c_v), (2, c_a), (3, c_j)):
        assert value == pytest.approx(np.max(np.abs(p.deriv(order)(x))), rel=1e-8)
    assert c_v == pytest.approx(315 / 128, rel=1e-12)
    assert make_law("poly9").characteristics.continuity == 4  # velocity to snap vanish at both ends


def test_double_harmonic_closed_form():
    # Rothbart, Cam Design Handbook: y = (1 - cos pi x)/2 - (1 - cos 2 pi x)/8; y' peaks at x = 2/3,
    # C_v = 3 sqrt(3) pi/8; the acceleration ends at -pi^2 against the dwell (a jump: C1)
    c = make_law("double_harmonic").characteristics
    assert c.C_v == pytest.approx(3 * math.sqrt(3) * math.pi / 8, rel=1e-9)
    assert c.C_a == pytest.approx(math.pi**2, rel=1e-9)
    assert c.continuity == 1 and math.isinf(c.C_j)


@pytest.mark.parametrize("name, bad, field", [
    ("scca", {"sine_share": 0.6, "constant_accel_share": 0.6}, "more than 1"),
    ("scca", {"sine_share": -0.1}, "sine_share"),
    ("s_curve", {"ramp_share": 0.0}, "ramp_share"),
    ("s_curve", {"ramp_share": 1.5}, "ramp_share"),
    ("trapezoidal_velocity", {"constant_speed_share": 1.0}, "constant_speed_share"),
    ("modified_sine_cv", {"chi": 0.3}, "chi"),
])
def test_bad_family_parameters(name, bad, field):
    with pytest.raises(ProblemError, match=field):
        make_law(name, **bad)


def test_laws_in_a_problem_file(tmp_path, reference_path):
    from strokeopt import load_problem

    text = reference_path.read_text()
    text = text.replace('law = "modified_sine"', 'law = "s_curve"\nramp_share = 0.8', 1)
    text = text.replace("chi = 0.095", "constant_speed_share = 0.25", 1)
    path = tmp_path / "scurve.toml"
    path.write_text(text)
    law = load_problem(path).default_law
    assert (law.name, law.params) == ("s_curve", {"constant_speed_share": 0.25, "ramp_share": 0.8})


# --------------------------------------------------------------------------- a move's own points

def test_points_law_through_a_quintics_points_is_that_quintic():
    # the degree-5 B-spline with v = a = 0 at both ends is unique; the 3-4-5 polynomial is one, so through its
    # own points the points law is the 3-4-5 law (on any span and stroke)
    from strokeopt.motion.laws import points_law

    poly5 = make_law("poly5")
    x = np.array([0.1, 0.3, 0.45, 0.7, 0.9])
    law = points_law(x * 40.0, poly5(x) * 12.0, 40.0, 12.0)
    grid = np.linspace(0, 1, 1001)
    assert np.allclose(law(grid), poly5(grid), atol=1e-12)
    c = law.characteristics
    assert (c.C_v, c.C_a, c.C_j) == pytest.approx((1.875, 10 / math.sqrt(3), 60.0), rel=1e-9)


@pytest.mark.parametrize("rest_order, polynomial", [(1, "cubic"), (2, "poly5"), (3, "poly7")])
def test_points_law_meets_its_dwells_with_its_rest_order(rest_order, polynomial):
    # through the points of the polynomial of its rest order (3-2, 3-4-5, 4-5-6-7) the spline is that polynomial
    from strokeopt.motion.laws import points_law

    x = np.array([5.0, 20.0, 30.0]) / 36.0
    y = make_law(polynomial)(x)
    law = points_law(x * 36.0, y * 10.0, 36.0, 10.0, rest_order)
    grid = np.linspace(0, 1, 501)
    assert np.allclose(law(grid), make_law(polynomial)(grid), atol=1e-11)
    ends = law.derivatives([0.0, 1.0], order=4)
    assert np.allclose(ends[0], [0.0, 1.0], atol=1e-12)
    for k in range(1, rest_order + 1):  # the first rest_order derivatives vanish at both ends
        assert np.allclose(ends[k], 0.0, atol=1e-9)
    assert law.characteristics.continuity == rest_order


@pytest.mark.parametrize("angles, positions, field, words", [
    ([10.0, 20.0], [2.0], "positions_mm", "1 positions for 2 angles"),
    ([0.0, 20.0], [2.0, 5.0], "angles_deg", "inside the move"),
    ([20.0, 10.0], [2.0, 5.0], "angles_deg", "rise strictly"),
    ([10.0, 20.0], [5.0, 2.0], "positions_mm", "must rise from 0"),
    ([10.0, 20.0], [2.0, 10.0], "positions_mm", "strictly between its ends"),
    ([10.0, "x"], [2.0, 5.0], "angles_deg", "list of finite numbers"),
    ([4.0, 8.0, 28.0, 32.0], [0.5, 9.5, 9.6, 9.9], "positions_mm", "goes back near"),
])
def test_points_law_refuses_points_that_are_no_rise(angles, positions, field, words):
    from strokeopt.motion.laws import points_law

    with pytest.raises(ProblemError, match=words) as exc:
        points_law(angles, positions, 36.0, 10.0, where=("f.toml", "timing.intervals[2]"),
                   positions_key="positions_mm")
    assert exc.value.field == f"timing.intervals[2].{field}"


def test_points_law_is_a_moves_own(reference_path):
    with pytest.raises(ProblemError, match="a move's own points"):
        make_law("points")


# --------------------------------------------------------------------------- moves that start or end at a speed

@pytest.mark.parametrize("start, end", [(0.0, 0.0), (0.0, 1.5), (0.75, 0.75), (1.125, 0.4), (1.0, 1.0)])
def test_poly5_between_speeds_meets_its_boundary_values(start, end):
    # VDI 2143's polynomial of degree 5 with boundary values: y(0) = 0, y(1) = 1, y' the given speeds, y'' = 0
    law = make_law("poly5_speeds", start_speed=start, end_speed=end)
    y, y1, y2 = law.derivatives([0.0, 1.0], order=2)
    assert np.allclose(y, [0, 1], atol=1e-12) and np.allclose(y1, [start, end], atol=1e-12)
    assert np.allclose(y2, 0, atol=1e-10)
    x = np.linspace(0, 1, 301)
    if start == end == 0.0:  # rest to rest: the 3-4-5 polynomial
        assert np.allclose(law(x), make_law("poly5")(x), atol=1e-12)
    if start == end == 1.0:  # at the mean speed at both ends: constant speed
        assert np.allclose(law(x), x, atol=1e-12)


def test_a_turn_that_closes_at_speed_runs_at_constant_speed():
    # the hybrid loom's single move of a turn, joined to itself at speed: the classic stroke is the crank at its
    # constant speed (200 picks/min: 2 pi x 200/60 rad/s), the linkage's own machine
    from pathlib import Path

    from strokeopt import load_problem

    problem = load_problem(Path(__file__).resolve().parents[2] / "problems" / "loom_beatup_hybrid.toml")
    stroke = problem.stroke()
    k = stroke.evaluate(np.linspace(0, stroke.period, 1001))
    assert np.allclose(k.v, 2 * math.pi * 200 / 60, rtol=1e-9) and np.allclose(k.a, 0, atol=1e-6)


def test_moves_joined_at_speed_keep_speed_and_acceleration_across_the_joint():
    from pathlib import Path

    from strokeopt import load_problem

    problem = load_problem(Path(__file__).resolve().parents[2] / "problems" / "known_optima" / "turning_spline.toml")
    stroke = problem.stroke()
    laws = problem.timing.move_laws(problem.spm)
    assert {law.name for law in laws.values()} == {"poly5_speeds"}
    for at in (stroke.pieces[1].t_start, 0.0):
        before, after = stroke.evaluate([(at - 1e-9) % stroke.period, at + 1e-9]).v
        assert before == pytest.approx(after, rel=1e-6) and after == pytest.approx(2 * math.pi, rel=1e-6)


def test_a_short_move_joined_at_speed_to_a_long_one_has_a_stroke(tmp_path):
    # 10 deg in 90 deg of cam, then 350 deg in 270, one turn a cycle: the joints at 1 deg per cam deg are 9 times
    # the short move's mean speed -- a classic stroke all the same, continuous in speed across the joints
    from pathlib import Path

    from strokeopt import load_problem

    text = (Path(__file__).resolve().parents[2] / "problems" / "known_optima" / "turning_spline.toml").read_text()
    text = text.replace("stroke_deg = 120", "stroke_deg = 10").replace("stroke_deg = 240", "stroke_deg = 350")
    path = tmp_path / "short.toml"
    path.write_text(text)
    problem = load_problem(path)
    laws = problem.timing.move_laws(problem.spm)
    assert laws[1].params == {"end_speed": 9.0, "start_speed": 9.0}
    stroke = problem.stroke()
    at = stroke.pieces[1].t_start
    before, after = stroke.evaluate([at - 1e-9, at + 1e-9]).v
    assert before == pytest.approx(after, rel=1e-6) == pytest.approx(2 * math.pi, rel=1e-6)
