"""The cam table of ``strokeopt solve --out``: resolution, master unit, columns, header; read back it
reproduces the stroke within its resolution."""

from __future__ import annotations

import csv
import math
from pathlib import Path

import numpy as np
import pytest

from strokeopt.cli.main import main
from strokeopt.files.design_file import read_design
from strokeopt.files.ranges import parse_cam_resolution
from strokeopt.errors import ProblemError

ROOT = Path(__file__).resolve().parents[2]
REFERENCE = ROOT / "problems" / "deco2000_needle_bar.toml"


def read_csv(path: Path) -> tuple[list[str], list[str], np.ndarray]:
    """The '#' header lines, the column names and the numbers of a cam_table.csv."""
    lines = path.read_text(encoding="utf-8").splitlines()
    comments = [line[2:] for line in lines if line.startswith("#")]
    rows = list(csv.reader(line for line in lines if not line.startswith("#")))
    return comments, rows[0], np.array(rows[1:], dtype=float)


@pytest.fixture(scope="module")
def counts_table(tmp_path_factory, reference_verified, write_verified):
    """The reference design (the session's one verified solve, conftest.py) written as ``solve --out DIR
    --cam-table-resolution 720/cycle --master-unit counts --master-counts 7200`` writes it: 720 points per
    cycle, the master in counts (7200 per cycle)."""
    from strokeopt.files.design_file import CamTableSpec

    out = tmp_path_factory.mktemp("cam") / "out"
    write_verified(reference_verified, out, CamTableSpec(parse_cam_resolution("720/cycle"), "counts", 7200),
                   report=False)
    return out


def test_header_states_units_motor_pulley_and_cycle(counts_table, capsys):
    comments, names, table = read_csv(counts_table / "cam_table.csv")
    data, _ = read_design(counts_table / "design.json")
    text = "\n".join(comments)
    assert f"motor: {data['motor']}; pulley: {data['pulley_teeth']}-tooth pulley" in text
    assert f"one cam cycle = {data['cycle_time_s'] * 1e3:.4f} ms = 2 stitches" in text
    assert "master counts, 7200 per cam cycle; 720 points, one every 0.5 deg" in text
    assert names == ["master_counts", "position_mm", "velocity_m_s", "acceleration_m_s2", "jerk_m_s3",
                     "motor_angle_deg", "motor_speed_rpm", "motor_torque_N_m"]
    for name in names:  # every column's unit is stated
        assert any(line.startswith(f"column {name} [") for line in comments)
    assert table.shape == (720, 8)
    assert np.array_equal(table[:, 0], np.arange(720) * 10.0)  # 10 counts per point


def test_table_reproduces_the_stroke_within_its_resolution(counts_table):
    _, names, table = read_csv(counts_table / "cam_table.csv")
    data, stroke = read_design(counts_table / "design.json")
    col = {n: table[:, i] for i, n in enumerate(names)}
    period = data["cycle_time_s"]
    # linear interpolation between the points, periodic over the cycle, against the exact stroke
    t = np.linspace(0.0, period, 20_001)[:-1]
    master = t / period * 7200.0
    s_table = np.interp(master, np.append(col["master_counts"], 7200.0), np.append(col["position_mm"],
                                                                                   col["position_mm"][0]))
    k = stroke.evaluate(t)
    h = period / 720  # one table step in time
    bound_mm = np.max(np.abs(k.a)) * h**2 / 8 * 1e3  # linear interpolation error bound + the 6 decimals written
    err = np.max(np.abs(s_table - k.s * 1e3))
    assert err <= bound_mm + 1e-6
    assert err > 0.05 * bound_mm  # the bound is not vacuous: a 0.5 deg table is visibly coarse
    # the other columns are the stroke's derivatives and the drive's at the points
    kt = stroke.evaluate(np.arange(720) * h)
    assert col["velocity_m_s"] == pytest.approx(kt.v, abs=1e-6)
    assert col["jerk_m_s3"] == pytest.approx(kt.j, abs=0.01)
    r = data["pulley_pitch_diameter_mm"] / 2e3
    assert np.radians(col["motor_angle_deg"]) == pytest.approx(col["position_mm"] * 1e-3 / r, rel=1e-5, abs=1e-6)
    assert col["motor_speed_rpm"] == pytest.approx(kt.v / r * 60 / (2 * math.pi), abs=2e-3)
    # the torque column is the design's torque: its peak at the points within 1 % of the fine-grid check
    peak = next(c["value"] for c in data["checks"] if c["name"] == "peak_torque")
    assert np.max(np.abs(col["motor_torque_N_m"])) == pytest.approx(peak, rel=0.01)


def test_fixed_width_text_is_the_master_and_the_motor_angle(counts_table):
    _, names, table = read_csv(counts_table / "cam_table.csv")
    lines = (counts_table / "cam_table.txt").read_text().splitlines()
    assert len(lines) == 720 and "//" in lines[0] and all("//" not in line for line in lines[1:])
    points = np.array([line.split("//")[0].split() for line in lines], dtype=float)
    assert len({len(line.split("//")[0].rstrip()) for line in lines}) == 1  # fixed width
    assert np.all(np.diff(points[:, 0]) > 0)  # master ascending
    assert points[:, 0] == pytest.approx(table[:, 0])
    assert points[:, 1] == pytest.approx(table[:, names.index("motor_angle_deg")], abs=1e-5)


@pytest.mark.parametrize("text, deg", [("0.1", 0.1), ("0.25deg", 0.25), ("720/cycle", 0.5), ("3600/cycle", 0.1)])
def test_resolution_forms(text, deg):
    assert parse_cam_resolution(text) == pytest.approx(deg, rel=1e-12)


@pytest.mark.parametrize("argv, words", [
    (["--cam-table-resolution", "0.7"], "does not divide the 360 deg"),
    (["--cam-table-resolution", "100"], "outside the plausible range"),
    (["--cam-table-resolution", "fine"], "expected degrees per point"),
    (["--master-unit", "counts", "--master-counts", "1000"], "not a whole number of counts per table point"),
])
def test_bad_cam_table_options_exit_2_before_the_solve(capsys, tmp_path, argv, words):
    code = main(["solve", str(REFERENCE), "--out", str(tmp_path / "o"), "--plot", "none", *argv])
    err = capsys.readouterr().err
    assert code == 2 and err.count("\n") == 1 and words in err
    assert not (tmp_path / "o" / "design.json").exists()


def test_cam_table_options_without_out_are_refused(capsys):
    code = main(["solve", str(REFERENCE), "--plot", "none", "--master-unit", "counts"])
    err = capsys.readouterr().err
    assert code == 2 and err.count("\n") == 1 and "give --out DIR" in err


def test_resolution_out_of_range_names_the_option():
    with pytest.raises(ProblemError, match="--cam-table-resolution"):
        parse_cam_resolution("0.0001")
