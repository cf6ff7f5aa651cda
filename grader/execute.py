"""Run one submission in a fresh, limited Python kernel and read its answers.

Stage *execute* of the pipeline (``grader/API.md``): ``execute_submission(path, variables,
limits) -> Execution``.

What one run does
    1. :func:`grader.notebook_load.read_notebook` reads and sanitizes the file (a notebook that
       cannot be read gives status ``"invalid_notebook"`` without starting anything).
    2. Two private folders are made in the run folder (:func:`grader.sandbox.run_folder`):
       the kernel's working folder, holding only a copy of the submission, and a control
       folder (connection file, IPC sockets, IPython's profile, the kernel's stderr) that is
       not its working folder.
    3. A kernel is started by the *kernel factory* — e.g. :class:`LocalKernel`: always
       the grader's own interpreter running ipykernel (whatever the notebook's kernelspec or
       language says), in its own session and process group, with a scrubbed environment, an
       address-space limit, one BLAS/OpenMP thread, and stdin/stdout closed.
    4. Every code cell runs in order (``allow_errors``: a cell that raises does not stop the
       rest) — through nbclient for a Jupyter kernel (:class:`LocalKernel`), through its cell
       server for a kernel forked from a zygote (:mod:`grader.kernels.channel`). A cell that runs
       longer than the cell time limit is interrupted (``KeyboardInterrupt``) and the next one
       runs.
    5. The answers are read by one more request the student never saw (:mod:`grader.extract`).
    6. A whole-notebook deadline is enforced here, outside nbclient: when it passes the kernel's
       process group is killed, whatever it was doing (a loop that swallows
       ``KeyboardInterrupt`` ends here).
    7. Always, in ``finally``: the process group is killed, the sockets closed, both folders
       removed.

Output
    Output is never graded. A forked kernel only counts it
    (:mod:`grader.kernels.cell_server`); from a
    Jupyter kernel, :class:`_CappedClient` keeps at most ``Limits.output_bytes``
    characters of it per notebook and drops the rest on arrival; display updates and widget
    (comm) messages, which nbclient would otherwise accumulate, are ignored. A single message
    larger than :data:`MAX_MESSAGE` is refused by ZeroMQ before it is read
    (``MAXMSGSIZE`` on the IOPub socket only), which severs IOPub: from then on outputs are
    no longer collected, cells still run, answers are still read (they come back on the shell
    channel), and ``output_truncated`` is set.

Statuses (``Execution.status``)
    ``"ok"``: every cell was run (some may have raised or timed out: ``cell_errors``) and the
    answers were read. ``"invalid_notebook"``: the file is not a notebook we can run.
    ``"timeout"``: the whole-notebook time limit passed; the kernel was killed; no answers.
    ``"kernel_died"``: the kernel process ended (``os._exit``, ``exit()``, a crash, memory);
    cells after it did not run; no answers. ``"error"``: the kernel could not be started, or
    the notebook ran but its answers could not be read (the notebook broke the machinery the
    extraction needs); no answers.

Swapping the kernel (issue 5's sandbox, warm kernels)
    The kernel's launch, interrupt and kill live in one class, :class:`LocalKernel`;
    :func:`execute_submission` takes ``kernel_factory``, any callable ``(workdir, control,
    limits) -> KernelProcess``. The warm pool (:mod:`grader.kernels.pool`, the grader's default)
    hands out kernels forked from a pre-imported zygote, with launch, interrupt and kill going
    through it (:class:`LocalKernel` subclass, sharing :meth:`LocalKernel._connect`). Without a
    factory, a submission runs in a one-slot sandboxed pool of its own (:mod:`grader.sandbox`)
    where a sandbox can be had (``sandbox=None``), and in an unsandboxed :class:`LocalKernel`
    otherwise or with ``sandbox=False``. ``Execution.sandboxed`` says which it was.

Floor 3 of grader/ (the stages of one submission; grader/API.md).
"""

from __future__ import annotations

import asyncio
import contextlib
import functools
import logging
import re
import shutil
import signal
import time
from collections.abc import Sequence
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any

from grader.extract import (
    ANSWER_SECONDS,
    EXTRACTION_FAILED,
    extraction_request,
    parse_answers,
)
from grader.kernels.base import STOP_TIMEOUT, KernelFactory, KernelProcess
from grader.kernels.local import LocalKernel
from grader.limits import Limits
from grader.notebook_load import CodeCell, SubmissionError, executable_notebook, read_notebook
from grader.notebook_metadata import identity_of

