"""Cam tables a controller loads, and the check that what it interpolates is the stroke that was verified.

A cam table is the motor angle (the slave, deg) over the cam angle (the master, deg; one cam cycle = 360 deg)
at equidistant master points. Each format is what a family of controllers reads, and each names how that
controller fills the gaps between the points:

=============  ==============================================================================  =============
format         what it holds                                                                    interpolation
=============  ==============================================================================  =============
``csv``        every column of ``cam_table.csv`` (as ``solve --out`` writes it)                linear
``xyva``       master, slave, dslave/dmaster, d2slave/dmaster2 (CODESYS ``MC_CAM_REF`` points)   quintic
``poly5``      motion-function points with their type ``Polynomial5`` (TwinCAT)                quintic
``segments``   one polynomial per segment: ``slave = c0 + c1 u + ... + c5 u^5``, u in [0, 1]  quintic
=============  ==============================================================================  =============

"quintic": the fifth-order polynomial between two points that meets position, velocity and acceleration at
both (the ``Polynomial5`` segment type of TwinCAT and of CODESYS's XYVA tables). Every format is written as
segments (:func:`segments`), read back as segments (:func:`read_segments`), and checked as segments
(:func:`deviation`): one mechanism, four layouts. :func:`segment_stroke` makes the segments the stroke a
drive would run, as one CasADi expression (``floor`` picks the segment), so the verified pipeline can judge it.
"""

from __future__ import annotations

import csv
import io
import math
from dataclasses import dataclass
from pathlib import Path

import casadi as ca
import numpy as np

from ..errors import ProblemError
from ..motion.stroke import Piece, StrokeFunction

#: format -> (interpolation, what it is, for --help); the names are design.transcription.settings.CAM_TABLE_FORMATS,
#: the ones a problem file's ``[design] cam_tables`` may ask for
FORMATS = {
    "csv": ("linear", "every column of cam_table.csv at equidistant master positions; linear between them"),
    "xyva": ("quintic", "master, slave, velocity and acceleration per point (CODESYS MC_CAM_REF XYVA); fifth-order "
                        "polynomials between them"),
    "poly5": ("quintic", "motion-function points of type Polynomial5 (TwinCAT): position, velocity, acceleration"),
    "segments": ("quintic", "one fifth-order polynomial per segment, c0..c5 in the segment's normalised master"),
}
#: The number of points a table may have: divisors of 36000, so every point sits on a 0.01 deg master position.
POINT_CHOICES = (36, 40, 45, 48, 60, 72, 80, 90, 100, 120, 144, 180, 200, 240, 300, 360, 400, 450, 480, 600, 720,
                 900, 1200, 1440, 1800, 2400, 3600, 4800, 7200, 9000, 12000, 18000, 36000)
#: Samples per segment of the check (the midpoint among them, where linear interpolation errs most).
CHECK_SAMPLES = 8


@dataclass(frozen=True)
class Segments:
    """A quantity over one cam cycle as ``n`` polynomial segments of the master (deg, one cycle = 360).

    ``coeffs[i]`` are ``c0..c5`` of ``value = sum c_k u^k`` on segment ``i``, ``u`` its normalised master
    position; linear segments have ``c2..c5 = 0``. ``breaks``: the ``n + 1`` master positions the segments
    join at (None: equidistant, ``i * 360/n``)."""

    coeffs: np.ndarray  # (n, 6)
    breaks: np.ndarray | None = None

    @property
    def n(self) -> int:
        return self.coeffs.shape[0]

    @property
    def step_deg(self) -> float:
        return 360.0 / self.n

    @property
    def edges(self) -> np.ndarray:
        return np.arange(self.n + 1) * self.step_deg if self.breaks is None else np.asarray(self.breaks, float)

    def evaluate(self, master_deg) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """The value, d/dmaster and d2/dmaster2 (per deg, per deg^2) at ``master_deg`` (mod 360)."""
        m = np.mod(np.atleast_1d(np.asarray(master_deg, float)), 360.0)
        edges = self.edges
        idx = np.clip(np.searchsorted(edges, m, side="right") - 1, 0, self.n - 1)
        width = np.diff(edges)[idx]
        u = (m - edges[idx]) / width
        c = self.coeffs[idx]
        powers = u[:, None] ** np.arange(6)
        p = np.sum(c * powers, axis=1)
        d1 = np.sum(c[:, 1:] * np.arange(1, 6) * powers[:, :5], axis=1) / width
        d2 = np.sum(c[:, 2:] * np.array([2, 6, 12, 20]) * powers[:, :4], axis=1) / width**2
        return p, d1, d2


