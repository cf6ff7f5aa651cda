"""The whole-notebook time limit (issue 13): answers set before the cell that ran out of time
are graded; the message names that cell and the limit; a cell that ignores the interrupt still
ends the run at the limit (plus the grace for reading answers)."""

from __future__ import annotations

import time
from pathlib import Path

import nbformat
from nbformat.v4 import new_code_cell, new_notebook

from grader.execute import OUT_OF_TIME_GRACE, execute_submission
from grader.limits import Limits

LIMITS = Limits(cell_timeout=30, total_timeout=4)


def _run(tmp_path: Path, *cells: str):
    path = tmp_path / "eve.ipynb"
    nbformat.write(new_notebook(cells=[new_code_cell(c) for c in cells]), path)
    t0 = time.monotonic()
    return execute_submission(path, ("x", "y", "z"), LIMITS), time.monotonic() - t0


def test_answers_set_before_the_cell_that_ran_out_of_time_are_read(tmp_path):
    result, _ = _run(tmp_path, "x = 41", "y = [1, 2]", "while True:\n    pass", "z = 3")
    assert result.status == "timeout"
    assert result.answers == {"x": 41, "y": [1, 2], "z": None}  # z's cell never ran
    assert "cell 3 (`while True:`)" in result.message and "(4 s)" in result.message
    assert "the answers set before it were read" in result.message
    assert result.cell_errors == ("cell 3 (`while True:`): the notebook's time limit (4 s) ran "
                                  "out while it ran; it was interrupted and the cells after it "
                                  "were not run",)


def test_a_cell_that_ignores_the_interrupt_ends_the_run_with_no_answers(tmp_path):
    result, seconds = _run(tmp_path, "x = 41",
                           "import signal\nsignal.signal(signal.SIGINT, signal.SIG_IGN)\n"
                           "while True:\n    pass")
    assert result.status == "timeout" and result.answers == {}
    assert "no answers could be read" in result.message
    assert seconds < LIMITS.total_timeout + OUT_OF_TIME_GRACE + 10
