"""Kinematics of a stroke: the summary table and its figure."""

from __future__ import annotations

import math
from pathlib import Path

import casadi as ca
import matplotlib.pyplot as plt
import numpy as np

from ..io.cycle import cycle_of
from ..motion.stroke import StrokeFunction
from .figures import frame_label, shade_dwells
from .format import format_table, period_text


def kinematics_summary(problem, stroke: StrokeFunction, spm: float, step_angle: float | None = None) -> dict:
    """Peaks per interval of the bar and of the pulley, as the kinematics command reports them; a
    transmission without a pulley radius (a screw and lever) reports its members and the motor
    instead (:func:`member_peaks`, with the step rate when ``step_angle`` [rad] of a stepper is given)."""
    if not hasattr(problem.transmission, "radius"):
        return _member_summary(problem, stroke, spm, step_angle)
    r = problem.transmission.radius
    sch = problem.timing.schedule(spm)
    laws = problem.timing.move_laws(spm)
    peaks = stroke.piece_peaks()
    intervals, moves = [], []
    deg = 180.0 / math.pi
    for itv, pk, t0, dur in zip(problem.timing.intervals, peaks, sch.t_start, sch.duration):
        row = {
            "index": itv.index,
            "name": itv.name,
            "kind": "move" if itv.is_move else "dwell",
            "law": laws[itv.index].label if itv.is_move else None,
            "stroke_mm": abs(itv.stroke) * 1e3,
            "direction": ("up" if itv.stroke > 0 else "down") if itv.is_move else None,
            "span_deg": 360.0 * dur / sch.period,  # the cam angle the interval takes at these times
            "span_nominal_deg": itv.span_deg,  # as the timing diagram states it
            "start_angle_deg": 360.0 * t0 / sch.period,
            "end_angle_deg": 360.0 * (t0 + dur) / sch.period,
            "time_s": dur,
            "v_max_m_s": pk.v_max,
            "a_max_m_s2": pk.a_max,
            "jerk_max_m_s3": pk.j_max,
            "pulley_speed_max_deg_s": pk.v_max / r * deg,
            "pulley_speed_max_rpm": pk.v_max / r * 60 / (2 * math.pi),
            "pulley_accel_max_deg_s2": pk.a_max / r * deg,
        }
        intervals.append(row)
        if itv.is_move:
            moves.append({"index": itv.move_index, "interval": itv.index, **{k: v for k, v in row.items() if k != "index"}})
    return {
        "problem": problem.name,
        "spm": spm,
        "cycle": problem.cycle.noun,  # the machine's cycle: "stitch", "pick" (io/cycle.py)
        "cycle_time_s": sch.period,  # the cam cycle: 1 / cam_revolutions_per_stitch stitches
        "stitch_period_s": 60.0 / spm,
        "interval_times": problem.timing.interval_times,
        "law": problem.default_law.name if len({m.law for m in problem.timing.moves}) == 1 else "mixed",
        "law_params": problem.default_law.params,
        "pulley_teeth": problem.pulley_teeth,
        "pulley_pitch_diameter_mm": problem.transmission.pitch_diameter * 1e3,
        "moves": moves,
        "intervals": intervals,
    }


def member_peaks(transmission, stroke: StrokeFunction, step_angle: float | None = None,
                 samples: int = 4001) -> list[list[dict]]:
    """Per piece of ``stroke``, the peaks of |speed|, |acceleration|, |jerk| of the motor and of every
    member of ``transmission`` (:meth:`~strokeopt.drive.transmission.Transmission.stage_kinematics`),
    and the motor's peak step rate [Hz] with ``step_angle`` [rad]. Jerk is unbounded (inf) where the
    stroke's is (:meth:`~strokeopt.motion.stroke.StrokeFunction.piece_peaks`)."""
    units = {"motor": "rad"} | {name: unit for name, _, unit in transmission.stages(ca.SX.sym("phi"))}
    out = []
    for piece, peak in zip(stroke.pieces, stroke.piece_peaks()):
        tau = np.linspace(0.0, piece.duration, samples)
        x, v, a, j = piece.derivatives(tau)
        rows = []
        for name, (_, dq, ddq, dddq) in transmission.stage_kinematics(x, v, a, j).items():
            jerk = math.inf if math.isinf(peak.j_max) else float(np.max(np.abs(dddq)))
            row = {"member": name, "unit": units[name], "v_max": float(np.max(np.abs(dq))),
                   "a_max": float(np.max(np.abs(ddq))), "jerk_max": jerk}
            if name == "motor" and step_angle is not None:
                row["step_rate_max_Hz"] = row["v_max"] / step_angle
            rows.append(row)
        out.append(rows)
    return out


