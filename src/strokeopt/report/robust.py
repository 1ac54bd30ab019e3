"""The tolerance study as text and figures (:func:`strokeopt.studies.robust.robust_study` makes the data)."""

from __future__ import annotations

from ..io.cycle import cycle_of
from .format import format_table

#: The result columns of the tables: (key, heading).
COLUMNS = (("handover_error_mm", "handover mm"), ("handover_error_deg", "handover deg"), ("max_lag_mm", "lag mm"),
           ("impact_velocity_m_s", "impact m/s"), ("peak_torque_N_m", "peak N m"))


def columns(report: dict) -> list[tuple[str, str]]:
    """The result columns of a study: :data:`COLUMNS`, then the results of a machine's own analysis (a linkage's
    swing, dwells, transmission index, crank torque), headed by their keys in words."""
    known = dict(COLUMNS)
    own = [(k, k.replace("_N_m", " N m").replace("_", " ")) for k in report.get("responses", ()) if k not in known]
    return list(COLUMNS) + own


def robust_text(report: dict) -> str:
    """Yield with its interval, failures by criterion, the worst samples and the rank correlations."""
    lo, hi = report["yield_interval"]
    lines = [f"{report['problem']} at {cycle_of(report).rate(report['spm'])}: {report.get('judged', 'the design')} on "
             f"{report['samples']} sampled machines ({report['method']}, seed {report['seed']})"]
    lines += [f"  {t['field']}: {t['lower']:.6g} to {t['upper']:.6g} ({t['distribution']}; nominal {t['nominal']:.6g})"
              for t in report["tolerances"]]
    if report.get("runner"):   # where it ran, and any worker lost on the way (its samples re-run on the others)
        lines.append(f"ran on: {report['runner']}")
    counted = f": {', '.join(report['criteria'])}" if report.get("criteria") else ""
    lines.append(f"yield: {100 * report['yield']:.1f} % meet every limit the problem sets{counted} (95 % interval "
                 f"{100 * lo:.1f} to {100 * hi:.1f} %)")
    for c in report.get("not_judged", ()):   # what the yield does not count: no limit judges it
        values = (f" {c['low']:.4g} to {c['high']:.4g} {c['unit']}" if c["low"] is not None else "")
        lines.append(f"not judged: {c['criterion']}{values} in {c['samples']} samples (no limit: set {c['limit_field']})")
    if report["failed_by"]:
        lines.append("failed: " + ", ".join(f"{name} in {n} samples" for name, n in
                                            sorted(report["failed_by"].items(), key=lambda kv: -kv[1])))
    fields = [t["field"] for t in report["tolerances"]]
    worst = [{**{f"p{i}": r.get(f) for i, f in enumerate(fields)}, **r,
              "failed_text": ", ".join(r.get("failed", [])) or "-"} for r in report["worst"]]
    cols = [("sample", "sample")] + [(f"p{i}", f) for i, f in enumerate(fields)] + \
        [c for c in columns(report) if any(c[0] in r for r in worst)] + [("failed_text", "fails")]
    lines += ["", format_table(worst, cols, title="the worst samples (the most limits failed first, then "
                                                  f"{report.get('worst_by', 'the largest handover error')})")]
    sens = [{k: f"{v:+.3f}" if isinstance(v, float) else v for k, v in s.items()}  # one format: correlations
            for s in report["sensitivity"]]
    cols = [("field", "tolerance")] + [c for c in columns(report) if any(c[0] in s for s in sens)]
    lines += ["", format_table(sens, cols, title="which tolerances matter: Spearman rank correlation with each "
                                                 "result (+1: rises with the part's value, 0: no effect; -: the "
                                                 "result does not vary over the samples beyond the simulation's "
                                                 "resolution)")]
    return "\n".join(lines)


#: The quantities a histogram may show, in order of preference: (row key, axis label, unit).
HISTOGRAMS = (("handover_error_mm", "handover error [mm]", "mm"),
              ("handover_error_deg", "handover error [deg]", "deg"), ("impact_velocity_m_s", "impact velocity [m/s]", "m/s"), ("peak_torque_N_m", "peak torque [N m]", "N m"))


def plot_robust(report: dict, path, limits: dict | None = None):
    """Histograms of the handover error and the impact velocity (limits drawn where the problem sets them) and
    the rank correlations as bars."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    import numpy as np
    from matplotlib.ticker import MaxNLocator

    limits = limits or {}
    rows = report["rows"]
    fig, axes = plt.subplots(1, 3, figsize=(13, 4.2), layout="constrained")
    # the two histograms of what the samples have: the handover error and impact velocity a problem judges, else
    # its peak torque (a problem without a handover or a contact model: no empty panels)
    own = [(k, label, "") for k, label in columns(report)[len(COLUMNS):]]   # a machine's own results
    def varies(key):   # a result the same in every sample (a dwell counted in whole steps) gets no panel
        values = [r[key] for r in rows if isinstance(r.get(key), (int, float))]
        return len(values) > 0 and (key in dict(COLUMNS) or max(values) > min(values))

    shown = [q for q in HISTOGRAMS + tuple(own) if varies(q[0])][:2]
    for ax in axes[len(shown):2]:
        ax.set_axis_off()
    for ax, (key, label, unit) in zip(axes[:2], shown):
        values = np.array([r[key] for r in rows if isinstance(r.get(key), (int, float))], float)
        if values.size:
            ax.hist(values, bins=min(40, max(8, values.size // 10)), color="#4c72b0")
        limit = limits.get(key)
        if limit is not None and values.size and limit <= 2 * values.max():
            ax.axvline(limit, color="#c44e52", label=f"limit {limit:g} {unit}")
            ax.legend(loc="upper right")
        elif limit is not None:  # far beyond the samples: named, not drawn (the samples would shrink to a line)
            ax.set_title(f"limit {limit:g} {unit}, {limit / values.max():.1f} x the largest sample" if values.size
                         else f"limit {limit:g} {unit}", fontsize=9)
        ax.set_xlabel(label)
        ax.set_ylabel("samples")
        ax.yaxis.set_major_locator(MaxNLocator(integer=True))  # a count: whole numbers
    sens = report["sensitivity"]
    heads = dict(columns(report))
    keys = [k for k in heads if any(k in s for s in sens)]
    width = 0.8 / max(1, len(keys))
    y = np.arange(len(sens))
    for j, key in enumerate(keys):
        axes[2].barh(y + j * width, [s.get(key) or 0.0 for s in sens], height=width, label=heads[key])
    axes[2].set_yticks(y + width * (len(keys) - 1) / 2, [s["field"].split(".")[-2] + "." + s["field"].split(".")[-1]
                                                         if s["field"].count(".") else s["field"] for s in sens])
    axes[2].set_xlim(-1, 1)
    axes[2].set_xticks([-1, -0.5, 0, 0.5, 1])  # not crowded at any figure width
    axes[2].set_xlabel("Spearman rank correlation [-]")
    axes[2].legend(loc="upper center", bbox_to_anchor=(0.5, -0.18), ncol=min(3, len(keys)), fontsize=8)
    unjudged = [c["criterion"] for c in report.get("not_judged", ())]
    fig.suptitle(f"{report['problem']}, {cycle_of(report).rate(report['spm'])}: yield {100 * report['yield']:.1f} % of "
                 f"{report['samples']} samples" + (f" ({', '.join(unjudged)} not judged)" if unjudged else ""))
    fig.savefig(path, dpi=120)
    plt.close(fig)
