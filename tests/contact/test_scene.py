"""Scenes build the CasADi ODE of exactly the bodies and elements they name."""

from __future__ import annotations

import math

import numpy as np
import pytest

from strokeopt import ProblemError, load_problem, make_scene
from strokeopt.contact.simulate import _drive_reference


def _ode(problem, scene, smoothing=0.0):
    sign, s_ref = _drive_reference(problem)
    return problem.scenes[scene].build(problem.stroke(500), sign, s_ref, smoothing)


def test_scene_state_sizes(reference):
    rel, full = reference.scenes["release"], reference.scenes["handover"]
    assert rel.free_bodies == ("control", "cage") and rel.state_size == 4
    assert full.state_size == 10
    # the built ODE has no state for a body the scene does not name (no needle, body 5, in 'release')
    assert _ode(reference, "release").state_size == 4
    assert _ode(reference, "handover").state_size == 10
    assert "needle" not in rel.bodies and "needle" in full.bodies


def test_only_named_elements_are_built(reference):
    ode = _ode(reference, "release")
    assert ode.outputs.size1_out("forces") == len(reference.scenes["release"].elements) == 7
    assert ode.outputs.size1_out("acc") == 2


def test_rest_forces_are_the_preloads(reference):
    # at t = 0 everything is at x = 0: the springs push with their preload (sources A.6), no contact acts yet
    ode = _ode(reference, "release")
    out = ode.outputs(0.0, np.zeros(4), [0, 0.0, 0.01])
    forces = dict(zip(reference.scenes["release"].elements, np.asarray(out[5]).ravel()))
    assert forces["k2"] == pytest.approx(900 * 17.1e-3)
    assert forces["k3"] == pytest.approx(690 * 15.8e-3)
    assert all(forces[c] == 0 for c in ("pad", "c21", "c32", "c13", "c31"))
    acc = np.asarray(out[4]).ravel()
    # control member: +k2 preload - k3 preload over its mass; cage: +k3 preload over its mass
    assert acc == pytest.approx([(900 * 17.1e-3 - 690 * 15.8e-3) / 41.9e-3, 690 * 15.8e-3 / 4.3e-3])


def test_driven_body_follows_the_stroke(reference):
    # x_shell = 32 mm - s(t): 0 at the upper dwell, 32 mm (toward the handover) at the end of move 1
    ode = _ode(reference, "release")
    stroke = reference.stroke(500)
    k = 1  # move 1
    p = stroke.pieces[k]
    x_end = ode.outputs(1.0, np.zeros(4), [k, p.t_start, p.duration])[1]
    v_mid = ode.outputs(0.5, np.zeros(4), [k, p.t_start, p.duration])[2]
    assert float(x_end) == pytest.approx(32e-3)
    assert float(v_mid) == pytest.approx(-stroke.evaluate(p.t_start + 0.5 * p.duration).v[0])
    assert float(v_mid) > 0


def test_smoothing_adds_k_eps_ln2_at_zero_compression(reference):
    eps = 1e-7
    ode = _ode(reference, "release", smoothing=eps)
    # control member exactly at the shell: c21 has zero compression
    out = ode.outputs(0.0, np.zeros(4), [0, 0.0, 0.01])
    f = dict(zip(reference.scenes["release"].elements, np.asarray(out[5]).ravel()))
    assert f["c21"] == pytest.approx(1e9 * eps * math.log(2), rel=1e-6)


@pytest.mark.parametrize("edit, field, words", [
    (('elements = ["k2", "k3", "pad", "c21", "c32", "c13", "c31"]', 'elements = ["k2", "k3", "pad", "c99"]'),
     "scenes.release.elements", "unknown element 'c99'"),
    (('elements = ["k2", "k3", "pad", "c21", "c32", "c13", "c31"]', 'elements = ["k2", "k3", "pad", "c35"]'),
     "scenes.release.elements", "needs body 'needle'"),
    (('bodies = ["shell", "control", "cage"]', 'bodies = ["control", "cage"]'), "scenes.release.bodies",
     "must include the driven body 'shell'"),
    (('bodies = ["shell", "control", "cage"]', 'bodies = ["shell", "control", "cage", "piston"]'),
     "scenes.release.bodies", "unknown body 'piston'"),
    (('bodies = ["shell", "control", "cage"]', 'bodies = ["shell", "control", "cage"]\nbodys = []'),
     "scenes.release.bodys", "unknown field"),
])
def test_bad_scene_is_an_error(write_problem, edit, field, words):
    path = write_problem(lambda t: t.replace(*edit))
    with pytest.raises(ProblemError) as exc:
        load_problem(path)
    assert exc.value.field == field and words in exc.value.message


def test_make_scene_from_names(reference):
    sc = make_scene(reference.model, "pad only", ["shell", "control"], ["k2", "pad", "c21"])
    assert sc.state_size == 2
    with pytest.raises(ProblemError, match="needs body 'cage'"):
        make_scene(reference.model, "bad", ["shell", "control"], ["k3"])
