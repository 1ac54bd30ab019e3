"""The units a problem's load is reported in: a linear load in mm, m/s, m/s2, m/s3 (SI metres inside), a rotary
load (``[timing]`` in deg, a sley on its shaft driven through a gearbox) in deg, rad/s, rad/s2, rad/s3 (SI
radians inside). The text tables keep their column keys; :func:`load_columns` relabels them and
:func:`with_load_stroke` adds the stroke in the problem's own unit."""

from __future__ import annotations

import math

#: label words of a linear load and their rotary counterparts
_ROTARY_WORDS = {"m/s": "rad/s", "m/s2": "rad/s2", "m/s3": "rad/s3", "m/s^2": "rad/s^2", "m/s^3": "rad/s^3",
                 "mm": "deg"}


def is_rotary(problem) -> bool:
    """True when the problem's load turns (``[timing]`` in deg)."""
    timing = getattr(problem, "timing", None)
    return bool(getattr(timing, "rotary", False))


def load_label(label: str, rotary: bool) -> str:
    """``label`` with its linear unit words (mm, m/s, m/s2, m/s3) replaced by the rotary ones when ``rotary``."""
    if not rotary:
        return label
    return " ".join(_ROTARY_WORDS.get(word, word) for word in label.split(" "))


def load_columns(cols: list[tuple[str, str]], rotary: bool) -> list[tuple[str, str]]:
    """Table columns ``(key, label)`` for the load's unit: ``stroke_mm`` becomes ``stroke_deg``."""
    if not rotary:
        return cols
    return [("stroke_deg", "stroke deg") if key == "stroke_mm" else (key, load_label(label, True)) for key, label in cols]


#: a move's sense for a rotary load: a sley turns, it does not go up or down
_ROTARY_DIRECTIONS = {"up": "positive", "down": "negative"}


def direction_word(direction: str | None, rotary: bool) -> str | None:
    """A move's sense in words: ``up``/``down`` for a linear load, ``positive``/``negative`` for a rotary one."""
    return _ROTARY_DIRECTIONS.get(direction, direction) if rotary else direction


def with_load_stroke(row: dict, rotary: bool) -> dict:
    """``row`` with ``stroke_deg`` beside its ``stroke_mm`` (which holds SI x 1e3) for a rotary load, and its
    ``direction`` in a rotary load's words."""
    if not rotary or "stroke_mm" not in row:
        return row
    out = {**row, "stroke_deg": math.degrees(row["stroke_mm"] * 1e-3)}
    if "direction" in row:
        out["direction"] = direction_word(row["direction"], True)
    return out