__all__ = [
    "STATUSES",
    "Execution",
    "Limits",
    "SubmissionError",
    "execute_submission",
]

log = logging.getLogger(__name__)

STATUSES = ("ok", "invalid_notebook", "timeout", "kernel_died", "error")


EXTRACTION_TIMEOUT = 10.0
"""Seconds the answer extraction may take, beyond :data:`grader.extract.ANSWER_SECONDS` per
answer (the kernel bounds the reading of each: :func:`extraction_seconds`), within what is left
of the whole-notebook limit."""


def extraction_seconds(variables: Sequence[str], limits: Limits) -> float:
    """How long the grader waits for the answers of ``variables``: :data:`EXTRACTION_TIMEOUT`
    and :data:`grader.extract.ANSWER_SECONDS` per answer, at most the notebook's limit."""
    return min(EXTRACTION_TIMEOUT + ANSWER_SECONDS * len(variables), limits.total_timeout)


OUT_OF_TIME_GRACE = 5.0
"""Seconds, past the whole-notebook limit, for interrupting the cell that ran out of time and
reading the answers set before it (a cell that ignores the interrupt is killed then)."""


_CELL_FILE = re.compile(r"\((?:\d+\.py|<ipython-input-\d+-[0-9a-f]+>), line (\d+)\)")
"""A cell's file name in an error message: ipykernel's, or IPython's (a forked kernel's)."""

_HINTS = {
    "SystemExit": "sys.exit() and exit() stop a script, not a notebook cell: remove it",
    "KeyboardInterrupt": "interrupted",
    "ModuleNotFoundError": "only the grader's installed packages are available",
    "StdinNotImplementedError": "input() waits for someone to type, and no one types while the "
                                "grader runs the notebook: write the value into the code instead",
}
"""What a student can do about an error, by its name (issue 33: words for a student, not the
kernel's own ``raw_input was called, but this frontend does not support input requests``)."""

NO_NETWORK = ("the grader runs notebooks without a network: put the data you need into the "
              "notebook itself (a list, or values in a cell) instead of downloading it")
"""The hint for an error that says a connection could not be made (:data:`_NETWORK_ERRORS`)."""

MISSING_MAGIC = ("the grader's kernel has IPython's own magics and %store, as Jupyter does; this "
                 "one comes from an extension it does not load: do the same in plain Python")
"""The hint for a magic the kernel does not know (``UsageError: Line magic function … not
found``)."""

_NETWORK_ERRORS = frozenset({
    "URLError", "HTTPError", "gaierror", "ConnectionError", "ConnectionRefusedError",
    "ConnectionResetError", "ConnectionAbortedError", "NewConnectionError", "MaxRetryError",
    "RemoteDisconnected", "timeout", "TimeoutError", "SSLError", "ProxyError",
})
"""Names of the exceptions urllib, socket, http.client, requests and urllib3 raise when no
connection can be made: in the sandbox there is no network at all."""

_NETWORK_TEXT = re.compile(r"Name or service not known|Temporary failure in name resolution|"
                           r"Network is unreachable|No address associated|nodename nor servname",
                           re.IGNORECASE)
"""What an ``OSError`` says when there is no network (raised under its own name)."""

_INSTALL_PATH = re.compile(r"(?:/[^\s'\"():,]+)?/(?:site|dist)-packages/([^\s'\"():,]+)")
"""A path inside an installed package (``/usr/lib/python3/dist-packages/IPython/display.py``):
shown as the package's own path (``IPython/display.py``), never the grader's machine's."""


def without_install_paths(text: str) -> str:
    """``text`` with every path into an installed package cut to the package's own part
    (``…/site-packages/IPython/display.py`` → ``IPython/display.py``): a student sees nothing
    of the grader's machine, and the part left is the same on theirs.

    Examples
    --------
    >>> without_install_paths("from 'IPython.display' (/opt/v/lib/python3.11/site-packages/"
    ...                       "IPython/display.py)")
    "from 'IPython.display' (IPython/display.py)"
    """
    return _INSTALL_PATH.sub(r"\1", text)


