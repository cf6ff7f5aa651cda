"""The cell server: what a kernel forked from a zygote runs instead of a Jupyter kernel.

Bound beside :mod:`grader.kernels.zygote` (a script: like it, this module imports nothing of the
grader) and imported by it. The zygote makes one IPython shell (:func:`make_shell`) before
its first fork; each forked kernel, once confined, connects to the grader's socket in its own
control folder and runs what the grader sends (:func:`serve`) in its own copy of that shell —
the same ``InteractiveShell`` (magics, ``display``, top-level ``await``, IPython's error
messages) a Jupyter kernel runs, without what a notebook's *grading* never
uses: ZeroMQ, five channels and their threads, message signing, a debugger. A kernel then
costs milliseconds of CPU where ipykernel's start-up alone cost about fifty (issue 17;
``benchmarks/bench_kernel_start.py``).

Protocol: one JSON object per line, UTF-8, on a ``SOCK_STREAM`` Unix socket. The kernel first
says ``{"ready": true}``; then, for each request of the grader, in order::

    {"n": 1, "op": "execute", "code": C}
        -> {"n": 1, "reply": {"status": "ok"}, "output": characters}
        -> {"n": 1, "reply": {"status": "error", "ename": E, "evalue": V}, "output": ...}
    {"n": 2, "op": "answers", "code": C, "user_expressions": {name: expression}}
        -> {"n": 2, "reply": {"status": "ok", "user_expressions": {...}}, "output": ...}

``reply`` is what an ipykernel ``execute_reply`` would hold (``user_expressions`` evaluated
only when the code raised nothing, as ipykernel does). ``output``: characters the request
printed or displayed — counted, never kept or sent, since output is never graded.
Everything the kernel says is untrusted (it is the student's process): the grader bounds
each line (:data:`grader.kernels.base.MAX_MESSAGE`, read by :mod:`grader.kernels.channel`) and
matches replies by ``n``.

Each forked kernel has its own IPython profile, where its environment's ``IPYTHONDIR`` says
(as a cold ipykernel has): ``%store`` (IPython's ``storemagic``, loaded as ipykernel loads it)
keeps its database there, in a folder of that kernel's own.

Interrupts: SIGINT raises ``KeyboardInterrupt`` while a request runs and is ignored between
requests, and ``input()`` and ``getpass()`` raise ``StdinNotImplementedError``, as in ipykernel
run by a front end that allows no input (nbclient, nbgrader).

Floor 2 of grader/ (one kernel; grader/API.md).
"""

from __future__ import annotations

import builtins
import contextlib
import getpass
import io
import json
import os
import signal
import socket
import sys
from typing import Any


class OutputCount(io.TextIOBase):
    """``sys.stdout``/``sys.stderr`` of a kernel: counts the characters written, keeps none
    (output is never graded; only whether it went over the limit is recorded)."""

    encoding = "utf-8"
    errors = "strict"

    def __init__(self, name: str) -> None:
        super().__init__()
        self.name = name
        self.count = 0

    def write(self, text: str) -> int:
        if not isinstance(text, str):
            raise TypeError(f"write() argument must be str, not {type(text).__name__}")
        self.count += len(text)
        return len(text)

    def writable(self) -> bool:
        return True

    def isatty(self) -> bool:
        return False

    def fileno(self) -> int:
        return 1  # /dev/null in a kernel: what a library writes at the fd level is dropped


def _content_size(content: Any) -> int:
    """Characters of text in displayed data, counted as :func:`grader.execute._content_size`
    counts a Jupyter kernel's output message (written again here: this module, bound alone
    beside the zygote, imports nothing of the grader)."""
    if isinstance(content, str):
        return len(content)
    if isinstance(content, dict):
        return sum(_content_size(v) for v in content.values())
    if isinstance(content, (list, tuple)):
        return sum(_content_size(v) for v in content)
    return 8


def make_shell() -> Any:
    """The IPython shell every forked kernel runs its cells in (made once, in the zygote).

    No history file (an in-memory database and no saving thread: the zygote must stay
    single-threaded to fork); displayed data counted, not kept; ``exit()`` does nothing, as in
    a Jupyter kernel run by nbclient (it asks the front end, which ignores it); ``%matplotlib``
    starts no GUI event loop (there is no screen).
    """
    from IPython.core.displaypub import DisplayPublisher
    from IPython.core.interactiveshell import InteractiveShell
    from traitlets.config import Config

    class CountingDisplay(DisplayPublisher):
        """``display()``: counts the characters of what is displayed, keeps nothing."""

        def publish(self, data: Any, metadata: Any = None, *args: Any, **kwargs: Any) -> None:
            out = sys.stdout
            if isinstance(out, OutputCount):
                out.count += _content_size(data)

        def clear_output(self, wait: bool = False) -> None:
            pass

    config = Config()
    config.HistoryManager.hist_file = ":memory:"
    config.HistoryManager.enabled = False
    config.InteractiveShell.colors = "nocolor"
    shell = InteractiveShell.instance(config=config)
    shell.display_pub = CountingDisplay(shell=shell, parent=shell)
    shell.ask_exit = lambda: None  # what exit() and quit() call
    shell.enable_gui = lambda gui=None: None  # %matplotlib: no event loop to run, no screen
    with contextlib.suppress(Exception):  # %store, as ipykernel loads it; without it, no %store
        shell.extension_manager.load_extension("storemagic")
    # once here, not in every kernel: what IPython sets up on its first cell (it leaves
    # nothing in the namespace: no history, no output)
    shell.run_cell("pass", store_history=False, silent=True)
    return shell


