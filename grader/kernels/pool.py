"""Warm kernels: one fresh kernel process per submission, forked from a pre-imported zygote.

A cold kernel (:class:`grader.kernels.local.LocalKernel`) spends about a second of CPU importing
ipykernel, IPython, numpy, scipy and sympy before it runs a line of the submission; on two
cores that alone caps the grader near nbgrader's speed. Here each worker slot owns a *zygote*
(:mod:`grader.kernels.zygote`), a server that has done those imports once; a kernel is a ``fork`` of
it, which starts in milliseconds with the modules already in (copy-on-write) memory. Every
submission still gets its own new process — fork semantics: a child that changes a module it
inherited changes its own copy only — in its own session, with its own private working and
control folders, limits and environment. While submission *k* runs in a slot, the kernel
for submission *k + 1* is forked and initialises (``prewarm``): it does not depend on the
submission until the submission is moved into its (until then empty) working folder.

:class:`KernelPool` is the ``kernel_factory`` of :func:`grader.execute.execute_submission`:
``pool.kernel(workdir, control, limits) -> PooledKernel``. A pooled kernel is not a Jupyter
kernel: it runs its cells in the IPython shell the zygote made (:mod:`grader.kernels.cell_server`),
and the grader talks to it over one Unix socket in its control folder
(:mod:`grader.kernels.channel`) — same cells, same error lines, same answers and limits as a cold
ipykernel (``tests/grader/test_cell_server.py`` runs both), at a fraction of the CPU. Launch,
interrupt, kill and the exit status go through the zygote.

Why one zygote per slot (and not one per run), and how issue 5's sandbox fits
    Issue 5 puts every kernel in a bubblewrap sandbox: read-only system and Python, a private
    writable folder, its own network and PID namespaces, resource limits. A forked kernel
    cannot be wrapped in ``bwrap`` after the fact, so the sandbox must already surround the
    zygote: :func:`zygote_command` is the one seam — issue 5 prefixes it with ``bwrap
    --unshare-all --die-with-parent --new-session --ro-bind`` (system, interpreter) ``--bind
    SLOT SLOT`` (the slot's folder, :attr:`Slot.folder`, where every kernel folder of the slot
    is made). Per slot, because then

    * with prewarm off (``KernelPool(prewarm=False)``), a slot's kernels never coexist: kernel
      *k* is killed — its process group, and every leftover, found because the zygote is a
      child subreaper — before kernel *k + 1* is forked. The per-slot ``bwrap`` alone then
      isolates every kernel from every other (other slots are other sandboxes). Issue 5 can
      ship on this with no more than the wrapped command;
    * with prewarm on, kernel *k* and the idle, prewarmed *k + 1* share the slot's sandbox,
      but never a world: each forked child makes its own namespaces before it runs anything
      (:mod:`grader.sandbox.world`, issue 11), so *k* can neither see nor reach *k + 1* — not
      its process, not its sockets, not its folders;
    * a kernel that kills or stops its zygote harms only its own slot: the kernel dies with its
      zygote (``PR_SET_PDEATHSIG``; that student's "kernel died" is their own doing), the slot
      starts a new zygote on its next kernel, and the other slot runs on;
    * pids differ inside a PID namespace, so the grader never signals a kernel itself: it asks
      the slot's zygote (:meth:`Zygote.request` ``signal`` / ``kill``), which also reports each
      kernel's exit status.

Nothing secret in a zygote
    It is started before any submission is read, from a script that imports nothing of the
    grader, with the scrubbed kernel environment (so its ``/proc/<pid>/environ``, which a
    forked child shares, holds nothing of the grader's), and only ever receives paths and the
    limits of the kernel it is asked to fork. It never holds the key, results or submissions.

Residual risks, and the sandbox (issues 5 and 11)
    Without a sandbox (``KernelPool(sandbox=None)``, ``eulertop grade --no-sandbox``), every
    kernel runs as the grader's user: it can signal (not ptrace: both the zygote and kernels
    are non-dumpable) the zygote and the other slot's kernel, and read any folder the user can
    — the cold path has the same exposure. With ``sandbox=`` (:mod:`grader.sandbox`, the
    grader's default) each slot's zygote runs in ``bwrap`` (:meth:`Zygote.__init__`), every
    kernel in a world of its own, and the submission is handed over by the zygote
    (``deliver``), as root and as an ordinary user alike.

Fallback
    Where ``fork`` is unavailable (not Linux) or a zygote cannot be started, kernels are cold
    (:class:`grader.kernels.local.LocalKernel`); ``eulertop grade --cold-kernels`` asks for that.

Floor 2 of grader/ (one kernel; grader/API.md).
"""

from __future__ import annotations

import asyncio
import base64
import contextlib
import json
import math
import os
import queue
import shutil
import signal
import socket
import subprocess
import sys
import threading
import time
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from grader.kernels.base import kernel_environment
from grader.kernels.channel import SOCKET_NAME, CellChannel, listen
from grader.kernels.local import LocalKernel
from grader.limits import Limits
from grader.sandbox import (
    SCRATCH,
    TOOLS,
    Sandbox,
    fresh_folder,
    run_folder,
    slot_uid,
    spawn,
)

__all__ = [
    "CPU_MARGIN",
    "FILE_BYTES",
    "PROCESSES",
    "KernelPool",
    "PooledKernel",
    "Slot",
    "Zygote",
    "ZygoteError",
    "child_limits",
    "fork_available",
    "zygote_command",
]

