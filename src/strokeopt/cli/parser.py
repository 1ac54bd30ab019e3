"""The command line's grammar: every command, its options and its help (with an example)."""

from __future__ import annotations

import argparse

from .camtable_command import cmd_camtable
from .commands import (cmd_accuracy, cmd_bench, cmd_kinematics, cmd_laws, cmd_simulate, cmd_size,
                       cmd_tradeoff, cmd_verify)
from .common import DEFAULT_OUT
from .solve_command import cmd_solve


def _problem_parent() -> argparse.ArgumentParser:
    """Options every command on a problem file takes."""
    p = argparse.ArgumentParser(add_help=False)
    p.add_argument("problem", metavar="PROBLEM", help="design problem file (TOML), e.g. problems/deco2000_needle_bar.toml")
    p.add_argument("--set", dest="overrides", action="append", default=[], metavar="KEY.PATH=VALUE",
                   help="override a value of the problem file, validated like the file "
                        "(repeatable; arrays 1-based: --set 'timing.intervals[2].law=poly5'; KEY=null removes "
                        "the key: --set 'motion.law=\"poly5\"' --set motion.chi=null)")
    p.add_argument("--json", action="store_true", help="print only JSON on stdout (for scripts)")
    return p


def _verbose_option(p: argparse.ArgumentParser, what: str) -> None:
    """--verbose, only on the commands that have solver or integrator output to show."""
    p.add_argument("--verbose", action="store_true", help=f"print {what}")


def _drive_options(p: argparse.ArgumentParser, design: str, repeatable: bool = False, rate: bool = True,
                   stroke: bool = False) -> None:
    """--motor, --pulley-teeth and --design: the same meaning on every command (cli/common.apply_drive_options);
    ``rate``: the command has --spm (the design's rate is used); ``stroke``: also --stroke FILE.csv."""
    more = " (repeatable: only these)" if repeatable else ""
    p.add_argument("--motor", action="append" if repeatable else "store", metavar="NAME",
                   help=f"catalogue motor of the drive{more}; the same as --set drive.motor=NAME")
    p.add_argument("--pulley-teeth", type=int, action="append" if repeatable else "store", metavar="Z",
                   help=f"pulley tooth count{more}; the same as --set transmission.pulley_teeth=Z")
    p.add_argument("--design", metavar="DESIGN_JSON",
                   help=f"a design.json of 'strokeopt solve --out': its {'stitch rate, ' if rate else ''}motor and "
                        f"pulley; {design}. A {'--spm, ' if rate else ''}--motor, --pulley-teeth or --set asking for "
                        "other values is an error")
    if stroke:
        p.add_argument("--stroke", dest="stroke_table", metavar="FILE.csv",
                       help="a motion made elsewhere as the stroke: a CSV cam table with cam_angle_deg (0 up to below "
                            "360) and position_mm (position_deg for a rotary load) columns, joined by a periodic "
                            "cubic spline (cam_table.csv of 'solve --out' is one); it replaces the problem's law")
    p.set_defaults(drive_lists=repeatable)


def _stroke_options(p: argparse.ArgumentParser, sweep: bool = False, law: bool = True) -> None:
    """--spm (and a START:STOP:STEP sweep where the command has one), --law, --chi."""
    p.add_argument("--spm", help="cycles per minute of the machine's cycle ([machine] cycle: stitches, picks)"
                   + (", or a sweep START:STOP:STEP" if sweep else "")
                   + " (default: machine.spm of the file)")
    if law:
        p.add_argument("--law", metavar="NAME[:PARAM=VALUE,...]",
                       help="use this motion law for every move, with its parameters after a colon (see "
                            "'strokeopt laws'; e.g. --law s_curve:ramp_share=0.6,constant_speed_share=0.2); the "
                            "file's parameters of the same law stay unless given, another law starts from its "
                            "defaults")
        p.add_argument("--chi", type=float, help="shape parameter chi of the modified sine law (0.001 <= chi <= 0.25)")


