"""Changes to an assignment's key after grading (issue 26): ``eulertop key set`` and ``eulertop
rekey``.

:func:`set_answer` changes one answer's tolerances, points or accepted alternatives, for every
student (``q3_T_nut``) or for one (``ada:q3_T_nut``); :func:`rekeyed` recomputes every
student's key from the parameters ``assignment.json`` recorded, with today's families and
solver (:func:`problems.generate.recorded_variants`), keeping what was set by hand (tolerances,
points, accepted values) — a solver fix reaches the key, an instructor's decisions stay. Both
return the new key and what changed, and touch no file; :func:`stage_key` stages it (mode 0600)
in the transaction of the rescore (:mod:`grader.rescore`) that carries the change to every
record, keeping the old one beside it.

Floor 4 of grader/ (the unit, what it is graded against, where its records go; grader/API.md).
"""

from __future__ import annotations

import copy
import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, replace
from datetime import UTC, datetime
from pathlib import Path
from typing import Any

from grader.assignment import Assignment, UsageError
from grader.plain_text import value_text
from grader.transaction import Transaction
from problems.answers import Answer
from problems.generate import json_text, key_hash
from solver.parameters import ParameterError

KEPT_BY_HAND = ("rtol", "atol", "points", "accepted", "rubric")
"""What :func:`rekeyed` keeps from the current key: the decisions an instructor makes."""


@dataclass(frozen=True)
class KeyChange:
    """One field of one student's answer, before and after."""

    student: str
    variable: str
    field: str
    before: Any
    after: Any

    def as_dict(self) -> dict:
        return {"student": self.student, "answer": self.variable, "field": self.field,
                "before": self.before, "after": self.after}

    def line(self, width: int = 0) -> str:
        """``ada  q3_T_nut  rtol: 0.001 → 0.005``, the student's id padded to ``width``."""
        return (f"{self.student:<{width}}  {self.variable}  {self.field}: "
                f"{value_text(self.before)} → {value_text(self.after)}")


def _answers(entry: Mapping) -> dict[str, dict]:
    """A student's key entry's answer dicts by variable (``q3_T_nut``)."""
    return {f"q{q['question']}_{a['name']}": a for q in entry["questions"]
            for a in q["answers"]}


def _rehash(entry: dict) -> None:
    entry["hash"] = key_hash(entry["questions"])


def _rebuilt(student: str, variable: str, answer: dict) -> dict:
    """``answer`` (a key file's dict, changed) read as an :class:`Answer` — its known mistakes
    that the answer would now grade right left out (:func:`problems.settings.still_wrong`) —
    and written back; :class:`UsageError` naming the student and the answer if it cannot be."""
    from problems.answers import Mistake
    from problems.settings import still_wrong

    try:
        bare = Answer.from_dict({**answer, "mistakes": []})
        mistakes = tuple(Mistake(**m) for m in answer["mistakes"])
        return replace(bare, mistakes=still_wrong(bare, mistakes)).to_dict()
    except (ParameterError, TypeError, ValueError) as e:
        raise UsageError(f"{student}'s {variable}: {e}") from None


def set_answer(a: Assignment, target: str, *, rtol: float | None = None,
               atol: float | None = None, points: float | None = None,
               accept: Sequence[Any] = (), rubric: Mapping[int, float] | None = None,
               ) -> tuple[dict, list[KeyChange]]:
    """``a``'s key with answer ``target`` (``q3_T_nut``, or ``ada:q3_T_nut`` for one student)
    changed: its tolerances, points, and ``accept`` added to its accepted values (each read as
    the answer's kind, as its key is). A written answer's ``rubric`` items (numbered from 1)
    given new points, its points their sum; its ``points`` changed, its items scaled with
    them. The new key (a copy) and the changes.

    Raises
    ------
    grader.assignment.UsageError
        No student has such an answer, no change was asked for, or a value the answer cannot
        take (the message names the student, the answer and the field).
    """
    student, _, variable = target.rpartition(":")
    asked = {"rtol": rtol, "atol": atol, "points": points}
    if all(v is None for v in asked.values()) and not accept and not rubric:
        raise UsageError(f"key set {target}: nothing to change (give --rtol, --atol, --points, "
                         "--accept or --rubric)")
    if student and student not in a.key["students"]:
        raise UsageError(f"key set {target}: no student {student!r} in the key")
    key = copy.deepcopy(a.key)
    changes = []
    for sid in [student] if student else a.ids:
        entry = key["students"][sid]
        answer = _answers(entry).get(variable)
        if answer is None:
            continue
        if answer["kind"] == "written":
            changes += _written_set(sid, variable, answer, points, rubric or {})
            asked = {**asked, "points": None}
        elif rubric:
            raise UsageError(f"key set {target}: {variable} is no written answer: it has no "
                             "rubric")
        for field, value in asked.items():
            if value is not None and answer[field] != float(value):
                changes.append(KeyChange(sid, variable, field, answer[field], float(value)))
                answer[field] = float(value)
        if accept:
            before = list(answer.get("accepted", []))
            after = before + [v for v in accept if v not in before]
            if after != before:
                changes.append(KeyChange(sid, variable, "accepted", before, after))
                answer["accepted"] = after
        changed = _rebuilt(sid, variable, answer)
        dropped = [m["name"] for m in answer["mistakes"]
                   if m["name"] not in {m2["name"] for m2 in changed["mistakes"]}]
        if dropped:  # a widened tolerance now accepts them: their feedback would never show
            changes.append(KeyChange(sid, variable, "mistakes dropped", [], dropped))
        answer.clear()
        answer.update(changed)
        _rehash(entry)
    if not any(variable in _answers(key["students"][s]) for s in key["students"]):
        known = sorted({v for s in a.ids for v in _answers(a.key["students"][s])})
        raise UsageError(f"key set {target}: no answer {variable!r} in the key; its answers: "
                         f"{', '.join(known)}")
    return key, changes


