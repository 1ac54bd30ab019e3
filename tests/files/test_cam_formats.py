"""Cam tables for controllers (``strokeopt camtable``, files/cam_formats.py): each format written, read back,
interpolated as its controller does and checked against the verified stroke; the interpolated stroke judged
by the verified pipeline."""

from __future__ import annotations

import json

import numpy as np
import pytest

from strokeopt.cli.main import main
from strokeopt.design.transcription.settings import CAM_TABLE_FORMATS
from strokeopt.files import cam_formats as cf


def test_the_formats_are_the_ones_a_problem_file_may_ask_for():
    assert tuple(cf.FORMATS) == CAM_TABLE_FORMATS


def test_quintic_segments_reproduce_a_quintic_and_meet_their_points():
    # a fifth-order polynomial over the whole cycle is reproduced exactly by the quintic through its own
    # position, velocity and acceleration at the points; straight lines meet the points only
    n = 36
    master = np.arange(n + 1) * (360.0 / n)
    poly = np.polynomial.Polynomial([3.0, -0.2, 1e-3, 4e-6, -2e-8, 3e-11])
    points = (poly(master), poly.deriv(1)(master), poly.deriv(2)(master))
    fine = np.linspace(0.0, 359.9, 3001)
    p, d1, d2 = cf.segments(points, "quintic").evaluate(fine)
    assert np.allclose(p, poly(fine), atol=1e-9)
    assert np.allclose(d1, poly.deriv(1)(fine), atol=1e-9)
    assert np.allclose(d2, poly.deriv(2)(fine), atol=1e-9)
    lin, slope, curvature = cf.segments(points, "linear").evaluate(master[:-1] + 5.0)
    assert np.allclose(lin, (poly(master[:-1]) + poly(master[1:])) / 2)  # the midpoint of each chord
    assert np.all(curvature == 0.0)


@pytest.fixture(scope="module")
def design(reference_written):
    from strokeopt.design.result import design_from_data
    from strokeopt.files.design_file import read_design
    from strokeopt import load_problem

    data, stroke = read_design(reference_written.out / "design.json")
    problem = load_problem(data["problem_file"]).with_spm(float(data["spm"]))
    return design_from_data(problem, data, stroke)


def test_deviation_falls_with_the_points_as_each_interpolation_should(design):
    # linear interpolation errs by a'' h^2/8: a quarter for twice the points; the quintic far faster
    lin = [cf.deviation(design, cf.design_segments(design, "csv", n)[0]).position_deg for n in (360, 720)]
    assert lin[1] / lin[0] == pytest.approx(0.25, rel=0.05)
    quint = [cf.deviation(design, cf.design_segments(design, "xyva", n)[0]).position_deg for n in (360, 720)]
    assert quint[1] / quint[0] < 0.25 and quint[0] < lin[0] / 100


def test_the_load_deviation_is_the_motor_angle_over_the_pulley_radius(design):
    d = cf.deviation(design, cf.design_segments(design, "csv", 720)[0])
    assert d.position_load == pytest.approx(np.radians(d.position_deg) * design.radius, rel=1e-3)


@pytest.mark.parametrize("fmt", ["xyva", *(pytest.param(f, marks=pytest.mark.slow)  # each re-simulates the design
                                            for f in ("poly5", "segments", "csv"))])
def test_camtable_check_of_the_reference_design(fmt, reference_written, tmp_path, capsys):
    # the acceptance: each format within 1 um at its default number of points, saying how many
    out = tmp_path / f"cam_{fmt}.csv"
    code = main(["camtable", str(reference_written.out / "design.json"), "--format", fmt, "--out", str(out),
                 "--check", "--json"])
    report = json.loads(capsys.readouterr().out)
    assert code == 0 and report["status"] == "ok"
    check = report["check"]
    assert check["position_load_um"] <= 1.0 and check["within_tolerance"]
    assert report["points"] == report["points_needed"]  # the fewest within 1 um (test_points_needed_is_the_fewest)
    assert report["resimulated"]["ok"] and "met: handover error" in report["resimulated"]["verdict"]
    # the re-simulated handover error is the verified one's within what the table changes (0.0415 mm)
    assert report["resimulated"]["handover_unit"] == "mm"
    assert report["resimulated"]["handover_error"] == pytest.approx(0.0415, rel=0.05)
    if fmt == "csv":  # linear: every column of cam_table.csv, and no acceleration between the points
        assert check["acceleration_share_of_peak"] == pytest.approx(1.0, rel=1e-6)
        assert report["drive_checks"] == []  # judged on the design: a linear table has no inertia torque
    else:
        assert check["acceleration_share_of_peak"] < 0.1
        rows = {c["name"]: c for c in report["drive_checks"]}
        assert all(c["ok"] for c in rows.values())
        # the table's stroke on the design's drive: the design's peak torque moved by what the quintic's
        # acceleration deviation (5.9 % of the peak at 180 points) moves the inertia torque: 0.9077 N m
        peak = rows["peak_torque"]
        assert peak["design_value"] == pytest.approx(0.8596, rel=1e-3)
        assert abs(peak["value"] / peak["design_value"] - 1) <= 1.05 * check["acceleration_share_of_peak"]