ZYGOTE_SCRIPT = Path(__file__).with_name("zygote.py")
WORLD_FILES = tuple(Path(__file__).parent.parent / "sandbox" / f
                    for f in ("world.py", "seccomp.py"))
"""Bound beside the zygote in the sandbox: each kernel's own namespaces and seccomp filter."""
CELL_SERVER = Path(__file__).with_name("cell_server.py")
"""What a forked kernel runs (:mod:`grader.kernels.cell_server`); bound beside the zygote."""

ZYGOTE_START_TIMEOUT = 60.0
"""Seconds a zygote may take to import its modules (a loaded machine: several seconds)."""

REQUEST_TIMEOUT = 10.0
"""Seconds a zygote may take to answer a request (a stopped zygote is then replaced)."""

CPU_MARGIN = 10
"""CPU seconds a kernel may use beyond the whole-notebook time limit (``RLIMIT_CPU``)."""

FILE_BYTES = 64 * 1024**2
"""Largest file a kernel may write (``RLIMIT_FSIZE``), bytes."""

PROCESSES = 64
"""Processes/threads a kernel may add to those its user has (``RLIMIT_NPROC``)."""


EARLY_PRELOAD = ("IPython", "numpy")
"""What the zygote of a pool started ``early`` imports before the class is known: what every
class's kernels have (:func:`grader.kernels.preload.preload_for` always gives numpy; IPython
is every kernel's shell)."""


class ZygoteError(RuntimeError):
    """A zygote could not be started, died, or did not answer."""


def fork_available() -> bool:
    """Can kernels be forked from a zygote here (Linux: ``fork``, ``prctl``, ``/proc``)?"""
    return sys.platform.startswith("linux") and hasattr(os, "fork") and \
        Path("/proc/self/task").is_dir()


def child_limits(limits: Limits) -> dict[str, int]:
    """The resource limits of a forked kernel (what :mod:`grader.kernels.zygote` applies).

    ``as``: address space, ``limits.memory_bytes``; ``cpu``: CPU seconds, the whole-notebook
    limit plus :data:`CPU_MARGIN`; ``fsize``: :data:`FILE_BYTES`; ``nproc``: :data:`PROCESSES`
    more than the user already has.
    """
    return {"as": limits.memory_bytes, "memory": limits.memory_bytes,
            "cpu": math.ceil(limits.total_timeout) + CPU_MARGIN,
            "fsize": FILE_BYTES, "nproc": PROCESSES}


def zygote_command(die_with_parent: bool = False,
                   preload: Sequence[str] | None = None, marker: str | None = None,
                   remove_own_folder: bool = True, more: bool = False) -> list[str]:
    """The zygote's argv — the seam issue 5's sandbox wraps (module docstring).

    ``preload``: the modules to import before forking (default
    :data:`grader.kernels.zygote.PRELOAD`;
    what ipykernel itself needs to start is always imported). ``marker``: a ``--run=`` argument
    (the run folder's name) that the zygote ignores, so that the zygote and every kernel forked
    from it (same command line) can be found from outside. ``remove_own_folder``: the zygote
    removes its working folder when it ends (not where that folder is the sandbox's tmpfs).
    ``more``: after ``preload`` it waits for the rest of its modules on stdin
    (:meth:`Zygote.preload_more`), before it makes its shell and says it is ready.
    """
    return [sys.executable, str(ZYGOTE_SCRIPT),
            *(["--remove-own-folder"] if remove_own_folder else []),
            *(["--die-with-parent"] if die_with_parent else []),
            *([f"--preload={','.join(preload)}"] if preload is not None else []),
            *(["--preload-more"] if more else []),
            *([f"--run={marker}"] if marker else [])]


