"""The report's figures: matplotlib, drawn off-screen and inlined as base64 PNG.

Each function takes plain numbers and returns the PNG bytes base64-encoded, for an
``<img src="data:image/png;base64,…">`` that works offline. A :class:`matplotlib.figure.Figure`
is made directly (no ``pyplot``: no global state, safe in the grader's threads), and PNG metadata
is left out so that the same class gives the same bytes.

Colours name what they show, the same in every figure and in the tables (:data:`COLOURS`).

Each figure's layout is fixed (:func:`margins`): room for its texts, measured with the font
they are drawn in (:func:`text_width`), not found by matplotlib's constrained layout, which
measured every text of the figure once more before drawing it — a third of the report's
drawing time, paid at the end of every ``eulertop grade`` (issue 34).

Floor 5 of grader/ (views of records, and file formats; grader/API.md).
"""

from __future__ import annotations

import base64
import io
from collections.abc import Mapping, Sequence

import numpy as np
from matplotlib.figure import Figure

COLOURS = {
    "correct": "#2ca02c",
    "follows": "#98df8a",
    "known mistake": "#ff7f0e",
    "wrong": "#d62728",
    "invalid": "#9467bd",
    "unanswered": "#c7c7c7",
    "pending": "#e0c060",
    "reviewed": "#17becf",
    "scores": "#1f77b4",
}


FONT = 10.0
"""Points: matplotlib's text size, of the tick labels and the axes' labels."""

TICKS = (3.5 + 3.5) / 72
"""Inches: a tick and the pad between it and its label (matplotlib's defaults)."""

LINE = 1.25 * FONT / 72
"""Inches: one line of text at :data:`FONT`."""

EDGE = 0.1
"""Inches of white between the outermost text and the figure's edge."""

X_AXIS = TICKS + LINE + 4 / 72 + LINE + EDGE
"""Inches below the axes: ticks, their labels, the label pad and the x label."""


def text_width(texts: Sequence[str], size: float = FONT) -> float:
    """Inches of the widest of ``texts`` at ``size`` points, in the font they are drawn in."""
    from matplotlib.font_manager import FontProperties
    from matplotlib.textpath import text_to_path

    prop = FontProperties(size=size)
    return max((text_to_path.get_text_width_height_descent(t, prop, ismath=False)[0] / 72
                for t in texts if t), default=0.0)


def y_axis(ticks: Sequence[str], label: bool = True) -> float:
    """Inches left of the axes: the y label (if any), its pad, the widest tick label, ticks."""
    return EDGE + (LINE + 4 / 72 if label else 0.0) + text_width(ticks) + TICKS


def margins(fig: Figure, left: float, bottom: float = X_AXIS, top: float = EDGE,
            right: float = 0.25) -> Figure:
    """``fig`` with its axes ``left``, ``bottom``, ``top`` and ``right`` inches from its
    edges. (``right``: room for half of the last x tick's label.)"""
    width, height = fig.get_size_inches()
    fig.subplots_adjust(left=left / width, right=1 - right / width, bottom=bottom / height,
                        top=1 - top / height)
    return fig


def count_ticks(peak: float) -> list[str]:
    """What the labels of a count axis up to ``peak`` may be, at their widest (integers, or
    steps of a fraction below 2)."""
    return [f"{peak:.0f}", "0.00"]


def png_base64(fig: Figure) -> str:
    """The figure as base64 PNG (no metadata: reproducible bytes)."""
    buffer = io.BytesIO()
    fig.savefig(buffer, format="png", dpi=100, metadata={"Software": None})
    return base64.b64encode(buffer.getvalue()).decode("ascii")


def score_histogram(percent: Sequence[float]) -> str:
    """Histogram of the graded students' scores, in percent of the maximum."""
    fig = Figure(figsize=(7, 2.8))
    ax = fig.add_subplot()
    heights, _, _ = ax.hist(percent, bins=np.linspace(0, 100, 21), color=COLOURS["scores"],
                            edgecolor="white")
    margins(fig, y_axis(count_ticks(max(heights, default=0) * 1.05)))
    if len(percent):
        ax.axvline(float(np.median(percent)), color="black", linestyle="--", linewidth=1,
                   label=f"median {np.median(percent):.0f} %")
        ax.legend(frameon=False)
    ax.set_xlabel("score (% of the maximum)")
    ax.set_ylabel("students")
    ax.set_xlim(0, 100)
    return png_base64(fig)


