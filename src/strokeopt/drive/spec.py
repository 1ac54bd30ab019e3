"""The ``[drive]`` section of a problem file: motor, load, limits, pulley range, belt, catalogues.

Where it sits: io/problem_file.py calls :func:`parse_drive` for the
``[drive]`` table; the :class:`DriveSpec` it returns (``problem.drive``)
gives the load (load.py), the limits and belt of the checks (checks.py) and
the catalogue (catalogue.py) that sizing.py and the design search.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace
from pathlib import Path

from ..errors import ProblemError
from .catalogue import BELT_CORDS, SHIPPED_FILES, load_catalogue, resolve_catalogue_file
from .checks import BeltSpec, DriveLimits
from .load import G, Load, LoadForce, Member
from .transmission import PROFILE_PITCH, TEETH_RANGE


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
    #: the gearboxes ``size`` chooses from for a transmission with a ratio (a gearbox, a linkage's crank): a
    #: catalogue file (gearboxes.py), None: the problem's own ratio
    gearbox_file: str | None = None
    #: how ``size`` ranks the pairs that fit: the least overload (the thesis's criterion: the most reserve) or
    #: the smallest motor (least rated torque, then least RMS torque: the cheapest that carries the cycle)
    choose: str = "least_overload"

    def catalogue(self, extra_files=()):
        """The shipped catalogue plus this problem's and ``extra_files``' catalogue files."""
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


#: The [drive] keys of a belt drive's pulley and belt: refused where the transmission has none.
BELT_DRIVE_KEYS = ("belt", "belt_cord", "belt_service_factor", "pulley_profile", "pulley_teeth_min", "pulley_teeth_max")


def parse_drive(f, base_dir: Path | None = None, model=None, reference=None, rotary: bool = False,
                transmission=None) -> DriveSpec:
    """Read the ``[drive]`` table (a :class:`~strokeopt.io.fields.Fields`) of a problem file. ``model``: the
    contact model (``[model]``), whose springs a load force may name (``model_spring``) instead of its numbers.
    ``rotary``: the load turns (``[timing]`` in deg): its ``moving_inertia_kg_m2`` about its shaft takes the
    place of ``moving_mass_kg`` in the same equations, its load forces are torques (N m, N m/rad, deg).
    ``transmission``: the problem's; one without a belt pulley refuses the keys of a belt and pulley."""
    motor = f.string("motor", None)
    if transmission is not None and transmission.name != "belt_pulley":  # a screw, a gearbox, a crank: no belt
        for key in BELT_DRIVE_KEYS:
            if f.has(key):
                raise f.error(key, f"is a belt drive's (its pulley and belt); the transmission, a {transmission.label} "
                                   "(transmission.type), has neither: remove it, or omit it where it comes from an "
                                   "extended file")
    own_bodies = getattr(transmission, "carries_load", False)
    if rotary:
        if f.has("moving_mass_kg"):
            raise f.error("moving_mass_kg", "the load turns ([timing] in deg): give its moving_inertia_kg_m2 about "
                                            "its shaft instead")
        # 1 g cm^2 (a small lever) to 1000 kg m^2 (a large turntable; a loom sley is 1.3 kg m^2); none needed where
        # the transmission's own bodies carry the load's (a linkage's links: only what is added to its output)
        mass = f.number("moving_inertia_kg_m2", 0.0, min=0.0, max=1e3) if own_bodies else \
            f.number("moving_inertia_kg_m2", min=1e-7, max=1e3)
    else:
        if f.has("moving_inertia_kg_m2"):
            raise f.error("moving_inertia_kg_m2", "the load translates ([timing] in mm): give its moving_mass_kg, or "
                                                  "state [timing] in deg for a rotary load")
        # 0.1 g (a knitting machine's screw nut is 3 g) to a tonne (a loom sley is 25 kg)
        mass = f.number("moving_mass_kg", 0.0, min=0.0, max=1e3) if own_bodies else \
            f.number("moving_mass_kg", min=1e-4, max=1e3)
    # a rotary load's gravity torque depends on its centre of gravity, which [drive] does not state: off
    gravity_dir = f.string("gravity", "off" if rotary else "down", choices=("off",) if rotary else ("down", "up", "off"))
    # positions in problem files are measured upward
    gravity = {"down": -G, "up": G, "off": 0.0}[gravity_dir]
    # servo drives give 100-500 % of rated torque for a peak; inertia ratios from 1:10 to 1000:1 are sized
    # a stepper's torque reserve under its pull-out curve: 1 (none) to 5; 1.5-2 is the usual guideline
    limits = DriveLimits(f.number("peak_limit_pct", 300.0, min=50.0, max=1000.0),
                         f.number("max_inertia_ratio", 10.0, min=0.1, max=1000.0),
                         f.number("pull_out_safety_factor", 1.5, min=1.0, max=5.0))
    profile = f.string("pulley_profile", "GT3", choices=tuple(PROFILE_PITCH))
    tmin = f.number("pulley_teeth_min", 14, integer=True, min=TEETH_RANGE[0], max=TEETH_RANGE[1])  # see transmission.py
    tmax = f.number("pulley_teeth_max", 52, integer=True, min=TEETH_RANGE[0], max=TEETH_RANGE[1])
    if tmax < tmin:
        raise f.error("pulley_teeth_max", f"{tmax} is below pulley_teeth_min {tmin}")
    belt = f.string("belt", None)
    cord = f.string("belt_cord", "glass", choices=BELT_CORDS)
    # belt catalogues' service factors run 1.0-2.5 (appendix 2: 1.5); a tension above 100 kN is no toothed belt
    service = f.number("belt_service_factor", 1.5, min=0.5, max=5.0)
    allowable = f.number("belt_allowable_tension_N", None, min=1.0, max=1e5)
    files = f.raw("catalogues", [])
    if not isinstance(files, list) or not all(isinstance(x, str) for x in files):
        raise f.error("catalogues", "must be an array of file names")
    resolved = []
    for x in files:  # a file beside the problem, else a shipped catalogue named by its file name
        p = resolve_catalogue_file(x, base_dir)
        if p is None:
            looked = Path(x) if Path(x).is_absolute() else (base_dir or Path(".")) / x
            raise f.error("catalogues", f"catalogue file {x!r} not found (looked for {looked}, and strokeopt ships "
                                        f"no catalogue of that name: {', '.join(SHIPPED_FILES)})")
        resolved.append(str(p))
    forces = []
    for row in f.tables("load_forces", required=False):
        name = row.string("name")
        kind = row.string("kind", choices=("spring", "constant", "friction"))
        if kind == "friction":  # against the velocity: no direction of its own
            forces.append(_friction(row, name, rotary))
            row.finish()
            continue
        direction = {"up": 1.0, "down": -1.0}[row.string("direction", choices=("up", "down"))]
        if rotary:
            forces.append(_rotary_load(row, name, kind, direction))
        elif kind == "spring" and row.has("model_spring"):
            forces.append(model_spring_force(row, name, direction, model, reference))
        elif kind == "spring":
            # forces up to 100 kN, stiffnesses up to 1e9 N/m (a contact, not a spring), positions within 10 m
            forces.append(LoadForce(name, kind, direction, row.number("preload_N", 0.0, min=0.0, max=1e5),
                                    row.number("stiffness_N_m", min=0.0, max=1e9),
                                    row.number("contact_position_mm", min=-1e4, max=1e4) * 1e-3))
        else:
            forces.append(LoadForce(name, kind, direction, row.number("force_N", min=0.0, max=1e5)))
        row.finish()
    if len({x.name for x in forces}) != len(forces):
        raise f.error("load_forces", "two load forces have the same name")
    members = []
    for row in f.tables("members", required=False):
        name, stage = row.string("name"), row.string("stage")
        if row.has("mass_kg") == row.has("inertia_kg_cm2"):
            raise row.error("mass_kg", "give the member's mass_kg (a linear stage) or its inertia_kg_cm2 "
                                       "(an angular stage), one of them")
        # as moving_mass_kg; inertias as a rotor's (catalogue.py: to 1e6 kg cm^2)
        inertia = row.number("mass_kg", min=0.0, max=1e3) if row.has("mass_kg") else \
            row.number("inertia_kg_cm2", min=0.0, max=1e6) * 1e-4
        members.append(Member(name, stage, inertia))
        row.finish()
    if len({x.name for x in members}) != len(members):
        raise f.error("members", "two members have the same name")
    gearboxes = _gearbox_file(f, base_dir, transmission)
    choose = f.string("choose", "least_overload", choices=RANKINGS)
    f.finish()
    efficiency = getattr(transmission, "efficiency", 1.0)
    return DriveSpec(motor, Load(mass, gravity, tuple(forces), tuple(members), efficiency), limits, profile, tmin, tmax, belt,
                     cord, service, allowable, tuple(resolved), f.file, gearboxes, choose)


