"""README.md is the landing page, and it and the documentation site speak to users with numbers
that agree with each other. The site's pages are the Markdown sources in ``docs/`` (the site
itself is built and checked in a browser by ``docs/tests/test_site.py``)."""

from __future__ import annotations

import re
from pathlib import Path

from problems.notebook import DEFAULT_INSTALL, TITLE_CELL

ROOT = Path(__file__).resolve().parents[1]
README = (ROOT / "README.md").read_text(encoding="utf-8")
DOCS = ROOT / "docs"
PAGES = {path.relative_to(DOCS).as_posix(): path.read_text(encoding="utf-8")
         for path in sorted(DOCS.rglob("*.md")) if "_build" not in path.parts}
# The pages that were README's sections: written for users in README's voice.
FROM_README = ("index.md", "getting-started.md", "students.md", "accuracy.md", "speed.md",
               "performance.md", "development.md", "compare.md", "changelog.md")
CI = (ROOT / ".ci" / "run").read_text(encoding="utf-8")


def _page(name: str) -> str:
    assert name in PAGES, f"docs/{name} is missing"
    return PAGES[name]


def test_readme_is_a_landing_page_of_at_most_200_lines():
    assert len(README.splitlines()) <= 200
    for heading in ("## Set-up on a fresh machine", "## A short tour", "## Where to read on"):
        assert heading in README
    assert len(re.findall(r"!\[|<img ", README)) == 1  # one picture


def test_readme_gives_the_two_set_up_commands_and_ci_runs_the_second_verbatim():
    commands = re.findall(r"^python3 -m venv \.venv && \. \.venv/bin/activate && (.+)$", README,
                          re.M)
    assert commands == ["pip install -e . && eulertop demo",
                        'pip install -e ".[test]" && ruff check . && python -m pytest']
    ci_lines = [line for line in CI.splitlines() if not line.startswith("#")]
    assert any(line.startswith(commands[1]) for line in ci_lines)


def test_readme_links_only_to_files_that_exist():
    for target in re.findall(r"\]\(([^)#\s]+)(?:#[^)]*)?\)", README):
        if not target.startswith(("http://", "https://")):
            assert (ROOT / target).exists(), target
    for image in re.findall(r'<img src="([^"]+)"', README):
        assert (ROOT / image).exists(), image


def test_the_speed_against_nbgrader_is_one_number_from_a_named_command():
    """Every "N× nbgrader" in README and the site is the bench_grade.py row's bold ratio."""
    row = next(line for line in _page("performance.md").splitlines()
               if "benchmarks/bench_grade.py" in line and line.startswith("|"))
    measured = re.search(r"\*\*(\d+(?:\.\d+)?)×\*\*", row).group(1)
    texts = [README, *PAGES.values()]
    claims = [c for text in texts for c in re.findall(r"(\d+(?:\.\d+)?)× nbgrader", text)]
    assert claims and set(claims) == {measured}
    for text in texts:  # and each claim names the command it comes from
        for line in text.splitlines():
            if re.search(r"\d× nbgrader", line):
                assert "bench_grade.py" in line


def test_every_measured_row_names_its_command():
    table = [line for line in _page("performance.md").splitlines() if line.startswith("| ")]
    assert len(table) > 2
    for row in table[2:]:  # past the header and its rule
        assert re.search(r"`[^`]*(python|eulertop)[^`]*`", row), row


def test_for_students_gives_one_install_command_the_notebook_repeats():
    students = _page("students.md")
    commands = re.findall(r"^%pip install \S+$", students, re.M)
    assert commands == [f"%pip install {DEFAULT_INSTALL}"]  # the student package (issue 33)
    title = TITLE_CELL.format(title="T", file="ada.ipynb", install=DEFAULT_INSTALL)
    assert commands[0] in title and "eulertop_check.check()" in title
    assert "eulertop_check.check()" in students and "JupyterHub" in students
    assert "Colab" in students and "VS Code" in students
    assert commands[0] in README and "eulertop_check.check()" in README


def test_no_wording_about_how_the_project_was_built():
    voiced = [README, *(_page(name) for name in FROM_README),
              *(text for name, text in PAGES.items() if name.startswith("instructors/"))]
    for text in voiced:
        for phrase in (r"\bwe\b", r"\bhelper\b", r"\blead engineer\b"):
            assert not re.search(phrase, text, re.I), phrase
    for name, text in [("README.md", README), *PAGES.items()]:
        for phrase in (r"\bour (machines|issue tracker|team)\b", r"\bissue \d+\b"):
            assert not re.search(phrase, text, re.I), (name, phrase)
