"""Verifying a design by re-simulation (contact/verify.py): the same results as simulating its stroke directly."""

from __future__ import annotations

import pytest

from strokeopt import load_problem, simulate_scene
from strokeopt.contact.verify import verify
from strokeopt.files.design_file import DesignStroke, load_design, write_design

KEYS = ("impact_velocity_m_s", "impact_angle_deg", "lag_end_angle_deg", "min_gap_N_mm", "release_angle_deg")


@pytest.fixture(scope="module")
def problem(reference_path):
    return load_problem(reference_path)


def test_verify_a_law_stroke_is_simulate_scene(problem):
    stroke = problem.stroke(600)
    r = verify(DesignStroke(problem, stroke, 600.0), "release")
    direct = simulate_scene(problem, "release", 600, stroke=stroke)
    assert r.spm == 600 and r.stroke_label == stroke.label
    for key in KEYS:
        assert r.metrics[key] == direct.metrics[key], key  # the same computation, bit for bit


def test_load_design_errors(tmp_path):
    from strokeopt import ProblemError

    bad = tmp_path / "design.json"
    bad.write_text('{"format": "strokeopt-design"}')
    with pytest.raises(ProblemError, match="missing"):
        load_design(bad)
    with pytest.raises(ProblemError, match="no such file"):
        load_design(tmp_path / "none.json")


@pytest.mark.slow  # solves a design (collocation, a few seconds)
def test_verify_a_solved_design_and_its_file(problem, tmp_path):
    from strokeopt.design.solve import solve_design

    design = solve_design(problem, objective="min_jerk", spm=600)
    r = verify(design, "release")
    direct = simulate_scene(problem, "release", 600, stroke=design.stroke)
    assert r.stroke_label.startswith("optimal") and r.spm == 600
    for key in KEYS:
        assert r.metrics[key] == direct.metrics[key], key
    # the design.json route (strokeopt verify) rebuilds the same stroke on the same problem
    path = write_design(design, tmp_path)[0]
    loaded = load_design(path)
    assert loaded.spm == 600 and loaded.objective == "min_jerk" and loaded.source == str(path)
    again = verify(loaded, "release")
    for key in KEYS:
        assert again.metrics[key] == pytest.approx(r.metrics[key], rel=1e-6, abs=1e-6), key
