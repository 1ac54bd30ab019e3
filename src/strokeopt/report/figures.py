"""What every figure shares: the coordinates its axes are in, and dwell bands on a cam-angle axis.

Every figure and table gives positions and velocities in the problem's coordinates: the problem
file's positions (``timing.start_position_mm`` and the moves' strokes; + is a move with
``direction = "up"``; 0 is the handover point of the reference problem). The contact model computes
in its own coordinates (from the start of the handover move, + toward the handover); its results
are turned into the problem's before they are drawn (:meth:`~strokeopt.contact.simulate.SceneResult.problem_position`).
"""

from __future__ import annotations

#: the axis-label suffix naming the problem's coordinates
PROBLEM_FRAME = "problem frame, + up"


def frame_label(quantity: str, unit: str, rotary: bool = False) -> str:
    """An axis label of a position or velocity in the problem's coordinates: 'position [mm]\\n(problem frame, + up)';
    a rotary load's (a sley's, ``rotary``): '+ positive angle'."""
    return f"{quantity} [{unit}]\n({'problem frame, + positive angle' if rotary else PROBLEM_FRAME})"


def shade_dwells(ax, timing, spm) -> None:
    """Grey bands over the dwells of a timing diagram (x axis: cam angle in degrees)."""
    sch = timing.schedule(spm)
    for itv, a0, a1 in zip(timing.intervals, sch.start_angle_deg, sch.end_angle_deg):
        if not itv.is_move:
            ax.axvspan(a0, a1, color="0.9", zorder=0, lw=0)


# --------------------------------------------------------------------------- figures that survive print

#: The width a report figure is drawn at [in]: an A4 page less the report's 12 mm margins (186 mm), so that
#: a figure prints at its own size and its smallest text (:data:`MIN_TEXT_PT`) at that size.
PRINT_WIDTH_IN = 186 / 25.4
#: The smallest text of a report figure [pt], printed on A4.
MIN_TEXT_PT = 7.5


def legend_outside(ax, where: str = "right", ncol: int = 1, **kwargs):
    """The legend of ``ax`` beside its data, never on it: right of the axes, or below them (``where``);
    constrained layout makes room for it."""
    kwargs.setdefault("fontsize", MIN_TEXT_PT + 0.5)
    if where == "below":  # as many columns as the figure's width holds (DejaVu Sans: about 0.6 em a character)
        labels = ax.get_legend_handles_labels()[1]
        column_pt = 0.6 * kwargs["fontsize"] * max((len(x) for x in labels), default=1) + 30
        room_pt = max(ax.get_position().width * 1.15, 0.3) * ax.figure.get_figwidth() * 72  # about the axes' width
        ncol = max(1, min(ncol, int(room_pt // column_pt)))
        # under the x label: its height in axes fractions from the axes' height in inches
        height = ax.get_position().height * ax.figure.get_figheight()
        return ax.legend(loc="upper center", bbox_to_anchor=(0.5, -0.55 / max(height, 0.5)), ncol=ncol,
                         frameon=False, **kwargs)
    return ax.legend(loc="upper left", bbox_to_anchor=(1.01, 1.0), ncol=ncol, frameon=False, borderaxespad=0.0,
                     **kwargs)


def _wrap(text: str, width_pt: float, fontsize: float) -> str:
    """``text`` wrapped to lines of at most ``width_pt`` (DejaVu Sans: about 0.6 em a character)."""
    import textwrap

    chars = max(int(width_pt / (0.6 * fontsize)), 12)
    return "\n".join(textwrap.fill(line, chars) for line in text.split("\n"))


def fit_titles(fig) -> None:
    """Wrap every axes title and the figure's suptitle that would be wider than its axes (the figure), so
    that nothing is clipped at the figure's edge; after the layout, check once more and shorten the wrap."""
    fig.canvas.draw()
    renderer = fig.canvas.get_renderer()
    for _ in range(3):
        changed = False
        for ax in fig.axes:
            for title in (ax.title, ax._left_title, ax._right_title):
                text = title.get_text()
                if not text:
                    continue
                box = title.get_window_extent(renderer)
                room = min(ax.get_window_extent(renderer).width * 1.15, fig.bbox.width * 0.98)
                if box.width > room or box.x0 < fig.bbox.x0 or box.x1 > fig.bbox.x1:
                    width_pt = room * 72.0 / fig.dpi * min(1.0, room / max(box.width, 1.0)) ** 0.2
                    title.set_text(_wrap(text.replace("\n", " "), width_pt, title.get_fontsize()))
                    changed = True
        sup = fig._suptitle
        if sup is not None and sup.get_text():
            box = sup.get_window_extent(renderer)
            if box.x0 < fig.bbox.x0 or box.x1 > fig.bbox.x1:
                sup.set_text(_wrap(sup.get_text().replace("\n", " "), fig.bbox.width * 0.95 * 72 / fig.dpi,
                                   sup.get_fontsize()))
                changed = True
        if not changed:
            return
        fig.canvas.draw()
        renderer = fig.canvas.get_renderer()


def _all_axes(fig) -> list:
    """The figure's axes with their child axes (secondary axes)."""
    out = []
    for ax in fig.axes:
        out += [ax] + [c for c in getattr(ax, "child_axes", []) if c not in fig.axes]
    return out


def drawn_texts(fig) -> list:
    """Every text of ``fig`` that its last draw put on the page: titles, axis labels, the tick labels in view,
    annotations, legends' texts, the figure's own texts (call after ``fig.canvas.draw()``)."""
    out = [t for t in fig.texts] + ([fig._suptitle] if fig._suptitle is not None else [])
    for leg in fig.legends:
        out += list(leg.get_texts())
    for ax in _all_axes(fig):
        out += [ax.title, ax._left_title, ax._right_title, ax.xaxis.label, ax.yaxis.label,
                ax.xaxis.offsetText, ax.yaxis.offsetText] + list(ax.texts)
        for axis in (ax.xaxis, ax.yaxis):
            for tick in axis._update_ticks():
                out += [t for t, on in ((tick.label1, tick.label1.get_visible()), (tick.label2, tick.label2.get_visible()))
                        if on]
        leg = ax.get_legend()
        if leg is not None:
            out += list(leg.get_texts()) + [leg.get_title()]
    return [t for t in out if t.get_visible() and t.get_text().strip()]


def texts_outside(fig) -> list[str]:
    """The texts of ``fig`` whose box leaves the figure (after its layout): what print would clip."""
    fig.canvas.draw()
    renderer = fig.canvas.get_renderer()
    box = fig.bbox
    out = []
    for t in drawn_texts(fig):
        e = t.get_window_extent(renderer)
        if e.x0 < box.x0 - 0.5 or e.y0 < box.y0 - 0.5 or e.x1 > box.x1 + 0.5 or e.y1 > box.y1 + 0.5:
            out.append(t.get_text())
    return out
