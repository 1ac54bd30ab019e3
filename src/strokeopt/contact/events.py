"""The results of a simulated cycle: event roles, metric names and event location.

A model marks, by name, the elements and the body that the results are about
(``[model.events]``, read into :class:`EventRoles`); :func:`scene_metrics` turns a
trajectory (simulate.py) into the metrics listed in :data:`METRICS`, the
needle-handover results of sources A.6:

* impact: the first time the ``impact`` contact closes (x2 reaches H); impact velocity = x2' then;
* lag = x_driven - x_follower > 1 um, starting before the impact (after it the stop holds the
  follower back); it lasts until the first time after its onset that x_follower' catches up
  with x_driven';
* remaining gap N = N - (x3 - x2), its minimum before the impact (on the output grid, and between
  the output points either side of the grid's minimum on the finer grid of ``refine``); premature release = gap N closed (remaining gap < 1 um) before the impact, or the needle
  released before the impact (the gap then closed between output points);
* release: the first time the grip's condition ends (x1 - x3 > M).

The source does not state these definitions exactly; these are ours. Events are
located in two steps: a sign change between output points (<= 0.25 deg apart, 0.06 deg
in move 1 of the reference problem), then the state at the output point before it is
integrated again over that interval on a grid 200 times finer (``refine``, given by
simulate.py) and the crossing is interpolated there (cubic Hermite for positions,
linear for velocities): far better than 0.1 deg, and independent of the output spacing
(tested).

The model (model.py) imports :class:`EventRoles` and :data:`ROLE_KINDS` from here;
this module imports nothing of the package.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

LAG_THRESHOLD = 1e-6  # m: x_driven - x_follower above this is a lag (contacts deflect ~1e-8 m)
GAP_CLOSED = 1e-6  # m: a remaining gap N below this is closed


# --------------------------------------------------------------------------- roles and metrics as data


@dataclass(frozen=True)
class EventRoles:
    """Which elements define the needle-handover results (sources A.6 definitions).

    * ``impact``: the contact whose first closing is the impact; its first body is the follower
      that hits the stop (the control member);
    * ``follower``: the body whose lag behind the driven body is reported (lag = x_driven - x_follower);
    * ``gap``: the contact whose remaining gap is reported (gap N: ``gap - (x_a - x_b)``);
    * ``release``: the grip whose acts_while condition ending is the release of the needle.
    Any of them may be empty.
    """

    impact: str | None = None
    follower: str | None = None
    gap: str | None = None
    release: str | None = None


#: What each role of ``[model.events]`` names: a body or an element of these kinds (file order).
ROLE_KINDS: dict[str, tuple[str, ...]] = {"impact": ("contact",), "follower": ("body",), "gap": ("contact",),
                                          "release": ("grip",)}


@dataclass(frozen=True)
class Metric:
    """One result of a simulated cycle: its key (unit-suffixed, as in the JSON report), the role it
    needs (it stays at ``default`` when the scene lacks it) and what it means."""

    key: str
    role: str | None
    meaning: str
    default: object = None


#: The metrics of :func:`scene_metrics`, in report order.
METRICS: tuple[Metric, ...] = (
    Metric("impact_velocity_m_s", "impact", "velocity of the impact contact's first body when the contact first closes"),
    Metric("impact_angle_deg", "impact", "cam angle of the impact"),
    Metric("lag", "follower", "the follower lags the driven body by more than LAG_THRESHOLD before the impact", False),
    Metric("lag_onset_angle_deg", "follower", "cam angle where the lag starts"),
    Metric("lag_end_angle_deg", "follower", "cam angle where the follower's velocity catches up with the driven body's"),
    Metric("max_lag_mm", "follower", "largest x_driven - x_follower before the impact (0 if never positive)"),
    Metric("gap_N_mm", "gap", "the gap of the gap contact in the model"),
    Metric("min_gap_N_mm", "gap", "smallest remaining gap before the impact (output grid, refined around its minimum)"),
    Metric("release_angle_deg", "release", "cam angle where the release grip's condition ends"),
    Metric("premature_release", "gap", "gap closed (or grip released) before the impact; None without an impact"),
    Metric("peak_pad_force_N", "impact", "peak force of the impact contact (located between the output points)"),
    Metric("peak_drive_force_N", None, "peak force the drive supplies to the driven body (located between the output "
                                       "points)"),
    Metric("peak_contact_forces_N", None, "peak force of each element of the scene (located between the output points)"),
    Metric("peak_drive_force_angle_deg", None, "cam angle of the drive force's peak"),
    Metric("peak_contact_force_angles_deg", None, "cam angle of each element's peak force"),
    Metric("peak_drive_force_error_pct", None, "estimated error of the drive force's peak: its window integrated again "
                                               "at 1/100 of the tolerances (None: not estimated)"),
    Metric("peak_contact_force_errors_pct", None, "estimated error of each element's peak, as for the drive force"),
    Metric("peak_forces_converged", None, "every peak's estimated error within 1 % (None: not estimated); the "
                                          "peaks that are not are named in unconverged_peaks"),
    Metric("unconverged_peaks", None, "the peaks whose estimated error is above 1 % ('drive' for the drive force)", ()),
)
METRIC_KEYS: tuple[str, ...] = tuple(mt.key for mt in METRICS)


# --------------------------------------------------------------------------- event location


def _hermite(t0, t1, y0, y1, d0, d1, tq):
    h = t1 - t0
    s = (tq - t0) / h
    h00, h10 = 2 * s**3 - 3 * s**2 + 1, s**3 - 2 * s**2 + s
    h01, h11 = -2 * s**3 + 3 * s**2, s**3 - s**2
    return h00 * y0 + h10 * h * d0 + h01 * y1 + h11 * h * d1


def _rising_crossing(t, y, dy, start: float = -math.inf):
    """First time ``>= start`` where ``y`` rises through 0 (``y < 0`` before, ``>= 0`` after),
    located on the cubic Hermite interpolant of ``(y, dy)``; returns ``(time, index)`` or None."""
    ok = (y[:-1] < 0) & (y[1:] >= 0) & (t[1:] > t[:-1]) & (t[1:] >= start)
    idx = np.flatnonzero(ok)
    if idx.size == 0:
        return None
    i = int(idx[0])
    lo, hi = max(t[i], start), t[i + 1]
    args = (t[i], t[i + 1], y[i], y[i + 1], dy[i], dy[i + 1])
    if _hermite(*args, lo) >= 0:
        return lo, i
    for _ in range(60):
        mid = 0.5 * (lo + hi)
        if _hermite(*args, mid) >= 0:
            hi = mid
        else:
            lo = mid
    return hi, i


def _linear(t, y, tq, i):
    return float(y[i] + (y[i + 1] - y[i]) * (tq - t[i]) / (t[i + 1] - t[i]))


def _event(S, y, dy, refine=None, start: float = -math.inf):
    """First rising zero of ``y(S)`` (slope ``dy(S)``) on the output grid of series ``S``, then located
    again on the finely re-integrated interval (``refine(i)``); returns ``(time, series, index)``."""
    hit = _rising_crossing(S.t, y(S), dy(S), start)
    if hit is None:
        return None
    t_hit, i = hit
    local = refine(i) if refine is not None else None
    if local is not None:
        sub = _rising_crossing(local.t, y(local), dy(local), start)
        if sub is not None:
            return sub[0], local, sub[1]
    return t_hit, S, i


def _refined_min(refine, i, n, t_end, y) -> float:
    """Smallest ``y`` on the finely re-integrated output intervals either side of output point ``i``
    (up to time ``t_end``); inf where nothing can be refined."""
    low = math.inf
    for k in (i - 1, i):
        local = refine(k) if 0 <= k < n - 1 else None
        if local is not None:
            values = y(local) if t_end is None else y(local)[local.t <= t_end]
            if values.size:
                low = min(low, float(np.min(values)))
    return low


# --------------------------------------------------------------------------- metrics


def scene_metrics(r, sc, refine=None, peaks=None) -> dict:
    """The metrics of :data:`METRICS` from a trajectory (None where not defined).

    ``r``: a :class:`~strokeopt.contact.simulate.SceneResult` (its ``remaining_gap`` is set here);
    ``sc``: its scene. ``refine(i)``: the trajectory re-integrated finely inside output interval
    ``i`` (events are located there); without it events are interpolated on the output grid.
    ``peaks``: element name (None for the drive force) -> :class:`~strokeopt.contact.peaks.Peak`,
    located between the output points (peaks.py); without them the peaks are the output grid's maxima.
    """
    model = sc.model
    roles = model.events
    t = r.t
    deg = 360.0 / r.period

    def px(S, b):
        return np.zeros_like(S.t) if b == "frame" else S.positions[b]

    def pv(S, b):
        return np.zeros_like(S.t) if b == "frame" else S.velocities[b]

    m = {mt.key: mt.default for mt in METRICS}
    t_imp = None
    closed_before_impact = False
    els = model.elements
    if roles.impact and roles.impact in sc.elements:
        el = els[roles.impact]
        ba, bb = el.bodies
        hit = _event(r, lambda S: px(S, ba) - px(S, bb) + el.offset, lambda S: pv(S, ba) - pv(S, bb), refine)
        if hit is not None:
            t_imp, S, i = hit
            m["impact_angle_deg"] = float(t_imp * deg)
            m["impact_velocity_m_s"] = _linear(S.t, S.velocities[ba], t_imp, i)
        m["peak_pad_force_N"] = float(peaks[roles.impact].value if peaks else np.max(np.abs(r.forces[roles.impact])))
    f = roles.follower
    d = sc.driven
    if f and f in sc.bodies and f != d:
        lag = r.positions[d] - r.positions[f]
        m["max_lag_mm"] = max(0.0, float(np.max(lag if t_imp is None else lag[t <= t_imp]))) * 1e3
        onset = _event(r, lambda S: S.positions[d] - S.positions[f] - LAG_THRESHOLD,
                       lambda S: S.velocities[d] - S.velocities[f], refine)
        if onset is not None and (t_imp is None or onset[0] < t_imp):  # after the impact the stop holds it back
            m["lag"] = True
            m["lag_onset_angle_deg"] = float(onset[0] * deg)
            end = _event(r, lambda S: S.velocities[f] - S.velocities[d],
                         lambda S: S.accelerations[f] - S.accelerations[d], refine, start=onset[0])
            if end is not None:
                m["lag_end_angle_deg"] = float(end[0] * deg)
    if roles.gap and roles.gap in sc.elements:
        el = els[roles.gap]
        ba, bb = el.bodies
        remaining = -(px(r, ba) - px(r, bb) + el.offset)
        m["gap_N_mm"] = el.gap * 1e3
        r.remaining_gap = remaining
        before = remaining if t_imp is None else remaining[t <= t_imp]
        smallest = float(np.min(before))
        if refine is not None:  # the gap closes for microseconds: look between the output points around it
            smallest = min(smallest, _refined_min(refine, int(np.argmin(before)), len(t), t_imp,
                                                  lambda S: -(px(S, ba) - px(S, bb) + el.offset)))
        m["min_gap_N_mm"] = smallest * 1e3
        closed_before_impact = smallest < GAP_CLOSED
    if roles.release:
        el = els[roles.release]
        p, q, off = el.acts_while
        if p in sc.bodies and q in sc.bodies:  # a condition between bodies of the scene, even if the grip is not built
            rel = _event(r, lambda S: -(px(S, p) - px(S, q) + off), lambda S: -(pv(S, p) - pv(S, q)), refine)
            if rel is not None:
                m["release_angle_deg"] = float(rel[0] * deg)
                if t_imp is not None and rel[0] < t_imp:
                    closed_before_impact = True  # released before the impact: the gap closed between output points
    if m["gap_N_mm"] is not None and t_imp is not None:
        m["premature_release"] = closed_before_impact
    if not peaks:
        m["peak_drive_force_N"] = float(np.max(np.abs(r.drive_force)))
        m["peak_contact_forces_N"] = {e: float(np.max(np.abs(fv))) for e, fv in r.forces.items()}
        return m
    m["peak_drive_force_N"] = peaks[None].value
    m["peak_contact_forces_N"] = {e: peaks[e].value for e in r.forces}
    m["peak_drive_force_angle_deg"] = peaks[None].t * deg
    m["peak_contact_force_angles_deg"] = {e: peaks[e].t * deg for e in r.forces}
    if any(p.error is not None for p in peaks.values()):

        def pct(p):
            return None if p.error is None else 100.0 * p.error

        m["peak_drive_force_error_pct"] = pct(peaks[None])
        m["peak_contact_force_errors_pct"] = {e: pct(peaks[e]) for e in r.forces}
        m["unconverged_peaks"] = tuple("drive" if e is None else e for e, p in peaks.items() if p.converged is False)
        unknown = any(p.converged is None for p in peaks.values())
        m["peak_forces_converged"] = False if m["unconverged_peaks"] else (None if unknown else True)
    return m
