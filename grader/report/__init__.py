"""The class report: item statistics, common wrong answers, copied answers.

Reads result records and the key, never runs student code (``grader/API.md``). One call,
:func:`report_for`, loads a graded class, runs every analysis and writes ``report.html``
(self-contained), ``report.csv`` and ``report_items.csv``:

* :mod:`grader.report.classdata` — what is read;
* :mod:`grader.report.items` — counts, facility, discrimination, flags;
* :mod:`grader.report.slips` — common wrong answers relative to each student's own key;
* :mod:`grader.report.copying` — answers matching another student's key or wrong answer;
* :mod:`grader.report.code_similarity` — nearly identical notebook code (token shingles);
* :mod:`grader.report.students`, :mod:`grader.report.figures`, :mod:`grader.report.page` —
  the table, the figures and the page; :mod:`grader.report.write` writes them;
* :mod:`grader.report.cli` — ``eulertop report``.

Floor 5 of grader/ (views of records, and file formats; grader/API.md).
"""

from grader.report.assemble import ClassReport, build_report
from grader.report.classdata import ClassData, load_class
from grader.report.write import report_for, write_report

__all__ = ["ClassData", "ClassReport", "build_report", "load_class", "report_for",
           "write_report"]
