"""Designs side by side: one HTML file, the design report's sections with a column per design.

Each design is gathered as for its own report (:func:`strokeopt.report.design_report.gather`); the
page overlays their strokes and torques and puts every number in one table per section, a column
per design, the better value of a row marked where a row has a better direction (lower torque,
larger margin). Every number carries its ``data-key`` (``designs[1].peak_torque_N_m``).
"""

from __future__ import annotations

import math
import time

from . import html as h
from .design_report import ReportData, binding_check

#: Which way a row is better: -1 lower, +1 higher, 0 neither (a fact, not a merit).
LOWER, HIGHER, NEITHER = -1, 1, 0


def _names(datas: list[ReportData]) -> list[str]:
    """A short name per design: its design file's directory (``out_a``), or the whole path where two share it."""
    from pathlib import Path

    paths = [d.source.replace("read from ", "") or f"design {i + 1}" for i, d in enumerate(datas)]
    short = [Path(p).parent.name or p for p in paths]
    return short if len(set(short)) == len(short) else paths


def plot_overlay(datas: list[ReportData], names: list[str]):
    """The designs' strokes (position, velocity, acceleration, jerk) and their torques over the cam angle
    and the torque-speed paths over the first design's motor curves."""
    import matplotlib.pyplot as plt

    from ..design.torque import design_torque
    from ..motion.stroke import StrokeFunction
    from .drive import draw_torque_speed, torque_angle_axis
    from .motion import draw_kinematics

    first = datas[0]
    strokes = [StrokeFunction(d.design.stroke.period, d.design.stroke.pieces, label=f"{n}: {d.design.objective}")
               for d, n in zip(datas, names)]
    fig = plt.figure(figsize=(10, 10.5), constrained_layout=True)
    grid = fig.add_gridspec(6, 2, height_ratios=[1, 1, 1, 1, 0.15, 1.6])
    axes = [fig.add_subplot(grid[0, :])]
    axes += [fig.add_subplot(grid[i, :], sharex=axes[0]) for i in range(1, 4)]
    draw_kinematics(axes, first.problem, strokes, first.design.spm, n=1441)
    axes[0].legend(fontsize=8, loc="best")
    ax_t = fig.add_subplot(grid[5, 0])
    ax_w = fig.add_subplot(grid[5, 1])
    drawn = False
    for d, n in zip(datas, names):
        torque = design_torque(d.design, samples=1441)
        if torque is None:
            continue
        t, terms = torque
        line, = ax_t.plot(360 * t / d.design.stroke.period, terms.total, lw=1.3, label=f"{n} ({d.design.motor})")
        if not drawn:
            draw_torque_speed(ax_w, d.design.motor_spec, terms.omega, terms.total, t, d.problem.drive.limits,
                              f"torque-speed paths over {d.design.motor}'s curves")
            drawn = True
        else:
            ax_w.plot(terms.omega * 60 / (2 * math.pi), terms.total, lw=1.2, color=line.get_color(), label=n)
    torque_angle_axis(ax_t, "motor torque over the cycle")
    if drawn:
        ax_w.legend(fontsize=7, loc="best")
    return fig


def _row(label: str, values: list, key: str | None, better: int = NEITHER) -> list[str]:
    """One table row: a cell per design, the best one marked when the row has a direction and they differ."""
    nums = [v for v in values if isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v)]
    best = None
    if better != NEITHER and len(nums) == len(values) and len(set(nums)) > 1:
        best = (min if better == LOWER else max)(nums)
    cells = [h.cell(v, f"designs[{i}].{key}" if key else None,
                    cls="better" if best is not None and v == best else "") for i, v in enumerate(values)]
    return [f'<th class="text">{h.escape(label)}</th>'] + cells


def _table(names: list[str], rows: list[list[str]]) -> str:
    return h.table(["", *names], rows)


def _check(d: ReportData, name: str, field: str = "value"):
    return next((c[field] for c in d.summary["checks"] if c["name"] == name), None)