_RUN_PATH = re.compile(r"(?:/[^\s'\"():,/]+)*/eulertop-\d+-[0-9a-f]{8}((?:/[^\s'\"():,/]+)*)")
"""A path into the grader's run folder (:func:`grader.sandbox.run_folder`: ``eulertop-<pid>-
<hex>``), where a kernel outside a sandbox has its working folder."""


def without_run_folder(text: str) -> str:
    """``text`` with every path into the grader's run folder cut to its last part, the name of
    the file (``/tmp/eulertop-81-3fa2c01b/w3/data.csv`` → ``data.csv``): what the student's own
    notebook calls it, nothing of the grader's machine.

    Examples
    --------
    >>> without_run_folder("No such file or directory: '/tmp/eulertop-81-3fa2c01b/w3/data.csv'")
    "No such file or directory: 'data.csv'"
    """
    return _RUN_PATH.sub(lambda m: m.group(1).rsplit("/", 1)[-1] or "…", text)


@dataclass(frozen=True)
class Execution:
    """The outcome of running one submission.

    Attributes
    ----------
    status : str
        One of :data:`STATUSES` (module docstring).
    message : str
        For a person: what happened, naming the cells (``cell 7 (`x = 1/0`): ZeroDivisionError:
        division by zero``).
    answers : dict
        Declared variable → plain JSON value (``None`` if unset), or an ``{"__invalid__":
        reason}`` marker (:func:`grader.extract.invalid_reason`). Only the declared names; empty
        when nothing could be read. Floats may be NaN or infinite (faithfully extracted; the
        comparison reports them).
    cell_errors : tuple of str
        One line per cell that raised, timed out, or was running when the kernel died or time
        ran out.
    duration : float
        Wall time of the run, seconds.
    output_truncated : bool
        Some output was dropped (over ``Limits.output_bytes``, or one message too large).
    sandboxed : bool
        The kernel ran inside the sandbox of :mod:`grader.sandbox` (issue 5).
    retry : bool
        The run failed for a reason that is not the submission's (no kernel could be started
        in time): the grader runs it again, and never keeps it as a final result.
    isolation : str
        What confined the kernel, for the record (:meth:`grader.sandbox.Sandbox.describe`).
    notes : tuple of str
        Remarks on the reading that begin ``message`` too (converted from nbformat v3; a
        notebook whose kernel is not Python: :func:`grader.notebook_load.language_note`).
    identity : grader.notebook_metadata.Identity or None
        What the notebook's metadata says it is (whose, of which assignment), read from the
        notebook this stage parsed; None where it was not parsed.
    """

    status: str
    message: str
    answers: dict[str, Any]
    cell_errors: tuple[str, ...]
    duration: float
    output_truncated: bool
    sandboxed: bool = False
    retry: bool = False
    isolation: str = ""
    notes: tuple[str, ...] = ()
    identity: Any = None  # what its metadata says it is (grader.notebook_metadata)


# --------------------------------------------------------------------------------------------
# One run


@dataclass
class _Run:
    """What a run has done so far (read when it ends, however it ends)."""

    cells: tuple[CodeCell, ...]
    limits: Limits
    phase: str = "starting"  # starting | running | extracting | done
    running: CodeCell | None = None
    errors: list[str] = field(default_factory=list)
    timed_out: set[int] = field(default_factory=set)
    answers: dict[str, Any] = field(default_factory=dict)
    problem: str | None = None
    truncated: bool = False
    out_of_time: CodeCell | None = None  # the cell running when the notebook's time ran out
    kept: int = 0  # characters of output so far (a cell server's count)


class _KernelDied(Exception):
    pass


