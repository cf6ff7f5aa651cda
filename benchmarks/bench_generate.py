"""Benchmark ``eulertop generate``: 300 students × all 14 families, notebooks and key.

Uses the registered templates in catalogue order, repeated when there are fewer than asked.
Each run is a fresh Python process, as ``eulertop generate`` is: the templates' one-time work
(sympy derivations, done once before the worker processes fork) is paid in every run, never
carried over from an earlier one. Prints the machine and its load average before and after,
and the median over the runs of

- ``generate``: the call ``generate_assignment`` alone (target: under 5 s on the 2-core machine
  with one worker process per core, issue 17);
- ``whole process``: interpreter start-up, imports and the call — what a user of
  ``eulertop generate`` waits for;
- ``CPU``: user + system seconds of that process and its worker processes.

Two families' sympy derivations are read back from the user's cache
(:mod:`problems.derivation_cache`), kept there by the first run; ``--no-cache`` derives them in
every run instead (``EULERTOP_CACHE_DIR=off``), as before they were kept. Either way they are
paid the same for every class size, so the cost of one more student (``--margin``) is the same.

``--breakdown`` adds one pass in one process that says where the CPU goes: the templates'
one-time work, drawing the variants, writing the notebooks, and the manifest and key entries.

``--margin`` measures instead what one more student costs (issue 34), against its floor, in
one run: ``eulertop generate``'s whole call for ``--students`` and for ``--large`` (default
twice as many: on a shared machine a run's time varies by half a second, which over 150
students added is ±3 ms a student, over 450 ±1 ms), in
fresh processes and alternating, into a temporary folder on disk and in memory (tmpfs, where
there is one) in turn, beside what creating a file costs in each (the cost at the margin is
the difference of a round's two calls over the students added, median of the rounds, in wall
time with one worker process per core, and in CPU time of the call and its workers); and, in
this process, per student,
drawing every question one student at a time, drawing them in one pass (each family with a
batch form for all the students at once), each question drawn in one pass alone (where the
drawing goes, family by family), and writing the files of the students drawn (the floor, what
generating costs when drawing is free: their notebooks, and their manifest and key entries,
timed apart). Rounds alternate them; medians. ``--record FILE`` keeps every timing,
``--page FILE`` writes the text into that page's ``bench_generate`` block
(``docs/speed.md``).

Run from the repository root (or after ``pip install -e .``):
``PYTHONPATH=. python benchmarks/bench_generate.py [--students 300] [--questions 14]
[--runs 3] [--jobs N] [--breakdown]``
"""

from __future__ import annotations

import argparse
import contextlib
import json
import os
import platform
import statistics
import subprocess
import sys
import time
from pathlib import Path

TARGET_S = 5.0
ROOT = Path(__file__).resolve().parent.parent

sys.path.insert(0, str(Path(__file__).resolve().parent))
import speed_page  # noqa: E402  (a module beside this script)


def machine() -> str:
    """One line describing where the numbers were measured."""
    import numpy as np

    return (f"{platform.machine()} {platform.processor() or ''} {os.cpu_count()} cores, "
            f"Python {platform.python_version()}, numpy {np.__version__}, {platform.system()}")


def _cpu() -> float:
    """CPU seconds of this process and its finished children (the generator's workers)."""
    t = os.times()
    return t.user + t.system + t.children_user + t.children_system


def _setup(students: int, questions: int) -> tuple:
    from problems.roster import Roster
    from problems.templates import FAMILIES

    names = list(FAMILIES)
    problems = tuple((names * questions)[:questions])
    roster = Roster(columns=("id", "name"), rows=tuple(
        {"id": f"s{i:04d}", "name": f"Student {i}"} for i in range(students)))
    return FAMILIES, problems, roster


