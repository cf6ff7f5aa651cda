"""The container image for instructors on macOS or Windows (issue 22): its steps, run here.

No Docker engine runs in CI, so the image is not built; its steps are checked and then played
in a container's layout, as the hosted tests do (:func:`tests.grader.hosted.conftest.
container_layout`: the same file system, the closed folders above this Python made passable):

* the ``Dockerfile`` copies every package the project installs (``pyproject.toml``'s
  ``packages.find``), its ``pyproject.toml`` and ``README.md``, and nothing ``.dockerignore``
  leaves out; it installs bubblewrap and the copied project, non-editable; its entry point is
  ``eulertop`` and its working folder the mounted one;
* what ``pip install .`` of those copies installs grades, with README's own ``docker run`` line
  (its arguments after the image's name), a class in a folder of its own, where bubblewrap
  fails as under Docker's default seccomp profile: in the ``container`` tier, honest students
  in full, the thief's key out of reach.
"""

from __future__ import annotations

import fnmatch
import os
import re
import shlex
import shutil
import subprocess
import sys
import tempfile
import tomllib
from pathlib import Path

import pytest

from tests.grader.tiers_support import (
    assert_graded_in_full_and_safe,
    eulertop,
    fake_bwrap,
    make_class,
    private_venv,
)

ROOT = Path(__file__).resolve().parents[1]
DOCKERFILE = (ROOT / "Dockerfile").read_text()
IGNORED = [line.strip() for line in (ROOT / ".dockerignore").read_text().splitlines()
           if line.strip() and not line.startswith("#")]
README = (ROOT / "README.md").read_text()


def instructions(keyword: str) -> list[str]:
    """The arguments of every ``keyword`` instruction of the Dockerfile (continuations
    joined)."""
    text = re.sub(r"\\\n\s*", " ", DOCKERFILE)
    return [m.group(1).strip() for m in re.finditer(rf"^{keyword}\s+(.+)$", text, re.M)]


def copied() -> list[str]:
    """The sources of the Dockerfile's ``COPY`` instructions."""
    return [src for args in instructions("COPY") for src in shlex.split(args)[:-1]]


def test_the_image_copies_what_the_project_installs_and_nothing_it_ignores():
    project = tomllib.loads((ROOT / "pyproject.toml").read_text())
    packages = {p.split(".")[0].rstrip("*") for p in project["tool"]["setuptools"]["packages"]
                ["find"]["include"]}  # "eulertop.*" is the package eulertop
    sources = {Path(s).name for s in copied()}
    assert packages | {"pyproject.toml", "README.md"} <= sources, sources
    for source in copied():
        assert (ROOT / source).exists(), source
        assert not any(fnmatch.fnmatch(source, pattern) for pattern in IGNORED), source
    for folder in ("tests", ".venv", ".git"):
        assert folder in IGNORED  # nothing of a checkout's own state enters the image


def test_the_image_installs_bubblewrap_and_the_project_and_runs_eulertop_in_work():
    runs = " ".join(instructions("RUN"))
    assert "apt-get install" in runs and "bubblewrap" in runs
    assert re.search(r"pip install (--no-cache-dir )?\.", runs)  # the copy, not editable
    assert instructions("ENTRYPOINT") == ['["eulertop"]']
    assert instructions("WORKDIR")[-1] == "/work"


def readme_docker_run() -> list[str]:
    """README's ``docker run`` line for grading: eulertop's arguments after the image."""
    match = re.search(r'^docker run --rm -v "\$PWD":/work eulertop ([^#\n]+)', README, re.M)
    assert match, "README has no 'docker run … eulertop grade …' line"
    return shlex.split(match.group(1))


@pytest.fixture
def image_root():
    folder = Path(tempfile.mkdtemp(prefix="eulertop-image-", dir="/tmp"))
    folder.chmod(0o755)
    yield folder
    shutil.rmtree(folder, ignore_errors=True)


def test_readme_s_docker_run_line_grades_a_folder_in_the_container_tier(image_root):
    from tests.grader.hosted.conftest import container_layout

    if os.geteuid() != 0:
        pytest.fail("runs as root (CI does): the container mode needs other uids", pytrace=False)
    layout = container_layout()
    assert layout is not None, "bubblewrap could not lay out a container's file system"
    opt = image_root / "opt" / "eulertop"  # COPY …, as the Dockerfile does
    opt.mkdir(parents=True)
    for source in copied():
        (shutil.copytree if (ROOT / source).is_dir() else shutil.copy)(
            ROOT / source, opt / Path(source).name)
    python, site = private_venv(image_root / "python")  # RUN pip install .
    done = subprocess.run([sys.executable, "-m", "pip", "install", "-q", "--no-deps",
                           "--disable-pip-version-check", "--target", str(site), str(opt)],
                          capture_output=True, text=True, timeout=600)
    assert done.returncode == 0, done.stderr
    args = readme_docker_run()
    assert args[0] == "grade"
    cls = make_class(image_root / "work")
    (cls["base"] / "subs").rename(cls["base"] / args[2])
    cls["subs"] = cls["base"] / args[2]
    done = eulertop([*args, "--jobs", "2"], python=str(python), cwd=cls["base"],
                    path_first=fake_bwrap(image_root, "docker"), prefix=layout)
    assert_graded_in_full_and_safe(cls, cls["base"] / args[1] / "graded", done, "container")
