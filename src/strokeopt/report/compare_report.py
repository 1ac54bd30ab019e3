"""Designs side by side: one HTML file, the design report's sections with a column per design.

Each design is gathered as for its own report (:func:`strokeopt.report.design_report.gather`); the
page overlays their strokes and torques and puts every number in one table per section, a column
per design, the better value of a row marked where a row has a better direction (lower torque,
larger margin), the values differ as printed and none is the margin of a bound held active. Every number carries its ``data-key`` (``designs[1].peak_torque_N_m``).
"""

from __future__ import annotations

import math
import time

import numpy as np

from . import html as h
from .design_report import ReportData, binding_check, sections_for
from .machine import ELASTIC_CHAIN, drive_text
from .units import is_rotary, load_label
from ..io.load_units import load_key

#: Which way a row is better: -1 lower, +1 higher, 0 neither (a fact, not a merit).
LOWER, HIGHER, NEITHER = -1, 1, 0


def _names(datas: list[ReportData]) -> list[str]:
    """A short name per design: its design file's directory (``out_a``), or the whole path where two share it."""
    from pathlib import Path

    paths = [d.source.replace("read from ", "") or f"design {i + 1}" for i, d in enumerate(datas)]
    short = [Path(p).parent.name or p for p in paths]
    return short if len(set(short)) == len(short) else paths


def plot_overlay(datas: list[ReportData], names: list[str]):
    """Two figures: the designs' strokes (position, velocity, acceleration, jerk) over the cam angle; their
    torques over the cam angle and every design's torque-speed path with its own peak and RMS operating
    points over the first design's motor curves (a stepper's: its demand over the pull-out curve, each
    peak marked), or None without a drive."""
    import matplotlib.pyplot as plt

    from ..design.torque import design_torque_path
    from ..motion.stroke import StrokeFunction
    from .drive import draw_torque_speed, mark_operating_points, torque_angle_axis
    from .figures import PRINT_WIDTH_IN, legend_outside
    from .motion import draw_kinematics

    first = datas[0]
    names = [n if len(n) <= 28 else "\u2026" + n[-27:] for n in names]  # a legend's names: a path's tail
    strokes = [StrokeFunction(d.design.stroke.period, d.design.stroke.pieces, label=f"{n}: {d.design.objective}")
               for d, n in zip(datas, names)]
    fig = plt.figure(figsize=(PRINT_WIDTH_IN, 8.0), constrained_layout=True)
    grid = fig.add_gridspec(4, 1)
    axes = [fig.add_subplot(grid[0])]
    axes += [fig.add_subplot(grid[i], sharex=axes[0]) for i in range(1, 4)]
    draw_kinematics(axes, first.problem, strokes, first.design.spm, n=1441)
    for ax in axes[:-1]:
        ax.tick_params(labelbottom=False)
    fig_t, (ax_t, ax_w) = plt.subplots(2, 1, figsize=(PRINT_WIDTH_IN, 7.8), constrained_layout=True,
                                       height_ratios=[1, 1.5])
    colors = plt.rcParams["axes.prop_cycle"].by_key()["color"]
    drawn = False
    for k, (d, n) in enumerate(zip(datas, names)):
        torque = design_torque_path(d.design, samples=1441)  # its peak: the checks' (the load's switches read)
        if torque is None:
            continue
        t, terms = torque
        color = colors[k % len(colors)]
        ax_t.plot(360 * t / d.design.stroke.period, terms.total, lw=1.3, color=color, label=f"{n} ({d.design.motor})")
        stepper = getattr(d.design.motor_spec, "kind", "servo") == "stepper"
        if not drawn:
            draw_torque_speed(ax_w, d.design.motor_spec, terms.omega, terms.total, t, d.problem.drive.limits,
                              f"torque-speed paths over {d.design.motor}'s "
                              + ("pull-out curve" if stepper else "curves"))
            drawn = True
            # the first design's path and points are drawn in the first colour by draw_torque_speed
            for line in ax_w.get_lines()[-(2 if stepper else 3):]:  # its path and its points
                line.set_color(color)
                line.set_label(f"{n}: {line.get_label()}" if line.get_label() != "cycle" else n)
        elif stepper:  # its demand and its point of least reserve, as the first design's
            from ..drive.checks import pull_out_ratio

            spec = d.design.motor_spec
            rate, demand = np.abs(terms.omega) / spec.step_angle, np.abs(terms.total)
            ratio = pull_out_ratio(demand, terms.omega, spec)
            i = int(np.argmax(ratio))
            ax_w.plot(rate, demand, lw=1.2, color=color, label=n)
            ax_w.plot(rate[i], demand[i], "o", color=color, ms=7, mec="k", mew=0.5,
                      label=f"{n}: least reserve: demand {demand[i]:.3f} N m at {rate[i]:.0f} Hz, "
                            + (f"{100 * ratio[i]:.0f} % of pull-out" if np.isfinite(ratio[i]) else "beyond the table"))
        else:
            mark_operating_points(ax_w, terms.omega, terms.total, t, color, n)
            for line in ax_w.get_lines()[-2:]:
                line.set_label(f"{n}: {line.get_label()}")
    torque_angle_axis(ax_t, "motor torque over the cycle")
    if drawn:
        legend_outside(ax_w, where="below", ncol=2)
    else:
        plt.close(fig_t)
        fig_t = None
    return fig, fig_t


