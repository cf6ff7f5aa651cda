"""``eulertop grade`` composed in one place: discover → execute → extract → compare → report.

Each stage is a module with one input and one output (grader/API.md); this module only wires
them together and owns the run's bookkeeping:

1. :func:`load_assignment` reads ``HW/assignment.json`` and ``HW/key.json``.
2. :func:`grader.discover.discover` maps files to roster ids (from names only).
3. Each submission is hashed; one whose file and key hash match its existing result record is
   skipped (resume), unless ``force``.
4. The others run through ``execute(path, variable_names, limits)`` — by default
   :func:`grader.execute.execute_submission`, injected so that tests and benchmarks can swap
   it — and :func:`grader.compare.compare` grades what came back, in this process.
5. Each finished student's record is written at once, atomically
   (:func:`grader.results.write_result`), with its feedback page; the gradebook and every
   feedback page are rebuilt from the records at the end.

Kernels: unless ``execute`` is given, each submission runs in a *warm* kernel — forked, one
fresh process per submission, from a per-slot zygote that has imported ipykernel, numpy, scipy
and sympy once (:mod:`grader.kernel_pool`); ``cold_kernels`` (``--cold-kernels``) starts each
kernel from scratch instead, as it is done automatically where ``fork`` is not available.

Sandbox (issue 5): with the default execution, every zygote and kernel runs in a bubblewrap
sandbox (:mod:`grader.sandbox`); where none can be had the run is refused
(:class:`UsageError` saying how to get one) unless ``sandbox=False`` (``--no-sandbox``), which
warns on every run and is written into every record (``sandboxed``) and ``grades.csv`` (a
``sandboxed`` column, present whenever some record was graded without one). All the run's
temporary folders are in one run folder (:func:`grader.sandbox.run_folder`); those of killed
runs are removed when the next run starts.

Parallelism: a pool of ``jobs`` *threads*. The work of a submission happens in its kernel, a
separate process; the grader's side is waiting on sockets and a little JSON, which threads do
without pickling the key or the results across processes and with the assignment loaded once.
A worker writes its own result as soon as it has one, so the records on disk are the run's
progress: a run killed at any moment loses at most the submissions in flight.

Concurrency between runs: a run holds ``fcntl.flock`` on ``OUT/.lock`` from start to end; a
second run on the same folder is refused (:class:`RunInProgress`). The lock goes with the
process, so a killed run never leaves a stale lock behind.
"""

from __future__ import annotations

import fcntl
import hashlib
import json
import os
import sys
import threading
from collections.abc import Callable, Iterator, Mapping, Sequence
from concurrent.futures import ThreadPoolExecutor, wait
from contextlib import contextmanager
from dataclasses import dataclass
from datetime import UTC, datetime
from functools import partial
from pathlib import Path
from typing import Any

from grader.compare import KeyAnswer, compare, key_answers, variable_names
from grader.discover import Problem, Submission, discover
from grader.gradebook import feedback_html, gradebook_csv, gradebook_rows, ran_code
from grader.results import (
    StudentResult,
    atomic_write_text,
    read_result,
    remove_stale_temporaries,
    write_result,
)

RESULTS, FEEDBACK, GRADES, LOCK = "results", "feedback", "grades.csv", ".lock"

Execute = Callable[[Path, Sequence[str], Any], Any]
"""``execute_submission(path, variables, limits) -> Execution`` (grader/API.md)."""


class UsageError(Exception):
    """The run cannot start (no assignment, no key, unreadable folder); nothing was written."""


class RunInProgress(UsageError):
    """Another grading run holds the output folder's lock."""


@dataclass(frozen=True)
class Assignment:
    """What grading needs from ``HW``: the roster, each student's public questions, the key."""

    folder: Path
    title: str
    columns: tuple[str, ...]
    rows: tuple[dict, ...]
    questions: tuple[int, ...]
    students: dict  # assignment.json "students": id -> {"questions": [public question, ...]}
    key: dict       # key.json

    @property
    def ids(self) -> tuple[str, ...]:
        return tuple(r["id"] for r in self.rows)

    def key_hash(self, student_id: str) -> str:
        return self.key["students"][student_id]["hash"]


@dataclass(frozen=True)
class RunReport:
    """What a run did: every roster student's result (roster order) and what it left alone."""

    results: tuple[StudentResult, ...]
    graded_now: tuple[str, ...]  # ids (re)graded by this run
    unchanged: tuple[str, ...]  # ids whose existing record was kept
    problems: tuple[Problem, ...]  # everything discovery could not use

    @property
    def not_graded(self) -> tuple[str, ...]:
        """Why-lines for every submission that could not be graded (exit status 1)."""
        failed = [f"{r.student_id}: {(r.message or 'failed').splitlines()[0]}"
                  for r in self.results if r.status == "failed"]
        stray = [p.message for p in self.problems if p.student_id is None and not p.ignored]
        return tuple(failed + stray)


