"""The study runner (studies/runner.py): a sweep on one worker, on a local Dask cluster and on a Dask cluster
started with the Dask command line, the same table from each; bad --workers and --scheduler; a failing task and
a dying worker reported with their items while the other items are kept."""

from __future__ import annotations

import json
import os
import shutil
import socket
import subprocess
import sys
import time
from pathlib import Path

import pytest

from strokeopt.cli.main import main
from strokeopt.errors import ProblemError
from strokeopt.studies.runner import StudyRunner, chunks, run_study, study_runner

MIN_JERK = Path(__file__).resolve().parents[2] / "problems" / "known_optima" / "min_jerk.toml"
SWEEP = ["--spm", "30:39:3"]  # four rates, a tenth of a second each


def _sweep(capsys, *options) -> dict:
    code = main(["solve", str(MIN_JERK), *SWEEP, "--json", "--plot", "none", *options])
    out = capsys.readouterr().out
    assert code == 0, out
    return json.loads(out)


def _same_table(a: dict, b: dict) -> None:
    """The same rows, objective and peak acceleration to 1e-6 relative (contiguous runs start cold: the
    solver's tolerance, not the digits, is what the two share)."""
    assert [r["spm"] for r in a["rows"]] == [r["spm"] for r in b["rows"]]
    assert [r["feasible"] for r in a["rows"]] == [r["feasible"] for r in b["rows"]]
    for ra, rb in zip(a["rows"], b["rows"]):
        assert rb["objective_value"] == pytest.approx(ra["objective_value"], rel=1e-6)
        assert rb["a_max_m_s2"] == pytest.approx(ra["a_max_m_s2"], rel=1e-6)
    assert a["fastest_feasible_spm"] == b["fastest_feasible_spm"]


@pytest.fixture(scope="module")
def one_worker():
    """The reference answer: the sweep in this process (``--workers 1``)."""
    from strokeopt import load_problem
    from strokeopt.studies.sweeps import sweep_design

    return {"rows": sweep_design(load_problem(MIN_JERK), [30.0, 33.0, 36.0, 39.0])}


def test_one_and_two_local_workers_give_the_same_sweep_table(capsys):
    one = _sweep(capsys, "--workers", "1")
    two = _sweep(capsys, "--workers", "2")
    _same_table(one, two)
    assert one["fastest_feasible_spm"] == 39.0
    # the known optimum at every rate: 3-4-5 polynomial, peak 5.7735 h / T^2 (h = 1 m, T = 30/spm s)
    for r in two["rows"]:
        assert r["a_max_m_s2"] == pytest.approx(5.7735 * (r["spm"] / 30.0) ** 2, rel=1e-3)


def test_runs_are_contiguous_and_one_worker_is_one_chain():
    assert chunks(list(range(11)), 2) == [list(range(6)), list(range(6, 11))]
    assert chunks([1, 2, 3], 8) == [[1], [2], [3]]
    assert chunks([1, 2, 3], 1) == [[1, 2, 3]]
    seen = []

    def step(shared, item, warm):
        seen.append((item, warm))
        return {"item": item}, item

    outcomes = run_study(step, [1, 2, 3], None)  # in this process: each item warm-started from the previous
    assert seen == [(1, None), (2, 1), (3, 2)] and [o.row for o in outcomes] == [{"item": k} for k in (1, 2, 3)]


# --- bad input ----------------------------------------------------------------------------------------------------

@pytest.mark.parametrize("workers, message", [("0", "0 worker processes is outside 1..256"),
                                              ("x", "expected a whole number of worker processes in 1..256, got 'x'"),
                                              ("257", "257 worker processes is outside 1..256")])
