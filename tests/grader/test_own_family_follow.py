"""Follow-through credit with a family of the instructor's own (issue 30): a key change that
turns the earlier answer right keeps the later answer's credit (``key set q1_a --rtol 0.08``,
the issue's q1_t 1 → 0), the family's own degenerate case reaches the feedback, and a family
file edited after ``generate`` is refused by ``rescore`` and recorded by ``rekey``."""

from __future__ import annotations

import json
import re
from pathlib import Path

import pytest

from eulertop.cli import main
from grader.audit import read_trail
from grader.pipeline import grade_assignment
from grader.results import read_result
from tests.grader.lever_family import key_values, lever_assignment, notebook
from tests.grader.report.synthetic_class import LiteralExecute

STUDENTS = ("near", "negative", "right")


def _submissions(hw: Path, folder: Path) -> Path:
    """``near``: an arm 5 % off and t worked out from it; ``negative``: that arm with its sign
    flipped and t worked out from it; ``right``: the key's."""
    folder.mkdir()
    for sid in STUDENTS:
        a = key_values(hw, sid)["q1_a"]
        mine = {"near": 1.05 * a, "negative": -1.05 * a, "right": a}[sid]
        (folder / f"{sid}.ipynb").write_text(notebook({"q1_a": mine, "q1_t": mine**2}))
    return folder


@pytest.fixture
def graded(tmp_path) -> Path:
    hw = lever_assignment(tmp_path, STUDENTS)
    grade_assignment(hw, _submissions(hw, tmp_path / "subs"), limits="LIMITS",
                     execute=LiteralExecute(), jobs=1)
    return hw


def _verdict(hw: Path, sid: str, variable: str):
    record = read_result(hw / "graded" / "results" / f"{sid}.json")
    return next(a.verdict for a in record.answers if a.variable == variable)


def test_widening_the_earlier_tolerance_keeps_the_later_credit(graded, capsys):
    assert _verdict(graded, "near", "q1_a").status == "wrong"
    assert (_verdict(graded, "near", "q1_t").status, _verdict(graded, "near", "q1_t").points) \
        == ("follows", 1.0)
    assert main(["key", "set", str(graded), "q1_a", "--rtol", "0.08"]) == 0
    out = capsys.readouterr().out
    assert re.search(r"near\s+q1_a\s+0 → 1", out), out
    assert "q1_t" not in out  # its points did not change
    a, t = _verdict(graded, "near", "q1_a"), _verdict(graded, "near", "q1_t")
    assert a.status == "correct"
    assert (t.status, t.points) == ("follows", 1.0), t.message
    assert "follows from your q1_a = " in t.message


def test_the_family_s_own_case_says_why(graded):
    t = _verdict(graded, "negative", "q1_t")
    assert (t.status, t.points) == ("wrong", 0.0)
    assert t.message.endswith("; no follow-through: your q1_a is negative: no arm is, so q1_t "
                              "from it shows nothing")
    assert _verdict(graded, "right", "q1_t").status == "correct"


def _files(folder: Path) -> dict[Path, bytes]:
    return {p: p.read_bytes() for p in folder.rglob("*") if p.is_file()}


def test_an_edited_family_file_is_refused_by_rescore_and_recorded_by_rekey(graded, capsys):
    family = graded.parent / "mine" / "lever.py"
    recorded = json.loads((graded / "assignment.json").read_text())["families"]["lever"]
    family.write_text(family.read_text().replace("earlier[\"a\"] ** 2",
                                                 "earlier[\"a\"] ** 2 * 1.0 + 0.0"))
    before = _files(graded)
    assert main(["rescore", str(graded)]) == 2
    err = capsys.readouterr().err
    assert err.startswith("eulertop rescore: ") and "Traceback" not in err
    assert f"{graded.parent / 'mine' / 'lever.py'}, family 'lever', changed" in err
    assert f"recorded sha256 {recorded['sha256'][:12]}" in err
    assert f"run 'eulertop rekey {graded}'" in err
    assert _files(graded) == before  # nothing written

    assert main(["rekey", str(graded), "--dry-run"]) == 0
    assert "its new sha256 would be recorded (--dry-run)" in capsys.readouterr().out
    assert _files(graded) == before

    assert main(["rekey", str(graded)]) == 0
    out = capsys.readouterr().out
    assert "family 'lever', changed" in out and "recomputed with it" in out
    assert f"its new sha256 recorded in {graded / 'assignment.json'}" in out
    now = json.loads((graded / "assignment.json").read_text())["families"]["lever"]
    assert now["file"] == recorded["file"]
    assert now["sha256"] != recorded["sha256"]
    import hashlib
    assert now["sha256"] == hashlib.sha256(family.read_bytes()).hexdigest()
    event = read_trail(graded / "graded")[-1]
    assert event["event"] == "rekey"
    assert event["family_files"] == [{"family": "lever", "file": recorded["file"],
                                      "was": recorded["sha256"], "now": now["sha256"]}]

    assert main(["rescore", str(graded)]) == 0
    assert "rescored" in capsys.readouterr().out
    assert _verdict(graded, "near", "q1_t").status == "follows"


def test_a_family_file_that_is_gone_is_named(graded, capsys):
    (graded.parent / "mine" / "lever.py").unlink()
    assert main(["rescore", str(graded)]) == 2
    assert "family 'lever', is gone since 'eulertop generate'" in capsys.readouterr().err
    assert main(["rekey", str(graded)]) == 2
    assert "is gone" in capsys.readouterr().err
