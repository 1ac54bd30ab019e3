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
from dataclasses import dataclass
from pathlib import Path

import casadi as ca
import numpy as np

from ..errors import ProblemError

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
        from .catalogue import load_catalogue

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
    from .catalogue import BELT_CORDS, PROFILE_PITCH

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


# --------------------------------------------------------------------------- sizing over a catalogue


@dataclass
class Candidate:
    """One motor with one pulley, checked over the cycle at ``spm``."""

    motor: object  # actuators.ServoMotor
    pulley: object  # actuators.Pulley
    spm: float
    checks: list[Check]
    peak_terms: dict  # torque terms [N m] at the instant of the peak torque
    peak_angle_deg: float
    max_spm: float | None = None
    max_spm_binding: str | None = None

    def check(self, name: str) -> Check:
        return next(c for c in self.checks if c.name == name)

    @property
    def feasible(self) -> bool:
        return all(c.ok for c in self.checks)

    @property
    def binding(self) -> str:
        """The check with the smallest margin (violated first, or closest to its limit)."""
        return binding_check(self.checks).name

    def row(self, explain: bool = False, with_max_spm: bool = False) -> dict:
        out = {
            "motor": self.motor.name,
            "pulley_teeth": self.pulley.teeth,
            "pulley_pitch_diameter_mm": self.pulley.pitch_diameter * 1e3,
            "peak_torque_N_m": self.check("peak_torque").value,
            "rms_torque_N_m": self.check("rms_torque").value,
            "overload_pct": self.check("overload").value,
            "peak_speed_rpm": self.check("peak_speed").value,
            "inertia_ratio": self.check("inertia_ratio").value,
            "feasible": self.feasible,
            "binding": self.binding,
            "margin": binding_check(self.checks).margin,
        }
        if with_max_spm:
            out["max_spm"] = self.max_spm
            out["max_spm_binding"] = self.max_spm_binding
        if explain:
            out["checks"] = [c.as_dict() for c in self.checks]
            out["peak_angle_deg"] = self.peak_angle_deg
            out["torque_at_peak_N_m"] = dict(self.peak_terms)
        return out


@dataclass
class Sizing:
    """The result of :func:`size_drive`: candidates ranked, and what they were computed from."""

    problem_name: str
    spm: float
    period: float
    candidates: list[Candidate]
    inputs: dict
    kinematics: object  # stroke.Kinematics of the whole cycle
    load: Load
    limits: DriveLimits
    max_spm_resolution: float | None = None

    def to_dict(self, explain: bool = False) -> dict:
        with_max = self.max_spm_resolution is not None
        out = {"problem": self.problem_name, "spm": self.spm, "cycle_time_s": self.period, "inputs": self.inputs,
               "candidates": [c.row(explain, with_max) for c in self.candidates]}
        if with_max:
            out["max_spm_resolution"] = self.max_spm_resolution
        return out

    def torque_curve(self, candidate: Candidate) -> TorqueTerms:
        k = self.kinematics
        return load_torque(candidate.motor, candidate.pulley.transmission(), self.load, k.s, k.v, k.a)

    def plot(self, path=None, candidate: Candidate | None = None):
        """The classic sizing picture for ``candidate`` (default: the best ranked); see
        :func:`strokeopt.plots.plot_sizing`."""
        from ..report.drive import plot_sizing

        return plot_sizing(self, candidate, path)


def scale_kinematics(kin, factor: float):
    """The same stroke run ``factor`` times faster: time / f, speed * f, acceleration * f^2, jerk * f^3.

    Exact for a timing diagram, whose interval times all scale with the cycle time.
    """
    from ..motion.stroke import Kinematics

    return Kinematics(kin.t / factor, kin.s, kin.v * factor, kin.a * factor**2, kin.j * factor**3)


def _candidates(kin, motors, pulleys, load: Load, limits: DriveLimits, belt: BeltSpec | None, spm: float,
                period: float) -> list[Candidate]:
    """Every motor with every pulley, vectorised: one torque evaluation per pulley over the
    whole cycle; the rotor term broadcast over the motors."""
    rotor = np.array([m.rotor_inertia for m in motors])[:, None]
    out = []
    for p in pulleys:
        tr = p.transmission()
        base = load_torque(0.0, tr, load, kin.s, kin.v, kin.a)  # everything but the rotor
        total = base.total[None, :] + rotor * base.eps[None, :]
        peak, rms, peak_speed, peak_force = _cycle_values(total, base.omega, base.load_force, kin.t)
        reflected = reflected_inertia(tr, load, base.phi)
        i_peak = np.argmax(np.abs(total), axis=-1)
        for k, m in enumerate(motors):
            i = int(i_peak[k])
            terms = {name: float(np.broadcast_to(val, kin.s.shape)[i]) for name, val in base.as_dict().items()}
            terms["rotor_inertia"] = float(rotor[k, 0] * base.eps[i])
            terms["total"] = float(total[k, i])
            checks = _checks(peak[k], rms[k], peak_speed, peak_force, m, reflected, limits, belt, p.teeth)
            out.append(Candidate(m, p, spm, checks, terms, float(360.0 * kin.t[i] / period)))
    return out


