"""Drive sizing for people: the text report and the figure of a :class:`~strokeopt.drive.sizing.Sizing`.

Where it sits: after drive/sizing.py, which computes and ranks; ``strokeopt
size`` (cli.py) prints :func:`sizing_text` and writes :func:`plot_sizing`.
"""

from __future__ import annotations

import math

import casadi as ca
import matplotlib.pyplot as plt
import numpy as np

from ..drive.checks import cycle_values, torque_limit
from ..transmissions import transmission_label
from ..io.cycle import cycle_of
from .format import format_table, period_text
from .units import direction_word


def sizing_verdict(sizing) -> str:
    """One line: the best pair, or why none passes (the binding limit of the pair closest to passing)."""
    best = sizing.candidates[0]
    if best.stepper:
        return stepper_verdict(best)
    b = best.check(best.binding)
    unit = "" if b.unit in ("", "-") else f" {b.unit}"   # a ratio has no unit to print
    what = (f"{b.name} {b.value:.4g}{unit} against the limit {b.limit:.4g}{unit} "
            f"(margin {b.margin:.3g})")
    if best.feasible:
        on = f"a {best.pulley.teeth}-tooth pulley" if best.pulley.teeth is not None else f"the {best.pulley.name}"
        return f"ok: {best.motor.name} with {on} ranks first; binding: {what}"
    closest = max(sizing.candidates, key=lambda c: c.check(c.binding).margin)
    c = closest.check(closest.binding)
    counts = {}
    for cand in sizing.candidates:
        for chk in cand.checks:
            if not chk.ok:
                counts[chk.name] = counts.get(chk.name, 0) + 1
    failing = ", ".join(f"{n} ({k} of {len(sizing.candidates)})" for n, k in sorted(counts.items(), key=lambda x: -x[1]))
    belt = closest.pulley.teeth is not None
    parts = "motor and pulley" if belt else "motor"
    which = f"{closest.motor.name} with {closest.pulley.teeth} teeth" if belt else closest.motor.name
    return (f"infeasible: no {parts} passes every check at {sizing.spm:g} spm; binding limit: {c.name} "
            f"({which}, the closest: {c.value:.4g} {c.unit} > limit {c.limit:.4g} {c.unit}); failing checks: {failing}")