# --------------------------------------------------------------------------------------------
# inputs


def _read_json(path: Path, what: str) -> dict:
    if not path.is_file():
        raise UsageError(f"{path}: no {what} here (is this an assignment folder written by "
                         "'eulertop generate'?)")
    try:
        return json.loads(path.read_text(encoding="utf-8"))
    except (OSError, UnicodeDecodeError, json.JSONDecodeError) as e:
        raise UsageError(f"{path}: cannot read the {what}: {e}") from None


def load_assignment(hw: Path) -> Assignment:
    """Read ``HW/assignment.json`` and ``HW/key.json``; :class:`UsageError` if unusable."""
    hw = Path(hw)
    if not hw.is_dir():
        raise UsageError(f"{hw}: no such assignment folder")
    manifest = _read_json(hw / "assignment.json", "assignment manifest (assignment.json)")
    key = _read_json(hw / "key.json", "answer key (key.json)")
    try:
        rows = tuple(manifest["roster"]["rows"])
        students = manifest["students"]
        absent = [r["id"] for r in rows if r["id"] not in key["students"]
                  or r["id"] not in students]
        questions = tuple(range(1, len(manifest["problems"]) + 1))
        columns = tuple(manifest["roster"]["columns"])
        title = manifest.get("title", hw.name)
    except (KeyError, TypeError) as e:
        raise UsageError(f"{hw}: assignment.json or key.json is not in the generator's "
                         f"layout (no {e})") from None
    if absent:
        raise UsageError(f"{hw}: key.json has no entry for {', '.join(absent)}; regenerate "
                         "the assignment")
    return Assignment(hw, title, columns, rows, questions, students, key)


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
    Anything unreadable gives None (the execution stage reports what is wrong with the file).
    """
    try:
        meta = json.loads(Path(path).read_bytes())["metadata"]["eulertop"]
        claim = meta.get("student", meta.get("student_id"))
    except Exception:
        return None
    return claim if isinstance(claim, str) else None


def now() -> str:
    """The ``graded_at`` stamp: UTC, to the second."""
    return datetime.now(UTC).isoformat(timespec="seconds")


# --------------------------------------------------------------------------------------------
# one student


def _execution_record(execution: Any) -> dict:
    # no duration: it differs on every run, and graded_at is the record's one volatile field
    return {"status": execution.status, "message": execution.message,
            "cell_errors": list(execution.cell_errors),
            "output_truncated": execution.output_truncated}


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
        execution=_execution_record(execution) if execution is not None else {},
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


# --------------------------------------------------------------------------------------------
# the run


@contextmanager
def run_lock(out: Path) -> Iterator[None]:
    """Hold ``OUT/.lock`` (``fcntl.flock``) for the run, or raise :class:`RunInProgress`."""
    fd = os.open(out / LOCK, os.O_RDWR | os.O_CREAT, 0o644)
    try:
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            holder = os.pread(fd, 64, 0).decode(errors="replace").strip()
            who = f" (pid {holder})" if holder.isdigit() else ""
            raise RunInProgress(f"{out}: another 'eulertop grade' run{who} is in progress on "
                                "this folder; wait for it to finish") from None
        os.ftruncate(fd, 0)
        os.pwrite(fd, str(os.getpid()).encode(), 0)
        yield
    finally:
        os.close(fd)  # releases the lock


def _unchanged(old: StudentResult | None, sha: str | None, key_hash: str,
               fresh: StudentResult | None = None, sandboxed: bool = False) -> bool:
    if old is None or old.submission_sha256 != sha or old.key_sha256 != key_hash:
        return False
    if sandboxed and ran_code(old) and not old.sandboxed:
        return False  # graded without a sandbox before: grade it in one now
    return fresh is None or (old.status, old.message) == (fresh.status, fresh.message)


def _plan(a: Assignment, found, out: Path, force: bool, sandboxed: bool = False):
    """Split the roster: (submissions to execute with their hashes, records to write, kept)."""
    to_run, to_write, kept = [], [], []
    problems = {p.student_id: p for p in found.problems if p.student_id is not None}
    by_id = {s.student_id: s for s in found.submissions}
    for sid in a.ids:
        old = None if force else read_result(out / RESULTS / f"{sid}.json")
        expected, key_hash = key_answers(a.key, sid), a.key_hash(sid)
        if sid in by_id:
            try:
                sha = file_sha256(by_id[sid].path)
            except OSError as e:
                to_write.append(ungraded_result(
                    sid, "failed", f"cannot read {by_id[sid].path.name}: {e.strerror}",
                    expected, key_hash))
                continue
            if _unchanged(old, sha, key_hash, sandboxed=sandboxed):
                kept.append(sid)
            else:
                to_run.append((by_id[sid], expected, key_hash, sha))
            continue
        fresh = (ungraded_result(sid, "failed", problems[sid].message, expected, key_hash)
                 if sid in problems else
                 ungraded_result(sid, "missing", "no submission", expected, key_hash))
        if _unchanged(old, None, key_hash, fresh):
            kept.append(sid)
        else:
            to_write.append(fresh)
    return to_run, to_write, kept


def _publish(a: Assignment, out: Path, result: StudentResult, reveal: bool) -> None:
    write_result(out / RESULTS, result)
    key = None
    if reveal:
        key = {k.variable: k.answer.value for k in key_answers(a.key, result.student_id)}
    page = feedback_html(a.title, result, a.students[result.student_id]["questions"], key)
    atomic_write_text(out / FEEDBACK / f"{result.student_id}.html", page)


def grade_assignment(
    hw: Path,
    submissions: Path,
    out: Path | None = None,
    *,
    limits: Any = None,
    jobs: int | None = None,
    force: bool = False,
    reveal: bool = False,
    execute: Execute | None = None,
    progress: Callable[[StudentResult], None] | None = None,
    on_plan: Callable[[int], Callable[[StudentResult], None] | None] | None = None,
    cold_kernels: bool = False,
    sandbox: bool = True,
) -> RunReport:
    """Grade every submission in ``submissions`` against the assignment ``hw``.

    Parameters
    ----------
    hw, submissions : Path
        The assignment folder and the submissions folder.
    out : Path, optional
        Output folder (default ``hw/graded``): ``results/``, ``feedback/``, ``grades.csv``.
    limits : grader.limits.Limits, optional
        Execution limits (default ``Limits()``).
    jobs : int, optional
        Submissions graded at once (default ``os.cpu_count()``).
    force : bool
        Regrade even students whose submission and key are unchanged.
    reveal : bool
        Show each student their own key values in their feedback page.
    execute : callable, optional
        ``execute(path, variables, limits) -> Execution``; default
        :func:`grader.execute.execute_submission` with warm kernels
        (:class:`grader.kernel_pool.KernelPool`, one slot per job).
    progress : callable, optional
        Called with each record as it is written (from worker threads).
    on_plan : callable, optional
        Called with the number of submissions to execute before any runs; may return the
        ``progress`` callable (so a progress bar knows its total).
    cold_kernels : bool
        With the default ``execute``: start every kernel from scratch, not from a zygote.
    sandbox : bool
        With the default ``execute``: run every kernel in the sandbox (refused where there is
        none); False runs them unsandboxed, with a warning on stderr and in the records.

    Raises
    ------
    UsageError
        Missing or unreadable inputs, no sandbox to be had (with ``sandbox``);
        :class:`RunInProgress` when another run holds the lock.
    """
    a = load_assignment(hw)
    submissions = Path(submissions)
    if not submissions.is_dir() or not os.access(submissions, os.R_OK | os.X_OK):
        raise UsageError(f"{submissions}: not a readable folder of submissions")
    out = Path(hw) / "graded" if out is None else Path(out)
    warm = execute is None and not cold_kernels
    found_sandbox = None
    if execute is None:
        found_sandbox = _sandbox(sandbox)
    if execute is None or limits is None:
        from grader.limits import Limits

        if execute is None:
            from grader.execute import execute_submission

            execute = partial(execute_submission, sandbox=found_sandbox is not None)
        limits = limits or Limits()
    try:
        for sub in (RESULTS, FEEDBACK):
            (out / sub).mkdir(parents=True, exist_ok=True)
    except OSError as e:
        raise UsageError(f"{out}: cannot create the output folder: {e.strerror}") from None
    with run_lock(out):
        remove_stale_temporaries(out, out / RESULTS, out / FEEDBACK)
        found = discover(submissions, a.ids)
        to_run, to_write, kept = _plan(a, found, out, force, found_sandbox is not None)
        if on_plan is not None:
            progress = on_plan(len(to_run) + len(to_write)) or progress
        for result in to_write:
            _publish(a, out, result, reveal)
            if progress:
                progress(result)
        jobs = jobs or os.cpu_count() or 1
        with _kernels(warm and bool(to_run), min(jobs, len(to_run)), found_sandbox) as factory:
            run = execute if factory is None else partial(execute, kernel_factory=factory)
            _run_all(a, out, to_run, run, limits, jobs, reveal, progress)
        results = {sid: read_result(out / RESULTS / f"{sid}.json") for sid in a.ids}
        _rebuild(a, out, results, reveal)
        _class_report(a, out, results, found.submissions)
    graded_now = tuple(t[0].student_id for t in to_run) + tuple(r.student_id for r in to_write)
    return RunReport(tuple(results[s] for s in a.ids), graded_now, tuple(kept), found.problems)


WITHOUT_SANDBOX = ("eulertop grade: WARNING: grading WITHOUT a sandbox (--no-sandbox): student "
                   "code runs as you and can read the answer key, other submissions and your "
                   "files, and reach the network; every result record and grades.csv say so\n")


def _sandbox(wanted: bool) -> Any:
    """The run's sandbox (:func:`grader.sandbox.probe`), or None when not ``wanted`` (which
    warns); :class:`UsageError` when wanted and there is none."""
    from grader.sandbox import SandboxUnavailable, probe

    if not wanted:
        sys.stderr.write(WITHOUT_SANDBOX)
        return None
    try:
        return probe()
    except SandboxUnavailable as err:
        raise UsageError(str(err)) from None


@contextmanager
def _kernels(warm: bool, slots: int, sandbox: Any = None) -> Iterator[Callable | None]:
    """The kernel factory of the run: a warm pool's (closed at the end), or None (default)."""
    if not warm:
        yield None
        return
    from grader.kernel_pool import KernelPool
    from grader.sandbox import run_folder

    with run_folder(), KernelPool(slots, sandbox=sandbox) as pool:
        yield pool.kernel