def test_points_needed_is_the_fewest(design):
    n = cf.points_needed(design, "xyva", 1e-6)
    smaller = cf.POINT_CHOICES[cf.POINT_CHOICES.index(n) - 1]
    assert cf.deviation(design, cf.design_segments(design, "xyva", n)[0]).position_load <= 1e-6
    assert cf.deviation(design, cf.design_segments(design, "xyva", smaller)[0]).position_load > 1e-6


def test_too_few_points_fail_the_check(reference_written, tmp_path, capsys):
    out = tmp_path / "coarse.csv"
    code = main(["camtable", str(reference_written.out / "design.json"), "--format", "xyva", "--points", "36",
                 "--out", str(out), "--check"])
    text = capsys.readouterr()
    assert code == 1 and "NOT within 1 um" in text.out and "check failed" in text.err


@pytest.mark.parametrize("argv, message", [
    (["--format", "xyva", "--points", "100000"], "--points: 100000 is not one of"),
    (["--format", "xyva", "--tolerance", "-1"], "--tolerance: must be a positive number"),
    (["--format", "xml"], "invalid choice: 'xml'"),
])
def test_bad_options(argv, message, reference_written, tmp_path, capsys):
    argv = ["camtable", str(reference_written.out / "design.json"), "--out", str(tmp_path / "t.csv"), *argv]
    try:
        code = main(argv)
    except SystemExit as exc:  # argparse's own refusal (an unknown format)
        code = exc.code
    err = capsys.readouterr().err
    assert code == 2 and message in err and "Traceback" not in err


def test_a_damaged_table_is_refused_naming_the_column(reference_written, tmp_path):
    from strokeopt.errors import ProblemError

    out = tmp_path / "t.csv"
    assert main(["camtable", str(reference_written.out / "design.json"), "--format", "xyva", "--out", str(out)]) == 0
    lines = out.read_text().splitlines()
    damaged = [*lines[:-3], lines[-3].rsplit(",", 1)[0] + ",abc", *lines[-2:]]
    out.write_text("\n".join(damaged))
    with pytest.raises(ProblemError, match="slave_acceleration_deg_per_deg2.*not a number"):
        cf.read_segments(out, "xyva")
    out.write_text("\n".join(lines[:-6] + lines[-5:]))  # a point left out: the master steps are uneven
    with pytest.raises(ProblemError, match="not .* equidistant"):
        cf.read_segments(out, "xyva")


def test_solve_out_writes_the_formats_the_problem_asks_for(design, tmp_path):
    # [design] cam_tables: solve --out writes cam_<format>.csv beside design.json (cli/solve_command.py)
    written = cf.write_tables(design, tmp_path, ("xyva", "segments"))
    assert [p.name for p, _ in written] == ["cam_xyva.csv", "cam_segments.csv"]
    for (path, n), fmt in zip(written, ("xyva", "segments")):
        assert n == cf.points_needed(design, fmt, 1e-6)
        assert cf.deviation(design, cf.read_segments(path, fmt)).position_load <= 1e-6


@pytest.mark.parametrize("value, message", [
    ('["xml"]', "unknown format 'xml'"),
    ('"xyva"', "must be a list of format names"),
    ('["xyva", "xyva"]', "names a format twice"),
])
def test_bad_cam_tables_field(reference_path, value, message):
    from strokeopt import ProblemError, load_problem

    with pytest.raises(ProblemError, match=message) as exc:
        load_problem(reference_path, [f"design.cam_tables={value}"])
    assert exc.value.field == "design.cam_tables"
    assert load_problem(reference_path, ['design.cam_tables=["poly5"]']).design.cam_tables == ("poly5",)


# --------------------------------------------------------------------------- --stroke FILE.csv: a motion made elsewhere