def sizing_text(sizing, report: dict, explain: bool = False) -> str:
    """The text report of ``strokeopt size``: inputs, the ranked table, and on request the
    highest stitch rates, the torque breakdown at the peak and the continuous radius.

    ``report`` is ``sizing.to_dict(explain)``, with a ``"continuous_radius"`` list of
    :meth:`~strokeopt.drive.sizing.RadiusOptimum.row` when that was asked for.
    """
    if sizing.candidates[0].stepper:
        return stepper_text(sizing, report, explain)
    with_max_spm = sizing.max_spm_resolution is not None
    inp = report["inputs"]
    if inp.get("load_unit") == "rad":  # a rotary load (report/units.py): inertia, torques, angles
        forces = "; ".join(f"{f['name']} ({f['kind']}, {f['torque_N_m']:g} N m + {f['stiffness_N_m_rad']:g} N m/rad "
                           f"beyond {f['contact_position_deg']:g} deg, pushing "
                           f"towards {direction_word(f['direction'], True)} angles)" for f in inp["load_forces"]) or "none"
        load = f"load: moving inertia {inp['moving_inertia_kg_m2']:g} kg m^2 (rotary, gravity off), load torques: {forces}"
        if "transmission_inertia_kg_m2" in inp:   # a linkage's links carry the load, their gravity its own
            lo, hi = inp["transmission_inertia_kg_m2"]
            geared = (report.get("drive") or {}).get("gearboxes")
            load = (f"load: the transmission's own bodies, {lo:.4g} to {hi:.4g} kg m^2 on "
                    + ("its input shaft (before the gearbox)" if geared else "the motor shaft")
                    + f" over the stroke, with their gravity and loads; added to the output: "
                    f"{inp['moving_inertia_kg_m2']:g} kg m^2, load torques: {forces}")
    else:
        forces = "; ".join(f"{f['name']} ({f['kind']}, {f['force_N']:g} N + {f['stiffness_N_m']:g} N/m "
                           f"beyond {f['contact_position_mm']:g} mm, pushing {f['direction']})"
                           for f in inp["load_forces"]) or "none"
        load = (f"load: moving mass {inp['moving_mass_kg']:g} kg, gravity {inp['gravity_m_s2']:g} m/s^2 along the "
                f"axis, load forces: {forces}")
    lines = [
        f"{report['problem']} at {cycle_of(report).rate(report['spm'])} "
        f"({period_text(report['cycle_time_s'], report['spm'], report)}, "
        f"{inp['law']}, {inp['samples']} samples over the whole cycle)",
        load,
        f"limits: torque limit = min(motor peak, drive peak limit {inp['peak_limit_pct']:g} % x rated torque) "
        f"(column 'limit N m'; overload = peak / rated), inertia ratio <= "
        f"{inp['max_inertia_ratio']:g}; " + (f"belt {inp['belt']} ({inp['belt_cord']} cord, service factor "
                                             f"{inp['belt_service_factor']})" if inp['belt'] is not None
                                             else "no belt checked"),
        ("ranked: feasible first, then the smallest motor (least rated torque), ties by the least RMS torque"
         if inp.get("choose") == "smallest_motor" else "ranked: feasible first, then by overload (peak / rated torque)")
        + "; 'binding' = the check with the least margin\n",
    ]
    if "drive" in report:
        d = report["drive"]
        names = lambda v: ", ".join(map(str, v)) if isinstance(v, list) else v  # noqa: E731
        what = (f"pulleys {names(d['pulley_teeth'])}" if d.get("transmission") is None
                else f"the problem's {d['transmission']}" + (f" through every gearbox of {d['gearboxes']}"
                                                             if d.get("gearboxes") else ""))
        lines.insert(3, f"drive: motors {names(d['motors'])}; {what} (from {d['from']})")
    belt = any(c.pulley.teeth is not None for c in sizing.candidates)  # no z and PD columns without a pulley
    gears = [("gearbox", "gearbox"), ("ratio", "i")] if any("gearbox" in c for c in report["candidates"]) else []
    cols = [("motor", "motor")] + gears + ([("pulley_teeth", "z"), ("pulley_pitch_diameter_mm", "PD mm")] if belt else []) + [
            ("peak_torque_N_m", "peak N m"), ("torque_limit_N_m", "limit N m"), ("rms_torque_N_m", "RMS N m"),
            ("overload_pct", "overload %"),
            ("peak_speed_rpm", "speed rpm"), ("inertia_ratio", "J ratio"), ("feasible", "feasible"),
            ("binding", "binding"), ("margin", "margin")]
    if with_max_spm:
        cols += [("max_spm", "max spm"), ("max_spm_binding", "limited by")]
    lines.append(format_table(report["candidates"], cols))
    if with_max_spm:
        lines.append(f"\nmax spm: bisection per pair to {sizing.max_spm_resolution:g} spm (rounded down); "
                     "'limited by' is the check that fails just above it")
    if explain:
        rows = [{"motor": c.motor.name, "z": c.pulley.teeth, "angle": c.peak_angle_deg, **c.peak_terms}
                for c in sizing.candidates]
        keys = [k for k in rows[0] if k not in ("motor", "z", "angle")]
        lines.append("\nmotor torque at the instant of the peak, by term [N m] (they add up to the total):")
        lines.append(format_table(rows, [("motor", "motor")] + ([("z", "z")] if belt else []) + [("angle", "cam deg")]
                                  + [(k, k) for k in keys]))
        best = sizing.candidates[0]
        lines.append(f"\nchecks of {best.motor.name} with "
                     + (f"z{best.pulley.teeth}:" if best.pulley.teeth is not None else f"the problem's {transmission_label(best.pulley.name)}:"))
        lines.append(format_table([c.as_dict() for c in best.checks], [("name", "check"), ("value", "value"),
                                  ("limit", "limit"), ("unit", "unit"), ("margin", "margin"), ("ok", "ok")]))
    if "continuous_radius" in report:
        lines.append("\ncontinuous pulley radius minimising the peak torque "
                     "(pulley inertia from the catalogue's model):")
        lines.append(format_table(report["continuous_radius"], [
            ("motor", "motor"), ("pitch_radius_mm", "radius mm"), ("pitch_diameter_mm", "PD mm"),
            ("teeth_equivalent", "teeth (not rounded)"), ("peak_torque_N_m", "peak N m")]))
    lines.append(f"\n{report['verdict']}" if "verdict" in report else "")
    return "\n".join(lines).rstrip()


