"""The servo's reports: the text and figure of ``strokeopt accuracy`` and of ``strokeopt tradeoff``.

The servo package computes (:func:`strokeopt.servo.accuracy.accuracy_report`,
:func:`strokeopt.studies.tradeoff.tradeoff`); this module writes its reports as
text tables and draws its figures.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ..io.load_units import error_unit
from ..servo.accuracy import AccuracyResult
from .figures import frame_label
from ..io.cycle import cycle_of
from .format import drive_text, format_table, format_value
from ..transmissions import transmission_label


# --------------------------------------------------------------------------- strokeopt accuracy


def _axis_lines(report: dict) -> list[str]:
    """The drive's mechanics in the report's words: a belt's pulley and stiffness, a gearbox's ratio and torsion, or a
    rigid transmission's varying ratio and inertia."""
    if report.get("compliance") == "rigid":
        u = report.get("position_unit", "mm")
        lo, hi = report["inertia_range_kg_m2"]
        return [f"{report['problem']} at {cycle_of(report).rate(report['spm'])}, {report['label']}: motor {report['motor']}, "
                f"{transmission_label(report['transmission'])} (rigid), ratio at the handover "
                f"{report[f'handover_ratio_{u}_per_rad']:.4g} {u}/rad",
                f"inertia on the motor shaft {lo:.4g} to {hi:.4g} kg m^2 over the stroke (rotor, transmission, load): "
                "the loop simulated with the drive's own nonlinear dynamics"]
    if report.get("position_unit") == "deg":
        return [f"{report['problem']} at {cycle_of(report).rate(report['spm'])}, {report['label']}: motor {report['motor']}, "
                f"{report['compliance']} ratio {report['ratio']:g}, load inertia {report['load_inertia_kg_m2']:g} kg m^2",
                f"{report['compliance']} {report['torsional_stiffness_N_m_arcmin']:g} N m/arcmin at the load "
                f"({report['stiffness_source']}), torsional mode {report['resonance_Hz']:.0f} Hz"]
    return [f"{report['problem']} at {cycle_of(report).rate(report['spm'])}, {report['label']}: motor {report['motor']}, "
            f"pulley PD {report['pulley_pitch_diameter_mm']:.2f} mm, moving mass {report['moving_mass_kg']:g} kg",
            f"belt {report['belt_stiffness_N_per_mm']:.0f} N/mm at the carrier ({report['belt_stiffness_source']}), "
            f"belt mode {report['belt_resonance_Hz']:.0f} Hz"]


