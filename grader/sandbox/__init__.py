"""The sandbox around student kernels (issues 5 and 11): one student, one disposable world.

A student notebook is untrusted code running on the instructor's machine next to the answer
key and next to other students' kernels. Two layers (``docs/security.md`` has the threat model
and the attacks that test it):

1. **Per slot, bubblewrap** (:meth:`Sandbox.command`) around the slot's zygote
   (:mod:`grader.kernels.pool`, :mod:`grader.kernels.zygote`), always in a user namespace:

   * read-only: ``/usr`` (and ``/bin``, ``/lib*``, ``/sbin`` as on the host), the running
     interpreter's prefixes and site-packages, the zygote with :mod:`world` and
     :mod:`seccomp` beside it (``/eulertop``: not the project's folder), and from ``/etc``
     only what the dynamic loader and fonts need (:data:`ETC`);
   * ``--proc``, ``--dev``, a small ``tmpfs`` at ``/tmp``; read-write: the slot's folder only
     (kernel control folders: the IPC sockets the grader talks to). No home folder, no
     assignment (key), no submissions, no results, no grader source;
   * namespaces: user, network, PID, IPC, UTS, cgroup; ``--new-session``,
     ``--die-with-parent``, ``--clearenv``; started in a session of its own (Ctrl-C in the
     instructor's terminal never reaches it).

   As root, the sandbox runs as a uid of the slot's own (:func:`slot_uid`, from a high range
   that no real user has), never as root: ``setpriv`` drops to it, inside a first, root
   ``bwrap`` that only makes folders above the Python it needs passable (:func:`_as_user`).
   As an ordinary user (a laptop), as that user.

2. **Per kernel, its own world** (:mod:`grader.sandbox.world`, made by the forked child
   before any code of the student runs): new user, PID, mount, network, IPC and UTS
   namespaces; the kernel is PID 1 of its own PID namespace, watched from outside by a keeper
   that enforces the memory limit on all its processes together; its own size-limited tmpfs
   at ``/tmp`` and ``/dev/shm``; the slot folder hidden but for its own control folder, made
   read-only once its sockets are bound; ``/``, ``/dev``, ``/proc/sys`` read-only; no
   capabilities; ``no_new_privs``; a seccomp filter (:mod:`grader.sandbox.seccomp`). No
   process of the grader or of another student is visible or reachable from it, and nothing
   it makes outlives it.

Tiers (issue 22), chosen by :func:`probe` and named in every record (:meth:`Sandbox.describe`)
    ``world`` — the two layers above. ``bwrap-per-kernel`` — where user namespaces do not nest
    inside bubblewrap (Ubuntu ≥ 25.04's bwrap profile leaves them without capabilities; some
    containers): layer 2 cannot be made, so layer 1 is made *per kernel* instead: one fresh
    ``bwrap`` for each kernel's zygote (:attr:`Sandbox.per_kernel`), with only that kernel's
    control folder in it, read-only, its own ``/tmp`` and ``/dev/shm`` tmpfs, and the same
    seccomp filter; the memory of its processes together is watched from the grader
    (:mod:`grader.kernels.pool`). The third tier, the container mode (as root where no user
    namespace can be made: another uid and rlimits), is :mod:`grader.kernels.container`'s.

Where no sandbox can be had, :func:`probe` raises :class:`SandboxUnavailable` with the cause and
its fix (:mod:`grader.sandbox.host`): ``eulertop grade`` refuses with them unless
``--no-sandbox`` is given.

Run folders (:func:`run_folder`)
    Every temporary folder of a grading process lives in one *run folder*,
    ``<tmp>/eulertop-<pid>-<8 hex digits>``, removed when the run ends. A run killed by SIGKILL
    cannot remove it; the next run removes such stale folders — only those whose name matches
    exactly that pattern, that belong to this user, and whose grader pid is no longer alive
    (:func:`remove_stale_run_folders`).

Floor 1 of grader/ (one student, one disposable world; grader/API.md).
"""

from __future__ import annotations

import contextlib
import fcntl
import functools
import itertools
import os
import queue
import re
import secrets
import shutil
import subprocess
import sys
import tempfile
import threading
from collections.abc import Iterator, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path

from grader.sandbox import host

__all__ = [
    "ETC",
    "RUN_FOLDER",
    "SCRATCH",
    "SCRATCH_BYTES",
    "TIERS",
    "Launch",
    "Sandbox",
    "SandboxUnavailable",
    "available",
    "fresh_folder",
    "passable",
    "probe",
    "remove_stale_run_folders",
    "run_folder",
    "slot_uid",
    "spawn",
]