def draw_torque_speed(ax, motor, omega, torque, t, limits, title: str) -> None:
    """The cycle's torque-speed path (``omega`` [rad/s], ``torque`` [N m] over times ``t``) with its
    peak and RMS operating points, over the motor's peak and rated (continuous) curves and the
    torque limit every check uses (:func:`~strokeopt.drive.checks.torque_limit` of ``limits``); a stepper's
    picture is its demand over its pull-out curve (:func:`draw_pull_out`)."""
    if getattr(motor, "kind", "servo") == "stepper":
        return draw_pull_out(ax, motor, omega, torque, limits, title)
    rpm = 60 / (2 * math.pi)
    m = motor
    w = np.linspace(-m.rated_speed, m.rated_speed, 101)
    drive_peak = torque_limit(m, limits)
    for sign in (1, -1):
        ax.plot(w * rpm, sign * m.continuous_torque(w), color="tab:green",
                label="motor rated (continuous)" if sign > 0 else None)
        ax.plot(w * rpm, sign * m.peak_envelope(w), color="tab:red", label="motor peak" if sign > 0 else None)
        ax.plot(w * rpm, sign * np.full_like(w, drive_peak), color="tab:red", ls=":",
                label=f"torque limit {drive_peak:.2f} N m (min of peak, {limits.peak_limit_pct:g} % rated)"
                if sign > 0 else None)
    for x in (-m.rated_speed * rpm, m.rated_speed * rpm):  # the peak_speed check's limit: named in the legend
        ax.axvline(x, color="0.5", lw=0.8, ls="--",
                   label=f"\u00b1rated speed {m.rated_speed * rpm:.0f} rpm (peak speed limit)" if x > 0 else None)
    mark_operating_points(ax, omega, torque, t, "tab:blue", "cycle")
    ax.set_xlabel("motor speed [rpm]")
    ax.set_ylabel("motor torque [N m]")
    ax.set_title(title)
    ax.grid(True, alpha=0.3)
    # below the axes: inside, the legend lies on the curves it names
    from .figures import legend_outside

    legend_outside(ax, where="below", ncol=2)


def mark_operating_points(ax, omega, torque, t, color, name: str) -> None:
    """One design's torque-speed path (``omega`` [rad/s], ``torque`` [N m] over times ``t``) in ``color``,
    its peak (circle) and RMS (diamond: the RMS torque of the sizing check at the RMS speed) marked and
    named with their values."""
    rpm = 60 / (2 * math.pi)
    omega, torque, t = np.asarray(omega, float), np.asarray(torque, float), np.asarray(t, float)
    ax.plot(omega * rpm, torque, color=color, lw=1.2, label=name)
    i = int(np.argmax(np.abs(torque)))
    ax.plot(omega[i] * rpm, torque[i], "o", color=color, ms=7, mec="k", mew=0.5,
            label=f"peak {torque[i]:.3f} N m at {omega[i] * rpm:.0f} rpm")
    (_, rms_torque), (_, rms_speed) = (cycle_values(y, omega, omega, t)[:2] for y in (torque, omega))
    ax.plot(rms_speed * rpm, rms_torque, "D", color=color, ms=6, mec="k", mew=0.5,
            label=f"RMS {rms_torque:.3f} N m at {rms_speed * rpm:.0f} rpm (RMS speed)")


def torque_angle_axis(ax, title: str, fontsize: float = 8) -> None:
    """An axis of motor torque over the cam angle (one cycle, 45 deg ticks), its legend (beside the data) and
    title."""
    from .figures import legend_outside

    ax.set_xlabel("cam angle [deg]")
    ax.set_ylabel("motor torque [N m]")
    ax.set_xlim(0, 360)
    ax.set_xticks(np.arange(0, 361, 45))
    ax.grid(True, alpha=0.3)
    legend_outside(ax, fontsize=fontsize)
    ax.set_title(title)


