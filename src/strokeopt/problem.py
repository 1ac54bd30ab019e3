"""The design problem: one validated, typed object, SI units inside, and how parsed data becomes one.

:func:`parse_problem` turns the data of a problem file (a dict, after ``extends`` and ``--set``) into a
:class:`Problem`; each ``[section]`` is read by the reader of the package that owns it (``[drive]`` by
``drive``, ``[design]`` by ``design``, ...), all through :class:`~strokeopt.io.fields.Fields`.
:meth:`Problem.with_overrides` makes a variant in memory. Reading files is
:mod:`strokeopt.files.problem_file`'s (``load_problem``); nothing here touches the disk.
"""

from __future__ import annotations

import copy
import math
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import TYPE_CHECKING

from .contact.model import parse_model
from .contact.scene import parse_scenes
from .contact.travel import check_travel
from .design.transcription.contact_setup import check_contact
from .design.transcription.free import check_free, check_outer
from .design.transcription.settings import parse_design
from .drive.spec import parse_drive
from .drive.transmission import Transmission
from .transmissions import TRANSMISSIONS
from .errors import ProblemError
from .io.cycle import CYCLE_NOUN, STITCH, MachineCycle
from .io.fields import _REQUIRED, Fields, apply_overrides
from .motion.laws import LAW_CHOICES, LAW_PARAMETERS, MotionLaw, make_law, points_law
from .motion.timing import INTERVAL_TIMES, SPM_RANGE, Interval, TimingDiagram
from .servo.kernel import ServoErrorTerm
from .servo.plant import varies
from .servo.settings import parse_servo

if TYPE_CHECKING:
    from .contact.model import Model
    from .contact.scene import Scene
    from .design.transcription.settings import DesignSettings
    from .drive.spec import DriveSpec
    from .servo.settings import ServoSettings


@dataclass(frozen=True)
class Problem:
    """A validated design problem, SI units inside."""

    file: Path
    name: str
    description: str
    spm: float
    timing: TimingDiagram
    default_law: MotionLaw
    transmission: Transmission  # [transmission]: the toothed pulley, with its teeth (no inertia: the ideal drive), or a screw and lever
    data: dict = field(repr=False)  # the raw data after overrides, for reporting
    model: Model | None = field(default=None, repr=False)  # [model]: the contact model (contact/model.py)
    scenes: dict[str, Scene] | None = field(default=None, repr=False)  # [scenes.*] (contact/scene.py)
    drive: DriveSpec | None = field(default=None, repr=False)  # [drive]: motor, load, limits (drive/spec.py)
    design: DesignSettings | None = field(default=None, repr=False)  # [design]: optimal stroke (design/settings.py)
    servo: "ServoSettings | None" = field(default=None, repr=False)  # [servo]: servo loop and belt (servo/settings.py)
    #: the ``--set`` texts applied to the file (a design records them, so every command that reads it
    #: sees the same problem)
    overrides: tuple = field(default=(), repr=False)
    #: the terms of the handover position error the design holds (design.request.ErrorTerm; the
    #: problem file gives the servo's term with a [servo] section)
    error_terms: tuple = field(default=(), repr=False)
    #: [machine] cycle: what one cycle of the machine is called ("stitch", "pick") and its rate's unit
    cycle: MachineCycle = field(default=STITCH)

    @property
    def pulley_teeth(self) -> int | None:
        """Tooth count of the problem's pulley (``transmission.pulley_teeth``); None without a pulley."""
        return getattr(self.transmission, "teeth", None)

    @property
    def period(self) -> float:
        return self.timing.period(self.spm)

    def stroke(self, spm: float | None = None):
        """The classic-law stroke of this problem at ``spm`` (default: the problem's)."""
        return self.timing.stroke(self.spm if spm is None else spm)

    def with_law(self, law: MotionLaw) -> "Problem":
        """The same problem with every move following ``law``."""
        return replace(self, timing=self.timing.with_law(law), default_law=law)

    def with_overrides(self, overrides) -> "Problem":
        """The same problem with ``--set`` texts applied to its data (in memory, validated like a file's);
        the design records them beside the ones it had."""
        overrides = [overrides] if isinstance(overrides, str) else list(overrides)
        if not overrides:
            return self
        data = copy.deepcopy(self.data)
        overridden = apply_overrides(data, overrides, str(self.file))
        return replace(parse_problem(data, str(self.file), overridden, Path(self.file)),
                       overrides=(*self.overrides, *overrides))

    def with_spm(self, spm: float) -> "Problem":
        if not (isinstance(spm, (int, float)) and SPM_RANGE[0] <= spm <= SPM_RANGE[1]):
            raise ProblemError(str(self.file), "machine.spm", f"{spm!r} is outside the plausible range "
                                                              f"[{SPM_RANGE[0]:g}, {SPM_RANGE[1]:g}]")
        return replace(self, spm=float(spm))


