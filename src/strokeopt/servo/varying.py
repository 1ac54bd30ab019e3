"""The servo loop through a transmission whose ratio varies with its position (a crank and connecting rod, a linkage
on its crank): the same cascade controller as :mod:`.loop`, closed around the rigid drive's own nonlinear dynamics.

Where the ratio ``mu = dx/dphi`` changes over the stroke, the inertia the motor sees, ``J(phi) = J_rotor + J_own(phi)
+ m mu(phi)^2``, changes with it and the torque has a speed term ``1/2 J'(phi) omega^2``: the plant is no longer
linear, and the loop's periodic response cannot be had from one state transition (:mod:`.lti`). Here:

* **Plant**: rigid, one degree of freedom in the motor angle: ``tau = T(phi, omega, eps)``, the load torque of
  :func:`~strokeopt.drive.load.load_torque` (the same function as the sizing and the design, through the
  transmission's AD transfer functions), solved for the motor's acceleration ``eps`` (affine in it for a lossless
  drive; two Newton steps where an efficiency makes it piecewise).
* **Controller**: :mod:`.loop`'s: P position, PI speed, the loop delay ``T_sigma`` as its Pade approximation,
  velocity feed-forward; the torque feed-forward is the rigid drive's own inverse dynamics at the table's points,
  ``J(theta) eps + 1/2 J'(theta) omega^2`` (acceleration feed-forward) plus the torque at rest there (gravity,
  springs: load feed-forward), the table being the stroke in motor angles (what a drive with a cam table in
  motor angle and a torque table does). Gains by the symmetric optimum on the *largest* inertia over the stroke,
  the crossover lowered until the margins the rule asks for hold at the least inertia too (where the same gains
  make the loop fastest, nearest the delay).
* **Simulation**: CasADi's Runge-Kutta integrator (:data:`RK_STEPS` RK4 steps) over each step of
  :func:`.loop.cycle_grid` with the inputs linear over the step (as :mod:`.lti` holds them), chained over the cycle
  (``mapaccum``), cycle after cycle from the commanded state until the state at the cycle's start repeats (the
  periodic steady state).

The error at the load is ``x_cmd - x(phi)``: all of it servo tracking (a rigid drive has no stretch); one encoder
count at the load is ``2 pi / counts`` times the ratio at the handover position.
"""

from __future__ import annotations

from dataclasses import dataclass

import casadi as ca
import numpy as np

from ..drive.load import load_torque
from ..errors import SolverError
from .lti import pade_delay

#: CasADi's fixed-step Runge-Kutta (RK4) steps per step of the grid (12 per table interval: about 10 us each at
#: 500 us). The loop's fastest pole (the delay's Pade, about pade_order / T_sigma = 6000 1/s) times the step is
#: 0.06, far inside RK4's stability; the reference needle bar's handover error through a crank agrees with CVODES to
#: about 0.1 % (`strokeopt bench --only servo_varying` prints both, and their times side by side).
RK_STEPS = 4
#: Cycles simulated at most before the state at the cycle's start repeats (the loop settles within a few ms; a
#: machine cycle is tens of ms or more: two or three cycles do).
MAX_CYCLES = 20
#: The change of the motor angle [rad] over one cycle below which the response is periodic (a millionth of an
#: encoder count of 16384 a turn is 4e-10 rad).
PERIODIC_TOL_RAD = 1e-10


@dataclass(frozen=True, eq=False)
class VaryingAxis:
    """A servo motor on a transmission of varying ratio, rigid: what :func:`.plant.axis_from_problem` returns for it.

    ``inertia_range``: the least and largest inertia on the motor shaft over the stroke [kg m^2] (the tuning rule
    uses the least); ``handover_ratio``: ``|dx/dphi|`` at the handover position (m/rad, or rad/rad on a rotary
    load)."""

    transmission: object
    rotor_inertia: float
    load: object
    torque_limit: float
    motor: str
    rotary: bool
    inertia_range: tuple[float, float]
    handover_ratio: float
    compliance: str = "rigid"
    belt_note: str = ""

    @property
    def total_inertia(self) -> float:
        """The inertia the gains are set on: the largest (its speed loop the slowest, the PI's and position loop's
        corners placed for it); where the inertia is less, the loop is faster and the tuning rule lowers the
        crossover until the margins hold there too."""
        return self.inertia_range[1]

    @property
    def radius(self) -> float:
        """The ratio at the handover [m/rad]: a motor angle error there times it is the load's."""
        return self.handover_ratio

    def motor_angle(self, s):
        return self.transmission.motor_angle(np.asarray(s, dtype=float))

    def dynamics(self) -> ca.Function:
        """``(phi, omega, tau) -> eps``, and ``(phi, omega, eps) -> (tau, J, tau at rest)`` of the rigid drive."""
        if "_dyn" not in self.__dict__:
            phi, omega, eps, tau = (ca.SX.sym(n) for n in ("phi", "omega", "eps", "tau"))
            x, mu, nu = self.transmission.symbolic_transfer(phi)

            def torque(p, w, e):
                return load_torque(self.rotor_inertia, self.transmission, self.load, ca.substitute(x, phi, p),
                                   ca.substitute(mu, phi, p) * w, ca.substitute(mu, phi, p) * e
                                   + ca.substitute(nu, phi, p) * w**2).total

            total = torque(phi, omega, eps)
            j = ca.jacobian(total, eps)
            acc = 0 * tau
            for _ in range(2):   # Newton in eps: exact after the first step where the torque is affine in it
                acc = acc - (ca.substitute(total, eps, acc) - tau) / ca.substitute(j, eps, acc)
            forward = ca.Function("forward", [phi, omega, tau], [acc])
            inverse = ca.Function("inverse", [phi, omega, eps], [total, j, torque(phi, 0 * omega, 0 * eps)])
            object.__setattr__(self, "_dyn", (forward, inverse))
        return self.__dict__["_dyn"]

    def feedforward(self, theta, omega, eps, acceleration: bool, load: bool) -> np.ndarray:
        """The drive's torque feed-forward at table points (motor angle, speed, acceleration): the inertial part of
        the rigid torque (``acceleration``) and its part at rest there (``load``: gravity and springs)."""
        _, inverse = self.dynamics()
        total, _, rest = (np.ravel(np.asarray(v, dtype=float)) for v in inverse.map(len(np.ravel(theta)))(
            np.ravel(theta)[None, :], np.ravel(omega)[None, :], np.ravel(eps)[None, :]))
        return (total - rest) * acceleration + rest * load

    def facts(self, scale: float, unit: str) -> dict:
        """The axis's numbers for the accuracy report (:meth:`~.accuracy.AccuracyResult.summary`)."""
        return {"transmission": self.transmission.name, "inertia_range_kg_m2": list(self.inertia_range),
                f"handover_ratio_{unit}_per_rad": self.handover_ratio * scale}


