"""Dynamics of a crank-driven linkage at constant crank speed: reduced inertia, input torque by the power
balance, and the same torque with every joint reaction by Newton-Euler (the check of the first).

Reduced inertia ``J(theta) = sum m |dc/dtheta|^2 + I (dphi/dtheta)^2`` (c a link's centre of gravity, phi
its angle) and its derivative come by AD: the centres and angles are expressions of the pose, evaluated
on the Taylor polynomial of q(theta + s) (closure.taylor) and differentiated in s. The power balance at
constant crank speed omega gives the crank torque

    M(theta) = 1/2 J'(theta) omega^2 + V'(theta) - sum_i F_i(theta) (u_i . dr_i/dtheta)

(V the potential of gravity, F_i a process force of magnitude F_i(theta) along the unit vector u_i at
the point r_i). Newton-Euler writes force and moment balances of every moving link with the joint
reactions and the crank torque as unknowns and solves them at each angle: a different computation, from
the accelerations of the centres of gravity, that must give the same torque.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import casadi as ca
import numpy as np

from .closure import rotate
from .kinematics import Cycle, Kinematics


@dataclass
class Dynamics:
    theta: np.ndarray          # [rad]
    omega: float               # crank speed [rad/s]
    J: np.ndarray              # reduced inertia at the crank [kg m^2]
    dJ: np.ndarray             # dJ/dtheta [kg m^2/rad]
    gravity_torque: np.ndarray # V'(theta) [N m]
    load_torque: np.ndarray    # -sum F_i u_i . r_i' [N m] (what the crank must add against the loads)
    torque: np.ndarray         # power balance crank torque [N m]
    torque_ne: np.ndarray      # Newton-Euler crank torque [N m]
    reactions: dict            # "joint (link/link)" -> |force| over the cycle [N]

    def to_dict(self) -> dict:
        i_max, i_min = int(np.argmax(self.torque)), int(np.argmin(self.torque))
        rel = np.abs(self.torque - self.torque_ne) / max(np.abs(self.torque).max(), 1e-300)
        return {"omega_rad_s": self.omega,
                "reduced_inertia_kg_m2": {"min": float(self.J.min()), "max": float(self.J.max())},
                "torque_N_m": {"max": float(self.torque[i_max]), "max_at_deg": _deg(self.theta[i_max]),
                               "min": float(self.torque[i_min]), "min_at_deg": _deg(self.theta[i_min]),
                               "rms": float(np.sqrt(np.mean(self.torque ** 2)))},
                "newton_euler_max_relative_difference": float(rel.max()),
                "peak_reactions_N": {k: float(v.max()) for k, v in self.reactions.items()}}


def _deg(theta: float) -> float:
    return round(math.degrees(theta) % 360, 6)


def load_magnitude(load, theta):
    """A load's magnitude [N] over the input angle: linear from force_start to force_end in its window; numpy
    for numbers, CasADi (``fmod``, ``if_else``) for symbols."""
    span = load.end - load.start
    if isinstance(theta, (ca.SX, ca.MX)):
        turn = 2 * math.pi
        rel = ca.fmod(ca.fmod(theta - load.start, turn) + turn, turn)
        ramp = load.force_start + (load.force_end - load.force_start) * ca.fmin(rel / span, 1)
        return ca.if_else(rel <= span + 1e-12, ramp, 0)
    rel = (theta - load.start) % (2 * math.pi)
    inside = rel <= span + 1e-12
    return np.where(inside, load.force_start + (load.force_end - load.force_start) * np.minimum(rel / span, 1), 0.0)


def _terms(kin: Kinematics) -> ca.Function:
    """J, J', V', the per-unit-force generalised loads, and what Newton-Euler needs, at one pose."""
    c, lk = kin.closure, kin.linkage
    pts = c.points(c.q, c.theta, c.p)
    s, dqs, _ = c.taylor(c.q)
    energy, potential, ne = 0, 0, []
    for link in lk.links:
        place, angle = c.link_frame(pts, c.p, link)
        centre = place(ca.DM(link.cg)) if link.cg is not None else pts[link.joints[0]]
        cs, phis = c.taylor(centre)[2], c.taylor(angle)[2]
        vel, rate = ca.jacobian(cs, s), ca.jacobian(phis, s)
        energy += link.mass * ca.dot(vel, vel) + link.inertia_cg * rate ** 2
        potential += link.mass * lk.gravity * cs[1]
        ne += [centre, ca.jacobian(vel, s), ca.jacobian(rate, s)]
    unit_loads, load_geo = [], []
    for load in lk.loads:
        link = lk.link(load.link)
        line = pts[link.joints[1]] - pts[link.joints[0]]
        u = rotate(line / ca.norm_2(line), load.direction)
        r = c.taylor(pts[load.joint])[2]
        unit_loads.append(ca.dot(u, ca.jacobian(r, s)))
        load_geo += [u, pts[load.joint]]
    at0 = lambda e: ca.substitute(e, s, 0)  # noqa: E731
    outs = [at0(energy), at0(ca.jacobian(energy, s)), at0(ca.jacobian(potential, s)),
            at0(ca.vertcat(*unit_loads)) if unit_loads else ca.SX(0, 1),
            at0(ca.vertcat(*ne)), ca.vertcat(*load_geo) if load_geo else ca.SX(0, 1),
            ca.vertcat(*[pts[j.name] for j in lk.joints if j.name in pts])]
    return ca.Function("dynamics_terms", [c.q, *dqs, c.theta, c.p], outs)


def _mapped_terms(kin: Kinematics, cycle: Cycle):
    lk = kin.linkage   # the Function holds the masses and centres of gravity: they are in its key
    key = ("dynamics", len(cycle.theta), tuple((k.mass, k.cg, k.inertia_cg) for k in lk.links), lk.loads, lk.gravity)
    if key not in kin._mapped:
        kin._mapped[key] = _terms(kin).map(len(cycle.theta))
    return _along(kin, cycle, key)


def reduced_terms(kin: Kinematics, cycle: Cycle) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """The crank's reduced inertia ``J`` [kg m^2], ``J'`` [kg m^2/rad], the gravity torque ``V'`` [N m] and each
    process load's torque per newton of its magnitude ``u . dr/dtheta`` [m] (n x loads) over ``cycle``: what a
    transmission through the linkage needs of its dynamics, at any crank speed."""
    J, dJ, dV, unit, *_ = _mapped_terms(kin, cycle)
    return J, dJ, dV, unit.reshape(len(cycle.theta), -1)


def analyse_dynamics(kin: Kinematics, cycle: Cycle, omega: float) -> Dynamics:
    """Reduced inertia, power-balance torque and Newton-Euler reactions over ``cycle`` at ``omega``."""
    J, dJ, dV, unit, ne, geo, joints = _mapped_terms(kin, cycle)
    th = cycle.theta
    forces = np.array([load_magnitude(load, th) for load in kin.linkage.loads]).T.reshape(len(th), -1)
    load_torque = -np.sum(forces * unit, axis=1) if unit.size else np.zeros(len(th))
    torque = 0.5 * dJ * omega ** 2 + dV + load_torque
    torque_ne, reactions = _newton_euler(kin, omega, ne, geo, joints, forces)
    return Dynamics(th, omega, J, dJ, dV, load_torque, torque, torque_ne, reactions)


def _along(kin, cycle, key):
    n = len(cycle.theta)
    vals = kin._mapped[key](cycle.q.T, cycle.dq.T, cycle.d2q.T, cycle.d3q.T, cycle.theta[None, :],
                            np.repeat(kin.p[:, None], n, 1))
    vals = [np.asarray(v).T for v in vals]
    return [vals[0].ravel(), vals[1].ravel(), vals[2].ravel(), *vals[3:]]


def _pairs(kin: Kinematics):
    """Revolute pairs: (joint, body on which the reaction acts +, body on which it acts -)."""
    lk = kin.linkage
    bodies = {j.name: (["ground"] if j.ground else []) for j in lk.joints}
    for link in lk.links:
        for j in link.joints:
            bodies[j].append(link.name)
    return [(j, members[0], other) for j, members in bodies.items() for other in members[1:]]


def _newton_euler(kin: Kinematics, omega: float, ne, geo, joints, forces):
    """Solve force and moment balances of every moving link for the reactions and the crank torque."""
    lk = kin.linkage
    moving = [link.name for link in lk.links]
    pairs = _pairs(kin)
    names = [j.name for j in lk.joints]
    n_unk = 2 * len(pairs) + 1
    torques, reactions = np.zeros(len(ne)), np.zeros((len(ne), len(pairs)))
    g = np.array([0.0, -lk.gravity])
    for k in range(len(ne)):
        A = np.zeros((3 * len(moving), n_unk))
        b = np.zeros(3 * len(moving))
        pos = joints[k].reshape(-1, 2)
        for i, link in enumerate(lk.links):
            centre, acc, alpha = ne[k][5 * i:5 * i + 2], ne[k][5 * i + 2:5 * i + 4], ne[k][5 * i + 4]
            rows = slice(3 * i, 3 * i + 3)
            for p_idx, (joint, plus, minus) in enumerate(pairs):
                sign = 1.0 if plus == link.name else (-1.0 if minus == link.name else 0.0)
                if sign:
                    arm = pos[names.index(joint)] - centre
                    A[rows, 2 * p_idx:2 * p_idx + 2] = sign * np.array([[1, 0], [0, 1], [-arm[1], arm[0]]])
            if link.name == lk.crank.link:
                A[3 * i + 2, -1] = 1.0
            rhs = np.concatenate([link.mass * (acc * omega ** 2 - g), [link.inertia_cg * alpha * omega ** 2]])
            for m, load in enumerate(lk.loads):
                if load.link == link.name:
                    f = forces[k, m] * geo[k][4 * m:4 * m + 2]
                    arm = geo[k][4 * m + 2:4 * m + 4] - centre
                    rhs -= np.array([f[0], f[1], arm[0] * f[1] - arm[1] * f[0]])
            b[rows] = rhs
        x = np.linalg.solve(A, b)
        torques[k] = x[-1]
        reactions[k] = np.hypot(x[0:-1:2], x[1:-1:2])
    return torques, {f"{j} ({a}/{o})": reactions[:, i] for i, (j, a, o) in enumerate(pairs)}
