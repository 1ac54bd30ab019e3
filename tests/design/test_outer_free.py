"""``[design.free.NAME]`` beyond a spring's stiffness (issue 38): ``field``/``range`` and ``moves``/``range_mm`` (a
coupled move: the impact point), read and checked with the file, searched around the verified solve
(studies/outer.py)."""

from __future__ import annotations

from dataclasses import dataclass, replace

import pytest

from strokeopt import ProblemError, SolverError, load_problem, solve_design, solve_verified
from strokeopt.design.transcription.settings import OuterFree
from strokeopt.studies.outer import solve_outer

IMPACT_POINT = """
[design.free.impact_point]
moves = { "model.contacts.c32.gap_mm" = -1.0, "model.contacts.pad.gap_mm" = 1.0 }
range_mm = [0, 5]
"""


def _file(tmp_path, reference_path, text, base="deco2000_contact_design.toml"):
    path = tmp_path / "p.toml"
    path.write_text(f'extends = "{(reference_path.parent / base).as_posix()}"\n' + text)
    return path


def test_the_forms_are_read(tmp_path, reference_path):
    p = load_problem(_file(tmp_path, reference_path, IMPACT_POINT))
    assert p.design.free == (("k2", 900.0, 3000.0),)  # the file's spring: a variable of the collocation
    (o,) = p.design.outer
    assert o == OuterFree("impact_point", (("model.contacts.c32.gap_mm", -1.0), ("model.contacts.pad.gap_mm", 1.0)),
                          0.0, 5.0)
    assert o.overrides(2.0, {"model.contacts.c32.gap_mm": 7.4, "model.contacts.pad.gap_mm": 23.0}) == [
        "model.contacts.c32.gap_mm=5.4", "model.contacts.pad.gap_mm=25.0"]
    # a field of its own; a stiffness named by its field is the short form (the collocation carries it)
    p = load_problem(_file(tmp_path, reference_path, '[design.free.mass]\nfield = "model.bodies.control.mass_g"\n'
                                                     'range = [35, 45]\n[design.free.k3]\nfield = '
                                                     '"model.springs.k3.stiffness_N_m"\nrange = [500, 900]\n'))
    assert p.design.outer == (OuterFree("mass", (("model.bodies.control.mass_g", 1.0),), 35.0, 45.0, absolute=True),)
    assert ("k3", 500.0, 900.0) in p.design.free
    assert p.design.outer[0].overrides(40.0, {}) == ["model.bodies.control.mass_g=40.0"]


@pytest.mark.parametrize("text, field, words", [
    ('[design.free.x]\nmoves = { "model.contacts.c99.gap_mm" = 1.0 }\nrange_mm = [0, 1]\n', "design.free.x.moves",
     "model.contacts.c99.gap_mm: no such field"),
    ('[design.free.x]\nmoves = { "model.contacts.c32.gap_mm" = 0.0 }\nrange_mm = [0, 1]\n', "design.free.x.moves",
     "each coefficient a non-zero number"),
    ('[design.free.x]\nmoves = { "model.contacts.c32.gap_mm" = -1.0 }\nrange_mm = [2, 1]\n', "design.free.x.range_mm",
     "must be finite with lower < upper"),
    ('[design.free.x]\nfield = "model.contacts.c32.gap_mm"\n', "design.free.x.range", "is required but missing"),
    ('[design.free.x]\nfield = "problem.name"\nrange = [0, 1]\n', "design.free.x.field", "not a number"),
    ('[design.free.x]\nfield = "model.contacts.c32.gap_mm"\nrange = [0, 1]\nstiffness_N_m = [1, 2]\n',
     "design.free.x", "needs one of"),
    ('[design.free.x]\nfield = "model.contacts.c32.gap_mm"\nrange = [5, 7]\n[design.free.y]\n'
     'field = "model.contacts.c13.gap_mm"\nrange = [3, 4]\n', "design.free.y", "this file has 2: x, y"),
])
def test_a_bad_entry_is_refused_naming_its_field(tmp_path, reference_path, text, field, words):
    with pytest.raises(ProblemError) as info:
        load_problem(_file(tmp_path, reference_path, text))
    assert info.value.field == field and words in info.value.message, str(info.value)


