"""The container sandbox mode: where bubblewrap cannot start (a Docker container with the
default seccomp profile, as on Gradescope and PrairieLearn), run the kernel as another user.

What it does (:class:`ContainerKernel`, a :class:`grader.execute.LocalKernel`)
    * As root, the kernel runs as an unprivileged user (:func:`kernel_user`: ``nobody``, or the
      ``--kernel-user`` option / ``EULERTOP_KERNEL_USER``), with no supplementary groups. Its
      working folder (the copy of the submission; ``HOME`` and ``TMPDIR``) and its control
      folder (the IPC sockets it binds) are handed to that user; every other folder of the run
      stays the grader's (0700).
    * Resource limits on the kernel and all it starts (:data:`LAUNCHER`): address space
      (``Limits.memory_bytes``), no core files, processes (:data:`MAX_PROCESSES`, counted per
      user), size of any file it writes (:data:`MAX_FILE_BYTES`), open files, CPU seconds. Its
      output is capped by :func:`grader.execute.execute_submission` as everywhere.
    * When the kernel stops, its process group is killed (as everywhere) and so is every
      process of its user started since it started (:func:`kill_new_processes`: a process
      that left the group with ``setsid`` does not outlive the run).
    * :func:`protect` makes the answer key and the grader's own files (the platform's source
      folder, its data) readable by the grader's user only, before any kernel starts.

What it does not do
    No namespaces: the kernel sees the container's file system (all that is world-readable),
    its process list, and its network if the platform gives one (Gradescope does; PrairieLearn
    does not unless ``enableNetworking``). The key is safe because of file permissions and the
    other uid, nothing more.

Where the grader is not root there is no other user to run the kernel as: the kernel runs as
the grader's own user and **can read the key**; :func:`kernel_user` returns None and
:data:`UNPROTECTED` says so in every result.
"""

from __future__ import annotations

import os
import pwd
import signal
import stat
import subprocess
import sys
from collections.abc import Iterable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from grader.execute import LocalKernel
from grader.limits import Limits

USER_VARIABLE = "EULERTOP_KERNEL_USER"
"""Environment variable naming the kernel's user (a name or a uid) when no option does."""

DEFAULT_USER = "nobody"

MAX_PROCESSES = 64
"""``RLIMIT_NPROC`` of the kernel's user: processes and threads it may have at once."""

MAX_FILE_BYTES = 64 * 1024**2
"""``RLIMIT_FSIZE``: largest file the kernel may write, bytes."""

MAX_OPEN_FILES = 256
"""``RLIMIT_NOFILE``: files and sockets the kernel may hold open."""

UNPROTECTED = ("WARNING: nothing protected the answer key from the submitted code: the grader "
               "does not run as root, so there is no other user to run the notebook as, and "
               "its code could read every file the grader can read, the key included.")

# The kernel command: sets its limits in its own code (not a preexec_fn: unsafe in a threaded
# process), then runs ipykernel. No braces: jupyter_client substitutes {names} in the command.
LAUNCHER = (
    "import resource as r, runpy, sys; "
    "a = [int(x) for x in sys.argv[1:6]]; del sys.argv[1:6]; "
    "K = (r.RLIMIT_AS, r.RLIMIT_NPROC, r.RLIMIT_FSIZE, r.RLIMIT_NOFILE, r.RLIMIT_CPU); "
    "s = lambda k, v, h: r.setrlimit(k, (v, v) if h == r.RLIM_INFINITY else (min(v, h),) * 2); "
    "[s(k, v, r.getrlimit(k)[1]) for k, v in zip(K, a) if v > 0]; "
    "r.setrlimit(r.RLIMIT_CORE, (0, 0)); "
    "runpy.run_module('ipykernel_launcher', run_name='__main__', alter_sys=True)"
)


@dataclass(frozen=True)
class KernelUser:
    """The unprivileged user a kernel runs as."""

    uid: int
    gid: int
    name: str

    def describe(self) -> str:
        return f"uid {self.uid}" + ("" if self.name == f"uid {self.uid}" else f" ({self.name})")


class KernelUserError(ValueError):
    """The kernel user asked for does not exist or is root."""


def kernel_user(wanted: str | None = None) -> KernelUser | None:
    """The user kernels run as: ``wanted`` (a name or a uid), else :data:`USER_VARIABLE`, else
    ``nobody`` (uid 65534 where there is no such entry). None when the grader is not root.

    Raises
    ------
    KernelUserError
        ``wanted`` names no user, or names root or a user whose group is root's.
    """
    if os.geteuid() != 0:
        return None
    wanted = wanted or os.environ.get(USER_VARIABLE) or DEFAULT_USER
    try:
        entry = pwd.getpwuid(int(wanted)) if wanted.isdigit() else pwd.getpwnam(wanted)
        user = KernelUser(entry.pw_uid, entry.pw_gid, entry.pw_name)
    except KeyError:
        if not wanted.isdigit() and wanted != DEFAULT_USER:
            raise KernelUserError(f"kernel user {wanted!r}: no such user here") from None
        uid = int(wanted) if wanted.isdigit() else 65534
        user = KernelUser(uid, uid, f"uid {uid}")
    if user.uid == 0:
        raise KernelUserError(f"kernel user {wanted!r} is root: name an unprivileged user")
    if user.gid == 0:
        raise KernelUserError(f"kernel user {wanted!r} has root's group as its own: name a "
                              "user of an unprivileged group")
    return user


