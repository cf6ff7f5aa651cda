"""The kernel contract (floor 2, ``grader/kernels/``): what every kernel a run starts is — its
process protocol (:class:`KernelProcess`), the factory that makes one, the environment it
gets, and the limits every channel to it keeps.

Floor 2 of grader/ (one kernel; grader/API.md).
"""

from __future__ import annotations

import os
import site
import sys
from collections.abc import Callable
from pathlib import Path
from typing import Any, Protocol

from grader.limits import Limits

MAX_MESSAGE = 4 * 1024**2
"""Largest single message (bytes) the grader accepts from a kernel, on any channel."""


RECEIVE_QUEUE = 64
"""Messages a channel's socket queues before it stops reading (``RCVHWM``)."""


RECONNECT_INTERVAL_MS = 5
"""Milliseconds between the grader's attempts to connect to a kernel not yet listening."""


STOP_TIMEOUT = 5.0
"""Seconds allowed for the kernel to be reaped after SIGKILL."""


class KernelProcess(Protocol):
    """A kernel for one run: what :func:`execute_submission` needs from a kernel launcher."""

    async def start(self) -> Any:
        """Start the kernel; return a started, ready ``AsyncKernelClient``."""

    async def interrupt(self) -> None:
        """Send the kernel a keyboard interrupt (SIGINT)."""

    async def stop(self) -> None:
        """Kill the kernel and everything it started; release sockets. Never raises."""

    def exit_status(self) -> int | None:
        """The kernel process's exit status once it has ended (negative: killed by a signal)."""


KernelFactory = Callable[[Path, Path, Limits], KernelProcess]


def kernel_environment(workdir: Path, control: Path) -> dict[str, str]:
    """The kernel's whole environment: built from scratch, nothing of the grader's own.

    ``HOME`` and ``TMPDIR`` are the private working folder; IPython's and matplotlib's
    configuration folders are in the control folder (empty: no startup files run); Jupyter
    configuration is ignored; one BLAS/OpenMP thread (``--jobs`` runs kernels side by side);
    a fixed hash seed for reproducible runs.
    """
    env = {
        "PATH": f"{Path(sys.executable).parent}{os.pathsep}{os.defpath}",
        "HOME": str(workdir),
        "TMPDIR": str(workdir),
        "LANG": "C.UTF-8",
        "LC_ALL": "C.UTF-8",
        "PYTHONHASHSEED": "0",
        "PYTHONDONTWRITEBYTECODE": "1",
        "IPYTHONDIR": str(control / "ipython"),
        "MPLCONFIGDIR": str(control / "matplotlib"),
        "MPLBACKEND": "Agg",
        "JUPYTER_NO_CONFIG": "1",
        "OPENBLAS_NUM_THREADS": "1",
        "OMP_NUM_THREADS": "1",
        "MKL_NUM_THREADS": "1",
        "NUMEXPR_NUM_THREADS": "1",
        "MALLOC_ARENA_MAX": "2",  # fewer malloc arenas: less address space per thread
    }
    if site.ENABLE_USER_SITE and site.getusersitepackages() in sys.path:
        # HOME moved: keep packages installed with `pip install --user` importable
        env["PYTHONUSERBASE"] = site.getuserbase()
    return env