def parse_problem(data: dict, file: str, overridden: frozenset = frozenset(), path: Path | None = None) -> Problem:
    top = Fields(_implied(data), file, "", overridden)

    meta = top.table("problem")
    name = meta.string("name")
    description = meta.string("description", "")
    meta.finish()

    machine = top.table("machine")
    spm = machine.number("spm", min=SPM_RANGE[0], max=SPM_RANGE[1])  # problem.SPM_RANGE says why
    # a cam revolution per 100 stitches to 100 revolutions per stitch: gears and indexing drives, not beyond
    revs = machine.number("cam_revolutions_per_stitch", 1.0, min=0.01, max=100.0)
    noun = machine.string("cycle", STITCH.noun)  # what one cycle of the machine is: "stitch", "pick"
    if not (len(noun) <= 24 and CYCLE_NOUN.fullmatch(noun)):
        raise machine.error("cycle", f"{noun!r} is not a cycle noun: one to three lower-case words of letters "
                                     f"(\"stitch\", \"pick\", \"test cycle\"), at most 24 characters")
    machine.finish()

    motion = top.table("motion")
    default_law = _read_law(motion, "law")
    motion.finish()

    timing = _read_timing(top.table("timing"), default_law, revs)
    _check_cycle(machine, timing, spm)

    transmission = _read_transmission(top.table("transmission"), timing)

    model = parse_model(top.table("model", required=False), transmission)
    scenes = parse_scenes(top.table("scenes", required=False), model)
    drive_table = top.table("drive", required=False)
    drive = parse_drive(drive_table, (path or Path(file)).parent, model, _model_reference(model, timing),
                        rotary=timing.rotary, transmission=transmission) if drive_table is not None else None
    if model is not None and model.transmission is not None and timing.intervals[0].start_position != 0:
        raise ProblemError(file, "timing.start_position_mm", "a model on the transmission's members starts at the "
                                                             "transmission's zero: start_position_mm must be 0")
    check_travel(model, timing, _model_reference(model, timing), file, unit_key(timing.unit))  # fits its stops
    if drive is not None:
        stages = transmission.stage_names()
        for k, member in enumerate(drive.load.members):
            if member.stage not in stages:
                raise ProblemError(file, f"drive.members[{k + 1}].stage", f"{member.stage!r} is no stage of the "
                                                                         f"{transmission.name}: {', '.join(stages)}")
    design_table = top.table("design", required=False)
    design = parse_design(design_table, rotary=timing.rotary) if design_table is not None else None
    check_contact(design.contact if design is not None else None, model, scenes, file)
    check_free(design.free if design is not None else (), model, drive, file, transmission, timing.position_range)
    check_outer(design.outer if design is not None else (), data, file)
    servo_table = top.table("servo", required=False)
    servo = parse_servo(servo_table, timing, spm, transmission) if servo_table is not None else None
    if top.has("synthesis") and (top.raw("synthesis") is None or transmission.name != "linkage"):
        raise top.error("synthesis", "states the targets `strokeopt linkage --synthesize` fits a linkage to: a "
                                     "[transmission] type = \"linkage\" has them")
    top.finish()
    return Problem(
        file=path or Path(file),
        name=name,
        description=description,
        spm=spm,
        cycle=MachineCycle(noun),
        timing=timing,
        default_law=default_law,
        transmission=transmission,
        data=data,
        model=model,
        scenes=scenes,
        drive=drive,
        design=design,
        servo=servo,
        # the design's servo term is the loop's error linear in the stroke (servo/table_term.py): a transmission of
        # varying ratio has no linear loop, its accuracy is the full simulation's (servo/varying.py), checked after
        error_terms=(ServoErrorTerm(),) if servo is not None and not varies(transmission, timing) else (),
    )


