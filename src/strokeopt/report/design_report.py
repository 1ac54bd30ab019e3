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
from .format import format_value, period_text

#: The report's sections: (id, heading), in the order of the data flow.
SECTIONS = [("problem", "Problem and timing diagram"), ("stroke", "Stroke: bar and motor"),
            ("drive", "Drive: torque, speed and checks"), ("accuracy", "Handover accuracy"),
            ("verification", "Contact-model verification"), ("numerics", "Numerical accuracy"),
            ("inputs", "Inputs and versions")]


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
    return ReportData(problem, verified.design, summary, verified.accuracy, dict(verified.scenes), left, versions(),
                      datetime.now(timezone.utc).strftime("%Y-%m-%d %H:%M UTC"), source)


# --------------------------------------------------------------------------- figures


def plot_timing(problem, stroke, spm: float):
    """The timing diagram: the bar position over the cam angle (top axis: time), dwells shaded, every
    interval named."""
    import matplotlib.pyplot as plt

    from .figures import frame_label, shade_dwells

    sch = problem.timing.schedule(spm)
    fig, ax = plt.subplots(figsize=(9, 3.0), constrained_layout=True)
    k = stroke.sample(1441)
    ax.plot(360 * k.t / stroke.period, k.s * 1e3, lw=1.4, color="tab:blue")
    shade_dwells(ax, problem.timing, spm)
    for itv, a0, a1 in zip(problem.timing.intervals, sch.start_angle_deg, sch.end_angle_deg):
        ax.axvline(a0, color="0.6", lw=0.6)
        ax.text((a0 + a1) / 2, 0.5, str(itv.index), transform=ax.get_xaxis_transform(), ha="center", va="center",
                fontsize=9, color="0.3")
    move = problem.timing.handover_move
    if move is not None:
        ax.axvline(sch.end_angle_deg[move.index - 1], color="tab:red", ls="--", lw=1, label="handover")
        ax.legend(fontsize=8, loc="lower right")
    ax.set_xlim(0, 360)
    ax.set_xticks(np.arange(0, 361, 30))
    ax.set_xlabel("cam angle [deg] (numbers: the intervals of the table)")
    ax.set_ylabel(frame_label("bar position", "mm"))
    ms = stroke.period * 1e3 / 360.0
    sec = ax.secondary_xaxis("top", functions=(lambda a: a * ms, lambda t: t / ms))
    sec.set_xlabel("time [ms]")
    ax.grid(True, alpha=0.3)
    return fig


def plot_stroke(problem, design, law_stroke):
    """Position, velocity, acceleration and jerk of the bar (left axes) and of the motor (right axes:
    the same curves over the pulley radius), the optimal stroke against the problem's law."""
    import matplotlib.pyplot as plt

    from .motion import draw_kinematics

    fig, axes = plt.subplots(4, 1, sharex=True, figsize=(9, 8.5), constrained_layout=True)
    draw_kinematics(list(axes), problem, [design.stroke, law_stroke], design.spm, n=1441)
    # the motor over the bar: the pulley radius, or a transmission's ratio mu at 0 mm (a screw and lever's
    # changes by less than 0.1 % over a stitch-cam step: the axis is that ratio's)
    r = design.radius if design.radius else float(np.ravel(problem.transmission.transfer(np.zeros(1))[1])[0])
    jerk_scale = 1e-3 if axes[3].get_ylabel().startswith("bar jerk [km") else 1.0
    for ax, (label, f) in zip(axes, [("motor angle [deg]", 1e-3 / r * 180 / math.pi),
                                     ("motor speed [rpm]", 60 / (2 * math.pi) / r),
                                     ("motor acc. [krad/s$^2$]", 1e-3 / r),
                                     ("motor jerk [Mrad/s$^3$]", 1e-6 / r / jerk_scale)]):
        sec = ax.secondary_yaxis("right", functions=(lambda y, f=f: y * f, lambda y, f=f: y / f))
        sec.set_ylabel(label, fontsize=8)
    return fig


