"""The design report: one self-contained HTML file of a solved design, in the order of the data flow.

problem and timing diagram -> stroke (bar and motor) with the classic-law comparison -> drive
(torque-speed path over the motor's curves, checks and margins, the binding limit) -> handover
accuracy (servo / belt / encoder) -> contact-model verification per scene -> numerical accuracy ->
the inputs and versions. :func:`gather` collects what a verified design holds (the full servo
simulation and the contact scenes of :func:`strokeopt.studies.verified.solve_verified`); :func:`design_report`
writes the page from it and from ``summary``, the very dict ``strokeopt solve --json`` prints. Nothing here
solves or simulates.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field
from datetime import datetime, timezone
from typing import Any

import numpy as np

from . import html as h
from .figures import PRINT_WIDTH_IN, legend_outside
from .format import format_value, period_text
from .machine import ELASTIC_CHAIN, NEEDLE_BAR, Machine, drive_text, machine_of
from .units import direction_word, is_rotary, load_label
from ..io.load_units import load_key, to_load_units
from .accuracy_section import section_accuracy
from .verification_section import section_verification

#: The report's sections: (id, heading), in the order of the data flow; a report shows those its machine has
#: (:func:`sections_for`), with headings in the machine's words.
SECTIONS = [("problem", "Problem and timing diagram"), ("stroke", "Stroke: output and motor"),
            ("drive", "Drive: torque, speed and checks"), ("accuracy", "Handover accuracy"),
            ("verification", "Contact-model verification"), ("numerics", "Numerical accuracy"),
            ("inputs", "Inputs and versions")]


def sections_for(machine: Machine) -> list[tuple[str, str]]:
    """The sections a report of ``machine`` has, each headed in its words: no handover accuracy without a
    handover, no contact verification without a contact model; an elastic chain's verification is its link
    forces and its accelerations against the rigid chain."""
    heads = dict(SECTIONS)
    heads["stroke"] = f"Stroke: {machine.output} and motor"
    if machine.stepper:
        heads["drive"] = "Drive: torque demand, pull-out curve and checks"
    if machine.scene == ELASTIC_CHAIN:
        heads["verification"] = "Elastic chain: link forces and accelerations against the rigid chain"
    elif machine.scene == NEEDLE_BAR:
        heads["verification"] = "Contact-model verification: impact, lag, gap and release"
    keep = [sid for sid, _ in SECTIONS if not (sid == "accuracy" and not machine.handover)
            and not (sid == "verification" and machine.scene is None)]
    return [(sid, heads[sid]) for sid in keep]


@dataclass
class ReportData:
    """What a design report shows: the design, the ``solve --json`` report of it, and what was simulated."""

    problem: Any
    design: Any
    summary: dict  # the dict `strokeopt solve --json` prints (design_summary + drive + comparison)
    accuracy: Any = None  # AccuracyResult of the full servo simulation, or None without [servo]
    scenes: dict = field(default_factory=dict)  # scene name -> SceneResult
    not_simulated: list = field(default_factory=list)  # scenes of the problem left out (and how to add them)
    versions: dict = field(default_factory=dict)
    created: str = ""
    source: str = ""  # where the design comes from: 'solved now' or the design file
    verification: dict | None = None  # the contact verification block of the design's scene (criteria, verdict)

    @property
    def machine(self) -> Machine:
        return machine_of(self.problem, self.design)


def versions() -> dict:
    """strokeopt, CasADi and IPOPT (the library CasADi loads), Python."""
    import platform
    from pathlib import Path

    import casadi

    from .. import __version__

    libs = sorted(Path(casadi.__file__).parent.glob("libipopt.so.*.*.*")) + \
        sorted(Path(casadi.__file__).parent.glob("libipopt*.dylib"))
    ipopt = next((p.name.split(".so.")[-1] for p in libs if ".so." in p.name), "bundled with CasADi")
    return {"strokeopt": __version__, "CasADi": casadi.__version__, "IPOPT": ipopt, "Python": platform.python_version()}


def gather(verified, summary: dict, source: str = "solved now") -> ReportData:
    """The report's data from a :class:`~strokeopt.studies.verified.VerifiedDesign` (the design, its full
    servo simulation and the scenes it was simulated in) and ``summary`` (the ``solve --json`` dict):
    nothing is computed here."""
    problem = verified.problem
    left = [n for n in (problem.scenes or {}) if n not in verified.scenes]
    summary = to_load_units(summary, is_rotary(problem))  # a rotary load's keys, whatever the summary's source
    return ReportData(problem, verified.design, summary, verified.accuracy, dict(verified.scenes), left, versions(),
                      datetime.now(timezone.utc).strftime("%Y-%m-%d %H:%M UTC"), source,
                      getattr(verified, "verification", None))


# --------------------------------------------------------------------------- figures


def plot_timing(problem, stroke, spm: float):
    """The timing diagram: the output's position over the cam angle (top axis: time), dwells shaded, every
    interval named, the handover (if the machine has one) dashed."""
    import matplotlib.pyplot as plt

    from .figures import frame_label, shade_dwells
    from .machine import machine_of

    output = machine_of(problem).output
    sch = problem.timing.schedule(spm)
    fig, ax = plt.subplots(figsize=(PRINT_WIDTH_IN, 2.9), constrained_layout=True)
    k = stroke.sample(1441)
    scale, unit = _position_scale(problem)
    ax.plot(360 * k.t / stroke.period, k.s * scale, lw=1.4, color="tab:blue")
    shade_dwells(ax, problem.timing, spm)
    for itv, a0, a1 in zip(problem.timing.intervals, sch.start_angle_deg, sch.end_angle_deg):
        ax.axvline(a0, color="0.6", lw=0.6)
        ax.text((a0 + a1) / 2, 0.5, str(itv.index), transform=ax.get_xaxis_transform(), ha="center", va="center",
                fontsize=9, color="0.3", bbox={"boxstyle": "round,pad=0.15", "fc": "white", "ec": "none", "alpha": 0.8})
    move = problem.timing.handover_move
    if move is not None:
        ax.axvline(sch.end_angle_deg[move.index - 1], color="tab:red", ls="--", lw=1, label="handover")
        legend_outside(ax)
    ax.set_xlim(0, 360)
    ax.set_xticks(np.arange(0, 361, 45))
    ax.set_xlabel("cam angle [deg] (numbers: the intervals of the table)")
    ax.set_ylabel(frame_label(f"{output} position", unit, is_rotary(problem)))
    ms = stroke.period * 1e3 / 360.0
    sec = ax.secondary_xaxis("top", functions=(lambda a: a * ms, lambda t: t / ms))
    sec.set_xlabel("time [ms]")
    ax.grid(True, alpha=0.3)
    return fig


def _position_scale(problem) -> tuple[float, str]:
    """The load's positions in the report: mm for a linear load, deg for a rotary one (SI x scale)."""
    return (180 / math.pi, "deg") if is_rotary(problem) else (1e3, "mm")


