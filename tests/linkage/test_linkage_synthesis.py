"""Linkage synthesis (strokeopt.linkage.synthesis): the loom's six-bar from no given geometry against Tab. 1
(digest C) and the blind-stitch linkage in the paper's layout against its speed table (digest D)."""

from __future__ import annotations

import math
import time

import numpy as np
import pytest

from strokeopt.linkage.kinematics import Kinematics, kinematics_of
from strokeopt.linkage.files import load_linkage_file
from strokeopt.linkage.synthesis import synthesize

from conftest import ROOT

BLIND = ROOT / "problems" / "blind_stitch_needle.toml"
LOOM = ROOT / "problems" / "loom_beatup_sixbar.toml"

# The loom file's synthesised joints replaced by arbitrary ones: the synthesis must not need them.
SCRAMBLE = [f"transmission.joints[{i}].{c}_mm={v}" for i, (x, y) in
            {3: (-50, 40), 4: (120, 10), 5: (80, 90), 6: (150, 100), 7: (200, -30), 8: (100, 250)}.items()
            for c, v in (("x", x), ("y", y))]
# Tab. 1 (digest C): tangential acceleration a_D at the 13 angles, held only to RMS 6 m/s^2 (the table
# contradicts its own speeds near beat-up by a factor of about 2)
A_D = [17.2, 14.5, 3.5, -3.8, -8.4, -6.7, -4.2, -6.3, -3.7, 0.8, 6.0, 13.8, 17.5]


@pytest.fixture(scope="module")
def loom_synthesis():
    problem = load_linkage_file(LOOM, SCRAMBLE, check_cycle=False)
    t0 = time.perf_counter()
    result = synthesize(problem)
    return problem, result, time.perf_counter() - t0


@pytest.mark.slow
def test_loom_synthesis_acceptance(loom_synthesis):
    # issue 24 / digest C: crank radii 18 and 12 mm, full rotation, sley swing 19.5 +- 0.3 deg, RMS <= 0.05 m/s
    # against the 13 v_D of Tab. 1, the front extreme (v_D = 0) at 355 +- 10 deg, under 60 s
    problem, result, seconds = loom_synthesis
    assert seconds < 60
    lk = problem.linkage.with_reference(result.best.coords)
    assert lk.length("A0", "C") * 1e3 == pytest.approx(18.0, abs=1e-6)
    assert lk.length("A0", "B") * 1e3 == pytest.approx(12.0, abs=1e-6)
    kin = kinematics_of(lk)
    cycle = kin.solve(720)          # refuses a geometry that does not turn fully or passes a dead centre
    assert cycle.index.min() >= problem.min_transmission_index
    sley = kin.output(cycle, "sley_angle")[0]
    assert math.degrees(sley.max() - sley.min()) == pytest.approx(19.5, abs=0.3)
    front = math.degrees(cycle.theta[int(np.argmin(sley))]) % 360
    assert min(abs(front - 355), abs(front + 5)) <= 10
    # the fit by the exact analysis (not the NLP's nodes): v_D at Tab. 1's angles
    v = kin.output(cycle, "sley_D")[1]
    k = [int(round(a * 2)) % 720 for a in problem.synthesis["angles_deg"]]
    rms = math.sqrt(np.mean((v[k] * problem.omega - np.array(problem.synthesis["speeds_m_s"])) ** 2))
    assert rms <= 0.05
    assert rms == pytest.approx(result.best.rms, abs=1e-9)
    a = kin.output(cycle, "sley_D")[2][k] * problem.omega ** 2
    assert math.sqrt(np.mean((a - np.array(A_D)) ** 2)) <= 6.0


@pytest.mark.slow
def test_loom_synthesis_reports_runners_up(loom_synthesis):
    # digest C: the tables do not determine a unique linkage (two six-bars were found there; here the
    # distinct runners-up that meet the same acceptance)
    problem, result, _ = loom_synthesis
    report = result.to_dict(Kinematics(problem.linkage))
    assert report["runners_up"] and not report["unique"] and "do not determine a unique linkage" in report["note"]
    assert all(r["rms_m_s"] <= 0.05 for r in report["runners_up"])


@pytest.mark.slow
def test_loom_file_is_the_synthesis_result(loom_synthesis):
    # the loom file's geometry is that synthesis's best solution (rounded to 1e-4 mm in the file), made by an
    # earlier run with the same seed from other starting coordinates: the synthesis is reproducible
    problem, result, _ = loom_synthesis
    filed = load_linkage_file(LOOM).linkage.reference()
    assert np.abs(filed - result.best.coords).max() <= 1e-7


@pytest.mark.slow
def test_blind_stitch_synthesis_in_the_papers_layout():
    # issue 24 / digest D: Watt chain, phi42 = phi41 + 135 deg, phi61 = phi6 + 225 deg, 2500 rpm
    # (261.80 rad/s): RMS <= 0.06 m/s against the 15 signed needle speeds
    problem = load_linkage_file(BLIND, check_cycle=False)
    assert problem.omega == pytest.approx(261.80, abs=0.005)
    result = synthesize(problem)
    lk = problem.linkage.with_reference(result.best.coords)
    xy = {j.name: j.xy for j in lk.joints}

    def angle(a, b, c, d):
        u, w = xy[b] - xy[a], xy[d] - xy[c]
        return math.degrees(math.atan2(u[0] * w[1] - u[1] * w[0], u @ w)) % 360

    # held as equality constraints, to IPOPT's tolerance (1e-9 on cross(u, w) in m^2: about 1e-5 deg here)
    assert angle("B", "O4", "O4", "C") == pytest.approx(135.0, abs=1e-4)
    assert angle("D", "O6", "O6", "I") == pytest.approx(225.0, abs=1e-4)
    kin = kinematics_of(lk)
    cycle = kin.solve(720)
    v = kin.output(cycle, "needle")[1]
    k = [int(round(a * 2)) % 720 for a in problem.synthesis["angles_deg"]]
    rms = math.sqrt(np.mean((v[k] * problem.omega - np.array(problem.synthesis["speeds_m_s"])) ** 2))
    assert rms <= 0.06
    assert rms == pytest.approx(result.best.rms, abs=1e-9)
