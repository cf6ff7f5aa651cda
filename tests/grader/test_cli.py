"""``eulertop grade`` end to end on a tiny generated class, with real kernels.

One module-scoped run grades: alice (the solutions notebook: all correct), bob (one answer
wrong, and a cell that sleeps so the kill test can interrupt him), carol (a known mistake:
the diagonal of the inertia tensor computed with Σ m x²), dave (missing), erin (a folder with
two notebooks), frank (not JSON) and mallory (not on the roster). Three kernels run in it;
the rest of the tests reuse it, or need no kernel.
"""

from __future__ import annotations

import csv
import html
import io
import json
import os
import shutil
import signal
import subprocess
import sys
import tempfile
import time
from contextlib import redirect_stderr, redirect_stdout
from dataclasses import replace
from pathlib import Path

import pytest

from eulertop.cli import build_parser, main
from grader import cli as grader_cli
from grader.graded_folder import run_lock
from grader.progress import Progress
from grader.results import StudentResult, read_result
from problems.generate import generate_assignment
from problems.roster import Roster
from problems.templates import FAMILIES

ROOT = Path(__file__).resolve().parents[2]
ROSTER = ("alice", "bob", "carol", "dave", "erin", "frank")
SLEEP = 3.0  # s, bob's extra cell: long enough to SIGKILL the grader while it runs


def _edit(nb: dict, variable: str, value) -> dict:
    for cell in nb["cells"]:
        src = "".join(cell["source"]) if isinstance(cell["source"], list) else cell["source"]
        cell["source"] = "\n".join(f"{variable} = {value!r}" if line.startswith(f"{variable} =")
                                   else line for line in src.splitlines())
    return nb


def _class(root: Path) -> tuple[Path, Path]:
    hw, subs = root / "HW", root / "subs"
    roster = Roster(("id", "email"), tuple({"id": s, "email": f"{s}@uni.example"}
                                           for s in ROSTER))
    generate_assignment(roster, hw, FAMILIES, problems=["inertia_tensor"], seed=8)
    key = json.loads((hw / "key.json").read_text())["students"]
    solution = lambda sid: json.loads((hw / "solutions" / f"{sid}.ipynb").read_text())  # noqa: E731
    (subs / "erin").mkdir(parents=True)
    (subs / "alice.ipynb").write_text(json.dumps(solution("alice")))
    bob = _edit(solution("bob"), "q1_I_diag", [1.0, 2.0, 3.0])
    bob["cells"].append({"cell_type": "code", "id": "slow", "metadata": {}, "outputs": [],
                         "execution_count": None, "source": f"import time; time.sleep({SLEEP})"})
    (subs / "bob.ipynb").write_text(json.dumps(bob))
    i_diag = key["carol"]["questions"][0]["answers"][0]
    assert i_diag["name"] == "I_diag" and i_diag["mistakes"]
    carol = _edit(solution("carol"), "q1_I_diag", i_diag["mistakes"][0]["value"])
    (subs / "carol.ipynb").write_text(json.dumps(carol))
    for name in ("a", "b"):
        (subs / "erin" / f"{name}.ipynb").write_text(json.dumps(solution("erin")))
    (subs / "frank.ipynb").write_text('{"cells": [')
    (subs / "mallory.ipynb").write_text(json.dumps(solution("alice")))
    return hw, subs


@pytest.fixture(scope="module")
def graded(tmp_path_factory):
    """The reference run: (hw, subs, exit status, stdout, stderr, results by id)."""
    hw, subs = _class(tmp_path_factory.mktemp("cli"))
    stdout, stderr = io.StringIO(), io.StringIO()  # module scope: no capsys
    with redirect_stdout(stdout), redirect_stderr(stderr):
        code = main(["grade", str(hw), str(subs), "--jobs", "2", "--timeout", "60"])
    stdout, stderr = stdout.getvalue(), stderr.getvalue()
    results = {s: read_result(hw / "graded" / "results" / f"{s}.json") for s in ROSTER}
    return hw, subs, code, stdout, stderr, results


# -- what a row says (issue 30): a class graded with real kernels whose rows must say what
# -- happened in words — a cell that raised and one stopped by --cell-timeout, a notebook made
# -- for another student, one from elsewhere (no eulertop metadata), an answer that cannot
# -- be read — graded all the same

