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
"""

from __future__ import annotations

import io
import json
import math
import re
import tokenize
from collections import Counter, defaultdict
from collections.abc import Iterable, Mapping
from dataclasses import dataclass
from pathlib import Path

SHINGLE = 5
"""Tokens per shingle."""

MIN_JACCARD = 0.5
MIN_SHARED = 20

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


def code_cells(path: Path) -> list[str]:
    """The sources of a notebook's code cells (``[]`` when it cannot be read as a notebook)."""
    try:
        nb = json.loads(Path(path).read_text(encoding="utf-8"))
        cells = nb["cells"]
    except (OSError, UnicodeDecodeError, ValueError, KeyError, TypeError):
        return []
    sources = []
    for cell in cells if isinstance(cells, list) else []:
        if isinstance(cell, dict) and cell.get("cell_type") == "code":
            src = cell.get("source", "")
            sources.append("".join(src) if isinstance(src, list) else str(src))
    return sources


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
        t = tokens(source)
        out.update(tuple(t[i:i + SHINGLE]) for i in range(len(t) - SHINGLE + 1))
    return out


def common_limit(notebooks: int) -> int:
    """A shingle in more notebooks than this is an idiom of the class, not evidence:
    ``max(3, 5 % of the class)``."""
    return max(3, math.ceil(0.05 * notebooks))


def similar_code(submissions: Mapping[str, Path], released: Mapping[str, Path],
                 order: Mapping[str, int] | None = None) -> tuple[SimilarCode, ...]:
    """Pairs of submissions whose own code is nearly identical (module docstring).

    Parameters
    ----------
    submissions : mapping
        Student id → submitted notebook.
    released : mapping
        Student id → the notebook they were handed (the shingles of all of them are removed).
    order : mapping, optional
        Student id → position, for the order of ids within a pair (default: sorted ids).

    Returns
    -------
    tuple of SimilarCode
        Highest Jaccard index first.
    """
    given: set = set()
    for path in released.values():
        given |= shingles(code_cells(path))
    own = {sid: shingles(code_cells(path)) - given for sid, path in submissions.items()}
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
