"""The second machine (seed digest B): the stepper-driven stitch-density drive of a knitting machine.

The same pipeline as the needle bar -- problem file, stroke, transmission, actuator -- with a screw and
lever (a position-dependent transmission, transfer functions by AD) and a stepper motor checked against
its pull-out torque-speed curve. Paper = the conference paper of seed digest B.
"""

from __future__ import annotations

import json
import math
from pathlib import Path

import casadi as ca
import numpy as np
import pytest

from strokeopt import ScrewLever, load_problem, make_law
from strokeopt.cli.main import main
from strokeopt.drive.load import Load, Member, load_torque
from strokeopt.drive.sizing import size_drive
from strokeopt.report.motion import kinematics_summary

KNITTING = Path(__file__).resolve().parents[1] / "problems" / "knitting_stitch_density.toml"


@pytest.fixture(scope="module")
def knitting():
    return load_problem(KNITTING)


def test_the_problem_file_states_the_papers_drive(knitting):
    tr = knitting.transmission
    assert isinstance(tr, ScrewLever) and (tr.lead, tr.R0, tr.R0P) == (2e-3, 15e-3, 25e-3)  # paper, digest B
    step = knitting.timing.moves[0]
    assert step.stroke == pytest.approx(4e-4) and knitting.timing.schedule(knitting.spm).duration[0] == pytest.approx(6e-3)
    assert knitting.pulley_teeth is None


def test_nut_speed_and_step_rate_of_the_paper(knitting):
    # paper, digest B: the nut must reach 0.08 m/s, a step rate of 7995 Hz at 1.8 deg per step and 2 mm lead,
    # with linear velocity ramps (parabolic law) moving the cam 0.4 mm in 6 ms; within 1 %
    summary = kinematics_summary(knitting, knitting.stroke(), knitting.spm, math.radians(1.8))
    members = {m["member"]: m for m in summary["moves"][0]["members"]}
    assert members["nut"]["v_max"] == pytest.approx(0.08, rel=0.01)
    assert members["motor"]["step_rate_max_Hz"] == pytest.approx(7995, rel=0.01)
    assert members["sleeve"]["v_max"] == pytest.approx(2 * 0.4e-3 / 6e-3, rel=1e-9)  # 2h/T of the parabolic law
    assert math.isinf(members["lever"]["jerk_max"])  # the ramps' acceleration jumps


@pytest.mark.parametrize("offset_deg", [0.0, 12.0])
def test_screw_lever_transfer_functions_against_the_papers_closed_forms(offset_deg):
    # paper, digest B: mu24 = cos^2(phi4)/R0, nu24 = -2 cos^3(phi4) sin(phi4)/R0^2,
    # mu46 = R0P/cos^2(phi4P), nu46 = 2 R0P sin(phi4P)/cos^3(phi4P); by AD of the stages, to rounding
    tr = ScrewLever(2e-3, 15e-3, 25e-3, offset=math.radians(offset_deg))
    x2, phi4 = ca.SX.sym("x2"), ca.SX.sym("phi4")
    lever, sleeve = tr.lever_angle(x2), tr.sleeve_position(phi4)
    f24 = ca.Function("f24", [x2], [ca.jacobian(lever, x2), ca.jacobian(ca.jacobian(lever, x2), x2)])
    f46 = ca.Function("f46", [phi4], [ca.jacobian(sleeve, phi4), ca.jacobian(ca.jacobian(sleeve, phi4), phi4)])
    for x in np.linspace(-8e-3, 8e-3, 9):
        p4 = math.atan(x / 15e-3)
        mu24, nu24 = (float(v) for v in f24(x))
        assert mu24 == pytest.approx(math.cos(p4) ** 2 / 15e-3, rel=1e-12)
        # nu24 is d(mu24)/d(x2) = d2 phi4 / d x2^2
        assert nu24 == pytest.approx(-2 * math.cos(p4) ** 3 * math.sin(p4) / 15e-3**2, rel=1e-10, abs=1e-9)
        p4p = p4 + tr.offset
        mu46, nu46 = (float(v) for v in f46(p4))
        assert mu46 == pytest.approx(25e-3 / math.cos(p4p) ** 2, rel=1e-12)
        assert nu46 == pytest.approx(2 * 25e-3 * math.sin(p4p) / math.cos(p4p) ** 3, rel=1e-10, abs=1e-15)


def test_stage_kinematics_are_the_time_derivatives_of_the_stages():
    # a smooth move (poly5) through an offset lever: each member's speed, acceleration and jerk against
    # central differences of its position over time
    from strokeopt.motion.stroke import law_piece

    tr = ScrewLever(2e-3, 15e-3, 25e-3, offset=math.radians(20))
    piece = law_piece(0.0, 6e-3, 0.0, 3e-3, make_law("poly5"))
    t = np.linspace(0.0, 6e-3, 6001)
    kin = tr.stage_kinematics(*piece.derivatives(t))
    dt = t[1] - t[0]
    for name, (q, dq, ddq, dddq) in kin.items():
        inner = slice(2, -2)
        assert dq[inner] == pytest.approx(np.gradient(q, dt)[inner], rel=1e-4, abs=1e-6 * np.max(np.abs(dq)))
        assert ddq[inner] == pytest.approx(np.gradient(dq, dt)[inner], rel=1e-3, abs=1e-5 * np.max(np.abs(ddq)))
        assert dddq[inner] == pytest.approx(np.gradient(ddq, dt)[inner], rel=1e-2, abs=1e-3 * np.max(np.abs(dddq)))


