"""What every command shares: loading the problem with the command's options, --spm values, figure
paths and writing, and printing JSON (stdout, also while solver logs go to stderr)."""

from __future__ import annotations

import re
import sys
import tempfile
from contextlib import contextmanager
from pathlib import Path

from .._stdout import stdout_to
from ..errors import ProblemError

DEFAULT_OUT = Path("strokeopt-out")


def _spm_value(text: str) -> float:
    from ..files.ranges import parse_spm

    return parse_spm(text)


#: What --motor and --pulley-teeth set: the problem field, and for ``solve`` the [design] choice that fixes it.
DRIVE_FIELDS = {"motor": ("drive.motor", "design.motor_choice"),
                "pulley_teeth": ("transmission.pulley_teeth", "design.pulley")}


def _option(name: str) -> str:
    return "--" + name.replace("_", "-")


def apply_drive_options(args, fix_in_design: bool = False) -> None:
    """One mechanism for the drive of every command: ``--design FILE`` (its stitch rate, stroke, motor and
    pulley), ``--motor NAME`` and ``--pulley-teeth Z`` become ``--set`` overrides of the problem (with
    ``fix_in_design``, the solve's, also ``design.motor_choice="fixed"`` / ``design.pulley="fixed"``).
    A second option asking for another value (``--set``, ``--spm``, or --motor against the design) is an
    error naming both. Repeatable options (``size``'s filters) stay lists. Sets ``args.drive_from`` (where
    the drive comes from), ``args.design_data`` and ``args.design_stroke`` (None without --design)."""
    from ..io.fields import parse_override

    if getattr(args, "drive_from", None) is not None:
        return
    design = getattr(args, "design", None)
    args.design_data = args.design_stroke = None
    forced = {}
    for text in args.overrides:
        key, value = parse_override(text)
        forced[".".join(str(k) for k in key)] = (text, value)
    if design is not None:
        from ..files.design_file import read_design

        data, args.design_stroke = read_design(design)
        args.design_data = data
        spm = getattr(args, "spm", None)
        if spm is not None and ":" in str(spm):
            raise ProblemError(design, "spm", f"a design is one stitch rate ({data['spm']:g} spm): --spm {spm} is a "
                                              "sweep; omit --spm")
        if spm is not None and abs(_spm_value(spm) - float(data["spm"])) > 1e-9:
            raise ProblemError(design, "spm", f"the design was solved at {data['spm']:g} spm, not at {spm} "
                                              "spm: omit --spm or solve the design at that rate")
        if "machine.spm" in forced and forced["machine.spm"][1] != float(data["spm"]):
            raise ProblemError(design, "spm", f"the design was solved at {data['spm']:g} spm, but --set "
                                              f"{forced['machine.spm'][0]} asks for another: omit the --set")
        args.spm = repr(float(data["spm"]))
        from ..files.design_file import design_overrides

        for text in design_overrides(data):  # the --set texts the design was solved with hold here too
            key, value = parse_override(text)
            path = ".".join(str(k) for k in key)
            if path in forced and forced[path][1] != value:
                raise ProblemError(design, "overrides", f"the design was solved with --set {text}, but --set "
                                                        f"{forced[path][0]} asks for another: omit the --set or "
                                                        "solve the design for it")
            if path not in forced:
                args.overrides.insert(0, text)
        for name, (path, _) in DRIVE_FIELDS.items():
            value = data.get(name)
            if value is None:
                continue
            given = getattr(args, name, None)
            for other in (given if isinstance(given, list) else [given]):
                if other is not None and other != value:
                    raise ProblemError(design, name, f"the design was solved with {name} {value}, but "
                                                     f"{_option(name)} {other} asks for another: omit "
                                                     f"{_option(name)} or solve the design for it")
            if path in forced and forced[path][1] != value:
                raise ProblemError(design, name, f"the design was solved with {name} {value}, but --set "
                                                 f"{forced[path][0]} forces another: omit the --set or solve "
                                                 "the design for it")
            setattr(args, name, [value] if getattr(args, "drive_lists", False) else value)
        args.drive_from = f"the design file {design}"
    else:
        given = [n for n in DRIVE_FIELDS if getattr(args, n, None)]
        args.drive_from = f"{', '.join(_option(n) for n in given)} on the command line" if given else "the problem file"
    where = design if design is not None else None
    for name, (path, choice) in DRIVE_FIELDS.items():
        value = getattr(args, name, None)
        if value is None or isinstance(value, list):
            continue
        option = f"--design {design}" if design is not None else f"{_option(name)} {value}"
        if path in forced and forced[path][1] != value:
            raise ProblemError(where or _option(name), name, f"{option} and --set {forced[path][0]} ask for "
                                                             f"different values: give one of them")
        if fix_in_design and choice in forced and forced[choice][1] != "fixed":
            raise ProblemError(where or _option(name), name, f"{option} fixes the {name.replace('_', ' ')}, but "
                                                             f"--set {forced[choice][0]} asks the solve to choose it: "
                                                             "give one of them")
        args.overrides.append(f'{path}="{value}"' if isinstance(value, str) else f"{path}={value!r}")
        if fix_in_design:
            args.overrides.append(f'{choice}="fixed"')


