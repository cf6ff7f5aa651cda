"""Fixtures of the hosted entrypoints' tests.

``hosted_hw`` (session)
    A generated assignment (two quick problem families, seed 11) for ``alice`` and ``bob``, whose
    roster has an ``email`` column, as a Gradescope course's would.
``public_tmp``
    A fresh folder under ``/tmp`` that every user may traverse (pytest's own temporary folders
    are private to root, which would hide the key from another uid for the wrong reason).
``kernel_uid``
    A fresh uid for the test's kernels (``$EULERTOP_KERNEL_USER``). Skips where the grader is
    not root (there is no other user to be). Where this Python lives where other users cannot
    run it (a pyenv under ``/root``, as on CI) but a container's would be runnable
    (``/usr/bin/python3``), the entrypoints run as a program in a *container layout*
    (:func:`container_layout`): the same file system, but for the closed folders above this
    Python, made passable as a container's are; without bubblewrap to make it, it fails.
``notebooks``
    Submissions built from the generated notebooks: ``right``, ``wrong``, ``broken``,
    ``oversized``, ``key_reader(key_path)`` (see :class:`Notebooks`).
"""

from __future__ import annotations

import copy
import json
import os
import secrets
import shutil
import subprocess
import sys
import tempfile
from dataclasses import dataclass
from pathlib import Path

import pytest

from problems.generate import generate_assignment
from problems.roster import read_roster
from problems.templates import FAMILIES

REPO = Path(__file__).resolve().parents[3]
ROSTER = "id,name,email\nalice,Alice A,alice@uni.edu\nbob,Bob B,bob@uni.edu\n"
PROBLEMS = ["inertia_tensor", "energy_momentum"]


@dataclass(frozen=True)
class HW:
    folder: Path
    key: dict

    def notebook(self, kind: str, sid: str) -> dict:
        return json.loads((self.folder / kind / f"{sid}.ipynb").read_text(encoding="utf-8"))

    def answers(self, sid: str) -> list[dict]:
        """The key's answers of ``sid`` with their variable names (``q<k>_<name>``)."""
        return [{**a, "variable": f"q{q['question']}_{a['name']}"}
                for q in self.key["students"][sid]["questions"] for a in q["answers"]]

    def max_points(self, sid: str) -> float:
        return sum(a["points"] for a in self.answers(sid))


@pytest.fixture(scope="session")
def hosted_hw(tmp_path_factory) -> HW:
    root = tmp_path_factory.mktemp("hosted")
    (root / "roster.csv").write_text(ROSTER, encoding="utf-8")
    folder = root / "HW"
    generate_assignment(read_roster(root / "roster.csv"), folder, FAMILIES, problems=PROBLEMS,
                        seed=11, title="Tops")
    return HW(folder, json.loads((folder / "key.json").read_text(encoding="utf-8")))


@pytest.fixture
def public_tmp():
    folder = Path(tempfile.mkdtemp(prefix="eulertop-hosted-test-", dir="/tmp"))
    folder.chmod(0o755)
    yield folder
    shutil.rmtree(folder, ignore_errors=True)


LAYOUT: list[str] = []
"""The argv prefix of the container layout the entrypoints run in, [] for none (in-process);
set by :func:`kernel_uid` for one test."""


def container_layout() -> list[str] | None:
    """As root with bubblewrap: a root ``bwrap`` (all capabilities kept: the entrypoint is
    root in a container) whose mount namespace makes the folders above this Python and this
    project passable by every user; None where bubblewrap cannot run."""
    from grader.sandbox import _python_paths, passable

    prefix = passable([*_python_paths(), str(REPO)], ["ALL"])
    if not prefix:
        return []
    probe = subprocess.run([*prefix, "true"], capture_output=True, timeout=30)
    return prefix if probe.returncode == 0 else None


