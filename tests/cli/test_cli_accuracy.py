"""`strokeopt accuracy` (and its bad input), as a user and a script see it."""

from __future__ import annotations

import json

import pytest

from strokeopt.cli.main import main
from strokeopt.cli.parser import build_parser
from strokeopt.files.design_file import write_design


def test_accuracy_json_and_plot(capsys, reference_path, tmp_path):
    fig = tmp_path / "acc.png"
    assert main(["accuracy", str(reference_path), "--spm", "600", "--json", "--plot", str(fig)]) == 0
    out, err = capsys.readouterr()
    data = json.loads(out)  # stdout is only JSON
    assert data["spm"] == 600
    assert set(data["contributions_mm"]) == {"servo_tracking", "belt_stretch", "encoder_quantisation"}
    # digest A.5: measured 0.076 mm at 600 spm; the same order is predicted
    assert 0.02 <= data["handover_error_mm"] <= 0.3
    assert data["motor"] == "055U2B30" and data["torque_limited"] is False
    assert fig.stat().st_size > 10_000 and str(fig) in err


def test_accuracy_text_with_law_comparison(capsys, reference_path):
    assert main(["accuracy", str(reference_path), "--compare-laws", "--plot", "none"]) == 0
    out = capsys.readouterr().out
    assert "handover error" in out and "servo tracking" in out and "belt stretch" in out
    assert "encoder quantisation" in out and "symmetric optimum" in out
    for law in ("parabolic", "cubic", "cosine", "modified_sine", "sine", "poly5", "poly7"):
        assert law in out


def test_accuracy_says_its_torque_is_the_servo_command_not_sizes(capsys, reference_path):
    # `size` checks the rigid-load peak; accuracy/tradeoff the servo's torque command: both stated, and they differ
    assert main(["size", str(reference_path), "--spm", "600", "--motor", "055U2B30", "--pulley-teeth", "28",
                 "--json", "--plot", "none"]) == 0
    rigid = json.loads(capsys.readouterr().out)["candidates"][0]["peak_torque_N_m"]
    assert main(["accuracy", str(reference_path), "--spm", "600", "--json", "--plot", "none"]) == 0
    data = json.loads(capsys.readouterr().out)
    assert "torque command" in data["torque_basis"] and "strokeopt size" in data["torque_basis"]
    assert abs(data["peak_torque_command_N_m"] - rigid) > 1e-3 * rigid
    assert main(["accuracy", str(reference_path), "--spm", "600", "--plot", "none"]) == 0
    lines = [ln for ln in capsys.readouterr().out.splitlines() if "rigid-load" in ln]
    assert len(lines) == 1 and "torque command" in lines[0]


def test_accuracy_law_option(capsys, reference_path):
    assert main(["accuracy", str(reference_path), "--law", "poly7", "--json", "--plot", "none"]) == 0
    data = json.loads(capsys.readouterr().out)
    assert data["label"] == "poly7" and data["handover_error_mm"] > 0


def test_help_teaches(capsys):
    with pytest.raises(SystemExit):
        build_parser().parse_args(["accuracy", "--help"])
    text = capsys.readouterr().out
    assert "servo tracking" in text and "Example: strokeopt accuracy" in text


@pytest.mark.parametrize("edit, field, words", [
    (lambda t: t.replace('tuning = "symmetric_optimum"', 'tuning = "manual"\nposition_gain_1_s = 0\n'
                         'speed_gain_N_m_s_rad = 0.01\nspeed_integral_time_ms = 10'),
     "servo.position_gain_1_s", "plausible range (0, 100000]"),
    (lambda t: t.replace('tuning = "symmetric_optimum"', 'tuning = "manual"\nposition_gain_1_s = 50\n'
                         'speed_gain_N_m_s_rad = -0.01\nspeed_integral_time_ms = 10'),
     "servo.speed_gain_N_m_s_rad", "plausible range (0, 10000]"),
    (lambda t: t.replace('tuning = "symmetric_optimum"', 'tuning = "manual"\nposition_gain_1_s = 50'),
     "servo.speed_gain_N_m_s_rad", "required"),
    (lambda t: t.replace("position_sampling_us = 250 ", "position_sampling_us = 20000 "),
     "servo.position_sampling_us", "shortest move"),
    (lambda t: t.replace("control_cycle_us = 500 ", "control_cycle_us = 15000 "),
     "servo.control_cycle_us", "shortest move"),
    (lambda t: t.replace("belt_span_mm = 139.5 ", "belt_span_mm = 0 "), "servo.belt_span_mm", "plausible range [1, 20000]"),
    (lambda t: t.replace("belt_damping_ratio = 0.05", "belt_damping_ration = 0.05"),
     "servo.belt_damping_ration", "did you mean"),
    (lambda t: t.replace('tuning = "symmetric_optimum"', 'tuning = "symmetric_optimum"\nposition_gain_1_s = 80'),
     "servo.position_gain_1_s", "only used with"),
])
def test_bad_servo_input_exits_2(capsys, write_problem, edit, field, words):
    path = write_problem(edit)
    assert main(["accuracy", str(path), "--plot", "none"]) == 2
    err = capsys.readouterr().err
    assert str(path) in err and field in err and words in err
    assert "Traceback" not in err and len(err.strip().splitlines()) == 1


