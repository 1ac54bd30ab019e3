'''The plant of one servo axis: motor, belt and bar as a two-mass system (SI units).

Second step of the servo flow: :func:`axis_from_problem` takes the motor,
pulley, belt and load of the problem's ``[drive]`` (and the catalogue) and the
belt geometry of ``[servo]`` (:class:`~.settings.ServoSettings`) and returns a
:class:`DriveAxis`, which the loop (:mod:`.loop`) closes.

* **Plant**: a two-mass system. The motor side (rotor + driving pulley,
  inertia ``J``) turns at angle ``theta``; the belt, a spring of stiffness
  ``k`` with damping ``c``, pulls the bar (mass ``m``, position ``x``,
  upward as in the problem file) towards ``r*theta``::

      J theta'' = tau - r*F_belt,      m x'' = F_belt + F_ext,
      F_belt = k (r theta - x) + c (r theta' - x')

  ``F_ext`` is gravity and the load forces of the problem's ``[drive]``
  (the bar's springs), evaluated along the commanded stroke.
* **Belt stiffness** (``EA`` from the belt catalogue, ``tensile_stiffness_glass_N``:
  an estimate, see ``drive/data/gt3_belts.toml``): the carrier is clamped in one span; the driving pulley
  pulls it through the span piece of length ``l1`` (pulley to carrier) and,
  the other way round, through the rest of the loop ``l2 = belt length -
  l1 - half the pulley's wrap``; both pieces are pretensioned springs in
  parallel, ``k = EA/l1 + EA/l2`` with ``EA`` = specific stiffness x width.
* **Torque limit**: ``min(motor peak torque, drive peak limit x rated
  torque)`` (:func:`strokeopt.drive.checks.torque_limit`, the limit of every command).
'''

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..drive.checks import torque_limit
from ..drive.transmission import BeltPulley
from ..errors import ProblemError
from .settings import ServoSettings, settings_of

#: GT3 glass-cord belt, tensile stiffness per mm of width [N per unit strain], for a
#: belt without catalogue data. Estimate, not a maker's figure: breaking tension of the
#: 9 mm belt 1990 N (digest A.4) over an elongation at break of 4 % for glass cord
#: -> EA = 49.75 kN for 9 mm, 5.5 kN per mm of width. The catalogue belts carry the same
#: estimate as ``tensile_stiffness_glass_N``; ``[servo] belt_specific_stiffness_N_per_mm``
#: replaces both.
GT3_GLASS_SPECIFIC_STIFFNESS_N_PER_MM = 5500.0


