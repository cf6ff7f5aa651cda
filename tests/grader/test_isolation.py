"""Isolation round 2 (issue 11): attacks by one student on the others, on the instructor's files
and on the grader — each run through ``eulertop grade`` as root *and* as an ordinary user, each
judged by its harm as measured from outside.

The battery runs in every isolation tier it applies to (issue 22): ``world`` (as root and as an
ordinary user), ``bwrap-per-kernel`` (both; a ``bwrap`` with ``--disable-userns`` on ``PATH``,
where nothing inside bubblewrap can make a user namespace), and ``container`` (as root: a
``bwrap`` that fails as under Docker's seccomp profile, in a container's file system layout).
The container mode has no namespaces: its kernels see this machine's process list (a01 finds
other processes, attaches to none), and a student's memory is counted per uid, not per PID
namespace. A kernel alone in its bubblewrap sees that sandbox's PID 1 and its own zygote
besides itself (a01: attaches to neither).

One class per mode: three honest students (their solutions notebooks; graded before, between
and after the attackers) and one attacker per attack, each attack in its own submission (so in
its own kernel, as in a real class). The same honest students are also graded alone (the clean
run). The grader runs in a subprocess; the ordinary user is ``eulertop-attacker`` (made here with
``useradd``), the project reached as a laptop user reaches theirs.

What is measured, never taken from the grader's own word:
* each honest student's record equals the clean run's (status, points, every verdict);
* the instructor's canary file and the assignment and submission folders, byte for byte;
* the grader's peak memory (``VmHWM`` of the grading process, read from ``/proc``);
* the largest resident memory of one student's processes together (sampled from ``/proc``,
  grouped by PID namespace: one per student);
* the run ends (no hang) and leaves no process, no SysV shared memory and no run folder;
* stdout, stderr, ``grades.csv`` and the feedback pages hold no raw control character.
"""

from __future__ import annotations

import contextlib
import hashlib
import json
import os
import shutil
import stat
import subprocess
import sys
import tempfile
import textwrap
import threading
import time
from dataclasses import replace
from pathlib import Path

import pytest
from nbformat.v4 import new_code_cell

from grader.results import StudentResult, read_result
from grader.sandbox import UID_BASE, _as_user, _python_paths, available
from problems.generate import generate_assignment
from problems.roster import Roster
from problems.templates import FAMILIES
from tests.grader.tiers_support import fake_bwrap, ordinary_user

ROOT = Path(__file__).resolve().parents[2]
HONEST = ("a00-honest", "a05b-honest", "z9-honest")  # graded before, between, after attacks
MEMORY = 2 * 1024**3  # the grader's default memory limit per submission
BIG_NOTEBOOK = 75 * 1024**2
GRADER_PEAK = 600 * 1024**2  # the grader's peak memory must stay under this, attacks included


def _needs_root_and_bwrap():
    if os.geteuid() != 0:
        pytest.fail("the isolation battery runs as root (CI does), to act both as root and as "
                    "an ordinary user", pytrace=False)
    if available() is None:
        pytest.fail("bubblewrap is not installed: `apt-get install bubblewrap` (README); the "
                    "battery must run, never skip", pytrace=False)


# --------------------------------------------------------------------------------------------
# the attacks: one cell each, added to that attacker's own (correct) release notebook

