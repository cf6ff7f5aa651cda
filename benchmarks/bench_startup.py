"""Start-up and marginal cost of ``eulertop grade`` (issue 17), nbgrader side by side.

Two classes of correct submissions (the students' solutions with a relative noise of 1e-6, as
in ``bench_grade.py``), of ``--small`` (10) and ``--large`` (50) students, each its own
assignment with the same problems. Every round times, as fresh processes, ``eulertop grade
--force`` of both classes at ``--jobs 1`` and ``--jobs 2`` (order alternated between rounds),
and from each pair

    marginal = (t_large - t_small) / (large - small)       seconds per notebook
    start-up = t_small - small * marginal                   seconds per run

so that what a run pays once (imports, sandbox, zygotes, the class report) and what each
notebook costs are told apart — in wall time, and in CPU time of the whole machine
(``/proc/stat``: the sandboxed kernels included; other jobs on the machine count too, so run it
on an idle one). Medians over ``--rounds`` (4). Then ``eulertop check`` of one notebook (median
of 5), and, unless ``--no-nbgrader``, nbgrader's ``autograde`` on the same two classes
(installed into a temporary virtual environment, as ``bench_grade.py`` does; fewer runs, it is
slow).

With ``--imports``, every submission first imports numpy, scipy, sympy and matplotlib, so that
the zygotes preload all of them (what they preload is what the class's code imports). The
speed of a pure-Python loop is printed before and after (the machines are shared; their speed
varies by a third from one minute to the next).

Run from the repository root: ``PYTHONPATH=. python benchmarks/bench_startup.py [--rounds 4]
[--small 10] [--large 50] [--no-nbgrader] [--imports] [--work S]``. ``--work S`` adds a cell
that keeps the kernel's CPU busy for S seconds: the class of a notebook that computes.

Each round also times the floor of a run's start-up (issue 34): a fresh interpreter importing
what the zygotes preload for these notebooks (IPython, the kernel's modules and, with
``--imports``, numpy, scipy, sympy and matplotlib) — what any grader that has them loaded
before the first notebook pays at least once. ``--record FILE`` keeps every timing (JSON),
``--page FILE`` writes start-up and floor side by side into that page's ``bench_startup``
block (``docs/speed.md``).
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

sys.path.insert(0, str(Path(__file__).resolve().parent))
from bench_grade import (  # a script beside this one
    ROOT,
    install_nbgrader,
    machine,
    noisy_notebook,
    time_nbgrader,
)

PROBLEMS = ["inertia_tensor", "euler_rotation"]


IMPORT_CELL = ("import numpy as np\nimport scipy.integrate\nimport sympy as sp\n"
               "import matplotlib.pyplot as plt")
"""With ``--imports``: a first code cell in every submission, importing every package the
zygotes can preload (``grader.kernels.preload.PRELOADABLE``), so that they all are."""


def work_cell(seconds: float) -> str:
    """A cell that keeps the CPU busy for ``seconds`` of the kernel's own CPU time."""
    return ("import time\nstart = time.process_time()\n"
            f"while time.process_time() - start < {seconds!r}:\n    pass")


def make_correct_class(root: Path, students: int, imports: bool = False,
                       work: float = 0.0) -> tuple[Path, Path]:
    """An assignment of ``students`` and one correct (lightly noisy) submission each (each
    importing :data:`IMPORT_CELL` first, with ``imports``; with a cell computing for ``work``
    seconds of CPU, if any)."""
    from problems.generate import generate_assignment
    from problems.roster import Roster
    from problems.templates import FAMILIES

    hw, subs = root / "HW", root / "subs"
    roster = Roster(("id",), tuple({"id": f"s{i:03d}"} for i in range(students)))
    generate_assignment(roster, hw, FAMILIES, problems=PROBLEMS, seed=2024)
    subs.mkdir()
    for i, row in enumerate(roster.rows):
        nb = noisy_notebook(json.loads((hw / "solutions" / f"{row['id']}.ipynb").read_text()),
                            i, False)
        for name, source in (("imports", IMPORT_CELL if imports else ""),
                             ("work", work_cell(work) if work else "")):
            if source:
                nb["cells"].insert(0, {"cell_type": "code", "execution_count": None, "id": name,
                                       "metadata": {}, "outputs": [], "source": source})
        (subs / f"{row['id']}.ipynb").write_text(json.dumps(nb))
    return hw, subs


def machine_cpu() -> float:
    """CPU seconds the whole machine has spent so far (``/proc/stat``: user, nice, system,
    irq, softirq, steal) — every process, the sandboxed kernels included, which no rusage of
    this process would count (they are reaped inside their sandboxes)."""
    fields = [int(x) for x in Path("/proc/stat").read_text().split("\n", 1)[0].split()[1:]]
    return sum(fields[i] for i in (0, 1, 2, 5, 6, 7)) / os.sysconf("SC_CLK_TCK")


