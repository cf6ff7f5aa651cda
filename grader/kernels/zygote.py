"""The warm fork server ("zygote") of :mod:`grader.kernels.pool`: one per worker slot.

Run by the grader as ``python grader/kernels/zygote.py`` (a script: this module imports nothing
of the
grader, so nothing of the grader's state is in its memory), with the scrubbed kernel
environment of :func:`grader.kernels.base.kernel_environment`, never the grader's own. It

1. makes itself non-dumpable (``PR_SET_DUMPABLE 0``: no ptrace, no ``/proc/<pid>/mem`` for
   processes without ``CAP_SYS_PTRACE``), a child subreaper (``PR_SET_CHILD_SUBREAPER``: a
   process a kernel leaves behind is re-parented here, where it is found and killed), and
   deaf to the catchable termination signals but SIGTERM;
2. with one BLAS/OpenMP thread set *before* numpy is imported, imports what every kernel
   needs — :data:`PRELOAD` (IPython, numpy, scipy, sympy) and :data:`KERNEL_MODULES` — makes
   the IPython shell every kernel runs its cells in (:func:`cell_server.make_shell`), and
   checks that it is still single-threaded and has no ZeroMQ context (both are unsafe across
   ``fork``);
   (With ``--preload-more``, started before the grader has read its class, it imports
   ``--preload``'s modules and then reads the rest from one line of its input,
   ``{"preload": [...]}``, before it makes the shell; the end of its input then ends it.)
3. writes ``{"ready": true, "pid", "preloaded", "cpu"}`` (``cpu``: the CPU seconds its start
   took) and then serves requests, one JSON object per line on stdin,
   answering on stdout; it reaps its children and reports each exit as an event.

Requests (``seq`` is echoed in the reply)::

    {"seq": 1, "op": "fork", "workdir": W, "control": C, "channel": S,
     "env": {...}, "limits": {"as": bytes, "cpu": s, "nproc": n, "fsize": bytes}}
        -> {"seq": 1, "pid": P}
    {"seq": 2, "op": "signal", "pid": P, "signal": 2}      # to P's whole process group
        -> {"seq": 2, "ok": true}
    {"seq": 3, "op": "kill", "pid": P}                      # SIGKILL P's group
        -> {"seq": 3, "ok": true}        # its exit event (leftovers killed) when reaped
    {"seq": 4, "op": "deliver", "pid": P, "name": N, "data": base64}
        -> {"seq": 4, "ok": true}        # file N into P's (still empty) scratch working folder

Sandboxed (issues 5 and 11, :mod:`grader.sandbox`), a fork request also has ``"world"`` and
``"scratch"``: the child leaves the zygote's world (:func:`world.enter`: new user, PID, mount,
network, IPC and UTS namespaces; the kernel is PID 1 of its own, watched by a keeper outside it)
and builds its own (:func:`world.build`: a size-limited tmpfs at ``/tmp`` holding ``scratch``
with ``work``, ``ipython``, ``matplotlib`` and the kernel's stderr; only its own control
folder). It sends the zygote a descriptor of its working folder over a socket pair; the
submission then arrives by ``deliver``, written through that descriptor (the grader cannot see
that tmpfs). The keeper reports on the same socket when it killed the kernel for its memory; the
exit event then says so (``"memory": bytes``).

In the ``bwrap-per-kernel`` tier (:mod:`grader.sandbox`: user namespaces do not nest), the zygote
is started in a fresh sandbox for one kernel and its fork request has ``"alone": true`` and
``"scratch"`` instead of ``"world"``: the zygote makes the kernel's folders in the sandbox's own
tmpfs and keeps a descriptor of its working folder for ``deliver``; the kernel makes no
namespaces (the sandbox is its own), stays dumpable (the grader outside watches its memory) and,
once connected, drops its capabilities and installs the seccomp filter, SysV IPC included
(:func:`world.seal_alone`).
    events: {"event": "exit", "pid": P, "status": S[, "memory": B]}  # S as Popen.returncode
            {"event": "stray", "pid": Q}                    # a leftover process was killed

End of stdin (the grader ended, however it ended) or SIGTERM (sent when the grader's thread
that started it ends, ``PR_SET_PDEATHSIG``) kills every child and leftover, removes the
kernels' folders (only those named in its fork requests), and exits. Pids are the zygote's own
(inside a PID namespace they differ from the grader's), which is why the grader signals
kernels through the zygote, never directly.

A forked child (:func:`_become_kernel`) starts its own session, asks to be SIGKILLed when the
zygote dies (``PR_SET_PDEATHSIG``), becomes non-dumpable (in its own world it stays dumpable,
for its keeper to read its memory; seccomp refuses ``ptrace``), closes every inherited fd
(the zygote's pipes to the grader included), applies the resource limits, replaces its
environment, chdirs into its private working folder, sends stdin/stdout to ``/dev/null`` and
stderr to ``control/kernel-stderr.txt``, reseeds what fork would otherwise share (numpy's
global random state), connects to the grader's socket ``S`` in its control folder (then, in its
own world, seals it: :func:`world.seal`), and serves the grader's requests there with its copy
of the zygote's shell (:func:`cell_server.serve`): no Jupyter kernel is started — the cells run
in the same IPython shell a Jupyter kernel runs them in, without its ZeroMQ channels, threads
and start-up (:mod:`grader.kernels.cell_server`).

Floor 2 of grader/ (one kernel; grader/API.md).
"""

