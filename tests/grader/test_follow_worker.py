"""The follow-through worker a rescore starts ahead (grader/follow_through.py, warm_worker): it
imports the built-in families while the records are read, is the one worker the rescore uses,
and has ended when the rescore has — whether it was needed, turned off or the change failed."""

from __future__ import annotations

import json
import shutil
from dataclasses import replace
from pathlib import Path

import nbformat
import numpy as np
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
from tests.grader.report.synthetic_class import LiteralExecute

STUDENTS = ("ann", "ben", "cy")


def _submission(hw: Path, sid: str) -> str:
    """The key's answers, but each chain's first answer 20 % off and the later ones worked out
    from it (what earns follow-through credit)."""
    manifest = json.loads((hw / "assignment.json").read_text())
    key = json.loads((hw / "key.json").read_text())
    answers = {}
    for question, entry in zip(manifest["students"][sid]["questions"],
                               key["students"][sid]["questions"], strict=True):
        values = {a["name"]: a["value"] for a in entry["answers"]}
        k = question["question"]
        answers |= {f"q{k}_{n}": v for n, v in values.items()}
        for a in entry["answers"]:
            first = (a.get("depends_on") or [None])[0]
            if first is None or not isinstance(values[first], float):
                continue
            earlier = dict(values, **{first: values[first] * 1.2})
            value = FAMILIES[question["family"]].follow(
                a["name"], question["parameters"], {d: earlier[d] for d in a["depends_on"]})
            answers[f"q{k}_{first}"] = earlier[first]
            answers[f"q{k}_{a['name']}"] = np.asarray(value).tolist()
    code = "\n".join(f"{name} = {value!r}" for name, value in answers.items())
    return nbformat.writes(nbformat.v4.new_notebook(cells=[nbformat.v4.new_code_cell(code)]))


@pytest.fixture(scope="module")
def graded(tmp_path_factory) -> Path:
    root = tmp_path_factory.mktemp("warm")
    hw, subs = root / "HW", root / "subs"
    roster = Roster(("id", "name"), tuple({"id": s, "name": s} for s in STUDENTS))
    generate_assignment(roster, hw, FAMILIES, problems=["heavy_top_constants"], seed=4)
    subs.mkdir()
    for sid in STUDENTS:
        (subs / f"{sid}.ipynb").write_text(_submission(hw, sid))
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
