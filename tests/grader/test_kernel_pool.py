"""Warm kernels forked from a zygote (grader/kernels/pool.py, grader/kernels/zygote.py).

References: the operating system's own account of each kernel — its pid, session, resource
limits, ``prctl`` flags, environment, descriptors and working folder, read *inside* the kernel
by the submission and extracted as answers — and ``/proc`` from outside for processes and
folders left behind. Nothing here is compared with a value the pool computed.

One pool (one slot, the default modules: a zygote start ≈ 1 s) is shared by the module; the
tests that break or kill zygotes make their own, importing only IPython (``LIGHT``).
"""

from __future__ import annotations

import json
import math
import os
import signal
import subprocess
import sys
import textwrap
import time
from pathlib import Path

import nbformat
import pytest
from nbformat.v4 import new_code_cell, new_notebook

from grader.execute import execute_submission
from grader.kernels import pool as kernel_pool
from grader.kernels.base import kernel_environment
from grader.kernels.local import LocalKernel
from grader.kernels.pool import FILE_BYTES, KernelPool, PooledKernel, fork_available
from grader.limits import Limits
from tests.grader.golden import CANARY


@pytest.fixture(scope="module", autouse=True)
def _required_here():
    """Fail, never skip: a missing sandbox must not pass silently (CI installs bubblewrap).
    Module-scoped, so it runs before the module's other fixtures start any kernel."""
    if not fork_available():
        pytest.fail("warm kernels need Linux fork", pytrace=False)

