"""What a grading run hands to people: ``grades.csv``, ``feedback/<id>.html``, the summary.

All three are *derived* from the result records (``results/<id>.json``) and the assignment
files, and are rebuilt from them — so a resumed run's gradebook is the same as an
uninterrupted run's, and changing ``--reveal`` rewrites every feedback page.

Feedback pages are for one student each and hold only that student's own parameters, answers,
verdicts and messages (and, with ``reveal``, that student's key values); nothing of any other
student is passed in. Everything is HTML-escaped — not only what the student wrote (submitted
values, exception messages their code raised, which verdict messages echo) but the instructor's
text too — and the page loads nothing from anywhere (no scripts, no external styles). Question
statements are shown as mathematics: their Markdown rendered and their LaTeX turned into MathML
(:func:`grader.statement_html.statement_html`: raw HTML in them escaped, the MathML cleaned).

Floor 5 of grader/ (views of records, and file formats; grader/API.md).
"""

from __future__ import annotations

import csv
import html
import io
import json
import re
from collections.abc import Mapping, Sequence
from typing import Any

from grader.extract import UNREADABLE, invalid_reason
from grader.plain_text import printable
from grader.results import StudentResult
from grader.statement_html import IMAGE_POLICY, statement_html, written_html
from grader.submissions import Problem
from grader.written import is_written, written_text
from problems.answers import WRITTEN

MAX_SHOWN = 400
"""Characters of a submitted value or message shown before it is cut (the record keeps all)."""


SHOWN_DIGITS = 4
"""Significant figures of every point count shown (:func:`number`); records keep the float."""

NOISE = 1e-9
"""Point counts smaller than this are shown as ``0``: what is left of a sum of fractions such
as ``1 - 0.9 - 0.1``, not points anyone gave."""


def number(x: float) -> str:
    """A point count for people and spreadsheets, to :data:`SHOWN_DIGITS` significant figures
    and never in exponent notation — the one rounding of every view (grades.csv, answers.csv,
    the summary, feedback pages, the report, LMS imports, rescore's change lines).

    Examples
    --------
    >>> number(3.0), number(2.5), number(22 / 3), number(14.999999999999998), number(-0.0)
    ('3', '2.5', '7.333', '15', '0')
    >>> number(12345.6), number(1 / 3000), number(1 - 0.9 - 0.1)
    ('12350', '0.0003333', '0')
    """
    import numpy as np

    if abs(x) < NOISE:
        x = 0.0  # -0.0 too
    return np.format_float_positional(x, precision=SHOWN_DIGITS, unique=True, fractional=False,
                                      trim="-")


def _cut(text: str, limit: int = MAX_SHOWN) -> str:
    return text if len(text) <= limit else text[:limit] + f"… ({len(text) - limit} more characters)"


# --------------------------------------------------------------------------------------------
# grades.csv


def ran_code(result: StudentResult) -> bool:
    """Did the student's code run for this record (a kernel was started for it)?"""
    return bool(result.execution) and result.execution.get("status") != "invalid_notebook"