def _study_runner_options(p: argparse.ArgumentParser, study: str,
                          spread: str = "each solving a contiguous run of the points warm-started within the run"
                          ) -> None:
    """--workers and --scheduler: where a study's tasks run (studies/runner.py); ``spread``: how the tasks share
    the workers."""
    p.add_argument("--workers", metavar="N",
                   help=f"worker processes for {study}, 1 to 256: 1 runs them in this process one after the other (the "
                        f"reference answer); N > 1 starts a Dask LocalCluster of N processes, {spread} (default: one "
                        "per core, or $STROKEOPT_SCHEDULER when set)")
    p.add_argument("--scheduler", metavar="tcp://HOST:PORT",
                   help=f"run {study} on the workers of this Dask scheduler (each with strokeopt installed, started "
                        "with 'dask worker tcp://HOST:PORT --nthreads 1'); the same as setting STROKEOPT_SCHEDULER. "
                        "An unreachable scheduler is an error before any work")


def _plot_option(p: argparse.ArgumentParser, name: str) -> None:
    p.add_argument("--plot", metavar="FILE",
                   help=f"figure file (default {DEFAULT_OUT}/<problem>_{name}.png, named by what distinguishes the "
                        "run; none with --json unless --plot asks; 'none' for no figure)")


def _simulation_arguments(p) -> None:
    p.add_argument("--scene", help="scene of the problem file ([scenes.NAME]; default: release, else the first)")
    _integrator_arguments(p)


def _integrator_arguments(p) -> None:
    """The contact model's integrator: --method, --rtol, --atol."""
    p.add_argument("--method", default="cvodes", choices=("cvodes", "idas"), help="SUNDIALS integrator (default cvodes)")
    p.add_argument("--rtol", type=float, default=1e-5, help="relative tolerance (default 1e-5: impact velocity to ~1e-4 m/s)")
    p.add_argument("--atol", type=float, default=1e-6,
                   help="absolute tolerance in scaled states: positions in mm, velocities in m/s (default 1e-6)")


def _cam_table_options(p: argparse.ArgumentParser) -> None:
    """How the cam table of ``solve --out`` samples the cycle (io/design_file.CamTableSpec)."""
    p.add_argument("--cam-table-resolution", metavar="DEG|N/cycle", default="0.1",
                   help="cam table step: degrees of the master axis per point (0.1 or 0.1deg; default 0.1, the "
                        "thesis drive's 3600 positions per revolution) or points per cam cycle (720/cycle)")
    p.add_argument("--master-unit", choices=("deg", "counts"), default="deg",
                   help="the cam table's master column: cam angle in deg (default) or master axis counts")
    p.add_argument("--master-counts", type=int, default=3600, metavar="N",
                   help="master axis counts per cam cycle with --master-unit counts (default 3600)")


class _Parser(argparse.ArgumentParser):
    """argparse's parser with bad input in one line (the epilog's promise) and exit 2: the command, the option and
    what is wrong, and where its help is, not the whole usage."""

    def error(self, message: str):
        self.exit(2, f"{self.prog}: error: {message} (see {self.prog} --help)\n")


