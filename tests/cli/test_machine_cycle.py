"""The machine's cycle in words (``[machine] cycle``): the loom's sley picks, so its outputs speak of picks and
picks/min, its gearbox is no pulley and its sley turns (positive/negative, not up/down); the needle bar's
outputs keep stitches and spm (their own tests hold them)."""

from __future__ import annotations

import re
from pathlib import Path

import pytest

from strokeopt.cli.main import main
from strokeopt.io.cycle import MachineCycle

ROOT = Path(__file__).resolve().parents[2]
LOOM = str(ROOT / "problems" / "loom_beatup_servo.toml")
FAST = ["--set", 'design.motor_choice="fixed"']  # the file's motor: one solve


def _words(text: str) -> str:
    """``text`` without the fields and options that name the rate and the cam's revolutions by their key."""
    return re.sub(r"machine\.(spm|cam_revolutions_per_stitch)|--spm", "", text)


def _assert_loom_words(text: str) -> None:
    body = _words(re.sub(r"<[^>]+>", " ", text))  # the words shown: no HTML tag or attribute
    for word in ("stitch", "spm", "pulley"):
        assert word not in body.lower(), (word, body[max(0, body.lower().find(word) - 120):][:240])
    words = body.replace("&quot;up&quot;", "").replace("&quot;down&quot;", "")  # the file's
    found = re.search(r"(?<![-\w])(up|down)(?![-\w])", words)  # own values (the inputs table) aside
    assert found is None, ("a rotary load's moves in up/down", words[max(0, found.start() - 120):][:240])


def test_cycle_words():
    assert MachineCycle().rate(600) == "600 spm" and MachineCycle().count("2") == "2 stitches"
    pick = MachineCycle("pick")
    assert pick.rate(200) == "200 picks/min" and pick.count("1") == "1 pick" and pick.rate_name == "pick rate"


def test_bad_cycle_noun_is_refused_in_one_line(capsys):
    assert main(["kinematics", LOOM, "--set", 'machine.cycle="Pick 2"', "--plot", "none"]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "machine.cycle" in err and "loom_beatup_servo.toml" in err


def test_loom_kinematics_and_size_speak_of_picks(capsys):
    assert main(["kinematics", LOOM, "--plot", "none"]) == 0
    text = capsys.readouterr().out
    assert "at 200 picks/min (cam cycle 300.0 ms = 1 pick of 300.0 ms" in text
    assert "positive" in text and "negative" in text
    _assert_loom_words(text)
    assert main(["size", LOOM, "--plot", "none"]) == 0
    text = capsys.readouterr().out
    assert "200 picks/min" in text
    _assert_loom_words(text.replace("pulley_teeth", ""))  # the column's key is no word of the text


@pytest.mark.slow
def test_loom_solve_text_and_report_speak_of_picks_and_the_gearbox(capsys, tmp_path):
    out = tmp_path / "loom"
    assert main(["solve", LOOM, *FAST, "--out", str(out), "--plot", "none"]) == 0
    text = capsys.readouterr().out
    assert "optimal stroke at 200 picks/min (cam cycle 300.0 ms = 1 pick of 300.0 ms" in text
    assert "gearbox of ratio 16" in text
    _assert_loom_words(text)
    html = (out / "report.html").read_text()
    assert "design at 200 picks/min" in html and "pick rate [picks/min]" in html
    assert "gear ratio" in html
    _assert_loom_words(html)


def test_tradeoff_refuses_a_drive_without_a_belt(capsys):
    """The trade-off searches a belt drive's rates: the loom's gearbox is refused in one line naming
    transmission.type (it was 'no GT3 pulley with None teeth in the catalogue'); accuracy judges it
    (tests/servo/test_gearbox_servo.py)."""
    assert main(["tradeoff", LOOM, "--plot", "none"]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "None" not in err
    assert "loom_beatup_servo.toml: transmission.type: is 'gearbox'" in err and "belt_pulley" in err


def test_knitting_rig_counts_test_cycles(capsys):
    """The knitting file's cycle is a test cycle of density changes, not a stitch ([machine] cycle)."""
    assert main(["kinematics", str(ROOT / "problems" / "knitting_stitch_density.toml"), "--plot", "none"]) == 0
    text = capsys.readouterr().out
    assert "at 1000 test cycles/min (cam cycle 60.0 ms = 1 test cycle of 60.0 ms" in text
    assert main(["simulate", str(ROOT / "problems" / "knitting_stitch_density.toml"), "--plot", "none"]) == 0
    text = capsys.readouterr().out
    assert "6 states) at 1000 test cycles/min" in text and "spm" not in text