def test_a_cam_table_read_as_a_stroke_is_the_design_stroke(design, reference_written):
    # cam_table.csv (3600 points, positions to 1e-6 mm) joined by the periodic cubic spline: the design's stroke
    # within 0.01 um, its acceleration within 1 % of the peak (what a table's six digits leave of it)
    stroke = cf.read_stroke(reference_written.out / "cam_table.csv", design.problem, design.spm)
    assert len(stroke.pieces) == len(design.problem.timing.intervals)  # a piece per interval, as a law's
    t = np.linspace(0.0, stroke.period, 40001)
    got, want = stroke.evaluate(t), design.stroke.evaluate(t)
    assert np.max(np.abs(got.s - want.s)) < 1e-8
    assert np.max(np.abs(got.a - want.a)) < 0.01 * np.max(np.abs(want.a))


def test_a_point_table_of_another_spacing_is_the_spline_through_it(reference, tmp_path):
    # uneven master steps: the periodic cubic spline through the points (scipy's), read by the stroke exactly
    from scipy.interpolate import CubicSpline

    angles = np.array([0, 10, 25, 45, 70, 100, 140, 180, 220, 260, 300, 330])
    mm = np.array([0, -1, -8, -20, -30, -31, -31, -25, -12, -3, 0, 0.5])
    path = tmp_path / "points.csv"
    path.write_text("# a motion from elsewhere\ncam_angle_deg,position_mm\n"
                    + "\n".join(f"{a},{p}" for a, p in zip(angles, mm)) + "\n")
    stroke = cf.read_stroke(path, reference, 500)
    spline = CubicSpline(np.append(angles, 360), np.append(mm, mm[0]) * 1e-3, bc_type="periodic")
    x = np.linspace(0, 359.9, 1777)
    k = stroke.evaluate(x / 360 * stroke.period)
    assert np.allclose(k.s, spline(x), atol=1e-12)
    assert np.allclose(k.v, spline(x, 1) * 360 / stroke.period, rtol=1e-9, atol=1e-9)


@pytest.mark.parametrize("text, field, words", [
    ("cam_angle_deg,position_mm\n" + "\n".join(f"{a},0" for a in range(0, 360, 90)), "cam_angle_deg", "at least 8"),
    ("angle,position_mm\n0,0\n", "master", "no master column"),
    ("cam_angle_deg,position_deg\n0,0\n", "position_mm", "moves a linear load"),
    ("cam_angle_deg,position_mm\n" + "\n".join(f"{a},0" for a in [5, *range(10, 360, 30)]), "cam_angle_deg",
     "must start at 0"),
    ("cam_angle_deg,position_mm\n" + "\n".join(f"{a},0" for a in [*range(0, 300, 30), 20]), "cam_angle_deg",
     "rise strictly"),
    ("cam_angle_deg,position_mm\n" + "\n".join(f"{a},{'nan' if a == 60 else 0}" for a in range(0, 360, 30)),
     "position_mm", "not finite"),
])
def test_bad_stroke_tables(reference, tmp_path, text, field, words):
    from strokeopt import ProblemError

    path = tmp_path / "t.csv"
    path.write_text(text + "\n")
    with pytest.raises(ProblemError, match=words) as exc:
        cf.read_stroke(path, reference)
    assert exc.value.field == field


@pytest.mark.parametrize("command", ["kinematics", "size", "simulate"])
def test_stroke_option_runs_through_the_commands(command, reference_path, reference_written, capsys):
    # the acceptance: a --stroke FILE.csv through kinematics, size and simulate
    table = str(reference_written.out / "cam_table.csv")
    extra = {"size": ["--motor", "055U2B30", "--pulley-teeth", "24"], "simulate": ["--scene", "release"]}
    assert main([command, str(reference_path), "--stroke", table, "--json", "--plot", "none",
                 *extra.get(command, [])]) == 0
    data = json.loads(capsys.readouterr().out)
    if command == "kinematics":
        move = data["moves"][0]
        assert move["law"] == "table cam_table.csv" and move["a_max_m_s2"] == pytest.approx(257.0, rel=0.01)
    elif command == "size":  # the design's drive and stroke: its peak torque, 0.8596 N m
        assert data["candidates"][0]["peak_torque_N_m"] == pytest.approx(0.8596, rel=0.01)
    else:  # the design's release scene: the impact at 2.607 m/s (the verified design's)
        assert data["impact_velocity_m_s"] == pytest.approx(2.607, rel=0.01)


