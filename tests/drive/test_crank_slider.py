"""The crank and connecting rod as a registered transmission: its position function against the textbook
slider-crank formulas, its reading from a problem file (ranges, the reach of [timing]), and the reference
needle bar designed through it (problems/deco2000_crank_slider.toml)."""

from __future__ import annotations

import math
import re
from pathlib import Path

import numpy as np
import pytest

from strokeopt import TRANSMISSIONS, CrankSlider, ProblemError, load_problem
from strokeopt.drive.crank_slider import DEAD_CENTRE_MARGIN_DEG

PROBLEMS = Path(__file__).resolve().parents[2] / "problems"
CRANK_FILE = PROBLEMS / "deco2000_crank_slider.toml"
PHI = np.linspace(0.2, 2.9, 13)


def _textbook(r: float, l: float, phi):
    """Slider-crank without offset (any kinematics text, e.g. Norton, Design of Machinery, eq. 4.13): travel from
    the outer dead centre and its first and second derivatives by the crank angle, written out by hand."""
    root = np.sqrt(l**2 - (r * np.sin(phi)) ** 2)
    x = r + l - r * np.cos(phi) - root
    mu = r * np.sin(phi) + r**2 * np.sin(phi) * np.cos(phi) / root
    nu = r * np.cos(phi) + r**2 * np.cos(2 * phi) / root + r**4 * np.sin(phi) ** 2 * np.cos(phi) ** 2 / root**3
    return x, mu, nu


@pytest.mark.parametrize("dead_centre, sense", [(0.0, 1.0), (-3e-4, 1.0), (0.04, -1.0)])
def test_ad_transfer_functions_equal_the_textbook_formulas(dead_centre, sense):
    tr = CrankSlider(0.018, 0.08, dead_centre=dead_centre, sense=sense)
    x, mu, nu = tr.transfer(PHI)
    bx, bmu, bnu = _textbook(0.018, 0.08, PHI)
    assert x == pytest.approx(dead_centre + sense * bx, rel=1e-12, abs=1e-15)
    assert mu == pytest.approx(sense * bmu, rel=1e-10)
    assert nu == pytest.approx(sense * bnu, rel=1e-10, abs=1e-12)
    assert tr.motor_angle(x) == pytest.approx(PHI, rel=1e-9)   # the inverse over the half turn


def test_reach_keeps_the_crank_off_its_dead_centres():
    tr = CrankSlider(0.018, 0.08, dead_centre=-3e-4, sense=1.0)
    m = math.radians(DEAD_CENTRE_MARGIN_DEG)
    lo, hi = float(tr.position(m)), float(tr.position(math.pi - m))
    assert tr.range_error(lo + 1e-9, hi - 1e-9) is None
    assert "outside" in tr.range_error(lo - 1e-5, hi)          # 10 um past the margin at the outer dead centre
    assert "outside" in tr.range_error(lo, hi + 1e-5)          # and at the inner one
    assert hi - lo < 2 * 0.018                                  # less than the full travel 2 r


def test_registry_reads_every_type_the_problem_reader_offers():
    assert list(TRANSMISSIONS) == ["belt_pulley", "screw_lever", "gearbox", "crank_slider", "linkage"]
    for name, cls in TRANSMISSIONS.items():
        # a linkage's load is its output's (an angle or a length): its fields decide
        assert cls.name == name and cls.label and cls.load_unit in (("m", "rad", None) if name == "linkage" else ("m", "rad"))
        assert cls.read.__func__ is not TRANSMISSIONS["belt_pulley"].__mro__[1].read.__func__, name


def test_the_crank_file_is_the_reference_with_a_crank():
    crank, belt = load_problem(CRANK_FILE), load_problem(PROBLEMS / "deco2000_needle_bar.toml")
    tr = crank.transmission
    assert isinstance(tr, CrankSlider) and (tr.r, tr.l, tr.dead_centre, tr.sense) == pytest.approx((0.020, 0.08, -3e-4, 1.0))
    assert tr.inertia == pytest.approx(0.43e-4)
    assert crank.timing == belt.timing and crank.data["model"] == belt.data["model"]   # extends the reference
    # the reference's servo drive without the belt's geometry; a varying ratio has no linear design term
    assert crank.servo is not None and "belt_span_mm" not in crank.data["servo"] and crank.error_terms == ()
    assert crank.drive.belt is None and crank.design.pulley == "fixed"
    assert crank.drive.load.moving_mass == 0.201


