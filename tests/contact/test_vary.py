"""`strokeopt simulate --vary`: a scene over the values of numbers of the problem (studies/vary.py, issue 38).

The thesis's chapter-7 question (seed digest A): moving the impact point (gap N smaller and the pad's gap H larger
by the same amount) lowers the impact velocity, until gap N closes before the impact and the needle is released
too early.
"""

from __future__ import annotations

import json

import pytest

from strokeopt import load_problem
from strokeopt.cli.main import main
from strokeopt.studies.runner import StudyRunner
from strokeopt.studies.vary import parse_vary, vary_scene

IMPACT_POINT = ["--vary", "model.contacts.c32.gap_mm-=3:5:1", "--vary", "model.contacts.pad.gap_mm+=3:5:1"]


@pytest.fixture(scope="module")
def problem(reference_path):
    return load_problem(reference_path, ["machine.spm=600"])


def test_the_impact_point_moved_until_the_needle_is_released_too_early(reference_path, capsys, tmp_path):
    args = ["simulate", str(reference_path), "--spm", "600", "--workers", "1", "--plot", str(tmp_path / "v.png")]
    assert main(args + IMPACT_POINT) == 0
    out = capsys.readouterr().out
    # gap N 7.4 - 3..5 mm, the pad's gap 23 + 3..5 mm: premature release at a 5 mm shift only
    assert "premature release from model.contacts.c32.gap_mm and model.contacts.pad.gap_mm = 2.4, 28" in out
    assert (tmp_path / "v.png").stat().st_size > 10_000
    assert main(args + IMPACT_POINT + ["--json"]) == 0
    data = json.loads(capsys.readouterr().out)
    assert data["status"] == "ok" and data["spm"] == 600
    assert [v["field"] for v in data["varied"]] == ["model.contacts.c32.gap_mm", "model.contacts.pad.gap_mm"]
    assert data["varied"][0]["values"] == pytest.approx([4.4, 3.4, 2.4])
    assert data["varied"][1]["values"] == pytest.approx([26.0, 27.0, 28.0])
    rows = data["rows"]
    assert [r["premature_release"] for r in rows] == [False, False, True]
    assert rows[2]["min_gap_N_mm"] < 1e-3 < rows[1]["min_gap_N_mm"]
    # the impact slows as the stop moves away from the shell's path (the pad met later on the move)
    speeds = [r["impact_velocity_m_s"] for r in rows]
    assert speeds[0] > speeds[1] > speeds[2]


def test_each_step_is_the_problem_with_its_set_texts(problem):
    varies = parse_vary(["model.springs.k2.stiffness_N_m=900:1500:600"], problem)
    rows = vary_scene(problem, "release", 600, varies, runner=StudyRunner(1))
    from strokeopt import simulate_scene

    stiff = simulate_scene(problem.with_overrides(["model.springs.k2.stiffness_N_m=1500.0"]), "release", 600)
    assert rows[1]["impact_velocity_m_s"] == stiff.metrics["impact_velocity_m_s"]
    assert rows[1]["impact_velocity_m_s"] != rows[0]["impact_velocity_m_s"]


@pytest.mark.parametrize("vary, words", [
    (["model.contacts.c32.gap_mm"], "expected FIELD=START:STOP:STEP"),
    (["model.contacts.c99.gap_mm=1:2:1"], "model.contacts.c99.gap_mm: no such field"),
    (["model.contacts.c32.gap_mm=a:b:c"], "expected VALUE or START:STOP:STEP"),
    (["model.contacts.c32.gap_mm=nan"], "every number must be finite"),
    (["model.contacts.c32.gap_mm=-5:0:1"], "at step 1 (model.contacts.c32.gap_mm = -5) the problem refuses it"),
    # gap N alone 3 mm smaller: the stroke would drive the shell, cage and control member into the frame (a
    # coupled move with the pad's gap keeps their sum)
    (["model.contacts.c32.gap_mm-=0:8:1"], "at step 4 (model.contacts.c32.gap_mm = 4.4) the problem refuses it: "
                                           "'move 1' takes the driven shell 32 mm"),
    (["model.contacts.c32.gap_mm=1:2:0.5", "model.contacts.pad.gap_mm=1:2:1"], "need as many values each"),
    (["model.contacts.c32.gap_mm=1", "model.contacts.c32.gap_mm=2"], "names a field twice"),
    (["problem.name=1"], "is 'DECO 2000 upper needle bar', not a number"),
    # the rate is the run's: a step cannot change it (each row would be simulated at --spm all the same)
    (["machine.spm=500:700:100"], "machine.spm: the rate is the run's: sweep it with --spm START:STOP:STEP"),
    (["model.springs.k2.damping_N_s_m*=1:2:0.5"], "FIELD+=..., FIELD-=... shift the file's value; no other operator"),
])
def test_bad_vary_is_refused_naming_the_field(reference_path, capsys, vary, words):
    args = ["simulate", str(reference_path), "--plot", "none"]
    for v in vary:
        args += ["--vary", v]
    assert main(args) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "--vary" in err and words in err, err


def test_vary_runs_one_scene_at_one_rate(reference_path, capsys):
    base = ["simulate", str(reference_path), "--plot", "none", "--vary", "model.contacts.c32.gap_mm=6:7:1"]
    assert main(base + ["--spm", "500:600:100"]) == 2
    assert "give --spm one rate, not a sweep" in capsys.readouterr().err
    assert main(base + ["--study", "tolerance"]) == 2
    assert "omit --study" in capsys.readouterr().err


@pytest.mark.slow  # starts a LocalCluster of two workers
def test_the_same_rows_on_two_workers(problem):
    varies = parse_vary(["model.contacts.c32.gap_mm=6:7:0.5"], problem)
    here = vary_scene(problem, "release", 600, varies, runner=StudyRunner(1))
    there = vary_scene(problem, "release", 600, varies, runner=StudyRunner(2))
    for a, b in zip(here, there):
        assert a["varied"] == b["varied"]
        assert a["impact_velocity_m_s"] == b["impact_velocity_m_s"] and a["min_gap_N_mm"] == b["min_gap_N_mm"]


def test_a_designs_stroke_over_the_values(reference_path, reference_written, capsys):
    args = ["simulate", str(reference_path), "--design", str(reference_written.design_json), "--plot", "none",
            "--json", "--workers", "1", "--vary", "model.springs.k2.stiffness_N_m=900:1200:300"]
    assert main(args) == 0
    rows = json.loads(capsys.readouterr().out)["rows"]
    assert all(r["stroke"].startswith("optimal") for r in rows)  # the design's stroke, not the file's law
    assert rows[0]["impact_velocity_m_s"] != rows[1]["impact_velocity_m_s"]


def test_an_element_of_a_force_laws_coefficients(reference_path, capsys):
    # the pad's law F = c1 x + c3 x^3: its linear coefficient c1 (element 2 of coefficients_SI, 1-based as --set)
    args = ["simulate", str(reference_path), "--spm", "600", "--plot", "none", "--json", "--workers", "1",
            "--vary", "model.force_laws.pad_65ShA.coefficients_SI[2]=3e5:6e5:3e5"]
    assert main(args) == 0
    rows = json.loads(capsys.readouterr().out)["rows"]
    assert rows[0]["peak_pad_force_N"] < rows[1]["peak_pad_force_N"]  # a stiffer pad pushes back harder
    # the element is checked as the file checks the law: c_0 (element 1) must stay 0
    assert main(args[:-1] + ["model.force_laws.pad_65ShA.coefficients_SI[1]=1:2:1"]) == 2
    assert "c_0 must be 0" in capsys.readouterr().err
