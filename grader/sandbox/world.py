"""One student, one disposable world: the namespaces a forked kernel makes for itself (issue 11).

Run inside a slot's zygote (:mod:`grader.kernels.zygote`), in the child it forks for a kernel.
This file
is bound alone into the sandbox next to the zygote and imports nothing but the standard
library (and :mod:`seccomp` beside it).

The forked child *C* (:func:`enter`) leaves the zygote's world:

1. its own session (it runs as the sandbox's user: as root, a uid of the slot's own);
2. ``unshare`` of user, mount, PID, network, IPC and UTS namespaces, with its uid and gid mapped
   to themselves (no other id exists in there, so no file of any other user is writable
   whatever the capabilities in that namespace);
3. a fork: the child *G* is PID 1 of the new PID namespace and becomes the kernel; *C* stays
   outside it, invisible and unreachable from it, as the kernel's *keeper*: it waits for *G*,
   enforces the memory limit on all of G's processes together (:func:`keep`) and exits with
   G's exit status (or dies of the same signal), which the zygote reports as the kernel's.

*G* (:func:`build`) then makes its world, before any code of the student runs:

* a fresh, size-limited ``tmpfs`` at ``/tmp`` (its working folder, ``HOME``, ``TMPDIR``,
  IPython's and matplotlib's folders, its stderr log), with ``/dev/shm`` a folder of the same
  tmpfs: together never more than ``scratch_bytes``, and gone with the namespace;
* its own ``/proc`` (only its own processes), with ``/proc/sys`` read-only;
* the slot folder (on the host disk, where every kernel's control folder is) hidden under an
  empty read-only tmpfs, with only its own control folder bound back, which is made read-only
  once the kernel has bound its sockets (:func:`seal`);
* ``/`` and ``/dev`` read-only; no network but its own loopback; no SysV IPC object or
  hostname shared with anyone.

:func:`seal`, after the kernel is initialised and before it serves: the control folder
read-only; every capability of the main thread dropped; ``no_new_privs``; the seccomp filter of
:mod:`seccomp` on every thread (no ``ptrace``, ``process_vm_*``, ``mount``, ``unshare``,
``setns``, ``keyctl``, ``bpf``, ``memfd_create`` …), after which nothing of the above can be
undone.

Floor 1 of grader/ (one student, one disposable world; grader/API.md).
"""

from __future__ import annotations

import contextlib
import ctypes
import json
import os
import re
import resource
import signal
import socket
import stat
import time

try:
    from grader.sandbox import seccomp
except ImportError:  # inside the sandbox: bound beside this file, not as a package
    import seccomp  # type: ignore[no-redef]

CLONE_NEWNS, CLONE_NEWUTS, CLONE_NEWIPC = 0x00020000, 0x04000000, 0x08000000
CLONE_NEWUSER, CLONE_NEWPID, CLONE_NEWNET = 0x10000000, 0x20000000, 0x40000000
MS_RDONLY, MS_NOSUID, MS_NODEV, MS_NOEXEC = 0x1, 0x2, 0x4, 0x8
MS_REMOUNT, MS_BIND, MS_REC, MS_PRIVATE = 0x20, 0x1000, 0x4000, 0x40000
PR_SET_PDEATHSIG, PR_SET_DUMPABLE = 1, 4

WATCH_INTERVAL = 0.05
"""Seconds between two looks of the keeper at the memory of the kernel's processes."""

SHM = "/tmp/.shm"
"""The folder of the kernel's tmpfs that is also its ``/dev/shm``."""

_libc = ctypes.CDLL(None, use_errno=True)
_libc.mount.argtypes = [ctypes.c_char_p, ctypes.c_char_p, ctypes.c_char_p, ctypes.c_ulong,
                        ctypes.c_char_p]


def _check(result: int, what: str) -> None:
    if result != 0:
        err = ctypes.get_errno()
        raise OSError(err, f"{what}: {os.strerror(err)}")


def mount(source: str | None, target: str, fstype: str | None, flags: int,
          data: str | None = None) -> None:
    """``mount(2)``; OSError naming the target on failure."""
    def enc(s):
        return (None if s is None else os.fsencode(s))
    _check(_libc.mount(enc(source), enc(target), enc(fstype), flags, enc(data)),
           f"mount {target}")


def read_only(target: str) -> None:
    """Make the mount at ``target`` read-only (a bind remount keeps its other flags)."""
    flags = MS_REMOUNT | MS_BIND | MS_RDONLY
    try:
        mount(None, target, None, flags)
    except PermissionError:  # a locked mount keeps nosuid/nodev: say them again
        mount(None, target, None, flags | MS_NOSUID | MS_NODEV)