def gradebook_rows(
    columns: Sequence[str],
    rows: Sequence[Mapping[str, str]],
    questions: Sequence[int],
    results: Mapping[str, StudentResult],
    sandbox_column: bool = False,
    override_column: bool | None = None,
    late_columns: bool | None = None,
    pending_column: bool | None = None,
) -> list[list[str]]:
    """The gradebook as rows of strings, header first.

    Columns: ``id``, the roster's other columns (as in the roster), ``q1`` … ``qN`` (points per
    question), ``total``, ``maximum``, ``status``, ``reason``; with ``sandbox_column`` (the
    pipeline sets it when some submission was graded without a sandbox, ``--no-sandbox``) a last
    column ``sandboxed``: ``yes`` / ``no`` (``""`` when nothing was executed); and, when some
    record holds an instructor's override (``override_column``, default: whether one does), a
    last column ``overridden``: what was, ``q3_T_nut; total`` (``""`` for the others). Where
    the assignment has a late policy (``late_columns``, default: whether a record holds a
    late entry), ``raw`` (the points before the penalty), ``late_by`` (how late, ``""`` when
    on time or the time is unknown) and ``penalty`` (the points it took) follow ``maximum``:
    ``total`` stays what the student gets. Where the assignment has written answers
    (``pending_column``, default: whether a record holds one pending or reviewed), ``pending``
    comes before ``status``: how many of the student's written answers no one has reviewed
    yet (each counted 0 in ``total`` until then).

    ``status`` keeps three kinds of student apart: ``graded`` (the notebook ran and its answers
    were compared; ``reason`` is empty, or a note such as a cell that raised), ``missing`` (no
    submission; ``reason`` says so) and ``failed`` (a submission that could not be run or read;
    ``reason`` says why, e.g. "the kernel died"). A student without a result record (only after
    an interrupted run) gets empty points and status ``not graded yet``. Every cell is one line
    free of control characters (:func:`csv_cell`).
    """
    others = [c for c in columns if c != "id"]
    if override_column is None:
        override_column = any(r.overridden for r in results.values())
    if late_columns is None:
        late_columns = any(r.late for r in results.values())
    if pending_column is None:
        pending_column = any(a.verdict.status in WRITTEN_STATUSES for r in results.values()
                             for a in r.answers)
    late_head = ["raw", "late_by", "penalty"] if late_columns else []
    pending_head = ["pending"] if pending_column else []
    table = [["id", *others, *(f"q{k}" for k in questions), "total", "maximum", *late_head,
              *pending_head, "status", "reason", *(["sandboxed"] if sandbox_column else []),
              *(["overridden"] if override_column else [])]]
    for row in rows:
        r = results.get(row["id"])
        if r is None:
            cells = [""] * (len(questions) + 2 + len(late_head) + len(pending_head))
            cells += ["not graded yet", ""]
        else:
            per_question = r.question_points()
            cells = [number(per_question.get(k, 0.0)) for k in questions]
            cells += [number(r.points), number(r.max_points)]
            cells += late_cells(r) if late_columns else []
            cells += [str(pending_count(r))] if pending_column else []
            cells += [r.status, reason(r)]
        if sandbox_column:
            cells.append("" if r is None else "yes" if r.sandboxed else "no" if ran_code(r)
                         else "")
        if override_column:
            cells.append("" if r is None else "; ".join(r.overridden))
        table.append([csv_cell(c) for c in [row["id"], *(row.get(c, "") for c in others),
                                            *cells]])
    return table


WRITTEN_STATUSES = ("pending", "reviewed")
"""The verdicts only a written answer has (:mod:`grader.reviews`)."""


def pending_count(result: StudentResult) -> int:
    """How many of ``result``'s written answers wait for a review."""
    return sum(a.verdict.status == "pending" for a in result.answers)


def raw_points(result: StudentResult) -> float:
    """The points before the late penalty and an override of the total: the answers' sum."""
    return sum(a.verdict.points for a in result.answers)


def late_cells(result: StudentResult) -> list[str]:
    """``raw``, ``late_by`` and ``penalty`` of one row (:func:`gradebook_rows`)."""
    from datetime import timedelta

    from problems.deadlines import spoken

    late = result.late
    late_by = late.get("late_by_seconds", 0.0)
    return [number(raw_points(result)),
            spoken(timedelta(seconds=late_by)) if late_by > 0 else "",
            number(late["points"]) if late.get("points") else ""]


ANSWER_COLUMNS = ("id", "question", "answer", "variable", "submitted", "points", "max",
                  "status", "mistake", "overridden")


def answers_rows(rows: Sequence[Mapping[str, str]],
                 results: Mapping[str, StudentResult]) -> list[list[str]]:
    """``answers.csv``, the long format: one row per student and answer, header first.

    Columns :data:`ANSWER_COLUMNS`: the student id, question number, the answer's name and
    notebook variable, the submitted value as JSON (empty when not set), points awarded and
    possible, the verdict's status, the recognised mistake (empty when none), and for an
    answer the instructor overrode (:mod:`grader.overrides`) what it had and why,
    ``was 0: <reason>`` (``points`` is then the override's; empty for the others). A written
    answer's ``submitted`` is its text (its attachments stay in the record). Students
    without a record are left out.
    """
    table = [list(ANSWER_COLUMNS)]
    for row in rows:
        r = results.get(row["id"])
        for a in r.answers if r is not None else ():
            v = a.verdict
            shown = written_text(a.submitted) if is_written(a.submitted) else a.submitted
            submitted = "" if shown is None else json.dumps(shown, ensure_ascii=False)
            table.append([r.student_id, str(a.question), a.name, a.variable, submitted,
                          number(v.points), number(v.max_points), v.status, v.mistake or "",
                          csv_cell(_overridden(r.overridden.get(a.variable)))])
    return table


def _overridden(override: Mapping[str, Any] | None) -> str:
    """An answer's override as one cell: ``was 0: <reason>``; ``""`` for none."""
    return "" if override is None else f"was {number(override['was'])}: {override['reason']}"


