"""The grader's end of a forked kernel's cell server (:mod:`grader.kernels.cell_server`).

The grader listens on a Unix socket in the kernel's private control folder
(:func:`listen`) before asking the zygote to fork; the kernel connects once confined and says
it is ready; :class:`CellChannel` then sends it requests one at a time and reads the replies.
Everything the kernel says is untrusted: a line longer than
:data:`grader.kernels.base.MAX_MESSAGE` is dropped
unread, a line that is not a reply to the request in hand is ignored, and a kernel that hangs
up (it died) raises :class:`ChannelClosed`.

Floor 2 of grader/ (one kernel; grader/API.md).
"""

from __future__ import annotations

import asyncio
import contextlib
import json
import os
import socket
from collections.abc import Callable
from pathlib import Path
from typing import Any

from grader.kernels.base import MAX_MESSAGE

SOCKET_NAME = "s"
"""The listening socket's name in the control folder (a Unix socket path is ≤ 107 bytes)."""


class ChannelClosed(Exception):
    """The kernel hung up (it ended) or never connected."""


def listen(control: Path, uid: int | None = None) -> socket.socket:
    """A non-blocking listening socket at ``control/s``, for one kernel to connect to
    (owned by ``uid`` when the kernel runs as that user)."""
    path = Path(control) / SOCKET_NAME
    listener = socket.socket(socket.AF_UNIX, socket.SOCK_STREAM)
    try:
        listener.bind(str(path))
        if uid is not None:
            os.chown(path, uid, uid)
        listener.listen(1)
        listener.setblocking(False)
    except BaseException:
        listener.close()
        raise
    return listener


class CellChannel:
    """Requests to one kernel's cell server, replies from it (module docstring).

    Parameters
    ----------
    listener : socket.socket
        From :func:`listen`; closed once the kernel has connected (no one else may).
    """

    runs_cells = True  # what grader.execute checks to run cells through it

    def __init__(self, listener: socket.socket) -> None:
        self.listener = listener
        self.reader: asyncio.StreamReader | None = None
        self.writer: asyncio.StreamWriter | None = None
        self.sent = 0

    async def connect(self, timeout: float, alive: Callable[[], bool]) -> None:
        """Wait (at most ``timeout`` seconds, while ``alive()``) for the kernel to connect
        and say it is ready; :class:`ChannelClosed` otherwise."""
        loop = asyncio.get_running_loop()
        accepting = asyncio.ensure_future(loop.sock_accept(self.listener))
        deadline = loop.time() + timeout
        while not accepting.done():
            await asyncio.wait({accepting}, timeout=0.25)
            if not accepting.done() and (not alive() or loop.time() > deadline):
                accepting.cancel()
                why = "ended" if not alive() else f"did not connect in {timeout:g} s"
                raise ChannelClosed(f"the kernel {why}")
        conn, _ = accepting.result()
        self.listener.close()
        self.reader, self.writer = await asyncio.open_unix_connection(
            sock=conn, limit=MAX_MESSAGE)
        remaining = max(0.1, deadline - loop.time())
        try:
            hello = await asyncio.wait_for(self._line(), remaining)
        except TimeoutError:
            raise ChannelClosed(f"the kernel did not say it was ready in {timeout:g} s") from None
        if not (isinstance(hello, dict) and hello.get("ready") is True):
            raise ChannelClosed("the kernel did not say it was ready")

    def send(self, op: str, code: str, **fields: Any) -> int:
        """Send one request; its number (for :meth:`reply`)."""
        self.sent += 1
        line = json.dumps({"n": self.sent, "op": op, "code": code, **fields}) + "\n"
        self.writer.write(line.encode())
        return self.sent

    async def reply(self, n: int) -> tuple[dict, int]:
        """The reply to request ``n`` and the characters of output it made."""
        while True:
            message = await self._line()
            if not isinstance(message, dict) or message.get("n") != n:
                continue
            reply, output = message.get("reply"), message.get("output")
            return (reply if isinstance(reply, dict) else {},
                    output if isinstance(output, int) and output >= 0 else 0)

    async def _line(self) -> Any:
        """The next line, decoded (None if it is not JSON or was too long)."""
        try:
            line = await self.reader.readline()
        except ValueError:  # longer than MAX_MESSAGE: dropped (asyncio discards it)
            return None
        except (ConnectionError, OSError):
            line = b""
        if not line:
            raise ChannelClosed("the kernel hung up")
        try:
            return json.loads(line)
        except (ValueError, RecursionError):
            return None

    def close(self) -> None:
        """Close the connection (or the listener, if the kernel never connected)."""
        with contextlib.suppress(Exception):
            self.listener.close()
        with contextlib.suppress(Exception):
            if self.writer is not None:
                self.writer.close()
