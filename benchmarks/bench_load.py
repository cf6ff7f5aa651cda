"""Load test of ``eulertop grade`` in its sandbox (issue 5): many submissions, some hostile.

Makes an assignment for ``--students`` (200) students; every tenth submission is adversarial
(:data:`ATTACKS`, from the battery of ``tests/grader/test_sandbox.py``: a fork bomb, 50 GB of
memory, filling the disk, a process left behind, sleeping past the time limit with interrupts
ignored, reading the key, the network, signalling every visible process), the others are the
students' solutions notebooks. Then runs ``eulertop grade --jobs J --timeout T`` as a fresh
process, sampling every 0.1 s the resident memory (RSS) of the grader and all its descendants
from ``/proc``, and reports:

* wall time, and notebooks per minute;
* peak memory: resident set (RSS) of the grader alone, and of the grader with every process
  below it (zygotes, kernels, bubblewrap) as the sum of their proportional set sizes (PSS:
  the pages forked kernels share with their zygote counted once, not once per kernel);
* whether every honest submission got full marks, and every attacker's status;
* what was left behind: processes carrying the run's marker (the run folder's name, on every
  sandboxed process's command line) and the run folder itself — both must be none.

Run from the repository root: ``PYTHONPATH=. python benchmarks/bench_load.py [--students 200]
[--jobs 2] [--timeout 20]``. ``tests/grader/test_faults.py`` runs a small version
(:func:`run_load` with 20 students).
"""

from __future__ import annotations

import argparse
import json
import os
import re
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]

ATTACKS = {
    "fork_bomb": "import os, time\nfor _ in range(5000):\n    if os.fork() == 0:\n"
                 "        time.sleep(60)\n        os._exit(0)",
    "memory": "import numpy as np\nblock = np.ones(50 * 1024**3, dtype=np.uint8)",
    "fill_disk": "with open('big', 'wb') as f:\n    for _ in range(4096):\n"
                 "        f.write(b'x' * 2**20)",
    "orphan": "import subprocess, sys\nsubprocess.Popen([sys.executable, '-c', "
              "'import time; time.sleep(600)'], start_new_session=True)",
    "sleeper": "import signal, time\nsignal.signal(signal.SIGINT, signal.SIG_IGN)\n"
               "time.sleep(10**6)",
    "read_key": "import os\nstolen = []\nfor top, dirs, files in os.walk('/'):\n"
                "    dirs[:] = [d for d in dirs if top != '/' or d not in ('proc', 'sys')]\n"
                "    stolen += [os.path.join(top, f) for f in files if f == 'key.json']\n"
                "assert not stolen, stolen",
    "network": "import socket\nsocket.create_connection(('1.1.1.1', 53), timeout=2)",
    "signal_all": "import os, signal\nfor p in os.listdir('/proc'):\n    if p.isdigit() and "
                  "int(p) != os.getpid():\n        try:\n            os.kill(int(p), 9)\n"
                  "        except OSError:\n            pass",
}
"""Attack name -> one cell's source, inserted before the answer cells."""

KEEP_ATTACKS = ("fork_bomb", "orphan", "read_key", "signal_all")
"""Attacks of the quick version (no sleeper: it would hold a slot for the whole time limit)."""