def check_interpreter(user: KernelUser | None) -> str | None:
    """Why ``user`` cannot run the grader's Python and import ipykernel, or None if it can.

    Python must be installed where other users may read it (not under ``/root``, which is
    private): the kernel runs the grader's own interpreter."""
    if user is None:
        return None
    try:
        done = subprocess.run([sys.executable, "-c", "import ipykernel, numpy"], cwd="/",
                              user=user.uid, group=user.gid, extra_groups=[],
                              capture_output=True, text=True, timeout=60,
                              env={"PATH": os.defpath, "HOME": "/"})
    except (OSError, subprocess.SubprocessError) as err:
        why = str(err)
    else:
        if done.returncode == 0:
            return None
        why = (done.stderr.strip().splitlines() or ["no message"])[-1]
    return (f"the kernel's user ({user.describe()}) cannot run this Python ({sys.executable}: "
            f"{why}); install eulertop in a Python that every user may read and run, e.g. "
            "/usr/bin/python3 or a virtual environment under /opt")


def describe(user: KernelUser | None) -> str:
    """One line for the results: how the kernel was confined."""
    if user is None:
        return ("container mode, as the grader's own user (not root): rlimits only; "
                + UNPROTECTED)
    return (f"container mode (no bubblewrap here): the notebook ran as {user.describe()} with "
            "resource limits, in a private folder; the key was readable by the grader only")


def protect(paths: Iterable[Path]) -> None:
    """Make each of ``paths`` (files or folders, recursively) readable by its owner only
    (group and others lose every permission). Links are not followed."""
    for top in paths:
        top = Path(top)
        if not top.exists() or top.is_symlink():
            continue
        for path in [top, *(top.rglob("*") if top.is_dir() else ())]:
            mode = path.lstat().st_mode
            if not stat.S_ISLNK(mode):
                os.chmod(path, stat.S_IMODE(mode) & 0o700)


def kernel_command(limits: Limits, own_user: bool = True) -> list[str]:
    """The kernel's argv: :data:`LAUNCHER` with its limits, then ipykernel's arguments.

    ``RLIMIT_NPROC`` counts every process of the user: it is set only where the kernel has a
    user of its own (``own_user``), not where it runs as the grader (0 leaves a limit alone)."""
    cpu = int(limits.total_timeout) + 30  # the grader kills it first; this is a backstop
    numbers = (limits.memory_bytes, MAX_PROCESSES if own_user else 0, MAX_FILE_BYTES,
               MAX_OPEN_FILES, cpu)
    return [sys.executable, "-c", LAUNCHER, *map(str, numbers), "-f", "{connection_file}",
            "--HistoryManager.hist_file=:memory:"]


def _manager_class(user: KernelUser | None) -> type:
    """``AsyncKernelManager`` whose connection file the kernel's user may read."""
    from jupyter_client import AsyncKernelManager

    class Manager(AsyncKernelManager):
        def write_connection_file(self, **kw: Any) -> Any:
            written = super().write_connection_file(**kw)
            if user is not None:
                os.chown(self.connection_file, user.uid, user.gid)
            return written

    return Manager


def _hand_over(folder: Path, user: KernelUser) -> None:
    """Give ``folder`` and what it holds to ``user`` (the kernel's own folders only)."""
    for path in [folder, *folder.rglob("*")]:
        os.chown(path, user.uid, user.gid, follow_symlinks=False)


def processes_of(uid: int) -> set[tuple[int, str]]:
    """``(pid, start time)`` of every live process of ``uid`` (from ``/proc``)."""
    found = set()
    for entry in os.scandir("/proc"):
        if not entry.name.isdigit():
            continue
        try:
            if entry.stat().st_uid != uid:
                continue
            with open(f"/proc/{entry.name}/stat", "rb") as f:
                fields = f.read().rsplit(b")", 1)[1].split()  # from field 3, the state
        except (OSError, IndexError):
            continue
        if len(fields) > 19 and fields[0] != b"Z":  # a zombie is dead already
            found.add((int(entry.name), fields[19].decode()))  # field 22: its start time
    return found


def kill_new_processes(uid: int, before: set[tuple[int, str]]) -> int:
    """SIGKILL every process of ``uid`` that is not in ``before`` (what a kernel left behind:
    a process that left the kernel's process group with ``setsid``); how many."""
    killed = 0
    for pid, _ in processes_of(uid) - before:
        try:
            os.kill(pid, signal.SIGKILL)
            killed += 1
        except OSError:
            pass
    return killed


class ContainerKernel(LocalKernel):
    """A :class:`LocalKernel` run as :attr:`user` (None: as the grader) with the limits of
    :data:`LAUNCHER`; ``sandboxed`` is False and ``isolation`` says what confined it."""

    sandboxed = False

    def __init__(self, workdir: Path, control: Path, limits: Limits,
                 user: KernelUser | None = None) -> None:
        super().__init__(workdir, control, limits)
        self.user = user
        self.isolation = describe(user)

    def kernel_argv(self) -> list[str]:
        return kernel_command(self.limits, own_user=self.user is not None)

    def manager_class(self) -> type:
        return _manager_class(self.user)

    def launch_options(self) -> dict[str, Any]:
        if self.user is None:
            return {}
        return {"user": self.user.uid, "group": self.user.gid, "extra_groups": []}

    async def start(self) -> Any:
        if self.user is not None:
            self._before = processes_of(self.user.uid)
            _hand_over(self.workdir, self.user)
            _hand_over(self.control, self.user)
        return await super().start()

    async def stop(self) -> None:
        await super().stop()
        if self.user is not None and hasattr(self, "_before"):
            kill_new_processes(self.user.uid, self._before)


def kernel_factory(user: KernelUser | None) -> Any:
    """``(workdir, control, limits) -> ContainerKernel`` for
    :func:`grader.execute.execute_submission`."""

    def factory(workdir: Path, control: Path, limits: Limits) -> ContainerKernel:
        return ContainerKernel(workdir, control, limits, user)

    return factory