def execute_submission(
    path: Path,
    variables: Sequence[str],
    limits: Limits,
    *,
    kernel_factory: KernelFactory | None = None,
    sandbox: bool | None = None,
) -> Execution:
    """Run the submission at ``path`` in a fresh kernel and read ``variables`` from it.

    Parameters
    ----------
    path : Path
        The submitted notebook (read, never modified).
    variables : sequence of str
        The declared answer variables (Python identifiers). Nothing of the key is passed.
    limits : Limits
        Time, memory and output limits.
    kernel_factory : callable, optional
        ``(workdir, control, limits) -> KernelProcess``. Default: a kernel of its own in the
        sandbox (:mod:`grader.sandbox`; a one-slot :class:`grader.kernels.pool.KernelPool`,
        nothing preloaded, closed at the end), or a :class:`LocalKernel` as ``sandbox`` says.
    sandbox : bool or None
        With the default factory only. None: sandboxed where a sandbox can be had, else not;
        True: sandboxed, or :class:`grader.sandbox.SandboxUnavailable`; False: never.

    Returns
    -------
    Execution
        Never raises for anything the submission does (module docstring: statuses).
    """
    start = time.monotonic()
    try:
        loaded = read_notebook(path, limits.submission_bytes)
    except SubmissionError as err:
        return Execution("invalid_notebook", f"not a valid notebook: {err}", {}, (),
                         time.monotonic() - start, False)
    run = _Run(loaded.cells, limits)
    whose, notes = identity_of(loaded.notebook.get("metadata"),
                                 loaded.notebook.get("cells")), loaded.notes
    del loaded  # its outputs may be large: not kept while the kernel runs
    kernel = None
    from grader.sandbox import fresh_folder, run_folder

    with run_folder() as folder, contextlib.ExitStack() as own:
        workdir = fresh_folder(folder, "w")
        control = fresh_folder(folder, "c")
        try:
            shutil.copyfile(path, workdir / Path(path).name)
            if kernel_factory is None:
                kernel_factory = _default_factory(sandbox, own)
            kernel = kernel_factory(workdir, control, limits)
            status = asyncio.run(_supervise(run, kernel, tuple(variables)))
        finally:
            if isinstance(kernel, LocalKernel):  # last resort, if the event loop was torn down
                kernel.kill_group()
                kernel.reap()
            shutil.rmtree(workdir, ignore_errors=True)
            shutil.rmtree(control, ignore_errors=True)
    return replace(_execution(run, status, notes, kernel, time.monotonic() - start),
                   identity=whose)


def _default_factory(sandbox: bool | None, stack: contextlib.ExitStack) -> KernelFactory:
    """The kernel factory when none is given (:func:`execute_submission`): a one-slot
    sandboxed pool, closed with ``stack``, or :class:`LocalKernel`."""
    if sandbox is False:
        return LocalKernel
    from grader import sandbox as sandboxes

    found = sandboxes.probe() if sandbox else sandboxes.available()
    if found is None:
        return LocalKernel
    from grader.kernels.pool import KernelPool

    pool = stack.enter_context(KernelPool(1, prewarm=False, preload=(), sandbox=found))
    return pool.kernel


async def _supervise(run: _Run, kernel: KernelProcess, variables: tuple[str, ...]) -> str:
    """Run the session under the whole-notebook deadline; the status. Kills the kernel.

    When the notebook's time runs out while a cell runs, that cell is interrupted, no later
    cell runs, and the answers set so far are read — all within :data:`OUT_OF_TIME_GRACE`
    more seconds; a cell that does not yield to the interrupt then, or time running out in any
    other phase, ends the run ("timeout", no answers)."""
    task = asyncio.ensure_future(_session(run, kernel, variables))
    try:
        done, _ = await asyncio.wait({task}, timeout=run.limits.total_timeout)
        if not done and run.phase == "running":
            run.out_of_time = run.running or run.cells[-1]
            await kernel.interrupt()
            done, _ = await asyncio.wait({task}, timeout=OUT_OF_TIME_GRACE)
        if not done:
            await kernel.stop()  # first: whatever the session awaits then fails fast
            task.cancel()
            await asyncio.wait({task}, timeout=STOP_TIMEOUT)
            if task.done() and not task.cancelled():
                task.exception()  # retrieved: how it unwound does not matter any more
            return "error" if run.phase == "starting" else "timeout"
        return task.result()
    except _KernelDied:
        return "kernel_died"
    except Exception as err:  # the grader's side failed on this notebook: say so, go on
        log.exception("execution failed")
        run.problem = f"the grader could not run this notebook ({type(err).__name__}: {err})"
        return "error"
    finally:
        if not task.done():
            task.cancel()
        await kernel.stop()


