"""The HTML report of a linkage problem file (``strokeopt report LINKAGE.toml --out FILE.html``): structure,
kinematics of every output with the mechanism figure, transmission quality over the cycle, the crank torque with
the motor and gearbox on the crank, and (``--servo SERVO.toml``) the linkage against a servo driving its output.

Every number a table shows carries its place in the commands' JSON as ``data-key``: ``kinematics.`` +
the key in ``strokeopt kinematics LINKAGE --json``, ``size.`` + the key in ``strokeopt size LINKAGE --json``,
``servo.`` + the key in :meth:`~strokeopt.studies.linkage_servo.LinkageServo.to_dict`. Formats and draws what it
is given (:class:`LinkageReportData`); nothing here solves.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

from . import html as h
from .linkage import _draw_transmission, plot_linkage, plot_linkage_size


@dataclass
class LinkageReportData:
    """What the report shows: the kinematics and size summaries (the commands' JSON), the solved cycle and its
    dynamics for the figures, the servo comparison or None, and where the page comes from."""

    kinematics: dict              # the transmission's analysis (Transmission.analysis: linkage.summary.summarize)
    size: dict                    # the report of `strokeopt size --json`, with the analysis's crank torque
    kin: Any                      # linkage.kinematics.Kinematics
    cycle: Any                    # its Cycle at the file's angles
    dynamics: Any                 # linkage.dynamics.Dynamics at the file's rpm
    servo: Any = None             # studies.linkage_servo.LinkageServo, or None
    servo_file: str = ""
    overrides: list = field(default_factory=list)
    versions: dict = field(default_factory=dict)
    created: str = ""


def _structure(d: LinkageReportData) -> str:
    k = d.kinematics
    st = k["structure"]
    facts = [("problem", k["problem"], "kinematics.transmission_analysis.problem"), ("file", k["file"], None),
             ("crank speed [rpm]", k["rpm"], "kinematics.transmission_analysis.rpm"), ("crank speed [rad/s]", k["omega_rad_s"],
                                                                 "kinematics.transmission_analysis.omega_rad_s"),
             ("mobility (Gruebler)", st["mobility"], "kinematics.transmission_analysis.structure.mobility"),
             ("links (with the ground)", st["links"], "kinematics.transmission_analysis.structure.links"),
             ("revolute joints", st["revolute_joints"], "kinematics.transmission_analysis.structure.revolute_joints"),
             ("independent loops", st["independent_loops"], "kinematics.transmission_analysis.structure.independent_loops"),
             ("largest closure residual [m]", k["closure"]["max_residual_m"], "kinematics.transmission_analysis.closure.max_residual_m"),
             ("pose after one turn, off by [m]", k["closure"]["return_error_m"], "kinematics.transmission_analysis.closure.return_error_m")]
    groups = [[h.cell(g["kind"]), h.cell(", ".join(g["links"])), h.cell(", ".join(g["joints"])),
               h.cell(", ".join(g["attached_to"]))] for g in st["groups"] if g["kind"] != "placement"]
    loops = [[h.cell("-".join(f["joints"])), h.cell(", ".join(f["links"])), h.cell(f["grashof"]), h.cell(f["class"]),
              h.cell(f["relative_to"])] for f in st["four_bar_loops"]]
    lengths = [[h.cell(link), h.cell(pair), h.cell(mm, f"kinematics.transmission_analysis.link_lengths_mm.{link}.{pair}")]
               for link, pairs in k["link_lengths_mm"].items() for pair, mm in pairs.items()]
    return (h.key_table(facts) + h.heading("Groups solved together") + h.table(["kind", "links", "joints",
                                                                                "attached to"], groups)
            + h.heading("Four-bar loops") + h.table(["joints", "links", "Grashof", "class", "relative to"], loops)
            + h.heading("Link lengths (from the reference pose)") + h.table(["link", "joints", "mm"], lengths))


OUTPUT_FACTS = [("swing", "swing_{unit}", "{unit}"), ("minimum at", "minimum_at_deg", "deg of crank"),
                ("maximum at", "maximum_at_deg", "deg of crank"), ("rise", "rise_deg", "deg of crank"),
                ("fall", "fall_deg", "deg of crank"), ("rise / fall", "asymmetry_rise_over_fall", "-")]


def _output(o: dict, i: int, pct: float) -> str:
    key = f"kinematics.transmission_analysis.outputs[{i}]"
    facts = [(f"{label} [{unit.format(unit=o['unit'])}]", o[name.format(unit=o["unit"])],
              f"{key}.{name.format(unit=o['unit'])}") for label, name, unit in OUTPUT_FACTS]
    for j, dw in enumerate(o["near_dwells"]):
        facts.append((f"near-dwell at the {dw['at']} (within {pct:g} % of the swing) [deg of crank]",
                      dw["length_deg"], f"{key}.near_dwells[{j}].length_deg"))
    for q in ("speed", "acceleration", "jerk"):
        facts.append((f"peak |{q}| [{o[q + '_unit'] if q != 'speed' else o['speed_unit']}]",
                      o["peaks"][q]["max_abs"], f"{key}.peaks.{q}.max_abs"))
    step = max(1, len(o["table"]) // 12)
    rows = [[h.cell(r["angle_deg"], f"{key}.table[{j}].angle_deg", shown=f"{r['angle_deg']:g}"),
             h.cell(r["position"], f"{key}.table[{j}].position"),
             h.cell(r["speed"], f"{key}.table[{j}].speed"), h.cell(r["acceleration"], f"{key}.table[{j}].acceleration"),
             h.cell(r["jerk"], f"{key}.table[{j}].jerk")] for j, r in enumerate(o["table"]) if j % step == 0]
    head = ["crank deg", f"position {o['unit']}", f"speed {o['speed_unit']}", f"accel {o['acceleration_unit']}",
            f"jerk {o['jerk_unit']}"]
    return h.heading(f"Output {o['name']} ({o['kind']})") + h.key_table(facts) + h.table(head, rows)


def _kinematics(d: LinkageReportData) -> str:
    k = d.kinematics
    out = h.para(f"Every output over one turn of the crank at {k['rpm']:g} rpm (exact: Newton continuation from the "
                 "reference pose, derivatives by AD); a near-dwell is where the output stays within "
                 f"{k['near_dwell_pct']:g} % of its swing of an extreme.")
    out += "".join(_output(o, i, k["near_dwell_pct"]) for i, o in enumerate(k["outputs"]))
    first = k["outputs"][0]["name"] if k["outputs"] else ""
    return out + h.svg_figure(plot_linkage(d.kin, d.cycle, k, None),
                              f"The mechanism at six crank angles 60 deg apart with the joints' paths; {first} and "
                              "its speed over the crank angle; the transmission index of every group.")


def _transmission(d: LinkageReportData) -> str:
    import matplotlib.pyplot as plt

    rows = []
    for i, t in enumerate(d.kinematics["transmission"]):
        key = f"kinematics.transmission_analysis.transmission[{i}]"
        rows.append([h.cell(t["group"]), h.cell(", ".join(t["links"])), h.cell(t["min_index"], f"{key}.min_index"),
                     h.cell(t["at_deg"], f"{key}.at_deg", shown=f"{t['at_deg']:g}"),
                     h.cell(t.get("min_transmission_angle_deg")),
                     h.cell(t["limit"], f"{key}.limit"), h.raw_cell(h.verdict(t["ok"]))])
    fig, ax = plt.subplots(figsize=(7.3, 2.8), constrained_layout=True)
    _draw_transmission(ax, d.cycle, d.kinematics["transmission"])
    ax.grid(alpha=0.3)
    return (h.para("The transmission index of a group is the Hadamard ratio of its block of the normalised closure "
                   "Jacobian: 1 at best, 0 at a dead centre; for a dyad it is the sine of Alt's transmission angle.")
            + h.table(["group", "links", "least index", "at crank deg", "Alt's angle deg", "limit", "result"], rows)
            + h.svg_figure(fig, "The transmission index over the crank angle, with the file's limit (dashed)."))


def _torque(d: LinkageReportData) -> str:
    s = d.size["transmission_analysis"]
    dyn = s["dynamics"]
    t = dyn["torque_N_m"]
    facts = [("crank torque max [N m]", t["max"], "size.transmission_analysis.dynamics.torque_N_m.max"),
             ("at crank [deg]", t["max_at_deg"], "size.transmission_analysis.dynamics.torque_N_m.max_at_deg"),
             ("crank torque min [N m]", t["min"], "size.transmission_analysis.dynamics.torque_N_m.min"),
             ("at crank [deg]", t["min_at_deg"], "size.transmission_analysis.dynamics.torque_N_m.min_at_deg"),
             ("crank torque RMS [N m]", t["rms"], "size.transmission_analysis.dynamics.torque_N_m.rms"),
             ("reduced inertia J, least [kg m^2]", dyn["reduced_inertia_kg_m2"]["min"],
              "size.transmission_analysis.dynamics.reduced_inertia_kg_m2.min"),
             ("reduced inertia J, largest [kg m^2]", dyn["reduced_inertia_kg_m2"]["max"],
              "size.transmission_analysis.dynamics.reduced_inertia_kg_m2.max"),
             ("Newton-Euler against the power balance (of the peak)", dyn["newton_euler_max_relative_difference"],
              "size.transmission_analysis.dynamics.newton_euler_max_relative_difference")]
    loads = [[h.cell(ld["name"]), h.cell(f"{ld['link']} at {ld['joint']}"), h.cell(ld["from_deg"]),
              h.cell(ld["to_deg"]), h.cell(ld["force_start_N"]), h.cell(ld["force_end_N"])] for ld in s["process_loads"]]
    z = d.size
    cands = [[h.cell(c.get("gearbox", "-")), h.cell(c.get("ratio", "-")), h.cell(c["motor"]),
              h.cell(c["peak_torque_N_m"], f"size.candidates[{i}].peak_torque_N_m"),
              h.cell(c["rms_torque_N_m"], f"size.candidates[{i}].rms_torque_N_m"),
              h.cell(c["peak_speed_rpm"]), h.cell(c["inertia_ratio"]), h.raw_cell(h.verdict(c["feasible"], "fits", "no")),
              h.cell(c["binding"])] for i, c in enumerate(z["candidates"])]
    chosen = f"{z['verdict']}."
    return (h.para(f"At a constant {s['rpm']:g} rpm the crank needs M = J' w^2 / 2 + V' - sum F (u . r') (power "
                   "balance); Newton-Euler's balances of every link give the same torque.")
            + (h.para("Note: " + s["note"], "note") if s.get("note") else "") + h.key_table(facts)
            + (h.heading("Process loads") + h.table(["load", "on", "from deg", "to deg", "start N", "end N"], loads)
               if loads else "")
            + h.svg_figure(plot_linkage_size(d.kin, d.cycle, d.dynamics, s, None),
                           "The mechanism and the transmission index; the crank torque by term with Newton-Euler's "
                           "(dots); the reduced inertia J and J' over the crank angle.")
            + h.heading("A servo motor and gearbox on the crank")
            + h.para("A servo motor (through a gearbox) on the crank at its constant speed, without the main shaft's "
                     "flywheel: the motor delivers every peak of the crank torque. "
                     f"Every motor of the catalogues ({', '.join(map(str, z['inputs']['catalogue_files'])) or 'the shipped'})"
                     + (f" with every gearbox of {z['drive']['gearboxes']}" if z["drive"].get("gearboxes") else "")
                     + f", ranked as `strokeopt size` ranks them ({z['inputs']['choose'].replace('_', ' ')} first).",
                     "note")
            + h.table(["gearbox", "i", "motor", "peak N m", "RMS N m", "motor rpm", "inertia ratio", "fits",
                       "binding"], cands) + h.para(chosen))


def _servo(d: LinkageReportData) -> str:
    from ..studies.linkage_servo import plot_linkage_servo

    r = d.servo
    rows = [[h.cell(row["quantity"]), h.cell(row["unit"]), _value(row["linkage"], f"servo.table[{i}].linkage"),
             _value(row["servo"], f"servo.table[{i}].servo")] for i, row in enumerate(r.table())]
    return (h.para(f"The linkage against its output driven directly by a servo through a gearbox ({d.servo_file}; "
                   "docs/loom-servo.md). The linkage's crank runs from the main shaft and flywheel, which even out its "
                   "peaks; a servo must deliver and absorb every peak itself.")
            + h.table(["quantity", "unit", "linkage", "servo"], rows)
            + h.svg_figure(plot_linkage_servo(r), "The output's angle, its acceleration, and the crank's and the "
                                                 "motor's torque over the crank angle."))


def _value(value, key: str) -> str:
    """A cell of the comparison: text as it is, a number with its key, a quantity a side has not ('-')."""
    if isinstance(value, str):
        return h.cell(value)
    return h.cell("-") if math.isnan(value) else h.cell(value, key)


def linkage_report(d: LinkageReportData) -> str:
    """The HTML text of the linkage report of ``d``."""
    sections = [("structure", "Linkage: structure", _structure(d)), ("kinematics", "Kinematics", _kinematics(d)),
                ("transmission", "Transmission quality", _transmission(d)),
                ("torque", "Crank torque and drive", _torque(d))]
    if d.servo is not None:
        sections.append(("servo", "Linkage against a servo", _servo(d)))
    facts = [("--set", "; ".join(d.overrides) or "none", None), ("created", d.created, None)]
    sections.append(("inputs", "Inputs and versions", h.key_table(facts + [(k, v, None) for k, v in d.versions.items()])))
    k = d.kinematics
    return h.page(f"{k['problem']}: planar linkage at {k['rpm']:g} rpm", f"{k['file']}; status {k['status']}; "
                  f"strokeopt {d.versions.get('strokeopt', '')}, {d.created}", sections)
