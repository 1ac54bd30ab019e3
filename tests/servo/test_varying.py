"""The servo loop through a transmission of varying ratio (servo/varying.py): the rigid drive's own nonlinear
dynamics under the cascade controller of servo/loop.py, simulated with CasADi's integrator."""

from __future__ import annotations

import dataclasses
import json
import math

import numpy as np
import pytest

from strokeopt import load_problem
from strokeopt.cli.main import main
from strokeopt.servo.accuracy import handover_accuracy
from strokeopt.servo.loop import Gains, loop_margins
from strokeopt.servo.plant import axis_from_problem
from strokeopt.servo.settings import settings_of
from strokeopt.servo.varying import varying_axis

from conftest import ROOT

CRANK = ROOT / "problems" / "deco2000_crank_slider.toml"


def test_on_a_constant_ratio_it_is_the_linear_loop_of_a_stiff_belt(reference):
    """The same loop, gains and feed-forwards: the nonlinear simulation of the rigid drive through the reference's
    pulley equals the linear model (servo/loop.py, exact periodic state) with the belt made 10^4 times stiffer, to
    0.2 % (without the bar's spring: the linear model holds a load force along the commanded stroke, linear between
    its samples, where the rigid drive meets the spring's jump at 9 mm where the bar is)."""
    settings = settings_of(reference)
    belt = axis_from_problem(reference, settings)
    motor = reference.drive.catalogue().motor(reference.drive.motor)
    load = dataclasses.replace(belt.load, forces=())      # gravity stays
    k = belt.belt_stiffness * 1e4
    m_red = 1 / (1 / belt.mass + belt.radius**2 / motor.rotor_inertia)
    stiff = dataclasses.replace(belt, motor_inertia=motor.rotor_inertia, belt_stiffness=k, load=load,
                                belt_damping=2 * 0.05 * math.sqrt(k * m_red))
    rigid = dataclasses.replace(varying_axis(reference, motor, belt.torque_limit), load=load)
    assert rigid.inertia_range == pytest.approx((stiff.total_inertia,) * 2, rel=1e-12)
    wc = 2 * math.pi * 80
    gains = Gains(wc / 4, stiff.total_inertia * wc, 2 / wc, wc, "the same for both")
    linear = handover_accuracy(reference, settings=settings, axis=stiff, gains=gains)
    simulated = handover_accuracy(reference, settings=settings, axis=rigid, gains=gains)
    assert simulated.handover_error == pytest.approx(linear.handover_error, rel=2e-3)
    assert np.abs(simulated.error).max() == pytest.approx(np.abs(linear.error).max(), rel=2e-3)
    assert simulated.peak_torque_command == pytest.approx(linear.peak_torque_command, rel=2e-3)


def test_the_crank_s_loop_is_tuned_for_its_inertia_range():
    """The gains by the rule on the largest inertia over the stroke, lowered until the margins hold at the least
    too; the handover error is servo tracking and one encoder count at the crank's ratio there."""
    crank = load_problem(CRANK)
    settings = settings_of(crank)
    axis = axis_from_problem(crank, settings)
    lo, hi = axis.inertia_range
    assert 1.5 < hi / lo < 3                               # the bar's mass seen through r sin(phi) + ...
    margins = loop_margins(axis, settings, handover_accuracy(crank).loop.gains)
    assert margins["gain_margin"] >= 2 and margins["modulus_margin"] >= 0.5 - 1e-3
    result = handover_accuracy(crank)
    assert result.quantisation == pytest.approx(2 * math.pi * axis.handover_ratio / settings.encoder_counts)
    # the long lower dwell (120-200 deg): the loop settles to the commanded position against the bar's spring (the
    # integral action and the load feed-forward), a thousandth of the moves' largest error
    dwell = (result.angle_deg > 120) & (result.angle_deg < 200)
    assert np.abs(result.error[dwell]).max() < 1e-3 * np.abs(result.error).max()
    assert 0 < result.handover_error < 0.05e-3               # a few um: the crank is near its dead centre there


def test_accuracy_of_the_crank_from_the_command_line(capsys):
    assert main(["accuracy", str(CRANK), "--json", "--plot", "none"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["status"] == "ok" and out["compliance"] == "rigid" and out["transmission"] == "crank_slider"
    lo, hi = out["inertia_range_kg_m2"]
    assert 0 < lo < hi and out["handover_error_mm"] == pytest.approx(
        out["contributions_mm"]["servo_tracking"] + out["contributions_mm"]["encoder_quantisation"], rel=1e-9)
    assert main(["accuracy", str(CRANK), "--plot", "none"]) == 0
    text = capsys.readouterr().out
    assert "crank and connecting rod (rigid)" in text and "belt" not in text.split("verdict")[0].lower()