def _shown(value) -> str:
    """A value as the table prints it (what a reader can tell apart)."""
    return h.format_value(value) if not isinstance(value, str) else value


def _dimensions(transmission) -> str:
    """A transmission's own dimensions as the design has them (a crank radius the solve chose among them), for the
    drive row: '; crank radius 20.31 mm, connecting rod length 80 mm'; nothing for a pulley (its row says it)."""
    facts = [] if hasattr(transmission, "radius") else transmission.facts()
    shown = []
    for label, value in facts:
        name, _, unit = label.partition(" [")
        shown.append(f"{name} {h.format_value(value)}" + (f" {unit.rstrip(']')}" if unit else ""))
    return "; " + ", ".join(shown) if shown else ""


def _row(label: str, values: list, key: str | None, better: int = NEITHER, active: list | None = None) -> list[str]:
    """One table row: a cell per design; where the row has a direction, the best one marked when the values
    differ as printed (a difference below the printed precision is a tie) and no design's value is a margin
    of a bound its solution holds active (``active``: one flag per design)."""
    nums = [v for v in values if isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v)]
    best = None
    if (better != NEITHER and len(nums) == len(values) and len({_shown(v) for v in nums}) > 1
            and not any(active or ())):
        best = (min if better == LOWER else max)(nums)
        if sum(_shown(v) == _shown(best) for v in nums) > 1:  # the best printed twice: a tie at the top
            best = None
    cells = [h.cell(v, f"designs[{i}].{key}" if key else None,
                    cls="better" if best is not None and v == best else "") for i, v in enumerate(values)]
    return [f'<th class="text">{h.escape(label)}</th>'] + cells


def _table(names: list[str], rows: list[list[str]]) -> str:
    """A table, a column per design; a row every design has no value in is left out."""
    rows = [r for r in rows if any(h._text(c) not in ("", "-") for c in r[1:])]
    return h.table(["", *names], rows, cls="compare", keep_empty=True)


def _check(d: ReportData, name: str, field: str = "value"):
    return next((c[field] for c in d.summary["checks"] if c["name"] == name), None)


def _at_bound(d: ReportData, name: str) -> bool:
    """The check ``name`` of ``d`` sits at its limit (|margin| within the check tolerance): its margin is the
    solver's tolerance, not a merit."""
    margin = _check(d, name, "margin")
    settings = getattr(d.design, "settings", None)
    tol = getattr(settings, "check_tolerance", None) or 0.005
    return margin is not None and math.isfinite(margin) and abs(margin) <= tol


