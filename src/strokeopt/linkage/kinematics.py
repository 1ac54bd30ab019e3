"""Exact kinematics of a linkage over its input cycle.

Positions by Newton with continuation over the input angle from the reference pose (which picks the
assembly branch): each step predicts to first order from the pose before, corrects by Newton, and is
accepted only when the residual is at most :data:`RESIDUAL_TOL` and the correction is small against
the move the transfer function predicts -- a step that jumps out of proportion is halved (a branch
change or a dead centre ahead). The whole cycle first runs as one CasADi ``mapaccum`` call; when any
step of it fails those checks, the cycle is walked again step by step with halving, which either
succeeds or names the angle and the links where the linkage cannot close. The pose after one turn
must equal the start. Derivatives (first to third) come from closure.py by AD.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import lru_cache

import casadi as ca
import numpy as np

from ..errors import ProblemError
from .closure import Closure, relative_angle
from .model import Linkage
from .structure import Structure, analyse_structure

RESIDUAL_TOL = 1e-11     # m, largest closure residual accepted after a step
JUMP_RATIO = 4.0         # a Newton correction above this multiple of the one q'' predicts halves the step
MIN_STEP = 1e-7          # rad, below this a step that still fails is a dead centre or no closure
MAX_STEP = math.radians(2.0)  # rad, the longest continuation step (a coarser grid is walked in substeps)
TOGGLE_INDEX = 1e-4      # transmission index below this: the chain passes a dead centre
RETURN_TOL = 1e-9        # m, the pose after one turn against the start


@dataclass
class Cycle:
    """The solved cycle: ``theta`` [rad] (n angles from the reference, one turn) with the unknown
    joints' coordinates ``q`` (n x nq) and their derivatives by the input angle."""

    linkage: Linkage
    structure: Structure
    theta: np.ndarray
    q: np.ndarray
    dq: np.ndarray
    d2q: np.ndarray
    d3q: np.ndarray
    residual: np.ndarray          # largest closure residual at each angle [m]
    index: np.ndarray             # transmission index per quality group (n x groups)
    return_error: float           # |q(after one turn) - q(start)| [m]
    substeps: int                 # steps the walk needed (n when no step was halved)

    @property
    def groups(self):
        return [g for g in self.structure.groups if g.kind != "placement"]


