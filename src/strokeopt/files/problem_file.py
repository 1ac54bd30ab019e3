"""Reading a design problem file (TOML): ``extends``, then ``--set`` overrides, then
:func:`strokeopt.problem.parse_problem`.

``extends = "base.toml"`` (a path relative to the file) makes a problem file a variant of another: the base
is read first (itself possibly extending a third), then the file's own tables are merged into it key by key
(a table merges with the base's table, any other value, an array of tables included, replaces the base's).
A cycle of ``extends`` is refused naming the chain. ``omit = ["servo", "transmission", "design.pulley"]`` beside
``extends`` drops those tables or keys of the base before the merge (a variant with another transmission
states its own ``[transmission]`` whole; one without a servo model drops ``[servo]``); a name the base does not
have is refused. Relative paths inside a base (a catalogue file) are read
from the directory of the file being loaded.
"""

from __future__ import annotations

import copy
import tomllib
from dataclasses import replace
from pathlib import Path

from ..errors import ProblemError
from ..io.fields import apply_overrides
from ..problem import Problem, parse_problem

#: The deepest chain of ``extends`` a problem file may have (a variant of a variant of ...).
EXTENDS_DEPTH_MAX = 8


def load_problem(path: str | Path, overrides: list[str] | None = None) -> Problem:
    """Read, extend, override and validate a problem file; ``overrides`` are ``--set`` texts
    (``"machine.spm=600"``)."""
    path = Path(path)
    file = str(path)
    data = read_problem_data(path)
    if isinstance(overrides, str):  # one override given as a string, not as a list of them
        overrides = [overrides]
    overrides = list(overrides or [])
    overridden = apply_overrides(data, overrides, file)
    return replace(parse_problem(data, file, overridden, path), overrides=tuple(overrides))


def read_problem_data(path: Path, chain: tuple[Path, ...] = ()) -> dict:
    """The data of the problem file ``path`` with its ``extends`` chain merged in (the base first)."""
    file = str(path)
    data = _read_toml(path, chain)
    base = data.pop("extends", None)
    omit = data.pop("omit", None)
    if base is None:
        if omit is not None:
            raise ProblemError(file, "omit", "drops tables or keys of a base: it needs extends")
        return data
    if not isinstance(base, str) or not base.strip():
        raise ProblemError(file, "extends", f"must be the name of a problem file (a string), got {base!r}")
    if any(ord(c) < 32 for c in base):
        raise ProblemError(file, "extends", f"{base!r} holds a control character: a file name has none")
    base_path = (path.parent / base)
    try:
        key = base_path.resolve()
        found = base_path.exists()
    except (OSError, ValueError) as exc:  # a name too long for the file system
        raise ProblemError(file, "extends", f"{base[:60]!r}{'...' if len(base) > 60 else ''} is no file name this "
                                            f"system can open: {exc.strerror or exc}") from None
    seen = chain + (path.resolve(),)
    if key in seen:
        names = " -> ".join(p.name for p in (*seen, key))
        raise ProblemError(file, "extends", f"{base!r} makes a cycle of extends: {names}")
    if len(seen) > EXTENDS_DEPTH_MAX:  # seen: this file and those extending it; its base would be one more
        raise ProblemError(file, "extends", f"a chain of more than {EXTENDS_DEPTH_MAX} extends")
    if not found:
        raise ProblemError(file, "extends", f"{base!r}: no such file (looked for {base_path})")
    return merge_tables(_omitted(read_problem_data(base_path, seen), omit, file, base), data)


def _omitted(base: dict, omit, file: str, base_name: str) -> dict:
    """``base`` without the dotted keys of ``omit`` (``"servo"``, ``"design.pulley"``); None: all of it."""
    if omit is None:
        return base
    if not (isinstance(omit, list) and all(isinstance(k, str) and k.strip() for k in omit)):
        raise ProblemError(file, "omit", f"must be an array of dotted keys of the base (\"servo\", "
                                         f"\"design.pulley\"), got {omit!r}")
    out = copy.deepcopy(base)
    for dotted in omit:
        *parents, last = dotted.split(".")
        table = out
        for key in parents:
            table = table.get(key) if isinstance(table, dict) else None
        if not isinstance(table, dict) or last not in table:
            raise ProblemError(file, "omit", f"{dotted!r} is not a table or key of the base {base_name!r}")
        del table[last]
    return out


def merge_tables(base: dict, own: dict) -> dict:
    """``own`` merged into ``base``: tables key by key, every other value (arrays of tables too) replaced."""
    out = dict(base)
    for key, value in own.items():
        if isinstance(value, dict) and isinstance(out.get(key), dict):
            out[key] = merge_tables(out[key], value)
        else:
            out[key] = value
    return out


def _read_toml(path: Path, chain: tuple) -> dict:
    file = str(path)
    try:
        text = path.read_text(encoding="utf-8")
    except FileNotFoundError:
        raise ProblemError(file, "", "no such file") from None
    except (OSError, UnicodeDecodeError) as exc:
        raise ProblemError(file, "", f"cannot be read: {exc}") from None
    try:
        return tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        where = f" (read as the base of {chain[-1].name})" if chain else ""
        raise ProblemError(file, "", f"is not valid TOML{where}: {exc}") from None
