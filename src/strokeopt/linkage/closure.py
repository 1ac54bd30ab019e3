"""Loop closure of a linkage as CasADi SX, built from its data (structure.py's equations).

Symbols: ``q`` the coordinates of the unknown joints, ``theta`` the input angle, ``p`` the reference
coordinates of every joint (so one set of Functions serves every geometry of a topology: analysis,
screening and synthesis). A distance row is ``(|pa - pb|^2 - L^2) / (2 L)``: metres, and at closure
its gradient is the unit vector along the link, so the Jacobian's rows are normalised and the
determinant of a dyad's block is the sine of Alt's transmission angle.

Derivatives with respect to the input are algorithmic, never hand-written: ``q' = -Phi_q^-1 Phi_theta``
(the implicit-function formula), and the higher ones order by order in Taylor mode (AD of the closure
along a polynomial of the pose, solved with the same block-triangular Jacobian); an output's or a
centre of gravity's derivatives by AD along the pose's Taylor polynomial (:meth:`Closure.taylor`).
"""

from __future__ import annotations

import math

import casadi as ca

from .model import Linkage
from .structure import Structure

NEWTON_STEPS = 3      # unrolled Newton iterations per continuation step


def cross(a, b):
    return a[0] * b[1] - a[1] * b[0]


def perp(a):
    return ca.vertcat(-a[1], a[0])


def rotate(v, angle):
    c, s = ca.cos(angle), ca.sin(angle)
    return ca.vertcat(c * v[0] - s * v[1], s * v[0] + c * v[1])


def relative_angle(e0, e):
    """The angle [rad] from direction ``e0`` to ``e`` in (-pi, pi], smooth in ``e``."""
    return ca.atan2(cross(e0, e), ca.dot(e0, e))


