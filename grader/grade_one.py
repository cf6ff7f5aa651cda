"""ONE submission graded (floor 4): the unit every front end shares — the local pool, Dask
workers, the hosted entrypoints — and, without a key, ``eulertop check``
(:func:`grader.run_file.run_one`).

Floor 4 of grader/ (the unit, what it is graded against, where its records go; grader/API.md).
"""

from __future__ import annotations

import hashlib
from collections.abc import Mapping, Sequence
from datetime import UTC, datetime
from pathlib import Path
from typing import Any

from grader.compare import KeyAnswer, compare, variable_names, written_names
from grader.notebook_metadata import identity
from grader.results import AnswerResult, StudentResult

# run_one and what it needs live in grader.run_file, which the student package ships too
# (issue 33); named here as well, where every way of grading has always imported them
from grader.run_file import RETRIES as RETRIES
from grader.run_file import Execute as Execute
from grader.run_file import Run as Run
from grader.run_file import copies_folder as copies_folder
from grader.run_file import run_one as run_one
from grader.run_file import submission_bytes as submission_bytes
from grader.run_file import unreadable as unreadable
from grader.submissions import Submission
from problems.generate import canonical_hash


def file_sha256(path: Path) -> str:
    """SHA-256 (hex) of a file's bytes."""
    digest = hashlib.sha256()
    with open(path, "rb") as f:
        for block in iter(lambda: f.read(1 << 20), b""):
            digest.update(block)
    return digest.hexdigest()


def claimed_student(path: Path) -> str | None:
    """The student id a notebook's own metadata names, if any — only ever *reported*.

    The generator writes ``metadata["eulertop"]["student"]``; ``"student_id"`` is accepted too
    (:func:`grader.notebook_metadata.named_student`). Anything unreadable gives None (the
    execution stage reports what is wrong with the file); it is parsed within the limits of
    :func:`grader.notebook_load.notebook_json`.
    """
    found = identity(Path(path).read_bytes())
    return None if found is None else found.student


def now() -> str:
    """The ``graded_at`` stamp: UTC, to the second."""
    return datetime.now(UTC).isoformat(timespec="seconds")


VARIANT = "variant"
"""The execution record's hash of the parameters the notebook was graded as
(:func:`parameters_hash`): a rescore tells by it that the student's variant changed since."""


def parameters_hash(parameters: Mapping[str, Any]) -> str:
    """``"sha256:<hex>"`` of a student's parameters by notebook variable
    (:func:`problems.generate.canonical_hash`, as a key entry's hash)."""
    return canonical_hash(dict(parameters))


def _execution_record(execution: Any, foreign: str = "",
                      parameters: Mapping[str, Any] | None = None) -> dict:
    # no duration: it differs on every run, and graded_at is the record's one volatile field
    record = {"status": execution.status, "message": execution.message,
              "cell_errors": list(execution.cell_errors),
              "output_truncated": execution.output_truncated}
    if foreign:  # the notebook that ran is not this assignment's, another student's or variant's
        record["foreign"] = foreign
    if parameters:
        record[VARIANT] = parameters_hash(parameters)
    if getattr(execution, "retry", False):
        record["retry"] = True
    if getattr(execution, "isolation", ""):
        record["isolation"] = execution.isolation
    return record


def scored(student_id: str, expected: Sequence[KeyAnswer], key_sha256: str, *, status: str,
           message: str, extracted: Mapping[str, Any] | None, execution: dict,
           sandboxed: bool, submission_sha256: str | None,
           compared: Sequence[AnswerResult] | None = None) -> StudentResult:
    """The record of ``student_id``: ``extracted`` (the answers read from their notebook; None
    or empty: none) compared with ``expected`` — the one way a record is built, by a grading
    run (:func:`record`, :func:`ungraded_result`) and by a rescore
    (:func:`grader.rescore.rescored`) alike; or, given ``compared`` (``expected`` and
    ``extracted`` unused), from answers compared with the key ``key_sha256`` before: a record's
    own, when a change leaves its key as it was (:func:`grader.rescore.restored`). Each
    answer's verdict carries its key points: the record's are their sum."""
    answers = compare(expected, extracted) if compared is None else tuple(compared)
    return StudentResult(
        student_id=student_id, status=status, message=message, answers=answers,
        points=sum(a.verdict.points for a in answers) if status == "graded" else 0.0,
        max_points=sum(a.verdict.max_points for a in answers),
        submission_sha256=submission_sha256, key_sha256=key_sha256, execution=execution,
        sandboxed=sandboxed, graded_at=now())