def _implied(data: dict) -> dict:
    """``data`` with the tables its transmission means where the file states no ``[timing]``
    (``Transmission.implied``: a linkage's crank turning at constant speed) under the file's own."""
    table = data.get("transmission")
    cls = TRANSMISSIONS.get(table.get("type")) if isinstance(table, dict) else None
    if "timing" in data or cls is None or cls.implied is None:
        return data
    out = dict(data)
    for key, tables in cls.implied.items():
        out[key] = {**copy.deepcopy(tables), **out.get(key, {})}
    return out


def _read_law(f: Fields, key: str, default: MotionLaw | None = None) -> MotionLaw:
    """A law name plus its parameters, read from the same table (``law = "modified_sine"``, ``chi = 0.095``)."""
    name = f.string(key, None if default is not None else _REQUIRED, choices=LAW_CHOICES)
    params = {}
    for pname in LAW_PARAMETERS:
        if f.has(pname):
            params[pname] = f.number(pname)  # its range is the law's own (motion/laws.py, make_law)
    if name is None:
        if params:
            name = default.name
            params = {**default.params, **params}
        else:
            return default
    return make_law(name, where=(f.file, f.where(key)), **params)


#: Plausible cycle (cam revolution) time [s]: 1 ms (20000 spm at two stitches a revolution) to 10 min; and the
#: shortest move a drive can follow [s]. Outside them the stroke's derivatives overflow or the servo
#: simulation's time grid cannot hold a cycle.
CYCLE_RANGE_S = (1e-3, 600.0)
SHORTEST_MOVE_S = 1e-4


def _check_cycle(machine: Fields, timing: TimingDiagram, spm: float) -> None:
    """The stitch rate, cam revolutions per stitch and spans together: a cycle and moves a drive can make."""
    period = timing.period(spm)
    if not CYCLE_RANGE_S[0] <= period <= CYCLE_RANGE_S[1]:
        raise machine.error("spm", f"{spm:g} spm at cam_revolutions_per_stitch = {timing.cam_revolutions_per_stitch:g} "
                                   f"is a cycle of {period:.3g} s, outside the plausible range "
                                   f"[{CYCLE_RANGE_S[0]:g}, {CYCLE_RANGE_S[1]:g}] s")
    sch = timing.schedule(spm)
    move = min(d for itv, d in zip(timing.intervals, sch.duration) if itv.is_move)
    if move < SHORTEST_MOVE_S:
        raise machine.error("spm", f"at {spm:g} spm the shortest move lasts {move * 1e6:.3g} us, below the "
                                   f"{SHORTEST_MOVE_S * 1e6:g} us a drive can follow: lower the rate or widen the move")


#: How far the span a published time implies may differ from the file's span_deg [deg]: the
#: thesis's own times and spans differ by up to 0.9 deg (reference problem, move 3 and dwell 6).
PUBLISHED_SPAN_TOLERANCE_DEG = 1.0
#: The shortest span of a move [deg of cam angle]: below it a move is an impact, not a cam motion.
MOVE_SPAN_MIN_DEG = 0.1


