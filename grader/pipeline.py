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
5. Each finished student's record is settled (follow-through credit, the reviews of its
   written answers, then the overrides) and
   committed at once with its feedback page and its line of the audit trail (a transaction:
   :mod:`grader.transaction`); the gradebook, every other page, the class report and the run's
   own line are committed together at the end.

Kernels: unless ``execute`` is given, each submission runs in a *warm* kernel — forked, one
fresh process per submission, from a per-slot zygote that has imported ipykernel, numpy, scipy
and sympy once (:mod:`grader.kernels.pool`); ``cold_kernels`` (``--cold-kernels``) starts each
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

Concurrency between commands: a run holds ``fcntl.flock`` on ``OUT/.lock`` from before it
reads the assignment to its end (:func:`grader.transaction.class_lock`); a second command on
the same folder waits for it (up to ``wait`` seconds, then :class:`RunInProgress`). The lock goes
with the process, so a killed run never leaves a stale lock behind; a killed run's last
transaction is finished, or its temporaries removed, by the next command that takes the lock.

Refused before anything is written (:class:`UsageError`, exit 2): a bad key or overrides file,
a SUBMISSIONS folder that holds no submission for any roster student
(:func:`require_submissions`), and an output folder inside SUBMISSIONS
(:func:`require_out_outside`), where the gradebook would become a submission.

Floor 7 of grader/ (the class run; grader/API.md).
"""

from __future__ import annotations

import hashlib
import json
import os
import shutil
import sys
import threading
import uuid
from collections.abc import Callable, Iterator, Mapping, Sequence
from contextlib import ExitStack, contextmanager, suppress
from dataclasses import dataclass, replace
from functools import partial
from pathlib import Path
from typing import Any

from grader.assignment import (
    Assignment,
    UsageError,
    load_assignment,
    require_assignment_folder,
)
from grader.discover import discover, require_handed_in
from grader.executors import Interrupted
from grader.executors.local import run_local, warm_kernels
from grader.follow_through import FollowThrough
from grader.grade_one import Execute, submission_bytes, ungraded_result, unreadable
from grader.gradebook import gradebook_csv, ran_code
from grader.graded_folder import DOWNLOAD, FEEDBACK, LMS_SUBMISSIONS, PAGES, RESULTS, graded_folder
from grader.lms.classlist import merge_rows
from grader.overrides import check_overrides, read_overrides, without_overrides
from grader.publish import (
    NO_REVIEWS,
    pages_reveal,
    prepare_report,
    records,
    settled,
    stage_record,
    stage_report,
    stage_views,
)
from grader.results import StudentResult, atomic_write_text, read_result
from grader.reviews import Reviews, check_reviews, read_reviews
from grader.submission_file import DEFAULT_MAX_BYTES, InvalidSubmission, read_submission
from grader.submissions import Problem
from grader.transaction import LOCK_WAIT, Transaction, class_lock


@dataclass(frozen=True)
class RunReport:
    """What a run did: every roster student's result (roster order) and what it left alone."""

    results: tuple[StudentResult, ...]
    graded_now: tuple[str, ...]  # ids (re)graded by this run
    unchanged: tuple[str, ...]  # ids whose existing record was kept
    problems: tuple[Problem, ...]  # everything discovery could not use
    notes: tuple[str, ...] = ()  # what matching an LMS download decided (late, newest …)

    @property
    def not_graded(self) -> tuple[str, ...]:
        """Why-lines for every submission that could not be graded (exit status 1)."""
        failed = [f"{r.student_id}: {(r.message or 'failed').splitlines()[0]}"
                  for r in self.results if r.status == "failed"]
        stray = [p.message for p in self.problems if p.student_id is None and not p.ignored]
        return tuple(failed + stray)


# --------------------------------------------------------------------------------------------
# inputs


# --------------------------------------------------------------------------------------------
# one student


# --------------------------------------------------------------------------------------------
# the run