TOLD = ("ann", "ben", "cy", "dot", "eve", "fay")


@pytest.fixture(scope="module")
def told(tmp_path_factory):
    """(hw, exit status, stdout, grades.csv rows by id, records by id)."""
    from tests.grader.golden import UNREADABLE_CLASSES, code_cell

    root = tmp_path_factory.mktemp("told")
    hw, subs = root / "HW", root / "subs"
    generate_assignment(Roster(("id",), tuple({"id": s} for s in TOLD)), hw, FAMILIES,
                        problems=["inertia_tensor"], seed=8)
    solution = lambda sid: json.loads((hw / "solutions" / f"{sid}.ipynb").read_text())  # noqa: E731
    subs.mkdir()
    ann = solution("ann")
    ann["cells"][3:3] = [code_cell("ratio = 1 / 0", "raises"),
                         code_cell("while True:\n    pass", "spins")]
    elsewhere = solution("dot")
    del elsewhere["metadata"]["eulertop"]  # e.g. a notebook of the student's own making
    eve = solution("eve")
    eve["cells"].append(code_cell(UNREADABLE_CLASSES + "q1_moments = wrapped(Hangs, q1_moments)",
                                  "unreadable"))
    fay = solution("cy")
    fay["metadata"]["eulertop"]["student"] = "fay"  # a classmate's copy, its name made hers
    for sid, nb in {"ann": ann, "ben": solution("cy"), "cy": solution("cy"), "dot": elsewhere,
                    "eve": eve, "fay": fay}.items():
        (subs / f"{sid}.ipynb").write_text(json.dumps(nb))
    stdout = io.StringIO()
    with redirect_stdout(stdout), redirect_stderr(io.StringIO()):
        code = main(["grade", str(hw), str(subs), "--jobs", "2", "--cell-timeout", "1"])
    with open(hw / "graded" / "grades.csv", newline="") as f:
        rows = {r["id"]: r for r in csv.DictReader(f)}
    records = {s: read_result(hw / "graded" / "results" / f"{s}.json") for s in TOLD}
    return hw, code, stdout.getvalue(), rows, records


def test_a_row_names_the_cells_that_raised_or_timed_out(told):
    hw, code, _, rows, _ = told
    assert code == 0
    assert rows["ann"]["status"] == "graded" and rows["ann"]["total"] == rows["ann"]["maximum"]
    assert rows["ann"]["reason"] == ("cell 4 (`ratio = 1 / 0`): ZeroDivisionError: division by "
                                     "zero; cell 5 (`while True:`): timed out after 1 s and was "
                                     "interrupted")
    assert rows["cy"]["reason"] == ""
    page = (hw / "graded" / "feedback" / "ann.html").read_text()
    assert "cell 5 (`while True:`): timed out after 1 s" in page


def test_a_notebook_not_this_assignments_is_graded_and_named_so(told):
    hw, _, stdout, rows, records = told
    assert rows["ben"]["reason"] == ("another student's notebook: its metadata names student "
                                     "'cy'; it was graded as 'ben', from its file name, all the "
                                     "same")
    assert rows["dot"]["reason"] == ("not this assignment's notebook: it has no eulertop answer "
                                     "list in its metadata; it was graded as 'dot', from its "
                                     "file name, all the same")
    assert rows["dot"]["total"] == rows["dot"]["maximum"]  # its answers are right: credited
    assert records["ben"].points < records["ben"].max_points  # cy's values on ben's key
    assert {s for s, r in records.items() if r.execution.get("foreign")} == {"ben", "dot", "fay"}
    assert "not this assignment's notebook, another student's or another variant's, graded all " \
           "the same (3): ben, dot, fay" in stdout
    page = html.unescape((hw / "graded" / "feedback" / "dot.html").read_text())
    assert "not this assignment's notebook: it has no eulertop answer list" in page


