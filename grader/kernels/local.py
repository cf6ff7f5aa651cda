"""A cold kernel (floor 2): a fresh ipykernel on this machine, launched, interrupted and
killed in one class (:class:`LocalKernel`), talked to through jupyter_client.

Floor 2 of grader/ (one kernel; grader/API.md).
"""

from __future__ import annotations

import asyncio
import contextlib
import functools
import os
import signal
import subprocess
import sys
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

from grader.kernels.base import (
    MAX_MESSAGE,
    RECEIVE_QUEUE,
    RECONNECT_INTERVAL_MS,
    STOP_TIMEOUT,
    kernel_environment,
)
from grader.limits import Limits

# The kernel command: the grader's interpreter sets its own resource limits, then runs
# ipykernel's launcher in-process. Done in the child's own code rather than a Popen preexec_fn,
# which is unsafe in a threaded grader (`--jobs` runs kernels from a thread pool). No braces:
# jupyter_client substitutes {names} in the command.
_LAUNCHER = (
    "import resource as r, runpy, sys; "
    "m = int(sys.argv.pop(1)); h = r.getrlimit(r.RLIMIT_AS)[1]; "
    "m = m if h == r.RLIM_INFINITY else min(m, h); "
    "r.setrlimit(r.RLIMIT_AS, (m, m)); r.setrlimit(r.RLIMIT_CORE, (0, 0)); "
    "runpy.run_module('ipykernel_launcher', run_name='__main__', alter_sys=True)"
)


def kernel_command(limits: Limits) -> list[str]:
    """The kernel's argv (``{connection_file}`` filled in by jupyter_client)."""
    return [sys.executable, "-c", _LAUNCHER, str(limits.memory_bytes), "-f", "{connection_file}",
            "--HistoryManager.hist_file=:memory:"]


