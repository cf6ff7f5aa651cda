"""Common wrong answers: the same slip found across students whose numbers all differ.

Every student has their own variant, so two students making the same slip give different wrong
numbers. What they share is the *relation* between their wrong value and their **own** key.
For each wrong answer the grader did not recognise as a known mistake, this module looks for
that relation (:func:`relation`):

1. a named relation from :data:`RELATIONS` — sign, factor 2, degrees/radians, 2π, π, reciprocal,
   square, supplementary and complementary angles, a swapped or sign-flipped vector component —
   matched within twice the answer's tolerance of the transformed key;
2. another answer of the same question typed in its place (``swapped with q2_p_alpha``);
3. otherwise, when the wrong value is a multiple of the key (a scalar, or a vector parallel to
   it), the ratio; for an angle also the offset. These are grouped when several students share
   them within the answer's tolerance (:func:`cluster`), so an unknown factor — 3/2, 4π —
   becomes visible although no relation in the list names it.

Students sharing a relation on an answer form a :class:`SlipGroup`; groups of at least
:data:`MIN_GROUP` students are reported, largest first, with the formula to add as a known
mistake to the template (``problems.answers.Mistake``). A group holding most of the class on a
question that almost nobody got right points at the key instead (a template bug).

Floor 5 of grader/ (views of records, and file formats; grader/API.md).
"""

from __future__ import annotations

import math
from collections import defaultdict
from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np

from grader.report.classdata import (
    NUMERIC_KINDS,
    ClassData,
    Item,
    close,
    numeric,
    submitted_values,
)
from problems.answers import Answer

MIN_GROUP = 3
"""Fewest students sharing a relation for it to be reported as a common wrong answer."""

CHANCE = 0.05
"""A shared ratio or offset no named relation explains is reported when fewer groups this
large are expected by chance in the whole class (all answers searched)."""

WINDOW = 25
"""The density of ratios around a group is counted over this many group widths."""

MATCH_FACTOR = 2.0
"""A wrong value matches a relation within this many times the answer's tolerance."""

Transform = Callable[[np.ndarray], np.ndarray | None]


def _scalar(f: Callable[[np.ndarray], np.ndarray]) -> Transform:
    return lambda v: f(v) if v.size == 1 else None


def _reciprocal(v: np.ndarray) -> np.ndarray | None:
    return 1 / v if v.size == 1 and v[0] != 0 else None


def _swap(i: int, j: int) -> Transform:
    def f(v: np.ndarray) -> np.ndarray | None:
        if v.size <= max(i, j):
            return None
        w = v.copy()
        w[[i, j]] = w[[j, i]]
        return w
    return f


def _flip(i: int) -> Transform:
    def f(v: np.ndarray) -> np.ndarray | None:
        if v.size <= i:
            return None
        w = v.copy()
        w[i] = -w[i]
        return w
    return f


@dataclass(frozen=True)
class Relation:
    """A named relation between a wrong value and the key.

    Attributes
    ----------
    name : str
        Short id, usable as a ``Mistake`` name.
    formula : str
        The wrong value in terms of the key ``v``, for people and for the template.
    kinds : tuple of str
        Answer kinds it applies to.
    apply : callable
        ``v → wrong value`` (None where it does not apply, e.g. a component of a scalar).
    """

    name: str
    formula: str
    kinds: tuple[str, ...]
    apply: Transform


_ALL, _ANGLE = ("scalar", "angle", "vector"), ("angle",)
RELATIONS: tuple[Relation, ...] = (
    Relation("sign", "-v", _ALL, lambda v: -v),
    Relation("factor_2", "2*v", _ALL, lambda v: 2 * v),
    Relation("half", "v/2", _ALL, lambda v: v / 2),
    Relation("degrees", "v*180/pi", _ALL, lambda v: np.degrees(v)),
    Relation("radians_twice", "v*pi/180", _ALL, lambda v: np.radians(v)),
    Relation("times_2pi", "2*pi*v", _ALL, lambda v: 2 * np.pi * v),
    Relation("over_2pi", "v/(2*pi)", _ALL, lambda v: v / (2 * np.pi)),
    Relation("times_pi", "pi*v", _ALL, lambda v: np.pi * v),
    Relation("over_pi", "v/pi", _ALL, lambda v: v / np.pi),
    Relation("reciprocal", "1/v", ("scalar",), _reciprocal),
    Relation("squared", "v**2", ("scalar",), _scalar(lambda v: v**2)),
    Relation("square_root", "sqrt(|v|)", ("scalar",), _scalar(lambda v: np.sqrt(np.abs(v)))),
    Relation("supplement", "pi - v", _ANGLE, (lambda v: np.pi - v)),
    Relation("complement", "pi/2 - v", _ANGLE, (lambda v: np.pi / 2 - v)),
    Relation("plus_pi", "v + pi", _ANGLE, (lambda v: v + np.pi)),
    Relation("minus_pi", "v - pi", _ANGLE, (lambda v: v - np.pi)),
    Relation("swap_x_y", "v with components 1 and 2 swapped", ("vector",), _swap(0, 1)),
    Relation("swap_x_z", "v with components 1 and 3 swapped", ("vector",), _swap(0, 2)),
    Relation("swap_y_z", "v with components 2 and 3 swapped", ("vector",), _swap(1, 2)),
    Relation("sign_x", "v with component 1 negated", ("vector",), _flip(0)),
    Relation("sign_y", "v with component 2 negated", ("vector",), _flip(1)),
    Relation("sign_z", "v with component 3 negated", ("vector",), _flip(2)),
)
"""The named relations tried, in this order (the first that matches is taken)."""

