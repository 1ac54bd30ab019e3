"""Dimensional synthesis of a linkage in the simultaneous form (IPOPT through CasADi).

The decision variables are the reference coordinates of the joints (so every link length and
ternary shape, and the free pivots) and, at every node of the input cycle, the coordinates of the
unknown joints and their derivatives by the input angle. Closure (closure.py's residual) and its
derivative are equality constraints at each node: IPOPT never calls an inner Newton. What the file
fixes is fixed (joints, lengths such as the loom's crank radii, angles between the arms of a ternary
link); link lengths are bounded; the transmission index of every group is at least the file's limit at
every node; consecutive nodes are tied by the trapezoidal rule on the pose (no branch change between
them). The objective is the squared error of the output's speed against a table; a swing and the
angle of the output's minimum can be stated too (two extra nodes at free angles where the speed is 0).

Starts are random geometries (seeded) that pass the analysis (full turn, no dead centre), ranked by
their fit; the best are solved, every result is checked again by the exact analysis, and distinct
solutions are reported beside the best: the tables do not determine a unique linkage.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field

import casadi as ca
import numpy as np

from ..errors import ProblemError
from ..io.fields import Fields
from .closure import cross, rotate
from .kinematics import Kinematics, kinematics_of
from .targets import SynthesisSpec, fit_report, poses_only, read_spec


@dataclass
class Candidate:
    coords: np.ndarray              # reference coordinates (flat, m)
    rms: float                      # speed fit of the exact analysis [m/s]
    report: dict                    # fit_report of the exact analysis
    ipopt: str = ""

    def lengths(self, kin: Kinematics) -> np.ndarray:
        lk = kin.linkage.with_reference(self.coords)
        return np.array([lk.length(a, b) for link in lk.links for i, a in enumerate(link.joints)
                         for b in link.joints[i + 1:]])


@dataclass
class SynthesisResult:
    best: Candidate
    runners_up: list = field(default_factory=list)
    starts: int = 0
    screened: int = 0
    feasible_screened: int = 0
    seconds: float = 0.0

    note: str = ""

    def to_dict(self, kin: Kinematics) -> dict:
        def one(c):
            lk = kin.linkage.with_reference(c.coords)
            return {**c.report, "ipopt": c.ipopt,
                    "joints_mm": {j.name: [round(j.x * 1e3, 4), round(j.y * 1e3, 4)] for j in lk.joints}}
        return {"best": one(self.best), "runners_up": [one(c) for c in self.runners_up],
                "starts_solved": self.starts, "geometries_screened": self.screened,
                "screened_feasible": self.feasible_screened, "seconds": round(self.seconds, 2),
                "unique": not self.runners_up, "targets_note": self.note,
                "note": "the targets do not determine a unique linkage: distinct geometries fit them"
                        if self.runners_up else "no distinct runner-up among the solved starts"}


def synthesize(problem, starts: int | None = None, screen: int | None = None, seed: int | None = None,
               progress=None) -> SynthesisResult:
    """Synthesise the linkage of ``problem`` (a LinkageProblem) against its ``[synthesis]`` targets."""
    t0 = time.perf_counter()
    spec = read_spec(problem, Fields(problem.synthesis, problem.file, "synthesis"))
    starts = starts or spec.starts
    kin = kinematics_of(problem.linkage) if _closes(problem) else Kinematics(problem.linkage)
    rng = np.random.default_rng(seed if seed is not None else spec.seed)
    pool, tried = _screen(kin, spec, problem, rng, screen or spec.screen)
    if spec.start_from_file:
        q = kin.screen(360)
        if q is not None:
            pool.insert(0, (0.0, problem.linkage.reference(), q))
    if not pool:
        raise ProblemError(problem.file, "synthesis", f"none of {tried} random geometries inside the stated bounds "
                                                       "turns fully: widen coordinate_box_mm or the length bounds")
    nlp = _Nlp(kin, spec, problem)
    found = []
    for k, (score, coords, q) in enumerate(pool[:starts]):
        if progress:
            progress(k, starts)
        result = nlp.solve(coords, q)
        if result is not None:
            found.append(result)
    found.sort(key=lambda c: c.rms)
    if not found:
        raise ProblemError(problem.file, "synthesis", f"no start of {starts} gave a linkage that turns fully and "
                                                       "passes the analysis")
    distinct = []
    for c in (c for c in found[1:] if c.rms <= spec.rms_max):   # runners-up that meet the acceptance too
        if all(np.abs(c.lengths(kin) - d.lengths(kin)).max() > 1e-3 for d in [found[0], *distinct]):
            distinct.append(c)
    return SynthesisResult(found[0], distinct[:3], min(starts, len(pool)), tried, len(pool),
                           time.perf_counter() - t0, spec.note)


def _closes(problem) -> bool:
    try:
        kinematics_of(problem.linkage).solve(problem.angles)
        return True
    except ProblemError:
        return False


def _random_geometry(kin: Kinematics, spec: SynthesisSpec, rng) -> np.ndarray:
    lk = kin.linkage
    coords = lk.reference().reshape(-1, 2).copy()
    box = spec.box
    for i, j in enumerate(lk.joints):
        if j.name not in spec.fixed_joints:
            coords[i] = rng.uniform(-box, box, 2)
    idx = lk.joint_index
    for (a, b), length in spec.fixed_lengths:
        d = coords[idx(b)] - coords[idx(a)]
        coords[idx(b)] = coords[idx(a)] + length * d / max(np.linalg.norm(d), 1e-12)
    for (a, b), (c, d), angle in spec.fixed_angles:
        u = coords[idx(b)] - coords[idx(a)]
        u = u / max(np.linalg.norm(u), 1e-12)
        r = np.linalg.norm(coords[idx(d)] - coords[idx(c)])
        ca_, sa = math.cos(angle), math.sin(angle)
        coords[idx(d)] = coords[idx(c)] + r * np.array([ca_ * u[0] - sa * u[1], sa * u[0] + ca_ * u[1]])
    return coords.ravel()


def _screen(kin: Kinematics, spec: SynthesisSpec, problem, rng, count: int):
    """Random geometries that turn fully within the bounds, best fit first: (score, coords, poses)."""
    pool = []
    for _ in range(count):
        coords = _random_geometry(kin, spec, rng)
        k2 = kin.with_geometry(coords)
        if not spec.lengths_ok(k2.linkage):
            continue
        q = k2.screen(360)
        if q is None:
            continue
        score = spec.screen_score(k2, q, problem)
        if score is not None:
            pool.append((score, coords, q))
    pool.sort(key=lambda t: t[0])
    return pool, count


class _Nlp:
    """The simultaneous-form NLP of one topology and spec, built once, solved from each start."""

    def __init__(self, kin: Kinematics, spec: SynthesisSpec, problem):
        self.kin, self.spec, self.problem = kin, spec, problem
        c = kin.closure
        qd = ca.SX.sym("qd", c.q.shape[0])
        phi = c.phi
        vel = ca.jtimes(phi, c.q, qd) + ca.jacobian(phi, c.theta)
        y = kin.output_expression(spec.output)
        dy = ca.jtimes(y, c.q, qd) + ca.jacobian(y, c.theta)
        ys = kin.output_expression(spec.swing_output or spec.output)
        dys = ca.jtimes(ys, c.q, qd) + ca.jacobian(ys, c.theta)
        idx = ca.vertcat(*c.group_indices(c.q, c.theta, c.p))
        self.node = ca.Function("node", [c.q, qd, c.theta, c.p], [phi, vel, dy, ys, dys, idx])
        self.nodes = spec.nodes(kin.linkage.crank.reference_angle)
        self._build()

    def _build(self):
        kin, spec = self.kin, self.spec
        lk = kin.linkage
        nq, npar = kin.closure.q.shape[0], 2 * len(lk.joints)
        p = ca.MX.sym("p", npar)
        unknown_cols = [2 * lk.joint_index(n) + k for n in kin.structure.unknown for k in (0, 1)]
        m = len(self.nodes)
        Q = ca.MX.sym("Q", nq, m - 1)
        QD = ca.MX.sym("QD", nq, m)
        extra = ca.MX.sym("X", 2 * nq + 1, 2 if spec.swing is not None else 0)
        g, lbg, ubg = [], [], []

        def add(expr, lo, hi):
            g.append(ca.vec(expr))
            n = g[-1].shape[0]
            lbg.extend(np.broadcast_to(lo, n)), ubg.extend(np.broadcast_to(hi, n))

        qs = ca.horzcat(p[unknown_cols], Q)   # node 0 is the reference pose itself
        th = np.array(self.nodes)[None, :]
        phi, vel, dy, y, _, index = self.node.map(m)(qs, QD, th, ca.repmat(p, 1, m))
        add(phi, 0, 0)
        add(vel, 0, 0)
        if index.shape[0]:
            add(index, spec.index_min * 1.05 + 0.005, np.inf)   # a margin: the index dips between nodes
        dth = np.diff(np.append(self.nodes, self.nodes[0] + 2 * math.pi))
        nxt = ca.horzcat(qs[:, 1:], qs[:, :1])
        nxt_d = ca.horzcat(QD[:, 1:], QD[:, :1])
        defect = nxt - qs - (QD + nxt_d) * ca.repmat(ca.DM(dth).T, nq, 1) / 2
        add(defect, -spec.defect_tol, spec.defect_tol)
        omega = self.problem.omega
        ti = [self.nodes.index(t) for t in spec.target_thetas(lk.crank.reference_angle)]
        err = dy[:, ti].T * omega - ca.DM(spec.speeds)
        obj = ca.sumsqr(err) * 1e2
        self._shape_constraints(p, add)
        if spec.swing is not None:
            obj += self._swing(p, extra, y, add)
        x = ca.veccat(p, Q, QD, extra)
        self.solver = ca.nlpsol("synthesis", "ipopt", {"x": x, "f": obj, "g": ca.vertcat(*g)},
                                {"ipopt.print_level": 0, "print_time": False, "ipopt.max_iter": 1000,
                                 "ipopt.tol": 1e-9, "ipopt.sb": "yes", "expand": True})
        self.lbg, self.ubg = np.array(lbg), np.array(ubg)
        self.sizes = (npar, nq, m, extra.shape)

    def _shape_constraints(self, p, add):
        spec, lk = self.spec, self.kin.linkage
        pt = lambda n: p[2 * lk.joint_index(n):2 * lk.joint_index(n) + 2]  # noqa: E731
        for link in lk.links:
            for i, a in enumerate(link.joints):
                for b in link.joints[i + 1:]:
                    add(ca.norm_2(pt(b) - pt(a)), spec.length_min, spec.length_max)
        for (a, b), length in spec.fixed_lengths:
            add(ca.norm_2(pt(b) - pt(a)), length, length)
        for (a, b), (c, d), angle in spec.fixed_angles:
            u, w = rotate(pt(b) - pt(a), angle), pt(d) - pt(c)
            add(cross(u, w), 0, 0)
            add(ca.dot(u, w), 0, np.inf)

    def _swing(self, p, extra, y, add):
        """Two nodes at free angles (the output's minimum and maximum): speed 0 there, every node's output
        between them, their difference the swing, the minimum inside its stated window."""
        spec, c = self.spec, self.kin.closure
        nq = c.q.shape[0]
        vals = []
        for k in range(2):
            q, qd, t = extra[:nq, k], extra[nq:2 * nq, k], extra[2 * nq, k]
            phi, vel, _, yk, dyk, index = self.node(q, qd, t, p)
            add(ca.vertcat(phi, vel, dyk), 0, 0)
            if index.shape[0]:
                add(index, spec.index_min * 1.05 + 0.005, np.inf)   # a margin: the index dips between nodes
            vals.append(yk)
        low, high = vals
        add(y - low, 0, np.inf)
        add(high - y, 0, np.inf)
        add(high - low, spec.swing - spec.swing_tol, spec.swing + spec.swing_tol)
        t_min = spec.minimum_at - self.kin.linkage.crank.reference_angle
        add(extra[2 * nq, 0] - t_min, -spec.minimum_tol, spec.minimum_tol)
        return 0

    def start_values(self, coords, q):
        """Initial values from a screened geometry's poses (360 angles from the reference)."""
        spec = self.spec
        npar, nq, m, xshape = self.sizes
        grid = self.kin.linkage.crank.reference_angle + 2 * math.pi * np.arange(len(q)) / len(q)
        pick = lambda t: int(round(((t - grid[0]) % (2 * math.pi)) / (grid[1] - grid[0]))) % len(q)  # noqa: E731
        kin = self.kin.with_geometry(coords)
        qd = np.asarray(kin._map("derivatives", len(q))(q.T, grid[None, :], np.repeat(coords[:, None], len(q), 1))[0]).T
        Q = np.array([q[pick(t)] for t in self.nodes]).T
        QD = np.array([qd[pick(t)] for t in self.nodes]).T
        parts = [coords, Q[:, 1:].T.ravel(), QD.T.ravel()]
        if xshape[1]:
            y = kin.output(poses_only(kin, grid, q, qd), spec.swing_output)[0]
            cols = []
            for k in (int(np.argmin(y)), int(np.argmax(y))):
                cols.append(np.concatenate([q[k], qd[k], [grid[k]]]))
            parts.append(np.array(cols).ravel())
        return np.concatenate(parts)

    def solve(self, coords, q) -> Candidate | None:
        x0 = self.start_values(coords, q)
        npar = self.sizes[0]
        lbx = np.full(x0.shape, -np.inf)
        ubx = np.full(x0.shape, np.inf)
        lk = self.kin.linkage
        for name in self.spec.fixed_joints:
            i = 2 * lk.joint_index(name)
            lbx[i:i + 2] = ubx[i:i + 2] = x0[i:i + 2]
        placed = {b for (_, b), _ in self.spec.fixed_lengths} | {d for _, (_, d), _ in self.spec.fixed_angles}
        for j in lk.joints:
            if j.name not in placed:   # a joint placed by a fixed length or angle follows its anchor
                i = 2 * lk.joint_index(j.name)
                lbx[i:i + 2], ubx[i:i + 2] = -self.spec.box, self.spec.box
        for name in self.spec.fixed_joints:
            i = 2 * lk.joint_index(name)
            lbx[i:i + 2] = ubx[i:i + 2] = lk.reference()[i:i + 2]
        sol = self.solver(x0=x0, lbx=lbx, ubx=ubx, lbg=self.lbg, ubg=self.ubg)
        status = self.solver.stats()["return_status"]
        coords = np.asarray(sol["x"]).ravel()[:npar]
        try:
            kin = self.kin.with_geometry(coords)
            cycle = kin.solve(self.problem.angles)
        except ProblemError as exc:
            self.last_refusal = exc.message
            return None
        if not self.spec.shape_ok(kin.linkage):
            self.last_refusal = f"IPOPT ended ({status}) outside the bounds or the fixed shape"
            return None
        report = fit_report(kin, cycle, self.spec, self.problem)
        if report["min_transmission_index"] < self.spec.index_min - 1e-6:
            self.last_refusal = f"transmission index {report['min_transmission_index']:.3g} between the nodes"
            return None
        return Candidate(coords, report["rms_m_s"], report, status)
