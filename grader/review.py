"""The review desk's Python API (issue 31): what ``eulertop review`` (a web app above
``grader/``) calls to score written answers by rubric, one question across all students, with
several TAs at once.

A :class:`ReviewSession` loads a graded class once — the assignment, the overrides, the reviews
and every record — and serves it from memory: the written answers of one question
(:meth:`~ReviewSession.written`), each under an opaque id that is the same in every session
(the student's id is there too, for the page's "show names" toggle, off by default); the
answers the grader flagged for a look (:meth:`~ReviewSession.flagged`); progress per question;
reusable comments. Each reading first reads what another command changed, when the class is
free (:meth:`~ReviewSession.refresh`; it never waits). Every change — a review
(:meth:`~ReviewSession.submit`), an override, a rubric item's points, a reusable comment — is
a change of the class like any command's: under the class's lock
(:func:`grader.transaction.class_lock`, waiting :data:`WAIT` seconds at most), from the class
as it is on disk then, committed as one transaction with its line of the audit trail
(:func:`grader.rescore.amended_class`). A review rescores its one student (their record
and page, ``grades.csv``, ``answers.csv``, ``reviews.json``, the trail; not the class report,
rebuilt once by :meth:`~ReviewSession.close`).

What changed on disk since the session read it — another TA's review, an ``eulertop
override``, a key change, a grading run — is found under the lock before each change: the
key, the manifest, the overrides and the reviews by their files' identity (device, inode,
size, modification time: every commit renames a new file into place), the records by the
audit trail's new lines. A line of a review or an override names its one student, whose record
alone is read again; any other line (a grading run, a rescore, a key change) reads every record
again. So two sessions that submit at once both land, one after the other, each attributed
(``by``: the session's grader), and neither undoes the other.

Ids: ``sha256("eulertop-review", seed, answer, student)``, 16 hex digits — stable, and not the
student's id (anonymity on the page is against bias, not a secret: the session knows who is
who).

Floor 7 of grader/ (the class run: beside :mod:`grader.rescore`; grader/API.md).
"""

from __future__ import annotations

import hashlib
import json
import math
import os
import threading
from collections.abc import Iterable, Sequence
from dataclasses import replace
from pathlib import Path
from typing import Any

from grader.assignment import (
    Assignment,
    UsageError,
    load_assignment,
    require_assignment_folder,
)
from grader.audit import AUDIT, who
from grader.follow_through import FollowThrough
from grader.grade_one import now
from grader.graded_folder import RESULTS, RunInProgress, graded_folder
from grader.overrides import OVERRIDES, read_overrides
from grader.publish import RowCache, records, report_notebooks, stage_report
from grader.rescore import Amendment, Loaded, amended_class, override_amendment
from grader.results import StudentResult, read_result
from grader.reviews import (
    MAX_COMMENT,
    REVIEWS,
    Review,
    Reviews,
    read_reviews,
    reviews_json,
    written_key,
)
from grader.transaction import Transaction, class_lock
from grader.written import text_sha256, written_text
from problems.answers import WRITTEN, grade

WAIT = 10.0
"""Seconds a change waits for another command holding the class before it is refused."""

PER_STUDENT = ("review", "override", "override removed", "comment")
"""Trail events whose line names the one student whose record they changed (or none)."""


class ReviewError(UsageError):
    """A request the desk refuses (an unknown id, a rubric item the answer has not, a class
    another command holds too long); the message is for the person."""


def answer_id(seed: Any, variable: str, student: str) -> str:
    """The opaque, stable id of ``student``'s ``variable`` (module docstring)."""
    text = json.dumps(["eulertop-review", seed, variable, student], ensure_ascii=False)
    return hashlib.sha256(text.encode("utf-8", "surrogatepass")).hexdigest()[:16]


def _stamp(path: Path) -> tuple | None:
    """A file's identity and state: (device, inode, size, modification time), None if none."""
    try:
        st = os.stat(path)
    except FileNotFoundError:
        return None
    return st.st_dev, st.st_ino, st.st_size, st.st_mtime_ns


