"""A planar linkage as a problem's transmission: a servo motor turns the linkage's crank (through a gearbox of
``ratio`` motor turns per crank turn) and the problem's load is one of the linkage's outputs (a rocker's angle,
a point's arc or coordinate).

The position function is the output over the crank angle from the exact closure (kinematics.py: Newton with
continuation, derivatives by AD), made a Fourier series of the crank angle (series.py) so that it evaluates on
numbers and on CasADi symbols alike and its transfer functions come by AD as every transmission's; the links'
reduced inertia ``J(theta)``, the gravity torque ``V'(theta)`` and each process load's torque per newton come
the same way from dynamics.py. Every series is checked against the exact closure between its samples
(:data:`FIT_TOLERANCE`); a linkage the samples do not resolve is refused.

The design states the load's motion in output coordinates, so the output must be monotonic over the crank
angles the motor turns through: the crank oscillates on one branch of the output, between two extremes where
``d output / d theta`` vanishes, kept :data:`~strokeopt.drive.crank_slider.DEAD_CENTRE_MARGIN_DEG` from them as
a crank and connecting rod is (``crank_range_deg`` states the branch; by default the one through the reference
pose). The motor angle is zero at the reference pose. The motor torque adds to the rotor's and the load's

    J_gear eps + (J(theta) eps / i + 1/2 J'(theta) omega^2 / i^2) / i + (V'(theta) - sum_i F_i u_i(theta)) / i,

``theta = theta_ref + phi / i`` (:meth:`LinkageTransmission.own_terms`): a direct or geared servo on the crank.
A crank that turns through the extremes (the hybrid, designed in crank coordinates) is not this transmission.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import lru_cache

import casadi as ca
import numpy as np

from ..drive.crank_slider import DEAD_CENTRE_MARGIN_DEG
from ..drive.transmission import Transmission, check_reach
from ..errors import ProblemError
from .dynamics import load_magnitude, reduced_terms
from .kinematics import kinematics_of
from .model import Linkage
from .series import Series

#: What the design states the motion of: one of the linkage's outputs (the crank oscillates on one branch), or
#: the crank itself (it turns, at the speed the design gives it: the hybrid).
COORDINATES = ("output", "crank")

#: Largest error of a series between its samples against the exact closure, relative to the function's
#: largest value (its swing for the output): above it the linkage is refused (more ``angles`` a turn).
FIT_TOLERANCE = 1e-8


@dataclass(frozen=True)
class LinkageFit:
    """The series of one output and of the dynamics, with the samples they came from and their check."""

    theta: np.ndarray          # crank angles of the samples [rad], from the reference angle
    y: Series
    J: Series
    dV: Series
    units: tuple               # one Series per process load: torque per newton [m]
    index: np.ndarray          # smallest transmission index at each sample
    error: float               # largest relative error between the samples


@lru_cache(maxsize=32)
def fit_linkage(linkage: Linkage, output: str, samples: int) -> LinkageFit:
    """The series of ``output`` and of the dynamics of ``linkage`` from ``samples`` poses a turn, checked at the
    poses between them; ValueError when they do not resolve it."""
    kin = kinematics_of(linkage)
    fine = kin.solve(2 * samples)  # the even poses are fitted, the odd ones check
    y, d1, *_ = kin.output(fine, output)
    J, _, dV, unit = reduced_terms(kin, fine)
    theta0 = float(fine.theta[0])
    slope = float(np.mean(d1))
    slope = slope if abs(slope) > 1e-9 * max(float(np.abs(d1).max()), 1e-300) else 0.0
    exact = [y, J, dV] + [unit[:, i] for i in range(unit.shape[1])]
    series = [Series.fit(theta0, f[0::2], slope if k == 0 else 0.0) for k, f in enumerate(exact)]
    odd = fine.theta[1::2]
    scale = lambda f: max(float(np.ptp(f)), float(np.abs(f).max()), 1e-300)  # noqa: E731
    error = max(float(np.abs(s(odd) - f[1::2]).max()) / scale(f) for s, f in zip(series, exact))
    error = max(error, float(np.abs(series[0].derivative()(odd) - d1[1::2]).max()) / scale(d1))
    index = fine.index.min(axis=1)[0::2] if fine.index.size else np.ones(samples)
    return LinkageFit(fine.theta[0::2], series[0], series[1], series[2], tuple(series[3:]), index, error)


class LinkageTransmission(Transmission):
    """A servo on the crank of ``linkage`` (through ``ratio`` motor turns per crank turn, the gearbox's own
    ``gear_inertia`` [kg m^2] on the motor shaft) driving the load ``output`` (module docstring);
    ``crank_range`` [rad] the crank angles of the branch the motor turns through, None: the branch through the
    reference pose kept the dead-centre margin from its extremes."""

    name = "linkage"
    label = "planar linkage"
    load_unit = None  # the output's: "rad" for an angle, "m" for an arc or a coordinate
    carries_load = True  # the links' masses are the load's
    #: a linkage file without [timing]: its crank at constant speed, one turn a machine cycle from the reference
    #: pose (a move of a whole turn that ends at the speed it starts with: the classic stroke turns it uniformly)
    implied = {"timing": {"start_position_deg": 0.0, "advance_deg": 360.0,
                          "intervals": [{"name": "turn", "span_deg": 360.0, "stroke_deg": 360.0, "direction": "up",
                                         "end": "speed"}]},
               "motion": {"law": "poly5_speeds", "start_speed": 1.0, "end_speed": 1.0},   # = constant speed
               "transmission": {"coordinates": "crank"}}
    #: the limits of the linkage's own analysis (``[transmission]`` min_transmission_index, near_dwell_pct)
    min_transmission_index, near_dwell_pct = 0.0, 5.0

    @classmethod
    def read(cls, fields, timing) -> "LinkageTransmission":
        return read_linkage_transmission(cls, fields, timing)

    def __init__(self, linkage: Linkage, output: str, ratio: float = 1.0, gear_inertia: float = 0.0,
                 samples: int = 720, crank_range: tuple[float, float] | None = None, coordinates: str = "output"):
        if not (ratio > 0 and math.isfinite(ratio)) or not (gear_inertia >= 0 and math.isfinite(gear_inertia)):
            raise ValueError("need a positive ratio and a gearbox inertia of zero or more")
        if coordinates not in COORDINATES:
            raise ValueError(f"coordinates must be one of {COORDINATES}")
        out = next(o for o in linkage.outputs if o.name == output)
        self.linkage, self.output, self.samples = linkage, output, int(samples)
        self.coordinates = coordinates
        self.ratio, self.inertia = float(ratio), float(gear_inertia)  # the links' inertia varies: inertia_at
        self.load_unit = "rad" if out.kind == "angle" or coordinates == "crank" else "m"
        self.theta_ref = linkage.crank.reference_angle
        self.fit = fit_linkage(linkage, output, self.samples)
        if self.fit.error > FIT_TOLERANCE:
            raise ValueError(f"its series miss the exact closure by {self.fit.error:.2g} (relative) between "
                             f"{self.samples} samples a turn; more samples (angles) resolve it")
        self._dy, self._dJ = self.fit.y.derivative(), self.fit.J.derivative()
        self._d2y = self._dy.derivative()
        if coordinates == "crank":  # the load is the crank itself: it turns, no branch
            self.branch = self.crank_range = None
            return
        self.branch = self._branch()
        self.crank_range = self._working_range() if crank_range is None else self._within_branch(crank_range)

    # -- the branch the motor turns through ------------------------------------------------------------
    def _extreme(self, theta: float) -> float:
        """The crank angle of the output's extreme near ``theta`` (Newton on its derivative)."""
        for _ in range(30):
            step = float(self._dy(theta)) / float(self._d2y(theta))
            theta -= step
            if abs(step) < 1e-14:
                break
        return theta

    def _branch(self) -> tuple[float, float]:
        """The crank angles ``(a, b)``, a < b, of the output's extremes around the reference pose."""
        th, d = self.fit.theta, self._dy(self.fit.theta)
        n = len(th)
        sense = np.sign(d[0]) or np.sign(d[1])
        ahead = next((j for j in range(1, n + 1) if np.sign(d[j % n]) != sense), None)
        if ahead is None:
            raise ValueError(f"the output {self.output} turns fully with the crank: it has no extremes to oscillate "
                             "between")
        behind = next(j for j in range(0, -n, -1) if np.sign(d[j % n]) != sense)
        step = 2 * math.pi / n
        hi = self._extreme(self.theta_ref + (ahead - 0.5) * step)
        lo = self._extreme(self.theta_ref + (behind + 0.5) * step)
        return lo, hi

    def _working_range(self) -> tuple[float, float]:
        margin = math.radians(DEAD_CENTRE_MARGIN_DEG)
        lo, hi = self.branch
        if hi - lo <= 2 * margin:
            raise ValueError(f"the output's branch through the reference pose spans {math.degrees(hi - lo):.3g} deg of "
                             f"crank, no more than twice the {DEAD_CENTRE_MARGIN_DEG:g} deg kept from its extremes")
        return lo + margin, hi - margin

    def _within_branch(self, crank_range) -> tuple[float, float]:
        a, b = sorted(float(c) for c in crank_range)
        lo, hi = self.branch
        margin = math.radians(DEAD_CENTRE_MARGIN_DEG)
        shift = 2 * math.pi * round((0.5 * (a + b) - 0.5 * (lo + hi)) / (2 * math.pi))
        a, b = a - shift, b - shift
        if not (lo + margin <= a + 1e-9 and b - 1e-9 <= hi - margin):
            raise ValueError(f"{math.degrees(a + shift):.6g}..{math.degrees(b + shift):.6g} deg of crank: the branch "
                             f"keeps {DEAD_CENTRE_MARGIN_DEG:g} deg from the output's extremes at "
                             f"{math.degrees(lo + shift):.6g} and {math.degrees(hi + shift):.6g} deg (where it turns back "
                             f"and the motor speed of an output speed has no bound): within "
                             f"{math.degrees(lo + margin + shift):.6g}..{math.degrees(hi - margin + shift):.6g} deg")
        return a, b

    # -- the position function -------------------------------------------------------------------------
    def crank_angle(self, phi):
        """The crank angle [rad] at the motor angle ``phi`` (zero at the reference pose)."""
        return self.theta_ref + phi / self.ratio

    def position(self, phi):
        if self.coordinates == "crank":
            return self.crank_angle(phi)
        return self.fit.y(self.crank_angle(phi))

    def chain(self):
        if self.coordinates == "crank":
            return [("crank", self.crank_angle, "rad")]
        return [("crank", self.crank_angle, "rad"), ("load", self.fit.y, self.load_unit)]

    def _inverse_grid(self) -> tuple[np.ndarray, np.ndarray]:
        """The output (ascending) and the crank angle at 2001 crank angles of the range."""
        th = np.linspace(*self.crank_range, 2001)
        x = self.fit.y(th)
        return (x, th) if x[-1] > x[0] else (x[::-1], th[::-1])

    def _inverse_guess(self) -> ca.Function:
        if not hasattr(self, "_guess"):
            x, th = self._inverse_grid()
            self._guess = ca.interpolant(f"{self.name}_guess", "bspline", [x.tolist()], th.tolist())
        return self._guess

    def inverse_position(self, x):
        """On the branch: a cubic spline of the crank angle over the output, then one Newton step on the series."""
        if self.coordinates == "crank":
            return self.ratio * (x - self.theta_ref)
        theta = self._inverse_guess()(x)
        theta = theta - (self.fit.y(theta) - x) / self._dy(theta)
        return self.ratio * (theta - self.theta_ref)

    def range_error(self, x_min: float, x_max: float) -> str | None:
        if self.coordinates == "crank":
            return None
        ends = sorted(float(self.fit.y(t)) for t in self.crank_range)
        scale = 1e3 if self.load_unit == "m" else 180 / math.pi
        unit = "mm" if self.load_unit == "m" else "deg"
        for x in (x_min, x_max):
            if not ends[0] - 1e-12 <= x <= ends[1] + 1e-12:
                a, b = (math.degrees(t) for t in self.crank_range)
                return (f"the position {x * scale:.6g} {unit} of {self.output} is outside {ends[0] * scale:.6g}.."
                        f"{ends[1] * scale:.6g} {unit}, where the crank turns from {a:.4g} to {b:.4g} deg on one branch "
                        f"of the output, {DEAD_CENTRE_MARGIN_DEG:g} deg from its extremes")
        return None

    def smallest_index(self) -> float:
        """The smallest transmission index of the linkage over the crank range (a turning crank: the whole turn)."""
        if self.crank_range is None:
            return float(self.fit.index.min())
        th = self.fit.theta
        a, b = self.crank_range
        inside = ((th - a) % (2 * math.pi)) <= (b - a)
        return float(self.fit.index[inside].min()) if inside.any() else float(self.fit.index.min())

    def facts(self):
        if self.coordinates == "crank":
            where = [("the load", "the crank (its angle designed; it turns)")]
        else:
            a, b = (math.degrees(t) for t in self.crank_range)
            where = [("linkage output (the load)", self.output), ("crank range [deg]", f"{a:.4g} to {b:.4g}")]
        return where + [("gear ratio [motor turns per crank turn]", self.ratio),
                ("series of the closure [harmonics; largest relative error]",
                 f"{self.fit.y.harmonics}; {self.fit.error:.1e}")]

    def load_switches(self) -> tuple[float, ...]:
        """Where a process load jumps: the start of its window where it starts above zero, its end where it
        ends above zero (the beat-up: 1961 N at 360 deg, none after); as crank angles in crank coordinates
        (every turn the stroke may reach), as output positions on the branch in output coordinates."""
        angles = [a for load in self.linkage.loads
                  for a, f in ((load.start, load.force_start), (load.end, load.force_end)) if f != 0]
        if self.coordinates == "crank":
            return tuple(a + 2 * math.pi * k for a in angles for k in range(-2, 3))
        a, b = self.crank_range
        inside = [a + (t - a) % (2 * math.pi) for t in angles]
        return tuple(float(self.fit.y(t)) for t in inside if t <= b)

    def same_position(self, x: float, switch: float) -> bool:
        if self.coordinates == "crank":  # modulo a turn
            d = (x - switch) % (2 * math.pi)
            return min(d, 2 * math.pi - d) <= 1e-9
        return super().same_position(x, switch)

    # -- the links' dynamics on the motor shaft ----------------------------------------------------------
    def inertia_at(self, phi):
        theta = self.crank_angle(phi)
        return self.inertia + self.fit.J(theta) / self.ratio**2

    def own_terms(self, phi, omega, eps) -> dict:
        i = self.ratio
        theta = self.crank_angle(phi if isinstance(phi, (ca.SX, ca.MX)) else np.asarray(phi, dtype=float))
        out = {"inertia": self.inertia_at(phi) * eps + 0.5 * self._dJ(theta) / i**3 * omega**2}
        if self.linkage.gravity:
            out["linkage gravity"] = self.fit.dV(theta) / i
        for load, unit in zip(self.linkage.loads, self.fit.units):
            out[load.name] = -load_magnitude(load, theta) * unit(theta) / i
        return out

    # numbers: the series in numpy, without a CasADi call per sample
    def transfer(self, phi):
        theta, i = self.crank_angle(np.asarray(phi, dtype=float)), self.ratio
        if self.coordinates == "crank":
            return theta, np.full_like(theta, 1 / i), np.zeros_like(theta)
        return self.fit.y(theta), self._dy(theta) / i, self._d2y(theta) / i**2

    def motor_angle(self, x):
        """On the branch: linear interpolation of the sampled output, then Newton steps on the series."""
        x = np.asarray(x, dtype=float)
        if self.coordinates == "crank":
            return self.ratio * (x - self.theta_ref)
        grid_x, grid_theta = self._inverse_grid()
        theta = np.interp(x, grid_x, grid_theta)
        for _ in range(4):
            theta = theta - (self.fit.y(theta) - x) / self._dy(theta)
        return self.ratio * (theta - self.theta_ref)

    def with_gearbox(self, entry) -> "LinkageTransmission":
        """The same linkage with the catalogue's gearbox ``entry`` (drive/gearboxes.py) between motor and crank."""
        return self.replaced(ratio=float(entry.ratio), inertia=float(entry.inertia), gearbox=entry.name)

    def analysis(self, problem, with_dynamics: bool = False) -> dict | None:
        """The linkage with its crank turning at the constant speed of one turn a machine cycle (linkage/summary.py:
        structure, every output's swing, near-dwells and asymmetry, the transmission index against its limit; with
        ``with_dynamics`` the crank torque checked by Newton-Euler); None where the crank oscillates on a branch."""
        if self.coordinates != "crank":
            return None
        from .summary import measures, summarize

        summary = summarize(self.at_constant_speed(problem), with_dynamics=with_dynamics)
        return {**summary, "measures": measures(summary, self.output)}

    def at_constant_speed(self, problem):
        """The linkage of ``problem`` with its crank at the constant speed of one turn a cam cycle, as the linkage
        package analyses it (:class:`~strokeopt.linkage.files.LinkageProblem`)."""
        from .files import LinkageProblem

        turns = problem.timing.cam_revolutions_per_stitch   # crank turns a machine cycle
        return LinkageProblem(str(problem.file), problem.name, problem.description, self.linkage, problem.spm * turns,
                              self.min_transmission_index, self.near_dwell_pct, self.samples,
                              dict(problem.data.get("synthesis") or {}))

    def __repr__(self) -> str:
        return f"LinkageTransmission(output={self.output!r}, ratio={self.ratio:g}, harmonics={self.fit.y.harmonics})"


