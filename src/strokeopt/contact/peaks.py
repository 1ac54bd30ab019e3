"""Peak forces located between the output points, and an estimate of how accurate each is.

A stiff contact (1e9 N/m on a few grams) acts for microseconds: its force spikes fall between
the output points of a cycle (37-170 us apart in the reference problem), so a peak read off the
output grid is whatever point happened to land on a spike (c32 of the release scene: 17 N at
the default tolerance, 694 N at rtol 1e-8; the spike is 2301 N at both). The integrator resolves
the spikes (it has to, to keep its error); they are only not sampled. :func:`locate_peaks` finds
them, for every element of the scene and for the drive force:

1. **Screening.** Between two output points a body's velocity changes by the integral of its
   acceleration; the trapezoid of the accelerations at the two points misses whatever acted
   between them: a body's *unresolved impulse* ``J = m (dv - h (a0 + a1) / 2)``. A spike of an
   element of stiffness ``k`` between bodies of reduced mass ``m*`` is a half sine of duration
   ``pi sqrt(m*/k)``, so its impulse bounds its height: ``F <= J / 2 sqrt(k/m*)`` (the larger of
   the two bodies' impulses; twice that where the element acts at an end of the interval, which may
   then hold only the half of the spike from its crest on or up to it; the drive force adds those
   of the elements on the driven body); a
   soft element's spring force drifts no more than ``k`` times its compression's stroke in the
   interval; an element that starts acting inside it may jump by its damping times the relative
   velocity (a grip: and its spring on the stretch it takes hold of); an element that cannot reach
   its switching point in the interval does not act there. An output interval is refined while
   that bound passes an element's peak found so far by more than :data:`GAIN`, the largest share
   first (at most :data:`MAX_REFINEMENTS`; a peak with candidates left is not converged).
2. **Refinement.** The interval is integrated again from the state at its start on
   :func:`peak_points` points (dense output: CVODES interpolates them); the peak is the vertex of
   the parabola through the largest sample and its neighbours (the sample itself at a jump), and
   where the samples are still coarse against the element's contact period, the two sub-intervals
   around it are integrated again.
3. **Accuracy.** Each peak is found again at 1/100 of the tolerances (:data:`TIGHTER`): its stroke
   piece is integrated at those tolerances from its start up to the output interval before the
   peak's, and the three output intervals around the peak from there, sampled as densely as the
   refinement; the difference is the peak's error estimate, and a peak whose estimate is above
   :data:`PEAK_TOLERANCE` is not converged: the result names it. The estimate covers the spike
   itself, the error carried into it from earlier in its piece (the impacts before it in a chain:
   in the release at 1200 spm, c32's spike is 0.5 % low at the default tolerance because the
   chain shell -> cage -> control member arrives a little differently; an estimate from the state
   at the interval's start gave 0.0002 %) and a spike the tighter run moves across an output
   point; not an error carried over from an earlier stroke piece (the pieces start at rest or in
   a dwell, where the contacts have settled).

Measured (tests/contact/test_contact_peaks.py, tests/contact/test_hard_cases.py): at the default tolerance every
peak of the release scene (500, 600 and 1200 spm) and of the hard cases is within 1 % of the same scene at rtol
1e-10 or marked not converged, and within 1 % of a brute-force run on 200 000 output points per stroke piece
(release, 500 spm); the estimates match the errors (release at 1200 spm: c32 0.49 % estimated, 0.49 % off;
c31 0.34 and 0.33 %; c13 0.20 and 0.20 %). The scene takes about 2 times its CPU time without the peaks in the
release scene (``strokeopt bench --only simulate_peaks``), 4-5 times in the handover scene (its 0.2 g needle
chatters: about 50 intervals refined, and both moves integrated again at the tighter tolerances).

:func:`locate_peaks` works on arrays and a re-integration callback; :func:`scene_peaks` hands it a scene's
trajectory and its stepper's integrators (simulate.py calls it).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .model import FRAME

PEAK_POINTS = 200  # points an output interval is integrated on again to find a peak in it (at least)
MAX_PEAK_POINTS = 2000  # (at most: shorter spikes are refined once more around their largest sample)
PARTIAL = 2.0  # a spike's height per impulse where the interval may hold only part of it (its crest to an end)
GAIN = 0.002  # an interval is refined if its bound passes a peak found so far by more than this share of it
PEAK_TOLERANCE = 0.01  # a peak whose estimated error is above this share of it is not converged
TIGHTER = 100.0  # the accuracy re-run divides rtol and atol by this
MAX_REFINEMENTS = 120  # output intervals refined per cycle at most (the screening's bound orders them)
SAMPLES_PER_SPIKE = 6  # below this many samples per contact half-period, the peak's neighbourhood is refined again


@dataclass
class Peak:
    """The largest |force| of one element (or of the drive) over the cycle.

    ``value`` N; ``t`` s; ``error``: estimated relative error (None: not estimated);
    ``converged``: ``error <= PEAK_TOLERANCE`` (None: not estimated)."""

    value: float
    t: float
    error: float | None = None
    converged: bool | None = None
    interval: int = -1  # output interval it lies in (-1: at an output point)


@dataclass(frozen=True)
class Quantity:
    """One force the peaks are located of: an element or the drive.

    ``spike``: ``sqrt(k/m*) / 2``, a spike's height per unresolved impulse (1/s; 0: not screened);
    ``half_period``: the shortest spike it can have, ``pi sqrt(m*/k)`` (s); ``bodies``: the bodies with
    states whose unresolved impulse bounds its spikes (a rider's host for a rider)."""

    name: str
    spike: float
    half_period: float
    bodies: tuple[str, ...] = ()
    stiffness: float = 0.0

    @classmethod
    def of_contact(cls, name: str, k: float, mass: float, bodies) -> "Quantity":
        """An element of stiffness ``k`` between bodies of reduced mass ``mass`` (inf: both fixed or driven)."""
        if not (k > 0 and 0 < mass < math.inf):
            return cls(name, 0.0, math.inf, tuple(bodies), k)
        return cls(name, 0.5 * math.sqrt(k / mass), math.pi * math.sqrt(mass / k), tuple(bodies), k)


def peak_points(longest: float, shortest: float) -> int:
    """Points to integrate an output interval on so that the shortest spike gets SAMPLES_PER_SPIKE of them
    in the longest output interval (within PEAK_POINTS and MAX_PEAK_POINTS)."""
    if not (shortest > 0 and math.isfinite(shortest)):
        return PEAK_POINTS
    return int(min(max(math.ceil(SAMPLES_PER_SPIKE * longest / shortest), PEAK_POINTS), MAX_PEAK_POINTS))


def _vertex(t, y, j):
    """Peak of samples ``y`` at ``t`` near their largest ``y[j]``: the vertex of the parabola through
    ``j-1, j, j+1`` when it is concave there and lies between them, else the sample."""
    if 0 < j < len(y) - 1:
        y0, y1, y2 = y[j - 1], y[j], y[j + 1]
        den = y0 - 2 * y1 + y2
        if den < 0 and min(y0, y2) >= 0.5 * y1:  # smooth there (not a jump: a contact closing with damping)
            d = 0.5 * (y0 - y2) / den
            if abs(d) <= 0.5:
                h = t[j + 1] - t[j]
                return float(y1 - 0.25 * (y0 - y2) * d), float(t[j] + d * h)
    return float(y[j]), float(t[j])


def unresolved_impulse(t, velocities, accelerations, inertia) -> np.ndarray:
    """Per output interval, ``|m (dv - h (a0 + a1)/2)|`` of one body (N s; 0 across a stroke joint)."""
    h = np.diff(t)
    j = np.abs(inertia * (np.diff(velocities) - 0.5 * h * (accelerations[1:] + accelerations[:-1])))
    j[h <= 0] = 0.0
    return j


def locate_peaks(t, grid_values, quantities, impulses, driven_terms, refine, may_act=None, jumps=None, carry=None):
    """The peak of every quantity over the cycle (a list of :class:`Peak`, in the order of ``quantities``).

    ``grid_values``: |value| on the output grid, one row per quantity; ``impulses``: body -> unresolved
    impulse per output interval; ``driven_terms``: indices of the quantities whose spikes load the
    quantity ``driven_terms[0]`` (the drive): ``(drive index, [element indices])`` or None;
    ``may_act``: per element (the first rows of ``quantities``) and output interval, whether it can act
    there at all (no spike where it cannot; None: everywhere); ``jumps``: per element and output interval,
    the largest value its force can jump to there (damping, a grip taking hold) and how far its spring
    force can move at most (stiffness times the largest stroke of its compression in the interval): a
    ``(jump, drift)`` pair of arrays, or None;
    ``refine(i, sa, sb, z0, tight)``: the re-integration of output interval ``i`` from ``sa`` to ``sb``
    (interval fractions, 0-1; ``z0``: a state inside it or None for the output point ``i``) returning
    ``(times, |values| per quantity, states)``; ``carry(i)``: ``(z, sa, sb)``, the window around output
    interval ``i`` a peak in it is estimated on (fractions of the interval: its neighbours in the same stroke
    piece) and the state at its start ``sa`` integrated at tighter tolerances from the start of the piece
    (None where that fails; ``carry`` None: no accuracy estimate, ``refine`` cannot re-run tighter).
    """
    nq, npts = grid_values.shape
    h = np.diff(t)
    peaks = []
    for q in range(nq):
        j = int(np.argmax(grid_values[q]))
        peaks.append(Peak(float(grid_values[q, j]), float(t[j]), interval=-1))
    # bound of each quantity in each output interval: its larger end value plus what its impulse allows
    ends = np.maximum(grid_values[:, :-1], grid_values[:, 1:])
    spike = _spike_bounds(quantities, impulses, grid_values)
    if jumps is not None:
        jump, drift = jumps
        spike[:len(jump)] = np.minimum(spike[:len(jump)], drift) + jump
    if may_act is not None:
        spike[:len(may_act)] = np.where(may_act, spike[:len(may_act)], 0.0)
    if driven_terms is not None:
        d, terms = driven_terms
        spike[d] = spike[terms].sum(axis=0) if terms else 0.0
    bound = ends + spike
    bound[:, h <= 0] = 0.0

    def found():
        return np.array([p.value for p in peaks]) * (1 + GAIN) + 1e-9

    # candidates: intervals where some quantity may pass the peak found so far; the one whose bound passes
    # it by the largest share first (the peaks found prune the rest)
    left = np.flatnonzero(np.any(bound > found()[:, None], axis=0))
    refined = 0
    unscreened = set()
    while left.size:
        share = np.max(bound[:, left] / found()[:, None], axis=0)
        keep = share > 1
        left, share = left[keep], share[keep]
        if not left.size:
            break
        if refined >= MAX_REFINEMENTS:
            unscreened = {q for q in range(nq) if np.any(bound[q, left] > found()[q])}
            break
        k = int(np.argmax(share))
        i = int(left[k])
        left = np.delete(left, k)
        refined += 1
        for q, (value, tq) in enumerate(_refined_peaks(refine, i, quantities, False)):
            if value > peaks[q].value:
                peaks[q] = Peak(value, tq, interval=i)
    if carry is not None:
        _estimate_errors(t, peaks, quantities, refine, carry, unscreened)
    return peaks, refined


def _spike_bounds(quantities, impulses, grid_values):
    """Per quantity and output interval, how high a spike of it can rise there above its larger end value.

    A spike of an element is a half sine of duration ``pi sqrt(m*/k)``: its impulse ``I`` bounds its height,
    ``F <= I sqrt(k/m*) / 2`` (``Quantity.spike``), the impulse being the larger unresolved impulse of its two
    bodies. Where the element acts at an end of the interval, the interval may hold only part of the spike,
    from its crest on or up to it: half the impulse, so twice the height (:data:`PARTIAL`). Without that, a
    spike astride an output point was bounded below its crest and never refined (the release at 1200 spm: c32
    13 388 N at the default tolerance, 14 042 N at rtol 1e-10, the crest 4.7 % above the bound)."""
    spike = np.zeros((grid_values.shape[0], grid_values.shape[1] - 1))
    acts = (grid_values[:, :-1] > 0) | (grid_values[:, 1:] > 0)
    for q, qt in enumerate(quantities):
        if qt.spike > 0 and qt.bodies:
            impulse = np.max([impulses[b] for b in qt.bodies], axis=0)
            spike[q] = qt.spike * np.where(acts[q], PARTIAL, 1.0) * impulse
    return spike


def _refined_peaks(refine, i, quantities, tight, sa=0.0, sb=1.0, z0=None, deeper=True):
    """Peak (value, time) of each quantity in output interval ``i`` between fractions ``sa`` and ``sb``,
    integrated again from ``z0`` (None: the output point's state); where the samples are coarse against a
    quantity's spikes, refined once more (``deeper``)."""
    got = refine(i, sa, sb, z0, tight)
    if got is None:  # the tighter re-run failed: no estimate
        return None
    ts, values, states = got
    out = []
    step = (sb - sa) / (len(ts) - 1)
    dt = ts[1] - ts[0]
    for q, qt in enumerate(quantities):
        j = int(np.argmax(values[q]))
        value, tq = _vertex(ts, values[q], j)
        if deeper and dt * SAMPLES_PER_SPIKE > qt.half_period and values[q, j] > 0:
            a = max(j - 1, 0)
            b = min(j + 1, len(ts) - 1)
            got = refine(i, sa + a * step, sa + b * step, states[:, a], tight)
            if got is None:
                return None
            sub = got[1]
            k = int(np.argmax(sub[q]))
            tsub = np.linspace(ts[a], ts[b], sub.shape[1])
            v2, t2 = _vertex(tsub, sub[q], k)
            if v2 > value:
                value, tq = v2, t2
        out.append((value, tq))
    return out


def _estimate_errors(t, peaks, quantities, refine, carry, unscreened):
    """Each peak's window integrated again at tighter tolerances, from a state integrated at those tolerances
    from the start of its stroke piece (``carry``): the difference is its error estimate, the error made in the
    spike and the error carried into it from earlier in the piece (the impacts before it in a chain)."""
    windows = {}
    for q, p in enumerate(peaks):
        if p.value <= 0:
            p.error, p.converged = 0.0, True
            continue
        i = p.interval if p.interval >= 0 else max(int(np.searchsorted(t, p.t)) - 1, 0)
        windows.setdefault(i, []).append(q)
    for i, qs in sorted(windows.items()):
        z0, fa, fb = carry(i)
        tight = None if z0 is None else _refined_peaks(refine, i, quantities, True, fa, fb, z0)
        if tight is None:  # the tighter re-run failed there: not estimated
            continue
        for q in qs:
            value = tight[q][0]
            p = peaks[q]
            p.error = abs(p.value - value) / max(value, p.value)
            p.converged = p.error <= PEAK_TOLERANCE and q not in unscreened


def _quantities(sc, result) -> list[Quantity]:
    """The scene's elements and the drive force as peaks.py sees them: spike height per unresolved impulse
    and shortest spike, from each element's stiffness (a force law's at the largest compression on the grid)
    and the reduced mass of its bodies (a fixed or driven body counts as infinitely heavy)."""
    model = sc.model
    free = set(sc.free_bodies)

    def state_body(b):
        if b in free:
            return b
        host = model.bodies[b].rides_on if b in model.bodies else None
        return host if host in free else None

    inertia = {b: model.reduced_inertia(b) for b in free}
    out = []
    for name in sc.elements:
        el = model.elements[name]
        bodies = [state_body(b) for b in el.bodies]
        bodies = tuple(b for b in bodies if b is not None)
        inv = sum(1.0 / inertia[b] for b in bodies)
        mass = 1.0 / inv if inv > 0 else math.inf
        k = el.stiffness
        if el.force_law is not None:  # its tangent stiffness at the largest compression reached
            a, b = el.bodies
            pa = result.positions[a] if a in result.positions else 0.0
            pb = result.positions[b] if b in result.positions else 0.0
            c = max(float(np.max(pa - pb + el.offset)), 0.0)
            coeffs = el.force_law.coefficients
            k = abs(sum(i * ci * c ** (i - 1) for i, ci in enumerate(coeffs) if i > 0))
        out.append(Quantity.of_contact(name, k, mass, bodies))
    on_driven = [i for i, name in enumerate(sc.elements) if sc.driven in model.elements[name].bodies]
    shortest = min((out[i].half_period for i in on_driven), default=math.inf)
    out.append(Quantity("drive", 0.0, shortest))
    return out


def scene_peaks(sc, ode, result, Z, S, P, stepper) -> dict:
    """Peaks of every element force and of the drive force of a simulated cycle (``result``, its states ``Z`` at
    ``S`` in the pieces ``P``; simulate.py), located between the output points with ``stepper``'s integrators.
    Returns element name (None: the drive force) -> :class:`Peak`."""
    quantities = _quantities(sc, result)
    grid = np.abs(np.vstack([result.forces[e] for e in sc.elements] + [result.drive_force]))
    model = sc.model
    impulses = {b: unresolved_impulse(result.t, result.velocities[b], result.accelerations[b], model.reduced_inertia(b))
                for b in sc.free_bodies}
    on_driven = [i for i, name in enumerate(sc.elements) if sc.driven in model.elements[name].bodies]
    may_act, jumps = _screening(sc, ode, result, Z, S, P, impulses, [q.stiffness for q in quantities])
    forces, maps = ode.forces, {}
    window = getattr(stepper, "window", None)
    starts = np.zeros(len(S), dtype=int)
    for i in range(1, len(S)):
        starts[i] = starts[i - 1] if S[i] > S[i - 1] else i

    h = np.diff(result.t)
    points = peak_points(float(np.max(h)) if h.size else 0.0, min(q.half_period for q in quantities))

    def refine(i, fa, fb, z0, tight):
        pk = P[:, i]
        sa = S[i] + fa * (S[i + 1] - S[i])
        sb = S[i] + fb * (S[i + 1] - S[i])
        z = Z[:, i] if z0 is None else z0
        span = max(1, round(fb - fa))  # output intervals (a window of the estimate: as densely sampled as one)
        zs = window(pk, z, sa, sb, tight, span * points) if window is not None else stepper.segment(pk, z, sa, sb)
        if zs is None:
            return None
        ss = np.linspace(sa, sb, zs.shape[1])
        mapped = maps.get(zs.shape[1]) or maps.setdefault(zs.shape[1], forces.map(zs.shape[1]))
        values = np.abs(np.asarray(mapped(ss[None, :], zs, np.tile(pk[:, None], (1, len(ss))))))
        return pk[1] + ss * pk[2], values, zs

    carried = {}  # stroke piece's first output point -> (the last output point carried to, its state)

    n = len(S)

    def carry(i):
        """Output interval ``i`` and its neighbours in the same stroke piece (a spike the tighter run moves
        across an output point stays inside) as fractions of interval ``i``, and the state at the window's
        start integrated at the tighter tolerances from the start of the piece (on from the last point
        carried to in the same piece; None where the integrator fails)."""
        def same_piece(j):
            return 0 <= j < n and starts[j] == starts[i] and (j == starts[i] or S[j] > S[j - 1])

        first = i - 1 if same_piece(i - 1) else i
        last = i + 2 if same_piece(i + 2) else i + 1
        a, z = carried.get(starts[i], (starts[i], Z[:, starts[i]]))
        if z is None or a > first:
            a, z = starts[i], Z[:, starts[i]]
        if first > a:
            zs = window(P[:, i], z, S[a], S[first], True, points)
            z = None if zs is None else zs[:, -1]
        carried[starts[i]] = (first, z)
        width = S[i + 1] - S[i]
        return z, (S[first] - S[i]) / width, (S[last] - S[i]) / width

    estimate = window is not None and getattr(getattr(stepper, "opts", None), "estimate", True)
    peaks, refined = locate_peaks(result.t, grid, quantities, impulses, (len(quantities) - 1, on_driven), refine,
                                  may_act, jumps, carry=carry if estimate else None)
    result.stats["peak_refinements"] = refined
    return {q.name if i < len(sc.elements) else None: p for i, (q, p) in enumerate(zip(quantities, peaks))}


def _screening(sc, ode, result, Z, S, P, impulses, stiffness) -> tuple[np.ndarray, tuple]:
    """Per element and output interval: whether the element can act somewhere in it; the largest force it
    can jump to there where it starts acting inside the interval: its damping on the relative velocity of
    its bodies (a grip: and its spring on their stretch); and how far its spring force can drift: its
    ``stiffness`` times that relative velocity times the interval (what binds a soft element). A switching function (>= 0 while the element acts) rises between two output
    points at most by its larger rate at them plus the velocity the unresolved impulses add, times the
    interval (with a quarter to spare)."""
    model = sc.model
    t = result.t
    h = np.diff(t)
    sw, rate = (np.asarray(v) for v in ode.switch_rates.map(Z.shape[1])(S[None, :], Z, P))
    free = set(sc.free_bodies)
    unresolved = {FRAME: 0.0, sc.driven: 0.0}
    for b in sc.bodies:
        host = b if b in free else model.bodies[b].rides_on
        if host in impulses:
            unresolved[b] = impulses[host] / model.reduced_inertia(host)

    def ends(x):
        return np.maximum(np.abs(x[1:]), np.abs(x[:-1]))

    def of(series, b):
        return series[b] if b != FRAME else np.zeros_like(t)

    may_act = np.zeros((len(sc.elements), len(h)), dtype=bool)
    jumps = np.zeros((len(sc.elements), len(h)))
    drift = np.zeros((len(sc.elements), len(h)))
    for k, name in enumerate(sc.elements):
        el = model.elements[name]
        kick = sum(unresolved.get(b, 0.0) for b in el.body_names)
        may_act[k] = 0.5 * (sw[k, 1:] + sw[k, :-1] + 1.25 * (ends(rate[k]) + kick) * h) >= 0
        starts = may_act[k] & (np.minimum(sw[k, 1:], sw[k, :-1]) < 0)
        a, b = el.bodies
        dv = ends(of(result.velocities, a) - of(result.velocities, b)) + kick
        jump = np.where(starts, el.damping * dv, 0.0)
        if el.kind == "grip":  # it takes hold of whatever stretch the two bodies have then
            stretch = ends(of(result.positions, a) - of(result.positions, b)) + dv * h
            jump = jump + np.where(starts, np.abs(el.elastic_force(stretch)), 0.0)
        jumps[k] = np.where(may_act[k], jump, 0.0)
        drift[k] = stiffness[k] * dv * h
    return may_act, (jumps, drift)
