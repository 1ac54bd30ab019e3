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

KNITTING = Path(__file__).resolve().parents[2] / "problems" / "knitting_stitch_density.toml"


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


# --------------------------------------------------------------------------- the elastic chain (scene "step")

from strokeopt.contact.chain import chain_results  # noqa: E402
from strokeopt.contact.simulate import simulate_scene  # noqa: E402

LG2 = [f"model.links.{k}.log_decrement={math.log10(2)!r}" for k in ("c2", "c4", "c6")]
NO_PLAY = ["model.links.c2.clearance_mm=0", "model.links.c4.clearance_rad=0"]


def _chain(sets=(), options=None):
    problem = load_problem(KNITTING, list(sets))
    stroke = problem.stroke()
    result = simulate_scene(problem, "step", options=options)
    return result, chain_results(problem, result, stroke)


@pytest.fixture(scope="module")
def step_ln2():
    return _chain()


@pytest.fixture(scope="module")
def step_lg2():
    return _chain(LG2)


def test_the_model_is_the_papers_three_dof_chain(knitting):
    model, scene = knitting.model, knitting.scenes["step"]
    assert scene.free_bodies == ("slider", "lever_arm", "cam") and scene.riders == ("lever", "sleeve")  # x2P, phi4P, x6P
    # damping from the logarithmic decrement ln 2 with the reduced masses at phi = 0 (paper, digest B):
    # m2* = m2P + I4 mu24^2, I4* = I4P + m6 mu46^2, m6* = m6P
    m2 = 6e-3 + 28e-7 / 15e-3**2
    i4 = 54e-7 + 3e-3 * 25e-3**2
    for link, k, m in (("c2", 1e7, m2), ("c4", 1680.0, i4), ("c6", 1e7, 90e-3)):
        assert model.links[link].damping == pytest.approx(math.log(2) / math.pi * math.sqrt(k * m), rel=1e-7)


def test_cam_acceleration_exceeds_the_rigid_chain_by_half(step_ln2, step_lg2):
    # paper, digest B: the cam's acceleration exceeds the rigid-body value by more than 50 %
    for _, chain in (step_ln2, step_lg2):
        cam = next(b for b in chain["bodies"] if b["body"] == "cam")
        assert cam["rigid_peak_accel"] == pytest.approx(4 * 0.4e-3 / 6e-3**2, rel=1e-6)  # 4h/T^2 of the ramps
        assert cam["ratio"] > 1.5


def test_screw_torque_of_the_paper(step_ln2, step_lg2):
    # paper, digest B: screw torque 4.6 N cm with friction 0.15; within 35 % with the stated screw
    # (Tr 10x2, pitch diameter 9 mm: problems/knitting_stitch_density.toml), both damping readings
    for _, chain in (step_ln2, step_lg2):
        assert chain["screw"]["screw_diameter_mm"] == pytest.approx(9.0) and chain["screw"]["thread_friction"] == 0.15
        assert chain["screw"]["screw_torque_N_cm"] == pytest.approx(4.6, rel=0.35)


#: the clearances read as dead zones of V on each side of the rest position (a total play of 2 V), where the
#: problem file takes V as the total play (half each side): the paper's eqs. 6-7 are not in the digest
PLAY_EACH_SIDE = ["model.links.c2.clearance_mm=0.02", "model.links.c4.clearance_rad=2e-5"]


def _f6_by_direction(sets=()):
    """Peak |F6| [N] of the step up (lifting, the first half of the test cycle) and of the step back (descending)."""
    result, _ = _chain(sets)
    t, f = np.asarray(result.t), np.abs(np.asarray(result.forces["c6"]))
    half = t < 0.5 * t[-1]
    return float(np.max(f[half])), float(np.max(f[~half]))


def test_peak_cam_force_of_the_paper():
    # paper, digest B (Fig. 8): peak cam force F6 32 N when descending, within 30 %. F6 is the link force on the
    # cam member 6P (c6, eq. 9; with c0 = 0 it is also m6P times the cam's acceleration). Reached with the
    # paper's printed damping "lg 2 / pi" and the clearances V2 = Phi4 = 1e-5 as dead zones of V each side:
    # descending 27.8 N (13 % below), the larger peak of the cycle as in the paper. The file's readings (ln 2,
    # total play V) give 21.7 N (lifting) and 17.2 N (descending), ln 2 with V each side 21.8 N, lg 2 with
    # the total play 22.4 N: all more than 30 % below. The paper's "nearly double when lifting" is not
    # reproduced by any reading (lifting 20.5 N with this one): the model is symmetric but for the clearances.
    lifting, descending = _f6_by_direction(LG2 + PLAY_EACH_SIDE)
    assert descending == pytest.approx(32.0, rel=0.30)
    assert descending > lifting
    file_lifting, file_descending = _f6_by_direction()
    assert max(file_lifting, file_descending) == pytest.approx(21.7, rel=0.02)  # the file's readings, stated above


