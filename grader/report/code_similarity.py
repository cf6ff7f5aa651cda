"""Nearly identical notebook code: the copy check's weaker evidence.

A notebook's code is cut into Python tokens by the standard library's :mod:`tokenize`
(comments kept, lower-cased; every number becomes ``#`` and every string ``"…"``, so a copy
whose numbers were changed to one's own variant still matches; layout tokens dropped), and
into *shingles*: every run of :data:`SHINGLE` consecutive tokens. What the student was handed is
removed — every shingle of any released notebook (``HW/release/<id>.ipynb``: a copy of a
classmate's notebook holds *their* parameters cell) — and so are
the idioms of the class: a shingle found in more than :func:`common_limit` notebooks
(``import numpy as np``, ``np.sqrt(``). Two notebooks are compared by the Jaccard index of what
is left, ``|A ∩ B| / |A ∪ B|``, computed exactly through an inverted index of the rare shingles
(only pairs sharing one are ever looked at; with the common ones gone, each list is short).

A pair is reported when the index is at least :data:`MIN_JACCARD` and they share at least
:data:`MIN_SHARED` shingles. Students who work together legitimately, or who start from the same
worked example, look alike too: this is a reason to look, weaker than a copied answer.
Cells that :mod:`tokenize` cannot read (unbalanced brackets, IPython magics) are split on
words and symbols instead.

Bounded per notebook (issue 23): a notebook is read as safely as for grading (a regular file
of at most the submission size limit, its JSON within :func:`grader.notebook_load.notebook_json`'s
limits), and only the first :data:`MAX_COMPARED_CHARS` characters of its code are tokenised; the
report names the notebooks that were cut (:attr:`NotebookCode.cut`).

Floor 5 of grader/ (views of records, and file formats; grader/API.md).
"""

from __future__ import annotations

import functools
import io
import math
import re
import tokenize
from collections import Counter, defaultdict
from collections.abc import Iterable, Mapping
from dataclasses import dataclass
from pathlib import Path

from grader.notebook_load import notebook_json
from grader.submission_file import read_submission

SHINGLE = 5
"""Tokens per shingle."""

MIN_JACCARD = 0.5
MIN_SHARED = 20

MAX_COMPARED_CHARS = 100_000
"""Characters of a notebook's code compared: the first ones, cut at a line end (a generated
solution has under ten thousand). Tokenising costs time and memory in proportion."""

_SKIP = {tokenize.NEWLINE, tokenize.NL, tokenize.INDENT, tokenize.DEDENT, tokenize.ENCODING,
         tokenize.ENDMARKER}
_WORDS = re.compile(r"\w+|[^\w\s]")


@dataclass(frozen=True)
class SimilarCode:
    """Two notebooks whose own code is nearly the same.

    Attributes
    ----------
    students : tuple of str
        The two ids, in roster order.
    jaccard : float
        Jaccard index of their filtered shingle sets.
    shared : int
        Shingles they share.
    """

    students: tuple[str, str]
    jaccard: float
    shared: int


@dataclass(frozen=True)
class NotebookCode:
    """The code of one notebook, as compared.

    Attributes
    ----------
    sources : tuple of str
        The sources of its code cells, :data:`MAX_COMPARED_CHARS` characters in all at most
        (empty when the file cannot be read as a notebook).
    cut : bool
        The notebook holds more code than that; only the first was compared.
    """

    sources: tuple[str, ...]
    cut: bool = False


def notebook_code(path: Path, limit: int = MAX_COMPARED_CHARS) -> NotebookCode:
    """The code of the notebook at ``path``: at most ``limit`` characters (module docstring)."""
    try:
        cells = notebook_json(read_submission(Path(path)))["cells"]
    except (OSError, ValueError, KeyError, TypeError):  # SubmissionError is a ValueError
        return NotebookCode(())
    sources, left = [], limit
    for cell in cells if isinstance(cells, list) else []:
        if isinstance(cell, dict) and cell.get("cell_type") == "code":
            src = cell.get("source", "")
            src = "".join(map(str, src)) if isinstance(src, list) else str(src)
            if len(src) > left:
                kept = src[:left]
                sources.append(kept[:kept.rfind("\n") + 1] or kept)
                return NotebookCode(tuple(sources), cut=True)
            sources.append(src)
            left -= len(src)
    return NotebookCode(tuple(sources))


