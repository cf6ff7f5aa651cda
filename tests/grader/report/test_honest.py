"""An honest class of 200 (real variants, real grading, arbitrary errors, known mistakes,
invalid and missing answers, every notebook's code its own): the report flags nobody.

False positives are measured, not only asserted: every pair of honest students whose answers
match on some answer is kept by the report with its expected count in an honest class; the
closest to being flagged must stay far above the threshold."""

from __future__ import annotations

from grader.report.copying import ALPHA
from grader.report.slips import MIN_GROUP


def test_no_pair_of_honest_students_is_flagged(honest_class):
    report = honest_class.report
    assert report.flagged_pairs == ()
    assert report.pairs, "chance single matches exist in a class this size: the check ran"
    assert all(len(p.matches) == 1 for p in report.pairs)
    assert min(p.expected for p in report.pairs) > 100 * ALPHA


def test_no_honest_notebooks_look_copied(honest_class):
    assert honest_class.report.code_checked
    assert honest_class.report.code == ()


def test_no_common_slip_and_no_broken_question_in_an_honest_class(honest_class):
    report = honest_class.report
    assert report.slips == ()
    assert not any(s.flags for s in report.questions)
    assert len(report.data.graded) == 200 and MIN_GROUP >= 3


def test_the_page_of_an_honest_class_says_nothing_stands_out(honest_class):
    page = (honest_class.made.graded / "report.html").read_text(encoding="utf-8")
    assert "Nothing stands out" in page
    assert "No pair of students has answers matching beyond chance" in page