TIERS = ("world", "bwrap-per-kernel", "container")
"""The isolation tiers, strongest first (module docstring)."""

TOOLS = "/eulertop"
"""Where the grader's own files a sandbox needs (the zygote script) appear inside it: not at
their path here, so nothing of the project's folders is visible."""

SCRATCH = "/tmp"
"""Where, inside the sandbox, the size-limited tmpfs of kernels' working folders is."""

SCRATCH_BYTES = 256 * 1024**2
"""Size of each kernel's own tmpfs (its ``/tmp`` and ``/dev/shm`` together), bytes; the
slot's own ``/tmp`` (the zygote's) has the same bound."""

ETC = ("/etc/ld.so.cache", "/etc/ld.so.conf", "/etc/ld.so.conf.d", "/etc/localtime",
       "/etc/fonts", "/etc/alternatives")
"""The pieces of ``/etc`` bound into the sandbox (read-only, when present)."""

UID_BASE, UID_SPAN = 0x60000000, 0x10000000
"""As root, each slot's sandbox runs as a uid/gid of its own drawn from
``[UID_BASE, UID_SPAN + UID_BASE)``: far above any real user (and below the 32-bit ``-1``).
Root of a user namespace that does not map this range (``unshare -r``, a rootless container)
has no such uids to give: its sandboxes run as its own uid, as an ordinary user's do."""

SHM_BYTES = 64 * 1024**2
"""Size of ``/dev/shm`` (a tmpfs of its own) in the ``bwrap-per-kernel`` tier, bytes."""

RUN_FOLDER = re.compile(r"eulertop-(\d+)-([0-9a-f]{8})")
"""Name of a run folder: ``eulertop-<grader pid>-<8 hex digits>``."""


class SandboxUnavailable(RuntimeError):
    """No sandbox can be had here; the message says why and how to get one
    (:attr:`diagnosis`: the cause and the fix apart)."""

    def __init__(self, diagnosis: host.Diagnosis) -> None:
        super().__init__(diagnosis.message())
        self.diagnosis = diagnosis


def slot_uid() -> int:
    """A fresh uid (= gid) for one slot's sandbox (as root), from the reserved high range."""
    return UID_BASE + secrets.randbelow(UID_SPAN)


@dataclass(frozen=True)
class Launch:
    """What starts one sandbox: ``argv`` and the uid it runs as (None: the grader's own)."""

    argv: list[str]
    uid: int | None

    def popen_options(self) -> dict:
        """Keyword arguments of ``subprocess.Popen`` for this launch: a session of its own
        (the terminal's Ctrl-C never reaches a sandbox)."""
        return {"start_new_session": True}


