"""The ``[design]`` section of a problem file: :class:`DesignSettings` and its reader.

First step of the design's flow (settings -> :mod:`.request` -> :mod:`.nlp` -> :mod:`.solve`):
:func:`parse_design` is called by :func:`strokeopt.files.problem_file.load_problem` with the
section's :class:`~strokeopt.io.fields.Fields`; unknown keys are errors.
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass, field

from ...drive.transmission import TEETH_RANGE
from ...motion.timing import SPM_RANGE
from .collocation import Mesh
from .objectives import OBJECTIVES, objective_of
from .solver import check_solver_options

MOTOR_CHOICES = ("fixed", "enumerate", "bonmin")


@dataclass(frozen=True)
class ContactSettings:
    """``[design.contact]``: what the design holds of the contact model (design/contact_setup.py checks the names).

    ``keep_closed``: contacts joining a follower to the driven body that must stay closed (their force at
    least ``min_contact_force`` [N]) while the follower rides on it; ``impact_velocity_max`` [m/s]: the
    velocity with which the cluster meets the ``[model.events] impact`` contact; ``lag_max`` [m]: the
    largest lag the verification accepts; ``scene``: the scene whose bodies and elements count (None:
    ``release`` if the problem has it, else its first).
    """

    keep_closed: tuple[str, ...] = ()
    min_contact_force: float = 1.0
    impact_velocity_max: float | None = None
    lag_max: float = 0.05e-3
    scene: str | None = None

PULLEY_CHOICES = ("fixed", "optimise", "continuous")


@dataclass(frozen=True)
class DesignSettings:
    """The ``[design]`` section of a problem file (SI units inside).

    ``rest_order``: derivatives that vanish at the ends of every move
    (1: velocity; 2: velocity and acceleration, the default for a servo
    following a cam table; 3: also jerk, with the jerk continuous inside the move).
    ``jerk_max``: bound on |jerk| [m/s^3] (None: unbounded);
    ``jerk_max_from_law``: bound each move by the peak jerk of the file's
    motion law on that move instead (at the design's own rate; ``jerk_law_spm``, the file's
    ``jerk_max_from_law = <spm>``: at that rate, a bound in m/s^3 that a free cycle time does not scale,
    the classic machine's jerk at its operating point). ``accuracy``: allowed position error at
    the handover [m]. ``check_points``: fine-grid points per mesh interval;
    ``check_tolerance``: relative violation between nodes that triggers a
    mesh refinement (at most ``refinements`` doublings). ``torque_reserve``: the share of the
    motor's torque limit the design leaves unused, for the servo loop (its torque command exceeds
    the rigid load's near the limit).
    """

    objective: str = "min_peak_torque"
    mesh_intervals: int = 40
    collocation_degree: int = 3
    rest_order: int = 2
    jerk_max: float | None = None
    jerk_max_from_law: bool = False
    accuracy: float = 0.5e-3
    motor_choice: str = "fixed"
    pulley: str = "fixed"
    pulley_teeth_min: int | None = None
    pulley_teeth_max: int | None = None
    check_points: int = 20
    check_tolerance: float = 0.005
    refinements: int = 2
    include_pulley_inertia: bool = True
    solver_options: dict = field(default_factory=dict)
    contact: ContactSettings | None = None
    #: ``[design.free.<element>]``: (element, lower, upper stiffness [N/m]) of the model parameters that are
    #: design variables (design/free.py checks the names)
    free: tuple = ()
    #: a stepper's pull-out curve held (True) or only reported (False: the check table says by how much the
    #: design exceeds it, status "limits exceeded"), for a move the motor cannot make, to see it anyway
    enforce_pull_out: bool = True
    torque_reserve: float = 0.0
    jerk_law_spm: float | None = None
    #: min_time: the relative width of a bracket of rates at which a rate that never settled is capped at its lower
    #: end (refine.solve_free_time; not a file field: the trade-off, which reports on a 10 spm grid, widens it)
    rate_bracket: float = 4e-3
    #: a catalogue search drops the motors a rigid lower bound of the peak torque rules out before solving
    #: (search/bounds.py; the answer is the exhaustive search's, faster where most motors cannot make the move)
    prune_catalogue: bool = True
    #: ``cam_tables``: the controller formats ``solve --out`` writes beside design.json (files/cam_formats.py)
    cam_tables: tuple = ()
    #: ``lengthen``: the move whose time ``max_duration`` makes as long as the limits allow (the other moves'
    #: times give it theirs; the dwells keep theirs)
    lengthen: str | None = None
    #: ``monotonic``: every move keeps its direction (its speed never changes sign: a crank that turns one way, a
    #: follower that does not turn back inside a move), held everywhere (Bernstein hull of the speed)
    monotonic: bool = False
    #: the ``[design.free.<name>]`` entries the collocation does not carry (:class:`OuterFree`, at most one): searched
    #: around the verified solve (studies/outer.py)
    outer: tuple = ()

    @property
    def mesh(self) -> Mesh:
        return Mesh(self.mesh_intervals, self.collocation_degree)


#: Handover accuracies a design may ask for [mm]: 0.1 um (below any encoder count of a sewing machine's
#: axis) to 100 mm (no accuracy at all); ``[design] handover_accuracy_mm`` and ``tradeoff --accuracies``.
ACCURACY_RANGE_MM = (1e-4, 100.0)


#: Handover accuracies of a rotary load [deg]: 0.1 arcsec (an encoder count of a fine direct drive) to 10 deg.
ACCURACY_RANGE_DEG = (3e-5, 10.0)


def _read_accuracy(f, rotary: bool) -> float:
    """The handover accuracy [m, or rad for a rotary load]: ``handover_accuracy_mm`` (default 0.5 mm, digest A.1)
    or, where the load turns, ``handover_accuracy_deg`` (default 0.05 deg: an estimate, a sley's 0.26 mm at its
    293.8 mm reed, of the order of the needle bar's 0.5 mm)."""
    key, other = ("handover_accuracy_deg", "handover_accuracy_mm") if rotary else \
        ("handover_accuracy_mm", "handover_accuracy_deg")
    if f.has(other):
        raise f.error(other, f"the load {'turns' if rotary else 'translates'} ([timing] in "
                             f"{'deg' if rotary else 'mm'}): state its accuracy as {key}")
    if rotary:
        return math.radians(f.number(key, 0.05, min=ACCURACY_RANGE_DEG[0], max=ACCURACY_RANGE_DEG[1]))
    # 0.1 um (an encoder count of a fine drive) to 100 mm (no constraint on any textile mechanism)
    return f.number(key, 0.5, min=ACCURACY_RANGE_MM[0], max=ACCURACY_RANGE_MM[1]) * 1e-3


def parse_design(f, *, file: str = "", rotary: bool = False) -> DesignSettings:
    """Read the ``[design]`` table with the :class:`~strokeopt.problem.Fields` reader (unknown keys are errors);
    ``rotary``: the load turns ([timing] in deg), so its handover accuracy is ``handover_accuracy_deg``."""
    if f is None:
        return DesignSettings()
    objective = f.string("objective", "min_peak_torque", choices=tuple(OBJECTIVES))
    # mesh: 2000 intervals of degree 9 per move is ~20000 collocation points, beyond any solve time worth waiting
    n = f.number("mesh_intervals", 40, integer=True, min=1, max=2000)
    d = f.number("collocation_degree", 3, integer=True, min=1, max=9)
    rest = f.number("rest_order", 2, integer=True, min=1, max=3)
    # jerk bound up to 1e9 m/s^3 (a 1 mm move in 0.1 ms); beyond it leave it out (unbounded)
    jerk = f.number("jerk_max_m_s3", None, positive=True, max=1e9)
    # true: each move's law's peak jerk at the design's rate; a rate [spm]: the law's jerk there, in m/s^3 at
    # every rate (the classic machine's jerk at its operating point)
    law = f.raw("jerk_max_from_law", False)
    law_spm = None
    if not isinstance(law, bool):
        if not isinstance(law, (int, float)):
            raise f.error("jerk_max_from_law", f"must be true, false or a stitch rate [spm] (the law's jerk at that "
                                               f"rate), got {law!r}")
        law_spm = f.number("jerk_max_from_law", min=SPM_RANGE[0], max=SPM_RANGE[1])
    from_law = law is True or law_spm is not None
    if from_law and jerk is not None:
        raise f.error("jerk_max_from_law", "give either jerk_max_m_s3 or jerk_max_from_law = true, not both")
    if rest == 3 and d < 2:
        raise f.error("collocation_degree", "rest_order = 3 (jerk continuous) needs collocation_degree >= 2")
    if objective_of(objective).jerk_continuous and d < 2:
        raise f.error("collocation_degree", f"{objective} needs collocation_degree >= 2 (snap of the acceleration "
                                            "polynomial)")
    accuracy = _read_accuracy(f, rotary)
    motor_choice = f.string("motor_choice", "fixed", choices=MOTOR_CHOICES)
    pulley = f.string("pulley", "fixed", choices=PULLEY_CHOICES)
    zmin = f.number("pulley_teeth_min", None, integer=True, min=TEETH_RANGE[0], max=TEETH_RANGE[1])  # see
    zmax = f.number("pulley_teeth_max", None, integer=True, min=TEETH_RANGE[0], max=TEETH_RANGE[1])  # transmission
    if zmin is not None and zmax is not None and zmax < zmin:
        raise f.error("pulley_teeth_max", f"must be at least pulley_teeth_min = {zmin}, got {zmax}")
    check_points = f.number("check_points", 20, integer=True, min=2, max=1000)
    # relative violation between nodes: from IPOPT's own precision (1e-12) to 100 % (a check that checks nothing)
    check_tol = f.number("check_tolerance", 0.005, min=1e-12, max=1.0)
    refinements = f.number("refinements", 2, integer=True, min=0, max=6)
    pulley_inertia = f.boolean("include_pulley_inertia", True)
    # 0 (the rigid load may use the whole limit) to 90 % (a design that uses a tenth of its motor)
    reserve = f.number("torque_reserve_pct", 0.0, min=0.0, max=90.0) / 100
    solver = f.table("solver", required=False)
    options = {}
    if solver is not None:
        for key in list(solver.data):
            value = solver.raw(key)
            # a table is the dotted names written as keys: [design.solver.ipopt] max_iter = 500, or
            # --set design.solver.ipopt.max_iter=500, is "ipopt.max_iter" = 500
            flat = _dotted(key, value) if isinstance(value, dict) else {key: value}
            for name, item in flat.items():
                if not isinstance(item, (int, float, str, bool)):
                    raise solver.error(name, f"solver options must be numbers, strings or booleans, got {item!r}")
            options.update(flat)
        solver.finish()
        problem = check_solver_options(options)  # asks the solver itself, before any build
        if problem is not None:
            raise solver.error(*problem)
    contact = parse_contact(f.table("contact", required=False))
    free, outer = parse_free(f.table("free", required=False))
    pull_out = f.boolean("enforce_pull_out", True)
    prune_catalogue = f.boolean("prune_catalogue", True)
    cam_tables = _read_cam_tables(f)
    lengthen = f.string("lengthen", None)   # a move's name: the problem reader checks it against [timing]
    monotonic = f.boolean("monotonic", False)
    if (lengthen is None) == (objective == "max_duration"):
        raise f.error("lengthen" if lengthen is not None else "objective",
                      "names the move objective = \"max_duration\" makes as long as the limits allow: give both")
    f.finish()
    return DesignSettings(objective, n, d, rest, jerk, from_law, accuracy, motor_choice, pulley, zmin, zmax,
                          check_points, check_tol, refinements, pulley_inertia, options, contact, free, pull_out,
                          reserve, law_spm, prune_catalogue=prune_catalogue, cam_tables=cam_tables, lengthen=lengthen,
                          monotonic=monotonic, outer=outer)


#: The cam-table formats of controllers strokeopt writes (files/cam_formats.py holds what each is).
CAM_TABLE_FORMATS = ("csv", "xyva", "poly5", "segments")


def _read_cam_tables(f) -> tuple:
    """``cam_tables = ["xyva", "poly5"]``: formats from :data:`CAM_TABLE_FORMATS`, each once."""
    value = f.raw("cam_tables", [])
    if not isinstance(value, list) or not all(isinstance(v, str) for v in value):
        raise f.error("cam_tables", f"must be a list of format names ({', '.join(CAM_TABLE_FORMATS)}), got {value!r}")
    for name in value:
        if name not in CAM_TABLE_FORMATS:
            raise f.error("cam_tables", f"unknown format {name!r}; choose from {', '.join(CAM_TABLE_FORMATS)}")
    if len(set(value)) != len(value):
        raise f.error("cam_tables", "names a format twice")
    return tuple(value)


def _dotted(prefix: str, table: dict) -> dict:
    """``{"ipopt": {"max_iter": 3}}`` under ``prefix`` as CasADi's dotted option names: ``{"ipopt.max_iter": 3}``."""
    out = {}
    for key, value in table.items():
        name = f"{prefix}.{key}"
        out.update(_dotted(name, value) if isinstance(value, dict) else {name: value})
    return out


#: ``model.springs.X.stiffness_N_m`` / ``model.contacts.X.stiffness_N_m``: a field the collocation carries (free.py)
_STIFFNESS_FIELD = re.compile(r"^model\.(springs|contacts)\.([A-Za-z0-9_\-]+)\.stiffness_N_m$")


@dataclass(frozen=True)
class OuterFree:
    """A ``[design.free.NAME]`` the collocation does not carry: one number ``d`` in ``[lower, upper]`` that sets the
    problem fields of ``moves`` (``(field, coefficient)``): each ``file value + coefficient * d``, or ``d`` itself
    where ``absolute`` (``field = ...``, ``range = [...]``). Searched around the verified solve (studies/outer.py)."""

    name: str
    moves: tuple
    lower: float
    upper: float
    absolute: bool = False

    def overrides(self, d: float, nominal: dict) -> list[str]:
        """The ``--set`` texts at ``d`` (``nominal``: field -> its value in the file)."""
        return [f"{f}={(d if self.absolute else nominal[f] + c * d)!r}" for f, c in self.moves]

    def describe(self) -> str:
        if self.absolute:
            return self.moves[0][0]
        return ", ".join(f"{f} {c:+g}" for f, c in self.moves) + " per unit"


def parse_free(f) -> tuple[tuple, tuple]:
    """Read ``[design.free.<name>]`` tables: ``stiffness_N_m = [lower, upper]`` (the name an element of the model,
    checked by design/free.py), ``field = "model.contacts.c32.gap_mm"`` with ``range = [lower, upper]`` in the field's
    unit, or ``moves = {"model.contacts.c32.gap_mm" = -1.0, "model.contacts.pad.gap_mm" = 1.0}`` with ``range_mm`` (or
    ``range``) ``= [lower, upper]`` (a coupled move: one number shifting several fields); and
    ``[design.free.transmission]``: ``<field> = [lower, upper]`` in the field's unit (checked against the
    transmission there). A spring's or contact's stiffness is a variable of the collocation; any other field is
    searched around the solve (:class:`OuterFree`, at most one). Returns ``(collocation entries (name, lower,
    upper), searched entries)``, a transmission's named ``transmission.<field>``."""
    if f is None:
        return (), ()
    out, outer = [], []
    for name in list(f.data):
        t = f.table(name)
        if name == "transmission":
            for key in list(t.data):
                lo, hi = _bounds(t, key, "in the field's unit")
                if not (0 < lo <= hi < math.inf):
                    raise t.error(key, f"bounds [{lo:g}, {hi:g}] must satisfy 0 < lower <= upper")
                out.append((f"transmission.{key}", lo, hi))
            t.finish()
            continue
        forms = [k for k in ("stiffness_N_m", "field", "moves") if t.has(k)]
        if len(forms) != 1:
            raise t.error("", "needs one of: stiffness_N_m = [lower, upper] (the element's stiffness); field = \"PATH\" "
                              "with range = [lower, upper]; moves = {PATH = coefficient, ...} with range_mm = [lower, "
                              "upper]" + (f" (it has {', '.join(forms)})" if forms else ""))
        if forms[0] == "moves":
            moves = t.raw("moves")
            if not isinstance(moves, dict) or not moves or not all(
                    isinstance(c, (int, float)) and not isinstance(c, bool) and math.isfinite(c) and c != 0
                    for c in moves.values()):
                raise t.error("moves", f"needs {{PATH = coefficient, ...}}, each coefficient a non-zero number, got "
                                       f"{moves!r}")
            if not (t.has("range_mm") or t.has("range")):
                raise t.error("range_mm", "is required: the bounds [lower, upper] of the shift, in mm (range_mm) or in "
                                          "the fields' unit (range)")
            lo, hi = _range(t, "range_mm" if t.has("range_mm") else "range")
            outer.append(OuterFree(name, tuple((str(p), float(c)) for p, c in moves.items()), lo, hi))
            t.finish()
            continue
        if forms[0] == "field":
            path = t.string("field")
            lo, hi = _range(t, "range")
            m = _STIFFNESS_FIELD.match(path)
            if m is None:
                outer.append(OuterFree(name, ((path, 1.0),), lo, hi, absolute=True))
                t.finish()
                continue
            element = m.group(2)
            key = "range"
        else:
            element, key = name, "stiffness_N_m"
            lo, hi = _bounds(t, key, "in N/m")
        # a stiffness of 1 N/m (a hair spring) to 1e9 N/m (a penalty contact); equal bounds fix it there
        if not (1.0 <= lo <= hi <= 1e9):
            raise t.error(key, f"bounds [{lo:g}, {hi:g}] must satisfy 1 <= lower <= upper <= 1e9 (N/m)")
        t.finish()
        out.append((element, lo, hi))
    f.finish()
    if len(outer) > 1:
        raise f.error(outer[1].name, f"one [design.free] entry outside the collocation is searched around the solve; "
                                     f"this file has {len(outer)}: {', '.join(o.name for o in outer)} (free a spring's "
                                     "stiffness in the collocation, or fix all but one)")
    return tuple(out), tuple(outer)


def _range(t, key: str) -> tuple[float, float]:
    lo, hi = _bounds(t, key, "in the field's unit")
    if not (math.isfinite(lo) and math.isfinite(hi) and lo < hi):
        raise t.error(key, f"bounds [{lo:g}, {hi:g}] must be finite with lower < upper")
    return lo, hi


def _bounds(t, key: str, unit: str) -> tuple[float, float]:
    bounds = t.raw(key)
    if (not isinstance(bounds, list) or len(bounds) != 2
            or not all(isinstance(b, (int, float)) and not isinstance(b, bool) for b in bounds)):
        raise t.error(key, f"needs bounds [lower, upper] {unit}, got {bounds!r}")
    return float(bounds[0]), float(bounds[1])


def parse_contact(f) -> ContactSettings | None:
    """Read ``[design.contact]`` (names are checked against the model by design/contact_setup.py)."""
    if f is None:
        return None
    keep = f.raw("keep_closed", [])
    if not isinstance(keep, list) or not all(isinstance(x, str) for x in keep):
        raise f.error("keep_closed", f"must be an array of contact names, got {keep!r}")
    if len(set(keep)) != len(keep):
        raise f.error("keep_closed", "names a contact twice")
    # a contact force up to 10 kN (the needle bar's springs give 4.5 N; a loom's tens of newtons)
    force = f.number("min_contact_force_N", 1.0, min=0.0, max=1e4)
    # impact velocities: a stop is met at 0.01-100 m/s (the needle bar: 2-3 m/s)
    vmax = f.number("impact_velocity_max_m_s", None, min=0.01, max=100.0)
    # lag accepted by the verification: 0.1 um (a contact's deflection is 0.01 um) to 100 mm
    lag = f.number("lag_max_mm", 0.05, min=1e-4, max=100.0) * 1e-3
    scene = f.string("scene", None)
    f.finish()
    return ContactSettings(tuple(keep), force, vmax, lag, scene)
