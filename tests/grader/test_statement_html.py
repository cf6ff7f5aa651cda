"""Feedback pages show statements as mathematics: Markdown rendered, LaTeX as MathML, safe.

The browser test opens real feedback pages in headless Chromium (Debian's ``chromium``, which
CI installs) and reads back the document it built: its text holds no raw ``$…$``, ``\\frac``
or ``**``. Like the sandbox battery it fails, never skips, when the browser is missing.
"""

from __future__ import annotations

import re
import shutil
import subprocess
from html.parser import HTMLParser
from pathlib import Path

import numpy as np
import pytest
from markdown_it import MarkdownIt

from grader.gradebook import feedback_html
from grader.results import StudentResult
from grader.statement_html import (
    _MATH,
    MATHML_ELEMENTS,
    clean_mathml,
    formula_html,
    statement_html,
)
from problems.templates import FAMILIES

HOSTILE = (r"Bold **spin** and $\text{<script>alert(1)</script> & x}$ then "
           '<img src=x onerror="alert(2)"> [link](javascript:alert(3)) ![i](http://example.com/a.png)'
           r" and $$\frac{1}{2} I \omega^2$$ \$5")
HTML_ELEMENTS = {"p", "strong", "em", "code", "a", "table", "thead", "tbody", "tr", "th", "td",
                 "ol", "ul", "li", "pre", "br", "h1", "h2", "h3", "hr", "blockquote"}


class _Tags(HTMLParser):
    def __init__(self):
        super().__init__()
        self.tags, self.attrs, self.values, self.text = set(), set(), [], []

    def handle_starttag(self, tag, attrs):
        self.tags.add(tag)
        self.attrs.update(k for k, _ in attrs)
        self.values += [v or "" for _, v in attrs]

    def handle_data(self, data):
        self.text.append(data)


def _parse(markup: str) -> _Tags:
    p = _Tags()
    p.feed(markup)
    return p


def test_markdown_and_latex_become_html_and_mathml():
    out = statement_html(r"A *top*: $\omega_3 = \frac{L}{I_3}$, and $$T = \tfrac12 I \dot\beta^2$$")
    assert "<em>top</em>" in out
    assert out.count("<math") == 2 and '<math display="block"' in out.replace(
        ' xmlns="http://www.w3.org/1998/Math/MathML"', "")
    assert "<mfrac>" in out and "$" not in out and "\\frac" not in out


def test_hostile_statements_stay_inert():
    out = statement_html(HOSTILE)
    tags = _parse(out)
    assert tags.tags <= HTML_ELEMENTS | MATHML_ELEMENTS, tags.tags - HTML_ELEMENTS
    assert not {a for a in tags.attrs if a.startswith("on")} and "src" not in tags.attrs
    assert not any(v.lower().startswith("javascript:") for v in tags.values)
    assert "<img" not in out and "<script" not in out
    text = "".join(tags.text)
    assert "alert(1)\xa0&\xa0x" in text  # the element dropped, its text kept, as text
    assert '<img src=x onerror="alert(2)">' in text  # raw HTML shown as the text it is
    assert "$5" in text and "**" not in text


def test_a_formula_latex2mathml_cannot_read_is_shown_as_its_source():
    out = statement_html(r"broken $x_{$ here")
    assert '<code class="latex">x_{</code>' in out


def _direct(latex: str, display: bool) -> str:
    """latex2mathml on the formula itself, cleaned: what the number-free forms must give."""
    from latex2mathml.converter import convert

    return clean_mathml(convert(latex.strip(), display="block" if display else "inline"))


@pytest.mark.parametrize("family", sorted(FAMILIES))
def test_formulas_converted_by_their_form_equal_the_formulas_converted_whole(family):
    """formula_html converts each form once (numbers as 0) and puts the numbers back: over
    every formula of this family's statements, byte for byte what converting it gives."""
    checked = 0
    for seed in range(12):
        statement = FAMILIES[family].generate(np.random.default_rng(seed)).statement
        for m in _MATH.finditer(statement):
            display = m.group("display") is not None
            latex = m.group("display" if display else "inline")
            assert formula_html(latex, display) == _direct(latex, display), latex
            checked += 1
    assert checked > 12


@pytest.mark.parametrize("family", sorted(FAMILIES))
def test_a_statement_rendered_from_what_is_remembered_equals_it_rendered_afresh(family):
    """statement_html remembers the rendered Markdown of a statement with its formulas set
    aside (a class's statements are few such texts): every statement of this family's, as
    the second of its kind, byte for byte what rendering it with a renderer of its own gives."""
    fresh = MarkdownIt("commonmark", {"html": False}).enable("table").disable("image")
    texts = [FAMILIES[family].generate(np.random.default_rng(seed)).statement
             for seed in range(12)]
    for text in texts + texts:  # the second time round, from what was remembered
        assert statement_html(text) == statement_html(text, fresh)


@pytest.mark.parametrize("latex", [r"\tfrac12 I_1 \dot\beta^2", r"x_0 = 0.5", r"2\pi r = 10.25",
                                   r"I_3 = 1.53 \times 10^{-5}", r"\omega_{12} = -3.0",
                                   r"0", r"a0 + 0 = 3"])
def test_numbers_next_to_letters_and_commands(latex):
    assert formula_html(latex) == _direct(latex, False)


def _page(tmp_path: Path, statements: list[str]) -> Path:
    questions = [{"question": i, "title": f"Q{i}", "statement": s, "params": {},
                  "answers": []} for i, s in enumerate(statements, start=1)]
    result = StudentResult("alice", "graded", "", (), 0, 0, None, "sha256:x", {}, True,
                           "2024-01-01T00:00:00+00:00")
    page = tmp_path / "alice.html"
    page.write_text(feedback_html("Tops", result, questions), encoding="utf-8")
    return page


def chromium(*args: str, profile: Path, timeout: float = 60) -> str:
    """Run headless Chromium offline with a fresh profile; its stdout."""
    exe = shutil.which("chromium") or shutil.which("chromium-browser")
    if exe is None:
        pytest.fail("chromium is not installed: `apt-get install chromium` (README); the "
                    "feedback pages must be checked in a browser, never skipped", pytrace=False)
    command = [exe, "--headless", "--no-sandbox", "--disable-gpu", "--no-first-run",
               "--disable-background-networking", "--disable-component-update",
               "--disable-sync", f"--user-data-dir={profile}", *args]
    done = subprocess.run(command, capture_output=True, text=True, timeout=timeout)
    assert done.returncode == 0, done.stderr[-2000:]
    return done.stdout


def test_in_a_browser_no_raw_latex_or_markdown_is_left(tmp_path, generated_assignment):
    import json

    manifest = json.loads((generated_assignment.hw / "assignment.json").read_text())
    statements = [q["statement"] for q in manifest["students"]["alice"]["questions"]]
    assert any("$$" in s for s in statements) and any("|" in s for s in statements)
    page = _page(tmp_path, [*statements, HOSTILE])
    dom = chromium("--dump-dom", page.as_uri(), profile=tmp_path / "profile")
    assert dom.count("<math") >= len(statements)
    body = re.sub(r"<(style|title)>.*?</\1>", "", dom, flags=re.S)
    # code spans hold Python (``beta_dot**2``, ``sp.Symbol('I_1')``): what is due there is code
    text = "".join(_parse(re.sub(r"<code[^>]*>.*?</code>", "", body, flags=re.S)).text)
    assert re.search(r"\$[^$\s][^$]*\$", text.replace("$5", "")) is None
    assert "\\frac" not in text and "**" not in text and "\\dot" not in text
    assert "<script" not in body.lower().replace("&lt;script", "")