def test_a_classmates_notebook_renamed_as_ones_own_is_named_another_variants(told):
    """fay handed in cy's notebook with its metadata made to name her: its parameters cell
    holds cy's parameters, drawn for another shape of body than hers (read here from the
    manifest), and the row says so."""
    hw, _, _, rows, records = told
    manifest = json.loads((hw / "assignment.json").read_text())
    (cy,), (fay,) = (manifest["students"][s]["questions"] for s in ("cy", "fay"))
    assert not set(cy["params"]) & set(fay["params"])  # the premise of this seed's class
    theirs = [f"q1_{name}" for name in cy["params"]]
    assert rows["fay"]["reason"] == (
        f"another variant's notebook: its parameters cell holds none of this student's "
        f"parameters ({', '.join(theirs[:3])}{', …' if len(theirs) > 3 else ''} instead); it "
        f"was graded as 'fay', from its file name, all the same")
    assert records["fay"].points < records["fay"].max_points  # cy's values on fay's key
    assert not records["cy"].execution.get("foreign") and rows["cy"]["reason"] == ""
    # each record keeps which parameters it was graded as: the student's own
    assert records["fay"].execution["variant"] != records["cy"].execution["variant"]


def test_an_answer_that_cannot_be_read_is_named_in_its_row_and_fails_alone(told):
    hw, _, _, rows, records = told
    eve = records["eve"]
    unread = {a.variable: a.verdict for a in eve.answers if a.verdict.status != "correct"}
    assert list(unread) == ["q1_moments"]
    message = "q1_moments could not be read: its value did not convert within 2 s (a loop " \
              "that does not end?)"
    assert unread["q1_moments"].message == message
    assert rows["eve"]["reason"] == message
    assert eve.points == eve.max_points - 1
    assert html.escape(message, quote=True) in (hw / "graded" / "feedback" / "eve.html").read_text()


def test_exit_status_one_lists_what_could_not_be_graded(graded):
    _, _, code, _, stderr, _ = graded
    assert code == 1
    listed = stderr.split("could not be graded:")[1]
    for fragment in ("erin: 2 notebooks", "frank: not a valid notebook",
                     "'mallory' is not on the roster"):
        assert fragment in listed
    assert "Traceback" not in stderr


def test_each_student_is_graded_as_expected(graded):
    r = graded[-1]
    assert {s: x.status for s, x in r.items()} == {
        "alice": "graded", "bob": "graded", "carol": "graded", "dave": "missing",
        "erin": "failed", "frank": "failed"}
    n = len(r["alice"].answers)  # inertia_tensor: one point per answer
    assert r["alice"].points == r["alice"].max_points == n > 1
    assert [a.verdict.status for a in r["bob"].answers] == ["wrong"] + ["correct"] * (n - 1)
    mistake = json.loads((graded[0] / "key.json").read_text())["students"]["carol"][
        "questions"][0]["answers"][0]["mistakes"][0]
    first = r["carol"].answers[0].verdict
    assert (first.status, first.mistake) == ("wrong", mistake["name"])
    assert first.message == mistake["feedback"]
    assert all(x.points == 0 for s, x in r.items() if s in ("dave", "erin", "frank"))
    assert r["alice"].execution["status"] == "ok"
    assert r["alice"].sandboxed  # the default: in the bubblewrap sandbox (issue 5)


def test_gradebook_summary_and_feedback(graded):
    hw, _, _, stdout, _, r = graded
    with open(hw / "graded" / "grades.csv", newline="") as f:
        rows = list(csv.reader(f))
    n = str(len(r["alice"].answers))
    assert rows[0] == ["id", "email", "q1", "total", "maximum", "status", "reason"]
    assert rows[1] == ["alice", "alice@uni.example", n, n, n, "graded", ""]
    assert rows[2][3:] == [str(int(n) - 1), n, "graded", ""]
    assert rows[4] == ["dave", "dave@uni.example", "0", "0", n, "missing", "no submission"]
    erin, frank = rows[5], rows[6]
    assert erin[5] == frank[5] == "failed"
    assert "2 notebooks" in erin[6] and "not a valid notebook" in frank[6]
    assert "3 graded, 1 missing, 2 failed of 6 students" in stdout
    # per answer, over the 3 graded: alice right, bob wrong on I_diag, carol a known mistake
    counts = {line.split()[0]: line.split()[1:] for line in stdout.splitlines()
              if line.startswith("q1_")}
    assert counts["q1_I_diag"] == ["1", "1", "1", "0", "0"]
    assert all(sum(map(int, c)) == 3 for c in counts.values())
    page = (hw / "graded" / "feedback" / "carol.html").read_text()
    assert html.escape(r["carol"].answers[0].verdict.message) in page
    key = json.loads((hw / "key.json").read_text())["students"]["carol"]
    # carol submitted a mistake for answer 0: its key value is not on her page unless revealed
    assert json.dumps(key["questions"][0]["answers"][0]["value"]) not in page


