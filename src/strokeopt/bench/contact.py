"""Benchmark of the contact model: one cycle of the release scene, CasADi CVODES against scipy Radau.

Both runs go through the same :func:`strokeopt.contact.simulate.integrate_scene` (the same scene
ODE, stroke restarts, scaling, output grid and event location); only the stepper differs: CasADi's
CVODES, or scipy's ``solve_ivp`` calling the scene's CasADi right-hand side and Jacobian from Python.
"""

from __future__ import annotations

import math
import warnings
from dataclasses import replace
from functools import partial

import casadi as ca
import numpy as np

from ..contact.simulate import SceneResult, SimulationOptions, integrate_scene, simulate_scene
from ..contact.stepper import REFINE_POINTS
from ..errors import SolverError
from ..files.problem_file import load_problem
from .registry import BenchResult, BenchRow, benchmark, best_time, reference_problem_path


BENCH_ACCURACY_M_S = 1e-3  # impact velocity accuracy both integrators must reach


class ScipyStepper:
    """The stepper of :func:`integrate_scene` (see :class:`~strokeopt.contact.simulate.CasadiStepper`)
    with scipy's ``solve_ivp`` (``method``, e.g. Radau); steps are counted as right-hand side calls."""

    def __init__(self, ode, grid, opts: SimulationOptions, scene: str, spm: float, method: str = "Radau"):
        from scipy.integrate import solve_ivp

        self._solve_ivp = solve_ivp
        self.ode, self.grid, self.scene, self.method = ode, grid, scene, method
        self.rtol, self.atol = opts.rtol, opts.atol
        self.name = f"scipy {method}"
        self.jac = ca.Function("scene_jacobian", [ode.dae["t"], ode.dae["x"], ode.dae["p"]],
                               [ca.jacobian(ode.dae["ode"], ode.dae["x"])])
        self.segment_steps = 0

    def _solve(self, pk, z0, span, t_eval):
        rhs, jac = self.ode.rhs, self.jac
        return self._solve_ivp(lambda s, y: np.asarray(rhs(s, y, pk)).ravel(), span, z0, method=self.method,
                               t_eval=t_eval, rtol=self.rtol, atol=self.atol, jac=lambda s, y: np.asarray(jac(s, y, pk)))

    def piece(self, k, piece, z, pk):
        sol = self._solve(pk, z, (0.0, 1.0), self.grid[1:])
        if not sol.success:
            raise SolverError(f"scipy {self.method} failed in piece {k + 1} of scene {self.scene!r}: {sol.message}")
        return sol.y, int(sol.nfev)

    def segment(self, pk, z0, sa, sb):
        sol = self._solve(list(pk), z0, (sa, sb), np.linspace(sa, sb, REFINE_POINTS + 1))
        if not sol.success:
            raise SolverError(f"scipy {self.method} failed refining an event of scene {self.scene!r}: {sol.message}")
        self.segment_steps += int(sol.nfev)
        return sol.y


def simulate_scene_scipy(problem, scene: str, spm: float | None = None, rtol: float = 1e-6, atol: float = 1e-7,
                         method: str = "Radau") -> SceneResult:
    """:func:`~strokeopt.contact.simulate.simulate_scene` (the problem's stroke, hard switches) with scipy's
    ``solve_ivp`` as the integrator: the reference peer of ``strokeopt bench``."""
    opts = SimulationOptions(rtol=rtol, atol=atol)
    result = integrate_scene(problem, scene, spm, None, opts, partial(ScipyStepper, method=method))
    result.options = replace(opts, method=f"scipy-{method}")
    return result


def _cvodes_against_scipy(problem, scene: str, spm, error, accuracy: float, what, reference):
    """One cycle of ``scene`` with CVODES at its default tolerance (best of 3, CPU) against scipy Radau at the
    loosest of rtol 1e-3, 1e-4, 1e-5 that reaches ``error(result, ref) <= accuracy``, both against a CVODES
    reference at rtol 1e-8. ``what(error)`` and ``reference(ref)`` are the rows' and the note's words.
    Returns (rows, notes, CVODES time, scipy time, CVODES error)."""
    ref = simulate_scene(problem, scene, spm, options=SimulationOptions(rtol=1e-8, atol=1e-9))
    runs = [simulate_scene(problem, scene, spm) for _ in range(3)]
    fast = min(r.cpu_time_s for r in runs)
    err_fast = error(runs[0], ref)
    rows = [BenchRow("CasADi CVODES, rtol 1e-5 (default), CPU", fast, what(err_fast))]
    notes = [f"reference: CVODES rtol 1e-8, {reference(ref)} ({ref.cpu_time_s:.2f} s CPU)"]
    slow = None
    for rtol in (1e-3, 1e-4, 1e-5):  # the loosest scipy tolerance that reaches the same accuracy
        with warnings.catch_warnings():  # Radau's step-size update divides by a zero error norm on long dwells
            warnings.simplefilter("ignore", RuntimeWarning)
            peer = simulate_scene_scipy(problem, scene, spm, rtol=rtol, atol=rtol / 10)
        err = error(peer, ref)
        rows.append(BenchRow(f"scipy solve_ivp Radau, rtol {rtol:g}, CPU", peer.cpu_time_s,
                             what(err) + ("" if err <= accuracy else " (not accurate enough)")))
        if err <= accuracy:
            slow = peer.cpu_time_s
            break
    if slow is None:
        notes.append(f"scipy Radau did not reach {what(accuracy)} down to rtol 1e-5; ratio against its last run")
        slow = rows[-1].seconds
    return rows, notes, fast, slow, err_fast