from __future__ import annotations

import contextlib
import ctypes
import errno
import gc
import json
import os
import resource
import select
import signal
import socket
import sys
import time

for _var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS", "NUMEXPR_NUM_THREADS"):
    os.environ[_var] = "1"  # before numpy is imported: a single-threaded zygote forks safely

PRELOAD = ("IPython", "numpy", "scipy", "scipy.linalg", "scipy.special", "scipy.integrate",
           "scipy.optimize", "sympy")
"""Modules imported once in the zygote; every kernel forked from it has them already."""

KERNEL_MODULES = ("IPython.core.interactiveshell", "IPython.core.completerlib",
                  "IPython.core.debugger", "pdb", "IPython.core.logger", "IPython.core.oinspect",
                  "IPython.utils.wildcard", "sqlite3", "faulthandler")
"""What a kernel's shell imports while it runs its first cells (measured with IPython 9:
the history's sqlite3, the debugger and the inspector); imported too, when present."""

WORLD_TIMEOUT = 10.0
"""Seconds a forked kernel may take to make its own world (mounts) before it is given up."""

world = None  # grader/sandbox/world.py, bound beside this script in the sandbox
cell_server = None  # grader/kernels/cell_server.py, beside this script (and in the sandbox)
shell = None  # the IPython shell every kernel runs its cells in (cell_server.make_shell)

PR_SET_PDEATHSIG, PR_SET_DUMPABLE, PR_SET_CHILD_SUBREAPER = 1, 4, 36
IGNORED = (signal.SIGINT, signal.SIGHUP, signal.SIGQUIT, signal.SIGUSR1, signal.SIGUSR2)
_libc = ctypes.CDLL(None, use_errno=True)


def prctl(option: int, value: int) -> None:
    """``prctl(2)`` with one argument; OSError on failure."""
    if _libc.prctl(option, ctypes.c_ulong(value), 0, 0, 0) != 0:
        err = ctypes.get_errno()
        raise OSError(err, os.strerror(err))


def _send(message: dict) -> None:
    data = (json.dumps(message) + "\n").encode()
    while data:
        data = data[os.write(1, data):]


def _children_of(pid: int) -> list[int]:
    """Live processes whose parent is ``pid`` (leftovers re-parented to this subreaper)."""
    found = []
    for entry in os.listdir("/proc"):
        if not entry.isdigit():
            continue
        try:
            with open(f"/proc/{entry}/stat", "rb") as f:
                fields = f.read().rsplit(b")", 1)[1].split()
        except OSError:
            continue
        if int(fields[1]) == pid and fields[0] != b"Z":
            found.append(int(entry))
    return found


