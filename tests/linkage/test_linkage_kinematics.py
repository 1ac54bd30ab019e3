"""Linkage structure and exact kinematics (strokeopt.linkage): the blind-stitch needle linkage of digest D
(and the loom's six-bar of digest C where its file is used), solved from data."""

from __future__ import annotations

import math
import re

import numpy as np
import pytest
from scipy.optimize import fsolve

from strokeopt.errors import ProblemError
from strokeopt.linkage.kinematics import kinematics_of
from strokeopt.linkage.files import load_linkage_file

from conftest import ROOT

BLIND = ROOT / "problems" / "blind_stitch_needle.toml"
LOOM = ROOT / "problems" / "loom_beatup_sixbar.toml"
FILES = [BLIND, LOOM]


@pytest.fixture(scope="module", params=FILES, ids=lambda p: p.stem)
def solved(request):
    problem = load_linkage_file(request.param)
    kin = kinematics_of(problem.linkage)
    return problem, kin, kin.solve(720)


def test_structure_both_files(solved):
    # digest C ("6 links, 7 revolute joints, mobility 3*5 - 2*7 = 1") and digest D (n = 3*5 - 2*7 = 1,
    # two loop closure equations): exact counts
    problem, kin, _ = solved
    s = kin.structure
    assert (s.mobility, s.n_links, s.n_revolute, s.n_loops) == (1, 6, 7, 2)


def test_loom_driven_chain_is_one_group():
    # digest C: "without the driver the rest is one 4-link/6-joint group (a triad), solved simultaneously"
    s = kinematics_of(load_linkage_file(LOOM).linkage).structure
    groups = [g for g in s.groups if g.kind != "placement"]
    assert len(groups) == 1
    g = groups[0]
    assert g.kind == "triad" and len(g.links) == 4 and len(set(g.joints) | set(g.attached)) == 6
    assert s.to_dict()["four_bar_loops"][0]["class"] == "double crank"   # digest C: C-B-E-F a double crank


def test_blind_stitch_is_two_dyads_in_series():
    # digest D: a crank-rocker O2-A-B-O4 in series with a rocker-rocker O4-C-D-O6 (Watt chain)
    s = kinematics_of(load_linkage_file(BLIND).linkage).structure
    assert [g.kind for g in s.groups if g.kind != "placement"] == ["dyad", "dyad"]
    loops = s.four_bars
    assert len(loops) == 2 and loops[0].kind.startswith("crank-rocker class (crank,")


def _without_joint(text: str, joint: str) -> str:
    """The file with joint ``joint`` removed: its [[transmission.joints]] entry and every mention in a link."""
    blocks = text.split("[[transmission.joints]]")
    blocks = [b for b in blocks if not re.match(rf'\s*name = "{joint}"', b)]
    text = "[[transmission.joints]]".join(blocks)
    return re.sub(rf'(joints = \[[^\]]*?)(, "{joint}"|"{joint}", )', r"\1", text)


@pytest.mark.parametrize("path, joint", [(BLIND, "D"), (LOOM, "E")])
def test_one_joint_removed_is_refused_naming_mobility_3(tmp_path, path, joint):
    # digest C/D: mobility 3*5 - 2*7 = 1; one revolute fewer gives 3*5 - 2*6 = 3
    bad = tmp_path / "bad.toml"
    bad.write_text(_without_joint(path.read_text(), joint))
    with pytest.raises(ProblemError) as err:
        load_linkage_file(bad)
    assert "mobility 3" in str(err.value) and str(bad) in str(err.value)


def test_closure_residual_and_return(solved):
    # issue 24 acceptance: residual <= 1e-9 m at 720 angles, pose after 360 deg = start within 1e-9 m
    _, _, cycle = solved
    assert len(cycle.theta) == 720
    assert cycle.residual.max() <= 1e-9
    assert cycle.return_error <= 1e-9


