"""Property tests of what ``strokeopt report`` and ``strokeopt compare`` read (issue 22): a design.json mutated field
by field (a number scaled by 10^k or its sign flipped, a value of another type, a key deleted) with options drawn
from valid and invalid values (scenes, integrator tolerances, --objective beside --design, --spm, the drive
options, --set texts, where the page goes; for compare one to three design files, missing ones included).

The property, for every case: no traceback; exit 0, 1 or 2 only; a refusal (2) is one line on stderr; under --json
stdout is one JSON object with a status, a failure object with its message when the command fails, and no NaN or
null where a number is expected; a page that is written holds no "nan" or "None" where a number is printed.

Cheap: the design is solved once per module; each case calls the command line in this process. A case that is
answered runs the whole pipeline (the full servo simulation, the contact scene, every section and figure) but
the figures are not laid out and rasterised into SVG (``html.svg_figure`` closes them unrendered): that is the
same for every design and is what tests/report/test_report_html.py checks. Derandomized: the same cases on
every run."""

from __future__ import annotations

import contextlib
import io
import json
import re

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from strokeopt.cli.main import main
from input_cases import field_paths, finite_json, mutated

from conftest import REFERENCE

#: keys a --json report may hold as null (an event that did not happen, a part that is not there)
NULLABLE = {"master_counts", "limit", "value", "margin"}
#: swapped in for a value: other types, extremes, nothing
SWAPS = ["abc", True, [1.0, 2.0], {"x": 1}, None, 0, -1, 1e308, float("nan"), float("inf")]
#: where a design's numbers go in the files it is read with (the parts report and compare read)
KEYS = ("moves", "checks", "drive", "comparison", "verification", "not_judged", "verdict", "intervals", "mesh",
        "objective", "objective_value", "spm", "cycle_time_s", "motor", "pulley_teeth", "status", "overrides",
        "transmission", "problem_file", "schema_version", "pulley_pitch_diameter_mm", "notes")


@pytest.fixture(scope="module")
def designs(tmp_path_factory) -> dict:
    """The reference design solved once (055U2B30 on 28 teeth, as a designer fixes them), and a second copy of it."""
    out = tmp_path_factory.mktemp("designs")
    with contextlib.redirect_stdout(io.StringIO()):
        assert main(["solve", str(REFERENCE), "--motor", "055U2B30", "--pulley-teeth", "28", "--out", str(out / "a"),
                     "--json", "--plot", "none"]) == 0
    text = (out / "a" / "design.json").read_text(encoding="utf-8")
    (out / "b").mkdir()
    (out / "b" / "design.json").write_text(text, encoding="utf-8")
    return {"data": json.loads(text), "other": out / "b" / "design.json", "dir": out}


@pytest.fixture(scope="module", autouse=True)
def unrendered_figures():
    """Figures made from the data but not rendered (see the module's docstring)."""
    import matplotlib.pyplot as plt

    from strokeopt.report import html

    def closed(fig, caption: str = "") -> str:
        plt.close(fig)
        return f"<figure><svg></svg><figcaption>{html.escape(caption)}</figcaption></figure>"

    with pytest.MonkeyPatch.context() as mp:
        mp.setattr(html, "svg_figure", closed)
        yield


def _skipped(key, depth) -> bool:
    """The design's fields the parts and compare read (:data:`KEYS`), and the first two rows of each array."""
    return (depth == 0 and key not in KEYS) or (isinstance(key, int) and key > 1)


def mutated_design(base):
    return mutated(base, sorted(field_paths(base, skip=_skipped, max_depth=2), key=repr), count=(0, 2),
                   operations=("scale", "sign", "swap", "delete"), swaps=SWAPS)


NUMBER_TEXTS = st.sampled_from(["1e-4", "1e-6", "0", "-1", "nan", "inf", "abc", "", "1e308", "5e-324"])
# each option fragment: mostly valid ones (the pipeline runs) and invalid ones (refused before any work)
SCENE = st.sampled_from([[], [], ["--scene", "release"], ["--scene", "nope"], ["--scene", ""],
                         ["--scene", "release", "--scene", "release"]])
TOLERANCES = st.one_of(st.just([]), st.just([]), NUMBER_TEXTS.map(lambda x: [f"--rtol={x}"]),
                       NUMBER_TEXTS.map(lambda x: [f"--atol={x}"]))
