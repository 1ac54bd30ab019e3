"""The sizing report: text and figure drawn from a Sizing (the drive package itself draws nothing)."""

from __future__ import annotations

import matplotlib.pyplot as plt

from strokeopt.drive.sizing import Sizing, optimal_radius, size_drive
from strokeopt.report.drive import plot_sizing, sizing_text


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
