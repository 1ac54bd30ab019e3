"""Actuators and drive components: servo motors, toothed pulleys, belts, and their catalogues.

Catalogues are TOML files. strokeopt ships three (package data in
``strokeopt/drive/data/``): ``motors.toml`` (thesis Tab. 4.5-4.6),
``gt3_pulleys.toml`` (GT3 pulleys, 14-52 grooves) and ``gt3_belts.toml``
(GT3 belts and the belt-check method of thesis appendix 2). A user adds
parts with files of the same form (``load_catalogue(extra_files=[...])`` or
``drive.catalogues`` in a problem file); a file may hold any of the tables::

    [[motor]]            name, model, maker, source, rated_speed_rpm, rated_torque_N_m,
                         stall_torque_N_m, peak_torque_N_m, rotor_inertia_kg_cm2
    [[stepper]]          name, model, maker, source, note, step_angle_deg, holding_torque_N_m,
                         rotor_inertia_kg_cm2, pull_out_step_rate_Hz = [...], pull_out_torque_N_m = [...]
    [[pulley]]           name, profile, teeth, inertia_kg_cm2 (optional, else the model)
    [inertia_model.<profile>]   kind = "power_law", source
    [[belt]]             name, profile, width_mm, width_factor,
                         breaking_tension_glass_N, breaking_tension_steel_N,
                         tensile_stiffness_glass_N, tensile_stiffness_steel_N (optional, EA)
    [belt_method.<profile>]     source, reference_width_mm, grooves, allowable_tension_N,
                                peak_tension_factor, breaking_safety

Names are unique across all loaded files; a duplicate is an error naming
both files. Units are converted to SI when read.
"""

from __future__ import annotations

import math
import tomllib
from dataclasses import dataclass, field
from importlib import resources
from pathlib import Path

import numpy as np

from ..errors import ProblemError
from ..io.fields import Fields, did_you_mean
from .transmission import PROFILE_PITCH, TEETH_RANGE, BeltPulley, pitch_diameter

RPM = 2 * math.pi / 60  # rad/s per rpm
KG_CM2 = 1e-4  # kg m^2 per kg cm^2
BUILTIN_FILES = ("motors.toml", "gt3_pulleys.toml", "gt3_belts.toml", "steppers.toml")
#: Catalogues shipped but read only when a problem names one in [drive] catalogues (by its file name): the
#: loom sley's servo motors stay out of the needle-bar problems' catalogue search.
SHIPPED_FILES = BUILTIN_FILES + ("loom_servos.toml",)
BELT_CORDS = ("glass", "steel")


# --------------------------------------------------------------------------- parts


@dataclass(frozen=True)
class ServoMotor:
    """A servo motor, SI units: speeds in rad/s, torques in N m, inertia in kg m^2.

    The torque-speed envelope is the simple catalogue one: continuous torque
    falls linearly from the stall torque at standstill to the rated torque at
    the rated speed; the peak torque is available up to the rated speed.
    """

    name: str
    rated_speed: float
    rated_torque: float
    stall_torque: float
    peak_torque: float
    rotor_inertia: float
    model: str = ""
    maker: str = ""
    source: str = ""

    @property
    def rated_speed_rpm(self) -> float:
        return self.rated_speed / RPM

    def continuous_torque(self, speed):
        """Continuous (thermal) torque [N m] at ``speed`` [rad/s]; zero beyond the rated speed."""
        w = np.abs(np.asarray(speed, dtype=float))
        line = self.stall_torque + (self.rated_torque - self.stall_torque) * w / self.rated_speed
        return np.where(w <= self.rated_speed, line, 0.0)

    def peak_envelope(self, speed):
        """Peak torque [N m] available at ``speed`` [rad/s]; zero beyond the rated speed."""
        w = np.abs(np.asarray(speed, dtype=float))
        return np.where(w <= self.rated_speed, self.peak_torque, 0.0)


