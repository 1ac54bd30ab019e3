"""Simulating a scene over one cycle with CasADi's SUNDIALS integrators, and its results.

:func:`simulate_scene` integrates the scene's ODE (scene.py) with its driven
body following a :class:`~strokeopt.stroke.StrokeFunction` (a classic law or an
optimised stroke) over one cycle, from rest at x = 0, and returns a
:class:`SceneResult`: the trajectory on a fine output grid, the element and
drive forces, and the needle-handover results of sources A.6:

* impact: the first time the ``impact`` contact closes (x2 reaches H); impact velocity = x2' then;
* lag = x_driven - x_follower > 1 um, starting before the impact (after it the stop holds the
  follower back); it lasts until the first time after its onset that x_follower' catches up
  with x_driven';
* remaining gap N = N - (x3 - x2), its minimum before the impact (on the output grid);
  premature release = gap N closed (remaining gap < 1 um) before the impact, or the needle
  released before the impact (the gap then closed between output points);
* release: the first time the grip's condition ends (x1 - x3 > M).

The source does not state these definitions exactly; these are ours. Events are
located in two steps: a sign change between output points (<= 0.25 deg apart, 0.06 deg
in move 1 of the reference problem), then the state at the output point before it is
integrated again over that interval on a grid 200 times finer and the crossing is
interpolated there (cubic Hermite for positions, linear for velocities): far better than
0.1 deg, and independent of the output spacing (tested).

How it is integrated, and why (measured on this machine, release scene, 600 spm,
modified sine, one cycle, CasADi 3.8.2; `strokeopt simulate ... --study tolerance`
prints the full table):

* one integrator object, restarted at every joint of the stroke (known-time
  discontinuities) with the piece index as a parameter, time normalised per piece, a
  fine output grid inside each call (output points cost almost nothing: CVODES
  interpolates them);
* hard ``if_else`` contact switches with CVODES (BDF) in one call per stroke piece: the
  error in impact velocity falls with the tolerance, 1e-4 m/s at the default rtol 1e-5;
* BDF order limited to 2 (``max_order``): orders 3-5 are not A-stable and the lightly damped
  contact modes (1e5-1e6 rad/s, damping ratio ~0.01) made CVODES fail its error test over
  and over: 90 549 steps, 0.70 s at rtol 1e-6 with the default order 5, against 40 773 steps,
  0.36 s with order 2 (order 1: 293 128 steps, 1.76 s);
* smoothing the switches (softplus of width eps) converges to the hard result as eps
  shrinks (impact velocity bias 7.6e-4 m/s at eps = 1 um, 1.7e-4 m/s at 0.1 um, whatever the
  tolerance) but takes 1.7-2x the steps of the hard switches at every tolerance, so the
  default is the hard switches; smoothing stays available (``smoothing``) for gradients;
* IDAS gives the same answer at about twice the cost of CVODES; CVODES is the default;
* restarting the integrator at every detected contact switch (``restart_at_switches``:
  windows of 200 output points, the crossing located between them, integrated up to it and
  restarted there) is as accurate as one call across the switches but 5-10x slower (80 and
  more switches per cycle, each a cold BDF start): 1.5 s at rtol 1e-4, 1.9 s at 1e-6;
* CasADi's own event support (``zero`` in the DAE) was not used: experimental in 3.8, it
  fires on one crossing direction only in CVODES and not at all in IDAS (casadi/casadi#4393).

Measured (``strokeopt simulate problems/deco2000_needle_bar.toml --scene release --spm 600
--study tolerance`` with rtol down to 1e-8; reference rtol 1e-9: impact 2.8510 m/s at 45.994 deg,
release 54.469 deg, 2.63 s CPU; CPU time includes building the ODE and the integrators; the
machine was shared, so times carry +-30 %)::

    method  smoothing mm   rtol   impact v error m/s  release error deg   steps   CPU s
    cvodes  0              1e-4   5.5e-4              2.4e-3               8 127  0.14
    cvodes  0              1e-5   9.7e-5              5.8e-3              20 984  0.25
    cvodes  0              1e-6   1.6e-5              9.7e-4              40 773  0.37
    cvodes  0              1e-7   5.5e-6              3.2e-4              92 802  0.71
    cvodes  0              1e-8   9.7e-7              7.0e-5             200 447  1.35
    idas    0              1e-5   3.3e-5              7.9e-4              33 445  0.67
    idas    0              1e-6   1.3e-5              1.4e-3              85 270  1.46
    cvodes  1e-3           1e-5   7.3e-4              1.9e-2              34 368  0.34
    cvodes  1e-3           1e-8   7.8e-4              2.4e-2             346 048  2.74
    cvodes  1e-4           1e-5   1.3e-4              8.1e-4              37 916  0.45
    cvodes  1e-4           1e-8   1.8e-4              8.4e-4             416 037  3.16
    cvodes  restarts       1e-4   8.9e-4              1.4e-2              24 518  1.53
    cvodes  restarts       1e-6   7.2e-6              8.4e-4              84 099  1.79

scipy ``solve_ivp`` Radau on the same ODE (``strokeopt bench --only simulate_release``): rtol
1e-3 misses the impact velocity by 0.52 m/s (6.9 s); rtol 1e-4 reaches 5.8e-4 m/s in 10.3 s,
63x the CPU time of CVODES at the default tolerance (0.163 s, error 2.7e-5 m/s).
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field, replace

import casadi as ca
import numpy as np

from ..errors import ProblemError, SolverError

LAG_THRESHOLD = 1e-6  # m: x_driven - x_follower above this is a lag (contacts deflect ~1e-8 m)
GAP_CLOSED = 1e-6  # m: a remaining gap N below this is closed
METHODS = ("cvodes", "idas")


@dataclass(frozen=True)
class SimulationOptions:
    """How to integrate.

    ``rtol``/``atol`` go to the integrator; ``atol`` is in the scaled states (positions in mm,
    velocities in m/s). ``smoothing`` (m) = 0 for hard switches. ``resolution_deg``: output grid
    spacing in the longest stroke piece (shorter pieces get the same number of points, so a finer
    spacing). ``restart_at_switches``: integrate piecewise between detected contact switches
    (restarting the integrator at each) instead of across them; slower, kept for the
    comparison of the tolerance study. ``integrator_options`` pass straight to ``casadi.integrator``.
    ``verbose``: let SUNDIALS print its own messages (otherwise only the SolverError says why).
    """

    method: str = "cvodes"
    rtol: float = 1e-5
    atol: float = 1e-6
    smoothing: float = 0.0
    resolution_deg: float = 0.25
    max_num_steps: int = 200_000
    restart_at_switches: bool = False
    integrator_options: dict | None = None
    verbose: bool = False

    def check(self) -> None:
        if self.method not in METHODS:
            raise ProblemError("options", "method", f"{self.method!r} is not one of {', '.join(METHODS)}")
        for name in ("rtol", "atol", "resolution_deg"):
            value = getattr(self, name)
            if not (isinstance(value, (int, float)) and math.isfinite(value) and value > 0):
                raise ProblemError("options", name, f"must be a positive number, got {value!r}")
        if not (math.isfinite(self.smoothing) and self.smoothing >= 0):
            raise ProblemError("options", "smoothing", f"must be zero (hard switches) or positive, got {self.smoothing!r}")


@dataclass
class SceneResult:
    """One simulated cycle: trajectory (SI, on the output grid), forces, results.

    ``positions``/``velocities``/``accelerations``: per body of the scene (the driven one
    included); ``forces``: per element of the scene (N, positive = compression);
    ``drive_force``: the force the drive must supply to the driven body, its inertia plus
    what the elements push back: ``m a - sum of element forces on it`` (N).

    Peak forces are maxima over the output grid. The pad's (a soft polynomial law) agree
    across tolerances; those of the 1e9 N/m contacts and the drive force they load are
    impact spikes microseconds long and depend on the grid and the tolerance: read them as
    orders of magnitude.
    """

    scene: str
    spm: float
    period: float
    t: np.ndarray
    positions: dict
    velocities: dict
    accelerations: dict
    forces: dict
    drive_force: np.ndarray
    metrics: dict
    cpu_time_s: float
    options: SimulationOptions
    driven: str = ""
    stats: dict = field(default_factory=dict)
    remaining_gap: np.ndarray | None = None  # m, of the model's gap contact (gap N), if in the scene
    stroke_label: str = ""

    @property
    def angle_deg(self) -> np.ndarray:
        return 360.0 * self.t / self.period

    def summary(self) -> dict:
        """JSON-ready results (unit-suffixed keys; None where an event does not happen)."""
        return {"scene": self.scene, "spm": self.spm, "stroke": self.stroke_label, **self.metrics,
                "cpu_time_s": self.cpu_time_s,
                "method": self.options.method, "rtol": self.options.rtol, "atol": self.options.atol,
                "smoothing_mm": self.options.smoothing * 1e3}

    def plot(self, path=None):
        """The figure of :func:`strokeopt.plots.plot_scene`; written to ``path`` when given."""
        from ..report.contact import plot_scene

        return plot_scene(self, path)


# --------------------------------------------------------------------------- integration


def _drive_reference(problem) -> tuple[float, float]:
    """``(sign, s_ref)`` of ``x_driven = sign * (s - s_ref)``: zero at the start of the handover move,
    positive in its direction (the first move if none is marked)."""
    moves = problem.timing.moves
    move = problem.timing.handover_move or moves[0]
    return (1.0 if move.stroke > 0 else -1.0), move.start_position


def _integrator(ode, opts: SimulationOptions, n_out: int, refine: bool = False):
    grid = np.linspace(0.0, 1.0, n_out + 1)
    dae = ode.refine_dae if refine else ode.dae
    # BDF order <= 2: the orders 3-5 are not A-stable, and the lightly damped contact modes
    # (1e5-1e6 rad/s, damping ratio ~0.01) made CVODES fail its error test over and over (4-10x more steps)
    iopts = {"abstol": opts.atol, "reltol": opts.rtol, "max_num_steps": opts.max_num_steps, "max_order": 2,
             "disable_internal_warnings": not opts.verbose}  # SUNDIALS prints "At t = ..." to stdout otherwise
    iopts.update(opts.integrator_options or {})
    return ca.integrator("scene_refine" if refine else "scene", opts.method, dae, 0.0, grid[1:], iopts), grid


#: SUNDIALS return flags in words (the SolverError says why instead of the raw flag).
_FLAG_WORDS = {
    "ERR_FAILURE": "the error test failed repeatedly (the step shrank to its minimum: the model is too stiff or "
                   "near-singular, e.g. a body of almost no mass)",
    "CONV_FAILURE": "the corrector did not converge (the step shrank to its minimum: the model is too stiff or "
                    "near-singular)",
    "TOO_MUCH_WORK": "max_num_steps reached",
    "TOO_MUCH_ACC": "the tolerances are tighter than the arithmetic allows",
}


def _why(exc: RuntimeError) -> str:
    text = str(exc).splitlines()[-1]
    for flag, words in _FLAG_WORDS.items():
        if flag in text:
            return words
    return text[:200]


def simulate_scene(problem, scene: str, spm: float | None = None, stroke=None,
                   options: SimulationOptions | None = None) -> SceneResult:
    """Integrate ``scene`` (a name of ``problem.scenes``) over one cycle at ``spm``.

    ``stroke``: any StrokeFunction (default: the problem's classic-law stroke at ``spm``); its
    period must be the cycle time at ``spm``. Raises ProblemError for bad input and SolverError
    when the integrator fails (with the reason).
    """
    opts = options or SimulationOptions()
    opts.check()
    if not problem.scenes:
        raise ProblemError(str(problem.file), "scenes", "the problem defines no [scenes.*] (and [model]) to simulate")
    if scene not in problem.scenes:
        raise ProblemError(str(problem.file), "scenes", f"no scene {scene!r}; the problem has: {', '.join(problem.scenes)}")
    spm = float(problem.spm if spm is None else spm)
    if not (math.isfinite(spm) and spm > 0):
        raise ProblemError("--spm", "", f"must be positive, got {spm!r}")
    sc = problem.scenes[scene]
    stroke = stroke if stroke is not None else problem.stroke(spm)
    period = problem.timing.period(spm)
    if abs(stroke.period - period) > 1e-9 * period:
        raise ProblemError(str(problem.file), "machine.spm", f"the stroke's period {stroke.period:g} s is not the cycle "
                                                             f"time {period:g} s at {spm:g} spm")
    cpu0 = time.process_time()
    sign, s_ref = _drive_reference(problem)
    ode = sc.build(stroke, sign, s_ref, opts.smoothing)
    spans = [p.duration for p in stroke.pieces]
    n_out = int(min(max(math.ceil(max(spans) / period * 360.0 / opts.resolution_deg), 20), 4000))
    if ode.state_size:
        integ, grid = _integrator(ode, opts, n_out)
    else:  # only the driven body: nothing to integrate
        integ, grid = None, np.linspace(0.0, 1.0, n_out + 1)

    def advance(k, piece, z, pk):
        try:
            res = integ(x0=z, p=pk)
        except RuntimeError as exc:
            raise SolverError(f"{opts.method} failed in stroke piece {k + 1} ({piece.label}) of scene {scene!r} at "
                              f"{spm:g} spm: {_why(exc)} (tighten or loosen the tolerances, "
                              f"or raise max_num_steps)") from None
        return np.asarray(res["xf"]), int(integ.stats().get("nsteps", 0) or 0)

    fine = {}

    def segment(pk, z0, sa, sb):
        if "f" not in fine:
            fine["f"] = _integrator(ode, opts, REFINE_POINTS, refine=True)[0]
            fine["nsteps"] = 0
        try:
            xf = np.asarray(fine["f"](x0=z0, p=np.concatenate([pk, [sa, sb]]))["xf"])
        except RuntimeError as exc:
            raise SolverError(f"{opts.method} failed between {sa:.6g} and {sb:.6g} of stroke piece {int(pk[0]) + 1} "
                              f"of scene {scene!r}: {_why(exc)}") from None
        fine["nsteps"] += int(fine["f"].stats().get("nsteps", 0) or 0)
        return np.hstack([np.asarray(z0, float)[:, None], xf])

    if opts.restart_at_switches:
        def advance(k, piece, z, pk):  # noqa: F811  (piecewise between detected switches)
            before = fine.get("nsteps", 0)
            sk, xf = _between_switches(ode, segment, z, pk)
            return sk, xf, fine["nsteps"] - before

    return _run(problem, sc, scene, spm, stroke, period, ode, grid, advance, segment, opts, cpu0)


REFINE_POINTS = 200


@dataclass
class _Series:
    t: np.ndarray
    positions: dict
    velocities: dict
    accelerations: dict


def _between_switches(ode, segment, z, pk):
    """Integrate one stroke piece (sigma 0 -> 1) piecewise between contact switches: windows of
    REFINE_POINTS output points; where a switching function changes sign inside a window, the
    crossing is located (linear between the window's points), the state integrated up to it and
    the integrator restarted there. Returns (sigma points, states) after the start."""
    sw = ode.switches
    pk = np.asarray(pk, float)
    s_out, z_out = [], []
    sa, width, after_restart = 0.0, 1.0 / 64, False
    while sa < 1.0 - 1e-12:
        sb = min(1.0, sa + width)
        zs = segment(pk, z, sa, sb)
        ss = np.linspace(sa, sb, zs.shape[1])
        vals = np.asarray(sw.map(len(ss))(ss[None, :], zs, np.tile(pk[:, None], (1, len(ss)))))
        on = vals >= 0
        changed = on[:, 1:] != on[:, :-1]
        if after_restart:
            changed[:, 0] = False  # the switch just passed
        cols = np.flatnonzero(changed.any(axis=0))
        if cols.size == 0:
            s_out.append(ss[1:])
            z_out.append(zs[:, 1:])
            sa, z, width, after_restart = sb, zs[:, -1], min(2 * width, 0.25), False
            continue
        j = int(cols[0])
        rows = np.flatnonzero(changed[:, j])
        frac = min(float(vals[r, j] / (vals[r, j] - vals[r, j + 1])) for r in rows)
        se = ss[j] + min(max(frac, 0.0), 1.0) * (ss[j + 1] - ss[j])
        ze = segment(pk, zs[:, j], ss[j], se)[:, -1] if se > ss[j] else zs[:, j]
        s_out += [ss[1:j + 1], [se]]
        z_out += [zs[:, 1:j + 1], ze[:, None]]
        sa, z, width, after_restart = se, ze, 1.0 / 512, True
    return np.concatenate(s_out), np.hstack(z_out)


def _series(ode, sc, Z, S, P):
    """Time, per-body positions/velocities/accelerations, element forces and drive force (SI) at the states Z."""
    out = ode.outputs.map(Z.shape[1])(S[None, :], Z, P)
    t, xd, vd, ad, acc, forces, drive = (np.asarray(o) for o in out)
    free = sc.free_bodies
    n = len(free)
    positions = {sc.driven: xd.ravel()}
    velocities = {sc.driven: vd.ravel()}
    accelerations = {sc.driven: ad.ravel()}
    for i, b in enumerate(free):
        positions[b] = Z[i] * 1e-3
        velocities[b] = Z[n + i]
        accelerations[b] = acc[i]
    return t.ravel(), positions, velocities, accelerations, {e: forces[i] for i, e in enumerate(sc.elements)}, drive.ravel()


def _run(problem, sc, scene, spm, stroke, period, ode, grid, advance, segment, opts, cpu0) -> SceneResult:
    """Integrate piece by piece with ``advance(k, piece, z0, p) -> (states on grid[1:], steps)``; collect
    results; ``segment(p, z0, sigma_a, sigma_b) -> states`` re-integrates one output interval finely."""
    nx = ode.state_size
    z = np.zeros(nx)
    zs, ps, sig = [], [], []
    steps = 0
    for k, piece in enumerate(stroke.pieces):
        if piece.duration <= 0:
            continue
        pk = [k, piece.t_start, piece.duration]
        sk = grid
        if nx:
            out = advance(k, piece, z, pk)
            if len(out) == 3:  # its own output points
                sk, xf, nst = out
                sk = np.concatenate([[0.0], sk])
            else:
                xf, nst = out
            zk = np.hstack([z[:, None], xf])
            steps += nst
        else:
            zk = np.zeros((0, len(grid)))
        if not np.all(np.isfinite(zk)):
            raise SolverError(f"{opts.method} returned non-finite states in piece {k + 1} of scene {scene!r}")
        zs.append(zk)
        sig.append(sk)
        ps.append(np.tile(np.array(pk, float)[:, None], (1, len(sk))))
        z = zk[:, -1]
    Z, S, P = np.hstack(zs), np.concatenate(sig), np.hstack(ps)
    t, positions, velocities, accelerations, fdict, drive = _series(ode, sc, Z, S, P)
    result = SceneResult(scene, spm, period, t, positions, velocities, accelerations, fdict,
                         drive, {}, 0.0, opts, sc.driven, {"nsteps": steps, "n_output": int(Z.shape[1])})
    result.stroke_label = stroke.label

    def refine(i):
        """The trajectory inside output interval ``[i, i+1]``, re-integrated from the state at ``i`` on a
        grid REFINE_POINTS times finer (events are then located far below the output spacing)."""
        if not nx or S[i + 1] <= S[i]:
            return None
        zsub = segment(P[:, i], Z[:, i], S[i], S[i + 1])
        ssub = np.linspace(S[i], S[i + 1], zsub.shape[1])
        return _Series(*_series(ode, sc, zsub, ssub, np.tile(P[:, i:i + 1], (1, len(ssub))))[:4])

    result.metrics = scene_metrics(result, sc, refine)
    result.cpu_time_s = time.process_time() - cpu0
    return result


def simulate_scene_scipy(problem, scene: str, spm: float | None = None, rtol: float = 1e-6, atol: float = 1e-7,
                         method: str = "Radau") -> SceneResult:
    """The same scene, stroke restarts, scaling, output grid and metrics, integrated by scipy's
    ``solve_ivp`` (the reference peer of ``strokeopt bench``; right-hand side and Jacobian are the
    scene's CasADi Functions called from Python)."""
    from scipy.integrate import solve_ivp

    opts = SimulationOptions(method="cvodes", rtol=rtol, atol=atol)
    sc = problem.scenes[scene]
    spm = float(problem.spm if spm is None else spm)
    stroke = problem.stroke(spm)
    period = problem.timing.period(spm)
    cpu0 = time.process_time()
    sign, s_ref = _drive_reference(problem)
    ode = sc.build(stroke, sign, s_ref, 0.0)
    spans = [p.duration for p in stroke.pieces]
    n_out = int(min(max(math.ceil(max(spans) / period * 360.0 / opts.resolution_deg), 20), 4000))
    grid = np.linspace(0.0, 1.0, n_out + 1)
    jac = ca.Function("scene_jacobian", [ode.dae["t"], ode.dae["x"], ode.dae["p"]], [ca.jacobian(ode.dae["ode"], ode.dae["x"])])

    def advance(k, piece, z, pk):
        sol = solve_ivp(lambda s, y: np.asarray(ode.rhs(s, y, pk)).ravel(), (0.0, 1.0), z, method=method,
                        t_eval=grid[1:], rtol=rtol, atol=atol, jac=lambda s, y: np.asarray(jac(s, y, pk)))
        if not sol.success:
            raise SolverError(f"scipy {method} failed in piece {k + 1} of scene {scene!r}: {sol.message}")
        return sol.y, int(sol.nfev)

    def segment(pk, z0, sa, sb):
        pk = list(pk)
        sol = solve_ivp(lambda s, y: np.asarray(ode.rhs(s, y, pk)).ravel(), (sa, sb), z0, method=method,
                        t_eval=np.linspace(sa, sb, REFINE_POINTS + 1), rtol=rtol, atol=atol,
                        jac=lambda s, y: np.asarray(jac(s, y, pk)))
        if not sol.success:
            raise SolverError(f"scipy {method} failed refining an event of scene {scene!r}: {sol.message}")
        return sol.y

    result = _run(problem, sc, scene, spm, stroke, period, ode, grid, advance, segment, opts, cpu0)
    result.options = replace(opts, method=f"scipy-{method}")
    return result


# --------------------------------------------------------------------------- events


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


def scene_metrics(r: SceneResult, sc, refine=None) -> dict:
    """The needle-handover results of sources A.6 from a trajectory (None where not defined).

    ``refine(i)``: the trajectory re-integrated finely inside output interval ``i`` (events are
    located there); without it events are interpolated on the output grid.
    """
    model = sc.model
    roles = model.events
    t = r.t
    deg = 360.0 / r.period

    def px(S, b):
        return np.zeros_like(S.t) if b == "frame" else S.positions[b]

    def pv(S, b):
        return np.zeros_like(S.t) if b == "frame" else S.velocities[b]

    def pa(S, b):
        return np.zeros_like(S.t) if b == "frame" else S.accelerations[b]

    m = {"impact_velocity_m_s": None, "impact_angle_deg": None, "lag": False, "lag_onset_angle_deg": None,
         "lag_end_angle_deg": None, "max_lag_mm": None, "gap_N_mm": None, "min_gap_N_mm": None,
         "release_angle_deg": None, "premature_release": None, "peak_pad_force_N": None}
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
        m["peak_pad_force_N"] = float(np.max(np.abs(r.forces[roles.impact])))
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
        m["min_gap_N_mm"] = float(np.min(before)) * 1e3
        closed_before_impact = bool(np.min(before) < GAP_CLOSED)
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
    m["peak_drive_force_N"] = float(np.max(np.abs(r.drive_force)))
    m["peak_contact_forces_N"] = {e: float(np.max(np.abs(fv))) for e, fv in r.forces.items()}
    return m


# --------------------------------------------------------------------------- sweeps and studies


def parse_spm_range(text: str) -> list[float]:
    """``"600"`` -> [600]; ``"300:1200:20"`` -> 300, 320, ..., 1200 (start:stop:step, stop included)."""
    parts = text.split(":")
    try:
        nums = [float(p) for p in parts]
    except ValueError:
        raise ProblemError("--spm", "", f"expected SPM or START:STOP:STEP, got {text!r}") from None
    if len(nums) == 1:
        values = nums
    elif len(nums) == 3:
        start, stop, step = nums
        if not step > 0 or stop < start:
            raise ProblemError("--spm", "", f"START:STOP:STEP needs STEP > 0 and STOP >= START, got {text!r}")
        values = list(np.arange(start, stop + 0.5 * step, step))
    else:
        raise ProblemError("--spm", "", f"expected SPM or START:STOP:STEP, got {text!r}")
    if not all(math.isfinite(x) and x > 0 for x in values):
        raise ProblemError("--spm", "", f"speeds must be positive, got {text!r}")
    return [float(x) for x in values]


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
                                                           "cpu_time_s": ref.cpu_time_s, **_key_metrics(ref.metrics)},
            "rows": rows}


def _key_metrics(m: dict) -> dict:
    return {k: m[k] for k in ("impact_velocity_m_s", "impact_angle_deg", "release_angle_deg", "lag_end_angle_deg")}


def _errors(m: dict, ref: dict) -> dict:
    def err(key):
        if m[key] is None or ref[key] is None:
            return None if m[key] is None and ref[key] is None else math.inf
        return abs(m[key] - ref[key])

    return {"impact_velocity_error_m_s": err("impact_velocity_m_s"), "release_angle_error_deg": err("release_angle_deg"),
            "impact_angle_error_deg": err("impact_angle_deg")}


# --------------------------------------------------------------------------- text reports


def _f(x, fmt: str, none: str = "-") -> str:
    return none if x is None else format(x, fmt)


def scene_text(problem, scene: str, summary: dict) -> str:
    """The results of one simulated cycle as a short text report."""
    sc = problem.scenes[scene]
    roles = sc.model.events
    s = summary
    lines = [f"{problem.name}: scene {scene!r} ({', '.join(sc.bodies)}; {sc.state_size} states) at {s['spm']:g} spm, "
             f"stroke: {s['stroke']}, interval times {problem.timing.interval_times}"]
    if s["gap_N_mm"] is not None:
        lines.append(f"gap N used by the model: {s['gap_N_mm']:g} mm (model.contacts.{roles.gap}.gap_mm)")
    f = roles.follower or "follower"
    if s["impact_velocity_m_s"] is not None:
        lines.append(f"impact of {f} on the stop ({roles.impact}): {s['impact_velocity_m_s']:.3f} m/s "
                     f"at {s['impact_angle_deg']:.2f} deg")
    elif roles.impact in sc.elements:
        lines.append(f"impact ({roles.impact}): none in this cycle")
    if s["lag"]:
        end = f"until {s['lag_end_angle_deg']:.2f} deg" if s["lag_end_angle_deg"] is not None else "not caught up in this cycle"
        lines.append(f"{f} lags the {sc.driven}: from {s['lag_onset_angle_deg']:.2f} deg {end} "
                     f"(largest lag before the impact {s['max_lag_mm']:.2f} mm)")
    elif s["max_lag_mm"] is not None:
        lines.append(f"{f} follows the {sc.driven} (no lag above {LAG_THRESHOLD * 1e6:g} um)")
    if s["min_gap_N_mm"] is not None:
        lines.append(f"smallest remaining gap N before the impact: {s['min_gap_N_mm']:.2f} mm")
    if s["release_angle_deg"] is not None:
        verdict = {True: "PREMATURE: gap N closed before the impact", False: "after the impact, not premature",
                   None: "no impact to compare with"}[s["premature_release"]]
        lines.append(f"needle released at {s['release_angle_deg']:.2f} deg ({verdict})")
    if s["peak_pad_force_N"] is not None:
        lines.append(f"peak pad force: {s['peak_pad_force_N']:.1f} N")
    lines.append(f"peak force the drive supplies to the {sc.driven}: {s['peak_drive_force_N']:.1f} N")
    lines.append("peak element forces [N] (on the output grid): " + ", ".join(f"{k} {v:.1f}" for k, v in s["peak_contact_forces_N"].items()))
    sw = "hard switches" if s["smoothing_mm"] == 0 else f"smoothing {s['smoothing_mm']:g} mm"
    lines.append(f"CPU time {s['cpu_time_s']:.3f} s ({s['method']}, rtol {s['rtol']:g}, atol {s['atol']:g}, {sw})")
    return "\n".join(lines)


SWEEP_COLUMNS = [("spm", "spm"), ("impact_velocity_m_s", "impact m/s"), ("impact_angle_deg", "impact deg"),
                 ("lag", "lag"), ("lag_end_angle_deg", "lag end deg"), ("min_gap_N_mm", "min gap N mm"),
                 ("release_angle_deg", "release deg"), ("premature_release", "premature"),
                 ("peak_pad_force_N", "pad N"), ("cpu_time_s", "CPU s")]

STUDY_COLUMNS = [("method", "method"), ("switching", "switching"), ("smoothing_mm", "smoothing mm"), ("rtol", "rtol"),
                 ("impact_velocity_error_m_s", "impact v error m/s"), ("release_angle_error_deg", "release error deg"),
                 ("impact_angle_error_deg", "impact angle error deg"), ("nsteps", "steps"), ("cpu_time_s", "CPU s")]