def test_a_rerun_grades_nothing_and_reveal_rewrites_the_feedback(graded, capsys):
    hw, subs, *_ = graded
    t0 = time.monotonic()
    assert main(["grade", str(hw), str(subs), "--reveal"]) == 1
    assert time.monotonic() - t0 < 5  # nothing executed (a kernel alone takes ~1 s)
    assert "6 unchanged, kept" in capsys.readouterr().out
    again = {s: read_result(hw / "graded" / "results" / f"{s}.json") for s in ROSTER}
    assert again == graded[-1]  # graded_at included: nothing was rewritten
    key = json.loads((hw / "key.json").read_text())["students"]["carol"]
    page = (hw / "graded" / "feedback" / "carol.html").read_text()
    assert json.dumps(key["questions"][0]["answers"][0]["value"]) in page


def _stable(r: StudentResult) -> StudentResult:
    return replace(r, graded_at="", execution={**r.execution, "duration": 0.0})


def test_sigkill_mid_run_then_resume_equals_an_uninterrupted_run(graded, tmp_path):
    hw0, subs0, *_, reference = graded
    hw = Path(shutil.copytree(hw0, tmp_path / "HW", ignore=shutil.ignore_patterns("graded")))
    subs = Path(shutil.copytree(subs0, tmp_path / "subs"))
    results = hw / "graded" / "results"
    scratch = tmp_path / "tmp"  # the killed run's kernel folders land here, not in /tmp
    scratch.mkdir()
    proc = subprocess.Popen(
        [sys.executable, "-m", "eulertop", "grade", str(hw), str(subs), "--jobs", "1"],
        cwd=ROOT, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, start_new_session=True,
        env={**os.environ, "TMPDIR": str(scratch)})
    try:
        deadline = time.monotonic() + 60
        while not (results / "alice.json").exists():  # alice done: bob is sleeping now
            assert proc.poll() is None and time.monotonic() < deadline
            time.sleep(0.05)
        time.sleep(0.5)
        os.kill(proc.pid, signal.SIGKILL)
        proc.wait()
    finally:
        try:
            os.killpg(proc.pid, signal.SIGKILL)  # the grader's own kernels, started by us
        except ProcessLookupError:
            pass
    written = sorted(results.glob("*.json"))
    assert "bob.json" not in [p.name for p in written]  # killed before bob was done
    assert all(read_result(p) is not None for p in written)  # nothing half-written
    assert main(["grade", str(hw), str(subs), "--jobs", "2"]) == 1
    resumed = {s: read_result(results / f"{s}.json") for s in ROSTER}
    assert {s: _stable(r) for s, r in resumed.items()} == \
        {s: _stable(r) for s, r in reference.items()}
    assert not [p for p in (hw / "graded").rglob(".*") if p.name != ".lock"]


def test_a_concurrent_run_waits_then_is_refused(graded, capsys):
    hw, subs, *_ = graded
    with run_lock(hw / "graded"):
        assert main(["grade", str(hw), str(subs), "--wait", "0.2"]) == 2
    err = capsys.readouterr().err
    assert "waiting for another command" in err
    assert "still holds this folder after 0.2 s of waiting" in err and "Traceback" not in err


@pytest.mark.parametrize(("case", "fragment"), [
    ("no HW", "no such assignment folder"),
    ("no key", "no answer key"),
    ("no submissions", "not a readable folder of submissions"),
])
def test_usage_errors_exit_2_without_traceback(graded, tmp_path, capsys, case, fragment):
    hw, subs = graded[0], graded[1]
    if case == "no HW":
        hw = tmp_path / "absent"
    elif case == "no key":
        hw = Path(shutil.copytree(hw, tmp_path / "HW", ignore=shutil.ignore_patterns("key.json")))
    else:
        subs = tmp_path / "absent"
    assert main(["grade", str(hw), str(subs)]) == 2
    err = capsys.readouterr().err
    assert fragment in err and "Traceback" not in err


@pytest.mark.parametrize("option", [["--jobs", "0"], ["--timeout", "-1"], ["--timeout", "x"]])
def test_bad_options_are_usage_errors(option, capsys):
    with pytest.raises(SystemExit) as stop:
        main(["grade", "HW", "SUBS", *option])
    assert stop.value.code == 2