ATTACKS = {
    # through the kernel
    "a01-ptrace": """
        import ctypes, os
        libc = ctypes.CDLL(None, use_errno=True)
        attached = []
        for pid in range(1, 2000):  # the zygote, the keepers, other kernels: by any number
            if pid != os.getpid() and libc.ptrace(16, pid, 0, 0) == 0:  # PTRACE_ATTACH
                attached.append(pid)
        visible = sorted(int(p) for p in os.listdir('/proc') if p.isdigit())
        print('attached', attached, 'visible', visible)
        assert attached == [] and visible == [os.getpid()], (attached, visible)
        """,
    "a02-plant-folders": """
        import os, re
        planted = 0
        mounts = open('/proc/self/mountinfo').read()
        paths = set(re.findall(r' (/tmp/eulertop-[^ ]+)', mounts))
        for base in {'/tmp', '/dev/shm', *paths, *(os.path.dirname(p) for p in paths)}:
            for i in range(400):
                for name in (f'c{i}', f'w{i}', f'z{i}', f'eulertop-{i}'):
                    try:
                        os.mkdir(os.path.join(base, name), 0)
                        planted += 1
                    except OSError:
                        pass
        print('planted', planted)
        """,
    "a03-symlinks-and-fifos": """
        import os, re
        swapped = []
        mounts = open('/proc/self/mountinfo').read()
        places = set(re.findall(r' (/tmp/eulertop-[^ ]+)', mounts))
        places |= {os.path.dirname(p) for p in places} | {os.getcwd(), '/tmp', '..'}
        for place in places:
            for name in ('kernel-stderr.txt', 'zygote-stderr.txt', 'kernel.json', 'k-shell-1',
                         'c1', 'c2', 'c3', 'w1', 'results', 'grades.csv'):
                target = os.path.join(place, name)
                for make in (lambda t: os.symlink(CANARY_PATH, t), lambda t: os.mkfifo(t)):
                    try:
                        if os.path.lexists(target):
                            os.rename(target, target + '.old')
                        make(target)
                        swapped.append(target)
                        break
                    except OSError:
                        pass
        print('swapped', len(swapped))
        """,
    "a04-fill-disks": """
        import os
        written = {}
        for place in ('/tmp', '/dev/shm', '/dev', '/', os.getcwd(), '..'):
            total = 0
            try:
                for i in range(64):
                    with open(os.path.join(place, f'fill{i}'), 'wb') as f:
                        for _ in range(64):
                            f.write(b'\\0' * (1 << 20))
                            total += 1 << 20
            except OSError as e:
                pass
            written[place] = total
        print('written', written)
        """,
    "a05-reach-other-kernels": """
        import os, socket
        reached = []
        for line in open('/proc/net/unix').read().splitlines()[1:]:
            path = line.split()[-1] if len(line.split()) > 7 else ''
            if path.startswith('/'):
                s = socket.socket(socket.AF_UNIX, socket.SOCK_STREAM)
                try:
                    s.connect(path)
                    s.sendall(b'\\xff' * 65536)
                    reached.append(path)
                except OSError:
                    pass
                finally:
                    s.close()
        for line in open('/proc/net/tcp').read().splitlines()[1:]:
            local, state = line.split()[1], line.split()[3]
            if state == '0A':  # listening
                port = int(local.split(':')[1], 16)
                try:
                    c = socket.create_connection(('127.0.0.1', port), timeout=1)
                    c.sendall(b'\\xff' * 65536)
                    reached.append(port)
                    c.close()
                except OSError:
                    pass
        print('reached', reached)
        """,
    "a06-huge-messages": """
        import os, socket, stat
        ip = get_ipython()
        k = getattr(ip, 'kernel', None)  # a Jupyter kernel (cold): its ZeroMQ channels
        if k is not None:
            big = 'x' * (192 * 1024**2)
            for channel in ('iopub', 'shell'):
                try:
                    if channel == 'iopub':
                        k.session.send(k.iopub_socket, 'stream', {'name': 'stdout', 'text': big},
                                       parent=k.get_parent())
                    else:
                        stream = getattr(k, 'shell_stream', None) or k.shell_streams[0]
                        k.session.send(stream, 'execute_reply', {'status': 'ok', 'pad': big},
                                       parent=k.get_parent('shell'),
                                       ident=k._parent_ident['shell'])
                except Exception as e:
                    print(channel, type(e).__name__, e)
            for _ in range(150):  # and a flood of messages just under any cap
                k.session.send(k.iopub_socket, 'stream',
                               {'name': 'stdout', 'text': 'y' * (3 * 1024**2)},
                               parent=k.get_parent())
            del big
        # a forked kernel: its one channel to the grader, a Unix socket among its descriptors
        chunk = b'z' * (16 * 1024**2)
        for fd in map(int, os.listdir('/proc/self/fd')):
            try:
                if not stat.S_ISSOCK(os.fstat(fd).st_mode):
                    continue
                s = socket.socket(fileno=os.dup(fd))
                for _ in range(12):  # 192 MiB in one line that never ends
                    s.sendall(chunk)
                for _ in range(60):  # then lines just under the grader's cap
                    s.sendall(b'y' * (4 * 1024**2 - 64) + b'\\n')
                s.sendall(b'\\n')
            except OSError as e:
                print('channel', fd, type(e).__name__, e)
        """,
    "a07-ipc-leftovers": """
        import ctypes, mmap, os
        libc = ctypes.CDLL(None, use_errno=True)
        libc.shmat.restype = ctypes.c_void_p
        made = []
        for _ in range(8):
            sid = libc.shmget(0, 200 * 1024**2, 0o1600)  # IPC_PRIVATE, IPC_CREAT | 0600
            if sid >= 0:
                made.append(sid)
                addr = libc.shmat(sid, None, 0)
                if addr not in (None, ctypes.c_void_p(-1).value):
                    ctypes.memset(addr, 1, 200 * 1024**2)
        memfd = []
        try:
            fd = os.memfd_create('leftover')
            os.ftruncate(fd, 200 * 1024**2)
            memfd.append(fd)
        except OSError as e:
            memfd.append(type(e).__name__)
        print('shm', made, 'memfd', memfd)
        """,
    "a08-memory-by-forking": """
        import os, time
        children = []
        for _ in range(4):
            pid = os.fork()
            if pid == 0:
                block = bytearray(650 * 1024**2)
                for i in range(0, len(block), 4096):
                    block[i] = 1
                time.sleep(20)
                os._exit(0)
            children.append(pid)
        for pid in children:
            os.waitpid(pid, 0)
        """,
    # own attacks in the same spirit
    "a09-escape-the-namespaces": """
        import ctypes, os
        libc = ctypes.CDLL(None, use_errno=True)
        done = []
        for name, call in [('unshare', lambda: libc.unshare(0x10000000)),
                           ('mount', lambda: libc.mount(b'none', b'/tmp', b'tmpfs', 0, None)),
                           ('setns', lambda: libc.setns(os.open('/proc/1/ns/pid', 0), 0)),
                           ('keyctl', lambda: libc.syscall(250, 0, 0, 0, 0, 0)),
                           ('bpf', lambda: libc.syscall(321, 0, 0, 0))]:
            try:
                if call() == 0:
                    done.append(name)
            except OSError:
                pass
        print('escaped', done)
        assert done == []
        """,
    "a10-signal-everything": """
        import os, signal
        try:
            os.kill(-1, signal.SIGKILL)  # everything it may signal: only its own namespace
        except OSError:
            pass
        """,
    "a11-leave-a-process": """
        import subprocess, sys
        subprocess.Popen([sys.executable, '-c', 'import time; time.sleep(600)', TOKEN_TEXT],
                         start_new_session=True)
        """,
    "a12-escapes-in-output": """
        raise ValueError('\\x1b[2J\\x1b]0;pwned\\x07 cleared your screen \\u202e evil')
        """,
}