def test_bad_gain_from_the_command_line_exits_2(capsys, reference_path):
    assert main(["accuracy", str(reference_path), "--set", "servo.speed_bandwidth_Hz=-5", "--plot", "none"]) == 2
    err = capsys.readouterr().err
    assert "servo.speed_bandwidth_Hz" in err and "(value from --set)" in err


def test_sampling_longer_than_the_move_at_a_higher_spm(capsys, write_problem):
    # 5 ms sampling is shorter than every move at 500 spm (move 3: 9.6 ms) but not at 1200 spm
    path = write_problem(lambda t: t.replace("position_sampling_us = 250 ", "position_sampling_us = 5000 "))
    assert main(["accuracy", str(path), "--spm", "1200", "--plot", "none"]) == 2
    assert "servo.position_sampling_us" in capsys.readouterr().err


# --------------------------------------------------------------------------- strokeopt tradeoff


def test_tradeoff_classic_json_and_plot(capsys, reference_path, tmp_path):
    fig = tmp_path / "trade.png"
    assert main(["tradeoff", str(reference_path), "--strokes", "classic", "--accuracies", "0.06,0.5",
                 "--resolution", "100", "--json", "--plot", str(fig)]) == 0
    out, err = capsys.readouterr()
    data = json.loads(out)
    pts = data["points"]
    assert [p["accuracy_mm"] for p in pts] == pytest.approx([0.06, 0.5])
    assert all(p["stroke"] == "modified_sine" and p["binding"] for p in pts)
    assert pts[0]["max_spm"] <= pts[1]["max_spm"]  # a looser accuracy never costs stitch rate
    assert pts[0]["binding"] == "handover_accuracy"
    # the rate above that the simulation rejected, with its error: beyond the accuracy, within a resolution step
    first = pts[0]
    assert first["max_spm"] < first["failed_spm"] <= first["max_spm"] + 100 + 1e-9
    assert first["failed_error_mm"] > 0.06 and first["failed_reason"].startswith("handover accuracy")
    assert first["handover_error_mm"] <= 0.06
    assert fig.stat().st_size > 10_000
    assert "torque command" in data["torque_basis"]


@pytest.mark.parametrize("args, words", [
    (["--accuracies", "0.1,abc"], "--accuracies"),
    (["--accuracies", "0.1,-0.2"], "every accuracy must lie in [0.0001, 100] mm"),
    (["--resolution", "0"], "--resolution"),
    (["--starts", "0"], "--starts: expected a whole number of starts per accuracy in 1..12, got '0'"),
    (["--starts", "13"], "--starts: expected a whole number of starts per accuracy in 1..12"),
    (["--starts", "two"], "--starts: expected a whole number"),
    (["--starts", "3"], "--starts: is for the optimal stroke"),  # with --strokes classic (below)
    (["--accuracies", ""], "--accuracies: expected comma-separated millimetres"),  # not the default list, silently
    (["--accuracies", "0.1,0.05,0.1"], "--accuracies: 0.1 mm given twice"),
])
def test_tradeoff_bad_options_exit_2(capsys, reference_path, args, words):
    assert main(["tradeoff", str(reference_path), "--strokes", "classic", "--plot", "none", *args]) == 2
    err = capsys.readouterr().err
    assert words in err and "Traceback" not in err


@pytest.mark.parametrize("args, words", [
    (["--resolution", "abc"], "argument --resolution: invalid float value: 'abc'"),
    (["--strokes", "foo"], "argument --strokes: invalid choice: 'foo'"),
])
def test_tradeoff_options_argparse_refuses_are_one_line_too(capsys, reference_path, args, words):
    with pytest.raises(SystemExit) as exc:
        main(["tradeoff", str(reference_path), "--plot", "none", *args])
    err = capsys.readouterr().err.strip()
    assert exc.value.code == 2 and words in err and "(see strokeopt tradeoff --help)" in err
    assert len(err.splitlines()) == 1 and "usage:" not in err


