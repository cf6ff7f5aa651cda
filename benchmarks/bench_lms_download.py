"""Benchmark reading an LMS bulk download: a Canvas zip of N students → (student, notebook) pairs.

Builds a Canvas "Download Submissions" zip of ``--students`` notebooks (each a generated
solutions notebook, one question family, about 10 kB) plus a PDF per tenth student, then times,
as median of ``--runs``: the zip's checks and extraction into a fresh folder
(:func:`grader.lms.archive.extract_download`) and the matching
(:func:`grader.discover.discover` with the Canvas class list). No kernel runs.

Run from the repository root: ``PYTHONPATH=. python benchmarks/bench_lms_download.py
[--students 500] [--runs 5]``
"""

from __future__ import annotations

import argparse
import os
import platform
import statistics
import tempfile
import time
import zipfile
from pathlib import Path

from grader.discover import discover
from grader.lms.archive import extract_download
from problems.generate import generate_assignment
from problems.roster import Roster
from problems.templates import FAMILIES


def _class(root: Path, n: int) -> tuple[Roster, Path]:
    rows = tuple({"id": f"s{i:04d}", "Student": f"Student{i}, Ann", "ID": str(10_000 + i),
                  "Section": "A"} for i in range(n))
    roster = Roster(("id", "Student", "ID", "Section"), rows, "canvas")
    hw = root / "HW"
    generate_assignment(roster, hw, FAMILIES, problems=["inertia_tensor"], seed=1)
    archive = root / "submissions.zip"
    with zipfile.ZipFile(archive, "w", zipfile.ZIP_DEFLATED) as z:
        for i, r in enumerate(rows):
            name = f"student{i}ann_{r['ID']}_{90_000 + i}_hw.ipynb"
            z.write(hw / "solutions" / f"{r['id']}.ipynb", name)
            if i % 10 == 0:
                z.writestr(f"student{i}ann_{r['ID']}_{80_000 + i}_scan.pdf", b"%PDF-1.4\n" * 100)
    return roster, archive


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--students", type=int, default=500)
    parser.add_argument("--runs", type=int, default=5)
    args = parser.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        root = Path(tmp)
        roster, archive = _class(root, args.students)
        extract, match = [], []
        for run in range(args.runs):
            out = root / f"out{run}"
            out.mkdir()
            t0 = time.perf_counter()
            folder = extract_download(archive, out / "download").folder
            t1 = time.perf_counter()
            found = discover(folder, roster.ids, roster.rows)
            t2 = time.perf_counter()
            extract.append(t1 - t0)
            match.append(t2 - t1)
            assert len(found.submissions) == args.students, found.problems[:3]
        print(f"{platform.processor() or platform.machine()}, {os.cpu_count()} cores, "
              f"Python {platform.python_version()}")
        print(f"Canvas zip: {args.students} notebooks + {len(found.problems)} PDFs, "
              f"{archive.stat().st_size / 1e6:.1f} MB")
        print(f"check + extract: median {statistics.median(extract):.3f} s; "
              f"match: median {statistics.median(match):.3f} s ({args.runs} runs)")


if __name__ == "__main__":
    main()
