"""Compare extracted answers with the key, in the grader process, failing closed.

The key never enters the student's kernel: the execution stage is given variable *names* only
(:func:`variable_names`) and returns plain JSON values; this stage grades them with the
problems' own answer definitions (:func:`problems.answers.grade`: correct / wrong / invalid /
missing, known mistakes with their feedback).

Fail closed (where nbgrader gave credit for output it could not parse): a student gets points
only for an answer that was extracted *and* compared correct. When nothing could be extracted
(the notebook is not valid, the kernel died, the run was cut at its time limit) every answer is
``missing`` with no points, whatever the notebook's saved outputs say; a comparison that itself
fails marks that answer ``invalid``, never correct.

Floor 3 of grader/ (the stages of one submission; grader/API.md).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any, NamedTuple

from grader.extract import UNREADABLE, invalid_reason
from grader.results import AnswerResult
from problems.answers import WRITTEN, Answer, Verdict, grade
from problems.generate import key_records

NOT_EXTRACTED = "not graded: the notebook did not run to the end, so no answer could be read"


class KeyAnswer(NamedTuple):
    """One answer of a student's key, with where it lives in the notebook."""

    variable: str
    question: int
    answer: Answer


def key_answers(key: Mapping, student_id: str) -> tuple[KeyAnswer, ...]:
    """A student's answers from a loaded ``key.json``, in question order, keeping the question
    number (for the gradebook's points per question); read by
    :func:`problems.generate.key_records`, next to the code that writes the key."""
    return tuple(KeyAnswer(*record) for record in key_records(key, student_id))


def variable_names(expected: Sequence[KeyAnswer]) -> tuple[str, ...]:
    """What the execution stage is told: the answer variables' names, nothing else — but
    those of written answers, which are read from the notebook's file, not its kernel
    (:func:`written_names`)."""
    return tuple(k.variable for k in expected if k.answer.kind != WRITTEN)


def written_names(expected: Sequence[KeyAnswer]) -> tuple[str, ...]:
    """The written answers' variables (:mod:`grader.written`)."""
    return tuple(k.variable for k in expected if k.answer.kind == WRITTEN)


def _grade_one(variable: str, answer: Answer, submitted: Any) -> Verdict:
    reason = invalid_reason(submitted)
    if reason is not None and reason.startswith(UNREADABLE):  # named: it failed alone
        return Verdict("invalid", 0.0, answer.points, f"{variable} {reason}")
    if reason is not None:  # the kernel held something that is not plain JSON
        return Verdict("invalid", 0.0, answer.points,
                       f"{reason}, which cannot be read as a {answer.kind} answer")
    try:
        return grade(answer, submitted)
    except Exception as e:  # a comparison bug must not give credit, nor stop the others
        return Verdict("invalid", 0.0, answer.points,
                       f"could not be compared ({type(e).__name__}); no points")


def compare(
    expected: Sequence[KeyAnswer], extracted: Mapping[str, Any] | None
) -> tuple[AnswerResult, ...]:
    """Grade each expected answer against the extracted values.

    Parameters
    ----------
    expected : sequence of KeyAnswer
        The student's key (:func:`key_answers`).
    extracted : mapping or None
        Variable name → plain JSON value from the executed notebook (None: unset). Empty or
        None when nothing could be extracted: then every answer is missing (fail closed).

    Returns
    -------
    tuple of AnswerResult
        One per expected answer, in order.
    """
    results = []
    for variable, question, answer in expected:
        if not extracted:
            verdict = Verdict("missing", 0.0, answer.points, NOT_EXTRACTED)
            submitted = None
        else:
            submitted = extracted.get(variable)
            verdict = _grade_one(variable, answer, submitted)
        results.append(AnswerResult(variable, question, answer.name, submitted, verdict))
    return tuple(results)