def reason(result: StudentResult) -> str:
    """Why a student has the status they have, in one line: the record's message (its first
    line for a failed one); for a graded one every line of it, then each cell that raised or
    timed out (:func:`cell_notes`) and each answer that could not be read
    (:func:`unreadable_notes`)."""
    if result.status == "failed":
        lines = [line for line in result.message.splitlines() if line.strip()]
        return lines[0] if lines else "could not be graded"
    if result.status == "missing":
        return result.message or "no submission"
    lines = [line.strip() for line in result.message.splitlines() if line.strip()]
    return "; ".join([*lines, *cell_notes(result), *unreadable_notes(result)])


_CELL = re.compile(r"cell \d+ \(")


def unreadable_notes(result: StudentResult) -> list[str]:
    """The verdicts of the answers whose value could not be read (``q2_x could not be read:
    its value did not convert within 2 s …``: :data:`grader.extract.UNREADABLE`)."""
    return [a.verdict.message for a in result.answers
            if (invalid_reason(a.submitted) or "").startswith(UNREADABLE)]


def cell_notes(result: StudentResult) -> list[str]:
    """The record's lines for the cells that raised or timed out (``cell 7 (`while True:`):
    timed out after 30 s and was interrupted``), but those its message already names — a
    notebook whose time ran out says in its message which cell was running."""
    notes = []
    for line in result.execution.get("cell_errors") or ():
        named = _CELL.match(str(line))
        if named is None or named.group() not in result.message:
            notes.append(str(line))
    return notes


_CONTROL = re.compile(r"[\x00-\x1f\x7f-\x9f\u2028\u2029]+")


def csv_cell(text: str, limit: int = MAX_SHOWN) -> str:
    """One spreadsheet cell: control characters (line breaks, tabs, escapes, NUL) become a
    space, and the text is cut at ``limit`` characters.

    Examples
    --------
    >>> csv_cell("cell 3 raised\nZeroDivisionError:\x1b[31m boom")
    'cell 3 raised ZeroDivisionError: [31m boom'
    """
    return _cut(_CONTROL.sub(" ", str(text)).strip(), limit)


FORMULA_START = ("=", "+", "-", "@", "\t", "\r")
"""What a spreadsheet reads as the start of a formula (OWASP, "CSV Injection")."""

_NUMBER = re.compile(r"[+-]?(?:\d+\.?\d*|\.\d+)(?:[eE][+-]?\d+)?")


def inert(cell: str) -> str:
    """A cell no spreadsheet runs: one that begins with one of :data:`FORMULA_START` gets a
    leading ``'`` (OWASP's advice; a spreadsheet shows the rest as text), unless it is a plain
    number such as ``-0.5``, which stays a number.

    Examples
    --------
    >>> inert('=HYPERLINK("http://x.example","hi")'), inert("-0.5"), inert("-x"), inert("a=b")
    ('\'=HYPERLINK("http://x.example","hi")', '-0.5', "'-x", 'a=b')
    """
    if cell.startswith(FORMULA_START) and not _NUMBER.fullmatch(cell):
        return "'" + cell
    return cell


def gradebook_csv(table: Sequence[Sequence[str]], quote_all: bool = False) -> str:
    """``table`` as CSV text: the one CSV writer of the project (grades, answers, the report's
    tables, ``submissions.csv``, every LMS import). RFC 4180 quoting (every field with
    ``quote_all``), ``\\r\\n`` line ends as spreadsheets expect; every cell :func:`printable`
    (control characters and lone surrogates as escapes) and :func:`inert` (no formulas)."""
    buffer = io.StringIO(newline="")
    writer = csv.writer(buffer, quoting=csv.QUOTE_ALL if quote_all else csv.QUOTE_MINIMAL)
    writer.writerows([[inert(printable(cell)) for cell in row] for row in table])
    return buffer.getvalue()


# --------------------------------------------------------------------------------------------
# feedback/<id>.html

_STYLE = """
body { font-family: sans-serif; max-width: 60em; margin: 2em auto; line-height: 1.4; }
table { border-collapse: collapse; margin: 0.5em 0 1.5em; }
td, th { border: 1px solid #bbb; padding: 0.25em 0.6em; text-align: left; vertical-align: top; }
.statement { background: #f6f6f6; padding: 0.1em 0.8em; }
math[display="block"] { margin: 0.6em 0; }
.correct, .follows { color: #165c16; } .wrong, .invalid, .missing { color: #9c1c1c; }
.override { background: #fff6d6; padding: 0.3em 0.8em; }
.pending { color: #7a5200; } .reviewed { color: #165c16; }
.written .answer, .written .comment { border-left: 3px solid #bbb; padding: 0 0.8em; }
.written img { max-width: 100%; }
code { white-space: pre-wrap; word-break: break-all; }
"""


