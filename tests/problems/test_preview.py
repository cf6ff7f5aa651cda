"""`eulertop problems preview`: parameters, key values and the statement as the student sees it,
rendered by the feedback pages' renderer, for a few seeds."""

from __future__ import annotations

import html
import re

import numpy as np

from eulertop.cli import main
from grader.statement_html import statement_html
from problems.notebook import comparison_line, python_literal
from problems.templates import FAMILIES


def test_preview_shows_parameters_key_and_the_rendered_statement(tmp_path, capsys):
    out = tmp_path / "pages" / "sleeping.html"
    assert main(["problems", "preview", "sleeping_top", "--seeds", "2", "--out", str(out)]) == 0
    printed = capsys.readouterr().out
    page = out.read_text(encoding="utf-8")
    for seed in (0, 1):
        v = FAMILIES["sleeping_top"].generate(np.random.default_rng(seed))
        assert f"<h2>seed {seed}</h2>" in page
        for name, value in v.parameters.items():  # every recorded parameter, labels too
            shown = value if isinstance(value, str) else python_literal(value)
            assert f"<code>{name}</code></td><td>{html.escape(shown)}</td>" in page
        for answer in v.answers:
            assert f"<code>{answer.name}</code></td><td>{python_literal(answer.value)} " in page
            assert f"{answer.name} = {python_literal(answer.value)}" in printed
        question = (f"## {v.title}\n\n{v.statement.strip()}\n\n"
                    f"{comparison_line(v.answers, 1)}")
        assert statement_html(question) in page  # the feedback pages' own rendering
    assert page.count("<math") >= 4 and not re.search(r"\$\\omega", page)
    assert "<td>within [0.03, 0.5]</td>" in page  # what a spec may do with M
    assert "<td>no: derived from the others</td>" in page  # and with omega3
    assert "Content-Security-Policy" in page and "<script" not in page
    assert printed.rstrip().endswith(f"wrote {out}")


def test_one_seed_and_a_family_from_a_file(tmp_path, capsys, monkeypatch):
    from eulertop import family_example

    monkeypatch.chdir(tmp_path)
    assert main(["problems", "preview", family_example.__file__, "--seed", "7"]) == 0
    page = (tmp_path / "preview-projectile.html").read_text(encoding="utf-8")
    assert "<h2>seed 7</h2>" in page and "<h2>seed 0</h2>" not in page


def test_a_page_that_cannot_be_written_is_reported_and_nothing_is_left(tmp_path, capsys):
    target = tmp_path / "taken"
    target.mkdir()  # a folder where the page should go
    assert main(["problems", "preview", "sleeping_top", "--out", str(target)]) == 1
    assert "nothing was written" in capsys.readouterr().err
    assert list(tmp_path.iterdir()) == [target] and list(target.iterdir()) == []