@dataclass(frozen=True)
class Sandbox:
    """How to start a zygote inside bubblewrap (module docstring).

    Attributes
    ----------
    bwrap : str
        Path of the ``bwrap`` executable.
    as_root : bool
        Every sandbox runs as a uid of its own (:func:`slot_uid`), never as the grader's: the
        grader is root with those uids to give. Otherwise as the grader's user. Either way in a
        user namespace.
    scratch_bytes : int
        Size of each kernel's own tmpfs (``/tmp`` and ``/dev/shm`` together), bytes.
    per_kernel : bool
        The ``bwrap-per-kernel`` tier: one sandbox per kernel, whose zygote forks that one
        kernel and no world of its own (user namespaces do not nest here); else ``world``.
    """

    bwrap: str
    as_root: bool
    scratch_bytes: int = SCRATCH_BYTES
    per_kernel: bool = False
    why_per_kernel: str = field(default="", compare=False)
    """Why a kernel cannot make a world of its own here (what :func:`probe` saw)."""

    @property
    def tier(self) -> str:
        """``world`` or ``bwrap-per-kernel`` (:data:`TIERS`)."""
        return TIERS[1] if self.per_kernel else TIERS[0]

    def describe(self) -> str:
        """One line for the run's header and every record: the tier, and what confines each
        kernel."""
        from grader.sandbox import seccomp

        try:
            seccomp.program()
            filtered = f"seccomp ({len(seccomp.refused(self.per_kernel))} calls refused)"
        except ValueError as err:
            filtered = f"no seccomp filter ({err})"
        who = (f"a uid of its own per {'kernel' if self.per_kernel else 'slot'}, never root"
               if self.as_root else "your uid")
        limits = ("limits: memory of all its processes together (watched), processes per "
                  "kernel, CPU time, file size (rlimits); no cgroups")
        if self.per_kernel:
            return (f"{self.tier}: a fresh bubblewrap sandbox per kernel (where a kernel "
                    "cannot make a world of its own inside one): own user, PID, mount, network, "
                    f"IPC and UTS namespaces, {filtered}, no capabilities, no_new_privs, "
                    f"{self.scratch_bytes // 1024**2} MiB tmpfs for /tmp and "
                    f"{SHM_BYTES // 1024**2} MiB for /dev/shm, read-only elsewhere; as {who}; "
                    f"{limits}")
        return (f"{self.tier}: bubblewrap, then per kernel: own user, PID, mount, network, IPC "
                f"and UTS namespaces, {filtered}, no capabilities, no_new_privs, "
                f"{self.scratch_bytes // 1024**2} MiB tmpfs for /tmp and /dev/shm, read-only "
                f"elsewhere; as {who}; {limits}")

    def command(self, argv: Sequence[str], env: Mapping[str, str], folder: Path,
                cwd: Path | str, files: Mapping[str, str] | None = None,
                uid: int | None = None, writable: bool = True) -> Launch:
        """Run ``argv`` with environment ``env`` (only), the folder ``folder`` bound (read-write,
        or read-only when not ``writable``), ``cwd`` as working folder, and ``files`` (host path
        → path in the sandbox) bound read-only under :data:`TOOLS`; as root, as ``uid``
        (default: a fresh one)."""
        if self.as_root and uid is None:
            uid = slot_uid()
        args = [self.bwrap, "--unshare-user", "--unshare-ipc", "--unshare-pid",
                "--unshare-net", "--unshare-uts", "--unshare-cgroup-try", "--die-with-parent",
                "--new-session", "--clearenv"]
        for name, value in env.items():
            args += ["--setenv", name, value]
        made: set[str] = {"/"}

        def ancestors(path: str, perms: str) -> list[str]:
            out = []
            for parent in reversed(Path(path).parents):
                p = str(parent)
                if p not in made:
                    made.add(p)
                    out += ["--perms", perms, "--dir", p]
            return out

        # The scratch tmpfs first: a later mount hides what lies under it, and the Python
        # environment itself may live under SCRATCH (a venv in /tmp, as in a CI clone).
        args += ["--perms", "0711", "--size", str(self.scratch_bytes), "--tmpfs", SCRATCH]
        made.add(SCRATCH)
        for top in ("/bin", "/sbin", "/lib", "/lib32", "/lib64", "/libx32"):
            if os.path.islink(top):
                args += ["--symlink", os.readlink(top), top]
            elif os.path.isdir(top):
                args += ["--ro-bind", top, top]
        args += ["--ro-bind", "/usr", "/usr"]
        bound = ["/usr", "/bin", "/sbin", "/lib", "/lib32", "/lib64", "/libx32"]
        sources = []
        for path in _python_paths():
            if any(path == b or path.startswith(b.rstrip("/") + "/") for b in bound):
                continue
            args += [*ancestors(path, "0755"), "--ro-bind", path, path]
            bound.append(path)
            sources.append(path)
        for path in ETC:
            if os.path.exists(path):
                args += [*ancestors(path, "0755"), "--ro-bind", path, path]
        for source, inside in (files or {}).items():
            if not inside.startswith(TOOLS + "/"):
                raise ValueError(f"{inside}: files go under {TOOLS}")
            args += [*ancestors(inside, "0755"), "--ro-bind", source, inside]
            sources.append(source)
        args += ["--proc", "/proc", "--dev", "/dev"]
        if self.per_kernel:  # no world of its own to put /dev/shm in its /tmp: a tmpfs of its own
            args += ["--perms", "1777", "--size", str(SHM_BYTES), "--tmpfs", "/dev/shm"]
        folder = str(Path(folder).resolve())
        args += [*ancestors(folder, "0711"), "--bind" if writable else "--ro-bind", folder,
                 folder]
        args += ["--chdir", str(Path(cwd).resolve()), "--", *argv]
        if uid is not None:
            args = [*_as_user(uid, [*sources, folder]), *args]
        return Launch(args, uid)


