"""``report.html``: one self-contained page, for the instructor.

Self-contained and offline: figures are inline SVG (``data:`` URIs), the style is one inline
``<style>``, and the per-student table's CSV is both written beside the page and embedded as a
``data:`` download link. A Content-Security-Policy in the page (``default-src 'none'``) forbids
every fetch, frame, form and plugin: the page cannot reach the network even if a value in it
were crafted to.

Sorting the table
    A table cannot sort itself without a script. Two ways were possible: a tiny inline script
    (click a column heading) allowed by the CSP through its SHA-256 hash, or tables pre-sorted
    on the server with the CSV for anything else. The page does both: the rows come sorted by
    score (useful with scripts off, printed, or in a mail client), and :data:`SORT_SCRIPT` —
    twenty lines, no library, no network — re-sorts on a click. The hash pins that exact
    script: any other script (say, markup smuggled in through a student's string value) is
    refused by the browser, on top of every value being HTML-escaped.

Floor 5 of grader/ (views of records, and file formats; grader/API.md).
"""

from __future__ import annotations

import base64
import hashlib
import html
import json
from collections.abc import Sequence

import numpy as np

from grader.report import figures
from grader.report.assemble import ClassReport
from grader.report.classdata import NUMERIC_KINDS, numeric
from grader.report.code_similarity import MAX_COMPARED_CHARS, MIN_JACCARD
from grader.report.copying import ALPHA
from grader.report.items import ItemStats, shown_categories
from problems.answers import WRITTEN

MAX_LISTED = 40
"""Students named in one cell before the list is cut (the CSV has them all)."""

SORT_SCRIPT = """
document.querySelectorAll("table.sortable").forEach(function (table) {
  table.setAttribute("data-sortable", "on");
  var heads = table.tHead.rows[0].cells;
  Array.prototype.forEach.call(heads, function (th, col) {
    th.tabIndex = 0;
    th.title = "sort by this column";
    function sort() {
      var up = th.getAttribute("aria-sort") !== "ascending";
      Array.prototype.forEach.call(heads, function (h) { h.removeAttribute("aria-sort"); });
      th.setAttribute("aria-sort", up ? "ascending" : "descending");
      var body = table.tBodies[0], rows = Array.prototype.slice.call(body.rows);
      function key(row) {
        var c = row.cells[col];
        return c.getAttribute("data-v") ?? c.textContent;
      }
      rows.sort(function (a, b) {
        var x = key(a), y = key(b), nx = parseFloat(x), ny = parseFloat(y);
        var d = (isNaN(nx) || isNaN(ny)) ? x.localeCompare(y) : nx - ny;
        return up ? d : -d;
      });
      rows.forEach(function (row) { body.appendChild(row); });
    }
    th.addEventListener("click", sort);
    th.addEventListener("keydown", function (e) { if (e.key === "Enter") { sort(); } });
  });
});
"""

STYLE = """
body { font-family: system-ui, sans-serif; max-width: 76rem; margin: 1.5rem auto;
       padding: 0 1rem; color: #222; line-height: 1.4; }
h1 { font-size: 1.5rem; } h2 { margin-top: 2.2rem; border-bottom: 1px solid #ddd; }
table { border-collapse: collapse; margin: 0.6rem 0; font-size: 0.85rem; }
th, td { border: 1px solid #ddd; padding: 0.2rem 0.45rem; text-align: left; vertical-align: top; }
th { background: #f4f4f4; } td.n { text-align: right; font-variant-numeric: tabular-nums; }
table.sortable th { cursor: pointer; }
th[aria-sort="ascending"]::after { content: " \\25B2"; }
th[aria-sort="descending"]::after { content: " \\25BC"; }
img { max-width: 100%; display: block; margin: 0.5rem 0; }
.flag { color: #b00020; font-weight: 600; } .note { color: #555; font-size: 0.9rem; }
.look li { margin: 0.2rem 0; } code { background: #f4f4f4; padding: 0 0.2rem; }
"""


CONTENTS = "<nav>" + " · ".join(
    f'<a href="#{anchor}">{name}</a>' for anchor, name in (
        ("look", "look at first"), ("scores", "scores"), ("items", "questions and answers"),
        ("written", "written answers"),
        ("mistakes", "known mistakes"), ("slips", "common wrong answers"),
        ("copying", "copied answers"), ("students", "students"))) + "</nav>"
