"""How far the bar is from its commanded position: the handover accuracy prediction.

Last step of the servo flow: :func:`handover_accuracy` builds the loop
(:mod:`.loop`) of the problem's axis (:mod:`.plant`), drives it with the
stroke's position table and returns an :class:`AccuracyResult` (commanded and
actual bar motion over one periodic cycle, the error and its causes);
:func:`accuracy_report` is the data of ``strokeopt accuracy`` (its text and
figure are drawn by :mod:`strokeopt.report.servo`).

* **Torque limit**: the model is linear: where the torque command exceeds
  the axis's limit the prediction does not hold, and the result says so
  (``torque_limited``) instead of reporting a number that is not true.
* **Encoder quantisation**: the position loop cannot resolve less than one
  encoder count; one count at the bar (``2 pi r / counts``) is added to the
  handover error as a bound.
* **Table phase**: where the table points fall relative to the stroke is
  chance: the result is the worst of :data:`TABLE_PHASES`.

The bar's error ``x_cmd - x`` splits exactly into the servo tracking error
``r (theta_cmd - theta)`` (what the drive itself reports as following
error) and the belt stretch ``r theta - x``; the belt stretch is split
further by superposition into its parts due to the bar's inertia and due
to the external forces.

The handover error is the largest bar error over ``handover_window_deg``
after the end of the handover move, plus one encoder count.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..drive.checks import torque_limit_text, within_limit
from ..io.load_units import error_unit
from .loop import (Gains, ServoLoop, build_loop, cycle_grid, loop_margins, periodic_response, reference_signals,
                   tuned_gains)
from .plant import DriveAxis, axis_from_problem
from .settings import ARCMIN, ServoSettings, check_sampling, settings_of

#: Keys of ``contributions_mm`` in an accuracy report.
CONTRIBUTIONS = ("servo_tracking", "belt_stretch", "encoder_quantisation")


@dataclass
class AccuracyResult:
    """Commanded vs. actual bar motion over one periodic cycle and the handover error.

    Arrays over ``t`` (one cycle, seconds): ``s_cmd``, ``x`` [m], errors [m]
    ``servo``, ``belt``, ``belt_inertia``, ``belt_load``; ``error = servo + belt``
    (= s_cmd - x), ``tau_cmd`` [N m]. Its figure: :func:`strokeopt.report.servo.plot_accuracy`.
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
        """``arr`` at the end of the handover move; the response is periodic, so a handover at the cycle's end
        (plus the loop delay: past the grid's last point) is read at the cycle's start."""
        return float(np.interp(self.handover_time, self.t, arr, period=self.period))

    def _window(self) -> np.ndarray:
        """Samples from the end of the handover move over ``handover_window_deg`` of cam angle, continued at the
        cycle's start where the window passes its end (a move that ends at 360 deg)."""
        since = (self.t - self.handover_time) % self.period
        return since <= self.loop.settings.handover_window / 360.0 * self.period

    def at_handover_worst(self, arr) -> float:
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
        servo, belt, belt_load = (self.at_handover_worst(a) for a in (self.servo, self.belt, self.belt_load))
        return {"servo_tracking": servo, "belt_stretch": belt, "encoder_quantisation": self.quantisation,
                "belt_stretch_inertia": belt - belt_load, "belt_stretch_forces": belt_load}

    def summary(self) -> dict:
        """The numbers of the report in the load's units: a bar's in mm (``handover_error_mm``, the belt's
        ``max_belt_stretch_mm``), a rotary load's in deg (``handover_error_deg``, ``max_stretch_deg``: the
        gearbox's wind-up); ``position_unit`` says which, ``compliance`` names the elastic element."""
        axis = self.loop.axis
        scale, u = error_unit(axis.rotary)
        c = self.contributions()
        out = {
            "spm": self.spm,
            "label": self.label,
            "position_unit": u,
            "compliance": axis.compliance,
            f"handover_error_{u}": self.handover_error * scale,
            f"contributions_{u}": {k: abs(c[k]) * scale for k in CONTRIBUTIONS},
            f"signed_contributions_{u}": {k: v * scale for k, v in c.items()},
            "handover_window_deg": self.loop.settings.handover_window,
            "handover_angle_deg": 360.0 * (self.handover_time - self.loop.settings.sum_small_time_constants) / self.period,
            "pulley_error_at_handover_deg": math.degrees(abs(c["servo_tracking"]) / axis.radius),
            f"max_error_{u}": float(np.max(np.abs(self.error))) * scale,
            f"max_servo_error_{u}": float(np.max(np.abs(self.servo))) * scale,
            f"residual_vibration_{u}": self.residual_vibration * scale,
            "dwell_after_handover": self.residual_window[1] > self.residual_window[0],  # else no residual to judge
            "peak_torque_command_N_m": self.peak_torque_command,
            "torque_limit_N_m": self.torque_limit,
            "torque_limited": self.torque_limited,
            "motor": axis.motor,
            "loop_delay_us": self.loop.settings.sum_small_time_constants * 1e6,
            "velocity_feedforward": self.loop.settings.velocity_feedforward,
            "acceleration_feedforward": self.loop.settings.acceleration_feedforward,
            "gains": self.loop.gains.as_dict(),
        }
        if axis.compliance == "rigid":  # a crank, a linkage: its varying ratio and inertia (servo/varying.py)
            out.update(axis.facts(scale, u))
        elif axis.rotary:  # a gearbox to a turning load: its ratio, wind-up and torsional stiffness
            out.update({"max_stretch_deg": float(np.max(np.abs(self.belt))) * scale, "ratio": 1 / axis.radius,
                        "load_inertia_kg_m2": axis.mass, "torsional_stiffness_N_m_arcmin": axis.belt_stiffness * ARCMIN,
                        "stiffness_source": axis.belt_note, "resonance_Hz": axis.resonance_hz,
                        "encoder_count_at_load_arcsec": math.degrees(self.quantisation) * 3600})
        else:
            out.update({"max_belt_stretch_mm": float(np.max(np.abs(self.belt))) * scale,
                        "pulley_pitch_diameter_mm": 2 * axis.radius * 1e3, "moving_mass_kg": axis.mass,
                        "belt_stiffness_N_per_mm": axis.belt_stiffness * 1e-3, "belt_stiffness_source": axis.belt_note,
                        "belt_resonance_Hz": axis.resonance_hz, "encoder_count_at_bar_um": self.quantisation * 1e6})
        return out

