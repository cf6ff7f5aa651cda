"""Grading on a Dask distributed cluster: ``eulertop grade HW SUBS --cluster ADDRESS``.

The executor of ``--cluster`` (``grader/API.md``, floor 6: where ``grade_one`` runs): the local pool
runs :func:`grader.grade_one.grade_one` on threads of this machine; this module runs the same
function on the workers of a Dask cluster. Nothing else of a run changes: the grader process
(the Dask *client*) plans the run, holds ``OUT/.lock``, and alone writes result records,
feedback pages and the gradebook, so resume, locking and the reports are those of a local run.

What travels
    Each task carries one student's submission *bytes* (read here, safely, by
    :func:`grader.submission_file.read_submission`), its SHA-256, that student's expected
    answers (:class:`grader.compare.KeyAnswer`, never the whole key) and the limits. Workers
    need no shared filesystem and never see the submissions folder; the bytes are written to a
    private file of the worker's run folder and :func:`grade_one` reads, checks (``sha``),
    copies and grades them as it does locally. It returns ``StudentResult.to_dict()``, which
    the client turns back into the record (exactly: the record round-trips).
Where it runs
    On each worker, a :class:`WorkerKernels` plugin holds a warm :class:`KernelPool` with one
    slot per worker thread, in the sandbox of *that* machine (:func:`grader.sandbox.probe`;
    ``--no-sandbox`` runs unsandboxed there too, and the records say so). A worker with no
    sandbox refuses the task and the run stops with a usage error naming the worker.
Failures
    A student's own failure (time limit, dead kernel, invalid notebook) is in the record and is
    final. The infrastructure's failures are not the student's: a worker that dies mid-task is
    handled by the scheduler (the task runs again elsewhere, up to its ``allowed-failures``,
    then ``KilledWorker``); the client resubmits a task that ended in ``KilledWorker``, a lost
    connection or a cancellation up to :data:`RESUBMIT` times, and a task that raised (a fault
    of the grader, never of the student: ``grade_one`` does not raise) is retried by Dask
    (``retries=``). One that still fails gets a ``failed`` record marked ``{"retry": true}``,
    so the next run grades it again. Each student's record is written once, by the first
    result that comes back.
Flow
    At most :func:`window` tasks are in flight (four per worker thread), so a class of 10⁵ never
    sits in the client's or the scheduler's memory at once; records are written as tasks
    complete (``as_completed``), which is also the progress shown.

``dask[distributed]`` is an optional dependency (``pip install eulertop[cluster]``); this module
imports it only inside functions, and :func:`require_distributed` says what to install.

Floor 6 of grader/ (where grade_one runs; where submissions come from; grader/API.md).
"""

from __future__ import annotations

import hashlib
import logging
import os
import re
import socket
import threading
from collections.abc import Callable, Iterator, Mapping, Sequence
from contextlib import ExitStack, contextmanager
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from grader.compare import KeyAnswer
from grader.results import StudentResult
from grader.submission_file import InvalidSubmission, read_submission
from grader.submissions import Submission

INSTALL = ("--cluster needs Dask distributed, which is not installed: "
           "pip install 'eulertop[cluster]'")
"""The one line ``--cluster`` prints without ``dask[distributed]``."""

RESUBMIT = 3
"""Times the client resubmits a task lost to the infrastructure (KilledWorker, connection)."""

TASK_RETRIES = 1
"""Dask's own ``retries=`` of a task that raised on the worker (a grader fault)."""

CONNECT_SECONDS = 30.0
"""How long to try reaching the scheduler, and to wait for its first worker."""

LOCAL = re.compile(r"local:(\d+)")

try:  # this module is imported only for --cluster; without Dask, require_distributed() says so
    from distributed import WorkerPlugin as _PluginBase
except ImportError:  # pragma: no cover - exercised by the "not installed" test in a subprocess
    _PluginBase = object


class ClusterError(Exception):
    """The cluster cannot be used (not installed, unreachable, no worker, no sandbox there)."""


