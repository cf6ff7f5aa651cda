"""Issue 22: eulertop grades from wherever it is installed.

Round 2's demo, from a virtual environment in a private folder under /tmp (``mktemp -d``: mode
0700; how CI jobs, tox and many scripts make one), recorded every student as failed: the
kernel's sandbox mounts a fresh /tmp and binds the Python back, and a file bound inside it
could not be bound again. Here the same class is graded, as root and as an ordinary user, from

* a virtual environment in a 0700 folder under /tmp, eulertop installed from its wheel (not
  editable);
* the same, with eulertop installed editable from a copy of the project in that folder;
* a user site (``pip install --user``) in a private home folder, with the system's Python;

each run from a working folder inside the private folder. What is measured: the honest
students' full marks, the thief's 0 and the key and canary unchanged
(:func:`tests.grader.tiers_support.assert_graded_in_full_and_safe`), and that the eulertop that
ran was the one installed there (its ``eulertop doctor`` line).

The environments reuse this test run's installed dependencies (numpy, nbclient, …) through a
``.pth`` line: what they have of their own, in the private folder, is eulertop itself and the
interpreter's prefix.
"""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

import pytest

from grader.sandbox import available
from tests.grader.tiers_support import (
    ROOT,
    assert_graded_in_full_and_safe,
    dependencies_line,
    eulertop,
    make_class,
    ordinary_user,
    private_venv,
)

SOURCES = ("pyproject.toml", "README.md", "solver", "problems", "grader", "eulertop",
           "eulertop_base")
"""What a copy of the project needs to be installed."""


@pytest.fixture(scope="module", autouse=True)
def _required_here():
    if os.geteuid() != 0:
        pytest.fail("these tests run as root (CI does), to act as root and as an ordinary user",
                    pytrace=False)
    if available() is None:
        pytest.fail("bubblewrap is not installed: `apt-get install bubblewrap` (README)",
                    pytrace=False)


def copy_project(dest: Path) -> Path:
    """The project's installable files copied to ``dest`` (no caches, no build folders)."""
    dest.mkdir(parents=True)
    ignore = shutil.ignore_patterns("__pycache__", "*.egg-info", "build", ".venv")
    for name in SOURCES:
        source = ROOT / name
        if source.is_dir():
            shutil.copytree(source, dest / name, ignore=ignore)
        else:
            shutil.copy(source, dest / name)
    return dest


def pip(*args: str) -> None:
    done = subprocess.run([sys.executable, "-m", "pip", "--disable-pip-version-check", "-q",
                           *args], capture_output=True, text=True, timeout=600)
    assert done.returncode == 0, done.stdout + done.stderr


@pytest.fixture(scope="module")
def wheel(tmp_path_factory) -> Path:
    """eulertop's wheel, built once from a copy of the project."""
    base = tmp_path_factory.mktemp("wheel")
    pip("wheel", "--no-deps", "-w", str(base / "dist"), str(copy_project(base / "src")))
    (found,) = (base / "dist").glob("eulertop-*.whl")
    return found


@pytest.fixture
def private_tmp():
    """A folder as ``mktemp -d`` makes it: under /tmp, mode 0700."""
    folder = Path(tempfile.mkdtemp(dir="/tmp"))
    assert folder.stat().st_mode & 0o777 == 0o700
    yield folder
    shutil.rmtree(folder, ignore_errors=True)


def _chown(folder: Path, uid: int) -> None:
    for path in [folder, *folder.rglob("*")]:
        os.lchown(path, uid, uid)


def _ran_from(python: Path, cwd: Path, uid: int | None, where: Path, reach,
              env: dict | None = None) -> None:
    """That eulertop was the one installed at ``where``: ``eulertop doctor`` says so."""
    done = eulertop(["doctor"], python=str(python), cwd=cwd, uid=uid, reach=reach, env=env)
    line = next(x for x in done.stdout.splitlines() if x.startswith("eulertop "))
    assert str(where) in line, done.stdout
    assert done.returncode == 0, done.stdout + done.stderr


@pytest.mark.parametrize("who", ["root", "ordinary user"])
@pytest.mark.parametrize("how", ["wheel", "editable"])
def test_a_venv_in_a_private_folder_under_tmp(private_tmp, wheel, who, how):
    uid = None if who == "root" else ordinary_user()
    python, site = private_venv(private_tmp)
    if how == "wheel":
        pip("install", "--no-deps", "--no-index", "--target", str(site), str(wheel))
        where = site
    else:
        where = copy_project(private_tmp / "eulertop-clone")
        pip("install", "--no-deps", "--target", str(site), "-e", str(where))
    cls = make_class(private_tmp / "class")
    if uid is not None:
        _chown(private_tmp, uid)
    done = eulertop(["grade", "HW", "subs", "--jobs", "2", "--timeout", "60"],
                    python=str(python), cwd=cls["base"], uid=uid, reach=[str(private_tmp)])
    assert_graded_in_full_and_safe(cls, cls["hw"] / "graded", done, "world")
    _ran_from(python, cls["base"], uid, where, [str(private_tmp)])


def test_a_user_site_in_a_private_home(private_tmp, wheel):
    """``pip install --user`` into a home folder of mode 0700, run by the system's Python
    (this run's base interpreter), as the ordinary user whose home it is."""
    uid = ordinary_user()
    home = private_tmp / "home"
    userbase = home / ".local"
    env = {"PYTHONUSERBASE": str(userbase), "HOME": str(home)}
    base_python = Path(sys.base_prefix) / "bin" / f"python{sys.version_info[0]}"
    probe = subprocess.run([str(base_python), "-c",
                            "import site; print(site.getusersitepackages())"],
                           env={**env, "PATH": os.defpath}, capture_output=True, text=True,
                           check=True)
    site = Path(probe.stdout.strip())
    site.mkdir(parents=True)
    pip("install", "--no-deps", "--no-index", "--target", str(site), str(wheel))
    (site / "eulertop_test_dependencies.pth").write_text(dependencies_line())
    cls = make_class(home / "class")
    home.chmod(0o700)
    _chown(private_tmp, uid)
    done = eulertop(["grade", "HW", "subs", "--jobs", "2", "--timeout", "60"],
                    python=str(base_python), cwd=cls["base"], uid=uid,
                    reach=[str(private_tmp)], env=env)
    assert_graded_in_full_and_safe(cls, cls["hw"] / "graded", done, "world")
    _ran_from(base_python, cls["base"], uid, site, [str(private_tmp)], env)
