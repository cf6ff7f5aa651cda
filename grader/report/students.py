"""The per-student table of the report, and the same rows as CSV for a spreadsheet.

One row per roster student: score, points per question, and what the report noticed about
them — the common slips they made, the classmates their answers match (flagged pairs) and
those whose code is nearly the same. Written as CSV by :func:`grader.gradebook.gradebook_csv`,
like every table of the project. Rows are sorted by score, highest first (ties by roster
order), so the table reads well even where the page's sorting script does not run.

Floor 5 of grader/ (views of records, and file formats; grader/API.md).
"""

from __future__ import annotations

from collections import defaultdict
from collections.abc import Sequence

from grader.gradebook import number
from grader.report.classdata import ClassData
from grader.report.code_similarity import SimilarCode
from grader.report.copying import CopyPair
from grader.report.slips import SlipGroup


def student_rows(data: ClassData, slips: Sequence[SlipGroup], pairs: Sequence[CopyPair],
                 code: Sequence[SimilarCode]) -> list[list[str]]:
    """The table as rows of strings, header first (columns in the module docstring)."""
    questions = data.assignment.questions
    has_name = "name" in data.assignment.columns
    notes = _notes(slips, pairs, code)
    header = ["id", *(["name"] if has_name else []), "status", "percent", "points", "maximum",
              *(f"q{k}" for k in questions), "slips", "answers match", "code like"]
    rows = []
    for i, row in enumerate(data.assignment.rows):
        sid = row["id"]
        r = data.results.get(sid)
        if r is None:
            cells = ["not graded yet", "", "", "", *([""] * len(questions))]
            score = -1.0
        else:
            per_q = r.question_points()
            score = 100 * r.points / r.max_points if r.max_points else 0.0
            cells = [r.status, f"{score:.1f}", number(r.points), number(r.max_points),
                     *(number(per_q.get(k, 0.0)) for k in questions)]
        cells += ["; ".join(notes[key][sid]) for key in ("slips", "pairs", "code")]
        rows.append((-score, i, [sid, *([row.get("name", "")] if has_name else []), *cells]))
    return [header, *(r[2] for r in sorted(rows, key=lambda t: t[:2]))]


def _notes(slips, pairs, code) -> dict[str, dict[str, list[str]]]:
    notes: dict[str, dict[str, list[str]]] = {k: defaultdict(list)
                                              for k in ("slips", "pairs", "code")}
    for g in slips:
        for sid in g.students:
            notes["slips"][sid].append(f"{g.variable}: {g.relation}")
    for p in pairs:
        if p.flagged:
            a, b = p.students
            notes["pairs"][a].append(b)
            notes["pairs"][b].append(a)
    for c in code:
        a, b = c.students
        notes["code"][a].append(b)
        notes["code"][b].append(a)
    return notes
