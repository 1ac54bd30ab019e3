"""The optimal stroke against the classic motion laws on the same timing and drive.

:func:`compare_with_laws` measures a :class:`~.result.Design` and every classic law (peaks,
integrals, torques on the design's motor and pulley) and says which laws meet the design
problem's own constraints; ``strokeopt solve --compare`` prints it (:mod:`strokeopt.report.design`).
"""

from __future__ import annotations

import math

import numpy as np

from .transcription.limits import ENFORCED_CHECKS
from .transcription.objectives import objective_of
from .transcription.request import design_moves
from .result import Design
from .torque import design_drive as _design_drive
from .transcription.settings import DesignSettings
from ..io.load_units import to_load_units
from ..motion.stroke import StrokeFunction


def _stroke_measures(design: Design, stroke: StrokeFunction, samples: int = 20_001) -> dict:
    """Peak acceleration and jerk over the moves, integrals of a^2 and jerk^2, and (with a drive) torques."""
    problem, spm = design.problem, design.spm
    sch = problem.timing.schedule(spm)
    a_max = j_max = 0.0
    int_a2 = int_j2 = 0.0
    peaks = stroke.piece_peaks(samples=2001)
    for itv, t0, dur, pk in zip(problem.timing.intervals, sch.t_start, sch.duration, peaks):
        if not itv.is_move:
            continue
        a_max = max(a_max, pk.a_max)
        j_max = max(j_max, pk.j_max)
        t = np.linspace(t0, t0 + dur, 2001)[:-1] + dur / 4000
        k = stroke.evaluate(t)
        int_a2 += float(np.sum(k.a**2) * dur / len(t))
        int_j2 += math.inf if math.isinf(pk.j_max) else float(np.sum(k.j**2) * dur / len(t))
    row = {"a_max_m_s2": a_max, "jerk_max_m_s3": j_max, "accel_squared": int_a2, "jerk_squared": int_j2}
    found = stroke_drive_checks(design, stroke, samples)
    if found is not None:
        from ..drive.load import load_torque

        drive, trans = _design_drive(design)
        k = stroke.sample(samples)
        checks = {c.name: c.value for c in found}
        row["_failed"] = [c.name for c in found if c.name in ENFORCED_CHECKS and not c.ok]
        tau = load_torque(design.motor_spec, trans, drive.load, k.s, k.v, k.a).total
        moving = np.zeros_like(k.t, dtype=bool)
        for itv, t0, dur in zip(problem.timing.intervals, sch.t_start, sch.duration):
            if itv.is_move:
                moving |= (k.t >= t0) & (k.t <= t0 + dur)
        dt = k.t[1] - k.t[0]
        row.update(peak_torque_N_m=checks["peak_torque"], energy=float(np.sum(tau[moving] ** 2) * dt))
        # a servo's RMS torque and speed; a stepper's demand against its pull-out curve and its step rate
        row.update({key: checks[name] for name, key in _CHECK_MEASURES if name in checks})
    return row


def stroke_drive_checks(design: Design, stroke: StrokeFunction, samples: int = 20_001) -> list | None:
    """The drive package's checks (peak and RMS torque, speed, belt, ...) of ``stroke`` on the design's motor and
    transmission, on ``samples`` points of the cycle; None without a motor or a ``[drive]``."""
    if design.motor_spec is None or design.problem.drive is None:
        return None
    from ..drive.checks import drive_checks

    drive, trans = _design_drive(design)
    k = stroke.sample(samples)
    grooves = design.pulley_teeth if design.pulley_teeth else drive.teeth_range[0]
    return drive_checks(design.motor_spec, trans, drive.load, k.t, k.s, k.v, k.a, limits=drive.limits,
                        belt=drive.belt, grooves=grooves)


_CHECK_MEASURES = (("rms_torque", "rms_torque_N_m"), ("peak_speed", "peak_speed_rpm"),
                   ("pull_out_torque", "pull_out_pct"), ("step_rate", "step_rate_Hz"))