#: Table phases tried (fractions of the table interval); the result is the worst of them.
TABLE_PHASES = (0.0, 0.25, 0.5, 0.75)


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


def handover_accuracy(problem, stroke=None, spm: float | None = None, *, settings: ServoSettings | None = None,
                      axis: DriveAxis | None = None, gains: Gains | None = None, label: str = "") -> AccuracyResult:
    """Predict how far the bar is from its commanded position over one cycle and at the handover.

    ``stroke`` defaults to the problem's classic-law stroke at ``spm`` (default
    the problem's). Raises :class:`ProblemError` when the sampling is as long
    as a move, :class:`SolverError` when the loop is unstable.
    """
    spm = problem.spm if spm is None else float(spm)
    settings = settings_of(problem, settings)
    check_sampling(settings.position_sampling, settings.control_cycle, problem.timing, spm,
                   (str(problem.file), "servo.position_sampling_us", "servo.control_cycle_us"))
    axis = axis or axis_from_problem(problem, settings)
    stroke = stroke if stroke is not None else problem.stroke(spm)
    if axis.compliance == "rigid":   # a transmission of varying ratio: its own nonlinear dynamics
        return _varying_accuracy(problem, stroke, spm, settings, axis, gains or tuned_gains(axis, settings), label)
    loop = build_loop(axis, settings, gains)
    t = cycle_grid(stroke.period, settings)
    inputs = []
    for phase in TABLE_PHASES:
        u = reference_signals(loop, stroke, t, phase=phase)
        # superposition: the external forces alone (and their share of the feed-forward) give their part
        inputs += [u, u - reference_signals(loop, stroke, t, forces=False, load_ff=False, phase=phase)]
    outputs = periodic_response(loop.system, t, *inputs)
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


