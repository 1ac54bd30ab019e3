"""One convention in every figure and table (issue 14, items 3 and 5): figure file names that carry what
distinguishes a run, no figure with --json unless --plot asks, positions in the problem's coordinates on
every axis, the solve's torque-speed figure, unwritable --out/--plot refused before the work, column
names that say what they are, one number format per column, the premature verdict and the gap agree."""

from __future__ import annotations

import matplotlib
import numpy as np
import pytest

from strokeopt.cli.main import main
from strokeopt.report.format import format_table

matplotlib.use("Agg")

STEM = "deco2000_needle_bar"


def _one_line_error(capsys, option: str) -> str:
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "Traceback" not in err and option in err, err
    return err


# --------------------------------------------------------------------------- figure files


def test_default_figures_are_named_by_what_distinguishes_them(capsys, reference_path, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    assert main(["kinematics", str(reference_path), "--spm", "600"]) == 0
    assert main(["kinematics", str(reference_path), "--spm", "700", "--law", "poly5"]) == 0
    names = sorted(f.name for f in (tmp_path / "strokeopt-out").iterdir())
    assert names == [f"{STEM}_kinematics_600spm_modified_sine_chi0.095.png", f"{STEM}_kinematics_700spm_poly5.png"]


def test_json_alone_writes_no_figure_unless_plot_asks(capsys, reference_path, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    assert main(["kinematics", str(reference_path), "--json"]) == 0
    assert main(["size", str(reference_path), "--spm", "600", "--motor", "055U2B30", "--json"]) == 0
    assert main(["simulate", str(reference_path), "--spm", "600", "--json"]) == 0
    assert not (tmp_path / "strokeopt-out").exists()
    assert main(["kinematics", str(reference_path), "--json", "--plot", "k.png"]) == 0
    assert (tmp_path / "k.png").stat().st_size > 10_000


@pytest.mark.slow  # two solves at 600 spm through the command line, with design.json, report and figures
def test_solve_writes_its_figure_once_with_the_torque_speed_path(capsys, reference_path, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    assert main(["solve", str(reference_path), "--spm", "600", "--out", "out"]) == 0
    name = f"{STEM}_solve_600spm_min_peak_torque.png"
    # with --out the figure goes beside design.json, and nowhere else
    assert sorted(f.name for f in (tmp_path / "out").iterdir()) == sorted(["cam_table.csv", "cam_table.txt", "design.json", "report.html", name])
    assert not (tmp_path / "strokeopt-out").exists()
    assert main(["solve", str(reference_path), "--spm", "600", "--objective", "min_rms_torque"]) == 0
    assert [f.name for f in (tmp_path / "strokeopt-out").iterdir()] == [f"{STEM}_solve_600spm_min_rms_torque.png"]


def test_design_figure_has_the_torque_speed_panel(reference, reference_verified):
    from strokeopt.report.design import plot_design

    design = reference_verified.design  # 500 spm: 055U2B30, 24 teeth, 0.8596 N m (conftest.py, solved once)
    fig = plot_design(design, reference.stroke(design.spm))
    panel = [ax for ax in fig.axes if ax.get_xlabel() == "motor speed [rpm]"]
    assert len(panel) == 1
    labels = panel[0].get_legend_handles_labels()[1]
    for wanted in ("motor peak", "motor rated", "torque limit 3.60 N m", "cycle", "RMS"):
        assert any(label.startswith(wanted) for label in labels), (wanted, labels)
    # the peak operating point with its sign, where it is drawn (move 1 runs down: negative torque)
    assert any(label.startswith(("peak 0.860 N m", "peak -0.860 N m")) for label in labels), labels
    assert design.motor in fig._suptitle.get_text() and "min_peak_torque" in fig._suptitle.get_text()
    # the path drawn is the design's: its largest |torque| is the peak of the check table
    cycle = next(line for line in panel[0].get_lines() if line.get_label() == "cycle")
    assert np.max(np.abs(cycle.get_ydata())) == pytest.approx(design.check_value("peak_torque"), rel=2e-3)


# --------------------------------------------------------------------------- unwritable outputs


@pytest.mark.parametrize("args, option", [
    (["solve", "{p}", "--out", "/proc/nope"], "--out"),
    (["solve", "{p}", "--plot", "/proc/nope/x.png"], "--plot"),
    (["kinematics", "{p}", "--plot", "/proc/nope/x.png"], "--plot"),
    (["size", "{p}", "--plot", "/proc/nope/x.png"], "--plot"),
    (["kinematics", "{p}", "--plot", "{tmp}/dir.png"], "--plot"),  # a directory, not a file
])
def test_unwritable_out_or_plot_is_a_one_line_error_before_any_work(args, option, capsys, reference_path, tmp_path,
                                                                    monkeypatch):
    import strokeopt.files.problem_file as problem_file

    def no_work(*a, **k):
        raise AssertionError("the problem was loaded: the output path was not checked first")

    monkeypatch.setattr(problem_file, "load_problem", no_work)
    (tmp_path / "dir.png").mkdir()
    assert main([a.format(p=reference_path, tmp=tmp_path) for a in args]) == 2
    _one_line_error(capsys, option)


# --------------------------------------------------------------------------- coordinates


def test_every_position_axis_names_its_frame(reference):
    from strokeopt.report.motion import plot_kinematics

    fig = plot_kinematics(reference, reference.stroke(600), 600)
    labels = [ax.get_ylabel() for ax in fig.axes]
    assert all("problem frame" in label for label in labels[:2]), labels


def test_simulate_figure_is_in_the_problems_coordinates(reference):
    from strokeopt.contact.simulate import simulate_scene
    from strokeopt.report.contact import plot_scene

    result = simulate_scene(reference, "release", 600)
    fig = plot_scene(result)
    position_ax, velocity_ax = fig.axes[1], fig.axes[0]
    assert "problem frame" in position_ax.get_ylabel() and "problem frame" in velocity_ax.get_ylabel()
    driven = next(line for line in position_ax.get_lines() if line.get_label() == result.driven)
    angle, y = driven.get_xdata(), driven.get_ydata()
    # the problem's stroke: 32 mm at the upper dwell, 0 at the handover (move 1 goes down, velocity negative)
    stroke = reference.stroke(600).evaluate(result.t)
    assert y == pytest.approx(stroke.s * 1e3, abs=1e-9)
    assert y[0] == pytest.approx(32.0) and y[np.argmin(np.abs(angle - 60.0))] == pytest.approx(0.0, abs=1e-6)
    v = next(line for line in velocity_ax.get_lines() if line.get_label().startswith(result.driven)).get_ydata()
    assert v.min() < -2.0 and v[np.argmin(np.abs(angle - 40.0))] < 0  # move 1: down, negative


# --------------------------------------------------------------------------- tables


def test_kinematics_text_names_cam_cycle_stitch_period_and_move_times(capsys, reference_path):
    assert main(["kinematics", str(reference_path), "--spm", "600", "--plot", "none"]) == 0
    out = capsys.readouterr().out
    assert "cam cycle 200.0 ms = 2 stitches of 100.0 ms" in out
    assert "interval time ms" in out and "time s" not in out
    move1 = next(line for line in out.splitlines() if "move 1" in line).split()
    assert "21.000" in move1  # move 1 takes 21 ms at 600 spm (published times), in ms


def test_solve_sweep_table_names_the_solve_time(capsys, reference_path, monkeypatch):
    import strokeopt.studies.sweeps as studies

    rows = [{"spm": spm, "feasible": True, "objective_value": v, "motor": "055U2B30", "pulley_teeth": 24,
             "peak_torque_N_m": v, "rms_torque_N_m": v / 2, "solve_time_s": 0.5, "reason": None,
             "objective_unit": "N m", "handover_error_mm": 0.04}
            for spm, v in ((700.0, 1.25), (1000.0, 2.5))]
    rows[1].update(feasible=False, reason="no motor of the catalogue can drive this design at 1000 spm; a long "
                                          "sentence that stays in its own column")
    monkeypatch.setattr(studies, "sweep_design", lambda *a, **k: rows)
    assert main(["solve", str(reference_path), "--spm", "700:1000:300", "--plot", "none"]) == 0
    out = capsys.readouterr().out
    assert "solve + verify s" in out and "objective N m" in out and "handover mm" in out
    # the reason, aligned left as the last column: the feasible row's '-' right after its time, no padding
    head = next(line for line in out.splitlines() if "why not" in line)
    assert head.endswith("why not") and next(line for line in out.splitlines() if line.strip().startswith("700")
                                             ).endswith("0.5000  -")
    spm_cells = [line.split()[0] for line in out.splitlines() if line.strip().startswith(("700", "1000"))]
    assert spm_cells == ["700", "1000"]  # one format per column: not 700.0 beside 1000


@pytest.mark.parametrize("values, cells", [
    ([700.0, 1000.0], ["700", "1000"]),
    ([1.5, 10.25], ["1.500", "10.250"]),
    ([2.606, 0.6413, 0.0], ["2.6060", "0.6413", "0.0000"]),
    ([307050.5, 176910.5, 0.0], ["3.071e+05", "1.769e+05", "0.000e+00"]),
    ([0.0313, 1990.0], ["0.03130", "1990"]),  # four decades: different quantities, each its own format
    ([1.5, None, True], ["1.500", "-", "yes"]),
])
def test_one_number_format_per_column(values, cells):
    text = format_table([{"x": v} for v in values], [("x", "x")])
    assert [line.strip() for line in text.splitlines()[2:]] == cells


def test_premature_verdict_and_printed_gap_agree(reference):
    from strokeopt.contact.events import GAP_CLOSED
    from strokeopt.contact.simulate import simulate_scene

    late = simulate_scene(reference, "release", 1180).metrics
    assert late["premature_release"] is True
    assert late["min_gap_N_mm"] < GAP_CLOSED * 1e3  # it printed +0.0014 mm beside "premature: yes"
    early = simulate_scene(reference, "release", 600).metrics
    assert early["premature_release"] is False and early["min_gap_N_mm"] > GAP_CLOSED * 1e3


def test_the_sweep_figure_names_its_objective_with_its_unit():
    """The design sweep's axis names the objective and its unit (it said "objective"), and the peak torque beside
    it where that is another quantity."""
    import matplotlib.pyplot as plt

    from strokeopt.report.design import plot_design_sweep

    rows = [{"spm": s, "feasible": True, "objective_value": v, "objective_unit": "m/s^2", "peak_torque_N_m": t,
             "motor": "055U2B30"} for s, v, t in ((400, 210.0, 0.6), (500, 330.0, 0.9))]
    fig = plot_design_sweep(rows, objective="min_peak_accel")
    ax = fig.axes[0]
    assert ax.get_ylabel() == "min_peak_accel [m/s^2]; peak torque [N m]"
    assert [t.get_text() for t in ax.get_legend().get_texts()] == ["optimal min_peak_accel [m/s^2]", "peak torque [N m]"]
    plt.close(fig)
    torque = [{**r, "objective_unit": "N m", "objective_value": r["peak_torque_N_m"]} for r in rows]
    fig = plot_design_sweep(torque, objective="min_peak_torque")
    assert fig.axes[0].get_ylabel() == "min_peak_torque [N m]"
    plt.close(fig)
