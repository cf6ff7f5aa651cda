"""Hosted packages of an assignment with a family of the instructor's own (issue 30): the
package carries the family's file, and the platform's grader credits follow-through as a local
``eulertop grade`` does — the same points and messages, answer by answer; a family that cannot
be loaded from the package, or was edited since ``generate``, stops ``eulertop package``.

The entrypoints run end to end in temporary roots laid out as each platform lays them out,
except for the kernel: the execution stage reads each answer as the literal its cell assigns
(:class:`~tests.grader.report.synthetic_class.LiteralExecute`), which is what is under test
here is what happens to the answers once extracted."""

from __future__ import annotations

import argparse
import json
import zipfile
from pathlib import Path

import pytest

from eulertop.cli import main
from grader.assignment import load_assignment
from grader.hosted import gradescope, prairielearn
from grader.hosted.grading import Isolation
from grader.hosted.package import NOTEBOOK, PackageError, gradescope_zip, prairielearn_question
from grader.pipeline import grade_assignment
from grader.results import read_result
from tests.grader.hosted.conftest import HW
from tests.grader.hosted.test_gradescope import LIMITS
from tests.grader.hosted.test_gradescope import layout as gradescope_layout
from tests.grader.hosted.test_gradescope import run as run_gradescope
from tests.grader.hosted.test_prairielearn import data_for
from tests.grader.hosted.test_prairielearn import layout as prairielearn_layout
from tests.grader.hosted.test_prairielearn import run as run_prairielearn
from tests.grader.lever_family import key_values, lever_assignment, notebook
from tests.grader.report.synthetic_class import LiteralExecute

PROBLEMS = ("lever", "sleeping_top")
KINDS = ("follows", "negative", "zero", "right")


def _answers(hw: Path, sid: str, kind: str) -> dict:
    """What ``sid`` submits: ``follows``, earlier answers off (the arm 5 %, the critical spin
    across the given one) with the later ones worked out from them; ``negative``: the arm's
    sign flipped (the family's own degenerate case); ``zero``: a zero arm and critical spin
    (the defaults' and sleeping_top's); ``right``: the key's."""
    key = key_values(hw, sid)
    manifest = json.loads((hw / "assignment.json").read_text())
    omega3 = manifest["students"][sid]["questions"][1]["parameters"]["omega3"]
    arm = {"follows": 1.05, "negative": -1.05, "zero": 0.0, "right": 1.0}[kind] * key["q1_a"]
    spin = {"follows": omega3 * (1.2 if omega3 >= key["q2_omega3_c"] else 0.8), "negative": 0.0,
            "zero": 0.0, "right": key["q2_omega3_c"]}[kind]
    return {**key, "q1_a": arm, "q1_t": arm**2, "q2_omega3_c": spin,
            "q2_stable": omega3 >= spin}


def _local(root: Path, students: tuple[str, ...], kinds: dict[str, str]) -> tuple[Path, dict]:
    """An assignment generated for ``students``, graded locally: the folder, and each
    student's (points, message) by variable."""
    hw = lever_assignment(root, students, PROBLEMS)
    subs = root / "subs"
    subs.mkdir()
    for sid in students:
        (subs / f"{sid}.ipynb").write_text(notebook(_answers(hw, sid, kinds[sid])))
    grade_assignment(hw, subs, limits="LIMITS", execute=LiteralExecute(), jobs=1)
    verdicts = {}
    for sid in students:
        record = read_result(hw / "graded" / "results" / f"{sid}.json")
        verdicts[sid] = {a.variable: (a.verdict.points, a.verdict.message)
                         for a in record.answers}
    return hw, verdicts


def _literal(module, monkeypatch) -> None:
    monkeypatch.setattr(module, "choose_isolation",
                        lambda *args: Isolation("bwrap", "literal values (test)", True,
                                                LiteralExecute()))


def _wheel(folder: Path) -> Path:
    wheel = folder / "eulertop-0.1.0-py3-none-any.whl"
    wheel.write_bytes(b"not installed by these tests")
    return wheel


STUDENTS = ("ann", "ben", "cy", "dee")


@pytest.fixture(scope="module")
def graded(tmp_path_factory) -> tuple[Path, dict]:
    return _local(tmp_path_factory.mktemp("own"), STUDENTS, dict(zip(STUDENTS, KINDS,
                                                                      strict=True)))


