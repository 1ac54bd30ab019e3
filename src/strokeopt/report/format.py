"""Reports: plain-text tables; JSON and single numbers through :mod:`strokeopt.io.plain`.

NaN never leaves strokeopt: :func:`to_json` refuses it; an unbounded value (the jerk of a law
whose acceleration jumps) becomes ``null`` in JSON and ``unbounded`` in a table.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from ..transmissions import transmission_label
from ..io.cycle import STITCH, cycle_of
from ..io.plain import format_value, to_json  # noqa: F401  (report's names for them)


def _is_number(x: Any) -> bool:
    return isinstance(x, (int, float, np.integer, np.floating)) and not isinstance(x, (bool, np.bool_)) \
        and math.isfinite(x)


def column_format(values: list, digits: int = 4):
    """One number format for a column's numbers: whole numbers as integers (700, 1000); else fixed
    decimals enough for ``digits`` significant digits of its smallest number (2.6060, 0.6413);
    scientific when they leave [0.001, 1e5) (3.070e+05). A column whose numbers span four decades or
    more holds different quantities (a checks table's values, each in its own unit): each number keeps
    :func:`format_value`, as do non-numbers (None, bool, inf, text)."""
    nums = [abs(float(x)) for x in values if _is_number(x)]
    nonzero = [x for x in nums if x > 0]
    if not nonzero or all(float(x) == round(float(x)) and abs(x) < 1e15 for x in nums):
        return lambda x: f"{int(round(float(x)))}" if _is_number(x) else format_value(x)
    low, high = min(nonzero), max(nonzero)
    if high / low >= 1e4:
        return format_value
    if high >= 10 ** (digits + 1) or low < 10 ** -(digits - 1):
        return lambda x: f"{float(x):.{digits - 1}e}" if _is_number(x) else format_value(x)
    decimals = max(digits - 1 - int(math.floor(math.log10(low))), 0)
    return lambda x: f"{float(x):.{decimals}f}" if _is_number(x) else format_value(x)


def format_table(rows: list[dict], columns: list[tuple[str, str]], title: str = "", text: tuple = ()) -> str:
    """A plain-text table. ``columns``: (key, header) pairs; headers carry units; one number
    format per column (:func:`column_format`); the columns whose keys are in ``text`` (sentences: a reason)
    are aligned left, so a long sentence in one row does not push the others' cells right."""
    formats = [column_format([r.get(k) for r in rows]) for k, _ in columns]
    cells = [[fmt(r.get(k)) for (k, _), fmt in zip(columns, formats)] for r in rows]
    heads = [h for _, h in columns]
    widths = [max([len(h)] + [len(c[i]) for c in cells]) for i, h in enumerate(heads)]
    left = [k in text for k, _ in columns]

    def line(parts) -> str:
        return "  ".join(p.ljust(w) if lj else p.rjust(w) for p, w, lj in zip(parts, widths, left)).rstrip()

    lines = [title] if title else []
    lines.append(line(heads))
    lines.append("  ".join("-" * w for w in widths))
    lines += [line(row) for row in cells]
    return "\n".join(lines)


def drive_text(drive: dict) -> str:
    """The line every report has: which motor and pulley it used and where they come from."""
    teeth = drive.get("pulley_teeth")
    pulley = f"pulley {teeth} teeth" if teeth is not None else \
        transmission_label(drive.get("transmission")) or "continuous pulley radius"
    return f"drive: motor {drive.get('motor') or '(none)'}, {pulley} (from {drive['from']})"


def period_text(cycle_s: float, spm: float, cycle=STITCH) -> str:
    """The cam cycle and the machine's cycle, both named: 'cam cycle 200.0 ms = 2 stitches of 100.0 ms'
    (``cycle``: the machine's cycle, io/cycle.py, or what has one: a problem, a design, a summary)."""
    stitch_s = 60.0 / spm
    stitches = cycle_s / stitch_s
    count = f"{round(stitches)}" if abs(stitches - round(stitches)) < 1e-9 else f"{stitches:.4g}"
    return f"cam cycle {cycle_s * 1e3:.1f} ms = {cycle_of(cycle).count(count)} of {stitch_s * 1e3:.1f} ms"
