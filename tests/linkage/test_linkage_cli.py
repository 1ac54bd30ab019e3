"""``strokeopt linkage``: the command's reports, its figure, and bad geometry refused in one line naming the
file, the field and (for geometry that cannot turn) the crank angle, with exit code 2."""

from __future__ import annotations

import json
import re

import pytest

from strokeopt.cli.main import main

from conftest import ROOT

BLIND = ROOT / "problems" / "blind_stitch_needle.toml"
LOOM = ROOT / "problems" / "loom_beatup_sixbar.toml"


def test_linkage_json_and_figure(capsys, tmp_path):
    fig = tmp_path / "loom.png"
    assert main(["linkage", str(LOOM), "--json", "--plot", str(fig)]) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["status"] == "ok" and fig.stat().st_size > 10_000
    # digest C: 6 links, 7 revolute joints, mobility 1; the driven chain one triad
    st = out["structure"]
    assert (st["mobility"], st["links"], st["revolute_joints"], st["independent_loops"]) == (1, 6, 7, 2)
    assert [g["kind"] for g in st["groups"] if g["kind"] != "placement"] == ["triad"]
    sley = next(o for o in out["outputs"] if o["name"] == "sley_angle")
    # digest C: sley swing 19.5 deg (+-0.3, the synthesis's acceptance), front extreme at 355 (+-10) deg
    assert sley["swing_deg"] == pytest.approx(19.5, abs=0.3)
    assert min(abs(sley["minimum_at_deg"] - 355), abs(sley["minimum_at_deg"] + 5)) <= 10
    assert {d["at"] for d in sley["near_dwells"]} == {"maximum", "minimum"}
    assert out["closure"]["max_residual_m"] <= 1e-9
    assert out["dynamics"]["newton_euler_max_relative_difference"] <= 1e-6


def test_linkage_text(capsys):
    # digest D: n = 3*5 - 2*7 = 1, two loop closure equations; the text names Alt's angle of each dyad
    assert main(["linkage", str(BLIND), "--plot", "none"]) == 0
    text = capsys.readouterr().out
    assert "mobility 1, 6 links (with the ground), 7 revolute joints, 2 independent loops" in text
    assert "near-dwell" in text
    # a dyad's quality in degrees against the file's limit (min_transmission_index 0.05 = sin 2.9 deg), the classic
    # guidance (40 deg, 30 at worst) warned of with the force it costs (1 / sin 4.72 deg = 12.1)
    assert ("transmission angle of the dyad coupler5, needle_rocker6: least 4.7 deg at 322 deg (Alt's; index 0.082); "
            "the file's limit 2.9 deg (min_transmission_index 0.05): ok") in text
    assert "WARNING: 4.7 deg is below the classic guidance" in text and "12.1 times" in text
    assert "least 68.0 deg" in text and text.count("below the classic guidance") == 1
    # the needle four-bar sits 0.0567 mm from a change point (s + l = p + q): warned; the first is 30 mm away
    assert "WARNING: loop C-O4-O6-D is 0.0567 mm from a change point" in text and text.count("from a change point") == 1


def test_the_json_states_the_change_point_distance_and_the_classic_guidance(capsys):
    assert main(["linkage", str(BLIND), "--json", "--plot", "none"]) == 0
    out = json.loads(capsys.readouterr().out)
    loops = out["structure"]["four_bar_loops"]
    assert [f["near_change_point"] for f in loops] == [False, True]
    s, l = min(loops[1]["lengths_mm"]), max(loops[1]["lengths_mm"])
    assert loops[1]["change_point_distance_mm"] == pytest.approx(abs(2 * (s + l) - sum(loops[1]["lengths_mm"])),
                                                                 abs=1e-3)
    assert [t["below_classic_guidance"] for t in out["transmission"]] == [False, True]


def _one_line_error(capsys, argv, field: str, angle: bool):
    assert main(argv) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1
    assert str(argv[1]) in err and field in err
    if angle:
        assert re.search(r"angle \d+\.\d+ deg", err), err
    return err


@pytest.mark.parametrize("override, joint, links", [
    # a crank too long for its coupler (the first four-bar turns Grashof -> non-Grashof): no closure beyond an angle
    ("transmission.joints[2].x_mm=60", "joint A", "links coupler3, rocker4"),
    # the needle rocker's pivot moved: the needle dyad reaches a toggle (dead centre) inside the cycle
    ("transmission.joints[7].x_mm=-20", "joint O6", "links coupler5, needle_rocker6"),
])
def test_geometry_that_cannot_turn_is_refused_naming_the_angle(capsys, override, joint, links):
    # issue 24 acceptance (bad geometry): one line naming the file, the field and the angle, exit 2; the field
    # is the one the user set (and the joint it moves), the links and the angle where the chain fails follow
    field = override.split("=")[0]
    err = _one_line_error(capsys, ["linkage", str(BLIND), "--set", override, "--plot", "none"], field, angle=True)
    assert f": {field}: {joint} as set by --set" in err and links in err and "dead centre" in err


def test_a_set_joint_of_the_loom_is_named_not_a_link(capsys):
    # the loom's crank pin C moved to 60 mm: the triad cannot close; the message names the field set and pin C
    err = _one_line_error(capsys, ["linkage", str(LOOM), "--set", "transmission.joints[2].x_mm=60", "--plot", "none"],
                          "transmission.joints[2].x_mm", angle=True)
    assert "joint C as set by --set" in err and "rod_CE, rod_BF, coupler, sley" in err
    assert "transmission.links" not in err