def require_out_outside(out: Path, submissions: Path) -> None:
    """:class:`UsageError` when the output folder is SUBMISSIONS or inside it."""
    inside = Path(os.path.realpath(out)).is_relative_to(os.path.realpath(submissions))
    if inside:
        raise UsageError(f"the output folder {out} is inside the submissions folder "
                         f"{submissions}, where the gradebook would be taken for submissions; "
                         "pass --out DIR outside it")


def require_submissions(submissions: Path, found: Any, ids: Sequence[str]) -> None:
    """:class:`UsageError` when ``found`` (a discovery of ``submissions``) has no submission,
    nor anything else, for any roster student: an empty or wrong folder, not a class where
    nobody handed in (that folder would hold at least one roster name)."""
    if found.submissions or any(p.student_id is not None for p in found.problems):
        return
    if getattr(found, "layout", "folder") != "folder" and found.problems:
        return  # an LMS download whose files matched no one: each is reported, with why
    shown = ", ".join(f"{sid}.ipynb" for sid in ids[:3]) + (", …" if len(ids) > 3 else "")
    strays = [p.path.name for p in found.problems]
    seen = f"; it holds {', '.join(strays[:5])}{', …' if len(strays) > 5 else ''}" \
        if strays else ""
    raise UsageError(f"no submissions found in {submissions}: expected one notebook per "
                     f"student named by roster id, <id>.ipynb or <id>/<notebook>.ipynb "
                     f"({shown}){seen}")


def _unchanged(old: StudentResult | None, sha: str | None, key_hash: str,
               fresh: StudentResult | None = None, sandboxed: bool = False) -> bool:
    if old is None or old.submission_sha256 != sha or old.key_sha256 != key_hash:
        return False
    if old.execution.get("retry"):
        return False  # not the student's doing (a kernel that could not start): grade again
    if old.execution.get("unread"):
        return False  # the key gained answers its notebook was never asked for (rescore)
    if sandboxed and ran_code(old) and not old.sandboxed:
        return False  # graded without a sandbox before: grade it in one now
    return fresh is None or (old.status, old.message) == (fresh.status, fresh.message)


PRELOAD_SCAN_BYTES = 2 * 1024**2
"""Largest submission whose imports :func:`_plan` looks for: that parses the whole notebook, at
up to twelve times its size (text outside the BMP); a larger one runs with what the others'
imports preload (issue 23)."""


