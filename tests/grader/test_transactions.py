"""Every change to a graded class whole or not at all (issue 30): refused commands write
nothing, concurrent ones wait and none is lost, a command killed at any step of its commit
leaves the class as before or as after, and the trail names every change that reached the disk.

The class: three students, two families with follow-through chains, graded with a fake
execution stage that reads the literals a submission's code cell assigns (no kernel: what is
under test is what happens to the records). "State" is every file of the assignment folder as
a person reads it, with the times of day, the kept key's time stamp and transaction ids
masked: two runs of one command give the same state.
"""

from __future__ import annotations

import json
import os
import re
import shutil
import signal
import stat
import subprocess
import sys
import time
from pathlib import Path

import nbformat
import pytest

import grader.transaction as transaction
from eulertop.cli import main
from grader.audit import AUDIT, read_trail
from grader.graded_folder import RESULTS, run_lock
from grader.overrides import OVERRIDES
from grader.pipeline import grade_assignment
from grader.results import read_result
from grader.transaction import JOURNAL, class_lock
from problems.generate import generate_assignment, key_hash
from problems.roster import Roster
from problems.templates import FAMILIES
from tests.grader.report.synthetic_class import LiteralExecute

ROOT = Path(__file__).resolve().parents[2]
STUDENTS = ("ada", "ben", "cy")
PROBLEMS = ("sleeping_top", "euler_rotation")
_TIME = re.compile(r"\d{4}-\d\d-\d\dT\d\d:\d\d:\d\d(\.\d+)?(\+00:00|Z)?")
_KEPT_KEY = re.compile(r"key\.json\.\d{8}T\d{6}Z(-\d+)?")
_TX = re.compile(r'"(transaction|run)": "[0-9a-f]{32}"')


def _key(hw: Path) -> dict:
    return json.loads((hw / "key.json").read_text())


def _answers(hw: Path, sid: str, wrong: bool) -> dict:
    """``sid``'s key values; with ``wrong``, the first answer of each question doubled."""
    answers = {}
    for q in _key(hw)["students"][sid]["questions"]:
        for n, a in enumerate(q["answers"]):
            value = a["value"]
            if wrong and n == 0 and isinstance(value, float):
                value *= 2
            answers[f"q{q['question']}_{a['name']}"] = value
    return answers


def _notebook(answers: dict) -> str:
    code = "\n".join(f"{name} = {value!r}" for name, value in answers.items())
    return nbformat.writes(nbformat.v4.new_notebook(cells=[nbformat.v4.new_code_cell(code)]))


def _write_submissions(hw: Path, subs: Path, extra: dict | None = None) -> Path:
    subs.mkdir(parents=True, exist_ok=True)
    for sid in STUDENTS:
        answers = {**_answers(hw, sid, wrong=sid != "ada"), **(extra or {})}
        (subs / f"{sid}.ipynb").write_text(_notebook(answers))
    return subs


@pytest.fixture(scope="module")
def small_class(tmp_path_factory) -> tuple[Path, Path]:
    root = tmp_path_factory.mktemp("transactions")
    hw = root / "HW"
    roster = Roster(("id",), tuple({"id": s} for s in STUDENTS))
    generate_assignment(roster, hw, FAMILIES, problems=list(PROBLEMS), seed=30)
    subs = _write_submissions(hw, root / "subs")
    grade_assignment(hw, subs, limits="LIMITS", execute=LiteralExecute(), jobs=1)
    return hw, subs


@pytest.fixture
def graded(small_class, tmp_path) -> tuple[Path, Path]:
    hw, subs = small_class
    return Path(shutil.copytree(hw, tmp_path / "HW")), subs


def state(hw: Path) -> dict[str, str]:
    """Every file of ``hw`` but the notebooks handed out, as text with times masked."""
    found = {}
    for path in sorted(hw.rglob("*")):
        rel = path.relative_to(hw).as_posix()
        if path.is_dir() or rel.split("/")[0] in ("release", "solutions") or \
                path.name == ".lock":
            continue
        text = path.read_text(encoding="utf-8", errors="replace")
        found[_KEPT_KEY.sub("key.json.<time>", rel)] = _TX.sub(
            r'"\1": "<id>"', _KEPT_KEY.sub("key.json.<time>", _TIME.sub("<time>", text)))
    return found


