"""Peak contact and drive forces located between the output points (contact/peaks.py), their error
estimates, and the time budget of a scene (contact/scene.py max_steps, contact/simulate.py).

The stiff contacts (1e9 N/m on a few grams) act for microseconds, between the output points: read off the
grid, the peak force of c32 in the release scene was 17 N at the default tolerance and 694 N at rtol 1e-8
(issue 22), while the spike is 2301 N at both.
"""

from __future__ import annotations

import time

import pytest

from strokeopt import ProblemError, SimulationOptions, SolverError, load_problem, simulate_scene
from strokeopt.cli.main import main

REFERENCE = SimulationOptions(rtol=1e-10, atol=1e-11, estimate=False)  # the reference (atol = rtol / 10), not estimated

# Brute force: the release scene at 500 spm integrated at rtol 1e-10, atol 1e-11 on 200 000 output points per
# stroke piece (0.07-0.6 us apart), each peak the vertex of the parabola through its largest sample (N).
BRUTE_FORCE_RELEASE_500 = {"pad": 480.6, "c21": 4682.5, "c32": 2301.5, "c31": 1518.9, "drive": 4683.9}


def _peaks(result) -> dict:
    m = result.metrics
    return {**m["peak_contact_forces_N"], "drive": m["peak_drive_force_N"]}


def _show(name, loose, tight):
    print(f"\n{name}: peak forces [N] at the default tolerance / at rtol 1e-10")
    for key, value in tight.items():
        print(f"  {key:6s} {loose[key]:10.1f} {value:10.1f}  ({100 * (loose[key] / value - 1) if value else 0:+.2f} %)")


def _within(loose, tight, share=0.01):
    return {k: (loose[k], v) for k, v in tight.items() if abs(loose[k] - v) > share * max(v, 1.0)}


@pytest.fixture(scope="module")
def problem(reference_path):
    return load_problem(reference_path)


@pytest.fixture(scope="module")
def release_default(problem):
    return simulate_scene(problem, "release", 500)


@pytest.fixture(scope="module")
def release_500(problem, release_default):
    """The release scene at the default tolerance and at rtol 1e-10 (the reference: its peaks located, not estimated)."""
    return release_default, simulate_scene(problem, "release", 500, options=REFERENCE)


@pytest.mark.slow  # the rtol 1e-10 reference
def test_release_peaks_at_the_default_tolerance_within_1_pct_of_1e_10(release_500):
    loose, tight = release_500
    a, b = _peaks(loose), _peaks(tight)
    _show("release, 500 spm", a, b)
    assert not _within(a, b)
    # the spikes were found: c32 is no longer the 17 N a grid point happened to catch
    assert b["c32"] > 2000 and a["c32"] > 2000


@pytest.mark.slow  # the rtol 1e-10 reference
def test_release_peaks_match_the_brute_force(release_500):
    for r in release_500:
        peaks = _peaks(r)
        for key, value in BRUTE_FORCE_RELEASE_500.items():
            assert peaks[key] == pytest.approx(value, rel=0.01), key


def test_peaks_are_at_least_the_grid_maxima_and_say_where(release_default):
    import numpy as np

    r = release_default
    m = r.metrics
    for e, f in r.forces.items():
        assert m["peak_contact_forces_N"][e] >= float(np.max(np.abs(f))) - 1e-9
        assert 0 <= m["peak_contact_force_angles_deg"][e] <= 360
    assert m["peak_drive_force_N"] >= float(np.max(np.abs(r.drive_force))) - 1e-9
    # the drive force peaks where the control member lands on the shell at the end of move 2 (c21)
    assert m["peak_drive_force_angle_deg"] == pytest.approx(m["peak_contact_force_angles_deg"]["c21"], abs=0.01)


@pytest.mark.slow  # the rtol 1e-10 reference
def test_each_peak_has_an_error_estimate_that_bounds_its_error(release_500):
    loose, tight = release_500
    m = loose.metrics
    assert m["peak_forces_converged"] is True and m["unconverged_peaks"] == ()
    errors = {**m["peak_contact_force_errors_pct"], "drive": m["peak_drive_force_error_pct"]}
    assert all(0 <= v <= 1 for v in errors.values())
    # the estimate is the error against rtol 1e-10, not a number that only agrees with itself: each peak's error
    # is within its estimate plus a tenth of a per cent (the reference's own)
    a, b = _peaks(loose), _peaks(tight)
    for key, value in b.items():
        assert abs(a[key] - value) <= (errors[key] + 0.1) / 100 * value + 1e-6, key


def test_a_peak_that_is_not_converged_is_named(problem):
    # rtol 1e-3: k3's peak is 6.9 % high and c31's 13 % (against rtol 1e-10: 13.334 and 1518.9 N); both estimated
    # above 1 %
    m = simulate_scene(problem, "release", 500, options=SimulationOptions(rtol=1e-3, atol=1e-4)).metrics
    assert m["peak_forces_converged"] is False
    assert {"k3", "c31"} <= set(m["unconverged_peaks"])
    assert m["peak_contact_force_errors_pct"]["k3"] > 5 and m["peak_contact_force_errors_pct"]["c31"] > 10
    assert all(m["peak_contact_force_errors_pct"].get(k, m["peak_drive_force_error_pct"]) > 1
               for k in m["unconverged_peaks"])