@dataclass(frozen=True)
class Task:
    """One submission to grade remotely: what :func:`grade_remote` needs, picklable."""

    student_id: str
    file_name: str
    data: bytes
    sha: str
    expected: tuple[KeyAnswer, ...]
    key_hash: str
    parameters: dict = field(default_factory=dict)  # the student's, by notebook variable


def require_distributed() -> None:
    """:class:`ClusterError` with :data:`INSTALL` when ``distributed`` cannot be imported."""
    try:
        import distributed  # noqa: F401
    except ImportError:
        raise ClusterError(INSTALL) from None


def parse_cluster(spec: str) -> int | str:
    """``local:N`` → N (workers of a LocalCluster), a scheduler address → itself.

    Raises
    ------
    ClusterError
        ``local:`` with no positive N, or an empty address.
    """
    spec = spec.strip()
    if spec.startswith("local"):
        match = LOCAL.fullmatch(spec)
        if match is None or int(match.group(1)) < 1:
            raise ClusterError(f"--cluster {spec!r}: expected local:N with N ≥ 1 workers, "
                               "or a scheduler address such as tcp://HOST:8786")
        return int(match.group(1))
    if not spec:
        raise ClusterError("--cluster: expected a scheduler address such as tcp://HOST:8786 "
                           "or local:N")
    return spec


def require_reachable(spec: str) -> None:
    """:class:`ClusterError` unless the scheduler at ``spec`` accepts a TCP connection (checked
    before a run writes anything; ``local:N`` and non-TCP addresses pass)."""
    target = parse_cluster(spec)
    if isinstance(target, int):
        return
    from distributed.comm import parse_address, parse_host_port

    scheme, location = parse_address(target)
    if scheme not in ("tcp", "tls"):
        return
    try:
        host, port = parse_host_port(location)
        socket.create_connection((host, port), timeout=CONNECT_SECONDS).close()
    except (OSError, ValueError, TypeError) as e:
        raise ClusterError(f"cannot reach the Dask scheduler at {target}: "
                           f"{getattr(e, 'strerror', None) or e}") from None


@contextmanager
def cluster_client(spec: str) -> Iterator[Any]:
    """A ``distributed.Client`` of ``spec`` (:func:`parse_cluster`), closed at the end.

    ``local:N`` starts a LocalCluster of N worker processes, one thread each, here; an address
    connects to a running scheduler, which must have at least one worker within
    :data:`CONNECT_SECONDS`.
    """
    require_distributed()
    target = parse_cluster(spec)
    from distributed import Client, LocalCluster

    with ExitStack() as stack:
        if isinstance(target, int):
            cluster = stack.enter_context(LocalCluster(
                n_workers=target, threads_per_worker=1, processes=True,
                dashboard_address=None, silence_logs=logging.ERROR))
            client = stack.enter_context(Client(cluster))
        else:
            try:
                client = stack.enter_context(Client(target, timeout=CONNECT_SECONDS))
            except (OSError, TimeoutError, ValueError) as e:
                raise ClusterError(f"cannot reach the Dask scheduler at {target}: "
                                   f"{e or type(e).__name__}") from None
            try:
                client.wait_for_workers(1, timeout=CONNECT_SECONDS)
            except (OSError, TimeoutError) as e:
                raise ClusterError(f"the Dask scheduler at {target} has no worker after "
                                   f"{CONNECT_SECONDS:g} s (start some: dask worker {target})"
                                   ) from e
        yield client


# --------------------------------------------------------------------------------------------
# on the worker


PRELOAD_MARK = "-preload:"


def plugin_name(sandbox: bool, cold: bool, preload: Sequence[str] | None = None) -> str:
    """The name of the :class:`WorkerKernels` plugin for these settings (a worker keeps one
    per name: a class that preloads other modules gets pools of its own)."""
    return ("eulertop-kernels" + ("" if sandbox else "-unsandboxed") + ("-cold" if cold else "")
            + ("" if preload is None else PRELOAD_MARK + ",".join(preload)))


def _settings(name: str) -> dict[str, Any]:
    """The :class:`WorkerKernels` settings a :func:`plugin_name` stands for."""
    base, _, preload = name.partition(PRELOAD_MARK)
    return {"sandbox": "unsandboxed" not in base, "cold": base.endswith("-cold"),
            "preload": tuple(filter(None, preload.split(","))) if PRELOAD_MARK in name else None}


