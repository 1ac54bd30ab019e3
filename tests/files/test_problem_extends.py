"""``extends`` in problem files: a variant states only what differs from its base; in-memory variants
(``Problem.with_overrides``) are validated like a file's and never re-read it."""

from __future__ import annotations

import shutil
from pathlib import Path

import pytest

from strokeopt import ProblemError, load_problem
from strokeopt.cli.main import main

PROBLEMS = Path(__file__).resolve().parents[2] / "problems"


def test_contact_design_file_holds_only_what_differs():
    # the contact-design file extends the reference: under 80 lines, and its merged data are the reference's
    # with its own tables merged in (the sections it does not state are the reference's, key for key)
    text = (PROBLEMS / "deco2000_contact_design.toml").read_text(encoding="utf-8")
    assert len(text.splitlines()) < 80 and 'extends = "deco2000_needle_bar.toml"' in text
    derived = load_problem(PROBLEMS / "deco2000_contact_design.toml")
    base = load_problem(PROBLEMS / "deco2000_needle_bar.toml")
    for section in ("timing", "transmission", "drive", "servo", "model", "scenes"):
        assert derived.data[section] == base.data[section], section
    assert derived.spm == 600 and base.spm == 500
    assert derived.design.motor_choice == "fixed" and base.design.motor_choice == "enumerate"
    assert derived.design.objective == base.design.objective == "min_peak_torque"  # merged from the base


def _copy(tmp_path, name="base.toml") -> Path:
    shutil.copy(PROBLEMS / "known_optima" / "min_jerk.toml", tmp_path / name)
    return tmp_path / name


def test_extends_merges_tables_and_replaces_arrays(tmp_path):
    _copy(tmp_path)
    (tmp_path / "v.toml").write_text('extends = "base.toml"\n[machine]\nspm = 45\n'
                                     '[[timing.intervals]]\nname = "rise"\nspan_deg = 90\nstroke_mm = 500\n'
                                     'direction = "up"\n[[timing.intervals]]\nname = "dwell"\nspan_deg = 90\n'
                                     '[[timing.intervals]]\nname = "return"\nspan_deg = 180\nstroke_mm = 500\n'
                                     'direction = "down"\n', encoding="utf-8")
    p = load_problem(tmp_path / "v.toml", ["design.objective=\"min_peak_accel\""])
    assert p.spm == 45 and p.data["machine"]["cam_revolutions_per_stitch"] == 1  # table merged key by key
    assert [i.name for i in p.timing.intervals] == ["rise", "dwell", "return"]  # the array replaced whole
    assert p.design.objective == "min_peak_accel" and p.default_law.name == "poly5"


@pytest.mark.parametrize("text, words", [
    ('extends = "b.toml"\n', "cycle of extends: a.toml -> b.toml -> a.toml"),
    ('extends = "missing.toml"\n', "'missing.toml': no such file"),
    ("extends = 3\n", "must be the name of a problem file"),
    # a NUL byte and a name too long for the file system ended in tracebacks (ValueError, OSError)
    ('extends = "a\\u0000b.toml"\n', "holds a control character"),
    ('extends = "' + "x" * 300 + '.toml"\n', "is no file name this system can open"),
])
def test_bad_extends_is_one_line_exit_2(tmp_path, capsys, text, words):
    (tmp_path / "a.toml").write_text(text, encoding="utf-8")
    (tmp_path / "b.toml").write_text('extends = "a.toml"\n', encoding="utf-8")
    with pytest.raises(ProblemError) as err:
        load_problem(tmp_path / "a.toml")
    assert err.value.field == "extends" and words in str(err.value)
    assert main(["kinematics", str(tmp_path / "a.toml"), "--plot", "none"]) == 2
    out = capsys.readouterr().err.strip().splitlines()
    assert len(out) == 1 and "a.toml" in out[0] and "extends" in out[0] and words in out[0]


def test_a_chain_of_eight_extends_is_read_and_nine_refused(tmp_path):
    # it said "a chain of more than 8 extends" for a chain of 8
    base = _copy(tmp_path)
    names = [base.name] + [f"v{k}.toml" for k in range(1, 10)]
    for k in range(1, 10):
        (tmp_path / names[k]).write_text(f'extends = "{names[k - 1]}"\n', encoding="utf-8")
    assert load_problem(tmp_path / "v8.toml").spm == load_problem(base).spm   # v8 -> v7 -> ... -> base: 8 extends
    with pytest.raises(ProblemError, match="a chain of more than 8 extends"):
        load_problem(tmp_path / "v9.toml")


