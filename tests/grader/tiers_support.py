"""What the tests of issue 22 share: a small class with a thief in it, machines emulated with a
``bwrap`` of their own on ``PATH``, and ``eulertop`` run in a subprocess as root or as an
ordinary user, from any Python.

The class (:func:`make_class`): two honest students (their solutions notebooks) and ``thief``,
whose notebook reads the answer key and the instructor's canary file by their absolute paths,
copies its own key values into its answers when it can, and tries to overwrite both files. What
is measured, from outside: the honest students' points, the thief's points (0 unless the key was
within its reach: a control run without a sandbox shows it would get them all), and the key,
the canary and the assignment folder byte for byte.

The emulated machines (:data:`FAKE_BWRAPS`): scripts named ``bwrap`` in a folder put first on
``PATH``, each standing for what a real system does to bubblewrap —
``apparmor`` (Ubuntu 24.04's restriction: "setting up uid map: Permission denied"),
``docker`` (a container's seccomp profile: namespaces "Operation not permitted"),
``no-userns`` (``user.max_user_namespaces = 0``: "No space left on device"),
``no-nesting`` (the real bwrap with ``--disable-userns``: a sandbox starts, but nothing inside it
can make a user namespace, as under Ubuntu ≥ 25.04's bwrap profile), and
``no-kernel`` (the real bwrap, but every zygote's sandbox fails to start: a machine where the
probe passes and no kernel starts).
"""

from __future__ import annotations

import hashlib
import json
import os
import pwd
import shutil
import subprocess
import sys
import sysconfig
from pathlib import Path

from nbformat.v4 import new_code_cell

from problems.generate import generate_assignment
from problems.roster import Roster
from problems.templates import FAMILIES

ROOT = Path(__file__).resolve().parents[2]
USER = "eulertop-attacker"  # the ordinary user of tests/grader/test_isolation.py
HONEST = ("ada", "bob")
THIEF = "thief"
CANARY_TEXT = "the instructor's own file\n"

THIEF_CELL = """
import json
KEY, CANARY = {key!r}, {canary!r}
stolen = False
try:
    key = json.load(open(KEY))
    for q in key['students']['thief']['questions']:
        for a in q['answers']:
            globals()[f"q{{q['question']}}_{{a['name']}}"] = a['value']
    stolen = True
except Exception as e:
    print('key:', type(e).__name__)
for path in (KEY, CANARY):
    try:
        with open(path, 'a') as f:
            f.write('vandalised')
    except Exception as e:
        print('write', path, type(e).__name__)
"""

_REAL = shutil.which("bwrap") or "/usr/bin/bwrap"
FAKE_BWRAPS = {
    "apparmor": "echo 'bwrap: setting up uid map: Permission denied' >&2\nexit 1\n",
    "docker": "echo 'bwrap: Creating new namespace failed: Operation not permitted' >&2\n"
              "exit 1\n",
    "no-userns": "echo 'bwrap: Creating new namespace failed: No space left on device' >&2\n"
                 "exit 1\n",
    "no-nesting": f"""for a in "$@"; do
  [ "$a" = "--" ] && break
  [ "$a" = "--unshare-user" ] && exec {_REAL} --disable-userns "$@"
done
exec {_REAL} "$@"
""",
    "no-kernel": f"""case "$*" in
  *zygote.py*) echo "bwrap: Can't mount proc on /newroot/proc: Operation not permitted" >&2
               exit 1 ;;
esac
exec {_REAL} "$@"
""",
}


def fake_bwrap(base: Path, kind: str) -> Path:
    """A folder (under ``base``, readable by every user) holding a ``bwrap`` of ``kind``."""
    folder = base / f"bin-{kind}"
    folder.mkdir(mode=0o755, exist_ok=True)
    script = folder / "bwrap"
    script.write_text("#!/bin/sh\n" + FAKE_BWRAPS[kind])
    script.chmod(0o755)
    return folder


def ordinary_user() -> int:
    """The uid of :data:`USER`, made with ``useradd`` if it does not exist yet."""
    try:
        return pwd.getpwnam(USER).pw_uid
    except KeyError:
        subprocess.run(["useradd", "--no-create-home", "--shell", "/usr/sbin/nologin", USER],
                       check=True, capture_output=True)
        return pwd.getpwnam(USER).pw_uid


