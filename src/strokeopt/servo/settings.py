"""The ``[servo]`` section: the drive's sampling, feed-forwards, tuning choice and belt geometry.

First step of the servo flow: :func:`parse_servo` (called by
:func:`strokeopt.io.problem_file.load_problem`) turns the section into a
:class:`ServoSettings`, SI units; :func:`check_sampling` refuses a sampling
time as long as a move. The plant (:mod:`.plant`), the loop (:mod:`.loop`) and
the accuracy prediction (:mod:`.accuracy`) read these settings.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

from ..errors import ProblemError

TUNING_RULES = ("symmetric_optimum", "manual")


@dataclass(frozen=True)
class ServoSettings:
    """The ``[servo]`` section of a problem file, SI units.

    Gains left at None come from the tuning rule (:func:`strokeopt.servo.loop.tune`).
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
    """Read the ``[servo]`` table (a :class:`~strokeopt.io.fields.Fields`).

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



def settings_of(problem, settings: ServoSettings | None = None) -> ServoSettings:
    """``settings`` if given, else the problem's ``[servo]`` section, else the defaults."""
    return settings or getattr(problem, "servo", None) or ServoSettings(file=str(problem.file))
