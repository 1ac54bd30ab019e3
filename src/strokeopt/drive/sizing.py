"""Drive sizing: every catalogue motor with every pulley, checked and ranked over the cycle.

Where it sits: at the end of the drive package. A problem's stroke (motion/)
sampled over the whole cycle, its ``[drive]`` section (spec.py) and the
catalogue (catalogue.py) go in; the motor torque of each pair (load.py) is
checked (checks.py) and the pairs are ranked (:func:`size_drive` ->
:class:`Sizing`). Also: the highest stitch rate of a pair (:func:`max_spm`)
and the continuous pulley radius minimising the peak torque
(:func:`optimal_radius`). Figures and text tables of a sizing are in
report/drive.py.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import casadi as ca
import numpy as np

from ..errors import ProblemError, SolverError
from ..motion.stroke import Kinematics
from .checks import (BeltSpec, Check, DriveLimits, binding_check, build_checks, cycle_values, pull_out_ratio,
                     stepper_checks)
from .load import Load, TorqueTerms, load_torque, reflected_inertia, rotor_inertia_of
from .transmission import PROFILE_PITCH, BeltPulley


@dataclass
class Candidate:
    """One motor with one pulley, checked over the cycle at ``spm``."""

    motor: object  # catalogue.ServoMotor
    pulley: object  # catalogue.Pulley
    spm: float
    checks: list[Check]
    peak_terms: dict  # torque terms [N m] at the instant of the peak torque
    peak_angle_deg: float
    max_spm: float | None = None
    max_spm_binding: str | None = None
    worst: dict | None = None  # a stepper's point of least pull-out reserve: speed, step rate, demand, pull-out

    def check(self, name: str) -> Check:
        return next(c for c in self.checks if c.name == name)

    @property
    def feasible(self) -> bool:
        return all(c.ok for c in self.checks)

    @property
    def binding(self) -> str:
        """The check with the smallest margin (violated first, or closest to its limit)."""
        return binding_check(self.checks).name

    @property
    def stepper(self) -> bool:
        return getattr(self.motor, "kind", "servo") == "stepper"

    def row(self, explain: bool = False, with_max_spm: bool = False) -> dict:
        if self.stepper:
            out = self._stepper_row(explain)
            if with_max_spm:
                out["max_spm"], out["max_spm_binding"] = self.max_spm, self.max_spm_binding
            return out
        out = {
            "motor": self.motor.name,
            **({"gearbox": self.pulley.name, "ratio": self.pulley.entry.ratio}
               if isinstance(self.pulley, GearboxChoice) else {}),
            "pulley_teeth": self.pulley.teeth,
            # None: the transmission is no belt pulley (a servo motor on a screw lever)
            "pulley_pitch_diameter_mm": None if self.pulley.pitch_diameter is None else self.pulley.pitch_diameter * 1e3,
            "peak_torque_N_m": self.check("peak_torque").value,
            "torque_limit_N_m": self.check("peak_torque").limit,
            "rms_torque_N_m": self.check("rms_torque").value,
            "overload_pct": self.check("overload").value,
            "peak_speed_rpm": self.check("peak_speed").value,
            "inertia_ratio": self.check("inertia_ratio").value,
            "feasible": self.feasible,
            "binding": self.binding,
            "margin": binding_check(self.checks).margin,
        }
        if with_max_spm:
            out["max_spm"] = self.max_spm
            out["max_spm_binding"] = self.max_spm_binding
        if explain:
            out["checks"] = [c.as_dict() for c in self.checks]
            out["peak_angle_deg"] = self.peak_angle_deg
            out["torque_at_peak_N_m"] = dict(self.peak_terms)
        return out


    def _stepper_row(self, explain: bool) -> dict:
        out = {"motor": self.motor.name, "transmission": self.pulley.name,
               "peak_torque_N_m": abs(self.peak_terms["total"]),
               "pull_out_pct": self.check("pull_out_torque").value, "pull_out_limit_pct": self.check("pull_out_torque").limit,
               "step_rate_Hz": self.check("step_rate").value, "max_step_rate_Hz": self.check("step_rate").limit,
               "inertia_ratio": self.check("inertia_ratio").value, "feasible": self.feasible, "binding": self.binding,
               "margin": binding_check(self.checks).margin, **(self.worst or {})}
        if explain:
            out["checks"] = [c.as_dict() for c in self.checks]
            out["peak_angle_deg"] = self.peak_angle_deg
            out["torque_at_peak_N_m"] = dict(self.peak_terms)
        return out


@dataclass(frozen=True)
class FixedTransmission:
    """The problem's own transmission as the one "pulley" a sizing tries (a screw and lever: nothing
    to choose from a catalogue)."""

    tr: object
    teeth = None
    pitch_diameter = None

    @property
    def name(self) -> str:
        return self.tr.name

    def transmission(self):
        return self.tr


@dataclass(frozen=True)
class GearboxChoice(FixedTransmission):
    """The problem's transmission through one gearbox of the catalogue (``[drive] gearboxes``): a "pulley" a
    sizing tries, with the gearbox's own checks (its output torques)."""

    entry: object = None  # gearboxes.GearboxEntry

    @property
    def name(self) -> str:
        return self.entry.name

    def checks(self, base) -> list[Check]:
        """The gearbox's output torque over the cycle (the motor-side torque without the rotor's and the
        gearbox's own inertia, times the ratio) against its rated (RMS) and peak output torques."""
        out = (np.asarray(base.total, float) - self.tr.inertia * np.asarray(base.eps, float)) * self.entry.ratio
        t = np.linspace(0.0, 1.0, out.size)   # equal time steps over the cycle
        peak, rms, _, _ = cycle_values(out, np.zeros_like(out), np.zeros_like(out), t)
        return [Check("gearbox_peak_output_torque", float(peak), self.entry.peak_output_torque, "N m"),
                Check("gearbox_rated_output_torque", float(rms), self.entry.rated_output_torque, "N m")]