def plot_drive(design):
    """The torque-speed path over the motor's curves and the torque over the cam angle."""
    import matplotlib.pyplot as plt

    from ..design.torque import design_torque
    from .drive import draw_torque_speed, draw_torque_terms

    t, terms = design_torque(design, samples=1441)
    fig, (ax1, ax2) = plt.subplots(1, 2, figsize=(11, 4.6), constrained_layout=True)
    draw_torque_speed(ax1, design.motor_spec, terms.omega, terms.total, t, design.problem.drive.limits,
                      f"{design.motor}: torque-speed path of the cycle")
    draw_torque_terms(ax2, 360 * t / design.stroke.period, terms, "torque over the cycle, by term")
    return fig


# --------------------------------------------------------------------------- sections


def _interval_rows(problem, spm: float) -> list[list[str]]:
    sch = problem.timing.schedule(spm)
    rows = []
    for itv, a0, a1, t0, dur in zip(problem.timing.intervals, sch.start_angle_deg, sch.end_angle_deg,
                                    sch.t_start, sch.duration):
        rows.append([h.cell(itv.index), h.cell(itv.name), h.cell("move" if itv.is_move else "dwell"),
                     h.cell(itv.law.label if itv.is_move else "-"),
                     h.cell(abs(itv.stroke) * 1e3 if itv.is_move else None),
                     h.cell(("up" if itv.stroke > 0 else "down") if itv.is_move else "-"),
                     h.cell(a0), h.cell(a1), h.cell(t0 * 1e3), h.cell((t0 + dur) * 1e3),
                     h.cell(itv.start_position * 1e3), h.cell("handover" if itv.handover else "")])
    return rows


def section_problem(d: ReportData) -> str:
    p, s = d.problem, d.summary
    facts = [("problem", p.name, "problem"), ("objective", s["objective"], "objective"),
             (f"objective value [{s['objective_unit']}]", s["objective_value"], "objective_value"),
             ("status", s["status"], "status"), ("stitch rate [spm]", s["spm"], "spm"),
             ("cam cycle [s]", s["cycle_time_s"], "cycle_time_s"), ("motor", s["motor"], "motor"),
             ("pulley teeth", s["pulley_teeth"], "pulley_teeth"),
             ("pulley pitch diameter [mm]", s["pulley_pitch_diameter_mm"], "pulley_pitch_diameter_mm"),
             ("peak torque [N m]", s["peak_torque_N_m"], "peak_torque_N_m"),
             ("RMS torque [N m]", s["rms_torque_N_m"], "rms_torque_N_m")]
    head = ["#", "interval", "kind", "law", "stroke mm", "direction", "from deg", "to deg", "from ms", "to ms",
            "start position mm", ""]
    return (h.para(f"{p.description} Design {d.source}; {period_text(s['cycle_time_s'], s['spm'])}.")
            + h.key_table(facts) + h.heading("Timing diagram (cam degrees and time)")
            + h.table(head, _interval_rows(p, s["spm"]))
            + h.svg_figure(plot_timing(p, d.design.stroke, s["spm"]),
                           "Bar position of the optimal stroke over one cam cycle; dwells shaded, the handover "
                           "dashed; top axis: time."))


def comparison_table(comparison: list[dict], objective: str, prefix: str = "comparison") -> str:
    cols = [("a_max_m_s2", "a_max m/s2"), ("jerk_max_m_s3", "jerk_max m/s3")]
    if comparison and "peak_torque_N_m" in comparison[0]:
        cols += [("peak_torque_N_m", "peak torque N m"), ("rms_torque_N_m", "RMS torque N m"),
                 ("peak_speed_rpm", "peak speed rpm")]
    if any(r.get("vs_optimal_pct") is not None for r in comparison):  # min_time, min_handover_error: none
        cols.append(("vs_optimal_pct", f"{objective} vs optimal %"))
    rows = []
    for i, r in enumerate(comparison):
        rows.append([h.cell(r["law"])] + [h.cell(r.get(k), f"{prefix}[{i}].{k}") for k, _ in cols]
                    + [h.raw_cell(h.verdict(r.get("feasible", True), "yes", "no: " + ", ".join(r.get("violates") or [])))])
    return h.table(["stroke"] + [c for _, c in cols] + ["feasible"], rows)


