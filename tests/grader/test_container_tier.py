"""Issue 30: the container tier never gives one uid to two kernels of a run, nor one in use
here — and two of its kernels alive at once can neither signal nor read each other.

The uids come from a range of the tests' own, far above any account (as
``tests/grader/hosted/conftest.py``'s ``kernel_uid``). What is measured: the uid each kernel's
process is launched as (``launch_options``: what ``Popen`` is given), the record of a
submission whose kernel could get none, and — with real kernels, run as root in a container
layout — what an attack of one kernel on the other did: the victim alive to the end, its file
unread, its folder unlisted; the same attack between two kernels sharing a uid (the old flaw)
is the control that shows the measure can see the harm.
"""

from __future__ import annotations

import hashlib
import json
import os
import secrets
import shutil
import subprocess
import sys
import tempfile
import threading
from concurrent.futures import ThreadPoolExecutor
from functools import partial
from pathlib import Path

import pytest
from nbformat.v4 import new_code_cell, new_notebook

from grader.execute import execute_submission
from grader.grade_one import RETRIES, grade_one
from grader.kernels.container import ContainerTier, NoFreeUid, RunUids
from grader.limits import Limits
from grader.submissions import Submission

ROOT = Path(__file__).resolve().parents[2]
TESTS_UIDS = 0x5E000000, 0x100000
"""The tests' own uids ``(first, count)``: no account, nothing of this machine's."""


@pytest.fixture(scope="module", autouse=True)
def _as_root():
    if os.geteuid() != 0:
        pytest.fail("these tests run as root (CI does): only root has other uids to give",
                    pytrace=False)


def uid_range(count: int) -> int:
    """The first uid of ``count`` fresh ones of :data:`TESTS_UIDS`."""
    first, span = TESTS_UIDS
    return first + secrets.randbelow(span - count)


def launched_as(kernel) -> int:
    """The uid ``kernel``'s process is started as."""
    options = kernel.launch_options()
    assert options["group"] == options["user"] and options["extra_groups"] == []
    return options["user"]


def test_kernels_made_from_many_threads_get_every_uid_once(tmp_path):
    """64 kernels of one run, asked for by 16 threads at once, over a range of 64 uids: each
    uid of the range exactly once; the 65th kernel gets none (the old random draw repeated
    uids: 64 draws from 64 all distinct has probability 64!/64^64 ≈ 3e-27)."""
    first = uid_range(64)
    factory = ContainerTier(RunUids(first, 64), "tests").kernel_factory()
    start = threading.Barrier(16)

    def make(_: int) -> list[int]:
        start.wait()
        return [launched_as(factory(tmp_path, tmp_path, Limits())) for _ in range(4)]

    with ThreadPoolExecutor(16) as pool:
        uids = [uid for batch in pool.map(make, range(16)) for uid in batch]
    assert sorted(uids) == list(range(first, first + 64))
    with pytest.raises(NoFreeUid, match="64 went to this run's kernels and 0 were in use"):
        factory(tmp_path, tmp_path, Limits())


def _notebook(folder: Path) -> Path:
    path = folder / "ada.ipynb"
    path.write_text(json.dumps(new_notebook(cells=[new_code_cell("x = 1")])), encoding="utf-8")
    return path


def test_with_three_uids_the_fourth_kernel_fails_to_start_as_the_graders_fault(tmp_path):
    """Three kernels take the three uids; the fourth submission's kernel cannot start: it is
    tried again (``RETRIES`` times, as every start that fails through no fault of the
    student's), then recorded failed with ``retry`` (graded again by the next run), the reason
    naming the range — never run as a uid another kernel has."""
    first = uid_range(3)
    factory = ContainerTier(RunUids(first, 3), "tests").kernel_factory()
    uids = [launched_as(factory(tmp_path, tmp_path, Limits())) for _ in range(3)]
    assert sorted(uids) == [first, first + 1, first + 2]
    asked = []

    def counted(*args):
        asked.append(args)
        return factory(*args)

    execute = partial(execute_submission, kernel_factory=counted)
    result = grade_one(Submission("ada", _notebook(tmp_path)), [], "key", Limits(), execute)
    assert len(asked) == 1 + RETRIES
    assert result.status == "failed" and result.execution == {"retry": True}
    assert "the grader could not run this notebook (NoFreeUid: no uid left" in result.message
    assert f"of the 3 uids {first}…{first + 2}, 3 went to this run's kernels" in result.message


