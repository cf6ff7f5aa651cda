"""Benchmark ``eulertop grade`` against bare nbclient and nbgrader's ``autograde`` (issue 4).

Makes an assignment of ``--students`` (40) students, and one submission each: the student's
solutions notebook with small noise on every number (relative 1e-6 — still correct — and, for
every fifth student, 1e-1 on one answer — wrong). Then, on the same notebooks, in one run:

* ``eulertop grade --jobs J --force`` as a fresh process (start-up included): notebooks per
  minute, from the median of ``--runs`` runs, with warm kernels (the default: forked from a
  zygote, :mod:`grader.kernels.pool`) and with ``--cold-kernels``; CPU seconds per notebook
  (user + system of the grader and every process it started, from ``RUSAGE_CHILDREN``);
* the same with ``--jobs 1``, and every notebook executed bare, one after the other, with
  ``nbclient.NotebookClient`` in one process: the per-notebook overhead of eulertop over bare
  execution is the difference of the two serial times, divided by the number of notebooks;
* nbgrader's ``autograde`` on equivalent notebooks — installed by this script with
  ``python -m venv`` and ``pip install nbgrader`` into a temporary folder (not a dependency of
  eulertop). Its source notebook is the first student's, with each answer cell an autograded
  answer and one test cell per question; each submission is the student's own notebook in that
  form, so every kernel runs the same parameters and answers as eulertop's. If the install
  fails (no network, no wheel), that is said and the rest is still reported.

Run from the repository root: ``PYTHONPATH=. python benchmarks/bench_grade.py [--students 40]
[--jobs 2] [--runs 3] [--problems inertia_tensor,euler_rotation] [--no-nbgrader]``.
"""

from __future__ import annotations

import argparse
import ast
import json
import os
import platform
import random
import resource
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def machine() -> str:
    """One line naming where the numbers were measured."""
    import nbclient
    import numpy as np

    cpu = platform.processor() or platform.machine()
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                cpu = line.split(":", 1)[1].strip()
                break
    except OSError:
        pass
    return (f"{cpu}, {os.cpu_count()} cores, {platform.system()} {platform.release()}, "
            f"Python {platform.python_version()}, numpy {np.__version__}, "
            f"nbclient {nbclient.__version__}")


def _noisy(value, rel: float, rng: random.Random):
    if isinstance(value, float):
        return value * (1 + rel * rng.uniform(-1, 1))
    if isinstance(value, list):
        return [_noisy(v, rel, rng) for v in value]
    return value


def _source(cell: dict) -> str:
    return "".join(cell["source"]) if isinstance(cell["source"], list) else cell["source"]


def noisy_notebook(nb: dict, seed: int, wrong: bool) -> dict:
    """The solutions notebook with each numeric answer perturbed (module docstring)."""
    rng = random.Random(seed)
    spoiled = not wrong
    for cell in nb["cells"]:
        if cell["metadata"].get("eulertop", {}).get("role") != "answer":
            continue
        lines = []
        for line in _source(cell).splitlines():
            name, sep, rest = line.partition(" = ")
            if sep and name.isidentifier():
                literal, _, comment = rest.partition("  #")
                value = ast.literal_eval(literal)
                rel = 1e-6 if spoiled else 1e-1
                noisy = _noisy(value, rel, rng)
                spoiled = spoiled or noisy != value
                line = f"{name} = {noisy!r}" + (f"  #{comment}" if comment else "")
            lines.append(line)
        cell["source"] = "\n".join(lines)
    return nb


def make_class(root: Path, students: int, problems: list[str]) -> tuple[Path, Path]:
    """An assignment and one noisy submission per student."""
    from problems.generate import generate_assignment
    from problems.roster import Roster
    from problems.templates import FAMILIES

    hw, subs = root / "HW", root / "subs"
    roster = Roster(("id",), tuple({"id": f"s{i:03d}"} for i in range(students)))
    generate_assignment(roster, hw, FAMILIES, problems=problems, seed=2024)
    subs.mkdir()
    for i, row in enumerate(roster.rows):
        nb = json.loads((hw / "solutions" / f"{row['id']}.ipynb").read_text())
        (subs / f"{row['id']}.ipynb").write_text(json.dumps(noisy_notebook(nb, i, i % 5 == 4)))
    return hw, subs


def _cpu(who: int) -> float:
    usage = resource.getrusage(who)
    return usage.ru_utime + usage.ru_stime


def _timed(cmd: list[str], **kw) -> tuple[float, float]:
    """(wall seconds, CPU seconds of the command and every process it waited for)."""
    c0, t0 = _cpu(resource.RUSAGE_CHILDREN), time.perf_counter()
    subprocess.run(cmd, check=False, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, **kw)
    return time.perf_counter() - t0, _cpu(resource.RUSAGE_CHILDREN) - c0