def motor_scale(problem, design) -> tuple[float | None, str]:
    """The motor's coordinate per unit of the output's [rad/m] and how it was found: the pulley radius, or a
    transmission's ratio at the output's zero (a screw and lever's changes by less than 0.1 % over a
    stitch-cam step). None where the ratio changes by more than :data:`RATIO_SPREAD_MAX` over the stroke's
    positions (a crank near its dead centres): the motor's motion is then no scale of the output's."""
    if design.radius:
        return 1.0 / design.radius, f"output over the pulley radius {design.radius * 1e3:.3f} mm"
    tr, label = problem.transmission, machine_of(problem).transmission
    lo, hi = tr.ratio_range(*problem.timing.position_range)
    if hi > (1 + RATIO_SPREAD_MAX) * lo:
        scale, unit = _position_scale(problem)
        return None, (f"the {label}'s ratio runs from {lo * scale:.4g} to {hi * scale:.4g} "
                      f"{unit}/rad over the stroke: the motor's motion is no scale of the output's, its speed and "
                      "torque are in the drive's figure")
    mu = float(np.ravel(tr.transfer(np.zeros(1))[1])[0])
    if is_rotary(problem):  # a gearbox: the load's angle is the motor's over the ratio
        return 1.0 / mu, f"the load's angle times the {label}'s ratio {1 / mu:g}"
    return 1.0 / mu, f"output over the {label}'s ratio at 0 mm ({mu * 1e3:.4g} mm/rad)"