def test_bad_worker_count_is_one_line(capsys, workers, message):
    assert main(["solve", str(MIN_JERK), *SWEEP, "--plot", "none", "--workers", workers]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert err == [f"strokeopt: error: --workers: {message}" + (" (1: in this process, without Dask)"
                                                               if "outside" in message else "")]


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def test_unreachable_scheduler_is_one_line_exit_2_before_any_work(capsys, monkeypatch):
    import strokeopt.studies.sweeps as sweeps

    solved = []
    monkeypatch.setattr(sweeps, "solve_verified", lambda *a, **k: solved.append(k) or pytest.fail("a solve ran"))
    address = f"tcp://127.0.0.1:{_free_port()}"  # nothing listens there
    t0 = time.perf_counter()
    assert main(["solve", str(MIN_JERK), *SWEEP, "--plot", "none", "--scheduler", address]) == 2
    elapsed = time.perf_counter() - t0
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith(f"strokeopt: error: --scheduler: cannot reach the Dask scheduler at "
                                               f"{address} (connection refused)")
    assert not solved and elapsed < 5.0
    monkeypatch.setenv("STROKEOPT_SCHEDULER", address)  # the same from the environment, naming the variable
    assert main(["solve", str(MIN_JERK), *SWEEP, "--plot", "none"]) == 2
    assert capsys.readouterr().err.startswith("strokeopt: error: STROKEOPT_SCHEDULER: cannot reach")


def test_a_server_that_is_no_dask_scheduler_is_one_line(capsys):
    import threading

    with socket.socket() as server:
        server.bind(("127.0.0.1", 0))
        server.listen()

        def answer():  # an HTTP server, say: it answers a Dask handshake with an error page
            conn, _ = server.accept()
            with conn:
                conn.sendall(b"HTTP/1.1 400 Bad Request\r\n\r\n")

        threading.Thread(target=answer, daemon=True).start()
        address = f"tcp://127.0.0.1:{server.getsockname()[1]}"
        t0 = time.perf_counter()
        assert main(["solve", str(MIN_JERK), *SWEEP, "--plot", "none", "--scheduler", address]) == 2
        assert time.perf_counter() - t0 < 5.0
    assert capsys.readouterr().err.strip() == (f"strokeopt: error: --scheduler: no Dask scheduler at {address}: the "
                                               "server there does not greet as Dask does; give the address of 'dask "
                                               "scheduler'")


@pytest.mark.parametrize("address", ["127.0.0.1:8786", "tcp://127.0.0.1", "tcp://127.0.0.1:0", "tcp://:8786",
                                     "tcp://127.0.0.1:70000", "udp://127.0.0.1:8786"])
def test_scheduler_address_is_checked_like_a_field(capsys, address):
    assert main(["solve", str(MIN_JERK), *SWEEP, "--plot", "none", "--scheduler", address]) == 2
    assert capsys.readouterr().err.strip() == (f"strokeopt: error: --scheduler: expected a Dask scheduler address "
                                               f"tcp://HOST:PORT (e.g. tcp://127.0.0.1:8786), got {address!r}")


def test_solve_help_says_where_a_study_runs(capsys):
    with pytest.raises(SystemExit):
        main(["solve", "--help"])
    out = " ".join(capsys.readouterr().out.split())
    assert "--workers N worker processes for a sweep (--spm START:STOP:STEP) or --study impact, 1 to 256" in out
    assert "--scheduler tcp://HOST:PORT" in out and "STROKEOPT_SCHEDULER" in out


def test_runner_options_belong_to_a_study(capsys):
    assert main(["solve", str(MIN_JERK), "--plot", "none", "--workers", "2"]) == 2
    assert "--workers: is for a sweep (--spm START:STOP:STEP) or --study impact" in capsys.readouterr().err
    with pytest.raises(ProblemError, match="give one of them"):
        study_runner("2", "tcp://127.0.0.1:8786")
    assert study_runner(None, None, environ={}, tasks=1) == StudyRunner(1)  # never more workers than tasks
    assert study_runner("1", None, environ={"STROKEOPT_SCHEDULER": "tcp://127.0.0.1:1"}).in_process  # option first


# --- a failing task, a dying worker -------------------------------------------------------------------------------

def test_a_failing_rate_is_reported_with_its_rate_and_the_others_kept(capsys, monkeypatch):
    import strokeopt.studies.sweeps as sweeps

    real = sweeps.solve_checked

    def flaky(problem, *, spm, **kw):
        if spm == 33.0:
            raise RuntimeError("the linear solver ran out of memory\n(second line)")
        return real(problem, spm=spm, **kw)

    monkeypatch.setattr(sweeps, "solve_checked", flaky)
    rows, err = _sweep_with_a_failure(capsys, [True, False, True, True])
    assert rows[1]["task_failed"] and rows[1]["reason"] == "task failed: RuntimeError: the linear solver ran out of memory"
    assert "strokeopt: failed: the task of 33 spm: task failed: RuntimeError: the linear solver ran out of memory" in err


def _sweep_with_a_failure(capsys, feasible: list) -> tuple[list, str]:
    """The rows and stderr of a one-worker sweep of the known optimum in which a task fails (exit 1)."""
    code = main(["solve", str(MIN_JERK), *SWEEP, "--json", "--plot", "none", "--workers", "1"])
    captured = capsys.readouterr()
    rows = json.loads(captured.out)["rows"]
    assert code == 1 and [r["feasible"] for r in rows] == feasible
    return rows, captured.err


def test_a_failing_verification_is_reported_with_its_rate_and_the_next_rate_starts_from_its_design(capsys, monkeypatch):
    """A rate's verification is a task of its own (the finish of its solve): its failure is the rate's, and the
    next rate's solve, chained to the solve, is not held up by it."""
    import strokeopt.studies.sweeps as sweeps

    real, starts = sweeps.verify_design, []
    real_solve = sweeps.solve_checked

    def flaky(design, **kw):
        if design.spm == 36.0:
            raise RuntimeError("the integrator stopped\n(second line)")
        return real(design, **kw)

    def watched(problem, *, spm, warm_start, **kw):
        starts.append(None if warm_start is None else warm_start.spm)
        return real_solve(problem, spm=spm, warm_start=warm_start, **kw)

    monkeypatch.setattr(sweeps, "verify_design", flaky)
    monkeypatch.setattr(sweeps, "solve_checked", watched)
    rows, _ = _sweep_with_a_failure(capsys, [True, True, False, True])
    assert rows[2]["reason"] == "task failed: RuntimeError: the integrator stopped"
    assert starts == [None, 30.0, 33.0, 36.0]  # the rate after the failed verification starts from its design


def _step_failing_on(shared, item, warm):
    """A study step for the tests (importable by the workers): item 2 raises, item ``shared`` kills its worker."""
    if item == 2:
        raise ValueError(f"no design for item {item}")
    if item == shared:
        os._exit(3)
    return {"item": item, "warm": warm}, item


@pytest.mark.slow
def test_on_local_workers_a_failure_and_a_lost_task_name_their_items():
    import dask
    import distributed  # noqa: F401  (its defaults in dask's config first: leaving the set below would drop them)

    with dask.config.set({"distributed.scheduler.allowed-failures": 0}):  # the first death loses the task
        outcomes = run_study(_step_failing_on, [0, 1, 2, 3, 4, 5], 4, runner=StudyRunner(2))
    by_item = {o.item: o for o in outcomes}
    assert [o.item for o in outcomes] == [0, 1, 2, 3, 4, 5]
    # runs [0, 1, 2] and [3, 4, 5]: 2 fails and 3 starts from what 2 started from (1); 4 kills its worker, 5 is
    # chained after it: both lost, named; 0, 1, 3 kept
    assert by_item[0].row == {"item": 0, "warm": None} and by_item[1].row == {"item": 1, "warm": 0}
    assert by_item[2].error == "ValueError: no design for item 2" and not by_item[2].lost
    assert by_item[3].row == {"item": 3, "warm": None}
    assert by_item[4].lost and by_item[5].lost and by_item[4].error.startswith("task lost: ")


def _step_killing_once(shared, item, warm):
    """A study step for the tests: item 4 kills its worker the first time it runs (``shared``: a marker file)."""
    if item == 4 and not os.path.exists(shared):
        open(shared, "w").close()
        os._exit(3)
    return {"item": item, "warm": warm}, item


@pytest.mark.slow
def test_a_worker_killed_mid_study_is_named_with_the_items_run_again(tmp_path):
    """Dask runs the killed worker's task again on the other worker: every item is answered, and the runner says
    which worker was lost and which items ran again (what a study's report prints as where it ran)."""
    runner = StudyRunner(2)
    outcomes = run_study(_step_killing_once, [0, 1, 2, 3, 4, 5], str(tmp_path / "killed"), runner=runner)
    assert [o.row["item"] for o in outcomes] == [0, 1, 2, 3, 4, 5] and all(o.ok for o in outcomes)
    (loss,) = runner.losses
    assert loss["worker"].startswith("tcp://127.0.0.1:") and 4 in loss["items"]
    text = runner.describe()
    assert text.startswith("2 local worker processes (Dask LocalCluster); 1 worker lost during the study: tcp://")
    assert "re-run on the others" in text and StudyRunner(2).describe() == "2 local worker processes (Dask LocalCluster)"


def test_local_workers_run_without_dask_s_malloc_trim_and_with_one_blas_thread(monkeypatch):
    # docs/studies.md: Dask's MALLOC_TRIM_THRESHOLD_ makes every solve about 10 % slower; one BLAS thread stays
    from strokeopt.studies.runner import WORKER_ENVIRON_UNSET, connected

    monkeypatch.delenv("MALLOC_TRIM_THRESHOLD_", raising=False)
    with connected(StudyRunner(2)) as client:
        client.wait_for_workers(2)
        environs = client.run(lambda: {k: os.environ.get(k) for k in ("MALLOC_TRIM_THRESHOLD_", "OMP_NUM_THREADS",
                                                                        "OPENBLAS_NUM_THREADS")})
    assert WORKER_ENVIRON_UNSET == ("MALLOC_TRIM_THRESHOLD_",) and len(environs) == 2
    for env in environs.values():
        assert env == {"MALLOC_TRIM_THRESHOLD_": None, "OMP_NUM_THREADS": "1", "OPENBLAS_NUM_THREADS": "1"}


# --- a cluster started with the Dask command line -----------------------------------------------------------------

def _dask_command() -> list[str]:
    beside = Path(sys.executable).with_name("dask")
    found = str(beside) if beside.exists() else shutil.which("dask")
    if found is None:
        pytest.fail("the 'dask' command is not installed (dask[distributed] is a dependency of strokeopt)")
    return [found]


@pytest.fixture(scope="module")
def dask_cluster(tmp_path_factory):
    """``dask scheduler`` and two ``dask worker`` processes on 127.0.0.1, as a user starts them; stopped (terminate,
    then kill) when the tests that use it end, passed or failed."""
    from distributed import Client

    tmp_path = tmp_path_factory.mktemp("dask")
    dask = _dask_command()
    port = _free_port()
    address = f"tcp://127.0.0.1:{port}"
    procs = []

    def start(*args, log):
        procs.append(subprocess.Popen([*dask, *args], stdout=subprocess.DEVNULL, stderr=open(tmp_path / log, "w"),
                                      stdin=subprocess.DEVNULL, cwd=tmp_path))

    try:
        start("scheduler", "--host", "127.0.0.1", "--port", str(port), "--dashboard-address", "127.0.0.1:0",
              log="scheduler.log")
        for k in (1, 2):
            start("worker", address, "--nthreads", "1", "--host", "127.0.0.1", "--dashboard-address", "127.0.0.1:0",
                  log=f"worker{k}.log")
        with Client(address, timeout=60) as client:
            client.wait_for_workers(2, timeout=120)
        yield address
    finally:
        for p in procs:
            p.terminate()
        for p in procs:
            try:
                p.wait(timeout=20)
            except subprocess.TimeoutExpired:
                p.kill()
                p.wait()


@pytest.mark.slow
def test_a_sweep_on_a_dask_cluster_gives_the_one_worker_table(capsys, dask_cluster, one_worker):
    on_cluster = _sweep(capsys, "--scheduler", dask_cluster)
    _same_table({**one_worker, "fastest_feasible_spm": 39.0}, on_cluster)


@pytest.mark.slow
def test_a_tolerance_study_on_a_dask_cluster_gives_the_one_worker_numbers(capsys, dask_cluster, tmp_path,
                                                                          reference_path):
    """The samples of a tolerance study are independent: the same numbers wherever they ran."""
    out = tmp_path / "design"
    assert main(["solve", str(reference_path), "--spm", "600", "--out", str(out), "--plot", "none", "--json"]) == 0
    capsys.readouterr()
    argv = ["robust", str(reference_path), "--design", str(out / "design.json"), "--tolerance",
            "model.springs.k2.stiffness_N_m=±10%", "--samples", "8", "--seed", "5", "--json", "--plot", "none"]
    assert main([*argv, "--workers", "1"]) == 0
    here = json.loads(capsys.readouterr().out)
    assert main([*argv, "--scheduler", dask_cluster]) == 0
    there = json.loads(capsys.readouterr().out)
    assert len(here["rows"]) == 8 and not any(r.get("error") for r in there["rows"])
    assert there["rows"] == here["rows"] and there["yield"] == here["yield"]
    assert there["runner"] == f"the Dask cluster at {dask_cluster}"
