"""Copied answers: wrong answers that equal another student's numbers.

Every student has their own variant, so the numbers of two students' keys differ. Two kinds of
match are strong evidence that work passed from one student to another:

``key``
    ``a``'s answer is wrong for ``a`` but equals, within the tolerance, the key of ``b``'s
    variant: ``a`` handed in ``b``'s result (the direction is known: ``a`` copied ``b``).
``wrong``
    ``a`` and ``b`` handed in the same *wrong* value although their keys differ: one copied the
    other's mistake (the direction is not known).

How unlikely a match is by chance (:func:`chance`) comes from the tolerance and the spread of the
variants: the number of the other students' values (keys, and wrong answers for ``wrong``)
within ``K`` tolerances of the matched value, plus one, over their count and over ``K``
(``K`` = :data:`WINDOW`) — the density of the class's values around the match, times the width
of the tolerance window — or, when larger, the fraction of those values within the tolerance
itself, less one (a point mass, which the smoothing would spread out). Values bunched together
(an answer with few possible keys, a wrong value many students give, such as 0) thus make a
match likely, and count for little. A vector is judged by its least telling component: the
smallest of the per-component chances bounds the chance that all components match, however
they are correlated (vectors that all lie on one axis, as a known mistake's ``[0, 0, L]``
does, count for no more than one number).

A pair's chance is the product over the answers that match, and the *expected number* of honest
pairs at least as unlikely in a class of this size is that product times the number of pairs of
students and the number of ways to pick that many answers (:func:`expected_pairs`). A pair is
flagged when that expectation is at most :data:`ALPHA`.

These are flags for a person to look at — two students working together, a shared worked
example — never penalties.

Floor 5 of grader/ (views of records, and file formats; grader/API.md).
"""

from __future__ import annotations

import math
from collections import defaultdict
from dataclasses import dataclass

import numpy as np

from grader.report.classdata import NUMERIC_KINDS, ClassData, Item, numeric, submitted_values

WINDOW = 25.0
"""``K``: the density of values around a match is counted within this many tolerances."""

ALPHA = 0.01
"""A pair is flagged when fewer than this many honest pairs would match as well by chance."""


@dataclass(frozen=True)
class Match:
    """One answer on which two students' numbers agree although their variants differ.

    Attributes
    ----------
    variable : str
    how : str
        ``"key"`` (``copier``'s answer is ``source``'s key) or ``"wrong"`` (the same wrong
        value; ``copier`` and ``source`` are then just the two students, unordered).
    copier, source : str
    submitted : list
        ``copier``'s value.
    other : list
        ``source``'s key (``key``) or wrong value (``wrong``).
    chance : float
        Probability of so close a match by chance (module docstring).
    """

    variable: str
    how: str
    copier: str
    source: str
    submitted: list
    other: list
    chance: float


@dataclass(frozen=True)
class CopyPair:
    """Two students whose answers match, with the evidence.

    Attributes
    ----------
    students : tuple of str
        The two ids, in roster order.
    matches : tuple of Match
        One per matching answer (the least likely when an answer matches in two ways).
    chance : float
        Product of the matches' chances.
    expected : float
        Expected number of honest pairs matching at least as unlikely in this class.
    direction : str
        ``"a copied b"`` when every ``key`` match runs one way, else ``""``.
    """

    students: tuple[str, str]
    matches: tuple[Match, ...]
    chance: float
    expected: float
    direction: str

    @property
    def flagged(self) -> bool:
        """Worth a person's look: :attr:`expected` ≤ :data:`ALPHA`."""
        return self.expected <= ALPHA


def _offsets(x: np.ndarray, values: np.ndarray, period: float | None) -> np.ndarray:
    """``values − x`` per component (rows), wrapped modulo ``period`` when given."""
    d = values - x
    if period is not None:
        half = period / 2
        d = half - np.remainder(half - d, period)
    return d


def chance(x: np.ndarray, reference: np.ndarray, tol: float, period: float | None) -> float:
    """Probability that a value falls within ``tol`` of ``x`` by chance, estimated from the
    ``reference`` values (rows) of the rest of the class (module docstring).

    Examples
    --------
    Keys spread evenly over [0, 100), a tolerance of 0.1: about 0.2 / 100.

    >>> ref = np.linspace(0, 100, 1000, endpoint=False)[:, None]
    >>> round(chance(np.array([50.0]), ref, 0.1, None), 4)
    0.0021
    """
    return _chance_of(np.abs(_offsets(x, reference, period)), tol)


def _chance_of(offsets: np.ndarray, tol: float) -> float:
    """:func:`chance` from the distances (rows, per component) of the reference values to the
    value: worked out once for all the matches of one student's value, each match weighing it
    against the rows that are not the pair's own."""
    if len(offsets) == 0 or tol <= 0:
        return 1.0
    # A vector matches only if every component does, so the least likely component bounds the
    # chance from above, whatever the correlations (values on a line or plane stay honest).
    return min(_chance_1d(offsets[:, j], tol) for j in range(offsets.shape[1]))