class LocalKernel:
    """A fresh ipykernel on this machine, in its own process group: the one place a kernel is
    launched, interrupted and killed (:class:`KernelProcess`).

    Parameters
    ----------
    workdir : Path
        The kernel's working folder (holds only the submission).
    control : Path
        A private folder for the connection file, the IPC sockets and the kernel's stderr.
    limits : Limits
        ``memory_bytes`` becomes the kernel's ``RLIMIT_AS``.
    """

    def __init__(self, workdir: Path, control: Path, limits: Limits) -> None:
        self.workdir, self.control, self.limits = Path(workdir), Path(control), limits
        self.km: Any = None
        self.kc: Any = None
        self.process: subprocess.Popen | None = None
        self._context: Any = None
        self._monitor: Any = None
        self.iopub_lost = False
        self.on_iopub_lost: Callable[[], None] | None = None

    def kernel_argv(self) -> list[str]:
        """The kernel's command (``{connection_file}`` substituted by jupyter_client)."""
        return kernel_command(self.limits)

    def launch_options(self) -> dict[str, Any]:
        """Further keyword arguments of the kernel's ``Popen`` (e.g. ``user``)."""
        return {}

    def manager_class(self) -> type:
        """The jupyter_client kernel manager that launches it."""
        from jupyter_client import AsyncKernelManager

        return AsyncKernelManager

    async def start(self) -> Any:
        self.km = self.manager_class()(
            kernel_name="eulertop-grader",
            kernel_spec_manager=_kernel_spec_manager_class()(self.kernel_argv()),
            transport="ipc", ip=str(self.control / "kernel"),
            connection_file=str(self.control / "kernel.json"), autorestart=False,
        )
        with open(self.control / "kernel-stderr.txt", "wb") as stderr:
            await self.km.start_kernel(
                env=kernel_environment(self.workdir, self.control), cwd=str(self.workdir),
                stdin=subprocess.DEVNULL, stdout=subprocess.DEVNULL, stderr=stderr,
                **self.launch_options(),
            )
        self.process = self.km.provisioner.process
        return await self._connect()

    async def _connect(self) -> Any:
        """Open the kernel manager's client's channels and wait until the kernel answers.

        Every channel refuses messages over :data:`MAX_MESSAGE` (issue 11). Ready means a
        ``kernel_info`` reply on the shell channel *and* a message on IOPub (so the
        subscription is live and no output is lost); jupyter_client's ``wait_for_ready`` also
        waits for 0.2 s of IOPub silence after that, a delay on every kernel start that the
        grader does not need (messages are matched to their request by ``msg_id``).
        """
        import zmq
        import zmq.asyncio

        self._context = zmq.asyncio.Context()
        # every channel's socket refuses a message over MAX_MESSAGE before reading it (the
        # connection is dropped), and queues few: one kernel cannot fill the grader's memory
        self._context.setsockopt(zmq.MAXMSGSIZE, MAX_MESSAGE)
        self._context.setsockopt(zmq.RCVHWM, RECEIVE_QUEUE)
        # a kernel handed out before it has bound its sockets refuses the first connection;
        # ZeroMQ's default is to try again 100 ms later, which a fresh kernel would wait out
        self._context.setsockopt(zmq.RECONNECT_IVL, RECONNECT_INTERVAL_MS)
        self.kc = self.km.client(context=self._context)
        # no heartbeat: the grader watches the kernel's process itself, and the heartbeat's
        # thread cannot be stopped once its kernel is gone (its REQ socket's send waits for a
        # peer forever: stop_channels() then never returned, and the run hung)
        self.kc.start_channels(hb=False)
        self._watch_iopub(zmq)
        await self._ready(self.limits.total_timeout)
        return self.kc

    async def _ready(self, timeout: float) -> None:
        from queue import Empty

        deadline = time.monotonic() + timeout
        while True:
            msg_id = self.kc.kernel_info()
            while True:  # this request's reply, or give up on it after a while
                try:
                    reply = await self.kc.get_shell_msg(timeout=0.5)
                except Empty:
                    reply = None
                    break
                if reply.get("parent_header", {}).get("msg_id") == msg_id:
                    break
            if reply is not None:
                try:
                    await self.kc.get_iopub_msg(timeout=0.25)
                    return
                except Empty:
                    pass  # IOPub not subscribed yet: ask again
            if self.exit_status() is not None:
                raise RuntimeError("the kernel died before it answered")
            if time.monotonic() > deadline:
                raise RuntimeError(f"the kernel did not answer in {timeout:g} s")

    def _watch_iopub(self, zmq: Any) -> None:
        """Note when IOPub is severed (a message over MAX_MESSAGE was refused)."""
        from zmq.utils.monitor import parse_monitor_message

        self._monitor = self.kc.iopub_channel.socket.get_monitor_socket(zmq.EVENT_DISCONNECTED)

        async def watch() -> None:
            with contextlib.suppress(Exception):
                parse_monitor_message(await self._monitor.recv_multipart())
                self.iopub_lost = True
                if self.on_iopub_lost is not None:
                    self.on_iopub_lost()

        self._watcher = asyncio.ensure_future(watch())

    async def interrupt(self) -> None:
        with contextlib.suppress(Exception):
            await self.km.interrupt_kernel()

    def exit_status(self) -> int | None:
        return None if self.process is None else self.process.poll()

    async def stop(self) -> None:
        self.kill_group()
        self._disconnect()
        with contextlib.suppress(Exception):
            if self.km is not None and self.km.has_kernel:
                await asyncio.wait_for(self.km.shutdown_kernel(now=True), STOP_TIMEOUT)
        with contextlib.suppress(Exception):
            if self.km is not None:
                await self.km.cleanup_resources()
        self.reap()
        with contextlib.suppress(Exception):
            if self._context is not None:
                self._context.destroy(linger=0)

    def _disconnect(self) -> None:
        """Stop watching IOPub and close the client's channels (the context stays)."""
        with contextlib.suppress(Exception):
            if getattr(self, "_watcher", None) is not None:
                self._watcher.cancel()
            if self._monitor is not None:
                self.kc.iopub_channel.socket.disable_monitor()
                self._monitor.close(linger=0)
        with contextlib.suppress(Exception):
            if self.kc is not None:
                self.kc.stop_channels()

    def kill_group(self) -> None:
        """SIGKILL the kernel's process group (the kernel and what it started), if unreaped."""
        if self.process is not None and self.process.returncode is None:
            with contextlib.suppress(OSError):
                os.killpg(self.process.pid, signal.SIGKILL)  # its own session: pgid == pid

    def reap(self) -> None:
        """Wait for the killed kernel so that no zombie is left."""
        if self.process is not None:
            with contextlib.suppress(Exception):
                self.process.wait(timeout=STOP_TIMEOUT)


@functools.cache
def _kernel_spec_manager_class() -> type:
    from jupyter_client.kernelspec import KernelSpec, KernelSpecManager

    class GraderKernelSpecs(KernelSpecManager):
        """Answers every kernel name with the grader's own Python kernel, run by ``argv``."""

        def __init__(self, argv: list[str], **kw: Any) -> None:
            super().__init__(**kw)
            self._spec = KernelSpec(argv=argv, display_name="eulertop grader (Python 3)",
                                    language="python", env={}, metadata={})

        def get_kernel_spec(self, kernel_name: str) -> Any:
            return self._spec

    return GraderKernelSpecs