def _plan(a: Assignment, found, out: Path, force: bool, sandboxed: bool = False,
          max_bytes: int = DEFAULT_MAX_BYTES):
    """Split the roster: (submissions to execute with their hashes, records to write, kept,
    the packages the ones to execute import).

    Each submission is read once here, safely (:func:`grader.submission_file.read_submission`:
    a regular file under ``max_bytes``), to hash it and to see what its code imports
    (:func:`grader.kernels.preload.packages_imported`: what the zygotes preload); one that is not
    is recorded "invalid submission: <why>"."""
    from grader.kernels.preload import packages_imported
    from grader.notebook_load import json_shape

    to_run, to_write, kept, packages = [], [], [], set()
    problems = {p.student_id: p for p in found.problems if p.student_id is not None}
    by_id = {s.student_id: s for s in found.submissions}
    for sid in a.ids:
        old = None if force else read_result(out / RESULTS / f"{sid}.json")
        expected, key_hash = a.expected(sid), a.key_hash(sid)
        if sid in by_id:
            try:
                data = read_submission(by_id[sid].path, max_bytes)
            except (OSError, InvalidSubmission) as e:
                fresh = ungraded_result(sid, "failed", unreadable(by_id[sid].path, e), expected,
                                        key_hash)
                if _unchanged(old, None, key_hash, fresh):
                    kept.append(sid)
                else:
                    to_write.append(fresh)
                continue
            sha = hashlib.sha256(data).hexdigest()
            if _unchanged(old, sha, key_hash, sandboxed=sandboxed):
                kept.append(sid)
            else:
                to_run.append((by_id[sid], expected, key_hash, sha, a.parameters(sid)))
                if len(data) <= PRELOAD_SCAN_BYTES and json_shape(data) is None:
                    packages |= packages_imported(data)
            continue
        fresh = (ungraded_result(sid, "failed", problems[sid].message, expected, key_hash)
                 if sid in problems else
                 ungraded_result(sid, "missing", "no submission", expected, key_hash))
        if _unchanged(old, None, key_hash, fresh):
            kept.append(sid)
        else:
            to_write.append(fresh)
    return to_run, to_write, kept, packages


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
    class_list: Sequence[Mapping[str, str]] = (),
    cluster: str | None = None,
    wait: float = LOCK_WAIT,
    yes: bool = False,
    times: Path | None = None,
    early: Any = None,
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
        (:class:`grader.kernels.pool.KernelPool`, one slot per job).
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
    class_list : sequence of dict, optional
        Rows of an LMS class list (``grade --roster``) whose columns are added to the
        roster's, by student id, to match an LMS download (:func:`grader.lms.classlist.merge_rows`).
    wait : float
        Seconds to wait for another command holding the output folder (default
        :data:`grader.transaction.LOCK_WAIT`).
    times : Path, optional
        ``--times FILE``: when each submission came in (CSV ``id,submitted_at``), for those
        an LMS download does not say (:mod:`grader.late`).
    early : grader.kernels.pool.KernelPool, optional
        The run's first zygote, started before anything was read
        (:func:`grader.kernels.early.early_pool`): the warm pool, when the run has one in
        that sandbox (its owner closes it otherwise).
    cluster : str, optional
        Grade on a Dask cluster (:mod:`grader.executors.dask`): a scheduler address
        (``tcp://HOST:PORT``) or ``local:N`` (a LocalCluster of N workers); ``jobs`` is then
        unused (each worker grades as many at once as it has threads) and the sandbox is
        that of each worker's machine.
    yes : bool
        Grade a SUBMISSIONS folder that is the assignment's ``release/`` or ``solutions/``, or
        a copy of one, all the same (:func:`grader.discover.require_handed_in`).

    Raises
    ------
    UsageError
        Missing or unreadable inputs, no sandbox to be had (with ``sandbox``), a bad key or
        overrides file: nothing written; :class:`RunInProgress` when another command holds
        the output folder for longer than ``wait``.
    """
    if cluster is not None:
        _require_cluster(cluster)
    require_assignment_folder(hw)  # before the output folder is made in it
    submissions, archive = _submissions_input(Path(submissions))
    out = graded_folder(hw, out)
    require_out_outside(out, submissions)
    if limits is None:
        from grader.limits import Limits

        limits = Limits()
    made = _make_out(out)
    with _unmade_on(UsageError, made), \
            class_lock(out, Path(hw), command="eulertop grade", wait=wait), \
            ExitStack() as stack:
        a, overrides, reviews = _checked_state(Path(hw), out)
        rows = merge_rows(a.rows, class_list)
        found = None if archive else _discovered(submissions, a, rows)
        if not archive:
            require_handed_in(hw, submissions, found, yes)
        own_execute = execute is None  # not one a test or a benchmark injected
        execute, isolation, warm, sandboxed = _choose_executor(execute, cold_kernels, sandbox,
                                                               cluster)
        if getattr(isolation, "tier", None) == "container":
            # kernels run as other users of this machine: nothing of ours for them
            isolation.private_folders(stack, hw, submissions, out)
        if archive:  # entries refused one by one: their owners' invalid submissions
            submissions, found = _unpacked(submissions, out, a, rows)
        to_run, to_write, kept, packages = _plan(a, found, out, force, sandboxed,
                                                 submission_bytes(limits))
        writer = _Writer(a, out, overrides, reveal, progress,
                         _submission_times(a, found, times), reviews)
        stack.callback(writer.close)
        from grader.kernels.preload import preload_for

        jobs = jobs or os.cpu_count() or 1
        # the kernels' zygotes start first: they import while this process writes
        with warm_kernels(warm and bool(to_run) and cluster is None, min(jobs, len(to_run)),
                          isolation, preload_for(packages), early=early,
                          work=len(to_run) + 1) as f:  # + the preflight's kernel
            if to_run and cluster is None:
                prepare_report()  # while the zygotes import: the preflight waits for them
            run = execute if f is None else partial(execute, kernel_factory=f)
            if own_execute and to_run and cluster is None:
                preflight(run, limits)  # before anything of the class is written
            _lms_submissions(found, submissions, out)
            if on_plan is not None:
                writer.progress = on_plan(len(to_run) + len(to_write)) or progress
            for result in to_write:
                writer(result)
            try:
                _execute_all(to_run, run, execute, limits, jobs, writer, cluster,
                             sandbox=sandbox, cold=cold_kernels, preload=preload_for(packages))
            except KeyboardInterrupt:
                writer.finish(found, kept, views_only=True)
                raise
        results = writer.finish(found, kept)
    return RunReport(tuple(results[s] for s in a.ids), writer.graded, tuple(kept),
                     found.problems, found.notes)


def _submissions_input(submissions: Path) -> tuple[Path, bool]:
    """``(submissions, whether it is a .zip download)``; :class:`UsageError` when it is neither
    a readable folder nor a .zip file."""
    archive = submissions.suffix.lower() == ".zip" and submissions.is_file()
    if not archive and (not submissions.is_dir()
                        or not os.access(submissions, os.R_OK | os.X_OK)):
        raise UsageError(f"{submissions}: not a readable folder of submissions (nor a .zip)")
    return submissions, archive


def _checked_state(hw: Path, out: Path) -> tuple[Assignment, tuple, Reviews]:
    """The assignment, the overrides and the reviews as they are now (under the lock), each
    checked: a bad key, override or review stops the run before anything is written."""
    a = load_assignment(hw)
    a.check_key()
    overrides = read_overrides(out)
    check_overrides(a, overrides)
    reviews = read_reviews(out)
    check_reviews(a, reviews)
    return a, overrides, reviews


def _discovered(submissions: Path, a: Assignment, rows: Sequence[Mapping[str, str]],
                refused: Mapping[Path, str] | None = None):
    """What ``submissions`` holds for ``a``'s roster (:func:`grader.discover.discover`);
    :class:`UsageError` when nothing of the class is there (:func:`require_submissions`)."""
    found = discover(submissions, a.ids, rows, refused)
    require_submissions(submissions, found, a.ids)
    return found


def _unpacked(archive: Path, out: Path, a: Assignment, rows: Sequence[Mapping[str, str]]):
    """A downloaded ``.zip`` extracted into ``OUT/download`` and discovered there."""
    folder, refused = _unpack(archive, out)
    return folder, _discovered(folder, a, rows, refused)


def _lms_submissions(found: Any, submissions: Path, out: Path) -> None:
    """``OUT/submissions.csv`` for an LMS download; removed for a folder (a previous run's
    table would describe other files)."""
    if found.layout != "folder":
        atomic_write_text(out / LMS_SUBMISSIONS, gradebook_csv(_lms_table(found, submissions)))
    else:
        (out / LMS_SUBMISSIONS).unlink(missing_ok=True)


def _execute_all(to_run, run, execute, limits, jobs, writer, cluster, *, sandbox: bool,
                 cold: bool, preload) -> None:
    """Run every planned submission, here or on the cluster; ``writer`` records each."""
    if cluster is not None:
        _run_on_cluster(cluster, to_run, execute, limits, writer, sandbox=sandbox, cold=cold,
                        preload=preload)
        return
    run_local(to_run, run, limits, jobs, writer)


class _Writer:
    """The one writer of a grading run's records: each settled (follow-through credit, then the
    overrides: :func:`grader.publish.settled`) and committed with its feedback page and its
    line of the audit trail, one at a time (the executors call it from several threads); at
    the end, the views and the run's own line (:meth:`finish`)."""

    def __init__(self, a: Assignment, out: Path, overrides: Sequence[Any], reveal: bool,
                 progress: Callable[[StudentResult], None] | None,
                 times: Mapping[str, dict], reviews: Reviews = NO_REVIEWS) -> None:
        self.a, self.out, self.overrides, self.reveal = a, out, tuple(overrides), reveal
        self.reviews = reviews
        self.progress, self.times = progress, times
        self.follow = FollowThrough.of(a)
        self.before = records(a, out)
        self.run = uuid.uuid4().hex  # names the run's lines in the trail
        self.graded: tuple[str, ...] = ()
        self._lock = threading.Lock()
        # pages of both kinds until finish() writes every one: what they show is not known then
        self._mixes = pages_reveal(out) not in (None, reveal)

    def __call__(self, result: StudentResult) -> None:
        result = replace(result, submitted=self.times.get(result.student_id, {}))
        result = settled(self.a, result, self.follow, self.overrides, self.reviews)
        with self._lock:
            tx = Transaction(self.out)
            stage_record(tx, self.a, self.out, result, self.reveal)
            if self._mixes:
                tx.remove(self.out / PAGES)
                self._mixes = False
            tx.trail("graded", [_graded_change(self.before.get(result.student_id), result)],
                     why="eulertop grade", run=self.run)
            tx.commit()
            self.graded += (result.student_id,)
        if self.progress:
            self.progress(result)  # the points as recorded: credit and overrides in

    def close(self) -> None:
        if self.follow is not None:
            self.follow.close()  # its worker, if one was started

    def finish(self, found: Any, kept: Sequence[str],
               views_only: bool = False) -> dict[str, StudentResult | None]:
        """The records kept with today's overrides, the gradebook, the pages and (unless
        ``views_only``: an interrupted run) the report, and the run's line, as one
        transaction; every record as it now is."""
        tx = Transaction(self.out)
        results = records(self.a, self.out)
        rewritten = _resettled(tx, self.a, self.out, results, kept,
                               (self.overrides, self.reviews), self.times, self.reveal)
        stage_views(tx, self.a, self.out, results, self.reveal,
                    published=set(self.graded) | set(rewritten))
        notebooks = {s.student_id: s.path for s in found.submissions}
        if not views_only:
            stage_report(tx, self.a, self.out, results, notebooks)
        tx.trail("grade" if not views_only else "grade interrupted",
                 [_graded_change(self.before.get(sid), results[sid]) for sid in rewritten],
                 why="eulertop grade", run=self.run, graded=len(self.graded), kept=len(kept),
                 notebooks={sid: str(Path(p).resolve()) for sid, p in notebooks.items()})
        tx.commit()
        return results


