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
#: The speed-up goal of a study on every core, per core (1.6 on two): the workers' share of the work.
WORKERS_RATIO_PER_CORE = 0.8
SWEEP_RATES = [400.0 + 20.0 * k for k in range(11)]
FIXED_DRIVE = ['design.motor_choice="fixed"', 'design.pulley="fixed"']


def _load() -> str:
    try:
        return f"{os.getloadavg()[0]:.2f}"
    except OSError:
        return "?"


def _cpu_s() -> float:
    """CPU seconds of this process (run on each worker by ``Client.run``)."""
    t = os.times()
    return t.user + t.system


def _timed_on_cluster(cores: int, study):
    """``study(runner)`` on a started LocalCluster of ``cores`` workers: (its result, start [s], wall [s], the
    workers' CPU [s])."""
    t0 = time.perf_counter()
    with connected(StudyRunner(cores)) as client:
        client.wait_for_workers(cores)
        start_s = time.perf_counter() - t0
        cpu0 = client.run(_cpu_s)
        t0 = time.perf_counter()  # the study on the started cluster, reached as any scheduler is
        result = study(StudyRunner(1, client.scheduler.address, "bench"))
        wall_s = time.perf_counter() - t0
        cpu1 = client.run(_cpu_s)
    return result, start_s, wall_s, sum(cpu1[w] - cpu0[w] for w in cpu1 if w in cpu0)


def _cpu_notes(one_cpu: float, one_s: float, every_cpu: float, every_s: float, cores: int, loads) -> list[str]:
    return [f"CPU work: {one_cpu:.1f} s on 1 worker, {every_cpu:.1f} s over {cores} workers; the workers got "
            f"{every_cpu / every_s:.2f} cores between them, the single one {one_cpu / one_s:.2f} (load average "
            f"{' -> '.join(loads)} on {os.cpu_count()} cores: the ratio is at most the number of idle cores)"]


@benchmark("study_sweep_workers", "a sweep of 11 rates (reference problem, thesis drive, 400:600:20 spm, each a "
                                  "verified solve) with 1 worker and with every core (a LocalCluster), side by side; "
                                  "the start of the cluster on its own row", target_s=None)
def _bench_study_sweep_workers() -> BenchResult:
    problem = load_problem(reference_problem_path(), FIXED_DRIVE)
    cores = default_workers()
    loads = [_load()]
    clear_cache()
    c0, t0 = _cpu_s(), time.perf_counter()
    one = sweep_design(problem, SWEEP_RATES)
    one_s, one_cpu = time.perf_counter() - t0, _cpu_s() - c0
    every, start_s, every_s, every_cpu = _timed_on_cluster(cores, lambda r: sweep_design(problem, SWEEP_RATES,
                                                                                        runner=r))
    loads.append(_load())
    worst = max(abs(b["objective_value"] / a["objective_value"] - 1.0)
                for a, b in zip(one, every) if a["feasible"] and b["feasible"])
    same = [a["feasible"] for a in one] == [b["feasible"] for b in every]
    return BenchResult(
        rows=[BenchRow("sweep, 1 worker (in this process)", one_s, f"{sum(r['feasible'] for r in one)} of 11 feasible"),
              BenchRow(f"sweep, {cores} workers (LocalCluster)", every_s,
                       f"{cores} contiguous runs of solves, each rate's verification a task of its own"),
              BenchRow(f"LocalCluster start, {cores} worker processes", start_s),
              BenchRow(f"sweep, {cores} workers, the start included (solve --spm)", start_s + every_s,
                       f"ratio {one_s / (start_s + every_s):.2f}")],
        measured_s=every_s, ratio=one_s / every_s, ratio_label=f"1 worker / {cores} workers",
        ratio_min=WORKERS_RATIO_PER_CORE * cores if cores > 1 else None,
        notes=[f"the same table: feasibility {'equal' if same else 'DIFFERENT'}, objective within "
               f"{worst:.1e} relative (a run's first rate starts cold: docs/studies.md)",
               *_cpu_notes(one_cpu, one_s, every_cpu, every_s, cores, loads)])


#: The tolerance study timed: samples of the reference design at 600 spm with k2 scattered by ±10 %.
ROBUST_SAMPLES = 200
ROBUST_TOLERANCE = "model.springs.k2.stiffness_N_m=±10%"


@benchmark("study_robust_workers", f"a tolerance study of {ROBUST_SAMPLES} samples (the reference design at 600 spm, "
                                   "k2 ±10 %, each sample its servo simulation and release scene) with 1 worker and "
                                   "with every core (a LocalCluster), side by side", target_s=None)
def _bench_study_robust_workers() -> BenchResult:
    from ..studies.robust import parse_tolerance, robust_study
    from ..studies.verified import solve_verified

    problem = load_problem(reference_problem_path(), ["machine.spm=600"])
    design = solve_verified(problem, compare=False).design
    tolerances = [parse_tolerance(ROBUST_TOLERANCE, problem)]
    cores = default_workers()
    loads = [_load()]
    c0, t0 = _cpu_s(), time.perf_counter()
    one = robust_study(design, tolerances, ROBUST_SAMPLES, seed=1)
    one_s, one_cpu = time.perf_counter() - t0, _cpu_s() - c0
    every, start_s, every_s, every_cpu = _timed_on_cluster(
        cores, lambda r: robust_study(design, tolerances, ROBUST_SAMPLES, seed=1, runner=r))
    loads.append(_load())
    same = one["rows"] == every["rows"]
    return BenchResult(
        rows=[BenchRow("tolerance study, 1 worker (in this process)", one_s, f"yield {one['yield']:.3f}"),
              BenchRow(f"tolerance study, {cores} workers (LocalCluster)", every_s, "every sample a task"),
              BenchRow(f"LocalCluster start, {cores} worker processes", start_s),
              BenchRow(f"tolerance study, {cores} workers, the start included", start_s + every_s,
                       f"ratio {one_s / (start_s + every_s):.2f}")],
        measured_s=every_s, ratio=one_s / every_s, ratio_label=f"1 worker / {cores} workers",
        ratio_min=WORKERS_RATIO_PER_CORE * cores if cores > 1 else None,
        notes=[f"the same numbers: {'every sample equal' if same else 'DIFFERENT'}",
               *_cpu_notes(one_cpu, one_s, every_cpu, every_s, cores, loads)])