def exact_slave(design, master_deg) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The verified design's motor angle [deg] and its first two derivatives over the master [deg/deg, deg/deg^2]
    at ``master_deg`` (one cam cycle = 360 deg), through the design's transmission."""
    from .design_file import design_transmission

    period = design.stroke.period
    t = np.asarray(master_deg, float) / 360.0 * period
    k = design.stroke.evaluate(t)
    phi, omega, alpha = design_transmission(design).motor_kinematics(k.s, k.v, k.a)
    dt = period / 360.0  # seconds per master deg
    return np.degrees(phi), np.degrees(omega) * dt, np.degrees(alpha) * dt**2


def segments(points, interpolation: str) -> Segments:
    """Segments through ``points = (slave, d1, d2)`` at ``n + 1`` equidistant master positions (the last closes
    the cycle): straight lines, or the quintic that meets position, velocity and acceleration at both ends."""
    p, v, a = (np.asarray(x, float) for x in points)
    n = len(p) - 1
    h = 360.0 / n
    dp = p[1:] - p[:-1]
    c = np.zeros((n, 6))
    c[:, 0] = p[:-1]
    if interpolation == "linear":
        c[:, 1] = dp
        return Segments(c)
    v0, v1, a0, a1 = v[:-1] * h, v[1:] * h, a[:-1] * h**2, a[1:] * h**2
    c[:, 1] = v0
    c[:, 2] = a0 / 2
    c[:, 3] = 10 * dp - 6 * v0 - 4 * v1 - 1.5 * a0 + 0.5 * a1
    c[:, 4] = -15 * dp + 8 * v0 + 7 * v1 + 1.5 * a0 - a1
    c[:, 5] = 6 * dp - 3 * v0 - 3 * v1 - 0.5 * a0 + 0.5 * a1
    return Segments(c)


def design_segments(design, fmt: str, n: int) -> tuple[Segments, tuple]:
    """The segments of format ``fmt`` with ``n`` points a cycle, and the points themselves."""
    master = np.arange(n + 1) * (360.0 / n)
    points = exact_slave(design, master)
    return segments(points, FORMATS[fmt][0]), points


@dataclass(frozen=True)
class Deviation:
    """The largest deviation of a table's interpolation from the verified stroke over one cycle."""

    position_deg: float        # motor angle
    position_load: float       # the load's position [m, or rad for a rotary load], through the local ratio
    velocity_rpm: float        # motor speed at the design's rate
    acceleration_rad_s2: float  # motor acceleration at the design's rate
    acceleration_share: float  # of the stroke's peak motor acceleration


def deviation(design, table: Segments) -> Deviation:
    """How far the table's interpolation lies from the verified stroke, on ``CHECK_SAMPLES`` points a segment."""
    from .design_file import design_transmission

    u = (np.arange(CHECK_SAMPLES) + 0.5) / CHECK_SAMPLES
    master = ((np.arange(table.n)[:, None] + u[None, :]) * table.step_deg).ravel()
    exact = exact_slave(design, master)
    approx = table.evaluate(master)
    dp, dv, da = (np.abs(x - y) for x, y in zip(approx, exact))
    period = design.stroke.period
    per_s = 360.0 / period  # master deg per second
    # the load's deviation: the motor angle's over the local ratio dphi/ds (motor_kinematics at unit speed)
    t = master / 360.0 * period
    k = design.stroke.evaluate(t)
    _, ratio, _ = design_transmission(design).motor_kinematics(k.s, np.ones_like(k.s), np.zeros_like(k.s))
    load = np.radians(dp) / np.maximum(np.abs(ratio), 1e-300)
    accel = np.radians(da) * per_s**2
    peak = float(np.max(np.abs(np.radians(exact[2]) * per_s**2))) or 1.0
    return Deviation(float(np.max(dp)), float(np.max(load)), float(np.max(dv)) * per_s / 6.0,
                     float(np.max(accel)), float(np.max(accel)) / peak)


