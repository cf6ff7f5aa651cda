"""``eulertop demo`` end to end: one real run (module fixture), then what it wrote and printed.

The demo is run once as a user would (``python -m eulertop demo --out DIR``) with a short
whole-notebook time limit, since the looping student's notebook runs until it. Everything is
then checked against *independent* sources: ``key.json`` (for the mistakes' names and
feedback), the roster in :mod:`eulertop.sample_class`, the release notebooks, and the grader's
own records — not against the demo's own verdict.
"""

from __future__ import annotations

import csv
import json
import os
import subprocess
import sys
import time
from pathlib import Path

import pytest

from eulertop.demo import ENTRIES, MARKER, FolderRefused, prepare_folder
from eulertop.sample_class import CLASS, SEED

ROOT = Path(__file__).resolve().parents[1]
TIMEOUT = 15  # s per notebook: the looping student's notebook runs this long
BY_PLAN = {}
for _s in CLASS:
    BY_PLAN.setdefault(_s.plan, []).append(_s)


def run_demo(cwd: Path, *args: str) -> subprocess.CompletedProcess:
    env = {**os.environ, "PYTHONPATH": os.pathsep.join(
        [str(ROOT), *filter(None, [os.environ.get("PYTHONPATH")])])}
    return subprocess.run([sys.executable, "-m", "eulertop", "demo", *args], cwd=cwd, env=env,
                          capture_output=True, text=True, timeout=600)


@pytest.fixture(scope="module")
def demo(tmp_path_factory):
    cwd = tmp_path_factory.mktemp("demo")
    start = time.perf_counter()
    done = run_demo(cwd, "--out", "out", "--timeout", str(TIMEOUT))
    seconds = time.perf_counter() - start
    out = cwd / "out"
    hw = out / "HW"
    results = {s.id: json.loads((hw / "graded" / "results" / f"{s.id}.json").read_text("utf-8"))
               for s in CLASS} if (hw / "graded" / "results").is_dir() else {}
    key = json.loads((hw / "key.json").read_text("utf-8")) if (hw / "key.json").exists() else {}
    return {"done": done, "seconds": seconds, "out": out, "hw": hw, "results": results,
            "key": key, "cwd": cwd}


def printed_row(demo, student_id: str) -> str:
    rows = [line for line in demo["done"].stdout.splitlines()
            if line.split(" ", 1)[0] == student_id]
    assert len(rows) == 1, rows
    return rows[0]


def key_answers(demo, student_id: str) -> dict:
    return {f"q{q['question']}_{a['name']}": a
            for q in demo["key"]["students"][student_id]["questions"] for a in q["answers"]}


def verdicts(demo, student_id: str) -> dict:
    return {a["variable"]: a["verdict"] for a in demo["results"][student_id]["answers"]}


def test_runs_in_time_with_progress(demo):
    done = demo["done"]
    assert done.returncode == 0, done.stdout[-3000:] + done.stderr[-3000:]
    assert demo["seconds"] < 180
    assert f"[{len(CLASS)}/{len(CLASS)}]" in done.stderr  # the grader's progress lines
    assert "were judged as intended" in done.stdout
    assert "NOT as intended" not in done.stdout


def test_gradebook_lists_every_student_by_name(demo):
    with open(demo["hw"] / "graded" / "grades.csv", encoding="utf-8", newline="") as f:
        rows = {row["id"]: row for row in csv.DictReader(f)}
    assert {s.id: s.name for s in CLASS} == {i: r["name"] for i, r in rows.items()}
    assert json.loads((demo["hw"] / "assignment.json").read_text("utf-8"))["seed"] == SEED


@pytest.mark.parametrize("student", BY_PLAN["correct"], ids=lambda s: s.id)
def test_correct_students_get_full_marks(demo, student):
    r = demo["results"][student.id]
    assert r["status"] == "graded"
    assert r["points"] == r["max_points"] > 0
    assert "all correct" in printed_row(demo, student.id)


@pytest.mark.parametrize("student", BY_PLAN["mistake"], ids=lambda s: s.id)
def test_mistakes_carry_the_keys_name_and_feedback(demo, student):
    listed = {v: m for v, a in key_answers(demo, student.id).items() for m in a["mistakes"]
              if m["name"] == student.mistake}
    assert listed, f"no answer of {student.id} lists {student.mistake}"
    got = verdicts(demo, student.id)
    for variable, mistake in listed.items():
        assert got[variable]["status"] == "wrong"
        assert got[variable]["mistake"] == student.mistake
        assert got[variable]["message"] == mistake["feedback"]
    assert all(v["status"] == "correct" for name, v in got.items() if name not in listed)
    assert student.mistake in printed_row(demo, student.id)


@pytest.mark.parametrize("student", BY_PLAN["slip"], ids=lambda s: s.id)
def test_slips_are_wrong_and_no_known_mistake(demo, student):
    wrong = {n: v for n, v in verdicts(demo, student.id).items() if v["status"] != "correct"}
    assert len(wrong) == 1
    ((name, verdict),) = wrong.items()
    assert name.startswith(f"q{student.question}_")
    assert verdict["status"] == "wrong" and verdict["mistake"] is None


