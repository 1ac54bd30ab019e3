"""A crank-driven linkage against a servo driving its output member directly (issue 24 item 5): the loom's
six-bar beat-up (problems/loom_beatup_sixbar.toml) against its sley on a servo motor through a gearbox with
an optimal stroke of the same swing, a true rear dwell and the beat-up at 0 deg
(problems/loom_beatup_servo.toml).

:func:`compare_linkage_servo` solves the servo problem with every gearbox of a catalogue
(``drive/data/gearboxes.toml``: ratio, output torques, inertia) and every motor the problem's catalogues
add (``[drive] catalogues``), keeps the pairs whose motor and gearbox carry the cycle, and picks the
smallest motor (least rated torque), then the least RMS torque. A pair whose motor cannot even hold the
load torque that no motion avoids (the static beat-up torque at the front, over the ratio) is dropped
before any NLP, with that reason. The linkage's numbers are its crank torque at constant crank speed
(power balance, linkage/dynamics.py): the crank is driven by the loom's main shaft and flywheel, which
evens out its peaks; a servo motor must deliver and absorb every peak itself.

:func:`hybrid_crank_speed` keeps the linkage and drives its crank by a servo at non-uniform speed (no
flywheel), designed in crank coordinates: the least peak crank torque for a rear dwell at least as long,
or the longest rear dwell for a peak crank torque.

The caller loads the files (files/ is a floor above); the table and figure are :meth:`LinkageServo.table`
and :func:`plot_linkage_servo`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ..design.solve import solve_design
from ..design.torque import design_torque
# the gearbox catalogue lives in drive/gearboxes.py; its names stay importable from here (notebook 07)
from ..drive.gearboxes import (KG_CM2, GearboxEntry, choose_smallest, gearbox_catalogue_file,  # noqa: F401
                               load_gearboxes)
from ..drive.catalogue import own_motors
from ..errors import ProblemError, SolverError
from ..linkage.dynamics import analyse_dynamics
from ..linkage.kinematics import kinematics_of
from ..linkage.summary import near_dwells


@dataclass
class LinkageSide:
    """The linkage at constant crank speed over one turn (crank angle from the beat-up)."""

    crank_deg: np.ndarray
    sley_deg: np.ndarray        # the output angle from its front extreme [deg]
    sley_accel: np.ndarray      # [rad/s^2]
    torque: np.ndarray          # crank torque [N m]
    omega: float                # crank speed [rad/s]
    swing_deg: float
    rear_dwell: dict            # the near-dwell at the rear extreme (the file's criterion)

    @property
    def power(self) -> np.ndarray:
        return self.torque * self.omega


@dataclass
class ServoCandidate:
    """One gearbox and motor: the design (or why there is none) and its numbers."""

    gearbox: GearboxEntry
    motor: str
    rated_torque: float
    design: object = None
    reason: str = ""            # why it does not carry the cycle ("" when it does)
    numbers: dict = field(default_factory=dict)

    @property
    def feasible(self) -> bool:
        return not self.reason


@dataclass
class LinkageServo:
    linkage: LinkageSide
    candidates: list[ServoCandidate]
    chosen: ServoCandidate | None
    servo_curves: dict = field(default_factory=dict)  # the chosen design over the crank angle

    def table(self) -> list[dict]:
        """The side-by-side rows: quantity, unit, linkage, servo."""
        lk, c = self.linkage, self.chosen
        n = c.numbers if c is not None else {}
        get = lambda key: n.get(key, math.nan)  # noqa: E731
        return [
            {"quantity": "drive", "unit": "", "linkage": "crank from the main shaft and flywheel",
             "servo": (f"{c.motor}, {c.gearbox.name} (i = {c.gearbox.ratio:g})" if c else "none fits")},
            {"quantity": "peak torque (crank / motor)", "unit": "N m", "linkage": float(np.abs(lk.torque).max()),
             "servo": get("peak_torque_N_m")},
            {"quantity": "RMS torque (crank / motor)", "unit": "N m", "linkage": float(np.sqrt(np.mean(lk.torque ** 2))),
             "servo": get("rms_torque_N_m")},
            {"quantity": "peak power delivered", "unit": "W", "linkage": float(lk.power.max()),
             "servo": get("peak_power_W")},
            {"quantity": "peak power absorbed", "unit": "W", "linkage": float(-lk.power.min()),
             "servo": get("peak_absorbed_W")},
            {"quantity": "peak torque on the sley shaft", "unit": "N m", "linkage": math.nan,
             "servo": get("peak_output_torque_N_m")},
            {"quantity": "peak sley acceleration", "unit": "rad/s^2", "linkage": float(np.abs(lk.sley_accel).max()),
             "servo": get("peak_sley_accel_rad_s2")},
            {"quantity": "sley swing", "unit": "deg", "linkage": lk.swing_deg, "servo": get("swing_deg")},
            {"quantity": "rear dwell (linkage: within 5 % of the swing)", "unit": "deg of crank",
             "linkage": lk.rear_dwell["length_deg"], "servo": get("rear_dwell_deg")},
        ]

    def to_dict(self) -> dict:
        return {"table": self.table(),
                "chosen": None if self.chosen is None else {"motor": self.chosen.motor,
                                                            "gearbox": self.chosen.gearbox.name,
                                                            "ratio": self.chosen.gearbox.ratio,
                                                            **self.chosen.numbers},
                "candidates": [{"gearbox": c.gearbox.name, "ratio": c.gearbox.ratio, "motor": c.motor,
                                "feasible": c.feasible, "reason": c.reason, **c.numbers} for c in self.candidates]}


def linkage_side(linkage_problem, output: str = "sley_angle") -> LinkageSide:
    """The linkage's output angle, acceleration and crank torque at its rpm over one turn."""
    kin = kinematics_of(linkage_problem.linkage)
    cycle = kin.solve(linkage_problem.angles)
    omega = linkage_problem.omega
    dyn = analyse_dynamics(kin, cycle, omega)
    y, _, d2, _ = kin.output(cycle, output)
    share = linkage_problem.near_dwell_pct / 100
    dwells = near_dwells(cycle.theta, y, share)
    # the output's positive sense runs towards the rear (Tab. 1: v_D > 0 away from the beat-up)
    rear = next(d for d in dwells if d["at"] == "maximum")
    crank = np.degrees(cycle.theta) % 360
    order = np.argsort(crank)
    return LinkageSide(crank[order], np.degrees(y - y.min())[order], (d2 * omega ** 2)[order], dyn.torque[order],
                       omega, float(np.degrees(y.max() - y.min())), rear)


