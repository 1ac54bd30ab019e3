"""Direct collocation of one move (design/collocation.py): the polynomials are exact, the hulls bound them.

The reference is the 3-4-5 polynomial y = 10 tau^3 - 15 tau^4 + 6 tau^5 (its acceleration is a cubic,
so a degree-3 mesh represents it exactly): every quantity the NLP sees must then be exact to round-off.
"""

from __future__ import annotations

import casadi as ca
import numpy as np
import pytest
from numpy.polynomial import Polynomial

from strokeopt.design.transcription.collocation import Mesh, MoveSolution, MoveVariables, fine_grid, move_piece, node_times

POLY5 = Polynomial([0, 0, 0, 10, -15, 6])


def _exact_solution(mesh: Mesh) -> MoveSolution:
    starts = np.arange(mesh.intervals + 1) * mesh.h
    nodes = (np.arange(mesh.intervals).reshape(-1, 1) + mesh.nodes.reshape(1, -1)) * mesh.h
    return MoveSolution(mesh, POLY5(starts), POLY5.deriv(1)(starts), POLY5.deriv(2)(nodes))


def _symbols(mesh: Mesh) -> tuple[MoveVariables, list]:
    S, V = ca.MX.sym("S", mesh.intervals + 1), ca.MX.sym("V", mesh.intervals + 1)
    a0, Acol = ca.MX.sym("a0"), ca.MX.sym("Acol", mesh.intervals, mesh.degree)
    return MoveVariables(mesh, S, V, a0, Acol), [S, V, a0, Acol]


def _numbers(sol: MoveSolution) -> list:
    return [sol.S, sol.V, sol.A[0, 0], sol.A[:, 1:]]


def test_nodes_are_the_interval_start_and_the_radau_points():
    mesh = Mesh(10, 3)
    assert mesh.nodes[0] == 0.0 and mesh.nodes[-1] == pytest.approx(1.0)
    assert len(mesh.nodes) == 4
    assert mesh.matrices(mesh.nodes)["a"] == pytest.approx(np.eye(4), abs=1e-12)  # Lagrange basis
    t = node_times(mesh)
    assert t[0] == 0.0 and t[-1] == pytest.approx(1.0) and np.all(np.diff(t) > 0)


@pytest.mark.parametrize("intervals, degree", [(1, 3), (7, 3), (20, 4)])
def test_solution_reproduces_a_polynomial_move_exactly(intervals, degree):
    mesh = Mesh(intervals, degree)  # degree 4: the cubic acceleration through 5 nodes is still that cubic
    sol = _exact_solution(mesh)
    tau = np.linspace(0, 1, 257)
    y, y1, y2, y3, y4 = sol.evaluate(tau)
    for got, k in zip((y, y1, y2, y3, y4), range(5)):
        assert got == pytest.approx(POLY5.deriv(k)(tau), abs=1e-9)


def test_symbolic_values_defects_and_integrals_are_exact():
    mesh = Mesh(8, 3)
    sol = _exact_solution(mesh)
    mv, syms = _symbols(mesh)
    theta = np.array([0.0, 0.3, 1.0])
    f = ca.Function("f", syms, [mv.at(theta, "s"), mv.at(theta, "v"), mv.at(theta, "a"), mv.at(theta, "j"),
                                mv.defects(), mv.jerk_joints(), mv.integral("a"), mv.integral("j")])
    s, v, a, j, defects, joints, int_a2, int_j2 = (np.array(x) for x in f(*_numbers(sol)))
    tau = (np.arange(mesh.intervals).reshape(-1, 1) + theta.reshape(1, -1)) * mesh.h
    for got, k in ((s, 0), (v, 1), (a, 2), (j, 3)):
        assert got == pytest.approx(POLY5.deriv(k)(tau), abs=1e-10)
    assert np.abs(defects).max() < 1e-12 and np.abs(joints).max() < 1e-9
    # integrals of a^2 and jerk^2 over the move: closed form from the polynomial
    assert int_a2.item() == pytest.approx((POLY5.deriv(2) ** 2).integ()(1.0), rel=1e-12)
    assert int_j2.item() == pytest.approx((POLY5.deriv(3) ** 2).integ()(1.0), rel=1e-12)  # 720 for 3-4-5


def test_bernstein_hulls_enclose_velocity_acceleration_and_jerk():
    mesh = Mesh(5, 3)
    sol = _exact_solution(mesh)
    mv, syms = _symbols(mesh)
    f = ca.Function("hull", syms, [mv.hull("v"), mv.hull("a"), mv.hull("j")])
    hv, ha, hj = (np.array(x) for x in f(*_numbers(sol)))
    theta = np.linspace(0, 1, 101)
    for k, hull, deriv in ((0, hv, 1), (1, ha, 2), (2, hj, 3)):
        values = POLY5.deriv(deriv)((np.arange(mesh.intervals).reshape(-1, 1) + theta.reshape(1, -1)) * mesh.h)
        assert np.all(values >= hull.min(axis=1, keepdims=True) - 1e-9)
        assert np.all(values <= hull.max(axis=1, keepdims=True) + 1e-9)
    # the hull of the velocity is tight at the ends of each interval (the first and last coefficients)
    ends = POLY5.deriv(1)(np.arange(mesh.intervals + 1) * mesh.h)
    assert hv[:, 0] == pytest.approx(ends[:-1], abs=1e-12) and hv[:, -1] == pytest.approx(ends[1:], abs=1e-12)


def test_move_piece_in_seconds_and_metres_matches_the_unit_solution():
    mesh = Mesh(6, 3)
    sol = _exact_solution(mesh)
    t0, duration, start, stroke = 0.05, 0.021, 0.032, -0.032  # move 1 at 600 spm: 32 mm down in 21 ms
    piece = move_piece(t0, duration, start, stroke, sol, "move 1")
    tau = np.linspace(0, 1, 50)
    s = np.array([float(piece.position(x)) for x in tau * duration]).ravel()
    assert s == pytest.approx(start + stroke * POLY5(tau), abs=1e-12)


def test_fine_grid_and_mesh_validation():
    grid = fine_grid(Mesh(4, 3), per_interval=5)
    assert len(grid) == 21 and grid[0] == 0.0 and grid[-1] == 1.0
    with pytest.raises(ValueError, match="intervals"):
        Mesh(0, 3)
    with pytest.raises(ValueError, match="degree"):
        Mesh(10, 12)
