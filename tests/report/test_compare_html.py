"""`strokeopt compare`: the min_peak_torque and min_rms_torque designs of the reference (500 spm) side by side."""

from __future__ import annotations

import json
from html.parser import HTMLParser
from pathlib import Path

import pytest

from strokeopt.cli.main import main
from strokeopt.io.plain import format_value
from strokeopt.report.design_report import SECTIONS

ROOT = Path(__file__).resolve().parents[2]
REFERENCE = ROOT / "problems" / "deco2000_needle_bar.toml"


class Cells(HTMLParser):
    """Every tagged cell (data-key -> value, class), the table header texts, the section ids."""

    def __init__(self):
        super().__init__()
        self.cells: dict[str, tuple[str, str]] = {}
        self.ids: list[str] = []
        self.heads: list[str] = []
        self._th = False

    def handle_starttag(self, tag, attrs):
        a = dict(attrs)
        if "data-key" in a:
            self.cells[a["data-key"]] = (a["data-value"], a.get("class") or "")
        if tag == "section":
            self.ids.append(a["id"])
        self._th = tag == "th"

    def handle_data(self, data):
        if self._th:
            self.heads.append(data)

    def handle_endtag(self, tag):
        self._th = False


@pytest.fixture(scope="module")
def two_designs(tmp_path_factory, reference_written, write_verified):
    """Two design.json files as ``solve --out DIR`` writes them, each in a directory named by its objective
    (compare's column heads): the reference (min_peak_torque, the session's one verified solve, conftest.py)
    and its min_rms_torque design, solved through the same verified pipeline."""
    import shutil

    from strokeopt import load_problem, solve_verified

    root = tmp_path_factory.mktemp("compare")
    (root / "min_peak_torque").mkdir()
    peak = shutil.copy(reference_written.design_json, root / "min_peak_torque" / "design.json")
    rms = solve_verified(load_problem(REFERENCE), objective="min_rms_torque")
    assert rms.ok
    written = write_verified(rms, root / "min_rms_torque", report=False)
    return root, [Path(peak), written.design_json]


def test_compare_shows_the_two_designs_side_by_side(two_designs, capsys):
    root, files = two_designs
    capsys.readouterr()
    html = root / "compare.html"
    assert main(["compare", *map(str, files), "--out", str(html), "--json"]) == 0
    info = json.loads(capsys.readouterr().out)
    assert info["status"] == "ok" and info["size_bytes"] < 1_000_000
    text = html.read_text(encoding="utf-8")
    assert "src=" not in text and "<script" not in text and text.count("<svg") >= 1
    p = Cells()
    p.feed(text)
    assert p.ids == [sid for sid, _ in SECTIONS]
    assert p.heads.count("min_peak_torque") >= 6 and p.heads.count("min_rms_torque") >= 6  # a column each, per table
    data = [json.loads(f.read_text()) for f in files]
    for i, d in enumerate(data):  # the numbers of each design file, exactly
        for key in ("spm", "pulley_teeth"):
            assert float(p.cells[f"designs[{i}].{key}"][0]) == d[key]
        # a peak and an RMS torque are not one row of numbers: each objective value says what it measures
        assert f"{format_value(d['objective_value'])} N m ({d['objective']})" in text
        for key, name in (("peak_torque_N_m", "peak_torque"), ("rms_torque_N_m", "rms_torque")):
            assert float(p.cells[f"designs[{i}].{key}"][0]) == next(c["value"] for c in d["checks"] if c["name"] == name)
    assert "objective value [N m]" not in text and "designs[0].objective_value" not in text
    peak = [float(p.cells[f"designs[{i}].peak_torque_N_m"][0]) for i in range(2)]
    rms = [float(p.cells[f"designs[{i}].rms_torque_N_m"][0]) for i in range(2)]
    assert peak[0] < peak[1] and rms[1] < rms[0]  # each objective wins its own measure
    # the better value of each row is marked: the peak torque in the first column, the RMS in the second
    assert "better" in p.cells["designs[0].peak_torque_N_m"][1] and "better" not in p.cells["designs[1].peak_torque_N_m"][1]
    assert "better" in p.cells["designs[1].rms_torque_N_m"][1] and "better" not in p.cells["designs[0].rms_torque_N_m"][1]
    # a row without a better direction marks nothing
    assert "better" not in p.cells["designs[0].spm"][1] + p.cells["designs[1].spm"][1]


def test_compare_needs_two_designs_and_says_which_file_is_bad(two_designs, capsys, tmp_path):
    _, files = two_designs
    assert main(["compare", str(files[0]), "--out", str(tmp_path / "c.html")]) == 2
    assert "two or more design files" in capsys.readouterr().err
    bad = tmp_path / "bad.json"
    bad.write_text("{}")
    assert main(["compare", str(files[0]), str(bad), "--out", str(tmp_path / "c.html")]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and str(bad) in err
    assert not (tmp_path / "c.html").exists()


@pytest.mark.slow  # two compare pages of the solved designs: about 10 s
def test_a_design_compared_with_itself_is_said(two_designs, capsys, tmp_path):
    # the same file twice, and a copy of it: their columns are identical, and compare says so before the work
    import shutil

    _, (peak, rms) = two_designs
    copy = shutil.copy(peak, tmp_path / "copy.json")
    assert main(["compare", str(peak), str(rms), str(copy), "--out", str(tmp_path / "c.html"), "--json"]) == 0
    out, err = capsys.readouterr()
    assert json.loads(out)["identical"] == [[str(peak), str(copy)]]
    assert f"note: {copy} is the same design as {peak}" in err
    assert main(["compare", str(peak), str(rms), "--out", str(tmp_path / "d.html"), "--json"]) == 0
    assert "identical" not in json.loads(capsys.readouterr().out)
