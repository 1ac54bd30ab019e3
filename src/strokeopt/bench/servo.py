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