#: The spread of a transmission's ratio over the stroke below which the report draws the motor's motion as a
#: scale of the output's (a screw and lever over a stitch-cam step: under 0.1 %).
RATIO_SPREAD_MAX = 1e-3


def plot_stroke(problem, design, law_stroke):
    """Position, velocity, acceleration and jerk of the output (left axes) and of the motor (right axes:
    the same curves over the pulley radius or the transmission's ratio), the optimal stroke against the
    problem's law."""
    import matplotlib.pyplot as plt

    from .motion import draw_kinematics

    fig, axes = plt.subplots(4, 1, sharex=True, figsize=(PRINT_WIDTH_IN, 7.8), constrained_layout=True)
    draw_kinematics(list(axes), problem, [design.stroke, law_stroke], design.spm, n=1441)
    per_m, _ = motor_scale(problem, design)
    if per_m is None:  # a varying ratio: no motor axes (the caption says why)
        return fig
    jerk_scale = 1e-3 if "[km" in axes[3].get_ylabel() else 1.0
    position = per_m if is_rotary(problem) else 1e-3 * per_m * 180 / math.pi   # the left axis in deg or mm
    for ax, (label, f) in zip(axes, [("motor angle [deg]", position),
                                     ("motor speed [rpm]", 60 / (2 * math.pi) * per_m),
                                     ("motor acc. [krad/s$^2$]", 1e-3 * per_m),
                                     ("motor jerk [Mrad/s$^3$]", 1e-6 * per_m / jerk_scale)]):
        sec = ax.secondary_yaxis("right", functions=(lambda y, f=f: y * f, lambda y, f=f: y / f))
        sec.set_ylabel(label, fontsize=8)
    return fig


def plot_drive(design):
    """The torque-speed path over the motor's curves (a servo's peak and rated curves, a stepper's pull-out
    curve) and the torque over the cam angle by term, one above the other."""
    import matplotlib.pyplot as plt

    from ..design.torque import design_torque_path
    from .drive import draw_torque_speed, draw_torque_terms

    t, terms = design_torque_path(design, samples=1441)  # its peak: the checks' (the load's switches read)
    fig, (ax1, ax2) = plt.subplots(2, 1, figsize=(PRINT_WIDTH_IN, 7.6), constrained_layout=True,
                                   height_ratios=[1.25, 1])
    stepper = getattr(design.motor_spec, "kind", "servo") == "stepper"
    draw_torque_speed(ax1, design.motor_spec, terms.omega, terms.total, t, design.problem.drive.limits,
                      f"{design.motor}: torque demand over its pull-out curve" if stepper
                      else f"{design.motor}: torque-speed path of the cycle")
    draw_torque_terms(ax2, 360 * t / design.stroke.period, terms, "motor torque over the cycle, by term")
    return fig


# --------------------------------------------------------------------------- sections


