"""`strokeopt bench`: speed measurements, each beside a reference measured in the same run.

Speed goals live here, never in unit tests. A benchmark is a function
registered with :func:`benchmark`; it takes no arguments, times the
capability and a reference implementation (a plain Python loop, an older
method) side by side, and returns a :class:`BenchResult`::

    @benchmark("my_capability", "what is timed, in one line", target_s=0.5)
    def _bench_my_capability() -> BenchResult:
        fast = best_time(lambda: new_way(), repeat=5)
        slow = best_time(lambda: reference_way(), repeat=1)
        return BenchResult(rows=[BenchRow("new way", fast), BenchRow("reference", slow)],
                           measured_s=fast, ratio=slow / fast, ratio_label="reference / new way")

To add one, put the decorated function in this module (below the others)
or in your own module and import that module in :func:`_load_all`. Keep each
benchmark under a few seconds: the machine is shared. ``strokeopt bench
--only NAME`` runs one; ``--json`` prints the results as JSON.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Callable

from ..errors import ProblemError


@dataclass(frozen=True)
class BenchRow:
    """One measured time [s]; ``note`` says what exactly (sizes, extrapolation)."""

    label: str
    seconds: float
    note: str = ""


@dataclass
class BenchResult:
    rows: list[BenchRow]
    measured_s: float  # the time compared with the benchmark's target
    ratio: float  # reference time / measured time, both measured in this run
    ratio_label: str
    notes: list[str] = field(default_factory=list)
    name: str = ""
    description: str = ""
    target_s: float | None = None
    #: a goal on the ratio itself (the ratio at most this), where the goal is relative to the peer measured beside
    ratio_max: float | None = None
    #: a goal that the ratio be at least this (a speed-up measured beside its peer)
    ratio_min: float | None = None

    @property
    def meets_target(self) -> bool | None:
        goals = [self.measured_s < self.target_s] if self.target_s is not None else []
        if self.ratio_max is not None:
            goals.append(self.ratio <= self.ratio_max)
        if self.ratio_min is not None:
            goals.append(self.ratio >= self.ratio_min)
        return all(goals) if goals else None

    def as_dict(self) -> dict:
        return {"name": self.name, "description": self.description, "target_s": self.target_s,
                "measured_s": self.measured_s, "meets_target": self.meets_target,
                "ratio": None if self.ratio != self.ratio else self.ratio,  # NaN: the peer was not measured
                "ratio_label": self.ratio_label, "ratio_max": self.ratio_max,
                "ratio_min": self.ratio_min, "notes": self.notes,
                "rows": [{"label": r.label, "seconds": r.seconds, "note": r.note} for r in self.rows]}


@dataclass(frozen=True)
class Benchmark:
    name: str
    description: str
    target_s: float | None
    fn: Callable[[], BenchResult]


REGISTRY: dict[str, Benchmark] = {}


def benchmark(name: str, description: str, target_s: float | None = None):
    """Register a benchmark function under ``name`` (see the module docstring)."""

    def deco(fn):
        if name in REGISTRY:
            raise ValueError(f"benchmark {name!r} registered twice")
        REGISTRY[name] = Benchmark(name, description, target_s, fn)
        return fn

    return deco


def best_time(fn: Callable[[], object], repeat: int = 5) -> float:
    """Smallest wall time [s] of ``repeat`` calls of ``fn``."""
    best = float("inf")
    for _ in range(repeat):
        t0 = time.perf_counter()
        fn()
        best = min(best, time.perf_counter() - t0)
    return best



def format_results(results: list[BenchResult]) -> str:
    lines = []
    for r in results:
        lines.append(f"{r.name}: {r.description}")
        for row in r.rows:
            lines.append(f"  {row.label:<48s} {row.seconds * 1e3:10.2f} ms  {row.note}")
        if r.ratio != r.ratio:  # NaN: the peer was not measured (not installed): said, not printed as "nanx"
            lines.append(f"  ratio {r.ratio_label}: not measured (the peer is missing: see the note)")
        else:
            lines.append(f"  ratio {r.ratio_label}: {r.ratio:.1f}x")
        if r.target_s is not None:
            verdict = "met" if r.measured_s < r.target_s else "NOT met"
            lines.append(f"  target: under {r.target_s:g} s -> measured {r.measured_s:.3f} s: {verdict}")
        if r.ratio_max is not None:
            verdict = "met" if r.ratio <= r.ratio_max else "NOT met"
            lines.append(f"  target: {r.ratio_label} at most {r.ratio_max:g}x -> {r.ratio:.2f}x: {verdict}")
        if r.ratio_min is not None:
            verdict = "met" if r.ratio >= r.ratio_min else "NOT met"
            lines.append(f"  target: {r.ratio_label} at least {r.ratio_min:g}x -> {r.ratio:.2f}x: {verdict}")
        lines += [f"  note: {n}" for n in r.notes]
        lines.append("")
    return "\n".join(lines).rstrip()


def reference_problem_path(name: str = "deco2000_needle_bar.toml") -> Path:
    """The reference problem file (or another of ``problems/``), from the working directory or the source tree."""
    for base in (Path.cwd(), Path(__file__).resolve().parents[3]):
        path = base / "problems" / name
        if path.is_file():
            return path
    raise ProblemError(f"problems/{name}", "", "problem file not found: run from the repository root")
