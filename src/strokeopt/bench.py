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

from .errors import ProblemError


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

    @property
    def meets_target(self) -> bool | None:
        return None if self.target_s is None else self.measured_s < self.target_s

    def as_dict(self) -> dict:
        return {"name": self.name, "description": self.description, "target_s": self.target_s,
                "measured_s": self.measured_s, "meets_target": self.meets_target, "ratio": self.ratio,
                "ratio_label": self.ratio_label, "notes": self.notes,
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


def _load_all() -> None:
    """Import the modules that register benchmarks outside this one."""
    from . import simulate  # noqa: F401  (simulate_release)
    from . import design  # noqa: F401  (design_resolve, design_reference, design_expand_jit, design_vs_rockit)


def run_benchmarks(only: list[str] | None = None) -> list[BenchResult]:
    _load_all()
    names = list(REGISTRY) if not only else only
    for n in names:
        if n not in REGISTRY:
            raise ProblemError("--only", "", f"unknown benchmark {n!r}; registered: {', '.join(REGISTRY)}")
    out = []
    for n in names:
        b = REGISTRY[n]
        r = b.fn()
        r.name, r.description, r.target_s = b.name, b.description, b.target_s
        out.append(r)
    return out


def format_results(results: list[BenchResult]) -> str:
    lines = []
    for r in results:
        lines.append(f"{r.name}: {r.description}")
        for row in r.rows:
            lines.append(f"  {row.label:<48s} {row.seconds * 1e3:10.2f} ms  {row.note}")
        lines.append(f"  ratio {r.ratio_label}: {r.ratio:.1f}x")
        if r.target_s is not None:
            verdict = "met" if r.meets_target else "NOT met"
            lines.append(f"  target: under {r.target_s:g} s -> measured {r.measured_s:.3f} s: {verdict}")
        lines += [f"  note: {n}" for n in r.notes]
        lines.append("")
    return "\n".join(lines).rstrip()


def reference_problem_path() -> Path:
    """The reference problem file, from the working directory or the source tree."""
    for base in (Path.cwd(), Path(__file__).resolve().parents[2]):
        path = base / "problems" / "deco2000_needle_bar.toml"
        if path.is_file():
            return path
    raise ProblemError("problems/deco2000_needle_bar.toml", "", "reference problem not found: run from the "
                                                                 "repository root")


# --------------------------------------------------------------------------- benchmarks


def size_pairs_loop(kin, motors, pulleys, load, limits, belt, spm, period):
    """Reference for the sizing benchmark: the same checks with one load-torque call per
    sample and pair (a Python loop), the way a first script would do it."""
    import numpy as np

    from .drive import _checks, load_torque, reflected_inertia

    out = []
    for p in pulleys:
        tr = p.transmission()
        for m in motors:
            total, omega, force = [], [], []
            for s, v, a in zip(kin.s, kin.v, kin.a):
                terms = load_torque(m, tr, load, float(s), float(v), float(a))
                total.append(float(terms.total))
                omega.append(float(terms.omega))
                force.append(float(terms.load_force))
            total = np.array(total)
            t = kin.t
            rms = float(np.sqrt(np.sum((total[1:] ** 2 + total[:-1] ** 2) * np.diff(t)) / (2 * (t[-1] - t[0]))))
            peak = float(np.max(np.abs(total)))
            reflected = reflected_inertia(tr, load, kin.s / tr.radius)
            out.append(_checks(peak, rms, max(map(abs, omega)), max(map(abs, force)), m, reflected, limits, belt,
                               p.teeth))
    return out


@benchmark("size_catalogue", "size the full catalogue (7 motors x 20 GT3 pulleys) at 600 spm, reference problem",
           target_s=0.5)
def _bench_size_catalogue() -> BenchResult:
    import numpy as np

    from .drive import _candidates
    from .problem import load_problem

    problem = load_problem(reference_problem_path())
    spec = problem.drive
    cat = spec.catalogue()
    motors = list(cat.motors.values())
    pulleys = cat.pulleys_of(spec.profile, spec.teeth_min, spec.teeth_max)
    belt = spec.belt_spec(cat)
    spm, samples = 600.0, 3601

    def vectorised(ms, ps):
        stroke = problem.stroke(spm)
        kin = stroke.sample(samples)
        return _candidates(kin, ms, ps, spec.load, spec.limits, belt, spm, stroke.period)

    vectorised(motors, pulleys)  # warm-up: CasADi builds its Functions on first use
    full = best_time(lambda: vectorised(motors, pulleys), repeat=5)
    sub_m, sub_p = motors[:1], pulleys[:2]
    sub_vec = best_time(lambda: vectorised(sub_m, sub_p), repeat=5)
    stroke = problem.stroke(spm)
    kin = stroke.sample(samples)
    loop_checks = []
    t0 = time.perf_counter()
    loop_checks = size_pairs_loop(kin, sub_m, sub_p, spec.load, spec.limits, belt, spm, stroke.period)
    sub_loop = time.perf_counter() - t0
    vec_checks = [c.checks for c in vectorised(sub_m, sub_p)]
    diff = max(abs(a.value - b.value) / max(abs(b.value), 1e-12)
               for ca_, cb in zip(loop_checks, vec_checks) for a, b in zip(ca_, cb))
    n_full, n_sub = len(motors) * len(pulleys), len(sub_m) * len(sub_p)
    return BenchResult(
        rows=[
            BenchRow(f"vectorised, {len(motors)} x {len(pulleys)} pairs", full,
                     f"{samples} samples per cycle, stroke sampled inside; best of 5"),
            BenchRow(f"vectorised, {len(sub_m)} x {len(sub_p)} pairs", sub_vec, "best of 5"),
            BenchRow(f"per-sample loop, {len(sub_m)} x {len(sub_p)} pairs", sub_loop, "one run"),
            BenchRow(f"per-sample loop, {len(motors)} x {len(pulleys)} pairs", sub_loop * n_full / n_sub,
                     f"extrapolated x{n_full // n_sub} from the row above, not run"),
        ],
        measured_s=full,
        ratio=sub_loop / sub_vec,
        ratio_label=f"loop / vectorised on the same {n_sub} pairs",
        notes=[f"largest relative difference of the check values, loop vs vectorised: {diff:.1e}"],
    )