def child(students: int, questions: int, jobs: int | None, seed: int, out: str) -> None:
    """One timed run, in a fresh process: print its times as one JSON line."""
    imports = time.perf_counter()
    from problems.generate import generate_assignment

    families, problems, roster = _setup(students, questions)
    imports = time.perf_counter() - imports
    start, cpu = time.perf_counter(), _cpu()
    generate_assignment(roster, Path(out), families, problems=problems, seed=seed,
                        title="benchmark", jobs=jobs)
    print(json.dumps({"generate": time.perf_counter() - start, "cpu_generate": _cpu() - cpu,
                      "cpu": _cpu(), "imports": imports, "problems": problems}))


def breakdown(students: int, questions: int) -> dict[str, float]:
    """CPU seconds of each part of generation, in this process (no files written)."""
    from problems.generate import prepare_families, student_entries, student_variants
    from problems.notebook import notebook_texts

    families, problems, roster = _setup(students, questions)
    clock = time.process_time
    parts, start = {}, clock()
    prepare_families(families, problems)
    parts["one-time template work"], start = clock() - start, clock()
    drawn = [student_variants(families, problems, 0, row["id"]) for row in roster.rows]
    parts["drawing the variants"], start = clock() - start, clock()
    for row, variants in zip(roster.rows, drawn, strict=True):
        notebook_texts("benchmark", row, variants, families, validate=False)
    parts["building and encoding the notebooks"], start = clock() - start, clock()
    for variants in drawn:
        student_entries(variants, 0)
    parts["manifest and key entries"] = clock() - start
    return parts


def child_environment() -> dict[str, str]:
    """The environment of a run: this one, with this repository first on the path."""
    return {**os.environ, "PYTHONPATH": os.pathsep.join(
        p for p in (str(ROOT), os.environ.get("PYTHONPATH", "")) if p)}


def _timed_child(students: int, questions: int, jobs: int | None, seed: int,
                 where: str | None = None) -> dict:
    """One fresh process generating ``students`` (:func:`child`) into a temporary folder in
    ``where`` (default: the temporary folder's usual place): its JSON line."""
    import tempfile

    env = child_environment()
    with tempfile.TemporaryDirectory(dir=where) as folder:
        command = [sys.executable, str(Path(__file__).resolve()), "--child",
                   str(Path(folder) / "HW"), "--seed", str(seed), "--students", str(students),
                   "--questions", str(questions), *(["--jobs", str(jobs)] if jobs else [])]
        done = subprocess.run(command, env=env, capture_output=True, text=True, check=True)
    return json.loads(done.stdout.splitlines()[-1])


COLLECTOR = "paused"
"""How the parts of a ``--margin`` run are timed (its record's ``collector``): with Python's
cycle collector paused, as the generator's workers pause it for each batch
(:func:`problems.generate._collector_paused`); a record without it had the collector on."""


def margin_parts(students: int, questions: int, rounds: int) -> dict[str, list]:
    """In this process, per round: the CPU seconds per student of drawing one student at a
    time, drawing in one pass, and writing the files of the students drawn — each with the
    cycle collector paused, as a worker draws and writes (:data:`COLLECTOR`)."""
    import tempfile

    from problems.generate import (
        RELEASE,
        SOLUTIONS,
        Question,
        _collector_paused,
        _write_student,
        class_variants,
        prepare_families,
        student_entries,
        student_variants,
    )

    families, problems, roster = _setup(students, questions)
    prepare_families(families, problems)
    asked = [Question.of(p) for p in problems]
    ids = [row["id"] for row in roster.rows]
    drawn: list = []

    def one_at_a_time():
        drawn[:] = [student_variants(families, asked, 0, sid) for sid in ids]

    def one_pass():
        drawn[:] = class_variants(families, asked, 0, ids, {})

    def notebooks():  # as the generator writes them (its own function)
        with tempfile.TemporaryDirectory() as folder:
            for sub in (RELEASE, SOLUTIONS):
                (Path(folder) / sub).mkdir()
            for row, variants in zip(roster.rows, drawn, strict=True):
                _write_student(Path(folder), "benchmark", row, variants, False, families)

    def entries():
        for variants in drawn:
            student_entries(variants, 0)

    def question(k: int):
        return lambda: class_variants(families, [asked[k]], 0, ids, {})

    def paused(part):
        def run():
            with _collector_paused():
                part()
        return run

    one_pass()
    contenders = {"one at a time": one_at_a_time, "one pass": one_pass,
                  "notebooks": notebooks, "entries": entries}
    contenders |= {f"question {k + 1}": question(k) for k in range(len(asked))}
    times = speed_page.interleaved({k: paused(f) for k, f in contenders.items()}, rounds)
    return {name: [r["cpu"] / students for r in rows] for name, rows in times.items()}


