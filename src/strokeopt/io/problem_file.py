"""Reading a design problem file (TOML) into a :class:`~strokeopt.problem.Problem`.

Keys carry their unit (``stroke_mm``, ``span_deg``); everything inside
strokeopt is SI. Each ``[section]`` is read by the reader of the package that
owns it (``[drive]`` by ``drive``, ``[design]`` by ``design``, ...), all
through :class:`~strokeopt.io.fields.Fields`.
"""

from __future__ import annotations

import tomllib
from pathlib import Path

from ..contact.model import parse_model
from ..contact.scene import parse_scenes
from ..design.settings import parse_design
from ..drive.spec import parse_drive
from ..drive.transmission import PROFILE_PITCH, BeltPulley
from ..errors import ProblemError
from ..motion.laws import LAW_NAMES, LAW_PARAMETERS, MotionLaw, make_law
from ..motion.timing import INTERVAL_TIMES, Interval, TimingDiagram
from ..problem import Problem
from ..servo.kernel import ServoErrorTerm
from ..servo.settings import parse_servo
from .fields import _REQUIRED, Fields, apply_overrides


def load_problem(path: str | Path, overrides: list[str] | None = None) -> Problem:
    """Read, override and validate a problem file."""
    path = Path(path)
    file = str(path)
    try:
        text = path.read_text(encoding="utf-8")
    except FileNotFoundError:
        raise ProblemError(file, "", "no such file") from None
    except (OSError, UnicodeDecodeError) as exc:
        raise ProblemError(file, "", f"cannot be read: {exc}") from None
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise ProblemError(file, "", f"is not valid TOML: {exc}") from None
    overridden = apply_overrides(data, list(overrides or []), file)
    return parse_problem(data, file, overridden, path)


def parse_problem(data: dict, file: str, overridden: frozenset = frozenset(), path: Path | None = None) -> Problem:
    top = Fields(data, file, "", overridden)

    meta = top.table("problem")
    name = meta.string("name")
    description = meta.string("description", "")
    meta.finish()

    machine = top.table("machine")
    spm = machine.number("spm", positive=True)
    revs = machine.number("cam_revolutions_per_stitch", 1.0, positive=True)
    machine.finish()

    motion = top.table("motion")
    default_law = _read_law(motion, "law")
    motion.finish()

    timing = _read_timing(top.table("timing"), default_law, revs)

    trans = top.table("transmission")
    trans.string("type", "belt_pulley", choices=("belt_pulley",))
    profile = trans.string("profile", "GT3", choices=tuple(PROFILE_PITCH))
    teeth = trans.number("pulley_teeth", integer=True, min=1)
    trans.finish()

    model = parse_model(top.table("model", required=False))
    scenes = parse_scenes(top.table("scenes", required=False), model)
    drive_table = top.table("drive", required=False)
    drive = parse_drive(drive_table, (path or Path(file)).parent) if drive_table is not None else None
    design_table = top.table("design", required=False)
    design = parse_design(design_table) if design_table is not None else None
    servo_table = top.table("servo", required=False)
    servo = parse_servo(servo_table, timing, spm) if servo_table is not None else None
    top.finish()
    return Problem(
        file=path or Path(file),
        name=name,
        description=description,
        spm=spm,
        timing=timing,
        default_law=default_law,
        transmission=BeltPulley.toothed(teeth, profile),
        data=data,
        model=model,
        scenes=scenes,
        drive=drive,
        design=design,
        servo=servo,
        error_terms=(ServoErrorTerm(),) if servo is not None else (),
    )


def _read_law(f: Fields, key: str, default: MotionLaw | None = None) -> MotionLaw:
    """A law name plus its parameters, read from the same table (``law = "modified_sine"``, ``chi = 0.095``)."""
    name = f.string(key, None if default is not None else _REQUIRED, choices=LAW_NAMES)
    params = {}
    for pname in LAW_PARAMETERS:
        if f.has(pname):
            params[pname] = f.number(pname)
    if name is None:
        if params:
            name = default.name
            params = {**default.params, **params}
        else:
            return default
    return make_law(name, where=(f.file, f.where(key)), **params)


#: How far the span a published time implies may differ from the file's span_deg [deg]: the
#: thesis's own times and spans differ by up to 0.9 deg (reference problem, move 3 and dwell 6).
PUBLISHED_SPAN_TOLERANCE_DEG = 1.0


def _read_timing(f: Fields, default_law: MotionLaw, revs: float) -> TimingDiagram:
    times = f.string("interval_times", "nominal", choices=INTERVAL_TIMES)
    position = f.number("start_position_mm") * 1e-3
    rows = f.tables("intervals")
    if len(rows) < 2:
        raise f.error("intervals", f"needs at least two intervals (a move and a dwell), got {len(rows)}")
    intervals = []
    n_moves = 0
    for row in rows:
        name = row.string("name")
        span = row.number("span_deg", min=0.0)
        stroke = row.number("stroke_mm", 0.0, min=0.0) * 1e-3
        published = row.number("published_time_s", None, min=0.0) if times == "nominal" else row.number("published_time_s", positive=True)
        handover = row.boolean("handover", False)
        if stroke > 0:
            if span <= 0:
                raise row.error("span_deg", f"a move ({stroke * 1e3:g} mm) needs a positive span, got {span:g} deg")
            direction = row.string("direction", choices=("up", "down"))
            law = _read_law(row, "law", default_law)
            n_moves += 1
            signed = stroke if direction == "up" else -stroke
            move_index = n_moves
        else:
            for key in ("direction", "law", *LAW_PARAMETERS):
                if row.has(key):
                    raise row.error(key, "a dwell (stroke_mm = 0) has no " + key)
            if handover:
                raise row.error("handover", "must be on the move that ends at the handover position, not on a dwell")
            law, signed, move_index = None, 0.0, None
        row.finish()
        intervals.append(Interval(len(intervals) + 1, name, span, position, position + signed, law,
                                  published, handover, move_index))
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
    start = intervals[0].start_position
    if abs(position - start) > 1e-9:
        raise f.error("intervals", f"the strokes do not close the cycle: the last interval ends at {position * 1e3:g} mm, "
                                   f"the first starts at {start * 1e3:g} mm (a move missing, or a direction wrong?)")
    if n_moves == 0:
        raise f.error("intervals", "has no move (every stroke_mm is 0)")
    if sum(i.handover for i in intervals) > 1:
        raise f.error("intervals", "more than one interval is marked handover = true")
    f.finish()
    return TimingDiagram(tuple(intervals), revs, times)