def _answers_read(expected: Sequence[KeyAnswer], run: Run) -> dict[str, Any]:
    """The answers read from a run: its kernel's, and its written answers read from the file
    (:mod:`grader.written`) — those only where the notebook ran to the end and its kernel's
    answers were read (or none were asked): fail closed alike."""
    execution = run.execution
    extracted = dict(execution.answers) if execution is not None else {}
    ran = execution is not None and execution.status == "ok"
    if run.written and (extracted or (ran and not variable_names(expected))):
        extracted.update(run.written)
    return extracted


def record(student_id: str, expected: Sequence[KeyAnswer], key_sha256: str,
           run: Run, parameters: Mapping[str, Any] | None = None) -> StudentResult:
    """The record of a submission that ran (or could not): its answers compared with
    ``expected``. A notebook that cannot be loaded, a kernel that dies, a time-out, or a grader
    fault gives a ``failed`` record saying so, with no points (fail closed). ``parameters``:
    the student's, by notebook variable (:meth:`grader.assignment.Assignment.parameters`);
    given, a notebook holding others is named another variant's, and the record keeps their
    hash (:data:`VARIANT`)."""
    execution = run.execution
    foreign = run.identity.not_for(student_id, parameters) if run.identity and execution \
        else ""
    notes = [run.problem] if run.problem else []
    extracted = _answers_read(expected, run)
    if execution is not None and (execution.status != "ok" or not extracted):
        notes.insert(0, execution.message or f"execution status {execution.status}")
    if foreign:
        notes.append(f"{foreign}; it was graded as {student_id!r}, from its file name, all the "
                     "same")
    return scored(
        student_id, expected, key_sha256,
        status="graded" if extracted else "failed",  # fail closed: nothing read, nothing given
        message="\n".join(notes), extracted=extracted,
        execution=(_execution_record(execution, foreign, parameters) if execution is not None
                   else {"retry": True} if run.fault else {}),
        sandboxed=bool(getattr(execution, "sandboxed", False)), submission_sha256=run.sha256)


def ungraded_result(
    student_id: str, status: str, message: str, expected: Sequence[KeyAnswer], key_sha256: str
) -> StudentResult:
    """The record of a student with no gradable submission (missing, or ambiguous)."""
    return scored(student_id, expected, key_sha256, status=status, message=message,
                  extracted=None, execution={}, sandboxed=False, submission_sha256=None)


def grade_one(submission: Submission, expected: Sequence[KeyAnswer], key_hash: str,
              limits: Any, execute: Execute | None = None, sha: str | None = None,
              copies: Path | None = None,
              parameters: Mapping[str, Any] | None = None) -> StudentResult:
    """Grade ONE submission — the unit every way of grading shares (the local pool, Dask
    workers, the hosted entrypoints): :func:`run_one`, then its answers compared with
    ``expected`` in this process (:func:`record`); never an exception. A submission that could
    not be read is recorded failed, saying why; one whose run still failed for a reason not
    the student's is recorded with ``"retry": true``, and the next run grades it again."""
    run = run_one(submission.path, variable_names(expected), limits, execute, sha, copies,
                  written_names(expected))
    if run.sha256 is None:
        return ungraded_result(submission.student_id, "failed", run.problem, expected, key_hash)
    return record(submission.student_id, expected, key_hash, run, parameters)