def _resettled(tx: Transaction, a: Assignment, out: Path,
               results: dict[str, StudentResult | None], kept: Sequence[str],
               amended: tuple[Sequence[Any], Reviews], times: Mapping[str, dict],
               reveal: bool) -> tuple[str, ...]:
    """The records kept unchanged by this run with the reviews, the overrides (``amended``),
    the late policy and the submission times as they are now (an override added or taken back
    since they were written, a deadline moved, a time now known), staged into ``tx`` and put
    into ``results``; their ids."""
    overrides, reviews = amended
    rewritten = []
    for sid in kept:
        record = results.get(sid)
        if record is None:
            continue
        was = without_overrides(replace(record, submitted=times.get(sid, record.submitted)))
        now = settled(a, was, None, overrides, reviews)
        if now != record:
            stage_record(tx, a, out, now, reveal)
            results[sid] = now
            rewritten.append(sid)
    return tuple(rewritten)


def _submission_times(a: Assignment, found: Any, times: Path | None) -> dict[str, dict]:
    """When each submission came in (:mod:`grader.late`): the LMS download's time where it
    gives one, else ``--times FILE``'s; :class:`UsageError` naming the row or file of a time
    that cannot be read."""
    from grader.late import download_time, read_times

    policy = a.manifest.get("late")
    zone = (policy or {}).get("zone")
    given = read_times(times, set(a.ids), zone) if times is not None else {}
    for s in found.submissions:
        if not s.submitted_at:
            continue
        try:
            given[s.student_id] = download_time(s.submitted_at, s.time_source,
                                                f"{s.student_id}: {s.time_source}", zone)
        except UsageError:
            if policy is not None:  # without a policy there is nothing to apply it to
                raise
    return given