def transmission_choices(problem, spec, teeth, cat) -> list:
    """What a sizing tries beside the motors: the catalogue's pulleys (``teeth``, else the problem's range), the
    catalogue's gearboxes (``[drive] gearboxes``) on a transmission with a ratio, else the problem's own."""
    tr = problem.transmission
    if not hasattr(tr, "radius"):  # nothing to choose but a gearbox: the problem's screw and lever, its ratio
        if teeth:
            raise ProblemError("--pulley-teeth", "", f"the problem's transmission is a {tr.name}, not a belt pulley")
        if spec.gearbox_file is not None:
            from .gearboxes import load_gearboxes

            return [GearboxChoice(tr.with_gearbox(g), g) for g in load_gearboxes(spec.gearbox_file)]
        return [FixedTransmission(tr)]
    if not teeth:
        pulleys = cat.pulleys_of(spec.profile, spec.teeth_min, spec.teeth_max)
        if not pulleys:
            raise ProblemError(spec.file, "drive.pulley_teeth_min", f"no {spec.profile} pulley in the catalogue between "
                                                                   f"{spec.teeth_min} and {spec.teeth_max} teeth")
        return pulleys
    pulleys = []
    for z in teeth:
        found = [p for p in cat.pulleys_of(spec.profile) if p.teeth == z]
        if not found:
            have = ", ".join(str(p.teeth) for p in cat.pulleys_of(spec.profile))
            raise ProblemError("--pulley-teeth", "", f"no {spec.profile} pulley with {z} teeth in the catalogue "
                                                     f"(have {have})")
        pulleys += found
    return pulleys


@dataclass
class Sizing:
    """The result of :func:`size_drive`: candidates ranked, and what they were computed from."""

    problem_name: str
    spm: float
    period: float
    candidates: list[Candidate]
    inputs: dict
    kinematics: Kinematics  # of the whole cycle
    load: Load
    limits: DriveLimits
    max_spm_resolution: float | None = None

    def to_dict(self, explain: bool = False) -> dict:
        with_max = self.max_spm_resolution is not None
        out = {"problem": self.problem_name, "spm": self.spm, "cycle_time_s": self.period, "inputs": self.inputs,
               "candidates": [c.row(explain, with_max) for c in self.candidates]}
        if with_max:
            out["max_spm_resolution"] = self.max_spm_resolution
        return out

    def torque_curve(self, candidate: Candidate) -> TorqueTerms:
        k = self.kinematics
        return load_torque(candidate.motor, candidate.pulley.transmission(), self.load, k.s, k.v, k.a)


def scale_kinematics(kin, factor: float):
    """The same stroke run ``factor`` times faster: time / f, speed * f, acceleration * f^2, jerk * f^3.

    Exact for a timing diagram, whose interval times all scale with the cycle time.
    """
    return Kinematics(kin.t / factor, kin.s, kin.v * factor, kin.a * factor**2, kin.j * factor**3)