class Zygote:
    """The grader's end of one zygote process: requests, replies, exit statuses.

    Parameters
    ----------
    folder : Path
        A new private folder: the zygote's working folder, ``HOME`` and ``TMPDIR``, and its
        log (``zygote-stderr.txt``).
    preload : sequence of str, optional
        Modules to import before forking (:func:`zygote_command`).
    sandbox : grader.sandbox.Sandbox, optional
        Start it inside this sandbox, with ``bind`` (the slot's folder) its one writable folder.
    marker : str, optional
        Put on the zygote's command line (:func:`zygote_command`) and in its environment
        (``EULERTOP_RUN``), and so on every kernel's.
    alone : bool
        In a sandbox of its own for one kernel (the ``bwrap-per-kernel`` tier): ``bind`` (that
        kernel's control folder) is bound read-only, and the zygote's working folder, ``HOME``
        and ``TMPDIR`` are the sandbox's own tmpfs (``folder`` on this machine then only holds
        its log).
    more : bool
        Started before the grader knows what the class imports: after ``preload`` it waits
        for the rest (:meth:`preload_more`).

    Started from :func:`grader.sandbox.spawn`'s long-lived thread, so that its parent-death
    signal (and ``bwrap --die-with-parent``) fires when the grader ends, not when the thread
    that happened to start it does.
    """

    def __init__(self, folder: Path, preload: Sequence[str] | None = None,
                 sandbox: Sandbox | None = None, bind: Path | None = None,
                 marker: str | None = None, uid: int | None = None,
                 alone: bool = False, more: bool = False) -> None:
        self.folder = Path(folder)
        self.folder.mkdir(mode=0o700, parents=True, exist_ok=True)
        if uid is not None and not alone:  # its working folder is its own
            os.chown(self.folder, uid, uid)
        home = Path(SCRATCH) if alone else self.folder
        env = kernel_environment(home, home)
        if marker:
            env["EULERTOP_RUN"] = marker
        argv = zygote_command(die_with_parent=True, preload=preload, marker=marker,
                              remove_own_folder=not alone, more=more)
        outer = env
        if sandbox is not None:  # with the per-kernel world beside it (grader/sandbox/world.py)
            inside = f"{TOOLS}/{ZYGOTE_SCRIPT.name}"
            argv[1] = inside
            argv.append("--world")
            files = {str(ZYGOTE_SCRIPT): inside,
                     **{str(f): f"{TOOLS}/{f.name}" for f in (CELL_SERVER, *WORLD_FILES)}}
            launch = sandbox.command(argv, env, bind or self.folder, home, files=files,
                                     uid=uid, writable=not alone)
            argv, options = launch.argv, launch.popen_options()
            outer = {"PATH": os.defpath, **({"EULERTOP_RUN": marker} if marker else {})}
        else:
            options = {"start_new_session": True}
        with open(self.folder / "zygote-stderr.txt", "wb") as log:
            self.process = spawn(argv, stdin=subprocess.PIPE, stdout=subprocess.PIPE,
                                 stderr=log, env=outer, cwd=self.folder, close_fds=True,
                                 **options)
        self._lock = threading.Lock()  # one writer at a time
        self._changed = threading.Condition()
        self._replies: dict[int, dict] = {}
        self._exits: dict[int, int] = {}
        self._forgotten: set[int] = set()  # released kernels whose exit event is to come
        self.memory_held: dict[int, int] = {}  # kernel pid -> bytes, when killed for memory
        self._seq = 0
        self.ready: dict | None = None
        self.dead = False
        self._reader = threading.Thread(target=self._read, name="eulertop-zygote", daemon=True)
        self._reader.start()

    def _read(self) -> None:
        try:
            for line in self.process.stdout:
                message = json.loads(line)
                with self._changed:
                    if "ready" in message:
                        self.ready = message
                    elif message.get("event") == "exit":
                        pid = int(message["pid"])
                        if pid in self._forgotten:  # released: no one asks any more
                            self._forgotten.discard(pid)
                            continue
                        self._exits[pid] = int(message["status"])
                        if "memory" in message:
                            self.memory_held[pid] = int(message["memory"])
                    elif "seq" in message:
                        self._replies[int(message["seq"])] = message
                    self._changed.notify_all()
        except (OSError, ValueError):
            pass
        finally:
            with self._changed:
                self.dead = True
                self._changed.notify_all()

    def wait_ready(self, timeout: float | None = None) -> None:
        """Block until the zygote has its modules imported (at most ``timeout``, default
        :data:`ZYGOTE_START_TIMEOUT`); :class:`ZygoteError` otherwise."""
        timeout = ZYGOTE_START_TIMEOUT if timeout is None else timeout
        with self._changed:
            self._changed.wait_for(lambda: self.ready is not None or self.dead, timeout)
            ready = self.ready
        if ready is None or not ready.get("ready"):
            tail = self._log_tail()
            self.close(timeout=0.5)
            why = (ready or {}).get("error") or (
                "it ended" if self.dead else f"no answer in {timeout:g} s")
            raise ZygoteError(f"the kernel zygote could not start: {why}{tail}")

    def preload_more(self, modules: Sequence[str]) -> None:
        """The rest of what a zygote started with ``more`` imports before it is ready (one
        line on its stdin; a zygote already gone is replaced when a kernel is asked of it)."""
        with self._lock, contextlib.suppress(OSError, ValueError):
            self.process.stdin.write((json.dumps({"preload": list(modules)}) + "\n").encode())
            self.process.stdin.flush()

    def _log_tail(self) -> str:
        with contextlib.suppress(OSError):
            text = (self.folder / "zygote-stderr.txt").read_text(errors="replace").strip()
            return f" ({text.splitlines()[-1]})" if text else ""
        return ""

    @property
    def alive(self) -> bool:
        """Running and answering (not ended, not known to be stuck)."""
        return not self.dead and self.process.poll() is None

    def request(self, op: str, timeout: float | None = None, **fields: Any) -> dict:
        """Send one request and wait for its reply (at most ``timeout``, default
        :data:`REQUEST_TIMEOUT`); :class:`ZygoteError` if there is none."""
        timeout = REQUEST_TIMEOUT if timeout is None else timeout
        with self._lock:
            self._seq += 1
            seq = self._seq
            try:
                self.process.stdin.write((json.dumps({"seq": seq, "op": op, **fields}) + "\n")
                                         .encode())
                self.process.stdin.flush()
            except (OSError, ValueError) as err:
                raise ZygoteError(f"the kernel zygote is gone ({err})") from None
        with self._changed:
            self._changed.wait_for(lambda: seq in self._replies or self.dead, timeout)
            reply = self._replies.pop(seq, None)
        if reply is None:
            if not self.dead:
                self.close(timeout=0.5)  # stopped or stuck: replace it, and its kernels
            raise ZygoteError(f"the kernel zygote did not answer {op!r}")
        if "error" in reply:  # what the kernel's own start wrote, if anything, says why
            raise ZygoteError(f"the kernel zygote could not {op}: {reply['error']}"
                              f"{self._log_tail()}")
        return reply

    def exit_status(self, pid: int) -> int | None:
        """Kernel ``pid``'s exit status once reaped (negative: a signal); SIGKILL when the
        zygote died before reporting it (its kernels die with it)."""
        with self._changed:
            if pid in self._exits:
                return self._exits[pid]
            return -signal.SIGKILL if self.dead else None

    def forget(self, pid: int) -> None:
        """Drop ``pid``'s exit status (it is no longer asked about), now or when it comes
        (a killed kernel is reaped a little after the kill's reply)."""
        with self._changed:
            if self._exits.pop(pid, None) is None:
                self._forgotten.add(pid)

    def end_input(self) -> None:
        """Close its input: it kills its kernels and leftovers and exits (:meth:`close`
        waits for that)."""
        with contextlib.suppress(OSError, ValueError):
            self.process.stdin.close()

    def kill(self) -> None:
        """End the zygote and all its kernels at once: SIGKILL to PID 1 of its sandbox's PID
        namespace (everything in the namespace dies with it) and to the process started here.
        (Killing that process alone is not enough as root: the sandbox's ``bwrap`` runs as
        another uid, and a change of uid clears the parent-death signal.)"""
        init = _host_pid(self.process.pid, 1)
        for pid in (init, self.process.pid):
            if pid is not None:
                with contextlib.suppress(OSError):
                    os.kill(pid, signal.SIGKILL)

    def close(self, timeout: float = 5.0) -> None:
        """End the zygote: end of input makes it kill its kernels and leftovers and exit."""
        self.end_input()
        try:
            self.process.wait(timeout)
        except subprocess.TimeoutExpired:
            self.kill()  # its kernels follow (PR_SET_PDEATHSIG)
            self.process.wait()
        with self._changed:
            self.dead = True
            self._changed.notify_all()
        with contextlib.suppress(OSError, ValueError):
            self.process.stdout.close()