def _read_timing(f: Fields, default_law: MotionLaw, revs: float) -> TimingDiagram:
    times = f.string("interval_times", "nominal", choices=INTERVAL_TIMES)
    # a linear load states its positions in mm, a rotary one (a sley on its shaft) in deg; one unit per file
    rows = f.tables("intervals")
    unit = _timing_unit(f, rows)
    ukey, to_si = ("mm", 1e-3) if unit == "m" else ("deg", math.pi / 180)
    # lengths in mm: within +-100 m of the origin, strokes up to 100 m (a loom sley swings 0.1 m, the known
    # optima use 1 m, a gantry tens of metres), so no position overflows a kinematic table; angles within
    # +-100 turns, strokes up to 100 turns (a sley swings 19.5 deg, an indexing table a turn)
    lim = 1e5 if unit == "m" else 36000.0
    position = f.number(f"start_position_{ukey}", min=-lim, max=lim) * to_si
    if len(rows) < 2 and not (len(rows) == 1 and rows[0].has("end") and rows[0].raw("end") == "speed"):
        raise f.error("intervals", f"needs at least two intervals (a move and a dwell; one move only where it ends "
                                   f"at speed, a crank turning), got {len(rows)}")
    intervals = []
    n_moves = 0
    for row in rows:
        name = row.string("name")
        span = row.number("span_deg", min=0.0, max=360.0)
        stroke = row.number(f"stroke_{ukey}", 0.0, min=0.0, max=lim) * to_si
        # published interval times: a cycle of at most an hour (only their proportions are used)
        published = row.number("published_time_s", None, min=0.0, max=3600.0) if times == "nominal" else \
            row.number("published_time_s", positive=True, max=3600.0)
        handover = row.boolean("handover", False)
        # a move's end: at rest (a dwell or a stop follows) or at speed (the next move starts at it)
        end_speed = row.string("end", "rest", choices=("rest", "speed")) == "speed" if stroke > 0 else False
        if stroke > 0:
            if span < MOVE_SPAN_MIN_DEG:
                raise row.error("span_deg", f"a move ({stroke / to_si:g} {ukey}) needs a span of at least "
                                            f"{MOVE_SPAN_MIN_DEG:g} deg, got {span:g} deg")
            direction = row.string("direction", choices=("up", "down"))
            if row.has("law") and row.raw("law") == "points":  # the move's own points (motion/laws.points_law)
                law = points_law(row.raw("angles_deg"), row.raw(f"positions_{ukey}"), span, stroke / to_si,
                                 row.number("rest_order", 2, integer=True, min=1, max=3),
                                 where=(row.file, row.path), positions_key=f"positions_{ukey}")
            else:
                law = _read_law(row, "law", default_law)
            n_moves += 1
            signed = stroke if direction == "up" else -stroke
            move_index = n_moves
        else:
            for key in ("direction", "law", "end", "angles_deg", f"positions_{ukey}", "rest_order", *LAW_PARAMETERS):
                if row.has(key):
                    raise row.error(key, f"a dwell (stroke_{ukey} = 0) has no " + key)
            if handover:
                raise row.error("handover", "must be on the move that ends at the handover position, not on a dwell")
            law, signed, move_index = None, 0.0, None
        row.finish()
        intervals.append(Interval(len(intervals) + 1, name, span, position, position + signed, law,
                                  published, handover, move_index, end_speed))
        position += signed
    total = sum(i.span_deg for i in intervals)
    if abs(total - 360.0) > 1e-6:
        raise f.error("intervals", f"spans add to {total:g} deg, not 360 deg: an interval is missing or a span is wrong")
    if times == "published":
        # the times set the schedule; the spans must still say the same (an edited span would be ignored)
        t_total = sum(i.published_time_s for i in intervals)
        for i, row in zip(intervals, rows):
            implied = 360.0 * i.published_time_s / t_total
            if abs(implied - i.span_deg) > PUBLISHED_SPAN_TOLERANCE_DEG:
                raise row.error("span_deg", f"{i.span_deg:g} deg, but interval_times = \"published\" takes the span "
                                            f"from published_time_s: {implied:.2f} deg; change both, or set "
                                            f"timing.interval_times = \"nominal\" to use the spans")
    for k, itv in enumerate(intervals):   # a move at speed hands it to a move, never to a dwell
        after = intervals[(k + 1) % len(intervals)]
        if itv.end_speed and not after.is_move:
            raise rows[k].error("end", f"\"speed\": the interval after {itv.name!r} is the dwell {after.name!r}, which "
                                       "starts at rest; end = \"rest\", or make the next interval a move")
    # a crank turning once a cycle advances a turn: its positions close the cycle modulo it
    advance = f.number("advance_deg", 0.0, min=-36000.0, max=36000.0) * to_si if unit == "rad" else 0.0
    start = intervals[0].start_position
    if abs(position - start - advance) > 1e-9:
        moved = f" + advance_deg {advance / to_si:g}" if advance else ""
        raise f.error("intervals", f"the strokes do not close the cycle: the last interval ends at {position / to_si:g} "
                                   f"{ukey}, the first starts at {start / to_si:g}{moved} {ukey} (a move missing, or a "
                                   "direction wrong?)")
    if n_moves == 0:
        raise f.error("intervals", f"has no move (every stroke_{ukey} is 0)")
    if sum(i.handover for i in intervals) > 1:
        raise f.error("intervals", "more than one interval is marked handover = true")
    f.finish()
    return TimingDiagram(tuple(intervals), revs, times, unit, advance)


