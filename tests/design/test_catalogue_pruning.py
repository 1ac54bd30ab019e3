"""The catalogue search drops the motors a rigid lower bound of the peak torque rules out, and gives the
exhaustive search's answer (design/search/bounds.py)."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from strokeopt import load_problem, solve_design
from strokeopt.cli.main import main
from strokeopt.design.search.bounds import least_peak_acceleration, torque_lower_bound
from strokeopt.design.solve import _request

PROBLEMS = Path(__file__).resolve().parents[2] / "problems"
REFERENCE = PROBLEMS / "deco2000_needle_bar.toml"


def test_least_peak_acceleration_is_the_known_optimum():
    # docs/architecture.md known optima: 4 h/T^2 without a jerk bound; with the modified sine's jerk bound
    # (C_j = 28.0 for chi = 0.095) the jerk-bounded optimum C_a = 4.445 (problems/known_optima/
    # jerk_bounded_peak_accel.toml, tests/design/test_known_optima.py)
    assert least_peak_acceleration(1.0, 1.0, None) == pytest.approx(4.0)
    problem = load_problem(PROBLEMS / "known_optima" / "jerk_bounded_peak_accel.toml")
    (mv, _) = _request(problem, None, None, None, None, False).moves
    c_a = least_peak_acceleration(abs(mv.stroke), mv.duration, mv.jerk_bound) * mv.duration**2 / abs(mv.stroke)
    assert c_a == pytest.approx(4.445, abs=1e-3)
    assert least_peak_acceleration(1.0, 1.0, 31.9) == pytest.approx(4.0)  # no move is possible: no bound made


@pytest.mark.slow  # one fixed-motor solve per catalogue motor
def test_the_bound_is_below_every_motors_optimum():
    problem = load_problem(REFERENCE, ["machine.spm=700", 'design.pulley="continuous"'])
    req = _request(problem, None, None, None, None, False)
    for motor in req.drive.motors():
        bound, _ = torque_lower_bound(req, motor)
        fixed = problem.with_overrides([f'drive.motor="{motor.name}"', 'design.motor_choice="fixed"'])
        design = solve_design(fixed)
        assert bound <= design.check_value("peak_torque") * (1 + 1e-3), motor.name


@pytest.mark.slow  # two catalogue searches at 980 spm
def test_pruned_search_gives_the_exhaustive_answer(capsys):
    out = {}
    for prune in ("true", "false"):
        assert main(["solve", str(REFERENCE), "--spm", "980", "--set", f"design.prune_catalogue={prune}",
                     "--json", "--plot", "none"]) == 0
        out[prune] = json.loads(capsys.readouterr().out)
    a, b = out["true"], out["false"]
    assert (a["motor"], a["pulley_teeth"]) == (b["motor"], b["pulley_teeth"]) == ("055U2C30", 34)
    assert a["objective_value"] == pytest.approx(b["objective_value"], rel=1e-9)
    assert any("3 of 7 motors ruled out before solving" in n for n in a["notes"])
