"""Reports: plain-text tables; JSON and single numbers through :mod:`strokeopt.io.plain`.

NaN never leaves strokeopt: :func:`to_json` refuses it; an unbounded value (the jerk of a law
whose acceleration jumps) becomes ``null`` in JSON and ``unbounded`` in a table.
"""

from __future__ import annotations

from ..io.plain import format_value, to_json  # noqa: F401  (report's names for them)


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


def drive_text(drive: dict) -> str:
    """The line every report has: which motor and pulley it used and where they come from."""
    teeth = drive.get("pulley_teeth")
    pulley = f"pulley {teeth} teeth" if teeth is not None else "continuous pulley radius"
    return f"drive: motor {drive.get('motor') or '(none)'}, {pulley} (from {drive['from']})"