def _section_verification(datas: list[ReportData], names: list[str], machine) -> str:
    from ..contact.chain import chain_results

    scenes = list(dict.fromkeys(n for d in datas for n in d.scenes))
    rows = []
    for sc in scenes:
        results = [d.scenes.get(sc) for d in datas]
        if machine.scene == ELASTIC_CHAIN:
            chains = [chain_results(d.problem, r, d.design.stroke) if r is not None else {} for d, r in zip(datas, results)]
            links = list(dict.fromkeys(k["link"] for c in chains for k in c.get("links", [])))
            for link in links:
                ks = [next((k for k in c.get("links", []) if k["link"] == link), None) for c in chains]
                unit = next(k["unit"] for k in ks if k is not None)
                rows.append(_row(f"{sc}: peak force of link {link} [{unit}]", [k and k["peak_abs"] for k in ks],
                                 None, LOWER))
            bodies = list(dict.fromkeys(b["body"] for c in chains for b in c.get("bodies", [])))
            for body in bodies:
                bs = [next((b for b in c.get("bodies", []) if b["body"] == body), None) for c in chains]
                rows.append(_row(f"{sc}: {body} peak acceleration, elastic / rigid", [b and b["ratio"] for b in bs],
                                 None, LOWER))
            continue
        ms = [r.summary() if r is not None else {} for r in results]
        rows.append(_row(f"{sc}: impact velocity [m/s]", [m.get("impact_velocity_m_s") for m in ms], None, LOWER))
        rows.append(_row(f"{sc}: lag [mm]", [(m.get("max_lag_mm") if m.get("lag") else 0.0) if m else None for m in ms],
                         None, LOWER))
        rows.append(_row(f"{sc}: lag end [deg]", [m.get("lag_end_angle_deg") for m in ms], None))
        rows.append(_row(f"{sc}: min gap N [mm]", [m.get("min_gap_N_mm") for m in ms], None, HIGHER))
        rows.append(_row(f"{sc}: release [deg]", [m.get("release_angle_deg") for m in ms], None))
        rows.append(_row(f"{sc}: premature release", [m.get("premature_release") for m in ms], None))
    out = _table(names, rows) if rows else h.para("No contact scenes simulated.")
    for n, d in zip(names, datas):  # a verdict is a sentence: below the table, not in a narrow cell
        if d.summary.get("verdict"):
            out += h.para(f"{n}: {d.summary['verdict']}")
    return out


