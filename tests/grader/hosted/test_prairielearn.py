"""PrairieLearn: the question ``eulertop package --for prairielearn`` writes, and its external
grader's entrypoint end to end in a temporary root laid out as PrairieLearn lays out ``/grade``
(tests/ = the question's tests folder, data/data.json, student/), with real kernels; results
checked against PrairieLearn's documented format."""

from __future__ import annotations

import argparse
import json
import runpy
import shutil
import stat
import uuid
from pathlib import Path

import pytest

from grader.assignment import load_assignment
from grader.hosted import prairielearn
from grader.hosted.grading import CONFIG
from grader.hosted.package import NOTEBOOK, prairielearn_question, variant_ids
from problems.generate import generate_assignment
from problems.roster import Roster
from problems.templates import FAMILIES
from tests.grader.hosted.conftest import HW, PROBLEMS, Notebooks, run_entrypoint
from tests.grader.hosted.platform_formats import check_prairielearn

VARIANTS = 3
LIMITS = {"cell_timeout": 10.0, "total_timeout": 60.0, "memory_bytes": 3 * 1024**3 // 2,
          "output_bytes": 100_000, "submission_bytes": 2 * 1024**2}


@pytest.fixture(scope="module")
def question(hosted_hw, tmp_path_factory) -> Path:
    """The packaged question (a stand-in wheel: the entrypoint does not use it)."""
    out = tmp_path_factory.mktemp("pl")
    wheel = out / "eulertop-0.1.0-py3-none-any.whl"
    wheel.write_bytes(b"wheel")
    args = argparse.Namespace(name="tops", variants=VARIANTS, topic="Rotation",
                              image="someone/eulertop-grader",
                              workspace_image="prairielearn/workspace-jupyterlab-python")
    config = {"sandbox": "container", "kernel_user": None, "limits": LIMITS,
              "platform": "prairielearn", "notebook": NOTEBOOK}
    return prairielearn_question(load_assignment(hosted_hw.folder), out / "course", wheel,
                                 config, args)


@pytest.fixture(scope="module")
def pool(hosted_hw, tmp_path_factory) -> HW:
    """The variants made independently here by the generator from HW's seed and problems."""
    folder = tmp_path_factory.mktemp("pool") / "HW"
    roster = Roster(("id",), tuple({"id": v} for v in variant_ids(VARIANTS)))
    generate_assignment(roster, folder, FAMILIES, problems=PROBLEMS, seed=11, title="Tops")
    return HW(folder, json.loads((folder / "key.json").read_text(encoding="utf-8")))


def layout(base: Path, question: Path, submission: bytes | None, data: dict) -> Path:
    """``base/grade`` as PrairieLearn makes it (files world-readable, as a job's are)."""
    root = base / "grade"
    shutil.copytree(question / "tests", root / "tests")
    (root / "data").mkdir(parents=True)
    (root / "data" / "data.json").write_text(json.dumps(data))
    (root / "student").mkdir()
    if submission is not None:
        (root / "student" / NOTEBOOK).write_bytes(submission)
    for path in [root, *root.rglob("*")]:
        path.chmod(0o755 if path.is_dir() else 0o644)
    return root


def data_for(variant: str) -> dict:
    return {"params": {"eulertop_variant": variant}, "correct_answers": {},
            "submitted_answers": {}, "format_errors": {}, "partial_scores": {}, "score": 0,
            "feedback": {}, "variant_seed": 4242, "options": {}, "raw_submitted_answers": {},
            "editable": False, "panel": "question", "extensions": {}, "num_valid_submissions": 1}


def run(root: Path, monkeypatch) -> tuple[dict, int]:
    status = run_entrypoint(prairielearn, prairielearn.ROOT_VARIABLE, root, monkeypatch)
    return check_prairielearn(root / "results" / "results.json"), status


def test_info_json_asks_for_external_grading_in_a_workspace(question):
    info = json.loads((question / "info.json").read_text())
    uuid.UUID(info["uuid"])
    assert info["type"] == "v3" and info["gradingMethod"] == "External"
    options = info["externalGradingOptions"]
    assert options["enabled"] is True and options["image"] == "someone/eulertop-grader"
    assert options["entrypoint"] == "/grade/tests/run" and 0 < options["timeout"] <= 600
    assert info["workspaceOptions"]["gradedFiles"] == [NOTEBOOK]
    assert (question / "tests" / "run").stat().st_mode & stat.S_IXUSR
    assert json.loads((question / "tests" / CONFIG).read_text())["notebook"] == NOTEBOOK


