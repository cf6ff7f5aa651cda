"""The adversarial battery (issue 5): every attack fails for the student, is reported, and
changes nothing else.

References: the operating system seen from *outside* the sandbox — ``/proc`` of this machine
(no process of the attack left, by a token in its command line), the file system (the key and
the other submissions byte for byte unchanged, no file written outside the private folder, the
run folder gone) and a TCP server this test starts on 127.0.0.1 (it counts connections) — and,
from *inside*, what each attack cell recorded about its own outcome (the exception it got),
extracted as answers. Nothing is compared with a value the sandbox code computed.

Many attacks share one notebook (one cell each, recording into an ``atk_*`` variable) so that
few kernels start; one ``KernelPool(2)`` (two sandboxes, prewarm on) serves the module.
"""

from __future__ import annotations

import hashlib
import json
import os
import secrets
import socket
import sys
import textwrap
import threading
import time
from pathlib import Path

import nbformat
import pytest
from nbformat.v4 import new_code_cell, new_notebook

from eulertop.cli import main
from grader.execute import OUT_OF_TIME_GRACE, execute_submission
from grader.kernels.pool import FILE_BYTES, PROCESSES, KernelPool
from grader.limits import Limits
from grader.results import read_result
from grader.sandbox import SCRATCH_BYTES, available
from problems.generate import generate_assignment
from problems.roster import Roster
from problems.templates import FAMILIES
from tests.grader.golden import CANARY

SANDBOX = available()
@pytest.fixture(scope="module", autouse=True)
def _required_here():
    """Fail, never skip: a missing sandbox must not pass silently (CI installs bubblewrap).
    Module-scoped, so it runs before the module's other fixtures start any kernel."""
    if SANDBOX is None:
        pytest.fail("bubblewrap (bwrap) is not installed: `apt-get install bubblewrap` "
                    "(README); the battery must run, never skip", pytrace=False)

