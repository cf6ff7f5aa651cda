"""``eulertop check``: runs the notebook as the grader would and reports the *form* of each
answer, never its correctness; exit 0 / 1 / 2; no traceback for a user's mistake. References:
the answer specs in the generated notebook's metadata and the values the golden notebooks set."""

from __future__ import annotations

import json
import sys
from pathlib import Path

import pytest

from eulertop.cli import main
from grader.check import answer_specs, check_value
from problems.answers import check_spec


def _check(path, capsys) -> tuple[int, str, str]:
    status = main(["check", str(path)])
    out, err = capsys.readouterr()
    return status, out, err


def test_a_fully_answered_notebook_passes(generated_assignment, write_golden, capsys):
    status, out, err = _check(write_golden("all_correct"), capsys)
    n = len(generated_assignment.specs())
    assert status == 0, out
    lines = out.splitlines()
    assert lines[0] == "Ran alice.ipynb as the grader will, in a fresh kernel."
    assert sum(line.startswith("  ok ") for line in lines) == n
    assert f"{n} of {n} answers present and well formed." in lines
    assert "never whether they are right" in lines[-1]
    assert "correct" not in out.replace("never whether they are right", "")
    assert err == ""


def test_missing_and_malformed_answers_are_named_with_the_reason(generated_assignment,
                                                                 write_golden, capsys):
    specs = generated_assignment.specs()
    scalars = [s for s in specs if s["kind"] in ("scalar", "angle")]
    status, out, _ = _check(write_golden("partly_answered"), capsys)
    assert status == 1
    rows = {line.split()[1]: line for line in out.splitlines() if line.startswith("  ")}
    first, second, third = (s["variable"] for s in scalars[:3])
    assert rows[first].split()[0] == "ok" and "well formed: 1.25" in rows[first]
    assert rows[second].split()[0] == "MALFORMED"
    assert rows[second].endswith("the string '2.5', not a number — remove the quotes")
    assert rows[third].split()[0] == "MALFORMED" and "a dict; " in rows[third]
    missing = [v for v, row in rows.items() if row.split()[0] == "MISSING"]
    assert len(missing) == len(specs) - 3
    assert rows[missing[0]].endswith("no answer: the variable is missing or still None")
    assert f"1 of {len(specs)} answers present and well formed; {len(specs) - 3} missing, " \
           "2 malformed." in out


@pytest.mark.parametrize("case, fragment", [
    ("missing", "no such file"),
    ("not_json", "not a notebook: not valid JSON"),
    ("no_metadata", "has no eulertop answer list in its metadata: check works on the notebook "
                    "you were given"),
    ("damaged", "has eulertop metadata that is damaged: check works on the notebook"),
    # read as grade reads a submission (grader.grade_one.run_one): a regular file only
    ("link", "alice.ipynb is a symbolic link, not a file"),
])
def test_usage_errors_exit_2_with_one_line(generated_assignment, write_golden, tmp_path, capsys,
                                           case, fragment):
    path = tmp_path / "alice.ipynb"
    if case == "not_json":
        path = write_golden("not_json")
    elif case in ("no_metadata", "damaged"):
        nb = generated_assignment.notebook("release")
        if case == "no_metadata":
            del nb["metadata"]["eulertop"]
        else:
            nb["metadata"]["eulertop"]["questions"][0]["answers"][0]["kind"] = "number"
        path.write_text(json.dumps(nb))
    elif case == "link":
        path.symlink_to(generated_assignment.release())
    status, out, err = _check(path, capsys)
    assert status == 2 and out == ""
    assert err.startswith("eulertop check: ") and fragment in err
    assert len(err.strip().splitlines()) == 1 and "Traceback" not in err


def test_answer_specs_come_from_the_notebook_metadata(generated_assignment):
    assert answer_specs(generated_assignment.release()) == generated_assignment.specs()


