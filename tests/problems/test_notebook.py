"""Student notebooks: valid nbformat v4, layout, no secrets, solutions that reproduce the key."""

from __future__ import annotations

import ast
import json
import math

import nbformat
import pytest
from hypothesis import example, given, settings
from hypothesis import strategies as st

from problems.generate import generate_assignment, student_answers
from problems.notebook import (
    _COMPACT,
    _cell,
    _cell_text,
    _indented_of,
    answer_line,
    build_notebook,
    build_notebooks,
    indented_json,
    notebook_text,
    notebook_texts,
    python_literal,
)
from problems.roster import read_roster

PROBLEMS = ("rod", "rod2")


@pytest.fixture
def hw(tmp_path, families, roster_path):
    out = tmp_path / "HW"
    generate_assignment(read_roster(roster_path), out, families, problems=PROBLEMS, seed=11,
                        title="Tops, week 3")
    return out


def read(hw, kind, sid="alice"):
    return nbformat.read(hw / kind / f"{sid}.ipynb", as_version=nbformat.NO_CONVERT)


@pytest.mark.parametrize("kind", ["release", "solutions"])
def test_valid_nbformat_v4_with_python_kernel(hw, kind):
    for sid in ("alice", "bob", "carol"):
        nb = read(hw, kind, sid)
        nbformat.validate(nb)
        assert nb.nbformat == 4
        assert nb.metadata.kernelspec.name == "python3"
        assert nb.metadata.eulertop.notebook == kind


def test_cell_layout_and_read_only_marks(hw):
    nb = read(hw, "release")
    ids = [c.id for c in nb.cells]
    assert ids == ["title", "rules", "parameters", "q1-statement", "q1-answer", "q2-statement",
                   "q2-answer"]
    for cell in nb.cells:
        answer = cell.id.endswith("answer")
        assert cell.metadata.get("editable", True) is answer
        assert cell.metadata.deletable is False
    first = nb.cells[0].source
    assert first.startswith("# Tops, week 3\n")
    # the first cell says how to check the notebook: from inside it (the student package,
    # which holds no solver) and in a terminal
    assert "%pip install eulertop-check" in first and "eulertop_check.check()" in first
    assert "eulertop-check alice.ipynb" in first
    rules = nb.cells[1].source
    assert "`alice` (Alice Ng)" in rules
    assert "**Conventions for every question**" in rules
    assert "q2_I_expr = None  # an expression in m, L, theta" in nb.cells[6].source


def test_answer_cells_have_one_line_per_answer(hw):
    nb, key = read(hw, "release"), json.loads((hw / "key.json").read_text())
    lines = nb.cells[4].source.splitlines()
    names = [a["name"] for a in key["students"]["alice"]["questions"][0]["answers"]]
    assert [line.split(" = ")[0] for line in lines] == [f"q1_{n}" for n in names]
    assert lines[0] == "q1_I_c = None  # kg m^2 — moment about the centre"
    assert lines[5] == ('q1_bigger = None  # one of "centre", "end" — '
                        "which axis has the larger moment")


def test_parameter_cell_defines_the_displayed_values(hw):
    nb = read(hw, "release")
    manifest = json.loads((hw / "assignment.json").read_text())
    namespace: dict = {}
    exec(nb.cells[2].source, namespace)  # our own generated cell
    for q in manifest["students"]["alice"]["questions"]:
        for name, value in q["params"].items():
            assert namespace[f"q{q['question']}_{name}"] == value


def _secret_strings(key_entry):
    """Text forms of the key's answers and known mistakes that must not leak."""
    for q in key_entry["questions"]:
        for a in q["answers"]:
            # choice and boolean values are necessarily among the public options
            if a["kind"] in ("choice", "boolean"):
                continue
            values = [a["value"], *(m["value"] for m in a["mistakes"])]
            for v in values:
                for x in v if isinstance(v, list) else [v]:
                    if isinstance(x, str):
                        yield x
                    elif x not in (0.0,):
                        yield repr(x)
                        yield f"{x:.4g}"


def test_release_notebooks_hold_no_answer_or_mistake_values(hw):
    key = json.loads((hw / "key.json").read_text())
    for sid, entry in key["students"].items():
        text = (hw / "release" / f"{sid}.ipynb").read_text()
        leaked = [s for s in _secret_strings(entry) if s in text]
        assert leaked == []
        meta = json.dumps(read(hw, "release", sid).metadata.eulertop)
        assert '"value"' not in meta and '"mistakes"' not in meta


