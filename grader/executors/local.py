"""The local executor (floor 6): ``jobs`` threads grading on this machine, with a warm pool of
kernels (:class:`grader.kernels.pool.KernelPool`); every record handed back to the run
(``publish``) as soon as it is made.

Floor 6 of grader/ (where grade_one runs; where submissions come from; grader/API.md).
"""

from __future__ import annotations

import threading
from collections.abc import Callable, Iterator, Sequence
from concurrent.futures import ThreadPoolExecutor, wait
from contextlib import contextmanager
from typing import Any

from grader.executors import Interrupted
from grader.grade_one import copies_folder, grade_one
from grader.results import StudentResult


@contextmanager
def warm_kernels(warm: bool, slots: int, sandbox: Any = None,
                 preload: Sequence[str] | None = None, early: Any = None,
                 work: int | None = None) -> Iterator[Callable | None]:
    """The kernel factory of the run: a warm pool's (closed at the end), or None (default);
    its zygotes import ``preload`` (:func:`grader.kernels.preload.preload_for`). ``early``:
    a pool started before the class was read (:func:`grader.kernels.early.early_pool`), used
    when it is in the run's sandbox and closed in the background at the end (its owner's
    close waits for that), else left to its owner to close. ``work``:
    the kernels the run will ask for, if known (:meth:`KernelPool.expect`)."""
    if not warm:
        yield None
        return
    from grader.kernels.pool import KernelPool
    from grader.sandbox import run_folder

    with run_folder():
        if early is not None and early.sandbox is sandbox and not early.cold:
            early.plan(slots, preload, work)
            try:
                yield early.kernel
            except BaseException:
                early.close()
                raise
            early.close_soon()  # while the run writes its report; its owner waits for it
            return
        with KernelPool(slots, sandbox=sandbox, preload=preload) as pool:
            pool.expect(work)
            yield pool.kernel


Task = tuple  # (Submission, expected key answers, key hash, submission's SHA-256, parameters)


def run_local(to_run: Sequence[Task], execute: Callable, limits: Any, jobs: int,
              publish: Callable[[StudentResult], None]) -> None:
    """Grade ``to_run`` (:func:`grader.grade_one.grade_one`) on ``jobs`` threads;
    ``publish(record)`` as each is made, from its worker. Ctrl-C: nothing new starts, nothing
    in flight is published, :class:`grader.executors.Interrupted` says how many were."""
    if not to_run:
        return
    stop = threading.Event()
    published = []

    def work(submission, expected, key_hash, sha, parameters):
        if stop.is_set():
            return
        result = grade_one(submission, expected, key_hash, limits, execute, sha, copies,
                           parameters)
        if stop.is_set():
            return  # stopped by Ctrl-C while it ran: no record, the next run grades it
        publish(result)
        published.append(result.student_id)

    with copies_folder() as copies:
        pool = ThreadPoolExecutor(max_workers=jobs, thread_name_prefix="eulertop-grade")
        futures = [pool.submit(work, *task) for task in to_run]
        try:
            wait(futures)
        except KeyboardInterrupt:
            # Ctrl-C: start nothing new and keep nothing of what is in flight; the caller's
            # closing of the kernel pool stops those kernels (a second Ctrl-C exits at once)
            stop.set()
            pool.shutdown(wait=False, cancel_futures=True)
            raise Interrupted(len(published), len(to_run)) from None
        pool.shutdown()
        for f in futures:
            f.result()  # a fault in publishing (disk full …) must not pass silently
