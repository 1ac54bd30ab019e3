"""The ``[synthesis]`` section of a linkage file (targets, what is fixed, bounds) and the fit of a solved
linkage against it, computed by the exact analysis (kinematics.py), never by the NLP's own nodes."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..io.fields import Fields
from .kinematics import Cycle, Kinematics

NODE_STEP_DEG = 10.0   # synthesis nodes: every 10 deg of the input, plus the table's angles


@dataclass
class SynthesisSpec:
    output: str                     # the output whose speed is tabulated
    angles: list                    # input angles of the table [rad]
    speeds: np.ndarray              # [m/s] (or rad/s for an angle output)
    rms_max: float
    fixed_joints: list
    fixed_lengths: list             # [((a, b), length m)]
    fixed_angles: list              # [((a, b), (c, d), angle rad)]
    length_min: float
    length_max: float
    box: float
    index_min: float
    starts: int
    screen: int
    seed: int
    swing_output: str | None = None
    swing: float | None = None      # [rad] of swing_output
    swing_tol: float = 0.0
    minimum_at: float = 0.0         # input angle of swing_output's minimum [rad]
    minimum_tol: float = 0.0
    defect_tol: float = 2e-3        # m, trapezoidal tie between nodes (a branch change breaks it by far more)
    start_from_file: bool = False   # the file's own geometry is one of the starts
    note: str = ""                  # what the targets leave out, printed with the fit

    def shape_ok(self, linkage, tol: float = 1e-6) -> bool:
        """Bounds, fixed lengths and fixed angles hold (a start IPOPT left infeasible does not)."""
        if not self.lengths_ok_within(linkage, tol):
            return False
        xy = {j.name: j.xy for j in linkage.joints}
        for (a, b), length in self.fixed_lengths:
            if abs(np.linalg.norm(xy[b] - xy[a]) - length) > tol:
                return False
        for (a, b), (c, d), angle in self.fixed_angles:
            u, w = xy[b] - xy[a], xy[d] - xy[c]
            got = math.atan2(u[0] * w[1] - u[1] * w[0], u @ w)
            if abs(math.remainder(got - angle, 2 * math.pi)) > tol:
                return False
        return True

    def lengths_ok_within(self, linkage, tol: float) -> bool:
        return all(self.length_min - tol <= linkage.length(a, b) <= self.length_max + tol
                   for link in linkage.links for i, a in enumerate(link.joints) for b in link.joints[i + 1:])

    def nodes(self, theta0: float) -> list:
        """Node angles: every NODE_STEP_DEG from the reference, plus the table's angles (reference first)."""
        offs = set(np.round(np.arange(0, 360, NODE_STEP_DEG), 9))
        offs |= {round(math.degrees(t - theta0) % 360, 9) for t in self.angles}
        return [theta0 + math.radians(o) for o in sorted(offs)]

    def target_thetas(self, theta0: float) -> list:
        nodes = self.nodes(theta0)
        out = []
        for t in self.angles:
            o = math.radians(round(math.degrees(t - theta0) % 360, 9))
            out.append(min(nodes, key=lambda n: abs(n - theta0 - o)))
        return out

    def lengths_ok(self, linkage) -> bool:
        for link in linkage.links:
            for i, a in enumerate(link.joints):
                for b in link.joints[i + 1:]:
                    if not self.length_min <= linkage.length(a, b) <= self.length_max:
                        return False
        return True

    def screen_score(self, kin: Kinematics, q: np.ndarray, problem) -> float | None:
        """Fit of a screened geometry (poses at 1 deg): RMS speed error, weighted by the swing's miss."""
        n = len(q)
        grid = kin.linkage.crank.reference_angle + 2 * math.pi * np.arange(n) / n
        p = np.repeat(kin.p[:, None], n, 1)
        dq = np.asarray(kin._map("derivatives", n)(q.T, grid[None, :], p)[0]).T
        idx = np.asarray(kin._map("quality", n)(q.T, grid[None, :], p))
        worst = idx.min() if idx.size else 1.0
        if worst < 1e-3:
            return None
        short = max(0.0, self.index_min - worst) / max(self.index_min, 1e-9)   # below the limit: IPOPT may mend it
        stub = poses_only(kin, grid, q, dq)
        y = kin.output(stub, self.output)
        at = [int(round(((t - grid[0]) % (2 * math.pi)) / (2 * math.pi / n))) % n for t in self.angles]
        rms = math.sqrt(np.mean((y[1, at] * problem.omega - self.speeds) ** 2))
        if self.swing_output is None:
            return rms * (1 + short)
        ys = kin.output(stub, self.swing_output)[0]
        swing = ys.max() - ys.min()
        return rms * (1 + abs(swing - self.swing) / self.swing) * (1 + short)


def poses_only(kin, grid, q, dq) -> Cycle:
    """A Cycle of poses and first derivatives only (higher ones zero): enough for an output's value and speed."""
    zero = np.zeros_like(q)
    return Cycle(kin.linkage, kin.structure, grid, q, dq, zero, zero, np.zeros(len(q)), np.zeros((len(q), 0)), 0.0,
                 len(q))


def _joints(f: Fields, key: str, names, count: int, value=None) -> tuple:
    """``count`` joint names of the field ``key`` (an array of known names, none twice; ``value``: a part of the
    field's value to check in its stead)."""
    value = f.raw(key) if value is None else value
    if not (isinstance(value, list) and len(value) == count and all(isinstance(v, str) for v in value)):
        raise f.error(key, f"must be an array of {count} joint names, got {value!r}")
    for name in value:
        if name not in names:
            raise f.error(key, f"names the unknown joint {name!r}; joints: {', '.join(names)}")
    if len(set(value)) != count:
        raise f.error(key, "names a joint twice")
    return tuple(value)


