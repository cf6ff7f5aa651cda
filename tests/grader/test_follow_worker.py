"""The follow-through worker a rescore starts ahead (grader/follow_through.py, warm_worker): it
imports the built-in families while the records are read, is the one worker the rescore uses,
and has ended when the rescore has — whether it was needed, turned off or the change failed."""

from __future__ import annotations

import json
import shutil
from dataclasses import replace
from pathlib import Path

import pytest

from grader import follow_through
from grader import rescore as rescore_module
from grader.assignment import UsageError, load_assignment
from grader.follow_through import FollowThrough, FollowWorker, warm_worker
from grader.pipeline import grade_assignment
from grader.rescore import rescore
from grader.results import read_result
from problems.generate import generate_assignment
from problems.roster import Roster
from problems.templates import FAMILIES
from tests.grader.report.synthetic_class import (
    LiteralExecute,
    followed_from_a_slip,
    literal_notebook,
)

STUDENTS = ("ann", "ben", "cy")


@pytest.fixture(scope="module")
def graded(tmp_path_factory) -> Path:
    root = tmp_path_factory.mktemp("warm")
    hw, subs = root / "HW", root / "subs"
    roster = Roster(("id", "name"), tuple({"id": s, "name": s} for s in STUDENTS))
    generate_assignment(roster, hw, FAMILIES, problems=["heavy_top_constants"], seed=4)
    subs.mkdir()
    manifest, key = (json.loads((hw / name).read_text()) for name in ("assignment.json",
                                                                       "key.json"))
    for sid in STUDENTS:
        answers, _ = followed_from_a_slip(manifest, key, sid)
        (subs / f"{sid}.ipynb").write_text(literal_notebook(answers))
    grade_assignment(hw, subs, limits="LIMITS", execute=LiteralExecute(), jobs=1)
    return hw


@pytest.fixture
def workers(monkeypatch) -> list[FollowWorker]:
    """Every follow-through worker started, in order."""
    started: list[FollowWorker] = []
    real = FollowWorker.__init__

    def counted(self, warm: bool = False) -> None:
        real(self, warm)
        self.warm = warm
        started.append(self)

    monkeypatch.setattr(FollowWorker, "__init__", counted)
    return started


def _statuses(hw: Path) -> dict:
    return {(sid, a.variable): (a.verdict.status, a.verdict.points) for sid in STUDENTS
            for a in read_result(hw / "graded" / "results" / f"{sid}.json").answers}


def test_a_rescore_uses_the_one_worker_it_started_ahead_and_ends_it(graded, tmp_path,
                                                                     workers):
    copy = Path(shutil.copytree(graded, tmp_path / "HW"))
    before = _statuses(graded)
    assert any(status == "follows" for status, _ in before.values())  # credit was computed
    rescore(copy)
    assert [w.warm for w in workers] == [True]  # no second worker: the one started ahead
    assert workers[0].process.poll() is not None  # ended with the rescore
    assert _statuses(copy) == before  # the same credit as grading gave


def test_no_worker_is_started_ahead_where_credit_is_off(graded, workers):
    a = load_assignment(graded)
    off = replace(a, manifest={**a.manifest, follow_through.FRACTION_KEY: 0})
    assert warm_worker(off) is None and workers == []
    worker = warm_worker(a)
    assert FollowThrough.of(off, worker) is None
    assert worker.process.wait(timeout=30) is not None  # taken and ended by of()


def test_a_failed_change_ends_the_worker_started_ahead(graded, tmp_path, workers,
                                                       monkeypatch):
    copy = Path(shutil.copytree(graded, tmp_path / "HW"))

    def refused(*args, **kwargs):
        raise UsageError("refused for the test")

    monkeypatch.setattr(rescore_module, "_amended", refused)
    with pytest.raises(UsageError, match="refused for the test"):
        rescore(copy)
    assert [w.warm for w in workers] == [True]
    assert workers[0].process.wait(timeout=30) is not None
