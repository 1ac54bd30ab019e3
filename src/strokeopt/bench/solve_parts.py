"""The reference solve in parts: ``strokeopt solve problems/deco2000_needle_bar.toml`` run once as a
command, its wall time split into imports, servo-loop tuning, the servo kernel numbers, the NLP build,
IPOPT, the verification and the rest, measured in that one run.

The parent (the benchmark ``solve_parts``) starts ``python -c`` with :func:`child` in a process of its
own, as a user runs the command; the child wraps the library functions of each part with a clock
that counts a part's own time (a part called inside another counts in the inner part only; an
``import`` statement counts as import wherever it runs) and prints the parts as JSON. The wrapped
functions are looked up by module and name: one that is not there any more is reported as missing,
not guessed.
"""

from __future__ import annotations

import json
import os
import resource
import runpy
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from ..errors import SolverError
from .registry import BenchResult, BenchRow, benchmark, reference_problem_path

#: The parts, in the order of the command's flow: (label, [(module, function name)]).
PARTS = (
    ("import", []),  # every import statement, and the package's own import before the clock starts
    ("problem file", [("strokeopt.files.problem_file", "load_problem")]),
    ("servo loop tuning", [("strokeopt.servo.loop", "tune")]),
    ("servo kernel numbers", [("strokeopt.servo.kernel", "_servo_numbers")]),
    ("NLP build (symbols, derivatives, numbers)", [("strokeopt.design.transcription.nlp", "build_graph"),
                                                   ("casadi", "nlpsol"),
                                                   ("strokeopt.design.transcription.nlp", "Built.numbers")]),
    ("IPOPT", []),  # the calls of the solvers nlpsol built
    ("design checks (fine grid, pins, solution)", [("strokeopt.studies.verified", "solve_design")]),
    ("verification: full servo simulation", [("strokeopt.servo.accuracy", "design_accuracy")]),
    ("verification: contact scene", [("strokeopt.studies.verified", "verify")]),
    ("classic laws beside the design", [("strokeopt.studies.verified", "compare_with_laws")]),
    ("figure", [("strokeopt.report.design", "plot_design")]),
)


class _Clock:
    """Own wall and CPU time per part: a call's time less the time of the parts called inside it."""

    def __init__(self):
        self.own: dict[str, float] = {}
        self.own_cpu: dict[str, float] = {}
        self.calls: dict[str, int] = {}
        self._stack: list[list[float]] = []

    def timed(self, label: str, fn):
        def call(*args, **kwargs):
            self._stack.append([0.0, 0.0])
            t0, c0 = time.perf_counter(), time.process_time()
            try:
                return fn(*args, **kwargs)
            finally:
                dt, dc = time.perf_counter() - t0, time.process_time() - c0
                inner, inner_cpu = self._stack.pop()
                self.own[label] = self.own.get(label, 0.0) + dt - inner
                self.own_cpu[label] = self.own_cpu.get(label, 0.0) + dc - inner_cpu
                self.calls[label] = self.calls.get(label, 0) + 1
                if self._stack:
                    self._stack[-1][0] += dt
                    self._stack[-1][1] += dc

        call.__wrapped__ = fn
        call.__name__ = getattr(fn, "__name__", label)
        call.__doc__ = getattr(fn, "__doc__", None)
        return call


class _TimedSolver:
    """A solver nlpsol built, its calls timed as IPOPT."""

    def __init__(self, solver, clock: _Clock):
        self._solver = solver
        self._call = clock.timed("IPOPT", solver)

    def __call__(self, *args, **kwargs):
        return self._call(*args, **kwargs)

    def __getattr__(self, name):
        return getattr(self._solver, name)


def _patch(clock: _Clock, missing: list[str]) -> None:
    import builtins
    import importlib

    builtins.__import__ = clock.timed("import", builtins.__import__)
    for label, targets in PARTS:
        for module, name in targets:
            *path, attr = name.split(".")
            try:
                owner = importlib.import_module(module)
                for part in path:
                    owner = getattr(owner, part)
                fn = getattr(owner, attr)
            except (ImportError, AttributeError):
                missing.append(f"{module}.{name}")
                continue
            if (module, name) == ("casadi", "nlpsol"):
                build = clock.timed(label, fn)
                setattr(owner, attr, lambda *a, _build=build, **k: _TimedSolver(_build(*a, **k), clock))
            else:
                setattr(owner, attr, clock.timed(label, fn))