@dataclass
class _Forked:
    """A kernel forked by a slot's zygote, with its folders and the socket it connects to."""

    zygote: Zygote
    pid: int
    workdir: Path
    control: Path
    listener: socket.socket  # grader.kernels.channel.listen: the kernel connects to it
    limits: Limits
    sandboxed: bool = False  # workdir is inside the sandbox: not a path of this machine
    uid: int | None = None  # the uid of the slot's sandbox (as root)
    watch: MemoryWatch | None = None  # alone in its sandbox: its zygote is its own


class MemoryWatch:
    """The keeper of a kernel alone in its sandbox (the ``bwrap-per-kernel`` tier), from the
    grader: every :data:`grader.sandbox.world.WATCH_INTERVAL` it sums the resident memory of the
    kernel's processes (this machine's ``/proc``; their proportional sizes when the first sum
    is over), and past ``limit`` bytes ends the whole sandbox and records what they held
    (``zygote.memory_held``), as the keeper of a kernel's own world does inside
    (:func:`grader.sandbox.world.keep`). Nothing in the sandbox can reach it."""

    def __init__(self, zygote: Zygote, pid: int, limit: int) -> None:
        self.zygote, self.pid, self.limit = zygote, pid, limit
        self.stopped = threading.Event()
        self.thread = threading.Thread(target=self._run, name="eulertop-memory", daemon=True)
        self.thread.start()

    def _run(self) -> None:
        from grader.sandbox.world import WATCH_INTERVAL, resident_bytes

        kernel = None
        while not self.stopped.wait(WATCH_INTERVAL) and self.zygote.alive:
            kernel = kernel or _host_pid(self.zygote.process.pid, self.pid)
            if kernel is None:
                continue
            used = resident_bytes(kernel)
            if used > self.limit:
                used = resident_bytes(kernel, proportional=True)
            if used > self.limit:
                self.zygote.memory_held[self.pid] = used
                self.zygote.kill()
                return

    def stop(self) -> None:
        self.stopped.set()
        if threading.current_thread() is not self.thread:
            self.thread.join(5)


def _host_pid(launcher: int, inner: int) -> int | None:
    """The pid on this machine of the process that is ``inner`` in the PID namespace of the
    sandbox started as ``launcher`` (the last of its ``NSpid``), or None."""
    from grader.sandbox.world import descendants

    for pid in descendants(launcher):
        with contextlib.suppress(OSError, ValueError, IndexError):
            with open(f"/proc/{pid}/status", "rb") as f:
                line = next(x for x in f if x.startswith(b"NSpid:"))
            ids = line.split()[1:]
            if len(ids) > 1 and int(ids[-1]) == inner and pid != launcher:
                return pid
    return None