def draw_torque_terms(ax, angle, terms, title: str) -> None:
    """The motor torque over the cam angle, its total and every term that is not zero (TorqueTerms)."""
    ax.plot(angle, terms.total, color="k", lw=1.5, label="total")
    for name, val in terms.as_dict().items():
        val = np.broadcast_to(val, angle.shape)
        if np.max(np.abs(val)) > 1e-9:
            ax.plot(angle, val, lw=0.9, label=name, ls="--" if name == "rotor_inertia" else "-")
    torque_angle_axis(ax, title)


def plot_sizing(sizing, candidate=None, path=None):
    """The classic sizing picture for ``candidate`` (default: the best ranked):
    the cycle's torque-speed trajectory over the motor's continuous and peak
    envelopes and the drive's peak limit, and the torque terms over the cam angle.
    ``sizing`` is a :class:`~strokeopt.drive.sizing.Sizing`."""
    c = candidate or sizing.candidates[0]
    terms = sizing.torque_curve(c)
    fig, (ax1, ax2) = plt.subplots(1, 2, figsize=(12, 4.8), constrained_layout=True)
    m = c.motor
    if c.stepper:
        draw_pull_out(ax1, m, terms.omega, terms.total, sizing.limits,
                      f"{m.name}, {c.pulley.name}, {sizing.spm:g} spm, {sizing.inputs['law']}")
    else:
        on = f"pulley z{c.pulley.teeth}" if c.pulley.teeth is not None else transmission_label(c.pulley.name)
        draw_torque_speed(ax1, m, terms.omega, terms.total, sizing.kinematics.t, sizing.limits,
                          f"{m.name}, {on}, {sizing.spm:g} spm, {sizing.inputs['law']}")
    draw_torque_terms(ax2, 360.0 * sizing.kinematics.t / sizing.period, terms,
                      f"torque over the cycle (binding: {c.binding})")
    if path is not None:
        from .figures import fit_titles

        fit_titles(fig)  # no title wider than its axes
        fig.savefig(path, dpi=110)
        plt.close(fig)
    return fig


def stepper_verdict(c) -> str:
    """The answer to "is the stepper at its limit?": the least pull-out reserve, where, and the binding check."""
    po, w = c.check("pull_out_torque"), c.worst
    where = (f"{w['worst_torque_N_m']:.3g} N m demanded at {w['worst_step_rate_Hz']:.0f} Hz where the pull-out "
             f"torque is {w['worst_pull_out_N_m']:.3g} N m ({po.value:.0f} % of it; allowed {po.limit:.0f} % with "
             f"safety factor {100 / po.limit:g})")
    b = c.check(c.binding)
    binding = f"binding: {b.name} {b.value:.4g} {b.unit} against {b.limit:.4g} {b.unit} (margin {b.margin:.3g})"
    if c.feasible:
        state = "ok, with reserve" if b.margin > 0.2 else "ok, at its limit"
        return f"{state}: {c.motor.name} on the {c.pulley.name}: {where}; {binding}"
    over = "beyond its pull-out curve (it loses steps)" if po.value > 100 else "inside its pull-out curve " \
        "but without the safety factor's reserve"
    return f"infeasible: {c.motor.name} on the {c.pulley.name} is {over}: {where}; {binding}"