def _places() -> dict[str, str]:
    """Where the classes are generated: ``disk``, the temporary folder's usual place; and
    ``memory``, ``/dev/shm`` where it is a RAM file system (Linux): creating a file on a
    virtual machine's disk can cost far more than everything else a student's notebook
    costs, so each figure is measured in both."""
    import tempfile

    places = {"disk": tempfile.gettempdir()}
    # no /proc/mounts (not Linux): no place in memory to measure
    with contextlib.suppress(OSError), open("/proc/mounts", encoding="utf-8") as mounts:
        if any(line.split()[1:3] == ["/dev/shm", "tmpfs"] for line in mounts):
            places["memory"] = "/dev/shm"
    return places


NOTEBOOK_BYTES = 47_000
"""About the size of a generated notebook of every built-in family (release 46.6 kB,
solutions 47.7 kB on average): what :func:`file_creation` writes into each file."""


def file_creation(places: dict[str, str], rounds: int, count: int = 300) -> dict[str, list]:
    """Per place, per round: the CPU and wall seconds of creating one file of
    :data:`NOTEBOOK_BYTES` (``count`` of them in a fresh folder, as a class's notebooks are
    written), the places taking turns."""
    import shutil
    import tempfile

    from problems.generate import _write_bytes  # as the generator writes a notebook

    data = b"x" * NOTEBOOK_BYTES
    found: dict[str, list] = {place: [] for place in places}
    for r in range(rounds):
        for place in places if r % 2 == 0 else list(places)[::-1]:
            folder = tempfile.mkdtemp(dir=places[place])
            try:
                cpu, wall = time.process_time(), time.perf_counter()
                for i in range(count):
                    _write_bytes(Path(folder) / f"s{i:04d}.ipynb", data)
                found[place].append({"cpu": (time.process_time() - cpu) / count,
                                     "wall": (time.perf_counter() - wall) / count})
            finally:
                shutil.rmtree(folder)
    return found


def measure_margin(students: int, questions: int, jobs: int | None, rounds: int,
                   command: str, large: int | None = None) -> dict:
    """Every timing of a ``--margin`` run, as its record holds them (the classes: ``students``
    and ``large``, default twice as many)."""
    large = large or 2 * students
    record = {"bench": "bench_generate", "command": command, "date": speed_page.now(),
              "machine": speed_page.machine(), "students": [students, large],
              "questions": questions, "jobs": jobs, "rounds": rounds}
    places = _places()
    record["places"] = places
    runs = {place: {students: [], large: []} for place in places}
    for r in range(rounds):
        for place in places if r % 2 == 0 else list(places)[::-1]:
            for n in (students, large) if r % 2 == 0 else (large, students):
                runs[place][n].append(_timed_child(n, questions, jobs, r, places[place]))
    for key in ("generate", "cpu_generate"):
        record[key] = {place: {str(n): [x[key] for x in found] for n, found in sizes.items()}
                       for place, sizes in runs.items()}
    record["file_creation"] = file_creation(places, rounds)
    from problems.templates import FAMILIES

    record["problems"] = [[name, FAMILIES[name].batched]
                          for name in _setup(students, questions)[1]]
    record["per_student_cpu"] = margin_parts(students, questions, rounds)
    record["collector"] = COLLECTOR
    record["load_after"] = [round(x, 2) for x in os.getloadavg()]
    return record