def points_needed(design, fmt: str, tolerance_load: float) -> int | None:
    """The fewest points (of :data:`POINT_CHOICES`) whose table meets ``tolerance_load`` in the load's position
    [m or rad]; None when even the most does not."""
    meets = lambda n: deviation(design, design_segments(design, fmt, n)[0]).position_load <= tolerance_load  # noqa: E731
    if not meets(POINT_CHOICES[-1]):
        return None
    lo, hi = -1, len(POINT_CHOICES) - 1  # the deviation falls as the points grow: bisect for the fewest that meet it
    while hi - lo > 1:
        mid = (lo + hi) // 2
        lo, hi = (lo, mid) if meets(POINT_CHOICES[mid]) else (mid, hi)
    return POINT_CHOICES[hi]


#: The position tolerance a table is written to by default: 0.001 of the load's unit (1 um, or 0.001 deg rotary).
DEFAULT_TOLERANCE = 1e-3


def default_tolerance(design) -> float:
    """:data:`DEFAULT_TOLERANCE` in the load's SI unit (m, or rad for a rotary load)."""
    return math.radians(DEFAULT_TOLERANCE) if design.problem.timing.rotary else DEFAULT_TOLERANCE * 1e-3


def write_tables(design, out_dir: Path, formats, header: list[str] | None = None) -> list[tuple[Path, int]]:
    """``solve --out``: ``cam_<format>.csv`` of each of ``formats`` in ``out_dir``, each with the fewest points
    within :func:`default_tolerance`; returns (path, points) pairs."""
    from .design_file import CamTableSpec, cam_table_header

    written = []
    for fmt in formats:
        n = points_needed(design, fmt, default_tolerance(design)) or POINT_CHOICES[-1]
        path = Path(out_dir) / f"cam_{fmt}.csv"
        write_table(design, fmt, n, path, header or cam_table_header(design, CamTableSpec(360.0 / n)))
        written.append((path, n))
    return written


# --------------------------------------------------------------------------- writing and reading the formats

def write_table(design, fmt: str, n: int, path: Path, header: list[str]) -> None:
    """Write the table of ``fmt`` with ``n`` points a cycle to ``path`` (``#`` lines: ``header``, then what
    the columns are and how the controller interpolates)."""
    from .design_file import CamTableSpec, cam_table_csv

    if fmt == "csv":
        path.write_text(cam_table_csv(design, CamTableSpec(360.0 / n)), encoding="utf-8")
        return
    table, (p, v, a) = design_segments(design, fmt, n)
    master = np.arange(n + 1) * (360.0 / n)
    lines = [f"# {h}" for h in header]
    lines.append(f"# interpolation: {FORMATS[fmt][1]}")
    if fmt == "xyva":
        lines.append("# derivatives over the master: velocity deg/deg, acceleration deg/deg^2")
        lines.append("master_deg,slave_deg,slave_velocity_deg_per_deg,slave_acceleration_deg_per_deg2")
        lines += [f"{m:.6f},{x:.10f},{y:.12g},{z:.12g}" for m, x, y, z in zip(master, p, v, a)]
    elif fmt == "poly5":
        lines.append("# each point's function_type is the segment that starts there (the last ends the cycle)")
        lines.append("point,function_type,master_position_deg,slave_position_deg,slave_velocity_deg_per_deg,"
                     "slave_acceleration_deg_per_deg2")
        lines += [f"{i},{'Polynomial5' if i < n else 'Undefined'},{m:.6f},{x:.10f},{y:.12g},{z:.12g}"
                  for i, (m, x, y, z) in enumerate(zip(master, p, v, a))]
    else:
        lines.append("# slave_deg = c0 + c1 u + c2 u^2 + c3 u^3 + c4 u^4 + c5 u^5, "
                     "u = (master - master_start)/(master_end - master_start)")
        lines.append("segment,master_start_deg,master_end_deg,c0_deg,c1_deg,c2_deg,c3_deg,c4_deg,c5_deg")
        lines += [f"{i},{master[i]:.6f},{master[i + 1]:.6f}," + ",".join(f"{c:.12g}" for c in row)
                  for i, row in enumerate(table.coeffs)]
    path.write_text("\n".join(lines) + "\n", encoding="utf-8")