def attack_cell(name: str, fields: dict) -> str:
    """The attack's source with the canary's path and the run's token filled in."""
    return (textwrap.dedent(ATTACKS[name]).replace("CANARY_PATH", repr(fields["canary"]))
            .replace("TOKEN_TEXT", repr(fields["token"])))


# --------------------------------------------------------------------------------------------
# the class, as an instructor's files


def build_class(base: Path, owner: int, token: str) -> dict:
    """The instructor's folders under ``base`` (owned by ``owner``): HW, SUBS (attack class),
    CLEAN (honest students only), a canary file; what the checks need."""
    canary = base / "instructor" / "canary.txt"
    canary.parent.mkdir(parents=True)
    canary.write_text("the instructor's own file\n")
    hw, subs, clean = base / "HW", base / "subs", base / "clean"
    ids = (*HONEST, *ATTACKS, "b1-big", "b2-link", "b3-zero", "b4-fifo")
    roster = Roster(("id",), tuple({"id": s} for s in sorted(ids)))
    generate_assignment(roster, hw, FAMILIES, problems=["inertia_tensor"], seed=11)
    subs.mkdir()
    clean.mkdir()
    for sid in HONEST:  # handed in as saved again (the generated bytes alone are refused)
        saved = json.dumps(json.loads((hw / "solutions" / f"{sid}.ipynb").read_text()))
        (subs / f"{sid}.ipynb").write_text(saved)
        (clean / f"{sid}.ipynb").write_text(saved)
    fields = {"canary": str(canary), "token": token}
    for name in ATTACKS:
        nb = json.loads((hw / "solutions" / f"{name}.ipynb").read_text())
        nb["cells"].insert(1, new_code_cell(attack_cell(name, fields), id="attack"))
        (subs / f"{name}.ipynb").write_text(json.dumps(nb))
    # through the submission file itself
    with open(subs / "b1-big.ipynb", "wb") as f:
        f.write(b'{"cells": [], "pad": "' + b"x" * BIG_NOTEBOOK + b'"}')
    os.symlink(hw / "solutions" / "b2-link.ipynb", subs / "b2-link.ipynb")
    os.symlink("/dev/zero", subs / "b3-zero.ipynb")
    os.mkfifo(subs / "b4-fifo.ipynb")
    (subs / "x\x1b[2J\x1b]0;pwned\x07.ipynb").write_text("{}")  # a stray file, its name
    for path in [base, *base.rglob("*")]:
        os.lchown(path, owner, owner)
    return {"hw": hw, "subs": subs, "clean": clean, "canary": canary}


