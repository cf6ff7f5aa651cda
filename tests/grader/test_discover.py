"""Discovery: which file is whose submission — from names only, nothing guessed."""

from __future__ import annotations

import pytest

from grader.discover import discover

ROSTER = ("alice", "bob", "carol", "dave", "erin", "Frank")


def _layout(root, files):
    for rel in files:
        p = root / rel
        if rel.endswith("/"):
            p.mkdir(parents=True)
        else:
            p.parent.mkdir(parents=True, exist_ok=True)
            p.write_text("{}")
    return root


@pytest.fixture
def found(tmp_path):
    _layout(tmp_path, [
        "alice.ipynb",                      # a file
        "bob/hw3.ipynb",                    # a folder with one notebook
        "bob/.ipynb_checkpoints/hw3-checkpoint.ipynb",  # hidden: ignored
        "carol/a.ipynb", "carol/b.ipynb",   # two notebooks: not guessed
        "dave.ipynb", "dave/dave.ipynb",    # a file and a folder: not guessed
        "erin/",                            # an empty folder
        "mallory.ipynb",                    # not on the roster
        "frank.ipynb",                      # differs from a roster id in case only
        "notes.txt",                        # not a notebook
        ".DS_Store",                        # hidden: ignored
    ])
    return discover(tmp_path, ROSTER)


def test_single_notebooks_are_found_by_file_or_folder_name(found, tmp_path):
    assert [(s.student_id, s.path) for s in found.submissions] == [
        ("alice", tmp_path / "alice.ipynb"), ("bob", tmp_path / "bob" / "hw3.ipynb")]


def test_roster_ids_without_a_file_are_missing(found):
    assert found.missing == ("Frank",)


@pytest.mark.parametrize(("sid", "fragment"), [
    ("carol", "2 notebooks (carol/a.ipynb, carol/b.ipynb); submit exactly one"),
    ("dave", "2 notebooks (dave/dave.ipynb, dave.ipynb)"),
    ("erin", "holds no .ipynb notebook"),
])
def test_ambiguous_or_empty_submissions_are_reported_for_their_student(found, sid, fragment):
    (problem,) = [p for p in found.problems if p.student_id == sid]
    assert fragment in problem.message
    assert not problem.ignored


@pytest.mark.parametrize(("name", "fragment", "ignored"), [
    ("mallory.ipynb", "'mallory' is not on the roster; not graded", False),
    ("frank.ipynb", "did you mean 'Frank'? ids are case-sensitive", False),
    ("notes.txt", "not a notebook", True),
])
def test_strays_are_reported_and_not_graded(found, name, fragment, ignored):
    (problem,) = [p for p in found.problems if p.path.name == name]
    assert fragment in problem.message
    assert problem.student_id is None
    assert problem.ignored is ignored


def test_hidden_entries_are_ignored(found):
    assert not any(p.path.name.startswith(".") for p in found.problems)
    assert len(found.problems) == 6


def test_an_empty_folder_means_everybody_is_missing(tmp_path):
    assert discover(tmp_path, ROSTER).missing == ROSTER