def compare_report(datas: list[ReportData]) -> str:
    """The HTML text of the comparison of ``datas`` (two or more designs): the sections of the first design's
    report (:func:`~strokeopt.report.design_report.sections_for` its machine), a column per design."""
    names = _names(datas)
    S = [d.summary for d in datas]
    machine = datas[0].machine
    cycle = datas[0].problem.cycle  # the machine's cycle: stitch, pick (io/cycle.py)
    heads = dict(sections_for(machine))
    built: dict = {}
    rows = [_row("problem", [s["problem"] for s in S], None), _row("objective", [s["objective"] for s in S], "objective"),
            _row("status", [s["status"] for s in S], "status"), _row(f"{cycle.rate_name} [{cycle.rate_unit}]", [s["spm"] for s in S], "spm"),
            _row("cam cycle [s]", [s["cycle_time_s"] for s in S], "cycle_time_s"),
            _row("drive", [drive_text(d.machine, s) + _dimensions(d.problem.transmission) for d, s in zip(datas, S)], None),
            _row("--set", ["; ".join(getattr(d.problem, "overrides", ())) or "none" for d in datas], None)]
    built["problem"] = _table(names, rows)
    if len({(s["objective"], s["objective_unit"]) for s in S}) == 1:   # one quantity: numbers in one row
        rows = [_row(f"objective value [{S[0]['objective_unit']}]", [s["objective_value"] for s in S], "objective_value")]
    else:   # designs for different objectives: each value says what it measures (a peak and an RMS are not one row)
        rows = [_row("objective value", [f"{h.format_value(s['objective_value'])} {s['objective_unit']} ({s['objective']})"
                                         for s in S], None)]
    moves = min(len(s["moves"]) for s in S)
    for i in range(moves):
        rotary = is_rotary(datas[0].problem)   # a rotary load's rad/s keys and labels (io/load_units.py)
        for k, label in (("a_max_m_s2", "a_max m/s2"), ("jerk_max_m_s3", "jerk_max m/s3"), ("v_max_m_s", "v_max m/s")):
            k, label = load_key(k, rotary), load_label(label, rotary)
            rows.append(_row(f"move {i + 1} {label}", [s["moves"][i][k] for s in S], f"moves[{i}].{k}", LOWER))
    strokes, torques = plot_overlay(datas, names)
    built["stroke"] = _table(names, rows) + h.svg_figure(
        strokes, f"The designs overlaid over the whole cam cycle: position, velocity, acceleration and jerk of the "
                 f"{machine.output}.")
    if torques is not None:
        points = ("least-reserve (circle)" if machine.stepper else "peak (circle) and RMS (diamond)")
        built["stroke"] += h.svg_figure(
            torques, f"Top: the motor torque of each design over the cycle. Bottom: every design's torque-speed "
                     f"path with its own {points} operating points over {datas[0].design.motor}'s "
                     + ("pull-out curve." if machine.stepper else "curves."))
    rows = [_row("motor", [s["motor"] for s in S], "motor"),
            _row("pulley teeth", [s["pulley_teeth"] for s in S], "pulley_teeth"),
            _row("peak torque [N m]", [s["peak_torque_N_m"] for s in S], "peak_torque_N_m", LOWER),
            _row("RMS torque [N m]", [s["rms_torque_N_m"] for s in S], "rms_torque_N_m", LOWER)]
    for name in dict.fromkeys(c["name"] for s in S for c in s["checks"]):
        unit = next(c["unit"] for s in S for c in s["checks"] if c["name"] == name)
        rows.append(_row(f"{name} [{unit}]", [_check(d, name) for d in datas], None, LOWER))
        rows.append(_row(f"{name}: margin", [_check(d, name, "margin") for d in datas], None, HIGHER,
                         active=[_at_bound(d, name) for d in datas]))
    rows.append(_row("binding limit", [(binding_check(s["checks"]) or {}).get("name") for s in S], None))
    rows.append(_row("active constraints", ["; ".join(s["active_constraints"]) or "none" for s in S], None))
    built["drive"] = _table(names, rows)
    acc = [d.accuracy.summary() if d.accuracy is not None else None for d in datas]
    rows = [_row("handover error [mm]", [a and a["handover_error_mm"] for a in acc], "accuracy.handover_error_mm", LOWER)]
    elastic = [a and a["compliance"] != "rigid" for a in acc]   # a rigid drive (a crank) has no stretch: "-"
    rows.append(_row("servo tracking [mm]", [a and a["signed_contributions_mm"]["servo_tracking"] for a in acc], None))
    rows.append(_row("belt stretch [mm]", [a["signed_contributions_mm"]["belt_stretch"] if e else None
                                           for a, e in zip(acc, elastic)], None))
    rows.append(_row("encoder (one count) [mm]", [a and a["contributions_mm"]["encoder_quantisation"] for a in acc], None))
    rows.append(_row("residual belt vibration [mm]", [a["residual_vibration_mm"] if e else None
                                                      for a, e in zip(acc, elastic)], None, LOWER))
    built["accuracy"] = _table(names, rows)
    built["verification"] = _section_verification(datas, names, machine)
    rows = [_row("mesh intervals x degree", [f"{s['mesh']['intervals']} x {s['mesh']['degree']}" for s in S], None),
            _row("IPOPT iterations", [s["iterations"] for s in S], "iterations"),
            _row("solve time [s]", [s["solve_time_s"] for s in S], "solve_time_s")]
    built["numerics"] = _table(names, rows)
    rows = [_row("problem file", [str(d.problem.file) for d in datas], None),
            _row("design file", [d.source.replace("read from ", "") for d in datas], None), _row("created", [datas[0].created] * len(datas), None)]
    rows += [_row(k, [v] * len(datas), None) for k, v in datas[0].versions.items()]
    built["inputs"] = _table(names, rows)
    sections = [(sid, heads[sid], built[sid]) for sid in heads]
    title = f"{S[0]['problem']}: {len(datas)} designs compared"
    sub = " | ".join(f"{n}: {s['objective']}, {drive_text(d.machine, s)}, {d.problem.cycle.rate(s['spm'])}"
                     for n, s, d in zip(names, S, datas)) + (" (green: the better value of a row, where the values "
                                                             "differ as printed and no bound is active)")
    return h.page(title, sub, sections)


def write_compare(datas: list[ReportData], path) -> dict:
    """Write the comparison of ``datas`` to ``path``; returns its size and build time (JSON-ready)."""
    from pathlib import Path

    t0 = time.perf_counter()
    text = compare_report(datas)
    Path(path).write_text(text, encoding="utf-8")
    return {"report": str(path), "size_bytes": len(text.encode("utf-8")), "build_time_s": time.perf_counter() - t0}
