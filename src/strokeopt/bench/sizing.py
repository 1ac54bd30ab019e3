"""Benchmark of drive sizing: the whole catalogue, vectorised, against a per-sample loop."""

from __future__ import annotations

import time

from ..files.problem_file import load_problem
from .registry import BenchResult, BenchRow, benchmark, best_time, reference_problem_path


def size_pairs_loop(kin, motors, pulleys, load, limits, belt, spm, period):
    """Reference for the sizing benchmark: the same checks with one load-torque call per
    sample and pair (a Python loop), the way a first script would do it."""
    import numpy as np

    from ..drive.checks import build_checks
    from ..drive.load import load_torque, reflected_inertia

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
            out.append(build_checks(peak, rms, max(map(abs, omega)), max(map(abs, force)), m, reflected, limits,
                                    belt, p.teeth))
    return out


@benchmark("size_catalogue", "size the full catalogue (7 motors x 20 GT3 pulleys) at 600 spm, reference problem",
           target_s=0.5)
def _bench_size_catalogue() -> BenchResult:
    from ..drive.sizing import candidates

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
        return candidates(kin, ms, ps, spec.load, spec.limits, belt, spm, stroke.period)

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
