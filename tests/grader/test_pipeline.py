"""The grading pipeline with a fake execution stage: sorting, resume, locking, failing closed.

The fake reads the answer assignments of a notebook's code cells with ``ast.literal_eval`` (the
solutions notebooks hold literals), so no kernel starts here; the real execution is exercised
end to end in ``test_cli.py``.
"""

from __future__ import annotations

import ast
import csv
import json
import re
import shutil
import threading
import time
from dataclasses import dataclass, replace
from pathlib import Path

import pytest

from grader.assignment import UsageError
from grader.graded_folder import RunInProgress, run_lock
from grader.notebook_load import SubmissionError
from grader.pipeline import grade_assignment
from grader.results import StudentResult, read_result
from problems.generate import generate_assignment
from problems.roster import Roster
from problems.templates import FAMILIES

ROSTER = ("alice", "bob", "carol", "dave", "erin", "frank")


@dataclass(frozen=True)
class FakeExecution:
    status: str
    message: str
    answers: dict
    cell_errors: tuple = ()
    duration: float = 0.5
    output_truncated: bool = False
    retry: bool = False


class FakeExecute:
    """``execute(path, variables, limits)``: literal answers, or a scripted failure."""

    def __init__(self):
        self.calls = []
        self.lock = threading.Lock()

    def __call__(self, path, variables, limits):
        with self.lock:
            self.calls.append((Path(path), tuple(variables), limits))
        try:
            nb = json.loads(Path(path).read_text())
        except ValueError as e:
            raise SubmissionError(f"not JSON: {e}") from None
        sources = ["".join(c["source"]) if isinstance(c["source"], list) else c["source"]
                   for c in nb["cells"] if c["cell_type"] == "code"]
        if any("KILL_KERNEL" in s for s in sources):
            return FakeExecution("kernel_died", "the kernel died in cell 5", {})
        if any("GRADER_BUG" in s for s in sources):
            raise RuntimeError("executor exploded")
        answers = dict.fromkeys(variables)
        for node in ast.walk(ast.parse("\n".join(sources))):
            if isinstance(node, ast.Assign) and isinstance(node.targets[0], ast.Name) \
                    and node.targets[0].id in answers:
                answers[node.targets[0].id] = ast.literal_eval(node.value)
        raised = [s for s in sources if "1 / 0" in s]
        if raised:
            return FakeExecution("error", "cell 6 raised ZeroDivisionError", answers,
                                 ("cell 6 raised ZeroDivisionError: division by zero",))
        return FakeExecution("ok", "", answers)


@pytest.fixture(scope="module")
def assignment(tmp_path_factory) -> Path:
    hw = tmp_path_factory.mktemp("pipeline") / "HW"
    roster = Roster(("id", "name"), tuple({"id": s, "name": s.title()} for s in ROSTER))
    generate_assignment(roster, hw, FAMILIES, problems=["inertia_tensor", "euler_rotation"],
                        seed=5)
    return hw


def _key(hw: Path) -> dict:
    return json.loads((hw / "key.json").read_text())


def _variables(hw: Path, sid: str) -> list[str]:
    return [f"q{q['question']}_{a['name']}" for q in _key(hw)["students"][sid]["questions"]
            for a in q["answers"]]


def _notebook(hw: Path, sid: str, extra_cell: str | None = None, wrong: str | None = None):
    nb = json.loads((hw / "solutions" / f"{sid}.ipynb").read_text())
    for cell in nb["cells"]:
        src = "".join(cell["source"]) if isinstance(cell["source"], list) else cell["source"]
        if wrong:
            cell["source"] = "\n".join(f"{wrong} = 'no idea'" if line.startswith(f"{wrong} =")
                                       else line for line in src.splitlines())
    if extra_cell:
        nb["cells"].append({"cell_type": "code", "id": "extra", "metadata": {},
                            "source": extra_cell, "outputs": [], "execution_count": None})
    return json.dumps(nb)