class ReviewSession:
    """A graded class loaded for review (module docstring).

    Parameters
    ----------
    hw : Path
        The assignment folder.
    out : Path, optional
        The grading output folder (default ``HW/graded``).
    grader : str, optional
        Who reviews: recorded as each review's and override's ``by`` (default: the operating
        system's user).
    reveal : bool
        Feedback pages rewritten with the student's key values (as ``eulertop grade
        --reveal``).
    wait : float
        Seconds each change waits for another command holding the class.

    Raises
    ------
    grader.assignment.UsageError
        No assignment, no records, an unreadable overrides or reviews file.
    """

    def __init__(self, hw: Path, out: Path | None = None, *, grader: str | None = None,
                 reveal: bool = False, wait: float = WAIT) -> None:
        self.hw = require_assignment_folder(hw)
        self.out = graded_folder(hw, out)
        if not (self.out / RESULTS).is_dir():
            raise ReviewError(f"{self.out / RESULTS}: no result records here; run 'eulertop "
                              "grade' first")
        self.grader, self.reveal, self.wait = grader or who(), reveal, wait
        self.changed = False  # something was committed: close() rebuilds the report
        self._mutex = threading.RLock()  # one change at a time within this session
        self._follow: FollowThrough | None = None
        self._rows = RowCache()  # grades.csv's and answers.csv's rows of the records held
        with self._locked():
            self._load()

    # -- loading, and what changed on disk

    def _locked(self):
        return class_lock(self.out, self.hw, command=f"eulertop review ({self.grader})",
                          wait=self.wait)

    def _load(self) -> None:
        """Everything read again (under the lock)."""
        if self._follow is not None:
            self._follow.close()
        self.a: Assignment = load_assignment(self.hw)
        self.overrides = read_overrides(self.out)
        self.reviews: Reviews = read_reviews(self.out)
        self.records: dict[str, StudentResult | None] = records(self.a, self.out)
        self._follow = FollowThrough.of(self.a)
        self._rows.fill(self.a, self.records)
        self._index()
        self._seen = self._disk()

    def _index(self) -> None:
        """The ids of every written answer of the class, and what each stands for."""
        seed = self.a.manifest.get("seed")
        self._ids: dict[str, tuple[str, str]] = {}
        self._by_answer: dict[tuple[str, str], str] = {}
        for variable in self.a.written():
            for sid in self.a.ids:
                if written_key(self.a, sid, variable) is not None:
                    key = answer_id(seed, variable, sid)
                    self._ids[key] = (sid, variable)
                    self._by_answer[(sid, variable)] = key

    def _disk(self) -> dict[str, Any]:
        """What the session knows of the files a change elsewhere rewrites."""
        return {"key": _stamp(self.hw / "key.json"),
                "manifest": _stamp(self.hw / "assignment.json"),
                "overrides": _stamp(self.out / OVERRIDES),
                "reviews": _stamp(self.out / REVIEWS),
                "trail": (_stamp(self.out / AUDIT) or (0, 0, 0, 0))[2]}

    def _refresh(self) -> None:
        """What another command changed since the session read the class, read again (under
        the lock; module docstring)."""
        now_on_disk = self._disk()
        seen, self._seen = self._seen, now_on_disk
        if now_on_disk == seen:
            return
        if (now_on_disk["key"], now_on_disk["manifest"]) != (seen["key"], seen["manifest"]):
            self._load()
            return
        if now_on_disk["overrides"] != seen["overrides"]:
            self.overrides = read_overrides(self.out)
        if now_on_disk["reviews"] != seen["reviews"]:
            self.reviews = read_reviews(self.out)
        students = self._trail_students(seen["trail"])
        if students is None:
            self.records = records(self.a, self.out)
        for sid in students or ():
            if sid in self.records:
                self.records[sid] = read_result(self.out / RESULTS / f"{sid}.json")

    def _trail_students(self, offset: int) -> set[str] | None:
        """The students whose records the trail's lines after ``offset`` changed; None when a
        line may have changed anyone's."""
        try:
            with open(self.out / AUDIT, "rb") as f:
                f.seek(offset)
                tail = f.read()
        except FileNotFoundError:
            return set()
        students: set[str] = set()
        for line in tail.decode("utf-8", "replace").splitlines():
            try:
                entry = json.loads(line)
            except ValueError:
                return None
            if entry.get("event") not in PER_STUDENT:
                return None
            if entry.get("student"):
                students.add(entry["student"])
        return students

    def refresh(self) -> None:
        """Read what another command changed since (module docstring), if the class is free
        now; else keep what the session holds (a reading never waits for a grading run)."""
        with self._mutex:
            try:
                with class_lock(self.out, self.hw, command=f"eulertop review ({self.grader})",
                                wait=0.0):
                    self._refresh()
            except RunInProgress:
                pass

    def _commit(self, amendment: Amendment, command: str) -> None:
        """``amendment`` committed from the class as the session holds it (under the lock),
        and the session's state moved on with it."""
        state = Loaded(self.hw, self.out, self.a, self.overrides, self.reviews, self.records)
        _, self.records = amended_class(state, amendment, reveal=self.reveal, command=command,
                                        follow=self._follow, rows=self._rows)
        if amendment.key is not None:
            self.a = replace(self.a, key=amendment.key)
        if amendment.overrides is not None:
            self.overrides = tuple(amendment.overrides)
        if amendment.reviews is not None:
            self.reviews = amendment.reviews
        self.changed = True
        self._seen = self._disk()

    # -- reading

    def questions(self) -> list[dict]:
        """The written questions: ``{"question": variable, "number", "prompt", "points",
        "rubric": [{"item", "points"}], "answers": how many students have it}``, in question
        order (the first student's key that has it gives its prompt and rubric)."""
        with self._mutex:
            self.refresh()
            found = []
            for variable in self.a.written():
                sids = [s for (s, v) in self._by_answer if v == variable]
                if not sids:
                    continue
                key = written_key(self.a, sids[0], variable)
                found.append({"question": variable, "number": key.question,
                              "prompt": key.answer.value, "points": key.answer.points,
                              "rubric": [r.to_dict() for r in key.answer.rubric],
                              "answers": len(sids)})
            return found

    def written(self, question: str) -> list[dict]:
        """Every answer to the written ``question`` (its variable, ``q5_veff_minimum``), in
        the order of their ids (not the roster's): ``{"id", "text", "review", "student",
        "status", "points", "max", "attachments"}`` — ``review`` None where there is none,
        else ``{"rubric", "adjust", "comment", "by", "at", "stale"}`` (stale: of other text
        than the student's now). ReviewError for a question the class has not."""
        with self._mutex:
            self.refresh()
            if question not in self.a.written():
                raise ReviewError(f"no written question {question!r}; the class has "
                                  f"{', '.join(self.a.written()) or 'none'}")
            ids = sorted(i for i, (_, v) in self._ids.items() if v == question)
            return [self._answer(i) for i in ids]

    def _answer(self, answer: str) -> dict:
        sid, variable = self._ids[answer]
        record = self.records.get(sid)
        found = next((a for a in record.answers if a.variable == variable), None) \
            if record is not None else None
        value = found.submitted if found is not None else None
        attachments = value.get("attachments", {}) if isinstance(value, dict) else {}
        return {"id": answer, "text": written_text(value), "review": self._review(sid, variable),
                "student": sid, "status": found.verdict.status if found else "missing",
                "points": found.verdict.points if found else 0.0,
                "max": found.verdict.max_points if found else 0.0,
                "attachments": sorted(attachments)}

    def _review(self, sid: str, variable: str) -> dict | None:
        review = self.reviews.of(sid, variable)
        if review is None:
            return None
        record = self.records.get(sid)
        found = next((a for a in record.answers if a.variable == variable), None) \
            if record is not None else None
        current = text_sha256(found.submitted) if found is not None else ""
        return {"rubric": list(review.rubric), "adjust": review.adjust,
                "comment": review.comment, "by": review.by, "at": review.at,
                "stale": review.text_sha256 != current}

    def answer(self, answer: str) -> dict:
        """One answer as :meth:`written` lists it; ReviewError for an unknown id."""
        with self._mutex:
            self.refresh()
            self._known(answer)
            return self._answer(answer)

    def html(self, answer: str) -> str:
        """What the student wrote, as the feedback page shows it
        (:func:`grader.statement_html.written_html`: safe HTML, formulas as MathML, kept
        images as ``data:`` URIs)."""
        from grader.statement_html import written_html

        with self._mutex:
            sid, variable = self._known(answer)
            record = self.records.get(sid)
            found = next((a for a in record.answers if a.variable == variable), None) \
                if record is not None else None
            return written_html(found.submitted if found is not None else None)

    def _known(self, answer: str) -> tuple[str, str]:
        if answer not in self._ids:
            raise ReviewError(f"no written answer with id {answer!r}")
        return self._ids[answer]

    def progress(self) -> dict[str, dict]:
        """Per written question: ``{"answers", "written", "reviewed", "pending", "stale"}``
        (stale: pending though reviewed, the text having changed since)."""
        with self._mutex:
            self.refresh()
            found = {}
            for variable in self.a.written():
                rows = [self._answer(i) for i, (_, v) in self._ids.items() if v == variable]
                found[variable] = {
                    "answers": len(rows),
                    "written": sum(r["status"] in ("pending", "reviewed") for r in rows),
                    "reviewed": sum(r["status"] == "reviewed" for r in rows),
                    "pending": sum(r["status"] == "pending" for r in rows),
                    "stale": sum(bool(r["review"] and r["review"]["stale"]) for r in rows)}
            return found

    # -- reviewing

    def submit(self, answer: str, rubric: Sequence[int], adjust: float = 0.0,
               comment: str = "") -> dict:
        """Review the answer ``answer`` (an id of :meth:`written`): the rubric items given
        (indices from 0), a points adjustment, a comment for the student. Committed at once
        (module docstring); the answer as it now is (:meth:`answer`). ReviewError: an unknown
        id, an answer with nothing written, items the rubric has not, a bad adjustment."""
        rubric, adjust = _rubric(rubric), _adjust(adjust)
        comment = _comment(comment)
        with self._mutex, self._locked():
            sid, variable = self._known(answer)
            self._refresh()
            value = self._submitted(sid, variable)
            review = Review(sid, variable, rubric, adjust, comment, self.grader, now(),
                            text_sha256(value))
            amendment = Amendment(
                "review", f"review of {sid}'s {variable} by {self.grader}",
                reviews=self.reviews.with_review(review), students=frozenset({sid}),
                report=False, details={"student": sid, "answer": variable,
                                       "review": review.to_dict()})
            self._commit(amendment, f"eulertop review ({self.grader})")
            return self._answer(answer)

    def _submitted(self, sid: str, variable: str) -> Any:
        """What ``sid`` wrote for ``variable`` (ReviewError: nothing to review)."""
        record = self.records.get(sid)
        found = next((a for a in record.answers if a.variable == variable), None) \
            if record is not None else None
        if found is None or found.verdict.status not in ("pending", "reviewed"):
            status = found.verdict.status if found is not None else "not graded"
            raise ReviewError(f"{sid}'s {variable} has nothing to review ({status})")
        return found.submitted

    def set_rubric(self, question: str, item: int, points: float) -> dict:
        """Rubric item ``item`` (from 0) of the written ``question`` worth ``points`` for every
        student who has it (a key change, ``eulertop key set --rubric``): everyone who has it
        is rescored, their reviews kept. The question as :meth:`questions` gives it."""
        from grader.key_edit import set_answer

        with self._mutex, self._locked():
            self._refresh()
            key, changes = set_answer(self.a, question, rubric={_index(item) + 1: points})
            if changes:
                self._commit(Amendment(
                    "key set", f"key set {question}: rubric item {item + 1} worth {points:g} "
                    f"(by {self.grader})", key=key, students=frozenset(), report=False,
                    details={"key_changes": [c.as_dict() for c in changes]}),
                    f"eulertop review ({self.grader})")
        return next(q for q in self.questions() if q["question"] == question)

    def override(self, student: str, answer: str | None = None, points: float | None = None,
                 reason: str = "", remove: bool = False) -> dict:
        """The same override as ``eulertop override HW STUDENT [ANSWER] --points P --reason
        TEXT`` (or ``--remove``), by the session's grader, audited; the student's record's
        points and overrides."""
        with self._mutex, self._locked():
            self._refresh()
            amendment = override_amendment(self.a, self.overrides, student, answer, points,
                                           reason, self.grader, now(), remove=remove)
            self._commit(replace(amendment, report=False), f"eulertop review ({self.grader})")
            record = self.records[student]
            return {"student": student, "points": record.points if record else None,
                    "overridden": dict(record.overridden) if record else {}}

    # -- flagged for a look

    def flagged(self) -> list[dict]:
        """The answers the grader flagged for a look: invalid, a known mistake, credited by
        follow-through, or wrong yet within twice the tolerance — each with the student's
        value and the key's: ``{"id", "student", "question", "variable", "why",
        "submitted", "key", "status", "points", "max", "message", "overridden"}``, by answer
        then id."""
        with self._mutex:
            self.refresh()
            found = [f for sid, record in self.records.items()
                     if record is not None and record.status == "graded"
                     for f in self._flags(sid, record)]
            return sorted(found, key=lambda f: (f["question"], f["variable"], f["id"]))

    def _flags(self, sid: str, record: StudentResult) -> list[dict]:
        """``sid``'s answers flagged for a look (:meth:`flagged`)."""
        keys = {k.variable: k.answer for k in self.a.expected(sid)}
        seed = self.a.manifest.get("seed")
        found = []
        for a in record.answers:
            key = keys.get(a.variable)
            why = _flag(a, key) if key is not None else None
            if why:
                found.append({
                    "id": answer_id(seed, a.variable, sid), "student": sid,
                    "question": a.question, "variable": a.variable, "why": why,
                    "submitted": a.submitted, "key": key.value, "status": a.verdict.status,
                    "points": a.verdict.points, "max": a.verdict.max_points,
                    "message": a.verdict.message,
                    "overridden": record.overridden.get(a.variable)})
        return found

    # -- reusable comments

    def comments(self, question: str) -> dict[str, str]:
        """The reusable comments of ``question``: name → text."""
        with self._mutex:
            self.refresh()
            return dict(self.reviews.comments.get(question, {}))

    def add_comment(self, question: str, name: str, text: str | None) -> dict[str, str]:
        """Keep the reusable comment ``name`` of ``question`` (``text`` None: take it back),
        in ``reviews.json``, as a change of its own; the question's comments."""
        if not isinstance(name, str) or not name.strip():
            raise ReviewError("a reusable comment needs a name")
        text = None if text is None else _comment(text)
        with self._mutex, self._locked():
            self._refresh()
            if question not in self.a.written():
                raise ReviewError(f"no written question {question!r}")
            self.reviews = self.reviews.with_comment(question, name.strip(), text)
            tx = Transaction(self.out)
            tx.write(self.out / REVIEWS, reviews_json(self.reviews))
            tx.trail("comment", why=f"reusable comment {name.strip()!r} of {question} "
                     f"{'removed' if text is None else 'kept'} by {self.grader}",
                     answer=question, name=name.strip())
            tx.commit()
            self._seen = self._disk()
        return self.comments(question)

    # -- the end

    def close(self) -> None:
        """Rebuild the class report once if anything was committed (its written questions'
        score distributions among it), and stop the follow-through worker."""
        with self._mutex:
            try:
                if self.changed:
                    with self._locked():
                        self._refresh()
                        tx = Transaction(self.out)
                        stage_report(tx, self.a, self.out, self.records,
                                     report_notebooks(self.out), "eulertop review")
                        tx.commit()
                    self.changed = False
            finally:
                if self._follow is not None:
                    self._follow.close()
                    self._follow = None

    def __enter__(self) -> ReviewSession:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()


