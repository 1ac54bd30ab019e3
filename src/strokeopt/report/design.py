"""Design results: mesh-study and stitch-rate sweep figures (and text tables)."""

from __future__ import annotations

import matplotlib.pyplot as plt


def plot_mesh_study(rows: list[dict], path=None):
    """Work-precision of the design collocation: objective error and violation between nodes vs solve time."""
    fig, axes = plt.subplots(1, 2, figsize=(10, 4), constrained_layout=True)
    for degree in sorted({r["degree"] for r in rows}):
        sel = [r for r in rows if r["degree"] == degree and not r.get("reference")]
        if not sel:
            continue
        t = [r["time_s"] for r in sel]
        axes[0].loglog(t, [max(r["objective_error_pct"], 1e-9) for r in sel], "o-", label=f"degree {degree}")
        axes[1].semilogx(t, [100 * r["violation_between_nodes"] for r in sel], "o-", label=f"degree {degree}")
        for r in sel:
            axes[0].annotate(str(r["intervals"]), (r["time_s"], max(r["objective_error_pct"], 1e-9)), fontsize=7,
                             xytext=(3, 3), textcoords="offset points")
    axes[0].set_ylabel("objective error vs finest mesh [%]")
    axes[1].set_ylabel("largest bound violation between nodes [%]")
    for ax in axes:
        ax.set_xlabel("build + solve time [s]")
        ax.grid(True, which="both", alpha=0.3)
        ax.legend(fontsize=8)
    axes[0].set_title("what accuracy costs in time (labels: mesh intervals)")
    if path is not None:
        fig.savefig(path, dpi=120)
        plt.close(fig)
    return fig


def plot_design_sweep(rows: list[dict], path=None):
    """Optimal objective (and peak torque) over the stitch rate of a design sweep; infeasible rates marked."""
    fig, ax = plt.subplots(figsize=(8, 4), constrained_layout=True)
    ok = [r for r in rows if r["feasible"]]
    bad = [r for r in rows if not r["feasible"]]
    if ok:
        ax.plot([r["spm"] for r in ok], [r["objective_value"] for r in ok], "o-", label="optimal objective")
        if ok[0].get("peak_torque_N_m") is not None:
            ax.plot([r["spm"] for r in ok], [r["peak_torque_N_m"] for r in ok], "s--", label="peak torque [N m]")
    for r in bad:
        ax.axvline(r["spm"], color="tab:red", alpha=0.4, lw=1)
    ax.set_xlabel("stitches per minute")
    ax.set_ylabel("objective")
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize=8)
    ax.set_title("optimal design over the stitch rate (red: infeasible)")
    if path is not None:
        fig.savefig(path, dpi=120)
        plt.close(fig)
    return fig