def _pose_at(kin, cycle, k, theta):
    """Positions solved afresh at ``theta`` from the cycle's pose k (Newton, checked residual)."""
    q, res, _, _ = kin.closure.function("step")(cycle.q[k], cycle.theta[k], theta, kin.p)
    assert float(res) <= 1e-11
    return np.asarray(q).ravel()


def test_ad_derivatives_against_central_differences(solved):
    # issue 24 acceptance: AD speeds and accelerations agree with central differences (h = 1e-4 rad)
    # within 1e-5 relative (to the cycle's peak of each quantity)
    _, kin, cycle = solved
    h = 1e-4
    peak1, peak2 = np.abs(cycle.dq).max(), np.abs(cycle.d2q).max()
    for k in range(0, 720, 9):
        qp = _pose_at(kin, cycle, k, cycle.theta[k] + h)
        qm = _pose_at(kin, cycle, k, cycle.theta[k] - h)
        fd1 = (qp - qm) / (2 * h)
        fd2 = (qp - 2 * cycle.q[k] + qm) / h ** 2
        assert np.abs(fd1 - cycle.dq[k]).max() <= 1e-5 * peak1
        assert np.abs(fd2 - cycle.d2q[k]).max() <= 1e-5 * peak2
    # the third derivative: central difference of the AD accelerations, same tolerance
    peak3 = np.abs(cycle.d3q).max()
    fd3 = (np.roll(cycle.d2q, -1, 0) - np.roll(cycle.d2q, 1, 0)) / (2 * (cycle.theta[1] - cycle.theta[0]))
    assert np.abs(fd3 - cycle.d3q).max() <= 2e-3 * peak3   # h = 0.5 deg here: O(h^2) = 2e-5 x d5q/d3q


def test_output_derivatives_against_central_differences(solved):
    # issue 24 acceptance (AD against central differences, h = 1e-4 rad, 1e-5 relative) for the outputs
    # (digest C's v_D of point D, digest D's needle-point speed)
    problem, kin, cycle = solved
    name = problem.linkage.outputs[0].name
    y = kin.output(cycle, name)
    fn = kin.output_function(name)
    h = 1e-4
    for k in range(0, 720, 15):
        def at(t):
            q = _pose_at(kin, cycle, k, t)
            return float(fn(q, q * 0, q * 0, q * 0, t, kin.p)[0])
        fd1 = (at(cycle.theta[k] + h) - at(cycle.theta[k] - h)) / (2 * h)
        assert abs(fd1 - y[1, k]) <= 1e-5 * np.abs(y[1]).max()


def _paper_positions(problem, phi2):
    """Needle point I by a literal implementation of the paper's position equations (7)-(12) (digest D):
    loop 1  l2 + l3 + l41 + l7 = 0, loop 2  l2 + l3 + l41 + l42 + l5 + l6 + l8 = 0 (x and y components),
    needle  l_I = l2 + l3 + l41 + l42 + l5 + l6 + l61, with phi42 = phi41 + 3 pi/4, phi61 = phi6 + 5 pi/4.
    The lengths are digest D's; scipy's fsolve with continuation from the file's reference pose."""
    l2, l3, l41, l42, l5, l6, l61 = (v / 1e3 for v in (8.92, 46.58, 66.44, 21.47, 21.55, 73.65, 44.58))
    l7, phi7 = 74.26e-3, math.radians(-16.1)
    l8, phi8 = 16.78e-3, math.radians(65.4)
    j = {jt.name: jt.xy for jt in problem.linkage.joints}
    ang = lambda v: math.atan2(v[1], v[0])  # noqa: E731
    x = np.array([ang(j["B"] - j["A"]), ang(j["O4"] - j["B"]), ang(j["D"] - j["C"]), ang(j["O6"] - j["D"])])

    def equations(u, p2):
        p3, p41, p5, p6 = u
        p42 = p41 + 3 * math.pi / 4
        return [l2 * math.cos(p2) + l3 * math.cos(p3) + l41 * math.cos(p41) + l7 * math.cos(phi7),     # (7)
                l2 * math.sin(p2) + l3 * math.sin(p3) + l41 * math.sin(p41) + l7 * math.sin(phi7),     # (8)
                l2 * math.cos(p2) + l3 * math.cos(p3) + l41 * math.cos(p41) + l42 * math.cos(p42)      # (9)
                + l5 * math.cos(p5) + l6 * math.cos(p6) + l8 * math.cos(phi8),
                l2 * math.sin(p2) + l3 * math.sin(p3) + l41 * math.sin(p41) + l42 * math.sin(p42)      # (10)
                + l5 * math.sin(p5) + l6 * math.sin(p6) + l8 * math.sin(phi8)]

    points = []
    for p2 in phi2:
        x = fsolve(equations, x, args=(p2,), xtol=1e-12)
        assert np.abs(equations(x, p2)).max() < 1e-14
        p3, p41, p5, p6 = x
        p42, p61 = p41 + 3 * math.pi / 4, p6 + 5 * math.pi / 4
        xi = (l2 * math.cos(p2) + l3 * math.cos(p3) + l41 * math.cos(p41) + l42 * math.cos(p42)   # (11)
              + l5 * math.cos(p5) + l6 * math.cos(p6) + l61 * math.cos(p61))
        yi = (l2 * math.sin(p2) + l3 * math.sin(p3) + l41 * math.sin(p41) + l42 * math.sin(p42)   # (12)
              + l5 * math.sin(p5) + l6 * math.sin(p6) + l61 * math.sin(p61))
        points.append((xi, yi))
    return np.array(points)