def _servo_numbers(design, gearbox: GearboxEntry) -> dict:
    t, terms = design_torque(design, samples=6001)
    k = design.stroke.sample(6001)
    power = terms.total * terms.omega
    problem = design.problem
    dwell = sum(itv.span_deg for itv in problem.timing.intervals if not itv.is_move and "rear" in itv.name) or \
        max((itv.span_deg for itv in problem.timing.intervals if not itv.is_move), default=0.0)
    return {"peak_torque_N_m": float(np.abs(terms.total).max()),
            "rms_torque_N_m": float(np.sqrt(np.mean(terms.total ** 2))),
            "peak_power_W": float(power.max()), "peak_absorbed_W": float(-power.min()),
            "peak_output_torque_N_m": float(np.abs(terms.load_force).max()),  # I a - load torques, at the sley
            "peak_sley_accel_rad_s2": float(np.abs(k.a).max()),
            "swing_deg": float(np.degrees(k.s.max() - k.s.min())),
            "peak_motor_speed_rpm": float(np.abs(terms.omega).max() * 60 / (2 * math.pi)),
            "rear_dwell_deg": float(dwell), "objective": design.objective,
            "objective_value": float(design.objective_value), "status": design.status}


def _static_torque(problem) -> float:
    """The largest load torque no motion avoids [N m at the load]: every load force at the positions the
    stroke must reach (the move ends), at rest."""
    load = problem.drive.load
    ends = sorted({p for itv in problem.timing.intervals for p in (itv.start_position, itv.end_position)})
    return max((abs(sum(float(f(np.array([x]), np.zeros(1))[0]) for f in load.forces)) for x in ends), default=0.0)