@pytest.fixture
def shared_folder():
    """A world-writable (sticky) folder in ``/tmp``, where any kernel could leave files."""
    folder = Path(tempfile.mkdtemp(prefix="eulertop-shared-", dir="/tmp"))
    folder.chmod(0o1777)
    yield folder
    shutil.rmtree(folder, ignore_errors=True)


def test_a_uid_that_owns_a_process_or_a_file_here_is_not_given(shared_folder):
    """Of three uids, one owns a file in a world-writable folder of ``/tmp`` and one runs a
    process (another run's kernels, say): the run gets the third, then none."""
    first = uid_range(3)
    planted = shared_folder / "left-behind"
    planted.write_text("")
    os.chown(planted, first, first)
    sleeper = subprocess.Popen(["sleep", "60"], user=first + 1, group=first + 1,
                               extra_groups=[])
    try:
        uids = RunUids(first, 3)
        assert uids.take().uid == first + 2
        with pytest.raises(NoFreeUid, match="1 went to this run's kernels and 2 were in use"):
            uids.take()
    finally:
        sleeper.kill()
        sleeper.wait()


@pytest.fixture
def drop():
    """Where the two kernels of :mod:`tests.grader.container_pair` leave what they saw: a
    world-writable folder in a folder of ``/tmp`` that is not (so the kernels' clean-up,
    which removes what their uid left in the world-writable folders of ``/tmp``, keeps it)."""
    base = Path(tempfile.mkdtemp(prefix="eulertop-pair-", dir="/tmp"))
    base.chmod(0o755)
    (base / "drop").mkdir(mode=0o1777)
    (base / "drop").chmod(0o1777)
    yield base / "drop"
    shutil.rmtree(base, ignore_errors=True)


def run_pair(drop: Path, first: int, count: int, mode: str) -> dict:
    """:mod:`tests.grader.container_pair` as root in a container layout; its report, and
    what the two kernels left in ``drop``."""
    from tests.grader.hosted.conftest import container_layout

    layout = container_layout()
    assert layout is not None, "bubblewrap could not lay out a container's file system"
    done = subprocess.run([*layout, sys.executable, "-m", "tests.grader.container_pair",
                           str(drop), str(first), str(count), mode], cwd=ROOT,
                          capture_output=True, text=True, timeout=400)
    assert done.returncode == 0, done.stderr[-3000:]
    got = json.loads(done.stdout.splitlines()[-1])
    for name in ("victim.json", "attack.json", "kill.txt"):
        path = drop / name
        got[name] = path.read_text() if path.exists() else None
    return got


def test_two_kernels_of_a_run_cannot_signal_or_read_each_other(drop):
    """A range of two uids: the two kernels alive at once get both (the old random draw gave
    them one uid half the time). The attacker's read of the victim's file and listing of its
    folder are refused, its ``SIGKILL`` too; the victim lives to see the attack end."""
    first = uid_range(2)
    got = run_pair(drop, first, 2, "tier")
    victim, attacker = got["victim"], got["attacker"]
    assert victim["status"] == "ok", victim["message"]
    assert attacker["status"] == "ok", attacker["message"]
    assert {victim["answers"]["my_uid"], attacker["answers"]["my_uid"]} == {first, first + 1}
    assert victim["answers"]["survived_attack"] is True
    attack = json.loads(got["attack.json"])
    assert attack == {"uid": attacker["answers"]["my_uid"], "read": "PermissionError",
                      "listing": "PermissionError"}
    assert got["kill.txt"] == "PermissionError"


def test_control_two_kernels_sharing_a_uid_kill_and_read_each_other(drop):
    """The same two notebooks, both kernels as one uid (the flaw the tier no longer has): the
    attacker reads the victim's secret (its SHA-256 is the one the victim published) and lists
    its folder, and the victim does not live to see the attack end."""
    first = uid_range(1)
    got = run_pair(drop, first, 1, "shared")
    attack, published = json.loads(got["attack.json"]), json.loads(got["victim.json"])
    assert hashlib.sha256(attack["read"].encode()).hexdigest() == published["sha256"]
    assert "secret.txt" in attack["listing"]
    assert got["victim"]["status"] != "ok"
    assert "survived_attack" not in got["victim"]["answers"]
