"""The check's table, as HTML in a notebook and as plain text elsewhere (issue 33).

Floor 8 of the grader's front ends (grader/API.md).
"""

from __future__ import annotations

from html import escape
from typing import Any

COLOURS = {"ok": "#1a7f37", "missing": "#9a6700", "malformed": "#cf222e"}

FOOTER = "This checks the form of your answers only, never whether they are right."


def tally(rows: Any) -> str:
    """``3 of 4 answers present and well formed; 1 missing, 0 malformed.``"""
    words = [r.word for r in rows]
    text = f"{words.count('ok')} of {len(words)} answers present and well formed"
    if words.count("missing") or words.count("malformed"):
        text += f"; {words.count('missing')} missing, {words.count('malformed')} malformed"
    return text + "."


def text(check: Any) -> str:
    """The plain-text table: one line an answer, then what the saved run said."""
    width = max((len(r.variable) for r in check.rows), default=0)
    lines = [f"Checked the answers in this kernel against {check.notebook}:"]
    for r in check.rows:
        lines.append(f"  {r.word:<9} {r.variable:<{width}}  {r.message}")
        if r.saved:
            lines.append(f"  {'':<9} {'':<{width}}  {r.saved}")
    lines += [tally(check.rows), *check.notes, FOOTER]
    return "\n".join(lines)


def html_table(check: Any) -> str:
    """The HTML table (escaped: answers and messages may hold anything)."""
    body = "".join(_row(r) for r in check.rows)
    notes = "".join(f"<p>{escape(n)}</p>" for n in check.notes)
    return (f"<div class=\"eulertop-check\"><p>Checked the answers in this kernel against "
            f"<code>{escape(check.notebook)}</code>:</p>"
            "<table><thead><tr><th>answer</th><th>form</th><th>why</th></tr></thead>"
            f"<tbody>{body}</tbody></table><p>{escape(tally(check.rows))}</p>{notes}"
            f"<p><small>{escape(FOOTER)}</small></p></div>")


def _row(r: Any) -> str:
    why = escape(r.message) + (f"<br><strong>{escape(r.saved)}</strong>" if r.saved else "")
    colour = COLOURS.get(r.word, "inherit")
    return (f"<tr><td><code>{escape(r.variable)}</code></td>"
            f"<td style=\"color:{colour};font-weight:bold\">{escape(r.word)}</td>"
            f"<td style=\"text-align:left\">{why}</td></tr>")