def _write(path: str, text: str) -> None:
    fd = os.open(path, os.O_WRONLY)
    try:
        os.write(fd, text.encode())
    finally:
        os.close(fd)


# --------------------------------------------------------------------------------------------
# C: leave the zygote's world, then keep the kernel


def enter(request: dict, link: socket.socket) -> None:
    """In the forked child C: new namespaces, then fork; returns in G (PID 1 of the new PID
    namespace) only — C keeps G (:func:`keep`) and never returns."""
    os.setsid()
    uid, gid = os.getuid(), os.getgid()
    flags = (CLONE_NEWUSER | CLONE_NEWNS | CLONE_NEWPID | CLONE_NEWNET | CLONE_NEWIPC
             | CLONE_NEWUTS)
    _check(_libc.unshare(flags), "unshare")
    # its own /proc/self/*_map are writable only while it is dumpable (a uid change, or the
    # zygote, made it not): for these three writes only
    _check(_libc.prctl(PR_SET_DUMPABLE, 1, 0, 0, 0), "prctl")
    _write("/proc/self/setgroups", "deny")
    _write("/proc/self/uid_map", f"{uid} {uid} 1")
    _write("/proc/self/gid_map", f"{gid} {gid} 1")
    _check(_libc.prctl(PR_SET_DUMPABLE, 0, 0, 0, 0), "prctl")
    # the /proc of this (the zygote's) PID namespace, kept open: G mounts its own over /proc
    # in the mount namespace the keeper shares with it
    proc = os.open("/proc", os.O_RDONLY | os.O_DIRECTORY)
    pid = os.fork()
    if pid == 0:
        # dies with its keeper (it cannot tell whether the keeper is already gone: its parent
        # is outside its PID namespace; the zygote then kills it as a stray)
        _check(_libc.prctl(PR_SET_PDEATHSIG, signal.SIGKILL, 0, 0, 0), "prctl")
        os.close(proc)
        return
    keep(pid, int(request["limits"]["memory"]), link, proc)


def keep(pid: int, memory: int, link: socket.socket, proc: int) -> None:
    """C, the keeper: wait for the kernel ``pid``; kill it (and so its whole PID namespace)
    if its processes together hold more than ``memory`` bytes; then end as it ended."""
    for signum in (signal.SIGINT, signal.SIGHUP, signal.SIGQUIT, signal.SIGTERM):
        signal.signal(signum, signal.SIG_IGN)
    kept = sorted({link.fileno(), proc})
    with contextlib.suppress(OSError):
        os.closerange(3, kept[0])
        os.closerange(kept[0] + 1, kept[1])
        os.closerange(kept[1] + 1, resource.getrlimit(resource.RLIMIT_NOFILE)[0])
    while True:
        done, status = os.waitpid(pid, os.WNOHANG)
        if done:
            break
        used = resident_bytes(pid, proc)
        if used > memory:  # over by the cheap upper bound: what do they hold in truth?
            used = resident_bytes(pid, proc, proportional=True)
        if used > memory:
            with contextlib.suppress(ProcessLookupError):
                os.kill(pid, signal.SIGKILL)
            with contextlib.suppress(OSError):
                link.send(json.dumps({"memory": used}).encode())
            _, status = os.waitpid(pid, 0)
            break
        time.sleep(WATCH_INTERVAL)
    code = os.waitstatus_to_exitcode(status)
    if code < 0:  # die of the same signal, so the zygote reports what G died of
        signal.signal(-code, signal.SIG_DFL)
        resource.setrlimit(resource.RLIMIT_CORE, (0, 0))
        os.kill(os.getpid(), -code)
        time.sleep(1)
    os._exit(code if code >= 0 else 1)