class Slot:
    """One worker slot: a zygote, and at most one prewarmed kernel waiting for a submission.

    Sandboxed (``sandbox``), the zygote runs in a ``bwrap`` sandbox whose one writable folder
    is the slot's folder (mode 0711: the sandbox's user reaches the control folders in it, made
    its own, without listing them); as root, as a uid of the slot's own (:func:`slot_uid`).
    Each kernel then hides the slot folder from itself but for its own control folder
    (:mod:`grader.sandbox.world`).
    """

    def __init__(self, folder: Path, preload: Sequence[str] | None = None,
                 sandbox: Sandbox | None = None, marker: str | None = None,
                 start: bool = True, more: bool = False) -> None:
        self.folder = Path(folder)
        self.sandbox, self.marker = sandbox, marker
        self.mode = 0o711 if sandbox is not None else 0o700
        self.uid = slot_uid() if sandbox is not None and sandbox.as_root else None
        self.alone = sandbox is not None and sandbox.per_kernel
        self.folder.mkdir(mode=0o700, parents=True, exist_ok=True)
        os.chmod(self.folder, self.mode)
        self.preload = preload
        self.more = more  # its first zygote waits for the rest of its preload (Zygote)
        self.zygote: Zygote | None = None
        self.waiting: _Forked | None = None
        self._prewarming: threading.Thread | None = None
        self.forks = 0
        self.starts = 0
        self._starting = threading.Lock()
        if not self.alone and start:  # else a zygote per kernel, in a sandbox of its own (fork)
            self.start_zygote()

    def ensure_zygote(self) -> None:
        """Start the slot's zygote unless it has one (alive, or still importing)."""
        with self._starting:
            if self.zygote is None and not self.alone:
                self.start_zygote()

    def start_zygote(self) -> None:
        if self.zygote is not None:
            self.zygote.close()
        self.starts += 1
        self.zygote = Zygote(self.folder / f"z{self.starts}", self.preload, self.sandbox,
                             self.folder, self.marker, self.uid, more=self.more)
        self.more = False  # a zygote started again imports all of its preload at once

    def fork(self, limits: Limits) -> _Forked:
        """Fork a new kernel (restarting a dead zygote first); :class:`ZygoteError`."""
        if self.alone:
            return self._fork_alone(limits)
        with self._starting:
            if self.zygote is None or not self.zygote.alive:
                self.start_zygote()
        self.zygote.wait_ready()
        self.folder.mkdir(mode=0o700, parents=True, exist_ok=True)  # a closed zygote's rmdir
        os.chmod(self.folder, self.mode)
        # short names: a Unix socket's path must fit in 107 bytes (sun_path)
        control = fresh_folder(self.folder, "c")
        sandboxed = self.sandbox is not None
        extra: dict[str, Any] = {}
        uid = None
        if sandboxed:  # its folders in the sandbox's tmpfs (not a path here), its own uid
            scratch = f"{SCRATCH}/{control.name}"
            workdir = Path(scratch) / "work"
            env = kernel_environment(workdir, control)
            env.update(IPYTHONDIR=f"{scratch}/ipython", MPLCONFIGDIR=f"{scratch}/matplotlib")
            extra["scratch"] = scratch
            extra["world"] = {"scratch_bytes": self.sandbox.scratch_bytes}
            uid = self.uid
        else:
            workdir = fresh_folder(self.folder, "w")
            env = kernel_environment(workdir, control)
        rlimits = child_limits(limits)
        listener = None
        try:
            listener = listen(control, uid)
            if uid is not None:
                os.chown(control, uid, uid)
            reply = self.zygote.request(
                "fork", workdir=str(workdir), control=str(control),
                channel=str(control / SOCKET_NAME), env=env, limits=rlimits, **extra)
        except BaseException:
            if listener is not None:
                listener.close()
            if not sandboxed:
                shutil.rmtree(workdir, ignore_errors=True)
            shutil.rmtree(control, ignore_errors=True)
            raise
        self.forks += 1
        return _Forked(self.zygote, int(reply["pid"]), workdir, control, listener, limits,
                       sandboxed, uid)

    def _fork_alone(self, limits: Limits) -> _Forked:
        """The ``bwrap-per-kernel`` tier: a new sandbox whose zygote forks one kernel, with that
        kernel's control folder bound read-only (its socket is bound here first), its folders
        in the sandbox's tmpfs, as root a uid of its own, and its memory watched from here
        (:class:`MemoryWatch`)."""
        control = fresh_folder(self.folder, "c")
        uid = slot_uid() if self.sandbox.as_root else None
        scratch = f"{SCRATCH}/k"
        workdir = Path(scratch) / "work"
        env = kernel_environment(workdir, control)
        env.update(IPYTHONDIR=f"{scratch}/ipython", MPLCONFIGDIR=f"{scratch}/matplotlib")
        listener = zygote = None
        try:
            listener = listen(control, uid)
            if uid is not None:
                os.chown(control, uid, uid)
            os.chmod(control, 0o500 if uid is None else 0o700)
            self.starts += 1
            zygote = Zygote(self.folder / f"z{self.starts}", self.preload, self.sandbox,
                            control, self.marker, uid, alone=True)
            zygote.wait_ready()
            reply = zygote.request(
                "fork", workdir=str(workdir), control=str(control),
                channel=str(control / SOCKET_NAME), env=env, limits=child_limits(limits),
                scratch=scratch, alone=True)
        except BaseException:
            if listener is not None:
                listener.close()
            if zygote is not None:
                zygote.close(timeout=1)
                shutil.rmtree(zygote.folder, ignore_errors=True)
            with contextlib.suppress(OSError):
                os.chmod(control, 0o700)
            shutil.rmtree(control, ignore_errors=True)
            raise
        self.forks += 1
        pid = int(reply["pid"])
        return _Forked(zygote, pid, workdir, control, listener, limits, True, uid,
                       MemoryWatch(zygote, pid, limits.memory_bytes))

    def take(self, limits: Limits) -> _Forked:
        """The prewarmed kernel if it is still usable, else a new one."""
        self._settle()
        forked, self.waiting = self.waiting, None
        if forked is not None:
            usable = ((forked.zygote is self.zygote or forked.watch is not None)
                      and forked.zygote.alive
                      and forked.limits == limits and forked.zygote.exit_status(forked.pid) is None
                      and (forked.sandboxed  # the zygote checks it (``deliver``)
                           or not any(forked.workdir.iterdir())))  # nothing planted in it
            if usable:
                return forked
            release(forked)
        return self.fork(limits)

    def prewarm(self, limits: Limits) -> None:
        """Fork the slot's next kernel now (it initialises while the current one runs)."""
        if self.waiting is None:
            with contextlib.suppress(ZygoteError, OSError):
                self.waiting = self.fork(limits)

    def prewarm_soon(self, limits: Limits) -> None:
        """:meth:`prewarm` in a thread of its own: the kernel that asks for it goes on at
        once; :meth:`take` and :meth:`close` wait for it first."""
        self._settle()
        self._prewarming = threading.Thread(target=self.prewarm, args=(limits,), daemon=True,
                                            name="eulertop-prewarm")
        self._prewarming.start()

    def _settle(self) -> None:
        if self._prewarming is not None:
            self._prewarming.join()
            self._prewarming = None

    def close(self) -> None:
        self._settle()
        if self.waiting is not None:
            release(self.waiting)
            self.waiting = None
        if self.zygote is not None:
            self.zygote.close()