@pytest.mark.slow
def test_accuracy_with_an_optimal_design(capsys, reference, reference_path, tmp_path):
    # the residual vibration of the optimal stroke next to the classic laws (issue scope 3)
    from dataclasses import replace

    from strokeopt.design.transcription.settings import DesignSettings
    from strokeopt.design.solve import solve_design

    settings = replace(reference.design or DesignSettings(), motor_choice="fixed", pulley="fixed", mesh_intervals=20)
    design = solve_design(reference, spm=600, settings=settings)
    write_design(design, tmp_path)
    path = tmp_path / "design.json"
    assert main(["accuracy", str(reference_path), "--design", str(path), "--json", "--plot", "none"]) == 0
    data = json.loads(capsys.readouterr().out)
    assert data["spm"] == 600 and len(data["laws"]) == 9  # the 8 compared laws and the optimum
    optimal = data["laws"][-1]
    assert optimal["law"].startswith("optimal") and 0 < optimal["handover_error_mm"] < 0.5
    # the optimum holds its acceleration continuous at the dwells: it rings the belt less than every law whose
    # acceleration jumps there (test_servo.py: those excite the belt mode most)
    jumps = [r["residual_vibration_mm"] for r in data["laws"] if r["law"].split(" ")[0] in ("parabolic", "cubic", "cosine")]
    assert len(jumps) == 3 and optimal["residual_vibration_mm"] < min(jumps)
    # a design solved at another rate is refused, naming the file
    assert main(["accuracy", str(reference_path), "--design", str(path), "--spm", "500", "--plot", "none"]) == 2
    assert str(path) in capsys.readouterr().err


@pytest.mark.slow
def test_accuracy_uses_the_drive_of_the_design(capsys, reference_path, tmp_path):
    # a design solved on a 22-tooth pulley is checked on that pulley and its motor, not the file's 28 teeth
    from dataclasses import replace

    from strokeopt.design.transcription.settings import DesignSettings
    from strokeopt.design.solve import solve_design
    from strokeopt.files.design_file import read_design
    from strokeopt.files.problem_file import load_problem
    from strokeopt.servo.accuracy import handover_accuracy

    z22 = load_problem(reference_path, ["transmission.pulley_teeth=22"])
    settings = replace(z22.design or DesignSettings(), motor_choice="fixed", pulley="fixed", mesh_intervals=20)
    write_design(solve_design(z22, spm=600, settings=settings), tmp_path)
    path = tmp_path / "design.json"
    assert main(["accuracy", str(reference_path), "--design", str(path), "--json", "--plot", "none"]) == 0
    data = json.loads(capsys.readouterr().out)
    assert data["drive"]["pulley_teeth"] == 22 and data["drive"]["from"] == f"the design file {path}"
    # the whole report is of the design's stroke, not of the problem's law
    assert data["label"].startswith("optimal") and data["handover_error_mm"] > 0
    assert data["drive"]["motor"] == data["motor"] == z22.drive.motor
    assert data["pulley_pitch_diameter_mm"] == pytest.approx(22 * 3 / 3.141592653589793, rel=1e-3)  # GT3: 3 mm pitch
    # the optimal row is the design's stroke on the design's drive
    _, stroke = read_design(path)
    direct = handover_accuracy(z22, stroke, 600)
    assert data["laws"][-1]["handover_error_mm"] == pytest.approx(direct.handover_error * 1e3, rel=1e-6)
    assert data["handover_error_mm"] == pytest.approx(direct.handover_error * 1e3, rel=1e-6)
    # the text says which drive it used and why solve's own check can be smaller
    assert main(["accuracy", str(reference_path), "--design", str(path), "--plot", "none"]) == 0
    out = capsys.readouterr().out
    assert "pulley 22 teeth (from the design file" in out and "end of the handover move" in out
    # forcing another pulley or motor than the design's is refused, not mixed
    for forced in ("transmission.pulley_teeth=28", "drive.motor=055U2C30"):
        assert main(["accuracy", str(reference_path), "--design", str(path), "--set", forced, "--plot", "none"]) == 2
        err = capsys.readouterr().err
        assert str(path) in err and forced in err and "Traceback" not in err