def outcomes(labels: Sequence[str], counts: Sequence[Mapping[str, int]]) -> str:
    """Stacked horizontal bars: per answer, how many students were correct, followed through
    from their own earlier answers, made a known mistake, were otherwise wrong, invalid or
    left it unanswered."""
    fig = Figure(figsize=(7, 0.8 + 0.28 * len(labels)))
    ax = fig.add_subplot()
    y = np.arange(len(labels))[::-1]
    left = np.zeros(len(labels))
    for name in ("correct", "follows", "known mistake", "wrong", "invalid", "unanswered",
                 "pending", "reviewed"):
        width = np.array([c.get(name, 0) for c in counts], dtype=float)
        if name in ("follows", "pending", "reviewed") and not width.any():
            continue  # in the legend only where some answer has it
        ax.barh(y, width, left=left, color=COLOURS[name], label=name, height=0.75)
        left += width
    ax.set_yticks(y, labels)
    ax.set_xlabel("students")
    height = fig.get_size_inches()[1]  # the legend above, centred on the figure (it may be
    legend = ax.legend(ncols=5, loc="upper center", frameon=False, fontsize="small",  # wider
                       bbox_to_anchor=(0.5, 1 - EDGE / 2 / height),  # than the axes)
                       bbox_transform=fig.transFigure)
    rows = -(-len(legend.get_texts()) // 5)
    margins(fig, y_axis(labels, label=False), top=EDGE + 0.05 + 0.22 * rows)
    return png_base64(fig)


def written_scores(points: Sequence[float], maximum: float) -> str:
    """Histogram of one written answer's reviewed scores, from 0 to ``maximum`` points."""
    fig = Figure(figsize=(7, 2.4))
    ax = fig.add_subplot()
    top = maximum if maximum > 0 else 1.0
    heights, _, _ = ax.hist(points, bins=np.linspace(0, top, min(20, max(4, int(4 * top))) + 1),
                            color=COLOURS["reviewed"], edgecolor="white")
    margins(fig, y_axis(count_ticks(max(heights, default=0) * 1.05)),
            right=0.1 + text_width([f"{top:g}", f"{top:.1f}"]) / 2)
    ax.set_xlabel("points given by the reviews")
    ax.set_ylabel("students")
    ax.set_xlim(0, top)
    return png_base64(fig)


def facility_discrimination(labels: Sequence[str], facility: Sequence[float],
                            discrimination: Sequence[float | None]) -> str:
    """Each answer placed by facility (x) and discrimination (y); the flagged regions shaded."""
    fig = Figure(figsize=(7, 3.6))
    ax = fig.add_subplot()
    shown = [label for label, f in zip(labels, facility, strict=True) if f is not None]
    margins(fig, y_axis(["−0.75"]), top=EDGE + 0.2,
            right=max(0.25, EDGE + 4 / 72 + text_width(shown, 7)))
    ax.axvspan(0, 0.4, color="#fbe3e3", zorder=0)
    ax.axhspan(-1, 0.1, color="#f0f0f0", zorder=0)
    for label, f, d in zip(labels, facility, discrimination, strict=True):
        if f is None:
            continue
        y = 0.0 if d is None else d
        ax.scatter([f], [y], color=COLOURS["scores"] if d is not None else "#999999", zorder=2)
        ax.annotate(label, (f, y), textcoords="offset points", xytext=(4, 3), fontsize=7)
    ax.set_xlim(-0.02, 1.02)
    ax.set_ylim(-1, 1)
    ax.set_xlabel("facility (mean fraction of the points)")
    ax.set_ylabel("discrimination (r with the rest)")
    return png_base64(fig)


def wrong_ratios(rows: Sequence[tuple[str, Sequence[float]]]) -> str:
    """Where the unrecognised wrong answers lie relative to each student's own key:
    log₁₀|wrong/key| per answer; a shared slip shows as a column of points."""
    fig = Figure(figsize=(7, 0.9 + 0.3 * max(len(rows), 1)))
    ax = fig.add_subplot()
    margins(fig, y_axis([r[0] for r in rows], label=False), top=EDGE + 0.15)
    for value, name in ((np.log10(2), "×2"), (-np.log10(2), "×½"),
                        (np.log10(180 / np.pi), "deg"), (np.log10(2 * np.pi), "2π"),
                        (-np.log10(2 * np.pi), "1/2π")):
        ax.axvline(value, color="#bbbbbb", linewidth=0.8, zorder=0)
        ax.annotate(name, (value, 1.0), xycoords=("data", "axes fraction"), fontsize=7,
                    ha="center", va="bottom", color="#777777")
    rng = np.random.default_rng(0)  # vertical jitter only, the same every time
    for k, (_, ratios) in enumerate(rows):
        y = len(rows) - 1 - k + rng.uniform(-0.25, 0.25, len(ratios))
        ax.scatter(np.log10(np.abs(ratios)), y, s=8, color=COLOURS["wrong"], alpha=0.6)
    ax.set_yticks(np.arange(len(rows))[::-1], [r[0] for r in rows])
    ax.set_xlim(-3, 3)
    ax.set_xlabel("log₁₀ |wrong value / the student's own key|")
    return png_base64(fig)
