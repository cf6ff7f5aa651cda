"""``eulertop problems preview``: a few variants of a family, as an instructor checks them.

For each seed (``numpy.random.default_rng(seed)``, as ``eulertop problems test`` draws): the
parameters (every recorded one: labels, and numbers the statement alone shows), the key's
values with their tolerances, points and known mistakes, and the question as the student
reads it — heading, statement and the line saying how each answer is compared, rendered by the
feedback pages' renderer (:func:`grader.statement_html.statement_html`, handed in by the front
end as ``render``: ``problems/`` sits below ``grader/``) — then the answer cell.

The page is one self-contained HTML file (no script, nothing loaded).
"""

from __future__ import annotations

import html
from collections.abc import Callable, Sequence

import numpy as np

from problems.answers import Answer
from problems.family import Family, Parameter
from problems.notebook import answer_line, comparison_line, python_literal
from problems.variant import Variant, answer_spec

_STYLE = """
body { font-family: system-ui, sans-serif; max-width: 60rem; margin: 2rem auto; padding: 0 1rem;
       line-height: 1.45; }
table { border-collapse: collapse; margin: .5rem 0 1rem; }
td, th { border: 1px solid #ccc; padding: .2rem .5rem; text-align: left; vertical-align: top; }
section { border-top: 2px solid #888; margin-top: 2rem; }
.statement { background: #f7f7f7; padding: .5rem 1rem; }
pre { background: #f0f0f0; padding: .5rem; overflow-x: auto; }
"""


def variants_of(family: Family, seeds: Sequence[int]) -> list[Variant]:
    """The family's variant for each seed."""
    family.prepare()
    return [family.generate(np.random.default_rng(seed)) for seed in seeds]


def preview_page(family: Family, seeds: Sequence[int],
                 render: Callable[[str], str]) -> tuple[str, list[Variant]]:
    """The HTML page for ``seeds`` (each statement's Markdown and LaTeX as HTML by ``render``),
    and the variants it shows."""
    variants = variants_of(family, seeds)
    title = f"{family.name}: {family.title}"
    parts = ["<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\">",
             "<meta http-equiv=\"Content-Security-Policy\" content=\"default-src 'none'; "
             "style-src 'unsafe-inline'\">",
             f"<title>{_e(title)}</title><style>{_STYLE}</style></head><body>",
             f"<h1>{_e(title)}</h1><p>{_e(family.summary)} — from {_e(family.origin)}</p>"]
    for seed, variant in zip(seeds, variants, strict=True):
        question = (f"## {variant.title}\n\n{variant.statement.strip()}\n\n"
                    f"{comparison_line(variant.answers, 1)}")
        cell = "\n".join(answer_line(answer_spec(a, 1)) for a in variant.answers)
        parts += [f"<section><h2>seed {seed}</h2>", "<h3>Parameters</h3>",
                  _parameter_table(family, variant), "<h3>Key</h3>", _key_table(variant),
                  "<h3>As the student reads it</h3>",
                  f"<div class=\"statement\">{render(question)}</div>",
                  f"<pre>{_e(cell)}</pre></section>"]
    parts.append("</body></html>\n")
    return "\n".join(parts), variants


def _e(text: object) -> str:
    return html.escape(str(text), quote=True)


def _parameter_table(family: Family, variant: Variant) -> str:
    declared = family.parameters
    rows = ["<tr><th>parameter</th><th>value</th><th>unit</th><th>where</th>"
            "<th>a spec may set it</th></tr>"]
    for name, value in variant.parameters.items():
        p = declared[name]
        where = "label" if p.is_choice else ("parameter cell" if p.in_cell else "statement")
        rows.append(f"<tr><td><code>{_e(name)}</code></td><td>{_e(_shown(value))}</td>"
                    f"<td>{_e(p.unit)}</td><td>{where}</td><td>{_e(_settable(p))}</td></tr>")
    return "<table>" + "".join(rows) + "</table>"


def _settable(p: Parameter) -> str:
    if p.is_choice:
        return "one or more of " + ", ".join(p.choices)
    if p.low is not None:
        return f"within [{p.low:g}, {p.high:g}]"
    return "no: derived from the others"


def _shown(value: object) -> str:
    return value if isinstance(value, str) else python_literal(value)


def _key_table(variant: Variant) -> str:
    rows = ["<tr><th>answer</th><th>key</th><th>kind</th><th>tolerance</th><th>points</th>"
            "<th>known mistakes</th></tr>"]
    for a in variant.answers:
        mistakes = ", ".join(f"{m.name} = {_shown(m.value)}" for m in a.mistakes)
        rows.append(f"<tr><td><code>{_e(a.name)}</code></td><td>{_e(_shown(a.value))} "
                    f"{_e(a.unit)}</td><td>{a.kind}</td><td>{_e(_tolerance(a))}</td>"
                    f"<td>{a.points:g}</td><td>{_e(mistakes)}</td></tr>")
    return "<table>" + "".join(rows) + "</table>"


def _tolerance(a: Answer) -> str:
    if a.kind in ("boolean", "choice"):
        return "exact"
    return f"rtol {a.rtol:g}" + (f", atol {a.atol:g}" if a.atol else "")


def preview_text(family: Family, seeds: Sequence[int], variants: Sequence[Variant]) -> list[str]:
    """One line of parameters and one of key values per seed, for the terminal."""
    lines = []
    for seed, v in zip(seeds, variants, strict=True):
        params = ", ".join(f"{k} = {_shown(x)}" for k, x in v.parameters.items())
        key = ", ".join(f"{a.name} = {_shown(a.value)}" for a in v.answers)
        lines += [f"seed {seed}: {v.title}", f"  parameters: {params}", f"  key: {key}"]
    return lines