def stepper_text(sizing, report: dict, explain: bool = False) -> str:
    """``strokeopt size`` for steppers: the demand against the pull-out curve, the step rate, the inertia ratio."""
    inp = report["inputs"]
    c0 = sizing.candidates[0]
    units = {name: "kg" if unit == "m" else "kg m^2" for name, _, unit in
             c0.pulley.transmission().stages(ca.SX.sym("phi"))}
    lines = [
        f"{report['problem']} at {cycle_of(report).rate(report['spm'])} "
        f"({period_text(report['cycle_time_s'], report['spm'], report)}, "
        f"{inp['law']}, {inp['samples']} samples over the whole cycle)",
        f"load: {inp.get('moving_mass_kg', inp.get('moving_inertia_kg_m2')):g} kg at the load, gravity {inp['gravity_m_s2']:g} m/s^2; members: "
        + ("; ".join(f"{m.name} ({m.inertia:g} {units[m.stage]} on the {m.stage})" for m in sizing.load.members)
           or "none"),
        f"checks: torque demand T = J(phi) phi'' + 1/2 J'(phi) phi'^2 + loads under the pull-out curve / "
        f"{sizing.limits.pull_out_safety_factor:g} at every speed; step rate under the curve's last; inertia "
        f"ratio <= {sizing.limits.max_inertia_ratio:g}",
        f"motor data: {c0.motor.model} ({c0.motor.source or 'no source'}{': ' + c0.motor.note if c0.motor.note else ''})\n",
    ]
    cols = [("motor", "motor"), ("peak_torque_N_m", "peak N m"), ("pull_out_pct", "% of pull-out"),
            ("pull_out_limit_pct", "allowed %"), ("worst_step_rate_Hz", "at Hz"), ("step_rate_Hz", "step rate Hz"),
            ("max_step_rate_Hz", "max Hz"), ("inertia_ratio", "J ratio"), ("feasible", "feasible"),
            ("binding", "binding"), ("margin", "margin")]
    if sizing.max_spm_resolution is not None:
        cols += [("max_spm", "max spm"), ("max_spm_binding", "limited by")]
    lines.append(format_table(report["candidates"], cols))
    if sizing.max_spm_resolution is not None and c0.max_spm is not None:
        scale = sizing.spm / c0.max_spm  # every interval's time scales with the cycle
        lines.append(f"\nmax spm: bisection to {sizing.max_spm_resolution:g} spm (rounded down); at {c0.max_spm:g} spm every "
                     f"interval takes {scale:.3g} x its time at {sizing.spm:g} spm")
    if explain:
        for c in sizing.candidates:
            lines.append(f"\nmotor torque of {c.motor.name} at its peak ({c.peak_angle_deg:.1f} deg), by term [N m]:")
            lines.append(format_table([c.peak_terms], [(k, k) for k in c.peak_terms]))
            lines.append(format_table([x.as_dict() for x in c.checks], [("name", "check"), ("value", "value"),
                                      ("limit", "limit"), ("unit", "unit"), ("margin", "margin"), ("ok", "ok")]))
    lines.append(f"\n{report['verdict']}" if "verdict" in report else "")
    return "\n".join(lines).rstrip()


def draw_pull_out(ax, motor, omega, torque, limits, title: str) -> None:
    """A stepper's torque-speed picture: the demand's path (|speed| in step rate, |torque|) over the
    pull-out curve and the curve divided by the safety factor; the point of least reserve marked."""
    rate = np.abs(np.asarray(omega, float)) / motor.step_angle
    torque = np.abs(np.asarray(torque, float))
    table = np.asarray(motor.pull_out_speed) / motor.step_angle
    ax.plot(table, motor.pull_out_torque, "o-", color="tab:red", ms=3, label=f"pull-out ({motor.source or 'data'})")
    ax.plot(table, np.asarray(motor.pull_out_torque) / limits.pull_out_safety_factor, ":", color="tab:red",
            label=f"pull-out / {limits.pull_out_safety_factor:g} (the check)")
    ax.axvline(table[-1], color="0.5", lw=0.8, ls="--", label=f"max step rate {table[-1]:.0f} Hz")
    ax.plot(rate, torque, color="tab:blue", lw=1.2, label="demand over the cycle")
    from ..drive.checks import pull_out_ratio

    ratio = pull_out_ratio(torque, omega, motor)
    i = int(np.argmax(ratio))
    ax.plot(rate[i], torque[i], "o", color="tab:blue", ms=7,
            label=f"least reserve: demand {torque[i]:.3f} N m at {rate[i]:.0f} Hz, "
                  + (f"{100 * ratio[i]:.0f} % of pull-out" if np.isfinite(ratio[i]) else "beyond the pull-out table"))
    ax.set_xlabel("step rate [Hz] (|motor speed| / step angle)")
    ax.set_ylabel("|motor torque| [N m]")
    ax.set_title(title, fontsize=10)
    ax.grid(True, alpha=0.3)
    from .figures import legend_outside

    legend_outside(ax, where="below", ncol=2)
