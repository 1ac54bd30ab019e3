"""The load a drive moves, and the motor torque and speed it asks for over a motion.

Where it sits: ``motion`` gives the load motion ``s, v, a``; a transmission
(transmission.py) maps it to the motor shaft; this module adds the load
(moving mass, gravity, load forces) and returns the motor torque and its
breakdown (:class:`TorqueTerms`). checks.py and sizing.py evaluate it over a
cycle; the design writes its collocation constraints with the same function.

    # numeric: s, v, a are numpy arrays of the load (bar) motion over one whole cycle
    terms = load_torque(motor, transmission, load, s, v, a)
    terms.total            # motor torque [N m], same shape as s
    terms.omega            # motor speed [rad/s]
    terms.as_dict()        # the breakdown: rotor inertia, transmission inertia, moving mass,
                           # gravity, each load force (they add up to ``total``)

    # symbolic: the SAME function on CasADi SX/MX (collocation constraints)
    terms = load_torque(motor, transmission, load, s_sym, v_sym, a_sym)
    opti.subject_to(-motor.peak_torque <= terms.total)   # etc.

``motor`` is a :class:`~strokeopt.drive.catalogue.ServoMotor` (or just its rotor
inertia in kg m^2); ``transmission`` any :class:`~strokeopt.drive.transmission.Transmission`
(a :class:`~strokeopt.drive.transmission.BeltPulley` carries its pulley's inertia);
``load`` a :class:`Load` (moving mass, gravity along the axis, load forces).

The model (rigid, one degree of freedom): with the load at ``x = f(phi)``,
``mu = dx/dphi``, ``nu = d2x/dphi2`` (AD, transmission.py) the force the
transmission applies to the load is ``F = m (a - g) - sum(F_load)`` and the
motor torque ``T = (J_rotor + J_transmission) eps + mu F``; a transmission whose own inertia varies (a linkage's links) adds
``J(phi) eps + 1/2 J'(phi) omega^2`` and the torques of its own loads (:meth:`Transmission.own_terms`). A member between motor and load (a nut,
a lever: :class:`Member`) of inertia ``I`` on a stage ``q(phi)`` adds ``I q' (q' eps + q'' omega^2)``,
which is ``J(phi) eps + 1/2 J'(phi) omega^2`` with ``J = I q'^2``; the load's own term is the same with
``I = m``, ``q = x``.
"""

from __future__ import annotations

from dataclasses import dataclass

import casadi as ca
import numpy as np

G = 9.81  # m/s^2, as the thesis uses (appendix 2)


def _symbolic(*xs) -> bool:
    return any(isinstance(x, (ca.SX, ca.MX)) for x in xs)


def _where(cond, a, b):
    """``a`` where ``cond`` else ``b``: numpy for numbers and arrays, ``if_else`` for CasADi symbols."""
    if _symbolic(cond, a, b):
        return ca.if_else(cond, a, b)
    return np.where(cond, a, b)


@dataclass(frozen=True)
class LoadForce:
    """A force on the load along its axis [N], as a function of the load position.

    ``kind = "constant"``: ``direction * force`` everywhere.
    ``kind = "spring"``: a compression spring met at ``contact_position`` [m]:
    beyond it (against ``direction``) it pushes with ``force`` (its preload)
    plus ``stiffness`` times the penetration; before it, nothing.
    ``kind = "friction"``: against the load's velocity ``v``, ``-(force sign + viscous v)`` (Coulomb ``force``
    [N], ``viscous`` [N s/m]; :func:`friction_sign`: at rest, against the acceleration ``a`` that starts the
    motion); on CasADi symbols smooth within ``smoothing`` [m/s] (the collocation's form), on numbers exact (the
    design's fine-grid check judges the exact one).
    ``direction`` is +1 (pushes towards +x) or -1. ``spring``: the name of the contact model's spring
    (``[model.springs]``) ``force`` and ``stiffness`` were derived from, or None (given in ``[drive]``).
    """

    name: str
    kind: str
    direction: float
    force: float
    stiffness: float = 0.0
    contact_position: float = 0.0
    spring: str | None = None
    viscous: float = 0.0
    smoothing: float = 1e-3

    def __call__(self, s, v=None, a=None):
        if self.kind == "constant":
            return self.direction * self.force + 0 * s
        if self.kind == "friction":
            if v is None:
                raise ValueError(f"the friction {self.name!r} needs the load's velocity")
            return -(self.force * friction_sign(v, a, self.smoothing) + self.viscous * v) + 0 * s
        penetration = self.direction * (self.contact_position - s)
        return _where(penetration > 0, self.direction * (self.force + self.stiffness * penetration), 0 * s)


