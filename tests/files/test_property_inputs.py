"""Property test of the problem reader and the command line (issue 14): whatever a problem file holds, strokeopt
answers or refuses it in one line -- never a traceback, never a NaN or a null number in its JSON, exit codes
0, 1 or 2 only.

Each example is the reference problem with one to three mutations (a number scaled by 10^k, a sign flipped, a
value's type swapped, a key deleted or misspelt, an array truncated), written as a TOML file, read with
``load_problem`` and run through a cheap command (``size --json`` at one motor, or ``kinematics --json``).
Derandomized: the same 300 files on every run.
"""

from __future__ import annotations

import contextlib
import io
import json
import math
import tomllib

from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
import pytest

from strokeopt import ProblemError, SolverError, load_problem
from strokeopt.cli.main import main
from input_cases import field_paths, finite_json, mutated
from test_inputs import NULLABLE

from conftest import REFERENCE

BASE = tomllib.loads(REFERENCE.read_text(encoding="utf-8"))


PATHS = sorted(field_paths(BASE), key=repr)


def _toml_value(value) -> str:
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, float):
        return "nan" if math.isnan(value) else ("inf" if value > 0 else "-inf") if math.isinf(value) else repr(value)
    if isinstance(value, int):
        return str(value)
    if isinstance(value, str):
        return json.dumps(value)
    if isinstance(value, list):
        return "[" + ", ".join(_toml_value(v) for v in value) + "]"
    return "{" + ", ".join(f"{json.dumps(k)} = {_toml_value(v)}" for k, v in value.items()) + "}"


def to_toml(data: dict) -> str:
    """The problem as TOML: each top-level entry on one line (tables inline)."""
    return "\n".join(f"{json.dumps(k)} = {_toml_value(v)}" for k, v in data.items()) + "\n"


SWAPS = ["abc", True, [1.0, 2.0], {"x": 1}, 0, -1, 1e308, 5e-324, float("nan"), float("inf")]


def mutated_problem():
    return mutated(BASE, PATHS, scales=(-300, -30, -12, -6, -3, -1, 1, 3, 6, 12, 30, 300), swaps=SWAPS,
                   whole_numbers=True)


def _no_bad_numbers(text: str) -> bool:
    def refuse(constant):
        raise ValueError(f"{constant} in the JSON")

    return finite_json(json.loads(text, parse_constant=refuse), NULLABLE)


@pytest.mark.slow  # 300 mutated problem files through the command line
@settings(max_examples=300, derandomize=True, deadline=None, database=None,
          suppress_health_check=[HealthCheck.too_slow, HealthCheck.function_scoped_fixture])
@given(data=mutated_problem(), kinematics=st.sampled_from([False, False, False, True]))  # size is 10x cheaper
def test_any_problem_file_is_answered_or_refused_in_one_line(tmp_path, data, kinematics):
    path = tmp_path / "mutant.toml"
    path.write_text(to_toml(data), encoding="utf-8")
    try:
        load_problem(path)
    except (ProblemError, SolverError):
        pass  # refused with a message; the command line must refuse it the same way below
    argv = ["kinematics", str(path)] if kinematics else ["size", str(path), "--motor", "055U2B30"]
    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        code = main([*argv, "--json", "--plot", "none"])
    assert code in (0, 1, 2), err.getvalue()
    lines = [x for x in err.getvalue().splitlines() if x.startswith("strokeopt:")]
    if code == 2:  # refused: one line naming the file
        assert len(lines) == 1 and lines[0].startswith(f"strokeopt: error: {path}: "), err.getvalue()
    if code == 1:
        assert len(lines) == 1, err.getvalue()
    if code == 0:
        assert _no_bad_numbers(out.getvalue()), out.getvalue()


def test_the_generator_writes_the_reference_back():
    # the TOML writer of the property test is faithful: the unmutated reference reads back unchanged
    assert tomllib.loads(to_toml(BASE)) == BASE