def _member_summary(problem, stroke: StrokeFunction, spm: float, step_angle: float | None) -> dict:
    sch = problem.timing.schedule(spm)
    laws = problem.timing.move_laws(spm)
    intervals, moves = [], []
    for itv, members, t0, dur in zip(problem.timing.intervals, member_peaks(problem.transmission, stroke, step_angle),
                                     sch.t_start, sch.duration):
        row = {"index": itv.index, "name": itv.name, "kind": "move" if itv.is_move else "dwell",
               "law": laws[itv.index].label if itv.is_move else None, "stroke_mm": abs(itv.stroke) * 1e3,
               "direction": ("up" if itv.stroke > 0 else "down") if itv.is_move else None,
               "span_deg": 360.0 * dur / sch.period, "span_nominal_deg": itv.span_deg,
               "start_angle_deg": 360.0 * t0 / sch.period, "end_angle_deg": 360.0 * (t0 + dur) / sch.period,
               "time_s": dur, "members": members}
        intervals.append(row)
        if itv.is_move:
            moves.append({"index": itv.move_index, "interval": itv.index, **{k: v for k, v in row.items() if k != "index"}})
    return {"problem": problem.name, "spm": spm, "cycle": problem.cycle.noun, "cycle_time_s": sch.period,
            "stitch_period_s": 60.0 / spm,
            "interval_times": problem.timing.interval_times,
            "law": problem.default_law.name if len({m.law for m in problem.timing.moves}) == 1 else "mixed",
            "law_params": problem.default_law.params, "transmission": problem.transmission.name,
            "load_unit": problem.timing.unit,  # "m", or "rad" for a rotary load ([timing] in deg)
            "step_angle_deg": None if step_angle is None else math.degrees(step_angle),
            "moves": moves, "intervals": intervals}


MEMBER_COLUMNS = [("interval", "interval"), ("member", "member"), ("v_max", "|speed| max"), ("a_max", "|accel| max"),
                  ("jerk_max", "|jerk| max"), ("unit", "unit (/s, /s2, /s3)"), ("step_rate_max_Hz", "step rate Hz")]


#: Peaks are magnitudes (|v| max ...), the move's sense in problem coordinates beside them (``direction``).
KINEMATICS_COLUMNS = [
    ("index", "#"), ("name", "interval"), ("stroke_mm", "stroke mm"), ("direction", "direction"),
    ("span_deg", "span deg"), ("time_ms", "interval time ms"), ("v_max_m_s", "|v| max m/s"),
    ("a_max_m_s2", "|a| max m/s2"), ("jerk_max_m_s3", "|jerk| max m/s3"), ("pulley_speed_max_deg_s", "pulley |w| deg/s"),
    ("pulley_speed_max_rpm", "pulley |n| rpm"), ("pulley_accel_max_deg_s2", "pulley |eps| deg/s2"),
]


def kinematics_text(summary: dict) -> str:
    if "members" in summary["intervals"][0]:
        return _member_text(summary)
    head = (f"{summary['problem']} at {cycle_of(summary).rate(summary['spm'])} "
            f"({period_text(summary['cycle_time_s'], summary['spm'], summary)}, "
            f"interval times {summary['interval_times']}), pulley {summary['pulley_teeth']} teeth, "
            f"PD {summary['pulley_pitch_diameter_mm']:.2f} mm")
    laws = sorted({m["law"] for m in summary["moves"]})
    head += "\nmotion law: " + ", ".join(laws)
    rows = [{**r, "time_ms": r["time_s"] * 1e3} for r in summary["intervals"]]
    columns = KINEMATICS_COLUMNS
    if len(laws) > 1:  # moves of different laws: each row says its own
        columns = [*KINEMATICS_COLUMNS[:4], ("law", "law"), *KINEMATICS_COLUMNS[4:]]
    return head + "\n\n" + format_table(rows, columns)


def _member_text(summary: dict) -> str:
    head = (f"{summary['problem']} at {cycle_of(summary).rate(summary['spm'])} "
            f"({period_text(summary['cycle_time_s'], summary['spm'], summary)}, "
            f"interval times {summary['interval_times']}), transmission {summary['transmission']}")
    head += "\nmotion law: " + ", ".join(sorted({m["law"] for m in summary["moves"]}))
    from .units import load_columns, with_load_stroke

    rotary = summary.get("load_unit") == "rad"  # a rotary load: strokes in deg (report/units.py)
    rows = [with_load_stroke({**r, "time_ms": r["time_s"] * 1e3}, rotary) for r in summary["intervals"]]
    cols = load_columns([c for c in KINEMATICS_COLUMNS
                         if c[0] in ("index", "name", "stroke_mm", "direction", "span_deg", "time_ms")], rotary)
    members = [{"interval": m["name"], **row} for m in summary["moves"] for row in m["members"]]
    step = summary["step_angle_deg"]
    note = (f"\nmotor and members in their own units (m or rad); step rate at {step:g} deg per step"
            if step is not None else "\nmotor and members in their own units (m or rad)")
    return (head + "\n\n" + format_table(rows, cols) + "\n\n" + format_table(members, MEMBER_COLUMNS
            if step is not None else MEMBER_COLUMNS[:-1]) + note)


