"""ONE submission graded (floor 4): the unit every front end shares — the local pool, Dask
workers, the hosted entrypoints — and, without a key, ``eulertop check`` (:func:`run_one`).

Floor 4 of grader/ (the unit, what it is graded against, where its records go; grader/API.md).
"""

from __future__ import annotations

import hashlib
import os
import shutil
from collections.abc import Callable, Iterator, Mapping, Sequence
from contextlib import contextmanager
from dataclasses import dataclass
from datetime import UTC, datetime
from pathlib import Path
from typing import Any

from grader.compare import KeyAnswer, compare, variable_names
from grader.notebook_metadata import Identity, identity
from grader.results import StudentResult
from grader.submission_file import DEFAULT_MAX_BYTES, InvalidSubmission, read_submission
from grader.submissions import Submission

Execute = Callable[[Path, Sequence[str], Any], Any]
"""``execute_submission(path, variables, limits) -> Execution`` (grader/API.md)."""


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


def _execution_record(execution: Any, foreign: str = "") -> dict:
    # no duration: it differs on every run, and graded_at is the record's one volatile field
    record = {"status": execution.status, "message": execution.message,
              "cell_errors": list(execution.cell_errors),
              "output_truncated": execution.output_truncated}
    if foreign:  # the notebook that ran is not this assignment's, or another student's
        record["foreign"] = foreign
    if getattr(execution, "retry", False):
        record["retry"] = True
    if getattr(execution, "isolation", ""):
        record["isolation"] = execution.isolation
    return record


@dataclass(frozen=True)
class Run:
    """What running one submission gave (:func:`run_one`)."""

    execution: Any | None  # the Execution (grader.execute); None when it did not run
    problem: str = ""  # why it did not run, or could not be read: for a person
    fault: bool = False  # the grader's own failure, not the student's: graded again next time
    sha256: str | None = None  # of the bytes that ran; None when they could not be read
    identity: Identity | None = None  # what its metadata says it is (student, answer list)


def scored(student_id: str, expected: Sequence[KeyAnswer], key_sha256: str, *, status: str,
           message: str, extracted: Mapping[str, Any] | None, execution: dict,
           sandboxed: bool, submission_sha256: str | None) -> StudentResult:
    """The record of ``student_id``: ``extracted`` (the answers read from their notebook; None
    or empty: none) compared with ``expected`` — the one way a record is built, by a grading
    run (:func:`record`, :func:`ungraded_result`) and by a rescore
    (:func:`grader.rescore.rescored`) alike."""
    answers = compare(expected, extracted)
    return StudentResult(
        student_id=student_id, status=status, message=message, answers=answers,
        points=sum(a.verdict.points for a in answers) if status == "graded" else 0.0,
        max_points=sum(k.answer.points for k in expected),
        submission_sha256=submission_sha256, key_sha256=key_sha256, execution=execution,
        sandboxed=sandboxed, graded_at=now())


def record(student_id: str, expected: Sequence[KeyAnswer], key_sha256: str,
           run: Run) -> StudentResult:
    """The record of a submission that ran (or could not): its answers compared with
    ``expected``. A notebook that cannot be loaded, a kernel that dies, a time-out, or a grader
    fault gives a ``failed`` record saying so, with no points (fail closed)."""
    execution = run.execution
    foreign = run.identity.not_for(student_id) if run.identity and execution else ""
    notes = [run.problem] if run.problem else []
    if execution is not None and (execution.status != "ok" or not execution.answers):
        notes.insert(0, execution.message or f"execution status {execution.status}")
    if foreign:
        notes.append(f"{foreign}; it was graded as {student_id!r}, from its file name, all the "
                     "same")
    extracted = execution.answers if execution is not None else {}
    return scored(
        student_id, expected, key_sha256,
        status="graded" if extracted else "failed",  # fail closed: nothing read, nothing given
        message="\n".join(notes), extracted=extracted,
        execution=(_execution_record(execution, foreign) if execution is not None else
                   {"retry": True} if run.fault else {}),
        sandboxed=bool(getattr(execution, "sandboxed", False)), submission_sha256=run.sha256)


def ungraded_result(
    student_id: str, status: str, message: str, expected: Sequence[KeyAnswer], key_sha256: str
) -> StudentResult:
    """The record of a student with no gradable submission (missing, or ambiguous)."""
    return scored(student_id, expected, key_sha256, status=status, message=message,
                  extracted=None, execution={}, sandboxed=False, submission_sha256=None)