class Closure:
    """Symbolic closure of one linkage topology; ``p`` carries the geometry."""

    def __init__(self, linkage: Linkage, structure: Structure):
        self.linkage = linkage
        self.structure = structure
        nq, nj = 2 * len(structure.unknown), 2 * len(linkage.joints)
        self.q = ca.SX.sym("q", nq)
        self.theta = ca.SX.sym("theta")
        self.p = ca.SX.sym("p", nj)
        self.phi = self.residual(self.q, self.theta, self.p)
        self.phi_q = ca.jacobian(self.phi, self.q)
        self.qd = self.block_solve(self.phi_q, -ca.jacobian(self.phi, self.theta))
        self._functions = {}

    def block_solve(self, a, b):
        """``a^-1 b`` by forward substitution over the groups (block-triangular order): a small
        expression, so its derivatives by AD stay small too."""
        x = [None] * a.shape[0]
        for g in self.structure.groups:
            rows, cols = list(g.rows), list(g.cols)
            rhs = b[rows]
            for j, xj in enumerate(x):
                if xj is not None and j not in cols:
                    rhs = rhs - a[rows, j] * xj
            sol = ca.solve(a[rows, cols], rhs)
            for k, c in enumerate(cols):
                x[c] = sol[k]
        return ca.vertcat(*x)

    # -- geometry ------------------------------------------------------------------------------
    def ref(self, p, name):
        i = self.linkage.joint_index(name)
        return ca.vertcat(p[2 * i], p[2 * i + 1])

    def points(self, q, theta, p) -> dict:
        """Every joint's position as a 2-vector expression of (q, theta, p)."""
        lk, st = self.linkage, self.structure
        crank = lk.link(lk.crank.link)
        pivot = self.ref(p, lk.crank.pivot)
        out = {}
        for j in lk.joints:
            if j.ground:
                out[j.name] = self.ref(p, j.name)
            elif j.name in crank.joints:
                out[j.name] = pivot + rotate(self.ref(p, j.name) - pivot, theta - lk.crank.reference_angle)
            elif j.name in st.unknown:
                k = st.unknown.index(j.name)
                out[j.name] = ca.vertcat(q[2 * k], q[2 * k + 1])
        return out

    def residual(self, q, theta, p):
        pts = self.points(q, theta, p)
        rows = []
        for eq in self.structure.equations:
            e0 = self.ref(p, eq.b) - self.ref(p, eq.a)
            if eq.kind == "distance":
                d = pts[eq.b] - pts[eq.a]
                length2 = ca.dot(e0, e0)
                rows.append((ca.dot(d, d) - length2) / (2 * ca.sqrt(length2)))
            else:
                d0 = self.ref(p, eq.c) - self.ref(p, eq.a)
                alpha = ca.dot(d0, e0) / ca.dot(e0, e0)
                beta = cross(e0, d0) / ca.dot(e0, e0)
                e = pts[eq.b] - pts[eq.a]
                rows.append(pts[eq.c] - (pts[eq.a] + alpha * e + beta * perp(e)))
        return ca.vertcat(*rows)

    def link_frame(self, pts: dict, p, link):
        """The pose of ``link``: a function placing a reference point [m] where the link has carried it,
        and the link's angle from its reference orientation (first two joints of its data)."""
        a, b = link.joints[0], link.joints[1]
        e0 = self.ref(p, b) - self.ref(p, a)
        e = pts[b] - pts[a]

        def place(point_ref):
            d0 = point_ref - self.ref(p, a)
            alpha = ca.dot(d0, e0) / ca.dot(e0, e0)
            beta = cross(e0, d0) / ca.dot(e0, e0)
            return pts[a] + alpha * e + beta * perp(e)

        return place, relative_angle(e0, e)

    def taylor(self, expr):
        """``expr`` on the cubic Taylor polynomial of the pose, q(theta + s) = q + dq s + d2q s^2/2 +
        d3q s^3/6; returns (s, [dq, d2q, d3q] symbols, the expression in s). Its derivatives in s at 0
        are the total derivatives of expr up to the third."""
        if not hasattr(self, "_taylor"):
            s = ca.SX.sym("s")
            dqs = [ca.SX.sym(f"d{k}q", self.q.shape[0]) for k in range(1, 4)]
            self._taylor = (s, dqs, self.q + dqs[0] * s + dqs[1] * s ** 2 / 2 + dqs[2] * s ** 3 / 6)
        s, dqs, qs = self._taylor
        return s, dqs, ca.substitute(expr, ca.vertcat(self.q, self.theta), ca.vertcat(qs, self.theta + s))

    def jet_function(self, name: str, expr, order: int = 3) -> ca.Function:
        """``expr(q, theta, p)`` and its first ``order`` derivatives along the cycle, from the pose's
        derivatives: expr is evaluated on the Taylor polynomial of q(theta + s) (exact to ``order``)
        and differentiated in s at 0 by AD. Inputs q, dq, d2q, d3q, theta, p."""
        s, dqs, e = self.taylor(expr)
        outs = [e]
        for _ in range(order):
            outs.append(ca.jacobian(outs[-1], s))
        outs = [ca.substitute(o, s, 0) for o in outs]
        names = ["y"] + [f"d{k}y" for k in range(1, order + 1)]
        return ca.Function(name, [self.q, *dqs, self.theta, self.p], outs,
                           ["q", "dq", "d2q", "d3q", "theta", "p"], names)

    # -- numbers -------------------------------------------------------------------------------
    def function(self, name: str) -> ca.Function:
        if name not in self._functions:
            self._functions[name] = getattr(self, "_make_" + name)()
        return self._functions[name]

    def _make_residual(self) -> ca.Function:
        return ca.Function("closure", [self.q, self.theta, self.p], [self.phi], ["q", "theta", "p"], ["phi"])

    def _make_step(self) -> ca.Function:
        """One continuation step: first-order prediction from (q0, theta0) to theta1, then Newton.
        Returns the pose, its largest residual [m], the Newton correction and the correction the second
        transfer function predicts: |q''| (mean of both ends) h^2 / 2, the remainder of a first-order
        prediction. A correction far above it is a jump to another assembly branch."""
        q0, t0, t1 = ca.SX.sym("q0", self.q.shape[0]), ca.SX.sym("t0"), ca.SX.sym("t1")
        derivs = self.function("derivatives")
        qd0, qdd0, _ = derivs(q0, t0, self.p)
        pred = q0 + qd0 * (t1 - t0)
        q = pred
        res = ca.Function("r", [self.q, self.theta, self.p], [self.phi, self.phi_q])
        for _ in range(NEWTON_STEPS):
            phi, jac = res(q, t1, self.p)
            q = q - self.block_solve(jac, phi)
        phi, _ = res(q, t1, self.p)
        _, qdd1, _ = derivs(q, t1, self.p)
        expected = (ca.norm_2(qdd0) + ca.norm_2(qdd1)) / 4 * (t1 - t0) ** 2
        return ca.Function("continuation_step", [q0, t0, t1, self.p],
                           [q, ca.mmax(ca.fabs(phi)), ca.norm_2(q - pred), expected],
                           ["q0", "theta0", "theta1", "p"], ["q", "residual", "correction", "move"])

    def _make_positions(self) -> ca.Function:
        pts = self.points(self.q, self.theta, self.p)
        flat = ca.vertcat(*[pts[j.name] for j in self.linkage.joints if j.name in pts])
        return ca.Function("positions", [self.q, self.theta, self.p], [flat], ["q", "theta", "p"], ["xy"])

    def _make_derivatives(self) -> ca.Function:
        """The pose's first three derivatives q_1, q_2, q_3 in Taylor mode: the k-th derivative in s of
        Phi(q + sum_{j<k} q_j s^j / j!, theta + s) at s = 0 (by AD) holds every term of the k-th total
        derivative of Phi = 0 but Phi_q q_k, so
        q_k = -Phi_q^-1 times it (the implicit-function formula, order by order)."""
        s = ca.SX.sym("s")
        out, poly = [], self.q
        for k in range(1, 4):
            e = ca.substitute(self.phi, ca.vertcat(self.q, self.theta), ca.vertcat(poly, self.theta + s))
            for _ in range(k):
                e = ca.jacobian(e, s)
            qk = self.block_solve(self.phi_q, -ca.substitute(e, s, 0))
            out.append(qk)
            poly = poly + qk * s ** k / math.factorial(k)
        q1, q2, q3 = out
        return ca.Function("pose_derivatives", [self.q, self.theta, self.p], [q1, q2, q3],
                           ["q", "theta", "p"], ["dq", "d2q", "d3q"])

    def group_indices(self, q, theta, p) -> list:
        """Per group (placements excluded) the transmission index: the Hadamard ratio of its closure block,
        |det B| / prod |row_i of B|, 1 when the rows are orthogonal, 0 at a toggle (dead centre). For a dyad
        the rows are unit vectors along its two links, and the index is the sine of Alt's transmission angle."""
        phi_q = ca.jacobian(self.residual(q, theta, p), q)
        out = []
        for g in self.structure.groups:
            if g.kind != "placement":
                block = phi_q[list(g.rows), list(g.cols)]
                scale = 1
                for i in range(block.shape[0]):
                    scale = scale * ca.norm_2(block[i, :])
                out.append(ca.fabs(ca.det(block)) / scale)
        return out

    def _make_quality(self) -> ca.Function:
        idx = self.group_indices(self.q, self.theta, self.p)
        return ca.Function("transmission_index", [self.q, self.theta, self.p], [ca.vertcat(*idx)],
                           ["q", "theta", "p"], ["index"])

    def quality_groups(self) -> list:
        return [g for g in self.structure.groups if g.kind != "placement"]
