"""The report's figures: matplotlib, drawn off-screen and inlined as base64 SVG.

Each function takes plain numbers and returns the SVG base64-encoded, for an
``<img src="data:image/svg+xml;base64,…">`` that works offline. A
:class:`matplotlib.figure.Figure` is made directly (no ``pyplot``: no global state, safe in the
grader's threads); the SVG has no date and fixed ids, so that the same class gives the same
bytes. Its texts stay text (in DejaVu Sans, the font their room was measured in, or the next
sans-serif the browser has), and bars are one collection per colour rather than a patch each:
together about a third less drawing than a PNG of patches, at the end of every
``eulertop grade`` (issue 34).

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
import threading
from collections.abc import Mapping, Sequence

import numpy as np
from matplotlib import rc_context
from matplotlib.axes import Axes
from matplotlib.collections import PolyCollection
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


SVG = {"svg.fonttype": "none", "svg.hashsalt": "eulertop"}
"""How the figures are written: texts as text, ids from a fixed salt (reproducible bytes)."""

_SAVING = threading.Lock()  # rc_context changes matplotlib's global settings while it lasts


def svg_base64(fig: Figure) -> str:
    """The figure as base64 SVG (no date, fixed ids: reproducible bytes)."""
    buffer = io.BytesIO()
    with _SAVING, rc_context(SVG):
        fig.savefig(buffer, format="svg", metadata={"Date": None, "Creator": None})
    return base64.b64encode(buffer.getvalue()).decode("ascii")


def bars(ax: Axes, x: Sequence[float] | np.ndarray, width: Sequence[float] | np.ndarray,
         y: Sequence[float] | np.ndarray, height: Sequence[float] | np.ndarray,
         based: str = "y", **style) -> PolyCollection:
    """The rectangles ``[x, x + width] × [y, y + height]`` (arrays, broadcast) as one collection
    on ``ax``; the ``based`` axis's limits stuck at the bars' bases (``y``, or ``x`` with
    ``based="x"``), as ``bar`` and ``barh`` leave them."""
    x, width, y, height = np.broadcast_arrays(*(np.asarray(v, float)
                                                for v in (x, width, y, height)))
    corners = np.stack([np.stack([x, y], -1), np.stack([x, y + height], -1),
                        np.stack([x + width, y + height], -1), np.stack([x + width, y], -1)],
                       axis=-2)
    collection = PolyCollection(corners, **style)
    getattr(collection.sticky_edges, based).extend(np.unique(y if based == "y" else x))
    ax.add_collection(collection)
    return collection


def histogram(ax: Axes, values: Sequence[float], edges: np.ndarray, colour: str) -> np.ndarray:
    """``ax.hist(values, edges, color=colour, edgecolor="white")`` drawn as one collection; the
    counts."""
    counts, _ = np.histogram(np.asarray(values, float), edges)
    bars(ax, edges[:-1], np.diff(edges), 0.0, counts, facecolor=colour, edgecolor="white")
    return counts


def score_histogram(percent: Sequence[float]) -> str:
    """Histogram of the graded students' scores, in percent of the maximum."""
    fig = Figure(figsize=(7, 2.8))
    ax = fig.add_subplot()
    heights = histogram(ax, percent, np.linspace(0, 100, 21), COLOURS["scores"])
    margins(fig, y_axis(count_ticks(max(heights, default=0) * 1.05)))
    if len(percent):
        ax.axvline(float(np.median(percent)), color="black", linestyle="--", linewidth=1,
                   label=f"median {np.median(percent):.0f} %")
        ax.legend(frameon=False)
    ax.set_xlabel("score (% of the maximum)")
    ax.set_ylabel("students")
    ax.set_xlim(0, 100)
    return svg_base64(fig)


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
        bars(ax, left, width, y - 0.375, 0.75, based="x", facecolor=COLOURS[name],
             edgecolor="none", label=name)
        left += width
    ax.set_yticks(y, labels)
    ax.set_xlabel("students")
    height = fig.get_size_inches()[1]  # the legend above, centred on the figure (it may be
    legend = ax.legend(ncols=5, loc="upper center", frameon=False, fontsize="small",  # wider
                       bbox_to_anchor=(0.5, 1 - EDGE / 2 / height),  # than the axes)
                       bbox_transform=fig.transFigure)
    rows = -(-len(legend.get_texts()) // 5)
    margins(fig, y_axis(labels, label=False), top=EDGE + 0.05 + 0.22 * rows)
    return svg_base64(fig)


def written_scores(points: Sequence[float], maximum: float) -> str:
    """Histogram of one written answer's reviewed scores, from 0 to ``maximum`` points."""
    fig = Figure(figsize=(7, 2.4))
    ax = fig.add_subplot()
    top = maximum if maximum > 0 else 1.0
    heights = histogram(ax, points, np.linspace(0, top, min(20, max(4, int(4 * top))) + 1),
                        COLOURS["reviewed"])
    margins(fig, y_axis(count_ticks(max(heights, default=0) * 1.05)),
            right=0.1 + text_width([f"{top:g}", f"{top:.1f}"]) / 2)
    ax.set_xlabel("points given by the reviews")
    ax.set_ylabel("students")
    ax.set_xlim(0, top)
    return svg_base64(fig)


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
    placed = [(label, f, 0.0 if d is None else d, COLOURS["scores"] if d is not None
               else "#999999")
              for label, f, d in zip(labels, facility, discrimination, strict=True)
              if f is not None]
    if placed:
        ax.scatter([p[1] for p in placed], [p[2] for p in placed], c=[p[3] for p in placed],
                   zorder=2)
    for label, f, y, _ in placed:
        ax.annotate(label, (f, y), textcoords="offset points", xytext=(4, 3), fontsize=7)
    ax.set_xlim(-0.02, 1.02)
    ax.set_ylim(-1, 1)
    ax.set_xlabel("facility (mean fraction of the points)")
    ax.set_ylabel("discrimination (r with the rest)")
    return svg_base64(fig)


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
    y = [len(rows) - 1 - k + rng.uniform(-0.25, 0.25, len(ratios))
         for k, (_, ratios) in enumerate(rows)]
    if rows:
        ax.scatter(np.log10(np.abs(np.concatenate([r for _, r in rows], dtype=float))),
                   np.concatenate(y), s=8, color=COLOURS["wrong"], alpha=0.6)
    ax.set_yticks(np.arange(len(rows))[::-1], [r[0] for r in rows])
    ax.set_xlim(-3, 3)
    ax.set_xlabel("log₁₀ |wrong value / the student's own key|")
    return svg_base64(fig)
