"""Benchmarks of the design step: re-solve, the full reference design, CasADi options, rockit."""

from __future__ import annotations

import time
from dataclasses import replace

import numpy as np

from ..design.transcription.nlp import clear_cache
from ..design.search.refine import solve_one
from ..design.transcription.request import DriveChoice, DriveSetup, SolveRequest
from ..design.solve import solve_design
from ..design.transcription.solver import solver_options
from ..files.problem_file import load_problem
from .registry import BenchResult, BenchRow, benchmark, best_time, reference_problem_path


def _known_optimum_path(name: str):
    return reference_problem_path().parent / "known_optima" / name


@benchmark("design_resolve", "reference design, thesis drive fixed (055U2B30, 28 teeth), 600 spm: re-solve "
                             "with the built solver (the step of a sweep)", target_s=0.5)
def _bench_design_resolve() -> BenchResult:

    p = load_problem(reference_problem_path(), ['design.motor_choice="fixed"', 'design.pulley="fixed"',
                                                "machine.spm=600"])
    s = replace(p.design, refinements=0)
    drive = DriveSetup(p, s)
    req = SolveRequest(p, 600.0, s, s.mesh, s.objective, drive, DriveChoice(drive.fixed_motor(), 28),
                       solver_options(s, None, False))  # no handover error terms
    clear_cache()
    t0 = time.perf_counter()
    first = solve_one(req)
    cold = time.perf_counter() - t0
    warm = best_time(lambda: solve_one(replace(req, warm=first.sols)), repeat=3)
    return BenchResult(rows=[BenchRow("first solve (builds the NLP and its derivatives)", cold,
                                      f"3 moves, {s.mesh.intervals} intervals x degree {s.mesh.degree}"),
                             BenchRow("re-solve, built solver, warm start", warm)],
                       measured_s=warm, ratio=cold / warm, ratio_label="first / re-solve",
                       notes=["all three moves in one NLP (move 1 alone is a third of it)",
                              "handover accuracy terms (servo/kernel.py) not included here"])

@benchmark("design_reference", "full reference design: every catalogue motor, pulley radius then teeth "
                               "(problems/deco2000_needle_bar.toml defaults)", target_s=10.0)
def _bench_design_reference() -> BenchResult:
    p = load_problem(reference_problem_path())
    clear_cache()
    t0 = time.perf_counter()
    d = solve_design(p)
    full = time.perf_counter() - t0
    t0 = time.perf_counter()
    solve_design(load_problem(reference_problem_path(), ['design.motor_choice="fixed"',
                                                         'design.pulley="fixed"']))
    fixed = time.perf_counter() - t0
    return BenchResult(rows=[BenchRow("catalogue design (7 motors, radius then teeth)", full,
                                      f"chose {d.motor}, {d.pulley_teeth} teeth"),
                             BenchRow("one motor, one pulley (the thesis drive)", fixed)],
                       measured_s=full, ratio=full / fixed, ratio_label="catalogue / single drive",
                       notes=["includes the servo-loop tuning of the handover accuracy term (numpy, no python-control; "
                              "the command's parts: benchmark solve_parts)"])

@benchmark("design_expand_jit", "CasADi options side by side on one design NLP (min peak acceleration, "
                                "jerk bound, 2 moves x 40 intervals): build + solve", target_s=None)
def _bench_design_expand_jit() -> BenchResult:
    import shutil


    p = load_problem(_known_optimum_path("jerk_bounded_peak_accel.toml"))
    rows = []
    times = {}
    variants = [("expand=False (MX)", {"expand": False}), ("expand=True (SX)", {"expand": True})]
    if shutil.which("gcc"):
        variants.append(("expand=True + jit (gcc -O1)", {"expand": True, "jit": True, "compiler": "shell",
                                                         "jit_options": {"flags": ["-O1"], "verbose": False}}))
    for label, opts in variants:
        clear_cache()
        t0 = time.perf_counter()
        d = solve_design(p, settings=_with_options(p, opts))
        build_solve = time.perf_counter() - t0
        resolve = best_time(lambda o=opts: solve_design(p, settings=_with_options(p, o), warm_start=d), repeat=3)
        times[label] = (build_solve, resolve)
        rows.append(BenchRow(label + ": build + solve", build_solve, f"C_a = {d.moves[0].C_a:.4f}"))
        rows.append(BenchRow(label + ": re-solve (built)", resolve))
    mx, sx = times["expand=False (MX)"], times["expand=True (SX)"]
    return BenchResult(rows=rows, measured_s=sx[0], ratio=mx[0] / sx[0], ratio_label="MX / SX (build + solve)",
                       notes=["jit pays a C compilation at every build; only a solver reused many times "
                              "can earn it back"])