def _lock_control(forked: _Forked) -> None:
    """After a sandboxed kernel bound its sockets: its control folder (on this machine's disk)
    is given back to the grader's user (as root), else made read-only — besides the read-only
    mount the kernel's world already put on it (:func:`grader.sandbox.world.seal`)."""
    with contextlib.suppress(OSError):
        if forked.uid is not None:
            os.chown(forked.control, os.geteuid(), os.getegid())
            os.chmod(forked.control, 0o700)
        else:
            os.chmod(forked.control, 0o500)


def release(forked: _Forked) -> int:
    """Kill a forked kernel (its group and leftovers), remove its folders; its exit status
    (negative: the signal that ended it). Never raises."""
    zygote = forked.zygote
    with contextlib.suppress(ZygoteError):
        if zygote.alive and zygote.exit_status(forked.pid) is None:
            zygote.request("kill", pid=forked.pid)  # reaped later: -SIGKILL below
    status = zygote.exit_status(forked.pid)
    zygote.forget(forked.pid)
    if forked.watch is not None:  # alone in its sandbox: the sandbox ends with it
        forked.watch.stop()
        zygote.close(timeout=2)
        shutil.rmtree(zygote.folder, ignore_errors=True)
    forked.listener.close()
    if not forked.sandboxed:  # a sandboxed one's is inside the sandbox (the zygote removed it)
        shutil.rmtree(forked.workdir, ignore_errors=True)
    with contextlib.suppress(OSError):
        os.chmod(forked.control, 0o700)  # read-only when locked without a uid of its own
    shutil.rmtree(forked.control, ignore_errors=True)
    return -signal.SIGKILL if status is None else status


