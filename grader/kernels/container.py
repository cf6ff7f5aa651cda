"""The container sandbox mode: where bubblewrap cannot start (a Docker container with the
default seccomp profile, as on Gradescope and PrairieLearn), run the kernel as another user.

What it does (:class:`ContainerKernel`, a :class:`grader.kernels.local.LocalKernel`)
    * As root, the kernel runs as an unprivileged user (:func:`kernel_user`: ``nobody``, or the
      ``--kernel-user`` option / ``EULERTOP_KERNEL_USER``), with no supplementary groups. Its
      working folder (the copy of the submission; ``HOME`` and ``TMPDIR``) and its control
      folder (the IPC sockets it binds) are handed to that user; every other folder of the run
      stays the grader's (0700).
    * Resource limits on the kernel and all it starts (:data:`LAUNCHER`): address space
      (``Limits.memory_bytes``), no core files, processes (:data:`MAX_PROCESSES`, counted per
      user), size of any file it writes (:data:`MAX_FILE_BYTES`), open files, CPU seconds. Its
      output is capped by :func:`grader.execute.execute_submission` as everywhere.
    * The seccomp filter of the sandboxed kernels (:mod:`grader.sandbox.seccomp`, SysV IPC
      refused too), installed by the kernel on itself before ipykernel starts.
    * While it runs, the resident memory of all its user's processes together is watched
      (:class:`UserMemoryWatch`); past ``Limits.memory_bytes`` they are all killed; so they are
      when it has written more than :data:`DISK_BYTES` to the machine's shared folders.
    * When the kernel stops, its process group is killed (as everywhere) and so is every
      process of its user, again and again until none is left (:func:`kill_all_of`: a process
      that left the group with ``setsid``, or a chain of short-lived ones, does not outlive
      the run).
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

The third isolation tier of ``eulertop grade`` (issue 22; :class:`ContainerTier`): as root where
no user namespace can be made (a Docker container with its default seccomp profile), the same
kernels, each as a uid of its own (:class:`RunUids`, from :func:`free_uids`): a run gives a uid
to one kernel at most, and never one that owns a process or a file in :data:`WRITABLE` (another
run's kernel), so no two students' kernels share a user; when the range is spent, a kernel
fails to start (:class:`NoFreeUid`: the grader's fault, retried and recorded so) rather than
share one. The instructor's folders (assignment, submissions, output) are made private to root
for the run (:func:`private_folders`).

Floor 2 of grader/ (one kernel; grader/API.md).
"""

from __future__ import annotations

import contextlib
import math
import os
import pwd
import secrets
import stat
import subprocess
import sys
import threading
from collections.abc import Iterable, Iterator
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from grader.kernels.local import LocalKernel
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
# process), installs the seccomp filter of the sandboxed kernels (grader/sandbox/seccomp.py, by
# its path: nothing else of the grader is imported), then runs ipykernel. No braces:
# jupyter_client substitutes {names} in the command.
LAUNCHER = (
    "import importlib.util as u, resource as r, runpy, sys; "
    "a = [int(x) for x in sys.argv[1:6]]; p = sys.argv[6]; del sys.argv[1:7]; "
    "K = (r.RLIMIT_AS, r.RLIMIT_NPROC, r.RLIMIT_FSIZE, r.RLIMIT_NOFILE, r.RLIMIT_CPU); "
    "s = lambda k, v, h: r.setrlimit(k, (v, v) if h == r.RLIM_INFINITY else (min(v, h),) * 2); "
    "[s(k, v, r.getrlimit(k)[1]) for k, v in zip(K, a) if v > 0]; "
    "r.setrlimit(r.RLIMIT_CORE, (0, 0)); "
    "f = u.spec_from_file_location('eulertop_seccomp', p); m = u.module_from_spec(f); "
    "f.loader.exec_module(m); m.install(ipc=True); del f, m, p, a; "
    "runpy.run_module('ipykernel_launcher', run_name='__main__', alter_sys=True)"
)
SECCOMP = Path(__file__).resolve().parent.parent / "sandbox" / "seccomp.py"
"""The filter the kernel installs on itself (:mod:`grader.sandbox.seccomp`, SysV IPC refused
too: with no IPC namespace of its own, a segment would outlive the kernel machine-wide)."""


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
            "resource limits and the memory of all its processes together watched, in a "
            "private folder; the key was readable by the grader only")


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
    return [sys.executable, "-c", LAUNCHER, *map(str, numbers), str(SECCOMP),
            "-f", "{connection_file}", "--HistoryManager.hist_file=:memory:"]


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