def tree_digest(folder: Path) -> dict[str, str]:
    out = {}
    for p in sorted(folder.rglob("*")):
        info = p.lstat()
        if stat.S_ISREG(info.st_mode):
            out[str(p.relative_to(folder))] = hashlib.sha256(p.read_bytes()).hexdigest()
        else:
            out[str(p.relative_to(folder))] = stat.filemode(info.st_mode)
    return out


# --------------------------------------------------------------------------------------------
# measuring from outside


def _status(pid: str) -> dict[str, str]:
    with open(f"/proc/{pid}/status") as f:
        return dict(line.split(":", 1) for line in f if ":" in line)


class Watch:
    """Samples /proc while a run goes: the grader's VmHWM, and per student the summed Pss of
    their processes (shared pages divided among their sharers: what the processes hold) —
    students told apart by PID namespace (the deepest: one per kernel; in the
    ``bwrap-per-kernel`` tier the sandbox's, one per kernel too) or, in the container mode, by
    uid (one per kernel)."""

    def __init__(self, token: str, tier: str = "world") -> None:
        self.tier = tier
        self.token = token.encode()
        self.grader_peak = 0
        self.student_peak = 0
        self.grader_pids: set[int] = set()
        self.stop = threading.Event()
        self.thread = threading.Thread(target=self._run, daemon=True)

    def _sample(self) -> None:
        groups: dict[str, int] = {}
        depth_of: dict[str, int] = {}
        for pid in filter(str.isdigit, os.listdir("/proc")):
            with contextlib.suppress(OSError, ValueError, KeyError):
                status = _status(pid)
                if self.token in Path(f"/proc/{pid}/cmdline").read_bytes():
                    self.grader_pids.add(int(pid))
                    hwm = int(status["VmHWM"].split()[0]) * 1024
                    self.grader_peak = max(self.grader_peak, hwm)
                    continue
                depth = len(status["NSpid"].split())
                uid = int(status["Uid"].split()[0])
                if self.tier == "container":
                    if uid < UID_BASE:
                        continue
                    ns = f"uid {uid}"
                elif depth < (2 if self.tier == "bwrap-per-kernel" else 3):
                    continue
                else:
                    ns = os.readlink(f"/proc/{pid}/ns/pid")
                rollup = Path(f"/proc/{pid}/smaps_rollup").read_text().splitlines()
                pss = next(int(line.split()[1]) for line in rollup if line.startswith("Pss:"))
                groups[ns] = groups.get(ns, 0) + pss * 1024
                depth_of[ns] = depth
        if groups:
            deepest = max(depth_of.values())
            self.student_peak = max(self.student_peak, max(
                v for ns, v in groups.items() if depth_of[ns] == deepest))

    def _run(self) -> None:
        while not self.stop.is_set():
            self._sample()
            time.sleep(0.03)

    def __enter__(self) -> Watch:
        self.thread.start()
        return self

    def __exit__(self, *exc: object) -> None:
        self.stop.set()
        self.thread.join(10)


