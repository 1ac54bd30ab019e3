"""The design's IPOPT solve (design/transcription/solver.py): the constraint Jacobian it gives IPOPT."""

from __future__ import annotations

import casadi as ca
import numpy as np

from strokeopt.design.transcription.solver import DENSE_ROW, constraint_jacobian


def test_constraint_jacobian_by_groups_equals_casadis_own():
    """Rows differentiated group by group (a dense group apart, as the servo term's handover rows) give CasADi's
    Jacobian of all rows at once: the same sparsity, the same numbers."""
    rng = np.random.default_rng(3)
    n = 3 * DENSE_ROW
    w, p = ca.MX.sym("w", n), ca.MX.sym("p", 20, n)
    banded = ca.vertcat(*[w[i] * w[i + 1] - ca.sin(w[i + 2]) for i in range(n - 2)])
    dense = ca.mtimes(p, w) / (1 + w[0] ** 2)  # every row touches every variable
    groups = [banded[: n // 2], ca.vertcat(dense, -dense), banded[n // 2:], w[-1] ** 3]
    ours = constraint_jacobian(groups, w, ca.vec(p))
    theirs = ca.Function("all", [w, ca.vec(p)], [ca.jacobian(ca.vertcat(*groups), w)])
    wv, pv = rng.standard_normal(n), rng.standard_normal(20 * n)
    g, jac = ours(wv, pv)
    expected = theirs(wv, pv)
    assert jac.sparsity() == expected.sparsity()
    assert np.max(np.abs(np.asarray(jac - expected))) <= 1e-12 * max(1.0, np.max(np.abs(np.asarray(expected))))
    assert np.allclose(np.asarray(g).ravel(), np.asarray(ca.Function("g", [w, ca.vec(p)], [ca.vertcat(*groups)])(wv, pv)).ravel())
    assert ours.name_out() == ["g", "jac_g_x"] and ours.name_in() == ["x", "p"]  # what IPOPT's interface asks for