"""Links to the sections (in-page anchors only)."""


def sha256_source(text: str) -> str:
    """A CSP source for an inline element's exact text: ``'sha256-…'``."""
    return "'sha256-" + base64.b64encode(hashlib.sha256(text.encode()).digest()).decode() + "'"


def content_security_policy() -> str:
    """The page's policy: nothing may load; only the page's own style and script run."""
    return (f"default-src 'none'; img-src data:; style-src {sha256_source(STYLE)}; "
            f"script-src {sha256_source(SORT_SCRIPT)}; base-uri 'none'; form-action 'none'")


def e(value: object) -> str:
    """HTML-escaped text."""
    return html.escape(str(value), quote=True)


def shown(value: object, digits: int = 6) -> str:
    """A submitted or key value for people: numbers to ``digits`` significant figures."""
    if isinstance(value, float):
        return f"{value:.{digits}g}"
    if isinstance(value, list) and len(value) == 1 and isinstance(value[0], int | float):
        return shown(float(value[0]), digits)  # a scalar, held as an array of one
    if isinstance(value, list) and all(isinstance(v, int | float) for v in value):
        return "[" + ", ".join(shown(float(v), digits) for v in value) + "]"
    text = json.dumps(value, ensure_ascii=False) if not isinstance(value, str) else value
    return text if len(text) <= 80 else text[:80] + "…"


def names(ids: Sequence[str]) -> str:
    """Escaped, comma-separated ids, cut after :data:`MAX_LISTED`."""
    cut = f", … ({len(ids) - MAX_LISTED} more)" if len(ids) > MAX_LISTED else ""
    return e(", ".join(ids[:MAX_LISTED])) + cut


def img(svg: str, alt: str) -> str:
    """A figure of :mod:`grader.report.figures` (base64 SVG) as an image."""
    return f'<img alt="{e(alt)}" src="data:image/svg+xml;base64,{svg}">'


def table(header: Sequence[str], rows: Sequence[Sequence[str]], sortable: bool = False) -> str:
    """An HTML table from already-escaped cell HTML (a cell starting ``<td`` is kept as is)."""
    head = "".join(f"<th>{h}</th>" for h in header)
    body = "".join("<tr>" + "".join(c if c.startswith("<td") else f"<td>{c}</td>" for c in r)
                   + "</tr>" for r in rows)
    cls = ' class="sortable"' if sortable else ""
    return f"<table{cls}><thead><tr>{head}</tr></thead><tbody>{body}</tbody></table>"


def num(value: float | None, fmt: str = ".2f") -> str:
    """A right-aligned numeric cell with its sort value."""
    if value is None:
        return '<td class="n" data-v="">—</td>'
    return f'<td class="n" data-v="{value!r}">{format(value, fmt)}</td>'


# ------------------------------------------------------------------------------------------
# sections


def look_first(report: ClassReport) -> str:
    """The bullet list at the top: what deserves a look."""
    items = []
    for s in (*report.questions, *report.answers):
        if s.flags and (s.name is None or "possibly broken" in s.flags):
            items.append(f"<b>{e(s.label)}</b> ({e(s.family)}): "
                         f'<span class="flag">{e(", ".join(s.flags))}</span>, facility '
                         f"{s.facility:.2f}{_agreement(report, s)}")
    for g in report.slips[:8]:
        items.append(f"common wrong answer on <b>{e(g.variable)}</b>: <code>{e(g.formula)}</code>"
                     f" ({len(g.students)} students)")
    for p in report.flagged_pairs:
        items.append(f"answers of <b>{e(p.students[0])}</b> and <b>{e(p.students[1])}</b> "
                     f"match on {len(p.matches)} answers (chance {p.chance:.1e})")
    for c in report.code:
        items.append(f"code of <b>{e(c.students[0])}</b> and <b>{e(c.students[1])}</b> is "
                     f"nearly identical (Jaccard {c.jaccard:.2f})")
    for sid, why in foreign_notebooks(report):
        items.append(f"the notebook graded as <b>{e(sid)}</b>'s: {e(why)}")
    if not items:
        return "<p>Nothing stands out: no flagged question, common slip or matching pair.</p>"
    return '<ul class="look">' + "".join(f"<li>{i}</li>" for i in items) + "</ul>"


