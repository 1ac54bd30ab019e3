"""The issue-22 repro of the reports: ``report`` and ``compare`` crashed (KeyError, TypeError, AttributeError,
ValueError at 7 sites) on a design.json with a move field, the checks, the drive or the comparison missing or of
the wrong type, e.g. ``moves[0].jerk_max_m_s3`` deleted and ``strokeopt report problems/deco2000_needle_bar.toml
--design x.json --out r.html``. The design file is validated whole on read (files/design_schema.py): each is
refused before any work, in one line naming the file and the field, exit 2, a JSON failure object under --json."""

from __future__ import annotations

import json

import pytest

from strokeopt.cli.main import main

from conftest import REFERENCE


def _del(path):
    def edit(d):
        node = d
        for key in path[:-1]:
            node = node[key]
        del node[path[-1]]
    return edit


def _set(path, value):
    def edit(d):
        node = d
        for key in path[:-1]:
            node = node[key]
        node[path[-1]] = value
    return edit


DAMAGE = [
    (_del(("moves", 0, "jerk_max_m_s3")), "moves[1].jerk_max_m_s3", "is required but missing"),  # the repro
    (_set(("moves", 0, "name"), 3), "moves[1].name", "must be a string"),
    (_set(("moves", 1, "a_max_m_s2"), "fast"), "moves[2].a_max_m_s2", "must be a number"),
    (_del(("checks", 0, "name")), "checks[1].name", "is required but missing"),
    (_set(("checks", 0, "margin"), "abc"), "checks[1].margin", "must be a number"),
    (_set(("checks", 1, "ok"), "yes"), "checks[2].ok", "must be true or false"),
    (_set(("checks",), {"x": 1}), "checks", "must be an array of tables"),
    (_set(("drive",), "055U2B30"), "drive", ""),
    (_set(("drive", "pulley_teeth"), "28"), "drive.pulley_teeth", "must be a number"),
    (_set(("comparison",), 7), "comparison", "must be an array of tables"),
    (_del(("comparison", 0, "law")), "comparison[1].law", "is required but missing"),
    (_set(("comparison", 1, "peak_torque_N_m"), "high"), "comparison[2].peak_torque_N_m", "must be a number"),
    (_set(("objective_value",), None), "objective_value", "must be a number"),
    (_del(("status",)), "status", "is required but missing"),
    (_set(("not_judged", 0, "value"), True), "not_judged[1].value", "must be a number"),
]


@pytest.mark.parametrize("command", ["report", "compare"])
@pytest.mark.parametrize("edit, field, words", DAMAGE, ids=[d[1] for d in DAMAGE])
def test_a_damaged_design_file_is_refused_naming_its_field(capsys, tmp_path, reference_written, command, edit,
                                                           field, words):
    data = json.loads(reference_written.design_json.read_text(encoding="utf-8"))
    edit(data)
    bad = tmp_path / "x.json"
    bad.write_text(json.dumps(data), encoding="utf-8")
    argv = (["report", str(REFERENCE), "--design", str(bad)] if command == "report"
            else ["compare", str(reference_written.design_json), str(bad)])
    assert main([*argv, "--out", str(tmp_path / "r.html")]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith(f"strokeopt: error: {bad}: {field}: ") and words in err[0], err
    assert not (tmp_path / "r.html").exists()
    assert main([*argv, "--out", str(tmp_path / "r.html"), "--json"]) == 2
    data = json.loads(capsys.readouterr().out)
    assert data["status"] == "bad input" and f"{bad}: {field}: " in data["message"]