@dataclass(frozen=True)
class StepperMotor:
    """A stepper motor, SI units: its step angle [rad], holding torque [N m], rotor inertia [kg m^2]
    and the pull-out torque-speed curve as a table (speeds [rad/s] increasing, torques [N m]).

    Between the table's points the pull-out torque is interpolated linearly; below the first point it
    is the first point's; beyond the last there is none (the motor loses steps): the last speed is the
    highest step rate it can run (:attr:`max_step_rate`).
    """

    name: str
    step_angle: float
    holding_torque: float
    rotor_inertia: float
    pull_out_speed: tuple[float, ...]
    pull_out_torque: tuple[float, ...]
    model: str = ""
    maker: str = ""
    source: str = ""
    note: str = ""
    kind = "stepper"

    @property
    def max_step_rate(self) -> float:
        """The highest step rate of the pull-out table [Hz]."""
        return self.pull_out_speed[-1] / self.step_angle

    def pull_out(self, speed):
        """Pull-out torque [N m] at ``speed`` [rad/s] (either sense); zero beyond the table."""
        w = np.abs(np.asarray(speed, dtype=float))
        return np.where(w <= self.pull_out_speed[-1], np.interp(w, self.pull_out_speed, self.pull_out_torque), 0.0)


@dataclass(frozen=True)
class PulleyInertiaModel:
    """Moment of inertia of a pulley from its pitch diameter: ``J = J_ref * (PD / PD_ref)**p``.

    Fitted by least squares in log-log to published (pitch diameter, inertia)
    pairs; works on floats, numpy arrays and CasADi symbols (``**`` only).
    """

    profile: str
    reference_diameter: float
    reference_inertia: float
    exponent: float
    source: str = ""

    @classmethod
    def fit(cls, profile: str, diameters, inertias, source: str = "") -> "PulleyInertiaModel":
        d = np.asarray(diameters, dtype=float)
        j = np.asarray(inertias, dtype=float)
        slope, intercept = np.polyfit(np.log(d), np.log(j), 1)
        d_ref = float(np.exp(np.mean(np.log(d))))
        return cls(profile, d_ref, float(np.exp(intercept + slope * np.log(d_ref))), float(slope), source)

    def __call__(self, pitch_diameter):
        return self.reference_inertia * (pitch_diameter / self.reference_diameter) ** self.exponent


@dataclass(frozen=True)
class Pulley:
    """A toothed pulley of the catalogue: ``teeth`` grooves, pitch diameter [m], moment of inertia [kg m^2].

    A catalogue record (name, where the inertia came from); as a transmission
    it is the :class:`~strokeopt.drive.transmission.BeltPulley` of
    :meth:`transmission`, the same object the problem's ``[transmission]``
    becomes. ``inertia_source`` says where the inertia came from: ``"data"``
    (the catalogue file) or ``"model"`` (the profile's fitted inertia model).
    """

    name: str
    profile: str
    teeth: int
    pitch_diameter: float
    inertia: float
    inertia_source: str = "data"

    @property
    def radius(self) -> float:
        return self.pitch_diameter / 2

    def transmission(self) -> BeltPulley:
        """The belt transmission of this pulley, carrying its inertia, teeth and profile."""
        return BeltPulley(self.pitch_diameter, self.inertia, self.teeth, self.profile)


@dataclass(frozen=True)
class Belt:
    """A toothed belt: width [m], width factor of the catalogue, minimum breaking tension [N] by cord."""

    name: str
    profile: str
    width: float
    width_factor: float
    breaking_tension: dict = field(default_factory=dict)  # cord -> N
    tensile_stiffness: dict = field(default_factory=dict)  # cord -> EA [N per unit strain] (servo/plant.py's belt spring)


@dataclass(frozen=True)
class BeltMethod:
    """The catalogue's belt-load method for one profile (thesis appendix 2)."""

    profile: str
    reference_width: float
    grooves: tuple[int, ...]
    allowable_tension: tuple[float, ...]  # N per reference width
    peak_tension_factor: float
    breaking_safety: float
    source: str = ""

    def allowable_tension_for(self, grooves: int) -> float:
        """Allowable working tension per reference width for a pulley of ``grooves``.

        A groove count between two rows takes the row below it (conservative);
        below the first row there is no rating and the result is 0.
        """
        k = int(np.searchsorted(np.asarray(self.grooves), grooves, side="right")) - 1
        return float(self.allowable_tension[k]) if k >= 0 else 0.0


# --------------------------------------------------------------------------- catalogue