ROOT = Path(__file__).resolve().parents[2]
LIMITS = Limits(cell_timeout=8.0, total_timeout=60.0, memory_bytes=3 * 1024**3 // 2)
SECRET = "canary-7f3a-sandbox-battery"


def processes_with(token: str) -> list[int]:
    """Live processes of this machine whose command line or environment holds ``token``."""
    found = []
    for pid in filter(str.isdigit, os.listdir("/proc")):
        for part in ("cmdline", "environ"):
            try:
                if token.encode() in Path(f"/proc/{pid}/{part}").read_bytes():
                    state = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[0]
                    if state not in ("Z", "X"):
                        found.append(int(pid))
                    break
            except OSError:
                pass
    return found


def tree_digest(folder: Path) -> dict[str, str]:
    """Relative path → SHA-256 of every file below ``folder``."""
    return {str(p.relative_to(folder)): hashlib.sha256(p.read_bytes()).hexdigest()
            for p in sorted(folder.rglob("*")) if p.is_file()}


class CountingServer:
    """A TCP server on 127.0.0.1 that counts connections and stops by itself."""

    def __init__(self, lifetime: float = 120.0) -> None:
        self.sock = socket.socket()
        self.sock.bind(("127.0.0.1", 0))
        self.sock.listen(8)
        self.sock.settimeout(0.2)
        self.port = self.sock.getsockname()[1]
        self.connections = 0
        self.deadline = time.monotonic() + lifetime
        self.stopped = threading.Event()
        self.thread = threading.Thread(target=self._serve, daemon=True)
        self.thread.start()

    def _serve(self) -> None:
        while not self.stopped.is_set() and time.monotonic() < self.deadline:
            try:
                conn, _ = self.sock.accept()
            except OSError:
                continue
            self.connections += 1
            conn.close()
        self.sock.close()

    def stop(self) -> None:
        self.stopped.set()
        self.thread.join(5)


@pytest.fixture(scope="module")
def pool():
    os.environ[CANARY] = SECRET  # in the grader before any sandbox starts
    try:
        with KernelPool(2, sandbox=SANDBOX) as sandboxed:
            yield sandboxed
    finally:
        del os.environ[CANARY]


@pytest.fixture(scope="module")
def victims(tmp_path_factory):
    """An instructor's folders: a key and another student's submission, at known paths."""
    root = tmp_path_factory.mktemp("victims")
    (root / "HW").mkdir()
    (root / "HW" / "key.json").write_text(json.dumps({"secret": SECRET}))
    (root / "subs").mkdir()
    (root / "subs" / "bob.ipynb").write_text(json.dumps({"bob": SECRET}))
    return root


def run_cells(pool, folder: Path, cells, variables, limits=LIMITS):
    path = folder / f"n{secrets.token_hex(3)}" / "eve.ipynb"
    path.parent.mkdir(parents=True)
    nbformat.write(new_notebook(cells=[new_code_cell(c) for c in cells]), path)
    return execute_submission(path, variables, limits, kernel_factory=pool.kernel)


ATTACKS = {
    "atk_key_relative": """
        found = []
        for rel in ['key.json', '../key.json', '../../key.json', '../HW/key.json',
                    '../../HW/key.json', '../../../HW/key.json', '../../../../HW/key.json']:
            try:
                found.append(open(rel).read()[:40])
            except OSError as e:
                pass
        atk_key_relative = found
        """,
    "atk_key_absolute": """
        try:
            atk_key_absolute = open({key!r}).read()
        except OSError as e:
            atk_key_absolute = type(e).__name__
        """,
    "atk_walk": """
        import os, sys
        hits, seen = [], 0
        # every name visible is checked; contents are read outside the host's own system
        # trees (/usr, the Python installation), which are bound read-only as they are and
        # would only make the walk slow (and its time, with a cold file cache, a flake)
        system = tuple({{'/usr/', sys.prefix + '/', sys.base_prefix + '/'}})
        for top, dirs, files in os.walk('/'):
            dirs[:] = [d for d in dirs if os.path.join(top, d) not in ('/proc', '/sys', '/dev')]
            seen += len(files)
            for f in files:
                p = os.path.join(top, f)
                if f in ('key.json', 'bob.ipynb') or {hw!r} in p:
                    hits.append(p)
                elif f.endswith('.json') and not p.startswith(system) and \
                        os.path.getsize(p) < 100_000:
                    try:
                        if {secret!r} in open(p, errors='replace').read():
                            hits.append(p)
                    except OSError:
                        pass
        atk_walk = [hits, seen > 1000, sorted(os.listdir('/')), os.path.exists({project!r}),
                    sorted(os.listdir({home!r})) if os.path.isdir({home!r}) else []]
        """,
    "atk_other_submission": """
        try:
            atk_other_submission = open({bob!r}).read()
        except OSError as e:
            atk_other_submission = type(e).__name__
        """,
    "atk_grader_proc": """
        out = []
        for part in ('environ', 'cmdline'):
            try:
                out.append(open('/proc/{grader}/' + part, 'rb').read().decode(errors='replace'))
            except OSError as e:
                out.append(type(e).__name__)
        leaked = []
        for pid in filter(str.isdigit, os.listdir('/proc')):
            try:
                if {secret!r}.encode() in open(f'/proc/{{pid}}/environ', 'rb').read():
                    leaked.append(pid)
            except OSError:
                pass
        atk_grader_proc = [out, leaked]
        """,
    "atk_network": """
        import socket
        out = []
        try:
            socket.create_connection(('127.0.0.1', {port}), timeout=2).close()
            out.append('connected')
        except OSError as e:
            out.append(type(e).__name__)
        for host in ('example.com', 'pypi.org', socket.gethostname()):
            try:
                socket.getaddrinfo(host, 443)
                out.append('resolved ' + host)
            except OSError as e:
                out.append(type(e).__name__)
        atk_network = out
        """,
    "atk_write_outside": """
        out = []
        for target in ({hw_new!r}, {subs_new!r}, '/tmp/planted', '/usr/planted', '../../planted',
                       '/planted', '/etc/planted'):
            try:
                with open(target, 'w') as f:
                    f.write('x')
                out.append('wrote ' + target)
            except OSError as e:
                out.append(type(e).__name__)
        atk_write_outside = out
        """,
    "atk_signal": """
        import os, signal
        out = []
        try:
            os.kill({grader}, signal.SIGKILL)
            out.append('signalled the grader pid')
        except OSError as e:
            out.append(type(e).__name__)
        killed = []
        for pid in map(int, filter(str.isdigit, os.listdir('/proc'))):
            if pid != os.getpid():
                try:
                    os.kill(pid, signal.SIGSTOP)
                    killed.append(pid)
                except OSError:
                    pass
        atk_signal = [out, killed, os.getpid() < 100]
        """,
    "atk_fill_disk": """
        import os
        out = []
        try:
            with open('big', 'wb') as f:
                for _ in range(1024):
                    f.write(b'x' * 2**20)
            out.append('wrote 1 GiB')
        except OSError as e:
            out.append(type(e).__name__ + ' ' + str(e.errno))
        written = 0
        try:
            for i in range(64):
                with open(f'part{{i}}', 'wb') as f:
                    for _ in range(64):
                        f.write(b'y' * 2**20)
                        written += 2**20
            out.append('no limit')
        except OSError as e:
            out.append(type(e).__name__ + ' ' + str(e.errno))
        for name in os.listdir('.'):
            if name.startswith(('big', 'part')):
                os.unlink(name)
        atk_fill_disk = [out, written]
        """,
    "atk_fork_bomb": """
        import os, time
        children = []
        error = None
        for _ in range(2000):
            try:
                pid = os.fork()
            except OSError as e:
                error = type(e).__name__
                break
            if pid == 0:
                time.sleep(60)
                os._exit(0)
            children.append(pid)
        for pid in children:
            os.kill(pid, 9)
            os.waitpid(pid, 0)
        atk_fork_bomb = [len(children), error]
        """,
    "atk_orphan": """
        import subprocess, sys
        orphan = subprocess.Popen([sys.executable, '-c', 'import time; time.sleep(300)',
                                   {token!r}], start_new_session=True)
        atk_orphan = orphan.pid > 0
        """,
    "atk_memory": """
        try:
            import numpy as np
            block = np.ones(50 * 1024**3, dtype=np.uint8)
            atk_memory = 'allocated'
        except MemoryError:
            atk_memory = 'MemoryError'
        """,
}


@pytest.fixture(scope="module")
def battery(pool, victims, tmp_path_factory):
    """The many-attacks notebook, run once: (Execution, token, server, digests before)."""
    server = CountingServer()
    token = f"eulertop-battery-orphan-{secrets.token_hex(4)}"
    fields = {"key": str(victims / "HW" / "key.json"), "bob": str(victims / "subs" / "bob.ipynb"),
              "hw": str(victims / "HW"), "secret": SECRET, "grader": os.getpid(),
              "port": server.port, "token": token,
              "project": str(ROOT / "grader"), "home": str(Path.home()),
              "hw_new": str(victims / "HW" / "planted"),
              "subs_new": str(victims / "subs" / "planted")}
    before = tree_digest(victims)
    cells = [textwrap.dedent(src).format(**fields) for src in ATTACKS.values()]
    cells.append("survived = 42")
    try:
        result = run_cells(pool, tmp_path_factory.mktemp("battery"), cells,
                           (*ATTACKS, "survived"))
    finally:
        server.stop()
    return result, token, server, before


def test_the_notebook_runs_to_the_end_in_the_sandbox(battery):
    result = battery[0]
    assert result.status == "ok", result.message
    assert result.sandboxed is True
    assert result.answers["survived"] == 42


def test_the_key_cannot_be_read(battery):
    a = battery[0].answers
    assert a["atk_key_relative"] == []
    assert a["atk_key_absolute"] == "FileNotFoundError"  # the instructor's folders: not there
    hits, walked, root, project_seen, home_entries = a["atk_walk"]
    assert hits == [] and walked  # it did walk the whole visible tree
    # No project source, wherever the project lives (in CI: under /tmp, where the sandbox has a
    # /tmp of its own). Of the home folder only the way to a Python installation inside it
    # (e.g. ~/.pyenv, bound read-only) may show.
    assert "home" not in root and not project_seen
    home = Path.home()
    python_dirs = {Path(p).resolve() for p in (sys.prefix, sys.base_prefix)}
    allowed = {q.relative_to(home).parts[0] for q in python_dirs if q.is_relative_to(home)}
    assert set(home_entries) <= allowed, home_entries


def test_other_submissions_and_the_graders_process_are_out_of_reach(battery):
    a = battery[0].answers
    assert a["atk_other_submission"] == "FileNotFoundError"
    (environ, cmdline), leaked = a["atk_grader_proc"]
    assert SECRET not in environ and SECRET not in cmdline and leaked == []
    assert environ in ("FileNotFoundError", "PermissionError")  # own PID namespace


def test_no_network(battery):
    result, _, server, _ = battery
    connect, *resolve = result.answers["atk_network"]
    assert connect in ("ConnectionRefusedError", "OSError", "TimeoutError")
    assert all(not r.startswith("resolved") for r in resolve[:2])
    assert server.connections == 0  # seen from the server's side


def test_nothing_is_written_outside_the_private_folder(battery, victims):
    result, _, _, before = battery
    wrote = [r for r in result.answers["atk_write_outside"] if r.startswith("wrote")]
    # /tmp is the kernel's own tmpfs (issue 11): writable, gone with the kernel
    assert wrote == ["wrote /tmp/planted", "wrote ../../planted"]
    assert tree_digest(victims) == before  # key and submissions byte for byte unchanged
    assert not Path("/tmp/planted").exists() and not Path("/planted").exists()


def test_signals_reach_nothing_but_the_kernel_itself(battery, pool):
    (grader, killed, small_pid) = battery[0].answers["atk_signal"]
    assert grader == ["ProcessLookupError"] or grader == ["PermissionError"]
    assert killed == [] and small_pid  # zygote, bwrap, prewarmed kernel: other users
    assert all(slot.zygote.alive for slot in pool.slots)


def test_the_disk_cannot_be_filled(battery):
    (big, rest), written = battery[0].answers["atk_fill_disk"]
    assert big == "OSError 27"  # EFBIG: RLIMIT_FSIZE
    assert rest == "OSError 28"  # ENOSPC: the sandbox's tmpfs, not this machine's disk
    assert 0 < written and written + FILE_BYTES <= SCRATCH_BYTES  # the tmpfs's size, no more


def test_a_fork_bomb_is_bounded(battery):
    forked, error = battery[0].answers["atk_fork_bomb"]
    assert error == "BlockingIOError" and forked < PROCESSES  # RLIMIT_NPROC, effective


def test_no_process_outlives_its_kernel(battery):
    _, token, _, _ = battery
    assert battery[0].answers["atk_orphan"] is True  # it was started
    deadline = time.monotonic() + 5
    while processes_with(token) and time.monotonic() < deadline:
        time.sleep(0.05)
    assert processes_with(token) == []


def test_fifty_gigabytes_cannot_be_allocated(battery):
    assert battery[0].answers["atk_memory"] == "MemoryError"


def test_sleeping_past_the_time_limit_is_killed(pool, tmp_path):
    limits = Limits(cell_timeout=1.0, total_timeout=4.0)
    token = f"eulertop-battery-sleeper-{secrets.token_hex(4)}"
    sleeper = (f"import signal, subprocess, sys, time\n"
               f"signal.signal(signal.SIGINT, signal.SIG_IGN)\n"
               f"subprocess.Popen([sys.executable, '-c', 'import time; time.sleep(300)', "
               f"{token!r}])\n"
               f"time.sleep(1000)")
    result = run_cells(pool, tmp_path, [sleeper, "x = 1"], ("x",), limits)
    assert result.status == "timeout" and result.answers == {}
    assert "stopped at the time limit for the whole notebook (4 s)" in result.message
    assert 4.0 <= result.duration < 4.0 + OUT_OF_TIME_GRACE + 5.0  # the grace to read answers
    time.sleep(0.2)
    assert processes_with(token) == []


def _class(root: Path) -> tuple[Path, Path]:
    hw, subs = root / "HW", root / "subs"
    roster = Roster(("id",), tuple({"id": s} for s in ("alice", "bob", "eve")))
    generate_assignment(roster, hw, FAMILIES, problems=["inertia_tensor"], seed=5)
    subs.mkdir()
    for sid in ("alice", "bob"):  # handed in as saved again (the generated bytes are refused)
        nb = json.loads((hw / "solutions" / f"{sid}.ipynb").read_text())
        (subs / f"{sid}.ipynb").write_text(json.dumps(nb))
    return hw, subs


def test_an_attacker_in_a_class_changes_nothing_for_the_others(tmp_path, victims):
    """Through ``eulertop grade --jobs 2``: eve's notebook (her solutions, plus attacks on
    the real key by absolute and relative path, the other submissions, the run's folders, a
    process left behind) beside two honest students."""
    hw, subs = _class(tmp_path)
    token = f"eulertop-battery-class-{secrets.token_hex(4)}"
    eve = json.loads((hw / "solutions" / "eve.ipynb").read_text())
    attack = textwrap.dedent(f"""\
        import os, shutil, subprocess, sys
        stolen = []
        for p in [{str(hw / 'key.json')!r}, '../HW/key.json', '../../HW/key.json',
                  {str(subs / 'alice.ipynb')!r}]:
            try:
                stolen.append(open(p).read())
            except OSError:
                pass
        for p in [{str(hw)!r}, {str(subs)!r}, '..', '../..']:
            shutil.rmtree(p, ignore_errors=True)
        subprocess.Popen([sys.executable, '-c', 'import time; time.sleep(300)', {token!r}],
                         start_new_session=True)
        assert not stolen, stolen
        """)
    eve["cells"].insert(1, new_code_cell(attack, id="attack"))
    (subs / "eve.ipynb").write_text(json.dumps(eve))
    before = {**tree_digest(hw), **{f"subs/{k}": v for k, v in tree_digest(subs).items()}}
    assert main(["grade", str(hw), str(subs), "--jobs", "2", "--timeout", "60"]) == 0
    results = {s: read_result(hw / "graded" / "results" / f"{s}.json")
               for s in ("alice", "bob", "eve")}
    for sid, r in results.items():  # eve's attacks failed; her answers still count
        assert r.status == "graded" and r.points == r.max_points, (sid, r.message)
        assert r.sandboxed
    assert results["eve"].execution["cell_errors"] == []  # `assert not stolen` held
    after = {**tree_digest(hw), **{f"subs/{k}": v for k, v in tree_digest(subs).items()}}
    assert {k: v for k, v in after.items() if not k.startswith("graded/")} == before
    assert processes_with(token) == []
    assert not list(Path(hw / "graded").rglob(".*.tmp"))


def test_without_a_sandbox_grade_refuses_unless_told_and_then_says_so(tmp_path, monkeypatch,
                                                                       capsys):
    import csv

    from grader import sandbox as sandboxes

    hw, subs = _class(tmp_path)
    monkeypatch.setattr(sandboxes.shutil, "which", lambda name: None)  # no bwrap installed
    sandboxes.probe.cache_clear()
    try:
        assert main(["grade", str(hw), str(subs), "--jobs", "1"]) == 2
        err = capsys.readouterr().err
        assert "no sandbox for student code: the bubblewrap program 'bwrap' is not installed" \
            in err and "apt-get install bubblewrap" in err and "--no-sandbox" in err
        assert not (hw / "graded" / "results" / "alice.json").exists()  # nothing was run
        assert main(["grade", str(hw), str(subs), "--jobs", "1", "--no-sandbox"]) == 0
        assert "WARNING: grading WITHOUT a sandbox" in capsys.readouterr().err
    finally:
        monkeypatch.undo()  # bwrap is back
        sandboxes.probe.cache_clear()
    records = {s: read_result(hw / "graded" / "results" / f"{s}.json") for s in ("alice", "bob")}
    assert all(r.status == "graded" and r.sandboxed is False for r in records.values())
    with open(hw / "graded" / "grades.csv", newline="") as f:
        rows = list(csv.DictReader(f))
    assert {r["id"]: r["sandboxed"] for r in rows} == {"alice": "no", "bob": "no", "eve": ""}
    # the next sandboxed run regrades what was graded without one
    assert main(["grade", str(hw), str(subs), "--jobs", "1"]) == 0
    assert all(read_result(hw / "graded" / "results" / f"{s}.json").sandboxed
               for s in ("alice", "bob"))
    with open(hw / "graded" / "grades.csv", newline="") as f:
        assert "sandboxed" not in next(csv.reader(f))
