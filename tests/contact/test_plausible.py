"""Forces beyond what any part could carry are flagged, never "ok" (issue 22).

The rule (contact/plausible.py): every element of a scene carries at most the elastic force at which it stores
all the energy at stake -- every body of the scene at twice its rigid speed (an elastic rebound off the driven
body, whose motion is imposed) plus every spring compressed by its preload and the full travel of its bodies --
plus its damping at the largest closing speed and the force that accelerates every body at twice its rigid
peak acceleration; the drive force at most the limits of the elements on the driven body plus its inertia.

Why this rule and not the catalogue's: the contact model takes the stroke as given, so a 1e9 N/m impact makes
the drive force a spike of microseconds. On the unmodified reference it is 4685 N, beyond the belt's breaking
load (1990 N) and beyond the motor's peak torque over the pulley's radius; a catalogue limit would call the
reference absurd. The energy limit leaves the reference more than 20 times below it and flags the issue's
stroke x1000 (1.6e10 N) by a factor of about 50."""

from __future__ import annotations

import json
from dataclasses import replace

import pytest

import strokeopt.problem
from strokeopt import load_problem
from strokeopt.cli.main import main
from strokeopt.contact.plausible import force_limits, scene_implausible
from strokeopt.contact.simulate import simulate_scene
from strokeopt.contact.verify import design_verification, verification

from conftest import ROOT
from test_travel import X1000, _sets


def _peaks(result) -> dict:
    return {**result.metrics["peak_contact_forces_N"], "drive": result.metrics["peak_drive_force_N"]}


@pytest.mark.parametrize("file, scene", [("deco2000_needle_bar.toml", "release"),
                                         ("deco2000_needle_bar.toml", "handover"),
                                         ("deco2000_contact_design.toml", "release"),
                                         ("knitting_stitch_density.toml", "step")])
def test_the_shipped_problems_are_far_below_their_limits(file, scene):
    p = load_problem(ROOT / "problems" / file)
    r = simulate_scene(p, scene)
    limits = force_limits(p, scene, p.stroke(), r.t)
    peaks = _peaks(r)
    print(file, scene, {k: f"{peaks[k]:.4g} / {limits[k]:.4g}" for k in limits})
    assert scene_implausible(p, r, p.stroke()) == []
    # every force at least 4 times below its limit (a spring's force is its own: 4.8 times for k2), the 1e9 N/m
    # contacts and the drive force of the needle bar at least 20 times
    assert all(peaks[k] * 4 < limits[k] for k in limits)
    stiff = [k for k in limits if k != "drive" and p.model.elements[k].stiffness >= 1e9]
    stiff += ["drive"] if stiff else []  # the knitting chain (1e7 N/m links): 7.5 times
    assert all(peaks[k] * 20 < limits[k] for k in stiff)


def test_the_catalogue_would_have_called_the_reference_absurd(reference):
    # why the limit is the model's, not the belt's: the drive force's stiff-contact spike of the unmodified
    # reference is beyond the belt's breaking load, a force the belt never carries as tension
    r = simulate_scene(reference, "release")
    belt = reference.drive.catalogue().belt(reference.drive.belt, ("test", "drive.belt"))
    breaking = belt.breaking_tension[reference.drive.belt_cord]
    assert r.metrics["peak_drive_force_N"] > breaking == 1990
    limit = force_limits(reference, "release", reference.stroke(), r.t)["drive"]
    assert r.metrics["peak_drive_force_N"] * 20 < limit


@pytest.fixture
def past_its_stops(monkeypatch, reference_path):
    """The stroke x1000 read past the check on read (contact/travel.py), to show the second line of defence."""
    monkeypatch.setattr(strokeopt.problem, "check_travel", lambda *args, **kwargs: None)
    return load_problem(reference_path, X1000)


def test_a_stroke_past_its_stops_gives_implausible_forces(past_its_stops):
    p = past_its_stops
    r = simulate_scene(p, "release")
    rows = scene_implausible(p, r, p.stroke())
    names = {row["force"] for row in rows}
    assert names == {"pad", "c32", "c13", "drive"}, rows
    pad = next(row for row in rows if row["force"] == "pad")
    assert pad["value"] == pytest.approx(1.587e10, rel=0.01) and pad["value"] > 40 * pad["limit"]
    block = verification(r, implausible=rows)
    assert block["status"] == "verification failed" and "plausible forces" in block["failed"]
    assert block["verdict"].startswith("verification failed: ") and ("plausible forces: peak force of c13 "
                                                                      "1.587e+10 N > plausible 1.02e+08 N") in block["verdict"]


def test_simulate_exits_1_with_the_values_and_the_limits(past_its_stops, reference_path, capsys):
    code = main(["simulate", str(reference_path), *_sets(X1000), "--plot", "none", "--json"])
    out, err = capsys.readouterr()
    data = json.loads(out)
    assert code == 1 and data["status"] == "implausible forces"
    assert {r["force"] for r in data["implausible_forces"]} == {"pad", "c32", "c13", "drive"}
    lines = [x for x in err.splitlines() if x.startswith("strokeopt:")]
    assert len(lines) == 1 and "implausible forces in scene 'release': peak force of c13 1.587e+10 N" in lines[0]
    code = main(["simulate", str(reference_path), *_sets(X1000), "--plot", "none"])
    out = capsys.readouterr().out
    assert code == 1 and "IMPLAUSIBLE forces" in out


def test_a_design_judged_past_its_stops_fails_its_verification(past_its_stops, reference_verified):
    # the verdict of verify, report and the studies (design_verification): a design whose problem and stroke are
    # the stroke x1000's
    design = replace(reference_verified.design, problem=past_its_stops, stroke=past_its_stops.stroke())
    block = design_verification(design, "release")
    assert block["status"] == "verification failed" and "plausible forces" in block["failed"]
    assert "verified" not in block["verdict"]