def candidates(kin, motors, pulleys, load: Load, limits: DriveLimits, belt: BeltSpec | None, spm: float,
               period: float) -> list[Candidate]:
    """Every motor with every pulley, vectorised: one torque evaluation per pulley over the
    whole cycle; the rotor term broadcast over the motors."""
    rotor = np.array([m.rotor_inertia for m in motors])[:, None]
    out = []
    for p in pulleys:
        tr = p.transmission()
        base = load_torque(0.0, tr, load, kin.s, kin.v, kin.a)  # everything but the rotor
        total = base.total[None, :] + rotor * base.eps[None, :]
        peak, rms, peak_speed, peak_force = cycle_values(total, base.omega, base.load_force, kin.t)
        reflected = reflected_inertia(tr, load, base.phi)
        i_peak = np.argmax(np.abs(total), axis=-1)
        for k, m in enumerate(motors):
            i = int(i_peak[k])
            terms = {name: float(np.broadcast_to(val, kin.s.shape)[i]) for name, val in base.as_dict().items()}
            terms["rotor_inertia"] = float(rotor[k, 0] * base.eps[i])
            terms["total"] = float(total[k, i])
            if getattr(m, "kind", "servo") == "stepper":
                checks = stepper_checks(total[k], base.omega, m, reflected, limits)
            else:
                checks = build_checks(peak[k], rms[k], peak_speed, peak_force, m, reflected, limits, belt, p.teeth)
            if isinstance(p, GearboxChoice):
                checks = checks + p.checks(base)
            cand = Candidate(m, p, spm, checks, terms, float(360.0 * kin.t[i] / period))
            if cand.stepper:
                ratio = pull_out_ratio(total[k], base.omega, m)
                w = int(np.argmax(ratio))
                cand.worst = {"worst_speed_rpm": abs(float(base.omega[w])) * 60 / (2 * math.pi),
                               "worst_step_rate_Hz": abs(float(base.omega[w])) / m.step_angle,
                               "worst_torque_N_m": abs(float(total[k, w])),
                               "worst_pull_out_N_m": float(m.pull_out(base.omega[w]))}
            out.append(cand)
    return out


def rank(candidates: list[Candidate], choose: str = "least_overload") -> list[Candidate]:
    """Feasible pairs first; then by the thesis's criterion, the theoretical overload
    (peak load torque / rated torque, thesis 4.6), lowest first; ties by inertia ratio. ``choose =
    "smallest_motor"`` (``[drive] choose``): the least rated torque first, ties by the least RMS torque."""
    if choose == "smallest_motor" and not any(c.stepper for c in candidates):
        return sorted(candidates, key=lambda c: (not c.feasible, c.motor.rated_torque, c.check("rms_torque").value))
    # a stepper's load ratio is its demand against the pull-out curve
    return sorted(candidates, key=lambda c: (not c.feasible, c.check("pull_out_torque" if c.stepper else "overload").value,
                                             c.check("inertia_ratio").value))


def bisect_highest(ok, lo: float, hi: float, resolution: float) -> tuple[float, float]:
    """Bracket ``(lo, hi)``, ``hi - lo <= resolution``, of the threshold where ``ok`` turns false,
    given ``ok(lo)`` and not ``ok(hi)`` (``ok`` true below the threshold): the highest feasible
    stitch rate is ``lo``, the first failing one ``hi``."""
    while hi - lo > resolution:
        mid = 0.5 * (lo + hi)
        if ok(mid):
            lo = mid
        else:
            hi = mid
    return lo, hi


def max_spm(kin, spm: float, motor, pulley, load: Load, limits: DriveLimits, belt: BeltSpec | None = None,
            resolution: float = 1.0, highest: float = 20_000.0) -> tuple[float | None, str]:
    """Highest stitch rate [spm] at which every check of ``motor`` with ``pulley`` passes.

    ``kin`` is the cycle sampled at ``spm``; other speeds scale it exactly
    (:func:`scale_kinematics`). Bisection to ``resolution`` spm; returns the
    highest feasible rate found (rounded down to the resolution, ``None`` if
    even ``resolution`` spm fails, ``highest`` if nothing binds below it) and
    the check that fails just above it.
    """
    period = kin.t[-1] - kin.t[0]

    def checks_at(x):
        k = scale_kinematics(kin, x / spm)
        return candidates(k, [motor], [pulley], load, limits, belt, x, period * spm / x)[0].checks

    def ok(x):
        return all(c.ok for c in checks_at(x))

    lo, hi = 0.0, spm
    if ok(spm):
        lo = spm
        while ok(hi := min(hi * 2, highest)):
            lo = hi
            if hi >= highest:
                return highest, binding_check(checks_at(highest)).name
    lo, hi = bisect_highest(ok, lo, hi, resolution)
    if lo < resolution:
        return None, binding_check(checks_at(resolution)).name
    failing = [c for c in checks_at(hi) if not c.ok]
    return math.floor(lo / resolution) * resolution, binding_check(failing or checks_at(hi)).name


