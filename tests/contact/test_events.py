"""Event roles and metric names as data (contact/events.py), and the shared integration core."""

from __future__ import annotations

import dataclasses

import pytest

from strokeopt import load_problem, simulate_scene
from strokeopt.contact.events import METRIC_KEYS, METRICS, ROLE_KINDS, EventRoles


@pytest.fixture(scope="module")
def problem(reference_path):
    return load_problem(reference_path)


def test_roles_table_matches_the_roles(reference):
    assert tuple(ROLE_KINDS) == tuple(f.name for f in dataclasses.fields(EventRoles))
    assert {mt.role for mt in METRICS} - {None} <= set(ROLE_KINDS)
    roles = reference.model.events
    for role, kinds in ROLE_KINDS.items():
        name = getattr(roles, role)
        kind = "body" if name in reference.model.bodies else reference.model.elements[name].kind
        assert kind in kinds


def test_metrics_are_the_declared_ones_in_order(problem):
    m = simulate_scene(problem, "release", 600).metrics
    assert tuple(m) == METRIC_KEYS
    assert m["peak_pad_force_N"] == m["peak_contact_forces_N"][problem.model.events.impact]


def test_metrics_of_a_scene_without_the_roles(problem):
    # only the driven body: every role-bound metric keeps its default
    from dataclasses import replace

    from strokeopt import make_scene

    only = replace(problem, scenes={"shell": make_scene(problem.model, "shell", ["shell"], [])})
    m = simulate_scene(only, "shell", 600).metrics
    assert tuple(m) == METRIC_KEYS
    for mt in METRICS:
        if mt.role is not None:
            assert m[mt.key] == mt.default, mt.key


@pytest.mark.slow  # scipy Radau on the release scene, a few seconds
def test_scipy_stepper_shares_the_core(problem):
    # the bench's scipy reference runs through the same core: same grid, same metrics to the tolerances
    from strokeopt.bench.contact import simulate_scene_scipy

    ref = simulate_scene(problem, "release", 600)
    peer = simulate_scene_scipy(problem, "release", 600, rtol=1e-4, atol=1e-5)
    assert peer.options.method == "scipy-Radau"
    assert peer.stats["n_output"] == ref.stats["n_output"]
    assert tuple(peer.metrics) == METRIC_KEYS
    assert peer.metrics["impact_velocity_m_s"] == pytest.approx(ref.metrics["impact_velocity_m_s"], abs=2e-3)
    assert peer.metrics["release_angle_deg"] == pytest.approx(ref.metrics["release_angle_deg"], abs=0.05)
