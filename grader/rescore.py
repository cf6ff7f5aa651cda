"""``eulertop rescore``: every verdict again from the answers stored in the records and the key as
it is now, without starting a kernel (issue 26).

What a student submitted is in their record (``results/<id>.json``: each answer's value as the
grader extracted it), so a changed key — a tolerance that was too tight, points moved, an
accepted alternative, a solver fix (``eulertop key set``, ``eulertop rekey``) — needs no
notebook to run again: each record is compared again (:func:`rescored`), follow-through
credit and the instructor's overrides applied last, as a grading run applies them; then the
gradebook, the answers table, every feedback page and the class report are rebuilt from the
records (:mod:`grader.publish`), and one line goes to the audit trail. What changed is
returned (and printed by the command): student, answer, points before → after, and why.

A record that is not ``graded`` (missing, or a notebook that could not be run) has no answers
to compare: its answers are all missing against the new key, its points and its message as
they were. An answer the key holds but the record does not (a key that gained an answer) reads
as unset: only a ``--force`` regrade can read it from the notebook.

Non-finite numbers: a record keeps NaN and infinities as the strings ``"NaN"``,
``"Infinity"``, ``"-Infinity"`` (strict JSON); they are read back as numbers where the answer
is numeric (scalar, angle, vector), as they were extracted. (A student who typed one of those
strings for a numeric answer is read as having given the number: invalid either way.)

Floor 7 of grader/ (the class run; grader/API.md).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from grader.assignment import Assignment, load_assignment
from grader.audit import record_event
from grader.compare import compare
from grader.follow_through import FollowThrough
from grader.grade_one import now
from grader.graded_folder import RESULTS, graded_folder, run_lock
from grader.overrides import TOTAL, apply_overrides, read_overrides, without_overrides
from grader.publish import class_report, publish_record, rebuild, report_notebooks
from grader.results import StudentResult, non_finite_read, read_result

NUMERIC = ("scalar", "angle", "vector")


@dataclass(frozen=True)
class Change:
    """One student's points that a rescore changes: an answer's (``answer`` its variable) or
    the total (``answer`` is ``"total"``), before and after, and why."""

    student: str
    answer: str
    before: float
    after: float
    why: str

    def as_dict(self) -> dict:
        return {"student": self.student, "answer": self.answer, "before": self.before,
                "after": self.after, "why": self.why}


@dataclass(frozen=True)
class Rescore:
    """What a rescore did (or, with ``dry_run``, would do)."""

    changes: tuple[Change, ...]
    rescored: tuple[str, ...]  # the students with a record
    unchanged: int  # of them, how many kept every point
    dry_run: bool


def rescored(a: Assignment, old: StudentResult,
             follow: FollowThrough | None = None) -> StudentResult:
    """``old`` compared again with ``a``'s key (the module docstring's rules), before
    follow-through credit (``follow``) and overrides."""
    sid = old.student_id
    expected = a.expected(sid)
    if old.status == "graded":
        kinds = {k.variable: k.answer.kind for k in expected}
        extracted = {x.variable: non_finite_read(x.submitted) if kinds.get(x.variable) in NUMERIC
                     else x.submitted for x in old.answers}
        for k in expected:
            extracted.setdefault(k.variable, None)
        answers = compare(expected, extracted)
    else:
        answers = compare(expected, None)
    result = StudentResult(
        student_id=sid, status=old.status, message=old.message, answers=answers,
        points=sum(x.verdict.points for x in answers) if old.status == "graded" else 0.0,
        max_points=sum(k.answer.points for k in expected),
        submission_sha256=old.submission_sha256, key_sha256=a.key_hash(sid),
        execution=old.execution, sandboxed=old.sandboxed, graded_at=now())
    return result if follow is None else follow.apply(result, expected)


def changes_between(old: StudentResult, new: StudentResult, why: str) -> list[Change]:
    """Every answer whose points differ between the two records, then the total's."""
    before = {x.variable: x.verdict.points for x in old.answers}
    found = []
    for x in new.answers:
        was = before.get(x.variable, 0.0)
        if x.verdict.points != was:
            note = new.overridden.get(x.variable, {}).get("reason")
            found.append(Change(old.student_id, x.variable, was, x.verdict.points,
                                f"overridden: {note}" if note else why))
    if new.points != old.points:
        note = new.overridden.get(TOTAL, {}).get("reason")
        found.append(Change(old.student_id, TOTAL, old.points, new.points,
                            f"overridden: {note}" if note else why))
    return found


