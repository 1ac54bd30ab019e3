"""Reading and validating design problem files (TOML).

Keys carry their unit (``stroke_mm``, ``span_deg``); everything inside
strokeopt is SI. Every mistake is reported as ``file: field: what is wrong``
(a :class:`~strokeopt.errors.ProblemError`), unknown keys included, so a
misspelt setting never passes silently.

Overrides (``--set key.path=value`` on the command line, ``overrides=`` here)
are applied to the raw data before validation and validated like the file.
Array elements are addressed 1-based: ``timing.intervals[2].law=poly5``.
"""

from __future__ import annotations

import difflib
import math
import re
import tomllib
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any

from .design import DesignSettings, parse_design
from .drive import DriveSpec, parse_drive
from .servo import ServoSettings, parse_servo
from .errors import ProblemError
from .laws import LAW_NAMES, LAW_PARAMETERS, MotionLaw, make_law
from .model import Model, parse_model
from .scene import Scene, parse_scenes
from .timing import INTERVAL_TIMES, Interval, TimingDiagram
from .transmission import BeltPulley, gt3_pitch_diameter

_REQUIRED = object()


class Fields:
    """Checked, typed access to one TOML table; unknown keys are errors at :meth:`finish`."""

    def __init__(self, data: dict, file: str, path: str = "", overridden: frozenset = frozenset()):
        if not isinstance(data, dict):
            raise ProblemError(file, path or "(top level)", f"must be a table, got {_kind(data)}")
        self.data = data
        self.file = file
        self.path = path
        self.overridden = overridden
        self._read: set[str] = set()

    def where(self, key: str) -> str:
        return f"{self.path}.{key}" if self.path else key

    def error(self, key: str, message: str) -> ProblemError:
        fld = self.where(key) if key else self.path
        if fld in self.overridden:
            message += " (value from --set)"
        return ProblemError(self.file, fld, message)

    def has(self, key: str) -> bool:
        return key in self.data

    def raw(self, key: str, default: Any = _REQUIRED) -> Any:
        self._read.add(key)
        if key not in self.data:
            if default is _REQUIRED:
                typo = difflib.get_close_matches(key, [k for k in self.data if isinstance(k, str)], n=1, cutoff=0.75)
                hint = f" (is {typo[0]!r} a misspelling of it?)" if typo else ""
                raise self.error(key, "is required but missing" + hint)
            return default
        return self.data[key]

    def number(self, key: str, default: Any = _REQUIRED, *, min: float | None = None, max: float | None = None,
               positive: bool = False, integer: bool = False) -> float:
        if key not in self.data and default is not _REQUIRED:
            self._read.add(key)
            return default
        value = self.raw(key)
        if isinstance(value, bool) or not isinstance(value, (int, float)):
            raise self.error(key, f"must be a number, got {_kind(value)} {value!r}")
        if not math.isfinite(value):
            raise self.error(key, f"must be finite, got {value!r}")
        if integer and int(value) != value:
            raise self.error(key, f"must be a whole number, got {value!r}")
        if positive and not value > 0:
            raise self.error(key, f"must be positive, got {value!r}")
        if min is not None and value < min:
            raise self.error(key, f"must be at least {min:g}, got {value!r}")
        if max is not None and value > max:
            raise self.error(key, f"must be at most {max:g}, got {value!r}")
        return int(value) if integer else float(value)

    def string(self, key: str, default: Any = _REQUIRED, *, choices: tuple[str, ...] | None = None) -> str:
        if key not in self.data and default is not _REQUIRED:
            self._read.add(key)
            return default
        value = self.raw(key)
        if not isinstance(value, str):
            raise self.error(key, f"must be a string, got {_kind(value)} {value!r}")
        if choices is not None and value not in choices:
            raise self.error(key, f"{value!r} is not one of {', '.join(choices)}{_did_you_mean(value, choices)}")
        return value

    def boolean(self, key: str, default: Any = _REQUIRED) -> bool:
        value = self.raw(key, default)
        if not isinstance(value, bool):
            raise self.error(key, f"must be true or false, got {value!r}")
        return value

    def table(self, key: str, required: bool = True) -> "Fields | None":
        value = self.raw(key, _REQUIRED if required else None)
        if value is None:
            return None
        if not isinstance(value, dict):
            raise self.error(key, f"must be a table ([{self.where(key)}]), got {_kind(value)}")
        return Fields(value, self.file, self.where(key), self.overridden)

    def tables(self, key: str, required: bool = True) -> list["Fields"]:
        value = self.raw(key, _REQUIRED if required else [])
        if not isinstance(value, list) or not all(isinstance(v, dict) for v in value):
            raise self.error(key, f"must be an array of tables ([[{self.where(key)}]]), got {_kind(value)}")
        return [Fields(v, self.file, f"{self.where(key)}[{i}]", self.overridden) for i, v in enumerate(value, 1)]

    def finish(self) -> None:
        """Raise on the first key that was never read: it is not part of the schema."""
        for key in self.data:
            if key not in self._read:
                known = sorted(self._read)
                raise self.error(key, f"unknown field{_did_you_mean(key, known)}; known here: {', '.join(known) or 'none'}")


