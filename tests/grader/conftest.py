"""Shared fixtures of the grader's tests.

Fixtures (names are the contract with other test files; keep them stable)

``generated_assignment`` (session)
    A real assignment made once by :func:`problems.generate.generate_assignment` (every
    catalogue family, seed 2024) for the roster ``alice, bob``, in a session temporary folder.
    A :class:`GeneratedAssignment`: ``.hw`` (the folder), ``.key`` (``key.json`` loaded),
    ``.release(sid)`` / ``.solutions(sid)`` (paths), ``.notebook(kind, sid)`` (the v4 dict),
    ``.specs(sid)`` (public answer specs from the notebook metadata), ``.variables(sid)``,
    ``.key_values(sid)`` (variable → key value, from ``key.json``).
``write_golden``
    ``write_golden(name, folder=None, student="alice", file_name=None) -> Path``: writes golden
    notebook ``name`` (``tests/grader/golden``: ``BUILDERS``) for that student and returns its
    path (default folder: the test's ``tmp_path``; default file name ``<student>.ipynb``, as a
    submission is named).
``fast_limits``
    :class:`grader.limits.Limits` for tests: 2 s per cell, 30 s in all, 1.5 GiB, 100 kB output.
``canary``
    Sets the environment variable ``golden.CANARY`` in the grader process for the test; returns
    its (secret) value.
"""

from __future__ import annotations

import json
from dataclasses import dataclass
from pathlib import Path

import pytest

from grader.limits import Limits
from problems.generate import generate_assignment
from problems.roster import read_roster
from problems.templates import FAMILIES
from tests.grader.golden import BUILDERS, CANARY

STUDENTS = ("alice", "bob")


@dataclass(frozen=True)
class GeneratedAssignment:
    """A generated assignment folder and easy access to what the tests need from it."""

    hw: Path
    key: dict

    def release(self, sid: str = "alice") -> Path:
        return self.hw / "release" / f"{sid}.ipynb"

    def solutions(self, sid: str = "alice") -> Path:
        return self.hw / "solutions" / f"{sid}.ipynb"

    def notebook(self, kind: str, sid: str = "alice") -> dict:
        return json.loads((self.hw / kind / f"{sid}.ipynb").read_text(encoding="utf-8"))

    def specs(self, sid: str = "alice") -> tuple[dict, ...]:
        meta = self.notebook("release", sid)["metadata"]["eulertop"]
        return tuple(a for q in meta["questions"] for a in q["answers"])

    def variables(self, sid: str = "alice") -> tuple[str, ...]:
        return tuple(s["variable"] for s in self.specs(sid))

    def key_values(self, sid: str = "alice") -> dict:
        return {f"q{q['question']}_{a['name']}": a["value"]
                for q in self.key["students"][sid]["questions"] for a in q["answers"]}


@pytest.fixture(scope="session")
def generated_assignment(tmp_path_factory) -> GeneratedAssignment:
    root = tmp_path_factory.mktemp("generated")
    roster = root / "roster.csv"
    roster.write_text("id,name\n" + "".join(f"{s},{s.title()}\n" for s in STUDENTS),
                      encoding="utf-8")
    hw = root / "HW"
    generate_assignment(read_roster(roster), hw, FAMILIES, seed=2024, title="Tops")
    return GeneratedAssignment(hw, json.loads((hw / "key.json").read_text(encoding="utf-8")))


@pytest.fixture
def write_golden(generated_assignment, tmp_path):
    def write(name: str, folder: Path | None = None, student: str = "alice",
              file_name: str | None = None) -> Path:
        a = generated_assignment
        content = BUILDERS[name](a.notebook("solutions", student), a.notebook("release", student),
                                 a.specs(student), a.hw)
        path = Path(folder or tmp_path) / (file_name or f"{student}.ipynb")
        path.parent.mkdir(parents=True, exist_ok=True)
        if isinstance(content, bytes):
            path.write_bytes(content)
        else:
            path.write_text(json.dumps(content, indent=1), encoding="utf-8")
        return path

    return write


@pytest.fixture
def fast_limits() -> Limits:
    return Limits(cell_timeout=2.0, total_timeout=30.0, memory_bytes=3 * 1024**3 // 2,
                  output_bytes=100_000)


@pytest.fixture
def canary(monkeypatch) -> str:
    secret = "canary-7f3a-do-not-leak"
    monkeypatch.setenv(CANARY, secret)
    return secret