NICE_RATIOS: tuple[tuple[str, float], ...] = tuple(
    (name, value) for name, value in (
        ("3", 3.0), ("1/3", 1 / 3), ("3/2", 1.5), ("2/3", 2 / 3), ("4", 4.0), ("1/4", 0.25),
        ("√2", math.sqrt(2)), ("1/√2", 1 / math.sqrt(2)), ("4π", 4 * math.pi),
        ("1/(4π)", 1 / (4 * math.pi)), ("π/2", math.pi / 2), ("2/π", 2 / math.pi),
        ("10", 10.0), ("1/10", 0.1), ("1000", 1000.0), ("1/1000", 1e-3), ("60", 60.0),
        ("1/60", 1 / 60), ("-2", -2.0), ("-1/2", -0.5)))
"""Constants a shared ratio or offset is named after when it is close to one (2, π, 180/π …
are named relations already)."""


@dataclass(frozen=True)
class SlipGroup:
    """Students whose wrong answers to one item stand in the same relation to their own keys.

    Attributes
    ----------
    variable : str
        The answer, ``q2_p_gamma``.
    relation : str
        The relation's name (``factor_2``, ``swapped_with_q2_p_alpha``, ``ratio_1.5``,
        ``offset_0.7854``).
    formula : str
        The wrong value in terms of the key ``v`` (for the template's ``Mistake``).
    students : tuple of str
        Who made it, in roster order.
    share : float
        Fraction of the graded students who answered this item with a number.
    examples : tuple of (str, list, list)
        A few ``(student, submitted, own key)``, to check by eye.
    """

    variable: str
    relation: str
    formula: str
    students: tuple[str, ...]
    share: float
    examples: tuple[tuple[str, list, list], ...]


def named_relation(answer: Answer, x: np.ndarray, v: np.ndarray) -> Relation | None:
    """The first of :data:`RELATIONS` relating ``x`` to the key ``v`` of ``answer``."""
    for rel in RELATIONS:
        if answer.kind not in rel.kinds:
            continue
        w = rel.apply(v)
        if w is not None and np.all(np.isfinite(w)) and close(answer, x, w, MATCH_FACTOR):
            return rel
    return None


def swapped_with(data: ClassData, sid: str, item: Item, x: np.ndarray) -> str | None:
    """Another answer of the same question whose own key ``x`` matches (typed in the wrong
    variable), or None."""
    answer = data.keys[sid][item.variable]
    for other in data.items:
        if (other.question != item.question or other.variable == item.variable
                or other.variable not in data.keys[sid]):  # not asked of this variant
            continue
        w = numeric(data.keys[sid][other.variable].value)
        if w is not None and close(answer, x, w, MATCH_FACTOR):
            return other.variable
    return None


def ratio(x: np.ndarray, v: np.ndarray, answer: Answer) -> float | None:
    """``c`` with ``x ≈ c·v`` (least squares; None unless the residual is within the answer's
    tolerance of ``x``, or ``v`` is zero)."""
    vv = float(v @ v)
    if vv == 0:
        return None
    c = float(x @ v) / vv
    residual = float(np.linalg.norm(x - c * v))
    return c if residual <= MATCH_FACTOR * (answer.atol + answer.rtol * np.linalg.norm(x)) \
        else None


def nice_name(value: float, rtol: float) -> str | None:
    """The name of the :data:`NICE_RATIOS` constant within ``rtol`` of ``value``, if any."""
    for name, c in NICE_RATIOS:
        if abs(value - c) <= rtol * abs(c):
            return name
    return None


def cluster(values: Sequence[float], width: float) -> list[list[int]]:
    """Indices of ``values`` in groups spanning at most ``width`` each (sorted, greedy).

    Examples
    --------
    >>> cluster([1.0, 5.0, 1.001, 0.999], 0.002)
    [[3, 0, 2], [1]]
    """
    order = sorted(range(len(values)), key=lambda i: values[i])
    groups: list[list[int]] = []
    for i in order:
        if groups and values[i] - values[groups[-1][0]] <= width:
            groups[-1].append(i)
        else:
            groups.append([i])
    return groups