def varying_axis(problem, motor, torque_limit: float) -> VaryingAxis:
    """The rigid axis of ``problem``'s motor on its transmission of varying ratio."""
    tr, load, timing = problem.transmission, problem.drive.load, problem.timing
    lo, hi = timing.position_range
    s = np.linspace(lo, hi, 401)
    phi = tr.motor_angle(s)
    axis = VaryingAxis(tr, motor.rotor_inertia, load, torque_limit, motor.name, timing.rotary, (0.0, 0.0), 0.0)
    _, inverse = axis.dynamics()
    _, j, _ = inverse.map(len(phi))(phi[None, :], np.zeros((1, len(phi))), np.zeros((1, len(phi))))
    j = np.ravel(np.asarray(j, dtype=float))
    handover = next((itv for itv in timing.intervals if itv.handover), None)
    at = handover.end_position if handover is not None else lo
    _, mu, _ = tr.transfer(np.atleast_1d(tr.motor_angle(np.atleast_1d(at))))
    return VaryingAxis(tr, motor.rotor_inertia, load, torque_limit, motor.name, timing.rotary,
                       (float(j.min()), float(j.max())), float(abs(np.ravel(mu)[0])))


def simulate_varying(axis: VaryingAxis, settings, gains, t: np.ndarray, u: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The periodic steady state over the grid ``t`` (one cycle) of the loop with inputs ``u`` (rows theta_ref,
    omega_ff, tau_ff, linear between the points): the motor angle and the torque command at every point."""
    forward, _ = axis.dynamics()
    delay = pade_delay(settings.sum_small_time_constants, settings.pade_order)
    nd = delay.nstates
    kp, kv, ti = gains.position_gain, gains.speed_gain, gains.speed_integral_time
    h = float(t[1] - t[0])
    x = ca.SX.sym("x", 3 + nd)          # phi, omega, z, the delay's states
    p = ca.SX.sym("p", 6)               # the inputs at the step's start and end
    tau_t = ca.SX.sym("t")
    ref = p[:3] + (p[3:] - p[:3]) * tau_t / h
    phi, omega, z, xd = x[0], x[1], x[2], x[3:]
    e_w = kp * (ref[0] - phi) + ref[1] - omega
    cmd = kv * e_w + kv / ti * z + ref[2]
    torque = ca.mtimes(ca.DM(delay.C), xd) + float(delay.D[0, 0]) * cmd
    ode = ca.vertcat(omega, forward(phi, omega, torque), e_w,
                     ca.mtimes(ca.DM(delay.A), xd) + ca.DM(delay.B) * cmd)
    step = ca.integrator("servo_step", "rk", {"x": x, "p": p, "t": tau_t, "ode": ode}, 0.0, h,
                         {"number_of_finite_elements": RK_STEPS})
    n = len(t) - 1
    cycle = step.mapaccum(n)
    params = np.vstack([u[:, :-1], u[:, 1:]])
    x0 = np.zeros(3 + nd)
    x0[0], x0[1] = u[0, 0], u[1, 0]
    for _ in range(MAX_CYCLES):
        states = np.asarray(cycle(x0=x0, p=params)["xf"], dtype=float)
        done = abs(states[0, -1] - x0[0]) <= PERIODIC_TOL_RAD
        x0 = states[:, -1]
        if done:
            break
    else:
        raise SolverError(f"the servo loop through the {axis.transmission.label} did not settle into a periodic "
                          f"response within {MAX_CYCLES} cycles")
    states = np.hstack([x0[:, None], states])   # the cycle's start (periodic: its end) and every step
    e = kp * (u[0] - states[0]) + u[1] - states[1]
    return states[0], kv * e + kv / ti * states[2] + u[2]


def rigid_open_loop(settings, gains, inertia: float) -> tuple[np.ndarray, np.ndarray]:
    """The loop broken at the torque command on a rigid inertia: ``Kv (Ti s + 1)(s + Kp) D(s) / (Ti J s^3)``."""
    from .lti import pade

    pn, pd = pade(settings.sum_small_time_constants, settings.pade_order)
    num = gains.speed_gain * np.polymul(np.polymul([gains.speed_integral_time, 1.0], [1.0, gains.position_gain]), pn)
    den = np.polymul([gains.speed_integral_time * inertia, 0.0, 0.0, 0.0], pd)
    return num, den