@pytest.mark.parametrize("value, kind, message", [
    ({"__invalid__": "a dict"}, "scalar", "a dict; a number is expected"),
    ({"__invalid__": "the complex number 1+2j"}, "vector",
     "the complex number 1+2j; a list of 3 numbers is expected"),
])
def test_markers_are_malformed_with_their_reason(generated_assignment, value, kind, message):
    spec = next(s for s in generated_assignment.specs() if s["kind"] == kind
                and (kind != "vector" or s["length"] == 3))
    verdict = check_value(spec, value)
    assert (verdict.status, verdict.message, verdict.points) == ("invalid", message, 0.0)


def test_plain_values_are_checked_by_the_problems_own_rules(generated_assignment):
    for spec in generated_assignment.specs():
        assert check_value(spec, None) == check_spec(spec, None)
        assert check_value(spec, "3.0") == check_spec(spec, "3.0")


def test_damaged_spec_entries_do_not_raise():
    verdict = check_value({"variable": "q1_a", "kind": "scalar", "points": "lots"}, 1.0)
    assert verdict.status == "invalid" and "damaged" in verdict.message


def _with_cells(nb: dict, *sources: str) -> dict:
    nb["cells"] += [{"cell_type": "code", "metadata": {}, "source": s, "outputs": [],
                     "execution_count": None} for s in sources]
    return nb


def test_messages_a_student_can_act_on(generated_assignment, tmp_path, capsys):
    """issue 33: input(), no network, and an import from IPython's own files, as
    ``eulertop check`` tells them (references: the cells written here)."""
    nb = _with_cells(generated_assignment.notebook("release"),
                     "name = input('your name? ')",
                     "import urllib.request\nurllib.request.urlopen('http://example.invalid/"
                     "d.csv', timeout=5)",
                     "from IPython.display import no_such_name")
    path = tmp_path / "alice.ipynb"
    path.write_text(json.dumps(nb))
    status, out, _ = _check(path, capsys)
    errors = [line for line in out.splitlines() if line.startswith("  - cell ")]
    assert status == 1 and len(errors) == 3, out
    assert errors[0].endswith("StdinNotImplementedError: raw_input was called, but this "
                              "frontend does not support input requests. — input() waits for "
                              "someone to type, and no one types while the grader runs the "
                              "notebook: write the value into the code instead")
    assert "the grader runs notebooks without a network: put the data you need into the " \
           "notebook itself" in errors[1]
    assert errors[2].endswith("ImportError: cannot import name 'no_such_name' from "
                              "'IPython.display' (IPython/display.py)")
    assert "-packages" not in out and str(Path(sys.prefix)) not in out


def test_a_notebook_of_another_language_is_named_so(generated_assignment, tmp_path, capsys):
    nb = _with_cells(generated_assignment.notebook("release"), "x <- c(1, 2)")
    nb["metadata"]["kernelspec"] = {"name": "ir", "display_name": "R", "language": "R"}
    path = tmp_path / "alice.ipynb"
    path.write_text(json.dumps(nb))
    _, out, _ = _check(path, capsys)
    assert out.splitlines()[1] == ("Note: this notebook's kernel runs 'r', but the grader runs "
                                   "every notebook as Python 3: open the notebook you were given "
                                   "(Python 3 kernel) and write your code there, in Python.")


def test_an_11_mib_notebook_with_one_emoji_is_read(generated_assignment, tmp_path):
    """issue 33: a limit of 40 MiB on the decoded text once refused it (44 MiB at 4 bytes a
    character), whatever --max-size said."""
    nb = generated_assignment.notebook("release")
    nb["cells"][0]["outputs"] = []
    nb["cells"].append({"cell_type": "markdown", "metadata": {},
                        "source": "a" * (11 * 1024**2) + "\U0001F600"})
    path = tmp_path / "alice.ipynb"
    path.write_text(json.dumps(nb, ensure_ascii=False), encoding="utf-8")
    assert 11 * 1024**2 < path.stat().st_size < 12 * 1024**2
    assert answer_specs(path) == generated_assignment.specs()