@pytest.fixture
def hw(assignment, tmp_path) -> Path:
    """A private copy of the generated assignment (runs write HW/graded)."""
    return Path(shutil.copytree(assignment, tmp_path / "HW"))


@pytest.fixture
def subs(hw, tmp_path) -> Path:
    """alice right, bob one answer invalid + a cell raising, carol's kernel dies, dave
    missing, erin two notebooks, frank not JSON, mallory not on the roster."""
    s = tmp_path / "subs"
    (s / "erin").mkdir(parents=True)
    (s / "alice.ipynb").write_text(_notebook(hw, "alice"))
    (s / "bob.ipynb").write_text(_notebook(hw, "bob", "1 / 0", wrong=_variables(hw, "bob")[0]))
    (s / "carol.ipynb").write_text(_notebook(hw, "carol", "KILL_KERNEL"))
    (s / "erin" / "a.ipynb").write_text(_notebook(hw, "erin"))
    (s / "erin" / "b.ipynb").write_text(_notebook(hw, "erin"))
    (s / "frank.ipynb").write_text("{not json")
    (s / "mallory.ipynb").write_text(_notebook(hw, "alice"))
    return s


def _run(hw, subs, execute, **kw):
    return grade_assignment(hw, subs, limits="LIMITS", execute=execute, jobs=2, **kw)


@pytest.fixture
def first_run(hw, subs):
    execute = FakeExecute()
    return _run(hw, subs, execute), execute


def _by_id(report) -> dict[str, StudentResult]:
    return {r.student_id: r for r in report.results}


def test_every_roster_student_gets_a_row_saying_what_happened(hw, first_run):
    report, _ = first_run
    r = _by_id(report)
    assert [x.student_id for x in report.results] == list(ROSTER)
    assert {s: x.status for s, x in r.items()} == {
        "alice": "graded", "bob": "graded", "carol": "failed", "dave": "missing",
        "erin": "failed", "frank": "failed"}
    assert r["alice"].points == r["alice"].max_points > 0
    assert r["bob"].points == r["bob"].max_points - 1  # one answer 'no idea', the rest right
    assert "cell 6 raised ZeroDivisionError" in r["bob"].message
    assert "the kernel died in cell 5" in r["carol"].message
    assert "2 notebooks" in r["erin"].message
    assert r["frank"].message.startswith("not a valid notebook: not JSON")
    assert r["dave"].message == "no submission"


def test_fail_closed_nothing_extracted_nothing_awarded(first_run):
    r = _by_id(first_run[0])
    for sid in ("carol", "dave", "erin", "frank"):
        assert r[sid].points == 0
        assert {a.verdict.status for a in r[sid].answers} == {"missing"}
        assert r[sid].max_points == r["alice"].max_points


def test_not_graded_lists_failures_and_strays(first_run):
    listed = "\n".join(first_run[0].not_graded)
    for fragment in ("carol:", "erin:", "frank:", "'mallory' is not on the roster"):
        assert fragment in listed
    assert "alice" not in listed and "dave" not in listed


def test_execution_gets_names_only(hw, first_run):
    _, execute = first_run
    calls = {p.stem: (variables, limits) for p, variables, limits in execute.calls}
    assert set(calls) == {"alice", "bob", "carol", "frank"}  # never mallory, dave or erin
    for sid, (variables, limits) in calls.items():
        assert list(variables) == _variables(hw, sid)
        assert limits == "LIMITS"


def test_records_round_trip_and_the_gradebook_is_built_from_them(hw, first_run):
    report, _ = first_run
    out = hw / "graded"
    for r in report.results:
        assert read_result(out / "results" / f"{r.student_id}.json") == r
        assert (out / "feedback" / f"{r.student_id}.html").is_file()
    with open(out / "grades.csv", newline="") as f:
        rows = list(csv.DictReader(f))
    assert [row["id"] for row in rows] == list(ROSTER)
    assert [row["name"] for row in rows] == [s.title() for s in ROSTER]
    for row, r in zip(rows, report.results, strict=True):
        assert float(row["total"]) == r.points == float(row["q1"]) + float(row["q2"])
        assert (float(row["maximum"]), row["status"]) == (r.max_points, r.status)
    assert sorted(p.name for p in out.iterdir()) == ["answers.csv", "audit.jsonl", "feedback",
                                                     "grades.csv", "pages.json", "report.csv",
                                                     "report.html", "report_items.csv",
                                                     "results"]


