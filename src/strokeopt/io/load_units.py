"""The keys and values a load's quantities have in files and JSON reports: a linear load's in mm, m/s, m/s^2,
m/s^3, a rotary load's (``[timing]`` in deg: a sley on its shaft) in deg, rad/s, rad/s^2, rad/s^3. SI inside
(metres or radians); the computing code makes its rows with the linear keys (``stroke_mm`` = SI x 1e3), and
:func:`to_load_units` renames them, with positions in deg, where a rotary load's data leaves strokeopt (design.json,
``solve --json``, the report). :func:`from_load_units` turns such data back into the linear keys for a reader:
design files written before (a rotary load's rad x 1e3 under ``stroke_mm``) and after read alike.
"""

from __future__ import annotations

import math

#: linear key -> rotary key
ROTARY_KEYS = {"stroke_mm": "stroke_deg", "start_position_mm": "start_position_deg", "position_mm": "position_deg",
               "v_max_m_s": "v_max_rad_s", "a_max_m_s2": "a_max_rad_s2", "jerk_max_m_s3": "jerk_max_rad_s3",
               "velocity_m_s": "velocity_rad_s", "acceleration_m_s2": "acceleration_rad_s2", "jerk_m_s3": "jerk_rad_s3",
               "a_max_nodes_m_s2": "a_max_nodes_rad_s2", "a_max_fine_m_s2": "a_max_fine_rad_s2",   # the fine grid's
               "position_error_end_mm": "position_error_end_deg"}
LINEAR_KEYS = {v: k for k, v in ROTARY_KEYS.items()}
#: the positions among them: mm (SI x 1e3) on a linear load, deg on a rotary one; the rest are SI either way
POSITIONS = ("stroke_mm", "start_position_mm", "position_mm", "position_error_end_mm")


def load_key(key: str, rotary: bool) -> str:
    """The key of a load's quantity for the load's kind: ``stroke_mm`` -> ``stroke_deg`` when ``rotary``."""
    return ROTARY_KEYS.get(key, key) if rotary else key


def _deg(key: str, value):
    return math.degrees(value * 1e-3) if key in POSITIONS and isinstance(value, (int, float)) else value


def _mm(key: str, value):
    return math.radians(value) * 1e3 if key in POSITIONS and isinstance(value, (int, float)) else value


def _convert(data, keys: dict, value_of):
    if isinstance(data, list):
        return [_convert(v, keys, value_of) for v in data]
    if not isinstance(data, dict):
        return data
    out = {}
    for key, value in data.items():
        if key in keys:
            out[keys[key]] = value_of(key if keys is ROTARY_KEYS else keys[key], value)
        else:
            out[key] = _convert(value, keys, value_of)
    if isinstance(out.get("columns"), list) and isinstance(out.get("rows"), list):   # a table: columns and rows
        cols = data["columns"]
        new = [keys.get(c, c) for c in cols]
        rows = [[value_of(c if keys is ROTARY_KEYS else keys.get(c, c), v) if c in keys else v
                 for c, v in zip(cols, row)] for row in data["rows"]]
        out.update(columns=new, rows=rows)
    return out


def to_load_units(data, rotary: bool):
    """``data`` (dicts and lists) with a rotary load's keys and positions in deg when ``rotary``; unchanged for a
    linear load. Keys already rotary stay as they are (applying it twice changes nothing)."""
    return _convert(data, ROTARY_KEYS, _deg) if rotary else data


def from_load_units(data):
    """``data`` with every rotary key back under its linear key (positions deg -> rad x 1e3): the form the
    readers of design files take. Data without rotary keys is returned as it is."""
    return _convert(data, LINEAR_KEYS, _mm)


def error_unit(rotary: bool) -> tuple[float, str]:
    """The scale from SI and the unit a load's position errors and accuracies are reported in: mm for a
    linear load (SI x 1e3), deg for a rotary one (rad x 180/pi)."""
    return (180.0 / math.pi, "deg") if rotary else (1e3, "mm")