def resident_bytes(root: int, proc: int | str = "/proc", proportional: bool = False) -> int:
    """Resident memory of process ``root`` and all its descendants together, bytes.

    By default the sum of their ``VmRSS`` (cheap; pages shared between them, or with the zygote
    they were forked from, count once per process: never less than what they hold). With
    ``proportional``, the sum of their ``Pss`` (``smaps_rollup``: each shared page divided
    among its sharers), what they hold in truth — dearer to read, so the keeper reads it only
    when the first sum is over the limit. ``proc``: the procfs to read (a path, or an open
    descriptor)."""
    dir_fd = proc if isinstance(proc, int) else None

    def read(entry: str, name: str) -> dict[bytes, bytes]:
        path = f"{entry}/{name}" if dir_fd is not None else f"{proc}/{entry}/{name}"
        with open(os.open(path, os.O_RDONLY, dir_fd=dir_fd), "rb") as f:
            return dict(line.split(b":", 1) for line in f if b":" in line)

    ours = descendants(root, proc)
    total = 0
    for pid in ours:
        with contextlib.suppress(OSError, ValueError):
            if proportional:
                total += int(read(str(pid), "smaps_rollup").get(b"Pss", b"0 kB").split()[0])
            else:
                total += int(read(str(pid), "status").get(b"VmRSS", b"0 kB").split()[0])
    return total * 1024


def descendants(root: int, proc: int | str = "/proc") -> set[int]:
    """Process ``root`` and all its descendants: from the ``children`` lists of their threads
    (a few reads, where the kernel has them), else from every process's parent (a read of
    each process of ``proc``, a few milliseconds on a busy machine)."""
    def open_in_proc(path: str, flags: int = os.O_RDONLY) -> int:
        if isinstance(proc, int):
            return os.open(path, flags, dir_fd=proc)
        return os.open(f"{proc}/{path}", flags)

    def children(pid: int) -> list[int]:
        try:
            fd = open_in_proc(f"{pid}/task", os.O_RDONLY | os.O_DIRECTORY)
        except OSError:
            return []  # it ended
        try:
            tasks = os.listdir(fd)
        finally:
            os.close(fd)
        found: list[int] = []
        for tid in tasks:
            with contextlib.suppress(OSError), \
                    open(open_in_proc(f"{pid}/task/{tid}/children"), "rb") as f:
                found += [int(c) for c in f.read().split()]
        return found

    try:
        os.close(open_in_proc(f"{root}/task/{root}/children"))
    except FileNotFoundError:
        try:
            os.close(open_in_proc(f"{root}/task", os.O_RDONLY | os.O_DIRECTORY))
        except OSError:
            return {root}  # it ended
        return _descendants_by_parent(root, proc)  # no children lists in this kernel
    except OSError:
        return _descendants_by_parent(root, proc)
    ours, todo = {root}, [root]
    while todo:
        for kid in children(todo.pop()):
            if kid not in ours:
                ours.add(kid)
                todo.append(kid)
    return ours


def _descendants_by_parent(root: int, proc: int | str) -> set[int]:
    dir_fd = proc if isinstance(proc, int) else None
    parent: dict[int, int] = {}
    for entry in os.listdir(proc):
        if not entry.isdigit():
            continue
        path = f"{entry}/stat" if dir_fd is not None else f"{proc}/{entry}/stat"
        with contextlib.suppress(OSError, ValueError, IndexError):
            with open(os.open(path, os.O_RDONLY, dir_fd=dir_fd), "rb") as f:
                parent[int(entry)] = int(f.read().rsplit(b")", 1)[1].split()[1])
    ours = {root}
    grew = True
    while grew:
        grew = False
        for pid, ppid in parent.items():
            if ppid in ours and pid not in ours:
                ours.add(pid)
                grew = True
    return ours


# --------------------------------------------------------------------------------------------
# G: the kernel's own world


def build(request: dict, link: socket.socket) -> None:
    """In G, before any code of the student: the mounts of the module docstring; hands the
    zygote a descriptor of the (empty) working folder, for the submission to be delivered."""
    world = request["world"]
    control = request["control"]
    slot = os.path.dirname(control)
    keep_control = os.open(control, os.O_PATH | os.O_DIRECTORY)
    mount(None, "/", None, MS_REC | MS_PRIVATE)
    # what is mounted below /tmp (a Python environment there, as in a CI clone) is bound back
    # over the kernel's own /tmp; the slot folder is not (hidden below)
    kept = [(point, os.open(point, os.O_PATH)) for point in _mounts_below("/tmp")
            if point != slot and not point.startswith(slot + "/")]
    uid, gid = os.getuid(), os.getgid()
    mount("tmpfs", "/tmp", "tmpfs", MS_NOSUID | MS_NODEV,
          f"size={int(world['scratch_bytes'])},mode=0700,uid={uid},gid={gid}")
    for point, fd in kept:
        _bind_back(point, fd)
    for folder in (request["scratch"], os.path.join(request["scratch"], "work"),
                   os.path.join(request["scratch"], "ipython"),
                   os.path.join(request["scratch"], "matplotlib"), SHM):
        os.makedirs(folder, 0o700, exist_ok=True)
    # the slot folder: every kernel's control folder is there; only its own shows
    os.makedirs(slot, 0o700, exist_ok=True)
    mount("tmpfs", slot, "tmpfs", MS_NOSUID | MS_NODEV | MS_NOEXEC, "size=16k,mode=0755")
    os.mkdir(control, 0o700)
    mount(f"/proc/self/fd/{keep_control}", control, None, MS_BIND)
    os.close(keep_control)
    read_only(slot)
    mount("proc", "/proc", "proc", MS_NOSUID | MS_NODEV | MS_NOEXEC)
    mount("/proc/sys", "/proc/sys", None, MS_BIND | MS_REC)
    read_only("/proc/sys")
    read_only("/dev")
    mount(SHM, "/dev/shm", None, MS_BIND)
    read_only("/")
    _write_ipc_limits(int(world["scratch_bytes"]))
    work = os.open(os.path.join(request["scratch"], "work"), os.O_RDONLY | os.O_DIRECTORY)
    try:
        socket.send_fds(link, [b"work"], [work])
    finally:
        os.close(work)


