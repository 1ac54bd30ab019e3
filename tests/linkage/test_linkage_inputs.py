"""Bad linkage inputs refused by name (issue 35, linkage inputs): each case is the issue's repro, and failed
before the fix (a ZeroDivisionError, a crank of length zero analysed, inf accepted as a target, --seed/--starts
ignored or unchecked, an output named twice, a gearbox name that disagreed with its values)."""

from __future__ import annotations

import pytest

from strokeopt.cli.main import main

from conftest import ROOT

LOOM = str(ROOT / "problems" / "loom_beatup_sixbar.toml")
BLIND = str(ROOT / "problems" / "blind_stitch_needle.toml")
SERVO = str(ROOT / "problems" / "blind_stitch_servo.toml")
LOOM_SERVO = str(ROOT / "problems" / "loom_beatup_servo.toml")


@pytest.mark.parametrize("argv, words", [
    # D moved onto B0: the sley's centre of gravity on the line B0-D divided by zero
    (["linkage", LOOM, "--set", "transmission.joints[6].x_mm=75.07", "--set", "transmission.joints[6].y_mm=-100.186"],
     "transmission.links[5].joints: joints B0 and D of link sley coincide"),
    # a crank of length zero was reported as a Grashof crank-rocker
    (["linkage", BLIND, "--set", "transmission.joints[2].x_mm=0"], "joints O2 and A of link crank coincide"),
    (["size", SERVO, "--set", "transmission.joints[2].x_mm=0"], "joints O2 and A of link crank coincide"),
    (["linkage", BLIND, "--synthesize", "--set", "synthesis.angles_deg=[1, 2, 3]", "--set",
      "synthesis.speeds_m_s=[0.5, inf, 0.1]"], "synthesis.speeds_m_s: entry 2 is inf"),
    (["linkage", BLIND, "--synthesize", "--set", "synthesis.angles_deg=[1, nan, 3]", "--set",
      "synthesis.speeds_m_s=[0.5, 0.2, 0.1]"], "synthesis.angles_deg: entry 2 is nan"),
    (["linkage", BLIND, "--synthesize", "--starts", "0"], "--starts: 0: the synthesis solves 1 to 200 starts"),
    (["linkage", BLIND, "--synthesize", "--starts", "1000"], "--starts: 1000"),
    (["linkage", BLIND, "--synthesize", "--seed", "-5"], "--seed: -5: a seed is 0 to 2^31"),
    (["linkage", BLIND, "--seed", "3"], "--seed: sets the synthesis: give it with --synthesize"),
    (["linkage", BLIND, "--starts", "3"], "--starts: sets the synthesis"),
    (["linkage", BLIND, "--set", 'transmission.outputs[2].name="needle"'],
     "transmission.outputs[2].name: output 'needle' is named twice"),
    # a catalogue gearbox named beside other values was a free label
    (["size", LOOM_SERVO, "--set", 'transmission.gearbox="planetary-160-i5"'],
     "transmission.gearbox: planetary-160-i5: the catalogue's has ratio = 5, the file 16"),
    (["size", LOOM_SERVO, "--set", 'transmission.gearbox="mine"'], "'mine' is not in the gearbox catalogue"),
])
def test_refused_by_name(argv, words, capsys):
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert words in err and "Traceback" not in err


def test_a_named_gearbox_supplies_its_values():
    from pathlib import Path

    from strokeopt.files.problem_file import read_problem_data
    from strokeopt.problem import parse_problem

    data = read_problem_data(Path(LOOM_SERVO))
    data["transmission"] = {"type": "gearbox", "gearbox": "planetary-160-i5"}
    tr = parse_problem(data, LOOM_SERVO).transmission
    assert (tr.ratio, tr.entry) == (5.0, "planetary-160-i5") and tr.inertia > 0
