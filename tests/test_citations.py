"""Code and documents cite the physics and the design by pages of this repository
(``docs/physics/``, ``grader/API.md``, ``problems/API.md``), never by a file outside it.

Every text file of the repository — code, documentation, tests, notebooks, CI scripts — is read;
a mention of the lecture's notes outside the repository (a ``shared/`` folder, an absolute path
of the machine the project was written on, or a notes file the repository does not hold, such as
the restatement of the physics or the design notes) fails, naming the file and line. The target
a citation of an R-id needs exists: the physics page has a section for each of R1–R21.
"""

from __future__ import annotations

import re
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
PHYSICS_PAGE = ROOT / "docs" / "physics" / "index.md"
SKIPPED = {"venv", "bench-out", "__pycache__", "_build", "node_modules", "build", "dist"}
"""Folders that are not the repository's own text, besides hidden ones (``.git``, ``.venv``,
test caches such as ``.hypothesis``) other than ``.ci``, and ``*.egg-info``."""


def _skipped(folder: str) -> bool:
    return folder in SKIPPED or folder.endswith(".egg-info") or \
        (folder.startswith(".") and folder != ".ci")


NOTES = ("physics", "design", "layout", "style")
OUTSIDE = re.compile(
    r"(?:\.\./)*\bshared/[\w./-]*"  # the notes folder beside the repository
    r"|/work/[\w./-]*"  # an absolute path of the machine it was written on
    r"|(?<![\w/.-])(?:[\w.-]+/)*(?:" + "|".join(NOTES) + r")\.md\b"  # a notes file by name
)


def outside_citations(text: str, folder: Path = ROOT) -> list[tuple[int, str]]:
    """``(line, what)`` of each citation in ``text`` of a file outside the repository; a notes
    file's name counts only where no such file exists (relative to the repository's root or to
    ``folder``, the citing file's)."""
    found = []
    for number, line in enumerate(text.splitlines(), start=1):
        for match in OUTSIDE.finditer(line):
            cited = match.group(0)
            held = not cited.startswith(("/", "shared/", "../")) and any(
                (base / cited).is_file() for base in (ROOT, folder))
            if not held:
                found.append((number, cited))
    return found


def repository_text_files() -> list[Path]:
    """Every file of the repository that reads as UTF-8 text, but this one (which names
    the patterns it looks for)."""
    files = []
    for path in sorted(ROOT.rglob("*")):
        parts = path.relative_to(ROOT).parts
        if any(_skipped(p) for p in parts[:-1]) or path.name == ".git":  # a worktree's link
            continue
        if path.is_file() and path != Path(__file__).resolve():
            try:
                path.read_text(encoding="utf-8")
            except (UnicodeDecodeError, OSError):
                continue
            files.append(path)
    return files


def test_the_walk_reads_code_docs_tests_and_notebooks():
    names = {p.relative_to(ROOT).as_posix() for p in repository_text_files()}
    assert {"solver/__init__.py", "solver/API.md", "problems/API.md", "grader/API.md",
            "docs/physics/index.md", "tests/test_layout.py", ".ci/run"} <= names
    assert any(n.startswith("notebooks/") and n.endswith(".ipynb") for n in names)


def test_no_file_cites_a_file_outside_the_repository():
    cited = [f"{path.relative_to(ROOT)}:{line}: {what}"
             for path in repository_text_files()
             for line, what in outside_citations(path.read_text(encoding="utf-8"), path.parent)]
    assert cited == []


def test_the_check_finds_each_kind_of_citation_outside():
    """Control of the test above: what the repository cited before issue 30 is found; its own
    pages are not."""
    text = ("every result R1–R21 of ../shared/physics.md\n"
            "Convention of ``/work/shared/physics.md``\n"
            "The design rule (``design.md``): parameters are rounded\n"
            "fail closed — style.md, and layout.md\n"
            "R7 (docs/physics/index.md), grader/API.md, problems/API.md, docs/security.md\n"
            "mp_reference.py, physics_md, a design.mdx file\n")
    assert outside_citations(text) == [
        (1, "../shared/physics.md"), (2, "/work/shared/physics.md"), (3, "design.md"),
        (4, "style.md"), (4, "layout.md")]


def test_the_physics_page_has_a_section_for_each_result():
    """What a citation of an R-id points at: a heading ``### Rn, …`` for R1–R21, in order."""
    headings = re.findall(r"^### R(\d+), ", PHYSICS_PAGE.read_text(encoding="utf-8"), re.M)
    assert [int(n) for n in headings] == list(range(1, 22))