#: ``[drive] choose``: how ``size`` ranks the pairs that fit (DriveSpec.choose)
RANKINGS = ("least_overload", "smallest_motor")


def _gearbox_file(f, base_dir: Path | None, transmission) -> str | None:
    """``[drive] gearboxes``: a gearbox catalogue beside the problem, or the shipped one by its file name; refused
    for a transmission without a ratio to choose (``with_gearbox``)."""
    name = f.string("gearboxes", None)
    if name is None:
        return None
    if transmission is not None and not hasattr(transmission, "with_gearbox"):
        raise f.error("gearboxes", f"chooses the ratio of a gearbox or a linkage's crank drive; the transmission, a "
                                   f"{transmission.label}, has none to choose")
    from .gearboxes import gearbox_catalogue_file

    path = resolve_catalogue_file(name, base_dir)
    if path is None and name == gearbox_catalogue_file().name:
        path = gearbox_catalogue_file()   # the shipped gearboxes, named by their file name
    if path is None:
        raise f.error("gearboxes", f"gearbox catalogue {name!r} not found (looked for {(base_dir or Path('.')) / name}, "
                                   f"and strokeopt ships {gearbox_catalogue_file().name})")
    return str(path)



def _friction(row, name: str, rotary: bool) -> LoadForce:
    """Friction against the load's velocity: ``coulomb_N`` and ``viscous_N_s_m`` (a rotary load: ``coulomb_N_m``,
    ``viscous_N_m_s_rad``), and the speed over which the collocation's smooth sign turns (``smoothing_m_s``,
    ``smoothing_deg_s``); the checks after the solve use the exact sign."""
    # forces as the other load forces' (to 100 kN); a viscous drag to 1e6 N s/m (a damper, not a guide);
    # the smoothing from 1 um/s to 1 m/s (a move's speeds are 0.1 to 10 m/s)
    if rotary:
        return LoadForce(name, "friction", 1.0, row.number("coulomb_N_m", 0.0, min=0.0, max=1e5),
                         viscous=row.number("viscous_N_m_s_rad", 0.0, min=0.0, max=1e6),
                         smoothing=math.radians(row.number("smoothing_deg_s", 0.1, min=1e-4, max=100.0)))
    return LoadForce(name, "friction", 1.0, row.number("coulomb_N", 0.0, min=0.0, max=1e5),
                     viscous=row.number("viscous_N_s_m", 0.0, min=0.0, max=1e6),
                     smoothing=row.number("smoothing_m_s", 1e-3, min=1e-6, max=1.0))


