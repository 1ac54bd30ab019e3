"""The reported part of a design file, checked whole on read: what the design's numbers, checks, drive and
classic-law comparison hold, as ``Design.summary`` and ``strokeopt solve --out`` write them.

:func:`~strokeopt.files.design_file.validate_design` checks what the stroke is rebuilt from (the mesh, the
moves' unit solutions, the intervals); :func:`validate_reported` checks everything else a command reads of a
design file -- ``design_from_data`` (the moves' names, times and peaks, the objective, the status), the
report and the comparison (the checks with their margins, the drive it came with, the classic-law rows) --
so that no command reads a field on its own and meets a missing key or a string where a number belongs.
Each field has its type and, for a number, a range; a field a design may lack (a design without a motor, a
file of ``solve --out`` without a comparison) may be absent or null where the writer writes null.
"""

from __future__ import annotations

from ..io.fields import Fields

#: Peaks of a move (speed, acceleration, jerk; m or rad based) and of a check: finite, of any size the
#: plausible problems give (a 100 m stroke in 0.1 ms is 1e6 m/s; jerks of 1e15 m/s^3 and more are of known-optima
#: tests), so only their type and finiteness are checked, and a peak's sign.
PEAK_MAX = 1e30


def _optional_number(f: Fields, key: str, **bounds) -> None:
    """A number, or absent, or null."""
    if f.data.get(key) is not None:
        f.number(key, **bounds)


def _optional_string(f: Fields, key: str) -> None:
    if f.data.get(key) is not None:
        f.string(key)


def _string_list(f: Fields, key: str) -> None:
    value = f.data.get(key, [])
    if not isinstance(value, list) or not all(isinstance(v, str) for v in value):
        raise f.error(key, f"must be a list of texts, got {value!r}: the design file is damaged")


def _rows(f: Fields, key: str) -> list[Fields]:
    """The tables of an array that may be absent (an empty list then)."""
    if key not in f.data:
        return []
    return f.tables(key)


def validate_reported(top: Fields) -> None:
    """Check the reported fields of a design file (``top``: its :class:`Fields`, after the stroke's part was
    checked); raises :class:`~strokeopt.errors.ProblemError` naming the file and the field."""
    top.string("objective")
    top.number("objective_value", min=-PEAK_MAX, max=PEAK_MAX)
    top.string("objective_unit")
    top.string("status")
    top.number("solve_time_s", min=0.0, max=1e7)
    top.number("iterations", 0, integer=True, min=0, max=10**9)
    _optional_string(top, "motor")
    _optional_number(top, "pulley_pitch_diameter_mm", positive=True, max=1e5)
    for key in ("notes", "active_constraints"):
        _string_list(top, key)
    if "fine_grid" in top.data and not isinstance(top.data["fine_grid"], dict):
        raise top.error("fine_grid", f"must be a table, got {top.data['fine_grid']!r}: the design file is damaged")
    for m in top.tables("moves"):
        m.number("index", integer=True, min=1, max=10**4)
        m.string("name")
        m.number("t_start_s", min=0.0, max=3600.0)
        m.number("duration_s", positive=True, max=3600.0)
        m.number("start_position_mm", min=-1e5, max=1e5)  # the ranges of [timing]
        for key in ("v_max_m_s", "a_max_m_s2", "jerk_max_m_s3"):
            m.number(key, min=0.0, max=PEAK_MAX)
        m.number("C_a", min=0.0, max=PEAK_MAX)
    for c in _rows(top, "checks"):
        c.string("name")
        c.number("value", min=-PEAK_MAX, max=PEAK_MAX)
        c.number("limit", min=-PEAK_MAX, max=PEAK_MAX)
        c.string("unit")
        _optional_number(c, "margin")  # null: no finite margin (a zero limit exceeded)
        c.boolean("ok")
        _optional_number(c, "design_term", min=-PEAK_MAX, max=PEAK_MAX)
    drive = top.table("drive", required=False)
    if drive is not None:
        _optional_string(drive, "motor")
        _optional_number(drive, "pulley_teeth", integer=True, min=1, max=10**4)
        _optional_string(drive, "from")
    for r in _rows(top, "comparison"):
        r.string("law")
        for key, value in r.data.items():
            if key in ("law", "violates", "feasible"):
                continue
            if value is not None:
                r.number(key, min=-PEAK_MAX, max=PEAK_MAX)
        if r.data.get("feasible") is not None:
            r.boolean("feasible")
        _string_list(r, "violates")
    _optional_string(top, "verdict")
    for r in _rows(top, "not_judged"):
        r.string("criterion")
        r.number("value", min=-PEAK_MAX, max=PEAK_MAX)
        r.string("unit")
    if "verification" in top.data and not isinstance(top.data["verification"], dict):
        raise top.error("verification", f"must be a table, got {top.data['verification']!r}: the design file is "
                                        "damaged")
