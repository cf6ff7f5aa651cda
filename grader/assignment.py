"""The assignment a class is graded against (floor 4): ``HW/assignment.json`` and ``HW/key.json``
read once into an :class:`Assignment`, with each student's key derived once.

Floor 4 of grader/ (the unit, what it is graded against, where its records go; grader/API.md).
"""

from __future__ import annotations

import json
from dataclasses import dataclass, field
from functools import cached_property
from pathlib import Path
from typing import Any

from grader.compare import KeyAnswer, key_answers
from problems.answers import WRITTEN, Answer
from problems.generate import ASSIGNMENT, key_hash
from problems.variant import variable_name


class UsageError(Exception):
    """The run cannot start (no assignment, no key, unreadable folder); nothing was written."""


@dataclass(frozen=True)
class Assignment:
    """What grading needs from ``HW``: the roster, each student's public questions, the key."""

    folder: Path
    title: str
    columns: tuple[str, ...]
    rows: tuple[dict, ...]
    questions: tuple[int, ...]
    manifest: dict  # assignment.json
    key: dict       # key.json
    _expected: dict = field(default_factory=dict, init=False, repr=False, compare=False)
    _written: list = field(default_factory=list, init=False, repr=False, compare=False)

    @cached_property
    def ids(self) -> tuple[str, ...]:
        return tuple(r["id"] for r in self.rows)

    @property
    def students(self) -> dict:
        """assignment.json's ``students``: id → {"questions": [public question, ...]}."""
        return self.manifest["students"]

    def expected(self, student_id: str) -> tuple[KeyAnswer, ...]:
        """``student_id``'s key answers (:func:`grader.compare.key_answers`), derived once per
        loaded assignment: the key does not change while it is loaded."""
        if student_id not in self._expected:
            try:
                self._expected[student_id] = tuple(key_answers(self.key, student_id))
            except (KeyError, TypeError, ValueError) as e:  # a key edited by hand, badly
                raise UsageError(f"{self.folder / 'key.json'}: {student_id}'s entry cannot be "
                                 f"read: {e}") from None
        return self._expected[student_id]

    def parameters(self, student_id: str) -> dict[str, Any]:
        """``student_id``'s parameters by notebook variable (``q2_M``), as ``assignment.json``
        records them and their notebook's parameters cell writes them; ``{}`` for a manifest
        without them (or a student it does not hold)."""
        try:
            return {variable_name(q["question"], name): value
                    for q in self.students[student_id]["questions"]
                    for name, value in q.get("params", {}).items()}
        except (KeyError, TypeError, AttributeError):
            return {}

    def verified(self, student_id: str) -> bool:
        """Whether ``student_id``'s key entry is the one its hash names (as ``generate`` and
        ``key set`` write it): its hash recomputed from its questions, not trusted (a hand edit
        leaves the old hash)."""
        entry = self.key["students"].get(student_id)
        try:
            return isinstance(entry, dict) and entry.get("hash") == key_hash(entry["questions"])
        except (KeyError, TypeError, ValueError):
            return False

    def answer_points(self, student_id: str) -> dict[str, float]:
        """``student_id``'s key answers' points by variable, in question order — read from a
        :meth:`verified` entry without building its answers (an expression answer is parsed
        with sympy), else from :meth:`expected`."""
        if student_id in self._expected or not self.verified(student_id):
            return {k.variable: k.answer.points for k in self.expected(student_id)}
        return {variable_name(q["question"], x["name"]): float(x.get("points", 1.0))
                for q in self.key["students"][student_id]["questions"] for x in q["answers"]}

    def written_expected(self, student_id: str) -> tuple[KeyAnswer, ...]:
        """``student_id``'s written answers of :meth:`expected`, building no other answer of a
        :meth:`verified` entry (what reviews need, without parsing an expression answer)."""
        if student_id in self._expected or not self.verified(student_id):
            return tuple(k for k in self.expected(student_id) if k.answer.kind == WRITTEN)
        try:
            return tuple(KeyAnswer(variable_name(q["question"], x["name"]), int(q["question"]),
                                   Answer.from_dict(x))
                         for q in self.key["students"][student_id]["questions"]
                         for x in q["answers"] if x.get("kind") == WRITTEN)
        except (KeyError, TypeError, ValueError) as e:  # as expected() says it
            raise UsageError(f"{self.folder / 'key.json'}: {student_id}'s entry cannot be "
                             f"read: {e}") from None

    def check_key(self) -> None:
        """Every student's key can be read (:class:`UsageError` naming the first that cannot):
        checked before a run writes anything."""
        for student_id in self.ids:
            self.expected(student_id)

    def written(self) -> tuple[str, ...]:
        """The variables of the written answers any student was asked (issue 31), in question
        order, from ``assignment.json``'s public answer specs; found once per loaded
        assignment."""
        if not self._written:
            found = {spec["variable"]: (q["question"], n)
                     for s in self.students.values() for q in s["questions"]
                     for n, spec in enumerate(q["answers"]) if spec.get("kind") == "written"}
            self._written.append(tuple(sorted(found, key=found.__getitem__)))
        return self._written[0]

    def key_hash(self, student_id: str) -> str:
        return self.key["students"][student_id]["hash"]


def _require_file(path: Path, what: str) -> None:
    if not path.is_file():
        raise UsageError(f"{path}: no {what} here (is this an assignment folder written by "
                         "'eulertop generate'?)")


def _read_json(path: Path, what: str) -> dict:
    _require_file(path, what)
    try:
        return json.loads(path.read_text(encoding="utf-8"))
    except (OSError, UnicodeDecodeError, json.JSONDecodeError) as e:
        raise UsageError(f"{path}: cannot read the {what}: {e}") from None


_MANIFEST = "assignment manifest (assignment.json)"


def require_assignment_folder(hw: Path) -> Path:
    """``hw``, a folder holding an assignment manifest; else :class:`UsageError` naming what is
    missing. Checked first by every command on a class, before its graded folder is looked
    for: a mistyped folder is not a class that has not been graded yet."""
    hw = Path(hw)
    if not hw.is_dir():
        raise UsageError(f"{hw}: no such assignment folder")
    _require_file(hw / ASSIGNMENT, _MANIFEST)
    return hw


def load_assignment(hw: Path) -> Assignment:
    """Read ``HW/assignment.json`` and ``HW/key.json``; :class:`UsageError` if unusable."""
    hw = require_assignment_folder(hw)
    manifest = _read_json(hw / ASSIGNMENT, _MANIFEST)
    key = _read_json(hw / "key.json", "answer key (key.json)")
    try:
        rows = tuple(manifest["roster"]["rows"])
        students = manifest["students"]
        absent = [r["id"] for r in rows if r["id"] not in key["students"]
                  or r["id"] not in students]
        questions = tuple(range(1, len(manifest["problems"]) + 1))
        columns = tuple(manifest["roster"]["columns"])
        title = manifest.get("title", hw.name)
    except (KeyError, TypeError) as e:
        raise UsageError(f"{hw}: assignment.json or key.json is not in the generator's "
                         f"layout (no {e})") from None
    if absent:
        raise UsageError(f"{hw}: key.json has no entry for {', '.join(absent)}; regenerate "
                         "the assignment")
    return Assignment(hw, title, columns, rows, questions, manifest, key)