def _e(value: Any) -> str:
    return html.escape(printable(value), quote=True)


def _shown(value: Any) -> str:
    """A submitted value as the student would recognise it (JSON), cut and escaped."""
    if value is None:
        return "<em>not set</em>"
    return f"<code>{_e(_cut(json.dumps(value, ensure_ascii=False)))}</code>"


def _parameters(question: Mapping[str, Any]) -> str:
    units = question.get("param_units", {})
    rows = "".join(
        f"<tr><td><code>{_e(name)}</code></td><td>{_e(value)}</td>"
        f"<td>{_e(units.get(name, ''))}</td></tr>"
        for name, value in question.get("params", {}).items()
    )
    return f"<table><tr><th>parameter</th><th>value</th><th>unit</th></tr>{rows}</table>"


def _answers_table(question: Mapping[str, Any], result: StudentResult,
                   key: Mapping[str, Any] | None) -> str:
    specs = {s["variable"]: s for s in question.get("answers", [])}
    mine = [a for a in result.answers if a.question == question["question"]
            and specs.get(a.variable, {}).get("kind") != WRITTEN]
    if not mine:
        return ""
    head = "<th>variable</th><th>unit</th><th>your answer</th><th>verdict</th><th>points</th>"
    head += "<th>message</th>" + ("<th>key</th>" if key is not None else "")
    rows = []
    for a in mine:
        spec = specs.get(a.variable, {})
        v = a.verdict
        cells = [
            f"<code>{_e(a.variable)}</code><br><small>{_e(spec.get('description', ''))}</small>",
            _e(spec.get("unit", "")),
            _shown(a.submitted),
            f'<span class="{_e(v.status)}">{_e(v.status)}</span>',
            f"{number(v.points)} / {number(v.max_points)}",
            _e(_cut(v.message)),
        ]
        if key is not None:
            cells.append(_shown(key.get(a.variable)))
        rows.append("<tr>" + "".join(f"<td>{c}</td>" for c in cells) + "</tr>")
    return f"<table><tr>{head}</tr>{''.join(rows)}</table>"


def _written_part(spec: Mapping[str, Any], result: StudentResult) -> str:
    """One written answer on its student's page: the prompt, what they wrote (rendered, safe:
    :func:`grader.statement_html.written_html`), and its review — the rubric's items given
    and not, the adjustment and the reviewer's comment — or that it waits for one."""
    variable = spec.get("variable", "")
    a = next((x for x in result.answers if x.variable == variable), None)
    if a is None:
        return ""
    v = a.verdict
    parts = [f'<div class="written"><h3>Written answer <code>{_e(variable)}</code>: '
             f'<span class="{_e(v.status)}">{_e(v.status)}</span>, {number(v.points)} / '
             f"{number(v.max_points)} points</h3>",
             f"<div class=\"statement\">{statement_html(spec.get('prompt', ''))}</div>",
             "<p>Your answer:</p>",
             f'<div class="answer">{written_html(a.submitted)}</div>' if a.submitted
             else "<p><em>nothing written</em></p>"]
    review = result.reviewed.get(variable)
    if review is not None:
        parts.append(_review_html(review))
    else:
        parts.append(f"<p>{_e(v.message)}</p>")
    return "\n".join(parts) + "</div>"


def _review_html(review: Mapping[str, Any]) -> str:
    """A review as the student reads it: each rubric item, given or not, then the adjustment
    and the comment (Markdown and formulas, rendered as statements are)."""
    rows = "".join(
        f"<tr><td>{'✓ given' if r['given'] else '✗ not given'}</td>"
        f"<td>{statement_html(r['item'])}</td><td>{number(r['points'])}</td></tr>"
        for r in review.get("rubric", ()))
    parts = ["<table><tr><th>rubric</th><th>item</th><th>points</th></tr>" + rows + "</table>"]
    if review.get("adjust"):
        parts.append(f"<p>Adjustment: {review['adjust']:+g} points.</p>")
    if review.get("comment"):
        who = _e(review.get("by") or "your reviewer")
        parts.append(f'<div class="comment"><p>Comment from {who}:</p>'
                     f'{statement_html(review["comment"])}</div>')
    return "\n".join(parts)