async def _session(run: _Run, kernel: KernelProcess, variables: tuple[str, ...]) -> str:
    try:
        kc = await kernel.start()
    except Exception as err:
        run.problem = f"could not start a Python kernel ({type(err).__name__}: {err})"
        return "error"
    if getattr(kc, "runs_cells", False):  # a forked kernel's cell server
        return await _cell_session(run, kernel, kc, variables)
    client = _capped_client(executable_notebook(run.cells), run, kernel)
    client.kc = kc
    if hasattr(kernel, "on_iopub_lost"):  # no output (nor idle status) will come: don't wait
        kernel.on_iopub_lost = lambda: setattr(client, "iopub_timeout", 0)
    run.phase = "running"
    for index, cell in enumerate(run.cells):
        if run.out_of_time is not None:
            break  # the notebook's time ran out: no more cells, read what was set
        await _run_cell(client, run, index, cell)
    run.phase = "extracting"
    run.answers, run.problem = await _extract(kc, kernel, variables, run.limits)
    return _done(run)


def _done(run: _Run) -> str:
    run.phase = "done"
    if run.problem is not None:
        return "error"
    return "ok" if run.out_of_time is None else "timeout"


async def _cell_session(run: _Run, kernel: KernelProcess, channel: Any,
                        variables: tuple[str, ...]) -> str:
    """The cells, then the extraction, through a forked kernel's cell server
    (:mod:`grader.kernels.channel`): what :func:`_run_cell` and :func:`_extract` do through
    nbclient and a Jupyter client, with the same time limits and records."""
    from grader.kernels.channel import ChannelClosed

    run.phase = "running"
    try:
        for cell in run.cells:
            if run.out_of_time is not None:
                break
            run.running = cell
            n = channel.send("execute", cell.source)
            reply = await _cell_reply(channel, n, run, kernel, run.limits.effective_cell_timeout)
            _note_reply(run, cell, reply)
            run.running = None
        run.phase = "extracting"
        request = extraction_request(variables)
        n = channel.send("answers", request.code, user_expressions=request.user_expressions)
        deadline = extraction_seconds(variables, run.limits)
        reply = await _cell_reply(channel, n, run, kernel, deadline, interrupt=False)
    except ChannelClosed:
        await _exit_reported(kernel)
        raise _KernelDied from None
    if reply is None:
        run.answers, run.problem = {}, (f"{EXTRACTION_FAILED}: reading them took more than "
                                        f"{deadline:g} s")
    else:
        run.answers, run.problem = parse_answers(reply, variables)
    return _done(run)


async def _cell_reply(channel: Any, n: int, run: _Run, kernel: KernelProcess, timeout: float,
                      interrupt: bool = True) -> dict | None:
    """The reply to request ``n``. Past ``timeout`` seconds the running cell is marked timed
    out and interrupted, and its reply still awaited (the whole-notebook limit bounds that);
    without ``interrupt``, None then."""
    waiting = asyncio.ensure_future(channel.reply(n))
    done, _ = await asyncio.wait({waiting}, timeout=timeout)
    if not done:
        if not interrupt:
            waiting.cancel()
            return None
        if run.running is not None:
            run.timed_out.add(run.running.position)
        await kernel.interrupt()
    reply, output = await waiting
    if output and not run.truncated:
        run.kept += output
        run.truncated = run.kept > run.limits.output_bytes
    return reply


def _note_reply(run: _Run, cell: CodeCell, reply: dict) -> None:
    """Record how one cell ended (as :func:`_run_cell` does)."""
    if run.out_of_time is cell:
        run.errors.append(f"{cell.label}: the notebook's time limit "
                          f"({run.limits.total_timeout:g} s) ran out while it ran; it was "
                          "interrupted and the cells after it were not run")
    elif cell.position in run.timed_out:
        run.errors.append(f"{cell.label}: timed out after "
                          f"{run.limits.effective_cell_timeout:g} s and was interrupted")
    elif reply.get("status") == "error":
        run.errors.append(f"{cell.label}: {_error_line(reply, run.limits)}")


async def _exit_reported(kernel: KernelProcess, wait: float = 2.0) -> None:
    """After a kernel hung up: give its exit status a moment to be reported (it comes from
    its zygote, a little after the connection closes), for the record to name the cause."""
    deadline = time.monotonic() + wait
    while kernel.exit_status() is None and time.monotonic() < deadline:
        await asyncio.sleep(0.005)


async def _run_cell(client: Any, run: _Run, index: int, cell: CodeCell) -> None:
    from nbclient.exceptions import DeadKernelError

    run.running = cell
    try:
        await client.async_execute_cell(client.nb.cells[index], index, execution_count=index + 1)
    except DeadKernelError:
        raise _KernelDied from None
    _note_reply(run, cell, client.replies.get(index) or {})
    run.running = None


