"""What the class report reads: the assignment, the key and the result records — nothing else.

The report never runs student code (``grader/API.md``, "The class report"). It reads
``HW/assignment.json`` and ``HW/key.json`` (through :func:`grader.assignment.load_assignment`, the
grader's one reader, so a broken folder gets the same message) and ``GRADED/results/<id>.json``
(:func:`grader.results.read_result`). Submitted notebooks are read only as text, for the code
similarity check (:mod:`grader.report.code_similarity`).

Numbers are compared as flat float arrays: a scalar or an angle is an array of one, a vector its
components (:func:`numeric`); booleans, choices and expressions are left out of the numerical
analyses (a choice among three options is shared by chance far too often to prove anything).

Floor 5 of grader/ (views of records, and file formats; grader/API.md).
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from grader.assignment import Assignment, UsageError, load_assignment
from grader.compare import KeyAnswer
from grader.graded_folder import RESULTS, graded_folder
from grader.results import StudentResult, read_result
from problems.answers import Answer

NUMERIC_KINDS = ("scalar", "angle", "vector")
"""Answer kinds whose values the slip and copy analyses compare."""


@dataclass(frozen=True)
class Item:
    """One answer of the assignment (the same for every student; values differ per variant).

    Attributes
    ----------
    variable : str
        The notebook variable, ``q3_beta1``.
    question : int
        Question number (1-based).
    name : str
        The answer's name within its question.
    kind : str
        The answer kind (``problems.answers.KINDS``).
    family : str
        The problem families of the students asked it (:func:`families_label`): one family,
        or the families of a spec's pool that ask an answer of this name.
    """

    variable: str
    question: int
    name: str
    kind: str
    family: str


@dataclass(frozen=True)
class ClassData:
    """One graded class: roster order, records and every student's key.

    Attributes
    ----------
    assignment : grader.assignment.Assignment
        The assignment as the grader reads it.
    items : tuple of Item
        Every answer, in question order (from the first student's key; the generator gives every
        student the same questions and answer names).
    results : dict
        Student id → result record, for the roster students that have one.
    keys : dict
        Student id → {variable: Answer}, every roster student's key.
    """

    assignment: Assignment
    items: tuple[Item, ...]
    results: dict[str, StudentResult]
    keys: dict[str, dict[str, Answer]]

    @property
    def ids(self) -> tuple[str, ...]:
        """Roster ids, in roster order."""
        return self.assignment.ids

    @property
    def graded(self) -> tuple[str, ...]:
        """Ids of the students whose notebook was executed and compared (status ``graded``)."""
        return tuple(s for s in self.ids
                     if s in self.results and self.results[s].status == "graded")

    def answer(self, student_id: str, variable: str):
        """The student's :class:`grader.results.AnswerResult` for ``variable`` (None if absent)."""
        return next((a for a in self.results[student_id].answers if a.variable == variable), None)


def load_class(hw: Path | Assignment, graded: Path | None = None) -> ClassData:
    """Read an assignment and its graded records.

    Parameters
    ----------
    hw : Path or Assignment
        The assignment folder (``eulertop generate``'s output), or the assignment already
        loaded from it (read once).
    graded : Path, optional
        The grading output folder (default ``hw/graded``), holding ``results/``.

    Raises
    ------
    grader.assignment.UsageError
        No assignment, unreadable key, or no result records (grade first).
    """
    a = hw if isinstance(hw, Assignment) else load_assignment(hw)
    folder = graded_folder(a.folder, graded) / RESULTS
    if not folder.is_dir():
        raise UsageError(f"{folder}: no result records here; run 'eulertop grade' first "
                         "(or pass --graded DIR)")
    results = {sid: read_result(folder / f"{sid}.json") for sid in a.ids}
    if not any(results.values()):
        raise UsageError(f"{folder}: no readable result record for any roster student; run "
                         "'eulertop grade' first")
    return class_data(a, results)


