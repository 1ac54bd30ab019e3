"""Transmissions: motor angle -> load position.

A transmission is its position function ``x = f(phi)`` (metres from radians),
written once with CasADi operations. Its first and second transfer functions
``mu = dx/dphi`` and ``nu = d2x/dphi2`` come from algorithmic differentiation,
so a position-dependent transmission (crank, screw and lever) needs nothing
but its position function.
"""

from __future__ import annotations

import math

import casadi as ca
import numpy as np

from ._casadi import evaluate


class Transmission:
    """Base: subclasses define :meth:`position` (CasADi-friendly)."""

    name = "transmission"

    def position(self, phi):
        raise NotImplementedError

    def _functions(self):
        if not hasattr(self, "_fns"):
            phi = ca.SX.sym("phi")
            x = self.position(phi)
            mu = ca.jacobian(x, phi)
            nu = ca.jacobian(mu, phi)
            self._fns = ca.Function(f"{self.name}_transfer", [phi], [x, mu, nu], ["phi"], ["x", "mu", "nu"])
        return self._fns

    def transfer(self, phi):
        """Numeric ``(x, mu, nu)`` at motor angles ``phi`` [rad]."""
        return tuple(evaluate(self._functions(), phi))

    def symbolic_transfer(self, phi):
        return tuple(self._functions()(phi))

    def motor_angle(self, x):
        """Motor angle [rad] for the load position ``x`` [m] (inverse of :meth:`position`)."""
        raise NotImplementedError(f"{type(self).__name__} has no inverse")

    def motor_kinematics(self, x, v, a):
        """Motor angle, speed and acceleration [rad, rad/s, rad/s^2] for a load motion.

        From ``v = mu*omega`` and ``a = mu*eps + nu*omega^2``.
        """
        phi = self.motor_angle(np.asarray(x, dtype=float))
        _, mu, nu = self.transfer(phi)
        omega = np.asarray(v) / mu
        eps = (np.asarray(a) - nu * omega**2) / mu
        return phi, omega, eps


class BeltPulley(Transmission):
    """A toothed belt on a pulley of pitch radius ``r``: ``x = r*phi``."""

    name = "belt_pulley"

    def __init__(self, pitch_diameter: float):
        if not (pitch_diameter > 0 and math.isfinite(pitch_diameter)):
            raise ValueError("pitch diameter must be positive")
        self.pitch_diameter = float(pitch_diameter)

    @property
    def radius(self) -> float:
        return self.pitch_diameter / 2

    def position(self, phi):
        return self.radius * phi

    def motor_angle(self, x):
        return np.asarray(x) / self.radius

    def __repr__(self) -> str:
        return f"BeltPulley(pitch_diameter={self.pitch_diameter * 1e3:.3f} mm)"


def gt3_pitch_diameter(teeth: int) -> float:
    """Pitch diameter [m] of a GT3 (3 mm pitch) pulley: PD = z * 3 mm / pi (thesis 4.2)."""
    return teeth * 3e-3 / math.pi
