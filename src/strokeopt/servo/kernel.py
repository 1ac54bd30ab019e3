"""The servo's term of the design's handover-accuracy constraint (an exact linear functional of the move
accelerations)."""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace
from pathlib import Path

import numpy as np

from ..drive.sizing import bisect_highest
from ..errors import ProblemError, SolverError
from .accuracy import handover_accuracy
from .loop import Gains, build_loop, tuned_gains as _tuned
from .plant import DriveAxis, axis_from_problem
from .settings import ServoSettings



# --------------------------------------------------------------------------- the design constraint


@dataclass(frozen=True)
class ErrorKernel:
    """The bar error at one instant as a linear functional of the stroke's acceleration.

    For the periodic steady state of the loop (continuous reference, no
    table sampling), ``e(t) = integral over one cycle of K_T(t - sigma) a(sigma) d sigma``
    with ``K_T`` the derivative of the error's response to a unit step of
    acceleration, folded onto one period. ``tau`` and ``values`` sample ``K_T``
    on ``[0, period]``.
    """

    period: float
    delay: float
    tau: np.ndarray
    values: np.ndarray

    def __call__(self, tau) -> np.ndarray:
        return np.interp(np.mod(tau, self.period), self.tau, self.values)

    def error_at(self, stroke, t: float, points: int = 20001) -> float:
        """``e(t + delay)`` for a stroke (numeric check of the functional)."""
        sigma = np.linspace(0.0, self.period, points)
        a = stroke.evaluate(sigma).a
        return float(np.trapezoid(self(t + self.delay - sigma) * a, sigma))


_KERNELS: dict = {}


def error_kernel(axis: DriveAxis, settings: ServoSettings, gains: Gains, period: float) -> ErrorKernel:
    """The :class:`ErrorKernel` of a loop for a cycle of ``period`` seconds (cached)."""
    import control

    key = (axis, settings, gains, round(period, 12))
    if key in _KERNELS:
        return _KERNELS[key]
    loop = build_loop(replace(axis, load=None), settings, gains)
    slowest = float(np.min(-loop.poles.real))
    horizon = max(period, 12.0 / slowest)
    step = min(settings.position_sampling / 25, period / 4000)
    t = np.arange(0.0, horizon + step, step)
    d = settings.sum_small_time_constants
    r = axis.radius
    td = np.clip(t - d, 0.0, None)
    s_ref = td**2 / 2  # the bar position commanded by a unit step of acceleration at t = 0, as the loop sees it
    u = np.vstack([s_ref / r, td / r, axis.total_inertia / r * np.ones_like(t), 0 * t])
    x = np.asarray(control.forced_response(loop.system, t, u).outputs)[2]
    e_step = s_ref - x
    k = np.gradient(e_step, t)
    n_per = int(round(period / step))
    tau = t[: n_per + 1]
    folded = np.zeros(n_per + 1)
    for start in range(0, len(t), n_per):
        chunk = k[start: start + n_per + 1]
        folded[: len(chunk)] += chunk
    if len(_KERNELS) > 32:
        _KERNELS.pop(next(iter(_KERNELS)))
    _KERNELS[key] = ErrorKernel(period, d, tau, folded)
    return _KERNELS[key]


#: Gauss-Legendre points per mesh interval for the error functional in the design.
KERNEL_POINTS = 6


def servo_handover_error(ctx):
    """Handover error term of the design (``design.HANDOVER_ERROR_TERMS``): the bar's error at the
    end of the handover move (:data:`WINDOW_POINTS`) from the servo loop and the belt,
    ``|e_motion + e_load| + one count``.

    ``e_motion`` is exact for the linear loop (continuous reference): a linear
    functional of the move accelerations (:class:`ErrorKernel`), the weights
    entering the NLP as parameters, so a solver built for one speed serves
    another. ``e_load`` (the load forces: springs, gravity) is taken from the
    simulation of the problem's classic stroke at the same speed. With a
    continuous pulley radius or a motor choice the kernel is that of the
    problem's own pulley and motor (an approximation; re-check the result with
    ``strokeopt accuracy``). None when the problem has no ``[servo]`` section.
    """
    import casadi as ca

    problem = ctx.problem
    settings = getattr(problem, "servo", None)
    if settings is None or ctx.drive is None or not ctx.moves or "spm" not in ctx.extra:
        return None
    if problem.timing.handover_move is None:
        return None
    x_q = (np.polynomial.legendre.leggauss(KERNEL_POINTS)[0] + 1) / 2
    b = ctx.built
    n = ctx.mesh.intervals
    errors = 0
    for k, mv in enumerate(ctx.moves):
        w_sym = b.params(f"servo kernel move {mv.index}", lambda c, k=k: _servo_numbers(c)["weights"][k],
                         (WINDOW_POINTS + 1, n * KERNEL_POINTS))
        a = ca.vec(ctx.si(k, x_q, "a"))  # column-major: the same order as the kernel's sigma
        errors = errors + ca.mtimes(w_sym, a)
    load = b.param("servo load error", lambda c: _servo_numbers(c)["load"])
    quant = b.param("servo encoder count", lambda c: _servo_numbers(c)["count"])
    e = errors + load
    return "servo loop and belt (servo.py)", ca.mmax(ca.sqrt(e**2 + 1e-14)) + quant