def _agreement(report: ClassReport, s: ItemStats) -> str:
    """For a possibly broken answer: the class agreeing on one relation to the key suggests
    the key is what is wrong."""
    if "possibly broken" not in s.flags:
        return ""
    wrong = s.counts["wrong"]
    group = next((g for g in report.slips if g.variable == s.label), None)
    if group is None or not wrong or len(group.students) < wrong / 2:
        return ""
    return (f" — {len(group.students)} of the {wrong} wrong answers are <code>"
            f"{e(group.formula)}</code> of the key: <b>check the key</b> (if the class is "
            "right, the key is off by the inverse)")


def scores_section(report: ClassReport) -> str:
    data = report.data
    percent = [100 * data.results[s].points / data.results[s].max_points
               for s in data.graded if data.results[s].max_points]
    status = {k: sum(1 for r in data.results.values() if r.status == k)
              for k in ("graded", "failed", "missing")}
    stats = (f"mean {np.mean(percent):.1f} %, median {np.median(percent):.1f} %"
             if percent else "no graded submission")
    return ('<h2 id="scores">Scores</h2>'
            f"<p>{len(data.ids)} students on the roster: {status['graded']} graded, "
            f"{status['failed']} could not be graded, "
            f"{status['missing']} handed in nothing. Graded scores: {stats}.</p>"
            + late_paragraph(data)
            + img(figures.score_histogram(percent), "histogram of the scores"))


def late_paragraph(data) -> str:
    """How many came in late, and what the late policy took (none without a policy)."""
    entries = [r.late for r in data.results.values() if r.late]
    if not entries and "late" not in data.assignment.manifest:
        return ""
    late = [x for x in entries if x.get("late_by_seconds", 0) > 0]
    penalised = [x for x in late if x.get("points")]
    closed = [x for x in late if x.get("closed")]
    extended = sum(1 for x in entries if x.get("extension"))
    taken = sum(x["points"] for x in penalised)
    return (f"<p>Late: {len(late)} of {len(entries)} submissions with a known time came in "
            f"after their deadline; {len(penalised)} lost points to the penalty "
            f"({taken:.4g} in all), {len(closed)} after the close; {extended} "
            "student(s) had an extension.</p>")


def _stats_rows(stats: Sequence[ItemStats], categories: Sequence[str]) -> list[list[str]]:
    rows = []
    for s in stats:
        flag = f'<span class="flag">{e(", ".join(s.flags))}</span>' if s.flags else ""
        rows.append([e(s.label), e(s.family), *(num(s.counts[c], "d") for c in categories),
                     num(s.facility), num(s.discrimination), flag])
    return rows


def items_section(report: ClassReport) -> str:
    categories = shown_categories(report.answers)
    header = ["item", "family", *categories, "facility", "discrimination", "flags"]
    answers = report.answers
    parts = [
        '<h2 id="items">Questions and answers</h2>',
        '<p class="note">Facility: mean fraction of the points earned by the graded students. '
        "Discrimination: correlation (point-biserial) of the item's score with the rest of the "
        "score — near zero or negative, strong students miss it as often as weak ones.</p>",
        table(header, _stats_rows(report.questions, categories), sortable=True),
        img(figures.outcomes([s.label for s in answers], [s.counts for s in answers]),
            "outcome of every answer"),
        img(figures.facility_discrimination([s.label for s in answers],
                                            [s.facility for s in answers],
                                            [s.discrimination for s in answers]),
            "facility against discrimination"),
        table(header, _stats_rows(answers, categories), sortable=True),
    ]
    return "".join(parts)


def written_section(report: ClassReport) -> str:
    """The written answers (:mod:`grader.reviews`): per answer, how many wait for a review,
    the distribution of the reviewed scores, and how often each rubric item was given."""
    data = report.data
    items = [i for i in data.items if i.kind == WRITTEN]
    if not items:
        return ""
    parts = ['<h2 id="written">Written answers</h2>']
    for item in items:
        answers = [a for s in data.graded if (a := data.answer(s, item.variable)) is not None]
        reviewed = [a.verdict.points for a in answers if a.verdict.status == "reviewed"]
        pending = sum(a.verdict.status == "pending" for a in answers)
        missing = sum(a.verdict.status == "missing" for a in answers)
        most = max((a.verdict.max_points for a in answers), default=0.0)
        mean = f", mean {np.mean(reviewed):.3g} of {most:g}" if reviewed else ""
        parts.append(f"<h3>{e(item.variable)} ({e(item.family)})</h3>"
                     f"<p>{len(reviewed)} reviewed{mean}; {pending} pending review; {missing} "
                     "unanswered.</p>")
        if reviewed:
            parts.append(img(figures.written_scores(reviewed, most),
                             f"distribution of the reviewed scores of {item.variable}"))
        parts.append(_rubric_table(data, item.variable))
    return "".join(parts)