def _index(i: Any) -> int:
    if isinstance(i, bool) or not isinstance(i, int) or i < 0:
        raise ReviewError(f"a rubric item is its index from 0, got {i!r}")
    return i


def _rubric(items: Iterable[Any]) -> tuple[int, ...]:
    if isinstance(items, str | bytes) or not isinstance(items, Iterable):
        raise ReviewError(f"rubric: a list of item indices, got {items!r}")
    given = tuple(sorted(_index(i) for i in items))
    if len(set(given)) != len(given):
        raise ReviewError(f"rubric: an item given twice in {list(given)}")
    return given


def _adjust(value: Any) -> float:
    if isinstance(value, bool) or not isinstance(value, int | float) or not math.isfinite(value):
        raise ReviewError(f"adjust: a finite number of points, got {value!r}")
    return float(value)


def _comment(text: Any) -> str:
    if not isinstance(text, str):
        raise ReviewError(f"comment: text, got {type(text).__name__}")
    if len(text) > MAX_COMMENT:
        raise ReviewError(f"comment: {len(text)} characters, at most {MAX_COMMENT}")
    return text


def _flag(a: Any, answer: Any) -> str | None:
    """Why the grader flags answer result ``a`` (of key ``answer``) for a look, or None."""
    v = a.verdict
    if answer.kind == WRITTEN:
        return None
    if v.status == "invalid":
        return "invalid"
    if v.status == "follows":
        return "follow-through"
    if v.status == "wrong" and v.mistake:
        return f"known mistake: {v.mistake}"
    if v.status == "wrong" and _within_twice(a.submitted, answer):
        return "within twice the tolerance"
    return None


def _within_twice(submitted: Any, answer: Any) -> bool:
    """Whether ``submitted`` is right with ``answer``'s tolerances doubled."""
    if answer.kind in ("boolean", "choice"):
        return False
    try:
        wide = replace(answer, rtol=2 * answer.rtol, atol=2 * answer.atol, mistakes=(),
                       depends_on=())
        return grade(wide, submitted).status == "correct"
    except (ValueError, TypeError):
        return False

