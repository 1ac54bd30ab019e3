"""Input that cannot be right is refused (issue 14): every numeric field has a plausible range, the solver
options are checked against the solver, --spm rates are finite, in range and few enough, a design.json is
validated like a problem file. Each case failed before (a traceback, a null number or a silent answer) and
is now one line naming the file, the field, the value and the range, exit code 2."""

from __future__ import annotations

import json

import pytest

from strokeopt.cli.main import main
from input_cases import finite_json

FIXED = ["--set", 'design.motor_choice="fixed"', "--set", 'design.pulley="fixed"']


def _error_line(capsys, argv, code=2) -> str:
    assert main(argv) == code
    captured = capsys.readouterr()
    assert captured.err.count("\n") == 1, captured.err  # one line, no traceback
    return captured.err.strip()


#: JSON fields that may be null and are not numbers (a dwell has no direction or law), and the documented null
#: numbers (the jerk of a law whose acceleration jumps is unbounded: null).
NULLABLE = {"direction", "law", "motor", "belt", "reason", "binding", "binding_limit", "note", "jerk_max_m_s3", "C_j",
            "peak_jerk_m_s3", "jerk_m_s3",
            # events of the contact model that did not happen (contact/events.py: None where an event does not)
            "impact_velocity_m_s", "impact_angle_deg", "lag_onset_angle_deg", "lag_end_angle_deg", "min_gap_N_mm",
            "release_angle_deg", "premature_release", "gap_N_mm"}


# ---------------------------------------------------------------- silent extremes (issue 14: accepted before)

@pytest.mark.parametrize("override, field, range_text", [
    ("machine.spm=1e12", "machine.spm", "[1, 20000]"),
    ("transmission.pulley_teeth=1", "transmission.pulley_teeth", "[8, 250]"),
    ("model.bodies.cage.mass_g=1e12", "model.bodies.cage.mass_g", "[0.001, 1e+07]"),
    ("model.bodies.cage.mass_g=5e-324", "model.bodies.cage.mass_g", "[0.001, 1e+07]"),
    ("model.springs.k2.stiffness_N_m=1e300", "model.springs.k2.stiffness_N_m", "[0, 1e+12]"),
    ("model.contacts.c32.stiffness_N_m=1e300", "model.contacts.c32.stiffness_N_m", "[0, 1e+12]"),
    ("design.check_tolerance=1e12", "design.check_tolerance", "[1e-12, 1]"),
    ("drive.pulley_teeth_max=9223372036854775807", "drive.pulley_teeth_max", "[8, 250]"),
    ("design.pulley_teeth_max=9223372036854775807", "design.pulley_teeth_max", "[8, 250]"),
    ("drive.moving_mass_kg=1e12", "drive.moving_mass_kg", "[0.0001, 1000]"),
    ("model.contacts.pad.gap_mm=1e300", "model.contacts.pad.gap_mm", "[0, 10000]"),  # where the k2 load starts
    ("drive.belt_service_factor=1e-9", "drive.belt_service_factor", "[0.5, 5]"),
    ("design.handover_accuracy_mm=1e-300", "design.handover_accuracy_mm", "[0.0001, 100]"),
    ("design.jerk_max_m_s3=1e300", "design.jerk_max_m_s3", "(0, 1e+09]"),
    ("servo.encoder_counts_per_rev=9223372036854775807", "servo.encoder_counts_per_rev", "[4, 4.29497e+09]"),
    ("servo.belt_width_mm=1e-300", "servo.belt_width_mm", "[1, 1000]"),
    ("timing.intervals[2].stroke_mm=1e300", "timing.intervals[2].stroke_mm", "[0, 100000]"),
    ("timing.start_position_mm=1e300", "timing.start_position_mm", "[-100000, 100000]"),
    ("machine.cam_revolutions_per_stitch=1e308", "machine.cam_revolutions_per_stitch", "[0.01, 100]"),
])
def test_implausible_values_are_refused(capsys, reference_path, override, field, range_text):
    line = _error_line(capsys, ["kinematics", str(reference_path), "--set", override, "--plot", "none", "--json"])
    value = override.split("=", 1)[1]
    assert f"{reference_path}: {field}: " in line and "outside the plausible range " + range_text in line, line
    assert str(float(value) if "." in value or "e" in value else int(value)) in line or value in line


def test_chi_has_a_plausible_lower_bound(capsys, reference_path):
    line = _error_line(capsys, ["kinematics", str(reference_path), "--set", "motion.chi=1e-300", "--plot", "none"])
    assert "motion.chi: 1e-300 is out of range [0.001, 0.25]" in line
    line = _error_line(capsys, ["kinematics", str(reference_path), "--chi", "1e-300", "--plot", "none"])
    assert "chi: 1e-300 is out of range [0.001, 0.25]" in line


