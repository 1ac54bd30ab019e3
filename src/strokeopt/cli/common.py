"""What every command shares: loading the problem with the command's options, --spm values, figure
paths and writing, and printing JSON (stdout, also while solver logs go to stderr)."""

from __future__ import annotations

import sys
from contextlib import contextmanager
from pathlib import Path

from .._stdout import stdout_to
from ..errors import ProblemError

DEFAULT_OUT = Path("strokeopt-out")





def _spm_value(text: str) -> float:
    from ..io.ranges import parse_spm

    return parse_spm(text)


def _load(args):
    from ..motion.laws import make_law
    from ..io.problem_file import load_problem

    overrides = list(args.overrides)
    if getattr(args, "spm", None) is not None and not isinstance(args.spm, list):
        overrides.append(f"machine.spm={_spm_value(args.spm)!r}")
    problem = load_problem(args.problem, overrides)
    law_name = getattr(args, "law", None)
    chi = getattr(args, "chi", None)
    if law_name is not None or chi is not None:
        name = law_name or problem.default_law.name
        params = {} if law_name and law_name != problem.default_law.name else dict(problem.default_law.params)
        if chi is not None:
            params["chi"] = chi
        problem = problem.with_law(make_law(name, where=("command line", "--law/--chi"), **params))
    return problem


def _plot_path(args, default_name: str) -> Path | None:
    """Where to write the figure: --plot FILE, none with --plot none, else strokeopt-out/<name>."""
    if args.plot is not None:
        return None if args.plot.lower() == "none" else Path(args.plot)
    stem = Path(args.problem).stem if hasattr(args, "problem") else "strokeopt"
    return DEFAULT_OUT / f"{stem}_{default_name}.png"


def _write_figure(figure_fn, path: Path | None, args) -> None:
    if path is None:
        return
    import matplotlib

    matplotlib.use("Agg")
    path.parent.mkdir(parents=True, exist_ok=True)
    figure_fn(path)
    print(f"figure written to {path}", file=sys.stderr if args.json else sys.stdout)


def progress_bar(args, desc: str, unit: str = "it", when: bool = True):
    """A progress wrapper for an iterable (tqdm on stderr), or None with --json or when not ``when``."""
    if args.json or not when:
        return None
    from tqdm import tqdm

    return lambda items, desc=desc: tqdm(items, desc=desc, unit=unit, file=sys.stderr, leave=False)


_JSON_OUT = None  # where --json output goes while solver logs are sent to stderr


def _emit(text: str) -> None:
    """Print the command's JSON (stdout, also when --verbose sends every log to stderr)."""
    print(text, file=_JSON_OUT or sys.stdout)


@contextmanager
def logs_to_stderr():
    """With --json --verbose: every log goes to stderr, so stdout carries only the JSON (:func:`_emit`)."""
    global _JSON_OUT
    with stdout_to(2) as original:
        _JSON_OUT = original
        try:
            yield
        finally:
            _JSON_OUT = None