def test_only_the_verified_solve_searches_it(tmp_path, reference_path):
    p = load_problem(_file(tmp_path, reference_path, IMPACT_POINT))
    with pytest.raises(ProblemError, match="design.free.impact_point: is searched around the verified solve"):
        solve_design(p)
    # a range whose end the problem refuses (gap N below zero) is said before any solve
    bad = _file(tmp_path, reference_path, IMPACT_POINT.replace("range_mm = [0, 5]", "range_mm = [0, 9]"))
    with pytest.raises(ProblemError, match=r"design.free.impact_point.range_mm: at 9 \(model.contacts.c32.gap_mm = "
                                           r"-1.6, model.contacts.pad.gap_mm = 32\) the problem refuses "
                                           r"model.contacts.c32.gap_mm: -1.59+6 is outside the plausible range"):
        solve_verified(load_problem(bad))


@dataclass(frozen=True)
class _Design:  # what solve_outer reads of a design
    objective_value: float
    d: float
    objective: str = "min_impact_velocity"
    objective_unit: str = "m/s"
    free_parameters: tuple = ()
    notes: tuple = ()


@dataclass(frozen=True)
class _Verified:
    design: _Design
    ok: bool
    verdict: str


def _fake(problem, outer, f, fails=lambda d: False):
    """solve_outer on the problem with a solve whose objective is ``f(d)`` (``fails(d)``: the design fails)."""
    calls = []

    def solve(point, inner, warm):
        d = float(next(o.split("=")[1] for o in point.overrides if o.startswith("model.contacts.pad.gap_mm"))) - 23.0
        calls.append((d, warm is not None))
        assert inner.outer == ()
        return _Verified(_Design(f(d), d), not fails(d), f"fails at {d:g}")

    settings = replace(problem.design, outer=(outer,))
    return solve_outer(problem, settings, solve), calls


def test_the_search_finds_the_best_point_and_says_what_binds_it(tmp_path, reference_path):
    p = load_problem(_file(tmp_path, reference_path, IMPACT_POINT))
    o = p.design.outer[0]
    found, calls = _fake(p, o, lambda d: (d - 2.3) ** 2 + 0.5)
    assert found.design.d == pytest.approx(2.3, abs=0.05)
    row = found.design.free_parameters[-1]
    assert row["value"] == pytest.approx(found.design.d, abs=1e-9) and row["at_bound"] is None and (row["lower"], row["upper"]) == (0, 5)
    assert "the points tried beside it are worse" in found.design.notes[-1]
    assert "scan, min_impact_velocity m/s: 0: 5.79, 1: 2.19" in found.design.notes[-1]
    assert not any(warm for _, warm in calls)  # each point is the solve a user gets for it (no start carried over)
    assert "(model.contacts.c32.gap_mm = 5.095, model.contacts.pad.gap_mm = 25.3)" in found.design.notes[-1]
    # decreasing towards a premature release beyond 3.2 mm: the search closes in on it and names the failure
    found, _ = _fake(p, o, lambda d: 1.0 - 0.1 * d, fails=lambda d: d > 3.2)
    assert 3.1 < found.design.d <= 3.2
    assert "fails (fails at" in found.design.notes[-1]
    # best at a bound
    found, _ = _fake(p, o, lambda d: 1.0 - 0.1 * d)
    assert found.design.d == pytest.approx(5.0) and "the range's upper bound" in found.design.notes[-1]
    # nothing passes
    with pytest.raises(SolverError, match="no value of design.free.impact_point in \\[0, 5\\] gives a design that "
                                          "passes"):
        _fake(p, o, lambda d: 1.0, fails=lambda d: True)


@pytest.mark.slow  # 14 verified points: half a minute
def test_the_impact_point_chosen_with_the_spring(reference_path):
    verified = solve_verified(load_problem(reference_path.parent / "deco2000_impact_point.toml"), compare=False)
    design = verified.design
    rows = {r["parameter"].split(" ")[0]: r for r in design.free_parameters}
    assert set(rows) == {"model.springs.k2.stiffness_N_m", "design.free.impact_point"}  # both variables
    shift = rows["design.free.impact_point"]["value"]
    assert 0 <= shift <= 5
    # the design's problem is the file's with the shift: gap N smaller, the pad's gap larger by it
    sets = dict(o.split("=", 1) for o in design.problem.overrides)
    assert float(sets["model.contacts.c32.gap_mm"]) == pytest.approx(7.4 - shift)
    assert float(sets["model.contacts.pad.gap_mm"]) == pytest.approx(23.0 + shift)
    # the full simulation confirms the optimum: the impact velocity within 2 % of the design's
    simulated = verified.scenes["release"].metrics["impact_velocity_m_s"]
    assert design.objective_value == pytest.approx(simulated, rel=0.02)
    # gentler than at the file's impact point with the same objective (0.78 m/s) and than the modified sine (2.85)
    assert design.objective_value < 0.7
    assert verified.ok and verified.verification["status"] == "ok"
    assert "what binds it:" in design.notes[-1]
