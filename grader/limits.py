"""The limits one submission runs under: time per cell, time in all, memory, kept output.

A record with no behaviour, shared by ``eulertop grade`` and ``eulertop check`` (the student's
check runs under exactly the grader's limits).

Floor 0 of grader/ (records and pure helpers; grader/API.md).
"""

from __future__ import annotations

import math
import numbers
from dataclasses import dataclass

from eulertop_base import ParameterError


@dataclass(frozen=True)
class Limits:
    """Execution limits of one submission.

    Attributes
    ----------
    cell_timeout : float
        Seconds one cell may run. The kernel is then interrupted (``KeyboardInterrupt``) and the
        next cell runs; the cell is reported as timed out. The effective value is
        ``min(cell_timeout, total_timeout)``.
    total_timeout : float
        Seconds for the whole notebook, kernel start and answer extraction included. The
        kernel is then killed (a loop that ignores the interrupt ends here) and no answer is
        read.
    memory_bytes : int
        Memory of the whole submission, bytes: the address-space limit (``RLIMIT_AS``) of each
        of its processes, and, sandboxed, the resident memory of all of them together (its
        keeper kills the kernel past it: :mod:`grader.sandbox.world`). An allocation beyond the
        first raises ``MemoryError`` in the student's cell.
    output_bytes : int
        Characters of cell output (prints, displays, tracebacks) kept per notebook; the rest is
        dropped as it arrives and ``Execution.output_truncated`` says so. Output is never
        graded; the cap only bounds the grader's memory.
    submission_bytes : int
        Largest submitted file read, bytes (``--max-size``); a larger one is refused before it
        is read (:mod:`grader.submission_file`).

    Raises
    ------
    eulertop_base.ParameterError
        A limit that is not a positive finite number (``ValueError`` naming the field).

    Examples
    --------
    >>> Limits(cell_timeout=60, total_timeout=20).effective_cell_timeout
    20.0
    """

    cell_timeout: float = 30.0
    total_timeout: float = 120.0
    memory_bytes: int = 2 * 1024**3
    output_bytes: int = 1_000_000
    submission_bytes: int = 20 * 1024**2

    def __post_init__(self) -> None:
        for field in ("cell_timeout", "total_timeout"):
            object.__setattr__(self, field, _positive(field, getattr(self, field)))
        for field in ("memory_bytes", "output_bytes", "submission_bytes"):
            value = _positive(field, getattr(self, field))
            if value != int(value):
                raise ParameterError(field, f"must be a whole number of bytes, got {value!r}")
            object.__setattr__(self, field, int(value))

    @property
    def effective_cell_timeout(self) -> float:
        """Seconds one cell may run: ``min(cell_timeout, total_timeout)``."""
        return min(self.cell_timeout, self.total_timeout)


def _positive(field: str, value: object) -> float:
    if isinstance(value, bool) or not isinstance(value, numbers.Real):
        raise ParameterError(field, f"must be a number, got {value!r}")
    value = float(value)
    if not (math.isfinite(value) and value > 0):
        raise ParameterError(field, f"must be positive and finite, got {value!r}")
    return value