class KernelPool:
    """Warm kernels for ``slots`` submissions at a time: the ``kernel_factory`` of
    :func:`grader.execute.execute_submission` (module docstring).

    Parameters
    ----------
    slots : int
        Kernels running at once (``--jobs``); one zygote each: the first slot's started now,
        the others' once it is ready, each slot lent out once its zygote is (zygotes importing
        at once share the cores with each other and with the grader: the first kernel would
        start later).
    prewarm : bool
        Fork each slot's next kernel while the current one runs.
    cold : bool
        Hand out cold :class:`~grader.kernels.local.LocalKernel` s only (also chosen automatically
        where :func:`fork_available` is false, or after a zygote failed to start).
    preload : sequence of str, optional
        Modules each zygote imports (default :data:`grader.kernels.zygote.PRELOAD`: ipykernel,
        IPython, numpy, scipy, sympy).
    sandbox : grader.sandbox.Sandbox, optional
        Run each slot's zygote, and so every kernel, in this sandbox (issues 5 and 11;
        :mod:`grader.sandbox`). None: no sandbox (the caller decided so). Sandboxed, the pool
        never falls back to unsandboxed cold kernels: a zygote that cannot start makes that
        submission's run fail ("error", retried by the grader).
    early : bool
        Started before the grader has read its class (issue 34: the zygote imports while
        the grader does): one slot, whose zygote imports :data:`EARLY_PRELOAD` and then
        waits; :meth:`plan` gives it the rest of ``preload`` and adds the other slots. No
        kernel is asked for before that.

    Use as a context manager (or call :meth:`close`): ending it kills every zygote, kernel and
    leftover process, and removes the pool's folder. The pool's folder is in the process's
    run folder (:func:`grader.sandbox.run_folder`).
    """

    def __init__(self, slots: int, *, prewarm: bool = True, cold: bool = False,
                 preload: Sequence[str] | None = None, sandbox: Sandbox | None = None,
                 early: bool = False) -> None:
        if sandbox is not None and (cold or not fork_available()):
            raise ValueError("a sandboxed pool forks its kernels: not cold, and on Linux")
        self.sandbox = sandbox
        self.prewarm = prewarm
        self.cold = cold or not fork_available()
        self.problem: str | None = None if not self.cold or cold else "fork is not available"
        self.folder: Path | None = None
        self.slots: list[Slot] = []
        self._free: queue.Queue[Slot] = queue.Queue()
        self._run = contextlib.ExitStack()
        self._closing, self._closed = threading.Lock(), False
        self._progress = threading.Condition()  # kernels given back (done), of work
        self._ending: threading.Thread | None = None  # close_soon's
        self.work: int | None = None
        self.done = 0
        if not self.cold:
            run = self._run.enter_context(run_folder())
            self.folder = fresh_folder(run, "p")
            if sandbox is not None:
                os.chmod(self.folder, 0o711)
            try:
                first = Slot(self.folder / "0", EARLY_PRELOAD if early else preload, sandbox,
                             run.name, more=early)
                self.slots.append(first)
                self._free.put(first)
                if not early:
                    self._add_slots(slots, preload)
            except BaseException:
                self.close()
                raise

    def plan(self, slots: int, preload: Sequence[str], work: int | None = None) -> None:
        """An ``early`` pool's class: ``slots`` kernels at once, each zygote importing
        ``preload`` (the first one the rest of it, :meth:`Zygote.preload_more`); ``work``:
        :meth:`expect`."""
        self.expect(work)
        if self.cold:
            return
        first = self.slots[0]
        if first.zygote is not None:
            first.zygote.preload_more([m for m in preload if m not in EARLY_PRELOAD])
        first.preload = tuple(dict.fromkeys((*EARLY_PRELOAD, *preload)))  # if started again
        self._add_slots(slots, preload)

    def _add_slots(self, slots: int, preload: Sequence[str] | None) -> None:
        """The slots after the first, their zygotes started once the first's is ready."""
        for i in range(1, max(1, slots)):
            self.slots.append(Slot(self.folder / str(i), preload, self.sandbox,
                                   self.slots[0].marker, start=False))
        later = [] if self.slots[0].alone else self.slots[1:]
        for slot in self.slots[1:]:
            if slot not in later:
                self._free.put(slot)
        if later:
            threading.Thread(target=self._start_later, args=(later,), daemon=True,
                             name="eulertop-zygotes").start()

    def expect(self, work: int | None) -> None:
        """The run will ask for ``work`` kernels (None: unknown): the other slots' zygotes
        are then started only while what is left of it would keep them busy
        (:meth:`_worth_more_slots`)."""
        with self._progress:
            self.work = work
            self._progress.notify_all()

    def _worth_more_slots(self) -> bool:
        """Wait until the work left would outlast another zygote's start: True; False once
        the pool is closed or the work is done first (the first slot did it all).

        At a time ``t`` after the first zygote was ready, with ``done`` of ``work`` kernels
        given back: the first slot alone needs about ``(work - done) * (t / done)`` more
        seconds (the time so far over what it finished, at least the kernel in hand's own);
        another zygote takes its start's ``cpu`` seconds (the first's, from its ready line)
        to be of use. A class of ten quick notebooks is done before a second zygote could
        fork one (issue 34: its import only took the cores from the kernels and the report);
        one of slow or many notebooks starts it after the first kernel or two."""
        start = self._start_cost()
        began = time.monotonic()
        with self._progress:
            while not self._closed:
                if self.work is None:
                    return True
                left, done = self.work - self.done, self.done
                if left <= 0:
                    return False
                if left * (time.monotonic() - began) / max(done, 1) > start:
                    return True
                self._progress.wait(0.02)
        return False

    def _start_cost(self) -> float:
        """CPU seconds the first slot's zygote took to start (its ready line), or 0."""
        first = self.slots[0].zygote
        return float((first.ready or {}).get("cpu", 0.0)) if first is not None else 0.0

    def _start_later(self, later: list[Slot]) -> None:
        """Start the zygotes of ``later`` once the first slot's is ready and the work left
        is worth it (:meth:`_worth_more_slots`), and lend out each slot once its own is
        ready (never after :meth:`close`)."""
        with contextlib.suppress(ZygoteError):
            self.slots[0].zygote.wait_ready()
        if not self._worth_more_slots():
            return
        for slot in later:
            with self._closing:
                if self._closed:
                    return
                slot.ensure_zygote()
        for slot in later:
            with contextlib.suppress(ZygoteError):
                slot.zygote.wait_ready()  # a zygote that failed is replaced by fork()
            self._free.put(slot)

    def kernel(self, workdir: Path, control: Path, limits: Limits) -> LocalKernel:
        """The kernel factory: ``(workdir, control, limits) -> KernelProcess``."""
        if self.cold:
            return LocalKernel(workdir, control, limits)
        return PooledKernel(self, workdir, control, limits)

    @property
    def forks(self) -> int:
        """Kernels forked so far, prewarmed ones included."""
        return sum(s.forks for s in self.slots)

    def acquire(self) -> Slot:
        return self._free.get()

    def give_back(self, slot: Slot) -> None:
        with self._progress:
            self.done += 1
            self._progress.notify_all()
        self._free.put(slot)

    def fail(self, err: Exception) -> None:
        """A zygote could not be started: cold kernels from now on, and say why once.
        Sandboxed: never (the error is the submission's run's)."""
        if self.sandbox is not None:
            raise RuntimeError(f"could not start a sandboxed kernel: {err}") from None
        if not self.cold:
            self.cold, self.problem = True, str(err)
            sys.stderr.write(f"eulertop grade: {err}; kernels start cold from now on "
                             "(slower, equally isolated)\n")

    def close_soon(self) -> None:
        """:meth:`close` in a thread of its own: the zygotes end (their kernels and
        leftovers killed, their folders removed: tens of milliseconds) while the caller goes
        on — the class report, at the end of a run; :meth:`close` waits for it."""
        if self._ending is None:
            self._ending = threading.Thread(target=self._close, name="eulertop-pool-close")
            self._ending.start()

    def close(self) -> None:
        """Kill every zygote, kernel and leftover; remove the pool's folder."""
        if self._ending is not None:
            self._ending.join()
        self._close()

    def _close(self) -> None:
        with self._closing, self._progress:  # no zygote is started after this
            self._closed = True
            self._progress.notify_all()
        for slot in self.slots:  # all of them end at once; then each is waited for
            if slot.zygote is not None:
                if slot.zygote.ready is None:  # still importing (started late): no kernels
                    slot.zygote.kill()  # to wait for, and its imports are not needed now
                slot.zygote.end_input()
        for slot in self.slots:
            slot.close()
        if self.folder is not None:
            shutil.rmtree(self.folder, ignore_errors=True)
        self._run.close()

    def __enter__(self) -> KernelPool:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()