def drive_used(args, problem, motor=None, pulley_teeth=None) -> dict:
    """The motor and pulley a command used and where they come from (every report says so);
    ``motor``/``pulley_teeth`` replace the problem's (a solve's choice)."""
    drive = getattr(problem, "drive", None)
    out = {"motor": motor or (drive.motor if drive is not None else None),
           "pulley_teeth": pulley_teeth or problem.pulley_teeth,
           "from": getattr(args, "drive_from", None) or "the problem file"}
    if not hasattr(problem.transmission, "radius"):  # no pulley: say which transmission
        out["transmission"] = problem.transmission.name
    return out


def require_belt_drive(problem, command: str) -> None:
    """``tradeoff`` searches the rates of a belt drive (its pulley's sizing and the belt mode's phase): a problem
    with another transmission (a gearbox, a screw and lever) is refused in one line naming it (``accuracy``
    judges the servo loop of any constant-ratio drive)."""
    name = problem.transmission.name
    if name != "belt_pulley":
        raise ProblemError(str(problem.file), "transmission.type",
                           f"is {name!r}; strokeopt {command} searches the rates of a belt drive (motor, pulley and belt "
                           f"span): it needs transmission.type = \"belt_pulley\" with pulley_teeth"
                           + (" (strokeopt accuracy judges the servo loop of a gearbox drive too)" if name == "gearbox"
                              else ""))


def step_angle(problem) -> float | None:
    """The step angle [rad] of the problem's motor when it is a stepper (``drive.motor``), else None."""
    drive = getattr(problem, "drive", None)
    if drive is None or drive.motor is None:
        return None
    from ..drive.selection import resolve_drive

    return getattr(resolve_drive(problem).actuator, "step_angle", None)


def _load(args, fix_in_design: bool = False):
    from ..motion.laws import make_law
    from ..files.problem_file import load_problem

    apply_drive_options(args, fix_in_design)
    overrides = list(args.overrides)
    if getattr(args, "spm", None) is not None and not isinstance(args.spm, list):
        overrides.append(f"machine.spm={_spm_value(args.spm)!r}")
    try:
        problem = load_problem(args.problem, overrides)
    except ProblemError as exc:  # an option's override that the problem has no field for: name the option
        options = [n for n in DRIVE_FIELDS if getattr(args, n, None) is not None]
        for name in options:
            section = DRIVE_FIELDS[name][0].split(".")[0]
            if exc.field == section and "no such field" in exc.message:
                by = "--design" if getattr(args, "design", None) else _option(name)
                raise ProblemError(args.problem, section, f"{by} needs a [{section}] section in the problem "
                                                          "file, which has none") from None
        raise
    law_name = getattr(args, "law", None)
    chi = getattr(args, "chi", None)
    timing = problem.timing
    if (law_name is not None or chi is not None) and not any(
            itv.is_move and not (timing.starts_at_speed(itv) or itv.end_speed) for itv in timing.intervals):
        raise ProblemError("--law" if law_name is not None else "--chi", "",
                           f"every move of {args.problem} starts or ends at speed and follows the polynomial of degree "
                           "5 between the speeds of its joints (a crank turning at constant speed: the linkage "
                           "without [timing]); no move runs a law to set")
    if law_name is not None or chi is not None:
        name, given = _law_option(law_name) if law_name else (problem.default_law.name, {})
        params = {} if law_name and name != problem.default_law.name else dict(problem.default_law.params)
        params.update(given)
        if chi is not None:
            if "chi" in given and given["chi"] != chi:
                raise ProblemError("command line", "--chi", f"{chi:g}, but --law gives chi = {given['chi']:g}: give it once")
            params["chi"] = chi
        problem = problem.with_law(make_law(name, where=("command line", "--law/--chi"), **params))
    table = getattr(args, "stroke_table", None)
    if table is not None:  # --stroke FILE.csv: a motion made elsewhere, judged on this problem's drive and model
        if getattr(args, "design", None) is not None:
            raise ProblemError("--stroke", "", "give the stroke once: --design (its optimal stroke) or --stroke")
        if law_name is not None or chi is not None:
            raise ProblemError("--stroke", "", "the table is the stroke: --law/--chi would not be used")
        from ..files.cam_formats import read_stroke

        args.design_stroke = read_stroke(table, problem)
    data = getattr(args, "design_data", None)
    if data is not None and data.get("motor") is not None and getattr(problem, "drive", None) is not None:
        cat = problem.drive.catalogue()  # the design's motor (a servo or a stepper): named by its file
        known = {**cat.motors, **cat.steppers}
        if data["motor"] not in known:
            raise ProblemError(str(args.design), "motor", f"{data['motor']!r} is not in the catalogue of "
                                                          f"{args.problem} ({', '.join(known)}): the design file is "
                                                          "damaged or of another problem")
    if data is not None:  # a design of another problem is refused here
        from ..files.design_file import check_design_fits

        check_design_fits(args.design_data, problem, str(args.design))
    return problem