def _when(iso: str, like: str | None = None) -> str:
    """An ISO 8601 time for people, ``2026-03-16 23:59 -05:00`` (in the offset of the time
    ``like`` where given, so that two times of one sentence read alike)."""
    from datetime import datetime

    moment = datetime.fromisoformat(iso)
    if like is not None:
        moment = moment.astimezone(datetime.fromisoformat(like).tzinfo)
    offset = moment.strftime("%z")
    return moment.strftime("%Y-%m-%d %H:%M") + (f" {offset[:3]}:{offset[3:]}" if offset else "")


def late_sentence(result: StudentResult) -> str:
    """What the late policy made of ``result`` (its ``late`` entry), in words for the student:
    the deadline that applied, when the work came in, how late, and what it cost."""
    from datetime import timedelta

    from problems.deadlines import spoken

    late, came = result.late, result.submitted
    due = f"Deadline: {_when(late['due'])}"
    if late.get("extension"):
        due += f" (your extension: {late['extension']})"
    source = f" ({came['source']})" if came.get("source") else ""
    seconds = late.get("late_by_seconds", 0.0)
    submitted = _when(came["at"], late["due"])
    if seconds <= 0:
        return f"{due}. Submitted {submitted}{source}: on time."
    late_by = spoken(timedelta(seconds=seconds))
    head = f"{due}. Submitted {submitted}{source}: {late_by} late"
    if late.get("closed"):
        what = "practice: graded, for no credit" if late["closed"] == "practice" else "no credit"
        return f"{head}, after the assignment closed — {what} (−{number(late['points'])} points)."
    if not late.get("periods"):
        return f"{head}, within the grace period: no penalty."
    unit = late.get("per", "day")
    count = f"{late['periods']} started {unit}{'s' if late['periods'] != 1 else ''}"
    base = "of the points earned" if late.get("of", "earned") == "earned" else "of the total"
    return (f"{head}: {count}, {number(late['percent'])} % {base} — "
            f"−{number(late['points'])} points.")


def feedback_html(
    title: str,
    result: StudentResult,
    questions: Sequence[Mapping[str, Any]],
    key: Mapping[str, Any] | None = None,
) -> str:
    """One student's feedback page.

    Parameters
    ----------
    title : str
        The assignment's title.
    result : StudentResult
        The student's result record.
    questions : sequence of dict
        The student's own questions from ``assignment.json`` (``students[id]["questions"]``:
        title, statement, params, param_units, public answer specs).
    key : mapping or None
        With ``--reveal``: this student's key values by variable; None hides them.
    """
    parts = [
        "<!DOCTYPE html>",
        '<html lang="en"><head><meta charset="utf-8">',
        '<meta http-equiv="Content-Security-Policy" content="default-src \'none\'; '
        f'style-src \'unsafe-inline\'; {IMAGE_POLICY}">',
        f"<title>{_e(title)} — {_e(result.student_id)}</title><style>{_STYLE}</style></head>",
        f"<body><h1>{_e(title)}</h1>",
        f"<p>Student <strong>{_e(result.student_id)}</strong> — status "
        f"<strong>{_e(result.status)}</strong>: {number(result.points)} of "
        f"{number(result.max_points)} points.</p>",
    ]
    if result.message:
        parts.append(f"<p class=\"message\">{_e(_cut(result.message, 4 * MAX_SHOWN))}</p>")
    if result.overridden:
        items = "".join(
            f"<li><code>{_e(what)}</code>: {number(o['was'])} → {number(o['points'])} points "
            f"— {_e(_cut(o['reason']))}</li>" for what, o in result.overridden.items())
        parts.append(f"<div class=\"override\"><p>Changed by your instructor:</p><ul>{items}"
                     "</ul></div>")
    if result.late:
        parts.append(f"<p class=\"late\">{_e(late_sentence(result))}</p>")
    errors = result.execution.get("cell_errors") or []
    if errors:
        items = "".join(f"<li><code>{_e(_cut(line))}</code></li>" for line in errors)
        parts.append(f"<p>While your notebook ran:</p><ul>{items}</ul>")
    for q in questions:
        parts.append(f"<h2>Question {_e(q['question'])}: {_e(q.get('title', ''))}</h2>")
        parts.append(f"<div class=\"statement\">{statement_html(q.get('statement', ''))}</div>")
        if q.get("params"):
            parts.append(_parameters(q))
        parts.append(_answers_table(q, result, key))
        parts += [_written_part(spec, result) for spec in q.get("answers", [])
                  if spec.get("kind") == WRITTEN]
    parts.append(f"<p><small>graded {_e(result.graded_at)}</small></p></body></html>\n")
    return "\n".join(parts)