# As the kernel's user: kill(-1) reaches exactly the processes that user may signal (its own),
# never the caller; ESRCH once there is none. Repeated, since a process may fork meanwhile.
_KILLER = ("import os, signal\n"
           "for _ in range(10000):\n"
           "    try:\n"
           "        os.kill(-1, signal.SIGKILL)\n"
           "    except ProcessLookupError:\n"
           "        break\n")


def kill_all_of(user: KernelUser) -> None:
    """SIGKILL every process of ``user``, again and again until none is left: ``kill(-1)``
    from a helper process of that user (as root only; the helper is not one of its targets).
    What the kernel left behind — a process that left its group with ``setsid``, a chain of
    short-lived ones, a fork bomb — cannot slip between a snapshot and a kill."""
    with contextlib.suppress(OSError, subprocess.SubprocessError):
        subprocess.run([sys.executable, "-I", "-S", "-c", _KILLER], user=user.uid,
                       group=user.gid, extra_groups=[], cwd="/", env={"PATH": os.defpath},
                       stdin=subprocess.DEVNULL, capture_output=True, timeout=60)


WRITABLE = ("/tmp", "/var/tmp", "/dev/shm")
"""The world-writable folders a kernel of its own uid could leave files in."""


def remove_files_of(uid: int, places: Iterable[str] = WRITABLE) -> int:
    """Remove everything ``uid`` owns in the world-writable folders ``places`` (and in the
    world-writable folders of others below them), links not followed; how many entries. Run
    once the kernel's processes are gone (:func:`kill_all_of`): nothing it planted is left for
    a later kernel or the machine."""
    import shutil

    removed = 0
    for path, info in _shared_entries(places):
        if info.st_uid == uid:
            with contextlib.suppress(OSError):
                if stat.S_ISDIR(info.st_mode):
                    shutil.rmtree(path, ignore_errors=True)
                else:
                    os.unlink(path)
                removed += 1
    return removed


def _shared_entries(places: Iterable[str]) -> Iterator[tuple[str, os.stat_result]]:
    """``(path, stat)`` of every entry of the folders ``places`` and of the world-writable
    folders below them (where any user may leave something), links not followed."""
    todo = [str(p) for p in places if os.path.isdir(p)]
    while todo:
        folder, found = todo.pop(), []
        with contextlib.suppress(OSError), os.scandir(folder) as entries:
            for entry in entries:
                with contextlib.suppress(OSError):
                    found.append((entry.path, entry.stat(follow_symlinks=False)))
        for path, info in found:
            yield path, info
            if stat.S_ISDIR(info.st_mode) and info.st_mode & stat.S_IWOTH:
                todo.append(path)


def uids_in_use(places: Iterable[str] = WRITABLE) -> set[int]:
    """The uids that own an entry of the shared folders ``places`` (:func:`_shared_entries`)
    or a process of this machine (a zombie too): in use, by a kernel of another run, say."""
    owners = {info.st_uid for _, info in _shared_entries(places)}
    for entry in os.scandir("/proc"):
        if entry.name.isdigit():
            with contextlib.suppress(OSError, ValueError, StopIteration), \
                    open(f"/proc/{entry.name}/status", "rb") as f:
                # real, effective, saved and file-system uid: read here, not from the owner of
                # /proc/<pid>, which is root for a process that cannot be dumped
                owners.update(map(int, next(x for x in f if x.startswith(b"Uid:")).split()[1:]))
    return owners


