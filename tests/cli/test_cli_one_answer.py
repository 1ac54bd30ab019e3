"""One answer everywhere: the commands agree on the drive, the handover error, the torque limit, what a
contact force is, and they end with an exit code and a JSON status that say the verdict."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from strokeopt.cli.main import main


def _run(capsys, argv):
    code = main(argv)
    out, err = capsys.readouterr()
    return code, out, err


def _json(capsys, argv, code=0):
    got, out, err = _run(capsys, argv + ["--json", "--plot", "none"])
    assert got == code, err
    return json.loads(out)


@pytest.fixture(scope="module")
def solved(reference_written):
    """The reference design (500 spm, the solve picks 055U2B30 and 24 teeth) as ``solve --out`` writes it:
    the session's one verified solve (conftest.py)."""
    return reference_written.design_json


@pytest.fixture(scope="module")
def solve_text(reference_path):
    """``strokeopt solve REFERENCE --plot none``: its exit code and its text, run once for this file."""
    import io
    from contextlib import redirect_stdout

    buf = io.StringIO()
    with redirect_stdout(buf):
        code = main(["solve", str(reference_path), "--plot", "none"])
    return code, buf.getvalue()


@pytest.fixture(scope="module")
def thesis_drive_json(reference_path):
    """``strokeopt solve REFERENCE --spm 600 --motor 055U2B30 --pulley-teeth 28 --json --plot none`` (the
    thesis drive at 600 spm): its exit code and its JSON, run once for this file."""
    import io
    from contextlib import redirect_stdout

    buf = io.StringIO()
    with redirect_stdout(buf):
        code = main(["solve", str(reference_path), "--spm", "600", "--motor", "055U2B30", "--pulley-teeth", "28",
                     "--json", "--plot", "none"])
    return code, json.loads(buf.getvalue())


def _solve_json(design_file) -> dict:
    return json.loads(design_file.read_text(encoding="utf-8"))


def test_solve_reports_the_handover_error_accuracy_design_prints(capsys, reference_path, solved, solve_text):
    # before: 0.03145 mm in solve (the design term) against 0.0415 mm in `accuracy --design` (full simulation)
    design = _solve_json(solved)
    row = next(c for c in design["checks"] if c["name"].startswith("handover accuracy"))
    acc = _json(capsys, ["accuracy", str(reference_path), "--design", str(solved)])
    assert row["value"] == pytest.approx(acc["handover_error_mm"], rel=1e-6)
    assert "full servo simulation" in row["name"] and row["unit"] == "mm"
    # the design term beside it: the full simulation's error at 25 instants of the handover window, every
    # table phase, within 2 % of it (0.04152 against 0.04152 mm; the continuous-reference kernel with the
    # classic stroke's load error gave 0.0431 mm, the end of the move alone 0.0315 mm)
    assert row["design_term"] > 0 and row["design_term"] == pytest.approx(row["value"], rel=0.02)
    # both texts print the same digits
    code, out, _ = _run(capsys, ["accuracy", str(reference_path), "--design", str(solved), "--plot", "none"])
    number = f"{acc['handover_error_mm']:.4g}"
    assert code == 0 and f"): {number} mm" in out
    code, out = solve_text  # strokeopt solve REFERENCE --plot none
    assert code == 0 and f"(full servo simulation): {number} mm" in out and "design term" in out


def test_one_torque_limit_in_every_command(capsys, reference_path, solved):
    # before: 5.500 N m in solve/size, 3.60 N m in accuracy; now min(5.5, 300 % x 1.2) = 3.6 N m everywhere
    design = _solve_json(solved)
    solve_limit = next(c["limit"] for c in design["checks"] if c["name"] == "peak_torque")
    acc = _json(capsys, ["accuracy", str(reference_path), "--design", str(solved)])
    size = _json(capsys, ["size", str(reference_path), "--design", str(solved)])
    limits = [solve_limit, acc["torque_limit_N_m"], size["candidates"][0]["torque_limit_N_m"]]
    assert limits == [pytest.approx(3.6, rel=1e-12)] * 3
    assert "min(motor peak 5.5 N m, drive peak limit 300 % x rated 1.2 N m)" in acc["torque_limit_basis"]
    code, out, _ = _run(capsys, ["accuracy", str(reference_path), "--plot", "none"])
    assert "torque limit 3.600 N m" in out
    code, out, _ = _run(capsys, ["size", str(reference_path), "--motor", "055U2B30", "--plot", "none"])
    assert "torque limit = min(motor peak, drive peak limit 300 % x rated torque)" in out and "3.600" in out


def test_size_of_a_design_is_the_designs_stroke_on_its_drive(capsys, reference_path, solved):
    design = _solve_json(solved)
    size = _json(capsys, ["size", str(reference_path), "--design", str(solved)])
    (c,) = size["candidates"]
    assert (c["motor"], c["pulley_teeth"]) == (design["motor"], design["pulley_teeth"]) == ("055U2B30", 24)
    peak = next(r["value"] for r in design["checks"] if r["name"] == "peak_torque")
    assert c["peak_torque_N_m"] == pytest.approx(peak, rel=2e-3)  # 3601 samples vs the fine grid
    assert size["spm"] == design["spm"] and size["drive"]["from"] == f"the design file {solved}"