def rescore(hw: Path | Assignment, out: Path | None = None, *, dry_run: bool = False,
            reveal: bool = False, why: str = "rescore", event: str = "rescore",
            **details: Any) -> Rescore:
    """Rescore a graded class (module docstring): ``HW`` (or its loaded assignment), its
    output folder ``out`` (default ``HW/graded``). ``dry_run``: compute and return the
    changes, write nothing. ``why`` is what each change says; ``event`` names the audit
    trail's line and ``details`` go into it (a key change passes its own).

    Raises
    ------
    grader.assignment.UsageError
        No assignment, no records, an unreadable overrides file, or another run holding the
        output folder (:class:`grader.graded_folder.RunInProgress`).
    """
    from grader.assignment import UsageError

    a = hw if isinstance(hw, Assignment) else load_assignment(hw)
    out = graded_folder(a.folder, out)
    if not (out / RESULTS).is_dir():
        raise UsageError(f"{out / RESULTS}: no result records here; run 'eulertop grade' "
                         "first (or pass --out DIR)")
    with run_lock(out):
        overrides = read_overrides(out)
        follow = FollowThrough.of(a)
        try:
            report, new = _rescored_class(a, out, overrides, follow, why, dry_run)
        finally:
            if follow is not None:
                follow.close()  # its worker, if one was started
        if dry_run:
            return report
        done = report.rescored
        for sid in done:
            publish_record(a, out, new[sid], reveal)
        rebuild(a, out, new, reveal, published=set(done))
        class_report(a, out, new, report_notebooks(out))
        record_event(out, event, (c.as_dict() for c in report.changes), why=why,
                     students=len(done), unchanged=report.unchanged, **details)
    return report


def _rescored_class(a: Assignment, out: Path, overrides: Sequence[Any],
                    follow: FollowThrough | None, why: str,
                    dry_run: bool) -> tuple[Rescore, dict[str, StudentResult | None]]:
    """Every record of ``out`` rescored (nothing written): the report, and the new records."""
    old = {sid: read_result(out / RESULTS / f"{sid}.json") for sid in a.ids}
    new: dict[str, StudentResult | None] = {}
    changes: list[Change] = []
    for sid, record in old.items():
        if record is None:
            new[sid] = None
            continue
        result = apply_overrides(rescored(a, without_overrides(record), follow), overrides)
        new[sid] = result
        changes += changes_between(record, result, why)
    done = tuple(sid for sid, r in old.items() if r is not None)
    touched = {c.student for c in changes}
    return Rescore(tuple(changes), done, len(done) - len(touched), dry_run), new


def change_lines(changes: Sequence[Change], limit: int | None = None) -> list[str]:
    """The changes as lines for a person: ``ada  q3_T_nut  0 → 2  (why)``."""
    from grader.gradebook import number

    shown = list(changes)[:limit] if limit else list(changes)
    width = max((len(c.student) for c in shown), default=0)
    answer = max((len(c.answer) for c in shown), default=0)
    lines = [f"  {c.student:<{width}}  {c.answer:<{answer}}  {number(c.before)} → "
             f"{number(c.after)}  ({c.why})" for c in shown]
    if limit and len(changes) > limit:
        lines.append(f"  … and {len(changes) - limit} more")
    return lines


def students_changed(changes: Sequence[Change]) -> Mapping[str, float]:
    """Each student whose total changed: the change in points."""
    return {c.student: c.after - c.before for c in changes if c.answer == TOTAL}