def resident_of(uid: int, proportional: bool = False) -> int:
    """Resident memory of all processes of ``uid`` together, bytes: the sum of their
    ``VmRSS``, or with ``proportional`` of their ``Pss`` (pages shared among them counted
    once), as the keeper of a sandboxed kernel counts (:func:`grader.sandbox.world.keep`)."""
    total = 0
    for pid, _ in processes_of(uid):
        name, field = ("smaps_rollup", b"Pss:") if proportional else ("status", b"VmRSS:")
        with contextlib.suppress(OSError, ValueError, StopIteration):
            with open(f"/proc/{pid}/{name}", "rb") as f:
                total += int(next(x for x in f if x.startswith(field)).split()[1]) * 1024
    return total


def bytes_of(uid: int, places: Iterable[str | Path]) -> int:
    """Bytes on disk (or in a tmpfs) of what ``uid`` owns in ``places`` — their files, and
    everything in its folders there — and of the files its processes hold open (deleted ones
    included); each file counted once."""
    seen: set[tuple[int, int]] = set()
    total = 0

    def count(info: os.stat_result) -> None:
        nonlocal total
        if stat.S_ISREG(info.st_mode) and (info.st_dev, info.st_ino) not in seen:
            seen.add((info.st_dev, info.st_ino))
            total += info.st_blocks * 512

    todo = [(str(p), False) for p in places if os.path.isdir(p)]
    while todo:
        folder, owned = todo.pop()
        with contextlib.suppress(OSError), os.scandir(folder) as entries:
            for entry in entries:
                with contextlib.suppress(OSError):
                    info = entry.stat(follow_symlinks=False)
                    mine = owned or info.st_uid == uid
                    if mine:
                        count(info)
                    if stat.S_ISDIR(info.st_mode) and (mine or info.st_mode & stat.S_IWOTH):
                        todo.append((entry.path, mine))
    for pid, _ in processes_of(uid):
        with contextlib.suppress(OSError):
            for fd in os.listdir(f"/proc/{pid}/fd"):
                with contextlib.suppress(OSError):
                    count(os.stat(f"/proc/{pid}/fd/{fd}"))
    return total


def _free_bytes(places: Iterable[str | Path]) -> int:
    """Free bytes of the file systems of ``places`` (each counted once)."""
    free: dict[int, int] = {}
    for place in places:
        with contextlib.suppress(OSError):
            info = os.statvfs(place)
            free[os.stat(place).st_dev] = info.f_bavail * info.f_frsize
    return sum(free.values())


class UserMemoryWatch:
    """Watches a kernel's user (a thread; every :data:`WATCH_INTERVAL`): the memory of all its
    processes together and, when the free space of the folders it may write to has fallen by
    more than ``disk`` bytes since it started, what it wrote there (:func:`bytes_of`); past
    ``limit`` or ``disk`` bytes, kills all its processes (:func:`kill_all_of`) and keeps what
    they held in :attr:`held` (memory) or :attr:`wrote` (disk)."""

    def __init__(self, user: KernelUser, limit: int, workdir: Path | None = None,
                 disk: int | None = None) -> None:
        self.user, self.limit = user, limit
        self.places = [*WRITABLE, *([str(workdir)] if workdir is not None else [])]
        self.disk = DISK_BYTES if disk is None else disk
        self.free = _free_bytes(self.places)
        self.held: int | None = None
        self.wrote: int | None = None
        self.stopped = threading.Event()
        self.thread = threading.Thread(target=self._run, name="eulertop-memory", daemon=True)
        self.thread.start()

    def _run(self) -> None:
        while not self.stopped.wait(WATCH_INTERVAL):
            used = resident_of(self.user.uid)
            if used > self.limit:
                used = resident_of(self.user.uid, proportional=True)
            if used > self.limit:
                self.held = used
                kill_all_of(self.user)
                return
            if self.free - _free_bytes(self.places) > self.disk:  # someone wrote: who?
                written = bytes_of(self.user.uid, self.places)
                if written > self.disk:
                    self.wrote = written
                    kill_all_of(self.user)
                    return

    def stop(self) -> None:
        self.stopped.set()
        self.thread.join(5)


WATCH_INTERVAL = 0.1
"""Seconds between two looks at the memory of a container-mode kernel's processes."""