def compare_linkage_servo(linkage_problem, servo_problem, gearboxes: list[GearboxEntry] | None = None,
                          motors: list[str] | None = None, progress=None) -> LinkageServo:
    """The linkage of ``linkage_problem`` (a :class:`~strokeopt.linkage.files.LinkageProblem`) against the servo
    problem ``servo_problem`` (a rotary :class:`~strokeopt.problem.Problem` through a gearbox) solved with every
    gearbox of ``gearboxes`` (default: the shipped catalogue) and every motor of ``motors`` (default: those of
    the problem's own ``[drive] catalogues``)."""
    if not servo_problem.timing.rotary or servo_problem.drive is None:
        raise ProblemError(str(servo_problem.file), "transmission.type", "the servo side needs a rotary load "
                                                                         "through a gearbox and a [drive] section")
    gearboxes = load_gearboxes() if gearboxes is None else gearboxes
    catalogue = servo_problem.drive.catalogue()
    if motors is None:  # the motors of the problem's own catalogue files, else every motor
        motors = own_motors(servo_problem.drive.catalogue_files, catalogue)
    static = _static_torque(servo_problem)
    candidates = []
    pairs = [(g, m) for g in gearboxes for m in motors]
    for g, name in (progress(pairs) if progress else pairs):
        motor = catalogue.motors[name]
        limit = min(motor.peak_torque, servo_problem.drive.limits.peak_limit_pct / 100 * motor.rated_torque)
        cand = ServoCandidate(g, name, motor.rated_torque)
        candidates.append(cand)
        if static / g.ratio > limit:
            cand.reason = (f"cannot hold the static load torque {static:.1f} N m / i = {static / g.ratio:.1f} N m "
                           f"(torque limit {limit:.1f} N m)")
            continue
        variant = servo_problem.with_overrides([f"transmission.ratio={g.ratio!r}",
                                                f"transmission.inertia_kg_cm2={g.inertia / KG_CM2!r}",
                                                f'transmission.gearbox="{g.name}"', f'drive.motor="{name}"',
                                                'design.motor_choice="fixed"'])
        try:
            design = solve_design(variant)
        except SolverError as exc:
            cand.reason = "no design: " + str(exc).splitlines()[0]
            continue
        cand.design = design
        cand.numbers = _servo_numbers(design, g)
        failed = [c["name"] for c in design.checks if not c.get("ok", True)]
        if failed:
            cand.reason = "limits exceeded: " + ", ".join(failed)
        elif cand.numbers["peak_output_torque_N_m"] > g.peak_output_torque:
            cand.reason = (f"gearbox peak output torque {g.peak_output_torque:g} N m < "
                           f"{cand.numbers['peak_output_torque_N_m']:.1f} N m")
    fits = [c for c in candidates if c.feasible]
    chosen = choose_smallest(fits, lambda c: c.rated_torque, lambda c: c.numbers["rms_torque_N_m"])
    result = LinkageServo(linkage_side(linkage_problem), candidates, chosen)
    if chosen is not None:
        t, terms = design_torque(chosen.design, samples=3601)
        k = chosen.design.stroke.sample(3601)
        result.servo_curves = {"crank_deg": 360 * t / chosen.design.stroke.period, "sley_deg": np.degrees(k.s),
                               "sley_accel": k.a, "torque": terms.total, "power": terms.total * terms.omega}
    return result


def table_text(result: LinkageServo) -> str:
    """The side-by-side table as text."""
    rows = result.table()
    out = [f"{'':46s} {'unit':>12s} {'linkage':>40s} {'servo':>40s}"]
    fmt = lambda x: x if isinstance(x, str) else ("-" if math.isnan(x) else f"{x:.4g}")  # noqa: E731
    for r in rows:
        out.append(f"{r['quantity']:46s} {r['unit']:>12s} {fmt(r['linkage']):>40s} {fmt(r['servo']):>40s}")
    return "\n".join(out)


