"""Runs of many simulations: speed sweeps and the integrators' work-precision study.

:func:`sweep_spm` simulates a scene over stitch rates (simulate.py) and
:func:`lag_onset_spm` reads the first rate at which a result turns true;
:func:`tolerance_study` compares tolerances, switch smoothing, CVODES/IDAS and
restarts at switches against a tight reference (the numbers quoted in
simulate.py come from it). report/contact.py prints and draws both; studies/vary.py steps numbers of the
problem at one rate.
"""

from __future__ import annotations

import math

from ..errors import SolverError
from .simulate import SimulationOptions, simulate_scene

#: The metrics the tolerance study reports of its reference.
STUDY_METRICS = ("impact_velocity_m_s", "impact_angle_deg", "release_angle_deg", "lag_end_angle_deg")
#: The errors the tolerance study reports: error key -> metric key.
STUDY_ERRORS = {"impact_velocity_error_m_s": "impact_velocity_m_s", "release_angle_error_deg": "release_angle_deg",
                "impact_angle_error_deg": "impact_angle_deg"}


def sweep_spm(problem, scene: str, spms, options: SimulationOptions | None = None, progress: bool = False) -> list[dict]:
    """Summaries of :func:`simulate_scene` over speeds (tqdm progress bar on stderr if ``progress``)."""
    spms = list(spms)
    it = spms
    if progress:
        from tqdm import tqdm

        it = tqdm(spms, desc=f"simulating {scene}", unit="spm", leave=False)
    return [simulate_scene(problem, scene, s, options=options).summary() for s in it]


def lag_onset_spm(rows: list[dict], key: str = "lag") -> float | None:
    """The first speed of a sweep at which the follower lags (or ``key``, e.g. ``premature_release``,
    is true; None if it never is)."""
    return next((r["spm"] for r in rows if r.get(key)), None)


REFERENCE_OPTIONS = SimulationOptions(rtol=1e-9, atol=1e-10)


def tolerance_study(problem, scene: str, spm: float | None = None, rtols=(1e-4, 1e-5, 1e-6, 1e-7),
                    smoothings=(1e-6, 1e-7), methods=("cvodes", "idas"), restarts: bool = True,
                    progress: bool = False, reference: SimulationOptions = REFERENCE_OPTIONS) -> dict:
    """Work-precision table: error of impact velocity and release angle against a tight reference
    (hard switches, ``reference`` tolerances) vs CPU time, over tolerances: hard switches with each of
    ``methods``, CVODES with each smoothing width (m), and (``restarts``) CVODES restarted at every
    detected switch. ``atol`` follows ``rtol / 10`` (positions in mm, velocities in m/s)."""
    ref = simulate_scene(problem, scene, spm, options=reference)
    cases = [(mth, rt, 0.0, False) for mth in methods for rt in rtols]
    cases += [("cvodes", rt, eps, False) for eps in smoothings if eps > 0 for rt in rtols]
    cases += [("cvodes", rt, 0.0, True) for rt in rtols] if restarts else []
    it = cases
    if progress:
        from tqdm import tqdm

        it = tqdm(cases, desc="tolerance study", leave=False)
    rows = []
    for mth, rt, eps, restart in it:
        opts = SimulationOptions(method=mth, rtol=rt, atol=rt / 10, smoothing=eps, restart_at_switches=restart)
        switching = "restarts" if restart else ("smoothed" if eps > 0 else "hard")
        row = {"method": mth, "switching": switching, "rtol": rt, "smoothing_mm": eps * 1e3}
        try:
            r = simulate_scene(problem, scene, spm, options=opts)
        except SolverError as exc:
            row.update({"failed": str(exc)})
            rows.append(row)
            continue
        row.update(_errors(r.metrics, ref.metrics))
        row.update({"cpu_time_s": r.cpu_time_s, "nsteps": r.stats["nsteps"]})
        rows.append(row)
    return {"scene": scene, "spm": ref.spm, "reference": {"rtol": reference.rtol, "atol": reference.atol,
                                                           "cpu_time_s": ref.cpu_time_s,
                                                           **{k: ref.metrics[k] for k in STUDY_METRICS}},
            "rows": rows}


def _errors(m: dict, ref: dict) -> dict:
    def err(key):
        if m[key] is None or ref[key] is None:
            return None if m[key] is None and ref[key] is None else math.inf
        return abs(m[key] - ref[key])

    return {name: err(key) for name, key in STUDY_ERRORS.items()}

