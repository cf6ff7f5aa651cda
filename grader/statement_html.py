"""A question statement (Markdown with LaTeX between ``$…$`` and ``$$…$$``) as safe HTML.

Markdown is rendered by markdown-it-py (CommonMark with tables; raw HTML in the text is *not*
passed through but escaped, images are off — the page loads nothing), and each formula by
latex2mathml into MathML, which current Chromium, Firefox and Safari render natively: no
script, no font download, so the feedback page stays one self-contained file under its strict
Content-Security-Policy.

latex2mathml does not escape text inside ``\\text{…}`` or stray ``&``, so its output is not
trusted: :func:`clean_mathml` re-writes it keeping only MathML elements and presentation
attributes, with all text escaped. A formula latex2mathml cannot read is shown as its LaTeX
source, escaped, in ``<code>``.

Floor 0 of grader/ (records and pure helpers; grader/API.md).
"""

from __future__ import annotations

import functools
import html
import re
from html.parser import HTMLParser
from typing import Any

_MATH = re.compile(r"\$\$(?P<display>.+?)\$\$|(?<![\\$])\$(?P<inline>[^$\n]+?)\$", re.S)
_SLOT = "EULERTOPMATH{}X"
_SLOT_RE = re.compile(r"EULERTOPMATH(\d+)X")

MATHML_ELEMENTS = frozenset("""
math mrow mi mn mo mtext mspace ms msub msup msubsup munder mover munderover mfrac msqrt mroot
mstyle mtable mtr mtd mpadded mphantom menclose merror semantics annotation mlabeledtr
""".split())
MATHML_ATTRIBUTES = frozenset("""
xmlns display mathvariant stretchy accent accentunder fence separator displaystyle scriptlevel
columnalign rowalign columnspacing rowspacing columnlines rowlines lspace rspace minsize maxsize
linethickness width height depth symmetric largeop movablelimits form notation encoding
""".split())


class _MathMLCleaner(HTMLParser):
    """Re-serialise MathML keeping only :data:`MATHML_ELEMENTS` and :data:`MATHML_ATTRIBUTES`."""

    def __init__(self) -> None:
        super().__init__(convert_charrefs=True)
        self.out: list[str] = []

    def handle_starttag(self, tag, attrs):
        if tag in MATHML_ELEMENTS:
            kept = "".join(f' {k}="{html.escape(v or "", quote=True)}"' for k, v in attrs
                           if k in MATHML_ATTRIBUTES
                           and (k != "xmlns" or v == "http://www.w3.org/1998/Math/MathML"))
            self.out.append(f"<{tag}{kept}>")

    def handle_endtag(self, tag):
        if tag in MATHML_ELEMENTS:
            self.out.append(f"</{tag}>")

    def handle_data(self, data):
        self.out.append(html.escape(data, quote=False))


def clean_mathml(markup: str) -> str:
    """``markup`` with every element and attribute outside MathML's presentation set dropped
    and every text escaped.

    Examples
    --------
    >>> clean_mathml('<math><mtext><script>x</script> & y</mtext></math>')
    '<math><mtext>x &amp; y</mtext></math>'
    """
    cleaner = _MathMLCleaner()
    cleaner.feed(markup)
    cleaner.close()
    return "".join(cleaner.out)


@functools.lru_cache(maxsize=8192)
def _converted(latex: str, display: bool) -> str | None:
    """``latex`` as cleaned MathML, or None if it cannot be read. Cached."""
    from latex2mathml.converter import convert

    try:
        return clean_mathml(convert(latex.strip(), display="block" if display else "inline"))
    except Exception:  # latex2mathml raises many kinds on bad input
        return None


_NUMBER = re.compile(r"(?<![A-Za-z])\d+(?:\.\d+)?")
"""A number written in a formula (not the digits of a command's argument, as in ``\\tfrac12``)."""
_ZERO = "<mn>0</mn>"