class WorkerKernels(_PluginBase):
    """A Dask worker plugin: the worker's run folder and warm kernels, for its whole life.

    Made lazily at the first task (a worker with no sandbox fails that task, not its start),
    closed when the worker closes (``teardown``). One :class:`grader.kernels.pool.KernelPool`
    slot per worker thread, in this machine's sandbox unless ``sandbox`` is False.
    """

    def __init__(self, sandbox: bool = True, cold: bool = False,
                 preload: Sequence[str] | None = None) -> None:
        self.sandbox, self.cold = sandbox, cold
        self.preload = None if preload is None else tuple(preload)
        self.name = plugin_name(sandbox, cold, self.preload)

    def setup(self, worker: Any = None) -> None:
        self._lock = threading.Lock()
        self._stack = ExitStack()
        self._slots = max(1, int(getattr(getattr(worker, "state", None), "nthreads", 1) or 1))
        self._ready: tuple[Path, Path, Callable | None] | None = None
        self._found: Any = None

    def teardown(self, worker: Any = None) -> None:
        with self._lock:
            self._ready = None
            self._stack.close()

    def folders(self, warm: bool) -> tuple[Path, Path, Callable | None]:
        """(staging folder, copies folder, kernel factory or None), made at first use; the
        warm kernels at the first task that wants them."""
        with self._lock:
            if self._ready is None:
                from grader.sandbox import fresh_folder, probe, run_folder

                self._found = probe() if self.sandbox else None  # SandboxUnavailable: fails
                run = self._stack.enter_context(run_folder())
                self._ready = (fresh_folder(run, "w"), fresh_folder(run, "s"), None)
            staging, copies, factory = self._ready
            if warm and factory is None and not self.cold:
                from grader.kernels.pool import KernelPool

                pool = self._stack.enter_context(
                    KernelPool(self._slots, sandbox=self._found, preload=self.preload))
                self._ready = (staging, copies, pool.kernel)
            return self._ready


def _plugin(name: str) -> WorkerKernels:
    from distributed import get_worker

    worker = get_worker()
    plugin = worker.plugins.get(name)
    if plugin is None:  # registered before this worker joined and not yet sent: make it here
        plugin = WorkerKernels(**_settings(name))
        plugin.setup(worker)
        worker.plugins[name] = plugin
    return plugin


def grade_remote(task: Task, limits: Any, execute: Callable | None, plugin: str) -> dict:
    """The Dask task: :func:`grader.grade_one.grade_one` of one submission on this worker.

    The bytes are written to a new private file (0600) of the worker's run folder, under the
    submission's own file name, and ``grade_one`` grades that file (checking ``task.sha``);
    the file is removed afterwards. Returns the record's ``to_dict()``.
    """
    import shutil
    from functools import partial

    from grader.grade_one import grade_one
    from grader.sandbox import fresh_folder

    kernels = _plugin(plugin)
    staging, copies, factory = kernels.folders(warm=execute is None)
    if execute is None:
        from grader.execute import execute_submission

        execute = partial(execute_submission, sandbox=kernels.sandbox)
        if factory is not None:
            execute = partial(execute, kernel_factory=factory)
    folder = fresh_folder(staging, "t")
    try:
        path = folder / task.file_name
        fd = os.open(path, os.O_WRONLY | os.O_CREAT | os.O_EXCL | os.O_NOFOLLOW, 0o600)
        with os.fdopen(fd, "wb") as f:
            f.write(task.data)
        result = grade_one(Submission(task.student_id, path), task.expected, task.key_hash,
                           limits, execute, task.sha, copies, task.parameters)
        return result.to_dict()
    finally:
        shutil.rmtree(folder, ignore_errors=True)


# --------------------------------------------------------------------------------------------
# on the client


def window(client: Any) -> int:
    """Tasks kept in flight: four per worker thread (at least 8)."""
    try:
        threads = sum(client.nthreads().values())
    except Exception:
        threads = 1
    return max(8, 4 * threads)


