"""Drive: the motor torque and speed over a cycle, and the sizing checks.

How to use it from another module (``design.py``, a notebook)::

    from strokeopt.drive import load_torque, drive_checks, DriveLimits, BeltSpec

    # numeric: s, v, a are numpy arrays of the load (bar) motion over one whole cycle
    terms = load_torque(motor, transmission, load, s, v, a)
    terms.total            # motor torque [N m], same shape as s
    terms.omega            # motor speed [rad/s]
    terms.as_dict()        # the breakdown: rotor inertia, transmission inertia, moving mass,
                           # gravity, each load force (they add up to ``total``)

    # symbolic: the SAME function on CasADi SX/MX (collocation constraints)
    terms = load_torque(motor, transmission, load, s_sym, v_sym, a_sym)
    opti.subject_to(-motor.peak_torque <= terms.total)   # etc.

    # the checks of a sampled cycle (t from 0 to the period, both ends included)
    checks = drive_checks(motor, transmission, load, t, s, v, a,
                          limits=DriveLimits(peak_limit_pct=300), belt=belt_spec, grooves=28)
    for c in checks: c.name, c.value, c.limit, c.unit, c.margin, c.ok

``motor`` is a :class:`~strokeopt.actuators.ServoMotor` (or just its rotor
inertia in kg m^2); ``transmission`` any :class:`~strokeopt.transmission.Transmission`
(a :class:`BeltPulley` carries its pulley's inertia); ``load`` a :class:`Load`
(moving mass, gravity along the axis, load forces). The problem file's
``[drive]`` section becomes a :class:`DriveSpec` (``problem.drive``), whose
``.load`` and ``.limits`` feed the calls above.

The model (rigid, one degree of freedom): with the load at ``x = f(phi)``,
``mu = dx/dphi``, ``nu = d2x/dphi2`` (AD, transmission.py) the force the
transmission applies to the load is ``F = m (a - g) - sum(F_load)`` and the
motor torque ``T = (J_rotor + J_transmission) eps + mu F``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path

import casadi as ca
import numpy as np

from .errors import ProblemError

G = 9.81  # m/s^2, as the thesis uses (appendix 2)
CHECK_NAMES = ("peak_torque", "overload", "rms_torque", "peak_speed", "inertia_ratio", "belt_width", "belt_breaking")


def _symbolic(*xs) -> bool:
    return any(isinstance(x, (ca.SX, ca.MX)) for x in xs)


def _where(cond, a, b):
    """``a`` where ``cond`` else ``b``: numpy for numbers and arrays, ``if_else`` for CasADi symbols."""
    if _symbolic(cond, a, b):
        return ca.if_else(cond, a, b)
    return np.where(cond, a, b)


# --------------------------------------------------------------------------- the load


@dataclass(frozen=True)
class LoadForce:
    """A force on the load along its axis [N], as a function of the load position.

    ``kind = "constant"``: ``direction * force`` everywhere.
    ``kind = "spring"``: a compression spring met at ``contact_position`` [m]:
    beyond it (against ``direction``) it pushes with ``force`` (its preload)
    plus ``stiffness`` times the penetration; before it, nothing.
    ``direction`` is +1 (pushes towards +x) or -1.
    """

    name: str
    kind: str
    direction: float
    force: float
    stiffness: float = 0.0
    contact_position: float = 0.0

    def __call__(self, s):
        if self.kind == "constant":
            return self.direction * self.force + 0 * s
        penetration = self.direction * (self.contact_position - s)
        return _where(penetration > 0, self.direction * (self.force + self.stiffness * penetration), 0 * s)


@dataclass(frozen=True)
class Load:
    """What the drive moves: a translating ``moving_mass`` [kg] (bar, carrier, belt),
    ``gravity`` [m/s^2] along the load axis (-9.81 for an axis pointing up), load forces."""

    moving_mass: float
    gravity: float = 0.0
    forces: tuple[LoadForce, ...] = ()


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

    def as_dict(self) -> dict:
        """The torque terms by name, in the order they add up to ``total``."""
        out = {"rotor_inertia": self.rotor_inertia, "transmission_inertia": self.transmission_inertia,
               "moving_mass": self.moving_mass, "gravity": self.gravity}
        out.update({f"force: {k}": v for k, v in self.forces.items()})
        return out


def _rotor_inertia(motor):
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
    forces = {f.name: f(s) for f in load.forces}
    f_ext = sum(forces.values()) if forces else 0 * s
    rotor = _rotor_inertia(motor) * eps
    trans = transmission.inertia * eps
    inertial = m * a * mu
    gravity = -m * load.gravity * mu
    force_torques = {k: -f * mu for k, f in forces.items()}
    load_force = m * (a - load.gravity) - f_ext
    total = rotor + trans + load_force * mu
    return TorqueTerms(phi, omega, eps, rotor, trans, inertial, gravity, force_torques, load_force, total)


def reflected_inertia(transmission, load: Load, phi=None) -> float:
    """Load inertia seen by the motor shaft [kg m^2]: transmission inertia + m * max(mu^2) over ``phi``."""
    phi = np.zeros(1) if phi is None else np.asarray(phi, dtype=float)
    _, mu, _ = transmission.transfer(phi)
    return float(transmission.inertia + load.moving_mass * np.max(np.asarray(mu) ** 2))


# --------------------------------------------------------------------------- checks


@dataclass(frozen=True)
class Check:
    """One sizing check: ``value`` must not exceed ``limit`` (both in ``unit``).

    ``margin = 1 - value/limit``: the fraction of the limit still free
    (negative when violated).
    """

    name: str
    value: float
    limit: float
    unit: str

    @property
    def margin(self) -> float:
        if self.limit > 0:
            return 1.0 - self.value / self.limit
        return -math.inf if self.value > 0 else 0.0

    @property
    def ok(self) -> bool:
        return bool(self.value <= self.limit)

    def as_dict(self) -> dict:
        return {"name": self.name, "value": self.value, "limit": self.limit, "unit": self.unit,
                "margin": self.margin, "ok": self.ok}


@dataclass(frozen=True)
class DriveLimits:
    """Limits that belong to the application, not to a part.

    ``peak_limit_pct``: the servo drive's peak current as % of the motor's
    rated torque (Digitax ST: 300 %, thesis 4.6). ``max_inertia_ratio``:
    largest load-to-rotor inertia ratio accepted (a common servo guideline,
    not from the thesis).
    """

    peak_limit_pct: float = 300.0
    max_inertia_ratio: float = 10.0


@dataclass(frozen=True)
class BeltSpec:
    """The belt of the drive and how it is checked (thesis appendix 2).

    ``allowable_tension`` [N per reference width], when given, replaces the
    catalogue row for the pulley's groove count.
    """

    belt: object  # actuators.Belt
    method: object  # actuators.BeltMethod
    service_factor: float = 1.5
    cord: str = "glass"
    allowable_tension: float | None = None


@dataclass(frozen=True)
class BeltLoad:
    """The numbers of the belt check (thesis appendix 2)."""

    peak_tension: float  # T_e [N]
    design_tension: float  # S * T_e [N]
    allowable_tension: float  # per reference width [N]
    required_width_factor: float
    breaking_load: float  # peak_tension_factor * T_e * safety [N]


def belt_load(peak_tension, grooves: int, spec: BeltSpec) -> BeltLoad:
    """Apply the catalogue method of thesis appendix 2 to a peak belt tension ``T_e`` [N]."""
    allow = spec.allowable_tension if spec.allowable_tension is not None else spec.method.allowable_tension_for(grooves)
    design = spec.service_factor * peak_tension
    required = design / allow if allow > 0 else math.inf
    breaking = spec.method.peak_tension_factor * peak_tension * spec.method.breaking_safety
    return BeltLoad(peak_tension, design, allow, required, breaking)


def _cycle_values(total, omega, load_force, t):
    """Peak |torque|, RMS torque over the whole cycle (trapezoidal in time), peak |speed|, peak |force|.

    ``total`` may carry leading axes (motors); the last axis is the samples.
    """
    period = t[-1] - t[0]
    if not period > 0:
        raise ValueError("the samples must span one whole cycle (t[-1] > t[0])")
    peak = np.max(np.abs(total), axis=-1)
    sq = total**2
    rms = np.sqrt(np.sum((sq[..., 1:] + sq[..., :-1]) * np.diff(t), axis=-1) / (2 * period))
    return peak, rms, float(np.max(np.abs(omega))), float(np.max(np.abs(load_force)))


def _checks(peak, rms, peak_speed, peak_force, motor, reflected, limits: DriveLimits,
            belt: BeltSpec | None, grooves: int | None) -> list[Check]:
    rpm = 60 / (2 * math.pi)
    out = [
        Check("peak_torque", float(peak), motor.peak_torque, "N m"),
        Check("overload", float(100 * peak / motor.rated_torque), limits.peak_limit_pct, "%"),
        Check("rms_torque", float(rms), motor.rated_torque, "N m"),
        Check("peak_speed", peak_speed * rpm, motor.rated_speed * rpm, "rpm"),
        Check("inertia_ratio", reflected / motor.rotor_inertia, limits.max_inertia_ratio, "-"),
    ]
    if belt is not None:
        if grooves is None:
            raise ValueError("the belt checks need the groove count of the pulley")
        bl = belt_load(peak_force, grooves, belt)
        if belt.cord not in belt.belt.breaking_tension:
            raise ProblemError("catalogue", f"belt {belt.belt.name}", f"has no breaking tension for {belt.cord} cord")
        out += [Check("belt_width", bl.required_width_factor, belt.belt.width_factor, "-"),
                Check("belt_breaking", bl.breaking_load, belt.belt.breaking_tension[belt.cord], "N")]
    return out


def drive_checks(motor, transmission, load: Load, t, s, v, a, *, limits: DriveLimits | None = None,
                 belt: BeltSpec | None = None, grooves: int | None = None) -> list[Check]:
    """The sizing checks of one motor and transmission over a sampled cycle.

    ``t`` must run over one whole cycle (0 to the period, both ends included,
    dwells too): the RMS torque is the time average over it. Checks:
    peak torque vs the motor's peak torque, overload (peak / rated) vs the
    drive's peak limit, RMS torque vs rated torque, peak speed vs rated speed,
    load-to-rotor inertia ratio, and with ``belt`` the belt width and
    breaking checks of thesis appendix 2 (``grooves`` of the smaller pulley).
    """
    t, s, v, a = (np.asarray(x, dtype=float) for x in (t, s, v, a))
    terms = load_torque(motor, transmission, load, s, v, a)
    peak, rms, peak_speed, peak_force = _cycle_values(terms.total, terms.omega, terms.load_force, t)
    reflected = reflected_inertia(transmission, load, terms.phi)
    return _checks(peak, rms, peak_speed, peak_force, motor, reflected, limits or DriveLimits(), belt, grooves)


def binding_check(checks: list[Check]) -> Check:
    """The check with the smallest margin: the one that binds first."""
    return min(checks, key=lambda c: c.margin)


# --------------------------------------------------------------------------- problem file


@dataclass(frozen=True)
class DriveSpec:
    """The ``[drive]`` section of a problem file, SI units."""

    motor: str | None
    load: Load
    limits: DriveLimits
    profile: str = "GT3"
    teeth_min: int = 14
    teeth_max: int = 52
    belt: str | None = None
    belt_cord: str = "glass"
    service_factor: float = 1.5
    allowable_tension: float | None = None
    catalogue_files: tuple[str, ...] = ()
    file: str = ""

    def catalogue(self, extra_files=()):
        """The shipped catalogue plus this problem's and ``extra_files``' catalogue files."""
        from .actuators import load_catalogue

        return load_catalogue(list(self.catalogue_files) + list(extra_files))

    def belt_spec(self, catalogue) -> BeltSpec | None:
        if self.belt is None:
            return None
        belt = catalogue.belt(self.belt, (self.file, "drive.belt"))
        if self.profile not in catalogue.belt_methods:
            raise ProblemError(self.file, "drive.belt", f"the catalogue has no belt method for profile {self.profile}")
        if self.belt_cord not in belt.breaking_tension:
            raise ProblemError(self.file, "drive.belt_cord", f"belt {belt.name} has no breaking tension for "
                                                             f"{self.belt_cord} cord")
        return BeltSpec(belt, catalogue.belt_methods[self.profile], self.service_factor, self.belt_cord,
                        self.allowable_tension)


def parse_drive(f, base_dir: Path | None = None) -> DriveSpec:
    """Read the ``[drive]`` table (a :class:`~strokeopt.problem.Fields`) of a problem file."""
    from .actuators import BELT_CORDS, PROFILE_PITCH

    motor = f.string("motor", None)
    mass = f.number("moving_mass_kg", positive=True)
    gravity_dir = f.string("gravity", "down", choices=("down", "up", "off"))
    # positions in problem files are measured upward
    gravity = {"down": -G, "up": G, "off": 0.0}[gravity_dir]
    limits = DriveLimits(f.number("peak_limit_pct", 300.0, positive=True),
                         f.number("max_inertia_ratio", 10.0, positive=True))
    profile = f.string("pulley_profile", "GT3", choices=tuple(PROFILE_PITCH))
    tmin = f.number("pulley_teeth_min", 14, integer=True, min=1)
    tmax = f.number("pulley_teeth_max", 52, integer=True, min=1)
    if tmax < tmin:
        raise f.error("pulley_teeth_max", f"{tmax} is below pulley_teeth_min {tmin}")
    belt = f.string("belt", None)
    cord = f.string("belt_cord", "glass", choices=BELT_CORDS)
    service = f.number("belt_service_factor", 1.5, positive=True)
    allowable = f.number("belt_allowable_tension_N", None, positive=True)
    files = f.raw("catalogues", [])
    if not isinstance(files, list) or not all(isinstance(x, str) for x in files):
        raise f.error("catalogues", "must be an array of file names")
    base = base_dir or Path(".")
    resolved = []
    for x in files:
        p = Path(x) if Path(x).is_absolute() else base / x
        if not p.is_file():
            raise f.error("catalogues", f"catalogue file {x!r} not found (looked for {p})")
        resolved.append(str(p))
    forces = []
    for row in f.tables("load_forces", required=False):
        name = row.string("name")
        kind = row.string("kind", choices=("spring", "constant"))
        direction = {"up": 1.0, "down": -1.0}[row.string("direction", choices=("up", "down"))]
        if kind == "spring":
            forces.append(LoadForce(name, kind, direction, row.number("preload_N", 0.0, min=0.0),
                                    row.number("stiffness_N_m", min=0.0),
                                    row.number("contact_position_mm") * 1e-3))
        else:
            forces.append(LoadForce(name, kind, direction, row.number("force_N", min=0.0)))
        row.finish()
    if len({x.name for x in forces}) != len(forces):
        raise f.error("load_forces", "two load forces have the same name")
    f.finish()
    return DriveSpec(motor, Load(mass, gravity, tuple(forces)), limits, profile, tmin, tmax, belt, cord, service,
                     allowable, tuple(resolved), f.file)