def _run_all(a, out, to_run, execute, limits, jobs, reveal, progress) -> None:
    """Execute and grade ``to_run`` on ``jobs`` threads; each worker publishes its own record."""
    if not to_run:
        return
    stop = threading.Event()

    def work(submission, expected, key_hash, sha):
        if stop.is_set():
            return
        result = grade_submission(submission, expected, key_hash, execute, limits, sha)
        _publish(a, out, result, reveal)
        if progress:
            progress(result)

    pool = ThreadPoolExecutor(max_workers=jobs, thread_name_prefix="eulertop-grade")
    futures = [pool.submit(work, *task) for task in to_run]
    try:
        wait(futures)
    except KeyboardInterrupt:
        # Ctrl-C: start nothing new; what runs finishes and is saved (bounded by the time
        # limit), still under the lock. A second Ctrl-C abandons it (the caller exits).
        stop.set()
        pool.shutdown(wait=False, cancel_futures=True)
        running = sum(not f.done() for f in futures)
        if running:
            sys.stderr.write(f"\ninterrupted: finishing the {running} submission(s) being "
                             "graded (Ctrl-C again to abandon them)\n")
        wait(futures)
        raise
    pool.shutdown()
    for f in futures:
        f.result()  # a fault in publishing (disk full …) must not pass silently


