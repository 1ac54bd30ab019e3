"""The servo's term of the design's handover-accuracy constraint (an exact linear functional of the move
accelerations): :class:`ServoErrorTerm`, passed to the design as one of ``Problem.error_terms``.

The design does not import this module: the problem file (:mod:`strokeopt.files.problem_file`) gives the
term to a problem with a ``[servo]`` section, and :func:`strokeopt.design.solve.solve_design` takes it
from there (or from its ``error_terms`` argument)."""

from __future__ import annotations

import math
from dataclasses import dataclass, replace
from typing import ClassVar

import numpy as np

from .accuracy import handover_accuracy
from .error_expression import ErrorExpression
from .loop import Gains, build_loop, tuned_gains as _tuned
from .lti import forced_response
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
    x = forced_response(loop.system, t, u)[0][2]
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


@dataclass(frozen=True)
class ServoErrorTerm:
    """The servo's handover error term of the design (a :class:`strokeopt.design.transcription.request.ErrorTerm`):
    the bar's error over the handover window (the end of the handover move and :data:`WINDOW_POINTS`
    instants after it) from the servo loop and the belt, ``|e_motion + e_load| + one count`` at each.

    ``e_motion`` is exact for the linear loop (continuous reference): a linear
    functional of the move accelerations (:class:`ErrorKernel`), the weights
    entering the NLP as parameters, so a solver built for one speed serves
    another. ``e_load`` (the load forces: springs, gravity) is taken from the
    simulation of the problem's classic stroke at the same speed. With a
    continuous pulley radius or a motor choice the kernel is that of the
    problem's own pulley and motor (an approximation; re-check the result with
    ``strokeopt accuracy``). The term has no parameters: it reads ``problem.servo`` at
    solve time (no term when the problem has no ``[servo]`` section). The problem file gives
    it to every problem with a ``[servo]`` section (``Problem.error_terms``).
    """

    name: ClassVar[str] = "servo loop and belt"

    def fixed_error(self, problem) -> float | None:
        """No part of this term is independent of the design (speed, motor and pulley set all of it)."""
        return None

    def expression(self, nlp):
        """The error [m] in the NLP under construction, or None without ``[servo]``, drive or handover move."""
        import casadi as ca

        req = nlp.request
        problem = req.problem
        if getattr(problem, "servo", None) is None or req.drive is None or not req.moves:
            return None
        if problem.timing.handover_move is None:
            return None
        x_q = (np.polynomial.legendre.leggauss(KERNEL_POINTS)[0] + 1) / 2
        b = nlp.built
        n = req.mesh.intervals
        errors = 0
        for k, mv in enumerate(req.moves):
            w_sym = b.params(f"servo kernel move {mv.index}", lambda r, k=k: _servo_numbers(r)["weights"][k],
                             (WINDOW_POINTS + 1, n * KERNEL_POINTS))
            a = ca.vec(nlp.si(k, x_q, "a"))  # column-major: the same order as the kernel's sigma
            errors = errors + ca.mtimes(w_sym, a)
        load = b.params("servo load error", lambda r: _servo_numbers(r)["load"], (WINDOW_POINTS + 1, 1))
        quant = b.param("servo encoder count", lambda r: _servo_numbers(r)["count"])
        return ErrorExpression(errors + load, quant)


def _servo_numbers(req) -> dict:
    """The numbers of :class:`ServoErrorTerm` for one solve (speed, motor, pulley): kernel weights
    per move, load error, encoder count. Computed once per solve (``req.cache``, the solve's
    :class:`~strokeopt.design.transcription.request.SolveRequest`)."""
    cache = req.cache
    if "servo" in cache:
        return cache["servo"]
    problem = req.problem
    settings = problem.servo
    spm = float(req.spm)
    timing = problem.timing
    move_h = timing.handover_move
    choice = req.choice
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
    n = req.mesh.intervals
    weights = []
    for mv in req.moves:
        t0 = float(sch.t_start[mv.interval - 1])
        dur = float(sch.duration[mv.interval - 1])
        sigma = (t0 + (np.arange(n).reshape(-1, 1) + x_q.reshape(1, -1)) * dur / n).ravel(order="F")
        w = np.tile(w_q, (n, 1)).ravel(order="F") * dur / n
        weights.append(kernel(t_check.reshape(-1, 1) + kernel.delay - sigma.reshape(1, -1)) * w.reshape(1, -1))
    cache["servo"] = {"weights": weights, "load": _load_error(problem, settings, axis, gains, spm, t_check),
                      "count": 2 * math.pi * axis.radius / settings.encoder_counts}
    return cache["servo"]


#: Instants after the end of the handover move checked in the design, spread evenly over the
#: handover window (the end of the move is one more): the full simulation takes the largest error
#: over the window, and a design that checked the end alone would place a zero of the residual
#: vibration there. Each instant is a pair of linear rows of the NLP (:class:`ErrorExpression`).
#: 24 instants space the 5.4 ms window at 617 spm by 1/11 of the 1.9 ms belt period of the
#: reference drive (a peak between them is underestimated by at most 4 % of the vibration's
#: amplitude; the full simulation confirms); 48 made a ``min_time`` solve at 0.03 mm 30 % slower.
WINDOW_POINTS = 24


#: Load errors by the values that determine them (timing, axis, servo settings, gains, speed); bounded.
_LOAD_ERRORS: dict = {}
_LOAD_ERRORS_SIZE = 32


def _load_error(problem, settings: ServoSettings, axis: DriveAxis, gains: Gains, spm: float,
                t_check: np.ndarray) -> np.ndarray:
    """Bar error at the instants ``t_check`` (from the start of the cycle) caused by the load forces
    alone (classic stroke, this speed)."""
    key = (problem.timing, axis, settings, gains, spm, tuple(np.round(t_check, 12)))
    if key not in _LOAD_ERRORS:
        if axis.load is None:
            value = np.zeros((len(t_check), 1))
        else:
            res = handover_accuracy(problem, spm=spm, settings=settings, axis=axis, gains=gains)
            t = t_check + settings.sum_small_time_constants
            value = np.interp(t, res.t, res.error_load).reshape(-1, 1)
        if len(_LOAD_ERRORS) >= _LOAD_ERRORS_SIZE:
            _LOAD_ERRORS.pop(next(iter(_LOAD_ERRORS)))
        _LOAD_ERRORS[key] = value
    return _LOAD_ERRORS[key]