class Zygote:
    """The server loop: fork kernels on request, signal them, reap them, kill leftovers."""

    def __init__(self) -> None:
        self.kernels: set[int] = set()  # forked kernels not yet reaped
        self.folders: list[str] = []  # the kernels' folders (from the requests), removed at end
        self.own: dict[int, dict] = {}  # kernel pid -> its request while alive
        self.links: dict[int, socket.socket] = {}  # kernel pid -> the zygote's end of its link
        self.workdirs: dict[int, int] = {}  # kernel pid -> descriptor of its working folder
        self.pid = os.getpid()
        self.buffer = b""
        self.ending = False
        self.wake_r, wake_w = os.pipe()
        os.set_blocking(self.wake_r, False)
        os.set_blocking(wake_w, False)
        signal.set_wakeup_fd(wake_w)
        signal.signal(signal.SIGCHLD, lambda *_: None)  # the wakeup fd does the work
        signal.signal(signal.SIGTERM, self._end)

    def _end(self, *_: object) -> None:
        self.ending = True

    # -- requests

    def serve(self) -> None:
        while not self.ending:
            ready, _, _ = select.select([0, self.wake_r], [], [])
            if self.wake_r in ready:
                with contextlib.suppress(BlockingIOError):
                    os.read(self.wake_r, 4096)
                self.reap()
            if 0 in ready and not self.ending:
                chunk = os.read(0, 65536)
                if not chunk:
                    return  # the grader is gone
                self.buffer += chunk
                while b"\n" in self.buffer:
                    line, self.buffer = self.buffer.split(b"\n", 1)
                    self.handle(json.loads(line))

    def handle(self, request: dict) -> None:
        op, reply = request.get("op"), {"seq": request.get("seq")}
        try:
            if op == "fork":
                reply["pid"] = self.fork(request)
            elif op == "signal":
                self.signal_group(int(request["pid"]), int(request["signal"]))
                reply["ok"] = True
            elif op == "kill":
                self.kill(int(request["pid"]))
                reply["ok"] = True
            elif op == "deliver":
                self.deliver(request)
                reply["ok"] = True
            else:
                reply["error"] = f"unknown op {op!r}"
        except Exception as err:  # report, keep serving
            reply["error"] = f"{type(err).__name__}: {err}"
        _send(reply)

    def fork(self, request: dict) -> int:
        in_world = request.get("world") is not None
        alone = bool(request.get("alone"))
        if (in_world or alone) and world is None:
            raise RuntimeError("no per-kernel world here (grader/sandbox/world.py not bound)")
        link = child_link = None
        if in_world:
            link, child_link = socket.socketpair(socket.AF_UNIX, socket.SOCK_SEQPACKET)
        workdir = self._make_scratch(request["scratch"]) if alone else None
        pid = os.fork()
        if pid == 0:
            code = 1
            signal.set_wakeup_fd(-1)  # the server's: a signal here must not write into it
            try:
                if link is not None:
                    link.close()
                    world.enter(request, child_link)  # returns in the kernel only
                _become_kernel(request, self.pid, child_link)
                code = 0
            except BaseException:
                with contextlib.suppress(BaseException):
                    import traceback

                    traceback.print_exc(file=sys.__stderr__)  # the kernel's stderr log
            finally:
                os._exit(code)  # never return into the server loop
        if child_link is not None:
            child_link.close()
            self.links[pid] = link
        if workdir is not None:
            self.workdirs[pid] = workdir
        self.kernels.add(pid)
        if not in_world and not alone:  # a sandbox's own folders are in its tmpfs, gone with it
            self.folders += [request["workdir"], request["control"]]
        self.own[pid] = request
        return pid

    @staticmethod
    def _make_scratch(scratch: str) -> int:
        """A lone kernel's folders in the sandbox's tmpfs (its working folder, IPython's and
        matplotlib's); a descriptor of the (empty) working folder."""
        for folder in (scratch, *(os.path.join(scratch, sub)
                                  for sub in ("work", "ipython", "matplotlib"))):
            os.makedirs(folder, 0o700, exist_ok=True)
        return os.open(os.path.join(scratch, "work"), os.O_RDONLY | os.O_DIRECTORY)

    def _workdir_fd(self, pid: int) -> int:
        """The descriptor of a kernel's working folder in its own world (sent once by the
        kernel when its mounts are made); waits for it at most :data:`WORLD_TIMEOUT`."""
        if pid in self.workdirs:
            return self.workdirs[pid]
        link = self.links.get(pid)
        if link is None:
            raise ValueError("no such kernel")
        link.settimeout(WORLD_TIMEOUT)
        try:
            _, fds, _, _ = socket.recv_fds(link, 16, 1)
        except (OSError, TimeoutError) as err:
            raise ValueError(f"the kernel did not make its world ({err})") from None
        if not fds:
            raise ValueError("the kernel ended before making its world")
        self.workdirs[pid] = fds[0]
        return fds[0]

    def deliver(self, request: dict) -> None:
        """Write one file of the submission into a sandboxed kernel's (still empty) working
        folder, in its own tmpfs, through the descriptor it sent (:meth:`_workdir_fd`)."""
        import base64

        pid = int(request["pid"])
        own = self.own.get(pid)
        if own is None or (own.get("world") is None and not own.get("alone")):
            raise ValueError("no such sandboxed kernel")
        name = str(request["name"])
        if os.path.basename(name) != name or name in ("", ".", ".."):
            raise ValueError(f"not a file name: {name!r}")
        where = self._workdir_fd(pid)
        if os.listdir(where):
            raise ValueError("the working folder is not empty")
        fd = os.open(name, os.O_WRONLY | os.O_CREAT | os.O_EXCL | os.O_NOFOLLOW, 0o600,
                     dir_fd=where)
        try:
            data = base64.b64decode(request["data"])
            while data:
                data = data[os.write(fd, data):]
        finally:
            os.close(fd)

    def signal_group(self, pid: int, signum: int) -> None:
        if pid not in self.kernels:
            return  # already reaped: its pid may be reused, do not signal it
        with contextlib.suppress(ProcessLookupError, PermissionError):
            os.killpg(pid, signum)  # its own session: pgid == pid
        with contextlib.suppress(ProcessLookupError, PermissionError):
            os.kill(pid, signum)  # in case it left its group

    # -- children

    def kill(self, pid: int) -> None:
        """SIGKILL kernel ``pid``'s group. Not waited for: it is reaped (and what it left
        behind killed) when it has ended, its exit event sent then — the grader goes on
        while the kernel's memory is torn down (a few milliseconds of a big process)."""
        if pid in self.kernels:
            self.signal_group(pid, signal.SIGKILL)
        else:
            self.kill_strays()

    def _exited(self, pid: int, status: int) -> None:
        self.kernels.discard(pid)
        event = {"event": "exit", "pid": pid, "status": os.waitstatus_to_exitcode(status)}
        event.update(self._close_link(pid))
        self._clear(pid)
        _send(event)

    def _close_link(self, pid: int) -> dict:
        """Close what the zygote holds of a kernel's world; what its keeper said (e.g.
        ``{"memory": bytes}`` when it killed the kernel for its memory)."""
        said: dict = {}
        if pid in self.workdirs:
            with contextlib.suppress(OSError):
                os.close(self.workdirs.pop(pid))
        link = self.links.pop(pid, None)
        if link is not None:
            link.setblocking(False)
            with contextlib.suppress(OSError, ValueError):
                while True:
                    data, fds, _, _ = socket.recv_fds(link, 4096, 1)
                    for fd in fds:
                        os.close(fd)
                    if not data:
                        break
                    if data != b"work":
                        said.update(json.loads(data))
            link.close()
        return said

    def _clear(self, pid: int) -> None:
        """A kernel ended: forget its request (its world, if any, ended with it)."""
        self.own.pop(pid, None)

    def reap(self) -> None:
        """Collect every ended child; after a kernel ends, kill its leftovers."""
        ended = False
        while True:
            try:
                pid, status = os.waitpid(-1, os.WNOHANG)
            except ChildProcessError:
                break
            if pid == 0:
                break
            if pid in self.kernels:
                self._exited(pid, status)
                ended = True
        if ended:
            self.kill_strays()

    def kill_strays(self) -> None:
        """SIGKILL every child that is not a live kernel: what a kernel left behind."""
        for _ in range(100):  # a fork bomb re-parents in waves; RLIMIT_NPROC bounds them
            strays = [p for p in _children_of(self.pid) if p not in self.kernels]
            if not strays:
                return
            for pid in strays:
                with contextlib.suppress(ProcessLookupError):
                    os.kill(pid, signal.SIGKILL)
                _send({"event": "stray", "pid": pid})
            for pid in strays:
                with contextlib.suppress(ChildProcessError):
                    os.waitpid(pid, 0)

    def shutdown(self) -> None:
        for pid in list(self.kernels):
            self.signal_group(pid, signal.SIGKILL)
        for pid in list(self.kernels):
            with contextlib.suppress(ChildProcessError):
                os.waitpid(pid, 0)
        self.kernels.clear()
        for pid in list(self.own):
            self._clear(pid)
        self.kill_strays()
        self.remove_folders()

    def remove_folders(self) -> None:
        """Remove the kernels' folders named in the fork requests; then *only if empty* (plain
        ``rmdir``, never a recursive removal) the zygote's own folder and the two above it (the
        slot's and the pool's): a grader that was killed leaves nothing behind."""
        import shutil

        for folder in self.folders:
            shutil.rmtree(folder, ignore_errors=True)
        if "--remove-own-folder" not in sys.argv:
            return
        here = os.getcwd()
        with contextlib.suppress(OSError):
            os.unlink(os.path.join(here, "zygote-stderr.txt"))
        # the profile folder the shell made (IPYTHONDIR); rmtree does not follow symlinks
        shutil.rmtree(os.path.join(here, "ipython"), ignore_errors=True)
        for folder in (here, os.path.dirname(here), os.path.dirname(os.path.dirname(here))):
            with contextlib.suppress(OSError):
                os.rmdir(folder)  # fails unless empty: never removes anything else