def test_public_spec_in_metadata(hw):
    meta = read(hw, "release").metadata.eulertop
    assert meta.student == "alice" and meta.assignment == "Tops, week 3"
    assert [q.family for q in meta.questions] == list(PROBLEMS)
    spec = {a.name: a for a in meta.questions[0].answers}
    assert spec["r_cm"].length == 3 and spec["r_cm"].unit == "m"
    assert spec["bigger"].options == ["centre", "end"]
    assert spec["I_expr"].symbols == ["m", "L", "theta"]
    assert spec["theta"].period == pytest.approx(2 * math.pi, rel=1e-15)


@pytest.mark.parametrize(
    "value", [None, True, 0.1, 1e-300, -2.5e17, 3, [0.1, [2.0, -0.0]], "m*g*l*cos(beta)", "it's"]
)
def test_python_literals_read_back_exactly(value):
    assert ast.literal_eval(python_literal(value)) == value


@pytest.mark.parametrize("bad", [float("nan"), float("inf"), {"a": 1}, object()])
def test_python_literal_refuses_what_is_not_plain_json(bad):
    with pytest.raises((ValueError, TypeError)):
        python_literal(bad)


def test_answer_line_for_a_dimensionless_vector():
    spec = {"variable": "q1_n", "kind": "vector", "length": 3, "unit": "", "description": ""}
    assert answer_line(spec, [0.0, 1.0, 0.0]) == "q1_n = [0.0, 1.0, 0.0]  # a list of 3 numbers"


READ_BACK = """\
import json as _json
print(_json.dumps({name: globals()[name] for name in %r}))
"""


def _execute_and_extract(path, variables):
    """Run a notebook in a fresh kernel; return its answer variables as plain JSON."""
    from nbclient import NotebookClient

    nb = nbformat.read(path, as_version=4)
    nb.cells.append(nbformat.v4.new_code_cell(READ_BACK % (variables,), id="read-back"))
    NotebookClient(nb, timeout=60, kernel_name="python3").execute()
    return json.loads(nb.cells[-1].outputs[0]["text"])


@pytest.mark.parametrize("kind", ["solutions", "release"])
def test_executed_notebook_yields_the_key_or_nothing(hw, kind):
    key = json.loads((hw / "key.json").read_text())
    expected = {var: a.value for var, a in student_answers(key, "bob").items()}
    got = _execute_and_extract(hw / kind / "bob.ipynb", sorted(expected))
    if kind == "solutions":
        assert got == expected  # exact: floats are written by repr
    else:
        assert got == dict.fromkeys(expected)


def dumps(value):
    return json.dumps(value, indent=1, sort_keys=True, ensure_ascii=False, allow_nan=False)


@pytest.mark.parametrize("kind", ["release", "solutions"])
def test_notebook_files_are_exactly_what_json_dumps_writes(hw, kind):
    """The generator's own JSON writer gives json.dumps's bytes (nbformat's layout)."""
    for sid in ("alice", "bob", "carol"):
        text = (hw / kind / f"{sid}.ipynb").read_text(encoding="utf-8")
        nb = json.loads(text)
        assert text == dumps(nb) + "\n"
        assert notebook_text(nb, validate=False) == notebook_text(nb) == text


@pytest.mark.parametrize("value", [
    {}, [], [[]], {"a": [{}]}, {"z": 1, "a": [1, 2.5, None, False, True, -0.0, 1e300, 10**30]},
    "\u2028\x00\"\\ θ", {"é": {"b": "x\ny", "a": [[1], []]}},
    (1, 2), {1: "non-string key"}, [float("inf")], {"k": {1.5}},
])
def test_indented_json_is_json_dumps(value):
    try:
        expected = dumps(value)
    except (TypeError, ValueError) as err:
        with pytest.raises(type(err)):
            indented_json(value)
    else:
        assert indented_json(value) == expected


def test_an_invalid_notebook_is_refused_only_when_validated():
    nb = {"nbformat": 4, "nbformat_minor": 5, "metadata": {},
          "cells": [{"cell_type": "nope", "id": "x"}]}
    with pytest.raises(ValueError, match="generated an invalid notebook"):
        notebook_text(nb)
    assert json.loads(notebook_text(nb, validate=False)) == nb