def shared_memory_segments() -> set[str]:
    return set(Path("/proc/sysvipc/shm").read_text().splitlines()[1:])


def processes_with(token: bytes) -> list[int]:
    found = []
    for pid in filter(str.isdigit, os.listdir("/proc")):
        with contextlib.suppress(OSError):
            if token in Path(f"/proc/{pid}/cmdline").read_bytes():
                state = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[0]
                if state not in ("Z", "X"):
                    found.append(int(pid))
    return found


def run_folders(pids) -> set[str]:
    """The run folders of the grader processes ``pids`` that exist now."""
    return {p.name for pid in pids for p in Path(tempfile.gettempdir()).glob(f"eulertop-{pid}-*")}


def grade(uid: int | None, hw: Path, subs: Path, out: Path, token: str, timeout: float = 600,
          tier: str = "world"):
    """``eulertop grade HW SUBS --out OUT --jobs 2`` in a subprocess, as root or as ``uid``, on
    a machine that allows ``tier`` (emulated: :func:`tier_machine`); (return code, stdout,
    stderr, Watch)."""
    code = f"import sys; from eulertop.cli import main; sys.exit(main())  # {token}"
    argv = [sys.executable, "-c", code, "grade", str(hw), str(subs), "--out", str(out),
            "--jobs", "2", "--timeout", "40"]
    bin_first, prefix = tier_machine(tier, out.parent)
    path = os.environ.get("PATH", os.defpath)
    env = {"PATH": f"{bin_first}:{path}" if bin_first else path, "LANG": "C.UTF-8",
           "HOME": str(out.parent), "TMPDIR": "/tmp"}
    if uid is not None:  # the project and its Python, reachable as a laptop user's are
        argv = [*_as_user(uid, [*_python_paths(), str(ROOT), str(out.parent)]), *argv]
    with Watch(token, tier) as watch:
        done = subprocess.run([*prefix, *argv], capture_output=True, timeout=timeout, env=env,
                              cwd=out.parent)
    return done.returncode, done.stdout.decode(errors="replace"), \
        done.stderr.decode(errors="replace"), watch


def tier_machine(tier: str, base: Path) -> tuple[Path | None, list[str]]:
    """What makes this machine one of ``tier`` (:mod:`tests.grader.tiers_support`): a folder
    to put first on ``PATH`` (its ``bwrap``) and a launcher prefix (the container's layout)."""
    if tier == "world":
        return None, []
    if tier == "bwrap-per-kernel":
        return fake_bwrap(base, "no-nesting"), []
    from tests.grader.hosted.conftest import container_layout

    layout = container_layout()
    assert layout is not None, "bubblewrap could not lay out a container's file system"
    return fake_bwrap(base, "docker"), layout


