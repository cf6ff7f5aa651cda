"""Item statistics: how each answer and each question fared across the class.

For every answer (and every question, its answers summed) over the students whose notebook was
graded:

* counts of ``correct``, ``wrong`` (no known mistake recognised), ``known mistake``, ``invalid``
  and ``unanswered`` (the grader's ``missing``); for written answers ``pending`` and
  ``reviewed`` (a pending answer has no score yet: it is left out of facility and
  discrimination);
* **facility**: the mean fraction of the item's points earned (classical test theory's
  difficulty index, p);
* **discrimination**: the point-biserial correlation between the item's score and the *rest*
  score (total minus the item), so the item is not correlated with itself
  (the "corrected item-total correlation"). A question that strong students miss as often as
  weak ones has a discrimination near zero; a negative one means strong students miss it more.

Flags for a person to look at (:func:`item_flags`):

* ``possibly broken``: almost nobody is right (facility ≤ :data:`BROKEN_FACILITY`) — a wrong key,
  an ambiguous statement; the common-wrong-answer analysis then says whether the class agrees on
  one relation to the key (which points at the key);
* ``hard``: facility below :data:`HARD_FACILITY` (and not broken);
* ``low discrimination`` / ``negative discrimination``.

Floor 5 of grader/ (views of records, and file formats; grader/API.md).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from grader.report.classdata import ClassData, question_families

CATEGORIES = ("correct", "follows", "known mistake", "wrong", "invalid", "unanswered")
"""How one answer is counted (in this order in tables and figures)."""

WRITTEN_CATEGORIES = ("pending", "reviewed")
"""How a written answer is counted besides (:mod:`grader.reviews`): waiting for a review, or
scored by one; tables show them where the class has written answers."""

ALL_CATEGORIES = (*CATEGORIES, *WRITTEN_CATEGORIES)

BROKEN_FACILITY = 0.05
HARD_FACILITY = 0.4
LOW_DISCRIMINATION = 0.1
MIN_STUDENTS = 5
"""Below this many graded students, facility and discrimination are not flagged."""


def category(verdict) -> str:
    """The :data:`CATEGORIES` entry of a verdict."""
    if verdict.status == "wrong":
        return "known mistake" if verdict.mistake else "wrong"
    return {"missing": "unanswered"}.get(verdict.status, verdict.status)


@dataclass(frozen=True)
class ItemStats:
    """Statistics of one answer (``name`` set) or one whole question (``name`` None).

    Attributes
    ----------
    label : str
        ``q3_beta1`` for an answer, ``q3`` for a question.
    question : int
    name : str or None
    family : str
        The families behind it (:func:`grader.report.classdata.families_label`): a question
        drawn from a spec's pool is named by its pool.
    counts : dict
        :data:`CATEGORIES` → number of graded students.
    facility : float or None
        Mean fraction of the points earned; None with no graded student.
    discrimination : float or None
        Point-biserial correlation of the item score with the rest score; None when either
        does not vary (everybody alike).
    flags : tuple of str
    """

    label: str
    question: int
    name: str | None
    family: str
    counts: dict
    facility: float | None
    discrimination: float | None
    flags: tuple[str, ...]


def point_biserial(item: np.ndarray, rest: np.ndarray) -> float | None:
    """Pearson correlation of ``item`` with ``rest`` (None if either is constant).

    With a right/wrong item this is the point-biserial coefficient; with partial credit it is the
    same formula (the corrected item-total correlation).

    Examples
    --------
    >>> point_biserial(np.array([1, 1, 0, 0.]), np.array([5, 4, 1, 0.]))
    0.9701425001453319
    >>> point_biserial(np.array([1, 1, 1.]), np.array([5, 4, 1.])) is None
    True
    """
    if len(item) < 2 or np.ptp(item) == 0 or np.ptp(rest) == 0:
        return None
    return float(np.corrcoef(item, rest)[0, 1])


def item_flags(facility: float | None, discrimination: float | None, n: int) -> tuple[str, ...]:
    """The flags of :mod:`grader.report.items`' docstring, from the statistics."""
    if facility is None or n < MIN_STUDENTS:
        return ()
    if facility <= BROKEN_FACILITY:
        return ("possibly broken",)
    flags = ["hard"] if facility < HARD_FACILITY else []
    if discrimination is not None and discrimination < 0:
        flags.append("negative discrimination")
    elif discrimination is not None and discrimination < LOW_DISCRIMINATION:
        flags.append("low discrimination")
    return tuple(flags)


def _stats(label, question, name, family, verdict_lists, totals) -> ItemStats:
    """``verdict_lists``: per graded student, the verdicts making up the item."""
    counts = dict.fromkeys(ALL_CATEGORIES, 0)
    for verdicts in verdict_lists:
        for v in verdicts:
            counts[category(v)] += 1
    # a written answer not reviewed yet has no score: left out of facility and discrimination
    verdict_lists = [[v for v in vs if v.status != "pending"] for vs in verdict_lists]
    earned = np.array([sum(v.points for v in vs) for vs in verdict_lists], dtype=float)
    possible = np.array([sum(v.max_points for v in vs) for vs in verdict_lists], dtype=float)
    if len(earned) == 0 or not np.any(possible > 0):
        return ItemStats(label, question, name, family, counts, None, None, ())
    facility = float(np.mean(np.divide(earned, possible, out=np.zeros_like(earned),
                                       where=possible > 0)))
    discrimination = point_biserial(earned, totals - earned)
    return ItemStats(label, question, name, family, counts, facility, discrimination,
                     item_flags(facility, discrimination, len(earned)))


def shown_categories(stats: Sequence[ItemStats]) -> tuple[str, ...]:
    """The categories a table of ``stats`` shows: :data:`CATEGORIES`, and the written ones
    where some item has a written answer."""
    written = any(s.counts.get(c) for s in stats for c in WRITTEN_CATEGORIES)
    return ALL_CATEGORIES if written else CATEGORIES


def item_statistics(data: ClassData) -> tuple[tuple[ItemStats, ...], tuple[ItemStats, ...]]:
    """``(per question, per answer)`` statistics over the graded students."""
    graded = [data.results[s] for s in data.graded]
    totals = np.array([r.points for r in graded], dtype=float)
    answers = []
    for item in data.items:
        lists = [[a.verdict for a in r.answers if a.variable == item.variable] for r in graded]
        asked = [i for i, verdicts in enumerate(lists) if verdicts]  # a variant may not ask it
        answers.append(_stats(item.variable, item.question, item.name, item.family,
                              [lists[i] for i in asked], totals[asked]))
    questions = []
    for q in data.assignment.questions:
        family = question_families(data.assignment, q)
        lists = [[a.verdict for a in r.answers if a.question == q] for r in graded]
        questions.append(_stats(f"q{q}", q, None, family, lists, totals))
    return tuple(questions), tuple(answers)
