"""The report's figures keep every text inside the picture (grader/report/figures.py: a layout
fixed from the measured texts, issue 34).

Reference: matplotlib's own extent of each text as Agg draws it — every tick label, axis label,
legend entry and annotation — against the figure's frame; labels long and short, classes
small and large, as the report passes them.
"""

from __future__ import annotations

import numpy as np
import pytest
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure
from matplotlib.text import Text

from grader.report import figures

LONG = ["1.I1", "2.omega_precession_rate", "3.angular_momentum_norm_at_t1", "4.T"]
SHORT = ["a", "b"]
MANY = [f"{q}.answer_{k}" for q in range(1, 9) for k in range(3)]  # 24 answers
EVERY_OUTCOME = {"correct": 40, "follows": 3, "known mistake": 9, "wrong": 120, "invalid": 2,
                 "unanswered": 1, "pending": 5, "reviewed": 7}

DRAWINGS = {
    "scores, one student": lambda: figures.score_histogram([100.0]),
    "scores, 300 students": lambda: figures.score_histogram(
        list(np.random.default_rng(0).uniform(0, 100, 300))),
    "scores, none": lambda: figures.score_histogram([]),
    "outcomes, long labels, every outcome": lambda: figures.outcomes(
        LONG, [EVERY_OUTCOME] * len(LONG)),
    "outcomes, short labels": lambda: figures.outcomes(SHORT, [{"correct": 1}] * 2),
    "outcomes, many answers": lambda: figures.outcomes(MANY, [{"correct": 5, "wrong": 1}]
                                                       * len(MANY)),
    "facility, labels at every edge": lambda: figures.facility_discrimination(
        LONG, [0.0, 1.0, 1.0, None], [1.0, -1.0, 1.0, 0.5]),
    "facility, many": lambda: figures.facility_discrimination(
        MANY, list(np.linspace(0, 1, len(MANY))), list(np.linspace(-1, 1, len(MANY)))),
    "written, four points": lambda: figures.written_scores([0, 1.5, 4, 4], 4.0),
    "written, thirty points": lambda: figures.written_scores([12.5, 30, 29], 30.0),
    "wrong ratios, long labels": lambda: figures.wrong_ratios(
        [(LONG[2], [2.0, 1e3, 1e-3]), (LONG[1], [57.3])]),
    "wrong ratios, one": lambda: figures.wrong_ratios([("a", [0.5])]),
}


@pytest.mark.parametrize("name", DRAWINGS)
def test_every_text_of_a_figure_is_inside_it(monkeypatch, name):
    drawn: list[Figure] = []
    monkeypatch.setattr(figures, "svg_base64", lambda fig: drawn.append(fig) or "")
    DRAWINGS[name]()
    (fig,) = drawn
    canvas = FigureCanvasAgg(fig)
    canvas.draw()
    renderer = canvas.get_renderer()
    frame = fig.bbox
    texts = [t for t in fig.findobj(Text) if t.get_visible() and t.get_text().strip()
             and _drawn(t)]
    assert len(texts) >= 4  # tick labels and axis labels at least
    for text in texts:
        box = text.get_window_extent(renderer)
        inside = (box.x0 >= frame.x0 - 0.5 and box.x1 <= frame.x1 + 0.5
                  and box.y0 >= frame.y0 - 0.5 and box.y1 <= frame.y1 + 0.5)
        assert inside, f"{text.get_text()!r} at {box} is cut by the frame {frame}"


def _drawn(text: Text) -> bool:
    """Whether Agg draws ``text``: a tick label only where its tick is in the axis's view."""
    for ax in text.figure.axes:
        for axis in (ax.xaxis, ax.yaxis):
            ticks = axis.get_major_ticks() + axis.get_minor_ticks()
            if any(text in (t.label1, t.label2) for t in ticks):
                low, high = sorted(axis.get_view_interval())
                return any(text in (t.label1, t.label2)
                           and low - 1e-9 <= t.get_loc() <= high + 1e-9 for t in ticks)
    return True
