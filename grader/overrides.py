"""An instructor's overrides of a class's grades, kept in ``HW/graded/overrides.toml`` (issue 26).

One override gives one student's answer (``q3_T_nut``) or their whole total a number of points,
with a reason. They are applied last, to every record a grading run or a rescore writes
(:func:`apply_overrides`), so they survive a resume and ``--force``; each record says which
were applied (``StudentResult.overridden``, with the points they replaced), and so do its
feedback page and ``grades.csv``. ``eulertop override`` adds or removes one.

The file is TOML, written here and read with :mod:`tomllib`::

    [[override]]
    student = "ada"
    answer = "q3_T_nut"          # absent: the student's total
    points = 2.0
    reason = "the statement's g was misprinted"
    by = "instructor"
    at = "2026-11-26T10:00:00+00:00"

Floor 4 of grader/ (the unit, what it is graded against, where its records go; grader/API.md).
"""

from __future__ import annotations

import json
import tomllib
from collections.abc import Iterable
from dataclasses import dataclass, replace
from pathlib import Path

from grader.assignment import Assignment, UsageError
from grader.late import late_entry, submitted_time
from grader.results import AnswerResult, StudentResult
from problems.deadlines import LatePolicy

OVERRIDES = "overrides.toml"
TOTAL = "total"
"""What :attr:`StudentResult.overridden` calls an override of the whole total."""


@dataclass(frozen=True)
class Override:
    """``student``'s ``answer`` (a variable; None: the total) given ``points``, and why."""

    student: str
    answer: str | None
    points: float
    reason: str
    by: str
    at: str

    @property
    def target(self) -> str:
        return self.answer or TOTAL


def read_overrides(out: Path) -> tuple[Override, ...]:
    """The overrides of the output folder ``out`` (none when there is no file);
    :class:`UsageError` naming the file and the entry at fault when it cannot be read."""
    path = Path(out) / OVERRIDES
    if not path.exists():
        return ()
    try:
        document = tomllib.loads(path.read_text(encoding="utf-8"))
    except (OSError, UnicodeDecodeError, tomllib.TOMLDecodeError) as e:
        raise UsageError(f"{path}: cannot read the overrides: {e}") from None
    entries = document.get("override", [])
    if set(document) - {"override"} or not isinstance(entries, list):
        raise UsageError(f"{path}: expected only [[override]] entries")
    found = []
    for n, entry in enumerate(entries, start=1):
        try:
            points = entry["points"]
            if isinstance(points, bool) or not isinstance(points, int | float):
                raise TypeError("points must be a number")
            found.append(Override(str(entry["student"]), entry.get("answer"), float(points),
                                  str(entry["reason"]), str(entry.get("by", "")),
                                  str(entry.get("at", ""))))
        except (KeyError, TypeError) as e:
            raise UsageError(f"{path}: override {n}: {e}") from None
    return tuple(found)


def _toml_string(text: str) -> str:
    # a JSON string is a TOML basic string (the same escapes; non-ASCII kept as UTF-8)
    return json.dumps(text, ensure_ascii=False)


def overrides_toml(overrides: Iterable[Override]) -> str:
    """The text of :data:`OVERRIDES` for ``overrides``."""
    lines = ["# Overrides of grades: written by 'eulertop override', applied last by every",
             "# 'eulertop grade' and 'eulertop rescore'. Each entry is one student's answer",
             "# (or, without 'answer', their total) given 'points', and why.", ""]
    for o in overrides:
        lines.append("[[override]]")
        lines.append(f"student = {_toml_string(o.student)}")
        if o.answer is not None:
            lines.append(f"answer = {_toml_string(o.answer)}")
        lines += [f"points = {o.points!r}", f"reason = {_toml_string(o.reason)}",
                  f"by = {_toml_string(o.by)}", f"at = {_toml_string(o.at)}", ""]
    return "\n".join(lines)


def without_overrides(result: StudentResult) -> StudentResult:
    """``result`` as it was before any override and late penalty: each overridden answer's
    points back to what the comparison gave, the total their sum."""
    if not result.overridden and not result.late:
        return result
    was = {k: v["was"] for k, v in result.overridden.items()}
    answers = tuple(_with_points(a, was[a.variable]) if a.variable in was else a
                    for a in result.answers)
    return replace(result, answers=answers, points=sum(a.verdict.points for a in answers),
                   overridden={}, late={})


def _with_points(answer: AnswerResult, points: float) -> AnswerResult:
    return replace(answer, verdict=replace(answer.verdict, points=points))


def apply_overrides(result: StudentResult, overrides: Iterable[Override],
                    late: LatePolicy | None = None) -> StudentResult:
    """``result`` with the overrides of its student and the late policy ``late`` applied, in
    this order: the overrides of answers, the late penalty (:mod:`grader.late`), the override
    of the total — each noted in the record (``overridden``, ``late``); any applied before are
    taken back first. The overrides are those :func:`check_overrides` accepted for the key
    ``result`` was compared with."""
    result = without_overrides(result)
    mine = [o for o in overrides if o.student == result.student_id]
    answers = {a.variable: a for a in result.answers}
    overridden = {}
    for o in (o for o in mine if o.answer is not None):
        overridden[o.answer] = _note(o, answers[o.answer].verdict.points)
        answers[o.answer] = _with_points(answers[o.answer], o.points)
    kept = tuple(answers[a.variable] for a in result.answers)
    points = sum(a.verdict.points for a in kept)
    entry, points = _penalised(result, late, points)
    for o in (o for o in mine if o.answer is None):
        overridden[TOTAL] = _note(o, points)
        points = o.points
    return replace(result, answers=kept, points=points, overridden=overridden, late=entry)


def _penalised(result: StudentResult, late: LatePolicy | None,
               earned: float) -> tuple[dict, float]:
    """The record's ``late`` entry and its points after the penalty (none without a policy, a
    known time, or a graded notebook)."""
    when = submitted_time(result.submitted) if late is not None else None
    if when is None or result.status != "graded":
        return {}, earned
    entry, taken = late_entry(late, result.student_id, when, earned, result.max_points)
    return entry, earned - taken


def check_overrides(a: Assignment, overrides: Iterable[Override],
                    source: str | None = OVERRIDES) -> None:
    """Each override names a student of ``a``'s roster and an answer of their key, with points
    within its own (or the key's total): else :class:`UsageError` naming the entry (``source``:
    the file's ``override N``; None: the override itself) — the one check of overrides, made
    before anything is written, with the key they will be applied with, so that no override
    can stop a command half-way."""
    for n, o in enumerate(overrides, start=1):
        where = f"{source}: override {n}" if source else f"override of {o.student}'s {o.target}"
        if o.student not in a.ids:
            raise UsageError(f"{where}: no student {o.student!r} in the assignment's roster")
        expected = a.answer_points(o.student)
        if o.answer is not None and o.answer not in expected:
            raise UsageError(f"{where}: {o.student} has no such answer {o.answer!r} in the "
                             f"key ({', '.join(expected)})")
        most = sum(expected.values()) if o.answer is None else expected[o.answer]
        if not 0.0 <= o.points <= most:
            raise UsageError(f"{where}: {o.points:g} points for {o.student}'s {o.target} is "
                             f"outside 0…{most:g}" + (_take_back(o) if source else ""))


def _take_back(o: Override) -> str:
    target = f"{o.student} {o.answer}" if o.answer else o.student
    return f" (change it, or take it back: 'eulertop override HW {target} --remove')"


def _note(o: Override, was: float) -> dict:
    return {"points": o.points, "was": was, "reason": o.reason, "by": o.by, "at": o.at}
