"""Numbers as they leave strokeopt: JSON-ready values and the one number format of tables and messages.

NaN never leaves: :func:`to_json` refuses it and names the field; an unbounded value (the jerk of a
law whose acceleration jumps) becomes ``null`` in JSON and ``unbounded`` in text. A leaf module: the
design file writer, the design's messages and every report use it.
"""

from __future__ import annotations

import json
import math
from typing import Any

import numpy as np


def plain(obj: Any, where: str = "") -> Any:
    if isinstance(obj, dict):
        return {k: plain(v, f"{where}.{k}" if where else str(k)) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [plain(v, f"{where}[{i}]") for i, v in enumerate(obj)]
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
    return json.dumps(plain(obj), indent=2, allow_nan=False)


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


def counted(n: int, singular: str, plural: str | None = None) -> str:
    """``n`` and its noun in the right number: '1 criterion', '2 criteria', '1 design limit'."""
    return f"{n} {singular if n == 1 else plural or singular + 's'}"
