"""``eulertop report``: writes the page where asked, compares code with --submissions, and
answers a usage error with one line and exit status 2."""

from __future__ import annotations

import csv
import shutil

import pytest

from eulertop.cli import main
from tests.grader.report.synthetic_class import PLANTED


@pytest.fixture
def graded_copy(planted_class, tmp_path):
    """A private copy of the planted class's HW (with graded/) and submissions."""
    hw = shutil.copytree(planted_class.made.hw, tmp_path / "HW")
    subs = shutil.copytree(planted_class.made.submissions, tmp_path / "subs")
    return hw, subs


def test_report_rewrites_the_page_in_the_graded_folder(graded_copy, capsys):
    hw, _ = graded_copy
    (hw / "graded" / "report.html").unlink()
    assert main(["report", str(hw)]) == 0
    out = capsys.readouterr().out
    assert f"wrote {hw / 'graded' / 'report.html'}" in out and "3 flagged pair(s)" in out
    assert "0 pair(s) with near-identical code" in out  # no --submissions: code not compared
    page = (hw / "graded" / "report.html").read_text(encoding="utf-8")
    assert "The notebooks were not available" in page


def test_out_and_submissions(graded_copy, tmp_path, capsys):
    hw, subs = graded_copy
    page = tmp_path / "elsewhere" / "class.html"
    assert main(["report", str(hw), "--graded", str(hw / "graded"), "--out", str(page),
                 "--submissions", str(subs)]) == 0
    assert "1 pair(s) with near-identical code" in capsys.readouterr().out
    assert page.is_file() and (page.parent / "class_items.csv").is_file()
    with open(page.parent / "class.csv", newline="") as f:
        rows = {r["id"]: r for r in csv.DictReader(f)}
    copier, source = PLANTED["notebook"]
    assert rows[copier]["code like"] == source


@pytest.mark.parametrize(("args", "message"), [
    (["{tmp}/nothing"], "no such assignment folder"),
    (["{hw}", "--graded", "{tmp}/empty"], "no result records here"),
    (["{hw}", "--out", "{tmp}"], "is a folder"),
    (["{hw}", "--submissions", "{tmp}/nothing"], "not a folder"),
])
def test_usage_errors_exit_2_with_one_line(planted_class, tmp_path, capsys, args, message):
    hw = planted_class.made.hw  # nothing is written on a usage error
    (tmp_path / "empty").mkdir()
    argv = ["report", *(a.format(tmp=tmp_path, hw=hw) for a in args)]
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert err.startswith("eulertop report: ") and message in err
    assert len(err.strip().splitlines()) == 1