DISK_BYTES = 256 * 1024**2
"""What a container-mode kernel may write to this machine's shared folders (``/tmp``,
``/var/tmp``, ``/dev/shm``, its working folder) in all, bytes: as much as a sandboxed kernel's
own tmpfs holds (:data:`grader.sandbox.SCRATCH_BYTES`)."""


class ContainerKernel(LocalKernel):
    """A :class:`LocalKernel` run as :attr:`user` (None: as the grader) with the limits of
    :data:`LAUNCHER`; ``isolation`` says what confined it, and ``sandboxed`` whether that kept
    the key out of its reach (another user: yes; the grader's own: no)."""

    def __init__(self, workdir: Path, control: Path, limits: Limits,
                 user: KernelUser | None = None, note: str | None = None) -> None:
        super().__init__(workdir, control, limits)
        self.user = user
        self.sandboxed = user is not None
        self.isolation = note or describe(user)
        self.watch: UserMemoryWatch | None = None

    @property
    def memory_held(self) -> int | None:
        """Bytes its processes held together when they were killed for that, or None."""
        return None if self.watch is None else self.watch.held

    disk_limit = DISK_BYTES

    @property
    def disk_held(self) -> int | None:
        """Bytes it had written to the machine's shared folders when it was killed for that,
        or None."""
        return None if self.watch is None else self.watch.wrote

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
            _hand_over(self.workdir, self.user)
            _hand_over(self.control, self.user)
            self.watch = UserMemoryWatch(self.user, self.limits.memory_bytes, self.workdir)
        return await super().start()

    async def stop(self) -> None:
        await super().stop()
        if self.user is not None:
            if self.watch is not None:
                self.watch.stop()
            kill_all_of(self.user)
            remove_files_of(self.user.uid)


def kernel_factory(user: KernelUser | None) -> Any:
    """``(workdir, control, limits) -> ContainerKernel`` for
    :func:`grader.execute.execute_submission`."""

    def factory(workdir: Path, control: Path, limits: Limits) -> ContainerKernel:
        return ContainerKernel(workdir, control, limits, user)

    return factory


# --------------------------------------------------------------------------------------------
# The container mode as the third tier of ``eulertop grade`` (issue 22)


def free_uids() -> tuple[int, int] | None:
    """A range ``(first, count)`` of uids that exist here and that no real user has, for
    kernels of their own: the sandbox's reserved range where it is mapped, else the part above
    10000 of the largest range a rootless container maps (at least 1000 uids); None if none."""
    from grader.sandbox import UID_BASE, UID_SPAN, host

    if host.uids_mapped(UID_BASE, UID_SPAN):
        return UID_BASE, UID_SPAN
    spans = [(max(lo, 10000), lo + n - max(lo, 10000)) for lo, n in host.mapped_uids()]
    spans = [(lo, n) for lo, n in spans if n >= 1000]
    return max(spans, key=lambda s: s[1]) if spans else None


class NoFreeUid(RuntimeError):
    """Every uid of a run's range was given to one of its kernels or is in use here: no more
    kernels of their own can start (the grader's fault, not the student's)."""


class RunUids:
    """The uids ``[first, first + count)`` (:func:`free_uids`) as one run gives them to its
    kernels, from any thread: each at most once, and none that an account has or that owns a
    process or a file in :data:`WRITABLE` when it is given (:func:`uids_in_use`)."""

    def __init__(self, first: int, count: int) -> None:
        if count < 1:
            raise ValueError(f"uids: a range of {count} uids holds none")
        self.first, self.count = first, count
        # A random order (a random start and a random stride co-prime with count: every uid
        # met once, none twice), not upwards from first: another run on this machine walks
        # the range in another order, so two runs started together rarely reach one uid at
        # the same time — uids_in_use cannot see a uid the other run chose a moment ago. A
        # uid passed over as in use is not met again: the range is thousands of uids.
        self._start, self._stride = secrets.randbelow(count), _coprime_stride(count)
        self._walked = self._given = 0
        self._lock = threading.Lock()

    def take(self) -> KernelUser:
        """The next uid, as a :class:`KernelUser` whose group is its own number;
        :class:`NoFreeUid` once none is left (a uid is never given twice)."""
        with self._lock:
            busy = uids_in_use()
            while self._walked < self.count:
                uid = self.first + (self._start + self._walked * self._stride) % self.count
                self._walked += 1
                if uid not in busy and not _has_account(uid):
                    self._given += 1
                    return KernelUser(uid, uid, f"uid {uid}")
        raise NoFreeUid(
            f"no uid left for a kernel of its own: of the {self.count} uids {self.first}…"
            f"{self.first + self.count - 1}, {self._given} went to this run's kernels and "
            f"{self.count - self._given} were in use here (an account, a process, or a file in "
            f"{', '.join(WRITABLE)}); uids are never shared between kernels, so grade again "
            "once other runs have ended, or map more uids into this container")


