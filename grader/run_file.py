"""ONE submission file run (floor 4): read safely, copied, executed, retried — what grading
(:func:`grader.grade_one.grade_one`) and the student's check (``eulertop check``,
``eulertop-check``: :mod:`grader.check`) share, without anything of the key: :func:`run_one`.

Shipped by the student package too (``student/pyproject.toml``, issue 33), so it imports
nothing of the comparison, the key or the records.

Floor 4 of grader/ (the unit; grader/API.md).
"""

from __future__ import annotations

import hashlib
import os
import shutil
from collections.abc import Callable, Iterator, Sequence
from contextlib import contextmanager
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from grader.notebook_metadata import Identity, identity
from grader.submission_file import DEFAULT_MAX_BYTES, InvalidSubmission, read_submission

Execute = Callable[[Path, Sequence[str], Any], Any]
"""``execute_submission(path, variables, limits) -> Execution`` (grader/API.md)."""


@dataclass(frozen=True)
class Run:
    """What running one submission gave (:func:`run_one`)."""

    execution: Any | None  # the Execution (grader.execute); None when it did not run
    problem: str = ""  # why it did not run, or could not be read: for a person
    fault: bool = False  # the grader's own failure, not the student's: graded again next time
    sha256: str | None = None  # of the bytes that ran; None when they could not be read
    identity: Identity | None = None  # what its metadata says it is (student, answer list)
    written: dict | None = None  # the written answers asked for, read from those bytes


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


def _written(data: bytes, variables: Sequence[str]) -> dict | None:
    """The written answers of ``variables`` in the notebook ``data`` (None: none asked)."""
    if not variables:
        return None
    from grader.written import written_answers

    return written_answers(data, variables)


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
            copies: Path | None = None, written: Sequence[str] = ()) -> Run:
    """Run ONE submission file — what grading and ``eulertop check`` share: a :class:`Run`,
    never an exception.

    The file is read as safely as the class run's plan reads it (a regular file under
    ``limits.submission_bytes``; checked to be ``sha`` when given), copied into a private
    folder (``copies``, default a new one in the run folder) and executed there by
    ``execute`` (default :func:`grader.execute.execute_submission`, in the sandbox). A run
    that failed for a reason that is not the student's (``Execution.retry``: no kernel could be
    started; or a fault of the grader's) is run again, up to :data:`RETRIES` times.

    ``written``: the written answers (``q5_veff_minimum``) read from the same bytes in this
    process, never the kernel (:func:`grader.written.written_answers`): ``Run.written``."""
    if copies is None:
        with copies_folder() as own:
            return run_one(path, variables, limits, execute, sha, own, written)
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
        whose = getattr(execution, "identity", None)  # parsed once, by the execution stage
        return Run(execution, problem, fault, sha,
                   whose if whose is not None else identity(data), _written(data, written))
    finally:
        shutil.rmtree(folder, ignore_errors=True)
