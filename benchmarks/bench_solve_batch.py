"""Throughput of `eulertop solve --batch` (issue 2): cases answered per second.

Run by hand::

    python benchmarks/bench_solve_batch.py [--cases 5000] [--repeats 3]

It writes a JSON-lines file of random, physically sensible cases of every scene (mostly heavy
tops, the costliest), runs the console script on it as a user would (a fresh process each time,
so start-up is included), and prints the median wall time over the repeats, the cases per second
and the machine. Not a test: these machines are shared and noisy, so only the ratios measured in
one run mean much.
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np


def random_cases(n: int, rng: np.random.Generator) -> list[dict]:
    """`n` cases: 70 % heavy tops, 10 % each free tops, Euler angles and point-mass bodies."""
    cases: list[dict] = []
    for i in range(n):
        kind = rng.choice(["heavy-top"] * 7 + ["free-top", "euler-angles", "inertia"])
        if kind == "heavy-top":
            i1 = rng.uniform(1e-4, 1e-3)
            case = {"I1": i1, "I3": i1 * rng.uniform(0.2, 1.5), "Mgl": rng.uniform(0.01, 0.3),
                    "beta0": rng.uniform(0.05, 3.0), "alpha_dot0": rng.uniform(-5, 5),
                    "beta_dot0": rng.uniform(-2, 2), "gamma_dot0": rng.uniform(50, 2000)}
        elif kind == "free-top":
            moments = np.sort(rng.uniform(1.0, 3.0, 3))
            while moments[0] + moments[1] < moments[2]:
                moments = np.sort(rng.uniform(1.0, 3.0, 3))
            case = {"I1": moments[0], "I2": moments[1], "I3": moments[2],
                    "omega0": rng.normal(size=3).tolist(), "t": rng.uniform(0, 10)}
        elif kind == "euler-angles":
            case = dict(zip(("alpha", "beta", "gamma", "alpha_dot", "beta_dot", "gamma_dot"),
                            rng.uniform(-3, 3, 6), strict=True))
        else:
            k = int(rng.integers(2, 6))
            case = {"masses": rng.uniform(0.1, 2, k).tolist(),
                    "positions": rng.uniform(-0.3, 0.3, (k, 3)).tolist()}
        cases.append({"id": i, "scene": str(kind),
                      **{k: (float(v) if np.isscalar(v) else v) for k, v in case.items()}})
    return cases


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--cases", type=int, default=5000)
    parser.add_argument("--repeats", type=int, default=3)
    args = parser.parse_args()
    cases = random_cases(args.cases, np.random.default_rng(2024))
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "cases.jsonl"
        path.write_text("".join(json.dumps(c) + "\n" for c in cases), encoding="utf-8")
        times, errors = [], 0
        for _ in range(args.repeats):
            start = time.perf_counter()
            proc = subprocess.run([sys.executable, "-m", "eulertop", "solve", "--batch", str(path)],
                                  capture_output=True, text=True, check=False)
            times.append(time.perf_counter() - start)
            errors = sum('"error"' in line for line in proc.stdout.splitlines())
        start = time.perf_counter()
        subprocess.run([sys.executable, "-m", "eulertop", "solve", "--batch", os.devnull],
                       capture_output=True, check=False)
        startup = time.perf_counter() - start
    median = statistics.median(times)
    print(f"machine: {platform.machine()} {platform.processor() or ''}, {os.cpu_count()} cores, "
          f"Python {platform.python_version()}, numpy {np.__version__}")
    print(f"eulertop solve --batch: {args.cases} cases ({errors} answered with an error), "
          f"median of {args.repeats}: {median:.2f} s → {args.cases / median:,.0f} cases/s "
          f"(process start-up with an empty batch: {startup:.2f} s)")


if __name__ == "__main__":
    main()