def _grade_args(*options: str):
    return build_parser("grade").parse_args(["grade", "HW", "SUBS", *options])


def test_timeout_sets_the_whole_notebook_limit_and_caps_the_cells():
    limits = grader_cli._limits(_grade_args("--timeout", "5"))
    assert (limits.total_timeout, limits.effective_cell_timeout) == (5.0, 5.0)
    assert grader_cli._limits(_grade_args()) == type(limits)()


def test_a_cell_limit_above_the_notebook_limit_is_clipped_with_a_note(capsys):
    limits = grader_cli._limits(_grade_args("--timeout", "20", "--cell-timeout", "45"))
    assert (limits.total_timeout, limits.effective_cell_timeout) == (20.0, 20.0)
    assert "a cell gets at most 20 s" in capsys.readouterr().err
    assert grader_cli._limits(_grade_args("--cell-timeout", "3")).effective_cell_timeout == 3.0


@pytest.mark.parametrize(("text", "size"), [("20", 20 * 1024**2), ("500K", 500 * 1024),
                                            ("2MiB", 2 * 1024**2), ("1G", 1024**3)])
def test_max_size_reads_sizes_with_units(text, size):
    assert grader_cli._limits(_grade_args("--max-size", text)).submission_bytes == size


@pytest.mark.parametrize("text", ["0", "-5M", "lots", "5X"])
def test_a_bad_max_size_is_a_usage_error(text):
    with pytest.raises(SystemExit) as stop:
        main(["grade", "HW", "SUBS", "--max-size", text])
    assert stop.value.code == 2


def test_check_is_served_from_grader_cli():
    args = build_parser("check").parse_args(["check", "nb.ipynb"])
    assert args._module == "grader.cli"
    assert callable(grader_cli.run_check)


def _result(sid: str, status: str, points: float) -> StudentResult:
    return StudentResult(sid, status, "", (), points, 3.0, None, "sha256:0", {}, False, "")


def test_progress_is_plain_lines_off_a_terminal_and_a_bar_on_one(tmp_path):
    with open(tmp_path / "log", "w+") as stream:
        p = Progress(2, stream, tty=False)
        p(_result("alice", "graded", 2.0))
        p(_result("bob", "failed", 0.0))
        stream.seek(0)
        assert stream.read() == "[1/2] alice: 2/3\n[2/2] bob: failed\n"
    with open(tmp_path / "tty", "w+", newline="") as stream:
        p = Progress(2, stream, tty=True)
        p(_result("alice", "graded", 2.0))
        p(_result("bob", "failed", 0.0))
        stream.seek(0)
        text = stream.read()
    assert text.count("\r") == 2 and text.endswith("2/2, 1 failed  bob: failed\n")


def test_the_console_script_leaves_at_once_with_all_said_and_written(graded, tmp_path):
    """``python -m eulertop grade`` ends without the interpreter's teardown
    (``eulertop.cli.QUICK_EXIT``): the same status, output and records as the reference run
    in this process, every file written, no run folder left behind."""
    hw0, subs, code, stdout, _, reference = graded
    hw = Path(shutil.copytree(hw0, tmp_path / "HW", ignore=shutil.ignore_patterns("graded")))
    with tempfile.TemporaryDirectory(dir="/tmp") as short:  # short: its sockets' paths fit
        scratch = Path(short)
        done = subprocess.run(
            [sys.executable, "-m", "eulertop", "grade", str(hw), str(subs), "--jobs", "2",
             "--timeout", "60"], cwd=ROOT, capture_output=True, text=True, timeout=300,
            env={**os.environ, "TMPDIR": str(scratch)})
        left = list(scratch.iterdir())
    assert done.returncode == code, done.stderr[-2000:]
    assert done.stdout.replace(str(hw), str(hw0)) == stdout
    results = {s: read_result(hw / "graded" / "results" / f"{s}.json") for s in ROSTER}
    assert {s: _stable(r) for s, r in results.items()} == \
        {s: _stable(r) for s, r in reference.items()}
    for name in ("grades.csv", "answers.csv", "report.html"):
        assert (hw / "graded" / name).stat().st_size > 0, name
    assert not left  # the run folder, its zygotes' and kernels': removed