def _margin(record: dict, key: str, place: str) -> tuple[float, float, float]:
    """Medians of the call for the small and the large class generated in ``place``, and the
    median over the rounds of their difference per student added: each round's two calls run
    one after the other, so a change of the shared machine's speed between rounds (a third
    and more within minutes) falls on both of a difference."""
    small, large = record["students"]
    t_small, t_large = record[key][place][str(small)], record[key][place][str(large)]
    differences = [(b - a) / (large - small) for a, b in zip(t_small, t_large, strict=True)]
    return statistics.median(t_small), statistics.median(t_large), statistics.median(differences)


_PLACES = {"disk": "on disk", "memory": "in memory, tmpfs"}


def render_margin(record: dict) -> list[str]:
    """The page's text, from the record alone."""
    small, large = record["students"]
    places = record["places"]
    parts = {k: statistics.median(v) for k, v in record["per_student_cpu"].items()}
    files = parts["notebooks"] + parts["entries"]
    ms = speed_page.seconds
    rows = []
    for place, folder in places.items():
        t_small, t_large, margin = _margin(record, "generate", place)
        cpu = _margin(record, "cpu_generate", place)[2]
        created = record["file_creation"][place]
        rows.append(f"| {_PLACES[place]} (`{folder}`) | {ms(t_small)} | {ms(t_large)} | "
                    f"**{ms(margin)}** | {ms(cpu)} | {ms(speed_page.median(created, 'cpu'))} |")
    return [
        speed_page.header(record),
        "",
        f"`eulertop generate` of {small} and of {large} students × {record['questions']} "
        f"questions (every built-in family), one worker process per core, each run a fresh "
        f"process, {record['rounds']} of each alternating, into a temporary folder "
        f"{' and '.join(f'{_PLACES[p]}' for p in places)} (taking turns). One more student "
        "costs the difference of the two calls of a round over the students added (median "
        "of the rounds), in wall time "
        "(the target: at most 3 ms) and in CPU time of the call and its worker processes. "
        "Beside it, in the same rounds, what creating one file of a notebook's size costs "
        "there (CPU time, median; a student has two):",
        "",
        f"| written to | {small} students | {large} students | one more student | "
        "its CPU | creating a file |",
        "|---|---|---|---|---|---|",
        *rows,
        "",
        "Per student, in one process (CPU time, medians of the same rounds, files on disk"
        + (", Python's cycle collector paused as the generator's workers pause it):"
           if record.get("collector") == COLLECTOR else "):"),
        "",
        "| per student, all questions | CPU |",
        "|---|---|",
        f"| drawing them one student at a time (every family, as before batch forms) | "
        f"{ms(parts['one at a time'])} |",
        f"| drawing them in one pass (families with a batch form: all students at once) | "
        f"{ms(parts['one pass'])} |",
        f"| writing the files of the students drawn — the floor | {ms(files)} |",
        f"| of which their notebooks (built, encoded, written) | {ms(parts['notebooks'])} |",
        f"| of which their manifest and key entries (encoded) | {ms(parts['entries'])} |",
        "",
        f"Drawing in one pass is {parts['one at a time'] / parts['one pass']:.2f}× drawing "
        f"one at a time; drawing and writing together are "
        f"{(parts['one pass'] + files) / files:.2f}× the floor. Where the drawing goes, "
        "each question drawn in one pass alone, per student (CPU time, medians of the same "
        "rounds), the costliest first:",
        "",
        "| question | family | batch form | CPU per student |",
        "|---|---|---|---|",
        *(f"| {k} | `{name}` | {'yes' if batched else 'no'} | "
          f"{ms(parts[f'question {k}'])} |" for k, (name, batched) in sorted(
              enumerate(record["problems"], start=1),
              key=lambda q: -parts[f"question {q[0]}"])),
    ]


