"""`strokeopt` command line: parse, call the public API, print or write. Thin on purpose.

Exit codes: 0 success, 2 bad input (problem file, option, catalogue) with a
one-line message naming the file and the field, 1 a solve or a check that
failed for a stated reason.
"""


from __future__ import annotations

import argparse
import sys
from pathlib import Path

from ..errors import ProblemError, SolverError, StrokeoptError
from ..io.plain import to_json
from .common import _emit, check_outputs, logs_to_stderr
from .parser import build_parser


def _check_plot_format(args) -> None:
    """A --plot file name matplotlib cannot write is bad input: say so before any work is done."""
    plot = getattr(args, "plot", None)
    if plot is None or plot.lower() == "none":
        return
    from matplotlib.backend_bases import FigureCanvasBase

    formats = FigureCanvasBase.get_supported_filetypes()
    suffix = Path(plot).suffix.lower().lstrip(".")
    if suffix not in formats:
        raise ProblemError("--plot", plot, f"cannot write a figure as {suffix or 'a file without extension'!r}; "
                                           f"use one of .{', .'.join(sorted(formats))}")



def _fail(args, word: str, status: str, exc: Exception, code: int) -> int:
    """One line on stderr; with --json also the JSON report a script reads (its status and the message)."""
    print(f"strokeopt: {word}: {exc}", file=sys.stderr)
    if getattr(args, "json", False):
        _emit(to_json({"status": status, "message": str(exc)}))
    return code


def command_parser(parser: argparse.ArgumentParser, command: str) -> argparse.ArgumentParser:
    """The sub-parser of ``command`` (for its usage line in an error)."""
    subs = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction))
    return subs.choices[command]


def _json_argument_errors(parser: argparse.ArgumentParser, argv: list[str]) -> None:
    """With --json, an argument error (a missing argument, a value argparse cannot read) also prints the JSON
    failure object every other failure prints, so a script reads one shape: ``{"status": "bad input", ...}``."""
    if "--json" not in argv:
        return
    subs = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction))
    for p in (parser, *subs.choices.values()):
        def error(message: str, p=p):  # the same one line as without --json
            print(f"{p.prog}: error: {message} (see {p.prog} --help)", file=sys.stderr)
            _emit(to_json({"status": "bad input", "message": message}))
            sys.exit(2)

        p.error = error


def main(argv: list[str] | None = None) -> int:
    parser = build_parser()
    _json_argument_errors(parser, list(sys.argv[1:] if argv is None else argv))
    args, extra = parser.parse_known_args(argv)
    if extra:  # said by the command's own parser: its usage, not the top level's
        command_parser(parser, args.command).error(f"unrecognized arguments: {' '.join(extra)}")
    args.typed_overrides = tuple(getattr(args, "overrides", None) or ())  # as typed (figure names), before any option adds
    try:
        _check_plot_format(args)
        check_outputs(args)  # an unwritable --out or --plot fails now, not after the work
        if getattr(args, "json", False) and getattr(args, "verbose", False):
            with logs_to_stderr():
                return args.run(args)
        return args.run(args)
    except ProblemError as exc:
        return _fail(args, "error", "bad input", exc, 2)
    except SolverError as exc:
        return _fail(args, "failed", "failed", exc, 1)
    except StrokeoptError as exc:
        return _fail(args, "error", "bad input", exc, 2)
    except KeyboardInterrupt:
        print("strokeopt: interrupted", file=sys.stderr)
        return 130
    except BrokenPipeError:  # e.g. `strokeopt size ... | head`: the reader left, nothing to report
        import os

        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
        return 0


if __name__ == "__main__":
    sys.exit(main())