def test_a_rerun_skips_what_is_unchanged(hw, subs, first_run):
    before, _ = first_run
    execute = FakeExecute()
    again = _run(hw, subs, execute)
    assert execute.calls == []
    assert again.results == before.results  # not even graded_at changed
    assert set(again.unchanged) == set(ROSTER)


def test_force_regrades_everything(hw, subs, first_run):
    execute = FakeExecute()
    again = _run(hw, subs, execute, force=True)
    assert len(execute.calls) == 4
    strip = lambda rs: [replace(r, graded_at="") for r in rs]  # noqa: E731
    assert strip(again.results) == strip(first_run[0].results)


def test_each_feedback_page_is_rendered_once_and_a_rerun_still_writes_them(hw, subs,
                                                                         monkeypatch):
    """A page written when its record is published is not rendered again at the end of the
    same run (the same record, the same page); a run that grades nothing rebuilds every
    page from the records, equal to what the first run wrote."""
    import grader.publish as publish

    rendered = []
    real = publish.feedback_html

    def counting(title, result, questions, key=None):
        rendered.append(result.student_id)
        return real(title, result, questions, key)

    monkeypatch.setattr(publish, "feedback_html", counting)
    _run(hw, subs, FakeExecute())
    assert sorted(rendered) == sorted(ROSTER)  # once each
    pages = {p.name: p.read_bytes() for p in (hw / "graded" / "feedback").iterdir()}
    for page in (hw / "graded" / "feedback").iterdir():
        page.unlink()
    rendered.clear()
    _run(hw, subs, FakeExecute())  # nothing to grade: every page from the records
    assert sorted(rendered) == sorted(ROSTER)
    assert {p.name: p.read_bytes() for p in (hw / "graded" / "feedback").iterdir()} == pages


def test_a_changed_submission_or_key_is_regraded(hw, subs, first_run):
    (subs / "bob.ipynb").write_text(_notebook(hw, "bob"))  # bob fixed his answer
    key = _key(hw)
    key["students"]["alice"]["hash"] = "sha256:changed"  # e.g. a reroll
    (hw / "key.json").write_text(json.dumps(key))
    (subs / "erin" / "b.ipynb").unlink()  # erin now has one notebook
    execute = FakeExecute()
    r = _by_id(_run(hw, subs, execute))
    assert sorted(p.stem for p, _, _ in execute.calls) == ["a", "alice", "bob"]
    assert r["bob"].points == r["bob"].max_points
    assert r["alice"].key_sha256 == "sha256:changed"
    assert r["erin"].status == "graded"


def test_the_variant_comes_from_the_file_name_and_a_mismatch_is_flagged(hw, tmp_path):
    s = tmp_path / "mixed"
    s.mkdir()
    (s / "bob.ipynb").write_text(_notebook(hw, "alice"))  # alice's notebook, named bob
    r = _by_id(_run(hw, s, FakeExecute()))["bob"]
    assert r.status == "graded"
    assert "metadata names student 'alice'; it was graded as 'bob'" in r.message
    assert r.points < r.max_points  # alice's values against bob's key


def test_a_grader_fault_on_one_submission_spares_the_others(hw, tmp_path):
    s = tmp_path / "s"
    s.mkdir()
    (s / "alice.ipynb").write_text(_notebook(hw, "alice", "GRADER_BUG"))
    (s / "bob.ipynb").write_text(_notebook(hw, "bob"))
    r = _by_id(_run(hw, s, FakeExecute()))
    assert r["alice"].status == "failed"
    assert "could not run this notebook (RuntimeError: executor exploded)" in r["alice"].message
    assert r["bob"].points == r["bob"].max_points