def formula_html(latex: str, display: bool = False) -> str:
    """One formula as MathML (cleaned), or its source in ``<code>`` if it cannot be read.

    A statement's formulas differ from student to student only in their numbers
    (``\\omega_3 = 315``): each is converted once with every number written as 0 (cached: a
    class of 300 has some 150 such forms for 16 000 formulas) and the numbers are put back, in
    order, as the ``<mn>`` elements they become — where the count of those tells the numbers
    apart from the form's own; else the formula itself is converted (cached too).
    ``tests/grader/test_statement_html.py`` checks the two ways agree on every family's
    statements."""
    numbers = _NUMBER.findall(latex)
    if numbers:
        form = _converted(_NUMBER.sub("0", latex), display)
        parts = form.split(_ZERO) if form is not None else []
        if len(parts) == len(numbers) + 1:
            return parts[0] + "".join(f"<mn>{n}</mn>{part}"
                                      for n, part in zip(numbers, parts[1:], strict=True))
    markup = _converted(latex, display)
    return markup if markup is not None else f'<code class="latex">{html.escape(latex)}</code>'


@functools.cache
def _markdown():
    from markdown_it import MarkdownIt

    return MarkdownIt("commonmark", {"html": False}).enable("table").disable("image")


IMAGE_POLICY = "img-src data:"
"""What a page's Content-Security-Policy adds to show a written answer's kept attachments."""


@functools.cache
def _student_markdown():
    from markdown_it import MarkdownIt

    return MarkdownIt("commonmark", {"html": False}).enable("table").disable(
        ["image", "link", "autolink", "linkify"], ignoreInvalid=True)


def written_html(value: Any) -> str:
    """A student's recorded written answer (:mod:`grader.written`) as HTML: its text rendered
    as a statement is but with links and images off as well — what a student wrote never
    becomes a link, a script or a request — then its kept attachments as ``data:`` images of
    their raster type (a page showing them allows :data:`IMAGE_POLICY`), and the attachments
    dropped and the notes, as text.

    Examples
    --------
    >>> out = written_html({"text": "[x](javascript:alert(1)) <script>1</script> $a$"})
    >>> "<a " in out or "<script" in out, "<math" in out
    (False, True)
    """
    from grader.written import KEPT_TYPES, written_text

    parts = [statement_html(written_text(value), _student_markdown())]
    if isinstance(value, dict):
        for name, a in (value.get("attachments") or {}).items():
            if a.get("type") in KEPT_TYPES and re.fullmatch(r"[A-Za-z0-9+/=]*", a.get("data", "")):
                parts.append(f'<p><img alt="{html.escape(str(name))}" '
                             f'src="data:{a["type"]};base64,{a["data"]}"></p>')
        notes = [f"{d.get('name')}: {d.get('why')}" for d in value.get("dropped") or ()]
        notes += [str(n) for n in value.get("notes") or ()]
        if notes:
            items = "".join(f"<li>{html.escape(n)}</li>" for n in notes)
            parts.append(f'<ul class="dropped">{items}</ul>')
    return "\n".join(parts)


def statement_html(text: str, markdown: Any = None) -> str:
    """``text`` (Markdown and LaTeX) as HTML: formulas set aside, Markdown rendered, formulas
    put back as MathML (module docstring). ``markdown``: the renderer (a ``MarkdownIt``;
    default the statements', images off) — what a student wrote is rendered with links off
    too (:func:`grader.written.written_html`).

    Examples
    --------
    >>> out = statement_html(r"**Spin** $\\omega = \\frac{L}{I}$ <b>")
    >>> "<strong>Spin</strong>" in out and "<mfrac>" in out and "&lt;b&gt;" in out
    True
    """
    formulas: list[str] = []

    def set_aside(m: re.Match) -> str:
        display = m.group("display") is not None
        formulas.append(formula_html(m.group("display" if display else "inline"), display))
        return _SLOT.format(len(formulas) - 1)

    slotted = _MATH.sub(set_aside, text)
    rendered = _rendered(slotted) if markdown is None else markdown.render(slotted)
    return _SLOT_RE.sub(lambda m: formulas[int(m.group(1))], rendered)


@functools.lru_cache(maxsize=1024)
def _rendered(slotted: str) -> str:
    """A statement's Markdown rendered, its formulas set aside (:func:`statement_html`),
    remembered: with the numbers inside the formulas, a class's statements are few texts (89
    among 4200 in a class of 300), each ~0.2 ms to parse and render."""
    return _markdown().render(slotted)