ROOT = Path(__file__).resolve().parents[2]
LIMITS = Limits(cell_timeout=1.0, total_timeout=20.0, memory_bytes=3 * 1024**3 // 2)
LIGHT = ()  # zygotes of the tests that kill them: IPython only, a faster start


def gone(pid: int, timeout: float = 5.0) -> bool:
    """True once no process ``pid`` exists (or it is a zombie nobody has reaped yet)."""
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        try:
            state = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[0]
        except OSError:
            return True
        if state in ("Z", "X"):
            return True
        time.sleep(0.02)
    return False


def settled(pool):
    """``pool`` once the kernel its slots fork ahead, in a thread of their own, is forked."""
    for slot in pool.slots:
        slot._settle()
    return pool


@pytest.fixture(scope="module")
def pool():
    os.environ[CANARY] = "canary-in-the-grader"  # set before the zygote starts
    try:
        with KernelPool(1) as warm:
            yield warm
    finally:
        del os.environ[CANARY]


@pytest.fixture
def run(pool, tmp_path):
    """``run(*cells, variables=..., using=pool) -> Execution`` of a one-off notebook."""
    def execute(*cells: str, variables, limits=LIMITS, using=None):
        path = tmp_path / f"n{len(list(tmp_path.iterdir()))}" / "alice.ipynb"
        path.parent.mkdir()
        nbformat.write(new_notebook(cells=[new_code_cell(c) for c in cells]), path)
        return execute_submission(path, variables, limits,
                                  kernel_factory=(using or pool).kernel)
    return execute


def test_every_submission_gets_a_fresh_process_with_fresh_state(pool, run):
    forks, ahead = settled(pool).forks, pool.slots[0].waiting is not None
    first = run("import os, sys, numpy\n"
                "preloaded = all(m in sys.modules for m in ('numpy', 'scipy', 'sympy'))\n"
                "pid = os.getpid()\nsecret = 'alice was here'\nnumpy.pi = 3\n"
                "sys.modules['planted'] = sys",
                variables=("pid", "preloaded", "secret"))
    second = run("import os, sys, numpy\npid = os.getpid()\n"
                 "seen = ['secret' in globals(), numpy.pi, 'planted' in sys.modules]",
                 variables=("pid", "seen"))
    assert first.status == second.status == "ok", (first.message, second.message)
    assert first.answers["preloaded"] is True  # imported before the submission ran: warm
    assert first.answers["secret"] == "alice was here"
    assert second.answers["seen"] == [False, math.pi, False]  # nothing of alice's run
    assert first.answers["pid"] != second.answers["pid"]
    assert gone(first.answers["pid"]) and gone(second.answers["pid"])
    # one fork per submission; each forks the next one ahead (prewarm), which the next takes
    assert settled(pool).forks - forks == 2 + (not ahead)
    assert pool.slots[0].waiting is not None


def test_what_the_zygote_imported_is_frozen_out_of_the_kernels_collections(run):
    """A collection in a kernel would write to every object the zygote imported (copying
    each page of them into the kernel); they are frozen, and the kernel still collects its
    own garbage (a reference cycle made by the submission is freed)."""
    done = run("import gc, weakref\n"
               "frozen = gc.get_freeze_count()\n"
               "enabled = gc.isenabled()\n"
               "class Node: pass\n"
               "a, b = Node(), Node()\n"
               "a.other, b.other = b, a\n"
               "alive = weakref.ref(a)\n"
               "del a, b\n"
               "gc.collect()\n"
               "freed = alive() is None",
               variables=("frozen", "enabled", "freed"))
    assert done.status == "ok", done.message
    assert done.answers["frozen"] > 100_000  # numpy, scipy, sympy, IPython: frozen
    assert done.answers["enabled"] is True and done.answers["freed"] is True


def test_the_child_is_confined_like_a_cold_kernel(pool, run):
    probe = textwrap.dedent("""\
        import ctypes, os, resource, signal
        libc = ctypes.CDLL(None)
        deathsig = ctypes.c_int(-1)
        libc.prctl(2, ctypes.byref(deathsig), 0, 0, 0)  # PR_GET_PDEATHSIG
        deathsig = deathsig.value
        dumpable = libc.prctl(3, 0, 0, 0, 0)  # PR_GET_DUMPABLE
        limits = [list(resource.getrlimit(getattr(resource, 'RLIMIT_' + name)))
                  for name in ('AS', 'CPU', 'FSIZE', 'NPROC', 'CORE')]
        own_session = os.getsid(0) == os.getpid() == os.getpgid(0)
        here = sorted(os.listdir('.'))
        cwd_is_home = os.getcwd() == os.environ['HOME'] == os.environ['TMPDIR']
        env = sorted(os.environ)
        with open('/proc/self/environ', 'rb') as f:
            environ_block = f.read().decode(errors='replace')
        stdin = os.readlink('/proc/self/fd/0')
        control = os.path.dirname(os.environ['IPYTHONDIR'])
        key_on_disk = os.path.exists(os.path.join(control, 'kernel.json'))
        files = []
        for fd in os.listdir('/proc/self/fd'):
            try:
                files.append(os.readlink(f'/proc/self/fd/{fd}'))
            except OSError:
                pass  # the descriptor listdir itself used
        """)
    result = run(probe, variables=("deathsig", "dumpable", "limits", "own_session", "here",
                                   "cwd_is_home", "env", "environ_block", "stdin", "files",
                                   "key_on_disk"))
    assert result.status == "ok", result.message
    a = result.answers
    assert a["deathsig"] == signal.SIGKILL  # dies with its zygote
    assert a["dumpable"] == 0  # PR_SET_DUMPABLE 0: not ptrace-able by its peers
    assert a["own_session"] is True  # killpg reaches everything it starts
    assert a["here"] == ["alice.ipynb"] and a["cwd_is_home"] is True
    address, cpu, fsize, nproc, core = a["limits"]
    assert address == [LIMITS.memory_bytes] * 2
    assert cpu[0] == cpu[1] >= LIMITS.total_timeout  # finite CPU seconds
    assert fsize == [FILE_BYTES] * 2 and core == [0, 0]
    assert 0 < nproc[0] == nproc[1] < 1_000_000  # finite, positive
    allowed = set(kernel_environment(Path("w"), Path("c"))) | {
        "JPY_PARENT_PID", "PYDEVD_USE_FRAME_EVAL", "TERM", "CLICOLOR", "CLICOLOR_FORCE",
        "FORCE_COLOR", "PAGER", "GIT_PAGER", "MPLBACKEND"}  # what the kernel itself sets
    assert set(a["env"]) <= allowed
    # the environment block the process started with is the zygote's: scrubbed too
    assert CANARY not in a["environ_block"] and "canary-in-the-grader" not in a["environ_block"]
    zygote = pool.slots[0].zygote.process  # its pipes to the grader are not inherited
    pipes = {os.readlink(f"/proc/self/fd/{f.fileno()}") for f in (zygote.stdin, zygote.stdout)}
    assert a["stdin"] == "/dev/null" and not pipes & set(a["files"])
    assert a["key_on_disk"] is False  # no connection file: its channel is one socket


def test_interrupt_and_exit_status_go_through_the_zygote(run):
    looped = run("while True:\n    pass", "x = 1", variables=("x",))
    assert looped.status == "ok" and looped.answers == {"x": 1}
    assert looped.cell_errors == ("cell 1 (`while True:`): timed out after 1 s and was "
                                  "interrupted",)
    died = run("import os\nos._exit(3)", "x = 1", variables=("x",))
    assert died.status == "kernel_died"
    assert "the process exited with status 3" in died.message


def test_a_process_left_behind_is_killed_when_its_kernel_ends(run):
    daemon = textwrap.dedent("""\
        import os, time
        r, w = os.pipe()
        if os.fork() == 0:           # detach twice: a new session, parent gone
            os.setsid()
            if os.fork() == 0:
                os.write(w, str(os.getpid()).encode()); os.close(w)
                time.sleep(60)
            os._exit(0)
        os.close(w)
        leftover = int(os.read(r, 20))
        """)
    result = run(daemon, variables=("leftover",))
    assert result.status == "ok", result.message
    assert gone(result.answers["leftover"])


def test_a_zygote_killed_or_stopped_by_a_kernel_is_replaced(run, monkeypatch):
    monkeypatch.setattr(kernel_pool, "REQUEST_TIMEOUT", 0.5)
    with KernelPool(1, preload=LIGHT, prewarm=False) as own:
        slot = own.slots[0]
        killer = run("import os, signal\nos.kill(os.getppid(), signal.SIGKILL)\n"
                     "import time; time.sleep(5)", "x = 1", variables=("x",), using=own)
        assert killer.status == "kernel_died"  # the student's own kernel died with it
        after = run("x = 2", variables=("x",), using=own)
        assert after.status == "ok" and after.answers == {"x": 2}
        assert slot.starts == 2  # a new zygote for the slot
        first = slot.fork(LIMITS)
        os.kill(slot.zygote.process.pid, signal.SIGSTOP)
        with pytest.raises(kernel_pool.ZygoteError, match="did not answer"):
            slot.zygote.request("kill", pid=first.pid)
        assert gone(first.pid)  # the stuck zygote was killed, and its kernel with it
        second = slot.fork(LIMITS)
        assert slot.starts == 3 and not gone(second.pid, timeout=0.1)
        zygote = slot.zygote.process.pid
    assert gone(zygote) and gone(second.pid)  # closing the pool ends both
    assert not own.folder.exists()


def test_the_pool_falls_back_to_cold_kernels(run, monkeypatch, capsys, tmp_path):
    with KernelPool(1, cold=True) as cold:
        assert isinstance(cold.kernel(tmp_path, tmp_path, LIMITS), LocalKernel)
        assert cold.folder is None and cold.slots == []  # nothing started, nothing made
    monkeypatch.setattr(kernel_pool, "zygote_command",
                        lambda **_: [sys.executable, "-c", "exit(5)"])
    with KernelPool(1, preload=LIGHT) as broken:
        assert isinstance(broken.kernel(tmp_path, tmp_path, LIMITS), PooledKernel)
        result = run("x = 3", variables=("x",), using=broken)
        assert result.status == "ok" and result.answers == {"x": 3}  # ran cold
        assert broken.cold and "could not start" in broken.problem
        assert not isinstance(broken.kernel(tmp_path, tmp_path, LIMITS), PooledKernel)
    assert "kernels start cold from now on" in capsys.readouterr().err


def test_zygotes_and_kernels_die_with_the_grader(tmp_path):
    script = textwrap.dedent(f"""\
        import json, sys, time
        sys.path.insert(0, {str(ROOT)!r})
        from grader.kernels.pool import KernelPool
        from grader.limits import Limits
        pool = KernelPool(2, preload=())
        forked = pool.slots[1].fork(Limits())
        zygotes = [slot.zygote.process.pid for slot in pool.slots]
        print(json.dumps([zygotes, forked.pid, str(pool.folder)]), flush=True)
        time.sleep(60)
        """)
    grader = subprocess.Popen([sys.executable, "-c", script], stdout=subprocess.PIPE,
                              text=True, env={**os.environ, "TMPDIR": str(tmp_path)})
    try:
        zygotes, kernel, folder = json.loads(grader.stdout.readline())
        assert not gone(kernel, timeout=0.2)
        grader.kill()  # SIGKILL: no cleanup code of the grader runs
        grader.wait()
        assert all(gone(pid) for pid in [*zygotes, kernel])
        deadline = time.monotonic() + 5
        while Path(folder).exists() and time.monotonic() < deadline:
            time.sleep(0.02)
        assert not Path(folder).exists()  # the zygotes removed it on their way out
    finally:
        grader.kill()
        grader.stdout.close()


def test_a_zygote_removes_only_what_it_was_given(tmp_path):
    """End of input in a folder with other files: they stay (only empty folders go)."""
    (tmp_path / "keep.txt").write_text("not the zygote's")
    done = subprocess.run(kernel_pool.zygote_command(preload=()), cwd=tmp_path,
                          stdin=subprocess.DEVNULL, capture_output=True, timeout=60,
                          env=kernel_environment(tmp_path, tmp_path))
    assert json.loads(done.stdout.splitlines()[0])["ready"] is True
    assert (tmp_path / "keep.txt").read_text() == "not the zygote's"


def test_the_other_slots_zygotes_start_once_the_first_is_ready(monkeypatch):
    """Zygotes importing at once share the cores: slot 1's starts after slot 0's is ready,
    and both slots are lent out; closing kills a zygote still importing (nothing to wait
    for)."""
    started, killed, by_name = [], [], {}
    start, kill = kernel_pool.Slot.start_zygote, kernel_pool.Zygote.kill

    def recording_start(slot):
        first = by_name.get((slot.folder.parent, "0"))
        started.append((slot.folder.name, [] if first is None else [first.zygote.ready
                                                                    is not None]))
        by_name[slot.folder.parent, slot.folder.name] = slot
        start(slot)

    def recording_kill(zygote):
        killed.append(zygote.ready)
        kill(zygote)

    monkeypatch.setattr(kernel_pool.Slot, "start_zygote", recording_start)
    monkeypatch.setattr(kernel_pool.Zygote, "kill", recording_kill)
    own = KernelPool(2, preload=())
    try:
        slots = {own.acquire().folder.name, own.acquire().folder.name}
    finally:
        own.close()
    assert slots == {"0", "1"}
    assert started == [("0", []), ("1", [True])]
    assert killed == []  # both were ready: ended by end of input, not killed
    late = KernelPool(2, preload=("sympy",))  # closed once slot 1's zygote is importing
    deadline = time.monotonic() + 60
    while late.slots[1].zygote is None and time.monotonic() < deadline:
        time.sleep(0.005)
    late.close()
    assert killed == [None]  # slot 1's, still importing sympy


@pytest.mark.parametrize(("start_cost", "second"), [(1e6, False), (0.0, True)])
def test_a_second_zygote_starts_only_for_work_that_outlasts_its_start(run, monkeypatch,
                                                                      start_cost, second):
    """Three quick notebooks, two slots: a second zygote that would take longer to start than
    the first slot takes for all three is never started (issue 34); one that costs nothing to
    start is started at once. (The cost a start takes is the first zygote's, patched here.)"""
    monkeypatch.setattr(KernelPool, "_start_cost", lambda pool: start_cost)
    own = KernelPool(2, preload=LIGHT)
    try:
        own.expect(3)
        for _ in range(3):
            assert run("x = 1", variables=("x",), using=own).status == "ok"
        deadline = time.monotonic() + 60
        while second and own.slots[1].zygote is None and time.monotonic() < deadline:
            time.sleep(0.01)
        assert own.done == 3
        assert (own.slots[1].zygote is not None) is second
    finally:
        own.close()
