"""Checked, typed access to the tables of a TOML file, and ``--set`` overrides.

Every mistake is reported as ``file: field: what is wrong`` (a
:class:`~strokeopt.errors.ProblemError`), unknown keys included, so a
misspelt setting never passes silently; every number is read with its
plausible range (:meth:`Fields.number`), so a value no machine has is refused
rather than computed with. Every section reader of strokeopt
(problem files, catalogue files, design files) reads through :class:`Fields`.

Overrides (``--set key.path=value`` on the command line, ``overrides=`` in
:func:`~strokeopt.files.problem_file.load_problem`) are applied to the raw data
before validation and validated like the file. Array elements are addressed
1-based: ``timing.intervals[2].law=poly5``.
"""

from __future__ import annotations

import difflib
import math
import re
import tomllib
from typing import Any

from ..errors import ProblemError

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
        """A finite number within its plausible range ``[min, max]`` (``positive``: above 0).

        Every numeric field of strokeopt's files is read with its range, written beside the read with a
        comment saying why (physically plausible, numerically safe); a value outside it is refused as
        ``file: field: VALUE is outside the plausible range [MIN, MAX]``.
        """
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
        if (positive and not value > 0) or (min is not None and value < min) or (max is not None and value > max):
            raise self.error(key, f"{value!r} is outside the plausible range {_range_text(min, max, positive)}")
        return int(value) if integer else float(value)

    def string(self, key: str, default: Any = _REQUIRED, *, choices: tuple[str, ...] | None = None) -> str:
        if key not in self.data and default is not _REQUIRED:
            self._read.add(key)
            return default
        value = self.raw(key)
        if not isinstance(value, str):
            raise self.error(key, f"must be a string, got {_kind(value)} {value!r}")
        if choices is not None and value not in choices:
            raise self.error(key, f"{value!r} is not one of {', '.join(choices)}{did_you_mean(value, choices)}")
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
                raise self.error(key, f"unknown field{did_you_mean(key, known)}; known here: {', '.join(known) or 'none'}")


def _range_text(lo: float | None, hi: float | None, positive: bool = False) -> str:
    """``[1, 2000]``, ``(0, 1e+06]``, ``>= 0``: the range :meth:`Fields.number` enforces, as it reads."""
    if positive and (lo is None or lo <= 0):
        left = "(0"
    elif lo is not None:
        left = f"[{lo:g}"
    else:
        left = None
    if hi is None:
        return "> 0" if left == "(0" else f">= {lo:g}" if left else "(any finite number)"
    return f"{left or '(-inf'}, {hi:g}]"


def _kind(value: Any) -> str:
    return {dict: "a table", list: "an array", str: "a string", bool: "a boolean", int: "an integer",
            float: "a number"}.get(type(value), type(value).__name__)


def did_you_mean(word: str, options) -> str:
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
    if value_text == "null":  # the key removed (a law parameter the new law does not take, an optional field)
        return path, REMOVE
    try:
        value = tomllib.loads(f"v = {value_text}")["v"]
    except tomllib.TOMLDecodeError:
        value = value_text
    return path, value


#: The value of ``--set key=null``: the key is removed from the problem (TOML has no null).
REMOVE = object()


def missing_element(seg: int, node) -> str:
    """Why ``[seg]`` finds nothing in ``node``: arrays of tables count from 1 in a path, as a reader counts them."""
    count = len(node) if isinstance(node, list) else 0
    return f"no element {seg} (there are {count}{', counted from 1' if seg == 0 and count else ''})"


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
                    raise ProblemError(file, where, f"--set {text}: {missing_element(seg, node)}")
                node = node[seg - 1]
            else:
                if isinstance(node, dict) and seg not in node and depth > 0:
                    # a table inside a section the file has (e.g. design.contact): made here, and the
                    # section's reader validates it like one written in the file (unknown names included)
                    node[seg] = {}
                if not isinstance(node, dict) or seg not in node:
                    raise ProblemError(file, where, f"--set {text}: no such field in the problem"
                                       f"{did_you_mean(seg, node) if isinstance(node, dict) else ''}")
                node = node[seg]
        last = path[-1]
        if isinstance(last, int) and isinstance(node, list):  # one element of an array of numbers or texts
            if not 1 <= last <= len(node):
                raise ProblemError(file, _format_path(path), f"--set {text}: {missing_element(last, node)}")
            if value is REMOVE or isinstance(node[last - 1], (dict, list)):
                raise ProblemError(file, _format_path(path), f"--set {text}: an element of an array of numbers or "
                                                             "texts is set to a value (to remove one, set the array)")
            node[last - 1] = value
            done.add(_format_path(path[:-1]))  # the array holds a value from --set
            continue
        if isinstance(last, int) or not isinstance(node, dict):
            raise ProblemError(file, _format_path(path), f"--set {text}: can only set a field of a table or an "
                                                         "element of an array")
        if value is REMOVE:
            if last not in node:
                raise ProblemError(file, _format_path(path), f"--set {text}: the problem has no such field to remove"
                                                             f"{did_you_mean(last, node)}")
            del node[last]
            done.add(_format_path(path))
            continue
        if isinstance(node.get(last), dict):
            raise ProblemError(file, _format_path(path), f"--set {text}: is a table; set one of its fields")
        node[last] = value
        done.add(_format_path(path))
    return frozenset(done)


def number_in(data: dict, field: str, file, option: str) -> float:
    """The number at the ``--set`` path ``field`` of a problem file's ``data`` (read from ``file``), or ProblemError
    naming ``option`` and the field (no such field, an element past the end, not a number)."""
    path, _ = parse_override(f"{field}=0")
    node = data
    for seg in path:
        if isinstance(seg, int) and not (isinstance(node, list) and 1 <= seg <= len(node)):
            raise ProblemError(option, field, f"{missing_element(seg, node)} in {file}")
        if isinstance(seg, str) and not (isinstance(node, dict) and seg in node):
            raise ProblemError(option, field, f"no such field in {file}"
                                              f"{did_you_mean(seg, node) if isinstance(node, dict) else ''}")
        node = node[seg - 1] if isinstance(seg, int) else node[seg]
    if isinstance(node, bool) or not isinstance(node, (int, float)):
        raise ProblemError(option, field, f"is {node!r}, not a number")
    return float(node)