def _graded_change(old: StudentResult | None, new: StudentResult) -> dict:
    """The audit trail's change of one student graded: their total before → after."""
    return {"student": new.student_id, "answer": "total",
            "before": None if old is None else old.points, "after": new.points,
            "why": new.status if old is None else f"regraded ({new.status})"}


def _unpack(archive: Path, out: Path) -> tuple[Path, dict[Path, str]]:
    """A downloaded ``.zip`` extracted, with its checks, into ``OUT/download``: that folder,
    and the entries refused one by one (:class:`grader.lms.archive.Extraction`)."""
    from grader.lms.archive import ArchiveError, extract_download

    try:
        extraction = extract_download(archive, out / DOWNLOAD)
    except ArchiveError as e:
        raise UsageError(f"{archive}: {e}") from None
    return extraction.folder, extraction.refused


def _lms_table(found: Any, root: Path) -> list[list[str]]:
    """``OUT/submissions.csv``: :func:`grader.lms.download.submissions_table`."""
    from grader.lms.download import submissions_table

    return submissions_table(found, root)


WITHOUT_SANDBOX = ("eulertop grade: WARNING: grading WITHOUT a sandbox (--no-sandbox): student "
                   "code runs as you and can read the answer key, other submissions and your "
                   "files, and reach the network; every result record and grades.csv say so\n")