def test_torque_demand_is_the_energy_form_with_the_position_dependent_inertia():
    # T = J(phi) phi'' + 1/2 J'(phi) phi'^2 with J = J_rotor + J_screw + m6 mu^2 + m2 mu2^2 + I4 mu4^2;
    # J from the paper's closed forms, J' by central differences: independent of load_torque's AD
    tr = ScrewLever(2e-3, 15e-3, 25e-3, offset=math.radians(25), inertia=1.2e-7)
    load = Load(0.093, 0.0, (), (Member("nut", "nut", 0.009), Member("lever", "lever", 8.2e-6)))
    phi = np.linspace(-60.0, 60.0, 7)
    omega, eps = np.full_like(phi, 250.0), np.linspace(-8e4, 8e4, 7)
    x, mu, nu = tr.transfer(phi)
    terms = load_torque(3.4e-6, tr, load, x, mu * omega, mu * eps + nu * omega**2)

    def inertia(p):
        x2 = tr.lead / (2 * math.pi) * p
        p4 = np.arctan(x2 / tr.R0)
        d4 = tr.lead / (2 * math.pi) * np.cos(p4) ** 2 / tr.R0  # mu24 of the paper times the screw's ratio
        d6 = tr.R0P / np.cos(p4 + tr.offset) ** 2 * d4
        return 3.4e-6 + 1.2e-7 + 0.093 * d6**2 + 0.009 * (tr.lead / (2 * math.pi)) ** 2 + 8.2e-6 * d4**2

    h = 1e-4
    j_prime = (inertia(phi + h) - inertia(phi - h)) / (2 * h)
    assert terms.total == pytest.approx(inertia(phi) * eps + 0.5 * j_prime * omega**2, rel=1e-6)


def test_size_answers_is_the_stepper_at_its_limit(knitting):
    sizing = size_drive(knitting)
    (c,) = sizing.candidates
    assert c.motor.name == "HY200-1713" and c.motor.source == "estimate"
    # the step rate against the curve's last point: the paper's 7995 Hz (digest B), within 1 %
    assert c.check("step_rate").value == pytest.approx(7995, rel=0.01)
    # the rotor dominates the demand: J_rotor * eps at 83 776 rad/s^2 (0.08 m/s of the nut in 3 ms, 2 mm lead)
    eps = 0.08 / 3e-3 * 2 * math.pi / 2e-3
    assert abs(c.peak_terms["rotor_inertia"]) == pytest.approx(c.motor.rotor_inertia * eps, rel=1e-3)
    assert abs(c.peak_terms["total"]) > abs(c.peak_terms["rotor_inertia"])  # screw, members and the cam add to it
    po = c.check("pull_out_torque")
    assert po.limit == pytest.approx(100 / 1.5)
    assert po.value == pytest.approx(100 * c.worst["worst_torque_N_m"] / c.worst["worst_pull_out_N_m"], rel=1e-9)
    assert c.binding == "pull_out_torque" and not c.feasible


def test_size_cli_reports_the_verdict_and_exits_1(capsys, tmp_path):
    code = main(["size", str(KNITTING), "--json"])
    report = json.loads(capsys.readouterr().out)
    assert code == 1 and report["status"] == "infeasible"
    assert report["verdict"].startswith("infeasible: HY200-1713") and "pull_out_torque" in report["verdict"]
    # a slow step the stepper can make: 60 ms instead of 6 ms (spans x 10 of a 600 ms cycle)
    slow = ["--set", "machine.spm=100"]
    assert main(["size", str(KNITTING), "--json", *slow]) == 0
    ok = json.loads(capsys.readouterr().out)
    assert ok["status"] == "ok" and ok["candidates"][0]["step_rate_Hz"] == pytest.approx(800, rel=0.01)
    png = tmp_path / "s.png"
    assert main(["size", str(KNITTING), "--plot", str(png), *slow]) == 0 and png.stat().st_size > 10_000


def _error(capsys, argv) -> str:
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1, err
    return err


def test_bad_stepper_curve_is_one_line(capsys, tmp_path):
    cat = tmp_path / "cat.toml"
    cat.write_text('[[stepper]]\nname = "X"\nstep_angle_deg = 1.8\nholding_torque_N_m = 0.3\n'
                   'rotor_inertia_kg_cm2 = 0.03\npull_out_step_rate_Hz = [100, 2000, 1000]\n'
                   'pull_out_torque_N_m = [0.2, 0.1, 0.05]\n')
    err = _error(capsys, ["size", str(KNITTING), "--catalogue", str(cat)])
    assert "stepper[1].pull_out_step_rate_Hz" in err and "increasing" in err


def test_lever_past_80_deg_is_one_line(capsys, tmp_path):
    # 6 mm of sleeve on a 1 mm arm would turn the lever to atan(6) = 80.5 deg
    err = _error(capsys, ["kinematics", str(KNITTING), "--set", "transmission.sleeve_arm_mm=1", "--set",
                          "timing.intervals[1].stroke_mm=6", "--set", "timing.intervals[3].stroke_mm=6"])
    assert "transmission.sleeve_arm_mm" in err and "80" in err


def test_unknown_member_stage_is_one_line(capsys):
    err = _error(capsys, ["size", str(KNITTING), "--set", 'drive.members[1].stage="screw"'])
    assert "drive.members[1].stage" in err and "nut, lever, sleeve" in err
