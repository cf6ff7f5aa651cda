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
def formula_html(latex: str, display: bool = False) -> str:
    """One formula as MathML (cleaned), or its source in ``<code>`` if it cannot be read.

    Cached: the conventions and most formulas of a statement are the same for every student,
    and converting one costs about a millisecond."""
    from latex2mathml.converter import convert

    try:
        return clean_mathml(convert(latex.strip(), display="block" if display else "inline"))
    except Exception:  # latex2mathml raises many kinds on bad input: show the source instead
        return f'<code class="latex">{html.escape(latex)}</code>'


@functools.cache
def _markdown():
    from markdown_it import MarkdownIt

    return MarkdownIt("commonmark", {"html": False}).enable("table").disable("image")


def statement_html(text: str) -> str:
    """``text`` (Markdown and LaTeX) as HTML: formulas set aside, Markdown rendered, formulas
    put back as MathML (module docstring).

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

    rendered = _markdown().render(_MATH.sub(set_aside, text))
    return _SLOT_RE.sub(lambda m: formulas[int(m.group(1))], rendered)