def test_gradescope_credits_follow_through_as_a_local_grade(graded, public_tmp, monkeypatch):
    hw, local = graded
    out = gradescope_zip(load_assignment(hw), public_tmp / "autograder.zip", _wheel(public_tmp),
                         {"sandbox": "auto", "kernel_user": None, "limits": LIMITS})
    with zipfile.ZipFile(out) as zf:
        shipped = json.loads(zf.read("assignment/assignment.json"))["families"]["lever"]
        assert shipped["file"] == "families/lever/lever.py"
        assert zf.read(f"assignment/{shipped['file']}") == \
            (hw.parent / "mine" / "lever.py").read_bytes()
    _literal(gradescope, monkeypatch)
    hw_record = HW(hw, json.loads((hw / "key.json").read_text()))
    verdicts = {}
    for sid in STUDENTS:
        base = public_tmp / sid
        base.mkdir()
        root = gradescope_layout(base, hw_record, notebook(_answers(hw, sid, dict(
            zip(STUDENTS, KINDS, strict=True))[sid])).encode(), [{"email": "", "sid": sid}],
            sandbox="auto")
        results, status = run_gradescope(root, monkeypatch)
        assert status == 0, results["output"]
        verdicts[sid] = {t["name"].rsplit("(", 1)[1].rstrip(")"): (t["score"], t["output"])
                         for t in results["tests"]}
    assert verdicts == local
    assert local["ann"]["q1_t"][1].startswith("follows from your q1_a = ")
    assert local["ann"]["q2_stable"][1].startswith("follows from your q2_omega3_c = ")
    assert "no follow-through: your q1_a is negative" in local["ben"]["q1_t"][1]
    assert "no follow-through: your q1_a is zero" in local["cy"]["q1_t"][1]


def test_prairielearn_credits_follow_through_as_a_local_grade(graded, tmp_path, public_tmp,
                                                              monkeypatch):
    hw, _ = graded
    variants = ("v000", "v001", "v002", "v003")
    kinds = dict(zip(variants, KINDS, strict=True))
    args = argparse.Namespace(name="lever", variants=len(variants), topic="Rotation",
                              image="someone/eulertop-grader",
                              workspace_image="prairielearn/workspace-jupyterlab-python")
    config = {"sandbox": "auto", "kernel_user": None, "limits": LIMITS,
              "platform": "prairielearn", "notebook": NOTEBOOK}
    question = prairielearn_question(load_assignment(hw), tmp_path / "course",
                                     _wheel(tmp_path), config, args)
    assert (question / "tests" / "assignment" / "families" / "lever" / "lever.py").is_file()
    # the same variants, generated and graded locally from the same seed and family file
    pool, local = _local(tmp_path / "local", variants, kinds)
    _literal(prairielearn, monkeypatch)
    for v in variants:
        base = public_tmp / v
        base.mkdir()
        submitted = notebook(_answers(pool, v, kinds[v])).encode()
        results, status = run_prairielearn(prairielearn_layout(base, question, submitted,
                                                               data_for(v)), monkeypatch)
        assert status == 0 and results["gradable"], results["message"]
        found = {t["name"].rsplit("(", 1)[1].rstrip(")"): (t["points"], t["message"])
                 for t in results["tests"]}
        assert found == local[v], v
    assert local["v000"]["q1_t"][1].startswith("follows from your q1_a = ")


UNLOADABLE = '''
from pathlib import Path

from eulertop.family import Answer, Parameter, follows_from

TABLE = float((Path(__file__).parent / "table.txt").read_text())  # beside the file only

NAME = "tabled"
TITLE = "A chain that reads a table beside it"
SUMMARY = "a = x times the table's number, then b = a + 1"
PARAMETERS = {"x": Parameter(low=1.0, high=2.0, figures=3)}


def answers(params):
    a = TABLE * params["x"]
    return (Answer("a", "scalar", a), follows_from(Answer("b", "scalar", a + 1), "a"))


def statement(params):
    return "Compute $a$, then $b = a + 1$ from your $a$."


def follow(name, params, earlier):
    return earlier["a"] + 1
'''