@pytest.mark.parametrize("argv, words", [
    (["kinematics", "--spm", "1e-12"], "--spm: 1e-12 spm is outside the plausible range [1, 20000]"),
    (["solve", "--spm", "400:1e9:1"], "--spm: 1e+09 spm is outside the plausible range [1, 20000]"),  # MemoryError
    (["solve", "--spm", "400:1400:0.1"], "10001 stitch rates, more than 2000"),
    (["simulate", "--spm", "400:inf:50"], "--spm: every number must be finite"),  # numpy ValueError
    (["simulate", "--spm", "nan:900:50"], "--spm: every number must be finite"),  # numpy ValueError
    (["accuracy", "--spm", "inf"], "--spm: every number must be finite"),
])
def test_stitch_rates_on_the_command_line(capsys, reference_path, argv, words):
    line = _error_line(capsys, [argv[0], str(reference_path), *argv[1:], "--plot", "none"])
    assert words in line, line


# ---------------------------------------------------------------- tracebacks before (issue 14)

@pytest.mark.parametrize("command, override, words", [
    # numpy MemoryError / array too big in the servo simulation
    ("accuracy", "machine.spm=1.0", "servo.position_sampling_us: 250 us makes 480000 samples of a 120 s cycle"),
    ("accuracy", "machine.spm=0.001", "machine.spm: 0.001 is outside the plausible range [1, 20000]"),
    ("accuracy", "machine.spm=1e-12", "machine.spm: 1e-12 is outside the plausible range [1, 20000]"),
    ("accuracy", "servo.control_cycle_us=0.001", "servo.control_cycle_us: 0.001 is outside the plausible range"),
    ("accuracy", "drive.moving_mass_kg=1e-300", "drive.moving_mass_kg: 1e-300 is outside the plausible range"),
    # ZeroDivisionError
    ("simulate", "machine.spm=5e-324", "machine.spm: 5e-324 is outside the plausible range [1, 20000]"),
    # ValueError: NaN in the report
    ("kinematics", "machine.cam_revolutions_per_stitch=1e308", "machine.cam_revolutions_per_stitch: 1e+308 is outside"),
    # a null number in the JSON after an overflow warning
    # (the reference's k2 is the model's: its load force reads preload and stiffness from [model.springs.k2])
    ("size", "model.springs.k2.stiffness_N_m=1e300", "model.springs.k2.stiffness_N_m: 1e+300 is outside the plausible"),
])
def test_former_tracebacks_and_nulls_are_one_line(capsys, reference_path, command, override, words):
    line = _error_line(capsys, [command, str(reference_path), "--set", override, "--plot", "none", "--json"])
    assert line.startswith(f"strokeopt: error: {reference_path}: ") and words in line, line


@pytest.mark.parametrize("override, words", [
    # the stitch rate and the cam revolutions per stitch together: a cycle of 6000 s, a move of 7 us
    (["machine.spm=1", "machine.cam_revolutions_per_stitch=0.01"], "a cycle of 6e+03 s, outside the plausible range"),
    (["machine.spm=20000", "machine.cam_revolutions_per_stitch=100"], "a cycle of 3e-05 s, outside the plausible range"),
    (["timing.intervals[5].span_deg=0.1", "timing.intervals[6].span_deg=84.8", 'timing.interval_times="nominal"'],
     "the shortest move lasts 66.7 us"),
])
def test_combined_quantities(capsys, reference_path, override, words):
    argv = ["kinematics", str(reference_path), "--plot", "none"]
    for o in override:
        argv += ["--set", o]
    line = _error_line(capsys, argv)
    assert ": machine.spm: " in line and words in line, line


# ---------------------------------------------------------------- solver options (tracebacks from CasADi before)

@pytest.mark.parametrize("option, field, words", [
    ("'ipopt.bogus_option' = 3", "design.solver.ipopt.bogus_option", "unknown solver option"),
    ("'ipopt.max_itr' = 3", "design.solver.ipopt.max_itr", "unknown solver option (did you mean 'ipopt.max_iter'?)"),
    ("'ipopt.max_iter' = -1", "design.solver.ipopt.max_iter", "-1 is not a valid setting (IPOPT: 0 <= (3000) < +inf"),
    ("'ipopt.max_iter' = 'abc'", "design.solver.ipopt.max_iter", "wrong type, got 'abc'"),
    ("'ipopt.tol' = -1.0", "design.solver.ipopt.tol", "-1.0 is not a valid setting (IPOPT: 0 < (1e-08) < +inf"),
    ("print_level = 5", "design.solver.print_level", "unknown solver option (did you mean 'ipopt.print_level'?)"),
    ("plugin = 'snopt'", "design.solver.plugin", "'snopt' is not a solver strokeopt can use"),
    ("expand = 'yes'", "design.solver.expand", "wrong type, got 'yes'"),
    ("'ipopt.mu_strategy' = 'fastest'", "design.solver.ipopt.mu_strategy", "'fastest' is not a valid setting"),
])
def test_solver_options_are_checked_before_any_build(capsys, write_problem, option, field, words):
    path = write_problem(lambda t: t + f"\n[design.solver]\n{option}\n")
    # kinematics builds no NLP: the options are checked when the file is read
    line = _error_line(capsys, ["kinematics", str(path), "--plot", "none"])
    assert f"{path}: {field}: " in line and words in line, line