@pytest.fixture
def kernel_uid(monkeypatch) -> int:
    """A uid of the tests' own for kernels (``$EULERTOP_KERNEL_USER``): no process of another
    user of this machine (``nobody``'s, say) is ever counted or killed as the kernel's."""
    from grader.kernels.container import USER_VARIABLE, check_interpreter, kernel_user

    if os.geteuid() != 0:
        pytest.skip("needs root: there is no other user to run the kernel as")
    monkeypatch.setenv(USER_VARIABLE, str(0x5E000000 + secrets.randbelow(0x100000)))
    user = kernel_user()
    why = check_interpreter(user)
    if why is not None:
        layout = container_layout()
        if not layout:  # bubblewrap is required (README): fail, never skip
            pytest.fail(f"{why}; and no bubblewrap here to lay the file system out as a "
                        "container's (apt-get install bubblewrap)", pytrace=False)
        monkeypatch.setattr(sys.modules[__name__], "LAYOUT", layout)
    return user.uid


def run_entrypoint(module, variable: str, root: Path, monkeypatch) -> int:
    """Run the entrypoint ``module`` (its ``main``) with ``$variable`` = ``root``: in this
    process, or as ``python -m module`` in the container layout if :func:`kernel_uid` chose
    one. Its exit status."""
    monkeypatch.setenv(variable, str(root))
    if not LAYOUT:
        return module.main([])
    done = subprocess.run([*LAYOUT, sys.executable, "-m", module.__name__], cwd=REPO,
                          env=dict(os.environ), capture_output=True, text=True, timeout=600)
    if done.returncode not in (0, 1):
        raise AssertionError(f"{module.__name__} failed ({done.returncode}):\n{done.stderr}")
    return done.returncode


def code_cell(source: str) -> dict:
    return {"cell_type": "code", "metadata": {}, "source": source, "outputs": [],
            "execution_count": None}


class Notebooks:
    """Submissions for one student, as file bytes."""

    def __init__(self, hw: HW) -> None:
        self.hw = hw

    @staticmethod
    def _bytes(nb: dict) -> bytes:
        return json.dumps(nb, indent=1).encode()

    def right(self, sid: str = "alice") -> bytes:
        """The solutions notebook: every answer the key's."""
        return self._bytes(self.hw.notebook("solutions", sid))

    def wrong(self, sid: str = "alice") -> tuple[bytes, float]:
        """The solutions with every vector answer replaced by twice it plus one; and the points
        it should still get (those of the other answers)."""
        nb = copy.deepcopy(self.hw.notebook("solutions", sid))
        changed = [a for a in self.hw.answers(sid) if a["kind"] == "vector"]
        lines = [f"{a['variable']} = [2 * x + 1 for x in {a['variable']}]" for a in changed]
        nb["cells"].append(code_cell("\n".join(lines)))
        kept = self.hw.max_points(sid) - sum(a["points"] for a in changed)
        return self._bytes(nb), kept

    def broken(self) -> bytes:
        """Not JSON: a notebook cut short."""
        return b'{"cells": [{"cell_type": "code", "sour'

    def oversized(self, sid: str, size: int) -> bytes:
        """The right notebook padded past ``size`` bytes with a markdown cell."""
        nb = copy.deepcopy(self.hw.notebook("solutions", sid))
        nb["cells"].append({"cell_type": "markdown", "metadata": {}, "source": "x" * size})
        return self._bytes(nb)

    def key_reader(self, sid: str, key_path: Path, key_sid: str | None = None) -> bytes:
        """The release notebook (no answers) plus a cell that reads every answer from the key
        file at ``key_path`` (the ``key_sid`` entry, default ``sid``): full marks iff the key
        could be read."""
        nb = copy.deepcopy(self.hw.notebook("release", sid))
        source = (
            "import json\n"
            "try:\n"
            f"    _key = json.load(open({str(key_path)!r}))\n"
            f"    for _q in _key['students'][{key_sid or sid!r}]['questions']:\n"
            "        for _a in _q['answers']:\n"
            "            globals()[f\"q{_q['question']}_{_a['name']}\"] = _a['value']\n"
            "except Exception as _e:\n"
            "    print('could not read the key:', _e)\n"
        )
        nb["cells"].append(code_cell(source))
        return self._bytes(nb)


@pytest.fixture
def notebooks(hosted_hw) -> Notebooks:
    return Notebooks(hosted_hw)
