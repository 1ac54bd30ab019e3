"""The servo loop of a drive without a belt: the loom's sley through a planetary gearbox (problems/
loom_beatup_servo.toml), its elastic mode the gearbox's torsion at the load, reported in the load's unit (deg).
The two-mass plant is the belt's with the ratio 1/i for the pulley radius, the sley's inertia for the bar's mass
and the torsional stiffness for the belt's: its mode and its static wind-up are checked against the formulas."""

from __future__ import annotations

import json
import math
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

from strokeopt import ProblemError, load_problem
from strokeopt.cli.main import main
from strokeopt.servo.accuracy import accuracy_report
from strokeopt.servo.plant import axis_from_problem

LOOM = Path(__file__).resolve().parents[2] / "problems" / "loom_beatup_servo.toml"
ARCMIN = math.pi / 10800


def test_the_gearbox_axis_is_the_two_mass_plant_with_the_ratio_and_torsion():
    problem = load_problem(LOOM)
    axis = axis_from_problem(problem)
    k = 150.0 / ARCMIN                                    # the file: 150 N m/arcmin at the sley
    j_motor = (50.0 + 4.0) * 1e-4                         # AC-servo-140-20's rotor + the gearbox on the motor shaft
    assert (axis.radius, axis.mass, axis.belt_stiffness) == pytest.approx((1 / 16, 1.3165, k))
    assert axis.motor_inertia == pytest.approx(j_motor) and axis.rotary and axis.compliance == "gearbox"
    f = math.sqrt(k * (1 / 1.3165 + (1 / 16) ** 2 / j_motor)) / (2 * math.pi)   # two masses on a torsion spring
    assert axis.resonance_hz == pytest.approx(f, rel=1e-12)
    assert f == pytest.approx(139.2, abs=0.1)


def test_accuracy_of_the_sley_in_deg_and_its_wind_up_under_the_beat_up():
    report, result = accuracy_report(load_problem(LOOM))
    assert report["status"] == "ok" and report["position_unit"] == "deg" and report["requirement_deg"] == 0.1
    assert "handover_error_mm" not in report and "belt_stiffness_N_per_mm" not in report
    assert report["handover_error_deg"] == pytest.approx(math.degrees(result.handover_error))
    # one encoder count at the sley: a turn of the motor over 16384 counts, over the ratio 16
    assert report["encoder_count_at_load_arcsec"] == pytest.approx(360 * 3600 / 16384 / 16)
    # the beat-up's 576.2 N m (165078 N m/rad x 0.2 deg) winds the gearbox up by T/k = 0.0640 deg: the loop holds the
    # motor, not the sley, so the forces' part of the error at the beat-up is that wind-up, plus the overshoot of the
    # torsional mode the force's ramp excites (less than 15 %)
    static = 165078.0 * math.radians(0.2) / (150.0 / ARCMIN)
    forces = -math.radians(report["signed_contributions_deg"]["belt_stretch_forces"])
    assert forces == pytest.approx(static, rel=0.05)
    assert math.degrees(static) == pytest.approx(0.0640, abs=1e-4)


def test_a_handover_at_the_cycle_end_is_judged_over_the_window_at_the_cycle_start():
    """The beat-up ends the cycle (360 deg): its window (10 deg) continues at the cycle's start. The handover
    error is the largest |error| over the samples within the window after the move's end, taken modulo the
    cycle, plus one count; a window of 0.5 deg sees less of it (it was the same number whatever the window,
    read at the grid's last point only)."""
    problem = load_problem(LOOM)
    _, result = accuracy_report(problem)
    since = (result.t - result.handover_time) % result.period
    inside = since <= 10.0 / 360.0 * result.period
    assert inside.sum() > 10 and result.t[inside].min() < 0.1 * result.period   # samples at the cycle's start
    assert result.handover_error == pytest.approx(np.max(np.abs(result.error[inside])) + result.quantisation,
                                                  rel=1e-12)
    _, short = accuracy_report(problem.with_overrides(["servo.handover_window_deg=0.5"]))
    assert short.handover_error < result.handover_error


def test_accuracy_command_on_the_gearbox(capsys):
    assert main(["accuracy", str(LOOM), "--plot", "none", "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["drive"]["transmission"] == "gearbox" and out["torsional_stiffness_N_m_arcmin"] == 150.0
    assert main(["accuracy", str(LOOM), "--plot", "none"]) == 0
    text = capsys.readouterr().out
    assert "gearbox wind-up" in text and "torsional mode 139 Hz" in text and " mm" not in text.split("servo loop")[1]


@pytest.mark.parametrize("override, field, words", [
    ("servo.belt_span_mm=100", "servo.belt_span_mm", "is for a drive with a belt; the transmission is a gearbox"),
    ("servo.torsional_stiffness_N_m_arcmin=0", "servo.torsional_stiffness_N_m_arcmin", "plausible range"),
    ("design.handover_accuracy_mm=0.5", "design.handover_accuracy_mm", "state its accuracy as handover_accuracy_deg"),
])
def test_servo_fields_of_another_drive_are_refused(override, field, words):
    with pytest.raises(ProblemError) as err:
        load_problem(LOOM, [override])
    assert err.value.field == field and words in err.value.message


def test_a_belt_drive_refuses_torsion_and_a_gearbox_needs_it(reference):
    with pytest.raises(ProblemError) as err:
        reference.with_overrides(["servo.torsional_stiffness_N_m_arcmin=100"])
    assert err.value.field == "servo.torsional_stiffness_N_m_arcmin" and "without a belt" in err.value.message
    problem = load_problem(LOOM)
    bare = replace(problem, servo=replace(problem.servo, torsional_stiffness=None))   # no stiffness stated
    with pytest.raises(ProblemError) as err:
        axis_from_problem(bare)
    assert err.value.field == "servo.torsional_stiffness_N_m_arcmin" and "data sheet" in err.value.message


def test_a_crank_s_servo_model_is_rigid():
    # a crank's ratio changes with its position: its servo model is the rigid drive's own dynamics
    # (servo/varying.py, tests/servo/test_varying.py); a torsional stiffness through it is refused naming the field
    crank = load_problem(LOOM.parent / "deco2000_crank_slider.toml")
    with pytest.raises(ProblemError) as err:
        axis_from_problem(replace(crank, servo=replace(crank.servo, torsional_stiffness=1e5)))
    assert err.value.field == "servo.torsional_stiffness_N_m_arcmin" and "is rigid" in err.value.message
    assert axis_from_problem(crank).compliance == "rigid" and crank.error_terms == ()


@pytest.mark.slow
def test_the_sley_design_holds_its_accuracy_in_deg():
    """`strokeopt solve` of the servo sley: the handover term in the design (rad inside), its row and verdict in
    deg, the known objective unchanged (min_rms_torque 13.98 N m with AC-servo-140-20: the accuracy does not bind)."""
    from strokeopt import solve_verified

    v = solve_verified(load_problem(LOOM))
    row = next(c for c in v.design.checks if c["name"].startswith("handover accuracy"))
    assert row["unit"] == "deg" and row["limit"] == pytest.approx(0.1) and row["ok"]
    # the design's term (the same simulation at instants of the window) agrees with the full simulation
    assert row["design_term"] == pytest.approx(row["value"], rel=5e-3)
    assert row["value"] == pytest.approx(math.degrees(v.accuracy.handover_error), rel=1e-9)
    assert v.design.motor == "AC-servo-140-20" and v.design.objective_value == pytest.approx(13.98, abs=0.01)
    assert "deg <= 0.1 deg" in v.verdict and "mm" not in v.verdict
