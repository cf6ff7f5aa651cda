"""Reviews of written answers (issue 31), kept in ``HW/graded/reviews.json`` beside the overrides.

A written answer (:mod:`problems.written`) is ``pending`` until a person reviews it: which items
of its rubric it earns, a points adjustment, a comment for the student, who and when. A review
is of the text it was given for (its SHA-256, :func:`grader.written.text_sha256`): a student's
new submission of other text is ``pending`` again, never scored by a review of the old one.
Reviews are applied to every record a grading run or a rescore finishes, after follow-through
credit and before the overrides (:func:`grader.publish.settled`): a reviewed answer gets its
given items' points plus the adjustment, clamped to 0 … its points (``reviewed``), and the
record says so (``StudentResult.reviewed``); an override of the answer still has the last word.
The file also keeps reusable comments, by answer: ``{"q5_veff_minimum": {"limits": "…"}}``.

The file is JSON, written here (one review a line) and read back::

    {
     "comments": {"q5_veff_minimum": {"limits": "Argue both ends: β → 0 and β → π."}},
     "format": "eulertop-reviews",
     "format_version": 1,
     "reviews": [
      {"adjust": -0.5, "answer": "q5_veff_minimum", "at": "2026-11-26T10:00:00+00:00",
       "by": "ta-lin", "comment": "…", "rubric": [0, 2], "student": "ada",
       "text_sha256": "…"}
     ]
    }

``rubric`` holds the given items' indices, counted from 0 in the key's order. Changing a
rubric item's points is a key change (``eulertop key set HW q5_veff_minimum --rubric 2=1.5``):
it rescores everyone who has that answer.

Floor 4 of grader/ (the unit, what it is graded against, where its records go; grader/API.md).
"""

from __future__ import annotations

import json
import math
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass, field, replace
from functools import cached_property
from pathlib import Path
from typing import Any

from grader.assignment import Assignment, UsageError
from grader.compare import KeyAnswer
from grader.results import AnswerResult, StudentResult
from grader.written import text_sha256
from problems.answers import PENDING, WRITTEN, Verdict

REVIEWS = "reviews.json"
FORMAT = "eulertop-reviews"
FORMAT_VERSION = 1
MAX_COMMENT = 10_000
"""Characters a review's comment, or a reusable comment, may hold."""


@dataclass(frozen=True)
class Review:
    """``student``'s written ``answer`` (its variable) reviewed: the rubric items given (their
    indices), a points ``adjust`` ment, a ``comment`` for the student, who (``by``) and when
    (``at``), and the SHA-256 of the text reviewed."""

    student: str
    answer: str
    rubric: tuple[int, ...]
    adjust: float
    comment: str
    by: str
    at: str
    text_sha256: str

    def to_dict(self) -> dict:
        return {"student": self.student, "answer": self.answer, "rubric": list(self.rubric),
                "adjust": self.adjust, "comment": self.comment, "by": self.by, "at": self.at,
                "text_sha256": self.text_sha256}

    @classmethod
    def from_dict(cls, d: Mapping[str, Any]) -> Review:
        """Inverse of :meth:`to_dict`; KeyError, TypeError or ValueError naming what is wrong."""
        rubric = d["rubric"]
        if not isinstance(rubric, list) or not all(_index(i) for i in rubric):
            raise ValueError(f"rubric must be a list of item indices, got {rubric!r}")
        adjust = d.get("adjust", 0.0)
        if isinstance(adjust, bool) or not isinstance(adjust, int | float) \
                or not math.isfinite(adjust):
            raise ValueError(f"adjust must be a finite number, got {adjust!r}")
        texts = {k: d.get(k, "") for k in ("comment", "by", "at")}
        if not all(isinstance(t, str) for t in texts.values()):
            raise ValueError("comment, by and at must be text")
        return cls(str(d["student"]), str(d["answer"]), tuple(rubric), float(adjust),
                   texts["comment"], texts["by"], texts["at"], str(d["text_sha256"]))


def _index(i: Any) -> bool:
    return isinstance(i, int) and not isinstance(i, bool) and i >= 0


