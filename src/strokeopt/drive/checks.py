"""The sizing checks of a drive over one sampled cycle.

Where it sits: after load.py (the motor torque over the cycle), before
sizing.py (every catalogue motor with every pulley). A :class:`Check` is one
limit and the value that must stay under it; :func:`drive_checks` runs them
all for one motor and transmission::

    checks = drive_checks(motor, transmission, load, t, s, v, a,
                          limits=DriveLimits(peak_limit_pct=300), belt=belt_spec, grooves=28)
    for c in checks: c.name, c.value, c.limit, c.unit, c.margin, c.ok

The belt checks follow the catalogue method of thesis appendix 2
(:func:`belt_load`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..errors import ProblemError
from .load import Load, load_torque, reflected_inertia

CHECK_NAMES = ("peak_torque", "overload", "rms_torque", "peak_speed", "inertia_ratio", "belt_width", "belt_breaking")


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
        return within_limit(self.value, self.limit)

    def as_dict(self) -> dict:
        return {"name": self.name, "value": self.value, "limit": self.limit, "unit": self.unit,
                "margin": self.margin, "ok": self.ok}


@dataclass(frozen=True)
class DriveLimits:
    """Limits that belong to the application, not to a part.

    ``peak_limit_pct``: the servo drive's peak current as % of the motor's
    rated torque (Digitax ST: 300 %, thesis 4.6). ``max_inertia_ratio``:
    largest load-to-rotor inertia ratio accepted (a common servo guideline,
    not from the thesis). ``pull_out_safety_factor``: a stepper's torque demand must stay under its
    pull-out torque divided by this at every speed (a stepper that exceeds its curve loses steps).
    """

    peak_limit_pct: float = 300.0
    max_inertia_ratio: float = 10.0
    pull_out_safety_factor: float = 1.5  # a stepper's demand stays under pull-out / this at every speed


@dataclass(frozen=True)
class BeltSpec:
    """The belt of the drive and how it is checked (thesis appendix 2).

    ``allowable_tension`` [N per reference width], when given, replaces the
    catalogue row for the pulley's groove count.
    """

    belt: object  # catalogue.Belt
    method: object  # catalogue.BeltMethod
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


def within_limit(value: float, limit: float, tolerance: float = 0.0) -> bool:
    """The one pass rule of every upper limit strokeopt judges: ``value`` meets ``limit`` when it exceeds it by
    no more than ``tolerance`` (relative: a design's ``[design] check_tolerance``, the violation between
    collocation nodes it accepts; an impact velocity's 2 % of the rigid cluster against the simulation; 0 for
    a classic law's table). The design's check rows, its full servo simulation, the contact verdict, the
    trade-off and the report all use it. A value equal to the limit within floating-point rounding
    (:data:`ROUNDING`, relative) meets it: a rate at which a speed reaches its limit exactly passes there."""
    return bool(value <= limit * (1.0 + tolerance) + ROUNDING * abs(limit))


#: The relative rounding :func:`within_limit` forgives: a few units in the last place of a double (a speed scaled
#: by a rate ratio, 3200 rpm x 250 / 200, is 4000.0000000000005); far below any tolerance a check states.
ROUNDING = 1e-12


def torque_limit(motor, limits: DriveLimits) -> float:
    """The torque limit of ``motor`` on its drive [N m]: ``min(motor peak, drive peak limit x rated)``.

    The one limit every command checks a peak torque against (the ``peak_torque`` check, the
    design's torque bound, the servo model's saturation). A stepper's is its pull-out torque at
    standstill over the safety factor (:attr:`DriveLimits.pull_out_safety_factor`): the most its
    pull-out curve allows at any speed.
    """
    if is_stepper(motor):
        return float(motor.pull_out(0.0)) / limits.pull_out_safety_factor
    return min(motor.peak_torque, limits.peak_limit_pct / 100 * motor.rated_torque)


def is_stepper(motor) -> bool:
    """Whether ``motor`` is a stepper (:class:`~strokeopt.drive.catalogue.StepperMotor`): its limits are its
    pull-out curve and step rate, not a servo's peak, rated torque and rated speed."""
    return getattr(motor, "kind", "servo") == "stepper"


def torque_limit_text(motor, limits: DriveLimits) -> str:
    """How :func:`torque_limit` is made, for a report: ``min(motor peak 5.5 N m, 300 % x rated 1.2 N m)``."""
    if is_stepper(motor):
        return (f"pull-out torque at standstill {float(motor.pull_out(0.0)):g} N m / safety factor "
                f"{limits.pull_out_safety_factor:g}")
    return (f"min(motor peak {motor.peak_torque:g} N m, drive peak limit {limits.peak_limit_pct:g} % x rated "
            f"{motor.rated_torque:g} N m)")


def belt_load(peak_tension, grooves: int, spec: BeltSpec) -> BeltLoad:
    """Apply the catalogue method of thesis appendix 2 to a peak belt tension ``T_e`` [N]."""
    allow = spec.allowable_tension if spec.allowable_tension is not None else spec.method.allowable_tension_for(grooves)
    design = spec.service_factor * peak_tension
    required = design / allow if allow > 0 else math.inf
    breaking = spec.method.peak_tension_factor * peak_tension * spec.method.breaking_safety
    return BeltLoad(peak_tension, design, allow, required, breaking)


def cycle_values(total, omega, load_force, t):
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


def build_checks(peak, rms, peak_speed, peak_force, motor, reflected, limits: DriveLimits,
                 belt: BeltSpec | None, grooves: int | None) -> list[Check]:
    """The checks of ``motor`` from the values of one cycle (:func:`cycle_values`) and the
    reflected inertia: peak torque, overload, RMS torque, peak speed, inertia ratio and,
    with ``belt``, the belt width and breaking checks (``grooves`` of the pulley)."""
    rpm = 60 / (2 * math.pi)
    out = [
        Check("peak_torque", float(peak), torque_limit(motor, limits), "N m"),
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
    peak torque vs the torque limit (:func:`torque_limit`: the lower of the motor's peak torque
    and the drive's peak limit x rated torque), overload (peak / rated) vs the drive's peak limit, RMS torque vs rated torque, peak speed vs rated speed,
    load-to-rotor inertia ratio, and with ``belt`` the belt width and
    breaking checks of thesis appendix 2 (``grooves`` of the smaller pulley).
    A stepper's checks are its peak torque against :func:`torque_limit` and :func:`stepper_checks`.
    """
    t, s, v, a = (np.asarray(x, dtype=float) for x in (t, s, v, a))
    terms = load_torque(motor, transmission, load, s, v, a)
    peak, rms, peak_speed, peak_force = cycle_values(terms.total, terms.omega, terms.load_force, t)
    reflected = reflected_inertia(transmission, load, terms.phi)
    limits = limits or DriveLimits()
    if is_stepper(motor):
        return ([Check("peak_torque", float(peak), torque_limit(motor, limits), "N m")]
                + stepper_checks(terms.total, terms.omega, motor, reflected, limits))
    return build_checks(peak, rms, peak_speed, peak_force, motor, reflected, limits or DriveLimits(), belt, grooves)


def binding_check(checks: list[Check]) -> Check:
    """The check with the smallest margin: the one that binds first (on a tie the first listed:
    ``peak_torque`` before ``overload``, which share the drive's limit when it is below the motor's peak)."""
    return min(checks, key=lambda c: round(c.margin, 12))


def stepper_checks(total, omega, motor, reflected: float, limits: DriveLimits) -> list[Check]:
    """The checks of a stepper (:class:`~strokeopt.drive.catalogue.StepperMotor`) over a cycle: the
    torque demand ``total`` [N m] at the speeds ``omega`` [rad/s] as % of the pull-out torque at each
    speed, against 100 % / ``pull_out_safety_factor``; the peak step rate against the table's last;
    the load/rotor inertia ratio. ``total`` may carry leading axes (motors); the last is the samples."""
    ratio = pull_out_ratio(total, omega, motor)
    return [
        Check("pull_out_torque", float(np.max(ratio)) * 100, 100 / limits.pull_out_safety_factor, "%"),
        Check("step_rate", float(np.max(np.abs(omega))) / motor.step_angle, motor.max_step_rate, "Hz"),
        Check("inertia_ratio", reflected / motor.rotor_inertia, limits.max_inertia_ratio, "-"),
    ]


def pull_out_ratio(total, omega, motor):
    """|torque| / pull-out torque at each sample's speed (inf where the speed is beyond the curve)."""
    pull_out = motor.pull_out(omega)
    with np.errstate(divide="ignore"):
        return np.where(pull_out > 0, np.abs(total) / np.where(pull_out > 0, pull_out, 1.0), np.inf)
