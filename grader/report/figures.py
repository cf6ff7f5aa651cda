"""The report's figures: matplotlib, drawn off-screen and inlined as base64 PNG.

Each function takes plain numbers and returns the PNG bytes base64-encoded, for an
``<img src="data:image/png;base64,…">`` that works offline. A :class:`matplotlib.figure.Figure`
is made directly (no ``pyplot``: no global state, safe in the grader's threads), and PNG metadata
is left out so that the same class gives the same bytes.

Colours name what they show, the same in every figure and in the tables (:data:`COLOURS`).

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


def png_base64(fig: Figure) -> str:
    """The figure as base64 PNG (no metadata: reproducible bytes)."""
    buffer = io.BytesIO()
    fig.savefig(buffer, format="png", dpi=100, metadata={"Software": None})
    return base64.b64encode(buffer.getvalue()).decode("ascii")


def score_histogram(percent: Sequence[float]) -> str:
    """Histogram of the graded students' scores, in percent of the maximum."""
    fig = Figure(figsize=(7, 2.8), layout="constrained")
    ax = fig.add_subplot()
    ax.hist(percent, bins=np.linspace(0, 100, 21), color=COLOURS["scores"], edgecolor="white")
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
    fig = Figure(figsize=(7, 0.8 + 0.28 * len(labels)), layout="constrained")
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
    ax.legend(ncols=5, loc="lower center", bbox_to_anchor=(0.5, 1.0), frameon=False,
              fontsize="small")
    return png_base64(fig)


def written_scores(points: Sequence[float], maximum: float) -> str:
    """Histogram of one written answer's reviewed scores, from 0 to ``maximum`` points."""
    fig = Figure(figsize=(7, 2.4), layout="constrained")
    ax = fig.add_subplot()
    top = maximum if maximum > 0 else 1.0
    ax.hist(points, bins=np.linspace(0, top, min(20, max(4, int(4 * top))) + 1),
            color=COLOURS["reviewed"], edgecolor="white")
    ax.set_xlabel("points given by the reviews")
    ax.set_ylabel("students")
    ax.set_xlim(0, top)
    return png_base64(fig)


def facility_discrimination(labels: Sequence[str], facility: Sequence[float],
                            discrimination: Sequence[float | None]) -> str:
    """Each answer placed by facility (x) and discrimination (y); the flagged regions shaded."""
    fig = Figure(figsize=(7, 3.6), layout="constrained")
    ax = fig.add_subplot()
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
    fig = Figure(figsize=(7, 0.9 + 0.3 * max(len(rows), 1)), layout="constrained")
    ax = fig.add_subplot()
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
