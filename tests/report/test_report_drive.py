"""The sizing report: text and figure drawn from a Sizing (the drive package itself draws nothing)."""

from __future__ import annotations

from pathlib import Path

import matplotlib.pyplot as plt
import pytest

from strokeopt.drive.sizing import Sizing, optimal_radius, size_drive
from strokeopt.report.drive import plot_sizing, sizing_text

ROOT = Path(__file__).resolve().parents[2]


def test_sizing_text_and_figure(reference):
    sizing = size_drive(reference, 500, motors=["055U2B30"], teeth=[28, 36], samples=721, find_max_spm=True,
                        resolution=10.0)
    assert not hasattr(Sizing, "plot")
    report = sizing.to_dict(explain=True)
    report["continuous_radius"] = [optimal_radius(sizing.candidates[0].motor, reference.drive.load,
                                                  sizing.kinematics).row()]
    text = sizing_text(sizing, report, explain=True)
    lines = text.splitlines()
    assert lines[0].startswith(f"{reference.name} at 500 spm")
    assert "ranked: feasible first" in text and "max spm: bisection per pair to 10 spm" in text
    assert "motor torque at the instant of the peak" in text and "checks of 055U2B30 with z" in text
    assert "continuous pulley radius" in text
    plain = sizing_text(sizing, sizing.to_dict())
    assert "instant of the peak" not in plain and "continuous pulley radius" not in plain
    fig = plot_sizing(sizing, sizing.candidates[-1])
    assert f"z{sizing.candidates[-1].pulley.teeth}" in fig.axes[0].get_title()
    plt.close(fig)


def _stated_peak(fig) -> float:
    """The peak torque the figure's torque-speed legend states ('peak -1.963 N m at -325 rpm')."""
    import re

    labels = [line.get_label() for ax in fig.axes for line in ax.get_lines()]
    (label,) = [lab for lab in labels if re.match(r"(\w+: )?peak -?\d", lab)]
    return abs(float(re.search(r"peak (-?[\d.]+) N m", label).group(1)))


def test_torque_speed_figures_state_the_peak_the_checks_report():
    """The figure's peak is read where the checks read theirs (the spring's switch, both sides): the report said
    'peak -1.963 N m' beside the checks' 2.015 N m of the same design (min_rms_torque)."""
    import strokeopt as so
    from strokeopt.report.design import plot_design
    from strokeopt.report.design_report import plot_drive

    for spm in (500, 600):
        design = so.solve_design(so.load_problem(ROOT / "problems" / "deco2000_needle_bar.toml")
                                 .with_spm(spm), objective="min_rms_torque")
        (peak,) = [c["value"] for c in design.checks if c["name"] == "peak_torque"]
        for fig in (plot_drive(design), plot_design(design)):
            assert _stated_peak(fig) == pytest.approx(peak, rel=1e-3), spm
            plt.close(fig)
