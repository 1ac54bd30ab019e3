"""The design report's handover-accuracy section: the full servo simulation's error by cause, its requirement,
the elastic mode (a belt's, or a gearbox's torsion) and the figure, in the load's units (mm, or deg for a
rotary load)."""

from __future__ import annotations

from ..drive.checks import within_limit
from ..io.load_units import error_unit
from . import html as h


def section_accuracy(d) -> str:
    """The section of ``d`` (:class:`~strokeopt.report.design_report.ReportData`)."""
    if d.accuracy is None:
        return h.para("Not predicted: the problem has no [servo] section (servo loop and its drive's elastic mode) "
                      "or no motor.")
    from .servo import plot_accuracy

    a = d.accuracy.summary()
    u = a["position_unit"]
    rotary = u == "deg"
    stretch = "gearbox wind-up" if rotary else "belt stretch"
    c, sc = a[f"contributions_{u}"], a[f"signed_contributions_{u}"]
    rigid = a["compliance"] == "rigid"   # a crank, a linkage: no elastic element, all of it servo tracking
    rows = [[h.cell("servo tracking"), h.cell(sc["servo_tracking"], f"accuracy.signed_contributions_{u}.servo_tracking")],
            *([] if rigid else [
                [h.cell(stretch), h.cell(sc["belt_stretch"], f"accuracy.signed_contributions_{u}.belt_stretch")],
                [h.cell(f"  of it: {d.machine.output} inertia"), h.cell(sc["belt_stretch_inertia"])],
                [h.cell("  of it: load forces"), h.cell(sc["belt_stretch_forces"])]]),
            [h.cell("encoder (one count, a bound)"),
             h.cell(c["encoder_quantisation"], f"accuracy.contributions_{u}.encoder_quantisation")],
            [h.cell(f"handover error (largest over {a['handover_window_deg']:g} deg after the handover)"),
             h.cell(a[f"handover_error_{u}"], f"accuracy.handover_error_{u}")]]
    limit = d.problem.design.accuracy * error_unit(rotary)[0] if d.problem.design is not None else None
    out = h.table(["contribution", u], rows)
    if rigid:
        lo, hi = a["inertia_range_kg_m2"]
        mode = (f"A rigid drive (its ratio varies: its own nonlinear dynamics simulated), inertia on the motor shaft "
                f"{lo:.4g} to {hi:.4g} kg m^2 over the stroke")
    else:
        mode = (f"{'Torsional' if rotary else 'Belt'} mode {a['resonance_Hz'] if rotary else a['belt_resonance_Hz']:.0f} "
                f"Hz; residual {a['compliance']} vibration in the dwell {a[f'residual_vibration_{u}']:.4f} {u}")
    if limit is not None:
        tol = d.problem.design.check_tolerance  # the solve's pass rule (drive.checks.within_limit)
        out += h.para(f"Requirement {limit:g} {u}: " + ("met" if within_limit(a[f"handover_error_{u}"], limit, tol)
                                                        else "NOT met")
                      + f" (full servo simulation: sampled position table, worst of its phases). "
                      f"{mode}; peak torque command {a['peak_torque_command_N_m']:.3f} N m"
                      + (f", ABOVE the torque limit {a['torque_limit_N_m']:.3f} N m: the drive saturates and the "
                         "prediction does not hold." if a["torque_limited"] else "."))
    out += h.svg_figure(plot_accuracy(d.accuracy, None, d.design.motor, output=d.machine.output, cycle=d.problem),
                        f"Commanded and actual position of the {d.machine.output}, and the error"
                        + ("" if rigid else f" with its servo and {stretch} parts")
                        + f" over the whole cycle; the handover window ({a['handover_window_deg']:g} deg) "
                        f"shaded: handover error {a[f'handover_error_{u}']:.4f} {u}.")
    return out
