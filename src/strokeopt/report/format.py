"""Reports: JSON-ready summaries and plain-text tables.

Numbers leave strokeopt through here. NaN never does: :func:`to_json` refuses
it; an unbounded value (the jerk of a law whose acceleration jumps) becomes
``null`` in JSON and ``unbounded`` in a table.
"""

from __future__ import annotations

import json
import math
from typing import Any

import numpy as np

from ..motion.stroke import StrokeFunction


def _clean(obj: Any, where: str = "") -> Any:
    if isinstance(obj, dict):
        return {k: _clean(v, f"{where}.{k}" if where else str(k)) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [_clean(v, f"{where}[{i}]") for i, v in enumerate(obj)]
    if isinstance(obj, (np.floating, float)):
        x = float(obj)
        if math.isnan(x):
            raise ValueError(f"NaN in report field {where!r}: refusing to report it")
        return None if math.isinf(x) else x
    if isinstance(obj, np.integer):
        return int(obj)
    if isinstance(obj, np.bool_):
        return bool(obj)
    return obj


def to_json(obj: Any) -> str:
    """JSON text of a report; infinities become null, NaN is an error."""
    return json.dumps(_clean(obj), indent=2, allow_nan=False)


def format_value(x: Any, digits: int = 4) -> str:
    if x is None:
        return "-"
    if isinstance(x, bool):
        return "yes" if x else "no"
    if isinstance(x, (int, np.integer)):
        return str(int(x))
    if isinstance(x, (float, np.floating)):
        if math.isinf(x):
            return "unbounded"
        if x == 0:
            return "0"
        if abs(x) >= 10 ** (digits + 1) or abs(x) < 10 ** -(digits - 1):
            return f"{x:.{digits - 1}e}"
        return f"{x:.{digits}g}" if abs(x) >= 10**digits else f"{x:.{max(digits - 1 - int(math.floor(math.log10(abs(x)))), 0)}f}"
    return str(x)


def format_table(rows: list[dict], columns: list[tuple[str, str]], title: str = "") -> str:
    """A plain-text table. ``columns``: (key, header) pairs; headers carry units."""
    cells = [[format_value(r.get(k)) for k, _ in columns] for r in rows]
    heads = [h for _, h in columns]
    widths = [max([len(h)] + [len(c[i]) for c in cells]) for i, h in enumerate(heads)]
    lines = [title] if title else []
    lines.append("  ".join(h.rjust(w) for h, w in zip(heads, widths)))
    lines.append("  ".join("-" * w for w in widths))
    lines += ["  ".join(c.rjust(w) for c, w in zip(row, widths)) for row in cells]
    return "\n".join(lines)


def kinematics_summary(problem, stroke: StrokeFunction, spm: float) -> dict:
    """Peaks per interval of the bar and of the pulley, as the kinematics command reports them."""
    r = problem.transmission.radius
    sch = problem.timing.schedule(spm)
    peaks = stroke.piece_peaks()
    intervals, moves = [], []
    deg = 180.0 / math.pi
    for itv, pk, t0, dur in zip(problem.timing.intervals, peaks, sch.t_start, sch.duration):
        row = {
            "index": itv.index,
            "name": itv.name,
            "kind": "move" if itv.is_move else "dwell",
            "law": itv.law.label if itv.is_move else None,
            "stroke_mm": abs(itv.stroke) * 1e3,
            "direction": ("up" if itv.stroke > 0 else "down") if itv.is_move else None,
            "span_deg": 360.0 * dur / sch.period,  # the cam angle the interval takes at these times
            "span_nominal_deg": itv.span_deg,  # as the timing diagram states it
            "start_angle_deg": 360.0 * t0 / sch.period,
            "end_angle_deg": 360.0 * (t0 + dur) / sch.period,
            "time_s": dur,
            "v_max_m_s": pk.v_max,
            "a_max_m_s2": pk.a_max,
            "jerk_max_m_s3": pk.j_max,
            "pulley_speed_max_deg_s": pk.v_max / r * deg,
            "pulley_speed_max_rpm": pk.v_max / r * 60 / (2 * math.pi),
            "pulley_accel_max_deg_s2": pk.a_max / r * deg,
        }
        intervals.append(row)
        if itv.is_move:
            moves.append({"index": itv.move_index, "interval": itv.index, **{k: v for k, v in row.items() if k != "index"}})
    return {
        "problem": problem.name,
        "spm": spm,
        "cycle_time_s": sch.period,
        "interval_times": problem.timing.interval_times,
        "law": problem.default_law.name if len({m.law for m in problem.timing.moves}) == 1 else "mixed",
        "law_params": problem.default_law.params,
        "pulley_teeth": problem.pulley_teeth,
        "pulley_pitch_diameter_mm": problem.transmission.pitch_diameter * 1e3,
        "moves": moves,
        "intervals": intervals,
    }


KINEMATICS_COLUMNS = [
    ("index", "#"), ("name", "interval"), ("stroke_mm", "stroke mm"), ("span_deg", "span deg"),
    ("time_s", "time s"), ("v_max_m_s", "v_max m/s"), ("a_max_m_s2", "a_max m/s2"),
    ("jerk_max_m_s3", "jerk_max m/s3"), ("pulley_speed_max_deg_s", "pulley w deg/s"),
    ("pulley_speed_max_rpm", "pulley rpm"), ("pulley_accel_max_deg_s2", "pulley eps deg/s2"),
]


def kinematics_text(summary: dict) -> str:
    head = (f"{summary['problem']} at {summary['spm']:g} spm (cycle {summary['cycle_time_s'] * 1e3:.1f} ms, "
            f"interval times {summary['interval_times']}), pulley {summary['pulley_teeth']} teeth, "
            f"PD {summary['pulley_pitch_diameter_mm']:.2f} mm")
    laws = sorted({m["law"] for m in summary["moves"]})
    head += "\nmotion law: " + ", ".join(laws)
    return head + "\n\n" + format_table(summary["intervals"], KINEMATICS_COLUMNS)