def test_a_second_run_is_told_one_is_in_progress(hw, subs, capsys):
    out = hw / "graded"
    out.mkdir()
    with run_lock(out, command="eulertop override"):
        with pytest.raises(RunInProgress, match=r"another command \(pid \d+: eulertop override\) "
                                                r"still holds this folder after 0.3 s"):
            _run(hw, subs, FakeExecute(), wait=0.3)
    assert "waiting for another command" in capsys.readouterr().err  # said once, at once
    assert not (out / "results").exists() or not any((out / "results").iterdir())


def test_a_second_run_waits_for_the_first(hw, subs):
    """A run started while another command holds the class waits for it, then grades."""
    out = hw / "graded"
    out.mkdir()
    held = threading.Event()

    def hold() -> None:
        with run_lock(out, command="eulertop rescore"):
            held.set()
            time.sleep(1.0)

    holder = threading.Thread(target=hold)
    holder.start()
    held.wait()
    start = time.monotonic()
    report = _run(hw, subs, FakeExecute(), wait=30)
    holder.join()
    assert time.monotonic() - start >= 0.9  # it did wait for the holder
    assert {r.student_id for r in report.results if r.status == "graded"}


def test_temporaries_of_a_killed_run_are_cleared(hw, subs):
    results = hw / "graded" / "results"
    results.mkdir(parents=True)
    (results / ".alice.json.abc.tmp").write_text('{"half')
    _run(hw, subs, FakeExecute())
    assert not list(results.glob(".*"))


@pytest.mark.parametrize(("case", "fragment"), [
    ("no HW", "no such assignment folder"),
    ("no key", r"no answer key \(key.json\) here"),
    ("bad key", "cannot read the answer key"),
    ("no submissions", "not a readable folder of submissions"),
])
def test_usage_errors(hw, subs, case, fragment):
    if case == "no HW":
        hw = hw.parent / "nothing"
    elif case == "no key":
        (hw / "key.json").unlink()
    elif case == "bad key":
        (hw / "key.json").write_text("{")
    else:
        subs = subs / "alice.ipynb"
    with pytest.raises(UsageError, match=fragment):
        _run(hw, subs, FakeExecute())


def test_an_unreadable_submission_fails_alone(hw, subs, monkeypatch):
    from grader import pipeline

    real = pipeline.read_submission

    def read(path, max_bytes):  # root reads any file: the refusal is simulated
        if path.name == "bob.ipynb":
            raise PermissionError(13, "Permission denied")
        return real(path, max_bytes)

    monkeypatch.setattr(pipeline, "read_submission", read)
    r = _by_id(_run(hw, subs, FakeExecute()))
    assert (r["bob"].status, r["bob"].message) == (
        "failed", "cannot read bob.ipynb: Permission denied")
    assert r["alice"].points == r["alice"].max_points


class FlakyStart(FakeExecute):
    """A kernel that cannot be started for alice's first ``failures`` runs (not her doing)."""

    def __init__(self, failures: int):
        super().__init__()
        self.failures = failures

    def __call__(self, path, variables, limits):
        if Path(path).name == "alice.ipynb" and self.failures > 0:
            with self.lock:
                self.failures -= 1
                self.calls.append((Path(path), tuple(variables), limits))
            return FakeExecution("error", "could not start a Python kernel (ZygoteError: …)",
                                 {}, retry=True)
        return super().__call__(path, variables, limits)


def test_a_kernel_that_could_not_start_is_retried_within_the_run(hw, subs):
    from grader.grade_one import RETRIES

    execute = FlakyStart(RETRIES)
    r = _by_id(_run(hw, subs, execute))
    assert r["alice"].status == "graded" and r["alice"].points == r["alice"].max_points
    assert sum(1 for p, *_ in execute.calls if p.name == "alice.ipynb") == RETRIES + 1


