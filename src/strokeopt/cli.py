"""`strokeopt` command line: parse, call the public API, print or write. Thin on purpose.

Exit codes: 0 success, 2 bad input (problem file, option, catalogue) with a
one-line message naming the file and the field, 1 a solve or a check that
failed for a stated reason.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from .errors import ProblemError, SolverError, StrokeoptError

DEFAULT_OUT = Path("strokeopt-out")


def _problem_parent() -> argparse.ArgumentParser:
    """Options every command on a problem file takes."""
    p = argparse.ArgumentParser(add_help=False)
    p.add_argument("problem", metavar="PROBLEM", help="design problem file (TOML), e.g. problems/deco2000_needle_bar.toml")
    p.add_argument("--set", dest="overrides", action="append", default=[], metavar="KEY.PATH=VALUE",
                   help="override a value of the problem file, validated like the file "
                        "(repeatable; arrays 1-based: --set 'timing.intervals[2].law=poly5')")
    p.add_argument("--json", action="store_true", help="print only JSON on stdout (for scripts)")
    p.add_argument("--verbose", action="store_true", help="print solver and integrator output")
    return p


def _spm_value(text: str) -> float:
    try:
        value = float(text)
    except ValueError:
        raise ProblemError("--spm", "", f"expected a number of stitches per minute, got {text!r}") from None
    if not value > 0 or value != value or value == float("inf"):
        raise ProblemError("--spm", "", f"must be positive, got {text}")
    return value


def _load(args):
    from .laws import make_law
    from .problem import load_problem

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


# --------------------------------------------------------------------------- commands


def cmd_laws(args) -> int:
    from .laws import law_table
    from .report import format_table, to_json

    rows = law_table()
    if args.json:
        print(to_json({"laws": rows}))
        return 0
    for r in rows:
        r["params"] = ", ".join(f"{k} = {v:g}" for k, v in r["params"].items()) or None
    print(format_table(rows, [("law", "law"), ("params", "parameters"), ("C_v", "C_v"), ("C_a", "C_a"),
                              ("C_j", "C_j"), ("continuity", "continuity"), ("first_jump", "first jump")],
                       title="Classic motion laws, unit rise (v = C_v h/T, a = C_a h/T^2, jerk = C_j h/T^3)"))
    print("\nC_j '-': the acceleration jumps (at the ends against a dwell, or inside), so the jerk is an impulse.")
    return 0


def cmd_kinematics(args) -> int:
    from .plots import plot_kinematics
    from .report import kinematics_summary, kinematics_text, to_json

    problem = _load(args)
    stroke = problem.stroke()
    summary = kinematics_summary(problem, stroke, problem.spm)
    if args.json:
        print(to_json(summary))
    else:
        print(kinematics_text(summary))
    _write_figure(lambda p: plot_kinematics(problem, stroke, problem.spm, p), _plot_path(args, "kinematics"), args)
    return 0


# --------------------------------------------------------------------------- parser


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="strokeopt",
        description="Design servo-driven reciprocating mechanisms (electronic cams): motion laws, "
                    "kinematics, drive sizing, optimal strokes and contact-model verification.",
        epilog="Start with: strokeopt kinematics problems/deco2000_needle_bar.toml  "
               "(each command has --help).",
    )
    sub = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")
    problem = _problem_parent()

    p = sub.add_parser("laws", help="table of the classic motion laws and their characteristic values",
                       description="The classic motion laws on a unit rise and their characteristic values "
                                   "C_v, C_a, C_j (computed from the laws, not typed in).")
    p.add_argument("--json", action="store_true", help="print only JSON on stdout")
    p.set_defaults(run=cmd_laws)

    p = sub.add_parser("kinematics", parents=[problem], help="peak speed, acceleration and jerk of each interval",
                       description="Kinematics of the problem's stroke: per interval the stroke, span, time, peak "
                                   "bar speed, acceleration and jerk, and peak pulley speed and acceleration; "
                                   "a figure of position, velocity, acceleration and jerk over the cam angle.",
                       epilog="Example: strokeopt kinematics problems/deco2000_needle_bar.toml --spm 600 --law poly5")
    p.add_argument("--spm", help="stitches per minute (default: machine.spm of the file)")
    p.add_argument("--law", help="use this motion law for every move (see 'strokeopt laws')")
    p.add_argument("--chi", type=float, help="shape parameter chi of the modified sine law (0 < chi <= 0.25)")
    p.add_argument("--plot", metavar="FILE", help=f"figure file (default {DEFAULT_OUT}/<problem>_kinematics.png; 'none' for no figure)")
    p.set_defaults(run=cmd_kinematics)
    return parser


def main(argv: list[str] | None = None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    try:
        return args.run(args)
    except ProblemError as exc:
        print(f"strokeopt: error: {exc}", file=sys.stderr)
        return 2
    except SolverError as exc:
        print(f"strokeopt: failed: {exc}", file=sys.stderr)
        return 1
    except StrokeoptError as exc:
        print(f"strokeopt: error: {exc}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print("strokeopt: interrupted", file=sys.stderr)
        return 130


if __name__ == "__main__":
    sys.exit(main())
