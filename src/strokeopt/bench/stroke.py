"""Benchmark of evaluating an optimal stroke: its polynomial pieces in numpy against the CasADi expression."""

from __future__ import annotations

import numpy as np

from .registry import BenchResult, BenchRow, benchmark, best_time


@benchmark("stroke_evaluate", "an optimal move's 80 quintic pieces at 20001 times, position to jerk: numpy locating "
                              "each time's polynomial against the CasADi expression (a branch per piece), mapped")
def _bench_stroke_evaluate() -> BenchResult:
    from .._casadi import evaluate
    from ..motion.stroke import polynomial_piece

    rng = np.random.default_rng(1)
    pieces, duration = 80, 25.2e-3  # move 1 of the reference design: 80 mesh intervals (its refined mesh), 25.2 ms
    breaks = np.arange(pieces) * (duration / pieces)
    piece = polynomial_piece(0.0, duration, breaks, rng.normal(size=(pieces, 6)))
    tau = np.linspace(0.0, duration, 20001)
    numeric = best_time(lambda: piece.derivatives(tau), repeat=5)
    casadi = best_time(lambda: evaluate(piece._ders, tau), repeat=3)
    worst = max(float(np.max(np.abs(a - b)) / np.max(np.abs(b)))
                for a, b in zip(piece.derivatives(tau), evaluate(piece._ders, tau)))
    return BenchResult(
        rows=[BenchRow("numpy (Piece.derivatives)", numeric, "best of 5"),
              BenchRow("CasADi Function, mapped", casadi, "best of 3")],
        measured_s=numeric, ratio=casadi / numeric, ratio_label="CasADi / numpy", ratio_min=5.0,
        notes=[f"the same numbers: largest difference {worst:.1e} of the peak (position to jerk)"])
