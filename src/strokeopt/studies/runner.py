"""The study runner: the independent pieces of a study (the rates of a sweep, the limits of the impact study)
(and the samples of the tolerance study, :mod:`.robust`) run as tasks on ``dask.distributed``, or one after the
other in this process.

Where the tasks run is a :class:`StudyRunner`:

* ``workers=1`` (no scheduler): in this process, without Dask, one piece after the other -- the reference answer;
* ``workers=N`` (N > 1): a ``dask.distributed.LocalCluster`` of N worker processes (one thread each) started for
  the study and closed after it (:func:`default_workers`: one per core of the machine);
* ``scheduler="tcp://HOST:PORT"`` (or the environment variable ``STROKEOPT_SCHEDULER``): the workers of an existing
  Dask cluster, each with strokeopt installed (``dask scheduler`` and ``dask worker tcp://HOST:PORT --nthreads 1``).
  An unreachable scheduler, a server that is no Dask scheduler, a scheduler without workers or a worker without
  strokeopt is bad input (:class:`~strokeopt.errors.ProblemError`, one line) raised before any task is submitted.

:func:`run_study` runs a *step* ``step(shared, item, warm) -> (row, warm)`` over the items. With ``chained=True``
the items are split into contiguous runs, one per worker, and within a run each item is warm-started from the
previous one's ``warm`` (with one worker: the single run of today's sequential study); each item is still a task
of its own (the progress bar counts them, a failure names one item), chained to its predecessor through Dask's
dependencies. ``shared`` (the problem, objective, settings) is sent to each worker once (``Client.scatter``), not
with every task: a worker's tasks see one problem object, so the NLPs built for it (``design/transcription/nlp.py``
NLP_CACHE, per process) serve every task on that worker.

A study may give a *finish* ``finish(shared, item, payload) -> row`` as well: the step then returns what the
finish needs in place of its row, and the finish of each item is a task of its own that depends on its step
only (a sweep's rate: the solve, chained to the solve before it, then its verification, which nothing waits
for). The chained steps are then short, and the finishes fill the workers as they free up: 11 rates on two
workers split 6/5 as whole verified solves, about evenly as solves and verifications.

A step that raises is reported with its item (:class:`TaskOutcome` ``error``) and the other items' results are
kept; the next item of its run starts from what the failed one started from. A worker that dies has its tasks
rescheduled by Dask on the others; a task that keeps killing workers (``distributed.scheduler.allowed-failures``)
is reported as lost (``lost=True``) with the items chained after it. Ctrl-C cancels the submitted tasks and
closes the cluster.
"""

from __future__ import annotations

import logging
import os
import re
import threading
import uuid
from contextlib import contextmanager
from dataclasses import dataclass, field
from typing import Any, Callable, Iterable

from ..errors import ProblemError

#: The most worker processes a study starts on this machine (``--workers``).
WORKERS_MAX = 256
#: How long to try to reach a scheduler (and to see a worker there) before saying it cannot be reached [s].
CONNECT_TIMEOUT_S = 5.0
#: The environment variable naming a scheduler (when neither --workers nor --scheduler is given).
SCHEDULER_ENV = "STROKEOPT_SCHEDULER"

_ADDRESS = re.compile(r"tcp://(?P<host>[A-Za-z0-9](?:[A-Za-z0-9.\-]*[A-Za-z0-9])?|\[[0-9A-Fa-f:.]+\]):(?P<port>\d{1,5})")


def default_workers() -> int:
    """Worker processes of the embedded cluster: one per core this process may run on."""
    try:
        return max(1, len(os.sched_getaffinity(0)))
    except AttributeError:  # not on Linux
        return max(1, os.cpu_count() or 1)


def parse_workers(text, option: str = "--workers") -> int:
    """A worker count (``--workers N``): a whole number in 1..256, else ProblemError naming ``option``."""
    try:
        n = int(str(text).strip())
    except ValueError:
        raise ProblemError(option, "", f"expected a whole number of worker processes in 1..{WORKERS_MAX}, "
                                       f"got {text!r}") from None
    if not 1 <= n <= WORKERS_MAX:
        raise ProblemError(option, "", f"{n} worker processes is outside 1..{WORKERS_MAX} (1: in this process, "
                                       "without Dask)")
    return n


def parse_scheduler(text, option: str = "--scheduler") -> str:
    """A Dask scheduler address ``tcp://HOST:PORT`` (port 1..65535), else ProblemError naming ``option``."""
    text = str(text).strip()
    m = _ADDRESS.fullmatch(text)
    if m is None or not 1 <= int(m["port"]) <= 65535:
        raise ProblemError(option, "", f"expected a Dask scheduler address tcp://HOST:PORT (e.g. tcp://127.0.0.1:8786), "
                                       f"got {text!r}")
    return text