def test_a_kernel_that_never_started_is_not_kept_and_the_next_run_grades_it(hw, subs):
    from grader.grade_one import RETRIES

    first = _by_id(_run(hw, subs, FlakyStart(RETRIES + 1)))
    assert first["alice"].status == "failed" and first["alice"].execution["retry"] is True
    again = FakeExecute()
    second = _by_id(_run(hw, subs, again))  # no --force
    assert [p.name for p, *_ in again.calls] == ["alice.ipynb"]  # only the one not graded
    assert second["alice"].status == "graded"
    assert second["alice"].points == second["alice"].max_points


def test_an_empty_submissions_folder_is_refused_naming_the_files_expected(hw, tmp_path):
    empty = tmp_path / "empty"
    empty.mkdir()
    (empty / "README.txt").write_text("hand in here")  # a stray file is not a submission
    with pytest.raises(UsageError) as err:
        _run(hw, empty, FakeExecute())
    message = str(err.value)
    assert message.startswith(f"no submissions found in {empty}")
    assert "alice.ipynb, bob.ipynb, carol.ipynb" in message and "README.txt" in message
    assert not (hw / "graded").exists()  # refused before anything was written


def test_a_class_where_one_student_handed_in_is_graded(hw, tmp_path):
    subs = tmp_path / "one"
    subs.mkdir()
    (subs / "alice.ipynb").write_text(_notebook(hw, "alice"))
    report = _run(hw, subs, FakeExecute())
    assert [r.status for r in report.results] == ["graded"] + ["missing"] * (len(ROSTER) - 1)


def _generated_copy(hw: Path, folder: Path, kinds: dict[str, str]) -> Path:
    """``folder`` holding, for each student of ``kinds``, their generated notebook of that kind
    (``release`` or ``solutions``), copied byte for byte."""
    folder.mkdir()
    for sid, kind in kinds.items():
        shutil.copyfile(hw / kind / f"{sid}.ipynb", folder / f"{sid}.ipynb")
    return folder


@pytest.mark.parametrize(("case", "fragment"), [
    ("release", "is the assignment's release folder (the blank notebooks handed out), not "
                "submissions: grading it would give every student 0"),
    ("solutions", "is the assignment's solutions folder (the key's answers filled in), not "
                  "submissions: grading it would give every student full marks"),
    ("link to solutions", "is the assignment's solutions folder"),
    ("copy of release", "every submission in {subs} (6) is byte for byte the notebook generated "
                        "for its student (6 as in {hw}/release: a copy?)"),
    ("copies of both", "(1 as in {hw}/release, 2 as in {hw}/solutions: a copy?), not one a "
                       "student worked in: grading them would give 0 or full marks as they came"),
])
def test_the_assignments_own_notebooks_are_refused_as_submissions(hw, tmp_path, case, fragment):
    """Issue 30: ``grade HW HW/release`` gave everyone 0 and ``HW/solutions`` full marks, with
    exit status 0 and no warning; by real path or by content, the run is refused before it
    writes anything."""
    subs = {"release": hw / "release", "solutions": hw / "solutions"}.get(case)
    if case == "link to solutions":
        subs = tmp_path / "handed-in"
        subs.symlink_to(hw / "solutions")
    elif case == "copy of release":
        subs = _generated_copy(hw, tmp_path / "subs", dict.fromkeys(ROSTER, "release"))
    elif case == "copies of both":
        subs = _generated_copy(hw, tmp_path / "subs", {"alice": "release", "bob": "solutions",
                                                       "carol": "solutions"})
    with pytest.raises(UsageError) as err:
        _run(hw, subs, FakeExecute())
    message = str(err.value)
    assert fragment.format(subs=subs, hw=hw) in message, message
    assert message.endswith("or --yes to grade it all the same")
    assert not (hw / "graded").exists()


