"""The notebooks in ``notebooks/``: committed without outputs, and each runs cleanly.

Every ``notebooks/*.ipynb`` is found by glob, so a new notebook is tested without editing this
file. Each is executed top to bottom in a fresh kernel (nbclient) with ``MPLBACKEND=Agg`` — the
notebooks themselves never choose a backend, so their figures show in Jupyter. The notebooks
assert their own checks against independent references (lecture24: scipy, sympy, ODEs); a
failing assert fails the run. ``example_submission.ipynb`` is also graded by the real grader
against a freshly generated key, and must get full marks.
"""

from __future__ import annotations

import os
import re
import shutil
from pathlib import Path

import nbformat
import pytest
from nbclient import NotebookClient

ROOT = Path(__file__).resolve().parents[1]
NOTEBOOKS = sorted((ROOT / "notebooks").glob("*.ipynb"))
EXAMPLE = ROOT / "notebooks" / "example_submission.ipynb"
EXAMPLE_PROBLEMS = ("euler_kinetic_energy", "turning_points", "motion_type", "sleeping_top")
EXAMPLE_SEED = 2024


def test_the_notebooks_are_there():
    names = {p.name for p in NOTEBOOKS}
    assert {"lecture24.ipynb", "instructor_guide.ipynb", "example_submission.ipynb",
            "speed_vs_accuracy.ipynb"} <= names


@pytest.fixture
def kernel_env(monkeypatch):
    """The kernel inherits this environment: a non-interactive backend, the repo importable."""
    monkeypatch.setenv("MPLBACKEND", "Agg")
    path = [str(ROOT), *filter(None, [os.environ.get("PYTHONPATH")])]
    monkeypatch.setenv("PYTHONPATH", os.pathsep.join(path))


@pytest.mark.parametrize("path", NOTEBOOKS, ids=lambda p: p.name)
def test_committed_without_outputs(path):
    nb = nbformat.read(path, as_version=4)
    nbformat.validate(nb)
    for i, cell in enumerate(nb.cells):
        if cell.cell_type == "code":
            assert cell.outputs == [], f"cell {i} has outputs"
            assert cell.execution_count is None, f"cell {i} has an execution count"
            assert "matplotlib.use(" not in cell.source, f"cell {i} forces a backend"


@pytest.mark.parametrize("path", NOTEBOOKS, ids=lambda p: p.name)
def test_runs_cleanly(path, tmp_path, kernel_env):
    nb = nbformat.read(path, as_version=4)
    client = NotebookClient(nb, timeout=300, kernel_name="python3",
                            resources={"metadata": {"path": str(tmp_path)}})
    client.execute()  # raises CellExecutionError on the first failing cell
    errors = [o for c in nb.cells if c.cell_type == "code" for o in c.outputs
              if o.output_type == "error"]
    assert errors == []


FORMULA_TEXT = re.compile(r"[αβγδθλμπωΩΣ²³½′̇√≤≥×∫⟨⟩ê]|\b[ITLpu][0-9αβγ]\b")
"""What a formula written in plain text or Unicode looks like (ω3, β̇², ½, I1, √, ≥ …)."""


def test_the_lecture_writes_its_formulas_in_latex():
    """lecture24's markdown, outside its ``$ … $`` formulas and ``code``, has no formula in
    Unicode or plain text left: students read it as the physics pages are typeset (issue 33)."""
    nb = nbformat.read(ROOT / "notebooks" / "lecture24.ipynb", as_version=4)
    for i, cell in enumerate(nb.cells):
        if cell.cell_type == "markdown":
            prose = re.sub(r"\$\$.+?\$\$|\$[^$]+\$|`[^`]*`", " ", cell.source, flags=re.S)
            assert FORMULA_TEXT.findall(prose) == [], f"cell {i}"


def test_example_submission_gets_full_marks(tmp_path):
    from grader.limits import Limits
    from grader.pipeline import grade_assignment
    from problems.generate import generate_assignment
    from problems.roster import read_roster
    from problems.templates import FAMILIES

    (tmp_path / "roster.csv").write_text("id,name\nada,Ada Lovelace\n", encoding="utf-8")
    hw = tmp_path / "HW"
    generate_assignment(read_roster(tmp_path / "roster.csv"), hw, FAMILIES,
                        problems=EXAMPLE_PROBLEMS, seed=EXAMPLE_SEED, title="PHY 711 HW 9")
    release = nbformat.read(hw / "release" / "ada.ipynb", as_version=4)
    example = nbformat.read(EXAMPLE, as_version=4)
    params = [next(c.source for c in nb.cells if c.get("id") == "parameters")
              for nb in (release, example)]
    assert params[0] == params[1], "the generator's variant changed: rebuild the example"
    subs = tmp_path / "submissions"
    subs.mkdir()
    shutil.copy(EXAMPLE, subs / "ada.ipynb")
    report = grade_assignment(hw, subs, limits=Limits(total_timeout=120), jobs=1)
    (result,) = report.results
    assert result.status == "graded"
    assert [a.variable for a in result.answers if a.verdict.status != "correct"] == []
    assert result.points == result.max_points > 0
