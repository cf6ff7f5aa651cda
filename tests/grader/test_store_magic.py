"""``%store`` in the grader's kernels (issue 33): it works as in Jupyter — IPython's own
``storemagic``, its database in the kernel's own profile (``$IPYTHONDIR/profile_default/db``,
a folder of that kernel's: its sandbox's tmpfs or its control folder) — in every kind of kernel
the grader runs: a cold ipykernel, a kernel forked outside a sandbox, in a world of its own, and
alone in a bubblewrap of its own. What one kernel stores no later kernel reads; and nothing of
the grader's run folder reaches what a student sees (``eulertop check``'s report, the records,
the feedback pages).

References: the values the test itself stores (``del`` then ``%store -r`` must bring them
back, so a store that failed leaves the answer missing), ipykernel itself (the cold kernel),
and the run folder's name (``eulertop-<pid>-<hex>``, :func:`grader.sandbox.run_folder`).
"""

from __future__ import annotations

import dataclasses
import json
import re
import subprocess
import sys
from pathlib import Path

import nbformat
import pytest
from nbformat.v4 import new_code_cell, new_notebook

from grader.execute import execute_submission
from grader.kernels.local import LocalKernel
from grader.kernels.pool import KernelPool
from grader.limits import Limits
from grader.pipeline import grade_assignment
from grader.sandbox import probe

ROOT = Path(__file__).resolve().parents[2]
LIMITS = Limits(cell_timeout=10.0, total_timeout=60.0)
RUN_FOLDER = re.compile(r"eulertop-\d+-[0-9a-f]{8}")
"""A path into the grader's run folder (:func:`grader.sandbox.run_folder` names it so)."""

ROUND_TRIP = "del {name}\n%store -r {name}"
"""A cell that forgets a variable and takes it back from ``%store``'s database."""

KINDS = ("cold ipykernel", "forked", "forked in its own world", "forked in a bwrap of its own")


@pytest.fixture(scope="module", params=KINDS)
def kernels(request):
    """``(workdir, control, limits) -> kernel`` of one kind, one slot (so that each kernel of
    a kind is forked from the zygote that forked the one before it)."""
    if request.param == "cold ipykernel":
        yield LocalKernel
        return
    sandbox = None if request.param == "forked" else probe()
    if request.param == "forked in a bwrap of its own":
        sandbox = dataclasses.replace(sandbox, per_kernel=True)
    with KernelPool(1, prewarm=False, preload=(), sandbox=sandbox) as pool:
        yield pool.kernel


def _notebook(folder: Path, name: str, cells: list[str]) -> Path:
    path = folder / name / "alice.ipynb"
    path.parent.mkdir()
    nbformat.write(new_notebook(cells=[new_code_cell(c) for c in cells]), path)
    return path


def test_store_takes_back_what_it_stored(kernels, tmp_path):
    path = _notebook(tmp_path, "store", ["x = [1.5, -2.25]\ny = 'top'\n%store x y",
                                         ROUND_TRIP.format(name="x"),
                                         ROUND_TRIP.format(name="y"), "z = 3"])
    run = execute_submission(path, ("x", "y", "z"), LIMITS, kernel_factory=kernels)
    assert (run.status, run.cell_errors) == ("ok", ())
    assert run.answers == {"x": [1.5, -2.25], "y": "top", "z": 3}


def test_what_one_kernel_stores_no_later_kernel_reads(kernels, tmp_path):
    first = _notebook(tmp_path, "first", ["secret = 0.2559\n%store secret"])
    later = _notebook(tmp_path, "later", ["secret = None\n%store -r secret\nz = 1"])
    stored = execute_submission(first, ("secret",), LIMITS, kernel_factory=kernels)
    read = execute_submission(later, ("secret", "z"), LIMITS, kernel_factory=kernels)
    assert (stored.status, stored.cell_errors, stored.answers) == ("ok", (), {"secret": 0.2559})
    assert (read.status, read.cell_errors, read.answers) == ("ok", (), {"secret": None, "z": 1})


def _with_round_trip(nb: dict, variable: str) -> dict:
    """``nb`` with a cell after the one that sets ``variable`` that stores it, forgets it and
    takes it back (``%store`` on the way from the answer to the grader)."""
    cells = nb["cells"]
    at = next(i for i, c in enumerate(cells) if c["cell_type"] == "code" and
              any(line.startswith(f"{variable} = ") for line in "".join(c["source"]).split("\n")))
    cells.insert(at + 1, new_code_cell(f"%store {variable}\n" + ROUND_TRIP.format(name=variable)))
    return nb


def _seen_by_student(text: str) -> list[str]:
    return RUN_FOLDER.findall(text)


def test_eulertop_check_reads_an_answer_store_brought_back(generated_assignment, tmp_path):
    a = generated_assignment
    first = a.variables()[0]
    path = tmp_path / "alice.ipynb"
    path.write_text(json.dumps(_with_round_trip(a.notebook("solutions"), first)),
                    encoding="utf-8")
    done = subprocess.run([sys.executable, "-m", "eulertop", "check", str(path)],
                          capture_output=True, text=True, timeout=300, cwd=ROOT)
    assert done.returncode == 0, done.stdout + done.stderr
    assert "did not finish normally" not in done.stdout
    n = len(a.variables())
    assert f"{n} of {n} answers present and well formed." in done.stdout
    assert re.search(rf"^  ok +{first} ", done.stdout, re.MULTILINE)
    assert _seen_by_student(done.stdout + done.stderr) == []


def test_a_grading_run_reads_what_store_brought_back_and_nothing_of_another(
        generated_assignment, tmp_path):
    """alice stores her first answer, forgets it and takes it back; bob, graded after her by
    a kernel of the same slot, forgets his own and takes back what is stored under its name:
    nothing (what alice stored was hers)."""
    a = generated_assignment
    subs = tmp_path / "subs"
    subs.mkdir()
    first = a.variables("alice")[0]
    (subs / "alice.ipynb").write_text(json.dumps(_with_round_trip(
        a.notebook("solutions", "alice"), first)), encoding="utf-8")
    bob = a.notebook("solutions", "bob")
    bob["cells"].append(new_code_cell(f"del {first}\n%store -r {first}"))
    (subs / "bob.ipynb").write_text(json.dumps(bob), encoding="utf-8")
    out = tmp_path / "graded"
    report = grade_assignment(a.hw, subs, out, jobs=1)
    alice, bob_result = sorted(report.results, key=lambda r: r.student_id)
    assert alice.sandboxed and alice.execution["cell_errors"] == []
    assert alice.points == alice.max_points
    assert {x.variable: x.verdict.status for x in bob_result.answers
            if x.verdict.status != "correct"} == \
        {first: "missing"}
    written = "".join(p.read_text(encoding="utf-8") for p in out.rglob("*")
                      if p.is_file() and p.suffix in (".json", ".html", ".csv"))
    assert _seen_by_student(written) == []


def test_an_error_naming_a_file_of_the_working_folder_names_it_as_the_notebook_does(tmp_path):
    """A cold kernel's working folder is in the run folder; an error that names a file there
    by its whole path shows the file's name, as the student's notebook calls it."""
    path = _notebook(tmp_path, "open", ["import os\nopen(os.path.abspath('nothing-here.csv'))",
                                        "where = os.getcwd()"])
    run = execute_submission(path, ("where",), LIMITS, kernel_factory=LocalKernel)
    assert RUN_FOLDER.search(run.answers["where"])  # the reference: it is in the run folder
    assert run.cell_errors == ("cell 1 (`import os`): FileNotFoundError: [Errno 2] No such "
                               "file or directory: 'nothing-here.csv'",)
