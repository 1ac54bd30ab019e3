"""The design report's verification section: the design's stroke re-simulated in its contact scenes and
judged, in the words of its machine -- the needle bar's impact, lag (with its size), gap N and release with
the scene over the whole cycle and a detail of its events; an elastic chain's link forces and each body's
acceleration against the rigid chain's. ``d`` is a :class:`~strokeopt.report.design_report.ReportData`;
nothing here simulates: the scenes are the verified design's."""

from __future__ import annotations

import math

from ..io.plain import counted
from . import html as h
from .machine import ELASTIC_CHAIN


def _criteria_table(block: dict) -> str:
    """The verification's criteria: value, limit, and met / FAILED / not judged."""
    rows = []
    for r in block["criteria"]:
        unit = r.get("unit") or ""
        value = ("yes" if r["value"] else "no") if isinstance(r["value"], bool) else r["value"]
        limit = "none" if r["limit"] is None else r["limit"]
        result = {True: h.verdict(True, "met"), False: h.verdict(False, no="FAILED"), None: "not judged"}[r["ok"]]
        rows.append([h.cell(r["criterion"]), h.cell(value), h.cell(limit), h.cell(unit), h.raw_cell(result)])
    return h.table(["criterion", "value", "limit", "unit", "result"], rows)


def _needle_bar_verification(d) -> str:
    from .contact import plot_scene

    rows, figs = [], ""
    keys = [("impact_velocity_m_s", "impact m/s"), ("impact_angle_deg", "impact deg"), ("max_lag_mm", "lag mm"),
            ("lag_onset_angle_deg", "lag from deg"), ("lag_end_angle_deg", "lag end deg"),
            ("min_gap_N_mm", "min gap N mm"), ("release_angle_deg", "release deg")]
    for name, r in d.scenes.items():
        m = r.summary()
        lag = m.get("max_lag_mm") if m.get("lag") else 0.0
        values = {**m, "max_lag_mm": lag}
        premature = m.get("premature_release")
        rows.append([h.cell(name)] + [h.cell(values.get(k), f"verification.{name}.{k}") for k, _ in keys]
                    + [h.raw_cell(h.verdict(not premature, "after the impact", "PREMATURE")
                                  if premature is not None else "no impact")])
        iv = m.get("impact_velocity_m_s")
        figs += h.svg_figure(plot_scene(r, problem=d.problem), f"Scene {name} over the whole cam cycle: velocities and positions "
                             f"of its bodies and the remaining gap N ({m.get('gap_N_mm'):g} mm at rest)"
                             + (f"; impact {iv:.2f} m/s at {m['impact_angle_deg']:.1f} deg" if iv is not None else "; no impact")
                             + (f", lag of {lag:.2f} mm from {m['lag_onset_angle_deg']:.1f} deg" if m.get("lag") else ", no lag")
                             + (f", release at {m['release_angle_deg']:.1f} deg" if m.get("release_angle_deg") is not None else "")
                             + ".")
        events = [m.get(k) for k in ("lag_onset_angle_deg", "impact_angle_deg", "release_angle_deg", "lag_end_angle_deg")]
        events = [a for a in events if a is not None]
        if events:  # the events take a few degrees of the cycle: a detail beside the whole
            window = (max(0.0, 5 * math.floor(min(events) / 5) - 10), min(360.0, 5 * math.ceil(max(events) / 5) + 10))
            figs += h.svg_figure(plot_scene(r, problem=d.problem, window=window),
                                 f"Scene {name}, detail of the events ({window[0]:g}-{window[1]:g} deg of the cycle "
                                 f"above), each axis scaled to it.")
    return h.table(["scene"] + [c for _, c in keys] + ["release"], rows) + figs


def _chain_verification(d) -> str:
    from ..contact.chain import chain_results
    from .contact import plot_chain

    out = ""
    for name, r in d.scenes.items():
        chain = chain_results(d.problem, r, d.design.stroke)
        bodies = [[h.cell(b["label"] or b["body"]), h.cell(b["stage"]), h.cell(b["elastic_peak_accel"]),
                   h.cell(b["rigid_peak_accel"]), h.cell(b["ratio"]), h.cell(b["unit"])] for b in chain["bodies"]]
        links = [[h.cell(k["link"]), h.cell(k["peak_compression"]), h.cell(k["peak_tension"]), h.cell(k["unit"]),
                  h.cell(k["clearance"] * (1e3 if k["unit"] == "N" else 1.0)),
                  h.cell("mm" if k["unit"] == "N" else "rad")] for k in chain["links"]]
        worst = max(chain["bodies"], key=lambda b: b["ratio"] or 0.0) if chain["bodies"] else None
        out += h.heading(f"Scene {name}: peak link forces (positive = compression)")
        out += h.table(["link", "peak compression", "peak tension", "unit", "play", "play unit"], links)
        out += h.heading(f"Scene {name}: peak acceleration of each body, the elastic chain against the rigid chain")
        out += h.table(["body", "member", "elastic peak", "rigid peak", "elastic / rigid", "unit"], bodies)
        if "screw" in chain:
            sc = chain["screw"]
            out += h.para(f"Screw torque from the peak nut force {sc['peak_nut_force_N']:.1f} N: "
                          f"{sc['screw_torque_N_cm']:.2f} N cm (pitch diameter {sc['screw_diameter_mm']:g} mm, friction "
                          f"{sc['thread_friction']:g}, flank angle {sc['thread_angle_deg']:g} deg, raising).")
        forces = ", ".join(f"{k['link']} {k['peak_abs']:.4g} {k['unit']}" for k in chain["links"])
        caption = (f"Scene {name} over the whole cam cycle: each body's acceleration in the elastic chain against the "
                   f"rigid chain's (from the stroke), one axis per body and unit, then the link forces by unit "
                   f"(peaks {forces})"
                   + (f"; the largest elastic-to-rigid ratio is the {worst['body']}'s, {worst['ratio']:.3g}"
                      if worst is not None and worst["ratio"] is not None else "") + ".")
        out += h.svg_figure(plot_chain(r, d.problem, d.design.stroke), caption)
    return out


def section_verification(d) -> str:
    if not d.scenes:
        return h.para("The problem has no contact model ([model], [scenes.*]): nothing to verify.")
    block = d.verification
    out = ""
    if block is not None:
        judged = h.para(f"The design's stroke re-simulated in scene {block['scene']!r} at {block['spm']:g} spm "
                        f"(contact model, CVODES) and judged:") + _criteria_table(block)
        oks = [r["ok"] for r in block["criteria"]]
        counts = [(oks.count(True), "met"), (oks.count(False), "failed"),
                  (oks.count(None), "not judged (the problem sets no limit: the value is reported)")]
        judged += h.para(f"Of {counted(len(oks), 'criterion', 'criteria')}: " + ", ".join(f"{n} {what}" for n, what in counts if n) + ".")
        out += f'<div class="keep">{judged}</div>'  # the judgement stays with the section's heading
    out += _chain_verification(d) if d.machine.scene == ELASTIC_CHAIN else _needle_bar_verification(d)
    if d.not_simulated:
        out += h.para("Not simulated here: " + ", ".join(d.not_simulated) + " (add with --scene NAME or --scene all; "
                      "strokeopt verify DESIGN.json --scene NAME).", "note")
    return out