REPORT_EXTRA = st.sampled_from([[], [], [], ["--objective", "min_rms_torque"], ["--objective", "nope"],
                                ["--spm", "600"], ["--spm", "abc"], ["--spm", "500"], ["--motor", "NOPE"],
                                ["--motor", "055U2B30"], ["--pulley-teeth", "7"], ["--pulley-teeth", "28"],
                                ["--set", "machine.spm=nan"], ["--set", "model.contacts.c32.gap_mm=6.5"],
                                ["--set", "design.handover_accuracy_mm=0.01"], ["--set", "nope=1"]])
OUT = st.sampled_from(["page.html", "page.html", "page.html", "page.txt", ".", "missing/dir/page.html", ""])


def _run(argv) -> tuple[int, str, str]:
    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        try:
            code = main(argv)
        except SystemExit as exc:  # argparse's own refusal of an option it cannot read
            code = exc.code
    return code, out.getvalue(), err.getvalue()


def _answered_once(code, out, err, json_mode: bool, page) -> None:
    """The property (module docstring)."""
    assert code in (0, 1, 2), err
    assert "Traceback" not in err, err
    if code == 2:  # one error line (argparse prints its usage above its own)
        lines = [x for x in err.splitlines() if x.startswith("strokeopt:") or ": error:" in x]
        assert len(lines) == 1, err
    if json_mode:
        def refuse(constant):
            raise ValueError(f"{constant} in the JSON")

        data = json.loads(out, parse_constant=refuse)
        assert isinstance(data, dict) and data.get("status"), out
        if code != 0:
            assert data["status"] != "ok" and data.get("message"), out
        assert finite_json(data, NULLABLE), out
    if code == 0:
        html = page.read_text(encoding="utf-8")
        assert not re.search(r">\s*(nan|NaN|None|null|inf)\s*<", html), re.findall(r".{80}>\s*(?:nan|None)\s*<", html)


def _drawn_design(data, designs, tmp_path) -> str:
    """A mutated design drawn, and where it is: a JSON file mostly, else a missing file, a directory or a broken file."""
    mutant = data.draw(mutated_design(designs["data"]), "design")
    kind = data.draw(st.sampled_from(["json"] * 8 + ["missing", "directory", "broken"]), "file")
    return _design_path(tmp_path, mutant, kind)


def _design_path(tmp_path, data, kind) -> str:
    if kind == "missing":
        return str(tmp_path / "no_such_design.json")
    if kind == "directory":
        return str(tmp_path)
    path = tmp_path / "design.json"
    path.write_text(json.dumps(data) if kind == "json" else "{not json", encoding="utf-8")
    return str(path)


@pytest.mark.slow  # 150 command lines; the answered ones run the servo simulation and the contact scene
@settings(max_examples=150, derandomize=True, deadline=None, database=None,
          suppress_health_check=[HealthCheck.too_slow, HealthCheck.function_scoped_fixture,
                                 HealthCheck.data_too_large])
@given(data=st.data())
def test_report_of_any_design_file_and_options_answers_or_refuses_in_one_line(tmp_path, designs, data):
    design = _drawn_design(data, designs, tmp_path)
    json_mode = data.draw(st.sampled_from([True, True, True, False]), "json")
    out = data.draw(OUT, "out")
    page = tmp_path / out if out not in ("", ".") else tmp_path
    argv = ["report", str(REFERENCE), "--design", design, "--out", str(page),
            *data.draw(SCENE, "scene"), *data.draw(TOLERANCES, "tolerances"), *data.draw(REPORT_EXTRA, "extra")]
    _answered_once(*_run(argv + (["--json"] if json_mode else [])), json_mode, page)


@pytest.mark.slow  # 150 command lines; the answered ones judge two or three designs
@settings(max_examples=150, derandomize=True, deadline=None, database=None,
          suppress_health_check=[HealthCheck.too_slow, HealthCheck.function_scoped_fixture,
                                 HealthCheck.data_too_large])
@given(data=st.data())
def test_compare_of_any_design_files_and_options_answers_or_refuses_in_one_line(tmp_path, designs, data):
    first = _drawn_design(data, designs, tmp_path)
    others = data.draw(st.sampled_from([[str(designs["other"])]] * 4 + [[], [first], [str(tmp_path / "gone.json")],
                                        [str(designs["other"]), str(designs["other"])]]), "others")
    json_mode = data.draw(st.sampled_from([True, True, True, False]), "json")
    out = data.draw(OUT, "out")
    page = tmp_path / out if out not in ("", ".") else tmp_path
    argv = ["compare", first, *others, "--out", str(page), *data.draw(SCENE, "scene"),
            *data.draw(TOLERANCES, "tolerances")]
    _answered_once(*_run(argv + (["--json"] if json_mode else [])), json_mode, page)