def _interval_rows(problem, spm: float) -> list[list[str]]:
    sch = problem.timing.schedule(spm)
    scale, _ = _position_scale(problem)
    rotary = is_rotary(problem)  # a sley turns: its moves are positive or negative, not up or down
    rows = []
    for itv, a0, a1, t0, dur in zip(problem.timing.intervals, sch.start_angle_deg, sch.end_angle_deg,
                                    sch.t_start, sch.duration):
        rows.append([h.cell(itv.index), h.cell(itv.name), h.cell("move" if itv.is_move else "dwell"),
                     h.cell(itv.law.label if itv.is_move else "-"),
                     h.cell(abs(itv.stroke) * scale if itv.is_move else None),
                     h.cell(direction_word("up" if itv.stroke > 0 else "down", rotary) if itv.is_move else "-"),
                     h.cell(a0), h.cell(a1), h.cell(t0 * 1e3), h.cell((t0 + dur) * 1e3),
                     h.cell(itv.start_position * scale), h.cell("handover" if itv.handover else "")])
    return rows


def _check(s: dict, name: str) -> dict | None:
    return next((c for c in s.get("checks") or [] if c["name"] == name), None)


def _transmission_facts(d: ReportData, m: Machine) -> list[tuple]:
    """The transmission's rows of the key facts: a pulley's teeth and pitch diameter, else what the transmission
    states of itself (:meth:`~strokeopt.drive.transmission.Transmission.facts`)."""
    s, tr = d.summary, d.problem.transmission
    if m.pulley:
        return [("transmission", "belt pulley", None), ("pulley teeth", s.get("pulley_teeth"), "pulley_teeth"),
                ("pulley pitch diameter [mm]", s.get("pulley_pitch_diameter_mm"), "pulley_pitch_diameter_mm")]
    return [("transmission", m.transmission, None)] + [(label, value, None) for label, value in tr.facts()]


def section_problem(d: ReportData) -> str:
    p, s, m = d.problem, d.summary, d.machine
    facts = [("problem", p.name, "problem"), ("objective", s["objective"], "objective"),
             (f"objective value [{s['objective_unit']}]", s["objective_value"], "objective_value"),
             ("status", s["status"], "status"), ("verdict", s.get("verdict"), None),
             (f"{p.cycle.rate_name} [{p.cycle.rate_unit}]", s["spm"], "spm"), ("cam cycle [s]", s["cycle_time_s"], "cycle_time_s"),
             ("motor", s["motor"], "motor"),
             ("motor kind", ("stepper (pull-out curve, step rate)" if m.stepper else "servo (peak and rated curves)")
              if m.motor else None, None)]
    facts += _transmission_facts(d, m)
    facts += [("peak torque [N m]", s["peak_torque_N_m"], "peak_torque_N_m")]
    if m.stepper:
        po, rate = _check(s, "pull_out_torque"), _check(s, "step_rate")
        facts += [("peak demand / pull-out torque [%]", po and po["value"], None),
                  ("peak step rate [Hz]", rate and rate["value"], None)]
    else:
        facts += [("RMS torque [N m]", s["rms_torque_N_m"], "rms_torque_N_m")]
    scale, unit = _position_scale(p)
    head = ["#", "interval", "kind", "law", f"stroke {unit}", "direction", "from deg", "to deg", "from ms", "to ms",
            f"start position {unit}", "handover"]
    sch = p.timing.schedule(s["spm"])
    moves = [i for i in p.timing.intervals if i.is_move]
    what = (f"{len(moves)} move{'s' if len(moves) != 1 else ''} of "
            + ", ".join(f"{abs(i.stroke) * scale:g} {unit} "
               f"{direction_word('up' if i.stroke > 0 else 'down', is_rotary(p))}" for i in moves))
    handover = p.timing.handover_move
    hand = (f"; the handover (dashed) ends move {handover.move_index} at {sch.end_angle_deg[handover.index - 1]:.1f} deg"
            if handover is not None else "; the machine has no handover")
    caption = (f"Position of the {m.output} over one cam cycle of {s['cycle_time_s'] * 1e3:.1f} ms: {what}; "
               f"dwells shaded{hand}; top axis: time.")
    return (h.para(f"{p.description} Design {d.source}; {period_text(s['cycle_time_s'], s['spm'], p)}.")
            + h.key_table(facts) + h.heading("Timing diagram (cam degrees and time)")
            + h.table(head, _interval_rows(p, s["spm"]))
            + h.svg_figure(plot_timing(p, d.design.stroke, s["spm"]), caption))


