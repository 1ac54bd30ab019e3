"""The objective ``min_impact_velocity`` (issue 38): the speed with which the needle bar's control member meets its
stop, at a crossing whose time is a variable of the NLP held at the stop's position (design/transcription/pins.py
``pin_crossing``), confirmed by the contact model's simulation."""

from __future__ import annotations

import numpy as np
import pytest

from strokeopt import ProblemError, load_problem, solve_design, verify_design
from strokeopt.cli.main import main


@pytest.fixture(scope="module")
def contact_file(reference_path):
    return reference_path.parent / "deco2000_contact_design.toml"


@pytest.fixture(scope="module")
def gentlest(contact_file):
    problem = load_problem(contact_file)
    design = solve_design(problem, objective="min_impact_velocity")
    return design, verify_design(design)


def test_the_design_meets_the_stop_as_the_simulation_does(gentlest):
    design, verified = gentlest
    # 600 spm, k2 free in [900, 3000] N/m, the thesis drive: 0.78 m/s, where the modified sine meets it at 2.85 m/s
    simulated = verified.scenes["release"].metrics["impact_velocity_m_s"]
    assert design.objective_unit == "m/s"
    assert design.objective_value == pytest.approx(simulated, rel=0.02)
    assert 0.1 < design.objective_value < 1.5
    # the crossing's time is the NLP's: the stroke passes the stop's position (9 mm above the handover) at that speed
    k = design.stroke.evaluate(np.linspace(0, design.stroke.period, 200001))
    i = np.nonzero(np.diff(np.sign(k.s - 0.009)))[0][0]
    assert abs(k.v[i]) == pytest.approx(design.objective_value, rel=1e-3)
    assert verified.ok and verified.verification["status"] == "ok"


def test_the_objective_needs_a_stop_the_moves_close(reference_path, capsys):
    with pytest.raises(ProblemError, match="min_impact_velocity needs \\[design.contact\\] and a \\[model.events\\] "
                                           "impact contact"):
        solve_design(load_problem(reference_path), objective="min_impact_velocity")
    assert main(["solve", str(reference_path), "--objective", "min_impact_velocity", "--plot", "none"]) == 2
    assert "design.objective: min_impact_velocity needs" in capsys.readouterr().err