def plot_kinematics(problem, strokes, spm: float, path: str | Path | None = None, n: int = 3601):
    """Position, velocity, acceleration and jerk over the cam angle; one line per stroke.

    ``strokes`` is a StrokeFunction or a list of them. Dwells are shaded, the
    handover point is marked. Returns the figure; writes it when ``path`` is given.
    """
    fig, axes = plt.subplots(4, 1, sharex=True, figsize=(9, 9), constrained_layout=True)
    draw_kinematics(list(axes), problem, strokes, spm, n)
    if path is not None:
        from .figures import fit_titles

        fit_titles(fig)  # no title wider than its axes
        fig.savefig(path, dpi=120)
        plt.close(fig)
    return fig


def stroke_names(strokes) -> str:
    """The labels of the strokes of a figure ('modified_sine (chi = 0.095)', 'optimal vs ...')."""
    return " vs ".join(dict.fromkeys(s.label for s in strokes if s.label))


def draw_kinematics(axes, problem, strokes, spm: float, n: int = 3601) -> None:
    """:func:`plot_kinematics` on four given axes (position, velocity, acceleration, jerk; shared x)."""
    if not isinstance(strokes, (list, tuple)):
        strokes = [strokes]
    j_peak = max(float(np.max(np.abs(s.sample(n).j))) for s in strokes)
    jerk_unit = ("km/s$^3$", 1e-3) if j_peak >= 1e4 else ("m/s$^3$", 1.0)
    units = [("position", "mm", 1e3), ("velocity", "m/s", 1.0), ("acceleration", "m/s$^2$", 1.0),
             ("jerk", *jerk_unit)]
    if problem.timing.rotary:  # a rotary load (a sley): deg, rad/s, rad/s^2, rad/s^3 (report/units.py)
        units = [("position", "deg", 180.0 / math.pi), ("velocity", "rad/s", 1.0),
                 ("acceleration", "rad/s$^2$", 1.0), ("jerk", "rad/s$^3$", 1.0)]
    for stroke in strokes:
        k = stroke.sample(n)
        angle = 360.0 * k.t / stroke.period
        for ax, y, (_, _, scale) in zip(axes, (k.s, k.v, k.a, k.j), units):
            ax.plot(angle, y * scale, lw=1.4, label=stroke.label)
    from .machine import machine_of

    output = machine_of(problem).output  # what the stroke moves: the bar, the cam
    for ax, (name, unit, _) in zip(axes, units):
        shade_dwells(ax, problem.timing, spm)
        ax.set_ylabel(frame_label(f"{output} {name}", unit, problem.timing.rotary))
        ax.grid(True, alpha=0.3)
        ax.axhline(0, color="0.5", lw=0.6)
    move = problem.timing.handover_move
    if move is not None:
        sch = problem.timing.schedule(spm)
        a_end = sch.end_angle_deg[move.index - 1]
        for ax in axes:
            ax.axvline(a_end, color="tab:red", ls="--", lw=1)
        _, unit, scale = units[0]   # the position axis: mm, or deg for a rotary load
        axes[0].annotate(f"handover ({move.end_position * scale:g} {unit})", (a_end, move.end_position * scale),
                         xytext=(8, 12), textcoords="offset points", color="tab:red")
    axes[-1].set_xlabel("cam angle [deg] (360 deg = one cam cycle)")
    axes[-1].set_xlim(0, 360)
    axes[-1].set_xticks(np.arange(0, 361, 30))
    has_dwell = any(not i.is_move for i in problem.timing.intervals)
    axes[0].set_title(f"{problem.name}: {stroke_names(strokes)} at {problem.cycle.rate(spm)} "
                      f"({period_text(problem.timing.period(spm), spm, problem)})"
                      + (", dwells shaded" if has_dwell else ""), fontsize=10)
    if len(strokes) > 1:
        from .figures import legend_outside

        # below the cam-angle axis, off the data (each axis carries the strokes' labels)
        legend_outside(axes[-1], where="below", ncol=min(len(strokes), 3))


def plot_laws(laws, path: str | Path | None = None, n: int = 2001):
    """The family of motion laws on a unit rise: position, velocity, acceleration and jerk over the
    normalised time, one line per law (a jerk impulse at a jump is left out, not drawn as a spike)."""
    x = np.linspace(0.0, 1.0, n)
    fig, axes = plt.subplots(4, 1, sharex=True, figsize=(9, 12), constrained_layout=True)
    colours = plt.get_cmap("tab10").colors  # ten hues, then the same hues dashed: no two lines alike
    for i, law in enumerate(laws):
        ders = law.derivatives(x, 3)
        style = {"color": colours[i % len(colours)], "ls": ("-", "--", ":")[i // len(colours) % 3], "lw": 1.1}
        for k, ax in enumerate(axes):
            ax.plot(x, ders[k], label=law.label if k == 0 else None, **style)
    for ax, name in zip(axes, ("y", "y' = v T/h", "y'' = a T^2/h", "y''' = jerk T^3/h")):
        ax.set_ylabel(name)
        ax.grid(alpha=0.3)
    axes[0].set_title("Motion laws, unit rise (strokeopt laws)")
    axes[-1].set_xlabel("x = t/T")
    fig.legend(loc="outside lower center", fontsize=7, ncol=2)
    if path is not None:
        fig.savefig(path, dpi=120)
        plt.close(fig)
    return fig
