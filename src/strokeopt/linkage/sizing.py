"""A servo motor and gearbox on a linkage's crank, at the machine's constant crank speed and without a flywheel:
what ``strokeopt size`` answers for a linkage problem file.

The crank torque over the cycle is the power balance of dynamics.py (checked there against Newton-Euler).
Through a gearbox of ratio i (efficiency 1) the motor turns at i omega and delivers M(theta) / i; at constant
speed the rotor's and the gearbox's inertia take no torque, they count in the load-to-rotor inertia ratio
(``J_max / i^2`` plus the gearbox's own). Every pair of a gearbox of the catalogue (``drive/data/gearboxes.toml``
unless the file's ``[drive] gearboxes`` names another) and a servo motor of the file's ``[drive] catalogues``
(else the shipped motors) is checked as ``strokeopt size`` checks a motor (drive/checks.build_checks: peak and
RMS torque, overload, speed, inertia ratio) and against the gearbox's output torques; the pair chosen is the
one the servo sley's study chooses (drive/gearboxes.choose_smallest: the smallest motor, then the least RMS).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ..drive.catalogue import RPM, SHIPPED_FILES, load_catalogue, own_motors, resolve_catalogue_file
from ..drive.checks import Check, DriveLimits, binding_check, build_checks, cycle_values
from ..drive.gearboxes import GearboxEntry, choose_smallest, gearbox_catalogue_file, load_gearboxes
from ..errors import ProblemError
from .dynamics import Dynamics

@dataclass(frozen=True)
class CrankDrive:
    """The optional ``[drive]`` section of a linkage file: the motor catalogues (``catalogues``: a file beside the
    problem or a shipped catalogue's name), the gearbox catalogue (``gearboxes``, default the shipped one) and the
    drive's limits (``peak_limit_pct``, ``max_inertia_ratio``, as a problem's [drive])."""

    catalogue_files: tuple[str, ...] = ()
    gearbox_file: str | None = None
    limits: DriveLimits = field(default_factory=DriveLimits)


def read_crank_drive(f, base_dir: Path) -> CrankDrive:
    """``[drive]`` of a linkage file (``f``: its :class:`~strokeopt.io.fields.Fields`, or None without one)."""
    if f is None:
        return CrankDrive()
    names = f.raw("catalogues", [])
    if not isinstance(names, list) or not all(isinstance(x, str) for x in names):
        raise f.error("catalogues", "must be an array of catalogue file names")
    files = tuple(str(_resolve(f, "catalogues", x, base_dir)) for x in names)
    gearboxes = f.string("gearboxes", None)
    gearbox_file = str(_resolve(f, "gearboxes", gearboxes, base_dir)) if gearboxes is not None else None
    limits = DriveLimits(f.number("peak_limit_pct", 300.0, min=50.0, max=1000.0),     # as a problem's [drive]
                         f.number("max_inertia_ratio", 10.0, min=0.1, max=1000.0))
    f.finish()
    return CrankDrive(files, gearbox_file, limits)


def _resolve(f, key: str, name: str, base_dir: Path) -> Path:
    path = resolve_catalogue_file(name, base_dir)
    if path is None and key == "gearboxes" and name == gearbox_catalogue_file().name:
        path = gearbox_catalogue_file()   # the shipped gearboxes, named by their file name
    if path is None:
        raise f.error(key, f"catalogue file {name!r} not found (looked for {base_dir / name}, and strokeopt ships no "
                           f"catalogue of that name: {', '.join(SHIPPED_FILES)})")
    return path


@dataclass
class CrankCandidate:
    """One gearbox with one servo motor on the crank: its checks over the cycle."""

    gearbox: GearboxEntry
    motor: object            # drive.catalogue.ServoMotor
    checks: list[Check]

    @property
    def feasible(self) -> bool:
        return all(c.ok for c in self.checks)

    def value(self, name: str) -> float:
        return next(c.value for c in self.checks if c.name == name)

    def row(self, explain: bool = False) -> dict:
        b = binding_check(self.checks)
        out = {"gearbox": self.gearbox.name, "ratio": self.gearbox.ratio, "motor": self.motor.name,
               "rated_torque_N_m": self.motor.rated_torque, "peak_torque_N_m": self.value("peak_torque"),
               "rms_torque_N_m": self.value("rms_torque"), "motor_speed_rpm": self.value("peak_speed"),
               "inertia_ratio": self.value("inertia_ratio"), "feasible": self.feasible, "binding": b.name,
               "margin": b.margin}
        if explain:
            out["checks"] = [c.as_dict() for c in self.checks]
        return out


@dataclass
class CrankSizing:
    omega: float
    candidates: list[CrankCandidate]         # feasible first, then by the choice's order
    chosen: CrankCandidate | None
    motors_from: list[str]                   # the catalogue files the motors come from
    gearboxes_from: str

    def to_dict(self, explain: bool = False) -> dict:
        return {"drive": "a servo motor and gearbox on the crank at constant crank speed, no flywheel "
                         "(gearbox efficiency 1)",
                "motors_from": self.motors_from, "gearboxes_from": self.gearboxes_from,
                "chosen": None if self.chosen is None else self.chosen.row(explain=True),
                "candidates": [c.row(explain) for c in self.candidates]}


def pair_checks(crank_torque: np.ndarray, omega: float, J_max: float, gearbox: GearboxEntry, motor,
                limits: DriveLimits) -> list[Check]:
    """The checks of ``motor`` through ``gearbox`` on a crank that needs ``crank_torque`` [N m] at equal steps of
    one turn at ``omega`` [rad/s]: the motor's (build_checks) and the gearbox's output torques."""
    i = gearbox.ratio
    t = np.linspace(0.0, 2 * math.pi / omega, len(crank_torque) + 1)   # equal steps: the turn closed
    total = np.append(crank_torque, crank_torque[0]) / i
    # the motor's speed from its rpm rounded to 1e-9 rpm, as a catalogue's rated speed is made: a motor driven at
    # exactly its rated speed passes (200 rpm x 10 is 2000 rpm, not 2000.0000000000002)
    motor_speed = round(omega / RPM * i, 9) * RPM
    peak, rms, speed, _ = cycle_values(total, np.full(len(t), motor_speed), np.zeros(len(t)), t)
    checks = build_checks(peak, rms, speed, 0.0, motor, gearbox.inertia + J_max / i ** 2, limits, None, None)
    out_peak, out_rms = peak * i, rms * i
    return checks + [Check("gearbox_peak_output_torque", float(out_peak), gearbox.peak_output_torque, "N m"),
                     Check("gearbox_rated_output_torque", float(out_rms), gearbox.rated_output_torque, "N m")]


def size_crank(dyn: Dynamics, drive: CrankDrive | None = None, motors: list[str] | None = None,
               extra_catalogues=()) -> CrankSizing:
    """Every gearbox with every motor on the crank of ``dyn`` (its power-balance torque at its speed), the
    pairs that carry the cycle first and the chosen one (the servo sley's rule); ``motors`` limits the motors
    (names of the catalogue, as ``size --motor``), ``extra_catalogues`` adds catalogue files (``--catalogue``)."""
    drive = drive or CrankDrive()
    files = list(drive.catalogue_files) + [str(x) for x in extra_catalogues]
    catalogue = load_catalogue(files)
    names = own_motors(files, catalogue) if motors is None else list(motors)
    for name in names:
        catalogue.motor(name, ("--motor", ""))   # an unknown name (or a stepper's) is refused naming the catalogue
    gearboxes = load_gearboxes(drive.gearbox_file)
    if not gearboxes:
        raise ProblemError(drive.gearbox_file or "gearboxes.toml", "gearbox", "the catalogue has no gearbox")
    cands = [CrankCandidate(g, catalogue.motors[m], pair_checks(dyn.torque, dyn.omega, float(dyn.J.max()), g,
                                                                  catalogue.motors[m], drive.limits))
             for g in gearboxes for m in names]
    chosen = choose_smallest([c for c in cands if c.feasible], lambda c: c.motor.rated_torque,
                             lambda c: c.value("rms_torque"))
    cands.sort(key=lambda c: (not c.feasible, c.motor.rated_torque, c.value("rms_torque")))
    motors_from = [str(f) for f in files] or ["the shipped catalogue"]
    return CrankSizing(dyn.omega, cands, chosen, motors_from, drive.gearbox_file or "the shipped gearboxes.toml")
