"""Direct collocation of one rest-to-rest move, in scaled (unit) variables.

A move of signed stroke ``H`` and duration ``T`` is stated in unit form:
``tau = t/T`` in [0, 1] and ``y = (s - s_start)/H`` from 0 to 1, so that
``v = H/T*y'``, ``a = H/T^2*y''``, ``jerk = H/T^3*y'''``. Every move of every
problem, in whatever units the user wrote it, becomes the same well-scaled
NLP (values of order 1-10); this is what makes IPOPT robust here (stated in
SI, a 40 ms / 30 mm move made IPOPT report false infeasibility).

Discretisation: the move is split into ``N`` mesh intervals of equal length
``h = 1/N``. States are position, velocity and acceleration, the control is
the jerk. In each interval the acceleration is the Lagrange polynomial of
degree ``d`` through its value at the interval start and at the ``d`` Radau
collocation points (the last of which is the interval end); the jerk is its
derivative (degree ``d - 1``). Velocity and position are its exact first and
second integrals, so the collocation equations ``s' = v``, ``v' = a``,
``a' = jerk`` hold exactly and the position is a polynomial of degree
``d + 2`` per interval; the continuity (defect) constraints join the
intervals' position and velocity. Path constraints (jerk, acceleration,
torque...) are imposed at the nodes (interval starts and collocation points);
:func:`fine_grid` checks them in between.

Everything here is linear algebra on precomputed numpy matrices applied to
CasADi MX symbols (built once, then ``expand``-ed to SX by the solver).
:func:`move_piece` turns a solved move back into a stroke piece (the exact polynomials).
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property

import casadi as ca
import numpy as np
from numpy.polynomial import Polynomial

from ...motion.stroke import Piece, polynomial_piece

SCHEMES = ("radau",)


@dataclass(frozen=True)
class Mesh:
    """``intervals`` equal mesh intervals, Lagrange acceleration polynomials of ``degree``."""

    intervals: int = 40
    degree: int = 3

    def __post_init__(self):
        if int(self.intervals) != self.intervals or self.intervals < 1:
            raise ValueError(f"mesh intervals must be a positive whole number, got {self.intervals!r}")
        if int(self.degree) != self.degree or not 1 <= self.degree <= 9:
            raise ValueError(f"collocation degree must be 1..9, got {self.degree!r}")

    @property
    def h(self) -> float:
        return 1.0 / self.intervals

    @cached_property
    def nodes(self) -> np.ndarray:
        """Local node positions in an interval: 0 and the Radau points (last = 1)."""
        return np.array([0.0] + list(ca.collocation_points(self.degree, "radau")))

    @cached_property
    def _basis(self) -> list[Polynomial]:
        nodes = self.nodes
        basis = []
        for j in range(len(nodes)):
            p = Polynomial([1.0])
            for m in range(len(nodes)):
                if m != j:
                    p = p * Polynomial([-nodes[m], 1.0]) / (nodes[j] - nodes[m])
            basis.append(p)
        return basis

    @cached_property
    def _coefficients(self) -> dict[str, np.ndarray]:
        """Ascending power coefficients (rows: power, columns: basis function) of a, j, snap, v, s."""
        size = self.degree + 3
        out = {k: np.zeros((size, self.degree + 1)) for k in ("a", "j", "snap", "v", "s")}
        for col, p in enumerate(self._basis):
            for key, poly in (("a", p), ("j", p.deriv(1)), ("snap", p.deriv(2)), ("v", p.integ()),
                              ("s", p.integ().integ())):
                c = poly.coef
                out[key][: len(c), col] = c
        return out

    def matrices(self, theta) -> dict[str, np.ndarray]:
        """Rows mapping an interval's node accelerations (``d + 1``) to values at local points ``theta``.

        Keys: ``a`` (acceleration), ``j`` (jerk, times 1/h), ``snap`` (times 1/h^2),
        ``v`` (velocity increment, times h), ``s`` (position increment, times h^2).
        """
        theta = np.atleast_1d(np.asarray(theta, dtype=float))
        powers = theta.reshape(-1, 1) ** np.arange(self.degree + 3).reshape(1, -1)
        return {k: powers @ c for k, c in self._coefficients.items()}

    def symbolic_rows(self, theta) -> dict:
        """:meth:`matrices` at one local point ``theta`` that is a CasADi expression (a variable of the NLP): rows
        of ``d + 1`` columns (1 x (d + 1) each)."""
        powers = ca.horzcat(*[theta ** p for p in range(self.degree + 3)])
        return {k: ca.mtimes(powers, c) for k, c in self._coefficients.items()}

    def unit_position_coefficients(self, s0: float, v0: float, a_nodes) -> np.ndarray:
        """Ascending coefficients in theta (0..1) of ``s0 + h*v0*theta + h^2 * double integral of a`` of one interval."""
        acc = Polynomial([0.0])
        for p, an in zip(self._basis, a_nodes):
            acc = acc + float(an) * p
        s = self.h**2 * acc.integ().integ() + Polynomial([s0, self.h * v0])
        return s.coef

    @cached_property
    def bernstein(self) -> np.ndarray:
        """Matrix mapping an interval's node accelerations to the Bernstein coefficients of its polynomial.

        A polynomial lies inside the convex hull of its Bernstein coefficients, so bounds
        imposed on them hold everywhere in the interval, not only at the nodes.
        """
        from math import comb

        d = self.degree
        x = self.nodes
        basis = np.array([[comb(d, i) * xj**i * (1 - xj) ** (d - i) for i in range(d + 1)] for xj in x])
        return np.linalg.inv(basis)

    @cached_property
    def quadrature(self) -> tuple[np.ndarray, np.ndarray]:
        """Gauss-Legendre points and weights on [0, 1], exact for degree ``2d + 1`` (squared accelerations)."""
        x, w = np.polynomial.legendre.leggauss(self.degree + 1)
        return (x + 1) / 2, w / 2


@dataclass
class MoveVariables:
    """Symbols of one move in unit form: ``S``, ``V`` (N+1 interval-start values), ``A`` (N x (d+1) node accelerations).

    ``a0`` is the acceleration at the move start; ``Acol`` the N x d values at the
    collocation points. ``A`` shares each interval's start value with the
    previous interval's end (continuity of the acceleration).
    """

    mesh: Mesh
    S: ca.MX
    V: ca.MX
    a0: ca.MX
    Acol: ca.MX

    @property
    def A(self) -> ca.MX:
        starts = ca.vertcat(self.a0, self.Acol[:-1, -1]) if self.mesh.intervals > 1 else self.a0
        return ca.horzcat(starts, self.Acol)

    def at(self, theta, kind: str) -> ca.MX:
        """N x len(theta) matrix of ``kind`` (s, v, a, j, snap) at local points of every interval."""
        m = self.mesh.matrices(theta)
        h = self.mesh.h
        A = self.A
        if kind == "a":
            return ca.mtimes(A, m["a"].T)
        if kind == "j":
            return ca.mtimes(A, m["j"].T) / h
        if kind == "snap":
            return ca.mtimes(A, m["snap"].T) / h**2
        theta = np.atleast_1d(np.asarray(theta, dtype=float))
        ones = np.ones((1, len(theta)))
        if kind == "v":
            return ca.mtimes(self.V[:-1], ones) + h * ca.mtimes(A, m["v"].T)
        if kind == "s":
            return (ca.mtimes(self.S[:-1], ones) + h * ca.mtimes(self.V[:-1], theta.reshape(1, -1))
                    + h**2 * ca.mtimes(A, m["s"].T))
        raise ValueError(kind)

    def hull(self, kind: str) -> ca.MX:
        """Bernstein coefficients of the velocity (N x (d+2)), acceleration (N x (d+1)) or jerk (N x d)
        polynomial of every interval.

        Bounding these bounds the quantity everywhere (convex hull property).
        """
        coef = ca.mtimes(self.A, self.mesh.bernstein.T)
        if kind == "a":
            return coef
        if kind == "v":  # v = V + h * integral of a: the integral's coefficients are the running sums / (d + 1)
            d = self.mesh.degree
            sums = [ca.MX.zeros(self.mesh.intervals, 1)]
            for i in range(d + 1):
                sums.append(sums[-1] + coef[:, i])
            return ca.repmat(self.V[:-1], 1, d + 2) + self.mesh.h / (d + 1) * ca.horzcat(*sums)
        if kind == "j":
            d = self.mesh.degree
            return d * (coef[:, 1:] - coef[:, :-1]) / self.mesh.h
        raise ValueError(kind)

    def defects(self) -> ca.MX:
        """Continuity of position and velocity across interval ends (exact integration of a)."""
        m = self.mesh.matrices([1.0])
        h = self.mesh.h
        A = self.A
        s_end = self.S[:-1] + h * self.V[:-1] + h**2 * ca.mtimes(A, m["s"].T)
        v_end = self.V[:-1] + h * ca.mtimes(A, m["v"].T)
        return ca.vertcat(self.S[1:] - s_end, self.V[1:] - v_end)

    def jerk_joints(self) -> ca.MX:
        """Jump of the jerk at the interior interval joints (N - 1 values)."""
        if self.mesh.intervals < 2:
            return ca.MX(0, 1)
        j_end = self.at([1.0], "j")[:-1, 0]
        j_start = self.at([0.0], "j")[1:, 0]
        return j_start - j_end

    def node_values(self, kind: str) -> ca.MX:
        """Values at all nodes (move start, then every collocation point), as one column."""
        if kind == "a":
            return ca.vertcat(self.a0, ca.vec(self.Acol.T))
        inner = self.at(self.mesh.nodes[1:], kind)
        first = self.at([0.0], kind)[0, 0]
        return ca.vertcat(first, ca.vec(inner.T))

    def integral(self, kind: str, power: int = 2) -> ca.MX:
        """Integral over the move (unit time) of ``kind**power`` (Gauss-Legendre, exact for polynomials up to degree 2d+1)."""
        x, w = self.mesh.quadrature
        vals = self.at(x, kind)
        return self.mesh.h * ca.sum1(ca.mtimes(vals**power, w.reshape(-1, 1)))


def node_times(mesh: Mesh) -> np.ndarray:
    """Unit times of :meth:`MoveVariables.node_values` (move start, then every collocation point)."""
    h = mesh.h
    k = np.arange(mesh.intervals).reshape(-1, 1)
    return np.concatenate([[0.0], ((k + mesh.nodes[1:].reshape(1, -1)) * h).ravel()])


@dataclass(frozen=True)
class MoveSolution:
    """Numeric unit-form solution of one move: interval-start S, V and node accelerations A (N x (d+1))."""

    mesh: Mesh
    S: np.ndarray
    V: np.ndarray
    A: np.ndarray

    def evaluate(self, tau) -> tuple[np.ndarray, ...]:
        """Unit position and its first four derivatives at unit times ``tau`` in [0, 1] (exact polynomials)."""
        tau = np.clip(np.atleast_1d(np.asarray(tau, dtype=float)), 0.0, 1.0)
        n, h = self.mesh.intervals, self.mesh.h
        k = np.minimum((tau / h).astype(int), n - 1)
        theta = tau / h - k
        m = self.mesh.matrices(theta)
        A = self.A[k]  # one row of node accelerations per point
        y = self.S[k] + h * self.V[k] * theta + h**2 * np.sum(m["s"] * A, axis=1)
        y1 = self.V[k] + h * np.sum(m["v"] * A, axis=1)
        y2 = np.sum(m["a"] * A, axis=1)
        y3 = np.sum(m["j"] * A, axis=1) / h
        y4 = np.sum(m["snap"] * A, axis=1) / h**2
        return y, y1, y2, y3, y4

    def position_polynomials(self, duration: float, s_start: float, stroke: float) -> list[np.ndarray]:
        """Per mesh interval, ascending coefficients in local time (seconds) of the position in metres."""
        out = []
        local = self.mesh.h * duration  # seconds per unit theta
        for k in range(self.mesh.intervals):
            c = self.mesh.unit_position_coefficients(self.S[k], self.V[k], self.A[k])
            coef = stroke * c / local ** np.arange(len(c))
            coef[0] += s_start
            out.append(coef)
        return out


def fine_grid(mesh: Mesh, per_interval: int = 20) -> np.ndarray:
    """Unit times with ``per_interval`` points inside every mesh interval (ends included)."""
    return np.linspace(0.0, 1.0, mesh.intervals * per_interval + 1)


def move_piece(t_start: float, duration: float, start: float, stroke: float, sol: MoveSolution, label: str) -> Piece:
    """A stroke piece reproducing the collocation polynomials of one move exactly (one polynomial per mesh interval)."""
    h = sol.mesh.h * duration
    return polynomial_piece(t_start, duration, np.arange(sol.mesh.intervals) * h,
                            sol.position_polynomials(duration, start, stroke), label)
