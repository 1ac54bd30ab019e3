"""Benchmarks of the servo step: the accuracy/stitch-rate trade-off against one design solve."""

from __future__ import annotations

import json
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from ..errors import SolverError
from .registry import BenchResult, BenchRow, benchmark, reference_problem_path

#: The trade-off may take this many times one design solve of the reference problem (issue 14).
TRADEOFF_RATIO_TARGET = 10.0


@benchmark("tradeoff_vs_solve", "strokeopt tradeoff problems/deco2000_needle_bar.toml (every default accuracy, "
                                "classic law and optimal stroke, one worker per core) against one strokeopt solve "
                                "of it, both run as the commands, one after the other (half a minute or more: the "
                                "whole trade-off runs)",
           target_s=60.0)
def _bench_tradeoff_vs_solve() -> BenchResult:
    path = reference_problem_path()
    with tempfile.TemporaryDirectory() as tmp:
        solve_s, solve_out = run_command(["solve", str(path), "--json", "--plot", str(Path(tmp) / "solve.png")])
        tradeoff_s, tradeoff_out = run_command(["tradeoff", str(path), "--json", "--plot", str(Path(tmp) / "t.png")])
    points = [p for p in tradeoff_out["points"] if p["stroke"] == "optimal"]
    rates = ", ".join(f"{p['accuracy_mm']:g} mm {p['max_spm'] if p['max_spm'] is not None else '-'}" for p in points)
    ratio = tradeoff_s / solve_s
    return BenchResult(rows=[BenchRow("strokeopt solve (catalogue search, 500 spm, verified)", solve_s,
                                      f"{solve_out['motor']}, {solve_out['pulley_teeth']} teeth"),
                             BenchRow("strokeopt tradeoff (classic law and optimal stroke)", tradeoff_s,
                                      f"optimal: {rates}")],
                       measured_s=tradeoff_s, ratio=ratio, ratio_label="tradeoff / one solve",
                       ratio_max=TRADEOFF_RATIO_TARGET,
                       notes=["wall times of the two commands, each in its own process (imports included), as a "
                              "user runs them"])


def run_command(args: list[str]) -> tuple[float, dict]:
    """Wall time [s] and JSON output of ``strokeopt ARGS`` in a process of its own."""
    t0 = time.perf_counter()
    done = subprocess.run([sys.executable, "-m", "strokeopt", *args], capture_output=True, text=True)
    seconds = time.perf_counter() - t0
    if done.returncode != 0:
        raise SolverError(f"strokeopt {' '.join(args[:2])} exited {done.returncode}: {done.stderr.strip()[-300:]}")
    return seconds, json.loads(done.stdout)


@benchmark("servo_varying", "the servo loop through the crank of problems/deco2000_crank_slider.toml (rigid, its ratio "
                            "varying): one handover accuracy (four table phases to the periodic state) with the RK4 "
                            "steps it uses against CasADi's CVODES at rtol 1e-10, the handover errors beside")
def _bench_servo_varying() -> BenchResult:
    import casadi as ca

    from ..files.problem_file import load_problem
    from . import registry
    from ..servo import varying
    from ..servo.accuracy import handover_accuracy

    problem = load_problem(registry.reference_problem_path().parent / "deco2000_crank_slider.toml")
    handover_accuracy(problem)   # imports and the tuning's cache out of both timings
    t0 = time.perf_counter()
    rk = handover_accuracy(problem)
    rk_s = time.perf_counter() - t0
    plain = ca.integrator

    def cvodes(name, plugin, dae, t0, tf, opts):
        return plain(name, "cvodes", dae, t0, tf, {"abstol": 1e-12, "reltol": 1e-10})

    varying.ca.integrator = cvodes
    try:
        t0 = time.perf_counter()
        cv = handover_accuracy(problem)
        cv_s = time.perf_counter() - t0
    finally:
        varying.ca.integrator = plain
    return BenchResult(rows=[BenchRow(f"RK4, {varying.RK_STEPS} steps per grid step", rk_s,
                                      f"handover error {rk.handover_error * 1e3:.5f} mm"),
                             BenchRow("CVODES, rtol 1e-10", cv_s, f"handover error {cv.handover_error * 1e3:.5f} mm "
                                      f"({100 * (rk.handover_error / cv.handover_error - 1):+.2f} % RK4 against it)")],
                       measured_s=rk_s, ratio=cv_s / rk_s, ratio_label="CVODES / RK4", ratio_min=2.0,
                       notes=["in this process, after one run that builds the functions and tunes the gains"])