def rank(candidates: list[Candidate]) -> list[Candidate]:
    """Feasible pairs first; then by the thesis's criterion, the theoretical overload
    (peak load torque / rated torque, thesis 4.6), lowest first; ties by inertia ratio."""
    return sorted(candidates, key=lambda c: (not c.feasible, c.check("overload").value, c.check("inertia_ratio").value))


def bisect_highest(ok, lo: float, hi: float, resolution: float) -> tuple[float, float]:
    """Bracket ``(lo, hi)``, ``hi - lo <= resolution``, of the threshold where ``ok`` turns false,
    given ``ok(lo)`` and not ``ok(hi)`` (``ok`` true below the threshold): the highest feasible
    stitch rate is ``lo``, the first failing one ``hi``."""
    while hi - lo > resolution:
        mid = 0.5 * (lo + hi)
        if ok(mid):
            lo = mid
        else:
            hi = mid
    return lo, hi


def max_spm(kin, spm: float, motor, pulley, load: Load, limits: DriveLimits, belt: BeltSpec | None = None,
            resolution: float = 1.0, highest: float = 20_000.0) -> tuple[float | None, str]:
    """Highest stitch rate [spm] at which every check of ``motor`` with ``pulley`` passes.

    ``kin`` is the cycle sampled at ``spm``; other speeds scale it exactly
    (:func:`scale_kinematics`). Bisection to ``resolution`` spm; returns the
    highest feasible rate found (rounded down to the resolution, ``None`` if
    even ``resolution`` spm fails, ``highest`` if nothing binds below it) and
    the check that fails just above it.
    """
    period = kin.t[-1] - kin.t[0]

    def checks_at(x):
        k = scale_kinematics(kin, x / spm)
        return _candidates(k, [motor], [pulley], load, limits, belt, x, period * spm / x)[0].checks

    def ok(x):
        return all(c.ok for c in checks_at(x))

    lo, hi = 0.0, spm
    if ok(spm):
        lo = spm
        while ok(hi := min(hi * 2, highest)):
            lo = hi
            if hi >= highest:
                return highest, binding_check(checks_at(highest)).name
    lo, hi = bisect_highest(ok, lo, hi, resolution)
    if lo < resolution:
        return None, binding_check(checks_at(resolution)).name
    failing = [c for c in checks_at(hi) if not c.ok]
    return math.floor(lo / resolution) * resolution, min(failing or checks_at(hi), key=lambda c: c.margin).name


def size_drive(problem, spm: float | None = None, *, catalogue=None, motors=None, teeth=None, samples: int = 3601,
               find_max_spm: bool = False, resolution: float = 1.0, progress=None) -> Sizing:
    """Rank every catalogue motor with every allowed pulley for the stroke of ``problem`` at ``spm``.

    ``motors``: names to keep (default all); ``teeth``: groove counts to keep
    (default the problem's ``pulley_teeth_min..max``). ``find_max_spm`` adds
    the highest feasible stitch rate of each pair (bisection to ``resolution``).
    ``progress``: a callable wrapping an iterable (tqdm) for the max-spm search.
    """
    spec = problem.drive
    if spec is None:
        raise ProblemError(str(problem.file), "drive", "the problem has no [drive] section (motor, moving mass, ...)")
    spm = problem.spm if spm is None else spm
    cat = catalogue if catalogue is not None else spec.catalogue()
    if spec.motor is not None:
        cat.motor(spec.motor, (spec.file, "drive.motor"))  # the problem's own motor must exist
    chosen = [cat.motor(n) for n in motors] if motors else list(cat.motors.values())
    if teeth:
        pulleys = []
        for z in teeth:
            found = [p for p in cat.pulleys_of(spec.profile) if p.teeth == z]
            if not found:
                have = ", ".join(str(p.teeth) for p in cat.pulleys_of(spec.profile))
                raise ProblemError("--pulley-teeth", "", f"no {spec.profile} pulley with {z} teeth in the catalogue "
                                                         f"(have {have})")
            pulleys += found
    else:
        pulleys = cat.pulleys_of(spec.profile, spec.teeth_min, spec.teeth_max)
        if not pulleys:
            raise ProblemError(spec.file, "drive.pulley_teeth_min", f"no {spec.profile} pulley in the catalogue between "
                                                                   f"{spec.teeth_min} and {spec.teeth_max} teeth")
    belt = spec.belt_spec(cat)
    stroke = problem.stroke(spm)
    kin = stroke.sample(samples)
    cands = _candidates(kin, chosen, pulleys, spec.load, spec.limits, belt, spm, stroke.period)
    if find_max_spm:
        it = progress(cands) if progress is not None else cands
        for c in it:
            c.max_spm, c.max_spm_binding = max_spm(kin, spm, c.motor, c.pulley, spec.load, spec.limits, belt, resolution)
    inputs = {
        "moving_mass_kg": spec.load.moving_mass,
        "gravity_m_s2": spec.load.gravity,
        "load_forces": [{"name": f.name, "kind": f.kind, "direction": "up" if f.direction > 0 else "down",
                         "force_N": f.force, "stiffness_N_m": f.stiffness,
                         "contact_position_mm": f.contact_position * 1e3} for f in spec.load.forces],
        "peak_limit_pct": spec.limits.peak_limit_pct,
        "max_inertia_ratio": spec.limits.max_inertia_ratio,
        "belt": belt.belt.name if belt else None,
        "belt_cord": belt.cord if belt else None,
        "belt_service_factor": belt.service_factor if belt else None,
        "law": stroke.label,
        "samples": samples,
        "catalogue_files": cat.files,
    }
    return Sizing(problem.name, spm, stroke.period, rank(cands), inputs, kin, spec.load, spec.limits,
                  resolution if find_max_spm else None)


