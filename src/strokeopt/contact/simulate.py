"""Simulating a scene over one cycle with CasADi's SUNDIALS integrators, and its results.

:func:`simulate_scene` integrates the scene's ODE (scene.py) with its driven
body following a :class:`~strokeopt.motion.stroke.StrokeFunction` (a classic law or an
optimised stroke) over one cycle, from rest at x = 0, and returns a
:class:`SceneResult`: the trajectory on a fine output grid, the element and
drive forces, and the metrics of events.py (impact, lag, remaining gap, release),
its events located on the trajectory re-integrated finely around them, its peak forces located
between the output points with an error estimate each (peaks.py). A scene has a step budget
(scene.py ``max_steps``): one whose contacts ring faster than it can follow is refused, one that
needs more steps stops, naming its stiffest contact.

The integration is shared by every integrator: :func:`integrate_scene` takes a
*stepper* (how one stroke piece and one output interval are integrated) and does
everything else, the validation, the scene ODE, the restarts at the joints of the
stroke, the output grid, the series and the event location. :func:`simulate_scene`
is it with CasADi's SUNDIALS integrators; ``strokeopt bench`` passes scipy's
``solve_ivp`` as the stepper (bench/contact.py) to compare the integrators alone.
Then studies.py sweeps and compares runs, verify.py re-simulates designs, and
report/contact.py prints and draws the results.

How it is integrated, and why (measured on this machine, release scene, 600 spm,
modified sine, one cycle, CasADi 3.8.2; `strokeopt simulate ... --study tolerance`
prints the full table):

* one integrator object, restarted at every joint of the stroke (known-time
  discontinuities) with the piece index as a parameter, time normalised per piece, a
  fine output grid inside each call (output points cost almost nothing: CVODES
  interpolates them); a piece that needs more steps at some output point than the budget
  left spreads over them is integrated again in chunks of output points, so that the budget
  stops a scene too stiff for it at any tolerance (stepper.py);
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
from dataclasses import dataclass, field

import numpy as np

from ..errors import ProblemError, SolverError
from .events import scene_metrics
from .options import METHODS, SimulationOptions  # noqa: F401  (the scene's options; METHODS for the readers)
from .peaks import scene_peaks
from .stepper import CasadiStepper, step_budget


@dataclass
class SceneResult:
    """One simulated cycle: trajectory (SI, on the output grid), forces, results.

    ``positions``/``velocities``/``accelerations``: per body of the scene (the driven one
    included); ``forces``: per element of the scene (N, positive = compression);
    ``drive_force``: the force the drive must supply to the driven body, its inertia plus
    what the elements push back: ``m a - sum of element forces on it`` (N); ``metrics``: those
    of :data:`strokeopt.contact.events.METRICS`. Figures: :func:`strokeopt.report.contact.plot_scene`.

    Peak forces (``metrics``) are located between the output points (peaks.py: the 1e9 N/m contacts
    and the drive force they load spike for microseconds), each with an error estimate; the series
    here are on the output grid and miss most spikes.
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
    # the model's coordinates in the problem's: problem position = frame_origin + frame_sign * model position
    frame_sign: float = 1.0
    frame_origin: float = 0.0  # m

    def problem_position(self, body: str) -> np.ndarray:
        """A body's position in the problem's coordinates (the stroke's: the file's positions) [m]."""
        return self.frame_origin + self.frame_sign * self.positions[body]

    def problem_velocity(self, body: str) -> np.ndarray:
        """A body's velocity in the problem's coordinates [m/s]."""
        return self.frame_sign * self.velocities[body]

    @property
    def angle_deg(self) -> np.ndarray:
        return 360.0 * self.t / self.period

    def summary(self) -> dict:
        """JSON-ready results (unit-suffixed keys; None where an event does not happen)."""
        return {"scene": self.scene, "spm": self.spm, "stroke": self.stroke_label, **self.metrics,
                "cpu_time_s": self.cpu_time_s,
                "method": self.options.method, "rtol": self.options.rtol, "atol": self.options.atol,
                "smoothing_mm": self.options.smoothing * 1e3}


def drive_reference(problem) -> tuple[float, float]:
    """``(sign, s_ref)`` of ``x_driven = sign * (s - s_ref)``: zero at the start of the handover move,
    positive in its direction (the first move if none is marked)."""
    if problem.model is not None and problem.model.transmission is not None:
        return 1.0, 0.0  # a model on the transmission's members: their own coordinates, from its zero
    moves = problem.timing.moves
    move = problem.timing.handover_move or moves[0]
    return (1.0 if move.stroke > 0 else -1.0), move.start_position


