"""The report finds every pattern planted in the synthetic class (60 students, real variants,
real grading): a hard question, a broken answer, an unknown slip, three copying pairs."""

from __future__ import annotations

import csv

import numpy as np

from tests.grader.report.synthetic_class import (
    BROKEN,
    BROKEN_FACTOR,
    COPIED_WRONG,
    HARD_QUESTION,
    PLANTED,
    SLIP,
)


def _stats(report, label):
    return next(s for s in (*report.questions, *report.answers) if s.label == label)


def test_grading_run_writes_the_report_page_and_its_csv_files(planted_class):
    graded = planted_class.made.graded
    page = (graded / "report.html").read_text(encoding="utf-8")
    assert "Class report: Synthetic class (planted patterns)" in page
    assert page.count('src="data:image/svg+xml;base64,') >= 4
    with open(graded / "report.csv", newline="") as f:
        rows = list(csv.DictReader(f))
    assert {r["id"] for r in rows} == set(planted_class.made.ids)
    with open(graded / "report_items.csv", newline="") as f:
        items = {r["item"]: r for r in csv.DictReader(f)}
    assert items[BROKEN]["flags"] == "possibly broken"


def test_students_not_graded_are_listed_but_left_out_of_the_statistics(planted_class):
    made, report = planted_class.made, planted_class.report
    missing, failed = made.ids[-2], made.ids[-1]
    assert report.data.results[missing].status == "missing"
    assert report.data.results[failed].status == "failed"
    assert set(report.data.graded) == set(made.ids) - {missing, failed}
    assert all(sum(s.counts.values()) == len(made.ids) - 2
               for s in report.answers)
    page = (made.graded / "report.html").read_text(encoding="utf-8")
    assert "1 could not be graded, 1 handed in nothing" in page
    with open(made.graded / "report.csv", newline="") as f:
        status = {r["id"]: r["status"] for r in csv.DictReader(f)}
    assert (status[missing], status[failed]) == ("missing", "failed")


def test_facility_is_the_mean_fraction_of_points_from_the_records(planted_class):
    data = planted_class.report.data
    for q in data.assignment.questions:
        fractions = []
        for sid in data.graded:
            r = data.results[sid]
            mine = [a.verdict for a in r.answers if a.question == q]
            fractions.append(sum(v.points for v in mine) / sum(v.max_points for v in mine))
        assert np.isclose(_stats(planted_class.report, f"q{q}").facility, np.mean(fractions))


def test_the_hard_question_is_flagged_hard_and_still_separates_strong_students(planted_class):
    report = planted_class.report
    hard = _stats(report, f"q{HARD_QUESTION}")
    assert "hard" in hard.flags
    # P(right) = ∫ 1/(1+exp(-10(a-0.75))) da over a in [0, 1] = 0.258; the rest is noise
    assert 0.1 < hard.facility < 0.4
    assert hard.discrimination > 0.25  # strong students get it: not a broken question
    for q in (1, 2):
        assert "hard" not in _stats(report, f"q{q}").flags


def test_the_broken_answer_is_flagged_and_the_class_agrees_on_the_keys_error(planted_class):
    report = planted_class.report
    broken = _stats(report, BROKEN)
    assert broken.flags == ("possibly broken",)
    assert broken.counts["correct"] == 0
    group = next(g for g in report.slips if g.variable == BROKEN)
    # the students computed the true value, the key is BROKEN_FACTOR times too large
    ratio = float(group.formula.split("*")[0].split("/")[0]) / float(
        group.formula.split("*")[0].split("/")[1])
    assert np.isclose(ratio, 1 / BROKEN_FACTOR)
    assert len(group.students) > broken.counts["wrong"] / 2
    page = (planted_class.made.graded / "report.html").read_text(encoding="utf-8")
    assert "check the key" in page
    others = [s for s in report.answers if s.label != BROKEN]
    assert not any("possibly broken" in s.flags for s in others)


def test_the_unknown_factor_two_slip_is_found_with_exactly_the_students_who_made_it(
        planted_class):
    made, report = planted_class.made, planted_class.report
    for sid in made.slip_students:  # the premise: the templates do not know this slip
        verdict = report.data.answer(sid, SLIP).verdict
        assert verdict.status == "wrong" and verdict.mistake is None
    group = next(g for g in report.slips if g.variable == SLIP and g.relation == "factor_2")
    assert group.formula == "2*v"
    assert set(group.students) == set(made.slip_students)
    assert len(made.slip_students) >= len(made.ids) // 3 - 3
    assert [g for g in report.slips if g.variable not in (SLIP, BROKEN)] == []


def test_exactly_the_three_copying_pairs_are_flagged(planted_class):
    report = planted_class.report
    flagged = {frozenset(p.students) for p in report.flagged_pairs}
    assert flagged == {frozenset(pair) for pair in PLANTED.values()}


def test_copied_answers_name_the_copier_and_the_answers_that_match(planted_class):
    pairs = {frozenset(p.students): p for p in planted_class.report.flagged_pairs}
    data = planted_class.report.data
    numeric = [i.variable for i in data.items if i.kind in ("scalar", "angle", "vector")]
    for name in ("answers", "notebook"):
        copier, source = PLANTED[name]
        pair = pairs[frozenset((copier, source))]
        assert pair.direction == f"{copier} copied {source}"
        on_key = {m.variable for m in pair.matches if m.how == "key"}
        assert on_key == set(numeric) - {BROKEN}  # the source's broken answer is wrong too
        assert pair.chance < 1e-20
    copier, source = PLANTED["wrong"]
    pair = pairs[frozenset((copier, source))]
    assert {m.variable for m in pair.matches} == set(COPIED_WRONG)
    assert all(m.how == "wrong" for m in pair.matches) and pair.direction == ""


def test_only_the_copied_notebook_has_near_identical_code(planted_class):
    code = planted_class.report.code
    copier, source = PLANTED["notebook"]
    assert [set(c.students) for c in code] == [{copier, source}]
    assert code[0].jaccard == 1.0


def test_the_student_table_lists_each_copiers_partner(planted_class):
    with open(planted_class.made.graded / "report.csv", newline="") as f:
        rows = {r["id"]: r for r in csv.DictReader(f)}
    for copier, source in PLANTED.values():
        assert rows[copier]["answers match"] == source
        assert rows[source]["answers match"] == copier
    copier, source = PLANTED["notebook"]
    assert rows[copier]["code like"] == source
    for sid in planted_class.made.slip_students:
        assert f"{SLIP}: factor_2" in rows[sid]["slips"]