@benchmark("simulate_release", "one cycle of the needle-bar release scene at 600 spm (CasADi CVODES vs scipy Radau, "
                               "impact velocity to 1e-3 m/s)", target_s=0.5)
def _bench_simulate_release() -> BenchResult:
    problem = load_problem(reference_problem_path())

    def error(r, ref):
        v = r.metrics["impact_velocity_m_s"]
        return abs(v - ref.metrics["impact_velocity_m_s"]) if v is not None else math.inf

    rows, notes, fast, slow, err_fast = _cvodes_against_scipy(
        problem, "release", 600.0, error, BENCH_ACCURACY_M_S, lambda err: f"impact velocity error {err:.1e} m/s",
        lambda ref: f"impact velocity {ref.metrics['impact_velocity_m_s']:.5f} m/s")
    notes.append("same scene ODE, stroke restarts, scaling, output grid and event location for both; scipy calls the "
                 "CasADi right-hand side and Jacobian from Python; target: CasADi >= 20x faster")
    if err_fast > BENCH_ACCURACY_M_S:
        notes.append(f"CasADi default missed the accuracy: {err_fast:.1e} m/s")
    return BenchResult(rows=rows, measured_s=fast, ratio=slow / fast, ratio_label="scipy Radau / CasADi CVODES (CPU)",
                       notes=notes)


@benchmark("simulate_step", "one elastic step change of the knitting stitch-density drive, 60 ms cycle (CasADi "
                            "CVODES vs scipy Radau, peak cam force F6 to 1 %)", target_s=0.2)
def _bench_simulate_step() -> BenchResult:
    problem = load_problem(reference_problem_path("knitting_stitch_density.toml"))

    def f6(r):
        return float(np.max(np.abs(r.forces["c6"])))

    rows, notes, fast, slow, _ = _cvodes_against_scipy(
        problem, "step", None, lambda r, ref: abs(f6(r) / f6(ref) - 1), 0.01,
        lambda err: f"peak F6 error {err:.1e}", lambda ref: f"peak F6 {f6(ref):.3f} N")
    notes.append("the same scene machinery as the needle bar (bodies on the screw-lever's members, links with "
                 "clearances); only the integrator differs")
    return BenchResult(rows=rows, measured_s=fast, ratio=slow / fast, ratio_label="scipy Radau / CasADi CVODES (CPU)",
                       notes=notes)


@benchmark("simulate_peaks", "the release scene at 1200 spm: its peak forces located between the output points with "
                             "an error estimate each (re-integrated at 1/100 of the tolerances from its stroke piece's "
                             "start) against the same cycle without them")
def _bench_simulate_peaks() -> BenchResult:
    problem = load_problem(reference_problem_path())
    with_peaks = best_time(lambda: simulate_scene(problem, "release", 1200.0), repeat=3)
    without = best_time(lambda: simulate_scene(problem, "release", 1200.0, options=SimulationOptions(peaks=False)),
                        repeat=3)
    r = simulate_scene(problem, "release", 1200.0)
    m = r.metrics
    worst = max(m["peak_contact_force_errors_pct"].items(), key=lambda kv: kv[1])
    return BenchResult(rows=[BenchRow("peaks located and estimated", with_peaks,
                                      f"{r.stats['peak_refinements']} output intervals refined; largest estimate "
                                      f"{worst[1]:.2g} % ({worst[0]})"),
                             BenchRow("the cycle alone (grid maxima)", without)],
                       measured_s=with_peaks, ratio=with_peaks / without, ratio_label="with peaks / without",
                       notes=["target: the peaks and their estimates at most 3x the cycle alone"], ratio_max=3.0)


#: every contact of the handover scene at 1e11 N/m (100 times the file's): too stiff for its step budget
STIFF_SETS = [f"model.contacts.{c}.stiffness_N_m=1e11" for c in ("c21", "c32", "c13", "c31", "c14", "c45", "c56", "c35")]


@benchmark("simulate_stiff_refusal", "the handover scene with every contact 100x stiffer (600 spm): refused at its "
                                     "step budget at rtol 1e-8 against at the default rtol 1e-5", target_s=60.0)
def _bench_simulate_stiff_refusal() -> BenchResult:
    problem = load_problem(reference_problem_path(), STIFF_SETS)

    def refused(rtol):
        try:
            simulate_scene(problem, "handover", 600.0, options=SimulationOptions(rtol=rtol))
        except SolverError as exc:
            return str(exc)
        raise AssertionError("the stiff handover scene was not refused")

    tight = best_time(lambda: refused(1e-8), repeat=1)
    default = best_time(lambda: refused(1e-5), repeat=1)
    return BenchResult(rows=[BenchRow("refused at rtol 1e-8", tight), BenchRow("refused at rtol 1e-5", default)],
                       measured_s=tight, ratio=tight / default, ratio_label="rtol 1e-8 / rtol 1e-5",
                       notes=["the budget bounds the time at any tolerance (4x max_steps at most, and one output "
                              "interval at most 10 % of the steps left); target: within 5x, under 60 s"],
                       target_s=60.0, ratio_max=5.0)