def _tasks_of_user(uid: int) -> int:
    """Threads the real user ``uid`` has now (what ``RLIMIT_NPROC`` counts)."""
    total = 0
    for entry in os.listdir("/proc"):
        if not entry.isdigit():
            continue
        try:
            with open(f"/proc/{entry}/status") as f:
                status = dict(line.split(":", 1) for line in f if ":" in line)
        except (OSError, ValueError):
            continue
        if int(status.get("Uid", "-1").split()[0]) == uid:
            total += int(status.get("Threads", "1"))
    return total


def _set_limit(which: int, value: int) -> None:
    hard = resource.getrlimit(which)[1]
    if hard != resource.RLIM_INFINITY:
        value = min(value, hard)
    resource.setrlimit(which, (value, value))


def _become_kernel(request: dict, zygote_pid: int, link: socket.socket | None = None) -> None:
    """In the forked child: confine this process, then run the kernel (returns when it ends).

    With ``request["world"]`` (sandboxed) this runs in G, the kernel's own namespaces already
    made by :func:`world.enter`; it builds the kernel's mounts (:func:`world.build`) and seals
    them once the kernel is initialised (:func:`world.seal`)."""
    scratch = request.get("scratch")
    in_world = request.get("world") is not None
    alone = bool(request.get("alone"))
    if in_world:
        world.build(request, link)
        link.close()
    else:
        os.setsid()
        prctl(PR_SET_PDEATHSIG, signal.SIGKILL)
        if os.getppid() != zygote_pid:  # the zygote died before the line above
            os._exit(1)
    prctl(PR_SET_DUMPABLE, 1 if in_world or alone else 0)
    # In its own world (or alone in its sandbox) a kernel stays dumpable: its keeper (or the
    # grader) must read its processes' memory (smaps_rollup). Nothing untrusted can name it —
    # other kernels are in other PID namespaces — and its own processes cannot ptrace
    # anything (seccomp).
    signal.set_wakeup_fd(-1)
    for signum in (signal.SIGCHLD, signal.SIGTERM, *IGNORED):
        signal.signal(signum, signal.SIG_DFL)
    os.umask(0o077)
    # stdio: nothing inherited stays open (fds 0 and 1 were the zygote's pipes to the grader)
    null = os.open(os.devnull, os.O_RDWR)
    log = os.open(os.path.join(scratch or request["control"], "kernel-stderr.txt"),
                  os.O_WRONLY | os.O_CREAT | os.O_TRUNC | os.O_NOFOLLOW, 0o600)
    os.dup2(null, 0)
    os.dup2(null, 1)
    os.dup2(log, 2)
    os.closerange(3, resource.getrlimit(resource.RLIMIT_NOFILE)[0])
    limits = request["limits"]
    _set_limit(resource.RLIMIT_CORE, 0)
    _set_limit(resource.RLIMIT_AS, int(limits["as"]))
    _set_limit(resource.RLIMIT_CPU, int(limits["cpu"]))
    _set_limit(resource.RLIMIT_FSIZE, int(limits["fsize"]))
    if in_world:  # counted in its own user namespace: its own processes only
        _set_limit(resource.RLIMIT_NPROC, int(limits["nproc"]))
    elif alone:  # counted in the sandbox's user namespace: the zygote's threads and its own
        _set_limit(resource.RLIMIT_NPROC, _tasks_of_user(os.getuid()) + int(limits["nproc"]))
    else:  # RLIMIT_NPROC counts every thread of the real user: what exists plus a margin
        base = limits.get("nproc_base")  # given where this /proc does not see every process
        base = _tasks_of_user(os.getuid()) if base is None else int(base)
        _set_limit(resource.RLIMIT_NPROC, base + int(limits["nproc"]))
    os.environ.clear()
    os.environ.update(request["env"])
    os.chdir(request["workdir"])
    import tempfile

    tempfile.tempdir = None  # gettempdir() is cached; TMPDIR changed
    if "numpy" in sys.modules:  # fork copied numpy's global random state: draw a fresh one
        sys.modules["numpy"].random.seed()
    channel = socket.socket(socket.AF_UNIX, socket.SOCK_STREAM)
    channel.connect(request["channel"])  # the grader's socket in the control folder
    if in_world or alone:  # connected: nothing of the world can be changed from here on
        sealed = world.seal(request) if in_world else world.seal_alone()
        print(f"eulertop: kernel sealed ({json.dumps(sealed)})", file=sys.stderr, flush=True)
    cell_server.serve(shell, channel)


