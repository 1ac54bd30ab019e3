"""The linkage benchmarks' reference (bench/linkage.py): the plain numpy/scipy fsolve loop solves the same loom
six-bar as strokeopt's kinematics, so the timing ratio compares like with like (issue 24: `strokeopt bench`)."""

from __future__ import annotations

import numpy as np

from strokeopt.bench import registry
from strokeopt.bench.linkage import loom_fsolve_cycle
from strokeopt.bench.run import run_benchmarks  # noqa: F401  (registers every benchmark)
from strokeopt.linkage.files import load_linkage_file
from strokeopt.linkage.kinematics import kinematics_of


def test_fsolve_reference_agrees_with_the_kinematics():
    problem = load_linkage_file(registry.reference_problem_path("loom_beatup_sixbar.toml"))
    kin = kinematics_of(problem.linkage)
    cycle = kin.solve(720)
    y, d1, d2, _ = kin.output(cycle, "sley_angle")
    angle, r1, r2, _ = loom_fsolve_cycle(problem.linkage)
    y = np.unwrap(y)
    assert np.abs((y - y[0]) - (angle - angle[0])).max() < 1e-9  # the same positions (an offset: the reference)
    assert np.abs(d1 - r1).max() < 1e-3 * np.abs(d1).max()       # central differences on a 0.5 deg grid
    assert np.abs(d2 - r2).max() < 1e-3 * np.abs(d2).max()
    assert {"linkage_cycle", "linkage_synthesis"} <= set(registry.REGISTRY)