# --------------------------------------------------------------------------------------------
# the terminal summary


def summary_table(results: Sequence[StudentResult], problems: Sequence[Problem] = ()) -> str:
    """A plain-text table, one line per student, then what was not graded and the counts."""
    header = ("id", "status", "points", "max", "note")
    lines = [(r.student_id, r.status, number(r.points), number(r.max_points),
              _cut(reason(r), 70)) for r in results]
    widths = [max(len(str(row[i])) for row in [header, *lines]) for i in range(4)]
    fmt = "  ".join(f"{{:<{w}}}" for w in widths) + "  {}"
    out = [fmt.format(*header).rstrip(), fmt.format(*("-" * w for w in widths), "----")]
    out += [fmt.format(*row).rstrip() for row in lines]
    counts = {s: sum(r.status == s for r in results) for s in ("graded", "missing", "failed")}
    out.append("")
    out.append(", ".join(f"{n} {s}" for s, n in counts.items()) + f" of {len(results)} students")
    late = [r.student_id for r in results if r.late.get("late_by_seconds", 0) > 0]
    if late:
        taken = sum(r.late.get("points", 0.0) for r in results)
        out.append(f"late ({len(late)}): {', '.join(late)}; the late policy took "
                   f"{number(taken)} points in all")
    waiting = [r for r in results if pending_count(r)]
    if waiting:
        out.append(f"written answers pending review: {sum(map(pending_count, waiting))}, of "
                   f"{len(waiting)} student(s); they count 0 until reviewed")
    foreign = [r.student_id for r in results if r.execution.get("foreign")]
    if foreign:
        out.append(f"not this assignment's notebook, another student's or another variant's, "
                   f"graded all the same "
                   f"({len(foreign)}): {', '.join(foreign)}")
    out += answer_counts(results)
    stray = [p for p in problems if p.student_id is None]
    if stray:
        out.append(f"not graded ({len(stray)}):")
        out += [f"  {p.message}" for p in stray]
    return "\n".join(out) + "\n"


OUTCOMES = ("correct", "follows", "wrong", "known mistake", "invalid", "unanswered", "pending",
            "reviewed")
"""The columns of :func:`answer_counts`: ``follows`` is a wrong answer credited because it
follows from the student's own earlier answers (:mod:`grader.follow_through`); a wrong answer
matching a known mistake is counted as ``known mistake`` (not also as ``wrong``);
``unanswered`` is the verdict ``missing``; ``pending`` and ``reviewed`` are written answers
waiting for a review and scored by one (:mod:`grader.reviews`)."""

SHOWN_WHEN_SEEN = ("follows", "pending", "reviewed")
"""Columns of :func:`answer_counts` shown only where some answer has them."""


def outcome(verdict: Any) -> str:
    """Which of :data:`OUTCOMES` a verdict is."""
    if verdict.status == "wrong":
        return "known mistake" if verdict.mistake else "wrong"
    return "unanswered" if verdict.status == "missing" else verdict.status


def answer_counts(results: Sequence[StudentResult]) -> list[str]:
    """Lines of a table: per answer variable (question order), how many graded submissions had
    it correct / wrong / a known mistake / invalid / unanswered. Students whose notebook was
    missing or could not be run are left out (they answered nothing); no lines when none was
    graded."""
    graded = [r for r in results if r.status == "graded"]
    if not graded:
        return []
    counts: dict[str, dict[str, int]] = {}
    for r in graded:
        for a in r.answers:
            row = counts.setdefault(a.variable, dict.fromkeys(OUTCOMES, 0))
            row[outcome(a.verdict)] += 1
    width = max(len("answer"), *map(len, counts))
    shown = [c for c in OUTCOMES  # follow-through, written answers: only where some are
             if c not in SHOWN_WHEN_SEEN or any(row[c] for row in counts.values())]
    head = "  ".join(f"{c:>{len(c)}}" for c in shown)
    lines = ["", f"per answer, over {len(graded)} graded submission(s):",
             f"{'answer':<{width}}  {head}"]
    for variable, row in counts.items():
        lines.append(f"{variable:<{width}}  " + "  ".join(f"{row[c]:>{len(c)}}" for c in shown))
    return lines