def test_a_link_too_short_in_the_loom(capsys):
    # issue 24 acceptance (a link too short to close), on the triad of digest C
    # the sley shaft B0 moved 60 mm towards the coupler: the sley cannot reach D over the whole turn
    err = _one_line_error(capsys, ["linkage", str(LOOM), "--set", "transmission.joints[7].y_mm=-40", "--plot", "none"],
                          "transmission.joints[7].y_mm: joint B0 as set by --set", angle=True)
    assert "rod_CE, rod_BF, coupler, sley" in err


def _variant(tmp_path, text: str) -> str:
    path = tmp_path / "variant.toml"
    path.write_text(text)
    return str(path)


def test_structural_errors_are_refused(capsys, tmp_path):
    # issue 24 acceptance: a joint named twice, a link naming an unknown joint, a mobility other than 1
    text = BLIND.read_text()
    twice = text.replace('name = "C"                    # second arm', 'name = "B"                    # second arm')
    _one_line_error(capsys, ["linkage", _variant(tmp_path, twice)], "transmission.joints[5].name", angle=False)
    unknown = text.replace('joints = ["C", "D"]', 'joints = ["C", "Q"]')
    err = _one_line_error(capsys, ["linkage", _variant(tmp_path, unknown)], "transmission.links[4].joints",
                          angle=False)
    assert "'Q'" in err
    extra = text.replace('joints = ["O4", "B", "C"]', 'joints = ["O4", "B"]').replace(
        '[[transmission.links]]\nname = "coupler5"', '[[transmission.links]]\nname = "arm42"\njoints = ["O4", "C"]\n\n'
                                                      '[[transmission.links]]\nname = "coupler5"')
    err = _one_line_error(capsys, ["linkage", _variant(tmp_path, extra)], "transmission.links", angle=False)
    assert "mobility 2" in err     # 3 x 6 - 2 x 8 = 2: the split rocker turns freely about O4


def test_transmission_limit_exit_1(capsys):
    # the blind-stitch reconstruction's needle dyad falls to sin(4.7 deg) = 0.082 (digest D reconstruction)
    assert main(["linkage", str(BLIND), "--set", "transmission.min_transmission_index=0.1", "--plot", "none"]) == 1
    assert "below the limit 0.1" in capsys.readouterr().err


PARALLELOGRAM = """
[problem]
name = "parallelogram four-bar"
[machine]
spm = 100
[transmission]
type = "linkage"
reference_angle_deg = 90.0
[transmission.crank]
link = "crank"
pivot = "O2"
[[transmission.joints]]
name = "O2"
x_mm = 0.0
y_mm = 0.0
ground = true
[[transmission.joints]]
name = "A"
x_mm = 0.0
y_mm = 10.0
[[transmission.joints]]
name = "B"
x_mm = 100.0
y_mm = 10.0
[[transmission.joints]]
name = "O4"
x_mm = 100.0
y_mm = 0.0
ground = true
[[transmission.links]]
name = "crank"
joints = ["O2", "A"]
[[transmission.links]]
name = "coupler"
joints = ["A", "B"]
[[transmission.links]]
name = "follower"
joints = ["O4", "B"]
[[transmission.outputs]]
name = "follower"
kind = "angle"
joint = "B"
about = "O4"
"""


def test_a_toggle_inside_the_cycle_is_refused(capsys, tmp_path):
    # a parallelogram four-bar (a Grashof change point) turns through two dead centres, at 0 and 180 deg,
    # where coupler and follower are collinear: refused with the angle
    err = _one_line_error(capsys, ["linkage", _variant(tmp_path, PARALLELOGRAM)], "transmission.links[2]",
                          angle=True)
    assert "dead centre (toggle) at input angle 0.00 deg" in err or "180.00 deg" in err


def test_synthesize_needs_a_synthesis_section(capsys, tmp_path):
    # README: bad input ends with one line naming the file and the field, exit 2
    _one_line_error(capsys, ["linkage", _variant(tmp_path, PARALLELOGRAM), "--synthesize"], "synthesis",
                    angle=False)


def test_synthesis_section_is_checked_at_load(capsys, tmp_path):
    # README: misspelt keys are errors (here in [synthesis], refused before any work)
    text = BLIND.read_text().replace("rms_max_m_s = 0.06", "rms_max_m_s = 0.06\nrms_maximum = 1")
    _one_line_error(capsys, ["linkage", _variant(tmp_path, text)], "synthesis.rms_maximum", angle=False)


def test_a_problem_of_another_machine_is_named(capsys):
    # before: "machine.rpm: is required but missing" for the needle-bar problem (a new user's mistake)
    from pathlib import Path

    from strokeopt.cli.main import main

    reference = Path(__file__).resolve().parents[2] / "problems" / "deco2000_needle_bar.toml"
    assert main(["linkage", str(reference), "--plot", "none"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "transmission.type" in err[0] and "is belt_pulley" in err[0]


@pytest.mark.parametrize("command, field", [("solve", "drive.motor"), ("simulate", "scenes"),
                                            ("accuracy", "drive.motor"), ("tradeoff", "transmission.type")])
def test_a_stroke_command_on_a_linkage_file_names_what_it_lacks(capsys, command, field):
    # a linkage file without [timing] is a problem (its crank at constant speed): a command that needs a motor, a
    # contact model or a belt says which field, in one line (it used to be refused as a file of another kind)
    assert main([command, str(LOOM), "--plot", "none"]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and f"{field}:" in err