def accuracy_text(report: dict) -> str:
    """The text of ``strokeopt accuracy`` from the report of :func:`~strokeopt.servo.accuracy.accuracy_report`."""
    g = report["gains"]
    u = report.get("position_unit", "mm")
    c = report[f"contributions_{u}"]
    sc = report[f"signed_contributions_{u}"]
    rotary = u == "deg"
    rigid = report.get("compliance") == "rigid"   # a crank, a linkage: no elastic element (servo/varying.py)
    stretch = "gearbox wind-up" if rotary else "belt stretch"
    stretch_key = "max_stretch_deg" if rotary else "max_belt_stretch_mm"
    lines = []
    used = report.get("drive")
    if used:
        lines.append(drive_text(used))
    if used and used["from"].startswith("the design file") and report.get("compliance") == "rigid":
        lines.append("  note: a transmission of varying ratio has no linear design term: the solve checks the design "
                     "by this simulation (the design does not hold it while it optimises)")
    elif used and used["from"].startswith("the design file"):
        # The design's handover term is this simulation's error as a linear functional of the stroke (the
        # sampled table, the window's instants, the load forces linearised about the solve's start: servo/
        # table_term.py); here the loop is simulated in full, so the two agree to the linearisation's error.
        lines.append("  note: the design's handover term is this simulation's error, linear in the stroke (the load "
                     "forces linearised about the solve's start); below is the full simulation of the loop")
    lines += [
        *_axis_lines(report),
        f"servo loop: Kp {g['position_gain_1_s']:.1f} 1/s, Kv {g['speed_gain_N_m_s_rad']:.4g} N m s/rad, "
        f"Ti {g['speed_integral_time_ms']:.2f} ms, speed bandwidth {g['speed_bandwidth_Hz']:.1f} Hz; "
        f"loop delay {report['loop_delay_us']:.0f} us; feed-forward velocity "
        f"{'on' if report['velocity_feedforward'] else 'off'}, acceleration "
        f"{'on' if report['acceleration_feedforward'] else 'off'}",
        f"  tuning: {g['tuning']}",
        f"  margins: gain {report['margins']['gain_margin']:.2f}, phase {report['margins']['phase_margin_deg']:.1f} deg, "
        f"modulus {report['margins']['modulus_margin']:.2f}",
        "",
        f"handover error (largest over {report['handover_window_deg']:g} deg after the end of the handover move at "
        f"{report['handover_angle_deg']:.1f} deg): {format_value(report[f'handover_error_{u}'])} {u} "
        f"(requirement {report[f'requirement_{u}']:g} {u})",
        f"  servo tracking        {sc['servo_tracking']:+.4f} {u}  ({'motor' if rotary or rigid else 'pulley'} {report['pulley_error_at_handover_deg']:.3f} deg)",
        *([] if rigid else [f"  {stretch:20s}  {sc['belt_stretch']:+.4f} {u}  (inertia {sc['belt_stretch_inertia']:+.4f}, "
                            f"forces {sc['belt_stretch_forces']:+.4f})"]),
        f"  encoder quantisation  {c['encoder_quantisation']:.4f} {u}  (one count, added as a bound)",
        f"over the cycle: max error {report[f'max_error_{u}']:.4f} {u}, max servo error "
        f"{report[f'max_servo_error_{u}']:.4f} {u}"
        + ("" if rigid else f", max {stretch} {report[stretch_key]:.4f} {u}; "
           + (f"residual {report['compliance']} vibration in the dwell after the handover "
              f"{report[f'residual_vibration_{u}']:.4f} {u}" if report.get("dwell_after_handover", True) else
              "no dwell follows the handover move (no residual vibration to judge)")),
        f"peak torque command {report['peak_torque_command_N_m']:.3f} N m (torque limit "
        f"{format_value(report['torque_limit_N_m'])} N m = {report.get('torque_limit_basis', 'min(motor peak, drive peak limit x rated)')})",
        f"  {report['torque_basis']}",
    ]
    if report["torque_limited"]:
        lines.append("WARNING: the torque command exceeds the limit: the drive saturates and the linear prediction "
                     "above does not hold")
    if "laws" in report:
        lines += ["", format_table(report["laws"], [
            ("law", "law"), (f"handover_error_{u}", f"handover {u}"),
            *([] if rigid else [(f"residual_vibration_{u}", f"residual {report['compliance']} vib. {u}")]),
            (f"max_error_{u}", f"max error {u}"),
            *([] if rigid else [(stretch_key, f"max {'wind-up' if rotary else 'belt'} {u}")]),
            ("peak_torque_command_N_m", "peak torque N m"), ("torque_limited", "saturates")],
            title=f"Motion laws at {cycle_of(report).rate(report['spm'])} on the same drive")]
    if "verdict" in report:
        lines += ["", report["verdict"]]
    return "\n".join(lines)


def plot_accuracy(result: AccuracyResult, path: str | Path | None = None, motor: str | None = None,
                  output: str = "bar", cycle=None):
    """Commanded vs. actual position of the ``output`` (problem frame), and the error and its parts over the
    cam angle; ``cycle``: the machine's cycle (a problem, or its :class:`~strokeopt.io.cycle.MachineCycle`) that
    names the rate (default: stitches)."""
    import matplotlib.pyplot as plt

    from .figures import PRINT_WIDTH_IN, legend_outside

    fig, axes = plt.subplots(2, 1, sharex=True, figsize=(PRINT_WIDTH_IN, 6.2), constrained_layout=True)
    axis = result.loop.axis
    scale, u = error_unit(axis.rotary)
    fmt = ".4f" if axis.rotary else ".3f"
    ang = result.angle_deg
    ax = axes[0]
    ax.plot(ang, result.s_cmd * scale, lw=1.4, label="commanded")
    ax.plot(ang, result.x * scale, lw=1.0, ls="--", label=f"actual ({output})")
    ax.set_ylabel(frame_label(f"{output} position", u, axis.rotary))
    ax = axes[1]
    ax.plot(ang, result.error * scale, lw=1.4, color="k", label=f"{output} error")
    ax.plot(ang, result.servo * scale, lw=1.0, label="servo tracking")
    if axis.compliance != "rigid":   # a rigid drive (a crank, a linkage) has no stretch: its error is the servo's
        ax.plot(ang, result.belt * scale, lw=1.0, label="gearbox wind-up" if axis.rotary else "belt stretch")
    ax.set_ylabel(f"error [{u}]\n(commanded - actual)")
    h_ang = 360.0 * (result.handover_time - result.loop.settings.sum_small_time_constants) / result.period
    for a in axes:
        a.axvline(h_ang, color="tab:red", ls="--", lw=1)
        over = h_ang + result.loop.settings.handover_window - 360.0
        if over > 0:  # a window past the cycle's end continues at its start
            a.axvspan(0.0, over, color="tab:red", alpha=0.08, lw=0)
        a.axvspan(h_ang, h_ang + result.loop.settings.handover_window, color="tab:red", alpha=0.08, lw=0,
                  label=f"handover window, error {result.handover_error * scale:{fmt}} {u}" if a is axes[1] else "handover")
        a.grid(True, alpha=0.3)
        legend_outside(a)
    axes[1].set_xlabel("cam angle [deg] (360 deg = one cam cycle)")
    axes[1].set_xlim(0, 360)
    axes[1].set_xticks(np.arange(0, 361, 45))
    on = f" on {motor}" if motor else ""
    axes[0].set_title(f"{result.label}{on} at {cycle_of(cycle).rate(result.spm)}: handover error {result.handover_error * scale:{fmt}} {u}")
    if path is not None:
        from .figures import fit_titles

        fit_titles(fig)  # no title wider than its axes
        fig.savefig(path, dpi=120)
        plt.close(fig)
    return fig