def _chance_1d(offsets: np.ndarray, tol: float) -> float:
    """:func:`chance` in one dimension, from the distances of the class's values to ``x``."""
    reach = WINDOW * tol
    near = int(np.sum(offsets <= reach))
    within = int(np.sum(offsets <= tol))
    smooth = (near + 1) / (len(offsets) * WINDOW)
    return float(min(1.0, max(smooth, (within - 1) / len(offsets))))


def expected_pairs(p: float, students: int, answers: int, matched: int) -> float:
    """Expected number of honest pairs matching on ``matched`` of ``answers`` answers with a
    combined chance ``p``: ``C(students, 2) · C(answers, matched) · p``."""
    return math.comb(students, 2) * math.comb(max(answers, matched), matched) * p


def _hits(x: np.ndarray, rows: np.ndarray, tols: np.ndarray, period) -> np.ndarray:
    """Which ``rows`` lie within their ``tols`` of ``x``."""
    return np.linalg.norm(_offsets(x, rows, period), axis=1) <= tols


def _item_matches(data: ClassData, item: Item) -> list[Match]:
    """Every ``key`` and ``wrong`` match on one answer (vectorised over the class)."""
    answers = {s: data.keys[s][item.variable] for s in data.graded
               if item.variable in data.keys[s]}  # a variant may not ask for it
    keys = {s: numeric(a.value) for s, a in answers.items()}
    values = submitted_values(data, item)
    # an answer that follows from a wrong earlier one is not the key's value either: the same
    # one in two notebooks is as telling as the same wrong one
    wrong = {s: x for s, (a, _, x) in values.items() if a.verdict.status in ("wrong", "follows")}
    out = []
    for shape in {x.shape for x in wrong.values()}:
        ids = [s for s, v in keys.items() if v is not None and v.shape == shape]
        if not ids:
            continue
        key_rows = np.array([keys[s] for s in ids])
        key_tols = np.array([answers[s].atol + answers[s].rtol * np.linalg.norm(keys[s])
                             for s in ids])
        w_ids = [s for s in ids if s in wrong]
        w_rows = np.array([wrong[s] for s in w_ids]).reshape(len(w_ids), *shape)
        # the class's values a match's chance is weighed against (all but the pair's own):
        # the keys, for a "key" match; the keys and the wrong answers, for a "wrong" one
        key_owners = np.array(ids, dtype=object)
        others_of_shape = [s for s, v in wrong.items() if v.shape == shape]
        all_rows = np.concatenate([key_rows, np.array([wrong[s] for s in others_of_shape])
                                   .reshape(len(others_of_shape), *shape)])
        all_owners = np.array(ids + others_of_shape, dtype=object)
        column = {t: j for j, t in enumerate(ids)}
        for s in w_ids:
            x, period = wrong[s], answers[s].period
            same_variant = _hits(keys[s], key_rows, key_tols, period)
            key_matches = np.flatnonzero(_hits(x, key_rows, key_tols, period) & ~same_variant)
            if len(key_matches):
                offsets, not_s = np.abs(_offsets(x, key_rows, period)), key_owners != s
                for j in key_matches:
                    t = ids[j]
                    out.append(Match(item.variable, "key", s, t, x.tolist(), keys[t].tolist(),
                                     _chance_of(offsets[not_s & (key_owners != t)], key_tols[j])))
            tol = answers[s].atol + answers[s].rtol * float(np.linalg.norm(x))
            wrong_matches = [w_ids[j] for j in np.flatnonzero(_hits(x, w_rows, tol, period))
                             if w_ids[j] > s and not same_variant[column[w_ids[j]]]]
            if wrong_matches:
                offsets, not_s = np.abs(_offsets(x, all_rows, period)), all_owners != s
                for t in wrong_matches:
                    out.append(Match(item.variable, "wrong", s, t, x.tolist(), wrong[t].tolist(),
                                     _chance_of(offsets[not_s & (all_owners != t)], tol)))
    return out


def copy_pairs(data: ClassData) -> tuple[CopyPair, ...]:
    """Every pair of students with at least one matching answer, most suspicious first (the
    flagged ones are those with :attr:`CopyPair.flagged`)."""
    items = [i for i in data.items if i.kind in NUMERIC_KINDS]
    best: dict[tuple[str, str], dict[str, Match]] = defaultdict(dict)
    order = {s: i for i, s in enumerate(data.ids)}
    for item in items:
        for m in _item_matches(data, item):
            pair = tuple(sorted((m.copier, m.source), key=order.__getitem__))
            kept = best[pair].get(m.variable)
            if kept is None or m.chance < kept.chance:
                best[pair][m.variable] = m
    n = len(data.graded)
    pairs = []
    for (a, b), by_var in best.items():
        matches = tuple(by_var[i.variable] for i in items if i.variable in by_var)
        p = math.prod(m.chance for m in matches)
        pairs.append(CopyPair((a, b), matches, p, expected_pairs(p, n, len(items), len(matches)),
                              _direction(matches)))
    return tuple(sorted(pairs, key=lambda c: (c.expected, c.students)))


def _direction(matches: tuple[Match, ...]) -> str:
    ways = {(m.copier, m.source) for m in matches if m.how == "key"}
    if len(ways) == 1:
        copier, source = next(iter(ways))
        return f"{copier} copied {source}"
    return ""