def test_solve_takes_motor_and_pulley_like_the_set_overrides(capsys, reference_path, thesis_drive_json):
    # before: `solve --motor` was an unrecognized argument; the 600 spm thesis drive gives 1.295 N m
    code, by_options = thesis_drive_json  # solve REFERENCE --spm 600 --motor 055U2B30 --pulley-teeth 28 --json
    assert code == 0
    by_set = _json(capsys, ["solve", str(reference_path), "--spm", "600", "--set", 'design.motor_choice="fixed"',
                            "--set", 'design.pulley="fixed"'])
    assert by_options["objective_value"] == pytest.approx(1.295, abs=5e-4)
    assert by_options["objective_value"] == pytest.approx(by_set["objective_value"], rel=1e-9)
    assert (by_options["motor"], by_options["pulley_teeth"]) == ("055U2B30", 28)
    assert by_options["drive"] == {"motor": "055U2B30", "pulley_teeth": 28,
                                   "from": "--motor, --pulley-teeth on the command line"}
    assert by_set["drive"]["from"] == "the problem file"


@pytest.mark.parametrize("argv, named", [
    (["solve", "--motor", "055U2B30", "--set", "drive.motor=055U2C30"], ("--motor 055U2B30", "drive.motor=055U2C30")),
    (["solve", "--pulley-teeth", "24", "--set", "design.pulley=optimise"], ("--pulley-teeth 24", "design.pulley")),
    (["kinematics", "--pulley-teeth", "24", "--set", "transmission.pulley_teeth=28"],
     ("--pulley-teeth 24", "transmission.pulley_teeth=28")),
])
def test_a_conflicting_drive_is_an_error_naming_both(capsys, reference_path, argv, named):
    code, _, err = _run(capsys, [argv[0], str(reference_path)] + argv[1:] + ["--plot", "none"])
    assert code == 2 and "Traceback" not in err and len(err.strip().splitlines()) == 1
    for text in named:
        assert text in err


@pytest.mark.parametrize("command", ["kinematics", "size", "solve", "simulate", "verify", "accuracy", "tradeoff"])
def test_design_against_another_motor_or_pulley_is_refused(capsys, reference_path, solved, command):
    for option in (["--pulley-teeth", "28"], ["--motor", "055U2C30"]):
        code, _, err = _run(capsys, [command, str(reference_path), "--design", str(solved), *option, "--plot", "none"])
        assert code == 2 and str(solved) in err and " ".join(option) in err and "Traceback" not in err


def test_every_report_says_which_drive_it_used(capsys, reference_path, solved, solve_text):
    kin = _json(capsys, ["kinematics", str(reference_path), "--pulley-teeth", "24"])
    assert kin["pulley_teeth"] == 24 and kin["drive"]["pulley_teeth"] == 24 and kin["drive"]["motor"] == "055U2B30"
    kin = _json(capsys, ["kinematics", str(reference_path), "--design", str(solved)])
    assert kin["pulley_teeth"] == 24 and kin["spm"] == 500
    assert {m["law"] for m in kin["moves"]} == {"optimal"}  # the design's stroke, not the file's law
    acc = _json(capsys, ["accuracy", str(reference_path), "--motor", "055U2C30"])
    assert acc["motor"] == acc["drive"]["motor"] == "055U2C30"
    for command in ("kinematics", "accuracy", "simulate"):
        code, out, _ = _run(capsys, [command, str(reference_path), "--pulley-teeth", "24", "--plot", "none"])
        assert code == 0 and "drive: motor 055U2B30, pulley 24 teeth (from --pulley-teeth on the command line)" in out
    code, out = solve_text  # strokeopt solve REFERENCE --plot none
    assert "drive: motor 055U2B30, pulley 24 teeth (from the solve's choice: design.motor_choice = enumerate" in out


def test_verify_takes_the_design_as_every_command_does(capsys, reference_path, solved):
    old = _json(capsys, ["verify", str(solved)])
    new = _json(capsys, ["verify", str(reference_path), "--design", str(solved)])
    sim = _json(capsys, ["simulate", str(reference_path), "--design", str(solved)])
    assert old["status"] == new["status"] == sim["status"] == "ok"
    assert old["impact_velocity_m_s"] == new["impact_velocity_m_s"] == sim["impact_velocity_m_s"]
    assert new["drive"] == {"motor": "055U2B30", "pulley_teeth": 24, "from": f"the design file {solved}"}
    code, _, err = _run(capsys, ["verify", str(solved), "--design", str(solved), "--problem", str(reference_path)])
    assert code == 2 and "--problem" in err


