"""The HTML report of a linkage problem file (issue 24 item 3, the report section): ``strokeopt report
LINKAGE.toml --out FILE.html`` has the structure, kinematics, transmission and crank-torque sections, every
tagged number equal to ``strokeopt kinematics --json`` / ``size --json``; the servo comparison renders with its
table's numbers."""

from __future__ import annotations

import json
import re
from html.parser import HTMLParser

import pytest

from strokeopt.cli.main import main

from conftest import ROOT

LOOM = ROOT / "problems" / "loom_beatup_sixbar.toml"


class Tags(HTMLParser):
    """Section ids, figures and every data-key with its data-value."""

    def __init__(self):
        super().__init__(convert_charrefs=True)
        self.ids, self.values, self.figures = [], {}, 0

    def handle_starttag(self, tag, attrs):
        a = dict(attrs)
        if tag == "section":
            self.ids.append(a.get("id"))
        if tag == "figure":
            self.figures += 1
        if "data-key" in a:
            assert a["data-key"] not in self.values, f"data-key {a['data-key']} twice"
            self.values[a["data-key"]] = a["data-value"]


def _parse(path) -> Tags:
    tags = Tags()
    tags.feed(path.read_text(encoding="utf-8"))
    return tags


def _at(data, key: str):
    """``data`` at a data-key: 'outputs[1].table[3].speed', 'link_lengths_mm.crank.A0-C'."""
    node = data
    for part in key.replace("]", "").split("."):
        name, *index = part.split("[")
        if name:
            node = node[name]
        for i in index:
            node = node[int(i)]
    return node


def _json(capsys, argv) -> dict:
    assert main(argv) == 0
    return json.loads(capsys.readouterr().out)


def test_linkage_report_sections_and_numbers(capsys, tmp_path):
    out = tmp_path / "loom.html"
    info = _json(capsys, ["report", str(LOOM), "--out", str(out), "--json"])
    assert info["status"] == "ok" and out.stat().st_size == info["size_bytes"]
    tags = _parse(out)
    assert tags.ids == ["structure", "kinematics", "transmission", "torque", "inputs"] and tags.figures == 3
    sources = {"kinematics": _json(capsys, ["kinematics", str(LOOM), "--json"]),
               "size": _json(capsys, ["size", str(LOOM), "--json"])}
    assert len(tags.values) > 100
    for key, value in tags.values.items():
        source, rest = key.split(".", 1)
        expected = _at(sources[source], rest)
        if isinstance(expected, float):
            assert float(value) == expected, key
        else:
            assert value == str(expected), key
    torque = sources["size"]["transmission_analysis"]["dynamics"]["torque_N_m"]["min"]
    assert tags.values["size.transmission_analysis.dynamics.torque_N_m.min"] == repr(torque)
    text = out.read_text()
    assert sources["size"]["verdict"] in text and "flywheel" in text
    # the crank angles of the output tables as the grid's (0, 30, 60), not to four digits (30.00, 120.0)
    angles = re.findall(r'data-key="kinematics\.transmission_analysis\.outputs\[0\]\.table\[\d+\]\.angle_deg" '
                        r'data-value="[^"]*">([^<]*)<', text)
    assert angles[:5] == ["0", "30", "60", "90", "120"]


def test_the_report_s_options(capsys, tmp_path):
    # --servo belongs to a linkage's report; a design option does not apply to one
    reference = ROOT / "problems" / "deco2000_needle_bar.toml"
    assert main(["report", str(reference), "--servo", str(LOOM), "--out", str(tmp_path / "r.html")]) == 2
    assert "--servo" in capsys.readouterr().err
    assert main(["report", str(LOOM), "--objective", "min_rms_torque", "--out", str(tmp_path / "r.html")]) == 2
    assert "--objective" in capsys.readouterr().err


def test_the_servo_comparison_renders(tmp_path):
    # the linkage against the servo sley: one gearbox, two motors (the study's test), rendered with its table
    from strokeopt import load_problem
    from strokeopt.linkage.dynamics import analyse_dynamics
    from strokeopt.linkage.files import load_linkage_file
    from strokeopt.linkage.kinematics import kinematics_of
    from strokeopt.cli.main import build_parser
    from strokeopt.cli.commands import size_report
    from strokeopt.cli.common import apply_drive_options
    from strokeopt.report.linkage_report import LinkageReportData, linkage_report
    from strokeopt.studies.linkage_servo import compare_linkage_servo, load_gearboxes

    problem = load_linkage_file(LOOM)
    loom = load_problem(LOOM)
    args = build_parser().parse_args(["size", str(LOOM)])
    apply_drive_options(args)
    _, size = size_report(args, loom, loom.drive.catalogue())
    servo = compare_linkage_servo(problem, load_problem(ROOT / "problems" / "loom_beatup_servo.toml"),
                                  [g for g in load_gearboxes() if g.name == "planetary-160-i16"],
                                  motors=["AC-servo-100-8", "AC-servo-140-20"])
    kin = kinematics_of(problem.linkage)
    cycle = kin.solve(problem.angles)
    data = LinkageReportData(loom.transmission.analysis(loom), size, kin, cycle,
                             analyse_dynamics(kin, cycle, problem.omega), servo, "loom_beatup_servo.toml")
    out = tmp_path / "servo.html"
    out.write_text(linkage_report(data), encoding="utf-8")
    tags = _parse(out)
    assert tags.ids[-2:] == ["servo", "inputs"] and tags.figures == 4
    table = servo.to_dict()
    servo_keys = [k for k in tags.values if k.startswith("servo.")]
    assert len(servo_keys) >= 12
    for key in servo_keys:
        assert float(tags.values[key]) == pytest.approx(_at(table, key.split(".", 1)[1]), rel=0, abs=0), key
    assert "flywheel" in out.read_text()


@pytest.mark.slow
def test_report_with_servo_from_the_command_line(capsys, tmp_path):
    # the whole comparison (every gearbox with every loom servo: about 20 solves) as docs/loom-servo.md states it
    out = tmp_path / "loom.html"
    assert main(["report", str(LOOM), "--servo", str(ROOT / "problems" / "loom_beatup_servo.toml"),
                 "--out", str(out)]) == 0
    tags = _parse(out)
    assert "servo" in tags.ids
    assert float(tags.values["servo.table[1].servo"]) == pytest.approx(23.05, abs=0.01)   # AC-servo-100-8, i = 25
