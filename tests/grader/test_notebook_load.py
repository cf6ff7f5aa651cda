"""Loading submissions: every unreadable file refused with a message for the student, v3
converted, and only the code cells' sources kept for execution."""

from __future__ import annotations

import json

import nbformat
import pytest

from grader import notebook_load
from grader.notebook_load import (
    SubmissionError,
    code_cells,
    executable_notebook,
    load_submission,
    read_notebook,
)


def _nb(cells, version=4) -> dict:
    return {"nbformat": version, "nbformat_minor": 5, "metadata": {}, "cells": cells}


def _code(source, **extra) -> dict:
    return {"cell_type": "code", "metadata": {}, "source": source, "outputs": [],
            "execution_count": None, **extra}


BAD_FILES = [
    ("not_json", b'{"cells": [', "not a notebook: not valid JSON (line 1, column 12"),
    ("empty_file", b"  \n", "the file is empty, not a notebook"),
    ("latin1", "{\"é\": 1}".encode("latin-1"), "not a notebook: the file is not UTF-8 text"),
    ("json_list", b"[1, 2]", "this is JSON, but not a Jupyter notebook"),
    ("no_version", json.dumps({"cells": []}).encode(), "this is JSON, but not a Jupyter notebook"),
    ("v2", json.dumps(_nb([], version=2)).encode(), "notebook format v2 is not supported"),
    ("v5", json.dumps(_nb([], version=5)).encode(), "notebook format v5 is not supported"),
    ("no_cells", json.dumps(_nb([])).encode(), "the notebook has no code"),
    ("blank_code", json.dumps(_nb([_code("  \n"), {"cell_type": "markdown", "metadata": {},
                                                     "source": "x = 1"}])).encode(),
     "the notebook has no code"),
    ("cells_not_list", json.dumps({**_nb([]), "cells": {}}).encode(),
     "the notebook has no list of cells"),
    ("cell_without_type", json.dumps(_nb([{"source": "x"}])).encode(),
     "cell 1 is malformed (no cell type)"),
    ("source_not_text", json.dumps(_nb([_code([1, 2])])).encode(),
     "cell 1: its source is not text"),
]


@pytest.mark.parametrize("name, content, message", BAD_FILES, ids=[b[0] for b in BAD_FILES])
def test_unreadable_files_are_refused_with_a_message(tmp_path, name, content, message):
    path = tmp_path / "alice.ipynb"
    path.write_bytes(content)
    with pytest.raises(SubmissionError) as info:
        load_submission(path)
    assert str(info.value).startswith(message)


def test_missing_file_and_folder(tmp_path):
    with pytest.raises(SubmissionError, match="no such file"):
        load_submission(tmp_path / "nobody.ipynb")
    with pytest.raises(SubmissionError, match="is a folder, not a file"):
        load_submission(tmp_path)


def test_too_large_files_are_not_read(tmp_path, monkeypatch):
    monkeypatch.setattr(notebook_load, "MAX_NOTEBOOK_BYTES", 100)
    path = tmp_path / "big.ipynb"
    path.write_text(json.dumps(_nb([_code("x = 1" + " " * 200)])))
    # the one wording of the size limit, grade's and check's (issue 33)
    with pytest.raises(SubmissionError, match=r"over the 100 bytes limit \(--max-size\)"):
        load_submission(path)


def test_cells_numbered_as_a_student_counts_them(tmp_path):
    cells = [{"cell_type": "markdown", "metadata": {}, "source": "# title"},
             _code(["x = 1\n", "y = 2"]), _code(""),
             {"cell_type": "raw", "metadata": {}, "source": "raw"},
             _code("\n\n    z = 3  # a long comment that goes on and on and on\n")]
    path = tmp_path / "a.ipynb"
    path.write_text(json.dumps(_nb(cells)))
    loaded = read_notebook(path)
    assert [(c.position, c.source) for c in loaded.cells] == [
        (2, "x = 1\ny = 2"), (5, "\n\n    z = 3  # a long comment that goes on and on and on\n")]
    assert [c.label for c in loaded.cells] == [
        "cell 2 (`x = 1`)", "cell 5 (`z = 3  # a long comment that goes on an…`)"]
    assert loaded.notes == ()


def test_v3_is_converted_with_a_note(tmp_path):
    v4 = nbformat.v4.new_notebook(cells=[nbformat.v4.new_markdown_cell("hi"),
                                         nbformat.v4.new_code_cell("a = 1\nb = 2")])
    path = tmp_path / "old.ipynb"
    path.write_text(nbformat.writes(nbformat.convert(v4, 3), version=3))
    assert json.loads(path.read_text())["nbformat"] == 3
    loaded = read_notebook(path)
    assert loaded.notebook.nbformat == 4
    assert [(c.position, c.source) for c in loaded.cells] == [(2, "a = 1\nb = 2")]
    assert loaded.notes == ("converted from the old notebook format v3 to v4",)


def test_only_code_sources_survive_sanitizing(tmp_path):
    forged = {"output_type": "execute_result", "data": {"text/plain": "42"}, "metadata": {},
              "execution_count": 1}
    cells = [_code("x = 1", outputs=[forged], execution_count=1,
                   metadata={"tags": ["skip-execution", "raises-exception"]})]
    nb = nbformat.from_dict({**_nb(cells), "metadata": {
        "kernelspec": {"name": "evil", "display_name": "R", "language": "R"}}})
    runnable = executable_notebook(code_cells(nb))
    nbformat.validate(runnable)
    assert runnable.metadata.kernelspec.name == "python3"
    assert [(c.source, c.outputs, c.metadata) for c in runnable.cells] == [("x = 1", [], {})]