@dataclass(frozen=True)
class DriveAxis:
    """The mechanics of one servo axis: a motor, an elastic element and the load, SI units.

    A belt to a translating bar (``radius`` the pulley's [m], ``mass`` [kg], ``belt_stiffness`` at the carrier
    [N/m]), or a gearbox to a rotary load (``rotary``: ``radius`` the ratio 1/i [rad/rad], ``mass`` the load's
    inertia [kg m^2], ``belt_stiffness`` the gearbox's torsional stiffness at the load [N m/rad]); the
    equations are the same two-mass system. ``compliance`` names the elastic element ("belt", "gearbox").
    """

    motor_inertia: float  # rotor + driving pulley [kg m^2]
    radius: float  # pulley pitch radius [m]
    mass: float  # moving mass of the bar, carrier and belt [kg]
    belt_stiffness: float  # [N/m] at the carrier
    belt_damping: float  # [N s/m]
    torque_limit: float  # [N m]
    load: object = None  # drive.Load (gravity and load forces), or None
    motor: str = ""
    belt_note: str = ""
    rotary: bool = False
    compliance: str = "belt"

    @property
    def total_inertia(self) -> float:
        return self.motor_inertia + self.mass * self.radius**2

    @property
    def resonance_hz(self) -> float:
        """Natural frequency of the two-mass belt mode (motor and bar moving against each other)."""
        return math.sqrt(self.belt_stiffness * (1 / self.mass + self.radius**2 / self.motor_inertia)) / (2 * math.pi)

    def state_matrix(self) -> np.ndarray:
        """``A`` of the plant's state space, states ``theta, omega, x, v`` (motor angle and speed, bar
        position and speed)."""
        j, r, m, k, c = self.motor_inertia, self.radius, self.mass, self.belt_stiffness, self.belt_damping
        return np.array([[0, 1, 0, 0],
                         [-k * r * r / j, -c * r * r / j, k * r / j, c * r / j],
                         [0, 0, 0, 1],
                         [k * r / m, c * r / m, -k / m, -c / m]])

    def motor_angle(self, s):
        """The motor angle [rad] of load positions ``s`` (the drive's table in motor angles)."""
        return np.asarray(s, dtype=float) / self.radius

    def feedforward(self, theta, omega, eps, acceleration: bool, load: bool) -> np.ndarray:
        """The drive's torque feed-forward at table points (motor angle, speed, acceleration): the rigid inertia's
        ``J_tot eps`` (``acceleration``) less the load forces' torque there (``load``)."""
        out = self.total_inertia * np.asarray(eps, dtype=float) if acceleration else 0 * np.asarray(eps, dtype=float)
        if load:
            out = out - self.radius * self.external_force(self.radius * np.asarray(theta), self.radius * np.asarray(omega))
        return out

    def external_force(self, s, v=None) -> np.ndarray:
        """Gravity plus the load forces on the bar [N], positive upward, along the positions ``s`` (and the
        velocities ``v``: a friction acts only where they are given -- the full simulation gives them, the
        design's servo error term, a function of the position, leaves friction to it)."""
        s = np.asarray(s, dtype=float)
        if self.load is None:
            return np.zeros_like(s)
        out = self.load.moving_mass * self.load.gravity + 0 * s
        for force in self.load.forces:
            if force.kind == "friction" and v is None:
                continue
            out = out + np.asarray(force(s, v), dtype=float)
        return out


def belt_stiffness(specific_stiffness: float, width: float, span: float, carrier: float | None,
                   belt_length: float | None, pitch_diameter: float) -> float:
    """Stiffness [N/m] of the belt at the carrier: the two belt pieces from the pulley in parallel."""
    if not span > 0:
        raise ValueError("the belt span must be positive")
    l1 = span / 2 if carrier is None else carrier
    length = 2 * span + math.pi * pitch_diameter if belt_length is None else belt_length
    l2 = length - l1 - math.pi * pitch_diameter / 2
    ea = specific_stiffness * width
    return ea / l1 + ea / l2


def _torsion_axis(problem, settings: ServoSettings, motor, catalogue) -> DriveAxis:
    """The axis of a drive without a belt: the motor, the transmission's constant ratio and the torsional
    stiffness of its gearbox or shaft at the load (``[servo] torsional_stiffness_N_m_arcmin``)."""
    file, drive, tr = str(problem.file), problem.drive, problem.transmission
    if motor is None:
        if drive.motor is None:
            raise ProblemError(file, "drive.motor", "name the motor of the axis (a catalogue name)")
        motor = catalogue.motor(drive.motor, (file, "drive.motor"))   # a servo motor: a stepper has no loop
    if varies(tr, problem.timing):   # a crank, a linkage: the rigid drive's own dynamics (servo/varying.py)
        if settings.torsional_stiffness is not None:
            raise ProblemError(file, "servo.torsional_stiffness_N_m_arcmin",
                               f"the servo model of a {tr.label} (its ratio changes with its position) is rigid: "
                               "leave the torsional stiffness out")
        from .varying import varying_axis

        return varying_axis(problem, motor, torque_limit(motor, drive.limits))
    if settings.torsional_stiffness is None:
        raise ProblemError(file, "servo.torsional_stiffness_N_m_arcmin",
                           f"is required for the servo model of a {tr.label}: the torsional stiffness of the gearbox "
                           "(or shaft) at the load, from its data sheet, in N m/arcmin")
    r, k = float(np.ravel(tr.transfer(np.zeros(1))[1])[0]), settings.torsional_stiffness
    j = motor.rotor_inertia + tr.inertia
    m = drive.load.moving_mass
    c = 2 * settings.torsional_damping_ratio * math.sqrt(k / (1 / m + r**2 / j))
    return DriveAxis(j, r, m, k, c, torque_limit(motor, drive.limits), drive.load, motor.name,
                     "[servo] torsional_stiffness_N_m_arcmin", problem.timing.rotary, tr.label)