def _fixed_lengths(f: Fields, names) -> list:
    """``[synthesis] fixed_lengths``: ``[((a, b), length [m])]``."""
    out = []
    for item in f.tables("fixed_lengths", required=False):
        out.append((_joints(item, "joints", names, 2), item.number("length_mm", min=1e-3, max=1e5) / 1e3))
        item.finish()
    return out


def _fixed_angles(f: Fields, names) -> list:
    """``[synthesis] fixed_angles``: ``[((a, b), (c, d), angle [rad])]``, the angle from line a-b to line c-d."""
    out = []
    for item in f.tables("fixed_angles", required=False):
        lines = item.raw("lines")
        if not (isinstance(lines, list) and len(lines) == 2):
            raise item.error("lines", f"must be two lines of two joints each ([[\"A\", \"B\"], [\"B\", \"C\"]]), "
                                      f"got {lines!r}")
        pair = [_joints(item, "lines", names, 2, ln) for ln in lines]
        out.append((pair[0], pair[1], math.radians(item.number("angle_deg", min=-360, max=360))))
        item.finish()
    return out


def read_spec(problem, f: Fields) -> SynthesisSpec:
    """Read and check ``[synthesis]`` (every field with its range)."""
    names = [j.name for j in problem.linkage.joints]
    outputs = [o.name for o in problem.linkage.outputs]
    output = f.string("output", choices=tuple(outputs))
    angles = f.raw("angles_deg")
    speeds = f.raw("speeds_m_s")
    if not (isinstance(angles, list) and isinstance(speeds, list) and len(angles) == len(speeds) >= 3
            and all(isinstance(v, (int, float)) and not isinstance(v, bool) for v in angles + speeds)):
        raise f.error("speeds_m_s", "angles_deg and speeds_m_s must be arrays of numbers of one length (3 or more)")
    for key, values in (("angles_deg", angles), ("speeds_m_s", speeds)):
        bad = [i for i, v in enumerate(values) if not math.isfinite(v)]
        if bad:
            raise f.error(key, f"entry {bad[0] + 1} is {values[bad[0]]!r}: every target must be a finite number")
    rms_max = f.number("rms_max_m_s", min=0, max=10)
    fixed = f.raw("fixed_joints", [])
    fixed_joints = _joints(f, "fixed_joints", names, len(fixed)) if isinstance(fixed, list) and fixed else ()
    if not isinstance(fixed, list):
        raise f.error("fixed_joints", f"must be an array of joint names, got {fixed!r}")
    lengths = _fixed_lengths(f, names)
    angles_fixed = _fixed_angles(f, names)
    spec = SynthesisSpec(
        output, [math.radians(a) for a in angles], np.array(speeds, dtype=float), rms_max, list(fixed_joints),
        lengths, angles_fixed,
        f.number("length_min_mm", min=0.1, max=1e4) / 1e3, f.number("length_max_mm", min=0.1, max=1e4) / 1e3,
        f.number("coordinate_box_mm", min=1, max=1e4) / 1e3, problem.min_transmission_index,
        f.number("starts", 8, min=1, max=200, integer=True), f.number("screen", 1500, min=10, max=100000, integer=True),
        f.number("seed", 1, min=0, max=2 ** 31, integer=True))
    spec.start_from_file = f.boolean("start_from_file", False)
    spec.note = f.string("note", "")
    if f.has("swing_deg"):
        spec.swing_output = f.string("swing_output", choices=tuple(outputs))
        spec.swing = math.radians(f.number("swing_deg", min=0.1, max=180))
        spec.swing_tol = math.radians(f.number("swing_tolerance_deg", min=0, max=45))
        spec.minimum_at = math.radians(f.number("minimum_at_deg", min=-360, max=720))
        spec.minimum_tol = math.radians(f.number("minimum_tolerance_deg", min=0, max=180))
    f.finish()
    return spec


def fit_report(kin: Kinematics, cycle: Cycle, spec: SynthesisSpec, problem) -> dict:
    """The fit of a solved linkage by the exact analysis: each target's error, RMS, swing, extremes."""
    n = len(cycle.theta)
    step = kin.closure.function("step")
    deriv = kin.closure.function("derivatives")
    fn = kin.output_function(spec.output)
    rows = []
    for t, v in zip(spec.angles, spec.speeds):
        k = int(round(((t - cycle.theta[0]) % (2 * math.pi)) / (2 * math.pi / n))) % n
        theta = cycle.theta[0] + (t - cycle.theta[0]) % (2 * math.pi)
        q = np.asarray(step(cycle.q[k], cycle.theta[k], theta, kin.p)[0]).ravel()
        d = [np.asarray(x).ravel() for x in deriv(q, theta, kin.p)]
        model = float(fn(q, *d, theta, kin.p)[1]) * problem.omega
        rows.append({"angle_deg": round(math.degrees(t) % 360, 6), "target": float(v), "model": model,
                     "error": model - float(v)})
    rms = math.sqrt(np.mean([r["error"] ** 2 for r in rows]))
    out = {"rms_m_s": rms, "targets": rows, "max_error_m_s": max(abs(r["error"]) for r in rows),
           "min_transmission_index": float(cycle.index.min()) if cycle.index.size else 1.0}
    if spec.swing_output is not None:
        y = kin.output(cycle, spec.swing_output)[0]
        out["swing_deg"] = math.degrees(y.max() - y.min())
        out["minimum_at_deg"] = math.degrees(cycle.theta[int(np.argmin(y))]) % 360
        out["maximum_at_deg"] = math.degrees(cycle.theta[int(np.argmax(y))]) % 360
    return out