def compare_with_laws(design: Design, laws=None) -> list[dict]:
    """The optimal stroke against classic laws on the same timing and drive (motor and pulley of the design).

    ``laws``: MotionLaw objects (default: every classic law, the problem's own law with its parameters).
    Each row: law, peak acceleration and jerk, integrals, peak and RMS torque (with a drive), and
    ``vs_optimal_pct``: how much larger the law's value of the design's objective measure is;
    ``feasible`` and ``violates``: whether the law meets the design problem's own constraints (rest
    order, jerk bounds, the drive package's enforced checks on the design's motor and pulley; the laws'
    handover accuracy is not checked) and which it breaks. The optimum comes first, then the
    feasible laws, then the infeasible ones: a law that breaks a constraint does not beat the optimum.
    """
    from ..motion.laws import compared_laws

    problem = design.problem
    if laws is None:
        laws = compared_laws(problem.default_law, [m.law for m in problem.timing.moves])
    measure = objective_of(design.objective).compare_measure
    settings = design.settings or getattr(problem, "design", None) or DesignSettings()
    opt = {"law": "optimal", **_stroke_measures(design, design.stroke)}
    opt.pop("_failed", None)  # the design's own checks (fine grid) say whether it is feasible
    failed = [c["name"] for c in design.checks if not c["ok"]]
    opt.update(feasible=not failed, violates=failed)
    rows = [opt]
    for law in laws:
        stroke = problem.with_law(law).stroke(design.spm)
        row = {"law": law.label, **_stroke_measures(design, stroke)}
        violates = (_law_violations(problem, design.spm, settings, law) + row.pop("_failed", [])
                    + _contact_violations(problem, settings, stroke))
        if law.characteristics.continuity < 2:  # the acceleration jumps at the dwells: the jerk is an impulse
            row.update(jerk_max_m_s3=math.inf, jerk_squared=math.inf)
        row.update(feasible=not violates, violates=violates)
        rows.append(row)
    for r in rows:
        base = opt.get(measure) if measure else None
        val = r.get(measure) if measure else None
        pct = 100.0 * (val / base - 1.0) if base and val is not None and math.isfinite(val) else None
        r["vs_optimal_pct"] = 0.0 if pct is not None and abs(pct) < 1e-6 else pct  # equal up to round-off: 0
    # a law that breaks the problem's constraints does not compete with the optimum: listed last
    ordered = [opt] + [r for r in rows[1:] if r["feasible"]] + [r for r in rows[1:] if not r["feasible"]]
    return to_load_units(ordered, problem.timing.rotary)   # a rotary load's a_max_rad_s2, jerk_max_rad_s3


def _contact_violations(problem, settings: DesignSettings, stroke: StrokeFunction, samples: int = 20_001) -> list[str]:
    """The ``[design.contact]`` limits a stroke breaks (design/contact_limits.py), on a fine sample of the cycle."""
    from .transcription.contact_setup import contact_design

    cd = contact_design(problem, settings)
    if cd is None:
        return []
    tol = settings.check_tolerance
    k = stroke.sample(samples)
    xd, vd, ad = cd.driven(np.asarray(k.s, float), np.asarray(k.v, float), np.asarray(k.a, float))
    out = []
    fmin = cd.settings.min_contact_force
    for name in cd.settings.keep_closed:
        force = np.asarray(cd.cluster.contact_force(name, xd, vd, ad), float)
        held = np.asarray(cd.cluster.holds(name, xd), bool)
        if held.any() and float(np.min(force[held])) < fmin - tol * max(abs(fmin), 1.0):
            out.append(f"keep_closed {name}")
    vmax = cd.settings.impact_velocity_max
    if vmax is not None and cd.impact is not None:
        c = cd.impact[2] * (xd - cd.impact[1])  # rises through 0 where the cluster meets the stop
        hits = np.flatnonzero((c[:-1] < 0) & (c[1:] >= 0))
        if hits.size and abs(float(vd[hits[0] + 1])) > vmax * (1 + tol):
            out.append("impact velocity")
    return out


_REST_NAMES = {1: "rest (velocity)", 2: "rest (acceleration)", 3: "rest (jerk)"}


def _law_violations(problem, spm: float, settings: DesignSettings, law) -> list[str]:
    """The constraints of the design problem (rest order, jerk bounds) a classic law breaks on its moves."""
    out = []
    c = law.characteristics
    if c.continuity < settings.rest_order:
        # the first derivative that does not vanish at the dwells (the design holds 1..rest_order at zero)
        out.append(_REST_NAMES[c.continuity + 1])
    c_j = c.C_j
    if settings.rest_order < 2 and math.isinf(c_j):
        # the design itself may jump in acceleration at the dwells (rest_order 1): only the jerk inside counts
        from ..motion.characteristics import _peak

        inner = law.derivatives([x + d for x in law.breaks for d in (-1e-9, 1e-9)] or [0.5], 2)[2]
        jumps = np.abs(inner[0::2] - inner[1::2]) if law.breaks else np.zeros(1)
        c_j = math.inf if np.max(jumps) > 1e-6 * (c.C_a + 1.0) else _peak(law, 3)
    for mv in design_moves(problem, spm, settings):
        if mv.jerk_bound is not None and c_j * mv.j_scale > mv.jerk_bound * (1 + settings.check_tolerance):
            out.append("jerk bound")
            break
    return out