def test_blind_stitch_against_the_papers_position_equations():
    # digest D: equations (7)-(12) (vector loops with the fixed offsets 135 and 225 deg) against the
    # generic solver: needle point within 1e-9 m at all 720 angles
    problem = load_linkage_file(BLIND)
    kin = kinematics_of(problem.linkage)
    cycle = kin.solve(720)
    k = kin.structure.unknown.index("I")
    generic = cycle.q[:, 2 * k:2 * k + 2]
    paper = _paper_positions(problem, cycle.theta)
    assert np.abs(paper - generic).max() <= 1e-9


def test_blind_stitch_reconstruction_matches_the_speed_table():
    # digest D: the reconstruction matches the 15 needle speeds to RMS 0.034 m/s at 261.80 rad/s
    problem = load_linkage_file(BLIND)
    assert problem.omega == pytest.approx(261.80, abs=0.005)
    kin = kinematics_of(problem.linkage)
    cycle = kin.solve(720)
    y = kin.output(cycle, "needle")
    deg = np.degrees(cycle.theta) % 360
    idx = [int(np.argmin(np.abs(deg - a))) for a in problem.synthesis["angles_deg"]]
    assert all(abs(deg[i] - a) < 1e-9 for i, a in zip(idx, problem.synthesis["angles_deg"]))
    v = y[1, idx] * problem.omega
    rms = math.sqrt(np.mean((v - np.array(problem.synthesis["speeds_m_s"])) ** 2))
    assert rms == pytest.approx(0.034, abs=0.0005)


@pytest.mark.parametrize("n", [4, 3])
def test_coarse_sampling_keeps_the_branch(solved, n):
    # a grid coarser than the longest continuation step is walked in substeps (halved where a step jumps):
    # the poses at 90 and 120 deg steps are those of the 720-angle cycle, on the same assembly branch
    _, kin, cycle = solved
    coarse = kin.solve(n)
    assert coarse.substeps > n
    assert np.abs(coarse.q - cycle.q[::720 // n]).max() <= 1e-11


def test_cycle_at_720_angles_under_50_ms(solved):
    # issue 24 acceptance (bench): a linkage cycle at 720 angles, positions and three derivatives, under 50 ms;
    # CPU time, the best of five (the machine's other work does not count against it)
    import time

    _, kin, _ = solved
    best = math.inf
    for _ in range(5):
        t0 = time.process_time()
        kin.solve(720)
        best = min(best, time.process_time() - t0)
    assert best < 0.050