def make_class(base: Path, owner: int = 0) -> dict:
    """HW (generated: ``inertia_tensor``), SUBS (the honest students' solutions and the
    thief's notebook) and the instructor's canary under ``base``, owned by ``owner``."""
    hw, subs = base / "HW", base / "subs"
    canary = base / "instructor" / "canary.txt"
    canary.parent.mkdir(parents=True)
    canary.write_text(CANARY_TEXT)
    roster = Roster(("id",), tuple({"id": s} for s in (*HONEST, THIEF)))
    generate_assignment(roster, hw, FAMILIES, problems=["inertia_tensor"], seed=5)
    subs.mkdir()
    for sid in HONEST:
        shutil.copy(hw / "solutions" / f"{sid}.ipynb", subs / f"{sid}.ipynb")
    nb = json.loads((hw / "release" / f"{THIEF}.ipynb").read_text())
    cell = THIEF_CELL.format(key=str(hw / "key.json"), canary=str(canary))
    nb["cells"].append(new_code_cell(cell, id="thief"))  # after the answer cells
    (subs / f"{THIEF}.ipynb").write_text(json.dumps(nb))
    for path in [base, *base.rglob("*")]:
        os.lchown(path, owner, owner)
    return {"base": base, "hw": hw, "subs": subs, "canary": canary,
            "digest": digest(hw), "max_points": max_points(hw)}


def digest(folder: Path) -> dict[str, str]:
    """Relative path → SHA-256 of every file below ``folder`` (its ``graded`` folder aside)."""
    return {str(p.relative_to(folder)): hashlib.sha256(p.read_bytes()).hexdigest()
            for p in sorted(folder.rglob("*"))
            if p.is_file() and p.relative_to(folder).parts[0] != "graded"}


def max_points(hw: Path) -> dict[str, float]:
    key = json.loads((hw / "key.json").read_text())
    return {sid: sum(a["points"] for q in s["questions"] for a in q["answers"])
            for sid, s in key["students"].items()}


def eulertop(args: list[str], *, python: str = sys.executable, cwd: Path,
             path_first: Path | None = None, uid: int | None = None,
             reach: list[str] = (), prefix: list[str] = (), timeout: float = 300,
             env: dict | None = None) -> subprocess.CompletedProcess:
    """``python -m eulertop ARGS`` in ``cwd``, as root or as ``uid`` (an ordinary user, with the
    folders of ``reach`` made passable as a laptop user's are), with ``path_first`` first on
    ``PATH`` and ``prefix`` (a launcher) before it all."""
    from grader.sandbox import _as_user, _python_paths

    path = os.environ.get("PATH", os.defpath)
    variables = {"PATH": f"{path_first}{os.pathsep}{path}" if path_first else path,
                 "LANG": "C.UTF-8", "HOME": str(cwd), "TMPDIR": "/tmp", **(env or {})}
    argv = [python, "-m", "eulertop", *args]
    if uid is not None:
        argv = [*_as_user(uid, [*_python_paths(), str(ROOT), *reach]), *argv]
    return subprocess.run([*prefix, *argv], cwd=cwd, env=variables, capture_output=True,
                          text=True, timeout=timeout)


def results(out: Path) -> dict[str, dict]:
    return {p.stem: json.loads(p.read_text()) for p in sorted((out / "results").glob("*.json"))}


def assert_graded_in_full_and_safe(cls: dict, out: Path, done: subprocess.CompletedProcess,
                                   tier: str) -> dict[str, dict]:
    """The honest students got every point, the thief none, the key and the canary are as
    they were, and every record and the run's header name ``tier``; the records."""
    assert done.returncode == 0, done.stderr[-3000:]
    assert f"eulertop grade: isolation: {tier}:" in done.stderr, done.stderr[-2000:]
    got = results(out)
    assert set(got) == {*HONEST, THIEF}, done.stderr[-2000:]
    for sid in HONEST:
        assert got[sid]["status"] == "graded", got[sid]["message"]
        assert got[sid]["points"] == cls["max_points"][sid]
    assert got[THIEF]["status"] == "graded" and got[THIEF]["points"] == 0, got[THIEF]
    for record in got.values():
        assert record["execution"]["isolation"].startswith(f"{tier}:"), record["execution"]
    assert cls["canary"].read_text() == CANARY_TEXT
    assert digest(cls["hw"]) == cls["digest"]
    return got


def dependencies_line() -> str:
    """This run's site-packages, for a ``.pth`` file: the dependencies without eulertop (an
    editable install's finder is a ``.pth`` of that folder, which a path line does not run)."""
    return sysconfig.get_paths()["purelib"] + "\n"


def private_venv(folder: Path, source: bool = False) -> tuple[Path, Path]:
    """A virtual environment in ``folder`` (no pip): its python and its site-packages, which
    reach this run's dependencies (and with ``source`` this project's folder)."""
    subprocess.run([sys.executable, "-m", "venv", "--without-pip", str(folder / "venv")],
                   check=True, timeout=120)
    site = folder / "venv" / Path(sysconfig.get_paths()["purelib"]).relative_to(sys.prefix)
    (site / "eulertop_test_dependencies.pth").write_text(
        dependencies_line() + (f"{ROOT}\n" if source else ""))
    return folder / "venv" / "bin" / "python", site