def test_a_class_where_some_handed_in_the_notebook_as_generated_is_graded(hw, tmp_path):
    subs = _generated_copy(hw, tmp_path / "subs", {"alice": "release", "bob": "solutions"})
    (subs / "carol.ipynb").write_text(_notebook(hw, "carol"))  # worked in: other bytes
    r = _by_id(_run(hw, subs, FakeExecute()))
    assert r["alice"].points == 0 and r["bob"].points == r["carol"].points == r["bob"].max_points


def test_yes_grades_the_solutions_folder_all_the_same(hw, capsys):
    from eulertop.cli import build_parser
    from grader.cli import run_grade

    def grade(*options: str) -> int:
        args = build_parser("grade").parse_args(["grade", str(hw), str(hw / "solutions"),
                                                 *options])
        return run_grade(args, execute=FakeExecute())

    assert grade() == 2
    err = capsys.readouterr().err
    assert err.startswith(f"eulertop grade: {hw / 'solutions'} is the assignment's solutions")
    assert err.count("\n") == 1 and "Traceback" not in err
    assert not (hw / "graded").exists()
    assert grade("--yes") == 0
    with open(hw / "graded" / "grades.csv", newline="") as f:
        assert all(row["total"] == row["maximum"] != "0" for row in csv.DictReader(f))


@pytest.mark.parametrize("where", ["inside", "same"])
def test_an_output_folder_inside_the_submissions_is_refused(hw, subs, where):
    out = subs / "graded" if where == "inside" else subs
    with pytest.raises(UsageError, match="inside the submissions folder"):
        _run(hw, subs, FakeExecute(), out=out)
    assert not (subs / "graded").exists()


def test_no_lock_file_is_left_after_a_run(hw, subs, first_run):
    assert not (hw / "graded" / ".lock").exists()
    with run_lock(hw / "graded"):
        assert (hw / "graded" / ".lock").is_file()
    assert not (hw / "graded" / ".lock").exists()
    with pytest.raises(RuntimeError), run_lock(hw / "graded"):
        raise RuntimeError("a run that fails")
    assert not (hw / "graded" / ".lock").exists()


def test_a_run_that_locked_a_removed_lock_file_takes_the_new_one(hw, subs, first_run,
                                                                  monkeypatch):
    """The race of removing a lock file: a run opens OUT/.lock, the holder removes it and
    releases, the run locks the removed file. It must notice and lock the file the path names
    now, or it and a third run would both hold "the" lock."""
    import grader.graded_folder as graded_folder

    real_flock = graded_folder.fcntl.flock

    lock = hw / "graded" / ".lock"
    calls = []

    def flock_after_removal(fd, op):
        if not calls:  # first attempt: the holder removes the file just before we lock it
            lock.unlink()
        calls.append(fd)
        return real_flock(fd, op)

    monkeypatch.setattr(graded_folder.fcntl, "flock", flock_after_removal)
    with run_lock(hw / "graded"):
        assert len(calls) == 2  # the first file was found removed; the second one is held
        assert lock.is_file()
        monkeypatch.setattr(graded_folder.fcntl, "flock", real_flock)
        with pytest.raises(RunInProgress):  # and it really is the lock others see
            with run_lock(hw / "graded"):
                pass
    assert not lock.exists()


@pytest.mark.parametrize("case", ["empty", "out inside"])
def test_the_command_exits_2_with_one_line(hw, subs, tmp_path, capsys, case):
    from eulertop.cli import main

    if case == "empty":
        (tmp_path / "empty").mkdir()
        argv = ["grade", str(hw), str(tmp_path / "empty")]
        expected = f"eulertop grade: no submissions found in {tmp_path / 'empty'}"
    else:
        argv = ["grade", str(hw), str(subs), "--out", str(subs / "graded")]
        expected = "eulertop grade: the output folder"
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert err.startswith(expected) and err.count("\n") == 1 and "Traceback" not in err