def _rows(path: Path) -> tuple[list[str], list[list[str]]]:
    text = [line for line in path.read_text(encoding="utf-8").splitlines() if line.strip() and not line.startswith("#")]
    if not text:
        raise ProblemError(str(path), "", "holds no table (only comments)")
    rows = list(csv.reader(io.StringIO("\n".join(text))))
    return [c.strip() for c in rows[0]], rows[1:]


def _column(path, names, rows, name) -> np.ndarray:
    if name not in names:
        raise ProblemError(str(path), name, f"no such column (the file has {', '.join(names)})")
    i = names.index(name)
    try:
        values = np.array([float(r[i]) for r in rows])
    except (ValueError, IndexError):
        raise ProblemError(str(path), name, "holds a value that is not a number") from None
    if not np.all(np.isfinite(values)):
        raise ProblemError(str(path), name, "holds a value that is not finite")
    return values


def read_segments(path: Path, fmt: str) -> Segments:
    """Read a table of ``fmt`` back as the segments its controller interpolates."""
    names, rows = _rows(path)
    col = lambda name: _column(path, names, rows, name)  # noqa: E731
    if fmt == "csv":
        master, slave = col("cam_angle_deg"), col("motor_angle_deg")
        closed = np.append(slave, slave[0])  # the cycle closes on its first point
        return _checked(path, master, segments((closed, 0 * closed, 0 * closed), "linear"), closed=False)
    if fmt == "segments":
        master = col("master_start_deg")
        coeffs = np.column_stack([col(f"c{k}_deg") for k in range(6)])
        return _checked(path, master, Segments(coeffs), closed=False)
    prefix = "master_position_deg" if fmt == "poly5" else "master_deg"
    slave = "slave_position_deg" if fmt == "poly5" else "slave_deg"
    master = col(prefix)
    p, v, a = col(slave), col("slave_velocity_deg_per_deg"), col("slave_acceleration_deg_per_deg2")
    return _checked(path, master, segments((p, v, a), "quintic"), closed=True)


def _checked(path, master, table: Segments, closed: bool) -> Segments:
    """The master positions are the equidistant ones the table's segments assume."""
    n = table.n
    expect = np.arange(n + 1 if closed else n) * (360.0 / n)
    if len(master) != len(expect) or np.max(np.abs(master - expect)) > 1e-5:
        raise ProblemError(str(path), "master", f"the master positions are not {n} equidistant steps over 360 deg "
                                                "(a table strokeopt wrote, or one of the same layout)")
    return table


# --------------------------------------------------------------------------- the table as the stroke a drive runs

def segments_expression(table: Segments, master):
    """The segments' value as a CasADi expression of the symbol ``master`` [deg, in 0..360]: the segment index
    (``floor`` on an equidistant table, a count of the breaks passed on another; either has derivative zero)
    picks each coefficient from a lookup, so velocity and acceleration are the polynomials' own."""
    n = table.n
    if table.breaks is None:
        idx = ca.fmin(ca.fmax(ca.floor(master / table.step_deg), 0), n - 1)
        start, width = idx * table.step_deg, table.step_deg
    else:
        edges = table.edges
        idx = ca.fmin(sum(master >= float(e) for e in edges[1:-1]), n - 1) if n > 1 else 0 * master
        start, width = _lookup("start", edges[:-1], idx), _lookup("width", np.diff(edges), idx)
    u = (master - start) / width
    return sum(_lookup(f"c{k}", table.coeffs[:, k], idx) * u**k for k in range(6))


def _lookup(name: str, values: np.ndarray, idx):
    """``values[idx]`` for a symbolic whole ``idx`` (a linear interpolant read at its nodes)."""
    values = np.asarray(values, float)
    if len(values) == 1:
        values = np.array([values[0], values[0]])
    return ca.interpolant(name, "linear", [list(range(len(values)))], values.tolist())(idx)