def _error_line(reply: dict, limits: Limits) -> str:
    ename = _short(reply.get("ename", "Error"), 60)
    evalue = _short(without_run_folder(str(reply.get("evalue", ""))[:2000]), 160)  # whole paths
    evalue = _CELL_FILE.sub(r"(line \1)", evalue)  # "(1063758517.py, line 2)": IPython's name
    evalue = without_install_paths(evalue)
    line = f"{ename}: {evalue}" if evalue else ename
    hint = _HINTS.get(ename)
    if ename in _NETWORK_ERRORS or _NETWORK_TEXT.search(evalue):
        hint = NO_NETWORK
    if ename == "UsageError" and "magic function" in evalue:
        hint = MISSING_MAGIC
    if ename == "MemoryError":
        hint = f"the memory limit is {_gib(limits.memory_bytes)}"
    return f"{line} — {hint}" if hint else line


async def _extract(
    kc: Any, kernel: KernelProcess, variables: tuple[str, ...], limits: Limits
) -> tuple[dict[str, Any], str | None]:
    from queue import Empty

    request = extraction_request(variables)
    msg_id = kc.execute(request.code, silent=False, store_history=False,
                        user_expressions=request.user_expressions, allow_stdin=False,
                        stop_on_error=False)
    seconds = extraction_seconds(variables, limits)
    deadline = time.monotonic() + seconds
    while True:
        try:
            msg = await kc.get_shell_msg(timeout=max(0.05, deadline - time.monotonic()))
        except Empty:
            if kernel.exit_status() is not None:
                raise _KernelDied from None
            if time.monotonic() >= deadline:
                return {}, f"{EXTRACTION_FAILED}: reading them took more than {seconds:g} s"
            continue
        parent = msg.get("parent_header") if isinstance(msg, dict) else None
        if isinstance(parent, dict) and parent.get("msg_id") == msg_id:
            return parse_answers(msg.get("content"), variables)


@functools.cache
def _cap_client_class() -> type:
    from nbclient import NotebookClient
    from nbclient.exceptions import CellExecutionComplete
    from nbformat.v4 import output_from_msg

    class CappedClient(NotebookClient):
        """nbclient's executor with bounded output and the grader's own interrupt."""

        def __init__(self, nb: Any, run: _Run, kernel: KernelProcess) -> None:
            super().__init__(nb, allow_errors=True, interrupt_on_timeout=True,
                             record_timing=False, timeout_func=self._cell_timeout,
                             log=_quiet_log())
            self.run, self.kernel = run, kernel
            self.kept = 0
            self.replies: dict[int, dict] = {}

        def _cell_timeout(self, cell: Any) -> float:
            return self.run.limits.effective_cell_timeout

        async def _async_handle_timeout(self, timeout: int, cell: Any = None) -> None:
            if self.run.running is not None:
                self.run.timed_out.add(self.run.running.position)
            await self.kernel.interrupt()
            return None  # keep waiting for the interrupted cell's reply

        async def _check_raise_for_error(self, cell: Any, cell_index: int,
                                         exec_reply: dict | None) -> None:
            content = exec_reply.get("content") if isinstance(exec_reply, dict) else None
            self.replies[cell_index] = content if isinstance(content, dict) else {}

        def process_message(self, msg: dict, cell: Any, cell_index: int) -> Any:
            # Every message is untrusted (the kernel holds the signing key): ignore malformed.
            try:
                msg_type, content = msg["msg_type"], msg["content"]
                if msg_type == "status" and content.get("execution_state") == "idle":
                    raise CellExecutionComplete()
                if msg_type in ("stream", "display_data", "execute_result", "error"):
                    return self._keep(cell, msg)
            except (KeyError, TypeError, AttributeError, ValueError):
                pass
            return None  # display updates, clear_output, comms: nothing the grader needs

        def _keep(self, cell: Any, msg: dict) -> Any:
            if self.run.truncated:
                return None
            size = _content_size(msg["content"])
            if self.kept + size > self.run.limits.output_bytes:
                self.run.truncated = True
                return None
            self.kept += size
            out = output_from_msg(msg)
            cell.outputs.append(out)
            return out

    return CappedClient


def _capped_client(nb: Any, run: _Run, kernel: KernelProcess) -> Any:
    return _cap_client_class()(nb, run, kernel)