def _variable(hw: Path, sid: str, n: int = 0) -> str:
    return read_result(hw / "graded" / RESULTS / f"{sid}.json").answers[n].variable


# -- refused commands write nothing


def test_a_key_change_an_override_forbids_is_refused_and_writes_nothing(graded, capsys):
    """The issue's case: an override of 1 point, then the answer's points set to 0.5."""
    hw, _ = graded
    variable = _variable(hw, "ben")
    assert main(["override", str(hw), "ben", variable, "--points", "0.5",
                 "--reason", "partial"]) == 0
    before = state(hw)
    capsys.readouterr()
    assert main(["key", "set", str(hw), variable, "--points", "0.25"]) == 2
    err = capsys.readouterr().err
    assert "overrides.toml: override 1: 0.5 points for ben's" in err
    assert f"eulertop override HW ben {variable} --remove" in err and "Traceback" not in err
    assert state(hw) == before  # the key too: nothing rewritten
    assert main(["rescore", str(hw)]) == 0  # and nothing was left half-way to block the next


def test_a_refused_override_writes_nothing(graded, capsys):
    hw, _ = graded
    before = state(hw)
    assert main(["override", str(hw), "ben", _variable(hw, "ben"), "--points", "99",
                 "--reason", "x"]) == 2
    assert "outside 0…" in capsys.readouterr().err
    assert state(hw) == before


# -- concurrent commands wait, and none is lost


def _eulertop(*argv: str) -> subprocess.Popen:
    return subprocess.Popen([sys.executable, "-m", "eulertop", *argv], cwd=ROOT,
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)


@pytest.mark.slow
def test_eight_overrides_at_once_all_land(graded):
    hw, _ = graded
    targets = [(sid, _variable(hw, sid, n)) for sid in STUDENTS for n in range(3)][:8]
    runs = [_eulertop("override", str(hw), sid, variable, "--points", "0",
                      "--reason", f"set {sid} {variable}") for sid, variable in targets]
    outcomes = [(p.wait(timeout=600), p.stdout.read(), p.stderr.read()) for p in runs]
    assert [code for code, _, _ in outcomes] == [0] * 8, outcomes
    assert sum("waiting for another command" in err for _, _, err in outcomes) >= 1
    text = (hw / "graded" / OVERRIDES).read_text()
    assert all(f"set {sid} {variable}" in text for sid, variable in targets)
    lines = [e for e in read_trail(hw / "graded") if e["event"] == "override"]
    assert sorted(e["why"] for e in lines) == sorted(f"set {s} {v}" for s, v in targets)
    for sid, variable in targets:  # each record carries its override
        record = read_result(hw / "graded" / RESULTS / f"{sid}.json")
        assert record.overridden[variable]["reason"] == f"set {sid} {variable}"


# -- a kill at any step of a commit


COUNTED = ("fsync", "replace", "write", "unlink", "rename", "fchmod")
_REAL_WRITE = os.write


def _run_until_step(action, step: int | None) -> int:
    """Run ``action()`` (an exit status) in a forked child whose file system calls are
    counted; the child dies (``os._exit``, as a kill would: no clean-up runs) at call number
    ``step``. Returns the calls counted (all of them when ``step`` is None)."""
    read, write = os.pipe()
    pid = os.fork()
    if pid == 0:  # the child
        os.close(read)
        calls = [0]

        def counted(real):
            def call(*args, **kwargs):
                calls[0] += 1
                if step is not None and calls[0] == step:
                    os._exit(77)
                return real(*args, **kwargs)
            return call

        for name in COUNTED:
            setattr(os, name, counted(getattr(os, name)))
        try:
            with open(os.devnull, "w") as quiet:
                sys.stdout = sys.stderr = quiet
                code = action()
        except BaseException:
            code = 99
        _REAL_WRITE(write, json.dumps([code, calls[0]]).encode())
        os._exit(0)
    os.close(write)
    _, status = os.waitpid(pid, 0)
    data = os.read(read, 4096)
    os.close(read)
    if step is not None and os.WEXITSTATUS(status) == 77:
        return step
    code, calls = json.loads(data)
    assert code == 0, f"the command itself failed ({code})"
    return calls


