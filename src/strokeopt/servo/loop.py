"""Servo loop and belt compliance: how far the bar is from its commanded position.

The model (python-control, continuous time, linear):

* **Plant**: a two-mass system. The motor side (rotor + driving pulley,
  inertia ``J``) turns at angle ``theta``; the belt, a spring of stiffness
  ``k`` with damping ``c``, pulls the bar (mass ``m``, position ``x``,
  upward as in the problem file) towards ``r*theta``::

      J theta'' = tau - r*F_belt,      m x'' = F_belt + F_ext,
      F_belt = k (r theta - x) + c (r theta' - x')

  ``F_ext`` is gravity and the load forces of the problem's ``[drive]``
  (the bar's springs), evaluated along the commanded stroke.
* **Belt stiffness** (``EA`` from the belt catalogue, ``tensile_stiffness_glass_N``:
  an estimate, see ``catalogue/gt3_belts.toml``): the carrier is clamped in one span; the driving pulley
  pulls it through the span piece of length ``l1`` (pulley to carrier) and,
  the other way round, through the rest of the loop ``l2 = belt length -
  l1 - half the pulley's wrap``; both pieces are pretensioned springs in
  parallel, ``k = EA/l1 + EA/l2`` with ``EA`` = specific stiffness x width.
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
  ``T_sigma`` (a delay common to both synchronised bars). Where the table
  points fall relative to the stroke is chance: the result is the worst of
  :data:`TABLE_PHASES`.
* **Tuning rule** (default gains, not fitted to any measurement): the
  symmetric optimum for the speed loop on the rigid total inertia
  ``J_tot = J + m r^2``: crossover ``w_c = 1/(2 T_sigma)``, ``Kv = J_tot w_c``,
  ``Ti = 4 T_sigma = 2/w_c``; the position loop closed four times slower,
  ``Kp = w_c/4``; ``w_c`` then lowered (bisection) until the loop with the
  belt mode keeps a gain margin of 2 and a modulus margin of 0.5. Giving
  ``speed_bandwidth_Hz`` replaces ``w_c``; ``tuning = "manual"`` with the
  three gains replaces the rule.
* **Torque limit**: ``min(motor peak torque, drive peak limit x rated
  torque)``. The model is linear: where the torque command exceeds the
  limit the prediction does not hold, and the result says so
  (``torque_limited``) instead of reporting a number that is not true.
* **Encoder quantisation**: the position loop cannot resolve less than one
  encoder count; one count at the bar (``2 pi r / counts``) is added to the
  handover error as a bound.

The bar's error ``x_cmd - x`` splits exactly into the servo tracking error
``r (theta_cmd - theta)`` (what the drive itself reports as following
error) and the belt stretch ``r theta - x``; the belt stretch is split
further by superposition into its parts due to the bar's inertia and due
to the external forces.

Results are the periodic steady state of the loop (found exactly from the
state transition over one cycle), not a start-up transient. The handover
error is the largest bar error over ``handover_window_deg`` after the end of
the handover move, plus one encoder count.

Beyond the prediction (``strokeopt accuracy``):

* :func:`servo_handover_error` is the servo's term of the design's handover
  accuracy constraint (``design.HANDOVER_ERROR_TERMS``): the same loop as an
  exact linear functional of the move accelerations (:class:`ErrorKernel`);
* :func:`tradeoff` (``strokeopt tradeoff``): the highest stitch rate for each
  required accuracy, classic law and optimal stroke, with the binding limit.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace
from pathlib import Path

import numpy as np

from ..drive.sizing import bisect_highest
from ..errors import ProblemError, SolverError

#: Keys of ``contributions_mm`` in an accuracy report.
CONTRIBUTIONS = ("servo_tracking", "belt_stretch", "encoder_quantisation")
TUNING_RULES = ("symmetric_optimum", "manual")

#: GT3 glass-cord belt, tensile stiffness per mm of width [N per unit strain], for a
#: belt without catalogue data. Estimate, not a maker's figure: breaking tension of the
#: 9 mm belt 1990 N (digest A.4) over an elongation at break of 4 % for glass cord
#: -> EA = 49.75 kN for 9 mm, 5.5 kN per mm of width. The catalogue belts carry the same
#: estimate as ``tensile_stiffness_glass_N``; ``[servo] belt_specific_stiffness_N_per_mm``
#: replaces both.
GT3_GLASS_SPECIFIC_STIFFNESS_N_PER_MM = 5500.0


# --------------------------------------------------------------------------- settings ([servo])


@dataclass(frozen=True)
class ServoSettings:
    """The ``[servo]`` section of a problem file, SI units.

    Gains left at None come from the tuning rule (module docstring).
    """

    position_sampling: float = 250e-6  # s
    control_cycle: float = 500e-6  # s
    current_loop_time_constant: float = 125e-6  # s
    encoder_counts: int = 16384  # per motor revolution
    velocity_feedforward: bool = True
    acceleration_feedforward: bool = True
    load_feedforward: bool = True
    tuning: str = "symmetric_optimum"
    speed_bandwidth: float | None = None  # rad/s (crossover of the speed loop)
    position_gain: float | None = None  # 1/s
    speed_gain: float | None = None  # N m s/rad
    speed_integral_time: float | None = None  # s
    belt_span: float = 139.5e-3  # m, free span between the pulleys (= centre distance, equal pulleys)
    carrier_from_pulley: float | None = None  # m, driving pulley to carrier at the handover (None: mid-span)
    belt_length: float | None = None  # m (None: 2 span + pi PD)
    belt_specific_stiffness: float | None = None  # N per unit strain per m of width (None: catalogue or estimate)
    belt_width: float = 9e-3  # m, used when no belt is named in [drive]
    belt_damping_ratio: float = 0.05
    pade_order: int = 3
    handover_window: float = 10.0  # deg of cam angle after the end of the handover move
    file: str = ""

    @property
    def sum_small_time_constants(self) -> float:
        """T_sigma: sample-and-hold (T_p/2) + computation (T_p) + current loop."""
        return 1.5 * self.position_sampling + self.current_loop_time_constant


def parse_servo(f, timing=None, spm: float | None = None) -> ServoSettings:
    """Read the ``[servo]`` table (a :class:`~strokeopt.problem.Fields`).

    With ``timing`` and ``spm`` it also checks that the sampling is shorter
    than the shortest move.
    """
    s = ServoSettings(file=f.file)
    tp = f.number("position_sampling_us", 250.0, positive=True) * 1e-6
    tc = f.number("control_cycle_us", 500.0, positive=True) * 1e-6
    ti = f.number("current_loop_time_constant_us", 125.0, min=0.0) * 1e-6
    counts = f.number("encoder_counts_per_rev", 16384, integer=True, min=1)
    vff = f.boolean("velocity_feedforward", True)
    aff = f.boolean("acceleration_feedforward", True)
    lff = f.boolean("load_feedforward", True)
    tuning = f.string("tuning", "symmetric_optimum", choices=TUNING_RULES)
    bw = f.number("speed_bandwidth_Hz", None, positive=True)
    kp = f.number("position_gain_1_s", None, positive=True)
    kv = f.number("speed_gain_N_m_s_rad", None, positive=True)
    tn = f.number("speed_integral_time_ms", None, positive=True)
    if tuning == "manual":
        for key, value in (("position_gain_1_s", kp), ("speed_gain_N_m_s_rad", kv), ("speed_integral_time_ms", tn)):
            if value is None:
                raise f.error(key, "is required with tuning = \"manual\" (or use tuning = \"symmetric_optimum\")")
        if bw is not None:
            raise f.error("speed_bandwidth_Hz", "is set by the gains with tuning = \"manual\"; remove it")
    else:
        for key, value in (("position_gain_1_s", kp), ("speed_gain_N_m_s_rad", kv), ("speed_integral_time_ms", tn)):
            if value is not None:
                raise f.error(key, "is only used with tuning = \"manual\" (the symmetric optimum sets the gains; "
                                   "change speed_bandwidth_Hz instead)")
    span = f.number("belt_span_mm", 139.5, positive=True) * 1e-3
    carrier = f.number("carrier_from_pulley_mm", None, positive=True)
    carrier = None if carrier is None else carrier * 1e-3
    if carrier is not None and not carrier < span:
        raise f.error("carrier_from_pulley_mm", f"{carrier * 1e3:g} mm is not inside the belt span of {span * 1e3:g} mm")
    length = f.number("belt_length_mm", None, positive=True)
    length = None if length is None else length * 1e-3
    if length is not None and not length > 2 * span:
        raise f.error("belt_length_mm", f"{length * 1e3:g} mm cannot wrap two pulleys {span * 1e3:g} mm apart")
    stiff = f.number("belt_specific_stiffness_N_per_mm", None, positive=True)
    width = f.number("belt_width_mm", 9.0, positive=True) * 1e-3
    zeta = f.number("belt_damping_ratio", 0.05, positive=True, max=1.0)
    order = f.number("pade_order", 3, integer=True, min=1, max=8)
    window = f.number("handover_window_deg", 10.0, min=0.0, max=90.0)
    f.finish()
    if timing is not None and spm is not None:
        check_sampling(tp, tc, timing, spm, (f.file, f.where("position_sampling_us"), f.where("control_cycle_us")))
    return replace(s, position_sampling=tp, control_cycle=tc, current_loop_time_constant=ti, encoder_counts=counts,
                   velocity_feedforward=vff, acceleration_feedforward=aff, load_feedforward=lff, tuning=tuning,
                   speed_bandwidth=None if bw is None else 2 * math.pi * bw, position_gain=kp, speed_gain=kv,
                   speed_integral_time=None if tn is None else tn * 1e-3, belt_span=span,
                   carrier_from_pulley=carrier, belt_length=length,
                   belt_specific_stiffness=None if stiff is None else stiff * 1e3, belt_width=width,
                   belt_damping_ratio=zeta, pade_order=order, handover_window=window)


def shortest_move(timing, spm: float) -> float:
    sch = timing.schedule(spm)
    return float(min(d for itv, d in zip(timing.intervals, sch.duration) if itv.is_move))


def check_sampling(tp: float, tc: float, timing, spm: float, where=("", "servo.position_sampling_us",
                                                                     "servo.control_cycle_us")) -> None:
    """A sampling time as long as a move cannot follow it: a :class:`ProblemError` naming the field."""
    move = shortest_move(timing, spm)
    for value, fld in ((tp, where[1]), (tc, where[2])):
        if value >= move:
            raise ProblemError(where[0], fld, f"{value * 1e6:g} us is not shorter than the shortest move "
                                              f"({move * 1e6:.0f} us at {spm:g} spm): the drive could not follow it")


# --------------------------------------------------------------------------- the axis


@dataclass(frozen=True)
class DriveAxis:
    """The mechanics of one servo axis with a belt to a translating bar, SI units."""

    motor_inertia: float  # rotor + driving pulley [kg m^2]
    radius: float  # pulley pitch radius [m]
    mass: float  # moving mass of the bar, carrier and belt [kg]
    belt_stiffness: float  # [N/m] at the carrier
    belt_damping: float  # [N s/m]
    torque_limit: float  # [N m]
    load: object = None  # drive.Load (gravity and load forces), or None
    motor: str = ""
    belt_note: str = ""

    @property
    def total_inertia(self) -> float:
        return self.motor_inertia + self.mass * self.radius**2

    @property
    def resonance_hz(self) -> float:
        """Natural frequency of the two-mass belt mode (motor and bar moving against each other)."""
        return math.sqrt(self.belt_stiffness * (1 / self.mass + self.radius**2 / self.motor_inertia)) / (2 * math.pi)

    def external_force(self, s) -> np.ndarray:
        """Gravity plus the load forces on the bar [N], positive upward, along the positions ``s``."""
        s = np.asarray(s, dtype=float)
        if self.load is None:
            return np.zeros_like(s)
        out = self.load.moving_mass * self.load.gravity + 0 * s
        for force in self.load.forces:
            out = out + np.asarray(force(s), dtype=float)
        return out


def belt_stiffness(specific_stiffness: float, width: float, span: float, carrier: float | None,
                   belt_length: float | None, pitch_diameter: float) -> float:
    """Stiffness [N/m] of the belt at the carrier: the two belt pieces from the pulley in parallel."""
    if not span > 0:
        raise ValueError("the belt span must be positive")
    l1 = span / 2 if carrier is None else carrier
    length = 2 * span + math.pi * pitch_diameter if belt_length is None else belt_length
    l2 = length - l1 - math.pi * pitch_diameter / 2
    ea = specific_stiffness * width
    return ea / l1 + ea / l2


def axis_from_problem(problem, settings: ServoSettings | None = None, *, motor=None, pulley_teeth: int | None = None,
                      radius: float | None = None) -> DriveAxis:
    """The :class:`DriveAxis` of a problem: motor, pulley, belt and load from its ``[drive]``
    and the catalogue, belt geometry and stiffness from ``[servo]``."""
    settings = settings or getattr(problem, "servo", None) or ServoSettings(file=str(problem.file))
    drive = getattr(problem, "drive", None)
    file = str(problem.file)
    if drive is None:
        raise ProblemError(file, "drive", "the servo model needs the [drive] section (motor, moving_mass_kg)")
    catalogue = drive.catalogue()
    if motor is None:
        if drive.motor is None:
            raise ProblemError(file, "drive.motor", "name the motor of the axis (a catalogue name)")
        motor = catalogue.motor(drive.motor, (file, "drive.motor"))
    teeth = pulley_teeth if pulley_teeth is not None else problem.pulley_teeth
    if radius is None:
        pulley = next((p for p in catalogue.pulleys_of(drive.profile) if p.teeth == teeth), None)
        if pulley is None:
            raise ProblemError(file, "transmission.pulley_teeth", f"no {drive.profile} pulley with {teeth} teeth "
                                                                  "in the catalogue")
        radius, j_pulley = pulley.radius, pulley.inertia
    else:
        j_pulley = float(catalogue.pulley_inertia(drive.profile, 2 * radius))
    # EA of the belt: [servo] belt_specific_stiffness_N_per_mm (x width) if given, else the catalogue
    # belt's tensile_stiffness for the drive's cord, else the glass-cord estimate per mm of width
    width = settings.belt_width
    ea, note = None, ""
    if settings.belt_specific_stiffness is not None:
        ea, note = None, "[servo] belt_specific_stiffness_N_per_mm"
    if drive.belt is not None:
        belt = catalogue.belt(drive.belt, (file, "drive.belt"))
        width = belt.width
        if settings.belt_specific_stiffness is None and drive.belt_cord in belt.tensile_stiffness:
            ea = belt.tensile_stiffness[drive.belt_cord]
            note = f"catalogue belt {belt.name}, {drive.belt_cord} cord"
    if ea is None:
        if settings.belt_specific_stiffness is not None:
            ea = settings.belt_specific_stiffness * width
        else:
            ea = GT3_GLASS_SPECIFIC_STIFFNESS_N_PER_MM * 1e3 * width
            note = "estimate for GT3 glass cord (breaking tension / 4 % elongation)"
    k = belt_stiffness(ea / width, width, settings.belt_span, settings.carrier_from_pulley, settings.belt_length,
                       2 * radius)
    j = motor.rotor_inertia + j_pulley
    m = drive.load.moving_mass
    m_red = 1 / (1 / m + radius**2 / j)
    c = 2 * settings.belt_damping_ratio * math.sqrt(k * m_red)
    limit = min(motor.peak_torque, drive.limits.peak_limit_pct / 100 * motor.rated_torque)
    return DriveAxis(j, radius, m, k, c, limit, drive.load, motor.name, note)


# --------------------------------------------------------------------------- the loop


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
        raise SolverError("no speed-loop bandwidth gives a robust servo loop with this belt and motor")
    return _rule_gains(axis, lo, f"symmetric optimum, w_c = 1/(2 T_sigma) = {wc0 / (2 * math.pi):.0f} Hz lowered "
                                 f"for gain margin {MIN_GAIN_MARGIN:g} and modulus margin {MIN_MODULUS_MARGIN:g} "
                                 f"(belt resonance {axis.resonance_hz:.0f} Hz)")


def open_loop(axis: DriveAxis, settings: ServoSettings, gains: Gains):
    """Loop transfer function (python-control), broken at the torque command:
    ``Kv (1 + 1/(Ti s)) (1 + Kp/s) D(s) omega/tau``."""
    import control

    j, r, m, k, c = axis.motor_inertia, axis.radius, axis.mass, axis.belt_stiffness, axis.belt_damping
    a = np.array([[0, 1, 0, 0], [-k * r * r / j, -c * r * r / j, k * r / j, c * r / j], [0, 0, 0, 1],
                  [k * r / m, c * r / m, -k / m, -c / m]])
    plant = control.ss2tf(control.ss(a, [[0], [1 / j], [0], [0]], [[0, 1, 0, 0]], 0))
    num, den = control.pade(settings.sum_small_time_constants, settings.pade_order)
    s = control.tf("s")
    pi = gains.speed_gain * (1 + 1 / (gains.speed_integral_time * s))
    return control.minreal(pi * (1 + gains.position_gain / s) * plant * control.tf(num, den), verbose=False)


def loop_margins(axis: DriveAxis, settings: ServoSettings, gains: Gains) -> dict:
    """Gain margin, phase margin [deg] and modulus margin (distance of the Nyquist curve to -1)."""
    import control

    gms, pms, sms, *_ = control.stability_margins(open_loop(axis, settings, gains), returnall=True)
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
    try:
        build_loop(axis, settings, gains)
    except SolverError:
        return False
    return True


@dataclass
class ServoLoop:
    """The closed loop as one python-control state-space system.

    Inputs ``theta_ref, omega_ff, tau_ff, F_ext``; outputs ``theta`` (motor
    angle), ``stretch`` (r theta - x), ``x`` (bar), ``tau_cmd`` (torque
    command before the loop delay).
    """

    axis: DriveAxis
    settings: ServoSettings
    gains: Gains
    system: object  # control.StateSpace

    @property
    def poles(self) -> np.ndarray:
        return np.linalg.eigvals(self.system.A)

    def stability_margin(self) -> float:
        """Largest real part of the closed-loop poles [1/s]; negative when stable."""
        return float(np.max(self.poles.real))


def build_loop(axis: DriveAxis, settings: ServoSettings, gains: Gains | None = None) -> ServoLoop:
    """The closed loop (python-control state space); :class:`SolverError` if it is unstable."""
    import control

    gains = gains or tune(axis, settings)
    for name, value in (("position_gain_1_s", gains.position_gain), ("speed_gain_N_m_s_rad", gains.speed_gain),
                        ("speed_integral_time_ms", gains.speed_integral_time)):
        if not (value > 0 and math.isfinite(value)):
            raise ProblemError(settings.file, f"servo.{name}", f"must be positive, got {value!r}")
    j, r, m, k, c = axis.motor_inertia, axis.radius, axis.mass, axis.belt_stiffness, axis.belt_damping
    # plant: states theta, omega, x, v; inputs tau, F_ext; outputs theta, omega, stretch, x
    a = np.array([[0, 1, 0, 0],
                  [-k * r * r / j, -c * r * r / j, k * r / j, c * r / j],
                  [0, 0, 0, 1],
                  [k * r / m, c * r / m, -k / m, -c / m]])
    b = np.array([[0, 0], [1 / j, 0], [0, 0], [0, 1 / m]])
    cmat = np.array([[1, 0, 0, 0], [0, 1, 0, 0], [r, 0, -1, 0], [0, 0, 1, 0]])
    plant = control.ss(a, b, cmat, np.zeros((4, 2)), inputs=["tau", "F_ext"],
                       outputs=["theta", "omega", "stretch", "x"], name="plant")
    num, den = control.pade(settings.sum_small_time_constants, settings.pade_order)
    delay = control.tf2ss(control.tf(num, den), inputs=["tau_cmd"], outputs=["tau"], name="delay")
    kp, kv, ti = gains.position_gain, gains.speed_gain, gains.speed_integral_time
    # PI speed controller with the P position controller and the feed-forwards:
    # e_w = kp (theta_ref - theta) + omega_ff - omega;  z' = e_w;  tau_cmd = kv e_w + kv/ti z + tau_ff
    row = np.array([[kp, 1.0, 0.0, -kp, -1.0]])  # over inputs theta_ref, omega_ff, tau_ff, theta, omega
    ctrl = control.ss(np.zeros((1, 1)), row, np.array([[kv / ti]]), kv * row + np.array([[0, 0, 1.0, 0, 0]]),
                      inputs=["theta_ref", "omega_ff", "tau_ff", "theta", "omega"], outputs=["tau_cmd"],
                      name="controller")
    system = control.interconnect(
        [plant, delay, ctrl], inplist=["theta_ref", "omega_ff", "tau_ff", "F_ext"],
        outlist=["theta", "stretch", "x", "tau_cmd"], inputs=["theta_ref", "omega_ff", "tau_ff", "F_ext"],
        outputs=["theta", "stretch", "x", "tau_cmd"], name="servo_loop")
    system = control.ss(system)
    loop = ServoLoop(axis, settings, gains, system)
    if loop.stability_margin() >= 0:
        raise SolverError(f"the servo loop is unstable with these gains (Kp = {kp:.4g} 1/s, Kv = {kv:.4g} N m s/rad, "
                          f"Ti = {ti * 1e3:.4g} ms, loop delay {settings.sum_small_time_constants * 1e6:.0f} us, "
                          f"belt resonance {axis.resonance_hz:.0f} Hz): lower the speed bandwidth or the gains")
    return loop


# --------------------------------------------------------------------------- simulation


@dataclass
class AccuracyResult:
    """Commanded vs. actual bar motion over one periodic cycle and the handover error.

    Arrays over ``t`` (one cycle, seconds): ``s_cmd``, ``x`` [m], errors [m]
    ``servo``, ``belt``, ``belt_inertia``, ``belt_load``; ``error = servo + belt``
    (= s_cmd - x), ``tau_cmd`` [N m].
    """

    spm: float
    period: float
    t: np.ndarray
    s_cmd: np.ndarray
    x: np.ndarray
    servo: np.ndarray
    belt: np.ndarray
    belt_load: np.ndarray
    tau_cmd: np.ndarray
    handover_time: float
    handover_index: int
    quantisation: float
    torque_limit: float
    loop: ServoLoop
    label: str = ""
    residual_window: tuple[float, float] = (0.0, 0.0)
    error_load: np.ndarray | None = None  # bar error caused by the external forces alone [m]

    @property
    def error(self) -> np.ndarray:
        return self.servo + self.belt

    @property
    def belt_inertia(self) -> np.ndarray:
        return self.belt - self.belt_load

    @property
    def angle_deg(self) -> np.ndarray:
        """Cam angle of the commanded stroke [deg] (the loop delay, common to every axis, taken out)."""
        return 360.0 * (self.t - self.loop.settings.sum_small_time_constants) / self.period

    def at_handover(self, arr) -> float:
        return float(np.interp(self.handover_time, self.t, arr))

    def _window(self) -> np.ndarray:
        """Samples from the end of the handover move over ``handover_window_deg`` of cam angle."""
        t1 = self.handover_time + self.loop.settings.handover_window / 360.0 * self.period
        return (self.t >= self.handover_time) & (self.t <= t1)

    def _worst(self, arr):
        """``arr`` at the instant of the largest |bar error| in the handover window (the end of the
        handover move itself included, interpolated)."""
        w = self._window()
        err = self.error
        at_end = self.at_handover(err)
        if np.any(w):
            idx = np.flatnonzero(w)[np.argmax(np.abs(err[w]))]
            if abs(err[idx]) > abs(at_end):
                return float(np.asarray(arr)[idx])
        return self.at_handover(arr)

    def at_handover_worst(self, arr) -> float:
        return self._worst(arr)

    @property
    def handover_error(self) -> float:
        """Largest |s_cmd - x| over the handover window plus one encoder count [m]."""
        return abs(self.at_handover_worst(self.error)) + self.quantisation

    @property
    def peak_torque_command(self) -> float:
        return float(np.max(np.abs(self.tau_cmd)))

    @property
    def torque_limited(self) -> bool:
        return self.peak_torque_command > self.torque_limit

    @property
    def residual_vibration(self) -> float:
        """Residual vibration of the belt mode [m]: the largest deviation of the belt stretch in the
        dwell after the handover from its value at the end of that dwell (where it has died out)."""
        t0, t1 = self.residual_window
        mask = (self.t >= t0) & (self.t <= t1)
        if not np.any(mask):
            return 0.0
        e = self.belt[mask]
        return float(np.max(np.abs(e - e[-1])))

    def contributions(self) -> dict:
        """The handover error by cause [m]: servo tracking and belt stretch at the instant of the
        largest error in the handover window (signed; they add up to it), encoder quantisation as a bound."""
        servo, belt, belt_load = (self._worst(a) for a in (self.servo, self.belt, self.belt_load))
        return {"servo_tracking": servo, "belt_stretch": belt, "encoder_quantisation": self.quantisation,
                "belt_stretch_inertia": belt - belt_load, "belt_stretch_forces": belt_load}

    def summary(self) -> dict:
        mm = 1e3
        c = self.contributions()
        axis = self.loop.axis
        return {
            "spm": self.spm,
            "label": self.label,
            "handover_error_mm": self.handover_error * mm,
            "contributions_mm": {k: abs(c[k]) * mm for k in CONTRIBUTIONS},
            "signed_contributions_mm": {k: v * mm for k, v in c.items()},
            "handover_window_deg": self.loop.settings.handover_window,
            "handover_angle_deg": 360.0 * (self.handover_time - self.loop.settings.sum_small_time_constants) / self.period,
            "pulley_error_at_handover_deg": math.degrees(abs(c["servo_tracking"]) / axis.radius),
            "max_error_mm": float(np.max(np.abs(self.error))) * mm,
            "max_servo_error_mm": float(np.max(np.abs(self.servo))) * mm,
            "max_belt_stretch_mm": float(np.max(np.abs(self.belt))) * mm,
            "residual_vibration_mm": self.residual_vibration * mm,
            "peak_torque_command_N_m": self.peak_torque_command,
            "torque_limit_N_m": self.torque_limit,
            "torque_limited": self.torque_limited,
            "motor": axis.motor,
            "pulley_pitch_diameter_mm": 2 * axis.radius * mm,
            "moving_mass_kg": axis.mass,
            "belt_stiffness_N_per_mm": axis.belt_stiffness * 1e-3,
            "belt_stiffness_source": axis.belt_note,
            "belt_resonance_Hz": axis.resonance_hz,
            "encoder_count_at_bar_um": self.quantisation * 1e6,
            "loop_delay_us": self.loop.settings.sum_small_time_constants * 1e6,
            "velocity_feedforward": self.loop.settings.velocity_feedforward,
            "acceleration_feedforward": self.loop.settings.acceleration_feedforward,
            "gains": self.loop.gains.as_dict(),
        }

    def plot(self, path=None):
        return plot_accuracy(self, path)


#: Simulation steps per table interval.
STEPS_PER_CYCLE = 12
#: Table phases tried (fractions of the table interval); the result is the worst of them.
TABLE_PHASES = (0.0, 0.25, 0.5, 0.75)


def table_interval(period: float, settings: ServoSettings) -> float:
    """The time between two table points the drive reads: the control cycle, rounded so that a
    whole number of table points fills the stitch cycle (the table is periodic in cam angle)."""
    return period / max(1, round(period / settings.control_cycle))


def _grid(period: float, settings: ServoSettings) -> np.ndarray:
    """One period of uniform time points, ``STEPS_PER_CYCLE`` per table interval, placed half a
    step off the table points (as the drive sees them, after the loop delay) so that the linear
    interpolation between points treats each step of the feed-forward symmetrically."""
    tc = table_interval(period, settings)
    h = tc / STEPS_PER_CYCLE
    t0 = (settings.sum_small_time_constants + h / 2) % h
    n = round(period / h)
    return t0 + h * np.arange(n + 1)


def _handover(problem, spm: float) -> tuple[float, tuple[float, float]]:
    """End time of the handover move and the dwell after it (the residual-vibration window)."""
    timing = problem.timing
    sch = timing.schedule(spm)
    move = timing.handover_move
    if move is None:
        move = timing.moves[0]
    k = move.index - 1
    t_end = float(sch.t_start[k] + sch.duration[k])
    nxt = (k + 1) % len(timing.intervals)
    if timing.intervals[nxt].is_move:
        return t_end, (t_end, t_end)
    return t_end, (t_end, t_end + float(sch.duration[nxt]))


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
    r = axis.radius
    tc = table_interval(stroke.period, s)
    d = s.sum_small_time_constants
    shift = phase * tc
    t = t - shift
    tt = t - d  # time as the reference sees it
    k = np.floor(tt / tc + 1e-9).astype(int)
    kc = np.round(t / tc).astype(int)
    k_lo = min(k.min(), kc.min()) - 1
    k_hi = max(k.max(), kc.max()) + 2
    table = stroke.evaluate(np.arange(k_lo, k_hi + 1) * tc + shift).s  # the position table the drive reads

    def pos(i):
        return table[i - k_lo]

    w = (tt - k * tc) / tc
    p0, p1 = pos(k), pos(k + 1)
    theta_ref = ((1 - w) * p0 + w * p1) / r
    omega_ff = (p1 - p0) / (tc * r) if s.velocity_feedforward else 0 * t
    # acceleration: second difference centred on the nearest table point
    eps = (pos(kc + 1) - 2 * pos(kc) + pos(kc - 1)) / (tc * tc * r)
    # the external forces act where the bar is: on the commanded stroke as the loop follows it (delayed)
    f_ext = axis.external_force(stroke.evaluate(t + shift - d).s) if forces else 0 * t
    tau_ff = 0 * t
    if s.acceleration_feedforward:
        tau_ff = tau_ff + axis.total_inertia * eps
    if s.load_feedforward if load_ff is None else load_ff:
        tau_ff = tau_ff - r * axis.external_force(pos(kc))
    return np.vstack([theta_ref, omega_ff, tau_ff, f_ext])


def simulate_loop(loop: ServoLoop, stroke, t: np.ndarray | None = None, *, forces: bool = True):
    """Periodic steady state of the closed loop following ``stroke``: ``(t, outputs, inputs)``.

    ``outputs`` rows: theta, stretch, x, tau_cmd; ``inputs`` see :func:`reference_signals`.
    """
    t = _grid(stroke.period, loop.settings) if t is None else t
    u = reference_signals(loop, stroke, t, forces=forces)
    return t, _periodic_response(loop.system, t, u)[0], u


def _periodic_response(sys, t: np.ndarray, *inputs: np.ndarray) -> list[np.ndarray]:
    """Outputs of the periodic steady state for each periodic input over one period ``t``.

    The state at the cycle start solves ``x0 = Phi x0 + x_forced(T)`` with the
    state transition ``Phi = exp(A T)`` (the closed loop is stable, so
    ``I - Phi`` is invertible). Several inputs are simulated at once, as
    copies of the system side by side.
    """
    import control
    import scipy.linalg

    n = len(inputs)
    big = control.append(*([sys] * n)) if n > 1 else sys
    u = np.vstack(inputs)
    free = control.forced_response(big, t, u, initial_state=np.zeros(big.nstates), return_states=True)
    phi = scipy.linalg.expm(sys.A * (t[-1] - t[0]))
    ns = sys.nstates
    x0 = np.concatenate([np.linalg.solve(np.eye(ns) - phi, free.states[i * ns:(i + 1) * ns, -1]) for i in range(n)])
    out = np.asarray(control.forced_response(big, t, u, initial_state=x0).outputs)
    no = sys.noutputs
    return [out[i * no:(i + 1) * no] for i in range(n)]


def handover_accuracy(problem, stroke=None, spm: float | None = None, *, settings: ServoSettings | None = None,
                      axis: DriveAxis | None = None, gains: Gains | None = None, label: str = "") -> AccuracyResult:
    """Predict how far the bar is from its commanded position over one cycle and at the handover.

    ``stroke`` defaults to the problem's classic-law stroke at ``spm`` (default
    the problem's). Raises :class:`ProblemError` when the sampling is as long
    as a move, :class:`SolverError` when the loop is unstable.
    """
    spm = problem.spm if spm is None else float(spm)
    settings = settings or getattr(problem, "servo", None) or ServoSettings(file=str(problem.file))
    check_sampling(settings.position_sampling, settings.control_cycle, problem.timing, spm,
                   (str(problem.file), "servo.position_sampling_us", "servo.control_cycle_us"))
    axis = axis or axis_from_problem(problem, settings)
    loop = build_loop(axis, settings, gains)
    stroke = stroke if stroke is not None else problem.stroke(spm)
    t = _grid(stroke.period, settings)
    inputs = []
    for phase in TABLE_PHASES:
        u = reference_signals(loop, stroke, t, phase=phase)
        # superposition: the external forces alone (and their share of the feed-forward) give their part
        inputs += [u, u - reference_signals(loop, stroke, t, forces=False, load_ff=False, phase=phase)]
    outputs = _periodic_response(loop.system, t, *inputs)
    delay = settings.sum_small_time_constants
    s_cmd = stroke.evaluate(t - delay).s
    t_h, window = _handover(problem, spm)
    t_h, window = t_h + delay, (window[0] + delay, window[1] + delay)
    quant = 2 * math.pi * axis.radius / settings.encoder_counts
    results = []
    for i in range(len(TABLE_PHASES)):
        theta, stretch, x, tau_cmd = outputs[2 * i]
        results.append(AccuracyResult(spm, stroke.period, t, s_cmd, x, s_cmd - axis.radius * theta, stretch,
                                      outputs[2 * i + 1][1], tau_cmd, t_h, int(np.searchsorted(t, t_h)), quant,
                                      axis.torque_limit, loop, label or stroke.label, window,
                                      -outputs[2 * i + 1][2]))
    return max(results, key=lambda r: r.handover_error)



def residual_vibration_table(problem, spm: float | None = None, strokes=(), *,
                             settings: ServoSettings | None = None, axis: DriveAxis | None = None,
                             gains: Gains | None = None, progress=None) -> list[dict]:
    """Handover error and residual belt vibration of every classic law on the problem's drive
    (and of any extra ``strokes``: ``(label, StrokeFunction)`` pairs, e.g. an optimal design)."""
    from ..motion.laws import LAW_NAMES, make_law

    spm = problem.spm if spm is None else float(spm)
    settings = settings or getattr(problem, "servo", None) or ServoSettings(file=str(problem.file))
    axis = axis or axis_from_problem(problem, settings)
    gains = gains or _tuned(axis, settings)
    cases = []
    for name in LAW_NAMES:
        law = problem.default_law if name == problem.default_law.name else make_law(name)
        cases.append((law.label, lambda law=law: problem.with_law(law).stroke(spm)))
    cases += [(label, lambda st=st: st) for label, st in strokes]
    rows = []
    for label, make in (progress(cases) if progress else cases):
        res = handover_accuracy(problem, make(), spm, settings=settings, axis=axis, gains=gains, label=label)
        rows.append({"law": label, "handover_error_mm": res.handover_error * 1e3,
                     "residual_vibration_mm": res.residual_vibration * 1e3,
                     "max_error_mm": float(np.max(np.abs(res.error))) * 1e3,
                     "max_belt_stretch_mm": float(np.max(np.abs(res.belt))) * 1e3,
                     "peak_torque_command_N_m": res.peak_torque_command, "torque_limited": res.torque_limited})
    return rows


# --------------------------------------------------------------------------- figures


def plot_accuracy(result: AccuracyResult, path: str | Path | None = None):
    """Commanded vs. actual bar position, and the error and its parts over the cam angle."""
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(2, 1, sharex=True, figsize=(9, 7), constrained_layout=True)
    ang = result.angle_deg
    ax = axes[0]
    ax.plot(ang, result.s_cmd * 1e3, lw=1.4, label="commanded")
    ax.plot(ang, result.x * 1e3, lw=1.0, ls="--", label="actual (bar)")
    ax.set_ylabel("bar position [mm]")
    ax.legend(loc="best", fontsize=8)
    ax = axes[1]
    ax.plot(ang, result.error * 1e3, lw=1.4, color="k", label="bar error (commanded - actual)")
    ax.plot(ang, result.servo * 1e3, lw=1.0, label="servo tracking")
    ax.plot(ang, result.belt * 1e3, lw=1.0, label="belt stretch")
    ax.set_ylabel("error [mm]")
    ax.legend(loc="best", fontsize=8)
    h_ang = 360.0 * (result.handover_time - result.loop.settings.sum_small_time_constants) / result.period
    for a in axes:
        a.axvline(h_ang, color="tab:red", ls="--", lw=1)
        a.axvspan(h_ang, h_ang + result.loop.settings.handover_window, color="tab:red", alpha=0.08, lw=0)
        a.grid(True, alpha=0.3)
    axes[1].annotate(f"handover: {result.handover_error * 1e3:.3f} mm", (h_ang, result.at_handover(result.error) * 1e3),
                     xytext=(10, 10), textcoords="offset points", color="tab:red")
    axes[1].set_xlabel("cam angle [deg]")
    axes[1].set_xlim(0, 360)
    axes[1].set_xticks(np.arange(0, 361, 30))
    axes[0].set_title(f"{result.label} at {result.spm:g} spm: handover error {result.handover_error * 1e3:.3f} mm")
    if path is not None:
        fig.savefig(path, dpi=120)
        plt.close(fig)
    return fig


# --------------------------------------------------------------------------- reports


#: What the torque of ``accuracy`` and ``tradeoff`` is, and why it differs from ``size``'s (one line of their
#: text and the ``torque_basis`` of their JSON).
TORQUE_BASIS = ("torque = the servo's torque command (rigid load + loop dynamics + feed-forward), not the rigid-load "
                "peak of the commanded stroke that 'strokeopt size' checks, so the two differ near the limit")


def accuracy_report(problem, spm: float | None = None, *, stroke=None, label: str = "", compare_laws: bool = False,
                    extra_strokes=(), progress=None) -> tuple[dict, AccuracyResult]:
    """The report of ``strokeopt accuracy``: the prediction for ``stroke`` (default: the problem's
    own law; ``label`` names it) and, with ``compare_laws``, the handover error and residual
    vibration of every classic law (plus ``extra_strokes``: ``(label, StrokeFunction)`` pairs).
    ``progress`` wraps an iterable (tqdm)."""
    spm = problem.spm if spm is None else float(spm)
    settings = problem.servo or ServoSettings(file=str(problem.file))
    axis = axis_from_problem(problem, settings)
    gains = _tuned(axis, settings)
    result = handover_accuracy(problem, stroke, spm=spm, settings=settings, axis=axis, gains=gains, label=label)
    design = getattr(problem, "design", None)
    requirement = design.accuracy if design is not None else 0.5e-3  # digest A.1: within 0.5 mm
    report = {"problem": problem.name, **result.summary(), "requirement_mm": requirement * 1e3,
              "torque_basis": TORQUE_BASIS,
              "margins": loop_margins(axis, settings, gains)}
    if compare_laws:
        report["laws"] = residual_vibration_table(problem, spm, extra_strokes, settings=settings, axis=axis,
                                                  gains=gains, progress=progress)
    return report, result


def accuracy_text(report: dict) -> str:
    from ..report.format import format_table

    g = report["gains"]
    c = report["contributions_mm"]
    sc = report["signed_contributions_mm"]
    lines = []
    used = report.get("drive_from_design")
    if used:
        lines += [
            f"drive of the design {used['design']}: motor {used.get('motor', report['motor'])}, pulley "
            f"{used.get('pulley_teeth', '-')} teeth (from the design file, not the problem file)",
            # The design solve checks the bar error at the end of the handover move only, for a continuous
            # reference (the error as a linear functional of the stroke's acceleration). This report simulates
            # the full loop: the position table sampled (worst of several table phases), the largest error
            # over the whole handover window after the move, plus one encoder count. It is therefore the
            # larger of the two, by the window's belt ringing and the sampling.
            "  note: the design solve checks the error at the end of the handover move with a continuous "
            "reference; below is the full loop (sampled table, largest error over the handover window, plus one "
            "encoder count), so it can be larger",
        ]
    lines += [
        f"{report['problem']} at {report['spm']:g} spm, {report['label']}: motor {report['motor']}, "
        f"pulley PD {report['pulley_pitch_diameter_mm']:.2f} mm, moving mass {report['moving_mass_kg']:g} kg",
        f"belt {report['belt_stiffness_N_per_mm']:.0f} N/mm at the carrier ({report['belt_stiffness_source']}), "
        f"belt mode {report['belt_resonance_Hz']:.0f} Hz",
        f"servo loop: Kp {g['position_gain_1_s']:.1f} 1/s, Kv {g['speed_gain_N_m_s_rad']:.4g} N m s/rad, "
        f"Ti {g['speed_integral_time_ms']:.2f} ms, speed bandwidth {g['speed_bandwidth_Hz']:.1f} Hz; "
        f"loop delay {report['loop_delay_us']:.0f} us; feed-forward velocity "
        f"{'on' if report['velocity_feedforward'] else 'off'}, acceleration "
        f"{'on' if report['acceleration_feedforward'] else 'off'}",
        f"  tuning: {g['tuning']}",
        f"  margins: gain {report['margins']['gain_margin']:.2f}, phase {report['margins']['phase_margin_deg']:.1f} deg, "
        f"modulus {report['margins']['modulus_margin']:.2f}",
        "",
        f"handover error (largest over {report['handover_window_deg']:g} deg after the end of the handover move at "
        f"{report['handover_angle_deg']:.1f} deg): {report['handover_error_mm']:.4f} mm "
        f"(requirement {report['requirement_mm']:g} mm)",
        f"  servo tracking        {sc['servo_tracking']:+.4f} mm  (pulley {report['pulley_error_at_handover_deg']:.3f} deg)",
        f"  belt stretch          {sc['belt_stretch']:+.4f} mm  (inertia {sc['belt_stretch_inertia']:+.4f}, "
        f"forces {sc['belt_stretch_forces']:+.4f})",
        f"  encoder quantisation  {c['encoder_quantisation']:.4f} mm  (one count, added as a bound)",
        f"over the cycle: max error {report['max_error_mm']:.4f} mm, max servo error "
        f"{report['max_servo_error_mm']:.4f} mm, max belt stretch {report['max_belt_stretch_mm']:.4f} mm; "
        f"residual belt vibration in the dwell after the handover {report['residual_vibration_mm']:.4f} mm",
        f"peak torque command {report['peak_torque_command_N_m']:.3f} N m (limit {report['torque_limit_N_m']:.2f} N m)",
        f"  {report['torque_basis']}",
    ]
    if report["torque_limited"]:
        lines.append("WARNING: the torque command exceeds the limit: the drive saturates and the linear prediction "
                     "above does not hold")
    if "laws" in report:
        lines += ["", format_table(report["laws"], [
            ("law", "law"), ("handover_error_mm", "handover mm"), ("residual_vibration_mm", "residual belt vib. mm"),
            ("max_error_mm", "max error mm"), ("max_belt_stretch_mm", "max belt mm"),
            ("peak_torque_command_N_m", "peak torque N m"), ("torque_limited", "saturates")],
            title=f"Motion laws at {report['spm']:g} spm on the same drive")]
    return "\n".join(lines)


_TUNED: dict = {}

def _tuned(axis: DriveAxis, settings: ServoSettings) -> Gains:
    key = (axis, settings)
    if key not in _TUNED:
        _TUNED[key] = tune(axis, settings)
    return _TUNED[key]
