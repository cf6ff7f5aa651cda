"""Where a graded notebook's time goes on the kernel's side (issue 17): a kernel forked from a
warm zygote (IPython's shell behind the cell server,
:mod:`grader.kernels.cell_server`), from the fork
request to its first answer, and three small cells; a cold Jupyter kernel (ipykernel, as
``--cold-kernels`` runs it) beside it.

For ``--kernels`` (12) kernels, one after another, of a one-slot :class:`grader.kernels.pool.
KernelPool` without prewarming (so each start is timed whole):

* **start**: ``PooledKernel.start`` — fork, the kernel's own world when sandboxed, the kernel
  connecting to the grader and saying it is ready — wall time, sandboxed and not; and, not
  sandboxed (its pid is then this machine's), the CPU time the kernel process spent up to then
  (``/proc/<pid>/stat``);
* **cells**: three small cells (``import numpy``, a product, an assignment) executed, wall and
  the kernel's CPU;
* **memory**: the kernel's private dirty memory after a full ``gc.collect()``
  (``/proc/<pid>/smaps_rollup``): what it copied of the zygote's pages.

Medians, the first two kernels of each pool left out (warming). Run from the repository root:
``PYTHONPATH=. python benchmarks/bench_kernel_start.py [--kernels 12]``.
"""

from __future__ import annotations

import argparse
import asyncio
import os
import statistics
import time

from grader.kernels.pool import KernelPool
from grader.limits import Limits
from grader.sandbox import fresh_folder, probe, run_folder

CELLS = ("import numpy as np\nx = np.eye(3)", "y = x @ x", "z = 1")
TICK = os.sysconf("SC_CLK_TCK")


def cpu_of(pid: int) -> float:
    """CPU seconds process ``pid`` (all its threads) has run so far: the threads'
    ``/proc/<pid>/task/<tid>/schedstat`` (nanoseconds; a forked kernel's start is a few
    milliseconds, below ``/proc/<pid>/stat``'s 10 ms tick), else user + system from
    ``/proc/<pid>/stat``."""
    try:
        total = 0
        for tid in os.listdir(f"/proc/{pid}/task"):
            with open(f"/proc/{pid}/task/{tid}/schedstat") as f:
                total += int(f.read().split()[0])
        return total / 1e9
    except (OSError, ValueError, IndexError):
        with open(f"/proc/{pid}/stat") as f:
            fields = f.read().rsplit(")", 1)[1].split()
        return (int(fields[11]) + int(fields[12])) / TICK


def private_dirty_mib(pid: int) -> float:
    with open(f"/proc/{pid}/smaps_rollup") as f:
        for line in f:
            if line.startswith("Private_Dirty:"):
                return int(line.split()[1]) / 1024
    raise RuntimeError("no Private_Dirty")


async def _run(client, code: str) -> None:
    """Run ``code`` and wait for its reply: through a forked kernel's cell channel, or a
    Jupyter client (matched by ``msg_id``)."""
    if getattr(client, "runs_cells", False):
        await client.reply(client.send("execute", code))
        return
    msg_id = client.execute(code)
    while (await client.get_shell_msg(timeout=10))["parent_header"].get("msg_id") != msg_id:
        pass


def one_pool(kernels: int, sandbox, cold: bool = False) -> list[dict[str, float]]:
    rows = []
    with run_folder() as run, KernelPool(1, prewarm=False, sandbox=sandbox, cold=cold) as pool:
        for _ in range(kernels):
            kernel = pool.kernel(fresh_folder(run, "w"), fresh_folder(run, "c"), Limits())

            async def measure(kernel=kernel) -> dict[str, float]:
                t0 = time.perf_counter()
                client = await kernel.start()
                row = {"start wall": time.perf_counter() - t0}
                pid = None
                if cold:
                    pid = kernel.process.pid
                elif sandbox is None:
                    pid = kernel.forked.pid
                if pid is not None:
                    row["start CPU"] = cpu_of(pid)
                t1 = time.perf_counter()
                for code in CELLS:
                    await _run(client, code)
                row["cells wall"] = time.perf_counter() - t1
                if pid is not None:
                    row["cells CPU"] = cpu_of(pid) - row["start CPU"]
                    await _run(client, "import gc; gc.collect()")
                    row["private dirty MiB"] = private_dirty_mib(pid) / 1000  # shown ×1000
                await kernel.stop()
                return row

            rows.append(asyncio.run(measure()))
    return rows[2:]


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--kernels", type=int, default=12)
    args = parser.parse_args(argv)
    print(f"load average before: {os.getloadavg()[0]:.2f}; medians of {args.kernels - 2} "
          "kernels each")
    for label, sandbox, cold in (("forked, not sandboxed", None, False),
                                 ("forked, sandboxed", probe(), False),
                                 ("cold ipykernel, not sandboxed", None, True)):
        rows = one_pool(args.kernels, sandbox, cold)
        parts = []
        for key in rows[0]:
            value = statistics.median(r[key] for r in rows)
            parts.append(f"{key} {value * 1000:.1f}" + ("" if "MiB" in key else " ms"))
        print(f"{label}: " + "; ".join(parts), flush=True)
    print(f"load average after: {os.getloadavg()[0]:.2f}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
