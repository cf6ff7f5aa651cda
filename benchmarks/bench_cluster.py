"""Benchmark grading on Dask (``--cluster local:2``) against the local pool (``--jobs 2``).

Grades the same class of N small real submissions (one question, ``inertia_tensor``; the
noisy solutions of ``bench_grade.py``, a fifth of them wrong) twice, sandboxed, with real
kernels: on this machine's pool of 2 slots, and on a LocalCluster of 2 worker processes of one
thread each. Prints side by side: wall time, throughput, and time per notebook; for the
cluster also its start-up (LocalCluster up and down, no work) and Dask's own overhead per task
(N no-op tasks carrying the same payload as a grading task: one submission's bytes and its
expected answers). It also prints the peak memory of the grader and everything under it
(resident set, sampled every 0.2 s), the disk each student's output takes, and the grader
process's own work per student (writing records and pages), which no cluster shares.

Run from the repository root, with the ``cluster`` extra installed:
``python benchmarks/bench_cluster.py [--students 200] [--problems inertia_tensor]``
"""

from __future__ import annotations

import argparse
import os
import sys
import tempfile
import threading
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))

from bench_grade import machine, make_class


class PeakMemory:
    """Peak resident memory of this process and all its descendants, sampled in a thread."""

    def __init__(self, every: float = 0.2) -> None:
        import psutil

        self.me, self.every, self.peak = psutil.Process(), every, 0
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._run, daemon=True)

    def _run(self) -> None:
        import psutil

        while not self._stop.is_set():
            total = 0
            for p in [self.me, *self.me.children(recursive=True)]:
                try:
                    total += p.memory_info().rss
                except psutil.Error:
                    pass
            self.peak = max(self.peak, total)
            self._stop.wait(self.every)

    def __enter__(self) -> PeakMemory:
        self._thread.start()
        return self

    def __exit__(self, *exc: object) -> None:
        self._stop.set()
        self._thread.join()


def _noop(payload: tuple) -> int:
    """A task that does nothing with a grading task's payload (Dask overhead only)."""
    return len(payload[0])


def dask_overhead(tasks: list[tuple]) -> tuple[float, float]:
    """(seconds to start and stop a 2-worker LocalCluster, seconds per no-op task)."""
    from distributed import as_completed

    from grader.executors.dask import cluster_client

    start = time.perf_counter()
    with cluster_client("local:2") as client:
        up = time.perf_counter() - start
        client.submit(_noop, tasks[0], pure=False).result()  # warm the workers' imports
        start = time.perf_counter()
        futures = [client.submit(_noop, t, pure=False) for t in tasks]
        for f in as_completed(futures):
            f.result()
        per_task = (time.perf_counter() - start) / len(tasks)
        down = time.perf_counter()
    up += time.perf_counter() - down
    return up, per_task


def grade(hw: Path, subs: Path, out: Path, **how) -> tuple[float, int]:
    """(wall seconds, peak bytes) of grading the class."""
    from grader.pipeline import grade_assignment

    with PeakMemory() as memory:
        start = time.perf_counter()
        report = grade_assignment(hw, subs, out, force=True, **how)
        wall = time.perf_counter() - start
    bad = [r.student_id for r in report.results if r.status != "graded"]
    if bad:
        raise SystemExit(f"bench_cluster: not graded: {', '.join(bad[:5])}")
    return wall, memory.peak


def client_cost(hw: Path, graded: Path) -> tuple[float, float]:
    """Seconds per student of the grader process's own work, whatever the cluster: a record
    that came back as JSON made into its result file and feedback page (``_publish``), and
    the final rebuild of the gradebook and every page (``_rebuild``), into a scratch folder."""
    from grader.assignment import load_assignment
    from grader.graded_folder import FEEDBACK, RESULTS
    from grader.publish import publish_record as _publish
    from grader.publish import rebuild as _rebuild
    from grader.results import StudentResult, read_result

    a = load_assignment(hw)
    records = {sid: read_result(graded / RESULTS / f"{sid}.json") for sid in a.ids}
    returned = [r.to_dict() for r in records.values()]
    with tempfile.TemporaryDirectory() as folder:
        out = Path(folder)
        (out / RESULTS).mkdir()
        (out / FEEDBACK).mkdir()
        start = time.perf_counter()
        for d in returned:
            _publish(a, out, StudentResult.from_dict(d), False)
        publish = (time.perf_counter() - start) / len(returned)
        start = time.perf_counter()
        _rebuild(a, out, records, False)
        rebuild = (time.perf_counter() - start) / len(returned)
    return publish, rebuild


def _disk(out: Path) -> float:
    files = [p for sub in ("results", "feedback") for p in (out / sub).iterdir()]
    return sum(p.stat().st_size for p in files) / max(1, len(files) // 2)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--students", type=int, default=200)
    parser.add_argument("--problems", default="inertia_tensor")
    args = parser.parse_args(argv)
    try:
        import distributed  # noqa: F401
    except ImportError:
        print("bench_cluster: needs pip install 'eulertop[cluster]'", file=sys.stderr)
        return 2
    from grader.assignment import load_assignment
    from grader.compare import key_answers

    n = args.students
    with tempfile.TemporaryDirectory() as folder:
        root = Path(folder)
        hw, subs = make_class(root, n, args.problems.split(","))
        a = load_assignment(hw)
        sizes = [p.stat().st_size for p in subs.iterdir()]
        payload = [((subs / f"{sid}.ipynb").read_bytes(), key_answers(a.key, sid))
                   for sid in a.ids]
        print(f"machine: {machine()}; load average {os.getloadavg()[0]:.1f} at the start")
        print(f"class: {n} submissions of {args.problems} (mean {sum(sizes) / n / 1024:.1f} "
              "KiB), sandboxed, real kernels")
        local, local_mem = grade(hw, subs, root / "local", jobs=2)
        up, per_task = dask_overhead(payload)
        remote, remote_mem = grade(hw, subs, root / "cluster", cluster="local:2")
        disk = _disk(root / "local")
        publish, rebuild = client_cost(hw, root / "local")
        print(f"load average {os.getloadavg()[0]:.1f} at the end")
    rows = [("local pool, --jobs 2", local, local_mem, ""),
            ("LocalCluster, 2 workers", remote, remote_mem,
             f"includes starting and stopping the cluster: {up:.1f} s measured apart; "
             f"without it {1000 * (remote - up) / n:.0f} ms per notebook")]
    print(f"{'where':26} {'wall':>8} {'notebooks/min':>14} {'per notebook':>13} "
          f"{'peak memory':>12}")
    for name, wall, mem, note in rows:
        print(f"{name:26} {wall:7.1f}s {60 * n / wall:14.0f} {1000 * wall / n:11.0f}ms "
              f"{mem / 2**20:10.0f}MiB  {note}")
    print(f"Dask overhead per task (no-op task with a grading task's payload, 2 workers): "
          f"{1000 * per_task:.1f} ms; cluster minus local per notebook: "
          f"{1000 * (remote - local) / n:.0f} ms")
    print(f"disk per student: {disk / 1024:.1f} KiB (result record + feedback page)")
    print(f"grader process per student (on its machine, whatever the cluster): "
          f"{1000 * publish:.1f} ms to write a returned record and its page, "
          f"{1000 * rebuild:.1f} ms in the final rebuild")
    return 0


if __name__ == "__main__":
    sys.exit(main())