def plot_linkage_servo(result: LinkageServo, path: str | Path | None = None, hybrid: list | None = None):
    """Sley angle, sley acceleration, and the crank's and the motor's torque over the crank angle; with
    ``hybrid`` (:class:`HybridDesign` list) their crank torques too."""
    import matplotlib

    matplotlib.use("Agg") if path is not None else None
    import matplotlib.pyplot as plt

    lk, sv = result.linkage, result.servo_curves
    fig, axes = plt.subplots(3, 1, sharex=True, figsize=(9, 8), constrained_layout=True)
    servo_label = (f"servo: {result.chosen.motor}, i = {result.chosen.gearbox.ratio:g}" if result.chosen
                   else "servo")
    axes[0].plot(lk.crank_deg, lk.sley_deg, label="linkage")
    axes[1].plot(lk.crank_deg, lk.sley_accel, label="linkage")
    axes[2].plot(lk.crank_deg, lk.torque, label="linkage: crank torque (main shaft)")
    if sv:
        axes[0].plot(sv["crank_deg"], sv["sley_deg"], label=servo_label)
        axes[1].plot(sv["crank_deg"], sv["sley_accel"], label=servo_label)
        axes[2].plot(sv["crank_deg"], sv["torque"], label=servo_label + ": motor torque")
    for hd in hybrid or ():
        axes[2].plot(hd.crank_deg, hd.torque, lw=1, ls="--", label=f"hybrid, crank torque: {hd.label}")
    axes[0].set_ylabel("sley angle from\nthe front, deg")
    axes[1].set_ylabel("sley acceleration\nrad/s$^2$")
    axes[2].set_ylabel("torque, N m")
    axes[2].set_xlabel("crank angle, deg (0 = beat-up; the servo's time as the crank angle at constant speed)")
    axes[0].set_title("loom beat-up: six-bar linkage against a servo-driven sley", fontsize=10)
    for ax in axes:
        ax.grid(True, alpha=0.3)
        ax.legend(fontsize=7)
    axes[2].set_xlim(0, 360)
    if path is not None:
        fig.savefig(path, dpi=120)
        plt.close(fig)
    return fig


@dataclass
class HybridDesign:
    """A servo driving the linkage's crank at non-uniform speed (no flywheel): the crank speed over the crank
    angle, the crank torque it needs, and the time the output spends in its rear near-dwell."""

    label: str
    crank_deg: np.ndarray       # nodes [deg]
    omega: np.ndarray           # crank speed at the nodes [rad/s]
    torque: np.ndarray          # crank torque at the midpoints [N m]
    power: np.ndarray           # crank power at the midpoints [W]
    dwell_time_s: float         # time the output spends in its rear near-dwell
    period_s: float

    def numbers(self) -> dict:
        return {"label": self.label, "peak_torque_N_m": float(np.abs(self.torque).max()),
                "rms_torque_N_m": float(np.sqrt(np.average(self.torque ** 2, weights=self._dt))),
                "peak_power_W": float(self.power.max()), "peak_absorbed_W": float(-self.power.min()),
                "dwell_time_ms": self.dwell_time_s * 1e3,
                "dwell_share_of_cycle_deg": 360 * self.dwell_time_s / self.period_s,
                "omega_min_rad_s": float(self.omega.min()), "omega_max_rad_s": float(self.omega.max())}

    @property
    def _dt(self) -> np.ndarray:
        h = math.radians(self.crank_deg[1] - self.crank_deg[0])
        w = self.omega
        return h * 0.5 * (1 / w + 1 / np.roll(w, -1))