def test_a_family_the_package_cannot_load_stops_it(tmp_path, capsys):
    mine = tmp_path / "mine"
    mine.mkdir()
    (mine / "tabled.py").write_text(UNLOADABLE)
    (mine / "table.txt").write_text("2.5\n")  # not a family file: the package leaves it
    (tmp_path / "roster.csv").write_text("id\nann\n")
    assert main(["generate", "--roster", str(tmp_path / "roster.csv"), "--families", str(mine),
                 "--problems", "tabled", "--out", str(tmp_path / "HW")]) == 0
    wheel = _wheel(tmp_path)
    for platform, out in (("gradescope", tmp_path / "a.zip"), ("prairielearn", tmp_path / "pl")):
        capsys.readouterr()
        assert main(["package", str(tmp_path / "HW"), "--for", platform, "--out", str(out),
                     "--wheel", str(wheel), "--variants", "2"]) == 2
        err = capsys.readouterr().err
        assert err.startswith("eulertop package: family 'tabled' cannot be loaded as the "
                              "package carries it (in families/tabled/)"), err
        assert "table.txt" in err and "Traceback" not in err
        assert not out.exists()


def test_an_edited_family_stops_the_gradescope_package(graded, tmp_path):
    hw, _ = graded
    edited = tmp_path / "HW"
    import shutil
    shutil.copytree(hw, edited)
    shutil.copytree(hw.parent / "mine", tmp_path / "mine")
    (tmp_path / "mine" / "lever.py").write_text((tmp_path / "mine" / "lever.py").read_text()
                                                + "\n# edited\n")
    with pytest.raises(PackageError, match=r"lever.py, family 'lever', changed .*"
                                           r"run 'eulertop rekey"):
        gradescope_zip(load_assignment(edited), tmp_path / "a.zip", _wheel(tmp_path),
                       {"sandbox": "auto", "kernel_user": None, "limits": LIMITS})
    assert not (tmp_path / "a.zip").exists()


HOST_BROKEN = "EULERTOP_TEST_FAMILY_BROKEN"
FRAGILE = '''
import os

from eulertop.family import Answer, Parameter, follows_from

if os.environ.get("HOST_BROKEN"):
    raise ImportError("this host lacks what the family imports")

NAME = "fragile"
TITLE = "A chain whose family cannot be loaded everywhere"
SUMMARY = "a = 2x, then b = a + 1 from your a"
PARAMETERS = {"x": Parameter(low=1.0, high=2.0, figures=3)}


def answers(params):
    a = 2 * params["x"]
    return (Answer("a", "scalar", a), follows_from(Answer("b", "scalar", a + 1), "a"))


def statement(params):
    return "Compute $a = 2x$, then $b = a + 1$ from your $a$."


def follow(name, params, earlier):
    return earlier["a"] + 1
'''.replace("HOST_BROKEN", HOST_BROKEN)


def test_a_family_the_platform_cannot_load_is_reported_never_swallowed(public_tmp,
                                                                       monkeypatch):
    """Packaged where the family loads, graded where it does not: the platform's run fails
    as the package's fault, naming the family; no score is given without its credit."""
    mine = public_tmp / "mine"
    mine.mkdir()
    (mine / "fragile.py").write_text(FRAGILE)
    (public_tmp / "roster.csv").write_text("id\nann\n")
    assert main(["generate", "--roster", str(public_tmp / "roster.csv"), "--families",
                 str(mine), "--problems", "fragile", "--out", str(public_tmp / "HW")]) == 0
    hw = public_tmp / "HW"
    a = key_values(hw, "ann")["q1_a"]
    _literal(gradescope, monkeypatch)
    base = public_tmp / "host"
    base.mkdir()
    root = gradescope_layout(base, HW(hw, json.loads((hw / "key.json").read_text())),
                             notebook({"q1_a": 1.1 * a, "q1_b": 1.1 * a + 1}).encode(),
                             [{"email": "", "sid": "ann"}], sandbox="auto")
    monkeypatch.setenv(HOST_BROKEN, "1")
    results, status = run_gradescope(root, monkeypatch)
    assert status == 1 and results["score"] == 0
    assert "this is not your fault" in results["output"]
    assert "family 'fragile' cannot be loaded for follow-through credit" in results["output"]
    assert "this host lacks what the family imports" in results["output"]
