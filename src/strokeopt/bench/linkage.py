"""Benchmarks of the planar linkages (issue 24): one cycle of the loom's six-bar at 720 crank angles (positions
and three derivatives by AD) against a plain numpy/scipy loop (``fsolve`` per angle, derivatives by central
differences on the grid), and the loom's dimensional synthesis."""

from __future__ import annotations

import math
import time

import numpy as np

from .registry import BenchResult, BenchRow, benchmark, best_time, reference_problem_path


def loom_fsolve_cycle(linkage, n: int = 720):
    """Reference: the loom's six-bar the way a first script solves it. Unknowns E, F, D (six coordinates);
    six distance equations (rods C-E, B-F, the coupler's three sides E-F, E-D, F-D, the sley B0-D) with the
    crank pins turned about A0; scipy's ``fsolve`` at each angle from the previous pose; the sley angle's
    first three derivatives by periodic central differences on the grid. Returns (sley angle, d1, d2, d3)."""
    from scipy.optimize import fsolve

    xy = {j.name: np.array(j.xy, dtype=float) for j in linkage.joints}
    a0, b0 = xy["A0"], xy["B0"]
    pairs = [("C", "E"), ("B", "F"), ("E", "F"), ("E", "D"), ("F", "D"), ("B0", "D")]
    lengths = np.array([linkage.length(a, b) for a, b in pairs])
    c0, bb0 = xy["C"] - a0, xy["B"] - a0

    def equations(u, th):
        cs, sn = math.cos(th), math.sin(th)
        pts = {"C": a0 + np.array([cs * c0[0] - sn * c0[1], sn * c0[0] + cs * c0[1]]),
               "B": a0 + np.array([cs * bb0[0] - sn * bb0[1], sn * bb0[0] + cs * bb0[1]]),
               "E": u[0:2], "F": u[2:4], "D": u[4:6], "B0": b0}
        return [float(np.dot(pts[a] - pts[b], pts[a] - pts[b])) - l * l for (a, b), l in zip(pairs, lengths)]

    theta = 2 * math.pi * np.arange(n) / n
    u = np.concatenate([xy["E"], xy["F"], xy["D"]])
    angle = np.empty(n)
    for k, th in enumerate(theta):
        u = fsolve(equations, u, args=(th,), xtol=1e-13)
        d = u[4:6] - b0
        angle[k] = math.atan2(d[1], d[0])
    angle = np.unwrap(angle)
    h = theta[1] - theta[0]
    roll = lambda y, s: np.roll(y, -s)  # noqa: E731  (y[k + s] on the periodic grid)
    d1 = (roll(angle, 1) - roll(angle, -1)) / (2 * h)
    d2 = (roll(angle, 1) - 2 * angle + roll(angle, -1)) / h ** 2
    d3 = (roll(angle, 2) - 2 * roll(angle, 1) + 2 * roll(angle, -1) - roll(angle, -2)) / (2 * h ** 3)
    return angle, d1, d2, d3


@benchmark("linkage_cycle", "loom six-bar: one cycle at 720 crank angles, positions and three derivatives (AD), "
                            "against a numpy/scipy fsolve loop with central differences", target_s=0.05)
def _bench_linkage_cycle() -> BenchResult:
    from ..linkage.files import load_linkage_file
    from ..linkage.kinematics import Kinematics

    problem = load_linkage_file(reference_problem_path("loom_beatup_sixbar.toml"))

    def ours():
        kin = Kinematics(problem.linkage)  # no cache: the CasADi functions are built once per Kinematics
        cycle = kin.solve(720)
        return kin, cycle, kin.output(cycle, "sley_angle")

    kin, cycle, (y, d1, d2, d3) = ours()  # warm-up (the first build of the CasADi functions)
    fresh = best_time(ours, repeat=3)

    def solve_only():
        c = kin.solve(720)
        return kin.output(c, "sley_angle")

    t_solve = best_time(solve_only, repeat=5)
    cpu0 = time.process_time()
    solve_only()
    cpu = time.process_time() - cpu0
    t_ref = best_time(lambda: loom_fsolve_cycle(problem.linkage), repeat=1)
    ref = loom_fsolve_cycle(problem.linkage)
    # the two agree in position; the grid's differences lose accuracy with each derivative
    shift = float(np.mean(np.unwrap(y) - ref[0]))
    err = [float(np.abs(np.unwrap(y) - ref[0] - shift).max())] + \
        [float(np.abs(a - b).max() / np.abs(a).max()) for a, b in zip((d1, d2, d3), ref[1:])]
    return BenchResult(
        rows=[BenchRow("strokeopt: solve + output derivatives", t_solve, f"{cpu * 1e3:.1f} ms CPU"),
              BenchRow("strokeopt: the same, building its CasADi functions first", fresh),
              BenchRow("numpy/scipy: fsolve per angle + central differences", t_ref)],
        measured_s=t_solve, ratio=t_ref / t_solve, ratio_label="fsolve loop / strokeopt",
        notes=[f"largest closure residual {cycle.residual.max():.1e} m, pose after one turn {cycle.return_error:.1e} m",
               f"fsolve loop against AD: sley angle {err[0]:.1e} rad; derivatives 1-3 by central differences "
               f"{err[1]:.1e}, {err[2]:.1e}, {err[3]:.1e} of their peaks (AD is exact to the closure residual)"])


@benchmark("linkage_synthesis", "loom six-bar: dimensional synthesis against Tab. 1 (the file's 8 starts, seed 1)",
           target_s=60.0)
def _bench_linkage_synthesis() -> BenchResult:
    from ..linkage.files import load_linkage_file
    from ..linkage.synthesis import synthesize

    problem = load_linkage_file(reference_problem_path("loom_beatup_sixbar.toml"))
    t0, c0 = time.perf_counter(), time.process_time()
    result = synthesize(problem)
    wall, cpu = time.perf_counter() - t0, time.process_time() - c0
    rms = result.best.rms
    return BenchResult(
        rows=[BenchRow("strokeopt: screen + multi-start IPOPT (simultaneous form)", wall,
                       f"{cpu:.1f} s CPU, {result.starts} starts of {result.screened} screened")],
        measured_s=wall, ratio=float("nan"), ratio_label="no peer",
        notes=[f"no open tool synthesises a six-bar triad in the simultaneous form to compare with; best RMS "
               f"{rms:.4f} m/s against Tab. 1's 13 speeds, {len(result.runners_up)} runners-up"])