def _recovered(hw: Path) -> None:
    """What the next command does first: take the lock, finish or undo what was left."""
    with class_lock(hw / "graded", hw, command="test"):
        pass


@pytest.mark.slow
@pytest.mark.parametrize("command", ["override", "key set"])
def test_a_kill_at_any_step_leaves_the_class_before_or_after(small_class, tmp_path, command):
    template, _ = small_class
    variable = _variable(template, "ben")
    argv = {"override": ["override", "{hw}", "ben", variable, "--points", "0.5",
                         "--reason", "partial credit"],
            "key set": ["key", "set", "{hw}", variable, "--rtol", "0.9"]}[command]

    def fresh(name: str) -> Path:
        return Path(shutil.copytree(template, tmp_path / name))

    def run(hw: Path, step: int | None) -> int:
        return _run_until_step(lambda: main([a.format(hw=hw) for a in argv]), step)

    before = state(template)
    whole = fresh("whole")
    steps = run(whole, None)
    after = state(whole)
    assert after != before and steps > 5
    outcomes = []
    for step in range(1, steps + 1):
        hw = fresh(f"step{step}")
        run(hw, step)
        _recovered(hw)
        now = state(hw)
        assert now in (before, after), f"step {step} of {steps}: half-written"
        assert not (hw / "graded" / JOURNAL).exists()
        assert not [p for p in hw.rglob(".*.tmp")], f"step {step}: temporaries left"
        outcomes.append("after" if now == after else "before")
        shutil.rmtree(hw)
    # killed early the change is lost whole; killed once committed, it is finished whole
    assert outcomes[0] == "before" and outcomes[-1] == "after"
    assert outcomes == sorted(outcomes, key=["before", "after"].index)  # one commit point


@pytest.mark.slow
def test_a_killed_grading_run_keeps_whole_records_each_in_the_trail(small_class, tmp_path):
    """A forced grading run killed at one step after another: each record on disk is whole
    and the trail has a line for exactly the records that reached the disk (those with a new
    ``graded_at``)."""
    template, subs = small_class

    def run(hw: Path, step: int | None) -> int:
        def action() -> int:
            grade_assignment(hw, subs, limits="LIMITS", execute=LiteralExecute(), jobs=1,
                             force=True)
            return 0
        return _run_until_step(action, step)

    counting = Path(shutil.copytree(template, tmp_path / "count"))
    steps = run(counting, None)
    assert steps > 3 * len(STUDENTS)
    for step in range(1, steps + 1):
        hw = Path(shutil.copytree(template, tmp_path / f"g{step}"))
        stamps = {sid: read_result(hw / "graded" / RESULTS / f"{sid}.json").graded_at
                  for sid in STUDENTS}
        trail_before = len(read_trail(hw / "graded"))
        time.sleep(1.0 if step == 1 else 0.0)  # a new graded_at: a later second than the old
        run(hw, step)
        _recovered(hw)
        now = {sid: read_result(hw / "graded" / RESULTS / f"{sid}.json") for sid in STUDENTS}
        assert all(r is not None for r in now.values()), f"step {step}: a record half-written"
        regraded = {sid for sid, r in now.items() if r.graded_at != stamps[sid]}
        lines = read_trail(hw / "graded")[trail_before:]
        named = {c["student"] for e in lines if e["event"] == "graded" for c in e["changes"]}
        assert named == regraded, f"step {step}: the trail and the records disagree"
        shutil.rmtree(hw)


# -- a SIGKILL at a real instant


