"""Reading a submitted file without trusting it (issue 11): a regular file, of bounded size.

The grader opens a student's file exactly once, here, and works from the bytes it read: it never
follows a symbolic link (a link to the solutions notebook would otherwise be graded), never
blocks on a FIFO or a device (``/dev/zero`` would never end), and never reads more than the
size limit (a 75 MB notebook is refused before it is read, not after it is parsed).

Floor 0 of grader/ (records and pure helpers; grader/API.md).
"""

from __future__ import annotations

import argparse
import os
import stat
from pathlib import Path

DEFAULT_MAX_BYTES = 20 * 1024**2
"""Largest submission read, bytes (``--max-size`` of ``eulertop grade``, ``eulertop check`` and
``eulertop-check``: one limit, applied by :func:`read_submission` alike)."""

MAX_SIZE_HELP = ("largest notebook read, e.g. 20M or 500K (default 20 MiB); a larger one is "
                 "refused without being read, as is anything that is not a regular file (a "
                 "named pipe, a device, a link); the same limit for eulertop grade and check")
"""The help of ``--max-size``, the same in every command that has it."""


class InvalidSubmission(ValueError):
    """The file is not one the grader will read; the message says why (for the record)."""


_SIZE_UNITS = {"": 1024**2, "k": 1024, "kb": 1024, "kib": 1024, "m": 1024**2, "mb": 1024**2,
               "mib": 1024**2, "g": 1024**3, "gb": 1024**3, "gib": 1024**3}


def size_argument(text: str) -> int:
    """``20`` (MiB), ``500K``, ``20M``, ``1G``, ``20MiB`` → bytes."""
    number = text.strip().rstrip("BbIiKkMmGg")
    unit = text.strip()[len(number):].lower()
    try:
        value = float(number) * _SIZE_UNITS[unit]
    except (ValueError, KeyError):
        raise argparse.ArgumentTypeError(f"expected a size such as 20M or 500K, got {text!r}") \
            from None
    if not 0 < value < float("inf"):
        raise argparse.ArgumentTypeError(f"must be a positive size, got {text!r}")
    return int(value)


def _kind(mode: int) -> str:
    for test, name in ((stat.S_ISLNK, "a symbolic link"), (stat.S_ISDIR, "a folder"),
                       (stat.S_ISFIFO, "a named pipe (FIFO)"), (stat.S_ISSOCK, "a socket"),
                       (stat.S_ISCHR, "a device"), (stat.S_ISBLK, "a device")):
        if test(mode):
            return name
    return "not a regular file"


def size_text(n: int) -> str:
    """``20 MiB``, ``75.3 MiB``, ``512 KiB``, ``12 bytes``."""
    for unit, size in (("GiB", 1024**3), ("MiB", 1024**2), ("KiB", 1024)):
        if n >= size:
            return f"{n / size:.3g} {unit}"
    return f"{n} bytes"


def read_submission(path: Path, max_bytes: int = DEFAULT_MAX_BYTES) -> bytes:
    """The bytes of the regular file ``path`` (not a link), at most ``max_bytes`` of them.

    Raises
    ------
    InvalidSubmission
        A link, FIFO, device, socket or folder; a file over ``max_bytes``; one that changed
        between the check and the read.
    OSError
        The file cannot be read at all (permissions): the caller says so.
    """
    info = os.lstat(path)
    if not stat.S_ISREG(info.st_mode):
        raise InvalidSubmission(f"{Path(path).name} is {_kind(info.st_mode)}, not a file")
    if info.st_size > max_bytes:
        raise InvalidSubmission(f"{Path(path).name} is {size_text(info.st_size)}, over the "
                                f"{size_text(max_bytes)} limit (--max-size)")
    # O_NOFOLLOW and O_NONBLOCK: swapped for a link or a FIFO after the check, it still
    # neither follows nor blocks; fstat then says what was opened
    fd = os.open(path, os.O_RDONLY | os.O_NOFOLLOW | os.O_NONBLOCK | os.O_CLOEXEC)
    try:
        opened = os.fstat(fd)
        if not stat.S_ISREG(opened.st_mode) or (opened.st_dev, opened.st_ino) != \
                (info.st_dev, info.st_ino):
            raise InvalidSubmission(f"{Path(path).name} changed while it was being read")
        chunks, left = [], max_bytes + 1
        while left > 0:
            chunk = os.read(fd, min(left, 1 << 20))
            if not chunk:
                break
            chunks.append(chunk)
            left -= len(chunk)
    finally:
        os.close(fd)
    data = b"".join(chunks)
    if len(data) > max_bytes:
        raise InvalidSubmission(f"{Path(path).name} grew over the {size_text(max_bytes)} "
                                "limit while it was being read")
    return data