def test_server_py_offers_the_variant_of_the_seed_made_by_the_generator(question, pool):
    generate = runpy.run_path(str(question / "server.py"))["generate"]
    seen = set()
    for seed in range(12):
        data = {"params": {}, "variant_seed": seed}
        generate(data)
        variant = data["params"]["eulertop_variant"]
        [workspace_file] = data["params"]["_workspace_files"]
        assert workspace_file["name"] == NOTEBOOK
        offered = question / workspace_file["questionFile"]
        # the notebook offered is the generator's own for that variant, byte for byte
        assert offered.read_bytes() == (pool.folder / "release" / f"{variant}.ipynb").read_bytes()
        seen.add(variant)
    assert seen == set(variant_ids(VARIANTS))
    # and the grader knows the same variant's key
    key = json.loads((question / "tests" / "assignment" / "key.json").read_text())
    assert key["students"] == pool.key["students"]


def test_the_grader_derives_the_same_variant_from_the_seed(question):
    generate = runpy.run_path(str(question / "server.py"))["generate"]
    a = load_assignment(question / "tests" / "assignment")
    for seed in (0, 7, 123456789, "a-string-seed"):
        data = {"params": {}, "variant_seed": seed}
        generate(data)
        assert prairielearn.variant_of({"variant_seed": seed}, a) == \
            data["params"]["eulertop_variant"]


def test_right_notebook_scores_one(question, pool, public_tmp, kernel_uid, monkeypatch):
    notebooks = Notebooks(pool)
    root = layout(public_tmp, question, notebooks.right("v001"), data_for("v001"))
    results, status = run(root, monkeypatch)
    assert status == 0 and results["gradable"] is True and results["score"] == 1.0
    assert [t["max_points"] for t in results["tests"]] == \
        [a["points"] for a in pool.answers("v001")]
    assert all(t["points"] == t["max_points"] for t in results["tests"])
    assert f"ran as uid {kernel_uid}" in results["message"]


def test_wrong_answers_lower_the_score(question, pool, public_tmp, kernel_uid, monkeypatch):
    data, kept = Notebooks(pool).wrong("v002")
    results, _ = run(layout(public_tmp, question, data, data_for("v002")), monkeypatch)
    assert results["score"] == pytest.approx(kept / pool.max_points("v002"))


def test_the_key_is_out_of_reach_of_the_notebook(question, pool, public_tmp, kernel_uid,
                                                 monkeypatch):
    key = public_tmp / "grade" / "tests" / "assignment" / "key.json"
    data = Notebooks(pool).key_reader("v000", key)
    root = layout(public_tmp, question, data, data_for("v000"))
    assert key.stat().st_mode & stat.S_IROTH  # readable by all, as PrairieLearn leaves it
    results, _ = run(root, monkeypatch)
    assert results["gradable"] is True and results["score"] == 0.0


@pytest.mark.parametrize("kind", ["broken", "oversized", "missing"])
def test_what_is_not_a_notebook_is_not_gradable(question, pool, public_tmp, monkeypatch, kind):
    notebooks = Notebooks(pool)
    data = {"broken": notebooks.broken(),
            "oversized": notebooks.oversized("v000", LIMITS["submission_bytes"] + 1),
            "missing": None}[kind]
    root = layout(public_tmp, question, data, data_for("v000"))
    # no kernel is needed to refuse these: any isolation will do here
    config = json.loads((root / "tests" / CONFIG).read_text())
    (root / "tests" / CONFIG).write_text(json.dumps({**config, "sandbox": "auto"}))
    results, status = run(root, monkeypatch)
    assert status == 0 and results["gradable"] is False
    assert results["message"].startswith("Not graded")
    assert results["format_errors"]


def test_unknown_variant_is_the_questions_fault_not_the_students(question, public_tmp,
                                                                monkeypatch):
    root = layout(public_tmp, question, b"{}", data_for("v999"))
    results, status = run(root, monkeypatch)
    assert status == 1 and results["gradable"] is False and "v999" in results["message"]


def test_another_variants_notebook_is_graded_against_this_variant_and_flagged(
        question, pool, public_tmp, kernel_uid, monkeypatch):
    data = Notebooks(pool).right("v002")
    results, _ = run(layout(public_tmp, question, data, data_for("v001")), monkeypatch)
    assert "FLAGGED: this notebook was made for variant v002, not v001" in results["message"]
    assert results["score"] < 1.0


def test_a_kernel_that_cannot_start_uses_no_attempt(question, pool, public_tmp, monkeypatch):
    from grader.execute import Execution
    from grader.hosted.grading import Isolation

    def no_kernel(path, variables, limits):
        return Execution("error", "could not start a Python kernel (test)", {}, (), 0.0, False,
                         retry=True)

    monkeypatch.setattr(prairielearn, "choose_isolation",
                        lambda *a: Isolation("container", "test", True, no_kernel))
    root = layout(public_tmp, question, Notebooks(pool).right("v000"), data_for("v000"))
    results, status = run(root, monkeypatch)
    assert status == 1 and results["gradable"] is False
    assert "could not start" in results["message"]