def _class_report(a: Assignment, out: Path, results: Mapping[str, StudentResult | None],
                  submissions: Sequence[Submission]) -> None:
    """``OUT/report.html`` (:mod:`grader.report`); a fault there is reported, never fatal to
    the grades already written."""
    from grader.report import build_report, write_report
    from grader.report.classdata import class_data

    try:
        report = build_report(class_data(a, results), {s.student_id: s.path for s in submissions})
        write_report(report, out / "report.html")
    except Exception as e:
        sys.stderr.write(f"eulertop grade: the class report could not be written "
                         f"({type(e).__name__}: {e}); the grades are complete\n")


def _rebuild(a: Assignment, out: Path, results: Mapping[str, StudentResult | None],
             reveal: bool) -> None:
    """The gradebook and every feedback page, from the records on disk."""
    present = {sid: r for sid, r in results.items() if r is not None}
    unsandboxed = any(ran_code(r) and not r.sandboxed for r in present.values())
    table = gradebook_rows(a.columns, a.rows, a.questions, present, sandbox_column=unsandboxed)
    atomic_write_text(out / GRADES, gradebook_csv(table))
    for sid, r in present.items():
        key = ({k.variable: k.answer.value for k in key_answers(a.key, sid)} if reveal else None)
        page = feedback_html(a.title, r, a.students[sid]["questions"], key)
        atomic_write_text(out / FEEDBACK / f"{sid}.html", page)