def friction_sign(v, a=None, smoothing: float = 1e-3):
    """The direction a friction opposes: the velocity's, and at rest the acceleration's (the motion about to
    start must overcome it). Numbers: exact; CasADi symbols: ``tanh(v/w + (1 - tanh(v/w)^2) a/(w/s))``, the
    velocity's sign beyond ``w = smoothing`` and the acceleration's at rest."""
    if _symbolic(v, a):
        t = ca.tanh(v / smoothing)
        return ca.tanh(v / smoothing + (1 - t**2) * (0 if a is None else a) / smoothing)
    v = np.asarray(v, dtype=float)
    if a is None:
        return np.sign(v)
    return np.where(v != 0, np.sign(v), np.sign(a))


@dataclass(frozen=True)
class Member:
    """A body the transmission moves on the way to the load (a nut, a lever): its ``inertia`` in the
    coordinate of the transmission's ``stage`` (kg on a linear stage, kg m^2 on an angular one)."""

    name: str
    stage: str
    inertia: float


@dataclass(frozen=True)
class Load:
    """What the drive moves: a translating ``moving_mass`` [kg] (bar, carrier, belt),
    ``gravity`` [m/s^2] along the load axis (-9.81 for an axis pointing up), load forces, and the
    members between the motor and the load (:class:`Member`)."""

    moving_mass: float
    gravity: float = 0.0
    forces: tuple[LoadForce, ...] = ()
    members: tuple[Member, ...] = ()
    #: the transmission's efficiency (``[transmission] efficiency``, 0 to 1): the motor supplies what the load
    #: takes over it while driving, and gets what the load gives times it while braking
    efficiency: float = 1.0

    @property
    def has_friction(self) -> bool:
        return any(f.kind == "friction" for f in self.forces)


@dataclass(frozen=True)
class TorqueTerms:
    """Motor torque [N m] and its breakdown; numpy arrays or CasADi expressions.

    ``total = rotor_inertia + transmission_inertia + moving_mass + gravity + sum(forces)``.
    ``load_force`` is the force the transmission applies to the load [N] (the belt's
    effective tension for a belt drive).
    """

    phi: object
    omega: object
    eps: object
    rotor_inertia: object
    transmission_inertia: object
    moving_mass: object
    gravity: object
    forces: dict
    load_force: object
    total: object
    members: dict = None  # member name -> its torque (Load.members), empty for a load without members
    efficiency: object = 0.0  # what the transmission's losses add (Load.efficiency; 0 for an ideal one)

    def as_dict(self) -> dict:
        """The torque terms by name, in the order they add up to ``total``."""
        out = {"rotor_inertia": self.rotor_inertia, "transmission_inertia": self.transmission_inertia,
               "moving_mass": self.moving_mass, "gravity": self.gravity}
        out.update({f"member: {k}": v for k, v in (self.members or {}).items()})
        out.update({f"force: {k}": v for k, v in self.forces.items()})
        if not (isinstance(self.efficiency, float) and self.efficiency == 0.0):
            out["efficiency loss"] = self.efficiency
        return out


def rotor_inertia_of(motor):
    """The rotor inertia [kg m^2] of ``motor``: a ServoMotor's, or ``motor`` itself when it is a number."""
    return getattr(motor, "rotor_inertia", motor)