# --------------------------------------------------------------------------- strokeopt tradeoff


def tradeoff_text(report: dict) -> str:
    """The text of ``strokeopt tradeoff`` from the report of :func:`~strokeopt.studies.tradeoff.tradeoff`."""
    kinds = {p["stroke"] for p in report["points"]}
    classic = f"classic law {report['law']}; " if kinds - {"optimal"} else ""
    tolerance = report.get("check_tolerance_pct")
    within = "" if tolerance is None or "optimal" not in kinds else (
        f" (the optimal stroke's within the design's check tolerance, {tolerance:g} %: between the instants the "
        "design holds, the error may peak that much higher)")
    head = (f"{report['problem']}: highest stitch rate for a required handover accuracy "
            f"(motor {report['motor']}, {report['pulley_teeth']}-tooth pulley; {classic}"
            f"rates to {report['resolution_spm']:g} spm)\n{report['torque_basis']}\n"
            f"confirmed: the full servo simulation meets the accuracy there{within} with the torque command within "
            "its limit; rejected: the rate above that failed (its error where it was simulated; '-': no higher rate "
            "was tried); without a rate: the lowest rate tried, for the optimal stroke the problem's own rate with "
            "its most accurate stroke\n"
            "binding limit: torque_limit = the servo's torque command (the optimal stroke's design keeps a reserve "
            "of its torque limit for it), peak_torque / rms_torque = the design's rigid-load checks, "
            "handover_accuracy = the simulated error (for the optimal stroke: the design's error term)")
    meaning = ([] if kinds <= {"optimal"} else ["the classic law meets the accuracy there and at every lower rate"]) + (
        ["the optimal stroke's design is for the confirmed rate (a lower rate needs its own solve: the error rises "
         "and falls with the rate)"] if "optimal" in kinds else [])
    head += "\nmax spm: the confirmed rate rounded down to the resolution; " + "; ".join(meaning)
    columns = [("accuracy_mm", "accuracy mm"), ("stroke", "stroke"), ("max_spm", "max spm"), ("binding", "binding limit"),
               ("confirmed_spm", "confirmed at spm"), ("handover_error_mm", "error there mm"),
               ("failed_spm", "rejected at spm"), ("failed_error_mm", "error at rejected mm")]
    points = report["points"]
    starts = report.get("starts", 1)
    if starts > 1:  # the optimal stroke from several start rates: how many reached the answer, what each found
        rates = ", ".join(f"{r:.1f}" for r in report.get("start_rates_spm", []))
        head += (f"\nstarts: each accuracy of the optimal stroke solved from {starts} start rates over one period of "
                 f"the belt mode's phase ({rates} spm); 'starts at best': how many confirmed the answer's rate, "
                 "'confirmed per start': the rate each start confirmed, on the grid ('-': none; '0 of K' at best: the "
                 "answer came from the next looser accuracy's design)")
        points = [{**p, "starts at best": "" if "starts" not in p else f"{p['starts_at_best']} of {p['starts']}",
                   "per start": " ".join("-" if r is None else f"{r:g}" for r in p.get("start_max_spm", []))}
                  for p in points]
        columns += [("starts at best", "starts at best"), ("per start", "confirmed per start")]
    ran = f"\nran on: {report['runner']}" if report.get("runner") else ""   # and any worker lost on the way
    return head + ran + "\n\n" + format_table(points, columns)


def _words(name: str) -> str:
    """An identifier as words for a figure: 'handover_accuracy' -> 'handover accuracy'."""
    return str(name).replace("_", " ")


