"""Design results: the text account of a design (:func:`design_text`), the JSON summary of
``strokeopt solve`` (:func:`design_summary`), and the mesh-study and stitch-rate sweep figures."""

from __future__ import annotations

from ..drive.checks import torque_limit_text
from ..io.cycle import STITCH, cycle_of
from ..io.load_units import load_key
from .format import format_table, format_value, period_text
from ..design.result import Design, design_summary, move_direction  # noqa: F401 (design_summary: read from here too)
from ..design.transcription.objectives import objective_of
from ..design.transcription.settings import DesignSettings


def plot_mesh_study(rows: list[dict], path=None):
    """Work-precision of the design collocation: objective error and violation between nodes vs solve time."""
    import matplotlib.pyplot as plt  # here: text reports do not import matplotlib

    fig, axes = plt.subplots(1, 2, figsize=(10, 4), constrained_layout=True)
    for degree in sorted({r["degree"] for r in rows}):
        sel = [r for r in rows if r["degree"] == degree and not r.get("reference")]
        if not sel:
            continue
        t = [r["time_s"] for r in sel]
        axes[0].loglog(t, [max(r["objective_error_pct"], 1e-9) for r in sel], "o-", label=f"degree {degree}")
        axes[1].semilogx(t, [100 * r["violation_between_nodes"] for r in sel], "o-", label=f"degree {degree}")
        for r in sel:
            axes[0].annotate(str(r["intervals"]), (r["time_s"], max(r["objective_error_pct"], 1e-9)), fontsize=7,
                             xytext=(3, 3), textcoords="offset points")
    axes[0].set_ylabel("objective error vs finest mesh [%]")
    axes[1].set_ylabel("largest bound violation between nodes [%]")
    for ax in axes:
        ax.set_xlabel("build + solve time [s]")
        ax.grid(True, which="both", alpha=0.3)
        ax.legend(fontsize=8)
    axes[0].set_title("what accuracy costs in time (labels: mesh intervals)")
    if path is not None:
        from .figures import fit_titles

        fit_titles(fig)  # no title wider than its axes
        fig.savefig(path, dpi=120)
        plt.close(fig)
    return fig


def plot_design(design: Design, law_stroke=None, path=None):
    """The optimal stroke (and the problem's classic law for comparison) over the cam angle, and,
    with a drive, the design's torque-speed path over the cycle with its peak and RMS operating
    points over its motor's peak, rated and drive-limit curves."""
    import matplotlib.pyplot as plt
    from ..design.torque import design_torque_path
    from .drive import draw_torque_speed
    from .motion import draw_kinematics

    path_torque = design_torque_path(design, 3601)  # its peak: the checks' (the load's switches read)
    fig = plt.figure(figsize=(15 if path_torque else 9, 9), constrained_layout=True)
    grid = fig.add_gridspec(4, 2 if path_torque else 1, width_ratios=[1.25, 1] if path_torque else None)
    axes = [fig.add_subplot(grid[0, 0])]
    axes += [fig.add_subplot(grid[i, 0], sharex=axes[0]) for i in range(1, 4)]
    for ax in axes[:-1]:
        ax.tick_params(labelbottom=False)
    strokes = [design.stroke] + ([law_stroke] if law_stroke is not None else [])
    draw_kinematics(axes, design.problem, strokes, design.spm)
    axes[0].set_title(f"{' vs '.join(s.label for s in strokes)}; {period_text(design.stroke.period, design.spm, design)}",
                      fontsize=9)
    from .machine import machine_of

    machine = machine_of(design.problem, design)
    drive = (f", motor {design.motor}, pulley {_pulley_text(design)}" if design.pitch_diameter is not None
             else f", {machine.drive_words} on the {machine.transmission}")
    what = f"{design.objective}" + (drive if design.motor else "")
    fig.suptitle(f"{design.problem.name}: optimal stroke ({what}) at {cycle_of(design).rate(design.spm)}", fontsize=11)
    if path_torque:
        t, terms = path_torque
        limits = design.problem.drive.limits
        draw_torque_speed(fig.add_subplot(grid[:, 1]), design.motor_spec, terms.omega, terms.total, t,
                          limits, "torque demand of the optimal stroke over the pull-out curve" if machine.stepper
                          else "torque-speed path of the optimal stroke over the cycle")
    if path is not None:
        from .figures import fit_titles

        fit_titles(fig)  # no title wider than its axes
        fig.savefig(path, dpi=110)
        plt.close(fig)
    return fig