def test_the_lg2_reading_damps_less(step_ln2, step_lg2):
    # the paper prints "lg 2 / pi"; read as lg 2 the decrement is 0.301 instead of 0.693: 43 % of the
    # damping and larger peaks (shown, not chosen: the file uses ln 2)
    (_, ln2), (_, lg2) = step_ln2, step_lg2
    for a, b in zip(ln2["links"], lg2["links"]):
        assert b["damping"] == pytest.approx(a["damping"] * math.log10(2) / math.log(2), rel=1e-9)
    peak = lambda chain, body: next(x["elastic_peak_accel"] for x in chain["bodies"] if x["body"] == body)  # noqa: E731
    assert peak(lg2, "cam") > peak(ln2, "cam")


def test_stiff_links_without_play_are_the_rigid_chain():
    # no clearance, a smooth law (poly5), the links 100 x and 1000 x stiffer (c4 the same factor): every body
    # follows its member of the rigid chain, closer the stiffer (tolerances tight enough for 1 nm deflections)
    from strokeopt.contact.simulate import SimulationOptions

    errors = []
    for factor in (100, 1000):
        stiff = [f"model.links.c2.stiffness_N_m={1e7 * factor:g}", f"model.links.c6.stiffness_N_m={1e7 * factor:g}",
                 f"model.links.c4.stiffness_N_m_rad={1680 * factor:g}", *NO_PLAY, 'motion.law="poly5"']
        result, chain = _chain(stiff, SimulationOptions(rtol=1e-8, atol=1e-9))
        errors.append(max(abs(b["ratio"] - 1) for b in chain["bodies"]))
        kin = load_problem(KNITTING, stiff).stroke().evaluate(result.t)
        assert np.max(np.abs(result.positions["cam"] - kin.s)) < 1e-7  # 0.1 um of 0.4 mm
    assert errors[1] < 1e-3 and errors[1] < errors[0] / 5


def test_zero_and_tiny_clearance_are_continuous():
    # no chatter blow-up: a 1 nm play gives the answer of none, in a bounded number of steps
    none, c_none = _chain(NO_PLAY)
    tiny, c_tiny = _chain(["model.links.c2.clearance_mm=1e-6", "model.links.c4.clearance_rad=1e-9"])
    for a, b in zip(c_none["links"], c_tiny["links"]):
        assert b["peak_abs"] == pytest.approx(a["peak_abs"], rel=0.01)
    for a, b in zip(c_none["bodies"], c_tiny["bodies"]):
        assert b["elastic_peak_accel"] == pytest.approx(a["elastic_peak_accel"], rel=0.02)
    assert tiny.stats["nsteps"] < 10 * none.stats["nsteps"] + 20_000


def test_simulate_step_cli(capsys, tmp_path):
    png = tmp_path / "step.png"
    assert main(["simulate", str(KNITTING), "--scene", "step", "--plot", str(png)]) == 0
    out = capsys.readouterr().out
    assert "elastic chain against the rigid chain" in out and "screw torque" in out
    assert png.stat().st_size > 20_000
    assert main(["simulate", str(KNITTING), "--scene", "step", "--json"]) == 0
    report = json.loads(capsys.readouterr().out)
    assert report["status"] == "ok" and {k["link"] for k in report["chain"]["links"]} == {"c2", "c4", "c6"}


def test_negative_clearance_is_one_line(capsys):
    err = _error(capsys, ["simulate", str(KNITTING), "--scene", "step", "--set", "model.links.c2.clearance_mm=-0.01"])
    assert "model.links.c2.clearance_mm" in err


def test_bench_registers_the_elastic_step():
    from strokeopt.bench import contact  # noqa: F401  (registers the contact benchmarks)
    from strokeopt.bench.registry import REGISTRY

    assert REGISTRY["simulate_step"].target_s == 0.2  # one elastic step simulation under 0.2 s (strokeopt bench)


def test_commands_without_the_screw_lever_or_stepper_say_so(capsys):
    # `solve` designs through the screw and lever (tests/design/test_knitting_design.py); the servo accuracy models a
    # servo motor's loop (a stepper has none) through a constant ratio: the stepper is refused in one line naming the
    # motor field
    err = _error(capsys, ["accuracy", str(KNITTING)])
    assert "drive.motor" in err and "'HY200-1713' is a stepper motor" in err and "takes a servo motor" in err


def test_max_spm_is_the_shortest_step_the_stepper_makes(knitting):
    # the highest test-cycle rate under the pull-out curve: at it every check passes, one spm above the
    # pull-out check fails; the step then takes 6 ms x 1000 / max_spm
    (c,) = size_drive(knitting, find_max_spm=True).candidates
    assert c.max_spm_binding == "pull_out_torque" and 100 < c.max_spm < 1000
    assert size_drive(knitting.with_spm(c.max_spm)).candidates[0].feasible
    above = size_drive(knitting.with_spm(c.max_spm + 1)).candidates[0]
    assert not above.feasible and above.binding == "pull_out_torque"