@dataclass
class Catalogue:
    """Every part loaded from the catalogue files, by name."""

    motors: dict[str, ServoMotor] = field(default_factory=dict)
    steppers: dict[str, StepperMotor] = field(default_factory=dict)
    pulleys: dict[str, Pulley] = field(default_factory=dict)
    belts: dict[str, Belt] = field(default_factory=dict)
    inertia_models: dict[str, PulleyInertiaModel] = field(default_factory=dict)
    belt_methods: dict[str, BeltMethod] = field(default_factory=dict)
    files: list[str] = field(default_factory=list)

    def motor(self, name: str, where: tuple[str, str] = ("--motor", "")) -> ServoMotor:
        """The servo motor called ``name``; an unknown name (or a stepper's) is a :class:`ProblemError` at ``where``."""
        if name in self.steppers:
            raise ProblemError(where[0], where[1], f"{name!r} is a stepper motor; this takes a servo motor (the "
                                                   f"catalogue's: {', '.join(self.motors)})")
        if name not in self.motors:
            raise ProblemError(where[0], where[1], f"unknown motor {name!r}{did_you_mean(name, self.motors)}; "
                                                   f"the catalogue has {', '.join(self.motors)}")
        return self.motors[name]

    def actuator(self, name: str, where: tuple[str, str] = ("--motor", "")):
        """The servo motor or the stepper called ``name``; an unknown name is a :class:`ProblemError` at ``where``."""
        if name in self.steppers:
            return self.steppers[name]
        if name not in self.motors:
            known = {**self.motors, **self.steppers}
            raise ProblemError(where[0], where[1], f"unknown motor {name!r}{did_you_mean(name, known)}; "
                                                   f"the catalogue has {', '.join(known)}")
        return self.motors[name]

    def belt(self, name: str, where: tuple[str, str] = ("--belt", "")) -> Belt:
        if name not in self.belts:
            raise ProblemError(where[0], where[1], f"unknown belt {name!r}{did_you_mean(name, self.belts)}; "
                                                   f"the catalogue has {', '.join(self.belts)}")
        return self.belts[name]

    def pulleys_of(self, profile: str, teeth_min: int = 1, teeth_max: int = 10**6) -> list[Pulley]:
        """Pulleys of a profile within a groove range, smallest first."""
        out = [p for p in self.pulleys.values() if p.profile == profile and teeth_min <= p.teeth <= teeth_max]
        return sorted(out, key=lambda p: p.teeth)

    def pulley_inertia(self, profile: str, pitch_diameter_m):
        """Inertia [kg m^2] of a pulley of any pitch diameter from the profile's model (continuous sizing)."""
        if profile not in self.inertia_models:
            raise ProblemError("catalogue", f"inertia_model.{profile}", "no pulley inertia model for this profile")
        return self.inertia_models[profile](pitch_diameter_m)


def builtin_catalogue_files() -> list[Path]:
    base = resources.files("strokeopt") / "drive" / "data"
    return [Path(str(base / name)) for name in BUILTIN_FILES]


def shipped_catalogue_file(name: str) -> Path | None:
    """The shipped catalogue file ``name`` (package data in ``strokeopt/drive/data/``, read only when a problem
    names it, as ``loom_servos.toml``), or None when strokeopt ships no such catalogue."""
    if name not in SHIPPED_FILES:
        return None
    return Path(str(resources.files("strokeopt") / "drive" / "data" / name))


def resolve_catalogue_file(name: str, base_dir: Path | None = None) -> Path | None:
    """Where a catalogue a problem names in ``[drive] catalogues`` is: a path (absolute, or relative to the
    problem file's directory ``base_dir``) when that file exists, else the shipped catalogue of that name
    (:func:`shipped_catalogue_file`), so a problem file names a shipped catalogue by its name and works from any
    directory; None when neither exists."""
    path = Path(name) if Path(name).is_absolute() else (base_dir or Path(".")) / name
    if path.is_file():
        return path
    return shipped_catalogue_file(name)