def test_the_json_report_says_whether_the_peaks_converged(reference_path, capsys):
    import json

    args = ["simulate", str(reference_path), "--scene", "release", "--plot", "none", "--json"]
    assert main(args) == 0
    data = json.loads(capsys.readouterr().out)
    assert data["peak_forces_converged"] is True and data["unconverged_peaks"] == []
    assert set(data["peak_contact_force_errors_pct"]) == set(data["peak_contact_forces_N"])
    assert main(args + ["--rtol", "1e-3", "--atol", "1e-4"]) == 0
    data = json.loads(capsys.readouterr().out)
    assert data["peak_forces_converged"] is False and "k3" in data["unconverged_peaks"]


# --------------------------------------------------------------------------- the time budget of a scene

STIFF = [f"model.contacts.{c}.stiffness_N_m=1e12" for c in ("c21", "c32", "c13", "c31", "c14", "c45", "c56", "c35")]


def test_contacts_too_stiff_for_the_budget_are_refused_at_once(reference_path, capsys):
    # issue 22: every contact at 1e12 N/m took 669 s in the handover scene and reported "ok" with 2.05e12 N
    p = load_problem(reference_path, STIFF)
    t0 = time.process_time()
    with pytest.raises(ProblemError, match=r"stiffness_N_m: 1e\+12 N/m on the 0.2 g needle rings with a period of "
                                           r"8.9e-08 s, shorter than scene 'handover' can resolve"):
        simulate_scene(p, "handover")
    assert time.process_time() - t0 < 1.0
    args = ["simulate", str(reference_path), "--scene", "handover", "--plot", "none"]
    for s in STIFF:
        args += ["--set", s]
    assert main(args) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "raise scenes.handover.max_steps" in err


def test_the_budget_is_a_validated_field(reference_path, problem, capsys):
    assert problem.scenes["release"].max_steps == 1_000_000
    p = load_problem(reference_path, ["scenes.release.max_steps=20000"])  # the scene takes 22 600
    with pytest.raises(SolverError, match=r"stopped after 19,\d{3} integrator steps \(its budget: 20,000, "
                                          r"scenes.release.max_steps\).*stiffest contact c13"):
        simulate_scene(p, "release", 500)
    assert main(["simulate", str(reference_path), "--scene", "release", "--plot", "none",
                 "--set", "scenes.release.max_steps=20000"]) == 1
    assert "failed: scene 'release' at 500 spm stopped" in capsys.readouterr().err
    for bad, words in (("100", "outside the plausible range"), ("12345.5", "whole number"), ('"many"', "must be a number")):
        with pytest.raises(ProblemError, match=words):
            load_problem(reference_path, [f"scenes.release.max_steps={bad}"])
    # below one step per contact period of the cage (1.3e-5 s in 0.24 s): refused before integrating
    with pytest.raises(ProblemError, match="model.contacts.c13.stiffness_N_m: .* raise scenes.release.max_steps"):
        simulate_scene(load_problem(reference_path, ["scenes.release.max_steps=10000"]), "release", 500)


def test_a_tighter_tolerance_gets_a_larger_budget(problem):
    sc = problem.scenes["release"]
    assert sc.step_budget(1e-5) == sc.step_budget(1e-3) == 1_000_000
    # (1e-5 / rtol)^(1/3), the steps BDF of order 2 takes, up to 4 times the budget (tests/contact/test_hard_cases.py:
    # a scene too stiff for it is refused at rtol 1e-8 about as soon as at the default)
    assert sc.step_budget(1e-6) == pytest.approx(2_154_434, rel=1e-6)
    assert sc.step_budget(1e-8) == sc.step_budget(1e-10) == 4_000_000
    with pytest.raises(SolverError, match=r"its budget: 20,000, the max_steps option"):
        simulate_scene(problem, "release", 500, options=SimulationOptions(max_steps=20_000))
    # restarted at every switch: the budget is checked after each stroke piece (45 891 steps by the end of the third)
    with pytest.raises(SolverError, match=r"stopped after [\d,]+ integrator steps \(its budget: 20,000, the max_steps"):
        simulate_scene(problem, "release", 500, options=SimulationOptions(max_steps=20_000, restart_at_switches=True))


def test_the_text_report_names_a_peak_that_is_not_converged(reference_path, capsys):
    args = ["simulate", str(reference_path), "--scene", "release", "--plot", "none"]
    assert main(args) == 0
    assert "peak forces converged: estimated error at most" in capsys.readouterr().out
    assert main(args + ["--rtol", "1e-3", "--atol", "1e-4"]) == 0
    assert "peak forces NOT CONVERGED: k3" in capsys.readouterr().out
