"""The first zygote of ``eulertop grade``, started before the grader reads its class (issue 34).

A zygote spends about a second importing; the grader, meanwhile, imports its own modules,
reads the assignment, finds the submissions and reads what they import — a third of a second
of its own. Started first, the zygote imports while the grader does: :func:`early_pool` starts
a :class:`~grader.kernels.pool.KernelPool` of one slot (``early``) as soon as this machine's
sandbox is known, its zygote importing what every class's kernels have
(:data:`~grader.kernels.pool.EARLY_PRELOAD`); once the class is read,
:meth:`~grader.kernels.pool.KernelPool.plan` gives it the rest and the other slots.

Nothing changes in what the zygote is: it is started from the same script, in the same sandbox
(:func:`grader.sandbox.probe`, which the run then finds cached), before any submission is read
— earlier than before, not later — and receives module names from the fixed list of
:mod:`grader.kernels.preload` only.

Floor 2 of grader/ (one kernel; grader/API.md).
"""

from __future__ import annotations

import threading
from collections.abc import Iterator
from contextlib import contextmanager
from typing import Any


@contextmanager
def early_pool(sandbox: bool) -> Iterator[Any]:
    """An ``early`` :class:`~grader.kernels.pool.KernelPool` in this machine's sandbox (none
    when not ``sandbox``: ``--no-sandbox``), closed at the end of the block; or None where
    kernels are not forked in a bubblewrap sandbox here (no ``fork``, no sandbox, the
    container tier): the run then chooses, and says why, as it always did."""
    found: dict[str, Any] = {}
    probing = threading.Thread(target=_probe, args=(found,), name="eulertop-probe")
    if sandbox:  # bubblewrap's start (a subprocess) while this process imports the pool
        probing.start()
    from grader.kernels.pool import KernelPool, fork_available

    if sandbox:
        probing.join()
    if not fork_available() or (sandbox and found.get("sandbox") is None):
        yield None
        return
    with KernelPool(1, sandbox=found.get("sandbox"), early=True) as pool:
        yield pool


def _probe(found: dict[str, Any]) -> None:
    """``found["sandbox"]``: :func:`grader.sandbox.probe`'s (cached) sandbox, if there is one."""
    from grader.sandbox import available

    try:
        found["sandbox"] = available()
    except Exception:  # the run probes again, and says what went wrong
        found["sandbox"] = None
