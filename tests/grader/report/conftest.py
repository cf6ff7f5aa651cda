"""Fixtures of the class report's tests: two synthetic classes, graded once per session.

``planted_class``
    60 students with every planted pattern (:mod:`tests.grader.report.synthetic_class`), graded
    by the real pipeline, whose last step wrote ``report.html``; ``.report`` is the
    :class:`grader.report.ClassReport` built again with the submissions, for assertions.
``honest_class``
    200 honest students: no planted pattern at all.
"""

from __future__ import annotations

from dataclasses import dataclass

import pytest

from grader.report import ClassReport, build_report, load_class
from grader.report.cli import submitted_notebooks
from tests.grader.report.synthetic_class import SyntheticClass, build_class


@dataclass
class Built:
    made: SyntheticClass
    report: ClassReport


def _built(folder, n, planted) -> Built:
    made = build_class(folder, n, planted=planted)
    data = load_class(made.hw, made.graded)
    return Built(made, build_report(data, submitted_notebooks(made.submissions, data.ids)))


@pytest.fixture(scope="session")
def planted_class(tmp_path_factory) -> Built:
    return _built(tmp_path_factory.mktemp("planted"), 60, True)


@pytest.fixture(scope="session")
def honest_class(tmp_path_factory) -> Built:
    return _built(tmp_path_factory.mktemp("honest"), 200, False)