def hybrid_crank_speed(linkage_problem, *, dwell_time_min_s: float | None = None,
                       peak_torque_max_N_m: float | None = None, n: int = 360,
                       speed_range: tuple[float, float] = (0.2, 5.0), rotor_inertia: float = 0.0) -> HybridDesign:
    """The hybrid: keep the linkage and drive its crank with a servo at non-uniform speed, one crank turn per
    machine cycle, the beat-up still at crank angle 0 at time 0. Designed in the input (crank) coordinate, as a
    crank-driven linkage has no unique inverse: the unknowns are w = omega^2 at ``n`` crank angles (periodic);
    the crank torque is ``J(theta) theta'' + J'(theta) omega^2 / 2 + M_ext(theta) = (J w)' / 2 + M_ext`` with
    the reduced inertia, gravity and process loads of linkage/dynamics.py (linear in w), the time of a step
    ``h w^(-1/2)`` (trapezoidal). With ``dwell_time_min_s``: the least peak crank torque with the output at
    least that long in its rear near-dwell (the file's criterion); with ``peak_torque_max_N_m``: the longest
    such dwell with the peak crank torque within it. The crank speed stays within ``speed_range`` times the
    constant speed. ``rotor_inertia`` [kg m^2]: a motor's rotor on the crank shaft, added to J (a gearbox of ratio
    i would add i^2 J_rotor); 0 by default, the crank's own torque. IPOPT."""
    import casadi as ca

    kin = kinematics_of(linkage_problem.linkage)
    cycle = kin.solve(8 * n)  # the terms at eighth steps: the NLP holds them at every quarter of each step
    omega0 = linkage_problem.omega
    dyn = analyse_dynamics(kin, cycle, omega0)
    J, dJ, ext = dyn.J + rotor_inertia, dyn.dJ, dyn.gravity_torque + dyn.load_torque
    theta = cycle.theta[0::8]
    h = 2 * math.pi / n
    period = 2 * math.pi / omega0
    y, *_ = kin.output(cycle, "sley_angle")
    rear = next(d for d in near_dwells(cycle.theta, y, linkage_problem.near_dwell_pct / 100) if d["at"] == "maximum")
    lo, hi = math.radians(rear["from_deg"]), math.radians(rear["to_deg"])
    mid = (theta + h / 2) % (2 * math.pi)
    in_dwell = ((mid - lo) % (2 * math.pi)) <= ((hi - lo) % (2 * math.pi))

    def torque_at(w_k, w_next, frac: float, offset: int, right_limit: bool = False):
        """The crank torque at ``frac`` of every step (w linear on the step: theta'' = w'/2 constant); with
        ``right_limit`` the load just after the node (a process load that ends at a node, as the beat-up
        at 360 = 0 deg, jumps there: both sides are held)."""
        ww = (1 - frac) * w_k + frac * w_next
        idx = (np.arange(n) * 8 + offset) % (8 * n)
        load = 2 * ext[(idx + 1) % (8 * n)] - ext[(idx + 2) % (8 * n)] if right_limit else ext[idx]
        return 0.5 * (dJ[idx] * ww + J[idx] * (w_next - w_k) / h) + load

    opti = ca.Opti()
    w = opti.variable(n)
    w_next = ca.vertcat(w[1:], w[0])
    torque = ca.vertcat(*(torque_at(w, w_next, q / 4, 2 * q) for q in range(5)), torque_at(w, w_next, 0.0, 0, True))
    inv = 1 / ca.sqrt(w)
    dt = h * 0.5 * (inv + ca.vertcat(inv[1:], inv[0]))
    opti.subject_to(ca.sum1(dt) == period)
    dwell = ca.sum1(dt * in_dwell)
    opti.subject_to(opti.bounded((speed_range[0] * omega0) ** 2, w, (speed_range[1] * omega0) ** 2))
    smooth = 1e-9 * ca.sumsqr(w_next - w)  # a tie between neighbours: no odd-even modes
    if dwell_time_min_s is not None:
        tau = opti.variable()
        opti.subject_to(opti.bounded(-tau, torque, tau))
        opti.subject_to(dwell >= dwell_time_min_s)
        opti.minimize(tau + smooth)
        opti.set_initial(tau, float(np.abs(dyn.torque).max()))
        label = f"least peak torque, dwell >= {dwell_time_min_s * 1e3:.2f} ms"
    elif peak_torque_max_N_m is not None:
        opti.subject_to(opti.bounded(-peak_torque_max_N_m, torque, peak_torque_max_N_m))
        opti.minimize(-dwell / period + smooth)
        label = f"longest dwell, peak torque <= {peak_torque_max_N_m:.2f} N m"
    else:
        raise ValueError("give dwell_time_min_s or peak_torque_max_N_m")
    opti.set_initial(w, omega0 ** 2)
    opti.solver("ipopt", {"print_time": False}, {"print_level": 0, "sb": "yes", "max_iter": 3000, "tol": 1e-10})
    try:
        sol = opti.solve()
    except RuntimeError as exc:
        raise SolverError(f"hybrid crank speed ({label}): IPOPT failed: {exc}") from None
    wv = np.asarray(sol.value(w)).ravel()
    # checked at every eighth of a step (half of them between the points the NLP holds), w linear on each step
    wn = np.roll(wv, -1)
    w_fine = np.empty(8 * n)
    tq = np.empty(8 * n)
    for q in range(8):
        w_fine[q::8] = (1 - q / 8) * wv + q / 8 * wn
        tq[q::8] = 0.5 * (dJ[q::8] * w_fine[q::8] + J[q::8] * (wn - wv) / h) + ext[q::8]
    return HybridDesign(label, np.degrees(cycle.theta), np.sqrt(w_fine), tq, tq * np.sqrt(w_fine),
                        float(sol.value(dwell)), period)