def _median(samples: list[tuple[float, float]]) -> tuple[float, float]:
    """The (wall, CPU) sample of median wall time."""
    ordered = sorted(samples)
    return ordered[(len(ordered) - 1) // 2]


def time_eulertop(hw: Path, subs: Path, jobs: int, runs: int,
                  cold: bool = False) -> tuple[float, float]:
    """(wall, CPU) seconds of ``eulertop grade --force`` as a fresh process (median run)."""
    cmd = [sys.executable, "-m", "eulertop", "grade", str(hw), str(subs), "--jobs", str(jobs),
           "--force", *(["--cold-kernels"] if cold else [])]
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    return _median([_timed(cmd, env=env, cwd=ROOT) for _ in range(runs)])


def time_bare(subs: Path, runs: int) -> tuple[float, float]:
    """(wall, CPU) seconds of executing every notebook with nbclient, serially, in-process
    (median run; CPU of this process and the kernels)."""
    import nbformat
    from nbclient import NotebookClient

    paths = sorted(subs.glob("*.ipynb"))

    def once() -> tuple[float, float]:
        c0 = _cpu(resource.RUSAGE_SELF) + _cpu(resource.RUSAGE_CHILDREN)
        t0 = time.perf_counter()
        for p in paths:
            nb = nbformat.read(p, as_version=4)
            NotebookClient(nb, kernel_name="python3", timeout=60, allow_errors=True).execute()
        return (time.perf_counter() - t0,
                _cpu(resource.RUSAGE_SELF) + _cpu(resource.RUSAGE_CHILDREN) - c0)

    return _median([once() for _ in range(runs)])


# --------------------------------------------------------------------------------------------
# nbgrader


def _nbgrader_notebook(nb: dict, points: dict[int, int]) -> dict:
    """A student's notebook in nbgrader's form: answer cells autograded, one test per question."""
    cells = []
    for cell in nb["cells"]:
        meta = cell["metadata"].get("eulertop", {})
        cell = {**cell, "metadata": {}}
        if cell["cell_type"] == "code":
            cell["outputs"], cell["execution_count"] = [], None
        if meta.get("role") == "answer":
            q = meta["question"]
            cell["metadata"]["nbgrader"] = {"grade": False, "solution": True, "locked": False,
                                            "grade_id": f"answer{q}", "schema_version": 3,
                                            "task": False}
            names = [line.split(" = ")[0] for line in _source(cell).splitlines()]
            cells.append(cell)
            cells.append({
                "cell_type": "code", "id": f"test{q}", "execution_count": None, "outputs": [],
                "source": "\n".join(f"assert {n} is not None" for n in names),
                "metadata": {"nbgrader": {"grade": True, "solution": False, "locked": True,
                                          "grade_id": f"test{q}", "points": points[q],
                                          "schema_version": 3, "task": False}},
            })
        else:
            cells.append(cell)
    return {**nb, "cells": cells}


def install_nbgrader(venv: Path) -> tuple[Path | None, str]:
    """``python -m venv`` + ``pip install nbgrader``; (the nbgrader executable, or None, why)."""
    t0 = time.perf_counter()
    steps = [[sys.executable, "-m", "venv", str(venv)],
             [str(venv / "bin" / "python"), "-m", "pip", "install", "-q", "nbgrader"]]
    for cmd in steps:
        done = subprocess.run(cmd, capture_output=True, text=True, check=False)
        if done.returncode != 0:
            return None, f"'{' '.join(cmd[-3:])}' failed: {done.stderr.strip()[-300:]}"
    return venv / "bin" / "nbgrader", f"installed in {time.perf_counter() - t0:.0f} s"


def time_nbgrader(nbgrader: Path, course: Path, hw: Path, subs: Path,
                  runs: int) -> tuple[float, float]:
    """(wall, CPU) seconds of ``nbgrader autograde ps1 --force`` over the same submissions
    (median run)."""
    key = json.loads((hw / "key.json").read_text())["students"]
    ids = sorted(key)
    points = {q["question"]: len(q["answers"]) for q in key[ids[0]]["questions"]}
    course.mkdir()
    (course / "nbgrader_config.py").write_text(
        f"c = get_config()\nc.CourseDirectory.root = {str(course)!r}\n"
        "c.CourseDirectory.db_url = 'sqlite:///' + " + repr(str(course / "gradebook.db")) + "\n"
        "c.ExecutePreprocessor.timeout = 60\n")
    source = course / "source" / "ps1"
    source.mkdir(parents=True)
    first = json.loads((subs / f"{ids[0]}.ipynb").read_text())
    (source / "ps1.ipynb").write_text(json.dumps(_nbgrader_notebook(first, points)))
    for sid in ids:
        target = course / "submitted" / sid / "ps1"
        target.mkdir(parents=True)
        nb = json.loads((subs / f"{sid}.ipynb").read_text())
        (target / "ps1.ipynb").write_text(json.dumps(_nbgrader_notebook(nb, points)))
    (course / "students.csv").write_text("id\n" + "\n".join(ids) + "\n")
    env = {**os.environ, "PYTHONPATH": "",
           "PATH": f"{nbgrader.parent}{os.pathsep}{os.environ.get('PATH', '')}"}
    for cmd in (["db", "student", "import", "students.csv"], ["generate_assignment", "ps1"]):
        done = subprocess.run([str(nbgrader), *cmd], cwd=course, env=env, capture_output=True,
                              text=True, check=False)
        if done.returncode != 0:
            raise RuntimeError(f"nbgrader {' '.join(cmd)}: {done.stderr.strip()[-500:]}")
    autograde = [str(nbgrader), "autograde", "ps1", "--force"]
    median = _median([_timed(autograde, cwd=course, env=env) for _ in range(runs)])
    graded = len(list(course.glob("autograded/*/ps1/ps1.ipynb")))
    if graded != len(ids):
        raise RuntimeError(f"autograde wrote {graded} of {len(ids)} graded notebooks")
    return median


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--students", type=int, default=40)
    parser.add_argument("--jobs", type=int, default=2)
    parser.add_argument("--runs", type=int, default=3)
    parser.add_argument("--problems", default="inertia_tensor,euler_rotation")
    parser.add_argument("--no-nbgrader", action="store_true")
    parser.add_argument("--nbgrader-venv", type=Path, metavar="DIR",
                        help="reuse a virtual environment that has nbgrader (default: install "
                             "it afresh into a temporary folder)")
    args = parser.parse_args(argv)
    n = args.students
    print(f"machine: {machine()}")
    with tempfile.TemporaryDirectory(prefix="bench-grade-") as tmp:
        tmp = Path(tmp)
        hw, subs = make_class(tmp, n, args.problems.split(","))
        print(f"{n} submissions, problems {args.problems}; median of {args.runs} run(s); "
              f"load average before: {os.getloadavg()[0]:.2f}")
        rows: dict[str, tuple[float, float]] = {}

        def row(label: str, sample: tuple[float, float]) -> None:
            rows[label] = sample
            wall, cpu = sample
            print(f"{label:34s} {wall:6.1f} s  {60 * n / wall:6.1f} notebooks/min  "
                  f"{wall / n:5.2f} s/notebook  CPU {cpu / n:5.2f} s/notebook", flush=True)

        warm_label, cold_label = (f"eulertop --jobs {args.jobs} (warm kernels)",
                                  f"eulertop --jobs {args.jobs} --cold-kernels")
        row(warm_label, time_eulertop(hw, subs, args.jobs, args.runs))
        row(cold_label, time_eulertop(hw, subs, args.jobs, args.runs, cold=True))
        row("eulertop --jobs 1 (warm kernels)", time_eulertop(hw, subs, 1, args.runs))
        row("bare nbclient, serial, in-process", time_bare(subs, args.runs))
        warm, one, bare = (rows[warm_label][0], rows["eulertop --jobs 1 (warm kernels)"][0],
                           rows["bare nbclient, serial, in-process"][0])
        print(f"overhead of eulertop (warm, --jobs 1) over bare nbclient: "
              f"{(one - bare) / n:+.2f} s/notebook (negative: faster than a bare run, whose "
              "kernels start cold)")
        if not args.no_nbgrader:
            if args.nbgrader_venv:
                nbgrader, note = args.nbgrader_venv / "bin" / "nbgrader", "reused"
            else:
                nbgrader, note = install_nbgrader(tmp / "venv")
            if nbgrader is None:
                print(f"nbgrader: could not be installed here ({note}); not measured")
                return 0
            print(f"nbgrader: {note}")
            try:
                row("nbgrader autograde (serial)",
                    time_nbgrader(nbgrader, tmp / "course", hw, subs, args.runs))
            except RuntimeError as e:
                print(f"nbgrader: could not be run ({e}); not measured")
                return 0
            nbg, cold = rows["nbgrader autograde (serial)"][0], rows[cold_label][0]
            print(f"throughput vs nbgrader: warm --jobs {args.jobs} {nbg / warm:.1f}x, "
                  f"cold --jobs {args.jobs} {nbg / cold:.1f}x, warm --jobs 1 {nbg / one:.1f}x")
        print(f"load average after: {os.getloadavg()[0]:.2f}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
