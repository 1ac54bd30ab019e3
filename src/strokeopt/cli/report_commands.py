"""``strokeopt report`` and ``strokeopt compare``: a design, or several side by side, as one HTML file."""

from __future__ import annotations

import sys

import time
from pathlib import Path

from ..errors import ProblemError
from .common import _emit, _load, _probe_dir, drive_used, progress_bar, states_design
from .commands import _sim_options
from .solve_command import solve_once


def _html_path(path: str) -> Path:
    """The --out FILE of a report: an .html file whose directory can be written (checked before any work)."""
    out = Path(path)
    if out.is_dir():
        raise ProblemError("--out", "", f"{path!r} is a directory: give a file name such as "
                                        f"{str(out / 'report.html')!r}")
    if out.suffix.lower() not in (".html", ".htm"):
        raise ProblemError("--out", "", f"{path!r}: the report is an HTML file, name it .html")
    _probe_dir(out.absolute().parent, "--out", "the report")
    return out


def _scenes(args, problem) -> list[str] | None:
    """--scene NAME (repeatable) or --scene all; None: the report's default (release, else the first)."""
    if not args.scene:
        return None
    names = list(problem.scenes or {})
    if args.scene == ["all"]:
        return names
    for name in args.scene:
        if name not in names:
            raise ProblemError(str(problem.file), "--scene", f"no scene {name!r}; the problem has: "
                                                             f"{', '.join(names) or 'none'}")
    return list(dict.fromkeys(args.scene))


def design_of(args, problem, scenes=None):
    """The verified design a report shows, the ``solve --json`` report of it, and where it comes from: read
    from --design (the numbers of the file, which ``solve --out`` wrote with its comparison and drive) and
    judged again, else solved now (the same pipeline as ``strokeopt solve``)."""
    from ..design.compare import compare_with_laws
    from ..design.result import design_from_data
    from ..studies.verified import verify_design

    data = args.design_data
    if data is None:
        verified, chosen = solve_once(args, problem, progress_bar(args, "solve", "solve"), scenes)
        return verified, {**verified.summary(), "drive": chosen}, "solved now"
    design = design_from_data(problem, data, args.design_stroke)
    verified = verify_design(design, scenes=scenes, options=getattr(args, "sim_options", None))
    chosen = data.get("drive") or drive_used(args, problem, design.motor, design.pulley_teeth)
    summary = {**verified.summary(), "drive": chosen, "comparison": data.get("comparison") or compare_with_laws(design)}
    return verified, summary, f"read from {args.design}"


def cmd_report(args) -> int:
    from ..report.design_report import gather, write_report
    from ..report.format import to_json

    out = _html_path(args.html)
    problem = _load(args, fix_in_design=states_design(args.problem))
    if problem.design is None and problem.transmission.analysis(problem) is not None:
        # nothing to design, a transmission with an analysis of its own (a linkage's crank at constant speed)
        from .linkage_command import stated_report

        return stated_report(args, problem, out)
    if getattr(args, "servo", None):
        raise ProblemError("--servo", "", f"{args.problem} states a design: --servo sets a linkage whose crank turns "
                                          "at constant speed against a servo (e.g. problems/loom_beatup_sixbar.toml "
                                          "--servo problems/loom_beatup_servo.toml)")
    if args.design is not None and args.objective is not None:  # it would be ignored: say so instead
        raise ProblemError("--objective", "", f"a design read from --design {args.design} was solved for its own "
                                              "objective; --objective is for a report that solves (omit one of them)")
    scenes = _scenes(args, problem)
    args.sim_options = _sim_options(args)
    t0 = time.perf_counter()  # the solve (or the design file) judged: servo simulation, scenes; then the page
    verified, summary, source = design_of(args, problem, scenes)
    data = gather(verified, summary, source)
    info = write_report(data, out)
    info["build_time_s"] = time.perf_counter() - t0
    # the page of a failed design is written all the same (what a colleague needs to see); the exit code is the
    # design's, as solve's: 1 where it exceeds a limit or fails its verification
    failed = not verified.ok
    info.update(status=verified.status if failed else "ok", scenes=list(data.scenes), design_status=summary["status"])
    if failed:
        info["message"] = verified.verdict
    if args.json:
        _emit(to_json(info))
    else:
        print(f"written {out} ({info['size_bytes'] / 1024:.0f} KB, built in {info['build_time_s']:.2f} s; design "
              f"{source}; scenes simulated: {', '.join(data.scenes) or 'none'})")
    if failed:
        print(f"strokeopt: {verified.status}: {verified.verdict}", file=sys.stderr)
    return 1 if failed else 0


def _design_file(path: str):
    """A design file's problem (its file, its --set texts, its stitch rate), the design and its ``solve --json``
    report as ``solve --out`` stored it."""
    from ..design.compare import compare_with_laws
    from ..design.result import design_from_data, design_summary
    from ..files.design_file import load_design, read_design

    data, stroke = read_design(path)
    problem = load_design(path).problem
    design = design_from_data(problem, data, stroke)
    chosen = data.get("drive") or {"motor": design.motor, "pulley_teeth": design.pulley_teeth, "from": str(path)}
    return problem, design, {**design_summary(design), "drive": chosen,
                             "comparison": data.get("comparison") or compare_with_laws(design)}


def cmd_compare(args) -> int:
    from ..report.compare_report import write_compare
    from ..report.design_report import gather
    from ..report.format import to_json

    out = _html_path(args.html)
    if len(args.designs) < 2:
        raise ProblemError("DESIGN.json", "", "compare needs two or more design files")
    loaded = [_design_file(path) for path in args.designs]  # every file read and checked before any simulation
    same = _same_designs(args.designs)
    for first, again in same:  # a design given twice is compared with itself: say so, once, before the work
        print(f"note: {again} is the same design as {first}: their columns will be identical", file=sys.stderr)
    t0 = time.perf_counter()
    datas = []
    from ..studies.verified import verify_design

    for path, (problem, design, summary) in zip(args.designs, loaded):
        verified = verify_design(design, scenes=_scenes(args, problem), options=_sim_options(args))
        datas.append(gather(verified, {**summary, "status": verified.status, "verdict": verified.verdict},
                            f"read from {path}"))
    info = write_compare(datas, out)
    info.update(status="ok", build_time_s=time.perf_counter() - t0, designs=list(args.designs))
    if same:
        info["identical"] = [[str(a), str(b)] for a, b in same]
    if args.json:
        _emit(to_json(info))
    else:
        print(f"written {out} ({info['size_bytes'] / 1024:.0f} KB, {len(datas)} designs, built in "
              f"{info['build_time_s']:.2f} s)")
    return 0


def _same_designs(paths) -> list[tuple[str, str]]:
    """Pairs of the design files given that hold the same design (the same file twice, or a copy of it)."""
    seen, same = {}, []
    for path in paths:
        try:
            key = Path(path).read_bytes()
        except OSError:
            continue
        if key in seen:
            same.append((seen[key], path))
        else:
            seen[key] = path
    return same