def _rotary_load(row, name: str, kind: str, direction: float) -> LoadForce:
    """A load torque on a rotary load: ``torque_N_m`` (constant), or a torsion spring met at
    ``contact_position_deg`` with ``preload_N_m`` and ``stiffness_N_m_rad`` (a cloth fell the reed beats
    against); the same :class:`LoadForce`, in N m, N m/rad and rad."""
    if kind == "constant":  # torques up to 100 kN m; stiffnesses up to 1e9 N m/rad (a contact); within 100 turns
        return LoadForce(name, kind, direction, row.number("torque_N_m", min=0.0, max=1e5))
    return LoadForce(name, kind, direction, row.number("preload_N_m", 0.0, min=0.0, max=1e5),
                     row.number("stiffness_N_m_rad", min=0.0, max=1e9),
                     math.radians(row.number("contact_position_deg", min=-36000.0, max=36000.0)))


def model_spring_force(row, name: str, direction: float, model, reference=None) -> LoadForce:
    """A spring load force taken from the contact model's spring ``model_spring`` (one source for both): its
    stiffness, and as preload the stiffness times its compression at installation (free minus installed length)."""
    spring = row.string("model_spring")
    for key in ("preload_N", "stiffness_N_m"):
        if row.has(key):
            raise row.error(key, f"comes from model_spring = {spring!r} ([model.springs.{spring}]); remove it")
    if model is None:
        raise row.error("model_spring", "names a spring of [model], but the problem has no [model] section")
    if spring not in model.springs:
        raise row.error("model_spring", f"unknown spring {spring!r}; [model.springs] has: {', '.join(model.springs) or 'none'}")
    el = model.springs[spring]
    if el.force_law is not None:
        raise row.error("model_spring", f"spring {spring!r} has a force law; a load force needs a linear spring")
    if row.has("model_contact"):
        if row.has("contact_position_mm"):
            raise row.error("contact_position_mm", "comes from model_contact (where that contact of [model] "
                                                   "closes); remove it")
        position = contact_closure_position(row, model, reference)
    else:
        position = row.number("contact_position_mm", min=-1e4, max=1e4) * 1e-3
    return LoadForce(name, "spring", direction, el.stiffness * el.preload, el.stiffness, position, spring)