def varies(transmission, timing) -> bool:
    """Whether the ratio of ``transmission`` changes over the positions of ``timing`` (a crank, a linkage)."""
    lo, hi = transmission.ratio_range(*timing.position_range)
    return not hi - lo <= 1e-9 * hi


def axis_from_problem(problem, settings: ServoSettings | None = None, *, motor=None, pulley_teeth: int | None = None,
                      radius: float | None = None, resolved=None) -> DriveAxis:
    """The :class:`DriveAxis` of a problem: motor, pulley, belt and load from its ``[drive]``
    and the catalogue, belt geometry and stiffness from ``[servo]``. ``resolved``: a design's
    :class:`~strokeopt.drive.selection.ResolvedDrive`, whose motor and pulley are taken as they are."""
    settings = settings_of(problem, settings)
    drive = getattr(problem, "drive", None)
    file = str(problem.file)
    if drive is None:
        raise ProblemError(file, "drive", "the servo model needs the [drive] section (motor, moving_mass_kg)")
    catalogue = drive.catalogue() if resolved is None else resolved.catalogue
    if not isinstance(problem.transmission, BeltPulley):
        if resolved is not None and resolved.actuator is not None:
            motor = resolved.actuator
        return _torsion_axis(problem, settings, motor, catalogue)
    if resolved is not None and resolved.radius is not None:
        motor, radius, j_pulley = resolved.actuator, resolved.radius, resolved.pulley_inertia
    if motor is None:
        if drive.motor is None:
            raise ProblemError(file, "drive.motor", "name the motor of the axis (a catalogue name)")
        motor = catalogue.motor(drive.motor, (file, "drive.motor"))
    teeth = pulley_teeth if pulley_teeth is not None else problem.pulley_teeth
    if resolved is not None and resolved.radius is not None:
        pass  # the design's pulley (catalogue or continuous), resolved once
    elif radius is None:
        pulley = next((p for p in catalogue.pulleys_of(drive.profile) if p.teeth == teeth), None)
        if pulley is None:
            raise ProblemError(file, "transmission.pulley_teeth", f"no {drive.profile} pulley with {teeth} teeth "
                                                                  "in the catalogue")
        radius, j_pulley = pulley.radius, pulley.inertia
    else:
        j_pulley = float(catalogue.pulley_inertia(drive.profile, 2 * radius))
    # EA of the belt: [servo] belt_specific_stiffness_N_per_mm (x width) if given, else the catalogue
    # belt's tensile_stiffness for the drive's cord, else the glass-cord estimate per mm of width
    width = settings.belt_width
    ea, note = None, ""
    if settings.belt_specific_stiffness is not None:
        ea, note = None, "[servo] belt_specific_stiffness_N_per_mm"
    if drive.belt is not None:
        belt = catalogue.belt(drive.belt, (file, "drive.belt"))
        width = belt.width
        if settings.belt_specific_stiffness is None and drive.belt_cord in belt.tensile_stiffness:
            ea = belt.tensile_stiffness[drive.belt_cord]
            note = f"catalogue belt {belt.name}, {drive.belt_cord} cord"
    if ea is None:
        if settings.belt_specific_stiffness is not None:
            ea = settings.belt_specific_stiffness * width
        else:
            ea = GT3_GLASS_SPECIFIC_STIFFNESS_N_PER_MM * 1e3 * width
            note = "estimate for GT3 glass cord (breaking tension / 4 % elongation)"
    k = belt_stiffness(ea / width, width, settings.belt_span, settings.carrier_from_pulley, settings.belt_length,
                       2 * radius)
    j = motor.rotor_inertia + j_pulley
    m = drive.load.moving_mass
    m_red = 1 / (1 / m + radius**2 / j)
    c = 2 * settings.belt_damping_ratio * math.sqrt(k * m_red)
    return DriveAxis(j, radius, m, k, c, torque_limit(motor, drive.limits), drive.load, motor.name, note)