def _choose_executor(execute: Execute | None, cold_kernels: bool, sandbox: bool,
                     cluster: str | None) -> tuple[Execute | None, Any, bool, bool]:
    """How the run executes: ``(execute, the isolation found, warm, sandboxed)``.

    A given ``execute`` (tests, benchmarks) is used as it is, unsandboxed; on a cluster each
    worker finds its own sandbox (``execute`` stays None); otherwise the isolation tier of
    this machine (:func:`_sandbox`) — the container tier with cold kernels of their own uids,
    the others with a warm pool unless ``cold_kernels``."""
    if execute is not None:
        return execute, None, False, False
    if cluster is not None:
        if not sandbox:
            sys.stderr.write(WITHOUT_SANDBOX)  # on the cluster's workers
        return None, None, False, sandbox
    from grader.execute import execute_submission

    found = _sandbox(sandbox)
    if getattr(found, "tier", None) == "container":
        return partial(execute_submission, kernel_factory=found.kernel_factory()), found, \
            False, True
    return partial(execute_submission, sandbox=found is not None), found, not cold_kernels, \
        found is not None


def _sandbox(wanted: bool) -> Any:
    """The run's isolation (:func:`grader.kernels.isolation.choose_tier`: a
    :class:`grader.sandbox.Sandbox` of the ``world`` or ``bwrap-per-kernel`` tier, or the
    ``container`` tier), or None when not ``wanted`` (which warns); :class:`UsageError` with
    the cause and its fix when wanted and there is none."""
    from grader.kernels.isolation import choose_tier
    from grader.sandbox import SandboxUnavailable

    if not wanted:
        sys.stderr.write(WITHOUT_SANDBOX)
        return None
    try:
        found = choose_tier()
    except SandboxUnavailable as err:
        raise UsageError(str(err)) from None
    sys.stderr.write(f"eulertop grade: isolation: {found.describe()}\n")
    return found


