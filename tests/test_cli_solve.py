"""`strokeopt solve` through strokeopt.cli.main."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from strokeopt.cli import main

ROOT = Path(__file__).resolve().parents[1]
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
    assert data["moves"][0]["C_a"] == pytest.approx(5.7735, rel=0.005)  # DESIGN.md known optimum
    assert {"v_max_m_s", "a_max_m_s2", "jerk_max_m_s3"} <= set(data["moves"][0])
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
    for name in ("design.json", "cam_table.csv", "stroke.png"):
        assert (out / name).is_file()
    assert (tmp_path / "f.png").is_file()
    header = (out / "cam_table.csv").read_text().splitlines()[0]
    assert header == "cam_angle_deg,position_mm,velocity_m_s,acceleration_m_s2,motor_angle_deg"


def test_sweep_prints_fastest_feasible_rate(capsys):
    argv = ["solve", str(KNOWN / "jerk_bounded_peak_accel.toml"), "--set", "design.jerk_max_from_law=false",
            "--set", "design.jerk_max_m_s3=60", "--spm", "30:42:6", "--plot", "none"]
    assert main(argv) == 0
    captured = capsys.readouterr()
    assert "fastest feasible stitch rate: 36 spm" in captured.out
    assert "jerk bound needs" in captured.out
    data = _json(capsys, argv + ["--json"])
    assert data["fastest_feasible_spm"] == 36 and [r["spm"] for r in data["rows"]] == [30, 36, 42]


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