def class_data(a: Assignment, results: Mapping[str, StudentResult | None]) -> ClassData:
    """The class from an assignment already loaded and its records (None: no record yet)."""
    present = {sid: r for sid, r in results.items() if r is not None and sid in a.students}
    keys = {sid: {k.variable: k.answer for k in a.expected(sid)} for sid in a.ids}
    return ClassData(a, _items(a), present, keys)


def _items(a: Assignment) -> tuple[Item, ...]:
    """Every answer asked of anyone, in the order of the first student asked it: variants of
    one family may ask for different answers (one student ``F_body``, another ``r_lab``), and
    the families of a pool each their own."""
    first: dict[str, KeyAnswer] = {}
    families: dict[str, dict[str, None]] = {}
    for sid in a.ids:
        asked = {q["question"]: q["family"] for q in a.key["students"][sid]["questions"]}
        for k in a.expected(sid):
            first.setdefault(k.variable, k)
            families.setdefault(k.variable, {})[asked[k.question]] = None
    items = (Item(v, k.question, k.answer.name, k.answer.kind, families_label(families[v]))
             for v, k in first.items())
    return tuple(sorted(items, key=lambda i: i.question))


def families_label(families: Iterable[str]) -> str:
    """How the report names the families behind a question or an answer: the family, or
    ``pool: a, b`` for several (a spec's ``pool``).

    Examples
    --------
    >>> families_label(["sleeping_top"]), families_label(["sleeping_top", "steady_precession"])
    ('sleeping_top', 'pool: sleeping_top, steady_precession')
    """
    names = list(families)
    return names[0] if len(names) == 1 else "pool: " + ", ".join(names)


def question_families(a: Assignment, question: int) -> str:
    """The families question ``question`` draws from (:func:`families_label`): its spec's pool
    as ``assignment.json`` records it, else its one family."""
    recorded = a.manifest.get("questions")
    if recorded is not None:
        return families_label(recorded[question - 1]["pool"])
    return families_label([a.manifest["problems"][question - 1]])


def numeric(value: Any) -> np.ndarray | None:
    """A submitted or key value as a flat float array, or None when it is not numeric.

    Examples
    --------
    >>> numeric(2.5), numeric([1, 2]), numeric("loops"), numeric(True), numeric("NaN")
    (array([2.5]), array([1., 2.]), None, None, None)
    """
    if isinstance(value, bool) or value is None:
        return None
    if isinstance(value, int | float):
        return np.array([float(value)]) if math.isfinite(value) else None
    if isinstance(value, list) and value and all(
            isinstance(v, int | float) and not isinstance(v, bool) for v in value):
        array = np.array(value, dtype=float)
        return array if np.all(np.isfinite(array)) else None
    return None


def tolerance(answer: Answer, key: np.ndarray) -> float:
    """The distance within which a value matches ``key`` under ``answer``'s rule."""
    return answer.atol + answer.rtol * float(np.linalg.norm(key))


def distance(answer: Answer, x: np.ndarray, v: np.ndarray) -> float:
    """The grader's distance between two values of ``answer``'s kind (angles wrapped modulo
    the period when the answer has one; vectors by the Euclidean norm)."""
    d = x - v
    if answer.period is not None:
        half = answer.period / 2
        d = half - np.remainder(half - d, answer.period)
    return float(np.linalg.norm(d))


def close(answer: Answer, x: np.ndarray, v: np.ndarray, factor: float = 1.0) -> bool:
    """``x`` within ``factor`` times ``answer``'s tolerance of ``v`` (same shape required)."""
    return x.shape == v.shape and distance(answer, x, v) <= factor * tolerance(answer, v)


def submitted_values(data: ClassData, item: Item) -> Mapping[str, tuple[Any, Answer, np.ndarray]]:
    """Graded students' numeric submissions for ``item``: id → (AnswerResult, own key Answer,
    value array); students with a non-numeric or missing value are left out."""
    out = {}
    for sid in data.graded:
        a = data.answer(sid, item.variable)
        x = numeric(a.submitted) if a is not None else None
        if x is not None:
            out[sid] = (a, data.keys[sid][item.variable], x)
    return out