def _content_size(content: Any) -> int:
    """Characters of text in an output message's content (what keeping it would cost)."""
    if isinstance(content, str):
        return len(content)
    if isinstance(content, dict):
        return sum(_content_size(v) for v in content.values())
    if isinstance(content, list):
        return sum(_content_size(v) for v in content)
    return 8


def _quiet_log() -> logging.Logger:
    # nbclient logs every timeout and interrupt at ERROR level; the grader reports them itself
    quiet = logging.getLogger("grader.execute.nbclient")
    quiet.setLevel(logging.CRITICAL)
    return quiet


# --------------------------------------------------------------------------------------------
# The record


def _execution(run: _Run, status: str, notes: Sequence[str], kernel: Any,
               duration: float) -> Execution:
    errors = list(run.errors)
    truncated = run.truncated or bool(getattr(kernel, "iopub_lost", False))
    if status == "kernel_died" and run.running is not None:
        errors.append(f"{run.running.label}: the kernel died while it ran")
    answered = run.phase == "done"  # read after the time ran out, too
    if status == "timeout" and run.running is not None and not answered:
        errors.append(f"{run.running.label}: still running when the time limit "
                      f"({run.limits.total_timeout:g} s) ran out")
    answers = run.answers if status == "ok" or (status == "timeout" and answered) else {}
    message = "; ".join([*notes, _summary(run, status, kernel, errors)])
    retry = status == "error" and run.phase == "starting"  # no kernel: not the student's doing
    return Execution(status, message, answers, tuple(errors), duration, truncated,
                     bool(getattr(kernel, "sandboxed", False)), retry,
                     str(getattr(kernel, "isolation", "") or ""), tuple(notes))


def _summary(run: _Run, status: str, kernel: Any, errors: Sequence[str]) -> str:
    n = len(run.cells)
    cells = f"{n} code cell{'s' if n != 1 else ''}"
    if status == "ok":
        if not errors:
            return f"ran all {cells} without an error"
        return f"ran all {cells}; {len(errors)} did not finish normally: " + "; ".join(errors)
    if status == "timeout" and run.phase == "done":
        return (f"stopped at the time limit for the whole notebook ({run.limits.total_timeout:g}"
                f" s) while {run.out_of_time.label} was running: it was interrupted, the cells "
                "after it were not run, and the answers set before it were read")
    if status == "timeout":
        where = f" while {run.running.label} was running" if run.running else ""
        if run.phase == "extracting":
            where = " while the answers were being read"
        return (f"stopped at the time limit for the whole notebook ({run.limits.total_timeout:g}"
                f" s){where} — a loop that does not end, or one that ignores interrupts? "
                "The kernel was stopped; no answers could be read")
    if status == "kernel_died":
        where = f" while {run.running.label} ran" if run.running else ""
        return (f"the Python kernel died{where}: {_death(kernel, run.limits)}. Cells after it "
                "did not run; no answers could be read")
    return run.problem or "the notebook could not be run"


def _death(kernel: Any, limits: Limits) -> str:
    code = kernel.exit_status() if kernel is not None else None
    wrote = getattr(kernel, "disk_held", None)
    if wrote:
        return (f"it was stopped when it had written {wrote / 1024**2:.0f} MiB to this "
                "machine's shared folders (/tmp, /var/tmp, /dev/shm and its working folder; "
                f"the limit is {kernel.disk_limit / 1024**2:.0f} MiB in all)")
    held = getattr(kernel, "memory_held", None)
    if held:
        return (f"it was stopped when its processes together held {_gib(held)}, over the "
                f"memory limit of {_gib(limits.memory_bytes)} for the whole notebook (all the "
                "processes it started count together)")
    memory = f"running out of memory (the limit is {_gib(limits.memory_bytes)})"
    if code is None or code == 0:
        return f"the process ended (exit(), quit(), os._exit(), or {memory})"
    if code > 0:
        return f"the process exited with status {code} (os._exit()? or {memory})"
    try:
        name = signal.Signals(-code).name
    except ValueError:
        name = f"signal {-code}"
    return f"the process was killed by {name} (a crash, or {memory})"


def _gib(n: int) -> str:
    return f"{n / 1024**3:.3g} GiB"


def _short(text: object, limit: int) -> str:
    text = " ".join(str(text).split())
    return text if len(text) <= limit else text[: limit - 1] + "…"