@pytest.mark.parametrize("reveal", [False, True])
def test_each_students_key_is_derived_once_per_run(hw, subs, monkeypatch, reveal):
    """Issue 24: the plan, the records, the pages (with ``--reveal`` the key's values) and the
    class report all use each student's key; it is derived from key.json once per run
    (round 2 derived it three or four times)."""
    import grader.assignment

    derived = []
    real = grader.assignment.key_answers

    def counting(key, student_id):
        derived.append(student_id)
        return real(key, student_id)

    monkeypatch.setattr(grader.assignment, "key_answers", counting)
    _run(hw, subs, FakeExecute(), reveal=reveal)
    assert sorted(derived) == sorted(ROSTER)


def _cells(path: Path) -> list[list[str]]:
    with open(path, newline="", encoding="utf-8") as f:
        return list(csv.reader(f))


def test_points_are_shown_to_four_significant_figures_and_recorded_exactly(hw, subs, capsys):
    """Issue 30: totals were shown as ``7.333333333``. A third of a point given by an override
    (``eulertop override``, then a grading run that applies it) is recorded as the float it is
    and shown as 0.3333 — its totals as ``<n>.333`` — in every view: grades.csv, answers.csv,
    the change lines, the progress and summary lines, the feedback page, the report's table
    and the LMS imports."""
    from eulertop.cli import build_parser, main
    from grader.cli import run_grade
    from grader.lms.export import build_grades

    def grade() -> str:
        args = build_parser("grade").parse_args(["grade", str(hw), str(subs), "--force"])
        run_grade(args, execute=FakeExecute())
        return "".join(capsys.readouterr())

    grade()
    variable = _variables(hw, "alice")[0]
    assert main(["override", str(hw), "alice", variable, "--points", repr(1 / 3),
                 "--reason", "a third of the way"]) == 0
    said = capsys.readouterr().out
    out = hw / "graded"
    record = read_result(out / "results" / "alice.json")
    whole = int(record.max_points) - 1  # every other answer right, one point each
    q1 = len(_key(hw)["students"]["alice"]["questions"][0]["answers"]) - 1
    assert record.points == whole + 1 / 3 and record.answers[0].verdict.points == 1 / 3
    assert re.search(rf"alice\s+{variable}\s+1 → 0\.3333 ", said), said
    assert re.search(rf"alice\s+total\s+{whole + 1} → {whole}\.333 ", said), said
    printed = grade()
    assert f"alice: {whole}.333/{whole + 1}" in printed  # the progress line
    assert re.search(rf"^alice\s+graded\s+{whole}\.333\s+{whole + 1}$", printed, re.M)
    grades = _cells(out / "grades.csv")
    alice = dict(zip(grades[0], next(r for r in grades if r[0] == "alice"), strict=True))
    assert (alice["q1"], alice["total"]) == (f"{q1}.333", f"{whole}.333")
    answers = _cells(out / "answers.csv")
    row = dict(zip(answers[0], next(r for r in answers if r[:1] + r[3:4] == ["alice", variable]),
                   strict=True))
    assert (row["points"], row["max"]) == ("0.3333", "1")
    assert row["overridden"] == "was 1: a third of the way"  # and no other answer is marked
    assert [r[0] for r in answers[1:] if r[-1]] == ["alice"]
    page = (out / "feedback" / "alice.html").read_text()
    assert f"{whole}.333 of {whole + 1} points" in page and "0.3333 / 1" in page
    report = _cells(out / "report.csv")
    assert dict(zip(report[0], next(r for r in report if r[0] == "alice"),
                    strict=True))["points"] == f"{whole}.333"
    grades, _, _ = build_grades(hw, out)  # what every LMS import writes
    assert grades.scores["alice"] == f"{whole}.333"
    assert grades.feedback["alice"].startswith(f"{whole}.333 of {whole + 1} points; Q1 {q1}.333/")
    for path in (out / "grades.csv", out / "answers.csv", out / "report.csv",
                 out / "feedback" / "alice.html"):
        assert "3333333" not in path.read_text(), path
    assert "3333333" not in said + printed
