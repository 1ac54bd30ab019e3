"""Integrating a scene with CasADi's SUNDIALS integrators: :class:`CasadiStepper`, the stepper of
:func:`strokeopt.contact.simulate.integrate_scene` (simulate.py says why CVODES, BDF of order 2 and one
call per stroke piece), and the scene's step budget (:func:`step_budget`, scene.py ``max_steps``), which it
keeps at any tolerance.
"""

from __future__ import annotations

from dataclasses import replace

import casadi as ca
import numpy as np

from ..errors import SolverError
from .options import SimulationOptions
from .peaks import PEAK_POINTS, TIGHTER
from .scene import BUDGET_RTOL

REFINE_POINTS = 200  # an output interval is re-integrated on this many points to locate an event in it
FIRST_CHUNK = 16  # output points the first chunk of a scene integrates (CasadiStepper.piece)
CHUNK_SHARE = 0.1  # a chunk is sized to take at most this share of the steps left at the rate seen so far


def _integrator(ode, opts: SimulationOptions, grid: np.ndarray, refine: bool = False, max_steps: int = 200_000):
    dae = ode.refine_dae if refine else ode.dae
    # BDF order <= 2: the orders 3-5 are not A-stable, and the lightly damped contact modes
    # (1e5-1e6 rad/s, damping ratio ~0.01) made CVODES fail its error test over and over (4-10x more steps);
    # max_num_steps bounds the steps between two output points (CVODES counts per output point)
    iopts = {"abstol": opts.atol, "reltol": opts.rtol, "max_num_steps": int(max_steps), "max_order": 2,
             "disable_internal_warnings": not opts.verbose}  # SUNDIALS prints "At t = ..." to stdout otherwise
    iopts.update(opts.integrator_options or {})
    return ca.integrator("scene_refine" if refine else "scene", opts.method, dae, 0.0, grid[1:], iopts)


#: SUNDIALS return flags in words (the SolverError says why instead of the raw flag).
_FLAG_WORDS = {
    "ERR_FAILURE": "the error test failed repeatedly (the step shrank to its minimum: the model is too stiff or "
                   "near-singular, e.g. a body of almost no mass)",
    "CONV_FAILURE": "the corrector did not converge (the step shrank to its minimum: the model is too stiff or "
                    "near-singular)",
    "TOO_MUCH_WORK": "the step budget ran out",
    "TOO_MUCH_ACC": "the tolerances are tighter than the arithmetic allows",
}


def _why(exc: RuntimeError) -> str:
    text = str(exc).splitlines()[-1]
    for flag, words in _FLAG_WORDS.items():
        if flag in text:
            return words
    return text[:200]


