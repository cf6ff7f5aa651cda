"""Near-identical code: tokens normalised, the handed-out code and class idioms removed."""

from __future__ import annotations

import json

from grader.report.code_similarity import common_limit, notebook_code, similar_code, tokens


def _notebook(path, *sources):
    cells = [{"cell_type": "code", "source": s, "metadata": {}, "outputs": [],
              "execution_count": None} for s in sources]
    path.write_text(json.dumps({"cells": cells, "metadata": {}, "nbformat": 4,
                                "nbformat_minor": 5}))
    return path


def _similar(subs, given=None):
    """similar_code over notebook files: ``given`` the one every student was handed."""
    code = {s: notebook_code(p) for s, p in subs.items()}
    return similar_code(code, [notebook_code(given)] if given else [])


def _own_code(k: int) -> str:
    words = ["alpha", "beta", "gamma", "delta", "eps", "zeta", "eta", "theta", "iota", "kappa"]
    return "\n".join(f"{words[(k + i) % 10]}{k}_{i} = np.sqrt({words[(k * i) % 10]}{i}) * {i}"
                     for i in range(12))


def test_numbers_and_strings_are_normalised_and_comments_kept():
    assert tokens("x = 1.5e3 + 'a'  # Note") == ["x", "=", "#", "+", '"…"', "# note"]
    assert tokens("%matplotlib inline\nx = (")[:2] == ["%", "matplotlib"]  # not Python: words


def test_a_copy_with_its_numbers_changed_is_found_and_other_work_is_not(tmp_path):
    given = _notebook(tmp_path / "release.ipynb", "import numpy as np\nq1_x = None")
    subs = {f"s{k}": _notebook(tmp_path / f"s{k}.ipynb", "import numpy as np", _own_code(k))
            for k in range(8)}
    copied = _own_code(3).replace("* 5", "* 7").replace("* 9", "* 2")
    subs["copy"] = _notebook(tmp_path / "copy.ipynb", "import numpy as np", copied)
    found = _similar(subs, given)
    assert [set(c.students) for c in found] == [{"s3", "copy"}]
    assert found[0].jaccard == 1.0


def test_code_everybody_was_handed_is_not_evidence(tmp_path):
    handed = _own_code(1)  # a long worked example in the released notebook
    given = _notebook(tmp_path / "release.ipynb", handed)
    subs = {s: _notebook(tmp_path / f"{s}.ipynb", handed) for s in ("a", "b")}
    assert _similar(subs, given) == ()


def test_an_idiom_of_the_class_is_not_evidence(tmp_path):
    idiom = _own_code(5)  # ten students share it (say, a snippet from the lecture)
    subs = {f"s{k}": _notebook(tmp_path / f"s{k}.ipynb", idiom) for k in range(10)}
    assert common_limit(10) < 10
    assert _similar(subs) == ()