def plot_design_sweep(rows: list[dict], path=None, objective: str | None = None, cycle=STITCH):
    """Optimal objective (and peak torque) over the machine's rate of a design sweep; infeasible rates marked
    (``cycle``: the machine's cycle, io/cycle.py)."""
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(8, 4), constrained_layout=True)
    ok = [r for r in rows if r["feasible"]]
    bad = [r for r in rows if not r["feasible"]]
    unit = next((r["objective_unit"] for r in ok if r.get("objective_unit")), "")
    quantity = f"{objective or 'objective'}" + (f" [{unit}]" if unit else "")
    if ok:
        ax.plot([r["spm"] for r in ok], [r["objective_value"] for r in ok], "o-", label=f"optimal {quantity}")
        if ok[0].get("peak_torque_N_m") is not None:
            ax.plot([r["spm"] for r in ok], [r["peak_torque_N_m"] for r in ok], "s--", label="peak torque [N m]")
    for r in bad:
        ax.axvline(r["spm"], color="tab:red", alpha=0.4, lw=1)
    cycle = cycle_of(cycle)
    ax.set_xlabel(f"{cycle.rate_name} [{cycle.rate_unit}]")
    ax.set_ylabel(quantity if not ok or ok[0].get("peak_torque_N_m") is None or unit == "N m" else
                  f"{quantity}; peak torque [N m]")
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize=8)
    motors = ", ".join(dict.fromkeys(str(r["motor"]) for r in ok if r.get("motor"))) or "-"
    ax.set_title(f"optimal design ({objective or 'objective'}; motor {motors}) over the {cycle.rate_name} "
                 "(red: infeasible)", fontsize=10)
    if path is not None:
        from .figures import fit_titles

        fit_titles(fig)  # no title wider than its axes
        fig.savefig(path, dpi=120)
        plt.close(fig)
    return fig


def feasible_text(row: dict) -> str:
    """``yes``, or ``no: `` and the constraints a comparison row breaks."""
    return "yes" if row.get("feasible", True) else "no: " + ", ".join(row.get("violates") or ["?"])


def _pulley_text(design: Design) -> str:
    if design.pitch_diameter is None:  # the problem's own transmission (a screw and lever): nothing chosen
        from .machine import machine_of

        return f"none (the problem's {machine_of(design.problem).transmission})"
    return (f"{design.pulley_teeth} teeth" if design.pulley_teeth is not None
            else "continuous radius (design.pulley = \"continuous\": no catalogue tooth count)")


def _machine_words(design: Design) -> str:
    from .machine import machine_of

    return machine_of(design.problem).transmission


def _refined(design: Design) -> str:
    """How the mesh grew from the problem's (a limit exceeded between nodes doubles it), or nothing."""
    start = getattr(design.settings, "mesh_intervals", None)
    return f", refined from {start} intervals" if start and design.mesh.intervals != start else ""


