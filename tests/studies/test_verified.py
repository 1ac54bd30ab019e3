"""One answer everywhere: the library's verified pipeline (``strokeopt.solve_verified``) and ``strokeopt
solve --json`` give the same design, status, verdict, handover error, checks and verification block, on the
reference problem, the contact-design file and the knitting drive -- there is no CLI-only composition."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

import strokeopt as so
from strokeopt.cli.main import main
from strokeopt.io.plain import to_json

PROBLEMS = Path(__file__).resolve().parents[2] / "problems"

CASES = [
    # (file, --set texts, --objective, expected status): the knitting drive with the pull-out curve reported,
    # not held, and the fastest step under it (min_time)
    ("deco2000_needle_bar.toml", [], None, "optimal"),
    ("deco2000_contact_design.toml", [], None, "optimal"),
    ("knitting_stitch_density.toml", [], "min_time", "optimal"),
]


def _same(a, b, path=""):
    """Field-by-field equality of two JSON values; floats to 1e-9 relative (two solves of one NLP)."""
    if isinstance(a, dict):
        assert isinstance(b, dict) and set(a) == set(b), f"{path}: keys {sorted(set(a) ^ set(b))}"
        for k in a:
            _same(a[k], b[k], f"{path}.{k}")
    elif isinstance(a, list):
        assert isinstance(b, list) and len(a) == len(b), path
        for i, (x, y) in enumerate(zip(a, b)):
            _same(x, y, f"{path}[{i}]")
    elif isinstance(a, float) and isinstance(b, float):
        assert a == pytest.approx(b, rel=1e-9, abs=1e-12), path
    else:
        assert a == b, path


@pytest.mark.slow  # three solves, each through the library and the command line
@pytest.mark.parametrize("name, sets, objective, status", CASES)
def test_library_and_cli_give_one_answer(capsys, name, sets, objective, status):
    problem = so.load_problem(PROBLEMS / name, sets)
    verified = so.solve_verified(problem, objective=objective)
    lib = json.loads(to_json(verified.summary()))
    argv = ["solve", str(PROBLEMS / name), "--json", "--plot", "none"] + [a for s in sets for a in ("--set", s)]
    code = main(argv + (["--objective", objective] if objective else []))
    cli = json.loads(capsys.readouterr().out)
    assert code == (0 if verified.ok else 1) and cli["status"] == verified.status == status
    cli.pop("drive")  # where the motor and pulley came from: the command line's options, not the design
    for volatile in ("solve_time_s",):  # wall times of two runs
        lib.pop(volatile), cli.pop(volatile)
    for block in (lib, cli):
        if "verification" in block:
            block["verification"].pop("cpu_time_s")
    _same(lib, cli)
    for key in ("status", "verdict", "checks", "not_judged", "objective_value", "motor", "pulley_teeth"):
        assert key in cli
    assert "verified" not in cli["verdict"] or not cli["not_judged"]  # never "verified" beside an unjudged value


def test_verdict_names_what_was_not_judged(reference):
    # the reference file sets no lag or impact-velocity limit: the design is "solved, 2 criteria not judged",
    # with their values, never "verified" (before: "verified in scene 'release'" beside a 1.7 mm lag)
    verified = so.verify_design(so.solve_design(reference))
    assert verified.status == "optimal" and verified.ok and not verified.strict_ok()
    assert verified.verdict.startswith("solved, 2 criteria not judged (scene 'release'): lag ")
    assert {r["criterion"] for r in verified.unjudged} == {"lag", "impact velocity"}
    assert {r["field"] for r in verified.unjudged} == {"design.contact.lag_max_mm",
                                                       "design.contact.impact_velocity_max_m_s"}
    assert "verified" not in verified.verification["verdict"].split(":")[0]
    assert len(repr(verified)) < 600 and repr(verified).startswith("VerifiedDesign(optimal: min_peak_torque")


def test_a_judged_design_is_verified(reference):
    # every criterion given a limit (loose enough to hold): the verdict says verified and names them
    judged = reference.with_overrides(["design.contact.lag_max_mm=10", "design.contact.impact_velocity_max_m_s=5"])
    verified = so.verify_design(so.solve_design(judged))
    assert verified.strict_ok() and verified.verdict.startswith("verified (scene 'release'): ")
    assert "lag" in verified.verdict and "impact velocity" in verified.verdict


def test_verdict_counts_in_the_right_number():
    """'1 criteria not judged' was printed: one criterion, one design limit are singular, more are plural."""
    from types import SimpleNamespace

    from strokeopt.io.plain import counted
    from strokeopt.studies.verified import _verdict

    lag = {"criterion": "lag", "ok": None, "value": 1.7, "unit": "mm"}
    block = {"status": "ok", "scene": "release", "criteria": [lag, {"criterion": "premature release", "ok": True}]}
    design = SimpleNamespace(status="optimal", notes=[], checks=[{"name": "peak_torque", "ok": True}])
    one = ({**lag, "field": "design.contact.lag_max_mm"},)
    assert _verdict(design, block, one).startswith("solved, 1 criterion not judged (scene 'release'): lag 1.7 mm")
    two = one + ({"criterion": "impact velocity", "value": 2.6, "unit": "m/s",
                  "field": "design.contact.impact_velocity_max_m_s"},)
    assert _verdict(design, block, two).startswith("solved, 2 criteria not judged")
    assert _verdict(design, None, ()) == ("solved: 1 design limit met on the rigid model; nothing re-simulated "
                                          "(no [servo] section, no scenes)")
    assert counted(1, "criterion", "criteria") == "1 criterion" and counted(3, "design limit") == "3 design limits"
