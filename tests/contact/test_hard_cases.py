"""The hard cases of the contact model, each at the default tolerance and at rtol 1e-8 (issue 39).

Two properties at every tolerance:

* **Honest peaks.** Every peak force marked converged is within 1 % of the same scene at rtol 1e-10 (the
  reference, its peaks located but not estimated: ``SimulationOptions(estimate=False)``; for the 1200 spm handover,
  rtol 1e-8); a peak that is not within 1 % is marked not converged.
  At rtol 1e-8 every peak converges (the estimate does not hide behind "not converged").
* **Bounded runs.** A scene ends within its step budget, or is refused naming its stiffest contact: the
  budget grows at most 4x from the default to a tight tolerance, and one output interval may take at most a
  tenth of the steps left, so a scene too stiff for it stops at rtol 1e-8 about as soon as at the default
  (``strokeopt bench --only simulate_stiff_refusal`` times both).

The events (impact, release, lag, the smallest gap N) agree between the two tolerances.
"""

from __future__ import annotations

import json
import re

import numpy as np
import pytest

from strokeopt import ProblemError, SimulationOptions, SolverError, load_problem, simulate_scene
from strokeopt.contact.stepper import CHUNK_SHARE
from strokeopt.report.format import to_json

REFERENCE_FILE = "deco2000_needle_bar.toml"
KNITTING_FILE = "knitting_stitch_density.toml"
DEFAULT = SimulationOptions()
TIGHT = SimulationOptions(rtol=1e-8, atol=1e-9)
REFERENCE = SimulationOptions(rtol=1e-10, atol=1e-11, estimate=False)  # the reference: its peaks located, not estimated
CONTACTS = ("c21", "c32", "c13", "c31", "c14", "c45", "c56", "c35")

# name, file, scene, spm (None: the file's), overrides, reference options (None: TIGHT is the reference)
SOLVED = [
    # issue 39: c32 13 388 N at the default tolerance, "converged", where rtol 1e-8 and 1e-10 give 14 043 N
    ("release 1200 spm", REFERENCE_FILE, "release", 1200, [], REFERENCE),
    ("1e9 N/m on the 0.2 g needle, zero gap c45 at the start", REFERENCE_FILE, "handover", 600, [], REFERENCE),
    ("handover 1200 spm, whole bar", REFERENCE_FILE, "handover", 1200, [], None),
    # gap N 9 mm with it: the chain shell -> cage -> control -> pad reaches 32 mm, the stroke's travel (with
    # gap N 7.4 mm it would end 1.6 mm deep in the pad, refused on read: contact/travel.py)
    ("zero gap P: cage held on both sides", REFERENCE_FILE, "release", 600,
     ["model.contacts.c13.gap_mm=0.0", "model.contacts.c32.gap_mm=9.0"], REFERENCE),
    # the stiffest pad: the 65 ShA law x1000 (about the metal contacts' 1e9 N/m at 1 mm), a hard stop
    ("stiffest pad law", REFERENCE_FILE, "release", 600,
     ["model.force_laws.pad_65ShA.coefficients_SI=[0.0, 4.4517e8, 0.0, 1.5739e15]"], REFERENCE),
    ("very soft pad", REFERENCE_FILE, "release", 600, ["model.force_laws.pad_65ShA.coefficients_SI=[0.0, 2e4]"],
     REFERENCE),
    ("knitting chain, clearances 1e-3 mm", KNITTING_FILE, "step", None,
     ["model.links.c2.clearance_mm=0.001", "model.links.c4.clearance_rad=1e-6"], REFERENCE),
]

REFUSED = [
    # every contact x1000 (1e12 N/m): the needle's contact period is below what the budget can resolve, refused
    # before integrating at 500 spm; at 1200 spm (a shorter cycle) it passes that check and the budget stops it
    ("contacts x1000", "handover", None, [f"model.contacts.{c}.stiffness_N_m=1e12" for c in CONTACTS]),
    ("contacts x1000, 1200 spm", "handover", 1200, [f"model.contacts.{c}.stiffness_N_m=1e12" for c in CONTACTS]),
    ("contacts x100", "handover", 600, [f"model.contacts.{c}.stiffness_N_m=1e11" for c in CONTACTS]),
]

def _peaks(r):
    m = r.metrics
    values = {**m["peak_contact_forces_N"], "drive": m["peak_drive_force_N"]}
    errors = {**(m["peak_contact_force_errors_pct"] or {}), "drive": m["peak_drive_force_error_pct"]}  # None: not estimated
    return values, errors, {k: k not in m["unconverged_peaks"] for k in values}