def design_text(design: Design, comparison: list[dict] | None = None) -> str:
    """A readable account of a design: choices, objective, moves, checks with margins, active constraints."""
    lines = [f"{design.problem.name}: optimal stroke at {cycle_of(design).rate(design.spm)} "
             f"({period_text(design.stroke.period, design.spm, design)}; {design.status}, "
             f"solved in {design.solve_time_s:.2f} s, mesh {design.mesh.intervals} x degree {design.mesh.degree}"
             f"{_refined(design)})",
             f"objective {design.objective}: {format_value(design.objective_value)} {design.objective_unit}"]
    if design.motor is not None:
        kind = " (stepper)" if getattr(design.motor_spec, "kind", "servo") == "stepper" else ""
        if design.pitch_diameter is None:  # the problem's own transmission: a gearbox, a screw and lever
            tr = design.problem.transmission
            ratio = f" of ratio {tr.ratio:g}" if hasattr(tr, "ratio") else ""
            lines.append(f"motor {design.motor}{kind}; the problem's {_machine_words(design)}{ratio}")
        else:
            lines.append(f"motor {design.motor}{kind}; pulley {_pulley_text(design)}, "
                         f"pitch diameter {design.pitch_diameter * 1e3:.2f} mm")
    lines.append("")
    from .units import is_rotary, load_columns, load_label, with_load_stroke

    rotary = is_rotary(design.problem)  # a sley on its shaft: deg, rad/s, rad/s2 (report/units.py)
    lines.append(format_table([with_load_stroke({**m.to_dict(), "duration_ms": f"{m.duration * 1e3:.3f}"}, rotary)
                               for m in design.moves],
                              load_columns([("index", "move"), ("name", "interval"), ("stroke_mm", "stroke mm"),
                                            ("direction", "direction"),
                                            ("duration_ms", "move time ms"), ("v_max_m_s", "|v| max m/s"),
                                            ("a_max_m_s2", "|a| max m/s2"),
                                            ("jerk_max_m_s3", "|jerk| max m/s3"), ("C_a", "C_a")], rotary)))
    if design.checks:
        lines.append("")
        verified = [c for c in design.checks if "design_term" in c]
        cols = [("name", "check"), ("value", "value"), ("limit", "limit"), ("unit", "unit"), ("margin", "margin"),
                ("ok", "ok")] + ([("design_term", "design term")] if verified else [])
        lines.append(format_table(design.checks, cols,
                                  title=f"checks (fine grid between collocation nodes; margin = 1 - value/limit; ok: "
                                        f"within the limit + check_tolerance "
                                        f"{100 * (design.settings or DesignSettings()).check_tolerance:g} %)"))
        lines += [f"{c['name']}: {format_value(c['value'])} {c['unit']}, the number `strokeopt accuracy --design` prints "
                  f"(sampled position table, largest error over the handover window, plus one encoder count); "
                  + (f"the design term, which the solve constrains (the same simulation at instants over the handover "
                     f"window, the load forces linearised at the design), "
                     f"gives {format_value(c['design_term'])} {c['unit']}" if c["design_term"] is not None else
                     "checked, not held by the solve: a transmission of varying ratio has no linear servo term "
                     "(servo/varying.py simulates its loop in full)") for c in verified]
        limit = next((c for c in design.checks if c["name"] == "peak_torque"), None)
        if limit is not None and design.motor_spec is not None and design.settings is not None:
            lines.append(f"torque limit {format_value(limit['limit'])} N m = "
                         f"{torque_limit_text(design.motor_spec, design.problem.drive.limits)}")
    lines.append("")
    lines.append("active constraints: " + ("; ".join(design.active_constraints) or "none"))
    if comparison:
        cols = [("law", "stroke"), (load_key("a_max_m_s2", rotary), load_label("a_max m/s2", rotary)),
                (load_key("jerk_max_m_s3", rotary), load_label("jerk_max m/s3", rotary))]
        if "peak_torque_N_m" in comparison[0]:
            cols += [(key, head) for key, head in (("peak_torque_N_m", "peak torque N m"),
                                                   ("rms_torque_N_m", "RMS torque N m"),
                                                   ("pull_out_pct", "pull-out %"), ("step_rate_Hz", "step rate Hz"))
                     if key in comparison[0]]
        if any(r.get("vs_optimal_pct") is not None for r in comparison):  # min_time, min_handover_error: none
            cols.append(("vs_optimal_pct", f"{design.objective} vs optimal %"))
        cols.append(("feasible_text", "feasible"))
        lines.append("")
        from .machine import machine_of

        motor = "" if not design.motor else (
            f" with {design.motor}, {_pulley_text(design)}" if design.pitch_diameter is not None
            else f" with {design.motor} on the problem's {machine_of(design.problem).transmission}")
        shown = [{**r, "feasible_text": feasible_text(r)} for r in comparison]
        lines.append(format_table(shown, cols, title=f"comparison with the classic laws{motor}"))
        if any(not r.get("feasible", True) for r in comparison):
            lines.append("laws marked 'no' break the problem's constraints (listed last): a lower value there "
                         "does not beat the optimum")
        beaten = [r for r in comparison[1:] if r.get("feasible", True) and (r.get("vs_optimal_pct") or 0.0) < 0]
        if beaten:
            lines.append(f"{beaten[0]['law']} is {-beaten[0]['vs_optimal_pct']:.3g} % below the optimal stroke and "
                         f"feasible: the collocation mesh resolves the optimum only to about that accuracy (this "
                         f"law may itself be the exact optimum); `strokeopt solve --study mesh` shows the error "
                         f"against the mesh size")
        if comparison[0].get("peak_torque_N_m") is not None and design.checks and any(
                c["name"].startswith("handover accuracy") for c in design.checks):
            lines.append("feasible: rest order, jerk bound and drive checks; the laws' handover accuracy is not "
                         "checked")
    for note in design.notes:
        lines.append(f"note: {note}")
    return "\n".join(lines)


