"""What the benchmarks that compare a figure with its floor share (issue 34): the run's record,
timing in interleaved rounds, and writing their block into the speed page.

Each such benchmark (``bench_heavy_top.py``, ``bench_generate.py``, ``bench_startup.py``)
measures ours and the floor in the same run, round after round (one of each per round, so that
a change of the shared machine's speed falls on both), writes every timing into a JSON record
under ``docs/bench/`` (``--record``), and renders its text from that record alone into its
block of ``docs/speed.md`` (``--page``), between ``<!-- <bench>: begin -->`` and
``<!-- <bench>: end -->``. ``tests/test_speed_page.py`` renders each block again from the
committed record and fails on a difference, so no number on the page is typed by hand.
"""

from __future__ import annotations

import json
import os
import platform
import statistics
import sys
import time
from collections.abc import Callable
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from solver.bench.summary import cpu_model, current_block, markers_of, replace_block  # noqa: E402


def machine() -> dict:
    """The CPU, its count, Python, numpy and scipy, and the load averages now."""
    import numpy
    import scipy

    return {"cpu": cpu_model(), "cpu_count": os.cpu_count(), "python": platform.python_version(),
            "numpy": numpy.__version__, "scipy": scipy.__version__,
            "load": [round(x, 2) for x in os.getloadavg()]}


def interleaved(contenders: dict[str, Callable[[], object]], rounds: int) -> dict[str, list]:
    """Each contender once per round, in turn (the order reversed every other round), for
    ``rounds`` rounds: ``{name: [{"wall": s, "cpu": s}, …]}`` (``cpu``: this process's CPU
    time, which other jobs on the machine disturb less than the wall clock)."""
    times: dict[str, list] = {name: [] for name in contenders}
    names = list(contenders)
    for i in range(rounds):
        for name in names if i % 2 == 0 else names[::-1]:
            cpu, wall = time.process_time(), time.perf_counter()
            contenders[name]()
            times[name].append({"wall": time.perf_counter() - wall,
                                "cpu": time.process_time() - cpu})
    return times


def median(rounds: list[dict], key: str = "wall") -> float:
    """The median of one clock over the rounds."""
    return statistics.median(r[key] for r in rounds)


def write_record(path: Path, record: dict) -> None:
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(json.dumps(record, indent=1) + "\n", encoding="utf-8")


def read_record(path: Path) -> dict:
    return json.loads(path.read_text(encoding="utf-8"))


def check_page(page: Path | None, bench: str) -> None:
    """Fail before measuring, not after, when ``page`` lacks the benchmark's block."""
    if page is not None:
        current_block(page.read_text(encoding="utf-8"), str(page), markers_of(bench))


def write_block(page: Path, bench: str, lines: list[str]) -> None:
    """Put ``lines`` between the benchmark's markers in ``page``."""
    begin, end = markers_of(bench)
    block = "\n".join([begin, *lines, end]) + "\n"
    text = page.read_text(encoding="utf-8")
    page.write_text(replace_block(text, block, str(page), (begin, end)), encoding="utf-8")


def header(record: dict) -> str:
    """Who measured what, where: the command, the date, the machine and its load."""
    m = record["machine"]
    return (f"Measured by `{record['command']}` on {record['date']}: {m['cpu']}, "
            f"{m['cpu_count']} CPUs (shared), Python {m['python']}, numpy {m['numpy']}, "
            f"scipy {m['scipy']}; load average {_load(m['load'])} at the start, "
            f"{_load(record['load_after'])} at the end.")


def _load(load: list[float]) -> str:
    return ", ".join(f"{x:.1f}" for x in load)


def seconds(x: float) -> str:
    """A duration with two or three significant digits: ``1.33 s``, ``460 ms``, ``2.1 ms``."""
    if x >= 1:
        return f"{x:.2f} s"
    if x >= 1e-3:
        return f"{x * 1e3:.3g} ms"
    return f"{x * 1e6:.3g} µs"


def now() -> str:
    return time.strftime("%Y-%m-%d %H:%M UTC", time.gmtime())