class NoKernel(UsageError):
    """The preflight could not run a kernel here (:func:`preflight`)."""


@contextmanager
def _unmade_on(error: type[BaseException], made: Sequence[Path]) -> Iterator[None]:
    """Remove the folders ``made`` (only if empty) when the block raises ``error``."""
    try:
        yield
    except error:
        for p in reversed(made):
            with suppress(OSError):
                p.rmdir()
        raise


def _make_out(out: Path) -> list[Path]:
    """Make the output folder's ``results/`` and ``feedback/``; the folders made now (taken
    back when no kernel can start, :func:`_unmade_on`); :class:`UsageError` when they cannot
    be."""
    made = [p for p in (out, out / RESULTS, out / FEEDBACK) if not p.exists()]
    try:
        for sub in (RESULTS, FEEDBACK):
            (out / sub).mkdir(parents=True, exist_ok=True)
    except OSError as e:
        raise UsageError(f"{out}: cannot create the output folder: {e.strerror}") from None
    return made


PREFLIGHT_CELL = "eulertop_preflight = 6 * 7"


def preflight(run: Execute, limits: Any) -> None:
    """Start one kernel exactly as the students' kernels start (``run``, the run's own
    execution) and run a trivial cell in it, before anything of the class is written: where
    that fails (twice), no kernel can start here — :class:`NoKernel` with what went wrong,
    instead of a failed record per student."""
    from nbformat.v4 import new_code_cell, new_notebook

    from grader.sandbox import fresh_folder, run_folder

    with run_folder() as base:
        folder = fresh_folder(base, "f")
        try:
            path = folder / "preflight.ipynb"
            path.write_text(json.dumps(new_notebook(cells=[new_code_cell(PREFLIGHT_CELL)])),
                            encoding="utf-8")
            for _ in range(2):
                execution = run(path, ["eulertop_preflight"], limits)
                if execution.status == "ok" and \
                        execution.answers.get("eulertop_preflight") == 42:
                    return
        finally:
            shutil.rmtree(folder, ignore_errors=True)
    raise NoKernel(
        "no kernel could start here, so no student was graded and nothing was written: a "
        f"trivial notebook, run as the students' will be, ended with '{execution.status}': "
        f"{execution.message}. Run 'eulertop doctor' for what this machine allows")


def _require_cluster(cluster: str) -> None:
    """:class:`UsageError` when ``--cluster`` cannot be used here (Dask not installed, a
    malformed ``local:N``, a scheduler that cannot be reached), before anything is written."""
    from grader.executors.dask import ClusterError, require_distributed, require_reachable

    try:
        require_distributed()
        require_reachable(cluster)
    except ClusterError as e:
        raise UsageError(str(e)) from None


def _run_on_cluster(cluster, to_run, execute, limits, publish, *, sandbox: bool, cold: bool,
                    preload: Sequence[str] | None = None) -> None:
    """The run on a Dask cluster (:func:`grader.executors.dask.grade_on_cluster`): the workers
    run :func:`grader.grade_one.grade_one`; this process publishes every record, as they come
    back."""
    if not to_run:
        return
    from grader.executors.dask import ClusterError, cluster_client, grade_on_cluster

    published = []
    stop = threading.Event()

    def counted(result: StudentResult) -> None:
        publish(result)
        published.append(result.student_id)

    try:
        with cluster_client(cluster) as client:
            try:
                grade_on_cluster(client, to_run, limits, counted, execute=execute,
                                 sandbox=sandbox, cold=cold, stop=stop, preload=preload)
            except KeyboardInterrupt:
                stop.set()  # in-flight tasks are cancelled when the client closes
                raise Interrupted(len(published), len(to_run)) from None
    except ClusterError as e:
        raise UsageError(str(e)) from None