def test_the_string_answer_is_invalid(demo):
    (student,) = BY_PLAN["string_angle"]
    bad = {n: v for n, v in verdicts(demo, student.id).items() if v["status"] != "correct"}
    ((name, verdict),) = bad.items()
    assert verdict["status"] == "invalid"
    assert "string" in verdict["message"]
    submitted = {a["variable"]: a["submitted"] for a in demo["results"][student.id]["answers"]}
    assert isinstance(submitted[name], str) and submitted[name].endswith(" rad")
    assert "invalid" in printed_row(demo, student.id)


# broken students: the record and the printed row say, in words, what went wrong
BROKEN = {
    "name_error": ("graded", "NameError"),
    "endless_loop": ("graded", "time limit"),  # the answers set before the loop count
    "empty": ("failed", "no code"),
    "unset": ("graded", "not set"),
    "absent": ("missing", "no submission"),
}


@pytest.mark.parametrize("plan", sorted(BROKEN))
def test_broken_students_are_told_what_went_wrong(demo, plan):
    (student,) = BY_PLAN[plan]
    status, words = BROKEN[plan]
    r = demo["results"][student.id]
    assert r["status"] == status
    record = " ".join([r["message"], *r["execution"].get("cell_errors", []),
                       *(a["verdict"]["message"] for a in r["answers"])])
    phrase = {"unset": "no answer", "name_error": "NameError"}.get(plan, words)
    assert phrase in record
    assert words in printed_row(demo, student.id)
    if plan == "unset":
        assert [v["status"] for v in verdicts(demo, student.id).values()].count("missing") == 1
    if plan in ("empty", "absent"):
        assert r["points"] == 0
    if plan == "endless_loop":  # the questions before the looping cell, and none after it
        got = verdicts(demo, student.id)
        assert all(v["status"] == ("correct" if int(name[1:].split("_")[0]) < student.question
                                   else "missing") for name, v in got.items()), got
        assert 0 < r["points"] < r["max_points"]


def _full_precision_numbers(value) -> set[str]:
    if isinstance(value, list):
        return set().union(*map(_full_precision_numbers, value)) if value else set()
    if isinstance(value, float) and len(repr(value).lstrip("-").replace(".", "")) >= 12:
        return {repr(value)}
    return set()


def test_no_key_in_any_submission(demo):
    for path in sorted((demo["out"] / "submissions").glob("*.ipynb")):
        text = path.read_text("utf-8")
        sid = path.stem
        for variable, a in key_answers(demo, sid).items():
            for number in _full_precision_numbers(a["value"]):
                assert number not in text, f"{sid}: key value of {variable} in the submission"
            for m in a["mistakes"]:
                assert m["feedback"] not in text, f"{sid}: mistake feedback in the submission"
        assert '"mistakes"' not in text and "key.json" not in text


def test_parameters_cells_unchanged_from_the_release(demo):
    made = sorted((demo["out"] / "submissions").glob("*.ipynb"))
    assert len(made) == len(CLASS) - 1  # one student hands nothing in
    for path in made:
        cells = json.loads(path.read_text("utf-8"))["cells"]
        if not cells:  # the empty notebook
            continue
        release = json.loads((demo["hw"] / "release" / path.name).read_text("utf-8"))["cells"]
        ours, theirs = ([c for c in cs if c.get("id") == "parameters"] for cs in (cells, release))
        assert ours == theirs, path.name


def test_charts_exist_or_a_note_says_why(demo):
    charts = sorted((demo["out"] / "bench").glob("*.png"))
    if charts:
        assert "charts: " in demo["done"].stdout
    else:
        assert "charts skipped" in demo["done"].stdout


def test_an_earlier_demo_needs_force(demo):
    before = sorted(p.name for p in demo["out"].iterdir())
    done = run_demo(demo["cwd"], "--out", "out")
    assert done.returncode == 2 and "--force" in done.stderr
    assert sorted(p.name for p in demo["out"].iterdir()) == before


def test_a_foreign_folder_is_never_replaced(tmp_path):
    (tmp_path / "mine").mkdir()
    (tmp_path / "mine" / "thesis.tex").write_text("precious")
    done = run_demo(tmp_path, "--out", "mine", "--force")
    assert done.returncode == 2 and "never replaced" in done.stderr
    assert sorted(p.name for p in (tmp_path / "mine").iterdir()) == ["thesis.tex"]


@pytest.mark.parametrize("extra", [None, "notes.txt"])
def test_force_clears_only_a_demo_folder(tmp_path, extra):
    out = tmp_path / "d"
    for name in ("HW", "submissions", "bench"):
        (out / name).mkdir(parents=True)
        (out / name / "x").write_text("old")
    (out / MARKER).write_text("")
    (out / "roster.csv").write_text("id\n")
    if extra:
        (out / extra).write_text("mine")
        with pytest.raises(FolderRefused):
            prepare_folder(out, force=True)
        assert (out / "HW" / "x").exists() and (out / extra).exists()
        return
    with pytest.raises(FolderRefused):
        prepare_folder(out, force=False)
    prepare_folder(out, force=True)
    assert sorted(os.listdir(out)) == [MARKER]
    assert MARKER in ENTRIES


def test_usage_errors_exit_2(tmp_path):
    done = run_demo(tmp_path, "--timeout", "-3")
    assert done.returncode == 2
    assert not (tmp_path / "eulertop-demo").exists()
