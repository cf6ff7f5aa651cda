"""`eulertop new-family NAME --out DIR`: a working, commented example family that passes the
self-test as written and generates like a built-in; refusals write nothing."""

from __future__ import annotations

import json
import math

import pytest

from eulertop.cli import main
from grader.selftest_run import grade_solutions
from problems.family_files import load_family_file
from problems.selftest import self_test


def self_test_graded(family, seeds, **options):
    """The self-test as `eulertop problems test` runs it: its solutions notebook run and
    graded by the grader (handed in as the front end does)."""
    return self_test(family, seeds, grade_solutions=grade_solutions, **options)


def test_the_written_family_passes_the_self_test_and_generates(tmp_path, capsys):
    assert main(["new-family", "pendulum_hw", "--out", str(tmp_path / "mine")]) == 0
    path = tmp_path / "mine" / "pendulum_hw.py"
    printed = capsys.readouterr().out
    assert f"eulertop problems test {path}" in printed
    source = path.read_text(encoding="utf-8")
    assert 'NAME = "pendulum_hw"' in source and "from eulertop.family import" in source
    assert source.count("\n#") >= 5  # commented: it explains itself
    family = load_family_file(path)
    report = self_test_graded(family, range(30))
    assert report.passed, [c for c in report.checks if c.failed]
    # the key is the projectile's, checked here from the shown values
    v = family.generate(__import__("numpy").random.default_rng(3))
    v0, theta, g = v.params["v0"], v.params["theta"], v.params["g"]
    assert v.answer("R").value == pytest.approx(v0**2 * math.sin(2 * theta) / g, rel=1e-12)
    assert v.answer("H").value == pytest.approx((v0 * math.sin(theta))**2 / (2 * g), rel=1e-12)
    roster = tmp_path / "roster.csv"
    roster.write_text("id\nada\n", encoding="utf-8")
    assert main(["generate", "--roster", str(roster), "--out", str(tmp_path / "HW"),
                 "--families", str(tmp_path / "mine"), "--problems",
                 "pendulum_hw,sleeping_top", "--seed", "1"]) == 0
    key = json.loads((tmp_path / "HW" / "key.json").read_text())
    assert [q["family"] for q in key["students"]["ada"]["questions"]] == ["pendulum_hw",
                                                                         "sleeping_top"]


@pytest.mark.parametrize(("name", "fragment"), [
    ("2fast", "not a Python identifier"),
    ("class", "not a Python identifier"),
    ("sleeping_top", "is a built-in family"),
])
def test_a_bad_name_is_refused_and_nothing_written(tmp_path, capsys, name, fragment):
    assert main(["new-family", name, "--out", str(tmp_path / "mine")]) == 2
    assert fragment in capsys.readouterr().err
    assert not (tmp_path / "mine").exists()


def test_an_existing_file_is_never_overwritten(tmp_path, capsys):
    (tmp_path / "mine.py").write_text("# my work\n", encoding="utf-8")
    assert main(["new-family", "mine", "--out", str(tmp_path)]) == 2
    assert "exists; nothing was written" in capsys.readouterr().err
    assert (tmp_path / "mine.py").read_text(encoding="utf-8") == "# my work\n"