@pytest.mark.parametrize("override, field, words", [
    ("transmission.rod_length_mm=15", "transmission.rod_length_mm", "longer than the crank radius"),
    # the travel refused naming the field the user set among those that place it (else the dead centre)
    ("transmission.crank_radius_mm=17", "transmission.crank_radius_mm", "outside"),      # 34 mm < 35 mm of travel
    ("transmission.crank_radius_mm=17.6", "transmission.crank_radius_mm", "outside"),    # 35.2 mm less the margins
    ("transmission.dead_centre_mm=1.0", "transmission.dead_centre_mm", "the position 0 mm is outside"),
    ('transmission.direction="down"', "transmission.direction", "outside"),
    ('drive.belt="GT3-3MR-09"', "drive.belt", "is a belt drive's"),                    # no belt to check
    ("drive.pulley_teeth_min=20", "drive.pulley_teeth_min", "a crank and connecting rod (transmission.type), has neither"),
    ("transmission.crank_radius_mm=0", "transmission.crank_radius_mm", "plausible range"),
    ('transmission.type="gearbox"', "transmission.type", "positions and strokes in deg"),
    # the crank radius as a design variable ([design.free.transmission])
    ("design.free.transmission.rod_length_mm=[70, 90]", "design.free.transmission.rod_length_mm",
     "no field 'rod_length_mm' a design may free; it offers: crank_radius_mm"),
    ("design.free.transmission.crank_radius_mm=[18, 80]", "design.free.transmission.crank_radius_mm",
     "shorter than the rod (80 mm)"),
    ("design.free.transmission.crank_radius_mm=[20, 18]", "design.free.transmission.crank_radius_mm",
     "0 < lower <= upper"),
    # a bound that cannot carry the stroke: refused before the NLP meets it (its acos has no derivative there)
    ("design.free.transmission.crank_radius_mm=[10, 30]", "design.free.transmission.crank_radius_mm",
     "at 10 mm the position 35 mm is outside"),
    ("design.free.transmission.crank_radius_mm=[5, 10]", "design.free.transmission.crank_radius_mm",
     "no radius of the bounds carries the stroke"),
    ("design.free.transmission.crank_radius_mm=20", "design.free.transmission.crank_radius_mm",
     "needs bounds [lower, upper]"),
])
def test_bad_crank_fields_name_the_field(override, field, words):
    with pytest.raises(ProblemError) as err:
        load_problem(CRANK_FILE, [override])
    assert err.value.field == field and words in err.value.message


def test_unknown_type_lists_the_registered_ones():
    with pytest.raises(ProblemError) as err:
        load_problem(CRANK_FILE, ['transmission.type="cam"'])
    assert err.value.field == "transmission.type"
    assert all(name in err.value.message for name in TRANSMISSIONS)


def test_a_free_radius_is_the_same_crank_as_a_stated_one():
    """The NLP's crank (its radius a CasADi symbol, ``with_free``) gives the motor motion of a crank built with
    that radius; its reach rows are >= 0 exactly where the reader's range check accepts the radius."""
    import casadi as ca

    tr = CrankSlider(0.020, 0.08, 0.43e-4, dead_centre=-3e-4, sense=1.0)
    r = ca.MX.sym("r")
    free = tr.with_free({"crank_radius_mm": r})
    x, v, a = np.array([0.0, 0.012, 0.034]), np.array([0.5, -1.5, 2.0]), np.array([40.0, -300.0, 120.0])
    symbolic = ca.Function("kin", [r], list(free.motor_kinematics(*(ca.MX(ca.DM(y)) for y in (x, v, a)))))
    rows = ca.Function("reach", [r], [ca.vertcat(*free.reach_rows(0.0, 0.035))])
    for radius in (17.0, 17.6, 18.0, 20.0, 26.0):
        stated = CrankSlider(radius * 1e-3, 0.08, 0.43e-4, dead_centre=-3e-4, sense=1.0)
        ok = stated.range_error(0.0, 0.035) is None
        assert (float(np.min(rows(radius).full())) >= 0) == ok, radius
        if ok:
            for got, want in zip(symbolic(radius), stated.motor_kinematics(x, v, a)):
                assert np.ravel(got.full()) == pytest.approx(np.ravel(want), rel=1e-12)
    assert free.inertia == tr.inertia and tr.r == 0.020          # the stated crank is left as it was


def test_a_belt_has_no_transmission_field_to_free():
    with pytest.raises(ProblemError) as err:
        load_problem(PROBLEMS / "deco2000_needle_bar.toml", ["design.free.transmission.crank_radius_mm=[18, 30]"])
    assert err.value.field == "design.free.transmission.crank_radius_mm"
    assert "design] pulley" in err.value.message