def timed(cmd: list[str]) -> tuple[float, float]:
    """(wall, machine CPU) seconds of ``cmd`` as a fresh process (it must succeed)."""
    c0, t0 = machine_cpu(), time.perf_counter()
    done = subprocess.run(cmd, cwd=ROOT, env={**os.environ, "PYTHONPATH": str(ROOT)},
                          stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True,
                          check=False)
    if done.returncode != 0:
        raise RuntimeError(f"{' '.join(cmd[2:5])} failed: {done.stderr[-400:]}")
    return time.perf_counter() - t0, machine_cpu() - c0


def python_speed() -> str:
    """How fast this machine runs Python right now (a shared machine's speed varies): the
    seconds of a pure-Python loop of 10⁷ additions, median of 3."""
    def loop() -> float:
        t0, x = time.perf_counter(), 0
        for i in range(10_000_000):
            x += i
        return time.perf_counter() - t0

    seconds = statistics.median(loop() for _ in range(3))
    return f"a pure-Python loop of 10^7 additions takes {seconds:.2f} s"


def grade(hw: Path, subs: Path, jobs: int) -> tuple[float, float]:
    """(wall, machine CPU) seconds of one ``eulertop grade --force``."""
    return timed([sys.executable, "-m", "eulertop", "grade", str(hw), str(subs), "--jobs",
                  str(jobs), "--force"])


def floor_command(imports: bool) -> list[str]:
    """A fresh interpreter importing what the zygotes preload (:func:`floor_modules`)."""
    return [sys.executable, "-c", f"import {', '.join(floor_modules(imports))}"]


def floor_modules(imports: bool) -> tuple[str, ...]:
    """What a class's zygotes import before the first kernel: IPython, the kernel's modules,
    and the preloaded packages of what the notebooks import."""
    from grader.kernels.preload import preload_for
    from grader.kernels.zygote import KERNEL_MODULES

    packages = {"numpy", "scipy", "sympy", "matplotlib"} if imports else set()
    return ("IPython", *preload_for(packages), *KERNEL_MODULES)


def render(record: dict) -> list[str]:
    """The page's text, from the record alone."""
    import speed_page

    floor = statistics.median(record["floor"])
    rows = []
    for jobs in ("1", "2"):
        startup = statistics.median(r[0] for r in record["samples"][jobs])
        marginal = statistics.median(r[1] for r in record["samples"][jobs])
        rows.append(f"| `--jobs {jobs}` | **{speed_page.seconds(startup)}** | "
                    f"{speed_page.seconds(marginal)} | {startup / floor:.2f} |")
    imported = ("each first importing numpy, scipy, sympy and matplotlib" if record["imports"]
                else "importing nothing")
    return [
        speed_page.header(record),
        "",
        f"`eulertop grade --force` of classes of {record['small']} and {record['large']} "
        f"correct submissions ({imported}), sandboxed, each run a fresh process, "
        f"{record['rounds']} rounds alternating the order: start-up = what a run pays once "
        "(the time of the small class less its notebooks at the margin). The floor: a fresh "
        f"interpreter importing what the zygotes preload ({speed_page.seconds(floor)}, median "
        "of the same rounds) — paid before any notebook can run.",
        "",
        "| | start-up | each notebook at the margin | start-up / floor |",
        "|---|---|---|---|",
        *rows,
        "",
        "The target: start-up at most 1.5 s with numpy, scipy, sympy and matplotlib "
        "preloaded, on two cores.",
    ]


