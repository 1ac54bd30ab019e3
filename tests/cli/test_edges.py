"""Trust at the edges: options validated like file fields, argument errors as JSON under --json, a screw no
torque can drive, a design file of another problem or with a stroke that does not join its dwells."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from strokeopt.cli.main import main

PROBLEMS = Path(__file__).resolve().parents[2] / "problems"
REFERENCE = PROBLEMS / "deco2000_needle_bar.toml"
KNITTING = PROBLEMS / "knitting_stitch_density.toml"


def _one_line(capsys, argv, code=2) -> str:
    assert main(argv) == code
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "Traceback" not in err[0]
    return err[0]


@pytest.mark.parametrize("option, words", [
    # before: a traceback (inf), "highest rate 0 spm" (1e9), searched accuracies the file would refuse
    (["--resolution", "inf"], "--resolution: must lie in [0.1, 500] spm"),
    (["--resolution", "1e9"], "--resolution: must lie in [0.1, 500] spm"),
    (["--accuracies", "1e-12"], "--accuracies: every accuracy must lie in [0.0001, 100] mm"),
    (["--accuracies", "0.1,1e12"], "--accuracies: every accuracy must lie in [0.0001, 100] mm"),
])
def test_tradeoff_options_have_ranges(capsys, option, words):
    assert words in _one_line(capsys, ["tradeoff", str(REFERENCE), "--plot", "none", *option])


@pytest.mark.parametrize("argv", [
    ["tradeoff", str(REFERENCE), "--resolution", "abc", "--json"],
    ["solve", "--json"],
    ["simulate", str(REFERENCE), "--json", "--spm"],
])
def test_argument_errors_under_json_print_the_failure_object(capsys, argv):
    with pytest.raises(SystemExit) as exc:
        main(argv)
    out, err = capsys.readouterr()
    data = json.loads(out)
    assert exc.value.code == 2 and data["status"] == "bad input" and data["message"] and data["message"] in err
    # one line, as without --json (the whole usage was printed before it)
    assert len(err.strip().splitlines()) == 1 and "usage:" not in err and "--help" in err


def test_a_screw_no_torque_can_drive_is_refused(capsys):
    # before: lead 100 mm with friction 0.5 reported a negative screw torque (-93 N cm raising a 42 N load)
    line = _one_line(capsys, ["kinematics", str(KNITTING), "--set", "transmission.lead_mm=100", "--set",
                              "transmission.thread_friction=0.5", "--plot", "none"])
    assert "transmission.lead_mm" in line and "74.2 deg" in line and "101.6 deg" in line and "no torque" in line


@pytest.fixture(scope="module")
def knitting_design(tmp_path_factory):
    out = tmp_path_factory.mktemp("knit")
    assert main(["solve", str(KNITTING), "--objective", "min_time", "--out", str(out), "--plot", "none",
                 "--json"]) == 0
    return out / "design.json"


def test_a_design_of_another_problem_is_refused(capsys, knitting_design, tmp_path):
    # before: the knitting drive's stepper put on the needle bar's belt, a 32 mm move with v_max 0.0
    line = _one_line(capsys, ["kinematics", str(REFERENCE), "--design", str(knitting_design), "--plot", "none"])
    assert "transmission" in line and "screw_lever" in line and "a design of another problem" in line
    data = json.loads(knitting_design.read_text(encoding="utf-8"))
    data.pop("transmission")  # a file of the first schema: the timing still tells them apart
    old = tmp_path / "old.json"
    old.write_text(json.dumps(data), encoding="utf-8")
    line = _one_line(capsys, ["kinematics", str(REFERENCE), "--design", str(old), "--plot", "none"])
    assert "intervals" in line and "4 intervals" in line


@pytest.mark.parametrize("edit, field, words", [
    (lambda d: d["intervals"][1].update(position_mm=d["intervals"][1]["position_mm"] + 99), "intervals[2]",
     "starts at"),
    (lambda d: d["moves"][0].update(direction="down" if d["moves"][0]["direction"] == "up" else "up"), "moves[1]",
     "does not join its dwells"),
])
def test_a_stroke_that_does_not_join_up_is_refused(capsys, knitting_design, tmp_path, edit, field, words):
    # before: re-simulated and reported "verified"
    data = json.loads(knitting_design.read_text(encoding="utf-8"))
    edit(data)
    bad = tmp_path / "bad.json"
    bad.write_text(json.dumps(data), encoding="utf-8")
    line = _one_line(capsys, ["verify", str(bad), "--plot", "none"])
    assert field in line and words in line


def test_report_of_a_design_file_refuses_an_objective(capsys, knitting_design, tmp_path):
    # before: --objective was ignored without a word
    line = _one_line(capsys, ["report", str(KNITTING), "--design", str(knitting_design), "--objective",
                              "min_peak_torque", "--out", str(tmp_path / "r.html")])
    assert "--objective" in line and "omit one of them" in line