def contact_closure_position(row, model, reference) -> float:
    """The stroke position [m] at which the contact ``model_contact`` of ``[model]`` (between a body and the
    frame) closes, in the problem's coordinates: the model's coordinate of a body is ``sign * (s - s_ref)``
    (``reference``, zero at the start of the handover move: contact/simulate.drive_reference), so the gap
    and the stroke are stated once, in ``[model]`` and ``[timing]``."""
    name = row.string("model_contact")
    if name not in model.contacts:
        raise row.error("model_contact", f"unknown contact {name!r}; [model.contacts] has: "
                                         f"{', '.join(model.contacts) or 'none'}")
    el = model.contacts[name]
    if "frame" not in el.bodies or reference is None:
        raise row.error("model_contact", f"contact {name!r} is between {el.bodies[0]} and {el.bodies[1]}: the "
                                         "position where a load force starts needs a contact with the frame on a "
                                         "model driven along the stroke")
    sign, s_ref = reference
    # closed where x_a - x_b + offset = 0 (offset = -gap): the moving body at -offset, or at +offset
    x = -el.offset if el.bodies[1] == "frame" else el.offset
    return s_ref + sign * x


def with_model_springs(load: Load, stiffness: dict) -> Load:
    """``load`` with the stiffness of the model springs in ``stiffness`` (name -> N/m, numbers or CasADi symbols)
    replaced in every load force derived from them; the installed compression (preload length) stays."""
    forces = []
    for f in load.forces:
        k = stiffness.get(f.spring) if f.spring is not None else None
        if k is None:
            forces.append(f)
            continue
        length = f.force / f.stiffness if f.stiffness else 0.0
        forces.append(replace(f, force=k * length, stiffness=k))
    return replace(load, forces=tuple(forces))