def _blamed(fields, exc):
    """``exc`` naming what the user set with --set where that, not the field it names, is the cause: a joint's
    coordinate or the reference angle (linkage/files.py's rule for `strokeopt linkage`)."""
    from .files import blame_the_set

    if any(f.startswith("timing.") for f in fields.overridden) and "timing." in exc.field:
        return exc   # the --set of [timing] is named already (check_reach)
    return blame_the_set(exc, {"transmission": fields.data}, fields.overridden)


def read_linkage_transmission(cls, fields, timing) -> LinkageTransmission:
    """``[transmission] type = "linkage"`` of a problem: the linkage (joints, links, crank, outputs, loads as a
    linkage file states them), ``output`` (the load: default the first), ``ratio`` and ``gear_inertia_kg_cm2``
    of a gearbox between the motor and the crank, ``gravity_m_s2`` (along -y of the linkage's frame),
    ``crank_range_deg`` (the branch) and ``angles`` (samples a turn)."""
    from .files import read_linkage

    # a gearbox of 0.1 (a step-up) to 1000 motor turns per crank turn, its inertia as Gearbox's; gravity as the
    # linkage file's (0: none, 9.81 along -y); the branch within one turn
    ratio = fields.number("ratio", 1.0, min=0.1, max=1000.0)
    gear = fields.number("gear_inertia_kg_cm2", 0.0, min=0.0, max=1e6) * 1e-4
    gravity = fields.number("gravity_m_s2", 0.0, min=0.0, max=20.0)
    coordinates = fields.string("coordinates", "output", choices=COORDINATES)
    crank_range = fields.raw("crank_range_deg", None)
    if coordinates == "crank" and crank_range is not None:
        raise fields.error("crank_range_deg", "is the branch an output's motion keeps to; with coordinates = "
                                              "\"crank\" the crank turns")
    if crank_range is not None and not (isinstance(crank_range, list) and len(crank_range) == 2 and
                                        all(isinstance(c, (int, float)) and math.isfinite(c) for c in crank_range)
                                        and 0 < abs(crank_range[1] - crank_range[0]) < 360):
        raise fields.error("crank_range_deg", "must be [from, to] in deg of crank angle, less than a turn apart")
    try:
        linkage, (index_min, dwell_pct, angles) = read_linkage(fields, fields.file, "linkage", gravity)
    except ProblemError as exc:
        raise _blamed(fields, exc) from None
    names = [o.name for o in linkage.outputs]
    if not names:
        raise fields.error("outputs", "a linkage that drives a load names it: add [[transmission.outputs]]")
    output = fields.string("output", names[0], choices=tuple(names))
    kind = next(o.kind for o in linkage.outputs if o.name == output)
    unit = "rad" if kind == "angle" or coordinates == "crank" else "m"
    if coordinates == "crank" and unit != timing.unit:
        raise fields.error("coordinates", "\"crank\": [timing] states the crank's angles in deg, not positions in mm")
    if unit != timing.unit:
        raise fields.error("output", f"{output!r} is {'an angle' if unit == 'rad' else 'a length (' + kind + ')'}: "
                                     f"[timing] states its positions in {'deg' if unit == 'rad' else 'mm'}, not in "
                                     f"{'deg' if timing.unit == 'rad' else 'mm'}")
    try:
        tr = cls(linkage, output, ratio, gear, angles,
                 None if crank_range is None else tuple(math.radians(c) for c in crank_range), coordinates)
    except ProblemError as exc:   # the closure refused (a dead centre, no closure): blame a --set geometry
        raise _blamed(fields, exc) from None
    except ValueError as exc:
        if crank_range is not None and "branch" in str(exc):
            raise _blamed(fields, fields.error("crank_range_deg", str(exc))) from None
        raise _blamed(fields, fields.error("angles", f"{exc}: the linkage's output or dynamics change too sharply for "
                                                     f"{angles} samples a turn (a link near a dead centre); more "
                                                     "samples a turn (angles) resolve it")) from None
    try:
        check_reach(tr, fields, "crank_range_deg" if crank_range is not None else "output", timing,
                    "positions within the branch, or another crank_range_deg")
        smallest = tr.smallest_index()
        # on a branch the design chooses, refused here; a crank that turns passes every pose of the file's linkage,
        # judged by its analysis (kinematics, size and report exit 1 below the limit)
        if smallest < index_min and coordinates == "output":
            raise fields.error("min_transmission_index", f"the linkage's transmission index falls to {smallest:.3g} "
                                                         f"over the crank range, below {index_min:g}")
    except ProblemError as exc:
        raise _blamed(fields, exc) from None
    fields.finish()
    tr.min_transmission_index, tr.near_dwell_pct = index_min, dwell_pct
    return tr