def _mounts_below(top: str) -> list[str]:
    """The outermost mount points strictly below ``top`` in this mount namespace, shortest
    first: one below another listed is left out, since binding the outer one back
    (``MS_REC``) brings it along — and a file bound inside a read-only folder could not be
    bound again (a Python under a private folder in /tmp, as root: the zygote's own files are
    bound inside its site-packages)."""
    points = set()
    with open("/proc/self/mountinfo") as f:
        for line in f:
            point = line.split()[4]
            point = re.sub(r"\\([0-7]{3})", lambda m: chr(int(m.group(1), 8)), point)
            if point.startswith(top.rstrip("/") + "/"):
                points.add(point)
    outermost: list[str] = []
    for point in sorted(points, key=len):
        if not any(point.startswith(o + "/") for o in outermost):
            outermost.append(point)
    return outermost


def _bind_back(point: str, fd: int) -> None:
    """Bind what ``fd`` holds (a folder or a file) read-only at ``point`` again."""
    if stat.S_ISDIR(os.fstat(fd).st_mode):
        os.makedirs(point, 0o755, exist_ok=True)
    else:
        os.makedirs(os.path.dirname(point), 0o755, exist_ok=True)
        os.close(os.open(point, os.O_WRONLY | os.O_CREAT, 0o644))
    mount(f"/proc/self/fd/{fd}", point, None, MS_BIND | MS_REC)
    os.close(fd)
    read_only(point)


def _write_ipc_limits(scratch_bytes: int) -> None:
    """SysV shared memory of this IPC namespace: at most the scratch size in all (the
    namespace's own sysctls; it and its objects end with the kernel)."""
    page = os.sysconf("SC_PAGE_SIZE")
    for name, value in (("shmmax", scratch_bytes), ("shmall", scratch_bytes // page),
                        ("shmmni", 64), ("msgmnb", 1 << 16), ("msgmni", 64)):
        with contextlib.suppress(OSError):
            _write(f"/proc/sys/kernel/{name}", str(value))


def seal(request: dict) -> dict:
    """After the kernel bound its sockets, before it serves: control folder read-only,
    capabilities dropped, ``no_new_privs``, the seccomp filter on every thread. What was
    enforced, for the record."""
    read_only(request["control"])
    drop_capabilities()
    return {"seccomp": seccomp.install()}


def seal_alone() -> dict:
    """:func:`seal` for a kernel alone in its sandbox (the ``bwrap-per-kernel`` tier), which
    has no world of its own to make read-only: capabilities dropped, ``no_new_privs``, the
    seccomp filter with SysV IPC refused too (its IPC namespace's limits cannot be set)."""
    drop_capabilities()
    return {"seccomp": seccomp.install(ipc=True)}


class _CapHeader(ctypes.Structure):
    _fields_ = [("version", ctypes.c_uint32), ("pid", ctypes.c_int)]


class _CapData(ctypes.Structure):
    _fields_ = [("effective", ctypes.c_uint32), ("permitted", ctypes.c_uint32),
                ("inheritable", ctypes.c_uint32)]


def drop_capabilities() -> None:
    """Empty the effective, permitted and inheritable capability sets of this thread."""
    header = _CapHeader(0x20080522, 0)  # _LINUX_CAPABILITY_VERSION_3
    data = (_CapData * 2)()
    _check(_libc.capset(ctypes.byref(header), data), "capset")