@dataclass(frozen=True)
class StudyRunner:
    """Where a study's tasks run (see the module docstring): ``workers`` processes on this machine (1: in this
    process, without Dask), or the workers of the Dask scheduler at ``scheduler``; ``source`` names the option or
    environment variable the address came from (for messages)."""

    workers: int = 1
    scheduler: str | None = None
    source: str = "--scheduler"
    #: what happened to the cluster during the studies it ran (:func:`run_on_client`): one entry per worker that died
    #: while tasks of a study were on it, ``{"worker": address, "items": [the items Dask ran again elsewhere]}``
    losses: list = field(default_factory=list, compare=False)

    @property
    def in_process(self) -> bool:
        return self.scheduler is None and self.workers == 1

    def describe(self) -> str:
        """Where the study ran, and any worker lost on the way (its tasks re-run on the others)."""
        if self.scheduler is not None:
            where = f"the Dask cluster at {self.scheduler}"
        else:
            where = "this process" if self.workers == 1 else f"{self.workers} local worker processes (Dask LocalCluster)"
        if not self.losses:
            return where
        lost = "; ".join(f"{e['worker']}" + (f" with items {', '.join(map(str, e['items']))} on it, re-run on the others"
                                              if e["items"] else "") for e in self.losses)
        return f"{where}; {len(self.losses)} worker{'s' if len(self.losses) > 1 else ''} lost during the study: {lost}"


def study_runner(workers=None, scheduler=None, *, tasks: int | None = None, environ=None) -> StudyRunner:
    """The runner of the command-line options ``--workers`` and ``--scheduler`` (texts or None), checked like a
    file's fields: both given is an error; neither: ``$STROKEOPT_SCHEDULER`` if set, else one worker per core.
    ``tasks``: the study's number of pieces (no more local workers are started than there are pieces)."""
    environ = os.environ if environ is None else environ
    if workers is not None and scheduler is not None:
        raise ProblemError("--workers", "", "--workers starts worker processes on this machine, --scheduler uses a "
                                            "cluster's: give one of them")
    if scheduler is not None:
        return StudyRunner(1, parse_scheduler(scheduler), "--scheduler")
    if workers is None and environ.get(SCHEDULER_ENV):
        return StudyRunner(1, parse_scheduler(environ[SCHEDULER_ENV], SCHEDULER_ENV), SCHEDULER_ENV)
    n = default_workers() if workers is None else parse_workers(workers)
    return StudyRunner(max(1, min(n, tasks)) if tasks is not None else n)


@dataclass
class TaskOutcome:
    """One item of a study: its ``row``, or ``error`` (``"Type: message"``, one line) when its step raised or its
    task was ``lost`` (its worker died too often, or the task was cancelled); ``warm`` stays where it was made."""

    item: Any
    row: dict | None = None
    error: str | None = None
    lost: bool = False
    warm: Any = None

    @property
    def ok(self) -> bool:
        return self.error is None


def chunks(items: list, count: int) -> list[list]:
    """``items`` in ``count`` contiguous runs of sizes differing by at most one (none empty)."""
    count = max(1, min(count, len(items)))
    size, extra = divmod(len(items), count)
    out, start = [], 0
    for k in range(count):
        stop = start + size + (k < extra)
        out.append(items[start:stop])
        start = stop
    return [c for c in out if c]


def run_study(step: Callable, items: Iterable, shared, *, runner: StudyRunner | None = None, progress=None,
              chained: bool = True, finish: Callable | None = None) -> list[TaskOutcome]:
    """Run ``step(shared, item, warm) -> (row, warm)`` for every item; one :class:`TaskOutcome` per item, in the
    order of ``items``. ``step`` must be a module-level function (the workers import it); ``shared`` is sent to
    each worker once. ``chained``: contiguous runs of items, one per worker, each item warm-started from the
    previous of its run (``warm`` None for the first); else every item starts cold. ``progress``: a callable
    wrapping an iterable (tqdm), advanced as each item ends. ``runner`` None: in this process. ``finish``
    (module-level too): ``finish(shared, item, payload) -> row`` after the step, whose row is then the payload
    (see the module docstring); a finish that raises is the item's error."""
    items = list(items)
    runner = runner or StudyRunner()
    if runner.in_process or not items:
        return _run_here(step, items, shared, progress, chained, finish)
    with connected(runner, len(items)) as client:
        return run_on_client(client, step, items, shared, progress=progress, chained=chained, finish=finish,
                             losses=runner.losses)