def size_drive(problem, spm: float | None = None, *, catalogue=None, motors=None, teeth=None, samples: int = 3601,
               find_max_spm: bool = False, resolution: float = 1.0, progress=None, stroke=None) -> Sizing:
    """Rank every catalogue motor with every allowed pulley for the stroke of ``problem`` at ``spm``.

    ``motors``: names to keep (default all); ``teeth``: groove counts to keep
    (default the problem's ``pulley_teeth_min..max``). ``find_max_spm`` adds
    the highest feasible stitch rate of each pair (bisection to ``resolution``).
    ``progress``: a callable wrapping an iterable (tqdm) for the max-spm search. ``stroke``: a
    stroke at ``spm`` to size for (an optimal design's) instead of the problem's law.
    """
    spec = problem.drive
    if spec is None:
        raise ProblemError(str(problem.file), "drive", "the problem has no [drive] section (motor, moving mass, ...)")
    spm = problem.spm if spm is None else spm
    cat = catalogue if catalogue is not None else spec.catalogue()
    own = cat.actuator(spec.motor, (spec.file, "drive.motor")) if spec.motor is not None else None  # must exist
    stepper = getattr(own, "kind", "servo") == "stepper"
    chosen = [cat.actuator(n) for n in motors] if motors else \
        list(cat.steppers.values()) if stepper else list(cat.motors.values())
    if len({getattr(m, "kind", "servo") for m in chosen}) > 1:
        raise ProblemError("--motor", "", "size servo motors and steppers in separate runs (their checks differ)")
    pulleys = transmission_choices(problem, spec, teeth, cat)
    belt = spec.belt_spec(cat)
    stroke = stroke if stroke is not None else problem.stroke(spm)
    kin = stroke.sample(samples)
    cands = candidates(kin, chosen, pulleys, spec.load, spec.limits, belt, spm, stroke.period)
    if find_max_spm:
        it = progress(cands) if progress is not None else cands
        for c in it:
            c.max_spm, c.max_spm_binding = max_spm(kin, spm, c.motor, c.pulley, spec.load, spec.limits, belt, resolution)
    rotary = problem.timing.rotary  # a rotary load's keys say its units: kg m^2, N m, N m/rad, deg
    own = {}
    if problem.transmission.carries_load:  # a linkage's links: their inertia on the motor shaft
        j = np.ravel(problem.transmission.inertia_at(problem.transmission.motor_angle(kin.s)))
        own = {"transmission_inertia_kg_m2": [float(j.min()), float(j.max())]}
    inputs = {
        ("moving_inertia_kg_m2" if rotary else "moving_mass_kg"): spec.load.moving_mass,
        "load_unit": problem.timing.unit,
        "gravity_m_s2": spec.load.gravity,
        "load_forces": [{"name": f.name, "kind": f.kind, "direction": "up" if f.direction > 0 else "down",
                         **({"torque_N_m": f.force, "stiffness_N_m_rad": f.stiffness,
                             "contact_position_deg": math.degrees(f.contact_position)} if rotary else
                            {"force_N": f.force, "stiffness_N_m": f.stiffness,
                             "contact_position_mm": f.contact_position * 1e3})} for f in spec.load.forces],
        **own,
        "peak_limit_pct": spec.limits.peak_limit_pct,
        "max_inertia_ratio": spec.limits.max_inertia_ratio,
        "belt": belt.belt.name if belt else None,
        "belt_cord": belt.cord if belt else None,
        "belt_service_factor": belt.service_factor if belt else None,
        "law": stroke.label,
        "choose": spec.choose,
        "samples": samples,
        "catalogue_files": cat.files,
    }
    return Sizing(problem.name, spm, stroke.period, rank(cands, spec.choose), inputs, kin, spec.load, spec.limits,
                  resolution if find_max_spm else None)


# --------------------------------------------------------------------------- continuous pulley radius