def _coprime_stride(count: int) -> int:
    """A random step of ``1…count`` with no factor in common with ``count``: walking ``count``
    steps of it modulo ``count`` meets every residue exactly once."""
    while True:
        step = 1 + secrets.randbelow(count)
        if math.gcd(step, count) == 1:
            return step


def _has_account(uid: int) -> bool:
    try:
        pwd.getpwuid(uid)
    except KeyError:
        return False
    return True


@dataclass(frozen=True)
class ContainerTier:
    """The ``container`` tier of one run of ``eulertop grade``: where no user namespace can be
    made and the grader is root, each kernel a :class:`ContainerKernel` as a uid of its own
    from ``uids`` (given once each, whatever thread asks); ``why`` says why bubblewrap could
    not be used."""

    uids: RunUids
    why: str
    tier: str = "container"

    def describe(self) -> str:
        """One line for the run's header and every record."""
        return (f"container: no bubblewrap here ({self.why}); each kernel runs as a uid of its "
                "own (given to no other kernel of the run, and to none in use here), with "
                "resource limits (memory of all its processes together watched, processes, "
                "CPU time, file size, open files), in a private folder, and everything of its "
                "uid killed when it ends; the assignment, submissions and output folders "
                "private to root during the run; no namespaces: it sees this machine's "
                "world-readable files, its process list and its network")

    def kernel_factory(self) -> Any:
        """``(workdir, control, limits) -> ContainerKernel``, each as the next uid of
        :attr:`uids` (:class:`NoFreeUid` when none is left: the run records that submission
        as not graded through no fault of its own)."""
        note = self.describe()

        def factory(workdir: Path, control: Path, limits: Limits) -> ContainerKernel:
            return ContainerKernel(workdir, control, limits, self.uids.take(), note)

        return factory

    def private_folders(self, stack: contextlib.ExitStack, *folders: Path) -> None:
        """Make ``folders`` private to their owner while ``stack`` lasts
        (:func:`private_folders`), saying so on stderr."""
        changed = stack.enter_context(private_folders(folders))
        if changed:
            names = ", ".join(str(p) for p in changed)
            sys.stderr.write(f"eulertop grade: container mode: {names} private to "
                             f"{pwd.getpwuid(os.geteuid()).pw_name} during the run (their "
                             "modes are given back at its end)\n")


@contextlib.contextmanager
def private_folders(folders: Iterable[Path]) -> Iterator[list[Path]]:
    """Take group and other users' permissions off each of ``folders`` (those that exist, not
    links) for the duration of the block, then give their modes back; the folders changed.
    Nothing below them is touched: a folder no other user may enter hides all it holds."""
    changed: list[tuple[Path, int]] = []
    try:
        for folder in dict.fromkeys(Path(f) for f in folders):
            with contextlib.suppress(OSError):
                info = folder.lstat()
                if stat.S_ISDIR(info.st_mode) and stat.S_IMODE(info.st_mode) & 0o077:
                    os.chmod(folder, stat.S_IMODE(info.st_mode) & 0o700)
                    changed.append((folder, stat.S_IMODE(info.st_mode)))
        yield [folder for folder, _ in changed]
    finally:
        for folder, mode in changed:
            with contextlib.suppress(OSError):
                os.chmod(folder, mode)