def margin_main(args: argparse.Namespace) -> int:
    speed_page.check_page(args.page, "bench_generate")
    command = " ".join(["python benchmarks/bench_generate.py", *sys.argv[1:]])
    record = measure_margin(args.students, args.questions, args.jobs, args.runs, command,
                            args.large)
    if args.record:
        speed_page.write_record(args.record, record)
    lines = render_margin(record)
    if args.page:
        speed_page.write_block(args.page, "bench_generate", lines)
    print("\n".join(lines))
    return 0


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--students", type=int, default=300)
    parser.add_argument("--questions", type=int, default=14)
    parser.add_argument("--jobs", type=int, default=None,
                        help="worker processes (default: one per core)")
    parser.add_argument("--runs", type=int, default=3)
    parser.add_argument("--large", type=int, default=None,
                        help="with --margin: the larger class (default twice --students); the "
                        "more students apart, the less a run's noise weighs on each")
    parser.add_argument("--no-cache", action="store_true",
                        help="derive the symbolic keys in every run (EULERTOP_CACHE_DIR=off)")
    parser.add_argument("--breakdown", action="store_true",
                        help="also say where the CPU goes (one more pass, in one process)")
    parser.add_argument("--margin", action="store_true",
                        help="what one more student costs, against the floor (issue 34)")
    parser.add_argument("--record", type=Path, help="with --margin: every timing, as JSON")
    parser.add_argument("--page", type=Path, help="with --margin: write the text into this "
                        "page's bench_generate block (docs/speed.md)")
    parser.add_argument("--child", metavar="OUT", help=argparse.SUPPRESS)
    parser.add_argument("--seed", type=int, default=0, help=argparse.SUPPRESS)
    args = parser.parse_args(argv)
    if args.no_cache:  # the runs, fresh processes, inherit it
        os.environ["EULERTOP_CACHE_DIR"] = "off"
    if args.child:
        child(args.students, args.questions, args.jobs, args.seed, args.child)
        return 0
    if args.margin:
        return margin_main(args)
    from problems.templates import FAMILIES

    if not FAMILIES:
        print("bench_generate: no problem families are registered "
              "(problems.templates.CATALOGUE is empty): nothing to measure", file=sys.stderr)
        return 1

    import tempfile

    load_before = os.getloadavg()[0]
    env = child_environment()
    runs = []
    for run in range(args.runs):
        with tempfile.TemporaryDirectory() as folder:
            command = [sys.executable, str(Path(__file__).resolve()), "--child",
                       str(Path(folder) / "HW"), "--seed", str(run), "--students",
                       str(args.students), "--questions", str(args.questions)]
            if args.jobs is not None:
                command += ["--jobs", str(args.jobs)]
            start = time.perf_counter()
            done = subprocess.run(command, env=env, capture_output=True, text=True, check=True)
            result = json.loads(done.stdout.splitlines()[-1])
            result["whole"] = time.perf_counter() - start
            runs.append(result)

    def median(key: str) -> float:
        return statistics.median(r[key] for r in runs)

    generate = [r["generate"] for r in runs]
    jobs = args.jobs or (len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity")
                         else os.cpu_count())
    print(f"machine: {machine()}; load average {load_before:.1f} before, "
          f"{os.getloadavg()[0]:.1f} after")
    print(f"problems: {', '.join(runs[0]['problems'])}")
    verdict = ""
    if (args.students, args.questions) == (300, 14):  # the class size the target is set for
        verdict = (f"; target < {TARGET_S:.0f} s: "
                   f"{'met' if median('generate') < TARGET_S else 'MISSED'}")
    print(f"generate {args.students} students × {args.questions} questions, jobs {jobs}, "
          f"a fresh process per run: median {median('generate'):.2f} s over {args.runs} runs "
          f"(min {min(generate):.2f}, max {max(generate):.2f}){verdict}")
    print(f"whole process (start-up, imports {median('imports'):.2f} s, generate): median "
          f"{median('whole'):.2f} s")
    print(f"CPU (user + system, the process and its workers): median {median('cpu'):.2f} s per "
          f"run, of which generate {median('cpu_generate'):.2f} s")
    if args.breakdown:
        parts = breakdown(args.students, args.questions)
        print("where the CPU goes (one process, CPU s): " + "; ".join(
            f"{name} {seconds:.2f}" for name, seconds in parts.items()))
    return 0


if __name__ == "__main__":
    sys.exit(main())
