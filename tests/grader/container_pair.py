"""Two kernels of one container-tier run, alive at the same time (issue 30): the *victim*
keeps a secret in a file of its private working folder and waits; the *attacker*, told the
victim's pid, folder and file (the strongest position: it needs to find nothing), tries to read
the file, to list the folder, and to kill the victim's kernel. Both are real notebooks run by
:func:`grader.execute.execute_submission` from two threads, as ``eulertop grade --jobs 2``
runs them.

Run as a program, as root, in a container layout
(:func:`tests.grader.hosted.conftest.container_layout`: other uids must be able to run this
Python), by ``tests/grader/test_container_tier.py``::

    python -m tests.grader.container_pair DROP FIRST COUNT MODE

``DROP`` is a folder every user may write to, where the two leave what they saw: the victim
``victim.json`` (its pid, uid, folder, file and the SHA-256 of its secret — never the secret),
the attacker ``attack.json`` (what each attempt gave) and ``kill.txt``. ``MODE`` ``tier``: both
kernels from one :class:`grader.kernels.container.ContainerTier`'s factory over the uids
``[FIRST, FIRST + COUNT)``; ``shared``: both as uid ``FIRST`` (the flaw of issue 30, as a
control: the same attack then does its harm). Prints each kernel's status, answers and message
as one JSON object.
"""

from __future__ import annotations

import json
import sys
import tempfile
import threading
from functools import partial
from pathlib import Path

from nbformat.v4 import new_code_cell, new_notebook

from grader.execute import execute_submission
from grader.kernels.container import ContainerTier, KernelUser, RunUids, kernel_factory
from grader.limits import Limits

WAIT = 90
"""Seconds either kernel waits for the other before it gives up."""

VICTIM = """
import hashlib, json, os, pathlib, secrets, time
drop = pathlib.Path({drop!r})
secret = secrets.token_hex(16)
pathlib.Path("secret.txt").write_text(secret)
note = {{"pid": os.getpid(), "uid": os.getuid(), "folder": os.getcwd(),
         "file": os.path.abspath("secret.txt"),
         "sha256": hashlib.sha256(secret.encode()).hexdigest()}}
(drop / "victim.part").write_text(json.dumps(note))
os.replace(drop / "victim.part", drop / "victim.json")
deadline = time.monotonic() + {wait}
while not (drop / "attacked").exists() and time.monotonic() < deadline:
    time.sleep(0.05)
survived_attack = (drop / "attacked").exists()
my_uid = os.getuid()
"""

ATTACKER = """
import json, os, pathlib, signal, time
drop = pathlib.Path({drop!r})
deadline = time.monotonic() + {wait}
while not (drop / "victim.json").exists() and time.monotonic() < deadline:
    time.sleep(0.05)
victim = json.loads((drop / "victim.json").read_text())

def attempt(action):
    try:
        return action()
    except Exception as err:
        return type(err).__name__

report = {{"uid": os.getuid(),
           "read": attempt(lambda: open(victim["file"]).read()),
           "listing": attempt(lambda: sorted(os.listdir(victim["folder"])))}}
(drop / "attack.part").write_text(json.dumps(report))
os.replace(drop / "attack.part", drop / "attack.json")
kill = attempt(lambda: os.kill(victim["pid"], signal.SIGKILL) or "sent")
(drop / "kill.txt").write_text(kill)
time.sleep(1)  # a victim that was killed is dead before it could see the mark
(drop / "attacked").touch()
my_uid = os.getuid()
"""

ANSWERS = {"victim": ("survived_attack", "my_uid"), "attacker": ("my_uid",)}


def notebooks(folder: Path, drop: Path) -> dict[str, Path]:
    """The two notebooks, written to ``folder`` (the grader's own: no kernel reads them)."""
    paths = {}
    for name, source in (("victim", VICTIM), ("attacker", ATTACKER)):
        nb = new_notebook(cells=[new_code_cell(source.format(drop=str(drop), wait=WAIT))])
        paths[name] = folder / f"{name}.ipynb"
        paths[name].write_text(json.dumps(nb), encoding="utf-8")
    return paths


def run_pair(drop: Path, first: int, count: int, mode: str) -> dict[str, dict]:
    """Both notebooks at once, each from its own thread; what each execution gave."""
    factory = (ContainerTier(RunUids(first, count), "tests").kernel_factory() if mode == "tier"
               else kernel_factory(KernelUser(first, first, f"uid {first}")))
    limits = Limits(cell_timeout=WAIT + 30, total_timeout=WAIT + 60)
    run = partial(execute_submission, limits=limits, kernel_factory=factory)
    got: dict[str, dict] = {}
    with tempfile.TemporaryDirectory() as private:
        paths = notebooks(Path(private), drop)

        def one(name: str) -> None:
            done = run(paths[name], ANSWERS[name])
            got[name] = {"status": done.status, "answers": done.answers,
                         "message": done.message}

        threads = [threading.Thread(target=one, args=(name,)) for name in paths]
        for thread in threads:
            thread.start()
        for thread in threads:
            thread.join()
    return got


if __name__ == "__main__":
    drop, first, count, mode = sys.argv[1:5]
    print(json.dumps(run_pair(Path(drop), int(first), int(count), mode)))