def test_a_base_with_an_error_is_named(tmp_path):
    base = _copy(tmp_path)
    base.write_text(base.read_text(encoding="utf-8").replace("spm = 30", "spm = -30"), encoding="utf-8")
    (tmp_path / "v.toml").write_text('extends = "base.toml"\n', encoding="utf-8")
    with pytest.raises(ProblemError, match="machine.spm"):
        load_problem(tmp_path / "v.toml")


def test_with_overrides_is_validated_and_reads_no_file(tmp_path):
    path = _copy(tmp_path)
    problem = load_problem(path, ["machine.spm=40"])
    path.unlink()  # a variant is made in memory: the file is gone and with_overrides still works
    faster = problem.with_overrides(["machine.spm=50"])
    assert (problem.spm, faster.spm) == (40, 50) and faster.overrides == ("machine.spm=40", "machine.spm=50")
    assert problem.with_overrides([]) is problem
    with pytest.raises(ProblemError, match="machine.spm"):
        problem.with_overrides(["machine.spm=-1"])


def test_load_force_contact_position_is_stated_once(reference_path):
    # the k2 load force starts where [model.contacts.pad] closes: 32 mm (upper dwell) - 23 mm (gap H) = 9 mm
    # (sources A.6); change the gap or the stroke and the rigid load model follows (before: a second number,
    # contact_position_mm = 9.0, that did not)
    p = load_problem(reference_path)
    (k2,) = p.drive.load.forces
    assert k2.contact_position == pytest.approx(0.009, abs=1e-12)
    # (a pad higher than 32 - 3.6 - 7.4 = 21 mm would stop the shell above its lower dwell: contact/travel.py)
    assert p.with_overrides(["model.contacts.pad.gap_mm=25"]).drive.load.forces[0].contact_position == \
        pytest.approx(0.007, abs=1e-12)
    assert p.with_overrides(["timing.start_position_mm=30"]).drive.load.forces[0].contact_position == \
        pytest.approx(0.007, abs=1e-12)


@pytest.mark.parametrize("sets, field, words", [
    (['drive.load_forces[1].model_contact="nope"'], "model_contact", "unknown contact 'nope'"),
    (['drive.load_forces[1].model_contact="c21"'], "model_contact", "between control and shell"),
    (["drive.load_forces[1].contact_position_mm=9.0"], "contact_position_mm", "comes from model_contact"),
])
def test_load_force_contact_errors(reference_path, sets, field, words):
    with pytest.raises(ProblemError) as err:
        load_problem(reference_path, sets)
    assert err.value.field.endswith(field) and words in err.value.message


def test_omit_drops_tables_and_keys_of_the_base(tmp_path):
    # a variant with another transmission states its [transmission] whole, without the base's belt keys
    _copy(tmp_path)
    base = load_problem(tmp_path / "base.toml")
    assert base.design is not None and "design" in base.data
    (tmp_path / "v.toml").write_text('extends = "base.toml"\nomit = ["design", "motion.law"]\n'
                                     '[motion]\nlaw = "sine"\n', encoding="utf-8")
    v = load_problem(tmp_path / "v.toml")
    assert v.design is None and "design" not in v.data and v.default_law.name == "sine"
    assert [(i.span_deg, i.stroke) for i in v.timing.intervals] == [(i.span_deg, i.stroke) for i in base.timing.intervals]


@pytest.mark.parametrize("text, words", [
    ('omit = ["design"]\n', "it needs extends"),
    ('extends = "base.toml"\nomit = ["servo"]\n', "'servo' is not a table or key of the base 'base.toml'"),
    ('extends = "base.toml"\nomit = ["design.nothing"]\n', "'design.nothing' is not a table or key"),
    ('extends = "base.toml"\nomit = "design"\n', "must be an array of dotted keys"),
    ('extends = "base.toml"\nomit = [""]\n', "must be an array of dotted keys"),
])
def test_bad_omit_names_the_field(tmp_path, text, words):
    _copy(tmp_path)
    (tmp_path / "v.toml").write_text(text, encoding="utf-8")
    with pytest.raises(ProblemError) as err:
        load_problem(tmp_path / "v.toml")
    assert err.value.field == "omit" and words in err.value.message
    assert main(["kinematics", str(tmp_path / "v.toml"), "--plot", "none"]) == 2