def child(t_start: float, cpu_start: float, problem: str, plot: str) -> None:
    """Run ``strokeopt solve PROBLEM --plot PLOT`` in this process with the parts timed; print them as JSON
    (the command's own output goes to the null device). ``t_start``, ``cpu_start``: the process's first
    wall-clock and CPU-clock readings."""
    clock = _Clock()
    missing: list[str] = []
    _patch(clock, missing)  # imports the modules whose functions it wraps
    # import time so far: the package, imported to reach this function, and the modules _patch imported
    clock.own["import"] = time.perf_counter() - t_start
    clock.own_cpu["import"] = time.process_time() - cpu_start
    real = os.dup(1), os.dup(2)
    sys.argv = ["strokeopt", "solve", problem, "--plot", plot]
    with open(os.devnull, "w") as null:
        os.dup2(null.fileno(), 1)
        os.dup2(null.fileno(), 2)
        t0 = time.perf_counter()
        try:
            runpy.run_module("strokeopt", run_name="__main__", alter_sys=True)  # python -m strokeopt
            code = 0
        except SystemExit as done:
            code = done.code
        finally:
            solve_s = time.perf_counter() - t0
            sys.stdout.flush()
            sys.stderr.flush()
            os.dup2(real[0], 1)
            os.dup2(real[1], 2)
    total, total_cpu = time.perf_counter() - t_start, time.process_time() - cpu_start
    print(json.dumps({"exit_code": code, "total_s": total, "total_cpu_s": total_cpu, "main_s": solve_s,
                      "own_s": clock.own, "own_cpu_s": clock.own_cpu, "calls": clock.calls, "missing": missing}))


#: What the child process runs (the first statement reads the clock before anything is imported).
CHILD_CODE = ("import time; t_start, cpu_start = time.perf_counter(), time.process_time(); import sys; "
              "from strokeopt.bench.solve_parts import child; child(t_start, cpu_start, sys.argv[1], sys.argv[2])")


def solve_parts(problem: Path | None = None) -> dict:
    """One timed run of the reference solve in a process of its own: its parts [s], the process's wall
    and CPU time (user + system) as the parent sees them."""
    problem = problem or reference_problem_path()
    with tempfile.TemporaryDirectory() as tmp:
        before = resource.getrusage(resource.RUSAGE_CHILDREN)
        t0 = time.perf_counter()
        done = subprocess.run([sys.executable, "-c", CHILD_CODE, str(problem), str(Path(tmp) / "solve.png")],
                              capture_output=True, text=True)
        wall = time.perf_counter() - t0
        after = resource.getrusage(resource.RUSAGE_CHILDREN)
    if done.returncode != 0 or not done.stdout.strip():
        raise SolverError(f"the timed solve failed ({done.returncode}): {done.stderr.strip()[-400:]}")
    out = json.loads(done.stdout.strip().splitlines()[-1])
    out["wall_s"] = wall
    out["cpu_s"] = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    return out


#: The goal of issue 21 for the reference solve as a command: at most this wall time on two cores.
SOLVE_TARGET_S = 4.0


@benchmark("solve_parts", "strokeopt solve problems/deco2000_needle_bar.toml as a command, its parts measured in "
                          "one run (import, servo tuning and kernel numbers, NLP build, IPOPT, verification)",
           target_s=SOLVE_TARGET_S)
def _bench_solve_parts() -> BenchResult:
    run = solve_parts()
    own, cpu = run["own_s"], run["own_cpu_s"]
    rows = [BenchRow("total: the command as a process", run["wall_s"],
                     f"CPU {run['cpu_s']:.2f} s (user + system); exit code {run['exit_code']}")]
    for label, _ in PARTS:
        calls = run["calls"].get(label, 0)
        what = "the package, then every import statement" if label == "import" else f"{calls} calls"
        rows.append(BenchRow(label, own.get(label, 0.0), f"CPU {cpu.get(label, 0.0):.3f} s; {what}"))
    rows.append(BenchRow("rest", run["total_s"] - sum(own.values()),
                         f"CPU {run['total_cpu_s'] - sum(cpu.values()):.3f} s; arguments, text output, what no part "
                         "names"))
    rows.append(BenchRow("interpreter start and exit", run["wall_s"] - run["total_s"],
                         "the process's wall time outside its own clock"))
    notes = ["wall times of one run; on a shared machine the CPU times are the steadier measure",
             "a part's time is its own: a part called inside another counts in the inner one only"]
    if run["missing"]:
        notes.append("not timed (no such function any more): " + ", ".join(run["missing"]))
    ipopt = own.get("IPOPT", 0.0)
    return BenchResult(rows=rows, measured_s=run["wall_s"], ratio=run["wall_s"] / ipopt if ipopt else float("nan"),
                       ratio_label="total / IPOPT", notes=notes)