def _infrastructure(err: BaseException) -> bool:
    """Was the task lost to the cluster rather than failed by the grader?"""
    from concurrent.futures import CancelledError

    from distributed import KilledWorker
    from distributed.comm.core import CommClosedError

    return isinstance(err, KilledWorker | CommClosedError | CancelledError | OSError
                      | TimeoutError)


def _fault_record(run: tuple, why: str) -> StudentResult:
    """A ``failed`` record for a submission the cluster could not grade: graded next run."""
    from dataclasses import replace

    from grader.grade_one import ungraded_result

    submission, expected, key_hash, sha, _ = run
    record = ungraded_result(submission.student_id, "failed",
                             f"the grader could not run this notebook ({why})", expected,
                             key_hash)
    return replace(record, submission_sha256=sha, execution={"retry": True})


def _unreadable(run: tuple, err: Exception) -> StudentResult:
    """The record :func:`grade_one` gives a submission it cannot read (its wording)."""
    from grader.grade_one import ungraded_result, unreadable

    submission, expected, key_hash, _, _ = run
    return ungraded_result(submission.student_id, "failed", unreadable(submission.path, err),
                           expected, key_hash)


def grade_on_cluster(
    client: Any,
    to_run: Sequence[tuple[Submission, Sequence[KeyAnswer], str, str | None]],
    limits: Any,
    publish: Callable[[StudentResult], None],
    *,
    execute: Callable | None = None,
    sandbox: bool = True,
    cold: bool = False,
    stop: threading.Event | None = None,
    preload: Sequence[str] | None = None,
) -> int:
    """Grade ``to_run`` (the pipeline's plan) on the cluster of ``client``; the count published.

    Parameters
    ----------
    client : distributed.Client
    to_run : sequence of (Submission, expected answers, key hash, sha256, parameters)
    limits : grader.limits.Limits
    publish : callable
        Writes one record (and shows progress); called here, in the client, once per student.
    execute : callable, optional
        Replaces execution on the workers (must be importable there); default: the workers'
        warm kernels, in their sandbox unless ``sandbox`` is False.
    cold : bool
        Start every kernel from scratch on the workers (``--cold-kernels``).
    stop : threading.Event, optional
        Set to stop submitting (Ctrl-C is handled by the caller).
    preload : sequence of str, optional
        What the workers' zygotes import (:func:`grader.kernels.preload.preload_for`: what the
        class's notebooks import); default: the zygote's own default.

    Raises
    ------
    ClusterError
        A worker has no sandbox, or cannot import eulertop.
    """
    from distributed import as_completed

    plugin = WorkerKernels(sandbox, cold, preload)
    _register(client, plugin)
    run = _ClusterRun(client, list(reversed(to_run)), limits, publish, execute, plugin.name,
                      stop)
    return run.grade(as_completed([]))


Planned = tuple[Submission, Sequence[KeyAnswer], str, str | None, Mapping[str, Any]]
"""One submission of the pipeline's plan: (submission, expected answers, key hash, sha256, the
student's parameters by notebook variable)."""