def _as_user(uid: int, sources: Sequence[str]) -> list[str]:
    """As root: what runs the sandbox's ``bwrap`` as ``uid`` instead — ``setpriv`` (no
    capability, no other group), inside a first, root ``bwrap`` (:func:`passable`) that only
    makes the folders above ``sources`` that ``uid`` could not pass (a Python under ``/root``)
    passable."""
    setpriv = shutil.which("setpriv") or "/usr/bin/setpriv"
    drop = [setpriv, f"--reuid={uid}", f"--regid={uid}", "--clear-groups", "--inh-caps=-all",
            "--"]
    return [*passable(sources, ["CAP_SETUID", "CAP_SETGID"]), *drop]


def passable(sources: Sequence[str], caps: Sequence[str] = ()) -> list[str]:
    """As root: the argv prefix of a root ``bwrap`` (keeping capabilities ``caps``) in whose
    mount namespace every folder above ``sources`` that other users could not pass is
    replaced by an empty one (mode 0711) with what is needed bound back; ``[]`` where every
    such folder is passable already. The rest of the file system is the host's, unchanged."""
    closed = sorted({str(p) for s in sources for p in Path(s).parents
                     if not os.stat(p).st_mode & 0o001}, key=len)
    if not closed:
        return []
    outer = [shutil.which("bwrap") or "bwrap", "--dev-bind", "/", "/", "--die-with-parent"]
    for cap in caps:
        outer += ["--cap-add", cap]
    for folder in closed:
        if any(folder.startswith(c.rstrip("/") + "/") for c in closed if c != folder):
            continue  # below one replaced already
        outer += ["--perms", "0711", "--tmpfs", folder]
        made = {folder}
        for source in sources:
            if source.startswith(folder.rstrip("/") + "/"):
                for parent in reversed(Path(source).parents):
                    if str(parent).startswith(folder.rstrip("/") + "/") and \
                            str(parent) not in made:
                        made.add(str(parent))
                        outer += ["--perms", "0711", "--dir", str(parent)]
                outer += ["--bind", source, source]
    return [*outer, "--"]


def _python_paths() -> list[str]:
    """What the interpreter needs, read-only: prefixes, ``sys.path`` folders."""
    import site

    paths = [sys.prefix, sys.base_prefix, sys.exec_prefix, sys.base_exec_prefix,
             str(Path(sys.executable).resolve().parent)]
    # only site-packages folders of sys.path: not the current folder, not a project on it
    # (an editable install's folder), which would show the project's files to every kernel
    paths += [p for p in sys.path if os.path.isabs(p)
              and os.path.basename(p.rstrip("/")) in ("site-packages", "dist-packages")]
    with contextlib.suppress(Exception):
        paths += site.getsitepackages()
    if site.ENABLE_USER_SITE:
        paths.append(site.getusersitepackages())
    out: list[str] = []
    for p in sorted({os.path.realpath(p) for p in paths}, key=len):
        if os.path.exists(p) and not any(p == o or p.startswith(o.rstrip("/") + "/")
                                         for o in out):
            out.append(p)
    return sorted(out)


NO_NESTING = 3
"""Exit status of :func:`probe`'s check when a kernel cannot make namespaces of its own inside
bubblewrap (the ``bwrap-per-kernel`` tier then)."""

_PROBE = """
import ctypes, os, socket, sys
try:
    socket.create_connection(('127.0.0.1', 9), timeout=1)
except OSError:
    pass
else:
    raise SystemExit('network reachable')
assert os.getpid() < 10, 'no PID namespace'
if __NESTING__:  # what each kernel does inside it (grader/sandbox/world.py), in small
    libc = ctypes.CDLL(None, use_errno=True)
    uid, gid = os.getuid(), os.getgid()
    def refused(what, err):
        sys.stderr.write('kernels cannot make namespaces of their own inside it: '
                         + what + ': ' + os.strerror(err) + '\\n')
        os._exit(__NO_NESTING__)
    if libc.unshare(0x10000000 | 0x00020000 | 0x20000000 | 0x40000000 | 0x08000000) != 0:
        refused('unshare', ctypes.get_errno())
    for name, text in (('setgroups', 'deny'), ('uid_map', f'{uid} {uid} 1'),
                       ('gid_map', f'{gid} {gid} 1')):
        try:
            with open('/proc/self/' + name, 'w') as f:
                f.write(text)
        except OSError as e:
            refused(name, e.errno)
    pid = os.fork()  # PID 1 of the new PID namespace: its own /proc, as a kernel's world has
    if pid == 0:
        if libc.mount(b'tmpfs', b'/tmp', b'tmpfs', 0, None) != 0:
            refused('mount /tmp', ctypes.get_errno())
        if libc.mount(b'proc', b'/proc', b'proc', 0, None) != 0:
            refused('mount /proc', ctypes.get_errno())
        os._exit(0)
    os._exit(os.waitstatus_to_exitcode(os.waitpid(pid, 0)[1]))
"""