def _servo_numbers(ctx) -> dict:
    """The numbers of :func:`servo_handover_error` for one solve (speed, motor, pulley): kernel weights
    per move, load error, encoder count. Computed once per solve (``ctx.extra["cache"]``)."""
    cache = ctx.extra["cache"]
    if "servo" in cache:
        return cache["servo"]
    problem = ctx.problem
    settings = problem.servo
    spm = float(ctx.extra["spm"])
    timing = problem.timing
    move_h = timing.handover_move
    choice = ctx.choice
    motor = choice.motor if choice is not None and choice.motor is not None else None
    teeth = choice.teeth if choice is not None and choice.teeth is not None else problem.pulley_teeth
    axis = axis_from_problem(problem, settings, motor=motor, pulley_teeth=teeth)
    gains = _tuned(axis, settings)
    sch = timing.schedule(spm)
    period = float(sch.period)
    kernel = error_kernel(axis, settings, gains, period)
    t_h = float(sch.t_start[move_h.index - 1] + sch.duration[move_h.index - 1])
    # the instants checked: the end of the handover move and WINDOW_POINTS more over the handover window
    t_check = t_h + np.linspace(0.0, settings.handover_window / 360.0 * period * (WINDOW_POINTS > 0),
                                WINDOW_POINTS + 1)
    x_q, w_q = np.polynomial.legendre.leggauss(KERNEL_POINTS)
    x_q, w_q = (x_q + 1) / 2, w_q / 2
    n = ctx.mesh.intervals
    weights = []
    for mv in ctx.moves:
        t0 = float(sch.t_start[mv.interval - 1])
        dur = float(sch.duration[mv.interval - 1])
        sigma = (t0 + (np.arange(n).reshape(-1, 1) + x_q.reshape(1, -1)) * dur / n).ravel(order="F")
        w = np.tile(w_q, (n, 1)).ravel(order="F") * dur / n
        weights.append(kernel(t_check.reshape(-1, 1) + kernel.delay - sigma.reshape(1, -1)) * w.reshape(1, -1))
    cache["servo"] = {"weights": weights, "load": _load_error(problem, settings, axis, gains, spm),
                      "count": 2 * math.pi * axis.radius / settings.encoder_counts}
    return cache["servo"]


#: Instants after the end of the handover move checked in the design, spread over the handover
#: window. 0: the end of the move only. The maximum over several instants is not smooth and made
#: IPOPT fail on tight accuracies (0.05 mm at 600 spm: iteration limit); ``strokeopt accuracy``
#: re-checks the whole window.
WINDOW_POINTS = 0


_LOAD_ERRORS: dict = {}



def _load_error(problem, settings: ServoSettings, axis: DriveAxis, gains: Gains, spm: float) -> float:
    """Bar error at the end of the handover move caused by the load forces alone (classic stroke, this speed)."""
    key = (id(problem), axis, settings, gains, spm)
    if key not in _LOAD_ERRORS:
        if axis.load is None:
            _LOAD_ERRORS[key] = 0.0
        else:
            res = handover_accuracy(problem, spm=spm, settings=settings, axis=axis, gains=gains)
            _LOAD_ERRORS[key] = res.at_handover(res.error_load)
    return _LOAD_ERRORS[key]


def _register_design_term() -> None:
    from ..design import solve as design

    if servo_handover_error not in design.HANDOVER_ERROR_TERMS:
        design.HANDOVER_ERROR_TERMS.append(servo_handover_error)


_register_design_term()


