"""Classic motion laws (cam laws) on the unit interval.

A law is the normalised stroke ``y(x)`` of a rise, ``x`` in [0, 1] the
normalised time (or cam angle) of the move and ``y(0) = 0``, ``y(1) = 1``.
A move of stroke ``h`` and duration ``T`` is ``s = s0 + h*y(t/T)``, so
``v = h/T*y'``, ``a = h/T^2*y''``, ``jerk = h/T^3*y'''`` (thesis eqs. 4.13-4.18).

Each law is written once, with CasADi operations on a symbol, and so evaluates
on floats, numpy arrays and CasADi SX/MX alike; its derivatives come from
CasADi's algorithmic differentiation, and its characteristic values
``C_v = max|y'|``, ``C_a = max|y''|``, ``C_j = max|y'''|`` are computed from
them, never typed in.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from functools import cache

import casadi as ca
import numpy as np

from .._casadi import evaluate
from ..errors import ProblemError
from .characteristics import Characteristics, characteristics_of
from .pieces import joints, mirrored_law, ramp_half, scca_half, with_constant_speed


def _parabolic(x):
    # constant acceleration +4 / -4, switching at the middle
    return ca.if_else(x < 0.5, 2 * x**2, 1 - 2 * (1 - x) ** 2)


def _cubic(x):
    # 3-2 polynomial: linear acceleration 6 - 12x
    return 3 * x**2 - 2 * x**3


def _cosine(x):
    # simple harmonic motion
    return (1 - ca.cos(math.pi * x)) / 2


def _sine(x):
    # cycloidal motion
    return x - ca.sin(2 * math.pi * x) / (2 * math.pi)


def _poly5(x):
    # 3-4-5 polynomial: v = a = 0 at both ends
    return 10 * x**3 - 15 * x**4 + 6 * x**5


def _poly7(x):
    # 4-5-6-7 polynomial: v = a = jerk = 0 at both ends
    return 35 * x**4 - 84 * x**5 + 70 * x**6 - 20 * x**7


def _modified_sine(x, chi):
    """Modified sine with shape parameter chi (thesis section 4.4).

    Acceleration: a quarter sine rising to the peak P over [0, chi], a half
    cosine from +P to -P over [chi, 1-chi], a quarter sine back to zero over
    [1-chi, 1]. P follows from y(1) = 1. chi = 1/8 is the classic modified
    sine, chi = 1/4 the cycloid, chi -> 0 the cosine law.
    """
    w = math.pi / (2 * chi)  # quarter-sine frequency
    span = 1 - 2 * chi  # length of the half-cosine segment
    W = math.pi / span if span > 0 else 0.0
    # y(1/2) = 1/2 fixes the peak: P * [(chi - 1/w)/w + span/(2w) + 1/W^2] = 1/2
    peak = 0.5 / ((chi - 1 / w) / w + span / (2 * w) + (1 / W**2 if span > 0 else 0.0))

    def rise(u):  # the first quarter sine, u in [0, chi]
        return peak / w * (u - ca.sin(w * u) / w)

    y_chi = peak / w * (chi - 1 / w)
    v_chi = peak / w
    u = x - chi
    middle = y_chi + v_chi * u + (peak / W**2 * (1 - ca.cos(W * u)) if span > 0 else 0.0)
    return ca.if_else(x < chi, rise(x), ca.if_else(x <= 1 - chi, middle, 1 - rise(1 - x)))


def _poly5_speeds(x, start_speed, end_speed):
    """VDI 2143's polynomial of degree 5 between given speeds: y(0) = 0, y(1) = 1, y'(0) = start_speed,
    y'(1) = end_speed (unit speeds: 1 is the move's mean speed), y'' = 0 at both ends. Both speeds 0: the 3-4-5
    polynomial (rest to rest); a move that starts or ends at a speed (rest to speed, speed to speed) is this."""
    a, b = 1.0 - start_speed, end_speed - start_speed
    a3, a4, a5 = np.linalg.solve([[1.0, 1.0, 1.0], [3.0, 4.0, 5.0], [6.0, 12.0, 20.0]], [a, b, 0.0])
    return start_speed * x + a3 * x**3 + a4 * x**4 + a5 * x**5


def _poly9(x):
    # 5-6-7-8-9 polynomial: v = a = jerk = snap = 0 at both ends
    return 126 * x**5 - 420 * x**6 + 540 * x**7 - 315 * x**8 + 70 * x**9


def _double_harmonic(x):
    # Rothbart's double harmonic: a rise that starts gently and ends hard (for a quick return; not symmetric)
    return (1 - ca.cos(math.pi * x)) / 2 - (1 - ca.cos(2 * math.pi * x)) / 8


def _scca(x, sine_share, constant_accel_share):
    return mirrored_law(x, scca_half(sine_share, constant_accel_share))


def _trapezoidal_velocity(x, constant_speed_share):
    return mirrored_law(x, with_constant_speed([("poly", 0.5, (1.0,))], constant_speed_share))


def _s_curve(x, ramp_share, constant_speed_share):
    return mirrored_law(x, with_constant_speed(ramp_half(ramp_share), constant_speed_share))


def _modified_sine_cv(x, chi, constant_speed_share):
    return mirrored_law(x, with_constant_speed(scca_half(2 * chi, 0.0), constant_speed_share))


def _points(x, points_x, points_y, rest_order):
    """A rise through given points: the B-spline of degree ``2 rest_order + 1`` through ``(0, 0)``, the points and
    ``(1, 1)`` whose first ``rest_order`` derivatives vanish at both ends (it meets the dwells as a law of that
    rest order does), as its polynomial pieces."""
    from scipy.interpolate import PPoly, make_interp_spline

    r = int(rest_order)
    xs, ys = np.array([0.0, *points_x, 1.0]), np.array([0.0, *points_y, 1.0])
    ends = [(k, 0.0) for k in range(1, r + 1)]
    pp = PPoly.from_spline(make_interp_spline(xs, ys, k=2 * r + 1, bc_type=(ends, ends)))
    keep = [i for i in range(len(pp.x) - 1) if pp.x[i + 1] > pp.x[i]]
    expr = None
    for i in reversed(keep):
        u = x - pp.x[i]
        piece = sum(float(c) * u ** (len(pp.c) - 1 - k) for k, c in enumerate(pp.c[:, i]))
        expr = piece if expr is None else ca.if_else(x < pp.x[i + 1], piece, expr)
    return expr


@dataclass(frozen=True)
class _LawSpec:
    title: str
    shape: object
    params: dict = field(default_factory=dict)  # name -> (default, low, high, low_open)
    breaks: object = lambda **p: ()  # interior points where the pieces join
    fixed: dict = field(default_factory=dict)  # a named member of a family: the family's parameters it fixes
    check: object = lambda **p: None  # a message where the parameters together are not a law
    symmetric: bool = True  # y(1 - x) = 1 - y(x)
    table: bool = False  # its parameters are a move's points (points_law), not numbers of a unit law


def _scca_check(sine_share, constant_accel_share):
    if sine_share + constant_accel_share > 1 + 1e-12:
        return (f"sine_share + constant_accel_share = {sine_share + constant_accel_share:g} is more than 1 "
                "(the two shares and the middle cosine's make up the move)")
    return None


#: A share of constant speed below 1: at 1 the move would have no time left to accelerate.
_CRUISE = (0.0, 0.0, 0.95, False)

_LAWS: dict[str, _LawSpec] = {
    "parabolic": _LawSpec("parabolic (constant acceleration)", _parabolic, breaks=lambda: (0.5,)),
    "cubic": _LawSpec("cubic 3-2 polynomial (linear acceleration)", _cubic),
    "cosine": _LawSpec("cosine (simple harmonic)", _cosine),
    "modified_sine": _LawSpec(
        "modified sine",
        _modified_sine,
        # chi in [0.001, 0.25]: 0.25 is the cycloid; the peak jerk grows as 1/chi, and below 0.001 the law is
        # the cosine law with a jerk spike a thousand times its own (chi -> 0 overflows it)
        params={"chi": (0.125, 0.001, 0.25, False)},
        breaks=lambda chi: (chi, 1 - chi),
    ),
    "sine": _LawSpec("sine (cycloidal; VDI 2143's inclined sine at rest-to-rest)", _sine),
    "poly5": _LawSpec("polynomial 3-4-5", _poly5),
    "poly7": _LawSpec("polynomial 4-5-6-7", _poly7),
    "poly9": _LawSpec("polynomial 5-6-7-8-9", _poly9),
    "poly5_speeds": _LawSpec(
        "polynomial of degree 5 between speeds (VDI 2143 rest-to-speed, speed-to-speed)", _poly5_speeds,
        # unit speeds: 1 is the move's mean speed; a short move joined at speed to a long fast one meets many
        # times its own (10 deg in 90 joined at 1 deg/deg: 9); beyond 100 the move is no longer a move of its own
        params={"start_speed": (0.0, -100.0, 100.0, False), "end_speed": (0.0, -100.0, 100.0, False)},
        symmetric=False),
    "modified_trapezoid": _LawSpec(
        "modified trapezoid (cycloidal flanks, constant acceleration)", _scca,
        fixed={"sine_share": 0.25, "constant_accel_share": 0.5},
        breaks=lambda sine_share, constant_accel_share: joints(scca_half(sine_share, constant_accel_share))),
    "scca": _LawSpec(
        "sine-constant-cosine acceleration family", _scca,
        params={"sine_share": (0.25, 0.0, 1.0, False), "constant_accel_share": (0.5, 0.0, 1.0, False)},
        breaks=lambda sine_share, constant_accel_share: joints(scca_half(sine_share, constant_accel_share)),
        check=_scca_check),
    "trapezoidal_velocity": _LawSpec(
        "trapezoidal velocity (constant acceleration, cruise, constant deceleration)", _trapezoidal_velocity,
        params={"constant_speed_share": (1 / 3, *_CRUISE[1:])},
        breaks=lambda constant_speed_share: joints(
            with_constant_speed([("poly", 0.5, (1.0,))], constant_speed_share))),
    "trapezoidal_acceleration": _LawSpec(
        "trapezoidal acceleration (straight jerk ramps over 1/8 of the move)", _s_curve,
        fixed={"ramp_share": 0.5, "constant_speed_share": 0.0},
        breaks=lambda ramp_share, constant_speed_share: joints(
            with_constant_speed(ramp_half(ramp_share), constant_speed_share))),
    "s_curve": _LawSpec(
        "jerk-limited S-curve (trapezoidal acceleration, cruise)", _s_curve,
        # ramp_share: the share of each acceleration phase spent ramping it (1 = a triangle); a drive's
        # limits A and J over an acceleration phase of time t_a give ramp_share = 2*A/(J*t_a)
        params={"ramp_share": (0.5, 0.0, 1.0, True), "constant_speed_share": (1 / 3, *_CRUISE[1:])},
        breaks=lambda ramp_share, constant_speed_share: joints(
            with_constant_speed(ramp_half(ramp_share), constant_speed_share))),
    "modified_sine_cv": _LawSpec(
        "modified sine with constant velocity", _modified_sine_cv,
        params={"chi": (0.125, 0.001, 0.25, False), "constant_speed_share": (0.5, *_CRUISE[1:])},
        breaks=lambda chi, constant_speed_share: joints(
            with_constant_speed(scca_half(2 * chi, 0.0), constant_speed_share))),
    "double_harmonic": _LawSpec("double harmonic (gentle start, hard end)", _double_harmonic, symmetric=False),
    "points": _LawSpec("B-spline through a move's points", _points, symmetric=False, table=True,
                       breaks=lambda points_x, points_y, rest_order: tuple(points_x)),
}

#: Names of the laws: the thesis's seven in the order it compares them, then the cam handbooks' further ones.
LAW_NAMES = tuple(name for name, spec in _LAWS.items() if not spec.table)
#: What a move's ``law`` may name: the laws and ``points`` (a move's own points, :func:`points_law`).
LAW_CHOICES = tuple(_LAWS)
#: The laws a design is compared with (solve's table, the report, ``accuracy``): the thesis's seven and the
#: modified trapezoid, the cam law used most; every other law is one ``--law`` away.
COMPARED_LAWS = (*LAW_NAMES[:7], "modified_trapezoid")

#: Every parameter name any law takes (``chi``), for readers of problem files.
LAW_PARAMETERS = tuple(sorted({p for spec in _LAWS.values() if not spec.table for p in spec.params}))


class MotionLaw:
    """One classic motion law with fixed parameters.

    Call it on anything CasADi accepts (float, numpy array, SX, MX) to get
    ``y(x)``; :meth:`derivatives` gives ``y, y', y'', y''', y''''`` numerically.
    """

    def __init__(self, name: str, **params: float):
        spec = _LAWS[name]
        self.name = name
        self.title = spec.title
        self.params = dict(params)
        self._spec = spec
        x = ca.SX.sym("x")
        y = spec.shape(x, **spec.fixed, **params)
        ders = [y]
        for _ in range(4):
            ders.append(ca.jacobian(ders[-1], x))
        self._y = ca.Function(f"law_{name}", [x], [y])
        self._ders = ca.Function(f"law_{name}_ders", [x], ders)

    def __repr__(self) -> str:
        if self._spec.table:
            return f"MotionLaw('points', {len(self.params['points_x'])} points)"
        p = ", ".join(f"{k}={v:g}" for k, v in self.params.items())
        return f"MotionLaw({self.name!r}{', ' + p if p else ''})"

    def __eq__(self, other) -> bool:
        return isinstance(other, MotionLaw) and (self.name, self.params) == (other.name, other.params)

    def __hash__(self) -> int:
        return hash((self.name, tuple(sorted(self.params.items()))))

    @property
    def label(self) -> str:
        if self._spec.table:
            return f"points ({len(self.params['points_x'])} points, rest order {self.params['rest_order']:g})"
        p = ", ".join(f"{k} = {v:g}" for k, v in self.params.items())
        if self.name == "poly5_speeds" and self.params.get("start_speed") == self.params.get("end_speed") == 1:
            return f"constant speed ({self.name}, {p})"   # a move at its mean speed throughout: a turning crank
        return f"{self.name} ({p})" if p else self.name

    @property
    def breaks(self) -> tuple[float, ...]:
        """Interior points where the law's pieces join (where a derivative may jump)."""
        return tuple(self._spec.breaks(**self._spec.fixed, **self.params))

    def __call__(self, x):
        """y(x): numeric for numbers/arrays, symbolic for CasADi expressions."""
        if isinstance(x, (ca.SX, ca.MX)):
            return self._y(x)
        (out,) = evaluate(self._y, x)
        return float(out) if out.ndim == 0 else out

    def derivatives(self, x, order: int = 3) -> tuple[np.ndarray, ...]:
        """Numeric ``(y, y', ..., y^(order))`` at the points ``x`` (order <= 4)."""
        return tuple(evaluate(self._ders, np.atleast_1d(np.asarray(x, dtype=float)))[: order + 1])

    def symbolic_derivatives(self, x, order: int = 3):
        """``(y, y', ..., y^(order))`` as CasADi expressions of the symbol ``x``."""
        return tuple(self._ders(x)[: order + 1])

    @property
    def characteristics(self) -> Characteristics:
        return characteristics_of(self)


def make_law(name: str, *, where: tuple[str, str] = ("<law>", "law"), **params: float) -> MotionLaw:
    """Validated constructor: ``make_law("modified_sine", chi=0.095)``.

    ``where`` is ``(file, field)`` for the error message.
    """
    file, fld = where
    if name in _LAWS and _LAWS[name].table:
        raise ProblemError(file, fld, f"law {name!r} is a move's own points: give it on a [[timing.intervals]] row "
                                      "with angles_deg and positions_mm (or positions_deg)")
    if name not in _LAWS:
        import difflib

        close = difflib.get_close_matches(str(name), LAW_NAMES, n=1, cutoff=0.75)
        hint = f" (did you mean {close[0]!r}?)" if close else ""
        raise ProblemError(file, fld, f"unknown motion law {name!r}{hint}; choose one of {', '.join(LAW_NAMES)}")
    spec = _LAWS[name]
    unknown = set(params) - set(spec.params)
    if unknown:
        extra = ", ".join(sorted(unknown))
        allowed = ", ".join(spec.params) or "none"
        table = fld.rsplit(".", 1)[0] + "." if "." in fld else ""  # "motion.law" -> the parameter is "motion.chi"
        hint = (f": remove it with --set {table}{sorted(unknown)[0]}=null, or use --law {name}" if table else "")
        raise ProblemError(file, fld, f"law {name!r} takes no parameter {extra} (parameters: {allowed}){hint}")
    full = {}
    table = fld.rsplit(".", 1)[0] + "." if "." in fld else ""  # "motion.law" -> the parameter is "motion.chi"
    for pname, (default, lo, hi, lo_open) in spec.params.items():
        value = params.get(pname, default)
        if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
            raise ProblemError(file, table + pname, f"must be a number, got {value!r}")
        if (value <= lo if lo_open else value < lo) or value > hi:
            raise ProblemError(file, table + pname, f"{value!r} is out of range {'(' if lo_open else '['}{lo:g}, {hi:g}] for law {name!r}")
        full[pname] = float(value)
    problem_with_them = spec.check(**full)
    if problem_with_them:
        raise ProblemError(file, table + sorted(full)[-1], problem_with_them)
    return _cached_law(name, tuple(sorted(full.items())))


@cache
def _cached_law(name: str, params: tuple) -> MotionLaw:
    return MotionLaw(name, **dict(params))


def law_table(laws=None) -> list[dict]:
    """The laws with their characteristic values: ``laws`` (MotionLaw objects), by default every law at its
    default parameters."""
    rows = []
    for law in laws if laws is not None else [make_law(name) for name in LAW_NAMES]:
        name = law.name
        c = law.characteristics
        rows.append(
            {
                "law": name,
                "title": law.title,
                "params": law.params,
                "C_v": c.C_v,
                "C_a": c.C_a,
                "C_j": None if math.isinf(c.C_j) else c.C_j,
                "continuity": f"C{c.continuity}",
                "first_jump": c.first_jump,
            }
        )
    return rows


def compared_laws(own: MotionLaw, others=()) -> list[MotionLaw]:
    """The laws a design is compared with: :data:`COMPARED_LAWS`, the problem's own law with its parameters in
    its place, then ``others`` (the laws of single moves) that are not among them. A move's own points are
    not compared: they are that move's, not a law for every move."""
    laws = [own if name == own.name else make_law(name) for name in COMPARED_LAWS]
    for law in (own, *others):
        if law not in laws and not _LAWS[law.name].table:
            laws.append(law)
    return laws


#: The rest orders a points law may meet its dwells with: velocity (1), acceleration (2), jerk (3) zero at the ends.
POINTS_REST_ORDERS = (1, 2, 3)


def points_law(angles_deg, positions, span_deg: float, stroke: float, rest_order: int = 2, *,
               where: tuple[str, str] = ("<law>", ""), positions_key: str = "positions") -> MotionLaw:
    """The ``points`` law of a move of ``span_deg`` and ``stroke`` (both positive, in the file's unit): the
    travelled ``positions`` (0 .. stroke from the move's start) at ``angles_deg`` (cam angle from the move's
    start, strictly inside the move), joined by the B-spline of :func:`_points`. ``where``: (file, the row's
    path) for the error messages, which name ``angles_deg`` or ``positions_key``."""
    file, row = where
    name = lambda key: f"{row}.{key}" if row else key  # noqa: E731
    angles, pos = (_number_list(v, file, name(k)) for v, k in ((angles_deg, "angles_deg"), (positions, positions_key)))
    if not angles:
        raise ProblemError(file, name("angles_deg"), "needs at least one point inside the move")
    if len(angles) != len(pos):
        raise ProblemError(file, name(positions_key), f"{len(pos)} positions for {len(angles)} angles")
    x, y = np.asarray(angles) / span_deg, np.asarray(pos) / stroke
    if np.any(np.diff(x) <= 0) or x[0] <= 0 or x[-1] >= 1:
        raise ProblemError(file, name("angles_deg"), f"must rise strictly inside the move (0 < angle < {span_deg:g} "
                                                     "deg from its start)")
    if np.any(y <= 0) or np.any(y >= 1) or np.any(np.diff(y) < 0):
        raise ProblemError(file, name(positions_key), f"must rise from 0 to the stroke {stroke:g} (the travel from "
                                                    "the move's start, strictly between its ends)")
    if rest_order not in POINTS_REST_ORDERS:
        raise ProblemError(file, name("rest_order"), f"must be one of {POINTS_REST_ORDERS}, got {rest_order!r}")
    law = _cached_law("points", (("points_x", tuple(map(float, x))), ("points_y", tuple(map(float, y))),
                                 ("rest_order", float(rest_order))))
    grid = np.linspace(0.0, 1.0, 4001)
    speed = law.derivatives(grid, 1)[1]
    if np.min(speed) < -1e-9 * np.max(np.abs(speed)):
        back = grid[int(np.argmin(speed))] * span_deg
        raise ProblemError(file, name(positions_key), f"the spline through the points goes back near {back:.3g} deg "
                                                    "into the move: add points there or lower rest_order")
    return law


def _number_list(value, file: str, field: str) -> list[float]:
    if isinstance(value, np.ndarray):
        value = value.tolist()
    if not isinstance(value, (list, tuple)) or not all(
            isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v) for v in value):
        raise ProblemError(file, field, f"must be a list of finite numbers, got {value!r}")
    return [float(v) for v in value]
