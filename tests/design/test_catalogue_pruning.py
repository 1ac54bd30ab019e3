"""The catalogue search drops the motors a rigid lower bound of the peak torque rules out, and gives the
exhaustive search's answer (design/search/bounds.py)."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from strokeopt import load_problem, solve_design
from strokeopt.cli.main import main
from dataclasses import replace

from strokeopt.design.search.bounds import (best_bound_first, cannot_win, least_peak_acceleration, near_limit,
                                            torque_lower_bound)
from strokeopt.design.search.diagnose import feasible_start
from strokeopt.design.transcription.request import DriveChoice
from strokeopt.errors import LimitError
from strokeopt.studies.sweeps import sweep_design
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


@pytest.mark.slow  # ten catalogue searches: five rates, with and without pruning; one pruned solve
def test_pruned_search_gives_the_exhaustive_answer_over_a_sweep(capsys):
    """Every rate of a sweep across the catalogue's range (the cheap rates where one motor wins at once, the
    rates near the limit where the best-bound motor fails and is checked for feasibility first, and a rate no
    motor can drive): the same motor, pulley and objective, or the same refusal, with and without pruning; and
    the command line's pruned solve at 980 spm gives the exhaustive answer there, saying what it skipped."""
    rates = [500.0, 800.0, 940.0, 980.0, 1000.0]
    rows = {}
    for prune in (True, False):
        problem = load_problem(REFERENCE, [f"design.prune_catalogue={str(prune).lower()}"])
        rows[prune] = sweep_design(problem, rates)
    for a, b in zip(rows[True], rows[False]):
        assert a["feasible"] == b["feasible"], a["spm"]
        if a["feasible"]:
            assert (a["motor"], a["pulley_teeth"]) == (b["motor"], b["pulley_teeth"]), a["spm"]
            assert a["objective_value"] == pytest.approx(b["objective_value"], rel=1e-6), a["spm"]
        else:  # the same closest motor and limit named
            assert a["reason"].split(";")[1].split("(")[0] == b["reason"].split(";")[1].split("(")[0], a["spm"]
    assert [r["feasible"] for r in rows[True]] == [True, True, True, True, False]
    assert main(["solve", str(REFERENCE), "--spm", "980", "--json", "--plot", "none"]) == 0   # prunes by default
    a, b = json.loads(capsys.readouterr().out), rows[False][rates.index(980.0)]
    assert (a["motor"], a["pulley_teeth"]) == (b["motor"], b["pulley_teeth"]) == ("055U2C30", 34)
    assert a["objective_value"] == pytest.approx(b["objective_value"], rel=1e-6)
    assert any("3 of 7 motors ruled out before solving" in n for n in a["notes"])
    # tried best bound first, the search stops where no bound left can beat the design found
    assert any("2 motors not solved" in n and "DSM4-07.34, CMP50M3000" in n for n in a["notes"])


def test_a_motor_near_its_limit_is_checked_for_feasibility_first():
    # 055U2B30 at 980 spm: its rigid bound is 94 % of its 3.6 N m limit; the relaxed problem names its RMS
    # torque (23 % over) without IPOPT proving the infeasibility of the full problem first
    problem = load_problem(REFERENCE, ["machine.spm=980", 'design.pulley="continuous"'])
    req = _request(problem, None, None, None, None, False)
    b30 = next(m for m in req.drive.motors() if m.name == "055U2B30")
    c30 = next(m for m in req.drive.motors() if m.name == "055U2C30")
    assert near_limit(req, b30) and not near_limit(req, c30)
    with pytest.raises(LimitError, match="rms_torque .* needs 1.4[0-9]+ N m, limit 1.2 N m"):
        feasible_start(replace(req, choice=DriveChoice(b30, None, req.drive.radius_bounds(),
                                                       belt_teeth=req.drive.teeth_range[1])))
    widest = req.drive.teeth_range[1]  # the belt rated as the largest pulley's, as the search rates it
    start = feasible_start(replace(req, choice=DriveChoice(c30, None, req.drive.radius_bounds(), belt_teeth=widest)))
    assert len(start) == len(req.moves)


def test_best_bound_first_orders_only_a_peak_torque_objective():
    problem = load_problem(REFERENCE, ["machine.spm=980"])
    req = _request(problem, None, None, None, None, False)
    ordered = best_bound_first(req, req.drive.motors())
    bounds = [b for _, b in ordered]
    assert bounds == sorted(bounds) and ordered[0][0].name == "055U2B30"
    rms = _request(problem, "min_rms_torque", None, None, None, False)
    smallest_first = [m for m, b in best_bound_first(rms, rms.drive.motors())]  # no bound: the smallest motor first
    assert [m.rated_torque for m in smallest_first] == sorted(m.rated_torque for m in rms.drive.motors())
    assert all(b is None for _, b in best_bound_first(rms, rms.drive.motors()))
    assert cannot_win(4.6, 4.557, 0.005) and not cannot_win(4.57, 4.557, 0.005) and not cannot_win(None, 1.0, 0.0)


@pytest.mark.slow  # a catalogue min_time
def test_designs_that_tie_keep_the_smallest_motor(capsys):
    # min_time on the reference problem is bound by the jerk bound of move 1 and the belt, not by the motor: several
    # motors reach 981.3 spm to the solver's tolerance; the search keeps the smallest (least rated torque) of them
    assert main(["solve", str(REFERENCE), "--objective", "min_time", "--json", "--plot", "none"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["spm"] == pytest.approx(981.3, abs=0.05)  # test_min_time.py: the sweep's 980 spm within 1 %
    assert (out["motor"], out["pulley_teeth"]) == ("055U2C30", 34)