@dataclass(frozen=True)
class RigidLoop:
    """The loop of a rigid axis of varying ratio (servo/varying.py): what an :class:`AccuracyResult` reads of it."""

    axis: object
    settings: ServoSettings
    gains: Gains


def _varying_accuracy(problem, stroke, spm: float, settings, axis, gains, label: str) -> AccuracyResult:
    """:func:`handover_accuracy` through a transmission of varying ratio (servo/varying.py): the worst of the table
    phases, the whole error servo tracking."""
    from .varying import simulate_varying

    loop = RigidLoop(axis, settings, gains)
    t = cycle_grid(stroke.period, settings)
    delay = settings.sum_small_time_constants
    s_cmd = stroke.evaluate(t - delay).s
    t_h, window = _handover(problem, spm)
    t_h, window = t_h + delay, (window[0] + delay, window[1] + delay)
    quant = 2 * math.pi * axis.handover_ratio / settings.encoder_counts
    zero = np.zeros_like(t)
    results = []
    for phase in TABLE_PHASES:
        phi, tau_cmd = simulate_varying(axis, settings, gains, t, reference_signals(loop, stroke, t, phase=phase)[:3])
        x = np.ravel(axis.transmission.transfer(phi)[0])
        results.append(AccuracyResult(spm, stroke.period, t, s_cmd, x, s_cmd - x, zero, zero, tau_cmd, t_h,
                                      int(np.searchsorted(t, t_h)), quant, axis.torque_limit, loop,
                                      label or stroke.label, window, zero))
    return max(results, key=lambda r: r.handover_error)


def stroke_accuracy(problem, stroke, spm: float, *, motor=None, pulley_teeth: int | None = None,
                    radius: float | None = None, label: str = "", resolved=None) -> AccuracyResult:
    """The full servo simulation of ``stroke`` at ``spm`` on a motor and pulley (default: the
    problem's; a :class:`~strokeopt.drive.catalogue.ServoMotor`, a tooth count, or a continuous
    ``radius``): the handover error ``strokeopt accuracy --design`` prints, and the number the
    command line's solve reports in its check table (the design package does not import servo)."""
    settings = settings_of(problem)
    axis = axis_from_problem(problem, settings, motor=motor, pulley_teeth=pulley_teeth, radius=radius,
                             resolved=resolved)
    return handover_accuracy(problem, stroke, spm=spm, settings=settings, axis=axis,
                             gains=tuned_gains(axis, settings), label=label)


def design_accuracy(design) -> AccuracyResult:
    """The full servo simulation of a design (:class:`~strokeopt.design.result.Design`): its stroke at its
    rate on its own problem (with the values of free model parameters it found), motor and pulley (or
    continuous radius) -- the number the solve's check table, the design report and ``strokeopt accuracy
    --design`` print."""
    return stroke_accuracy(design.problem, design.stroke, design.spm, resolved=design.drive)