def build_parser() -> argparse.ArgumentParser:
    parser = _Parser(
        prog="strokeopt",
        description="Design servo-driven reciprocating mechanisms (electronic cams): motion laws, "
                    "kinematics, drive sizing, optimal strokes and contact-model verification.",
        epilog="Start with: strokeopt solve problems/deco2000_needle_bar.toml  "
               "(each command has --help with an example). "
               "Exit codes: 0 success; 1 a solve, a check or a verification that failed (the verdict says which "
               "limit); 2 bad input (one line naming the file, the field and what is wrong). "
               "Every --json report has a 'status': 'ok'; 'optimal' or 'acceptable' (solve: IPOPT's verdict); "
               "'infeasible' (size, a solve sweep: no candidate or rate passes); 'limits exceeded' (solve, accuracy: "
               "a limit is broken, exit 1); 'verification failed' (solve, verify: the stroke re-simulated in the contact model breaks a criterion, exit 1); "
               "'implausible forces' (simulate: a peak force beyond what the scene's bodies and springs can load an "
               "element with, the model taken where it does not hold, exit 1); "
               "'targets missed' (bench); 'failed' (a solve or an integration that did not succeed, exit 1) and "
               "'bad input' (exit 2), each with the 'message' stderr shows.",
    )
    from .. import __version__

    parser.add_argument("--version", action="version", version=f"strokeopt {__version__}")
    sub = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")
    problem = _problem_parent()

    p = sub.add_parser("laws", help="table of the motion laws and their characteristic values",
                       description="The motion laws on a unit rise (the thesis's seven, the modified trapezoid, the "
                                   "trapezoidal velocity and acceleration, the S-curve, the modified sine with "
                                   "constant velocity, the SCCA family, polynomials and the double harmonic) and their "
                                   "characteristic values C_v, C_a, C_j (computed from the laws, not typed in). A "
                                   "problem file names a law with law = NAME and its parameters beside it; a "
                                   "command takes --law NAME:PARAM=VALUE,...",
                       epilog="Examples: strokeopt laws --json; strokeopt laws --plot laws.png; strokeopt laws --law "
                              "trapezoidal_velocity:constant_speed_share=0.5 --law modified_sine:chi=0.095")
    p.add_argument("--json", action="store_true", help="print only JSON on stdout")
    p.add_argument("--plot", metavar="FILE", help="a figure of every law's position, velocity, acceleration and jerk")
    p.add_argument("--law", action="append", metavar="NAME[:PARAM=VALUE,...]",
                   help="only this law, at these parameters (repeatable), e.g. --law s_curve:ramp_share=0.3 --law "
                        "modified_sine:chi=0.095")
    p.set_defaults(run=cmd_laws)

    p = sub.add_parser("kinematics", parents=[problem], help="peak speed, acceleration and jerk of each interval",
                       description="Kinematics of the problem's stroke: per interval the stroke, span, time, peak "
                                   "bar speed, acceleration and jerk, and peak pulley speed and acceleration; "
                                   "a figure of position, velocity, acceleration and jerk over the cam angle. "
                                   "A linkage problem file ([transmission] type = \"linkage\"): every output's "
                                   "position, speed, acceleration and jerk over the crank angle at the file's rpm "
                                   "(--spm: the crank's rpm), its swing, near-dwells, rise/fall asymmetry and the "
                                   "least transmission index (exit 1 below the file's limit); the figure draws the "
                                   "mechanism at six poses with the joint paths and the transmission index.",
                       epilog="Examples: strokeopt kinematics problems/deco2000_needle_bar.toml --spm 600 --law poly5; "
                              "strokeopt kinematics problems/loom_beatup_sixbar.toml --json")
    _stroke_options(p)
    _drive_options(p, "the design's optimal stroke replaces the problem's law", stroke=True)
    _plot_option(p, "kinematics_<spm>spm_<law>")
    p.set_defaults(run=cmd_kinematics)

    p = sub.add_parser("size", parents=[problem], help="rank motors and pulleys: torque, RMS, speed, inertia, belt checks",
                       description="Drive sizing: every catalogue motor with every allowed pulley, over the whole "
                                   "cycle of the problem's stroke: peak torque against the motor's peak and the "
                                   "drive's peak limit (overload = peak / rated), RMS torque against the rated "
                                   "torque, peak speed against the rated speed, load/rotor inertia ratio, belt width "
                                   "and breaking checks (thesis appendix 2). The load is the [drive] section of the "
                                   "problem: moving mass, gravity, load forces. A linkage problem file: the crank "
                                   "torque at the file's constant rpm by the power balance (reduced inertia J and J', "
                                   "gravity, process loads in their crank-angle windows) checked against Newton-Euler, "
                                   "and a servo motor and gearbox on the crank without a flywheel: every gearbox "
                                   "with every motor of the file's [drive] catalogues, the smallest motor that fits "
                                   "chosen (as the servo sley's study chooses).",
                       epilog="Examples: strokeopt size problems/deco2000_needle_bar.toml --spm 600 --max-spm "
                              "--motor 055U2B30 --explain; strokeopt size problems/loom_beatup_sixbar.toml --explain. "
                              "Exit code 1 (status 'infeasible') when no pair passes every check; the verdict line "
                              "names the binding limit.")
    _stroke_options(p)
    _drive_options(p, "its optimal stroke replaces the problem's law", repeatable=True, stroke=True)
    p.add_argument("--catalogue", action="append", default=[], metavar="FILE",
                   help="an extra catalogue file (motors, pulleys, belts; repeatable)")
    p.add_argument("--max-spm", action="store_true",
                   help="also find each pair's highest stitch rate with every check passing (bisection, 1 spm)")
    p.add_argument("--continuous-radius", action="store_true",
                   help="also the pulley radius minimising each motor's peak torque (not rounded to teeth)")
    p.add_argument("--explain", action="store_true", help="torque breakdown at the peak and every check's margin")
    _plot_option(p, "size_<spm>spm_<law>_<motor>_z<teeth>")
    p.set_defaults(run=cmd_size)

    p = sub.add_parser("solve", parents=[problem], help="optimal stroke, pulley and motor by direct collocation",
                       description="Solve the design problem of the file ([design], [drive]): the stroke of every move "
                                   "between its fixed dwells by direct collocation (IPOPT), with the pulley radius "
                                   "(continuous, then the nearest catalogue tooth counts) and the motor (enumerated "
                                   "or Bonmin) as decisions. Prints the motor, pulley, objective, every check with its "
                                   "margin, the active constraints and a comparison with the classic laws on the same "
                                   "drive. --spm START:STOP:STEP sweeps the stitch rate (warm-started) and prints the "
                                   "fastest feasible rate; --study mesh prints what accuracy costs in time. "
                                   "Objectives: min_peak_torque, min_rms_torque, min_energy, min_peak_accel, "
                                   "min_accel_squared, min_jerk, min_snap; min_stiffness: the softest springs "
                                   "of [design.free]; min_impact_velocity: the gentlest impact on the stop of "
                                   "[model.events] ([design.contact]); min_handover_error: the most accurate stroke at this "
                                   "rate (the servo's error term); min_time: the highest stitch rate "
                                   "within every limit (the cycle time free, --spm the start of the search), "
                                   "with the binding limits named; max_duration: the longest time of the move "
                                   "[design] lengthen names, the moves' times free (their sum the cycle's), the "
                                   "spans found recorded as --set texts. [design] monotonic = true keeps every "
                                   "move's direction (a crank that turns one way). [design.contact] holds the contact model in the "
                                   "collocation (keep_closed contacts, min_contact_force_N, impact_velocity_max_m_s); [design.free.NAME] frees a "
                                   "spring's stiffness in the collocation, or any number of the model (field, range) or "
                                   "several moved together (moves, range_mm: the impact point), searched around the "
                                   "verified solve; "
                                   "with [scenes], the optimal stroke is re-simulated and judged (a verification "
                                   "block; status 'verification failed', exit 1, names the criterion).",
                       epilog="Examples: strokeopt solve problems/deco2000_needle_bar.toml; "
                              "strokeopt solve problems/deco2000_needle_bar.toml --spm 600 --out out/; "
                              "strokeopt solve problems/deco2000_needle_bar.toml --spm 400:900:50; "
                              "strokeopt solve problems/known_optima/min_jerk.toml")
    p.add_argument("--objective", help="objective (overrides design.objective of the file); min_time answers "
                                       "'how fast can it go?'")
    _stroke_options(p, sweep=True)
    p.add_argument("--strict", action="store_true",
                   help="a criterion the problem sets no limit for (reported 'not judged' with its value, e.g. the "
                        "lag without [design.contact] lag_max_mm) fails the design: exit 1 (for CI)")
    _drive_options(p, "the solve re-solves the stroke at that rate on that drive. --motor/--pulley-teeth fix the "
                      "motor/pulley (the same as --set design.motor_choice='\"fixed\"' / design.pulley='\"fixed\"')")
    _verbose_option(p, "IPOPT's (and Bonmin's) output of the solve")
    p.add_argument("--out", metavar="DIR", help="write design.json, the cam table (cam_table.csv, cam_table.txt) "
                                                "and the design report (report.html) into DIR, and the figure too "
                                                "unless --plot or --json says otherwise")
    _cam_table_options(p)
    p.add_argument("--study", choices=("mesh", "impact"),
                   help="'mesh': objective error, violation between nodes and time over mesh sizes and collocation "
                        "degrees; 'impact': what quietness costs, the design under each impact-velocity limit of "
                        "--impact-range (needs [design.contact]), each point verified by re-simulation")
    p.add_argument("--impact-range", metavar="MIN:MAX[:POINTS]",
                   help="with --study impact: impact-velocity limits in m/s, POINTS (default 8, at most 20) evenly "
                        "from MIN to MAX, e.g. 1.6:2.9:8")
    _study_runner_options(p, "a sweep (--spm START:STOP:STEP) or --study impact")
    _plot_option(p, "solve_<spm>spm_<objective>")
    p.set_defaults(run=cmd_solve)

    p = sub.add_parser("bench", help="speed benchmarks, each against a reference measured in the same run",
                       description="Run the registered benchmarks (strokeopt/bench/): each times a capability "
                                   "and a reference implementation side by side and prints the ratio and its target.",
                       epilog="Examples: strokeopt bench --list; strokeopt bench --only size_catalogue; "
                              "strokeopt bench --check (exit 1 when a target is missed)")
    p.add_argument("--only", action="append", metavar="NAME", help="run only this benchmark (repeatable; the names: "
                                                                   "--list, or the end of this help)")
    p.add_argument("--list", action="store_true", help="list the benchmarks (name and what each times) and stop")
    p.add_argument("--check", action="store_true", help="exit 1 when a benchmark misses its target (for CI)")
    p.add_argument("--json", action="store_true", help="print only JSON on stdout")
    _with_benchmark_names(p)
    p.set_defaults(run=cmd_bench)

    p = sub.add_parser("simulate", parents=[problem],
                       help="contact model over one cycle: impact, lag, gap N, needle release (CasADi CVODES)",
                       description="Integrate a scene of the problem's contact model ([model], [scenes.NAME]) over one "
                                   "cam cycle with its driven body following the problem's stroke, from rest. Prints the "
                                   "impact velocity and angle of the control member on the stop, the lag behind the "
                                   "shell and when it ends, the smallest remaining gap N before the impact, the needle "
                                   "release angle and whether it was premature, peak pad, contact and drive forces. "
                                   "--spm START:STOP:STEP sweeps the speed; --vary FIELD=START:STOP:STEP sweeps a number of the "
                                   "model (several --vary: a coupled move); --study tolerance prints a work-precision "
                                   "table. Cam angles: 360 deg per cycle, 0 at the start of the first interval.",
                       epilog="Examples: strokeopt simulate problems/deco2000_needle_bar.toml --scene release --spm 600; "
                              "strokeopt simulate problems/deco2000_needle_bar.toml --spm 300:1200:20 --plot sweep.png; "
                              "strokeopt simulate problems/deco2000_needle_bar.toml --set "
                              "model.springs.k2.stiffness_N_m=1240 --set model.contacts.c32.gap_mm=6.5; strokeopt simulate "
                              "problems/deco2000_needle_bar.toml --spm 600 --vary model.contacts.c32.gap_mm-=0:5:1 "
                              "--vary model.contacts.pad.gap_mm+=0:5:1")
    _stroke_options(p, sweep=True)
    _drive_options(p, "the design's optimal stroke is simulated (the contact model itself has no motor or belt)", stroke=True)
    _verbose_option(p, "the integrator's statistics")
    _simulation_arguments(p)
    p.add_argument("--study", choices=("tolerance",),
                   help="'tolerance': error of impact velocity and release angle against a tight reference vs CPU "
                        "time, over tolerances and smoothing widths")
    p.add_argument("--vary", action="append", default=[], metavar="FIELD=START:STOP:STEP",
                   help="simulate the scene at one rate over values (or one VALUE) of a number of the problem (a --set path: "
                        "model.contacts.c32.gap_mm=5:7.4:0.2, model.bodies.control.mass_g=35:50:5) and print a "
                        "table and a figure of its results; FIELD+=... / FIELD-=... shift the file's value; several "
                        "--vary move together step by step (the impact point: --vary model.contacts.c32.gap_mm-=0:5:1 "
                        "--vary model.contacts.pad.gap_mm+=0:5:1)")
    _study_runner_options(p, "the steps of --vary", spread="each simulating steps as they free up")
    _plot_option(p, "simulate_<scene>_<spm>spm_<law>")
    p.set_defaults(run=cmd_simulate)

    p = sub.add_parser("verify", help="simulate a scene with the stroke of a design.json (written by the design solve)",
                       description="Re-simulate an optimised stroke: read the design (its exact stroke, speed, motor, "
                                   "pulley and problem file) and integrate a scene of the problem's contact model with "
                                   "it, reporting the same results as 'simulate'. Two forms: 'verify PROBLEM --design "
                                   "DESIGN.json' (like every other command) and 'verify DESIGN.json' (the problem "
                                   "recorded in the design, or --problem FILE). Prints a verification block (premature "
                                   "release, lag against [design.contact] lag_max_mm, impact velocity against "
                                   "impact_velocity_max_m_s, the design's handover accuracy: value, limit, pass/fail) "
                                   "and a one-line verdict; exit code 1 (status 'verification failed') when one fails.",
                       epilog="Example: strokeopt solve problems/deco2000_needle_bar.toml --out out && "
                              "strokeopt verify problems/deco2000_needle_bar.toml --design out/design.json "
                              "--scene release")
    p.add_argument("file", metavar="PROBLEM|DESIGN.json",
                   help="the problem file (with --design), or a design file written by the design solve")
    p.add_argument("--problem", help="with a DESIGN.json argument: problem file (default: the problem_file "
                                     "recorded in it)")
    p.add_argument("--set", dest="overrides", action="append", default=[], metavar="KEY.PATH=VALUE",
                   help="override a value of the problem file (e.g. --set model.springs.k2.stiffness_N_m=1240)")
    p.add_argument("--json", action="store_true", help="print only JSON on stdout (for scripts)")
    _drive_options(p, "its optimal stroke is simulated")
    _verbose_option(p, "the integrator's statistics")
    _simulation_arguments(p)
    _plot_option(p, "verify_<scene>_<spm>spm_<objective>")
    p.set_defaults(run=cmd_verify)

    from ..files.cam_formats import FORMATS

    p = sub.add_parser("camtable", help="a design.json as the cam table a controller loads, checked",
                       description="Write the stroke of a design (its motor angle over the cam angle) as a cam table "
                                   "of a controller's format, at equidistant master points: "
                                   + "; ".join(f"{k}: {v[1]}" for k, v in FORMATS.items())
                                   + ". The number of points is the fewest that keep the interpolated position "
                                   "within --tolerance, or --points. --check reads the file back, interpolates it "
                                   "as the format's controller does, reports the largest position, velocity and "
                                   "acceleration deviation from the verified stroke, and re-simulates the design "
                                   "with the interpolated stroke (the verified pipeline's verdict); exit code 1 when "
                                   "it fails.",
                       epilog="Examples: strokeopt solve problems/deco2000_needle_bar.toml --out out && strokeopt "
                              "camtable out/design.json --format xyva --out out/cam_xyva.csv --check; strokeopt "
                              "camtable out/design.json --format xyva --check-file edited.csv")
    p.add_argument("file", metavar="DESIGN.json", help="a design file written by 'strokeopt solve --out DIR'")
    p.add_argument("--problem", help="problem file (default: the problem_file recorded in the design)")
    p.add_argument("--format", required=True, choices=list(FORMATS), help="the controller's table format")
    p.add_argument("--out", dest="out_file", metavar="FILE",
                   help="the table file to write (a file that exists is written over only if it is a table "
                        "strokeopt wrote)")
    p.add_argument("--check-file", metavar="FILE",
                   help="check a table that exists (one edited by hand, or written before) instead of writing one: "
                        "read as --format says, against the design's verified stroke")
    p.add_argument("--points", type=int, metavar="N",
                   help="segments a cam cycle, from 36 to 36000 and dividing 36000, so every point sits on a 0.01 deg "
                        "master position (default: the fewest within --tolerance)")
    p.add_argument("--tolerance", type=float, metavar="MM",
                   help="largest position deviation of the interpolated table from the verified stroke, in mm of "
                        "the load (deg for a rotary load); default 0.001 (1 um)")
    p.add_argument("--check", action="store_true", help="read the file back, measure its deviation and re-simulate "
                                                         "(always with --check-file)")
    p.add_argument("--json", action="store_true", help="print only JSON on stdout (for scripts)")
    p.set_defaults(run=cmd_camtable, overrides=[])

    p = sub.add_parser("accuracy", parents=[problem], help="handover accuracy: servo loop, belt stretch, encoder",
                       description="Predict how far the bar is from its commanded position at the handover and over "
                                   "the cycle, from the cascade position/speed loop of the servo drive (sampling, "
                                   "feed-forwards, gains by a stated rule, [servo]), the belt as a spring between "
                                   "motor and bar, and the encoder resolution; the error is split into servo "
                                   "tracking, belt stretch (inertia and load forces) and encoder quantisation. "
                                   "--compare-laws adds the handover error and the residual vibration of every "
                                   "classic law on the same drive.",
                       epilog="Example: strokeopt accuracy problems/deco2000_needle_bar.toml --spm 600 --compare-laws. "
                              "Exit code 1 (status 'limits exceeded') when the handover error exceeds the "
                              "requirement or the torque command the torque limit.")
    _stroke_options(p)
    p.add_argument("--compare-laws", action="store_true",
                   help="also report handover error and residual vibration of every classic law")
    _drive_options(p, "the prediction is for its optimal stroke, and the classic laws follow as a table", stroke=True)
    _plot_option(p, "accuracy_<spm>spm_<law>_<motor>")
    p.set_defaults(run=cmd_accuracy)

    p = sub.add_parser("tradeoff", parents=[problem], help="what accuracy costs: highest stitch rate per handover accuracy",
                       description="For required handover accuracies (default 0.02 to 1 mm) find the highest stitch "
                                   "rate at which the handover error (strokeopt accuracy) and every drive limit still "
                                   "hold, with the problem's classic law and, separately, with the optimal stroke "
                                   "(strokeopt solve with the accuracy constraint, on the problem's motor and pulley); "
                                   "each point names its binding limit. The optimal stroke: one min_time design "
                                   "solve per accuracy (each from the problem's own rate and stroke, each accuracy "
                                   "a task: --workers, --scheduler), confirmed by the full servo simulation (below "
                                   "a rejected rate, a short search with fixed-rate designs); a line per step on "
                                   "stderr (from worker processes, as they print it).",
                       epilog="Example: strokeopt tradeoff problems/deco2000_needle_bar.toml --strokes classic "
                              "--accuracies 0.05,0.1,0.5")
    p.add_argument("--accuracies", metavar="MM,MM,...", help="required accuracies in mm (default 0.02,0.03,0.05,0.1,0.2,0.3,0.5,1)")
    p.add_argument("--strokes", choices=("both", "classic", "optimal"), default="both",
                   help="which strokes to compare (default both)")
    p.add_argument("--resolution", type=float, default=10.0, help="stitch-rate resolution of the search [spm] (default 10)")
    p.add_argument("--starts", default="1", metavar="K",
                   help="starts per accuracy of the optimal stroke, 1 to 12 (default 1: the problem's own rate): K "
                        "start rates spread over one period of the belt mode's phase in the handover window, each a "
                        "task of the runner; the highest confirmed rate is kept and the table says how many starts "
                        "reached it (K times the solves)")
    _drive_options(p, "the stroke is solved again at every rate", rate=False)
    _study_runner_options(p, "the optimal stroke's accuracies",
                          "each taking the next accuracy as it frees up; every accuracy starts from the problem's "
                          "own rate and stroke, so the table is the same on any number of workers")
    _plot_option(p, "tradeoff_<strokes>_<law>_<motor>")
    p.set_defaults(run=cmd_tradeoff)
    _report_parsers(sub, problem)
    from .linkage_command import add_linkage_parser
    from .robust_command import add_robust_parser

    add_linkage_parser(sub, problem)
    add_robust_parser(sub, problem, _drive_options, _study_runner_options, _plot_option)
    return parser


