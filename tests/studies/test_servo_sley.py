"""A sley driven directly by a servo (issue 24 item 5): a rotary load through a gearbox, positions in deg.

Known optimum (seed digest C: sley swing 19.5 deg, 200 rpm, I0 = 13.42 kgf cm s^2 = 1.3165 kg m^2): a
rest-to-rest swing of h = 19.5 deg in T = 0.130 s (156 deg of crank at 200 rpm) with ratio 1, no rotor
inertia (1e-10 kg m^2, the catalogue's least) and no beat-up force: min_peak_accel gives the parabolic law,
eps_max = 4 h / T^2 = 80.6 rad/s^2, and min_peak_torque I0 eps_max = 106.0 N m; the modified sine
(chi = 0.125, C_a = 5.528) 146.6 N m."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from strokeopt import load_problem
from strokeopt.design.solve import solve_design
from strokeopt.drive.load import load_torque
from strokeopt.drive.transmission import Gearbox
from strokeopt.errors import ProblemError
from strokeopt.motion.laws import make_law

SERVO_FILE = Path(__file__).resolve().parents[2] / "problems" / "loom_beatup_servo.toml"

I0 = 13.42 * 9.80665 * 1e-2  # digest C: 13.42 kgf cm s^2 = 1.31605 kg m^2 (the digest: 1.3165, within 0.05 %)

PROBLEM = """
[problem]
name = "servo sley, known optimum"

[machine]
spm = 200
cam_revolutions_per_stitch = 1

[motion]
law = "parabolic"

[timing]
start_position_deg = 0

[[timing.intervals]]
name = "back"
span_deg = 156
stroke_deg = 19.5
direction = "up"

[[timing.intervals]]
name = "rear dwell"
span_deg = 48

[[timing.intervals]]
name = "forward"
span_deg = 156
stroke_deg = 19.5
direction = "down"

[transmission]
type = "gearbox"
ratio = 1

[drive]
motor = "no-rotor"
catalogues = ["motor.toml"]
moving_inertia_kg_m2 = 1.3165
max_inertia_ratio = 1000

