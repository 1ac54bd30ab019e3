"""Running the registered benchmarks (``strokeopt bench``)."""

from __future__ import annotations

from ..errors import ProblemError
from .registry import REGISTRY, BenchResult


def _load_all() -> None:
    """Import the modules that register benchmarks outside this one."""
    from . import contact, design, report, servo, sizing, solve_parts, studies  # noqa: F401  (each registers its benchmarks)


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