# --- in this process --------------------------------------------------------------------------------------------

def _run_here(step, items, shared, progress, chained, finish) -> list[TaskOutcome]:
    outcomes, warm = [], None
    for item in (progress(items) if progress is not None else items):
        out = _run_step(step, shared, item, warm if chained else None)
        warm = out.warm
        outcomes.append(out if finish is None else _run_finish(finish, shared, out))
    for out in outcomes:
        out.warm = None
    return outcomes


_TASK_LOCK = threading.Lock()  # one solve at a time per process: IPOPT (MUMPS) and the NLP cache are not thread-safe


def _run_step(step, shared, item, warm) -> TaskOutcome:
    """One item; a step that raises is an outcome with its error, passing on the start it was given."""
    with _TASK_LOCK:
        try:
            row, made = step(shared, item, warm)
        except Exception as exc:  # noqa: BLE001  (reported with its item; the other items go on)
            return TaskOutcome(item, error=_one_line(exc), warm=warm)
    return TaskOutcome(item, row, warm=made)


def _run_finish(finish, shared, done: TaskOutcome) -> TaskOutcome:
    """The finish of an item whose step ``done`` ran (a step's error is the item's; the warm start is not kept)."""
    if not done.ok:
        return TaskOutcome(done.item, error=done.error, lost=done.lost)
    with _TASK_LOCK:
        try:
            return TaskOutcome(done.item, finish(shared, done.item, done.row))
        except Exception as exc:  # noqa: BLE001  (reported with its item; the other items go on)
            return TaskOutcome(done.item, error=_one_line(exc))


def _one_line(exc: BaseException) -> str:
    text = str(exc).strip().splitlines()
    return f"{type(exc).__name__}: {text[0]}" if text else type(exc).__name__


# --- on Dask ----------------------------------------------------------------------------------------------------

class _Shared:
    """What every task of a study shares, scattered to each worker once (one object, not a container of them)."""

    __slots__ = ("value",)

    def __init__(self, value):
        self.value = value


def _task(step, shared: _Shared, item, previous: TaskOutcome | None) -> TaskOutcome:
    """One item on a worker, warm-started from its predecessor's outcome (None: cold)."""
    return _run_step(step, shared.value, item, None if previous is None else previous.warm)


def _finish_task(finish, shared: _Shared, done: TaskOutcome) -> TaskOutcome:
    """The finish of one item on a worker (:func:`_run_finish`)."""
    return _run_finish(finish, shared.value, done)


def _without_warm(outcome: TaskOutcome) -> TaskOutcome:
    """The outcome as the client needs it (the warm start, e.g. a whole Design, stays on the worker)."""
    return TaskOutcome(outcome.item, outcome.row, outcome.error, outcome.lost)


class _Completed:
    """The futures of a study in the order they end (a sized iterable, so a progress bar shows the total)."""

    def __init__(self, futures, loop):
        self.futures, self.loop = futures, loop

    def __len__(self) -> int:
        return len(self.futures)

    def __iter__(self):
        from distributed import as_completed

        return iter(as_completed(self.futures, loop=self.loop))


def run_on_client(client, step, items: list, shared, *, progress=None, chained: bool = True,
                  finish: Callable | None = None, losses: list | None = None) -> list[TaskOutcome]:
    """:func:`run_study` on an open ``distributed.Client`` (one run of items per worker of its cluster); every worker
    that dies while tasks of the study are on it is appended to ``losses`` (:func:`_lost_workers`)."""
    slots = max(1, len(client.nthreads())) if chained else len(items)
    token = uuid.uuid4().hex[:8]
    scattered = client.scatter(_Shared(shared), broadcast=True, hash=False)
    futures, steps = [None] * len(items), [None] * len(items)
    indexed = list(enumerate(items))
    for run in chunks(indexed, slots):
        previous = None
        for k, item in run:
            # the steps first where a worker has both ready: a run's chain of steps is the study's critical path
            steps[k] = client.submit(_task, step, scattered, item, previous, pure=False, priority=1,
                                     key=f"strokeopt-{token}-{k}")
            previous = steps[k] if chained else None
            futures[k] = steps[k] if finish is None else client.submit(
                _finish_task, finish, scattered, steps[k], pure=False, key=f"strokeopt-{token}-{k}-finish")
    try:
        done = _Completed(futures, client.loop)
        for _ in (progress(done) if progress is not None else done):
            pass
        # every row through a small task beside its outcome: a finished outcome whose worker died since is
        # computed again by Dask; a lost one gives its row task its error
        rows = [client.submit(_without_warm, fut, pure=False, key=f"strokeopt-{token}-{k}-row")
                for k, fut in enumerate(futures)]
        outcomes = []
        for row, item in zip(rows, items):
            try:
                outcomes.append(row.result())
            except Exception as exc:  # noqa: BLE001  (its task, or one it was chained to, was lost)
                outcomes.append(TaskOutcome(item, error=f"task lost: {_one_line(exc)}", lost=True))
        if losses is not None:
            losses += _lost_workers(client, token, items)
        return outcomes
    except BaseException:
        client.cancel(futures + steps, force=True)
        raise
    finally:
        client.cancel([scattered], force=True)


