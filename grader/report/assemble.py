"""The class report put together: every analysis run once over the records, then written.

:func:`build_report` reads the class (:mod:`grader.report.classdata`) and runs the item
statistics, the known mistakes, the common wrong answers, the copied-answer and code-similarity
checks; :func:`write_report` writes ``report.html`` (one self-contained page,
:mod:`grader.report.page`), ``report.csv`` (the per-student table) and ``report_items.csv``
(the statistics per question and per answer) beside it, atomically.

Floor 5 of grader/ (views of records, and file formats; grader/API.md).
"""

from __future__ import annotations

from collections import Counter
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path

from grader.gradebook import gradebook_csv
from grader.report.classdata import ClassData
from grader.report.code_similarity import SimilarCode, notebook_code, similar_code
from grader.report.copying import CopyPair, copy_pairs
from grader.report.items import ItemStats, item_statistics
from grader.report.slips import SlipGroup, slip_groups


@dataclass(frozen=True)
class KnownMistake:
    """A known mistake of one answer and how many graded students made it."""

    variable: str
    name: str
    count: int
    feedback: str


@dataclass(frozen=True)
class ClassReport:
    """Everything the page shows.

    Attributes
    ----------
    data : ClassData
    questions, answers : tuple of ItemStats
        Per question and per answer (:mod:`grader.report.items`).
    mistakes : tuple of KnownMistake
        Most frequent first.
    slips : tuple of SlipGroup
        Common wrong answers (:mod:`grader.report.slips`).
    pairs : tuple of CopyPair
        Every pair with a matching answer, most suspicious first; :attr:`flagged_pairs` are
        those worth a look.
    code : tuple of SimilarCode
        Nearly identical notebooks (empty when no submissions were given).
    code_checked : bool
        Whether the notebooks were available for the code comparison.
    code_cut : tuple of str
        The students whose notebooks hold more code than is compared (only the first
        :data:`~grader.report.code_similarity.MAX_COMPARED_CHARS` characters were).
    """

    data: ClassData
    questions: tuple[ItemStats, ...]
    answers: tuple[ItemStats, ...]
    mistakes: tuple[KnownMistake, ...]
    slips: tuple[SlipGroup, ...]
    pairs: tuple[CopyPair, ...]
    code: tuple[SimilarCode, ...]
    code_checked: bool
    code_cut: tuple[str, ...] = ()

    @property
    def flagged_pairs(self) -> tuple[CopyPair, ...]:
        """The pairs whose matching answers are unlikely by chance (:attr:`CopyPair.flagged`)."""
        return tuple(p for p in self.pairs if p.flagged)


def known_mistakes(data: ClassData) -> tuple[KnownMistake, ...]:
    """Known mistakes by frequency among the graded students, with their feedback."""
    counts: Counter = Counter()
    feedback: dict[tuple[str, str], str] = {}
    for sid in data.graded:
        for a in data.results[sid].answers:
            if a.verdict.status == "wrong" and a.verdict.mistake:
                k = (a.variable, a.verdict.mistake)
                counts[k] += 1
                m = data.keys[sid][a.variable].mistake(a.verdict.mistake)
                feedback.setdefault(k, m.feedback if m else a.verdict.message)
    order = {i.variable: n for n, i in enumerate(data.items)}
    return tuple(KnownMistake(v, name, n, feedback[(v, name)]) for (v, name), n in
                 sorted(counts.items(), key=lambda kv: (-kv[1], order[kv[0][0]], kv[0][1])))


def build_report(data: ClassData, submissions: Mapping[str, Path] | None = None) -> ClassReport:
    """Run every analysis over a loaded class.

    Parameters
    ----------
    data : ClassData
    submissions : mapping, optional
        Student id → submitted notebook, for the code comparison (skipped when None).
    """
    questions, answers = item_statistics(data)
    code: tuple[SimilarCode, ...] = ()
    cut: tuple[str, ...] = ()
    if submissions is not None:
        release = data.assignment.folder / "release"
        graded = set(data.graded)
        mine = {s: notebook_code(p) for s, p in submissions.items() if s in graded}
        released = [notebook_code(release / f"{s}.ipynb") for s in mine
                    if (release / f"{s}.ipynb").is_file()]
        code = similar_code(mine, released, {s: i for i, s in enumerate(data.ids)})
        cut = tuple(s for s in data.ids if s in mine and mine[s].cut)
    return ClassReport(data, questions, answers, known_mistakes(data), slip_groups(data),
                       copy_pairs(data), code, submissions is not None, cut)


def items_csv(report: ClassReport) -> str:
    """The statistics per question and per answer as CSV."""
    from grader.report.items import shown_categories

    categories = shown_categories(report.answers)
    header = ["item", "question", "answer", "family", *categories, "facility",
              "discrimination", "flags"]
    rows = [header]
    for s in (*report.questions, *report.answers):
        rows.append([s.label, str(s.question), s.name or "", s.family,
                     *(str(s.counts[c]) for c in categories),
                     "" if s.facility is None else f"{s.facility:.4f}",
                     "" if s.discrimination is None else f"{s.discrimination:.4f}",
                     "; ".join(s.flags)])
    return gradebook_csv(rows)