def impact_study_text(report: dict) -> str:
    """The impact study (design/studies.py ``impact_study``): one row per impact-velocity limit."""
    rows = report["rows"]
    free = sorted({k for r in rows for k in r if k.startswith("model.")})
    table = [{**r, "verified": "-" if r.get("verified") is None else ("yes" if r["verified"] else "NO"),
              "why": r.get("reason") or ("" if r.get("verified") is not False else r.get("verdict", ""))} for r in rows]
    cols = [("impact_velocity_max_m_s", "limit m/s"), ("feasible", "feasible"), ("objective_value", "objective"),
            ("peak_torque_N_m", "peak N m"), *[(k, k.split(".")[2] + " " + k.split(".")[3]) for k in free],
            ("simulated_impact_velocity_m_s", "simulated m/s"), ("max_lag_mm", "lag mm"), ("verified", "verified"),
            ("solve_time_s", "solve + verify s"), ("why", "why not")]
    title = (f"{report['problem']} at {report['spm']:g} spm: {report['objective']} under each impact-velocity limit "
             f"(each design re-simulated in its contact model" + (f"; {report['runner']})" if report.get("runner")
                                                                   else ")"))
    return format_table(table, cols, title=title, text=("why",))




def plot_impact_study(rows: list[dict], path=None, objective: str | None = None, title: str = ""):
    """What quietness costs: the objective over the impact-velocity limit; the simulated impact velocity beside it.
    ``title``: the figure's title (problem and stitch rate)."""
    import matplotlib.pyplot as plt  # here: text reports do not import matplotlib

    fig, axes = plt.subplots(1, 2, figsize=(10, 4), constrained_layout=True)
    ok = [r for r in rows if r["feasible"]]
    lim = [r["impact_velocity_max_m_s"] for r in ok]
    axes[0].plot(lim, [r["objective_value"] for r in ok], "o-")
    bad = [r for r in ok if r.get("verified") is False]
    if bad:
        axes[0].plot([r["impact_velocity_max_m_s"] for r in bad], [r["objective_value"] for r in bad], "rx", ms=10,
                     label="verification failed")
        axes[0].legend(fontsize=8)
    for r in rows:
        if not r["feasible"]:
            axes[0].axvline(r["impact_velocity_max_m_s"], color="0.7", ls=":")
    unit = ok[0].get("objective_unit", "") if ok else ""
    quantity = objective_of(objective).quantity
    axes[0].set_ylabel(f"{quantity} [{unit}]" + (f" ({objective})" if objective else ""))
    if title:
        fig.suptitle(title)
    axes[0].set_title("what quietness costs (dotted: infeasible limits)")
    sim = [r for r in ok if r.get("simulated_impact_velocity_m_s") is not None]
    axes[1].plot([r["impact_velocity_max_m_s"] for r in sim], [r["simulated_impact_velocity_m_s"] for r in sim], "o",
                 label="full simulation")
    if lim:
        axes[1].plot([min(lim), max(lim)], [min(lim), max(lim)], "k--", lw=0.8, label="the limit")
    axes[1].set_ylabel("impact velocity [m/s]")
    axes[1].set_title("each design re-simulated (contact model)")
    axes[1].legend(fontsize=8)
    for ax in axes:
        ax.set_xlabel("impact velocity limit [m/s]")
        ax.grid(True, alpha=0.3)
    if path is not None:
        from .figures import fit_titles

        fit_titles(fig)  # no title wider than its axes
        fig.savefig(path, dpi=120)
        plt.close(fig)
    return fig