def _lost_workers(client, token: str, items: list) -> list[dict]:
    """The workers the scheduler removed unexpectedly while they held tasks of the study ``token`` (its
    "remove-worker" events), each with the items whose tasks Dask then ran again elsewhere (in the study's order)."""
    out = []
    for worker, keys in client.run_on_scheduler(_removals):
        ks = sorted({int(m[1]) for k in keys if (m := re.fullmatch(rf"strokeopt-{token}-(\d+)(-\w+)?", k))})
        if ks:
            out.append({"worker": worker, "items": [items[k] for k in ks]})
    return out


def _removals(dask_scheduler) -> list[tuple[str, list[str]]]:
    """On the scheduler: every unexpected removal of a worker it logged, with the keys of the tasks it was running or
    held (plain data: the event log itself does not pickle)."""
    out = []
    for _, event in dask_scheduler.get_events("all"):
        if isinstance(event, dict) and event.get("action") == "remove-worker" and not event.get("expected"):
            keys = set(event.get("processing-tasks") or ()) | set(event.get("lost-computed-tasks") or ())
            out.append((str(event.get("worker", "?")), [str(k) for k in keys]))
    return out


@contextmanager
def connected(runner: StudyRunner, tasks: int | None = None):
    """A ``distributed.Client`` on the runner's cluster: a LocalCluster of ``runner.workers`` processes (at most
    ``tasks``) started here and closed on leaving, or the scheduler at ``runner.scheduler`` (ProblemError, one
    line, when it cannot be reached within :data:`CONNECT_TIMEOUT_S`, is no Dask scheduler, has no worker or a
    worker lacks strokeopt)."""
    if runner.scheduler is None:
        from distributed import Client, LocalCluster

        n = runner.workers if tasks is None else max(1, min(runner.workers, tasks))
        with _quiet_dask():
            cluster = None
            try:
                with _ctrl_c_held(), _worker_environ():
                    cluster = LocalCluster(n_workers=n, threads_per_worker=1, processes=True, dashboard_address=":0",
                                           silence_logs=logging.ERROR, preload=[_WORKER_IGNORES_CTRL_C])
                with Client(cluster) as client:
                    yield client
            finally:
                if cluster is not None:
                    cluster.close()
        return
    client = _reach(runner)
    try:
        yield client
    finally:
        client.close()


def check_reachable(runner: StudyRunner) -> None:
    """A scheduler that refuses the connection or is no Dask scheduler, said before a study does any other work
    (ProblemError, one line; the full connection, its workers and their strokeopt are checked when the study
    starts). Nothing to check for local workers."""
    if runner.scheduler is not None:
        _probe(runner)


def _reach(runner: StudyRunner):
    _probe(runner)  # before importing Dask (a second)
    from distributed import Client

    with _quiet_dask():
        try:
            client = Client(runner.scheduler, timeout=CONNECT_TIMEOUT_S, set_as_default=False)
        except Exception as exc:  # noqa: BLE001  (whatever the connection met: one line)
            raise ProblemError(runner.source, "", f"cannot reach the Dask scheduler at {runner.scheduler} within "
                                                  f"{CONNECT_TIMEOUT_S:g} s ({_one_line(exc)[:120]}); start one with "
                                                  "'dask scheduler' or give another address") from None
    try:
        try:
            client.wait_for_workers(1, timeout=CONNECT_TIMEOUT_S)
        except (OSError, TimeoutError):
            raise ProblemError(runner.source, "", f"the Dask scheduler at {runner.scheduler} has no worker (waited "
                                                  f"{CONNECT_TIMEOUT_S:g} s): start some with 'dask worker "
                                                  f"{runner.scheduler} --nthreads 1'") from None
        from importlib.metadata import version

        try:
            client.run(version, "strokeopt")
        except Exception as exc:  # noqa: BLE001  (a worker without strokeopt: its error, one line)
            raise ProblemError(runner.source, "", f"a worker of {runner.scheduler} cannot run strokeopt "
                                                  f"({_one_line(exc)}): install strokeopt where the workers run") \
                from None
    except BaseException:
        client.close()
        raise
    return client