def submission_bytes(limits: Any) -> int:
    """The largest submission read (``limits.submission_bytes``; the default where the limits
    given have none)."""
    return getattr(limits, "submission_bytes", DEFAULT_MAX_BYTES)


def unreadable(path: Path, err: OSError | InvalidSubmission) -> str:
    """Why a submission file could not be read — the one wording of every stage that reads
    one (the plan, :func:`grade_one`, the Dask executor)."""
    if isinstance(err, InvalidSubmission):
        return f"invalid submission: {err}"
    return f"cannot read {Path(path).name}: {getattr(err, 'strerror', None) or err}"


RETRIES = 2
"""Times a submission is run again after a failure that is not its own (:func:`grade_one`)."""


@contextmanager
def copies_folder() -> Iterator[Path]:
    """A private folder of the run folder for the grader's own copies of submissions."""
    from grader.sandbox import fresh_folder, run_folder

    with run_folder() as run:
        folder = fresh_folder(run, "s")
        try:
            yield folder
        finally:
            shutil.rmtree(folder, ignore_errors=True)


def _execute(path: Path, variables: Sequence[str], execute: Execute,
             limits: Any) -> tuple[Any | None, str, bool]:
    """One attempt: ``(execution or None, why not, the grader's fault)``; never raises."""
    from grader.notebook_load import SubmissionError

    try:
        return execute(path, variables, limits), "", False
    except SubmissionError as e:
        return None, f"not a valid notebook: {e}", False
    except Exception as e:  # one student's fault must not stop the others
        return None, f"the grader could not run this notebook ({type(e).__name__}: {e})", True


def run_one(path: Path, variables: Sequence[str], limits: Any,
            execute: Execute | None = None, sha: str | None = None,
            copies: Path | None = None) -> Run:
    """Run ONE submission file — what grading and ``eulertop check`` share: a :class:`Run`,
    never an exception.

    The file is read as safely as the class run's plan reads it (a regular file under
    ``limits.submission_bytes``; checked to be ``sha`` when given), copied into a private
    folder (``copies``, default a new one in the run folder) and executed there by
    ``execute`` (default :func:`grader.execute.execute_submission`, in the sandbox). A run
    that failed for a reason that is not the student's (``Execution.retry``: no kernel could be
    started; or a fault of the grader's) is run again, up to :data:`RETRIES` times."""
    if copies is None:
        with copies_folder() as own:
            return run_one(path, variables, limits, execute, sha, own)
    if execute is None:
        from grader.execute import execute_submission as execute
    path = Path(path)
    try:
        data = read_submission(path, submission_bytes(limits))
    except (OSError, InvalidSubmission) as e:
        return Run(None, unreadable(path, e))
    if sha is None:
        sha = hashlib.sha256(data).hexdigest()
    if hashlib.sha256(data).hexdigest() != sha:
        return Run(None, "invalid submission: the file changed while the class was being graded")
    from grader.sandbox import fresh_folder

    folder = fresh_folder(copies, "c")
    copy = folder / path.name
    try:
        fd = os.open(copy, os.O_WRONLY | os.O_CREAT | os.O_EXCL | os.O_NOFOLLOW, 0o600)
        with os.fdopen(fd, "wb") as f:
            f.write(data)
        for _ in range(RETRIES + 1):
            execution, problem, fault = _execute(copy, variables, execute, limits)
            if not (fault or getattr(execution, "retry", False)):
                break
        return Run(execution, problem, fault, sha, identity(data))
    finally:
        shutil.rmtree(folder, ignore_errors=True)


def grade_one(submission: Submission, expected: Sequence[KeyAnswer], key_hash: str,
              limits: Any, execute: Execute | None = None, sha: str | None = None,
              copies: Path | None = None) -> StudentResult:
    """Grade ONE submission — the unit every way of grading shares (the local pool, Dask
    workers, the hosted entrypoints): :func:`run_one`, then its answers compared with
    ``expected`` in this process (:func:`record`); never an exception. A submission that could
    not be read is recorded failed, saying why; one whose run still failed for a reason not
    the student's is recorded with ``"retry": true``, and the next run grades it again."""
    run = run_one(submission.path, variable_names(expected), limits, execute, sha, copies)
    if run.sha256 is None:
        return ungraded_result(submission.student_id, "failed", run.problem, expected, key_hash)
    return record(submission.student_id, expected, key_hash, run)