def chance_groups(n: int, k: int, local: int) -> float:
    """Expected number of groups of ``k`` or more, among ``n`` values, within one window by
    chance, when ``local`` other values lie in the :data:`WINDOW` windows around it:
    ``n · C(n−1, k−1) · q^(k−1)`` with ``q = (local + 1) / (n · WINDOW)`` the local share of
    values per window (each value as the group's lowest, ``k − 1`` others in its window).

    Examples
    --------
    >>> f"{chance_groups(40, 3, 2):.2g}"
    '0.27'
    """
    q = min(1.0, (local + 1) / (n * WINDOW))
    return n * math.comb(n - 1, k - 1) * q ** (k - 1)


def relation(data: ClassData, sid: str, item: Item, x: np.ndarray) -> tuple[str, str] | None:
    """``(name, formula)`` of a named relation or a swapped answer for one wrong value."""
    answer = data.keys[sid][item.variable]
    v = np.asarray(answer.value, dtype=float).ravel()
    if x.shape != v.shape:
        return None
    rel = named_relation(answer, x, v)
    if rel is not None:
        return rel.name, rel.formula
    other = swapped_with(data, sid, item, x)
    if other is not None:
        return f"swapped_with_{other}", f"the key of {other}"
    return None


def _coordinates(how: str, rows) -> list[tuple[float, tuple]]:
    """``(u, (sid, x, v))`` per wrong value: ``u`` = log|ratio| (one sign at a time) or the
    offset, the coordinate in which a shared slip is a narrow group."""
    out = []
    for sid, answer, x, v in rows:
        c = ratio(x, v, answer) if how != "offset" else float((x - v)[0])
        if c is None or (how == "ratio+" and c <= 0) or (how == "ratio-" and c >= 0):
            continue
        out.append((math.log(abs(c)) if how != "offset" else c, (sid, x, v)))
    return out


def _formula(how: str, u: float, rtol: float) -> tuple[str, str]:
    if how == "offset":
        nice = nice_name(u / np.pi, 4 * MATCH_FACTOR * rtol)
        return f"offset_{u:.4g}", f"v + {nice}*pi" if nice else f"v + {u:.6g}"
    c = math.exp(u) * (1 if how == "ratio+" else -1)
    nice = nice_name(c, 4 * MATCH_FACTOR * rtol)
    return f"ratio_{c:.4g}", f"{nice}*v" if nice else f"{c:.6g}*v"


def _unexplained_groups(item: Item, rows, tests: int) -> dict[tuple[str, str], list]:
    """Group the wrong values no named relation explains by a shared ratio (and, for angles,
    a shared offset), keeping groups unlikely by chance: :func:`chance_groups` times the
    number of answers searched (``tests``) at most :data:`CHANCE`."""
    groups: dict[tuple[str, str], list] = {}
    if not rows:
        return groups
    rtol = max(r[1].rtol for r in rows)
    atol = max(r[1].atol for r in rows)
    scale = float(np.median([np.linalg.norm(r[3]) for r in rows]))
    for how in ("ratio+", "ratio-", "offset"):
        if how == "offset" and item.kind != "angle":
            continue
        found = _coordinates(how, rows)
        u = [f[0] for f in found]
        width = 2 * MATCH_FACTOR * (rtol if how != "offset" else atol + rtol * scale)
        for members in cluster(u, width):
            k = len(members)
            centre = float(np.median([u[i] for i in members]))
            local = sum(abs(w - centre) <= WINDOW * width / 2 for w in u) - k
            if k < MIN_GROUP or tests * chance_groups(len(u), k, local) > CHANCE:
                continue
            groups[_formula(how, centre, rtol)] = [found[i][1] for i in members]
    return groups


def slip_groups(data: ClassData) -> tuple[SlipGroup, ...]:
    """Every common wrong answer of the class (module docstring), largest group first."""
    out = []
    for item in data.items:
        if item.kind not in NUMERIC_KINDS:
            continue
        values = submitted_values(data, item)
        named: dict[tuple[str, str], list] = defaultdict(list)
        rest = []
        for sid, (a, answer, x) in values.items():
            if a.verdict.status != "wrong" or a.verdict.mistake:
                continue
            v = np.asarray(answer.value, dtype=float).ravel()
            found = relation(data, sid, item, x)
            if found is None:
                rest.append((sid, answer, x, v))
            else:
                named[found].append((sid, x, v))
        named.update(_unexplained_groups(item, rest, 3 * len(data.items)))
        for (name, formula), members in named.items():
            if len(members) >= MIN_GROUP:
                out.append(_group(data, item, name, formula, members, len(values)))
    return tuple(sorted(out, key=lambda g: (-len(g.students), g.variable, g.relation)))


def _group(data, item, name, formula, members, answered) -> SlipGroup:
    order = {s: i for i, s in enumerate(data.ids)}
    members = sorted(members, key=lambda m: order[m[0]])
    examples = tuple((sid, x.tolist(), v.tolist()) for sid, x, v in members[:3])
    return SlipGroup(item.variable, name, formula, tuple(m[0] for m in members),
                     len(members) / max(answered, 1), examples)