def plot_tradeoff(report: dict, path: str | Path | None = None):
    """Highest stitch rate over the required handover accuracy, one line per stroke: each point the rate the full
    simulation confirmed, labelled with the limit that binds there and the error the simulation found; a hollow
    marker above it the rate the simulation rejected."""
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(8, 5), constrained_layout=True)
    markers = {"handover_accuracy": "o", "torque_limit": "s", "peak_torque": "s", "overload": "s",
               "rms_torque": "D", "peak_speed": "^", "sampling": "v"}
    colours = plt.rcParams["axes.prop_cycle"].by_key()["color"]
    kinds = list(dict.fromkeys(p["stroke"] for p in report["points"]))
    bindings: dict = {}  # the marker of every binding limit drawn (the legend explains them)
    for colour, kind in zip(colours, kinds):
        pts = [p for p in report["points"] if p["stroke"] == kind and p["max_spm"] is not None]
        none = [p["accuracy_mm"] for p in report["points"] if p["stroke"] == kind and p["max_spm"] is None]
        if pts:
            ax.plot([p["accuracy_mm"] for p in pts], [p["max_spm"] for p in pts], lw=1.4, color=colour,
                    label=_words(kind))
        if none:  # accuracies without a rate: a cross at the bottom, a row per stroke, named in the legend
            ax.plot(none, [0.03 + 0.045 * kinds.index(kind)] * len(none), "x", color=colour, ms=7, mew=1.6,
                    transform=ax.get_xaxis_transform(),
                    label=f"{_words(kind)}: no rate at {', '.join(f'{a:g}' for a in none)} mm (crosses at the bottom)")
        if not pts:
            continue
        x = [p["accuracy_mm"] for p in pts]
        right = max(x)
        # the rate above each point that the full simulation rejected: a hollow marker joined to the point
        failed = [p for p in pts if p.get("failed_spm") is not None]
        for p in failed:
            ax.plot([p["accuracy_mm"]] * 2, [p["max_spm"], p["failed_spm"]], lw=0.8, color=colour, alpha=0.6)
        if failed:
            ax.plot([p["accuracy_mm"] for p in failed], [p["failed_spm"] for p in failed], "v", mfc="none",
                    color=colour, label=f"{_words(kind)}: the rate above, rejected by the simulation")
        said = None  # a label only where the rate or the binding limit changes (looser accuracies repeat them)
        for p in pts:
            marker = markers.get(p["binding"], "x")
            bindings.setdefault(marker, []).append(_words(p["binding"]))
            ax.plot(p["accuracy_mm"], p["max_spm"], marker, color=colour)
            if said == (p["max_spm"], p["binding"]):
                continue
            above = said is not None and said[0] == p["max_spm"]  # beside a label at the same rate: above the line
            said = (p["max_spm"], p["binding"])
            last = p["accuracy_mm"] == right  # the rightmost label goes to the left of its point, inside the axes
            error = "" if p.get("handover_error_mm") is None else f", error {p['handover_error_mm']:.3g} mm"
            reached = "" if "starts" not in p else f", {p['starts_at_best']} of {p['starts']} starts"
            ax.annotate(_words(p["binding"]) + error + reached, (p["accuracy_mm"], p["max_spm"]),
                        xytext=(-4 if last else 4, 5 if above else -10),
                        textcoords="offset points", fontsize=7, color=colour, ha="right" if last else "left")
    for marker, names in bindings.items():  # what each marker's binding limit is (grey: any stroke)
        ax.plot([], [], marker, color="0.45", label="binds: " + " / ".join(dict.fromkeys(names)))
    from matplotlib.ticker import FixedLocator, FuncFormatter, NullFormatter

    ax.set_xscale("log")
    # ticks at the requested accuracies, as plain decimals (0.05, 0.1, 0.2), not 6e-2 / 2e-1; every one in view,
    # those without a rate too
    asked = sorted({p["accuracy_mm"] for p in report["points"]})
    ax.xaxis.set_major_locator(FixedLocator(asked))
    ax.xaxis.set_major_formatter(FuncFormatter(lambda v, _: f"{v:g}"))
    ax.xaxis.set_minor_formatter(NullFormatter())
    span = (asked[-1] / asked[0]) ** 0.06 if asked[-1] > asked[0] else 1.5
    ax.set_xlim(asked[0] / span, asked[-1] * span)
    ax.set_xlabel("required handover accuracy [mm]")
    ax.set_ylabel("highest stitch rate [spm]")
    classic = any(p["stroke"] != "optimal" for p in report["points"])
    drive = [f"classic law {report['law']}" if report.get("law") and classic else "",
             f"motor {report['motor']}, {report['pulley_teeth']}-tooth pulley" if report.get("motor") else ""]
    ax.set_title(f"{report['problem']}: what accuracy costs in stitch rate"
                 + (f"\n({'; '.join(d for d in drive if d)})" if any(drive) else ""), fontsize=10)
    ax.grid(True, which="both", alpha=0.3)
    fig.legend(loc="outside lower center", ncols=2, fontsize=8)  # below the axes: clear of every point and label
    if path is not None:
        from .figures import fit_titles

        fit_titles(fig)  # no title wider than its axes
        fig.savefig(path, dpi=120)
        plt.close(fig)
    return fig