def test_a_contact_force_says_what_it_is(capsys, reference_path, solved):
    # before: "peak force the drive supplies to the shell: 3348 N" with no limit, while solve checks 1990 N
    code, out, _ = _run(capsys, ["verify", str(reference_path), "--design", str(solved), "--plot", "none"])
    line = next(x for x in out.splitlines() if x.startswith("peak force the drive supplies"))
    assert code == 0 and "stiff-contact spike" in line and "microseconds long" in line
    assert "the belt's breaking load is 1990 N (GT3-3MR-09, glass cord)" in line
    data = _json(capsys, ["simulate", str(reference_path)])
    assert data["belt_breaking_load_N"] == 1990


def test_size_with_no_feasible_pair_exits_1_with_a_verdict(capsys, reference_path):
    # before: every pulley "no", exit 0, no verdict
    code, out, err = _run(capsys, ["size", str(reference_path), "--spm", "1200", "--motor", "055U2B30",
                                   "--plot", "none"])
    verdict = out.strip().splitlines()[-1]
    assert code == 1 and verdict.startswith("infeasible: no motor and pulley passes every check at 1200 spm")
    assert "binding limit: belt_breaking" in verdict and "binding limit" in err
    data = _json(capsys, ["size", str(reference_path), "--spm", "1200", "--motor", "055U2B30"], code=1)
    assert data["status"] == "infeasible" and data["verdict"] == verdict
    ok = _json(capsys, ["size", str(reference_path), "--motor", "055U2B30"])
    assert ok["status"] == "ok" and ok["verdict"].startswith("ok: 055U2B30")


@pytest.mark.parametrize("argv, code, status", [
    (["laws"], 0, "ok"),
    (["kinematics", "{p}"], 0, "ok"),
    (["size", "{p}", "--motor", "055U2B30"], 0, "ok"),
    (["solve", "{p}", "--spm", "600", "--motor", "055U2B30", "--pulley-teeth", "28"], 0, "optimal"),
    pytest.param(["solve", "{p}", "--spm", "1500:1600:100", "--motor", "055U2B30", "--pulley-teeth", "28"], 1,
                 "infeasible", marks=pytest.mark.slow),  # a sweep of two solves that fail
    (["simulate", "{p}"], 0, "ok"),
    (["simulate", "{p}", "--spm", "500:600:100"], 0, "ok"),
    (["accuracy", "{p}"], 0, "ok"),
    (["accuracy", "{p}", "--set", "design.handover_accuracy_mm=0.03"], 1, "limits exceeded"),
    (["tradeoff", "{p}", "--strokes", "classic", "--accuracies", "0.5", "--resolution", "400"], 0, "ok"),
])
def test_every_json_has_a_status(capsys, reference_path, argv, code, status, request):
    argv = [a.format(p=reference_path) for a in argv]
    if argv == ["solve", str(reference_path), "--spm", "600", "--motor", "055U2B30", "--pulley-teeth", "28"]:
        got, data = request.getfixturevalue("thesis_drive_json")  # the same command line, run once
        assert got == code and data["status"] == status
        return
    if argv[0] == "laws":
        got, out, err = _run(capsys, argv + ["--json"])
        assert got == code and json.loads(out)["status"] == status
        return
    data = _json(capsys, argv, code=code)
    assert data["status"] == status


def test_statuses_and_exit_codes_are_documented(capsys):
    with pytest.raises(SystemExit):
        main(["--help"])
    out = " ".join(capsys.readouterr().out.split())
    for status in ("'ok'", "'infeasible'", "'limits exceeded'", "'verification failed'", "'targets missed'"):
        assert status in out
    assert "Exit codes: 0" in out


def test_version(capsys):
    from strokeopt import __version__

    with pytest.raises(SystemExit) as exc:
        main(["--version"])
    assert exc.value.code == 0 and capsys.readouterr().out.strip() == f"strokeopt {__version__}"


@pytest.mark.parametrize("command, has_verbose", [("kinematics", False), ("size", False), ("accuracy", False),
                                                  ("tradeoff", False), ("solve", True), ("simulate", True),
                                                  ("verify", True)])
def test_verbose_only_where_something_is_printed(capsys, command, has_verbose):
    with pytest.raises(SystemExit):
        main([command, "--help"])
    assert ("--verbose" in capsys.readouterr().out) == has_verbose


@pytest.mark.parametrize("argv, code, status", [
    (["solve", "problems/deco2000_needle_bar.toml", "--spm", "2000", "--motor", "055U2B30", "--pulley-teeth", "28"],
     1, "failed"),
    (["kinematics", "problems/deco2000_needle_bar.toml", "--set", "drive.moving_mass_kg=-1"], 2, "bad input"),
])
def test_a_failure_with_json_still_prints_a_json_status(argv, code, status, capsys):
    # a script reading --json gets a report on every exit, not an empty stdout
    root = Path(__file__).resolve().parents[2]
    argv = [str(root / a) if a.startswith("problems/") else a for a in argv]
    assert main([*argv, "--json", "--plot", "none"]) == code
    out, err = capsys.readouterr()
    data = json.loads(out)
    assert data["status"] == status and data["message"] and data["message"] in err