def section_stroke(d: ReportData) -> str:
    s = d.summary
    moves = [[h.cell(m["index"], f"moves[{i}].index"), h.cell(m["stroke_mm"], f"moves[{i}].stroke_mm"),
              h.cell(m["direction"]), h.cell(m["duration_s"] * 1e3),
              h.cell(m["v_max_m_s"], f"moves[{i}].v_max_m_s"), h.cell(m["a_max_m_s2"], f"moves[{i}].a_max_m_s2"),
              h.cell(m["jerk_max_m_s3"], f"moves[{i}].jerk_max_m_s3"), h.cell(m["C_a"], f"moves[{i}].C_a")]
             for i, m in enumerate(s["moves"])]
    law = d.problem.stroke(s["spm"])
    out = h.svg_figure(plot_stroke(d.problem, d.design, law),
                       f"The optimal stroke against the problem's law ({law.label}); left axes the bar, right axes "
                       "the motor (bar over the pulley radius).")
    out += h.heading("Moves") + h.table(["move", "stroke mm", "direction", "move time ms", "v_max m/s",
                                         "a_max m/s2", "jerk_max m/s3", "C_a"], moves)
    if s.get("comparison"):
        out += h.heading(f"Comparison with the classic laws on the same drive ({s['motor']}, "
                         f"{s['pulley_teeth']} teeth)") + comparison_table(s["comparison"], s["objective"])
        out += h.para("Laws marked 'no' break the design problem's constraints (listed last); the laws' handover "
                      "accuracy is not checked.", "note")
    return out


def binding_check(checks: list[dict]) -> dict | None:
    """The check with the least margin (the limit that binds first)."""
    finite = [c for c in checks if c.get("margin") is not None and math.isfinite(c["margin"])]
    return min(finite, key=lambda c: c["margin"]) if finite else None


def checks_table(checks: list[dict], prefix: str = "checks") -> str:
    rows = [[h.cell(c["name"]), h.cell(c["value"], f"{prefix}[{i}].value"), h.cell(c["limit"], f"{prefix}[{i}].limit"),
             h.cell(c["unit"]), h.cell(c["margin"], f"{prefix}[{i}].margin"), h.raw_cell(h.verdict(c["ok"]))]
            for i, c in enumerate(checks)]
    return h.table(["check", "value", "limit", "unit", "margin (1 - value/limit)", ""], rows)


def section_drive(d: ReportData) -> str:
    s = d.summary
    if d.design.motor_spec is None:
        return h.para("The problem has no [drive] section: no motor, no torque, no drive checks.")
    b = binding_check(s["checks"])
    out = h.svg_figure(plot_drive(d.design), "Left: the cycle's torque-speed path with its peak and RMS operating "
                       "points over the motor's peak and rated curves and the drive's torque limit. Right: the "
                       "torque over the cam angle by term.")
    out += h.heading("Checks (fine grid between the collocation nodes)") + checks_table(s["checks"])
    if b is not None:
        out += h.para(f"Binding limit: {b['name']} ({format_value(b['value'])} {b['unit']} against "
                      f"{format_value(b['limit'])} {b['unit']}, margin {100 * b['margin']:.1f} %).")
    out += h.para("Active constraints at the solution: " + ("; ".join(s["active_constraints"]) or "none") + ".")
    drive = s.get("drive") or {}
    if drive:
        out += h.para(f"Motor and pulley from {drive.get('from')}.", "note")
    return out