def unit_key(unit: str) -> str:
    """The suffix of a problem file's position keys for the load's SI unit: "mm" for "m", "deg" for "rad"."""
    return "mm" if unit == "m" else "deg"


def _timing_unit(f: Fields, rows: list[Fields]) -> str:
    """"m" when ``[timing]`` states its positions and strokes in mm, "rad" when in deg; both is refused."""
    found = {u for u, key in (("m", "mm"), ("rad", "deg"))
             if f.has(f"start_position_{key}") or any(r.has(f"stroke_{key}") for r in rows)}
    if len(found) > 1:
        raise f.error("start_position_deg" if f.has("start_position_deg") else "intervals",
                      "states positions in both mm and deg: a problem states one unit (mm for a linear load, "
                      "deg for a rotary one)")
    return found.pop() if found else "m"


def _read_transmission(trans: Fields, timing: TimingDiagram) -> Transmission:
    """``[transmission]``: its ``type`` (transmissions.py: a belt pulley by default) reads the rest; the
    load it drives must be the one ``[timing]`` states (mm for a translating load, deg for a rotary one)."""
    kind = trans.string("type", next(iter(TRANSMISSIONS)), choices=tuple(TRANSMISSIONS))
    cls = TRANSMISSIONS[kind]
    if cls.load_unit is not None and cls.load_unit != timing.unit:  # None: its own fields say (a linkage's output)
        others = sorted(name for name, c in TRANSMISSIONS.items() if c.load_unit in (timing.unit, None))
        raise trans.error("type", f"{kind!r} drives a {'rotary' if cls.load_unit == 'rad' else 'linear'} load, but "
                                  f"[timing] states its positions in {unit_key(timing.unit)}: a {cls.label} takes "
                                  f"positions and strokes in {unit_key(cls.load_unit)} (start_position_"
                                  f"{unit_key(cls.load_unit)}, stroke_{unit_key(cls.load_unit)}); for positions in "
                                  f"{unit_key(timing.unit)}: {', '.join(others)}")
    return cls.read(trans, timing)


def _model_reference(model, timing: TimingDiagram) -> tuple[float, float] | None:
    """``(sign, s_ref)`` of a model driven along the stroke: its coordinate is ``sign * (s - s_ref)``, zero at
    the start of the handover move (the first move without one), positive in its direction; None without a
    model or for a model on a transmission's members (contact/simulate.drive_reference, the same rule)."""
    if model is None or model.transmission is not None:
        return None
    move = timing.handover_move or timing.moves[0]
    return (1.0 if move.stroke > 0 else -1.0), move.start_position