def _send(sock: socket.socket, message: dict) -> None:
    sock.sendall((json.dumps(message, default=repr) + "\n").encode())


def _reply(result: Any) -> dict:
    """An ipykernel-shaped ``execute_reply`` content of one ``run_cell`` result."""
    if result.success:
        return {"status": "ok"}
    err = result.error_before_exec if result.error_before_exec is not None \
        else result.error_in_exec
    return {"status": "error", "ename": type(err).__name__, "evalue": str(err)}


def _answers(shell: Any, request: dict) -> dict:
    """The extraction: its code run in the notebook's namespace as a cell's would be, but
    straight (none of IPython's input transformations, hooks or output: the grader's own
    code, not the student's), then its expressions evaluated there, each given as the
    ``text/plain`` of its value — its ``repr``, which is what IPython's formatter gives for
    the string the extraction makes (ipykernel's ``user_expressions``, without the other
    formats nobody reads)."""
    try:
        exec(compile(request["code"], "<eulertop-answers>", "exec"), shell.user_global_ns,
             shell.user_ns)
    except (Exception, SystemExit) as err:  # a notebook that broke what the code needs
        return {"status": "error", "ename": type(err).__name__, "evalue": str(err),
                "user_expressions": {}}
    expressions = request.get("user_expressions")
    values = {}
    for name, expression in (expressions if isinstance(expressions, dict) else {}).items():
        try:
            text = repr(eval(str(expression), shell.user_global_ns, shell.user_ns))
        except (Exception, SystemExit) as err:
            values[name] = {"status": "error", "ename": type(err).__name__,
                            "evalue": str(err), "traceback": []}
        else:
            values[name] = {"status": "ok", "data": {"text/plain": text}, "metadata": {}}
    return {"status": "ok", "user_expressions": values}


def _run(shell: Any, request: dict) -> dict:
    """Run one request's code in the shell, interruptible; its reply."""
    code = request.get("code")
    if not isinstance(code, str):
        return {"status": "error", "ename": "ValueError", "evalue": "no code"}
    signal.signal(signal.SIGINT, signal.default_int_handler)
    try:
        if request.get("op") == "answers":
            return _answers(shell, request)
        return _reply(shell.run_cell(code, store_history=True, silent=False))
    except KeyboardInterrupt:  # landed outside the cell's own code (IPython's machinery)
        return {"status": "error", "ename": "KeyboardInterrupt", "evalue": ""}
    finally:
        signal.signal(signal.SIGINT, signal.SIG_IGN)


def _no_input(*args: Any, **kwargs: Any) -> str:
    """``input()`` in a kernel: there is no one to answer (ipykernel's own message)."""
    from IPython.core.error import StdinNotImplementedError

    raise StdinNotImplementedError(
        "raw_input was called, but this frontend does not support input requests.")


def _own_profile(shell: Any) -> None:
    """This kernel's own IPython profile, ``$IPYTHONDIR/profile_default`` of the environment the
    grader gives it, where a cold ipykernel has its profile — not the zygote's (read-only in the
    sandbox, shared by every kernel of the slot outside it, and a path of the grader's run
    folder). ``%store`` keeps its database there, as in Jupyter: in a folder of this kernel's
    own (its sandbox's tmpfs, or its control folder), which no later kernel sees."""
    from IPython.core.profiledir import ProfileDir

    shell.ipython_dir = os.environ.get("IPYTHONDIR") or os.path.expanduser("~/.ipython")
    shell.profile_dir = ProfileDir.create_profile_dir(
        os.path.join(shell.ipython_dir, "profile_default"))
    if isinstance(getattr(type(shell), "db", None), property):
        shell.db = None  # IPython 9: made again on first use, in the profile now set
    else:  # IPython 7 and 8 made it with the shell
        shell.db = type(shell.db)(os.path.join(shell.profile_dir.location, "db"))


def serve(shell: Any, sock: socket.socket) -> None:
    """In the forked kernel: say ready, then run the grader's requests until it hangs up."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)  # until a request runs
    out, err = OutputCount("<stdout>"), OutputCount("<stderr>")
    sys.stdout, sys.stderr = out, err
    sys.stdin = io.StringIO()
    builtins.input = getpass.getpass = _no_input
    _own_profile(shell)
    requests = sock.makefile("rb")
    _send(sock, {"ready": True})
    while True:
        try:
            sock.setblocking(True)  # a cell may have made it non-blocking (a shared descriptor)
            line = requests.readline()
        except KeyboardInterrupt:  # an interrupt between requests: ignored (and so here)
            continue
        if not line:
            return  # the grader hung up
        try:
            request = json.loads(line)
            n = request["n"]
        except (ValueError, KeyError, TypeError):
            continue
        before = out.count + err.count
        reply = _run(shell, request)
        with contextlib.suppress(KeyboardInterrupt):
            _send(sock, {"n": n, "reply": reply, "output": out.count + err.count - before})