def _stable(r: StudentResult) -> StudentResult:
    execution = {k: v for k, v in r.execution.items() if k != "duration"}
    return replace(r, graded_at="", execution=execution, submission_sha256=None)


MODES = {"root": ("root", "world"), "ordinary user": ("ordinary user", "world"),
         "root, bwrap-per-kernel": ("root", "bwrap-per-kernel"),
         "ordinary user, bwrap-per-kernel": ("ordinary user", "bwrap-per-kernel"),
         "root, container": ("root", "container")}
"""Who grades, and in which tier (the container mode needs root: another uid to run as)."""


@pytest.fixture(scope="module", params=list(MODES))
def battle(request):
    """One mode's attack run and clean run, with everything measured around them."""
    _needs_root_and_bwrap()
    who, tier = MODES[request.param]
    uid = None if who == "root" else ordinary_user()
    owner = 0 if uid is None else uid
    base = Path(tempfile.mkdtemp(prefix="eulertop-isolation-"))
    os.chmod(base, 0o755)
    token = (f"eulertop-isolation-{os.getpid()}-"
             f"{request.param.replace(' ', '-').replace(',', '')}")
    try:
        files = build_class(base, owner, token)
        before = {name: tree_digest(files[name]) for name in ("hw", "subs", "clean")}
        canary = files["canary"].read_bytes()
        segments = shared_memory_segments()
        free = shutil.disk_usage(tempfile.gettempdir()).free
        clean_out, attack_out = base / "graded-clean", base / "graded-attack"
        for out in (clean_out, attack_out):
            out.mkdir()
            os.chown(out, owner, owner)
        clean = grade(uid, files["hw"], files["clean"], clean_out, token + "-clean", tier=tier)
        t0 = time.monotonic()
        attacked = grade(uid, files["hw"], files["subs"], attack_out, token + "-attack",
                         tier=tier)
        seconds = time.monotonic() - t0
        time.sleep(0.5)
        left = {"processes": processes_with(token.encode()),
                "segments": shared_memory_segments() - segments,
                "folders": run_folders(attacked[3].grader_pids | clean[3].grader_pids),
                "disk_used": free - shutil.disk_usage(tempfile.gettempdir()).free}
        report = os.environ.get("EULERTOP_BATTERY_REPORT")
        if report:  # the measured numbers, for docs/security.md
            with open(report, "a") as f:
                f.write(json.dumps({
                    "mode": request.param, "seconds": round(seconds, 1),
                    "grader_peak_mib": round(attacked[3].grader_peak / 2**20),
                    "clean_grader_peak_mib": round(clean[3].grader_peak / 2**20),
                    "student_peak_mib": round(attacked[3].student_peak / 2**20),
                    "left": {k: (len(v) if isinstance(v, (list, set)) else round(v / 2**20, 1))
                             for k, v in left.items()},
                    "honest_equal": all(
                        _stable(records(attack_out)[sid]) == _stable(records(clean_out)[sid])
                        for sid in HONEST),
                    "records": {sid: [r.status, r.points, r.max_points, r.message[:160]]
                                for sid, r in sorted(records(attack_out).items())},
                }) + "\n")
        yield {
            "mode": request.param, "tier": tier, "files": files, "before": before,
            "canary": canary,
            "clean": clean, "attacked": attacked, "seconds": seconds,
            "clean_out": clean_out, "attack_out": attack_out,
            "left": left,
        }
    finally:
        shutil.rmtree(base, ignore_errors=True)


def records(out: Path) -> dict[str, StudentResult]:
    return {p.stem: read_result(p) for p in (out / "results").glob("*.json")}


# --------------------------------------------------------------------------------------------
# the harm, one test per kind


def test_the_attacked_run_ends_and_grades_everyone(battle):
    code, _, err, _ = battle["attacked"]
    assert code in (0, 1), err[-3000:]
    assert f"eulertop grade: isolation: {battle['tier']}:" in err  # the tier meant
    assert battle["seconds"] < 300
    got = records(battle["attack_out"])
    assert set(got) >= set(HONEST) | set(ATTACKS)