class CasadiStepper:
    """Integrates a scene ODE with ``casadi.integrator`` (CVODES or IDAS, ``opts.method``).

    The interface every stepper of :func:`integrate_scene` has:

    * ``name``: the integrator's name in messages;
    * ``piece(k, piece, z0, p) -> (states on grid[1:], steps)``: one stroke piece, ``sigma`` 0 -> 1;
    * ``segment(p, z0, sigma_a, sigma_b) -> states``: ``z0`` and the states on REFINE_POINTS points
      from ``sigma_a`` to ``sigma_b`` (event location, restarts at switches);
    * ``segment_steps``: the steps of all ``segment`` calls so far.
    """

    def __init__(self, ode, grid: np.ndarray, opts: SimulationOptions, scene: str, spm: float):
        self.ode, self.opts, self.scene, self.spm = ode, opts, scene, spm
        self.name = opts.method
        self.budget = step_budget(ode.scene, opts)
        self.steps = 0  # of the stroke pieces so far
        self.grid = grid
        self._segment = None  # built on first use
        self._windows = {}  # peak windows (peaks.py), at the tolerances and tighter
        self.segment_steps = 0

    def piece(self, k, piece, z, pk):
        """One stroke piece; stops the scene once its steps pass the budget, whatever the tolerance.

        First in one call that may take the steps left spread evenly over the piece's output points (CVODES
        counts its steps per output point); a piece that needs more at some point (a stiff contact ringing, or
        an impact) is integrated again from its start in chunks of output points, each sized to take at most
        :data:`CHUNK_SHARE` of the steps left at the rate of the last (the first :data:`FIRST_CHUNK` points).
        A single output interval that takes more than that share stops the scene: its steps have shrunk so far
        that the rest of the cycle cannot be done within the budget (the contacts x100 of the handover scene:
        5e-11 s steps in a 0.12 s cycle). The budget counts the steps of every call."""
        n = len(self.grid) - 1
        left = max(self.budget - self.steps, 1)
        integ = _integrator(self.ode, self.opts, self.grid, max_steps=max(left // n, 1))
        try:
            res = integ(x0=z, p=pk)
        except RuntimeError as exc:
            if "TOO_MUCH_WORK" not in str(exc):
                raise self._failed(k, piece, exc) from None
            self.steps += max(left // n, 1)  # at least (a failed call's statistics are lost)
            return self._chunked(k, piece, z, np.asarray(pk, float))
        steps = int(integ.stats().get("nsteps", 0) or 0)
        self.steps += steps
        if self.steps > self.budget:
            raise self._over_budget(k, piece, steps)
        return np.asarray(res["xf"]), steps

    def _chunked(self, k, piece, z, pk):
        """:meth:`piece` in chunks of output points (restarting the integrator at each). A chunk of ``m`` points
        may take ``1/m`` of its share per point; where one point needs more, the chunk is halved and integrated
        again, down to one point with the whole share."""
        n = len(self.grid) - 1
        out, j, steps, m, rate = [], 0, 0, FIRST_CHUNK, 0.0
        while j < n:
            share = max(int(CHUNK_SHARE * (self.budget - self.steps)), 1)
            if rate > 0:
                m = min(2 * m, int(share / rate))
            m = max(1, min(m, n - j))
            cap = max(share // m, 1)
            integ = _integrator(self.ode, self.opts, np.linspace(0.0, 1.0, m + 1), refine=True, max_steps=cap)
            try:
                res = integ(x0=z, p=np.concatenate([pk, [self.grid[j], self.grid[j + m]]]))
            except RuntimeError as exc:
                if "TOO_MUCH_WORK" not in str(exc):
                    raise self._failed(k, piece, exc) from None
                self.steps += cap  # at least (a failed call's statistics are lost)
                steps += cap
                if m == 1:
                    raise self._over_budget(k, piece, steps, self.grid[j], self.grid[j + m], cap) from None
                if self.steps > self.budget:
                    raise self._over_budget(k, piece, steps, 0.0, self.grid[j]) from None
                m, rate = m // 2, 0.0
                continue
            taken = int(integ.stats().get("nsteps", 0) or 0)
            steps += taken
            self.steps += taken
            if self.steps > self.budget:
                raise self._over_budget(k, piece, steps, 0.0, self.grid[j + m])
            rate = max(taken / m, 1e-9)
            out.append(np.asarray(res["xf"]))
            z = out[-1][:, -1]
            j += m
        return np.hstack(out), steps

    def _failed(self, k, piece, exc) -> SolverError:
        return SolverError(f"{self.opts.method} failed in stroke piece {k + 1} ({piece.label}) of scene {self.scene!r} "
                           f"at {self.spm:g} spm: {_why(exc)} (tighten or loosen the tolerances)")

    def _over_budget(self, k, piece, steps, sa=0.0, sb=1.0, single=None) -> SolverError:
        """The scene needs more steps than its budget: where, the step it was taking, the stiffest contact.
        ``steps``: those of the piece when it ended past the budget at ``sb`` (a fraction of the piece);
        ``single``: the steps one output interval, from ``sa`` to ``sb``, could not do with (it needs more than
        a share of the steps left: see :meth:`piece`)."""
        sc = self.ode.scene
        if single is not None:
            ms = (piece.t_start + sa * piece.duration) * 1e3, (piece.t_start + sb * piece.duration) * 1e3
            where = f"{ms[0]:.4g} ms into the cycle, in "
            step = (f"the output interval from there to {ms[1]:.4g} ms needed more than {single:,} steps, "
                    f"{CHUNK_SHARE:.0%} of the {max(self.budget - self.steps + single, 0):,} then left")
        else:
            where = f"{(piece.t_start + sb * piece.duration) * 1e3:.4g} ms into the cycle, in "
            step = f"its steps there averaged {sb * piece.duration / max(steps, 1):.2g} s"
        periods = sc.contact_periods()
        stiff = ""
        if periods:
            period, name, body = periods[0]
            el = sc.model.elements[name]
            table = "links" if el.kind == "link" else ("springs" if el.kind == "spring" else "contacts")
            stiff = (f", forced by its stiffest contact {name} ({el.stiffness:.3g} N/m on the "
                     f"{sc.model.bodies[body].mass * 1e3:.3g} g {body}: contact period {period:.2g} s); soften it "
                     f"(model.{table}.{name}.stiffness_N_m) or")
        if self.opts.max_steps is not None:
            budget = "the max_steps option"
        elif self.budget == sc.max_steps:
            budget = f"scenes.{sc.name}.max_steps"
        else:
            budget = f"scenes.{sc.name}.max_steps = {sc.max_steps:,} at rtol {BUDGET_RTOL:g}, scaled to rtol {self.opts.rtol:g}"
        return SolverError(f"scene {self.scene!r} at {self.spm:g} spm stopped after {self.steps:,} integrator steps "
                           f"(its budget: {self.budget:,}, {budget}); it had reached {where}stroke piece {k + 1} "
                           f"({piece.label}), and {step}{stiff or ';'} raise scenes.{sc.name}.max_steps")

    def window(self, pk, z0, sa, sb, tight=False, points=PEAK_POINTS):
        """``z0`` and the states on ``points`` points from ``sigma_a`` to ``sigma_b`` (peaks.py); ``tight``: at
        the tolerances divided by TIGHTER (its accuracy estimate; None if the integrator fails there)."""
        if not tight and points == REFINE_POINTS:  # the event location's integrator
            return self.segment(pk, z0, sa, sb)
        integ = self._windows.get((tight, points))
        if integ is None:
            opts = self.opts
            if tight:
                opts = replace(opts, rtol=max(opts.rtol / TIGHTER, 1e-12), atol=max(opts.atol / TIGHTER, 1e-13))
            integ = self._windows[tight, points] = _integrator(self.ode, opts, np.linspace(0.0, 1.0, points + 1),
                                                               refine=True, max_steps=self.budget)
        try:
            xf = np.asarray(integ(x0=z0, p=np.concatenate([pk, [sa, sb]]))["xf"])
        except RuntimeError as exc:
            if tight:
                return None
            raise SolverError(f"{self.opts.method} failed locating a peak force between {sa:.6g} and {sb:.6g} of stroke "
                              f"piece {int(pk[0]) + 1} of scene {self.scene!r}: {_why(exc)}") from None
        self.segment_steps += int(integ.stats().get("nsteps", 0) or 0)
        return np.hstack([np.asarray(z0, float)[:, None], xf])

    def segment(self, pk, z0, sa, sb):
        if self._segment is None:
            self._segment = _integrator(self.ode, self.opts, np.linspace(0.0, 1.0, REFINE_POINTS + 1), refine=True,
                                        max_steps=self.budget)
        try:
            xf = np.asarray(self._segment(x0=z0, p=np.concatenate([pk, [sa, sb]]))["xf"])
        except RuntimeError as exc:
            raise SolverError(f"{self.opts.method} failed between {sa:.6g} and {sb:.6g} of stroke piece "
                              f"{int(pk[0]) + 1} of scene {self.scene!r}: {_why(exc)}") from None
        self.segment_steps += int(self._segment.stats().get("nsteps", 0) or 0)
        return np.hstack([np.asarray(z0, float)[:, None], xf])


def step_budget(scene, opts: SimulationOptions) -> int:
    """The integrator steps a cycle of ``scene`` may take with ``opts`` (its own budget unless ``opts.max_steps``)."""
    return int(opts.max_steps) if opts.max_steps is not None else scene.step_budget(opts.rtol)