[design]
objective = "{objective}"
rest_order = 1
motor_choice = "fixed"
"""

MOTOR = """
[[motor]]
name = "no-rotor"
source = "test: a rotor of 1e-10 kg m^2, nothing beside the sley's 1.3165"
rated_speed_rpm = 3000
rated_torque_N_m = 1000
stall_torque_N_m = 1000
peak_torque_N_m = 3000
rotor_inertia_kg_cm2 = 1e-6
"""


def _problem(tmp_path, objective="min_peak_torque", text=PROBLEM):
    (tmp_path / "motor.toml").write_text(MOTOR, encoding="utf-8")
    path = tmp_path / "sley.toml"
    path.write_text(text.replace("{objective}", objective), encoding="utf-8")
    return load_problem(path)


def test_units_and_gearbox(tmp_path):
    problem = _problem(tmp_path)
    assert problem.timing.rotary and isinstance(problem.transmission, Gearbox)
    move = problem.timing.moves[0]
    assert move.stroke == pytest.approx(math.radians(19.5), rel=1e-12)
    assert problem.drive.load.moving_mass == 1.3165 and problem.drive.load.gravity == 0.0
    # digest C: I0 = 13.42 kgf cm s^2 = 1.3165 kg m^2 (0.1 %)
    assert I0 == pytest.approx(1.3165, rel=1e-3)
    g = Gearbox(16.0)
    x, mu, nu = g.transfer(np.array([0.0, 32.0]))
    assert x[1] == pytest.approx(2.0) and np.allclose(mu, 1 / 16) and np.allclose(nu, 0.0)


@pytest.mark.parametrize("objective", ["min_peak_accel", "min_peak_torque"])
def test_known_optimum(tmp_path, objective):
    # digest C: 19.5 deg in 0.130 s: eps_max = 4 h / T^2 = 80.6 rad/s^2, I0 eps_max = 106.0 N m
    problem = _problem(tmp_path, objective)
    assert problem.timing.schedule(200).duration[0] == pytest.approx(0.130)
    design = solve_design(problem)
    h, T = math.radians(19.5), 0.130
    assert 4 * h / T**2 == pytest.approx(80.6, rel=1e-3)
    for move in design.moves:
        assert move.a_max == pytest.approx(80.6, rel=0.01)
    if objective == "min_peak_torque":
        assert design.objective_value == pytest.approx(106.0, rel=0.01)


def test_modified_sine(tmp_path):
    # digest C with the modified sine (chi = 0.125): 146.6 N m
    problem = _problem(tmp_path).with_law(make_law("modified_sine"))
    kin = problem.stroke().sample(20001)
    terms = load_torque(problem.drive.catalogue().motors["no-rotor"], problem.transmission, problem.drive.load,
                        kin.s, kin.v, kin.a)
    assert float(np.max(np.abs(terms.total))) == pytest.approx(146.6, rel=0.01)


@pytest.mark.parametrize("edit, field, words", [
    (lambda t: t.replace("start_position_deg = 0", "start_position_deg = 0\nstart_position_mm = 0"),
     "timing.start_position_deg", "one unit"),
    (lambda t: t.replace('type = "gearbox"\nratio = 1', 'pulley_teeth = 28'), "transmission.type", "deg"),
    (lambda t: t.replace("moving_inertia_kg_m2", "moving_mass_kg"), "drive.moving_mass_kg", "moving_inertia_kg_m2"),
    (lambda t: t.replace("[drive]\n", '[drive]\nbelt = "GT3-3MR-09"\n'), "drive.belt", "gearbox"),
    (lambda t: t.replace("[drive]\n", '[drive]\ngravity = "down"\n'), "drive.gravity", ""),
])
def test_refusals(tmp_path, edit, field, words):
    with pytest.raises(ProblemError) as err:
        _problem(tmp_path, text=edit(PROBLEM))
    assert err.value.field == field and words in err.value.message


def test_linkage_against_servo():
    # issue 24 item 5: the loom's six-bar against its sley on a servo (docs/loom-servo.md); one gearbox and
    # two motors of the catalogue entries: the 8 N m servo cannot hold the beat-up through i = 16 (576.2 / 16 =
    # 36.0 N m > 24 N m), the 20 N m servo can
    from pathlib import Path

    from strokeopt.linkage.files import load_linkage_file
    from strokeopt.studies.linkage_servo import compare_linkage_servo, load_gearboxes

    root = Path(__file__).resolve().parents[2] / "problems"
    servo = load_problem(root / "loom_beatup_servo.toml")
    assert servo.timing.rotary and servo.transmission.ratio == 16.0
    gearboxes = [g for g in load_gearboxes() if g.name == "planetary-160-i16"]
    result = compare_linkage_servo(load_linkage_file(root / "loom_beatup_sixbar.toml"), servo, gearboxes,
                                   motors=["AC-servo-100-8", "AC-servo-140-20"])
    small, chosen = result.candidates
    assert not small.feasible and "static load torque" in small.reason and small.design is None
    assert result.chosen is chosen and chosen.motor == "AC-servo-140-20"
    n = chosen.numbers
    assert n["peak_torque_N_m"] == pytest.approx(1961.3 * 0.2938 / 16, rel=0.01)  # the beat-up held at the front
    assert n["swing_deg"] == pytest.approx(19.5, abs=1e-6)
    assert n["rear_dwell_deg"] >= result.linkage.rear_dwell["length_deg"] == pytest.approx(64.5)
    rows = {r["quantity"]: r for r in result.table()}
    assert rows["peak torque (crank / motor)"]["linkage"] == pytest.approx(19.31, abs=0.01)  # docs/linkages.md
    assert rows["peak sley acceleration"]["linkage"] == pytest.approx(89.6, abs=0.1)


def test_hybrid_crank_speed():
    # issue 24 item 5, the hybrid: the linkage kept, its crank on a servo at non-uniform speed (docs/loom-servo.md);
    # the peak torque reported is checked between the points the NLP holds
    from pathlib import Path

    from strokeopt.linkage.files import load_linkage_file
    from strokeopt.studies.linkage_servo import hybrid_crank_speed, linkage_side

    lp = load_linkage_file(Path(__file__).resolve().parents[2] / "problems" / "loom_beatup_sixbar.toml")
    lk = linkage_side(lp)
    dwell0 = lk.rear_dwell["length_deg"] / 360 * 0.3  # 64.5 deg of crank at 200 rpm: 53.75 ms
    peak0 = float(np.abs(lk.torque).max())
    low = hybrid_crank_speed(lp, dwell_time_min_s=dwell0).numbers()
    assert low["dwell_time_ms"] >= dwell0 * 1e3 - 1e-6 and low["peak_torque_N_m"] < 0.6 * peak0
    long = hybrid_crank_speed(lp, peak_torque_max_N_m=peak0).numbers()
    assert long["peak_torque_N_m"] <= peak0 * (1 + 1e-6) and long["dwell_time_ms"] > 2.5 * dwell0 * 1e3


def test_the_servo_problem_names_its_shipped_catalogue(tmp_path, monkeypatch):
    # the servo file names the loom servos by the shipped catalogue's name (not a path into src/): a copy of the
    # file, read from another directory, finds them; a name that is neither a file nor a shipped catalogue is
    # refused naming the shipped ones
    import shutil
    from pathlib import Path

    from strokeopt.drive.catalogue import shipped_catalogue_file

    copy = tmp_path / "elsewhere" / "loom_beatup_servo.toml"
    copy.parent.mkdir()
    shutil.copy(Path(__file__).resolve().parents[2] / "problems" / "loom_beatup_servo.toml", copy)
    other = tmp_path / "cwd"
    other.mkdir()
    monkeypatch.chdir(other)
    problem = load_problem(copy)
    assert list(problem.drive.catalogue_files) == [str(shipped_catalogue_file("loom_servos.toml"))]
    assert "AC-servo-140-20" in problem.drive.catalogue().motors
    bad = copy.read_text().replace('catalogues = ["loom_servos.toml"]', 'catalogues = ["loom_servo.toml"]')
    copy.write_text(bad)
    with pytest.raises(ProblemError) as err:
        load_problem(copy)
    assert err.value.field == "drive.catalogues" and "loom_servos.toml" in err.value.message


def test_a_rotary_design_file_and_report_say_deg_and_rad(tmp_path, capsys):
    # a rotary load's design.json, solve --json and report: positions in deg and speeds in rad/s under keys that
    # say so (before: stroke_mm holding rad x 1e3); the file reads back to the same stroke, as does one written
    # before (mm-named keys): io/load_units.py
    import json
    import re

    from strokeopt.cli.main import main
    from strokeopt.files.design_file import read_design
    from strokeopt.io.load_units import from_load_units

    _problem(tmp_path, "min_peak_accel")
    out = tmp_path / "out"
    # exit 1: the test motor's rotor of 1e-10 kg m^2 breaks the inertia ratio; the files are written all the same
    assert main(["solve", str(tmp_path / "sley.toml"), "--out", str(out), "--json", "--plot", "none"]) == 1
    summary = json.loads(capsys.readouterr().out)
    text = (out / "design.json").read_text()
    for data in (summary, json.loads(text)):
        move = data["moves"][0]
        assert move["stroke_deg"] == pytest.approx(19.5, abs=1e-9) and move["a_max_rad_s2"] == pytest.approx(80.6,
                                                                                                               rel=0.01)
        assert "v_max_rad_s" in move and "jerk_max_rad_s3" in move
    assert not re.search(r'"(stroke|start_position|position)_mm"|"(v_max|velocity)_m_s"|_m_s[23]"', text)
    data = json.loads(text)
    assert data["intervals"][1]["position_deg"] == pytest.approx(19.5, abs=1e-9)
    cols = data["cam_table"]["columns"]
    assert cols[1:5] == ["position_deg", "velocity_rad_s", "acceleration_rad_s2", "jerk_rad_s3"]
    assert max(row[1] for row in data["cam_table"]["rows"]) == pytest.approx(19.5, abs=1e-6)
    assert "position_deg" in (out / "cam_table.csv").read_text()
    _, stroke = read_design(out / "design.json")
    old = tmp_path / "old.json"   # the same design as a file of before: mm-named keys holding rad x 1e3
    old.write_text(json.dumps(from_load_units(data)))
    assert '"stroke_mm": 340.3' in old.read_text()
    _, stroke_old = read_design(old)
    t = np.linspace(0, stroke.period, 97)
    assert np.allclose(stroke.evaluate(t).s, stroke_old.evaluate(t).s, atol=1e-12)
    assert stroke.evaluate(t).s.max() == pytest.approx(math.radians(19.5), rel=1e-9)
    # the report: the tables say deg and rad/s, the tagged numbers are the JSON's
    html = (out / "report.html").read_text()
    assert "stroke deg" in html and "a_max rad/s2" in html and "start position deg" in html
    assert "stroke mm" not in html and "a_max m/s2" not in html and "v_max m/s" not in html
    tag = re.search(r'data-key="moves\[0\]\.stroke_deg" data-value="([^"]+)"', html)
    assert tag and float(tag.group(1)) == summary["moves"][0]["stroke_deg"]


def test_kinematics_and_size_json_of_a_rotary_load_say_their_units(capsys):
    # before: kinematics --json gave stroke_mm = 340.34 for a 19.5 deg stroke; size --json moving_mass_kg = 1.3165
    # (kg m^2), contact_position_mm = 3.49 and stiffness_N_m = 165078 (N m/rad) for the beat-up
    import json

    from strokeopt.cli.main import main

    assert main(["kinematics", str(SERVO_FILE), "--json", "--plot", "none"]) == 0
    text = capsys.readouterr().out
    assert json.loads(text)["moves"][0]["stroke_deg"] == pytest.approx(19.5) and "stroke_mm" not in text
    main(["size", str(SERVO_FILE), "--json", "--plot", "none"])
    inputs = json.loads(capsys.readouterr().out)["inputs"]
    force = inputs["load_forces"][0]
    assert inputs["moving_inertia_kg_m2"] == 1.3165 and "moving_mass_kg" not in inputs
    assert (force["torque_N_m"], force["stiffness_N_m_rad"], force["contact_position_deg"]) == pytest.approx(
        (0.0, 165078.0, 0.2))