def load_catalogue(extra_files=(), builtin: bool = True) -> Catalogue:
    """Read the shipped catalogue files (unless ``builtin=False``) and then ``extra_files``.

    Every field is validated; a duplicate name (within a file or across
    files), a missing field or an unknown key raises :class:`ProblemError`
    naming the file and the field.
    """
    files = (builtin_catalogue_files() if builtin else []) + [Path(f) for f in extra_files]
    cat = Catalogue()
    origin: dict[tuple[str, str], str] = {}
    pending: list[tuple[Fields, str, str, int]] = []  # pulleys without inertia: resolved after all models are fitted
    for path in files:
        file = str(path)
        try:
            data = tomllib.loads(path.read_text(encoding="utf-8"))
        except FileNotFoundError:
            raise ProblemError(file, "", "catalogue file not found") from None
        except (OSError, UnicodeDecodeError) as exc:
            raise ProblemError(file, "", f"cannot be read: {exc}") from None
        except tomllib.TOMLDecodeError as exc:
            raise ProblemError(file, "", f"is not valid TOML: {exc}") from None
        cat.files.append(file)
        top = Fields(data, file)

        def unique(kind: str, row: Fields) -> str:
            name = row.string("name")
            if not name.strip():
                raise row.error("name", "must not be empty")
            if (kind, name) in origin:
                raise row.error("name", f"duplicate {kind} name {name!r} (already defined in {origin[(kind, name)]})")
            origin[(kind, name)] = file
            return name

        for row in top.tables("motor", required=False):
            name = unique("motor", row)
            motor = ServoMotor(
                name=name,
                model=row.string("model", name),
                maker=row.string("maker", ""),
                source=row.string("source", ""),
                # servo motors: to 100000 rpm and 10 kN m, rotor inertias to 1e6 kg cm^2
                rated_speed=row.number("rated_speed_rpm", positive=True, max=1e5) * RPM,
                rated_torque=row.number("rated_torque_N_m", positive=True, max=1e4),
                stall_torque=row.number("stall_torque_N_m", positive=True, max=1e4),
                peak_torque=row.number("peak_torque_N_m", positive=True, max=1e5),
                rotor_inertia=row.number("rotor_inertia_kg_cm2", positive=True, max=1e6) * KG_CM2,
            )
            if motor.peak_torque < motor.rated_torque:
                raise row.error("peak_torque_N_m", f"{motor.peak_torque:g} is below the rated torque {motor.rated_torque:g}")
            row.finish()
            cat.motors[name] = motor

        for row in top.tables("stepper", required=False):
            name = unique("motor", row)  # one name space: --motor and drive.motor take either kind
            step = math.radians(row.number("step_angle_deg", min=0.01, max=90.0))  # microsteps to 4-step motors
            speeds = _number_list(row, "pull_out_step_rate_Hz")
            torques = _number_list(row, "pull_out_torque_N_m")
            if len(speeds) != len(torques):
                raise row.error("pull_out_torque_N_m", f"has {len(torques)} values for {len(speeds)} step rates")
            if any(b <= a for a, b in zip(speeds, speeds[1:])):
                raise row.error("pull_out_step_rate_Hz", "must be a table of increasing step rates")
            if speeds[-1] > 1e6:  # a million full steps a second is past any stepper and driver
                raise row.error("pull_out_step_rate_Hz", f"{speeds[-1]:g} Hz is above the plausible 1e6 Hz")
            holding = row.number("holding_torque_N_m", positive=True, max=1e3)  # steppers end near 50 N m
            if max(torques) > holding:
                raise row.error("pull_out_torque_N_m", f"{max(torques):g} N m is above the holding torque {holding:g}")
            cat.steppers[name] = StepperMotor(
                name, step, holding, row.number("rotor_inertia_kg_cm2", positive=True, max=1e4) * KG_CM2,
                tuple(f * step for f in speeds), tuple(torques), row.string("model", name), row.string("maker", ""),
                row.string("source", ""), row.string("note", ""))
            row.finish()

        for profile, m in _profile_tables(top, "inertia_model", "pulley"):
            m.string("kind", "power_law", choices=("power_law",))
            src = m.string("source", "")
            m.finish()
            cat.inertia_models[profile] = PulleyInertiaModel(profile, 0.0, 0.0, 0.0, src)  # fitted below

        for row in top.tables("pulley", required=False):
            name = unique("pulley", row)
            profile = row.string("profile", choices=tuple(PROFILE_PITCH))
            teeth = row.number("teeth", integer=True, min=TEETH_RANGE[0], max=TEETH_RANGE[1])  # transmission.py
            row.string("source", "")  # where the entry's numbers come from (a citation, or "estimate" and why)
            pd = pitch_diameter(profile, teeth)
            if row.has("inertia_kg_cm2"):
                inertia = row.number("inertia_kg_cm2", positive=True, max=1e6) * KG_CM2
                cat.pulleys[name] = Pulley(name, profile, teeth, pd, inertia, "data")
            else:
                pending.append((row, name, profile, teeth))
            row.finish()

        for profile, m in _profile_tables(top, "belt_method", "belt"):
            grooves = _number_list(m, "grooves", integer=True)
            tension = _number_list(m, "allowable_tension_N")
            if len(grooves) != len(tension):
                raise m.error("allowable_tension_N", f"has {len(tension)} values for {len(grooves)} groove counts")
            if any(b <= a for a, b in zip(grooves, grooves[1:])):
                raise m.error("grooves", "must increase")
            cat.belt_methods[profile] = BeltMethod(
                profile, m.number("reference_width_mm", min=1.0, max=1e3) * 1e-3, tuple(int(g) for g in grooves),
                tuple(tension), m.number("peak_tension_factor", min=0.1, max=100.0),
                m.number("breaking_safety", min=0.1, max=100.0), m.string("source", ""))
            m.finish()

        for row in top.tables("belt", required=False):
            name = unique("belt", row)
            profile = row.string("profile", choices=tuple(PROFILE_PITCH))
            row.string("source", "")  # where the entry's numbers come from (a citation, or "estimate" and why)
            cat.belts[name] = Belt(
                # belts: 1 mm to 1 m wide, breaking tensions and EA up to 1e8 N
                name, profile, row.number("width_mm", min=1.0, max=1e3) * 1e-3,
                row.number("width_factor", positive=True, max=1e3),
                {cord: row.number(f"breaking_tension_{cord}_N", positive=True, max=1e8) for cord in BELT_CORDS
                 if row.has(f"breaking_tension_{cord}_N")},
                {cord: row.number(f"tensile_stiffness_{cord}_N", positive=True, max=1e10) for cord in BELT_CORDS
                 if row.has(f"tensile_stiffness_{cord}_N")})
            if not cat.belts[name].breaking_tension:
                raise row.error("breaking_tension_glass_N", "a belt needs at least one breaking tension "
                                                            "(breaking_tension_glass_N or breaking_tension_steel_N)")
            row.finish()
        top.finish()

    for profile, model in list(cat.inertia_models.items()):
        known = [p for p in cat.pulleys.values() if p.profile == profile and p.inertia_source == "data"]
        if len(known) < 2:
            raise ProblemError(cat.files[-1], f"inertia_model.{profile}",
                               f"needs at least two {profile} pulleys with inertia_kg_cm2 to fit, found {len(known)}")
        cat.inertia_models[profile] = PulleyInertiaModel.fit(
            profile, [p.pitch_diameter for p in known], [p.inertia for p in known], model.source)
    for row, name, profile, teeth in pending:
        if profile not in cat.inertia_models:
            raise row.error("inertia_kg_cm2", f"is missing and there is no inertia model for profile {profile!r} "
                                              "to compute it: give the pulley's moment of inertia")
        pd = pitch_diameter(profile, teeth)
        cat.pulleys[name] = Pulley(name, profile, teeth, pd, float(cat.inertia_models[profile](pd)), "model")
    return cat