def _kind(value: Any) -> str:
    return {dict: "a table", list: "an array", str: "a string", bool: "a boolean", int: "an integer",
            float: "a number"}.get(type(value), type(value).__name__)


def _did_you_mean(word: str, options) -> str:
    close = difflib.get_close_matches(word, list(options), n=1)
    return f" (did you mean {close[0]!r}?)" if close else ""


# --------------------------------------------------------------------------- overrides

_SEGMENT = re.compile(r"^([A-Za-z_][A-Za-z0-9_]*)((?:\[\d+\])*)$")


def parse_override(text: str) -> tuple[list, Any]:
    """``"a.b[2].c=1.5"`` -> ``(["a", "b", 2, "c"], 1.5)``; the value is read as TOML, else as a string."""
    if "=" not in text:
        raise ProblemError("--set", text, "expected key.path=value")
    key, value_text = (s.strip() for s in text.split("=", 1))
    path: list = []
    for seg in key.split("."):
        m = _SEGMENT.match(seg)
        if not m:
            raise ProblemError("--set", key, f"bad key segment {seg!r} (use names and 1-based [index])")
        path.append(m.group(1))
        path.extend(int(i) for i in re.findall(r"\[(\d+)\]", m.group(2)))
    try:
        value = tomllib.loads(f"v = {value_text}")["v"]
    except tomllib.TOMLDecodeError:
        value = value_text
    return path, value


def _format_path(path: list) -> str:
    out = ""
    for p in path:
        out += f"[{p}]" if isinstance(p, int) else (f".{p}" if out else p)
    return out


def apply_overrides(data: dict, overrides: list[str], file: str) -> frozenset:
    """Apply ``--set`` overrides in place; returns the set of overridden field paths."""
    done = set()
    for text in overrides:
        path, value = parse_override(text)
        node = data
        for depth, seg in enumerate(path[:-1]):
            where = _format_path(path[: depth + 1])
            if isinstance(seg, int):
                if not isinstance(node, list) or not 1 <= seg <= len(node):
                    raise ProblemError(file, where, f"--set {text}: no element {seg} (there are {len(node) if isinstance(node, list) else 0})")
                node = node[seg - 1]
            else:
                if not isinstance(node, dict) or seg not in node:
                    raise ProblemError(file, where, f"--set {text}: no such field in the problem"
                                       f"{_did_you_mean(seg, node) if isinstance(node, dict) else ''}")
                node = node[seg]
        last = path[-1]
        if isinstance(last, int) or not isinstance(node, dict):
            raise ProblemError(file, _format_path(path), f"--set {text}: can only set a field of a table")
        if isinstance(node.get(last), dict):
            raise ProblemError(file, _format_path(path), f"--set {text}: is a table; set one of its fields")
        node[last] = value
        done.add(_format_path(path))
    return frozenset(done)


# --------------------------------------------------------------------------- the problem


@dataclass(frozen=True)
class Problem:
    """A validated design problem, SI units inside."""

    file: Path
    name: str
    description: str
    spm: float
    timing: TimingDiagram
    default_law: MotionLaw
    pulley_teeth: int
    transmission: BeltPulley
    data: dict = field(repr=False)  # the raw data after overrides, for reporting
    model: Model | None = field(default=None, repr=False)  # [model]: the contact model (model.py)
    scenes: dict[str, Scene] | None = field(default=None, repr=False)  # [scenes.*] (scene.py)
    drive: DriveSpec | None = field(default=None, repr=False)  # [drive]: motor, load, limits (drive.py)
    design: DesignSettings | None = field(default=None, repr=False)  # [design]: optimal stroke (design.py)
    servo: "ServoSettings | None" = field(default=None, repr=False)  # [servo]: servo loop and belt (servo.py)

    @property
    def period(self) -> float:
        return self.timing.period(self.spm)

    def stroke(self, spm: float | None = None):
        """The classic-law stroke of this problem at ``spm`` (default: the problem's)."""
        return self.timing.stroke(self.spm if spm is None else spm)

    def with_law(self, law: MotionLaw) -> "Problem":
        """The same problem with every move following ``law``."""
        return replace(self, timing=self.timing.with_law(law), default_law=law)

    def with_spm(self, spm: float) -> "Problem":
        if not (isinstance(spm, (int, float)) and math.isfinite(spm) and spm > 0):
            raise ProblemError(str(self.file), "machine.spm", f"must be positive, got {spm!r}")
        return replace(self, spm=float(spm))


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
    trans.string("profile", "GT3", choices=("GT3",))
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
        pulley_teeth=teeth,
        transmission=BeltPulley(gt3_pitch_diameter(teeth)),
        data=data,
        model=model,
        scenes=scenes,
        drive=drive,
        design=design,
        servo=servo,
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