def make_class(root: Path, students: int, attacks=tuple(ATTACKS)) -> tuple[Path, Path, dict]:
    """An assignment and submissions; ``{student id: attack name or None}``."""
    from problems.generate import generate_assignment
    from problems.roster import Roster
    from problems.templates import FAMILIES

    ids = [f"s{i:03d}" for i in range(students)]
    hw, subs = root / "HW", root / "subs"
    generate_assignment(Roster(("id",), tuple({"id": s} for s in ids)), hw, FAMILIES,
                        problems=["inertia_tensor"], seed=11)
    subs.mkdir()
    plan = {}
    for i, sid in enumerate(ids):
        nb = json.loads((hw / "solutions" / f"{sid}.ipynb").read_text())
        attack = attacks[(i // 10) % len(attacks)] if i % 10 == 9 else None
        if attack:
            nb["cells"].insert(1, {"cell_type": "code", "id": "attack", "metadata": {},
                                   "outputs": [], "execution_count": None,
                                   "source": ATTACKS[attack]})
        (subs / f"{sid}.ipynb").write_text(json.dumps(nb))
        plan[sid] = attack
    return hw, subs, plan


def _tree(pid: int) -> list[int]:
    """``pid`` and all its descendants (from ``/proc/<pid>/task/*/children``)."""
    out, todo = [], [pid]
    while todo:
        p = todo.pop()
        out.append(p)
        try:
            for task in os.listdir(f"/proc/{p}/task"):
                todo += map(int, Path(f"/proc/{p}/task/{task}/children").read_text().split())
        except OSError:
            pass
    return out


def _memory(pid: int, field: str = "Pss:") -> int:
    """Bytes of ``pid``'s memory: proportional set size (shared pages — a forked kernel's
    copy-on-write modules — counted once across the processes sharing them), or ``VmRSS:``."""
    source = "smaps_rollup" if field == "Pss:" else "status"
    try:
        for line in Path(f"/proc/{pid}/{source}").read_text().splitlines():
            if line.startswith(field):
                return int(line.split()[1]) * 1024
    except OSError:
        pass
    return 0


def marked(marker: str) -> list[int]:
    """Live processes whose command line or environment holds ``marker``."""
    found = []
    for pid in filter(str.isdigit, os.listdir("/proc")):
        for part in ("cmdline", "environ"):
            try:
                if marker.encode() in Path(f"/proc/{pid}/{part}").read_bytes():
                    found.append(int(pid))
                    break
            except OSError:
                pass
    return found


def run_load(root: Path, students: int = 200, jobs: int = 2, timeout: float = 20.0,
             attacks=tuple(ATTACKS)) -> dict:
    """Grade a class of ``students`` (a tenth adversarial) in ``root``; the measurements."""
    hw, subs, plan = make_class(root, students, attacks)
    tmp = root / "tmp"
    tmp.mkdir()
    env = {**os.environ, "TMPDIR": str(tmp), "PYTHONPATH": str(ROOT)}
    start = time.monotonic()
    proc = subprocess.Popen([sys.executable, "-m", "eulertop", "grade", str(hw), str(subs),
                             "--jobs", str(jobs), "--timeout", str(timeout)],
                            cwd=ROOT, env=env, stdout=subprocess.DEVNULL,
                            stderr=subprocess.PIPE, text=True)
    peak_tree = peak_grader = 0
    marker = f"eulertop-{proc.pid}-"
    while proc.poll() is None:
        pids = _tree(proc.pid)
        peak_tree = max(peak_tree, sum(_memory(p) for p in pids))
        peak_grader = max(peak_grader, _memory(proc.pid, "VmRSS:"))
        time.sleep(0.1)
    wall = time.monotonic() - start
    stderr = proc.stderr.read()
    proc.stderr.close()
    time.sleep(0.2)
    results = {sid: json.loads((hw / "graded" / "results" / f"{sid}.json").read_text())
               for sid in plan}
    honest = [sid for sid, a in plan.items() if a is None]
    wrong = [sid for sid in honest if results[sid]["status"] != "graded"
             or results[sid]["points"] != results[sid]["max_points"]]
    return {
        "students": students, "jobs": jobs, "exit": proc.returncode, "wall": wall,
        "per_minute": 60 * students / wall, "peak_rss_tree": peak_tree,
        "peak_rss_grader": peak_grader, "honest": len(honest), "honest_wrong": wrong,
        "attackers": {sid: (a, results[sid]["status"], results[sid]["points"])
                      for sid, a in plan.items() if a},
        "left_processes": marked(marker),
        "left_folders": [p.name for p in tmp.iterdir() if re.match(r"eulertop-\d+-", p.name)],
        "sandboxed": all(r["sandboxed"] for r in results.values()),
        "stderr": stderr,
    }


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--students", type=int, default=200)
    parser.add_argument("--jobs", type=int, default=2)
    parser.add_argument("--timeout", type=float, default=20.0)
    args = parser.parse_args(argv)
    root = Path(tempfile.mkdtemp(prefix="bench-load-"))
    try:
        r = run_load(root, args.students, args.jobs, args.timeout)
    finally:
        shutil.rmtree(root, ignore_errors=True)
    mib = 1024**2
    print(f"{r['students']} submissions ({len(r['attackers'])} adversarial), --jobs {r['jobs']},"
          f" --timeout {args.timeout:g}: exit status {r['exit']}")
    print(f"wall time {r['wall']:.1f} s ({r['per_minute']:.0f} notebooks/min); peak memory: "
          f"grader {r['peak_rss_grader'] / mib:.0f} MiB (RSS), grader + all its processes "
          f"{r['peak_rss_tree'] / mib:.0f} MiB (sum of PSS)")
    print(f"honest submissions graded with full marks: {r['honest'] - len(r['honest_wrong'])}"
          f" of {r['honest']}; all sandboxed: {r['sandboxed']}")
    for sid, (attack, status, points) in sorted(r["attackers"].items()):
        print(f"  {sid} {attack:<11} {status:<7} {points:g} points")
    print(f"left behind: {len(r['left_processes'])} processes, "
          f"{len(r['left_folders'])} run folders")
    ok = not r["honest_wrong"] and not r["left_processes"] and not r["left_folders"]
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