#: The comparison's columns: (key, header); those no row has a value for are left out.
COMPARISON_COLUMNS = [("a_max_m_s2", "a_max m/s2"), ("jerk_max_m_s3", "jerk_max m/s3"),
                      ("peak_torque_N_m", "peak torque N m"), ("rms_torque_N_m", "RMS torque N m"),
                      ("peak_speed_rpm", "peak speed rpm"), ("pull_out_pct", "pull-out %"),
                      ("step_rate_Hz", "step rate Hz")]


def comparison_table(comparison: list[dict], objective: str, prefix: str = "comparison", rotary: bool = False) -> str:
    cols = [(load_key(k, rotary), load_label(head, rotary)) for k, head in COMPARISON_COLUMNS]
    cols = [(k, head) for k, head in cols if any(r.get(k) is not None for r in comparison)]
    if any(r.get("vs_optimal_pct") is not None for r in comparison):  # min_time, min_handover_error: none
        cols.append(("vs_optimal_pct", f"{objective} vs optimal %"))
    rows = []
    for i, r in enumerate(comparison):
        rows.append([h.cell(r["law"])] + [h.cell(r.get(k), f"{prefix}[{i}].{k}") for k, _ in cols]
                    + [h.raw_cell(h.verdict(r.get("feasible", True), "yes", "no: " + ", ".join(r.get("violates") or [])))])
    return h.table(["stroke"] + [c for _, c in cols] + ["feasible"], rows)


def section_stroke(d: ReportData) -> str:
    s, m = d.summary, d.machine
    rotary = is_rotary(d.problem)   # a rotary load: deg, rad/s, rad/s2, rad/s3 (io/load_units.py)
    keys = [load_key(k, rotary) for k in ("stroke_mm", "v_max_m_s", "a_max_m_s2", "jerk_max_m_s3")]
    moves = [[h.cell(mv["index"], f"moves[{i}].index"), h.cell(mv[keys[0]], f"moves[{i}].{keys[0]}"),
              h.cell(direction_word(mv["direction"], rotary)), h.cell(mv["duration_s"] * 1e3),
              *(h.cell(mv[k], f"moves[{i}].{k}") for k in keys[1:]), h.cell(mv["C_a"], f"moves[{i}].C_a")]
             for i, mv in enumerate(s["moves"])]
    law = d.problem.stroke(s["spm"])
    scale, how = motor_scale(d.problem, d.design)
    a_opt = max(mv[keys[2]] for mv in s["moves"])
    a_law = float(np.max(np.abs(law.sample(1441).a)))
    acc = "rad/s\u00b2" if rotary else "m/s\u00b2"
    caption = (f"The optimal stroke of the {m.output} against the problem's law ({law.label}) over the whole cam "
               f"cycle: peak |acceleration| {a_opt:.4g} {acc} against the law's {a_law:.4g} {acc}. Left axes: the "
               f"{m.output}; " + (f"right axes: the motor ({how})." if scale is not None else f"no motor axes: {how}."))
    head = ["move", "stroke mm", "direction", "move time ms", "v_max m/s", "a_max m/s2", "jerk_max m/s3", "C_a"]
    out = h.heading("Moves") + h.table([load_label(x, rotary) for x in head], moves)
    out += h.svg_figure(plot_stroke(d.problem, d.design, law), caption)
    if s.get("comparison"):
        out += h.heading(f"Comparison with the classic laws on the same drive ({drive_text(m, s)})") \
            + comparison_table(s["comparison"], s["objective"], rotary=rotary)
        note = "Laws marked 'no' break the design problem's constraints (listed last)"
        out += h.para(note + ("; the laws' handover accuracy is not checked." if m.handover else "."), "note")
    return out