_drive_reference = drive_reference  # the name tests/contact/test_scene.py imports


# --------------------------------------------------------------------------- the shared core


def simulate_scene(problem, scene: str, spm: float | None = None, stroke=None,
                   options: SimulationOptions | None = None) -> SceneResult:
    """Integrate ``scene`` (a name of ``problem.scenes``) over one cycle at ``spm``.

    ``stroke``: any StrokeFunction (default: the problem's classic-law stroke at ``spm``); its
    period must be the cycle time at ``spm``. Raises ProblemError for bad input and SolverError
    when the integrator fails (with the reason).
    """
    return integrate_scene(problem, scene, spm, stroke, options, CasadiStepper)


def integrate_scene(problem, scene: str, spm: float | None, stroke, options: SimulationOptions | None,
                    make_stepper) -> SceneResult:
    """:func:`simulate_scene` with the stepper ``make_stepper(ode, grid, options, scene, spm)`` (see
    :class:`CasadiStepper` for what a stepper does); everything but the integrator is shared."""
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
    sc.check_resolvable(str(problem.file), period, step_budget(sc, opts))
    cpu0 = time.process_time()
    sign, s_ref = drive_reference(problem)
    ode = sc.build(stroke, sign, s_ref, opts.smoothing)
    spans = [p.duration for p in stroke.pieces]
    n_out = int(min(max(math.ceil(max(spans) / period * 360.0 / opts.resolution_deg), 20), 4000))
    grid = np.linspace(0.0, 1.0, n_out + 1)
    # only the driven body: nothing to integrate
    stepper = make_stepper(ode, grid, opts, scene, spm) if ode.state_size else None
    result = _run(sc, scene, spm, stroke, period, ode, grid, stepper, opts, cpu0)
    result.frame_sign, result.frame_origin = sign, s_ref
    return result


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
    t, xd, vd, ad, acc, forces, drive, riders = (np.asarray(o) for o in out)
    free = sc.free_bodies
    n = len(free)
    positions = {sc.driven: xd.ravel()}
    velocities = {sc.driven: vd.ravel()}
    accelerations = {sc.driven: ad.ravel()}
    for i, b in enumerate(free):
        positions[b] = Z[i] * 1e-3
        velocities[b] = Z[n + i]
        accelerations[b] = acc[i]
    for i, b in enumerate(sc.riders):  # carried through the transmission by their hosts
        positions[b], velocities[b], accelerations[b] = riders[3 * i], riders[3 * i + 1], riders[3 * i + 2]
    return t.ravel(), positions, velocities, accelerations, {e: forces[i] for i, e in enumerate(sc.elements)}, drive.ravel()


def _run(sc, scene, spm, stroke, period, ode, grid, stepper, opts, cpu0) -> SceneResult:
    """Integrate piece by piece with ``stepper`` (across the contact switches, or restarted at each with
    ``opts.restart_at_switches``); collect the series; locate the events on finely re-integrated intervals."""
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
            if opts.restart_at_switches:  # its own output points, at the switches
                before = stepper.segment_steps
                sk, xf = _between_switches(ode, stepper.segment, z, pk)
                sk = np.concatenate([[0.0], sk])
                nst = stepper.segment_steps - before
                if steps + nst > getattr(stepper, "budget", math.inf):  # the piece-wise path keeps it too
                    stepper.steps = steps + nst
                    raise stepper._over_budget(k, piece, nst)
            else:
                xf, nst = stepper.piece(k, piece, z, pk)
            zk = np.hstack([z[:, None], xf])
            steps += nst
        else:
            zk = np.zeros((0, len(grid)))
        if not np.all(np.isfinite(zk)):
            raise SolverError(f"{stepper.name} returned non-finite states in piece {k + 1} of scene {scene!r}")
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
        zsub = stepper.segment(P[:, i], Z[:, i], S[i], S[i + 1])
        ssub = np.linspace(S[i], S[i + 1], zsub.shape[1])
        return _Series(*_series(ode, sc, zsub, ssub, np.tile(P[:, i:i + 1], (1, len(ssub))))[:4])

    peaks = scene_peaks(sc, ode, result, Z, S, P, stepper) if nx and opts.peaks else None
    result.metrics = scene_metrics(result, sc, refine, peaks)
    result.cpu_time_s = time.process_time() - cpu0
    return result

