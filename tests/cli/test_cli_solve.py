"""`strokeopt solve` through strokeopt.cli.main."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from strokeopt.cli.main import main
from strokeopt.files.design_file import read_design

ROOT = Path(__file__).resolve().parents[2]
KNOWN = ROOT / "problems" / "known_optima"
REFERENCE = ROOT / "problems" / "deco2000_needle_bar.toml"


def _json(capsys, argv):
    code = main(argv)
    out = capsys.readouterr()
    assert code == 0, out.err
    return json.loads(out.out)


def test_known_optimum_json(capsys, tmp_path):
    data = _json(capsys, ["solve", str(KNOWN / "min_jerk.toml"), "--json", "--plot", "none"])
    for key in ("status", "objective", "objective_value", "motor", "pulley_teeth", "spm", "peak_torque_N_m",
                "rms_torque_N_m", "moves", "active_constraints", "solve_time_s"):
        assert key in data
    assert data["status"] == "optimal" and data["objective"] == "min_jerk"
    assert data["moves"][0]["index"] == 1
    assert data["moves"][0]["C_a"] == pytest.approx(5.7735, rel=0.005)  # docs/architecture.md known optimum
    assert {"v_max_m_s", "a_max_m_s2", "jerk_max_m_s3"} <= set(data["moves"][0])
    # the convention of `strokeopt kinematics`: stroke_mm >= 0 with a direction
    assert [(m["stroke_mm"], m["direction"]) for m in data["moves"]] == [(1000, "up"), (1000, "down")]
    rows = {r["law"]: r for r in data["comparison"]}
    assert rows["poly5"]["vs_optimal_pct"] == pytest.approx(0, abs=0.01)  # the optimum is the 3-4-5 law
    assert rows["poly7"]["vs_optimal_pct"] > 0


def test_objective_and_spm_override_the_file(capsys):
    data = _json(capsys, ["solve", str(KNOWN / "min_jerk.toml"), "--objective", "min_peak_accel", "--spm", "60",
                          "--json", "--plot", "none"])
    assert data["objective"] == "min_peak_accel" and data["spm"] == 60
    # 1 m in 0.5 s at rest_order 2 (a = 0 at the ends): peak acceleration above 4 h/T^2 = 16 m/s^2
    assert data["objective_value"] > 16


def test_text_report_and_out_dir(capsys, tmp_path):
    out = tmp_path / "design"
    code = main(["solve", str(KNOWN / "jerk_bounded_peak_accel.toml"), "--out", str(out), "--plot",
                 str(tmp_path / "f.png")])
    text = capsys.readouterr().out
    assert code == 0
    assert "objective min_peak_accel: 4.445" in text
    assert "active constraints: jerk bound move 1" in text
    assert "modified_sine (chi = 0.095)" in text  # the comparison with the file's law
    # the figure once, where --plot says (not also into --out)
    assert sorted(f.name for f in out.iterdir()) == ["cam_table.csv", "cam_table.txt", "design.json", "report.html"]
    assert (tmp_path / "f.png").is_file()
    # the column names follow the '#' lines stating the cycle, master, motor, pulley and units
    header = [line for line in (out / "cam_table.csv").read_text().splitlines() if not line.startswith("#")][0]
    assert header == ("cam_angle_deg,position_mm,velocity_m_s,acceleration_m_s2,jerk_m_s3,motor_angle_deg,"
                      "motor_speed_rpm")  # no motor in this problem: no torque column
    # design.json: stroke_mm >= 0 with a direction, and the stroke rebuilt from it goes up then back down
    data, stroke = read_design(out / "design.json")
    assert [(m["stroke_mm"], m["direction"]) for m in data["moves"]] == [(1000, "up"), (1000, "down")]
    ends = [itv["t_start_s"] + itv["duration_s"] for itv in data["intervals"]]
    assert stroke.evaluate(np.array(ends) - 1e-9).s == pytest.approx([1.0, 0.0], abs=1e-6)
    assert "1000         up" in text and "1000       down" in text


@pytest.mark.slow  # two sweeps of three rates through the command line
def test_sweep_prints_fastest_feasible_rate(capsys):
    argv = ["solve", str(KNOWN / "jerk_bounded_peak_accel.toml"), "--set", "design.jerk_max_from_law=false",
            "--set", "design.jerk_max_m_s3=60", "--spm", "30:42:6", "--plot", "none"]
    assert main(argv) == 0
    captured = capsys.readouterr()
    assert "fastest feasible stitch rate: 36 spm" in captured.out
    assert "jerk bound needs" in captured.out
    data = _json(capsys, argv + ["--json"])
    assert data["fastest_feasible_spm"] == 36 and [r["spm"] for r in data["rows"]] == [30, 36, 42]
    assert data["fastest_feasible_is_sweep_end"] is False


@pytest.mark.slow  # two sweeps of two rates through the command line
def test_sweep_that_never_fails_says_the_limit_is_beyond_it(capsys):
    # every rate feasible: the end of the sweep is a lower bound of the fastest rate, not the fastest rate
    argv = ["solve", str(KNOWN / "min_jerk.toml"), "--spm", "30:40:10", "--plot", "none"]
    assert main(argv) == 0
    out = capsys.readouterr().out
    assert "fastest feasible stitch rate: >= 40 spm (the end of the sweep; every rate was feasible)" in out
    data = _json(capsys, argv + ["--json"])
    assert data["fastest_feasible_spm"] == 40 and data["fastest_feasible_is_sweep_end"] is True


def test_mesh_study(capsys, tmp_path):
    data = _json(capsys, ["solve", str(KNOWN / "jerk_bounded_peak_accel.toml"), "--study", "mesh", "--json",
                          "--plot", str(tmp_path / "study.png")])
    rows = data["rows"]
    assert rows[-1]["reference"] and rows[-1]["objective_error_pct"] == 0
    # finer meshes of the same degree are at least as accurate
    deg3 = [r["objective_error_pct"] for r in rows if r["degree"] == 3]
    assert deg3 == sorted(deg3, reverse=True)
    assert all(r["violation_between_nodes"] < 1e-6 for r in rows)  # hull bounds hold everywhere
    assert (tmp_path / "study.png").is_file()


def test_mesh_study_text_says_the_violation_is_relative(capsys):
    """The column had no unit: the violation between nodes is relative to the bound (value / limit - 1)."""
    assert main(["solve", str(KNOWN / "jerk_bounded_peak_accel.toml"), "--study", "mesh", "--plot", "none"]) == 0
    text = capsys.readouterr().out
    assert "violation between nodes (relative)" in text and "relative to the bound (value / limit - 1)" in text


def test_bad_input_exits_2_with_one_line(capsys):
    assert main(["solve", str(KNOWN / "min_jerk.toml"), "--objective", "min_speed"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "min_speed" in err and "min_peak_torque" in err
    assert main(["solve", str(KNOWN / "min_jerk.toml"), "--spm", "900:400:50"]) == 2
    assert "STOP" in capsys.readouterr().err


def test_infeasible_exits_1_naming_the_constraint(capsys):
    code = main(["solve", str(KNOWN / "min_jerk.toml"), "--set", "design.jerk_max_m_s3=20", "--plot", "none"])
    err = capsys.readouterr().err
    assert code == 1
    assert err.startswith("strokeopt: failed: move") and "jerk bound needs 32 m/s^3, limit 20 m/s^3" in err
    assert "Ipopt" not in err and "EXIT" not in err


def test_comparison_flags_laws_that_break_the_problems_constraints(capsys):
    # min_jerk.toml holds v = a = 0 at the ends (rest_order = 2): the cubic, cosine and parabolic laws
    # jump in acceleration at the dwells, so their lower (or infinite) jerk integral is no win
    data = _json(capsys, ["solve", str(KNOWN / "min_jerk.toml"), "--json", "--plot", "none"])
    rows = data["comparison"]
    by_law = {r["law"]: r for r in rows}
    assert rows[0]["law"] == "optimal" and rows[0]["feasible"] is True and rows[0]["violates"] == []
    for law in ("parabolic", "cubic", "cosine"):
        assert by_law[law]["feasible"] is False and by_law[law]["violates"] == ["rest (acceleration)"]
        assert by_law[law]["jerk_max_m_s3"] is None  # an impulse at the dwells: infinite (null in JSON)
    for law in ("sine", "poly5", "poly7"):
        assert by_law[law]["feasible"] is True and by_law[law]["violates"] == []
    # infeasible laws come last, and no feasible law beats the optimum
    flags = [r["feasible"] for r in rows]
    assert flags == sorted(flags, reverse=True)
    assert all(r["vs_optimal_pct"] >= -1e-6 for r in rows if r["feasible"])
    # the text table says it on the law's line
    assert main(["solve", str(KNOWN / "min_jerk.toml"), "--plot", "none"]) == 0
    text = capsys.readouterr().out
    cubic = next(line for line in text.splitlines() if line.strip().startswith("cubic"))
    assert cubic.endswith("no: rest (acceleration)")
    assert "break the problem's constraints" in text


def test_comparison_follows_the_files_rest_order_and_jerk_bound(capsys):
    # rest_order = 1 lets the acceleration jump at the dwells: the cubic is then allowed; a jerk bound
    # of 61 m/s^3 (h = 1 m, T = 1 s) rules out the laws whose C_j exceeds 61 (modified sine 69.5)
    data = _json(capsys, ["solve", str(KNOWN / "min_jerk.toml"), "--set", "design.rest_order=1", "--set",
                          "design.jerk_max_m_s3=61", "--json", "--plot", "none"])
    by_law = {r["law"]: r for r in data["comparison"]}
    assert by_law["cubic"]["feasible"] is True
    assert by_law["modified_sine (chi = 0.125)"]["violates"] == ["jerk bound"]
    assert by_law["parabolic"]["violates"] == ["jerk bound"]  # its acceleration jumps mid-move
    assert by_law["poly5"]["feasible"] is True


def test_out_must_be_a_directory_checked_before_solving(capsys, tmp_path):
    existing = tmp_path / "README.md"
    existing.write_text("not a directory\n")
    for out in (existing, existing / "sub"):
        code = main(["solve", str(KNOWN / "min_jerk.toml"), "--out", str(out), "--plot", str(tmp_path / "f.png")])
        captured = capsys.readouterr()
        assert code == 2 and captured.out == ""
        assert captured.err.count("\n") == 1 and captured.err.startswith("strokeopt: error: --out: ")
        assert "not a directory" in captured.err and "Traceback" not in captured.err
    assert not (tmp_path / "f.png").exists()  # nothing solved, nothing drawn
    assert existing.read_text() == "not a directory\n"


def test_infeasible_message_first_line_short_then_details(capsys):
    code = main(["solve", str(KNOWN / "min_jerk.toml"), "--set", "design.jerk_max_m_s3=20", "--plot", "none"])
    lines = capsys.readouterr().err.splitlines()
    assert code == 1
    assert len(lines[0]) < 120 and "jerk bound needs 32 m/s^3, limit 20 m/s^3 (60.0 % over)" in lines[0]
    assert lines[1].startswith("  also (move ") and "jerk bound" in lines[1]


def test_a_design_over_its_limits_between_nodes_is_not_optimal(capsys):
    # the jerk bound is held on Bernstein coefficients up to IPOPT's precision (~1e-8 relative); with a
    # check tolerance below that and no refinement the fine grid finds it over: status and exit code say so
    code = main(["solve", str(KNOWN / "jerk_bounded_peak_accel.toml"), "--set", "design.check_tolerance=1e-12",
                 "--set", "design.refinements=0", "--plot", "none", "--json"])
    captured = capsys.readouterr()
    data = json.loads(captured.out)
    failed = [c for c in data["checks"] if not c["ok"]]
    assert code == 1 and data["status"] == "limits exceeded" and failed
    assert failed[0]["name"] in captured.err and "limits exceeded between collocation nodes" in captured.err
    # the same design with the default tolerance is fine (the margin shows the exact value either way)
    assert main(["solve", str(KNOWN / "jerk_bounded_peak_accel.toml"), "--plot", "none", "--json"]) == 0
    assert json.loads(capsys.readouterr().out)["status"] == "optimal"


def test_a_feasible_law_below_the_optimum_is_explained(capsys):
    # inertia matching at rest_order 1: the parabolic law is the exact optimum, the mesh's optimum is 0.1 % above it
    assert main(["solve", str(KNOWN / "inertia_matching.toml"), "--plot", "none"]) == 0
    out = capsys.readouterr().out
    assert "parabolic is" in out and "below the optimal stroke and feasible" in out and "--study mesh" in out
    assert "None teeth" not in out and "continuous radius" in out


def test_an_incomplete_design_file_names_the_missing_field(capsys, tmp_path):
    bad = tmp_path / "design.json"
    bad.write_text(json.dumps({"format": "strokeopt-design", "mesh": {"intervals": 4, "degree": 3}}))
    assert main(["verify", str(bad), "--plot", "none"]) == 2
    err = capsys.readouterr().err
    assert str(bad) in err and "moves" in err and "missing" in err and "Traceback" not in err
