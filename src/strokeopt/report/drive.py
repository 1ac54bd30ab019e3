"""Drive sizing: its figure (and text tables)."""

from __future__ import annotations

import math

import matplotlib.pyplot as plt
import numpy as np


def plot_sizing(sizing, candidate=None, path=None):
    """The classic sizing picture for ``candidate`` (default: the best ranked):
    the cycle's torque-speed trajectory over the motor's continuous and peak
    envelopes and the drive's peak limit, and the torque terms over the cam angle.
    ``sizing`` is a :class:`strokeopt.drive.Sizing`."""
    c = candidate or sizing.candidates[0]
    terms = sizing.torque_curve(c)
    rpm = 60 / (2 * math.pi)
    fig, (ax1, ax2) = plt.subplots(1, 2, figsize=(12, 4.8), constrained_layout=True)
    m = c.motor
    w = np.linspace(-m.rated_speed, m.rated_speed, 101)
    drive_peak = min(m.peak_torque, sizing.limits.peak_limit_pct / 100 * m.rated_torque)
    for sign in (1, -1):
        ax1.plot(w * rpm, sign * m.continuous_torque(w), color="tab:green",
                 label="continuous (thermal)" if sign > 0 else None)
        ax1.plot(w * rpm, sign * m.peak_envelope(w), color="tab:red", label="motor peak" if sign > 0 else None)
        ax1.plot(w * rpm, sign * np.full_like(w, drive_peak), color="tab:red", ls=":",
                 label=f"drive limit ({sizing.limits.peak_limit_pct:g} % rated)" if sign > 0 else None)
    for x in (-m.rated_speed * rpm, m.rated_speed * rpm):
        ax1.axvline(x, color="0.5", lw=0.8, ls="--")
    ax1.plot(terms.omega * rpm, terms.total, color="tab:blue", lw=1.2, label="cycle")
    rms = c.check("rms_torque").value
    ax1.axhline(rms, color="tab:blue", ls="--", lw=0.8, label=f"RMS {rms:.2f} N m")
    ax1.set_xlabel("motor speed [rpm]")
    ax1.set_ylabel("motor torque [N m]")
    ax1.set_title(f"{m.name}, pulley z{c.pulley.teeth}, {sizing.spm:g} spm")
    ax1.grid(True, alpha=0.3)
    ax1.legend(fontsize=8, loc="best")
    angle = 360.0 * sizing.kinematics.t / sizing.period
    ax2.plot(angle, terms.total, color="k", lw=1.5, label="total")
    for name, val in terms.as_dict().items():
        val = np.broadcast_to(val, angle.shape)
        if np.max(np.abs(val)) > 1e-9:
            ax2.plot(angle, val, lw=0.9, label=name, ls="--" if name == "rotor_inertia" else "-")
    ax2.set_xlabel("cam angle [deg]")
    ax2.set_ylabel("motor torque [N m]")
    ax2.set_xlim(0, 360)
    ax2.set_xticks(np.arange(0, 361, 45))
    ax2.grid(True, alpha=0.3)
    ax2.legend(fontsize=8, loc="best")
    ax2.set_title(f"torque over the cycle (binding: {c.binding})")
    if path is not None:
        fig.savefig(path, dpi=110)
        plt.close(fig)
    return fig