@dataclass(frozen=True)
class RadiusOptimum:
    """The belt-pulley radius that minimises a motor's peak torque over the cycle."""

    motor: str
    radius: float  # m
    peak_torque: float  # N m
    pulley_inertia: float  # kg m^2 at that radius
    teeth_equivalent: float  # pitch diameter / (pitch / pi), not rounded

    def row(self) -> dict:
        """The optimum in report units (mm, kg cm^2)."""
        return {"motor": self.motor, "pitch_radius_mm": self.radius * 1e3, "pitch_diameter_mm": 2e3 * self.radius,
                "teeth_equivalent": self.teeth_equivalent, "peak_torque_N_m": self.peak_torque,
                "pulley_inertia_kg_cm2": self.pulley_inertia * 1e4}


def optimal_radius(motor, load: Load, kin, pulley_inertia=None, bounds=(2e-3, 0.2), pitch: float = PROFILE_PITCH["GT3"],
                   solver_options: dict | None = None) -> RadiusOptimum:
    """Pulley pitch radius minimising the peak motor torque of a belt drive over the sampled cycle.

    For a belt, ``T_k(r) = (J_rotor + J_pulley(r)) a_k / r + r F_k`` with the load
    force ``F_k`` of each sample, so the problem is ``min z`` subject to
    ``-z <= T_k(r) <= z``, solved by IPOPT through CasADi. ``pulley_inertia``:
    a function of the pitch diameter (CasADi-friendly; the catalogue's model),
    or None for none. With inertia only and no pulley inertia the optimum is
    ``r = sqrt(J_rotor / m)`` (inertia matching).
    """
    base = load_torque(0.0, BeltPulley(2.0), load, kin.s, kin.v, kin.a)  # r = 1: eps = a, mu = 1
    acc = np.asarray(base.eps, dtype=float)
    force = np.asarray(base.load_force, dtype=float)
    j_rotor = rotor_inertia_of(motor)

    def torque_np(radius):
        jp = float(pulley_inertia(2 * radius)) if pulley_inertia is not None else 0.0
        return (j_rotor + jp) * acc / radius + radius * force

    # The peak is set by a few samples: solve on those that peak somewhere on a grid of radii,
    # then check every sample at the optimum and add any that exceeds it (an active-set loop).
    active = set()
    for radius in np.geomspace(bounds[0], bounds[1], 48):
        active.update(np.argsort(-np.abs(torque_np(radius)))[:3].tolist())
    r = ca.SX.sym("r")
    z = ca.SX.sym("z")
    jp = pulley_inertia(2 * r) if pulley_inertia is not None else 0.0
    opts = {"ipopt.print_level": 0, "print_time": False, "ipopt.sb": "yes", "ipopt.tol": 1e-10}
    opts.update(solver_options or {})
    r0 = float(np.clip(math.sqrt(j_rotor / load.moving_mass), *bounds))
    for _ in range(20):
        idx = sorted(active)
        torque = (j_rotor + jp) * ca.DM(acc[idx]) / r + r * ca.DM(force[idx])
        nlp = {"x": ca.vertcat(r, z), "f": z, "g": ca.vertcat(torque - z, torque + z)}
        solver = ca.nlpsol("radius", "ipopt", nlp, opts)
        n = len(idx)
        res = solver(x0=[r0, 1.0], lbx=[bounds[0], 0.0], ubx=[bounds[1], ca.inf],
                     lbg=np.r_[np.full(n, -np.inf), np.zeros(n)], ubg=np.r_[np.zeros(n), np.full(n, np.inf)])
        if not solver.stats()["success"]:
            raise SolverError(f"pulley radius optimisation for {getattr(motor, 'name', 'motor')} failed: "
                              f"{solver.stats()['return_status']}")
        r0, z0 = (float(x) for x in np.asarray(res["x"]).ravel())
        full = np.abs(torque_np(r0))
        worst = int(np.argmax(full))
        if worst in active or full[worst] <= z0 * (1 + 1e-7):  # within IPOPT's constraint tolerance
            break
        active.add(worst)
    else:
        raise SolverError("pulley radius optimisation did not settle on its peak samples in 20 rounds")
    r_opt, z_opt = r0, float(np.max(np.abs(torque_np(r0))))
    jp_opt = float(pulley_inertia(2 * r_opt)) if pulley_inertia is not None else 0.0
    return RadiusOptimum(getattr(motor, "name", ""), r_opt, z_opt, jp_opt, 2 * r_opt * math.pi / pitch)