@dataclass(frozen=True)
class Reviews:
    """The reviews of a class and its reusable comments (variable → name → text)."""

    reviews: tuple[Review, ...] = ()
    comments: Mapping[str, Mapping[str, str]] = field(default_factory=dict)

    @cached_property
    def _by_answer(self) -> dict[tuple[str, str], Review]:
        return {(r.student, r.answer): r for r in self.reviews}

    def of(self, student: str, answer: str) -> Review | None:
        """The review of ``student``'s ``answer``, if there is one."""
        return self._by_answer.get((student, answer))

    def with_review(self, review: Review) -> Reviews:
        """These reviews with ``review`` in place of any earlier one of the same answer."""
        kept = tuple(r for r in self.reviews
                     if (r.student, r.answer) != (review.student, review.answer))
        return replace(self, reviews=(*kept, review))

    def with_comment(self, answer: str, name: str, text: str | None) -> Reviews:
        """These reviews with the reusable comment ``name`` of ``answer`` set (None: gone)."""
        comments = {k: dict(v) for k, v in self.comments.items()}
        mine = comments.setdefault(answer, {})
        if text is None:
            mine.pop(name, None)
        else:
            mine[name] = text
        return replace(self, comments={k: v for k, v in comments.items() if v})


def read_reviews(out: Path) -> Reviews:
    """The reviews of the output folder ``out`` (none when there is no file); UsageError naming
    the file and the entry at fault when it cannot be read."""
    path = Path(out) / REVIEWS
    try:
        document = json.loads(path.read_text(encoding="utf-8"))
    except FileNotFoundError:
        return Reviews()
    except (OSError, UnicodeDecodeError, json.JSONDecodeError) as e:
        raise UsageError(f"{path}: cannot read the reviews: {e}") from None
    if not isinstance(document, dict) or document.get("format") != FORMAT:
        raise UsageError(f"{path}: not a reviews file (no \"format\": \"{FORMAT}\")")
    found = []
    for n, entry in enumerate(document.get("reviews", []), start=1):
        try:
            found.append(Review.from_dict(entry))
        except (KeyError, TypeError, ValueError, AttributeError) as e:
            raise UsageError(f"{path}: review {n}: {e}") from None
    return Reviews(tuple(found), _comments(path, document.get("comments", {})))


def _comments(path: Path, comments: Any) -> dict[str, dict[str, str]]:
    ok = isinstance(comments, dict) and all(
        isinstance(v, dict) and all(isinstance(t, str) for t in v.values())
        for v in comments.values())
    if not ok:
        raise UsageError(f"{path}: comments must map an answer to named texts")
    return {str(k): {str(n): t for n, t in v.items()} for k, v in comments.items()}


def reviews_json(reviews: Reviews) -> str:
    """The text of :data:`REVIEWS`: one review a line, sorted by answer and student (a diff
    shows what changed)."""
    ordered = sorted(reviews.reviews, key=lambda r: (r.answer, r.student))
    lines = [json.dumps(r.to_dict(), sort_keys=True, ensure_ascii=False, allow_nan=False)
             for r in ordered]
    body = ",\n  ".join(lines)
    comments = json.dumps(reviews.comments, sort_keys=True, ensure_ascii=False)
    return (f'{{\n "comments": {comments},\n "format": "{FORMAT}",\n '
            f'"format_version": {FORMAT_VERSION},\n "reviews": [' +
            (f"\n  {body}\n ]" if lines else "]") + "\n}\n")


def written_key(a: Assignment, student: str, answer: str) -> KeyAnswer | None:
    """``student``'s key entry of the written answer ``answer``, or None."""
    return next((k for k in a.written_expected(student) if k.variable == answer), None)