@benchmark("design_vs_rockit", "min-jerk rest-to-rest move, h = 1 m, T = 1 s: strokeopt against rockit "
                               "(DirectCollocation N=50, degree 3), build + solve", target_s=None)
def _bench_design_vs_rockit() -> BenchResult:

    def ours():
        clear_cache()
        p = load_problem(_known_optimum_path("min_jerk.toml"))
        return solve_design(p).moves[0].C_a

    c_ours = ours()
    t_ours = best_time(ours, repeat=3)
    rows = [BenchRow("strokeopt (load + build + solve, 2 moves x 40 intervals x degree 3)", t_ours,
                     f"C_a error {100 * abs(c_ours / 5.773502692 - 1):.2g} %")]
    notes = ["strokeopt solves the rise and the return (the cycle must close): twice rockit's work"]
    try:
        from rockit import DirectCollocation, Ocp
    except ImportError:
        notes.append("rockit not installed (pip install rockit-meco, the 'bench' extra): no comparison")
        return BenchResult(rows=rows, measured_s=t_ours, ratio=float("nan"), ratio_label="rockit / strokeopt",
                           notes=notes)

    def theirs():
        ocp = Ocp(T=1.0)
        s, v, a = ocp.state(), ocp.state(), ocp.state()
        j = ocp.control()
        ocp.set_der(s, v)
        ocp.set_der(v, a)
        ocp.set_der(a, j)
        for x, x0, x1 in ((s, 0, 1), (v, 0, 0), (a, 0, 0)):
            ocp.subject_to(ocp.at_t0(x) == x0)
            ocp.subject_to(ocp.at_tf(x) == x1)
        ocp.add_objective(ocp.integral(j**2))
        ocp.solver("ipopt", {"ipopt.print_level": 0, "print_time": False, "ipopt.sb": "yes", "expand": True})
        ocp.method(DirectCollocation(N=50, degree=3))
        sol = ocp.solve()
        _, acc = sol.sample(a, grid="integrator", refine=20)
        return float(np.max(np.abs(acc)))

    c_theirs = theirs()
    t_theirs = best_time(theirs, repeat=3)
    rows.append(BenchRow("rockit (build + solve, 1 move x 50 intervals x degree 3)", t_theirs,
                         f"C_a error {100 * abs(c_theirs / 5.773502692 - 1):.2g} %"))
    return BenchResult(rows=rows, measured_s=t_ours, ratio=t_theirs / t_ours, ratio_label="rockit / strokeopt",
                       notes=notes + ["target: strokeopt at least 3x faster end to end"])




@benchmark("design_impact_study", "what quietness costs: problems/deco2000_contact_design.toml at 600 spm, 8 "
                                  "impact-velocity limits 1.6-2.9 m/s, each solved and verified by re-simulation, "
                                  "against one verified solve", target_s=60.0)
def _bench_design_impact_study() -> BenchResult:
    from ..contact.verify import design_verification
    from ..studies.sweeps import impact_study

    p = load_problem(reference_problem_path().parent / "deco2000_contact_design.toml")
    limits = [1.6 + 1.3 * k / 7 for k in range(8)]
    clear_cache()
    t0 = time.perf_counter()
    one = solve_design(p)
    design_verification(one)
    t_one = time.perf_counter() - t0
    clear_cache()
    t0 = time.perf_counter()
    rows = impact_study(p, limits)
    t_study = time.perf_counter() - t0
    verified = sum(1 for r in rows if r.get("verified"))
    return BenchResult(rows=[BenchRow("one solve + verification (builds the NLP)", t_one),
                             BenchRow("impact study, 8 limits, each solved and verified", t_study,
                                      f"{verified} of {len(rows)} verified")],
                       measured_s=t_study, ratio=t_study / t_one, ratio_label="study / one verified solve",
                       notes=["each limit is a new NLP structure (the limit is part of the settings)"])


