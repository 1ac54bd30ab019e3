"""Property tests of what commands read besides problem files (issue 22): a design.json mutated field by field,
and the trade-off's options. Whatever they hold, strokeopt answers or refuses in one line -- never a traceback,
exit codes 0, 1 or 2 only, under --json a JSON object (a failure object when it fails), no NaN or null where a
number is expected. Derandomized: the same cases on every run."""

from __future__ import annotations

import contextlib
import io
import json

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from strokeopt.cli.main import main
from input_cases import field_paths, mutated
from test_property_inputs import SWAPS, _no_bad_numbers

from conftest import REFERENCE


@pytest.fixture(scope="module")
def design_data(tmp_path_factory) -> dict:
    out = tmp_path_factory.mktemp("design")
    assert main(["solve", str(REFERENCE), "--motor", "055U2B30", "--pulley-teeth", "28", "--out", str(out),
                 "--json", "--plot", "none"]) == 0
    return json.loads((out / "design.json").read_text(encoding="utf-8"))


def _skipped(key, depth) -> bool:
    """The design file's keys and array elements down to the move rows (not every collocation number)."""
    return key in ("cam_table", "comparison") or (isinstance(key, int) and key > 2)


def _run(argv) -> tuple[int, str, str]:
    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        try:
            code = main(argv)
        except SystemExit as exc:  # argparse's own refusal (an option it cannot read)
            code = exc.code
    return code, out.getvalue(), err.getvalue()


def _one_answer(code, out, err, json_mode=True):
    assert code in (0, 1, 2), err
    assert "Traceback" not in err, err
    lines = [x for x in err.splitlines() if x.startswith("strokeopt:") or ": error:" in x]
    if code == 2:
        assert len(lines) == 1, err
    if json_mode:
        data = json.loads(out)
        assert isinstance(data, dict) and data.get("status")
        if code != 0:
            assert data["status"] in ("bad input", "failed", "infeasible", "limits exceeded",
                                      "verification failed") and data.get("message", data.get("status"))
        else:
            assert _no_bad_numbers(out), out


def mutated_design(base):
    return mutated(base, sorted(field_paths(base, skip=_skipped, max_depth=3), key=repr),
                   operations=("scale", "sign", "swap", "delete"), swaps=SWAPS[:4] + [None, 0, -1, 1e308])


@pytest.mark.slow  # 300 design files, each read by a command
@settings(max_examples=300, derandomize=True, deadline=None, database=None,
          suppress_health_check=[HealthCheck.too_slow, HealthCheck.function_scoped_fixture])
@given(data=st.data())
def test_any_design_file_is_answered_or_refused_in_one_line(tmp_path, design_data, data):
    mutant = data.draw(mutated_design(design_data))
    path = tmp_path / "design.json"
    path.write_text(json.dumps(mutant), encoding="utf-8")
    _one_answer(*_run(["kinematics", str(REFERENCE), "--design", str(path), "--json", "--plot", "none"]))


OPTION_TEXTS = st.one_of(
    st.sampled_from(["inf", "-inf", "nan", "0", "-1", "1e9", "1e-9", "abc", "", "1e308", "5e-324", "0.05"]),
    st.floats(allow_nan=True, allow_infinity=True).map(repr))
ACCURACY_TEXTS = st.one_of(
    st.sampled_from(["0", "-0.1", "1e-12", "1e12", "nan", "inf", "0.1,", ",", "0.1,abc", "", "1e-5", "200"]),
    st.lists(st.sampled_from(["0", "-1", "1e-6", "1e3", "nan", "x"]), min_size=1, max_size=3).map(",".join))


@pytest.mark.slow  # 300 command lines, each reading the problem file
@settings(max_examples=300, derandomize=True, deadline=None, database=None,
          suppress_health_check=[HealthCheck.too_slow])
@given(resolution=OPTION_TEXTS, accuracies=ACCURACY_TEXTS)
def test_tradeoff_options_outside_their_ranges_are_refused_in_one_line(resolution, accuracies):
    # every generated case has at least one option outside its range or unreadable: refused before any solve
    code, out, err = _run(["tradeoff", str(REFERENCE), f"--resolution={resolution}", f"--accuracies={accuracies}",
                           "--json", "--plot", "none"])
    assert code == 2, (resolution, accuracies, err)
    _one_answer(code, out, err)
