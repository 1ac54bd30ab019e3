"""A design remembers the problem it was solved for: its --set overrides travel with design.json."""

from __future__ import annotations

import json

import pytest

from strokeopt.files.design_file import load_design
from strokeopt import load_problem, verify
from strokeopt.cli.main import main

K2 = "model.springs.k2.stiffness_N_m=1240"


@pytest.fixture(scope="module")
def design_dir(tmp_path_factory, reference_path):
    out = tmp_path_factory.mktemp("design")
    code = main(["solve", str(reference_path), "--spm", "550", "--motor", "055U2B30", "--pulley-teeth", "28",
                 "--set", K2, "--out", str(out), "--json", "--plot", "none"])
    assert code == 0
    return out


def test_design_file_records_the_overrides(design_dir):
    data = json.loads((design_dir / "design.json").read_text())
    assert K2 in data["overrides"]


def test_verify_uses_the_design_overrides(design_dir, reference_path, capsys):
    capsys.readouterr()
    assert main(["verify", str(reference_path), "--design", str(design_dir / "design.json"), "--json",
                 "--plot", "none"]) in (0, 1)
    with_design = json.loads(capsys.readouterr().out)["impact_velocity_m_s"]
    assert main(["verify", str(design_dir / "design.json"), "--json", "--plot", "none"]) in (0, 1)
    positional = json.loads(capsys.readouterr().out)["impact_velocity_m_s"]
    # the library path gives the same number, and it is the stiffer spring's (not the file's 900 N/m)
    lib = verify(load_design(design_dir / "design.json"), "release").metrics["impact_velocity_m_s"]
    stock = load_problem(reference_path, ["machine.spm=550"])
    from strokeopt.files.design_file import read_design

    _, stroke = read_design(design_dir / "design.json")
    from strokeopt import simulate_scene

    soft = simulate_scene(stock, "release", 550, stroke=stroke).metrics["impact_velocity_m_s"]
    assert with_design == pytest.approx(positional, rel=1e-9) == pytest.approx(lib, rel=1e-9)
    assert abs(with_design - soft) > 0.05  # the override changes the answer: it must not be lost


@pytest.mark.parametrize("extra", [["--set", "model.springs.k2.stiffness_N_m=900"], ["--set", "machine.spm=700"]])
def test_a_set_against_the_design_is_an_error(design_dir, reference_path, extra, capsys):
    code = main(["verify", str(reference_path), "--design", str(design_dir / "design.json"), *extra, "--plot", "none"])
    err = capsys.readouterr().err
    assert code == 2 and "design" in err and err.count("\n") == 1


def test_load_problem_takes_one_override_as_a_string(reference_path):
    assert load_problem(reference_path, "machine.spm=600").spm == 600.0


@pytest.mark.parametrize("edit, words", [
    ({"schema_version": 99}, "schema_version: 99: written by a newer strokeopt; this one reads design files up to "
                             "schema 2"),
    ({"schema_version": "2"}, "schema_version: must be a positive whole number, got '2'"),
])
def test_design_file_schema_is_checked(tmp_path, capsys, design_dir, edit, words):
    # one versioned schema: a newer file is refused saying what to do, a file of the first schema (no
    # schema_version, "version": 1) is read as it is
    data = json.loads((design_dir / "design.json").read_text(encoding="utf-8"))
    assert data["schema_version"] == 2 and "verdict" in data and "not_judged" in data
    old = {k: v for k, v in data.items() if k != "schema_version"}
    (tmp_path / "old.json").write_text(json.dumps({**old, "version": 1}), encoding="utf-8")
    assert main(["verify", str(tmp_path / "old.json"), "--json", "--plot", "none"]) in (0, 1)
    capsys.readouterr()
    bad = {k: v for k, v in {**data, **edit}.items() if v is not None}
    (tmp_path / "bad.json").write_text(json.dumps(bad), encoding="utf-8")
    assert main(["verify", str(tmp_path / "bad.json"), "--plot", "none"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "bad.json" in err[0] and words in err[0]


@pytest.mark.parametrize("edit, field, words", [
    (lambda d: {**d, "motor": "XYZ"}, "motor", "'XYZ' is not in the catalogue of"),
    (lambda d: {**d, "problem_file": "/nonexistent/x.toml"}, "problem_file", "pass --problem FILE"),
    (None, "", "is not JSON (expecting property name"),
])
def test_a_hand_edited_design_is_refused_naming_its_own_file(reference_written, tmp_path, capsys, edit, field, words):
    # the design file is named, not the problem file it points to (a new user's edits: a motor, a moved problem)
    data = json.loads((reference_written.out / "design.json").read_text())
    path = tmp_path / "design.json"
    path.write_text(json.dumps(edit(data)) if edit else "{not json")
    assert main(["verify", str(path), "--plot", "none"]) == 2
    err = capsys.readouterr().err
    assert f"{path}: {field + ': ' if field else ''}" in err and words in err and "Traceback" not in err