def test_honest_students_are_graded_exactly_as_in_a_clean_run(battle):
    assert battle["clean"][0] == 0, battle["clean"][2][-3000:]
    clean, attacked = records(battle["clean_out"]), records(battle["attack_out"])
    for sid in HONEST:
        assert clean[sid].status == "graded" and clean[sid].points == clean[sid].max_points
        assert _stable(attacked[sid]) == _stable(clean[sid]), (sid, attacked[sid].message)


def test_attackers_get_their_own_grade_and_no_more(battle):
    got = records(battle["attack_out"])
    cells = ("a01-ptrace", "a09-escape-the-namespaces")  # cells that assert the failure
    errors = got["a01-ptrace"].execution["cell_errors"]
    if battle["tier"] == "container":  # no PID namespace: a01 sees others, attaches to none
        assert len(errors) == 1 and "AssertionError: ([], [" in errors[0], errors
        cells = cells[1:]
    elif battle["tier"] == "bwrap-per-kernel":  # it sees its own sandbox: init, zygote, itself
        assert len(errors) == 1 and errors[0].endswith("AssertionError: ([], [1, 2, 3])"), errors
        cells = cells[1:]
    for name in cells:
        assert got[name].status == "graded", got[name].message
        assert got[name].execution["cell_errors"] == [], got[name].execution
    assert "stopped when its processes together held" in got["a08-memory-by-forking"].message


def test_the_instructors_files_are_untouched(battle):
    files = battle["files"]
    assert files["canary"].read_bytes() == battle["canary"]
    for name in ("hw", "subs", "clean"):
        now = {k: v for k, v in tree_digest(files[name]).items() if not k.startswith("graded")}
        assert now == battle["before"][name], name
    outs = [battle["attack_out"], battle["clean_out"]]
    for out in outs:
        for p in out.rglob("*"):  # nothing the student made: only the grader's own files
            assert p.is_dir() or (p.is_file() and not p.is_symlink()), p


def test_the_graders_memory_stays_bounded(battle):
    assert 0 < battle["attacked"][3].grader_peak < GRADER_PEAK, battle["attacked"][3].grader_peak


def test_one_students_processes_together_stay_under_the_memory_limit(battle):
    peak = battle["attacked"][3].student_peak
    assert 0 < peak < MEMORY * 1.25, peak  # keeper's look every 50 ms: a little overshoot


def test_submission_files_are_read_only_if_they_are_regular_and_small(battle):
    got = records(battle["attack_out"])
    for sid, what in (("b1-big", "over the 20 MiB limit"), ("b2-link", "a symbolic link"),
                      ("b3-zero", "a symbolic link"), ("b4-fifo", "a named pipe")):
        assert got[sid].status == "failed" and got[sid].points == 0, got[sid]
        assert got[sid].message.startswith("invalid submission:") and what in got[sid].message


def test_nothing_is_left_behind(battle):
    left = battle["left"]
    assert left["processes"] == []
    assert left["segments"] == set()
    assert left["folders"] == set()
    # the fill attack tries to write gigabytes in each place; what it could write went to its
    # own tmpfs (256 MiB), gone with it. The free space of a shared machine moves by tens of
    # MiB on its own, hence a bound well under what the attack would leave
    assert left["disk_used"] < 512 * 1024**2


def test_no_control_character_reaches_a_terminal_a_csv_or_a_page(battle):
    _, out, err, _ = battle["attacked"]
    for text in (out, err, (battle["attack_out"] / "grades.csv").read_text()):
        assert "\x1b" not in text and "\x07" not in text and "\u202e" not in text
    page = (battle["attack_out"] / "feedback" / "a12-escapes-in-output.html").read_text()
    assert "\x1b" not in page and "\u202e" not in page and "\\x1b[2J" in page