@benchmark("design_step", "the knitting drive's 6 ms step move (problems/knitting_stitch_density.toml, its "
                          "objective, the pull-out curve reported): build + solve through the screw and lever",
           target_s=1.0)
def _bench_design_step() -> BenchResult:
    p = load_problem(reference_problem_path("knitting_stitch_density.toml"), ["design.enforce_pull_out=false"])

    def cold(options=None):
        clear_cache()
        t0 = time.perf_counter()
        d = solve_design(p, settings=_with_options(p, options))
        return time.perf_counter() - t0, d

    t_file, d = min((cold() for _ in range(2)), key=lambda r: r[0])
    t_mx, _ = min((cold({"expand": False}) for _ in range(2)), key=lambda r: r[0])
    warm = best_time(lambda: solve_design(p, warm_start=d), repeat=3)
    return BenchResult(rows=[BenchRow("build + solve, the file's options (expand = true)", t_file,
                                      f"{d.objective}, {len(d.moves)} moves x {d.mesh.intervals} intervals"),
                             BenchRow("build + solve, not expanded (the default for a servo term)", t_mx),
                             BenchRow("re-solve, built solver, warm start", warm)],
                       measured_s=t_file, ratio=t_mx / t_file, ratio_label="not expanded / expanded",
                       notes=["one design: both moves (step up, step back) in one NLP, the torque through the "
                              "screw and lever's J(phi), J'(phi) at every collocation node"])


def _with_options(problem, options: dict):
    """The problem's [design] settings with ``options`` over its solver options (CasADi/IPOPT)."""
    from dataclasses import replace

    from ..design.transcription.settings import DesignSettings

    settings = problem.design or DesignSettings()
    return replace(settings, solver_options={**settings.solver_options, **(options or {})})


#: The catalogue design near the belt's limit may take at most this many times the one at 500 spm (issue 21).
CATALOGUE_980_RATIO = 2.0
CATALOGUE_REPEATS = 2


@benchmark("design_catalogue_search", "strokeopt solve problems/deco2000_needle_bar.toml at 980 spm (the catalogue "
                                      "search near the belt's limit) against the same at 500 spm, and at 980 spm "
                                      "without pruning (every motor solved), each run as the command")
def _bench_design_catalogue_search() -> BenchResult:
    from .servo import run_command

    path = str(reference_problem_path())
    runs = {}
    for _ in range(CATALOGUE_REPEATS):  # in turn, the least of each: a load that comes and goes hits both alike
        for key, args in (("500", ["--spm", "500"]), ("980", ["--spm", "980"]),
                          ("980 exhaustive", ["--spm", "980", "--set", "design.prune_catalogue=false"])):
            seconds, out = run_command(["solve", path, *args, "--json", "--plot", "none"])
            runs[key] = min(runs.get(key, (seconds, out)), (seconds, out), key=lambda r: r[0])
    (s500, d500), (s980, d980), (sall, dall) = runs["500"], runs["980"], runs["980 exhaustive"]
    same = (d980["motor"], d980["pulley_teeth"]) == (dall["motor"], dall["pulley_teeth"])
    return BenchResult(
        rows=[BenchRow("500 spm, pruned search", s500, f"{d500['motor']}, {d500['pulley_teeth']} teeth"),
              BenchRow("980 spm, pruned search", s980, f"{d980['motor']}, {d980['pulley_teeth']} teeth"),
              BenchRow("980 spm, every motor solved (prune_catalogue = false)", sall,
                       f"{dall['motor']}, {dall['pulley_teeth']} teeth: {'the same' if same else 'DIFFERENT'}; "
                       f"pruning {sall / s980:.1f}x faster")],
        measured_s=s980, ratio=s980 / s500, ratio_label="980 spm / 500 spm", ratio_max=CATALOGUE_980_RATIO,
        notes=[f"wall times of the commands, each in its own process (imports and verification included), the "
               f"least of {CATALOGUE_REPEATS} runs in turn",
               *(n for n in d980["notes"] if "motors" in n)])
