"""Published kinematic figures of the thesis, reproduced from the motion laws.

Reference problem: problems/deco2000_needle_bar.toml (thesis Tab. 4.1), modified
sine chi = 0.095, GT3 pulley 28 teeth (pitch diameter 26.74 mm).
"""

from __future__ import annotations

import math

import pytest

from strokeopt import load_problem, make_law

REL = 0.01  # "reproduce within 1 %" (sources A.3)

# thesis Tab. 4.2: 500 spm, published interval times; per move 1/2/3
TAB_4_2 = {
    "v_max_m_s": (2.17, 1.92, 0.54),
    "a_max_m_s2": (270.81, 193.23, 174.94),
    "pulley_speed_max_deg_s": (9309, 8224, 2291),
    "pulley_accel_max_deg_s2": (1_160_514, 828_057, 749_688),
}
# thesis Tab. 4.8: the same law at 600 spm
TAB_4_8 = {
    "v_max_m_s": (2.61, 2.30, 0.64),
    "a_max_m_s2": (389.96, 278.25, 251.91),
}
# thesis appendix 3: move 1 at 500 spm, interval time 37.4/1500 s; max bar acceleration, speed
APPENDIX_3 = {
    "parabolic": (203.99, 2.55),
    "cubic": (307.20, 1.92),
    "cosine": (252.66, 2.01),
    "sine": (321.70, 2.56),
    "poly5": (295.59, 2.40),
    "poly7": (384.55, 2.80),
}


def _moves(problem, spm):
    from strokeopt.report.motion import kinematics_summary

    return kinematics_summary(problem, problem.stroke(spm), spm)["moves"]


def _tolerance(key, move, published):
    if key == "v_max_m_s" and move == 3:
        # thesis Tab. 4.2/4.8 print 0.54 / 0.64 m/s for move 3, but the same tables' pulley
        # speed (2291 deg/s at PD 26.74 mm) means 0.5346 m/s: the printed value is off in its
        # last digit. Tolerance: one unit of that digit.
        return 0.01
    return REL * published


@pytest.mark.parametrize("key", list(TAB_4_2))
@pytest.mark.parametrize("move", [1, 2, 3])
def test_tab_4_2(reference, key, move):  # thesis Tab. 4.2
    published = TAB_4_2[key][move - 1]
    ours = _moves(reference, 500)[move - 1][key]
    assert ours == pytest.approx(published, abs=_tolerance(key, move, published))


@pytest.mark.parametrize("key", list(TAB_4_8))
@pytest.mark.parametrize("move", [1, 2, 3])
def test_tab_4_8(reference, key, move):  # thesis Tab. 4.8
    published = TAB_4_8[key][move - 1]
    ours = _moves(reference, 600)[move - 1][key]
    assert ours == pytest.approx(published, abs=_tolerance(key, move, published))


def test_tab_4_2_pulley_speed_implies_move_3_bar_speed(reference):
    # thesis Tab. 4.2: 2291 deg/s * r(26.74 mm) = 0.5346 m/s — the bar speed we test move 3 against at 1 %
    implied = 2291 * math.pi / 180 * reference.transmission.radius
    assert _moves(reference, 500)[2]["v_max_m_s"] == pytest.approx(implied, rel=REL)


@pytest.mark.parametrize("law", list(APPENDIX_3))
def test_appendix_3(reference_path, law):  # thesis appendix 3
    problem = load_problem(reference_path, ["timing.interval_times=nominal"]).with_law(make_law(law))
    move1 = _moves(problem, 500)[0]
    assert move1["time_s"] == pytest.approx(37.4 / 1500)
    a_pub, v_pub = APPENDIX_3[law]
    assert move1["a_max_m_s2"] == pytest.approx(a_pub, rel=REL)
    assert move1["v_max_m_s"] == pytest.approx(v_pub, rel=REL)
    # the thesis sampled its curves: its peaks sit at or below the exact ones
    assert move1["a_max_m_s2"] >= a_pub * (1 - 1e-3)