class PooledKernel(LocalKernel):
    """A forked kernel from a :class:`KernelPool` slot (:class:`grader.kernels.base.KernelProcess`).

    ``workdir`` and ``control`` are :func:`~grader.execute.execute_submission`'s folders: the
    submission copied into ``workdir`` is moved into the forked kernel's own working folder
    (made in the slot's folder, empty until then) when the kernel is handed out. If the slot's
    zygote cannot be started, this kernel (and every later one) is a cold
    :class:`~grader.kernels.local.LocalKernel` instead.
    """

    def __init__(self, pool: KernelPool, workdir: Path, control: Path, limits: Limits) -> None:
        super().__init__(workdir, control, limits)
        self.pool = pool
        self.slot: Slot | None = None
        self.forked: _Forked | None = None
        self.cold = False
        self.channel: CellChannel | None = None
        self._status: int | None = None
        self._released = False

    async def start(self) -> Any:
        self.slot = await asyncio.to_thread(self.pool.acquire)
        try:
            self.forked = await asyncio.to_thread(self.slot.take, self.limits)
            if self.forked.sandboxed:
                await asyncio.to_thread(self._deliver)
        except ZygoteError as err:
            self._give_back()
            self.pool.fail(err)
            self.cold = True
            return await super().start()
        if not self.forked.sandboxed:
            for entry in self.workdir.iterdir():  # the submission, into the kernel's own folder
                os.replace(entry, self.forked.workdir / entry.name)
        forked = self.forked
        self.channel = CellChannel(forked.listener)
        await self.channel.connect(self.limits.total_timeout,
                                   lambda: self.exit_status() is None)
        if forked.sandboxed:  # connected and sealed: no more writing in a folder of this machine
            await asyncio.to_thread(_lock_control, forked)
        if self.pool.prewarm:
            self.slot.prewarm_soon(self.limits)
        return self.channel

    @property
    def sandboxed(self) -> bool:
        """Whether this kernel runs in the pool's sandbox."""
        return self.pool.sandbox is not None and not self.cold

    @property
    def isolation(self) -> str:
        """What confined this kernel (:meth:`grader.sandbox.Sandbox.describe`), or ""."""
        return self.pool.sandbox.describe() if self.sandboxed else ""

    @property
    def memory_held(self) -> int | None:
        """Bytes its processes held together when its keeper killed it for that, or None."""
        forked = self.forked
        return None if forked is None else forked.zygote.memory_held.get(forked.pid)

    def _deliver(self) -> None:
        """Hand the submission to a sandboxed kernel's working folder through its zygote
        (that folder is in the sandbox's tmpfs); a prewarmed kernel whose folder is no longer
        empty is replaced by a new one, once."""
        files = [(e.name, base64.b64encode(e.read_bytes()).decode()) for e in
                 sorted(self.workdir.iterdir())]
        for attempt in (1, 2):
            try:
                for name, data in files:
                    self.forked.zygote.request("deliver", pid=self.forked.pid, name=name,
                                               data=data)
                return
            except ZygoteError:
                release(self.forked)
                if attempt == 2:
                    raise
                self.forked = self.slot.fork(self.limits)

    async def interrupt(self) -> None:
        if self.cold:
            return await super().interrupt()
        with contextlib.suppress(ZygoteError):
            if self.forked is not None:
                await asyncio.to_thread(self.forked.zygote.request, "signal",
                                        pid=self.forked.pid, signal=int(signal.SIGINT))

    def exit_status(self) -> int | None:
        if self.cold:
            return super().exit_status()
        if self._released:
            return self._status
        return None if self.forked is None else self.forked.zygote.exit_status(self.forked.pid)

    async def stop(self) -> None:
        if self.cold:
            return await super().stop()
        if self.channel is not None:
            self.channel.close()
        await asyncio.to_thread(self.kill_group)

    def kill_group(self) -> None:
        """Kill the kernel's group and leftovers, remove its folders, free the slot (once)."""
        if self.cold:
            return super().kill_group()
        if self.forked is not None and not self._released:
            self._released = True
            self._status = release(self.forked)
        self._give_back()

    def reap(self) -> None:
        if self.cold:
            super().reap()

    def _give_back(self) -> None:
        if self.slot is not None:
            slot, self.slot = self.slot, None
            self.pool.give_back(slot)