def test_good_solver_options_are_used(capsys, write_problem):
    path = write_problem(lambda t: t + "\n[design.solver]\n'ipopt.max_iter' = 300\n'ipopt.mu_strategy' = 'adaptive'\n")
    assert main(["solve", str(path), *FIXED, "--spm", "600", "--plot", "none", "--json"]) == 0
    assert json.loads(capsys.readouterr().out)["status"] == "optimal"


# ---------------------------------------------------------------- design.json (tracebacks in verify before)

@pytest.fixture(scope="module")
def design_json(reference_written):
    """A design.json as ``solve --out`` writes it (the session's reference design, conftest.py), to damage."""
    return json.loads(reference_written.design_json.read_text())


def _truncate(d):
    d["moves"][0]["unit_solution"]["S"] = d["moves"][0]["unit_solution"]["S"][:-3]


def _empty(d):
    d["moves"][1]["unit_solution"] = {"S": [], "V": [], "A": []}


def _ragged(d):
    d["moves"][2]["unit_solution"]["A"][5] = [1.0]


def _nan_stroke(d):
    d["moves"][0]["stroke_mm"] = float("nan")


def _nan_node(d):
    d["moves"][0]["unit_solution"]["V"][3] = float("nan")


def _no_mesh(d):
    del d["mesh"]


def _string_cycle(d):
    d["cycle_time_s"] = "fast"


def _lost_move(d):
    d["moves"] = d["moves"][1:]


@pytest.mark.parametrize("damage, field, words", [
    (_truncate, "moves[1].unit_solution.S", "has shape (38,), the mesh needs (41,)"),
    (_empty, "moves[2].unit_solution.S", "has shape (0,), the mesh needs (41,)"),
    (_ragged, "moves[3].unit_solution.A", "must be an array of numbers"),
    (_nan_stroke, "moves[1].stroke_mm", "must be finite, got nan"),
    (_nan_node, "moves[1].unit_solution.V", "finite numbers only"),
    (_no_mesh, "mesh", "is required but missing"),
    (_string_cycle, "cycle_time_s", "must be a number"),
    (_lost_move, "intervals[2].kind", "no entry of moves has interval = 2"),
])
@pytest.mark.parametrize("command", ["verify", "accuracy"])
def test_a_damaged_design_file_is_refused(capsys, tmp_path, reference_path, design_json, damage, field, words,
                                          command):
    data = json.loads(json.dumps(design_json))
    damage(data)
    path = tmp_path / "design.json"
    path.write_text(json.dumps(data))
    argv = ["verify", str(path)] if command == "verify" else ["accuracy", str(reference_path), "--design", str(path)]
    line = _error_line(capsys, [*argv, "--plot", "none"])
    assert f"{path}: {field}: " in line and words in line, line


# ---------------------------------------------------------------- extreme but plausible: finite answers

@pytest.mark.parametrize("argv", [
    ["kinematics", "--spm", "1", "--set", "servo.position_sampling_us=10000", "--set", "servo.control_cycle_us=10000"],
    ["kinematics", "--spm", "4000"],
    # the knitting machine of the sources (B): 3 g to 90 g, c = 1e7 N/m, clearances 1e-5 m
    ["simulate", "--set", "model.bodies.cage.mass_g=3", "--set", "model.bodies.control.mass_g=90",
     "--set", "model.springs.k3.stiffness_N_m=1e7", "--set", "model.contacts.c13.gap_mm=0.01",
     "--set", "model.contacts.c32.gap_mm=9.0"],  # gap P 0.01 mm and gap N 9 mm: the chain to the pad fits 32 mm
    ["size", "--motor", "055U2B30", "--set", "drive.moving_mass_kg=0.003", "--set", "model.springs.k2.stiffness_N_m=1e7"],
    ["accuracy", "--set", "machine.spm=50"],
])
def test_extreme_but_plausible_inputs_give_finite_answers(capsys, reference_path, argv):
    code = main([argv[0], str(reference_path), *argv[1:], "--plot", "none", "--json"])
    out = capsys.readouterr().out
    assert code in (0, 1)
    assert finite_json(json.loads(out), NULLABLE)
