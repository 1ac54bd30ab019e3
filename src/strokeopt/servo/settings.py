"""The ``[servo]`` section: the drive's sampling, feed-forwards, tuning choice and belt geometry.

First step of the servo flow: :func:`parse_servo` (called by
:func:`strokeopt.files.problem_file.load_problem`) turns the section into a
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
    #: a drive without a belt (a gearbox): the torsional stiffness of the gearbox or shaft at the load [N m/rad]
    #: and the damping ratio of that mode
    torsional_stiffness: float | None = None
    torsional_damping_ratio: float = 0.05
    pade_order: int = 3
    handover_window: float = 10.0  # deg of cam angle after the end of the handover move
    file: str = ""

    @property
    def sum_small_time_constants(self) -> float:
        """T_sigma: sample-and-hold (T_p/2) + computation (T_p) + current loop."""
        return 1.5 * self.position_sampling + self.current_loop_time_constant


#: The ``[servo]`` keys of a belt's geometry and stiffness, and those of a drive without a belt: a problem states
#: the ones of its own transmission.
BELT_KEYS = ("belt_span_mm", "carrier_from_pulley_mm", "belt_length_mm", "belt_specific_stiffness_N_per_mm",
             "belt_width_mm", "belt_damping_ratio")
TORSION_KEYS = ("torsional_stiffness_N_m_arcmin", "torsional_damping_ratio")
ARCMIN = math.pi / (180 * 60)


def parse_servo(f, timing=None, spm: float | None = None, transmission=None) -> ServoSettings:
    """Read the ``[servo]`` table (a :class:`~strokeopt.io.fields.Fields`).

    With ``timing`` and ``spm`` it also checks that the sampling is shorter
    than the shortest move. With ``transmission`` it refuses the keys of another kind of drive: a belt's
    geometry where there is no belt pulley, a torsional stiffness where there is one.
    """
    if transmission is not None:
        belt = transmission.name == "belt_pulley"
        for key in (TORSION_KEYS if belt else BELT_KEYS):
            if f.has(key):
                raise f.error(key, f"is for a drive {'without a belt' if belt else 'with a belt'}; the transmission is "
                                   f"a {transmission.label}: its elastic mode is "
                                   + ("the belt's (belt_span_mm, belt_damping_ratio)" if belt else
                                      "the torsion of its gearbox or shaft (torsional_stiffness_N_m_arcmin)"))
    s = ServoSettings(file=f.file)
    # servo drives sample and read their tables every 31.25 us to a few ms: 1 us to 100 ms is plausible
    tp = f.number("position_sampling_us", 250.0, min=1.0, max=1e5) * 1e-6
    tc = f.number("control_cycle_us", 500.0, min=1.0, max=1e5) * 1e-6
    ti = f.number("current_loop_time_constant_us", 125.0, min=0.0, max=1e5) * 1e-6
    # from a 1-line resolver to 2^32 counts (a 32-bit absolute encoder)
    counts = f.number("encoder_counts_per_rev", 16384, integer=True, min=4, max=2**32)
    vff = f.boolean("velocity_feedforward", True)
    aff = f.boolean("acceleration_feedforward", True)
    lff = f.boolean("load_feedforward", True)
    tuning = f.string("tuning", "symmetric_optimum", choices=TUNING_RULES)
    # gains within what a sampled loop can hold: bandwidths to 100 kHz, gains to 1e5 1/s and 1e4 N m s/rad,
    # integral times from 1 us to 1000 s
    bw = f.number("speed_bandwidth_Hz", None, positive=True, max=1e5)
    kp = f.number("position_gain_1_s", None, positive=True, max=1e5)
    kv = f.number("speed_gain_N_m_s_rad", None, positive=True, max=1e4)
    tn = f.number("speed_integral_time_ms", None, min=1e-3, max=1e6)
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
    # belt lengths: spans from 1 mm to 20 m (a belt conveyor), widths 1 mm to 1 m
    span = f.number("belt_span_mm", 139.5, min=1.0, max=2e4) * 1e-3
    carrier = f.number("carrier_from_pulley_mm", None, positive=True, max=2e4)
    carrier = None if carrier is None else carrier * 1e-3
    if carrier is not None and not carrier < span:
        raise f.error("carrier_from_pulley_mm", f"{carrier * 1e3:g} mm is not inside the belt span of {span * 1e3:g} mm")
    length = f.number("belt_length_mm", None, positive=True, max=5e4)
    length = None if length is None else length * 1e-3
    if length is not None and not length > 2 * span:
        raise f.error("belt_length_mm", f"{length * 1e3:g} mm cannot wrap two pulleys {span * 1e3:g} mm apart")
    # specific stiffness of belts: ~1e3 (rubber) to ~1e6 N per mm of width (steel cord); a decade each way
    stiff = f.number("belt_specific_stiffness_N_per_mm", None, min=100.0, max=1e7)
    width = f.number("belt_width_mm", 9.0, min=1.0, max=1e3) * 1e-3
    zeta = f.number("belt_damping_ratio", 0.05, positive=True, max=1.0)
    # gearboxes' data sheets give the torsional stiffness at the output in N m/arcmin: a small planetary about 1, a
    # large one several hundred; 0.01 to 1e5 leaves a decade each way
    torsion = f.number("torsional_stiffness_N_m_arcmin", None, min=0.01, max=1e5)
    torsion_zeta = f.number("torsional_damping_ratio", 0.05, positive=True, max=1.0)
    order = f.number("pade_order", 3, integer=True, min=1, max=8)
    window = f.number("handover_window_deg", 10.0, min=0.0, max=90.0)
    f.finish()
    if timing is not None and spm is not None:
        check_sampling(tp, tc, timing, spm, (f.file, f.where("position_sampling_us"), f.where("control_cycle_us")),
                       simulate=False)
    return replace(s, position_sampling=tp, control_cycle=tc, current_loop_time_constant=ti, encoder_counts=counts,
                   velocity_feedforward=vff, acceleration_feedforward=aff, load_feedforward=lff, tuning=tuning,
                   speed_bandwidth=None if bw is None else 2 * math.pi * bw, position_gain=kp, speed_gain=kv,
                   speed_integral_time=None if tn is None else tn * 1e-3, belt_span=span,
                   carrier_from_pulley=carrier, belt_length=length,
                   belt_specific_stiffness=None if stiff is None else stiff * 1e3, belt_width=width,
                   belt_damping_ratio=zeta, pade_order=order, handover_window=window,
                   torsional_stiffness=None if torsion is None else torsion / ARCMIN,
                   torsional_damping_ratio=torsion_zeta)


def shortest_move(timing, spm: float) -> float:
    sch = timing.schedule(spm)
    return float(min(d for itv, d in zip(timing.intervals, sch.duration) if itv.is_move))


#: The most samples of the servo's sampling a cycle may hold for the servo simulation (accuracy, tradeoff):
#: its time grid has 12 to 25 points a sample, ~60 MB at this count (500 spm and 250 us: 960 samples).
MAX_SAMPLES_PER_CYCLE = 20000


def check_sampling(tp: float, tc: float, timing, spm: float, where=("", "servo.position_sampling_us",
                                                                     "servo.control_cycle_us"),
                   simulate: bool = True) -> None:
    """A sampling time as long as a move cannot follow it: a :class:`ProblemError` naming the field. With
    ``simulate`` (the servo simulation is about to run) a cycle of more than :data:`MAX_SAMPLES_PER_CYCLE`
    samples is refused too."""
    move = shortest_move(timing, spm)
    for value, fld in ((tp, where[1]), (tc, where[2])):
        if value >= move:
            raise ProblemError(where[0], fld, f"{value * 1e6:g} us is not shorter than the shortest move "
                                              f"({move * 1e6:.0f} us at {spm:g} spm): the drive could not follow it")
    period = timing.period(spm)
    for value, fld in ((tp, where[1]), (tc, where[2])):
        if simulate and period / value > MAX_SAMPLES_PER_CYCLE:
            raise ProblemError(where[0], fld, f"{value * 1e6:g} us makes {period / value:.0f} samples of a {period:.3g} s "
                                              f"cycle ({spm:g} spm), more than the servo simulation's "
                                              f"{MAX_SAMPLES_PER_CYCLE}: sample at least every "
                                              f"{period / MAX_SAMPLES_PER_CYCLE * 1e6:.0f} us or raise the stitch rate")



def settings_of(problem, settings: ServoSettings | None = None) -> ServoSettings:
    """``settings`` if given, else the problem's ``[servo]`` section, else the defaults."""
    return settings or getattr(problem, "servo", None) or ServoSettings(file=str(problem.file))
