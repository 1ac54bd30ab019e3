"""``strokeopt robust PROBLEM``: the tolerance study of a design (studies/robust.py)."""

from __future__ import annotations

import sys

from ..errors import ProblemError
from .common import _emit, _load, _plot_path, _write_figure, progress_bar, spm_tag, states_design


def add_robust_parser(sub, problem_parent, drive_options, runner_options, plot_option) -> None:
    """Register ``robust`` on the sub-parsers ``sub``."""
    p = sub.add_parser("robust", parents=[problem_parent],
                       help="tolerance study: the yield of a design when its parts scatter, and which tolerances matter",
                       description="Will the machines we build meet the limits? The design's stroke (--design "
                                   "DESIGN.json, else solved now) is judged on sampled machines whose parts scatter "
                                   "as --tolerance says (any numeric field of the problem by its --set path; "
                                   "FIELD=±X% relative, FIELD=±X in the field's unit, ':normal' for ±3 sigma), "
                                   "drawn by a seeded Sobol or Latin-hypercube sample: each sample through the full "
                                   "servo simulation, the contact scene and the drive checks. Prints the yield (the "
                                   "share meeting every limit the problem sets, with its 95 % interval), the worst "
                                   "samples and the Spearman rank correlation of each tolerance with each result. "
                                   "The same seed gives the same numbers, on one worker or many.",
                       epilog="Example: strokeopt robust problems/deco2000_needle_bar.toml --spm 600 "
                              "--tolerance 'model.springs.k2.stiffness_N_m=±10%' "
                              "--tolerance 'model.contacts.c32.gap_mm=±0.1' --samples 200")
    p.add_argument("--tolerance", action="append", default=[], metavar="FIELD=±X[%][:normal]",
                   help="the scatter of one numeric field of the problem (repeatable)")
    p.add_argument("--samples", default="1000", help="sampled machines (8 to 100000; default 1000)")
    p.add_argument("--seed", default="0", help="seed of the sample (a whole number; default 0)")
    p.add_argument("--method", choices=("sobol", "lhs"), default="sobol",
                   help="quasi-random sample: scrambled Sobol (default) or Latin hypercube")
    p.add_argument("--spm", help="stitches per minute of a design solved now (default: machine.spm of the file)")
    drive_options(p, "its stroke is the one judged on every sampled machine")
    runner_options(p, "the samples", "each simulating the next sample as it frees up (the samples do not depend on "
                                      "each other: the same numbers on any number of workers)")
    plot_option(p, "robust_<spm>spm")
    p.set_defaults(run=cmd_robust)


def _whole(text, option: str, lo: int, hi: int) -> int:
    try:
        value = int(str(text))
    except ValueError:
        raise ProblemError(option, "", f"expected a whole number, got {text!r}") from None
    if not lo <= value <= hi:
        raise ProblemError(option, "", f"must lie in [{lo}, {hi}], got {value}")
    return value


def cmd_robust(args) -> int:
    from ..design.result import design_from_data
    from ..io.plain import to_json
    from ..report.robust import plot_robust, robust_text
    from ..io.load_units import error_unit
    from ..studies.robust import SAMPLES_RANGE, check_distinct, judge_stated, parse_tolerance, robust_study
    from ..studies.runner import study_runner
    from ..studies.verified import solve_verified

    samples = _whole(args.samples, "--samples", *SAMPLES_RANGE)
    seed = _whole(args.seed, "--seed", 0, 2**32 - 1)
    if not args.tolerance:  # before any work
        raise ProblemError("--tolerance", "", "name at least one tolerance, e.g. --tolerance "
                                              "'model.springs.k2.stiffness_N_m=±10%'")
    problem = _load(args, fix_in_design=states_design(args.problem))
    tolerances = [parse_tolerance(t, problem) for t in args.tolerance]
    check_distinct(tolerances)
    runner = study_runner(args.workers, args.scheduler, tasks=samples)  # an unreachable scheduler: before any work
    # a machine that states its motion and nothing to design (a linkage's crank at constant speed): the samples
    # are judged by its transmission's own analysis; else the design's stroke on every sample
    stated = args.design_data is None and problem.design is None and problem.transmission.analysis(problem) is not None
    if stated:
        design = None
    elif args.design_data is not None:
        design = design_from_data(problem, args.design_data, args.design_stroke)
    else:
        design = solve_verified(problem, compare=False).design
    progress = progress_bar(args, "samples", "sample")
    report = robust_study(problem if stated else design, tolerances, samples, seed=seed, method=args.method,
                          runner=runner, progress=progress, judge=judge_stated if stated else None)
    report["runner"] = runner.describe()
    if args.json:
        _emit(to_json(report))
    else:
        print(robust_text(report))
    settings = None if stated else design.settings
    contact = getattr(settings, "contact", None)
    scale, unit = error_unit(problem.timing.rotary)   # the accuracy in the handover error's unit
    limits = {f"handover_error_{unit}": None if settings is None else settings.accuracy * scale,
              "impact_velocity_m_s": None if contact is None else contact.impact_velocity_max}
    _write_figure(lambda p: plot_robust(report, p, limits), _plot_path(args, "robust", spm_tag(report["spm"])), args)
    errors = [r for r in report["rows"] if r.get("error")]
    if errors:
        print(f"strokeopt: {len(errors)} samples could not be judged (first: sample {errors[0]['sample']}: "
              f"{errors[0]['error']})", file=sys.stderr)
    return 0
