"""Transmissions: motor angle -> load position.

A transmission is its position function ``x = f(phi)`` (metres from radians),
written once with CasADi operations. Its first and second transfer functions
``mu = dx/dphi`` and ``nu = d2x/dphi2`` come from algorithmic differentiation,
so a position-dependent transmission (crank, screw and lever) needs nothing
but its position function.

Where it sits: first in the drive package. The toothed-pulley geometry
(:data:`PROFILE_PITCH`, :func:`pitch_diameter`) is here, once: the problem's
``[transmission]`` (a :class:`BeltPulley` with its teeth), the catalogue's
pulleys (catalogue.py) and the design's pulley search all use it. load.py
turns a load motion into motor torque through a transmission.
"""

from __future__ import annotations

import math

import casadi as ca
import numpy as np

from .._casadi import evaluate


class Transmission:
    """Base: subclasses define :meth:`position` (CasADi-friendly) and, to be driven
    from a prescribed load motion, :meth:`inverse_position`.

    ``inertia`` [kg m^2] is the moment of inertia the transmission adds on the
    motor shaft (a pulley, a screw); the drive adds it to the rotor's.
    """

    name = "transmission"
    inertia = 0.0

    def position(self, phi):
        raise NotImplementedError

    def inverse_position(self, x):
        """Motor angle [rad] for the load position ``x`` [m], with CasADi operations."""
        raise NotImplementedError(f"{type(self).__name__} has no inverse")

    def _functions(self):
        if not hasattr(self, "_fns"):
            phi = ca.SX.sym("phi")
            x = self.position(phi)
            mu = ca.jacobian(x, phi)
            nu = ca.jacobian(mu, phi)
            self._fns = ca.Function(f"{self.name}_transfer", [phi], [x, mu, nu], ["phi"], ["x", "mu", "nu"])
        return self._fns

    def _inverse_function(self):
        if not hasattr(self, "_inv"):
            x = ca.SX.sym("x")
            self._inv = ca.Function(f"{self.name}_inverse", [x], [self.inverse_position(x)], ["x"], ["phi"])
        return self._inv

    def transfer(self, phi):
        """Numeric ``(x, mu, nu)`` at motor angles ``phi`` [rad]."""
        return tuple(evaluate(self._functions(), phi))

    def symbolic_transfer(self, phi):
        return tuple(self._functions()(phi))

    def motor_angle(self, x):
        """Motor angle [rad] for the load position ``x`` [m] (inverse of :meth:`position`)."""
        (phi,) = evaluate(self._inverse_function(), x)
        return phi

    def motor_kinematics(self, x, v, a):
        """Motor angle, speed and acceleration [rad, rad/s, rad/s^2] for a load motion.

        From ``v = mu*omega`` and ``a = mu*eps + nu*omega^2``. Numeric
        (numpy) for numeric input, CasADi expressions for CasADi symbols.
        """
        if isinstance(x, (ca.SX, ca.MX)) or isinstance(v, (ca.SX, ca.MX)) or isinstance(a, (ca.SX, ca.MX)):
            phi = self._inverse_function()(x)
            _, mu, nu = self.symbolic_transfer(phi)
            omega = v / mu
            return phi, omega, (a - nu * omega**2) / mu
        phi = self.motor_angle(np.asarray(x, dtype=float))
        _, mu, nu = self.transfer(phi)
        omega = np.asarray(v) / mu
        eps = (np.asarray(a) - nu * omega**2) / mu
        return phi, omega, eps


#: Tooth pitch [m] of each toothed-belt profile strokeopt knows.
PROFILE_PITCH = {"GT3": 3e-3}

#: Plausible pulley tooth counts (``transmission.pulley_teeth``, the pulley ranges of [drive] and [design],
#: catalogue pulleys): below 8 teeth a toothed belt does not wrap a pulley (catalogues start at 10-14),
#: above 250 a pulley is a flywheel (catalogues end near 150-216).
TEETH_RANGE = (8, 250)


def pitch_diameter(profile: str, teeth) -> float:
    """Pitch diameter [m] of a pulley: ``z * pitch / pi`` (GT3: 3 mm pitch, thesis 4.2)."""
    return teeth * PROFILE_PITCH[profile] / math.pi


def gt3_pitch_diameter(teeth: int) -> float:
    """Pitch diameter [m] of a GT3 (3 mm pitch) pulley: PD = z * 3 mm / pi (thesis 4.2)."""
    return pitch_diameter("GT3", teeth)


