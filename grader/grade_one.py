"""ONE submission graded (floor 4): the unit every front end shares — the local pool, Dask
workers, the hosted entrypoints — and, without a key, ``eulertop check`` (:func:`run_one`)."""

from __future__ import annotations

import hashlib
import os
import shutil
from collections.abc import Callable, Iterator, Sequence
from contextlib import contextmanager
from datetime import UTC, datetime
from pathlib import Path
from typing import Any

from grader.compare import KeyAnswer, compare, variable_names
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

    The generator writes ``metadata["eulertop"]["student"]``; ``"student_id"`` is accepted too.
    Anything unreadable gives None (the execution stage reports what is wrong with the file);
    it is parsed within the limits of :func:`grader.notebook_load.notebook_json`.
    """
    from grader.notebook_load import notebook_json

    try:
        meta = notebook_json(Path(path).read_bytes())["metadata"]["eulertop"]
        claim = meta.get("student", meta.get("student_id"))
    except Exception:
        return None
    return claim if isinstance(claim, str) else None


def now() -> str:
    """The ``graded_at`` stamp: UTC, to the second."""
    return datetime.now(UTC).isoformat(timespec="seconds")


def _execution_record(execution: Any) -> dict:
    # no duration: it differs on every run, and graded_at is the record's one volatile field
    record = {"status": execution.status, "message": execution.message,
              "cell_errors": list(execution.cell_errors),
              "output_truncated": execution.output_truncated}
    if getattr(execution, "retry", False):
        record["retry"] = True
    if getattr(execution, "isolation", ""):
        record["isolation"] = execution.isolation
    return record


def grade_submission(
    submission: Submission,
    expected: Sequence[KeyAnswer],
    key_sha256: str,
    execute: Execute,
    limits: Any,
    sha256: str | None = None,
) -> StudentResult:
    """Execute one submission, compare its answers, and make its record; never raises.

    A notebook that cannot be loaded (``SubmissionError``), a kernel that dies, a time-out, or a
    grader fault on this one file gives a ``failed`` record saying so, with no points.
    """
    from grader.notebook_load import SubmissionError

    sha256 = sha256 or file_sha256(submission.path)
    notes = []
    fault = False  # the grader's own failure, not the student's: graded again next time
    claim = claimed_student(submission.path)
    if claim is not None and claim != submission.student_id:
        notes.append(f"note: the notebook's metadata names student {claim!r}; it was graded as "
                     f"{submission.student_id!r}, from its file name")
    try:
        execution = execute(submission.path, variable_names(expected), limits)
    except SubmissionError as e:
        execution = None
        notes.insert(0, f"not a valid notebook: {e}")
    except Exception as e:  # one student's fault must not stop the others
        execution = None
        fault = True
        notes.insert(0, f"the grader could not run this notebook ({type(e).__name__}: {e})")
    extracted = execution.answers if execution is not None else {}
    answers = compare(expected, extracted)
    if execution is not None and (execution.status != "ok" or not extracted):
        notes.insert(0, execution.message or f"execution status {execution.status}")
    return StudentResult(
        student_id=submission.student_id,
        status="graded" if extracted else "failed",  # fail closed: nothing read, nothing given
        message="\n".join(notes),
        answers=answers,
        points=sum(a.verdict.points for a in answers),
        max_points=sum(k.answer.points for k in expected),
        submission_sha256=sha256,
        key_sha256=key_sha256,
        execution=(_execution_record(execution) if execution is not None else
                   {"retry": True} if fault else {}),
        sandboxed=bool(getattr(execution, "sandboxed", False)),
        graded_at=now(),
    )


def ungraded_result(
    student_id: str, status: str, message: str, expected: Sequence[KeyAnswer], key_sha256: str
) -> StudentResult:
    """The record of a student with no gradable submission (missing, or ambiguous)."""
    answers = compare(expected, None)
    return StudentResult(student_id, status, message, answers, 0.0,
                         sum(k.answer.points for k in expected), None, key_sha256, {}, False,
                         now())


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


def grade_one(submission: Submission, expected: Sequence[KeyAnswer], key_hash: str,
              limits: Any, execute: Execute | None = None, sha: str | None = None,
              copies: Path | None = None) -> StudentResult:
    """Grade ONE submission — the unit every way of grading shares (the local pool, a cluster,
    the hosted entrypoints): its record, never an exception.

    The submission is read as safely as in :func:`_plan` (a regular file under
    ``limits.submission_bytes``; checked to be ``sha`` when given), copied into a private
    folder (``copies``, default a new one in the run folder), executed by ``execute``
    (default :func:`grader.execute.execute_submission`, in the sandbox) and compared with
    ``expected`` in this process. A run that failed for a reason that is not the student's
    (``Execution.retry``: no kernel could be started) is run again, up to :data:`RETRIES`
    times; if it still fails, its record says so and the next run grades it again."""
    if copies is None:
        with copies_folder() as own:
            return grade_one(submission, expected, key_hash, limits, execute, sha, own)
    if execute is None:
        from grader.execute import execute_submission as execute
    max_bytes = getattr(limits, "submission_bytes", DEFAULT_MAX_BYTES)
    try:
        data = read_submission(submission.path, max_bytes)
    except (OSError, InvalidSubmission) as e:
        why = (f"invalid submission: {e}" if isinstance(e, InvalidSubmission) else
               f"cannot read {submission.path.name}: {e.strerror}")
        return ungraded_result(submission.student_id, "failed", why, expected, key_hash)
    if sha is None:
        sha = hashlib.sha256(data).hexdigest()
    if hashlib.sha256(data).hexdigest() != sha:
        return ungraded_result(submission.student_id, "failed", "invalid submission: the file "
                               "changed while the class was being graded", expected, key_hash)
    from grader.sandbox import fresh_folder

    folder = fresh_folder(copies, "c")
    copy = folder / submission.path.name
    try:
        fd = os.open(copy, os.O_WRONLY | os.O_CREAT | os.O_EXCL | os.O_NOFOLLOW, 0o600)
        with os.fdopen(fd, "wb") as f:
            f.write(data)
        own = Submission(submission.student_id, copy)
        for _ in range(RETRIES + 1):
            result = grade_submission(own, expected, key_hash, execute, limits, sha)
            if not result.execution.get("retry"):
                break
        return result
    finally:
        shutil.rmtree(folder, ignore_errors=True)
