"""Grading throughput before and after a change, side by side in one run (issue 11).

Grades one class (``--students`` solutions notebooks, default 40) with ``eulertop grade --jobs
2 --force``, alternately with this checkout and with another checkout of eulertop (``--base
DIR``, e.g. a ``git worktree`` of the commit before the change), ``--runs`` times each (ABAB…,
so both see the same machine load), and reports the median wall time of each and their ratio.
Both run on this interpreter (the other checkout first on ``PYTHONPATH``).

    git worktree add /tmp/eulertop-base <commit>
    PYTHONPATH=. python benchmarks/bench_isolation.py --base /tmp/eulertop-base
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def make_class(folder: Path, students: int) -> tuple[Path, Path]:
    sys.path.insert(0, str(ROOT))
    from problems.generate import generate_assignment
    from problems.roster import Roster
    from problems.templates import FAMILIES

    hw, subs = folder / "HW", folder / "subs"
    roster = Roster(("id",), tuple({"id": f"s{i:03d}"} for i in range(students)))
    generate_assignment(roster, hw, FAMILIES, problems=["inertia_tensor", "euler_rotation"],
                        seed=3)
    subs.mkdir()
    for path in (hw / "solutions").glob("*.ipynb"):  # saved again: grade refuses the generated
        (subs / path.name).write_text(json.dumps(json.loads(path.read_text())))  # bytes alone
    return hw, subs


def grade_seconds(checkout: Path, hw: Path, subs: Path, out: Path) -> float:
    env = {**os.environ, "PYTHONPATH": str(checkout)}
    argv = [sys.executable, "-c", "import sys; from eulertop.cli import main; sys.exit(main())",
            "grade", str(hw), str(subs), "--out", str(out), "--jobs", "2", "--force"]
    t0 = time.perf_counter()
    done = subprocess.run(argv, env=env, cwd=checkout, capture_output=True, text=True)
    seconds = time.perf_counter() - t0
    if done.returncode != 0:
        raise SystemExit(f"{checkout}: grade failed ({done.returncode}): {done.stderr[-2000:]}")
    return seconds


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--base", type=Path, required=True, help="the other checkout")
    parser.add_argument("--students", type=int, default=40)
    parser.add_argument("--runs", type=int, default=3)
    args = parser.parse_args()
    with tempfile.TemporaryDirectory(prefix="eulertop-bench-") as tmp:
        hw, subs = make_class(Path(tmp), args.students)
        times: dict[str, list[float]] = {"this": [], "base": []}
        for i in range(args.runs):
            for name, checkout in (("this", ROOT), ("base", args.base.resolve())):
                seconds = grade_seconds(checkout, hw, subs, Path(tmp) / f"out-{name}")
                times[name].append(seconds)
                print(f"run {i + 1}: {name}: {seconds:.2f} s", file=sys.stderr, flush=True)
    this, base = (statistics.median(times[k]) for k in ("this", "base"))
    print(f"{args.students} notebooks, --jobs 2, median of {args.runs} runs each (ABAB…):")
    print(f"  this checkout: {this:.2f} s ({60 * args.students / this:.0f} notebooks/min)")
    print(f"  base {args.base}: {base:.2f} s ({60 * args.students / base:.0f} notebooks/min)")
    print(f"  time ratio this/base: {this / base:.3f}")


if __name__ == "__main__":
    main()