def tokens(source: str) -> list[str]:
    """Normalised tokens of one cell (module docstring).

    Examples
    --------
    >>> tokens("w = 2.5 * np.sqrt(x)  # Spin Rate")
    ['w', '=', '#', '*', 'np', '.', 'sqrt', '(', 'x', ')', '# spin rate']
    """
    out = []
    try:
        for tok in tokenize.generate_tokens(io.StringIO(source).readline):
            if tok.type in _SKIP:
                continue
            if tok.type == tokenize.NUMBER:
                out.append("#")
            elif tok.type == tokenize.STRING:
                out.append('"…"')
            elif tok.type == tokenize.COMMENT:
                out.append(" ".join(tok.string.lower().split()))
            else:
                out.append(tok.string)
    except (tokenize.TokenError, IndentationError, SyntaxError):
        return ["#" if w[0].isdigit() else w for w in _WORDS.findall(source)]
    return out


def shingles(sources: Iterable[str]) -> set[tuple[str, ...]]:
    """Every run of :data:`SHINGLE` tokens within a cell, over all ``sources``."""
    out = set()
    for source in sources:
        t = _cell_tokens(source) if len(source) <= REMEMBERED_CHARS else tokens(source)
        out.update(tuple(t[i:i + SHINGLE]) for i in range(len(t) - SHINGLE + 1))
    return out


REMEMBERED_CHARS = 4096
"""Cells at most this long have their tokens remembered (:func:`_cell_tokens`, at most 2048
cells: some 25 MB at worst); a longer one, rare and costly to keep, is read each time."""


@functools.lru_cache(maxsize=2048)
def _cell_tokens(source: str) -> tuple[str, ...]:
    """:func:`tokens` of a cell, remembered: the notebooks handed out share most of their cells
    (322 distinct among 4500 in a class of 300), and a submission repeats the cells it was
    handed."""
    return tuple(tokens(source))


def common_limit(notebooks: int) -> int:
    """A shingle in more notebooks than this is an idiom of the class, not evidence:
    ``max(3, 5 % of the class)``."""
    return max(3, math.ceil(0.05 * notebooks))


def similar_code(submissions: Mapping[str, NotebookCode], released: Iterable[NotebookCode],
                 order: Mapping[str, int] | None = None) -> tuple[SimilarCode, ...]:
    """Pairs of submissions whose own code is nearly identical (module docstring).

    Parameters
    ----------
    submissions : mapping
        Student id → the code of the submitted notebook (:func:`notebook_code`).
    released : iterable of NotebookCode
        The code of the notebooks the students were handed (the shingles of all are removed).
    order : mapping, optional
        Student id → position, for the order of ids within a pair (default: sorted ids).

    Returns
    -------
    tuple of SimilarCode
        Highest Jaccard index first.
    """
    given: set = set()
    for code in released:
        given |= shingles(code.sources)
    own = {sid: shingles(code.sources) - given for sid, code in submissions.items()}
    frequency = Counter(s for sh in own.values() for s in sh)
    limit = common_limit(len(own))
    rare = {sid: {s for s in sh if frequency[s] <= limit} for sid, sh in own.items()}
    index: dict[tuple, list[str]] = defaultdict(list)
    for sid, sh in rare.items():
        for s in sh:
            index[s].append(sid)
    shared: Counter = Counter()
    for holders in index.values():
        for i, a in enumerate(holders):
            for b in holders[i + 1:]:
                shared[tuple(sorted((a, b)))] += 1
    rank = order or {s: i for i, s in enumerate(sorted(own))}
    out = []
    for (a, b), n in shared.items():
        jaccard = n / (len(rare[a]) + len(rare[b]) - n)
        if jaccard >= MIN_JACCARD and n >= MIN_SHARED:
            out.append(SimilarCode(tuple(sorted((a, b), key=rank.__getitem__)), jaccard, n))
    return tuple(sorted(out, key=lambda c: (-c.jaccard, c.students)))