#: Run in each local worker process as it starts (a Dask preload): Ctrl-C is the study's process's to act on, and
#: strokeopt and CasADi are imported while the cluster starts, not by each worker's first task.
_WORKER_IGNORES_CTRL_C = ("import signal\nsignal.signal(signal.SIGINT, signal.SIG_IGN)\n"
                          "import casadi, strokeopt.studies.sweeps, strokeopt.studies.robust\n")


#: Environment variables Dask's nanny sets in each worker process that strokeopt's local workers go without
#: (``distributed.nanny.pre-spawn-environ``; None unsets): ``MALLOC_TRIM_THRESHOLD_`` (64 KiB: memory handed back to
#: the system as soon as it is freed) makes every solve's many short-lived allocations system calls, about 10 %
#: slower solves here. One BLAS thread each stays (Dask's ``OMP_NUM_THREADS=1`` and the like).
WORKER_ENVIRON_UNSET = ("MALLOC_TRIM_THRESHOLD_",)


@contextmanager
def _worker_environ():
    """Dask's settings of the local workers' environment, less :data:`WORKER_ENVIRON_UNSET`."""
    import dask.config

    with dask.config.set({f"distributed.nanny.pre-spawn-environ.{k}": None for k in WORKER_ENVIRON_UNSET}):
        yield


@contextmanager
def _ctrl_c_held():
    """A Ctrl-C (SIGINT) while the local cluster starts is held and raised as KeyboardInterrupt when the start is
    done (raised inside Dask's start it may be lost); the worker processes ignore it (:data:`_WORKER_IGNORES_CTRL_C`):
    the study's process cancels their tasks and closes the cluster, with one line (cli/main.py)."""
    import signal

    held = []
    try:
        before = signal.signal(signal.SIGINT, lambda *_: held.append(True))
    except ValueError:  # not the main thread: signals are the main thread's to handle
        yield
        return
    try:
        yield held
    except BaseException:
        if held:  # the start failed because of the Ctrl-C (a worker process interrupted as it started)
            raise KeyboardInterrupt from None
        raise
    finally:
        signal.signal(signal.SIGINT, before)
    if held:
        raise KeyboardInterrupt


def _probe(runner: StudyRunner) -> None:
    """A refused or unroutable address, or a server that is no Dask scheduler, said at once (Dask's own connect
    retries until its timeout, and reads whatever a server sends as a message length). A Dask scheduler greets a
    connection with its handshake: one message, its length first (8 bytes, little-endian)."""
    import socket
    import struct

    m = _ADDRESS.fullmatch(runner.scheduler)
    host, port = m["host"].strip("[]"), int(m["port"])
    try:
        with socket.create_connection((host, port), timeout=CONNECT_TIMEOUT_S) as sock:
            sock.settimeout(CONNECT_TIMEOUT_S)
            greeting = b""
            while len(greeting) < 8:
                chunk = sock.recv(8 - len(greeting))
                if not chunk:
                    break
                greeting += chunk
    except socket.timeout:
        greeting = None
    except OSError as exc:
        why = exc.strerror or str(exc) or type(exc).__name__
        raise ProblemError(runner.source, "", f"cannot reach the Dask scheduler at {runner.scheduler} ({why.lower()}"
                                              "): start one with 'dask scheduler' or give another address") from None
    if greeting is None or len(greeting) < 8 or not 0 < struct.unpack("<Q", greeting)[0] < 1 << 20:
        said = f"said nothing within {CONNECT_TIMEOUT_S:g} s" if not greeting else "does not greet as Dask does"
        raise ProblemError(runner.source, "", f"no Dask scheduler at {runner.scheduler}: the server there {said}; "
                                              "give the address of 'dask scheduler'")


@contextmanager
def _quiet_dask():
    """Dask's own log lines (cluster start and stop, connection retries) off the study's output; warnings stay."""
    names = ("distributed", "distributed.client", "distributed.scheduler", "distributed.nanny",
             "distributed.worker", "distributed.core", "distributed.comm")
    loggers = [logging.getLogger(n) for n in names]
    levels = [lg.level for lg in loggers]
    for lg in loggers:
        lg.setLevel(logging.ERROR)
    try:
        yield
    finally:
        for lg, level in zip(loggers, levels):
            lg.setLevel(level)