# --------------------------------------------------------------------------- continuous pulley radius


@dataclass(frozen=True)
class RadiusOptimum:
    """The belt-pulley radius that minimises a motor's peak torque over the cycle."""

    motor: str
    radius: float  # m
    peak_torque: float  # N m
    pulley_inertia: float  # kg m^2 at that radius
    teeth_equivalent: float  # pitch diameter / (pitch / pi), not rounded


def optimal_radius(motor, load: Load, kin, pulley_inertia=None, bounds=(2e-3, 0.2), pitch: float = 3e-3,
                   solver_options: dict | None = None) -> RadiusOptimum:
    """Pulley pitch radius minimising the peak motor torque of a belt drive over the sampled cycle.

    For a belt, ``T_k(r) = (J_rotor + J_pulley(r)) a_k / r + r F_k`` with the load
    force ``F_k`` of each sample, so the problem is ``min z`` subject to
    ``-z <= T_k(r) <= z``, solved by IPOPT through CasADi. ``pulley_inertia``:
    a function of the pitch diameter (CasADi-friendly; the catalogue's model),
    or None for none. With inertia only and no pulley inertia the optimum is
    ``r = sqrt(J_rotor / m)`` (inertia matching).
    """
    from ..errors import SolverError
    from .transmission import BeltPulley

    base = load_torque(0.0, BeltPulley(2.0), load, kin.s, kin.v, kin.a)  # r = 1: eps = a, mu = 1
    acc = np.asarray(base.eps, dtype=float)
    force = np.asarray(base.load_force, dtype=float)
    j_rotor = _rotor_inertia(motor)

    def torque_np(radius):
        jp = float(pulley_inertia(2 * radius)) if pulley_inertia is not None else 0.0
        return (j_rotor + jp) * acc / radius + radius * force

    # The peak is set by a few samples: solve on those that peak somewhere on a grid of radii,
    # then check every sample at the optimum and add any that exceeds it (an active-set loop).
    active = set()
    for radius in np.geomspace(bounds[0], bounds[1], 48):
        active.update(np.argsort(-np.abs(torque_np(radius)))[:3].tolist())
    r = ca.SX.sym("r")
    z = ca.SX.sym("z")
    jp = pulley_inertia(2 * r) if pulley_inertia is not None else 0.0
    opts = {"ipopt.print_level": 0, "print_time": False, "ipopt.sb": "yes", "ipopt.tol": 1e-10}
    opts.update(solver_options or {})
    r0 = float(np.clip(math.sqrt(j_rotor / load.moving_mass), *bounds))
    for _ in range(20):
        idx = sorted(active)
        torque = (j_rotor + jp) * ca.DM(acc[idx]) / r + r * ca.DM(force[idx])
        nlp = {"x": ca.vertcat(r, z), "f": z, "g": ca.vertcat(torque - z, torque + z)}
        solver = ca.nlpsol("radius", "ipopt", nlp, opts)
        n = len(idx)
        res = solver(x0=[r0, 1.0], lbx=[bounds[0], 0.0], ubx=[bounds[1], ca.inf],
                     lbg=np.r_[np.full(n, -np.inf), np.zeros(n)], ubg=np.r_[np.zeros(n), np.full(n, np.inf)])
        if not solver.stats()["success"]:
            raise SolverError(f"pulley radius optimisation for {getattr(motor, 'name', 'motor')} failed: "
                              f"{solver.stats()['return_status']}")
        r0, z0 = (float(x) for x in np.asarray(res["x"]).ravel())
        full = np.abs(torque_np(r0))
        worst = int(np.argmax(full))
        if worst in active or full[worst] <= z0 * (1 + 1e-7):  # within IPOPT's constraint tolerance
            break
        active.add(worst)
    else:
        raise SolverError("pulley radius optimisation did not settle on its peak samples in 20 rounds")
    r_opt, z_opt = r0, float(np.max(np.abs(torque_np(r0))))
    jp_opt = float(pulley_inertia(2 * r_opt)) if pulley_inertia is not None else 0.0
    return RadiusOptimum(getattr(motor, "name", ""), r_opt, z_opt, jp_opt, 2 * r_opt * math.pi / pitch)