def _try(sandbox: Sandbox, nesting: bool) -> subprocess.CompletedProcess:
    """Start a small program in ``sandbox`` that checks it (no network, a PID namespace, and
    with ``nesting`` the namespaces a kernel makes inside); what it ended with."""
    folder = Path(tempfile.mkdtemp(prefix="eulertop-probe-"))
    code = _PROBE.replace("__NESTING__", str(nesting)).replace("__NO_NESTING__", str(NO_NESTING))
    try:
        launch = sandbox.command([sys.executable, "-I", "-c", code], {"PATH": "/usr/bin"},
                                 folder, folder)
        if launch.uid is not None:
            os.chown(folder, launch.uid, launch.uid)
        try:
            return subprocess.run(launch.argv, capture_output=True, timeout=30, text=True,
                                  stdin=subprocess.DEVNULL, **launch.popen_options())
        except (OSError, subprocess.TimeoutExpired) as err:
            return subprocess.CompletedProcess(launch.argv, 1, "", f"bwrap: {err}")
    finally:
        shutil.rmtree(folder, ignore_errors=True)


@functools.cache
def probe() -> Sandbox:
    """The sandbox of this machine, checked by starting one: the ``world`` tier where a kernel
    can make namespaces of its own inside bubblewrap, else ``bwrap-per-kernel``;
    :class:`SandboxUnavailable` with the cause and fix (:func:`grader.sandbox.host.explain`)
    where bubblewrap cannot start at all — not Linux, no ``bwrap``, user namespaces refused
    (AppArmor, a sysctl, a container's seccomp profile)."""
    if not sys.platform.startswith("linux"):
        raise SandboxUnavailable(host.Diagnosis(
            "platform", f"bubblewrap needs Linux (this is {sys.platform})",
            "Fix: grade in the container image (README, 'Grading on macOS, Windows or in a "
            f"container'), {host.NO_SANDBOX}."))
    bwrap = shutil.which("bwrap")
    if bwrap is None:
        raise SandboxUnavailable(host.missing_bwrap())
    as_root = os.geteuid() == 0 and host.uids_mapped(UID_BASE, UID_SPAN)
    done = _try(Sandbox(bwrap, as_root), nesting=True)
    if done.returncode == 0:
        return Sandbox(bwrap, as_root)
    if done.returncode == NO_NESTING:
        why = done.stderr.strip().splitlines()[-1] if done.stderr.strip() else ""
        per_kernel = Sandbox(bwrap, as_root, per_kernel=True, why_per_kernel=why)
        again = _try(per_kernel, nesting=False)
        if again.returncode == 0:
            return per_kernel
        done = again
    raise SandboxUnavailable(host.explain(done.stderr))


def available() -> Sandbox | None:
    """:func:`probe`'s sandbox, or None where there is none."""
    try:
        return probe()
    except SandboxUnavailable:
        return None


# --------------------------------------------------------------------------------------------
# Starting processes from one long-lived thread


class _Spawner:
    """Starts processes from one daemon thread that lives as long as the grader.

    ``bwrap --die-with-parent`` and the zygote's own parent-death signal fire when the
    *thread* that started them ends, not the process; kernels are started from short-lived
    threads (``asyncio.to_thread``, worker pools). Started from this thread, they die exactly
    when the grader does — however it ends, SIGKILL included.
    """

    def __init__(self) -> None:
        self.requests: queue.Queue = queue.Queue()
        self.thread = threading.Thread(target=self._serve, name="eulertop-spawner", daemon=True)
        self.thread.start()

    def _serve(self) -> None:
        while True:
            args, kwargs, reply = self.requests.get()
            try:
                reply.put((subprocess.Popen(*args, **kwargs), None))
            except BaseException as err:  # handed to the caller
                reply.put((None, err))

    def popen(self, *args, **kwargs) -> subprocess.Popen:
        reply: queue.Queue = queue.Queue(maxsize=1)
        self.requests.put((args, kwargs, reply))
        process, err = reply.get()
        if err is not None:
            raise err
        return process


_spawner_lock = threading.Lock()
_spawner: _Spawner | None = None