def _written_set(student: str, variable: str, answer: dict, points: float | None,
                 rubric: Mapping[int, float]) -> list[KeyChange]:
    """A written answer's rubric items given new points (numbered from 1) and its points their
    sum, or its points changed and its items scaled with them, in place; the changes."""
    items = answer["rubric"]
    changes = []
    if points is not None and not rubric and float(points) != answer["points"]:
        scale = float(points) / answer["points"] if answer["points"] else 0.0
        rubric = {n: item["points"] * scale for n, item in enumerate(items, start=1)}
    for n, value in sorted(rubric.items()):
        if not 1 <= n <= len(items):
            raise UsageError(f"{student}'s {variable}: no rubric item {n} (it has 1…{len(items)})")
        if items[n - 1]["points"] != float(value):
            changes.append(KeyChange(student, variable, f"rubric item {n}",
                                     items[n - 1]["points"], float(value)))
            items[n - 1]["points"] = float(value)
    total = sum(item["points"] for item in items)
    if total != answer["points"]:
        changes.append(KeyChange(student, variable, "points", answer["points"], total))
        answer["points"] = total
    return changes


def rekeyed(a: Assignment, families: Mapping[str, Any]) -> tuple[dict, list[KeyChange]]:
    """``a``'s key recomputed from the parameters it recorded (module docstring); the new key
    and each value or known mistake that changed.

    Raises
    ------
    grader.assignment.UsageError
        The assignment recorded no parameters (generated before they were), or a family of it
        is not to be had here.
    """
    from problems.generate import GenerateError, key_entry, recorded_questions, recorded_variants

    manifest = a.manifest
    try:
        families, _ = recorded_questions(manifest, a.folder, families)
        fresh = {sid: key_entry(recorded_variants(manifest, families, sid)) for sid in a.ids}
    except GenerateError as e:
        raise UsageError(f"{a.folder}: cannot recompute the key: "
                         f"{str(e).removeprefix('--reroll: ')}") from None
    key = copy.deepcopy(a.key)
    changes = []
    for sid in a.ids:
        old, new = _answers(key["students"][sid]), _answers(fresh[sid])
        for variable, answer in new.items():
            kept = old.get(variable, {})
            for field in KEPT_BY_HAND:
                if field in kept:
                    answer[field] = kept[field]
            for field in ("value", "mistakes"):
                if kept and not _same(kept.get(field), answer.get(field)):
                    changes.append(KeyChange(sid, variable, field, kept.get(field),
                                             answer.get(field)))
            if not kept:
                changes.append(KeyChange(sid, variable, "value", None, answer["value"]))
        for variable in old.keys() - new.keys():
            changes.append(KeyChange(sid, variable, "value", old[variable]["value"], None))
        entry = fresh[sid]
        _rehash(entry)
        key["students"][sid] = entry
    return key, changes


def _same(x: Any, y: Any) -> bool:
    """Equal plain JSON, floats to the last bit (NaN equal to NaN)."""
    if isinstance(x, float) and isinstance(y, float):
        return x == y or (math.isnan(x) and math.isnan(y))
    if isinstance(x, list) and isinstance(y, list):
        return len(x) == len(y) and all(_same(p, q) for p, q in zip(x, y, strict=True))
    if isinstance(x, dict) and isinstance(y, dict):
        return x.keys() == y.keys() and all(_same(x[k], y[k]) for k in x)
    return x == y


def stage_key(tx: Transaction, hw: Path, key: Mapping) -> Path:
    """Stage ``HW/key.json`` (mode 0600) to hold ``key``, the old one kept beside it as
    ``key.json.<UTC time>`` (0600 too); the old one's path."""
    path = Path(hw) / "key.json"
    stamp = datetime.now(UTC).strftime("%Y%m%dT%H%M%SZ")
    old = path.with_name(f"key.json.{stamp}")
    n = 1
    while old.exists():
        n += 1
        old = path.with_name(f"key.json.{stamp}-{n}")
    tx.write(old, path.read_bytes())
    tx.write(path, json_text(key))  # as the generator writes it
    return old