class BeltPulley(Transmission):
    """A toothed belt on a pulley of pitch radius ``r``: ``x = r*phi``; ``inertia`` of the pulley [kg m^2].

    ``pitch_diameter`` and ``inertia`` may be CasADi expressions (a pulley radius that is a
    decision variable of the design NLP); numbers are checked. ``teeth`` and ``profile``
    say which toothed pulley it is (:meth:`toothed`), or are None for a pulley of any radius.
    """

    name = "belt_pulley"

    @classmethod
    def toothed(cls, teeth: int, profile: str = "GT3", inertia=0.0) -> "BeltPulley":
        """The pulley of ``teeth`` grooves of ``profile``: its pitch diameter from :func:`pitch_diameter`."""
        return cls(pitch_diameter(profile, teeth), inertia, teeth, profile)

    def __init__(self, pitch_diameter, inertia=0.0, teeth: int | None = None, profile: str | None = None):
        symbolic = isinstance(pitch_diameter, (ca.SX, ca.MX)) or isinstance(inertia, (ca.SX, ca.MX))
        if not symbolic:
            if not (pitch_diameter > 0 and math.isfinite(pitch_diameter)):
                raise ValueError("pitch diameter must be positive")
            if not (inertia >= 0 and math.isfinite(inertia)):
                raise ValueError("pulley inertia must be zero or positive")
            pitch_diameter, inertia = float(pitch_diameter), float(inertia)
        self.pitch_diameter = pitch_diameter
        self.inertia = inertia
        self.teeth = teeth
        self.profile = profile

    @property
    def radius(self):
        return self.pitch_diameter / 2

    def position(self, phi):
        return self.radius * phi

    def inverse_position(self, x):
        return x / self.radius

    # constant ratio: the same numbers as the AD transfer functions, without a CasADi call per sample
    def transfer(self, phi):
        phi = np.asarray(phi, dtype=float)
        return self.radius * phi, np.full_like(phi, self.radius), np.zeros_like(phi)

    def symbolic_transfer(self, phi):
        return self.radius * phi, self.radius + 0 * phi, 0 * phi

    def motor_angle(self, x):
        return np.asarray(x) / self.radius

    def motor_kinematics(self, x, v, a):
        return x / self.radius, v / self.radius, a / self.radius

    def __repr__(self) -> str:
        if isinstance(self.pitch_diameter, (ca.SX, ca.MX)):
            return "BeltPulley(pitch_diameter=<symbolic>)"
        return f"BeltPulley(pitch_diameter={self.pitch_diameter * 1e3:.3f} mm)"


class SliderCrank(Transmission):
    """A crank of radius ``r`` and connecting rod ``l`` driving a slider.

    ``x`` is the slider's travel from the dead centre (phi = 0), towards the
    crank shaft: ``x = r + l - r cos(phi) - sqrt(l^2 - r^2 sin^2(phi))``.
    The inverse uses the half turn 0 <= phi <= pi.
    """

    name = "slider_crank"

    def __init__(self, crank_radius: float, rod_length: float, inertia: float = 0.0):
        if not (crank_radius > 0 and rod_length > crank_radius):
            raise ValueError("need 0 < crank radius < rod length")
        self.r, self.l, self.inertia = float(crank_radius), float(rod_length), float(inertia)

    def position(self, phi):
        return self.r + self.l - self.r * ca.cos(phi) - ca.sqrt(self.l**2 - (self.r * ca.sin(phi)) ** 2)

    def inverse_position(self, x):
        d = self.r + self.l - x
        return ca.acos((d**2 + self.r**2 - self.l**2) / (2 * d * self.r))


class ScrewLever(Transmission):
    """Screw and lever of the knitting-machine stitch-cam drive (sources B).

    The motor turns a screw of lead ``s``; the nut moves ``x2 = s/(2 pi) phi``
    and tilts a lever, ``phi4 = atan(x2/R0)``; the lever's other arm, at
    ``offset`` [rad] to the first, moves the sleeve ``x6 = R0P tan(phi4 + offset)``
    (minus its value at phi = 0, so x6(0) = 0).
    """

    name = "screw_lever"

    def __init__(self, lead: float, R0: float, R0P: float, offset: float = 0.0, inertia: float = 0.0):
        if not (lead > 0 and R0 > 0 and R0P > 0):
            raise ValueError("lead and lever arms must be positive")
        self.lead, self.R0, self.R0P, self.offset, self.inertia = (float(lead), float(R0), float(R0P),
                                                                   float(offset), float(inertia))

    def position(self, phi):
        x2 = self.lead / (2 * math.pi) * phi
        phi4 = ca.atan(x2 / self.R0)
        return self.R0P * (ca.tan(phi4 + self.offset) - math.tan(self.offset))

    def inverse_position(self, x):
        phi4 = ca.atan(x / self.R0P + math.tan(self.offset)) - self.offset
        return 2 * math.pi / self.lead * self.R0 * ca.tan(phi4)