@pytest.mark.slow
def test_design_through_the_crank_holds_the_torque_of_the_textbook_crank():
    """The reference stroke designed through the crank (motor fixed), its crank radius chosen with it: its peak
    torque, re-derived here from the stroke with the textbook transfer functions at the radius found (not the
    transmission's AD), is the design's checked peak; the radius found lies inside its bounds, the design's
    problem carries it, and it beats the least radius the bar's travel allows; the crank's varying ratio
    costs torque against the belt's 0.8596 N m (docs/sources.md)."""
    from strokeopt import solve_design
    from strokeopt.drive.load import G

    problem = load_problem(CRANK_FILE, ['design.motor_choice="fixed"'])
    design = solve_design(problem)
    assert design.status == "optimal" and design.motor == "055U2B30"
    (row,) = design.free_parameters
    assert row["parameter"] == "transmission.crank_radius_mm" and row["at_bound"] is None
    assert 18.0 < row["value"] < 30.0
    assert design.problem.transmission.r == pytest.approx(row["value"] * 1e-3, rel=1e-12)
    assert problem.transmission.r == 0.020                        # the file's, the solve's start
    least = solve_design(load_problem(CRANK_FILE, ['design.motor_choice="fixed"',
                                                   "design.free.transmission.crank_radius_mm=[18, 18]"]))
    assert design.objective_value < least.objective_value * 0.95   # the least radius costs >= 5 % more torque
    k = design.stroke.sample(20001)
    tr, load = design.problem.transmission, problem.drive.load
    phi = tr.motor_angle(k.s)
    _, mu, nu = _textbook(tr.r, tr.l, phi)
    omega = k.v / mu
    eps = (k.a - nu * omega**2) / mu
    spring = sum(np.asarray(f(k.s), dtype=float) for f in load.forces)
    j = design.motor_spec.rotor_inertia + tr.inertia
    torque = j * eps + mu * (load.moving_mass * (k.a + G) - spring)
    peak = next(c["value"] for c in design.checks if c["name"] == "peak_torque")
    assert np.abs(torque).max() == pytest.approx(peak, rel=2e-3)
    assert 1.0 < peak < 3.6                       # above the belt's optimum, within the drive's 3.6 N m
    speed = next(c["value"] for c in design.checks if c["name"] == "peak_speed")
    assert np.abs(omega).max() * 60 / (2 * math.pi) == pytest.approx(speed, rel=2e-3)


@pytest.mark.slow
def test_belt_or_crank_is_one_compare(reference_written, tmp_path, capsys):
    """`strokeopt solve` writes the crank design with its verdict, its handover accuracy from the full simulation of
    the rigid drive (servo/varying.py) and its report; `strokeopt compare` sets it beside the reference's belt
    design."""
    import json

    from strokeopt.cli.main import main

    out = tmp_path / "crank"
    assert main(["solve", str(CRANK_FILE), "--set", 'design.motor_choice="fixed"', "--out", str(out),
                 "--plot", "none", "--json"]) == 0
    summary = json.loads(capsys.readouterr().out)
    assert summary["drive"]["transmission"] == "crank_slider" and summary["drive"]["pulley_teeth"] is None
    assert "transmission.crank_radius_mm = " in summary["drive"]["from"]           # the radius it chose, named
    # the handover checked by the full simulation of the rigid drive (no design term), and the page written
    row = next(c for c in summary["checks"] if c["name"].startswith("handover accuracy"))
    assert row["design_term"] is None and row["ok"] and 0 < row["value"] < 0.05
    assert "handover accuracy (full servo simulation)" in (out / "report.html").read_text(encoding="utf-8")
    assert "handover error" in summary["verdict"].split("met:")[-1]
    html = tmp_path / "belt_or_crank.html"
    assert main(["compare", str(reference_written.design_json), str(out / "design.json"), "--out", str(html),
                 "--json"]) == 0
    assert json.loads(capsys.readouterr().out)["status"] == "ok"
    text = html.read_text(encoding="utf-8")
    assert "crank and connecting rod" in text and "24-tooth pulley" in text
    assert re.search(r"crank radius (19|2\d)\.\d+ mm, connecting rod length 80\.00 mm", text)   # the radius it chose
    assert f"{summary['objective_value']:.4g}" in text and "0.8596" in text      # both peaks side by side
    assert summary["objective_value"] > 0.8596