def states_design(path) -> bool:
    """Whether the problem file states a ``[design]`` (``--motor`` then fixes the solve's choice; without one a
    file may state its motion and nothing to design, a linkage's crank at constant speed); a file that cannot be
    read: True (the problem reader then says why)."""
    from ..files.problem_file import read_problem_data

    try:
        return "design" in read_problem_data(Path(path))
    except ProblemError:
        return True


def _law_option(text: str) -> tuple[str, dict]:
    """``--law NAME`` or ``--law NAME:PARAM=VALUE,...`` (``s_curve:ramp_share=0.6,constant_speed_share=0.2``)."""
    name, _, rest = text.partition(":")
    params = {}
    for item in filter(None, (part.strip() for part in rest.split(","))):
        key, eq, value = (part.strip() for part in item.partition("="))
        try:
            number = float(value) if eq else None
        except ValueError:
            number = None
        if number is None:
            raise ProblemError("command line", "--law", f"{item!r} is not PARAM=NUMBER (as in "
                                                        "--law s_curve:ramp_share=0.6)")
        if key in params:
            raise ProblemError("command line", "--law", f"{key} is given twice")
        params[key] = number
    return name.strip(), params


def _slug(text) -> str:
    """A file-name part of a label: 'modified_sine (chi = 0.095)' -> 'modified_sine_chi0.095'."""
    text = re.sub(r"\s*=\s*", "", str(text))
    return re.sub(r"[^A-Za-z0-9.+-]+", "_", text).strip("_")


def _plot_path(args, command: str, *tags) -> Path | None:
    """Where to write the figure: --plot FILE; none with --plot none, or with --json unless --plot asks;
    else strokeopt-out/<problem>_<command>_<tags>.png, the tags being what distinguishes this figure
    from another of the same command (scene, stitch rate, law or objective, motor): figures of different
    runs do not overwrite each other."""
    if args.plot is not None:
        return None if args.plot.lower() == "none" else Path(args.plot)
    if getattr(args, "json", False):
        return None
    stem = Path(args.problem).stem if getattr(args, "problem", None) else "strokeopt"
    parts = [stem, command, *(_slug(t) for t in tags if t not in (None, ""))]
    sets = list(getattr(args, "typed_overrides", None) or ())
    if sets:  # a run with --set is another figure: a short digest of the --set texts typed names it
        import hashlib

        parts.append("set-" + hashlib.sha1("\n".join(sets).encode()).hexdigest()[:8])
    return DEFAULT_OUT / ("_".join(parts) + ".png")


def spm_tag(spm) -> str:
    """The stitch-rate part of a figure name: '600spm', or '400-900-50spm' for a sweep START:STOP:STEP."""
    if isinstance(spm, str):
        return spm.replace(":", "-") + "spm"
    if isinstance(spm, (list, tuple)):
        step = spm[1] - spm[0] if len(spm) > 1 else 0
        return f"{spm[0]:g}-{spm[-1]:g}-{step:g}spm"
    return f"{spm:g}spm"


def _probe_dir(directory: Path, option: str, what: str) -> None:
    """Create ``directory`` (and its parents) and write a scratch file into it, or raise ProblemError."""
    try:
        if directory.is_file():
            raise NotADirectoryError(20, "not a directory")
        directory.mkdir(parents=True, exist_ok=True)
        with tempfile.TemporaryFile(dir=directory):
            pass
    except OSError as exc:
        raise ProblemError(option, "", f"cannot write {what} into {str(directory)!r}: "
                                       f"{exc.strerror or exc}") from None


def check_outputs(args) -> None:
    """Before any work: --out DIR and the directory of --plot FILE must be writable (created if missing)."""
    out = getattr(args, "out", None)
    if out is not None:
        from ..files.design_file import check_out_dir

        _probe_dir(check_out_dir(out), "--out", "design.json")
    plot = getattr(args, "plot", None)
    if plot is not None and plot.lower() != "none":
        if Path(plot).is_dir():
            raise ProblemError("--plot", "", f"{plot!r} is a directory: give a figure file name such as "
                                             f"{str(Path(plot) / 'figure.png')!r}")
        _probe_dir(Path(plot).absolute().parent, "--plot", "the figure")


def _write_figure(figure_fn, path: Path | None, args) -> None:
    if path is None:
        return
    import matplotlib

    matplotlib.use("Agg")
    _probe_dir(path.absolute().parent, "--plot" if args.plot else "figure directory", "the figure")
    try:
        figure_fn(path)
    except OSError as exc:
        raise ProblemError("--plot", "", f"cannot write the figure {str(path)!r}: {exc.strerror or exc}") from None
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