def split(small: float, large: float, n_small: int, n_large: int) -> tuple[float, float]:
    """(start-up, marginal) seconds from the times of a small and a large class."""
    marginal = (large - small) / (n_large - n_small)
    return small - n_small * marginal, marginal


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--rounds", type=int, default=4)
    parser.add_argument("--small", type=int, default=10)
    parser.add_argument("--large", type=int, default=50)
    parser.add_argument("--nbgrader-runs", type=int, default=1)
    parser.add_argument("--no-nbgrader", action="store_true")
    parser.add_argument("--imports", action="store_true",
                        help="every submission first imports numpy, scipy, sympy and "
                        "matplotlib (all of what the zygotes can preload)")
    parser.add_argument("--work", type=float, default=0.0, metavar="S",
                        help="every submission also computes for S seconds of CPU (a notebook "
                        "that does something, rather than only state its answers)")
    parser.add_argument("--record", type=Path, help="write every timing into this JSON file")
    parser.add_argument("--page", type=Path, help="write start-up and its floor into this "
                        "page's bench_startup block (docs/speed.md)")
    args = parser.parse_args(argv)
    import speed_page

    speed_page.check_page(args.page, "bench_startup")
    record = {"bench": "bench_startup", "date": speed_page.now(),
              "command": " ".join(["python benchmarks/bench_startup.py", *sys.argv[1:]]),
              "machine": speed_page.machine(), "small": args.small, "large": args.large,
              "rounds": args.rounds, "imports": args.imports, "floor": []}
    print(f"machine: {machine()}")
    with tempfile.TemporaryDirectory(prefix="bench-startup-") as tmp:
        tmp = Path(tmp)
        classes = {n: make_correct_class(tmp / f"c{n}", n, args.imports, args.work)
                   for n in (args.small, args.large)}
        imported = f", each first importing: {IMPORT_CELL!r}" if args.imports else \
            ", importing nothing"
        if args.work:
            imported += f", each computing for {args.work:g} s of CPU"
        print(f"classes of {args.small} and {args.large} correct submissions, problems "
              f"{','.join(PROBLEMS)}{imported}; {args.rounds} rounds; load average before: "
              f"{os.getloadavg()[0]:.2f}; {python_speed()}", flush=True)
        samples: dict[int, list[tuple[float, ...]]] = {1: [], 2: []}
        for r in range(args.rounds):
            for jobs in ((1, 2) if r % 2 == 0 else (2, 1)):
                sizes = (args.small, args.large) if r % 2 == 0 else (args.large, args.small)
                t = {n: grade(*classes[n], jobs) for n in sizes}
                s, m = split(t[args.small][0], t[args.large][0], args.small, args.large)
                cs, cm = split(t[args.small][1], t[args.large][1], args.small, args.large)
                samples[jobs].append((s, m, cs, cm))
                record["floor"].append(timed(floor_command(args.imports))[0])
                print(f"  round {r + 1} --jobs {jobs}: {args.small} in {t[args.small][0]:.2f} s,"
                      f" {args.large} in {t[args.large][0]:.2f} s -> start-up {s:.2f} s, "
                      f"marginal {1000 * m:.0f} ms/notebook; machine CPU: start-up {cs:.2f} s, "
                      f"{1000 * cm:.0f} ms/notebook", flush=True)
        medians = {j: [statistics.median(col) for col in zip(*samples[j], strict=True)]
                   for j in samples}
        for jobs, (s, m, cs, cm) in medians.items():
            print(f"eulertop grade --jobs {jobs}: start-up {s:.2f} s, marginal "
                  f"{1000 * m:.0f} ms/notebook ({60 / m:.0f} notebooks/min at the margin); "
                  f"machine CPU {cs:.2f} s at start-up and {1000 * cm:.0f} ms a notebook; "
                  f"medians of {args.rounds} rounds")
        ratios = [one[1] / two[1] for one, two in zip(samples[1], samples[2], strict=True)]
        print(f"--jobs 2 against --jobs 1 at the margin: {statistics.median(ratios):.2f}x "
              f"(median of the rounds' ratios; each round's: "
              f"{', '.join(f'{x:.2f}' for x in ratios)})")
        notebook = classes[args.small][0] / "solutions" / "s000.ipynb"
        checks = [timed([sys.executable, "-m", "eulertop", "check", str(notebook)])[0]
                  for _ in range(5)]
        print(f"eulertop check of one notebook: median {statistics.median(checks):.2f} s "
              f"(5 runs: {', '.join(f'{x:.2f}' for x in checks)})")
        if not args.no_nbgrader:
            nbgrader, note = install_nbgrader(tmp / "venv")
            if nbgrader is None:
                print(f"nbgrader: could not be installed here ({note}); not measured")
            else:
                t = {n: time_nbgrader(nbgrader, tmp / f"course{n}", *classes[n],
                                      args.nbgrader_runs)[0] for n in classes}
                s, m = split(t[args.small], t[args.large], args.small, args.large)
                print(f"nbgrader autograde ({note}): {args.small} in {t[args.small]:.1f} s, "
                      f"{args.large} in {t[args.large]:.1f} s -> start-up {s:.2f} s, marginal "
                      f"{1000 * m:.0f} ms/notebook; eulertop --jobs 2 is "
                      f"{m / medians[2][1]:.1f}x faster at the margin")
        print(f"load average after: {os.getloadavg()[0]:.2f}; {python_speed()}")
    record["samples"] = {str(j): rows for j, rows in samples.items()}
    record["load_after"] = [round(x, 2) for x in os.getloadavg()]
    if args.record:
        speed_page.write_record(args.record, record)
    if args.page:
        speed_page.write_block(args.page, "bench_startup", render(record))
    print("\n".join(render(record)))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