def load_torque(motor, transmission, load: Load, s, v, a) -> TorqueTerms:
    """Motor torque to drive ``load`` along the motion ``s, v, a`` (position, speed,
    acceleration of the load, SI) through ``transmission``.

    Works on numpy arrays (any shape) and on CasADi SX/MX symbols alike; the
    terms are written once, below. ``motor`` is a ServoMotor or a rotor
    inertia [kg m^2] (a number, or an array broadcasting against ``s``).
    """
    phi, omega, eps = transmission.motor_kinematics(s, v, a)
    if _symbolic(phi):
        _, mu, _ = transmission.symbolic_transfer(phi)
    else:
        _, mu, _ = transmission.transfer(phi)
    m = load.moving_mass
    forces = {f.name: f(s, v, a) for f in load.forces}
    f_ext = sum(forces.values()) if forces else 0 * s
    rotor = rotor_inertia_of(motor) * eps
    own = transmission.own_terms(phi, omega, eps)  # its bodies' inertia; a linkage's gravity and loads by name
    trans = own.pop("inertia")
    inertial = m * a * mu
    gravity = -m * load.gravity * mu
    force_torques = {k: -f * mu for k, f in forces.items()}
    load_force = m * (a - load.gravity) - f_ext
    through = load_force * mu  # what goes through the transmission to the load
    total = rotor + trans
    for name, torque in own.items():
        force_torques[name] = torque
        total = total + torque
    members = {}
    if load.members:  # J_i(phi) eps + 1/2 J_i'(phi) omega^2 with J_i = I_i q_i'^2: I_i q_i' (q_i' eps + q_i'' omega^2)
        stage = transmission.stage_transfer(phi)
        for member in load.members:
            d1, d2 = stage[member.stage]
            members[member.name] = member.inertia * d1 * (d1 * eps + d2 * omega**2)
            through = through + members[member.name]
    loss = efficiency_loss(through, omega, load.efficiency)
    total = total + through + loss
    return TorqueTerms(phi, omega, eps, rotor, trans, inertial, gravity, force_torques, load_force, total, members,
                       loss)


#: The power over which the collocation's smooth efficiency turns from driving to braking [W]; the turn is centred
#: at -3 times it, so a motor at rest under torque (starting or holding) counts as driving, as the exact rule does.
EFFICIENCY_SMOOTHING_W = 0.01


def efficiency_loss(through, omega, efficiency: float):
    """What a transmission of ``efficiency`` adds to the torque ``through`` it at the motor speed ``omega``: the
    motor supplies ``through / efficiency`` while it drives the load (power ``through * omega >= 0``) and gets
    ``through * efficiency`` back while the load drives it. On CasADi symbols the switch is smooth
    (``tanh(power / 0.01 W + 3)``), on numbers exact."""
    if efficiency == 1.0:
        return 0.0 * through
    up, down = 1.0 / efficiency - 1.0, efficiency - 1.0
    if _symbolic(through, omega):
        driving = (1 + ca.tanh(through * omega / EFFICIENCY_SMOOTHING_W + 3.0)) / 2
        return (down + (up - down) * driving) * through
    return np.where(np.asarray(through) * np.asarray(omega) >= 0, up, down) * through


def reflected_inertia(transmission, load: Load, phi=None) -> float:
    """Load inertia seen by the motor shaft [kg m^2]: transmission inertia + m * max(mu^2) over ``phi``."""
    phi = np.zeros(1) if phi is None else np.asarray(phi, dtype=float)
    _, mu, _ = transmission.transfer(phi)
    j = load.moving_mass * np.asarray(mu) ** 2 + transmission.inertia_at(phi)
    if load.members:
        stage = transmission.stage_transfer(phi)
        j = j + sum(m.inertia * np.asarray(stage[m.stage][0]) ** 2 for m in load.members)
    return float(np.max(j))


def read_efficiency(fields) -> float:
    """``[transmission] efficiency`` of a belt, gearbox or screw: 0.1 (a worm gear at its worst) to 1 (ideal, the
    default), :func:`efficiency_loss`'s."""
    return fields.number("efficiency", 1.0, min=0.1, max=1.0)
