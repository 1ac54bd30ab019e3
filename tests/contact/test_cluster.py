"""The rigid cluster (contact/cluster.py): contact forces derived from [model] alone, checked against the
full simulation."""

from __future__ import annotations

import numpy as np
import pytest

from strokeopt import load_problem, simulate_scene
from strokeopt.contact.cluster import build_cluster
from strokeopt.contact.simulate import SimulationOptions


@pytest.fixture(scope="module")
def problem(reference_path):
    return load_problem(reference_path)


def test_cluster_of_the_release_scene(problem):
    cl = build_cluster(problem.scenes["release"])
    # closed at rest: c21 (control on the shell) and c31 (cage on the shell); c32, c13 have gaps
    assert cl.joins == {"control": ("c21", "shell"), "cage": ("c31", "shell")}
    # the control member's subtree meets its stop (pad, gap H = 23 mm) when the shell is 23 mm down
    assert cl.closing_positions("c21") == [("pad", pytest.approx(0.023), 1.0)]
    # at rest: the preloads of k2 (900 N/m x 17.1 mm) minus k3 (690 N/m x 15.8 mm), sources A.6
    assert float(cl.contact_force("c21", 0.0, 0.0, 0.0)) == pytest.approx(900 * 17.1e-3 - 690 * 15.8e-3, rel=1e-12)


def test_contact_force_equals_the_full_simulation_while_closed(problem):
    # 250 spm, modified sine: the control member follows the shell (lag from ~340 spm, thesis ch. 6). The
    # simulation's penalty contact (1e9 N/m) turns 1 nm of integration error into 1 N: tight tolerances. From 10 deg
    # on: the bodies start at rest with unloaded contacts, a transient that dies out in the first dwell (A.6).
    sc = problem.scenes["release"]
    cl = build_cluster(sc)
    r = simulate_scene(problem, "release", 250, options=SimulationOptions(rtol=1e-8, atol=1e-9))
    d = sc.driven
    derived = cl.contact_force("c21", r.positions[d], r.velocities[d], r.accelerations[d])
    closed = cl.holds("c21", r.positions[d]) & (r.t < r.metrics["impact_angle_deg"] * r.period / 360) & (r.angle_deg > 10)
    assert closed.sum() > 500 and not r.metrics["lag"]
    sim = r.forces["c21"][closed]
    assert np.max(np.abs(derived[closed] - sim) / np.abs(derived[closed])) < 0.01
    assert derived[closed].min() < 0.5 * derived[closed].max()  # the force does vary over the move


def test_contact_force_symbolic_equals_numeric(problem):
    import casadi as ca

    cl = build_cluster(problem.scenes["release"])
    x, v, a, k = (ca.MX.sym(n) for n in "xvak")
    fn = ca.Function("f", [x, v, a, k], [cl.contact_force("c21", x, v, a, stiffness={"k2": k})])
    assert float(fn(0.01, 1.0, 50.0, 900.0)) == pytest.approx(float(cl.contact_force("c21", 0.01, 1.0, 50.0)))
    # a stiffer k2 with the same installed length: the preload grows with it
    assert float(fn(0.0, 0, 0, 1800.0)) - float(fn(0.0, 0, 0, 900.0)) == pytest.approx(900 * 17.1e-3)