def section_accuracy(d: ReportData) -> str:
    if d.accuracy is None:
        return h.para("Not predicted: the problem has no [servo] section (servo loop and belt model) or no motor.")
    from .servo import plot_accuracy

    a = d.accuracy.summary()
    c, sc = a["contributions_mm"], a["signed_contributions_mm"]
    rows = [[h.cell("servo tracking"), h.cell(sc["servo_tracking"], "accuracy.signed_contributions_mm.servo_tracking")],
            [h.cell("belt stretch"), h.cell(sc["belt_stretch"], "accuracy.signed_contributions_mm.belt_stretch")],
            [h.cell("  of it: bar inertia"), h.cell(sc["belt_stretch_inertia"])],
            [h.cell("  of it: load forces"), h.cell(sc["belt_stretch_forces"])],
            [h.cell("encoder (one count, a bound)"),
             h.cell(c["encoder_quantisation"], "accuracy.contributions_mm.encoder_quantisation")],
            [h.cell(f"handover error (largest over {a['handover_window_deg']:g} deg after the handover)"),
             h.cell(a["handover_error_mm"], "accuracy.handover_error_mm")]]
    limit = d.problem.design.accuracy * 1e3 if d.problem.design is not None else None
    out = h.table(["contribution", "mm"], rows)
    if limit is not None:
        out += h.para(f"Requirement {limit:g} mm: " + ("met" if a["handover_error_mm"] <= limit else "NOT met")
                      + f" (full servo simulation: sampled position table, worst of its phases). Belt mode "
                      f"{a['belt_resonance_Hz']:.0f} Hz; residual belt vibration in the dwell "
                      f"{a['residual_vibration_mm']:.4f} mm; peak torque command {a['peak_torque_command_N_m']:.3f} N m"
                      + (f", ABOVE the torque limit {a['torque_limit_N_m']:.3f} N m: the drive saturates and the "
                         "prediction does not hold." if a["torque_limited"] else "."))
    out += h.svg_figure(plot_accuracy(d.accuracy, None, d.design.motor),
                        "Commanded and actual bar position, and the error with its servo and belt parts over the "
                        "cycle; the handover window shaded.")
    return out


def section_verification(d: ReportData) -> str:
    from .contact import plot_scene

    if not d.scenes:
        return h.para("The problem has no contact model ([model], [scenes.*]): nothing to verify.")
    rows, figs = [], ""
    keys = [("impact_velocity_m_s", "impact m/s"), ("impact_angle_deg", "impact deg"), ("lag_end_angle_deg", "lag end deg"),
            ("min_gap_N_mm", "min gap N mm"), ("release_angle_deg", "release deg")]
    for name, r in d.scenes.items():
        m = r.summary()
        ok = not m.get("premature_release")
        rows.append([h.cell(name)] + [h.cell(m.get(k), f"verification.{name}.{k}") for k, _ in keys]
                    + [h.cell(m.get("lag"), f"verification.{name}.lag"),
                       h.raw_cell(h.verdict(ok, "pass", "FAIL: premature release"))])
        figs += h.svg_figure(plot_scene(r), f"Scene {name}: velocities, positions and the remaining gap N; "
                                            "impact and release marked.")
    out = h.table(["scene"] + [c for _, c in keys] + ["lag", "verdict"], rows) + figs
    if d.not_simulated:
        out += h.para("Not simulated here: " + ", ".join(d.not_simulated) + " (add with --scene NAME or --scene all; "
                      "strokeopt verify DESIGN.json --scene NAME).", "note")
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
    return (h.key_table(facts) + h.para(
        "What tightening costs: `strokeopt solve PROBLEM --study mesh` solves the same design on finer meshes and "
        "higher degrees and prints the objective's error against the finest with the time each took; `strokeopt "
        "simulate PROBLEM --study tolerance` does the same for the integrator's tolerances."))


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
             ("motor and pulley of the design", f"{drive.get('motor')}, {drive.get('pulley_teeth')} teeth, from "
                                                f"{drive.get('from')}" if drive else "-", None),
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
    sections = [(sid, head, builders[sid](d)) for sid, head in SECTIONS]
    title = f"{d.problem.name}: {s['objective']} design at {s['spm']:g} spm"
    sub = (f"motor {s['motor'] or '(none)'}, pulley {s['pulley_teeth'] or 'continuous'} teeth; status {s['status']}; "
           f"strokeopt {d.versions.get('strokeopt', '')}, {d.created}")
    return h.page(title, sub, sections)


def write_report(d: ReportData, path) -> dict:
    """Write the report of ``d`` to ``path``; returns its size and the time it took (a JSON-ready dict)."""
    from pathlib import Path

    t0 = time.perf_counter()
    text = design_report(d)
    Path(path).write_text(text, encoding="utf-8")
    return {"report": str(path), "size_bytes": len(text.encode("utf-8")), "build_time_s": time.perf_counter() - t0}