def check_review(a: Assignment, review: Review, where: str) -> None:
    """One review against the key it will be applied with: its student is on the roster,
    its answer is one of their written answers, its items are the rubric's (each once), its
    comment is within :data:`MAX_COMMENT`; else :class:`UsageError` naming ``where``."""
    if review.student not in a.ids:
        raise UsageError(f"{where}: no student {review.student!r} in the assignment's roster")
    key = written_key(a, review.student, review.answer)
    if key is None:
        raise UsageError(f"{where}: {review.student} has no written answer {review.answer!r}")
    items = len(key.answer.rubric)
    if len(set(review.rubric)) != len(review.rubric) or any(i >= items
                                                            for i in review.rubric):
        raise UsageError(f"{where}: rubric items {list(review.rubric)} are not distinct items "
                         f"of {review.answer}'s rubric, 0…{items - 1}")
    if len(review.comment) > MAX_COMMENT:
        raise UsageError(f"{where}: a comment of {len(review.comment)} characters (at most "
                         f"{MAX_COMMENT})")


def check_reviews(a: Assignment, reviews: Reviews, source: str = REVIEWS) -> None:
    """Every review checked (:func:`check_review`) with the key it will be applied with, before
    anything is written."""
    for n, review in enumerate(reviews.reviews, start=1):
        check_review(a, review, f"{source}: review {n}")


def review_points(key: KeyAnswer, review: Review) -> float:
    """What ``review`` gives ``key``'s answer: its items' points plus the adjustment, within
    0 … the answer's points."""
    given = sum(key.answer.rubric[i].points for i in review.rubric)
    return min(max(given + review.adjust, 0.0), key.answer.points)


def _pending(a: AnswerResult) -> AnswerResult:
    """A written answer as the comparison left it: pending (a review taken back first, or a
    note that it is stale: a record settled before, :func:`grader.rescore.restored`)."""
    if a.verdict.status not in ("reviewed", "pending"):
        return a
    return replace(a, verdict=Verdict("pending", 0.0, a.verdict.max_points, PENDING))


def _reviewed(a: AnswerResult, key: KeyAnswer, review: Review) -> tuple[AnswerResult, dict]:
    """``a`` scored by ``review``, and the record's entry saying how."""
    points = review_points(key, review)
    given = set(review.rubric)
    rubric = [{"item": r.item, "points": r.points, "given": i in given}
              for i, r in enumerate(key.answer.rubric)]
    note = f"{len(given)} of {len(rubric)} rubric items"
    if review.adjust:
        note += f", adjusted by {review.adjust:+g}"
    verdict = Verdict("reviewed", points, key.answer.points,
                      f"reviewed by {review.by or 'a reviewer'}: {note}")
    entry = {"rubric": rubric, "adjust": review.adjust, "comment": review.comment,
             "by": review.by, "at": review.at}
    return replace(a, verdict=verdict), entry


STALE = ("reviewed before this text was submitted: not scored until it is reviewed again "
         "(a review is of the text it was given for)")


def apply_reviews(result: StudentResult, reviews: Reviews,
                  expected: Sequence[KeyAnswer]) -> StudentResult:
    """``result`` with its written answers scored by their reviews (module docstring); any
    applied before are taken back first. A record that is not ``graded`` is returned as it
    is."""
    if result.status != "graded":
        return result
    keys = {k.variable: k for k in expected if k.answer.kind == WRITTEN}
    mine = {r.answer: r for r in reviews.reviews if r.student == result.student_id}
    answers, entries = [], {}
    for a in result.answers:
        key, review = keys.get(a.variable), mine.get(a.variable)
        if key is not None:
            a = _pending(a)
        if key is not None and review is not None and a.verdict.status == "pending":
            if review.text_sha256 == text_sha256(a.submitted):
                a, entries[a.variable] = _reviewed(a, key, review)
            else:
                a = replace(a, verdict=replace(a.verdict, message=STALE))
        answers.append(a)
    if tuple(answers) == result.answers and entries == result.reviewed:
        return result
    return replace(result, answers=tuple(answers), reviewed=entries,
                   points=sum(a.verdict.points for a in answers))


def pending_answers(result: StudentResult) -> tuple[str, ...]:
    """The variables of ``result``'s written answers not scored yet."""
    return tuple(a.variable for a in result.answers if a.verdict.status == "pending")


def reviews_of(reviews: Iterable[Review], student: str) -> tuple[Review, ...]:
    """``student``'s reviews."""
    return tuple(r for r in reviews if r.student == student)
