"""`strokeopt bench`: the registry and the catalogue-sizing benchmark (structure and agreement, no timing goals)."""

from __future__ import annotations

import json

import numpy as np
import pytest

from strokeopt.bench import registry as bench
from strokeopt.bench.sizing import size_pairs_loop
from strokeopt.bench.run import run_benchmarks  # noqa: F401  (registers every benchmark)
from strokeopt.cli.main import main


def test_registry_and_duplicate_names():
    assert "size_catalogue" in bench.REGISTRY
    with pytest.raises(ValueError):
        bench.benchmark("size_catalogue", "again")(lambda: None)


def test_loop_reference_agrees_with_the_vectorised_sizing(reference):
    from strokeopt.drive.sizing import candidates

    spec = reference.drive
    cat = spec.catalogue()
    motors, pulleys = list(cat.motors.values())[:2], cat.pulleys_of("GT3")[:2]
    stroke = reference.stroke(600)
    kin = stroke.sample(301)
    belt = spec.belt_spec(cat)
    loop = size_pairs_loop(kin, motors, pulleys, spec.load, spec.limits, belt, 600, stroke.period)
    vec = candidates(kin, motors, pulleys, spec.load, spec.limits, belt, 600, stroke.period)
    assert len(loop) == len(vec) == 4
    for checks, cand in zip(loop, vec):
        assert [c.name for c in checks] == [c.name for c in cand.checks]
        assert np.array([c.value for c in checks]) == pytest.approx([c.value for c in cand.checks], rel=1e-12)


def test_bench_command_json(capsys):
    assert main(["bench", "--json", "--only", "size_catalogue"]) == 0
    data = json.loads(capsys.readouterr().out)
    (r,) = data["benchmarks"]
    assert r["name"] == "size_catalogue" and r["target_s"] == 0.5
    assert len(r["rows"]) == 4 and all(row["seconds"] > 0 for row in r["rows"])
    assert r["measured_s"] == r["rows"][0]["seconds"] and r["ratio"] > 0
    assert isinstance(r["meets_target"], bool)


def test_bench_text_and_unknown_name(capsys):
    results = [bench.BenchResult([bench.BenchRow("x", 0.01)], 0.01, 3.0, "y / x", name="demo", description="d",
                                 target_s=0.5)]
    text = bench.format_results(results)
    assert "ratio y / x: 3.0x" in text and "target: under 0.5 s" in text and "met" in text
    assert main(["bench", "--only", "nope"]) == 2
    assert "unknown benchmark 'nope'" in capsys.readouterr().err


def test_solve_parts_names_functions_that_exist_and_counts_own_time():
    # every part of the timed reference solve wraps a function that is there (none would be reported missing),
    # and a part called inside another counts in the inner one only
    import importlib
    import time

    from strokeopt.bench.solve_parts import PARTS, _Clock

    for _, targets in PARTS:
        for module, name in targets:
            owner = importlib.import_module(module)
            for part in name.split("."):
                owner = getattr(owner, part)
            assert callable(owner), (module, name)
    clock = _Clock()
    inner = clock.timed("inner", lambda: time.sleep(0.02))
    outer = clock.timed("outer", lambda: (time.sleep(0.01), inner()))
    outer()
    assert clock.calls == {"inner": 1, "outer": 1}
    assert 0.02 <= clock.own["inner"] < 0.2 and 0.01 <= clock.own["outer"] < 0.02 + 0.1


@pytest.mark.slow  # two crank accuracies, one with CVODES (about 10 s)
def test_the_varying_ratio_servo_s_rk4_agrees_with_cvodes():
    """servo/varying.py's RK4 steps against CVODES at rtol 1e-10 on the crank drive: the handover errors within 0.5 %
    (the bench prints both; its time ratio is the bench's, not a test's)."""
    import re

    from strokeopt.bench import servo  # noqa: F401  (registers it)

    result = bench.REGISTRY["servo_varying"].fn()
    errors = [float(re.search(r"handover error ([0-9.]+) mm", r.note)[1]) for r in result.rows]
    assert len(errors) == 2 and errors[0] == pytest.approx(errors[1], rel=5e-3) and 0 < errors[0] < 0.05