def _profile_tables(top: Fields, key: str, what: str):
    """``(profile, table)`` of every ``[key.PROFILE]`` table of a catalogue file; an unknown profile is an error."""
    tables = top.table(key, required=False)
    if tables is None:
        return
    for profile in list(tables.data):
        m = tables.table(profile)
        if profile not in PROFILE_PITCH:
            raise m.error("", f"unknown {what} profile {profile!r}; known: {', '.join(PROFILE_PITCH)}")
        yield profile, m
    tables.finish()


def _number_list(f: Fields, key: str, integer: bool = False) -> list[float]:
    value = f.raw(key)
    if not isinstance(value, list) or not value:
        raise f.error(key, "must be a non-empty array of numbers")
    out = []
    for i, v in enumerate(value, 1):
        if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v) or v <= 0:
            raise f.error(key, f"element {i} must be a positive number, got {v!r}")
        if integer and int(v) != v:
            raise f.error(key, f"element {i} must be a whole number, got {v!r}")
        out.append(float(v))
    return out


def own_motors(catalogue_files, catalogue) -> list[str]:
    """The servo motors a problem's own catalogue files add (``[drive] catalogues``), else every servo motor of
    ``catalogue``: the motors a motor-and-gearbox choice tries."""
    own = load_catalogue(list(catalogue_files), builtin=False).motors if catalogue_files else {}
    return list(own) or list(catalogue.motors)