class Kinematics:
    """Closure and output Functions of one linkage, and the cycle solver."""

    def __init__(self, linkage: Linkage, structure: Structure | None = None):
        self.linkage = linkage
        self.structure = structure or analyse_structure(linkage)
        self.closure = Closure(linkage, self.structure)
        self._mapped = {}

    @property
    def p(self) -> np.ndarray:
        return self.linkage.reference()

    def q_reference(self) -> np.ndarray:
        return np.concatenate([self.linkage.joint(n).xy for n in self.structure.unknown])

    def with_geometry(self, coords) -> "Kinematics":
        """The same topology (and compiled Functions) for other reference coordinates (flat, metres)."""
        other = Kinematics.__new__(Kinematics)
        other.__dict__.update(self.__dict__)
        other.linkage = self.linkage.with_reference(coords)
        return other

    def screen(self, n: int = 360) -> np.ndarray | None:
        """The poses at n angles (n >= 180) by the fast walk only (no refusal): None where it fails or does
        not return to the start."""
        grid = self.linkage.crank.reference_angle + 2 * math.pi * np.arange(n + 1) / n
        q = self._fast_walk(grid)
        if q is None or np.linalg.norm(q[-1] - q[0]) > RETURN_TOL:
            return None
        return q[:-1]

    # -- the walk ----------------------------------------------------------------------------------
    def solve(self, n: int = 720) -> Cycle:
        theta0 = self.linkage.crank.reference_angle
        grid = theta0 + 2 * math.pi * np.arange(n + 1) / n
        q = self._fast_walk(grid) if 2 * math.pi / n <= MAX_STEP else None
        substeps = n
        if q is None or np.linalg.norm(q[-1] - q[0]) > RETURN_TOL:
            q, substeps = self._careful_walk(grid)
        ret = float(np.linalg.norm(q[-1] - q[0]))
        if ret > RETURN_TOL:
            raise self._error(grid[-1], q[-2], f"does not return to its reference pose after one turn of the "
                                               f"input ({ret * 1e3:.3g} mm off): the crank cannot turn fully "
                                               "on this assembly branch")
        q = q[:-1]
        theta = grid[:-1]
        dq, d2q, d3q = self._map("derivatives", n)(q.T, theta[None, :], np.repeat(self.p[:, None], n, 1))
        res = self._map("residual", n)(q.T, theta[None, :], np.repeat(self.p[:, None], n, 1))
        index = self._map("quality", n)(q.T, theta[None, :], np.repeat(self.p[:, None], n, 1))
        cycle = Cycle(self.linkage, self.structure, theta, q, np.asarray(dq).T, np.asarray(d2q).T,
                      np.asarray(d3q).T, np.max(np.abs(np.asarray(res)), axis=0), np.asarray(index).T.reshape(n, -1),
                      ret, substeps)
        self._check_toggle(cycle)
        return cycle

    def _map(self, name: str, n: int) -> ca.Function:
        key = (name, n)
        if key not in self._mapped:
            self._mapped[key] = self.closure.function(name).map(n)
        return self._mapped[key]

    def _fast_walk(self, grid: np.ndarray) -> np.ndarray | None:
        """The whole cycle in one mapaccum call; None when a step fails the checks."""
        n = len(grid) - 1
        key = ("walk", n)
        if key not in self._mapped:
            self._mapped[key] = self.closure.function("step").mapaccum("walk", n)
        q_out, res, corr, move = self._mapped[key](self.q_reference(), grid[None, :-1], grid[None, 1:],
                                                   np.repeat(self.p[:, None], n, 1))
        res, corr, move = (np.asarray(a).ravel() for a in (res, corr, move))
        if not (np.all(res <= RESIDUAL_TOL) and np.all(corr <= JUMP_RATIO * move + 1e-13)):
            return None
        return np.vstack([self.q_reference(), np.asarray(q_out).T])

    def _careful_walk(self, grid: np.ndarray) -> tuple[np.ndarray, int]:
        """Step by step from the reference pose, halving every step that fails (residual or jump)."""
        step = self.closure.function("step")
        q = self.q_reference()
        t = grid[0]
        out, count = [q], 0
        for target in grid[1:]:
            while t < target - 1e-15:
                h = min(target - t, MAX_STEP)
                while True:
                    q_new, res, corr, move = (np.asarray(v).ravel() for v in step(q, t, t + h, self.p))
                    if res[0] <= RESIDUAL_TOL and corr[0] <= JUMP_RATIO * move[0] + 1e-13:
                        break
                    h /= 2
                    if h < MIN_STEP:
                        raise self._no_closure(t, q)
                q, t = q_new, t + h
                count += 1
            out.append(q)
        return np.vstack(out), count

    # -- refusals ---------------------------------------------------------------------------------
    def _worst_group(self, q, theta):
        idx = np.asarray(self.closure.function("quality")(q, theta, self.p)).ravel()
        groups = [g for g in self.structure.groups if g.kind != "placement"]
        k = int(np.argmin(idx))
        return groups[k], float(idx[k])

    def _error(self, theta, q, message: str) -> ProblemError:
        group, _ = self._worst_group(q, theta)
        field = self.linkage.field_of(f"link:{group.links[0]}", "links")
        return ProblemError(self.linkage.file, field,
                            f"at input angle {math.degrees(theta) % 360:.2f} deg the linkage (links "
                            f"{', '.join(group.links)}) {message}")

    def _no_closure(self, theta, q) -> ProblemError:
        group, idx = self._worst_group(q, theta)
        field = self.linkage.field_of(f"link:{group.links[0]}", "links")
        return ProblemError(self.linkage.file, field,
                            f"the linkage cannot close beyond input angle {math.degrees(theta) % 360:.2f} deg: "
                            f"links {', '.join(group.links)} (joints {', '.join(group.joints)}) reach a dead centre "
                            f"there (transmission index {idx:.2g}); a link is too short or a crank too long for the "
                            "input to turn fully")

    def _check_toggle(self, cycle: Cycle) -> None:
        if cycle.index.size == 0:
            return
        k, g = np.unravel_index(int(np.argmin(cycle.index)), cycle.index.shape)
        if cycle.index[k, g] < TOGGLE_INDEX:
            group = cycle.groups[g]
            field = self.linkage.field_of(f"link:{group.links[0]}", "links")
            raise ProblemError(self.linkage.file, field,
                               f"links {', '.join(group.links)} pass a dead centre (toggle) at input angle "
                               f"{math.degrees(cycle.theta[k]) % 360:.2f} deg (transmission index "
                               f"{cycle.index[k, g]:.2g}): the driven chain locks there")

    # -- outputs ------------------------------------------------------------------------------------
    def output_expression(self, name: str):
        """The output ``name`` as an expression of (q, theta, p) (SI: rad or m)."""
        out = next(o for o in self.linkage.outputs if o.name == name)
        c = self.closure
        pts = c.points(c.q, c.theta, c.p)
        end = pts[out.end]
        if out.kind in ("x", "y"):
            return out.sign * end[0 if out.kind == "x" else 1]
        start = pts[out.start]
        e0 = c.ref(c.p, out.end) - c.ref(c.p, out.start)
        angle = relative_angle(e0, end - start)
        if out.kind == "angle":
            return out.sign * angle
        return out.sign * ca.norm_2(e0) * angle

    def output_function(self, name: str) -> ca.Function:
        key = ("output", name)
        if key not in self._mapped:
            self._mapped[key] = self.closure.jet_function(f"output_{name}", self.output_expression(name))
        return self._mapped[key]

    def output(self, cycle: Cycle, name: str) -> np.ndarray:
        """The output over the cycle and its first three derivatives by the input angle (4 x n)."""
        return self.along(cycle, self.output_function(name))

    def along(self, cycle: Cycle, fn: ca.Function) -> list[np.ndarray]:
        """A jet Function (closure.jet_function) over the cycle: each output as (n x size) arrays,
        a scalar output as a 1-d array; a scalar jet's four outputs stacked (4 x n)."""
        n = len(cycle.theta)
        vals = fn.map(n)(cycle.q.T, cycle.dq.T, cycle.d2q.T, cycle.d3q.T, cycle.theta[None, :],
                         np.repeat(self.p[:, None], n, 1))
        vals = [np.asarray(v).T for v in vals]
        if all(v.shape[1] == 1 for v in vals):
            return np.vstack([v.ravel() for v in vals])
        return vals


@lru_cache(maxsize=16)
def _cached(linkage: Linkage) -> Kinematics:
    return Kinematics(linkage)


def kinematics_of(linkage: Linkage) -> Kinematics:
    """The (cached) Kinematics of ``linkage`` (a Linkage is hashable by its data)."""
    return _cached(linkage)
