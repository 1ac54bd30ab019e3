"""Problem files: validation, overrides, and the CLI's one-line errors (exit 2, no traceback)."""

from __future__ import annotations

import pytest

from strokeopt import ProblemError, load_problem
from strokeopt.cli.main import main


def _run_error(capsys, argv):
    code = main(argv)
    out, err = capsys.readouterr()
    assert code == 2
    assert "Traceback" not in err and "Traceback" not in out
    lines = [line for line in err.splitlines() if line.strip()]
    assert len(lines) == 1, err
    return lines[0]


MOVE_2 = """[[timing.intervals]]
name = "move 2"
span_deg = 46.5
stroke_mm = 35.0
direction = "up"
published_time_s = 0.0312
"""


@pytest.mark.parametrize(
    "edit, field, words",
    [
        # a missing interval: the spans no longer add to 360 deg
        (lambda t: t.replace(MOVE_2, ""), "timing.intervals", "not 360"),
        (lambda t: t.replace("span_deg = 169.6", "span_deg = 170.6"), "timing.intervals", "add to 361"),
        (lambda t: t.replace("stroke_mm = 3.0", "stroke_mm = -3.0"), "timing.intervals[5].stroke_mm", "outside the plausible range [0, 100000]"),
        (lambda t: t.replace('law = "modified_sine"', 'law = "trapezoidal"'), "motion.law", "not one of"),
        (lambda t: t.replace("chi = 0.095", "chi = 0.4"), "motion.chi", "out of range"),
        (lambda t: t.replace('direction = "up"', 'direction = "sideways"', 1), "timing.intervals[4].direction", "not one of"),
        (lambda t: t.replace("spm = 500", "spm = -5"), "machine.spm", "outside the plausible range [1, 20000]"),
        (lambda t: t.replace("pulley_teeth = 28", "pulley_teeth = 28.5"), "transmission.pulley_teeth", "whole number"),
        (lambda t: t.replace("[machine]", "[machine]\nspeed_rpm = 3"), "machine.speed_rpm", "unknown field"),
        (lambda t: t.replace('direction = "down"\nhandover = true', 'direction = "up"\nhandover = true'),
         "timing.intervals", "do not close the cycle"),
    ],
)
def test_bad_problem_files(capsys, write_problem, edit, field, words):
    path = write_problem(edit)
    line = _run_error(capsys, ["kinematics", str(path), "--plot", "none"])
    assert line.startswith(f"strokeopt: error: {path}: ")
    assert f": {field}" in line and words in line, line


def test_not_toml(capsys, tmp_path):
    path = tmp_path / "bad.toml"
    path.write_text("this is [not toml\n")
    line = _run_error(capsys, ["kinematics", str(path)])
    assert str(path) in line and "not valid TOML" in line


def test_missing_file(capsys, tmp_path):
    line = _run_error(capsys, ["kinematics", str(tmp_path / "nope.toml")])
    assert "no such file" in line


def test_set_unknown_key(capsys, reference_path):
    line = _run_error(capsys, ["kinematics", str(reference_path), "--set", "motion.chix=0.1", "--plot", "none"])
    assert "motion.chix" in line and "unknown field" in line and "did you mean 'chi'" in line and "--set" in line


def test_set_unknown_section(capsys, reference_path):
    line = _run_error(capsys, ["kinematics", str(reference_path), "--set", "motoin.chi=0.1", "--plot", "none"])
    assert "motoin" in line and "no such field" in line


def test_set_bad_value_is_validated(capsys, reference_path):
    line = _run_error(capsys, ["kinematics", str(reference_path), "--set", "motion.chi=0", "--plot", "none"])
    assert "chi" in line and "out of range" in line


def test_spm_zero(capsys, reference_path):
    line = _run_error(capsys, ["kinematics", str(reference_path), "--spm", "0", "--plot", "none"])
    assert "--spm" in line and "outside the plausible range [1, 20000]" in line


def test_unknown_law_on_command_line(capsys, reference_path):
    line = _run_error(capsys, ["kinematics", str(reference_path), "--law", "bogus", "--plot", "none"])
    assert "--law" in line and "bogus" in line


def test_set_overrides_apply(reference_path):
    p = load_problem(reference_path, ["motion.chi=0.125", "timing.intervals[2].law=poly5", "machine.spm=600"])
    assert p.spm == 600
    assert p.timing.intervals[1].law.name == "poly5"
    assert p.timing.intervals[3].law.params == {"chi": 0.125}


def test_set_index_out_of_range(reference_path):
    with pytest.raises(ProblemError, match=r"timing.intervals\[9\].*no element 9"):
        load_problem(reference_path, ["timing.intervals[9].law=poly5"])
    with pytest.raises(ProblemError, match=r"no element 0 \(there are \d+, counted from 1\)"):
        load_problem(reference_path, ["timing.intervals[0].law=poly5"])


def test_law_on_a_dwell_is_an_error(write_problem):
    path = write_problem(lambda t: t.replace("span_deg = 169.6", 'span_deg = 169.6\nlaw = "poly5"'))
    with pytest.raises(ProblemError, match=r"timing.intervals\[3\].law: a dwell"):
        load_problem(path)


def test_misspelt_required_key_is_named(write_problem):
    path = write_problem(lambda t: t.replace("start_position_mm = 32.0", "start_positon_mm = 32.0"))
    with pytest.raises(ProblemError, match=r"timing.start_position_mm: is required but missing "
                                           r"\(is 'start_positon_mm' a misspelling of it\?\)"):
        load_problem(path)


@pytest.mark.parametrize("sets,field,words", [
    # with interval_times = "published" the times set the schedule: an edited span must not be ignored
    (["timing.intervals[2].span_deg=45", "timing.intervals[6].span_deg=62.3"], "timing.intervals[2].span_deg",
     "published_time_s: 37.80 deg"),
    # a move without a span is the span's error, not a later symptom (sampling, division by zero)
    (["timing.intervals[5].span_deg=0", "timing.intervals[6].span_deg=84.9"], "timing.intervals[5].span_deg",
     "needs a span of at least 0.1 deg"),
])
def test_spans_that_would_be_ignored_or_empty(capsys, reference_path, sets, field, words):
    args = ["kinematics", str(reference_path), "--plot", "none"]
    for s in sets:
        args += ["--set", s]
    line = _run_error(capsys, args)
    assert field in line and words in line


def test_set_makes_a_table_inside_a_section(capsys, reference_path):
    # before: --set design.contact.keep_closed=... said "no such field" (the reference has no [design.contact])
    # though the error of a typo listed 'contact' as known; now the table is made and validated like the file's
    p = load_problem(reference_path, ['design.contact.keep_closed=["c21"]', "design.contact.min_contact_force_N=0"])
    assert p.design.contact.keep_closed == ("c21",) and p.design.contact.min_contact_force == 0.0
    line = _run_error(capsys, ["kinematics", str(reference_path), "--set", 'design.contcat.keep_closed=["c21"]',
                               "--plot", "none"])
    assert "design.contcat" in line and "did you mean 'contact'" in line