def binding_check(checks: list[dict]) -> dict | None:
    """The check with the least margin (the limit that binds first)."""
    finite = [c for c in checks if c.get("margin") is not None and math.isfinite(c["margin"])]
    return min(finite, key=lambda c: c["margin"]) if finite else None


def checks_table(checks: list[dict], prefix: str = "checks") -> str:
    rows = [[h.cell(c["name"]), h.cell(c["value"], f"{prefix}[{i}].value"), h.cell(c["limit"], f"{prefix}[{i}].limit"),
             h.cell(c["unit"]), h.cell(c["margin"], f"{prefix}[{i}].margin"), h.raw_cell(h.verdict(c["ok"]))]
            for i, c in enumerate(checks)]
    return h.table(["check", "value", "limit", "unit", "margin (1 - value/limit)", "result"], rows)


def _drive_caption(d: ReportData) -> str:
    """The drive figure's caption, from the design's numbers and its motor's kind."""
    s, m = d.summary, d.machine
    limits = d.problem.drive.limits
    if m.stepper:
        po, rate = _check(s, "pull_out_torque"), _check(s, "step_rate")
        spec = d.design.motor_spec
        least = (f"its least reserve at {po['value']:.4g} % of the pull-out torque (allowed {po['limit']:.4g} %)"
                 if po else "")
        return (f"Top: the torque demand |T| over the cycle against {d.design.motor}'s pull-out curve "
                f"({getattr(spec, 'source', None) or 'motor data'}) and the curve divided by the safety factor "
                f"{limits.pull_out_safety_factor:g} (the check), {least}; the peak step rate "
                + (f"{rate['value']:.0f} Hz against {rate['limit']:.0f} Hz. " if rate else ". ")
                + "Bottom: the motor torque over the cam angle, by term.")
    speed = _check(s, "peak_speed")
    return (f"Top: the cycle's torque-speed path with its peak ({s['peak_torque_N_m']:.3f} N m) and RMS "
            f"({s['rms_torque_N_m']:.3f} N m) operating points over {d.design.motor}'s peak and rated (continuous) "
            f"curves, the drive's torque limit and the rated speed"
            + (f" (peak speed {speed['value']:.0f} of {speed['limit']:.0f} rpm)" if speed else "")
            + ". Bottom: the motor torque over the cam angle, by term.")


def section_drive(d: ReportData) -> str:
    s = d.summary
    if d.design.motor_spec is None:
        return h.para("The problem has no [drive] section: no motor, no torque, no drive checks.")
    b = binding_check(s["checks"])
    out = h.heading("Checks (fine grid between the collocation nodes)") + checks_table(s["checks"])
    if b is not None:
        out += h.para(f"Binding limit: {b['name']} ({format_value(b['value'])} {b['unit']} against "
                      f"{format_value(b['limit'])} {b['unit']}, margin {100 * b['margin']:.1f} %).")
    out += h.para("Active constraints at the solution: " + ("; ".join(s["active_constraints"]) or "none") + ".")
    out += h.svg_figure(plot_drive(d.design), _drive_caption(d))
    drive = s.get("drive") or {}
    if drive:
        out += h.para(f"Motor and {'pulley' if d.machine.pulley else 'transmission'} from {drive.get('from')}.", "note")
    return out