def _rubric_table(data, variable: str) -> str:
    """How many reviewed answers were given each rubric item."""
    given: dict[str, list[int]] = {}
    for sid in data.graded:
        for n, r in enumerate(data.results[sid].reviewed.get(variable, {}).get("rubric", ())):
            counts = given.setdefault(f"{n + 1}. {r['item']}", [0, 0])
            counts[0] += bool(r["given"])
            counts[1] += 1
    if not given:
        return ""
    rows = [[e(item), num(g, "d"), num(n, "d")] for item, (g, n) in given.items()]
    return table(["rubric item", "given", "reviewed"], rows)


def mistakes_section(report: ClassReport) -> str:
    rows = [[e(m.variable), f"<code>{e(m.name)}</code>", num(m.count, "d"), e(m.feedback)]
            for m in report.mistakes]
    body = table(["answer", "known mistake", "students", "feedback they got"], rows, True) \
        if rows else "<p>No known mistake was made.</p>"
    return '<h2 id="mistakes">Known mistakes</h2>' + body


def _ratio_rows(report: ClassReport) -> list[tuple[str, list[float]]]:
    data, rows = report.data, []
    for item in data.items:
        if item.kind not in NUMERIC_KINDS:
            continue
        ratios = []
        for sid in data.graded:
            a = data.answer(sid, item.variable)
            if a is None or a.verdict.status != "wrong" or a.verdict.mistake:
                continue
            x, v = numeric(a.submitted), numeric(data.keys[sid][item.variable].value)
            if x is not None and v is not None and x.shape == v.shape and np.linalg.norm(v):
                r = np.linalg.norm(x) / np.linalg.norm(v)
                if r > 0:
                    ratios.append(float(r))
        rows.append((item.variable, ratios))
    return rows


def slips_section(report: ClassReport) -> str:
    rows = []
    for g in report.slips:
        ex = "<br>".join(f"{e(s)}: {e(shown(x))} (key {e(shown(v))})" for s, x, v in g.examples)
        rows.append([e(g.variable), f"<code>{e(g.relation)}</code>", f"<code>{e(g.formula)}"
                     "</code>", num(len(g.students), "d"), num(100 * g.share, ".0f"),
                     names(g.students), ex])
    intro = ('<p class="note">Wrong answers the templates do not know, related to each '
             "student's <em>own</em> key (v): a shared relation means a shared slip. Add a "
             "frequent one to the template as a known mistake (<code>Mistake(name, formula, "
             "feedback)</code>) so students get feedback on it.</p>")
    body = table(["answer", "relation", "wrong value", "students", "% of answers", "who",
                  "examples"], rows, True) if rows else \
        "<p>No wrong answer is shared by enough students to stand out.</p>"
    ratio_rows = [r for r in _ratio_rows(report) if r[1]]
    figure = img(figures.wrong_ratios(ratio_rows), "wrong answers against the students' keys") \
        if ratio_rows else ""
    return '<h2 id="slips">Common wrong answers</h2>' + intro + body + figure


def _match_text(m) -> str:
    if m.how == "key":
        return (f"{e(m.variable)}: {e(m.copier)} gave {e(shown(m.submitted))} = "
                f"{e(m.source)}'s key {e(shown(m.other))} (chance {m.chance:.1e})")
    return (f"{e(m.variable)}: same wrong value {e(shown(m.submitted))} / "
            f"{e(shown(m.other))} (chance {m.chance:.1e})")


def foreign_notebooks(report: ClassReport) -> list[tuple[str, str]]:
    """``(student, why)`` of each record whose notebook is not the student's own, in roster
    order: not this assignment's, another student's or another variant's
    (``execution["foreign"]``, :func:`grader.grade_one.record`)."""
    results = report.data.results
    return [(sid, str(results[sid].execution["foreign"])) for sid in report.data.ids
            if sid in results and results[sid].execution.get("foreign")]