class _ClusterRun:
    """The state of one :func:`grade_on_cluster`: the submissions still to send (``pending``,
    last first), those in flight (``by_key``: Dask key → run), each student's attempts, the
    students published, and the window of tasks in flight."""

    def __init__(self, client: Any, pending: list[Planned], limits: Any,
                 publish: Callable[[StudentResult], None], execute: Callable | None,
                 plugin: str, stop: threading.Event | None) -> None:
        from grader.grade_one import submission_bytes

        self.client, self.pending, self.limits, self.publish = client, pending, limits, publish
        self.execute, self.plugin, self.stop = execute, plugin, stop
        self.max_bytes = submission_bytes(limits)
        self.by_key: dict[str, Planned] = {}
        self.attempts: dict[str, int] = {}
        self.done: set[str] = set()
        self.published = 0
        self.limit = window(client)

    @property
    def stopping(self) -> bool:
        return self.stop is not None and self.stop.is_set()

    def grade(self, completed: Any) -> int:
        """Send the submissions through ``completed`` (a Dask ``as_completed``), publishing
        each student's first record; the count published."""
        self.fill(completed, 1)
        for finished, future in enumerate(completed, start=1):
            run = self.by_key.pop(future.key)
            record = self.outcome(future, run, completed, finished)
            if record is None or self.stopping:
                continue
            if run[0].student_id not in self.done:  # one record per student, the first back
                self.record(run[0].student_id, record)
            if not self.stopping:
                self.fill(completed, finished)
        return self.published

    def fill(self, completed: Any, finished: int) -> None:
        """Top up to the window; it is looked up again now and then, since workers may come
        and go during a run (dask-jobqueue's scale or adapt)."""
        if finished % 32 == 0:
            self.limit = window(self.client)
        while len(self.by_key) < self.limit and self.submit_next(completed):
            pass

    def submit_next(self, completed: Any) -> bool:
        """Send the next readable submission (publishing the record of each unreadable one on
        the way); False when none is left."""
        while self.pending:
            run = self.pending.pop()
            data = self.read(run)
            if data is not None:
                self.submit(run, data, completed)
                return True
        return False

    def read(self, run: Planned) -> bytes | None:
        """The submission's bytes, or None once its unreadable record is published."""
        try:
            return read_submission(run[0].path, self.max_bytes)
        except (OSError, InvalidSubmission) as e:
            self.record(run[0].student_id, _unreadable(run, e))
            return None

    def submit(self, run: Planned, data: bytes, completed: Any) -> None:
        """One :class:`Task` to the cluster, under a key of its own."""
        submission, expected, key_hash, sha, parameters = run
        sha = sha or hashlib.sha256(data).hexdigest()
        task = Task(submission.student_id, submission.path.name, data, sha, tuple(expected),
                    key_hash, dict(parameters))
        future = self.client.submit(grade_remote, task, self.limits, self.execute, self.plugin,
                                    pure=False, retries=TASK_RETRIES,
                                    key=f"eulertop-grade-{submission.student_id}-"
                                        f"{os.urandom(4).hex()}")
        self.by_key[future.key] = (submission, expected, key_hash, sha, parameters)
        completed.add(future)

    def outcome(self, future: Any, run: Planned, completed: Any, finished: int
                ) -> StudentResult | None:
        """The record a finished task gives; None when it was lost to the infrastructure and
        sent again. :class:`ClusterError` when a worker has no sandbox or no eulertop."""
        from grader.sandbox import SandboxUnavailable

        try:
            return StudentResult.from_dict(future.result())
        except SandboxUnavailable as e:
            raise ClusterError(f"a worker of the cluster has no sandbox: {e}") from None
        except ModuleNotFoundError as e:
            raise ClusterError(f"a worker of the cluster cannot import {e.name!r}: install "
                               "eulertop (the same version) on every worker") from None
        except BaseException as e:
            if isinstance(e, KeyboardInterrupt | SystemExit):
                raise
            if self.resubmitted(run, e, completed, finished):
                return None
            return _fault_record(run, f"{type(e).__name__}: {e}"[:300])
        finally:
            future.release()

    def resubmitted(self, run: Planned, err: BaseException, completed: Any, finished: int) -> bool:
        """Send ``run`` again if ``err`` is the infrastructure's and its attempts allow."""
        sid = run[0].student_id
        self.attempts[sid] = self.attempts.get(sid, 0) + 1
        if not _infrastructure(err) or self.attempts[sid] > RESUBMIT or self.stopping:
            return False
        self.pending.append(run)
        self.fill(completed, finished)
        return True

    def record(self, student_id: str, record: StudentResult) -> None:
        """Publish a student's record (once: the student is then done)."""
        self.done.add(student_id)
        self.publish(record)
        self.published += 1


def _register(client: Any, plugin: WorkerKernels) -> None:
    """Install ``plugin`` on every worker, present and future. One already registered under
    the same name (an earlier run's, same settings) is kept: registering again would close its
    warm kernels, perhaps under another run on the same cluster."""
    name = plugin.name

    def registered(dask_scheduler: Any) -> bool:
        return name in getattr(dask_scheduler, "worker_plugins", {})

    try:
        if client.run_on_scheduler(registered):
            return
    except Exception:  # a scheduler that refuses run_on_scheduler: register anyway
        pass
    client.register_plugin(plugin, name=name)