def segment_stroke(design, table: Segments, label: str) -> StrokeFunction:
    """The stroke the drive runs from ``table`` (the motor angle, deg): the load's position through the design's
    transmission of the interpolated motor angle, one CasADi expression over the cycle."""
    from .design_file import design_transmission

    period = design.stroke.period
    position = design_transmission(design).position
    return _interval_stroke(design.problem, design.spm, lambda t: position(
        segments_expression(table, t * (360.0 / period)) * (math.pi / 180.0)), label)


def _interval_stroke(problem, spm: float, position, label: str) -> StrokeFunction:
    """A stroke of ``problem`` at ``spm`` whose position is the CasADi expression ``position(t)`` of the cycle
    time, cut into a piece per interval of the timing (so every per-interval table reads it as a law's)."""
    sch = problem.timing.schedule(spm)
    tau = ca.SX.sym("tau")
    pieces = [Piece(float(t0), float(dur), ca.Function("stroke_table", [tau], [position(float(t0) + tau)]), label)
              for t0, dur in zip(sch.t_start, sch.duration)]
    return StrokeFunction(sch.period, pieces, label)


# --------------------------------------------------------------------------- a stroke made elsewhere, as a table

#: The master columns a stroke table may name (cam angle, deg, one cam cycle = 360).
MASTER_COLUMNS = ("cam_angle_deg", "master_deg", "master_position_deg")
#: The fewest points a stroke table may have (a cubic spline through fewer says little of a cycle).
STROKE_POINTS_MIN = 8


def read_stroke(path, problem, spm: float | None = None) -> StrokeFunction:
    """A motion made elsewhere as a stroke of ``problem`` at ``spm``: a CSV with a master column (cam angle,
    deg, from 0 up to below 360) and the load's position (``position_mm``, or ``position_deg`` for a rotary
    load), ``#`` lines ignored -- ``cam_table.csv`` of ``solve --out`` is one. The points are joined by the
    periodic cubic spline through them (position, speed and acceleration continuous over the cycle)."""
    from scipy.interpolate import CubicSpline

    path = Path(path)
    if not path.is_file():
        raise ProblemError(str(path), "", "no such file (a CSV cam table: cam_angle_deg and position_mm columns)")
    names, rows = _rows(path)
    rotary = problem.timing.rotary
    master = next((n for n in MASTER_COLUMNS if n in names), None)
    if master is None:
        raise ProblemError(str(path), "master", f"no master column: name one of {', '.join(MASTER_COLUMNS)} (the "
                                                f"file has {', '.join(names)})")
    pos, other = ("position_deg", "position_mm") if rotary else ("position_mm", "position_deg")
    if pos not in names:
        why = f" ({problem.file} moves a {'rotary' if rotary else 'linear'} load)" if other in names else ""
        raise ProblemError(str(path), pos, f"no such column{why}; the file has {', '.join(names)}")
    angle, value = _column(path, names, rows, master), _column(path, names, rows, pos)
    if len(angle) < STROKE_POINTS_MIN:
        raise ProblemError(str(path), master, f"{len(angle)} points; a cycle needs at least {STROKE_POINTS_MIN}")
    if angle[0] != 0.0 or np.any(np.diff(angle) <= 0) or angle[-1] >= 360.0:
        raise ProblemError(str(path), master, "must start at 0 and rise strictly to below 360 deg (one cam cycle; "
                                              "the cycle closes on the first point)")
    x = np.append(angle, 360.0)
    y = np.append(value, value[0]) * (math.pi / 180.0 if rotary else 1e-3)
    spline = CubicSpline(x, y, bc_type="periodic")
    width = np.diff(x)
    coeffs = np.zeros((len(angle), 6))
    for k in range(4):  # scipy holds (x - x_i)^(3 - row); the segments hold u^k with u = (x - x_i)/width
        coeffs[:, k] = spline.c[3 - k] * width**k
    table = Segments(coeffs, None if np.allclose(width, width[0], rtol=0, atol=1e-9) else x)
    spm = problem.spm if spm is None else float(spm)
    period = problem.timing.period(spm)
    return _interval_stroke(problem, spm, lambda t: segments_expression(table, t * (360.0 / period)),
                            f"table {path.name}")