@pytest.mark.slow  # rtol 1e-10: 3-30 s each
@pytest.mark.parametrize("case", SOLVED, ids=[c[0] for c in SOLVED])
def test_hard_case_peaks_honest_events_agree_steps_bounded(reference_path, case):
    name, file, scene, spm, overrides, reference_options = case
    p = load_problem(reference_path.parent / file, overrides)
    runs = {o.rtol: simulate_scene(p, scene, spm, options=o) for o in (DEFAULT, TIGHT, reference_options) if o}
    reference = runs[(reference_options or TIGHT).rtol]
    ref, _, _ = _peaks(reference)
    if reference_options is None:  # rtol 1e-8 as the reference: its own estimates hold it
        assert reference.metrics["peak_forces_converged"] is True
    print(f"\n{name}: peak forces [N] against the reference, estimate and error [%]")
    for options in (DEFAULT, TIGHT) if reference_options else (DEFAULT,):
        values, errors, converged = _peaks(runs[options.rtol])
        for key, value in ref.items():
            error = abs(values[key] - value) / value * 100 if value > 1e-6 else 0.0
            print(f"  rtol {options.rtol:g} {key:6s} {values[key]:10.1f} {value:10.1f}  estimate {errors[key]:.3f} "
                  f"error {error:.3f} {'converged' if converged[key] else 'NOT converged'}")
            if converged[key]:
                assert error <= 1.0, (options.rtol, key)
        if options is TIGHT:
            assert all(converged.values()), "at rtol 1e-8 every peak converges"
    # bounded, finite, and the events agree between the default tolerance and rtol 1e-8
    a, b = runs[DEFAULT.rtol], runs[TIGHT.rtol]
    for r, options in ((a, DEFAULT), (b, TIGHT)):
        assert all(np.all(np.isfinite(x)) for x in r.positions.values())
        assert r.stats["nsteps"] < 0.25 * p.scenes[scene].step_budget(options.rtol)  # no step-size collapse
        json.loads(to_json(r.summary()))  # nothing NaN reaches the report
    if scene == "step":  # the knitting scene has no needle events
        return
    ma, mb = a.metrics, b.metrics
    for key in ("impact_angle_deg", "release_angle_deg", "lag_end_angle_deg"):
        # a premature release is where the lag grazes gap N shut (its smallest value -2 um at 1200 spm): a
        # shallow crossing whose angle the default tolerance places 0.34 deg late (35.96 against 35.62 deg at
        # rtol 1e-6 to 1e-10)
        tol = 0.5 if key == "release_angle_deg" and ma["premature_release"] else 0.1
        if ma[key] is None or mb[key] is None:
            assert ma[key] is None and mb[key] is None, key
        else:
            assert abs(ma[key] - mb[key]) < tol, key
    assert ma["impact_velocity_m_s"] == pytest.approx(mb["impact_velocity_m_s"], abs=5e-3)
    assert ma["min_gap_N_mm"] == pytest.approx(mb["min_gap_N_mm"], abs=0.01)
    assert ma["premature_release"] == mb["premature_release"]


def test_the_1200_spm_release_peak_of_c32(reference_path):
    # issue 39: rtol 1e-8 and 1e-10 give c32 14 043 N; the default tolerance reported 13 388 N as converged (its
    # spike astride an output point was bounded below its crest, and its estimate started from the state at the
    # interval, after the chain's earlier impacts)
    m = simulate_scene(load_problem(reference_path), "release", 1200).metrics
    c32 = m["peak_contact_forces_N"]["c32"]
    assert "c32" not in m["unconverged_peaks"]
    assert c32 == pytest.approx(14043, rel=0.01)
    # and its estimate says how far it is: 0.5 % low, estimated at 0.49 %
    assert abs(c32 / 14043 - 1) * 100 <= m["peak_contact_force_errors_pct"]["c32"] + 0.1


@pytest.mark.slow  # runs to the budget: 2-20 s each
@pytest.mark.parametrize("options", [DEFAULT, TIGHT], ids=["default", "rtol 1e-8"])
@pytest.mark.parametrize("case", REFUSED, ids=[c[0] for c in REFUSED])
def test_a_scene_too_stiff_for_its_budget_is_refused_at_any_tolerance(reference_path, case, options):
    name, scene, spm, overrides = case
    p = load_problem(reference_path, overrides)
    budget = p.scenes[scene].step_budget(options.rtol)
    with pytest.raises((ProblemError, SolverError)) as info:
        simulate_scene(p, scene, spm, options=options)
    text = str(info.value)
    assert re.search(r"stiffest contact c(35|45)|model\.contacts\.c(35|45)\.stiffness_N_m", text), text
    assert f"raise scenes.{scene}.max_steps" in text
    steps = re.search(r"stopped after ([\d,]+) integrator steps \(its budget: ([\d,]+)", text)
    if steps:  # refused while integrating: within its budget and a share of it (the last call's)
        used, stated = (int(g.replace(",", "")) for g in steps.groups())
        assert stated == budget
        assert used <= (1 + CHUNK_SHARE) * budget
    else:  # refused before integrating: the contact's period against the budget's mean step
        assert isinstance(info.value, ProblemError) and f"budget of {budget:,} steps" in text