@pytest.mark.slow
def test_a_real_kill_at_random_instants(small_class, tmp_path):
    template, _ = small_class
    variable = _variable(template, "cy")
    before = state(template)
    whole = Path(shutil.copytree(template, tmp_path / "whole"))
    assert main(["override", str(whole), "cy", variable, "--points", "0.5", "--reason", "r"]) == 0
    after = state(whole)
    start = time.monotonic()
    run = _eulertop("override", str(whole), "cy", variable, "--points", "0.5", "--reason", "r")
    run.wait(timeout=600)
    duration = time.monotonic() - start
    seen = set()
    for n in range(8):
        hw = Path(shutil.copytree(template, tmp_path / f"k{n}"))
        run = _eulertop("override", str(hw), "cy", variable, "--points", "0.5", "--reason", "r")
        time.sleep(duration * (0.35 + 0.1 * n))  # from start-up to the end of the commit
        run.send_signal(signal.SIGKILL)
        run.wait()
        _recovered(hw)
        now = state(hw)
        assert now in (before, after), f"kill {n}: half-written"
        seen.add(now == after)
        shutil.rmtree(hw)
    assert seen  # at least one kill landed; which side each fell on is chance


# -- the trail


def test_the_trail_is_private(graded):
    hw, _ = graded
    trail = hw / "graded" / AUDIT
    os.chmod(trail, 0o644)  # as an earlier version left it
    assert main(["rescore", str(hw)]) == 0
    assert stat.S_IMODE(os.stat(trail).st_mode) == 0o600
    fresh = hw / "graded2"
    grade_assignment(hw, _write_submissions(hw, hw.parent / "s2"), out=fresh, limits="LIMITS",
                     execute=LiteralExecute(), jobs=1)
    assert stat.S_IMODE(os.stat(fresh / AUDIT).st_mode) == 0o600


def test_a_journal_left_by_a_kill_is_finished_once(graded):
    """A committed journal whose renames were half done and whose trail line already landed:
    the next command finishes the renames and does not write the line again."""
    hw, _ = graded
    out = hw / "graded"
    tx = transaction.Transaction(out)
    target = out / "note.txt"
    tx.write(target, "after")
    tx.trail("test", why="a test change")
    # what commit() does up to the commit point, then a kill
    tmp = transaction._staged(target, b"after", durable=True)
    journal = {"id": tx.id, "renames": [[tmp.name, target.name]], "removes": [],
               "trail": tx._lines}
    transaction._write_journal(out, journal)
    from grader.audit import append_lines

    append_lines(out, tx._lines)  # the trail line got there before the kill
    count = len(read_trail(out))
    _recovered(hw)
    assert target.read_text() == "after" and not tmp.exists()
    assert len(read_trail(out)) == count  # not written twice
    assert not (out / JOURNAL).exists()


# -- a key that gains an answer


def test_a_key_that_gains_an_answer_runs_exactly_those_notebooks_again(graded, tmp_path,
                                                                         capsys):
    hw, _ = graded
    subs = _write_submissions(hw, tmp_path / "subs2", extra={"q1_extra": 1.5})
    execute = LiteralExecute()
    grade_assignment(hw, subs, limits="LIMITS", execute=execute, jobs=1, force=True)
    key = _key(hw)
    for sid in ("ada", "ben"):  # cy's key does not gain it
        entry = key["students"][sid]
        added = dict(entry["questions"][0]["answers"][0], name="extra", value=1.5,
                     mistakes=[], depends_on=[])
        added.pop("accepted", None)
        entry["questions"][0]["answers"].append(added)
        entry["hash"] = key_hash(entry["questions"])
    (hw / "key.json").write_text(json.dumps(key))
    capsys.readouterr()
    assert main(["rescore", str(hw)]) == 0
    said = capsys.readouterr().out
    assert "2 student(s) answered before the key had q1_extra" in said
    assert "runs exactly these: ada, ben" in said
    ada = read_result(hw / "graded" / RESULTS / "ada.json")
    extra = next(a for a in ada.answers if a.variable == "q1_extra")
    assert extra.verdict.status == "missing" and "not read yet" in extra.verdict.message
    assert ada.execution["unread"] == ["q1_extra"]
    assert main(["rescore", str(hw)]) == 0  # a second rescore keeps them unread
    assert read_result(hw / "graded" / RESULTS / "ada.json").execution["unread"] == ["q1_extra"]
    execute.calls = 0
    grade_assignment(hw, subs, limits="LIMITS", execute=execute, jobs=1)
    assert execute.calls == 2  # ada and ben, not cy
    for sid in ("ada", "ben"):
        record = read_result(hw / "graded" / RESULTS / f"{sid}.json")
        assert "unread" not in record.execution
        assert next(a for a in record.answers if a.variable == "q1_extra").verdict.status == \
            "correct"
    execute.calls = 0
    grade_assignment(hw, subs, limits="LIMITS", execute=execute, jobs=1)
    assert execute.calls == 0