def _foreign_part(report: ClassReport) -> str:
    rows = [[e(sid), e(why)] for sid, why in foreign_notebooks(report)]
    body = table(["student", "why"], rows, True) if rows else \
        ("<p>None: no notebook graded is another student's or another variant's, as far as "
         "its metadata and its parameters cell tell.</p>")
    return ("<h3>Notebooks that are not the student's own</h3>"
            '<p class="note">Each was graded as the student its file name says, against their '
            "key, all the same; its row and feedback page say why.</p>" + body)


def copying_section(report: ClassReport) -> str:
    intro = ('<p class="note">Flags for a person to look at, never penalties. A wrong answer '
             "equal to another student's key, or two students' identical wrong answers, are "
             "unlikely by chance because every variant differs; the chance comes from the "
             "tolerance and the spread of the class's values. A pair is listed when fewer than "
             f"{ALPHA} such pairs are expected in an honest class of this size.</p>")
    code = {c.students: c for c in report.code}
    rows = []
    for p in report.flagged_pairs:
        c = code.get(p.students)
        rows.append([e(p.students[0]), e(p.students[1]), num(len(p.matches), "d"),
                     num(p.chance, ".1e"), num(p.expected, ".1e"), e(p.direction),
                     "" if c is None else f"{c.jaccard:.2f}",
                     "<br>".join(_match_text(m) for m in p.matches)])
    body = table(["student", "student", "answers matching", "chance", "expected by chance",
                  "direction", "code Jaccard", "matching answers"], rows, True) if rows else \
        "<p>No pair of students has answers matching beyond chance.</p>"
    crows = [[e(c.students[0]), e(c.students[1]), num(c.jaccard), num(c.shared, "d")]
             for c in report.code]
    if not report.code_checked:
        cbody = ("<p>The notebooks were not available, so their code was not compared "
                 "(<code>eulertop report --submissions DIR</code>).</p>")
    elif crows:
        cbody = table(["student", "student", "Jaccard", "shared shingles"], crows, True)
    else:
        cbody = f"<p>No two notebooks share {MIN_JACCARD:.0%} or more of their own code.</p>"
    if report.code_cut:
        cbody += (f'<p class="note">Only the first {MAX_COMPARED_CHARS:,} characters of code were '
                  f"compared for {', '.join(e(s) for s in report.code_cut)}: their notebooks "
                  "hold more.</p>")
    return ('<h2 id="copying">Copied answers</h2>' + intro + body + _foreign_part(report) +
            "<h3>Nearly identical code (weaker evidence)</h3>"
            '<p class="note">Token shingles of each notebook\'s own code (what the student was '
            "handed and the class's common idioms removed), compared by the Jaccard index.</p>"
            + cbody)


def students_section(table_rows: Sequence[Sequence[str]], csv_text: str, csv_name: str) -> str:
    header, *rows = table_rows
    numeric_cols = {i for i, h in enumerate(header)
                    if h in ("percent", "points", "maximum") or (h[1:].isdigit() and h[0] == "q")}
    cells = [[num(float(c), ".4g") if i in numeric_cols and c else e(c)
              for i, c in enumerate(r)] for r in rows]
    data_uri = "data:text/csv;charset=utf-8;base64," + base64.b64encode(
        csv_text.encode()).decode()
    return ('<h2 id="students">Students</h2>'
            f'<p>Sorted by score; click a heading to sort by it. The same table as CSV: '
            f'<a download="{e(csv_name)}" href="{data_uri}">download</a> (also written as '
            f"<code>{e(csv_name)}</code> beside this page).</p>"
            + table([e(h) for h in header], cells, sortable=True))


def report_html(report: ClassReport, table_rows: Sequence[Sequence[str]], csv_text: str,
                csv_name: str = "report.csv") -> str:
    """The whole page (module docstring)."""
    title = report.data.assignment.title
    body = "".join((
        f"<h1>Class report: {e(title)}</h1>", CONTENTS,
        '<h2 id="look">Look at first</h2>', look_first(report),
        scores_section(report), items_section(report), written_section(report),
        mistakes_section(report),
        slips_section(report), copying_section(report),
        students_section(table_rows, csv_text, csv_name),
    ))
    return ("<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\">"
            f'<meta http-equiv="Content-Security-Policy" content="{content_security_policy()}">'
            f"<title>Class report: {e(title)}</title><style>{STYLE}</style></head>"
            f"<body>{body}<script>{SORT_SCRIPT}</script></body></html>\n")