def test_the_two_notebooks_built_together_are_the_ones_built_alone(families):
    """build_notebooks shares the common cells; a memo encodes them once: same notebooks, same
    text as building and encoding each alone."""
    from problems.generate import student_variants

    variants = student_variants(families, PROBLEMS, 5, "alice")
    row = {"id": "alice", "name": "Alice Ng"}
    release, solutions = build_notebooks("Tops", row, variants)
    assert release == build_notebook("Tops", row, variants)
    assert solutions == build_notebook("Tops", row, variants, solutions=True)
    assert release["cells"][0] is solutions["cells"][0]  # shared, not copied
    memo: dict = {}
    texts = [notebook_text(nb, memo=memo) for nb in (release, solutions)]
    assert memo and texts == [dumps(release) + "\n", dumps(solutions) + "\n"]
    assert texts[0] != texts[1]


def test_notebook_texts_are_the_built_notebooks_encoded(families):
    """notebook_texts (cells around their encoded sources, question records kept by content)
    writes what notebook_text writes of build_notebooks, and what json.dumps writes of what it
    reads back — for every built-in family, a written part, and students sharing cells."""
    from problems.generate import class_variants, prepare_families, resolve_problems
    from problems.templates import FAMILIES
    from problems.written import Written, written_variant

    every = {**FAMILIES, **families}
    questions = resolve_problems([*FAMILIES, "rod"], every)
    prepare_families(every, questions)
    written = written_variant(Written("why", "Why does the top *not* fall?", 2.0,
                                      [("torque", 1.0), ("precession", 1.0)]))
    for seed in (3, 4):
        ids = ["alice", "bob", "s\u2028\"é"]
        for sid, variants in zip(ids, class_variants(every, questions, seed, ids, {}),
                                 strict=True):
            row = {"id": sid, "name": "Ann <O'Neil>"}
            variants = [*variants, written]
            texts = notebook_texts(f"Tops {seed}", row, variants, every)
            built = build_notebooks(f"Tops {seed}", row, variants, every)
            assert list(texts) == [notebook_text(nb) for nb in built]
            assert [dumps(json.loads(text)) + "\n" for text in texts] == list(texts)


def test_an_invalid_notebook_text_is_refused_only_when_validated(families, monkeypatch):
    from problems import notebook
    from problems.generate import student_variants

    variants = student_variants(families, PROBLEMS, 5, "alice")
    monkeypatch.setattr(notebook, "KERNELSPEC", {"language": "python"})  # no name: invalid
    with pytest.raises(ValueError, match="generated an invalid notebook"):
        notebook_texts("Tops", {"id": "alice"}, variants)
    assert notebook_texts("Tops", {"id": "alice"}, variants, validate=False)


_JSON_SCALARS = (st.none() | st.booleans() | st.integers(-10**20, 10**20)
                 | st.floats(allow_nan=False, allow_infinity=False) | st.text())
_JSON = st.recursive(_JSON_SCALARS, lambda inner: st.lists(inner, max_size=4)
                     | st.dictionaries(st.text(), inner, max_size=4), max_leaves=12)


@settings(max_examples=300, deadline=None)
@given(st.dictionaries(st.text(), _JSON, max_size=5))
@example({"a": 1}).via("equal in Python")
@example({"a": 1.0}).via("equal in Python")
@example({"a": True}).via("equal in Python")
@example({"a": [0.0]}).via("equal in Python")
@example({"a": [-0.0]}).via("equal in Python")
def test_a_question_record_kept_by_content_is_json_dumps(record):
    """Records kept by their one-line JSON: the same text json.dumps writes at their place, and
    never that of another record equal to it in Python (1, 1.0 and True; 0.0 and -0.0)."""
    notebook = {"metadata": {"eulertop": {"questions": [record]}}}
    text = _indented_of(_COMPACT.encode(record), "\n    ")  # as _encoded_question makes it
    assert dumps(notebook) == ('{\n "metadata": {\n  "eulertop": {\n   "questions": [\n    '
                               + text + "\n   ]\n  }\n }\n}")


@settings(max_examples=300, deadline=None)
@given(kind=st.sampled_from(["code", "markdown"]), cell_id=st.text(min_size=1),
       source=st.text(), editable=st.booleans(), question=st.none() | st.integers(0, 99),
       written=st.none() | st.text())
def test_a_cell_text_is_json_dumps(kind, cell_id, source, editable, question, written):
    """A cell's text made from its frame (made once) and its source's lines is the text
    json.dumps writes of the cell in a notebook's cells, whatever the source."""
    cell = _cell(kind, cell_id, source, editable, question, written)
    expected = dumps({"cells": [cell]})
    assert expected == '{\n "cells": [\n  ' + _cell_text(
        kind, cell_id, source, editable, question, written) + "\n ]\n}"