def compare_report(datas: list[ReportData]) -> str:
    """The HTML text of the comparison of ``datas`` (two or more designs)."""
    names = _names(datas)
    S = [d.summary for d in datas]
    sections = []
    rows = [_row("problem", [s["problem"] for s in S], None), _row("objective", [s["objective"] for s in S], "objective"),
            _row("status", [s["status"] for s in S], "status"), _row("stitch rate [spm]", [s["spm"] for s in S], "spm"),
            _row("cam cycle [s]", [s["cycle_time_s"] for s in S], "cycle_time_s"),
            _row("--set", ["; ".join(getattr(d.problem, "overrides", ())) or "none" for d in datas], None)]
    sections.append(("problem", "Problem and timing", _table(names, rows)))
    rows = [_row(f"objective value [{s0}]" if len({s['objective_unit'] for s in S}) == 1 else "objective value",
                 [s["objective_value"] for s in S], "objective_value")
            for s0 in [S[0]["objective_unit"]]]
    moves = min(len(s["moves"]) for s in S)
    for i in range(moves):
        for k, label in (("a_max_m_s2", "a_max m/s2"), ("jerk_max_m_s3", "jerk_max m/s3"), ("v_max_m_s", "v_max m/s")):
            rows.append(_row(f"move {i + 1} {label}", [s["moves"][i][k] for s in S], f"moves[{i}].{k}", LOWER))
    fig = h.svg_figure(plot_overlay(datas, names), "The designs overlaid: bar position, velocity, acceleration and jerk "
                                                   "over the cam angle; the motor torque over the cycle and the "
                                                   "torque-speed paths.")
    sections.append(("stroke", "Stroke and torque, overlaid", fig + _table(names, rows)))
    rows = [_row("motor", [s["motor"] for s in S], "motor"), _row("pulley teeth", [s["pulley_teeth"] for s in S], "pulley_teeth"),
            _row("peak torque [N m]", [s["peak_torque_N_m"] for s in S], "peak_torque_N_m", LOWER),
            _row("RMS torque [N m]", [s["rms_torque_N_m"] for s in S], "rms_torque_N_m", LOWER)]
    for name in dict.fromkeys(c["name"] for s in S for c in s["checks"]):
        unit = next(c["unit"] for s in S for c in s["checks"] if c["name"] == name)
        rows.append(_row(f"{name} [{unit}]", [_check(d, name) for d in datas], None, LOWER))
        rows.append(_row(f"{name}: margin", [_check(d, name, "margin") for d in datas], None, HIGHER))
    rows.append(_row("binding limit", [(binding_check(s["checks"]) or {}).get("name") for s in S], None))
    sections.append(("drive", "Drive: torques and checks", _table(names, rows)))
    acc = [d.accuracy.summary() if d.accuracy is not None else None for d in datas]
    rows = [_row("handover error [mm]", [a and a["handover_error_mm"] for a in acc], "accuracy.handover_error_mm", LOWER)]
    for k in ("servo_tracking", "belt_stretch"):
        rows.append(_row(f"{k.replace('_', ' ')} [mm]", [a and a["signed_contributions_mm"][k] for a in acc], None))
    rows.append(_row("residual belt vibration [mm]", [a and a["residual_vibration_mm"] for a in acc], None, LOWER))
    sections.append(("accuracy", "Handover accuracy", _table(names, rows)))
    scenes = list(dict.fromkeys(n for d in datas for n in d.scenes))
    rows = []
    for sc in scenes:
        ms = [d.scenes[sc].summary() if sc in d.scenes else {} for d in datas]
        rows.append(_row(f"{sc}: impact velocity [m/s]", [m.get("impact_velocity_m_s") for m in ms], None, LOWER))
        rows.append(_row(f"{sc}: min gap N [mm]", [m.get("min_gap_N_mm") for m in ms], None, HIGHER))
        rows.append(_row(f"{sc}: release [deg]", [m.get("release_angle_deg") for m in ms], None))
        rows.append(_row(f"{sc}: premature release", [m.get("premature_release") for m in ms], None))
    sections.append(("verification", "Contact-model verification",
                     _table(names, rows) if rows else h.para("No contact scenes simulated.")))
    rows = [_row("mesh intervals x degree", [f"{s['mesh']['intervals']} x {s['mesh']['degree']}" for s in S], None),
            _row("IPOPT iterations", [s["iterations"] for s in S], "iterations"),
            _row("solve time [s]", [s["solve_time_s"] for s in S], "solve_time_s")]
    sections.append(("numerics", "Numerical accuracy", _table(names, rows)))
    rows = [_row("problem file", [str(d.problem.file) for d in datas], None),
            _row("design file", [d.source.replace("read from ", "") for d in datas], None), _row("created", [datas[0].created] * len(datas), None)]
    rows += [_row(k, [v] * len(datas), None) for k, v in datas[0].versions.items()]
    sections.append(("inputs", "Inputs and versions", _table(names, rows)))
    title = f"{S[0]['problem']}: {len(datas)} designs compared"
    sub = " | ".join(f"{n}: {s['objective']}, {s['motor']}, {s['pulley_teeth']} teeth, {s['spm']:g} spm"
                     for n, s in zip(names, S)) + " (green: the better value of a row)"
    return h.page(title, sub, sections)


def write_compare(datas: list[ReportData], path) -> dict:
    """Write the comparison of ``datas`` to ``path``; returns its size and build time (JSON-ready)."""
    from pathlib import Path

    t0 = time.perf_counter()
    text = compare_report(datas)
    Path(path).write_text(text, encoding="utf-8")
    return {"report": str(path), "size_bytes": len(text.encode("utf-8")), "build_time_s": time.perf_counter() - t0}