def spawn(*args, **kwargs) -> subprocess.Popen:
    """``subprocess.Popen(*args, **kwargs)``, started from the grader's spawner thread."""
    global _spawner
    with _spawner_lock:
        if _spawner is None or not _spawner.thread.is_alive():
            _spawner = _Spawner()
        spawner = _spawner
    return spawner.popen(*args, **kwargs)


# --------------------------------------------------------------------------------------------
# Run folders

_run_lock = threading.Lock()
_run: dict = {"path": None, "users": 0}
_names = itertools.count()

SOCKET_PATH = 107
"""Longest path of a Unix socket (``sun_path``), bytes; IPC sockets live in control folders."""


def fresh_folder(parent: Path, letter: str) -> Path:
    """A new private folder (0700) ``parent/<letter><n>``: short names, since an IPC socket's
    whole path must fit in :data:`SOCKET_PATH` bytes."""
    while True:
        with _run_lock:
            path = Path(parent) / f"{letter}{next(_names)}"
        try:
            path.mkdir(mode=0o700)
            return path
        except FileExistsError:
            continue


def _run_parent() -> Path:
    """Where run folders are made: the temporary-files folder, unless its path is too long for
    the sockets below it (then ``/tmp``)."""
    parent = Path(tempfile.gettempdir())
    if len(os.fsencode(parent)) + 40 > SOCKET_PATH and os.access("/tmp", os.W_OK | os.X_OK):
        return Path("/tmp")
    return parent


def _pid_alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:
        return True
    return True


def remove_stale_run_folders(parent: Path | None = None) -> list[Path]:
    """Remove run folders of graders that were killed (module docstring); the list.

    Only entries of ``parent`` (default: the temporary-files folder) that are folders (not
    links) named exactly like :data:`RUN_FOLDER`, owned by this user, whose pid is not a live
    process, and not this process's own.
    """
    parent = Path(parent or _run_parent())
    removed = []
    with contextlib.suppress(OSError):
        for entry in os.scandir(parent):
            match = RUN_FOLDER.fullmatch(entry.name)
            if match is None or not entry.is_dir(follow_symlinks=False):
                continue
            pid = int(match.group(1))
            if pid == os.getpid() or _pid_alive(pid) or _owner_alive(Path(entry.path)):
                continue
            with contextlib.suppress(OSError):
                if entry.stat(follow_symlinks=False).st_uid != os.geteuid():
                    continue
                shutil.rmtree(entry.path)
                removed.append(Path(entry.path))
    return removed


OWNER = ".owner"
"""A file of each run folder its grader holds locked (``flock``) while it lives."""


def _owner_alive(folder: Path) -> bool:
    """Whether the grader of run folder ``folder`` still holds its :data:`OWNER` lock: a pid
    alone cannot say (a grader in another PID namespace sharing this ``/tmp``, a reused pid),
    a lock held by a live process can."""
    try:
        fd = os.open(folder / OWNER, os.O_RDONLY | os.O_NOFOLLOW)
    except OSError:
        return False  # none (a folder of an older version): the pid decides
    try:
        fcntl.flock(fd, fcntl.LOCK_SH | fcntl.LOCK_NB)
    except BlockingIOError:
        return True
    finally:
        os.close(fd)
    return False


def _hold_owner(folder: Path) -> int:
    """Make and lock ``folder``'s :data:`OWNER` file for this process's life of the folder;
    the descriptor (closed, which releases it, when the folder is removed)."""
    fd = os.open(folder / OWNER, os.O_RDWR | os.O_CREAT | os.O_EXCL | os.O_NOFOLLOW, 0o600)
    fcntl.flock(fd, fcntl.LOCK_EX)
    return fd


@contextlib.contextmanager
def run_folder() -> Iterator[Path]:
    """The process's run folder for the duration of the block (shared by nested and
    concurrent users; made by the first, removed by the last; stale ones removed first)."""
    with _run_lock:
        if _run["users"] == 0:
            parent = _run_parent()
            remove_stale_run_folders(parent)
            path = parent / f"eulertop-{os.getpid()}-{secrets.token_hex(4)}"
            path.mkdir(mode=0o711)
            os.chmod(path, 0o711)  # kernels with uids of their own traverse it to their folder
            _run["path"], _run["owner"] = path, _hold_owner(path)
        _run["users"] += 1
        path = _run["path"]
    try:
        yield path
    finally:
        with _run_lock:
            _run["users"] -= 1
            if _run["users"] == 0:
                shutil.rmtree(path, ignore_errors=True)
                os.close(_run.pop("owner"))
                _run["path"] = None
