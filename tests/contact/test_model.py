"""The contact model as data: the needle bar of sources A.6 read from the reference problem, and bad input."""

from __future__ import annotations

import casadi as ca
import pytest

from strokeopt import ForceLaw, ProblemError, load_problem
from conftest import stated_k2
from strokeopt.cli.main import main


def test_needle_bar_bodies_and_masses(reference):
    # sources A.6 body table (thesis ch. 5)
    m = reference.model
    masses_g = {name: b.mass * 1e3 for name, b in m.bodies.items()}
    assert masses_g == pytest.approx({"shell": 81.7, "control": 41.9, "cage": 4.3, "roller": 0.6, "needle": 0.2,
                                      "other_roller": 0.6}, rel=1e-12)
    assert m.driven == "shell"
    assert sum(b.driven for b in m.bodies.values()) == 1


def test_springs_preloads_and_damping(reference):
    # sources A.6: k2 900 N/m (89 / 71.9 mm), k3 690 (29.2 / 13.4), k4 1680 (11.2 / 9.4), k6 1680 without preload
    s = reference.model.springs
    assert {k: (e.stiffness, e.preload * 1e3) for k, e in s.items()} == {
        "k2": (900.0, pytest.approx(17.1)), "k3": (690.0, pytest.approx(15.8)), "k4": (1680.0, pytest.approx(1.8)),
        "k6": (1680.0, 0.0)}
    assert [s[k].damping for k in ("k2", "k3", "k4", "k6")] == [13.15, 3.32, 5.0, 5.0]
    assert all(e.kind == "spring" for e in s.values())
    assert s["k6"].bodies == ("other_roller", "frame")


def test_contacts_gaps_and_grip(reference):
    # sources A.6 gaps: H 23, N 7.4 (model file), P 3.6, R 1.1, U 24.3, M 1 mm; contacts 1e9 N/m, grip 1e6 N/m
    c = reference.model.contacts
    gaps = {k: e.gap * 1e3 for k, e in c.items() if e.kind == "contact"}
    assert gaps == pytest.approx({"pad": 23.0, "c21": 0.0, "c32": 7.4, "c13": 3.6, "c31": 0.0, "c14": 1.1,
                                  "c45": 0.0, "c56": 24.3})
    assert all(e.stiffness == 1e9 and e.damping == 100.0 for k, e in c.items() if k not in ("pad", "c35"))
    grip = c["c35"]
    assert grip.kind == "grip" and grip.stiffness == 1e6
    assert grip.acts_while[:2] == ("cage", "shell") and grip.acts_while[2] == pytest.approx(1e-3)
    assert grip.body_names == {"cage", "needle", "shell"}
    assert c["pad"].damping == 28.5 and c["pad"].force_law is not None


def test_pad_force_law_eq_4_32(reference):
    # thesis eq. 4.32: F20 = 1.5739e12 x^3 + 4.4517e5 x [N, x in m]
    pad = reference.model.contacts["pad"]
    for x in (1e-4, 1e-3, 2.5e-3):
        assert pad.elastic_force(x) == pytest.approx(1.5739e12 * x**3 + 4.4517e5 * x, rel=1e-12)
    law = ForceLaw("cubic", (0.0, 2.0, 0.0, 3.0))
    xs = ca.SX.sym("x")
    assert float(ca.Function("f", [xs], [law(xs)])(0.5)) == pytest.approx(2 * 0.5 + 3 * 0.125)


def test_event_roles(reference):
    ev = reference.model.events
    assert (ev.impact, ev.follower, ev.gap, ev.release) == ("pad", "control", "c32", "c35")


def test_override_reaches_the_model(reference_path):
    p = load_problem(reference_path, ["model.springs.k2.stiffness_N_m=1240", "model.contacts.c32.gap_mm=6.5"])
    assert p.model.springs["k2"].stiffness == 1240.0
    assert p.model.contacts["c32"].gap == pytest.approx(6.5e-3)


@pytest.mark.parametrize("override, field, words", [
    ("model.bodies.control.mass_g=-41.9", "model.bodies.control.mass_g", "plausible range [0.001, 1e+07]"),
    ("model.bodies.cage.driven=true", "model.bodies", "exactly one body must be driven"),
    ("model.bodies.shell.driven=false", "model.bodies", "none is"),
    ('model.springs.k2.bodies=["shell", "ghost"]', "model.springs.k2.bodies", "unknown body 'ghost'"),
    ('model.springs.k2.bodies=["shell", "shell"]', "model.springs.k2.bodies", "two different bodies"),
    ('model.springs.k2.bodies=["shell"]', "model.springs.k2.bodies", "exactly 2"),
    ("model.springs.k2.installed_length_mm=95.0", "model.springs.k2.installed_length_mm", "longer than the free"),
    ("model.contacts.pad.force_law=\"pad_50ShA\"", "model.contacts.pad.force_law", "unknown force law"),
    ("model.contacts.c32.gap_mm=-1.0", "model.contacts.c32.gap_mm", "plausible range [0, 10000]"),
    ("model.contacts.c32.stifness_N_m=1.0", "model.contacts.c32.stifness_N_m", "did you mean 'stiffness_N_m'"),
    ("model.contacts.c21.kind=\"spring\"", "model.contacts.c21.kind", "not one of contact, grip"),
    ('model.contacts.c35.acts_while=["cage", "nobody"]', "model.contacts.c35.acts_while", "unknown body"),
    ("model.force_laws.pad_65ShA.coefficients_SI=[1.0, 2.0]", "model.force_laws.pad_65ShA.coefficients_SI", "c_0 must be 0"),
    ("model.events.release=\"c32\"", "model.events.release", "expected a grip"),
])
def test_bad_model_input_names_the_field(reference_path, override, field, words):
    with pytest.raises(ProblemError) as exc:
        load_problem(reference_path, [override])
    assert exc.value.field == field
    assert words in exc.value.message


def test_force_law_and_stiffness_exclusive(write_problem):
    path = write_problem(lambda t: t.replace('force_law = "pad_65ShA"', 'force_law = "pad_65ShA"\nstiffness_N_m = 1e9'))
    with pytest.raises(ProblemError, match="either stiffness_N_m or force_law"):
        load_problem(path)


def test_problem_without_model_still_loads(write_problem):
    path = write_problem(lambda t: stated_k2(t).split("# ---------------------------------------------------------------"
                                                      "------------ dynamic model")[0])
    p = load_problem(path)
    assert p.model is None and p.scenes is None


@pytest.mark.parametrize("override", ["model.bodies.control.mass_g=-41.9", "model.bodies.cage.driven=true",
                                      'model.springs.k2.bodies=["shell", "ghost"]'])
def test_cli_bad_model_exit_2(capsys, reference_path, override):
    assert main(["simulate", str(reference_path), "--set", override, "--plot", "none"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "model." in err and "Traceback" not in err