def test_a_held_lock_makes_a_command_wait_then_give_up(graded, capsys):
    hw, _ = graded
    with run_lock(hw / "graded", command="eulertop grade"):
        assert main(["rescore", str(hw), "--wait", "0.3"]) == 2
    err = capsys.readouterr().err
    assert "waiting for another command" in err and "eulertop grade" in err
    assert "still holds this folder after 0.3 s" in err


# -- a change touches only whom it reaches


def _bytes(hw: Path) -> dict[str, bytes]:
    return {p.relative_to(hw).as_posix(): p.read_bytes()
            for p in (hw / "graded").rglob("*") if p.is_file()}


@pytest.mark.parametrize("command", ["override", "key set one", "key set all", "rescore"])
def test_a_change_rewrites_only_the_records_and_pages_it_reaches(graded, capsys, command):
    hw, _ = graded
    variable = _variable(hw, "ben")
    argv = {"override": ["override", str(hw), "ben", variable, "--points", "0",
                         "--reason", "r"],
            "key set one": ["key", "set", str(hw), f"ben:{variable}", "--rtol", "0.9"],
            "key set all": ["key", "set", str(hw), variable, "--rtol", "0.9"],
            "rescore": ["rescore", str(hw)]}[command]
    reached = {"override": {"ben"}, "key set one": {"ben"}, "key set all": set(STUDENTS),
               "rescore": set()}[command]  # a rescore of an unchanged key changes nobody
    before = _bytes(hw)
    time.sleep(1.0)  # a record rewritten now would have a later graded_at
    assert main(argv) == 0
    after = _bytes(hw)
    for sid in STUDENTS:
        for path in (f"graded/results/{sid}.json", f"graded/feedback/{sid}.html"):
            assert (after[path] != before[path]) == (sid in reached), (command, path)
    said = capsys.readouterr().out
    assert f"{len(reached) if reached else len(STUDENTS)} student(s) rescored" in said


def test_a_one_student_change_leaves_the_report_marked_out_of_date(graded, capsys):
    """An override rescores one student and leaves the class report to a later command (it
    reads every record and key: seconds, for one student's change): the page says so until
    ``eulertop report`` (or a rescore) rebuilds it."""
    hw, _ = graded
    page = hw / "graded" / "report.html"
    before = page.read_text()
    assert "Out of date" not in before
    ben = read_result(hw / "graded" / RESULTS / "ben.json")
    wrong = next(a for a in ben.answers if a.verdict.points < a.verdict.max_points)
    assert main(["override", str(hw), "ben", wrong.variable, "--points",
                 str(wrong.verdict.max_points), "--reason", "r"]) == 0
    marked = page.read_text()
    assert "Out of date:</strong> grades changed after this report was made" in marked
    assert marked.replace(marked[marked.index('<p class="stale"'):marked.index("</p>", marked.index(
        '<p class="stale"')) + 4], "") == before  # the notice, and nothing else, added
    assert main(["report", str(hw)]) == 0
    assert "Out of date" not in page.read_text()
    assert main(["override", str(hw), "ben", wrong.variable, "--remove"]) == 0
    assert "Out of date" in page.read_text()
    assert main(["rescore", str(hw)]) == 0
    assert "Out of date" not in page.read_text()
