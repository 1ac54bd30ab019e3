"""Friction on the load and the transmission's efficiency (issue 33, item 2): the torque a hand calculation gives,
term by term, driving and braking; the collocation's smooth forms against the exact ones; the files' fields; and
the shortest move under a torque limit with them, a closed form."""

from __future__ import annotations

import math
from pathlib import Path

import casadi as ca
import numpy as np
import pytest

from strokeopt import Load, LoadForce, ProblemError, load_problem, load_torque
from strokeopt.design.solve import solve_design
from strokeopt.drive.transmission import BeltPulley

KNOWN = Path(__file__).resolve().parents[2] / "problems" / "known_optima"
J_ROTOR, MASS, R = 0.23e-4, 0.2, 28 * 3e-3 / math.pi / 2  # min_time.toml: 055U2B30, 0.2 kg, 28 GT3 teeth


def _torque(load, s, v, a):
    return load_torque(J_ROTOR, BeltPulley(2 * R), load, np.array([s]), np.array([v]), np.array([a]))


@pytest.mark.parametrize("v, a", [(1.2, 300.0), (1.2, -300.0), (-0.8, 150.0), (-0.8, -150.0), (0.0, 200.0)])
def test_friction_by_hand(v, a):
    # F = -(F_c sign(v) + c v), at rest against the starting acceleration; the motor gives
    # J eps + (m a - F) r with eps = a/r (a belt: mu = r)
    load = Load(MASS, 0.0, (LoadForce("guide", "friction", 1.0, 20.0, viscous=5.0),))
    terms = _torque(load, 0.01, v, a)
    sign = math.copysign(1.0, v) if v != 0 else math.copysign(1.0, a)
    force = -(20.0 * sign + 5.0 * v)
    assert float(terms.forces["guide"][0]) == pytest.approx(-force * R, rel=1e-12)
    assert float(terms.total[0]) == pytest.approx(J_ROTOR * a / R + (MASS * a - force) * R, rel=1e-12)


@pytest.mark.parametrize("v, a, driving", [(1.2, 300.0, True), (1.2, -300.0, False), (-0.8, -150.0, True),
                                           (-0.8, 150.0, False), (0.0, 200.0, True)])
def test_efficiency_by_hand(v, a, driving):
    # what goes through the belt to the load, m a r: divided by eta while the motor drives it (power >= 0),
    # times eta while the load drives the motor; the rotor's own J eps does not pass the belt
    load = Load(MASS, 0.0, (), (), 0.8)
    terms = _torque(load, 0.0, v, a)
    through = MASS * a * R
    expected = J_ROTOR * a / R + (through / 0.8 if driving else through * 0.8)
    assert float(terms.total[0]) == pytest.approx(expected, rel=1e-12)
    assert float(terms.as_dict()["efficiency loss"][0]) == pytest.approx(expected - J_ROTOR * a / R - through)


def test_the_smooth_forms_are_the_exact_ones_away_from_rest():
    # the collocation's symbols: friction within 1e-3 m/s of rest, efficiency within 0.03 W of no power
    load = Load(MASS, 0.0, (LoadForce("guide", "friction", 1.0, 20.0, viscous=5.0),), (), 0.7)
    s, v, a = (ca.SX.sym(n) for n in "sva")
    f = ca.Function("f", [s, v, a], [load_torque(J_ROTOR, BeltPulley(2 * R), load, s, v, a).total])
    for v_, a_ in [(1.2, 300.0), (1.2, -300.0), (-0.8, 150.0), (-0.8, -150.0), (0.05, -20.0)]:
        exact = float(_torque(load, 0.0, v_, a_).total[0])
        assert float(f(0.0, v_, a_)) == pytest.approx(exact, rel=1e-9)


def test_friction_and_efficiency_fields(tmp_path):
    base = (KNOWN / "min_time.toml").read_text()
    path = tmp_path / "p.toml"
    path.write_text(base + '\n[[drive.load_forces]]\nname = "guide"\nkind = "friction"\ncoulomb_N = 20\n'
                           'viscous_N_s_m = 4\n')
    problem = load_problem(path, ["transmission.efficiency=0.9"])
    (force,) = problem.drive.load.forces
    assert (force.kind, force.force, force.viscous, force.smoothing) == ("friction", 20.0, 4.0, 1e-3)
    assert problem.drive.load.efficiency == 0.9
    for sets, field, words in [(["transmission.efficiency=0"], "transmission.efficiency", "outside the plausible range"),
                               (["transmission.efficiency=1.2"], "transmission.efficiency", "outside the plausible range"),
                               (["drive.load_forces[1].direction=\"up\""], "drive.load_forces[1].direction",
                                "unknown field"),
                               (["drive.load_forces[1].coulomb_N=-1"], "drive.load_forces[1].coulomb_N", "range")]:
        with pytest.raises(ProblemError, match=words) as exc:
            load_problem(path, sets)
        assert exc.value.field == field


def _bang_bang(a_up: float, a_down: float, h: float = 0.010) -> float:
    # the shortest rest-to-rest move with acceleration a_up and deceleration a_down: h = v^2/2 (1/a_up + 1/a_down)
    return math.sqrt(2 * h * (1 / a_up + 1 / a_down))


def test_shortest_move_through_a_lossy_belt():
    # min_time.toml (2.4 N m on J/r + m r) through a belt of efficiency 0.8: the motor accelerates the mass with
    # m r/eta and brakes it with m r eta, so T = sqrt(2 h (1/a_up + 1/a_down)); within 0.5 % at the file's mesh
    design = solve_design(load_problem(KNOWN / "min_time.toml", ["transmission.efficiency=0.8"]))
    t = _bang_bang(2.4 / (J_ROTOR / R + MASS * R / 0.8), 2.4 / (J_ROTOR / R + MASS * R * 0.8))
    assert design.status == "optimal"
    for move in design.moves:
        assert move.duration == pytest.approx(t, rel=5e-3)
    assert design.check_value("peak_torque") == pytest.approx(2.4, rel=5e-3)


def test_shortest_move_against_coulomb_friction(tmp_path):
    # 20 N of guide friction: it costs the motor (2.4/r - 20) N of acceleration force and lends it (2.4/r + 20)
    # while braking; the same closed form, within 0.5 %
    path = tmp_path / "friction.toml"
    path.write_text((KNOWN / "min_time.toml").read_text()
                    + '\n[[drive.load_forces]]\nname = "guide"\nkind = "friction"\ncoulomb_N = 20\n')
    design = solve_design(load_problem(path))
    inertia = J_ROTOR / R**2 + MASS
    t = _bang_bang((2.4 / R - 20.0) / inertia, (2.4 / R + 20.0) / inertia)
    assert design.status == "optimal"
    for move in design.moves:
        assert move.duration == pytest.approx(t, rel=5e-3)
