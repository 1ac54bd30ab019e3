"""Running the registered benchmarks (``strokeopt bench``)."""

from __future__ import annotations

from ..errors import ProblemError
from .registry import REGISTRY, BenchResult


def _load_all() -> None:
    """Import the modules that register benchmarks outside this one."""
    from . import contact, design, linkage, report, servo, sizing, solve_parts, stroke, studies  # noqa: F401  (each registers its benchmarks)


def benchmark_names() -> list[tuple[str, str]]:
    """Every registered benchmark: ``(name, description)``."""
    _load_all()
    return [(b.name, b.description) for b in REGISTRY.values()]


def run_benchmarks(only: list[str] | None = None, progress=None) -> list[BenchResult]:
    """Run the benchmarks ``only`` (default: all); ``progress(name, k, n, seconds_or_None)`` is told when each
    starts (None) and ends (its wall time)."""
    import time

    _load_all()
    names = list(REGISTRY) if not only else only
    for n in names:
        if n not in REGISTRY:
            raise ProblemError("--only", "", f"unknown benchmark {n!r}; registered: {', '.join(REGISTRY)}")
    out = []
    for k, n in enumerate(names, 1):
        b = REGISTRY[n]
        if progress is not None:
            progress(n, k, len(names), None)
        t0 = time.perf_counter()
        r = b.fn()
        r.name, r.description, r.target_s = b.name, b.description, b.target_s
        out.append(r)
        if progress is not None:
            progress(n, k, len(names), time.perf_counter() - t0)
    return out
