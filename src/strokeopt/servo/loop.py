"""The servo loop: the drive's cascade controller closed around the plant, and its periodic response.

Third step of the servo flow: :func:`build_loop` closes the loop around a
:class:`~.plant.DriveAxis` with the :class:`Gains` of :func:`tune` (or
:func:`tuned_gains`, the same cached); :func:`reference_signals` turns a stroke
into the loop's inputs as the drive reads its position table, and
:func:`periodic_response` gives the periodic steady state the accuracy
prediction (:mod:`.accuracy`) reads.

The model (continuous time, linear; state space and responses in numpy, :mod:`.lti`):

* **Servo drive**: a cascade position / speed loop (Control Techniques
  Digitax ST, digest A.5): P position controller ``Kp``, PI speed
  controller ``Kv (1 + 1/(Ti s))`` on the motor encoder, velocity and
  acceleration (torque) feed-forward switchable. Sampling is modelled as
  delays: the position loop samples every ``T_p`` = 250 us, so the loop
  sees the sample-and-hold (``T_p/2``), one sample of computation
  (``T_p``) and the current loop (time constant ``T_i``), together the
  sum of small time constants ``T_sigma``, represented by a Pade
  approximation inside the loop. The position table is read every control
  cycle ``T_c`` = 500 us (rounded so that a whole number of table points
  fills the stitch cycle) and interpolated linearly; the speed
  feed-forward is the table's difference quotient held over the cycle,
  the torque feed-forward ``J_tot eps - r F_ext`` (``eps`` the table's
  second difference; with ``load_feedforward`` the load forces too, as
  the sizing computes them). The drive delays its position and speed
  references by ``T_sigma`` so that they meet the feed-forward torque at
  the motor; the error is measured against the stroke delayed by the same
  ``T_sigma`` (a delay common to both synchronised bars).
* **Tuning rule** (default gains, not fitted to any measurement): the
  symmetric optimum for the speed loop on the rigid total inertia
  ``J_tot = J + m r^2``: crossover ``w_c = 1/(2 T_sigma)``, ``Kv = J_tot w_c``,
  ``Ti = 4 T_sigma = 2/w_c``; the position loop closed four times slower,
  ``Kp = w_c/4``; ``w_c`` then lowered (bisection) until the loop with the
  belt mode keeps a gain margin of 2 and a modulus margin of 0.5. Giving
  ``speed_bandwidth_Hz`` replaces ``w_c``; ``tuning = "manual"`` with the
  three gains replaces the rule.

Results are the periodic steady state of the loop (found exactly from the
state transition over one cycle), not a start-up transient.
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass

import numpy as np

from ..errors import ProblemError, SolverError
from .lti import StateSpace, pade, pade_delay, periodic_steady_state, stability_margins
from .plant import DriveAxis
from .settings import ServoSettings


# --------------------------------------------------------------------------- tuning


@dataclass(frozen=True)
class Gains:
    position_gain: float  # Kp [1/s]
    speed_gain: float  # Kv [N m s/rad]
    speed_integral_time: float  # Ti [s]
    speed_bandwidth: float  # w_c [rad/s] (rule) or Kv/J_tot (manual)
    rule: str

    def as_dict(self) -> dict:
        return {"position_gain_1_s": self.position_gain, "speed_gain_N_m_s_rad": self.speed_gain,
                "speed_integral_time_ms": self.speed_integral_time * 1e3,
                "speed_bandwidth_Hz": self.speed_bandwidth / (2 * math.pi), "tuning": self.rule}


#: Robustness the tuning rule asks for: gain margin and modulus (stability) margin of the loop.
MIN_GAIN_MARGIN = 2.0  # 6 dB
MIN_MODULUS_MARGIN = 0.5  # sensitivity peak <= 2


def _rule_gains(axis: DriveAxis, wc: float, rule: str) -> Gains:
    return Gains(wc / 4, axis.total_inertia * wc, 2 / wc, wc, rule)


def tune(axis: DriveAxis, settings: ServoSettings) -> Gains:
    """Gains by the stated rule, or the manual ones.

    Rule: the symmetric optimum on the rigid total inertia with the crossover
    ``w_c = 1/(2 T_sigma)`` from the sampling (or ``speed_bandwidth_Hz``);
    where the belt resonance leaves the loop less robust than a gain margin of
    2 (6 dB) and a modulus margin of 0.5 (sensitivity peak 2), ``w_c`` is
    lowered (bisection) until it meets both. A given ``speed_bandwidth_Hz`` is
    taken as it is (and only checked for stability).
    """
    if settings.tuning == "manual":
        return Gains(settings.position_gain, settings.speed_gain, settings.speed_integral_time,
                     settings.speed_gain / axis.total_inertia, "manual")
    if settings.speed_bandwidth:
        return _rule_gains(axis, settings.speed_bandwidth, "symmetric optimum, w_c = speed_bandwidth_Hz")
    wc0 = 1 / (2 * settings.sum_small_time_constants)
    if _robust(axis, settings, _rule_gains(axis, wc0, "")):
        return _rule_gains(axis, wc0, "symmetric optimum, w_c = 1/(2 T_sigma)")
    lo, hi = 0.0, wc0
    for _ in range(30):
        mid = 0.5 * (lo + hi)
        if _robust(axis, settings, _rule_gains(axis, mid, "")):
            lo = mid
        else:
            hi = mid
        if hi - lo < 1e-3 * wc0:
            break
    if lo <= 0:
        raise SolverError(f"no speed-loop bandwidth gives a robust servo loop with this {axis.compliance} and motor")
    why = (f"{axis.compliance} resonance {axis.resonance_hz:.0f} Hz" if axis.compliance != "rigid" else
           "on the largest inertia over the stroke, met at the least too")
    return _rule_gains(axis, lo, f"symmetric optimum, w_c = 1/(2 T_sigma) = {wc0 / (2 * math.pi):.0f} Hz lowered "
                                 f"for gain margin {MIN_GAIN_MARGIN:g} and modulus margin {MIN_MODULUS_MARGIN:g} ({why})")


@functools.lru_cache(maxsize=64)
def tuned_gains(axis: DriveAxis, settings: ServoSettings) -> Gains:
    """:func:`tune`, remembered for the last axes and settings (both hashable; bounded cache)."""
    return tune(axis, settings)


# --------------------------------------------------------------------------- the closed loop


def open_loop(axis: DriveAxis, settings: ServoSettings, gains: Gains) -> tuple[np.ndarray, np.ndarray]:
    """Loop transfer function broken at the torque command, ``Kv (1 + 1/(Ti s)) (1 + Kp/s) D(s) omega/tau``,
    as numerator and denominator coefficients (highest power of ``s`` first).

    The plant's ``omega/tau`` in closed form: ``(m s^2 + c s + k) / (s (J m s^2 + c J_tot s + k J_tot))``
    with ``J_tot = J + m r^2`` (the motor angle's double integrator, one of its poles cancelled by the
    speed output's zero at the origin); ``D(s)`` the Padé approximation of the loop delay."""
    j, m, c, k = axis.motor_inertia, axis.mass, axis.belt_damping, axis.belt_stiffness
    j_tot = axis.total_inertia
    kp, kv, ti = gains.position_gain, gains.speed_gain, gains.speed_integral_time
    pade_num, pade_den = pade(settings.sum_small_time_constants, settings.pade_order)
    num = kv * np.polymul(np.polymul(np.polymul([ti, 1.0], [1.0, kp]), [m, c, k]), pade_num)
    den = np.polymul(np.polymul([ti, 0.0, 0.0, 0.0], [j * m, c * j_tot, k * j_tot]), pade_den)
    return num, den


def loop_margins(axis: DriveAxis, settings: ServoSettings, gains: Gains) -> dict:
    """Gain margin, phase margin [deg] and modulus margin (distance of the Nyquist curve to -1); a rigid axis of
    varying inertia (servo/varying.py): the worse of its least and largest inertia."""
    if axis.compliance == "rigid":
        from .varying import rigid_open_loop

        both = [loop_margins_of(rigid_open_loop(settings, gains, j)) for j in axis.inertia_range]
        return {k: min(m[k] for m in both) for k in both[0]}
    return loop_margins_of(open_loop(axis, settings, gains))


def loop_margins_of(loop: tuple) -> dict:
    """:func:`loop_margins` of an open loop given as numerator and denominator coefficients."""
    gms, pms, sms = stability_margins(*loop)
    # the gain may rise by the smallest factor > 1 at a phase crossover (the integrators make
    # crossovers at low frequency where the gain could only fall: those are not margins)
    up = [float(g) for g in np.atleast_1d(gms) if g > 1]
    pm = [float(p) for p in np.atleast_1d(pms)]
    sm = [float(x) for x in np.atleast_1d(sms)]
    return {"gain_margin": min(up) if up else math.inf, "phase_margin_deg": min(pm) if pm else math.inf,
            "modulus_margin": min(sm) if sm else math.inf}


def _robust(axis: DriveAxis, settings: ServoSettings, gains: Gains) -> bool:
    m = loop_margins(axis, settings, gains)
    if not (m["gain_margin"] >= MIN_GAIN_MARGIN and m["modulus_margin"] >= MIN_MODULUS_MARGIN
            and m["phase_margin_deg"] > 0):
        return False
    if axis.compliance == "rigid":   # the margins at both ends of its inertia: no state space to build
        return True
    try:
        build_loop(axis, settings, gains)
    except SolverError:
        return False
    return True


@dataclass
class ServoLoop:
    """The closed loop as one state-space system (:class:`~.lti.StateSpace`).

    Inputs ``theta_ref, omega_ff, tau_ff, F_ext``; outputs ``theta`` (motor
    angle), ``stretch`` (r theta - x), ``x`` (bar), ``tau_cmd`` (torque
    command before the loop delay).
    """

    axis: DriveAxis
    settings: ServoSettings
    gains: Gains
    system: StateSpace

    @property
    def poles(self) -> np.ndarray:
        return np.linalg.eigvals(self.system.A)

    def stability_margin(self) -> float:
        """Largest real part of the closed-loop poles [1/s]; negative when stable."""
        return float(np.max(self.poles.real))


def build_loop(axis: DriveAxis, settings: ServoSettings, gains: Gains | None = None) -> ServoLoop:
    """The closed loop (state space); :class:`SolverError` if it is unstable."""
    gains = gains or tune(axis, settings)
    for name, value in (("position_gain_1_s", gains.position_gain), ("speed_gain_N_m_s_rad", gains.speed_gain),
                        ("speed_integral_time_ms", gains.speed_integral_time)):
        if not (value > 0 and math.isfinite(value)):
            raise ProblemError(settings.file, f"servo.{name}", f"must be positive, got {value!r}")
    j, r, m = axis.motor_inertia, axis.radius, axis.mass
    kp, kv, ti = gains.position_gain, gains.speed_gain, gains.speed_integral_time
    delay = pade_delay(settings.sum_small_time_constants, settings.pade_order)
    nd = delay.nstates
    # states: plant theta, omega, x, v (0-3); the delay's (4 .. 3 + nd); the speed controller's integral z
    # inputs: theta_ref, omega_ff, tau_ff, F_ext; outputs: theta, stretch (r theta - x), x, tau_cmd
    n = 4 + nd + 1
    # the PI speed controller with the P position controller and the feed-forwards:
    # e_w = kp (theta_ref - theta) + omega_ff - omega;  z' = e_w;  tau_cmd = kv e_w + kv/ti z + tau_ff
    e_x = np.zeros(n)
    e_x[[0, 1]] = -kp, -1.0
    e_u = np.array([kp, 1.0, 0.0, 0.0])
    cmd_x = kv * e_x
    cmd_x[-1] = kv / ti
    cmd_u = kv * e_u + np.array([0.0, 0.0, 1.0, 0.0])
    # the torque at the motor: the delay's output, tau = C_d x_d + D_d tau_cmd
    tau_x = float(delay.D[0, 0]) * cmd_x
    tau_x[4:4 + nd] += delay.C[0]
    tau_u = float(delay.D[0, 0]) * cmd_u
    a = np.zeros((n, n))
    b = np.zeros((n, 4))
    a[:4, :4] = axis.state_matrix()
    a[1] += tau_x / j  # J omega' = tau - r F_belt
    b[1] += tau_u / j
    b[3, 3] = 1 / m  # m v' = F_belt + F_ext
    a[4:4 + nd, 4:4 + nd] = delay.A
    a[4:4 + nd] += np.outer(delay.B[:, 0], cmd_x)
    b[4:4 + nd] += np.outer(delay.B[:, 0], cmd_u)
    a[-1] = e_x
    b[-1] = e_u
    c = np.zeros((4, n))
    c[0, 0] = 1.0
    c[1, 0], c[1, 2] = r, -1.0
    c[2, 2] = 1.0
    c[3] = cmd_x
    d = np.zeros((4, 4))
    d[3] = cmd_u
    loop = ServoLoop(axis, settings, gains, StateSpace(a, b, c, d))
    if loop.stability_margin() >= 0:
        raise SolverError(f"the servo loop is unstable with these gains (Kp = {kp:.4g} 1/s, Kv = {kv:.4g} N m s/rad, "
                          f"Ti = {ti * 1e3:.4g} ms, loop delay {settings.sum_small_time_constants * 1e6:.0f} us, "
                          f"{axis.compliance} resonance {axis.resonance_hz:.0f} Hz): lower the speed bandwidth or the gains")
    return loop


# --------------------------------------------------------------------------- the periodic response


#: Simulation steps per table interval.
STEPS_PER_CYCLE = 12


def table_interval(period: float, settings: ServoSettings) -> float:
    """The time between two table points the drive reads: the control cycle, rounded so that a
    whole number of table points fills the stitch cycle (the table is periodic in cam angle)."""
    return period / max(1, round(period / settings.control_cycle))


def cycle_grid(period: float, settings: ServoSettings) -> np.ndarray:
    """One period of uniform time points, ``STEPS_PER_CYCLE`` per table interval, placed half a
    step off the table points (as the drive sees them, after the loop delay) so that the linear
    interpolation between points treats each step of the feed-forward symmetrically."""
    tc = table_interval(period, settings)
    h = tc / STEPS_PER_CYCLE
    t0 = (settings.sum_small_time_constants + h / 2) % h
    n = round(period / h)
    return t0 + h * np.arange(n + 1)


def reference_signals(loop: ServoLoop, stroke, t: np.ndarray, *, forces: bool = True,
                      load_ff: bool | None = None, phase: float = 0.0) -> np.ndarray:
    """The loop's inputs over ``t``: rows theta_ref, omega_ff, tau_ff, F_ext.

    The drive reads the position table every control cycle ``T_c`` at
    ``t_k = k T_c`` and interpolates linearly between the points; the speed
    feed-forward is the table's difference quotient held over the cycle, the
    acceleration feed-forward the difference of two of them, held over the
    cycle centred on the table point. The torque feed-forward is the rigid
    load torque ``J_tot eps - r F_ext`` (with ``load_feedforward``, else the
    inertia term only). The drive delays its position and speed references by
    the loop delay ``T_sigma`` so that they meet the feed-forward torque at the
    motor (the torque passes the loop delay); the commanded bar position the
    error is measured against is the stroke delayed by the same ``T_sigma``.
    ``phase`` shifts the table points by that fraction of the table interval
    (where the control cycles fall relative to the stroke is a matter of chance).
    """
    s = loop.settings
    axis = loop.axis
    tc = table_interval(stroke.period, s)
    d = s.sum_small_time_constants
    shift = phase * tc
    t = t - shift
    tt = t - d  # time as the reference sees it
    k = np.floor(tt / tc + 1e-9).astype(int)
    kc = np.round(t / tc).astype(int)
    k_lo = min(k.min(), kc.min()) - 1
    k_hi = max(k.max(), kc.max()) + 2
    # the position table the drive reads, in motor angles
    table = axis.motor_angle(stroke.evaluate(np.arange(k_lo, k_hi + 1) * tc + shift).s)

    def pos(i):
        return table[i - k_lo]

    w = (tt - k * tc) / tc
    p0, p1 = pos(k), pos(k + 1)
    theta_ref = (1 - w) * p0 + w * p1
    omega_ff = (p1 - p0) / tc if s.velocity_feedforward else 0 * t
    # acceleration: second difference centred on the nearest table point
    eps = (pos(kc + 1) - 2 * pos(kc) + pos(kc - 1)) / (tc * tc)
    # the external forces act where the bar is: on the commanded stroke as the loop follows it (delayed)
    held = stroke.evaluate(t + shift - d) if forces and axis.compliance != "rigid" else None
    f_ext = axis.external_force(held.s, held.v) if held is not None else 0 * t
    tau_ff = axis.feedforward(pos(kc), (pos(kc + 1) - pos(kc - 1)) / (2 * tc), eps, s.acceleration_feedforward,
                              s.load_feedforward if load_ff is None else load_ff)
    return np.vstack([theta_ref, omega_ff, tau_ff, f_ext])


def simulate_loop(loop: ServoLoop, stroke, t: np.ndarray | None = None, *, forces: bool = True):
    """Periodic steady state of the closed loop following ``stroke``: ``(t, outputs, inputs)``.

    ``outputs`` rows: theta, stretch, x, tau_cmd; ``inputs`` see :func:`reference_signals`.
    """
    t = cycle_grid(stroke.period, loop.settings) if t is None else t
    u = reference_signals(loop, stroke, t, forces=forces)
    return t, periodic_response(loop.system, t, u)[0], u


def periodic_response(sys: StateSpace, t: np.ndarray, *inputs: np.ndarray) -> list[np.ndarray]:
    """Outputs of the periodic steady state for each periodic input over one period ``t``.

    The state at the cycle start solves ``x0 = Phi x0 + x_forced(T)`` with the state transition
    ``Phi = exp(A T)`` (the closed loop is stable, so ``I - Phi`` is invertible); the inputs are
    simulated together, one set of inputs per column of the state (:func:`.lti.periodic_steady_state`).
    """
    y = periodic_steady_state(sys, t, np.stack(inputs, axis=-1))
    return [y[:, :, i] for i in range(len(inputs))]