def test_stroke_option_refuses_a_second_stroke(reference_path, reference_written, capsys):
    table = str(reference_written.out / "cam_table.csv")
    assert main(["kinematics", str(reference_path), "--stroke", table, "--law", "poly5", "--plot", "none"]) == 2
    assert "--stroke: the table is the stroke" in capsys.readouterr().err
    assert main(["kinematics", str(reference_path), "--stroke", table, "--design",
                 str(reference_written.out / "design.json"), "--plot", "none"]) == 2
    assert "give the stroke once" in capsys.readouterr().err


@pytest.mark.parametrize("command", ["kinematics", "size", "simulate"])
def test_a_points_law_file_runs_through_the_commands(command, write_problem, capsys):
    # the acceptance: a law = "points" file through kinematics, size and simulate
    path = write_problem(lambda text: text.replace(
        'handover = true                   # ends at the needle handover position\npublished_time_s = 0.0252\n',
        'handover = true\npublished_time_s = 0.0252\nlaw = "points"\nangles_deg = [6, 12, 18.7, 25, 31]\n'
        'positions_mm = [1.6, 8.0, 16.0, 24.0, 30.4]\n', 1))
    extra = {"size": ["--motor", "055U2B30"], "simulate": ["--scene", "release"]}
    assert main([command, str(path), "--json", "--plot", "none", *extra.get(command, [])]) == 0
    data = json.loads(capsys.readouterr().out)
    if command == "kinematics":
        move = data["moves"][0]
        assert move["law"] == "points (5 points, rest order 2)" and move["stroke_mm"] == pytest.approx(32.0)
        assert data["moves"][1]["law"].startswith("modified_sine")
    elif command == "size":
        assert data["candidates"][0]["motor"] == "055U2B30" and data["candidates"][0]["peak_torque_N_m"] > 0
    else:
        assert data["stroke"].startswith("modified_sine (chi = 0.095), points") and data["impact_velocity_m_s"] > 0


def test_out_never_writes_over_the_design_or_another_file(reference_written, tmp_path, capsys):
    design = reference_written.out / "design.json"
    before = design.read_bytes()
    assert main(["camtable", str(design), "--format", "xyva", "--out", str(design)]) == 2
    assert "is the design file itself" in capsys.readouterr().err
    other = tmp_path / "notes.csv"
    other.write_text("my own numbers\n")
    assert main(["camtable", str(design), "--format", "xyva", "--out", str(other)]) == 2
    assert "not a cam table strokeopt wrote" in capsys.readouterr().err
    assert design.read_bytes() == before and other.read_text() == "my own numbers\n"
    table = tmp_path / "t.csv"  # a table strokeopt wrote is written over
    assert main(["camtable", str(design), "--format", "xyva", "--out", str(table)]) == 0
    assert main(["camtable", str(design), "--format", "poly5", "--out", str(table)]) == 0
    assert "Polynomial5" in table.read_text()
    assert main(["camtable", str(design), "--format", "xyva"]) == 2
    assert "give --out FILE" in capsys.readouterr().err


@pytest.mark.slow  # two table checks with their re-simulations: about 5 s
def test_check_file_judges_a_table_edited_by_hand(reference_written, tmp_path, capsys):
    # one point of an xyva table moved by 0.05 deg of motor: about 10 um at the bar (24-tooth pulley, r 11.46 mm)
    design = str(reference_written.out / "design.json")
    table = tmp_path / "edited.csv"
    assert main(["camtable", design, "--format", "xyva", "--out", str(table)]) == 0
    capsys.readouterr()
    lines = table.read_text().splitlines()
    i = next(k for k, line in enumerate(lines) if line.startswith("30.000000,"))
    master, slave, *rest = lines[i].split(",")
    lines[i] = ",".join([master, repr(float(slave) + 0.05), *rest])
    table.write_text("\n".join(lines) + "\n")
    code = main(["camtable", design, "--format", "xyva", "--check-file", str(table), "--json"])
    out, err = capsys.readouterr()
    report = json.loads(out)
    assert code == 1 and report["status"] == "check failed" and not report["written"]
    assert report["check"]["position_motor_deg"] == pytest.approx(0.05, rel=0.01)
    assert report["check"]["position_load_um"] == pytest.approx(np.radians(0.05) * 11.459e-3 * 1e6, rel=0.01)
    assert "position 9.9" in err and "over the tolerance 1 um" in err