def _report_parsers(sub, problem) -> None:
    """``report`` and ``compare``: HTML files of designs (cli/report_commands.py)."""
    from .report_commands import cmd_compare, cmd_report

    p = sub.add_parser("report", parents=[problem], help="one self-contained HTML design report (print it, hand it over)",
                       description="Write the design report of a design: one HTML file, every figure inlined, no "
                                   "script or external resource, printable (a page per section). Sections in the "
                                   "order of the data flow: problem and timing diagram; stroke of bar and motor with "
                                   "the classic-law comparison; drive (torque-speed path over the motor's curves, "
                                   "checks with margins, the binding limit); handover accuracy (servo, belt, "
                                   "encoder); contact-model verification per scene; numerical accuracy; the inputs "
                                   "(the problem as resolved with every --set) and versions. Without --design the "
                                   "design is solved first, as 'strokeopt solve' does; 'solve --out DIR' writes "
                                   "DIR/report.html too. A linkage problem file's report: structure, kinematics of "
                                   "every output, transmission quality, crank torque and the motor and gearbox on "
                                   "the crank ('strokeopt kinematics' and 'size' of it), and with --servo the "
                                   "linkage against a servo.",
                       epilog="Examples: strokeopt report problems/deco2000_needle_bar.toml --out report.html; "
                              "strokeopt solve problems/deco2000_needle_bar.toml --spm 600 --out out && strokeopt "
                              "report problems/deco2000_needle_bar.toml --design out/design.json --out "
                              "out/report.html --scene all; strokeopt report problems/loom_beatup_sixbar.toml "
                              "--servo problems/loom_beatup_servo.toml --out loom.html")
    p.add_argument("--out", dest="html", required=True, metavar="FILE.html", help="the report file to write")
    p.add_argument("--objective", help="objective of the solve (without --design; overrides design.objective)")
    _stroke_options(p, law=False)
    _drive_options(p, "the report shows that design (its numbers as the file holds them) instead of solving")
    p.add_argument("--scene", action="append", metavar="NAME",
                   help="contact scene to verify (repeatable; 'all': every scene; default: release, else the "
                        "first: the others can take seconds each)")
    p.add_argument("--servo", metavar="SERVO.toml",
                   help="with a linkage problem file: also set the linkage against its output driven directly by a "
                        "servo through a gearbox, this problem file solved with every gearbox and motor of its "
                        "catalogues (e.g. problems/loom_beatup_servo.toml; about 20 solves)")
    _integrator_arguments(p)
    p.set_defaults(run=cmd_report, plot=None, verbose=False)

    p = sub.add_parser("compare", help="designs side by side in one HTML file (overlaid curves, a column per design)",
                       description="Compare two or more designs (design.json files of 'strokeopt solve --out'): the "
                                   "design report's sections with the designs side by side: their strokes and "
                                   "torques overlaid, the torque-speed paths over the motor's curves, and one table "
                                   "per section with a column per design, the better value of each row marked "
                                   "(lower torque, jerk, error; larger margin). Each design is read with the problem "
                                   "file and --set texts it records.",
                       epilog="Example: strokeopt solve problems/deco2000_needle_bar.toml --spm 600 --out peak && "
                              "strokeopt solve problems/deco2000_needle_bar.toml --spm 600 --objective "
                              "min_rms_torque --out rms && strokeopt compare peak/design.json rms/design.json "
                              "--out compare.html")
    p.add_argument("designs", nargs="+", metavar="DESIGN.json", help="two or more design files")
    p.add_argument("--out", dest="html", required=True, metavar="FILE.html", help="the comparison file to write")
    p.add_argument("--scene", action="append", metavar="NAME",
                   help="contact scene to verify for each design (repeatable; 'all'; default: release, else the first)")
    _integrator_arguments(p)
    p.add_argument("--json", action="store_true", help="print only JSON on stdout (for scripts)")
    p.set_defaults(run=cmd_compare, plot=None, verbose=False)


def _with_benchmark_names(p: argparse.ArgumentParser) -> None:
    """``bench --help`` ends with the benchmarks' names, read only when the help is printed (listing them
    imports the benchmark modules, which no other command needs)."""
    plain = p.format_help

    def format_help() -> str:
        from ..bench.run import benchmark_names

        return plain() + "\nbenchmarks:\n" + "\n".join(f"  {n:<28s} {d}" for n, d in benchmark_names()) + "\n"

    p.format_help = format_help