def residual_vibration_table(problem, spm: float | None = None, strokes=(), *,
                             settings: ServoSettings | None = None, axis: DriveAxis | None = None,
                             gains: Gains | None = None, progress=None) -> list[dict]:
    """Handover error and residual belt vibration of every classic law on the problem's drive
    (and of any extra ``strokes``: ``(label, StrokeFunction)`` pairs, e.g. an optimal design)."""
    from ..motion.laws import compared_laws

    spm = problem.spm if spm is None else float(spm)
    settings = settings_of(problem, settings)
    axis = axis or axis_from_problem(problem, settings)
    gains = gains or tuned_gains(axis, settings)
    scale, u = error_unit(axis.rotary)
    cases = []
    for law in compared_laws(problem.default_law, [m.law for m in problem.timing.moves]):
        cases.append((law.label, lambda law=law: problem.with_law(law).stroke(spm)))
    cases += [(label, lambda st=st: st) for label, st in strokes]
    rows = []
    for label, make in (progress(cases) if progress else cases):
        res = handover_accuracy(problem, make(), spm, settings=settings, axis=axis, gains=gains, label=label)
        rows.append({"law": label, f"handover_error_{u}": res.handover_error * scale,
                     f"residual_vibration_{u}": res.residual_vibration * scale,
                     f"max_error_{u}": float(np.max(np.abs(res.error))) * scale,
                     ("max_stretch_deg" if axis.rotary else "max_belt_stretch_mm"): float(np.max(np.abs(res.belt))) * scale,
                     "peak_torque_command_N_m": res.peak_torque_command, "torque_limited": res.torque_limited})
    return rows


# --------------------------------------------------------------------------- the report of strokeopt accuracy


#: What the torque of ``accuracy`` and ``tradeoff`` is, and why it differs from ``size``'s (one line of their
#: text and the ``torque_basis`` of their JSON).
TORQUE_BASIS = ("torque = the servo's torque command (rigid load + loop dynamics + feed-forward), not the rigid-load "
                "peak of the commanded stroke that 'strokeopt size' checks, so the two differ near the limit")


def accuracy_report(problem, spm: float | None = None, *, stroke=None, label: str = "", compare_laws: bool = False,
                    extra_strokes=(), progress=None, tolerance: float = 0.0) -> tuple[dict, AccuracyResult]:
    """The report of ``strokeopt accuracy``: the prediction for ``stroke`` (default: the problem's
    own law; ``label`` names it) and, with ``compare_laws``, the handover error and residual
    vibration of every classic law (plus ``extra_strokes``: ``(label, StrokeFunction)`` pairs).
    ``progress`` wraps an iterable (tqdm). The error is judged by the one pass rule
    (:func:`~strokeopt.drive.checks.within_limit`) within ``tolerance``: a design's ``check_tolerance`` for a
    design's stroke, 0 for a classic law."""
    spm = problem.spm if spm is None else float(spm)
    settings = settings_of(problem)
    axis = axis_from_problem(problem, settings)
    gains = tuned_gains(axis, settings)
    result = handover_accuracy(problem, stroke, spm=spm, settings=settings, axis=axis, gains=gains, label=label)
    design = getattr(problem, "design", None)
    scale, u = error_unit(axis.rotary)
    # digest A.1: within 0.5 mm (a rotary load's default: design/transcription/settings.py)
    requirement = design.accuracy if design is not None else (math.radians(0.05) if axis.rotary else 0.5e-3)
    motor = problem.drive.catalogue().motor(axis.motor)
    report = {"problem": problem.name, "cycle": problem.cycle.noun, **result.summary(),
              f"requirement_{u}": requirement * scale,
              "torque_limit_basis": torque_limit_text(motor, problem.drive.limits),
              "torque_basis": TORQUE_BASIS,
              "margins": loop_margins(axis, settings, gains)}
    broken = []
    if not within_limit(result.handover_error, requirement, tolerance):
        broken.append(f"handover error {result.handover_error * scale:.4f} {u} > requirement {requirement * scale:g} {u}")
    if result.torque_limited:
        broken.append(f"torque command {result.peak_torque_command:.3f} N m > torque limit {axis.torque_limit:.3f} "
                      "N m (the drive saturates)")
    report["status"] = "limits exceeded" if broken else "ok"
    report["verdict"] = ("limits exceeded: " + "; ".join(broken) if broken else
                         f"ok: handover error {result.handover_error * scale:.4f} {u} within {requirement * scale:g} {u}, "
                         f"torque command within the torque limit {axis.torque_limit:.3f} N m")
    if compare_laws:
        report["laws"] = residual_vibration_table(problem, spm, extra_strokes, settings=settings, axis=axis,
                                                  gains=gains, progress=progress)
    return report, result