PRELOAD_MORE_BYTES = 64 * 1024
"""Longest line of ``--preload-more``'s modules the zygote reads (a few dozen names)."""


def _preload_more() -> tuple[str, ...] | None:
    """With ``--preload-more``: the modules the grader asks for once it has read its class,
    one line ``{"preload": [name, ...]}`` on stdin, read a byte at a time (what follows it is
    the server's: :meth:`Zygote.serve`); None at the end of input."""
    line = b""
    while not line.endswith(b"\n"):
        byte = os.read(0, 1)
        if not byte or len(line) > PRELOAD_MORE_BYTES:
            return None
        line += byte
    names = json.loads(line).get("preload", [])
    return tuple(str(name) for name in names)


def main() -> None:
    """Entry point: make the server ready (imports), then serve until the grader leaves."""
    global world, cell_server, shell
    if sys.path and os.path.abspath(sys.path[0]) == os.path.dirname(os.path.abspath(__file__)):
        if "--world" in sys.argv:  # sandboxed: world.py and seccomp.py are bound beside us
            import world as world_module

            world = world_module
        import cell_server as cell_server_module

        cell_server = cell_server_module
        del sys.path[0]  # run as a script: the grader's folder is not for kernels to import
    prctl(PR_SET_DUMPABLE, 0)
    prctl(PR_SET_CHILD_SUBREAPER, 1)
    for signum in IGNORED:
        signal.signal(signum, signal.SIG_IGN)
    signal.signal(signal.SIGTERM, signal.SIG_IGN)  # until the server handles it
    if "--die-with-parent" in sys.argv:  # when the grader's starting thread outlives us
        prctl(PR_SET_PDEATHSIG, signal.SIGTERM)  # SIGTERM: cleaned up like end of input
    import importlib

    # What is imported here is shared with every kernel until written to; a garbage
    # collection in a kernel writes to every object it visits (copying the page). So: no
    # collection while importing, then everything frozen (out of the collector's sight) before
    # the first fork; collections after that (the zygote's, its kernels') visit only newer
    # objects.
    gc.disable()
    preload = PRELOAD
    for arg in sys.argv[1:]:
        if arg.startswith("--preload="):
            preload = tuple(filter(None, arg.split("=", 1)[1].split(",")))
    for name in preload:
        importlib.import_module(name)
    for name in KERNEL_MODULES:
        with contextlib.suppress(ImportError):
            importlib.import_module(name)
    if "--preload-more" in sys.argv:  # started before the grader read its class (issue 34)
        more = _preload_more()
        if more is None:
            return  # the grader ended (or has no kernel to ask for) before saying
        for name in more:
            importlib.import_module(name)
        preload = (*preload, *(name for name in more if name not in preload))
    shell = cell_server.make_shell()
    threads = len(os.listdir("/proc/self/task"))
    zmq = sys.modules.get("zmq")
    if threads != 1 or (zmq is not None and zmq.Context._instance is not None):
        _send({"ready": False, "error": f"not fork-safe after imports ({threads} threads)"})
        return
    gc.freeze()
    gc.enable()
    zygote = Zygote()
    _send({"ready": True, "pid": zygote.pid, "preloaded": list(preload),
           "cpu": round(time.process_time(), 3)})  # what a start costs (another slot's)
    try:
        zygote.serve()
    finally:
        zygote.shutdown()
    # everything is cleaned up: skip the interpreter's finalisation of every module the
    # zygote imported (a few hundred ms the grader would wait for at the end of every run)
    with contextlib.suppress(OSError, ValueError):
        sys.stdout.flush()
    os._exit(0)


if __name__ == "__main__":
    try:
        main()
    except OSError as err:
        if err.errno != errno.EPIPE:
            raise
