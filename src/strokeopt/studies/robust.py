"""The tolerance study: will the machines we build meet the limits? (:func:`robust_study`)

A design is verified with the nominal parts. Built parts scatter: a spring's rate, the belt's stiffness, the
masses, the gaps. :func:`robust_study` samples the scatter of the fields a user names (``--tolerance
FIELD=±10%``: any numeric field of the problem file, by its ``--set`` path), quasi-randomly (Sobol or Latin
hypercube from :mod:`scipy.stats.qmc`, seeded, so the same study gives the same numbers), and judges the *same
stroke* on each sampled machine through the same verification as the solve (:func:`.verified.verify_design`:
the full servo simulation and the contact scene) plus the drive's torque and belt checks on the sampled load.

The answer: the yield (the share of samples that meet every limit the problem sets, with a 95 % Wilson
interval), the worst samples with their parameters, and which tolerances matter: Spearman rank correlations of
each parameter with the handover error, the lag and the impact velocity (a quasi-random sample does not allow
Sobol indices; rank correlations need no model). The samples are independent tasks on the study runner
(:mod:`.runner`): the same numbers with one worker or many.
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass, replace

import numpy as np

from ..contact.options import SimulationOptions
from ..drive.selection import resolve_drive
from ..errors import ProblemError
from ..io.fields import number_in
from ..io.load_units import error_unit
from .runner import run_study
from .verified import verify_design

#: Sample designs of :func:`robust_study`.
METHODS = ("sobol", "lhs")
#: The fewest and most samples one study takes (a yield from fewer than 8 samples says nothing).
SAMPLES_RANGE = (8, 100_000)
#: The largest relative scatter [fraction]: beyond 90 % a part is not the part the design was made for.
RELATIVE_MAX = 0.9

_TEXT = re.compile(r"^(?P<field>[A-Za-z_][\w.\[\]]*)\s*=\s*(?:±|\+-|\+/-)\s*(?P<value>[0-9.eE+-]+)\s*(?P<pct>%)?"
                   r"\s*(?::\s*(?P<dist>uniform|normal))?\s*$")


@dataclass(frozen=True)
class Tolerance:
    """The scatter of one numeric field (its ``--set`` path): ``half_width`` either side of the nominal value,
    relative (a fraction) or absolute (in the field's own unit, as its name says: ``gap_mm``); ``distribution``
    ``uniform`` over the interval or ``normal`` with the interval as +-3 sigma (clipped to it)."""

    field: str
    nominal: float
    half_width: float
    relative: bool
    distribution: str = "uniform"

    @property
    def bounds(self) -> tuple[float, float]:
        d = abs(self.nominal) * self.half_width if self.relative else self.half_width
        return self.nominal - d, self.nominal + d

    def value(self, u: float) -> float:
        """The field's value at the unit sample ``u`` in (0, 1)."""
        lo, hi = self.bounds
        if self.distribution == "uniform":
            return lo + (hi - lo) * u
        from scipy.stats import norm

        z = float(np.clip(norm.ppf(min(max(u, 1e-12), 1 - 1e-12)), -3.0, 3.0))
        return self.nominal + z * (hi - lo) / 6.0

    def describe(self) -> str:
        width = f"±{100 * self.half_width:g} %" if self.relative else f"±{self.half_width:g}"
        return f"{self.field} = {self.nominal:g} {width} ({self.distribution})"


def parse_tolerance(text: str, problem, option: str = "--tolerance") -> Tolerance:
    """``FIELD=±10%`` (relative), ``FIELD=±0.1`` (absolute, the field's unit), ``...:normal`` (±3 sigma);
    the field must be a number of the problem, the scatter positive, and both extremes valid values of the
    field (checked as the problem file checks them: a stiffness that would go negative is refused)."""
    m = _TEXT.match(str(text))
    if m is None:
        raise ProblemError(option, str(text), "expected FIELD=±X% or FIELD=±X (the field's unit), optionally "
                                              ":normal, e.g. 'model.springs.k2.stiffness_N_m=±10%'")
    field = m["field"]
    nominal = number_in(problem.data, field, problem.file, option)
    try:
        half = float(m["value"]) / (100.0 if m["pct"] else 1.0)
    except ValueError:
        raise ProblemError(option, field, f"{m['value']!r} is not a number") from None
    if not (math.isfinite(half) and half > 0):
        raise ProblemError(option, field, f"the scatter must be positive, got {m['value']}")
    if m["pct"] and half > RELATIVE_MAX:
        raise ProblemError(option, field, f"±{100 * half:g} % is beyond ±{100 * RELATIVE_MAX:g} %: not the part the "
                                          "design was made for")
    tol = Tolerance(field, nominal, half, bool(m["pct"]), m["dist"] or "uniform")
    if any(b == nominal for b in tol.bounds):  # +-1e-300 on 900 N/m: every sample the nominal machine
        raise ProblemError(option, field, f"±{m['value']}{m['pct'] or ''} changes no value of {nominal:g}: every "
                                          "sample would be the nominal machine")
    check_applies([tol])
    for value in tol.bounds:  # both extremes must be values the problem file accepts
        try:
            problem.with_overrides([f"{field}={value!r}"])
        except ProblemError as exc:
            raise ProblemError(option, field, f"{tol.describe()} reaches {value:g}, which the problem refuses: "
                                              f"{exc.message}") from None
    return tol


def unit_samples(count: int, dims: int, method: str = "sobol", seed: int = 0) -> np.ndarray:
    """``count`` points in the unit cube of ``dims`` dimensions (scrambled Sobol or Latin hypercube, seeded)."""
    from scipy.stats import qmc

    if method == "sobol":
        import warnings

        with warnings.catch_warnings():  # a count that is no power of two: still a well spread sample
            warnings.simplefilter("ignore", UserWarning)
            return qmc.Sobol(dims, scramble=True, seed=seed).random(count)
    return qmc.LatinHypercube(dims, seed=seed).random(count)


#: The tables whose numbers a sample cannot change: the design's stroke keeps its rate, its timing, its law and
#: its settings (a sample judges the same stroke on another machine).
FIXED_BY_DESIGN = ("machine", "timing", "motion", "design", "problem")


def check_applies(tolerances: list[Tolerance], design=None) -> None:
    """Refuse a tolerance the study cannot apply to a design's samples: a field of :data:`FIXED_BY_DESIGN`, or
    (given the ``design``) the pulley of a design that chose its own (its teeth are the design's)."""
    for t in tolerances:
        table = t.field.split(".", 1)[0].split("[", 1)[0]
        if table in FIXED_BY_DESIGN:
            raise ProblemError("--tolerance", t.field, f"[{table}] is the design's: every sample judges the design's "
                                                       "stroke as solved (its rate, timing, law and settings), so a "
                                                       "scatter here would change nothing; solve a variant (--set) "
                                                       "for another rate or timing")
        if t.field.startswith("transmission.pulley_teeth") and design is not None and design.pulley_teeth is not None:
            raise ProblemError("--tolerance", t.field, f"the design chose its own pulley ({design.pulley_teeth} teeth): "
                                                       "a sample keeps it")


def check_distinct(tolerances: list[Tolerance]) -> None:
    """One scatter per field (a second would overwrite the first in every sample): else ProblemError naming it."""
    seen: dict = {}
    for t in tolerances:
        if t.field in seen:
            raise ProblemError("--tolerance", "", f"{t.field} is given twice ({seen[t.field].describe()} and "
                                                  f"{t.describe()}): give each field one tolerance")
        seen[t.field] = t


def robust_study(design, tolerances: list[Tolerance], samples: int = 1000, *, seed: int = 0, method: str = "sobol",
                 runner=None, progress=None, judge=None) -> dict:
    """The tolerance study of ``design`` (a solved or read-back :class:`~strokeopt.design.result.Design`):
    ``samples`` machines drawn from ``tolerances``, each judged with the design's stroke. Returns ``{"yield",
    "yield_interval", "samples", "failed_by", "worst", "sensitivity", "rows", "tolerances", ...}``. ``judge``:
    :func:`judge_stated` with a problem for ``design`` (a machine that states its motion, nothing to design:
    a linkage's crank at constant speed), judged by its transmission's own analysis."""
    if not tolerances:
        raise ProblemError("--tolerance", "", "name at least one tolerance, e.g. "
                                              "--tolerance 'model.springs.k2.stiffness_N_m=±10%'")
    if not SAMPLES_RANGE[0] <= samples <= SAMPLES_RANGE[1]:
        raise ProblemError("--samples", "", f"must lie in [{SAMPLES_RANGE[0]}, {SAMPLES_RANGE[1]}], got {samples}")
    if method not in METHODS:
        raise ProblemError("--method", "", f"{method!r} is not one of {', '.join(METHODS)}")
    check_distinct(tolerances)
    check_applies(tolerances, None if judge is not None else design)
    u = unit_samples(samples, len(tolerances), method, seed)
    items = [(k, tuple(t.value(float(x)) for t, x in zip(tolerances, row))) for k, row in enumerate(u)]
    outcomes = run_study(_sample_step, items, (design, tuple(tolerances), judge or judge_sample), runner=runner,
                         progress=progress, chained=False)
    rows = [{"sample": o.item[0], **{t.field: v for t, v in zip(tolerances, o.item[1])},
             **(o.row if o.ok else {"ok": False, "failed": ["error"], "error": o.error})} for o in outcomes]
    problem = design if judge is not None else design.problem
    return summarise(rows, tolerances, problem, problem.spm if judge is not None else design.spm, method, seed,
                     stated=judge is not None)


def _sample_step(shared, item, warm):
    """One sampled machine: the design's stroke on the problem with the sampled values (a runner step)."""
    design, tolerances, judge = shared
    _, values = item
    return judge(design, [f"{t.field}={v!r}" for t, v in zip(tolerances, values)]), None


def judge_stated(problem, overrides: list[str]) -> dict:
    """A machine that states its motion (no ``[design]``) with ``overrides``: its transmission's own results
    (``Transmission.analysis``'s ``measures``: a linkage's swing, near-dwells, least transmission index and crank
    torque), ``ok`` where the analysis passes its limits."""
    sampled = problem.with_overrides(overrides)
    own = sampled.transmission.analysis(sampled, with_dynamics=True)
    failed = [] if own["status"] == "ok" else ["transmission index"]
    return {**own["measures"], "ok": not failed, "failed": failed, "criteria": ["transmission index"]}


#: The contact scene of a sample: the default integration without locating each peak force between the output
#: points (no force is judged by its size here; the plausibility bound is far above the grid's error).
SAMPLE_SCENE_OPTIONS = SimulationOptions(peaks=False)
#: The relative spread of a result over the samples below which it has no rank correlation (10 x the sampled
#: scene's rtol): the contact-aware design's impact speed varies by 4e-5 over 16 machines, the integrator's noise.
NOT_VARYING = 10 * SAMPLE_SCENE_OPTIONS.rtol


#: The drive checks a sample reports, by their keys in its row (the unit in the name).
DRIVE_RESULTS = {"peak_torque": "peak_torque_N_m", "rms_torque": "rms_torque_N_m", "belt_tension": "belt_tension_N"}


def judge_sample(design, overrides: list[str]) -> dict:
    """The design's stroke on its problem with ``overrides``: handover error, lag, impact velocity, premature
    release, peak torque and belt checks, ``ok`` when every judged limit holds and ``failed`` naming the rest."""
    problem = design.problem.with_overrides(overrides)
    drive = None if design.drive is None else resolve_drive(
        problem, motor=design.drive.actuator, pulley_teeth=design.pulley_teeth, pitch_diameter=design.pitch_diameter,
        include_pulley_inertia=getattr(design.settings, "include_pulley_inertia", True))
    sampled = replace(design, problem=problem, drive=drive, verification=None, status="optimal")
    verified = verify_design(sampled, options=SAMPLE_SCENE_OPTIONS)
    row, failed, unjudged, judged = {}, [], [], []
    if verified.accuracy is None and any(itv.handover for itv in problem.timing.intervals):
        unjudged.append("handover accuracy")   # no servo model: the design's note says why
    if verified.accuracy is not None:
        scale, unit = error_unit(problem.timing.rotary)   # mm on a linear load, deg on a rotary one
        row[f"handover_error_{unit}"] = verified.accuracy.handover_error * scale
        # the verified design's own row: the one pass rule within the design's check tolerance (verified_handover)
        held = next((c for c in verified.design.checks if c["name"].startswith("handover accuracy")), None)
        if held is not None:
            judged.append("handover accuracy")
            if not held["ok"]:
                failed.append("handover accuracy")
    for c in (verified.verification or {}).get("criteria", []):
        key = {"lag": "max_lag_mm", "impact velocity": "impact_velocity_m_s",
               "premature release": "premature_release"}.get(c["criterion"])
        if key is not None:
            row[key] = c["value"]
        if c["ok"] is False and c["criterion"] != "handover accuracy":
            failed.append(c["criterion"])
        if c["ok"] is None and c["criterion"] in NOT_JUDGED:
            unjudged.append(c["criterion"])
        elif c["ok"] is not None and c["criterion"] != "handover accuracy":
            judged.append(c["criterion"])
    for check in _drive_checks(sampled):
        if check.name in DRIVE_RESULTS:
            row[DRIVE_RESULTS[check.name]] = float(check.value)
            judged.append(check.name)
            if not check.ok:
                failed.append(check.name)
    row.update(ok=not failed, failed=failed, not_judged=unjudged, criteria=judged)
    return row


#: The criteria a sample may leave unjudged, with the key of their value in its row and the field that would
#: judge them (the verification's own: a lag or impact velocity without a [design.contact] limit; a handover
#: without a servo model)
NOT_JUDGED = {"lag": ("max_lag_mm", "mm", "design.contact.lag_max_mm"),
              "impact velocity": ("impact_velocity_m_s", "m/s", "design.contact.impact_velocity_max_m_s"),
              "handover accuracy": (None, "", "[servo] (the servo loop and belt model)")}


def unjudged_summary(rows: list[dict]) -> list[dict]:
    """The criteria some sample left unjudged: each with the range of its values over the samples and the field
    that would judge it (a yield counts only what is judged: these are named beside it)."""
    out = []
    for name in dict.fromkeys(n for r in rows for n in r.get("not_judged", ())):
        key, unit, field = NOT_JUDGED[name]
        values = [r[key] for r in rows if key is not None and isinstance(r.get(key), (int, float))]
        out.append({"criterion": name, "samples": sum(name in r.get("not_judged", ()) for r in rows),
                    "low": min(values) if values else None, "high": max(values) if values else None,
                    "unit": unit, "limit_field": field})
    return out


def _drive_checks(design) -> list:
    """The drive package's checks of the design's stroke on its (sampled) drive; none without a drive."""
    if design.drive is None or design.drive.actuator is None:
        return []
    from ..drive.checks import drive_checks

    d = design.drive
    k = design.stroke.sample(2001)
    return drive_checks(d.actuator, d.transmission, design.problem.drive.load, k.t, k.s, k.v, k.a, limits=d.limits,
                        belt=d.belt, grooves=design.pulley_teeth or design.problem.drive.teeth_min)


def wilson_interval(successes: int, n: int, z: float = 1.959964) -> tuple[float, float]:
    """The 95 % Wilson score interval of a yield ``successes / n``."""
    if n == 0:
        return 0.0, 1.0
    p = successes / n
    centre = (p + z * z / (2 * n)) / (1 + z * z / n)
    half = z * math.sqrt(p * (1 - p) / n + z * z / (4 * n * n)) / (1 + z * z / n)
    return max(0.0, centre - half), min(1.0, centre + half)


#: The results a sensitivity is given for (the ones the scatter moves and a limit may judge).
RESPONSES = ("handover_error_mm", "handover_error_deg", "max_lag_mm", "impact_velocity_m_s", "peak_torque_N_m")


def summarise(rows: list[dict], tolerances: list[Tolerance], problem, spm: float, method: str, seed: int,
              stated: bool = False) -> dict:
    """Yield with its interval, failures by criterion, the five worst samples, rank correlations (of
    :data:`RESPONSES`, and of every result a stated machine's rows have: ``responses``)."""
    from scipy.stats import spearmanr

    n = len(rows)
    good = sum(1 for r in rows if r.get("ok"))
    lo, hi = wilson_interval(good, n)
    failed_by: dict[str, int] = {}
    for r in rows:
        for name in r.get("failed", []):
            failed_by[name] = failed_by.get(name, 0) + 1
    fields = {t.field for t in tolerances}
    own = [k for r in rows for k, v in r.items() if k not in fields and k != "sample" and k not in RESPONSES
           and isinstance(v, float)] if stated else []   # a stated machine's own results (a linkage's measures)
    responses = RESPONSES + tuple(dict.fromkeys(own))
    sens = []
    for t in tolerances:
        x = np.array([r[t.field] for r in rows], float)
        entry = {"field": t.field}
        for key in responses:
            y = np.array([r.get(key, np.nan) for r in rows], float)
            ok = np.isfinite(y)
            # a result that varies by less than the contact simulation resolves (10 x its rtol, relative) over the
            # samples does not vary: its ranks would be the integrator's noise, not the part's effect
            if ok.sum() < 8 or not np.ptp(x[ok]) > 0:
                continue
            varies = np.ptp(y[ok]) > NOT_VARYING * np.max(np.abs(y[ok]))
            entry[key] = float(spearmanr(x[ok], y[ok]).statistic) if varies else None   # None: does not vary
        sens.append(entry)
    # the most limits failed, then the largest handover error, then the largest peak torque (where nothing fails
    # and no handover is judged, the samples in index order were listed as the worst)
    # (a stated machine: the most limits failed, then the least transmission index, its limit's margin)
    worst = sorted(rows, key=lambda r: (len(r.get("failed", [])),
                                        r.get("handover_error_mm", r.get("handover_error_deg", 0.0)),
                                        r.get("peak_torque_N_m", 0.0), -r.get("min_transmission_index", 0.0)),
                   reverse=True)[:5]
    return {"status": "ok", "problem": problem.name, "spm": spm, "cycle": problem.cycle.noun, "samples": n,
            "method": method, "judged": "the file's motion" if stated else "the design's stroke",
            "worst_by": "the least transmission index" if stated else "the largest handover error",
            "responses": [k for k in responses if any(k in r for r in rows)],
            "seed": seed, "tolerances": [{"field": t.field, "nominal": t.nominal, "lower": t.bounds[0],
                                          "upper": t.bounds[1], "distribution": t.distribution} for t in tolerances],
            "yield": good / n if n else 0.0, "yield_interval": [lo, hi], "failed_by": failed_by,
            "not_judged": unjudged_summary(rows),
            "criteria": list(dict.fromkeys(c for r in rows for c in r.get("criteria", ()))),   # what the yield counts
            "worst": worst, "sensitivity": sens, "rows": rows}