def section_numerics(d: ReportData) -> str:
    from ..design.transcription.settings import DesignSettings
    from ..design.transcription.solver import solver_options

    s, design = d.summary, d.design
    settings = design.settings or DesignSettings()
    fg = design.fine_grid or {}
    opts = solver_options(settings, None, False)
    facts = [("mesh intervals per move", s["mesh"]["intervals"], "mesh.intervals"),
             ("collocation degree", s["mesh"]["degree"], "mesh.degree"),
             ("check tolerance between nodes", settings.check_tolerance, None),
             ("mesh refinements allowed", settings.refinements, None),
             ("worst relative violation between nodes", fg.get("worst_relative_violation"), None),
             ("peak torque at the nodes [N m]", fg.get("peak_torque_nodes_N_m"), None),
             ("peak torque on the fine grid [N m]", fg.get("peak_torque_fine_N_m"), None),
             ("IPOPT iterations", s["iterations"], "iterations"), ("solve time [s]", s["solve_time_s"], "solve_time_s")]
    facts += [(f"solver option {k}", v if isinstance(v, (int, float, str)) else str(v), None)
              for k, v in sorted(opts.items()) if "tol" in k or k in ("plugin",)]
    for name, r in d.scenes.items():
        o = r.options
        facts.append((f"contact scene {name}: integrator", f"{o.method}, rtol {o.rtol:g}, atol {o.atol:g}, "
                                                          f"CPU {r.cpu_time_s:.2f} s", None))
    return (h.para(
        "What tightening costs: `strokeopt solve PROBLEM --study mesh` solves the same design on finer meshes and "
        "higher degrees and prints the objective's error against the finest with the time each took; `strokeopt "
        "simulate PROBLEM --study tolerance` does the same for the integrator's tolerances.") + h.key_table(facts))


def _flat(data, prefix: str = "") -> list[tuple[str, Any]]:
    """A nested problem table as ``key.path = value`` rows (the form --set takes; arrays 1-based)."""
    out = []
    if isinstance(data, dict):
        for k, v in data.items():
            out += _flat(v, f"{prefix}.{k}" if prefix else str(k))
    elif isinstance(data, list) and data and all(isinstance(v, dict) for v in data):
        for i, v in enumerate(data, 1):
            out += _flat(v, f"{prefix}[{i}]")
    else:
        out.append((prefix, data))
    return out


def section_inputs(d: ReportData) -> str:
    import json

    p = d.problem
    sets = list(getattr(p, "overrides", ()))
    drive = d.summary.get("drive") or {}
    facts = [("problem file", str(p.file), None), ("--set", "; ".join(sets) or "none", None),
             ("drive of the design", f"{drive_text(d.machine, d.summary)}, from {drive.get('from')}" if drive
              else drive_text(d.machine, d.summary), None),
             ("created", d.created, None)] + [(k, v, None) for k, v in d.versions.items()]
    rows = [[h.cell(k), h.cell(json.dumps(v) if not isinstance(v, str) else f'"{v}"')] for k, v in _flat(p.data)]
    return (h.key_table(facts) + h.heading("The problem as resolved (every value after the --set overrides)")
            + h.table(["key (as --set takes it)", "value"], rows))


def design_report(d: ReportData) -> str:
    """The HTML text of the design report of ``d``."""
    builders = {"problem": section_problem, "stroke": section_stroke, "drive": section_drive,
                "accuracy": section_accuracy, "verification": section_verification, "numerics": section_numerics,
                "inputs": section_inputs}
    s = d.summary
    m = d.machine
    sections = [(sid, head, builders[sid](d)) for sid, head in sections_for(m)]
    title = f"{d.problem.name}: {s['objective']} design at {d.problem.cycle.rate(s['spm'])}"
    sub = (f"{drive_text(m, s)}; status {s['status']}; "
           f"strokeopt {d.versions.get('strokeopt', '')}, {d.created}")
    return h.page(title, sub, sections)


def write_report(d: ReportData, path) -> dict:
    """Write the report of ``d`` to ``path``; returns its size and the time it took (a JSON-ready dict)."""
    from pathlib import Path

    t0 = time.perf_counter()
    text = design_report(d)
    Path(path).write_text(text, encoding="utf-8")
    return {"report": str(path), "size_bytes": len(text.encode("utf-8")), "build_time_s": time.perf_counter() - t0}
