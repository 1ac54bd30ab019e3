"""Benchmarks of the study runner (studies/runner.py): a sweep on one worker and on every core, side by side,
and what starting the local Dask cluster costs."""

from __future__ import annotations

import os
import time

from ..design.transcription.nlp import clear_cache
from ..files.problem_file import load_problem
from ..studies.runner import StudyRunner, connected, default_workers
from ..studies.sweeps import sweep_design
from .registry import BenchResult, BenchRow, benchmark, reference_problem_path

#: The sweep timed: 11 rates of the reference problem on the thesis drive (each a verified solve).
SWEEP_RATES = [400.0 + 20.0 * k for k in range(11)]
FIXED_DRIVE = ['design.motor_choice="fixed"', 'design.pulley="fixed"']


def _load() -> str:
    try:
        return f"load average {os.getloadavg()[0]:.2f} on {os.cpu_count()} cores"
    except OSError:
        return ""


@benchmark("study_sweep_workers", "a sweep of 11 rates (reference problem, thesis drive, 400:600:20 spm, each a "
                                  "verified solve) with 1 worker and with every core (a LocalCluster), side by side; "
                                  "the start of the cluster on its own row", target_s=None)
def _bench_study_sweep_workers() -> BenchResult:
    problem = load_problem(reference_problem_path(), FIXED_DRIVE)
    cores = default_workers()
    before = _load()
    clear_cache()
    t0 = time.perf_counter()
    one = sweep_design(problem, SWEEP_RATES)
    one_s = time.perf_counter() - t0
    t0 = time.perf_counter()
    with connected(StudyRunner(cores)) as client:
        client.wait_for_workers(cores)
        start_s = time.perf_counter() - t0
        t0 = time.perf_counter()  # the same sweep on the started cluster, reached as any scheduler is
        every = sweep_design(problem, SWEEP_RATES, runner=StudyRunner(1, client.scheduler.address, "bench"))
        every_s = time.perf_counter() - t0
    worst = max(abs(b["objective_value"] / a["objective_value"] - 1.0)
                for a, b in zip(one, every) if a["feasible"] and b["feasible"])
    same = [a["feasible"] for a in one] == [b["feasible"] for b in every]
    return BenchResult(
        rows=[BenchRow("sweep, 1 worker (in this process)", one_s, f"{sum(r['feasible'] for r in one)} of 11 feasible"),
              BenchRow(f"sweep, {cores} workers (LocalCluster)", every_s,
                       f"{cores} contiguous runs of rates; the workers import strokeopt with their first rate"),
              BenchRow(f"LocalCluster start, {cores} worker processes", start_s),
              BenchRow(f"sweep, {cores} workers, the start included (solve --spm)", start_s + every_s,
                       f"ratio {one_s / (start_s + every_s):.2f}")],
        measured_s=every_s, ratio=one_s / every_s, ratio_label=f"1 worker / {cores} workers",
        notes=[f"the same table: feasibility {'equal' if same else 'DIFFERENT'}, objective within "
               f"{worst:.1e} relative (a run's first rate starts cold: docs/studies.md)", before,
               "the workers share the machine with whatever else runs on it: the ratio is at most the number of "
               "idle cores"])
